"""EMVA 1288 Release 4.0 *Linear* characterisation: the analysis half (frames in, quantities out).

The European Machine Vision Association's standard 1288, Release 4.0 (June 2021), comes as two
documents.  *Linear* ("EMVA1288Linear_4.0Release.pdf", also ISO 24942) characterises cameras with a
linear response through the photon transfer curve; *General* drops the photon transfer curve for
nonlinear or pre-processed cameras.  The quantities computed here (system gain from the photon
transfer slope, η = R/K, σ_d, ...) are those of the **Linear** document, and the section and
equation numbers below refer to it.  (The PDF itself could not be read while this was written: the
numbers and the Release 4 changes — the 0.1-0.2 % saturation definition, the mean-deviation
linearity error, the mean-difference correction of eq. 18, the SNR = 1 threshold of eq. 26 — were
taken from the EMVA reference implementation's issue tracker and from notes that quote the
document; check them against the PDF.)

Everything is pure numpy (plus :mod:`statistics` from the standard library for the normal quantile).
The caller measures (or simulates) the frames and computes the photon count per pixel; this module
only evaluates them:

* :class:`EmvaSeries` — the input: a photon-transfer series of frame pairs with dark pairs at each
  exposure time, and optionally the two stacks of the nonuniformity measurement.
* :func:`analyse` — the standard's quantities from a series.
* :func:`expected` — the same quantities for an ideal linear camera from its configured parameters,
  by the standard's definitions, to compare measured against configured.
* helpers: :func:`photons_per_pixel` (eq. 4), :func:`pair_statistics` (eqs. 16, 18),
  :func:`temporal_dark_noise` (eqs. 53, 54), :func:`sensitivity_threshold` (eq. 26),
  :func:`linearity_fit` (section 6.9), :func:`spatial_statistics` (section 8, eqs. 35-42).

Choices the standard leaves to the evaluator, and departures from it, are named where they are made:
the photon-transfer regression has a free offset (the EMVA reference implementation forces it through
the origin; that slope is returned too, in ``details``); the saturation point is interpolated between
steps when no step has 0.1-0.2 % of its pixels at the maximum value (the standard defines the
saturation exposure as one that has); the temporal dark noise is the dark variance extrapolated to
zero exposure time when the exposure time is varied (as the reference implementation does); the
spatial variances are computed from the frames as given, without the high-pass filter of section
8.1 that removes the light source's nonuniformity (pass frames of uniform illumination).

The steps of :func:`analyse`, with the standard's sections (Release 4.0 Linear):

1. Mean and temporal variance of every bright and dark pair (eqs. 16, 18; :func:`pair_statistics`).
2. Saturation (sections 2.7, 6.5): ``saturation="pixel_fraction"`` (Release 4) — the exposure at
   which 0.1-0.2 % of the pixels show ``max_dn`` (see ``_saturation_by_pixel_fraction``);
   ``"variance_max"`` (Release 3.1, and the fallback when ``max_dn`` is None or never reached) —
   the step where the temporal variance σ²_y peaks.  μ_y.sat is the dark-corrected mean there.
3. Photon transfer (section 6.6, eq. 50): σ²_y − σ²_y.dark = K·(μ_y − μ_y.dark) + c, a linear
   regression over the steps from 0 to 70 % of μ_y.sat − μ_y.dark; K is its slope.
4. Responsivity (section 6.6, eq. 49): μ_y − μ_y.dark = R·μ_p, regression through the origin over
   the same range; quantum efficiency η = R/K (eq. 52).
5. Temporal dark noise (section 6.6, eqs. 53, 54): σ_d = √(σ²_y.dark − 1/12)/K, with the
   0.24 DN² rule (:func:`temporal_dark_noise`).  With ≥ 3 distinct exposure times σ²_y.dark is
   the dark variance extrapolated to zero exposure time (intercept of a line against t_exp),
   so that the dark current's shot noise is not counted as dark noise; otherwise the mean of the
   dark pairs' variances.
6. Saturation capacity μ_e.sat = η·μ_p.sat, SNR_max = √μ_e.sat (section 2), in dB 20·log10.
7. Absolute sensitivity threshold μ_p.min (eq. 26; :func:`sensitivity_threshold`) and dynamic
   range DR = μ_p.sat/μ_p.min (eq. 28), in dB 20·log10.
8. Dark current (section 7.1): slope of μ_y.dark against t_exp divided by K (e⁻/s); also, in
   ``details``, from the slope of σ²_y.dark against t_exp divided by K².
9. Linearity (section 6.9): the relative-weight regression of μ_y − μ_y.dark on μ_p over 5-95 %
   of saturation (:func:`linearity_fit`); ``linearity="mean_abs"`` (Release 4): ``LE = mean |δ_y|``;
   ``"half_range"`` (Release 3.1): LE = (max δ_y − min δ_y)/2.  Both are in ``details``.
10. DSNU1288 = s_y.dark/K in e⁻ and PRNU1288 = √(s²_y.50 − s²_y.dark)/(μ_y.50 − μ_y.dark) in %
    (section 8, eqs. 66, 67; :func:`spatial_statistics`), with the temporal-noise correction
    s²_y = s²_y.measured − σ²_y.stack/L.  NaN without the spatial stacks.

References
----------
.. [EMVA1288] see docs/references.md
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from statistics import NormalDist
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from spectracam.core.errors import ConfigError

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["DARK_VARIANCE_FLOOR_DN2", "LINEARITY_FIT_RANGE", "LINEARITY_METHODS", "PLANCK_H_J_S",
           "RESULT_KEYS", "SATURATED_FRACTION_TARGET", "SATURATED_FRACTION_WINDOW", "SATURATION_METHODS",
           "SENSITIVITY_FIT_MAX", "SIGMA_Q2_DN2", "SPEED_OF_LIGHT_M_S", "EmvaSeries", "analyse", "expected",
           "linearity_fit", "pair_statistics", "photons_per_pixel", "sensitivity_threshold",
           "spatial_statistics", "temporal_dark_noise"]

#: Quantisation noise variance of a uniform quantiser with a step of 1 DN, DN² (section 2, noise model).
SIGMA_Q2_DN2 = 1.0 / 12.0
#: Below this dark variance (DN²) the temporal dark noise is dominated by quantisation and only an
#: upper limit σ_d < 0.40/K is given (section 6.6, eq. 54).
DARK_VARIANCE_FLOOR_DN2 = 0.24
#: Saturation (sections 2.7 and 6.5): the exposure at which between 0.1 and 0.2 % of the pixels show
#: the maximum digital value.  Where no step of the series falls in the window the exposure is
#: interpolated to the window's middle.
SATURATED_FRACTION_WINDOW = (0.001, 0.002)
SATURATED_FRACTION_TARGET = 0.0015
#: Photon transfer and responsivity fits use the points from 0 to 70 % of saturation (section 6.6).
SENSITIVITY_FIT_MAX = 0.70
#: The linearity fit uses the points from 5 to 95 % of saturation (section 6.9).
LINEARITY_FIT_RANGE = (0.05, 0.95)

PLANCK_H_J_S = 6.62607015e-34
SPEED_OF_LIGHT_M_S = 299792458.0

SATURATION_METHODS = ("pixel_fraction", "variance_max")
LINEARITY_METHODS = ("mean_abs", "half_range")

#: The keys of the main results of :func:`analyse` and :func:`expected`.
RESULT_KEYS = (
    "system_gain_DN_per_e",
    "quantum_efficiency",
    "dark_noise_e",
    "saturation_capacity_e",
    "snr_max_db",
    "dynamic_range_db",
    "dark_current_e_per_s",
    "dsnu_e",
    "prnu_percent",
    "linearity_error_percent",
)

_NORMAL = NormalDist()


# --------------------------------------------------------------------------------------------------
# Input
# --------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class EmvaSeries:
    """One EMVA 1288 measurement of a monochrome sensor (or one colour channel) at one wavelength.

    Photon transfer series (section 6 allows varying either the exposure time at constant
    irradiance or the irradiance at constant exposure time; section 6.5 asks for at least 50 steps,
    equally spaced, from dark to beyond saturation):

    * ``exposure_times_s`` — shape ``(n,)``, seconds: the exposure time of each step.
    * ``mu_p`` — shape ``(n,)``: mean number of photons collected by one pixel's area during the
      exposure of each step, μ_p = A·E·t_exp·λ/(h·c) (eq. 4; :func:`photons_per_pixel`).
      Strictly increasing, ≥ 0.
    * ``bright_pairs`` — shape ``(n, 2, M, N)``: two frames (A, B) of digital numbers (DN) per step,
      taken under the same conditions.  Any real dtype (uint16 raw data is fine); not copied.
    * ``dark_pairs`` — shape ``(n, 2, M, N)``: two dark frames per step at that step's exposure time
      (section 6.5), or ``(1, 2, M, N)``: one dark pair for all steps when every step has the same
      exposure time (irradiance varied).  With fewer than three distinct exposure times the dark
      current is not evaluated (NaN).

    Spatial nonuniformity (section 8): optional; without it DSNU and PRNU are NaN.

    * ``spatial_dark`` — shape ``(L, M, N)``, DN: L dark frames.
    * ``spatial_bright`` — shape ``(L', M, N)``, DN: L' frames at about 50 % of saturation, same
      exposure time as ``spatial_dark``.  The standard recommends L = 100 (fewer are allowed: the
      residual temporal noise σ²/L is subtracted).
    * ``spatial_mu_p`` — photons per pixel of the bright stack (reported only).
    * ``spatial_exposure_time_s`` — their exposure time (reported only).

    Camera and geometry:

    * ``max_dn`` — the largest digital value the camera outputs, 2^k − 1 for a k-bit output.  It is
      needed for the Release 4 saturation definition (fraction of pixels at the maximum value); with
      ``None`` the saturation falls back to the maximum of the photon transfer variance.
    * ``wavelength_nm`` — wavelength of the (narrow-band) light, nm.
    * ``pixel_area_um2`` — pixel area A, µm² (for the per-area quantities in ``details``).
    """

    wavelength_nm: float
    pixel_area_um2: float
    exposure_times_s: np.ndarray
    mu_p: np.ndarray
    bright_pairs: np.ndarray
    dark_pairs: np.ndarray
    max_dn: float | None = None
    spatial_dark: np.ndarray | None = None
    spatial_bright: np.ndarray | None = None
    spatial_mu_p: float | None = None
    spatial_exposure_time_s: float | None = None

    def __post_init__(self):
        def put(name, value):
            object.__setattr__(self, name, value)

        for name in ("wavelength_nm", "pixel_area_um2"):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and v > 0):
                raise ConfigError(name, getattr(self, name), "a finite number > 0")
            put(name, v)
        t = np.asarray(self.exposure_times_s, dtype=np.float64)
        mu_p = np.asarray(self.mu_p, dtype=np.float64)
        if t.ndim != 1 or t.size < 3:
            raise ConfigError("exposure_times_s", t.shape, "a 1-D array of at least 3 exposure times")
        if mu_p.shape != t.shape:
            raise ConfigError("mu_p", mu_p.shape, f"the shape of exposure_times_s, {t.shape}")
        if not (np.isfinite(t).all() and (t >= 0).all()):
            raise ConfigError("exposure_times_s", t, "finite and >= 0")
        if not (np.isfinite(mu_p).all() and (mu_p >= 0).all() and (np.diff(mu_p) > 0).all()):
            raise ConfigError("mu_p", mu_p, "finite, >= 0 and strictly increasing (dark to saturation)")
        put("exposure_times_s", t)
        put("mu_p", mu_p)
        n = t.size

        bright = np.asarray(self.bright_pairs)
        if bright.ndim != 4 or bright.shape[:2] != (n, 2) or min(bright.shape[2:]) < 2:
            raise ConfigError("bright_pairs", bright.shape, f"shape (n, 2, M, N) with n = {n} and M, N >= 2")
        dark = np.asarray(self.dark_pairs)
        if dark.ndim != 4 or dark.shape[1] != 2 or dark.shape[0] not in (1, n) or dark.shape[2:] != bright.shape[2:]:
            raise ConfigError("dark_pairs", dark.shape, f"shape ({n} or 1, 2, {bright.shape[2]}, {bright.shape[3]})")
        if dark.shape[0] == 1 and n > 1 and np.ptp(t) > 0:
            raise ConfigError("dark_pairs", dark.shape, "one dark pair per step when the exposure time varies")
        for name, a in (("bright_pairs", bright), ("dark_pairs", dark)):
            if not (np.issubdtype(a.dtype, np.integer) or np.issubdtype(a.dtype, np.floating)):
                raise ConfigError(name, a.dtype, "an integer or floating-point array of DN")
        put("bright_pairs", bright)
        put("dark_pairs", dark)

        if self.max_dn is not None:
            m = float(self.max_dn)
            if not (math.isfinite(m) and m > 0):
                raise ConfigError("max_dn", self.max_dn, "None or a finite number > 0 (2**bits - 1)")
            put("max_dn", m)

        if (self.spatial_dark is None) != (self.spatial_bright is None):
            raise ConfigError("spatial_dark/spatial_bright", "one missing", "both stacks or neither")
        if self.spatial_dark is not None:
            for name in ("spatial_dark", "spatial_bright"):
                s = np.asarray(getattr(self, name))
                if s.ndim != 3 or s.shape[0] < 2 or s.shape[1:] != bright.shape[2:]:
                    raise ConfigError(name, s.shape, f"shape (L, {bright.shape[2]}, {bright.shape[3]}) with L >= 2")
                put(name, s)

    @property
    def frame_shape(self) -> tuple[int, int]:
        return tuple(self.bright_pairs.shape[2:])

    @property
    def n_steps(self) -> int:
        return int(self.mu_p.size)


def photons_per_pixel(irradiance_W_m2: ArrayLike, exposure_time_s: ArrayLike, pixel_area_um2: float,
                      wavelength_nm: float) -> np.ndarray:
    """Mean number of photons on one pixel, μ_p = A·E·t_exp·λ/(h·c) (eq. 4).

    Parameters
    ----------
    irradiance_W_m2 : array_like
        Irradiance E on the sensor, W/m² (broadcasts with ``exposure_time_s``).
    exposure_time_s : array_like
        Exposure time t_exp, s.
    pixel_area_um2 : float
        Pixel area A, µm².
    wavelength_nm : float
        The light's wavelength λ (monochromatic), nm.

    Returns
    -------
    ndarray
        μ_p, photons (float64, the broadcast shape).
    """
    A = pixel_area_um2 * 1e-12
    lam = wavelength_nm * 1e-9
    energy_J = np.asarray(irradiance_W_m2, dtype=np.float64) * exposure_time_s * A
    return energy_J * lam / (PLANCK_H_J_S * SPEED_OF_LIGHT_M_S)


# --------------------------------------------------------------------------------------------------
# Building blocks
# --------------------------------------------------------------------------------------------------


def pair_statistics(frame_a: ArrayLike, frame_b: ArrayLike) -> tuple[float, float]:
    """Mean and temporal variance from two frames taken under the same conditions.

    μ_y = ½(μ[A] + μ[B]) (eq. 16) and
    σ²_y = 1/(2MN)·Σ(y_A − y_B)² − ½(μ[A] − μ[B])² (eq. 18; the correction by the difference of the
    two frames' means is new in Release 4).  The difference removes every fixed pattern, so σ²_y is
    the purely temporal variance.

    Parameters
    ----------
    frame_a, frame_b : array_like
        ``(M, N)`` the two frames, DN (or any linear unit).

    Returns
    -------
    mu_y : float
        The mean, in the frames' unit (DN).
    var_y : float
        The temporal variance, that unit squared (DN²).
    """
    a = np.asarray(frame_a, dtype=np.float64)
    b = np.asarray(frame_b, dtype=np.float64)
    ma, mb = float(a.mean()), float(b.mean())
    d = a - b
    var = 0.5 * float(np.mean(d * d)) - 0.5 * (ma - mb) ** 2
    return 0.5 * (ma + mb), var


def temporal_dark_noise(var_y_dark_DN2: float, K: float) -> tuple[float, bool, float]:
    """Temporal dark noise σ_d = √(σ²_y.dark − σ²_q)/K in e⁻ (section 6.6, eq. 53).

    When σ²_y.dark < 0.24 DN² the quantisation noise dominates and the standard gives only the upper
    limit σ_d < 0.40/K (eq. 54): σ²_y.dark is then set to 0.24 DN² (√(0.24 − 1/12) = 0.396).

    Parameters
    ----------
    var_y_dark_DN2 : float
        The temporal dark variance σ²_y.dark, DN².
    K : float
        The system gain, DN/e⁻.

    Returns
    -------
    sigma_d_e : float
        σ_d, e⁻ rms.
    is_upper_limit : bool
        Whether it is eq. 54's upper limit.
    var_y_dark_used_DN2 : float
        The dark variance used, DN².
    """
    limited = var_y_dark_DN2 < DARK_VARIANCE_FLOOR_DN2
    v = DARK_VARIANCE_FLOOR_DN2 if limited else float(var_y_dark_DN2)
    return math.sqrt(v - SIGMA_Q2_DN2) / K, bool(limited), v


def sensitivity_threshold(eta: float, var_y_dark_DN2: float, K: float) -> float:
    """Absolute sensitivity threshold μ_p.min in photons: the exposure at which SNR = 1 (eq. 26).

    Solving η·μ_p = √(σ²_d + σ²_q/K² + η·μ_p) (the SNR of eq. 21 set to 1) gives
    μ_p.min = (1/η)·(√(σ²_y.dark/K² + 1/4) + 1/2), since σ²_d + σ²_q/K² = σ²_y.dark/K².
    (Release 3.1 used the approximation (σ_y.dark/K + 1/2)/η.)

    Parameters
    ----------
    eta : float
        The quantum efficiency η, e⁻ per photon.
    var_y_dark_DN2 : float
        The temporal dark variance σ²_y.dark, DN² (as :func:`temporal_dark_noise` used it).
    K : float
        The system gain, DN/e⁻.

    Returns
    -------
    float
        μ_p.min, photons per pixel.
    """
    return (math.sqrt(var_y_dark_DN2 / K**2 + 0.25) + 0.5) / eta


def linearity_fit(x: ArrayLike, y: ArrayLike) -> tuple[float, float, np.ndarray]:
    """The standard's linearity regression (section 6.9): y ≈ a0 + a1·x with relative weights.

    Minimises Σ((y − a0 − a1·x)/y)², i.e. a least-squares fit with weights 1/y², so every point
    counts by its relative deviation.

    Parameters
    ----------
    x : array_like
        ``(n,)`` the exposure of each step (photons per pixel, or anything proportional), n ≥ 3.
    y : array_like
        ``(n,)`` the dark-subtracted mean signal of each step, DN, all > 0.

    Returns
    -------
    a0, a1 : float
        The offset (DN) and the slope.
    deviation_percent : ndarray
        ``(n,)`` δ_y = 100·(y − (a0 + a1·x))/(a0 + a1·x), %.

    Raises
    ------
    ConfigError
        Shapes that differ, fewer than 3 points, or a signal ≤ 0.
    """
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    if x.shape != y.shape or x.size < 3 or not (y > 0).all():
        raise ConfigError("linearity points", f"{x.size} points", "at least 3, all with a signal > 0")
    A = np.column_stack([1.0 / y, x / y])
    (a0, a1), *_ = np.linalg.lstsq(A, np.ones_like(y), rcond=None)
    fit = a0 + a1 * x
    return float(a0), float(a1), 100.0 * (y - fit) / fit


def spatial_statistics(stack: ArrayLike) -> dict:
    """Spatial mean and variances of a stack of L frames (section 8; eqs. 35-42).

    ⟨y⟩ is the average of the L frames; σ²_y.stack the mean over pixels of the per-pixel temporal
    variance (unbiased, L − 1).  The spatial variance of ⟨y⟩ still holds σ²_y.stack/L of temporal
    noise, which is subtracted: s²_y = s²_y.measured − σ²_y.stack/L.  Release 4 also splits s²_y into
    column, row and pixel parts: the variances of the column and row averages (minus their temporal
    parts σ²/(L·M), σ²/(L·N)) are s²_cav = s²_col + s²_pixel/M and s²_rav = s²_row + s²_pixel/N, and
    s²_y = s²_col + s²_row + s²_pixel.

    Parameters
    ----------
    stack : array_like
        ``(L, M, N)`` L frames, DN.

    Returns
    -------
    dict
        ``L``; ``mu_y`` (DN); ``var_y_stack``, ``s2_y_measured``, ``s2_y``, ``s2_y_col``, ``s2_y_row``,
        ``s2_y_pixel`` (DN²).
    """
    s = np.asarray(stack)
    L, M, N = s.shape
    total = np.zeros((M, N))
    total_sq = np.zeros((M, N))
    for frame in s:  # frame by frame: no float64 copy of the whole stack
        f = frame.astype(np.float64)
        total += f
        total_sq += f * f
    avg = total / L
    var_stack = float(np.mean((total_sq - L * avg * avg) / (L - 1)))
    mu = float(avg.mean())
    s2_measured = float(np.var(avg, ddof=1))
    s2 = s2_measured - var_stack / L
    cav = float(np.var(avg.mean(axis=0), ddof=1)) - var_stack / (L * M)  # variance of the N column means
    rav = float(np.var(avg.mean(axis=1), ddof=1)) - var_stack / (L * N)  # variance of the M row means
    system = np.array([[1.0, 0.0, 1.0 / M], [0.0, 1.0, 1.0 / N], [1.0, 1.0, 1.0]])
    s2_col, s2_row, s2_pixel = np.linalg.solve(system, [cav, rav, s2])
    return {
        "L": int(L), "mu_y": mu, "var_y_stack": var_stack, "s2_y_measured": s2_measured, "s2_y": s2,
        "s2_y_col": float(s2_col), "s2_y_row": float(s2_row), "s2_y_pixel": float(s2_pixel),
    }


def _slope_intercept(x, y):
    slope, intercept = np.polyfit(np.asarray(x, float), np.asarray(y, float), 1)
    return float(slope), float(intercept)


def _sqrt_or_nan(v):
    return math.sqrt(v) if v >= 0 else math.nan


def _db(ratio):
    return 20.0 * math.log10(ratio) if ratio > 0 else math.nan


# --------------------------------------------------------------------------------------------------
# Saturation
# --------------------------------------------------------------------------------------------------


def _saturation_by_pixel_fraction(mu_p, frac, n_samples):
    """(index_lo, weight, how) of the saturation point, or None (no step reaches 0.1 %).

    Sections 2.7 and 6.5: the saturation exposure is the one where 0.1-0.2 % of the pixels show
    the maximum value.  A step inside that window is taken as it is (the one nearest 0.15 %);
    otherwise the exposure where 0.15 % is reached is interpolated between the two steps around it,
    linearly in the normal quantile of the fraction (for a Gaussian spread of pixel values that
    quantile is nearly linear in the exposure).  A step with no saturated pixel counts as half a
    pixel.
    """
    lo, hi = SATURATED_FRACTION_WINDOW
    inside = np.flatnonzero((frac >= lo) & (frac <= hi))
    if inside.size:
        i = int(inside[np.argmin(np.abs(frac[inside] - SATURATED_FRACTION_TARGET))])
        return i, 0.0, "step in the 0.1-0.2 % window"
    above = np.flatnonzero(frac > SATURATED_FRACTION_TARGET)
    if above.size == 0:
        return None
    j = int(above[0])
    if j == 0:
        raise ConfigError("bright_pairs", "first step", "unsaturated: more than 0.2 % of its pixels are at max_dn")
    i = j - 1
    floor = 0.5 / n_samples
    zi = _NORMAL.inv_cdf(min(max(frac[i], floor), 1 - floor))
    zj = _NORMAL.inv_cdf(min(max(frac[j], floor), 1 - floor))
    zt = _NORMAL.inv_cdf(SATURATED_FRACTION_TARGET)
    w = (zt - zi) / (zj - zi) if zj > zi else 0.0
    return i, float(min(max(w, 0.0), 1.0)), "interpolated to 0.15 % between two steps"


# --------------------------------------------------------------------------------------------------
# Analysis
# --------------------------------------------------------------------------------------------------


def analyse(series: EmvaSeries, *, saturation: str = "pixel_fraction", linearity: str = "mean_abs") -> dict:
    """Evaluate an EMVA 1288 Release 4.0 Linear measurement.

    Steps 1-10, with the standard's sections (Release 4.0 Linear), are listed in the module docstring.

    Parameters
    ----------
    series : EmvaSeries
        The measurement: bright and dark frame pairs per step with their photons per pixel μ_p and exposure
        times, and optionally the two stacks of the nonuniformity measurement.
    saturation : {"pixel_fraction", "variance_max"}
        The saturation point (step 2): 0.1-0.2 % of the pixels at ``max_dn`` (Release 4), or the step where the
        temporal variance peaks (Release 3.1; also the fallback).
    linearity : {"mean_abs", "half_range"}
        The linearity error reported (step 9): ``mean |δ_y|`` (Release 4) or (max δ_y − min δ_y)/2 (Release 3.1).

    Returns
    -------
    dict
        The keys of :data:`RESULT_KEYS` (floats; ``quantum_efficiency`` as a fraction 0-1), plus ``"curves"``
        (per-step arrays for plots: photon transfer, SNR, linearity deviation, saturated fraction, and the masks
        of the steps each fit used — ``sensitivity_fit_mask`` (steps 3./4.), ``linearity_fit_mask`` (step 9.) —
        and of the steps beyond the saturation point, ``beyond_saturation_mask``, which no fit uses) and
        ``"details"`` (intermediate scalars, the methods used and the alternative definitions).

    Raises
    ------
    spectracam.core.errors.ConfigError
        An unknown ``saturation`` or ``linearity``, or a series the fits cannot use (a first step already
        saturated, fewer than 3 steps below 70 % of saturation, a variance that does not grow with the signal).

    References
    ----------
    .. [EMVA1288] see docs/references.md; Release 4.0 Linear, and Release 3.1 for the alternative definitions.
    """
    _check_choice("saturation", saturation, SATURATION_METHODS)
    _check_choice("linearity", linearity, LINEARITY_METHODS)
    st = _step_statistics(series)
    sat = _saturation_point(series, st, saturation)
    gain = _photon_transfer(series.mu_p, st, sat)
    dark = _dark_noise(st, gain.K)
    cap = _saturation_capacity(gain, sat.mu_p, dark.var_used, series.pixel_area_um2)
    current = _dark_current(st, gain.K, dark.var_slope)
    lin = _linearity(series.mu_p, st.signal, sat)
    nu = _nonuniformity(series, gain.K, sat.signal)
    le = lin.mean_abs if linearity == "mean_abs" else lin.half_range
    quantities = _quantities(gain.K, gain.eta, dark.sigma_d, cap.mu_e_sat, cap.dynamic_range, current.e_per_s,
                             nu.dsnu, nu.prnu, le)
    details = {**sat.details, **gain.details, **dark.details, **cap.details, **current.details, **lin.details,
               **nu.details}
    return {**quantities, "curves": _curves(series, st, gain, dark.var_used, sat.mu_p, lin), "details": details}


def _check_choice(name: str, value, allowed: tuple) -> None:
    """Refuse a method name that is not one of ``allowed`` (ConfigError naming it)."""
    if value not in allowed:
        raise ConfigError(name, value, f"one of {', '.join(allowed)}")


def _quantities(K, eta, sigma_d, mu_e_sat, dynamic_range, dark_current, dsnu, prnu, linearity_error) -> dict:
    """The main results keyed by :data:`RESULT_KEYS`; SNR_max = √μ_e.sat (section 2) and DR (eq. 28) in dB."""
    return dict(zip(RESULT_KEYS, (K, eta, sigma_d, mu_e_sat, _db(math.sqrt(mu_e_sat)), _db(dynamic_range),
                                  dark_current, dsnu, prnu, linearity_error)))


class _StepStatistics(NamedTuple):
    """Step 1: per-step means and temporal variances of the bright and dark pairs (eqs. 16, 18), DN and DN²."""

    mu_y: np.ndarray
    var_y: np.ndarray
    saturated_fraction: np.ndarray
    mu_d: np.ndarray            # one per dark pair
    var_d: np.ndarray
    t_dark: np.ndarray          # the dark pairs' exposure times
    mu_y_dark: np.ndarray       # the dark pairs' values, one per step
    var_y_dark: np.ndarray
    signal: np.ndarray          # μ_y − μ_y.dark, DN
    excess_var: np.ndarray      # σ²_y − σ²_y.dark, DN²


def _step_statistics(series: EmvaSeries) -> _StepStatistics:
    """Step 1: mean and temporal variance of every bright and dark pair (eqs. 16, 18), dark-corrected per step."""
    n = series.n_steps
    mu_y, var_y, frac = _bright_statistics(series)
    nd = series.dark_pairs.shape[0]
    mu_d = np.empty(nd)
    var_d = np.empty(nd)
    for i in range(nd):
        mu_d[i], var_d[i] = pair_statistics(*series.dark_pairs[i])
    t_dark = series.exposure_times_s if nd == n else series.exposure_times_s[:1]
    mu_y_dark = np.broadcast_to(mu_d, (n,)) if nd == 1 else mu_d
    var_y_dark = np.broadcast_to(var_d, (n,)) if nd == 1 else var_d
    return _StepStatistics(mu_y, var_y, frac, mu_d, var_d, t_dark, mu_y_dark, var_y_dark, mu_y - mu_y_dark,
                           var_y - var_y_dark)


def _bright_statistics(series: EmvaSeries) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(μ_y, σ²_y, fraction of pixels at max_dn)`` per step of the bright pairs (eqs. 16, 18; section 6.5)."""
    n = series.n_steps
    M, N = series.frame_shape
    mu_y = np.empty(n)
    var_y = np.empty(n)
    frac = np.zeros(n)
    for i in range(n):
        a, b = series.bright_pairs[i]
        mu_y[i], var_y[i] = pair_statistics(a, b)
        if series.max_dn is not None:
            frac[i] = (np.count_nonzero(a >= series.max_dn) + np.count_nonzero(b >= series.max_dn)) / (2.0 * M * N)
    return mu_y, var_y, frac


class _Saturation(NamedTuple):
    """Step 2: the saturation point (sections 2.7, 6.5)."""

    mu_p: float       # μ_p.sat, photons
    signal: float     # μ_y.sat − μ_y.dark, DN
    details: dict


def _saturation_point(series: EmvaSeries, st: _StepStatistics, saturation: str) -> _Saturation:
    """Step 2: μ_p.sat and μ_y.sat − μ_y.dark, interpolated between the steps around it (sections 2.7, 6.5)."""
    mu_p, signal = series.mu_p, st.signal
    i_sat, w_sat, how, method = _saturation_step(series, st, saturation)
    j_sat = min(i_sat + 1, series.n_steps - 1)
    mu_p_sat = float(mu_p[i_sat] + w_sat * (mu_p[j_sat] - mu_p[i_sat]))
    signal_sat = float(signal[i_sat] + w_sat * (signal[j_sat] - signal[i_sat]))
    if not signal_sat > 0:
        raise ConfigError("bright_pairs", "saturation signal", "above the dark level")
    return _Saturation(mu_p_sat, signal_sat, dict(saturation_method=method, saturation_how=how,
                                                  saturation_index=i_sat, mu_p_sat=mu_p_sat,
                                                  mu_y_sat_minus_dark_DN=signal_sat))


def _saturation_step(series: EmvaSeries, st: _StepStatistics, saturation: str) -> tuple[int, float, str, str]:
    """``(index_lo, weight, how, method)``: Release 4's 0.1-0.2 % of pixels at max_dn, else the variance maximum."""
    sat = None
    method = saturation
    if saturation == "pixel_fraction":
        if series.max_dn is None:
            method = "variance_max (fallback: max_dn is None)"
        else:
            M, N = series.frame_shape
            sat = _saturation_by_pixel_fraction(series.mu_p, st.saturated_fraction, 2 * M * N)
            if sat is None:
                method = "variance_max (fallback: no step has 0.1 % of its pixels at max_dn)"
    if sat is None:
        sat = (int(np.argmax(st.var_y)), 0.0, "step of maximum temporal variance")
    return (*sat, method)


class _Gain(NamedTuple):
    """Steps 3 and 4: system gain K (DN/e⁻), quantum efficiency η and the steps their fits used."""

    K: float
    eta: float
    in_range: np.ndarray
    details: dict


def _photon_transfer(mu_p: np.ndarray, st: _StepStatistics, sat: _Saturation) -> _Gain:
    """Steps 3, 4: K from the photon transfer (eq. 50), R through the origin (eq. 49), η = R/K (eq. 52), 0-70 %."""
    signal, excess_var = st.signal, st.excess_var
    in_range = (mu_p <= sat.mu_p) & (signal <= SENSITIVITY_FIT_MAX * sat.signal)
    if np.count_nonzero(in_range) < 3:
        raise ConfigError("mu_p", f"{np.count_nonzero(in_range)} steps below 70 % of saturation", "at least 3")
    K, ptc_offset = _slope_intercept(signal[in_range], excess_var[in_range])
    if not K > 0:
        raise ConfigError("bright_pairs", f"photon transfer slope {K:g}", "a variance that grows with the signal")
    x, y = signal[in_range], excess_var[in_range]
    K_origin = float(np.dot(x, y) / np.dot(x, x))
    p = mu_p[in_range]
    R = float(np.dot(p, signal[in_range]) / np.dot(p, p))
    eta = R / K
    return _Gain(K, eta, in_range, dict(K_through_origin=K_origin, ptc_offset_DN2=ptc_offset,
                                        responsivity_DN_per_photon=R,
                                        n_sensitivity_points=int(np.count_nonzero(in_range))))


class _DarkNoise(NamedTuple):
    """Step 5: the temporal dark noise and the dark variance it came from."""

    sigma_d: float       # e⁻ (or its upper limit)
    var_used: float      # σ²_y.dark after the 0.24 DN² rule, DN²
    var_slope: float     # slope of σ²_y.dark against t_exp, DN²/s (NaN with fewer than 3 exposure times)
    details: dict


def _dark_noise(st: _StepStatistics, K: float) -> _DarkNoise:
    """Step 5: σ_d from σ²_y.dark extrapolated to t_exp = 0 (or the dark pairs' mean) (section 6.6, eqs. 53, 54)."""
    details: dict = {}
    if np.unique(st.t_dark).size >= 3:
        var_dark_slope, var_dark_0 = _slope_intercept(st.t_dark, st.var_d)
        details["var_y_dark_how"] = "extrapolated to t_exp = 0"
    else:
        var_dark_slope, var_dark_0 = math.nan, float(np.mean(st.var_d))
        details["var_y_dark_how"] = "mean of the dark pairs"
    sigma_d, upper_limit, var_dark_used = temporal_dark_noise(var_dark_0, K)
    details.update(var_y_dark_DN2=var_dark_0, var_y_dark_min_texp_DN2=float(st.var_d[np.argmin(st.t_dark)]),
                   dark_noise_is_upper_limit=upper_limit)
    return _DarkNoise(sigma_d, var_dark_used, var_dark_slope, details)


class _Capacity(NamedTuple):
    """Steps 6 and 7: saturation capacity μ_e.sat (e⁻) and dynamic range μ_p.sat/μ_p.min."""

    mu_e_sat: float
    dynamic_range: float
    details: dict


def _saturation_capacity(gain: _Gain, mu_p_sat: float, var_dark_used: float, area: float) -> _Capacity:
    """Steps 6, 7: μ_e.sat = η·μ_p.sat (section 2), μ_p.min (eq. 26) and DR = μ_p.sat/μ_p.min (eq. 28)."""
    K, eta = gain.K, gain.eta
    mu_e_sat = eta * mu_p_sat
    mu_p_min = sensitivity_threshold(eta, var_dark_used, K)
    dr = mu_p_sat / mu_p_min
    return _Capacity(mu_e_sat, dr, dict(
        mu_e_sat=mu_e_sat, mu_p_min=mu_p_min, mu_e_min=eta * mu_p_min,
        mu_p_sat_per_um2=mu_p_sat / area, mu_p_min_per_um2=mu_p_min / area,
        mu_e_sat_per_um2=mu_e_sat / area, mu_e_min_per_um2=eta * mu_p_min / area,
        snr_max=math.sqrt(mu_e_sat), dynamic_range=dr))


class _DarkCurrent(NamedTuple):
    """Step 8: the dark current, e⁻/s (NaN with fewer than 3 exposure times)."""

    e_per_s: float
    details: dict


def _dark_current(st: _StepStatistics, K: float, var_dark_slope: float) -> _DarkCurrent:
    """Step 8: slope of μ_y.dark against t_exp over K (section 7.1); from σ²_y.dark's slope over K² in details."""
    if np.unique(st.t_dark).size >= 3:
        dark_slope_DN, dark_offset = _slope_intercept(st.t_dark, st.mu_d)
        dark_current = dark_slope_DN / K
        dark_current_var = var_dark_slope / K**2
    else:
        dark_offset, dark_current, dark_current_var = float(np.mean(st.mu_d)), math.nan, math.nan
    return _DarkCurrent(dark_current, dict(dark_current_from_variance_e_per_s=dark_current_var,
                                           mu_y_dark_at_zero_DN=dark_offset))


class _Linearity(NamedTuple):
    """Step 9: the linearity errors (%), the per-step deviation δ_y (%) and the steps the fit used."""

    mean_abs: float
    half_range: float
    deviation: np.ndarray
    in_range: np.ndarray
    details: dict


def _linearity(mu_p: np.ndarray, signal: np.ndarray, sat: _Saturation) -> _Linearity:
    """Step 9: relative-weight fit over 5-95 % of saturation (section 6.9); LE = mean |δ_y| and (max − min)/2."""
    lo, hi = LINEARITY_FIT_RANGE
    lin_range = (mu_p <= sat.mu_p) & (signal >= lo * sat.signal) & (signal <= hi * sat.signal)
    a0, a1, _ = linearity_fit(mu_p[lin_range], signal[lin_range])
    fit = a0 + a1 * mu_p
    deviation = np.where(fit != 0, 100.0 * (signal - fit) / np.where(fit != 0, fit, 1.0), np.nan)
    dev_in = deviation[lin_range]
    le_mean_abs = float(np.mean(np.abs(dev_in)))
    le_half_range = float((dev_in.max() - dev_in.min()) / 2.0)
    return _Linearity(le_mean_abs, le_half_range, deviation, lin_range, dict(
        linearity_error_mean_abs_percent=le_mean_abs, linearity_error_half_range_percent=le_half_range,
        linearity_error_min_percent=float(dev_in.min()), linearity_error_max_percent=float(dev_in.max()),
        linearity_fit_offset_DN=a0, linearity_fit_slope_DN_per_photon=a1))


class _Nonuniformity(NamedTuple):
    """Step 10: DSNU1288 (e⁻) and PRNU1288 (%), NaN without the spatial stacks."""

    dsnu: float
    prnu: float
    details: dict


def _nonuniformity(series: EmvaSeries, K: float, signal_sat: float) -> _Nonuniformity:
    """Step 10: DSNU1288 = s_y.dark/K, PRNU1288 = √(s²_y.50 − s²_y.dark)/(μ_y.50 − μ_y.dark) (section 8, eq. 66, 67)."""
    if series.spatial_dark is None:
        return _Nonuniformity(math.nan, math.nan, {})
    sd = spatial_statistics(series.spatial_dark)
    sb = spatial_statistics(series.spatial_bright)
    dsnu = _sqrt_or_nan(sd["s2_y"]) / K
    contrast = sb["mu_y"] - sd["mu_y"]  # μ_y.50 − μ_y.dark

    def prnu_of(part):
        return 100.0 * _sqrt_or_nan(sb[part] - sd[part]) / contrast if contrast > 0 else math.nan

    return _Nonuniformity(dsnu, prnu_of("s2_y"), dict(
        spatial_dark=sd, spatial_bright=sb,
        dsnu_col_e=_sqrt_or_nan(sd["s2_y_col"]) / K, dsnu_row_e=_sqrt_or_nan(sd["s2_y_row"]) / K,
        dsnu_pixel_e=_sqrt_or_nan(sd["s2_y_pixel"]) / K, dsnu_DN=_sqrt_or_nan(sd["s2_y"]),
        prnu_col_percent=prnu_of("s2_y_col"), prnu_row_percent=prnu_of("s2_y_row"),
        prnu_pixel_percent=prnu_of("s2_y_pixel"),
        spatial_mu_p=series.spatial_mu_p, spatial_exposure_time_s=series.spatial_exposure_time_s,
        spatial_fraction_of_saturation=contrast / signal_sat,
    ))


def _curves(series: EmvaSeries, st: _StepStatistics, gain: _Gain, var_dark_used: float, mu_p_sat: float,
            lin: _Linearity) -> dict:
    """Per-step arrays for plots: photon transfer, SNR measured and modelled (eq. 21), linearity, fit masks."""
    mu_p, K, eta = series.mu_p, gain.K, gain.eta
    with np.errstate(divide="ignore", invalid="ignore"):
        snr = np.where(st.var_y > 0, st.signal / np.sqrt(np.maximum(st.var_y, 0)), np.nan)
    snr_model = eta * mu_p / np.sqrt(var_dark_used / K**2 + eta * mu_p)  # eq. 21 with the fitted K, η, σ²_y.dark
    return {
        "mu_p": mu_p.copy(), "exposure_times_s": series.exposure_times_s.copy(),
        "mu_y": st.mu_y, "var_y": st.var_y, "mu_y_dark": np.array(st.mu_y_dark), "var_y_dark": np.array(st.var_y_dark),
        "snr": snr, "snr_model": snr_model, "snr_ideal": np.sqrt(mu_p),
        "saturated_fraction": st.saturated_fraction, "sensitivity_fit_mask": gain.in_range,
        "linearity_fit_mask": lin.in_range, "beyond_saturation_mask": mu_p > mu_p_sat,
        "linearity_deviation_percent": lin.deviation,
    }


# --------------------------------------------------------------------------------------------------
# Expected values of an ideal linear camera
# --------------------------------------------------------------------------------------------------


def _clipped_variance(m, s2, c, nodes, weights, spread):
    """Mean over a Gaussian fixed pattern (sd ``spread``) of Var(min(X, c)), X ~ N(m + δ, s2)."""
    s = math.sqrt(s2)
    out = 0.0
    for z, w in zip(nodes, weights):
        mu = m + spread * z
        a = (c - mu) / s
        Phi = 0.5 * (1.0 + math.erf(a / math.sqrt(2.0)))
        phi = math.exp(-0.5 * a * a) / math.sqrt(2.0 * math.pi)
        e1 = mu * Phi - s * phi + c * (1.0 - Phi)
        e2 = (mu * mu + s2) * Phi - s * (mu + c) * phi + c * c * (1.0 - Phi)
        out += w * (e2 - e1 * e1)
    return out


def expected(*, gain_DN_per_e: float, quantum_efficiency: float, read_noise_e: float, dark_current_e_per_s: float,
             dsnu_e: float, prnu_fraction: float, full_well_e: float, adc_bits: int, black_level_DN: float,
             series_photon_rate_per_s: float | None = None, saturation: str = "pixel_fraction") -> dict:
    """The quantities of :func:`analyse` for an ideal linear camera, from its configured parameters.

    The camera: photo-electrons Poisson with mean η·μ_p·(1 + PRNU pattern), dark electrons Poisson with mean
    (dark current)·t_exp, charge clipped at ``full_well_e``, a per-pixel dark offset (DSNU pattern, e⁻) and Gaussian
    read noise added on readout, then y = round(K·v + black level) clipped to 0 … 2^bits − 1.  The patterns are
    Gaussian with the given standard deviations.  By the standard's definitions:

    * K, η, the dark current, DSNU1288 (e⁻) and PRNU1288 (%) are the configured values.
    * σ_d = read noise (the dark variance at zero exposure is K²σ²_read + 1/12 DN²; eq. 53), or the upper limit
      0.40/K when that variance is below 0.24 DN² (eq. 54).
    * μ_e.sat (sections 2.7, 6.5), ``saturation="pixel_fraction"``: the photo-electrons at which 0.15 % of the
      pixels reach 2^bits − 1, i.e. μ_e + d + z·σ_tot = (2^bits − 1.5 − black)/K with z = Φ⁻¹(1 − 0.0015) and
      σ²_tot = μ_e + d + σ²_read + (PRNU·μ_e)² + DSNU² (the temporal and the fixed-pattern spread; d = dark
      electrons).  ``"variance_max"``: the μ_e at which the mean temporal variance of the clipped signal peaks.
      When the full well clips below the ADC's range no pixel reaches the maximum code and, like :func:`analyse`,
      this falls back to ``"variance_max"``.
    * SNR_max = √μ_e.sat; μ_p.min from eq. 26; DR = μ_e.sat/(η·μ_p.min); both in dB.
    * Linearity error 0 %.

    Parameters
    ----------
    gain_DN_per_e, quantum_efficiency, read_noise_e, dark_current_e_per_s, dsnu_e, prnu_fraction : float
        K, DN/e⁻; η, e⁻ per photon; σ_read, e⁻ rms; dark current, e⁻/s; DSNU, e⁻ rms; PRNU, a fraction.
    full_well_e, black_level_DN : float
        The full well, e⁻; the black level, DN.
    adc_bits : int
        The ADC's resolution, bits.
    series_photon_rate_per_s : float or None
        Photons per pixel per second of a series varying the exposure time (d = dark current·μ_p/rate); None: d = 0.
    saturation : str
        ``"pixel_fraction"`` or ``"variance_max"``.

    Returns
    -------
    dict
        The keys of :data:`RESULT_KEYS` and ``"details"``.
    """
    K, eta = float(gain_DN_per_e), float(quantum_efficiency)
    _check_choice("saturation", saturation, SATURATION_METHODS)
    _check_positive(gain_DN_per_e=K, quantum_efficiency=eta, full_well_e=full_well_e)
    max_dn = 2.0**adc_bits - 1.0
    dark_per_photo_e = 0.0 if series_photon_rate_per_s is None else \
        dark_current_e_per_s / (eta * series_photon_rate_per_s)
    var_dark_DN2 = (K * read_noise_e) ** 2 + SIGMA_Q2_DN2
    sigma_d, upper, var_dark_used = temporal_dark_noise(var_dark_DN2, K)
    cam = _IdealCamera(read_noise_e, dsnu_e, prnu_fraction, full_well_e, dark_per_photo_e,
                       (max_dn - 0.5 - black_level_DN) / K)
    method = _expected_saturation_method(cam, saturation)
    mu_e_sat = _saturation_at_pixel_fraction(cam) if method == "pixel_fraction" else _saturation_at_variance_max(cam)
    mu_p_min = sensitivity_threshold(eta, var_dark_used, K)
    mu_e_min = eta * mu_p_min
    quantities = _quantities(K, eta, sigma_d, mu_e_sat, mu_e_sat / mu_e_min, float(dark_current_e_per_s),
                             float(dsnu_e), 100.0 * float(prnu_fraction), 0.0)
    details = dict(saturation_method=method, mu_e_sat=mu_e_sat, mu_p_sat=mu_e_sat / eta, mu_e_min=mu_e_min,
                   mu_p_min=mu_p_min, var_y_dark_DN2=var_dark_DN2, dark_noise_is_upper_limit=upper,
                   adc_clip_e=cam.clip_adc_e, max_dn=max_dn)
    return {**quantities, "details": details}


def _check_positive(**values) -> None:
    """Refuse any value that is not a finite number > 0 (ConfigError naming it)."""
    for name, v in values.items():
        if not (math.isfinite(v) and v > 0):
            raise ConfigError(name, v, "a finite number > 0")


@dataclass(frozen=True)
class _IdealCamera:
    """The ideal linear camera of :func:`expected`, in electrons (section 2's noise model)."""

    read_noise_e: float
    dsnu_e: float
    prnu_fraction: float
    full_well_e: float
    #: Dark electrons per photo-electron along the series (0: irradiance varied at a short exposure time).
    dark_per_photo_e: float
    #: The charge at which K·v + black ≥ max − 0.5 rounds to the maximum code, e⁻.
    clip_adc_e: float

    def temporal2(self, mu):
        """Temporal variance at μ_e photo-electrons, e⁻²: photo and dark shot noise and the read noise."""
        return mu * (1 + self.dark_per_photo_e) + self.read_noise_e**2

    def fixed2(self, mu):
        """Fixed-pattern variance at μ_e photo-electrons, e⁻²: PRNU and DSNU."""
        return (self.prnu_fraction * mu) ** 2 + self.dsnu_e**2


def _expected_saturation_method(cam: _IdealCamera, saturation: str) -> str:
    """``saturation``, or the variance maximum when the full well clips before 0.1 % reach the maximum code (6.5)."""
    # can the ADC's maximum be reached before the well is full? (fraction at the full well)
    z_fw = (cam.clip_adc_e - cam.full_well_e) / math.sqrt(cam.read_noise_e**2 + cam.dsnu_e**2 + 1e-12)
    adc_limits = _NORMAL.cdf(-z_fw) >= SATURATED_FRACTION_WINDOW[0]
    if saturation == "pixel_fraction" and not adc_limits:
        return "variance_max (fallback: the full well clips below the maximum code)"
    return saturation


def _saturation_at_pixel_fraction(cam: _IdealCamera) -> float:
    """μ_e.sat where 0.15 % of the pixels reach the maximum code: μ_e + d + z·σ_tot = clip (sections 2.7, 6.5)."""
    z = _NORMAL.inv_cdf(1.0 - SATURATED_FRACTION_TARGET)
    lo, hi = 0.0, cam.clip_adc_e
    for _ in range(200):   # μ + d + z·σ_tot = clip is monotone in μ
        mid = 0.5 * (lo + hi)
        if mid * (1 + cam.dark_per_photo_e) + z * math.sqrt(cam.temporal2(mid) + cam.fixed2(mid)) < cam.clip_adc_e:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _saturation_at_variance_max(cam: _IdealCamera) -> float:
    """μ_e.sat where the mean temporal variance of the clipped signal peaks (Release 3.1's definition, section 6.5)."""
    nodes, weights = np.polynomial.hermite_e.hermegauss(41)
    weights = weights / weights.sum()
    if cam.full_well_e < cam.clip_adc_e:
        # the well clips the charge; the dark offset (DSNU) and the read noise come after it
        clip, after = cam.full_well_e, cam.read_noise_e**2
        before_t = lambda mu: mu * (1 + cam.dark_per_photo_e)  # noqa: E731
        before_f = lambda mu: (cam.prnu_fraction * mu) ** 2   # noqa: E731
    else:
        clip, after, before_t, before_f = cam.clip_adc_e, 0.0, cam.temporal2, cam.fixed2
    grid = np.linspace(0.3 * clip, 1.2 * clip, 3001)
    var = [after + _clipped_variance(mu * (1 + cam.dark_per_photo_e), before_t(mu), clip, nodes, weights,
                                     math.sqrt(before_f(mu)))
           for mu in grid]
    return float(grid[int(np.argmax(var))])
