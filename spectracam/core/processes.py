"""Child processes die with the command: a signal that ends spectracam ends the processes it forked
(the paper's sensitivity workers, a sweep's local Dask cluster), and a child whose parent is gone
— killed with SIGKILL, which no handler sees — is killed by the kernel (Linux ``PR_SET_PDEATHSIG``)."""
from __future__ import annotations

import os
import signal
import time

__all__ = ["die_with_parent", "is_main", "mark_main", "terminate_children"]

#: The process that installed the command's signal handlers (children inherit the handler, not the role).
_MAIN_PID: list = []


def mark_main() -> None:
    """Record this process as the command's own (called where the signal handlers are installed)."""
    _MAIN_PID[:] = [os.getpid()]


def is_main() -> bool:
    return not _MAIN_PID or _MAIN_PID[0] == os.getpid()


def terminate_children(timeout_s: float = 2.0) -> None:
    """SIGTERM every child process this one started with multiprocessing, then SIGKILL what is left
    after ``timeout_s``; safe to call from a signal handler.

    Parameters
    ----------
    timeout_s : float
        How long the children together get to exit after SIGTERM, s.
    """
    try:
        import multiprocessing

        kids = multiprocessing.active_children()
    except Exception:  # noqa: BLE001 - never let the cleanup itself fail
        return
    for p in kids:
        try:
            p.terminate()
        except Exception:  # noqa: BLE001
            pass
    deadline = time.monotonic() + timeout_s
    for p in kids:
        try:
            p.join(max(0.0, deadline - time.monotonic()))
            if p.is_alive():
                p.kill()
                p.join(1.0)
        except Exception:  # noqa: BLE001
            pass


def die_with_parent() -> None:
    """In a forked worker: default signal actions, and SIGKILL from the kernel when the parent dies
    (Linux; elsewhere nothing)."""
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, signal.SIG_DFL)
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except Exception:  # noqa: BLE001 - not Linux
        pass
    if os.getppid() == 1:  # the parent died before prctl took effect
        os._exit(1)
