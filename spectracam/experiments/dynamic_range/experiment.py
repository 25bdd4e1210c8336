"""Which architecture and read-out keep colour across a high-dynamic-range scene (issue 36, item 5):
``spectracam dynamic-range``.

Every design (architecture / exposure scheme) × read-out (:data:`spectracam.sensor.READOUT_NAMES`) × die temperature
captures the shipped light-group scenes (:mod:`spectracam.scene.lights`):

* ``ladder`` (``scenes/hdr_ladder.toml``) — ColorCheckers side by side, each under the same daylight at its own level,
  white luminances spaced evenly in log from 0.01 to 100 000 cd/m²;
* ``charts`` (``scenes/hdr_charts.toml``) — a chart in sun beside one in deep shade under sky light.

Two exposures of each scene:

* ``scene`` — one exposure for the whole scene, metered on the brightest chart's white (paper 4.5) to ``white_fill``
  of what the read-out encodes (``headroom`` × the well: a high-dynamic-range read-out exposes longer, for the
  shadows), then shortened to the hand-held limit if longer: the dynamic range *within* one scene;
* ``chart`` — each chart's own exposure (metered on its own white, shortened to the limit): the range of scene
  levels the camera works at, where the hand-held limit, not the well, sets the low end.

Each chart's rendering is display-referred: clipped to the display's range (``processing.gamut_clip``, on here), as a
screen shows it; a chart the exposure starves is then scored on what a screen would show, not on noise amplified
past any display.

Each chart is scored as the paper scores its one chart (:func:`spectracam.evaluation.score.score_region`): the
conversion fitted under its own light and level (the camera told the light, as the paper's; each chart rendered
against its own white, as an eye adapted to that part of the scene sees it), per-pixel ΔE*ab (CIE 1976) and CIEDE2000
against the truth, S-CIELAB, and the rendered-luminance SNR of its white and of its middle grey (Neutral 5), each the
mean over ``seeds`` noise seeds with its spread; and ``delta_e_capture``, the per-pixel ΔE against the camera's own
noise-free rendering of the chart.  The **kept range** of a run of the ladder is the span of white luminances over
which the mean ΔE stays below :data:`DELTA_E_KEPT`, interpolated in log luminance between charts, measured both
against the camera's noise-free rendering (``against = "capture"``: what the sensor and its read-out keep) and
against the scene (``"scene"``: the filters' own conversion error included); a bound at the ladder's end is
reported as such (``lo_open`` / ``hi_open``: the range may be larger).
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

    from spectracam.camera import CameraSpec
    from spectracam.camera.capture import RawCapture
    from spectracam.pipeline.scene_file import Scene
    from spectracam.render import RadianceCube
    from spectracam.scene.reference import ChartCell

__all__ = ["DELTA_E_KEPT", "DESIGNS", "GREY_PATCH", "HAND_HELD_LIMIT_S", "KEPT_METRICS", "QUICK_IMAGE_PX", "SCENES", "TEMPERATURES_C",
           "DynamicRangeResult", "DynamicRangeRun", "chart_rows", "dynamic_range_figure", "dynamic_range_markdown",
           "expose_hdr", "kept_range", "plan", "run_dynamic_range", "summary_lines", "write_dynamic_range_outputs"]

#: The shipped scenes: name in the results → scene file.
SCENES = {"ladder": "hdr_ladder.toml", "charts": "hdr_charts.toml"}
#: The paper's three architectures, each with the exposure scheme its section 5 favours.
DESIGNS = ("cfa/single", "prism/optimal", "fsc/optimal")
#: Die temperatures, °C: room (the paper's dark current), warm, automotive grade 2 (AEC-Q100: up to 105 °C).
TEMPERATURES_C = (25.0, 65.0, 105.0)
#: The hand-held limit, s: 1/30 s, the slowest shutter the 1/focal-length rule allows a phone-class lens.
HAND_HELD_LIMIT_S = 1.0 / 30.0
#: A colour is kept while its mean ΔE*ab is below this: 3, the issue's threshold, just above the 2.15 ΔE*ab mean
#: perceptibility tolerance for pictorial images (Stokes, Fairchild & Berns 1992 [Stokes1992]).
DELTA_E_KEPT = 3.0
#: The chart's middle grey (0-based: Neutral 5, 0.70 density) and its white.
GREY_PATCH, WHITE = 21, 18
#: Image size of ``--quick`` (each chart a cell of it).
QUICK_IMAGE_PX = {"ladder": (640, 240), "charts": (320, 120)}
EXPOSURES = ("scene", "chart")
#: What a kept colour is measured against: ``capture`` — this camera's own noise-free rendering of the chart (what
#: the sensor and read-out lose: noise, quantisation, clipping; the filters' conversion error aside); ``scene`` — the
#: scene's truth (the conversion error included: a camera whose filters alone miss by 3 keeps nothing).
KEPT_METRICS = {"capture": "delta_e_capture", "scene": "delta_e_ab"}


@dataclasses.dataclass(frozen=True)
class DynamicRangeRun:
    """What a run measures; :func:`plan` builds and validates it before any work."""

    quick: bool
    seeds: int
    renderer: str
    sets: tuple
    scenes: dict          # name → Scene (the --set applied)
    designs: tuple
    readouts: tuple
    temperatures_C: tuple
    time_limit_s: float


def _scene(name: str, quick: bool, sets: tuple):
    from spectracam.pipeline.overrides import apply_overrides
    from spectracam.pipeline.scene_file import parse_scene, read_toml, shipped_scene_file

    data = read_toml(shipped_scene_file(SCENES[name]), "scene file")
    # display-referred: each chart is shown clipped to the display's range, as a screen shows it (a chart the exposure
    # starves would otherwise be scored on noise amplified ~10⁷ past any display; --set processing.gamut_clip=false)
    data = {**data, "processing": {**data.get("processing", {}), "gamut_clip": True}}
    if quick:
        w, h = QUICK_IMAGE_PX[name]
        data = {**data, "image": {**data.get("image", {}), "width": w, "height": h}}
    source = f"spectracam dynamic-range ({SCENES[name]})"
    if sets:
        data = apply_overrides(data, sets, defaults=lambda: parse_scene(data, source).to_dict())
        source += " with the command line's options"
    return parse_scene(data, source)


def plan(quick: bool = False, seeds: int | None = None, renderer: str = "analytic", sets: Sequence[str] = (),
         designs: Sequence[str] = DESIGNS, readouts: Sequence[str] | None = None,
         temperatures_C: Sequence[float] | None = None) -> DynamicRangeRun:
    """Every scene with ``sets`` applied, and the cases, validated (a bad value is one line before any work).

    Parameters
    ----------
    quick : bool
        ``--quick``: 25 and 105 °C, one seed (each unless given), smaller scenes.
    seeds : int or None
        None: 3 (1 with ``quick``).
    renderer : str
    sets : sequence of str
        ``--set PATH=VALUE``; not the paths a case sets (read-out, temperature, design).
    designs : sequence of str
    readouts : sequence of str or None
        None: every read-out.
    temperatures_C : sequence of float or None
        Die temperatures, °C; None: :data:`TEMPERATURES_C`.

    Returns
    -------
    DynamicRangeRun
        With the hand-held time limit, :data:`HAND_HELD_LIMIT_S`.

    Raises
    ------
    SpectracamError
        On an invalid value.
    """
    from spectracam.sensor import READOUT_NAMES

    readouts = tuple(READOUT_NAMES if readouts is None else readouts)
    temperatures = tuple(float(t) for t in (((25.0, 105.0) if quick else TEMPERATURES_C) if temperatures_C is None
                                            else temperatures_C))
    for r in readouts:
        if r not in READOUT_NAMES:
            raise SpectracamError(f"--readout = {r!r}: not a read-out; one of {', '.join(READOUT_NAMES)}")
    for s in sets:   # what the command varies per case is not also a --set (it would be silently overwritten)
        for path, option in (("sensor.readout", "--readout"), ("sensor.temperature_C", "--temperature"),
                             ("capture.architecture", "--design"), ("capture.exposure", "--design"),
                             ("capture.design", "--design")):
            if str(s).split("=", 1)[0].strip() == path:
                raise SpectracamError(f"--set {s}: dynamic-range sets {path} for each case; use {option}")
    scenes = {name: _scene(name, quick, tuple(sets)) for name in SCENES}
    for d in designs:
        scenes["ladder"].camera.with_design(d, "--design")
    for t in temperatures:   # the sensor's own check, once per temperature
        for r in readouts:
            scenes["ladder"].camera.sensor.replace(temperature_C=t, readout=r)
    n = seeds if seeds is not None else (1 if quick else 3)
    return DynamicRangeRun(quick, int(n), renderer, tuple(sets), scenes, tuple(designs), readouts, temperatures,
                           HAND_HELD_LIMIT_S)


def expose_hdr(cube: RadianceCube, camera: CameraSpec, seed: int, white_radiance: np.ndarray,
               limit_s: float) -> RawCapture:
    """A capture of ``cube`` metered on ``white_radiance`` ``(B,)`` (``white_fill`` of the read-out's range, the
    camera's exposure scheme), shortened in proportion to last at most ``limit_s``.

    Parameters
    ----------
    cube : RadianceCube
        W·m⁻²·sr⁻¹·nm⁻¹.
    camera : CameraSpec
    seed : int
        The noise seed.
    white_radiance : ndarray
        ``(B,)`` the metered white's radiance.
    limit_s : float
        The longest capture, s.

    Returns
    -------
    RawCapture
        Its metering recorded as ``hdr_white`` with the factor it was shortened by.
    """
    from spectracam.camera import band_weights
    from spectracam.camera.capture import RawCapture, capture_time_s
    from spectracam.sensor.exposure import exposure_times_s
    from spectracam.sensor.kernels import SpectralRates

    arch = camera.architecture()
    weights = band_weights(camera, cube.grid)
    white = np.asarray(white_radiance, np.float64) @ weights.astype(np.float64)
    times = exposure_times_s(camera.capture.exposure, white, camera.sensor, arch, camera.capture.white_fill,
                             camera.capture.exposure_split)
    scale = min(1.0, limit_s / capture_time_s(arch, times, camera.sensor))
    times = times * scale
    digital, expected = arch.record(SpectralRates(cube.radiance, weights), times, camera.sensor, seed)
    metering = {"kind": "hdr_white", "limit_ms": 1e3 * limit_s, "shortened_by": scale}
    return RawCapture(digital=digital, expected_e=expected, exposure_times_s=times,
                      capture_time_s=capture_time_s(arch, times, camera.sensor), layout=arch.layout, camera=camera,
                      seed=seed, metered_rate_e_per_s=white, scene=cube.metadata.get("scene"), metering=metering)


#: What each chart's row holds (means over seeds, and their standard deviations).
_METRICS = ("delta_e_ab", "delta_e_2000", "delta_e_capture", "s_cielab", "snr_white_db", "snr_grey_db")


def _cell_score(raw, rates, cell, processing) -> dict:
    from spectracam.evaluation.score import score_region

    patches, de2000, de_camera = score_region(raw, rates, cell.reference, processing)
    return {"delta_e_ab": float(np.mean([p.delta_e_mean for p in patches])), "delta_e_2000": float(np.mean(de2000)),
            "delta_e_capture": float(np.mean(de_camera)),
            "s_cielab": float(np.mean([p.s_cielab_mean for p in patches])),
            "snr_white_db": patches[WHITE].snr_rendered_db, "snr_grey_db": patches[GREY_PATCH].snr_rendered_db}


def _mean_sd(values) -> tuple[float | None, float | None]:
    v = np.array([np.nan if x is None else x for x in values], float)
    v = v[np.isfinite(v)]
    if not v.size:
        return None, None
    return float(v.mean()), float(v.std(ddof=1)) if v.size > 1 else 0.0


def chart_rows(cube: RadianceCube, scene: Scene, cells: Sequence[ChartCell], camera: CameraSpec,
               run: DynamicRangeRun, exposure: str) -> list[dict]:
    """One row per chart of ``scene`` for one camera and exposure (``scene`` or ``chart``), each metric's mean and
    standard deviation over the run's seeds.

    Parameters
    ----------
    cube : RadianceCube
        ``scene``'s render.
    scene : Scene
    cells : sequence of ChartCell
        Its charts (:func:`~spectracam.scene.reference.chart_cells`).
    camera : CameraSpec
    run : DynamicRangeRun
        Its seeds and time limit.
    exposure : str
        ``"scene"``: one capture metered on the brightest chart; ``"chart"``: one per chart, metered on it.

    Returns
    -------
    list of dict
        ``chart``, white luminance (cd/m²), exposure times (ms), a note (why not exposed) and each metric with
        ``_sd``.
    """
    from spectracam.evaluation.score import camera_rates

    brightest = max(cells, key=lambda c: c.reference.illuminant.white_luminance_cd_m2)
    per_cell: dict = {c.name: [] for c in cells}
    times: dict = {c.name: None for c in cells}
    notes: dict = {c.name: None for c in cells}
    for seed in range(run.seeds):
        groups = [(brightest, cells)] if exposure == "scene" else [(c, [c]) for c in cells]
        for metered, scored in groups:
            try:
                raw = expose_hdr(cube, camera, seed, metered.reference.patch_radiance[WHITE], run.time_limit_s)
            except SpectracamError as e:   # e.g. a hot die whose dark current outruns a dim chart's light
                for c in scored:
                    per_cell[c.name].append(dict.fromkeys(_METRICS))
                    notes[c.name] = f"not exposed: {e}"
                continue
            rates = camera_rates(raw, scene.processing, metered.reference)
            for c in scored:
                per_cell[c.name].append(_cell_score(raw, rates, c, scene.processing))
                times[c.name] = [1e3 * t for t in raw.exposure_times_s]
    rows = []
    for c in cells:
        row = {"chart": c.name, "white_luminance_cd_m2": float(c.reference.illuminant.white_luminance_cd_m2),
               "exposure_times_ms": times[c.name], "note": notes[c.name]}
        for k in _METRICS:
            row[k], row[k + "_sd"] = _mean_sd([s[k] for s in per_cell[c.name]])
        rows.append(row)
    return rows


def kept_range(rows: list[dict], threshold: float = DELTA_E_KEPT, metric: str = "delta_e_ab") -> dict:
    """The widest span of white luminance over which the mean ``metric`` stays below ``threshold``: the longest run of
    consecutive charts (by luminance) below it, each end moved to where it crosses the threshold, interpolated
    linearly in log luminance with the next chart; ``lo_open``/``hi_open`` when the run reaches the ladder's end.

    Parameters
    ----------
    rows : list of dict
        :func:`chart_rows`' of one case.
    threshold : float
        ΔE.
    metric : str
        A row key (None: not scored, never below).

    Returns
    -------
    dict
        ``lo_cd_m2``, ``hi_cd_m2`` (None when no chart is below), ``range_db`` (20·log₁₀ hi/lo), ``lo_open``,
        ``hi_open``.
    """
    rows = sorted(rows, key=lambda r: r["white_luminance_cd_m2"])
    lum = np.log10([r["white_luminance_cd_m2"] for r in rows])
    de = np.array([np.inf if r[metric] is None else r[metric] for r in rows])
    ok = de < threshold
    best, i = None, 0
    while i < len(rows):
        if ok[i]:
            j = i
            while j + 1 < len(rows) and ok[j + 1]:
                j += 1
            if best is None or lum[j] - lum[i] > lum[best[1]] - lum[best[0]]:
                best = (i, j)
            i = j + 1
        else:
            i += 1
    if best is None:
        return {"lo_cd_m2": None, "hi_cd_m2": None, "range_db": 0.0, "lo_open": False, "hi_open": False}

    def cross(a, b):   # log luminance where ΔE crosses the threshold between charts a (kept) and b (not)
        if not np.isfinite(de[b]):
            return lum[a]
        return lum[a] + (lum[b] - lum[a]) * (threshold - de[a]) / (de[b] - de[a])

    i, j = best
    lo = cross(i, i - 1) if i > 0 else lum[i]
    hi = cross(j, j + 1) if j + 1 < len(rows) else lum[j]
    return {"lo_cd_m2": float(10**lo), "hi_cd_m2": float(10**hi), "range_db": float(20 * (hi - lo)),
            "lo_open": i == 0, "hi_open": j + 1 == len(rows)}


class DynamicRangeResult(TypedDict):
    """results.json: the run's parameters, one row per chart and case, the kept ranges of the ladder."""

    parameters: dict
    rows: list
    kept: list
    seconds: float


def _cases(run: DynamicRangeRun):
    for design in run.designs:
        for readout in run.readouts:
            for t in run.temperatures_C:
                yield design, readout, t


def run_dynamic_range(run: DynamicRangeRun, log: Callable[[str], object] = print,
                      progress: bool = False) -> DynamicRangeResult:
    """Render each scene once; capture and score it for every case (see the module docstring).

    Parameters
    ----------
    run : DynamicRangeRun
        :func:`plan`'s.
    log : callable
        ``log(line)`` per case.
    progress : bool

    Returns
    -------
    DynamicRangeResult
        results.json's keys but ``command``.
    """
    from spectracam.pipeline import render
    from spectracam.scene.reference import chart_cells

    t0 = time.perf_counter()
    rows, kept = [], []
    for name, scene in run.scenes.items():
        cube = render(scene, run.renderer)
        cells = chart_cells(scene)
        for design, readout, t in _cases(run):
            camera = scene.camera.with_design(design)
            camera = camera.replace(sensor=camera.sensor.replace(readout=readout, temperature_C=t))
            for exposure in EXPOSURES:
                case = {"scene": name, "design": design, "readout": readout, "temperature_C": t, "exposure": exposure}
                these = chart_rows(cube, scene, cells, camera, run, exposure)
                rows += [{**case, **r} for r in these]
                if name == "ladder":
                    kept += [{**case, "against": against, **kept_range(these, metric=KEPT_METRICS[against])}
                             for against in KEPT_METRICS]
            log(f"  {name}: {design} {readout} {t:g} °C done ({time.perf_counter() - t0:.0f} s)")
    params = {"quick": run.quick, "seeds": run.seeds, "renderer": run.renderer, "sets": list(run.sets),
              "designs": list(run.designs), "readouts": list(run.readouts), "temperatures_C": list(run.temperatures_C),
              "time_limit_ms": 1e3 * run.time_limit_s, "delta_e_kept": DELTA_E_KEPT,
              "scenes": {k: s.to_dict() for k, s in run.scenes.items()}}
    return DynamicRangeResult(parameters=params, rows=rows, kept=kept, seconds=time.perf_counter() - t0)


# ------------------------------------------------------------------------------------------------ the outputs


def dynamic_range_figure(result: dict) -> Figure:
    """Mean ΔE against the chart's white luminance on the ladder (one exposure for the scene, the first temperature):
    against the scene (top) and against the camera's noise-free rendering (bottom), a column per design, a line per
    read-out; the kept threshold dashed; values above 1000 drawn at 1000.

    Parameters
    ----------
    result : dict
        :func:`run_dynamic_range`'s.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from spectracam.io.plots import palette, pyplot

    plt = pyplot()   # Agg, the colour-blind-safe cycle

    p = result["parameters"]
    designs, readouts, t0 = p["designs"], p["readouts"], p["temperatures_C"][0]
    fig, axes = plt.subplots(2, len(designs), figsize=(3.8 * len(designs) + 1.6, 6.4), sharex=True, sharey=True,
                             squeeze=False)
    colours = palette(len(readouts))
    for col, design in enumerate(designs):
        for row, (metric, label) in enumerate((("delta_e_ab", "ΔE*ab against the scene"),
                                                ("delta_e_capture", "ΔE against the noise-free capture"))):
            ax = axes[row][col]
            for k, readout in enumerate(readouts):
                rs = sorted((r for r in result["rows"] if r["scene"] == "ladder" and r["design"] == design
                             and r["readout"] == readout and r["temperature_C"] == t0 and r["exposure"] == "scene"),
                            key=lambda r: r["white_luminance_cd_m2"])
                y = np.minimum([np.nan if r[metric] is None else r[metric] for r in rs], 1e3)
                ax.plot([r["white_luminance_cd_m2"] for r in rs], y, "o-", color=colours[k], label=readout, ms=3)
            ax.axhline(DELTA_E_KEPT, color="0.4", ls="--", lw=0.8)
            ax.set_xscale("log")
            ax.set_yscale("log")
            if row == 0:
                ax.set_title(design)
            else:
                ax.set_xlabel("chart white luminance (cd/m²)")
            if col == 0:
                ax.set_ylabel(label, fontsize=9)
    axes[0][-1].legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8, frameon=False)
    fig.suptitle(f"One exposure for the whole ladder, metered on its brightest white, {t0:g} °C "
                 f"(dashed: ΔE = {DELTA_E_KEPT:g})", fontsize=10)
    fig.tight_layout()
    return fig


def _fmt(v, f="{:.2f}") -> str:
    return "—" if v is None else f.format(v)


def dynamic_range_markdown(result: dict, command: str) -> str:
    """report.md: the kept ranges of the ladder, then the two-chart scene's sun and shade.

    Parameters
    ----------
    result : dict
        :func:`run_dynamic_range`'s.
    command : str
        The command, recorded at the top.

    Returns
    -------
    str
    """
    p = result["parameters"]
    lines = ["# Dynamic range: which architecture and read-out keep colour", "", f"Command: `{command}`", "",
             f"Seeds: {p['seeds']}; renderer: {p['renderer']}; hand-held limit {p['time_limit_ms']:.1f} ms. "
             f"Kept: mean per-pixel ΔE < {p['delta_e_kept']:g}, against the camera's own noise-free rendering "
             "(`capture`: what the sensor and read-out lose) or against the scene (`scene`: the filters' conversion "
             "error included); the camera is told each chart's light (docs/metrics.md, \"Dynamic range\").", "",
             "## Kept range on the ladder (0.01–100 000 cd/m²)", "",
             "| design | read-out | °C | exposure | against | from (cd/m²) | to (cd/m²) | kept (dB) |",
             "|---|---|---|---|---|---|---|---|"]
    for k in result["kept"]:
        lo = ("≤ " if k["lo_open"] else "") + _fmt(k["lo_cd_m2"], "{:.3g}")
        hi = ("≥ " if k["hi_open"] else "") + _fmt(k["hi_cd_m2"], "{:.3g}")
        lines.append(f"| {k['design']} | {k['readout']} | {k['temperature_C']:g} | {k['exposure']} | {k['against']} | "
                     f"{lo} | {hi} | "
                     f"{k['range_db']:.1f} |")
    lines += ["", "## Sun and shade (hdr_charts), one exposure for the scene", "",
              "| design | read-out | °C | chart | white (cd/m²) | ΔE*ab | ΔE2000 | S-CIELAB | ΔE vs noise-free | "
              "SNR grey (dB) |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in result["rows"]:
        if r["scene"] == "charts" and r["exposure"] == "scene":
            lines.append(f"| {r['design']} | {r['readout']} | {r['temperature_C']:g} | {r['chart']} | "
                         f"{r['white_luminance_cd_m2']:.4g} | {_fmt(r['delta_e_ab'])} ± {_fmt(r['delta_e_ab_sd'])} | "
                         f"{_fmt(r['delta_e_2000'])} | {_fmt(r['s_cielab'])} | {_fmt(r['delta_e_capture'])} | "
                         f"{_fmt(r['snr_grey_db'], '{:.1f}')} |")
    return "\n".join(lines) + "\n"


def summary_lines(result: dict) -> list[str]:
    """One line per design and read-out: the range kept within one scene (against the camera's noise-free rendering)
    at the first temperature.

    Parameters
    ----------
    result : dict
        :func:`run_dynamic_range`'s.

    Returns
    -------
    list of str
        For the command's log, range in dB and cd/m².
    """
    t0 = result["parameters"]["temperatures_C"][0]
    return [f"  {k['design']:14s} {k['readout']:17s} kept {k['range_db']:5.1f} dB "
            f"({_fmt(k['lo_cd_m2'], '{:.3g}')}–{_fmt(k['hi_cd_m2'], '{:.3g}')} cd/m²)"
            for k in result["kept"] if k["temperature_C"] == t0 and k["exposure"] == "scene" and k["against"] == "capture"]


def write_dynamic_range_outputs(out_dir: str | Path, result: dict, command: str) -> list:
    """results.json, report.md and dynamic_range.png/.svg, atomically.

    Parameters
    ----------
    out_dir : str or Path
    result : dict
        :func:`run_dynamic_range`'s.
    command : str

    Returns
    -------
    list of Path
        The files written.
    """
    from spectracam.io.report import write_figure_json_markdown

    return write_figure_json_markdown(out_dir, "dynamic_range", dynamic_range_figure(result), "results.json", result,
                                      command, "report.md", dynamic_range_markdown(result, command))
