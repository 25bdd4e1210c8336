"""Plots of a sweep: a metric against one axis, one line per value of another (mean ± std over trials)."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import SpectracamError


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


def plot_sweep(out_dir: str | Path, x: str | None = None, line: str | None = None, panel: str | None = None,
               metrics: list[str] | None = None) -> list[Path]:
    """Write ``plots/<metric>.png`` and ``.svg``: x = ``x`` axis, lines = ``line`` axis, one panel per
    value of ``panel``; other axes are averaged over.  Defaults: the axes in the sweep file's order."""
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
    panels = sorted({r[f"axis:{panel}"] for r in rows}, key=str) if panel else [None]
    lines = sorted({r[f"axis:{line}"] for r in rows}, key=str) if line else [None]
    paths = []
    for metric in metrics:
        fig, axs = plt.subplots(1, len(panels), figsize=(4.6 * len(panels), 3.8), squeeze=False, sharey=True)
        for ax, pv in zip(axs[0], panels):
            cmap = plt.get_cmap("viridis", max(len(lines), 2))
            for li, lv in enumerate(lines):
                sel = [r for r in rows if (pv is None or r[f"axis:{panel}"] == pv) and (lv is None or r[f"axis:{line}"] == lv)]
                xs = sorted({r[f"axis:{x}"] for r in sel}, key=lambda v: (isinstance(v, str), v))
                vals = [[r[metric] for r in sel if r[f"axis:{x}"] == xv and r[metric] is not None] for xv in xs]
                mean = [np.mean(v) if v else np.nan for v in vals]
                std = [np.std(v) if v else np.nan for v in vals]
                ax.errorbar([str(v) if isinstance(v, str) else v for v in xs], mean, yerr=std, marker="o", ms=3,
                            capsize=2, color=cmap(li), label=None if lv is None else f"{line} = {lv}")
            ax.set_xlabel(x)
            ax.grid(alpha=0.3)
            if pv is not None:
                ax.set_title(f"{panel} = {pv}", fontsize=9)
        axs[0][0].set_ylabel(metric)
        if line:
            axs[0][-1].legend(fontsize=6, ncol=2)
        others = [a for a in varying if a not in (x, line, panel)]
        fig.suptitle(f"{metric}: mean ± std over {meta['trials']} trial(s)"
                     + (f", averaged over {', '.join(others)}" if others else ""), fontsize=9)
        fig.tight_layout()
        paths += save_figure(fig, *(Path(out_dir) / "plots" / f"{metric}.{fmt}" for fmt in ("png", "svg")), dpi=130,
                             tight=False)
    return paths
