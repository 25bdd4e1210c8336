"""The architectures comparison's figures and report (``spectracam architectures``)."""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from spectracam.io.plots import palette, pyplot

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["figure_comparison", "figure_responsivities", "figure_spacetime", "report_markdown"]


def _rows(results, light, factor):
    return [r for r in results["rows"] if r["illuminant"] == light and r["light_factor"] == factor]


def figure_comparison(results: dict) -> Figure:
    """Figure 5-style panels per light: rendered SNR (a) and per-pixel ΔE (b) of every design against
    the light level (log), error bars the spread over seeds; (c) held-out against training conversion
    error at the paper's level.

    Parameters
    ----------
    results : dict
        An architectures run's results (``rows``, ``parameters``).

    Returns
    -------
    matplotlib.figure.Figure
        One row of three panels per light.
    """
    plt = pyplot()
    lights = list(dict.fromkeys(r["illuminant"] for r in results["rows"]))
    designs = results["parameters"]["designs"]
    fig, axes = plt.subplots(len(lights), 3, figsize=(16, 5.2 * len(lights)), squeeze=False)
    cmap = plt.get_cmap("tab20")
    styles = {d: dict(color=cmap(i % 20), marker="osD^v<>p*hX"[i % 11], ls="-" if d.endswith("single") else "--")
              for i, d in enumerate(designs)}
    for row_axes, light in zip(axes, lights):
        for ax, metric, label in ((row_axes[0], "snr_rendered_db", "rendered luminance SNR (dB)"),
                                  (row_axes[1], "delta_e_mean", "per-pixel ΔE*ab (lines) and S-CIELAB (dotted)")):
            _draw_level_panel(ax, results, light, metric, label, styles)
        _draw_conversion_panel(row_axes[2], results, light, styles)
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), 7), fontsize=9, frameon=False)
    fig.suptitle(f"Every architecture with the paper's camera and noise ({len(results['parameters']['seeds'])} "
                 "seeds; bars: ±1 sample std over seeds)", fontsize=13)
    fig.tight_layout(rect=(0, 0.06, 1, 0.97))
    return fig


def _draw_level_panel(ax, results: dict, light: str, metric: str, label: str, styles: dict) -> None:
    """One light's ``metric`` of every design against the light level (S-CIELAB dotted beside ΔE*ab)."""
    designs = results["parameters"]["designs"]
    factors = results["parameters"]["light_factors"]
    level = results["parameters"]["paper_white_luminance_cd_m2"]
    for d in designs:
        for m, extra in ((metric, {}), *((("s_cielab_mean", {"ls": ":", "label": None}),)
                                         if metric == "delta_e_mean" else ())):
            pts = [(f * level, r[m], r[f"{m}_sd"], r.get("usable", True) is not False) for f in factors
                   for r in _rows(results, light, f) if r["design"] == d and r.get(m) is not None]
            if pts:
                x, y, e, ok = map(np.array, zip(*pts))
                ax.errorbar(x, y, yerr=e, capsize=3, **{"label": d, **styles[d], **extra})
                if (~ok).any():   # no usable image: greyed, hatched markers over the design's own
                    ax.scatter(x[~ok], y[~ok], s=90, facecolor="0.85", edgecolor="0.4", hatch="////",
                               zorder=4, label=None)
    if any(r.get("usable") is False for r in results["rows"] if r["illuminant"] == light):
        ax.text(0.01, 0.01, "grey hatched: no usable image (docs/metrics.md); never ranked",
                transform=ax.transAxes, fontsize=8, color="0.3", va="bottom")
    ax.set_xscale("log")
    ax.set_xlabel("white luminance (cd/m²); the paper's light is the rightmost")
    ax.set_ylabel(label)
    ax.set_title(f"{light}: {label}", fontsize=11)
    ax.grid(True, which="both", alpha=0.3)
    if metric == "delta_e_mean":
        ax.set_yscale("log")


def _draw_conversion_panel(ax, results: dict, light: str, styles: dict) -> None:
    """One light's held-out against training conversion error at the paper's level, coinciding designs labelled once."""
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


def figure_responsivities(results: dict) -> Figure:
    """Each architecture's channel responsivities R_k(λ) (filter × QE × IR cut, e⁻/photon) on the
    scene's bands.

    Parameters
    ----------
    results : dict
        An architectures run's results: the architectures of its ``rows``, the camera of ``parameters["scene"]``.

    Returns
    -------
    matplotlib.figure.Figure
        One panel per architecture, four to a row, against wavelength, nm.
    """
    from spectracam.camera import CameraSpec, camera_responsivities
    from spectracam.pipeline.scene_file import Scene

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


def figure_spacetime(results: dict) -> Figure:
    """(a) MTF50 against false colour at the edge for every spatial design (resolution against colour
    artefacts; hollow markers: with the optical low-pass filter); (b) S-CIELAB spatial error on the star;
    (c) colour breakup and (d) S-CIELAB against the own still capture, against speed.

    Parameters
    ----------
    results : dict
        An architectures run's results: ``space`` (the spatial rows and parameters, noise off) and ``time`` (the
        motion rows).

    Returns
    -------
    matplotlib.figure.Figure
        Four panels, one colour per architecture.
    """
    plt = pyplot()
    space, time_ = results["space"], results["time"]
    archs = list(dict.fromkeys(r["design"].split("/")[0] for r in time_["rows"]))
    colour = dict(zip(archs, palette(len(archs))))
    fig, axes = plt.subplots(2, 2, figsize=(18, 11), gridspec_kw={"wspace": 0.75})
    _draw_tradeoff_panel(axes[0, 0], space, colour)
    ax = axes[0, 1]
    rows = sorted(space["rows"], key=lambda r: r["scielab_spatial_star"])
    y = np.arange(len(rows))
    ax.barh(y, [r["scielab_spatial_star"] for r in rows], color=[colour.get(r["design"].split("/")[0], "k") for r in rows])
    ax.set_yticks(y, [r["label"] for r in rows], fontsize=7)
    ax.invert_yaxis()
    ax.set(xlabel="S-CIELAB ΔE*ab on the Siemens star (spatial error; lower is better)",
           title="(b) colour moiré and blur on the star")
    ax.title.set_fontsize(10)
    ax.grid(True, axis="x", alpha=0.3)
    designs = list(dict.fromkeys(r["design"] for r in time_["rows"]))
    for ax, metric, label in ((axes[1, 0], "breakup_width_px",
                               "(c) colour breakup, px (spread of the channels' edges, motion alone)"),
                              (axes[1, 1], "scielab_delta_e", "(d) S-CIELAB ΔE*ab against the own still capture")):
        for i, d in enumerate(designs):
            pts = sorted((r["speed_px_per_ms"], np.nan if r[metric] is None else r[metric])   # None: no edge found
                         for r in time_["rows"] if r["design"] == d)
            x, v = zip(*pts)
            ax.plot(x, v, marker="osD^v<>p"[i % 8], color=colour[d.split("/")[0]], label=d)
        ax.set(xlabel="image speed on the sensor, px/ms", ylabel=label.split(") ")[1], title=label)
        ax.title.set_fontsize(10)
        ax.grid(True, alpha=0.3)
    axes[1, 1].legend(fontsize=8)
    sp = space["parameters"]
    fig.suptitle(f"Space (noise off, {sp['pixel_pitch_um']:g} µm pixel, f/{sp['f_number']:g}) and time (the paper's "
                 "noise and light, global shutter): every architecture", fontsize=12)
    fig.subplots_adjust(left=0.05, right=0.98, top=0.92, bottom=0.06, hspace=0.3)   # room for panel (a)'s key
    return fig


def _draw_tradeoff_panel(ax, space: dict, colour: dict) -> None:
    """:func:`figure_spacetime`'s panel (a): MTF50 against false colour at the edge of every spatial design,
    designs that coincide numbered once, with a key beside the panel."""
    points: dict = {}    # designs that coincide (noise-free planes of the same filters) share one label
    for r in space["rows"]:
        if r["mtf50_cy_per_px"] is None:
            continue
        olpf = r["olpf_separation_px"] > 0
        c = colour.get(r["design"].split("/")[0], "k")
        ax.scatter(r["false_colour_edge"], r["mtf50_cy_per_px"], s=55, marker="s" if r["demosaic"] == "menon2007" else "o",
                   facecolors="none" if olpf else c, edgecolors=c, linewidths=1.5)
        key = (round(r["false_colour_edge"], 2), round(r["mtf50_cy_per_px"], 3))
        points.setdefault(key, []).append(r["label"].replace("/single", "").replace("/optimal", "").replace(" aligned", ""))
    key = []   # numbers beside the points and a key beside the panel: the names no longer collide
    for n, ((x, y), names) in enumerate(sorted(points.items(), key=lambda kv: (-kv[0][1], kv[0][0])), start=1):
        ax.annotate(str(n), (x, y), fontsize=7, xytext=(4, 2) if n % 2 else (4, -8), textcoords="offset points")
        key.append(f"{n:>2}  {' = '.join(names)}")
    ax.text(1.02, 1.0, "\n".join(key), transform=ax.transAxes, va="top", ha="left", fontsize=6.5, family="monospace")
    ax.set_xscale("symlog", linthresh=0.5)
    ax.set(xlabel="false colour at the neutral edge, √(Δa*²+Δb*²) (lower is better)",
           ylabel="MTF50 of displayed luminance, cy/px (higher is better)",
           title="(a) resolution against false colour (circles bilinear, squares Menon 2007; hollow: OLPF 1 px)")
    ax.title.set_fontsize(10)
    ax.grid(True, alpha=0.3)


def _fmt(v, sd=None, digits=2):
    if v is None:
        return "–"
    return f"{v:.{digits}f}" + (f" ± {sd:.{digits}f}" if sd is not None else "")


def _rank(rows, key) -> dict:
    order = sorted((r for r in rows if r.get(key) is not None), key=lambda r: r[key])
    return {r["design"]: i + 1 for i, r in enumerate(order)}


def _both_ways_table(rows) -> list[str]:
    """The oracle camera (told the light) beside the developed one (finds its own white), with each one's rank."""
    ro, rd = _rank(rows, "delta_e_mean"), _rank(rows, "developed_delta_e_mean")
    out = ["The same designs with a camera that is told the light (oracle) and one that finds its own white "
           "(developed: percentile metering, corrected-moments white balance, dual-illuminant calibration):", "",
           "| design | ΔE*ab oracle (rank) | ΔE*ab developed (rank) | CIEDE2000 oracle / developed | "
           "white error ° ± sd | held-out ΔE oracle / developed | developed capture ms |",
           "|---|---:|---:|---:|---:|---:|---:|"]
    for r in sorted(rows, key=lambda r: r["developed_delta_e_mean"] if r["developed_delta_e_mean"] is not None
                    else float("inf")):
        out.append(f"| {r['design']} | {_fmt(r['delta_e_mean'], r['delta_e_mean_sd'])} ({ro.get(r['design'], '–')}) | "
                   f"{_fmt(r['developed_delta_e_mean'], r['developed_delta_e_mean_sd'])} "
                   f"({rd.get(r['design'], '–')}) | {_fmt(r.get('delta_e2000_mean'))} / "
                   f"{_fmt(r['developed_delta_e2000_mean'])} | "
                   f"{_fmt(r['developed_awb_recovery_deg'], r['developed_awb_recovery_deg_sd'])} | "
                   f"{_fmt(r.get('held_out_delta_e'))} / {_fmt(r.get('developed_held_out_delta_e'))} | "
                   f"{r['developed_capture_time_ms']:.2f} |")
    return out + [""]


def report_markdown(results: dict, command: str) -> str:
    """report.md: the setup, one table per light and level, and what wins where.

    Parameters
    ----------
    results : dict
    command : str

    Returns
    -------
    str"""
    p = results["parameters"]
    lines = ["# Every architecture with the paper's camera", "", f"Command: `{command}`", "",
             f"Renderer {p['renderer']}{' (quick: 160x120)' if p['quick'] else ''}; seeds {p['seeds']}; the "
             f"paper's light: a white of {p['paper_white_luminance_cd_m2']:.2f} cd/m² (×{', ×'.join(f'{f:g}' for f in p['light_factors'])}).",
             "", "Definitions:", ""]
    for key in ("snr_db", "snr_rendered_db", "delta_e_mean", "s_cielab_mean", "delta_e_training",
                "held_out_delta_e", "usable"):
        if key in p:
            lines.append(f"- `{key}`: {p[key]}")
    lines.append("")
    for light in dict.fromkeys(r["illuminant"] for r in results["rows"]):
        for f in p["light_factors"]:
            rows = _rows(results, light, f)
            sc_rank = _rank([r for r in rows if r.get("usable", True) is not False], "s_cielab_mean")
            de_rank = _rank([r for r in rows if r.get("usable", True) is not False], "delta_e_mean")
            lines += [f"## {light}, {f:g}× the paper's light", "",
                      "| design | channels | capture ms | ΔE*ab mean ± sd (rank) | S-CIELAB mean ± sd (rank) | "
                      "rendered SNR dB ± sd | white SNR dB | raw SNR dB | training ΔE | held-out ΔE (p95) | "
                      "usable |",
                      "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
            for r in sorted(rows, key=lambda r: (r.get("usable", True) is False, r["delta_e_mean"])):
                usable = "yes" if r.get("usable", True) is not False else f"**no**: {r['unusable_reason']}"
                lines.append(f"| {r['design']} | {r['channels']} | {r['capture_time_ms']:.2f} | "
                             f"{_fmt(r['delta_e_mean'], r['delta_e_mean_sd'])} ({de_rank.get(r['design'], '–')}) | "
                             f"{_fmt(r.get('s_cielab_mean'), r.get('s_cielab_mean_sd'))} "
                             f"({sc_rank.get(r['design'], '–')}) | "
                             f"{_fmt(r['snr_rendered_db'], r['snr_rendered_db_sd'])} | "
                             f"{_fmt(r.get('snr_white_rendered_db'), digits=1)} | {_fmt(r['snr_db'])} | "
                             f"{_fmt(r['delta_e_training'])} | {_fmt(r.get('held_out_delta_e'))} "
                             f"({_fmt(r.get('held_out_delta_e_p95'))}) | {usable} |")
            lines += ["", "Ranks count usable cases only (–: no usable image).", ""]
            if rows and "developed_delta_e_mean" in rows[0]:
                lines += _both_ways_table(rows)
    if "natural" in results:
        lines += _natural_markdown(results)
    lines += ["## What wins where", "",
              "Each verdict names the score it rests on: `delta_e_mean` is the per-pixel ΔE*ab against the scene, "
              "`s_cielab_mean` the same pixels through the eye's filters (S-CIELAB: a demosaicker's averaging "
              "counts for no more than the eye's), `snr_rendered_db` the rendered luminance SNR; `developed_*` the "
              "camera that finds its own white. Only usable cases are ranked; \"no usable image\" where none is.", "",
              "| light | level | metric (the score it rests on) | design | value |", "|---|---:|---|---|---:|"]
    for w in results["winners"]:
        lines.append(f"| {w['illuminant']} | {w['light_factor']:g}× | {w['metric']} | "
                     f"{w['design'] if w['design'] is not None else w.get('note', 'no usable image')} | "
                     f"{_fmt(w['value'], w['sd'])} |")
    lines += _verdict_lines(results)
    if "space" in results:
        lines += _spacetime_markdown(results)
    return "\n".join(lines)


def _verdict_lines(results: dict) -> list[str]:
    """Does S-CIELAB change the order of the paper's prism and the Bayer array (and Quad Bayer's place)?  Per light
    and level where both are usable: the ΔE*ab and S-CIELAB differences with their seed spreads."""
    out = []
    pairs = (("prism/optimal", "cfa/single"), ("quad_bayer/single", "cfa/single"),
             ("quad_bayer/single", "prism/optimal"))
    for light in dict.fromkeys(r["illuminant"] for r in results["rows"]):
        for f in results["parameters"]["light_factors"]:
            rows = {r["design"]: r for r in _rows(results, light, f)}
            for a, b in pairs:
                ra, rb = rows.get(a), rows.get(b)
                if ra is None or rb is None:
                    continue
                if ra.get("usable") is False or rb.get("usable") is False:
                    out.append(f"- {light}, {f:g}×: {a} against {b}: no verdict (no usable image: "
                               f"{ra.get('unusable_reason') or rb.get('unusable_reason')})")
                    continue
                if ra.get("s_cielab_mean") is None or rb.get("s_cielab_mean") is None:
                    continue

                def word(x, y):
                    return "ahead of" if x < y else "behind"
                de_a, de_b = ra["delta_e_mean"], rb["delta_e_mean"]
                sc_a, sc_b = ra["s_cielab_mean"], rb["s_cielab_mean"]
                same = (de_a < de_b) == (sc_a < sc_b)
                out.append(f"- {light}, {f:g}×: {a} is {word(de_a, de_b)} {b} on per-pixel ΔE*ab ({de_a:.2f} ± "
                           f"{ra['delta_e_mean_sd'] or 0:.2f} vs {de_b:.2f} ± {rb['delta_e_mean_sd'] or 0:.2f}) and "
                           f"{word(sc_a, sc_b)} it on S-CIELAB ({sc_a:.2f} ± {ra['s_cielab_mean_sd'] or 0:.2f} vs "
                           f"{sc_b:.2f} ± {rb['s_cielab_mean_sd'] or 0:.2f}): "
                           + ("the same verdict" if same else "**S-CIELAB reverses the verdict**"))
    return (["", "### Does S-CIELAB change the verdict?", "",
             "Per-pixel ΔE*ab counts a demosaicker's averaging of neighbours as less noise; S-CIELAB blurs every "
             "design's noise by the eye's filters. ± is the spread over seeds (sample std).", ""] + out + [""]
            if out else [])


def _natural_markdown(results: dict) -> list[str]:
    nat = results["natural"]
    lines = ["## Natural scenes", "",
             "Every design on the shipped textured targets, the paper's camera and level, the targets' own light; "
             "every pixel scored against its known spectra (colours the conversion was not fitted on): per-pixel "
             "ΔE*ab and S-CIELAB at each target's viewing geometry (spectracam.evaluation.target_score), mean ± sd over seeds.",
             ""]
    for name, g in nat["parameters"].items():
        rows = [r for r in nat["rows"] if r["scene"] == name]
        de, sc = _rank(rows, "delta_e_mean"), _rank(rows, "s_cielab_mean")
        lines += [f"### {name} ({g['image_px'][0]}x{g['image_px'][1]}, {g['illuminant']}, "
                  f"{g['viewing_distance_m']:g} m, {g['display_pixel_pitch_mm']:.3g}-mm display pixels)", "",
                  "| design | ΔE*ab mean ± sd (rank) | ΔE*ab p95 | S-CIELAB mean ± sd (rank) | S-CIELAB p95 |",
                  "|---|---:|---:|---:|---:|"]
        for r in sorted(rows, key=lambda r: r["s_cielab_mean"]):
            lines.append(f"| {r['design']} | {_fmt(r['delta_e_mean'], r['delta_e_mean_sd'])} ({de[r['design']]}) | "
                         f"{_fmt(r['delta_e_p95'])} | {_fmt(r['s_cielab_mean'], r['s_cielab_mean_sd'])} "
                         f"({sc[r['design']]}) | {_fmt(r['s_cielab_p95'])} |")
        lines.append("")
    return lines


def _spacetime_markdown(results: dict) -> list[str]:
    space, time_ = results["space"], results["time"]
    sp = space["parameters"]
    lines = ["", "## Space", "",
             f"The spatial experiment's slanted edge (5°, 4:1) and Siemens star, {sp['pixel_pitch_um']:g} µm pixel, "
             f"f/{sp['f_number']:g}, sensor noise {'on' if sp['noise'] else 'off (the spatial artefacts alone)'}, "
             f"renderer {sp['renderer']} ({space['wall_s']:.1f} s). MTF50: e-SFR of the displayed luminance; false "
             "colour: mean chroma √(Δa*²+Δb*²) within 2 px of the neutral edge against the same camera's rendering of "
             "the ideal image; S-CIELAB: spatial error on the star against the same reference (docs/metrics.md).", "",
             "| design | MTF50 cy/px | false colour, edge | false colour, star | S-CIELAB star |",
             "|---|---:|---:|---:|---:|"]
    for r in sorted(space["rows"], key=lambda r: -(r["mtf50_cy_per_px"] or 0)):
        lines.append(f"| {r['label']} | {_fmt(r['mtf50_cy_per_px'], digits=3)} | {_fmt(r['false_colour_edge'])} | "
                     f"{_fmt(r['false_colour_star'])} | {_fmt(r['scielab_spatial_star'])} |")
    tp = time_["parameters"]
    lines += ["", "## Time", "",
              f"The motion experiment's edge moving across the sensor, global shutter, the paper's noise, light set so "
              f"that cfa/single needs 28 ms (white {tp['white_luminance_cd_m2']:.1f} cd/m²), renderer {tp['renderer']} "
              f"({time_['wall_s']:.1f} s). Breakup: the spread of the colour channels' edge positions (each where its "
              "profile across the edge crosses 50 %, sub-pixel) beyond their spread in the design's own noise-free "
              "still capture (noise-free captures: motion alone; blur does not move a 50 % point, docs/metrics.md). "
              "S-CIELAB (motion): the noisy capture "
              "against that still capture. False colour (still): the still capture against the camera's rendering of "
              "the ideal image, within 2 px of the edge (demosaicking).", "",
              "| design | capture ms | speed px/ms | breakup px | S-CIELAB (motion) | false colour (still) | MTF50 |",
              "|---|---:|---:|---:|---:|---:|---:|"]
    for r in time_["rows"]:
        lines.append(f"| {r['design']} | {r['capture_time_ms']:.1f} | {r['speed_px_per_ms']:g} | "
                     f"{_fmt(r['breakup_width_px'])} | {r['scielab_delta_e']:.2f} | "
                     f"{r['false_colour_still']:.2f} | {_fmt(r['mtf50_cy_per_px'], digits=3)} |")
    lines += ["", "## What wins in space and time", "", "| part | metric | design | value |", "|---|---|---|---:|"]
    for w in results["spacetime_winners"]:
        at = f" at {w['speed_px_per_ms']:g} px/ms" if "speed_px_per_ms" in w else ""
        lines.append(f"| {w['part']} | {w['metric']}{at} | {w['design']} | {w['value']:.3f} |")
    lines += ["", "![space and time](architectures_spacetime.png)", ""]
    return lines
