"""The sensor's high-dynamic-range read-out schemes (issue 36): how a pixel's charge becomes one merged word.

The paper's sensor reads each pixel once, at the end of the exposure (``readout = "single"``: :func:`spectracam.
sensor.expose` and the fused kernel).  The schemes here read it more than once and merge the reads into one
estimate ``Q_est`` of the total charge (photo + dark) the pixel would have collected in ``time_s`` without a well —
so ``Q_est`` can exceed ``q_max``: that is the extended range.  Every raw read is digitised by the sensor's own
n-bit ADC (``DN = K·Q + black level``, floored, clipped to its codes; the quantisation and clipping switches
honoured) and the merge works on the digitised reads at mid-step, ``(DN − b + ½)/K``: the extended range is what
the real ADC can deliver, not what the charge was.

* ``multiple_capture`` [LiuElGamal2001]_, [LiuElGamal2003]_: N non-destructive samples at ``t_k = k·T/N`` after a
  reset sample at 0, the recursive weighted least-squares estimate of the photocurrent with saturation and motion
  detection (or the last unsaturated sample over its time).
* ``dual_gain``: one integration read at a high and a low conversion gain [Solhusvik2019]_.
* ``split_pixel``: a large and a small photodiode, ``split_ratio`` less sensitive [Solhusvik2019]_.
* ``bracketing``: ``bracketing_frames`` sequential exposures ``T, T/r, T/r², …`` [Debevec1997]_.

The merged word: ``digital = round(output_dn_per_e·Q_est + black level)`` (round half up, an integer code when the
sensor quantises, else continuous), clipped to ``[0, output_top_dn]``, and companded (:func:`compand`) when
``companding_bits`` is set.  :func:`decode` inverts it: electrons-equivalent at ``time_s``, photo + dark.

Fixed pattern (``pattern``: ``(offset_e, gain, dark_gain)`` arrays or None, as :class:`spectracam.sensor.
FixedPattern`): the PRNU gain multiplies the rate, the DSNU factor the dark current, and the offset (e⁻ at the
sensor's conversion gain) is added to every raw read, as in :func:`spectracam.sensor.expose`; a multiple capture
subtracts it with its reset sample (digital correlated double sampling), the others keep it, as a single read does.
This module does not import :mod:`spectracam.sensor` (its ``__init__`` imports this one): the sensor is taken by
its attributes.
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING, Callable, NamedTuple

import numpy as np

from spectracam.core.errors import SpectracamError
from spectracam.core.registry import Registry
from spectracam.sensor import kernels

if TYPE_CHECKING:
    from collections.abc import Sequence

    from numpy.typing import ArrayLike

    from spectracam.sensor import FixedPattern, SensorSpec

__all__ = ["AdcRead", "READOUTS", "ReadoutScheme", "SATURATION_MARGIN_SIGMA", "SWITCH_FRACTION", "adc_read",
           "compand", "companding_bound", "companding_curve", "decode", "estimate_current", "expand",
           "high_gain_read_noise_e", "multiple_capture_samples", "multiple_capture_variance", "output_black_dn",
           "output_dn_per_e", "output_top_dn", "read", "read_bracketing", "read_dual_gain", "read_multiple_capture",
           "read_split_pixel", "snr_curve"]

#: A multiple-capture sample counts as saturated when its read, less the reset read, is within this many σ of the
#: read difference (σ_V·√2, quantisation included) below the well or the ADC's top: a clipped sample reads the well
#: plus noise, so 4 σ misses one in 30 000, and an unclipped sample there is at most 4 σ of signal lost.
SATURATION_MARGIN_SIGMA = 4.0
#: ``split_pixel`` and ``bracketing`` use a read while it is below this fraction of its well (or ADC range): 10 %
#: below the well, which the read's own noise (σ ≈ √(0.9·q_max) = 340 e⁻ of 131 072) never crosses, so a clipped
#: read is never taken for a valid one.
SWITCH_FRACTION = 0.9


class ReadoutScheme(NamedTuple):
    """One read-out scheme: its read, its range and its time."""

    read: Callable  # (rate_e_per_s, time_s, sensor, noise, pattern) -> (digital float32, expected_e float32)
    headroom: Callable  # sensor -> largest rate it encodes over a single read's q_max/T
    capture_time_s: Callable  # (sensor, time_s) -> the time the read-out takes


class AdcRead(NamedTuple):
    """The digitisation of one read: ``k_dn_per_e`` DN per e⁻, black level, top code, mid-step (½ or 0), the
    range above the black level in e⁻, and the switches."""

    k_dn_per_e: float
    black_dn: float
    top_dn: float
    half: float
    range_e: float
    quant: bool
    clip: bool


def adc_read(sensor: SensorSpec, gain: float = 1.0) -> AdcRead:
    """The sensor's ADC for a read at ``gain`` × its system gain (a high conversion gain, a small photodiode).

    Parameters
    ----------
    sensor : SensorSpec
        The sensor (its ``system_gain_dn_per_e``, ``black_level_dn``, ``adc_bits``, switches).
    gain : float
        The read's conversion gain over the sensor's.

    Returns
    -------
    AdcRead
        The read's constants.
    """
    k = sensor.system_gain_dn_per_e * gain
    n = 2.0**sensor.adc_bits
    return AdcRead(k, sensor.black_level_dn, n - 1.0 if sensor.quantization else n,
                   0.5 if sensor.quantization else 0.0, (n - sensor.black_level_dn) / k, bool(sensor.quantization),
                   bool(sensor.clipping))


def _digitise(q_e, adc: AdcRead):
    """DN of reads ``q_e`` (float64 or float32 ndarray; new array), as :func:`spectracam.sensor.adc`."""
    dn = q_e * adc.k_dn_per_e + adc.black_dn
    if adc.quant:
        np.floor(dn, out=dn)
    if adc.clip:
        np.clip(dn, 0.0, adc.top_dn, out=dn)
    return dn


def _undigitise(dn, adc: AdcRead):
    """e⁻ at mid-step, ``(DN − b + ½)/K``."""
    return (dn - adc.black_dn + adc.half) / adc.k_dn_per_e


# ------------------------------------------------------------------ the pixel's charge, its pattern, its noise
class _Pattern(NamedTuple):
    offset_e: np.ndarray | None = None
    gain: np.ndarray | None = None
    dark_gain: np.ndarray | None = None


def _flat_pattern(pattern, shape) -> _Pattern:
    """The pattern's parts as flat float32 arrays of the rates' size (or None)."""
    if pattern is None:
        return _Pattern()
    parts = []
    for a in tuple(pattern)[:3]:
        if a is not None:
            a = np.asarray(a, np.float32)
            a = a.reshape(shape) if a.size == int(np.prod(shape)) else np.broadcast_to(a, shape)
            a = np.ascontiguousarray(a).reshape(-1)
        parts.append(a)
    return _Pattern(*parts)


def _charge(rate, time_s: float, dark_e_per_s: float, pat: _Pattern):
    """(expected charge ``ρ·T·g + i_d·T·d`` float32, the current ``ρ·g + i_d·d`` float64), flat."""
    mean = rate * np.float32(time_s)
    cur = rate.copy()
    if pat.gain is not None:
        mean *= pat.gain
        cur *= pat.gain
    if pat.dark_gain is None:
        mean += np.float32(dark_e_per_s * time_s)
        cur += np.float32(dark_e_per_s)
    else:
        mean += np.float32(dark_e_per_s * time_s) * pat.dark_gain
        cur += np.float32(dark_e_per_s) * pat.dark_gain
    return mean, cur.astype(np.float64)


def _stream(noise: np.random.SeedSequence, *key: int) -> np.random.SeedSequence:
    return np.random.SeedSequence(noise.entropy, spawn_key=(*noise.spawn_key, *key))


def _normals(noise, stream: int, n: int) -> np.ndarray:
    """``n`` standard normals (float32), value ``i`` a counter-based draw of pixel ``i``: the same for any
    chunking or number of threads, and on both backends (:class:`~spectracam.sensor.kernels.CounterRNG`)."""
    return kernels.CounterRNG(_stream(noise, stream)).standard_normal(n, np.float32).astype(np.float64)


def _shot(mean_e, sensor, noise, stream: int):
    """``mean_e`` (float64) with shot noise: Gaussian ``m + √m·z`` (the paper's 3.4) or Poisson counts (a
    :class:`numpy.random.Generator` of the stream over the whole frame: independent of any chunking)."""
    if not sensor.shot_noise:
        return mean_e.copy()
    if sensor.shot_noise_model == "poisson":
        return np.random.default_rng(_stream(noise, stream)).poisson(np.maximum(mean_e, 0.0)).astype(np.float64)
    return mean_e + np.sqrt(np.maximum(mean_e, 0.0)) * _normals(noise, stream, mean_e.size)


def _single_read(mean_e, sensor, noise, streams, offset_e, adc: AdcRead, sigma_e: float, well_e: float):
    """One integration and read: shot noise, the well, read noise ``sigma_e``, the offset, the ADC → DN."""
    q = _shot(mean_e, sensor, noise, streams[0])
    if sensor.clipping:
        np.clip(q, 0.0, well_e, out=q)
    if sigma_e > 0:
        q += sigma_e * _normals(noise, streams[1], q.size)
    if offset_e is not None:
        q += offset_e
    return _digitise(q, adc)


def _well_e(sensor, adc: AdcRead) -> float:
    """The largest charge a read distinguishes: the well or the ADC's range, whichever is less."""
    return min(sensor.q_max_e, adc.range_e)


# ------------------------------------------------------------------ the merged output word
def _scheme(sensor) -> "ReadoutScheme":
    if sensor.readout == "single" or sensor.readout not in READOUTS:
        raise SpectracamError(f"sensor.readout = {sensor.readout!r}: not a read-out of spectracam.sensor.readout; "
                              f"one of {', '.join(repr(n) for n in READOUTS.names)} (the single read is "
                              "spectracam.sensor.expose)")
    return READOUTS[sensor.readout]


def output_dn_per_e(sensor: SensorSpec) -> float:
    """DN per electron of the merged output word (its linear part, below the first companding knee).

    Twice the finest read's system gain — the sensor's K, or ``K·dual_gain_ratio`` for ``dual_gain`` — so the
    mid-step value of every read (``(DN + ½)/K``, and its multiples by a power of the integer ratios) is a code of
    the merged word: the merge adds no quantisation of its own and no bias.  ``single``: K.

    Parameters
    ----------
    sensor : SensorSpec
        The sensor.

    Returns
    -------
    float
        DN per e⁻.
    """
    k = sensor.system_gain_dn_per_e
    if sensor.readout == "single":
        return k
    return 2.0 * k * (sensor.dual_gain_ratio if sensor.readout == "dual_gain" else 1.0)


def output_black_dn(sensor: SensorSpec) -> float:
    """The merged word's black level, DN: the sensor's pedestal in electrons, ``b/K``, at the word's gain (so
    negative noise and offsets clip no more often than a single read's).

    Parameters
    ----------
    sensor : SensorSpec
        The sensor (its black level b and system gain K, its ``readout``).

    Returns
    -------
    float
        ``b·K_out/K``, DN of the merged word (b itself for ``single``).
    """
    return sensor.black_level_dn * output_dn_per_e(sensor) / sensor.system_gain_dn_per_e


def _linear_top_dn(sensor) -> float:
    """The largest linear merged word: the black level plus the scheme's range (headroom × a read's range)."""
    adc = adc_read(sensor)
    v = output_black_dn(sensor) + output_dn_per_e(sensor) * adc.range_e * _scheme(sensor).headroom(sensor)
    return float(math.floor(v) if sensor.quantization else v)


def output_top_dn(sensor: SensorSpec) -> float:
    """The largest merged output value (companded, when ``companding_bits`` is set).

    Parameters
    ----------
    sensor : SensorSpec
        The sensor.

    Returns
    -------
    float
        DN; for ``single`` the ADC's top, ``2ⁿ − 1`` (``2ⁿ`` without quantisation).
    """
    if sensor.readout == "single":
        return float(2**sensor.adc_bits - 1 if sensor.quantization else 2**sensor.adc_bits)
    top = _linear_top_dn(sensor)
    if sensor.companding_bits is None:
        return top
    return float(compand(np.array([top]), sensor)[0])


def _encode(q_est_e, sensor) -> np.ndarray:
    """The merged word of estimates ``q_est_e`` (float64): ``K_out·Q + b_out``, rounded half up to a code when
    quantising, clipped to ``[0, top]``, companded; float32."""
    o = q_est_e * output_dn_per_e(sensor) + output_black_dn(sensor)
    if sensor.quantization:
        o = np.floor(o + 0.5, out=o)
    if sensor.clipping:
        np.clip(o, 0.0, _linear_top_dn(sensor), out=o)
    if sensor.companding_bits is not None:
        o = compand(o, sensor)
    return o.astype(np.float32)


def decode(digital: ArrayLike, sensor: SensorSpec) -> np.ndarray:
    """Electrons-equivalent at the nominal exposure time from merged output words: the scheme's estimate of the
    total charge (photo + dark, ``current × time_s``, beyond the well where the scheme extends the range).

    The companding is expanded at each segment's mid-step (:func:`expand`), then ``(word − b_out)/K_out``.  For
    ``single`` it is :func:`spectracam.sensor.adc_inverse` (``(DN − b + ½)/K``).

    Parameters
    ----------
    digital : ndarray
        Merged output words (as :func:`read` returns them).
    sensor : SensorSpec
        The sensor.

    Returns
    -------
    ndarray
        float64 electrons, the shape of ``digital``.
    """
    d = np.asarray(digital, np.float64)
    if sensor.readout == "single":
        return _undigitise(d, adc_read(sensor))
    if sensor.companding_bits is not None:
        d = expand(d, sensor)
    return (d - output_black_dn(sensor)) / output_dn_per_e(sensor)


# ------------------------------------------------------------------ companding
def companding_curve(sensor: SensorSpec) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The piecewise-linear companding of the merged word into ``companding_bits`` bits: where each segment starts
    and its step (the rule: :func:`companding_bound`).

    Parameters
    ----------
    sensor : SensorSpec
        The sensor (``companding_bits`` set; the merged word's gain, black level and top).

    Returns
    -------
    x_starts : ndarray
        Linear merged word (DN) at which each segment starts, float64.
    code_starts : ndarray
        The companded code at each start, float64.
    steps : ndarray
        Linear words per code in each segment, ``2^j``, float64 (one segment of step 1: the identity).

    Raises
    ------
    SpectracamError
        ``companding_bits`` too few to hold the merged word's range.
    """
    return _companding(sensor)[:3]


def companding_bound(sensor: SensorSpec) -> float:
    """The bound c of the companding's steps, ``step ≤ c·σ`` (½ where the codes allow; see :func:`_companding`):
    the companding adds at most ``c²/12`` to the variance.

    Parameters
    ----------
    sensor : SensorSpec
        The sensor (``companding_bits`` set).

    Returns
    -------
    float
        c, in units of the shot noise σ at the step's level; 0 when the merged word fits its bits as it is (no
        companding).
    """
    return _companding(sensor)[3]


def _companding(sensor):
    """The piecewise-linear compression of the merged word into ``companding_bits`` bits.

    Segment ``j`` starts at linear word ``x_j`` (code ``c_j``) with step ``2^j`` (slope ``2⁻ʲ``, as automotive HDR
    sensors' 20/24 → 12-bit PWL outputs [Solhusvik2019]_).  Rule: a step never exceeds half the shot noise at its
    level, ``2^j ≤ ½·σ(x)``, ``σ(x) = √(K_out·(x − b_out))`` DN — so it adds at most ``(½)²/12 = 2 %`` to the
    variance (1 % to the noise); the knee of step ``2^j`` is the first multiple of the previous step past
    ``b_out + (2·2^j)²/K_out``.  Where ``2^bits`` codes cannot hold the range by that rule the bound relaxes
    (c·σ, c growing by 2^¼; :func:`companding_bound`) until they can.  A range that fits as it is: one segment, the identity.

    Parameters
    ----------
    sensor : SensorSpec
        The sensor (``companding_bits``, the merged word's gain, black level and top).

    Returns
    -------
    x_starts, code_starts, steps : ndarray
        float64, one per segment.
    """
    top, kout, b = _linear_top_dn(sensor), output_dn_per_e(sensor), output_black_dn(sensor)
    codes = 2.0**sensor.companding_bits - 1
    if top <= codes:
        return np.zeros(1), np.zeros(1), np.ones(1), 0.0
    c = 0.5
    while c < 2.0**40:
        xs, cs, ss = [0.0], [0.0], [1.0]
        for j in range(1, 48):
            knee = b + (2.0**j / c) ** 2 / kout
            if knee >= top:
                break
            x = xs[-1] + max(math.ceil((knee - xs[-1]) / ss[-1]), 1) * ss[-1]
            cs.append(cs[-1] + (x - xs[-1]) / ss[-1])
            xs.append(x)
            ss.append(2.0**j)
        if cs[-1] + math.floor((top - xs[-1]) / ss[-1]) <= codes:
            return np.array(xs), np.array(cs), np.array(ss), c
        c *= 2.0**0.25
    raise SpectracamError(f"sensor.companding_bits = {sensor.companding_bits}: cannot hold the merged word's "
                          f"{top:.0f} DN; allowed: more bits")


def compand(linear: ArrayLike, sensor: SensorSpec) -> np.ndarray:
    """Linear merged words → companded codes (:func:`companding_curve`); floored within a segment when the sensor
    quantises, continuous otherwise.

    Parameters
    ----------
    linear : ndarray
        Linear merged words, DN.
    sensor : SensorSpec
        The sensor.

    Returns
    -------
    ndarray
        float64 codes.
    """
    xs, cs, ss = companding_curve(sensor)
    lin = np.asarray(linear, np.float64)
    j = np.clip(np.searchsorted(xs, lin, side="right") - 1, 0, len(xs) - 1)
    steps = (lin - xs[j]) / ss[j]
    return cs[j] + (np.floor(steps) if sensor.quantization else steps)


def expand(codes: ArrayLike, sensor: SensorSpec) -> np.ndarray:
    """Companded codes → linear merged words at each code's mid-step (the mean of the ``2^j`` integer words a code
    of step ``2^j`` holds: ``+ (2^j − 1)/2``; continuous codes: exact).

    Parameters
    ----------
    codes : ndarray
        Companded codes.
    sensor : SensorSpec
        The sensor.

    Returns
    -------
    ndarray
        float64 linear words.
    """
    xs, cs, ss = companding_curve(sensor)
    c = np.asarray(codes, np.float64)
    j = np.clip(np.searchsorted(cs, c, side="right") - 1, 0, len(cs) - 1)
    lin = xs[j] + (c - cs[j]) * ss[j]
    return lin + (ss[j] - 1.0) / 2.0 if sensor.quantization else lin


# ------------------------------------------------------------------ multiple capture
class _McConstants(NamedTuple):
    sv: float  # read noise of one sample, e⁻
    sigma2: float  # its variance with the quantisation's, e⁻²: the estimator's observation noise
    satlev: float  # a sample less the reset above this, e⁻, is saturated
    thr2: float  # motion threshold², 0: none
    wls: bool


def _mc_constants(sensor) -> _McConstants:
    """Each sample's read noise is ``σ_r/√2`` (a correlated double sample, the reset read less the signal read,
    then has the sensor's σ_r: N = 1 is today's single read); the estimator weighs samples by that plus the
    ADC's ``Δ²/12`` (floored at 10⁻⁶ e⁻² so a noise-free sensor divides by no zero)."""
    adc = adc_read(sensor)
    sv = sensor.read_noise_rms_e / math.sqrt(2.0)
    sigma2 = max(sv * sv + (1.0 / (12.0 * adc.k_dn_per_e**2) if adc.quant else 0.0), 1e-6)
    satlev = _well_e(sensor, adc) - SATURATION_MARGIN_SIGMA * math.sqrt(2.0 * sigma2)
    return _McConstants(sv, sigma2, satlev, sensor.motion_threshold_sigma**2, sensor.readout_estimator == "wls")


def multiple_capture_samples(current_e_per_s: ArrayLike, time_s: float, sensor: SensorSpec,
                             noise: np.random.SeedSequence, offset_e: ArrayLike | None = None,
                             start: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """The N + 1 digitised samples of a multiple capture (NumPy), for currents ``(n,)`` e⁻/s.

    Charge accumulates with its shot noise (Gaussian increments ``i·Δt + √(i·Δt)·z``, or Poisson counts), the well
    clips it at ``q_max``, each read adds ``σ_r/√2`` of read noise and the offset, and the ADC digitises it.  The
    normals are those of the numba kernel (pixel ``start + i``'s Philox draws): the same numbers.

    Parameters
    ----------
    current_e_per_s : ndarray
        Total current (photo × PRNU + dark × DSNU) of each pixel, float64 ``(n,)``.
    time_s : float
        Exposure time T; samples at ``t_k = k·T/N``.
    sensor : SensorSpec
        The sensor (``readout_samples`` = N).
    noise : numpy.random.SeedSequence
        The frame's temporal noise.
    offset_e : ndarray or None
        Each pixel's offset, e⁻.
    start : int
        The first pixel's index in the frame (its counters).

    Returns
    -------
    samples_e : ndarray
        ``(N + 1, n)`` float64 reads at mid-step, e⁻ (the reset sample first).
    at_top : ndarray
        ``(N + 1, n)`` bool: the ADC read its top code.

    References
    ----------
    .. [LiuElGamal2001] see docs/references.md.
    """
    n_s, adc, c = sensor.readout_samples, adc_read(sensor), _mc_constants(sensor)
    dt = time_s / n_s
    cur = np.asarray(current_e_per_s, np.float64)
    idx = np.arange(start, start + cur.size, dtype=np.uint64)
    key = kernels.stream_key(noise)
    off = 0.0 if offset_e is None else np.asarray(offset_e, np.float64)
    q = np.zeros(cur.size)
    ys, tops = np.empty((n_s + 1, cur.size)), np.empty((n_s + 1, cur.size), bool)
    for s in range(n_s + 1):
        if s % 2 == 0:
            w = kernels.philox_np(idx, key, s // 2)
        zs, zr = kernels.normal_pair_np(*(w[:2] if s % 2 == 0 else w[2:]))
        if s > 0:
            inc = cur * dt
            if not sensor.shot_noise:
                q += inc
            elif sensor.shot_noise_model == "poisson":
                q += np.random.default_rng(_stream(noise, 1000 + s, start)).poisson(np.maximum(inc, 0.0))
            else:
                q += inc + np.sqrt(np.maximum(inc, 0.0)) * zs.astype(np.float64)
            if sensor.clipping:
                np.minimum(q, sensor.q_max_e, out=q)
        dn = _digitise(np.maximum(q, 0.0) + zr.astype(np.float64) * c.sv + off, adc)
        ys[s], tops[s] = _undigitise(dn, adc), adc.clip & (dn >= adc.top_dn)
    return ys, tops


def estimate_current(times_s: Sequence[float] | np.ndarray, samples_e: ArrayLike, sensor: SensorSpec,
                     at_top: np.ndarray | None = None) -> np.ndarray:
    """The multiple-capture estimate of the current from samples (NumPy, vectorised over pixels).

    ``wls``: the recursive weighted least-squares estimate [LiuElGamal2001]_ — a Kalman filter on (charge, current)
    with process noise ``max(î, 0)·Δt`` (the shot noise of the current estimate) and observation noise σ_V² + Δ²/12,
    started from the reset sample and the first difference; for a known current it is the best linear unbiased
    estimate under ``y_k = C + i·t_k + Σ shot + V_k`` (:func:`multiple_capture_variance`).  A saturated sample (at the
    ADC's top, or less the reset within :data:`SATURATION_MARGIN_SIGMA` σ of the well) ends the estimate at the
    sample before; so does a sample whose innovation exceeds ``motion_threshold_sigma`` × its σ (motion,
    [LiuElGamal2003]_; 0: off).  ``last_sample``: ``(y_k* − y_0)/t_k*``, k* the last unsaturated sample.  A pixel
    saturated at its first sample gives that sample's difference (the most the scheme encodes).

    Parameters
    ----------
    times_s : sequence of float
        ``t_0 = 0, t_1 … t_N``, s (any increasing times).
    samples_e : ndarray
        ``(N + 1, ...)`` reads, e⁻, the reset first.
    sensor : SensorSpec
        The sensor (estimator, motion threshold, noise, well).
    at_top : ndarray or None
        ``(N + 1, ...)`` bool: samples that read the ADC's top code (saturated whatever their value).

    Returns
    -------
    ndarray
        The current, e⁻/s, float64, the shape of one sample.

    References
    ----------
    .. [LiuElGamal2001] see docs/references.md.
    .. [LiuElGamal2003] see docs/references.md.
    """
    y = np.asarray(samples_e, np.float64)
    t = np.asarray(times_s, np.float64)
    c = _mc_constants(sensor)
    st = [np.zeros(y.shape[1:]) for _ in range(5)] + [np.ones(y.shape[1:])]
    for k in range(1, y.shape[0]):
        sat = (y[k] - y[0] >= c.satlev) | (False if at_top is None else at_top[k])
        sat = sat & bool(sensor.clipping)
        st = _kalman_np(k == 1, y[k], y[0], sat, t[k] - t[k - 1], t[k], st, c)
    return st[1]


def _kalman_np(first, y, y0, sat, dt, tk, st, c: _McConstants):
    """:func:`~spectracam.sensor._numba_readout.kalman_step` on arrays: the same operations in the same order."""
    qh, ih, pqq, pqi, pii, act = st
    live = (act != 0.0) & ~sat
    ih = np.where((act != 0.0) & sat & first, (y - y0) / dt, ih)
    act = np.where(sat, 0.0, act)
    if not c.wls:
        return qh, np.where(live, (y - y0) / tk, ih), pqq, pqi, pii, act
    if first:
        i1 = (y - y0) / dt
        q = np.maximum(i1, 0.0)
        new = (y, i1, np.full_like(y, c.sigma2), np.full_like(y, c.sigma2 / dt), (q * dt + 2.0 * c.sigma2) / (dt * dt))
    else:
        q = np.maximum(ih, 0.0)
        mqq = pqq + 2.0 * dt * pqi + dt * dt * pii + q * dt
        mqi = pqi + dt * pii
        pred = qh + dt * ih
        nu = y - pred
        s = mqq + c.sigma2
        if c.thr2 > 0.0:
            moved = live & (nu * nu > c.thr2 * s)
            live &= ~moved
            act = np.where(moved, 0.0, act)
        kq, ki = mqq / s, mqi / s
        new = (pred + kq * nu, ih + ki * nu, mqq * (1.0 - kq), mqi * (1.0 - kq), pii - ki * mqi)
    out = tuple(np.where(live, a, b) for a, b in zip(new, (qh, ih, pqq, pqi, pii)))
    return (*out, act)


_NUMBA: dict = {}
#: Pixels per chunk of the NumPy multiple capture (its (N + 1) sample planes stay in memory).
_NP_CHUNK = 1 << 16


def _numba_readout():
    """The numba kernel module, or None (no numba, ``SPECTRACAM_FUSED=0``, or it failed to compile here)."""
    if not kernels.available():
        return None
    if "mod" not in _NUMBA:
        try:
            from spectracam.sensor import _numba_readout as mod
        except Exception:  # noqa: BLE001 - numba that does not load: the NumPy path
            mod = None
        _NUMBA["mod"] = mod
    return _NUMBA["mod"]


def _mc_numba(mod, rate, time_s, sensor, noise, pat: _Pattern):
    """The kernel over bands of pixels on the kernels' thread pool (every value depends on its pixel alone)."""
    n, adc, c = rate.size, adc_read(sensor), _mc_constants(sensor)
    one, zero = np.ones(1, np.float32), np.zeros(1, np.float32)
    k0, k1 = (np.uint64(v) for v in kernels.stream_key(noise))
    out, mean = np.empty(n, np.float32), np.empty(n, np.float32)
    args = (rate, one if pat.gain is None else pat.gain, one if pat.dark_gain is None else pat.dark_gain,
            zero if pat.offset_e is None else pat.offset_e, k0, k1, np.int64(sensor.readout_samples), float(time_s),
            float(sensor.dark_rate_e_per_s), float(sensor.dark_rate_e_per_s * time_s), float(sensor.q_max_e), c.sv,
            adc.k_dn_per_e, adc.black_dn, adc.half, adc.top_dn, c.satlev, c.sigma2, c.thr2, output_dn_per_e(sensor),
            output_black_dn(sensor), _linear_top_dn(sensor), bool(sensor.shot_noise),
            sensor.shot_noise_model == "poisson", adc.clip, adc.quant, c.wls)
    parts = max(1, min(kernels.threads(), n // mod.BLOCK + 1))
    bounds = [(n * j // parts, n * (j + 1) // parts) for j in range(parts)]
    futures = [kernels._pool().submit(mod.mc_kernel, np.int64(a), np.int64(b), *args, out, mean) for a, b in bounds]
    for f in futures:
        f.result()
    return out, mean


def _mc_numpy(rate, time_s, sensor, noise, pat: _Pattern):
    mean, cur = _charge(rate, time_s, sensor.dark_rate_e_per_s, pat)
    est = np.empty(rate.size)
    times = np.arange(sensor.readout_samples + 1) * (time_s / sensor.readout_samples)
    for a in range(0, rate.size, _NP_CHUNK):
        sl = slice(a, min(a + _NP_CHUNK, rate.size))
        ys, tops = multiple_capture_samples(cur[sl], time_s, sensor, noise,
                                            None if pat.offset_e is None else pat.offset_e[sl], a)
        est[sl] = estimate_current(times, ys, sensor, tops)
    o = est * time_s * output_dn_per_e(sensor) + output_black_dn(sensor)
    if sensor.quantization:
        o = np.floor(o + 0.5, out=o)
    if sensor.clipping:
        np.clip(o, 0.0, _linear_top_dn(sensor), out=o)
    return o.astype(np.float32), mean


def read_multiple_capture(rate_e_per_s: np.ndarray, time_s: float, sensor: SensorSpec, noise: np.random.SeedSequence,
                          pattern: FixedPattern | None = None, backend: str | None = None
                          ) -> tuple[np.ndarray, np.ndarray]:
    """A multiple capture (``readout = "multiple_capture"``): N = ``readout_samples`` non-destructive samples at
    ``t_k = k·T/N`` after a reset sample, merged by ``readout_estimator`` (:func:`estimate_current`).

    Parameters
    ----------
    rate_e_per_s : ndarray
        Photo-electron rates, any shape.
    time_s : float
        Exposure time T, s.
    sensor : SensorSpec
        The sensor.
    noise : numpy.random.SeedSequence
        The frame's temporal noise.
    pattern : FixedPattern or None
        ``(offset_e, gain, dark_gain)``.
    backend : str or None
        "numba" or "numpy" (default: numba where available).  Gaussian shot noise: the same normals on both, the
        estimate the same float64 operations.

    Returns
    -------
    digital, expected_e : ndarray
        The merged words (float32) and the noise-free charge (float32), the rates' shape.

    References
    ----------
    .. [LiuElGamal2001] see docs/references.md.
    """
    shape = np.shape(rate_e_per_s)
    rate = np.ascontiguousarray(rate_e_per_s, np.float32).reshape(-1)
    pat = _flat_pattern(pattern, shape)
    mod = _numba_readout() if backend != "numpy" else None
    if mod is not None:
        out, mean = _mc_numba(mod, rate, time_s, sensor, noise, pat)
    else:
        out, mean = _mc_numpy(rate, time_s, sensor, noise, pat)
    if sensor.companding_bits is not None:
        out = compand(out, sensor).astype(np.float32)
    return out.reshape(shape), mean.reshape(shape)


# ------------------------------------------------------------------ dual gain, split pixel, bracketing
def _prepare(rate_e_per_s, time_s, sensor, pattern):
    shape = np.shape(rate_e_per_s)
    rate = np.ascontiguousarray(rate_e_per_s, np.float32).reshape(-1)
    pat = _flat_pattern(pattern, shape)
    mean, _ = _charge(rate, time_s, sensor.dark_rate_e_per_s, pat)
    off = None if pat.offset_e is None else pat.offset_e.astype(np.float64)
    return shape, rate, pat, mean, off


def high_gain_read_noise_e(sensor: SensorSpec) -> float:
    """The read noise of ``dual_gain``'s high-gain read, e⁻ rms: the read chain's noise is fixed in volts, so in
    electrons it falls with the conversion gain — ``read_noise_uV/(g·ratio)`` when the sensor states it in µV, else
    ``read_noise_rms_e/ratio``.

    Parameters
    ----------
    sensor : SensorSpec
        The sensor.

    Returns
    -------
    float
        e⁻ rms (0 with the read noise switched off).
    """
    if not sensor.read_noise:
        return 0.0
    if sensor.read_noise_uV is not None:
        return sensor.read_noise_uV / (sensor.conversion_gain_uV_per_e * sensor.dual_gain_ratio)
    return sensor.read_noise_rms_e / sensor.dual_gain_ratio


def read_dual_gain(rate_e_per_s: np.ndarray, time_s: float, sensor: SensorSpec, noise: np.random.SeedSequence,
                   pattern: FixedPattern | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Dual conversion gain (``readout = "dual_gain"``) [Solhusvik2019]_: one integration (shot noise, the well
    ``q_max``) read twice by the same ADC — at ``dual_gain_ratio`` × the conversion gain (its swing ``q_max/ratio``
    e⁻, its read noise :func:`high_gain_read_noise_e`, the offset, fixed in volts, ``offset_e/ratio``) and at the
    sensor's own.  Merged: the high-gain read while it is below ``dual_gain_switch`` of its swing, else the low.

    Parameters
    ----------
    rate_e_per_s : ndarray
        Photo-electron rates, any shape.
    time_s : float
        Exposure time, s.
    sensor : SensorSpec
        The sensor.
    noise : numpy.random.SeedSequence
        The frame's temporal noise.
    pattern : FixedPattern or None
        ``(offset_e, gain, dark_gain)``.

    Returns
    -------
    digital, expected_e : ndarray
        Merged words and the noise-free charge (float32), the rates' shape.

    References
    ----------
    .. [Solhusvik2019] see docs/references.md.
    """
    shape, rate, pat, mean, off = _prepare(rate_e_per_s, time_s, sensor, pattern)
    ratio = sensor.dual_gain_ratio
    adc_l, adc_h = adc_read(sensor), adc_read(sensor, ratio)
    q = _shot(mean.astype(np.float64), sensor, noise, 0)
    if sensor.clipping:
        np.clip(q, 0.0, sensor.q_max_e, out=q)
    reads = []
    for adc, sigma, stream, o in ((adc_h, high_gain_read_noise_e(sensor), 1, None if off is None else off / ratio),
                                  (adc_l, sensor.read_noise_rms_e, 2, off)):
        v = q + sigma * _normals(noise, stream, q.size) if sigma > 0 else q.copy()
        if o is not None:
            v += o
        reads.append(_undigitise(_digitise(v, adc), adc))
    est = np.where(reads[0] < sensor.dual_gain_switch * min(sensor.q_max_e, adc_h.range_e), reads[0], reads[1])
    return _encode(est, sensor).reshape(shape), mean.reshape(shape)


def read_split_pixel(rate_e_per_s: np.ndarray, time_s: float, sensor: SensorSpec, noise: np.random.SeedSequence,
                     pattern: FixedPattern | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Split pixel (``readout = "split_pixel"``) [Solhusvik2019]_: the sensor's photodiode and a small one of
    sensitivity ``1/split_ratio`` (its dark current too: it scales with the area) and full well
    ``split_small_well_fraction·q_max``, each read once with the sensor's read noise (e⁻) and ADC — the small one at
    the conversion gain that fills the ADC with its well (K/fraction; its offset, a fraction of its swing as the
    sensor's is of its own, ``offset_e·fraction``).  Merged: the large read while below :data:`SWITCH_FRACTION` of its
    well, else the small read × ``split_ratio``.

    Parameters
    ----------
    rate_e_per_s : ndarray
        Photo-electron rates of the large photodiode, any shape.
    time_s : float
        Exposure time, s.
    sensor : SensorSpec
        The sensor.
    noise : numpy.random.SeedSequence
        The frame's temporal noise.
    pattern : FixedPattern or None
        ``(offset_e, gain, dark_gain)``.

    Returns
    -------
    digital, expected_e : ndarray
        Merged words and the large photodiode's noise-free charge (float32), the rates' shape.

    References
    ----------
    .. [Solhusvik2019] see docs/references.md.
    """
    shape, rate, pat, mean, off = _prepare(rate_e_per_s, time_s, sensor, pattern)
    ratio, frac = sensor.split_ratio, sensor.split_small_well_fraction
    adc_l, adc_s = adc_read(sensor), adc_read(sensor, 1.0 / frac)
    m64 = mean.astype(np.float64)
    e_l = _undigitise(_single_read(m64, sensor, noise, (0, 1), off, adc_l, sensor.read_noise_rms_e,
                                   sensor.q_max_e), adc_l)
    e_s = _undigitise(_single_read(m64 / ratio, sensor, noise, (2, 3), None if off is None else off * frac, adc_s,
                                   sensor.read_noise_rms_e, frac * sensor.q_max_e), adc_s)
    est = np.where(e_l < SWITCH_FRACTION * _well_e(sensor, adc_l), e_l, ratio * e_s)
    return _encode(est, sensor).reshape(shape), mean.reshape(shape)


def _frame_dn(rate, time_s, sensor, noise, pat: _Pattern, shape2d):
    """One bracketed frame, a full single read: the fused kernel where it runs, else NumPy."""
    if kernels.available():
        out = kernels.expose(rate.reshape(shape2d), time_s, sensor, noise, _Pattern(*(
            None if a is None else a.reshape(shape2d) for a in pat)))
        if out is not None:
            return out[0].reshape(-1).astype(np.float64)
    mean, _ = _charge(rate, time_s, sensor.dark_rate_e_per_s, pat)
    off = None if pat.offset_e is None else pat.offset_e.astype(np.float64)
    return _single_read(mean.astype(np.float64), sensor, noise, (0, 1), off, adc_read(sensor),
                        sensor.read_noise_rms_e, sensor.q_max_e)


def read_bracketing(rate_e_per_s: np.ndarray, time_s: float, sensor: SensorSpec, noise: np.random.SeedSequence,
                    pattern: FixedPattern | None = None, frame_rates: Sequence[ArrayLike] | None = None
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Exposure bracketing (``readout = "bracketing"``) [Debevec1997]_: ``bracketing_frames`` sequential full
    single reads of ``T, T/r, T/r², …`` (``r = bracketing_ratio``), each with its own shot, dark and read noise, well
    and ADC.  Merged: the longest frame below :data:`SWITCH_FRACTION` of the well, scaled to T (the shortest where
    every frame is saturated).  Why not an inverse-variance merge of all unsaturated frames: the longest holds
    ``r/(r + 1)`` or more of their signal, so the weighted merge would gain at most ``1 + 1/r`` in variance, and it
    would blend frames taken at different times — the longest alone keeps motion to one frame.

    Parameters
    ----------
    rate_e_per_s : ndarray
        Photo-electron rates, any shape.
    time_s : float
        The longest frame's time T, s.
    sensor : SensorSpec
        The sensor.
    noise : numpy.random.SeedSequence
        The frame's temporal noise (frame f: its spawn f).
    pattern : FixedPattern or None
        ``(offset_e, gain, dark_gain)``.
    frame_rates : sequence of ndarray or None
        One rate array (or scalar) per frame, for a scene that moves between frames; default: ``rate_e_per_s``.

    Returns
    -------
    digital, expected_e : ndarray
        Merged words and the noise-free charge at T of ``rate_e_per_s`` (float32), the rates' shape.

    References
    ----------
    .. [Debevec1997] see docs/references.md.
    """
    shape, rate, pat, mean, _ = _prepare(rate_e_per_s, time_s, sensor, pattern)
    n_f, r = sensor.bracketing_frames, sensor.bracketing_ratio
    if frame_rates is not None and len(frame_rates) != n_f:
        raise SpectracamError(f"frame_rates: {len(frame_rates)} arrays; allowed: one per frame, {n_f}")
    shape2d = (shape[0], -1) if len(shape) >= 2 else (1, -1)
    adc = adc_read(sensor)
    est = np.zeros(rate.size)
    for f in reversed(range(n_f)):  # shortest first; a longer unsaturated frame replaces it
        rf = rate if frame_rates is None else np.ascontiguousarray(
            np.broadcast_to(np.asarray(frame_rates[f], np.float32), shape)).reshape(-1)
        e = _undigitise(_frame_dn(rf, time_s / r**f, sensor, _stream(noise, f), pat, shape2d), adc)
        est = e * r**f if f == n_f - 1 else np.where(e < SWITCH_FRACTION * _well_e(sensor, adc), e * r**f, est)
    return _encode(est, sensor).reshape(shape), mean.reshape(shape)


# ------------------------------------------------------------------ closed forms
def multiple_capture_variance(current_e_per_s: float, time_s: float, sensor: SensorSpec,
                              estimator: str | None = None) -> float:
    """The variance of the multiple-capture estimate of a constant current, (e⁻/s)², closed form.

    ``wls``: the generalised least-squares variance ``[(XᵀΣ⁻¹X)⁻¹]₁₁`` of the model ``y_k = C + i·t_k + e_k``,
    ``X = [1, t_k]``, ``Σ_jk = i·min(t_j, t_k) + σ²·δ_jk`` (cumulative shot noise; per-sample read noise σ_V² = σ_r²/2
    plus the ADC's Δ²/12), over the reset sample and the samples before the first whose mean charge reaches the
    saturation level (the well less :data:`SATURATION_MARGIN_SIGMA` σ).  ``last_sample``: ``(i·t* + 2σ²)/t*²``.

    Parameters
    ----------
    current_e_per_s : float
        Total current (photo + dark), e⁻/s.
    time_s : float
        Exposure time T, s.
    sensor : SensorSpec
        The sensor.
    estimator : str or None
        "wls" or "last_sample" (default: the sensor's ``readout_estimator``).

    Returns
    -------
    float
        (e⁻/s)².

    References
    ----------
    .. [LiuElGamal2001] see docs/references.md.
    """
    c = _mc_constants(sensor)
    n_s = sensor.readout_samples
    t = np.arange(n_s + 1) * (time_s / n_s)
    i = max(float(current_e_per_s), 0.0) if sensor.shot_noise else 0.0
    k = max(n_s if not sensor.clipping else int(np.sum(float(current_e_per_s) * t[1:] < c.satlev)), 1)
    if (estimator or sensor.readout_estimator) == "last_sample":
        return (i * t[k] + 2.0 * c.sigma2) / t[k] ** 2
    ts = t[:k + 1]
    cov = i * np.minimum.outer(ts, ts) + c.sigma2 * np.eye(k + 1)
    x = np.stack([np.ones_like(ts), ts], axis=1)
    return float(np.linalg.inv(x.T @ np.linalg.solve(cov, x))[1, 1])


def _companding_var_e2(s_e, sensor):
    """The companding's added variance at charge ``s_e``: a step of ``2^j`` words adds ``(4^j − 1)/12`` words²
    over the linear word's own rounding."""
    if sensor.companding_bits is None:
        return 0.0
    xs, _, ss = companding_curve(sensor)
    x = output_black_dn(sensor) + output_dn_per_e(sensor) * s_e
    step = ss[np.clip(np.searchsorted(xs, x, side="right") - 1, 0, len(xs) - 1)]
    return (step**2 - 1.0) / 12.0 / output_dn_per_e(sensor) ** 2


def _read_var(s_e, sigma_e, adc: AdcRead, sensor):
    """Variance of one read at charge ``s_e``, e⁻²: shot + read + the ADC's Δ²/12."""
    return (s_e if sensor.shot_noise else 0.0) + sigma_e**2 + (1.0 / (12.0 * adc.k_dn_per_e**2) if adc.quant else 0.0)


def _scheme_var(s, sensor):
    """(variance e⁻², range e⁻) of the scheme's merged estimate at mean charges ``s`` (float64 array)."""
    adc = adc_read(sensor)
    well = _well_e(sensor, adc)
    name = sensor.readout
    if name == "single":
        return _read_var(s, sensor.read_noise_rms_e, adc, sensor), well
    if name == "multiple_capture":
        v = np.array([multiple_capture_variance(x, 1.0, sensor) for x in s.reshape(-1)]).reshape(s.shape)
        rnd = 1.0 / (12.0 * output_dn_per_e(sensor) ** 2) if sensor.quantization and _mc_constants(sensor).wls else 0
        return v + rnd, well * sensor.readout_samples
    if name == "dual_gain":
        adc_h = adc_read(sensor, sensor.dual_gain_ratio)
        high = s < sensor.dual_gain_switch * min(sensor.q_max_e, adc_h.range_e)
        return np.where(high, _read_var(s, high_gain_read_noise_e(sensor), adc_h, sensor),
                        _read_var(s, sensor.read_noise_rms_e, adc, sensor)), well
    if name == "split_pixel":
        r, frac = sensor.split_ratio, sensor.split_small_well_fraction
        small = r * r * _read_var(s / r, sensor.read_noise_rms_e, adc_read(sensor, 1.0 / frac), sensor)
        return np.where(s < SWITCH_FRACTION * well, _read_var(s, sensor.read_noise_rms_e, adc, sensor), small), \
            well * r * frac
    r, n_f = sensor.bracketing_ratio, sensor.bracketing_frames
    var = np.full(s.shape, np.nan)
    for f in reversed(range(n_f)):
        sf = s / r**f
        vf = r ** (2 * f) * _read_var(sf, sensor.read_noise_rms_e, adc, sensor)
        var = vf if f == n_f - 1 else np.where(sf < SWITCH_FRACTION * well, vf, var)
    return var, well * r ** (n_f - 1)


def snr_curve(signal_e: ArrayLike, sensor: SensorSpec) -> np.ndarray:
    """The read-out's signal-to-noise ratio against the mean charge, closed form: mean over σ of its merged
    estimate (e⁻ at the exposure time), shot + read + quantisation noise of the read it uses — so ``dual_gain``
    and ``split_pixel`` show the dip where they switch reads, ``bracketing`` where it switches frames.

    Parameters
    ----------
    signal_e : array_like
        Mean photo + dark charge at the exposure time, e⁻.
    sensor : SensorSpec
        The sensor (any ``readout``, ``single`` included).

    Returns
    -------
    ndarray
        Linear SNR, float64; NaN beyond the scheme's range (the merged word clipped).

    References
    ----------
    .. [EMVA1288] see docs/references.md; the SNR of a linear camera.
    .. [LiuElGamal2001] see docs/references.md.
    """
    s = np.asarray(signal_e, np.float64)
    var, top = _scheme_var(s, sensor)
    if sensor.readout != "single":
        var = var + _companding_var_e2(s, sensor)
    with np.errstate(divide="ignore", invalid="ignore"):
        snr = s / np.sqrt(var)
    return np.where(s < top, snr, np.nan) if sensor.clipping else snr


# ------------------------------------------------------------------ the registry
def _one(sensor) -> float:
    return 1.0


def _same_time(sensor, time_s: float) -> float:
    return float(time_s)


#: The read-out schemes beside the single read: name → :class:`ReadoutScheme`.
READOUTS: Registry = Registry("sensor.readout", "read-out scheme")
READOUTS.register("multiple_capture", ReadoutScheme(read_multiple_capture, lambda s: float(s.readout_samples),
                                                    _same_time))
READOUTS.register("dual_gain", ReadoutScheme(read_dual_gain, _one, _same_time))
READOUTS.register("split_pixel", ReadoutScheme(read_split_pixel,
                                               lambda s: s.split_ratio * s.split_small_well_fraction, _same_time))
READOUTS.register("bracketing", ReadoutScheme(
    read_bracketing, lambda s: s.bracketing_ratio ** (s.bracketing_frames - 1),
    lambda s, t: float(sum(t / s.bracketing_ratio**f for f in range(s.bracketing_frames)))))


def read(rate_e_per_s: np.ndarray, time_s: float, sensor: SensorSpec, noise: np.random.SeedSequence,
         pattern: FixedPattern | None = None) -> tuple[np.ndarray, np.ndarray]:
    """One frame by the sensor's read-out scheme (``sensor.readout``; ``single`` is
    :func:`spectracam.sensor.expose`'s, and raises here).

    Parameters
    ----------
    rate_e_per_s : ndarray
        Photo-electron rates, any shape (float32).
    time_s : float
        Exposure time, s.
    sensor : SensorSpec
        The sensor.
    noise : numpy.random.SeedSequence
        The frame's temporal noise.
    pattern : FixedPattern or None
        ``(offset_e, gain, dark_gain)``.

    Returns
    -------
    digital, expected_e : ndarray
        Merged output words (float32, :func:`decode` reads them) and the noise-free charge ``ρ·T·g + i_d·T·d``
        (float32, unclipped), the rates' shape.

    References
    ----------
    .. [LiuElGamal2001] see docs/references.md.
    .. [Solhusvik2019] see docs/references.md.
    .. [Debevec1997] see docs/references.md.
    """
    return _scheme(sensor).read(rate_e_per_s, time_s, sensor, noise, pattern)
