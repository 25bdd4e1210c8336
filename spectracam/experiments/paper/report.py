"""Writes the paper experiment's outputs: figures (PNG + SVG), results.json, report.md, case files."""
from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

from spectracam.core.files import atomic_write
from spectracam.io.plots import save_figure
from spectracam.experiments.paper import figures
from spectracam.experiments.paper.claims import derivations

if TYPE_CHECKING:
    from collections.abc import Callable

__all__ = ["PAPER_CLAIMS_NOTE", "both_ways_lines", "report_markdown", "write_paper_outputs"]

PAPER_CLAIMS_NOTE = ("Verdicts: reproduced — direction and size as the paper states; partly — the direction "
                     "holds, the size does not; not — the direction does not hold.")


def _table(header: list[str], rows: list[list]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(x) for x in row) + " |" for row in rows]
    return "\n".join(lines)


def _per_design(results: dict, key: str, fmt: str) -> str:
    data = results[key]
    temps = results["parameters"]["temperatures_K"]
    return _table(["design"] + [f"{t} K" for t in temps],
                  [[d] + [fmt.format(v[t]) if v[t] is not None else "∞" for t in temps] for d, v in data.items()])


def report_markdown(results: dict, command: str) -> str:
    """report.md: the choices the paper leaves open, every figure's numbers, the claims and their sensitivity.

    Parameters
    ----------
    results : dict
        The paper run's results (:func:`~spectracam.experiments.paper.experiment.run_paper`'s first).
    command : str
        The command that made them, recorded at the top.

    Returns
    -------
    str
        The markdown.
    """
    lines = [*_header_lines(results, command), *_figure_lines(results), *_claims_lines(results)]
    lines += _sensitivity_lines(results)
    lines += ["## Files", "", "`results.json` holds every number above; `cases/` holds the raw (raw.exr) and rendered "
              "(rendered.exr) images of every case — and the spectral radiance (radiance.exr) of every light with "
              "`--save-cubes` — each carrying the parameters it came from.", ""]
    return "\n".join(lines)


def _header_lines(results: dict, command: str) -> list:
    """The title, the command that made the report and the choices the paper does not give."""
    p = results["parameters"]
    return [
        "# spectracam: Catrysse, Wandell & El Gamal (1999), section 5, reproduced", "",
        f"Made by `{command}` (renderer: {p['renderer']}{', quick' if p['quick'] else ''}; seed {p['seed']}).", "",
        "## Parameters the paper does not give", "",
        _open_choices(p), ""]


def _open_choices(p: dict) -> str:
    """The table of the choices the paper does not give: each one's value here and why."""
    sc = p["scene"]
    cam = {k: sc[k] for k in ("optics", "filters", "sensor", "capture")}
    return _table(["choice", "value here", "why"], [
        ["light level", f"{p['white_luminance_cd_m2']:.1f} cd/m² white-diffuser luminance "
                        f"({p['illuminance_lux']:.0f} lx), all illuminants",
         p["light_calibration"] + " (Fig. 5 caption)"],
        ["pixel", f"{cam['sensor']['pixel_pitch_um']:g} µm pitch, fill factor {cam['sensor']['fill_factor']:g}",
         "a 131072 e⁻ well at ~1300 e⁻/µm² implies ~100 µm²"],
        ["QE", f"{cam['filters']['qe']}"
         + (f", collection depth {cam['filters']['collection_depth_um']:g} µm" if cam['filters']['qe'] == "photodiode"
            else "") + f", peak {cam['filters']['qe_peak']:g}",
         "a front-illuminated CMOS photodiode of 1999 collects from a shallow depth (silicon absorption, Green "
         "2008); of the readings mapped by `spectracam consistency`, the physical one that reproduces most claims"],
        ["FPN < 1 %", f"{cam['sensor']['fpn_reading']} reading of {cam['sensor']['fpn_fraction']:g} × full swing",
         "'std': an rms of that fraction; 'bound': a uniform spread of that width (rms /√12)"],
        ["black level", f"{cam['sensor']['black_level_DN'] if cam['sensor']['black_level_DN'] is not None else 'default (2ⁿ⁻⁵ DN)'}",
         "a pedestal keeps the dark noise off code 0 (EMVA 1288); the paper's ADC is not described"],
        ["display", sc["processing"]["display"], "the paper's 'simple CRT display' (Brainard 1997 phosphors)"],
        ["adaptation", sc["processing"]["adaptation"], "preserves CIELAB against each white exactly"],
        ["SNR of three channels", sc["processing"]["snr_combination"], p["snr"]],
        ["ΔE", sc["processing"]["delta_e"], p["delta_e"]],
        ["demosaicking", sc["processing"]["demosaic"], "colour-demosaicing; scored inside patch masks only"],
    ])


def _figure_lines(results: dict) -> list:
    """The exposures and Figures 4, 5 and 6 (with the held-out and both-ways tables between them)."""
    p = results["parameters"]
    return [
        "## Exposure (capture time, ms)", "", _per_design(results, "exposure_ms", "{:.1f}"), "",
        "## Figure 4: relative response to the white patch (R, G, B; 1 = full well)", "",
        _table(["design"] + [f"{t} K" for t in p["temperatures_K"]],
               [[d] + [" / ".join(f"{x:.2f}" for x in v[t]) for t in p["temperatures_K"]]
                for d, v in results["fig4_white_response"].items()]), "",
        "![Figure 4](fig4.png)", "",
        "## Figure 5a: SNR (dB), mean over the 24 patches", "", _per_design(results, "fig5a_snr_db", "{:.1f}"), "",
        "## Figure 5b: mean ΔE*ab over the 24 patches", "", _per_design(results, "fig5b_delta_e", "{:.2f}"), "",
        "ΔE*ab of each patch's mean colour (noise averaged out, mostly the conversion):", "",
        _per_design(results, "fig5b_delta_e_of_mean", "{:.2f}"), "",
        *_s_cielab_lines(results),
        "![Figure 5](fig5.png)", "",
        *_held_out_lines(results),
        *both_ways_lines(results),
        f"## Figure 6: cumulative error budget, {p['budget_design']} under {p['budget_illuminant']}", "",
        _table(["step", "mean ΔE*ab", "S-CIELAB (against the scene)"],
               [[s["label"], f"{s['delta_e']:.2f}", "–" if s.get("s_cielab") is None else f"{s['s_cielab']:.2f}"]
                for s in results["fig6_budget_delta_e"]]), "",
        f"Method: {p['fig6_method']}.", "",
        "![Figure 6](fig6.png)", ""]


def _claims_lines(results: dict) -> list:
    """The paper's claims beside this run's numbers, and why a size cannot be met."""
    return [
        "## The paper's claims beside this run", "", PAPER_CLAIMS_NOTE, "",
        _table(["claim", "paper", "this run", "verdict", "why it differs"],
               [[c["claim"], c["paper"], c["measured"], c["verdict"], c["why"]] for c in results["claims"]]), "",
        *derivations(results)]


def _sensitivity_lines(results: dict) -> list:
    """Which claims survive which alternative reading, and the key numbers under each."""
    sens = results["sensitivity"]
    if not sens["alternatives"]:
        return []
    names = list(sens["alternatives"])
    return ["## Sensitivity: which conclusions survive which choices", "",
            "Each column reruns the whole comparison with one choice changed (same renders, same seed).", "",
            _table(["alternative", "why"], [[n, sens["alternatives"][n]["reason"]] for n in names]), "",
            _table(["claim", "default"] + names,
                   [[cid] + [v.get(n, "") for n in ["default"] + names] for cid, v in sens["claims"].items()]), "",
            "Key numbers under each alternative (5000 K where the grid has it):", "",
            _table(["alternative", "cfa ms", "fsc ms", "SNR cfa", "SNR fsc", "SNR fsc bal.", "ΔE cfa",
                    "ΔE fsc", "ΔE fsc bal."],
                   [[n] + _key_numbers(sens["alternatives"][n]) for n in names]
                   + [["default"] + _key_numbers(results)]), ""]


def _s_cielab_lines(results: dict) -> list:
    """Figure 5b's per-pixel ΔE*ab beside S-CIELAB: the same pixels, the noise blurred by the eye's filters."""
    if not results.get("fig5b_s_cielab"):
        return []
    v = results["parameters"].get("s_cielab_viewing", {})
    temps = results["parameters"]["temperatures_K"]
    rows = [[d] + [f"{results['fig5b_delta_e'][d][t]:.2f} / {results['fig5b_s_cielab'][d][t]:.2f}" for t in temps]
            for d in results["fig5b_s_cielab"]]
    return ["Per-pixel ΔE*ab / S-CIELAB on the same pixels (Zhang & Wandell's spatial extension: rendering and scene "
            f"through the eye's filters, {v.get('viewing_distance_m', 0.5):g} m from a display of "
            f"{v.get('display_pixel_pitch_mm', 25.4 / 120):.3g}-mm pixels, {v.get('samples_per_degree', 0):.1f} "
            "samples per degree; the noise counts as much as the eye sees of it; docs/metrics.md):", "",
            _table(["design"] + [f"{t} K" for t in temps], rows), ""]


def _key_numbers(r: dict) -> list[str]:
    T = "5000" if "5000" in r["exposure_ms"].get("cfa/single", {}) else None

    def g(key, d, fmt):
        try:
            per = r[key][d]
            t = T or sorted(per, key=float)[len(per) // 2]
            return fmt.format(per[t])
        except (KeyError, TypeError):
            return "–"

    return [g("exposure_ms", "cfa/single", "{:.0f}"), g("exposure_ms", "fsc/optimal", "{:.0f}"),
            g("fig5a_snr_db", "cfa/single", "{:.1f}"), g("fig5a_snr_db", "fsc/optimal", "{:.1f}"),
            g("fig5a_snr_db", "fsc/balanced", "{:.1f}"), g("fig5b_delta_e", "cfa/single", "{:.2f}"),
            g("fig5b_delta_e", "fsc/optimal", "{:.2f}"), g("fig5b_delta_e", "fsc/balanced", "{:.2f}")]


def both_ways_lines(results: dict) -> list[str]:
    """The oracle camera (the paper's: told the light) beside the developed one (its own metering, white balance and
    calibration), per design and light (issue 33).

    Parameters
    ----------
    results : dict
        A run's results; its ``both_ways`` (:func:`~spectracam.experiments.paper.experiment.both_ways`) is tabled.

    Returns
    -------
    list of str
        Markdown lines: tables of mean ΔE*ab, S-CIELAB (when scored), CIEDE2000, held-out ΔE*ab (each cell
        ``oracle / developed``) and the developed camera's white-balance angles, °; empty without ``both_ways``.
    """
    bw = results.get("both_ways")
    if not bw:
        return []
    temps = results["parameters"]["temperatures_K"]
    o, d = bw["oracle"], bw["developed"]

    def cell(f, design, t, fmt="{:.2f}"):
        a, b = o[f][design][t], d[f][design][t]
        return " / ".join("–" if v is None else fmt.format(v) for v in (a, b))

    rows = [[design] + [cell("delta_e_mean", design, t) for t in temps] for design in o["delta_e_mean"]]
    rows_sc = [[design] + [cell("s_cielab_mean", design, t) for t in temps] for design in o.get("s_cielab_mean", {})]
    rows2000 = [[design] + [cell("delta_e2000_mean", design, t) for t in temps] for design in o["delta_e_mean"]]
    held = [[design] + [cell("held_out_delta_e", design, t) for t in temps] for design in o["delta_e_mean"]]
    awb = [[design] + [f"{d['awb_recovery_deg'][design][t]:.2f}° / {d['awb_reproduction_deg'][design][t]:.2f}°"
                       for t in temps] for design in o["delta_e_mean"]]
    proc = bw["developed_processing"]
    return ["## The camera that is told the light beside one that finds its own", "",
            "Each cell: oracle / developed.  The oracle is the paper's camera (exposure metered on the chart's white "
            "patch, conversion fitted under the scene's own light); the developed camera meters a preview itself "
            f"(`{proc['camera']}`: percentile metering), estimates the light's neutral from the image "
            "(white balance `corrected_moments`, trained on colours that are not the chart's) and interpolates two "
            "DNG calibrations (CIE A, D65) by the colour temperature it finds (`dual_illuminant`); it shows its "
            "metered white at display Y = 1.  Same renders, same seed.  Definitions: docs/metrics.md.", "",
            "Mean per-pixel ΔE*ab over the 24 patches:", "", _table(["design"] + [f"{t} K" for t in temps], rows), "",
            *(["Mean per-pixel S-CIELAB (the same pixels through the eye's filters):", "",
               _table(["design"] + [f"{t} K" for t in temps], rows_sc), ""] if rows_sc else []),
            "Mean per-pixel CIEDE2000:", "", _table(["design"] + [f"{t} K" for t in temps], rows2000), "",
            "Held-out colours (noise-free, through the matrix each camera used), mean ΔE*ab:", "",
            _table(["design"] + [f"{t} K" for t in temps], held), "",
            "The developed camera's white-balance error (recovery / reproduction angle against the true neutral):", "",
            _table(["design"] + [f"{t} K" for t in temps], awb), ""]


def _held_out_lines(results: dict) -> list:
    """The conversion's noise-free error on the 24 patches it is fitted on (training) beside the error
    on a library it never saw (held out), per design and light (spectracam.evaluation.heldout)."""
    lib = results.get("held_out_library")
    if not lib or not results.get("held_out_delta_e"):
        return []
    temps = list(next(iter(results["held_out_delta_e"].values())))
    rows = [[d] + [f"{results['delta_e_conversion'][d][t]:.2f} / {results['held_out_delta_e'][d][t]:.2f} "
                   f"(p95 {results['delta_e_conversion_p95'][d][t]:.1f} / {results['held_out_delta_e_p95'][d][t]:.1f})"
                   for t in temps] for d in results["held_out_delta_e"]]
    return ["## The conversion on colours it was not fitted on", "",
            f"Noise-free ΔE of the conversion alone: on the 24 chart patches it is fitted on (training) / on the "
            f"{lib['samples']} samples of `{lib['library']}` under the same light (held out); mean (95th percentile). "
            "The paper scores only the training set.", "",
            _table(["design"] + [f"{t} K" for t in temps], rows), ""]


def write_paper_outputs(out_dir: str | Path, results: dict, cases: dict, cubes: dict | None, command: str,
                        step: Callable[[str], object] = lambda msg: None, save_cubes: bool = False) -> list[Path]:
    """Figures, results.json, report.md, and every case's raw and rendered EXR; the spectral radiance
    cubes (30 bands, ~37 MB each at 640x480) only with ``save_cubes`` — they are in the render cache.

    Parameters
    ----------
    out_dir : str or Path
        The output directory; case files go under ``cases/LIGHT/DESIGN/``.
    results : dict
        The run's results (with ``command``).
    cases : dict
        :func:`~spectracam.experiments.paper.experiment.comparison`'s cases.
    cubes : dict or None
        Light label → ``(scene, cube)``, written only with ``save_cubes``.
    command : str
        The command, for report.md.
    step : callable
        ``step(line)`` after the summary files and after the case files.
    save_cubes : bool
        Also write each light's radiance cube (``cases/LIGHT/radiance.exr``).

    Returns
    -------
    list of Path
        The figures (PNG and SVG), results.json and report.md (the case files are not listed).
    """
    from spectracam.io.exr import write_radiance_exr, write_raw_exr
    from spectracam.io.report import write_rendered_exr

    out = Path(out_dir)
    paths = []
    for name, make in (("fig4", figures.fig4), ("fig5", figures.fig5), ("fig6", figures.fig6)):
        paths += save_figure(make(results), out / f"{name}.png", out / f"{name}.svg", tight=False)
    paths.append(atomic_write(out / "results.json", json.dumps(results, indent=1, allow_nan=False).encode()))
    paths.append(atomic_write(out / "report.md", report_markdown(results, command).encode()))
    step("figures, results.json and report.md written")
    for key, (scene, cube) in (cubes or {}).items() if save_cubes else ():
        write_radiance_exr(out / "cases" / key / "radiance.exr", cube)
    for (key, design), c in cases.items():
        items = ([(design.replace("/", "-"), c["raw"], c["score"])] if design != "budget" else
                 [(f"budget-{i}", raw, res) for i, (_, _, raw, res) in enumerate(c)])
        for name, raw, res in items:
            write_raw_exr(out / "cases" / key / name / "raw.exr", raw)
            write_rendered_exr(out / "cases" / key / name / "rendered.exr", res)
    step("case files written")
    return paths
