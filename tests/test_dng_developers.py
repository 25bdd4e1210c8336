"""raw.dng in the raw developers other than LibRaw: darktable (darktable-cli) and RawTherapee (rawtherapee-cli),
when installed (skipped with the reason otherwise).  ``tools/dng_developers.py`` measures the default camera in
all three; these check, fast, what the file must make them do: no cast, the pedestal subtracted once, the same
output from run to run."""
import os
import shutil
import subprocess

import numpy as np
import pytest
from conftest import small_scene

from spectracam import ChartReference, capture
from spectracam.io.dng import write_dng
from spectracam.core.cielab import xyz_to_lab

GREYS = slice(19, 24)  # greys 20-24 (1-based; 0-based 19-23): 8, 6.5, 5, 3.5 and the black


def needs(exe):
    if shutil.which(exe) is None:
        pytest.skip(f"{exe} is not installed (apt install {exe.split('-')[0]}): not tested here")


@pytest.fixture(scope="module")
def scene_3000():
    return small_scene(illuminant={"temperature_K": 3000})


def capture_file(path, scene, design):
    """A noise-free capture with a 12-bit ADC and a 128-DN pedestal — as large a share of the range as the
    default 8-bit camera's 8 DN, so a pedestal developed as signal shows as it does there, without the 8-bit
    ADC's quantisation of the dark greys — written as DNG; ``(raw, reference)``."""
    from spectracam.render import render

    sensor = scene.camera.sensor.replace(adc_bits=12, black_level_DN=128.0).off("shot_noise", "read_noise", "fpn",
                                                                                "dark_current")
    raw = capture(render(scene, "analytic"), design=design, seed=0, scene=scene, sensor=sensor)
    ref = ChartReference.of(scene)
    write_dng(path, raw, ref)
    return raw, ref


def lab_of(rgb, ref):
    """CIELAB (against D65) of each patch's mean linear sRGB, scaled so greys 20-23 have the scene's Y; the
    boxes follow a centred crop (RawTherapee crops a mosaic)."""
    import colour

    M = np.asarray(colour.RGB_COLOURSPACES["sRGB"].matrix_RGB_to_XYZ)
    dy, dx = (ref.height_px - rgb.shape[0]) // 2, (ref.width_px - rgb.shape[1]) // 2
    xyz = np.stack([rgb[r.start - dy:r.stop - dy, c.start - dx:c.stop - dx].reshape(-1, 3).mean(axis=0)
                    for r, c in ref.boxes]) @ M.T
    xyz *= ref.patch_xyz[19:23, 1].sum() / xyz[19:23, 1].sum()
    return xyz_to_lab(xyz, M.sum(axis=1))


def darktable(dng, out, mode, tmp_path):
    """darktable-cli with a fresh config directory and an in-memory library (else runs are not independent),
    no exposure/filmic/base curve (workflow none), the given chromatic adaptation, linear Rec.709 16-bit TIFF."""
    import tifffile

    config = tmp_path / f"config-{out.stem}"
    r = subprocess.run(["darktable-cli", str(dng), str(out), "--icc-type", "LIN_REC709", "--apply-custom-presets",
                        "false", "--core", "--configdir", str(config), "--library", ":memory:",
                        "--conf", "plugins/imageio/format/tiff/bpp=16", "--conf", "plugins/darkroom/workflow=none",
                        "--conf", f"plugins/darkroom/chromatic-adaptation={mode}"], capture_output=True, text=True)
    assert r.returncode == 0 and out.exists(), r.stdout + r.stderr
    return tifffile.imread(out).astype(np.float64) / 65535.0


def libraw(dng):
    rawpy = pytest.importorskip("rawpy")
    with rawpy.imread(str(dng)) as r:
        return r.postprocess(use_camera_wb=True, no_auto_bright=True, output_bps=16, gamma=(1, 1), user_flip=0,
                             output_color=rawpy.ColorSpace.sRGB) / 65535.0


@pytest.mark.parametrize("design", ["prism/single", "cfa/single"])
def test_darktable_develops_without_cast_and_repeatably(tmp_path, scene_3000, design):
    """darktable 4.2 at 3000 K.  Prism (LinearRaw): darktable does not subtract a LinearRaw BlackLevel, so
    the file holds the pixels less the pedestal; before, the pedestal developed as a blue cast growing toward
    the black (this file: a* +2.8…+11.3, b* −9.7…−29 on greys 20-24, the black at L* 32.6 for 20.8) and,
    with ColorMatrix1 only and CalibrationIlluminant1 255, the modern chromatic adaptation had no matrix at
    all (a* ±90).  CFA: the pedestal stays in the pixels and BlackLevel, which darktable subtracts.  Now
    (measured): greys 20-24 within 0.7 a*, 1.1 b* of the scene (legacy) and 0.5, 0.7 (modern); the black's
    L* within 0.05; legacy equal to LibRaw's development within 0.02; two runs identical."""
    needs("darktable-cli")
    dng = tmp_path / "raw.dng"
    raw, ref = capture_file(dng, scene_3000, design)
    truth = xyz_to_lab(ref.patch_xyz, ref.white_xyz)
    first = darktable(dng, tmp_path / "legacy1.tif", "legacy", tmp_path)
    second = darktable(dng, tmp_path / "legacy2.tif", "legacy", tmp_path)
    np.testing.assert_array_equal(first, second)  # a fresh config each: the same output
    modern = darktable(dng, tmp_path / "modern.tif", "modern", tmp_path)
    for rgb in (first, modern):
        lab = lab_of(rgb, ref)
        assert np.abs(lab[GREYS, 1:] - truth[GREYS, 1:]).max() <= 2.0, (lab[GREYS], truth[GREYS])
        assert abs(lab[23, 0] - truth[23, 0]) <= 0.5, (lab[23], truth[23])  # the pedestal subtracted, once
    # legacy chromatic adaptation white-balances with AsShotNeutral and converts with ColorMatrix2, as LibRaw
    np.testing.assert_allclose(lab_of(first, ref)[GREYS], lab_of(libraw(dng), ref)[GREYS], atol=0.1)


def test_rawtherapee_develops_linear_raw_without_cast(tmp_path, scene_3000):
    """RawTherapee 5.9 (neutral profile: camera white balance, camera-standard matrix, sRGB output) on the
    prism file: greys 20-24 within 2 of the scene, the black's L* within 0.5 (measured: as LibRaw, within
    0.02).  A LinearRaw file: RawTherapee 5.9 refuses ("Error loading file") CFA DNGs this small (160×120 …
    256×120 px; 256×192 and larger load)."""
    needs("rawtherapee-cli")
    import colour
    import tifffile

    dng = tmp_path / "raw.dng"
    raw, ref = capture_file(dng, scene_3000, "prism/single")
    out = tmp_path / "rt.tif"
    r = subprocess.run(["rawtherapee-cli", "-o", str(out), "-t", "-b16", "-Y", "-c", str(dng)], capture_output=True,
                       text=True, env={**os.environ, "HOME": str(tmp_path)})
    assert r.returncode == 0 and out.exists(), r.stdout + r.stderr
    lab = lab_of(colour.models.eotf_sRGB(tifffile.imread(out) / 65535.0), ref)
    truth = xyz_to_lab(ref.patch_xyz, ref.white_xyz)
    assert np.abs(lab[GREYS, 1:] - truth[GREYS, 1:]).max() <= 2.0, (lab[GREYS], truth[GREYS])
    assert abs(lab[23, 0] - truth[23, 0]) <= 0.5, (lab[23], truth[23])
    np.testing.assert_allclose(lab[GREYS], lab_of(libraw(dng), ref)[GREYS], atol=0.1)
