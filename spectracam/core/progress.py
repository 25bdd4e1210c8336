"""Progress bars on stderr: drawn only when stderr is a terminal and progress is asked for (a command's
``--quiet`` turns them off), never when stderr is piped or redirected to a file.  Each long command has
one bar over its natural unit (bands, lights, cases, cells, readings, designs, iterations); a bar only
counts — it never changes how the work is split, so every number is the same with or without it.

A terminal whose size is unknown (a pseudo-terminal that was never given one: ``script`` run from a
pipe, ``docker exec -t``, CI runners, ``os.openpty()``) reports 0 × 0.  tqdm then takes −1 columns
and −1 rows and, at row −1, draws nothing at all — which is why a long render under such a terminal
printed only the lines before and after its bar.  :func:`bar` gives such a terminal 80 × 24.
"""
from __future__ import annotations

import os
import sys
from collections.abc import Callable, Iterable, Iterator
from typing import TYPE_CHECKING, Any, TypeVar

if TYPE_CHECKING:
    from tqdm import tqdm

T = TypeVar("T")

__all__ = ["DEFAULT_SIZE", "Counter", "bar", "close_bars", "duration_text", "note", "on_terminal"]

#: The size given to a terminal that reports none (0 × 0): the VT100's.
DEFAULT_SIZE = (80, 24)


def on_terminal(progress: bool = True) -> bool:
    """Should a bar be drawn: progress asked for, and stderr a terminal?

    Parameters
    ----------
    progress : bool
        Whether progress was asked for (False with ``--quiet``).

    Returns
    -------
    bool
        True when ``progress`` and stderr is a terminal.
    """
    try:
        return bool(progress) and sys.stderr is not None and sys.stderr.isatty()
    except (AttributeError, ValueError):  # a replaced or closed stderr
        return False


def _size() -> dict:
    """tqdm's ``ncols``/``nrows`` for a terminal that reports no size; nothing (tqdm asks) otherwise."""
    try:
        cols, rows = os.get_terminal_size(sys.stderr.fileno())
    except (OSError, AttributeError, ValueError):
        cols = rows = 0
    if cols > 0 and rows > 0:
        return {}
    return {"ncols": (cols if cols > 0 else DEFAULT_SIZE[0]) - 1, "nrows": rows if rows > 0 else DEFAULT_SIZE[1]}


def bar(iterable: Iterable | None = None, *, total: int | None = None, desc: str, unit: str, progress: bool = True,
        leave: bool = False, **kwargs: Any) -> tqdm:
    """A tqdm bar on stderr over ``iterable`` (or ``total`` steps, advanced with ``.update()``), disabled
    unless :func:`on_terminal`; cleared when done (``leave=False``): the command's own lines stay.

    Parameters
    ----------
    iterable : iterable or None
        What the bar iterates over; None: a bar advanced by hand.
    total : int or None
        The number of steps (default: ``len(iterable)`` where it has one).
    desc : str
        The bar's label.
    unit : str
        One step's name.
    progress : bool
        False: no bar at all (``--quiet``).
    leave : bool
        Keep the finished bar on the terminal.
    **kwargs : Any
        More of ``tqdm``'s options.

    Returns
    -------
    tqdm
        The bar (disabled, but still counting, where none is drawn).
    """
    from tqdm import tqdm

    enabled = on_terminal(progress)
    return tqdm(iterable, total=total, desc=desc, unit=unit, leave=leave, file=sys.stderr, disable=not enabled,
                dynamic_ncols=False, **(_size() if enabled else {}), **kwargs)


def note(msg: str) -> None:
    """One line on stderr that does not tear a bar being drawn (tqdm clears and redraws around it).

    Parameters
    ----------
    msg : str
        The line, without its newline.
    """
    tqdm = sys.modules.get("tqdm")
    if tqdm is not None and getattr(tqdm.tqdm, "_instances", None):
        tqdm.tqdm.write(msg, file=sys.stderr)
        return
    sys.stderr.write(msg + "\n")
    sys.stderr.flush()


def close_bars() -> None:
    """Close every bar still drawn (each clears its line), so that an error's one line starts a line."""
    tqdm = sys.modules.get("tqdm")
    for b in list(getattr(getattr(tqdm, "tqdm", None), "_instances", None) or ()):
        try:
            b.close()
        except Exception:  # noqa: BLE001 - a bar that cannot close must not hide the error being reported
            pass


def duration_text(seconds: float) -> str:
    """``"3 h 05 min"``, ``"12 min 40 s"``, ``"9 s"``: a time left, to the precision that matters.

    Parameters
    ----------
    seconds : float
        The time, s (rounded to whole seconds; below 0 reads 0).

    Returns
    -------
    str
        Hours and minutes from an hour up, minutes and seconds from a minute up, else seconds.
    """
    s = max(0, int(round(seconds)))
    if s >= 3600:
        return f"{s // 3600} h {s % 3600 // 60:02d} min"
    if s >= 60:
        return f"{s // 60} min {s % 60:02d} s"
    return f"{s} s"


class Counter:
    """Work counted toward a total, said so that a long run is never silent: on a terminal, a bar
    (:func:`bar`: done/total, rate, time left); with stderr piped or redirected (a log file, CI), where no
    bar is drawn, a line through ``log`` at most every ``every_s`` seconds —
    ``sweep cells: 1200 of 99999 cells, 45.1 cells/s, about 36 min 30 s left``.  Once, as soon as a rate is
    known (``estimate_after_s`` in, or after ``estimate_after_n`` units), it says the estimate up front
    (``sweep cells: 99999 cells, about 36 min (45.1 cells/s)``) when the work will take longer than
    ``announce_over_s``.  ``progress`` off (``--quiet``): nothing at all.  Like a bar, it only counts.

    Parameters
    ----------
    total : int
        How many units the work has.
    desc : str
        What is counted, the lines' and the bar's first words (``"sweep cells"``).
    unit : str
        One unit's name, singular (``"cell"``).
    log : callable or None
        Where the lines go (a function of one string); None: nowhere.
    progress : bool
        False (``--quiet``): no bar and no lines.
    initial : int
        Units already done (a resumed run).
    every_s : float
        The least time between two lines, s.
    estimate_after_s : float
        Time after the first update when the estimate is said, s (or after ``estimate_after_n`` units).
    estimate_after_n : int
        Units after the first update when the estimate is said.
    announce_over_s : float
        Say the estimate only for work estimated to take longer than this, s.
    """

    def __init__(self, total: int, *, desc: str, unit: str, log: Callable[[str], object] | None = None,
                 progress: bool = True, initial: int = 0,
                 every_s: float = 30.0, estimate_after_s: float = 2.0, estimate_after_n: int = 50,
                 announce_over_s: float = 10.0):
        import time

        self._clock = time.monotonic
        self.total, self.desc, self.unit = int(total), desc, unit
        self.done = self.initial = int(initial)
        self.log = log if (log is not None and progress) else (lambda msg: None)
        self.bar = bar(total=total, initial=initial, desc=desc, unit=unit, progress=progress)
        self.lines = bool(progress) and self.bar.disable   # no bar drawn: say it in lines
        self.every_s, self.announce_over_s = every_s, announce_over_s
        self.estimate_after_s, self.estimate_after_n = estimate_after_s, estimate_after_n
        self.t0 = self.last = self._clock()
        self.first: tuple | None = None   # (time, done) at the first update: the rate leaves out a warm-up
        self.announced = False

    def rate(self) -> float | None:
        """Units per second since the first unit was done (the first one pays for compiling and caches), or
        since the start while only one update has come; None before the first."""
        now = self._clock()
        if self.first is not None and self.done > self.first[1] and now > self.first[0]:
            return (self.done - self.first[1]) / (now - self.first[0])
        n, dt = self.done - self.initial, now - self.t0
        return n / dt if n > 0 and dt > 0 else None

    def left_s(self) -> float | None:
        r = self.rate()
        return (self.total - self.done) / r if r else None

    def update(self, n: int = 1) -> None:
        """Count ``n`` more units done; advance the bar, or say a line when one is due.

        Parameters
        ----------
        n : int
            Units just done.
        """
        self.done += n
        self.bar.update(n)
        now = self._clock()
        if self.first is None:
            self.first = (now, self.done)
            return
        left = self.left_s()
        if not self.announced and left is not None and (now - self.first[0] >= self.estimate_after_s
                                                        or self.done - self.first[1] >= self.estimate_after_n):
            self.announced = True
            if left > self.announce_over_s:
                self.log(f"{self.desc}: {self.total - self.done} {self.unit}s to go, estimated {duration_text(left)} "
                         f"({self._rate_text()})")
                self.last = now
        if self.lines and self.announced and now - self.last >= self.every_s and self.done < self.total:
            self.log(self.line())
            self.last = now

    def _rate_text(self) -> str:
        r = self.rate() or 0.0
        return f"{r:.3g} {self.unit}s/s" if r >= 1 else f"{1 / r:.3g} s a {self.unit}" if r > 0 else "no rate yet"

    def line(self) -> str:
        left = self.left_s()
        return (f"{self.desc}: {self.done} of {self.total} {self.unit}s, {self._rate_text()}"
                + (f", about {duration_text(left)} left" if left is not None else ""))

    def close(self) -> None:
        self.bar.close()

    def iterate(self, items: Iterable[T]) -> Iterator[T]:
        """``items``, each counted once the loop's body is done with it; closed when the loop ends.

        Parameters
        ----------
        items : iterable
            The work, one unit an item.

        Yields
        ------
        T
            Each item of ``items``.
        """
        try:
            for x in items:
                yield x
                self.update()
        finally:
            self.close()
