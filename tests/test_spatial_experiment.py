"""The spatial experiment end to end (closed-form renders, small images) and its output contract."""
import json

import numpy as np

import pytest
from click.testing import CliRunner

from spectracam.core.errors import ConfigError
from spectracam.experiments.spatial.command import spatial_cmd
from spectracam.experiments.spatial.experiment import load_spatial

SMALL = ["edge_size_px=[64, 64]", "star_size_px=[64, 64]", "chart_size_px=[96, 64]", "zone_plate_size_px=[64, 64]",
         "pixel_pitches_um=[10.0, 2.0]", "f_numbers=[1.4]", "wavelengths.step_nm=30", "supersampling=2"]
NEUTRAL = ("edge", "zone_plate", "star")
EDGES = ("edge", "edge_red_cyan", "edge_blue_yellow", "edge_skin", "edge_foliage_sky")
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
    # designs (cfa × 3 demosaickers × without/with OLPF, prism aligned/misaligned, fsc) × cases × 9 targets
    assert len(results["rows"]) == 9 * 2 * 9
    assert results["parameters"]["spatial"]["esfr_correct_binning"] is False   # ISO 12233:2017 as stated
    for r in results["rows"]:
        assert all(k in r for k in FIELDS)
        # every slanted edge, neutral or coloured, has a finite MTF50 and a colour error at the edge
        assert (r["mtf50_cy_per_px"] is not None) == (r["target"] in EDGES), r
        assert (r["edge_delta_e"] is not None) == (r["target"] in EDGES), r
        assert (r["false_colour"] is not None) == (r["target"] in NEUTRAL), r
        assert (r["aliasing_delta_e"] is not None) == r["target"].startswith("zone_plate"), r
        assert r["seeds"] == 1 and not any(k.endswith("_ci95") for k in r)   # noise off: one deterministic capture
    for name in ("report.md", "mtf_curves.json", "mtf.png", "summary.png", "scielab_star.png", "scielab_zone_plate.png",
                 "scielab_edge_red_cyan.png", "crops_10um_f1.4.png"):
        assert (out / name).is_file(), name
    assert not (out / "cases").exists()   # --no-maps
    data = json.loads((out / "mtf_curves.json").read_text())
    curves = data["curves"]
    assert len(curves) == 9 * 2 * len(EDGES) and all(len(c["Y"]) == len(c["frequencies_cy_per_px"]) for c in curves)
    assert {"G", "Y", "G OLPF 1 px", "Y OLPF 1 px"} <= set(data["closed_form"]["10um_f1.4"])
    report = (out / "report.md").read_text()
    assert "## Answer" in report
    for name in ("mtf.png", "summary.png", "scielab_star.png", "crops_10um_f1.4.png"):   # every figure shown once
        assert report.count(f"]({name})") == 1, name


def test_sampling_colour_is_zero_without_a_mosaic_and_large_with_one(run):
    """Against the optics reference (every channel at every pixel through the same lens), the noise-free
    field-sequential camera and the aligned prism make no colour at a coloured edge; every demosaicker does."""
    _, results = run
    for t in EDGES:
        for pitch in (10.0, 2.0):
            row = {r["label"]: r for r in rows_of(results, target=t, pixel_pitch_um=pitch)}
            assert row["fsc/optimal"]["edge_delta_e"] < 1e-3 and row["prism/optimal aligned"]["edge_delta_e"] < 1e-3
            assert row["prism/optimal misaligned 0.5 px"]["edge_delta_e"] > 0.3, (t, pitch)
            for dm in ("bilinear", "malvar2004", "menon2007"):
                assert row[f"cfa/single {dm}"]["edge_delta_e"] > 0.5, (t, pitch, dm)


def test_aliasing_counts_against_the_nyquist_reference(run):
    """The zone plate above the Nyquist radius: a camera without a low-pass filter aliases (the
    band-limited reference is flat there), the Bayer array most; an OLPF cuts the CFA's aliasing."""
    _, results = run
    for t in ("zone_plate", "zone_plate_chroma"):
        for pitch in (10.0, 2.0):
            row = {r["label"]: r for r in rows_of(results, target=t, pixel_pitch_um=pitch)}
            assert row["fsc/optimal"]["aliasing_delta_e"] > 0.05, (t, pitch)
            for dm in ("bilinear", "malvar2004", "menon2007"):
                plain, olpf = row[f"cfa/single {dm}"], row[f"cfa/single {dm} OLPF 1 px"]
                assert plain["aliasing_delta_e"] > 2 * row["fsc/optimal"]["aliasing_delta_e"], (t, pitch, dm)
                assert olpf["aliasing_delta_e"] < plain["aliasing_delta_e"], (t, pitch, dm)


def test_footprint_reference_hides_aliasing_the_nyquist_reference_shows():
    from spectracam.experiments.spatial.experiment import load_spatial, run_spatial

    base = SMALL + ["pixel_pitches_um=[10.0]", "targets=['zone_plate']", "designs=['fsc/optimal']"]
    out = {}
    for ref in ("nyquist", "footprint"):
        spec, scene = load_spatial(base + [f"reference='{ref}'"])
        out[ref] = run_spatial(spec, scene, renderer="analytic", keep_images=False)["rows"][0]
    # the box footprint aliases exactly as the sensor does: against it, the sensor's own aliasing is invisible
    assert out["nyquist"].aliasing_delta_e > 3 * out["footprint"].aliasing_delta_e


def test_standard_esfr_reads_lower_than_the_binning_corrected_one():
    from spectracam.experiments.spatial.experiment import load_spatial, run_spatial

    base = SMALL + ["pixel_pitches_um=[10.0]", "targets=['edge']", "designs=['fsc/optimal']"]
    m = {}
    for corr in (False, True):
        spec, scene = load_spatial(base + [f"esfr_correct_binning={str(corr).lower()}"])
        m[corr] = run_spatial(spec, scene, renderer="analytic", keep_images=False)["rows"][0].mtf50_cy_per_px
    assert 1.005 < m[True] / m[False] < 1.04, m   # the binning's sinc(f·Δ) loss at MTF50 ≈ 0.5 cy/px: ~2 %


def test_noise_seeds_give_a_mean_with_its_interval():
    from spectracam.experiments.spatial.experiment import load_spatial, run_spatial
    from spectracam.experiments.spatial.score import SpatialRow

    spec, scene = load_spatial(SMALL + ["pixel_pitches_um=[10.0]", "targets=['edge']", "noise=true", "seeds=3",
                                        "designs=['fsc/optimal']"])
    row = run_spatial(spec, scene, renderer="analytic", keep_images=False)["rows"][0]
    assert isinstance(row, SpatialRow) and row.seeds == 3
    for key in ("scielab_delta_e_spatial", "false_colour", "mtf50_cy_per_px"):
        lo, hi = row.interval95[key]
        vals = row.by_seed[key]
        assert len(vals) == 3 and len(set(vals)) == 3, key          # three different noise draws
        assert lo < getattr(row, key) < hi and getattr(row, key) == pytest.approx(sum(vals) / 3)
    assert row.false_colour > 0.2   # noise chroma the noise-free field-sequential camera does not have (0.08)
    with pytest.raises(Exception):
        row.target = "star"          # rows are frozen


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


def test_every_case_is_written_as_exr_png_and_error_map(tmp_path):
    """cases/<pitch>um_f<N>/<target>/: each design's displayed image as linear EXR (read back by
    OpenImageIO, with the parameters that made it) and sRGB PNG, the reference's too, and an error map
    whose colour bar is drawn beside it on the target's own scale."""
    oiio = pytest.importorskip("OpenImageIO")
    from PIL import Image

    args = ["-o", str(tmp_path), "--renderer", "analytic", "--quiet"]
    for s in SMALL + ["pixel_pitches_um=[10.0]", "targets=['edge', 'zone_plate']", "demosaics=['bilinear']",
                      "olpf_separations_px=[0]", "misregistrations_px=[0]", "designs=['cfa/single', 'fsc/optimal']"]:
        args += ["--set", s]
    res = CliRunner().invoke(spatial_cmd, args, catch_exceptions=False)
    assert res.exit_code == 0, res.output
    folder = tmp_path / "cases" / "10um_f1.4" / "zone_plate"
    assert sorted(p.name for p in folder.iterdir()) == sorted(
        ["cfa-single_bilinear.exr", "cfa-single_bilinear.png", "cfa-single_bilinear_error.png", "fsc-optimal.exr",
         "fsc-optimal.png", "fsc-optimal_error.png", "reference.exr", "reference.png"])
    inp = oiio.ImageInput.open(str(folder / "fsc-optimal.exr"))
    spec = inp.spec()
    pixels = inp.read_image("float")
    inp.close()
    assert pixels.shape == (64, 64, 3) and np.isfinite(pixels).all() and 0.05 < pixels.mean() < 1.0
    params = json.loads(spec.getattribute("spectracamParameters"))
    assert params["case"] == {"pixel_pitch_um": 10.0, "f_number": 1.4, "target": "zone_plate", "design": "fsc/optimal"}
    assert params["spatial"]["targets"] == ["edge", "zone_plate"] and params["command"].startswith("spectracam spatial")
    png = np.asarray(Image.open(folder / "fsc-optimal.png"))
    assert png.shape[:2] == (64, 64) and png.dtype == np.uint8 and (png[..., 3:] == 255).all()   # RGB(A), opaque
    err = np.asarray(Image.open(folder / "cfa-single_bilinear_error.png"))
    assert err.shape[1] > err.shape[0] >= 256          # the map enlarged to ≥ 256 px and its colour bar beside it
    scales = json.loads((tmp_path / "cases" / "scales.json").read_text())["vmax_delta_e_by_target"]
    assert set(scales) == {"edge", "zone_plate"} and all(v > 0 for v in scales.values())
