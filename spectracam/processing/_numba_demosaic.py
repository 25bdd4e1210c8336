"""Numba kernel of :func:`spectracam.processing.color.demosaic`'s ``bilinear`` on a Bayer mosaic (imported on first
use; needs numba): the whole image in one pass, bands of rows on the kernels' pool, instead of three full-size
``scipy.ndimage.convolve`` passes per band of rows.

The arithmetic is colour-demosaicing's ``demosaicing_CFA_Bayer_bilinear``: each channel's samples (the mosaic times
the channel's mask) convolved with ``[[0, 1, 0], [1, 4, 1], [0, 1, 0]] / 4`` (G) or ``[[1, 2, 1], [2, 4, 2],
[1, 2, 1]] / 4`` (R, B), the image extended by reflection (``scipy.ndimage``'s "reflect": ``d c b a | a b c d``).
The weights are powers of two, so only the order of the nine additions can differ from SciPy's: the values agree
to the rounding of float64 (``tests/test_fused_score.py``).
"""
from __future__ import annotations

import numpy as np

from spectracam.core.parallel import njit_cached

#: The two kernels, ``[green?][dy + 1][dx + 1]``.
_WEIGHTS = np.array([[[0.25, 0.5, 0.25], [0.5, 1.0, 0.5], [0.25, 0.5, 0.25]],
                     [[0.0, 0.25, 0.0], [0.25, 1.0, 0.25], [0.0, 0.25, 0.0]]])


@njit_cached(nogil=True)
def bilinear_bayer_kernel(start, stop, cfa, chan, green, weights, divisor, out):
    """Rows ``[start, stop)`` of ``out`` ``(H, W, 3)``: channel ``chan[y % 2, x % 2]`` of the Bayer tile is the one
    site ``(y, x)`` records; ``green[c]`` picks channel ``c``'s kernel in ``weights``; each channel ``c`` is divided
    by ``divisor[c]`` as it is written (the exposure normalisation; 1 for none: the same values)."""
    h, w = cfa.shape
    for y in range(start, stop):
        for x in range(w):
            a0 = a1 = a2 = 0.0
            for dy in range(-1, 2):
                yy = y + dy
                yy = -yy - 1 if yy < 0 else (2 * h - yy - 1 if yy >= h else yy)
                for dx in range(-1, 2):
                    xx = x + dx
                    xx = -xx - 1 if xx < 0 else (2 * w - xx - 1 if xx >= w else xx)
                    c = chan[yy & 1, xx & 1]
                    v = weights[green[c], dy + 1, dx + 1] * np.float64(cfa[yy, xx])
                    if c == 0:
                        a0 += v
                    elif c == 1:
                        a1 += v
                    else:
                        a2 += v
            out[y, x, 0], out[y, x, 1], out[y, x, 2] = a0 / divisor[0], a1 / divisor[1], a2 / divisor[2]
