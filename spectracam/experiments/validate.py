"""Real cameras checked against their published colour matrices, offline (``spectracam validate``).

For every shipped camera with a published XYZ(D65)→camera matrix ``M``
(:data:`spectracam.cameras.PUBLISHED_MATRICES`), the ColorChecker is rendered under CIE D65 and
captured by that camera's measured curves with every noise source off (a ``cfa/single`` capture
metered on the white patch, no clipping); each patch's raw rates are the means of its own sites.

* **Neutral**: the white patch's raw ``R/G`` and ``B/G`` against ``M·XYZ_white`` — the raw values the
  real camera records for that patch as its matrix implies.  For a camera whose gains were
  published with its curves (the Canon) this is an independent check of the curves; for one whose
  gains were restored from this very matrix (the Nikon) it checks only the restoration (it was
  fitted on a perfect white under D65, not on the patch).
* **ΔE*ab with the published matrix**: ``XYZ = M⁻¹·raw``, scaled so that the white patch has its own
  luminance (exposure normalised on a grey card, as a photographer does), against the scene's XYZ,
  CIELAB relative to the D65 white — the matrix was fitted by Adobe on other data, so this is a
  score on colours the conversion was not fitted on.
* **ΔE*ab of the least-squares fit**: a 3×3 fitted on the same 24 patches and scored on them — a
  *training* score, shown beside it as the lower bound a linear conversion reaches.

Beside these, the cameras' own measurements shipped by Debian packages, where installed
(:mod:`spectracam.experiments.validate_wb`): the simulated neutral under the light of each firmware
white-balance preset (darktable's ``wb_presets.json``) and RawTherapee's measured DCP profiles' matrices
against spectracam's fits; skipped, with the reason, where the files are absent.
"""
from __future__ import annotations

import numpy as np

from ..cameras import CAMERAS, PUBLISHED_MATRICES, d65_response, energy_sensitivities, library_curves, library_table
from ..chart import WHITE_PATCH
from ..errors import ConfigError
from ..metrics import delta_e, xyz_to_lab

#: The scene: the shipped D65 chart, small (noise-free, so the size does not change the means).
SCENE_OVERRIDES = {"image": {"width": 192, "height": 144}}


def validation_scene(camera_name: str):
    """The shipped D65 chart scene with the camera's curves, noise-free, flat QE (the curves hold it), on
    400–700 nm or the part of it the curves cover (the Sigma's stop at 680 nm)."""
    from ..scene import parse_scene, read_toml, shipped_scene_file

    data = read_toml(shipped_scene_file("d65.toml"), "scene file")
    lo, hi = library_curves(camera_name).range_nm  # the scene's 400-700 nm, narrowed to the curves' range
    wavelengths = {"start_nm": max(400.0, lo), "stop_nm": min(700.0, hi), "step_nm": 10.0}
    data = {**data, **SCENE_OVERRIDES, "wavelengths": wavelengths,
            "filters": {**data.get("filters", {}), "kind": "camera", "camera": camera_name, "qe": "flat"},
            "sensor": {**data.get("sensor", {}), "shot_noise": False, "dark_current": False, "read_noise": False,
                       "fpn": False, "quantization": False}}
    return parse_scene(data, f"spectracam validate ({camera_name})")


def raw_patch_rates(scene, renderer: str) -> np.ndarray:
    """``(24, 3)`` raw rates (e⁻/s) of the patches from a real render and noise-free capture."""
    from ..pipeline import capture
    from ..reference import ChartReference
    from ..render import render
    from ..score import channel_stats

    cube = render(scene, renderer)
    raw = capture(cube, scene=scene)
    means, _ = channel_stats(raw, ChartReference.of(scene).boxes)
    return means / np.asarray(raw.exposure_times_s)[None, :]


def validate_camera(name: str, renderer: str = "analytic") -> dict:
    """One camera's row: simulated and published neutral, ΔE*ab with the published matrix and the fit."""
    from ..reference import ChartReference

    curves = library_curves(name)
    matrix = PUBLISHED_MATRICES[curves.matrix]
    scene = validation_scene(name)
    ref = ChartReference.of(scene)
    rates = raw_patch_rates(scene, renderer)
    sim = rates[WHITE_PATCH] / rates[WHITE_PATCH][1]
    pub = matrix.neutral(ref.patch_xyz[WHITE_PATCH])
    lab_scene = xyz_to_lab(ref.patch_xyz, ref.white_xyz)
    est = rates @ np.linalg.inv(matrix.matrix).T
    est *= ref.patch_xyz[WHITE_PATCH, 1] / est[WHITE_PATCH, 1]
    de_pub = delta_e(xyz_to_lab(est, ref.white_xyz), lab_scene, "cie1976")
    fit, *_ = np.linalg.lstsq(rates, ref.patch_xyz, rcond=None)
    de_fit = delta_e(xyz_to_lab(rates @ fit, ref.white_xyz), lab_scene, "cie1976")
    row = {"camera": name, "model": matrix.model, "matrix_xyz_to_camera": list(matrix.xyz_to_camera),
           "matrix_source": matrix.source, "gains": curves.gains_note if curves.per_channel else "as published",
           "white_RG_simulated": float(sim[0]), "white_BG_simulated": float(sim[2]),
           "white_RG_published": float(pub[0]), "white_BG_published": float(pub[2]),
           "white_RG_error_percent": float(100 * (sim[0] / pub[0] - 1)),
           "white_BG_error_percent": float(100 * (sim[2] / pub[2] - 1)),
           "delta_e_published_mean": float(de_pub.mean()), "delta_e_published_max": float(de_pub.max()),
           "delta_e_fit_mean": float(de_fit.mean()), "delta_e_fit_max": float(de_fit.max()),
           "delta_e_published_per_patch": de_pub.round(4).tolist(), "delta_e_fit_per_patch": de_fit.round(4).tolist(),
           "patch_names": list(ref.names)}
    if curves.per_channel:  # what the defect gave: the channels at equal gains, on the white patch
        from ..chart import patch_reflectances

        r = d65_response(curves.wavelengths_nm, curves.values, patch_reflectances(scene.chart)[WHITE_PATCH][1])
        row["white_RG_equal_gains"], row["white_BG_equal_gains"] = float(r[0]), float(r[2])
    return row


def run_validate(renderer: str = "analytic") -> dict:
    """Every shipped camera with a published matrix, and the library as ``spectracam cameras`` lists it."""
    from .validate_wb import run_validate_wb

    names = [n for n in CAMERAS if library_curves(n).matrix in PUBLISHED_MATRICES and _usable(n)]
    rows = [validate_camera(n, renderer) for n in names]
    return {"renderer": renderer, "illuminant": "CIE D65", "chart": validation_scene(CAMERAS[0]).chart.dataset,
            "definitions": {
                "neutral": "raw R/G and B/G of the ColorChecker's white patch (noise-free capture) against "
                           "M·XYZ(white patch) of the published XYZ(D65)→camera matrix M",
                "delta_e_published": "CIE 1976 ΔE*ab of XYZ = M⁻¹·raw (scaled to the white patch's Y) against the "
                                     "scene's XYZ, CIELAB relative to D65; M was not fitted on these patches",
                "delta_e_fit": "CIE 1976 ΔE*ab of a 3×3 least-squares fit raw→XYZ on the same 24 patches (a training "
                               "score)"},
            "cameras": rows, "library": library_table(),
            # the cameras' own measurements from Debian packages (darktable, rawtherapee-data), or why skipped
            "real_camera_data": run_validate_wb(names)}


def _usable(name: str) -> bool:
    try:
        energy_sensitivities(name)
        return True
    except ConfigError:
        return False


def validate_markdown(result: dict, command: str) -> str:
    lines = ["# Real cameras against their published matrices", "", f"`{command}`", "",
             f"Chart: {result['chart']} under {result['illuminant']}, noise-free, renderer {result['renderer']}.", "",
             "| camera | gains | white R/G sim / published | B/G sim / published | ΔE*ab published M (mean / max) "
             "| ΔE*ab LS fit, training (mean / max) |", "|---|---|---|---|---|---|"]
    for r in result["cameras"]:
        lines.append(f"| {r['camera']} | {r['gains']} | {r['white_RG_simulated']:.3f} / {r['white_RG_published']:.3f} "
                     f"({r['white_RG_error_percent']:+.1f} %) | {r['white_BG_simulated']:.3f} / "
                     f"{r['white_BG_published']:.3f} ({r['white_BG_error_percent']:+.1f} %) | "
                     f"{r['delta_e_published_mean']:.2f} / {r['delta_e_published_max']:.2f} | "
                     f"{r['delta_e_fit_mean']:.2f} / {r['delta_e_fit_max']:.2f} |")
    for r in result["cameras"]:
        if "white_RG_equal_gains" in r:
            lines += ["", f"{r['camera']} read as shipped (each channel normalised to a peak of 1, so at equal "
                          f"gains): its white would read R/G {r['white_RG_equal_gains']:.3f}, B/G "
                          f"{r['white_BG_equal_gains']:.3f} against the published {r['white_RG_published']:.3f}, "
                          f"{r['white_BG_published']:.3f} — the gains must be restored."]
    lines += ["", "## Definitions", ""] + [f"* **{k}**: {v}" for k, v in result["definitions"].items()]
    if "real_camera_data" in result:  # white-balance presets and DCP profiles (validate_wb)
        from .validate_wb import wb_markdown

        lines += [""] + wb_markdown(result["real_camera_data"])
    lines += ["", "## The library", "", "| camera | range, nm | normalisation | gains | published matrix | source |",
              "|---|---|---|---|---|---|"]
    for c in result["library"]:
        lines.append(f"| {c['name']} | {c['range_nm'][0]:g}–{c['range_nm'][1]:g} | {c['normalisation']} | {c['gains']} "
                     f"| {c['published_matrix'] or '–'} | {c['source']} |")
    return "\n".join(lines) + "\n"


def validate_figure(result: dict):
    from ..io.plots import pyplot

    plt = pyplot()
    rows = result["cameras"]
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.4), gridspec_kw={"width_ratios": [1.3, 2.2]})
    x = np.arange(len(rows))
    for j, (key, label) in enumerate((("RG", "R/G"), ("BG", "B/G"))):
        axes[0].bar(x + (j - 0.5) * 0.4 - 0.1, [r[f"white_{key}_simulated"] for r in rows], 0.2,
                    label=f"{label} simulated", color=["#c0392b", "#2c6fbb"][j])
        axes[0].bar(x + (j - 0.5) * 0.4 + 0.1, [r[f"white_{key}_published"] for r in rows], 0.2,
                    label=f"{label} published M", color=["#e6a09a", "#9dbbe0"][j])
    axes[0].set_xticks(x, [r["model"].replace(" ", "\n", 1) for r in rows], fontsize=8)
    axes[0].set_ylabel("white patch raw, relative to G")
    axes[0].set_title("neutral under D65")
    axes[0].legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2)
    names = rows[0]["patch_names"] if rows else []
    px = np.arange(len(names))
    for i, r in enumerate(rows):
        w = 0.8 / max(len(rows), 1)
        axes[1].bar(px + i * w - 0.4 + w / 2, r["delta_e_published_per_patch"], w * 0.9,
                    label=f"{r['model']}: published M (mean {r['delta_e_published_mean']:.2f})")
        axes[1].plot(px + i * w - 0.4 + w / 2, r["delta_e_fit_per_patch"], "k_", ms=6,
                     label="LS fit, training" if i == 0 else None)
    axes[1].set_xticks(px, names, rotation=70, fontsize=7)
    axes[1].set_ylabel("ΔE*ab (CIE 1976)")
    axes[1].set_title("simulated raw converted by each camera's published matrix")
    axes[1].legend(fontsize=8)
    fig.tight_layout()
    return fig


def write_validate_outputs(out_dir, result: dict, command: str) -> list:
    """validate.json, validate.md and validate.png/.svg, atomically."""
    from ..io.report import write_figure_json_markdown

    return write_figure_json_markdown(out_dir, "validate", validate_figure(result), "validate.json", result, command,
                                      "validate.md", validate_markdown(result, command))
