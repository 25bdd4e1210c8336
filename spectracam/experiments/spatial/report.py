"""Outputs of the spatial experiment: results.json, mtf_curves.json, figures (PNG + SVG), report.md."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from spectracam.core.files import atomic_write, json_default
from spectracam.io.plots import pyplot, save_figure, srgb_image

__all__ = ["ARCH_COLOURS", "COLOURS", "MAP_PERCENTILE", "REPORT_TABLES", "SUMMARY_PANELS", "answer",
           "figure_crops", "figure_mtf", "figure_scielab_maps", "figure_summary", "report_markdown",
           "write_case_images", "write_outputs"]


def _cases(rows):
    return list(dict.fromkeys((r.pixel_pitch_um, r.f_number) for r in rows))


def _labels(rows):
    return list(dict.fromkeys(r.label for r in rows))


def _by_key(rows) -> dict:
    return {(r.label, r.pixel_pitch_um, r.f_number, r.target): r for r in rows}


def _get(rows, label, pitch, N, target, key):
    r = _by_key(rows).get((label, pitch, N, target))
    return None if r is None else getattr(r, key)


def _design_of(rows) -> dict:
    """label → its row's (design, demosaic, olpf_separation_px, misregistration_px): no label parsing."""
    return {r.label: r for r in rows}


COLOURS = {("cfa", "bilinear"): "#D55E00", ("cfa", "malvar2004"): "#E69F00", ("cfa", "menon2007"): "#CC79A7",
           ("prism", None): "#0072B2", ("fsc", None): "#009E73"}   # Okabe & Ito's (spectracam.io.plots.OKABE_ITO)
#: Other architectures (``spectracam architectures``), one colour each whatever their demosaicker.
ARCH_COLOURS = {"stacked": "#000000", "rgbw": "#56B4E9", "ryyb": "#F0E442", "cmy": "#999999", "quad_bayer": "#666666"}


def _colour(row) -> str:
    arch = row.design.split("/")[0]
    if arch == "prism" and row.misregistration_px > 0:
        return "#17becf"
    return COLOURS.get((arch, row.demosaic), ARCH_COLOURS.get(arch, "#000000"))


def _style(row) -> str:
    """Line style: dashed for a misaligned prism, dash-dot with an optical low-pass filter."""
    return "--" if row.misregistration_px > 0 else "-." if row.olpf_separation_px > 0 else "-"


def _hatch(row):
    return "//" if row.misregistration_px > 0 else ".." if row.olpf_separation_px > 0 else None


def _short(label: str) -> str:
    return label.replace("/optimal", "").replace("/single", "")


def _identical_groups(curves) -> list[list]:
    """Curves grouped where their Y e-SFRs agree to 1e-4 (noise-free, the aligned prism and the
    field-sequential camera sample the same planes): one line per group, every label in its legend."""
    groups: list[list] = []
    for c in curves:
        y = np.asarray(c["Y"])
        for g in groups:
            y0 = np.asarray(g[0]["Y"])
            if y0.shape == y.shape and y.size and np.abs(y0 - y).max() < 1e-4:
                g.append(c)
                break
        else:
            groups.append([c])
    return groups


def figure_mtf(result: dict, out: Path) -> list[Path]:
    """mtf.png and mtf.svg: the neutral edge's e-SFR of the displayed luminance Y per design, one panel per case
    (pixel pitch, f-number), designs whose curves agree to 1e-4 drawn once, with the closed form (diffraction ×
    pixel aperture, and × each OLPF) dotted.

    Parameters
    ----------
    result : dict
        What :func:`~spectracam.experiments.spatial.experiment.run_spatial` returns.
    out : Path
        The output folder.

    Returns
    -------
    list of Path
        The files written; none without edge curves.
    """
    plt = pyplot()
    curves = [c for c in result["mtf_curves"] if c["target"] == "edge"]
    rows = _design_of(result["rows"])
    cases = _cases(result["rows"])
    if not curves:
        return []
    n = len(cases)
    cols = min(2, n)
    rws = -(-n // cols)
    fig, axes = plt.subplots(rws, cols, figsize=(6.5 * cols, 4.6 * rws), squeeze=False, constrained_layout=True)
    top = 1.05
    for ax, (p, N) in zip(axes.ravel(), cases):
        mine = [c for c in curves if c["pixel_pitch_um"] == p and c["f_number"] == N]
        for g in _identical_groups(mine):
            r = rows[g[0]["label"]]
            f = np.asarray(g[0]["frequencies_cy_per_px"])
            top = max(top, float(np.max(g[0]["Y"], initial=0)) + 0.03)
            ax.plot(f, g[0]["Y"], _style(r), color=_colour(r), lw=1.5,
                    label=" = ".join(_short(c["label"]) for c in g) + (" (identical)" if len(g) > 1 else ""))
        cf = result["closed_form"].get(f"{p:g}um_f{N:g}")
        if cf:
            ax.plot(cf["frequencies_cy_per_px"], cf["Y"], ":", color="k", lw=1.3,
                    label="closed form: diffraction × pixel aperture, Y")
            for key in (k for k in cf if k.startswith("Y OLPF")):
                ax.plot(cf["frequencies_cy_per_px"], cf[key], ":", color="0.5", lw=1.3,
                        label=f"closed form × {key[2:]}, Y")
        ax.axvline(0.5, color="0.6", lw=0.8)
        ax.axhline(0.5, color="0.8", lw=0.6)
        ax.set(xlim=(0, 1), xlabel="spatial frequency (cycles / pixel); grey line: Nyquist",
               ylabel="e-SFR of the displayed luminance Y", title=f"{p:g} µm pixel, f/{N:g}")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right", frameon=True)
    for ax in axes.ravel()[:n]:
        ax.set_ylim(0, min(top, 1.25))
    for ax in axes.ravel()[n:]:
        ax.axis("off")
    esfr = "ISO 12233:2017" + (" + binning correction" if result["parameters"]["spatial"]["esfr_correct_binning"] else "")
    fig.suptitle(f"Neutral slanted edge (5°, 4:1), e-SFR ({esfr}) of Y per design", fontsize=11)
    return save_figure(fig, out / "mtf.png", out / "mtf.svg")


#: The summary's panels: (target, metric, y label, title); a panel shows when its target ran.
SUMMARY_PANELS = (
    ("edge", "mtf50_cy_per_px", "MTF50 (cycles/pixel)", "neutral edge: resolution (higher is better)"),
    ("edge", "false_colour", "√(Δa*² + Δb*²)", "neutral edge: false colour"),
    ("edge_red_cyan", "edge_delta_e", "ΔE*ab at the edge", "red/cyan edge: colour error at the edge"),
    ("edge_blue_yellow", "edge_delta_e", "ΔE*ab at the edge", "blue/yellow edge: colour error at the edge"),
    ("zone_plate", "aliasing_delta_e", "S-CIELAB ΔE*ab above Nyquist", "luminance zone plate: aliasing"),
    ("zone_plate_chroma", "aliasing_delta_e", "S-CIELAB ΔE*ab above Nyquist", "chroma zone plate: aliasing"),
    ("star", "scielab_delta_e_spatial", "S-CIELAB ΔE*ab (spatial)", "Siemens star: spatial error"),
    ("chart", "scielab_delta_e_spatial", "S-CIELAB ΔE*ab (spatial)", "tilted chart: spatial error"),
)


def figure_summary(result: dict, out: Path) -> list[Path]:
    """summary.png and summary.svg: a bar chart per :data:`SUMMARY_PANELS` panel whose target ran, one bar per
    design and case (with its 95 % interval over seeds where noise is on).

    Parameters
    ----------
    result : dict
        What :func:`~spectracam.experiments.spatial.experiment.run_spatial` returns.
    out : Path
        The output folder.

    Returns
    -------
    list of Path
        The files written; none when no panel's target ran.
    """
    plt = pyplot()
    rows = result["rows"]
    cases, labels, index, designs = _cases(rows), _labels(rows), _by_key(rows), _design_of(rows)
    targets = {r.target for r in rows}
    panels = [p for p in SUMMARY_PANELS if p[0] in targets]
    if not panels:
        return []
    ncol = min(3, len(panels))
    nrow = -(-len(panels) // ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(5.2 * ncol, 3.6 * nrow + 0.8), squeeze=False, constrained_layout=True)
    x = np.arange(len(cases))
    wbar = 0.8 / len(labels)
    for ax, (t, key, ylabel, title) in zip(axes.ravel(), panels):
        for i, lab in enumerate(labels):
            vals, err = [], [[], []]
            for p, N in cases:
                r = index.get((lab, p, N, t))
                v = None if r is None else getattr(r, key)
                ci = None if r is None else r.interval95.get(key)
                vals.append(np.nan if v is None else v)
                err[0].append(0 if ci is None or v is None else v - ci[0])
                err[1].append(0 if ci is None or v is None else ci[1] - v)
            ax.bar(x + (i - (len(labels) - 1) / 2) * wbar, vals, wbar, color=_colour(designs[lab]), label=lab,
                   hatch=_hatch(designs[lab]), yerr=err if any(map(any, err)) else None, capsize=1.5)
        ax.set_xticks(x, [f"{p:g} µm, f/{N:g}" for p, N in cases], fontsize=8)
        ax.set_ylabel(ylabel, fontsize=9)
        ax.set_title(title, fontsize=10)
        ax.grid(axis="y", alpha=0.3)
    for ax in axes.ravel()[len(panels):]:
        ax.axis("off")
    handles, names = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, names, loc="outside lower center", ncol=min(5, len(names)), fontsize=8, frameon=False)
    spec = result["parameters"]["spatial"]
    fig.suptitle("Spatial comparison per design and case" + (
        f" (noise on: mean and 95 % interval over {spec['seeds']} seeds)" if spec["noise"] else " (noise off)"),
        fontsize=11)
    return save_figure(fig, out / "summary.png", out / "summary.svg")


def _crop_box(target, shape):
    h, w = shape[:2]
    if target in ("star", "zone_plate", "zone_plate_chroma"):
        r = max(16, min(h, w) // 5) if target == "star" else min(h, w) // 2 - 4
        return slice(h // 2 - r, h // 2 + r), slice(w // 2 - r, w // 2 + r)
    if target.startswith("edge"):
        r = max(12, min(h, w) // 6)
        return slice(h // 2 - r, h // 2 + r), slice(w // 2 - r, w // 2 + r)
    r = max(16, h // 4)
    return slice(h // 2 - r, h // 2 + r), slice(w // 2 - int(1.5 * r), w // 2 + int(1.5 * r))


def _targets_with_images(result, case) -> list:
    return [t for t in result["parameters"]["spatial"]["targets"] if (case[0], case[1], t, "reference") in result["images"]]


def figure_crops(result: dict, out: Path, case: tuple[float, float]) -> list[Path]:
    """``crops_<pitch>um_f<N>.png``: the centre of every target's image, the reference and each design, for one
    case (nearest-neighbour zoom).

    Parameters
    ----------
    result : dict
        What :func:`~spectracam.experiments.spatial.experiment.run_spatial` returns.
    out : Path
        The output folder.
    case : tuple of float
        ``(pixel pitch µm, f-number)``.

    Returns
    -------
    list of Path
        The file written; none when the case kept no images.
    """
    plt = pyplot()
    labels = _labels(result["rows"])
    targets = _targets_with_images(result, case)
    if not targets:
        return []
    white = result["display_white"]
    fig, axes = plt.subplots(len(targets), len(labels) + 1, figsize=(1.9 * (len(labels) + 1), 2.0 * len(targets) + 0.6),
                             squeeze=False, constrained_layout=True)
    for i, t in enumerate(targets):
        for j, lab in enumerate(["reference"] + labels):
            im = result["images"][(case[0], case[1], t, lab)]["xyz"]
            ax = axes[i, j]
            ax.imshow(srgb_image(im[_crop_box(t, im.shape)].astype(float), white), interpolation="nearest")
            ax.set_xticks([]), ax.set_yticks([])
            if i == 0:
                ax.set_title("reference\n(scene ≤ Nyquist)" if lab == "reference" else _short(lab).replace(" ", "\n", 1),
                             fontsize=8)
            if j == 0:
                ax.set_ylabel(t.replace("_", " "), fontsize=9)
    fig.suptitle(f"Crops of each design, {case[0]:g} µm pixel, f/{case[1]:g} (nearest-neighbour zoom; full images "
                 "in cases/)", fontsize=10)
    return [save_figure(fig, out / f"crops_{case[0]:g}um_f{case[1]:g}.png")]


#: Percentile of a target's error-map values that tops its colour scale (a few hot pixels do not set it).
MAP_PERCENTILE = 99.5


def _map_scale(result, target: str) -> float:
    """The colour scale of a target's error maps, ΔE*ab: the :data:`MAP_PERCENTILE` percentile over every design and case
    inside the scored region, rounded up to 2 significant figures (one scale per target, so its maps compare)."""
    vals = [im["scielab"][im["region"]] for (p, N, t, lab), im in result["images"].items() if t == target and "scielab" in im]
    if not vals:
        return 1.0
    v = float(np.percentile(np.concatenate(vals), MAP_PERCENTILE))
    if v <= 0:
        return 1.0
    e = np.floor(np.log10(v)) - 1
    return float(np.ceil(v / 10**e) * 10**e)


def figure_scielab_maps(result: dict, out: Path, target: str = "star") -> list[Path]:
    """``scielab_<target>.png``: one target's S-CIELAB error maps against the camera's own rendering of the
    reference, inside the scored region, per case and design, on one scale (:data:`MAP_PERCENTILE`).

    Parameters
    ----------
    result : dict
        What :func:`~spectracam.experiments.spatial.experiment.run_spatial` returns.
    out : Path
        The output folder.
    target : str
        The target's name, e.g. ``"star"``.

    Returns
    -------
    list of Path
        The file written; none when no case kept this target's images.
    """
    plt = pyplot()
    rows = result["rows"]
    labels = _labels(rows)
    cases = [c for c in _cases(rows) if (c[0], c[1], target, labels[0]) in result["images"]]
    if not cases:
        return []
    vmax = _map_scale(result, target)
    fig, axes = plt.subplots(len(cases), len(labels), figsize=(2.0 * len(labels) + 1.2, 2.1 * len(cases) + 0.6),
                             squeeze=False, constrained_layout=True)
    for i, c in enumerate(cases):
        for j, lab in enumerate(labels):
            im = result["images"][(c[0], c[1], target, lab)]
            ax = axes[i, j]
            h = ax.imshow(np.where(im["region"], im["scielab"], np.nan), cmap="magma", vmin=0, vmax=vmax,
                          interpolation="nearest")
            ax.set_xticks([]), ax.set_yticks([])
            if i == 0:
                ax.set_title(_short(lab).replace(" ", "\n", 1), fontsize=8)
            if j == 0:
                ax.set_ylabel(f"{c[0]:g} µm, f/{c[1]:g}", fontsize=8)
    fig.colorbar(h, ax=axes, shrink=0.7, label=f"S-CIELAB ΔE*ab against the camera's own rendering of the reference "
                                              f"(scale 0–{vmax:g}: 99.5th percentile of this target)")
    fig.suptitle(f"{target.replace('_', ' ')}: S-CIELAB error maps inside the scored region", fontsize=10)
    return [save_figure(fig, out / f"scielab_{target}.png")]


def _slug(label: str) -> str:
    return label.replace("/", "-").replace(" ", "_")


def _map_with_colourbar(delta_e_map: np.ndarray, region: np.ndarray, vmax: float) -> np.ndarray:
    """RGB uint8: the map (magma, 0–``vmax`` ΔE*ab, outside the region grey), enlarged to at least 256 px,
    with a colour bar and its scale drawn beside it by PIL in matplotlib's DejaVu Sans (no figure per map)."""
    from matplotlib import colormaps
    from PIL import Image, ImageDraw, ImageFont

    rgb = (colormaps["magma"](np.clip(delta_e_map / vmax, 0, 1))[..., :3] * 255).astype(np.uint8)
    rgb[~region] = 128
    k = max(1, int(np.ceil(256 / max(rgb.shape[:2]))))
    rgb = np.repeat(np.repeat(rgb, k, 0), k, 1)
    h, w = rgb.shape[:2]
    bar = (colormaps["magma"](np.linspace(1, 0, h))[:, None, :3] * 255).astype(np.uint8).repeat(16, 1)
    canvas = Image.new("RGB", (max(w + 110, 290), h + 24), "white")
    canvas.paste(Image.fromarray(rgb), (0, 0))
    canvas.paste(Image.fromarray(bar), (w + 8, 0))
    draw = ImageDraw.Draw(canvas)
    import matplotlib

    font = ImageFont.truetype(str(Path(matplotlib.get_data_path()) / "fonts" / "ttf" / "DejaVuSans.ttf"), 13)
    for frac in (0.0, 0.5, 1.0):
        y = int((1 - frac) * (h - 1))
        draw.line([(w + 24, y), (w + 30, y)], fill="black")
        draw.text((w + 33, max(0, min(h - 14, y - 7))), f"{frac * vmax:.3g}", fill="black", font=font)
    draw.text((2, h + 4), "S-CIELAB ΔE*ab against own reference", fill="black", font=font)
    return np.asarray(canvas)


def write_case_images(result: dict, out: Path, command: str) -> list[Path]:
    """Every design's displayed image of every case and target (and the reference) as linear display
    RGB EXR (half floats, with the parameters that made it) and sRGB PNG, and its S-CIELAB error map
    (colour bar drawn in, one scale per target) under ``cases/<pitch>um_f<N>/<target>/``.

    Parameters
    ----------
    result : dict
        What :func:`~spectracam.experiments.spatial.experiment.run_spatial` returns.
    out : Path
        The output folder.
    command : str
        The command line, stored in each EXR's parameters.

    Returns
    -------
    list of Path
        The files written, ``cases/scales.json`` (each target's map scale) last.
    """
    from spectracam.processing.color import display_rgb_to_xyz
    from spectracam.io.exr import write_exr
    from spectracam.io.report import display_chromaticities, write_png
    from spectracam._version import __version__

    spec = result["parameters"]["spatial"]
    display = result["parameters"]["scene"]["processing"]["display"]
    to_rgb = np.linalg.inv(display_rgb_to_xyz(display))
    white = result["display_white"]
    scales = {t: _map_scale(result, t) for t in spec["targets"]}
    paths = []
    for (p, N, t, lab), im in result["images"].items():
        folder = out / "cases" / f"{p:g}um_f{N:g}" / t
        params = {"command": command, "spatial": spec, "scene": result["parameters"]["scene"],
                  "case": {"pixel_pitch_um": p, "f_number": N, "target": t, "design": lab},
                  "reference": result["parameters"]["reference"], "seed": int(im.get("seed", spec["seed"]))}
        attrs = {"spectracamVersion": __version__, "spectracamKind": "rendered",
                 "spectracamUnits": f"linear RGB of the display ({display}), white = 1",
                 "chromaticities": display_chromaticities(display), "spectracamParameters": params,
                 "spectracamSeed": params["seed"]}
        rgb = np.asarray(im["xyz"], np.float64) @ to_rgb.T
        paths.append(write_exr(folder / f"{_slug(lab)}.exr", {"R": rgb[..., 0], "G": rgb[..., 1], "B": rgb[..., 2]},
                               attrs, half=True))
        paths.append(write_png(folder / f"{_slug(lab)}.png",
                               (srgb_image(np.asarray(im["xyz"], float), white) * 255 + 0.5).astype(np.uint8)))
        if "scielab" in im:
            paths.append(write_png(folder / f"{_slug(lab)}_error.png",
                                   _map_with_colourbar(im["scielab"], im["region"], scales[t])))
    if paths:
        paths.append(atomic_write(out / "cases" / "scales.json", json.dumps(
            {"colormap": "magma", "vmin_delta_e": 0.0, "vmax_delta_e_by_target": scales,
             "what": "S-CIELAB ΔE*ab against the camera's own rendering of the reference image; grey: outside the "
                     "scored region; scale: 99.5th percentile of the target's maps, rounded up"}, indent=1).encode()))
    return paths


def _fmt(v, f="{:.3f}"):
    return "–" if v is None else f.format(v)


def _with_ci(row, key, f="{:.2f}"):
    """``value`` or ``value (lo–hi)`` where the row has a 95 % interval over seeds."""
    if row is None or getattr(row, key) is None:
        return "–"
    ci = row.interval95.get(key)
    v = f.format(getattr(row, key))
    return v if ci is None else f"{v} ({f.format(ci[0])}–{f.format(ci[1])})"


def answer(result: dict) -> list[str]:
    """The paper's question answered with numbers (means with 95 % intervals where noise is on).

    Parameters
    ----------
    result : dict
        What :func:`~spectracam.experiments.spatial.experiment.run_spatial` returns.

    Returns
    -------
    list of str
        Markdown, one line per case (pitch, f-number) whose edge MTF50 is there for the field-sequential design
        and every CFA.
    """
    rows = result["rows"]
    index, designs = _by_key(rows), _design_of(rows)
    labels = _labels(rows)
    cfa = [lab for lab in labels if designs[lab].design.startswith("cfa") and designs[lab].olpf_separation_px == 0]
    olpf = [lab for lab in labels if designs[lab].design.startswith("cfa") and designs[lab].olpf_separation_px > 0]
    mis = [lab for lab in labels if designs[lab].misregistration_px > 0]
    lines = []
    for p, N in _cases(rows):
        s = _answer_case(p, N, index, designs, labels, cfa, olpf, mis)
        if s is not None:
            lines.append(s)
    return lines


def _answer_case(p: float, N: float, index: dict, designs: dict, labels: list, cfa: list, olpf: list,
                 mis: list) -> str | None:
    """:func:`answer`'s line for one case (pixel pitch ``p`` µm, f-number ``N``); None where the edge MTF50 of
    the field-sequential design or of a CFA is missing."""
    def g(lab, t, key):
        r = index.get((lab, p, N, t))
        return None if r is None else getattr(r, key)

    def c(lab, t, key, f="{:.2f}"):
        return _with_ci(index.get((lab, p, N, t)), key, f)

    fsc, prism = "fsc/optimal", "prism/optimal aligned"
    m = {lab: g(lab, "edge", "mtf50_cy_per_px") for lab in cfa}
    if g(fsc, "edge", "mtf50_cy_per_px") is None or not m or any(v is None for v in m.values()):
        return None
    best, worst = max(m, key=m.get), min(m, key=m.get)
    s = (f"* **{p:g} µm, f/{N:g}.** MTF50 (displayed luminance, neutral edge): field-sequential "
         f"{c(fsc, 'edge', 'mtf50_cy_per_px', '{:.3f}')} cy/px, prism (aligned) {c(prism, 'edge', 'mtf50_cy_per_px', '{:.3f}')}; "
         f"the colour filter array {c(worst, 'edge', 'mtf50_cy_per_px', '{:.3f}')} ({designs[worst].demosaic}) to "
         f"{c(best, 'edge', 'mtf50_cy_per_px', '{:.3f}')} ({designs[best].demosaic}).")
    fc = {lab: g(lab, "edge", "false_colour") for lab in labels}
    if fc.get(fsc) is not None and all(fc.get(lab) for lab in cfa):
        ratios = [fc[lab] / max(fc[k], 1e-9) for lab in cfa for k in (fsc, prism) if fc.get(k) is not None]
        s += (f" False colour at the neutral edge: FSC {c(fsc, 'edge', 'false_colour')}, aligned prism "
              f"{c(prism, 'edge', 'false_colour')}, CFA {min(fc[lab] for lab in cfa):.2f}–{max(fc[lab] for lab in cfa):.2f} "
              f"(the CFA {min(ratios):.1f}–{max(ratios):.1f}× the prism's and FSC's).")
    for t, what in (("edge_red_cyan", "red/cyan"), ("edge_blue_yellow", "blue/yellow")):
        e = {lab: g(lab, t, "edge_delta_e") for lab in labels}
        if e.get(fsc) is not None and all(e.get(lab) is not None for lab in cfa):
            s += (f" Colour error at the {what} edge: FSC {c(fsc, t, 'edge_delta_e')}, CFA "
                  + ", ".join(f"{designs[lab].demosaic} {c(lab, t, 'edge_delta_e')}" for lab in cfa) + " ΔE*ab.")
    for t, what in (("zone_plate", "luminance"), ("zone_plate_chroma", "chroma")):
        a = {lab: g(lab, t, "aliasing_delta_e") for lab in labels}
        if a.get(fsc) is not None:
            s += (f" Aliasing on the {what} zone plate (S-CIELAB above Nyquist): FSC {c(fsc, t, 'aliasing_delta_e')}, "
                  f"CFA " + "/".join(c(lab, t, "aliasing_delta_e") for lab in cfa)
                  + (f", CFA with OLPF " + "/".join(c(lab, t, "aliasing_delta_e") for lab in olpf) if olpf else "")
                  + " ΔE*ab.")
    for lab in mis:
        s += (f" {_short(lab).replace('prism ', 'The prism ')}: MTF50 {c(lab, 'edge', 'mtf50_cy_per_px', '{:.3f}')}, "
              f"false colour at the edge {c(lab, 'edge', 'false_colour')}.")
    for lab in olpf:
        plain = next((k for k in cfa if designs[k].demosaic == designs[lab].demosaic), None)
        if plain and None not in (g(plain, "edge", "mtf50_cy_per_px"), g(lab, "edge", "mtf50_cy_per_px")):
            s += (f" {designs[lab].demosaic} with an OLPF of {designs[lab].olpf_separation_px:g} px: MTF50 "
                  f"{g(plain, 'edge', 'mtf50_cy_per_px'):.3f} → {g(lab, 'edge', 'mtf50_cy_per_px'):.3f}, false colour "
                  f"{_fmt(g(plain, 'edge', 'false_colour'), '{:.2f}')} → {_fmt(g(lab, 'edge', 'false_colour'), '{:.2f}')}.")
    return s


#: The report's tables: target → metrics (a table each, one column per case).
REPORT_TABLES = {
    "edge": ("mtf50_cy_per_px", "false_colour", "edge_delta_e", "scielab_delta_e_spatial", "scielab_delta_e"),
    "edge_red_cyan": ("mtf50_cy_per_px", "edge_delta_e", "scielab_delta_e_spatial"),
    "edge_blue_yellow": ("mtf50_cy_per_px", "edge_delta_e", "scielab_delta_e_spatial"),
    "edge_skin": ("mtf50_cy_per_px", "edge_delta_e", "scielab_delta_e_spatial"),
    "edge_foliage_sky": ("mtf50_cy_per_px", "edge_delta_e", "scielab_delta_e_spatial"),
    "zone_plate": ("aliasing_delta_e", "passband_delta_e", "false_colour", "scielab_delta_e"),
    "zone_plate_chroma": ("aliasing_delta_e", "passband_delta_e", "scielab_delta_e"),
    "star": ("false_colour", "scielab_delta_e_spatial", "scielab_delta_e", "cielab_delta_e_spatial", "cielab_delta_e"),
    "chart": ("scielab_delta_e_spatial", "scielab_delta_e", "cielab_delta_e", "patch_delta_e", "defocus_max_um"),
}


def report_markdown(result: dict, command: str) -> str:
    """report.md: the answer, a table per target and metric, the figures, the set-up and the time per stage.

    Parameters
    ----------
    result : dict
        What :func:`~spectracam.experiments.spatial.experiment.run_spatial` returns.
    command : str
        The command line that made it.

    Returns
    -------
    str
        Markdown.
    """
    rows = result["rows"]
    spec = result["parameters"]["spatial"]
    noise = (f"noise on (the paper's camera, `scenes/paper.toml`): every number is the mean over {spec['seeds']} seeds "
             "with its 95 % Student-t interval in brackets" if spec["noise"] else
             "noise off: the spatial artefacts alone, one deterministic capture (`--set noise=true` adds the paper's "
             "camera noise and seeds)")
    out = _intro_lines(result, command, noise)
    out += _metric_tables(rows)
    out += ["## Figures", ""]
    for f in result.get("figures", []):
        if f not in _INTRO_FIGURES:   # shown once, with the answer
            out.append(f"![{f}]({f})")
    out += _setup_lines(result, spec, noise)
    out += ["## Time per stage (s)", "", "| target | " + " | ".join(result["timings"][next(iter(result["timings"]))])
            + " |", "|---|" + "---|" * 5]
    for t, st in result["timings"].items():
        out.append(f"| {t} | " + " | ".join(f"{v:.2f}" for v in st.values()) + " |")
    return "\n".join(out) + "\n"


#: The figures the report shows beside its answer (not a second time under Figures).
_INTRO_FIGURES = ("summary.png", "mtf.png")


def _intro_lines(result, command: str, noise: str) -> list[str]:
    """The title, how the report was made, the question, its answer and the summary figures."""
    return ["# spectracam spatial: does removing demosaicking give the prism and field-sequential cameras a spatial "
            "advantage?", "",
            f"Made by `{command}` (renderer {result['renderer']}, {result['wall_s']:.1f} s; {noise}).", "",
            "Catrysse, Wandell & El Gamal (1999) scored uniform patches only and named the next step: \"incorporate "
            "spatial factors to understand how the elimination of demosaicing provides a spatial advantage for FSC\". "
            "Here each design photographs slanted edges (neutral and coloured), zone plates (luminance and chroma), a "
            "Siemens star and a ColorChecker tilted in depth through a diffraction-limited lens and the pixel's "
            "aperture; the displayed image is scored by the e-SFR (MTF50), false colour, colour error at edges, "
            "aliasing and S-CIELAB (definitions and formulas: docs/metrics.md, \"Spatial\").", "",
            "## Answer", "", *answer(result), "",
            f"Reference: {result['parameters']['reference']} (aliasing counts as error). Spatial error = against the "
            "same camera's rendering of that reference (its colour-conversion error removed); `scielab_delta_e` / "
            "`cielab_delta_e` are against the reference itself and add the conversion error, which is the same for "
            "every design.", "",
            "![summary](summary.png)", "", "![MTF](mtf.png)", ""]


def _metric_tables(rows) -> list[str]:
    """One table per target and metric of :data:`REPORT_TABLES`: a row per design, a column per case."""
    cases, labels, index = _cases(rows), _labels(rows), _by_key(rows)
    out = []
    for t, keys in REPORT_TABLES.items():
        if not any(r.target == t for r in rows):
            continue
        out += [f"## {t.replace('_', ' ')}", ""]
        for key in keys:
            out += [f"**{key}**", "", "| design | " + " | ".join(f"{p:g} µm f/{N:g}" for p, N in cases) + " |",
                    "|---|" + "---|" * len(cases)]
            for lab in labels:
                out.append(f"| {lab} | " + " | ".join(_with_ci(index.get((lab, p, N, t)), key,
                                                               "{:.3f}" if "mtf" in key else "{:.2f}")
                                                      for p, N in cases) + " |")
            out.append("")
    return out


def _setup_lines(result, spec: dict, noise: str) -> list[str]:
    """The set-up and the choices made: cases, optics, targets, designs, sensor, S-CIELAB and e-SFR."""
    esfr = ("ISO 12233:2017 as the standard states it" if not spec["esfr_correct_binning"] else
            "ISO 12233:2017 with the binning correction of `spectracam.evaluation.esfr` (not in the standard)")
    return ["", "## Set-up and choices", "",
            f"* Cases: pixel pitch {', '.join(f'{p:g}' for p in spec['pixel_pitches_um'])} µm × f/"
            f"{', f/'.join(f'{n:g}' for n in spec['f_numbers'])}; a {spec['focal_length_mm']:g} mm thin lens, each target "
            "framed to the same pixels at every pitch (object distance from the magnification).",
            f"* Optics: the diffraction-limited OTF of a circular pupil per band, the pixel aperture (fill factor "
            f"{result['parameters']['fill_factor']:g}) integrated before sampling, {spec['supersampling']}×"
            f"{spec['supersampling']} sub-pixels per pixel; cos⁴ fall-off {'on' if spec['cos4'] else 'off'}.",
            "* Targets: slanted edges at 5° between ColorChecker neutral 6.5 and 3.5 (4.0:1), red/cyan, blue/yellow, "
            "dark/light skin and foliage/blue sky; zone plates ½ + ½cos(πkr²) reaching "
            f"{spec['zone_plate_max_cy_per_px']:g} cy/px at the inscribed radius (the two neutrals; magenta/cyan, "
            f"L* 51.0/51.8); a Siemens star of {spec['star_cycles']} cycles of the neutrals; the ColorChecker turned "
            f"{spec['chart_tilt_deg']:g}° about the vertical (thin-lens defocus across the field, focus at its centre).",
            f"* Designs: {', '.join(spec['designs'])}; mosaics with each demosaicking method that takes them, without "
            "and with a 4-spot birefringent optical low-pass filter (OLPF: spots at (±d/2, ±d/2) px, OTF "
            "cos(π·fx·d)·cos(π·fy·d)); a prism aligned and misaligned (red sensor shifted along x, blue along y by the "
            "stated amount, before sampling); field-sequential and stacked designs need no demosaicking.",
            f"* Sensor: {noise}.",
            f"* S-CIELAB: {result['samples_per_degree']:.1f} samples/degree (one image pixel per display pixel at "
            f"{spec['display_pixel_pitch_mm']:.3f} mm, viewed from {spec['viewing_distance_m']:g} m).",
            f"* e-SFR: {esfr}; MTF50 of the displayed luminance Y; per-channel MTF50 in results.json (None where a "
            "channel sees no usable step).",
            "* Every design's image of every case: `cases/<pitch>um_f<N>/<target>/` (linear EXR, sRGB PNG, error map "
            "with its scale).", ""]


def write_outputs(out_dir: Path, result: dict, command: str, maps: bool = True) -> list[Path]:
    """Write the figures, the case images, results.json, mtf_curves.json and report.md; ``result`` gains
    ``figures`` (the PNGs' names).

    Parameters
    ----------
    out_dir : Path
        The output folder.
    result : dict
        What :func:`~spectracam.experiments.spatial.experiment.run_spatial` returns.
    command : str
        The command line, in results.json, report.md and the EXRs.
    maps : bool
        Write every design's image and error map under ``cases/`` (:func:`write_case_images`).

    Returns
    -------
    list of Path
        Every file written.
    """
    out_dir = Path(out_dir)
    paths = []
    paths += figure_mtf(result, out_dir)
    paths += figure_summary(result, out_dir)
    for c in _cases(result["rows"]):
        paths += figure_crops(result, out_dir, c)
    for t in result["parameters"]["spatial"]["targets"]:
        paths += figure_scielab_maps(result, out_dir, t)
    result["figures"] = [p.name for p in paths if p.suffix == ".png"]
    if maps:
        paths += write_case_images(result, out_dir, command)
    public = {k: v for k, v in result.items() if k not in ("images", "mtf_curves", "display_white", "rows")}
    public["rows"] = [r.to_dict() for r in result["rows"]]
    public["display_white"] = np.asarray(result["display_white"]).tolist()
    public["command"] = command
    paths.append(atomic_write(out_dir / "results.json", json.dumps(public, indent=1, allow_nan=False,
                                                                   default=json_default).encode()))
    paths.append(atomic_write(out_dir / "mtf_curves.json", json.dumps(
        {"curves": result["mtf_curves"], "closed_form": result["closed_form"]}, allow_nan=False,
        default=json_default).encode()))
    paths.append(atomic_write(out_dir / "report.md", report_markdown(result, command).encode()))
    return paths
