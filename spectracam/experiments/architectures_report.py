"""The architectures comparison's figures and report (``spectracam architectures``)."""
from __future__ import annotations

import numpy as np

from ..io.plots import pyplot


def _rows(results, light, factor):
    return [r for r in results["rows"] if r["illuminant"] == light and r["light_factor"] == factor]


def figure_comparison(results: dict):
    """Figure 5-style panels per light: rendered SNR (a) and per-pixel ΔE (b) of every design against
    the light level (log), error bars the spread over seeds; (c) held-out against training conversion
    error at the paper's level."""
    plt = pyplot()
    lights = list(dict.fromkeys(r["illuminant"] for r in results["rows"]))
    designs = results["parameters"]["designs"]
    factors = results["parameters"]["light_factors"]
    level = results["parameters"]["paper_white_luminance_cd_m2"]
    fig, axes = plt.subplots(len(lights), 3, figsize=(16, 5.2 * len(lights)), squeeze=False)
    cmap = plt.get_cmap("tab20")
    styles = {d: dict(color=cmap(i % 20), marker="osD^v<>p*hX"[i % 11], ls="-" if d.endswith("single") else "--")
              for i, d in enumerate(designs)}
    for row_axes, light in zip(axes, lights):
        for ax, metric, label in ((row_axes[0], "snr_rendered_db", "rendered luminance SNR (dB)"),
                                  (row_axes[1], "delta_e_mean", "per-pixel ΔE*ab against the scene")):
            for d in designs:
                pts = [(f * level, r[metric], r[f"{metric}_sd"]) for f in factors
                       for r in _rows(results, light, f) if r["design"] == d and r[metric] is not None]
                if pts:
                    x, y, e = map(np.array, zip(*pts))
                    ax.errorbar(x, y, yerr=e, capsize=3, label=d, **styles[d])
            ax.set_xscale("log")
            ax.set_xlabel("white luminance (cd/m²); the paper's light is the rightmost")
            ax.set_ylabel(label)
            ax.set_title(f"{light}: {label}", fontsize=11)
            ax.grid(True, which="both", alpha=0.3)
            if metric == "delta_e_mean":
                ax.set_yscale("log")
        ax = row_axes[2]
        points: dict = {}   # designs whose noise-free errors coincide (filter sums of the same three) share a label
        for r in _rows(results, light, 1.0):
            if r.get("held_out_delta_e") is not None:
                ax.scatter(r["delta_e_training"], r["held_out_delta_e"], s=60, **{k: v for k, v in
                           styles[r["design"]].items() if k in ("color", "marker")})
                key = (round(r["delta_e_training"], 3), round(r["held_out_delta_e"], 3))
                points.setdefault(key, []).append(r["architecture"])
        for (x, y), names in points.items():
            names = list(dict.fromkeys(names))
            text = names[0] if len(names) == 1 else f"{len(names)} architectures:\n" + "\n".join(
                ", ".join(names[i:i + 3]) for i in range(0, len(names), 3))
            ax.annotate(text, (x, y), fontsize=8, xytext=(-10, -8) if len(names) > 1 else (5, 5),
                        textcoords="offset points", ha="right" if len(names) > 1 else "left",
                        va="top" if len(names) > 1 else "bottom")
        lim = ax.get_xlim()[1], ax.get_ylim()[1]
        top = max(lim)
        ax.plot([0, top], [0, top], color="0.6", lw=0.8, ls=":")
        ax.set_xlabel("training ΔE*ab (the 24 patches the conversion is fitted on)")
        lib = next((r.get("held_out_library") for r in results["rows"] if r.get("held_out_library")), "held-out")
        ax.set_ylabel(f"held-out ΔE*ab ({lib})")
        ax.set_title(f"{light}: colour conversion, noise-free", fontsize=11)
        ax.grid(True, alpha=0.3)
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), 7), fontsize=9, frameon=False)
    fig.suptitle(f"Every architecture with the paper's camera and noise ({len(results['parameters']['seeds'])} "
                 "seeds; bars: ±1 sample std over seeds)", fontsize=13)
    fig.tight_layout(rect=(0, 0.06, 1, 0.97))
    return fig


def figure_responsivities(results: dict):
    """Each architecture's channel responsivities R_k(λ) (filter × QE × IR cut, e⁻/photon) on the
    scene's bands."""
    from ..camera import CameraSpec, camera_responsivities
    from ..scene import Scene

    plt = pyplot()
    scene = Scene.from_dict(results["parameters"]["scene"])
    archs = list(dict.fromkeys(r["architecture"] for r in results["rows"]))
    cols = 4
    rows = -(-len(archs) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4 * cols, 3.2 * rows), squeeze=False, sharey=True)
    colours = {"R": "tab:red", "G": "tab:green", "B": "tab:blue", "C": "c", "M": "m", "Y": "goldenrod", "W": "0.3"}
    lam = scene.grid.centres_nm
    for ax, arch in zip(axes.flat, archs):
        camera: CameraSpec = scene.camera.with_design(arch)
        R = camera_responsivities(camera, scene.grid)
        for k, name in enumerate(camera.architecture().channels):
            ax.plot(lam, R[k], color=colours.get(name, None), label=name)
        ax.set_title(arch, fontsize=11)
        ax.set_xlabel("wavelength (nm)")
        ax.legend(fontsize=8)
        ax.grid(True, alpha=0.3)
    for ax in axes[:, 0]:
        ax.set_ylabel("responsivity (e⁻/photon)")
    for ax in list(axes.flat)[len(archs):]:
        ax.axis("off")
    fig.suptitle("Channel responsivities: filter × QE × IR cut (stacked: Beer–Lambert layer windows)", fontsize=12)
    fig.tight_layout(rect=(0, 0, 1, 0.95))
    return fig


def _fmt(v, sd=None, digits=2):
    if v is None:
        return "–"
    return f"{v:.{digits}f}" + (f" ± {sd:.{digits}f}" if sd is not None else "")


def report_markdown(results: dict, command: str) -> str:
    """report.md: the setup, one table per light and level, and what wins where."""
    p = results["parameters"]
    lines = ["# Every architecture with the paper's camera", "", f"Command: `{command}`", "",
             f"Renderer {p['renderer']}{' (quick: 160x120)' if p['quick'] else ''}; seeds {p['seeds']}; the "
             f"paper's light: a white of {p['paper_white_luminance_cd_m2']:.2f} cd/m² (×{', ×'.join(f'{f:g}' for f in p['light_factors'])}).",
             "", "Definitions:", ""]
    for key in ("snr_db", "snr_rendered_db", "delta_e_mean", "delta_e_training", "held_out_delta_e"):
        lines.append(f"- `{key}`: {p[key]}")
    lines.append("")
    for light in dict.fromkeys(r["illuminant"] for r in results["rows"]):
        for f in p["light_factors"]:
            rows = _rows(results, light, f)
            lines += [f"## {light}, {f:g}× the paper's light", "",
                      "| design | channels | capture ms | ΔE mean ± sd | rendered SNR dB ± sd | raw SNR dB | "
                      "training ΔE | held-out ΔE (p95) |", "|---|---|---:|---:|---:|---:|---:|---:|"]
            for r in sorted(rows, key=lambda r: r["delta_e_mean"]):
                lines.append(f"| {r['design']} | {r['channels']} | {r['capture_time_ms']:.2f} | "
                             f"{_fmt(r['delta_e_mean'], r['delta_e_mean_sd'])} | "
                             f"{_fmt(r['snr_rendered_db'], r['snr_rendered_db_sd'])} | {_fmt(r['snr_db'])} | "
                             f"{_fmt(r['delta_e_training'])} | {_fmt(r.get('held_out_delta_e'))} "
                             f"({_fmt(r.get('held_out_delta_e_p95'))}) |")
            lines.append("")
    lines += ["## What wins where", "", "| light | level | metric | design | value |", "|---|---:|---|---|---:|"]
    for w in results["winners"]:
        lines.append(f"| {w['illuminant']} | {w['light_factor']:g}× | {w['metric']} | {w['design']} | "
                     f"{_fmt(w['value'], w['sd'])} |")
    lines += ["", "Spatial resolution (MTF50, false colour, S-CIELAB) and motion (colour breakup) of the paper's "
              "three architectures: `spectracam spatial` and `spectracam motion`.", ""]
    return "\n".join(lines)
