"""Numba kernel of the ``multiple_capture`` read-out (:mod:`spectracam.sensor.readout`; imported on first use).

One pass per band of pixels: for each block of :data:`BLOCK` pixels the samples ``k = 0 … N`` are made one after
the other, each in one loop over the block (the compiler turns the loop body into selects and vectorises it): the
charge grows by its shot-noise increment, the well clips it, the read adds its noise and the offset, the ADC
digitises it, and the recursive estimate (:func:`_estimate`) takes it in.  Random numbers are the fused
capture's (:mod:`spectracam.sensor._numba_kernels`): Philox4x32-10 of the counter ``(pixel low, pixel high,
k // 2, 0)``; samples ``2m`` and ``2m + 1`` share one draw (words 0, 1 and 2, 3, each a Box–Muller pair: the shot
increment's normal and the read's).  Every value depends on (key, pixel, sample) alone, so the result does not
depend on the number of threads.  ``readout._mc_numpy`` computes the same numbers in NumPy (the normals
bit-identical, the float64 arithmetic in the same order).
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from spectracam.sensor._numba_kernels import _MASK, _S32, _njit, normal_pair, philox, poisson

__all__ = ["BLOCK", "POISSON_KEY_XOR", "mc_kernel"]

#: Pixels per block: the per-sample state of a block (9 float64 arrays) stays in the L1 cache.
BLOCK = 256
#: The Poisson counts of ``shot_noise_model = "poisson"`` come from the key with this word xor-ed into its first
#: half, at counter ``pixel·(N + 1) + k`` (NumPy's algorithm, :func:`~spectracam.sensor._numba_kernels.poisson`).
POISSON_KEY_XOR = 0x5BD1E995


@_njit(nogil=True)
def _draw(a, m, s, k0, k1, zs_e, zr_e, zs_o, zr_o):
    """The normals of samples ``s`` and ``s + 1`` of pixels ``a … a + m``: one Philox draw ``s // 2`` each, two
    Box–Muller pairs (shot, read)."""
    for x in range(m):
        pix = np.uint64(a + x)
        a0, a1, a2, a3 = philox(pix & _MASK, pix >> _S32, np.uint64(s // 2), np.uint64(0), k0, k1)
        zs_e[x], zr_e[x] = normal_pair(a0, a1)
        zs_o[x], zr_o[x] = normal_pair(a2, a3)


@_njit(nogil=True)
def _grow(a, m, s, n_s, dt, cur, q, zs, qtop, shot, use_poisson, kp0, k1):
    """The charge of sample ``s`` (> 0): the increment ``i·Δt`` with its shot noise, the well ``qtop``."""
    if shot and use_poisson:
        for x in range(m):
            idx = np.uint64(a + x) * np.uint64(n_s + 1) + np.uint64(s)
            q[x] = min(q[x] + poisson(cur[x] * dt, idx, kp0, k1), qtop)
    elif shot:
        for x in range(m):
            inc = cur[x] * dt
            q[x] = min(q[x] + inc + math.sqrt(max(inc, 0.0)) * np.float64(zs[x]), qtop)
    else:
        for x in range(m):
            q[x] = min(q[x] + cur[x] * dt, qtop)


@_njit(nogil=True)
def _sample(m, q, zr, off, sv, k, black, half, lo, top, quant, y, y0, sat, satlev, first):
    """Read, offset and ADC of every pixel of the block: ``y`` (e⁻ at mid-step) and ``sat`` (at the ADC's top or,
    less the reset ``y0``, at ``satlev``).  ``first``: the reset sample (into ``y0``).  ``lo``/``top``: the ADC's
    clip (±inf without clipping)."""
    for x in range(m):
        dn = (max(q[x], 0.0) + np.float64(zr[x]) * sv + off[x]) * k + black
        dn = math.floor(dn) if quant else dn
        dn = min(max(dn, lo), top)
        y[x] = (dn - black + half) / k
        sat[x] = dn >= top
    if first:
        y0[:m] = y[:m]
    for x in range(m):
        sat[x] = sat[x] | (y[x] - y0[x] >= satlev)


@_njit(nogil=True)
def _estimate(m, s, dt, tk, y, y0, sat, qh, ih, pqq, pqi, pii, act, sigma2, thr2, wls):
    """Sample ``s`` (> 0) into the recursive estimate, branch free (see ``readout.estimate_current``)."""
    for x in range(m):
        d, st, a = y[x] - y0[x], sat[x], act[x]
        if s == 1:  # the first difference starts the estimate (also where it saturates: the most encodable)
            i1 = d / dt
            qq = max(i1, 0.0)
            qh[x], ih[x], pqq[x], pqi[x] = y[x], i1, sigma2, sigma2 / dt
            pii[x] = (qq * dt + 2.0 * sigma2) / (dt * dt)
            act[x] = 0.0 if st else a
        elif not wls:
            live = (a != 0.0) & (not st)
            ih[x] = d / tk if live else ih[x]
            act[x] = a if live else 0.0
        else:
            qq = max(ih[x], 0.0)
            mqq = pqq[x] + 2.0 * dt * pqi[x] + dt * dt * pii[x] + qq * dt
            mqi = pqi[x] + dt * pii[x]
            pred = qh[x] + dt * ih[x]
            nu = y[x] - pred
            sv = mqq + sigma2
            kq, ki = mqq / sv, mqi / sv
            live = (a != 0.0) & (not st) & (not ((thr2 > 0.0) & (nu * nu > thr2 * sv)))
            qh[x] = pred + kq * nu if live else qh[x]
            ih[x] = ih[x] + ki * nu if live else ih[x]
            pqq[x] = mqq * (1.0 - kq) if live else pqq[x]
            pqi[x] = mqi * (1.0 - kq) if live else pqi[x]
            pii[x] = pii[x] - ki * mqi if live else pii[x]
            act[x] = a if live else 0.0


@_njit(nogil=True)
def mc_kernel(start, stop, rate, gains, dgains, offs, k0, k1, n_s, time_s, dark_rate, dark_e, qmax, sv, k,
              black, half, top, satlev, sigma2, thr2, kout, out_black, out_top, shot, use_poisson, clip, quant, wls,
              out_dn, out_mean):
    """Pixels ``[start, stop)``: ``out_dn`` the merged output word (before companding), ``out_mean`` the
    expected charge.  gains/dgains/offs: per-pixel arrays, or one value (size 1) for every pixel."""
    dt = time_s / n_s
    kp0 = k0 ^ np.uint64(POISSON_KEY_XOR)
    t32, d32, r32 = np.float32(time_s), np.float32(dark_e), np.float32(dark_rate)
    inf = np.inf
    qtop, lo, hi = (qmax, 0.0, top) if clip else (inf, -inf, inf)
    satl = satlev if clip else inf
    cur, q, y0, y, off = np.empty(BLOCK), np.empty(BLOCK), np.empty(BLOCK), np.empty(BLOCK), np.empty(BLOCK)
    qh, ih, pqq, pqi, pii, act = (np.empty(BLOCK), np.empty(BLOCK), np.empty(BLOCK), np.empty(BLOCK),
                                  np.empty(BLOCK), np.empty(BLOCK))
    z = np.empty((4, BLOCK), np.float32)
    sat = np.empty(BLOCK, np.bool_)
    for a in range(start, stop, BLOCK):
        m = min(BLOCK, stop - a)
        for x in range(m):
            g = gains[a + x] if gains.size > 1 else gains[0]
            dg = dgains[a + x] if dgains.size > 1 else dgains[0]
            off[x] = offs[a + x] if offs.size > 1 else offs[0]
            out_mean[a + x] = (rate[a + x] * t32) * g + d32 * dg
            cur[x] = np.float64(rate[a + x] * g + r32 * dg)
            q[x], act[x], ih[x] = 0.0, 1.0, 0.0
        for s in range(n_s + 1):
            if s % 2 == 0:
                _draw(a, m, s, k0, k1, z[0], z[1], z[2], z[3])
            zs, zr = (z[0], z[1]) if s % 2 == 0 else (z[2], z[3])
            if s > 0:
                _grow(a, m, s, n_s, dt, cur, q, zs, qtop, shot, use_poisson, kp0, k1)
            _sample(m, q, zr, off, sv, k, black, half, lo, hi, quant, y, y0, sat, satl, s == 0)
            if s > 0:
                _estimate(m, s, dt, s * dt, y, y0, sat, qh, ih, pqq, pqi, pii, act, sigma2, thr2, wls)
        for x in range(m):
            o = ih[x] * time_s * kout + out_black
            o = math.floor(o + 0.5) if quant else o
            out_dn[a + x] = np.float32(min(max(o, lo), out_top if clip else inf))
