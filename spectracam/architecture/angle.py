"""Filters across the field: how each architecture's colour filter changes with the angle of incidence.

* A **dichroic coating** (the prism's beam splitters, a field-sequential wheel's interference filters) moves
  its whole curve to shorter wavelengths as the angle of incidence θ grows, by the effective-index law
  ``λ(θ) = λ₀·√(1 − (n₀ sinθ / n_eff)²)`` [Smith2008]_, n_eff the stack's effective index (typically 1.5–1.9
  for most coatings [Smith2008]_; 1.7 here) and n₀ the incident medium's (1: air).
* A **field-sequential filter wheel** is often tilted (to send its reflections out of the beam): the angle of
  incidence is that between the ray and the tilted filter's normal, :func:`tilted_incidence_deg`, and the
  same law applies.
* A **CFA's dye** absorbs along its path: a ray refracted into a dye layer of index n_d ≈ 1.55 [COMPASS]_
  crosses it at θ_i = asin(sinθ/n_d), a path 1/cosθ_i times the layer's thickness, so by Beer–Lambert its
  transmittance T becomes ``T^(1/cos θ_i)`` [Macleod2010]_.

Functions take wavelengths (nm) and curves as NumPy arrays and broadcast over angle arrays (one angle per
pixel): an angle array of shape ``S`` and a curve of ``n`` wavelengths give ``S + (n,)``.  At θ = 0 each is
the identity.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from spectracam.core.errors import ConfigError

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["N_DYE", "N_EFF_COATING", "N_PRISM_GLASS", "coating_cutoff_nm", "coating_shift_factor",
           "dye_internal_angle_deg", "dye_path_factor", "dye_transmittance", "prism_incidence_deg", "shift_curve",
           "tilted_incidence_deg", "wheel_filter_curve"]

#: Effective index of a dichroic (TiO₂/SiO₂-type) stack: "typically in the range of 1.5 to 1.9 for most coatings"
#: [Smith2008]_; 1.7, the middle, a stated choice (a coating's maker states its own).
N_EFF_COATING = 1.7
#: Refractive index of a CFA's colour-filter layer: 1.55, as COMPASS's BSI pixel stack [COMPASS]_ (pigmented
#: acrylic resists sit near 1.5–1.6); a stated typical value, not a measured filter's.
N_DYE = 1.55
#: Index of a colour-splitting prism's glass (BK7-like crown, 1.52 at 550 nm), for :func:`prism_incidence_deg`.
N_PRISM_GLASS = 1.52


def _angle(aoi_deg, name: str) -> np.ndarray:
    a = np.asarray(aoi_deg, dtype=np.float64)
    if not np.all(np.isfinite(a)) or np.any(np.abs(a) >= 90):
        raise ConfigError(name, float(np.max(np.abs(a))) if a.size else aoi_deg,
                          "angles of incidence must lie strictly between -90 and 90 degrees")
    return a


def _index(n: float, name: str, lo: float = 1.0) -> float:
    if isinstance(n, bool) or not isinstance(n, (int, float)) or not np.isfinite(n) or n < lo:
        raise ConfigError(name, n, f"must be a refractive index ≥ {lo:g}")
    return float(n)


def coating_shift_factor(aoi_deg: ArrayLike, n_eff: float = N_EFF_COATING, n0: float = 1.0) -> np.ndarray:
    """The factor ``λ(θ)/λ₀`` by which a dichroic coating's features move with the angle of incidence.

    Parameters
    ----------
    aoi_deg : array_like
        Angle of incidence θ in the incident medium, degrees.
    n_eff : float
        The stack's effective index (:data:`N_EFF_COATING`); must exceed ``n0·|sinθ|``.
    n0 : float
        The incident medium's index (1: air).

    Returns
    -------
    ndarray
        ``√(1 − (n₀ sinθ / n_eff)²)``, float64, the shape of ``aoi_deg``; exactly 1 at θ = 0.

    References
    ----------
    .. [Smith2008] see docs/references.md; chapter 11, the wavelength shift with obliquity.
    """
    theta = _angle(aoi_deg, "coating.aoi_deg")
    n_eff, n0 = _index(n_eff, "coating.n_eff"), _index(n0, "coating.n0")
    s = n0 * np.sin(np.radians(theta)) / n_eff
    if np.any(np.abs(s) >= 1):
        raise ConfigError("coating.n_eff", n_eff, f"must exceed n0·sinθ = {float(np.max(np.abs(s))) * n_eff:g}")
    return np.sqrt(1.0 - s**2)


def coating_cutoff_nm(cutoff_nm: ArrayLike, aoi_deg: ArrayLike, n_eff: float = N_EFF_COATING,
                      n0: float = 1.0) -> np.ndarray:
    """A dichroic coating's cut-off (or any feature) at an angle of incidence.

    Parameters
    ----------
    cutoff_nm : array_like
        λ₀, the feature's wavelength at normal incidence, nm.
    aoi_deg : array_like
        θ, degrees (broadcast against ``cutoff_nm``).
    n_eff, n0 : float
        As :func:`coating_shift_factor`.

    Returns
    -------
    ndarray
        ``λ(θ) = λ₀·√(1 − (n₀ sinθ / n_eff)²)``, nm; ``λ(0) = λ₀``.

    References
    ----------
    .. [Smith2008] see docs/references.md; chapter 11.
    """
    return np.asarray(cutoff_nm, dtype=np.float64) * coating_shift_factor(aoi_deg, n_eff, n0)


def shift_curve(wavelengths_nm: ArrayLike, transmittance: ArrayLike, aoi_deg: ArrayLike, n_eff: float = N_EFF_COATING,
                n0: float = 1.0, design_aoi_deg: float = 0.0) -> np.ndarray:
    """A dichroic filter's transmittance at another angle of incidence: the whole curve scaled in wavelength.

    Parameters
    ----------
    wavelengths_nm : array_like
        ``(n,)`` increasing wavelengths, nm.
    transmittance : array_like
        ``(n,)`` the curve at ``design_aoi_deg``.
    aoi_deg : array_like
        Angles of incidence, degrees, any shape S.
    n_eff, n0 : float
        As :func:`coating_shift_factor`.
    design_aoi_deg : float
        The angle at which ``transmittance`` was measured or designed (0: normal incidence; a prism's
        beam splitter is specified at its own angle).

    Returns
    -------
    ndarray
        ``S + (n,)``: ``T_θ(λ) = T(λ·s(θ_d)/s(θ))``, s = :func:`coating_shift_factor`, linearly interpolated,
        the end values held beyond the curve; exactly ``transmittance`` where θ = ``design_aoi_deg``.

    References
    ----------
    .. [Smith2008] see docs/references.md; chapter 11 (the effective-index approximation shifts every
       feature by the same factor).
    """
    wl = np.asarray(wavelengths_nm, dtype=np.float64)
    t = np.asarray(transmittance, dtype=np.float64)
    if wl.ndim != 1 or wl.shape != t.shape or wl.size < 2 or np.any(np.diff(wl) <= 0):
        raise ConfigError("coating.wavelengths_nm", wl.shape, "must be ≥ 2 increasing wavelengths (nm) with as "
                                                             "many transmittances")
    ratio = coating_shift_factor(design_aoi_deg, n_eff, n0) / coating_shift_factor(aoi_deg, n_eff, n0)
    query = np.asarray(ratio)[..., None] * wl
    out = np.interp(query, wl, t)
    same = np.asarray(ratio)[..., None] == 1.0
    return np.where(same, t, out)


def tilted_incidence_deg(tilt_deg: ArrayLike, field_x_deg: ArrayLike, field_y_deg: ArrayLike = 0.0) -> np.ndarray:
    """The angle of incidence on a filter tilted about the y axis, for rays at field angles (x, y).

    Parameters
    ----------
    tilt_deg : array_like
        The filter's tilt τ (its normal turned by τ in the x–z plane), degrees.
    field_x_deg, field_y_deg : array_like
        The ray's angle to the optical axis in the x–z and y–z planes, degrees (the object-side field angle
        for a wheel in front of the lens, the chief-ray angle for one between lens and sensor).

    Returns
    -------
    ndarray
        θ = the angle between the ray ``(tan φx, tan φy, 1)`` and the normal ``(−sin τ, 0, cos τ)``, degrees
        (≥ 0): ``|τ + φx|`` for rays in the plane of the tilt (φy = 0).

    References
    ----------
    .. [Smith2008] see docs/references.md; chapter 11 (a tilted interference filter).
    """
    t = np.radians(np.asarray(tilt_deg, dtype=np.float64))
    tx = np.tan(np.radians(np.asarray(field_x_deg, dtype=np.float64)))
    ty = np.tan(np.radians(np.asarray(field_y_deg, dtype=np.float64)))
    cos_theta = (-np.sin(t) * tx + np.cos(t)) / np.sqrt(1.0 + tx**2 + ty**2)
    return np.degrees(np.arccos(np.clip(cos_theta, -1.0, 1.0)))


def wheel_filter_curve(wavelengths_nm: ArrayLike, transmittance: ArrayLike, tilt_deg: float, field_x_deg: ArrayLike,
                       field_y_deg: ArrayLike = 0.0, n_eff: float = N_EFF_COATING) -> np.ndarray:
    """A field-sequential wheel's interference filter, tilted by τ, seen by rays at field angles (x, y).

    Parameters
    ----------
    wavelengths_nm, transmittance : array_like
        ``(n,)`` the filter at normal incidence.
    tilt_deg : float
        The wheel's tilt, degrees.
    field_x_deg, field_y_deg : array_like
        The rays' field angles, degrees, any shape S.
    n_eff : float
        The coating's effective index.

    Returns
    -------
    ndarray
        ``S + (n,)``: :func:`shift_curve` at :func:`tilted_incidence_deg` (in air).

    References
    ----------
    .. [Smith2008] see docs/references.md; chapter 11.
    """
    aoi = tilted_incidence_deg(tilt_deg, field_x_deg, field_y_deg)
    return shift_curve(wavelengths_nm, transmittance, aoi, n_eff)


def prism_incidence_deg(field_deg: ArrayLike, coating_aoi_deg: float = 0.0,
                        n_glass: float = N_PRISM_GLASS) -> np.ndarray:
    """The angle of incidence on a beam splitter inside a prism, in the glass, for a ray at a field angle.

    Parameters
    ----------
    field_deg : array_like
        The ray's angle to the axis in air, in the plane of the splitter's tilt, degrees.
    coating_aoi_deg : float
        The splitter's angle to the axis in the glass (its design angle of incidence), degrees.
    n_glass : float
        The prism's index.

    Returns
    -------
    ndarray
        ``θ_d + asin(sin φ / n_g)``, degrees, in the glass: use it with ``n0 = n_glass`` and
        ``design_aoi_deg = coating_aoi_deg`` in :func:`shift_curve`.  With θ_d = 0 this gives the air law
        exactly (``n_g·sin(asin(sin φ/n_g)) = sin φ``).

    References
    ----------
    .. [Smith2008] see docs/references.md; Snell's law and chapter 11.
    """
    phi = _angle(field_deg, "prism.field_deg")
    n_glass = _index(n_glass, "prism.n_glass")
    return float(coating_aoi_deg) + np.degrees(np.arcsin(np.sin(np.radians(phi)) / n_glass))


def dye_internal_angle_deg(aoi_deg: ArrayLike, n_dye: float = N_DYE, n0: float = 1.0) -> np.ndarray:
    """The angle of a ray inside a CFA's dye layer (Snell; the layers above are parallel, so n·sinθ is kept).

    Parameters
    ----------
    aoi_deg : array_like
        Angle of incidence on the sensor in the medium of index ``n0``, degrees.
    n_dye : float
        The dye layer's index (:data:`N_DYE`).
    n0 : float
        The incident medium's index (1: air).

    Returns
    -------
    ndarray
        θ_i = asin(n₀ sinθ / n_d), degrees.

    References
    ----------
    .. [COMPASS] see docs/references.md; the colour-filter layer's index.
    """
    theta = _angle(aoi_deg, "dye.aoi_deg")
    n_dye, n0 = _index(n_dye, "dye.n_dye"), _index(n0, "dye.n0")
    s = n0 * np.sin(np.radians(theta)) / n_dye
    if np.any(np.abs(s) >= 1):
        raise ConfigError("dye.n_dye", n_dye, "must exceed n0·sinθ (the ray would not enter the dye)")
    return np.degrees(np.arcsin(s))


def dye_path_factor(aoi_deg: ArrayLike, n_dye: float = N_DYE, n0: float = 1.0) -> np.ndarray:
    """How much longer the oblique path through a dye layer is: ``1/cos θ_i``.

    Parameters
    ----------
    aoi_deg : array_like
        Angle of incidence, degrees.
    n_dye, n0 : float
        As :func:`dye_internal_angle_deg`.

    Returns
    -------
    ndarray
        ``1/cos θ_i`` ≥ 1, float64; exactly 1 at θ = 0.

    References
    ----------
    .. [Macleod2010] see docs/references.md; absorption along an oblique path.
    """
    return 1.0 / np.cos(np.radians(dye_internal_angle_deg(aoi_deg, n_dye, n0)))


def dye_transmittance(transmittance: ArrayLike, aoi_deg: ArrayLike, n_dye: float = N_DYE, n0: float = 1.0) -> np.ndarray:
    """A CFA dye's transmittance at an angle of incidence (Beer–Lambert along the longer path).

    Parameters
    ----------
    transmittance : array_like
        ``(n,)`` the dye's internal transmittance at normal incidence, in [0, 1].
    aoi_deg : array_like
        Angles of incidence, degrees, any shape S.
    n_dye, n0 : float
        As :func:`dye_internal_angle_deg`.

    Returns
    -------
    ndarray
        ``S + (n,)``: ``T^(1/cos θ_i)``; exactly ``transmittance`` at θ = 0.  Surface reflections are
        not part of it (their change with angle is small below ~30°).

    References
    ----------
    .. [Macleod2010] see docs/references.md; .. [COMPASS] likewise.
    """
    t = np.asarray(transmittance, dtype=np.float64)
    if not np.all(np.isfinite(t)) or np.any(t < 0) or np.any(t > 1):
        raise ConfigError("dye.transmittance", [float(np.nanmin(t)), float(np.nanmax(t))],
                          "values must lie in [0, 1]")
    path = np.asarray(dye_path_factor(aoi_deg, n_dye, n0))[..., None]
    out = np.power(t, path)
    return np.where(path == 1.0, t, out)
