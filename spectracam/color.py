"""Colour processing (paper, section 3.5): demosaic, exposure normalisation, the linear colour
conversion to a display, and the display model.

Target of the conversion: the display RGB that reproduces the scene's CIE 1931 XYZ carried to the
display white — by scaling XYZ (von Kries in XYZ, the default: CIELAB against each white is then
preserved exactly) or by a Bradford transform.  The 3×3 matrix is fitted by least squares on the
chart's noise-free camera responses (paper 3.5: "a linear transformation, found using conventional
methods").
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .architecture import bayer_sites
from .errors import SpectracamError

DEMOSAIC_METHODS = ("bilinear", "malvar2004", "menon2007", "patch")
DISPLAYS = ("crt", "srgb")
ADAPTATIONS = ("xyz_scaling", "bradford")
#: colour-science's phosphor spectra of a typical CRT (Brainard 1997), the paper's "simple CRT display".
CRT_PRIMARIES = "Typical CRT Brainard 1997"


@dataclass(frozen=True)
class ProcessingSpec:
    demosaic: str = "bilinear"
    display: str = "crt"
    adaptation: str = "xyz_scaling"
    #: Clip display RGB to [0, 1] before it is shown (off by default: the paper scores the linear
    #: conversion, and clipping would mix gamut limits into the conversion error).
    gamut_clip: bool = False
    #: "cie1976" (ΔE*ab, the paper's) or "ciede2000".
    delta_e: str = "cie1976"
    #: How the three channel SNRs combine: "power" (10·log10 Σμ²/Σσ²) or "mean_db".
    snr_combination: str = "power"


def display_rgb_to_xyz(display: str) -> np.ndarray:
    """3×3 matrix from linear display RGB (white R=G=B=1) to CIE 1931 XYZ with the white's Y = 1."""
    import colour

    if display == "srgb":
        return np.asarray(colour.RGB_COLOURSPACES["sRGB"].matrix_RGB_to_XYZ, float)
    from .spectra import cie_1931_cmfs

    wl, cmfs = cie_1931_cmfs()
    prim = colour.MSDS_DISPLAY_PRIMARIES[CRT_PRIMARIES]
    spd = np.stack([np.interp(wl, prim.wavelengths, np.asarray(prim.values)[:, k], left=0, right=0) for k in range(3)])
    M = np.trapezoid(spd[:, :, None] * cmfs[None, :, :], wl, axis=1).T  # columns: XYZ of each primary
    return M / M[1].sum()


def adaptation_matrix(white_from: np.ndarray, white_to: np.ndarray, method: str) -> np.ndarray:
    """3×3 matrix carrying XYZ seen under ``white_from`` to the corresponding XYZ under ``white_to``."""
    if method == "xyz_scaling":
        return np.diag(white_to / white_from)
    import colour

    return np.asarray(colour.adaptation.matrix_chromatic_adaptation_VonKries(white_from, white_to, transform="Bradford"))


def demosaic(mosaic: np.ndarray, pattern: str, method: str) -> np.ndarray:
    """``(H, W, 3)`` full-colour image from a Bayer mosaic (colour-demosaicing; or ``patch``)."""
    import colour_demosaicing as cd

    if method == "bilinear":
        return cd.demosaicing_CFA_Bayer_bilinear(mosaic, pattern)
    if method == "malvar2004":
        return cd.demosaicing_CFA_Bayer_Malvar2004(mosaic, pattern)
    if method == "menon2007":
        return cd.demosaicing_CFA_Bayer_Menon2007(mosaic, pattern)
    if method == "patch":
        return tile_replicate(mosaic, pattern)
    raise SpectracamError(f"processing.demosaic = {method!r}: must be one of {', '.join(DEMOSAIC_METHODS)}")


def tile_replicate(mosaic: np.ndarray, pattern: str) -> np.ndarray:
    """The paper's reading (it ignores spatial artefacts): every pixel of a 2×2 Bayer tile gets the
    tile's own R and B and the mean of its two G — each channel from pixels of that channel only,
    never interpolated across tiles, so inside a patch's mask no other surface leaks in."""
    h, w = mosaic.shape
    H, W = h // 2 * 2, w // 2 * 2
    out = np.zeros((h, w, 3), dtype=np.float64)
    acc = np.zeros((H // 2, W // 2, 3))
    cnt = np.zeros(3)
    for dy, dx, k in bayer_sites(pattern):
        acc[:, :, k] += mosaic[dy:H:2, dx:W:2]
        cnt[k] += 1
    acc /= cnt
    out[:H, :W] = np.repeat(np.repeat(acc, 2, axis=0), 2, axis=1)
    return out


def fit_conversion(camera: np.ndarray, target_rgb: np.ndarray) -> np.ndarray:
    """3×3 M minimising ‖camera·M − target‖² over the chart's patches (rows), ``(n, 3)`` each."""
    M, *_ = np.linalg.lstsq(camera, target_rgb, rcond=None)
    return M
