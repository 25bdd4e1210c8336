"""The high-dynamic-range read-out schemes (issue 36, item 2): spectracam.sensor.readout."""
import numpy as np
import pytest

from spectracam.core.errors import ConfigError, SpectracamError
from spectracam.sensor import SensorSpec, adc_inverse, expose, fixed_pattern, kernels
from spectracam.sensor import readout as ro

T = 0.05
N_PX = 10_000
# a fine ADC (16 bits: K ≈ 0.5 DN/e⁻) so the statistics are those of the charge; dark current on
FINE = dict(adc_bits=16, fpn=False)


def _seed(i=1):
    return np.random.SeedSequence([7, i])


def _decoded(sensor, current_e_per_s, n=N_PX, seed=1, **kw):
    rate = np.full(n, current_e_per_s - sensor.dark_rate_e_per_s, np.float32)
    d, m = ro.READOUTS[sensor.readout].read(rate, T, sensor, _seed(seed), None, **kw)
    return ro.decode(d, sensor), m


# ------------------------------------------------------------------ multiple capture
@pytest.mark.parametrize("current", [2e4, 1e6, 1e7])  # read-noise bound, shot bound, saturated from sample 3 on
def test_wls_variance_matches_its_closed_form(current):
    s = SensorSpec(readout="multiple_capture", motion_threshold_sigma=0, **FINE)
    e, m = _decoded(s, current)
    var_i = np.var(e / T)
    assert var_i == pytest.approx(ro.multiple_capture_variance(current, T, s), rel=0.05)
    assert e.mean() == pytest.approx(current * T, rel=0.003)
    if current == 1e7:  # only 2 of 8 samples: the variance is that of 2, not of 8
        assert ro.multiple_capture_variance(current, T, s) > 3 * ro.multiple_capture_variance(
            current, T, s.replace(clipping=False))


def test_last_sample_variance_is_its_closed_form():
    s = SensorSpec(readout="multiple_capture", readout_estimator="last_sample", **FINE)
    for current, k in ((1e6, 8), (1e7, 2)):
        e, _ = _decoded(s, current)
        sigma2 = (s.read_noise_rms_e**2 / 2 + 1 / (12 * s.system_gain_dn_per_e**2))
        t = k * T / 8
        assert np.var(e / T) == pytest.approx((current * t + 2 * sigma2) / t**2, rel=0.05)


def test_wls_beats_last_sample_where_read_noise_counts():
    s = SensorSpec(readout="multiple_capture", **FINE)
    assert ro.multiple_capture_variance(2e3, T, s) < 0.7 * ro.multiple_capture_variance(2e3, T, s, "last_sample")


def _constructed(current, n=N_PX, qmax=131072.0, sigma=20 / np.sqrt(2), seed=3):
    t = np.arange(9) * T / 8
    rng = np.random.default_rng(seed)
    cur = np.broadcast_to(np.asarray(current, float)[:, None], (9, n)) if np.ndim(current) else current
    shot = np.cumsum(np.sqrt(np.diff(t, prepend=0)[:, None] * np.maximum(cur, 0)) * rng.standard_normal((9, n)), 0)
    q = np.cumsum(np.diff(t, prepend=0)[:, None] * cur * np.ones((9, n)), 0) + shot
    return t, np.minimum(q, qmax) + sigma * rng.standard_normal((9, n)) + 1000.0  # + an unknown reset level


def test_saturation_detection_leaves_the_estimate_unbiased():
    s = SensorSpec(readout="multiple_capture", quantization=False, **FINE)
    current = s.q_max_e / (1.5 * T / 8)  # the well fills between samples 1 and 2: sample 2 on saturated
    t, y = _constructed(current)
    est = ro.estimate_current(t, y, s)
    assert est.mean() == pytest.approx(current, rel=0.003)
    assert np.var(est) == pytest.approx(ro.multiple_capture_variance(current, T, s), rel=0.08)
    naive = (y[-1] - y[0]) / T  # what a single read would report: the well
    assert naive.mean() < 0.2 * current


def test_motion_detection_keeps_the_current_before_the_step():
    s = SensorSpec(readout="multiple_capture", quantization=False, q_max_e=1e9, **FINE)
    step = np.array([1e6] * 5 + [4e6] * 4)  # the current quadruples after sample 4 (something bright moves in)
    t, y = _constructed(step)
    est = ro.estimate_current(t, y, s)
    assert np.median(est) == pytest.approx(1e6, rel=0.01)
    blended = ro.estimate_current(t, y, s.replace(motion_threshold_sigma=0))
    assert np.median(blended) > 1.5e6


def test_one_sample_is_a_single_read():
    s = SensorSpec(readout="multiple_capture", readout_samples=1, **FINE)
    e, m = _decoded(s, 2e6)
    single = SensorSpec(**FINE)
    dn, _ = expose(np.full(N_PX, 2e6 - s.dark_rate_e_per_s, np.float32), T, single, _seed(2))
    ref = adc_inverse(dn.astype(np.float64), single)
    assert e.mean() == pytest.approx(ref.mean(), rel=0.002)
    assert e.var() == pytest.approx(ref.var(), rel=0.05)


@pytest.mark.skipif(not kernels.available(), reason="numba not available")
def test_numba_and_numpy_agree():
    s = SensorSpec(readout="multiple_capture", adc_bits=12)
    rate = np.random.default_rng(0).uniform(0, 2e7, 4000).astype(np.float32)
    p = fixed_pattern(s, (1, 4000), 3)
    a = ro.read_multiple_capture(rate, T, s, _seed(), p, backend="numba")
    b = ro.read_multiple_capture(rate, T, s, _seed(), p, backend="numpy")
    assert np.mean(a[0] == b[0]) > 0.999 and np.array_equal(a[1], b[1])  # same normals, same float64 steps
    sp = s.replace(shot_noise_model="poisson", fpn=False)
    flat = np.full(N_PX, 3e6, np.float32)
    a, b = (ro.decode(ro.read_multiple_capture(flat, T, sp, _seed(), None, backend=k)[0], sp) for k in ("numba", "numpy"))
    assert a.mean() == pytest.approx(b.mean(), rel=0.002) and a.var() == pytest.approx(b.var(), rel=0.08)


# ------------------------------------------------------------------ dual gain, split pixel, bracketing: SNR
def _snr_points(sensor):
    if sensor.readout == "dual_gain":
        sw = sensor.dual_gain_switch * sensor.q_max_e / sensor.dual_gain_ratio
        return [3e3, 0.8 * sw, 1.2 * sw, 1e5]
    if sensor.readout == "split_pixel":
        sw = ro.SWITCH_FRACTION * sensor.q_max_e
        return [3e3, 0.8 * sw, 1.2 * sw, 0.8 * sensor.q_max_e * 4]
    sw = ro.SWITCH_FRACTION * sensor.q_max_e
    return [3e3, 0.8 * sw, 1.2 * sw, 10 * sw]


@pytest.mark.parametrize("name", ["dual_gain", "split_pixel", "bracketing"])
def test_snr_matches_the_closed_form_and_dips_at_the_switch(name):
    s = SensorSpec(readout=name, adc_bits=12, fpn=False)
    pts = _snr_points(s)
    for sig in pts:
        e, _ = _decoded(s, sig / T, n=N_PX)
        assert e.mean() / e.std() == pytest.approx(float(ro.snr_curve(sig, s)), rel=0.05), (name, sig)
    sw = ro.SWITCH_FRACTION * s.q_max_e if name != "dual_gain" else s.dual_gain_switch * s.q_max_e / 4
    assert ro.snr_curve(sw * 1.001, s) < ro.snr_curve(sw * 0.999, s)  # the dip


def test_snr_curve_of_a_single_read_is_shot_read_and_quantisation():
    s = SensorSpec(adc_bits=12)
    q = 1 / s.system_gain_dn_per_e
    assert ro.snr_curve(1e4, s) == pytest.approx(1e4 / np.sqrt(1e4 + 400 + q * q / 12))
    assert np.isnan(ro.snr_curve(2e5, s))


# ------------------------------------------------------------------ decode across the extended range
@pytest.mark.parametrize("name", ["multiple_capture", "dual_gain", "split_pixel", "bracketing"])
@pytest.mark.parametrize("bits", [None, 12])
def test_decode_recovers_the_charge_across_the_range(name, bits):
    s = SensorSpec(readout=name, adc_bits=10, companding_bits=bits)
    top = ro.READOUTS[name].headroom(s) * s.q_max_e
    p = fixed_pattern(s, (1, 4000), 5)
    for frac in (0.003, 0.05, 0.3, 0.8):
        rate = np.full((1, 4000), frac * top / T, np.float32)
        d, m = ro.read(rate, T, s, _seed(), p)
        assert d.max() <= ro.output_top_dn(s)
        e = ro.decode(d, s)
        # FPN offsets (1 % of the swing) stay in a single read's output; the mean over pixels cancels them
        assert e.mean() == pytest.approx(m.mean(), rel=0.01, abs=300), (name, frac)


def test_companding_round_trip_and_its_noise():
    s = SensorSpec(readout="multiple_capture", adc_bits=12, readout_samples=16, companding_bits=12, fpn=False)
    assert ro.output_top_dn(s) <= 2**12 - 1
    c = ro.companding_bound(s)
    assert 0.5 <= c < 1.5
    lin = np.arange(0, ro._linear_top_dn(s) + 1)
    codes = ro.compand(lin, s)
    assert np.array_equal(ro.compand(ro.expand(codes, s), s), codes)
    assert np.all(np.abs(ro.expand(codes, s) - lin) <= ro.companding_curve(s)[2].max() / 2)
    plain = s.replace(companding_bits=None)
    for sig in (1e4, 3e5, 1.5e6):
        a, _ = _decoded(s, sig / T)
        b, _ = _decoded(plain, sig / T)
        assert a.std() / b.std() < np.sqrt(1 + c * c / 12) + 0.01  # steps ≤ c·σ add at most c²/12 to the variance
        assert a.mean() == pytest.approx(b.mean(), rel=0.002)


# ------------------------------------------------------------------ reproducibility
@pytest.mark.parametrize("name", ["multiple_capture", "dual_gain", "split_pixel", "bracketing"])
def test_same_seed_same_frame_and_threads_do_not_matter(name, monkeypatch):
    s = SensorSpec(readout=name, adc_bits=12)
    rate = np.random.default_rng(1).uniform(0, 1e7, (40, 300)).astype(np.float32)
    a = ro.read(rate, T, s, _seed(1))[0]
    assert np.array_equal(a, ro.read(rate, T, s, _seed(1))[0])
    assert not np.array_equal(a, ro.read(rate, T, s, _seed(2))[0])
    monkeypatch.setenv("SPECTRACAM_THREADS", "1")
    monkeypatch.setattr(ro, "_NP_CHUNK", 1000)
    assert np.array_equal(a, ro.read(rate, T, s, _seed(1))[0])


def test_numpy_path_does_not_depend_on_chunking(monkeypatch):
    s = SensorSpec(readout="multiple_capture", adc_bits=12)
    rate = np.random.default_rng(1).uniform(0, 1e7, 5000).astype(np.float32)
    a = ro.read_multiple_capture(rate, T, s, _seed(), backend="numpy")[0]
    monkeypatch.setattr(ro, "_NP_CHUNK", 777)
    assert np.array_equal(a, ro.read_multiple_capture(rate, T, s, _seed(), backend="numpy")[0])


# ------------------------------------------------------------------ bracketing with motion, times, errors
def test_bracketing_takes_the_longest_unsaturated_frame():
    s = SensorSpec(readout="bracketing", adc_bits=12, fpn=False)
    rate = np.full(2000, 3e6, np.float32)  # saturates frame 0 (T), not frame 1 (T/8)
    moved = [rate, rate * 2, rate * 2]  # the scene doubles after the first frame
    e = ro.decode(ro.read_bracketing(rate, T, s, _seed(), None, frame_rates=moved)[0], s)
    assert np.median(e) == pytest.approx(2 * 3e6 * T + s.dark_rate_e_per_s * T, rel=0.02)
    assert ro.READOUTS["bracketing"].capture_time_s(s, T) == pytest.approx(T * (1 + 1 / 8 + 1 / 64))
    with pytest.raises(SpectracamError, match="frame_rates"):
        ro.read_bracketing(rate, T, s, _seed(), None, frame_rates=[rate])


def test_headroom_and_output_words():
    s = SensorSpec(readout="split_pixel")
    assert ro.READOUTS["split_pixel"].headroom(s) == 4.0
    d = SensorSpec(readout="dual_gain")
    assert ro.output_dn_per_e(d) == pytest.approx(2 * 4 * d.system_gain_dn_per_e)
    assert ro.output_top_dn(SensorSpec()) == 255
    with pytest.raises(SpectracamError, match="readout = 'single'"):
        ro.read(np.ones(3, np.float32), T, SensorSpec(), _seed())


@pytest.mark.parametrize("field, value", [("readout", "triple"), ("readout_samples", 0), ("readout_estimator", "ml"),
                                          ("dual_gain_ratio", 1.0), ("split_small_well_fraction", 0.0),
                                          ("bracketing_frames", 0), ("companding_bits", 4),
                                          ("motion_threshold_sigma", -1)])
def test_bad_readout_fields_are_one_line_errors(field, value):
    with pytest.raises(ConfigError) as e:
        SensorSpec(**{field: value})
    assert field in str(e.value) and "\n" not in str(e.value)
