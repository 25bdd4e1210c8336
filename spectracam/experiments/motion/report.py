"""Outputs of the motion experiment: results.json, mtf_curves.json, figures (PNG + SVG), an animated
GIF of the field-sequential frames, report.md; every case's images and maps (:mod:`.cases`)."""
from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np

from spectracam.core.files import atomic_write, json_default
from spectracam.io.plots import pyplot, save_figure, srgb_image
from spectracam.experiments.motion.cases import MAP_VMIN_TOP, case_stem, map_name, write_case_outputs
from spectracam.experiments.motion.experiment import series

__all__ = ["COLOURS", "REST_AT", "answer", "figure_crops", "figure_curves", "fsc_frames_gif",
           "report_markdown", "write_outputs"]

COLOURS = {"cfa/single": "#D55E00", "prism/optimal": "#0072B2", "fsc/optimal": "#009E73",
           "fsc/balanced": "#CC79A7"}   # Okabe & Ito's (spectracam.io.plots.OKABE_ITO): distinct to colour-blind readers


def _designs(rows):
    return list(dict.fromkeys(r.design for r in rows))


def _snr(rows, design):
    return next((r.snr_db for r in rows if r.design == design), None)


#: Where "at rest" is drawn on a log speed axis: this fraction of the slowest moving speed.
REST_AT = 1 / 3


def _speed_axis(ax, speeds):
    """A log axis of image speed with ticks only at the speeds that ran, the still capture drawn apart
    at the left ("at rest", after an axis break). Returns the x of each speed."""
    from matplotlib.ticker import NullLocator

    moving = [s for s in speeds if s > 0]
    if not moving:
        return {s: s for s in speeds}
    rest = moving[0] * REST_AT
    xs = {s: (rest if s == 0 else s) for s in speeds}
    ax.set_xscale("log")
    ax.set_xticks(sorted(xs.values()))
    ax.set_xticklabels([("at rest" if s == 0 else f"{s:g}") for s in sorted(speeds)], rotation=45, ha="right",
                       rotation_mode="anchor", fontsize=9)
    ax.xaxis.set_minor_locator(NullLocator())
    ax.set_xlim(moving[0] * REST_AT ** 1.5, moving[-1] * 1.3)
    if 0 in speeds:   # the break between "at rest" and the log axis: two slashes on the x axis
        b = moving[0] * REST_AT ** 0.5
        for dx in (0.93, 1.07):
            ax.plot([b * dx / 1.03, b * dx * 1.03], [-0.015, 0.015], transform=ax.get_xaxis_transform(),
                    color="k", lw=1.0, clip_on=False)
    return xs


def _plot_design(ax, xs, speeds, values, rolling, colour):
    """One design's series: the moving speeds joined, the still one joined by a dotted line (across the break)."""
    x = np.array([xs[s] for s in speeds])
    y = np.asarray(values, float)
    ls = "--" if rolling else "-"
    kw = dict(color=colour, alpha=0.7 if rolling else 1.0, lw=1.4)
    moving = np.asarray(speeds) > 0
    ax.plot(x[moving], y[moving], ls, marker="x" if rolling else "o", ms=4, **kw)
    if (~moving).any() and moving.any():
        ax.plot(x[~moving], y[~moving], marker="x" if rolling else "o", ms=4, ls="none", **kw)
        first = np.argmax(moving)
        ax.plot([x[~moving][0], x[first]], [y[~moving][0], y[first]], ":", **kw)


def _crossing_band(ax, ans, lo_x):
    """The crossing (dotted line) and its 95 % interval over the seeds (shaded), where on the axis."""
    v = ans.get("speed_px_per_ms")
    if v:
        ax.text(0.02, 0.97, f"fsc/optimal worse than cfa/single\nfrom {v:.2g} px/ms (zoomed in d)",
                transform=ax.transAxes, va="top", fontsize=9)
    if v and v >= lo_x:
        ax.axvline(v, color="0.3", lw=0.9, ls=":")
    ci = ans.get("ci95_px_per_ms")
    if ci and ci[0] >= lo_x:
        ax.axvspan(ci[0], ci[1], color="0.5", alpha=0.18, lw=0)


def _crossing_window(ans) -> tuple[float, float]:
    """The speeds the crossing panel shows: the crossing ± 2.5 half-widths of its 95 % interval, at least
    ± 15 % of the swept step it lies in, never below 0."""
    v = ans["speed_px_per_ms"]
    step = ans["between"][1] - ans["between"][0]
    if not ans.get("ci95_px_per_ms"):    # one capture per speed: half the step either side
        return max(0.0, v - step / 2), v + step / 2
    lo, hi = ans["ci95_px_per_ms"]
    pad = max(2.5 * (hi - lo) / 2, 0.15 * step)
    return max(0.0, min(lo, v) - pad), max(hi, v) + pad


def _panel_crossing(ax, result, design="fsc/optimal", other="cfa/single"):
    """The S-CIELAB crossing of ``design`` over ``other`` (global shutter) on a linear axis zoomed on it: the
    means (±1 sd over the seeds at the swept speeds), each seed's curve, the crossing and its 95 % interval."""
    from matplotlib.ticker import MaxNLocator

    rows = result["rows"]
    ans = result["answer"].get(design, {}).get("scielab", {})
    ax.set_title(f"(d) the crossing: {design} against {other}, global shutter\n(S-CIELAB ΔE*ab, zoomed; linear speed)",
                 fontsize=11)
    if ans.get("status") != "crosses":
        ax.text(0.5, 0.5, f"{design}: {ans.get('status', 'not run')}", ha="center", va="center",
                transform=ax.transAxes, fontsize=11)
        ax.set_axis_off()
        return
    x0, x1 = _crossing_window(ans)
    grid = np.linspace(x0, x1, 50)
    seen = []
    for d in (other, design):
        rs = sorted((r for r in rows if r.design == d and not r.rolling_shutter), key=lambda r: r.speed_px_per_ms)
        x = np.array([r.speed_px_per_ms for r in rs])
        y = np.array([r.scielab_delta_e for r in rs], float)
        sd = np.array([r.scielab_delta_e_sd or 0.0 for r in rs])
        per = np.array([r.scielab_delta_e_by_seed for r in rs], float)
        c = COLOURS.get(d, "#7f7f7f")
        several = per.ndim == 2 and per.shape[1] > 1
        ax.plot(x, y, color=c, lw=1.8, label=d + (", mean (± 1 sd at the swept speeds)" if several else ""))
        ax.errorbar(x, y, yerr=sd, color=c, ls="none", marker="o", ms=5, capsize=3)
        if several:
            ax.plot(x, per, color=c, lw=0.7, alpha=0.4)
            seen += [np.interp(grid, x, per[:, j]) for j in range(per.shape[1])]
        seen.append(np.interp(grid, x, y))
    v = ans["speed_px_per_ms"]
    ci = ans.get("ci95_px_per_ms")
    ax.axvline(v, color="0.2", lw=1.0, ls=":", label=f"crossing{' of the means' if ci else ''}, {v:.3g} px/ms")
    if ci:
        n = len(ans["by_seed_px_per_ms"])
        ax.axvspan(ci[0], ci[1], color="0.5", alpha=0.2, lw=0,
                   label=f"95 % interval over {n} seeds: {ci[0]:.2g}–{ci[1]:.2g} px/ms")
        for p in ans["by_seed_px_per_ms"]:
            ax.plot([p, p], [0, 0.05], transform=ax.get_xaxis_transform(), color="0.2", lw=1.4)
    lo, hi = float(np.min(seen)), float(np.max(seen))
    ax.set_xlim(x0, x1)
    ax.xaxis.set_major_locator(MaxNLocator(5))
    ax.set_ylim(lo - 0.1 * (hi - lo), hi + 0.45 * (hi - lo))   # room for the legend above the curves
    ax.set_xlabel("image speed, px/ms (linear)" + ("\nthin lines: each seed, joined linearly between the swept "
                  "speeds as the crossing is;\nshort marks: each seed's crossing" if ci else ""), fontsize=10)
    ax.set_ylabel("S-CIELAB ΔE*ab against the still capture", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=9, loc="upper left")


def figure_curves(result: dict, out: Path) -> list[Path]:
    """breakup_scielab.png/.svg: breakup width, S-CIELAB and CIELAB against speed for every design and
    shutter, and the S-CIELAB crossing of fsc/optimal over cfa/single zoomed.

    Parameters
    ----------
    result : dict
        The motion run's result.
    out : Path
        The output directory.

    Returns
    -------
    list of Path
        The PNG and SVG.
    """
    from matplotlib.lines import Line2D

    plt = pyplot()
    rows = result["rows"]
    spec = result["parameters"]["motion"]
    shutters = sorted({r.rolling_shutter for r in rows})
    speeds = sorted({r.speed_px_per_ms for r in rows})
    seeds = len(rows[0].seeds)
    mean = f" (mean over {seeds} noise seeds)" if spec["noise"] and seeds > 1 else ""
    panels = [("breakup_width_px", "(a) colour breakup, px: spread of the channels' edges\n(moved by the motion, "
               "sub-pixel; noise-free captures)"),
              ("scielab_delta_e", f"(b) S-CIELAB ΔE*ab at the edge{mean}\n(against the camera's own still capture)"),
              ("cielab_delta_e", f"(c) CIELAB ΔE*ab at the edge{mean}\n(against the camera's own still capture)")]
    fig, axes = plt.subplots(2, 2, figsize=(13, 10), constrained_layout=True)
    ans = result["answer"].get("fsc/optimal", {}).get("scielab", {})
    for ax, (key, title) in zip(axes.ravel(), panels):
        xs = _speed_axis(ax, speeds)
        for d in _designs(rows):
            for rolling in shutters:
                s, y = series(rows, d, rolling, key)
                _plot_design(ax, xs, list(s), y, rolling, COLOURS.get(d, "#7f7f7f"))
        ax.set_xlabel("image speed, px/ms (log scale; ticks: the swept speeds)", fontsize=10)
        ax.set_title(title, fontsize=11)
        ax.grid(alpha=0.3)
    moving = [s for s in speeds if s > 0]
    if moving:
        _crossing_band(axes[0, 1], ans, moving[0])
    _panel_crossing(axes[1, 1], result)
    handles = [Line2D([], [], color=COLOURS.get(d, "#7f7f7f"), marker="o", ms=4,
                      label=d + (f" (SNR {_snr(rows, d):.1f} dB)" if spec["noise"] and _snr(rows, d) is not None else ""))
               for d in _designs(rows)]
    if len(shutters) > 1:
        handles += [Line2D([], [], color="0.3", ls="-", marker="o", ms=4, label="global shutter"),
                    Line2D([], [], color="0.3", ls="--", marker="x", ms=4, alpha=0.7, label="rolling shutter")]
    axes[0, 0].legend(handles=handles, fontsize=9, loc="upper left")
    noise = ("the paper's sensor noise; legend: each design's chart SNR" if spec["noise"] else "sensor noise off")
    fig.suptitle(f"A moving neutral edge captured by each design ({noise})\nsolid: global shutter, dashed: rolling; "
                 "dotted: from the still capture (drawn apart at the left) to the slowest speed", fontsize=12)
    return save_figure(fig, out / "breakup_scielab.png", out / "breakup_scielab.svg")


def _pick_speeds(speeds, n=4):
    speeds = sorted(speeds)
    if len(speeds) <= n:
        return speeds
    idx = np.unique(np.round(np.linspace(0, len(speeds) - 1, n)).astype(int))
    return [speeds[i] for i in idx]


def _crop(im, rows=None):
    h = im.shape[0]
    r = rows or max(8, h // 6)
    return im[h // 2 - r:h // 2 + r, 4:-4]   # demosaicking's border columns left out


def figure_crops(result: dict, out: Path, rolling: bool = False) -> list[Path]:
    """crops.png (crops_rolling.png with ``rolling``): the moving edge as each design shows it at up to four speeds,
    under the scene at t = 0, nearest-neighbour zoomed.

    Parameters
    ----------
    result : dict
        The motion run's result (its kept images).
    out : Path
    rolling : bool
        The rolling-shutter cases (else the global shutter's).

    Returns
    -------
    list of Path
        The PNG.
    """
    plt = pyplot()
    rows = result["rows"]
    designs = _designs(rows)
    speeds = _pick_speeds({r.speed_px_per_ms for r in rows})
    white = result["display_white"]
    fig, axes = plt.subplots(len(designs) + 1, len(speeds), figsize=(3.0 * len(speeds), 1.35 * (len(designs) + 1)),
                             squeeze=False, constrained_layout=True)
    ideal = result["images"][(designs[0], "ideal")]["xyz"]
    for j, v in enumerate(speeds):
        ax = axes[0, j]
        ax.imshow(srgb_image(_crop(ideal).astype(float), white), interpolation="nearest")
        ax.set_title(f"{v:g} px/ms" if v > 0 else "at rest", fontsize=11)
        for i, d in enumerate(designs):
            im = result["images"][(d, v, rolling)]["xyz"]
            axes[i + 1, j].imshow(srgb_image(_crop(im).astype(float), white), interpolation="nearest")
    for i, lab in enumerate(["scene (t = 0)"] + designs):
        axes[i, 0].set_ylabel(lab, fontsize=10)
    for ax in axes.ravel():
        ax.set_xticks([]), ax.set_yticks([])
    fig.suptitle(f"The moving edge as each design shows it ({'rolling' if rolling else 'global'} shutter; "
                 "motion to the right; nearest-neighbour zoom)", fontsize=12)
    return [save_figure(fig, out / f"crops{'_rolling' if rolling else ''}.png")]


#: The GIF's width at least (its pixels repeated) and its captions' font size, px: text ≥ 12 px high.
GIF_MIN_WIDTH_PX, CAPTION_FONT_PX = 512, 18


def _caption_font(size_px: int):
    """A scalable font for the GIF's captions: matplotlib's DejaVu Sans (always there with matplotlib)."""
    from matplotlib import font_manager
    from PIL import ImageFont

    return ImageFont.truetype(font_manager.findfont("DejaVu Sans"), size_px)


def _wrap(text: str, font, width_px: int) -> list[str]:
    lines, line = [], ""
    for word in text.split():
        trial = f"{line} {word}".strip()
        if line and font.getlength(trial) > width_px:
            lines.append(line)
            line = word
        else:
            line = trial
    return lines + [line]


def _captioned(rgb: np.ndarray, lines: list[str], n_lines: int, scale: int, font):
    """A frame (0–1 RGB) zoomed ``scale`` times under its caption (room for ``n_lines`` lines, so that
    every frame of the GIF has the same size), white on black, as a palette image."""
    from PIL import Image, ImageDraw

    a = (np.clip(rgb, 0, 1) * 255).astype(np.uint8)
    a = np.repeat(np.repeat(a, scale, 0), scale, 1)
    step = CAPTION_FONT_PX + 6
    top = step * n_lines + 4
    canvas = Image.new("RGB", (a.shape[1], a.shape[0] + top), (0, 0, 0))
    canvas.paste(Image.fromarray(a), (0, top))
    draw = ImageDraw.Draw(canvas)
    for i, line in enumerate(lines):
        draw.text((4, 3 + i * step), line, fill=(255, 255, 255), font=font)
    return canvas.convert("P", palette=Image.ADAPTIVE, colors=255)


def fsc_frames_gif(result: dict, out: Path, design: str = "fsc/optimal", speed: float | None = None) -> list[Path]:
    """An animated GIF: the field-sequential camera's R, G and B frames (each in its colour, as the
    sensor recorded them, one after another) and then the displayed image they make together; zoomed
    to at least :data:`GIF_MIN_WIDTH_PX` wide, captions of :data:`CAPTION_FONT_PX` px.

    Parameters
    ----------
    result : dict
        The motion run's result (its kept images and exposure windows).
    out : Path
    design : str
        A three-frame design.
    speed : float or None
        px/ms; None: the fastest whose smear stays within a third of the image's width.

    Returns
    -------
    list of Path
        fsc_frames.gif; empty when the design has no global-shutter case.
    """
    rows = [r for r in result["rows"] if r.design == design and not r.rolling_shutter]
    if not rows:
        return []
    w = result["images"][(design, rows[0].speed_px_per_ms, False)]["xyz"].shape[1]
    if speed is None:   # the fastest speed whose whole smear stays inside the image's middle half
        ok = [r.speed_px_per_ms for r in rows if r.blur_px <= w / 3] or [rows[0].speed_px_per_ms]
        speed = max(ok)
    im = result["images"][(design, speed, False)]
    rates = np.asarray(im["cam_rates"], float)
    top = np.percentile(rates, 99.5, axis=(0, 1))
    window = result["exposure_timing"].get(design, {})
    tints = np.eye(3)
    frames, names = [], []
    for k in range(3):
        g = np.clip(rates[..., k] / top[k], 0, 1)
        rgb = g[..., None] * (0.25 + 0.75 * tints[k])[None, None, :]
        frames.append(rgb ** (1 / 2.2))
        when = ""
        if window.get("start_ms"):
            t0, dt = window["start_ms"][k], window["duration_ms"][k]
            when = f", t = {t0:.0f} to {t0 + dt:.0f} ms".replace("-", "−")
        names.append(f"{design}: {'RGB'[k]} frame{when}")
    frames.append(srgb_image(np.asarray(im["xyz"], float), result["display_white"]))
    names.append(f"{design} at {speed:g} px/ms: the displayed image")
    scale = max(2, -(-GIF_MIN_WIDTH_PX // w))
    font = _caption_font(CAPTION_FONT_PX)
    captions = [_wrap(name, font, w * scale - 8) for name in names]
    n_lines = max(map(len, captions))
    pics = [_captioned(f, lines, n_lines, scale, font) for f, lines in zip(frames, captions)]
    buf = io.BytesIO()
    pics[0].save(buf, format="GIF", save_all=True, append_images=pics[1:], duration=[900, 900, 900, 1800], loop=0)
    return [atomic_write(out / "fsc_frames.gif", buf.getvalue())]


def _fmt(v, f="{:.2f}"):
    return "–" if v is None or (isinstance(v, float) and not np.isfinite(v)) else f.format(v)


def answer(result: dict) -> list[str]:
    """The question answered with the numbers.

    Parameters
    ----------
    result : dict
        The motion run's result (its ``answer`` and rows).

    Returns
    -------
    list of str
        Markdown lines.
    """
    a = result["answer"]
    rows = result["rows"]
    lines = []

    def snr(d):
        return _snr(rows, d)

    for d in ("fsc/optimal", "fsc/balanced", "prism/optimal"):
        for rolling in (False, True):
            e = a.get(f"{d}{' rolling' if rolling else ''}")
            if not e:
                continue
            s, c = e["scielab"], e["cielab"]
            still = e["still_scielab"]
            shutter = "rolling shutter" if rolling else "global shutter"
            lead = (f"* **{d}, {shutter}** (SNR {_fmt(snr(d), '{:.1f}')} dB vs the CFA's "
                    f"{_fmt(snr('cfa/single'), '{:.1f}')} dB; S-CIELAB still {still[0]:.2f} vs {still[1]:.2f}): ")
            if s["status"] == "crosses":
                px_ms = s["speed_px_per_ms"]
                mm_s = px_ms * 1e3 * result["parameters"]["motion"]["object_pixel_mm"]
                spread = ""
                if s.get("ci95_px_per_ms"):
                    lo, hi = s["ci95_px_per_ms"]
                    spread = (f"; over {len(s['by_seed_px_per_ms'])} noise seeds {s['mean_px_per_ms']:.2g} px/ms, 95 % "
                              f"interval {lo:.2g}–{hi:.2g}")
                lines.append(lead + f"its S-CIELAB error exceeds the CFA's from **{px_ms:.2g} px/ms** ({px_ms * 1e3:.2g} "
                             f"px/s, {mm_s:.2g} mm/s in the scene; between the swept {s['between'][0]:g} and "
                             f"{s['between'][1]:g} px/ms{spread}); CIELAB from {_fmt(c['speed_px_per_ms'], '{:.2g}')} "
                             "px/ms.")
            else:
                lines.append(lead + f"S-CIELAB: {s['status']}; CIELAB: {c['status']}"
                             + (f" ({c['speed_px_per_ms']:.3g} px/ms)" if c.get("speed_px_per_ms") else "") + ".")
    for rolling in (False, True):
        e = a.get(f"balanced beats optimal{' rolling' if rolling else ''}")
        if e and e["scielab"].get("speed_px_per_ms") is not None:
            lines.append(f"* **fsc/balanced against fsc/optimal, {'rolling' if rolling else 'global'} shutter**: the balanced "
                         f"scheme's S-CIELAB error is the smaller of the two from {e['scielab']['speed_px_per_ms']:.3g} px/ms.")
    return lines


def _tables(result) -> list[str]:
    """One table per metric and shutter: each design across the speeds."""
    rows = result["rows"]
    speeds = sorted({r.speed_px_per_ms for r in rows})
    out = []
    for key in ("scielab_delta_e", "cielab_delta_e", "breakup_width_px", "edge_blur_px", "breakup_threshold_width_px",
                "false_colour_still", "mtf50_cy_per_px", "scielab_delta_e_scene"):
        for rolling in sorted({r.rolling_shutter for r in rows}):
            out += [f"**{key}** ({'rolling' if rolling else 'global'} shutter)", "",
                    "| design | SNR dB | " + " | ".join(f"{v:g}" for v in speeds) + " px/ms |",
                    "|---|---|" + "---|" * len(speeds)]
            for d in _designs(rows):
                _, ys = series(rows, d, rolling, key)
                out.append(f"| {d} | {_fmt(_snr(rows, d), '{:.1f}')} | " + " | ".join(
                    _fmt(y, "{:.3f}" if "mtf" in key else "{:.2f}") for y in ys) + " |")
            out.append("")
    return out


def _case_files(result) -> list[str]:
    """What images/ and maps/ hold, and the map figure of the first speed past the crossing."""
    rows = result["rows"]
    speeds = sorted({r.speed_px_per_ms for r in rows})
    first = rows[0]
    example = case_stem(first.design, first.speed_px_per_ms, first.rolling_shutter)
    v = result["answer"].get("fsc/optimal", {}).get("scielab", {}).get("speed_px_per_ms")
    shown = next((s for s in speeds if v is not None and s > v), speeds[-1])
    return ["## Every case", "",
            f"* `images/<design>_<speed>px-per-ms_<global|rolling>.exr` (e.g. `images/{example}.exr`): the displayed "
            "image (the first noise seed's capture) as linear RGB of the display, half floats, with the parameters "
            "that made it in the header (`spectracamParameters`: the case, its exposure windows, the seed, the "
            "experiment's parameters); the same name `.png`: its sRGB rendering, one pixel per pixel.",
            f"* `maps/scielab_<speed>px-per-ms.png`: per speed, the S-CIELAB ΔE*ab map of every design and shutter "
            "against that design's own still capture, on one colour scale per figure (its 99.5th percentile, at "
            f"least {MAP_VMIN_TOP:g}; stated on the colour bar) so the designs compare at that speed.", "",
            f"![S-CIELAB maps at {shown:g} px/ms](maps/{map_name(shown)})", "",
            "Other speeds: " + ", ".join(f"[{s:g}](maps/{map_name(s)})" for s in speeds) + " px/ms.", ""]


def _setup(result) -> list[str]:
    spec = result["parameters"]["motion"]
    g = result["parameters"]["geometry"]
    noise = (f"the paper’s sensor noise (shot, dark current, read, FPN, 8-bit ADC), {spec['seeds']} seed"
             f"{'s' if spec['seeds'] > 1 else ''} from {spec['seed']} shared by every design and speed (common random "
             "numbers); every noisy score is their mean" if spec["noise"] else "off")
    esfr = ("with the binning correction, which ISO 12233:2017 does not make (`esfr_correct_binning = true`)"
            if spec.get("esfr_correct_binning") else "as ISO 12233:2017 states it (`esfr_correct_binning = false`)")
    return ["## Set-up and choices", "",
            f"* Target: a {spec['edge_size_px'][0]}×{spec['edge_size_px'][1]} px slanted edge "
            f"({spec['edge_angle_deg']:g}°) between ColorChecker neutral 6.5 and 3.5 (4:1), moving along "
            f"{spec['direction_deg']:g}° at each speed; one pixel is {spec['object_pixel_mm']:g} mm in the scene "
            f"(so 1 px/ms = {1e3 * spec['object_pixel_mm']:g} mm/s).",
            f"* Camera: {spec['pixel_pitch_um']:g} µm pixels, f/{spec['f_number']:g}, {spec['focal_length_mm']:g} mm lens "
            f"at {g['object_distance_mm']:.0f} mm; diffraction and the pixel aperture as in `spectracam spatial`.",
            f"* Light: {result['parameters']['white_luminance_cd_m2']:.1f} cd/m² on the white diffuser, so that "
            f"cfa/single needs {spec['cfa_exposure_ms']:g} ms (the paper's 28 ms at 5000 K).",
            f"* Noise: {noise}; SNR is the paper's (chart patches, channels combined) — a flat area's SNR does not "
            "depend on the motion.",
            f"* Timing: CFA and prism simultaneous (prism windows aligned at their {spec['prism_alignment']}); "
            f"field-sequential frames in the order {spec['order']} with a {spec['readout_gap_ms']:g} ms readout gap; "
            f"rolling shutter {spec['line_time_us']:g} µs per row.",
            f"* Time slices: the image moves at most {spec['max_step_px']:g} px between slices"
            + (f" (or {spec['slices']} slices)" if spec['slices'] else "")
            + f"; {spec['samples_per_subpixel']} samples per sub-pixel per capture shared by its slices (at least 1 "
            f"each), {spec['supersampling']}×{spec['supersampling']} sub-pixels per pixel; render mode "
            f"`{spec['render_mode']}`.",
            "* Breakup (`breakup_width_px`): each camera channel's edge profile (averaged along the slanted edge in "
            "0.25 px bins, normalised by the still capture's plateaus) is located where it crosses 50 %; the "
            "breakup is the spread (max − min) of the channels' shifts from their still positions — sub-pixel, "
            "v·(t_last − t_first) for frames in sequence (t: each window's middle), 0 for one shared window. Blur "
            "(`edge_blur_px`): the channels' mean 10–90 % rise. `breakup_threshold_width_px`: the distance over "
            f"which the chroma the motion adds (0.5 px bins) exceeds {spec['breakup_threshold']:g} ΔE*ab (blur and "
            "demosaicking count in it; it cannot read below 2 bins). S-CIELAB and CIELAB: mean "
            f"within {spec['zone_half_width_px']:g} px of the edge, against the design's own still capture (the "
            f"`*_scene` columns: against the scene); S-CIELAB at {result['parameters']['samples_per_degree']:.1f} "
            "samples/degree.",
            f"* MTF50: the e-SFR of the displayed luminance across the edge, {esfr}.", ""]


def report_markdown(result: dict, command: str) -> str:
    """report.md: the answer, the figures, the tables, the exposure windows, the case files, the setup and the time
    per stage.

    Parameters
    ----------
    result : dict
        The motion run's result.
    command : str
        The command, recorded at the top.

    Returns
    -------
    str
    """
    out = ["# spectracam motion: when does the field-sequential camera's SNR advantage become a perceptual loss?", "",
           f"Made by `{command}` (renderer {result['renderer']}, {result['wall_s']:.1f} s, "
           f"{result['slice_renders']} slice renders).", "",
           "Catrysse, Wandell & El Gamal (1999) weigh the field-sequential camera's SNR advantage against \"the "
           "temporal disadvantages of FSC\". Here a neutral slanted edge moves across the image while each design "
           "captures it with the paper's exposure control, light level and sensor noise; the displayed image is "
           "scored against the same camera's noise-free still capture (the edge at rest: its own demosaicking and "
           "conversion, so only motion and noise count; docs/metrics.md) and, in the `*_scene` columns of "
           "results.json, against the still scene.", "",
           "## Answer", "", *answer(result), "",
           "How the balanced scheme changes it: it gives the field-sequential camera the CFA's total time, so the "
           "frames are closer in time (smaller breakup at every speed) but each frame gets about a quarter of the "
           "light; the SNR falls far below the CFA's and the error of a still scene is already larger — there is "
           "no SNR advantage left to lose. The rolling shutter delays each row by the same time for every channel, "
           "so it skews the edge but adds no colour: it moves the crossing by less than the sweep resolves.", "",
           "![breakup and S-CIELAB against speed](breakup_scielab.png)", "", "![crops](crops.png)", "",
           "![field-sequential frames](fsc_frames.gif)", "", *_tables(result)]
    out += ["## Exposure windows (ms, t = 0 the middle of the capture; row 0)", "",
            "| design | R | G | B | capture |", "|---|---|---|---|---|"]
    for k, t in result["exposure_timing"].items():
        if "rolling" in k:
            continue
        out.append(f"| {k} | " + " | ".join(f"{s:.1f} … {s + d:.1f}" for s, d in zip(t["start_ms"], t["duration_ms"]))
                   + f" | {t['capture_time_ms']:.1f} |")
    out += ["", *(_case_files(result) if result.get("images") and result.get("case_images_written", True) else []),
            *_setup(result),
            "## Time per stage (s)", "", "| " + " | ".join(result["timings"]) + " |",
            "|" + "---|" * len(result["timings"]),
            "| " + " | ".join(f"{v:.2f}" for v in result["timings"].values()) + " |", ""]
    return "\n".join(out)


def write_outputs(out_dir: Path, result: dict, command: str, images: bool = True) -> list[Path]:
    """The figures, every case's images and maps (:mod:`.cases`; not with ``images=False``, ``--no-images``),
    results.json (rows as :meth:`~.experiment.MotionRow.to_dict`), mtf_curves.json and report.md.

    Parameters
    ----------
    out_dir : Path
    result : dict
        :func:`~.experiment.run_motion`'s.
    command : str
        Recorded in results.json and report.md.
    images : bool
        Also write every case's images and the S-CIELAB maps.

    Returns
    -------
    list of Path
        The files written.
    """
    out_dir = Path(out_dir)
    result = {**result, "case_images_written": bool(images)}
    rows = result["rows"]
    paths = []
    paths += figure_curves(result, out_dir)
    paths += figure_crops(result, out_dir, False)
    if any(r.rolling_shutter for r in rows):
        paths += figure_crops(result, out_dir, True)
    paths += fsc_frames_gif(result, out_dir) if any(r.design == "fsc/optimal" for r in rows) else []
    figures = [p.name for p in paths if p.suffix in (".png", ".gif")]
    cases = write_case_outputs(result, out_dir) if images and result.get("images") else []
    paths += cases
    result["figures"] = figures + [p.relative_to(out_dir).as_posix() for p in cases if p.parent.name == "maps"]
    result["case_files"] = {"images": sum(p.parent.name == "images" for p in cases),
                            "pattern": "images/<design>_<speed>px-per-ms_<global|rolling>.exr and .png"}
    public = {k: ([r.to_dict() for r in v] if k == "rows" else v) for k, v in result.items()
              if k not in ("images", "mtf_curves", "display_white", "case_images_written")}
    public["display_white"] = np.asarray(result["display_white"]).tolist()
    public["command"] = command
    paths.append(atomic_write(out_dir / "results.json", json.dumps(public, indent=1, allow_nan=False,
                                                                   default=json_default).encode()))
    paths.append(atomic_write(out_dir / "mtf_curves.json", json.dumps({"curves": result["mtf_curves"]},
                                                                      default=json_default).encode()))
    paths.append(atomic_write(out_dir / "report.md", report_markdown(result, command).encode()))
    return paths
