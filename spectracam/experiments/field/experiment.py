"""Which architecture keeps colour uniform to the corner, and with which microlens shift (issue 37, item 5):
``spectracam field``.

Every design (architecture / exposure scheme) × pixel pitch (:data:`PITCHES_UM`: 1.4 and 10 µm) × microlens shift ×
lens-shading correction captures two scenes through a stated lens and pixel:

* the lens: the relative illumination falls as cos⁴ of the chief ray's angle, which grows linearly with image height
  to :data:`CRA_CORNER_DEG` at the sensor's corner (``--cra``; 25°, a phone-class camera module);
* the pixel (``[pixel]``, :class:`spectracam.sensor.angle.PixelAngleSpec`): microlens acceptance, optical and
  electrical crosstalk and the filters' angle shifts on (:data:`PIXEL`), the microlens shifted by a fraction of what
  would centre the corner's chief ray (:data:`SHIFTS`: 0, ½, 1);
* the corrections (:data:`CORRECTIONS`, ``processing.shading``): none; one gain table per channel calibrated on a
  flat field under a 2960 K light and applied under the scene's (``single``); tables at 2960, 4850 and 5930 K
  interpolated to the light's colour temperature, as libcamera's ALSC does (``cct``).

The scenes, under the d65 scene's light (``--set`` changes it):

* ``flat``: the chart's Neutral 5 filling the field.  Its rendered colour is averaged in :data:`RADIAL_BINS` rings of
  relative image height r (0 at the centre, 1 at the corner) and scored as ΔE*ab (CIE 1976) of each ring's mean
  colour against the scene (``delta_e_ab``) and against the centre ring's (``delta_e_centre``: the colour shading,
  which the conversion's own error does not enter; ``delta_ab_centre``, its chroma part √(Δa*² + Δb*²), the colour
  shading without the lightness), the ring's luminance against the centre's, and the ring's mean
  per-pixel S-CIELAB against the scene;
* ``chart``: the ColorChecker filling the field (its patches' centres lie at r = 0.18 … 0.73).  Each patch's mean per-pixel
  ΔE*ab and S-CIELAB against the scene, and ``delta_e_axis``: ΔE*ab between its mean colour and that of the same
  design on the axis (no field: the paper's camera), the colour the field alone costs.

Every camera is the paper's (told the light: its conversion fitted on the chart's noise-free rates on the axis) and
metered on the chart's white patch as the axis sees it (a camera meters its preview, not its corner).  Every number
is the mean over ``seeds`` noise seeds with its standard deviation.
"""
from __future__ import annotations

import dataclasses
import time
from typing import TYPE_CHECKING, TypedDict

import numpy as np

from spectracam.core.errors import SpectracamError

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence
    from pathlib import Path

    from matplotlib.figure import Figure

__all__ = ["CORRECTIONS", "CRA_CORNER_DEG", "DESIGNS", "GREY_PATCH", "MAP_BLOCK_PX", "PITCHES_UM", "PIXEL", "QUICK_IMAGE_PX", "RADIAL_BINS", "SHIFTS",
           "WHITE_PATCH", "FieldResult", "FieldRun", "field_figure", "field_markdown", "field_maps_figure", "plan",
           "radial_bins", "run_field", "summary_lines", "write_field_outputs"]

#: The paper's three architectures, each with the exposure scheme its section 5 favours.
DESIGNS = ("cfa/single", "prism/optimal", "fsc/optimal")
#: The chief ray's angle at the sensor's corner, degrees: 25°, a phone-class module (its lens is far from
#: telecentric); the IMX477's libcamera table needs a 1.55 corner gain, cos⁴ 25.3° (docs/metrics.md, "Field").
CRA_CORNER_DEG = 25.0
#: The pixel's response to the angle: every effect on (spectracam.sensor.angle; their defaults' sources there).
PIXEL = {"microlens": True, "optical_crosstalk": True, "electrical_crosstalk": True, "filter_angle": True}
#: Pixel pitches, µm: a phone-class module's 1.4 µm (where a 25° chief ray moves the spot by a large part of the
#: pixel) and the paper's sensor's 10 µm (``sensor.pixel_pitch_um`` of the shipped scenes).
PITCHES_UM = (1.4, 10.0)
#: Microlens shifts, as fractions of the shift that centres the corner's chief ray on the photodiode
#: (``pixel.microlens_shift_fraction``): none, half, full.
SHIFTS = (0.0, 0.5, 1.0)
#: Lens-shading corrections (``processing.shading``).
CORRECTIONS = ("none", "single", "cct")
#: Rings of relative image height the flat field is averaged in (r = 0 … 1 in equal steps).
RADIAL_BINS = 10
#: The chart's middle grey (Neutral 5, 0-based) and its white.
GREY_PATCH, WHITE_PATCH = 21, 18
#: The maps' blocks, pixels: each block's mean colour (the noise averaged, the shading kept).
MAP_BLOCK_PX = 8
#: Image size of ``--quick``.
QUICK_IMAGE_PX = (320, 240)


@dataclasses.dataclass(frozen=True)
class FieldRun:
    """What a run measures; :func:`plan` builds and validates it before any work."""

    quick: bool
    seeds: int
    renderer: str
    sets: tuple
    scene: object          # the chart scene (lens and pixel set, --set applied)
    designs: tuple
    shifts: tuple
    corrections: tuple
    cra_corner_deg: float
    pitches_um: tuple


class FieldResult(TypedDict, total=False):
    parameters: dict
    rows: list
    seconds: float
    #: The checks against real measurements (IMX477 tables, lensfun); None with ``--quick``.
    measured: dict | None
    #: (design, correction) → the flat grey's ΔE*ab map at the largest shift, first seed (not written to JSON).
    maps: dict


def _scene(quick: bool, sets: tuple, cra_deg: float):
    from spectracam.pipeline.overrides import apply_overrides
    from spectracam.pipeline.scene_file import parse_scene, read_toml, shipped_scene_file

    data = read_toml(shipped_scene_file("d65.toml"), "scene file")
    data = {**data, "optics": {**data.get("optics", {}), "relative_illumination": "cos4", "chief_ray": "linear",
                               "cra_corner_deg": float(cra_deg)},
            "pixel": {**data.get("pixel", {}), **PIXEL}}
    if quick:
        w, h = QUICK_IMAGE_PX
        data = {**data, "image": {**data.get("image", {}), "width": w, "height": h}}
    source = "spectracam field (d65.toml, cos4 lens, every pixel effect on)"
    if sets:
        data = apply_overrides(data, sets, defaults=lambda: parse_scene(data, source).to_dict())
        source += " with the command line's options"
    return parse_scene(data, source)


def plan(quick: bool = False, seeds: int | None = None, renderer: str = "analytic", sets: Sequence[str] = (),
         designs: Sequence[str] = DESIGNS, shifts: Sequence[float] | None = None,
         corrections: Sequence[str] | None = None, cra_deg: float = CRA_CORNER_DEG,
         pitches_um: Sequence[float] | None = None) -> FieldRun:
    """The scene with ``sets`` applied, and the cases, validated (a bad value is one line before any work).

    Parameters
    ----------
    quick : bool
        ``--quick``: shifts 0 and 1, a 1.4 µm pixel, one seed (each unless given).
    seeds : int or None
    renderer : str
    sets : sequence of str
        ``--set PATH=VALUE``; not the paths a case sets (shift, correction, chief-ray angle, pitch, design).
    designs, corrections : sequence of str, optional
    shifts, pitches_um : sequence of float, optional
        Microlens shifts (fractions of the ideal) and pixel pitches (µm); None: :data:`SHIFTS`, :data:`PITCHES_UM`.
    cra_deg : float
        The chief ray's angle at the corner, degrees (0–60).

    Returns
    -------
    FieldRun

    Raises
    ------
    SpectracamError
        On an invalid value.
    """
    from spectracam.processing.shading import SHADING_CORRECTIONS

    shifts = tuple(float(s) for s in (((0.0, 1.0) if quick else SHIFTS) if shifts is None else shifts))
    corrections = tuple(CORRECTIONS if corrections is None else corrections)
    for c in corrections:
        if c not in SHADING_CORRECTIONS:
            raise SpectracamError(f"--correction = {c!r}: not a lens-shading correction; one of "
                                  + ", ".join(SHADING_CORRECTIONS))
    if not isinstance(cra_deg, (int, float)) or isinstance(cra_deg, bool) or not 0 < cra_deg < 60:
        raise SpectracamError(f"--cra = {cra_deg!r}: the chief ray's angle at the corner must be between 0 and 60°")
    for s in sets:   # what the command varies per case is not also a --set (it would be silently overwritten)
        for path, option in (("pixel.microlens_shift_fraction", "--shift"), ("processing.shading", "--correction"),
                             ("optics.cra_corner_deg", "--cra"), ("sensor.pixel_pitch_um", "--pitch"),
                             ("capture.architecture", "--design"),
                             ("capture.exposure", "--design"), ("capture.design", "--design")):
            if str(s).split("=", 1)[0].strip() == path:
                raise SpectracamError(f"--set {s}: field sets {path} for each case; use {option}")
    scene = _scene(quick, tuple(sets), float(cra_deg))
    if scene.camera.optics.on_axis:
        raise SpectracamError("--set: the lens is on the axis (optics.relative_illumination = 'none' and no chief-ray "
                              "angle); field measures the field")
    for d in designs:
        scene.camera.with_design(d, "--design")
    for s in shifts:
        scene.camera.pixel.replace(microlens_shift_fraction=s)   # its own check, one line
    pitches = tuple(float(p) for p in (((1.4,) if quick else PITCHES_UM) if pitches_um is None else pitches_um))
    for p in pitches:
        scene.camera.sensor.replace(pixel_pitch_um=p)
    n = seeds if seeds is not None else (1 if quick else 2)
    return FieldRun(quick, int(n), renderer, tuple(sets), scene, tuple(designs), shifts, corrections, float(cra_deg),
                    pitches)


def radial_bins(shape: tuple[int, int], n: int = RADIAL_BINS) -> np.ndarray:
    """Each pixel's ring ``(H, W)`` int: ⌊n·r⌋ (clipped to n − 1) of its relative image height r = distance from the
    image's centre over the half diagonal.

    Parameters
    ----------
    shape : tuple of int
        ``(H, W)``.
    n : int
        Rings.

    Returns
    -------
    ndarray
        ``(H, W)`` int64, 0 … n − 1.
    """
    h, w = shape
    y = np.arange(h) - (h - 1) / 2.0
    x = np.arange(w) - (w - 1) / 2.0
    r = np.hypot(y[:, None], x[None, :]) / np.hypot((h - 1) / 2.0, (w - 1) / 2.0)
    return np.minimum((r * n).astype(np.int64), n - 1)


def _patch_radius(reference) -> np.ndarray:
    h, w = reference.height_px, reference.width_px
    half = np.hypot((h - 1) / 2.0, (w - 1) / 2.0)
    return np.array([np.hypot((r.start + r.stop - 1) / 2.0 - (h - 1) / 2.0, (c.start + c.stop - 1) / 2.0 - (w - 1) / 2.0)
                     / half for r, c in reference.boxes])


def _mean_sd(values) -> tuple:
    v = np.asarray(values, float)
    return v.mean(axis=0), (v.std(axis=0, ddof=1) if v.shape[0] > 1 else np.zeros(v.shape[1:]))


def _flat_score(raw, reference, processing, rings: np.ndarray, truth_lab: np.ndarray) -> dict:
    """The flat grey's rings: each ring's mean colour's ΔE*ab against the scene and against the centre ring, its
    luminance over the centre's, its mean per-pixel S-CIELAB against the scene; and the per-pixel ΔE*ab from the
    centre's colour, averaged in blocks of :data:`MAP_BLOCK_PX` (the map)."""
    from spectracam.core.cielab import delta_e, xyz_to_lab
    from spectracam.evaluation.scielab import scielab
    from spectracam.evaluation.score import display_rgb
    from spectracam.processing.color import display_rgb_to_xyz

    rgb, _ = display_rgb(raw, reference, processing)
    M_disp = display_rgb_to_xyz(processing.display)
    white = M_disp.sum(axis=1)
    xyz = rgb.astype(np.float64) @ M_disp.T
    n = int(rings.max()) + 1
    flat_rings = rings.ravel()
    counts = np.bincount(flat_rings, minlength=n)
    ring_xyz = np.stack([np.bincount(flat_rings, weights=xyz[..., k].ravel(), minlength=n) for k in range(3)], -1) \
        / counts[:, None]
    ring_lab = xyz_to_lab(ring_xyz, white)
    truth_xyz = _lab_to_xyz(truth_lab, white)
    sc = scielab(xyz, np.broadcast_to(truth_xyz, xyz.shape), white,
                 processing.samples_per_degree)
    b = MAP_BLOCK_PX
    h, w = (xyz.shape[0] // b) * b, (xyz.shape[1] // b) * b
    blocks = xyz[:h, :w].reshape(h // b, b, w // b, b, 3).mean(axis=(1, 3))
    de_map = delta_e(xyz_to_lab(blocks, white), np.broadcast_to(ring_lab[0], blocks.shape))
    return {"delta_e_ab": delta_e(ring_lab, np.broadcast_to(truth_lab, ring_lab.shape)),
            "delta_e_centre": delta_e(ring_lab, np.broadcast_to(ring_lab[0], ring_lab.shape)),
            "delta_ab_centre": np.hypot(*(ring_lab[:, 1:] - ring_lab[0, 1:]).T),
            "luminance_ratio": ring_xyz[:, 1] / ring_xyz[0, 1],
            "s_cielab": np.bincount(flat_rings, weights=sc.ravel(), minlength=n) / counts, "map": de_map}


def _lab_to_xyz(lab, white) -> np.ndarray:
    """CIE 1976 L*a*b* → XYZ on the white's scale (CIE 15:2018's inverse)."""
    L, a, b = np.asarray(lab, float)[..., 0], np.asarray(lab, float)[..., 1], np.asarray(lab, float)[..., 2]
    fy = (L + 16) / 116
    f = np.stack([fy + a / 500, fy, fy - b / 200], -1)
    d = 6 / 29
    t = np.where(f > d, f**3, 3 * d * d * (f - 4 / 29))
    return t * np.asarray(white, float)


def _chart_score(raw, reference, processing) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per patch: mean per-pixel ΔE*ab, mean per-pixel S-CIELAB, rendered mean L*a*b*."""
    from spectracam.evaluation.score import score

    s = score(raw, reference, processing)
    return (np.array([p.delta_e_mean for p in s.patches]),
            np.array([np.nan if p.s_cielab_mean is None else p.s_cielab_mean for p in s.patches]),
            np.array([p.rendered_lab for p in s.patches], float))


def _capture(cube, camera, seed: int, reference):
    from spectracam.camera.capture import capture

    return capture(cube, camera, seed, white_radiance=reference.patch_radiance[WHITE_PATCH])


def _design_rows(run: FieldRun, scene, reference, chart, flat, rings, radius, design: str, pitch: float, maps: dict,
                 log, progress: bool) -> list:
    """The rows of one design at one pixel pitch: every microlens shift × correction."""
    from spectracam.core.cielab import delta_e
    from spectracam.evaluation.score import score

    base = scene.camera.with_design(design, "--design")
    base = base.replace(sensor=base.sensor.replace(pixel_pitch_um=pitch))
    axis = base.replace(optics=base.optics.replace(relative_illumination="none", cra_corner_deg=0.0),
                        pixel=type(base.pixel)())
    axis_scores = [score(_capture(chart, axis, seed, reference), reference, scene.processing)
                   for seed in range(run.seeds)]
    axis_lab = np.mean([[p.rendered_lab for p in s.patches] for s in axis_scores], axis=0)
    truth_lab = np.array(axis_scores[0].patches[GREY_PATCH].scene_lab, float)
    outer = radius >= np.median(radius)
    rows = []
    for shift in run.shifts:
        camera = base.replace(pixel=base.pixel.replace(microlens_shift_fraction=shift))
        raws = [(_capture(flat, camera, seed, reference), _capture(chart, camera, seed, reference))
                for seed in range(run.seeds)]
        for correction in run.corrections:
            processing = scene.processing.replace(shading=correction)
            flats = [_flat_score(f, reference, processing, rings, truth_lab) for f, _ in raws]
            charts = [_chart_score(c, reference, processing) for _, c in raws]
            row = {"design": design, "pixel_pitch_um": pitch, "microlens_shift_fraction": shift,
                   "correction": correction, "exposure_ms": [1e3 * t for t in raws[0][1].exposure_times_s]}
            for k in ("delta_e_ab", "delta_e_centre", "delta_ab_centre", "luminance_ratio", "s_cielab"):
                m, sd = _mean_sd([f[k] for f in flats])
                row[f"flat_{k}"], row[f"flat_{k}_sd"] = m.tolist(), sd.tolist()
            de, sde = _mean_sd([c[0] for c in charts])
            sc, ssc = _mean_sd([c[1] for c in charts])
            axis_de, axis_sd = _mean_sd([delta_e(c[2], axis_lab) for c in charts])
            corner = [f["delta_e_centre"][-1] for f in flats]
            corner_ab = [f["delta_ab_centre"][-1] for f in flats]
            outer_de = [float(np.mean(delta_e(c[2], axis_lab)[outer])) for c in charts]
            row.update({"chart_delta_e_ab": de.tolist(), "chart_delta_e_ab_sd": sde.tolist(),
                        "chart_s_cielab": sc.tolist(), "chart_s_cielab_sd": ssc.tolist(),
                        "chart_delta_e_axis": axis_de.tolist(), "chart_delta_e_axis_sd": axis_sd.tolist(),
                        "flat_corner_delta_e_centre": float(np.mean(corner)),
                        "flat_corner_delta_e_centre_sd": float(np.std(corner, ddof=1)) if len(corner) > 1 else 0.0,
                        "flat_corner_delta_ab_centre": float(np.mean(corner_ab)),
                        "flat_corner_delta_ab_centre_sd": float(np.std(corner_ab, ddof=1)) if len(corner_ab) > 1
                        else 0.0,
                        "chart_outer_delta_e_axis": float(np.mean(outer_de)),
                        "chart_outer_delta_e_axis_sd": float(np.std(outer_de, ddof=1)) if len(outer_de) > 1 else 0.0,
                        "chart_mean_delta_e_ab": float(np.mean(de))})
            rows.append(row)
            if shift == max(run.shifts) and pitch == min(run.pitches_um):
                maps[(design, correction)] = flats[0]["map"]
            if progress:
                log(f"{design:14s} {pitch:4.1f} µm, shift {shift:3.1f}, {correction:6s}: flat grey's corner "
                    f"ΔE*ab {row['flat_corner_delta_e_centre']:5.2f} from its centre; chart's outer half "
                    f"{row['chart_outer_delta_e_axis']:5.2f} from the axis")
    return rows


def run_field(run: FieldRun, log: Callable[[str], object] = print, progress: bool = True) -> FieldResult:
    """Every case of ``run``: a row per design × pixel pitch × microlens shift × correction.

    Parameters
    ----------
    run : FieldRun
        :func:`plan`'s.
    log : callable
        ``log(line)`` per case.
    progress : bool

    Returns
    -------
    FieldResult
        The parameters, rows, the measured lenses (:mod:`.measured`), the time (s) and the maps.
    """
    from spectracam.render import RadianceCube, render
    from spectracam.scene.reference import ChartReference

    t0 = time.perf_counter()
    scene = run.scene
    reference = ChartReference.of(scene)
    chart = render(scene, run.renderer)
    flat = RadianceCube(np.ascontiguousarray(np.broadcast_to(reference.patch_radiance[GREY_PATCH].astype(np.float32),
                                                             chart.radiance.shape)), chart.wavelengths_nm,
                        {**chart.metadata, "flat": "Neutral 5 filling the field"})
    rings = radial_bins(chart.radiance.shape[:2])
    radius = _patch_radius(reference)
    rows, maps = [], {}
    for design in run.designs:
        for pitch in run.pitches_um:
            rows += _design_rows(run, scene, reference, chart, flat, rings, radius, design, pitch, maps, log, progress)
    params = {"seeds": run.seeds, "renderer": run.renderer, "quick": run.quick, "sets": list(run.sets),
              "designs": list(run.designs), "microlens_shift_fractions": list(run.shifts),
              "corrections": list(run.corrections), "cra_corner_deg": run.cra_corner_deg,
              "pixel_pitches_um": list(run.pitches_um),
              "radial_bins": RADIAL_BINS, "ring_edges": np.linspace(0, 1, RADIAL_BINS + 1).tolist(),
              "patch_radius": radius.tolist(), "patch_names": list(reference.names),
              "light_cct_K": _cct(reference), "scene": scene.to_dict()}
    measured = None if run.quick else _measured(log)
    return FieldResult(parameters=params, rows=rows, measured=measured, seconds=time.perf_counter() - t0, maps=maps)


def _measured(log) -> dict:
    """The checks against real measurements (:mod:`spectracam.experiments.field.measured`): the Raspberry Pi HQ
    camera's lens-shading tables and a lensfun lens's vignetting; each None, with the reason, where its data is not
    installed."""
    from spectracam.experiments.field.measured import imx477_reproduction, lensfun_reproduction

    out: dict = {}
    for name, check in (("imx477", imx477_reproduction), ("lensfun", lensfun_reproduction)):
        try:
            out[name] = check()
        except SpectracamError as e:
            out[name], out[f"{name}_not_run"] = None, str(e)
            log(f"not checked against {name}: {e}")
    return out


def _cct(reference) -> float:
    from spectracam.processing.calibration import light_cct_K

    return light_cct_K(reference.illuminant)


# ------------------------------------------------------------------------------------------------ the outputs


def field_figure(result: dict) -> Figure:
    """The flat grey's colour shading (ΔE*ab from the centre's colour) against relative image height: a column per
    design, a line per microlens shift (colour) and correction (style).

    Parameters
    ----------
    result : dict
        :func:`run_field`'s.

    Returns
    -------
    matplotlib.figure.Figure
        A row per pixel pitch.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    p = result["parameters"]
    designs, shifts, corrections = p["designs"], p["microlens_shift_fractions"], p["corrections"]
    pitches = p["pixel_pitches_um"]
    edges = np.asarray(p["ring_edges"])
    r = 0.5 * (edges[1:] + edges[:-1])
    fig, axes = plt.subplots(len(pitches), len(designs), figsize=(3.9 * len(designs) + 1.8, 3.3 * len(pitches) + 0.6),
                             sharex=True, sharey=True, squeeze=False)
    colours = ("#0072B2", "#E69F00", "#009E73", "#CC79A7", "#56B4E9")   # Okabe–Ito: distinct for colour-blind readers
    styles = {"none": "-", "single": "--", "cct": ":"}
    for k, pitch in enumerate(pitches):
        for col, design in enumerate(designs):
            ax = axes[k][col]
            for i, s in enumerate(shifts):
                for c in corrections:
                    row = next(x for x in result["rows"] if x["design"] == design and x["pixel_pitch_um"] == pitch
                               and x["microlens_shift_fraction"] == s and x["correction"] == c)
                    ax.plot(r, row["flat_delta_e_centre"], styles.get(c, "-"), color=colours[i % len(colours)],
                            lw=1.4, label=f"shift {s:g}, {c}")
            ax.set_title(f"{design}, {pitch:g} µm pixels", fontsize=9)
            ax.set_yscale("symlog", linthresh=0.1)
            ax.grid(alpha=0.3)
            if k == len(pitches) - 1:
                ax.set_xlabel("relative image height r")
        axes[k][0].set_ylabel("flat grey: ΔE*ab from the centre", fontsize=9)
    axes[0][-1].legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=7, frameon=False)
    fig.suptitle(f"Colour shading of a flat grey, CRA {p['cra_corner_deg']:g}° at the corner, cos⁴ fall-off", fontsize=10)
    fig.tight_layout()
    return fig


def field_maps_figure(run_maps: dict, result: dict) -> Figure:
    """Maps: each design's flat grey as rendered, ΔE*ab from the centre's colour per pixel (block-averaged), a column
    per correction, at the largest microlens shift.

    Parameters
    ----------
    run_maps : dict
        The result's ``maps``.
    result : dict
        :func:`run_field`'s (its parameters).

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    p = result["parameters"]
    designs, corrections = p["designs"], p["corrections"]
    fig, axes = plt.subplots(len(designs), len(corrections), figsize=(3.2 * len(corrections) + 1.2,
                                                                      2.5 * len(designs)), squeeze=False)
    top = max(float(np.nanmax(m)) for m in run_maps.values()) or 1.0
    im = None
    for i, d in enumerate(designs):
        for j, c in enumerate(corrections):
            ax = axes[i][j]
            im = ax.imshow(run_maps[(d, c)], cmap="magma", vmin=0.0, vmax=top)
            ax.set_xticks([])
            ax.set_yticks([])
            if i == 0:
                ax.set_title(f"correction: {c}", fontsize=9)
            if j == 0:
                ax.set_ylabel(d, fontsize=9)
    fig.colorbar(im, ax=axes, shrink=0.8, label="ΔE*ab from the centre's colour")
    fig.suptitle(f"Flat grey, {min(p['pixel_pitches_um']):g} µm pixels, microlens shift "
                 f"{max(p['microlens_shift_fractions']):g}, CRA {p['cra_corner_deg']:g}° at the corner", fontsize=10)
    return fig


def _fmt(v, f="{:.2f}") -> str:
    return "—" if v is None or (isinstance(v, float) and not np.isfinite(v)) else f.format(v)


def field_markdown(result: dict, command: str) -> str:
    """report.md: the corner's colour shading and the chart's cost of the field, per design, shift and correction.

    Parameters
    ----------
    result : dict
        :func:`run_field`'s.
    command : str
        The command, recorded at the top.

    Returns
    -------
    str
    """
    p = result["parameters"]
    lines = ["# Off the axis: which architecture keeps colour uniform to the corner", "", f"Command: `{command}`", "",
             f"Lens: cos⁴ relative illumination, chief ray linear to {p['cra_corner_deg']:g}° at the corner; pixel: "
             "microlens, optical and electrical crosstalk and the filters' angle shifts on; light "
             f"{p['light_cct_K']:.0f} K. Seeds: {p['seeds']}; renderer: {p['renderer']}. ΔE*ab is CIE 1976 "
             "(docs/metrics.md, \"Field\").", "",
             "| design | pixel (µm) | microlens shift | correction | flat grey at the corner: ΔE*ab from the centre | "
             "its chroma shift √(Δa*² + Δb*²) | "
             "luminance at the corner / centre | chart's outer half: ΔE*ab from the axis | chart ΔE*ab (scene) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in result["rows"]:
        lines.append(f"| {r['design']} | {r['pixel_pitch_um']:g} | {r['microlens_shift_fraction']:g} | {r['correction']} | "
                     f"{r['flat_corner_delta_e_centre']:.2f} ± {r['flat_corner_delta_e_centre_sd']:.2f} | "
                     f"{r['flat_corner_delta_ab_centre']:.2f} | "
                     f"{r['flat_luminance_ratio'][-1]:.3f} | {r['chart_outer_delta_e_axis']:.2f} ± "
                     f"{r['chart_outer_delta_e_axis_sd']:.2f} | "
                     f"{r['chart_mean_delta_e_ab']:.2f} |")
    if result.get("measured"):
        from spectracam.experiments.field.measured import measured_markdown

        lines += ["", measured_markdown(result["measured"].get("imx477"), result["measured"].get("lensfun"))]
    return "\n".join(lines) + "\n"


def summary_lines(result: dict) -> list[str]:
    """Per design and pixel pitch: the shift and correction that keep the corner's colour closest to the centre's.

    Parameters
    ----------
    result : dict
        :func:`run_field`'s.

    Returns
    -------
    list of str
        One line each, for the command's log.
    """
    out = []
    for d in result["parameters"]["designs"]:
        for pitch in result["parameters"]["pixel_pitches_um"]:
            rows = [r for r in result["rows"] if r["design"] == d and r["pixel_pitch_um"] == pitch]
            best = min(rows, key=lambda r: r["flat_corner_delta_e_centre"])
            out.append(f"  {d:14s} {pitch:4.1f} µm: most uniform with shift {best['microlens_shift_fraction']:g} and "
                       f"correction {best['correction']}: the corner's grey ΔE*ab "
                       f"{best['flat_corner_delta_e_centre']:.2f} from the centre's")
    return out


def write_field_outputs(out_dir: str | Path, result: dict, command: str) -> list:
    """results.json, report.md, field.png/.svg and (with the result's maps) field_maps.png/.svg, atomically.

    Parameters
    ----------
    out_dir : str or Path
    result : dict
        :func:`run_field`'s (its maps are kept out of results.json).
    command : str

    Returns
    -------
    list of Path
        The files written.
    """
    from pathlib import Path

    from spectracam.io.plots import save_figure
    from spectracam.io.report import write_figure_json_markdown

    maps = result.get("maps")
    result = {k: v for k, v in result.items() if k != "maps"}
    paths = write_figure_json_markdown(out_dir, "field", field_figure(result), "results.json", result, command,
                                       "report.md", field_markdown(result, command))
    if maps:
        paths += save_figure(field_maps_figure(maps, result), Path(out_dir) / "field_maps.png",
                             Path(out_dir) / "field_maps.svg")
    return paths
