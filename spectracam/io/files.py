"""Writing files so that they appear complete or not at all, with the user's permissions.

Every file spectracam writes goes through :func:`atomic_write`: the content goes to a hidden
temporary file in the target directory, which is renamed over the target only when complete.
``mkstemp`` creates files readable by the owner only; the file is given the mode the user's umask
asks for (0644 under umask 022), as ``open()`` would.  Inside :func:`staged`, a command's files stay
under their temporary names until the command succeeds, then all are renamed together; on any error
or signal every temporary file (and every directory made for them) is removed, so a command's
outputs appear together or not at all.
"""
from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path
from typing import Callable

_STAGES: list[dict] = []
#: Temporary files that exist right now (being written, or staged): what a signal handler removes.
_LIVE: set = set()


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _make_parent(path: Path) -> None:
    missing = []
    p = path.parent
    while not p.exists():
        missing.append(p)
        p = p.parent
    path.parent.mkdir(parents=True, exist_ok=True)
    if _STAGES:
        _STAGES[-1]["dirs"].extend(reversed(missing))


def atomic_write(path: str | Path, content: bytes | Callable[[str], object], now: bool = False) -> Path:
    """Write ``content`` (bytes, or a function that writes a file at the path it is given) to
    ``path`` atomically; returns the path.  ``now``: rename at once even inside :func:`staged` (a
    journal's header, which must survive an interruption)."""
    path = Path(path)
    _make_parent(path)
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=path.suffix, dir=path.parent)
    _LIVE.add(tmp)
    done = False
    try:
        os.fchmod(fd, 0o666 & ~_umask())
        if isinstance(content, (bytes, bytearray)):
            with os.fdopen(fd, "wb") as f:
                fd = None
                f.write(content)
        else:
            os.close(fd)
            fd = None
            content(tmp)
        if _STAGES and not now:
            _STAGES[-1]["files"].append((tmp, path))
        else:
            os.replace(tmp, path)
            _LIVE.discard(tmp)
        done = True
    finally:
        if fd is not None:
            os.close(fd)
        if not done:
            _LIVE.discard(tmp)
            if os.path.exists(tmp):
                os.unlink(tmp)
    return path


def remove_unfinished() -> None:
    """Remove every temporary file and every directory made for staged files (a signal handler's
    last act before the process exits)."""
    for tmp in list(_LIVE):
        with contextlib.suppress(OSError):
            os.unlink(tmp)
    for stage in _STAGES:
        for d in reversed(stage["dirs"]):
            with contextlib.suppress(OSError):
                d.rmdir()


@contextlib.contextmanager
def staged():
    """All files written inside appear together when the block ends, or none (see the module doc)."""
    stage = {"files": [], "dirs": []}
    _STAGES.append(stage)
    try:
        yield
    except BaseException:
        for tmp, _ in stage["files"]:
            _LIVE.discard(tmp)
            with contextlib.suppress(OSError):
                os.unlink(tmp)
        for d in reversed(stage["dirs"]):
            with contextlib.suppress(OSError):
                d.rmdir()  # only if empty
        raise
    finally:
        _STAGES.pop()
    for tmp, path in stage["files"]:
        os.replace(tmp, path)
        _LIVE.discard(tmp)
