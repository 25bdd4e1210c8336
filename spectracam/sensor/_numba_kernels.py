"""Numba kernels of :mod:`spectracam.sensor.kernels` (imported on first use; needs numba).

One pass per frame: for each image row the cube's spectra are read once and weighted with SIMD
loads (:func:`_dot`, an LLVM intrinsic: 16 bands per instruction), then one vectorised loop draws
the counter-based noise and runs the sensor model to digital numbers.  The kernels release the GIL;
:mod:`spectracam.sensor.kernels` runs them on bands of rows on a thread pool.  Every random number is a
function of (key, pixel index, draw): the output does not depend on the number of threads.

The random numbers: Philox4x32-10 (Salmon et al., SC'11) keyed by 64 bits of the frame's seed
sequence, counter ``(pixel index low, high, draw, 0)``; Box–Muller on 24-bit uniforms with Cephes
polynomials for log, sin and cos (float32, no library calls, so the loop vectorises).  The same
arithmetic in NumPy (``kernels.philox_np``, ``kernels.normal_pair_np``) gives bit-identical values.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np
from llvmlite import ir
from numba.core import cgutils, types
from numba.extending import intrinsic

from spectracam.core.parallel import njit_cached as _njit

LANES = 16
_F32 = ir.FloatType()
_I32 = ir.IntType(32)
_I64 = ir.IntType(64)
_VF = ir.VectorType(_F32, LANES)


@intrinsic
def _dot(typingctx, a, abase, w, wbase, nbands):
    """``Σ_{j < nbands} a[abase + j]·w[wbase + j]`` in float32, 16 lanes at a time: per block of 16
    bands two vector loads, the lanes past ``nbands`` set to 0 by a select (not a multiply, which
    would turn a neighbour's inf into NaN), a multiply and an add into one accumulator; then one
    fixed pairwise tree (8+8, 4+4, 2+2, 1+1).  Reads whole blocks of 16 from both arrays: the
    caller keeps them in bounds (``w`` padded with zeros to a multiple of 16)."""
    sig = types.float32(a, abase, w, wbase, nbands)

    def codegen(context, builder, signature, args):
        arr_a = context.make_array(signature.args[0])(context, builder, args[0])
        arr_w = context.make_array(signature.args[2])(context, builder, args[2])
        pa = builder.gep(arr_a.data, [args[1]], source_etype=_F32)
        pw = builder.gep(arr_w.data, [args[3]], source_etype=_F32)
        n = args[4] if args[4].type == _I64 else builder.sext(args[4], _I64)
        nblk = builder.sdiv(builder.add(n, ir.Constant(_I64, LANES - 1)), ir.Constant(_I64, LANES))
        lanes = ir.Constant(ir.VectorType(_I64, LANES), [ir.Constant(_I64, j) for j in range(LANES)])
        zero = ir.Constant(_VF, [0.0] * LANES)
        acc = cgutils.alloca_once_value(builder, zero)
        with cgutils.for_range(builder, nblk) as loop:
            off = builder.mul(loop.index, ir.Constant(_I64, LANES))
            va = builder.load(builder.gep(pa, [off], source_etype=_F32), typ=_VF, align=4)
            vw = builder.load(builder.gep(pw, [off], source_etype=_F32), typ=_VF, align=4)
            left = builder.sub(n, off)
            nv = builder.insert_element(ir.Constant(ir.VectorType(_I64, LANES), ir.Undefined), left,
                                        ir.Constant(_I32, 0))
            nv = builder.shuffle_vector(nv, nv, ir.Constant(ir.VectorType(_I32, LANES), [0] * LANES))
            va = builder.select(builder.icmp_signed("<", lanes, nv), va, zero)
            builder.store(builder.fadd(builder.load(acc), builder.fmul(va, vw)), acc)
        v, width = builder.load(acc), LANES
        while width > 1:
            half = width // 2
            lo = builder.shuffle_vector(v, v, ir.Constant(ir.VectorType(_I32, half), list(range(half))))
            hi = builder.shuffle_vector(v, v, ir.Constant(ir.VectorType(_I32, half), list(range(half, width))))
            v, width = builder.fadd(lo, hi), half
        return builder.extract_element(v, ir.Constant(_I32, 0))

    return sig, codegen


@intrinsic
def _f32_bits(typingctx, x):
    sig = types.int32(types.float32)
    return sig, lambda context, builder, signature, args: builder.bitcast(args[0], _I32)


@intrinsic
def _bits_f32(typingctx, x):
    sig = types.float32(types.int32)
    return sig, lambda context, builder, signature, args: builder.bitcast(args[0], _F32)


# --- Philox4x32-10 on uint64 lanes holding 32-bit words (the products are 32x32 -> 64 bits) ---
_M0, _M1 = np.uint64(0xD2511F53), np.uint64(0xCD9E8D57)
_W0, _W1 = np.uint64(0x9E3779B9), np.uint64(0xBB67AE85)
_MASK, _S32, _S8 = np.uint64(0xFFFFFFFF), np.uint64(32), np.uint64(8)


@nb.njit(inline="always")
def _philox_round(c0, c1, c2, c3, k0, k1):
    """One Philox4x32 round: two 32x32 -> 64-bit products, their halves mixed with the other words and the key."""
    p0, p1 = _M0 * c0, _M1 * c2
    return ((p1 >> _S32) ^ c1 ^ k0) & _MASK, p1 & _MASK, ((p0 >> _S32) ^ c3 ^ k1) & _MASK, p0 & _MASK


@nb.njit(inline="always")
def philox(c0, c1, c2, c3, k0, k1):
    """Philox4x32-10 of counter (c0..c3) under key (k0, k1); the fixed-count loop is unrolled by the
    compiler, so loops over it vectorise."""
    for _ in range(9):
        c0, c1, c2, c3 = _philox_round(c0, c1, c2, c3, k0, k1)
        k0, k1 = (k0 + _W0) & _MASK, (k1 + _W1) & _MASK
    return _philox_round(c0, c1, c2, c3, k0, k1)


_F2M24 = np.float32(2.0**-24)
_ONE, _HALF, _ZERO = np.float32(1.0), np.float32(0.5), np.float32(0.0)
_SQRTHF = np.float32(0.707106781186547524)
_LN2_HI, _LN2_LO = np.float32(0.693359375), np.float32(-2.12194440e-4)
_LOGP = tuple(np.float32(c) for c in (7.0376836292e-2, -1.1514610310e-1, 1.1676998740e-1, -1.2420140846e-1,
                                      1.4249322787e-1, -1.6668057665e-1, 2.0000714765e-1, -2.4999993993e-1,
                                      3.3333331174e-1))
_PIO2 = np.float32(np.pi / 2)
_S1, _S2, _S3 = np.float32(-1.6666654611e-1), np.float32(8.3321608736e-3), np.float32(-1.9515295891e-4)
_C1, _C2, _C3 = np.float32(4.166664568298827e-2), np.float32(-1.388731625493765e-3), np.float32(2.443315711809948e-5)


@nb.njit(inline="always")
def uniform_open(u):
    """(0, 1]: ``(k + 1)·2⁻²⁴`` from the top 24 bits of a 32-bit word, exact in float32."""
    return np.float32(np.int32(u >> _S8) + 1) * _F2M24


@nb.njit(inline="always")
def uniform(u):
    """[0, 1): ``k·2⁻²⁴`` from the top 24 bits (NumPy's float32 convention)."""
    return np.float32(np.int32(u >> _S8)) * _F2M24


@nb.njit(inline="always")
def logf(x):
    """Natural log of a positive normal float32 (Cephes ``logf``, < 2 ulp)."""
    b = _f32_bits(x)
    e = np.float32((b >> 23) - 126)
    m = _bits_f32((b & 0x7FFFFF) | 0x3F000000)  # mantissa in [0.5, 1)
    small = m < _SQRTHF
    e = e - _ONE if small else e
    m = (m + m - _ONE) if small else (m - _ONE)
    z = m * m
    y = _LOGP[0]
    y = y * m + _LOGP[1]
    y = y * m + _LOGP[2]
    y = y * m + _LOGP[3]
    y = y * m + _LOGP[4]
    y = y * m + _LOGP[5]
    y = y * m + _LOGP[6]
    y = y * m + _LOGP[7]
    y = y * m + _LOGP[8]
    y = y * m * z
    y = y + _LN2_LO * e
    y = y - _HALF * z
    return m + y + _LN2_HI * e


@nb.njit(inline="always")
def sincos2pi(v):
    """sin and cos of 2πv for v in [0, 1): quadrant from 4v, Cephes polynomials on [-π/4, π/4)."""
    t = v * np.float32(4.0) + _HALF
    qf = np.floor(t)
    x = (t - qf - _HALF) * _PIO2
    q = np.int32(qf)
    z = x * x
    s = ((_S3 * z + _S2) * z + _S1) * z * x + x
    c = ((_C3 * z + _C2) * z + _C1) * z * z - _HALF * z + _ONE
    swap = (q & 1) != 0
    sn = c if swap else s
    cs = s if swap else c
    sn = -sn if (q & 2) != 0 else sn
    cs = -cs if ((q + 1) & 2) != 0 else cs
    return sn, cs


@nb.njit(inline="always")
def normal_pair(a0, a1):
    """Two independent standard normals (Box–Muller) from two 32-bit words; |z| ≤ 5.77."""
    r = np.float32(math.sqrt(np.float32(-2.0) * logf(uniform_open(a0))))
    s, c = sincos2pi(uniform(a1))
    return r * c, r * s


@nb.njit(inline="always")
def _u53(a, b):
    """[0, 1) double from two 32-bit words (53 bits)."""
    return (np.float64(a >> np.uint64(5)) * 67108864.0 + np.float64(b >> np.uint64(6))) * (1.0 / 9007199254740992.0)


@nb.njit
def poisson(lam, i, k0, k1):
    """A Poisson count of mean ``lam`` for pixel ``i``, from the counters (i, draw ≥ 1): NumPy's
    algorithms — multiplication for lam < 10, Hörmann's PTRS above."""
    if not lam > 0.0:
        return 0.0
    lo, hi = i & _MASK, i >> _S32
    draw = np.uint64(1)
    if lam < 10.0:
        enlam = math.exp(-lam)
        count, prod = 0.0, 1.0
        while True:
            a0, a1, a2, a3 = philox(lo, hi, draw, np.uint64(0), k0, k1)
            draw += np.uint64(1)
            for u in (_u53(a0, a1), _u53(a2, a3)):
                prod *= u
                if prod > enlam:
                    count += 1.0
                else:
                    return count
    slam, loglam = math.sqrt(lam), math.log(lam)
    b = 0.931 + 2.53 * slam
    a = -0.059 + 0.02483 * b
    invalpha = 1.1239 + 1.1328 / (b - 3.4)
    vr = 0.9277 - 3.6224 / (b - 2.0)
    while True:
        a0, a1, a2, a3 = philox(lo, hi, draw, np.uint64(0), k0, k1)
        draw += np.uint64(1)
        U = _u53(a0, a1) - 0.5
        V = _u53(a2, a3)
        us = 0.5 - abs(U)
        k = np.floor((2.0 * a / us + b) * U + lam + 0.43)
        if us >= 0.07 and V <= vr:
            return k
        if k < 0.0 or (us < 0.013 and V > us):
            continue
        accept = -lam + k * loglam - math.lgamma(k + 1.0)
        if math.log(V) + math.log(invalpha) - math.log(a / (us * us) + b) <= accept:
            return k


@nb.njit(inline="always")
def _words(i, k0, k1):
    """The four Philox words of pixel (or value) ``i``'s first draw: counter ``(i low, i high, 0, 0)``."""
    return philox(i & _MASK, i >> _S32, np.uint64(0), np.uint64(0), k0, k1)


#: What :func:`_pattern_row` draws (``sensor.fixed_pattern``'s per-pixel parts): an offset s·N plus the
#: column FPN (FPN reading "std"), an offset s·(U − ½) plus the column FPN ("bound"), a PRNU gain
#: 1 + s·N, a DSNU factor max(1 + s·N, 0).
_OFFSET, _OFFSET_BOUND, _GAIN, _DARK_GAIN = 0, 1, 2, 3


@nb.njit(inline="always")
def _pattern_row(buf, row0, key, scale, column, part):
    """``buf[x]`` = the fixed pattern's ``part`` (a constant at each call, so the loop keeps no branch
    and vectorises) of pixel ``row0 + x``, drawn from ``key``; ``column``: the column FPN the offsets
    add.  Returns ``buf``."""
    k0, k1 = np.uint64(key[0]), np.uint64(key[1])
    for x in range(buf.shape[0]):
        b0, b1, b2, b3 = _words(row0 + np.uint64(x), k0, k1)
        if part == _OFFSET_BOUND:
            buf[x] = (uniform(b0) - _HALF) * scale + column[x]
        elif part == _OFFSET:
            buf[x] = normal_pair(b0, b1)[0] * scale + column[x]
        elif part == _GAIN:
            buf[x] = normal_pair(b0, b1)[0] * scale + _ONE
        else:  # the DSNU factor, never negative
            buf[x] = max(normal_pair(b0, b1)[0] * scale + _ONE, _ZERO)
    return buf


@nb.njit(inline="always")
def _sensor_row(dn, mean, r, t, grow, dark, drow, orow, row0, k0, k1, shot, poisson_shot, clip, qmax, sigma_r,
                gain_k, black, quant, full_scale):
    """One row of one output: charge ``r·t·gain + dark·DSNU`` (into ``mean``), shot noise (Gaussian
    ``z0·√m``, or a Poisson count where ``poisson_shot``), the well, read noise ``z1·σ``, the offset,
    the ADC (into ``dn``).  ``poisson_shot`` is a constant at each call: the Gaussian loop has no calls
    and no branches the compiler cannot turn into selects, so it vectorises."""
    for x in range(dn.shape[0]):
        i = row0 + np.uint64(x)
        a0, a1, a2, a3 = _words(i, k0, k1)
        z0, z1 = normal_pair(a0, a1)
        m = r[x] * t
        m = m * grow[x]
        m = m + dark * drow[x]
        mean[x] = m
        if poisson_shot:
            q = np.float32(poisson(np.float64(m), i, k0, k1)) if shot else m
        else:
            q = z0 * np.float32(math.sqrt(m)) + m if shot else m
        if clip:
            q = min(max(q, _ZERO), qmax)
        q = q + z1 * sigma_r
        q = q + orow[x]
        q = q * gain_k + black
        if quant:
            q = np.floor(q)
        if clip:
            q = min(max(q, _ZERO), full_scale)
        dn[x] = q


@_njit(nogil=True)
def capture_kernel(y_start, y_stop, cube, nbands, wpad, wstride, chan, times, darks, offs, gains, dgains, keys,
                   draw_mode, draw_keys, draw_scale, qmax, sigma_r, gain_k, black, full_scale, shot, use_poisson, clip,
                   quant, out_dn, out_mean):
    """Rows ``[y_start, y_stop)`` of the image in one pass (each thread takes a band of rows).

    cube: flat float32 ``(pixels·nbands)``, pixel-interleaved; wpad: per channel ``c`` the weights at
    ``[c·wstride, c·wstride + nbands)``, zero to ``(c+1)·wstride`` (a multiple of 16); chan
    ``(J, th, tw)``: the channel output ``j`` records at each site of the tile; times, darks (J,):
    exposure s and dark electrons; offs/gains/dgains: 3-tuples (output j uses element j) of
    ``(H, W)`` patterns or ``(1, W)`` rows (0 / 1 / 1 where the sensor has none, or the column FPN);
    keys (J, 2): Philox keys of the temporal noise; draw_mode (J, 3), for the offset, the PRNU gain
    and the DSNU factor: 0 — it is in offs/gains/dgains, 1 — draw it here from key
    ``draw_keys[j, part]`` (offset s·N plus the column FPN in offs, gain 1 + s·N, DSNU
    max(1 + s·N, 0), s = ``draw_scale[j, part]``), 2 — an offset s·(U − ½) (FPN reading "bound"):
    exactly what ``sensor.fixed_pattern`` draws.  The other arguments are the sensor's float32
    constants and switches (``sensor.expose``'s steps); writes the rows of out_dn and out_mean
    ``(J, H, W)``.
    """
    J, H, W = out_dn.shape
    th, tw = chan.shape[1], chan.shape[2]
    total = cube.shape[0]
    nblk = (nbands + LANES - 1) // LANES
    rates = np.empty((J, W), np.float32)
    obuf = np.empty(W, np.float32)
    gbuf = np.empty(W, np.float32)
    dbuf = np.empty(W, np.float32)
    for y in range(y_start, y_stop):
        # 1. the spectra of this row, read once: each output's channel weights
        crow = chan[:, y % th, :]
        xt = 0
        for x in range(W):
            base = (y * W + x) * nbands
            fast = base + nblk * LANES <= total
            for j in range(J):
                kb = crow[j, xt] * wstride
                if fast:
                    rates[j, x] = _dot(cube, base, wpad, kb, nbands)
                else:  # the last pixels, whose 16-lane read would pass the end of the cube
                    acc = _ZERO
                    for b in range(nbands):
                        acc += cube[base + b] * wpad[kb + b]
                    rates[j, x] = acc
            xt += 1
            if xt == tw:
                xt = 0
        # 2. the sensor, per output: charge, noise, well, read noise, offset, ADC
        for j in range(J):
            t, dark = times[j], darks[j]
            k0, k1 = np.uint64(keys[j, 0]), np.uint64(keys[j, 1])
            off, g, dg = offs[j], gains[j], dgains[j]
            orow = off[y if off.shape[0] > 1 else np.int64(0)]
            grow = g[y if g.shape[0] > 1 else np.int64(0)]
            drow = dg[y if dg.shape[0] > 1 else np.int64(0)]
            row0 = np.uint64(y * W)
            # the fixed pattern's per-pixel parts drawn here, each in its own vectorised loop
            om = draw_mode[j, 0]
            if om == 1:  # offset, FPN reading "std", plus the column FPN in orow
                orow = _pattern_row(obuf, row0, draw_keys[j, 0], draw_scale[j, 0], orow, _OFFSET)
            elif om == 2:  # FPN reading "bound"
                orow = _pattern_row(obuf, row0, draw_keys[j, 0], draw_scale[j, 0], orow, _OFFSET_BOUND)
            if draw_mode[j, 1] == 1:  # PRNU gain
                grow = _pattern_row(gbuf, row0, draw_keys[j, 1], draw_scale[j, 1], orow, _GAIN)
            if draw_mode[j, 2] == 1:  # DSNU factor
                drow = _pattern_row(dbuf, row0, draw_keys[j, 2], draw_scale[j, 2], orow, _DARK_GAIN)
            dn, mean, r = out_dn[j, y], out_mean[j, y], rates[j]
            if use_poisson:
                _sensor_row(dn, mean, r, t, grow, dark, drow, orow, row0, k0, k1, shot, True, clip, qmax, sigma_r,
                            gain_k, black, quant, full_scale)
            else:
                _sensor_row(dn, mean, r, t, grow, dark, drow, orow, row0, k0, k1, shot, False, clip, qmax, sigma_r,
                            gain_k, black, quant, full_scale)


@_njit(nogil=True)
def fill_kernel(out, start, k0, k1, normal):
    """``out[i]`` = the standard normal (or [0, 1) uniform) of counter ``start + i`` under (k0, k1)."""
    if normal:
        for x in range(out.shape[0]):
            a0, a1, a2, a3 = _words(np.uint64(start + x), k0, k1)
            out[x] = normal_pair(a0, a1)[0]
    else:
        for x in range(out.shape[0]):
            a0, a1, a2, a3 = _words(np.uint64(start + x), k0, k1)
            out[x] = uniform(a0)
