"""``spectracam dynamic-range`` (issue 36, item 5): the kept range against its definition, the read-outs' order on
the shipped ladder, the command's files and its refusals."""
import json
import math

import pytest

from spectracam.experiments.dynamic_range.experiment import DELTA_E_KEPT, kept_range


def _rows(lums, des):
    return [{"white_luminance_cd_m2": L, "delta_e_ab": d} for L, d in zip(lums, des)]


def test_kept_range_interpolates_the_crossings_in_log_luminance():
    k = kept_range(_rows([1e-2, 1e-1, 1.0, 10.0, 100.0], [10.0, 2.0, 1.0, 2.0, 10.0]))
    # between 0.1 (ΔE 2) and 0.01 (ΔE 10) the threshold 3 lies 1/8 of a decade below 0.1; the same above 10
    assert k["lo_cd_m2"] == pytest.approx(10 ** -1.125, rel=1e-12)
    assert k["hi_cd_m2"] == pytest.approx(10 ** 1.125, rel=1e-12)
    assert k["range_db"] == pytest.approx(20 * 2.25, rel=1e-12)
    assert not k["lo_open"] and not k["hi_open"]


def test_kept_range_takes_the_widest_run_and_says_when_it_reaches_an_end():
    k = kept_range(_rows([1e-2, 1e-1, 1.0, 10.0, 100.0, 1e3], [1.0, 1.0, 9.0, 1.0, 1.0, 1.0]))
    assert k["lo_open"] is False and k["hi_open"] is True
    assert k["hi_cd_m2"] == pytest.approx(1e3)
    assert k["lo_cd_m2"] == pytest.approx(10 ** (1 - (DELTA_E_KEPT - 1.0) / 8.0), rel=1e-12)
    everything = kept_range(_rows([1.0, 10.0], [0.5, 0.5]))
    assert everything["lo_open"] and everything["hi_open"] and everything["range_db"] == pytest.approx(20.0)


def test_kept_range_of_nothing_kept_is_zero_and_unscored_charts_are_not_kept():
    assert kept_range(_rows([1.0, 10.0], [5.0, 4.0]))["range_db"] == 0.0
    k = kept_range(_rows([1.0, 10.0, 100.0], [None, 1.0, 1.0]))
    assert k["lo_cd_m2"] == pytest.approx(10.0) and k["hi_open"]


@pytest.fixture(scope="module")
def ladder_run():
    from spectracam.experiments.dynamic_range.experiment import plan, run_dynamic_range

    # a modern sensor (12-bit ADC, 0.1 % offset FPN): the paper's 8 bits and 1 % FPN cap a single read near 40 dB
    run = plan(quick=True, seeds=1, renderer="analytic", designs=("cfa/single",),
               readouts=("single", "multiple_capture", "bracketing"), temperatures_C=(25.0,),
               sets=("sensor.adc_bits=12", "sensor.fpn_fraction=0.001"))
    return run_dynamic_range(run, log=lambda *a: None)


def _kept(result, readout, exposure="scene", against="capture"):
    return next(k for k in result["kept"] if k["readout"] == readout and k["exposure"] == exposure
                and k["against"] == against)


def test_the_single_read_keeps_the_bright_charts_and_loses_the_dark(ladder_run):
    rows = sorted((r for r in ladder_run["rows"] if r["scene"] == "ladder" and r["readout"] == "single"
                   and r["exposure"] == "scene"), key=lambda r: r["white_luminance_cd_m2"])
    assert rows[-1]["delta_e_capture"] < DELTA_E_KEPT < rows[0]["delta_e_capture"]
    assert all(r["delta_e_ab"] >= r["delta_e_capture"] - 0.5 for r in rows)   # the conversion's own error on top
    k = _kept(ladder_run, "single")
    # per-pixel ΔE < 3 asks ~35 dB of every patch's pixels: the single read keeps the top of the ladder only
    assert k["hi_open"] and 6.0 < k["range_db"] < 40.0
    # the paper's block filters miss the chart by more than 3 ΔE*ab even without noise: nothing kept against the scene
    assert _kept(ladder_run, "single", against="scene")["range_db"] == 0.0


def test_high_dynamic_range_read_outs_keep_a_wider_range_in_one_exposure(ladder_run):
    single = _kept(ladder_run, "single")["range_db"]
    assert _kept(ladder_run, "multiple_capture")["range_db"] > single + 6.0      # N = 8: up to 18 dB more
    assert _kept(ladder_run, "bracketing")["range_db"] > single + 12.0           # 8² = 64: up to 36 dB more


def test_the_result_carries_spreads_exposures_and_parameters(ladder_run):
    r = ladder_run["rows"][0]
    for k in ("delta_e_ab", "delta_e_2000", "s_cielab", "delta_e_capture", "snr_white_db", "snr_grey_db",
              "exposure_times_ms"):
        assert k in r
    assert r["delta_e_ab_sd"] == 0.0            # one seed
    assert ladder_run["parameters"]["time_limit_ms"] == pytest.approx(1e3 / 30)
    assert {r["scene"] for r in ladder_run["rows"]} == {"ladder", "charts"}
    assert json.loads(json.dumps(ladder_run, allow_nan=False))


def test_each_chart_metered_on_its_own_white_is_not_shortened_past_the_hand_held_limit(ladder_run):
    for r in ladder_run["rows"]:
        if r["exposure"] == "chart" and r["readout"] == "single":
            assert max(r["exposure_times_ms"]) <= 1e3 / 30 * (1 + 1e-9)


def test_the_command_writes_its_files_and_refuses_bad_values_in_one_line(tmp_path):
    from click.testing import CliRunner

    from spectracam.cli import main

    out = tmp_path / "dr"
    r = CliRunner().invoke(main, ["dynamic-range", "-o", str(out), "--quick", "--design", "prism/optimal",
                                  "--readout", "dual_gain", "--temperature", "65", "--quiet"])
    assert r.exit_code == 0, r.output
    for name in ("results.json", "report.md", "dynamic_range.png", "dynamic_range.svg"):
        assert (out / name).stat().st_size > 0
    res = json.loads((out / "results.json").read_text())
    assert res["parameters"]["readouts"] == ["dual_gain"] and res["parameters"]["temperatures_C"] == [65.0]
    assert "--readout dual_gain" in res["command"]
    for bad in (["--readout", "nosuch"], ["--design", "cfa/optimal"], ["--set", "sensor.readout_samples=0"],
                ["--temperature", "400"], ["--set", "sensor.readout=dual_gain"], ["--set", "sensor.temperature_C=60"]):
        r = CliRunner().invoke(main, ["dynamic-range", "-o", str(tmp_path / "x"), "--quick", "--quiet", *bad])
        assert r.exit_code != 0
        msg = r.output.strip().splitlines()
        assert len(msg) == 1 and "Traceback" not in r.output, r.output
    assert math.isfinite(res["seconds"])


def test_a_chart_a_hot_die_cannot_expose_is_recorded_as_such_not_as_an_error():
    """At 105 °C the paper's dark current (×205 by the generation law) outruns the light of a 0.01 cd/m² chart:
    metered on its own white, that chart has no exposure; its row says so, and it counts as not kept."""
    from spectracam.experiments.dynamic_range.experiment import plan, run_dynamic_range

    run = plan(quick=True, seeds=1, renderer="analytic", designs=("cfa/single",), readouts=("single",),
               temperatures_C=(105.0,))
    res = run_dynamic_range(run, log=lambda *a: None)
    dim = next(r for r in res["rows"] if r["scene"] == "ladder" and r["exposure"] == "chart"
               and r["white_luminance_cd_m2"] == 0.01)
    assert dim["delta_e_ab"] is None and dim["note"].startswith("not exposed: exposure: channel")
    k = next(k for k in res["kept"] if k["exposure"] == "chart" and k["against"] == "capture")
    assert k["lo_cd_m2"] is None or k["lo_cd_m2"] > 0.01


def test_a_chart_of_a_light_group_scores_as_the_same_chart_alone():
    """The sun chart of hdr_charts, noise-free, against the one-light scene of that chart at its cell's size: the
    same scored pixels, so the same per-patch ΔE*ab, and the same S-CIELAB (filtered on its cell alone) but where the
    demosaicker reads across the cell's edge."""
    import numpy as np

    from spectracam.evaluation.score import camera_rates, score_region
    from spectracam.pipeline import capture, render, score
    from spectracam.pipeline.scene_file import load_scene, parse_scene
    from spectracam.scene.reference import chart_cells

    off = ["sensor.shot_noise=false", "sensor.read_noise=false", "sensor.fpn=false", "sensor.dark_current=false",
           "sensor.quantization=false"]
    hdr = load_scene("scenes/hdr_charts.toml", ["image.width=320", "image.height=128", *off])
    sun = chart_cells(hdr)[0]
    assert sun.name == "sun" and (sun.cols.start, sun.cols.stop) == (0, 160)
    data = hdr.to_dict()
    data.pop("lights")
    alone = parse_scene({**data, "illuminant": sun.illuminant.to_dict(), "image": {"width": 160, "height": 128}})
    raw_hdr = capture(render(hdr, "analytic"), hdr.camera, seed=0)
    raw_alone = capture(render(alone, "analytic"), alone.camera, seed=0)
    np.testing.assert_allclose(raw_hdr.exposure_times_s, raw_alone.exposure_times_s, rtol=1e-9)
    patches, _, de_capture = score_region(raw_hdr, camera_rates(raw_hdr, hdr.processing), sun.reference,
                                          hdr.processing)
    want = score(raw_alone, alone).patches
    np.testing.assert_allclose([p.delta_e_mean for p in patches], [p.delta_e_mean for p in want], atol=1e-4)
    got_sc = np.array([p.s_cielab_mean for p in patches])
    want_sc = np.array([p.s_cielab_mean for p in want])
    edge = np.arange(5, 24, 6)      # the chart's last column, next to the shade cell
    inner = np.setdiff1d(np.arange(24), edge)
    np.testing.assert_allclose(got_sc[inner], want_sc[inner], atol=1e-4)
    # the demosaicker reads one pixel across the cell's edge (the shade chart's surround, not the image border the
    # chart alone replicates); the eye's filters carry that into the last column's patches: a few hundredths
    np.testing.assert_allclose(got_sc[edge], want_sc[edge], atol=0.1)
    assert max(de_capture) < 1e-3                     # noise-free: the capture is its own noise-free rendering
