"""Scores that do not flatter: the colour conversion judged on colours it was not fitted on.

The conversion (paper 3.5) is fitted on the 24 chart patches under the scene's light — a *training*
set, as a camera maker calibrates — so the chart's own conversion error is a training error.  Here
the same conversion is applied to a *held-out* library of measured reflectances
(:mod:`spectracam.reflectances`, default the CIE 2017 99 samples) under the same light:

    ΔE_i = ΔE( Lab_display(ρ_i · M · M_disp),  Lab_scene(XYZ_i) )

with ρ_i the sample's noise-free photo-electron rates (band-averaged ``E·S_i/π`` through the
camera), M the fitted conversion, ``M_disp`` the display's RGB→XYZ, Lab of the display's output
against the display white and the sample's true Lab against the light's white (exactly how the
chart's ``delta_e_conversion`` is defined).  Noise-free: it isolates what the conversion cannot
reach; the noise's own error is in the chart scores.  Reported: mean, 95th percentile, max, count.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .camera import CameraSpec, photo_electron_rates
from .color import ProcessingSpec, display_rgb_to_xyz
from .illuminant import IlluminantSpec, spectral_irradiance
from .metrics import delta_e, xyz_to_lab
from .reflectances import load
from .reference import observer_grid
from .spectra import WavelengthGrid, band_sample_points

#: Points per band of the band averages (0.5 nm in a 10-nm band): the chart's 200 give the same
#: conversion error within 7e-5 ΔE*ab on the chart's own patches.
POINTS_PER_BAND = 20
#: Samples handled at once (memory: ~100 MB of reflectances on the 0.1-nm colorimetry grid).
CHUNK = 4096


@dataclass(frozen=True, eq=False)
class HeldOutColours:
    """A library under one light on one wavelength grid: what a camera is shown and the truth."""

    library: str
    names: tuple
    radiance: np.ndarray     # (n, B) band-averaged, W·m⁻²·sr⁻¹·nm⁻¹
    xyz: np.ndarray          # (n, 3), Y = 1 for a perfect white diffuser
    white_xyz: np.ndarray    # (3,), the light's white, Y = 1


@lru_cache(maxsize=16)
def held_out_colours(library: str, illuminant: IlluminantSpec, grid: WavelengthGrid) -> HeldOutColours:
    """Band radiance and CIE 1931 XYZ of every sample of ``library`` under ``illuminant`` (memoised)."""
    lo, hi = float(grid.edges_nm[0]), float(grid.edges_nm[-1])
    rset = load(library)
    rset.check_covers(lo, hi)
    E = spectral_irradiance(illuminant)
    lam_b = band_sample_points(grid, POINTS_PER_BAND)                 # (B, P + 1)
    e_b = E(lam_b) / np.pi
    # the chart's colorimetry (spectracam.reference.colorimetry): trapezoids at its 0.1 nm (1 nm moved
    # the chart's conversion error by up to 0.008 ΔE*ab), as one (n, L) @ (L, 3) product per chunk
    lam, xyz_bar = observer_grid(lo, hi)
    trapezoid = np.full(lam.size, lam[1] - lam[0])
    trapezoid[[0, -1]] *= 0.5
    weights = (E(lam) / np.pi)[:, None] * xyz_bar * trapezoid[:, None]          # (L, 3)
    white = weights.sum(axis=0)
    radiance = np.empty((len(rset), len(grid.centres_nm)))
    xyz = np.empty((len(rset), 3))
    for a in range(0, len(rset), CHUNK):
        sl = slice(a, a + CHUNK)
        y = rset.at(lam_b.ravel(), sl).reshape(-1, *lam_b.shape) * e_b[None]
        radiance[sl] = 0.5 * (y[..., 1:] + y[..., :-1]).mean(axis=-1)
        xyz[sl] = rset.at(lam, sl) @ weights
    return HeldOutColours(library, rset.sample_names, radiance, xyz / white[1], white / white[1])


def conversion_errors(colours: HeldOutColours, camera: CameraSpec, grid: WavelengthGrid, conversion: np.ndarray,
                      processing: ProcessingSpec) -> np.ndarray:
    """``(n,)`` ΔE of each sample through the fitted 3×3 ``conversion`` (see the module)."""
    rates = photo_electron_rates(colours.radiance.astype(np.float32), grid, camera).astype(np.float64)
    M_disp = display_rgb_to_xyz(processing.display)
    shown = xyz_to_lab(rates @ conversion @ M_disp.T, M_disp.sum(axis=1))
    truth = xyz_to_lab(colours.xyz, colours.white_xyz)
    return np.asarray(delta_e(shown, truth, processing.delta_e), float)


def summary(errors: np.ndarray, library: str) -> dict:
    """The report's block: mean, 95th percentile and max ΔE, and the sample count."""
    e = np.asarray(errors, float)
    return {"library": library, "samples": int(e.size), "delta_e_mean": float(e.mean()),
            "delta_e_p95": float(np.percentile(e, 95)), "delta_e_max": float(e.max())}


def held_out_block(library: str, illuminant: IlluminantSpec, grid: WavelengthGrid, camera: CameraSpec,
                   conversion: np.ndarray, processing: ProcessingSpec) -> dict:
    """:func:`summary` of ``library`` under the light, through a conversion fitted elsewhere."""
    colours = held_out_colours(library, illuminant, grid)
    return summary(conversion_errors(colours, camera, grid, conversion, processing), library)
