"""EMVA 1288 (Release 4.0, linear sensors) measured on the simulated camera: a datasheet.

The camera's sensor is lit uniformly by monochromatic light at one wavelength through one colour
channel's filter (default: green, at 540 nm), and measured as the standard prescribes: a photon-
transfer series of frame pairs from dark to beyond saturation, varying the exposure time at
constant irradiance, with a dark pair at every exposure time; and stacks of dark and ~50 %-bright
frames for the spatial non-uniformities.  :mod:`spectracam.evaluation.emva1288` analyses them; the configured
block holds what the standard's definitions give for the configured camera, so every measured
quantity can be held against it.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, TypedDict

import numpy as np

from spectracam.camera import CameraSpec
from spectracam.core.errors import ConfigError, SpectracamError
from spectracam.evaluation.emva1288 import LINEARITY_FIT_RANGE, SENSITIVITY_FIT_MAX, EmvaSeries, analyse, expected
from spectracam.architecture.filters import CHANNELS, responsivities
from spectracam.sensor import dark_gain_moments, fixed_pattern, noise_stream, read_frame
from spectracam.core.spectra import WavelengthGrid
from spectracam.io.plots import OKABE_ITO

if TYPE_CHECKING:
    from pathlib import Path

    from matplotlib.figure import Figure

__all__ = ["EMVA_STREAM", "KEYS", "LABELS", "LINEARITY_CLAUSE", "ROLES", "SATURATION_CLAUSE",
           "SENSITIVITY_CLAUSE", "EmvaResult", "EmvaSetup", "channel_qe", "configured", "datasheet_markdown", "figures",
           "point_roles", "run_emva", "simulate_series", "write_emva_outputs"]

#: The quantities of the datasheet, in the order EMVA 1288 lists them.
KEYS = ("system_gain_DN_per_e", "quantum_efficiency", "dark_noise_e", "saturation_capacity_e", "snr_max_db",
        "dynamic_range_db", "dark_current_e_per_s", "dsnu_e", "prnu_percent", "linearity_error_percent")
EMVA_STREAM = 10


@dataclass(frozen=True)
class EmvaSetup:
    """How the measurement is taken (the standard's minimums where it sets one)."""

    channel: str = "G"
    wavelength_nm: float = 540.0
    #: Frame size, px: 256 × 256 = 65536 pixels a frame (σ of a variance ±0.6 %).
    width: int = 256
    height: int = 256
    #: Photon-transfer steps, dark to 110 % of saturation (the standard: at least 50).
    steps: int = 60
    #: Frames in each spatial stack (the standard recommends 100; the σ²/L correction handles fewer).
    spatial_frames: int = 16
    #: Time to fill the well at the chosen irradiance, s: long enough that the dark current is
    #: measured over the series (1000 e⁻/s × 5 s = 5000 e⁻ for the default pixel).
    saturation_time_s: float = 5.0
    seed: int = 0


def channel_qe(camera: CameraSpec, channel: str, wavelength_nm: float) -> float:
    """η at one wavelength: the channel's filter × QE (electrons per photon).

    Parameters
    ----------
    camera : CameraSpec
        Its filters.
    channel : str
        ``"R"``, ``"G"`` or ``"B"``.
    wavelength_nm : float
        nm.

    Returns
    -------
    float
        e⁻/photon.
    """
    grid = WavelengthGrid([wavelength_nm - 0.1, wavelength_nm, wavelength_nm + 0.1])
    return float(responsivities(camera.filters, grid)[CHANNELS.index(channel), 1])


def simulate_series(camera: CameraSpec, setup: EmvaSetup = EmvaSetup()) -> tuple[EmvaSeries, dict]:
    """The frames of the measurement, taken with one physical sensor (one fixed pattern).

    Parameters
    ----------
    camera : CameraSpec
        Its sensor, read ``single``.
    setup : EmvaSetup

    Returns
    -------
    series : EmvaSeries
        Bright and dark pairs at every step (DN), the spatial stacks and the photons per pixel μ_p.
    info : dict
        ``eta`` (e⁻/photon) and ``photons_per_s`` (per pixel).

    Raises
    ------
    SpectracamError
        For another read-out, a non-finite wavelength, or a channel that does not respond there.
    """
    s = camera.sensor
    if s.readout != "single":
        raise SpectracamError(f"sensor.readout = {s.readout!r}: EMVA 1288 Linear's photon transfer needs a read-out "
                              "whose variance is linear in its signal (the 'single' read); spectracam datasheet measures "
                              "every read-out by EMVA 1288 General")
    import math

    if not (isinstance(setup.wavelength_nm, (int, float)) and math.isfinite(setup.wavelength_nm)):
        raise SpectracamError(f"--wavelength = {setup.wavelength_nm!r}: must be a finite wavelength in nm")
    eta = channel_qe(camera, setup.channel, setup.wavelength_nm)
    if not eta > 0:
        lam = np.arange(300.0, 1101.0)
        R = responsivities(camera.filters, WavelengthGrid(lam))[CHANNELS.index(setup.channel)]
        hint = (f"it responds most at {lam[int(np.argmax(R))]:g} nm; pass --wavelength there" if R.max() > 0 else
                "it responds nowhere in 300–1100 nm; check the filters")
        raise SpectracamError(f"--channel = {setup.channel!r}: does not respond at --wavelength {setup.wavelength_nm:g} "
                              f"nm (filter × QE = 0 there), so EMVA 1288 cannot light it; {hint}")
    shape = (setup.height, setup.width)
    pattern = fixed_pattern(s, shape, setup.seed, 0)
    photons_per_s = s.q_max_e / (eta * setup.saturation_time_s)  # μ_p per second at this irradiance
    rate = np.full(shape, eta * photons_per_s, np.float32)
    zero = np.zeros(shape, np.float32)
    times = np.linspace(0.0, 1.1 * setup.saturation_time_s, setup.steps)
    times[0] = 1e-6  # a dark-most step with a finite exposure

    def frame(r, t, *stream):
        return read_frame(r, t, s, noise_stream(setup.seed, EMVA_STREAM, *stream), pattern)[0]

    bright = np.stack([[frame(rate, t, 0, i, j) for j in range(2)] for i, t in enumerate(times)])
    dark = np.stack([[frame(zero, t, 1, i, j) for j in range(2)] for i, t in enumerate(times)])
    t50 = 0.5 * setup.saturation_time_s
    spatial_dark = np.stack([frame(zero, t50, 2, j) for j in range(setup.spatial_frames)])
    spatial_bright = np.stack([frame(rate, t50, 3, j) for j in range(setup.spatial_frames)])
    series = EmvaSeries(wavelength_nm=setup.wavelength_nm, pixel_area_um2=s.pixel_area_um2,
                        exposure_times_s=times, mu_p=photons_per_s * times, bright_pairs=bright, dark_pairs=dark,
                        max_dn=2.0**s.adc_bits - 1, spatial_dark=spatial_dark, spatial_bright=spatial_bright,
                        spatial_mu_p=photons_per_s * t50, spatial_exposure_time_s=t50)
    return series, {"eta": eta, "photons_per_s": photons_per_s}


def configured(camera: CameraSpec, setup: EmvaSetup, photons_per_s: float, eta: float) -> dict:
    """The standard's quantities for the configured camera (see :func:`spectracam.evaluation.emva1288.expected`).

    Parameters
    ----------
    camera : CameraSpec
    setup : EmvaSetup
        Its saturation time, s (the spatial stacks' exposure is half of it).
    photons_per_s : float
        Photons per pixel per second at the measurement's irradiance.
    eta : float
        e⁻/photon.

    Returns
    -------
    dict
        :func:`~spectracam.evaluation.emva1288.expected`'s.
    """
    s = camera.sensor
    t50 = 0.5 * setup.saturation_time_s
    dark = s.dark_rate_e_per_s
    # DSNU1288: the spatial spread of the dark signal at the spatial stack's exposure, e⁻ —
    # offset FPN (pixel and column) and the dark current's non-uniformity
    dsnu = np.sqrt((s.fpn_rms_e if s.fpn else 0.0) ** 2 + (s.column_fpn_fraction * s.q_max_e if s.fpn else 0.0) ** 2
                   + dark_gain_moments(s)[1] * (dark * t50) ** 2)
    return expected(gain_DN_per_e=s.system_gain_dn_per_e, quantum_efficiency=eta,
                    read_noise_e=s.read_noise_rms_e, dark_current_e_per_s=dark,
                    dsnu_e=float(dsnu), prnu_fraction=s.prnu_fraction if s.fpn else 0.0, full_well_e=s.q_max_e,
                    adc_bits=s.adc_bits, black_level_DN=s.black_level_dn - 0.5,  # the ADC floors: round(x − ½)
                    series_photon_rate_per_s=photons_per_s)


def _in_camera_terms(e) -> str:
    """What an analysis refusal means for the simulated camera."""
    if e.value == "first step":
        return "even its darkest exposure step has more than 0.2 % of pixels at the top code"
    if e.value == "saturation signal":
        return "no exposure step rises above the dark level"
    return "its frames do not give the photon-transfer series the standard analyses"


class EmvaResult(TypedDict):
    """What :func:`run_emva` returns, emva.json's keys but ``command``: the datasheet's quantities (:data:`KEYS`)
    configured and measured (None where undefined), notes on them, the fits the plots draw, the set-up, the
    camera, and the measured curves (a step without temporal noise has a NaN SNR; the writer makes it null)."""

    configured: dict[str, float | None]
    measured: dict[str, float | None]
    notes: dict[str, bool | str]
    fit: dict[str, float | str]
    setup: dict[str, str | int | float]
    camera: dict
    curves: dict[str, list[float]]


def run_emva(camera: CameraSpec, setup: EmvaSetup = EmvaSetup()) -> EmvaResult:
    """Measure and analyse; ``{"configured", "measured", "setup", "camera", "curves"}``.

    Parameters
    ----------
    camera : CameraSpec
    setup : EmvaSetup

    Returns
    -------
    EmvaResult
        emva.json's keys but ``command``.

    Raises
    ------
    SpectracamError
        When the series cannot be analysed as EMVA 1288 prescribes (named in the camera's terms).
    """
    series, info = simulate_series(camera, setup)
    try:
        measured = analyse(series)
    except ConfigError as e:  # the analysis's own terms ("bright_pairs = 'first step'") → the camera's
        raise SpectracamError(f"emva: this camera cannot be measured as EMVA 1288 prescribes: {_in_camera_terms(e)} "
                              f"(analysis: {e.field} = {e.value!r}: {e.allowed}); check the [sensor] table (black "
                              "level, FPN, dark current, ADC range)") from None
    conf = configured(camera, setup, info["photons_per_s"], info["eta"])
    pick = lambda d: {k: (None if d[k] is None or not np.isfinite(d[k]) else float(d[k])) for k in KEYS}  # noqa: E731
    d = measured["details"]
    return {"configured": pick(conf), "measured": pick(measured),
            "notes": {"dark_noise_is_upper_limit": bool(conf["details"]["dark_noise_is_upper_limit"]),
                      "saturation_method": conf["details"]["saturation_method"]},
            # what the plots draw besides the curves: the fits and the saturation point
            "fit": {**{k: float(d[k]) for k in ("ptc_offset_DN2", "mu_p_sat", "mu_y_sat_minus_dark_DN",
                                                "linearity_fit_offset_DN", "linearity_fit_slope_DN_per_photon")},
                    "saturation_method": d["saturation_method"]},
            "setup": {**setup.__dict__}, "camera": camera.to_dict(),
            "curves": {k: np.asarray(v).tolist() for k, v in measured.get("curves", {}).items()
                       if np.ndim(v) == 1}}


LABELS = {"system_gain_DN_per_e": ("system gain K", "DN/e⁻", "{:.5g}"),
          "quantum_efficiency": ("quantum efficiency η", "", "{:.4f}"),
          "dark_noise_e": ("temporal dark noise σ_d", "e⁻", "{:.2f}"),
          "saturation_capacity_e": ("saturation capacity μ_e.sat", "e⁻", "{:.0f}"),
          "snr_max_db": ("SNR_max", "dB", "{:.2f}"),
          "dynamic_range_db": ("dynamic range", "dB", "{:.2f}"),
          "dark_current_e_per_s": ("dark current", "e⁻/s", "{:.1f}"),
          "dsnu_e": ("DSNU1288", "e⁻", "{:.1f}"),
          "prnu_percent": ("PRNU1288", "%", "{:.3f}"),
          "linearity_error_percent": ("linearity error LE", "%", "{:.4f}")}


def _fmt(fmt: str, v) -> str:
    return "–" if v is None else fmt.format(v)


def datasheet_markdown(result: dict, command: str) -> str:
    """The EMVA 1288 datasheet of the simulated camera: configured beside measured.

    Parameters
    ----------
    result : dict
        :func:`run_emva`'s.
    command : str
        The command, recorded at the top.

    Returns
    -------
    str
        datasheet.md's text.
    """
    c, m, st = result["configured"], result["measured"], result["setup"]
    lines = ["# EMVA 1288 datasheet of the simulated camera", "",
             f"Made by `{command}`. Release 4.0, linear sensors; channel {st['channel']} at {st['wavelength_nm']:g} nm, "
             f"{st['width']}×{st['height']} px, {st['steps']} photon-transfer steps (exposure time varied, dark pair "
             f"at each), spatial stacks of {st['spatial_frames']} frames, seed {st['seed']}.", "",
             "| quantity | unit | configured | measured | difference |", "|---|---|---|---|---|"]
    for k in KEYS:
        name, unit, fmt = LABELS[k]
        d = "–" if (c[k] in (None, 0) or m[k] is None) else f"{100 * (m[k] / c[k] - 1):+.2f} %"
        lines.append(f"| {name} | {unit} | {_fmt(fmt, c[k])} | {_fmt(fmt, m[k])} | {d} |")
    notes = result["notes"]
    lines += ["", "Configured: what the standard's definitions give for the configured camera (the saturation by "
              f"its 0.1–0.2 % rule: {notes['saturation_method']})."]
    if notes["dark_noise_is_upper_limit"]:
        lines.append("The dark variance is below 0.24 DN² (quantisation-limited), so the standard gives only an upper "
                     "limit for σ_d, 0.40/K, in both columns.")
    lines += ["", "![photon transfer](photon_transfer.png) ![SNR](snr.png) ![linearity](linearity.png)", "",
              "In the plots, filled dots are the steps a fit used; hollow orange circles the steps below saturation "
              "that the standard leaves out of it (photon transfer and SNR: above 70 % of saturation, §6.6; "
              "linearity: outside 5–95 %, §6.9) and grey crosses the steps beyond saturation.", ""]
    return "\n".join(lines)


#: Why a plot leaves a step out of its fit: the clauses of EMVA 1288 Release 4.0 Linear (section numbers
#: as in :mod:`spectracam.evaluation.emva1288`).  Each plot draws the steps its fit used as filled dots, the steps
#: below saturation outside its fit range as hollow orange circles and the steps beyond saturation as
#: grey crosses, each excluded kind with a legend entry "excluded from the fit (EMVA 1288 …)".
SENSITIVITY_CLAUSE = f"EMVA 1288 §6.6: above {100 * SENSITIVITY_FIT_MAX:.0f} % of saturation"
LINEARITY_CLAUSE = (f"EMVA 1288 §6.9: outside {100 * LINEARITY_FIT_RANGE[0]:.0f}–{100 * LINEARITY_FIT_RANGE[1]:.0f} "
                    "% of saturation")
SATURATION_CLAUSE = "EMVA 1288 §6.5: beyond saturation"
#: The roles a step can have in a plot, in drawing order, and the ``gid`` of their matplotlib artists.
ROLES = ("fit", "excluded", "beyond_saturation")


def point_roles(curves: dict) -> dict:
    """``{figure: {role: mask}}``: boolean masks over the photon-transfer steps for each figure, taken
    from the analysis's own masks (:func:`spectracam.evaluation.emva1288.analyse` ``curves``).  ``"fit"``: the
    steps the figure's fit used (photon transfer and SNR: the 0–70 % range of K and η, which the SNR
    model curve is drawn with; linearity: 5–95 %); ``"excluded"``: the other steps up to saturation;
    ``"beyond_saturation"``: the steps past the saturation point, which no fit uses.

    Parameters
    ----------
    curves : dict
        The result's ``curves`` (its fit masks).

    Returns
    -------
    dict
        ``photon_transfer``, ``snr``, ``linearity`` → ``fit``, ``excluded``, ``beyond_saturation`` boolean arrays.
    """
    beyond = np.asarray(curves["beyond_saturation_mask"], bool)
    out = {}
    for name, key in (("photon_transfer", "sensitivity_fit_mask"), ("snr", "sensitivity_fit_mask"),
                      ("linearity", "linearity_fit_mask")):
        fit = np.asarray(curves[key], bool) & ~beyond
        out[name] = {"fit": fit, "excluded": ~fit & ~beyond, "beyond_saturation": beyond}
    return out


def _saturation_label(fit: dict) -> str:
    how = ("0.1–0.2 % of pixels at the top code" if fit["saturation_method"] == "pixel_fraction"
           else "maximum of the temporal variance")
    return f"saturation ({how})"


def _draw_steps(ax, x, y, roles, fit_label, clause, shown=None, off_scale=None):
    """The steps of one plot by role; ``shown``: the steps the axes can show (a log axis drops ≤ 0);
    ``off_scale``: −1/+1 for steps drawn at the bottom/top edge (their y already clipped there)."""
    n = len(x)
    shown = np.ones(n, bool) if shown is None else shown
    off = np.zeros(n, int) if off_scale is None else off_scale
    style = {"fit": dict(marker="o", ms=3.5, color=OKABE_ITO[0], label=fit_label),
             "excluded": dict(marker="o", ms=4.5, mfc="none", mew=1.1, color=OKABE_ITO[4],
                              label=f"excluded from the fit ({clause})"),
             "beyond_saturation": dict(marker="x", ms=4.5, mew=1.1, color="0.4",
                                       label=f"excluded from the fit ({SATURATION_CLAUSE})")}
    for role in ROLES:
        m = roles[role] & shown
        on, edge = m & (off == 0), m & (off != 0)
        if on.any():
            ax.plot(x[on], y[on], ls="none", gid=role, **style[role])
        for sign, marker in ((-1, "v"), (1, "^")):
            e = edge & (off == sign)
            if e.any():
                kw = {k: v for k, v in style[role].items() if k not in ("marker", "label")}
                ax.plot(x[e], y[e], ls="none", marker=marker, gid=f"{role}_off_scale", clip_on=False,
                        label=None if on.any() else style[role]["label"], **kw)


def figures(result: dict) -> dict[str, Figure]:
    """``{name: figure}``: photon transfer, SNR and linearity, as the standard draws them, with the
    steps each fit left out marked (:func:`point_roles`).

    Parameters
    ----------
    result : dict
        :func:`run_emva`'s (its ``curves`` and ``fit``).

    Returns
    -------
    dict of str to matplotlib.figure.Figure
        Three figures, by file name.
    """
    from spectracam.io.plots import pyplot

    plt = pyplot()
    cv = result["curves"]
    fit = result["fit"]
    mu_y, var_y = np.asarray(cv["mu_y"]), np.asarray(cv["var_y"])
    mu_d, var_d = np.asarray(cv["mu_y_dark"]), np.asarray(cv["var_y_dark"])
    mu_p = np.asarray(cv["mu_p"])
    signal, excess = mu_y - mu_d, var_y - var_d
    roles = point_roles(cv)
    K = result["measured"]["system_gain_DN_per_e"]
    sat = dict(color="0.35", ls=":", lw=1.0, label=_saturation_label(fit))
    out = {}
    out["photon_transfer"] = _photon_transfer_figure(plt, fit, roles["photon_transfer"], signal, excess, K, sat)
    out["snr"] = _snr_figure(plt, cv, fit, roles["snr"], mu_p, sat)
    out["linearity"] = _linearity_figure(plt, cv, fit, roles["linearity"], mu_p, signal, sat)
    return out


def _photon_transfer_figure(plt, fit: dict, r: dict, signal, excess, K: float, sat: dict):
    """The photon transfer curve: the variance's excess over dark against the signal, and its fit."""
    fig, ax = plt.subplots(figsize=(6, 4.3))
    _draw_steps(ax, signal, excess, r, f"fit range (0–{100 * SENSITIVITY_FIT_MAX:.0f} % of saturation)",
                SENSITIVITY_CLAUSE)
    x = np.array([0, signal[r["fit"]].max()])
    ax.plot(x, K * x + fit["ptc_offset_DN2"], "-", color=OKABE_ITO[1], label=f"fit: slope K = {K:.4g} DN/e⁻")
    ax.axvline(fit["mu_y_sat_minus_dark_DN"], **sat)
    ax.set_xlabel("μ_y − μ_y.dark (DN)")
    ax.set_ylabel("σ²_y − σ²_y.dark (DN²)")
    ax.set_title("Photon transfer", fontsize=10)
    ax.legend(fontsize=7, loc="upper left")
    ax.grid(alpha=0.3)
    return fig


def _snr_figure(plt, cv: dict, fit: dict, r: dict, mu_p, sat: dict):
    """The SNR against the photons per pixel: measured, the EMVA 1288 model and the ideal sensor."""
    fig, ax = plt.subplots(figsize=(6, 4.3))
    snr = np.asarray(cv["snr"], float)
    shown = (mu_p >= 0.5 * mu_p[mu_p > 0][1]) & np.isfinite(snr) & (snr > 0)  # the first step is dark
    ax.set_xscale("log")
    ax.set_yscale("log")
    _draw_steps(ax, mu_p, snr, r, "measured (the steps K and η are fitted on)", SENSITIVITY_CLAUSE,
                shown=shown)
    ax.plot(mu_p[shown], np.asarray(cv["snr_model"])[shown], "-", color=OKABE_ITO[1], label="EMVA 1288 model")
    ax.plot(mu_p[shown], np.asarray(cv["snr_ideal"])[shown], "--", color="0.5", label="ideal sensor")
    ax.axvline(fit["mu_p_sat"], **sat)
    ax.set_xlabel("μ_p (photons per pixel)")
    ax.set_ylabel("SNR")
    ax.set_title("Signal-to-noise ratio", fontsize=10)
    ax.legend(fontsize=7, loc="upper left")
    ax.grid(alpha=0.3, which="both")
    return fig


def _linearity_figure(plt, cv: dict, fit: dict, r: dict, mu_p, signal, sat: dict):
    """Linearity: the signal and its weighted fit above, the deviation from the fit below."""
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(6, 6.4), sharex=True, height_ratios=(1, 1))
    a0, a1 = fit["linearity_fit_offset_DN"], fit["linearity_fit_slope_DN_per_photon"]
    fit_label = f"fit range ({100 * LINEARITY_FIT_RANGE[0]:.0f}–{100 * LINEARITY_FIT_RANGE[1]:.0f} % of saturation)"
    _draw_steps(top, mu_p, signal, r, fit_label, LINEARITY_CLAUSE)
    xs = np.array([0.0, mu_p.max()])
    top.plot(xs, a0 + a1 * xs, "-", color=OKABE_ITO[1], lw=1, label="fit (weights 1/y², EMVA 1288 §6.9)")
    top.axvline(fit["mu_p_sat"], **sat)
    top.set_ylabel("μ_y − μ_y.dark (DN)")
    top.set_title("Linearity", fontsize=10)
    top.grid(alpha=0.3)
    _draw_deviation(bottom, cv, fit, r, mu_p, fit_label)
    handles, labels = top.get_legend_handles_labels()
    for h, label in zip(*bottom.get_legend_handles_labels()):  # the off-scale entry; the roles are above
        if label not in labels:
            handles.append(h)
            labels.append(label)
    fig.legend(handles, labels, fontsize=7, loc="upper center", bbox_to_anchor=(0.5, 0.02), ncol=1)
    bottom.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def _draw_deviation(ax, cv: dict, fit: dict, r: dict, mu_p, fit_label: str) -> None:
    """The deviation from the linear fit, on the fit range's scale; steps beyond it drawn at the edge."""
    dev = np.asarray(cv["linearity_deviation_percent"], float)
    ok = np.isfinite(dev)
    lim = 3.0 * float(np.abs(dev[r["fit"] & ok]).max() or 1.0)  # the fit range's scale: LE is read here
    off = np.where(ok & (dev > lim), 1, np.where(ok & (dev < -lim), -1, 0))
    _draw_steps(ax, mu_p, np.clip(dev, -lim, lim), r, fit_label, LINEARITY_CLAUSE, shown=ok, off_scale=off)
    if off.any():
        ax.plot([], [], ls="none", marker="v", color="0.4", mfc="none",
                label=f"off scale (|δ| > {lim:.2g} %): drawn at the edge")
    ax.axhline(0, color="0.5", lw=0.8)
    ax.axvline(fit["mu_p_sat"], color="0.35", ls=":", lw=1.0)
    ax.set_ylim(-1.08 * lim, 1.08 * lim)
    ax.set_xlabel("μ_p (photons per pixel)")
    ax.set_ylabel("deviation from the linear fit δ_y (%)")


def write_emva_outputs(out_dir: str | Path, result: dict, command: str) -> list:
    """emva.json, datasheet.md and the three figures (PNG + SVG), atomically.

    Parameters
    ----------
    out_dir : str or Path
    result : dict
        :func:`run_emva`'s (NaN written as null).
    command : str

    Returns
    -------
    list of Path
        The files written.
    """
    import json
    from pathlib import Path

    from spectracam.core.files import atomic_write
    from spectracam.io.plots import save_figure

    out = Path(out_dir)
    paths = []
    for name, fig in figures(result).items():
        paths += save_figure(fig, out / f"{name}.png", out / f"{name}.svg")
    # a step with no temporal noise has no SNR (NaN): JSON has no NaN, so it is written as null
    curves = {k: [None if isinstance(x, float) and not np.isfinite(x) else x for x in v]
              for k, v in result["curves"].items()}
    payload = {k: v for k, v in result.items() if k != "curves"} | {"command": command, "curves": curves}
    paths.append(atomic_write(out / "emva.json", json.dumps(payload, indent=1, allow_nan=False).encode()))
    paths.append(atomic_write(out / "datasheet.md", datasheet_markdown(result, command).encode()))
    return paths
