"""``spectracam design``: optimise every design, score it on held-out colours, verify it by Monte Carlo through the
capture → score pipeline, and compare it with the paper's filters, the best block pair of the grid and the Luther
camera (quantal CIE 1931 CMFs × QE: no conversion error at all — the bound of a noise-free camera; under noise
its overlapping curves make the conversion amplify the noise, and a noise-aware design can beat it).

Steps: :func:`setup` (experiment, light level, scenes), then per design :func:`design_one` (optimise,
:func:`predicted`, :func:`monte_carlo`), then :mod:`spectracam.experiments.design.report` writes the files.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, TypedDict

import numpy as np

from spectracam.architecture import ARCHITECTURES
from spectracam.core.errors import ConfigError, SpectracamError
from spectracam.core.spectra import WavelengthGrid
from spectracam.scene.illuminant import IlluminantSpec
from spectracam.experiments.design.problem import CHART, DesignProblem
from spectracam.experiments.design.spec import DesignSpec

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

    from spectracam.camera import CameraSpec
    from spectracam.processing.color import ProcessingSpec

__all__ = ["GRID_CUTOFFS_NM", "DesignResult", "Setup", "design_one", "experiment_path", "grid_best", "light_label",
           "monte_carlo", "predicted", "render_cubes", "run_design", "setup"]

#: The grid sweep's block cutoffs (spectracam/scenes/sweeps/cfa_cutoffs.toml): 450-530 × 570-650 nm in 10-nm steps.
GRID_CUTOFFS_NM = (np.arange(450.0, 531.0, 10.0), np.arange(570.0, 651.0, 10.0))


@dataclass(frozen=True, eq=False)
class Setup:
    """The experiment's camera and processing, the light level, and one chart scene per light."""

    spec: DesignSpec
    camera: object
    processing: object
    level_cd_m2: float
    scenes: tuple
    labels: tuple


def light_label(light: float | str) -> str:
    """A design file's light as the results label it: a colour temperature ``3000`` → ``"3000K"``, a CIE name as is.

    Parameters
    ----------
    light : float or str
        A blackbody temperature, K, or a CIE illuminant's name.

    Returns
    -------
    str
        The label.
    """
    return f"{light:g}K" if isinstance(light, (int, float)) else str(light)


def experiment_path(value: str, base_dir: Path) -> Path:
    """The file a design file's ``experiment`` names: a path relative to the design file, else a shipped
    experiment by name exactly as ``--experiment`` takes it (``paper``, ``paper.toml``, ``scenes/paper``).

    Parameters
    ----------
    value : str
        The design file's ``experiment``.
    base_dir : Path
        The design file's directory.

    Returns
    -------
    Path
        The existing file, or the shipped experiment.

    Raises
    ------
    ConfigError
        When it is neither.
    """
    from spectracam.experiments.options import shipped_files, shipped_named

    path = Path(value)
    if not path.is_absolute():
        path = base_dir / path
    if path.exists():
        return path
    found = shipped_named(value, "experiment file")
    if found is None:
        names = ", ".join(shipped_files("experiment file")) or "none in this installation"
        raise ConfigError("experiment", value, f"no such experiment file (relative to {base_dir}), and not the name of "
                          f"a shipped experiment (shipped: {names})")
    return found


def setup(spec: DesignSpec, base_dir: Path) -> Setup:
    """Load the experiment the spec names and build one scene per light at its calibrated level.

    Parameters
    ----------
    spec : DesignSpec
        Its ``experiment``, ``lights`` (K or CIE names) and ``image_px``.
    base_dir : Path
        Where ``experiment`` is relative to.

    Returns
    -------
    Setup
        The experiment's camera and processing, the level (cd/m², the paper's calibration), the scenes and labels.
    """
    from spectracam.experiments.paper.experiment import calibrated_luminance, load_experiment

    path = experiment_path(spec.experiment, base_dir)
    exp = load_experiment(path)
    camera, processing = exp.base.camera, exp.base.processing
    level = calibrated_luminance(exp, camera)
    w, h = spec.image_px
    base = exp.base.replace(image=exp.base.image.replace(width=w, height=h))
    scenes = []
    for light in spec.lights:
        ill = (IlluminantSpec("blackbody", float(light), None, level) if isinstance(light, (int, float))
               else IlluminantSpec("cie", None, light, level))
        scenes.append(base.replace(illuminant=ill))
    return Setup(spec, camera, processing, level, tuple(scenes), tuple(light_label(v) for v in spec.lights))


def predicted(problem: DesignProblem, x: np.ndarray | None = None, camera: CameraSpec | None = None,
              scores: Sequence[str] | None = None) -> dict:
    """The model's expected ΔE*ab and expected S-CIELAB (``*_s_cielab``; docs/metrics.md, "Expected S-CIELAB in the
    design model") on the training, held-out and chart colours, and the chart SNR, per light and averaged, for design
    ``x`` or a pipeline ``camera`` (the paper's, Luther's, a grid pair); ``scores=("delta_e",)`` leaves S-CIELAB out.

    Parameters
    ----------
    problem : DesignProblem
    x, camera : ndarray or CameraSpec, optional
    scores : sequence of str, optional

    Returns
    -------
    dict"""
    from spectracam.camera import camera_responsivities
    from spectracam.experiments.design.ad import numpy, tensor
    from spectracam.experiments.design.model import SCORES, CameraModel, evaluate

    scores = SCORES if scores is None else tuple(scores)

    if camera is not None:
        R = [tensor(r) for r in camera_responsivities(camera, problem.grid)]
        same = (camera.capture.architecture == problem.camera.capture.architecture
                and camera.capture.exposure == problem.model.exposure)
        model = problem.model if same else CameraModel.of(camera, problem.processing)   # the demosaic's factors once
        white = getattr(problem, "white", None) or [None] * len(problem.lights)
        results = [evaluate(R, light, model, None, None, w, scores) for light, w in zip(problem.lights, white)]
    else:
        results = problem.evaluate(tensor(np.asarray(x, float)), scores=scores)
    out = {"by_light": {}}
    for light, r in zip(problem.lights, results):
        out["by_light"][light.label] = {
            "training": float(numpy(r.delta_e[problem.training]).mean()),
            "held_out": float(numpy(r.delta_e[problem.held_out]).mean()),
            "held_out_p95": float(np.percentile(numpy(r.delta_e[problem.held_out]), 95)),
            "chart": float(numpy(r.delta_e[CHART]).mean()),
            "chart_snr_db": float(numpy(r.snr_db[CHART]).mean()),
            "exposure_ms": [1e3 * float(numpy(t).reshape(-1)[0]) for t in r.times_s],
            "clipped_training_colours": r.clipped[problem.training]}
        if "s_cielab" in scores:
            out["by_light"][light.label].update(
                training_s_cielab=float(numpy(r.s_cielab[problem.training]).mean()),
                held_out_s_cielab=float(numpy(r.s_cielab[problem.held_out]).mean()),
                held_out_s_cielab_p95=float(np.percentile(numpy(r.s_cielab[problem.held_out]), 95)),
                chart_s_cielab=float(numpy(r.s_cielab[CHART]).mean()))
        if problem.white:   # the estimated white's extra error, and the totals the objective saw
            for k, name in (("training", problem.training), ("held_out", problem.held_out)):
                pen = float(numpy(r.white_penalty[name]).mean())
                out["by_light"][light.label][f"{k}_white_penalty"] = pen
                out["by_light"][light.label][f"{k}_estimated_white"] = out["by_light"][light.label][k] + pen
    keys = ["training", "held_out", "held_out_p95", "chart", "chart_snr_db"]
    if "s_cielab" in scores:
        keys += ["training_s_cielab", "held_out_s_cielab", "held_out_s_cielab_p95", "chart_s_cielab"]
    if problem.white:
        keys += ["training_white_penalty", "training_estimated_white", "held_out_white_penalty",
                 "held_out_estimated_white"]
    for k in keys:
        out[k] = float(np.mean([v[k] for v in out["by_light"].values()]))
    return out


def monte_carlo(camera: CameraSpec, cubes: dict, processing: ProcessingSpec, seeds: int, base_seed: int = 0,
                keep: list | None = None) -> dict:
    """Chart ΔE*ab and SNR of ``camera`` through the real capture → score pipeline, ``seeds`` captures per light
    (seeds ``base_seed … base_seed + seeds − 1``): per light the mean and the spread over seeds, and their mean;
    the chart's measured S-CIELAB the same way (``s_cielab``, ``s_cielab_std``: the score's
    ``ChartSummary.s_cielab_mean``, where the score has it).  ``keep``: where given, the first capture (first light,
    first seed) is appended as ``(raw, score)`` — the design's page images; the numbers are the same either way.

    Parameters
    ----------
    camera : CameraSpec
        With its design (``camera.design``).
    cubes : dict
        Light label → ``(scene, cube)``.
    processing : ProcessingSpec
    seeds, base_seed : int
    keep : list or None

    Returns
    -------
    dict
        ``mean`` and ``std`` (the chart ΔE*ab over lights, per seed), ``seeds``, ``snr_db``, ``by_light``, and
        ``s_cielab``/``s_cielab_std`` where scored.
    """
    from spectracam.experiments.paper.experiment import design_case

    by_light, per_seed, sc_seed = {}, [], []
    for label, (scene, cube) in cubes.items():
        des, snrs, scs = [], [], []
        for k in range(seeds):
            c = design_case(cube, scene, camera, processing, camera.design, base_seed + k)
            if keep is not None and not keep:
                keep.append((c["raw"], c["score"]))
            des.append(c["delta_e"])
            snrs.append(c["snr_db"])
            scs.append(getattr(c["score"].summary, "s_cielab_mean", None))
        by_light[label] = {"delta_e": float(np.mean(des)), "delta_e_std": float(np.std(des, ddof=1)) if seeds > 1
                           else 0.0, "snr_db": float(np.mean(snrs)), "by_seed": [float(v) for v in des]}
        if None not in scs:
            by_light[label].update(s_cielab=float(np.mean(scs)), s_cielab_by_seed=[float(v) for v in scs])
        per_seed.append(des)
        sc_seed.append(scs)
    per_seed = np.asarray(per_seed)            # (lights, seeds)
    chart_by_seed = per_seed.mean(axis=0)      # the chart mean over lights, per seed
    out = {"mean": float(chart_by_seed.mean()),
           "std": float(chart_by_seed.std(ddof=1)) if seeds > 1 else 0.0,
           "seeds": int(seeds), "snr_db": float(np.mean([v["snr_db"] for v in by_light.values()])),
           "by_light": by_light}
    if not any(None in s for s in sc_seed):
        sc = np.asarray(sc_seed, float).mean(axis=0)
        out.update(s_cielab=float(sc.mean()), s_cielab_std=float(sc.std(ddof=1)) if seeds > 1 else 0.0)
    return out


def grid_best(problem: DesignProblem) -> dict:
    """The grid sweep's block pairs scored by the model on the training objective (expected ΔE*ab, or S-CIELAB
    with ``objective = "s_cielab"``): the best pair and its score.

    Parameters
    ----------
    problem : DesignProblem
        A ``cfa`` design; its camera gets each pair of :data:`GRID_CUTOFFS_NM`.

    Returns
    -------
    dict
        ``cutoffs_nm`` (nm), ``camera``, ``predicted`` (:func:`predicted`, both scores), ``evaluations`` and ``grid``
        (every ``(c1, c2, score)``).
    """
    key = "training_s_cielab" if getattr(problem, "score", "delta_e") == "s_cielab" else "training"
    best = None
    rows = []
    for c1 in GRID_CUTOFFS_NM[0]:
        for c2 in GRID_CUTOFFS_NM[1]:
            cam = problem.camera.replace(filters=problem.camera.filters.replace(kind="block",
                                                                                cutoffs_nm=(float(c1), float(c2))))
            p = predicted(problem, camera=cam, scores=("delta_e",) if key == "training" else None)
            rows.append((float(c1), float(c2), p[key]))
            if best is None or p[key] < best[2]:
                best = (float(c1), float(c2), p[key], cam, p)
    return {"cutoffs_nm": [best[0], best[1]], "camera": best[3], "predicted": predicted(problem, camera=best[3]),
            "evaluations": len(rows), "grid": rows}


def design_one(problem: DesignProblem, spec: DesignSpec, cubes: dict,
               log: Callable[[str], object] = lambda m: None, progress: bool = False) -> dict:
    """Optimise one design and score it every way (see the module); the cameras are returned for the report.

    Parameters
    ----------
    problem : DesignProblem
        The design, its parametrisation, the lights and the score optimised.
    spec : DesignSpec
        The optimiser's limits, the Monte Carlo seeds and which references to score (developed, Luther, grid).
    cubes : dict
        Light label → ``(scene, cube)``: the rendered charts the Monte Carlo captures (:func:`render_cubes`).
    log : callable
        ``log(line)``: the optimiser's summary and the Monte Carlo against the model.
    progress : bool
        A bar over the optimiser's iterations.

    Returns
    -------
    dict
        The optimised camera's variables, history, predicted and Monte Carlo ΔE*ab (chart and held out), the
        same for the paper's filters (and the Luther camera, the grid's best), the times, s, and under
        ``_cameras`` and ``_shot`` the cameras and a capture for the report.
    """
    from spectracam.experiments.design.optimise import optimise

    t0 = time.perf_counter()
    opt = optimise(problem, max_iterations=spec.max_iterations, tolerance=spec.tolerance, log=log, progress=progress)
    t_opt = time.perf_counter() - t0
    designed = problem.camera_of(opt.x)
    paper = problem.camera if not problem.split else problem.camera.with_design(
        problem.design.replace("/split", "/balanced"))
    entry = {"design": problem.design, "parametrisation": problem.param.name,
             "variables": problem.describe(opt.x), "evaluations": opt.evaluations, "iterations": opt.iterations,
             "optimiser": opt.message, "optimise_s": t_opt, "objective": opt.objective,
             "history": [{"objective": v, ("training_s_cielab" if problem.score == "s_cielab" else
                                           "training_delta_e"): d} for v, d in opt.history],
             "camera": designed.to_dict()}
    p_opt = predicted(problem, opt.x)
    entry["predicted_delta_e"] = p_opt
    entry["held_out_delta_e"] = p_opt["held_out"]
    t1 = time.perf_counter()
    shot: list = []
    entry["monte_carlo_delta_e"] = monte_carlo(designed, cubes, problem.processing, spec.seeds, keep=shot)
    developed = None
    if spec.developed:   # the same cameras developed by a camera that finds its own white (issue 33)
        from spectracam.pipeline import camera_processing

        developed = camera_processing(problem.processing, "developed")
        entry["monte_carlo_developed_delta_e"] = monte_carlo(designed, cubes, developed, spec.seeds)
    log(f"{problem.design}: Monte Carlo {entry['monte_carlo_delta_e']['mean']:.3f} ΔE (chart, {spec.seeds} seeds) "
        f"against the model's {p_opt['chart']:.3f}; expected S-CIELAB {p_opt['chart_s_cielab']:.3f}"
        + (f", measured {entry['monte_carlo_delta_e']['s_cielab']:.3f}" if "s_cielab" in entry["monte_carlo_delta_e"]
           else ""))
    _score_references(entry, problem, spec, cubes, paper, developed)
    entry["verify_s"] = time.perf_counter() - t1
    entry["_cameras"] = {"optimised": designed, "paper": paper}
    entry["_shot"] = shot[0] if shot else None
    return entry


def _score_references(entry: dict, problem: DesignProblem, spec: DesignSpec, cubes: dict, paper: CameraSpec,
                      developed: ProcessingSpec | None) -> None:
    """:func:`design_one`'s references, into ``entry``: the paper's filters, the Luther camera and the grid's best
    (where the spec asks for them), each predicted and by Monte Carlo."""
    paper_pred = predicted(problem, camera=paper)
    entry["paper_filters"] = {"design": paper.design, "predicted_delta_e": paper_pred,
                              "held_out_delta_e": paper_pred["held_out"],
                              "monte_carlo_delta_e": monte_carlo(paper, cubes, problem.processing, spec.seeds)}
    if developed is not None:
        entry["paper_filters"]["monte_carlo_developed_delta_e"] = monte_carlo(paper, cubes, developed, spec.seeds)
    if spec.luther and not problem.param.stacked:
        luther = paper.replace(filters=paper.filters.replace(kind="xyz"))
        lp = predicted(problem, camera=luther)
        entry["luther"] = {"predicted_delta_e": lp, "held_out_delta_e": lp["held_out"],
                           "monte_carlo_delta_e": monte_carlo(luther, cubes, problem.processing, spec.seeds)}
    if spec.grid and not problem.param.stacked and problem.camera.capture.architecture == "cfa":
        g = grid_best(problem)
        entry["grid_best"] = {"cutoffs_nm": g["cutoffs_nm"], "evaluations": g["evaluations"],
                              "predicted_delta_e": g["predicted"], "held_out_delta_e": g["predicted"]["held_out"],
                              "monte_carlo_delta_e": monte_carlo(g["camera"], cubes, problem.processing, spec.seeds),
                              "grid": g["grid"]}


def render_cubes(st: Setup, log: Callable[[str], object] = lambda m: None) -> dict:
    """One rendered chart cube per light (cached like every render).

    Parameters
    ----------
    st : Setup
        Its scenes, labels and the spec's renderer.
    log : callable
        ``log(line)`` per light rendered.

    Returns
    -------
    dict
        Light label → ``(scene, cube)``.
    """
    from spectracam.io.cache import cached_render

    cubes = {}
    for label, scene in zip(st.labels, st.scenes):
        t = time.perf_counter()
        cube, hit = cached_render(scene, st.spec.renderer)
        cubes[label] = (scene, cube)
        log(f"render {label}: {'cached' if hit else st.spec.renderer} ({time.perf_counter() - t:.1f} s)")
    return cubes


class DesignResult(TypedDict):
    """What :func:`run_design` returns: each design's entry by name (its cameras under ``_cameras``, its first Monte
    Carlo capture under ``_shot``: raw, score), the time and the bands' grid (``_grid``).  The writer drops ``_grid``,
    ``_cameras`` and ``_shot`` (the shot written as ``cases/<design>/raw.exr`` and ``rendered.exr``) and adds
    ``command`` and ``comparison`` (:func:`spectracam.experiments.design.report.table_rows`) to make results.json."""

    parameters: dict
    designs: dict[str, dict]
    time_s: float
    _grid: WavelengthGrid


def run_design(spec: DesignSpec, base_dir: Path, log: Callable[[str], object] = lambda m: None,
               st: Setup | None = None, progress: bool = False) -> DesignResult:
    """Every design of ``spec``: the results.json dict, with each design's cameras under ``_cameras`` (``st``:
    its :func:`setup`, if made already); ``progress``: bars over the designs and each one's iterations.

    Parameters
    ----------
    spec : DesignSpec
    base_dir : Path
        The design file's directory.
    log : callable
    st : Setup or None
    progress : bool

    Returns
    -------
    DesignResult"""
    from spectracam.core.progress import bar
    from spectracam.experiments.design.model import DEFAULT_DISPLAY_PIXEL_PITCH_MM, DEFAULT_VIEWING_DISTANCE_M, viewing_samples_per_degree

    t0 = time.perf_counter()
    st = st or setup(spec, base_dir)
    cubes = render_cubes(st, log)
    designs = {}
    for d in bar(spec.designs, desc="designs", unit="design", progress=progress):
        variables = ARCHITECTURES[d.partition("/")[0]].design_variables()   # the architecture says what it designs
        problem = DesignProblem(d, "depths" if variables == "depths" else spec.filters, spec, st.camera, st.processing,
                                list(st.scenes), spec.training, spec.held_out)
        designs[d] = design_one(problem, spec, cubes, log, progress=progress)
    spd = viewing_samples_per_degree(st.processing)
    return {"parameters": {"design_spec": spec.to_dict(), "white_luminance_cd_m2": st.level_cd_m2,
                           "lights": list(st.labels), "camera": st.camera.to_dict(),
                           "processing": st.processing.to_dict(),
                           "objective": ("mean expected ΔE*ab (CIE 1976)" if spec.objective == "delta_e" else
                                         f"mean expected S-CIELAB ΔE*ab (Zhang & Wandell's filters at {spd:.4g} samples "
                                         "per degree, after the demosaicker; docs/metrics.md, 'Expected S-CIELAB in "
                                         "the design model')")
                                        + " over the training library × lights, the "
                                        "conversion fitted on the chart under each light (paper 3.5)"
                                        + ("" if spec.white_balance == "oracle" else
                                           f", plus the extra noise-free ΔE*ab of balancing by the white "
                                           f"{spec.white_balance} finds in training Mondrians of the training colours "
                                           "(docs/metrics.md, 'The design with an estimated white')")
                                        + (f", minus {spec.snr_weight:g} × mean combined SNR (dB)"
                                           if spec.snr_weight else ""),
                           "monte_carlo": f"chart ΔE*ab (paper Fig. 5b) through capture → score, {spec.seeds} seeds "
                                          f"per light at {spec.image_px[0]}×{spec.image_px[1]} px, "
                                          f"{spec.renderer} renders; mean over lights, spread over seeds",
                           "s_cielab": {"samples_per_degree": spd,
                                        "viewing_distance_m": getattr(st.processing, "viewing_distance_m",
                                                                      DEFAULT_VIEWING_DISTANCE_M),
                                        "display_pixel_pitch_mm": getattr(st.processing, "display_pixel_pitch_mm",
                                                                          DEFAULT_DISPLAY_PIXEL_PITCH_MM),
                                        "expected": "*_s_cielab in predicted_delta_e: the expected S-CIELAB ΔE*ab of a "
                                                    "flat patch of each colour, the noise after the demosaicker and "
                                                    "the eye's filters (docs/metrics.md)",
                                        "monte_carlo": "s_cielab in monte_carlo_*: the chart's measured mean "
                                                       "S-CIELAB (ChartSummary.s_cielab_mean)"}},
            "designs": designs, "time_s": time.perf_counter() - t0, "_grid": st.scenes[0].grid}
