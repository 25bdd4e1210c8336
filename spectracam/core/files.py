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
import errno
import os
import stat
import tempfile
from pathlib import Path
from typing import Callable, Iterator

__all__ = ["WriteError", "atomic_write", "json_default", "regular_file", "remove_unfinished",
           "stage_outputs", "staged", "staged_after", "user_cache_dir"]

_STAGES: list[dict] = []
#: Temporary files that exist right now (being written, or staged): what a signal handler removes.
_LIVE: set = set()


def user_cache_dir() -> Path:
    """spectracam's folder in the user's cache: ``$XDG_CACHE_HOME/spectracam`` (the XDG Base Directory
    specification's user cache, when set to an absolute path; a relative one is ignored), else
    ``~/.cache/spectracam``.  The render cache and the snapshot of colour-science's tables live below it.

    Returns
    -------
    Path
        The folder (not made here).
    """
    xdg = os.environ.get("XDG_CACHE_HOME", "")
    base = Path(xdg) if xdg and Path(xdg).is_absolute() else Path.home() / ".cache"
    return base / "spectracam"


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


#: What a path that is not a regular file is, by its ``stat`` type, for the one line that refuses it.
_NOT_REGULAR = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISSOCK, "a socket"),
                (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"), (stat.S_ISDIR, "a directory"))


def regular_file(path: str | Path, what: str) -> Path:
    """``path`` if it is a regular file (or a link to one), checked with ``stat.S_ISREG`` before anything
    opens it: every loader of a user's file (scene, sweep, design and config TOML, curve and camera CSVs,
    reflectances, EXRs, photographs, a directory's report.json for ``view``) calls this first.  A FIFO
    opened for reading blocks until a writer comes — a hang, not an error — and a device may never end:
    both are refused in one line (:class:`~spectracam.core.errors.ConfigError` naming ``what``, exit 2).  A path
    that does not exist is returned as is: the caller's own open says "no such file" in its words.

    Parameters
    ----------
    path : str or Path
        The user's file.
    what : str
        The field or option that named it, for the error.

    Returns
    -------
    Path
        ``path``.
    """
    from spectracam.core.errors import ConfigError

    p = Path(path)
    try:
        mode = os.stat(p).st_mode
    except (OSError, ValueError):
        return p
    if stat.S_ISREG(mode):
        return p
    kind = next((name for test, name in _NOT_REGULAR if test(mode)), "not a regular file")
    raise ConfigError(what, str(p), f"is {kind}, not a regular file; give a file")


class WriteError(OSError):
    """A file could not be written, whatever the writing library raised (OpenEXR raises RuntimeError
    on a full disk, tifffile struct.error on a field it cannot hold): one error path for every writer,
    which the command line reports in one line (exit 1) and the render cache survives."""


def atomic_write(path: str | Path, content: bytes | Callable[[str], object], now: bool = False) -> Path:
    """Write ``content`` to ``path`` atomically (a temporary file beside it, then a rename).

    Any failure of the writer is an :class:`OSError` naming the path; a target that is a directory is refused
    before writing.

    Parameters
    ----------
    path : str or Path
        The output file; missing parent directories are made.
    content : bytes or callable
        The bytes, or a function that writes the file at the (temporary) path it is given.
    now : bool
        Rename at once even inside :func:`staged` (a journal's header, which must survive an interruption).

    Returns
    -------
    Path
        ``path``.
    """
    path = Path(path)
    if path.is_dir():
        raise IsADirectoryError(21, "a directory is in the way of the output file", str(path))
    _make_parent(path)
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=path.suffix, dir=path.parent)
    _LIVE.add(tmp)
    done = False
    try:
        os.fchmod(fd, 0o666 & ~_umask())
        if isinstance(content, (bytes, bytearray)):
            try:
                with os.fdopen(fd, "wb") as f:
                    fd = None
                    f.write(content)
            except OSError as e:  # a full disk names no file: name the output
                raise OSError(e.errno, e.strerror or str(e), str(path)) from None
        else:
            os.close(fd)
            fd = None
            try:
                content(tmp)
            except (OSError, KeyboardInterrupt, SystemExit):
                raise
            except Exception as e:  # noqa: BLE001 - a library's own error type for an I/O failure
                first = (str(e).splitlines() or [type(e).__name__])[0].replace(tmp, str(path))
                raise WriteError(errno.EIO, f"{type(e).__name__}: {first}", str(path)) from None
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
def staged() -> Iterator[None]:
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
    # all or nothing: every target is checked before the first rename; a rename that still fails
    # removes what this stage already renamed (new files of this command) and every temporary file
    for tmp, path in stage["files"]:
        if Path(path).is_dir():
            _discard(stage, [])
            raise IsADirectoryError(21, "a directory is in the way of the output file", str(path))
    done = []
    try:
        for tmp, path in stage["files"]:
            os.replace(tmp, path)
            _LIVE.discard(tmp)
            done.append(path)
    except OSError:
        _discard(stage, done)
        raise


def stage_outputs() -> tuple[list, list]:
    """The running stage's files (their final paths) and the directories made for them."""
    stage = _STAGES[-1]
    return [Path(p) for _, p in stage["files"]], list(stage["dirs"])


@contextlib.contextmanager
def staged_after(outputs: tuple[list, list]) -> Iterator[None]:
    """A stage for files made from ``outputs`` (:func:`stage_outputs` of a stage just put in place): should
    it fail or a signal come, those outputs and their directories are removed too, so they and what is
    made from them (``--view``'s page) appear together or not at all.

    Parameters
    ----------
    outputs : tuple of (list, list)
        The files and the directories the earlier stage made (:func:`stage_outputs`).

    Yields
    ------
    None
        The block runs inside the new stage.
    """
    paths, dirs = outputs
    made = [str(p) for p in paths]
    _LIVE.update(made)  # remove_unfinished (a signal) takes them too
    try:
        with staged():
            _STAGES[-1]["dirs"][:0] = dirs  # removed once empty
            yield
    except BaseException:
        for p in made:
            with contextlib.suppress(OSError):
                os.unlink(p)
        for d in reversed(dirs):
            with contextlib.suppress(OSError):
                d.rmdir()
        raise
    finally:
        _LIVE.difference_update(made)


def _discard(stage: dict, renamed: list) -> None:
    for tmp, _ in stage["files"]:
        _LIVE.discard(tmp)
        with contextlib.suppress(OSError):
            os.unlink(tmp)
    for path in renamed:
        with contextlib.suppress(OSError):
            os.unlink(path)
    for d in reversed(stage["dirs"]):
        with contextlib.suppress(OSError):
            d.rmdir()


def json_default(o: object) -> object:
    """``json.dumps(default=)`` for NumPy scalars and arrays.

    Parameters
    ----------
    o : object
        What ``json`` cannot write itself.

    Returns
    -------
    object
        The Python scalar of a NumPy scalar, the nested list of an array; anything else raises ``TypeError``.
    """
    import numpy as np

    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(type(o).__name__)
