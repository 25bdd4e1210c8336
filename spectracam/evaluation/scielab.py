"""S-CIELAB: the spatial extension of CIELAB of Zhang & Wandell.

X. Zhang and B. A. Wandell, "A spatial extension of CIELAB for digital color-image reproduction",
SID Symposium Digest 27 (1996) 731-734; J. Soc. Inf. Display 5(1) (1997) 61-63. Reference implementations:
X. Zhang's Matlab distribution (1996-98) and ISETCam's ``metrics/scielab`` (MIT licence), read to compare
numbers; this code is written from the paper.

1. XYZ → opponent channels (O1 luminance, O2 red-green, O3 blue-yellow) by the 3×3 matrix
   :data:`XYZ_TO_OPPONENT` (Poirson & Wandell's opponent space expressed in CIE 1931 XYZ);
2. each channel is convolved with its kernel, a weighted sum of 2-D Gaussians
   ``E_i(x, y) = k_i exp(-(x² + y²) / s_i²)`` with the published weights ``w_i`` and spreads ``s_i`` in
   degrees of visual angle (:data:`SCIELAB_FILTERS`), converted to pixels with the samples per degree;
3. back to XYZ with the inverse matrix, then CIELAB against the white and ΔE per pixel
   (ΔE*ab, CIE 1976, by default; CIEDE2000 as an option).

Kernel normalisation, exactly: each Gaussian component is sampled on the square support and divided by its
sum (the paper's ``k_i``: each component sums to 1); the weighted sum ``Σ w_i E_i`` is then divided by its
own sum, ``Σ w_i`` (0.918, 0.861, 0.859 — the published weights do not add up to 1), so every kernel sums
to exactly 1. This is what the reference code does (Zhang's distribution divides the weights by their sum
beforehand, ISETCam's ``sumGauss`` divides the summed kernel by its sum), and it is what makes S-CIELAB
equal CIELAB on uniform areas, the property Zhang & Wandell require. The support is a square of
``support_deg`` (1° by default, as both reference implementations: ``filterSize = sampPerDeg``) with an
odd number of samples; the luminance kernel's widest Gaussian (4.336°) is therefore nearly flat over it
and acts as the subtraction of a local mean.

Spreads: the paper writes each Gaussian as ``exp(-(x² + y²)/s²)`` with ``s`` the spread in degrees; we use
that. Zhang's distribution lists larger numbers (0.05, 0.225, 7.0; 0.0685, 0.826; 0.092, 0.6451°) that
its Gaussian routine treats as full widths at half maximum — the paper's ``s`` times 2√ln2 within a few per
cent, so the same filters. ISETCam's current ``gauss2`` treats those same numbers as half widths at half
maximum, which makes its Gaussians about 2.1× wider than the paper's; we do not follow it.

References
----------
.. [Zhang1996] see docs/references.md
.. [Zhang1997] see docs/references.md; the filters and the opponent matrix as printed.
.. [Poirson1993] see docs/references.md; the opponent space.
"""
from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np
from scipy import fft, ndimage

from spectracam.core.cielab import delta_e as _delta_e
from spectracam.core.parallel import threads
from spectracam.core.cielab import xyz_to_lab as _xyz_to_lab
from spectracam.processing.color import samples_per_degree  # noqa: F401  (the viewing geometry is the display's)

if TYPE_CHECKING:
    from numpy.typing import ArrayLike, DTypeLike

__all__ = ["OPPONENT_TO_XYZ", "SCIELAB_FILTERS", "XYZ_TO_OPPONENT", "XYZ_TO_OPPONENT_AS_PRINTED",
           "filter_extended_opponent", "reflected_indices", "scielab", "scielab_components", "scielab_filter",
           "scielab_filter_fft", "scielab_kernels", "scielab_reach"]

#: The published filters, Zhang & Wandell (1997), table: per opponent channel, (weight w_i, spread s_i in
#: degrees of visual angle) of the Gaussians ``k_i exp(-(x² + y²)/s_i²)``.
SCIELAB_FILTERS: dict[str, tuple[tuple[float, float], ...]] = {
    "luminance": ((0.921, 0.0283), (0.105, 0.133), (-0.108, 4.336)),
    "red_green": ((0.531, 0.0392), (0.330, 0.494)),
    "blue_yellow": ((0.488, 0.0536), (0.371, 0.386)),
}

#: CIE 1931 XYZ → opponent (O1, O2, O3), rows O1, O2, O3: the matrix of the reference code (Zhang's
#: ``cmatrix('xyz2opp')``, ISETCam's ``colorTransformMatrix('xyz2opp', 2)``), whose 3-decimal rounding the
#: paper prints. The paper prints O2's Z coefficient as -0.077; the code has +0.0771569, which keeps the
#: red-green channel small for whites as an opponent channel should be (O2/O1 = -0.06 for D65, against
#: -0.25 with the printed sign; see :data:`XYZ_TO_OPPONENT_AS_PRINTED`). Uniform fields give CIELAB
#: whichever matrix is used (any invertible matrix cancels); the sign matters for patterns only.
XYZ_TO_OPPONENT = np.array([[0.2787336, 0.7218031, -0.1065520],
                            [-0.4487736, 0.2898056, 0.0771569],
                            [0.0859513, -0.5899859, 0.5011089]])

#: Its inverse, opponent → XYZ, computed once (a solve per image cost 83 ms at 1 Mpx; issue 38).
OPPONENT_TO_XYZ = np.linalg.inv(XYZ_TO_OPPONENT)

#: The matrix as printed in Zhang & Wandell (1997): O1 = 0.279X + 0.72Y - 0.107Z,
#: O2 = -0.449X + 0.29Y - 0.077Z, O3 = 0.086X - 0.59Y + 0.501Z (pass it as ``opponent_matrix`` to use it).
XYZ_TO_OPPONENT_AS_PRINTED = np.array([[0.279, 0.72, -0.107],
                                       [-0.449, 0.29, -0.077],
                                       [0.086, -0.59, 0.501]])

_CHANNELS = ("luminance", "red_green", "blue_yellow")
_BOUNDARIES = ("reflect", "wrap", "nearest")


def _check_spd(spd) -> float:
    s = float(spd)
    if not (s > 0 and np.isfinite(s)):
        raise ValueError(f"S-CIELAB: samples_per_degree = {spd!r}: a positive, finite number")
    return s


def _support(spd: float, support_deg: float) -> np.ndarray:
    """Odd number of sample positions, pixels, centred on 0, spanning ``support_deg``."""
    if not (support_deg > 0 and np.isfinite(support_deg)):
        raise ValueError(f"S-CIELAB: support_deg = {support_deg!r}: a positive, finite number")
    n = max(1, 2 * int(np.ceil(spd * support_deg / 2.0)) - 1)
    return np.arange(n) - (n - 1) / 2.0


def _components(spd: float, support_deg: float, channel: str) -> tuple[np.ndarray, np.ndarray]:
    """1-D unit-sum Gaussians exp(-x²/(s·spd)²) (rows: components) and their weights normalised to sum 1."""
    x = _support(spd, support_deg)
    w = np.array([c[0] for c in SCIELAB_FILTERS[channel]])
    s = np.array([c[1] for c in SCIELAB_FILTERS[channel]]) * spd
    g = np.exp(-(x[None, :] / s[:, None]) ** 2)
    return g / g.sum(axis=1, keepdims=True), w / w.sum()


def scielab_kernels(samples_per_degree: float, support_deg: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The three S-CIELAB point spreads (luminance, red-green, blue-yellow), each summing to 1.

    Parameters
    ----------
    samples_per_degree : float
        Image samples per degree of visual angle (see :func:`samples_per_degree`).
    support_deg : float
        Side of the square support, degrees (1° as the reference code); an odd number of samples.

    Returns
    -------
    tuple of three (n, n) ndarrays
        ``Σ w_i E_i / Σ w_i`` with ``E_i`` the unit-sum sampled Gaussian ``exp(-(x² + y²)/(s_i·spd)²)``.

    Raises
    ------
    ValueError
        ``samples_per_degree`` not a positive, finite number.

    References
    ----------
    .. [Zhang1997] see docs/references.md; the published weights and spreads (:data:`SCIELAB_FILTERS`).

    Examples
    --------
    >>> k = scielab_kernels(41.0)
    >>> [kk.shape for kk in k]
    [(41, 41), (41, 41), (41, 41)]
    >>> [round(float(kk.sum()), 12) for kk in k]
    [1.0, 1.0, 1.0]
    """
    spd = _check_spd(samples_per_degree)
    out = []
    for ch in _CHANNELS:
        g, w = _components(spd, support_deg, ch)
        out.append(np.einsum("i,ij,ik->jk", w, g, g))
    return tuple(out)


def scielab_filter(xyz: ArrayLike, samples_per_degree: float, *, support_deg: float = 1.0,
                   boundary: str = "reflect", opponent_matrix: ArrayLike = XYZ_TO_OPPONENT) -> np.ndarray:
    """Spatially filter an XYZ image as S-CIELAB does: opponent space, per-channel kernels, back to XYZ.

    The kernels are sums of separable Gaussians, so the filtering is done exactly as a sum of row and
    column convolutions (equal to the 2-D convolution with :func:`scielab_kernels`).

    Parameters
    ----------
    xyz : array_like, shape (rows, cols, 3)
        CIE 1931 XYZ image.
    samples_per_degree : float
        Image samples per degree of visual angle.
    support_deg : float
        Kernel support, degrees.
    boundary : {"reflect", "wrap", "nearest"}
        Extension beyond the image (``scipy.ndimage`` modes; "reflect" is Matlab's ``symmetric``
        padding, "wrap" is periodic as ISETCam's FFT filtering).
    opponent_matrix : array_like, shape (3, 3)
        XYZ → opponent matrix (rows O1, O2, O3).

    Returns
    -------
    ndarray, shape (rows, cols, 3)
        Filtered XYZ.

    Raises
    ------
    ValueError
        An image not of shape (rows, cols, 3), an unknown ``boundary``, ``samples_per_degree`` not a positive,
        finite number, or an ``opponent_matrix`` not of shape (3, 3).

    Examples
    --------
    A uniform field is unchanged:

    >>> f = scielab_filter(np.full((8, 8, 3), [0.3, 0.4, 0.5]), 30.0)
    >>> bool(np.allclose(f, [0.3, 0.4, 0.5], rtol=0, atol=1e-15))
    True
    """
    img = np.asarray(xyz, dtype=float)
    if img.ndim != 3 or img.shape[-1] != 3:
        raise ValueError(f"S-CIELAB: expected an XYZ image of shape (rows, cols, 3), got {img.shape}")
    if boundary not in _BOUNDARIES:
        raise ValueError(f"S-CIELAB: boundary = {boundary!r}: one of {', '.join(_BOUNDARIES)}")
    spd = _check_spd(samples_per_degree)
    m = np.asarray(opponent_matrix, dtype=float)
    if m.shape != (3, 3):
        raise ValueError(f"S-CIELAB: opponent_matrix has shape {m.shape}, expected (3, 3)")
    opp = img @ m.T
    out = np.empty_like(opp)
    for c, ch in enumerate(_CHANNELS):
        g, w = _components(spd, support_deg, ch)
        plane = opp[..., c]
        acc = np.zeros_like(plane)
        for wi, gi in zip(w, g):
            tmp = ndimage.correlate1d(plane, gi, axis=0, mode=boundary)
            acc += wi * ndimage.correlate1d(tmp, gi, axis=1, mode=boundary)
        out[..., c] = acc
    return np.linalg.solve(m, out.reshape(-1, 3).T).T.reshape(out.shape)


@lru_cache(maxsize=8)
def _kernel_spectra(spd: float, shape: tuple[int, int], dtype: str) -> np.ndarray:
    """``(shape[0], shape[1]//2 + 1, 3)``: the real FFTs of the three kernels of :func:`scielab_kernels` zero-padded
    to ``shape`` (memoised: every capture of one scene is filtered at one size)."""
    k = scielab_kernels(spd)
    out = np.stack([fft.rfft2(kk.astype(dtype), s=shape) for kk in k], axis=-1)
    out.flags.writeable = False
    return out


def scielab_filter_fft(xyz: ArrayLike, samples_per_degree: float, dtype: DTypeLike = np.float64) -> np.ndarray:
    """:func:`scielab_filter` computed by FFT, in ``dtype``.

    The filter of :func:`scielab_filter` with a reflecting boundary, 1° support and the reference opponent matrix,
    computed as one FFT convolution per opponent channel with the full 2-D kernels of :func:`scielab_kernels`.

    The image is extended by the kernels' reach with ``numpy.pad(mode="symmetric")`` — scipy.ndimage's "reflect",
    so the result equals :func:`scielab_filter`'s to the rounding of ``dtype`` (float64: 1e-15 of the largest
    value; float32: about 1e-6, which moves a ΔE of 10 by up to 1e-4; ``tests/test_scielab_scores.py``).  On a
    640×480 image, with the kernels' spectra memoised, about 2× faster in float64 (3× in float32) than the 14
    row and column passes, which is why the chart scores filter their renderings the same way (in float64, band by
    band, through :func:`filter_extended_opponent`, which this calls after its pad).

    Parameters
    ----------
    xyz, samples_per_degree
        As :func:`scielab_filter`.
    dtype : numpy dtype
        Precision of the FFT convolution: float64 (the default) or float32.

    Returns
    -------
    ndarray, shape (rows, cols, 3)
        Filtered XYZ, float64.

    Raises
    ------
    ValueError
        An image not of shape (rows, cols, 3), or ``samples_per_degree`` not a positive, finite number.

    Examples
    --------
    >>> x = np.random.default_rng(0).random((30, 40, 3))
    >>> bool(np.allclose(scielab_filter_fft(x, 20.0, np.float64), scielab_filter(x, 20.0), rtol=0, atol=1e-12))
    True
    """
    img = np.asarray(xyz, dtype=float)
    if img.ndim != 3 or img.shape[-1] != 3:
        raise ValueError(f"S-CIELAB: expected an XYZ image of shape (rows, cols, 3), got {img.shape}")
    spd = _check_spd(samples_per_degree)
    r = scielab_reach(spd)
    opp = np.pad((img @ XYZ_TO_OPPONENT.T).astype(np.dtype(dtype)), ((r, r), (r, r), (0, 0)), mode="symmetric")
    return filter_extended_opponent(opp, spd).astype(float, copy=False) @ OPPONENT_TO_XYZ.T


def scielab_components(samples_per_degree: float) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
    """Each opponent channel's kernel as its separable parts: :func:`scielab_kernels`' ``k = Σ w_i g_i g_iᵀ``.

    Parameters
    ----------
    samples_per_degree : float
        Image samples per degree of visual angle.

    Returns
    -------
    tuple of three (weights, gaussians)
        Per channel (luminance, red-green, blue-yellow): the weights ``(n,)``, summing to 1, and the unit-sum 1-D
        Gaussians ``(n, 2r + 1)`` sampled on the 1° support (:func:`scielab_reach`).

    Raises
    ------
    ValueError
        ``samples_per_degree`` not a positive, finite number.

    Examples
    --------
    >>> w, g = scielab_components(41.0)[0]
    >>> k = scielab_kernels(41.0)[0]
    >>> bool(np.allclose(np.einsum("i,ij,ik->jk", w, g, g), k, rtol=0, atol=1e-18))
    True
    """
    spd = _check_spd(samples_per_degree)
    return tuple((w, g) for g, w in (_components(spd, 1.0, ch) for ch in _CHANNELS))


def scielab_reach(samples_per_degree: float) -> int:
    """The S-CIELAB kernels' reach, pixels: half the side of :func:`scielab_kernels`' (1° support) less the centre.

    Parameters
    ----------
    samples_per_degree : float
        Image samples per degree of visual angle.

    Returns
    -------
    int
        ``r``: the kernels are ``(2r + 1, 2r + 1)``.

    Examples
    --------
    >>> scielab_reach(41.0)
    20
    """
    return _support(_check_spd(samples_per_degree), 1.0).size // 2


def reflected_indices(start: int, stop: int, n: int) -> np.ndarray:
    """Indices ``start … stop − 1`` of an axis of ``n`` samples extended by reflection about its ends, as
    ``numpy.pad(mode="symmetric")`` (SciPy's "reflect") extends it: ``d c b a | a b c d | d c b a``, period ``2n``.

    Parameters
    ----------
    start, stop : int
        The extended axis' positions (negative, or ``n`` and beyond, outside the axis).
    n : int
        Samples on the axis, ≥ 1.

    Returns
    -------
    ndarray of int
        ``stop − start`` indices in ``[0, n)``.

    Examples
    --------
    >>> reflected_indices(-2, 6, 4).tolist()
    [1, 0, 0, 1, 2, 3, 3, 2]
    """
    i = np.arange(start, stop) % (2 * n)
    return np.where(i < n, i, 2 * n - 1 - i)


def filter_extended_opponent(opp: np.ndarray, samples_per_degree: float) -> np.ndarray:
    """The S-CIELAB filters applied, by FFT, to an opponent image that already extends the kernels' reach ``r``
    (:func:`scielab_reach`) beyond the wanted pixels on every side (by reflection at an image's edge, by its own
    pixels inside it): the wanted pixels' filtered opponent values.

    One real FFT convolution per opponent channel with the full 2-D kernels of :func:`scielab_kernels`, zero-padded
    to a fast length; the circular wrap reaches only the ``2r`` first rows and columns of the result, which are the
    extension's, so the wanted pixels are the linear convolution's exactly (to the rounding of the FFT).  A band of a
    larger image is filtered with its neighbours' rows as its extension, with no second margin (issue 38).

    Parameters
    ----------
    opp : ndarray, shape (rows + 2r, cols + 2r, 3)
        Opponent (O1, O2, O3) values, float64 or float32 (the FFT's precision).
    samples_per_degree : float
        Image samples per degree of visual angle.

    Returns
    -------
    ndarray, shape (rows, cols, 3)
        The filtered opponent values, in ``opp``'s precision.

    Raises
    ------
    ValueError
        ``samples_per_degree`` not a positive, finite number, or ``opp`` not ``(rows, cols, 3)`` with at least
        ``2r + 1`` rows and columns.
    """
    spd = _check_spd(samples_per_degree)
    r = scielab_reach(spd)
    if opp.ndim != 3 or opp.shape[-1] != 3 or min(opp.shape[:2]) <= 2 * r:
        raise ValueError(f"S-CIELAB: an extended opponent image of shape {opp.shape}: (rows, cols, 3) with more "
                         f"than {2 * r} rows and columns (the kernels' reach, {r} px, either side)")
    h, w = opp.shape[:2]
    shape = (fft.next_fast_len(h, real=True), fft.next_fast_len(w, real=True))
    workers = threads()   # the same numbers on any number of threads (pocketfft splits the 1-D transforms)
    spectrum = fft.rfft2(opp, s=shape, axes=(0, 1), workers=workers)
    spectrum *= _kernel_spectra(spd, shape, opp.dtype.name)
    return fft.irfft2(spectrum, s=shape, axes=(0, 1), workers=workers)[2 * r:h, 2 * r:w]


def scielab(xyz1: ArrayLike, xyz2: ArrayLike, white_xyz: ArrayLike, samples_per_degree: float,
            delta_e: str = "cie1976", *, support_deg: float = 1.0, boundary: str = "reflect",
            opponent_matrix: ArrayLike = XYZ_TO_OPPONENT) -> np.ndarray:
    """S-CIELAB colour difference map between two XYZ images (Zhang & Wandell 1996/1997).

    Parameters
    ----------
    xyz1, xyz2 : array_like, shape (rows, cols, 3)
        CIE 1931 XYZ images of the same size, on the scale of ``white_xyz``.
    white_xyz : array_like, shape (3,)
        XYZ of the white both images are referred to (any Y scale, the same as the images').
    samples_per_degree : float
        Image samples per degree of visual angle (:func:`samples_per_degree` from the viewing geometry).
    delta_e : {"cie1976", "ciede2000"}
        Colour-difference formula (``spectracam.core.cielab.DELTA_E_METHODS``).
    support_deg, boundary, opponent_matrix
        As :func:`scielab_filter`.

    Returns
    -------
    ndarray, shape (rows, cols)
        ΔE per pixel.

    Raises
    ------
    ValueError
        Images of different shapes, a ``white_xyz`` that is not three positive values, or what
        :func:`scielab_filter` refuses.
    spectracam.core.errors.ConfigError
        An unknown ``delta_e``.

    References
    ----------
    .. [Zhang1997] see docs/references.md
    .. [Zhang1996] see docs/references.md

    Examples
    --------
    Uniform fields give the plain CIELAB difference:

    >>> w = np.array([0.9505, 1.0, 1.089])
    >>> a = np.full((16, 16, 3), [0.20, 0.21, 0.25]); b = np.full((16, 16, 3), [0.22, 0.21, 0.22])
    >>> d = scielab(a, b, w, 40.0)
    >>> from spectracam.core.cielab import delta_e, xyz_to_lab
    >>> bool(np.allclose(d, delta_e(xyz_to_lab(a[0, 0], w), xyz_to_lab(b[0, 0], w)), rtol=0, atol=1e-9))
    True
    """
    a, b = np.asarray(xyz1, dtype=float), np.asarray(xyz2, dtype=float)
    if a.shape != b.shape:
        raise ValueError(f"S-CIELAB: the images differ in shape: {a.shape} and {b.shape}")
    white = np.asarray(white_xyz, dtype=float)
    if white.shape != (3,) or not np.all(white > 0):
        raise ValueError(f"S-CIELAB: white_xyz = {white_xyz!r}: three positive XYZ values")
    kw = dict(support_deg=support_deg, boundary=boundary, opponent_matrix=opponent_matrix)
    lab1 = _xyz_to_lab(scielab_filter(a, samples_per_degree, **kw), white)
    lab2 = _xyz_to_lab(scielab_filter(b, samples_per_degree, **kw), white)
    return np.asarray(_delta_e(lab1, lab2, delta_e))
