"""Per-case outputs of the motion experiment: what each design showed at each speed and shutter.

* ``images/<design>_<speed>px-per-ms_<shutter>.exr`` — the displayed image (first noise seed) as linear
  RGB of the display in half floats, with the parameters that made it in its header
  (:func:`spectracam.io.report.write_display_exr`: ``spectracamParameters``, ``spectracamSeed``);
* the same name ``.png`` — its sRGB rendering, one pixel per pixel (:func:`spectracam.io.plots.srgb_image`);
* ``maps/scielab_<speed>px-per-ms.png`` — one figure per speed: the S-CIELAB ΔE*ab map of every design and
  shutter against that design's own noise-free still capture (what motion and noise add), all on one
  colour scale — the 99.5th percentile of the figure's maps, at least :data:`MAP_VMIN_TOP` — so that the
  designs compare within the figure; the scale is stated in the colour bar's label. One figure per speed
  rather than one per case: the question is which design breaks up at a given speed, and per-case
  figures each with their own colour bar would neither compare nor be few enough to look at.
"""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from spectracam.processing.color import display_rgb_to_xyz
from spectracam.io.plots import pyplot, save_figure, srgb_image
from spectracam.io.report import write_display_exr, write_png

if TYPE_CHECKING:
    from collections.abc import Iterable

    from numpy.typing import ArrayLike

    from spectracam.experiments.motion.experiment import MotionRow

#: Lowest top of a map figure's colour scale, ΔE*ab (about one just-noticeable difference): a figure
#: of near-zero maps (a still capture against itself) is not stretched to show rounding.
MAP_VMIN_TOP = 1.0
#: Percentile of the figure's map values that tops the colour scale (a few hot pixels do not set it).
MAP_PERCENTILE = 99.5


def case_stem(design: str, speed_px_per_ms: float, rolling: bool) -> str:
    """``fsc-optimal_0.01px-per-ms_global``: the file name of a case, without its suffix.

    Parameters
    ----------
    design : str
        ``architecture/exposure``.
    speed_px_per_ms : float
        The image speed, px/ms.
    rolling : bool
        Rolling shutter (else global).

    Returns
    -------
    str
    """
    return f"{design.replace('/', '-')}_{speed_px_per_ms:g}px-per-ms_{'rolling' if rolling else 'global'}"


def map_name(speed_px_per_ms: float) -> str:
    """The file name of one speed's S-CIELAB map figure, ``scielab_<speed>px-per-ms.png``.

    Parameters
    ----------
    speed_px_per_ms : float
        px/ms.

    Returns
    -------
    str
    """
    return f"scielab_{speed_px_per_ms:g}px-per-ms.png"


def case_parameters(result: dict, row: MotionRow) -> dict:
    """Everything that made a case's displayed image: the case, its exposure windows, the seed shown,
    the experiment's parameters (motion, calibrated scene, geometry) and the renderer.

    Parameters
    ----------
    result : dict
        The motion run's result.
    row : MotionRow
        The case.

    Returns
    -------
    dict
        JSON-ready; stored in the case's EXR.
    """
    p = result["parameters"]
    key = f"{row.design}{' rolling' if row.rolling_shutter else ''}"
    full = row.to_dict()
    case = {k: full[k] for k in ("design", "speed_px_per_ms", "speed_mm_per_s", "rolling_shutter", "blur_px",
                                "capture_time_ms", "exposure_ms", "slices", "slice_dt_ms", "samples_per_slice")}
    return {"what": "the displayed image of the moving edge (the first noise seed's capture)", "case": case,
            "exposure_timing": result["exposure_timing"].get(key), "seed": int(row.seeds[0]),
            "processing": p["scene"]["processing"], "renderer": result["renderer"], **p}


def write_case_images(result: dict, out: Path) -> list[Path]:
    """``images/<case>.exr`` and ``.png`` for every case kept in ``result["images"]``.

    Parameters
    ----------
    result : dict
        The motion run's result (its ``images``: display XYZ per case).
    out : Path
        The output directory.

    Returns
    -------
    list of Path
        Two files per kept case: linear display RGB (EXR, with :func:`case_parameters`) and sRGB (PNG).
    """
    white = np.asarray(result["display_white"], float)
    xyz_to_rgb = np.linalg.inv(display_rgb_to_xyz(result["parameters"]["scene"]["processing"]["display"]))
    paths = []
    for row in result["rows"]:
        im = result["images"].get((row.design, row.speed_px_per_ms, row.rolling_shutter))
        if im is None:
            continue
        stem = case_stem(row.design, row.speed_px_per_ms, row.rolling_shutter)
        rgb = np.asarray(im["xyz"], float) @ xyz_to_rgb.T          # linear display RGB, white = 1
        paths.append(write_display_exr(out / "images" / f"{stem}.exr", rgb, case_parameters(result, row)))
        srgb = srgb_image(np.asarray(im["xyz"], float), white)
        paths.append(write_png(out / "images" / f"{stem}.png", (srgb * 255 + 0.5).astype(np.uint8)))
    return paths


def map_scale(maps: Iterable[ArrayLike]) -> float:
    """The top of a figure's colour scale: the :data:`MAP_PERCENTILE` of its maps' values, at least
    :data:`MAP_VMIN_TOP`.

    Parameters
    ----------
    maps : iterable of array_like
        The S-CIELAB ΔE maps of one figure (non-finite values ignored).

    Returns
    -------
    float
        ΔE*ab.
    """
    values = np.concatenate([np.asarray(m, float).ravel() for m in maps])
    values = values[np.isfinite(values)]
    return max(MAP_VMIN_TOP, float(np.percentile(values, MAP_PERCENTILE))) if values.size else MAP_VMIN_TOP


def _zone_outline(ax, zone: np.ndarray) -> None:
    """The zone's left and right boundary in each row, as two lines (cheaper than a contour)."""
    rows = np.arange(zone.shape[0])
    any_ = zone.any(axis=1)
    first = np.where(any_, zone.argmax(axis=1) - 0.5, np.nan)
    last = np.where(any_, zone.shape[1] - zone[:, ::-1].argmax(axis=1) - 0.5, np.nan)
    for x in (first, last):
        ax.plot(x, rows, color="#4fc3f7", lw=0.9)


def figure_map(result: dict, speed_px_per_ms: float, out: Path) -> list[Path]:
    """``maps/scielab_<speed>px-per-ms.png``: every design (columns) and shutter (rows) at one speed.

    Parameters
    ----------
    result : dict
        The motion run's result.
    speed_px_per_ms : float
    out : Path

    Returns
    -------
    list of Path
        The figure written; empty when no case at this speed kept its images.
    """
    plt = pyplot()
    rows = [r for r in result["rows"] if r.speed_px_per_ms == speed_px_per_ms
            and (r.design, r.speed_px_per_ms, r.rolling_shutter) in result["images"]]
    if not rows:
        return []
    designs = list(dict.fromkeys(r.design for r in rows))
    shutters = sorted({r.rolling_shutter for r in rows})
    images = {(r.design, r.rolling_shutter): result["images"][(r.design, speed_px_per_ms, r.rolling_shutter)]
              for r in rows}
    vmax = map_scale(im["scielab"] for im in images.values())
    # a fixed layout (no constrained layout, no tight box): a map figure is made per speed, so it must be quick
    w_in, h_in = 3.0 * len(designs) + 1.6, 3.3 * len(shutters) + 0.9
    fig, axes = plt.subplots(len(shutters), len(designs), figsize=(w_in, h_in), squeeze=False,
                             gridspec_kw=dict(left=0.1 / w_in, right=1 - 1.5 / w_in, bottom=0.1 / h_in,
                                              top=1 - 0.9 / h_in, wspace=0.06, hspace=0.25))
    cmap = plt.get_cmap("magma").with_extremes(bad="#d0d0d0")
    shown = None
    for i, rolling in enumerate(shutters):
        for j, d in enumerate(designs):
            ax = axes[i, j]
            ax.set_xticks([]), ax.set_yticks([])
            if (d, rolling) not in images:
                ax.set_axis_off()
                continue
            im = images[(d, rolling)]
            shown = ax.imshow(im["scielab"], cmap=cmap, vmin=0.0, vmax=vmax, interpolation="nearest")
            _zone_outline(ax, im["zone"])
            ax.set_xlim(-0.5, im["zone"].shape[1] - 0.5), ax.set_ylim(im["zone"].shape[0] - 0.5, -0.5)
            ax.set_title(f"{d}, {'rolling' if rolling else 'global'} shutter\nmean in the zone "
                         f"{np.nanmean(im['scielab'][im['zone']]):.2f} (first seed)", fontsize=10)
    cax = fig.add_axes((1 - 1.25 / w_in, 0.1 / h_in + 0.05, 0.16 / w_in, 1 - 1.0 / h_in - 0.1))
    bar = fig.colorbar(shown, cax=cax, extend="max")
    bar.set_label(f"S-CIELAB ΔE*ab per pixel against the design's own still capture\n(scale 0–{vmax:.3g}: the "
                  f"{MAP_PERCENTILE:g}th percentile of this figure's maps, at least {MAP_VMIN_TOP:g})", fontsize=10)
    noise = result["parameters"]["motion"]["noise"]
    what = f"moving at {speed_px_per_ms:g} px/ms" if speed_px_per_ms > 0 else "at rest"
    adds = {(True, True): "what motion and noise add to", (True, False): "what motion adds to",
            (False, True): "what noise adds to", (False, False): "against"}[(speed_px_per_ms > 0, bool(noise))]
    fig.suptitle(f"The edge {what}: {adds} each design's still photograph\n(blue lines: the zone the mean is taken over; grey: the border, "
                 "not scored)", fontsize=11, y=1 - 0.08 / h_in, va="top")
    return [save_figure(fig, out / "maps" / map_name(speed_px_per_ms), dpi=100, tight=False)]


def write_case_outputs(result: dict, out: Path) -> list[Path]:
    """Every case's images and one S-CIELAB map figure per speed (module docstring).

    Parameters
    ----------
    result : dict
        The motion run's result.
    out : Path

    Returns
    -------
    list of Path
        The files written.
    """
    out = Path(out)
    paths = write_case_images(result, out)
    for v in sorted({r.speed_px_per_ms for r in result["rows"]}):
        paths += figure_map(result, v, out)
    return paths


__all__ = ["case_parameters", "case_stem", "figure_map", "map_name", "map_scale", "write_case_images",
           "write_case_outputs"]
