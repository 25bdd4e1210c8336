"""Checked against real measurements (issue 37, item 6): the Raspberry Pi HQ camera's lens-shading tables and a
lensfun lens's vignetting.

Two checks, each stating what is **fitted** (one number) and what is **predicted** from it with nothing more fitted:

* :func:`imx477_reproduction`: a Bayer camera of the Sony IMX477's geometry (4056 × 3040 pixels of 1.55 µm) behind an
  exit-pupil lens, its pixel's microlens and optical and electrical crosstalk on.  The lens's exit-pupil distance is
  fitted so that the simulated luminance table's corner/centre gain is the one of Raspberry Pi's tuning file
  [RPiTuning]; the Cr and Cb tables' corner/centre ratios at 2960, 4850 and 5930 K and the luminance table's shape
  away from the corners are then predicted and set beside the file's.
* :func:`lensfun_reproduction`: lensfun's measured vignetting of a lens [Lensfun] fitted at one aperture by the
  exit-pupil model (one parameter, the exit pupil's distance [Foote1915]) and by cos⁴ of a chief-ray angle growing
  linearly to a fitted corner angle [Smith2008]; the exit-pupil fit is then used to predict the curve at another
  aperture.

:func:`measured_markdown` writes both as a short markdown section.  Every number returned is a plain float, int, bool
or string (JSON-serialisable).

References: see ``docs/references.md`` ([RPiTuning], [libcamera], [Lensfun], [Smith2008], [Foote1915]).

The IMX477 model (:func:`imx477_reproduction`).  The camera: Bayer (``cfa/single``); :data:`IMX477_PIXEL`,
:data:`IMX477_FILTERS`; the lens the HQ camera's 6 mm CS-mount lens by assumption (the tuning file names none; its 33°
corner field angle can give the file's fall-off, the 16 mm C lens's 14° could not by cos⁴ alone), at
:data:`IMX477_F_NUMBER` (assumed).

Why a reduced image is exact here: in spectracam a pixel's flat-field value depends on where it is only through
the chief-ray angle, the azimuth and the relative illumination there (the crosstalk kernel and microlens are
evaluated per pixel for a locally uniform scene, :func:`~spectracam.camera.field.field_rates`), and all three
depend on h/z only.  So the sensor is simulated with positions shrunk by ``decimation`` (507 × 380 pixels at
the real 1.55 µm pitch, which the crosstalk and the microlens spot depend on) and the exit pupil shrunk by the
same factor: simulated pixel (i, j) is exactly the real sensor's point (8i + 3.5, 8j + 3.5), the centre of its
8 × 8 block.  The fitted and stated distance is the full sensor's.  What is lost: each 16 × 12 cell averages 507
× 380 / 192 ≈ 1000 sampled points rather than 64 times as many (the field is smooth at that scale), and a
sampled R site stands 8 real pixels from its G neighbour rather than one.

What the model lacks, each a cause of colour shading in a real module that is absent here: the IR-cut filter's
angle dependence (an interference coating's edge moves to shorter wavelengths with the chief ray's angle,
cutting red at the corners: in a real module a major cause of Cr > 1; here the IR cut is the same at every
angle); the lens's own colour (chromatic vignetting, coatings); mechanical vignetting; the lens's decentring (the
file's corners differ, 1.548 to 1.619; the model is centred); the sensor's real microlens shift, stack, dyes and
spectral responses (all stated, not known); the tool's reading of one green and its rounding.
"""
from __future__ import annotations

import math
import time
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from spectracam.core.errors import SpectracamError
from spectracam.optics.field import LENSFUN_DIR, cos4_illumination, exit_pupil_illumination

if TYPE_CHECKING:
    from collections.abc import Sequence

    from numpy.typing import ArrayLike

    from spectracam.camera import CameraSpec
    from spectracam.core.spectra import WavelengthGrid

__all__ = ["CALIBRATION_TEMPERATURES_K", "IMX477_DECIMATION", "IMX477_F_NUMBER", "IMX477_PITCH_UM", "IMX477_PIXEL",
           "IMX477_FILTERS", "IMX477_SIZE_PX", "LENSFUN_APERTURE", "LENSFUN_LENS", "LENSFUN_PREDICT_APERTURE",
           "fit_cos4_corner", "fit_exit_pupil", "imx477_camera", "imx477_reproduction", "lensfun_reproduction",
           "measured_markdown", "simulated_alsc_tables"]

#: The IMX477's active pixels, (H, W), and pitch, µm (Raspberry Pi HQ camera: 12.3 MP, 7.857 mm diagonal).
IMX477_SIZE_PX = (3040, 4056)
IMX477_PITCH_UM = 1.55
#: The simulated image is the sensor shrunk by this factor in position only (pitch kept): 507 × 380 pixels, one per
#: 8 × 8 block of the real sensor (4056 = 8·507, 3040 = 8·380 exactly); see :func:`imx477_reproduction`.
IMX477_DECIMATION = 8
#: The lens's f-number during the tuning file's calibration: assumed (not recorded in the file).
IMX477_F_NUMBER = 2.8
#: The colour temperatures of the tuning file's colour tables, K [RPiTuning].
CALIBRATION_TEMPERATURES_K = (2960.0, 4850.0, 5930.0)
#: The pixel (``[pixel]``): microlens, optical and electrical crosstalk and the dyes' oblique path on; a back-side
#: illuminated stack (the IMX477 is a stacked back-illuminated sensor) of 1.5 µm, the middle of the 1–2 µm that
#: :class:`~spectracam.sensor.angle.PixelAngleSpec` states for such pixels; everything else its defaults.
IMX477_PIXEL = {"microlens": True, "optical_crosstalk": True, "electrical_crosstalk": True, "filter_angle": True,
                "stack_height_um": 1.5}
#: The colour filters (``[filters]``): the IMX477's spectral responses are not published, so broad Gaussian dyes
#: (peaks 600, 530, 460 nm, 100 nm wide) on a silicon photodiode collecting from 3 µm, behind an IR cut at 650 nm.
IMX477_FILTERS = {"kind": "gaussian", "centres_nm": [600.0, 530.0, 460.0], "fwhm_nm": [100.0, 100.0, 100.0],
                  "qe": "photodiode", "collection_depth_um": 3.0, "ir_cut_nm": 650.0, "ir_cut_width_nm": 20.0}
#: The lensfun check's lens, the aperture its exit pupil is fitted at (stopped down: natural vignetting) and the one
#: it is predicted at (wide open).
LENSFUN_LENS = "Canon EF 50mm f/1.8 II"
LENSFUN_APERTURE = 8.0
LENSFUN_PREDICT_APERTURE = 1.8
#: Points of r = 0 … 1 (the calibration frame's relative radius) the lensfun curves are compared on.
_LENSFUN_POINTS = 101


# --------------------------------------------------------------------------------------------------- the IMX477
def imx477_camera(exit_pupil_mm: float, *, decimation: int = IMX477_DECIMATION, f_number: float = IMX477_F_NUMBER,
                  microlens_shift_fraction: float = 0.0) -> tuple[CameraSpec, WavelengthGrid, tuple[int, int]]:
    """The simulated Raspberry Pi HQ camera: the IMX477 behind an exit-pupil lens.

    Parameters
    ----------
    exit_pupil_mm : float
        The lens's exit-pupil distance for the **full** sensor, mm; the simulated optics get ``exit_pupil_mm /
        decimation`` (positions shrink by ``decimation``, so every chief-ray angle and relative illumination is the
        full sensor's).
    decimation : int
        A divisor of 3040 and 4056 (1, 2, 4, 8).
    f_number : float
        The lens's f-number (the exit pupil as a disc, the microlens's cone).
    microlens_shift_fraction : float
        ``pixel.microlens_shift_fraction`` (0: microlenses centred on their pixels).

    Returns
    -------
    tuple
        ``(camera, grid, shape)``: the :class:`~spectracam.camera.CameraSpec`, its wavelength grid (d65.toml's
        400–700 nm in 10 nm bands) and the simulated image's ``(H, W)``.

    References
    ----------
    .. [RPiTuning] see docs/references.md.
    .. [Foote1915] see docs/references.md (the exit pupil as a disc).
    """
    from spectracam.pipeline.scene_file import parse_scene, read_toml, shipped_scene_file

    h, w = IMX477_SIZE_PX
    if not isinstance(decimation, int) or decimation < 1 or h % decimation or w % decimation:
        raise SpectracamError(f"decimation = {decimation!r}: must be a whole divisor of {w} and {h} (1, 2, 4, 8)")
    shape = (h // decimation, w // decimation)
    data = read_toml(shipped_scene_file("d65.toml"), "scene file")
    data = {**data,
            "optics": {**data.get("optics", {}), "f_number": float(f_number), "relative_illumination": "exit_pupil",
                       "exit_pupil_form": "disk", "chief_ray": "exit_pupil",
                       "exit_pupil_mm": float(exit_pupil_mm) / decimation},
            "pixel": {**IMX477_PIXEL, "microlens_shift_fraction": float(microlens_shift_fraction)},
            "filters": dict(IMX477_FILTERS),
            "sensor": {**data.get("sensor", {}), "pixel_pitch_um": IMX477_PITCH_UM},
            "image": {**data.get("image", {}), "width": shape[1], "height": shape[0]},
            "capture": {"architecture": "cfa", "exposure": "single"}}
    scene = parse_scene(data, "spectracam field: the IMX477 (Raspberry Pi HQ camera)")
    return scene.camera, scene.grid, shape


def _median3(table: np.ndarray) -> np.ndarray:
    """OpenCV's ``medianBlur(…, 3)`` (borders replicated), as the tuning tool smooths its tables [libcamera]."""
    from scipy.ndimage import median_filter

    return median_filter(np.asarray(table, float), size=3, mode="nearest")


def simulated_alsc_tables(camera: CameraSpec, grid: WavelengthGrid, shape: tuple[int, int],
                          temperatures_K: Sequence[float] = CALIBRATION_TEMPERATURES_K) -> dict:
    """The tables Raspberry Pi's camera tuning tool would write for a simulated camera.

    Each light's noise-free raw flat field (:func:`~spectracam.processing.shading.flat_field` under
    :func:`~spectracam.processing.shading.calibration_light`) is read on 12 × 16 cells, channel by channel on its
    own sites (:func:`~spectracam.processing.shading.calibrate_gain_tables`, ``"cell_mean"``), split into a
    luminance table (G's gains) and Cr = R/G, Cb = B/G gains
    (:func:`~spectracam.processing.shading.luminance_and_colour_tables`), each smoothed by a 3 × 3 median as the
    tool's ``ctt_alsc.py`` does; the luminance table is the mean over the lights of G's table normalised to a
    minimum of 1 (the tool's ``lum_lut``).  Left out: the tool reads only one of the two greens, and rounds to 3
    decimals.

    Parameters
    ----------
    camera : CameraSpec
        A mosaic camera.
    grid : WavelengthGrid
    shape : tuple of int
        ``(H, W)`` pixels.
    temperatures_K : sequence of float
        The calibration lights' colour temperatures, K.

    Returns
    -------
    dict
        ``luminance`` ``(12, 16)``, ``cr`` and ``cb``: ``{K: (12, 16)}`` (numpy arrays).

    References
    ----------
    .. [libcamera] see docs/references.md (``ctt_alsc.py``).
    """
    from spectracam.processing.shading import (ShadingSpec, calibrate_gain_tables, calibration_light, flat_field,
                                               luminance_and_colour_tables)

    layout = camera.architecture().layout
    spec = ShadingSpec(method="cell_mean")
    lums, cr, cb = [], {}, {}
    for t in temperatures_K:
        flat = flat_field(camera, grid, shape, calibration_light(float(t)))
        lum, colour = luminance_and_colour_tables(calibrate_gain_tables(flat, spec, layout))
        lum = _median3(lum)
        lums.append(lum / lum.min())
        cr[float(t)], cb[float(t)] = _median3(colour[0]), _median3(colour[2])
    return {"luminance": np.mean(lums, axis=0), "cr": cr, "cb": cb}


def _edges(table) -> dict:
    """Middle of the left/right and of the top/bottom edges over the centre (a 12 × 16 table's 2 × 2 middles)."""
    from spectracam.processing.shading import table_figures

    t = np.asarray(table, float)
    r, c = t.shape
    rows, cols = slice((r - 1) // 2, r // 2 + 1), slice((c - 1) // 2, c // 2 + 1)
    centre = table_figures(t)["centre"]
    return {"edge_x_over_centre": float((t[rows, 0].mean() + t[rows, -1].mean()) / 2 / centre),
            "edge_y_over_centre": float((t[0, cols].mean() + t[-1, cols].mean()) / 2 / centre)}


def _step_signs(values) -> list:
    return [int(np.sign(b - a)) for a, b in zip(values, values[1:])]


def imx477_reproduction(tuning_path: str | Path | None = None, *, decimation: int = IMX477_DECIMATION,
                        f_number: float = IMX477_F_NUMBER, microlens_shift_fraction: float = 0.0) -> dict:
    """Reproduce the shape of the Raspberry Pi HQ camera's (IMX477) lens-shading tables.

    **Fitted** (one parameter): the lens's exit-pupil distance z (the relative illumination of an exit pupil seen as
    a disc of the lens's f-number [Foote1915], and the chief-ray angle ``atan(h/z)``), by Brent's method so that the
    simulated luminance table's corner/centre gain (:func:`simulated_alsc_tables`; mean of the four corner cells over
    the central 2 × 2, :func:`~spectracam.processing.shading.table_figures`) is the tuning file's.

    **Predicted** (nothing more fitted): the Cr (R/G) and Cb (B/G) tables' corner/centre ratios under flat fields at
    2960, 4850 and 5930 K, from the pixel's model alone (its crosstalk and microlens against the chief-ray angle the
    fitted lens gives), and the luminance table's shape away from the corners (the middles of its edges, and the
    rms over all cells of the ratio of the two tables normalised at the centre).

    The camera, why a reduced image is exact here, and what the model lacks: the module docstring.

    Parameters
    ----------
    tuning_path : str or pathlib.Path, optional
        The tuning file; None: :func:`~spectracam.processing.shading.find_libcamera_tuning` ("imx477").
    decimation : int
        See :func:`imx477_camera`.
    f_number : float
        The lens's f-number (assumed).
    microlens_shift_fraction : float
        ``pixel.microlens_shift_fraction`` (stated, 0: centred microlenses; the IMX477's is not published).

    Returns
    -------
    dict
        ``fitted``, ``predicted`` (per CCT, keyed "2960" …), ``luminance_shape``, ``parameters`` (each stated
        parameter's value and source), ``agreement`` (booleans), ``tuning_file``, ``seconds``; plain numbers.

    Raises
    ------
    SpectracamError
        If no tuning file is given and none is installed (Debian: ``apt-get install libcamera-ipa``).

    References
    ----------
    .. [RPiTuning], [libcamera], [Foote1915], [Smith2008] see docs/references.md.
    """
    from spectracam.processing.shading import find_libcamera_tuning, read_libcamera_alsc

    t0 = time.perf_counter()
    path = find_libcamera_tuning("imx477") if tuning_path is None else Path(tuning_path)
    if path is None:
        raise SpectracamError("the Raspberry Pi HQ camera's tuning file imx477.json is not installed (Debian: "
                              "apt-get install libcamera-ipa)")
    alsc = read_libcamera_alsc(path)
    temps, measured_lum, corner_mm, z, fit, fitted = _fit_imx477(alsc, decimation, f_number, microlens_shift_fraction)
    predicted, (cr_s, cb_s, cr_m, cb_m) = _predictions(fit, alsc, temps)
    shape = _luminance_shape(fit, alsc, measured_lum)
    agreement = _agreement(fitted, cr_s, cb_s, cr_m, cb_m)
    parameters = _parameters(decimation, f_number, microlens_shift_fraction, corner_mm, z, temps)
    return {"fitted": fitted, "predicted": predicted, "luminance_shape": shape, "parameters": parameters,
            "agreement": agreement, "tuning_file": str(path), "seconds": time.perf_counter() - t0}


def _fit_imx477(alsc, decimation: int, f_number: float, microlens_shift_fraction: float) -> tuple:
    """``(lights, the file's luminance figures, corner mm, fitted z mm, the simulated tables at z, the fit's
    record)``: the exit pupil fitted to the tuning file's luminance corner gain."""
    from spectracam.processing.shading import table_figures

    temps = tuple(sorted(alsc.cr_by_cct))
    measured_lum = table_figures(alsc.luminance_lut)
    target = measured_lum["corner_over_centre"]
    corner_mm = IMX477_PITCH_UM * 1e-3 * math.hypot(*IMX477_SIZE_PX) / 2

    runs: dict = {}

    def tables(z_mm: float) -> dict:
        if z_mm not in runs:
            camera, grid, shape = imx477_camera(z_mm, decimation=decimation, f_number=f_number,
                                                microlens_shift_fraction=microlens_shift_fraction)
            runs[z_mm] = simulated_alsc_tables(camera, grid, shape, temps)
        return runs[z_mm]

    def gain(z_mm: float) -> float:
        return table_figures(tables(z_mm)["luminance"])["corner_over_centre"]

    cell_h = math.hypot(IMX477_SIZE_PX[0] / 2 * 11 / 12, IMX477_SIZE_PX[1] / 2 * 15 / 16) * IMX477_PITCH_UM * 1e-3
    z = _fit_pupil(gain, target, cell_h)
    fit = tables(z)
    achieved = gain(z)
    fitted = {"parameter": "optics.exit_pupil_mm", "value": z, "simulated_value_mm": z / decimation,
              "corner_cra_deg": math.degrees(math.atan(corner_mm / z)),
              "corner_cell_cra_deg": math.degrees(math.atan(cell_h / z)),
              "lens_corner_cell_illumination": float(exit_pupil_illumination(cell_h, z, f_number)),
              "measured_target": target, "achieved": achieved, "relative_error": achieved / target - 1.0,
              "what": "the luminance table's corner/centre gain (mean of the 4 corner cells over the central 2 × 2)",
              "evaluations": len(runs)}

    return temps, measured_lum, corner_mm, z, fit, fitted


def _fit_pupil(gain, target: float, cell_h: float) -> float:
    """The exit-pupil distance, mm, at which ``gain(z)`` is ``target`` (Brent's method in log z)."""
    def residual(log_z: float) -> float:      # nearly linear in log z: Brent converges in a few steps
        return math.log(max(gain(math.exp(log_z)) - 1.0, 1e-12)) - math.log(target - 1.0)

    # start: the lens alone (small pupil, cos⁴ at the corner cell's centre) giving the whole fall-off; the pixel's
    # own loss makes the fitted pupil farther; the bracket is widened until it changes sign
    z0 = cell_h / math.sqrt(math.sqrt(target) - 1.0)
    lo, hi = math.log(z0), math.log(2.5 * z0)
    for _ in range(6):
        if residual(lo) > 0:
            break
        lo -= math.log(2.0)
    for _ in range(6):
        if residual(hi) < 0:
            break
        hi += math.log(2.0)
    if residual(lo) <= 0 or residual(hi) >= 0:
        raise SpectracamError(f"imx477: no exit-pupil distance between {math.exp(lo):.3g} and {math.exp(hi):.3g} "
                              f"mm gives the tuning file's corner/centre gain {target:.4f}")
    return math.exp(brentq(residual, lo, hi, xtol=1e-3))     # 0.1 % in z: ≈ 0.2 % in the gain's excess over 1


def _predictions(fit: dict, alsc, temps) -> tuple[dict, tuple]:
    """Per light: the model's and the file's Cr and Cb corner/centre ratios; and the four series."""
    from spectracam.processing.shading import table_figures

    predicted, cr_m, cb_m, cr_s, cb_s = {}, [], [], [], []
    for t in temps:
        row = {"cct_K": float(t),
               "model_cr": table_figures(fit["cr"][t])["corner_over_centre"],
               "model_cb": table_figures(fit["cb"][t])["corner_over_centre"],
               "measured_cr": table_figures(alsc.cr_by_cct[t])["corner_over_centre"],
               "measured_cb": table_figures(alsc.cb_by_cct[t])["corner_over_centre"]}
        predicted[f"{t:.0f}"] = row
        cr_s.append(row["model_cr"]), cb_s.append(row["model_cb"])
        cr_m.append(row["measured_cr"]), cb_m.append(row["measured_cb"])

    return predicted, (cr_s, cb_s, cr_m, cb_m)


def _luminance_shape(fit: dict, alsc, measured_lum: dict) -> dict:
    """The luminance tables' shapes, model against file, both over their centres."""
    from spectracam.processing.shading import table_figures

    model_lum = fit["luminance"] / table_figures(fit["luminance"])["centre"]
    meas_lum = alsc.luminance_lut / measured_lum["centre"]
    ratio = model_lum / meas_lum - 1.0
    shape = {"model": _edges(fit["luminance"]), "measured": _edges(alsc.luminance_lut),
             "rms_ratio_minus_1": float(np.sqrt(np.mean(ratio**2))),
             "max_abs_ratio_minus_1": float(np.abs(ratio).max()),
             "model_table": [[float(v) for v in row] for row in model_lum],
             "what": "both tables over their centres; ratio = model / measured cell by cell"}
    return shape


def _agreement(fitted: dict, cr_s, cb_s, cr_m, cb_m) -> dict:
    """What agrees with the file: the fit, the signs, the steps with colour temperature, the sizes."""
    def within_2x(model, meas):
        return all(0.5 <= (a - 1.0) / (b - 1.0) <= 2.0 for a, b in zip(model, meas))

    return {
        "luminance_fit_within_1pct": abs(fitted["relative_error"]) < 0.01,
        "cr_sign": all((a > 1) == (b > 1) for a, b in zip(cr_s, cr_m)),
        "cb_sign": all((a < 1) == (b < 1) for a, b in zip(cb_s, cb_m)),
        "cr_cct_steps": _step_signs(cr_s) == _step_signs(cr_m),
        "cb_cct_steps": _step_signs(cb_s) == _step_signs(cb_m),
        "cr_cct_ends": bool(np.sign(cr_s[-1] - cr_s[0]) == np.sign(cr_m[-1] - cr_m[0])),
        "cb_cct_ends": bool(np.sign(cb_s[-1] - cb_s[0]) == np.sign(cb_m[-1] - cb_m[0])),
        "cr_magnitude_within_2x": within_2x(cr_s, cr_m),
        "cb_magnitude_within_2x": within_2x(cb_s, cb_m),
    }


def _parameters(decimation: int, f_number: float, microlens_shift_fraction: float, corner_mm: float, z: float,
                temps) -> dict:
    """Every stated parameter of the IMX477 model: its value and its source (or that it is assumed)."""
    return {
        "sensor": {"value": f"{IMX477_SIZE_PX[1]} × {IMX477_SIZE_PX[0]} px, {IMX477_PITCH_UM} µm pitch, "
                            f"{2 * corner_mm:.3f} mm diagonal",
                   "source": "Sony IMX477 (Raspberry Pi HQ camera product brief)"},
        "simulation": {"value": f"{IMX477_SIZE_PX[1] // decimation} × {IMX477_SIZE_PX[0] // decimation} px at "
                                f"{IMX477_PITCH_UM} µm, exit pupil / {decimation}",
                       "source": "exact for this model: a pixel's response depends on h/z only (docstring)"},
        "architecture": {"value": "cfa/single (RGGB Bayer)", "source": "the IMX477's Bayer mosaic"},
        "lens": {"value": "Raspberry Pi 6 mm CS-mount lens, exit-pupil disc form", "source": "assumed: the tuning "
                 "file names no lens"},
        "optics.f_number": {"value": float(f_number), "source": "assumed (the calibration's aperture is not recorded)"},
        "optics.exit_pupil_mm": {"value": z, "source": "fitted (see fitted)"},
        "pixel": {"value": {**IMX477_PIXEL, "microlens_shift_fraction": float(microlens_shift_fraction)},
                  "source": "stated: stack 1.5 µm for a back-illuminated pixel (PixelAngleSpec's 1–2 µm); shift "
                            "unknown; other [pixel] fields at their defaults (sources in spectracam/sensor/angle.py)"},
        "filters": {"value": dict(IMX477_FILTERS), "source": "assumed: the IMX477's spectral responses are not "
                                                             "published; broad dyes, IR cut at 650 nm"},
        "wavelengths": {"value": "400–700 nm, 10 nm bands", "source": "d65.toml"},
        "calibration_lights": {"value": [float(t) for t in temps], "source": "the tuning file's colour tables; "
                               "Planckian below 5000 K, CIE daylight from it (calibration_light)"},
        "tables": {"value": "12 × 16 cell means per channel, 3 × 3 median, luminance = mean over the lights of G's "
                            "table / its minimum", "source": "Raspberry Pi's ctt_alsc.py [libcamera]"},
    }


# --------------------------------------------------------------------------------------------------- lensfun
def fit_exit_pupil(height_mm: ArrayLike, curve: ArrayLike, f_number: float | None,
                   bounds_mm: tuple = (1.0, 1e5)) -> dict:
    """The exit-pupil distance whose relative illumination best fits a curve (least squares over the points).

    Parameters
    ----------
    height_mm : array_like
        Image heights, mm.
    curve : array_like
        The relative illumination there (1 on the axis).
    f_number : float or None
        The aperture (the pupil a disc of radius z/2N, :func:`~spectracam.optics.field.exit_pupil_illumination`);
        None: a small pupil (cos⁴).
    bounds_mm : tuple of float
        The distances searched, mm (bounded Brent search in log z).

    Returns
    -------
    dict
        ``exit_pupil_mm``, ``rms`` and ``max_abs`` residual (model − curve), ``at_bound`` (the best fit lies at a
        bound: the curve falls off less, or more, than any distance there gives).

    References
    ----------
    .. [Foote1915] see docs/references.md; .. [Smith2008] likewise.
    """
    h, v = np.asarray(height_mm, float), np.asarray(curve, float)

    def rms(log_z):
        return float(np.sqrt(np.mean((exit_pupil_illumination(h, math.exp(log_z), f_number) - v) ** 2)))

    lo, hi = math.log(bounds_mm[0]), math.log(bounds_mm[1])
    res = minimize_scalar(rms, bounds=(lo, hi), method="bounded", options={"xatol": 1e-7})
    z = math.exp(res.x)
    resid = exit_pupil_illumination(h, z, f_number) - v
    return {"exit_pupil_mm": z, "rms": float(np.sqrt(np.mean(resid**2))), "max_abs": float(np.abs(resid).max()),
            "at_bound": bool(min(res.x - lo, hi - res.x) < 1e-4)}


def fit_cos4_corner(r: ArrayLike, curve: ArrayLike, bounds_deg: tuple = (0.0, 60.0)) -> dict:
    """The corner chief-ray angle θ_c whose ``cos⁴(θ_c·r)`` best fits a curve over relative radii r (least
    squares).

    Parameters
    ----------
    r : array_like
        Relative image heights, 0 … 1 (1: the corner θ_c is stated at).
    curve : array_like
        The relative illumination there.
    bounds_deg : tuple of float
        The angles searched, degrees.

    Returns
    -------
    dict
        ``cra_corner_deg``, ``rms`` and ``max_abs`` residual.

    References
    ----------
    .. [Smith2008] see docs/references.md (the cosine-fourth law).
    """
    r, v = np.asarray(r, float), np.asarray(curve, float)

    def rms(theta):
        return float(np.sqrt(np.mean((cos4_illumination(theta * r) - v) ** 2)))

    res = minimize_scalar(rms, bounds=bounds_deg, method="bounded", options={"xatol": 1e-8})
    resid = cos4_illumination(res.x * r) - v
    return {"cra_corner_deg": float(res.x), "rms": float(np.sqrt(np.mean(resid**2))),
            "max_abs": float(np.abs(resid).max())}


def lensfun_reproduction(lens: str = LENSFUN_LENS, focal_mm: float = 50.0, aperture: float = LENSFUN_APERTURE,
                         predict_aperture: float = LENSFUN_PREDICT_APERTURE,
                         db_dir: str | Path = LENSFUN_DIR) -> dict:
    """Fit and predict a lensfun lens's measured vignetting with the exit-pupil and cos⁴ models.

    **Fitted** at ``aperture`` over r = 0 … 1 of the calibration frame (101 points; lensfun's "pa" curve
    [Lensfun]): (a) the exit pupil's distance z, the pupil a disc of that f-number [Foote1915]; (b) separately, the
    corner angle θ_c of ``cos⁴(θ_c·r)`` [Smith2008].  Also shown, with nothing fitted: cos⁴ of the field angle
    ``atan(h/f)`` (a thin lens with its pupil at the focal length).

    **Predicted**: the exit-pupil curve at ``predict_aperture`` with the same z, against lensfun's calibration there.
    The model knows only the pupil's obliquity; wide open a lens's fall-off is mostly mechanical vignetting (the
    pupil clipped by the barrel's other stops off the axis), which it does not have, so a large miss there is the
    expected honest result, not a fault of the fit.

    Parameters
    ----------
    lens : str
        A lens model as lensfun spells it.
    focal_mm : float
        Focal length, mm (the nearest calibrated one is used).
    aperture : float
        The f-number fitted at (stopped down: natural vignetting).
    predict_aperture : float
        The f-number predicted at.
    db_dir : str or pathlib.Path
        lensfun's database (Debian ``liblensfun-data-v1``).

    Returns
    -------
    dict
        ``lens``, ``calibration`` (focal, crop factor, radius of r = 1 in mm, source file, k at both apertures),
        ``fitted`` (``exit_pupil`` and ``cos4``, each its parameter, rms and max residual), ``baseline``
        (``cos4_field_angle``: rms and max residual), ``predicted`` (aperture, the model's and lensfun's value at
        r = 1, rms and max residual of the exit-pupil prediction and of the cos⁴ fit, which ignores the aperture),
        ``curves`` (r and the curves, lists), ``seconds``.

    References
    ----------
    .. [Lensfun] see docs/references.md (the "pa" model and database).
    .. [Foote1915] see docs/references.md; .. [Smith2008] likewise.
    """
    from spectracam.optics.field import lensfun_vignetting, pa_illumination

    t0 = time.perf_counter()
    at = lensfun_vignetting(lens, focal_mm, aperture, db_dir=db_dir)
    wide = lensfun_vignetting(lens, focal_mm, predict_aperture, db_dir=db_dir)
    radius = at.radius_mm
    r = np.linspace(0.0, 1.0, _LENSFUN_POINTS)
    h = r * radius
    v_fit = pa_illumination(h, at.k, radius)
    v_wide = pa_illumination(h, wide.k, radius)
    ep = fit_exit_pupil(h, v_fit, at.aperture)
    c4 = fit_cos4_corner(r, v_fit)
    field = cos4_illumination(np.degrees(np.arctan(h / at.focal_mm)))
    pred = exit_pupil_illumination(h, ep["exit_pupil_mm"], wide.aperture)
    c4_curve = cos4_illumination(c4["cra_corner_deg"] * r)
    out = _lensfun_result(lens, at, wide, radius, r, h, v_fit, v_wide, ep, c4, field, pred, c4_curve)
    return {**out, "seconds": time.perf_counter() - t0}


def _lensfun_result(lens, at, wide, radius, r, h, v_fit, v_wide, ep, c4, field, pred, c4_curve) -> dict:
    """:func:`lensfun_reproduction`'s figures and curves (plain numbers)."""
    return {
        "lens": lens,
        "calibration": {"focal_mm": float(at.focal_mm), "crop_factor": float(at.crop_factor), "radius_mm": radius,
                        "source": at.source, "fit_aperture": float(at.aperture), "fit_k": list(at.k),
                        "fit_how": at.how, "predict_aperture": float(wide.aperture), "predict_k": list(wide.k),
                        "predict_how": wide.how},
        "fitted": {"exit_pupil": {"parameter": "exit_pupil_mm", "value": ep["exit_pupil_mm"], "rms": ep["rms"],
                                  "max_abs": ep["max_abs"], "at_bound": ep["at_bound"],
                                  "form": f"disc at f/{at.aperture:g}"},
                   "cos4": {"parameter": "cra_corner_deg", "value": c4["cra_corner_deg"], "rms": c4["rms"],
                            "max_abs": c4["max_abs"]},
                   "measured_corner": float(v_fit[-1]), "exit_pupil_corner": float(
                       exit_pupil_illumination(radius, ep["exit_pupil_mm"], at.aperture)),
                   "cos4_corner": float(c4_curve[-1])},
        "baseline": {"cos4_field_angle": {"rms": float(np.sqrt(np.mean((field - v_fit) ** 2))),
                                          "max_abs": float(np.abs(field - v_fit).max()), "corner": float(field[-1]),
                                          "what": "cos⁴ atan(h/f), nothing fitted"}},
        "predicted": {"aperture": float(wide.aperture), "model_corner": float(pred[-1]),
                      "measured_corner": float(v_wide[-1]),
                      "rms": float(np.sqrt(np.mean((pred - v_wide) ** 2))),
                      "max_abs": float(np.abs(pred - v_wide).max()),
                      "cos4_fit_rms": float(np.sqrt(np.mean((c4_curve - v_wide) ** 2))),
                      "what": f"exit pupil fitted at f/{at.aperture:g}, evaluated at f/{wide.aperture:g}"},
        "curves": {"r": r.tolist(), "measured_fit_aperture": v_fit.tolist(), "exit_pupil_fit": (
            exit_pupil_illumination(h, ep["exit_pupil_mm"], at.aperture)).tolist(), "cos4_fit": c4_curve.tolist(),
            "measured_predict_aperture": v_wide.tolist(), "exit_pupil_predicted": pred.tolist()},
    }


# --------------------------------------------------------------------------------------------------- report
def measured_markdown(imx: dict | None, lens: dict | None) -> str:
    """A short markdown section of the two checks (either may be None: not run, e.g. its data not installed).

    Parameters
    ----------
    imx : dict or None
        :func:`imx477_reproduction`'s result.
    lens : dict or None
        :func:`lensfun_reproduction`'s result.

    Returns
    -------
    str
        Markdown: a heading, a table of the IMX477's fitted and predicted figures beside the tuning file's, and one
        of the lensfun fits and prediction.

    References
    ----------
    .. [RPiTuning], [Lensfun] see docs/references.md.
    """
    return "\n".join(["## Checked against real measurements", "", *_imx477_markdown(imx), *_lensfun_markdown(lens)])


def _imx477_markdown(imx: dict | None) -> list:
    out: list = []
    if imx is None:
        out += ["The Raspberry Pi HQ camera's tuning file is not installed (Debian: `libcamera-ipa`): not checked.", ""]
    else:
        f, a, s = imx["fitted"], imx["agreement"], imx["luminance_shape"]
        shift = imx["parameters"]["pixel"]["value"]["microlens_shift_fraction"]
        out += [f"**Raspberry Pi HQ camera (IMX477), `{imx['tuning_file']}`.** Fitted: the exit pupil "
                f"{f['value']:.2f} mm (corner chief ray {f['corner_cra_deg']:.1f}°) so that the luminance table's "
                f"corner/centre gain is the file's {f['measured_target']:.4f} (got {f['achieved']:.4f}). Predicted, "
                f"nothing more fitted: the colour tables' corner/centre ratios (microlens shift {shift:g}, f/"
                f"{imx['parameters']['optics.f_number']['value']:g}, lens and filters assumed: see `parameters`).",
                "", "| light | Cr model | Cr measured | Cb model | Cb measured |", "|---|---|---|---|---|"]
        for key, row in imx["predicted"].items():
            out.append(f"| {key} K | {row['model_cr']:.4f} | {row['measured_cr']:.4f} | {row['model_cb']:.4f} | "
                       f"{row['measured_cb']:.4f} |")
        out.append(f"| edges x / y (luminance) | {s['model']['edge_x_over_centre']:.3f} / "
                   f"{s['model']['edge_y_over_centre']:.3f} | {s['measured']['edge_x_over_centre']:.3f} / "
                   f"{s['measured']['edge_y_over_centre']:.3f} | | |")
        yes = lambda b: "yes" if b else "no"  # noqa: E731
        out += ["", f"Sign right: Cr > 1 {yes(a['cr_sign'])}, Cb < 1 {yes(a['cb_sign'])}; colour-temperature steps "
                f"as measured: Cr {yes(a['cr_cct_steps'])}, Cb {yes(a['cb_cct_steps'])}; within a factor 2 of the "
                f"measured deviation: Cr {yes(a['cr_magnitude_within_2x'])}, Cb {yes(a['cb_magnitude_within_2x'])}. "
                f"Luminance table, model over measured cell by cell: rms {s['rms_ratio_minus_1']:.1%}, max "
                f"{s['max_abs_ratio_minus_1']:.1%}. The model has no angle-dependent IR cut, chromatic or mechanical "
                "vignetting, or decentring.", ""]
    return out


def _lensfun_markdown(lens: dict | None) -> list:
    out: list = []
    if lens is None:
        out += ["lensfun's database is not installed (Debian: `liblensfun-data-v1`): not checked.", ""]
    else:
        c, f, p, b = lens["calibration"], lens["fitted"], lens["predicted"], lens["baseline"]["cos4_field_angle"]
        out += [f"**{lens['lens']}** at {c['focal_mm']:g} mm (lensfun `{c['source']}`, crop {c['crop_factor']:g}, "
                f"r = 1 at {c['radius_mm']:.2f} mm).", "",
                "| model | fitted | at | corner model / lensfun | rms | max |", "|---|---|---|---|---|---|",
                f"| exit pupil (disc) | z = {f['exit_pupil']['value']:.1f} mm | f/{c['fit_aperture']:g} | "
                f"{f['exit_pupil_corner']:.3f} / {f['measured_corner']:.3f} | {f['exit_pupil']['rms']:.4f} | "
                f"{f['exit_pupil']['max_abs']:.4f} |",
                f"| cos⁴, linear CRA | θ_c = {f['cos4']['value']:.1f}° | f/{c['fit_aperture']:g} | "
                f"{f['cos4_corner']:.3f} / {f['measured_corner']:.3f} | {f['cos4']['rms']:.4f} | "
                f"{f['cos4']['max_abs']:.4f} |",
                f"| cos⁴ atan(h/f), nothing fitted | — | f/{c['fit_aperture']:g} | {b['corner']:.3f} / "
                f"{f['measured_corner']:.3f} | {b['rms']:.4f} | {b['max_abs']:.4f} |",
                f"| exit pupil, predicted | same z | f/{p['aperture']:g} | {p['model_corner']:.3f} / "
                f"{p['measured_corner']:.3f} | {p['rms']:.4f} | {p['max_abs']:.4f} |", "",
                f"Wide open (f/{p['aperture']:g}) the lens's fall-off is mostly mechanical vignetting, which the "
                "exit-pupil model lacks.", ""]
    return out
