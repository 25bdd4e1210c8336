"""``spectracam datasheet``: the figures a sensor datasheet quotes, computed from the simulated sensor (issue 36).

The run (spec → run → result): the configured sensor's own figures; a photon-transfer series through
:func:`spectracam.sensor.read_frame` for every read-out (EMVA 1288 *General*: SNR curve, SNR = 1 threshold,
saturation, dynamic range); the SNR 1 and SNR 10 illuminances at the sensor and at the scene and the ISO 12232
speeds under a stated light; ISO 17321-1's SMI; and, from the chart rendered by the configured camera, ISO 15739
visual noise of its grey patches and the chart's ΔE*ab and CIEDE2000.  The metric functions are
:mod:`spectracam.evaluation.datasheet`; the files are written by :mod:`.report`.
"""
from __future__ import annotations

import importlib.util
import math
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, TypedDict

import numpy as np

from spectracam.camera import CameraSpec
from spectracam.core.errors import SpectracamError
from spectracam.core.spectra import WavelengthGrid, cmf_band_weights, energy_to_photons
from spectracam.evaluation import datasheet as ds
from spectracam.sensor import (READOUT_NAMES, SensorSpec, adc_full_scale_dn, adc_inverse, fixed_pattern, noise_stream,
                               read_frame)

if TYPE_CHECKING:
    from spectracam.pipeline.scene_file import Scene

__all__ = ["DATASHEET_STREAM", "DatasheetResult", "DatasheetSpec", "available_readouts", "chart_figures",
           "measure_readout", "photometry", "run_datasheet", "sensor_figures", "smi_figures", "speeds"]

#: The noise stream of the datasheet's frames (beside the captures' and EMVA's).
DATASHEET_STREAM = 11
#: The wavelengths of the photometry and of the SMI, nm: 380–780 nm in 5 nm steps (ISO 17321-1's range).
GRID_NM = np.arange(380.0, 781.0, 5.0)


@dataclass(frozen=True)
class DatasheetSpec:
    """What the datasheet states: its light, exposure, object, lens (the camera's) and how it measures."""

    #: A few seconds: 48 × 48 px frames, 4 steps per decade (else 128 × 128 px, 8 per decade).
    quick: bool = False
    seed: int = 0
    #: The read-outs measured; None: every one (``sensor.readout`` set on the command line: that one).
    readouts: tuple | None = None
    #: The exposure time of the SNR 1/10 illuminances and of the photon-transfer series, s.
    exposure_time_s: float = 1.0 / 30.0
    #: The light of the photometric figures and the ISO speeds: CIE D65 (colour-science's SPD).
    light: str = "D65"
    #: The object of the scene-side illuminances: an 18 % grey (the mid-tone of ISO 12232 and ISO 2720).
    reflectance: float = 0.18
    #: The channel whose SNR the photometric figures and the noise speeds read (the luminance's proxy).
    channel: str = "G"
    #: EMVA 1288's monochromatic light: photons per pixel are μ_e/η at this wavelength through ``channel``.
    wavelength_nm: float = 540.0
    #: The SMI's fit (:func:`spectracam.evaluation.datasheet.smi_fit`).
    smi_fit: str = "delta_e"

    @property
    def size_px(self) -> int:
        return 48 if self.quick else 128

    @property
    def steps_per_decade(self) -> int:
        return 4 if self.quick else 8


class DatasheetResult(TypedDict):
    """What :func:`run_datasheet` returns, results.json's keys but ``command``."""

    parameters: dict
    sensor: dict
    readouts: dict
    photometry: dict
    iso12232: dict
    smi: dict
    chart: dict
    notes: list


def sensor_figures(sensor: SensorSpec) -> dict:
    """The configured sensor's own figures, as a datasheet lists them.

    Parameters
    ----------
    sensor : SensorSpec

    Returns
    -------
    dict
        Read-out, full well (e⁻), read noise (e⁻ rms), conversion gain (µV/e⁻), temperature (°C), dark current (e⁻/s)
        and its law, pixel pitch (µm), fill factor, ADC bits, system gain (DN/e⁻), black level (DN), hot-pixel
        fraction, FPN (e⁻ rms) and PRNU (%); FPN and PRNU 0 with the fixed pattern off.
    """
    return {"readout": sensor.readout, "full_well_e": sensor.q_max_e, "read_noise_e": sensor.read_noise_rms_e,
            "conversion_gain_uV_per_e": sensor.conversion_gain_uV_per_e, "temperature_C": sensor.temperature_C,
            "dark_current_e_per_s": sensor.dark_rate_e_per_s, "dark_current_law": sensor.dark_current_law,
            "pixel_pitch_um": sensor.pixel_pitch_um, "fill_factor": sensor.fill_factor, "adc_bits": sensor.adc_bits,
            "system_gain_DN_per_e": sensor.system_gain_dn_per_e, "black_level_DN": sensor.black_level_dn,
            "hot_pixel_fraction": sensor.hot_pixel_fraction, "fpn_rms_e": sensor.fpn_rms_e if sensor.fpn else 0.0,
            "prnu_percent": 100 * sensor.prnu_fraction if sensor.fpn else 0.0}


def available_readouts(requested: tuple | None) -> tuple[tuple, tuple]:
    """``(measured, not available)``: the read-outs asked for (None: all five) that this installation can read —
    every one but ``single`` needs :mod:`spectracam.sensor.readout`.

    Parameters
    ----------
    requested : tuple or None
        Read-out names; None: every one of ``READOUT_NAMES``.

    Returns
    -------
    tuple of (tuple, tuple)
        The names that can be measured here and those that cannot, each in the order asked.
    """
    names = tuple(READOUT_NAMES) if requested is None else tuple(requested)
    if importlib.util.find_spec("spectracam.sensor.readout") is not None:
        return names, ()
    return tuple(n for n in names if n == "single"), tuple(n for n in names if n != "single")


def _floor_e(sensor: SensorSpec, time_s: float) -> float:
    """The temporal noise floor in the dark, e⁻ rms: read, dark shot and quantisation noise."""
    q = 1.0 / (12 * sensor.system_gain_dn_per_e**2) if sensor.quantization else 0.0
    return math.sqrt(sensor.read_noise_rms_e**2 + sensor.dark_rate_e_per_s * time_s + q)


def _series(sensor: SensorSpec, spec: DatasheetSpec, index: int) -> dict:
    """The frames of a photon-transfer series at the spec's exposure time, the irradiance stepped logarithmically
    from a tenth of the noise floor until the output is clipped (two steps in a row with half the pixels at the top
    value or a mean within 0.5 % of the step before), in
    linearised electrons: ``{signal_e, var_e, top_fraction}`` per step."""
    shape, t = (spec.size_px, spec.size_px), spec.exposure_time_s
    pattern = fixed_pattern(sensor, shape, spec.seed, 0)
    top = adc_full_scale_dn(sensor)

    def frame(rate_e_per_s, *stream):
        d, _ = read_frame(np.full(shape, rate_e_per_s, np.float32), t, sensor,
                          noise_stream(spec.seed, DATASHEET_STREAM, index, *stream), pattern)
        return d

    dark = [adc_inverse(frame(0.0, 0, j), sensor) for j in range(2)]
    lo = max(0.01, 0.1 * _floor_e(sensor, t))
    bright, fractions, means, clipped, k = [], [], [], 0, 0
    while clipped < 2 and lo * 10 ** (k / spec.steps_per_decade) < 1e5 * sensor.q_max_e:
        mu = lo * 10 ** (k / spec.steps_per_decade)
        pair = [frame(mu / t, 1, k, j) for j in range(2)]
        fractions.append(float(np.mean([np.mean(d >= top) for d in pair])))
        bright.append([adc_inverse(d, sensor) for d in pair])
        means.append(float(np.mean(bright[-1])))
        flat = len(means) > 1 and means[-2] > 0 and abs(means[-1] / means[-2] - 1) < ds.PLATEAU_TOLERANCE / 2
        clipped = clipped + 1 if (fractions[-1] >= 0.5 or flat) else 0
        k += 1
    mu_e, var_e = ds.series_statistics(np.asarray(bright, np.float64), np.asarray(dark, np.float64))
    return {"signal_e": mu_e, "var_e": var_e, "top_fraction": np.asarray(fractions)}


def _model_snr(sensor: SensorSpec, signal_e: np.ndarray, time_s: float):
    """The read-out's closed-form SNR (:func:`spectracam.sensor.readout.snr_curve` where it exists; the linear
    model for ``single``), or None."""
    if sensor.readout == "single":
        k = sensor.system_gain_dn_per_e if sensor.quantization else None
        return ds.snr_model_linear(signal_e, sensor.read_noise_rms_e, sensor.dark_rate_e_per_s * time_s, k)
    try:
        from spectracam.sensor.readout import snr_curve
    except ImportError:
        return None
    return np.asarray(snr_curve(np.asarray(signal_e, float), sensor), float)


def measure_readout(sensor: SensorSpec, spec: DatasheetSpec, eta: float, index: int = 0) -> dict:
    """One read-out measured: its SNR curve (measured and closed-form), saturation, SNR = 1 threshold, dynamic
    range, SNR_max, and the signals of SNR 10 and 40; photons per pixel at ``eta`` (EMVA 1288's μ_p = μ_e/η).

    Parameters
    ----------
    sensor : SensorSpec
        With the read-out to measure.
    spec : DatasheetSpec
        Frame size, steps per decade, exposure time (s) and seed.
    eta : float
        Quantum efficiency at the spec's wavelength, e⁻/photon.
    index : int
        The read-out's noise stream (distinct per read-out).

    Returns
    -------
    dict
        Signals in e⁻ (and photons): ``saturation_e``, ``threshold_e``, ``snr1_e``/``snr10_e``/``snr40_e`` (None
        where never reached), ``dynamic_range`` (and dB), ``snr_max`` (and dB), and the ``curve``.
    """
    s = _series(sensor, spec, index)
    mu, var = s["signal_e"], s["var_e"]
    with np.errstate(divide="ignore", invalid="ignore"):
        snr = np.where(var > 0, mu / np.sqrt(np.maximum(var, 0)), np.nan)
    sat, how = ds.saturation_signal(mu, s["top_fraction"], var)
    below = mu <= sat * 1.0001
    cross = {lv: ds.snr_crossing(mu[below], snr[below], lv) for lv in (1.0, 10.0, 40.0)}
    dr, dr_db = ds.dynamic_range(sat, cross[1.0])
    model = _model_snr(sensor, mu, spec.exposure_time_s)
    snr_max = float(np.nanmax(snr[below])) if np.isfinite(snr[below]).any() else None
    return {"saturation_e": sat, "saturation_method": how, "saturation_photons": sat / eta,
            "threshold_e": cross[1.0], "threshold_photons": None if cross[1.0] is None else cross[1.0] / eta,
            "dynamic_range": dr, "dynamic_range_db": dr_db, "snr_max": snr_max,
            "snr_max_db": None if not snr_max else 20 * math.log10(snr_max),
            "snr1_e": cross[1.0], "snr10_e": cross[10.0], "snr40_e": cross[40.0],
            "curve": {"signal_e": mu.tolist(), "photons": (mu / eta).tolist(), "snr": snr.tolist(),
                      "snr_model": None if model is None else model.tolist(), "top_fraction": s["top_fraction"].tolist()}}


def photometry(camera: CameraSpec, spec: DatasheetSpec) -> dict:
    """Electrons per lux·s at the sensor plane per channel, under the stated light, and what a lux of scene
    illuminance gives on the sensor plane for the stated object, through the camera's lens (its f-number,
    transmittance and irradiance form: :meth:`CameraSpec.photo_electron_rates`).

    Parameters
    ----------
    camera : CameraSpec
    spec : DatasheetSpec
        Its light (a CIE illuminant) and object reflectance.

    Returns
    -------
    dict
        ``e_per_lux_s`` per channel (e⁻ per lux·s at the sensor plane), ``sensor_lux_per_scene_lux`` (for the
        object; ``…_white`` for a perfect white), and the light, channels and lens it used.
    """
    from spectracam.optics import irradiance_factor, radiance_to_photon_irradiance
    from spectracam.scene.illuminant import IlluminantSpec, white_diffuser_radiance

    grid = WavelengthGrid(GRID_NM)
    light = IlluminantSpec(kind="cie", temperature_K=None, name=spec.light, white_luminance_cd_m2=1.0 / math.pi)
    rad = white_diffuser_radiance(light, grid)                         # perfect white under 1 lux
    rates = np.asarray(camera.photo_electron_rates(rad[None, :], grid), float)[0]   # e⁻/s per pixel
    k_band = radiance_to_photon_irradiance(grid, camera.optics) / energy_to_photons(1.0, np.asarray(grid.centres_nm))
    sensor_lux = float(683.0 * np.sum(rad * k_band * cmf_band_weights(grid)[:, 1]))   # sensor-plane lux
    channels = camera.architecture().channels
    return {"light": f"CIE {spec.light}", "channels": list(channels),
            "e_per_lux_s": dict(zip(channels, (rates / sensor_lux).tolist())),
            "sensor_lux_per_scene_lux_white": sensor_lux,
            "sensor_lux_per_scene_lux": spec.reflectance * sensor_lux, "reflectance": spec.reflectance,
            "f_number": camera.optics.f_number, "transmittance": camera.optics.transmittance,
            "irradiance_form": camera.optics.irradiance_form, "irradiance_factor_sr": irradiance_factor(camera.optics)}


def speeds(measured: dict, phot: dict, spec: DatasheetSpec, channel: str, iso_sat_constant: float) -> dict:
    """SNR 1/10 illuminances (sensor and scene) of ``channel`` at the exposure time, and the ISO 12232 speeds:
    H = μ_e/(e⁻ per lux·s); S_sat from the first channel to clip (a neutral object: every channel's saturation
    charge over its electrons per lux·s), S_noise from ``channel``.

    Parameters
    ----------
    measured : dict
        :func:`measure_readout`'s (signals in e⁻).
    phot : dict
        :func:`photometry`'s.
    spec : DatasheetSpec
        Its exposure time, s.
    channel : str
        The channel read.
    iso_sat_constant : float
        ISO 12232's saturation-speed constant.

    Returns
    -------
    dict
        Exposures ``H_*_lux_s`` (lux·s), speeds ``S_sat``, ``S_noise40``, ``S_noise10``, and the SNR 1/10 illuminances
        at the sensor and the scene, lux (None where the SNR is never reached).
    """
    c = phot["e_per_lux_s"][channel]
    t, to_scene = spec.exposure_time_s, 1.0 / phot["sensor_lux_per_scene_lux"]
    h = lambda e: None if e is None else e / c  # noqa: E731  lux·s at the sensor plane
    lux = {f"snr{n}": (None if h(measured[f"snr{n}_e"]) is None else h(measured[f"snr{n}_e"]) / t) for n in (1, 10)}
    h_sat = measured["saturation_e"] / max(phot["e_per_lux_s"].values())
    out = {"channel": channel, "exposure_time_s": t, "H_sat_lux_s": h_sat,
           "H_snr10_lux_s": h(measured["snr10_e"]), "H_snr40_lux_s": h(measured["snr40_e"]),
           "S_sat": ds.iso_speed(iso_sat_constant, h_sat),
           "S_noise40": ds.iso_speed(ds.ISO12232_NOISE_CONSTANT, h(measured["snr40_e"])),
           "S_noise10": ds.iso_speed(ds.ISO12232_NOISE_CONSTANT, h(measured["snr10_e"]))}
    for name, v in lux.items():
        out[f"{name}_sensor_lux"] = v
        out[f"{name}_scene_lux"] = None if v is None else v * to_scene
    return out


def smi_figures(camera: CameraSpec, fit: str = "delta_e") -> dict:
    """ISO 17321-1's SMI of the camera's channels: the ColorChecker's 18 chromatic patches (ISO 17321-1 Table D.1,
    ``iso17321``) under CIE D65, 380–780 nm in 5 nm steps; both fits.

    Parameters
    ----------
    camera : CameraSpec
        Its channels' responsivities.
    fit : str
        The fit reported unsuffixed (``"delta_e"`` or ``"least_squares"``); the other's keys are suffixed.

    Returns
    -------
    dict
        ``smi``, ``delta_e_mean`` and the other fit's ``smi_<fit>``, ``delta_e_mean_<fit>``, with the light and patches.
    """
    import colour

    from spectracam.core.spectra import cie_1931_cmfs
    from spectracam.scene.reflectances import load

    grid = WavelengthGrid(GRID_NM)
    R = np.asarray(camera.architecture().responsivities(camera.filters, grid), float)
    wl, xyz = cie_1931_cmfs()
    cmfs = np.stack([np.interp(GRID_NM, wl, xyz[:, k]) for k in range(3)], axis=-1)
    d65 = colour.SDS_ILLUMINANTS["D65"]
    S = np.interp(GRID_NM, np.asarray(d65.wavelengths, float), np.asarray(d65.values, float))
    patches = load("iso17321").at(GRID_NM, ds.SMI_PATCHES)
    out = {"illuminant": "CIE D65", "patches": "ColorChecker 1-18 (ISO 17321-1 Table D.1)", "fit": fit}
    for name in ("delta_e", "least_squares"):
        r = ds.sensitivity_metamerism_index(R, GRID_NM, S, patches, cmfs, name)
        key = "" if name == fit else "_" + name
        out |= {f"smi{key}": r.smi, f"delta_e_mean{key}": r.delta_e_mean}
    return out


def chart_figures(scene: Scene, spec: DatasheetSpec) -> dict:
    """The chart through the configured camera (closed-form render): ΔE*ab and CIEDE2000, per pixel and of the
    patches' mean colours, and ISO 15739 visual noise of the six grey patches at the scene's viewing geometry.

    Parameters
    ----------
    scene : Scene
        A chart scene.
    spec : DatasheetSpec
        Its seed.

    Returns
    -------
    dict
        ``delta_e_ab_mean``, ``delta_e2000_mean``, ``…_of_mean``, the illuminant, samples per degree and
        ``visual_noise`` per grey patch.
    """
    import colour

    from spectracam.pipeline import simulate
    from spectracam.processing.color import display_rgb_to_xyz, samples_per_degree
    from spectracam.scene.reference import ChartReference

    _, _, score = simulate(scene, "analytic", seed=spec.seed)
    lab_scene = np.array([p.scene_lab for p in score.patches], float)
    lab_rend = np.array([p.rendered_lab for p in score.patches], float)
    ref = ChartReference.of(scene)
    proc = scene.processing
    M_disp = display_rgb_to_xyz(proc.display)
    white = M_disp @ np.ones(3)
    spd = samples_per_degree(proc.viewing_distance_m, proc.display_pixel_pitch_mm * 1e-3)
    greys = {}
    for i in range(18, 24):
        r, c = ref.boxes[i]
        greys[ref.names[i]] = ds.visual_noise(score.rendered_rgb[r, c] @ M_disp.T, white, spd)
    return {"delta_e_ab_mean": score.summary.delta_e_mean, "delta_e2000_mean": score.summary.delta_e2000_mean,
            "delta_e_ab_of_mean": float(np.linalg.norm(lab_scene - lab_rend, axis=-1).mean()),
            "delta_e2000_of_mean": float(np.mean(colour.delta_E(lab_scene, lab_rend, method="CIE 2000"))),
            "illuminant": scene.illuminant.label, "samples_per_degree": spd, "visual_noise": greys}


def run_datasheet(scene: Scene, spec: DatasheetSpec = DatasheetSpec()) -> DatasheetResult:
    """The datasheet of ``scene``'s camera: ``{parameters, sensor, readouts, photometry, iso12232, smi, chart,
    notes}`` (every read-out of ``spec.readouts`` measured; the photometric figures from the configured one).

    Parameters
    ----------
    scene : Scene
        A chart scene; its camera is measured.
    spec : DatasheetSpec

    Returns
    -------
    DatasheetResult
        results.json's keys but ``command``.

    Raises
    ------
    SpectracamError
        When the camera does not record ``spec.channel``, or its read-out cannot be read in this installation.
    """
    from spectracam.experiments.emva.experiment import channel_qe
    from spectracam.io.dng import ISO_SATURATION_CONSTANT

    camera = scene.camera
    channels = camera.architecture().channels
    if spec.channel not in channels:
        raise SpectracamError(f"datasheet: channel {spec.channel!r} is not recorded by this camera's architecture "
                              f"(channels: {', '.join(channels)})")
    eta = channel_qe(camera, spec.channel, spec.wavelength_nm) if spec.channel in ("R", "G", "B") else 1.0
    measured_names, missing = available_readouts(spec.readouts)
    readouts = {n: measure_readout(camera.sensor.replace(readout=n), spec, eta, i)
                for i, n in enumerate(measured_names)}
    phot = photometry(camera, spec)
    configured = readouts.get(camera.sensor.readout)
    notes = [f"read-out {n!r} not measured: spectracam.sensor.readout is not in this installation" for n in missing]
    if configured is None and camera.sensor.readout in missing:
        raise SpectracamError(f"sensor.readout = {camera.sensor.readout!r}: this installation cannot read it "
                              "(spectracam.sensor.readout is missing); use 'single'")
    if configured is None:
        configured = measure_readout(camera.sensor, spec, eta, len(measured_names))
    return {"parameters": {**asdict(spec), "eta": eta, "scene": scene.to_dict()},
            "sensor": sensor_figures(camera.sensor), "readouts": readouts, "photometry": phot,
            "iso12232": speeds(configured, phot, spec, spec.channel, ISO_SATURATION_CONSTANT),
            "smi": smi_figures(camera, spec.smi_fit), "chart": chart_figures(scene, spec), "notes": notes}
