"""The sensor physics that sets the floor (issue 36, item 3, first part): dark current against temperature (each
law against its closed form written here independently, the paper's numbers unchanged at the reference, the EMVA
1288 measurement of a warm sensor) and read noise that depends on the conversion gain."""
import math

import pytest

from spectracam.camera import CameraSpec
from spectracam.core.errors import ConfigError
from spectracam.sensor import SensorSpec
from spectracam.sensor.temperature import dark_current_factor, local_doubling_K, silicon_band_gap_ev

K_B = 8.617333262e-5       # eV/K, CODATA 2018
T0 = 298.15                # 25 °C


def gap(T):
    """Silicon's band gap, Thurmond (1975): 1.170 − 4.73e-4 T²/(T + 636) eV."""
    return 1.170 - 4.73e-4 * T * T / (T + 636.0)


def test_silicon_band_gap_is_the_published_value_at_300_K():
    assert silicon_band_gap_ev(300.0) == pytest.approx(1.12, abs=0.005)     # Sze & Ng, Table of Si: 1.12 eV


@pytest.mark.parametrize("law", ["generation", "diffusion", "doubling"])
def test_at_the_reference_temperature_every_law_leaves_the_papers_dark_current(law):
    s = SensorSpec(dark_current_law=law)
    assert s.dark_current_factor == 1.0
    assert s.dark_rate_e_per_s == s.dark_current_e_per_s_um2 * s.pixel_area_um2 == 1000.0   # paper 4.4, 10 µm


@pytest.mark.parametrize("t_C", [-20.0, 0.0, 45.0, 85.0])
def test_generation_and_diffusion_laws_are_their_closed_forms(t_C):
    T = t_C + 273.15
    generation = (T / T0) ** 1.5 * math.exp(-gap(T) / (2 * K_B * T) + gap(T0) / (2 * K_B * T0))
    diffusion = (T / T0) ** 3 * math.exp(-gap(T) / (K_B * T) + gap(T0) / (K_B * T0))
    assert dark_current_factor("generation", t_C, 25.0) == pytest.approx(generation, rel=1e-12)
    assert dark_current_factor("diffusion", t_C, 25.0) == pytest.approx(diffusion, rel=1e-12)
    assert SensorSpec(temperature_C=t_C).dark_rate_e_per_s == pytest.approx(1000.0 * generation, rel=1e-12)


def test_the_doubling_law_doubles_per_doubling_temperature():
    for d in (5.0, 7.5):
        s = SensorSpec(dark_current_law="doubling", dark_doubling_K=d, temperature_C=25.0 + d)
        assert s.dark_current_factor == pytest.approx(2.0, rel=1e-14)
        assert SensorSpec(dark_current_law="doubling", dark_doubling_K=d, temperature_C=25.0 - 2 * d,
                          dark_reference_C=25.0).dark_current_factor == pytest.approx(0.25, rel=1e-14)


def test_the_default_doubling_temperature_is_the_generation_laws_own():
    """d ln I/dT of the generation law, analytically: 3/(2T) + (E_g − T·E_g′)/(2kT²), with
    E_g′ = −α T (T + 2β)/(T + β)²; T_d = ln 2 over it: 8.31 K at 25 °C."""
    a, b = 4.73e-4, 636.0
    slope = 1.5 / T0 + (gap(T0) + T0 * a * T0 * (T0 + 2 * b) / (T0 + b) ** 2) / (2 * K_B * T0**2)
    assert local_doubling_K(T0) == pytest.approx(math.log(2) / slope, abs=1e-6)
    assert local_doubling_K(T0) == pytest.approx(8.31, abs=0.01)
    s = SensorSpec(dark_current_law="doubling", temperature_C=25.0 + math.log(2) / slope)
    assert s.dark_current_factor == pytest.approx(2.0, rel=1e-6)


def test_a_reference_other_than_25_C_carries_the_value_stated_there():
    s = SensorSpec(dark_reference_C=60.0, temperature_C=60.0)
    assert s.dark_rate_e_per_s == 1000.0
    assert SensorSpec(dark_reference_C=60.0, temperature_C=25.0).dark_rate_e_per_s == pytest.approx(
        1000.0 / dark_current_factor("generation", 60.0, 25.0), rel=1e-12)


@pytest.mark.parametrize("field, value, allowed", [("read_noise_uV", -5.0, "between 0 and 1e+06 µV"),
                                                   ("temperature_C", 200.0, "between -100 and 150 °C"),
                                                   ("dark_reference_C", -150.0, "between -100 and 150 °C"),
                                                   ("dark_current_law", "arrhenius", "'generation', 'diffusion'"),
                                                   ("dark_doubling_K", -1.0, "between 0 and 100 K")])
def test_bad_temperature_values_are_one_line(field, value, allowed):
    with pytest.raises(ConfigError) as e:
        SensorSpec(**{field: value})
    assert f"sensor.{field}" in str(e.value) and allowed in str(e.value) and "\n" not in str(e.value)


def test_emva_measures_the_warm_sensors_dark_current():
    """The EMVA 1288 series of a 12-bit sensor at 40 °C: the dark current it measures (the slope of the dark signal
    against exposure time) is the generation law's 3.2 × the paper's 1000 e⁻/s, within 3 %."""
    from spectracam.experiments.emva.experiment import EmvaSetup, run_emva

    sensor = SensorSpec(adc_bits=12, temperature_C=40.0)
    r = run_emva(CameraSpec(sensor=sensor), EmvaSetup(width=64, height=64))
    assert r["configured"]["dark_current_e_per_s"] == pytest.approx(sensor.dark_rate_e_per_s, rel=1e-12)
    assert sensor.dark_rate_e_per_s / 1000.0 == pytest.approx(3.2, abs=0.1)
    assert r["measured"]["dark_current_e_per_s"] == pytest.approx(sensor.dark_rate_e_per_s, rel=0.03)


def test_read_noise_in_volts_at_the_papers_gain_is_the_papers_capture():
    """100 µV at 5 µV/e⁻ is the paper's 20 e⁻: the same digital numbers, bit for bit, on both capture paths."""
    import numpy as np

    from spectracam.pipeline import capture, render
    from spectracam.pipeline.scene_file import parse_scene

    scene = parse_scene({"image": {"width": 64, "height": 48}})
    cube = render(scene, "analytic")
    paper = capture(cube, scene=scene, seed=3)
    volts = scene.replace(camera=scene.camera.replace(sensor=scene.camera.sensor.replace(read_noise_uV=100.0)))
    assert volts.camera.sensor.read_noise_rms_e == 20.0
    np.testing.assert_array_equal(capture(cube, scene=volts, seed=3).digital, paper.digital)


def test_a_higher_conversion_gain_lowers_the_read_noise_and_emva_measures_it():
    """The read chain's 100 µV at 10 µV/e⁻ is 10 e⁻ referred to the pixel: the EMVA 1288 series of a 12-bit sensor
    configures the dark noise σ_d (read noise with the dark current's shot noise at the shortest exposure) exactly
    as for a sensor stated at 10 e⁻, and measures it (the dark frames' temporal variance over K²) within 3 %."""
    from spectracam.experiments.emva.experiment import EmvaSetup, run_emva

    sensor = SensorSpec(adc_bits=12, read_noise_uV=100.0, conversion_gain_uV_per_e=10.0)
    assert sensor.read_noise_rms_e == 10.0
    assert SensorSpec(read_noise_uV=100.0, read_noise=False).read_noise_rms_e == 0.0
    setup = EmvaSetup(width=64, height=64)
    r = run_emva(CameraSpec(sensor=sensor), setup)
    stated = run_emva(CameraSpec(sensor=SensorSpec(adc_bits=12, read_noise_e=10.0, conversion_gain_uV_per_e=10.0)),
                      setup)
    assert r["configured"]["dark_noise_e"] == stated["configured"]["dark_noise_e"]
    assert r["measured"]["dark_noise_e"] == pytest.approx(r["configured"]["dark_noise_e"], rel=0.03)
    paper = run_emva(CameraSpec(sensor=SensorSpec(adc_bits=12)), setup)     # 20 e⁻: a larger floor
    assert paper["configured"]["dark_noise_e"] > r["configured"]["dark_noise_e"] + 5


def test_a_law_taken_past_any_sensor_is_one_line():
    """A doubling every 0.001 K over 125 K overflows: refused naming the field, the value reached and the bound."""
    with pytest.raises(ConfigError) as e:
        SensorSpec(temperature_C=150.0, dark_current_law="doubling", dark_doubling_K=0.001)
    assert str(e.value).startswith("sensor.temperature_C = 150.0: the doubling law") and "at most 1e9" in str(e.value)


# ---- hot pixels: the dark-signal non-uniformity's tail (issue 36, item 3) ----

def _dark_gain(sensor, shape=(512, 512), seed=3):
    from spectracam.sensor import fixed_pattern

    return fixed_pattern(sensor, shape, seed).dark_gain


def test_hot_pixels_are_the_stated_share_with_an_exponential_excess_and_keep_the_mean():
    import numpy as np

    p, m = 0.01, 20.0
    s = SensorSpec(hot_pixel_fraction=p, hot_pixel_mean_factor=m)
    g = _dark_gain(s).astype(np.float64) * (1 + p * m)      # undo the normalisation: 1 + excess
    excess = g - 1.0
    hot = excess > 0
    n = excess.size
    assert abs(hot.mean() - p) < 4 * math.sqrt(p * (1 - p) / n)          # binomial, 4 σ
    k = hot.sum()
    assert excess[hot].mean() == pytest.approx(m, rel=4 / math.sqrt(k))  # exponential: σ of the mean m/√k
    # exponential: the median of the excess is m·ln 2
    assert np.median(excess[hot]) == pytest.approx(m * math.log(2), rel=0.1)
    mean, var = _dark_gain(s).mean(), _dark_gain(s).var()
    want_mean, want_var = __import__("spectracam.sensor", fromlist=["x"]).dark_gain_moments(s)
    assert mean == pytest.approx(want_mean, rel=4 * math.sqrt(want_var / n))
    assert var == pytest.approx(want_var, rel=0.1)


def test_hot_pixels_with_dsnu_combine_as_their_moments_say():
    import numpy as np

    from spectracam.sensor import dark_gain_moments

    s = SensorSpec(hot_pixel_fraction=0.002, hot_pixel_mean_factor=50.0, dsnu_fraction=0.3)
    g = _dark_gain(s, (1024, 1024)).astype(np.float64)
    mean, var = dark_gain_moments(s)
    assert g.mean() == pytest.approx(mean, abs=4 * math.sqrt(var / g.size))
    assert g.var() == pytest.approx(var, rel=0.1)
    assert g.min() >= 0.0


def test_hot_pixels_off_leave_the_pattern_as_it_was():
    base = SensorSpec(dsnu_fraction=0.2)
    assert (_dark_gain(base) == _dark_gain(base.replace(hot_pixel_mean_factor=3.0))).all()
    assert _dark_gain(SensorSpec()) is None
    assert _dark_gain(SensorSpec(hot_pixel_fraction=0.01, dark_current=False)) is None


def test_the_fused_capture_records_the_same_hot_pixels_as_the_steps():
    """The fused kernel takes the drawn plane as it is: its capture equals the NumPy steps' exactly with only the
    fixed pattern on (no temporal noise to differ in)."""
    import numpy as np

    from spectracam.sensor import PatternRef, expose, kernels, noise_stream

    if not kernels.available():
        pytest.skip("the fused backend (numba) is not installed")
    s = SensorSpec(hot_pixel_fraction=0.05, adc_bits=12, fpn_fraction=0.0).off("shot_noise", "read_noise")
    rate = np.full((64, 48), 2000.0, np.float32)
    ref = PatternRef(s, rate.shape, 5)
    fused = kernels.record(rate, np.zeros((1, 1, 1), np.int64), [2.0], s, [noise_stream(5, 2, 0)], [ref])
    steps = expose(rate, 2.0, s, noise_stream(5, 2, 0), ref.draw())
    assert np.array_equal(fused[1][0], steps[1])
    assert np.array_equal(fused[0][0], steps[0])
    assert (steps[1] > 2.0 * (2000.0 * 2.0 + 2000.0)).any()          # some pixels are hot


def test_emva_measures_the_hot_pixels_dsnu():
    from spectracam.experiments.emva.experiment import EmvaSetup, run_emva

    sensor = SensorSpec(adc_bits=12, hot_pixel_fraction=0.01, hot_pixel_mean_factor=10.0, fpn_fraction=0.0)
    r = run_emva(CameraSpec(sensor=sensor), EmvaSetup(width=128, height=128))
    got, want = r["measured"]["dsnu_e"], r["configured"]["dsnu_e"]
    assert got == pytest.approx(want, rel=0.2)
    assert want > 1000.0 * 2.5 * 0.3       # the tail: σ ≈ 0.37 of the mean dark at t50 = 2.5 s
