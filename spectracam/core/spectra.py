"""Wavelength grids, Planck's law, photon conversion and band averaging.

A *band* is the interval between the midpoints of neighbouring grid wavelengths (the outer bands
are symmetric about their centre).  A scene's ``start_nm``/``stop_nm``/``step_nm`` put the band
edges on the stated limits, so the stated range is integrated exactly at any step.  Radiance cubes hold the band average
``(1/Δλ)∫_band L(λ) dλ`` of the spectral radiance, so integrals over the cube are sums of
``value·Δλ``.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["BOLTZMANN_K_J_PER_K", "CIE_RANGE_NM", "CMFS_NAME", "K_M_LM_PER_W", "PLANCK_H_J_S",
           "SPEED_OF_LIGHT_M_S", "Spectrum", "WavelengthGrid", "band_average", "band_sample_points",
           "cie_1931_cmfs", "cmf_band_weights", "energy_to_photons", "logistic_cut", "logistic_scale_nm",
           "luminance_cd_m2", "planck_radiance", "tabulated"]

#: CODATA 2018 exact SI constants.
PLANCK_H_J_S = 6.62607015e-34
SPEED_OF_LIGHT_M_S = 299792458.0
BOLTZMANN_K_J_PER_K = 1.380649e-23

#: Maximum luminous efficacy of radiation for photopic vision, lm/W (CIE 1931, ȳ at 555 nm).
K_M_LM_PER_W = 683.0

#: Range of the CIE 1931 2° colour-matching functions shipped by colour-science, nm.
CIE_RANGE_NM = (360.0, 830.0)

CMFS_NAME = "CIE 1931 2 Degree Standard Observer"

Spectrum = Callable[[np.ndarray], np.ndarray]
"""A spectrum is a vectorised function of wavelength in nm."""


@dataclass(frozen=True)
class WavelengthGrid:
    """Band centres in nm, strictly increasing, with the band edges derived from them.

    Held as a tuple so that grids (and the scenes holding them) compare and hash by value.

    >>> WavelengthGrid([400, 410, 420]).edges_nm.tolist()
    [395.0, 405.0, 415.0, 425.0]
    """

    centres_nm: tuple

    def __post_init__(self):
        object.__setattr__(self, "centres_nm", tuple(float(x) for x in np.asarray(self.centres_nm, float).ravel()))

    @property
    def edges_nm(self) -> np.ndarray:
        """Band edges: midpoints between centres; the outer edges mirror the first/last half-widths."""
        c = np.asarray(self.centres_nm, dtype=float)
        if c.size == 1:
            return np.array([c[0] - 0.5, c[0] + 0.5])
        mid = 0.5 * (c[1:] + c[:-1])
        return np.concatenate([[c[0] - (mid[0] - c[0])], mid, [c[-1] + (c[-1] - mid[-1])]])

    @property
    def widths_nm(self) -> np.ndarray:
        return np.diff(self.edges_nm)

    def __len__(self) -> int:
        return len(self.centres_nm)


def planck_radiance(wavelength_nm: np.ndarray, temperature_K: float) -> np.ndarray:
    """Blackbody spectral radiance in W·m⁻²·sr⁻¹·nm⁻¹ (Planck's law).

    Parameters
    ----------
    wavelength_nm : array_like
        Wavelengths, nm.
    temperature_K : float
        Temperature, K.

    Returns
    -------
    ndarray
        ``2hc²/λ⁵ / (exp(hc/(λkT)) − 1)`` per nm, W·m⁻²·sr⁻¹·nm⁻¹, the shape of ``wavelength_nm``.

    References
    ----------
    .. [CODATA2018] see docs/references.md; h, c and k.
    """
    lam_m = np.asarray(wavelength_nm, dtype=float) * 1e-9
    x = PLANCK_H_J_S * SPEED_OF_LIGHT_M_S / (lam_m * BOLTZMANN_K_J_PER_K * temperature_K)
    per_m = 2.0 * PLANCK_H_J_S * SPEED_OF_LIGHT_M_S**2 / lam_m**5 / np.expm1(x)
    return per_m * 1e-9


def tabulated(wavelengths_nm: ArrayLike, values: ArrayLike) -> Spectrum:
    """Piecewise-linear interpolation of tabulated data, zero outside the table.

    Linear interpolation is what Mitsuba's ``regular``/``irregular`` spectra do, so both renderers
    see the same continuous spectrum.

    Parameters
    ----------
    wavelengths_nm : array_like
        Increasing wavelengths of the table, nm.
    values : array_like
        The values at those wavelengths.

    Returns
    -------
    Spectrum
        A vectorised function of wavelength in nm.
    """
    wl = np.asarray(wavelengths_nm, dtype=float)
    v = np.asarray(values, dtype=float)

    def f(lam_nm: np.ndarray) -> np.ndarray:
        return np.interp(lam_nm, wl, v, left=0.0, right=0.0)

    return f


def band_sample_points(grid: WavelengthGrid, points_per_band: int) -> np.ndarray:
    """Equally spaced wavelengths spanning each band, edges included.

    Parameters
    ----------
    grid : WavelengthGrid
        The bands.
    points_per_band : int
        Intervals per band.

    Returns
    -------
    ndarray
        ``(n_bands, points_per_band + 1)`` wavelengths, nm.
    """
    e = grid.edges_nm
    t = np.linspace(0.0, 1.0, points_per_band + 1)
    return e[:-1, None] + (e[1:] - e[:-1])[:, None] * t[None, :]


def band_average(f: Spectrum, grid: WavelengthGrid, points_per_band: int = 200) -> np.ndarray:
    """Band averages ``(1/Δλ)∫_band f dλ`` by the trapezoid rule on ``points_per_band`` intervals.

    Parameters
    ----------
    f : Spectrum
        A vectorised function of wavelength in nm (its values may have leading axes).
    grid : WavelengthGrid
        The bands.
    points_per_band : int
        Trapezoid intervals per band.

    Returns
    -------
    ndarray
        One average per band (last axis), in the unit of ``f``.
    """
    lam = band_sample_points(grid, points_per_band)
    y = f(lam)
    return 0.5 * (y[..., 1:] + y[..., :-1]).mean(axis=-1)


def energy_to_photons(values_per_nm: np.ndarray, wavelength_nm: np.ndarray) -> np.ndarray:
    """Convert spectral energy quantities (W/…) to photon rates (photons·s⁻¹/…): multiply by λ/(hc).

    The paper, section 3.1: the photon description is obtained by dividing energy by hc/λ.

    Parameters
    ----------
    values_per_nm : array_like
        Spectral energy quantities, W/… (e.g. W·m⁻²·sr⁻¹·nm⁻¹).
    wavelength_nm : array_like
        Their wavelengths, nm (broadcasting with ``values_per_nm``).

    Returns
    -------
    ndarray
        Photon rates, photons·s⁻¹/… (e.g. photons·s⁻¹·m⁻²·sr⁻¹·nm⁻¹).

    References
    ----------
    .. [Catrysse1999] see docs/references.md; section 3.1.
    .. [CODATA2018] see docs/references.md; h and c.
    """
    lam_m = np.asarray(wavelength_nm, dtype=float) * 1e-9
    return np.asarray(values_per_nm) * lam_m / (PLANCK_H_J_S * SPEED_OF_LIGHT_M_S)


def cie_1931_cmfs() -> tuple[np.ndarray, np.ndarray]:
    """The CIE 1931 2° colour-matching functions from colour-science (its table, read by
    :func:`spectracam.core.colour_data.cmfs_1931`).

    Returns
    -------
    wavelengths : ndarray
        ``(n,)`` wavelengths, nm (:data:`CIE_RANGE_NM`).
    cmfs : ndarray
        ``(n, 3)`` x̄ȳz̄.

    References
    ----------
    .. [CIE015] see docs/references.md; the CIE 1931 standard colorimetric observer.
    """
    from spectracam.core import colour_data

    return colour_data.cmfs_1931()


def cmf_band_weights(grid: WavelengthGrid) -> np.ndarray:
    """``(n_bands, 3)`` weights W such that XYZ = Σ_b L_b·W_b approximates ∫L(λ)·x̄ȳz̄(λ)dλ.

    Each weight is the band's width times the band-averaged colour-matching function, so a cube of
    band-averaged radiance integrates exactly when L is constant within each band.  A plain
    tensordot with these weights replaces colour-science's per-spectrum path: a whole cube integrates in
    one matrix product.

    Parameters
    ----------
    grid : WavelengthGrid
        The bands, nm.

    Returns
    -------
    ndarray
        ``(n_bands, 3)`` weights W, nm (the CIE 1931 x̄ȳz̄ averaged over each band, times its width).

    References
    ----------
    .. [CIE015] see docs/references.md
    """
    wl, xyz = cie_1931_cmfs()
    avg = np.stack([band_average(tabulated(wl, xyz[:, k]), grid) for k in range(3)], axis=-1)
    return avg * grid.widths_nm[:, None]


def luminance_cd_m2(radiance_bands: np.ndarray, grid: WavelengthGrid) -> np.ndarray:
    """Luminance 683·∫L(λ)ȳ(λ)dλ of band-averaged radiance (last axis = bands), cd/m².

    Parameters
    ----------
    radiance_bands : array_like
        Band-averaged radiance, W·m⁻²·sr⁻¹·nm⁻¹, last axis = bands.
    grid : WavelengthGrid
        The bands.

    Returns
    -------
    ndarray
        Luminance, cd/m² (the shape of ``radiance_bands`` without its last axis).

    References
    ----------
    .. [CIE015] see docs/references.md; K_m = 683 lm/W and ȳ.
    """
    return K_M_LM_PER_W * np.tensordot(radiance_bands, cmf_band_weights(grid)[:, 1], axes=([-1], [0]))


def logistic_scale_nm(edge_width_nm: float) -> float:
    """Scale s of a logistic edge 1/(1 + exp(−(λ − c)/s)) rising from 10 % to 90 % over ``edge_width_nm``.

    Parameters
    ----------
    edge_width_nm : float
        Width of the 10 % → 90 % rise, nm.

    Returns
    -------
    float
        ``s = edge_width_nm / (2 ln 9)``, nm.
    """
    return edge_width_nm / (2 * np.log(9.0))


def logistic_cut(cut_nm: float, edge_width_nm: float) -> Spectrum:
    """Transmittance ``λ → T`` of a short-pass (IR-cut) edge.

    Parameters
    ----------
    cut_nm : float
        Wavelength of 50 % transmittance, nm.
    edge_width_nm : float
        Width of the fall from 90 % to 10 %, nm.

    Returns
    -------
    Spectrum
        ``λ → 1/(1 + exp((λ − cut_nm)/s))`` with s from :func:`logistic_scale_nm`, λ in nm.
    """
    s = logistic_scale_nm(edge_width_nm)
    return lambda lam: 1.0 / (1.0 + np.exp((np.asarray(lam, float) - cut_nm) / s))
