"""Processing: what a camera does with its capture — demosaicking, colour conversion and display
(:mod:`~spectracam.processing.color`), the white it estimates (:mod:`~spectracam.processing.white_balance`), the
calibration it interpolates by it (:mod:`~spectracam.processing.calibration`), the developed-camera chain that joins
them (:mod:`~spectracam.processing.develop`, issue 33) and the tone curves of the written pictures
(:mod:`~spectracam.processing.tone`).

The modules form a chain with no loop: :mod:`~spectracam.processing.registries` (the cameras and the registries the
estimators and calibrations register into) < :mod:`~spectracam.processing.color` (with ``ProcessingSpec``, which
validates against them) < :mod:`~spectracam.processing.white_balance`, :mod:`~spectracam.processing.calibration` <
:mod:`~spectracam.processing.develop`.  This face imports them all, so every registry is complete once
``spectracam.processing`` (or any module under it) is imported, and re-exports the developed-camera chain.
"""
from spectracam.processing.registries import CALIBRATIONS, CAMERAS, WHITE_BALANCE_METHODS
from spectracam.processing import calibration, white_balance  # noqa: F401  (each registers its methods)
from spectracam.processing.develop import (Development, develop, metered_camera, metering_method, oracle_block,
                                           scored_reflectances, training_camera)

__all__ = ["CAMERAS", "CALIBRATIONS", "WHITE_BALANCE_METHODS", "Development", "develop", "metered_camera",
           "metering_method", "oracle_block", "scored_reflectances", "training_camera"]
