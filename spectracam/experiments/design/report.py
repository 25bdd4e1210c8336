"""What ``spectracam design`` writes: results.json, report.md, curves.csv and the figures (curves, convergence,
comparison), every file with the command and design spec it came from."""
from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from collections.abc import Callable

    from matplotlib.figure import Figure

    from spectracam.core.spectra import WavelengthGrid

__all__ = ["VARIANTS", "figure_comparison", "figure_convergence", "figure_curves", "report_markdown",
           "responsivity_table", "table_rows", "write_design_outputs"]

#: Rows of the comparison, in order: (key in a design's entry, label).
VARIANTS = (("paper_filters", "paper's filters"), ("grid_best", "grid's best block pair"), ("optimised", "optimised"),
            ("luther", "Luther camera (no conversion error)"))


def _variant(entry: dict, key: str) -> dict | None:
    return entry if key == "optimised" else entry.get(key)


def table_rows(results: dict) -> list[dict]:
    """One row per design and variant: expected ΔE (training, held out, chart), Monte Carlo chart ΔE ± spread.

    Parameters
    ----------
    results : dict
        A design run's results (``designs``: each design's entry with its :data:`VARIANTS`).

    Returns
    -------
    list of dict
        ``design``, ``filters`` (the variant's label), ``training``, ``held_out``, ``chart_predicted``,
        ``chart_monte_carlo`` ± ``chart_mc_std``, ``snr_db``, ``mc_snr_db``; the developed camera's, the S-CIELAB and
        the estimated white's fields where the run has them.
    """
    rows = []
    for name, e in results["designs"].items():
        for key, label in VARIANTS:
            v = _variant(e, key)
            if v is None:
                continue
            p, mc = v["predicted_delta_e"], v["monte_carlo_delta_e"]
            row = {"design": name, "filters": label, "training": p["training"], "held_out": p["held_out"],
                   "chart_predicted": p["chart"], "chart_monte_carlo": mc["mean"], "chart_mc_std": mc["std"],
                   "snr_db": p["chart_snr_db"], "mc_snr_db": mc["snr_db"]}
            dev = v.get("monte_carlo_developed_delta_e")
            if dev is not None:   # the same camera developed by a camera that finds its own white (issue 33)
                row.update(chart_monte_carlo_developed=dev["mean"], chart_mc_developed_std=dev["std"])
            if "chart_s_cielab" in p:   # the expected S-CIELAB beside the expected ΔE*ab (docs/metrics.md)
                row.update(training_s_cielab=p["training_s_cielab"], held_out_s_cielab=p["held_out_s_cielab"],
                           chart_s_cielab_predicted=p["chart_s_cielab"])
            if "s_cielab" in mc:
                row.update(chart_s_cielab_monte_carlo=mc["s_cielab"], chart_s_cielab_mc_std=mc["s_cielab_std"])
            if "training_estimated_white" in p:
                row.update(training_estimated_white=p["training_estimated_white"],
                           held_out_estimated_white=p["held_out_estimated_white"])
            rows.append(row)
    return rows


def report_markdown(results: dict, command: str) -> str:
    """report.md: the setup, the comparison table (expected and Monte Carlo ΔE*ab, SNR), S-CIELAB and the developed
    camera where the run has them, and each design's variables and optimisation.

    Parameters
    ----------
    results : dict
        A design run's results.
    command : str
        The command, recorded at the top.

    Returns
    -------
    str
        The markdown.
    """
    spec = results["parameters"]["design_spec"]
    out = [f"# Filter design by gradient\n\n`{command}`\n",
           f"Training: {spec['training']} × lights {', '.join(results['parameters']['lights'])} at "
           f"{results['parameters']['white_luminance_cd_m2']:.4g} cd/m²; held out: {spec['held_out']}; filters: "
           f"{spec['filters']}. {results['parameters']['objective']}. Monte Carlo: {results['parameters']['monte_carlo']}.\n",
           "| design | filters | training ΔE (expected) | held-out ΔE (expected) | chart ΔE expected | chart ΔE Monte Carlo "
           "(± sd over seeds) | chart SNR dB |", "|---|---|---|---|---|---|---|"]
    for r in table_rows(results):
        out.append(f"| {r['design']} | {r['filters']} | {r['training']:.2f} | {r['held_out']:.2f} | "
                   f"{r['chart_predicted']:.2f} | {r['chart_monte_carlo']:.2f} ± {r['chart_mc_std']:.2f} | "
                   f"{r['snr_db']:.1f} |")
    sc = [r for r in table_rows(results) if "chart_s_cielab_predicted" in r]
    if sc:
        s = results["parameters"].get("s_cielab", {})
        out += ["\nPer-pixel ΔE*ab against S-CIELAB (Zhang & Wandell's filters"
                + (f" at {s['samples_per_degree']:.3g} samples per degree" if "samples_per_degree" in s else "")
                + "): on a flat patch the eye's filters average the noise the demosaicker has already correlated, so "
                "a demosaicker's averaging of neighbours no longer counts as less noise (docs/metrics.md, \"Expected "
                "S-CIELAB in the design model\").  Expected: the model; Monte Carlo: the chart's measured mean "
                "(± sd over seeds).\n",
                "| design | filters | held-out ΔE*ab | held-out S-CIELAB | chart ΔE*ab expected | chart S-CIELAB expected "
                "| chart ΔE*ab Monte Carlo | chart S-CIELAB Monte Carlo |", "|---|---|---|---|---|---|---|---|"]
        for r in sc:
            mc = (f"{r['chart_s_cielab_monte_carlo']:.2f} ± {r['chart_s_cielab_mc_std']:.2f}"
                  if "chart_s_cielab_monte_carlo" in r else "—")
            out.append(f"| {r['design']} | {r['filters']} | {r['held_out']:.2f} | {r['held_out_s_cielab']:.2f} | "
                       f"{r['chart_predicted']:.2f} | {r['chart_s_cielab_predicted']:.2f} | "
                       f"{r['chart_monte_carlo']:.2f} ± {r['chart_mc_std']:.2f} | {mc} |")
    dev = [r for r in table_rows(results) if "chart_monte_carlo_developed" in r]
    if dev:
        out += ["\nThe same cameras developed two ways, chart ΔE*ab by Monte Carlo (± sd over seeds): the oracle (told "
                "the light: the paper's) and the developed camera (its own percentile metering, corrected-moments white "
                "balance and dual-illuminant calibration; docs/metrics.md).  The oracle/developed ratio of the paper's "
                "filters to each design says how much the oracle flatters the design.\n",
                "| design | filters | oracle | developed | developed − oracle |", "|---|---|---|---|---|"]
        for r in dev:
            out.append(f"| {r['design']} | {r['filters']} | {r['chart_monte_carlo']:.2f} ± {r['chart_mc_std']:.2f} | "
                       f"{r['chart_monte_carlo_developed']:.2f} ± {r['chart_mc_developed_std']:.2f} | "
                       f"{r['chart_monte_carlo_developed'] - r['chart_monte_carlo']:+.2f} |")
    out.append("\n| design | variables | evaluations | optimise s |\n|---|---|---|---|")
    for name, e in results["designs"].items():
        out.append(f"| {name} | {json.dumps(e['variables'])} | {e['evaluations']} | {e['optimise_s']:.1f} |")
    return "\n".join(out) + "\n"


def responsivity_table(results: dict, grid: WavelengthGrid) -> tuple[list[str], np.ndarray]:
    """Header and rows of curves.csv: wavelength, then each design's optimised and paper responsivities per
    channel (electrons per photon, band averages).

    Parameters
    ----------
    results : dict
        A design run's results, with each design's ``_cameras`` (``optimised``, ``paper``).
    grid : WavelengthGrid
        The bands, nm.

    Returns
    -------
    header : list of str
        ``wavelength_nm``, then ``design:optimised|paper:channel``.
    data : ndarray
        ``(B, columns)``: band centres, nm, then responsivities, e⁻/photon.
    """
    from spectracam.camera import camera_responsivities

    cols, data = ["wavelength_nm"], [np.asarray(grid.centres_nm, float)]
    for name, e in results["designs"].items():
        for which in ("optimised", "paper"):
            cam = e["_cameras"][which]
            R = camera_responsivities(cam, grid)
            for ch, r in zip(cam.architecture().channels, R):
                cols.append(f"{name}:{which}:{ch}")
                data.append(r)
    return cols, np.stack(data, axis=1)


#: Channel colours: Okabe & Ito's vermillion, bluish green and blue for R, G, B (spectracam.io.plots.OKABE_ITO), which
#: keep their meaning and stay apart for colour-blind readers.
_COLOURS = {"R": "#D55E00", "G": "#009E73", "B": "#0072B2", "W": "0.4", "Y": "#E69F00", "C": "#56B4E9",
            "M": "#CC79A7"}


def figure_curves(results: dict, grid: WavelengthGrid) -> Figure:
    """Each design's optimised responsivities (solid) against the paper's (dashed).

    Parameters
    ----------
    results : dict
        A design run's results, with each design's ``_cameras``.
    grid : WavelengthGrid
        The bands, nm.

    Returns
    -------
    matplotlib.figure.Figure
        One panel per design, three to a row, titled with its held-out expected ΔE*ab before → after.
    """
    from spectracam.camera import camera_responsivities
    from spectracam.io.plots import pyplot

    plt = pyplot()
    names = list(results["designs"])
    n = len(names)
    cols = min(3, n)
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.0 * rows + 0.9), squeeze=False, sharex=True)
    lam = np.asarray(grid.centres_nm, float)
    for ax, name in zip(axes.flat, names):
        e = results["designs"][name]
        for which, style in (("paper", "--"), ("optimised", "-")):
            cam = e["_cameras"][which]
            for i, (ch, r) in enumerate(zip(cam.architecture().channels, camera_responsivities(cam, grid))):
                ax.plot(lam, r, style, color=_COLOURS.get(ch, f"C{i}"), lw=1.6 if which == "optimised" else 1.0,
                        label=f"{ch} {which}" if which == "optimised" else None)
        p, q = e["predicted_delta_e"], e["paper_filters"]["predicted_delta_e"]
        ax.set_title(f"{name}: held-out ΔE {q['held_out']:.2f} → {p['held_out']:.2f}", fontsize=9)
        ax.set_ylabel("e⁻ per photon")
    for ax in axes.flat[n:]:
        ax.axis("off")
    for ax in axes[-1]:
        ax.set_xlabel("wavelength, nm")
    handles, labels = axes.flat[0].get_legend_handles_labels()   # one key for every panel, below them all
    handles.append(plt.Line2D([], [], ls="--", color="0.3", lw=1.0))
    labels.append("the paper's filters")
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=8, frameon=False)
    fig.suptitle("optimised responsivities (solid) against the paper's filters (dashed)", fontsize=10)
    fig.tight_layout(rect=(0, 0.07, 1, 0.95))
    return fig


def figure_convergence(results: dict) -> Figure:
    """The training ΔE*ab (or S-CIELAB, the objective's) at every evaluation, per design.

    Parameters
    ----------
    results : dict
        A design run's results: each design's ``history``.

    Returns
    -------
    matplotlib.figure.Figure
        The best value so far against the evaluations (log x).
    """
    from spectracam.io.plots import pyplot

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for i, (name, e) in enumerate(results["designs"].items()):
        de = [h.get("training_delta_e", h.get("training_s_cielab")) for h in e["history"]]
        ax.plot(np.arange(1, len(de) + 1), np.minimum.accumulate(de), color=f"C{i % 10}", label=name)
    ax.set_xlabel("model evaluations (objective + gradient)")
    sc = results["parameters"]["design_spec"].get("objective") == "s_cielab"
    ax.set_ylabel("best training S-CIELAB ΔE*ab (expected)" if sc else "best training ΔE*ab (expected)")
    ax.set_xscale("log")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    ax.set_title("convergence", fontsize=10)
    return fig


def figure_comparison(results: dict) -> Figure:
    """Held-out expected ΔE and Monte Carlo chart ΔE per design: paper's filters, optimised, Luther.

    Parameters
    ----------
    results : dict
        A design run's results.

    Returns
    -------
    matplotlib.figure.Figure
        Two bar panels, one bar per variant the run has.
    """
    from spectracam.io.plots import pyplot

    plt = pyplot()
    names = list(results["designs"])
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    present = [(k, lab) for k, lab in VARIANTS if any(_variant(results["designs"][n], k) is not None for n in names)]
    width = 0.8 / len(present)    # the variants a run has, side by side, centred on their design (no empty slot)
    for j, (key, label) in enumerate(present):
        for ax, what in zip(axes, ("held_out", "mc")):
            xs, ys, es = [], [], []
            for i, name in enumerate(names):
                v = _variant(results["designs"][name], key)
                if v is None:
                    continue
                xs.append(i + (j - (len(present) - 1) / 2) * width)
                if what == "held_out":
                    ys.append(v["held_out_delta_e"])
                    es.append(0.0)
                else:
                    ys.append(v["monte_carlo_delta_e"]["mean"])
                    es.append(v["monte_carlo_delta_e"]["std"])
            if xs:
                ax.bar(xs, ys, width, yerr=es if what == "mc" else None, color=f"C{j}", label=label, capsize=2)
    for ax, title in zip(axes, ("expected ΔE*ab on the held-out library", "chart ΔE*ab, Monte Carlo (± sd, seeds)")):
        ax.set_xticks(range(len(names)))
        ax.set_xticklabels(names, rotation=35, ha="right", fontsize=8)
        ax.set_title(title, fontsize=10)
        ax.grid(axis="y", alpha=0.3)
    axes[0].set_ylabel("ΔE*ab")
    handles, labels = axes[0].get_legend_handles_labels()   # below the panels, over no bar
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=8, frameon=False)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    return fig


def write_design_outputs(out_dir: str | Path, results: dict, command: str,
                         step: Callable[[str], object] = lambda m: None) -> list:
    """Every file of a design run (the module).

    Parameters
    ----------
    out_dir : str or Path
    results : dict
        :func:`~spectracam.experiments.design.run.run_design`'s (``_grid`` and each design's ``_cameras`` and
        ``_shot`` are kept out of results.json).
    command : str
        Recorded in results.json, report.md, curves.json and under each figure.
    step : callable
        ``step(line)`` once written.

    Returns
    -------
    list of Path
        Every file written (the figures' PNG and SVG, the cases' EXR files included).
    """
    from spectracam.core.files import atomic_write, json_default
    from spectracam.experiments.architectures.experiment import write_shots
    from spectracam.io.plots import save_figure

    out = Path(out_dir)
    grid = results["_grid"]
    public = {**{k: v for k, v in results.items() if k != "_grid"}, "command": command,
              "designs": {k: {kk: vv for kk, vv in v.items() if kk not in ("_cameras", "_shot")}
                          for k, v in results["designs"].items()},
              "comparison": table_rows(results)}
    paths = [atomic_write(out / "results.json", json.dumps(public, indent=1, allow_nan=False,
                                                           default=json_default).encode())]
    paths.append(atomic_write(out / "report.md", report_markdown(results, command).encode()))
    header, data = responsivity_table(results, grid)
    lines = [",".join(header)] + [",".join(f"{v:.6g}" for v in row) for row in data]   # one header row: any reader
    paths.append(atomic_write(out / "curves.csv", ("\n".join(lines) + "\n").encode()))
    meta = {"command": command, "file": "curves.csv",
            "columns": "wavelength_nm (the band's centre, nm), then design:optimised|paper:channel",
            "unit": "band-averaged responsivity, electrons per photon"}
    paths.append(atomic_write(out / "curves.json", (json.dumps(meta, indent=1) + "\n").encode()))
    for name, fig in (("curves", figure_curves(results, grid)), ("convergence", figure_convergence(results)),
                      ("comparison", figure_comparison(results))):
        fig.text(0.005, -0.01, command, fontsize=5, color="0.45", va="top")   # where it came from, below everything
        paths += save_figure(fig, out / f"{name}.png", out / f"{name}.svg")
    shots = {k: v["_shot"] for k, v in results["designs"].items() if v.get("_shot") is not None}
    paths += write_shots(out / "cases", shots)   # each optimised design's first Monte Carlo capture: its page's images
    step(f"wrote {out}/results.json, report.md, curves.csv (+ curves.json), curves, convergence and comparison "
         ".png/.svg" + (f", cases/ with {len(shots)} designs' raw.exr and rendered.exr" if shots else ""))
    return paths
