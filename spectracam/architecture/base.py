"""Colour architectures (paper, section 2): how the colour channels are sampled and timed.

An architecture says which channels it records and their spectral responsivities
(:meth:`Architecture.responsivities`: by default the three filters of ``[filters]``), turns
per-channel photo-electron rates ``(H, W, N)`` and per-channel exposure times into recorded frames,
and says what those frames are — its :class:`Layout`.  Later stages (demosaicking, scoring, the EXR
and DNG writers) dispatch on the layout, never on the architecture's name, so a new architecture is
one subclass registered in :data:`ARCHITECTURES` (``@ARCHITECTURES.register("name")``) in one file:
the paper's three are here, later ones in :mod:`spectracam.architecture` (every module there is
imported by the package face).

An architecture is described once, here: what it records (its layout), what its channels are made of
(:attr:`Architecture.primaries`: the three filters of ``[filters]``, alone, in pairs or none) and so
what the filter design (:mod:`spectracam.experiments.design`) can vary to shape them
(:meth:`Architecture.design_variables`); the design asks the architecture, never its name.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from spectracam.sensor import kernels
from spectracam.architecture.filters import CHANNELS, responsivities
from spectracam.core.registry import Registry
from spectracam.sensor import NOISE_SOURCES, TEMPORAL_STREAM, PatternRef, SensorSpec, noise_stream, read_frame

if TYPE_CHECKING:
    from spectracam.architecture.filters import FilterSpec
    from spectracam.camera import CameraSpec
    from spectracam.core.spectra import WavelengthGrid
    from spectracam.sensor import FixedPattern
    from spectracam.sensor.kernels import SpectralRates

__all__ = ["ARCHITECTURES", "CFA_PATTERNS", "FIXED_PATTERN_CHOICES", "PLANE_KINDS", "Architecture",
           "ColourFilterArray", "DichroicPrism", "FieldSequential", "MosaicArchitecture", "MosaicLayout",
           "PlanesLayout", "complementary", "make_architecture"]

#: Architectures: name → :class:`Architecture` subclass.
ARCHITECTURES: Registry = Registry("capture.architecture", "architecture")
CFA_PATTERNS = ("RGGB", "GRBG", "GBRG", "BGGR")
#: Whether the three channels' fixed patterns are one sensor's or three sensors': ``physical`` — as
#: the architecture is built (the prism's three sensors differ, field-sequential frames share one
#: sensor's); ``shared`` or ``independent`` to examine the other case.
FIXED_PATTERN_CHOICES = ("physical", "shared", "independent")


@dataclass(frozen=True)
class MosaicLayout:
    """One frame in which every pixel sees one channel, in a repeating tile of indices into
    ``channels`` (default R, G, B: 0 R, 1 G, 2 B); ``(H, W)`` digital numbers.

    >>> MosaicLayout.bayer("GRBG").channel_index((2, 4)).tolist()
    [[1, 0, 1, 0], [2, 1, 2, 1]]
    """

    tile: tuple[tuple[int, ...], ...]
    #: The channels' names, one letter each (a DNG CFA colour: R, G, B, C, M, Y or W).
    channels: tuple[str, ...] = CHANNELS

    @classmethod
    def bayer(cls, pattern: str) -> "MosaicLayout":
        """The 2×2 Bayer tile of a pattern such as ``"RGGB"`` (read row by row).

        Parameters
        ----------
        pattern : str
            Four of R, G, B, row by row.

        Returns
        -------
        MosaicLayout
            The layout of that tile.
        """
        k = [CHANNELS.index(c) for c in pattern]
        return cls(((k[0], k[1]), (k[2], k[3])))

    @property
    def tile_shape(self) -> tuple[int, int]:
        return len(self.tile), len(self.tile[0])

    @property
    def pattern(self) -> str:
        """The tile's channels as letters, row by row (``"RGGB"``; 16 letters for a 4×4 tile)."""
        return "".join(self.channels[k] for row in self.tile for k in row)

    @property
    def bayer_pattern(self) -> str | None:
        """The Bayer pattern of the tile's geometry when it is a 2×2 tile of three channels with
        channel 1 on a diagonal (``"RGGB"`` for R Y Y B too: a Bayer demosaicker needs only where the
        three lattices lie), else ``None``."""
        if self.tile_shape != (2, 2) or len(self.channels) != 3:
            return None
        geometry = "".join(CHANNELS[k] for row in self.tile for k in row)
        return geometry if geometry in CFA_PATTERNS else None

    def sites(self) -> list[tuple[int, int, int]]:
        """``(dy, dx, channel)`` of every site of the tile."""
        return [(dy, dx, k) for dy, row in enumerate(self.tile) for dx, k in enumerate(row)]

    def channel_index(self, shape: tuple[int, int]) -> np.ndarray:
        """``(H, W)`` channel index of every pixel.

        Parameters
        ----------
        shape : tuple of int
            ``(H, W)`` pixels.

        Returns
        -------
        ndarray
            ``(H, W)`` integer channel indices, the tile repeated from the top left.
        """
        th, tw = self.tile_shape
        h, w = shape
        return np.tile(np.asarray(self.tile), (-(-h // th), -(-w // tw)))[:h, :w]

    def sample(self, rates: np.ndarray) -> np.ndarray:
        """``(H, W)`` mosaic of an ``(H, W, 3)`` image: strided selection, no per-pixel work.

        Parameters
        ----------
        rates : ndarray
            ``(H, W, N)``, every channel at every pixel.

        Returns
        -------
        ndarray
            ``(H, W)`` float32, each pixel its own channel's value.
        """
        h, w, _ = rates.shape
        th, tw = self.tile_shape
        mosaic = np.empty((h, w), dtype=np.float32)
        for dy, dx, k in self.sites():
            mosaic[dy::th, dx::tw] = rates[dy::th, dx::tw, k]
        return mosaic


#: What three planes can be: sensors exposed together, or frames of one sensor in sequence.
PLANE_KINDS = ("sensors", "frames", "layers")


@dataclass(frozen=True)
class PlanesLayout:
    """Three full-resolution planes R, G, B, ``(3, H, W)`` digital numbers: three sensors exposed
    together (``"sensors"``, each with its own registration), frames of one sensor in sequence
    (``"frames"``), or photodiodes stacked in every pixel, exposed together (``"layers"``: registered by
    construction)."""

    kind: str
    description: str
    #: The planes' channels, in order.
    channels: tuple[str, ...] = CHANNELS

    def __post_init__(self):
        if self.kind not in PLANE_KINDS:  # a mistyped kind would be timed and written as something else
            from spectracam.core.errors import SpectracamError

            raise SpectracamError(f"layout kind = {self.kind!r}: must be one of " + ", ".join(map(repr, PLANE_KINDS)))


class Architecture(ABC):
    """A way of sampling colour channels.  Subclasses set ``name``, ``independent_exposures``
    and ``layout`` and implement :meth:`capture_time_s` and :meth:`record`; one whose channels are
    made of the three filters of ``[filters]`` otherwise than one each says how in :attr:`primaries`, and
    one whose channels are not made of them at all implements :meth:`responsivities` (and, to be
    designed, :meth:`design_variables`).

    Parameters
    ----------
    cfa_pattern : str
        The Bayer phase, one of :data:`CFA_PATTERNS` (a mosaic's tile follows it).
    fixed_pattern : str
        One of :data:`FIXED_PATTERN_CHOICES`: ``"physical"`` (one pattern per physical sensor), ``"shared"``
        (one for every channel) or ``"independent"`` (one per channel).
    """

    name: str = ""
    #: Can each channel have its own exposure time?
    independent_exposures: bool = True
    #: Physical sensors the channels are recorded on (1 or 3).
    sensors: int = 1
    #: What each channel is made of, in the channels' order, from the three filters R, G, B of ``[filters]``
    #: (× QE × IR cut): one of them (``"R"``), two passed together (``"RG"``: yellow, ``"GB"``: cyan, ``"RB"``:
    #: magenta — the sum, capped at the unfiltered pixel, :func:`complementary`) or none (``"W"``: the unfiltered
    #: pixel).  What :meth:`responsivities` computes, and what the filter design models.
    primaries: tuple[str, ...] = CHANNELS

    def __init__(self, cfa_pattern: str = "RGGB", fixed_pattern: str = "physical"):
        self.cfa_pattern, self.fixed_pattern = cfa_pattern, fixed_pattern

    def configure(self, camera: CameraSpec) -> "Architecture":
        """This architecture as ``camera`` (a :class:`~spectracam.camera.CameraSpec`) builds it: an
        architecture whose channels depend on the camera (the number of stacked layers) returns a
        configured copy; by default itself.

        Parameters
        ----------
        camera : CameraSpec
            The camera.

        Returns
        -------
        Architecture
            Itself, or a configured copy.
        """
        return self

    @property
    def channels(self) -> tuple[str, ...]:
        """The recorded channels' names, in the order of the rates and exposure times."""
        return self.layout.channels

    def responsivities(self, filters: FilterSpec, grid: WavelengthGrid) -> np.ndarray:
        """``(N, n_bands)`` band-averaged responsivities of the channels, electrons per photon (paper
        3.3): the three filters of ``[filters]`` × QE × IR cut, combined as :attr:`primaries` says.

        Parameters
        ----------
        filters : FilterSpec
            The ``[filters]`` table (filters, QE, IR cut).
        grid : WavelengthGrid
            The bands.

        Returns
        -------
        ndarray
            ``(N, n_bands)``, electrons per photon.
        """
        R = responsivities(filters, grid)
        if tuple(self.primaries) == CHANNELS:
            return R
        combined = [p for p in self.primaries if p not in CHANNELS]
        rows = dict(zip(combined, complementary(R, filters, grid, *combined)))
        return np.stack([R[CHANNELS.index(p)] if p in CHANNELS else rows[p] for p in self.primaries])

    @classmethod
    def design_variables(cls) -> str | None:
        """What the filter design (:mod:`spectracam.experiments.design`) varies to shape this architecture's
        channels: ``"filters"`` — the three filters of ``[filters]``, each channel made of them as
        :attr:`primaries` says — when its channels are those :meth:`responsivities` makes of them; ``None`` when
        an architecture computes its channels its own way, which the design cannot model (it refuses it by
        name).  Stacked photodiodes answer ``"depths"``."""
        return "filters" if cls.responsivities is Architecture.responsivities else None

    def channel_patterns(self, sensor: SensorSpec, shape: tuple[int, int], seed: int, drawn: bool = True) -> list:
        """The fixed pattern each of the channels is recorded with (see FIXED_PATTERN_CHOICES);
        ``drawn=False``: :class:`~spectracam.sensor.PatternRef` s, drawn where they are used (the
        fused capture draws the per-pixel parts in its own pass).

        Parameters
        ----------
        sensor : SensorSpec
            The sensor (its fixed-pattern noise).
        shape : tuple of int
            ``(H, W)`` pixels.
        seed : int
            The capture's seed.
        drawn : bool
            Draw the patterns now (:class:`~spectracam.sensor.FixedPattern`) or leave them references.

        Returns
        -------
        list
            One pattern (or reference) per channel; channels on one sensor share one object.
        """
        independent = self.fixed_pattern == "independent" or (self.fixed_pattern == "physical" and self.sensors > 1)
        shape, n = tuple(shape), len(self.channels)
        if independent:
            refs = [PatternRef(sensor, shape, seed, k) for k in range(n)]
        else:  # one sensor: one pattern, shared by the channels
            refs = [PatternRef(sensor, shape, seed, 0)] * n
        if drawn:
            return [r.draw() for r in refs] if independent else [refs[0].draw()] * n
        return refs

    @property
    @abstractmethod
    def layout(self) -> MosaicLayout | PlanesLayout:
        """What the recorded frames are."""

    @abstractmethod
    def capture_time_s(self, times_s: np.ndarray) -> float:
        """Total time the capture takes, given the per-channel exposure times.

        Parameters
        ----------
        times_s : ndarray
            ``(N,)`` exposure times, s.

        Returns
        -------
        float
            The capture time, s (the sum of sequential exposures, the longest of simultaneous ones).
        """

    @abstractmethod
    def record(self, rates: np.ndarray | SpectralRates, times_s: np.ndarray, sensor: SensorSpec,
               seed: int) -> tuple[np.ndarray, np.ndarray]:
        """Returns ``(digital, expected_e)``: arrays of the architecture's layout.

        Parameters
        ----------
        rates : ndarray or SpectralRates
            ``(H, W, N)`` photo-electron rates, e⁻/s, of every channel at every pixel (or the spectral rates the
            fused kernel weights itself).
        times_s : ndarray
            ``(N,)`` exposure times, s (a mosaic uses the first).
        sensor : SensorSpec
            The sensor.
        seed : int
            The capture's seed (fixed pattern and temporal noise).

        Returns
        -------
        digital, expected_e : ndarray
            Digital numbers (DN) and the expected charge (e⁻): ``(H, W)`` for a mosaic, ``(N, H, W)`` for planes.
        """

    def record_mosaic(self, rates: np.ndarray | SpectralRates, times_s: np.ndarray, sensor: SensorSpec,
                      seed: int) -> tuple[np.ndarray, np.ndarray]:
        """One exposure of one sensor behind a colour filter array of this architecture's layout.

        Parameters
        ----------
        rates : ndarray or SpectralRates
            ``(H, W, 3)`` e⁻/s — an array, or a :class:`~spectracam.sensor.kernels.SpectralRates` whose cube the
            fused kernel reads once, weighting each pixel with its own channel only.
        times_s : ndarray
            Exposure times, s; the first is used.
        sensor : SensorSpec
            The sensor.
        seed : int
            The capture's seed.

        Returns
        -------
        digital, expected_e : ndarray
            ``(H, W)`` digital numbers (DN) and expected charge (e⁻).
        """
        noise, pattern = noise_stream(seed, TEMPORAL_STREAM, 0), PatternRef(sensor, tuple(rates.shape[:2]), seed, 0)
        tile = getattr(self.layout, "tile", None)
        if tile is not None and sensor.readout == "single":   # the fused pass reads once; other read-outs: their own
            out = kernels.record(rates, np.asarray(tile, np.int64)[None], times_s[:1], sensor, [noise], [pattern])
            if out is not None:
                return out[0][0], out[1][0]
        mosaic = self._site_rates(rates, tile)
        return read_frame(mosaic, times_s[0], sensor, noise, pattern.draw())

    def _site_rates(self, rates, tile) -> np.ndarray:
        """``(H, W)`` the photo-electron rate of each pixel's own channel: the fused pass with every noise source,
        the dark current and the clips off for one second (its expected charge is then the rate, exactly), so the
        cube is read once and only each site's channel is weighted; else the layout's strided selection."""
        if tile is not None:
            quiet = SensorSpec().off(*NOISE_SOURCES, "clipping")
            out = kernels.record(rates, np.asarray(tile, np.int64)[None], np.ones(1), quiet,
                                 [noise_stream(0, TEMPORAL_STREAM, 0)], [PatternRef(quiet, tuple(rates.shape[:2]), 0)])
            if out is not None:
                return out[1][0]
        return self.layout.sample(rates)

    @staticmethod
    def record_planes(rates: np.ndarray | SpectralRates, times_s: np.ndarray, sensor: SensorSpec, seed: int,
                      patterns: list[FixedPattern | PatternRef]) -> tuple[np.ndarray, np.ndarray]:
        """Full-resolution exposures, channel k with fixed pattern ``patterns[k]`` (a
        :class:`~spectracam.sensor.FixedPattern` or a :class:`~spectracam.sensor.PatternRef`);
        returns ``(N, H, W)`` digital numbers and expected electrons.  The fused kernel records up to
        three in one pass over the cube.

        Parameters
        ----------
        rates : ndarray or SpectralRates
            ``(H, W, N)`` photo-electron rates, e⁻/s, of every channel at every pixel (or the spectral rates the
            fused kernel weights itself).
        times_s : ndarray
            ``(N,)`` exposure times, s one per channel.
        sensor : SensorSpec
            The sensor.
        seed : int
            The capture's seed (fixed pattern and temporal noise).
        patterns : list
            One fixed pattern (or reference) per channel.

        Returns
        -------
        digital, expected_e : ndarray
            ``(N, H, W)`` digital numbers (DN) and expected charge (e⁻).
        """
        n = len(patterns)
        noises = [noise_stream(seed, TEMPORAL_STREAM, k) for k in range(n)]
        out = None if sensor.readout != "single" else kernels.record(
            rates, np.arange(n, dtype=np.int64).reshape(n, 1, 1), times_s, sensor, noises, patterns)
        if out is not None:
            return out
        drawn = {}  # a pattern shared by channels is drawn once
        for p in patterns:
            if id(p) not in drawn:
                drawn[id(p)] = p.draw() if isinstance(p, PatternRef) else p
        rates = np.asarray(rates)
        out = [read_frame(np.ascontiguousarray(rates[:, :, k]), times_s[k], sensor, noises[k], drawn[id(patterns[k])])
               for k in range(n)]
        return np.stack([o[0] for o in out]), np.stack([o[1] for o in out])


class MosaicArchitecture(Architecture):
    """One sensor, one exposure, behind a colour filter array: a subclass gives its tile (indices
    into its channel names) for a Bayer phase ``cfa_pattern`` and, unless the channels are the three
    filters of ``[filters]``, their responsivities."""

    independent_exposures = False
    channel_names: tuple[str, ...] = CHANNELS

    def tile_for(self, cfa_pattern: str) -> tuple[tuple[int, ...], ...]:
        """The tile for a Bayer phase (default: the 2×2 Bayer geometry, channel 1 on the diagonal).

        Parameters
        ----------
        cfa_pattern : str
            One of :data:`CFA_PATTERNS`.

        Returns
        -------
        tuple of tuple of int
            The tile's channel indices, row by row.
        """
        return MosaicLayout.bayer(cfa_pattern).tile

    @property
    def layout(self):
        return MosaicLayout(self.tile_for(self.cfa_pattern), self.channel_names)

    def capture_time_s(self, times_s: np.ndarray) -> float:
        return float(times_s[0])

    def record(self, rates: np.ndarray | SpectralRates, times_s: np.ndarray, sensor: SensorSpec,
               seed: int) -> tuple[np.ndarray, np.ndarray]:
        return self.record_mosaic(rates, times_s, sensor, seed)


def complementary(R: np.ndarray, filters: FilterSpec, grid: WavelengthGrid, *pairs: str) -> np.ndarray:
    """Responsivities of filters that pass what two of the primaries R, G, B of ``R`` ``(3, B)`` pass
    together (``"RG"``: yellow, ``"GB"``: cyan, ``"RB"``: magenta) or everything (``"W"``: no
    filter), ``(len(pairs), B)``: the sum, capped at the unfiltered pixel's QE × IR cut (no dye
    transmits more than 1).  For the paper's block filters these are exact complements.

    Parameters
    ----------
    R : ndarray
        ``(3, B)`` responsivities of R, G, B, electrons per photon.
    filters : FilterSpec
        The ``[filters]`` table (the unfiltered pixel's QE × IR cut).
    grid : WavelengthGrid
        The bands.
    *pairs : str
        ``"RG"``, ``"GB"``, ``"RB"`` or ``"W"``.

    Returns
    -------
    ndarray
        ``(len(pairs), B)``, electrons per photon.
    """
    from spectracam.architecture.filters import clear_responsivity

    clear = clear_responsivity(filters, grid)
    rows = []
    for pair in pairs:
        rows.append(clear if pair == "W" else np.minimum(sum(R[CHANNELS.index(c)] for c in pair), clear))
    return np.stack(rows)


@ARCHITECTURES.register("cfa")
class ColourFilterArray(MosaicArchitecture):
    """One sensor, one exposure, a Bayer colour filter array (paper 2: CFA)."""

    name = "cfa"


@ARCHITECTURES.register("prism")
class DichroicPrism(Architecture):
    """Three sensors behind a dichroic prism, exposed together, each with its own fixed pattern."""

    name = "prism"
    sensors = 3  # three physical sensors: three fixed patterns
    layout = PlanesLayout("sensors", "R, G, B: three sensors behind a dichroic prism, exposed together")

    def capture_time_s(self, times_s: np.ndarray) -> float:
        return float(np.max(times_s))

    def record(self, rates: np.ndarray | SpectralRates, times_s: np.ndarray, sensor: SensorSpec,
               seed: int) -> tuple[np.ndarray, np.ndarray]:
        return self.record_planes(rates, times_s, sensor, seed,
                                 self.channel_patterns(sensor, rates.shape[:2], seed, drawn=False))


@ARCHITECTURES.register("fsc")
class FieldSequential(Architecture):
    """One sensor, three exposures in sequence through a time-varying filter (paper 2: FSC)."""

    name = "fsc"
    layout = PlanesLayout("frames", "R, G, B: three exposures of one sensor in sequence, in this order")

    def capture_time_s(self, times_s: np.ndarray) -> float:
        return float(np.sum(times_s))

    def record(self, rates: np.ndarray | SpectralRates, times_s: np.ndarray, sensor: SensorSpec,
               seed: int) -> tuple[np.ndarray, np.ndarray]:  # one sensor: the same FPN in every frame
        return self.record_planes(rates, times_s, sensor, seed,
                                 self.channel_patterns(sensor, rates.shape[:2], seed, drawn=False))


def make_architecture(name: str, cfa_pattern: str = "RGGB", fixed_pattern: str = "physical") -> Architecture:
    """An instance of the registered architecture ``name``.

    Parameters
    ----------
    name : str
        A name in :data:`ARCHITECTURES`.
    cfa_pattern : str
        The Bayer phase (mosaics).
    fixed_pattern : str
        One of :data:`FIXED_PATTERN_CHOICES`.

    Returns
    -------
    Architecture
        The instance (not yet configured for a camera: :meth:`Architecture.configure`).
    """
    return ARCHITECTURES[name](cfa_pattern, fixed_pattern)
