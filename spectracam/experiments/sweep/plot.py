"""Plots of a sweep: a metric against one axis, one line per value of another (mean ± std over trials),
with the base scene's cell and the best cell marked, in human labels with units."""
from __future__ import annotations

import json
import re
import textwrap
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from spectracam.core.errors import SpectracamError
from spectracam.io.plots import OKABE_ITO

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["AXIS_LABELS", "LARGER_IS_BETTER", "LEGEND_ROWS", "METRIC_LABELS", "axis_label", "load_results",
           "metric_label", "natural_key", "plot_sweep", "resolve_axes", "sweep_figure", "with_value"]

#: Human labels of the metrics a sweep records (and whether they carry noise, so get error bars).
METRIC_LABELS = {
    "delta_e_mean": ("mean ΔE*ab per pixel", True), "delta_e_of_mean": ("ΔE*ab of the patch means", True),
    "delta_e_conversion": ("ΔE*ab of the colour conversion alone", False),
    "snr_combined_db": ("combined SNR (dB)", True), "snr_R_db": ("SNR of R (dB)", True),
    "snr_G_db": ("SNR of G (dB)", True), "snr_B_db": ("SNR of B (dB)", True),
    "capture_time_ms": ("capture time (ms)", False), "exposure_R_ms": ("exposure of R (ms)", False),
    "exposure_G_ms": ("exposure of G (ms)", False), "exposure_B_ms": ("exposure of B (ms)", False)}
#: Human labels of common axes; others are spelled out from their path.
AXIS_LABELS = {"filters.cutoffs_nm[0]": "blue/green cutoff (nm)", "filters.cutoffs_nm[1]": "green/red cutoff (nm)",
               "illuminant.temperature_K": "colour temperature (K)", "capture.design": "design",
               "sensor.read_noise_e": "read noise (e⁻)", "sensor.pixel_pitch_um": "pixel pitch (µm)",
               "optics.f_number": "f-number", "sensor.adc_bits": "ADC bits"}
_UNITS = {"nm": "nm", "K": "K", "e": "e⁻", "um": "µm", "ms": "ms", "s": "s", "db": "dB", "mm": "mm"}
#: Metrics where larger is better (the best cell is the maximum); for the others it is the minimum.
LARGER_IS_BETTER = ("snr_combined_db", "snr_R_db", "snr_G_db", "snr_B_db")


def axis_label(path: str) -> str:
    """``"sensor.read_noise_e"`` → ``"read noise (e⁻)"``.

    Parameters
    ----------
    path : str
        A sweep axis (a scene-file path).

    Returns
    -------
    str
        :data:`AXIS_LABELS`' label, else the field's name in words with its unit suffix spelled out; else ``path``.
    """
    if path in AXIS_LABELS:
        return AXIS_LABELS[path]
    m = re.match(r"^[a-z_]+\.([A-Za-z_0-9]+?)(?:_([A-Za-z]+))?(\[\d+\])?$", path)
    if not m:
        return path
    name, unit, idx = m.groups()
    if unit not in _UNITS:
        name, unit = f"{name}_{unit}" if unit else name, None
    return name.replace("_", " ") + (f" {idx}" if idx else "") + (f" ({_UNITS[unit]})" if unit else "")


def metric_label(metric: str) -> str:
    """A metric's label for an axis (:data:`METRIC_LABELS`; else its name in words).

    Parameters
    ----------
    metric : str

    Returns
    -------
    str
    """
    return METRIC_LABELS.get(metric, (metric.replace("_", " "), True))[0]


def load_results(out_dir: str | Path) -> tuple[dict, list[dict]]:
    """sweep.json and results.parquet of a finished sweep, checked to describe one sweep (one line if not).

    Parameters
    ----------
    out_dir : str or Path

    Returns
    -------
    tuple of (dict, list of dict)
        sweep.json's metadata (``axes``, ``metrics``, ``trials``, …) and the table's rows."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    out = Path(out_dir)
    for name in ("results.parquet", "sweep.json"):
        if not (out / name).exists():
            raise SpectracamError(f"directory = {str(out)!r}: has no {name}; run spectracam sweep into it first")
    from spectracam.core.files import regular_file

    try:
        meta = json.loads(regular_file(out / "sweep.json", "file").read_text())
        if not isinstance(meta, dict) or not {"axes", "metrics", "trials"} <= meta.keys():
            raise ValueError("keys missing")
        axes, metrics, trials = meta["axes"], meta["metrics"], meta["trials"]
        if not (isinstance(axes, list) and axes and all(isinstance(a, list) and len(a) == 2 and isinstance(a[0], str)
                                                        and isinstance(a[1], list) for a in axes)):
            raise ValueError("axes must be a non-empty list of [path, values] pairs")
        if not (isinstance(metrics, list) and metrics and all(isinstance(m, str) for m in metrics)):
            raise ValueError("metrics must be a non-empty list of names")
        if isinstance(trials, bool) or not isinstance(trials, int) or trials < 1:
            raise ValueError("trials must be an integer >= 1")
    except (ValueError, UnicodeDecodeError) as e:
        raise SpectracamError(f"file = {str(out / 'sweep.json')!r}: damaged ({e}); run the sweep again") from None
    except OSError as e:
        raise SpectracamError(f"file = {str(out / 'sweep.json')!r}: cannot be read ({e.strerror})") from None
    try:
        table = pq.read_table(regular_file(out / "results.parquet", "file"))
        rows = table.to_pylist()
    except (pa.ArrowException, OSError) as e:
        raise SpectracamError(f"file = {str(out / 'results.parquet')!r}: not a readable Parquet table "
                              f"({str(e).splitlines()[0]}); rerun with spectracam sweep --resume") from None
    # the two files must describe the same sweep: every axis and metric sweep.json names is a column
    columns = set(table.column_names)
    table_axes = ", ".join(c[5:] for c in table.column_names if c.startswith("axis:")) or "none"
    for name, _ in axes:
        if f"axis:{name}" not in columns:
            raise SpectracamError(f"file = {str(out / 'sweep.json')!r}: names the axis {name!r}, which "
                                  f"{str(out / 'results.parquet')!r} lacks (its axes: {table_axes}); the two files "
                                  "are not of one sweep: run the sweep again")
    for m in metrics:
        if m not in columns:
            raise SpectracamError(f"file = {str(out / 'sweep.json')!r}: names the metric {m!r}, which "
                                  f"{str(out / 'results.parquet')!r} lacks; the two files are not of one sweep: run "
                                  "the sweep again")
    if not rows:
        raise SpectracamError(f"file = {str(out / 'results.parquet')!r}: holds no results; rerun with spectracam sweep "
                              "--resume")
    return meta, rows


def _base_value(row: dict, axis: str):
    """The base scene's value of an axis, from a row's recorded parameters (None if unknown)."""
    m = re.match(r"^([a-z_]+\.[A-Za-z_0-9]+)(?:\[(\d+)\])?$", axis)
    if not m or m.group(1) not in row:
        return None
    v = row[m.group(1)]
    if m.group(2) is not None:
        v = json.loads(v)[int(m.group(2))] if isinstance(v, str) else None
    return v


def natural_key(v: object) -> tuple:
    """Sort key of an axis value: numbers by value, then text with its runs of digits compared as numbers
    (``"fsc 9"`` before ``"fsc 10"``), so lines, panels and x values come in the variable's own order.

    Parameters
    ----------
    v : object
        A number (not a bool) or anything with a text form.

    Returns
    -------
    tuple
        Comparable with every other value's key.
    """
    if _is_number(v):
        return (0, float(v), ())
    parts = re.split(r"(\d+(?:\.\d+)?)", str(v))
    return (1, 0.0, tuple((0, float(t), "") if i % 2 else (1, 0.0, t) for i, t in enumerate(parts)))


def _is_number(v) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)


def _fmt(v: float) -> str:
    return f"{v:.3g}" if abs(v) < 1000 else f"{v:.0f}"


def with_value(path: str, v: object) -> str:
    """``("illuminant.temperature_K", 3000)`` → ``"colour temperature = 3000 K"``.

    Parameters
    ----------
    path : str
        A sweep axis.
    v : object
        Its value.

    Returns
    -------
    str
    """
    m = re.match(r"^(.*) \((.+)\)$", axis_label(path))
    return f"{m.group(1)} = {v} {m.group(2)}" if m else f"{axis_label(path)} = {v}"


def _annotate_best(ax, xy, text: str, points) -> None:
    """Write ``text`` in the corner of ``ax`` that covers fewest of the plotted ``points`` (data
    coordinates), with a leader line to the best cell at ``xy``."""
    ax.autoscale_view()
    to_axes = ax.transData + ax.transAxes.inverted()
    pts = to_axes.transform(np.array([p for p in points if np.isfinite(p[1])] or [xy], dtype=float))
    bbox = ax.get_window_extent()
    lines = text.split("\n")
    w = (max(map(len, lines)) * 8 * 0.6 + 8) / 72 * ax.figure.dpi / bbox.width
    h = (len(lines) * 8 * 1.25 + 6) / 72 * ax.figure.dpi / bbox.height
    bx = to_axes.transform([xy])[0]
    best_corner = None
    for cx, ha in ((0.03, "left"), (0.5, "center"), (0.97, "right")):
        for cy, va in ((0.97, "top"), (0.03, "bottom")):
            x0 = {"left": cx, "center": cx - w / 2, "right": cx - w}[ha]
            y0 = cy - h if va == "top" else cy
            covered = np.sum((pts[:, 0] > x0 - 0.02) & (pts[:, 0] < x0 + w + 0.02)
                             & (pts[:, 1] > y0 - 0.03) & (pts[:, 1] < y0 + h + 0.03))
            score = (covered, np.hypot(x0 + w / 2 - bx[0], y0 + h / 2 - bx[1]))
            if best_corner is None or score < best_corner[0]:
                best_corner = (score, (cx, cy), ha, va)
    _, xyt, ha, va = best_corner
    ax.annotate(text, xy, xytext=xyt, textcoords="axes fraction", ha=ha, va=va, fontsize=8, color=OKABE_ITO[1],
                zorder=6, bbox=dict(boxstyle="round,pad=0.3", fc="white", ec=OKABE_ITO[1], lw=0.6, alpha=0.9),
                arrowprops=dict(arrowstyle="-", color=OKABE_ITO[1], lw=0.8, shrinkB=7))


def resolve_axes(meta: dict, x: str | None = None, line: str | None = None,
                 panel: str | None = None) -> tuple[str, str | None, str | None]:
    """The x, line and panel axes: those asked for, the others from the sweep's varying axes.

    Parameters
    ----------
    meta : dict
        sweep.json's metadata (its ``axes``: ``[path, values]`` pairs).
    x, line, panel : str or None
        The axes asked for; None: chosen from the varying ones (x the last, line the one before, panel the first).

    Returns
    -------
    tuple of (str, str or None, str or None)

    Raises
    ------
    SpectracamError
        When an axis asked for is not the sweep's.
    """
    axes = [a for a, _ in meta["axes"]]
    varying = [a for a, v in meta["axes"] if len(v) > 1]
    for name, value in (("x", x), ("line", line), ("panel", panel)):
        if value is not None and value not in axes:
            raise SpectracamError(f"--{name} = {value!r}: must be one of the sweep's axes: {', '.join(axes)}")
    rest = [a for a in varying if a not in (x, line, panel)]
    x = x or (rest.pop() if rest else axes[0])
    rest = [a for a in rest if a != x]
    line = line or (rest.pop() if rest else None)
    rest = [a for a in rest if a != line]
    panel = panel or (rest.pop(0) if rest else None)
    return x, line, panel


#: Legend entries in one column at most (more go into further columns, beside the axes).
LEGEND_ROWS = 13


@dataclass(frozen=True)
class _Layout:
    """What every panel of a sweep figure shares: its axes, their values and x positions, the line colours."""
    metric: str
    x: str
    line: str | None
    panel: str | None
    base: dict
    noisy: bool
    lines: list
    xs_all: list
    numeric_x: bool
    pos: dict
    colors: list


def sweep_figure(meta: dict, rows: list[dict], metric: str, x: str, line: str | None = None,
                 panel: str | None = None, base: dict | None = None) -> Figure:
    """The figure of one metric: x = ``x`` axis, one line per value of ``line`` (in the variable's order,
    coloured along a sequential colormap when it is numeric), one panel per value of ``panel``; other
    axes averaged over.  In each panel the best cell is circled and annotated with its value and line,
    and its line drawn thick; the base scene's cell is starred.

    Parameters
    ----------
    meta : dict
        sweep.json's metadata.
    rows : list of dict
        results.parquet's rows.
    metric : str
    x : str
    line, panel : str or None
    base : dict or None
        Axis → the base scene's value; None: sweep.json's ``base_values``.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from spectracam.io.plots import pyplot

    plt = pyplot()
    base = base if base is not None else meta.get("base_values", {})
    varying = [a for a, v in meta["axes"] if len(v) > 1]
    noisy = METRIC_LABELS.get(metric, ("", True))[1] and meta["trials"] > 1
    larger = metric in LARGER_IS_BETTER
    panels = sorted({r[f"axis:{panel}"] for r in rows}, key=natural_key) if panel else [None]
    lines = sorted({r[f"axis:{line}"] for r in rows}, key=natural_key) if line else [None]
    xs_all = sorted({r[f"axis:{x}"] for r in rows}, key=natural_key)
    numeric_x = all(_is_number(v) for v in xs_all)
    pos = {v: (float(v) if numeric_x else float(i)) for i, v in enumerate(xs_all)}
    lay = _Layout(metric, x, line, panel, base, noisy, lines, xs_all, numeric_x, pos, _line_colors(plt, line, lines))
    line_name = axis_label(line) if line else ""
    axes_width = 4.6 * len(panels) + 0.9
    fig, axs = plt.subplots(1, len(panels), figsize=(axes_width, 4.0), squeeze=False, sharey=True)
    starred, notes = False, []
    for ax, pv in zip(axs[0], panels):
        series = _panel_series(rows, lay, pv)
        best = _best_cell(series, larger)
        starred = _draw_series(ax, lay, series, best) or starred
        note = _mark_best(ax, lay, series, best)
        if note is not None:
            notes.append(note)
        _finish_panel(ax, lay, pv)
    axs[0][0].set_ylabel(metric_label(metric))
    for note in notes:  # once every panel is drawn: the panels share their y range
        _annotate_best(*note)
    leg = _sweep_legend(fig, lay, starred, line_name)
    others = [a for a in varying if a not in (x, line, panel)]
    title = (metric_label(metric) + (f": mean ± std over {meta['trials']} trials" if noisy else "")
             + (f", averaged over {', '.join(axis_label(a) for a in others)}" if others else ""))
    _fit_legend(fig, leg, axes_width, title)
    return fig


def _line_colors(plt, line: str | None, lines: list) -> list:
    """One colour per line: along viridis when the line values are numbers, else from tab10 (tab20)."""
    if line and all(_is_number(v) for v in lines):
        cmap = plt.get_cmap("viridis")
        return [cmap(t) for t in np.linspace(0.0, 0.85, len(lines))] if len(lines) > 1 else [cmap(0.0)]
    cmap = plt.get_cmap("tab10" if len(lines) <= 10 else "tab20")
    return [cmap(i % cmap.N) for i in range(len(lines))]


def _panel_series(rows: list[dict], lay: _Layout, pv) -> list:
    """One panel's lines: ``(line value, x values, mean, std, usable)`` each, over the trials and other axes."""
    x, line, panel, metric = lay.x, lay.line, lay.panel, lay.metric
    series = []
    for lv in lay.lines:
        sel = [r for r in rows if (pv is None or r[f"axis:{panel}"] == pv)
               and (lv is None or r[f"axis:{line}"] == lv)]
        xs = sorted({r[f"axis:{x}"] for r in sel}, key=natural_key)
        vals = [[r[metric] for r in sel if r[f"axis:{x}"] == xv and r[metric] is not None] for xv in xs]
        series.append((lv, xs, np.array([np.mean(v) if v else np.nan for v in vals]),
                       np.array([np.std(v) if v else np.nan for v in vals]),
                       [all(r.get("usable", True) is not False for r in sel if r[f"axis:{x}"] == xv) for xv in xs]))
    return series


def _best_cell(series: list, larger: bool):
    """``(line index, x value, mean)`` of the best cell, never one with a trial that is no usable image."""
    best = None  # (line index, x value, mean): never a cell with a trial that is no usable image (.usability)
    for li, (lv, xs, mean, _, usable) in enumerate(series):
        for xv, mv, ok in zip(xs, mean, usable):
            if ok and np.isfinite(mv) and (best is None or (mv > best[2] if larger else mv < best[2])):
                best = (li, xv, mv)
    return best


def _draw_series(ax, lay: _Layout, series: list, best) -> bool:
    """Draw a panel's lines (the best one thick) and star the base scene's cell; returns whether it did."""
    x, line, base, pos = lay.x, lay.line, lay.base, lay.pos
    starred = False
    for li, (lv, xs, mean, std, _) in enumerate(series):
        thick = best is not None and best[0] == li and len(lay.lines) > 1
        style = dict(marker="o", ms=4 if thick else 3, lw=2.8 if thick else 1.2, color=lay.colors[li],
                     zorder=3 if thick else 2, label=None if lv is None else str(lv))
        xp = [pos[v] for v in xs]
        if lay.noisy:
            ax.errorbar(xp, mean, yerr=std, capsize=2, elinewidth=1.4 if thick else 0.8, **style)
        else:
            ax.plot(xp, mean, **style)
        for xv, mv in zip(xs, mean):
            if base.get(x) == xv and (line is None or base.get(line) == lv) and np.isfinite(mv):
                ax.plot([pos[xv]], [mv], marker="*", ms=13, mfc="none", mec="black", ls="none", zorder=4)
                starred = True
    return starred


def _mark_best(ax, lay: _Layout, series: list, best):
    """Circle the best cell and return its note for :func:`_annotate_best` (None if there is none)."""
    if best:
        li, bx, bv = best
        pos, x, line = lay.pos, lay.x, lay.line
        ax.plot([pos[bx]], [bv], marker="o", ms=12, mfc="none", mec=OKABE_ITO[1], mew=1.6, ls="none", zorder=5)
        text = f"best: {_fmt(bv)}\nat {with_value(x, bx)}" + (f"\non {with_value(line, lay.lines[li])}" if line else "")
        return (ax, (pos[bx], bv), text, [(pos[v], m) for _, xs, mean, _, _ in series for v, m in zip(xs, mean)])
    if any(np.isfinite(m).any() for _, _, m, _, _ in series):
        ax.text(0.5, 0.97, "no usable image: no best cell (docs/metrics.md)", transform=ax.transAxes,
                ha="center", va="top", fontsize=8, color="0.3")
    return None


def _finish_panel(ax, lay: _Layout, pv) -> None:
    """A panel's x ticks, x label, grid and title."""
    from matplotlib.ticker import MaxNLocator

    xs_all, pos = lay.xs_all, lay.pos
    if not lay.numeric_x or len(xs_all) <= 9:
        ax.set_xticks([pos[v] for v in xs_all], [str(v) for v in xs_all])
    elif all(float(v).is_integer() for v in xs_all):
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel(axis_label(lay.x))
    ax.grid(alpha=0.3)
    if pv is not None:
        ax.set_title(with_value(lay.panel, pv), fontsize=10)


def _sweep_legend(fig, lay: _Layout, starred: bool, line_name: str):
    """The figure's legend, right of the panels: the lines, the base scene's star, the best cell's circle."""
    from matplotlib.lines import Line2D

    line = lay.line
    handles = [Line2D([], [], color=c, marker="o", ms=3, lw=1.2) for c in lay.colors] if line else []
    labels = [str(v) for v in lay.lines] if line else []
    if starred:
        handles.append(Line2D([], [], marker="*", ms=11, mfc="none", mec="black", ls="none"))
        labels.append("the base scene")
    handles.append(Line2D([], [], marker="o", ms=10, mfc="none", mec=OKABE_ITO[1], mew=1.6, ls="none"))
    labels.append("best (annotated;\nits line thick)" if line else "best (annotated)")
    ncol = -(-len(handles) // LEGEND_ROWS)
    return fig.legend(handles, labels, loc="center left", bbox_to_anchor=(1.0, 0.5), fontsize=8, frameon=False,
                      ncol=ncol, columnspacing=1.0, handlelength=1.6, title=line_name or None, title_fontsize=8)


def _fit_legend(fig, leg, axes_width: float, title: str) -> None:
    """Widen the figure by the legend's width, set the wrapped title and lay the panels out beside the legend."""
    fig.canvas.draw()  # the legend's size, to widen the figure by
    legend_width = leg.get_window_extent().width / fig.dpi + 0.25
    width = axes_width + legend_width
    fig.set_figwidth(width)
    fig.suptitle(textwrap.fill(title, max(40, int(width * 13))), fontsize=10)
    fig.tight_layout(rect=(0, 0, 1 - legend_width / width, 1))
    leg.set_bbox_to_anchor((1 - legend_width / width + 0.1 / width, 0.5), transform=fig.transFigure)


def plot_sweep(out_dir: str | Path, x: str | None = None, line: str | None = None, panel: str | None = None,
               metrics: list[str] | None = None, base: dict | None = None) -> list[Path]:
    """Write ``plots/<metric>.png`` and ``.svg`` (:func:`sweep_figure`): x = ``x`` axis, lines = ``line``
    axis, one panel per value of ``panel``; other axes are averaged over.  Defaults: the axes in the sweep
    file's order.  ``base``: axis → the base scene's value, marked with a star (default: from the sweep.json).

    Parameters
    ----------
    out_dir : str or Path
        The sweep's directory; the plots go to ``plots/`` in it.
    x, line, panel : str or None
        Axes (:func:`resolve_axes`).
    metrics : list of str or None
        The metrics plotted; None: every one the sweep recorded.
    base : dict or None

    Returns
    -------
    list of Path
        A PNG and an SVG per metric.

    Raises
    ------
    SpectracamError
        For a metric the sweep did not record, or a directory without a readable finished sweep.
    """
    from spectracam.io.plots import save_figure

    meta, rows = load_results(out_dir)
    x, line, panel = resolve_axes(meta, x, line, panel)
    for m in metrics or []:
        if m not in meta["metrics"]:
            raise SpectracamError(f"--metric = {m!r}: this sweep recorded {', '.join(meta['metrics'])}")
    paths = []
    for metric in metrics or meta["metrics"]:
        fig = sweep_figure(meta, rows, metric, x, line, panel, base)
        paths += save_figure(fig, *(Path(out_dir) / "plots" / f"{metric}.{fmt}" for fmt in ("png", "svg")),
                             tight=False)
    return paths
