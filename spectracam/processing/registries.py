"""The processing's named choices, at the bottom of :mod:`spectracam.processing`: the cameras of ``processing.camera``
and the registries the white-balance estimators and the calibrations register into.

:class:`~spectracam.processing.color.ProcessingSpec` validates its fields against these, and
:mod:`~spectracam.processing.white_balance` and :mod:`~spectracam.processing.calibration` fill them, so neither has
to be imported by the other or by the spec (no import loop).  The package face, :mod:`spectracam.processing`, imports
both before anything can read a spec, so the registries are complete whenever one is validated.
"""
from __future__ import annotations

from spectracam.core.registry import Registry

__all__ = ["CALIBRATIONS", "CAMERAS", "WHITE_BALANCE_METHODS"]

#: Each camera's steps (issue 33): ``capture.metering``, ``processing.white_balance``, ``processing.calibration``.
CAMERAS = {
    "oracle": {"metering": "white_patch", "white_balance": "oracle", "calibration": "scene_light"},
    "developed": {"metering": "percentile", "white_balance": "corrected_moments", "calibration": "dual_illuminant"},
}

#: Estimators (:mod:`spectracam.processing.white_balance`): name → function ``(ctx: Estimation) → neutral (N,)``.
WHITE_BALANCE_METHODS: Registry = Registry("processing.white_balance", "white-balance estimator")

#: Calibrations (:mod:`spectracam.processing.calibration`): name → function
#: ``(ctx: Calibration, neutral (N,)) → (N×3 camera→XYZ-at-display-white, info)``.
CALIBRATIONS: Registry = Registry("processing.calibration", "colour calibration")
