"""``spectracam white-balance`` (issue 33, item 3): the estimators' angular errors per sensor over ≥ 20 scene × light
cases, their statistics, and the command's refusals."""
from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from spectracam.cli import main
from spectracam.experiments.white_balance.experiment import FAMILIES, LUTHER, error_statistics, estimators
from spectracam.processing.white_balance import TRAINING_LIGHTS, WHITE_BALANCE_METHODS

#: The quick run, at 80×60 pixels so that the test stays short (the command's --quick is 160×120).
ARGS = ["--quick", "--set", "image.width=80", "--set", "image.height=60"]


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("wb") / "out"
    r = CliRunner().invoke(main, ["white-balance", "-o", str(out), *ARGS])
    assert r.exit_code == 0, r.output
    return out, r.output, json.loads((out / "results.json").read_text())


def test_quick_run_writes_its_files_and_a_line_per_sensor(quick_run):
    out, output, res = quick_run
    for name in ("results.json", "report.md", "white_balance.png", "white_balance.svg"):
        assert (out / name).stat().st_size > 0, name
    keys = [s["key"] for s in res["parameters"]["sensors"]]
    assert keys[0] == "paper" and keys[-1] == LUTHER and len(keys) >= 3
    for k in keys:
        assert f"  {k}: recovery error mean/median/p95" in output
    report = (out / "report.md").read_text()
    # the report says what the trained estimator was trained on: fluorescent and LED lights are held out for it
    assert "TRAINING_LIGHTS" in report and "held-out lights" in report and "FL2" in report
    assert all(f"{v:g} K" in report if k == "blackbody" else v in report for k, v in TRAINING_LIGHTS)
    assert res["parameters"]["sets"] == ["image.width=80", "image.height=60"] and res["parameters"]["quick"]
    assert res["command"].startswith("spectracam white-balance -o ")


def test_at_least_20_cases_per_sensor_every_estimator_but_the_oracle(quick_run):
    _, _, res = quick_run
    p = res["parameters"]
    assert set(p["estimators"]) == set(estimators()) == set(WHITE_BALANCE_METHODS.names) - {"oracle"}
    assert {x["family"] for x in p["lights"]} == set(FAMILIES)
    assert {x["label"] for x in p["lights"]} >= {"2700 K", "7500 K", "D50", "D65", "D75", "FL2", "FL7", "FL11",
                                                  "LED-B1", "LED-B3", "LED-BH1", "LED-V1"}
    assert set(p["scenes"]) == {"chart", "mondrian", "dead_leaves", "photo"}
    for s in p["sensors"]:
        mine = [c for c in res["cases"] if c["sensor"] == s["key"]]
        cases = {(c["scene"], c["light"]) for c in mine}
        assert len(cases) == p["cases_per_sensor"] == len(mine) >= 20     # one seed with --quick
        assert set(mine[0]["estimates"]) == set(p["estimators"])
    # the Sigma's curves stop at 680 nm: its scenes have a narrower grid of their own
    sigma = [s for s in p["sensors"] if s["key"].startswith("Sigma")]
    assert not sigma or sigma[0]["wavelengths_nm"] == [400.0, 680.0]
    # the trained estimator never trains on the scored colours, and its training block is recorded per scene
    for key, blocks in res["training"].items():
        assert set(blocks) == set(p["scenes"])
        assert all(b["excluded_as_scored_colours"] >= 1 and b["samples"] > 20 for b in blocks.values())


def test_statistics_equal_a_recomputation_from_the_cases(quick_run):
    _, _, res = quick_run
    for s in res["parameters"]["sensors"]:
        mine = [c for c in res["cases"] if c["sensor"] == s["key"]]
        for m in res["parameters"]["estimators"]:
            for e in ("recovery_deg", "reproduction_deg"):
                x = np.array([c["estimates"][m][e] for c in mine])
                st = res["statistics"][s["key"]][m][e]
                assert st["n"] == len(x)
                assert st["mean"] == pytest.approx(x.mean(), rel=1e-12)
                assert st["median"] == pytest.approx(np.median(x), rel=1e-12)
                assert st["p95"] == pytest.approx(np.percentile(x, 95), rel=1e-12)
                assert st["mean_spread_over_seeds"] is None          # one seed
                for f in FAMILIES:
                    want = np.mean([c["estimates"][m][e] for c in mine if c["family"] == f])
                    assert st["by_family"][f] == pytest.approx(want, rel=1e-12)
                for n in res["parameters"]["scenes"]:
                    want = np.mean([c["estimates"][m][e] for c in mine if c["scene"] == n])
                    assert st["by_scene"][n] == pytest.approx(want, rel=1e-12)


def test_the_luther_cameras_estimates_are_finite(quick_run):
    _, _, res = quick_run
    luther = [c for c in res["cases"] if c["sensor"] == LUTHER]
    assert luther
    for c in luther:
        assert np.all(np.isfinite(c["true_neutral"]))
        for m, v in c["estimates"].items():
            assert m != "oracle"
            assert np.isfinite(v["recovery_deg"]) and np.isfinite(v["reproduction_deg"]) and np.all(
                np.isfinite(v["neutral"]))
            assert 0 <= v["recovery_deg"] < 90


@pytest.mark.parametrize("value", ["0", "x", "-3", "101"])
def test_a_bad_seeds_value_is_one_clear_line(tmp_path, value):
    r = CliRunner().invoke(main, ["white-balance", "-o", str(tmp_path / "o"), "--seeds", value])
    assert r.exit_code == 2
    lines = r.output.strip().splitlines()
    assert len(lines) == 1 and "--seeds" in lines[0] and "Traceback" not in r.output
    assert not (tmp_path / "o").exists()


def test_a_bad_set_is_refused_before_any_work(tmp_path):
    r = CliRunner().invoke(main, ["white-balance", "-o", str(tmp_path / "o"), "--quick", "--set", "sensor.nosuch=1"])
    assert r.exit_code == 2 and len(r.output.strip().splitlines()) == 1 and "nosuch" in r.output
    assert not (tmp_path / "o").exists()


def test_statistics_of_a_hand_made_list():
    values = [float(v) for v in range(1, 21)]          # 1 … 20
    seeds = [0] * 10 + [1] * 10                         # seed 0: 1 … 10 (mean 5.5); seed 1: 11 … 20 (mean 15.5)
    families = ["blackbody", "LED"] * 10               # odd values / even values
    st = error_statistics(values, seeds, families, ["a"] * 5 + ["b"] * 15)
    assert st["n"] == 20 and st["mean"] == 10.5 and st["median"] == 10.5 and st["max"] == 20.0
    assert st["p95"] == pytest.approx(19.05)            # linear interpolation: 1 + 0.95·19
    assert st["per_seed_mean"] == [5.5, 15.5]
    assert st["mean_spread_over_seeds"] == pytest.approx(np.sqrt(50.0))   # sample std of (5.5, 15.5)
    assert st["by_family"] == {"blackbody": 10.0, "LED": 11.0}
    assert st["by_scene"] == {"a": 3.0, "b": 13.0}
    one = error_statistics([2.0, 4.0, 9.0], [0, 0, 0])
    assert one["median"] == 4.0 and one["mean"] == 5.0 and one["mean_spread_over_seeds"] is None
    assert one["p95"] == pytest.approx(4.0 + 0.9 * 5.0)
    from spectracam.core.errors import SpectracamError

    with pytest.raises(SpectracamError):
        error_statistics([1.0, float("nan")])
