"""Evaluation (paper, sections 3.6 and 5): CIELAB ΔE and channel SNR, vectorised.

CIELAB uses each image's own white: the scene's illuminant for the scene, the display white for the
rendering.  ΔE*ab (CIE 1976) is the default, CIEDE2000 an option.
"""
from __future__ import annotations

import numpy as np

from spectracam.core.registry import Registry

__all__ = ["DELTA_E_METHODS", "SNR_COMBINATIONS", "combine_snr_db", "delta_e", "snr_db", "xyz_to_lab"]

#: Colour-difference formulas: name → function ``(lab1, lab2) → ΔE`` over the last axis.
DELTA_E_METHODS: Registry = Registry("processing.delta_e", "colour-difference formula")
#: SNR combinations: name → function ``(means, stds) → dB`` over the last (channel) axis.
SNR_COMBINATIONS: Registry = Registry("processing.snr_combination", "SNR combination")


def xyz_to_lab(xyz: np.ndarray, white_xyz: np.ndarray) -> np.ndarray:
    """CIE 1976 L*a*b* of XYZ (last axis) relative to ``white_xyz``.

    Parameters
    ----------
    xyz : array_like, shape (..., 3)
        CIE 1931 XYZ, last axis.
    white_xyz : array_like, shape (3,)
        XYZ of the white (any Y scale, same as ``xyz``).

    Returns
    -------
    ndarray, shape (..., 3)
        L*, a*, b*.

    References
    ----------
    .. [CIE015] see docs/references.md; CIE 1976 L*a*b*.
    .. [Catrysse1999] see docs/references.md; section 3.6.
    """
    import colour

    white = np.asarray(white_xyz, float)
    return colour.XYZ_to_Lab(np.asarray(xyz, float) / white[1], colour.XYZ_to_xy(white / white[1]))


@DELTA_E_METHODS.register("cie1976")
def _delta_e_1976(lab1, lab2):
    """ΔE*ab, the Euclidean distance in CIELAB (the paper's, 3.6)."""
    return np.linalg.norm(np.asarray(lab1, float) - np.asarray(lab2, float), axis=-1)


@DELTA_E_METHODS.register("ciede2000")
def _delta_e_2000(lab1, lab2):
    """CIEDE2000 (CIE 142:2001), colour-science's implementation."""
    import colour

    return colour.delta_E(lab1, lab2, method="CIE 2000")


def delta_e(lab1: np.ndarray, lab2: np.ndarray, method: str = "cie1976") -> np.ndarray:
    """Colour difference of the registered formula ``method``.

    Parameters
    ----------
    lab1, lab2 : array_like, shape (..., 3)
        CIELAB colours, last axis.
    method : str
        A name in :data:`DELTA_E_METHODS`: ``"cie1976"`` (ΔE*ab, the Euclidean distance, the paper's 3.6) or
        ``"ciede2000"`` (CIEDE2000, CIE 142:2001, colour-science's implementation).

    Returns
    -------
    ndarray, shape (...)
        ΔE per colour.

    Raises
    ------
    ConfigError
        An unknown ``method``.

    References
    ----------
    .. [CIE015] see docs/references.md; ΔE*ab.
    .. [CIE142] see docs/references.md; CIEDE2000.

    Examples
    --------
    >>> float(delta_e([50.0, 0.0, 0.0], [50.0, 3.0, 4.0]))
    5.0
    """
    return DELTA_E_METHODS[method](lab1, lab2)


def snr_db(means: np.ndarray, stds: np.ndarray) -> np.ndarray:
    """20·log10(μ/σ) of a recorded signal (electrons) per channel (paper 5).

    Parameters
    ----------
    means, stds : array_like
        Mean μ and standard deviation σ of the signal, electrons, per channel.

    Returns
    -------
    ndarray
        SNR, dB.

    References
    ----------
    .. [Catrysse1999] see docs/references.md; section 5.
    """
    return 20 * np.log10(np.asarray(means, float) / np.asarray(stds, float))


@SNR_COMBINATIONS.register("power")
def _snr_power(means, stds):
    """10·log10(Σμ²/Σσ²): the signal and noise powers of the colour vector."""
    return 10 * np.log10((means**2).sum(-1) / (stds**2).sum(-1))


@SNR_COMBINATIONS.register("mean_db")
def _snr_mean_db(means, stds):
    """The average of the three channels' 20·log10(μ/σ)."""
    return (20 * np.log10(means / stds)).mean(-1)


def combine_snr_db(means: np.ndarray, stds: np.ndarray, how: str = "power") -> np.ndarray:
    """One SNR for the three channels (last axis), by the registered combination ``how``.

    Parameters
    ----------
    means, stds : array_like, shape (..., 3)
        Mean μ and standard deviation σ per channel, last axis.
    how : str
        A name in :data:`SNR_COMBINATIONS`: ``"power"`` (10·log10(Σμ²/Σσ²), the signal and noise powers of the
        colour vector) or ``"mean_db"`` (the average of the channels' 20·log10(μ/σ)).

    Returns
    -------
    ndarray, shape (...)
        SNR, dB.

    Raises
    ------
    ConfigError
        An unknown ``how``.

    References
    ----------
    .. [Catrysse1999] see docs/references.md; section 5.

    Examples
    --------
    >>> round(float(combine_snr_db([10.0, 10.0, 10.0], [1.0, 1.0, 1.0])), 6)
    20.0
    """
    return SNR_COMBINATIONS[how](np.asarray(means, float), np.asarray(stds, float))
