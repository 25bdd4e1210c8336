"""Optical constants of silicon and the collection-depth photodiode quantum-efficiency model.

The data are M. A. Green's self-consistent optical parameters of intrinsic crystalline silicon at
300 K (Green, *Sol. Energy Mater. Sol. Cells* **92** (2008) 1305–1310,
doi:10.1016/j.solmat.2008.06.009), shipped as ``spectracam/data/silicon_green2008.csv``
(250–1450 nm in 10 nm steps: absorption coefficient α in 1/cm, refractive index n and extinction
coefficient k; the file's header says where the numbers were taken from).

The quantum efficiency of a photodiode that collects every carrier generated between depths
``z0`` and ``d`` below the surface, and none elsewhere, is

    QE(λ) = (1 − R(λ)) · (exp(−α(λ)·z0) − exp(−α(λ)·d)),

with ``R`` the normal-incidence reflectance of the air/silicon interface (Theuwissen 1995;
Janesick 2001).
"""
from __future__ import annotations

from functools import lru_cache
from importlib.resources import files
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["DATA_FILE", "absorption_coefficient_per_um", "photodiode_qe", "reflectance", "refractive_index"]

DATA_FILE = "silicon_green2008.csv"


class _Table(NamedTuple):
    wavelength_nm: np.ndarray
    log_alpha_per_um: np.ndarray
    n: np.ndarray
    k: np.ndarray


@lru_cache(maxsize=1)
def _table() -> _Table:
    """Read the Green (2008) table once (α converted from 1/cm to 1/µm, stored as its logarithm)."""
    text = (files("spectracam") / "data" / DATA_FILE).read_text(encoding="utf-8")
    rows = [line for line in text.splitlines() if line.strip() and not line.lstrip().startswith("#")]
    header = [c.strip() for c in rows[0].split(",")]
    if header != ["wavelength_nm", "alpha_per_cm", "n", "k"]:
        raise ValueError(f"{DATA_FILE}: unexpected columns {header}")
    data = np.loadtxt(rows[1:], delimiter=",", ndmin=2)
    wl, alpha_cm, n, k = data.T
    if not (np.all(np.diff(wl) > 0) and np.all(alpha_cm > 0)):
        raise ValueError(f"{DATA_FILE}: wavelengths must increase and α must be positive")
    arrays = (wl, np.log(alpha_cm * 1e-4), n, k)
    for a in arrays:
        a.setflags(write=False)
    return _Table(*arrays)


def _checked_wavelength(wavelength_nm) -> np.ndarray:
    wl = np.asarray(wavelength_nm, dtype=float)
    t = _table()
    lo, hi = float(t.wavelength_nm[0]), float(t.wavelength_nm[-1])
    if not np.all((wl >= lo) & (wl <= hi)):  # also rejects NaN
        raise ValueError(f"wavelength outside the Green (2008) silicon table ({lo:g}–{hi:g} nm)")
    return wl


def _alpha_per_um(wl: np.ndarray) -> np.ndarray:
    """α in 1/µm at checked wavelengths: linear interpolation in log α, then exp."""
    t = _table()
    return np.exp(np.interp(wl, t.wavelength_nm, t.log_alpha_per_um))


def absorption_coefficient_per_um(wavelength_nm: ArrayLike) -> np.ndarray:
    """Band-to-band absorption coefficient α of intrinsic silicon at 300 K, in 1/µm.

    Linear interpolation in log α of the table of M. A. Green, "Self-consistent optical parameters
    of intrinsic silicon at 300 K including temperature coefficients", *Sol. Energy Mater. Sol.
    Cells* 92 (2008) 1305–1310 (10 nm steps). Log-linear interpolation is exact for an exponential
    absorption edge and never produces negative values. 1/α is the absorption depth, at which the
    light intensity has fallen to 1/e.

    Parameters
    ----------
    wavelength_nm : float or array_like
        Wavelength(s) in nm, inside the table's range 250–1450 nm.

    Returns
    -------
    numpy.ndarray
        α in 1/µm (1/cm × 1e-4), same shape as `wavelength_nm`.

    Raises
    ------
    ValueError
        If any wavelength lies outside the table's range (or is NaN).

    Examples
    --------
    >>> a = absorption_coefficient_per_um([550.0, 650.0])  # Green (2008): 6.39e3 and 2.79e3 /cm
    >>> [round(float(x), 4) for x in a]
    [0.639, 0.279]
    """
    return _alpha_per_um(_checked_wavelength(wavelength_nm))


def _n_k(wl: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """n linearly interpolated; k = α·λ/(4π) from the log-interpolated α (consistent with α)."""
    t = _table()
    n = np.interp(wl, t.wavelength_nm, t.n)
    k = _alpha_per_um(wl) * (wl * 1e-3) / (4 * np.pi)
    return n, k


def refractive_index(wavelength_nm: ArrayLike) -> np.ndarray:
    """Real refractive index n of intrinsic silicon at 300 K (Green 2008), linearly interpolated.

    Parameters
    ----------
    wavelength_nm : float or array_like
        Wavelength(s) in nm, inside the table's range 250–1450 nm.

    Returns
    -------
    numpy.ndarray
        n, same shape as `wavelength_nm` (3.9–4.7 in the visible).

    Raises
    ------
    ValueError
        If any wavelength lies outside the table's range.

    Examples
    --------
    >>> round(float(refractive_index(600.0)), 2)
    3.94
    """
    return _n_k(_checked_wavelength(wavelength_nm))[0]


def reflectance(wavelength_nm: ArrayLike) -> np.ndarray:
    """Normal-incidence reflectance of a bare air/silicon interface.

    Fresnel's formula for an absorbing medium, ``R = ((n − 1)² + k²) / ((n + 1)² + k²)``, with the
    complex refractive index ``n + ik`` of M. A. Green, *Sol. Energy Mater. Sol. Cells* 92 (2008)
    1305–1310. ``n`` is interpolated linearly in wavelength and ``k = α·λ/(4π)`` is taken from the
    log-interpolated α of :func:`absorption_coefficient_per_um`, so both stay consistent. No oxide,
    passivation or anti-reflection layer is included.

    Parameters
    ----------
    wavelength_nm : float or array_like
        Wavelength(s) in nm, inside the table's range 250–1450 nm.

    Returns
    -------
    numpy.ndarray
        Reflectance R in [0, 1], same shape as `wavelength_nm`.

    Raises
    ------
    ValueError
        If any wavelength lies outside the table's range.

    Examples
    --------
    >>> round(float(reflectance(600.0)), 3)  # n = 3.94, k = 0.0199
    0.354
    """
    wl = _checked_wavelength(wavelength_nm)
    n, k = _n_k(wl)
    return ((n - 1) ** 2 + k**2) / ((n + 1) ** 2 + k**2)


def photodiode_qe(wavelength_nm: ArrayLike, depth_um: ArrayLike, *, reflectance_loss: bool = True,
                  surface_dead_layer_um: ArrayLike = 0.0) -> np.ndarray:
    """External quantum efficiency of a silicon photodiode in the collection-depth model.

    ``QE = (1 − R)·(exp(−α·z0) − exp(−α·d))`` with ``z0 = surface_dead_layer_um`` and
    ``d = depth_um``: the photons that enter the silicon (fraction ``1 − R``) are absorbed with
    Beer–Lambert's law, and the fraction absorbed between ``z0`` and ``d`` below the surface is
    collected. This is the classic collection-depth model of front-side sensors (e.g. A. J. P.
    Theuwissen, *Solid-State Imaging with Charge-Coupled Devices*, Kluwer, 1995; J. R. Janesick,
    *Scientific Charge-Coupled Devices*, SPIE Press, 2001), with α and R from M. A. Green,
    *Sol. Energy Mater. Sol. Cells* 92 (2008) 1305–1310.

    Assumptions: normal incidence on bare silicon (or a perfect anti-reflection coating when
    `reflectance_loss` is False); one pass of the light (no reflection from the back or from
    deeper interfaces, no interference in overlying layers, no filters or microlenses); every
    carrier generated inside the collection region ``[z0, d]`` (the depletion region plus whatever
    diffuses into it) is collected and every carrier generated outside it is lost, i.e. a sharp
    collection boundary instead of a diffusion profile; one electron per absorbed photon (quantum
    yield 1, valid above ~350 nm); intrinsic silicon at 300 K (no free-carrier absorption).

    Parameters
    ----------
    wavelength_nm : float or array_like
        Wavelength(s) in nm, inside the table's range 250–1450 nm.
    depth_um : float or array_like
        Collection depth d below the surface, µm; broadcast against `wavelength_nm`.
    reflectance_loss : bool, optional
        If True (default) multiply by ``1 − R`` of bare silicon (:func:`reflectance`); if False,
        assume a perfect anti-reflection coating (R = 0).
    surface_dead_layer_um : float or array_like, optional
        Depth z0 of the surface layer whose carriers recombine before collection, µm; ``0 ≤ z0 ≤ d``.

    Returns
    -------
    numpy.ndarray
        QE in [0, 1], electrons per incident photon, of the broadcast shape.

    Raises
    ------
    ValueError
        If a wavelength lies outside the table's range, or unless ``0 ≤ z0 ≤ d``.

    Examples
    --------
    >>> qe = photodiode_qe([450.0, 550.0, 650.0], depth_um=2.0)  # shallow CMOS diode: weak red
    >>> [round(float(q), 3) for q in qe]
    [0.575, 0.456, 0.28]
    """
    wl = _checked_wavelength(wavelength_nm)
    d = np.asarray(depth_um, dtype=float)
    z0 = np.asarray(surface_dead_layer_um, dtype=float)
    if not np.all((z0 >= 0) & (d >= z0)):  # also rejects NaN
        raise ValueError("need 0 <= surface_dead_layer_um <= depth_um")
    alpha = absorption_coefficient_per_um(wl)
    # exp(-α z0) - exp(-α d) = exp(-α z0)·(1 - exp(-α (d - z0))), written with expm1 so that thin
    # collection regions (α·(d - z0) ≪ 1) keep full relative precision.
    collected = np.exp(-alpha * z0) * -np.expm1(-alpha * (d - z0))
    if reflectance_loss:
        collected = (1.0 - reflectance(wl)) * collected
    return collected
