"""The figures a sensor datasheet quotes, computed from frames and spectra (issue 36): pure numpy functions.

* **Photon-transfer SNR and dynamic range for any read-out** (EMVA 1288 Release 4.0 *General*): the mean
  signal and the temporal noise of each step of a series, from frame pairs, in linearised electrons
  (:func:`series_statistics`); the signal where the SNR first reaches a level (:func:`snr_crossing`); the
  saturation signal by the 0.1–0.2 % rule (:func:`saturation_signal`); DR = μ_sat/μ_min with μ_min the SNR = 1
  threshold (:func:`dynamic_range`).  *General* defines the threshold by the SNR curve itself, not by the
  photon-transfer fit of *Linear*, because a high-dynamic-range read-out is not linear in variance.
* **The linear model** (EMVA 1288 *Linear*, eq. 27's SNR): :func:`snr_model_linear`.
* **ISO 12232 speeds**: S_sat = 78/H_sat, S_noise = 10/H_SNR (:func:`iso_speed`).
* **ISO 17321-1 sensitivity metamerism index**: :func:`sensitivity_metamerism_index`.
* **ISO 15739 visual noise**: :func:`visual_noise` (CSF-filtered opponent channels, CIELUV).

References
----------
.. [EMVA1288] see docs/references.md
.. [EMVA1288General] see docs/references.md
.. [ISO12232] see docs/references.md
.. [ISO15739] see docs/references.md
.. [ISO17321-1] see docs/references.md
.. [Johnson2003] see docs/references.md
"""
from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from spectracam.core.errors import ConfigError
from spectracam.evaluation.emva1288 import SATURATED_FRACTION_TARGET, pair_statistics

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["ISO12232_NOISE_CONSTANT", "OPPONENT_FROM_XYZ", "PLATEAU_TOLERANCE", "SMI_PATCHES", "VISUAL_NOISE_WEIGHTS", "SmiResult",
           "csf_chrominance", "csf_luminance", "dynamic_range", "iso_speed", "saturation_signal", "series_statistics",
           "sensitivity_metamerism_index", "smi_fit", "snr_crossing", "snr_model_linear", "visual_noise",
           "white_preserving_fit"]

#: ISO 12232's noise-based speeds: S_noise = 10/H_SNR (lux·s), SNR 40 ("excellent") and SNR 10 ("acceptable").
ISO12232_NOISE_CONSTANT = 10.0
#: A series has reached its plateau (saturated) when two steps' mean signals differ by less than this fraction.
PLATEAU_TOLERANCE = 0.01
#: ISO 17321-1's patches: the 18 chromatic patches of the ColorChecker (the six neutrals are left out).
SMI_PATCHES = slice(0, 18)
#: XYZ → the opponent space (A, C1, C2) in which the eye's CSFs filter (Johnson & Fairchild's iCAM matrix).
OPPONENT_FROM_XYZ = np.array([[0.0556, 0.9981, -0.0254],
                              [0.9510, -0.9038, 0.0000],
                              [0.0386, 1.0822, -1.0276]])
#: ISO 15739's weighted sum of the filtered image's standard deviations, VN = σ_L* + 0.852·σ_u* + 0.323·σ_v*.
VISUAL_NOISE_WEIGHTS = (1.0, 0.852, 0.323)


# ------------------------------------------------------------------------------------------------
# EMVA 1288: photon transfer for any read-out


def series_statistics(bright_e: np.ndarray, dark_e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean signal and temporal variance of each step of a photon-transfer series, in electrons.

    Parameters
    ----------
    bright_e : ndarray
        ``(n, 2, M, N)``: a frame pair per step, linearised to electrons (``adc_inverse``).
    dark_e : ndarray
        ``(2, M, N)``: one dark pair at the series' exposure time, electrons.

    Returns
    -------
    mu_e : ndarray
        ``(n,)`` dark-subtracted mean signal μ_y − μ_y.dark, e⁻ (EMVA 1288 eq. 16).
    var_e : ndarray
        ``(n,)`` temporal variance σ²_y, e⁻² (eq. 18: the pair difference, which removes every fixed pattern).

    References
    ----------
    .. [EMVA1288] see docs/references.md; eqs. 16 and 18.
    """
    mu_dark, _ = pair_statistics(dark_e[0], dark_e[1])
    stats = np.array([pair_statistics(a, b) for a, b in bright_e], float).reshape(-1, 2)
    return stats[:, 0] - mu_dark, stats[:, 1]


def snr_crossing(signal: ArrayLike, snr: ArrayLike, level: float) -> float | None:
    """The signal at which the SNR first rises through ``level``, interpolated linearly in log–log; None if never.

    Parameters
    ----------
    signal : array_like
        Increasing signal of each step (any unit; > 0 where it matters).
    snr : array_like
        The SNR of each step (NaN where undefined).
    level : float
        The SNR sought (1: EMVA 1288's absolute sensitivity threshold; 10, 40: ISO 12232's criteria).

    Returns
    -------
    float or None
    """
    x, y = np.asarray(signal, float), np.asarray(snr, float)
    ok = np.isfinite(y) & (x > 0) & (y > 0)
    x, y = x[ok], y[ok]
    above = np.nonzero(y >= level)[0]
    if above.size == 0:
        return None
    i = int(above[0])
    if i == 0:
        return None if y[0] > level else float(x[0])
    lx, ly = np.log(x[i - 1:i + 1]), np.log(y[i - 1:i + 1])
    t = (np.log(level) - ly[0]) / (ly[1] - ly[0])
    return float(np.exp(lx[0] + t * (lx[1] - lx[0])))


def saturation_signal(signal: ArrayLike, top_fraction: ArrayLike, var: ArrayLike) -> tuple[float, str]:
    """The saturation signal μ_sat: where 0.15 % of the pixels show the top output value (EMVA 1288 Release 4,
    sections 2.7 and 6.5; log-interpolated between the steps around it); else, when the mean signal has stopped
    rising (a read-out whose clipped pixels sit below its top output value: the last two steps within 1 %), the
    onset of that plateau, where the temporal variance peaks; else where the temporal variance peaks (Release 3.1's
    definition).

    Parameters
    ----------
    signal : array_like
        ``(n,)`` mean signal of each step, increasing (e⁻ or DN).
    top_fraction : array_like
        ``(n,)`` fraction of the pixels at the top output value in each step.
    var : array_like
        ``(n,)`` temporal variance of each step.

    Returns
    -------
    (float, str)
        μ_sat in the unit of ``signal``, and how it was found (``"pixel_fraction"``, ``"plateau"`` or
        ``"variance_max"``).
    """
    x, f, v = (np.asarray(a, float) for a in (signal, top_fraction, var))
    hit = np.nonzero(f >= SATURATED_FRACTION_TARGET)[0]
    if hit.size and hit[0] > 0 and x[hit[0] - 1] > 0:
        i = int(hit[0])
        lo, hi = max(f[i - 1], 1e-12), f[i]
        t = (np.log(SATURATED_FRACTION_TARGET) - np.log(lo)) / (np.log(hi) - np.log(lo))
        return float(np.exp(np.log(x[i - 1]) + t * (np.log(x[i]) - np.log(x[i - 1])))), "pixel_fraction"
    if x.size >= 3 and x[-1] > 0 and abs(x[-1] / x[-2] - 1) < PLATEAU_TOLERANCE:
        # clipped below the top value: the onset of clipping is where the temporal variance peaks (on the plateau the
        # clipped pixels have no noise left, so an SNR measured there is no SNR of the sensor)
        return float(x[int(np.nanargmax(v))]), "plateau"
    return float(x[int(np.nanargmax(v))]), "variance_max"


def dynamic_range(mu_sat: float, mu_min: float | None) -> tuple[float | None, float | None]:
    """DR = μ_sat/μ_min (EMVA 1288 eq. 28; *General*: μ_min where the SNR curve reaches 1), and in dB, 20·log10.

    Parameters
    ----------
    mu_sat : float
        The saturation signal μ_sat (:func:`saturation_signal`).
    mu_min : float or None
        The signal where the SNR reaches 1 (:func:`snr_crossing`), same unit; None when never reached.

    Returns
    -------
    ratio : float or None
        μ_sat/μ_min; None without a μ_min > 0.
    db : float or None
        20·log10 of it, dB.

    Examples
    --------
    >>> dynamic_range(1000.0, 10.0)
    (100.0, 40.0)
    """
    if mu_min is None or not mu_min > 0:
        return None, None
    ratio = float(mu_sat / mu_min)
    return ratio, float(20.0 * np.log10(ratio))


def snr_model_linear(mu_e: ArrayLike, read_noise_e: float, dark_e: float, gain_dn_per_e: float | None) -> np.ndarray:
    """The SNR of a linear sensor, ``μ_e / sqrt(μ_e + μ_d + σ_r² + σ_q²/K²)`` (EMVA 1288 *Linear*, section 2.5;
    σ_q² = 1/12 DN², none when ``gain_dn_per_e`` is None: no quantiser).

    Parameters
    ----------
    mu_e : array_like
        Photo-electrons, e⁻.
    read_noise_e : float
        Read noise σ_r, e⁻ rms.
    dark_e : float
        Dark electrons in the exposure μ_d (their shot noise), e⁻.
    gain_dn_per_e : float or None
        System gain K, DN/e⁻.

    Returns
    -------
    ndarray
    """
    mu = np.asarray(mu_e, float)
    quant = 0.0 if gain_dn_per_e is None else 1.0 / (12.0 * gain_dn_per_e**2)
    return mu / np.sqrt(mu + dark_e + read_noise_e**2 + quant)


def iso_speed(constant: float, exposure_lux_s: float | None) -> float | None:
    """An ISO 12232 speed, ``constant / H`` with H the focal-plane exposure in lux·s: S_sat = 78/H_sat,
    S_noise40 = 10/H_SNR40, S_noise10 = 10/H_SNR10.

    Parameters
    ----------
    constant : float
        78 (:data:`~spectracam.io.dng.ISO_SATURATION_CONSTANT`, S_sat) or 10 (:data:`ISO12232_NOISE_CONSTANT`).
    exposure_lux_s : float or None
        The focal-plane exposure H, lux·s; None when not reached.

    Returns
    -------
    float or None
        The speed; None without an exposure > 0.

    Examples
    --------
    >>> iso_speed(78.0, 0.78)
    100.0
    """
    if exposure_lux_s is None or not exposure_lux_s > 0:
        return None
    return float(constant / exposure_lux_s)


# ------------------------------------------------------------------------------------------------
# ISO 17321-1: sensitivity metamerism index


def white_preserving_fit(camera: np.ndarray, xyz: np.ndarray, camera_white: np.ndarray,
                         xyz_white: np.ndarray) -> np.ndarray:
    """The N×3 matrix M minimising ‖camera·M − xyz‖² subject to ``camera_white·M = xyz_white`` exactly.

    Each column m solves min ‖C·m − x‖² s.t. wᵀm = x_w: m = m_ls + G⁻¹w·(x_w − wᵀm_ls)/(wᵀG⁻¹w), G = CᵀC.

    Parameters
    ----------
    camera : ndarray
        ``(n, N)`` camera responses of the patches.
    xyz : ndarray
        ``(n, 3)`` their tristimulus values.
    camera_white, xyz_white : ndarray
        ``(N,)`` and ``(3,)``: the perfect white's.

    Returns
    -------
    ndarray
        ``(N, 3)``.
    """
    C, X, w = np.asarray(camera, float), np.asarray(xyz, float), np.asarray(camera_white, float)
    G = C.T @ C
    m_ls = np.linalg.solve(G, C.T @ X)
    g = np.linalg.solve(G, w)
    return m_ls + np.outer(g, (np.asarray(xyz_white, float) - w @ m_ls) / (w @ g))


def _lab(xyz, white):
    from spectracam.core.cielab import xyz_to_lab

    return xyz_to_lab(xyz, white)


def smi_fit(camera: np.ndarray, xyz: np.ndarray, camera_white: np.ndarray, xyz_white: np.ndarray,
            fit: str = "delta_e") -> np.ndarray:
    """The white-preserving N×3 matrix of the SMI: ``"least_squares"`` (:func:`white_preserving_fit`) or
    ``"delta_e"`` — the one minimising the mean ΔE*ab, found from the least-squares one (Nelder–Mead over the
    matrices that keep the white: M = M_ls + B·Qᵀ, Q an orthonormal basis of the directions w·Q = 0).

    Parameters
    ----------
    camera : ndarray
        ``(n, N)`` camera responses of the patches.
    xyz : ndarray
        ``(n, 3)`` their CIE XYZ.
    camera_white : ndarray
        ``(N,)`` the perfect white's camera response.
    xyz_white : ndarray
        ``(3,)`` its XYZ (also CIELAB's white).
    fit : str
        ``"delta_e"`` or ``"least_squares"``.

    Returns
    -------
    ndarray
        ``(N, 3)`` M with ``camera·M ≈ xyz`` and ``camera_white·M = xyz_white``.

    Raises
    ------
    ConfigError
        Another ``fit``.
    """
    M0 = white_preserving_fit(camera, xyz, camera_white, xyz_white)
    if fit == "least_squares":
        return M0
    if fit != "delta_e":
        raise ConfigError("fit", fit, "'delta_e' or 'least_squares'")
    from scipy.optimize import minimize

    w = np.asarray(camera_white, float)
    Q = np.linalg.svd(w[None, :])[2][1:].T           # (N, N−1): w·Q = 0
    ref = _lab(xyz, xyz_white)

    def cost(b):
        M = M0 + Q @ b.reshape(Q.shape[1], 3)
        return float(np.linalg.norm(_lab(camera @ M, xyz_white) - ref, axis=-1).mean())

    res = minimize(cost, np.zeros(Q.shape[1] * 3), method="Nelder-Mead",
                   options={"xatol": 1e-10, "fatol": 1e-12, "maxiter": 20000, "maxfev": 20000})
    b = res.x if res.fun <= cost(np.zeros(Q.shape[1] * 3)) else np.zeros(Q.shape[1] * 3)
    return M0 + Q @ b.reshape(Q.shape[1], 3)


class SmiResult(NamedTuple):
    """The SMI, the mean ΔE*ab it is made of, each patch's ΔE*ab, and the matrix."""

    smi: float
    delta_e_mean: float
    delta_e: np.ndarray
    matrix: np.ndarray


def sensitivity_metamerism_index(responsivities: np.ndarray, wavelengths_nm: ArrayLike, illuminant: ArrayLike,
                                 reflectances: np.ndarray,
                                 cmfs: np.ndarray, fit: str = "delta_e") -> SmiResult:
    """ISO 17321-1's sensitivity metamerism index, SMI = 100 − 5.5·mean ΔE*ab.

    The camera counts photons, so channel k of a surface ρ under the light S is ``Σ S·ρ·R_k·λ`` (R_k in
    electrons per photon, λ turning energy into photons); the truth is ``Σ S·ρ·x̄ȳz̄``.  The camera's responses
    are carried to XYZ by the white-preserving matrix of :func:`smi_fit` and both are compared in CIELAB
    relative to the perfect white (ΔE*ab, the mean over the patches).  A camera whose energy responsivities
    ``R_k(λ)·λ`` are a linear combination of the colour-matching functions (the Luther condition) scores 100.

    Parameters
    ----------
    responsivities : ndarray
        ``(N, n)`` R_k(λ), electrons per photon.
    wavelengths_nm : array_like
        ``(n,)`` uniformly spaced wavelengths, nm.
    illuminant : array_like
        ``(n,)`` relative spectral power S(λ) (ISO 17321-1: CIE D65).
    reflectances : ndarray
        ``(p, n)`` the patches (ISO 17321-1: the ColorChecker's 18 chromatic patches, :data:`SMI_PATCHES`).
    cmfs : ndarray
        ``(n, 3)`` x̄ȳz̄ (CIE 1931 2°).
    fit : str
        ``"delta_e"`` (default) or ``"least_squares"``.

    Returns
    -------
    SmiResult

    References
    ----------
    .. [ISO17321-1] see docs/references.md
    """
    lam = np.asarray(wavelengths_nm, float)
    S, rho = np.asarray(illuminant, float), np.asarray(reflectances, float)
    cam_w = np.asarray(responsivities, float) @ (S * lam)            # (N,)
    xyz_w = np.asarray(cmfs, float).T @ S                            # (3,)
    cam = (rho * (S * lam)) @ np.asarray(responsivities, float).T    # (p, N)
    xyz = (rho * S) @ np.asarray(cmfs, float)                        # (p, 3)
    scale_c, scale_x = 1.0 / cam_w.max(), 1.0 / xyz_w[1]
    M = smi_fit(cam * scale_c, xyz * scale_x, cam_w * scale_c, xyz_w * scale_x, fit)
    de = np.linalg.norm(_lab(cam * scale_c @ M, xyz_w * scale_x) - _lab(xyz * scale_x, xyz_w * scale_x), axis=-1)
    return SmiResult(float(100.0 - 5.5 * de.mean()), float(de.mean()), de, M)


# ------------------------------------------------------------------------------------------------
# ISO 15739: visual noise


def csf_luminance(f_cpd: ArrayLike) -> np.ndarray:
    """The luminance CSF, ``0.63·f^0.616·exp(−0.085·f)`` (Movshon & Kiorpes, as Johnson & Fairchild use it),
    normalised to a peak of 1 (at f = 0.616/0.085 = 7.25 cycles/degree); 0 at f = 0 (the mean is kept apart).

    Parameters
    ----------
    f_cpd : array_like
        Spatial frequency, cycles per degree.

    Returns
    -------
    ndarray
        The sensitivity, same shape, peak 1.
    """
    f = np.asarray(f_cpd, float)
    peak = 0.63 * (0.616 / 0.085) ** 0.616 * np.exp(-0.616)
    return 0.63 * f**0.616 * np.exp(-0.085 * f) / peak


def csf_chrominance(f_cpd: ArrayLike, channel: int) -> np.ndarray:
    """The chromatic CSFs of Johnson & Fairchild (sums of two exponentials), 1 at f = 0:
    channel 1 (red–green) ``91.228·e^(−0.0003·f^2.803) + 74.907·e^(−0.0038·f^2.601)``, channel 2 (yellow–blue)
    ``5.623·e^(−0.00001·f^3.4066) + 41.9363·e^(−0.083·f^1.3684)``, each over its value at 0.

    Parameters
    ----------
    f_cpd : array_like
        Spatial frequency, cycles per degree.
    channel : int
        1 (red–green) or 2 (yellow–blue), of :data:`OPPONENT_FROM_XYZ`.

    Returns
    -------
    ndarray
        The sensitivity, same shape, 1 at f = 0.
    """
    a1, b1, c1, a2, b2, c2 = {1: (91.228, 0.0003, 2.803, 74.907, 0.0038, 2.601),
                              2: (5.623, 0.00001, 3.4066, 41.9363, 0.083, 1.3684)}[channel]
    f = np.asarray(f_cpd, float)
    return (a1 * np.exp(-b1 * f**c1) + a2 * np.exp(-b2 * f**c2)) / (a1 + a2)


def _filtered_xyz(xyz: np.ndarray, samples_per_degree: float) -> np.ndarray:
    """The image through the eye's filters: opponent channels, each's mean kept and its variations weighted by
    its CSF in the frequency domain, back to XYZ (negative values set to 0)."""
    h, w = xyz.shape[:2]
    fy, fx = np.meshgrid(np.fft.fftfreq(h), np.fft.fftfreq(w), indexing="ij")
    f_cpd = np.hypot(fy, fx) * samples_per_degree
    filters = (csf_luminance(f_cpd), csf_chrominance(f_cpd, 1), csf_chrominance(f_cpd, 2))
    opp = xyz @ OPPONENT_FROM_XYZ.T
    out = np.empty_like(opp)
    for k in range(3):
        mean = opp[..., k].mean()
        out[..., k] = mean + np.fft.ifft2(np.fft.fft2(opp[..., k] - mean) * filters[k]).real
    return np.maximum(out @ np.linalg.inv(OPPONENT_FROM_XYZ).T, 0.0)


def visual_noise(xyz: np.ndarray, white_xyz: ArrayLike, samples_per_degree: float) -> dict:
    """ISO 15739 visual noise of a uniform patch: ``VN = σ_L* + 0.852·σ_u* + 0.323·σ_v*`` of its CSF-filtered image.

    The patch's XYZ goes to the opponent channels (:data:`OPPONENT_FROM_XYZ`), each is filtered by its CSF
    (:func:`csf_luminance`, :func:`csf_chrominance`) at the viewing geometry's samples per degree, back to XYZ
    and to CIELUV relative to ``white_xyz``; the standard deviations of L*, u*, v* over the patch are weighted
    (:data:`VISUAL_NOISE_WEIGHTS`).

    Parameters
    ----------
    xyz : ndarray
        ``(h, w, 3)`` the patch as displayed, CIE XYZ (any scale shared with the white).
    white_xyz : array_like
        ``(3,)`` the display's white.
    samples_per_degree : float
        Image pixels per degree of visual angle.

    Returns
    -------
    dict
        ``visual_noise`` and ``sigma_L``, ``sigma_u``, ``sigma_v``.

    References
    ----------
    .. [ISO15739] see docs/references.md; Annex B (the weights, the opponent filtering).
    .. [Johnson2003] see docs/references.md; the CSFs.
    """
    import colour

    a = np.asarray(xyz, float)
    if a.ndim != 3 or a.shape[-1] != 3 or min(a.shape[:2]) < 2:
        raise ConfigError("xyz", a.shape, "an (h, w, 3) patch with h, w >= 2")
    white = np.asarray(white_xyz, float)
    filtered = _filtered_xyz(a / white[1], samples_per_degree)
    luv = colour.XYZ_to_Luv(filtered, colour.XYZ_to_xy(white / white[1]))
    s = luv.reshape(-1, 3).std(axis=0)
    vn = float(np.dot(VISUAL_NOISE_WEIGHTS, s))
    return {"visual_noise": vn, "sigma_L": float(s[0]), "sigma_u": float(s[1]), "sigma_v": float(s[2])}
