"""Figures: one place that selects matplotlib's file-only backend and saves PNG/SVG atomically."""
from __future__ import annotations

import io
import sys
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np

from spectracam.core.files import atomic_write

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["FIGURE_DPI", "OKABE_ITO", "configure", "figure", "palette", "pyplot", "save_figure", "srgb_image"]

#: Every PNG figure's resolution, dots per inch (fit to print; the SVG beside it scales without limit).
FIGURE_DPI = 200
#: Okabe & Ito's eight colours, which stay distinct for readers with any common colour-vision deficiency
#: (docs/references.md [Okabe2008]); yellow last, since it is faint on white.  The default colour cycle of every
#: figure.
OKABE_ITO = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000", "#F0E442")


def palette(n: int) -> list[str]:
    """``n`` colours: :data:`OKABE_ITO` in order, repeated past eight (tell such lines apart by their markers).

    Parameters
    ----------
    n : int
        How many colours.

    Returns
    -------
    list of str
        ``n`` hexadecimal colours, ``"#RRGGBB"``.
    """
    return [OKABE_ITO[i % len(OKABE_ITO)] for i in range(n)]


def configure() -> ModuleType:
    """matplotlib on the Agg backend (no display needed), SVG text written as text (``svg.fonttype = "none"``:
    selectable, searchable, editable), not as glyph paths, and :data:`OKABE_ITO` as the colour cycle.

    Returns
    -------
    module
        ``matplotlib``.
    """
    import matplotlib

    matplotlib.use("Agg")
    matplotlib.rcParams["svg.fonttype"] = "none"
    from cycler import cycler

    matplotlib.rcParams["axes.prop_cycle"] = cycler(color=list(OKABE_ITO))
    return matplotlib


def pyplot() -> ModuleType:
    """matplotlib.pyplot, with :func:`configure`'s settings."""
    configure()
    import matplotlib.pyplot as plt

    return plt


def figure(**kwargs: object) -> Figure:
    """A figure made without pyplot (whose import, 0.3 s, a command that draws one figure need not pay), on the
    settings of :func:`configure`; :func:`save_figure` saves it like any other.

    Parameters
    ----------
    **kwargs
        :class:`matplotlib.figure.Figure`'s (``figsize``, ...).

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    configure()
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(**kwargs)
    FigureCanvasAgg(fig)   # the canvas pyplot's Agg backend would give it: draw() and get_renderer() work as there
    return fig


def save_figure(fig: Figure, *paths: str | Path, dpi: int | None = None, tight: bool = True) -> list[Path] | Path:
    """Save a figure in the format of each path's suffix (png, svg), atomically, then close it: PNGs at ``dpi``
    (default :data:`FIGURE_DPI`; a lower one only for a picture shown at its own pixel size, such as motion's
    per-case maps).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure; closed afterwards, also when a save fails.
    *paths : str or Path
        Where to write it; each suffix (``.png``, ``.svg``, ``.pdf``) names the format.
    dpi : int or None
        Dots per inch of raster formats; ``None``: :data:`FIGURE_DPI`.
    tight : bool
        Crop to the drawn content (``bbox_inches="tight"``).

    Returns
    -------
    Path or list of Path
        The path written, or the list of them when several are given.
    """
    dpi = FIGURE_DPI if dpi is None else dpi
    configure()
    out = []
    try:
        for path in map(Path, paths):
            buf = io.BytesIO()
            fig.savefig(buf, format=path.suffix.lstrip("."), dpi=dpi, **({"bbox_inches": "tight"} if tight else {}))
            out.append(atomic_write(path, buf.getvalue()))
    finally:
        if "matplotlib.pyplot" in sys.modules:   # a figure pyplot made is closed there; one made by figure() is not its
            sys.modules["matplotlib.pyplot"].close(fig)
    return out[0] if len(out) == 1 else out


def srgb_image(xyz: np.ndarray, display_white: np.ndarray) -> np.ndarray:
    """sRGB (0–1, encoded) of display-relative XYZ: the display white shown as D65 white.

    The white is adapted to D65 by the Bradford transform (von Kries form), then IEC 61966-2-1's sRGB primaries
    and encoding; values outside the gamut are clipped.

    Parameters
    ----------
    xyz : ndarray
        ``(..., 3)`` CIE 1931 XYZ on the display's scale (its white, at Y = 1, shows as sRGB white).
    display_white : ndarray
        ``(3,)`` XYZ of the display white.

    Returns
    -------
    ndarray
        ``(..., 3)`` encoded sRGB in 0–1.
    """
    import colour

    d65 = np.asarray(colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"])
    wxy = colour.XYZ_to_xy(display_white / display_white[1])
    M = np.asarray(colour.adaptation.matrix_chromatic_adaptation_VonKries(
        colour.xy_to_XYZ(wxy), colour.xy_to_XYZ(d65), transform="Bradford"))
    rgb = colour.XYZ_to_RGB(xyz @ M.T, "sRGB", apply_cctf_encoding=False)
    return np.clip(colour.cctf_encoding(np.clip(rgb, 0, 1), "sRGB"), 0, 1)
