"""The pixel's response to the angle of the light that reaches it (issue 37, item 2).

Off the optical axis the chief ray reaches a pixel at an angle θ (the chief-ray angle, CRA, of the lens at that
image height).  Three things then change, per wavelength:

**Microlens acceptance** (:func:`microlens_acceptance`).  The microlens focuses the light through a dielectric stack
of height ``h`` and index ``n_s`` onto the photodiode's opening, a square of side ``a = a_f·p`` (pitch ``p``).  A ray
at θ in air travels at ``θ_s = asin(sin θ / n_s)`` in the stack, so the focused spot lands displaced by
``h·tan θ_s`` from the opening's centre [Catrysse2002]; a microlens shifted towards the optical axis by ``s`` brings
it back by ``s``, and the shift that cancels a stated CRA is ``s = h·tan θ_s(CRA)`` (:func:`microlens_shift_um`;
[Agranov2003] measure the response of such shifted microlenses).  The spot is a Gaussian (``spot = "gaussian"``) of
rms radius ``σ² = σ_diff² + (r_cone/2)²`` — the diffraction spot of the microlens, ``σ_diff = 0.42·(λ/n_s)·N_ml``
with ``N_ml = h/p`` [Zhang2007], and the geometric image of the lens's cone of half-angle ``atan(1/2N)`` (a disc of
radius ``r_cone = h·tan θ_s(cone)``, rms ``r_cone/2`` per axis) — or a square top-hat of the same rms (``"tophat"``).
The acceptance is the fraction of the spot inside the opening, divided by its value at normal incidence with no
shift: 1 on the axis, so a centred pixel at normal incidence keeps today's response exactly.

**Optical crosstalk** (:func:`crosstalk_kernel`).  The light that enters the silicon through the opening refracts to
``θ_si = asin(sin θ / n_Si(λ))`` and is absorbed at depth ``z`` with density ``α'·exp(−α'·z)``, ``α' = α/cos θ_si``
(Beer–Lambert along the oblique path), having moved laterally by ``z·tan θ_si``.  Charge generated above the
collection depth ``d`` (the photodiode QE's ``filters.collection_depth_um``) is collected by the pixel whose cell
it is generated in [Agranov2003]; long wavelengths, absorbed deeper (α small [Green2008]), travel further and leak more.
The entry position is the spot truncated to the opening, which makes each cell's share a closed form in ``erf``,
integrated over depth by Gauss–Legendre quadrature.

**Electrical crosstalk** (``electrical_crosstalk``).  Carriers generated in the field-free layer below ``d``
(thickness ``field_free_depth_um``) diffuse: one generated ``u`` below ``d`` reaches the depletion edge with
probability ``cosh((t − u)/L)/cosh(t/L)`` (steady 1-D diffusion with the edge absorbing and the epi/substrate
interface reflecting, diffusion length ``L`` [Sze2007]), spread laterally by a Gaussian of rms ``u`` (a stated
simplification: isotropic diffusion over the vertical distance travelled).  Today's QE counts none of them.

The kernel ``K[..., b, i, j]`` (3×3 per band ``b``) is the charge that lands in the pixel at row offset ``i − 1`` and
column offset ``j − 1`` per unit of today's collected charge (the collection-depth QE at normal incidence); charge
beyond the neighbours is given to the nearest neighbour, so the kernel sums to the pixel's collected fraction
exactly.  :func:`apply_crosstalk` spreads a charge image with it (charge conserved at the borders by reflection), and
:func:`effective_responsivities` turns a colour-filter mosaic's responsivities into what each tile site records.

References: see ``docs/references.md`` ([Agranov2003], [Catrysse2002], [Green2008], [Sze2007], [Zhang2007]).
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from spectracam.core.errors import ConfigError
from spectracam.core.spec import Spec

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["SPOT_SHAPES", "PixelAngleSpec", "angle_in_medium_deg", "apply_crosstalk", "crosstalk_kernel",
           "effective_responsivities", "identity_kernel", "microlens_acceptance", "microlens_shift_um",
           "pixel_angle_response", "spot_sigma_um"]

#: Spot shapes on the photodiode: a Gaussian, or a square top-hat of the same rms per axis.
SPOT_SHAPES = ("gaussian", "tophat")
#: Gauss–Legendre nodes per depth interval of the crosstalk integral.
_DEPTH_NODES = 48


@dataclass(frozen=True)
class PixelAngleSpec(Spec):
    """How the pixel answers the angle of incidence; every switch off by default (today's response)."""

    TABLE = "pixel"

    #: Microlens acceptance against angle on (False: acceptance 1 everywhere, as today).
    microlens: bool = False
    #: Height of the dielectric stack from the microlens to the photodiode, µm: the microlens focuses on the
    #: photodiode, so it is also its focal length.  4 µm: a front-side-illuminated stack of a few metal layers
    #: (Catrysse & Wandell 2002 [Catrysse2002] model stacks of this order); a back-side-illuminated pixel's is ~1–2 µm.
    stack_height_um: float = 4.0
    #: Refractive index of the stack: 1.46, silicon dioxide.
    stack_index: float = 1.46
    #: Side of the photodiode's square opening as a fraction of the pitch: 0.5 (a quarter of the area, a stated
    #: choice typical of a front-side-illuminated 4T pixel).
    aperture_fraction: float = 0.5
    #: "gaussian" or "tophat" (:data:`SPOT_SHAPES`).
    spot: str = "gaussian"
    #: The microlens shift as a fraction of the one that cancels the lens's CRA at each image height
    #: (shift = fraction × stack height × tan θ_s(CRA)); 0: microlenses centred on their pixels.
    microlens_shift_fraction: float = 0.0
    #: Optical crosstalk (oblique light absorbed under the neighbour) on.
    optical_crosstalk: bool = False
    #: Electrical crosstalk (carriers diffusing from the field-free layer below the collection depth) on.
    electrical_crosstalk: bool = False
    #: Thickness of the field-free layer below the collection depth, µm: 3 µm, a stated choice (epitaxial layers of
    #: CMOS image sensors are a few µm thick).
    field_free_depth_um: float = 3.0
    #: Minority-carrier (electron) diffusion length in it, µm: 100 µm, the order of √(D·τ) with D ≈ 35 cm²/s and
    #: τ ≈ 3 µs in lightly doped p-type silicon [Sze2007].
    diffusion_length_um: float = 100.0
    #: The filters' response to the chief ray's angle across the field (spectracam.architecture.angle): the prism's
    #: dichroic coatings and the field-sequential wheel's interference filters shift to shorter wavelengths, a CFA's
    #: dyes absorb along a longer path.  Off by default (the filters as at normal incidence everywhere); it changes
    #: nothing where the chief-ray angle is 0.
    filter_angle: bool = False

    def validate(self) -> None:
        self.boolean("microlens", "optical_crosstalk", "electrical_crosstalk", "filter_angle")
        self.number("stack_height_um", 0, 100, lo_open=True, unit="µm")
        self.number("stack_index", 1, 4)
        self.number("aperture_fraction", 0, 1, lo_open=True)
        self.choice("spot", SPOT_SHAPES)
        self.number("microlens_shift_fraction", 0, 2)
        self.number("field_free_depth_um", 0, 1000, unit="µm")
        self.number("diffusion_length_um", 0, 1e6, lo_open=True, unit="µm")

    @property
    def any_on(self) -> bool:
        """Whether anything differs from today's response."""
        return self.microlens or self.optical_crosstalk or self.electrical_crosstalk


def _checked_angle(theta_deg, name: str = "theta_deg") -> np.ndarray:
    t = np.asarray(theta_deg, dtype=float)
    if not np.all(np.isfinite(t)) or np.any(np.abs(t) >= 90):
        raise ConfigError(name, _shown(t), "must be finite angles of incidence strictly between -90 and 90 degrees")
    return t


def _shown(a: np.ndarray):
    return float(a) if a.ndim == 0 else f"array with values {np.nanmin(a):g}…{np.nanmax(a):g}"


def _positive(values, name: str, unit: str = "") -> np.ndarray:
    a = np.asarray(values, dtype=float)
    if a.size == 0 or not np.all(np.isfinite(a)) or np.any(a <= 0):
        raise ConfigError(name, _shown(a) if a.size else [], f"must be finite numbers > 0{unit}")
    return a


def angle_in_medium_deg(theta_deg: ArrayLike, index: ArrayLike) -> np.ndarray:
    """The ray's angle inside a medium of refractive index ``index`` after entering from air (Snell's law).

    Parameters
    ----------
    theta_deg : float or array_like
        Angle of incidence in air, degrees, |θ| < 90.
    index : float or array_like
        Refractive index of the medium (≥ 1), broadcast against ``theta_deg``.

    Returns
    -------
    numpy.ndarray
        ``asin(sin θ / n)`` in degrees.

    References
    ----------
    .. [Catrysse2002] see docs/references.md (the stack's refraction).
    """
    t = np.radians(_checked_angle(theta_deg))
    return np.degrees(np.arcsin(np.sin(t) / _positive(index, "index")))


def microlens_shift_um(cra_deg: ArrayLike, spec: PixelAngleSpec) -> np.ndarray:
    """The microlens shift that cancels a chief-ray angle: ``stack height × tan θ_s(CRA)``, µm.

    Parameters
    ----------
    cra_deg : float or array_like
        The chief-ray angle to compensate, degrees (in air).
    spec : PixelAngleSpec
        The stack (``stack_height_um``, ``stack_index``).

    Returns
    -------
    numpy.ndarray
        The shift towards the optical axis, µm, where the focused spot of a ray at ``cra_deg`` lands back on
        the opening's centre.

    References
    ----------
    .. [Agranov2003] see docs/references.md (shifted microlenses).
    """
    return spec.stack_height_um * np.tan(np.radians(angle_in_medium_deg(cra_deg, spec.stack_index)))


def spot_sigma_um(wavelength_nm: ArrayLike, spec: PixelAngleSpec, *, pixel_pitch_um: float,
                  f_number: float | None = None) -> np.ndarray:
    """Rms radius per axis of the microlens's spot on the photodiode, µm.

    Parameters
    ----------
    wavelength_nm : array_like
        Wavelengths, nm.
    spec : PixelAngleSpec
        The stack.
    pixel_pitch_um : float
        Pixel pitch p, µm (the microlens's diameter).
    f_number : float, optional
        The lens's f-number N (its cone of half-angle ``atan(1/2N)``); None: collimated light.

    Returns
    -------
    numpy.ndarray
        ``√(σ_diff² + (r_cone/2)²)``, ``σ_diff = 0.42·(λ/n_s)·h/p`` [Zhang2007], ``r_cone = h·tan θ_s(cone)``.

    References
    ----------
    .. [Zhang2007] see docs/references.md (Gaussian approximation of the Airy spot).
    """
    wl_um = _positive(wavelength_nm, "wavelength_nm", " nm") * 1e-3
    p = float(_positive(pixel_pitch_um, "pixel_pitch_um", " µm"))
    sigma_diff = 0.42 * (wl_um / spec.stack_index) * spec.stack_height_um / p
    r_cone = 0.0
    if f_number is not None:
        cone_deg = np.degrees(np.arctan(0.5 / float(_positive(f_number, "f_number"))))
        r_cone = spec.stack_height_um * np.tan(np.radians(angle_in_medium_deg(cone_deg, spec.stack_index)))
    return np.sqrt(sigma_diff**2 + (r_cone / 2) ** 2)


def _erf(x):
    """The error function, from SciPy, imported on first use (the camera stage imports this module; SciPy's import
    costs as much as the rest of a command's start-up)."""
    from scipy.special import erf

    return erf(x)


def _cdf(x, mu, sigma, shape: str):
    """The spot's 1-D cumulative distribution at ``x`` (centre ``mu``, rms ``sigma``)."""
    if shape == "gaussian":
        return 0.5 * (1 + _erf((x - mu) / (np.sqrt(2) * sigma)))
    half = np.sqrt(3) * sigma  # a top-hat of rms σ spans ±√3·σ
    return np.clip((x - mu + half) / (2 * half), 0.0, 1.0)


def _inside(d_um, sigma, half_um, shape: str):
    """Fraction of a 1-D spot centred at ``d_um`` inside ``[−half, half]``."""
    return _cdf(half_um, d_um, sigma, shape) - _cdf(-half_um, d_um, sigma, shape)


def _residual_um(theta_deg, spec: PixelAngleSpec, shift_um):
    """Signed radial displacement of the spot from the opening's centre: ``h·tan θ_s − shift``, µm."""
    return microlens_shift_um(theta_deg, spec) - np.asarray(shift_um, float)


def microlens_acceptance(theta_deg: ArrayLike, wavelength_nm: ArrayLike, spec: PixelAngleSpec, *,
                         pixel_pitch_um: float, f_number: float | None = None, shift_um: ArrayLike = 0.0,
                         azimuth_deg: ArrayLike = 0.0) -> np.ndarray:
    """Relative microlens acceptance: the fraction of the focused spot inside the photodiode's opening, over its
    value at normal incidence with no shift.

    Parameters
    ----------
    theta_deg : float or array_like
        Angle of incidence of the chief ray at each pixel, degrees (shape ``S``).
    wavelength_nm : array_like
        Band centres, nm (shape ``(B,)``).
    spec : PixelAngleSpec
        The stack, opening and spot shape.  With ``spec.microlens`` off the acceptance is 1.
    pixel_pitch_um : float
        Pixel pitch, µm.
    f_number : float, optional
        The lens's f-number (the spot's geometric part, :func:`spot_sigma_um`).
    shift_um : float or array_like
        Microlens shift towards the axis at each pixel, µm (broadcast against ``theta_deg``; :func:`microlens_shift_um`).
    azimuth_deg : float or array_like
        Direction of the image height at each pixel, degrees (0: along a row).

    Returns
    -------
    numpy.ndarray
        ``(*S, B)`` acceptance, exactly 1 at θ = 0 with no shift.

    References
    ----------
    .. [Catrysse2002] see docs/references.md (geometric optical efficiency against angle).
    """
    theta = _checked_angle(theta_deg)
    wl = np.atleast_1d(_positive(wavelength_nm, "wavelength_nm", " nm"))
    shape = np.broadcast_shapes(theta.shape, np.shape(shift_um), np.shape(azimuth_deg))
    if not spec.microlens:
        return np.ones((*shape, wl.size))
    sigma = spot_sigma_um(wl, spec, pixel_pitch_um=pixel_pitch_um, f_number=f_number)
    half = 0.5 * spec.aperture_fraction * pixel_pitch_um
    d = _residual_um(theta, spec, shift_um)[..., None]
    phi = np.radians(np.asarray(azimuth_deg, float))[..., None]
    f = _inside(d * np.cos(phi), sigma, half, spec.spot) * _inside(d * np.sin(phi), sigma, half, spec.spot)
    f0 = _inside(0.0, sigma, half, spec.spot) * _inside(0.0, sigma, half, spec.spot)
    return np.broadcast_to(f / f0, (*shape, wl.size)).copy()


def identity_kernel(shape: Sequence[int] = (), n_bands: int = 1) -> np.ndarray:
    """The kernel of no crosstalk: ``(*shape, n_bands, 3, 3)`` with 1 at the centre, 0 elsewhere.

    Parameters
    ----------
    shape : sequence of int
        The leading shape (e.g. a field's ``(H, W)``); ``()`` for one kernel.
    n_bands : int
        The number of wavelength bands.

    Returns
    -------
    ndarray
        ``(*shape, n_bands, 3, 3)`` float64.
    """
    k = np.zeros((*tuple(shape), n_bands, 3, 3))
    k[..., 1, 1] = 1.0
    return k


def _cells_truncated(mu, entry_mu, sigma, half, pitch, shape: str):
    """Share of charge in the cells −1, 0, +1 along one axis: the entry position (the spot centred at ``entry_mu``,
    rms ``sigma``, truncated to the opening ``[−half, half]``) moved by ``mu``.  ``(..., 3)``, summing to 1."""
    lo = _cdf(-half, entry_mu, sigma, shape)
    norm = _cdf(half, entry_mu, sigma, shape) - lo
    c = [(_cdf(np.clip(e - mu, -half, half), entry_mu, sigma, shape) - lo) / norm for e in (-0.5 * pitch, 0.5 * pitch)]
    return np.stack([c[0], c[1] - c[0], 1 - c[1]], axis=-1)


def _cells_gaussian(mu, mean, var, pitch):
    """As :func:`_cells_truncated` for a Gaussian position of ``mean + mu`` and variance ``var``."""
    s = np.sqrt(var)
    c = [0.5 * (1 + _erf((e - mu - mean) / (np.sqrt(2) * s))) for e in (-0.5 * pitch, 0.5 * pitch)]
    return np.stack([c[0], c[1] - c[0], 1 - c[1]], axis=-1)


def _truncated_moments(entry_mu, sigma, half, shape: str, n: int = 65):
    """Mean and variance of the spot truncated to the opening (midpoint quadrature over the opening)."""
    x = (np.arange(n) + 0.5) / n * 2 * half - half
    mu, sg = np.asarray(entry_mu)[..., None], np.asarray(sigma)[..., None]
    w = _cdf(x + half / n, mu, sg, shape) - _cdf(x - half / n, mu, sg, shape)
    w = w / np.maximum(w.sum(-1, keepdims=True), 1e-300)
    m = (w * x).sum(-1)
    return m, np.maximum((w * x**2).sum(-1) - m**2, 0.0)


def _depth_integral(weight_fn, cells_fn, lo_um, hi_um, alpha):
    """``∫ weight(z)·cells(z) dz`` over ``[lo, hi]`` (Gauss–Legendre), rescaled so its total is the exact
    ``∫ weight`` given by ``weight_fn(None)`` (None: not rescaled); returns ``(..., 3, 3)``."""
    x, w = np.polynomial.legendre.leggauss(_DEPTH_NODES)
    total = None
    for xi, wi in zip(x, w):
        z = lo_um + (hi_um - lo_um) * (xi + 1) / 2
        term = (wi * (hi_um - lo_um) / 2) * weight_fn(z)[..., None, None] * cells_fn(z)
        total = term if total is None else total + term
    exact = weight_fn(None)
    if exact is None:
        return total
    quad = total.sum((-2, -1))
    scale = np.divide(exact, quad, out=np.zeros_like(quad), where=quad > 0)
    return total * scale[..., None, None]


class _Geometry:
    """Per (pixel, band) quantities shared by the optical and electrical integrals."""

    def __init__(self, theta_deg, wavelength_nm, alpha_per_um, n_silicon, spec, pitch, f_number, shift_um,
                 azimuth_deg):
        theta = _checked_angle(theta_deg)
        wl = np.atleast_1d(_positive(wavelength_nm, "wavelength_nm", " nm"))
        alpha = np.broadcast_to(_positive(alpha_per_um, "alpha_per_um", " per µm"), wl.shape)
        n_si = np.broadcast_to(_positive(n_silicon, "n_silicon"), wl.shape)
        self.shape = np.broadcast_shapes(theta.shape, np.shape(shift_um), np.shape(azimuth_deg))
        t_si = np.radians(angle_in_medium_deg(theta[..., None], n_si))  # (*S, B)
        phi = np.radians(np.asarray(azimuth_deg, float))[..., None]
        self.tan_x, self.tan_y = np.tan(t_si) * np.cos(phi), np.tan(t_si) * np.sin(phi)
        self.alpha, self.alpha_path = alpha, alpha / np.cos(t_si)
        d = _residual_um(theta, spec, shift_um)[..., None]
        self.entry_x, self.entry_y = d * np.cos(phi) + 0 * t_si, d * np.sin(phi) + 0 * t_si
        self.sigma = spot_sigma_um(wl, spec, pixel_pitch_um=pitch, f_number=f_number) + 0 * t_si
        self.half, self.pitch, self.spot = 0.5 * spec.aperture_fraction * pitch, pitch, spec.spot


def _optical(g: _Geometry, depth_um: float) -> np.ndarray:
    """Charge collected above the collection depth, per cell, per unit of today's (normal-incidence) charge."""
    today = -np.expm1(-g.alpha * depth_um)

    def weight(z):
        if z is None:
            return -np.expm1(-g.alpha_path * depth_um) / today
        return g.alpha_path * np.exp(-g.alpha_path * z) / today

    def cells(z):
        cx = _cells_truncated(z * g.tan_x, g.entry_x, g.sigma, g.half, g.pitch, g.spot)
        cy = _cells_truncated(z * g.tan_y, g.entry_y, g.sigma, g.half, g.pitch, g.spot)
        return cy[..., :, None] * cx[..., None, :]

    return _depth_integral(weight, cells, 0.0, depth_um, g.alpha)


def _electrical(g: _Geometry, depth_um: float, spec: PixelAngleSpec) -> np.ndarray:
    """Charge diffusing up from the field-free layer below the collection depth, per cell, per unit of today's."""
    thick, length = spec.field_free_depth_um, spec.diffusion_length_um
    today = -np.expm1(-g.alpha * depth_um)
    mx, vx = _truncated_moments(g.entry_x, g.sigma, g.half, g.spot)
    my, vy = _truncated_moments(g.entry_y, g.sigma, g.half, g.spot)

    def weight(z):
        if z is None:
            return None
        reach = np.cosh((thick - (z - depth_um)) / length) / np.cosh(thick / length)
        return g.alpha_path * np.exp(-g.alpha_path * z) * reach / today

    def cells(z):
        u2 = (z - depth_um) ** 2
        cx = _cells_gaussian(z * g.tan_x, mx, vx + u2, g.pitch)
        cy = _cells_gaussian(z * g.tan_y, my, vy + u2, g.pitch)
        return cy[..., :, None] * cx[..., None, :]

    return _depth_integral(weight, cells, depth_um, depth_um + thick, g.alpha)


def crosstalk_kernel(theta_deg: ArrayLike, wavelength_nm: ArrayLike, alpha_per_um: ArrayLike, n_silicon: ArrayLike,
                     spec: PixelAngleSpec, *, pixel_pitch_um: float, collection_depth_um: float,
                     f_number: float | None = None, shift_um: ArrayLike = 0.0, azimuth_deg: ArrayLike = 0.0
                     ) -> np.ndarray:
    """Where a pixel's photo-charge is collected: a 3×3 kernel per band.

    Parameters
    ----------
    theta_deg : float or array_like
        Angle of incidence of the chief ray at each pixel, degrees (shape ``S``).
    wavelength_nm : array_like
        Band centres, nm (``(B,)``).
    alpha_per_um : array_like
        Silicon's absorption coefficient at those bands, 1/µm (``(B,)``; the camera passes
        ``spectracam.architecture.silicon.absorption_coefficient_per_um(grid.centres_nm)`` [Green2008]).
    n_silicon : float or array_like
        Silicon's refractive index at those bands (``(B,)`` or one number; Green's table gives 3.9–4.7 in the visible).
    spec : PixelAngleSpec
        The pixel (``optical_crosstalk``, ``electrical_crosstalk`` and their parameters; the spot and opening).
    pixel_pitch_um : float
        Pixel pitch, µm.
    collection_depth_um : float
        Depth above which the photodiode collects its own cell's charge, µm (``filters.collection_depth_um``).
    f_number : float, optional
        The lens's f-number (the spot's size, :func:`spot_sigma_um`).
    shift_um : float or array_like
        Microlens shift towards the axis at each pixel, µm.
    azimuth_deg : float or array_like
        Direction of the image height at each pixel, degrees (0: along a row, towards increasing column).

    Returns
    -------
    numpy.ndarray
        ``(*S, B, 3, 3)``: ``K[..., b, i, j]`` is the charge collected by the pixel at row offset ``i − 1`` and column
        offset ``j − 1``, per unit of the charge today's collection-depth QE counts at normal incidence.  Its sum is
        the pixel's collected fraction; with both crosstalks off it is 1 at the centre and 0 elsewhere.

    References
    ----------
    .. [Agranov2003] see docs/references.md (optical and electrical crosstalk against angle).
    .. [Green2008] see docs/references.md (α of silicon).
    .. [Sze2007] see docs/references.md (minority-carrier diffusion).
    """
    depth = float(_positive(collection_depth_um, "collection_depth_um", " µm"))
    g = _Geometry(theta_deg, wavelength_nm, alpha_per_um, n_silicon, spec, float(_positive(
        pixel_pitch_um, "pixel_pitch_um", " µm")), f_number, shift_um, azimuth_deg)
    n_bands = g.alpha.size
    if not (spec.optical_crosstalk or spec.electrical_crosstalk):
        return identity_kernel(g.shape, n_bands)
    k = _optical(g, depth) if spec.optical_crosstalk else identity_kernel(g.shape, n_bands) * \
        (-np.expm1(-g.alpha_path * depth) / -np.expm1(-g.alpha * depth))[..., None, None]
    if spec.electrical_crosstalk and spec.field_free_depth_um > 0:
        k = k + _electrical(g, depth, spec)
    return np.broadcast_to(k, (*g.shape, n_bands, 3, 3)).copy()


def pixel_angle_response(theta_deg: ArrayLike, wavelength_nm: ArrayLike, alpha_per_um: ArrayLike,
                         n_silicon: ArrayLike, spec: PixelAngleSpec, *, pixel_pitch_um: float,
                         collection_depth_um: float, f_number: float | None = None, shift_um: ArrayLike = 0.0,
                         azimuth_deg: ArrayLike = 0.0) -> np.ndarray:
    """Microlens acceptance times the crosstalk kernel: the whole per-band transfer of a pixel at angle θ.

    Parameters
    ----------
    theta_deg, wavelength_nm, alpha_per_um, n_silicon, spec, pixel_pitch_um, collection_depth_um, f_number, shift_um, azimuth_deg
        As :func:`crosstalk_kernel` (and :func:`microlens_acceptance`).

    Returns
    -------
    numpy.ndarray
        ``(*S, B, 3, 3)``; exactly :func:`identity_kernel` when ``spec`` has everything off, and at θ = 0 with no
        shift when only the microlens is on.

    References
    ----------
    .. [Catrysse2002] see docs/references.md.
    """
    kw = dict(pixel_pitch_um=pixel_pitch_um, f_number=f_number, shift_um=shift_um, azimuth_deg=azimuth_deg)
    acc = microlens_acceptance(theta_deg, wavelength_nm, spec, **kw)
    k = crosstalk_kernel(theta_deg, wavelength_nm, alpha_per_um, n_silicon, spec,
                         collection_depth_um=collection_depth_um, **kw)
    return k if not spec.microlens else k * acc[..., None, None]


def apply_crosstalk(charge_e: ArrayLike, kernel: ArrayLike) -> np.ndarray:
    """Spread a charge image by a crosstalk kernel; charge sent off the image is reflected back into its edge pixel.

    Parameters
    ----------
    charge_e : array_like
        ``(H, W)`` charge generated at each pixel, electrons (one band, or already weighted).
    kernel : array_like
        ``(3, 3)`` for every pixel, or ``(H, W, 3, 3)`` per pixel (the source pixel's), as :func:`crosstalk_kernel`.

    Returns
    -------
    numpy.ndarray
        ``(H, W)`` charge collected; its total is ``Σ charge·kernel.sum()`` (for a kernel summing to 1, the input's).

    References
    ----------
    .. [Agranov2003] see docs/references.md.
    """
    q = np.asarray(charge_e, dtype=float)
    k = np.asarray(kernel, dtype=float)
    if q.ndim != 2 or k.shape[-2:] != (3, 3) or k.ndim not in (2, 4) or (k.ndim == 4 and k.shape[:2] != q.shape):
        raise ConfigError("kernel", f"shape {k.shape} for charge {q.shape}",
                          "must be (3, 3) or (H, W, 3, 3) beside an (H, W) charge image")
    h, w = q.shape
    out = np.zeros((h + 2, w + 2))
    for i in range(3):
        for j in range(3):
            out[i:i + h, j:j + w] += q * k[..., i, j]
    out[1, :] += out[0, :]
    out[-2, :] += out[-1, :]
    out[:, 1] += out[:, 0]
    out[:, -2] += out[:, -1]
    return out[1:-1, 1:-1]


def effective_responsivities(tile: ArrayLike, responsivities: ArrayLike, kernel: ArrayLike) -> np.ndarray:
    """What each site of a colour-filter mosaic records, with its neighbours' light leaking in (a locally uniform
    scene): ``R_eff[r, c] = Σ_ij R[tile[r − i + 1, c − j + 1]]·K[i, j]`` (indices modulo the tile).

    Parameters
    ----------
    tile : array_like of int
        ``(th, tw)`` channel index at each site, e.g. RGGB as ``[[0, 1], [1, 2]]``.
    responsivities : array_like
        ``(N, B)`` responsivity of each channel per band (filter × QE), e⁻/photon.
    kernel : array_like
        ``(..., B, 3, 3)`` per band (:func:`crosstalk_kernel` or :func:`pixel_angle_response`).

    Returns
    -------
    numpy.ndarray
        ``(..., th, tw, B)`` effective responsivities; with :func:`identity_kernel`, exactly ``R[tile]``.

    References
    ----------
    .. [Agranov2003] see docs/references.md (the colour mixing that crosstalk causes in a Bayer mosaic).
    """
    t = np.asarray(tile)
    R = np.asarray(responsivities, dtype=float)
    k = np.asarray(kernel, dtype=float)
    if t.ndim != 2 or t.size == 0 or not np.issubdtype(t.dtype, np.integer) or t.min() < 0 or t.max() >= len(R):
        raise ConfigError("tile", np.asarray(tile).tolist(), f"must be a 2-D tile of channel indices 0…{len(R) - 1}")
    if R.ndim != 2 or k.shape[-3:] != (R.shape[1], 3, 3):
        raise ConfigError("kernel", f"shape {k.shape}", f"must be (..., {R.shape[1]}, 3, 3) for responsivities "
                          f"{R.shape}")
    th, tw = t.shape
    rows, cols = np.arange(th)[:, None], np.arange(tw)[None, :]
    out = np.zeros((*k.shape[:-3], th, tw, R.shape[1]))
    for i in range(3):
        for j in range(3):
            src = t[(rows - (i - 1)) % th, (cols - (j - 1)) % tw]  # (th, tw): the channel whose light arrives
            out = out + R[src] * k[..., None, None, :, i, j]
    return out
