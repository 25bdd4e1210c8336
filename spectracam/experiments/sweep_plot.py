"""Plots of a sweep: a metric against one axis, one line per value of another (mean ± std over trials),
with the base scene's cell and the best cell marked, in human labels with units."""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np

from ..errors import SpectracamError

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
    """``"sensor.read_noise_e"`` → ``"read noise (e⁻)"``."""
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
    return METRIC_LABELS.get(metric, (metric.replace("_", " "), True))[0]


def load_results(out_dir: str | Path) -> tuple[dict, list[dict]]:
    import pyarrow as pa
    import pyarrow.parquet as pq

    out = Path(out_dir)
    for name in ("results.parquet", "sweep.json"):
        if not (out / name).exists():
            raise SpectracamError(f"directory = {str(out)!r}: has no {name}; run spectracam sweep into it first")
    try:
        meta = json.loads((out / "sweep.json").read_text())
        if not isinstance(meta, dict) or not {"axes", "metrics", "trials"} <= meta.keys():
            raise ValueError("keys missing")
    except (ValueError, UnicodeDecodeError) as e:
        raise SpectracamError(f"file = {str(out / 'sweep.json')!r}: damaged ({e}); run the sweep again") from None
    try:
        rows = pq.read_table(out / "results.parquet").to_pylist()
    except (pa.ArrowException, OSError) as e:
        raise SpectracamError(f"file = {str(out / 'results.parquet')!r}: not a readable Parquet table "
                              f"({str(e).splitlines()[0]}); rerun with spectracam sweep --resume") from None
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


def plot_sweep(out_dir: str | Path, x: str | None = None, line: str | None = None, panel: str | None = None,
               metrics: list[str] | None = None, base: dict | None = None) -> list[Path]:
    """Write ``plots/<metric>.png`` and ``.svg``: x = ``x`` axis, lines = ``line`` axis, one panel per
    value of ``panel``; other axes are averaged over.  Defaults: the axes in the sweep file's order.
    ``base``: axis → the base scene's value, marked with a star (default: from the sweep.json)."""
    from ..io.plots import pyplot, save_figure

    plt = pyplot()
    meta, rows = load_results(out_dir)
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
    for m in metrics or []:
        if m not in meta["metrics"]:
            raise SpectracamError(f"--metric = {m!r}: this sweep recorded {', '.join(meta['metrics'])}")
    metrics = metrics or meta["metrics"]
    base = base if base is not None else meta.get("base_values", {})
    panels = sorted({r[f"axis:{panel}"] for r in rows}, key=str) if panel else [None]
    lines = sorted({r[f"axis:{line}"] for r in rows}, key=str) if line else [None]
    key = lambda v: (isinstance(v, str), v)  # noqa: E731
    paths = []
    for metric in metrics:
        noisy = METRIC_LABELS.get(metric, ("", True))[1] and meta["trials"] > 1
        fig, axs = plt.subplots(1, len(panels), figsize=(4.6 * len(panels) + 1.8, 3.8), squeeze=False, sharey=True)
        for ax, pv in zip(axs[0], panels):
            cmap = plt.get_cmap("viridis", max(len(lines), 2))
            best = None
            for li, lv in enumerate(lines):
                sel = [r for r in rows if (pv is None or r[f"axis:{panel}"] == pv)
                       and (lv is None or r[f"axis:{line}"] == lv)]
                xs = sorted({r[f"axis:{x}"] for r in sel}, key=key)
                vals = [[r[metric] for r in sel if r[f"axis:{x}"] == xv and r[metric] is not None] for xv in xs]
                mean = np.array([np.mean(v) if v else np.nan for v in vals])
                xp = [str(v) if isinstance(v, str) else v for v in xs]
                label = None if lv is None else f"{lv}"
                if noisy:
                    ax.errorbar(xp, mean, yerr=[np.std(v) if v else np.nan for v in vals], marker="o", ms=3,
                                capsize=2, color=cmap(li), label=label)
                else:
                    ax.plot(xp, mean, marker="o", ms=3, color=cmap(li), label=label)
                for xv, mv in zip(xp, mean):
                    if np.isfinite(mv) and (best is None or (mv > best[1] if metric in LARGER_IS_BETTER
                                                             else mv < best[1])):
                        best = (xv, mv)
                    if base.get(x) == xv and (line is None or base.get(line) == lv) and np.isfinite(mv):
                        ax.plot([xv], [mv], marker="*", ms=13, mfc="none", mec="black", ls="none",
                                label="the base scene" if li == 0 or line else None)
            if best:
                ax.plot([best[0]], [best[1]], marker="o", ms=11, mfc="none", mec="tab:red", mew=1.5, ls="none",
                        label="best")
            ax.set_xlabel(axis_label(x))
            ax.grid(alpha=0.3)
            if pv is not None:
                ax.set_title(f"{axis_label(panel)} = {pv}", fontsize=9)
        axs[0][0].set_ylabel(metric_label(metric))
        handles, labels = axs[0][-1].get_legend_handles_labels()
        uniq = dict(zip(labels, handles))
        if uniq:
            fig.legend(uniq.values(), uniq.keys(), loc="center right", fontsize=7, frameon=False,
                       title=axis_label(line) if line else None, title_fontsize=7)
        others = [a for a in varying if a not in (x, line, panel)]
        fig.suptitle(metric_label(metric) + (f": mean ± std over {meta['trials']} trials" if noisy else "")
                     + (f", averaged over {', '.join(axis_label(a) for a in others)}" if others else ""), fontsize=9)
        fig.tight_layout(rect=(0, 0, 1 - 1.7 / fig.get_figwidth(), 1))
        paths += save_figure(fig, *(Path(out_dir) / "plots" / f"{metric}.{fmt}" for fmt in ("png", "svg")), dpi=130,
                             tight=False)
    return paths
