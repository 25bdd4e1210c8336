"""CMOS image sensor in current-integration mode (paper, sections 3.4 and 4.4).

Per pixel and channel: photo-electrons ``ρ·T`` plus dark electrons ``i_d·A·T`` integrate with
shot noise on a well that holds ``q_max`` electrons; read noise ``Q_r`` is added on readout; the
voltage ``V = g·Q + V_FPN`` (additive fixed-pattern noise) is quantised by an n-bit uniform ADC
whose full scale is the full well, ``g·q_max``.  Everything here is in electrons (``V/g``), so the
conversion gain only names the voltage scale.  Each noise source switches off on its own.
"""
from __future__ import annotations

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


def rng_for(seed: int, *stream: int) -> np.random.Generator:
    """An independent generator for one purpose, derived from the one seed (NumPy SeedSequence)."""
    return np.random.default_rng(np.random.SeedSequence([seed, *stream]))


FPN_STREAM, TEMPORAL_STREAM = 1, 2


def fixed_pattern(sensor: SensorSpec, shape: tuple[int, int], seed: int, sensor_index: int = 0):
    """Per-pixel offset (electrons) and gain of one physical sensor: the same for every frame and
    capture with this seed and sensor index, different across pixels and sensors."""
    rng = rng_for(seed, FPN_STREAM, sensor_index)
    offset = gain = None
    if sensor.fpn and sensor.fpn_fraction > 0:
        if sensor.fpn_reading == "std":
            offset = rng.standard_normal(shape, dtype=np.float32) * np.float32(sensor.fpn_rms_e)
        else:
            offset = (rng.random(shape, dtype=np.float32) - np.float32(0.5)) * np.float32(sensor.fpn_fraction * sensor.q_max_e)
    if sensor.fpn and sensor.prnu_fraction > 0:
        gain = 1 + rng.standard_normal(shape, dtype=np.float32) * np.float32(sensor.prnu_fraction)
    return offset, gain


def expose(photo_rate_e_per_s: np.ndarray, time_s: float, sensor: SensorSpec, rng: np.random.Generator,
           pattern=(None, None)) -> tuple[np.ndarray, np.ndarray]:
    """One exposure of one frame.  Returns (digital numbers, expected electrons without noise).

    ``photo_rate_e_per_s`` is ``A·∫E_q·R_k dλ`` per pixel (paper, 3.3); ``pattern`` is the sensor's
    ``(offset_e, gain)`` from :func:`fixed_pattern`.  Digital numbers are float32 integers in
    ``[0, 2ⁿ − 1]`` (or unquantised ``V/step`` when quantisation is off).
    """
    offset, gain = pattern
    t = np.float32(time_s)
    mean = photo_rate_e_per_s * t
    if gain is not None:
        mean *= gain
    mean += np.float32(sensor.dark_rate_e_per_s * time_s)
    if sensor.shot_noise:
        if sensor.shot_noise_model == "poisson":
            q = rng.poisson(mean).astype(np.float32)
        else:
            q = rng.standard_normal(mean.shape, dtype=np.float32)
            q *= np.sqrt(mean)
            q += mean
    else:
        q = mean.copy()
    if sensor.clipping:
        np.clip(q, 0.0, sensor.q_max_e, out=q)  # the well holds 0..q_max electrons
    if sensor.read_noise and sensor.read_noise_e > 0:
        q += rng.standard_normal(q.shape, dtype=np.float32) * np.float32(sensor.read_noise_e)
    if offset is not None:
        q += offset
    q *= np.float32(1.0 / sensor.quantization_step_e)  # V/(g·step): digital-number units
    if sensor.quantization:
        np.floor(q, out=q)
    if sensor.clipping:
        np.clip(q, 0.0, 2**sensor.adc_bits - 1, out=q)
    return q, mean
