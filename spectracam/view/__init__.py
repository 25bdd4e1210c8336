"""``spectracam view DIR``: one self-contained interactive page, DIR/index.html, for any output directory."""
from __future__ import annotations

from pathlib import Path

__all__ = ["write_view"]


def write_view(directory: str | Path, log=None) -> Path:
    """Write ``DIR/index.html`` for an output directory of any command (:mod:`.page`); returns its path."""
    from spectracam.view.page import write_page

    return write_page(Path(directory), log=log)
