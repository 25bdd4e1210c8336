"""Scoring outputs: rendered EXR (linear display RGB, with the display's chromaticities), an sRGB PNG
preview (the display's white adapted to D65), a ΔE map on a fixed scale, JSON and CSV."""
from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from spectracam._version import __version__
from spectracam.processing.color import adaptation_matrix, display_rgb_to_xyz
from spectracam.evaluation.score import ChartScore
from spectracam.io.exr import write_exr
from spectracam.core.files import atomic_write
from spectracam.io.plots import save_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from spectracam.evaluation.target_score import TargetScore

__all__ = ["DELTA_E_VMAX", "REC709_CHROMATICITIES", "delta_e_figure", "display_chromaticities", "report_csv",
           "srgb_preview", "target_csv", "write_display_exr", "write_figure_json_markdown", "write_png",
           "write_rendered_exr", "write_score_outputs", "write_target_outputs"]


#: ITU-R BT.709 / sRGB primaries and D65 white, CIE 1931 xy (IEC 61966-2-1).
REC709_CHROMATICITIES = (0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290)


def display_chromaticities(display: str) -> tuple[float, ...]:
    """The OpenEXR ``chromaticities`` of a display's linear RGB: the xy of its red, green and blue
    primaries and of its white (R = G = B = 1); Rec. 709/D65 for "srgb", computed from the display's
    RGB → XYZ matrix for any other (the CRT's phosphors).

    Parameters
    ----------
    display : str
        A registered display (``"srgb"``, ``"crt"``, …).

    Returns
    -------
    tuple of float
        ``(x_R, y_R, x_G, y_G, x_B, y_B, x_W, y_W)``, CIE 1931 xy.
    """
    if display == "srgb":
        return REC709_CHROMATICITIES
    M = display_rgb_to_xyz(display)
    xy = [c[:2] / c.sum() for c in (M[:, 0], M[:, 1], M[:, 2], M.sum(axis=1))]
    return tuple(float(v) for c in xy for v in c)


def srgb_preview(rendered_rgb: np.ndarray, display: str, adapt_white: bool = True, tone_curve: str = "srgb"
                 ) -> np.ndarray:
    """8-bit sRGB of linear display RGB: display RGB → XYZ → (``adapt_white``: Bradford from the
    display's white to sRGB's D65, so that what is neutral on the display looks neutral on an sRGB
    screen) → linear sRGB, through ``tone_curve`` (:mod:`spectracam.processing.tone`; ``srgb``: clipped),
    sRGB-encoded.  ``adapt_white=False`` shows the display's colours as they are (the CRT's white, x, y = 0.289,
    0.313, about 8300 K, stays bluish).

    Parameters
    ----------
    rendered_rgb : ndarray
        ``(H, W, 3)`` linear RGB of the display, its white at 1.
    display : str
        The registered display whose RGB it is.
    adapt_white : bool
        Adapt the display's white to D65 (Bradford).
    tone_curve : str
        A registered tone curve.

    Returns
    -------
    ndarray
        ``(H, W, 3)`` uint8, sRGB-encoded (IEC 61966-2-1).
    """
    from spectracam.core import colour_data
    from spectracam.processing.tone import tone_map

    M = display_rgb_to_xyz(display)
    to_srgb = colour_data.srgb_matrix("XYZ_to_RGB")
    if adapt_white:
        d65 = colour_data.srgb_matrix("RGB_to_XYZ").sum(axis=1)
        to_srgb = to_srgb @ adaptation_matrix(M.sum(axis=1), d65, "bradford")
    lin = rendered_rgb @ (to_srgb @ M).T
    return (np.clip(colour_data.srgb_encode(tone_map(lin, tone_curve)), 0, 1) * 255 + 0.5).astype(np.uint8)


def write_png(path: Path, rgb8: np.ndarray) -> Path:
    """An 8-bit image as PNG.

    Parameters
    ----------
    path : Path
        The file to write (temp file, then rename).
    rgb8 : ndarray
        ``(H, W, 3)`` uint8 (or ``(H, W, 4)`` with alpha).

    Returns
    -------
    Path
        The file written.
    """
    from spectracam.io.plots import configure

    configure()
    import matplotlib.image   # pyplot.imsave's own function, without pyplot

    buf = io.BytesIO()
    matplotlib.image.imsave(buf, rgb8, format="png")
    return atomic_write(path, buf.getvalue())


#: The ΔE map's default colour scale, ΔE*ab: fixed, so maps of different cases compare.
DELTA_E_VMAX = 20.0


def delta_e_figure(delta_e_map: np.ndarray, title: str, vmax: float | None = DELTA_E_VMAX) -> Figure:
    """The per-pixel ΔE map inside the patch masks (grey where nothing is scored), with a colour bar
    as tall as the image beside it.  ``vmax``: the top of the scale (default a fixed 0–20 so that maps
    compare across cases; values above it show the top colour, the bar's arrow); ``None``: the map's
    own 99th percentile (at least 10).

    Parameters
    ----------
    delta_e_map : ndarray
        ``(H, W)`` ΔE*ab per pixel, NaN outside the patch masks.
    title : str
        The figure's title.
    vmax : float or None
        The top of the colour scale, ΔE*ab; None: from the map.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, not yet saved (:func:`~spectracam.io.plots.save_figure`).
    """
    from mpl_toolkits.axes_grid1 import make_axes_locatable

    from matplotlib import colormaps

    from spectracam.io.plots import figure

    h, w = delta_e_map.shape
    fixed = vmax is not None
    if not fixed:
        finite = delta_e_map[np.isfinite(delta_e_map)]
        vmax = max(10.0, float(np.percentile(finite, 99))) if finite.size else 10.0
    fig = figure(figsize=(7.0, 7.0 * h / w + 0.6))
    ax = fig.subplots()
    cmap = colormaps["magma"].with_extremes(bad="#d0d0d0")
    im = ax.imshow(delta_e_map, cmap=cmap, vmin=0, vmax=vmax, interpolation="nearest")
    ax.set_axis_off()
    ax.set_title(title, fontsize=9)
    cax = make_axes_locatable(ax).append_axes("right", size="3.5%", pad=0.1)
    scale = f"fixed scale 0–{vmax:g}" if fixed else f"scale 0–{vmax:.3g} (this map)"
    bar = fig.colorbar(im, cax=cax, extend="max" if np.nanmax(delta_e_map, initial=0) > vmax else "neither")
    bar.set_label(f"ΔE*ab per pixel, patch masks only ({scale})", fontsize=8)
    bar.ax.tick_params(labelsize=8)
    return fig


def _num(x) -> str:
    return "inf" if x is None else f"{x:.3f}"


def write_rendered_exr(path: str | Path, result: ChartScore) -> Path:
    """The displayed image (linear display RGB) with every parameter of the score that made it, in
    half floats (11-bit mantissa: 5e-4 relative, below what a display shows; the numbers are in
    report.json), half the size of float32.

    Parameters
    ----------
    path : str or Path
        The file to write.
    result : ChartScore
        The score (its rendered RGB and parameters).

    Returns
    -------
    Path
        The file written.
    """
    return write_display_exr(path, result.rendered_rgb, result.parameters)


def write_display_exr(path: str | Path, rgb: np.ndarray, params: dict) -> Path:
    """Linear display RGB ``(H, W, 3)`` in half floats with the parameters that made it.

    Parameters
    ----------
    path : str or Path
        The file to write.
    rgb : ndarray
        ``(H, W, 3)`` linear RGB of the display, its white at 1.
    params : dict
        The score's parameters; ``params["processing"]["display"]`` gives the ``chromaticities`` attribute,
        ``params["seed"]`` the seed.

    Returns
    -------
    Path
        The file written.
    """
    display = params["processing"]["display"]
    attrs = {"spectracamVersion": __version__, "spectracamKind": "rendered",
             "spectracamUnits": f"linear RGB of the display ({display}), white = 1",
             # the standard attribute viewers read to interpret R, G, B (primaries and white, CIE xy)
             "chromaticities": display_chromaticities(display),
             "spectracamParameters": json.dumps(params, sort_keys=True), "spectracamSeed": int(params["seed"])}
    return write_exr(path, {"R": rgb[..., 0], "G": rgb[..., 1], "B": rgb[..., 2]}, attrs, half=True)


def write_figure_json_markdown(out_dir: str | Path, stem: str, figure: Figure, json_name: str, result: dict,
                               command: str, md_name: str, markdown: str) -> list[Path]:
    """An experiment's three outputs, each written atomically: ``stem``.png/.svg of ``figure``, ``json_name`` (the
    result with the command that made it, strict JSON) and ``md_name``.

    Parameters
    ----------
    out_dir : str or Path
        The experiment's output folder.
    stem : str
        The figure's file name without suffix.
    figure : matplotlib.figure.Figure
        The figure (closed once saved).
    json_name : str
        The JSON file's name.
    result : dict
        The result; ``command`` is added to it.
    command : str
        The command line that made it.
    md_name : str
        The Markdown file's name.
    markdown : str
        The Markdown text.

    Returns
    -------
    list of Path
        The PNG, the SVG, the JSON and the Markdown file.
    """
    out = Path(out_dir)
    paths = save_figure(figure, out / f"{stem}.png", out / f"{stem}.svg")
    paths.append(atomic_write(out / json_name,
                              json.dumps({**result, "command": command}, indent=1, allow_nan=False).encode()))
    paths.append(atomic_write(out / md_name, markdown.encode()))
    return paths


def report_csv(result: ChartScore) -> bytes:
    """One row per patch and a chart-average row.

    Parameters
    ----------
    result : ChartScore
        The chart's score.

    Returns
    -------
    bytes
        UTF-8 CSV: CIELAB of scene and rendering, ΔE*ab (mean, of the mean, conversion) and SNR per channel and
        combined, dB (``inf`` when noise-free).
    """
    buf = io.StringIO()
    wr = csv.writer(buf)
    wr.writerow(["patch", "name", "scene_L", "scene_a", "scene_b", "rendered_L", "rendered_a", "rendered_b",
                 "delta_e_mean", "delta_e_of_mean", "delta_e_conversion", "snr_R_db", "snr_G_db", "snr_B_db",
                 "snr_combined_db"])
    for p in result.patches:
        wr.writerow([p.patch, p.name, *p.scene_lab, *p.rendered_lab, f"{p.delta_e_mean:.4f}",
                     f"{p.delta_e_of_mean:.4f}", f"{p.delta_e_conversion:.4f}",
                     *(_num(getattr(p, f"snr_{k}_db")) for k in "RGB"), _num(p.snr_combined_db)])
    c = result.summary
    wr.writerow(["chart", "average", "", "", "", "", "", "", f"{c.delta_e_mean:.4f}", f"{c.delta_e_of_mean:.4f}",
                 f"{c.delta_e_conversion:.4f}", *(_num(getattr(c, f"snr_{k}_db")) for k in "RGB"),
                 _num(c.snr_combined_db)])
    return buf.getvalue().encode()


def write_score_outputs(out_dir: str | Path, result: ChartScore, adapt_white: bool = True,
                        vmax: float | None = DELTA_E_VMAX) -> list[Path]:
    """rendered.exr, rendered.png, delta_e.png, report.json and report.csv in ``out_dir``;
    ``adapt_white`` and ``vmax``: see :func:`srgb_preview` and :func:`delta_e_figure`.

    Parameters
    ----------
    out_dir : str or Path
        The folder to write into.
    result : ChartScore
        The chart's score.
    adapt_white : bool
        For the PNG preview.
    vmax : float or None
        The ΔE map's top, ΔE*ab.

    Returns
    -------
    list of Path
        The files written, in that order.
    """
    out = Path(out_dir)
    params = result.parameters
    display = params["processing"]["display"]
    paths = [write_rendered_exr(out / "rendered.exr", result),
             write_png(out / "rendered.png", srgb_preview(result.rendered_rgb, display, adapt_white,
                                                                params["processing"].get("tone_curve", "srgb")))]
    c = result.summary
    snr = "∞" if c.snr_combined_db is None else f"{c.snr_combined_db:.1f}"
    name = (params.get("scene") or {}).get("name", "")
    title = f"{params['camera']['capture']['architecture']}/{params['camera']['capture']['exposure']}, {name}: " \
            f"mean ΔE*ab {c.delta_e_mean:.2f}, SNR {snr} dB"
    paths.append(save_figure(delta_e_figure(result.delta_e_map, title, vmax), out / "delta_e.png"))
    paths.append(atomic_write(out / "report.json", json.dumps(result.to_dict(), indent=1, allow_nan=False).encode()))
    paths.append(atomic_write(out / "report.csv", report_csv(result)))
    return paths


def target_csv(result: TargetScore) -> bytes:
    """One row per scored sample of a textured target (interior pixels), then the per-pixel summary.

    Parameters
    ----------
    result : TargetScore
        The target's score.

    Returns
    -------
    bytes
        UTF-8 CSV: per sample its pixels, CIELAB of scene and rendering and ΔE*ab; then the per-pixel mean ΔE*ab.
    """
    buf = io.StringIO()
    wr = csv.writer(buf)
    wr.writerow(["sample", "name", "pixels", "scene_L", "scene_a", "scene_b", "rendered_L", "rendered_a",
                 "rendered_b", "delta_e_of_mean", "delta_e_mean", "delta_e_conversion"])
    for s in result.samples:
        wr.writerow([s.label, s.name, s.pixels, *s.scene_lab, *s.rendered_lab, f"{s.delta_e_of_mean:.4f}",
                     f"{s.delta_e_mean:.4f}", f"{s.delta_e_conversion:.4f}"])
    h = result.held_out
    wr.writerow(["all pixels", h["kind"], h["pixels"], "", "", "", "", "", "", "", f"{h['delta_e_mean']:.4f}", ""])
    return buf.getvalue().encode()


def write_target_outputs(out_dir: str | Path, result: TargetScore, adapt_white: bool = True) -> list[Path]:
    """A textured target's score (:class:`~spectracam.evaluation.target_score.TargetScore`): rendered.exr/.png,
    delta_e.png and s_cielab.png (per pixel, fixed 0–20 scale), report.json and report.csv.

    Parameters
    ----------
    out_dir : str or Path
        The folder to write into.
    result : TargetScore
        The target's score.
    adapt_white : bool
        For the PNG preview (:func:`srgb_preview`).

    Returns
    -------
    list of Path
        The files written, in that order.
    """
    out = Path(out_dir)
    params = result.parameters
    display = params["processing"]["display"]
    paths = [write_display_exr(out / "rendered.exr", result.rendered_rgb, params),
             write_png(out / "rendered.png", srgb_preview(result.rendered_rgb, display, adapt_white,
                                                                params["processing"].get("tone_curve", "srgb")))]
    h = result.held_out
    design = f"{params['camera']['capture']['architecture']}/{params['camera']['capture']['exposure']}"
    name = (params.get("scene") or {}).get("name", "")
    for fname, image, what in (("delta_e.png", result.delta_e_map, "ΔE*ab"),
                               ("s_cielab.png", result.scielab_map, "S-CIELAB ΔE")):
        key = "delta_e" if fname == "delta_e.png" else "s_cielab"
        title = f"{design}, {name}: {what} per pixel, mean {h[key + '_mean']:.2f}, 95th percentile {h[key + '_p95']:.2f}"
        fig = delta_e_figure(image, title)
        fig.axes[-1].set_ylabel(f"{what} per pixel against the known spectra (fixed scale 0–{DELTA_E_VMAX:g})",
                                fontsize=8)
        paths.append(save_figure(fig, out / fname))
    paths.append(atomic_write(out / "report.json", json.dumps(result.to_dict(), indent=1, allow_nan=False).encode()))
    paths.append(atomic_write(out / "report.csv", target_csv(result)))
    return paths
