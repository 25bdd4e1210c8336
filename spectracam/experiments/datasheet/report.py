"""The datasheet's files: ``datasheet.md`` (a sensor engineer's datasheet), ``results.json`` (every number, the
parameters and the command) and ``snr.png``/``snr.svg`` (every read-out's SNR curve, measured and closed-form)."""
from __future__ import annotations

import json
import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["datasheet_markdown", "snr_figure", "write_datasheet_outputs"]


def _f(v, fmt: str = "{:.4g}") -> str:
    return "–" if v is None or (isinstance(v, float) and not math.isfinite(v)) else fmt.format(v)


def _sensor_rows(s: dict) -> list[str]:
    return ["| full well | e⁻ | " + _f(s["full_well_e"], "{:.0f}") + " |",
            "| read noise (at the conversion gain " + _f(s["conversion_gain_uV_per_e"]) + " µV/e⁻) | e⁻ rms | "
            + _f(s["read_noise_e"], "{:.2f}") + " |",
            f"| dark current at {s['temperature_C']:g} °C ({s['dark_current_law']} law) | e⁻/s | "
            + _f(s["dark_current_e_per_s"], "{:.4g}") + " |",
            "| pixel pitch (fill factor " + _f(s["fill_factor"]) + ") | µm | " + _f(s["pixel_pitch_um"]) + " |",
            "| ADC | bits | " + str(s["adc_bits"]) + " |",
            "| system gain K | DN/e⁻ | " + _f(s["system_gain_DN_per_e"], "{:.5g}") + " |",
            "| offset FPN | e⁻ rms | " + _f(s["fpn_rms_e"], "{:.1f}") + " |",
            "| hot pixels | fraction | " + _f(s["hot_pixel_fraction"]) + " |",
            "| configured read-out | | " + s["readout"] + " |"]


def _readout_rows(readouts: dict) -> list[str]:
    rows = ["| read-out | saturation (e⁻) | SNR = 1 threshold (e⁻) | DR | DR (dB) | SNR_max (dB) | SNR 10 at (e⁻) |",
            "|---|---|---|---|---|---|---|"]
    for name, r in readouts.items():
        rows.append(f"| {name} | {_f(r['saturation_e'], '{:.0f}')} | {_f(r['threshold_e'], '{:.1f}')} | "
                    f"{_f(r['dynamic_range'], '{:.0f}')} | {_f(r['dynamic_range_db'], '{:.1f}')} | "
                    f"{_f(r['snr_max_db'], '{:.1f}')} | {_f(r['snr10_e'], '{:.0f}')} |")
    return rows


def _sensitivity_rows(p: dict, iso: dict, spec: dict) -> list[str]:
    t = iso["exposure_time_s"]
    cond = f"{iso['channel']} channel, {p['light']}, {_f(t * 1000, '{:.1f}')} ms"
    scene = (f"{100 * p['reflectance']:g} % grey, f/{p['f_number']:g}, T = {p['transmittance']:g} "
             f"({p['irradiance_form']})")
    return [f"| SNR 1 illuminance at the sensor ({cond}) | lux | {_f(iso['snr1_sensor_lux'])} |",
            f"| SNR 10 illuminance at the sensor ({cond}) | lux | {_f(iso['snr10_sensor_lux'])} |",
            f"| SNR 1 illuminance at the scene ({scene}) | lux | {_f(iso['snr1_scene_lux'])} |",
            f"| SNR 10 illuminance at the scene ({scene}) | lux | {_f(iso['snr10_scene_lux'])} |",
            f"| ISO 12232 saturation speed S_sat = 78/H_sat (H_sat {_f(iso['H_sat_lux_s'])} lux·s) | | "
            f"{_f(iso['S_sat'], '{:.0f}')} |",
            f"| ISO 12232 noise speed S_noise40 = 10/H_SNR40 (\"excellent\") | | {_f(iso['S_noise40'], '{:.0f}')} |",
            f"| ISO 12232 noise speed S_noise10 = 10/H_SNR10 (\"acceptable\") | | {_f(iso['S_noise10'], '{:.0f}')} |"]


def _colour_rows(smi: dict, chart: dict) -> list[str]:
    rows = [f"| ISO 17321-1 SMI ({smi['illuminant']}, {smi['patches']}, ΔE-optimal white-preserving matrix) | | "
            f"{_f(smi['smi'], '{:.1f}')} |",
            f"| SMI with the least-squares white-preserving matrix | | {_f(smi['smi_least_squares'], '{:.1f}')} |",
            f"| chart ΔE*ab, per-pixel mean ({chart['illuminant']}) | | {_f(chart['delta_e_ab_mean'], '{:.2f}')} |",
            f"| chart CIEDE2000, per-pixel mean | | {_f(chart['delta_e2000_mean'], '{:.2f}')} |",
            f"| chart ΔE*ab of the patches' mean colours | | {_f(chart['delta_e_ab_of_mean'], '{:.2f}')} |",
            f"| chart CIEDE2000 of the patches' mean colours | | {_f(chart['delta_e2000_of_mean'], '{:.2f}')} |"]
    for name, v in chart["visual_noise"].items():
        rows.append(f"| ISO 15739 visual noise, {name} | | {_f(v['visual_noise'], '{:.2f}')} |")
    return rows


def datasheet_markdown(result: dict, command: str) -> str:
    """The datasheet as Markdown: the sensor's configured figures, every read-out's EMVA 1288 figures, the
    photometric sensitivity and ISO speeds, the colour figures, and how each was made.

    Parameters
    ----------
    result : dict
        :func:`~spectracam.experiments.datasheet.experiment.run_datasheet`'s.
    command : str
        The command, recorded at the top.

    Returns
    -------
    str
        datasheet.md's text.
    """
    p, spec = result["parameters"], result["parameters"]
    lines = ["# Sensor datasheet of the simulated camera", "",
             f"Made by `{command}`; seed {spec['seed']}, frames of {48 if spec['quick'] else 128} × "
             f"{48 if spec['quick'] else 128} px. Every figure's definition is in docs/metrics.md (\"Sensor "
             "datasheet\").", "", "## Sensor", "", "| figure | unit | value |", "|---|---|---|",
             *_sensor_rows(result["sensor"]), "",
             "## Dynamic range and SNR per read-out (EMVA 1288 Release 4.0 General)", "",
             f"Photon-transfer series at {_f(spec['exposure_time_s'] * 1000, '{:.1f}')} ms, irradiance stepped "
             "logarithmically, frame pairs (temporal noise) in linearised electrons; DR = μ_sat/μ_min with μ_min at "
             f"SNR = 1. Photons per pixel are μ_e/η with η = {_f(p['eta'])} ({spec['channel']} channel at "
             f"{spec['wavelength_nm']:g} nm).", "", *_readout_rows(result["readouts"]), "",
             "![SNR](snr.png)", "", "## Sensitivity (ISO 12232)", "", "| figure | unit | value |", "|---|---|---|",
             *_sensitivity_rows(result["photometry"], result["iso12232"], spec), "",
             "## Colour and visual noise", "", "| figure | unit | value |", "|---|---|---|",
             *_colour_rows(result["smi"], result["chart"]), ""]
    lines += [f"Visual noise: the chart's grey patches rendered by the configured camera, viewed at "
              f"{_f(result['chart']['samples_per_degree'], '{:.1f}')} pixels per degree."]
    lines += ["", *[f"- {n}" for n in result["notes"]], ""] if result["notes"] else [""]
    return "\n".join(lines) + "\n"


def snr_figure(result: dict) -> Figure:
    """Every read-out's SNR against photons per pixel on one log–log plot: measured (dots), closed form (line).

    Parameters
    ----------
    result : dict
        A datasheet result: each read-out's ``curve`` and ``saturation_e``.

    Returns
    -------
    matplotlib.figure.Figure
        Points above saturation left out.
    """
    from spectracam.io.plots import pyplot

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    for i, (name, r) in enumerate(result["readouts"].items()):
        color = f"C{i}"
        x, y = np.asarray(r["curve"]["photons"], float), np.asarray(r["curve"]["snr"], float)
        sig = np.asarray(r["curve"]["signal_e"], float)
        ok = (x > 0) & np.isfinite(y) & (y > 0) & (sig <= 1.0001 * r["saturation_e"])
        ax.plot(x[ok], y[ok], "o", ms=3, color=color, label=f"{name} (measured)", gid=f"measured_{name}")
        if r["curve"]["snr_model"] is not None:
            m = np.asarray(r["curve"]["snr_model"], float)
            okm = (x > 0) & np.isfinite(m) & (m > 0) & (sig <= 1.0001 * r["saturation_e"])
            ax.plot(x[okm], m[okm], "-", lw=1, color=color, label=f"{name} (closed form)", gid=f"model_{name}")
    ax.axhline(1.0, color="0.5", ls=":", lw=0.8)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("μ_p (photons per pixel)")
    ax.set_ylabel("SNR")
    ax.set_title("SNR per read-out (EMVA 1288 General)", fontsize=10)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, loc="upper left")
    return fig


def _clean(v):
    """JSON has no NaN or infinity: null."""
    if isinstance(v, float) and not math.isfinite(v):
        return None
    if isinstance(v, dict):
        return {k: _clean(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_clean(x) for x in v]
    if isinstance(v, np.generic):
        return _clean(v.item())
    return v


def write_datasheet_outputs(out_dir: str | Path, result: dict, command: str) -> list:
    """datasheet.md, results.json and snr.png/snr.svg, atomically.

    Parameters
    ----------
    out_dir : str or Path
    result : dict
        :func:`~spectracam.experiments.datasheet.experiment.run_datasheet`'s (NaN and infinities written as null).
    command : str
        Recorded in results.json and datasheet.md.

    Returns
    -------
    list of Path
        The files written.
    """
    from spectracam.core.files import atomic_write
    from spectracam.io.plots import save_figure

    out = Path(out_dir)
    paths = list(save_figure(snr_figure(result), out / "snr.png", out / "snr.svg"))
    payload = _clean({**result, "command": command})
    paths.append(atomic_write(out / "results.json", json.dumps(payload, indent=1, allow_nan=False).encode()))
    paths.append(atomic_write(out / "datasheet.md", datasheet_markdown(result, command).encode()))
    return paths
