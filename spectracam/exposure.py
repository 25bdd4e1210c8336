"""Exposure control by white-patch metering (paper, section 4.5).

``single``   one time for all channels: the first channel to saturate on the white patch reaches
             full well (the paper's "traditional" scheme, the only one a CFA can use);
``optimal``  per-channel times, each channel reaches full well on the white patch;
``balanced`` the optimal ratios, scaled so the total capture time equals the single exposure time
             (for field-sequential: the three frames together take as long as one CFA exposure).
"Saturate" counts dark electrons too: a channel is full when photo + dark charge = q_max.
"""
from __future__ import annotations

import numpy as np

from .errors import SpectracamError
from .sensor import SensorSpec

EXPOSURE_SCHEMES = ("single", "optimal", "balanced")


def exposure_times_s(scheme: str, white_rate_e_per_s: np.ndarray, sensor: SensorSpec, architecture) -> np.ndarray:
    """Per-channel exposure times ``(3,)`` in seconds for the architecture under a scheme."""
    if scheme not in EXPOSURE_SCHEMES:
        raise SpectracamError(f"capture.exposure = {scheme!r}: must be one of {', '.join(EXPOSURE_SCHEMES)}")
    saturation = sensor.q_max_e / (np.asarray(white_rate_e_per_s, float) + sensor.dark_rate_e_per_s)
    single = np.full(3, saturation.min())
    if scheme == "single":
        return single
    if not architecture.independent_exposures:
        raise SpectracamError(f"capture.exposure = {scheme!r}: the {architecture.name} architecture has one "
                              "exposure for all channels; use 'single'")
    if scheme == "optimal":
        return saturation
    # the paper (5.1): "FSC with total exposure equal to the CFA exposure duration" — one single time
    return saturation * (saturation.min() / architecture.capture_time_s(saturation))
