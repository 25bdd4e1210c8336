"""When each channel integrates: exposure windows per architecture, and the rolling shutter.

The exposure *times* come from the registry's exposure schemes (:mod:`spectracam.sensor.exposure`: single,
optimal, balanced, metered on the white patch as in the paper); this module says *when* each of
them is open, dispatching on the architecture's layout as the rest of spectracam does:

* one mosaic (``cfa``) or three sensors exposed together (``prism``, ``PlanesLayout("sensors")``):
  simultaneous windows. With unequal times (``prism/optimal``) they either open together
  (``prism_alignment = "start"``: one shutter opens every sensor, each is read when full; the default,
  the simplest electronics) or share their middle (``"centre"``: the smallest colour shift);
* three frames of one sensor in sequence (``fsc``, ``PlanesLayout("frames")``): consecutive windows in
  ``order`` (default R, G, B, the architecture's frame order), each followed by a readout gap
  ``readout_gap_ms`` before the next frame opens (the sensor is read and the colour filter switches);
* ``rolling_shutter``: every row's windows are those of row 0 delayed by ``row × line_time_us``
  (rows read one after another, top to bottom), for every architecture.

Times are seconds with ``t = 0`` the middle of the whole capture (all rows), so designs of different
length are centred on the same instant and the scene's pose at ``t = 0`` is their common reference.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from spectracam.architecture.base import PlanesLayout
from spectracam.core.spec import Spec

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from spectracam.architecture.base import Architecture

PRISM_ALIGNMENTS = ("start", "centre")


@dataclass(frozen=True)
class TimingSpec(Spec):
    """How the exposure windows are placed in time."""

    TABLE = "timing"
    #: Order of a field-sequential camera's frames (the architecture's R, G, B).
    order: str = "RGB"
    #: Between two field-sequential frames: the frame is read and the tunable filter switches (an LC
    #: filter of the time switches in about a millisecond).
    readout_gap_ms: float = 1.0
    rolling_shutter: bool = False
    #: Row-to-row delay of a rolling shutter: a 1000-row CMOS sensor read in 30 ms (30 frames/s).
    line_time_us: float = 30.0
    prism_alignment: str = "start"

    def validate(self) -> None:
        if not isinstance(self.order, str) or sorted(self.order) != ["B", "G", "R"]:
            raise self.error("order", "must be a permutation of 'RGB', e.g. 'RGB' or 'GRB'")
        self.number("readout_gap_ms", 0.0, 1e4, unit="ms")
        self.boolean("rolling_shutter")
        self.number("line_time_us", 0.0, 1e5, unit="µs")
        self.choice("prism_alignment", PRISM_ALIGNMENTS)


@dataclass(frozen=True)
class CaptureTiming:
    """The windows of one capture: channel k of row r is open over
    ``[start_s[k] + row_delay_s[r], start_s[k] + row_delay_s[r] + duration_s[k]]``."""

    start_s: np.ndarray          # (N,) row 0, in the architecture's channel order
    duration_s: np.ndarray       # (N,)
    row_delay_s: np.ndarray      # (rows,)
    sequential: bool

    @property
    def span_s(self) -> tuple[float, float]:
        """First opening and last closing over every row."""
        return (float((self.start_s).min() + self.row_delay_s.min()),
                float((self.start_s + self.duration_s).max() + self.row_delay_s.max()))

    @property
    def capture_time_s(self) -> float:
        """Row 0's first opening to last closing (the architecture's capture time plus readout gaps)."""
        return float((self.start_s + self.duration_s).max() - self.start_s.min())

    def groups(self) -> list[tuple[int, ...]]:
        """Channels sharing one window (integrated once): e.g. ``[(0, 1, 2)]`` for a CFA."""
        out: dict = {}
        for k in range(len(self.start_s)):
            out.setdefault((round(float(self.start_s[k]), 12), round(float(self.duration_s[k]), 12)), []).append(k)
        return [tuple(v) for v in out.values()]

    def overlap_s(self, k: int, lo_s: np.ndarray, hi_s: np.ndarray) -> np.ndarray:
        """``(rows, n)`` seconds of each interval ``[lo, hi]`` inside channel k's window of each row.

        Parameters
        ----------
        k : int
            The channel.
        lo_s, hi_s : ndarray
            ``(n,)`` the intervals' ends, s (capture time, 0 at the capture's middle).

        Returns
        -------
        ndarray
            ``(rows, n)`` overlap, s, ≥ 0.
        """
        a = self.start_s[k] + self.row_delay_s[:, None]
        b = a + self.duration_s[k]
        return np.clip(np.minimum(b, np.asarray(hi_s)[None, :]) - np.maximum(a, np.asarray(lo_s)[None, :]), 0.0, None)

    def to_dict(self) -> dict:
        return {"start_ms": (1e3 * self.start_s).tolist(), "duration_ms": (1e3 * self.duration_s).tolist(),
                "row_delay_ms_first_last": [1e3 * float(self.row_delay_s[0]), 1e3 * float(self.row_delay_s[-1])],
                "sequential": self.sequential, "capture_time_ms": 1e3 * self.capture_time_s,
                "span_ms": [1e3 * x for x in self.span_s]}


def capture_timing(architecture: Architecture, times_s: ArrayLike, timing: TimingSpec, rows: int,
                   first_row: int = 0) -> CaptureTiming:
    """The windows of an architecture's capture with per-channel exposure ``times_s`` (N,), for image
    rows ``first_row … first_row + rows − 1`` (row 0 is read first; a negative first row is a margin
    above the image), centred so that the middle of the whole capture is ``t = 0``.

    Parameters
    ----------
    architecture : Architecture
        Field-sequential frames are exposed one after another in ``timing.order``; other channels together.
    times_s : array_like
        ``(N,)`` exposure times, s.
    timing : TimingSpec
        Read-out gap (ms), frame order, prism alignment, rolling shutter and line time (µs).
    rows : int
        How many rows.
    first_row : int
        The first row's index (negative: a margin above the image).

    Returns
    -------
    CaptureTiming
        Each channel's start and duration (s), each row's delay (s) and whether the frames are sequential.

    Examples
    --------

    >>> from spectracam.architecture.base import make_architecture
    >>> t = capture_timing(make_architecture("fsc"), [0.01, 0.02, 0.03], TimingSpec(readout_gap_ms=1.0), 1)
    >>> (1e3 * t.start_s).round(3).tolist(), round(1e3 * t.capture_time_s, 3)
    ([-31.0, -20.0, 1.0], 62.0)
    """
    T = np.asarray(times_s, float)
    layout = architecture.layout
    sequential = isinstance(layout, PlanesLayout) and layout.kind == "frames"
    start = np.zeros(T.size)
    if sequential:
        t = 0.0
        for c in timing.order:
            k = architecture.channels.index(c)
            start[k] = t
            t += T[k] + timing.readout_gap_ms * 1e-3
    elif timing.prism_alignment == "centre":
        start = (T.max() - T) / 2
    line = timing.line_time_us * 1e-6 if timing.rolling_shutter else 0.0
    delay = line * (first_row + np.arange(rows, dtype=float))
    lo, hi = start.min() + delay.min(), (start + T).max() + delay.max()
    mid = (lo + hi) / 2
    return CaptureTiming(start - mid, T.copy(), delay, sequential)


__all__ = ["CaptureTiming", "PRISM_ALIGNMENTS", "TimingSpec", "capture_timing"]
