"""``spectracam architectures``: every registered architecture beside the paper's three, with the
paper's camera, light and noise (issue 20).

The camera, the chart and the light level are those of ``spectracam paper`` (its experiment file:
the level at which cfa/single needs the paper's exposure at the calibration temperature).  Each
architecture is captured with every exposure scheme that applies to it (``single`` for one
exposure; ``optimal`` and ``balanced`` too where the channels have their own exposures) under two
lights — the paper's error-budget illuminant (D65) and its warmest blackbody (3000 K) — at the
paper's level and at 1/10 and 1/100 of it (the render is linear in the level: one render per light),
and scored over several noise seeds (common random numbers: every design sees the same seeds).
At the paper's level each design is metered as the paper meters it (its first channel to fill
its well on the white patch ends the exposure).  Dimmed, a hand-held limit: each design is metered
at the dim light and its exposures scaled down so the capture lasts at most the Bayer array's
exposure at the paper's level (:func:`time_limit_s`) — without it every design would expose 10× and
100× longer and reach the same SNR; with it the arrays that collect more light per pixel (W, Y, C,
M filters) and the single-exposure designs show what they gain in dim light.

In space and time (:mod:`.architectures_spacetime`): one design per architecture on the spatial
experiment's slanted edge and Siemens star (MTF50, false colour, S-CIELAB; mosaics with and without an
optical low-pass filter) and the motion experiment's moving edge (colour breakup and S-CIELAB against the
design's own still capture), with the paper's pixel pitch and f-number.

Per row: the per-pixel ΔE against the scene and the chart's S-CIELAB on the same pixels (the eye's filters blur
every design's noise alike, so a demosaicker's averaging counts for no more than the eye's; docs/metrics.md), each
the mean and spread over seeds, the raw channels' combined
SNR and the rendered luminance SNR (after the colour conversion, so its noise amplification
counts; docs/metrics.md), the conversion's noise-free error on the 24 patches it is fitted on
(training) and on held-out colours (``processing.held_out``), and the capture time; and the same case captured
and developed by a camera that finds its own white (issue 33, :func:`developed_case`: ``developed_*`` fields —
its own percentile metering, held to the same time limit when dimmed, the trained white balance and the
dual-illuminant calibration), ranked beside the oracle's.  Every row says whether it is a usable image
(:mod:`.usability`: the white patch's rendered SNR and the mean S-CIELAB against stated thresholds); an unusable case
is never named a winner.

On natural scenes (:func:`natural_case`): each design captures the shipped textured targets (``NATURAL_SCENES``:
dead leaves of the CIE 2017 samples, a photograph made spectral) under D65 at the paper's level, scored per pixel
against their known spectra (:mod:`spectracam.evaluation.target_score`): per-pixel ΔE*ab and S-CIELAB on colours the
conversion was not fitted on, at each target's viewing geometry.
"""
from __future__ import annotations

import re

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, TypedDict

import numpy as np

from spectracam.architecture.base import ARCHITECTURES
from spectracam.camera.capture import capture, capture_time_s
from spectracam.core.errors import ConfigError
from spectracam.sensor.exposure import EXPOSURE_SCHEMES, METERED_SCHEMES
from spectracam.scene.illuminant import IlluminantSpec
from spectracam.scene.reference import ChartReference
from spectracam.evaluation.score import score
from spectracam.experiments.paper.experiment import PaperExperiment, calibrated_luminance, quick_scene, scaled
from spectracam.evaluation.usability import NO_USABLE_IMAGE, UsabilitySpec

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

    from spectracam.pipeline.scene_file import Scene
    from spectracam.render import RadianceCube

__all__ = ["LIGHT_FACTORS", "NATURAL_SCENES", "SEEDS", "WINNER_METRICS", "ArchitecturesResult", "ArchitecturesRun",
           "case", "designs", "developed_case", "judge", "natural_case", "restamped", "run_architectures",
           "run_natural", "time_limit_s", "winners", "write_architectures_outputs", "write_shots"]

#: Light levels, as fractions of the paper's (its calibrated white luminance).
LIGHT_FACTORS = (1.0, 0.1, 0.01)
#: Noise seeds per case (the full run; ``--quick`` uses 2).
SEEDS = 5
#: The shipped textured scenes (scenes/*.toml) every design captures too: targets whose every pixel is scored
#: against its known spectra, on colours the conversion was not fitted on.
NATURAL_SCENES = ("dead_leaves", "photo")


def designs() -> list[str]:
    """Every registered architecture with every exposure scheme that applies to it and needs no designed
    parameters (:data:`~spectracam.sensor.exposure.METERED_SCHEMES`)."""
    out = []
    for name in ARCHITECTURES:
        schemes = [s for s in EXPOSURE_SCHEMES.names if s in METERED_SCHEMES] \
            if ARCHITECTURES[name].independent_exposures else ("single",)
        out += [f"{name}/{s}" for s in schemes]
    return out


@dataclass(frozen=True)
class ArchitecturesRun:
    """What one ``architectures`` run compares (module docstring)."""

    experiment: PaperExperiment
    quick: bool = False
    seeds: int = SEEDS
    light_factors: tuple = LIGHT_FACTORS
    #: Below these a case is no usable image and is never named a winner (:mod:`.usability`).
    usability: UsabilitySpec = UsabilitySpec()
    #: The textured natural scenes every design also captures (:func:`natural_case`); () for none.
    natural_scenes: tuple = None

    def __post_init__(self):
        if not isinstance(self.seeds, int) or isinstance(self.seeds, bool) or not 1 <= self.seeds <= 100:
            raise ConfigError("--seeds", self.seeds, "must be a whole number of seeds from 1 to 100")
        if not isinstance(self.usability, UsabilitySpec):
            raise ConfigError("usability", self.usability, "must be a UsabilitySpec (min_white_snr_db, "
                              "max_s_cielab_mean)")
        if self.natural_scenes is None:
            object.__setattr__(self, "natural_scenes", NATURAL_SCENES)
        bad = [n for n in self.natural_scenes if n not in NATURAL_SCENES]
        if bad:
            raise ConfigError("natural_scenes", list(self.natural_scenes), "must be drawn from "
                              + ", ".join(NATURAL_SCENES))

    def scenes(self, level: float) -> dict:
        """The two lights' scenes: the paper's error-budget illuminant (D65) and its warmest blackbody.

        Parameters
        ----------
        level : float
            The white diffuser's luminance, cd/m² (the paper's calibrated level).

        Returns
        -------
        dict of str to Scene
            ``"D65"`` and ``"3000 K"`` (the labels the rows carry) → the base scene under that light, at
            :func:`~spectracam.experiments.paper.experiment.quick_scene`'s size with ``quick``.
        """
        base = quick_scene(self.experiment.base, self.quick)
        warm = min(self.experiment.temperatures_K)
        return {self.experiment.budget_illuminant: base.replace(
                    illuminant=IlluminantSpec("cie", None, self.experiment.budget_illuminant, level)),
                f"{warm:g} K": base.replace(illuminant=IlluminantSpec("blackbody", warm, None, level))}


def _stats(values) -> tuple[float | None, float | None]:
    v = [x for x in values if x is not None]
    if len(v) < len(values) or not v:
        return None, None
    return float(np.mean(v)), float(np.std(v, ddof=1)) if len(v) > 1 else 0.0


#: A chart case's fields averaged over the seeds (each with its spread, ``_sd``): row key → the score summary's field.
_CASE_STATS = (("delta_e_mean", "delta_e_mean"), ("delta_e2000_mean", "delta_e2000_mean"),
               ("delta_e_of_mean", "delta_e_of_mean"), ("snr_db", "snr_combined_db"),
               ("snr_rendered_db", "snr_rendered_db"), ("s_cielab_mean", "s_cielab_mean"),
               ("s_cielab_p95", "s_cielab_p95"), ("snr_white_rendered_db", "snr_white_rendered_db"))
#: The developed camera's (:func:`developed_case`), each row key prefixed ``developed_``.
_DEVELOPED_STATS = tuple((k, k) for k in ("delta_e_mean", "delta_e2000_mean", "delta_e_p95", "awb_recovery_deg",
                                          "snr_rendered_db", "s_cielab_mean", "snr_white_rendered_db"))


def _seed_stats(scores: list, fields: tuple, prefix: str = "") -> dict:
    """``{prefix + key: mean, prefix + key_sd: spread}`` over the seeds' scores of each ``(key, summary field)``."""
    row = {}
    for key, name in fields:
        row[f"{prefix}{key}"], row[f"{prefix}{key}_sd"] = _stats([getattr(s.summary, name) for s in scores])
    return row


def time_limit_s(scene: Scene) -> float:
    """The longest capture the dimmed cases allow: cfa/single's exposure on ``scene``'s white patch.

    Parameters
    ----------
    scene : Scene
        The scene at the paper's level.

    Returns
    -------
    float
        cfa/single's capture time, s, with its single exposure metered on the white patch.
    """
    from spectracam.scene.chart import WHITE_PATCH
    from spectracam.sensor.exposure import exposure_times_s

    cam = scene.camera.with_design("cfa/single")
    white = ChartReference.of(scene).patch_rates(cam)[WHITE_PATCH]
    return float(cam.architecture().capture_time_s(exposure_times_s("single", white, cam.sensor, cam.architecture(),
                                                                    cam.capture.white_fill)))


def case(scene: Scene, cube: RadianceCube, design: str, seeds: Sequence[int], limit_s: float | None = None,
         keep: dict | None = None) -> dict:
    """One design under one light and level, over ``seeds``: a results row.  ``limit_s``: the longest
    capture allowed (module docstring); the exposures metered on the white patch are scaled down to it.  ``keep``:
    where given, ``keep[design]`` = the first seed's ``(raw, score)`` (the page's images of the design; the row is
    the same either way).

    Parameters
    ----------
    scene : Scene
    cube : RadianceCube
        The chart's render at this light and level.
    design : str
    seeds : sequence of int
    limit_s : float or None
        The longest capture, s; None: as metered.
    keep : dict or None

    Returns
    -------
    dict
        The row: times (ms), seed means and spreads (``_sd``), the conversion's errors, :func:`developed_case`'s.
    """
    from spectracam.scene.chart import WHITE_PATCH
    from spectracam.sensor.exposure import exposure_times_s

    camera = scene.camera.with_design(design)
    reference = ChartReference.of(scene)
    white = reference.patch_radiance[WHITE_PATCH]
    metering, scale = None, 1.0
    if limit_s is not None:
        arch = camera.architecture()
        times = exposure_times_s(camera.capture.exposure, reference.patch_rates(camera)[WHITE_PATCH], camera.sensor,
                                 arch, camera.capture.white_fill, camera.capture.exposure_split)
        scale = min(1.0, limit_s / capture_time_s(arch, times, camera.sensor))
        # exposure times are inversely proportional to the metered white: metering on a brighter white
        # shortens them by ``scale`` (the dark charge aside; shorter, so it stays negligible)
        metering = {"kind": "time_limit", "limit_ms": 1e3 * limit_s,
                    "note": "metered on the white patch, then shortened so the capture lasts at most limit_ms"}
    scores, raw = [], None
    for seed in seeds:
        raw = capture(cube, camera, seed, white_radiance=white / scale, metering=metering)
        scores.append(score(raw, reference, scene.processing))
        if keep is not None and design not in keep:
            keep[design] = (raw, scores[0])
    s0 = scores[0]
    row = {"design": design, "time_limited": scale < 1.0, "architecture": camera.capture.architecture, "exposure": camera.capture.exposure,
           "channels": "".join(raw.layout.channels) if all(len(c) == 1 for c in raw.layout.channels)
           else ",".join(raw.layout.channels),
           "capture_time_ms": 1e3 * float(raw.capture_time_s),
           "exposure_ms": [1e3 * float(t) for t in raw.exposure_times_s],
           "delta_e_training": s0.summary.delta_e_conversion}
    row.update(_seed_stats(scores, _CASE_STATS))
    if s0.held_out is not None:
        row["held_out_delta_e"] = s0.held_out["delta_e_mean"]
        row["held_out_delta_e_p95"] = s0.held_out["delta_e_p95"]
        row["held_out_library"] = s0.held_out["library"]
    row["conversion_matrix"] = s0.parameters["conversion_matrix"]
    row.update(developed_case(scene, cube, design, seeds, limit_s))
    return row


def developed_case(scene: Scene, cube: RadianceCube, design: str, seeds: Sequence[int],
                   limit_s: float | None = None) -> dict:
    """The same case with the developed camera (issue 33): it meters a preview itself (shortened to ``limit_s`` when
    dimmed), estimates its white and interpolates its calibration; ``developed_*`` fields.

    Parameters
    ----------
    scene : Scene
    cube : RadianceCube
        The chart's render at this light and level.
    design : str
        ``architecture/exposure``.
    seeds : sequence of int
        The noise seeds.
    limit_s : float or None
        The longest capture, s; None: as metered.

    Returns
    -------
    dict
        ``developed_capture_time_ms``, the seed means and spreads of ``developed_delta_e_mean``, ``…_p95``,
        ``…_awb_recovery_deg`` and the rest, and ``developed_held_out_delta_e`` when the processing names a library.
    """
    from spectracam.pipeline import camera_processing
    from spectracam.processing import metered_camera

    processing = camera_processing(scene.processing, "developed")
    camera = metered_camera(scene.camera.with_design(design), processing)
    reference = ChartReference.of(scene)
    scores, raw = [], None
    for seed in seeds:
        raw = capture(cube, camera, seed, time_limit_s=limit_s)
        scores.append(score(raw, reference, processing))
    row = {"developed_capture_time_ms": 1e3 * float(raw.capture_time_s)}
    row.update(_seed_stats(scores, _DEVELOPED_STATS, "developed_"))
    if scores[0].held_out is not None:
        row["developed_held_out_delta_e"] = _stats([s.held_out["delta_e_mean"] for s in scores])[0]
    return row


class _ArchitecturesKeys(TypedDict):
    parameters: dict
    rows: list[dict]
    winners: list[dict]
    timings_s: dict[str, float]
    _shots: dict


class ArchitecturesResult(_ArchitecturesKeys, total=False):
    """What :func:`run_architectures` returns, results.json's keys but ``command``: a row per design × light ×
    level on the chart and what wins (the base's keys, always there; ``_shots``, each design's first capture at the
    paper's light for its page, the writer keeps out of results.json); ``natural`` with ``run.natural_scenes``;
    ``space``, ``time`` and ``spacetime_winners`` with ``spacetime``."""

    natural: dict
    space: dict
    time: dict
    spacetime_winners: list[dict]


def run_architectures(run: ArchitecturesRun, renderer: str = "mitsuba", use_cache: bool = True,
                      step: Callable[[str], object] = lambda msg: None, log: Callable[[str], object] | None = None,
                      progress: bool = False, spacetime: bool = True) -> ArchitecturesResult:
    """Every design × light × level × seed (module docstring): ``results`` (rows and what wins); with
    ``spacetime`` the spatial and motion comparisons too (``space``, ``time``).

    Parameters
    ----------
    run : ArchitecturesRun
        What to compare.
    renderer : str
        ``"mitsuba"`` or ``"analytic"``.
    use_cache : bool
        Read and fill the render cache.
    step : callable
        ``step(line)`` per step done.
    log : callable or None
        The renderer's and sub-runs' notices (None: none).
    progress : bool
        Progress bars on a terminal.
    spacetime : bool
        Also run :func:`~.spacetime.run_space` and :func:`~.spacetime.run_time`.

    Returns
    -------
    ArchitecturesResult
        results.json's keys but ``command``, and ``_shots``.
    """
    import time

    from spectracam.experiments.architectures.spacetime import run_space, run_time, spacetime_winners

    exp = run.experiment
    level = calibrated_luminance(exp, exp.base.camera)
    seed0 = exp.base.render.seed
    seeds = [seed0 + i for i in range(run.seeds)]
    t0 = time.perf_counter()
    shots: dict = {}
    rows = _chart_rows(run, level, seeds, renderer, use_cache, step, log, progress, shots)
    t_chart = time.perf_counter() - t0
    extra = {}
    if run.natural_scenes:
        t1 = time.perf_counter()
        extra["natural"] = run_natural(run, level, renderer, seeds, log, progress, use_cache)
        step(f"natural scenes: {', '.join(run.natural_scenes)} × {len(designs())} designs "
             f"({time.perf_counter() - t1:.1f} s)")
    if spacetime:
        base = exp.base.replace(illuminant=IlluminantSpec("blackbody", exp.calibration_temperature_K, None, level))
        sub_log = restamped(step) if log is not None else None   # one clock for the whole run
        extra["space"] = run_space(base, renderer, run.quick, sub_log, progress=progress)
        step(f"space: {len(extra['space']['rows'])} designs on the slanted edge and the Siemens star "
             f"({extra['space']['wall_s']:.1f} s)")
        extra["time"] = run_time(base, renderer, run.quick, sub_log, progress=progress)
        step(f"time: {len({r['design'] for r in extra['time']['rows']})} designs × "
             f"{len({r['speed_px_per_ms'] for r in extra['time']['rows']})} speeds ({extra['time']['wall_s']:.1f} s)")
        extra["spacetime_winners"] = spacetime_winners(extra["space"], extra["time"])
    return {"parameters": _run_parameters(run, renderer, level, seeds),
            "rows": rows, "winners": winners(rows), **extra,
            "timings_s": {"chart": t_chart, "total": time.perf_counter() - t0}, "_shots": shots}


#: The clock a sub-run (spatial, motion) stamps its own lines with, ``[  12.3 s] `` from its own start.
_OWN_CLOCK = re.compile(r"^\[\s*[\d.]+ s\] ")


def restamped(step: Callable[[str], object]) -> Callable[[str], object]:
    """A log for the space and time sub-runs whose lines carry this run's clock (``step``) instead of their own,
    which restarts at 0 in each: the command's log reads as one clock (issue 39).

    Parameters
    ----------
    step : callable
        ``step(line)``, which stamps its own clock.

    Returns
    -------
    callable
        ``log(msg)``: ``msg`` without a leading ``[  12.3 s] ``, passed to ``step``.

    Examples
    --------
    >>> lines = []
    >>> restamped(lambda m: lines.append("[ 99.0 s] " + m))("[   1.5 s] 10 µm, f/1.4, edge: 8 designs scored")
    >>> lines
    ['[ 99.0 s] 10 µm, f/1.4, edge: 8 designs scored']
    """
    return lambda msg: step(_OWN_CLOCK.sub("", msg))


def _chart_rows(run: ArchitecturesRun, level: float, seeds: list, renderer: str, use_cache: bool, step, log,
                progress: bool, shots: dict | None = None) -> list[dict]:
    """Every design under each light at each level on the chart (:func:`case`), judged: the results' rows;
    ``shots``: filled with each design's first capture under the first light at the paper's level (:func:`case`)."""
    from spectracam.io.cache import cached_render
    from spectracam.core.progress import bar
    from spectracam.render import render

    rows = []
    scenes = run.scenes(level)
    with bar(total=len(scenes) * len(run.light_factors) * len(designs()), desc="chart cases", unit="case",
             progress=progress) as cases:
        for light, scene in scenes.items():
            if use_cache:
                cube, hit = cached_render(scene, renderer, progress=progress, log=log)
            else:
                cube, hit = render(scene, renderer=renderer, progress=progress, log=log), False
            step(f"render {light}: {'cached' if hit else renderer}")
            limit = time_limit_s(scene)
            for factor in run.light_factors:
                sc, cb = scaled(scene, cube, factor)
                for design in designs():
                    first = factor == 1.0 and light == next(iter(scenes))
                    row = case(sc, cb, design, seeds, None if factor == 1.0 else limit, shots if first else None)
                    rows.append({"illuminant": light, "light_factor": factor,
                                 "white_luminance_cd_m2": level * factor, **row, **judge(row, run.usability)})
                    cases.update(1)
                step(f"{light} at {factor:g}× the paper's light: {len(designs())} designs × {len(seeds)} seeds")
    return rows


def _run_parameters(run: ArchitecturesRun, renderer: str, level: float, seeds: list) -> dict:
    """The results' ``parameters``: the run's settings and what each field of a row means."""
    exp = run.experiment
    return {"renderer": renderer, "quick": run.quick, "seeds": seeds,
            "light_factors": list(run.light_factors), "paper_white_luminance_cd_m2": level,
            "designs": designs(), "scene": exp.base.to_dict(),
            "snr_db": "chart mean of each patch's combined raw-channel SNR "
                      "(processing.snr_combination), mean over seeds; _sd: its spread (sample std)",
            "snr_rendered_db": "chart mean of each patch's 20·log10(Y/σ_Y): the raw channels' "
                               "measured means and noise through the exposure normalisation and "
                               "the colour conversion to display luminance, channels independent "
                               "(docs/metrics.md), mean over seeds",
            "delta_e_mean": "chart mean of each patch's mean per-pixel ΔE against the scene "
                            "(processing.delta_e), mean over seeds",
            "delta_e_training": "the conversion's noise-free ΔE on the 24 patches it is fitted on",
            "held_out_delta_e": "the conversion's noise-free ΔE on processing.held_out's colours",
            "s_cielab_mean": "S-CIELAB (Zhang & Wandell 1997) on the same pixels as delta_e_mean: the "
                             "rendered image and the scene's truth through the eye's filters at "
                             f"{exp.base.processing.viewing_distance_m:g} m from a display of "
                             f"{exp.base.processing.display_pixel_pitch_mm:.4g}-mm pixels "
                             f"({exp.base.processing.samples_per_degree:.1f} samples per degree), "
                             "chart mean of each patch's mean, mean over seeds (docs/metrics.md)",
            "usable": "usable image: the white patch's rendered SNR ≥ "
                      f"{run.usability.min_white_snr_db:g} dB (ISO 12232's 'acceptable' SNR 10) and "
                      f"the mean S-CIELAB ≤ {run.usability.max_s_cielab_mean:g} (a flat grey image "
                      "scores ~41); an unusable case is never named a winner (docs/metrics.md)",
            "usability": run.usability.to_dict()}


def judge(row: dict, usability: UsabilitySpec) -> dict:
    """``usable``/``unusable_reason`` of a case (the oracle camera's, mean over seeds) and ``developed_usable``/
    ``developed_unusable_reason`` (the developed camera's) by the rule of :mod:`.usability`.

    Parameters
    ----------
    row : dict
        A results row (:func:`case`).
    usability : UsabilitySpec
        The thresholds.

    Returns
    -------
    dict
        ``usable`` (bool) and ``unusable_reason`` (str, ``""`` when usable), and the ``developed_`` pair when the row
        has the developed camera's fields.
    """
    out = {}
    for prefix in ("", "developed_"):
        if f"{prefix}delta_e_mean" in row:
            ok, why = usability.judge(row.get(f"{prefix}s_cielab_mean"), row.get(f"{prefix}snr_white_rendered_db"))
            out[f"{prefix}usable"], out[f"{prefix}unusable_reason"] = ok, why
    return out


def _usable(row: dict, metric: str) -> bool:
    """Whether ``row`` may be named a winner on ``metric`` (the developed camera's flag for its metrics)."""
    return row.get("developed_usable" if metric.startswith("developed_") else "usable", True) is not False


#: What each light and level's winners are judged on: the metric and whether the least or the most wins.
WINNER_METRICS = (("delta_e_mean", min), ("s_cielab_mean", min), ("snr_rendered_db", max),
                  ("developed_delta_e_mean", min), ("developed_s_cielab_mean", min),
                  ("developed_delta_e2000_mean", min))


def winners(rows: list[dict]) -> list[dict]:
    """For each light and level: the design with the lowest per-pixel ΔE*ab, the lowest S-CIELAB, the highest
    rendered SNR (and the developed camera's ΔE*ab, S-CIELAB, CIEDE2000) among the usable cases only — "no usable
    image" where none is (``design`` ``None``, ``note``); and overall the lowest held-out conversion error and the
    shortest capture time at the paper's level.

    Parameters
    ----------
    rows : list of dict
        The judged results rows.

    Returns
    -------
    list of dict
        ``illuminant``, ``light_factor``, ``metric``, ``design`` (None with a ``note`` when no case is usable; tied
        designs comma-separated for the noise-free metrics), ``value`` and ``sd``.
    """
    out = []
    for light in dict.fromkeys(r["illuminant"] for r in rows):
        for factor in dict.fromkeys(r["light_factor"] for r in rows):
            group = [r for r in rows if r["illuminant"] == light and r["light_factor"] == factor]
            for metric, best in WINNER_METRICS:
                present = [r for r in group if r.get(metric) is not None]
                scored = [r for r in present if _usable(r, metric)]
                if scored:
                    w = best(scored, key=lambda r: r[metric])
                    out.append({"illuminant": light, "light_factor": factor, "metric": metric,
                                "design": w["design"], "value": w[metric], "sd": w.get(f"{metric}_sd")})
                elif present:
                    out.append({"illuminant": light, "light_factor": factor, "metric": metric, "design": None,
                                "value": None, "sd": None, "note": NO_USABLE_IMAGE})
        group = [r for r in rows if r["illuminant"] == light and r["light_factor"] == 1.0]
        for metric in ("held_out_delta_e", "capture_time_ms"):
            scored = [r for r in group if r.get(metric) is not None and _usable(r, metric)]
            if scored:   # noise-free numbers tie exactly where the filters are sums of the same three: name all
                best = min(r[metric] for r in scored)
                tied = [r["design"] for r in scored if r[metric] <= best * (1 + 1e-6)]
                out.append({"illuminant": light, "light_factor": 1.0, "metric": metric, "design": ", ".join(tied),
                            "value": best, "sd": None})
    return out


def natural_case(scene: Scene, cube: RadianceCube, design: str, seeds: Sequence[int]) -> dict:
    """One design capturing one textured scene (metered on its chart's white patch, as the chart cases are) over
    ``seeds``: the per-pixel ΔE*ab and S-CIELAB of :mod:`spectracam.evaluation.target_score` (held out: colours the conversion
    was not fitted on), mean and spread over seeds.

    Parameters
    ----------
    scene : Scene
        The textured scene (its target, light and viewing geometry).
    cube : RadianceCube
        Its render.
    design : str
        ``architecture/exposure``.
    seeds : sequence of int
        The noise seeds.

    Returns
    -------
    dict
        ``design``, ``delta_e_mean``, ``delta_e_p95``, ``s_cielab_mean``, ``s_cielab_p95`` (each with ``_sd``) and
        ``pixels`` (how many were scored).
    """
    from spectracam.scene.reference import TargetReference
    from spectracam.evaluation.target_score import score_target

    from spectracam.scene.chart import WHITE_PATCH

    camera = scene.camera.with_design(design)
    chart, target = ChartReference.of(scene), TargetReference.of(scene)
    white = chart.patch_radiance[WHITE_PATCH]   # the chart's white patch under the same light (as pipeline.capture)
    scores = [score_target(capture(cube, camera, seed, white_radiance=white), chart, target, scene.target,
                           scene.processing) for seed in seeds]
    row = {"design": design}
    for key in ("delta_e_mean", "delta_e_p95", "s_cielab_mean", "s_cielab_p95"):
        row[key], row[f"{key}_sd"] = _stats([s.held_out[key] for s in scores])
    row["pixels"] = scores[0].held_out["pixels"]
    return row


def run_natural(run: ArchitecturesRun, level: float, renderer: str, seeds: Sequence[int],
                log: Callable[[str], object] | None = None, progress: bool = False, use_cache: bool = True) -> dict:
    """Every design on each of ``run.natural_scenes`` (:func:`natural_case`), with the paper's camera and processing
    under the scene's own light at the paper's level.

    Parameters
    ----------
    run : ArchitecturesRun
    level : float
        The paper's white luminance, cd/m².
    renderer : str
    seeds : sequence of int
    log : callable or None
        The renderer's notices.
    progress, use_cache : bool
        Progress bars; read and fill the render cache.

    Returns
    -------
    dict
        ``rows`` (``scene`` and :func:`natural_case`'s fields per design) and ``parameters`` (per scene: viewing
        distance, m, display pixel pitch, mm, image size, px, and illuminant).
    """
    from spectracam.io.cache import cached_render
    from spectracam.render import render
    from spectracam.pipeline.scene_file import load_scene, shipped_scene_file

    exp, rows, geometry = run.experiment, [], {}
    for name in run.natural_scenes:
        own = load_scene(shipped_scene_file(f"{name}.toml"))
        scene = quick_scene(exp.base, run.quick).replace(
            target=own.target, illuminant=own.illuminant.replace(white_luminance_cd_m2=level),
            image=own.image if not run.quick else own.image.replace(width=own.image.width // 4,
                                                                     height=own.image.height // 4))
        # through the render cache, whose key holds a textured scene's [target] table (spectracam.io.cache.render_key)
        cube = (cached_render(scene, renderer, progress=progress, log=log)[0] if use_cache
                else render(scene, renderer=renderer, progress=progress, log=log))
        geometry[name] = {"viewing_distance_m": scene.target.viewing_distance_m,
                          "display_pixel_pitch_mm": scene.target.display_pixel_pitch_mm,
                          "image_px": [scene.image.width, scene.image.height], "illuminant": scene.illuminant.label}
        rows += [{"scene": name, **natural_case(scene, cube, d, seeds)} for d in designs()]
    return {"rows": rows, "parameters": geometry}


def write_architectures_outputs(out_dir: str | Path, results: dict, command: str,
                                step: Callable[[str], object] = lambda msg: None) -> list:
    """results.json, report.md and the figures (architectures.png/.svg, responsivities.png/.svg); and each
    design's first capture at the paper's light (``_shots``, not in results.json): ``cases/<architecture>-<scheme>/``
    raw.exr and rendered.exr, the images of its page (``spectracam view``).

    Parameters
    ----------
    out_dir : str or Path
    results : dict
        :func:`run_architectures`'s result.
    command : str
        The command, recorded in results.json and report.md.
    step : callable
        ``step(line)`` once the files are written.

    Returns
    -------
    list of Path
        Every file written (architectures_spacetime.png/.svg too with ``space``).
    """
    import json

    from spectracam.core.files import atomic_write
    from spectracam.io.plots import save_figure
    from spectracam.experiments.architectures.report import figure_comparison, figure_responsivities, figure_spacetime, report_markdown

    out = Path(out_dir)
    shots = results.get("_shots") or {}
    results = {**{k: v for k, v in results.items() if k != "_shots"}, "command": command}
    paths = save_figure(figure_comparison(results), out / "architectures.png", out / "architectures.svg")
    paths += save_figure(figure_responsivities(results), out / "responsivities.png", out / "responsivities.svg")
    if "space" in results:
        paths += save_figure(figure_spacetime(results), out / "architectures_spacetime.png",
                             out / "architectures_spacetime.svg")
    paths.append(atomic_write(out / "results.json", json.dumps(results, indent=1, allow_nan=False).encode()))
    paths.append(atomic_write(out / "report.md", report_markdown(results, command).encode()))
    paths += write_shots(out / "cases", shots)
    step(f"wrote {out}/results.json, report.md, architectures.png/.svg, responsivities.png/.svg"
         + (", architectures_spacetime.png/.svg" if "space" in results else "")
         + (f", cases/ with {len(shots)} designs' raw.exr and rendered.exr" if shots else ""))
    return paths


def write_shots(directory: Path, shots: dict) -> list:
    """``directory/<design with - for />/raw.exr`` and ``rendered.exr`` of each ``design → (raw, score)``.

    Parameters
    ----------
    directory : Path
        Where the designs' folders go.
    shots : dict
        ``design → (RawCapture, ChartScore)``.

    Returns
    -------
    list of Path
        The files written, two per design.
    """
    from spectracam.io.exr import write_raw_exr
    from spectracam.io.report import write_rendered_exr

    paths = []
    for design, (raw, result) in shots.items():
        d = Path(directory) / design.replace("/", "-")
        paths += [write_raw_exr(d / "raw.exr", raw), write_rendered_exr(d / "rendered.exr", result)]
    return paths
