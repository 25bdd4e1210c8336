"""Imaging optics: scene radiance to photon irradiance at the sensor (paper, section 3.2).

``E_q(λ) = π·sin²θ·T(λ)·C_q(λ)`` with ``f# = 1/(2·tanθ)``, i.e. ``sin²θ = 1/(1 + 4·f#²)`` (the
``exact`` form), or the paraxial ``π/(4·f#²)`` the paper uses (valid for ``f# ≫ 1/4``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .spectra import energy_to_photons

IRRADIANCE_FORMS = ("paraxial", "exact")


@dataclass(frozen=True)
class OpticsSpec:
    #: Effective f-number; the paper's section 4.2 uses 1.4.
    f_number: float = 1.4
    #: Lens transmittance T(λ), taken flat; the paper (4.2) assumes T = 1.
    transmittance: float = 1.0
    #: "paraxial" π/(4N²) (the paper's equation) or "exact" π/(1+4N²).
    irradiance_form: str = "paraxial"


def irradiance_factor(optics: OpticsSpec) -> float:
    """Image irradiance per unit scene radiance, sr (paper, section 3.2)."""
    n2 = optics.f_number**2
    return float(np.pi / (4 * n2) if optics.irradiance_form == "paraxial" else np.pi / (1 + 4 * n2))


def radiance_to_photon_irradiance(wavelengths_nm: np.ndarray, optics: OpticsSpec) -> np.ndarray:
    """Per-band factor from spectral radiance (W·m⁻²·sr⁻¹·nm⁻¹) to photon irradiance at the sensor
    (photons·s⁻¹·m⁻²·nm⁻¹): :func:`irradiance_factor` × T × λ/(hc)."""
    k = irradiance_factor(optics) * optics.transmittance
    return energy_to_photons(1.0, np.asarray(wavelengths_nm, float)) * k


def photon_irradiance(radiance: np.ndarray, wavelengths_nm: np.ndarray, optics: OpticsSpec) -> np.ndarray:
    """Band-averaged photon irradiance at the sensor, photons·s⁻¹·m⁻²·nm⁻¹, float32, same shape."""
    return radiance * radiance_to_photon_irradiance(wavelengths_nm, optics).astype(np.float32)
