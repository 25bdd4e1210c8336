"""The read-outs (issue 36, item 2) through every architecture: what each records decodes to the charge it was
exposed to, the exposure uses the read-out's range, the capture lasts as long as its frames, the raw EXR carries the
merged word back, and the DNG says in one line why it cannot."""
import numpy as np
import pytest

from spectracam.core.errors import SpectracamError
from spectracam.sensor import READOUT_NAMES, adc_inverse

DESIGNS = ("cfa/single", "prism/optimal", "fsc/optimal", "rgbw/single", "stacked/single")


@pytest.fixture(scope="module")
def scene_cube():
    from spectracam.pipeline import render
    from spectracam.pipeline.scene_file import load_scene

    scene = load_scene("scenes/d65.toml", ["image.width=96", "image.height=72", "sensor.adc_bits=12"])
    return scene, render(scene, "analytic")


def _camera(scene, design, readout, **sensor):
    cam = scene.camera.with_design(design)
    return cam.replace(sensor=cam.sensor.replace(readout=readout, **sensor))


@pytest.mark.parametrize("design", DESIGNS)
@pytest.mark.parametrize("readout", READOUT_NAMES)
def test_every_read_out_decodes_to_the_charge_it_was_exposed_to(scene_cube, design, readout):
    from spectracam.pipeline import capture
    from spectracam.scene.reference import ChartReference

    scene, cube = scene_cube
    raw = capture(cube, _camera(scene, design, readout), seed=2)
    e = adc_inverse(raw.digital, raw.camera.sensor)
    r, c = ChartReference.of(scene).boxes[18]     # the white patch: every read-out's brightest part of the chart
    if raw.expected_e.ndim == 2:
        got, want = e[r, c].mean(), raw.expected_e[r, c].mean()
    else:
        got, want = e[:, r, c].mean(axis=(1, 2)), raw.expected_e[:, r, c].mean(axis=(1, 2))
    # the mean of ~100 pixels: shot noise, the paper's 1 % FPN (1300 e⁻ rms, 130 e⁻ over 100 pixels), the quantiser
    np.testing.assert_allclose(got, want, rtol=0.01, atol=200.0)


def test_the_exposure_fills_the_read_outs_range_and_the_capture_lasts_its_frames(scene_cube):
    from spectracam.pipeline import capture
    from spectracam.sensor.readout import READOUTS

    scene, cube = scene_cube
    single = capture(cube, _camera(scene, "fsc/optimal", "single"), seed=0)
    for readout in ("multiple_capture", "split_pixel", "bracketing", "dual_gain"):
        cam = _camera(scene, "fsc/optimal", readout)
        raw = capture(cube, cam, seed=0)
        headroom = READOUTS[readout].headroom(cam.sensor)
        np.testing.assert_allclose(raw.exposure_times_s, single.exposure_times_s * headroom, rtol=1e-12)
        frames = sum(t / cam.sensor.bracketing_ratio ** k for t in raw.exposure_times_s
                     for k in range(cam.sensor.bracketing_frames)) if readout == "bracketing" \
            else raw.exposure_times_s.sum()
        assert raw.capture_time_s == pytest.approx(frames, rel=1e-12)


def test_the_fused_site_rates_are_the_strided_selection():
    from spectracam.architecture.base import make_architecture
    from spectracam.sensor import kernels
    from spectracam.sensor.kernels import SpectralRates

    if not kernels.available():
        pytest.skip("the fused backend (numba) is not installed")
    rng = np.random.default_rng(0)
    cube = rng.random((40, 30, 31), dtype=np.float32)
    for name in ("cfa", "rgbw", "quad_bayer", "cmy"):
        arch = make_architecture(name)
        w = rng.random((31, len(arch.channels)), dtype=np.float32)
        fused = arch._site_rates(SpectralRates(cube, w), arch.layout.tile)
        np.testing.assert_allclose(fused, arch.layout.sample(SpectralRates(cube, w).compute()), rtol=1e-6)


def test_a_merged_word_goes_through_the_raw_exr_and_not_into_a_dng(scene_cube, tmp_path):
    from spectracam.io.dng import write_dng
    from spectracam.io.exr import read_raw_exr, write_raw_exr
    from spectracam.pipeline import capture, score

    scene, cube = scene_cube
    cam = _camera(scene, "cfa/single", "multiple_capture", companding_bits=16)
    raw = capture(cube, cam, seed=4)
    assert raw.digital.max() > 2 ** 12        # beyond a single read's codes
    back = read_raw_exr(write_raw_exr(tmp_path / "raw.exr", raw))
    assert np.array_equal(back.digital, raw.digital)
    s = scene.replace(camera=cam)
    assert score(back, s).summary.delta_e_mean == pytest.approx(score(raw, s).summary.delta_e_mean, abs=1e-9)
    with pytest.raises(SpectracamError, match="sensor.readout = 'multiple_capture': its merged"):
        write_dng(tmp_path / "raw.dng", raw)
    assert not (tmp_path / "raw.dng").exists()


@pytest.mark.parametrize("readout", [r for r in READOUT_NAMES if r != "single"])
def test_what_knows_one_read_only_says_so_in_one_line(readout):
    from spectracam.camera import CameraSpec
    from spectracam.experiments.design.model import SensorModel
    from spectracam.experiments.emva.experiment import EmvaSetup, run_emva
    from spectracam.sensor import SensorSpec

    cam = CameraSpec(sensor=SensorSpec(readout=readout))
    with pytest.raises(SpectracamError, match=f"sensor.readout = '{readout}': EMVA 1288 Linear") as e:
        run_emva(cam, EmvaSetup(width=16, height=16))
    assert "\n" not in str(e.value) and "spectracam datasheet" in str(e.value)
    with pytest.raises(SpectracamError, match=f"sensor.readout = '{readout}': the design's expected-error model"):
        SensorModel.of(cam)
