"""Imaging optics: scene radiance to photon irradiance at the sensor (paper, section 3.2).

``E_q(λ) = π·sin²θ·T(λ)·C_q(λ)`` with ``f# = 1/(2·tanθ)``, i.e. ``sin²θ = 1/(1 + 4·f#²)`` (the
``exact`` form), or the paraxial ``π/(4·f#²)`` the paper uses (valid for ``f# ≫ 1/4``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from spectracam.core.registry import Registry
from spectracam.core.spec import check_curve
from spectracam.core.spectra import WavelengthGrid, band_average, energy_to_photons, tabulated
from spectracam.optics.field import FieldSpec

__all__ = ["IRRADIANCE_FORMS", "FieldSpec", "OpticsSpec", "irradiance_factor", "radiance_to_photon_irradiance"]

#: Irradiance forms: name → image irradiance per unit scene radiance (sr) as a function of f-number.
IRRADIANCE_FORMS: Registry = Registry("optics.irradiance_form", "irradiance form")
IRRADIANCE_FORMS.register("paraxial", lambda n: np.pi / (4 * n**2))  # the paper's equation, 3.2
IRRADIANCE_FORMS.register("exact", lambda n: np.pi / (1 + 4 * n**2))  # π·sin²θ with tanθ = 1/(2N)


@dataclass(frozen=True)
class OpticsSpec(FieldSpec):
    """The lens: f-number, transmittance, the irradiance form (paper 3.2) and, from :class:`FieldSpec`, how the
    irradiance and the chief ray's angle vary across the field (issue 37; by default every pixel is the centre of the
    field, as in the paper).  The field's keys sit flat in ``[optics]`` (``--set optics.cra_corner_deg=25``)."""

    TABLE = "optics"

    #: Effective f-number; the paper's section 4.2 uses 1.4.
    f_number: float = 1.4
    #: Lens transmittance T(λ), taken flat; the paper (4.2) assumes T = 1.
    transmittance: float = 1.0
    #: "paraxial" π/(4N²) (the paper's equation) or "exact" π/(1+4N²).
    irradiance_form: str = "paraxial"
    #: A measured T(λ) of the lens (wavelength nm, transmittance), e.g. from ``transmittance_file``
    #: in a scene file; multiplies ``transmittance``.  Empty: flat.
    transmittance_curve_nm: tuple = ()
    transmittance_curve: tuple = ()

    def validate(self) -> None:
        self.number("f_number", 0.5, 64.0)
        self.number("transmittance", 0, 1, lo_open=True)
        self.choice("irradiance_form", IRRADIANCE_FORMS)
        check_curve(self, "transmittance_curve_nm", "transmittance_curve", required=False)
        self.validate_field()

    def to_dict(self) -> dict:
        """As :meth:`Spec.to_dict`, the field's keys left out where they hold their defaults: a camera on the axis
        records exactly what it recorded before the field existed (its files and the render cache's keys)."""
        out, base = super().to_dict(), FieldSpec().to_dict()
        return {k: v for k, v in out.items() if k not in base or v != base[k]}


def irradiance_factor(optics: OpticsSpec) -> float:
    """Image irradiance per unit scene radiance, sr (paper, section 3.2).

    Parameters
    ----------
    optics : OpticsSpec
        The lens: its f-number N and ``irradiance_form``.

    Returns
    -------
    float
        ``π/(4N²)`` (``"paraxial"``, the paper's) or ``π/(1 + 4N²)`` (``"exact"``), sr.

    References
    ----------
    .. [Catrysse1999] see docs/references.md; section 3.2.

    Examples
    --------
    >>> round(irradiance_factor(OpticsSpec(f_number=2.0)), 6)  # π/16
    0.19635
    """
    return float(IRRADIANCE_FORMS[optics.irradiance_form](optics.f_number))


def radiance_to_photon_irradiance(grid: WavelengthGrid | ArrayLike, optics: OpticsSpec) -> np.ndarray:
    """Per-band factor from spectral radiance to photon irradiance at the sensor.

    Parameters
    ----------
    grid : WavelengthGrid or array_like
        A :class:`WavelengthGrid` (a measured T is averaged over each band) or wavelengths, nm.
    optics : OpticsSpec
        The lens: f-number, transmittance T and a measured T(λ), if any.

    Returns
    -------
    ndarray
        One factor per band or wavelength, :func:`irradiance_factor` × T(λ) × λ/(hc): from spectral radiance
        (W·m⁻²·sr⁻¹·nm⁻¹) to photon irradiance (photons·s⁻¹·m⁻²·nm⁻¹).

    References
    ----------
    .. [Catrysse1999] see docs/references.md; sections 3.1 and 3.2.
    """
    centres = np.asarray(grid.centres_nm if isinstance(grid, WavelengthGrid) else grid, float)
    k = irradiance_factor(optics) * optics.transmittance
    factor = energy_to_photons(1.0, centres) * k
    if optics.transmittance_curve:
        T = tabulated(optics.transmittance_curve_nm, optics.transmittance_curve)
        factor = factor * (band_average(T, grid) if isinstance(grid, WavelengthGrid) else T(centres))
    return factor
