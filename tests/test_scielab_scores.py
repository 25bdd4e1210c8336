"""The chart's S-CIELAB beside its per-pixel ΔE*ab, and the rule that names no winner from an unusable image."""
import math

import numpy as np
import pytest

from conftest import small_scene
from spectracam.camera import CameraSpec, CaptureSpec
from spectracam.camera.capture import capture
from spectracam.processing.color import ProcessingSpec, adaptation_matrix, display_rgb_to_xyz
from spectracam.core.errors import ConfigError
from spectracam.scene.reference import ChartReference
from spectracam.evaluation.score import chart_scielab_map, chart_truth_xyz, developed_rgb, score
from spectracam.sensor import SensorSpec
from spectracam.evaluation.scielab import samples_per_degree, scielab

NOISELESS = SensorSpec().off("shot_noise", "dark_current", "read_noise", "fpn", "quantization")


@pytest.fixture(scope="module")
def noisy(scene_5000, analytic_5000):
    """The default Bayer camera with its noise, and its score."""
    ref = ChartReference.of(scene_5000)
    raw = capture(analytic_5000, scene_5000.camera, 3, ref.white_box)
    return raw, ref, score(raw, ref, scene_5000.processing)


def test_noise_free_uniform_patches_give_their_cielab_difference():
    # Zhang & Wandell's requirement: on a uniform area S-CIELAB is CIELAB.  Noise-free, without demosaicking, each
    # patch's scored box is uniform; at 10 samples per degree the filters (9 taps) reach 4 px, less than the box's
    # inset from the patch edge at 320x240 (0.15 of a 38-px patch: 5.7 px)
    from spectracam.render import render

    scene = small_scene(illuminant={"temperature_K": 5000}, image={"width": 320, "height": 240})
    ref = ChartReference.of(scene)
    cam = CameraSpec(sensor=NOISELESS, capture=CaptureSpec("prism", "optimal"))
    raw = capture(render(scene, "analytic"), cam, 0, ref.white_box)
    processing = scene.processing.replace(viewing_distance_m=0.5, display_pixel_pitch_mm=0.8727)
    assert processing.samples_per_degree == pytest.approx(10.0, rel=1e-3)
    res = score(raw, ref, processing)
    truth = chart_truth_xyz(ref, slice(0, ref.height_px), slice(0, ref.width_px))
    for p, (r, c) in enumerate(ref.boxes):   # the premise: each box and the filters' 4-px reach lie in its patch
        near = truth[r.start - 4:r.stop + 4, c.start - 4:c.stop + 4]
        np.testing.assert_allclose(near, np.broadcast_to(ref.patch_xyz[p], near.shape), atol=1e-12)
    for p in res.patches:
        assert p.s_cielab_mean == pytest.approx(p.delta_e_mean, abs=2e-4)   # float32 maps of ΔE up to ~20
    assert res.summary.s_cielab_mean == pytest.approx(res.summary.delta_e_mean, abs=2e-4)
    assert res.summary.s_cielab_p95 == pytest.approx(res.summary.delta_e_p95, abs=2e-4)


def test_s_cielab_is_below_per_pixel_delta_e_for_a_noisy_capture(noisy):
    # the eye's filters average the noise the per-pixel ΔE counts in full; the conversion's error stays
    _, _, res = noisy
    c = res.summary
    assert c.s_cielab_mean < c.delta_e_mean and c.s_cielab_p95 < c.delta_e_p95
    # …and it is not the noise-free error either: the noise the eye sees is left (a filter that removed everything
    # would give ΔE of the patch means)
    assert c.s_cielab_mean > 0.5 * c.delta_e_of_mean
    assert sum(p.s_cielab_mean < p.delta_e_mean for p in res.patches) >= 22


def test_chart_map_equals_scielab_of_the_whole_image_band_by_band(noisy, scene_5000, monkeypatch):
    # the crop to the scored boxes plus the filters' reach, and the bands of rows, change nothing: the map equals
    # spectracam.evaluation.scielab on the whole rendered image against the whole truth image
    import importlib

    score_module = importlib.import_module("spectracam.evaluation.score")

    raw, ref, res = noisy
    processing = scene_5000.processing
    rgb, _, _ = developed_rgb(raw, ref, processing)
    M = display_rgb_to_xyz(processing.display)
    white = M.sum(axis=1)
    truth = chart_truth_xyz(ref, slice(0, ref.height_px), slice(0, ref.width_px))
    truth = truth @ adaptation_matrix(ref.white_xyz, white, processing.adaptation).T
    spd = samples_per_degree(processing.viewing_distance_m, processing.display_pixel_pitch_mm * 1e-3)
    whole = scielab(rgb @ M.T, truth, white, spd)
    mask = np.isfinite(res.delta_e_map)
    got = chart_scielab_map(rgb, ref, processing)
    assert np.array_equal(np.isfinite(got), mask)
    np.testing.assert_allclose(got[mask], whole[mask], rtol=0, atol=1e-4)
    monkeypatch.setattr(score_module, "SCIELAB_CHUNK_PIXELS", 3000)   # ~20 rows a band
    score_module._truth_scielab_lab.cache_clear()
    banded = chart_scielab_map(rgb, ref, processing)
    score_module._truth_scielab_lab.cache_clear()
    np.testing.assert_allclose(banded[mask], got[mask], rtol=0, atol=1e-5)


def test_truth_image_is_the_patch_colours_over_their_pixel_areas(scene_5000):
    ref = ChartReference.of(scene_5000)
    truth = chart_truth_xyz(ref, slice(0, ref.height_px), slice(0, ref.width_px))
    for p, (r, c) in enumerate(ref.boxes):
        np.testing.assert_allclose(truth[r, c], np.broadcast_to(ref.patch_xyz[p], truth[r, c].shape), atol=1e-12)
    np.testing.assert_allclose(truth[0, 0], ref.chart.surround_reflectance * ref.white_xyz, atol=1e-12)


def test_scoring_draws_no_random_numbers_and_leaves_the_other_scores_alone(noisy, scene_5000):
    raw, ref, res = noisy
    state = np.random.get_state()[1].copy()
    again = score(raw, ref, scene_5000.processing)
    assert np.array_equal(np.random.get_state()[1], state)
    assert again.summary == res.summary
    # the viewing geometry moves S-CIELAB only
    far = score(raw, ref, scene_5000.processing.replace(viewing_distance_m=2.0))
    for f in ("delta_e_mean", "delta_e_p95", "snr_combined_db", "delta_e2000_mean"):
        assert getattr(far.summary, f) == getattr(res.summary, f)
    assert far.summary.s_cielab_mean < res.summary.s_cielab_mean   # farther: more pixels per degree, more blur
    assert res.parameters["s_cielab"]["samples_per_degree"] == pytest.approx(41.228, abs=1e-3)


@pytest.mark.parametrize("changes, field", [
    ({"viewing_distance_m": 0}, "viewing_distance_m"), ({"viewing_distance_m": -1}, "viewing_distance_m"),
    ({"viewing_distance_m": math.nan}, "viewing_distance_m"), ({"viewing_distance_m": "far"}, "viewing_distance_m"),
    ({"viewing_distance_m": True}, "viewing_distance_m"), ({"display_pixel_pitch_mm": 0}, "display_pixel_pitch_mm"),
    ({"display_pixel_pitch_mm": math.inf}, "display_pixel_pitch_mm"),
    ({"viewing_distance_m": 100, "display_pixel_pitch_mm": 0.01}, "viewing_distance_m"),   # 1.7e5 samples/degree
    ({"viewing_distance_m": 0.05, "display_pixel_pitch_mm": 10}, "viewing_distance_m"),    # 0.09 samples/degree
])
def test_viewing_geometry_is_validated_in_one_line(changes, field):
    with pytest.raises(ConfigError) as e:
        ProcessingSpec(**changes)
    assert str(e.value).startswith(f"processing.{field} = ") and "\n" not in str(e.value)


def test_validation_uses_the_scielab_samples_per_degree():
    for d, p in ((0.5, 25.4 / 120), (3.0, 0.5), (0.1, 1.0)):
        spec = ProcessingSpec(viewing_distance_m=d, display_pixel_pitch_mm=p)
        assert spec.samples_per_degree == samples_per_degree(d, p * 1e-3)
    assert ProcessingSpec.from_dict({"viewing_distance_m": 1}).viewing_distance_m == 1.0


# -- no winner from an unusable image ------------------------------------------------------------------------------

def test_usability_thresholds_and_reasons():
    from spectracam.evaluation.usability import UsabilitySpec

    u = UsabilitySpec()
    assert (u.min_white_snr_db, u.max_s_cielab_mean) == (20.0, 40.0)
    assert u.judge(8.0, 36.0) == (True, "") and u.judge(40.0, 20.0) == (True, "")   # the thresholds themselves pass
    ok, why = u.judge(149.5, -13.0)
    assert not ok and why == "white-patch SNR -13.0 dB < 20 dB; mean S-CIELAB 149.5 > 40"
    assert u.judge(5.0, 19.9) == (False, "white-patch SNR 19.9 dB < 20 dB")
    assert u.judge(41.0, None) == (False, "mean S-CIELAB 41.0 > 40")   # noise-free or undefined SNR: ΔE decides
    assert u.judge(5.0, None) == (True, "") and u.judge(None, 30.0)[0] is False
    for bad in ({"min_white_snr_db": math.nan}, {"max_s_cielab_mean": 0}, {"max_s_cielab_mean": "x"}):
        with pytest.raises(ConfigError) as e:
            UsabilitySpec(**bad)
        assert str(e.value).startswith("usability.") and "\n" not in str(e.value)


def test_winners_skip_unusable_cases_and_say_when_none_is_usable():
    from spectracam.experiments.architectures.experiment import winners

    def row(design, de, usable, factor=1.0):
        return {"illuminant": "D65", "light_factor": factor, "design": design, "delta_e_mean": de,
                "delta_e_mean_sd": 0.1, "s_cielab_mean": de / 2, "s_cielab_mean_sd": 0.1, "usable": usable,
                "unusable_reason": "" if usable else "mean ΔE*ab > 40"}

    rows = [row("a", 5.0, True), row("b", 3.0, False), row("c", 200.0, False, 0.01), row("d", 150.0, False, 0.01)]
    got = {(w["light_factor"], w["metric"]): w for w in winners(rows)}
    assert got[(1.0, "delta_e_mean")]["design"] == "a" and got[(1.0, "s_cielab_mean")]["design"] == "a"
    for m in ("delta_e_mean", "s_cielab_mean"):
        assert got[(0.01, m)]["design"] is None and got[(0.01, m)]["note"] == "no usable image"


@pytest.fixture(scope="module")
def dim_and_normal():
    """architectures at the paper's light and at 1/100 of it (quick, analytic, one seed, chart only)."""
    from spectracam.experiments.options import default_experiment
    from spectracam.experiments.architectures.experiment import ArchitecturesRun, run_architectures
    from spectracam.experiments.paper.experiment import load_experiment

    run = ArchitecturesRun(load_experiment(default_experiment(), ()), quick=True, seeds=1, light_factors=(1.0, 0.01),
                           natural_scenes=())
    return run_architectures(run, renderer="analytic", use_cache=False, spacetime=False)


def test_architectures_at_a_hundredth_of_the_light_names_no_winner(dim_and_normal, tmp_path):
    from spectracam.experiments.architectures.experiment import write_architectures_outputs

    res = dim_and_normal
    dim = [r for r in res["rows"] if r["light_factor"] == 0.01]
    assert dim and not any(r["usable"] for r in dim) and all(r["unusable_reason"] for r in dim)
    for w in res["winners"]:
        if w["light_factor"] == 0.01:
            assert w["design"] is None and w["note"] == "no usable image"
    # the paper's light: every design usable, and the winners are the plain minima / maxima as before the rule
    normal = [r for r in res["rows"] if r["light_factor"] == 1.0]
    assert all(r["usable"] and r["developed_usable"] for r in normal)
    for w in res["winners"]:
        if w["light_factor"] == 1.0 and w["metric"] in ("delta_e_mean", "s_cielab_mean"):
            group = [r for r in normal if r["illuminant"] == w["illuminant"]]
            assert w["design"] == min(group, key=lambda r: r[w["metric"]])["design"]
    for r in res["rows"]:   # S-CIELAB beside ΔE*ab in every row, with its spread
        for key in ("s_cielab_mean", "s_cielab_mean_sd", "s_cielab_p95", "snr_white_rendered_db", "usable",
                    "developed_s_cielab_mean", "developed_usable"):
            assert key in r
    write_architectures_outputs(tmp_path, res, "test")
    md = (tmp_path / "report.md").read_text()
    assert "no usable image" in md and "S-CIELAB mean ± sd (rank)" in md and "Does S-CIELAB change the verdict" in md
    what_wins = md.split("## What wins where")[1]
    for line in what_wins.splitlines():
        if line.startswith("| D65 | 0.01× |") or line.startswith("| 3000 K | 0.01× |"):
            assert "no usable image" in line


def test_sweep_rows_carry_s_cielab_and_usability(scene_5000, analytic_5000):
    from spectracam.experiments.sweep.experiment import METRICS, run_cell

    assert {"s_cielab_mean", "s_cielab_p95", "snr_white_rendered_db"} <= set(METRICS)
    out = run_cell(0, {"illuminant.temperature_K": 5000}, scene_5000, analytic_5000, 1, 7,
                   ("delta_e_mean", "s_cielab_mean", "s_cielab_p95"))
    row = out["rows"][0]
    assert row["s_cielab_mean"] < row["delta_e_mean"] and row["usable"] is True and row["unusable_reason"] == ""


def test_score_row_has_s_cielab(noisy):
    from spectracam.pipeline import BOTH_WAYS_FIELDS, score_row

    _, _, res = noisy
    row = score_row(res)
    assert set(row) == set(BOTH_WAYS_FIELDS)
    assert row["s_cielab_mean"] == res.summary.s_cielab_mean and row["s_cielab_p95"] == res.summary.s_cielab_p95


def test_architectures_usability_options_reach_the_run_and_are_validated(monkeypatch, tmp_path):
    """--min-white-snr-db / --max-s-cielab set the run's UsabilitySpec and are recorded in the command; a bad value
    is one line with exit 2 before any work."""
    from click.testing import CliRunner

    from spectracam import cli
    from spectracam.experiments.architectures import experiment as arch

    seen = {}

    def fake_run(run, **kwargs):
        seen["usability"] = run.usability
        raise SystemExit(0)

    monkeypatch.setattr(arch, "run_architectures", fake_run)
    r = CliRunner().invoke(cli.main, ["architectures", "-o", str(tmp_path / "a"), "--quick", "--quiet",
                                      "--min-white-snr-db", "25", "--max-s-cielab", "12.5"])
    assert r.exit_code == 0, r.output
    assert seen["usability"].min_white_snr_db == 25.0 and seen["usability"].max_s_cielab_mean == 12.5
    for opt, value in (("--min-white-snr-db", "99"), ("--max-s-cielab", "nan"), ("--max-s-cielab", "0.1")):
        r = CliRunner().invoke(cli.main, ["architectures", "-o", str(tmp_path / "b"), "--quick", opt, value])
        assert r.exit_code == 2, r.output
        assert len(r.output.strip().splitlines()) == 1 and "usability." in r.output
    assert not (tmp_path / "b").exists()


@pytest.mark.parametrize("shape", [(480, 640), (37, 53), (12, 9)])
def test_fft_filter_equals_the_row_and_column_passes(shape):
    """The chart scores' FFT filter (numpy 'symmetric' padding = scipy 'reflect') is scielab_filter to rounding:
    float64 (the default) to 1e-12, float32 to 2e-6 of the values' scale — including images smaller than the kernels' reach."""
    from spectracam.evaluation.scielab import scielab_filter, scielab_filter_fft

    x = np.random.default_rng(3).random((*shape, 3))
    ref = scielab_filter(x, 41.23)
    assert np.abs(scielab_filter_fft(x, 41.23) - ref).max() < 1e-12
    assert np.abs(scielab_filter_fft(x, 41.23, np.float32) - ref).max() < 2e-6


@pytest.mark.parametrize("n", [1, 2, 5, 33])
@pytest.mark.parametrize("reach", [0, 1, 4, 20, 70])
def test_reflected_indices_are_numpys_symmetric_padding(n, reach):
    """The bands' extension beyond the image's edges is numpy.pad's "symmetric" (scipy's "reflect"), also when the
    reach is longer than the axis (the reflection repeats)."""
    from spectracam.evaluation.scielab import reflected_indices

    axis = np.arange(n) * 10
    want = np.pad(axis, (reach, reach + 3), mode="symmetric")
    np.testing.assert_array_equal(axis[reflected_indices(-reach, n + reach + 3, n)], want)


def test_the_extended_filter_refuses_a_band_within_its_reach():
    from spectracam.evaluation.scielab import filter_extended_opponent, scielab_reach

    r = scielab_reach(41.23)
    assert r == 20
    with pytest.raises(ValueError) as e:
        filter_extended_opponent(np.zeros((2 * r, 100, 3)), 41.23)
    assert str(e.value).count("\n") == 0 and "(40, 100, 3)" in str(e.value) and "more than 40 rows" in str(e.value)


@pytest.mark.parametrize("fused", ["1", "0"])
@pytest.mark.parametrize("size", [(60, 36), (200, 150)])
def test_chart_map_with_neighbouring_rows_as_the_margin_is_the_whole_images(size, fused, monkeypatch):
    """Each band of the chart's S-CIELAB is filtered with its neighbours' rows (reflected rows at the image's
    edges) as its only margin (issue 38): the map equals scielab of the whole image, in bands of a few rows, on a
    chart smaller than the kernels' reach (60 × 36 at 41 samples/degree: reach 20) and a larger one; with the
    compiled kernels and without (``SPECTRACAM_FUSED=0``)."""
    import importlib

    import spectracam

    score_module = importlib.import_module("spectracam.evaluation.score")
    monkeypatch.setenv("SPECTRACAM_FUSED", fused)
    scene = small_scene(image={"width": size[0], "height": size[1]})
    raw = spectracam.capture(spectracam.render(scene, "analytic"), scene=scene)
    ref, processing = ChartReference.of(scene), scene.processing
    rgb, _, _ = developed_rgb(raw, ref, processing)
    M = display_rgb_to_xyz(processing.display)
    white = M.sum(axis=1)
    truth = chart_truth_xyz(ref, slice(0, ref.height_px), slice(0, ref.width_px))
    truth = truth @ adaptation_matrix(ref.white_xyz, white, processing.adaptation).T
    whole = scielab(rgb @ M.T, truth, white, processing.samples_per_degree)
    for chunk in (1 << 19, 7 * (size[0] + 40)):   # one band; bands of 7 rows
        monkeypatch.setattr(score_module, "SCIELAB_CHUNK_PIXELS", chunk)
        score_module._truth_scielab_lab.cache_clear()
        got = chart_scielab_map(rgb, ref, processing)
        mask = np.isfinite(got)
        assert mask.sum() == sum((r.stop - r.start) * (c.stop - c.start) for r, c in ref.boxes) > 0
        np.testing.assert_allclose(got[mask], whole[mask], rtol=0, atol=2e-5)
    score_module._truth_scielab_lab.cache_clear()
