"""Outputs of the motion experiment: results.json, mtf_curves.json, figures (PNG + SVG), an animated
GIF of the field-sequential frames, report.md."""
from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np

from ..io.files import atomic_write, json_default
from ..io.plots import pyplot, save_figure, srgb_image

COLOURS = {"cfa/single": "#d62728", "prism/optimal": "#1f77b4", "fsc/optimal": "#2ca02c", "fsc/balanced": "#9467bd"}


def _designs(rows):
    out = []
    for r in rows:
        if r["design"] not in out:
            out.append(r["design"])
    return out


def _series(rows, design, rolling, key):
    rs = sorted((r for r in rows if r["design"] == design and r["rolling_shutter"] == rolling),
                key=lambda r: r["speed_px_per_ms"])
    return [r["speed_px_per_ms"] for r in rs], [np.nan if r[key] is None else r[key] for r in rs]


def figure_curves(result, out: Path) -> list[Path]:
    plt = pyplot()
    rows = result["rows"]
    shutters = sorted({r["rolling_shutter"] for r in rows})
    speeds = sorted({r["speed_px_per_ms"] for r in rows})
    positive = [s for s in speeds if s > 0]
    lin = min(positive) if positive else 1.0
    panels = [("breakup_width_px", f"colour-breakup width, px\n(chroma added by the motion > "
               f"{result['parameters']['motion']['breakup_threshold']:g} ΔE*ab)"),
              ("scielab_delta_e", "S-CIELAB ΔE*ab at the edge\n(against the camera's own still capture)"),
              ("cielab_delta_e", "CIELAB ΔE*ab at the edge\n(against the camera's own still capture)")]
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.3), constrained_layout=True)
    for ax, (key, title) in zip(axes, panels):
        for d in _designs(rows):
            for rolling in shutters:
                x, y = _series(rows, d, rolling, key)
                snr = next(r["snr_db"] for r in rows if r["design"] == d)
                lab = f"{d}" + (f" ({snr:.1f} dB)" if snr is not None else "") + (" rolling" if rolling else "")
                ax.plot(x, y, "--" if rolling else "-", marker="o" if not rolling else "x", ms=4,
                        color=COLOURS.get(d, "#7f7f7f"), lw=1.4, label=lab, alpha=0.7 if rolling else 1.0)
        ax.set_xscale("symlog", linthresh=lin, linscale=0.5)
        ax.set(xlabel="image speed, px/ms", title=title)
        ax.grid(alpha=0.3)
    ans = result["answer"].get("fsc/optimal", {}).get("scielab", {})
    if ans.get("speed_px_per_ms"):
        axes[1].axvline(ans["speed_px_per_ms"], color="0.4", lw=0.8, ls=":")
        axes[1].annotate(f"FSC worse than CFA\nfrom {ans['speed_px_per_ms']:.3g} px/ms", (ans["speed_px_per_ms"], 0.97),
                         xycoords=("data", "axes fraction"), va="top", fontsize=8)
    axes[0].legend(fontsize=7, loc="upper left")
    fig.suptitle("A moving neutral edge (legend: the design's SNR with the paper's noise); solid: global shutter, "
                 "dashed: rolling shutter", fontsize=10)
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


def figure_crops(result, out: Path, rolling: bool = False) -> list[Path]:
    plt = pyplot()
    rows = result["rows"]
    designs = _designs(rows)
    speeds = _pick_speeds({r["speed_px_per_ms"] for r in rows})
    white = result["display_white"]
    fig, axes = plt.subplots(len(designs) + 1, len(speeds), figsize=(3.0 * len(speeds), 1.35 * (len(designs) + 1)),
                             squeeze=False, constrained_layout=True)
    ideal = result["images"][(designs[0], "ideal")]["xyz"]
    for j, v in enumerate(speeds):
        ax = axes[0, j]
        ax.imshow(srgb_image(_crop(ideal).astype(float), white), interpolation="nearest")
        ax.set_title(f"{v:g} px/ms", fontsize=9)
        for i, d in enumerate(designs):
            im = result["images"][(d, v, rolling)]["xyz"]
            axes[i + 1, j].imshow(srgb_image(_crop(im).astype(float), white), interpolation="nearest")
    for i, lab in enumerate(["scene (t = 0)"] + designs):
        axes[i, 0].set_ylabel(lab, fontsize=8)
    for ax in axes.ravel():
        ax.set_xticks([]), ax.set_yticks([])
    fig.suptitle(f"The moving edge as each design shows it ({'rolling' if rolling else 'global'} shutter; "
                 "motion to the right; nearest-neighbour zoom)", fontsize=10)
    return [save_figure(fig, out / f"crops{'_rolling' if rolling else ''}.png")]


def fsc_frames_gif(result, out: Path, design: str = "fsc/optimal", speed: float | None = None,
                   scale: int = 4) -> list[Path]:
    """An animated GIF: the field-sequential camera's R, G and B frames (each in its colour, as the
    sensor recorded them, one after another) and then the displayed image they make together."""
    from PIL import Image, ImageDraw

    rows = [r for r in result["rows"] if r["design"] == design and not r["rolling_shutter"]]
    if not rows:
        return []
    if speed is None:   # the fastest speed whose whole smear stays inside the image's middle half
        w = result["images"][(design, rows[0]["speed_px_per_ms"], False)]["xyz"].shape[1]
        ok = [r["speed_px_per_ms"] for r in rows if r["blur_px"] <= w / 3] or [rows[0]["speed_px_per_ms"]]
        speed = max(ok)
    im = result["images"][(design, speed, False)]
    rates = np.asarray(im["cam_rates"], float)
    white = result["display_white"]
    top = np.percentile(rates, 99.5, axis=(0, 1))
    tints = np.eye(3)
    frames, names = [], []
    for k in range(3):
        g = np.clip(rates[..., k] / top[k], 0, 1)
        rgb = g[..., None] * (0.25 + 0.75 * tints[k])[None, None, :]
        frames.append(rgb ** (1 / 2.2))
        names.append(f"{'RGB'[k]} frame, {rows[0]['exposure_ms'][k]:.0f} ms")
    frames.append(srgb_image(np.asarray(im["xyz"], float), white))
    names.append(f"{design} at {speed:g} px/ms (displayed)")
    pics = []
    for f, name in zip(frames, names):
        a = (np.clip(f, 0, 1) * 255).astype(np.uint8)
        a = np.repeat(np.repeat(a, scale, 0), scale, 1)
        canvas = Image.new("RGB", (a.shape[1], a.shape[0] + 14), (0, 0, 0))
        canvas.paste(Image.fromarray(a), (0, 14))
        ImageDraw.Draw(canvas).text((2, 1), name, fill=(255, 255, 255))
        pics.append(canvas.convert("P", palette=Image.ADAPTIVE, colors=255))
    buf = io.BytesIO()
    pics[0].save(buf, format="GIF", save_all=True, append_images=pics[1:], duration=[700, 700, 700, 1400], loop=0)
    return [atomic_write(out / "fsc_frames.gif", buf.getvalue())]


def _fmt(v, f="{:.2f}"):
    return "–" if v is None or (isinstance(v, float) and not np.isfinite(v)) else f.format(v)


def answer(result) -> list[str]:
    """The question answered with the numbers."""
    a = result["answer"]
    rows = result["rows"]
    lines = []

    def snr(d):
        return next((r["snr_db"] for r in rows if r["design"] == d), None)

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


def report_markdown(result, command: str) -> str:
    rows = result["rows"]
    spec = result["parameters"]["motion"]
    g = result["parameters"]["geometry"]
    designs = _designs(rows)
    speeds = sorted({r["speed_px_per_ms"] for r in rows})
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
           "![field-sequential frames](fsc_frames.gif)", ""]
    for key in ("scielab_delta_e", "cielab_delta_e", "breakup_width_px", "false_colour_still", "mtf50_cy_per_px",
                "scielab_delta_e_scene"):
        for rolling in sorted({r["rolling_shutter"] for r in rows}):
            out += [f"**{key}** ({'rolling' if rolling else 'global'} shutter)", "",
                    "| design | SNR dB | " + " | ".join(f"{v:g}" for v in speeds) + " px/ms |",
                    "|---|---|" + "---|" * len(speeds)]
            for d in designs:
                _, ys = _series(rows, d, rolling, key)
                snr = next(r["snr_db"] for r in rows if r["design"] == d)
                out.append(f"| {d} | {_fmt(snr, '{:.1f}')} | " + " | ".join(
                    _fmt(y, "{:.3f}" if "mtf" in key else "{:.2f}") for y in ys) + " |")
            out.append("")
    out += ["## Exposure windows (ms, t = 0 the middle of the capture; row 0)", "",
            "| design | R | G | B | capture |", "|---|---|---|---|---|"]
    for k, t in result["exposure_timing"].items():
        if "rolling" in k:
            continue
        out.append(f"| {k} | " + " | ".join(f"{s:.1f} … {s + d:.1f}" for s, d in zip(t["start_ms"], t["duration_ms"]))
                   + f" | {t['capture_time_ms']:.1f} |")
    out += ["", "## Set-up and choices", "",
            f"* Target: a {spec['edge_size_px'][0]}×{spec['edge_size_px'][1]} px slanted edge "
            f"({spec['edge_angle_deg']:g}°) between ColorChecker neutral 6.5 and 3.5 (4:1), moving along "
            f"{spec['direction_deg']:g}° at each speed; one pixel is {spec['object_pixel_mm']:g} mm in the scene "
            f"(so 1 px/ms = {1e3 * spec['object_pixel_mm']:g} mm/s).",
            f"* Camera: {spec['pixel_pitch_um']:g} µm pixels, f/{spec['f_number']:g}, {spec['focal_length_mm']:g} mm lens "
            f"at {g['object_distance_mm']:.0f} mm; diffraction and the pixel aperture as in `spectracam spatial`.",
            f"* Light: {result['parameters']['white_luminance_cd_m2']:.1f} cd/m² on the white diffuser, so that "
            f"cfa/single needs {spec['cfa_exposure_ms']:g} ms (the paper's 28 ms at 5000 K).",
            f"* Noise: {'the paper’s sensor noise (shot, dark current, read, FPN, 8-bit ADC), one seed for every design and speed (common random numbers)' if spec['noise'] else 'off'}; "
            "SNR is the paper's (chart patches, channels combined) — a flat area's SNR does not depend on the motion.",
            f"* Timing: CFA and prism simultaneous (prism windows aligned at their {spec['prism_alignment']}); "
            f"field-sequential frames in the order {spec['order']} with a {spec['readout_gap_ms']:g} ms readout gap; "
            f"rolling shutter {spec['line_time_us']:g} µs per row.",
            f"* Time slices: the image moves at most {spec['max_step_px']:g} px between slices"
            + (f" (or {spec['slices']} slices)" if spec['slices'] else "")
            + f"; {spec['samples_per_subpixel']} samples per sub-pixel per capture shared by its slices (at least 1 "
            f"each), {spec['supersampling']}×{spec['supersampling']} sub-pixels per pixel; render mode "
            f"`{spec['render_mode']}`.",
            f"* Breakup width: the chroma the camera adds (against its own rendering of the still scene), averaged "
            f"along the edge in 0.5 px bins, above {spec['breakup_threshold']:g} ΔE*ab. S-CIELAB and CIELAB: mean "
            f"within {spec['zone_half_width_px']:g} px of the edge, against the scene; S-CIELAB at "
            f"{result['parameters']['samples_per_degree']:.1f} samples/degree.", "",
            "## Time per stage (s)", "", "| " + " | ".join(result["timings"]) + " |",
            "|" + "---|" * len(result["timings"]),
            "| " + " | ".join(f"{v:.2f}" for v in result["timings"].values()) + " |", ""]
    return "\n".join(out)


def write_outputs(out_dir: Path, result: dict, command: str) -> list[Path]:
    out_dir = Path(out_dir)
    paths = []
    paths += figure_curves(result, out_dir)
    paths += figure_crops(result, out_dir, False)
    if any(r["rolling_shutter"] for r in result["rows"]):
        paths += figure_crops(result, out_dir, True)
    paths += fsc_frames_gif(result, out_dir) if any(r["design"] == "fsc/optimal" for r in result["rows"]) else []
    result["figures"] = [p.name for p in paths if p.suffix in (".png", ".gif")]
    public = {k: v for k, v in result.items() if k not in ("images", "mtf_curves", "display_white")}
    public["display_white"] = np.asarray(result["display_white"]).tolist()
    public["command"] = command
    paths.append(atomic_write(out_dir / "results.json", json.dumps(public, indent=1, allow_nan=False,
                                                                   default=json_default).encode()))
    paths.append(atomic_write(out_dir / "mtf_curves.json", json.dumps({"curves": result["mtf_curves"]},
                                                                      default=json_default).encode()))
    paths.append(atomic_write(out_dir / "report.md", report_markdown(result, command).encode()))
    return paths
