"""Figures: one place that selects matplotlib's file-only backend and saves PNG/SVG atomically."""
from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from spectracam.core.files import atomic_write

__all__ = ["pyplot", "save_figure", "srgb_image"]


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


def srgb_image(xyz: np.ndarray, display_white: np.ndarray) -> np.ndarray:
    """sRGB (0–1, encoded) of display-relative XYZ: the display white shown as D65 white."""
    import colour

    d65 = np.asarray(colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"])
    wxy = colour.XYZ_to_xy(display_white / display_white[1])
    M = np.asarray(colour.adaptation.matrix_chromatic_adaptation_VonKries(
        colour.xy_to_XYZ(wxy), colour.xy_to_XYZ(d65), transform="Bradford"))
    rgb = colour.XYZ_to_RGB(xyz @ M.T, "sRGB", apply_cctf_encoding=False)
    return np.clip(colour.cctf_encoding(np.clip(rgb, 0, 1), "sRGB"), 0, 1)
