"""Every architecture in space and time, for ``spectracam architectures`` (issue 20): the spatial
experiment (:mod:`spectracam.experiments.spatial`) and the motion experiment (:mod:`spectracam.experiments.motion`) run on
one design per architecture, with the paper's camera (its pixel pitch and f-number).

* **Space** — the slanted edge and the Siemens star, noise off (the spatial artefacts alone): MTF50 of
  the displayed luminance, false colour at the neutral edge, and the S-CIELAB spatial error on the star
  (against the same camera's rendering of the ideal image); mosaics with bilinear demosaicking (any
  periodic mosaic) and Menon 2007 (three-channel mosaics; others remosaicked to Bayer first), each
  without and with a one-pixel 4-spot optical low-pass filter.
* **Time** — the slanted edge moving across the sensor at a few speeds, global shutter, the paper's
  noise and light (cfa/single needs 28 ms): colour breakup from the motion alone
  (``breakup_width_px``, against the design's own noise-free still capture, 0 at rest),
  S-CIELAB against that still capture (``scielab_delta_e``: noise and motion), the still
  capture's demosaicking false colour, and the capture time.

Each design is the architecture with the paper's scheme for it: ``single`` for one exposure,
``optimal`` where the channels have their own exposures (the paper's better FSC/prism scheme).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from spectracam.architecture.base import ARCHITECTURES

if TYPE_CHECKING:
    from collections.abc import Callable

    from spectracam.pipeline.scene_file import Scene

__all__ = ["DEMOSAICS", "OLPF_PX", "SPEEDS_PX_PER_MS", "run_space", "run_time", "spacetime_designs",
           "spacetime_winners"]

#: The motion comparison's speeds, px/ms on the sensor (full run; --quick: the first, third and last).
SPEEDS_PX_PER_MS = (0.0, 0.01, 0.02, 0.04, 0.08)
#: Mosaics: bilinear (any periodic mosaic) and the best maintained Bayer method.
DEMOSAICS = ("bilinear", "menon2007")
#: Mosaics without and with a 4-spot optical low-pass filter of one pixel's spot separation.
OLPF_PX = (0.0, 1.0)


def spacetime_designs() -> list[str]:
    """One design per registered architecture: ``optimal`` where the channels have their own exposures."""
    return [f"{name}/{'optimal' if ARCHITECTURES[name].independent_exposures else 'single'}" for name in ARCHITECTURES]


def _experiment_scene(scene, quick: bool):
    """The paper's scene for the spatial and motion experiments: its light, camera and processing;
    20-nm bands for ``--quick``, as those experiments' own quick runs use."""
    if not quick:
        return scene
    from spectracam.pipeline.scene_file import parse_grid

    return scene.replace(grid=parse_grid({"start_nm": 400, "stop_nm": 700, "step_nm": 20}))


def run_space(scene: Scene, renderer: str, quick: bool, log: Callable[[str], object] | None = None,
              progress: bool = False) -> dict:
    """The spatial experiment on every design (module docstring): its rows and timing.

    Parameters
    ----------
    scene : Scene
        The paper's scene at its calibrated light: its camera's pixel pitch and f-number are used.
    renderer : str
        ``"mitsuba"`` or ``"analytic"``.
    quick : bool
        ``--quick``: the spatial experiment's quick run, 20-nm bands.
    log : callable or None
        ``log(msg)`` for the spatial run's lines.
    progress : bool
        Progress bars on a terminal.

    Returns
    -------
    dict
        ``rows`` (per design × demosaicker × OLPF: ``mtf50_cy_per_px``, ``false_colour_edge``, ``false_colour_star``,
        ``scielab_spatial_star``, ``scielab_spatial_edge``), ``wall_s`` (s) and ``parameters``.
    """
    from spectracam.experiments.spatial.experiment import SpatialSpec, run_spatial

    cam = scene.camera
    spec = SpatialSpec(designs=tuple(spacetime_designs()), pixel_pitches_um=(cam.sensor.pixel_pitch_um,),
                       f_numbers=(cam.optics.f_number,), targets=("edge", "star"), demosaics=DEMOSAICS,
                       olpf_separations_px=OLPF_PX, misregistrations_px=(0.0,))
    spec = spec.quick() if quick else spec
    res = run_spatial(spec, _experiment_scene(scene, quick), renderer, log, keep_images=False, progress=progress)
    rows = []
    for label in dict.fromkeys(r.label for r in res["rows"]):
        edge = next(r for r in res["rows"] if r.label == label and r.target == "edge")
        star = next(r for r in res["rows"] if r.label == label and r.target == "star")
        rows.append({"label": label, "design": edge.design, "demosaic": edge.demosaic,
                     "olpf_separation_px": edge.olpf_separation_px,
                     "mtf50_cy_per_px": edge.mtf50_cy_per_px, "false_colour_edge": edge.false_colour,
                     "false_colour_star": star.false_colour, "scielab_spatial_star": star.scielab_delta_e_spatial,
                     "scielab_spatial_edge": edge.scielab_delta_e_spatial})
    return {"rows": rows, "wall_s": res["wall_s"],
            "parameters": {"spatial": spec.to_dict(), "renderer": renderer, "noise": spec.noise,
                           "pixel_pitch_um": cam.sensor.pixel_pitch_um, "f_number": cam.optics.f_number}}


def run_time(scene: Scene, renderer: str, quick: bool, log: Callable[[str], object] | None = None,
             progress: bool = False) -> dict:
    """The motion experiment on every design (module docstring): its rows and timing.

    Parameters
    ----------
    scene : Scene
        The paper's scene at its calibrated light.
    renderer : str
        ``"mitsuba"`` or ``"analytic"``.
    quick : bool
        ``--quick``: the motion experiment's quick run, every other speed of :data:`SPEEDS_PX_PER_MS`, 20-nm bands.
    log : callable or None
        ``log(msg)`` for the motion run's lines.
    progress : bool
        Progress bars on a terminal.

    Returns
    -------
    dict
        ``rows`` (per design × speed, px/ms: ``breakup_width_px``, ``scielab_delta_e``, ``capture_time_ms``, …),
        ``wall_s`` (s) and ``parameters`` (with the white luminance, cd/m²).
    """
    from spectracam.experiments.motion.experiment import MotionSpec, run_motion

    cam = scene.camera
    spec = MotionSpec(designs=tuple(spacetime_designs()), rolling_shutter=(False,),
                      pixel_pitch_um=cam.sensor.pixel_pitch_um, f_number=cam.optics.f_number)
    spec = spec.quick() if quick else spec
    spec = spec.replace(speeds_px_per_ms=SPEEDS_PX_PER_MS[::2] if quick else SPEEDS_PX_PER_MS)
    res = run_motion(spec, _experiment_scene(scene, quick), renderer, log, keep_images=False, progress=progress)
    keys = ("breakup_width_px", "scielab_delta_e", "scielab_delta_e_sd", "cielab_delta_e", "false_colour_still",
            "breakup_width_scene_px", "scielab_delta_e_scene", "mtf50_cy_per_px", "capture_time_ms", "snr_db",
            "edge_blur_px", "breakup_threshold_width_px")
    rows = [{k: v for k, v in r.to_dict().items() if k in ("design", "speed_px_per_ms", *keys)} for r in res["rows"]]
    return {"rows": rows, "wall_s": res["wall_s"],
            "parameters": {"motion": spec.to_dict(), "renderer": renderer,
                           "white_luminance_cd_m2": res["parameters"]["white_luminance_cd_m2"]}}


def spacetime_winners(space: dict, time_: dict) -> list[dict]:
    """Resolution (highest MTF50), least false colour at the edge, least S-CIELAB error on the star
    (over every spatial design), and at the fastest speed the least colour breakup and least motion
    S-CIELAB error (ties named).

    Parameters
    ----------
    space : dict
        :func:`run_space`'s result.
    time_ : dict
        :func:`run_time`'s result.

    Returns
    -------
    list of dict
        ``part`` (``"space"``/``"time"``), ``metric``, ``design`` (tied designs comma-separated), ``value``; the
        time winners also ``speed_px_per_ms``.
    """
    out = []
    for metric, best in (("mtf50_cy_per_px", max), ("false_colour_edge", min), ("scielab_spatial_star", min)):
        scored = [r for r in space["rows"] if r.get(metric) is not None]
        if scored:
            v = best(r[metric] for r in scored)
            tied = [r["label"] for r in scored if abs(r[metric] - v) <= 1e-6 * max(1.0, abs(v))]
            out.append({"part": "space", "metric": metric, "design": ", ".join(tied), "value": v})
    fast = max(r["speed_px_per_ms"] for r in time_["rows"])
    group = [r for r in time_["rows"] if r["speed_px_per_ms"] == fast]
    for metric in ("breakup_width_px", "scielab_delta_e"):
        scored = [r for r in group if r.get(metric) is not None]   # None: the edge left the image
        if not scored:
            continue
        v = min(r[metric] for r in scored)
        tied = [r["design"] for r in scored if abs(r[metric] - v) <= 1e-6 * max(1.0, abs(v))]
        out.append({"part": "time", "metric": metric, "speed_px_per_ms": fast, "design": ", ".join(tied), "value": v})
    return out
