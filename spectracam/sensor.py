"""CMOS image sensor in current-integration mode (paper, sections 3.4 and 4.4).

Per pixel and channel: photo-electrons ``ρ·T`` plus dark electrons ``i_d·A·T`` integrate with
shot noise on a well that holds ``q_max`` electrons; read noise ``Q_r`` is added on readout; the
voltage ``V = g·Q + V_FPN`` (additive fixed-pattern noise) is quantised by an n-bit uniform ADC
whose full scale is the full well, ``g·q_max``.  Everything here is in electrons (``V/g``), so the
conversion gain only names the voltage scale.  Each noise source switches off on its own.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

FPN_READINGS = ("std", "bound")
SHOT_NOISE_MODELS = ("gaussian", "poisson")


@dataclass(frozen=True)
class SensorSpec:
    #: Full-well capacity, electrons (paper, 4.4).
    q_max_e: float = 131072.0
    #: Read noise σ_r, electrons rms (paper, 4.4).
    read_noise_e: float = 20.0
    #: Dark current density, electrons per second per µm² of photodiode (paper, 4.4).
    dark_current_e_per_s_um2: float = 10.0
    #: ADC resolution, bits (paper, 4.4).
    adc_bits: int = 8
    #: Offset fixed-pattern noise as a fraction of full swing (paper, 4.4: "FPN < 1 % full output swing").
    fpn_fraction: float = 0.01
    #: How to read "FPN < 1 %": "std" — the rms across pixels is that fraction (how datasheets quote
    #: FPN; the worst case the spec allows), or "bound" — every pixel's offset lies within a spread of
    #: that fraction (uniform, rms = fraction/√12).
    fpn_reading: str = "std"
    #: Gain FPN (PRNU), rms fraction of the signal; the paper ignores it (footnote §), so 0.
    prnu_fraction: float = 0.0
    #: Pixel pitch, µm.  The paper gives none; a full well of 131072 e⁻ at ~1300 e⁻/µm² suggests
    #: ~100 µm² of photodiode, i.e. a 10 µm pixel.
    pixel_pitch_um: float = 10.0
    #: Fraction of the pixel that collects light (microlenses make the effective value near 1).
    fill_factor: float = 1.0
    #: Conversion gain g, µV per electron (sets only the voltage scale of V = g·Q + V_FPN).
    conversion_gain_uV_per_e: float = 5.0
    #: "gaussian" (the paper's 3.4: variance = mean) or "poisson" (exact counting statistics).
    shot_noise_model: str = "gaussian"
    shot_noise: bool = True
    dark_current: bool = True
    read_noise: bool = True
    fpn: bool = True
    quantization: bool = True
    clipping: bool = True

    @property
    def pixel_area_um2(self) -> float:
        """Photosensitive area A = pitch² × fill factor, µm²."""
        return self.pixel_pitch_um**2 * self.fill_factor

    @property
    def dark_rate_e_per_s(self) -> float:
        return self.dark_current_e_per_s_um2 * self.pixel_area_um2 if self.dark_current else 0.0

    @property
    def quantization_step_e(self) -> float:
        """Electrons per digital number: q_max / 2ⁿ."""
        return self.q_max_e / 2**self.adc_bits

    @property
    def fpn_rms_e(self) -> float:
        swing = self.fpn_fraction * self.q_max_e
        return swing if self.fpn_reading == "std" else swing / np.sqrt(12.0)

    def off(self, *sources: str) -> "SensorSpec":
        """A copy with the named noise sources switched off (e.g. ``off("fpn", "read_noise")``)."""
        import dataclasses

        return dataclasses.replace(self, **{s: False for s in sources})


def noise_stream(seed: int, *stream: int) -> np.random.SeedSequence:
    """The seed sequence for one purpose (fixed pattern, a frame's temporal noise), from the one seed."""
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


def fixed_pattern(sensor: SensorSpec, shape: tuple[int, int], seed: int, sensor_index: int = 0):
    """Per-pixel offset (electrons) and gain of one physical sensor: the same for every frame and
    capture with this seed and sensor index, different across pixels and sensors."""
    offset = gain = None
    n = int(np.prod(shape))
    if sensor.fpn and sensor.fpn_fraction > 0:
        offset = np.empty(n, np.float32)
        seq = noise_stream(seed, FPN_STREAM, sensor_index, 0)
        swing = np.float32(sensor.fpn_fraction * sensor.q_max_e)

        def draw_offset(i, sl):
            rng = _chunk_rng(seq, i)
            if sensor.fpn_reading == "std":
                rng.standard_normal(out=offset[sl], dtype=np.float32)
                offset[sl] *= np.float32(sensor.fpn_rms_e)
            else:  # uniform over a spread of fpn_fraction of full swing
                rng.random(out=offset[sl], dtype=np.float32)
                offset[sl] -= np.float32(0.5)
                offset[sl] *= swing

        _map_chunks(draw_offset, n)
        offset = offset.reshape(shape)
    if sensor.fpn and sensor.prnu_fraction > 0:
        gain = np.empty(n, np.float32)
        seq = noise_stream(seed, FPN_STREAM, sensor_index, 1)

        def draw_gain(i, sl):
            _chunk_rng(seq, i).standard_normal(out=gain[sl], dtype=np.float32)
            gain[sl] *= np.float32(sensor.prnu_fraction)
            gain[sl] += np.float32(1.0)

        _map_chunks(draw_gain, n)
        gain = gain.reshape(shape)
    return offset, gain


def expose(photo_rate_e_per_s: np.ndarray, time_s: float, sensor: SensorSpec, noise: np.random.SeedSequence,
           pattern=(None, None)) -> tuple[np.ndarray, np.ndarray]:
    """One exposure of one frame.  Returns (digital numbers, expected electrons without noise).

    ``photo_rate_e_per_s`` is ``A·∫E_q·R_k dλ`` per pixel (paper, 3.3); ``noise`` seeds this frame's
    temporal noise; ``pattern`` is the sensor's ``(offset_e, gain)`` from :func:`fixed_pattern`.
    Digital numbers are float32 integers in ``[0, 2ⁿ − 1]`` (or unquantised ``V/step`` in
    ``[0, 2ⁿ]`` when quantisation is off).  Works in place, chunk by chunk, on all cores.
    """
    offset, gain = pattern
    shape = photo_rate_e_per_s.shape
    rate = np.ascontiguousarray(photo_rate_e_per_s, dtype=np.float32).reshape(-1)
    off = None if offset is None else offset.reshape(-1)
    g = None if gain is None else gain.reshape(-1)
    n = rate.size
    mean = np.empty(n, np.float32)
    q = np.empty(n, np.float32)
    t = np.float32(time_s)
    dark = np.float32(sensor.dark_rate_e_per_s * time_s)
    inv_step = np.float32(1.0 / sensor.quantization_step_e)
    # full scale (the full well) is 2ⁿ steps: the top code 2ⁿ − 1 holds [q_max − step, q_max);
    # without quantisation the output is the continuous V/step, clipped at full scale
    top = np.float32(2**sensor.adc_bits - 1 if sensor.quantization else 2**sensor.adc_bits)

    def run(i, sl):
        rng = _chunk_rng(noise, i)
        m, out = mean[sl], q[sl]
        np.multiply(rate[sl], t, out=m)
        if g is not None:
            m *= g[sl]
        m += dark
        if sensor.shot_noise:
            if sensor.shot_noise_model == "poisson":
                out[...] = rng.poisson(m)
            else:  # the paper's 3.4: Gaussian with variance = mean
                rng.standard_normal(out=out, dtype=np.float32)
                out *= np.sqrt(m)
                out += m
        else:
            out[...] = m
        if sensor.clipping:
            np.clip(out, 0.0, sensor.q_max_e, out=out)  # the well holds 0..q_max electrons
        if sensor.read_noise and sensor.read_noise_e > 0:
            r = rng.standard_normal(out.size, dtype=np.float32)
            r *= np.float32(sensor.read_noise_e)
            out += r
        if off is not None:
            out += off[sl]
        out *= inv_step  # V/(g·step): digital-number units
        if sensor.quantization:
            np.floor(out, out=out)
        if sensor.clipping:
            np.clip(out, 0.0, top, out=out)

    _map_chunks(run, n)
    return q.reshape(shape), mean.reshape(shape)
