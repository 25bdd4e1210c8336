"""The paper's experiment (section 5): exposure, Figure 4, Figures 5a/5b and Figure 6.

For each blackbody illuminant the chart is rendered once (cached), then captured and scored by every
design with the same noise seed (common random numbers: the designs differ only in the design).
Figure 6 adds the error sources one at a time on the colour filter array under D65: the noise steps
are scored against the noise-free rendering of the same camera (the conversion error removed); the
last step scores against the scene, adding the conversion error.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, TypedDict

import numpy as np

from spectracam.camera import CameraSpec
from spectracam.camera.capture import capture
from spectracam.scene.chart import WHITE_PATCH
from spectracam.processing.color import ProcessingSpec
from spectracam.core.errors import ConfigError, SpectracamError
from spectracam.scene.illuminant import IlluminantSpec
from spectracam.pipeline.overrides import apply_overrides, parse_assignment
from spectracam.scene.reference import ChartReference
from spectracam.render import RadianceCube
from spectracam.pipeline.scene_file import Scene, experiment_base_scene, read_toml
from spectracam.evaluation.score import score
from spectracam.core.spec import _is_number

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable

    from spectracam.camera.capture import RawCapture
    from spectracam.evaluation.score import ChartScore

__all__ = ["BUDGET_STEPS", "EXPERIMENT_KEYS", "QUICK_IMAGE_PX", "Alternative", "BudgetStep",
           "PaperExperiment", "PaperResult", "both_ways", "calibrated_luminance", "comparison", "comparison_cases",
           "design_case", "error_budget", "load_experiment", "quick_scene", "run_paper", "scaled",
           "scenes_for"]


@dataclass(frozen=True)
class BudgetStep:
    """One step of Figure 6: the error sources on (``sensor`` noise switches) and what ΔE is
    measured against (``"camera"``: the same camera without noise; ``"scene"``: adds the conversion)."""

    id: str
    label: str
    sources: tuple
    against: str


#: Figure 6's steps, each adding one error source to the last (paper, Fig. 6).
BUDGET_STEPS = (
    BudgetStep("perfect", "perfect system", (), "camera"),
    BudgetStep("shot_noise", "+ photon shot noise", ("shot_noise",), "camera"),
    BudgetStep("cmos_noise", "+ CMOS noise (read, dark, FPN)", ("shot_noise", "dark_current", "read_noise", "fpn"),
               "camera"),
    BudgetStep("quantization", "+ 8-bit quantization",
               ("shot_noise", "dark_current", "read_noise", "fpn", "quantization"), "camera"),
    BudgetStep("conversion", "+ colour conversion", ("shot_noise", "dark_current", "read_noise", "fpn", "quantization"),
               "scene"),
)
#: Keys of an experiment file (``--set`` paths starting with one of these name the experiment;
#: any other path names a field of the base scene).
EXPERIMENT_KEYS = ("base_scene", "scene", "temperatures_K", "budget_illuminant", "budget_design", "designs", "light",
                   "sensitivity")


@dataclass(frozen=True)
class Alternative:
    """Another reading of a choice the paper leaves open: camera/processing tables over the base's."""

    name: str
    reason: str
    tables: dict = field(default_factory=dict)  # optics/filters/sensor/processing overrides
    light_scale: float = 1.0

    def camera(self, base: CameraSpec, source: str | None = None) -> CameraSpec:
        """The camera of this reading: ``base`` with the optics/filters/sensor/capture tables over it.

        Parameters
        ----------
        base : CameraSpec
            The base scene's camera.
        source : str or None
            Named in a validation error (the experiment file and this reading's name).

        Returns
        -------
        CameraSpec
            The camera; ``base`` unchanged when the reading has no camera tables.
        """
        return CameraSpec.from_dict({k: v for k, v in self.tables.items() if k != "processing"}, source, base)

    def processing(self, base: ProcessingSpec, source: str | None = None) -> ProcessingSpec:
        """The processing of this reading: ``base`` with the ``processing`` table over it.

        Parameters
        ----------
        base : ProcessingSpec
            The base scene's processing.
        source : str or None
            Named in a validation error.

        Returns
        -------
        ProcessingSpec
            The processing; ``base`` unchanged when the reading has no ``processing`` table.
        """
        return ProcessingSpec.from_dict(self.tables.get("processing", {}), source, base)


@dataclass(frozen=True)
class PaperExperiment:
    base: Scene
    temperatures_K: tuple = (3000.0, 4000.0, 5000.0, 6000.0, 7000.0)
    budget_illuminant: str = "D65"
    budget_design: str = "cfa/single"
    designs: tuple = ("cfa/single", "fsc/optimal", "fsc/balanced", "prism/optimal")
    cfa_exposure_ms: float | None = 28.0
    calibration_temperature_K: float = 5000.0
    white_luminance_cd_m2: float | None = None
    alternatives: tuple = ()


def _list(data: dict, key: str, default, ok, allowed: str, source: str) -> list:
    v = data.pop(key, default)
    if not isinstance(v, list) or not v or not all(ok(x) for x in v):
        raise ConfigError(key, v, allowed, source)
    return v


def load_experiment(path: str | Path, overrides: Iterable[str | tuple[str, object]] = ()) -> PaperExperiment:
    """Read and validate an experiment file (see scenes/paper.toml).  ``overrides`` (``--set``):
    a path whose table is an experiment key changes the experiment, any other the base scene.

    Parameters
    ----------
    path : str or Path
        The experiment file.
    overrides : iterable of str or (str, object)
        ``PATH=VALUE`` strings or ``(path, value)`` pairs, applied in order.

    Returns
    -------
    PaperExperiment
        The experiment, its base scene and sensitivity alternatives validated.

    Raises
    ------
    ConfigError
        On an invalid key or value (a textured target, a temperature outside 1000–40000 K, an unknown design…).
    """
    p = Path(path)
    src = str(p)
    pairs = [parse_assignment(o) if isinstance(o, str) else o for o in overrides]
    mine = [(k, v) for k, v in pairs if k.split(".")[0].split("[")[0] in EXPERIMENT_KEYS]
    scene_overrides = [(k, v) for k, v in pairs if (k, v) not in mine]
    t = _experiment_table(p, mine)
    base = experiment_base_scene(t, p.parent, scene_overrides, src)
    t.pop("base_scene", None)
    t.pop("scene", None)
    if base.target.textured:
        raise ConfigError("target.kind", base.target.kind, "the paper's experiment scores the ColorChecker; a "
                          "textured target is scored by simulate or score", src)
    temps = _list(t, "temperatures_K", list(PaperExperiment.temperatures_K),
                  lambda x: _is_number(x) and 1000 <= x <= 40000,
                  "must be a non-empty list of colour temperatures, 1000–40000 K", src)
    designs = _list(t, "designs", list(PaperExperiment.designs), lambda x: isinstance(x, str),
                    "must be a non-empty list like ['cfa/single', 'fsc/optimal']", src)
    for field_, d in [("designs", d) for d in designs] + [("budget_design", t.get("budget_design", "cfa/single"))]:
        try:
            base.camera.with_design(d, field_)
        except ConfigError as e:
            raise e.with_source(src) from None
    budget_design = t.pop("budget_design", PaperExperiment.budget_design)
    budget_illuminant = _budget_illuminant(t, src)
    level, cfa_ms, cal_T = _light(t, src)
    alternatives = [_sensitivity_alternative(i, alt, base, src) for i, alt in enumerate(t.pop("sensitivity", []))]
    return PaperExperiment(base=base, temperatures_K=tuple(float(x) for x in temps), budget_illuminant=budget_illuminant,
                           budget_design=budget_design, designs=tuple(designs), cfa_exposure_ms=cfa_ms,
                           calibration_temperature_K=float(cal_T), white_luminance_cd_m2=level,
                           alternatives=tuple(alternatives))


def _experiment_table(p: Path, mine: list) -> dict:
    """The experiment file's table with its ``--set`` overrides applied; an unknown key is refused."""
    src = str(p)
    t = read_toml(p, "experiment file")
    light_sets = {k.split(".", 1)[1] for k, _ in mine if k.startswith("light.")}
    if isinstance(t.get("light"), dict) and light_sets & {"white_luminance_cd_m2", "cfa_exposure_ms"}:
        # --set of one way to give the light replaces the file's other way (the command line comes last)
        t["light"] = {k: v for k, v in t["light"].items()
                      if k not in {"white_luminance_cd_m2", "cfa_exposure_ms"} - light_sets}
    t = apply_overrides(t, mine)
    for k in t:
        if k not in EXPERIMENT_KEYS:
            raise ConfigError(k, t[k], "unknown key; an experiment file has " + ", ".join(EXPERIMENT_KEYS), src)
    return t


def _budget_illuminant(t: dict, src: str) -> str:
    """The error budget's illuminant (taken from ``t``): a CIE illuminant colour-science ships."""
    from spectracam.core import colour_data

    budget_illuminant = t.pop("budget_illuminant", PaperExperiment.budget_illuminant)
    if budget_illuminant not in colour_data.illuminant_names():
        raise ConfigError("budget_illuminant", budget_illuminant,
                          "must be a CIE illuminant colour-science ships, e.g. D65", src)
    return budget_illuminant


def _light(t: dict, src: str) -> tuple:
    """``(white luminance or None, cfa/single's exposure in ms or None, calibration temperature)`` from the
    ``[light]`` table (taken from ``t``)."""
    light = t.pop("light", {})
    if not isinstance(light, dict):
        raise ConfigError("light", light, "must be a table", src)
    for k in light:
        if k not in ("white_luminance_cd_m2", "cfa_exposure_ms", "at_temperature_K"):
            raise ConfigError(f"light.{k}", light[k], "unknown key; allowed: white_luminance_cd_m2, cfa_exposure_ms, "
                              "at_temperature_K", src)
    if "white_luminance_cd_m2" in light and "cfa_exposure_ms" in light:
        raise ConfigError("light", light, "give either white_luminance_cd_m2 (a fixed level) or cfa_exposure_ms (the "
                                          "level at which cfa/single needs that time), not both", src)
    level = light.get("white_luminance_cd_m2")
    cfa_ms = None if level is not None else light.get("cfa_exposure_ms", 28.0)
    cal_T = light.get("at_temperature_K", 5000.0)
    for k, v, lo, hi in (("white_luminance_cd_m2", level, 0, None), ("cfa_exposure_ms", cfa_ms, 0, None),
                         ("at_temperature_K", cal_T, 1000, 40000)):
        if v is not None and not (_is_number(v) and v > lo and (hi is None or v <= hi)):
            raise ConfigError(f"light.{k}", v, f"must be a number > {lo}" + (f" and ≤ {hi}" if hi else ""), src)
    return level, cfa_ms, cal_T


def _sensitivity_alternative(i: int, alt, base: Scene, src: str) -> Alternative:
    """The ``i``-th ``[[sensitivity]]`` table as an :class:`Alternative`, its camera and processing validated."""
    where = f"sensitivity[{i}]"
    if not isinstance(alt, dict):
        raise ConfigError(where, alt, "must be a table", src)
    a = dict(alt)
    name, reason = a.pop("name", f"alternative {i}"), a.pop("reason", "")
    scale = a.pop("light_scale", 1.0)
    if not (_is_number(scale) and scale > 0):
        raise ConfigError(f"{where}.light_scale", scale, "must be a number > 0", src)
    tables = {k: a.pop(k) for k in ("optics", "filters", "sensor", "processing") if k in a}
    for k in a:
        raise ConfigError(f"{where}.{k}", a[k], "unknown key; allowed: name, reason, light_scale, optics, "
                          "filters, sensor, processing", src)
    alternative = Alternative(str(name), str(reason), tables, float(scale))
    alternative.camera(base.camera, f"{src}: {name}")  # validate now
    alternative.processing(base.processing, f"{src}: {name}")
    return alternative


def calibrated_luminance(exp: PaperExperiment, camera: CameraSpec) -> float:
    """White-diffuser luminance at which cfa/single needs ``cfa_exposure_ms`` at the calibration
    temperature: rates scale with the level, so solve white_fill·q_max = (level/L₁·w₁ + dark)·T in closed form.

    Parameters
    ----------
    exp : PaperExperiment
        The experiment: ``cfa_exposure_ms`` (ms) and ``calibration_temperature_K``, or a fixed
        ``white_luminance_cd_m2``.
    camera : CameraSpec
        The camera whose highest white-patch rate (e⁻/s at L₁ = 100 cd/m²) is solved for.

    Returns
    -------
    float
        The white diffuser's luminance, cd/m²; ``white_luminance_cd_m2`` itself when the experiment fixes it.

    Raises
    ------
    SpectracamError
        When dark current alone would fill the well within ``cfa_exposure_ms``.
    """
    if exp.white_luminance_cd_m2 is not None:
        return exp.white_luminance_cd_m2
    ref = exp.base.replace(illuminant=IlluminantSpec("blackbody", exp.calibration_temperature_K, None, 100.0))
    white = ChartReference.of(ref).patch_rates(camera)[WHITE_PATCH]
    s = camera.sensor
    T = exp.cfa_exposure_ms * 1e-3
    need = camera.capture.white_fill * s.q_max_e / T - s.dark_rate_e_per_s
    if need <= 0:
        raise SpectracamError(f"light.cfa_exposure_ms = {exp.cfa_exposure_ms:g}: dark current alone fills the well "
                              "sooner; choose a shorter exposure")
    return 100.0 * need / white.max()


def scaled(scene: Scene, cube: RadianceCube, factor: float) -> tuple[Scene, RadianceCube]:
    """Rendering is linear in the light level: a scaled cube is the render at a scaled level (the
    scene says so too, so that scoring fits the conversion on the light the camera saw).

    Parameters
    ----------
    scene : Scene
        The scene rendered.
    cube : RadianceCube
        Its render, radiance W·m⁻²·sr⁻¹·nm⁻¹.
    factor : float
        The light level's factor.

    Returns
    -------
    tuple of (Scene, RadianceCube)
        The scene with its white luminance times ``factor`` and the cube's radiance times ``factor`` (float32);
        the two unchanged when ``factor`` is 1.
    """
    if factor == 1.0:
        return scene, cube
    ill = scene.illuminant.replace(white_luminance_cd_m2=scene.illuminant.white_luminance_cd_m2 * factor)
    scene = scene.replace(illuminant=ill)
    return scene, RadianceCube(cube.radiance * np.float32(factor), cube.wavelengths_nm, {**cube.metadata, "scene": scene.to_dict()})


def design_case(cube: RadianceCube, scene: Scene, camera: CameraSpec, processing: ProcessingSpec, design: str,
                seed: int) -> dict:
    """One design under one light: its capture, score and the numbers the figures show.

    Parameters
    ----------
    cube : RadianceCube
        The chart's render under the light.
    scene : Scene
        The scene rendered (its chart reference and white box).
    camera, processing : CameraSpec, ProcessingSpec
        The camera, metered anew when the processing finds its own white, and the processing.
    design : str
        ``architecture/exposure`` (``"fsc/optimal"``).
    seed : int
        The noise seed.

    Returns
    -------
    dict
        ``exposure_ms`` (capture time), ``channel_ms``, ``white_response`` (the white patch, fraction of the well),
        ``snr_db``, ``delta_e``, ``delta_e_of_mean``, ``delta_e_conversion``, ``s_cielab``, ``s_cielab_p95``,
        ``held_out``, ``training``, and the ``raw`` capture and its ``score``.
    """
    cam = camera.with_design(design)
    if not processing.told_the_light:   # a camera that finds its own white meters itself too (issue 33)
        from spectracam.processing import metered_camera

        cam = metered_camera(cam, processing)
    reference = ChartReference.of(scene)
    raw = capture(cube, cam, seed, reference.white_box)
    result = score(raw, reference, processing)
    s = cam.sensor
    white = (raw.metered_rate_e_per_s + s.dark_rate_e_per_s) * raw.exposure_times_s / s.q_max_e
    c = result.summary
    return {"exposure_ms": c.capture_time_ms, "channel_ms": (1e3 * raw.exposure_times_s).tolist(),
            "white_response": white.tolist(), "snr_db": c.snr_combined_db, "delta_e": c.delta_e_mean,
            "delta_e_of_mean": c.delta_e_of_mean, "delta_e_conversion": c.delta_e_conversion,
            "s_cielab": c.s_cielab_mean, "s_cielab_p95": c.s_cielab_p95,
            "held_out": result.held_out, "training": result.training, "raw": raw, "score": result}


def error_budget(cube: RadianceCube, scene: Scene, camera: CameraSpec, processing: ProcessingSpec, design: str,
                 seed: int) -> list[tuple[BudgetStep, float, RawCapture, ChartScore]]:
    """Figure 6: ``[(step, ΔE, raw, score)]`` for each of :data:`BUDGET_STEPS`.

    Parameters
    ----------
    cube : RadianceCube
        The chart's render under the budget's illuminant.
    scene : Scene
        The scene rendered.
    camera, processing : CameraSpec, ProcessingSpec
        The camera, whose sensor has each step's sources on and the rest off, and the processing.
    design : str
        The design (``"cfa/single"``).
    seed : int
        The noise seed, the same for every step.

    Returns
    -------
    list of tuple
        Per step: the step, its mean ΔE*ab (against the noise-free camera or the scene, ``step.against``), the
        capture and its score.
    """
    cam = camera.with_design(design)
    reference = ChartReference.of(scene)
    s0 = cam.sensor
    out, raws = [], {}
    for step in BUDGET_STEPS:
        # a source the camera has switched off stays off; everything not yet added is off
        sensor = s0.off(*(n for n in ("shot_noise", "dark_current", "read_noise", "fpn", "quantization")
                          if n not in step.sources))
        if sensor not in raws:
            raws[sensor] = capture(cube, cam.replace(sensor=sensor), seed, reference.white_box)
        raw = raws[sensor]
        res = score(raw, reference, processing, delta_e_reference=step.against)
        out.append((step, res.summary.delta_e_mean, raw, res))
    return out


def comparison(exp: PaperExperiment, cubes: dict, camera: CameraSpec, processing: ProcessingSpec,
               light_scale: float = 1.0, keep_cases: bool = False,
               tick: Callable[[], object] = lambda: None) -> tuple[dict, dict]:
    """Every design under every blackbody, and Figure 6.  ``cubes``: label → (scene, cube); ``tick`` is
    called after each case (a progress bar's step: :func:`comparison_cases` of them).

    Parameters
    ----------
    exp : PaperExperiment
    cubes : dict
        ``"3000"``…, and the budget's illuminant → ``(scene, cube)``.
    camera, processing : CameraSpec, ProcessingSpec
    light_scale : float
        The light level's factor (:func:`scaled`).
    keep_cases : bool
        Also return each case (:func:`design_case`'s dict; the budget's list under ``(illuminant, "budget")``).
    tick : callable

    Returns
    -------
    tuple of (dict, dict)
        The results' per-design fields (design → temperature → value) and ``fig6_budget_delta_e``; the cases.
    """
    seed = exp.base.render.seed
    res = {"exposure_ms": {}, "channel_exposure_ms": {}, "fig4_white_response": {}, "fig5a_snr_db": {},
           "fig5b_delta_e": {}, "fig5b_delta_e_of_mean": {}, "delta_e_conversion": {}, "delta_e_conversion_p95": {},
           "held_out_delta_e": {}, "held_out_delta_e_p95": {}, "fig5b_s_cielab": {}, "fig5b_s_cielab_p95": {}}
    cases = {}
    for T in exp.temperatures_K:
        key = f"{T:g}"
        scene, cube = scaled(*cubes[key], light_scale)
        for design in exp.designs:
            c = design_case(cube, scene, camera, processing, design, seed)
            for field_, value in (("exposure_ms", c["exposure_ms"]), ("channel_exposure_ms", c["channel_ms"]),
                                  ("fig4_white_response", c["white_response"]), ("fig5a_snr_db", c["snr_db"]),
                                  ("fig5b_delta_e", c["delta_e"]), ("fig5b_delta_e_of_mean", c["delta_e_of_mean"]),
                                  ("delta_e_conversion", c["delta_e_conversion"]),
                                  ("fig5b_s_cielab", c["s_cielab"]), ("fig5b_s_cielab_p95", c["s_cielab_p95"])):
                res[field_].setdefault(design, {})[key] = value
            if c["held_out"] is not None:   # the conversion on colours it was not fitted on (spectracam.evaluation.heldout)
                for field_, value in (("delta_e_conversion_p95", c["training"]["delta_e_p95"]),
                                      ("held_out_delta_e", c["held_out"]["delta_e_mean"]),
                                      ("held_out_delta_e_p95", c["held_out"]["delta_e_p95"])):
                    res[field_].setdefault(design, {})[key] = value
                res["held_out_library"] = {k: c["held_out"][k] for k in ("library", "samples")}
            if keep_cases:
                cases[(key, design)] = c
            tick()
    scene, cube = scaled(*cubes[exp.budget_illuminant], light_scale)
    budget = error_budget(cube, scene, camera, processing, exp.budget_design, seed)
    res["fig6_budget_delta_e"] = [{"step": step.id, "label": step.label, "delta_e": de,
                                   "s_cielab": r.summary.s_cielab_mean} for step, de, _, r in budget]
    if keep_cases:
        cases[(exp.budget_illuminant, "budget")] = budget
    tick()
    return res, cases


def both_ways(exp: PaperExperiment, cubes: dict, camera: CameraSpec, processing: ProcessingSpec, cases: dict,
              tick: Callable[[], object] = lambda: None) -> dict:
    """Every design under every blackbody scored by the oracle camera (the cases of :func:`comparison`) and by the
    developed one (``processing.camera = "developed"``: its own metering, white and calibration; captured anew with
    the same seed): ``{"oracle": {field: {design: {T: v}}}, "developed": {...}, "white_balance": {design: {T: block}}}``.

    Parameters
    ----------
    exp : PaperExperiment
    cubes : dict
        Temperature label → ``(scene, cube)``.
    camera, processing : CameraSpec, ProcessingSpec
        The base camera and processing; the developed processing is made from it.
    cases : dict
        :func:`comparison`'s cases (``keep_cases=True``), the oracle's scores.
    tick : callable
        Called after each case.

    Returns
    -------
    dict
        As above, with ``developed_processing`` (the developed camera's ``camera``, ``white_balance`` and
        ``calibration`` settings).
    """
    from spectracam.pipeline import BOTH_WAYS_FIELDS, camera_processing, score_row
    from spectracam.processing import metered_camera

    seed = exp.base.render.seed
    developed = camera_processing(processing, "developed")
    out = {"oracle": {f: {} for f in BOTH_WAYS_FIELDS}, "developed": {f: {} for f in BOTH_WAYS_FIELDS},
           "white_balance": {}, "developed_processing": {k: developed.to_dict()[k] for k in
                                                         ("camera", "white_balance", "calibration")}}
    for T in exp.temperatures_K:
        key = f"{T:g}"
        scene, cube = cubes[key]
        reference = ChartReference.of(scene)
        for design in exp.designs:
            cam = metered_camera(camera.with_design(design), developed)
            raw = capture(cube, cam, seed, reference.white_box)
            result = score(raw, reference, developed)
            for name, r in (("oracle", cases[(key, design)]["score"]), ("developed", result)):
                for f, v in score_row(r).items():
                    out[name][f].setdefault(design, {})[key] = v
            out["white_balance"].setdefault(design, {})[key] = result.white_balance
            tick()
    return out


def comparison_cases(exp: PaperExperiment) -> int:
    """How many cases :func:`comparison` runs: every design under every blackbody, and the budget.

    Parameters
    ----------
    exp : PaperExperiment

    Returns
    -------
    int
        ``len(temperatures_K) × len(designs) + 1``.
    """
    return len(exp.temperatures_K) * len(exp.designs) + 1


#: ``--quick``: a first look at a quarter of the pixels each way, the same physics.
QUICK_IMAGE_PX = (160, 120)


def quick_scene(scene: Scene, quick: bool = True) -> Scene:
    """``scene`` at :data:`QUICK_IMAGE_PX` when ``quick``.

    Parameters
    ----------
    scene : Scene
    quick : bool
        ``--quick``.

    Returns
    -------
    Scene
        ``scene`` at 160 × 120 px, or ``scene`` itself.
    """
    w, h = QUICK_IMAGE_PX
    return scene.replace(image=scene.image.replace(width=w, height=h)) if quick else scene


def scenes_for(exp: PaperExperiment, level: float, quick: bool) -> dict[str, Scene]:
    """The scenes the experiment renders: the base scene under each blackbody and under the budget's illuminant.

    Parameters
    ----------
    exp : PaperExperiment
    level : float
        The white diffuser's luminance, cd/m² (:func:`calibrated_luminance`).
    quick : bool
        ``--quick`` (:func:`quick_scene`).

    Returns
    -------
    dict of str to Scene
        ``"3000"``, … (K) and the budget's illuminant (``"D65"``) → scene.
    """
    base = quick_scene(exp.base, quick)
    out = {f"{T:g}": base.replace(illuminant=IlluminantSpec("blackbody", T, None, level)) for T in exp.temperatures_K}
    out[exp.budget_illuminant] = base.replace(illuminant=IlluminantSpec("cie", None, exp.budget_illuminant, level))
    return out


_SHARED: dict = {}  # what forked workers inherit instead of receiving it pickled (the cubes are large)


def _alternative(i: int):
    exp, cubes = _SHARED["exp"], _SHARED["cubes"]
    alt = exp.alternatives[i]
    camera, processing = alt.camera(exp.base.camera, alt.name), alt.processing(exp.base.processing, alt.name)
    return comparison(exp, cubes, camera, processing, light_scale=alt.light_scale)[0]


def _one_thread():
    import os

    from spectracam.core.processes import die_with_parent

    die_with_parent()  # no orphan if the command is killed
    os.environ["SPECTRACAM_THREADS"] = "1"  # one process per core already


def _alternatives(exp: PaperExperiment, cubes: dict, tick=lambda: None) -> list[dict]:
    """Every sensitivity alternative's comparison, in processes forked from this one (they share
    the cubes; the same seeds, so the same numbers as one after the other), one per core; ``tick``
    is called as each one's result arrives (in order)."""
    import multiprocessing
    import os

    _SHARED.update(exp=exp, cubes=cubes)
    try:
        jobs = range(len(exp.alternatives))
        workers = min(len(jobs), int(os.environ.get("SPECTRACAM_THREADS") or os.cpu_count() or 1))
        out = []
        if workers < 2 or "fork" not in multiprocessing.get_all_start_methods():
            for j in jobs:
                out.append(_alternative(j))
                tick()
            return out
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("fork"),
                                 initializer=_one_thread) as ex:
            for r in ex.map(_alternative, jobs):
                out.append(r)
                tick()
        return out
    finally:
        _SHARED.clear()


class _PaperKeys(TypedDict):
    parameters: dict
    exposure_ms: dict[str, dict[str, float]]
    channel_exposure_ms: dict[str, dict[str, list[float]]]
    fig4_white_response: dict[str, dict[str, list[float]]]
    fig5a_snr_db: dict[str, dict[str, float | None]]
    fig5b_delta_e: dict[str, dict[str, float]]
    fig5b_delta_e_of_mean: dict[str, dict[str, float]]
    delta_e_conversion: dict[str, dict[str, float]]
    delta_e_conversion_p95: dict[str, dict[str, float]]
    held_out_delta_e: dict[str, dict[str, float]]
    held_out_delta_e_p95: dict[str, dict[str, float]]
    fig5b_s_cielab: dict[str, dict[str, float | None]]
    fig5b_s_cielab_p95: dict[str, dict[str, float | None]]
    fig6_budget_delta_e: list[dict]
    claims: list[dict]
    both_ways: dict
    sensitivity: dict
    timings_s: dict[str, float]


class PaperResult(_PaperKeys, total=False):
    """What :func:`run_paper` returns first, results.json's keys but ``command``.  The per-design fields map
    design → blackbody (``"3000"``, …) → value; the held-out fields are filled, and ``held_out_library`` is
    there, when the processing names a held-out library.  (The keys that may be missing are declared here, the
    others in the base: ``NotRequired`` in a string annotation is not seen at run time on Python 3.11.)"""

    held_out_library: dict


def run_paper(exp: PaperExperiment, renderer: str = "mitsuba", quick: bool = False, use_cache: bool = True,
              step: Callable[[str], object] = lambda msg: None, log: Callable[[str], object] | None = None,
              progress: bool = False) -> tuple[PaperResult, dict, dict]:
    """Run the whole experiment (paper section 5); returns (results, cases, cubes).  ``step`` receives one line per
    step; ``progress``: bars over the lights rendered, the cases and the sensitivity alternatives on a terminal.

    Parameters
    ----------
    exp : PaperExperiment
    renderer : str
    quick, use_cache : bool
        ``--quick``; read and fill the render cache.
    step, log : callable
        ``step(line)`` per step; ``log``: the renderer's notices (None: none).
    progress : bool

    Returns
    -------
    tuple of (PaperResult, dict, dict)
        The results (results.json's keys but ``command``), :func:`comparison`'s cases, label → ``(scene, cube)``.
    """
    import time

    from spectracam.core.progress import bar

    timings = {}
    t0 = time.perf_counter()
    level = calibrated_luminance(exp, exp.base.camera)
    cubes = _render_lights(exp, level, quick, renderer, use_cache, step, log, progress)
    timings["render_s"] = time.perf_counter() - t0
    t = time.perf_counter()
    with bar(total=comparison_cases(exp), desc="paper cases", unit="case", progress=progress) as b:
        main, cases = comparison(exp, cubes, exp.base.camera, exp.base.processing, keep_cases=True,
                                 tick=lambda: b.update(1))
    timings["designs_and_budget_s"] = time.perf_counter() - t
    step(f"designs and error budget ({timings['designs_and_budget_s']:.1f} s)")
    t = time.perf_counter()
    with bar(total=len(exp.temperatures_K) * len(exp.designs), desc="developed camera", unit="case",
             progress=progress) as b:
        developed = both_ways(exp, cubes, exp.base.camera, exp.base.processing, cases, tick=lambda: b.update(1))
    timings["developed_s"] = time.perf_counter() - t
    step(f"the developed camera ({timings['developed_s']:.1f} s)")
    from spectracam.experiments.paper.claims import evaluate, survival

    claims = evaluate(main)
    t = time.perf_counter()
    alt_results, alt_claims = _sensitivity(exp, cubes, step, progress)
    timings["sensitivity_s"] = time.perf_counter() - t
    base = exp.base.replace(illuminant=IlluminantSpec("blackbody", exp.calibration_temperature_K, None, level))
    results = {
        "parameters": _parameters(exp, renderer, quick, level, base),
        **main,
        "claims": claims,
        "both_ways": developed,
        "sensitivity": {"alternatives": alt_results, "claims": survival(claims, alt_claims)},
        "timings_s": timings,
    }
    return results, cases, cubes


def _render_lights(exp: PaperExperiment, level: float, quick: bool, renderer: str, use_cache: bool, step, log,
                   progress: bool) -> dict:
    """Render the chart under every light of the experiment (through the render cache when ``use_cache``):
    ``{label: (scene, cube)}``."""
    import time

    from spectracam.io.cache import cached_render
    from spectracam.core.progress import bar
    from spectracam.render import render

    cubes = {}
    scenes = scenes_for(exp, level, quick)
    for key, scene in bar(scenes.items(), total=len(scenes), desc="render lights", unit="light", progress=progress):
        t = time.perf_counter()
        if use_cache:
            cube, hit = cached_render(scene, renderer, progress=progress, log=log)
        else:
            cube, hit = render(scene, renderer=renderer, progress=progress, log=log), False
        cubes[key] = (scene, cube)
        step(f"render {key}{' K' if key[0].isdigit() else ''}: {'cached' if hit else renderer} "
             f"({time.perf_counter() - t:.1f} s)")
    return cubes


def _sensitivity(exp: PaperExperiment, cubes: dict, step, progress: bool) -> tuple[dict, dict]:
    """Every sensitivity alternative's results and claims, by name."""
    import time

    from spectracam.core.progress import bar
    from spectracam.experiments.paper.claims import evaluate

    alt_results, alt_claims = {}, {}
    t0 = time.perf_counter()
    with bar(total=len(exp.alternatives), desc="sensitivity", unit="reading", progress=progress) as b:
        alternatives = _alternatives(exp, cubes, tick=lambda: b.update(1))
    for alt, r in zip(exp.alternatives, alternatives):
        alt_results[alt.name] = {"reason": alt.reason, **r}
        alt_claims[alt.name] = evaluate(r)
    # one line for the readings, which finish together (run in parallel), not one line each at the same instant
    step(f"sensitivity: {len(exp.alternatives)} readings ({time.perf_counter() - t0:.1f} s): "
         + "; ".join(alt.name for alt in exp.alternatives))
    return alt_results, alt_claims


def _parameters(exp: PaperExperiment, renderer: str, quick: bool, level: float, base: Scene) -> dict:
    """The results' ``parameters``: the experiment's settings, its light and how each figure is measured."""
    return {
        "renderer": renderer, "quick": quick, "seed": exp.base.render.seed,
        "designs": list(exp.designs), "temperatures_K": [f"{T:g}" for T in exp.temperatures_K],
        "budget_illuminant": exp.budget_illuminant, "budget_design": exp.budget_design,
        "white_luminance_cd_m2": level, "illuminance_lux": base.illuminant.illuminance_lux,
        "light_calibration": (f"cfa/single needs {exp.cfa_exposure_ms:g} ms at {exp.calibration_temperature_K:g} K"
                              if exp.white_luminance_cd_m2 is None else "fixed in the experiment file"),
        "scene": base.to_dict(),
        "fig6_method": "noise steps: per-pixel ΔE*ab against the noise-free rendering of the same camera (the "
                       "conversion error removed), sources added in the order shown, so the perfect system's "
                       "residual is the Monte Carlo noise of the render; last step: against the scene, adding "
                       "the colour conversion error",
        "snr": "chart average of each patch's combined SNR (see processing.snr_combination)",
        "delta_e": "chart average of each patch's mean per-pixel ΔE (processing.delta_e)",
        "s_cielab": "S-CIELAB (Zhang & Wandell 1997): the rendered image and the scene's truth image through the "
                    "eye's filters, then the per-pixel ΔE (processing.delta_e) on the same patch pixels; chart "
                    "average of each patch's mean (fig5b_s_cielab; fig5b_s_cielab_p95: the 95th percentile over "
                    "every patch's pixels); always against the scene (the budget steps too); docs/metrics.md",
        "s_cielab_viewing": {"viewing_distance_m": exp.base.processing.viewing_distance_m,
                             "display_pixel_pitch_mm": exp.base.processing.display_pixel_pitch_mm,
                             "samples_per_degree": exp.base.processing.samples_per_degree},
    }
