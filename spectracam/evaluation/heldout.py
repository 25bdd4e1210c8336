"""Scores that do not flatter: the colour conversion judged on colours it was not fitted on.

The conversion (paper 3.5) is fitted on the 24 chart patches under the scene's light — a *training*
set, as a camera maker calibrates — so the chart's own conversion error is a training error.  Here
the same conversion is applied to a *held-out* library of measured reflectances
(:mod:`spectracam.scene.reflectances`, default the CIE 2017 99 samples) under the same light:

    ΔE_i = ΔE( Lab_display(ρ_i · M · M_disp),  Lab_scene(XYZ_i) )

with ρ_i the sample's noise-free photo-electron rates (band-averaged ``E·S_i/π`` through the
camera), M the fitted conversion, ``M_disp`` the display's RGB→XYZ, Lab of the display's output
against the display white and the sample's true Lab against the light's white (exactly how the
chart's ``delta_e_conversion`` is defined).  Noise-free: it isolates what the conversion cannot
reach; the noise's own error is in the chart scores.  Reported: mean, 95th percentile, max, count.
"""
from __future__ import annotations

import numpy as np

from spectracam.camera import CameraSpec, photo_electron_rates
from spectracam.processing.color import ProcessingSpec, display_rgb_to_xyz
from spectracam.scene.illuminant import IlluminantSpec
from spectracam.core.cielab import delta_e, xyz_to_lab
from spectracam.scene.reference import LibraryColours, library_colours
from spectracam.core.spectra import WavelengthGrid

__all__ = ["conversion_errors", "held_out_block", "summary"]

#: The library's colours under a light: moved to :mod:`spectracam.scene.reference` (the truth of a scene),
#: where a textured target (:mod:`spectracam.scene.target`) finds them too.
HeldOutColours, held_out_colours = LibraryColours, library_colours


def conversion_errors(colours: LibraryColours, camera: CameraSpec, grid: WavelengthGrid, conversion: np.ndarray,
                      processing: ProcessingSpec) -> np.ndarray:
    """``(n,)`` ΔE of each sample through the fitted 3×3 ``conversion`` (see the module).

    Parameters
    ----------
    colours : LibraryColours
        The library's samples under the light: their band-averaged radiance, W·m⁻²·sr⁻¹·nm⁻¹, and true XYZ.
    camera : CameraSpec
        The camera whose noise-free photo-electron rates (e⁻/s) are converted.
    grid : WavelengthGrid
        The bands of the radiance.
    conversion : ndarray
        ``(3, 3)`` the fitted conversion from rates to the display's linear RGB (paper 3.5).
    processing : ProcessingSpec
        Its display and ΔE formula (``delta_e``, CIE 1976 ΔE*ab by default).

    Returns
    -------
    ndarray
        ``(n,)`` ΔE per sample.
    """
    rates = photo_electron_rates(colours.radiance.astype(np.float32), grid, camera).astype(np.float64)
    M_disp = display_rgb_to_xyz(processing.display)
    shown = xyz_to_lab(rates @ conversion @ M_disp.T, M_disp.sum(axis=1))
    truth = xyz_to_lab(colours.xyz, colours.white_xyz)
    return np.asarray(delta_e(shown, truth, processing.delta_e), float)


def summary(errors: np.ndarray, library: str) -> dict:
    """The report's block: mean, 95th percentile and max ΔE, and the sample count.

    Parameters
    ----------
    errors : ndarray
        ``(n,)`` ΔE per sample (:func:`conversion_errors`).
    library : str
        The library's name, as reported.

    Returns
    -------
    dict
        ``library``, ``samples``, ``delta_e_mean``, ``delta_e_p95``, ``delta_e_max``.
    """
    e = np.asarray(errors, float)
    return {"library": library, "samples": int(e.size), "delta_e_mean": float(e.mean()),
            "delta_e_p95": float(np.percentile(e, 95)), "delta_e_max": float(e.max())}


def held_out_block(library: str, illuminant: IlluminantSpec, grid: WavelengthGrid, camera: CameraSpec,
                   conversion: np.ndarray, processing: ProcessingSpec) -> dict:
    """:func:`summary` of ``library`` under the light, through a conversion fitted elsewhere.  Memoised per
    camera, light and conversion (the last :data:`HELD_OUT_MEMO` of them): every seed and noise step of a camera
    under a light shares its conversion, so a paper run computes each once instead of once per case.

    Parameters
    ----------
    library : str
        A reflectance library of :mod:`spectracam.scene.reflectances` (e.g. the CIE 2017 99 samples).
    illuminant : IlluminantSpec
        The scene's light, at its absolute level.
    grid : WavelengthGrid
        The scene's bands.
    camera : CameraSpec
        The camera.
    conversion : ndarray
        ``(3, 3)`` the conversion fitted on the chart.
    processing : ProcessingSpec
        Its display and ΔE formula.

    Returns
    -------
    dict
        :func:`summary`'s block (a copy).
    """
    conversion = np.asarray(conversion, float)
    key = (library, illuminant, grid, camera, conversion.shape, conversion.tobytes(), processing.display,
           processing.delta_e)
    if key not in _BLOCKS:
        colours = held_out_colours(library, illuminant, grid)
        _BLOCKS[key] = summary(conversion_errors(colours, camera, grid, conversion, processing), library)
        while len(_BLOCKS) > HELD_OUT_MEMO:
            _BLOCKS.pop(next(iter(_BLOCKS)))
    return dict(_BLOCKS[key])


#: Held-out blocks kept by :func:`held_out_block` (a few hundred bytes each).
HELD_OUT_MEMO = 256
_BLOCKS: dict = {}
