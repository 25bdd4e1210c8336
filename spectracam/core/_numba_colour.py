"""Numba kernels of :mod:`spectracam.core.cielab` (imported on first use; needs numba): CIELAB and ΔE of many
colours in one compiled pass, float64, without the dozens of full-size temporaries of the array formulas.

Each kernel takes a band ``[start, stop)`` of its index range and releases the GIL
(:func:`spectracam.core.parallel.run_bands` runs the bands on the pool).  The formulas are colour-science's, step
by step (``XYZ_to_Lab``, ``delta_E_CIE2000``), so the values agree with it to the rounding of float64
(``tests/test_fused_score.py``).
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from spectracam.core.parallel import njit_cached

#: CIE 15's ε = (24/116)³ and the slope and offset of the lightness function's linear part (841/108, 16/116).
_EPS = (24.0 / 116.0) ** 3
_SLOPE, _OFFSET = 841.0 / 108.0, 16.0 / 116.0
_THIRD = 1.0 / 3.0
_25_7 = 25.0 ** 7
_DEG = math.pi / 180.0

#: ΔE formulas by code (:data:`spectracam.core.cielab.DELTA_E_CODES`).
CIE1976, CIEDE2000 = 0, 1


@nb.njit(inline="always")
def _f(t):
    """CIE 1976's lightness function of a ratio to the white: ``t^⅓`` above ε, linear below."""
    return t ** _THIRD if t > _EPS else _SLOPE * t + _OFFSET


@nb.njit(inline="always")
def lab(x, y, z, m, wn):
    """L*, a*, b* of ``m @ (x, y, z)`` (XYZ scaled by the white's Y) against the white ``wn`` (its Y = 1)."""
    X = m[0, 0] * x + m[0, 1] * y + m[0, 2] * z
    Y = m[1, 0] * x + m[1, 1] * y + m[1, 2] * z
    Z = m[2, 0] * x + m[2, 1] * y + m[2, 2] * z
    fx, fy, fz = _f(X / wn[0]), _f(Y / wn[1]), _f(Z / wn[2])
    return 116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)


@nb.njit(inline="always")
def _hue(b, a):
    """Hue angle in degrees on [0, 360), 0 where a = b = 0 (colour-science's convention)."""
    if b == 0.0 and a == 0.0:
        return 0.0
    return math.degrees(math.atan2(b, a)) % 360.0


@nb.njit(inline="always")
def _hue_terms(h1, h2, c12):
    """CIEDE2000's hue difference Δh' and mean hue h̄' (CIE 142:2001; Sharma et al. 2005, eq. 10 and 14)."""
    d = h2 - h1
    if c12 == 0.0:
        dh = 0.0
    elif abs(d) <= 180.0:
        dh = d
    elif d > 180.0:
        dh = d - 360.0
    else:
        dh = d + 360.0
    s, ad = h1 + h2, abs(h1 - h2)
    if c12 == 0.0:
        hb = s
    elif ad <= 180.0:
        hb = s / 2.0
    elif s < 360.0:
        hb = (s + 360.0) / 2.0
    else:
        hb = (s - 360.0) / 2.0
    return dh, hb


@nb.njit(inline="always")
def de2000(L1, a1, b1, L2, a2, b2):
    """CIEDE2000 (CIE 142:2001) with k_L = k_C = k_H = 1, as colour-science's ``delta_E_CIE2000``."""
    cb = (math.hypot(a1, b1) + math.hypot(a2, b2)) / 2.0
    cb7 = cb ** 7
    g = 0.5 * (1.0 - math.sqrt(cb7 / (cb7 + _25_7)))
    ap1, ap2 = (1.0 + g) * a1, (1.0 + g) * a2
    cp1, cp2 = math.hypot(ap1, b1), math.hypot(ap2, b2)
    c12 = cp1 * cp2
    dh, hb = _hue_terms(_hue(b1, ap1), _hue(b2, ap2), c12)
    dL, dC = L2 - L1, cp2 - cp1
    dH = 2.0 * math.sqrt(c12) * math.sin(dh / 2.0 * _DEG)
    lb2 = ((L1 + L2) / 2.0 - 50.0) ** 2
    cbp = (cp1 + cp2) / 2.0
    t = (1.0 - 0.17 * math.cos((hb - 30.0) * _DEG) + 0.24 * math.cos(2.0 * hb * _DEG)
         + 0.32 * math.cos((3.0 * hb + 6.0) * _DEG) - 0.20 * math.cos((4.0 * hb - 63.0) * _DEG))
    dtheta = 30.0 * math.exp(-(((hb - 275.0) / 25.0) ** 2))
    cbp7 = cbp ** 7
    rt = -math.sin(2.0 * dtheta * _DEG) * 2.0 * math.sqrt(cbp7 / (cbp7 + _25_7))
    sl = 1.0 + (0.015 * lb2) / math.sqrt(20.0 + lb2)
    sc, sh = 1.0 + 0.045 * cbp, 1.0 + 0.015 * cbp * t
    x, y, z = dL / sl, dC / sc, dH / sh
    return math.sqrt(x * x + y * y + z * z + rt * y * z)


@nb.njit(inline="always")
def delta_e(L1, a1, b1, L2, a2, b2, method):
    """ΔE of the formula ``method`` (:data:`CIE1976` or :data:`CIEDE2000`)."""
    if method == CIEDE2000:
        return de2000(L1, a1, b1, L2, a2, b2)
    return math.sqrt((L1 - L2) ** 2 + (a1 - a2) ** 2 + (b1 - b2) ** 2)


@njit_cached(nogil=True)
def lab_kernel(start, stop, xyz, m, wn, out):
    """``out[i]`` = L*a*b* of ``m @ xyz[i]`` against ``wn``, for rows ``[start, stop)`` of ``xyz`` ``(n, 3)``."""
    for i in range(start, stop):
        out[i, 0], out[i, 1], out[i, 2] = lab(np.float64(xyz[i, 0]), np.float64(xyz[i, 1]), np.float64(xyz[i, 2]),
                                              m, wn)


@njit_cached(nogil=True)
def delta_e_kernel(start, stop, lab1, lab2, method, out):
    """``out[i]`` = ΔE of ``lab1[i]`` and ``lab2[i]`` (``lab2`` one row: every colour against it)."""
    one = lab2.shape[0] == 1
    for i in range(start, stop):
        k = 0 if one else i
        out[i] = delta_e(lab1[i, 0], lab1[i, 1], lab1[i, 2], lab2[k, 0], lab2[k, 1], lab2[k, 2], method)


@njit_cached(nogil=True)
def box_kernel(start, stop, rgb, boxes, m, wn, against, method, de_map, sums):
    """Boxes ``[start, stop)`` of a rendered image: per pixel of box ``p`` (rows ``boxes[p, 0]:boxes[p, 1]``,
    columns ``boxes[p, 2]:boxes[p, 3]``) the CIELAB of ``m @ rgb`` (display RGB to XYZ, scaled by the white's Y)
    and its ΔE of the formula ``method`` against ``against[p]``, written to ``de_map``; ``sums[p]`` = (Σ ΔE,
    Σ CIEDE2000) over the box's pixels, in float64."""
    for p in range(start, stop):
        L2, a2, b2 = against[p, 0], against[p, 1], against[p, 2]
        s0 = s1 = 0.0
        for y in range(boxes[p, 0], boxes[p, 1]):
            for x in range(boxes[p, 2], boxes[p, 3]):
                L1, a1, b1 = lab(np.float64(rgb[y, x, 0]), np.float64(rgb[y, x, 1]), np.float64(rgb[y, x, 2]), m, wn)
                d = delta_e(L1, a1, b1, L2, a2, b2, method)
                de_map[y, x] = d
                s0 += d
                s1 += d if method == CIEDE2000 else de2000(L1, a1, b1, L2, a2, b2)
        sums[p, 0], sums[p, 1] = s0, s1


@njit_cached(nogil=True)
def gather_kernel(start, stop, img, rows, cols, m, out):
    """Rows ``[start, stop)`` of ``out`` ``(len(rows), len(cols), 3)``: ``m @ img[rows[i], cols[j]]`` in float64 —
    an image's pixels picked (repeated, reflected) and carried through a 3 × 3 matrix in one pass (S-CIELAB's
    extended opponent band)."""
    for i in range(start, stop):
        y = rows[i]
        for j in range(cols.shape[0]):
            x = cols[j]
            a, b, c = np.float64(img[y, x, 0]), np.float64(img[y, x, 1]), np.float64(img[y, x, 2])
            out[i, j, 0] = m[0, 0] * a + m[0, 1] * b + m[0, 2] * c
            out[i, j, 1] = m[1, 0] * a + m[1, 1] * b + m[1, 2] * c
            out[i, j, 2] = m[2, 0] * a + m[2, 1] * b + m[2, 2] * c


@njit_cached(nogil=True)
def masked_lab_kernel(start, stop, f, keep, offsets, m, wn, out):
    """Rows ``[start, stop)`` of ``f`` ``(h, w, 3)``: the CIELAB of ``m @ f[i, j]`` against ``wn`` at the pixels where
    ``keep[i, j]``, into ``out[offsets[i] + k]`` (``k``: the kept pixel's rank in its row; row-major order)."""
    for i in range(start, stop):
        k = offsets[i]
        for j in range(f.shape[1]):
            if keep[i, j]:
                out[k, 0], out[k, 1], out[k, 2] = lab(f[i, j, 0], f[i, j, 1], f[i, j, 2], m, wn)
                k += 1


@njit_cached(nogil=True)
def masked_delta_e_kernel(start, stop, f, keep, offsets, m, wn, ref, method, out, row0, col0):
    """Rows ``[start, stop)`` of ``f`` ``(h, w, 3)``: at the pixels where ``keep[i, j]``, the ΔE of the formula
    ``method`` between the CIELAB of ``m @ f[i, j]`` against ``wn`` and ``ref[offsets[i] + k]`` (row-major rank, as
    :func:`masked_lab_kernel` writes it), into ``out[row0 + i, col0 + j]``."""
    for i in range(start, stop):
        k = offsets[i]
        for j in range(f.shape[1]):
            if keep[i, j]:
                L1, a1, b1 = lab(f[i, j, 0], f[i, j, 1], f[i, j, 2], m, wn)
                out[row0 + i, col0 + j] = delta_e(L1, a1, b1, ref[k, 0], ref[k, 1], ref[k, 2], method)
                k += 1
