"""The spatial experiment end to end (closed-form renders, small images) and its output contract."""
import json

import pytest
from click.testing import CliRunner

from spectracam.errors import ConfigError
from spectracam.spatial.command import spatial_cmd
from spectracam.spatial.experiment import load_spatial

SMALL = ["edge_size_px=[64, 64]", "star_size_px=[64, 64]", "chart_size_px=[96, 64]", "pixel_pitches_um=[10.0, 2.0]",
         "f_numbers=[1.4]", "wavelengths.step_nm=30", "supersampling=2"]
FIELDS = ("design", "demosaic", "misregistration_px", "pixel_pitch_um", "f_number", "target", "mtf50_cy_per_px",
          "false_colour", "scielab_delta_e", "cielab_delta_e")


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("spatial")
    args = ["-o", str(out), "--renderer", "analytic", "--no-maps", "--quiet"]
    for s in SMALL:
        args += ["--set", s]
    res = CliRunner().invoke(spatial_cmd, args, catch_exceptions=False)
    assert res.exit_code == 0, res.output
    return out, json.loads((out / "results.json").read_text())


def rows_of(results, **match):
    return [r for r in results["rows"] if all(r[k] == v for k, v in match.items())]


def test_output_contract(run):
    out, results = run
    # designs (cfa × 3 demosaickers × without/with OLPF, prism aligned/misaligned, fsc) × cases × targets
    assert len(results["rows"]) == 9 * 2 * 3
    for r in results["rows"]:
        assert all(k in r for k in FIELDS)
        assert (r["mtf50_cy_per_px"] is not None) == (r["target"] == "edge")
        assert (r["false_colour"] is None) == (r["target"] == "chart")
    for name in ("report.md", "mtf_curves.json", "mtf.png", "summary.png", "scielab_star.png", "crops_10um_f1.4.png"):
        assert (out / name).is_file(), name
    curves = json.loads((out / "mtf_curves.json").read_text())["curves"]
    assert len(curves) == 9 * 2 and all(len(c["Y"]) == len(c["frequencies_cy_per_px"]) for c in curves)
    assert "## Answer" in (out / "report.md").read_text()


def test_removing_demosaicking_sharpens_and_misregistration_colours(run):
    _, results = run
    for pitch in (10.0, 2.0):
        edge = {r["label"]: r for r in rows_of(results, target="edge", pixel_pitch_um=pitch)}
        fsc, prism = edge["fsc/optimal"], edge["prism/optimal aligned"]
        # noise-free, same exposures: the aligned prism and the field-sequential camera see the same planes
        assert prism["mtf50_cy_per_px"] == pytest.approx(fsc["mtf50_cy_per_px"], rel=1e-6)
        assert fsc["mtf50_cy_per_px"] > 1.3 * edge["cfa/single bilinear"]["mtf50_cy_per_px"]
        assert edge["prism/optimal misaligned 0.5 px"]["false_colour"] > 3 * prism["false_colour"]
        star = {r["label"]: r for r in rows_of(results, target="star", pixel_pitch_um=pitch)}
        assert star["fsc/optimal"]["scielab_delta_e_spatial"] < min(
            v["scielab_delta_e_spatial"] for k, v in star.items() if k.startswith("cfa"))


def test_olpf_trades_sharpness_for_less_false_colour(run):
    """A one-pixel 4-spot low-pass filter in front of the Bayer array: lower MTF50 on the edge, less
    false colour at the edge and less S-CIELAB error on the star (colour moiré), for every demosaicker."""
    _, results = run
    for pitch in (10.0, 2.0):
        edge = {r["label"]: r for r in rows_of(results, target="edge", pixel_pitch_um=pitch)}
        star = {r["label"]: r for r in rows_of(results, target="star", pixel_pitch_um=pitch)}
        for dm in ("bilinear", "malvar2004", "menon2007"):
            plain, olpf = f"cfa/single {dm}", f"cfa/single {dm} OLPF 1 px"
            assert edge[olpf]["olpf_separation_px"] == 1.0 and edge[plain]["olpf_separation_px"] == 0.0
            assert edge[olpf]["mtf50_cy_per_px"] < edge[plain]["mtf50_cy_per_px"], (pitch, dm)
            assert edge[olpf]["false_colour"] < edge[plain]["false_colour"], (pitch, dm)
            assert star[olpf]["false_colour"] < star[plain]["false_colour"], (pitch, dm)


def test_bad_settings_are_one_config_error():
    with pytest.raises(ConfigError, match="demosaics"):
        load_spatial(["demosaics=['patch']"])
    with pytest.raises(ConfigError, match="none of them takes rgbw/single"):
        load_spatial(["designs=['rgbw/single']", "demosaics=['menon2007']"])
    with pytest.raises(ConfigError, match="olpf_separations_px"):
        load_spatial(["olpf_separations_px=[9]"])
    with pytest.raises(ConfigError, match="designs"):
        load_spatial(["designs=['bayer']"])
    with pytest.raises(ConfigError, match="unknown key"):
        load_spatial(["pitch=3"])
    with pytest.raises(ConfigError, match="unknown table"):
        load_spatial(["image.width=3"])
    spec, scene = load_spatial(["sensor.fill_factor=0.5", "f_numbers=[2.8]"], quick=True)
    assert scene.camera.sensor.fill_factor == 0.5 and spec.f_numbers == (2.8,) and len(scene.grid) == 15
