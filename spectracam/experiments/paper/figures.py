"""Figures 4, 5 and 6 drawn like the paper's: colour temperature on x, a marker per channel/design."""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from spectracam.io.plots import OKABE_ITO
from spectracam.io.plots import figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["CHANNEL_STYLE", "DESIGN_STYLE", "PAPER_DESIGNS", "fig4", "fig5", "fig6"]

#: The paper's markers: Fig. 4 circles R, triangles G, squares B; Fig. 5 circles CFA, triangles FSC,
#: squares FSC balanced (the prism, not in the paper's Fig. 5, gets diamonds).
CHANNEL_STYLE = {"R": ("o", "tab:red"), "G": ("^", "tab:green"), "B": ("s", "tab:blue"), "C": ("v", "c"),
                 "M": ("D", "m"), "Y": ("P", "goldenrod"), "W": ("*", "0.3")}
#: The paper's four designs (Fig. 4 draws the paper's two of them; any other architecture gets its own panel).
PAPER_DESIGNS = ("cfa/single", "fsc/optimal", "fsc/balanced", "prism/optimal")
DESIGN_STYLE = {"cfa/single": ("o", "black", "-"), "fsc/optimal": ("^", OKABE_ITO[0], "--"),
                "fsc/balanced": ("s", OKABE_ITO[4], ":"), "prism/optimal": ("D", OKABE_ITO[3], "-.")}


def fig4(results: dict) -> Figure:
    """Figure 4: each channel's response to the white patch; a filled marker where the channel
    reaches the metered fill of the well (the one that ends a single exposure; paper 4.5: "near
    saturation", ``capture.white_fill``).

    Parameters
    ----------
    results : dict
        The paper run's results (results.json): ``fig4_white_response`` (design → temperature, K → the
        channels' responses as fractions of the full well) and ``parameters``.

    Returns
    -------
    matplotlib.figure.Figure
        One panel per design drawn: ``cfa/single`` and ``fsc/optimal``, and any design outside the paper's.
    """
    from matplotlib.lines import Line2D

    f4 = results["fig4_white_response"]
    fill = (results.get("parameters", {}).get("scene") or {}).get("capture", {}).get("white_fill", 1.0)
    designs = [d for d in ("cfa/single", "fsc/optimal") if d in f4] + [d for d in f4 if d not in PAPER_DESIGNS]
    designs = designs or list(f4)[:2]
    fig = figure(figsize=(4.2 * len(designs) + 2.1, 3.6))
    axes = fig.subplots(1, len(designs), sharey=True, squeeze=False)
    names = {"R": "red", "G": "green", "B": "blue", "C": "cyan", "M": "magenta", "Y": "yellow", "W": "white (clear)"}
    seen: dict = {}
    for ax, d in zip(axes[0], designs):
        T = sorted(f4[d], key=float)
        resp = np.array([f4[d][t] for t in T])
        x = np.array([float(t) for t in T])
        for k, c in enumerate(_channels(results, d)):
            m, col = CHANNEL_STYLE.get(c, ("x", f"C{k}"))
            h, = ax.plot(x, resp[:, k], marker=m, color=col, mfc="none", ls="-")
            seen.setdefault(f'"{names.get(c, c)}" channel', h)
            full = resp[:, k] >= fill - 1e-3
            ax.plot(x[full], resp[full, k], ls="none", marker=m, color=col)
        if np.allclose(resp, fill, atol=1e-3):
            ax.text(0.5, 0.55, f"each channel has its own exposure:\nall three reach {fill:g} of the well\n(lines coincide)",
                    transform=ax.transAxes, ha="center", fontsize=8, color="0.3")
        ax.set_title(f"{d}", fontsize=10)
        ax.set_xlabel("colour temperature (K)")
        ax.set_ylim(0, 1.08)
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel("relative response to white (1 = full well)")
    labels, handles = list(seen), list(seen.values())
    handles.append(Line2D([], [], ls="none", marker="o", color="0.3"))
    labels.append(f"filled: at the metered\nfill ({fill:g} of the well)")
    fig.legend(handles, labels, loc="center right", fontsize=8, frameon=False)
    fig.suptitle("Figure 4: response of each channel to a white surface", fontsize=10)
    fig.tight_layout(rect=(0, 0, 1 - 2.0 / fig.get_figwidth(), 1))
    return fig


def _channels(results: dict, design: str) -> tuple:
    """The channels a design records (the paper's R, G, B unless the run's camera says otherwise)."""
    scene = (results.get("parameters") or {}).get("scene")
    if design in PAPER_DESIGNS or not scene:
        return ("R", "G", "B")
    from spectracam.pipeline.scene_file import Scene

    return Scene.from_dict(scene).camera.with_design(design).architecture().channels


def fig5(results: dict) -> Figure:
    """Figure 5: (a) the SNR, dB, and (b) the mean ΔE*ab over the 24 patches against colour temperature, one line per
    design, each labelled with its capture time at 5000 K, ms.

    Parameters
    ----------
    results : dict
        The paper run's results: ``fig5a_snr_db``, ``fig5b_delta_e`` and ``exposure_ms`` (design → temperature →
        value).

    Returns
    -------
    matplotlib.figure.Figure
        The two panels.
    """
    fig = figure(figsize=(9, 3.8))
    a, b = fig.subplots(1, 2)
    for ax, key, ylabel, title in ((a, "fig5a_snr_db", "SNR (dB)", "(a) SNR"),
                                   (b, "fig5b_delta_e", "mean ΔE*ab", "(b) perceptual error")):
        for d, per_T in results[key].items():
            m, col, ls = DESIGN_STYLE.get(d, ("x", "gray", "-"))
            T = sorted(per_T, key=float)
            ms = results["exposure_ms"][d]
            at = "5000" if "5000" in ms else sorted(ms, key=float)[len(ms) // 2]
            ax.plot([float(t) for t in T], [per_T[t] for t in T], marker=m, color=col, ls=ls, mfc="none",
                    label=f"{d} ({ms[at]:.0f} ms)")
        ax.set_xlabel("colour temperature (K)")
        ax.set_ylabel(ylabel)
        ax.set_title(title, fontsize=10)
        ax.grid(alpha=0.3)
    b.set_ylim(bottom=0)
    handles, labels = a.get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=8, frameon=False,
               title="design (capture time at 5000 K, as in the paper's caption)", title_fontsize=8)
    fig.suptitle("Figure 5: averages over the 24 patches", fontsize=10)
    fig.tight_layout(rect=(0, 0.14, 1, 1))
    return fig


def fig6(results: dict) -> Figure:
    """Figure 6: the error budget, the mean ΔE*ab after each step is added in turn (perfect, shot noise, CMOS noise,
    quantization, colour conversion), as bars.

    Parameters
    ----------
    results : dict
        The paper run's results: ``fig6_budget_delta_e`` (the steps' ``label`` and ``delta_e``) and ``parameters``
        (``budget_design``, ``budget_illuminant``).

    Returns
    -------
    matplotlib.figure.Figure
        One bar per step, labelled with its ΔE*ab.
    """
    steps = [(s["label"], s["delta_e"]) for s in results["fig6_budget_delta_e"]]
    fig = figure(figsize=(6.5, 3.6))
    ax = fig.subplots()
    names = [s.replace("+ ", "+\n").replace(" (", "\n(") for s, _ in steps]
    ax.bar(range(len(steps)), [v for _, v in steps], color="0.55", edgecolor="black")
    for i, (_, v) in enumerate(steps):
        ax.text(i, v, f"{v:.2f}", ha="center", va="bottom", fontsize=8)
    ax.set_xticks(range(len(steps)), names, fontsize=7)
    ax.set_ylabel("mean ΔE*ab")
    p = results["parameters"]
    ax.set_title(f"Figure 6: cumulative error, {p['budget_design']} under {p['budget_illuminant']}", fontsize=10)
    fig.tight_layout()
    return fig
