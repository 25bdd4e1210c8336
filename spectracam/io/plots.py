"""Figures: one place that selects matplotlib's file-only backend and saves PNG/SVG atomically."""
from __future__ import annotations

import io
from pathlib import Path

from .files import atomic_write


def pyplot():
    """matplotlib.pyplot on the Agg backend (no display needed); SVG text is written as text
    (``svg.fonttype = "none"``: selectable, searchable, editable), not as glyph paths."""
    import matplotlib

    matplotlib.use("Agg")
    matplotlib.rcParams["svg.fonttype"] = "none"
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig, *paths: str | Path, dpi: int = 120, tight: bool = True) -> list[Path] | Path:
    """Save a figure in the format of each path's suffix (png, svg), atomically, then close it.
    Returns the path, or the list of paths when several are given."""
    plt = pyplot()
    out = []
    try:
        for path in map(Path, paths):
            buf = io.BytesIO()
            fig.savefig(buf, format=path.suffix.lstrip("."), dpi=dpi, **({"bbox_inches": "tight"} if tight else {}))
            out.append(atomic_write(path, buf.getvalue()))
    finally:
        plt.close(fig)
    return out[0] if len(out) == 1 else out
