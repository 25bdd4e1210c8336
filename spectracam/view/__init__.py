"""``spectracam view DIR``: one self-contained interactive page, DIR/index.html, for any output directory."""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Callable

__all__ = ["write_view"]


def write_view(directory: str | Path, log: Callable[[str], object] | None = None) -> Path:
    """Write ``DIR/index.html`` for an output directory of any command (:mod:`.page`); returns its path.

    Parameters
    ----------
    directory : str or Path
        An output directory a spectracam command wrote.
    log : callable or None
        Given one line (the page's path, size, cases and figures) once it is written; None: silent.

    Returns
    -------
    Path
        ``directory/index.html``.
    """
    from spectracam.view.page import write_page

    return write_page(Path(directory), log=log)
