"""The motion experiment end to end on a tiny edge (closed-form renders), and its command."""
import dataclasses
import json

import numpy as np
import pytest

from spectracam.core.errors import ConfigError
from spectracam.experiments.motion.experiment import MotionRow, load_motion, run_motion

TINY = ("edge_size_px=[48, 32]", "speeds_px_per_ms=[0.0, 0.05, 0.2]", "samples_per_subpixel=4",
        "zone_half_width_px=12.0", "wavelengths={start_nm = 400, stop_nm = 700, step_nm = 30}")


#: The keys of a row of results.json, in order: what readers of the file rely on.
ROW_KEYS = ["design", "speed_px_per_ms", "speed_mm_per_s", "rolling_shutter", "breakup_width_px", "max_added_chroma",
            "breakup_width_scene_px", "false_colour_still", "channel_edge_shift_px", "edge_blur_px",
            "breakup_threshold_width_px", "breakup_threshold_width_scene_px", "scielab_delta_e", "cielab_delta_e",
            "scielab_delta_e_scene", "cielab_delta_e_scene", "mtf50_cy_per_px", "scielab_delta_e_sd",
            "cielab_delta_e_sd", "scielab_delta_e_scene_sd", "cielab_delta_e_scene_sd", "mtf50_cy_per_px_sd",
            "scielab_delta_e_by_seed", "seeds", "snr_db", "blur_px", "capture_time_ms", "exposure_ms", "slices",
            "slice_dt_ms", "samples_per_slice"]


def test_rows_have_the_fields_and_fsc_breaks_up():
    spec, scene = load_motion(TINY)
    r = run_motion(spec, scene, renderer="analytic", keep_images=False)
    assert len(r["rows"]) == 4 * 3 * 2
    row = r["rows"][0]
    assert isinstance(row, MotionRow) and list(row.to_dict()) == ROW_KEYS
    assert isinstance(row.to_dict()["seeds"], list) and row.to_dict()["exposure_ms"] == list(row.exposure_ms)
    with pytest.raises(dataclasses.FrozenInstanceError):
        row.scielab_delta_e = 0.0          # rows are results: frozen
    with pytest.raises(TypeError):
        row["scielab_delta_e"] = 0.0
    by = {(x.design, x.speed_px_per_ms, x.rolling_shutter): x for x in r["rows"]}
    # the field-sequential colour breaks up with speed, and more than the CFA's at the fastest
    assert by[("fsc/optimal", 0.2, False)].breakup_width_px > by[("fsc/optimal", 0.0, False)].breakup_width_px + 3
    assert by[("fsc/optimal", 0.2, False)].scielab_delta_e > by[("cfa/single", 0.2, False)].scielab_delta_e
    # FSC's SNR advantage (paper: +1 to +3 dB) and the balanced scheme's loss
    assert by[("fsc/optimal", 0.0, False)].snr_db > by[("cfa/single", 0.0, False)].snr_db
    assert by[("fsc/balanced", 0.0, False)].snr_db < by[("cfa/single", 0.0, False)].snr_db
    assert "fsc/optimal" in r["answer"]
    # the light is calibrated so the CFA needs the paper's 28 ms with the white metered to its fill
    assert by[("cfa/single", 0.0, False)].capture_time_ms == pytest.approx(28.0, rel=1e-4)


def test_scored_against_the_own_still_capture():
    """Noise off: at rest a design equals its own still capture (breakup 0, S-CIELAB 0, its error map 0)
    whatever its demosaicking false colour, which is reported apart (the CFA's, not the planes'); moving,
    the field-sequential frames break up, the simultaneous CFA does not at 0.05 px/ms. Starting the
    sweep above 0 still scores against the still capture."""
    spec, scene = load_motion(TINY + ("noise=false", "rolling_shutter=[false]",
                                      "designs=['cfa/single', 'fsc/optimal', 'rgbw/single']"))
    r = run_motion(spec, scene, renderer="analytic")
    by = {(x.design, x.speed_px_per_ms): x for x in r["rows"]}
    for d in ("cfa/single", "fsc/optimal", "rgbw/single"):
        assert by[(d, 0.0)].breakup_width_px == 0 and by[(d, 0.0)].scielab_delta_e == 0
        still_map = r["images"][(d, 0.0, False)]["scielab"]
        assert np.nanmax(still_map) < 1e-9 and np.isfinite(still_map).sum() == (32 - 8) * (48 - 8)
    fast = r["images"][("fsc/optimal", 0.2, False)]
    assert np.nanmax(fast["scielab"]) > 5     # the breakup shows in the map, inside the zone scored
    assert np.nanmean(fast["scielab"][fast["zone"]]) == pytest.approx(by[("fsc/optimal", 0.2)].scielab_delta_e)
    assert by[("cfa/single", 0.0)].false_colour_still > 20 * by[("fsc/optimal", 0.0)].false_colour_still
    assert by[("cfa/single", 0.0)].breakup_width_scene_px > 0  # against the scene it counts as breakup
    assert by[("fsc/optimal", 0.2)].breakup_width_px > 3 > by[("cfa/single", 0.05)].breakup_width_px
    moving = run_motion(spec.replace(speeds_px_per_ms=(0.2,)), scene, renderer="analytic", keep_images=False)
    assert [x.speed_px_per_ms for x in moving["rows"]] == [0.2] * 3
    assert moving["rows"][1].breakup_width_px == by[("fsc/optimal", 0.2)].breakup_width_px


def test_esfr_is_the_standard_unless_asked():
    """MTF50 is ISO 12233:2017's e-SFR by default; the binning correction, asked for, raises it (a sharp
    still edge: by about 2 %), and the choice is recorded with the parameters."""
    spec, scene = load_motion(("edge_size_px=[96, 48]", "samples_per_subpixel=4", "zone_half_width_px=12.0",
                               "wavelengths={start_nm = 400, stop_nm = 700, step_nm = 30}", "noise=false",
                               "rolling_shutter=[false]", "designs=['prism/optimal']", "speeds_px_per_ms=[0.0, 0.05]"))
    assert spec.esfr_correct_binning is False
    standard = run_motion(spec, scene, renderer="analytic", keep_images=False)
    corrected = run_motion(spec.replace(esfr_correct_binning=True), scene, renderer="analytic", keep_images=False)
    assert standard["parameters"]["motion"]["esfr_correct_binning"] is False
    assert corrected["parameters"]["motion"]["esfr_correct_binning"] is True
    ratio = [c.mtf50_cy_per_px / s.mtf50_cy_per_px for s, c in zip(standard["rows"], corrected["rows"])]
    assert all(x > 1.002 for x in ratio)
    assert 1.01 < ratio[0] < 1.03                         # at rest
    for bad in ("1", "'yes'"):
        with pytest.raises(ConfigError, match="esfr_correct_binning"):
            load_motion((f"esfr_correct_binning={bad}",))


def test_seeds_give_a_spread_and_an_interval():
    """With the paper's noise each noisy metric is a mean over the seeds with its spread; the crossing
    comes per seed with a 95 % interval around their mean; one seed gives no interval."""
    spec, scene = load_motion(TINY + ("rolling_shutter=[false]", "designs=['cfa/single', 'fsc/optimal']",
                                      "speeds_px_per_ms=[0.0, 0.02, 0.05, 0.1, 0.2]", "seeds=3"))
    r = run_motion(spec, scene, renderer="analytic", keep_images=False)
    for row in r["rows"]:
        assert len(row.scielab_delta_e_by_seed) == 3 and row.seeds == (0, 1, 2)
        assert row.scielab_delta_e == pytest.approx(sum(row.scielab_delta_e_by_seed) / 3)
        assert row.scielab_delta_e_sd > 0          # different noise, different errors
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
    """The figures, results.json with the rows' keys, and every case's displayed image (linear EXR read back
    by OpenImageIO, with the parameters that made it in its header; sRGB PNG) and one map figure per speed."""
    from click.testing import CliRunner
    from PIL import Image

    from spectracam.experiments.motion.command import motion_cmd

    out = tmp_path / "m"
    args = ["-o", str(out), "--renderer", "analytic", "--quiet", "--set", "designs=[\"cfa/single\", \"fsc/optimal\"]",
            "--set", "rolling_shutter=[false]"] + [a for s in TINY for a in ("--set", s)]
    res = CliRunner().invoke(motion_cmd, args, catch_exceptions=False)
    assert res.exit_code == 0, res.output
    data = json.loads((out / "results.json").read_text())
    assert len(data["rows"]) == 2 * 3 and all(list(r) == ROW_KEYS for r in data["rows"])
    for f in ("report.md", "breakup_scielab.png", "crops.png", "fsc_frames.gif", "mtf_curves.json"):
        assert (out / f).exists()
    assert sorted(p.name for p in (out / "images").glob("*.exr")) == sorted(
        f"{d}_{v}px-per-ms_global.exr" for d in ("cfa-single", "fsc-optimal") for v in ("0", "0.05", "0.2"))
    assert len(list((out / "images").glob("*.png"))) == 6
    assert sorted(p.name for p in (out / "maps").iterdir()) == sorted(f"scielab_{v}px-per-ms.png"
                                                                      for v in ("0", "0.05", "0.2"))
    assert "maps/scielab_0.2px-per-ms.png" in data["figures"]
    oiio = pytest.importorskip("OpenImageIO")
    img = oiio.ImageInput.open(str(out / "images" / "fsc-optimal_0.2px-per-ms_global.exr"))
    spec = img.spec()
    pixels = img.read_image(0, 0, 0, 3, "float")
    img.close()
    assert (spec.height, spec.width, spec.nchannels) == (32, 48, 3) and pixels.shape == (32, 48, 3)
    params = json.loads(spec.getattribute("spectracamParameters"))
    assert params["case"]["design"] == "fsc/optimal" and params["case"]["speed_px_per_ms"] == 0.2
    assert params["motion"]["edge_size_px"] == [48, 32] and params["motion"]["esfr_correct_binning"] is False
    assert params["seed"] == spec.getattribute("spectracamSeed") == 0
    # the displayed image in display RGB, white = 1: the 4:1 neutrals (N 6.5 and N 3.5) either side of the edge
    bright, dark = np.median(pixels[:, -8:], axis=(0, 1)), np.median(pixels[:, :8], axis=(0, 1))
    assert np.all((0.25 < bright) & (bright < 0.45)) and 3.0 < bright.mean() / dark.mean() < 5.0
    with Image.open(out / "images" / "fsc-optimal_0.2px-per-ms_global.png") as png:
        assert png.size == (48, 32)


def test_no_images_skips_the_case_files_and_keeps_the_rest(tmp_path):
    """``--no-images`` (issue 38): figures, results.json (the same rows) and report.md, no images/ or maps/."""
    from click.testing import CliRunner

    from spectracam.experiments.motion.command import motion_cmd

    out = tmp_path / "m"
    args = ["-o", str(out), "--renderer", "analytic", "--quiet", "--no-images", "--set",
            "designs=[\"cfa/single\", \"fsc/optimal\"]", "--set", "rolling_shutter=[false]"] \
        + [a for s in TINY for a in ("--set", s)]
    res = CliRunner().invoke(motion_cmd, args, catch_exceptions=False)
    assert res.exit_code == 0, res.output
    data = json.loads((out / "results.json").read_text())
    assert len(data["rows"]) == 2 * 3 and all(list(r) == ROW_KEYS for r in data["rows"])
    assert data["command"].endswith("--no-images") and "case_images_written" not in data
    for f in ("report.md", "breakup_scielab.png", "crops.png", "fsc_frames.gif", "mtf_curves.json"):
        assert (out / f).exists()
    assert not (out / "images").exists() and not (out / "maps").exists()
    assert data["case_files"]["images"] == 0 and not any(f.startswith("maps/") for f in data["figures"])
    assert "images/<design>" not in (out / "report.md").read_text()
