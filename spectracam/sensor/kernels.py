"""The fused capture: radiance cube → digital numbers in one pass per frame (issue 10, "Speed").

:func:`record` reads each pixel's spectrum once and, in the same loop, weights it with the channel
its site records (the ``(bands, 3)`` matrix of :func:`~spectracam.camera.band_weights`: the CFA or
plane selection costs nothing), integrates the charge (PRNU gain, dark current × DSNU), adds shot
noise (Gaussian, variance = mean, or Poisson), clips to the well, adds read noise and the offset
FPN (pixel + column), and runs the ADC with its clip — exactly the model of :mod:`spectracam.sensor`,
whose NumPy steps (:func:`~spectracam.sensor.expose`) stay the reference implementation.  The
per-pixel parts of the fixed pattern are drawn in the same pass (the values
:func:`~spectracam.sensor.fixed_pattern` would draw), so a 12-Mpx frame allocates only its two
outputs.  Prism and field-sequential frames are recorded together: the cube is read once for three.

The kernels (``_numba_kernels``) are compiled by numba, cached on disk (a few seconds, once per
machine), release the GIL and run on bands of rows on ``SPECTRACAM_THREADS`` threads (default: all
cores).  Without numba, where it cannot compile, or with ``SPECTRACAM_FUSED=0``, :func:`record`
returns ``None`` and the architectures take the NumPy path.  Why numba rather than drjit's LLVM
backend (measured on the 2-core development machine, 4000×3000×30 cube): drjit maps the NumPy cube
without a copy and draws its Philox normals fast (12 M in 0.03 s), but it can read the
pixel-interleaved spectra only by gathers — 30 per pixel, 0.31 s for the weighting alone, 0.56 s
for a fused capture — while numba's contiguous 16-lane loads bring the whole capture to ~0.13 s;
and a wrong libLLVM aborts a drjit process, so it would need a subprocess probe first.

Random numbers are counter based: value ``i`` of a stream is Philox4x32-10 of the counter ``i``
under a 64-bit key drawn from the stream's :class:`numpy.random.SeedSequence`, so one seed fixes
every value whatever the number of threads or the order of the work.  Normals are Box–Muller on
24-bit uniforms (float32; |z| ≤ 5.77, a tail of probability 8e-9 left out).  :class:`CounterRNG`
hands the same numbers to :func:`~spectracam.sensor.fixed_pattern`; without numba its NumPy twin
(:func:`philox_np`, :func:`normal_pair_np`) computes bit-identical values.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from spectracam.core.parallel import pool as _pool  # noqa: F401  (the pool, for the read-out's kernels)
from spectracam.core.parallel import fused_enabled, run_bands, threads

if TYPE_CHECKING:
    from collections.abc import Sequence

    from numpy.typing import ArrayLike, DTypeLike

    from spectracam.sensor import FixedPattern, PatternRef, SensorSpec

__all__ = ["LANES", "CounterRNG", "SpectralRates", "available", "expose", "normal_pair_np", "philox_np",
           "record", "stream_key", "threads", "uniform_np"]

#: Bands weighted per SIMD instruction; the weight rows are padded to a multiple of it.
LANES = 16
_STATE: dict = {}


def _numba():
    """The numba kernels module, or None (numba missing, broken, or ``SPECTRACAM_FUSED=0``)."""
    if not fused_enabled():
        return None
    if "module" not in _STATE:
        try:
            from spectracam.sensor import _numba_kernels as mod
        except Exception:  # no numba, or one that does not load: the NumPy path
            mod = None
        _STATE["module"] = mod
    return _STATE["module"]


def available() -> bool:
    """Will :func:`record` run the fused kernels (rather than return None)?"""
    return _numba() is not None


def _run(kernel: str, n: int, args_for) -> bool:
    """Run numba kernel ``kernel(*args_for(start, stop))`` over ``[0, n)`` split into one band per
    thread (the kernels release the GIL); False if the backend cannot run here — it is then switched
    off for the process and the caller takes the NumPy path.  Bands only decide who computes what:
    every value depends on its index alone."""
    mod = _numba()
    if mod is None:
        return False
    try:
        run_bands(getattr(mod, kernel), n, args_for)
    except Exception as e:
        try:
            from numba.core.errors import NumbaError
        except Exception:  # noqa: BLE001 - a numba too broken to import its errors cannot compile either
            NumbaError = Exception  # noqa: N806
        import traceback

        in_backend = any(("/numba/" in f.filename or "/llvmlite/" in f.filename)
                         for f in traceback.extract_tb(e.__traceback__))
        if not (isinstance(e, NumbaError) or in_backend):
            raise  # a fault of the data or a bug: never hidden by a silent switch to the other path
        # numba or llvmlite cannot compile or run the kernel here (an unsupported target): the NumPy path, said once
        _STATE["module"] = None
        import sys

        sys.stderr.write(f"spectracam: the fused sensor kernels do not compile here ({type(e).__name__}: "
                         f"{(str(e).splitlines() or [''])[0][:120]}); using the NumPy path (same numbers, slower)\n")
        return False
    return True


# ------------------------------------------------------------------ counter-based random numbers
_M0, _M1 = np.uint64(0xD2511F53), np.uint64(0xCD9E8D57)
_W0, _W1 = np.uint64(0x9E3779B9), np.uint64(0xBB67AE85)


def stream_key(seq: np.random.SeedSequence) -> tuple[int, int]:
    """The 64-bit Philox key (two 32-bit words) of a seed sequence.

    Parameters
    ----------
    seq : numpy.random.SeedSequence
        The stream's seed sequence.

    Returns
    -------
    tuple of int
        The key's two 32-bit words, its first two generated uint32 values.
    """
    k = seq.generate_state(2, np.uint32)
    return int(k[0]), int(k[1])


def philox_np(index: np.ndarray, key: tuple[int, int], draw: int = 0
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Philox4x32-10 of counters ``(index low, index high, draw, 0)`` in NumPy: four uint32 arrays.

    Parameters
    ----------
    index : ndarray
        The values' indices (64-bit counters; a pixel's index in the frame).
    key : tuple of int
        The stream's key (:func:`stream_key`).
    draw : int
        The third counter word: a further draw of the same indices (0: the first four words of each).

    Returns
    -------
    tuple of ndarray
        The four uint32 words of each counter, each the shape of ``index``.
    """
    i = np.asarray(index, np.uint64)
    c0, c1 = i.astype(np.uint32), (i >> np.uint64(32)).astype(np.uint32)  # astype keeps the low word
    c2, c3 = np.full(i.shape, draw, np.uint32), np.zeros(i.shape, np.uint32)
    p = np.empty(i.shape, np.uint64)
    k0, k1 = int(key[0]), int(key[1])
    for r in range(10):
        if r:
            k0, k1 = (k0 + int(_W0)) & 0xFFFFFFFF, (k1 + int(_W1)) & 0xFFFFFFFF
        np.multiply(c0, _M0, out=p, dtype=np.uint64)
        lo0 = p.astype(np.uint32)
        hi0 = np.right_shift(p, np.uint64(32), out=p).astype(np.uint32)
        np.multiply(c2, _M1, out=p, dtype=np.uint64)
        lo1 = p.astype(np.uint32)
        hi1 = np.right_shift(p, np.uint64(32), out=p).astype(np.uint32)
        hi1 ^= c1
        hi1 ^= np.uint32(k0)
        hi0 ^= c3
        hi0 ^= np.uint32(k1)
        c0, c1, c2, c3 = hi1, lo1, hi0, lo0
    return c0, c1, c2, c3


_F = np.float32
_LOGP = [_F(c) for c in (7.0376836292e-2, -1.1514610310e-1, 1.1676998740e-1, -1.2420140846e-1, 1.4249322787e-1,
                         -1.6668057665e-1, 2.0000714765e-1, -2.4999993993e-1, 3.3333331174e-1)]


def _logf_np(x):
    b = x.view(np.int32)
    e = ((b >> 23) - 126).astype(np.float32)
    m = ((b & 0x7FFFFF) | 0x3F000000).astype(np.int32).view(np.float32)
    small = m < _F(0.707106781186547524)
    e = np.where(small, e - _F(1), e)
    m = np.where(small, m + m - _F(1), m - _F(1))
    z = m * m
    y = np.full_like(m, _LOGP[0])
    for c in _LOGP[1:]:
        y = y * m + c
    y = y * m * z
    y = y + _F(-2.12194440e-4) * e
    y = y - _F(0.5) * z
    return m + y + _F(0.693359375) * e


def _sincos2pi_np(v):
    t = v * _F(4) + _F(0.5)
    qf = np.floor(t)
    x = (t - qf - _F(0.5)) * _F(np.pi / 2)
    q = qf.astype(np.int32)
    z = x * x
    s = ((_F(-1.9515295891e-4) * z + _F(8.3321608736e-3)) * z + _F(-1.6666654611e-1)) * z * x + x
    c = ((_F(2.443315711809948e-5) * z + _F(-1.388731625493765e-3)) * z + _F(4.166664568298827e-2)) * z * z \
        - _F(0.5) * z + _F(1)
    swap = (q & 1) != 0
    sn, cs = np.where(swap, c, s), np.where(swap, s, c)
    return np.where((q & 2) != 0, -sn, sn), np.where(((q + 1) & 2) != 0, -cs, cs)


def uniform_np(a: ArrayLike) -> np.ndarray:
    """[0, 1) float32 from 32-bit words: ``(a >> 8)·2⁻²⁴``.

    Parameters
    ----------
    a : array_like
        uint32 words (from :func:`philox_np`).

    Returns
    -------
    ndarray
        float32 uniform values on [0, 1), multiples of 2⁻²⁴, the shape of ``a``.
    """
    return (np.asarray(a, np.uint32) >> 8).astype(np.int32).astype(np.float32) * _F(2.0**-24)


def normal_pair_np(a0: ArrayLike, a1: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Box–Muller on two words, as the kernels compute it (bit-identical).

    Parameters
    ----------
    a0 : array_like
        uint32 words giving the radius (a uniform on (0, 1], 24 bits).
    a1 : array_like
        uint32 words giving the angle (a uniform on [0, 1), 24 bits).

    Returns
    -------
    tuple of ndarray
        Two float32 standard normals per pair of words, ``r·cos`` and ``r·sin``.
    """
    u = ((np.asarray(a0, np.uint32) >> 8).astype(np.int32) + 1).astype(np.float32) * _F(2.0**-24)
    r = np.sqrt(_F(-2) * _logf_np(u))
    s, c = _sincos2pi_np(uniform_np(a1))
    return r * c, r * s


class CounterRNG:
    """A NumPy-Generator-like source whose value ``i`` depends only on (seed sequence, ``start + i``).

    ``standard_normal`` and ``random`` (float32, ``out=``) are counter based — numba's parallel kernel
    when available, else the bit-identical NumPy twin; any other method is a
    :class:`numpy.random.Generator` seeded from the same sequence (for plug-in FPN readings).

    Parameters
    ----------
    seq : numpy.random.SeedSequence
        The stream; its key is :func:`stream_key` of it.
    start : int
        The counter of this source's value 0 (a chunk's first pixel in the frame).
    """

    def __init__(self, seq: np.random.SeedSequence, start: int = 0):
        self.seq, self.start, self.key = seq, int(start), stream_key(seq)
        self._gen = None

    def _fill(self, out, size, dtype, normal: bool):
        if out is None:
            out = np.empty(size if size is not None else (), dtype=dtype)
        flat = out.reshape(-1) if out.flags.c_contiguous and out.dtype == np.float32 else None
        k0, k1 = np.uint64(self.key[0]), np.uint64(self.key[1])
        if flat is None or not _run("fill_kernel", flat.size,
                                    lambda a, b: (flat[a:b], np.int64(self.start + a), k0, k1, normal)):
            a0, a1, _, _ = philox_np(np.arange(self.start, self.start + out.size, dtype=np.uint64), self.key)
            out[...] = (normal_pair_np(a0, a1)[0] if normal else uniform_np(a0)).reshape(out.shape)
        return out

    def standard_normal(self, size: int | tuple[int, ...] | None = None, dtype: DTypeLike = np.float64,
                        out: np.ndarray | None = None) -> np.ndarray:
        """Standard normals, value ``i`` from counter ``start + i`` (Box–Muller on 24-bit uniforms, float32).

        Parameters
        ----------
        size : int or tuple of int or None
            The shape of a new array (when ``out`` is None).
        dtype : data-type
            Its type; the values are float32 numbers whatever it is.
        out : ndarray or None
            Filled in place where given (the parallel kernel runs on a C-contiguous float32 one).

        Returns
        -------
        ndarray
            ``out``, or the new array.
        """
        return self._fill(out, size, dtype, True)

    def random(self, size: int | tuple[int, ...] | None = None, dtype: DTypeLike = np.float64,
               out: np.ndarray | None = None) -> np.ndarray:
        """Uniforms on [0, 1), value ``i`` from counter ``start + i`` (24 bits, float32).

        Parameters
        ----------
        size : int or tuple of int or None
            The shape of a new array (when ``out`` is None).
        dtype : data-type
            Its type; the values are float32 numbers whatever it is.
        out : ndarray or None
            Filled in place where given (the parallel kernel runs on a C-contiguous float32 one).

        Returns
        -------
        ndarray
            ``out``, or the new array.
        """
        return self._fill(out, size, dtype, False)

    def __getattr__(self, name):
        if self._gen is None:
            self._gen = np.random.default_rng(self.seq)
        return getattr(self._gen, name)


# ------------------------------------------------------------------ spectral rates, not yet computed
class SpectralRates:
    """Photo-electron rates ``(H, W, 3)`` of a radiance cube, ``radiance @ weights``, not computed:
    the fused path reads the cube itself.  Anything that indexes it or asks for an array gets the
    rates computed once (as :func:`~spectracam.camera.photo_electron_rates` does), so an
    architecture written for arrays keeps working.

    Parameters
    ----------
    radiance : ndarray
        The radiance cube ``(H, W, B)``, W·m⁻²·sr⁻¹·nm⁻¹.
    weights : ndarray
        ``(B, N)`` band weights (:func:`~spectracam.camera.band_weights`), one column per channel: e⁻/s per pixel
        per W·m⁻²·sr⁻¹·nm⁻¹ of each band; kept as float32.
    """

    def __init__(self, radiance: np.ndarray, weights: np.ndarray):
        self.radiance, self.weights = radiance, np.asarray(weights, np.float32)
        self._rates = None

    @property
    def shape(self) -> tuple[int, ...]:
        return (*self.radiance.shape[:-1], self.weights.shape[1])

    ndim = property(lambda self: len(self.shape))
    dtype = np.dtype(np.float32)

    def compute(self) -> np.ndarray:
        if self._rates is None:
            r = self.radiance
            self._rates = (r.reshape(-1, r.shape[-1]) @ self.weights).reshape(self.shape)
        return self._rates

    def mean(self, rows: slice, cols: slice) -> np.ndarray:
        """The mean rates ``(3,)`` of a box of pixels (for metering), float64, without computing the
        rest: the box's mean spectrum times the weights (the rates are linear in the radiance).

        Parameters
        ----------
        rows : slice
            The box's rows.
        cols : slice
            The box's columns.

        Returns
        -------
        ndarray
            The mean photo-electron rate of each channel, e⁻/s, float64.
        """
        box = self.radiance[rows, cols]
        return box.mean(axis=tuple(range(box.ndim - 1)), dtype=np.float64) @ self.weights.astype(np.float64)

    def __array__(self, dtype=None, copy=None):
        return self.compute() if dtype is None else self.compute().astype(dtype)

    def __getitem__(self, index):
        return self.compute()[index]


# ------------------------------------------------------------------ the fused sensor
#: How the kernel draws a per-pixel part of a fixed pattern (sensor.PixelDraw.kind → mode).
_DRAW_KINDS = {"offset": 1, "offset-bound": 2, "gain": 1, "dark_gain": 1}

def _source(rates):
    """(flat float32 spectra, bands, padded weights, weight stride, H, W) of rates — a
    :class:`SpectralRates` reads its cube; an ``(H, W, C)`` or ``(H, W)`` array is its own "cube"
    with identity weights (exact: ×1 and +0)."""
    if isinstance(rates, SpectralRates) and rates._rates is None:
        cube, weights = rates.radiance, rates.weights
    else:
        cube = np.asarray(rates, np.float32)
        if cube.ndim == 2:
            cube = cube[:, :, None]
        if cube.ndim != 3:
            return None
        weights = np.eye(cube.shape[2], dtype=np.float32)
    if cube.dtype != np.float32 or not cube.flags.c_contiguous:
        cube = np.ascontiguousarray(cube, np.float32)
    h, w, b = cube.shape
    stride = -(-b // LANES) * LANES
    wpad = np.zeros((weights.shape[1], stride), np.float32)
    wpad[:, :b] = weights.T
    return cube.reshape(-1), b, wpad.reshape(-1), stride, h, w


def record(rates: SpectralRates | np.ndarray, channels: np.ndarray, times_s: Sequence[float] | np.ndarray,
           sensor: SensorSpec, noises: Sequence[np.random.SeedSequence],
           patterns: Sequence[FixedPattern | PatternRef]) -> tuple[np.ndarray, np.ndarray] | None:
    """Outputs ``j`` = 0…J−1 of one pass: output ``j`` records, at tile site ``(y mod th, x mod tw)``,
    channel ``channels[j, …]`` of ``rates`` for ``times_s[j]`` seconds with temporal noise from seed
    sequence ``noises[j]`` and fixed pattern ``patterns[j]``.  Returns ``(digital, expected_e)``,
    each ``(J, H, W)`` float32 — what :func:`~spectracam.sensor.expose` gives for each output — or
    None when the fused backend is not available.

    Parameters
    ----------
    rates : SpectralRates or ndarray
        The radiance cube with its band weights (read in the pass), or photo-electron rates ``(H, W, C)`` or
        ``(H, W)``, e⁻/s.
    channels : ndarray
        ``(J, th, tw)`` int: the channel each tile site of output ``j`` records; J is at most 3.
    times_s : sequence of float
        Exposure time of each output, s.
    sensor : SensorSpec
        The sensor.
    noises : sequence of numpy.random.SeedSequence
        Each output's temporal noise.
    patterns : sequence of FixedPattern or PatternRef
        Each output's fixed pattern, drawn or (a :class:`~spectracam.sensor.PatternRef`) with its per-pixel parts
        drawn in the pass.

    Returns
    -------
    tuple of ndarray or None
        Digital numbers (DN) and expected electrons (the noise-free charge, e⁻), each ``(J, H, W)`` float32; None
        without the fused backend, or for rates or channels it does not take.
    """
    if _numba() is None:
        return None
    src = _source(rates)
    if src is None:
        return None
    cube, nbands, wpad, stride, h, w = src
    channels = np.ascontiguousarray(channels, np.int64)
    j = channels.shape[0]
    if j > 3 or channels.min() < 0 or channels.max() >= wpad.size // stride:
        return None
    times = np.asarray(times_s, np.float64)[:j]
    darks = np.array([np.float32(sensor.dark_rate_e_per_s * t) for t in times], np.float32)
    offs, gains, dgains, draw_mode, draw_keys, draw_scale = _pattern_args(patterns, j, h, w)
    keys = np.array([stream_key(s) for s in noises[:j]], np.uint32)
    fs = 2**sensor.adc_bits - 1 if sensor.quantization else 2**sensor.adc_bits
    dn = np.empty((j, h, w), np.float32)
    mean = np.empty((j, h, w), np.float32)
    sigma = sensor.read_noise_rms_e
    args = (cube, np.int64(nbands), wpad, np.int64(stride), channels, times.astype(np.float32), darks, offs, gains,
            dgains, keys, draw_mode, draw_keys, draw_scale, np.float32(sensor.q_max_e), np.float32(sigma),
            np.float32(sensor.system_gain_dn_per_e), np.float32(sensor.black_level_dn), np.float32(fs),
            bool(sensor.shot_noise), sensor.shot_noise_model == "poisson", bool(sensor.clipping),
            bool(sensor.quantization), dn, mean)
    ok = _run("capture_kernel", h, lambda a, b: (np.int64(a), np.int64(b), *args))
    return (dn, mean) if ok else None


def _pattern_args(patterns, j: int, h: int, w: int) -> tuple:
    """The fixed-pattern arguments of the capture kernel for outputs 0…j−1 (:func:`record`): the offset, gain and
    dark-gain planes (three each, writable C float32; a row for a row broadcast, a dummy row of 0 or 1 where
    absent) and, per output and part, how the kernel draws it (0: it does not), its key and its scale."""
    zeros, ones = np.zeros((1, w), np.float32), np.ones((1, w), np.float32)

    def plane(a, dummy):  # writable C float32 (a read-only array would compile another kernel)
        if a is None:
            return dummy
        a = np.asarray(a)
        if a.shape != (h, w):
            a = np.broadcast_to(a, (h, w))
        if a.strides[0] == 0:  # a row broadcast to the image: the row
            a = a[:1]
        ok = a.dtype == np.float32 and a.flags.c_contiguous and a.flags.writeable
        return a if ok else np.array(a, np.float32, order="C")

    parts, seen = [], {}
    for p in patterns[:j]:  # a pattern, or a reference to one whose per-pixel parts are drawn in the pass
        if id(p) not in seen:
            seen[id(p)] = p.parts() if callable(getattr(p, "parts", None)) else (p, (None, None, None))
        parts.append(seen[id(p)])
    offs = tuple(plane(parts[min(k, j - 1)][0].offset_e, zeros) for k in range(3))
    gains = tuple(plane(parts[min(k, j - 1)][0].gain, ones) for k in range(3))
    dgains = tuple(plane(parts[min(k, j - 1)][0].dark_gain, ones) for k in range(3))
    # per output and part (offset, gain, dark gain): how the kernel draws it (0: it does not), key, scale
    draws = [[d for d in dr] for _, dr in parts]
    draw_mode = np.array([[0 if d is None else _DRAW_KINDS[d.kind] for d in dr] for dr in draws], np.int64)
    draw_keys = np.array([[(0, 0) if d is None else stream_key(d.seq) for d in dr] for dr in draws], np.uint32)
    draw_scale = np.array([[0.0 if d is None else d.scale for d in dr] for dr in draws], np.float32)
    return offs, gains, dgains, draw_mode, draw_keys, draw_scale


def expose(photo_rate_e_per_s: np.ndarray, time_s: float, sensor: SensorSpec, noise: np.random.SeedSequence,
           pattern: FixedPattern) -> tuple[np.ndarray, np.ndarray] | None:
    """The fused twin of :func:`spectracam.sensor.expose` on given rates ``(H, W)`` (or any shape),
    or None without the fused backend.  With no noise source on, bit-identical to it.

    Parameters
    ----------
    photo_rate_e_per_s : ndarray
        Photo-electrons per second per pixel, any shape.
    time_s : float
        Exposure time, s.
    sensor : SensorSpec
        The sensor.
    noise : numpy.random.SeedSequence
        Seeds this frame's temporal noise.
    pattern : FixedPattern
        The fixed pattern ``(offset_e, gain, dark_gain)``, drawn (each an array of the rates' size, or None).

    Returns
    -------
    tuple of ndarray or None
        Digital numbers (DN) and expected electrons (e⁻), float32, the rates' shape; None without the fused
        backend.
    """
    rate = np.asarray(photo_rate_e_per_s, np.float32)
    shape = rate.shape
    r2 = rate.reshape(shape if rate.ndim == 2 else (1, -1))

    def flat(a):
        return None if a is None else np.asarray(a, np.float32).reshape(r2.shape)

    p = type(pattern)(*(flat(a) for a in pattern))
    out = record(r2, np.zeros((1, 1, 1), np.int64), [time_s], sensor, [noise], [p])
    return None if out is None else (out[0][0].reshape(shape), out[1][0].reshape(shape))
