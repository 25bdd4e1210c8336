"""Colour architectures (paper, section 2): how the three channels are sampled and timed.

An architecture turns per-channel photo-electron rates ``(H, W, 3)`` and per-channel exposure times
into recorded frames.  Add one by subclassing :class:`Architecture` and decorating it with
:func:`register`; nothing else needs editing.
"""
from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from .errors import SpectracamError
from .filters import CHANNELS
from .sensor import TEMPORAL_STREAM, SensorSpec, expose, fixed_pattern, noise_stream

ARCHITECTURES: dict[str, type["Architecture"]] = {}
CFA_PATTERNS = ("RGGB", "GRBG", "GBRG", "BGGR")


def bayer_sites(pattern: str) -> list[tuple[int, int, int]]:
    """``(dy, dx, channel)`` of the four sites of a 2×2 Bayer tile, channel 0 R, 1 G, 2 B."""
    return [(i // 2, i % 2, CHANNELS.index(c)) for i, c in enumerate(pattern)]


def register(cls):
    ARCHITECTURES[cls.name] = cls
    return cls


class Architecture(ABC):
    name: str = ""
    #: Can each channel have its own exposure time?
    independent_exposures: bool = True

    def __init__(self, cfa_pattern: str = "RGGB"):
        self.cfa_pattern = cfa_pattern

    @abstractmethod
    def capture_time_s(self, times_s: np.ndarray) -> float:
        """Total time the capture takes, given the per-channel exposure times."""

    @abstractmethod
    def record(self, rates: np.ndarray, times_s: np.ndarray, sensor: SensorSpec, seed: int):
        """Returns ``(digital, expected_e)``: arrays of the architecture's frame layout."""

    @staticmethod
    def expose_planes(rates, times_s, sensor, seed, patterns):
        """Three full-resolution exposures, channel k with fixed pattern ``patterns[k]``;
        returns ``(3, H, W)`` digital numbers and expected electrons."""
        out = [expose(np.ascontiguousarray(rates[:, :, k]), times_s[k], sensor, noise_stream(seed, TEMPORAL_STREAM, k),
                      patterns[k]) for k in range(3)]
        return np.stack([o[0] for o in out]), np.stack([o[1] for o in out])


@register
class ColourFilterArray(Architecture):
    name = "cfa"
    independent_exposures = False

    def capture_time_s(self, times_s):
        return float(times_s[0])

    def channel_index(self, shape: tuple[int, int]) -> np.ndarray:
        """``(H, W)`` channel index (0 R, 1 G, 2 B) of every pixel for this Bayer pattern."""
        tile = np.zeros((2, 2), dtype=int)
        for dy, dx, k in bayer_sites(self.cfa_pattern):
            tile[dy, dx] = k
        h, w = shape
        return np.tile(tile, ((h + 1) // 2, (w + 1) // 2))[:h, :w]

    def record(self, rates, times_s, sensor, seed):
        h, w, _ = rates.shape
        mosaic = np.empty((h, w), dtype=np.float32)
        for dy, dx, k in bayer_sites(self.cfa_pattern):  # strided selection, no per-pixel work
            mosaic[dy::2, dx::2] = rates[dy::2, dx::2, k]
        return expose(mosaic, times_s[0], sensor, noise_stream(seed, TEMPORAL_STREAM, 0),
                      fixed_pattern(sensor, (h, w), seed, 0))


@register
class DichroicPrism(Architecture):
    name = "prism"

    def capture_time_s(self, times_s):
        return float(np.max(times_s))

    def record(self, rates, times_s, sensor, seed):
        shape = rates.shape[:2]  # three physical sensors: three fixed patterns
        return self.expose_planes(rates, times_s, sensor, seed, [fixed_pattern(sensor, shape, seed, k) for k in range(3)])


@register
class FieldSequential(Architecture):
    name = "fsc"

    def capture_time_s(self, times_s):
        return float(np.sum(times_s))

    def record(self, rates, times_s, sensor, seed):
        pattern = fixed_pattern(sensor, rates.shape[:2], seed, 0)  # one sensor: the same FPN in every frame
        return self.expose_planes(rates, times_s, sensor, seed, [pattern] * 3)


def make_architecture(name: str, cfa_pattern: str = "RGGB") -> Architecture:
    if name not in ARCHITECTURES:
        raise SpectracamError(f"capture.architecture = {name!r}: must be one of {', '.join(ARCHITECTURES)}")
    if cfa_pattern not in CFA_PATTERNS:
        raise SpectracamError(f"capture.cfa_pattern = {cfa_pattern!r}: must be one of {', '.join(CFA_PATTERNS)}")
    return ARCHITECTURES[name](cfa_pattern)
