"""EMVA 1288 Release 4.0 Linear analysis (spectracam.evaluation.emva1288) against a camera whose parameters we set.

A small, self-contained linear camera (Poisson photo- and dark electrons, a full well, a Gaussian
DSNU and PRNU pattern from a fixed seed, Gaussian read noise, an ADC with gain K, a black level and a
12-bit clip) makes a photon-transfer series by varying the exposure time at constant irradiance, with
a dark pair at every exposure time, and the two stacks of the nonuniformity measurement.
``analyse`` must give back what ``expected`` derives from the configuration.

Tolerances (relative unless stated), and why:

* 2 % for K, η, σ_d, μ_e.sat, the dark current, DSNU and PRNU: the statistical errors of this
  256×256-pixel, 64-step series are 0.1-0.6 % (K, η: ~0.3 % rms over seeds, −0.56 % for this one; the
  dark noise, dark current and DSNU inherit K's error; DSNU, PRNU: the realised pattern's
  standard deviation scatters by 1/√(2·65536) ≈ 0.3 % around the configured one, and the spatial
  variance estimate by ≈ 0.3 %; μ_e.sat: η's error plus the interpolation of the saturated fraction).
* dB quantities: the dB equivalent of 2 % of the underlying ratio — 20·log10(1.02) = 0.172 dB for DR
  and half that, 0.086 dB, for SNR_max = √μ_e.sat.
* Linearity error: the ideal camera's is 0, so an absolute bound, 0.05 % (the step means scatter
  by ~0.01 % of the signal); a camera with a known 5 % compressive nonlinearity must give the value
  the same regression gives on its noise-free response, within 10 % (a 64×64 camera, to stay fast).
* Saturation by the Release 3.1 variance maximum: 4 %, because the maximum is located only to within
  the series' step (1.8 % of μ_p.sat here) and the variance curve is flat at its top.

A factor-2 bug (dropping the ½ of the difference variance, patched into the analysis) and the
missing σ²/L correction of the DSNU (recomputed from the same statistics) must both fall far outside
these tolerances.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

from spectracam.evaluation import emva1288 as emva
from spectracam.core.errors import ConfigError


@dataclass(frozen=True)
class LinearCamera:
    K: float = 0.5                 # DN/e⁻
    eta: float = 0.6               # quantum efficiency at the test wavelength
    read_noise_e: float = 3.0
    dark_current_e_per_s: float = 200.0
    dsnu_e: float = 2.0            # rms of the per-pixel dark offset
    prnu: float = 0.01             # rms of the per-pixel relative gain
    full_well_e: float = 12000.0   # above the ADC's range: the 12-bit clip saturates first
    bits: int = 12
    black_DN: float = 64.0
    shape: tuple = (256, 256)
    nonlinearity: float = 0.0      # y ∝ e·(1 − nonlinearity·e/full_well), a compressive bow
    seed: int = 1288

    def expected(self, rate=None, **kw):
        return emva.expected(
            gain_DN_per_e=self.K, quantum_efficiency=self.eta, read_noise_e=self.read_noise_e,
            dark_current_e_per_s=self.dark_current_e_per_s, dsnu_e=self.dsnu_e, prnu_fraction=self.prnu,
            full_well_e=self.full_well_e, adc_bits=self.bits, black_level_DN=self.black_DN,
            series_photon_rate_per_s=rate, **kw)


class Capture:
    """Frames of a LinearCamera: fixed patterns from the camera's seed, temporal noise from a stream."""

    def __init__(self, cam: LinearCamera):
        self.cam = cam
        patterns = np.random.default_rng(cam.seed)
        self.gain_map = 1.0 + patterns.normal(0.0, cam.prnu, cam.shape)
        self.offset_map_e = patterns.normal(0.0, cam.dsnu_e, cam.shape)
        self.rng = np.random.default_rng(cam.seed + 1)

    def frames(self, mu_p: float, t_exp: float, count: int) -> np.ndarray:
        cam = self.cam
        lam = cam.eta * mu_p * self.gain_map + cam.dark_current_e_per_s * t_exp
        out = np.empty((count, *cam.shape), np.uint16)
        for k in range(count):
            e = np.minimum(self.rng.poisson(lam).astype(np.float64), cam.full_well_e)
            if cam.nonlinearity:
                e = e * (1.0 - cam.nonlinearity * e / cam.full_well_e)
            v = e + self.offset_map_e + self.rng.normal(0.0, cam.read_noise_e, cam.shape)
            out[k] = np.clip(np.rint(cam.K * v + cam.black_DN), 0, 2**cam.bits - 1)
        return out


def make_series(cam: LinearCamera, steps=64, beyond=1.12, L=16, spatial=True):
    """Exposure-time series at constant irradiance from dark to `beyond` × the expected saturation."""
    mu_p_sat = cam.expected()["details"]["mu_p_sat"]
    t_max = 0.04
    rate = beyond * mu_p_sat / t_max                  # photons per pixel per second
    t = t_max * np.arange(1, steps + 1) / steps
    cap = Capture(cam)
    bright = np.stack([cap.frames(rate * ti, ti, 2) for ti in t])
    dark = np.stack([cap.frames(0.0, ti, 2) for ti in t])
    kw = {}
    if spatial:
        t_half = 0.5 * mu_p_sat / rate
        kw = dict(spatial_dark=cap.frames(0.0, t_half, L), spatial_bright=cap.frames(rate * t_half, t_half, L),
                  spatial_mu_p=rate * t_half, spatial_exposure_time_s=t_half)
    series = emva.EmvaSeries(wavelength_nm=550.0, pixel_area_um2=3.45**2, exposure_times_s=t, mu_p=rate * t,
                             bright_pairs=bright, dark_pairs=dark, max_dn=2**cam.bits - 1, **kw)
    return series, rate


CAMERA = LinearCamera()

TOLERANCES = {  # key: (kind, tolerance) — "rel" fraction or "abs" in the key's unit
    "system_gain_DN_per_e": ("rel", 0.02),
    "quantum_efficiency": ("rel", 0.02),
    "dark_noise_e": ("rel", 0.02),
    "saturation_capacity_e": ("rel", 0.02),
    "snr_max_db": ("abs", 10 * math.log10(1.02)),
    "dynamic_range_db": ("abs", 20 * math.log10(1.02)),
    "dark_current_e_per_s": ("rel", 0.02),
    "dsnu_e": ("rel", 0.02),
    "prnu_percent": ("rel", 0.02),
    "linearity_error_percent": ("abs", 0.05),
}


def deviation(kind, measured, configured):
    return (measured - configured) / configured if kind == "rel" else measured - configured


@pytest.fixture(scope="module")
def run():
    series, rate = make_series(CAMERA)
    return series, emva.analyse(series), CAMERA.expected(rate)


def table(measured, configured):
    rows = ["| quantity | configured | measured | deviation | tolerance |", "|---|---|---|---|---|"]
    for key, (kind, tol) in TOLERANCES.items():
        d = deviation(kind, measured[key], configured[key])
        fmt = f"{100 * d:+.2f} %" if kind == "rel" else f"{d:+.4f}"
        tfmt = f"{100 * tol:.0f} %" if kind == "rel" else f"±{tol:.3f}"
        rows.append(f"| {key} | {configured[key]:.5g} | {measured[key]:.5g} | {fmt} | {tfmt} |")
    return "\n".join(rows)


def test_camera_obeys_the_standards_measurement_conditions(run):
    series, result, _ = run
    # section 6.5: at most 0.5 % of the dark pixels at code 0 (here: none)
    assert np.mean(series.dark_pairs == 0) < 0.005
    # at least 50 steps from dark to saturation; the series reaches beyond it
    assert result["details"]["saturation_index"] >= 50
    assert result["curves"]["saturated_fraction"][-1] > emva.SATURATED_FRACTION_WINDOW[1]
    assert result["details"]["saturation_method"] == "pixel_fraction"
    assert set(emva.RESULT_KEYS) <= set(result)


@pytest.mark.parametrize("key", list(TOLERANCES))
def test_analyse_recovers_the_configured_camera(run, key):
    _, measured, configured = run
    kind, tol = TOLERANCES[key]
    d = deviation(kind, measured[key], configured[key])
    why = f"{key}: measured {measured[key]:.6g}, configured {configured[key]:.6g}\n"
    assert abs(d) <= tol, why + table(measured, configured)


def test_tolerances_are_far_tighter_than_a_factor_two_bug(run, monkeypatch):
    """Dropping the ½ of σ²_y = ½·mean((y_A − y_B)²) doubles K: it must fail by far."""
    series, good, configured = run

    orig = emva.pair_statistics

    def without_half(a, b):  # mean((y_A − y_B)²) − (μ_A − μ_B)²: the ½ forgotten
        mu, var = orig(a, b)
        return mu, 2.0 * var

    monkeypatch.setattr(emva, "pair_statistics", without_half)
    bad = emva.analyse(series)
    assert bad["system_gain_DN_per_e"] / good["system_gain_DN_per_e"] == pytest.approx(2.0, rel=0.01)
    kind, tol = TOLERANCES["system_gain_DN_per_e"]
    assert abs(deviation(kind, bad["system_gain_DN_per_e"], configured["system_gain_DN_per_e"])) > 20 * tol
    # η = R/K halves too
    assert abs(deviation("rel", bad["quantum_efficiency"], configured["quantum_efficiency"])) > 20 * tol


def test_dsnu_needs_the_temporal_noise_correction(run):
    """Without subtracting σ²_y.stack/L the DSNU is biased far beyond its tolerance."""
    series, good, configured = run
    sd = good["details"]["spatial_dark"]
    K = good["system_gain_DN_per_e"]
    uncorrected = math.sqrt(sd["s2_y_measured"]) / K
    assert abs(uncorrected / configured["dsnu_e"] - 1) > 2 * TOLERANCES["dsnu_e"][1]
    assert good["dsnu_e"] == pytest.approx(math.sqrt(sd["s2_y_measured"] - sd["var_y_stack"] / sd["L"]) / K)


def test_no_row_or_column_pattern_is_invented(run):
    _, result, configured = run
    d = result["details"]
    assert d["dsnu_pixel_e"] == pytest.approx(configured["dsnu_e"], rel=0.02)
    assert d["prnu_pixel_percent"] == pytest.approx(configured["prnu_percent"], rel=0.02)
    for key in ("dsnu_col_e", "dsnu_row_e"):  # white patterns: row/column parts are ~1/√256 of the total
        assert not d[key] > 0.2 * configured["dsnu_e"]


def test_dark_current_from_variance_and_dark_noise_rule(run):
    _, result, configured = run
    # section 7.1: the slope of σ²_y.dark over t_exp divided by K² (noisier than the mean's slope)
    from_variance = result["details"]["dark_current_from_variance_e_per_s"]
    assert from_variance == pytest.approx(configured["dark_current_e_per_s"], rel=0.05)
    assert not result["details"]["dark_noise_is_upper_limit"]


def test_curves_for_plots(run):
    series, result, _ = run
    c = result["curves"]
    for key in ("mu_p", "mu_y", "var_y", "mu_y_dark", "var_y_dark", "snr", "snr_model", "linearity_deviation_percent"):
        assert c[key].shape == (series.n_steps,)
    fit = c["sensitivity_fit_mask"]
    # measured SNR follows the linear model (eq. 21) below saturation
    np.testing.assert_allclose(c["snr"][fit][2:], c["snr_model"][fit][2:], rtol=0.02)


def test_fit_masks_are_the_standards_ranges(run):
    """The steps each fit used (and the plots mark; issue 23) are the standard's: photon transfer and
    responsivity 0-70 % of μ_y.sat − μ_y.dark, linearity 5-95 %, neither past the saturation exposure;
    ``beyond_saturation_mask`` is every step past it.  The numbers are written out, not read from the
    module's constants."""
    series, result, _ = run
    c, d = result["curves"], result["details"]
    signal = c["mu_y"] - c["mu_y_dark"]
    sat = d["mu_y_sat_minus_dark_DN"]
    below = series.mu_p <= d["mu_p_sat"]
    np.testing.assert_array_equal(c["beyond_saturation_mask"], ~below)
    np.testing.assert_array_equal(c["sensitivity_fit_mask"], below & (signal <= 0.70 * sat))
    np.testing.assert_array_equal(c["linearity_fit_mask"], below & (signal >= 0.05 * sat) & (signal <= 0.95 * sat))
    # this series has steps in every role: below 5 %, 70-95 %, 95 % to saturation, beyond it
    for part in (signal < 0.05 * sat, below & (signal > 0.70 * sat), below & (signal > 0.95 * sat), ~below):
        assert part.any()


def test_saturation_by_variance_maximum(run):
    """Release 3.1's definition, which the caller may ask for: 4 % (the step is 1.8 % of μ_p.sat)."""
    series, _, _ = run
    rate = series.mu_p[0] / series.exposure_times_s[0]
    measured = emva.analyse(series, saturation="variance_max")
    configured = CAMERA.expected(rate, saturation="variance_max")
    assert measured["details"]["saturation_method"] == "variance_max"
    assert measured["saturation_capacity_e"] == pytest.approx(configured["saturation_capacity_e"], rel=0.04)


def test_linearity_error_of_a_nonlinear_camera():
    cam = LinearCamera(shape=(64, 64), nonlinearity=0.05, seed=7)
    series, _ = make_series(cam, spatial=False)
    result = emva.analyse(series)
    # the same regression on the noise-free response over the range analyse used
    mask = result["curves"]["linearity_fit_mask"]
    mu_p = series.mu_p[mask]
    e = cam.eta * mu_p
    y = cam.K * e * (1 - cam.nonlinearity * e / cam.full_well_e)
    _, _, dev = emva.linearity_fit(mu_p, y)
    assert result["linearity_error_percent"] == pytest.approx(np.mean(np.abs(dev)), rel=0.10)
    half_range = (dev.max() - dev.min()) / 2
    assert result["details"]["linearity_error_half_range_percent"] == pytest.approx(half_range, rel=0.10)
    half = emva.analyse(series, linearity="half_range")
    assert half["linearity_error_percent"] == result["details"]["linearity_error_half_range_percent"]
    assert result["linearity_error_percent"] > 5 * TOLERANCES["linearity_error_percent"][1]


def test_full_well_below_the_adc_range_and_quantisation_limited_dark_noise():
    # the well fills before the maximum code: no pixel reaches max_dn, both sides fall back to the
    # variance maximum (4 %: located to within a step, as above)
    cam = LinearCamera(shape=(64, 64), full_well_e=6000.0, seed=3)
    series, rate = make_series(cam, spatial=False)
    measured, configured = emva.analyse(series), cam.expected(rate)
    assert measured["details"]["saturation_method"].startswith("variance_max (fallback")
    assert configured["details"]["saturation_method"].startswith("variance_max (fallback")
    assert measured["saturation_capacity_e"] == pytest.approx(configured["saturation_capacity_e"], rel=0.04)
    # σ²_y.dark = (0.1·2)² + 1/12 < 0.24 DN²: only the upper limit 0.40/K (eq. 54) on both sides
    cam = LinearCamera(shape=(64, 64), K=0.1, read_noise_e=2.0, black_DN=16, dsnu_e=1.0, full_well_e=50000.0, seed=4)
    series, rate = make_series(cam, spatial=False)
    measured, configured = emva.analyse(series), cam.expected(rate)
    assert measured["details"]["dark_noise_is_upper_limit"] and configured["details"]["dark_noise_is_upper_limit"]
    assert measured["dark_noise_e"] * measured["system_gain_DN_per_e"] == pytest.approx(math.sqrt(0.24 - 1 / 12))
    assert measured["dark_noise_e"] == pytest.approx(configured["dark_noise_e"], rel=0.02)


def test_building_blocks():
    # eq. 18: the difference of the two means is taken out of the variance
    a = np.array([[0.0, 2.0], [4.0, 6.0]])
    mu, var = emva.pair_statistics(a, a + 1.0)
    assert (mu, var) == (3.5, 0.0)
    mu, var = emva.pair_statistics(a, np.array([[1.0, 1.0], [5.0, 5.0]]))
    assert mu == 3.0 and var == pytest.approx(0.5)
    # eq. 53/54: below 0.24 DN² only the upper limit 0.40/K
    s, limited, v = emva.temporal_dark_noise(0.1, K=2.0)
    assert limited and v == 0.24 and s == pytest.approx(math.sqrt(0.24 - 1 / 12) / 2.0) and s < 0.40 / 2.0
    s, limited, _ = emva.temporal_dark_noise(1.0 + 1 / 12, K=0.5)
    assert not limited and s == pytest.approx(2.0)
    # eq. 26: SNR = 1 at μ_p.min under the linear model of eq. 21
    eta, K, v = 0.5, 0.25, 3.0
    mp = emva.sensitivity_threshold(eta, v, K)
    assert eta * mp / math.sqrt(v / K**2 + eta * mp) == pytest.approx(1.0)
    # eq. 4: 1 W/m² for 1 s on 1 µm² at 500 nm
    photons = 1e-12 * 500e-9 / (6.62607015e-34 * 299792458.0)
    assert emva.photons_per_pixel(1.0, 1.0, 1.0, 500.0) == pytest.approx(photons)
    # section 6.9: an exactly linear response has no deviation
    a0, a1, dev = emva.linearity_fit([1.0, 2.0, 3.0, 4.0], [12.0, 14.0, 16.0, 18.0])
    assert (a0, a1) == (pytest.approx(10.0), pytest.approx(2.0)) and np.abs(dev).max() < 1e-9


def test_series_is_checked():
    frames = np.zeros((3, 2, 4, 4), np.uint16)
    ok = dict(wavelength_nm=550.0, pixel_area_um2=10.0, exposure_times_s=[1.0, 2.0, 3.0], mu_p=[0.0, 1.0, 2.0],
              bright_pairs=frames, dark_pairs=frames)
    emva.EmvaSeries(**ok)
    for change in (dict(mu_p=[0.0, 2.0, 1.0]), dict(bright_pairs=frames[:2]), dict(dark_pairs=frames[:1]),
                   dict(dark_pairs=frames[:, :, :3]), dict(spatial_dark=frames[0]), dict(wavelength_nm=0.0)):
        with pytest.raises(ConfigError):
            emva.EmvaSeries(**{**ok, **change})
    # one dark pair serves all steps only at one exposure time
    emva.EmvaSeries(**{**ok, "exposure_times_s": [1.0, 1.0, 1.0], "dark_pairs": frames[:1]})
    with pytest.raises(ConfigError):
        emva.analyse(emva.EmvaSeries(**ok), saturation="knee")


if __name__ == "__main__":  # prints the measured-vs-configured table
    s, r = make_series(CAMERA)
    print(table(emva.analyse(s), CAMERA.expected(r)))


def test_column_and_row_parts_keep_their_axes_on_a_non_square_frame():
    """Issue 18's planted slip: M (rows) and N (columns) swapped.  On a 40 × 200 frame with a strong
    pixel pattern (σ 10 DN) and a weak column pattern (σ 1 DN), swapping 1/M and 1/N moves the column
    part by 100·(1/40 − 1/200) = 2 DN² (200 %), and swapping the axes puts it in the rows."""
    from spectracam.evaluation.emva1288 import spatial_statistics

    rng = np.random.default_rng(5)
    M, N, L = 40, 200, 8
    col = rng.normal(0, 1.0, N)
    pix = rng.normal(0, 10.0, (M, N))
    stack = 500 + pix[None] + col[None, None, :] + rng.normal(0, 0.5, (L, M, N))
    s = spatial_statistics(stack)
    # the column part: the sample variance of the column offsets, within the estimator's spread
    # (pixel noise left in a column mean, 100/40 DN², has sd ~ 2.5·√(2/199) ≈ 0.25 DN²)
    assert s["s2_y_col"] == pytest.approx(np.var(col, ddof=1), abs=0.6)
    assert abs(s["s2_y_row"]) < 0.6 and s["s2_y_pixel"] == pytest.approx(100.0, rel=0.05)
