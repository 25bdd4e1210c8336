"""Tone curves for the pictures a run writes (``processing.tone_curve``): how linear display RGB becomes the 8-bit
sRGB of ``rendered.png`` and the page.  Never inside a score — every ΔE is computed on the linear rendering.

``srgb``    clip to [0, 1] and encode with IEC 61966-2-1's curve (what every written picture did before issue 33);
``filmic``  J. Hable's filmic curve ("Uncharted 2 tone mapping", GDC 2010: A = 0.15, B = 0.50, C = 0.10, D = 0.20,
            E = 0.02, F = 0.30, linear white W = 11.2), with an exposure of 2 so that mid-grey keeps about its
            level; it rolls highlights off instead of clipping them (a developed camera's metered white at Y = 1
            keeps its texture), then the sRGB encoding.
"""
from __future__ import annotations

import numpy as np

from spectracam.core.registry import Registry

__all__ = ["FILMIC_EXPOSURE", "HABLE", "HABLE_WHITE", "TONE_CURVES", "tone_map"]

#: Tone curves: name → function ``(linear RGB, ≥ 0 where shown) → values in [0, 1] before the sRGB encoding``.
TONE_CURVES: Registry = Registry("processing.tone_curve", "tone curve")

#: Hable's constants and his linear white point (GDC 2010), and the exposure applied before the curve.
HABLE = {"A": 0.15, "B": 0.50, "C": 0.10, "D": 0.20, "E": 0.02, "F": 0.30}
HABLE_WHITE = 11.2
FILMIC_EXPOSURE = 2.0


@TONE_CURVES.register("srgb")
def _srgb(linear: np.ndarray) -> np.ndarray:
    """Clipped to [0, 1]."""
    return np.clip(linear, 0.0, 1.0)


def _hable(x):
    a, b, c, d, e, f = (HABLE[k] for k in "ABCDEF")
    return (x * (a * x + c * b) + d * e) / (x * (a * x + b) + d * f) - e / f


@TONE_CURVES.register("filmic")
def _filmic(linear: np.ndarray) -> np.ndarray:
    """Hable's curve, normalised so that the white point W maps to 1.

    >>> float(_filmic(np.array([HABLE_WHITE / FILMIC_EXPOSURE]))[0])
    1.0
    """
    x = np.maximum(linear, 0.0) * FILMIC_EXPOSURE
    return np.clip(_hable(x) / _hable(HABLE_WHITE), 0.0, 1.0)


def tone_map(linear: np.ndarray, curve: str = "srgb") -> np.ndarray:
    """Values in [0, 1] of linear sRGB through the registered tone curve (the sRGB encoding follows).

    Parameters
    ----------
    linear : ndarray
        ``(..., 3)`` linear sRGB (white = 1; above 1 where highlights exceed it).
    curve : str
        A registered tone curve: ``"srgb"`` (clipped to [0, 1]) or ``"filmic"`` (Hable's curve).

    Returns
    -------
    ndarray
        Same shape, in [0, 1], still linear.
    """
    return TONE_CURVES[curve](linear)
