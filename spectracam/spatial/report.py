"""Outputs of the spatial experiment: results.json, mtf_curves.json, figures (PNG + SVG), report.md."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..io.files import atomic_write, json_default
from ..io.plots import pyplot, save_figure, srgb_image


def _cases(rows):
    seen = []
    for r in rows:
        c = (r["pixel_pitch_um"], r["f_number"])
        if c not in seen:
            seen.append(c)
    return seen


def _labels(rows):
    seen = []
    for r in rows:
        if r["label"] not in seen:
            seen.append(r["label"])
    return seen


def _get(rows, label, pitch, N, target, key):
    for r in rows:
        if r["label"] == label and r["pixel_pitch_um"] == pitch and r["f_number"] == N and r["target"] == target:
            return r[key]
    return None


COLOURS = {"cfa/single bilinear": "#d62728", "cfa/single malvar2004": "#ff7f0e", "cfa/single menon2007": "#e377c2",
           "prism/optimal aligned": "#1f77b4", "fsc/optimal": "#2ca02c"}


#: Other architectures (``spectracam architectures``), one colour each whatever their demosaicker.
ARCH_COLOURS = {"stacked": "#8c564b", "rgbw": "#9467bd", "ryyb": "#bcbd22", "cmy": "#17becf", "quad_bayer": "#7f7f7f"}


def _colour(label):
    base = label.split(" OLPF")[0]   # with or without the low-pass filter: one colour (the line style differs)
    if base in COLOURS:
        return COLOURS[base]
    if "misaligned" in label:
        return "#17becf"
    return ARCH_COLOURS.get(label.split("/")[0], "#000000")


def _style(label):
    """Line style: dashed for a misaligned prism, dash-dot with an optical low-pass filter."""
    return "--" if "misaligned" in label else "-." if "OLPF" in label else "-"


def figure_mtf(result, out: Path) -> list[Path]:
    plt = pyplot()
    curves = result["mtf_curves"]
    cases = _cases(result["rows"])
    if not curves:
        return []
    n = len(cases)
    cols = min(2, n)
    rws = -(-n // cols)
    fig, axes = plt.subplots(rws, cols, figsize=(6 * cols, 4 * rws), squeeze=False, constrained_layout=True)
    for ax, (p, N) in zip(axes.ravel(), cases):
        for c in curves:
            if c["pixel_pitch_um"] == p and c["f_number"] == N:
                f = np.asarray(c["frequencies_cy_per_px"])
                ax.plot(f, c["Y"], _style(c["label"]), color=_colour(c["label"]), lw=1.4, label=c["label"])
        cf = result["closed_form"].get(f"{p:g}um_f{N:g}")
        if cf:
            ax.plot(cf["frequencies_cy_per_px"], cf["G"], ":", color="k", lw=1.2,
                    label="diffraction × pixel aperture (closed form, G)")
            for key in (k for k in cf if k.startswith("G OLPF")):
                ax.plot(cf["frequencies_cy_per_px"], cf[key], ":", color="0.45", lw=1.2,
                        label=f"… × {key[2:]} (closed form, G)")
        ax.axvline(0.5, color="0.6", lw=0.8)
        ax.axhline(0.5, color="0.8", lw=0.6)
        ax.set(xlim=(0, 1), ylim=(0, 1.25), xlabel="cycles / pixel", ylabel="e-SFR of displayed luminance Y",
               title=f"{p:g} µm pixel, f/{N:g}")
        ax.grid(alpha=0.3)
    for ax in axes.ravel()[n:]:
        ax.axis("off")
    handles, names = axes.ravel()[0].get_legend_handles_labels()
    fig.legend(handles, names, loc="outside lower center", ncol=4, fontsize=8, frameon=False)
    fig.suptitle("Slanted edge (ISO 12233 e-SFR, 5°, 4:1): MTF per design; grey line: Nyquist", fontsize=11)
    return save_figure(fig, out / "mtf.png", out / "mtf.svg")


def figure_summary(result, out: Path) -> list[Path]:
    plt = pyplot()
    rows = result["rows"]
    cases = _cases(rows)
    labels = _labels(rows)
    panels = [("edge", "mtf50_cy_per_px", "MTF50, cycles/pixel (edge; higher is better)"),
              ("star", "scielab_delta_e_spatial", "S-CIELAB ΔE, spatial error (star)"),
              ("edge", "false_colour", "false colour √(Δa*²+Δb*²) at the edge"),
              ("chart", "scielab_delta_e_spatial", "S-CIELAB ΔE, spatial error (tilted chart)")]
    targets = {r["target"] for r in rows}
    panels = [p for p in panels if p[0] in targets]
    fig, axes = plt.subplots(1, len(panels), figsize=(5 * len(panels), 4.2), squeeze=False, constrained_layout=True)
    x = np.arange(len(cases))
    wbar = 0.8 / len(labels)
    for ax, (t, key, title) in zip(axes[0], panels):
        for i, lab in enumerate(labels):
            vals = [_get(rows, lab, p, N, t, key) for p, N in cases]
            vals = [np.nan if v is None else v for v in vals]
            ax.bar(x + (i - (len(labels) - 1) / 2) * wbar, vals, wbar, color=_colour(lab), label=lab,
                   hatch="//" if "misaligned" in lab else ".." if "OLPF" in lab else None)
        ax.set_xticks(x, [f"{p:g} µm\nf/{N:g}" for p, N in cases])
        ax.set_title(title, fontsize=10)
        ax.grid(axis="y", alpha=0.3)
    handles, names = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, names, loc="outside lower center", ncol=len(names), fontsize=8, frameon=False)
    return save_figure(fig, out / "summary.png", out / "summary.svg")


def _crop_box(target, shape):
    h, w = shape[:2]
    if target == "star":
        c = min(h, w) // 2
        r = max(16, min(h, w) // 5)
        return slice(c - r, c + r), slice(w // 2 - r, w // 2 + r)
    if target == "edge":
        r = max(12, min(h, w) // 6)
        return slice(h // 2 - r, h // 2 + r), slice(w // 2 - r, w // 2 + r)
    r = max(16, h // 4)
    return slice(h // 2 - r, h // 2 + r), slice(w // 2 - int(1.5 * r), w // 2 + int(1.5 * r))


def figure_crops(result, out: Path, case) -> list[Path]:
    plt = pyplot()
    rows = result["rows"]
    labels = _labels(rows)
    targets = [t for t in ("edge", "star", "chart") if (case[0], case[1], t, "ideal") in result["images"]]
    white = result["display_white"]
    fig, axes = plt.subplots(len(targets), len(labels) + 1, figsize=(2.2 * (len(labels) + 1), 2.3 * len(targets)),
                             squeeze=False)
    for i, t in enumerate(targets):
        for j, lab in enumerate(["ideal"] + labels):
            im = result["images"][(case[0], case[1], t, lab)]["xyz"]
            box = _crop_box(t, im.shape)
            ax = axes[i, j]
            ax.imshow(srgb_image(im[box].astype(float), white), interpolation="nearest")
            ax.set_xticks([]), ax.set_yticks([])
            if i == 0:
                ax.set_title("ideal (scene)" if lab == "ideal" else lab.replace("/optimal", "").replace("/single", ""),
                             fontsize=8)
    fig.suptitle(f"Crops of each design, {case[0]:g} µm pixel, f/{case[1]:g} (nearest-neighbour zoom)", fontsize=10)
    return [save_figure(fig, out / f"crops_{case[0]:g}um_f{case[1]:g}.png")]


def figure_scielab_maps(result, out: Path, target: str = "star") -> list[Path]:
    plt = pyplot()
    rows = result["rows"]
    labels = _labels(rows)
    cases = [c for c in _cases(rows) if (c[0], c[1], target, labels[0]) in result["images"]]
    if not cases:
        return []
    maps = {(c, lab): np.where(result["images"][(c[0], c[1], target, lab)]["region"],
                               result["images"][(c[0], c[1], target, lab)]["scielab"], np.nan)
            for c in cases for lab in labels}
    vmax = float(np.nanpercentile(np.concatenate([m.ravel() for m in maps.values()]), 99.5))
    fig, axes = plt.subplots(len(cases), len(labels), figsize=(2.3 * len(labels), 2.4 * len(cases)), squeeze=False)
    for i, c in enumerate(cases):
        for j, lab in enumerate(labels):
            ax = axes[i, j]
            h = ax.imshow(maps[(c, lab)], cmap="magma", vmin=0, vmax=vmax, interpolation="nearest")
            ax.set_xticks([]), ax.set_yticks([])
            if i == 0:
                ax.set_title(lab.replace("/optimal", "").replace("/single", ""), fontsize=8)
            if j == 0:
                ax.set_ylabel(f"{c[0]:g} µm, f/{c[1]:g}", fontsize=8)
    fig.colorbar(h, ax=axes, shrink=0.6, label="S-CIELAB ΔE*ab (spatial error)")
    fig.suptitle(f"S-CIELAB maps (spatial error, inside the scored region), {target}", fontsize=10)
    return [save_figure(fig, out / f"scielab_{target}.png")]


def write_maps(result, out: Path) -> list[Path]:
    """Every S-CIELAB map (spatial error) as a PNG, one image pixel per map pixel, magma from 0 to the
    largest ΔE of all maps (written in maps/scale.json)."""
    import io as _io

    import matplotlib.image

    maps = {k: im["scielab"] for k, im in result["images"].items() if "scielab" in im}
    if not maps:
        return []
    vmax = float(max(np.max(m) for m in maps.values()))
    paths = []
    for (p, N, t, lab), m in maps.items():
        buf = _io.BytesIO()
        matplotlib.image.imsave(buf, m, cmap="magma", vmin=0.0, vmax=vmax, format="png")
        name = f"{t}_{p:g}um_f{N:g}_{lab.replace('/', '-').replace(' ', '_')}.png"
        paths.append(atomic_write(out / "maps" / name, buf.getvalue()))
    paths.append(atomic_write(out / "maps" / "scale.json", json.dumps(
        {"colormap": "magma", "vmin_delta_e": 0.0, "vmax_delta_e": vmax,
         "what": "S-CIELAB ΔE*ab against the camera's own rendering of the ideal image"}).encode()))
    return paths


def _fmt(v, f="{:.3f}"):
    return "–" if v is None else f.format(v)


def answer(result) -> list[str]:
    """The paper's question answered with numbers."""
    rows = result["rows"]
    lines = []
    cfa_labels = [lab for lab in _labels(rows) if lab.startswith("cfa") and "OLPF" not in lab]
    olpf_labels = [lab for lab in _labels(rows) if lab.startswith("cfa") and "OLPF" in lab]
    mis = sorted({r["misregistration_px"] for r in rows if r["design"].startswith("prism") and r["misregistration_px"] > 0})
    for p, N in _cases(rows):
        fsc = _get(rows, "fsc/optimal", p, N, "edge", "mtf50_cy_per_px")
        prism = _get(rows, "prism/optimal aligned", p, N, "edge", "mtf50_cy_per_px")
        cfa = {lab: _get(rows, lab, p, N, "edge", "mtf50_cy_per_px") for lab in cfa_labels}
        star = {lab: _get(rows, lab, p, N, "star", "scielab_delta_e_spatial") for lab in _labels(rows)}
        if fsc is None or not cfa or any(v is None for v in cfa.values()):
            continue
        best = max(cfa, key=lambda k: cfa[k])
        worst = min(cfa, key=lambda k: cfa[k])
        s = (f"* **{p:g} µm, f/{N:g}.** MTF50 (displayed luminance): field-sequential {fsc:.3f} cy/px, prism (aligned) "
             f"{_fmt(prism)}; the colour filter array {cfa[worst]:.3f} ({worst.split()[-1]}) to {cfa[best]:.3f} "
             f"({best.split()[-1]}) — removing demosaicking gains ×{fsc / cfa[worst]:.2f} over {worst.split()[-1]} and "
             f"×{fsc / cfa[best]:.2f} over {best.split()[-1]}.")
        if star.get("fsc/optimal") is not None:
            cs = {k: v for k, v in star.items() if k in cfa_labels and v is not None}
            bcfa = min(cs, key=lambda k: cs[k])
            s += (f" S-CIELAB spatial error on the star: FSC {star['fsc/optimal']:.2f}, best CFA "
                  f"({bcfa.split()[-1]}) {cs[bcfa]:.2f}, worst CFA {max(cs.values()):.2f} ΔE.")
        for m in mis:
            lab = f"prism/optimal misaligned {m:g} px"
            pm = _get(rows, lab, p, N, "edge", "mtf50_cy_per_px")
            ps = star.get(lab)
            pf = _get(rows, lab, p, N, "edge", "false_colour")
            cf_best = min(_get(rows, c, p, N, "edge", "false_colour") for c in cfa_labels)
            if pm is not None:
                s += (f" Misaligned by {m:g} px the prism keeps MTF50 {pm:.3f} but its false colour at the edge rises to "
                      f"{pf:.2f} (aligned {_fmt(_get(rows, 'prism/optimal aligned', p, N, 'edge', 'false_colour'), '{:.2f}')}, "
                      f"best CFA {cf_best:.2f})")
                if ps is not None and star.get("prism/optimal aligned") is not None:
                    s += (f" and its S-CIELAB error on the star to {ps:.2f} ΔE (aligned "
                          f"{star['prism/optimal aligned']:.2f}, best CFA {min(cs.values()):.2f})")
                s += "."
        for lab in olpf_labels:   # the same demosaicker without the filter
            plain = lab.split(" OLPF")[0]
            m0, m1 = _get(rows, plain, p, N, "edge", "mtf50_cy_per_px"), _get(rows, lab, p, N, "edge", "mtf50_cy_per_px")
            f0, f1 = _get(rows, plain, p, N, "edge", "false_colour"), _get(rows, lab, p, N, "edge", "false_colour")
            s0, s1 = star.get(plain), star.get(lab)
            if None not in (m0, m1, f0, f1):
                s += (f" {plain.split()[-1]} with an OLPF of {lab.split('OLPF ')[1]}: MTF50 {m0:.3f} → {m1:.3f}, "
                      f"false colour at the edge {f0:.2f} → {f1:.2f}"
                      + (f", S-CIELAB on the star {s0:.2f} → {s1:.2f}" if None not in (s0, s1) else "") + ".")
        lines.append(s)
    return lines


def report_markdown(result, command: str) -> str:
    rows = result["rows"]
    spec = result["parameters"]["spatial"]
    cases = _cases(rows)
    labels = _labels(rows)
    out = ["# spectracam spatial: does removing demosaicking give the prism and field-sequential cameras a spatial "
           "advantage?", "",
           f"Made by `{command}` (renderer {result['renderer']}, {result['wall_s']:.1f} s).", "",
           "Catrysse, Wandell & El Gamal (1999) scored uniform patches only and named the next step: \"incorporate "
           "spatial factors to understand how the elimination of demosaicing provides a spatial advantage for FSC\". "
           "Here each design photographs an ISO 12233 slanted edge, a Siemens star and a ColorChecker tilted in depth "
           "through a diffraction-limited lens and the pixel's aperture; the displayed image is scored by the e-SFR "
           "(MTF50), false colour at neutral edges, and S-CIELAB.", "",
           "## Answer", "", *answer(result), "",
           "Spatial error = against the same camera's rendering of the ideal image (its colour-conversion error removed); "
           "against the scene itself (the paper's reference) the columns `scielab_delta_e` / `cielab_delta_e` of "
           "results.json and the tables below add the conversion error, which is the same for every design.", "",
           "![summary](summary.png)", "", "![MTF](mtf.png)", ""]
    for t, keys in (("edge", ("mtf50_cy_per_px", "false_colour", "scielab_delta_e_spatial", "scielab_delta_e",
                              "cielab_delta_e")),
                    ("star", ("false_colour", "scielab_delta_e_spatial", "scielab_delta_e", "cielab_delta_e_spatial",
                              "cielab_delta_e")),
                    ("chart", ("scielab_delta_e_spatial", "scielab_delta_e", "cielab_delta_e", "patch_delta_e",
                               "defocus_max_um"))):
        if not any(r["target"] == t for r in rows):
            continue
        out += [f"## {t}", ""]
        for key in keys:
            out += [f"**{key}**", "", "| design | " + " | ".join(f"{p:g} µm f/{N:g}" for p, N in cases) + " |",
                    "|---|" + "---|" * len(cases)]
            for lab in labels:
                out.append(f"| {lab} | " + " | ".join(_fmt(_get(rows, lab, p, N, t, key),
                                                            "{:.3f}" if "mtf" in key else "{:.2f}") for p, N in cases) + " |")
            out.append("")
    out += ["## Figures", ""]
    for f in result.get("figures", []):
        out.append(f"![{f}]({f})")
    out += ["", "## Set-up and choices", "",
            f"* Cases: pixel pitch {', '.join(f'{p:g}' for p in spec['pixel_pitches_um'])} µm × f/"
            f"{', f/'.join(f'{n:g}' for n in spec['f_numbers'])}; a {spec['focal_length_mm']:g} mm thin lens, each target "
            "framed to the same pixels at every pitch (object distance from the magnification).",
            f"* Optics: the diffraction-limited OTF of a circular pupil per band, the pixel aperture (fill factor "
            f"{result['parameters']['fill_factor']:g}) integrated before sampling, {spec['supersampling']}×"
            f"{spec['supersampling']} sub-pixels per pixel; cos⁴ fall-off {'on' if spec['cos4'] else 'off'}.",
            "* Targets: edge 5° between ColorChecker neutral 6.5 and neutral 3.5 (4.0:1); Siemens star of "
            f"{spec['star_cycles']} cycles of the same neutrals; the ColorChecker turned {spec['chart_tilt_deg']:g}° "
            "about the vertical (thin-lens defocus across the field, focus at its centre).",
            f"* Designs: {', '.join(spec['designs'])}; mosaics with each demosaicking method that takes them, without "
            "and with a 4-spot birefringent optical low-pass filter (OLPF: spots at (±d/2, ±d/2) px, OTF "
            "cos(π·fx·d)·cos(π·fy·d)); a prism aligned and misaligned (red sensor shifted along x, blue along y by the "
            "stated amount, before sampling); field-sequential and stacked designs need no demosaicking.",
            f"* Sensor noise {'on (the paper’s camera)' if spec['noise'] else 'off (spatial artefacts alone; --set noise=true adds the paper’s noise)'}.",
            f"* S-CIELAB: {result['samples_per_degree']:.1f} samples/degree (one image pixel per display pixel at "
            f"{spec['display_pixel_pitch_mm']:.3f} mm, viewed from {spec['viewing_distance_m']:g} m).",
            "* e-SFR: ISO 12233:2017 with the binning correction of `spectracam.spatial.esfr` (closer to the truth "
            "than the standard's −2.5 % at 0.5 cy/px); MTF50 of the displayed luminance Y; per-channel MTF50 in "
            "results.json.", "",
            "## Time per stage (s)", "", "| target | " + " | ".join(result["timings"][next(iter(result["timings"]))]) + " |",
            "|---|" + "---|" * 5]
    for t, st in result["timings"].items():
        out.append(f"| {t} | " + " | ".join(f"{v:.2f}" for v in st.values()) + " |")
    return "\n".join(out) + "\n"


def write_outputs(out_dir: Path, result: dict, command: str, maps: bool = True) -> list[Path]:
    out_dir = Path(out_dir)
    paths = []
    paths += figure_mtf(result, out_dir)
    paths += figure_summary(result, out_dir)
    cases = _cases(result["rows"])
    for c in cases:
        paths += figure_crops(result, out_dir, c)
    for t in ("star", "edge", "chart"):
        paths += figure_scielab_maps(result, out_dir, t)
    result["figures"] = [p.name for p in paths if p.suffix == ".png"]
    if maps:
        paths += write_maps(result, out_dir)
    public = {k: v for k, v in result.items() if k not in ("images", "mtf_curves", "display_white")}
    public["display_white"] = np.asarray(result["display_white"]).tolist()
    public["command"] = command
    paths.append(atomic_write(out_dir / "results.json", json.dumps(public, indent=1, allow_nan=False,
                                                                   default=json_default).encode()))
    paths.append(atomic_write(out_dir / "mtf_curves.json", json.dumps(
        {"curves": result["mtf_curves"], "closed_form": result["closed_form"]}, allow_nan=False,
        default=json_default).encode()))
    paths.append(atomic_write(out_dir / "report.md", report_markdown(result, command).encode()))
    return paths
