"""Issue 33: a camera that finds its own white — metering, white-balance estimators, the DNG's dual-illuminant
calibration, and every score reported for the oracle and the developed camera."""
from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import assert_gradient_is_central_differences

import spectracam as sc
from spectracam import pipeline
from spectracam.processing.color import ProcessingSpec
from spectracam.core.errors import ConfigError, SpectracamError
from spectracam.processing import CAMERAS, metered_camera
from spectracam.processing.calibration import D50_XYZ, dual_illuminant_matrices, xy_to_cct
from spectracam.processing.white_balance import (WHITE_BALANCE_METHODS, Estimation, estimate_neutral,
                                                 minkowski_mean, recovery_error_deg, reproduction_error_deg)
from spectracam.scene.reference import ChartReference
from spectracam.render import RadianceCube
from spectracam.pipeline.scene_file import shipped_dir

NEUTRAL = np.array([0.31, 0.55, 0.77])


def _estimate(method: str, image: np.ndarray, valid=None, **proc) -> np.ndarray:
    p = ProcessingSpec(camera="developed", white_balance=method, **proc)
    valid = np.ones(image.shape[:2], bool) if valid is None else valid
    return estimate_neutral(Estimation(image, valid, p))


def _unit(v):
    return np.asarray(v, float) / np.linalg.norm(v)


def test_grey_world_on_an_exactly_grey_world_returns_the_neutral():
    rng = np.random.default_rng(1)
    values = rng.uniform(0.05, 1.0, 64 * 48)
    # every channel holds the same values in another order: each channel's mean is the same grey
    image = np.stack([NEUTRAL[k] * rng.permutation(values) for k in range(3)], axis=-1).reshape(64, 48, 3) * 1e4
    assert np.max(np.abs(_estimate("grey_world", image) - _unit(NEUTRAL))) < 1e-9
    # a world that is not grey on average is not returned as the neutral
    tinted = image * np.array([1.2, 1.0, 1.0])
    assert recovery_error_deg(_estimate("grey_world", tinted), NEUTRAL) > 1.0


def test_white_patch_ignores_a_hot_pixel():
    rng = np.random.default_rng(2)
    image = rng.uniform(0.0, 0.6, (100, 100, 3)) * NEUTRAL * 1e4          # coloured surfaces below the white
    image[:5, :40] = NEUTRAL * 1e4                                        # a white patch: 2 % of the pixels
    image[70, 70] = np.array([50.0, 0.1, 0.1]) * 1e4                      # a hot red pixel, far brighter
    assert np.max(np.abs(_estimate("white_patch", image) - _unit(NEUTRAL))) < 1e-12
    # the plain maximum (max-RGB) would be fooled by it
    assert recovery_error_deg(image.reshape(-1, 3).max(axis=0), NEUTRAL) > 30


def test_grey_edge_on_a_known_gradient_returns_the_neutral():
    y, x = np.mgrid[0:60, 0:80].astype(float)
    ramp = 3.0 * x + 0.5 * y + 7.0 * np.sin(x / 9.0)
    offsets = np.array([900.0, 50.0, 4000.0])      # flat colour: invisible to an edge-based estimator
    image = ramp[..., None] * NEUTRAL + offsets
    assert np.max(np.abs(_estimate("grey_edge", image) - _unit(NEUTRAL))) < 1e-9
    # grey world is misled by the flat colour
    assert recovery_error_deg(_estimate("grey_world", image), NEUTRAL) > 5


def test_shades_of_grey_spans_grey_world_to_max():
    rng = np.random.default_rng(3)
    px = rng.uniform(0, 1, (5000, 3))
    assert np.allclose(minkowski_mean(px, 1.0), px.mean(axis=0), rtol=1e-12)
    assert np.allclose(minkowski_mean(px, 2.0), np.sqrt((px ** 2).mean(axis=0)), rtol=1e-12)
    assert np.all(np.abs(minkowski_mean(px, 64.0) - px.max(axis=0)) < 0.1)
    image = px.reshape(50, 100, 3)
    assert np.allclose(_estimate("shades_of_grey", image, white_balance_p=1.0), _estimate("grey_world", image))


def test_angular_errors_by_hand():
    assert recovery_error_deg(np.array([1.0, 0.0, 0.0]), np.array([1.0, 1.0, 0.0])) == pytest.approx(45.0)
    assert recovery_error_deg(np.array([2.0, 4.0, 6.0]), np.array([1.0, 2.0, 3.0])) == pytest.approx(0.0, abs=1e-6)
    # reproduction: the true white divided by the estimate, (1, 1, 0.5), against the achromatic (1, 1, 1)
    want = np.degrees(np.arccos(2.5 / (1.5 * np.sqrt(3))))
    assert reproduction_error_deg(np.array([1.0, 1.0, 2.0]), np.ones(3)) == pytest.approx(want, rel=1e-12)
    # the two differ in general, and both vanish for the right neutral at any scale
    assert reproduction_error_deg(3 * NEUTRAL, NEUTRAL) == pytest.approx(0.0, abs=1e-6)


def _scene(name="d65", **proc):
    scene = sc.load_scene(str(shipped_dir() / f"{name}.toml"))
    scene = scene.replace(image=scene.image.replace(width=160, height=120))
    return scene.replace(processing=scene.processing.replace(**proc)) if proc else scene


def test_dual_illuminant_equals_each_calibration_at_its_light_and_is_monotone():
    scene = _scene()
    ref = ChartReference.of(scene)
    dual = dual_illuminant_matrices(ref, scene.camera, "xyz_scaling")
    t_a, t_d65 = dual.cct_K
    assert t_a == pytest.approx(2856, abs=3) and t_d65 == pytest.approx(6504, abs=3)
    assert np.array_equal(dual.forward_matrix(t_a), dual.forward_matrices[0])
    assert np.array_equal(dual.forward_matrix(t_d65), dual.forward_matrices[1])
    assert np.array_equal(dual.forward_matrix(2000.0), dual.forward_matrices[0])   # clamped outside
    assert np.array_equal(dual.forward_matrix(9000.0), dual.forward_matrices[1])
    temps = np.linspace(t_a, t_d65, 40)
    w = np.array([dual.weight(t) for t in temps])
    assert np.all(np.diff(w) < 0) and w[0] == 1.0 and w[-1] == 0.0
    # linear in 1/CCT: halfway in mired is weight 1/2
    assert dual.weight(2.0 / (1 / t_a + 1 / t_d65)) == pytest.approx(0.5, abs=1e-12)
    # every element of the interpolated matrix moves monotonically from FM_A to FM_D65: each step in the direction
    # of the whole change (a weight that went back and forth, or an element interpolated the wrong way, fails)
    fm = np.stack([dual.forward_matrix(t) for t in temps])
    d = np.diff(fm, axis=0)
    total = dual.forward_matrices[1] - dual.forward_matrices[0]
    assert np.all(d * total[None] >= -1e-15) and np.allclose(d.sum(axis=0), total, atol=1e-12)
    # a ForwardMatrix maps the balanced neutral to D50 exactly (DNG 1.6 chapter 6)
    for FM in dual.forward_matrices:
        assert np.max(np.abs(np.ones(3) @ FM - D50_XYZ)) < 1e-12


def test_a_luther_camera_finds_the_light_it_was_calibrated_under():
    scene = _scene()
    cam = scene.camera.replace(filters=scene.camera.filters.replace(kind="xyz", qe="flat"))
    ref = ChartReference.of(scene)
    dual = dual_illuminant_matrices(ref, cam, "xyz_scaling")
    for neutral, t in zip(dual.neutrals, dual.cct_K):
        xy, cct, _ = dual.neutral_to_xy(neutral)
        assert cct == pytest.approx(t, abs=15)
    assert xy_to_cct([0.3127, 0.3290]) == pytest.approx(6504, abs=2)


def test_oracle_is_the_papers_chain_and_developed_differs():
    scene = _scene()
    cube = pipeline.render(scene, "analytic")
    raw = pipeline.capture(cube, scene=scene)
    assert raw.metering is None      # the oracle meters the white patch as before
    oracle = pipeline.score(raw, scene)
    from spectracam.evaluation.score import conversion_matrix

    M = conversion_matrix(ChartReference.of(scene), raw.camera, scene.processing)
    assert np.array_equal(np.asarray(oracle.parameters["conversion_matrix"]), M)
    assert oracle.white_balance["recovery_deg"] == 0.0 and oracle.summary.awb_recovery_deg == 0.0
    # ΔE2000 and the 95th percentile beside ΔE*ab
    assert 0 < oracle.summary.delta_e2000_mean < oracle.summary.delta_e_mean < oracle.summary.delta_e_p95
    dev_scene = _scene(camera="developed")
    dev_raw = pipeline.capture(cube, scene=dev_scene)
    assert dev_raw.metering["method"] == "percentile"
    dev = pipeline.score(dev_raw, dev_scene)
    assert dev.white_balance["method"] == "corrected_moments"
    assert dev.white_balance["calibration"] == "dual_illuminant"
    assert 0 < dev.summary.awb_recovery_deg < 20
    assert dev.summary.delta_e_mean > oracle.summary.delta_e_mean
    # the trained estimator never trained on the chart: every training reflectance that matches a patch is removed
    assert dev.white_balance["training"]["samples"] + dev.white_balance["training"]["excluded_as_scored_colours"] == 190


def test_oracle_white_with_scene_light_calibration_is_the_oracle_chain():
    p = ProcessingSpec(camera="developed", white_balance="oracle", calibration="scene_light")
    assert p.told_the_light
    assert not ProcessingSpec(camera="developed").told_the_light
    for cam, steps in CAMERAS.items():
        q = ProcessingSpec(camera=cam)
        assert (q.white_balance_method, q.calibration_method) == (steps["white_balance"], steps["calibration"])


def test_scene_light_calibration_with_the_true_white_reproduces_the_oracle_colours():
    """Estimated white = true white through the scene-light matrix: the same colours up to the brightness, which a
    camera that is not told the light takes from its metered white (the white patch, shown at Y = 1)."""
    scene = _scene(camera="developed", white_balance="oracle", calibration="scene_light")
    scene = scene.replace(processing=scene.processing.replace(white_balance="oracle"))
    cube = pipeline.render(scene, "analytic")
    oracle_scene = _scene()
    raw = pipeline.capture(cube, scene=oracle_scene)
    M0 = np.asarray(pipeline.score(raw, oracle_scene).parameters["conversion_matrix"])
    # white balance by the truth, calibration under the scene light, metering on the white patch: the oracle
    assert np.array_equal(np.asarray(pipeline.score(raw, scene).parameters["conversion_matrix"]), M0)
    est = scene.replace(processing=scene.processing.replace(white_balance="white_patch"))
    M1 = np.asarray(pipeline.score(raw, est).parameters["conversion_matrix"])
    ratio = M1 / M0
    # only the rows (channels) are rescaled: diag(e/ê)·M, times one brightness factor
    assert np.allclose(ratio, ratio[:, :1], rtol=1e-9)


def _uniform_cube(scene, reflectance_of_pixels):
    from spectracam.scene.illuminant import white_diffuser_radiance

    white = white_diffuser_radiance(scene.illuminant, scene.grid)
    rad = (np.asarray(reflectance_of_pixels, float)[..., None] * white).astype(np.float32)
    return RadianceCube(rad, scene.grid.centres_nm, {"renderer": None})


@pytest.mark.parametrize("method", ["average", "percentile"])
def test_metering_finds_the_implied_white(method):
    from spectracam.camera import band_weights
    from spectracam.sensor.metering import metered_white_rates

    scene = _scene()
    cap = scene.camera.capture.replace(metering=method)
    rng = np.random.default_rng(4)
    if method == "average":   # a uniform grey of the target reflectance: its white is the perfect white
        refl = np.full((40, 40), cap.metering_target)
    else:                     # 5 % of the pixels a perfect white, the rest darker: the 99th percentile is white
        refl = rng.uniform(0.05, 0.8, (40, 40))
        refl[:2] = 1.0
    cube = _uniform_cube(scene, refl)
    w = band_weights(scene.camera, scene.grid).astype(np.float64)
    white = _uniform_cube(scene, np.ones((1, 1))).radiance[0, 0].astype(np.float64) @ w
    got = metered_white_rates(cube.radiance, w, cap)
    assert np.allclose(got, white, rtol=1e-6)


def test_metering_auto_follows_the_camera_and_an_explicit_one_wins():
    scene = _scene(camera="developed")
    assert metered_camera(scene.camera, scene.processing).capture.metering == "percentile"
    assert metered_camera(scene.camera, ProcessingSpec()).capture.metering == "white_patch"
    cam = scene.camera.replace(capture=scene.camera.capture.replace(metering="average"))
    assert metered_camera(cam, scene.processing).capture.metering == "average"


@pytest.mark.parametrize("field,value", [("processing.camera", "guess"), ("processing.white_balance", "max"),
                                         ("processing.calibration", "triple"), ("capture.metering", "spot"),
                                         ("processing.white_balance_p", 0.5), ("capture.metering_percentile", 101),
                                         ("capture.metering_target", 0), ("processing.white_balance_sigma_px", -1),
                                         ("processing.white_balance_training", "nosuch")])
def test_bad_values_name_the_field(field, value):
    from spectracam.pipeline.scene_file import Scene

    table, key = field.split(".")
    with pytest.raises(ConfigError, match=field.replace(".", r"\.")):
        Scene.from_dict({table: {key: value}})


def test_a_trained_estimator_with_nothing_left_to_train_on_is_refused(tmp_path):
    # by name, before any work: the scored chart's own library
    with pytest.raises(ConfigError, match="white_balance_training.*scored scene's own library"):
        _scene(camera="developed", white_balance_training="colorchecker24")
    # by content: a file of the chart's own spectra (a copy under another name) leaves nothing once they are removed
    from spectracam.scene.chart import patch_reflectances

    scene = _scene(camera="developed")
    lam = np.arange(380.0, 781.0, 5.0)
    rows = np.stack([rho(lam) for _, rho in patch_reflectances(scene.chart)])
    csv = tmp_path / "copy.csv"
    csv.write_text("wavelength_nm," + ",".join(f"p{i}" for i in range(24)) + "\n"
                   + "\n".join(f"{w:g}," + ",".join(f"{v:.6f}" for v in rows[:, j]) for j, w in enumerate(lam)) + "\n")
    scene = _scene(camera="developed", white_balance_training=f"file:{csv}")
    cube = pipeline.render(scene, "analytic")
    raw = pipeline.capture(cube, scene=scene)
    with pytest.raises(SpectracamError, match="white_balance_training.*remain"):
        pipeline.score(raw, scene)


def test_every_estimator_runs_on_a_chart_and_beats_chance():
    scene = _scene(camera="developed")
    cube = pipeline.render(scene, "analytic")
    raw = pipeline.capture(cube, scene=scene)
    for method in WHITE_BALANCE_METHODS:
        s = scene.replace(processing=scene.processing.replace(white_balance=method))
        r = pipeline.score(raw, s)
        assert r.white_balance["method"] == method
        assert 0 <= r.summary.awb_recovery_deg < 15, method
        assert np.isfinite(r.summary.delta_e_mean)


def test_simulate_reports_both_cameras(tmp_path):
    from click.testing import CliRunner

    from spectracam.cli import main

    out = tmp_path / "d65"
    res = CliRunner().invoke(main, ["simulate", "d65", "-o", str(out), "--renderer", "analytic", "--quiet",
                                    "--set", "image.width=160", "--set", "image.height=120"])
    assert res.exit_code == 0, res.output
    report = json.loads((out / "report.json").read_text())
    bw = report["both_ways"]
    assert set(bw) >= {"oracle", "developed"}
    assert bw["oracle"]["delta_e_mean"] == report["chart"]["delta_e_mean"]
    assert bw["oracle"]["awb_recovery_deg"] == 0.0 and bw["developed"]["awb_recovery_deg"] > 0
    for k in ("delta_e_mean", "delta_e_p95", "delta_e2000_mean", "held_out_delta_e", "metered_exposure_ms"):
        assert bw["developed"][k] > 0
    assert report["white_balance"]["method"] == "oracle"
    # the page shows the two cameras side by side
    from spectracam.view.page import both_ways_table

    table = both_ways_table(report)
    assert "oracle (told the light)" in table and f"{bw['developed']['delta_e_mean']:.2f}" in table
    assert "S-CIELAB" in table and f"{bw['developed']['s_cielab_mean']:.2f}" in table


def test_a_sweep_over_the_white_balance(tmp_path):
    from pathlib import Path

    import pyarrow.parquet as pq

    from spectracam.experiments.sweep.experiment import load_sweep, run_sweep

    base = (Path(__file__).parent.parent / "scenes" / "blackbody_5000K.toml").resolve()
    p = tmp_path / "sweep.toml"
    p.write_text(f"""
base_scene = "{base}"
renderer = "analytic"
trials = 1
seed = 3
metrics = ["delta_e_mean", "delta_e2000_mean", "awb_recovery_deg", "capture_time_ms"]
[scene]
image = {{ width = 96, height = 72 }}
processing = {{ camera = "developed" }}
[axes]
"illuminant.temperature_K" = [3000, 6500]
"processing.white_balance" = ["oracle", "grey_world", "white_patch", "corrected_moments"]
""")
    run_sweep(load_sweep(p), tmp_path / "out", serial=True, progress=False)
    rows = pq.read_table(tmp_path / "out" / "results.parquet").to_pylist()
    assert len(rows) == 8
    by = {(r["illuminant.temperature_K"], r["processing.white_balance"]): r for r in rows}
    for T in (3000, 6500):
        assert by[(T, "oracle")]["awb_recovery_deg"] == 0.0
        assert all(by[(T, m)]["awb_recovery_deg"] > 0 for m in ("grey_world", "white_patch", "corrected_moments"))
        # the developed camera meters its own preview: percentile metering, the same for every estimator
        assert len({by[(T, m)]["capture_time_ms"] for m in ("oracle", "grey_world")}) == 1
        assert by[(T, "grey_world")]["delta_e_mean"] != by[(T, "oracle")]["delta_e_mean"]


@pytest.mark.parametrize("camera", ["oracle", "developed"])
def test_dng_carries_forward_matrices_and_the_cameras_own_neutral(tmp_path, camera):
    import tifffile
    from click.testing import CliRunner

    from spectracam.cli import main

    out = tmp_path / camera
    res = CliRunner().invoke(main, ["simulate", "blackbody_3000K", "-o", str(out), "--renderer", "analytic", "--quiet",
                                    "--set", "image.width=160", "--set", "image.height=120",
                                    "--set", f"processing.camera={camera}"])
    assert res.exit_code == 0, res.output
    report = json.loads((out / "report.json").read_text())
    with tifffile.TiffFile(out / "raw.dng") as t:
        tags = t.pages[0].tags

        def rationals(code):
            v = np.asarray(tags[code].value, float)
            return v[0::2] / v[1::2]

        for code in (50964, 50965):   # ForwardMatrix1, 2: XYZ_D50 = FM·balanced camera, the neutral onto D50
            fm = rationals(code).reshape(3, 3)
            assert np.allclose(fm @ np.ones(3), D50_XYZ, atol=3e-6)
        assert (tags[50778].value, tags[50779].value) == (17, 21)   # CIE A and D65
        asn = rationals(50728)
    times = np.asarray([report["chart"][f"exposure_{k}_ms"] for k in "RGB"])
    want = np.asarray(report["white_balance"]["neutral"]) * times
    assert np.allclose(asn, want / want.max(), atol=2e-6)
    if camera == "developed":   # the camera's own white, not the truth
        truth = np.asarray(report["white_balance"]["true_neutral"]) * times
        assert np.max(np.abs(asn - truth / truth.max())) > 1e-3


# ---- the design with an estimated white ------------------------------------------------------------------------
@pytest.fixture(scope="module")
def paper_design():
    from spectracam.experiments.design.spec import DesignSpec
    from spectracam.experiments.paper.experiment import calibrated_luminance, load_experiment
    from spectracam.scene.illuminant import IlluminantSpec
    from spectracam.pipeline.scene_file import shipped_scene_file

    exp = load_experiment(shipped_scene_file("paper.toml"))
    level = calibrated_luminance(exp, exp.base.camera)
    base = exp.base.replace(image=exp.base.image.replace(width=160, height=120))
    scenes = [base.replace(illuminant=IlluminantSpec("blackbody", 3000.0, None, level))]
    return exp, scenes, DesignSpec


def _design_problem(paper_design, **settings):
    from spectracam.experiments.design.problem import DesignProblem

    exp, scenes, DesignSpec = paper_design
    return DesignProblem("cfa/single", "gaussian", DesignSpec(filters="gaussian", **settings), exp.base.camera,
                         exp.base.processing, scenes, "tcs14", "vs15")


def test_design_white_penalty_is_the_numpy_computation(paper_design):
    from spectracam.experiments.design.ad import numpy as tnumpy
    from spectracam.experiments.design.ad import tensor
    from spectracam.core.cielab import xyz_to_lab

    p = _design_problem(paper_design, white_balance="shades_of_grey", white_balance_p=6.0)
    x = p.initial()
    res = p.evaluate(tensor(x))[0]
    got = tnumpy(res.white_penalty["tcs14"])
    # the same in numpy from the model's own inputs
    R = np.stack([tnumpy(r) for r in p.responsivities(tensor(x))])          # (N, B)
    light, wm = p.lights[0], p.white[0]["tcs14"]
    cs = light.sets["tcs14"]
    rates = cs.weights @ R.T                                                 # (S, N)
    M = np.array([[float(tnumpy(m).reshape(-1)[0]) for m in row] for row in res.conversion])   # (N, 3)
    e = wm.white_weights @ R.T
    est = (wm.weights @ (rates / e) ** 6.0 / wm.weights.sum(axis=1)[:, None]) ** (1 / 6.0) * e   # (K, N)
    Md = p.model.display_matrix
    y = M @ Md[1]
    g = e / est
    g *= (e @ y) / ((g * e) @ y)[:, None]
    white = Md.sum(axis=1)
    truth = cs.lab
    plain = np.linalg.norm(xyz_to_lab(rates @ M @ Md.T, white) - truth, axis=-1).mean()
    want = np.array([np.linalg.norm(xyz_to_lab((rates * gj) @ M @ Md.T, white) - truth, axis=-1).mean() - plain
                     for gj in g])
    np.testing.assert_allclose(got, want, rtol=1e-7, atol=1e-9)
    assert np.all(np.isfinite(want)) and want.mean() > 0.05     # an estimated white costs something


def test_design_objective_adds_the_white_penalty_and_its_gradient_is_exact(paper_design):
    from spectracam.experiments.design.ad import numpy as tnumpy
    from spectracam.experiments.design.ad import tensor

    oracle = _design_problem(paper_design)
    est = _design_problem(paper_design, white_balance="grey_world")
    x = oracle.initial()
    v0, _, de0 = oracle.value_and_gradient(x)
    v1, g, de1 = est.value_and_gradient(x)
    pen = tnumpy(est.evaluate(tensor(x), sets=("tcs14",))[0].white_penalty["tcs14"]).mean()
    assert v1 == pytest.approx(v0 + pen, rel=1e-9) and de1 == pytest.approx(de0 + pen, rel=1e-9)
    assert_gradient_is_central_differences(est, x, g, (0, 2, x.size - 1))


def test_design_white_balance_values_are_checked():
    from spectracam.experiments.design.spec import DesignSpec

    with pytest.raises(ConfigError, match="white_balance"):
        DesignSpec(white_balance="corrected_moments")
    with pytest.raises(ConfigError, match="white_balance_p"):
        DesignSpec(white_balance_p=0.5)


def test_tone_curve_changes_the_picture_never_the_score(tmp_path):
    from click.testing import CliRunner
    from PIL import Image

    from spectracam.cli import main
    from spectracam.processing.tone import tone_map

    out = {}
    for tone in ("srgb", "filmic"):
        d = tmp_path / tone
        res = CliRunner().invoke(main, ["simulate", "d65", "-o", str(d), "--renderer", "analytic", "--quiet",
                                        "--set", "image.width=160", "--set", "image.height=120",
                                        "--set", "processing.camera='developed'",
                                        "--set", f"processing.tone_curve='{tone}'"])
        assert res.exit_code == 0, res.output
        out[tone] = (json.loads((d / "report.json").read_text()), np.asarray(Image.open(d / "rendered.png")))
    (a, png_a), (b, png_b) = out["srgb"], out["filmic"]
    assert a["chart"] == b["chart"] and a["both_ways"] == b["both_ways"]
    assert np.abs(png_a.astype(int) - png_b.astype(int)).max() > 20
    # the developed camera shows its metered white at Y = 1: sRGB clips it, filmic keeps it below the top code
    x = np.array([0.0, 0.18, 1.0, 4.0])
    s, f = tone_map(x, "srgb"), tone_map(x, "filmic")
    assert s.tolist() == [0.0, 0.18, 1.0, 1.0] and f[0] == 0 and np.all(np.diff(f) > 0) and f[-1] < 1


@pytest.mark.parametrize("adaptation", ["xyz_scaling", "bradford", "cat16"])
def test_every_adaptation_carries_white_to_white_and_the_developed_camera_runs_with_it(adaptation):
    from spectracam.processing.color import adaptation_matrix

    a, b = np.array([1.0985, 1.0, 0.3558]), np.array([0.9505, 1.0, 1.0888])   # CIE A, D65
    A = adaptation_matrix(a, b, adaptation)
    assert np.allclose(A @ a, b, atol=1e-9)
    if adaptation == "cat16":   # not the Bradford matrix: a named, different transform
        assert not np.allclose(A, adaptation_matrix(a, b, "bradford"), atol=1e-3)
    scene = _scene("blackbody_3000K", camera="developed", white_balance="oracle", adaptation=adaptation)
    cube = pipeline.render(scene, "analytic")
    r = pipeline.score(pipeline.capture(cube, scene=scene), scene)
    assert r.white_balance["calibration"] == "dual_illuminant" and np.isfinite(r.summary.delta_e_mean)


def test_the_shipped_two_cameras_sweep_loads_every_estimator():
    from spectracam.experiments.sweep.experiment import load_sweep
    from spectracam.processing.white_balance import WHITE_BALANCE_METHODS
    from spectracam.pipeline.scene_file import shipped_scene_file

    sw = load_sweep(shipped_scene_file("sweeps/two_cameras.toml"))
    axes = dict(sw.axes)
    assert set(axes["processing.white_balance"]) == set(WHITE_BALANCE_METHODS)
    assert len(sw.cells()) == 2 * 3 * len(WHITE_BALANCE_METHODS)
    assert sw.base["processing"]["camera"] == "developed"
