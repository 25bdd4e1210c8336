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

#: The size given to a terminal that reports none (0 × 0): the VT100's.
DEFAULT_SIZE = (80, 24)


def on_terminal(progress: bool = True) -> bool:
    """Should a bar be drawn: progress asked for, and stderr a terminal?"""
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


def bar(iterable=None, *, total: int | None = None, desc: str, unit: str, progress: bool = True,
        leave: bool = False, **kwargs):
    """A tqdm bar on stderr over ``iterable`` (or ``total`` steps, advanced with ``.update()``), disabled
    unless :func:`on_terminal`; cleared when done (``leave=False``): the command's own lines stay."""
    from tqdm import tqdm

    enabled = on_terminal(progress)
    return tqdm(iterable, total=total, desc=desc, unit=unit, leave=leave, file=sys.stderr, disable=not enabled,
                dynamic_ncols=False, **(_size() if enabled else {}), **kwargs)


def note(msg: str) -> None:
    """One line on stderr that does not tear a bar being drawn (tqdm clears and redraws around it)."""
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
