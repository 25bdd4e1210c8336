"""Compiled rasteriser of :mod:`spectracam.scene.target`: occluding discs and rectangles on a label image.

One loop over shapes (not over pixels): each shape visits only the texels of its bounding box and
labels those still bare whose centre it covers, so the first shape drawn lies on top.
"""
from __future__ import annotations

import numba as nb
import numpy as np


def _njit(fn):
    try:
        return nb.njit(cache=True)(fn)
    except RuntimeError:  # no cache directory usable: compile each run
        return nb.njit(fn)


@_njit
def paint_shapes(labels, cx, cy, half_w, half_h, colour, discs, bare):
    """Label the bare (< 0) texels of ``labels`` (rows, cols) covered by each shape in turn — a disc
    of radius ``half_w`` or a rectangle of half sides ``half_w, half_h`` about the texel coordinates
    ``(cx, cy)`` — with its ``colour``; returns how many texels are still bare (``bare`` before)."""
    h, w = labels.shape
    for k in range(cx.size):
        if bare == 0:
            break
        x0 = max(int(np.floor(cx[k] - half_w[k])), 0)
        x1 = min(int(np.ceil(cx[k] + half_w[k])) + 1, w)
        y0 = max(int(np.floor(cy[k] - half_h[k])), 0)
        y1 = min(int(np.ceil(cy[k] + half_h[k])) + 1, h)
        r2 = half_w[k] * half_w[k]
        c = colour[k]
        for y in range(y0, y1):
            dy = y + 0.5 - cy[k]
            if discs and dy * dy > r2:
                continue
            for x in range(x0, x1):
                if labels[y, x] >= 0:
                    continue
                dx = x + 0.5 - cx[k]
                if discs:
                    if dx * dx + dy * dy > r2:
                        continue
                elif abs(dx) > half_w[k] or abs(dy) > half_h[k]:
                    continue
                labels[y, x] = c
                bare -= 1
    return bare
