"""Writing files so that they appear complete or not at all, with the user's permissions.

Every file spectracam writes goes through :func:`atomic_write`: the content goes to a hidden
temporary file in the target directory, which is renamed over the target only when complete.
``mkstemp`` creates files readable by the owner only; the file is given the mode the user's umask
asks for (0644 under umask 022), as ``open()`` would.
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Callable


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def atomic_write(path: str | Path, content: bytes | Callable[[str], object]) -> Path:
    """Write ``content`` (bytes, or a function that writes a file at the path it is given) to
    ``path`` atomically; returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=path.suffix, dir=path.parent)
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
        os.replace(tmp, path)
    finally:
        if fd is not None:
            os.close(fd)
        if os.path.exists(tmp):
            os.unlink(tmp)
    return path
