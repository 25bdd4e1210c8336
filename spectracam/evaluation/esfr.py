"""ISO 12233:2017 edge-based spatial frequency response (e-SFR) of a slanted edge.

The algorithm of ISO 12233:2017, clause 6 and annex D (unchanged from ISO 12233:2014), as
implemented by its author's reference code (P. D. Burns, ``sfrmat3``/``sfrmat4``; see Burns, "Slanted-edge
MTF for digital camera and scanner analysis", Proc. IS&T PICS 2000, pp. 135-138):

1. per row, the derivative of the pixel values with the FIR ``[-1/2, +1/2]``; the edge location is the
   centroid of that derivative under a Hamming window (first centred on the region, then, in a
   second pass, on each row's fitted edge position);
2. a least-squares fit of edge location against row: a line (the standard), or a 2nd-order polynomial
   (``fit_order=2``, as ISO 12233:2023 / ``sfrmat5`` allow);
3. the rows are cut to a whole number of phase cycles (``round(floor(rows·|tan θ|) / |tan θ|)`` rows, as
   ``sfrmat``), and every pixel is projected along the fitted edge into bins 1/4 pixel wide
   (4× oversampling), giving the edge spread function (ESF): ``4 × columns`` bins spanning the region
   (as ``sfrmat``'s ``project``), an empty bin interpolated from its neighbours;
4. the line spread function (LSF) is the ESF's discrete derivative, the ``[-1/2, 0, +1/2]`` FIR of the
   standard (``derivative="central"``; ``"forward"`` gives the two-tap ``[-1/2, +1/2]``), centred by
   circular rotation on its maximum and multiplied by a Hamming window;
5. the e-SFR is the modulus of its DFT normalised to 1 at zero frequency, divided by the frequency
   response of the derivative FIR (``sinc(2 f Δ)`` for the central difference at bin spacing Δ,
   ``sinc(f Δ)`` for the two-tap one; the correction is capped at 10 as in the standard) — the
   correction ISO 12233:2014 introduced (its printed D(k) has a misprint, see Imatest, "LSF correction
   factor for slanted-edge MTF measurements", 2015; we use the exact response of the FIR used);
6. frequencies in cycles per pixel measured along the edge normal: the bin spacing normal to the edge is
   ``cos θ / 4`` pixel (Burns' ``delfac``), so ``f_k = k / (N Δ)``.

The frequency response of the derivative FIR is the correction the standard makes; two biases of the
binning it does not correct, and ``correct_binning=True`` (not part of the standard, off by default) does:

* averaging the ESF over a bin multiplies the SFR by ``sinc(f Δ)``: -2.5 % at 0.5 cy/px for a 5° edge;
* the pixels' phases are not spread evenly over the bins (the number of rows is a whole number of
  cycles only to within a row, and a bin gets ``⌊n/4⌋`` or ``⌈n/4⌉`` of the ``n`` phases), which puts
  each bin's samples off its centre by a pattern repeating every pixel and leaks the SFR from
  ``1 - f`` into ``f`` (about ±0.01-0.05 near 1 cy/px, growing with the angle);

with it each bin's value is placed at the mean position of its samples and resampled to the bin centres
by linear interpolation, and the SFR is divided by ``sinc(f Δ)``. On an ideal 5° edge blurred by a
Gaussian of σ = 0.6 px and pixel-integrated (tests/test_spatial_metrics.py) the standard's e-SFR is
within 0.7 % of the closed form up to 0.3 cy/px and 2 % up to 0.5 cy/px, MTF50 -0.4 %; corrected,
0.5 % up to 0.5 cy/px, 0.001 in absolute terms up to 1 cy/px, MTF50 +0.1 %. The remaining error is
the Hamming window's (it falls as the square of the region's width).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["ESFRResult", "NoEdge", "esfr"]


class NoEdge(ValueError):
    """The image holds no edge the e-SFR can use (too weak against the noise, or not a straight edge
    inside the region): a property of the image, not of the call — callers score it as no MTF."""

#: Smallest region accepted: rows and columns.
MIN_ROWS, MIN_COLS = 8, 8


@dataclass(frozen=True)
class ESFRResult:
    """The e-SFR of one slanted edge.

    Attributes
    ----------
    frequencies_cy_per_px : ndarray
        Spatial frequencies along the edge normal, cycles/pixel, from 0 to (at least) 1.
    sfr : ndarray
        The e-SFR at those frequencies, 1 at zero frequency, corrected for the derivative FIR.
    mtf50_cy_per_px : float
        Frequency where the SFR first falls to 0.5, linearly interpolated (NaN if it never does).
    edge_angle_deg : float
        Angle of the fitted (linear) edge from the image axis it is near: for a near-vertical edge the
        column of the edge grows with the row index when positive; for a near-horizontal one the row
        grows with the column index when positive.
    orientation : str
        ``"vertical"`` or ``"horizontal"`` (detected from the image gradients).
    esf : ndarray
        The oversampled edge spread function (bin spacing ``bin_width_px`` along the normal), oriented
        dark to bright.
    lsf : ndarray
        The centred, windowed line spread function whose DFT gives ``sfr``.
    bin_width_px : float
        ESF sample spacing along the edge normal, pixels (``cos θ / oversampling``).
    rows_used : int
        Number of rows (along the edge) kept: a whole number of phase cycles.
    """

    frequencies_cy_per_px: np.ndarray
    sfr: np.ndarray
    mtf50_cy_per_px: float
    edge_angle_deg: float
    orientation: str
    esf: np.ndarray
    lsf: np.ndarray
    bin_width_px: float
    rows_used: int


def _hamming(x: np.ndarray, centre) -> np.ndarray:
    """Hamming window 0.54 + 0.46 cos(π (x - c) / h) centred at ``centre`` (any shape broadcasting with
    ``x``), its half-width h reaching the farther end of ``x`` (Burns' asymmetric ``ahamming``)."""
    c = np.asarray(centre, float)
    half = np.maximum(c - x[..., :1], x[..., -1:] - c) + 0.5
    return 0.54 + 0.46 * np.cos(np.pi * (x - c) / half)


def _edge_locations(deriv: np.ndarray, x: np.ndarray, centres) -> np.ndarray:
    """Per-row centroid of the windowed derivative (ISO 12233:2017, D.2)."""
    w = deriv * _hamming(x, centres)
    den = w.sum(axis=1)
    if np.any(den <= 0):
        raise NoEdge(f"e-SFR: no edge found in row {int(np.argmax(den <= 0))} (derivative sums to ≤ 0)")
    return (w * x).sum(axis=1) / den


def _fit(rows: np.ndarray, loc: np.ndarray, order: int) -> np.ndarray:
    """Least-squares polynomial coefficients, lowest order first."""
    return np.polynomial.polynomial.polyfit(rows, loc, order)


def esfr(image: ArrayLike, *, fit_order: int = 1, oversampling: int = 4, derivative: str = "central",
         correct_binning: bool = False, max_frequency_cy_per_px: float = 1.0) -> ESFRResult:
    """ISO 12233:2017 edge-based SFR (e-SFR) of a slanted edge.

    Parameters
    ----------
    image : array_like, shape (rows, cols)
        One channel (or luminance), linear in exposure, holding one straight edge slanted by about
        2-10° from the vertical or the horizontal (detected) and crossing the whole region
        (top and bottom for a near-vertical edge). ISO 12233:2017 recommends an edge contrast of 4:1.
    fit_order : {1, 2}
        Order of the edge-position fit: 1 (linear, ISO 12233:2017) or 2 (ISO 12233:2023 allows
        polynomials).
    oversampling : int
        Bins per pixel for the ESF (4 in the standard).
    derivative : {"central", "forward"}
        ESF→LSF FIR: ``"central"`` is the standard's ``[-1/2, 0, +1/2]`` (response ``sinc(2 f Δ)``),
        ``"forward"`` the two-tap ``[-1/2, +1/2]`` (response ``sinc(f Δ)``). Either is divided out.
    correct_binning : bool
        Not part of the standard (default off): place each ESF bin at the mean position of its samples
        (resampled to the bin centres) and divide by ``sinc(f Δ)``, the attenuation of averaging over a
        bin; removes the binning's -2.5 % at 0.5 cy/px and its phase leakage (see the module).
    max_frequency_cy_per_px : float
        Highest frequency returned (the first DFT bin at or above it is included).

    Returns
    -------
    ESFRResult

    Raises
    ------
    ValueError
        With one line saying why: not 2-D, not finite, too small, no edge (contrast not above the
        noise), an edge not crossing the region, or an angle too small for one phase cycle.

    References
    ----------
    .. [ISO12233] see docs/references.md; clause 6 and annex D.
    .. [ISO12233-2023] see docs/references.md; the polynomial edge fit, ``fit_order=2``.
    .. [Burns2000] see docs/references.md; reference code ``sfrmat3``/``sfrmat4``/``sfrmat5``.

    Examples
    --------
    A 5° edge blurred by a Gaussian of σ = 0.6 px (point-sampled, so no pixel aperture): the SFR is
    exp(-2π²σ²f²), whose MTF50 is √(ln 2 / 2π²) / σ = 0.3123 cy/px.

    >>> import numpy as np
    >>> from scipy.special import ndtr
    >>> r, c = np.mgrid[0:100, 0:64]
    >>> t = np.tan(np.radians(5.0))
    >>> img = 0.2 + 0.6 * ndtr((c - 31.7 - t * (r - 50)) * np.cos(np.radians(5.0)) / 0.6)
    >>> res = esfr(img, correct_binning=True)
    >>> res.orientation, round(res.edge_angle_deg, 2), round(res.mtf50_cy_per_px, 3)
    ('vertical', 5.0, 0.312)
    >>> round(float(res.sfr[0]), 6), bool(res.frequencies_cy_per_px[-1] >= 1.0)
    (1.0, True)
    """
    a, orientation = _oriented(_checked(image, fit_order, derivative, oversampling))
    edge = _slanted_edge(a, orientation, fit_order)
    return _edge_sfr(edge, oversampling, derivative, correct_binning, max_frequency_cy_per_px)


class _SlantedEdge(NamedTuple):
    """An edge found and fitted (ISO 12233:2017, D.2): the region turned near-vertical and its fitted edge."""

    image: np.ndarray        # the region as a float array, the edge near-vertical
    orientation: str         # "vertical" or "horizontal": the edge's orientation in the given image
    sign: float              # the polarity (+1: dark to bright along the columns)
    slope: float             # columns per row of the linear fit
    edge: np.ndarray         # the fit's polynomial coefficients, lowest order first


def _slanted_edge(a: np.ndarray, orientation: str, fit_order: int) -> _SlantedEdge:
    """Steps 1-2: the edge's polarity, its per-row centroids and their polynomial fit (ISO 12233:2017, D.2)."""
    sign = _polarity(a)
    slope, edge = _fit_edge(a, sign, fit_order)
    return _SlantedEdge(a, orientation, sign, slope, edge)


def _edge_sfr(e: _SlantedEdge, oversampling, derivative: str, correct_binning: bool,
              max_frequency_cy_per_px: float) -> ESFRResult:
    """Steps 3-6: the binned ESF, its windowed LSF and the corrected e-SFR along the edge normal (ISO 12233:2017,
    annex D)."""
    esf, n_use = _project(e.image, e.edge, e.slope, e.sign, int(oversampling), correct_binning)
    lsf = _line_spread(esf, derivative)
    freq, sfr = _sfr(lsf, e.slope, int(oversampling), derivative, correct_binning, max_frequency_cy_per_px)
    return ESFRResult(frequencies_cy_per_px=freq, sfr=sfr, mtf50_cy_per_px=_mtf50(freq, sfr),
                      edge_angle_deg=float(np.degrees(np.arctan(e.slope))), orientation=e.orientation, esf=esf,
                      lsf=lsf, bin_width_px=float(np.cos(np.arctan(e.slope)) / oversampling), rows_used=n_use)


def _checked(image, fit_order, derivative, oversampling) -> np.ndarray:
    """The image as a float array, with every argument checked (one line each)."""
    a = np.asarray(image, dtype=float)
    if a.ndim != 2:
        raise ValueError(f"e-SFR: expected a 2-D array (one channel), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError("e-SFR: the image has NaN or infinite values")
    if fit_order not in (1, 2):
        raise ValueError(f"e-SFR: fit_order = {fit_order!r}: 1 (linear) or 2 (quadratic)")
    if derivative not in ("central", "forward"):
        raise ValueError(f"e-SFR: derivative = {derivative!r}: 'central' or 'forward'")
    if int(oversampling) != oversampling or oversampling < 1:
        raise ValueError(f"e-SFR: oversampling = {oversampling!r}: a positive integer (4 in ISO 12233)")
    return a


def _oriented(a: np.ndarray) -> tuple[np.ndarray, str]:
    """A near-vertical edge (transposed if it is near-horizontal: its gradient mostly along the columns)."""
    gx = np.abs(np.diff(a, axis=1)).mean() if a.shape[1] > 1 else 0.0
    gy = np.abs(np.diff(a, axis=0)).mean() if a.shape[0] > 1 else 0.0
    orientation = "vertical" if gx >= gy else "horizontal"
    if orientation == "horizontal":
        a = a.T
    nlin, npix = a.shape
    if nlin < MIN_ROWS or npix < MIN_COLS:
        raise ValueError(f"e-SFR: region of {nlin} x {npix} pixels (along x across the edge) is too small: "
                         f"need at least {MIN_ROWS} along and {MIN_COLS} across the edge")
    return a, orientation


def _polarity(a: np.ndarray) -> float:
    """+1 for dark → bright along the rows, -1 the other way; :class:`NoEdge` if the step is within the noise."""
    npix = a.shape[1]
    k = max(2, npix // 10)
    left, right = a[:, :k].mean(), a[:, -k:].mean()
    step = right - left
    noise = 1.4826 * np.median(np.abs(np.diff(a, axis=0))) / np.sqrt(2.0)
    if not abs(step) > max(5.0 * noise, 1e-12 * (abs(left) + abs(right)), 0.0):
        raise NoEdge(f"e-SFR: no edge: the two sides differ by {abs(step):.3g}, noise {noise:.3g}")
    return 1.0 if step > 0 else -1.0


def _fit_edge(a: np.ndarray, sign: float, fit_order: int) -> tuple[float, np.ndarray]:
    """Steps 1–2: each row's edge location (windowed derivative centroid, twice) and the fitted edge:
    ``(slope of the linear fit, edge column per row)``."""
    nlin, npix = a.shape
    x = np.arange(npix - 1) + 0.5
    deriv = sign * 0.5 * np.diff(a, axis=1)
    rows = np.arange(nlin, dtype=float)
    loc = _edge_locations(deriv, x[None, :], np.full((nlin, 1), (npix - 1) / 2.0))
    coef = _fit(rows, loc, fit_order)
    loc = _edge_locations(deriv, x[None, :], np.polynomial.polynomial.polyval(rows, coef)[:, None])
    coef = _fit(rows, loc, fit_order)
    slope = _fit(rows, loc, 1)[1]
    edge = np.polynomial.polynomial.polyval(rows, coef)
    margin = 1.0
    if edge.min() < margin or edge.max() > npix - 1 - margin:
        raise NoEdge(f"e-SFR: the fitted edge leaves the region (columns {edge.min():.1f} to {edge.max():.1f} "
                     f"of 0 to {npix - 1}): it must cross the whole region")
    if nlin * abs(slope) < 1.0:
        angle = np.degrees(np.arctan(slope))
        raise ValueError(f"e-SFR: edge angle {angle:.2f}° too close to the pixel axis for {nlin} rows: "
                         f"need rows·|tan θ| ≥ 1 (ISO 12233 uses about 5°)")
    return float(slope), edge


def _project(a, edge, slope, sign, oversampling, correct_binning) -> tuple[np.ndarray, int]:
    """Step 3: a whole number of phase cycles of rows projected along the edge into 1/oversampling-pixel
    bins: ``(ESF, rows used)``."""
    nlin, npix = a.shape
    n_use = min(nlin, int(round(np.floor(nlin * abs(slope)) / abs(slope))))
    a, edge = a[:n_use], edge[:n_use]
    offset = (np.arange(npix)[None, :] - edge[:, None]) * oversampling  # distance to the edge along x, bins
    nbin = oversampling * npix                                           # the ESF spans the region's width
    lo = int(np.floor(0.5 * (offset.min() + offset.max()))) - nbin // 2  # centred on the region (sfrmat)
    idx = np.floor(offset).astype(np.int64) - lo
    keep = (idx >= 0) & (idx < nbin)
    counts = np.bincount(idx[keep], minlength=nbin)
    sums = np.bincount(idx[keep], weights=sign * a[keep], minlength=nbin)
    filled = counts > 0
    if filled.sum() < 0.9 * nbin:
        raise ValueError(f"e-SFR: {nbin - filled.sum()} of {nbin} ESF bins are empty: more rows are needed")
    centres = np.arange(nbin) + 0.5                                      # bin centres, in bins from lo
    if correct_binning:   # each bin at the mean position of its samples, resampled to the bin centres
        at = np.bincount(idx[keep], weights=offset[keep] - lo, minlength=nbin)[filled] / counts[filled]
    else:
        at = centres[filled]
    return np.interp(centres, at, sums[filled] / counts[filled]), n_use


def _line_spread(esf: np.ndarray, derivative: str) -> np.ndarray:
    """Step 4: the LSF, the ESF's discrete derivative centred on its maximum and Hamming-windowed."""
    nbin = esf.size
    lsf = np.empty(nbin)
    if derivative == "central":
        lsf[1:-1] = 0.5 * (esf[2:] - esf[:-2])
        lsf[0], lsf[-1] = lsf[1], lsf[-2]
    else:
        lsf[:-1] = 0.5 * (esf[1:] - esf[:-1])
        lsf[-1] = lsf[-2]
    peak = int(round(np.flatnonzero(lsf == lsf.max()).mean()))
    lsf = np.roll(lsf, nbin // 2 - peak)
    return lsf * _hamming(np.arange(nbin, dtype=float), float(nbin // 2))


def _sfr(lsf, slope, oversampling, derivative, correct_binning, max_frequency_cy_per_px):
    """Steps 5–6: ``(frequencies along the edge normal, cy/px; |DFT| normalised and corrected)``."""
    nbin = lsf.size
    spectrum = np.abs(np.fft.rfft(lsf))
    if not spectrum[0] > 0:
        raise NoEdge("e-SFR: the line spread function integrates to ≤ 0: no usable edge")
    bin_width = np.cos(np.arctan(slope)) / oversampling              # ESF spacing along the normal, px
    freq = np.arange(spectrum.size) / (nbin * bin_width)
    response = np.sinc((2.0 if derivative == "central" else 1.0) * freq * bin_width)
    if correct_binning:
        response = response * np.sinc(freq * bin_width)
    sfr = spectrum / spectrum[0] / np.maximum(response, 0.1)         # correction capped at 10 (ISO 12233)
    n_out = min(spectrum.size, int(np.ceil(max_frequency_cy_per_px * nbin * bin_width - 1e-9)) + 1)
    return freq[:n_out], sfr[:n_out]


def _mtf50(freq: np.ndarray, sfr: np.ndarray) -> float:
    """Where the SFR first falls to 0.5, linearly interpolated (NaN if it never does)."""
    below = np.flatnonzero(sfr < 0.5)
    if not below.size:
        return float("nan")
    j = below[0]
    return float(freq[j - 1] + (sfr[j - 1] - 0.5) / (sfr[j - 1] - sfr[j]) * (freq[j] - freq[j - 1]))
