"""The paper's experiment (section 5): exposure, Figure 4, Figures 5a/5b and Figure 6.

For each blackbody illuminant the chart is rendered once (cached), then captured and scored by every
design with the same noise seed (common random numbers: the designs differ only in the design).
Figure 6 adds the error sources one at a time on the colour filter array under D65: the noise steps
are scored against the noise-free rendering of the same camera (the conversion error removed); the
last step scores against the scene, adding the conversion error.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..capture import CameraSpec, capture
from ..color import ProcessingSpec
from ..errors import SpectracamError
from ..illuminant import IlluminantSpec
from ..render import RadianceCube
from ..scene import Scene, _Table, camera_tables, load_scene, parse_camera, parse_processing, read_toml
from ..score import score, white_patch_rates

BUDGET_STEPS = ("perfect system", "+ photon shot noise", "+ CMOS noise (read, dark, FPN)",
                "+ 8-bit quantization", "+ colour conversion")


@dataclass(frozen=True)
class Alternative:
    name: str
    reason: str
    tables: dict = field(default_factory=dict)  # optics/filters/sensor/processing overrides
    light_scale: float = 1.0


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


def _design(name: str, source: str) -> tuple[str, str]:
    arch, _, scheme = name.partition("/")
    parse_camera({"capture": {"architecture": arch, "exposure": scheme or "?"}}, source=source)
    return arch, scheme


def load_experiment(path: str | Path) -> PaperExperiment:
    """Read and validate an experiment file (see scenes/paper.toml)."""
    p = Path(path)
    t = _Table(read_toml(p, "experiment file"), "", str(p))
    base = load_scene(p.parent / t.string("base_scene", "blackbody_5000K.toml"))
    temps = t.data.pop("temperatures_K", list(PaperExperiment.temperatures_K))
    if not isinstance(temps, list) or not temps or not all(
            isinstance(x, (int, float)) and not isinstance(x, bool) and 1000 <= x <= 40000 for x in temps):
        raise t.error("temperatures_K", temps, "must be a non-empty list of colour temperatures, 1000–40000 K")
    designs = t.data.pop("designs", list(PaperExperiment.designs))
    if not isinstance(designs, list) or not designs or not all(isinstance(d, str) for d in designs):
        raise t.error("designs", designs, "must be a non-empty list like ['cfa/single', 'fsc/optimal']")
    for d in designs:
        _design(d, f"{p}: designs")
    budget_design = t.string("budget_design", PaperExperiment.budget_design)
    _design(budget_design, f"{p}: budget_design")
    budget_illuminant = t.string("budget_illuminant", PaperExperiment.budget_illuminant)
    import colour

    if budget_illuminant not in colour.SDS_ILLUMINANTS:
        raise t.error("budget_illuminant", budget_illuminant, "must be a CIE illuminant colour-science ships, e.g. D65")
    light = t.table("light")
    level = cfa_ms = None
    if light.has("white_luminance_cd_m2"):
        level = light.number("white_luminance_cd_m2", None, 0, lo_open=True, unit="cd/m²")
    else:
        cfa_ms = light.number("cfa_exposure_ms", 28.0, 0, lo_open=True, unit="ms")
    cal_T = light.number("at_temperature_K", 5000.0, 1000, 40000, unit="K")
    light.done()
    alternatives = []
    for i, alt in enumerate(t.data.pop("sensitivity", [])):
        a = _Table(alt, f"sensitivity[{i}]", str(p))
        name, reason = a.string("name", f"alternative {i}"), a.string("reason", "")
        scale = a.number("light_scale", 1.0, 0, lo_open=True)
        tables = {k: a.data.pop(k) for k in ("optics", "filters", "sensor", "processing") if a.has(k)}
        a.done()
        parse_camera({k: v for k, v in tables.items() if k != "processing"}, source=f"{p}: {name}", base=base.camera)
        parse_processing(tables.get("processing", {}), source=f"{p}: {name}", base=base.processing)
        alternatives.append(Alternative(name, reason, tables, scale))
    t.done()
    return PaperExperiment(base=base, temperatures_K=tuple(float(x) for x in temps), budget_illuminant=budget_illuminant,
                           budget_design=budget_design, designs=tuple(designs), cfa_exposure_ms=cfa_ms,
                           calibration_temperature_K=cal_T, white_luminance_cd_m2=level,
                           alternatives=tuple(alternatives))


def with_camera(camera: CameraSpec, design: str) -> CameraSpec:
    arch, scheme = design.split("/")
    return dataclasses.replace(camera, architecture=arch, exposure=scheme)


def calibrated_luminance(exp: PaperExperiment, camera: CameraSpec) -> float:
    """White-diffuser luminance at which cfa/single needs ``cfa_exposure_ms`` at the calibration
    temperature: rates scale with the level, so solve q_max = (level/L₁·w₁ + dark)·T in closed form."""
    if exp.white_luminance_cd_m2 is not None:
        return exp.white_luminance_cd_m2
    ref = exp.base.replace(illuminant=IlluminantSpec("blackbody", exp.calibration_temperature_K, None, 100.0))
    white = white_patch_rates(ref, camera)
    s = camera.sensor
    T = exp.cfa_exposure_ms * 1e-3
    need = s.q_max_e / T - s.dark_rate_e_per_s
    if need <= 0:
        raise SpectracamError(f"light.cfa_exposure_ms = {exp.cfa_exposure_ms:g}: dark current alone fills the well "
                              "sooner; choose a shorter exposure")
    return 100.0 * need / white.max()


def scaled(scene: Scene, cube: RadianceCube, factor: float) -> tuple[Scene, RadianceCube]:
    """Rendering is linear in the light level: a scaled cube is the render at a scaled level (the
    scene says so too, so that scoring fits the conversion on the light the camera saw)."""
    if factor == 1.0:
        return scene, cube
    ill = dataclasses.replace(scene.illuminant, white_luminance_cd_m2=scene.illuminant.white_luminance_cd_m2 * factor)
    scene = scene.replace(illuminant=ill)
    return scene, RadianceCube(cube.radiance * np.float32(factor), cube.wavelengths_nm, {**cube.metadata, "scene": scene.to_dict()})


def design_case(cube, scene: Scene, camera: CameraSpec, processing: ProcessingSpec, design: str, seed: int):
    cam = with_camera(camera, design)
    raw = capture(cube, seed=seed, camera=cam, scene=scene)
    result = score(raw, scene, processing)
    from ..capture import WHITE_PATCH

    s = cam.sensor
    white = (raw.patch_rates_e_per_s[WHITE_PATCH] + s.dark_rate_e_per_s) * raw.exposure_times_s / s.q_max_e
    chart = result.report["chart"]
    return {"exposure_ms": 1e3 * raw.capture_time_s, "channel_ms": (1e3 * raw.exposure_times_s).tolist(),
            "white_response": white.tolist(), "snr_db": chart["snr_combined_db"], "delta_e": chart["delta_e_mean"],
            "delta_e_of_mean": chart["delta_e_of_mean"], "delta_e_conversion": chart["delta_e_conversion"],
            "raw": raw, "score": result}


def error_budget(cube, scene: Scene, camera: CameraSpec, processing: ProcessingSpec, design: str, seed: int):
    """Figure 6: ``[(step, ΔE, raw, score)]``, each step adding one error source to the last."""
    cam = with_camera(camera, design)
    s0 = cam.sensor
    perfect = dataclasses.replace(s0, shot_noise=False, dark_current=False, read_noise=False, fpn=False,
                                  quantization=False)
    sensors = [perfect, dataclasses.replace(perfect, shot_noise=s0.shot_noise),
               dataclasses.replace(perfect, shot_noise=s0.shot_noise, dark_current=s0.dark_current,
                                   read_noise=s0.read_noise, fpn=s0.fpn),
               s0]
    out = []
    for step, sensor in zip(BUDGET_STEPS, sensors):
        raw = capture(cube, sensor, seed=seed, camera=cam, scene=scene)
        res = score(raw, scene, processing, reference="camera")
        out.append((step, res.report["chart"]["delta_e_mean"], raw, res))
    res = score(out[-1][2], scene, processing, reference="scene")
    out.append((BUDGET_STEPS[-1], res.report["chart"]["delta_e_mean"], out[-1][2], res))
    return out


def comparison(exp: PaperExperiment, cubes: dict, camera: CameraSpec, processing: ProcessingSpec,
               light_scale: float = 1.0, keep_cases: bool = False) -> tuple[dict, dict]:
    """Every design under every blackbody, and Figure 6.  ``cubes``: label → (scene, cube)."""
    seed = exp.base.render.seed
    res = {"exposure_ms": {}, "channel_exposure_ms": {}, "fig4_white_response": {}, "fig5a_snr_db": {},
           "fig5b_delta_e": {}, "fig5b_delta_e_of_mean": {}, "delta_e_conversion": {}}
    cases = {}
    for T in exp.temperatures_K:
        key = f"{T:g}"
        scene, cube = scaled(*cubes[key], light_scale)
        for design in exp.designs:
            c = design_case(cube, scene, camera, processing, design, seed)
            for field_, value in (("exposure_ms", c["exposure_ms"]), ("channel_exposure_ms", c["channel_ms"]),
                                  ("fig4_white_response", c["white_response"]), ("fig5a_snr_db", c["snr_db"]),
                                  ("fig5b_delta_e", c["delta_e"]), ("fig5b_delta_e_of_mean", c["delta_e_of_mean"]),
                                  ("delta_e_conversion", c["delta_e_conversion"])):
                res[field_].setdefault(design, {})[key] = value
            if keep_cases:
                cases[(key, design)] = c
    scene, cube = scaled(*cubes[exp.budget_illuminant], light_scale)
    budget = error_budget(cube, scene, camera, processing, exp.budget_design, seed)
    res["fig6_budget_delta_e"] = [[step, de] for step, de, _, _ in budget]
    if keep_cases:
        cases[(exp.budget_illuminant, "budget")] = budget
    return res, cases


def scenes_for(exp: PaperExperiment, level: float, quick: bool) -> dict[str, Scene]:
    base = exp.base
    if quick:  # a first look: a quarter of the pixels each way, the same physics
        base = base.replace(image=dataclasses.replace(base.image, width=160, height=120))
    out = {f"{T:g}": base.replace(illuminant=IlluminantSpec("blackbody", T, None, level)) for T in exp.temperatures_K}
    out[exp.budget_illuminant] = base.replace(illuminant=IlluminantSpec("cie", None, exp.budget_illuminant, level))
    return out


def run_paper(exp: PaperExperiment, renderer: str = "mitsuba", quick: bool = False, use_cache: bool = True,
              step=lambda msg: None, log=None, progress: bool = False) -> tuple[dict, dict, dict]:
    """Run the whole experiment; returns (results, cases, cubes).  ``step`` receives one line per step."""
    import time

    from ..render import render
    from ..render.cache import cached_render

    timings = {}
    t0 = time.perf_counter()
    level = calibrated_luminance(exp, exp.base.camera)
    cubes = {}
    for key, scene in scenes_for(exp, level, quick).items():
        t = time.perf_counter()
        if use_cache:
            cube, hit = cached_render(scene, renderer, progress=progress, log=log)
        else:
            cube, hit = render(scene, renderer=renderer, progress=progress, log=log), False
        cubes[key] = (scene, cube)
        step(f"render {key}{' K' if key[0].isdigit() else ''}: {'cached' if hit else renderer} "
             f"({time.perf_counter() - t:.1f} s)")
    timings["render_s"] = time.perf_counter() - t0
    t = time.perf_counter()
    main, cases = comparison(exp, cubes, exp.base.camera, exp.base.processing, keep_cases=True)
    timings["designs_and_budget_s"] = time.perf_counter() - t
    step(f"designs and error budget ({timings['designs_and_budget_s']:.1f} s)")
    from .claims import evaluate, survival

    claims = evaluate(main)
    t = time.perf_counter()
    alt_results, alt_claims = {}, {}
    for alt in exp.alternatives:
        tables = camera_tables(exp.base.camera)
        for k, v in alt.tables.items():
            if k != "processing":
                tables[k].update(v)
        camera = parse_camera(tables, source=alt.name)
        processing = parse_processing(alt.tables.get("processing", {}), source=alt.name, base=exp.base.processing)
        r, _ = comparison(exp, cubes, camera, processing, light_scale=alt.light_scale)
        alt_results[alt.name] = {"reason": alt.reason, **r}
        alt_claims[alt.name] = evaluate(r)
        step(f"sensitivity: {alt.name}")
    timings["sensitivity_s"] = time.perf_counter() - t
    base = exp.base.replace(illuminant=IlluminantSpec("blackbody", exp.calibration_temperature_K, None, level))
    results = {
        "parameters": {
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
        },
        **main,
        "claims": claims,
        "sensitivity": {"alternatives": alt_results, "claims": survival(claims, alt_claims)},
        "timings_s": timings,
    }
    return results, cases, cubes
