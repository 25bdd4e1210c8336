"""The motion experiment end to end on a tiny edge (closed-form renders), and its command."""
import json

import pytest

from spectracam.errors import ConfigError
from spectracam.motion.experiment import load_motion, run_motion

TINY = ("edge_size_px=[48, 32]", "speeds_px_per_ms=[0.0, 0.05, 0.2]", "samples_per_subpixel=4",
        "zone_half_width_px=12.0", "wavelengths={start_nm = 400, stop_nm = 700, step_nm = 30}")


def test_rows_have_the_fields_and_fsc_breaks_up():
    spec, scene = load_motion(TINY)
    r = run_motion(spec, scene, renderer="analytic", keep_images=False)
    assert len(r["rows"]) == 4 * 3 * 2
    for row in r["rows"]:
        for k in ("design", "speed_px_per_ms", "rolling_shutter", "breakup_width_px", "scielab_delta_e",
                  "cielab_delta_e", "snr_db"):
            assert k in row
    by = {(x["design"], x["speed_px_per_ms"], x["rolling_shutter"]): x for x in r["rows"]}
    # the field-sequential colour breaks up with speed, and more than the CFA's at the fastest
    assert by[("fsc/optimal", 0.2, False)]["breakup_width_px"] > by[("fsc/optimal", 0.0, False)]["breakup_width_px"] + 3
    assert by[("fsc/optimal", 0.2, False)]["scielab_delta_e"] > by[("cfa/single", 0.2, False)]["scielab_delta_e"]
    # FSC's SNR advantage (paper: +1 to +3 dB) and the balanced scheme's loss
    assert by[("fsc/optimal", 0.0, False)]["snr_db"] > by[("cfa/single", 0.0, False)]["snr_db"]
    assert by[("fsc/balanced", 0.0, False)]["snr_db"] < by[("cfa/single", 0.0, False)]["snr_db"]
    assert "fsc/optimal" in r["answer"]
    # the light is calibrated so the CFA needs the paper's 28 ms with the white metered to its fill
    assert by[("cfa/single", 0.0, False)]["capture_time_ms"] == pytest.approx(28.0, rel=1e-4)


def test_scored_against_the_own_still_capture():
    """Noise off: at rest a design equals its own still capture (breakup 0, S-CIELAB 0) whatever its
    demosaicking false colour, which is reported apart (the CFA's, not the planes'); moving, the
    field-sequential frames break up, the simultaneous CFA does not at 0.05 px/ms. Starting the sweep
    above 0 still scores against the still capture."""
    spec, scene = load_motion(TINY + ("noise=false", "rolling_shutter=[false]",
                                      "designs=['cfa/single', 'fsc/optimal', 'rgbw/single']"))
    r = run_motion(spec, scene, renderer="analytic", keep_images=False)
    by = {(x["design"], x["speed_px_per_ms"]): x for x in r["rows"]}
    for d in ("cfa/single", "fsc/optimal", "rgbw/single"):
        assert by[(d, 0.0)]["breakup_width_px"] == 0 and by[(d, 0.0)]["scielab_delta_e"] == 0
    assert by[("cfa/single", 0.0)]["false_colour_still"] > 20 * by[("fsc/optimal", 0.0)]["false_colour_still"]
    assert by[("cfa/single", 0.0)]["breakup_width_scene_px"] > 0  # against the scene it counts as breakup
    assert by[("fsc/optimal", 0.2)]["breakup_width_px"] > 3 > by[("cfa/single", 0.05)]["breakup_width_px"]
    moving = run_motion(spec.replace(speeds_px_per_ms=(0.2,)), scene, renderer="analytic", keep_images=False)
    assert [x["speed_px_per_ms"] for x in moving["rows"]] == [0.2] * 3
    assert moving["rows"][1]["breakup_width_px"] == by[("fsc/optimal", 0.2)]["breakup_width_px"]


def test_seeds_give_a_spread_and_an_interval():
    """With the paper's noise each noisy metric is a mean over the seeds with its spread; the crossing
    comes per seed with a 95 % interval around their mean; one seed gives no interval."""
    spec, scene = load_motion(TINY + ("rolling_shutter=[false]", "designs=['cfa/single', 'fsc/optimal']",
                                      "speeds_px_per_ms=[0.0, 0.02, 0.05, 0.1, 0.2]", "seeds=3"))
    r = run_motion(spec, scene, renderer="analytic", keep_images=False)
    for row in r["rows"]:
        assert len(row["scielab_delta_e_by_seed"]) == 3 and row["seeds"] == [0, 1, 2]
        assert row["scielab_delta_e"] == pytest.approx(sum(row["scielab_delta_e_by_seed"]) / 3)
        assert row["scielab_delta_e_sd"] > 0          # different noise, different errors
    a = r["answer"]["fsc/optimal"]["scielab"]
    assert len(a["by_seed_px_per_ms"]) == 3 and all(x is not None for x in a["by_seed_px_per_ms"])
    assert a["mean_px_per_ms"] == pytest.approx(sum(a["by_seed_px_per_ms"]) / 3)
    lo, hi = a["ci95_px_per_ms"]
    assert lo < a["mean_px_per_ms"] < hi
    one = run_motion(spec.replace(seeds=1), scene, renderer="analytic", keep_images=False)
    assert "ci95_px_per_ms" not in one["answer"]["fsc/optimal"]["scielab"]
    with pytest.raises(ConfigError, match="seeds"):
        load_motion(("seeds=0",))


def test_unknown_key_is_refused():
    with pytest.raises(ConfigError):
        load_motion(("speeds_px_per_ms=[-1]",))
    with pytest.raises(ConfigError):
        load_motion(("designs=[\"cfa/fast\"]",))


def test_command_writes_its_files(tmp_path):
    from click.testing import CliRunner

    from spectracam.motion.command import motion_cmd

    out = tmp_path / "m"
    args = ["-o", str(out), "--renderer", "analytic", "--quiet", "--set", "designs=[\"cfa/single\", \"fsc/optimal\"]",
            "--set", "rolling_shutter=[false]"] + [a for s in TINY for a in ("--set", s)]
    res = CliRunner().invoke(motion_cmd, args, catch_exceptions=False)
    assert res.exit_code == 0, res.output
    data = json.loads((out / "results.json").read_text())
    assert len(data["rows"]) == 2 * 3
    for f in ("report.md", "breakup_scielab.png", "crops.png", "fsc_frames.gif", "mtf_curves.json"):
        assert (out / f).exists()
