"""The scene illuminant: a blackbody, any illuminant colour-science ships (CIE A, D series, FL1–FL12,
FL3.x, HP1–5, LED-B1…V2, ...) or a measured SPD, at an absolute level.

The level is the luminance of a perfect white (Lambertian, reflectance 1) diffuser under the
illuminant, L_w = 683·∫(E(λ)/π)·ȳ(λ)dλ in cd/m², or equivalently the illuminance E_v = π·L_w in lux.
Both integrals run over the CIE 1931 range, 360–830 nm, at 1 nm.
"""
from __future__ import annotations

import math
from collections.abc import Collection
from dataclasses import dataclass

import numpy as np

from spectracam.core.errors import ConfigError
from spectracam.core.registry import Registry
from spectracam.core.spec import Spec, _is_number
from spectracam.core.spectra import (K_M_LM_PER_W, Spectrum, WavelengthGrid, cie_1931_cmfs, planck_radiance,
                                     tabulated)

__all__ = ["ILLUMINANTS", "MIN_SPD_SAMPLES", "TEMPERATURE_RANGE_K", "TYPE_KEYS", "IlluminantSpec",
           "irradiance_scale", "relative_spd", "spectral_irradiance", "switched_table",
           "white_diffuser_radiance"]

#: Colour temperatures accepted for a blackbody, K: below 1000 K almost nothing is visible; above
#: 40000 K the spectral shape no longer changes appreciably across the visible.
TEMPERATURE_RANGE_K = (1000.0, 40000.0)

#: Illuminant types: name → function of the spec giving the relative spectral shape.
ILLUMINANTS: Registry = Registry("illuminant.type", "illuminant type")


@ILLUMINANTS.register("blackbody")
def _blackbody(spec: "IlluminantSpec") -> Spectrum:
    """Planck's law at ``temperature_K``."""
    T = float(spec.temperature_K)
    return lambda lam: planck_radiance(lam, T)


@ILLUMINANTS.register("cie")
def _cie(spec: "IlluminantSpec") -> Spectrum:
    """A tabulated CIE illuminant from colour-science (``name``: D65, D50, A, FL2, ...; its table, read by
    :func:`spectracam.core.colour_data.illuminant_sd`)."""
    from spectracam.core import colour_data

    return tabulated(*colour_data.illuminant_sd(spec.name))


@ILLUMINANTS.register("measured")
def _measured(spec: "IlluminantSpec") -> Spectrum:
    """A measured SPD (``wavelengths_nm``, ``values``; ``file`` in a scene file), linear between the
    samples and zero outside them."""
    return tabulated(spec.wavelengths_nm, spec.values)


#: Fewest samples of a measured SPD.
MIN_SPD_SAMPLES = 3


@dataclass(frozen=True)
class IlluminantSpec(Spec):
    """What the scene file's ``[illuminant]`` table describes (``type`` there is ``kind`` here)."""

    TABLE = "illuminant"

    kind: str = "blackbody"
    temperature_K: float | None = 5000.0
    name: str | None = None  # a key of colour.SDS_ILLUMINANTS, for kind = "cie"
    #: Luminance of a perfect white diffuser, cd/m².  100 cd/m² is a dim indoor scene.
    white_luminance_cd_m2: float = 100.0
    #: kind = "measured": the SPD (any scale: it is set by the luminance), and where it came from.
    wavelengths_nm: tuple = ()
    values: tuple = ()

    def validate(self) -> None:
        ILLUMINANTS.check(self.kind)  # named "type" in the file
        if self.kind == "blackbody":
            self.number("temperature_K", *TEMPERATURE_RANGE_K, unit="K")
        elif self.kind == "cie":
            from spectracam.core import colour_data

            names = colour_data.illuminant_names()
            if self.name not in names:
                raise self.error("name", "must be a CIE illuminant or another light colour-science ships, e.g. D65, A, "
                                 f"FL2, LED-B1 ({len(names)} names: colour.SDS_ILLUMINANTS)")
        elif self.kind == "measured":
            self.string("name")
            wl, v = self.wavelengths_nm, self.values
            if not isinstance(wl, tuple) or len(wl) < MIN_SPD_SAMPLES or not all(_is_number(x) for x in wl) \
                    or any(b <= a for a, b in zip(wl, wl[1:])):
                raise self.error("wavelengths_nm", f"must be at least {MIN_SPD_SAMPLES} increasing wavelengths in nm",
                                 list(wl) if isinstance(wl, tuple) else wl)
            if not isinstance(v, tuple) or len(v) != len(wl) or not all(_is_number(x) and x >= 0 for x in v):
                raise self.error("values", f"must be {len(wl)} spectral power values ≥ 0 (one per wavelength)",
                                 (list(v)[:8] if isinstance(v, tuple) else v))
            if not any(x > 0 for x in v):
                raise self.error("values", "must not all be 0 (a light that gives no light)", list(v)[:8])
            if wl[0] < 300 or wl[-1] > 1100:
                raise self.error("wavelengths_nm", "must lie within 300–1100 nm (an SPD in nm, not µm or m)",
                                 [wl[0], wl[-1]])
            object.__setattr__(self, "wavelengths_nm", tuple(float(x) for x in wl))
            object.__setattr__(self, "values", tuple(float(x) for x in v))
        self.number("white_luminance_cd_m2", 0, lo_open=True, unit="cd/m²")

    @property
    def illuminance_lux(self) -> float:
        return float(np.pi * self.white_luminance_cd_m2)

    @property
    def label(self) -> str:
        if self.kind == "measured":
            return f"measured SPD {self.name}"
        return f"{self.temperature_K:g} K blackbody" if self.kind == "blackbody" else f"CIE {self.name}"

    def to_dict(self) -> dict:
        d: dict = {"type": self.kind, "white_luminance_cd_m2": self.white_luminance_cd_m2}
        if self.kind == "blackbody":
            d["temperature_K"] = self.temperature_K
        else:
            d["name"] = self.name
        if self.kind == "measured":
            d["wavelengths_nm"], d["values"] = list(self.wavelengths_nm), list(self.values)
        return d

    @classmethod
    def from_dict(cls, data: object, source: str | None = None,
                  base: IlluminantSpec | None = None) -> IlluminantSpec:
        """The TOML table: ``type``, ``temperature_K`` or ``name``, and ``white_luminance_cd_m2`` or
        ``illuminance_lux`` (= π × the luminance).  Keys not given keep ``base``'s values.

        Parameters
        ----------
        data : object
            The ``[illuminant]`` table; another ``type`` than ``base``'s keeps only its level.
        source : str or None
            Where the table came from, for the error.
        base : IlluminantSpec or None
            The illuminant whose values fill the keys not given; None: the default.

        Returns
        -------
        IlluminantSpec
            The validated illuminant.
        """
        if not isinstance(data, dict):
            raise ConfigError("illuminant", data, "must be a table", source)
        d = dict(data)
        if "white_luminance_cd_m2" in d and "illuminance_lux" in d:
            raise ConfigError("illuminant.illuminance_lux", d["illuminance_lux"],
                              "give either white_luminance_cd_m2 or illuminance_lux, not both", source)
        if "illuminance_lux" in d:
            lux = d.pop("illuminance_lux")
            if not (isinstance(lux, (int, float)) and not isinstance(lux, bool) and math.isfinite(lux) and lux > 0):
                raise ConfigError("illuminant.illuminance_lux", lux, "must be a number > 0 lx", source)
            d["white_luminance_cd_m2"] = lux / math.pi
        merged = (base or cls()).to_dict()
        if "type" in d and d["type"] != merged["type"]:  # another type: only the level carries over
            merged = {"type": d["type"], "white_luminance_cd_m2": merged["white_luminance_cd_m2"]}
        merged.update(d)
        kind = merged.pop("type")
        others = {"blackbody": ("name", "wavelengths_nm", "values"), "cie": ("temperature_K", "wavelengths_nm",
                                                                             "values"),
                  "measured": ("temperature_K",)}.get(kind, ())
        for other in others:
            if other in d:
                raise ConfigError(f"illuminant.{other}", d[other], f"unknown key for a {kind!r} illuminant", source)
            merged.pop(other, None)
        if kind == "cie":
            merged.setdefault("name", "D65")
        if kind == "measured":
            merged.setdefault("name", "(from the scene file)")
        return super().from_dict({"kind": kind, "temperature_K": None, **merged}, source)


#: The keys of an ``[illuminant]`` table that belong to one type (the level keys belong to every type).
TYPE_KEYS = {"blackbody": ("temperature_K",), "cie": ("name",), "measured": ("name", "wavelengths_nm", "values",
                                                                            "file")}


def switched_table(table: dict, key: str, value: object, kept: Collection[str] = frozenset()) -> dict:
    """The ``[illuminant]`` table with ``key`` (``type``, or ``file``: a measured SPD) set to ``value`` by
    the override path.  A new type (or a new SPD file) drops the keys of the type the table had — those
    the user did not set in the same overrides (``kept``) — so ``--set illuminant.file=spd.csv`` works on
    a blackbody or CIE scene as a ``file =`` line does in the scene file; the level stays.

    >>> switched_table({"type": "cie", "name": "D65", "white_luminance_cd_m2": 50.0}, "file", "spd.csv")
    {'type': 'measured', 'white_luminance_cd_m2': 50.0, 'file': 'spd.csv'}
    >>> switched_table({"type": "cie", "name": "D65"}, "type", "blackbody", {"temperature_K"})
    {'type': 'blackbody'}

    Parameters
    ----------
    table : dict
        The ``[illuminant]`` table as it stands (not changed).
    key : str
        ``"type"`` or ``"file"``.
    value : object
        The new type, or the measured SPD's file.
    kept : collection of str
        Keys the same overrides set, kept even when the type changes.

    Returns
    -------
    dict
        The new table.
    """
    t = dict(table)
    new_type = "measured" if key == "file" else value
    if key == "file" or t.get("type", IlluminantSpec.kind) != new_type:
        for k in {k for keys in TYPE_KEYS.values() for k in keys} - set(kept):
            t.pop(k, None)
        if key == "file" and "type" not in kept:
            t["type"] = "measured"
    t[key] = value
    return t


def relative_spd(spec: IlluminantSpec) -> Spectrum:
    """The illuminant's spectral shape (arbitrary scale).

    Parameters
    ----------
    spec : IlluminantSpec
        The illuminant (its ``kind`` picks the shape from :data:`ILLUMINANTS`).

    Returns
    -------
    Spectrum
        The relative SPD as a function of wavelength in nm.
    """
    return ILLUMINANTS[spec.kind](spec)


def irradiance_scale(spec: IlluminantSpec) -> float:
    """Factor k turning the relative SPD S(λ) into spectral irradiance E(λ) = k·S(λ), W·m⁻²·nm⁻¹.

    k makes a perfect white diffuser, of radiance E/π, have the luminance ``white_luminance_cd_m2``
    (683 lm/W × ∫ E/π · ȳ dλ over the CIE 1931 2° observer, 1-nm steps).

    Parameters
    ----------
    spec : IlluminantSpec
        The illuminant (its shape and its level).

    Returns
    -------
    float
        k, W·m⁻²·nm⁻¹ per unit of the relative SPD.
    """
    wl, cmfs = cie_1931_cmfs()  # 1 nm steps
    white_radiance_per_k = relative_spd(spec)(wl) / np.pi
    lum_per_k = K_M_LM_PER_W * np.trapezoid(white_radiance_per_k * cmfs[:, 1], wl)
    return spec.white_luminance_cd_m2 / lum_per_k


def spectral_irradiance(spec: IlluminantSpec) -> Spectrum:
    """Absolute spectral irradiance on the chart, W·m⁻²·nm⁻¹ (the chart faces the light).

    Parameters
    ----------
    spec : IlluminantSpec
        The light: its spectral shape (blackbody, a CIE or other named light, or measured) and the luminance
        of a perfect white diffuser under it, ``white_luminance_cd_m2``, cd/m², which sets the scale.

    Returns
    -------
    Spectrum
        ``λ → E(λ) = k·S(λ)`` (λ in nm, E in W·m⁻²·nm⁻¹), scaled so that a perfect white diffuser,
        radiance ``E/π``, has luminance ``683·∫(E/π)·ȳ dλ = white_luminance_cd_m2`` over 360–830 nm.

    References
    ----------
    .. [Catrysse1999] see docs/references.md; section 3.1.
    .. [CIE015] see docs/references.md; ȳ and K_m = 683 lm/W.

    Examples
    --------
    >>> E = spectral_irradiance(IlluminantSpec("blackbody", 5000.0, None, 100.0))
    >>> wl = np.arange(360.0, 831.0)
    >>> round(float(683 * np.trapezoid(E(wl) / np.pi * cie_1931_cmfs()[1][:, 1], wl)), 6)
    100.0
    """
    k = irradiance_scale(spec)
    shape = relative_spd(spec)
    return lambda lam: k * shape(lam)


def white_diffuser_radiance(spec: IlluminantSpec, grid: WavelengthGrid) -> np.ndarray:
    """Band-averaged radiance ``(B,)`` of a perfect white (Lambertian, reflectance 1) diffuser facing
    the illuminant, ``E/π``, W·m⁻²·sr⁻¹·nm⁻¹ on ``grid`` (its luminance is ``white_luminance_cd_m2``).

    Parameters
    ----------
    spec : IlluminantSpec
        The illuminant, at its absolute level.
    grid : WavelengthGrid
        The bands.

    Returns
    -------
    ndarray
        ``(B,)`` float64 radiance, W·m⁻²·sr⁻¹·nm⁻¹, each the band's mean.
    """
    from spectracam.core.spectra import band_average

    E = spectral_irradiance(spec)
    return band_average(lambda lam: E(lam) / np.pi, grid)
