"""One thread pool for every compiled kernel (the sensor's fused capture, the score's colour): bands of an index
range run on ``SPECTRACAM_THREADS`` threads (default: all cores).  The kernels release the GIL, and every value
they write depends on its index alone, so the bands decide only who computes what, never a number."""
from __future__ import annotations

import os
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from concurrent.futures import ThreadPoolExecutor

__all__ = ["fused_enabled", "njit_cached", "pool", "run_bands", "threads"]

_STATE: dict = {}


def fused_enabled() -> bool:
    """Whether the compiled kernels may run: ``SPECTRACAM_FUSED`` (read at every call) is not 0, no, false, off or
    numpy.  Off, the sensor takes its NumPy steps and the score colour-science's and colour-demosaicing's formulas."""
    return os.environ.get("SPECTRACAM_FUSED", "1").strip().lower() not in ("0", "no", "false", "off", "numpy")


def threads() -> int:
    """``SPECTRACAM_THREADS`` (default: all cores), read at every call."""
    return max(1, int(os.environ.get("SPECTRACAM_THREADS") or os.cpu_count() or 1))


def pool() -> ThreadPoolExecutor:
    """The kernels' thread pool; a new one in a forked child (the parent's threads are not there)."""
    if _STATE.get("pool_pid") != os.getpid():
        from concurrent.futures import ThreadPoolExecutor

        _STATE["pool"] = ThreadPoolExecutor(max_workers=max(threads(), os.cpu_count() or 1),
                                            thread_name_prefix="spectracam-kernels")
        _STATE["pool_pid"] = os.getpid()
    return _STATE["pool"]


def run_bands(fn: Callable[..., object], n: int, args_for: Callable[[int, int], tuple],
              parts: int | None = None) -> None:
    """``fn(*args_for(start, stop))`` over ``[0, n)`` split into ``parts`` bands (default: one per thread), each
    on the pool; returns when all are done and raises the first band's exception.

    Parameters
    ----------
    fn : callable
        The kernel (it releases the GIL and writes its band of the output).
    n : int
        The length of the index range.
    args_for : callable
        ``(start, stop)`` → the arguments of ``fn`` for that band.
    parts : int or None
        The number of bands; None: :func:`threads`; 1 runs in the calling thread.
    """
    parts = max(1, min(parts or threads(), n))
    if parts == 1:
        fn(*args_for(0, n))
        return
    bounds = [(n * k // parts, n * (k + 1) // parts) for k in range(parts)]
    for f in [pool().submit(fn, *args_for(a, b)) for a, b in bounds]:
        f.result()


def njit_cached(**kw: Any) -> Callable[[Callable], Callable]:
    """``numba.njit(cache=True, **kw)``, or without the on-disk cache where no cache directory can be used.

    Parameters
    ----------
    **kw : Any
        numba.njit's options (``parallel``, ``fastmath``, ``nogil``, …).

    Returns
    -------
    callable
        A decorator compiling a function with them.
    """
    import numba as nb

    def deco(fn):
        try:
            return nb.njit(cache=True, **kw)(fn)
        except RuntimeError:  # "cannot cache function ...: no locator available"
            return nb.njit(**kw)(fn)

    return deco
