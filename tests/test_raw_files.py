"""raw.exr and raw.dng: written, read back by independent readers, and the capture command."""
import json
import subprocess
import sys

import numpy as np
import pytest

from spectracam import ChartReference, capture
from spectracam.camera import CameraSpec
from spectracam.errors import ConfigError
from spectracam.io.dng import write_dng, xyz_to_camera_matrix
from spectracam.io.exr import read_exr, read_raw_exr, write_radiance_exr, write_raw_exr
from spectracam.scene import parse_scene

parse_camera = CameraSpec.from_dict


@pytest.fixture(scope="module")
def cfa_raw(scene_5000, analytic_5000):
    return capture(analytic_5000, seed=4, scene=scene_5000)


def test_raw_exr_round_trip_cfa_and_fsc(tmp_path, cfa_raw, scene_5000, analytic_5000):
    write_raw_exr(tmp_path / "cfa.exr", cfa_raw)
    back = read_raw_exr(tmp_path / "cfa.exr")
    np.testing.assert_array_equal(back.digital, cfa_raw.digital)
    assert back.layout == cfa_raw.layout and back.camera == cfa_raw.camera and back.seed == 4
    np.testing.assert_array_equal(back.exposure_times_s, cfa_raw.exposure_times_s)
    channels, attrs = read_exr(tmp_path / "cfa.exr")
    assert list(channels) == ["Y"] and attrs["spectracamCfaPattern"] == "RGGB"
    fsc = capture(analytic_5000, design="fsc/balanced", seed=4, scene=scene_5000)
    write_raw_exr(tmp_path / "fsc.exr", fsc)
    channels, attrs = read_exr(tmp_path / "fsc.exr")
    assert sorted(channels) == ["B", "G", "R"] and "sequence" in attrs["spectracamFrames"]
    assert json.loads(attrs["spectracamCaptureTimeS"]) == pytest.approx(cfa_raw.capture_time_s)


def test_dng_reads_back_in_libraw(tmp_path, cfa_raw, scene_5000):
    rawpy = pytest.importorskip("rawpy")
    colour = pytest.importorskip("colour")
    reference = ChartReference.of(scene_5000)
    write_dng(tmp_path / "raw.dng", cfa_raw, reference)
    with rawpy.imread(str(tmp_path / "raw.dng")) as r:
        np.testing.assert_array_equal(r.raw_image, cfa_raw.digital.astype(np.uint16))
        assert r.color_desc == b"RGBG" and r.raw_pattern.tolist() == [[0, 1], [3, 2]]
        assert r.white_level == 255 and list(r.black_level_per_channel) == [0, 0, 0, 0]
        # LibRaw derives its camera→sRGB matrix from our ColorMatrix1 (DNG spec, chapter 6)
        M = xyz_to_camera_matrix(cfa_raw, reference)
        cam_rgb = M @ np.asarray(colour.RGB_COLOURSPACES["sRGB"].matrix_RGB_to_XYZ)
        cam_rgb /= cam_rgb.sum(axis=1, keepdims=True)
        np.testing.assert_allclose(r.color_matrix[:, :3], np.linalg.inv(cam_rgb), atol=2e-3)
        assert r.postprocess().shape == (120, 160, 3)


@pytest.mark.parametrize("pattern, desc", [("GRBG", [[1, 0], [2, 3]]), ("BGGR", [[2, 3], [1, 0]])])
def test_dng_patterns(tmp_path, pattern, desc, scene_5000, analytic_5000):
    rawpy = pytest.importorskip("rawpy")
    raw = capture(analytic_5000, camera=parse_camera({"capture": {"cfa_pattern": pattern}}), scene=scene_5000)
    write_dng(tmp_path / "p.dng", raw, ChartReference.of(scene_5000))
    with rawpy.imread(str(tmp_path / "p.dng")) as r:
        # LibRaw numbers the second green 3: check the colour at each position instead
        names = [[r.color_desc.decode()[c] for c in row] for row in r.raw_pattern.tolist()]
        assert "".join(sum(names, [])) == pattern


def test_camera_tables_validate():
    with pytest.raises(ConfigError, match=r"sensor.adc_bits = 0: must be an integer between 1 and 24"):
        parse_camera({"sensor": {"adc_bits": 0}})
    with pytest.raises(ConfigError, match=r"filters.cutoffs_nm = \[610, 490\]: .*increasing"):
        parse_camera({"filters": {"cutoffs_nm": [610, 490]}})
    with pytest.raises(ConfigError, match=r"sensor.fpn = 'yes': must be true or false"):
        parse_camera({"sensor": {"fpn": "yes"}})
    with pytest.raises(ConfigError, match=r"capture.exposure = 'optimal'.*cfa"):
        parse_scene({"capture": {"exposure": "optimal"}})
    base = parse_camera({"sensor": {"read_noise_e": 5}})
    cam = parse_camera({"optics": {"f_number": 2.8}}, base=base)
    assert cam.sensor.read_noise_e == 5 and cam.optics.f_number == 2.8


def test_capture_command(tmp_path, scene_5000, mitsuba_5000):
    write_radiance_exr(tmp_path / "radiance.exr", mitsuba_5000)
    cfg = tmp_path / "cam.toml"
    cfg.write_text("[sensor]\nadc_bits = 10\n[capture]\narchitecture = 'prism'\nexposure = 'optimal'\n")
    run = lambda *a: subprocess.run([sys.executable, "-m", "spectracam", *a], capture_output=True, text=True)
    r = run("capture", str(tmp_path / "radiance.exr"), "-o", str(tmp_path / "cfa"))
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "cfa" / "raw.dng").exists()
    r = run("capture", str(tmp_path / "radiance.exr"), "-o", str(tmp_path / "prism"), "--config", str(cfg))
    assert r.returncode == 0, r.stderr
    raw = read_raw_exr(tmp_path / "prism" / "raw.exr")
    assert raw.design == "prism/optimal" and raw.camera.sensor.adc_bits == 10 and raw.digital.max() <= 1023
    assert raw.capture_time_s == pytest.approx(raw.exposure_times_s.max())
    r = run("capture", str(tmp_path / "radiance.exr"), "-o", str(tmp_path / "bad"), "--exposure", "balanced")
    assert r.returncode == 2 and "capture.exposure = 'balanced'" in r.stderr and not (tmp_path / "bad").exists()
