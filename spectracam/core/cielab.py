"""Evaluation (paper, sections 3.6 and 5): CIELAB ΔE and channel SNR, vectorised.

CIELAB uses each image's own white: the scene's illuminant for the scene, the display white for the
rendering.  ΔE*ab (CIE 1976) is the default, CIEDE2000 an option.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from spectracam.core.registry import Registry

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["DELTA_E_CODES", "DELTA_E_METHODS", "FUSED_MIN_COLOURS", "SNR_COMBINATIONS", "combine_snr_db", "delta_e",
           "lab_white", "rgb_to_lab", "snr_db", "xyz_to_lab"]

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
    x = np.asarray(xyz)
    if x.ndim >= 1 and x.shape[-1] == 3 and x.size and _kernels() is not None:
        return rgb_to_lab(x, _EYE, white_xyz)
    import colour

    white = np.asarray(white_xyz, float)
    return colour.XYZ_to_Lab(np.asarray(xyz, float) / white[1], colour.XYZ_to_xy(white / white[1]))


#: :func:`xyz_to_lab` and :func:`delta_e` run compiled kernels (``core/_numba_colour.py``: one pass, float64, no
#: temporaries; colour-science's own formulas cost ~1 ms a call whatever the size, 1.8 s of a paper run), on every
#: core from this many colours.  The two agree to the rounding of float64 (``tests/test_fused_score.py``);
#: ``SPECTRACAM_FUSED=0`` or no numba: colour-science's.
FUSED_MIN_COLOURS = 4096
_EYE = np.eye(3)
#: The ΔE formulas the kernels compute, by the code they know them by.
DELTA_E_CODES = {"cie1976": 0, "ciede2000": 1}
_STATE: dict = {}


def _kernels():
    """The compiled colour kernels' module, or None (numba missing or broken, or ``SPECTRACAM_FUSED=0``)."""
    from spectracam.core.parallel import fused_enabled

    if not fused_enabled():
        return None
    if "module" not in _STATE:
        try:
            from spectracam.core import _numba_colour as mod
        except Exception:  # noqa: BLE001 - no numba, or one that does not load: colour-science's formulas
            mod = None
        _STATE["module"] = mod
    return _STATE["module"]


def lab_white(white_xyz: ArrayLike) -> np.ndarray:
    """The white as colour-science's ``XYZ_to_Lab`` takes it: its chromaticity ``x, y`` (``XYZ_to_xy``) back to
    XYZ with Y = 1 (``xyY_to_XYZ``: ``x·Y/y``, ``(1 − x − y)·Y/y``), the same operations in the same order.

    Parameters
    ----------
    white_xyz : array_like
        ``(3,)`` CIE 1931 XYZ of the white, any scale.

    Returns
    -------
    ndarray
        ``(3,)`` XYZ of the same chromaticity with Y = 1.

    Examples
    --------
    >>> lab_white([0.5, 2.0, 1.5]).tolist()
    [0.25, 1.0, 0.75]
    """
    w = np.asarray(white_xyz, float)
    w = w / w[1]
    total = w[0] + w[1] + w[2]
    x, y = w[0] / total, w[1] / total
    return np.array([x * 1.0 / y, 1.0, (1.0 - x - y) * 1.0 / y])


def rgb_to_lab(rgb: np.ndarray, matrix: np.ndarray, white_xyz: np.ndarray) -> np.ndarray:
    """CIE 1976 L*a*b* ``(..., 3)`` of ``rgb @ matrix.T`` (any linear RGB to XYZ) against ``white_xyz``: what
    ``xyz_to_lab(rgb @ matrix.T, white_xyz)`` gives, in one compiled pass without the XYZ image where numba is
    available (on every core from :data:`FUSED_MIN_COLOURS` colours).

    Parameters
    ----------
    rgb : ndarray
        ``(..., 3)`` linear RGB.
    matrix : ndarray
        ``(3, 3)`` RGB → CIE 1931 XYZ.
    white_xyz : ndarray
        ``(3,)`` XYZ of the reference white (CIELAB's X_n, Y_n, Z_n, CIE 15:2004).

    Returns
    -------
    ndarray
        ``(..., 3)`` float64 L*, a*, b*.

    Examples
    --------
    >>> rgb_to_lab(np.ones((1, 3)), np.eye(3), np.ones(3)).round(6).tolist()
    [[100.0, 0.0, 0.0]]
    """
    from spectracam.core.parallel import run_bands

    x = np.asarray(rgb)
    mod = _kernels()
    if mod is None or not x.size:
        return xyz_to_lab(x @ np.asarray(matrix, float).T, white_xyz) if x.size else np.zeros(x.shape)
    flat = x.reshape(-1, 3)
    if flat.dtype not in (np.float32, np.float64) or not flat.flags.c_contiguous:
        flat = np.ascontiguousarray(flat, np.float64)
    m = np.ascontiguousarray(np.asarray(matrix, float) / float(np.asarray(white_xyz, float)[1]))
    out = np.empty(flat.shape, np.float64)
    wn = lab_white(white_xyz)
    run_bands(mod.lab_kernel, len(flat), lambda a, b: (np.int64(a), np.int64(b), flat, m, wn, out),
              parts=None if len(flat) >= FUSED_MIN_COLOURS else 1)
    return out.reshape(x.shape)


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
    fn = DELTA_E_METHODS[method]
    a, b = np.asarray(lab1, float), np.asarray(lab2, float)
    mod = _kernels() if method in DELTA_E_CODES else None
    if mod is None or a.ndim not in (1, 2) or a.shape[-1] != 3 or b.shape not in (a.shape, (3,), (1, 3)) \
            or (a.ndim == 1 and b.ndim != 1):
        return fn(lab1, lab2)
    if a.ndim == 1:   # one colour: a number, as the formulas give
        return delta_e(a[None], b.reshape(1, 3), method)[0]
    from spectracam.core.parallel import run_bands

    a, b = np.ascontiguousarray(a), np.ascontiguousarray(b.reshape(-1, 3))
    out = np.empty(len(a))
    code = np.int64(DELTA_E_CODES[method])
    run_bands(mod.delta_e_kernel, len(a), lambda i, j: (np.int64(i), np.int64(j), a, b, code, out),
              parts=None if len(a) >= FUSED_MIN_COLOURS else 1)
    return out


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
