"""The sensor back end against closed forms (issue 3)."""
import dataclasses

import numpy as np
import pytest

from spectracam import capture
from spectracam.architecture.base import MosaicLayout, make_architecture
from spectracam.camera import CameraSpec, CaptureSpec
from spectracam.camera import photo_electron_rates as _rates
from spectracam.camera.capture import capture as capture_stage
from spectracam.core.errors import ConfigError
from spectracam.scene.reference import ChartReference
from spectracam.sensor.exposure import exposure_times_s
from spectracam.architecture.filters import FilterSpec, responsivities
from spectracam.optics import OpticsSpec, irradiance_factor
from spectracam.render import RadianceCube
from spectracam.sensor import SensorSpec, adc_inverse, expose, fixed_pattern, noise_stream
from spectracam.core.spectra import PLANCK_H_J_S, SPEED_OF_LIGHT_M_S, WavelengthGrid

GRID = np.arange(400.0, 701.0, 10.0)
QUIET = SensorSpec().off("shot_noise", "dark_current", "read_noise", "fpn", "quantization", "clipping")


def photo_electron_rates(cube, camera):
    return _rates(cube.radiance, cube.grid, camera)


def flat_cube(L=1e-3, shape=(64, 64)):
    """A uniform field of constant band-averaged radiance L, W·m⁻²·sr⁻¹·nm⁻¹."""
    return RadianceCube(np.full((*shape, GRID.size), L, np.float32), GRID.copy(), {})


def test_irradiance_factor_forms():
    assert irradiance_factor(OpticsSpec(1.4)) == pytest.approx(np.pi / (4 * 1.96))
    assert irradiance_factor(OpticsSpec(1.4, irradiance_form="exact")) == pytest.approx(np.pi / (1 + 4 * 1.96))
    assert irradiance_factor(OpticsSpec(2.8)) == pytest.approx(irradiance_factor(OpticsSpec(1.4)) / 4)


def test_photo_electrons_match_closed_form():
    # block filters with cutoffs on band edges, flat QE: ρ_k = A·q·k·L/(hc)·∫λ dλ over the pass band
    L, qe, N = 2e-3, 0.5, 1.4
    cam = CameraSpec(optics=OpticsSpec(N), filters=FilterSpec(cutoffs_nm=(495.0, 605.0), qe_peak=qe))
    rates = photo_electron_rates(flat_cube(L), cam)
    A = cam.sensor.pixel_area_um2 * 1e-12
    k = np.pi / (4 * N**2)
    bands = {"R": (605.0, 705.0), "G": (495.0, 605.0), "B": (395.0, 495.0)}
    for c, (a, b) in zip("RGB", bands.values()):
        expected = A * qe * k * L * (b**2 - a**2) / 2 * 1e-9 / (PLANCK_H_J_S * SPEED_OF_LIGHT_M_S)
        assert rates[..., "RGB".index(c)].mean() == pytest.approx(expected, rel=1e-5)


def test_block_filters_split_a_straddling_band():
    R = responsivities(FilterSpec(qe_peak=1.0), WavelengthGrid(GRID))
    i490, i610 = list(GRID).index(490.0), list(GRID).index(610.0)
    assert R[2, i490] == pytest.approx(0.5) and R[1, i490] == pytest.approx(0.5)
    assert R[1, i610] == pytest.approx(0.5) and R[0, i610] == pytest.approx(0.5)
    np.testing.assert_allclose(R.sum(axis=0), 1.0)  # block filters pass every photon exactly once


def test_mean_electrons_and_photon_transfer_variance():
    sensor = SensorSpec(fpn=False, quantization=False)
    rate = np.full((400, 400), 2.0e6, np.float32)
    t = 0.01
    dn, expected = expose(rate, t, sensor, noise_stream(3, 9))
    e = adc_inverse(dn, sensor)
    mean_e = 2.0e6 * t + sensor.dark_rate_e_per_s * t
    assert expected.mean() == pytest.approx(mean_e, rel=1e-6)
    assert e.mean() == pytest.approx(mean_e, rel=1e-3)
    # photon transfer: var = shot (= mean, photo + dark) + read²; 160k samples → ±0.35 % (1σ)
    assert e.var() == pytest.approx(mean_e + sensor.read_noise_e**2, rel=0.02)


@pytest.mark.parametrize("model", ["gaussian", "poisson"])
def test_dark_frame_statistics(model):
    sensor = SensorSpec(fpn=False, quantization=False, shot_noise_model=model)
    t = 2.0
    dn, _ = expose(np.zeros((400, 400), np.float32), t, sensor, noise_stream(1, 9))
    e = adc_inverse(dn, sensor)
    dark = sensor.dark_current_e_per_s_um2 * sensor.pixel_area_um2 * t  # 2000 e⁻
    assert e.mean() == pytest.approx(dark, rel=2e-3)
    assert e.var() == pytest.approx(dark + sensor.read_noise_e**2, rel=0.02)


def test_quantisation_step_is_qmax_over_2n():
    # without a pedestal the ADC spans the full well: step q_max/2ⁿ (the paper's ADC)
    sensor = QUIET.replace(quantization=True, adc_bits=8, black_level_DN=0.0)
    assert sensor.quantization_step_e == 512.0 and sensor.system_gain_dn_per_e == 1 / 512
    electrons = np.arange(0, 131072, 37, dtype=np.float32)
    dn, _ = expose(electrons, 1.0, sensor, noise_stream(0))
    np.testing.assert_array_equal(dn, np.floor(electrons / 512.0))
    s12 = dataclasses.replace(sensor, adc_bits=12)
    assert expose(np.array([1000.0], np.float32), 1.0, s12, noise_stream(0))[0][0] == np.floor(1000 / 32)
    # the default pedestal, 2ⁿ⁻⁵ DN, sits below the full well: K = (2ⁿ − b)/q_max, full well → 2ⁿ
    d = QUIET.replace(quantization=True)
    assert d.black_level_dn == 8 and d.system_gain_dn_per_e == pytest.approx(248 / 131072)
    dn, _ = expose(np.array([0.0, 529.0, 131072 * 0.999], np.float32), 1.0, d, noise_stream(0))
    np.testing.assert_array_equal(dn, [8, 9, 255])
    # an explicit ADC range: the conversion gain reaches the digital numbers, K = 2ⁿ·g/V_fs
    k = QUIET.replace(quantization=True, conversion_gain_uV_per_e=10.0, adc_full_scale_V=1.0, black_level_DN=0.0)
    assert k.system_gain_dn_per_e == pytest.approx(256 * 10e-6)
    assert expose(np.array([10000.0], np.float32), 1.0, k, noise_stream(0))[0][0] == np.floor(10000 * 256e-5)


def test_full_well_clipping():
    sensor = SensorSpec(fpn=False, read_noise=False, quantization=False)
    dn, _ = expose(np.full(1000, 1e9, np.float32), 1.0, sensor, noise_stream(0))
    np.testing.assert_array_equal(dn, 256.0)  # unquantised: full scale = q_max/step = 2ⁿ
    dn, _ = expose(np.full(1000, 1e9, np.float32), 1.0, dataclasses.replace(sensor, quantization=True), noise_stream(0))
    np.testing.assert_array_equal(dn, 255.0)  # quantised: the top code 2ⁿ − 1
    # the well holds q_max: with shot noise off, 0.9·q_max passes and 1.5·q_max reads as q_max
    s16 = dataclasses.replace(sensor, adc_bits=16, shot_noise=False, dark_current=False)
    dn, _ = expose(np.array([0.9, 1.5], np.float32) * np.float32(131072), 1.0, s16, noise_stream(0))
    np.testing.assert_allclose(adc_inverse(dn, s16), [0.9 * 131072, 131072], rtol=1e-6)
    unclipped = s16.off("clipping")
    assert adc_inverse(expose(np.array([2e5], np.float32), 1.0, unclipped, noise_stream(0))[0], unclipped)[0] \
        == pytest.approx(2e5, rel=1e-6)
    unclipped, _ = expose(np.full(10, 1e9, np.float32), 1.0, sensor.off("clipping"), noise_stream(0))
    assert unclipped.min() > 1e5


@pytest.mark.parametrize("reading, rms", [("std", 0.01 * 131072), ("bound", 0.01 * 131072 / np.sqrt(12))])
def test_fpn_fixed_across_frames_different_across_pixels(reading, rms):
    sensor = SensorSpec(fpn_reading=reading)
    a = fixed_pattern(sensor, (300, 300), seed=5, sensor_index=0).offset_e
    b = fixed_pattern(sensor, (300, 300), seed=5, sensor_index=0).offset_e
    c = fixed_pattern(sensor, (300, 300), seed=5, sensor_index=1).offset_e
    np.testing.assert_array_equal(a, b)
    assert a.std() == pytest.approx(rms, rel=0.02) and abs(np.corrcoef(a.ravel(), c.ravel())[0, 1]) < 0.01
    if reading == "bound":
        assert np.abs(a).max() <= 0.005 * 131072


def test_fsc_frames_share_fpn_prism_sensors_do_not():
    cube = flat_cube(shape=(200, 200))
    everywhere = (slice(None), slice(None))
    sensor = SensorSpec(quantization=False, shot_noise=False, read_noise=False, dark_current=False)
    for arch, shared in (("fsc", True), ("prism", False)):
        raw = capture_stage(cube, CameraSpec(sensor=sensor, capture=CaptureSpec(arch, "optimal")), 2, everywhere)
        resid = adc_inverse(raw.digital, sensor) - raw.expected_e
        corr = np.corrcoef(resid[0].ravel(), resid[2].ravel())[0, 1]
        assert (corr > 0.999) if shared else (abs(corr) < 0.02)


def test_exposure_rules():
    white = np.array([3e6, 5e6, 1e6])
    s = SensorSpec()
    sat = s.q_max_e / (white + s.dark_rate_e_per_s)
    cfa, fsc, prism = (make_architecture(n) for n in ("cfa", "fsc", "prism"))
    single = exposure_times_s("single", white, s, cfa)
    np.testing.assert_allclose(single, sat.min())
    opt = exposure_times_s("optimal", white, s, fsc)
    np.testing.assert_allclose(opt, sat)
    assert fsc.capture_time_s(opt) == pytest.approx(sat.sum())
    assert prism.capture_time_s(opt) == pytest.approx(sat.max())
    bal = exposure_times_s("balanced", white, s, fsc)
    assert fsc.capture_time_s(bal) == pytest.approx(single[0]) and bal / bal[0] == pytest.approx(sat / sat[0])
    assert prism.capture_time_s(exposure_times_s("balanced", white, s, prism)) == pytest.approx(single[0])
    with pytest.raises(ConfigError, match="capture.exposure = 'optimal': the cfa architecture has one exposure"):
        CaptureSpec("cfa", "optimal")
    # "near saturation" (paper 4.5): every time scales with the metered fill
    np.testing.assert_allclose(exposure_times_s("optimal", white, s, fsc, 0.9), 0.9 * sat)
    for bad in (0.0, 1.01, float("nan")):
        with pytest.raises(ConfigError, match="capture.white_fill"):
            CaptureSpec(white_fill=bad)


@pytest.mark.parametrize("fill, clipped_lo, clipped_hi", [(1.0, 0.4, 0.95), (0.95, 0.0, 0.0)])
def test_white_metered_near_saturation_does_not_clip(scene_5000, analytic_5000, fill, clipped_lo, clipped_hi):
    """With the paper's noise (FPN as a bound) the white metered at full well clips most of its
    pixels (80 % at this seed: the flooring ADC reads a full well as the top code); metered at 95 % (the default) none."""
    from spectracam.experiments.paper.experiment import load_experiment
    from spectracam.pipeline.scene_file import shipped_scene_file

    paper_camera = load_experiment(shipped_scene_file("paper.toml")).base.camera
    cam = paper_camera.replace(capture=paper_camera.capture.replace(white_fill=fill)).with_design("prism/optimal")
    raw = capture(analytic_5000, cam, seed=3, scene=scene_5000)
    r, c = ChartReference.of(scene_5000).white_box
    top = 2 ** cam.sensor.adc_bits - 1
    share = float(np.mean(raw.digital[:, r, c] >= top))
    assert clipped_lo <= share <= clipped_hi, share


def test_optimal_prism_and_fsc_have_identical_expected_electrons(scene_5000, analytic_5000):
    p = capture(analytic_5000, design="prism/optimal", scene=scene_5000)
    f = capture(analytic_5000, design="fsc/optimal", scene=scene_5000)
    np.testing.assert_array_equal(p.expected_e, f.expected_e)
    from spectracam.scene.chart import patch_masks

    white = patch_masks(scene_5000.chart, 160, 120)[18]
    # each channel's white-patch mean reaches the metered fill of the well, 95 % (photo + dark)
    np.testing.assert_allclose(p.expected_e[:, white].mean(axis=1), 0.95 * 131072.0, rtol=1e-5)
    assert p.capture_time_s == pytest.approx(p.exposure_times_s.max())
    assert f.capture_time_s == pytest.approx(f.exposure_times_s.sum())


@pytest.mark.parametrize("pattern", ["RGGB", "GRBG", "GBRG", "BGGR"])
def test_cfa_mosaic_samples_the_right_channel(pattern, scene_5000, analytic_5000):
    cam = CameraSpec(capture=CaptureSpec(cfa_pattern=pattern))
    raw = capture(analytic_5000, camera=cam, scene=scene_5000)
    rates = photo_electron_rates(analytic_5000, cam)
    idx = MosaicLayout.bayer(pattern).channel_index(rates.shape[:2])
    assert "RGB"[idx[0, 0]] == pattern[0] and "RGB"[idx[1, 1]] == pattern[3]
    expected = np.take_along_axis(rates, idx[..., None], axis=2)[..., 0] * raw.exposure_times_s[0]
    np.testing.assert_allclose(raw.expected_e, expected + SensorSpec().dark_rate_e_per_s * raw.exposure_times_s[0], rtol=1e-5)
    assert raw.digital.shape == (120, 160) and raw.layout == MosaicLayout.bayer(pattern)


def test_camera_spec_design_is_used_unless_overridden(scene_5000, analytic_5000):
    prism = CameraSpec(capture=CaptureSpec("prism", "optimal"))
    raw = capture(analytic_5000, camera=prism, scene=scene_5000)
    assert raw.design == "prism/optimal" and raw.digital.shape == (3, 120, 160)
    raw = capture(analytic_5000, camera=prism, design="fsc/optimal", scene=scene_5000)
    assert raw.design == "fsc/optimal" and raw.camera.sensor == prism.sensor
    # without a camera, the camera of the scene the cube records (not the paper's default)
    fsc_scene = scene_5000.replace(camera=CameraSpec(capture=CaptureSpec("fsc", "balanced")))
    from spectracam.render import render

    assert capture(render(fsc_scene, "analytic")).design == "fsc/balanced"


def test_same_seed_same_capture(scene_5000, analytic_5000):
    a = capture(analytic_5000, seed=7, scene=scene_5000)
    b = capture(analytic_5000, seed=7, scene=scene_5000)
    c = capture(analytic_5000, seed=8, scene=scene_5000)
    np.testing.assert_array_equal(a.digital, b.digital)
    assert not np.array_equal(a.digital, c.digital)


def test_chunked_noise_is_deterministic_and_independent_across_chunks():
    from spectracam.sensor import CHUNK_PX

    n = 2 * CHUNK_PX + 12345  # three chunks, run on a thread pool
    rate = np.full(n, 1e6, np.float32)
    sensor = SensorSpec(fpn=False, quantization=False, clipping=False, dark_current=False)
    a, _ = expose(rate, 0.01, sensor, noise_stream(1, 2))
    b, _ = expose(rate, 0.01, sensor, noise_stream(1, 2))
    np.testing.assert_array_equal(a, b)
    e = adc_inverse(a, sensor) - 1e4
    first, second = e[:CHUNK_PX], e[CHUNK_PX:2 * CHUNK_PX]
    assert abs(np.corrcoef(first, second)[0, 1]) < 0.005
    assert second.var() == pytest.approx(1e4 + 400, rel=0.01)


def test_folded_weights_equal_the_explicit_optics_path():
    from spectracam.optics import radiance_to_photon_irradiance

    cube = RadianceCube(np.random.default_rng(0).random((8, 9, GRID.size), dtype=np.float32) * 1e-3, GRID.copy(), {})
    cam = CameraSpec(filters=FilterSpec(qe="silicon"), optics=OpticsSpec(2.0, 0.9, "exact"))
    Eq = cube.radiance.astype(np.float64) * radiance_to_photon_irradiance(GRID, cam.optics)
    R = responsivities(cam.filters, WavelengthGrid(GRID))
    explicit = np.einsum("hwb,kb->hwk", Eq, R * 10.0) * cam.sensor.pixel_area_um2 * 1e-12
    np.testing.assert_allclose(photo_electron_rates(cube, cam), explicit, rtol=1e-5)
