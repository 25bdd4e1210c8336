"""A camera's own decisions (issue 33): the white it estimates and the calibration it interpolates by it.

The paper's camera knows the light: its conversion is fitted on the chart under the scene's own illuminant and its
exposure is metered on the chart's white patch.  ``processing.camera`` names the whole chain (:data:`CAMERAS`):

``oracle``     metering ``white_patch``, white balance ``oracle``, calibration ``scene_light`` — the paper's reading,
               computed exactly as before (its numbers do not move);
``developed``  metering ``percentile``, white balance ``corrected_moments`` (trained, never on the scored colours),
               calibration ``dual_illuminant`` (the DNG model) — a camera that must find its own white.

Each step can be overridden on its own (``capture.metering``, ``processing.white_balance``,
``processing.calibration``); ``auto`` takes the camera's.  :func:`develop` turns a capture's camera image into the
N×3 matrix the camera renders it with, and reports the white it found.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

from spectracam.core.errors import SpectracamError
from spectracam.processing.calibration import Calibration, white_neutral
from spectracam.processing.color import display_rgb_to_xyz
from spectracam.processing.registries import CALIBRATIONS, CAMERAS
from spectracam.processing.white_balance import (Estimation, band_reflectance, estimate_neutral, exclusion_key,
                                                 recovery_error_deg, reproduction_error_deg, trained_correction,
                                                 training_camera, usable_pixels)

if TYPE_CHECKING:
    from spectracam.camera import CameraSpec
    from spectracam.camera.capture import RawCapture
    from spectracam.processing.color import ProcessingSpec
    from spectracam.scene.reference import ChartReference, TargetReference

__all__ = ["CAMERAS", "Development", "develop", "metered_camera", "metering_method", "oracle_block",
           "scored_reflectances", "training_camera"]


def metering_method(camera: CameraSpec, processing: ProcessingSpec) -> str:
    """``capture.metering`` with ``auto`` resolved by ``processing.camera``.

    Parameters
    ----------
    camera : CameraSpec
        The camera (its ``capture.metering``).
    processing : ProcessingSpec
        The processing (its ``camera``: ``"oracle"`` or ``"developed"``).

    Returns
    -------
    str
        The metering method (``"patch"``, ``"brightest"``, …), never ``"auto"``.
    """
    m = camera.capture.metering
    return CAMERAS[processing.camera]["metering"] if m == "auto" else m


def metered_camera(camera: CameraSpec, processing: ProcessingSpec) -> CameraSpec:
    """``camera`` with its metering resolved by ``processing.camera`` (the capture stage reads ``auto`` as the white
    patch: whoever holds the processing resolves it).

    Parameters
    ----------
    camera : CameraSpec
        The camera (its ``capture.metering``).
    processing : ProcessingSpec
        The processing (its ``camera``: ``"oracle"`` or ``"developed"``).

    Returns
    -------
    CameraSpec
        ``camera`` itself when nothing changes, else a copy.
    """
    m = metering_method(camera, processing)
    return camera if m == camera.capture.metering else camera.replace(capture=camera.capture.replace(metering=m))


@dataclass(frozen=True, eq=False)
class Development:
    """What the camera decided for one image: the matrix ``(N, 3)`` from camera rates to linear display RGB, and the
    report's ``white_balance`` block."""

    matrix: np.ndarray
    white_balance: dict
    #: The estimated neutral ``(N,)``, e⁻/s up to scale (unit norm): the DNG's AsShotNeutral.
    neutral: np.ndarray | None = None


def scored_reflectances(reference: ChartReference, target_reference: TargetReference | None = None) -> tuple:
    """The scored scene's colours as band reflectances ``(n, B)``, whatever the light (the trained estimator never
    trains on them): the chart's patches, and a textured target's library.

    Parameters
    ----------
    reference : ChartReference
        The chart (its patches and bands).
    target_reference : TargetReference, optional
        A textured target (its reflectance library).

    Returns
    -------
    tuple of ndarray
        ``(24, B)`` the patches' band reflectances, then ``(n, B)`` the library's when there is a target.
    """
    return _scored(reference.chart, reference.grid, None if target_reference is None else target_reference.library)


@lru_cache(maxsize=16)
def _scored(chart, grid, library) -> tuple:
    from spectracam.scene.chart import patch_reflectances
    from spectracam.scene.reflectances import load
    from spectracam.core.spectra import band_average

    out = [np.stack([band_average(rho, grid) for _, rho in patch_reflectances(chart)])]
    if library is not None:
        out.append(band_reflectance(load(library, "target.library"), grid))
    return tuple(np.ascontiguousarray(a, np.float64) for a in out)


def develop(image: np.ndarray, raw: RawCapture, reference: ChartReference, processing: ProcessingSpec,
            target_reference: TargetReference | None = None) -> Development:
    """The developed camera's rendering matrix for the camera image ``(H, W, N)`` (e⁻/s; demosaicked,
    exposure-normalised) of ``raw``: estimate the neutral (``processing.white_balance``), calibrate by it
    (``processing.calibration``), and show the metered white at display Y = 1.

    Parameters
    ----------
    image : ndarray
        ``(H, W, N)`` camera rates, e⁻/s.
    raw : RawCapture
        The capture (its camera, exposure times and metered white).
    reference : ChartReference
        The chart under the scene's light (the calibration's and the true neutral's).
    processing : ProcessingSpec
        The white balance, calibration and display.
    target_reference : TargetReference, optional
        A textured target, whose colours the trained estimator leaves out.

    Returns
    -------
    Development
        The ``(N, 3)`` matrix, the ``white_balance`` block and the estimated neutral.

    Raises
    ------
    SpectracamError
        The metered white renders at a luminance that is not > 0.
    """
    camera = raw.camera
    true = white_neutral(reference.illuminant, reference.grid, camera)
    ctx = Estimation(image, usable_pixels(image, raw.exposure_times_s, camera.sensor), processing, camera,
                     reference.grid, true, scored_reflectances(reference, target_reference))
    estimate = estimate_neutral(ctx)
    M, info = CALIBRATIONS[processing.calibration_method](Calibration(reference, camera, processing, true), estimate)
    metered = raw.metered_rate_e_per_s if raw.metered_rate_e_per_s is not None else true
    Y = float(np.asarray(metered, float) @ M @ display_rgb_to_xyz(processing.display)[1])
    if not np.isfinite(Y) or Y <= 0:
        raise SpectracamError(f"processing: the metered white renders at luminance {Y:g}; the estimated neutral "
                              f"{np.round(estimate, 6).tolist()} leaves the camera no white to show")
    M = M / Y
    block = {"method": processing.white_balance_method, "calibration": processing.calibration_method,
             "neutral": (estimate / estimate.max()).tolist(), "true_neutral": (true / true.max()).tolist(),
             "recovery_deg": float(recovery_error_deg(estimate, true)),
             "reproduction_deg": float(reproduction_error_deg(estimate, true)),
             "pixels_used": int(ctx.valid.sum()), **info}
    if processing.white_balance_method == "corrected_moments":
        block["training"] = trained_correction(training_camera(camera), reference.grid,
                                               processing.white_balance_training,
                                               exclusion_key(ctx.scored_reflectances)).to_dict()
    return Development(M, block, estimate)


def oracle_block(reference: ChartReference, camera: CameraSpec, processing: ProcessingSpec) -> dict:
    """The ``white_balance`` block of the oracle chain: the true neutral, errors 0.

    Parameters
    ----------
    reference : ChartReference
        The chart under the scene's light.
    camera : CameraSpec
        The camera.
    processing : ProcessingSpec
        The processing (not read: the oracle's block is the same for every one).

    Returns
    -------
    dict
        ``method``, ``calibration``, ``neutral`` and ``true_neutral`` (max 1), ``recovery_deg`` and
        ``reproduction_deg`` (0).
    """
    true = white_neutral(reference.illuminant, reference.grid, camera)
    n = (true / true.max()).tolist()
    return {"method": "oracle", "calibration": "scene_light", "neutral": n, "true_neutral": n,
            "recovery_deg": 0.0, "reproduction_deg": 0.0}
