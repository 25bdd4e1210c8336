"""The optics across the field: where each pixel sits, the chief ray's angle there and the light it gets.

The paper (section 3.2) computes the irradiance of the centre of the field only.  Off the axis a lens
delivers less: the *relative illumination* ``RI(h) = E(h)/E(0)`` at image height ``h`` falls, by the
natural vignetting cos⁴θ of the chief ray's angle θ [Smith2008]_, by a lens's own curve (its exit pupil
seen obliquely [Foote1915]_, or a measured table), or by lensfun's polynomial ``1 + k₁r² + k₂r⁴ + k₃r⁶``
[Lensfun]_.  The chief-ray angle (CRA) that reaches a pixel, on which the filters' and the pixel's angular
response depend (:mod:`spectracam.architecture.angle`), is stated at the corner (growing linearly with
the image height), read from a table (a sensor or lens datasheet's CRA curve), or follows from the exit
pupil's distance, ``tan θ = h / z_ep``.  Outside the lens's image circle no light arrives.

Everything here is float64 NumPy over whole images.  :class:`FieldSpec`'s defaults mean *on the axis
everywhere*: CRA 0 and relative illumination exactly 1, so a camera that leaves them alone is today's.
"""
from __future__ import annotations

import functools
import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from spectracam.core.errors import ConfigError
from spectracam.core.spec import Spec

__all__ = ["CHIEF_RAY_MODELS", "EXIT_PUPIL_FORMS", "FULL_FRAME_HALF_DIAGONAL_MM", "LENSFUN_DIR",
           "RELATIVE_ILLUMINATION_FORMS", "FieldMaps", "FieldSpec", "LensfunVignetting", "chief_ray_angle_deg",
           "cos4_illumination", "exit_pupil_illumination", "field_maps", "half_diagonal_mm", "image_height_mm",
           "lensfun_vignetting", "pa_illumination", "pixel_positions_mm", "relative_illumination"]

#: How the relative illumination falls across the field (:func:`relative_illumination`).
RELATIVE_ILLUMINATION_FORMS = ("none", "cos4", "exit_pupil", "table", "pa")
#: The exit-pupil form: "small" (a small pupil: cos⁴ of the angle the pupil's centre subtends) or "disk"
#: (the pupil a uniform disc of radius ``z_ep/(2N)``, exact for any aperture [Foote1915]_).
EXIT_PUPIL_FORMS = ("small", "disk")
#: Where the chief-ray angle comes from (:func:`chief_ray_angle_deg`).
CHIEF_RAY_MODELS = ("linear", "table", "exit_pupil")
#: Debian's ``liblensfun-data-v1`` database [Lensfun]_.
LENSFUN_DIR = Path("/usr/share/lensfun/version_1")
#: Half the diagonal of the 36 × 24 mm frame, mm: lensfun's (Hugin's) vignetting radius r = 1 at crop factor 1.
FULL_FRAME_HALF_DIAGONAL_MM = math.hypot(36.0, 24.0) / 2


@dataclass(frozen=True, kw_only=True)
class FieldSpec(Spec):
    """The lens and sensor across the field.  ``TABLE`` is ``"optics"``: the fields belong in the camera's
    ``[optics]`` table (:class:`~spectracam.optics.OpticsSpec` derives from this class; the fields are keyword-only,
    so a derived spec's own positional fields keep their places)."""

    TABLE = "optics"

    #: "none" (1 everywhere: the paper), "cos4" (cos⁴ of the chief-ray angle), "exit_pupil" (the lens's own
    #: curve from ``exit_pupil_mm``), "table" (a measured curve) or "pa" (lensfun's polynomial).
    relative_illumination: str = "none"
    #: Distance from the exit pupil to the image plane, mm (a lens datasheet gives it); None: not stated.
    exit_pupil_mm: float | None = None
    #: The exit-pupil form: "small" (cos⁴) or "disk" (the pupil a disc of the camera's f-number).
    exit_pupil_form: str = "small"
    #: A measured relative illumination: image heights, mm (increasing), and RI there (1 on the axis).
    illumination_height_mm: tuple = ()
    illumination_curve: tuple = ()
    #: lensfun's "pa" coefficients (k1, k2, k3) and the image height of r = 1, mm (None: the sensor's half
    #: diagonal); :meth:`LensfunVignetting.field` fills both from the database.
    pa_k: tuple = ()
    pa_radius_mm: float | None = None
    #: The chief-ray angle: "linear" (``cra_corner_deg`` at ``cra_corner_mm``), "table" or "exit_pupil".
    chief_ray: str = "linear"
    #: CRA at the corner, degrees; 0: telecentric (on axis everywhere).
    cra_corner_deg: float = 0.0
    #: The image height at which ``cra_corner_deg`` is stated, mm; None: the sensor's half diagonal.
    cra_corner_mm: float | None = None
    #: A CRA curve: image heights, mm (increasing), and CRA there, degrees.
    cra_height_mm: tuple = ()
    cra_table_deg: tuple = ()
    #: The lens's image circle, diameter in mm; pixels outside it get no light.  None: it covers the sensor.
    image_circle_diameter_mm: float | None = None
    #: Where the optical axis meets the sensor, (x, y) mm from the sensor's centre.
    optical_centre_mm: tuple = (0.0, 0.0)

    def validate(self) -> None:
        self.validate_field()

    def validate_field(self) -> None:
        """The field's checks, each one line naming the field (an :class:`OpticsSpec` calls it too)."""
        self.choice("relative_illumination", RELATIVE_ILLUMINATION_FORMS)
        self.choice("exit_pupil_form", EXIT_PUPIL_FORMS)
        self.choice("chief_ray", CHIEF_RAY_MODELS)
        for name in ("exit_pupil_mm", "pa_radius_mm", "cra_corner_mm", "image_circle_diameter_mm"):
            if getattr(self, name) is not None:
                self.number(name, 0, 1e5, lo_open=True, unit="mm")
        needs_pupil = self.relative_illumination == "exit_pupil" or self.chief_ray == "exit_pupil"
        if needs_pupil and self.exit_pupil_mm is None:
            raise self.error("exit_pupil_mm", "must be given (a distance in mm) with relative_illumination or "
                                              "chief_ray \"exit_pupil\"")
        self.number("cra_corner_deg", 0, 80, unit="°")
        c = self.optical_centre_mm
        if not (isinstance(c, tuple) and len(c) == 2 and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                             and math.isfinite(v) for v in c)):
            raise self.error("optical_centre_mm", "must be a list of 2 numbers (x, y), mm",
                             list(c) if isinstance(c, tuple) else c)
        object.__setattr__(self, "optical_centre_mm", tuple(float(v) for v in c))
        self._table("illumination_height_mm", "illumination_curve", self.relative_illumination == "table", 0, 2)
        self._table("cra_height_mm", "cra_table_deg", self.chief_ray == "table", 0, 80)
        if self.relative_illumination == "pa" or self.pa_k:
            self.numbers("pa_k", 3)

    def _table(self, x_name: str, y_name: str, required: bool, lo: float, hi: float) -> None:
        """A curve of image heights (≥ 0 mm, increasing) and values in [lo, hi], of equal length."""
        x, y = getattr(self, x_name), getattr(self, y_name)
        if not x and not y and not required:
            return
        n = len(x) if isinstance(x, tuple) else -1
        if n < 2:
            raise self.error(x_name, "must be ≥ 2 increasing image heights, mm ≥ 0, with as many values in "
                                     + y_name)
        self.numbers(x_name, n, 0, increasing=True, unit="mm")
        if not isinstance(y, tuple) or len(y) != n:
            raise self.error(y_name, f"must be a list of {n} numbers (one per {x_name})")
        self.numbers(y_name, n, lo)
        if max(y) > hi:
            raise self.error(y_name, f"values must lie in [{lo:g}, {hi:g}]", [min(y), max(y)])

    @property
    def on_axis(self) -> bool:
        """True when every pixel is treated as the centre of the field: the defaults (today's camera)."""
        return (self.relative_illumination == "none" and self.chief_ray == "linear" and self.cra_corner_deg == 0
                and self.image_circle_diameter_mm is None)


@dataclass(frozen=True)
class FieldMaps:
    """Per-pixel maps ``(H, W)`` float64: position (x, y) and image height h, mm; chief-ray angle, degrees;
    relative illumination (1 on the axis, 0 outside the image circle)."""

    x_mm: np.ndarray
    y_mm: np.ndarray
    height_mm: np.ndarray
    cra_deg: np.ndarray
    illumination: np.ndarray


def pixel_positions_mm(shape: tuple[int, int], pixel_pitch_um: float,
                       centre_mm: tuple[float, float] = (0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """The lateral position of each pixel's centre relative to the optical axis.

    Parameters
    ----------
    shape : tuple of int
        ``(H, W)`` pixels of the sensor (or the image it records).
    pixel_pitch_um : float
        Pixel pitch, µm (``SensorSpec.pixel_pitch_um``).
    centre_mm : tuple of float
        Where the optical axis meets the sensor, (x, y) mm from the sensor's centre.

    Returns
    -------
    x_mm, y_mm : ndarray
        ``(H, W)`` float64: ``x = (j − (W−1)/2)·p − x₀`` along a row, ``y = (i − (H−1)/2)·p − y₀`` down the
        columns.  With an odd size and the axis centred, the middle pixel is at exactly (0, 0).

    References
    ----------
    .. [Catrysse1999] see docs/references.md; section 3.2 (the centre of the field only).
    """
    h, w = (int(n) for n in shape)
    p_mm = float(pixel_pitch_um) * 1e-3
    x = (np.arange(w, dtype=np.float64) - (w - 1) / 2) * p_mm - float(centre_mm[0])
    y = (np.arange(h, dtype=np.float64) - (h - 1) / 2) * p_mm - float(centre_mm[1])
    return np.broadcast_to(x, (h, w)).copy(), np.broadcast_to(y[:, None], (h, w)).copy()


def image_height_mm(shape: tuple[int, int], pixel_pitch_um: float,
                    centre_mm: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
    """Each pixel's distance from the optical axis, mm.

    Parameters
    ----------
    shape, pixel_pitch_um, centre_mm
        As :func:`pixel_positions_mm`.

    Returns
    -------
    ndarray
        ``(H, W)`` float64 image height ``h = √(x² + y²)``, mm.

    References
    ----------
    .. [Smith2008] see docs/references.md; image height and field angle.
    """
    x, y = pixel_positions_mm(shape, pixel_pitch_um, centre_mm)
    return np.hypot(x, y)


def half_diagonal_mm(shape: tuple[int, int], pixel_pitch_um: float) -> float:
    """Half the sensor's diagonal, mm: ``p·√(W² + H²)/2`` (to the outer corner of the corner pixel).

    Parameters
    ----------
    shape, pixel_pitch_um
        As :func:`pixel_positions_mm`.

    Returns
    -------
    float
        The image height of the sensor's corner, mm.

    References
    ----------
    .. [Lensfun] see docs/references.md; vignetting radius 1 = half the diagonal.
    """
    return float(pixel_pitch_um) * 1e-3 * math.hypot(shape[0], shape[1]) / 2


def chief_ray_angle_deg(height_mm: ArrayLike, field: FieldSpec, corner_mm: float) -> np.ndarray:
    """The chief ray's angle of incidence on the sensor at each image height.

    Parameters
    ----------
    height_mm : array_like
        Image heights, mm.
    field : FieldSpec
        ``chief_ray``: "linear" (``cra_corner_deg·h/h_c``, h_c = ``cra_corner_mm`` or ``corner_mm``; a
        stated CRA grows nearly linearly with h in lens and sensor datasheets), "table" (linear interpolation
        in ``cra_height_mm``/``cra_table_deg``, the end values held beyond them) or "exit_pupil"
        (``atan(h/z_ep)``).
    corner_mm : float
        The sensor's half diagonal, mm (:func:`half_diagonal_mm`).

    Returns
    -------
    ndarray
        CRA, degrees, float64, the shape of ``height_mm``; exactly 0 with the defaults.

    References
    ----------
    .. [Smith2008] see docs/references.md; the chief ray and the exit pupil.
    """
    h = np.asarray(height_mm, dtype=np.float64)
    if field.chief_ray == "table":
        return np.interp(h, field.cra_height_mm, field.cra_table_deg)
    if field.chief_ray == "exit_pupil":
        return np.degrees(np.arctan2(h, field.exit_pupil_mm))
    h_c = field.cra_corner_mm if field.cra_corner_mm is not None else corner_mm
    if field.cra_corner_deg == 0:
        return np.zeros_like(h)
    return field.cra_corner_deg * h / h_c


def cos4_illumination(angle_deg: ArrayLike) -> np.ndarray:
    """The natural vignetting of a small pupil: ``cos⁴θ``.

    Parameters
    ----------
    angle_deg : array_like
        The chief ray's angle θ, degrees.

    Returns
    -------
    ndarray
        ``cos⁴θ``, float64 (1 at θ = 0).

    References
    ----------
    .. [Smith2008] see docs/references.md; the cosine-fourth law of illumination.
    """
    c = np.cos(np.radians(np.asarray(angle_deg, dtype=np.float64)))
    return c**4


def exit_pupil_illumination(height_mm: ArrayLike, exit_pupil_mm: float, f_number: float | None = None) -> np.ndarray:
    """A lens's relative illumination from its exit pupil's distance and the image height.

    Parameters
    ----------
    height_mm : array_like
        Image heights h, mm.
    exit_pupil_mm : float
        Distance z from the exit pupil to the image plane, mm.
    f_number : float, optional
        None: a small pupil, ``cos⁴θ`` with ``tan θ = h/z``.  Given: the pupil a uniform Lambertian disc of
        radius ``a = z/(2N)`` parallel to the sensor, whose irradiance at (ρ = h/z, α = a/z) is
        ``E ∝ 1 − (1 + ρ² − α²)/√((1 + ρ² + α²)² − 4ρ²α²)`` [Foote1915]_, divided by its value on the axis
        ``2α²/(1 + α²)`` (the ``"exact"`` irradiance form ``π/(1 + 4N²)`` of :mod:`spectracam.optics`).  It
        tends to cos⁴θ as N grows.

    Returns
    -------
    ndarray
        Relative illumination E(h)/E(0), float64 (1 on the axis).

    References
    ----------
    .. [Foote1915] see docs/references.md; the irradiance from a radiating disc.
    .. [Smith2008] see docs/references.md; the cosine-fourth law.
    """
    rho = np.asarray(height_mm, dtype=np.float64) / float(exit_pupil_mm)
    if f_number is None:
        return 1.0 / (1.0 + rho**2) ** 2
    a2 = (1.0 / (2.0 * float(f_number))) ** 2
    s = 1.0 + rho**2
    e = 1.0 - (s - a2) / np.sqrt((s + a2) ** 2 - 4.0 * rho**2 * a2)
    return np.where(rho == 0, 1.0, e / (2.0 * a2 / (1.0 + a2)))  # exactly 1 on the axis


def pa_illumination(height_mm: ArrayLike, k: Sequence[float], radius_mm: float) -> np.ndarray:
    """lensfun's (Hugin's, Pablo d'Angelo's) vignetting polynomial.

    Parameters
    ----------
    height_mm : array_like
        Image heights h, mm.
    k : sequence of 3 floats
        (k1, k2, k3).
    radius_mm : float
        The image height of r = 1, mm: half the diagonal of the frame the lens was calibrated on.

    Returns
    -------
    ndarray
        ``V(r) = 1 + k1·r² + k2·r⁴ + k3·r⁶`` with ``r = h/radius_mm``, float64; not clipped (beyond the
        calibrated frame, r > 1, the polynomial is an extrapolation).

    References
    ----------
    .. [Lensfun] see docs/references.md; vignetting model "pa" (libs/lensfun/mod-color.cpp).
    """
    r2 = (np.asarray(height_mm, dtype=np.float64) / float(radius_mm)) ** 2
    k1, k2, k3 = (float(v) for v in k)
    return 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))


def relative_illumination(height_mm: ArrayLike, field: FieldSpec, corner_mm: float,
                          f_number: float | None = None) -> np.ndarray:
    """The relative illumination ``E(h)/E(0)`` the field spec describes, 0 outside the image circle.

    Parameters
    ----------
    height_mm : array_like
        Image heights, mm.
    field : FieldSpec
        ``relative_illumination``: "none" (1), "cos4" (cos⁴ of :func:`chief_ray_angle_deg`), "exit_pupil"
        (:func:`exit_pupil_illumination`), "table" (linear interpolation, the end values held) or "pa"
        (:func:`pa_illumination`).
    corner_mm : float
        The sensor's half diagonal, mm (the CRA's and the "pa" radius's default).
    f_number : float, optional
        The lens's f-number, for ``exit_pupil_form = "disk"``.

    Returns
    -------
    ndarray
        float64, the shape of ``height_mm``; exactly 1 everywhere with the defaults.

    References
    ----------
    .. [Smith2008] see docs/references.md; .. [Foote1915] and .. [Lensfun] likewise.
    """
    h = np.asarray(height_mm, dtype=np.float64)
    form = field.relative_illumination
    if form == "cos4":
        ri = cos4_illumination(chief_ray_angle_deg(h, field, corner_mm))
    elif form == "exit_pupil":
        disk = field.exit_pupil_form == "disk"
        if disk and f_number is None:
            raise ConfigError("optics.exit_pupil_form", "disk", "needs the lens's f-number (optics.f_number)")
        ri = exit_pupil_illumination(h, field.exit_pupil_mm, f_number if disk else None)
    elif form == "table":
        ri = np.interp(h, field.illumination_height_mm, field.illumination_curve)
    elif form == "pa":
        ri = pa_illumination(h, field.pa_k, field.pa_radius_mm if field.pa_radius_mm is not None else corner_mm)
    else:
        ri = np.ones_like(h)
    if field.image_circle_diameter_mm is not None:
        ri = np.where(h <= field.image_circle_diameter_mm / 2, ri, 0.0)
    return np.clip(ri, 0.0, None)


def field_maps(shape: tuple[int, int], pixel_pitch_um: float, field: FieldSpec,
               f_number: float | None = None) -> FieldMaps:
    """Every per-pixel quantity of the field at once.

    Parameters
    ----------
    shape : tuple of int
        ``(H, W)`` pixels.
    pixel_pitch_um : float
        Pixel pitch, µm.
    field : FieldSpec
        The lens and sensor across the field.
    f_number : float, optional
        The lens's f-number (``exit_pupil_form = "disk"``).

    Returns
    -------
    FieldMaps
        Positions, image height, CRA and relative illumination, each ``(H, W)`` float64.

    References
    ----------
    .. [Smith2008] see docs/references.md.
    """
    x, y = pixel_positions_mm(shape, pixel_pitch_um, field.optical_centre_mm)
    h = np.hypot(x, y)
    corner = half_diagonal_mm(shape, pixel_pitch_um)
    return FieldMaps(x_mm=x, y_mm=y, height_mm=h, cra_deg=chief_ray_angle_deg(h, field, corner),
                     illumination=relative_illumination(h, field, corner, f_number))


# ------------------------------------------------------------------ lensfun's database
@dataclass(frozen=True)
class LensfunVignetting:
    """One lens's vignetting from lensfun: ``V(r) = 1 + k1 r² + k2 r⁴ + k3 r⁶``, r = 1 at ``radius_mm``."""

    lens: str
    crop_factor: float
    focal_mm: float
    aperture: float
    distance_m: float
    k: tuple[float, float, float]
    #: The aperture's coefficients: "exact" (stored), "interpolated" (between two stored apertures) or "nearest"
    #: (beyond them); ``focal_mm`` and ``distance_m`` are always the nearest calibration's.
    how: str
    source: str

    @property
    def radius_mm(self) -> float:
        """Half the diagonal of the frame it was calibrated on, mm (36 × 24 mm / crop factor)."""
        return FULL_FRAME_HALF_DIAGONAL_MM / self.crop_factor

    def field(self, **changes: object) -> FieldSpec:
        """A :class:`FieldSpec` with this relative illumination (``"pa"``) and any other fields changed.

        Parameters
        ----------
        **changes : object
            Other fields of the :class:`FieldSpec` (not its ``pa_`` ones).

        Returns
        -------
        FieldSpec
            ``relative_illumination = "pa"`` with this lens's ``k`` and ``radius_mm``.
        """
        return FieldSpec(relative_illumination="pa", pa_k=self.k, pa_radius_mm=self.radius_mm, **changes)


def _calibrations(lens_el) -> list[tuple[float, float, float, tuple[float, float, float]]]:
    """``(focal, aperture, distance, (k1, k2, k3))`` of a lens element's "pa" vignetting entries."""
    out = []
    for v in lens_el.iter("vignetting"):
        if v.get("model") == "pa":
            out.append((float(v.get("focal")), float(v.get("aperture")), float(v.get("distance", 1000)),
                        tuple(float(v.get(n, 0)) for n in ("k1", "k2", "k3"))))
    return out


@functools.lru_cache(maxsize=4)
def _lensfun_index(db_dir: str) -> dict[str, list[tuple[float, list, str]]]:
    """Lens model (lower case, every ``<model>`` spelling) → ``[(crop factor, calibrations, file)]`` of the
    entries with "pa" vignetting data."""
    index: dict[str, list] = {}
    for path in sorted(Path(db_dir).glob("*.xml")):
        for lens in ET.parse(path).getroot().iter("lens"):
            cal = _calibrations(lens)
            if not cal:
                continue
            crop = float(lens.findtext("cropfactor", "1"))
            for name in {m.text.strip().lower() for m in lens.findall("model") if m.text}:
                index.setdefault(name, []).append((crop, cal, path.name))
    return index


def _pick(cal: list, focal_mm: float, aperture: float, distance_m: float) -> tuple[tuple, str, float, float]:
    """The coefficients at (focal, aperture, distance): the nearest focal length and distance (in log), then
    exact or linear in stops (log₂ N) between the two nearest apertures, the end ones held beyond them."""
    f = min({c[0] for c in cal}, key=lambda v: abs(math.log(v / focal_mm)))
    at_f = [c for c in cal if c[0] == f]
    d = min({c[2] for c in at_f}, key=lambda v: abs(math.log(v / distance_m)))
    rows = sorted((c[1], c[3]) for c in at_f if c[2] == d)
    ns = np.array([r[0] for r in rows])
    ks = np.array([r[1] for r in rows])
    exact = np.isclose(ns, aperture, rtol=1e-6)
    if exact.any():
        k, how = ks[np.argmax(exact)], "exact"
    else:
        stops = np.log2(ns)
        k = np.array([np.interp(math.log2(aperture), stops, ks[:, j]) for j in range(3)])
        how = "interpolated" if ns[0] < aperture < ns[-1] else "nearest"
    return tuple(float(v) for v in k), how, f, d


def lensfun_vignetting(lens: str, focal_mm: float, aperture: float, distance_m: float = 1000.0,
                       crop_factor: float | None = None, db_dir: str | Path = LENSFUN_DIR) -> LensfunVignetting:
    """A named lens's measured vignetting from lensfun's XML database.

    Parameters
    ----------
    lens : str
        The lens model as lensfun spells it in any ``<model>`` (case ignored), e.g. "Canon EF 50mm f/1.8 II".
    focal_mm, aperture, distance_m : float
        Focal length (mm), f-number and focus distance (m; lensfun writes 1000 for infinity).
    crop_factor : float, optional
        Which calibration of the lens (each is made on one body): the nearest crop factor; None: the
        largest frame (smallest crop factor).
    db_dir : str or Path
        The database (Debian's ``liblensfun-data-v1``: ``/usr/share/lensfun/version_1``).

    Returns
    -------
    LensfunVignetting
        ``k`` from the calibration at the nearest focal length and distance (log scale), at the aperture
        if stored, else linear in stops between the two nearest stored apertures (``how``); ``focal_mm`` and
        ``distance_m`` are the calibration's.

    References
    ----------
    .. [Lensfun] see docs/references.md; database format and vignetting model "pa".
    """
    if not Path(db_dir).is_dir():
        raise ConfigError("lensfun.db_dir", str(db_dir), "no lensfun database there (Debian: apt-get install "
                                                          "liblensfun-data-v1)")
    for name, v, lo in (("focal_mm", focal_mm, 0.1), ("aperture", aperture, 0.3), ("distance_m", distance_m, 0.01)):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < lo:
            raise ConfigError(f"lensfun.{name}", v, f"must be a number ≥ {lo:g}")
    entries = _lensfun_index(str(db_dir)).get(lens.strip().lower())
    if not entries:
        raise ConfigError("lensfun.lens", lens, f"no lens of that model with vignetting data in {db_dir}")
    if crop_factor is None:
        crop, cal, src = min(entries, key=lambda e: e[0])
    else:
        crop, cal, src = min(entries, key=lambda e: abs(e[0] - crop_factor))
    k, how, f, d = _pick(cal, float(focal_mm), float(aperture), float(distance_m))
    return LensfunVignetting(lens=lens, crop_factor=crop, focal_mm=f, aperture=float(aperture), distance_m=d, k=k,
                             how=how, source=src)
