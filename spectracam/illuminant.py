"""The scene illuminant: a blackbody or a CIE illuminant at an absolute level.

The level is the luminance of a perfect white (Lambertian, reflectance 1) diffuser under the
illuminant, L_w = 683·∫(E(λ)/π)·ȳ(λ)dλ in cd/m², or equivalently the illuminance E_v = π·L_w in lux.
Both integrals run over the CIE 1931 range, 360–830 nm, at 1 nm.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .spectra import K_M_LM_PER_W, Spectrum, cie_1931_cmfs, planck_radiance, tabulated

#: Colour temperatures accepted for a blackbody, K: below 1000 K almost nothing is visible; above
#: 40000 K the spectral shape no longer changes appreciably across the visible.
TEMPERATURE_RANGE_K = (1000.0, 40000.0)


@dataclass(frozen=True)
class IlluminantSpec:
    """What the scene file's ``[illuminant]`` table describes."""

    kind: str = "blackbody"  # "blackbody" or "cie"
    temperature_K: float | None = 5000.0
    name: str | None = None  # a key of colour.SDS_ILLUMINANTS, for kind = "cie"
    #: Luminance of a perfect white diffuser, cd/m².  100 cd/m² is a dim indoor scene.
    white_luminance_cd_m2: float = 100.0

    @property
    def illuminance_lux(self) -> float:
        return float(np.pi * self.white_luminance_cd_m2)

    @property
    def label(self) -> str:
        return f"{self.temperature_K:g} K blackbody" if self.kind == "blackbody" else f"CIE {self.name}"


def relative_spd(spec: IlluminantSpec) -> Spectrum:
    """The illuminant's spectral shape (arbitrary scale)."""
    if spec.kind == "blackbody":
        T = float(spec.temperature_K)
        return lambda lam: planck_radiance(lam, T)
    import colour

    sd = colour.SDS_ILLUMINANTS[spec.name]
    return tabulated(sd.wavelengths, sd.values)


def irradiance_scale(spec: IlluminantSpec) -> float:
    """Factor k turning the relative SPD S(λ) into spectral irradiance E(λ) = k·S(λ), W·m⁻²·nm⁻¹."""
    wl, cmfs = cie_1931_cmfs()  # 1 nm steps
    white_radiance_per_k = relative_spd(spec)(wl) / np.pi
    lum_per_k = K_M_LM_PER_W * np.trapezoid(white_radiance_per_k * cmfs[:, 1], wl)
    return spec.white_luminance_cd_m2 / lum_per_k


def spectral_irradiance(spec: IlluminantSpec) -> Spectrum:
    """Absolute spectral irradiance on the chart, W·m⁻²·nm⁻¹ (the chart faces the light)."""
    k = irradiance_scale(spec)
    shape = relative_spd(spec)
    return lambda lam: k * shape(lam)
