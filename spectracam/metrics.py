"""Evaluation (paper, sections 3.6 and 5): CIELAB ΔE and channel SNR, vectorised.

CIELAB uses each image's own white: the scene's illuminant for the scene, the display white for the
rendering.  ΔE*ab (CIE 1976) is the default, CIEDE2000 an option.
"""
from __future__ import annotations

import numpy as np

DELTA_E_METHODS = ("cie1976", "ciede2000")
SNR_COMBINATIONS = ("power", "mean_db")


def xyz_to_lab(xyz: np.ndarray, white_xyz: np.ndarray) -> np.ndarray:
    """CIE 1976 L*a*b* of XYZ (last axis) relative to ``white_xyz`` (any Y scale, same as ``xyz``)."""
    import colour

    white = np.asarray(white_xyz, float)
    return colour.XYZ_to_Lab(np.asarray(xyz, float) / white[1], colour.XYZ_to_xy(white / white[1]))


def delta_e(lab1: np.ndarray, lab2: np.ndarray, method: str = "cie1976") -> np.ndarray:
    if method == "cie1976":
        return np.linalg.norm(np.asarray(lab1, float) - np.asarray(lab2, float), axis=-1)
    import colour

    return colour.delta_E(lab1, lab2, method="CIE 2000")


def snr_db(means: np.ndarray, stds: np.ndarray) -> np.ndarray:
    """20·log10(μ/σ) of a recorded signal (electrons) per channel."""
    return 20 * np.log10(np.asarray(means, float) / np.asarray(stds, float))


def combine_snr_db(means: np.ndarray, stds: np.ndarray, how: str = "power") -> np.ndarray:
    """One SNR for the three channels (last axis): ``power`` = 10·log10(Σμ²/Σσ²), the signal and noise
    powers of the colour vector; ``mean_db`` = the average of the three channels' dB."""
    means, stds = np.asarray(means, float), np.asarray(stds, float)
    if how == "power":
        return 10 * np.log10((means**2).sum(-1) / (stds**2).sum(-1))
    return (20 * np.log10(means / stds)).mean(-1)
