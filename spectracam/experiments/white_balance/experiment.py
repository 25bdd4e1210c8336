"""The white-balance estimators' statistics per sensor (issue 33, item 3): ``spectracam white-balance``.

Every registered estimator but the oracle (:data:`spectracam.processing.white_balance.WHITE_BALANCE_METHODS`) finds
the neutral of the same captured image, for every sensor of :func:`sensors` and every case of :data:`SCENES` ×
:data:`LIGHTS`:

* **sensors** — the paper's camera (its experiment's base scene: ``cfa/single``, block filters, photodiode QE), each
  shipped measured camera (``filters.kind = "camera"``, flat QE, on the part of 400–700 nm its curves cover, as
  ``spectracam validate`` does) and a Luther camera (``filters.kind = "xyz"``, flat QE) as the reference; all share the
  paper's optics, pixel and noise, so only the spectral design differs;
* **scenes** — the shipped ColorChecker chart and the textured Mondrian, dead leaves and photograph of the CIE 2017
  99 samples (``cfi99``), at 320×240 pixels (160×120 with ``--quick``);
* **lights** — blackbodies 2700–7500 K, CIE D50, D65, D75, fluorescent FL2, FL7, FL11 and LEDs LED-B1, LED-B3,
  LED-BH1, LED-V1 (colour-science's names), all at the scenes' white luminance (100 cd/m²).

Each scene × light is rendered once per wavelength grid (a render does not depend on the sensor; the Sigma's curves
stop at 680 nm, so its scenes have a grid of their own) and captured by each sensor of that grid with the developed
camera's metering (``processing.camera = "developed"``: a percentile of its own preview), noise on, seeds 0…N−1.
The estimators see :func:`spectracam.evaluation.score.camera_rates` (demosaicked, exposure-normalised) and its usable pixels, as
:func:`spectracam.processing.develop` gives them, the scored scene's colours included, so that the trained estimator
never trains on them.  Errors are the recovery and reproduction angles (degrees) against the sensor's true neutral
(:func:`spectracam.processing.calibration.white_neutral`).
"""
from __future__ import annotations

import dataclasses
import time
from typing import TYPE_CHECKING, TypedDict

import numpy as np

from spectracam.core.errors import SpectracamError

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Sequence
    from pathlib import Path

    from matplotlib.figure import Figure
    from numpy.typing import ArrayLike

    from spectracam.experiments.paper.experiment import PaperExperiment
    from spectracam.pipeline.scene_file import Scene
    from spectracam.render import RadianceCube
    from spectracam.scene.illuminant import IlluminantSpec

__all__ = ["DEFINITIONS", "FAMILIES", "FAMILY_COLOURS", "LIGHTS", "LUTHER", "PAPER_DESIGN", "SCENES",
           "WAVELENGTHS", "Sensor", "WhiteBalanceResult", "WhiteBalanceRun", "case_scene", "error_statistics",
           "estimators", "light_family", "light_label", "light_spec", "measure", "parameters", "plan", "run_job",
           "run_white_balance", "sensor_statistics", "sensors", "summary_line", "training_block",
           "white_balance_figure", "white_balance_markdown", "write_white_balance_outputs"]

#: The scenes: shipped scene file → its name in the results.
SCENES = {"d65": "chart", "mondrian": "mondrian", "dead_leaves": "dead_leaves", "photo": "photo"}
#: The lights: ``(type, temperature_K or colour-science name)``.
LIGHTS = (tuple(("blackbody", float(t)) for t in (2700, 3500, 4500, 5500, 6500, 7500))
          + tuple(("cie", n) for n in ("D50", "D65", "D75", "FL2", "FL7", "FL11", "LED-B1", "LED-B3", "LED-BH1",
                                       "LED-V1")))
#: Light families, in the report's order.
FAMILIES = ("blackbody", "daylight", "fluorescent", "LED")
#: Image size, pixels (width, height).
IMAGE_PX, QUICK_IMAGE_PX = (320, 240), (160, 120)
#: Noise seeds per case.
SEEDS, QUICK_SEEDS = 3, 1
#: The wavelength grid before a measured camera narrows it to its curves' range.
WAVELENGTHS = {"start_nm": 400.0, "stop_nm": 700.0, "step_nm": 10.0}
#: The paper's camera's design (its Figure 6 design).
PAPER_DESIGN = "cfa/single"
#: The reference sensor's key.
LUTHER = "Luther (XYZ)"


def light_label(kind: str, value: float | str) -> str:
    """A light's name in the results: ``"6500 K"`` for a blackbody, else its colour-science name.

    Parameters
    ----------
    kind : str
        ``"blackbody"`` or ``"cie"`` (:data:`LIGHTS`).
    value : float or str
        The blackbody's temperature, K, or the CIE light's name.

    Returns
    -------
    str
        The label.
    """
    return f"{value:g} K" if kind == "blackbody" else str(value)


def light_family(kind: str, value: float | str) -> str:
    """A light's family (:data:`FAMILIES`): blackbody, daylight (``D…``), fluorescent (``FL…``) or LED (``LED…``).

    Parameters
    ----------
    kind : str
        ``"blackbody"`` or ``"cie"`` (:data:`LIGHTS`).
    value : float or str
        The blackbody's temperature, K, or the CIE light's name.

    Returns
    -------
    str
        The family; ``"other"`` for a CIE name of none of them.
    """
    if kind == "blackbody":
        return "blackbody"
    name = str(value)
    if name.startswith("FL"):
        return "fluorescent"
    if name.startswith("LED"):
        return "LED"
    if name.startswith("D"):
        return "daylight"
    return "other"


def light_spec(kind: str, value: float | str, level: float) -> IlluminantSpec:
    """A light of :data:`LIGHTS` as an illuminant.

    Parameters
    ----------
    kind : str
        ``"blackbody"`` or ``"cie"``.
    value : float or str
        The blackbody's temperature, K, or the CIE light's name.
    level : float
        Its white luminance, cd/m².

    Returns
    -------
    IlluminantSpec
        The light.
    """
    from spectracam.scene.illuminant import IlluminantSpec

    if kind == "blackbody":
        return IlluminantSpec("blackbody", float(value), None, level)
    return IlluminantSpec("cie", None, str(value), level)


def estimators() -> list[str]:
    """Every registered estimator but the oracle (which is the truth)."""
    from spectracam.processing.white_balance import WHITE_BALANCE_METHODS

    return [m for m in WHITE_BALANCE_METHODS.names if m != "oracle"]


@dataclasses.dataclass(frozen=True)
class Sensor:
    key: str            # its name in the results
    label: str          # what the report calls it
    filters: dict       # the scene's [filters] table
    range_nm: tuple | None = None   # the curves' range, to which the grid is narrowed


def sensors(exp: PaperExperiment) -> list[Sensor]:
    """The paper's camera, every usable shipped measured camera, the Luther camera.

    Parameters
    ----------
    exp : PaperExperiment
        The paper's experiment: its base scene's filters are the paper's camera's.

    Returns
    -------
    list of Sensor
        The paper's camera first, the Luther camera last.
    """
    from spectracam.architecture.cameras import CAMERAS, library_curves
    from spectracam.experiments.validate.experiment import _usable

    base = exp.base.to_dict()["filters"]
    cut = "/".join(f"{c:g}" for c in base.get("cutoffs_nm", []))
    paper = Sensor("paper", f"the paper's camera ({PAPER_DESIGN}, {base['kind']} filters {cut} nm, {base['qe']} QE)",
                   base)
    measured = [Sensor(n, f"{n} (measured curves, flat QE)", {"kind": "camera", "camera": n, "qe": "flat"},
                       tuple(library_curves(n).range_nm)) for n in CAMERAS if _usable(n)]
    return [paper, *measured, Sensor(LUTHER, "Luther camera (CIE 1931 x̄ȳz̄ filters, flat QE): the reference",
                                     {"kind": "xyz", "qe": "flat"})]


@dataclasses.dataclass(frozen=True)
class WhiteBalanceRun:
    """What a run measures; :func:`plan` builds and validates it before any work."""

    quick: bool
    seeds: int
    renderer: str
    sets: tuple
    sensors: tuple               # Sensor
    scenes: dict                 # sensor key → scene name → Scene (illuminant: the scene file's, replaced per light)

    @property
    def grids(self) -> list[tuple]:
        """``[(grid, [sensor keys])]``: the sensors that share a wavelength grid share its renders."""
        out: list = []
        for s in self.sensors:
            grid = next(iter(self.scenes[s.key].values())).grid
            for g, keys in out:
                if g == grid:
                    keys.append(s.key)
                    break
            else:
                out.append((grid, [s.key]))
        return out

    def jobs(self) -> list[tuple]:
        """``(grid index, scene name)``: one job renders the scene under every light and captures it with every
        sensor of that grid (it trains the estimator those sensors need for that scene's scored colours); the
        largest first."""
        jobs = [(g, name) for g in range(len(self.grids)) for name in SCENES.values()]
        return sorted(jobs, key=lambda j: -len(self.grids[j[0]][1]))

    @property
    def cases_per_sensor(self) -> int:
        return len(SCENES) * len(LIGHTS)


def case_scene(exp: PaperExperiment, sensor: Sensor, file: str, quick: bool,
               sets: Iterable[str | tuple[str, object]] = ()) -> Scene:
    """The scene ``file`` (shipped) as ``sensor`` captures it, with ``--set`` applied.

    Parameters
    ----------
    exp : PaperExperiment
        The paper's experiment: its base scene's optics, sensor, capture and processing.
    sensor : Sensor
        Its filters, and the wavelength range its curves cover.
    file : str
        The shipped scene file's stem, e.g. ``"mondrian"``.
    quick : bool
        :data:`QUICK_IMAGE_PX` instead of :data:`IMAGE_PX`.
    sets : iterable of str or (str, object)
        ``--set``: ``PATH=VALUE`` strings or ``(path, value)`` pairs.

    Returns
    -------
    Scene
        Validated, the developed camera's processing, the grid narrowed to the sensor's range.
    """
    from spectracam.pipeline.overrides import apply_overrides
    from spectracam.pipeline.scene_file import parse_scene, read_toml, shipped_scene_file

    base = exp.base.to_dict()
    w, h = QUICK_IMAGE_PX if quick else IMAGE_PX
    data = read_toml(shipped_scene_file(f"{file}.toml"), "scene file")
    capture = {**base["capture"], "architecture": PAPER_DESIGN.split("/")[0], "exposure": PAPER_DESIGN.split("/")[1]}
    data = {**data, "image": {"width": w, "height": h}, "wavelengths": dict(WAVELENGTHS), "optics": base["optics"],
            "filters": dict(sensor.filters), "sensor": base["sensor"], "capture": capture,
            "processing": {**base["processing"], "camera": "developed"}}
    source = f"spectracam white-balance ({sensor.key}, {file})"
    if sets:
        data = apply_overrides(data, sets, defaults=lambda: parse_scene(data, source).to_dict())
    wl = data.get("wavelengths")
    if sensor.range_nm is not None and isinstance(wl, dict) and "start_nm" in wl and "stop_nm" in wl:
        lo, hi = sensor.range_nm
        try:
            data = {**data, "wavelengths": {**wl, "start_nm": max(float(wl["start_nm"]), lo),
                                            "stop_nm": min(float(wl["stop_nm"]), hi)}}
        except (TypeError, ValueError):
            pass  # a wrong value: the scene's own check names it
    return parse_scene(data, source if not sets else f"{source} with the command line's options")


def plan(quick: bool = False, seeds: int | None = None, renderer: str = "analytic",
         sets: Iterable[str | tuple[str, object]] = (), exp: PaperExperiment | None = None) -> WhiteBalanceRun:
    """Every sensor's every scene, validated (a bad ``--set`` is one line before any work).

    Parameters
    ----------
    quick : bool
        Smaller images and fewer seeds (:data:`QUICK_IMAGE_PX`, :data:`QUICK_SEEDS`).
    seeds : int or None
        Noise seeds per case (None: :data:`SEEDS`, or :data:`QUICK_SEEDS` with ``quick``).
    renderer : str
        ``"analytic"`` or ``"mitsuba"``.
    sets : iterable of str or (str, object)
        ``--set``: applied to every case's scene.
    exp : PaperExperiment or None
        The paper's experiment (None: ``paper.toml``, shipped).

    Returns
    -------
    WhiteBalanceRun
        Every sensor and scene.
    """
    from spectracam.pipeline.scene_file import shipped_scene_file
    from spectracam.experiments.paper.experiment import load_experiment

    exp = exp or load_experiment(shipped_scene_file("paper.toml"))
    sens = tuple(sensors(exp))
    scenes = {s.key: {name: case_scene(exp, s, file, quick, tuple(sets)) for file, name in SCENES.items()}
              for s in sens}
    n = seeds if seeds is not None else (QUICK_SEEDS if quick else SEEDS)
    return WhiteBalanceRun(quick, int(n), renderer, tuple(sets), sens, scenes)


# ------------------------------------------------------------------------------------------------ the measurement


def _processings(scene) -> dict:
    """Each estimator's processing (the scene's, its estimator replaced), validated once."""
    return {m: scene.processing.replace(white_balance=m) for m in estimators()}


def measure(cube: RadianceCube, scene: Scene, seed: int, processings: dict | None = None) -> dict:
    """One capture of ``cube`` as ``scene`` and every estimator's neutral and errors on it.

    Parameters
    ----------
    cube : RadianceCube
        The scene rendered under its light.
    scene : Scene
        The camera and processing that capture it.
    seed : int
        The noise seed.
    processings : dict or None
        Estimator → its processing (None: the scene's with each estimator of :func:`estimators`).

    Returns
    -------
    dict
        ``exposure_ms`` per channel, ``pixels_used`` of ``pixels``, ``true_neutral`` (max 1) and ``estimates``:
        estimator → ``recovery_deg``, ``reproduction_deg`` and its ``neutral`` (max 1).
    """
    from spectracam.pipeline import capture
    from spectracam.processing import scored_reflectances
    from spectracam.processing.calibration import white_neutral
    from spectracam.processing.white_balance import (Estimation, estimate_neutral, recovery_error_deg, reproduction_error_deg,
                                            usable_pixels)
    from spectracam.scene.reference import ChartReference, TargetReference
    from spectracam.evaluation.score import camera_rates

    processings = processings or _processings(scene)
    raw = capture(cube, seed=seed, scene=scene)
    image = camera_rates(raw, scene.processing, ChartReference.of(scene))
    camera = raw.camera
    true = white_neutral(scene.illuminant, scene.grid, camera)
    scored = scored_reflectances(ChartReference.of(scene), TargetReference.of(scene) if scene.target.textured else None)
    ctx = Estimation(image, usable_pixels(image, raw.exposure_times_s, camera.sensor), scene.processing, camera,
                     scene.grid, true, scored)
    out = {}
    for m, p in processings.items():
        e = estimate_neutral(dataclasses.replace(ctx, processing=p))
        out[m] = {"recovery_deg": float(recovery_error_deg(e, true)),
                  "reproduction_deg": float(reproduction_error_deg(e, true)),
                  "neutral": np.round(e / e.max(), 6).tolist()}
    return {"exposure_ms": [float(1e3 * t) for t in raw.exposure_times_s], "pixels_used": int(ctx.valid.sum()),
            "pixels": int(ctx.valid.size), "true_neutral": np.round(true / true.max(), 6).tolist(), "estimates": out}


def training_block(scene: Scene) -> dict:
    """The trained estimator's training block for ``scene``'s sensor and scored colours (memoised: trained once per
    process for each sensor, grid and set of scored colours).

    Parameters
    ----------
    scene : Scene
        Its camera, grid, training library and scored colours (excluded from the training).

    Returns
    -------
    dict
        The trained correction, as a dict.
    """
    from spectracam.processing import scored_reflectances, training_camera
    from spectracam.processing.white_balance import exclusion_key, trained_correction
    from spectracam.scene.reference import ChartReference, TargetReference

    scored = scored_reflectances(ChartReference.of(scene), TargetReference.of(scene) if scene.target.textured else None)
    return trained_correction(training_camera(scene.camera), scene.grid, scene.processing.white_balance_training,
                              exclusion_key(scored)).to_dict()


def run_job(run: WhiteBalanceRun, job: tuple, tick: Callable[[], object] = lambda: None) -> tuple[list[dict], dict]:
    """One scene on one grid: each light rendered once and captured by every sensor of the grid, every seed.
    ``(rows, {sensor: training block})``; ``tick`` after each light.

    Parameters
    ----------
    run : WhiteBalanceRun
        The run.
    job : tuple
        ``(grid index, scene name)``, of :meth:`WhiteBalanceRun.jobs`.
    tick : callable
        Called after each light.

    Returns
    -------
    rows : list of dict
        One per sensor, light and seed: the case and :func:`measure`'s numbers.
    training : dict
        Sensor → its training block (empty without the trained estimator).

    Raises
    ------
    SpectracamError
        Naming the case, when a capture or an estimate fails.
    """
    from spectracam.render import render

    g, name = job
    _, keys = run.grids[g]
    procs = {key: _processings(run.scenes[key][name]) for key in keys}
    training = {key: training_block(run.scenes[key][name]) for key in keys} \
        if "corrected_moments" in estimators() else {}
    rows = []
    for kind, value in LIGHTS:
        cube = None
        for key in keys:
            base = run.scenes[key][name]
            scene = base.replace(illuminant=light_spec(kind, value, base.illuminant.white_luminance_cd_m2))
            if cube is None:
                cube = render(scene, renderer=run.renderer)
            for seed in range(run.seeds):
                try:
                    m = measure(cube, scene, seed, procs[key])
                except SpectracamError as e:   # a plain error (pickles from a worker), naming the case
                    raise SpectracamError(f"white-balance: {key}, {name} under {light_label(kind, value)}, seed "
                                          f"{seed}: {e}") from None
                rows.append({"sensor": key, "scene": name, "light": light_label(kind, value),
                             "family": light_family(kind, value), "seed": seed, **m})
        tick()
    return rows, training


_SHARED: dict = {}   # what forked workers inherit instead of receiving it pickled


def _job(i: int) -> tuple[list[dict], dict]:
    run = _SHARED["run"]
    return run_job(run, run.jobs()[i])


def _one_thread():
    import os

    from spectracam.core.processes import die_with_parent

    die_with_parent()
    os.environ["SPECTRACAM_THREADS"] = "1"


def _run_forked(run: WhiteBalanceRun, jobs: list, n: int, keep: Callable[[tuple, tuple], object],
                update: Callable[[int], object]) -> None:
    """:func:`run_white_balance`'s jobs in ``n`` processes forked from this one; ``keep(job, result)`` in the jobs'
    order, ``update(lights)`` after each."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    _SHARED["run"] = run
    try:
        with ProcessPoolExecutor(n, mp_context=multiprocessing.get_context("fork"),
                                 initializer=_one_thread) as ex:
            for job, r in zip(jobs, ex.map(_job, range(len(jobs)))):
                keep(job, r)
                update(len(LIGHTS))
    finally:
        _SHARED.clear()


class WhiteBalanceResult(TypedDict):
    """What :func:`run_white_balance` returns, results.json's keys but ``command``: the trained estimator's
    training block by sensor and scene, a row per case and seed, the statistics by sensor and estimator
    (:func:`sensor_statistics`) and :data:`DEFINITIONS`."""

    experiment: str
    parameters: dict
    training: dict[str, dict[str, dict]]
    cases: list[dict]
    statistics: dict[str, dict]
    definitions: dict[str, str]
    seconds: float


def run_white_balance(run: WhiteBalanceRun, log: Callable[[str], object] = lambda msg: None, progress: bool = False,
                      workers: int | None = None) -> WhiteBalanceResult:
    """Every case's errors, the statistics and the parameters (results.json).  The jobs run in processes forked
    from this one, one per core (the analytic renderer; Mitsuba renders here on its own threads); the numbers do
    not depend on how many (each capture has its own seed).

    Parameters
    ----------
    run : WhiteBalanceRun
        What to measure (:func:`plan`).
    log : callable
        ``log(line)``: the captures made and the time.
    progress : bool
        A bar over the scene × light renders.
    workers : int or None
        Processes (None: one per core, ``SPECTRACAM_THREADS`` if set, at most one per job).

    Returns
    -------
    WhiteBalanceResult
        The rows sorted by sensor, scene, light and seed, the training blocks, the statistics and the parameters.
    """
    import multiprocessing
    import os

    from spectracam.core.progress import bar

    t0 = time.perf_counter()
    jobs = run.jobs()
    n = workers or min(len(jobs), int(os.environ.get("SPECTRACAM_THREADS") or os.cpu_count() or 1))
    rows: list = []
    training: dict = {}

    def keep(job, result):
        rows.extend(result[0])
        for key, block in result[1].items():
            training.setdefault(key, {})[job[1]] = block

    with bar(total=len(jobs) * len(LIGHTS), desc="scene × light", unit="render", progress=progress) as b:
        if n < 2 or run.renderer != "analytic" or "fork" not in multiprocessing.get_all_start_methods():
            for job in jobs:
                keep(job, run_job(run, job, b.update))
        else:
            _run_forked(run, jobs, n, keep, b.update)
    order = {s.key: i for i, s in enumerate(run.sensors)}
    scene_order = {n: i for i, n in enumerate(SCENES.values())}
    light_order = {light_label(*x): i for i, x in enumerate(LIGHTS)}
    rows.sort(key=lambda r: (order[r["sensor"]], scene_order[r["scene"]], light_order[r["light"]], r["seed"]))
    training = {s.key: {name: training[s.key][name] for name in SCENES.values()} for s in run.sensors
                if s.key in training}
    seconds = time.perf_counter() - t0
    log(f"{len(rows)} captures in {seconds:.1f} s ({n if run.renderer == 'analytic' else 1} process(es))")
    return {"experiment": "white-balance", "parameters": parameters(run), "training": training,
            "cases": rows, "statistics": sensor_statistics(rows, [s.key for s in run.sensors], estimators()),
            "definitions": DEFINITIONS, "seconds": seconds}


def parameters(run: WhiteBalanceRun) -> dict:
    """results.json's ``parameters``: the run's settings, every scene, light and sensor (with its camera), each
    estimator's settings and the processing.

    Parameters
    ----------
    run : WhiteBalanceRun
        The run.

    Returns
    -------
    dict
        JSON-ready.
    """
    from spectracam.processing import white_balance as wb

    first = run.scenes[run.sensors[0].key]
    any_scene = first["chart"]
    proc = any_scene.processing
    settings = {m: {} for m in estimators()}
    settings.update({k: v for k, v in {
        "white_patch": {"percentile": wb.WHITE_PATCH_PERCENTILE},
        "shades_of_grey": {"p": proc.white_balance_p},
        "grey_edge": {"p": proc.white_balance_p, "sigma_px": proc.white_balance_sigma_px},
        "corrected_moments": {"training_library": proc.white_balance_training, "moment_orders": list(wb.MOMENT_ORDERS),
                              "edge_orders": list(wb.EDGE_ORDERS), "scenes_per_light": wb.TRAINING_SCENES_PER_LIGHT,
                              "surfaces": list(wb.TRAINING_SURFACES), "seed": wb.TRAINING_SEED,
                              "exclude_rms": wb.EXCLUDE_RMS, "ridge": wb.TRAINING_RIDGE,
                              "training_lights": [light_label(k, v) for k, v in wb.TRAINING_LIGHTS]},
    }.items() if k in settings})
    trained_on = {light_label(k, v) for k, v in wb.TRAINING_LIGHTS}
    return {
        "quick": run.quick, "renderer": run.renderer, "seeds": list(range(run.seeds)), "sets": list(run.sets),
        "image_px": [any_scene.image.width, any_scene.image.height],
        "scenes": {name: {"file": f"{file}.toml", "title": first[name].name, "target": first[name].target.kind,
                          "library": first[name].target.library if first[name].target.textured else None,
                          "chart": first[name].chart.dataset,
                          # the scene as the first sensor captures it, its light and camera aside (below)
                          "scene": {k: v for k, v in first[name].to_dict().items()
                                    if k not in ("illuminant", "optics", "filters", "sensor", "capture")}}
                   for file, name in SCENES.items()},
        "lights": [{"label": light_label(k, v), "family": light_family(k, v), "type": k,
                    **({"temperature_K": v} if k == "blackbody" else {"name": v}),
                    "white_luminance_cd_m2": any_scene.illuminant.white_luminance_cd_m2,
                    "in_trained_estimators_training": light_label(k, v) in trained_on} for k, v in LIGHTS],
        "sensors": [{"key": s.key, "label": s.label, "filters": s.filters,
                     "wavelengths_nm": [float(run.scenes[s.key]["chart"].grid.edges_nm[0]),
                                        float(run.scenes[s.key]["chart"].grid.edges_nm[-1])],
                     "camera": run.scenes[s.key]["chart"].camera.to_dict()} for s in run.sensors],
        "estimators": settings, "clip_share": wb.CLIP_SHARE,
        "processing": proc.to_dict(), "metering": "the developed camera's (processing.camera = developed)",
        "cases_per_sensor": len(SCENES) * len(LIGHTS),
    }


DEFINITIONS = {
    "recovery_deg": "angle between the estimated and the true neutral in camera space (Hordley & Finlayson 2006)",
    "reproduction_deg": "angle between true/estimate and the achromatic (1, …, 1) (Finlayson & Zakizadeh 2014)",
    "mean, median, p95": "over every case (scene × light) and seed of the sensor; p95 = numpy.percentile(x, 95)",
    "mean_spread_over_seeds": "sample standard deviation (ddof = 1) of the per-seed means; null with one seed",
    "by_family": "the mean over the cases under each light family",
    "by_scene": "the mean over the cases of each scene",
}


# ------------------------------------------------------------------------------------------------ statistics


def error_statistics(values: ArrayLike, seeds: ArrayLike | None = None, families: Sequence[str] | None = None,
                     scenes: Sequence[str] | None = None) -> dict:
    """Mean, median, 95th percentile and maximum of ``values``; with ``seeds``, each seed's mean and their sample
    standard deviation (``None`` with one seed); with ``families`` (``scenes``), each light family's (scene's) mean.

    Parameters
    ----------
    values : array_like
        Errors, degrees.
    seeds : array_like or None
        Each value's noise seed.
    families : sequence of str or None
        Each value's light family.
    scenes : sequence of str or None
        Each value's scene.

    Returns
    -------
    dict
        ``n``, ``mean``, ``median``, ``p95``, ``max``; ``per_seed_mean`` and ``mean_spread_over_seeds``,
        ``by_family`` (in :data:`FAMILIES`' order), ``by_scene`` where asked for.

    Raises
    ------
    SpectracamError
        With no value, or one not finite.

    Examples
    --------
    >>> error_statistics([1.0, 2.0, 3.0, 4.0])["median"]
    2.5
    """
    x = np.asarray(values, float)
    if x.size == 0 or not np.all(np.isfinite(x)):
        raise SpectracamError(f"white-balance statistics: {x.size} values, "
                              f"{int(np.sum(~np.isfinite(x)))} of them not finite")
    out = {"n": int(x.size), "mean": float(x.mean()), "median": float(np.median(x)),
           "p95": float(np.percentile(x, 95)), "max": float(x.max())}
    if seeds is not None:
        s = np.asarray(seeds)
        per_seed = [float(x[s == k].mean()) for k in sorted(set(s.tolist()))]
        out["per_seed_mean"] = per_seed
        out["mean_spread_over_seeds"] = float(np.std(per_seed, ddof=1)) if len(per_seed) > 1 else None
    if families is not None:
        f = np.asarray(families)
        present = [k for k in FAMILIES if np.any(f == k)] + sorted(set(f.tolist()) - set(FAMILIES))
        out["by_family"] = {k: float(x[f == k].mean()) for k in present}
    if scenes is not None:
        sc = np.asarray(scenes)
        out["by_scene"] = {k: float(x[sc == k].mean()) for k in dict.fromkeys(sc.tolist())}
    return out


def sensor_statistics(rows: list[dict], sensor_keys: Iterable[str], methods: Sequence[str]) -> dict:
    """``{sensor: {estimator: {"recovery_deg": stats, "reproduction_deg": stats}}}`` over the rows.

    Parameters
    ----------
    rows : list of dict
        The cases (:func:`run_job`).
    sensor_keys : iterable of str
        The sensors.
    methods : sequence of str
        The estimators.

    Returns
    -------
    dict
        Each sensor's and estimator's :func:`error_statistics` of either angle, with seeds, families and scenes.
    """
    out = {}
    for key in sensor_keys:
        mine = [r for r in rows if r["sensor"] == key]
        seeds, fams, scenes = [r["seed"] for r in mine], [r["family"] for r in mine], [r["scene"] for r in mine]
        out[key] = {m: {e: error_statistics([r["estimates"][m][e] for r in mine], seeds, fams, scenes)
                        for e in ("recovery_deg", "reproduction_deg")} for m in methods}
    return out


# ------------------------------------------------------------------------------------------------ outputs


def _num(x, fmt=".2f") -> str:
    return "–" if x is None else format(x, fmt)


def white_balance_markdown(result: dict, command: str) -> str:
    """report.md: the set-up, a table per sensor of each estimator's errors (with means per light family and
    scene), every sensor's recovery mean, the definitions and the estimators' settings.

    Parameters
    ----------
    result : dict
        What :func:`run_white_balance` returns.
    command : str
        The command line that made it.

    Returns
    -------
    str
        Markdown.
    """
    from spectracam.processing.white_balance import TRAINING_LIGHTS

    p = result["parameters"]
    stats = result["statistics"]
    methods = list(p["estimators"])
    lights = ", ".join(x["label"] for x in p["lights"])
    trained = ", ".join(light_label(k, v) for k, v in TRAINING_LIGHTS)
    held = [x["label"] for x in p["lights"] if not x["in_trained_estimators_training"]]
    lines = ["# White-balance estimators per sensor", "", f"`{command}`", "",
             f"{p['cases_per_sensor']} cases per sensor ({len(p['scenes'])} scenes × {len(p['lights'])} lights), "
             f"{len(p['seeds'])} noise seed(s) each, {p['image_px'][0]}×{p['image_px'][1]} px, renderer "
             f"{p['renderer']}; {result['seconds']:.0f} s.", "",
             "* scenes: " + ", ".join(f"{k} ({v['title']})" for k, v in p["scenes"].items()),
             f"* lights ({p['lights'][0]['white_luminance_cd_m2']:g} cd/m² white): {lights}",
             "* capture: the developed camera's metering (percentile of its own preview), every noise source on; "
             "each sensor shares the paper's optics, pixel, ADC and noise — only the spectral design differs",
             "* the estimators see the demosaicked, exposure-normalised camera image and its unclipped pixels",
             "",
             f"**The trained estimator (corrected_moments)** was trained on {p['processing']['white_balance_training']} "
             f"Mondrians under TRAINING_LIGHTS = {trained}, never on the scored scene's colours. So the fluorescent "
             "and LED lights are held-out lights for it (and, of the lights here, " + ", ".join(held) + " are not in "
             "its training set). The other estimators are not trained.", ""]
    for s in p["sensors"]:
        lines += _sensor_table(s, stats[s["key"]], methods, p["scenes"])
    lines += ["## Recovery error mean (°), every sensor", "",
              "| estimator | " + " | ".join(s["key"] for s in p["sensors"]) + " |",
              "|---|" + "---|" * len(p["sensors"])]
    for m in methods:
        lines.append(f"| {m} | " + " | ".join(f"{stats[s['key']][m]['recovery_deg']['mean']:.2f}"
                                             for s in p["sensors"]) + " |")
    lines += ["", "## Definitions", ""] + [f"* **{k}**: {v}" for k, v in result["definitions"].items()]
    lines += ["", "## Estimator settings", ""] + [f"* **{m}**: {v or 'no parameter'}" for m, v in
                                                  p["estimators"].items()]
    return "\n".join(lines) + "\n"


def _sensor_table(s: dict, st: dict, methods: list, scenes: dict) -> list[str]:
    """:func:`white_balance_markdown`'s section of one sensor ``s``: a row per estimator of its statistics ``st``."""
    lines = [f"## {s['label']}", "",
             f"Grid {s['wavelengths_nm'][0]:g}–{s['wavelengths_nm'][1]:g} nm.", "",
             "| estimator | recovery mean ± seed spread | median | p95 | max | reproduction mean | median | p95 | "
             + " | ".join(f"recovery mean, {f}" for f in FAMILIES) + " | "
             + " | ".join(f"recovery mean, {n}" for n in scenes) + " |",
             "|---|" + "---|" * (7 + len(FAMILIES) + len(scenes))]
    for m in methods:
        r, q = st[m]["recovery_deg"], st[m]["reproduction_deg"]
        spread = r.get("mean_spread_over_seeds")
        lines.append(f"| {m} | {r['mean']:.2f}" + (f" ± {spread:.2g}" if spread is not None else "")
                     + f" | {r['median']:.2f} | {r['p95']:.2f} | {r['max']:.2f} | {q['mean']:.2f} | "
                     f"{q['median']:.2f} | {q['p95']:.2f} | "
                     + " | ".join(_num(r["by_family"].get(f)) for f in FAMILIES) + " | "
                     + " | ".join(_num(r["by_scene"].get(n)) for n in scenes) + " |")
    lines.append("")
    return lines


FAMILY_COLOURS = {"blackbody": "#d35400", "daylight": "#2c6fbb", "fluorescent": "#27ae60", "LED": "#8e44ad"}


def white_balance_figure(result: dict) -> Figure:
    """Recovery error distribution per estimator, one panel per sensor: boxes (quartiles, whiskers 5–95 %), the
    mean (white diamond) and every case coloured by its light family.

    Parameters
    ----------
    result : dict
        What :func:`run_white_balance` returns.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, not saved.
    """
    from spectracam.io.plots import pyplot

    plt = pyplot()
    p = result["parameters"]
    methods = list(p["estimators"])
    sens = p["sensors"]
    fig, axes = plt.subplots(1, len(sens), figsize=(3.0 * len(sens) + 1.0, 4.6), sharey=True, squeeze=False)
    rng = np.random.default_rng(0)
    top = max(max(r["estimates"][m]["recovery_deg"] for r in result["cases"]) for m in methods)
    for ax, s in zip(axes[0], sens):
        mine = [r for r in result["cases"] if r["sensor"] == s["key"]]
        data = [[r["estimates"][m]["recovery_deg"] for r in mine] for m in methods]
        ax.boxplot(data, whis=(5, 95), showfliers=False, widths=0.6,
                   medianprops={"color": "black"}, boxprops={"color": "#555555"})
        for j, m in enumerate(methods):
            fam = [r["family"] for r in mine]
            x = j + 1 + rng.uniform(-0.22, 0.22, len(mine))
            ax.scatter(x, data[j], s=8, alpha=0.6, linewidths=0,
                       c=[FAMILY_COLOURS.get(f, "grey") for f in fam], zorder=3)
            ax.plot(j + 1, np.mean(data[j]), "D", mfc="white", mec="black", ms=5, zorder=4)
        ax.set_xticks(range(1, len(methods) + 1), [m.replace("_", "\n") for m in methods], fontsize=7)
        title = s["key"] if s["key"] != "paper" else "paper's camera"
        ax.set_title(title.replace(" (", "\n("), fontsize=9)
        ax.grid(axis="y", alpha=0.3)
        ax.set_ylim(0, top * 1.05)
    axes[0][0].set_ylabel("recovery angular error, degrees")
    handles = [plt.Line2D([], [], ls="", marker="o", color=c, label=f) for f, c in FAMILY_COLOURS.items()]
    handles.append(plt.Line2D([], [], ls="", marker="D", mfc="white", mec="black", label="mean"))
    fig.legend(handles=handles, loc="lower center", ncol=len(handles), fontsize=8, frameon=False)
    fig.suptitle(f"White-balance estimators: {p['cases_per_sensor']} scene × light cases per sensor, "
                 f"{len(p['seeds'])} seed(s) (boxes: quartiles, whiskers 5–95 %)", fontsize=10)
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    return fig


def write_white_balance_outputs(out_dir: str | Path, result: dict, command: str) -> list:
    """results.json, report.md and white_balance.png/.svg, atomically.

    Parameters
    ----------
    out_dir : str or Path
        The output folder.
    result : dict
        What :func:`run_white_balance` returns.
    command : str
        The command line, in results.json and report.md.

    Returns
    -------
    list of Path
        The PNG, the SVG, the JSON and the Markdown file.
    """
    from spectracam.io.report import write_figure_json_markdown

    return write_figure_json_markdown(out_dir, "white_balance", white_balance_figure(result), "results.json", result,
                                      command, "report.md", white_balance_markdown(result, command))


def summary_line(result: dict, key: str) -> str:
    """One line per sensor: each estimator's recovery error mean / median / p95.

    Parameters
    ----------
    result : dict
        What :func:`run_white_balance` returns.
    key : str
        The sensor.

    Returns
    -------
    str
        The line, naming the estimator of the lowest mean.
    """
    st = result["statistics"][key]
    best = min(st, key=lambda m: st[m]["recovery_deg"]["mean"])
    return f"  {key}: recovery error mean/median/p95 (°) " + "; ".join(
        f"{m} {v['recovery_deg']['mean']:.2f}/{v['recovery_deg']['median']:.2f}/{v['recovery_deg']['p95']:.2f}"
        for m, v in st.items()) + f" — best {best}"
