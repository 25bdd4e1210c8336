"""CMOS image sensor in current-integration mode (paper, sections 3.4 and 4.4).

Per pixel and channel the recorded value is built by named steps, each one term of the paper's
section 3.4: :func:`integrate_charge` (photo-electrons ``ρ·T``, times the pixel's PRNU gain, plus
dark electrons ``i_d·A·T``, times its DSNU factor), :func:`add_shot_noise`, :func:`clip_to_well`
(``q_max``), :func:`add_read_noise` (``Q_r``), :func:`add_offset_fpn` (``V_FPN``, pixel and column)
and :func:`adc`: ``DN = K·Q + black level``, an n-bit uniform quantiser clipped to its codes, with
the system gain ``K = 2ⁿ·g / V_fs`` (EMVA 1288: DN per electron) from the conversion gain ``g`` and
the ADC's full-scale voltage ``V_fs``; :func:`adc_inverse` sits beside it.  The well clip and the
ADC clip are separate stages.  Each noise source switches off on its own.  :func:`expose` runs the
steps in place, chunk by chunk, on all cores: the reference implementation.  A capture normally
runs :mod:`spectracam.sensor.kernels` instead — the same model fused into one pass over the radiance cube,
with counter-based random numbers — and falls back to these steps where it cannot run.  The fixed
pattern (:func:`fixed_pattern`) is a counter-based draw of each pixel on both paths.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Callable, NamedTuple

import numpy as np

from spectracam.core.errors import ConfigError
from spectracam.sensor.kernels import CounterRNG
from spectracam.core.registry import Registry
from spectracam.core.spec import Spec
from spectracam.sensor.temperature import DARK_CURRENT_LAWS, dark_current_factor

__all__ = ["CHUNK_PX", "CounterRNG", "FPN_READINGS", "FixedPattern", "FpnReading", "NOISE_SOURCES", "PatternDraws",
           "PatternRef", "PixelDraw", "READOUT_ESTIMATORS", "READOUT_NAMES", "SHOT_NOISE_MODELS", "SensorSpec", "adc",
           "adc_full_scale_dn", "adc_inverse", "add_offset_fpn", "add_read_noise", "add_shot_noise", "clip_to_well",
           "dark_gain_moments", "expose", "fixed_pattern", "fixed_pattern_parts", "hot_pixel_excess",
           "integrate_charge", "noise_stream", "read_frame"]


class FpnReading(NamedTuple):
    """How a stated FPN fraction of full swing becomes per-pixel offsets."""

    rms_per_swing: float  # rms offset / (fraction × full swing)
    draw: Callable  # (rng, out float32 array, swing_e) → fills ``out`` with offsets in electrons


def _draw_std(rng, out, swing_e):
    rng.standard_normal(out=out, dtype=np.float32)
    out *= np.float32(swing_e)


def _draw_bound(rng, out, swing_e):
    rng.random(out=out, dtype=np.float32)
    out -= np.float32(0.5)
    out *= np.float32(swing_e)


#: Readings of "FPN < x % of full swing": ``std`` — the rms across pixels is that fraction (how
#: datasheets quote FPN; the worst case the statement allows); ``bound`` — every offset lies within
#: a spread of that fraction (uniform, rms = fraction/√12).
FPN_READINGS: Registry = Registry("sensor.fpn_reading", "FPN reading")
FPN_READINGS.register("std", FpnReading(1.0, _draw_std))
FPN_READINGS.register("bound", FpnReading(1.0 / np.sqrt(12.0), _draw_bound))


def _gaussian_shot(mean, out, rng):
    """The paper's 3.4: Gaussian with variance = mean."""
    rng.standard_normal(out=out, dtype=np.float32)
    out *= np.sqrt(mean)
    out += mean


def _poisson_shot(mean, out, rng):
    """Exact counting statistics."""
    out[...] = rng.poisson(mean)


#: Shot-noise models: name → function ``(mean_e, out, rng)`` filling ``out`` with noisy electrons.
SHOT_NOISE_MODELS: Registry = Registry("sensor.shot_noise_model", "shot-noise model")
SHOT_NOISE_MODELS.register("gaussian", _gaussian_shot)
SHOT_NOISE_MODELS.register("poisson", _poisson_shot)

#: Read-out schemes (:data:`spectracam.sensor.readout.READOUTS` holds their functions) and the estimators of
#: ``multiple_capture``: names here, so the sensor's table validates without importing the schemes.
READOUT_NAMES = ("single", "multiple_capture", "dual_gain", "split_pixel", "bracketing")
READOUT_ESTIMATORS = ("wls", "last_sample")

#: The switchable error sources, in the order the paper's Figure 6 adds them.
NOISE_SOURCES = ("shot_noise", "dark_current", "read_noise", "fpn", "quantization")


@dataclass(frozen=True)
class SensorSpec(Spec):
    TABLE = "sensor"

    #: Full-well capacity, electrons (paper, 4.4).
    q_max_e: float = 131072.0
    #: Read noise σ_r, electrons rms (paper, 4.4).
    read_noise_e: float = 20.0
    #: The read chain's noise referred to the pixel's output (source follower, column amplifier, ADC), µV rms
    #: (issue 36).  When given, the read noise in electrons is ``read_noise_uV / conversion_gain_uV_per_e``: a higher
    #: conversion gain lowers it, as a dual-conversion-gain pixel's high-gain read does.  None: ``read_noise_e`` as
    #: stated (the paper's 20 e⁻, which is 100 µV at its 5 µV/e⁻).
    read_noise_uV: float | None = None
    #: Dark current density, electrons per second per µm² of photodiode (paper, 4.4), at ``dark_reference_C``.
    dark_current_e_per_s_um2: float = 10.0
    #: The die's temperature, °C (issue 36): the dark current follows it by ``dark_current_law``
    #: (:mod:`spectracam.sensor.temperature`).  25 °C: the reference, the paper's dark current unchanged.
    temperature_C: float = 25.0
    #: The temperature at which ``dark_current_e_per_s_um2`` holds, °C: the paper states none; 25 °C is where
    #: sensor datasheets quote their dark current.
    dark_reference_C: float = 25.0
    #: How the dark current follows temperature: "generation" (depletion-region generation, ∝ T^1.5·exp(−E_g/2kT);
    #: silicon near room temperature), "diffusion" (∝ T³·exp(−E_g/kT)), or "doubling" (2^(ΔT/T_d), a datasheet's rule).
    dark_current_law: str = "generation"
    #: The doubling temperature T_d of the "doubling" law, K.  None: the generation law's own at the reference
    #: temperature (8.3 K at 25 °C).
    dark_doubling_K: float | None = None
    #: ADC resolution, bits (paper, 4.4).
    adc_bits: int = 8
    #: Black level (pedestal) added before the ADC, DN.  The paper's ADC clips at code 0, which
    #: truncates the negative half of the dark noise (EMVA 1288 allows ≤ 0.5 % of dark pixels at 0).
    #: Default (None): 2ⁿ⁻⁵ DN, 1/32 of the range — 8 DN at 8 bits, 3 σ of the default offset FPN.
    black_level_DN: float | None = None
    #: ADC full-scale input, V.  Default (None): the full well above the pedestal,
    #: ``g·q_max·2ⁿ/(2ⁿ − black level)``, so a full well reads the top code as in the paper.
    adc_full_scale_V: float | None = None
    #: Offset fixed-pattern noise as a fraction of full swing (paper, 4.4: "FPN < 1 % full output swing").
    fpn_fraction: float = 0.01
    #: How to read "FPN < 1 %": "std" — the rms across pixels is that fraction (how datasheets quote
    #: FPN; the worst case the spec allows), or "bound" — every pixel's offset lies within a spread of
    #: that fraction (uniform, rms = fraction/√12).
    fpn_reading: str = "std"
    #: Gain FPN (PRNU), rms fraction of the signal; the paper ignores it (footnote §), so 0.
    prnu_fraction: float = 0.0
    #: Dark-signal non-uniformity: rms of each pixel's dark current, fraction of the mean; the paper
    #: has none, so 0 (typical CMOS: 0.1–0.5).
    dsnu_fraction: float = 0.0
    #: Column FPN: rms of per-column offsets, fraction of full swing (column amplifiers and ADCs);
    #: the paper has none, so 0.
    column_fpn_fraction: float = 0.0
    #: The physical sensor: the seed of its fixed pattern.  None: the capture's seed (every capture a
    #: new sensor, as the paper's trials); a number: one sensor, many frames.
    pattern_seed: int | None = None
    #: Pixel pitch, µm.  The paper gives none; a full well of 131072 e⁻ at ~1300 e⁻/µm² suggests
    #: ~100 µm² of photodiode, i.e. a 10 µm pixel.
    pixel_pitch_um: float = 10.0
    #: Fraction of the pixel that collects light (microlenses make the effective value near 1).
    fill_factor: float = 1.0
    #: Conversion gain g, µV per electron (sets only the voltage scale of V = g·Q + V_FPN).
    conversion_gain_uV_per_e: float = 5.0
    #: "gaussian" (the paper's 3.4: variance = mean) or "poisson" (exact counting statistics).
    shot_noise_model: str = "gaussian"
    #: Hot pixels (issue 36): the share of pixels in the dark-signal non-uniformity's tail.  Each hot pixel's dark
    #: current is raised by ``X·i_d`` with X exponential of mean ``hot_pixel_mean_factor``: measured dark-current
    #: histograms are positively skewed with a long tail (Baer 2006 [Baer2006]), and their hot pixels form a separate
    #: latent class (Forcina & Carbone 2018 [Forcina2018]).  Every pixel's factor is then divided by the mean, so
    #: ``dark_current_e_per_s_um2`` stays the mean over all pixels, as EMVA 1288 measures it
    #: (:func:`dark_gain_moments`).  0: none (the paper).
    hot_pixel_fraction: float = 0.0
    #: The mean extra dark current of a hot pixel, in multiples of the mean dark current: 20, a stated choice (a hot
    #: pixel an order of magnitude above its neighbours); a measured sensor's histogram sets it.
    hot_pixel_mean_factor: float = 20.0
    #: How each pixel is read (:mod:`spectracam.sensor.readout`, issue 36): "single" (one read at the end of the
    #: exposure: the paper), "multiple_capture" (``readout_samples`` non-destructive reads, Liu & El Gamal 2001),
    #: "dual_gain", "split_pixel" or "bracketing".
    readout: str = "single"
    #: Non-destructive samples per exposure of ``multiple_capture``, N (Liu & El Gamal simulate 32; 8 keeps the
    #: frame rate of a 2000s column-parallel ADC).
    readout_samples: int = 8
    #: The photocurrent estimate of ``multiple_capture``: "wls" (the recursive weighted least-squares estimate with
    #: saturation and motion detection, Liu & El Gamal 2001/2003) or "last_sample" (the last sample before saturation
    #: divided by its time).
    readout_estimator: str = "wls"
    #: Motion detection of the "wls" estimate: a sample further than this many standard deviations from the
    #: prediction ends the estimate at the previous sample (Liu & El Gamal 2003).  0: no motion detection.
    motion_threshold_sigma: float = 4.0
    #: ``dual_gain``: the high conversion gain over the low one (the floating diffusion's extra capacitance switched
    #: out; 4 is typical of dual-conversion-gain pixels).  The low gain is ``conversion_gain_uV_per_e`` (full well).
    dual_gain_ratio: float = 4.0
    #: ``dual_gain``: the high-gain read is used while it is below this fraction of its own swing (``q_max/ratio``).
    dual_gain_switch: float = 0.9
    #: ``split_pixel``: the large photodiode's sensitivity over the small one's.
    split_ratio: float = 16.0
    #: ``split_pixel``: the small photodiode's full well as a fraction of ``q_max_e``.
    split_small_well_fraction: float = 0.25
    #: ``bracketing``: sequential exposures, each ``bracketing_ratio`` times shorter than the one before.
    bracketing_frames: int = 3
    bracketing_ratio: float = 8.0
    #: The merged high-dynamic-range word companded (piecewise linear, as automotive sensors output it) into this
    #: many bits, and expanded by the processing.  None: the merged word is written linear.
    companding_bits: int | None = None
    shot_noise: bool = True
    dark_current: bool = True
    read_noise: bool = True
    fpn: bool = True
    quantization: bool = True
    clipping: bool = True

    def validate(self) -> None:
        self.number("q_max_e", 1, 1e9, unit="e-")
        self.number("read_noise_e", 0, 1e6, unit="e-")
        if self.read_noise_uV is not None:
            self.number("read_noise_uV", 0, 1e6, unit="µV")
        self.number("dark_current_e_per_s_um2", 0, 1e9)
        # cooled scientific sensors run near −100 °C, automotive grade 0 up to 150 °C (AEC-Q100)
        self.number("temperature_C", -100, 150, unit="°C")
        self.number("dark_reference_C", -100, 150, unit="°C")
        self.choice("dark_current_law", DARK_CURRENT_LAWS)
        if self.dark_doubling_K is not None:
            self.number("dark_doubling_K", 0, 100, lo_open=True, unit="K")
        factor = self.dark_current_factor
        if not np.isfinite(factor) or factor * self.dark_current_e_per_s_um2 > 1e9:
            raise self.error("temperature_C", f"the {self.dark_current_law} law takes the dark current from "
                             f"{self.dark_current_e_per_s_um2:g} e-/s/µm² at {self.dark_reference_C:g} °C to "
                             f"{factor * self.dark_current_e_per_s_um2:.3g} there; allowed: at most 1e9 e-/s/µm² "
                             "(the dark_current_e_per_s_um2 bound)")
        self.integer("adc_bits", 1, 24)
        if self.black_level_DN is not None:
            self.number("black_level_DN", 0, 2 ** (self.adc_bits - 1), unit="DN")
        if self.adc_full_scale_V is not None:
            self.number("adc_full_scale_V", 0, 1000, lo_open=True, unit="V")
        self.number("fpn_fraction", 0, 1)
        self.choice("fpn_reading", FPN_READINGS)
        self.number("prnu_fraction", 0, 1)
        self.number("dsnu_fraction", 0, 10)
        self.number("column_fpn_fraction", 0, 1)
        if self.pattern_seed is not None:
            self.integer("pattern_seed", 0, 2**63 - 1)
        self.number("pixel_pitch_um", 0.1, 1000, unit="µm")
        self.number("fill_factor", 0, 1, lo_open=True)
        self.number("conversion_gain_uV_per_e", 0, lo_open=True)
        self.choice("shot_noise_model", SHOT_NOISE_MODELS)
        self.number("hot_pixel_fraction", 0, 1)
        self.number("hot_pixel_mean_factor", 0, 1e6)
        self.choice("readout", READOUT_NAMES)
        self.integer("readout_samples", 1, 1024)
        self.choice("readout_estimator", READOUT_ESTIMATORS)
        self.number("motion_threshold_sigma", 0, 1e3)
        self.number("dual_gain_ratio", 1, 1e3, lo_open=True)
        self.number("dual_gain_switch", 0, 1, lo_open=True)
        self.number("split_ratio", 1, 1e6, lo_open=True)
        self.number("split_small_well_fraction", 0, 1, lo_open=True)
        self.integer("bracketing_frames", 1, 16)
        self.number("bracketing_ratio", 1, 1e4, lo_open=True)
        if self.companding_bits is not None:
            self.integer("companding_bits", 8, 24)
        self.boolean(*NOISE_SOURCES, "clipping")

    @property
    def pixel_area_um2(self) -> float:
        """Photosensitive area A = pitch² × fill factor, µm²."""
        return self.pixel_pitch_um**2 * self.fill_factor

    @property
    def read_noise_rms_e(self) -> float:
        """The read noise in electrons rms: ``read_noise_uV / conversion_gain_uV_per_e`` when the read chain's noise
        is given in volts, else ``read_noise_e``; 0 with the read noise switched off."""
        if not self.read_noise:
            return 0.0
        return self.read_noise_e if self.read_noise_uV is None else self.read_noise_uV / self.conversion_gain_uV_per_e

    @property
    def dark_current_factor(self) -> float:
        """``I(T)/I(T_ref)``: the dark current at ``temperature_C`` over that at ``dark_reference_C``, by
        ``dark_current_law`` (exactly 1 at the reference)."""
        return dark_current_factor(self.dark_current_law, self.temperature_C, self.dark_reference_C,
                                   self.dark_doubling_K)

    @property
    def dark_rate_e_per_s(self) -> float:
        """Mean dark charge per second of one pixel, e⁻/s: density × photodiode area × the temperature's factor."""
        if not self.dark_current:
            return 0.0
        return self.dark_current_e_per_s_um2 * self.pixel_area_um2 * self.dark_current_factor

    @property
    def black_level_dn(self) -> float:
        """The pedestal, DN (see ``black_level_DN``)."""
        return float(2 ** (self.adc_bits - 5) if self.black_level_DN is None else self.black_level_DN)

    @property
    def adc_full_scale_v(self) -> float:
        """The ADC's full-scale input, V (see ``adc_full_scale_V``)."""
        if self.adc_full_scale_V is not None:
            return self.adc_full_scale_V
        n = 2**self.adc_bits
        return self.conversion_gain_uV_per_e * 1e-6 * self.q_max_e * n / (n - self.black_level_dn)

    @property
    def system_gain_dn_per_e(self) -> float:
        """K = 2ⁿ·g/V_fs, digital numbers per electron (EMVA 1288's system gain)."""
        return 2**self.adc_bits * self.conversion_gain_uV_per_e * 1e-6 / self.adc_full_scale_v

    @property
    def quantization_step_e(self) -> float:
        """Electrons per digital number, 1/K."""
        return 1.0 / self.system_gain_dn_per_e

    @property
    def fpn_rms_e(self) -> float:
        return self.fpn_fraction * self.q_max_e * FPN_READINGS[self.fpn_reading].rms_per_swing

    def off(self, *sources: str) -> SensorSpec:
        """A copy with the named noise sources (or ``clipping``) switched off (e.g. ``off("fpn", "read_noise")``).

        Parameters
        ----------
        *sources : str
            Names of :data:`NOISE_SOURCES` (``shot_noise``, ``dark_current``, ``read_noise``, ``fpn``,
            ``quantization``) or ``clipping``.

        Returns
        -------
        SensorSpec
            The same sensor with those switches False.

        Raises
        ------
        ConfigError
            A name that is not a switch.
        """
        for s in sources:
            if s not in (*NOISE_SOURCES, "clipping"):
                raise ConfigError("sensor", s, "not a switch; one of " + ", ".join((*NOISE_SOURCES, "clipping")))
        return self.replace(**{s: False for s in sources})


def noise_stream(seed: int, *stream: int) -> np.random.SeedSequence:
    """The seed sequence for one purpose (fixed pattern, a frame's temporal noise), from the one seed.

    Parameters
    ----------
    seed : int
        The capture's seed.
    *stream : int
        The purpose's path of integers (e.g. ``FPN_STREAM``, the sensor's index, the part).

    Returns
    -------
    numpy.random.SeedSequence
        ``SeedSequence([seed, *stream])``.
    """
    return np.random.SeedSequence([seed, *stream])


FPN_STREAM, TEMPORAL_STREAM = 1, 2
#: Pixels per independently seeded chunk: chunks run on all cores, and the result does not depend
#: on how many there are.
CHUNK_PX = 1 << 20


def _chunk_rng(seq: np.random.SeedSequence, i: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(seq.entropy, spawn_key=(*seq.spawn_key, i)))


def _pool():
    global _POOL
    if _POOL is None:
        from concurrent.futures import ThreadPoolExecutor

        # SPECTRACAM_THREADS: e.g. 1 in each worker process of a Dask cluster, which already has one per core
        _POOL = ThreadPoolExecutor(max_workers=int(os.environ.get("SPECTRACAM_THREADS") or os.cpu_count() or 1))
    return _POOL


_POOL = None


def _map_chunks(fn, n: int) -> None:
    """Run ``fn(i, slice)`` over the flat chunks of an n-pixel frame (NumPy releases the GIL)."""
    chunks = [(i, slice(a, min(a + CHUNK_PX, n))) for i, a in enumerate(range(0, n, CHUNK_PX))]
    if len(chunks) == 1:
        fn(*chunks[0])
    else:
        for f in [_pool().submit(fn, i, sl) for i, sl in chunks]:
            f.result()


class FixedPattern(NamedTuple):
    """One physical sensor's per-pixel non-uniformities (``None`` where absent): additive offset, e⁻
    (pixel and column FPN); PRNU gain; DSNU factor on the dark current."""

    offset_e: np.ndarray | None = None
    gain: np.ndarray | None = None
    dark_gain: np.ndarray | None = None


def _draw(seq, n: int, fill) -> np.ndarray:
    """``n`` float32 values, ``fill(rng, out)`` per chunk; value ``i`` of ``rng.standard_normal`` and
    ``rng.random`` is the counter-based draw ``i`` of ``seq`` (:class:`~spectracam.sensor.kernels.CounterRNG`),
    the same whatever the chunking, the number of threads and the backend."""
    out = np.empty(n, np.float32)
    _map_chunks(lambda i, sl: fill(CounterRNG(seq, sl.start), out[sl]), n)
    return out


def _normal_around_one(rms: float):
    def fill(rng, out):
        rng.standard_normal(out=out, dtype=np.float32)
        out *= np.float32(rms)
        out += np.float32(1.0)

    return fill


def fixed_pattern(sensor: SensorSpec, shape: tuple[int, int], seed: int, sensor_index: int = 0) -> FixedPattern:
    """The fixed pattern of one physical sensor: the same for every frame with this seed (or the
    sensor's ``pattern_seed``) and sensor index, different across pixels and sensors.  Every value
    is a counter-based draw of its pixel (:class:`~spectracam.sensor.kernels.CounterRNG`).

    Parameters
    ----------
    sensor : SensorSpec
        The sensor: its FPN, PRNU, DSNU, column FPN and hot-pixel settings, and its switches.
    shape : tuple of int
        ``(H, W)`` pixels.
    seed : int
        The capture's seed (the sensor's ``pattern_seed`` replaces it when set).
    sensor_index : int
        Which sensor of a multi-sensor camera (a prism's three): each has its own pattern.

    Returns
    -------
    FixedPattern
        The offsets (e⁻), PRNU gains and DSNU factors, each ``shape`` float32 or None where absent; all None
        with ``fpn`` off.
    """
    return fixed_pattern_parts(sensor, shape, seed, sensor_index, defer=False)[0]


class PixelDraw(NamedTuple):
    """One per-pixel part of a fixed pattern as a draw, for a kernel that makes it in its own pass:
    value ``i`` of the counter-based stream ``seq`` (N standard normal, U uniform on [0, 1)) gives
    ``scale``·N (``kind`` "offset", FPN reading ``std``), ``scale``·(U − ½) ("offset-bound"),
    1 + ``scale``·N ("gain", PRNU) or max(1 + ``scale``·N, 0) ("dark_gain", DSNU) — exactly the
    float32 values :func:`fixed_pattern` draws."""

    seq: np.random.SeedSequence
    kind: str
    scale: float


class PatternDraws(NamedTuple):
    """The parts of a fixed pattern left to the fused kernel (each a :class:`PixelDraw` or None)."""

    offset: PixelDraw | None = None
    gain: PixelDraw | None = None
    dark_gain: PixelDraw | None = None


def fixed_pattern_parts(sensor: SensorSpec, shape: tuple[int, int], seed: int, sensor_index: int = 0,
                        defer: bool = True) -> tuple[FixedPattern, PatternDraws]:
    """:func:`fixed_pattern` with its per-pixel parts left undrawn (``defer``; offsets only for the
    built-in FPN readings): returns the pattern — whose ``offset_e`` then holds only the column FPN,
    a row broadcast to ``shape``, or None — and the :class:`PatternDraws` the fused kernel makes.

    Parameters
    ----------
    sensor : SensorSpec
        The sensor, as for :func:`fixed_pattern`.
    shape : tuple of int
        ``(H, W)`` pixels.
    seed : int
        The capture's seed (the sensor's ``pattern_seed`` replaces it when set).
    sensor_index : int
        Which sensor of a multi-sensor camera.
    defer : bool
        Leave the per-pixel offset, PRNU gain and DSNU factor to the fused kernel (the DSNU is drawn here all the
        same when there are hot pixels); False: draw everything, as :func:`fixed_pattern`.

    Returns
    -------
    pattern : FixedPattern
        What is drawn here: offsets (e⁻), gains and dark-current factors, ``shape`` float32, or None.
    draws : PatternDraws
        The parts left to the fused kernel (None where drawn here or absent).
    """
    if sensor.pattern_seed is not None:
        seed = sensor.pattern_seed
    if not sensor.fpn:
        return FixedPattern(), PatternDraws()
    n = int(np.prod(shape))
    offset, offset_draw = _offset_part(sensor, shape, n, seed, sensor_index, defer)
    gain = gain_draw = None
    if sensor.prnu_fraction > 0:
        seq = noise_stream(seed, FPN_STREAM, sensor_index, 1)
        if defer:
            gain_draw = PixelDraw(seq, "gain", sensor.prnu_fraction)
        else:
            gain = _draw(seq, n, _normal_around_one(sensor.prnu_fraction)).reshape(shape)
    dark_gain, dark_draw = _dark_gain_part(sensor, shape, n, seed, sensor_index, defer)
    return FixedPattern(offset, gain, dark_gain), PatternDraws(offset_draw, gain_draw, dark_draw)


def _offset_part(sensor: SensorSpec, shape: tuple[int, int], n: int, seed: int, sensor_index: int,
                 defer: bool) -> tuple[np.ndarray | None, PixelDraw | None]:
    """The offset of :func:`fixed_pattern_parts`, e⁻: (pixel FPN plus column FPN as an array, or None; the pixel
    FPN as a :class:`PixelDraw` left to the fused kernel, or None)."""
    offset = draw = None
    if sensor.fpn_fraction > 0:
        reading = FPN_READINGS[sensor.fpn_reading]
        swing = sensor.fpn_fraction * sensor.q_max_e
        seq = noise_stream(seed, FPN_STREAM, sensor_index, 0)
        if defer and reading.draw in (_draw_std, _draw_bound):
            draw = PixelDraw(seq, "offset-bound" if reading.draw is _draw_bound else "offset", swing)
        else:
            offset = _draw(seq, n, lambda rng, out: reading.draw(rng, out, swing)).reshape(shape)
    if sensor.column_fpn_fraction > 0:
        cols = _draw(noise_stream(seed, FPN_STREAM, sensor_index, 2), shape[-1],
                     lambda rng, out: _draw_std(rng, out, sensor.column_fpn_fraction * sensor.q_max_e))
        if offset is not None:
            offset = offset + cols
        else:
            offset = np.broadcast_to(cols, shape)
            offset = offset if draw is not None else offset.copy()
    return offset, draw


def _dark_gain_part(sensor: SensorSpec, shape: tuple[int, int], n: int, seed: int, sensor_index: int,
                    defer: bool) -> tuple[np.ndarray | None, PixelDraw | None]:
    """The dark-current factor of :func:`fixed_pattern_parts`: (DSNU with the hot-pixel tail as an array, or None;
    the DSNU as a :class:`PixelDraw` left to the fused kernel — only without hot pixels —, or None)."""
    dark_gain = draw = None
    hot = sensor.hot_pixel_fraction > 0 and sensor.dark_current
    if sensor.dsnu_fraction > 0 and sensor.dark_current:
        seq = noise_stream(seed, FPN_STREAM, sensor_index, 3)
        if defer and not hot:
            draw = PixelDraw(seq, "dark_gain", sensor.dsnu_fraction)
        else:
            dark_gain = _draw(seq, n, _normal_around_one(sensor.dsnu_fraction))
            dark_gain = np.maximum(dark_gain, 0.0, out=dark_gain).reshape(shape)  # a dark current is never negative
    if hot:   # drawn here, beside the DSNU: the fused kernel takes the plane as it is
        tail = hot_pixel_excess(sensor, n, noise_stream(seed, FPN_STREAM, sensor_index, 4)).reshape(shape)
        dark_gain = tail + 1.0 if dark_gain is None else np.add(dark_gain, tail, out=dark_gain)
        # the stated dark current stays the mean over all pixels (as EMVA 1288 measures it): the tail redistributes
        dark_gain /= np.float32(1.0 + sensor.hot_pixel_fraction * sensor.hot_pixel_mean_factor)
    return dark_gain, draw


def hot_pixel_excess(sensor: SensorSpec, n: int, seq: np.random.SeedSequence) -> np.ndarray:
    """The dark-signal non-uniformity's tail: each pixel's extra dark current in multiples of the mean, float32.

    A pixel is hot with probability ``p = hot_pixel_fraction``; a hot pixel's excess is exponential with mean
    ``m = hot_pixel_mean_factor``; one uniform draw ``u`` per pixel decides both (``u < p``: hot, with excess
    ``−m·ln(u/p)``, since ``u/p`` is then uniform on (0, 1)).  The excess's mean is ``p·m`` and its variance
    ``p·m²·(2 − p)``.

    Parameters
    ----------
    sensor : SensorSpec
        The sensor (``hot_pixel_fraction`` p, ``hot_pixel_mean_factor`` m).
    n : int
        Pixels.
    seq : numpy.random.SeedSequence
        The counter-based stream of the uniform draws (value ``i``: pixel ``i``).

    Returns
    -------
    ndarray
        ``(n,)`` float32 excess dark current, multiples of the mean dark current; 0 for a pixel that is not hot.

    References
    ----------
    .. [EMVA1288] see docs/references.md; section 8.4, the logarithmic histogram of the dark signal.
    """
    p, m = np.float32(sensor.hot_pixel_fraction), np.float32(sensor.hot_pixel_mean_factor)

    def fill(rng, out):
        rng.random(out=out, dtype=np.float32)
        hot = out < p
        u = np.maximum(out, np.float32(1e-30))
        out[...] = np.where(hot, -m * np.log(u / p), np.float32(0.0))

    return _draw(seq, n, fill)


def dark_gain_moments(sensor: SensorSpec) -> tuple[float, float]:
    """Mean and variance across pixels of the dark-current factor: the DSNU's ``1`` and ``σ²`` (its clip at 0
    ignored) with the hot-pixel tail's ``p·m`` and ``p·m²·(2 − p)`` (:func:`hot_pixel_excess`), divided by the
    mean ``1 + p·m`` so that the stated dark current stays the mean of all pixels: ``(1, (σ² + p·m²·(2 − p)) /
    (1 + p·m)²)``; ``(1, 0)`` without the fixed pattern or the dark current.

    Parameters
    ----------
    sensor : SensorSpec
        The sensor (``dsnu_fraction`` σ, ``hot_pixel_fraction`` p, ``hot_pixel_mean_factor`` m, switches).

    Returns
    -------
    mean, variance : float
        Of the per-pixel dark-current factor (dimensionless; the mean is 1).
    """
    if not (sensor.fpn and sensor.dark_current):
        return 1.0, 0.0
    p, m = sensor.hot_pixel_fraction, sensor.hot_pixel_mean_factor
    return 1.0, (sensor.dsnu_fraction ** 2 + p * m * m * (2.0 - p)) / (1.0 + p * m) ** 2


class PatternRef(NamedTuple):
    """A physical sensor's fixed pattern before it is drawn: :meth:`draw` is :func:`fixed_pattern`;
    the fused capture takes :meth:`parts` and draws the per-pixel parts in its own pass."""

    sensor: SensorSpec
    shape: tuple[int, int]
    seed: int
    sensor_index: int = 0

    def draw(self) -> FixedPattern:
        return fixed_pattern(self.sensor, self.shape, self.seed, self.sensor_index)

    def parts(self) -> tuple[FixedPattern, PatternDraws]:
        return fixed_pattern_parts(self.sensor, self.shape, self.seed, self.sensor_index)


def integrate_charge(rate_e_per_s: np.ndarray, time_s: float, dark_e: float, gain: np.ndarray | None = None,
                     dark_gain: np.ndarray | None = None, out: np.ndarray | None = None) -> np.ndarray:
    """Expected charge ``ρ·T·g + i_d·A·T·d`` (paper 3.4; ``g`` the PRNU gain and ``d`` the DSNU
    factor of each pixel, 1 without them), e⁻.

    Parameters
    ----------
    rate_e_per_s : ndarray
        Photo-electron rates ρ, e⁻/s.
    time_s : float
        Exposure time T, s.
    dark_e : float
        Mean dark charge of the exposure ``i_d·A·T``, e⁻.
    gain : ndarray or None
        Each pixel's PRNU gain g (None: 1).
    dark_gain : ndarray or None
        Each pixel's DSNU factor d (None: 1).
    out : ndarray or None
        Where to write (None: a new array).

    Returns
    -------
    ndarray
        The expected charge, e⁻ (``out`` when given).
    """
    out = np.multiply(rate_e_per_s, np.float32(time_s), out=out)
    if gain is not None:
        out *= gain
    if dark_gain is None:
        out += np.float32(dark_e)
    else:
        out += np.float32(dark_e) * dark_gain
    return out


def add_shot_noise(mean_e: np.ndarray, out: np.ndarray, rng: np.random.Generator | CounterRNG,
                   model: str = "gaussian") -> np.ndarray:
    """Photon and dark-current shot noise on ``mean_e`` into ``out`` (registered ``model``).

    Parameters
    ----------
    mean_e : ndarray
        Expected charge, e⁻.
    out : ndarray
        Receives the noisy charge, e⁻ (float32, the shape of ``mean_e``).
    rng : numpy.random.Generator or CounterRNG
        The random numbers.
    model : str
        A name of :data:`SHOT_NOISE_MODELS`: ``"gaussian"`` (variance = mean, paper 3.4) or ``"poisson"``.

    Returns
    -------
    ndarray
        ``out``.
    """
    SHOT_NOISE_MODELS[model](mean_e, out, rng)
    return out


def clip_to_well(charge_e: np.ndarray, q_max_e: float) -> np.ndarray:
    """The well holds 0..q_max electrons (paper 3.4).

    Parameters
    ----------
    charge_e : ndarray
        Charge, e⁻; clipped in place.
    q_max_e : float
        Full-well capacity, e⁻.

    Returns
    -------
    ndarray
        ``charge_e``, clipped to ``[0, q_max_e]``.
    """
    return np.clip(charge_e, 0.0, q_max_e, out=charge_e)


def add_read_noise(charge_e: np.ndarray, rng: np.random.Generator | CounterRNG, read_noise_e: float) -> np.ndarray:
    """Gaussian read noise σ_r added on readout (paper 3.4: Q_r).

    Parameters
    ----------
    charge_e : ndarray
        Charge, e⁻ (float32); the noise is added in place.
    rng : numpy.random.Generator or CounterRNG
        The random numbers.
    read_noise_e : float
        σ_r, e⁻ rms.

    Returns
    -------
    ndarray
        ``charge_e``.
    """
    r = rng.standard_normal(charge_e.size, dtype=np.float32).reshape(charge_e.shape)
    r *= np.float32(read_noise_e)
    charge_e += r
    return charge_e


def add_offset_fpn(charge_e: np.ndarray, offset_e: np.ndarray) -> np.ndarray:
    """The pixel's fixed offset, V_FPN/g (paper 3.4).

    Parameters
    ----------
    charge_e : ndarray
        Charge, e⁻; the offset is added in place.
    offset_e : ndarray
        Each pixel's offset, e⁻ (:attr:`FixedPattern.offset_e`).

    Returns
    -------
    ndarray
        ``charge_e``.
    """
    charge_e += offset_e
    return charge_e


def adc_full_scale_dn(sensor: SensorSpec) -> float:
    """Largest output: code 2ⁿ − 1 when quantising, else the continuous full scale 2ⁿ; for a high-dynamic-range
    read-out, the top of its merged output word (:func:`spectracam.sensor.readout.output_top_dn`).

    Parameters
    ----------
    sensor : SensorSpec
        The sensor (``adc_bits``, ``quantization``, ``readout``).

    Returns
    -------
    float
        The largest digital number, DN.
    """
    if sensor.readout != "single":
        from spectracam.sensor.readout import output_top_dn

        return float(output_top_dn(sensor))
    return float(2**sensor.adc_bits - 1 if sensor.quantization else 2**sensor.adc_bits)


def adc(charge_e: np.ndarray, sensor: SensorSpec) -> np.ndarray:
    """n-bit uniform ADC, in place: ``DN = K·Q + black level``, floored to a code and clipped to
    ``0 … 2ⁿ − 1`` (the ADC clip; without quantisation the output is continuous, clipped to
    ``0 … 2ⁿ``).  With the default full scale the top code holds ``[q_max − 1/K, q_max)``.

    Parameters
    ----------
    charge_e : ndarray
        Charge, e⁻ (float32); overwritten with digital numbers.
    sensor : SensorSpec
        The sensor: system gain K, black level, ``adc_bits``, ``quantization`` and ``clipping``.

    Returns
    -------
    ndarray
        ``charge_e``, now digital numbers, DN.

    Examples
    --------
    >>> s = SensorSpec(q_max_e=256.0, adc_bits=8, black_level_DN=0.0)
    >>> adc(np.array([-3.0, 0.4, 1.0, 254.9, 300.0], np.float32), s).tolist()
    [0.0, 0.0, 1.0, 254.0, 255.0]
    """
    charge_e *= np.float32(sensor.system_gain_dn_per_e)
    charge_e += np.float32(sensor.black_level_dn)
    if sensor.quantization:
        np.floor(charge_e, out=charge_e)
    if sensor.clipping:
        np.clip(charge_e, 0.0, np.float32(adc_full_scale_dn(sensor)), out=charge_e)
    return charge_e


def adc_inverse(digital: np.ndarray, sensor: SensorSpec) -> np.ndarray:
    """Electrons from digital numbers: the black level removed, at mid-step, ``(DN − b + ½)/K`` (or
    ``(DN − b)/K`` when not quantised) — the least-error estimate for a uniform quantiser.

    Parameters
    ----------
    digital : ndarray
        Digital numbers, DN (a high-dynamic-range read-out's merged words: decoded by
        :func:`spectracam.sensor.readout.decode`).
    sensor : SensorSpec
        The sensor that recorded them.

    Returns
    -------
    ndarray
        Electrons, e⁻ (photo + dark charge, with the offset FPN still in it), the shape of ``digital``.

    Examples
    --------
    >>> s = SensorSpec(q_max_e=256.0, adc_bits=8, black_level_DN=8.0, adc_full_scale_V=256 * 5e-6)  # K = 1
    >>> adc_inverse(np.array([8.0, 18.0]), s).round(9).tolist()
    [0.5, 10.5]
    """
    if sensor.readout != "single":   # a merged high-dynamic-range word: the read-out's own inverse
        from spectracam.sensor.readout import decode

        return decode(digital, sensor)
    return (digital - sensor.black_level_dn + (0.5 if sensor.quantization else 0.0)) * sensor.quantization_step_e


def read_frame(photo_rate_e_per_s: np.ndarray, time_s: float, sensor: SensorSpec, noise: np.random.SeedSequence,
               pattern: FixedPattern = FixedPattern()) -> tuple[np.ndarray, np.ndarray]:
    """One frame read the way ``sensor.readout`` reads it: :func:`expose` for ``single`` (the paper), else the
    read-out scheme of :mod:`spectracam.sensor.readout` (its merged output word, which :func:`adc_inverse` decodes).

    Parameters
    ----------
    photo_rate_e_per_s : ndarray
        Photo-electrons per second per pixel, any shape.
    time_s : float
        Exposure time, s.
    sensor : SensorSpec
        The sensor; its ``readout`` picks the scheme.
    noise : numpy.random.SeedSequence
        Seeds this frame's temporal noise.
    pattern : FixedPattern
        The sensor's fixed pattern (default: none).

    Returns
    -------
    digital : ndarray
        Digital numbers (``single``) or merged output words, float32, the rates' shape.
    expected_e : ndarray
        The noise-free charge, photo + dark, e⁻, float32.
    """
    if sensor.readout == "single":
        return expose(photo_rate_e_per_s, time_s, sensor, noise, pattern)
    from spectracam.sensor.readout import read

    return read(np.ascontiguousarray(photo_rate_e_per_s, np.float32), time_s, sensor, noise, pattern)


def expose(photo_rate_e_per_s: np.ndarray, time_s: float, sensor: SensorSpec, noise: np.random.SeedSequence,
           pattern: FixedPattern = FixedPattern()) -> tuple[np.ndarray, np.ndarray]:
    """One exposure of one frame: (digital numbers, expected electrons without noise).

    Works in place, chunk by chunk, on all cores.

    Parameters
    ----------
    photo_rate_e_per_s : ndarray
        Photo-electrons per second, ``A·∫E_q·R_k dλ`` per pixel (paper, 3.3); any shape.
    time_s : float
        Exposure time, s.
    sensor : SensorSpec
        The sensor: dark current, well, noise sources and ADC.
    noise : numpy.random.SeedSequence
        Seeds this frame's temporal noise.
    pattern : FixedPattern
        The sensor's :class:`FixedPattern` (default: none).

    Returns
    -------
    digital : ndarray
        Digital numbers: float32 integers in ``[0, 2ⁿ − 1]`` (or continuous in ``[0, 2ⁿ]`` when quantisation is off).
    expected_e : ndarray
        Expected electrons: the noise-free charge, photo + dark, float32.  Both have the shape of the rates.

    References
    ----------
    .. [Catrysse1999] see docs/references.md; sections 3.3 and 3.4.
    .. [EMVA1288] see docs/references.md; the system gain K, DN per electron.
    """
    offset, gain, dark_gain = pattern
    shape = photo_rate_e_per_s.shape
    rate = np.ascontiguousarray(photo_rate_e_per_s, dtype=np.float32).reshape(-1)
    off = None if offset is None else offset.reshape(-1)
    g = None if gain is None else gain.reshape(-1)
    dg = None if dark_gain is None else dark_gain.reshape(-1)
    n = rate.size
    mean = np.empty(n, np.float32)
    q = np.empty(n, np.float32)
    dark = sensor.dark_rate_e_per_s * time_s

    def run(i, sl):
        rng = _chunk_rng(noise, i)
        m, out = mean[sl], q[sl]
        integrate_charge(rate[sl], time_s, dark, None if g is None else g[sl], None if dg is None else dg[sl], out=m)
        if sensor.shot_noise:
            add_shot_noise(m, out, rng, sensor.shot_noise_model)
        else:
            out[...] = m
        if sensor.clipping:
            clip_to_well(out, sensor.q_max_e)
        if sensor.read_noise_rms_e > 0:
            add_read_noise(out, rng, sensor.read_noise_rms_e)
        if off is not None:
            add_offset_fpn(out, off[sl])
        adc(out, sensor)

    _map_chunks(run, n)
    return q.reshape(shape), mean.reshape(shape)
