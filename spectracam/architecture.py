"""Colour architectures (paper, section 2): how the three channels are sampled and timed.

An architecture turns per-channel photo-electron rates ``(H, W, 3)`` and per-channel exposure times
into recorded frames, and says what those frames are — its :class:`Layout`.  Later stages
(demosaicking, scoring, the EXR and DNG writers) dispatch on the layout, never on the
architecture's name, so a new architecture is one subclass registered in :data:`ARCHITECTURES`
(``@ARCHITECTURES.register("name")``), from any module.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

from . import kernels
from .filters import CHANNELS
from .registry import Registry
from .sensor import TEMPORAL_STREAM, PatternRef, SensorSpec, expose, noise_stream

#: Architectures: name → :class:`Architecture` subclass.
ARCHITECTURES: Registry = Registry("capture.architecture", "architecture")
CFA_PATTERNS = ("RGGB", "GRBG", "GBRG", "BGGR")
#: Whether the three channels' fixed patterns are one sensor's or three sensors': ``physical`` — as
#: the architecture is built (the prism's three sensors differ, field-sequential frames share one
#: sensor's); ``shared`` or ``independent`` to examine the other case.
FIXED_PATTERN_CHOICES = ("physical", "shared", "independent")


@dataclass(frozen=True)
class MosaicLayout:
    """One frame in which every pixel sees one channel, in a repeating tile of channel indices
    (0 R, 1 G, 2 B); ``(H, W)`` digital numbers.

    >>> MosaicLayout.bayer("GRBG").channel_index((2, 4)).tolist()
    [[1, 0, 1, 0], [2, 1, 2, 1]]
    """

    tile: tuple[tuple[int, ...], ...]

    @classmethod
    def bayer(cls, pattern: str) -> "MosaicLayout":
        """The 2×2 Bayer tile of a pattern such as ``"RGGB"`` (read row by row)."""
        k = [CHANNELS.index(c) for c in pattern]
        return cls(((k[0], k[1]), (k[2], k[3])))

    @property
    def tile_shape(self) -> tuple[int, int]:
        return len(self.tile), len(self.tile[0])

    @property
    def pattern(self) -> str:
        """The tile's channels as letters, row by row (``"RGGB"``; 16 letters for a 4×4 tile)."""
        return "".join(CHANNELS[k] for row in self.tile for k in row)

    @property
    def bayer_pattern(self) -> str | None:
        """The Bayer pattern name when the tile is a 2×2 Bayer tile, else ``None``."""
        return self.pattern if self.tile_shape == (2, 2) and self.pattern in CFA_PATTERNS else None

    def sites(self) -> list[tuple[int, int, int]]:
        """``(dy, dx, channel)`` of every site of the tile."""
        return [(dy, dx, k) for dy, row in enumerate(self.tile) for dx, k in enumerate(row)]

    def channel_index(self, shape: tuple[int, int]) -> np.ndarray:
        """``(H, W)`` channel index of every pixel."""
        th, tw = self.tile_shape
        h, w = shape
        return np.tile(np.asarray(self.tile), (-(-h // th), -(-w // tw)))[:h, :w]

    def sample(self, rates: np.ndarray) -> np.ndarray:
        """``(H, W)`` mosaic of an ``(H, W, 3)`` image: strided selection, no per-pixel work."""
        h, w, _ = rates.shape
        th, tw = self.tile_shape
        mosaic = np.empty((h, w), dtype=np.float32)
        for dy, dx, k in self.sites():
            mosaic[dy::th, dx::tw] = rates[dy::th, dx::tw, k]
        return mosaic


#: What three planes can be: sensors exposed together, or frames of one sensor in sequence.
PLANE_KINDS = ("sensors", "frames")


@dataclass(frozen=True)
class PlanesLayout:
    """Three full-resolution planes R, G, B, ``(3, H, W)`` digital numbers: three sensors exposed
    together (``"sensors"``) or three frames of one sensor in sequence (``"frames"``)."""

    kind: str
    description: str

    def __post_init__(self):
        if self.kind not in PLANE_KINDS:  # a mistyped kind would be timed and written as something else
            from .errors import SpectracamError

            raise SpectracamError(f"layout kind = {self.kind!r}: must be one of " + ", ".join(map(repr, PLANE_KINDS)))


class Architecture(ABC):
    """A way of sampling three colour channels.  Subclasses set ``name``, ``independent_exposures``
    and ``layout`` and implement :meth:`capture_time_s` and :meth:`record`."""

    name: str = ""
    #: Can each channel have its own exposure time?
    independent_exposures: bool = True
    #: Physical sensors the channels are recorded on (1 or 3).
    sensors: int = 1

    def __init__(self, cfa_pattern: str = "RGGB", fixed_pattern: str = "physical"):
        self.cfa_pattern, self.fixed_pattern = cfa_pattern, fixed_pattern

    def channel_patterns(self, sensor: SensorSpec, shape, seed: int, drawn: bool = True) -> list:
        """The fixed pattern each of the three channels is recorded with (see FIXED_PATTERN_CHOICES);
        ``drawn=False``: :class:`~spectracam.sensor.PatternRef` s, drawn where they are used (the
        fused capture draws the per-pixel parts in its own pass)."""
        independent = self.fixed_pattern == "independent" or (self.fixed_pattern == "physical" and self.sensors > 1)
        shape = tuple(shape)
        if independent:
            refs = [PatternRef(sensor, shape, seed, k) for k in range(3)]
        else:  # one sensor: one pattern, shared by the three channels
            refs = [PatternRef(sensor, shape, seed, 0)] * 3
        if drawn:
            return [r.draw() for r in refs] if independent else [refs[0].draw()] * 3
        return refs

    @property
    @abstractmethod
    def layout(self) -> MosaicLayout | PlanesLayout:
        """What the recorded frames are."""

    @abstractmethod
    def capture_time_s(self, times_s: np.ndarray) -> float:
        """Total time the capture takes, given the per-channel exposure times."""

    @abstractmethod
    def record(self, rates: np.ndarray, times_s: np.ndarray, sensor: SensorSpec, seed: int):
        """Returns ``(digital, expected_e)``: arrays of the architecture's layout."""

    def record_mosaic(self, rates, times_s, sensor, seed):
        """One exposure of one sensor behind a colour filter array of this architecture's layout.

        ``rates``: ``(H, W, 3)`` — an array, or a :class:`~spectracam.kernels.SpectralRates` whose
        cube the fused kernel reads once, weighting each pixel with its own channel only."""
        noise, pattern = noise_stream(seed, TEMPORAL_STREAM, 0), PatternRef(sensor, tuple(rates.shape[:2]), seed, 0)
        tile = getattr(self.layout, "tile", None)
        if tile is not None:
            out = kernels.record(rates, np.asarray(tile, np.int64)[None], times_s[:1], sensor, [noise], [pattern])
            if out is not None:
                return out[0][0], out[1][0]
        mosaic = self.layout.sample(rates)
        return expose(mosaic, times_s[0], sensor, noise, pattern.draw())

    @staticmethod
    def record_planes(rates, times_s, sensor, seed, patterns):
        """Three full-resolution exposures, channel k with fixed pattern ``patterns[k]`` (a
        :class:`~spectracam.sensor.FixedPattern` or a :class:`~spectracam.sensor.PatternRef`);
        returns ``(3, H, W)`` digital numbers and expected electrons.  The fused kernel records the
        three in one pass over the cube."""
        noises = [noise_stream(seed, TEMPORAL_STREAM, k) for k in range(3)]
        out = kernels.record(rates, np.arange(3, dtype=np.int64).reshape(3, 1, 1), times_s, sensor, noises, patterns)
        if out is not None:
            return out
        drawn = {}  # a pattern shared by channels is drawn once
        for p in patterns:
            if id(p) not in drawn:
                drawn[id(p)] = p.draw() if isinstance(p, PatternRef) else p
        rates = np.asarray(rates)
        out = [expose(np.ascontiguousarray(rates[:, :, k]), times_s[k], sensor, noises[k], drawn[id(patterns[k])])
               for k in range(3)]
        return np.stack([o[0] for o in out]), np.stack([o[1] for o in out])


@ARCHITECTURES.register("cfa")
class ColourFilterArray(Architecture):
    """One sensor, one exposure, a Bayer colour filter array (paper 2: CFA)."""

    name = "cfa"
    independent_exposures = False

    @property
    def layout(self):
        return MosaicLayout.bayer(self.cfa_pattern)

    def capture_time_s(self, times_s):
        return float(times_s[0])

    def record(self, rates, times_s, sensor, seed):
        return self.record_mosaic(rates, times_s, sensor, seed)


@ARCHITECTURES.register("prism")
class DichroicPrism(Architecture):
    """Three sensors behind a dichroic prism, exposed together, each with its own fixed pattern."""

    name = "prism"
    sensors = 3  # three physical sensors: three fixed patterns
    layout = PlanesLayout("sensors", "R, G, B: three sensors behind a dichroic prism, exposed together")

    def capture_time_s(self, times_s):
        return float(np.max(times_s))

    def record(self, rates, times_s, sensor, seed):
        return self.record_planes(rates, times_s, sensor, seed,
                                 self.channel_patterns(sensor, rates.shape[:2], seed, drawn=False))


@ARCHITECTURES.register("fsc")
class FieldSequential(Architecture):
    """One sensor, three exposures in sequence through a time-varying filter (paper 2: FSC)."""

    name = "fsc"
    layout = PlanesLayout("frames", "R, G, B: three exposures of one sensor in sequence, in this order")

    def capture_time_s(self, times_s):
        return float(np.sum(times_s))

    def record(self, rates, times_s, sensor, seed):  # one sensor: the same FPN in every frame
        return self.record_planes(rates, times_s, sensor, seed,
                                 self.channel_patterns(sensor, rates.shape[:2], seed, drawn=False))


def make_architecture(name: str, cfa_pattern: str = "RGGB", fixed_pattern: str = "physical") -> Architecture:
    """An instance of the registered architecture ``name``."""
    return ARCHITECTURES[name](cfa_pattern, fixed_pattern)
