"""Exposure control by white-patch metering (paper, section 4.5).

``single``   one time for all channels: the first channel to saturate on the white patch reaches
             full well (the paper's "traditional" scheme, the only one a CFA can use; with a W pixel
             it is W that ends the exposure);
``optimal``  per-channel times, each channel reaches full well on the white patch;
``balanced`` the optimal ratios, scaled so the total capture time equals the single exposure time
             (for field-sequential: the three frames together take as long as one CFA exposure).
``split``    each channel exposed for its share of the single exposure time (``[capture]``'s
             ``exposure_split``; shares of a field-sequential capture summing to ≤ 1 keep its total within
             that time), capped at the channel's own saturation: a designed split (``spectracam design``).
"Saturate" counts dark electrons too, and means "near saturation" (paper 4.5): a channel is metered
full when its mean photo + dark charge on the white patch reaches ``white_fill·q_max`` (the
``[capture]`` table's ``white_fill``, 0.95 by default, so the white's noise does not clip it).
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from spectracam.core.errors import SpectracamError
from spectracam.core.registry import Registry
from spectracam.sensor import SensorSpec

if TYPE_CHECKING:
    from spectracam.architecture.base import Architecture

__all__ = ["EXPOSURE_SCHEMES", "METERED_SCHEMES", "MIN_PHOTO_SHARE", "exposure_times_s",
           "saturation_times_s"]

#: Smallest share of the white patch's charge at saturation that must come from light: below it the
#: dark current fills the well and the "exposure" measures the dark current, not the scene.
MIN_PHOTO_SHARE = 0.01

#: Exposure schemes: name → function ``(saturation_s (N,), architecture, split) → times_s (N,)``, where
#: ``saturation_s`` is each channel's time to fill the well on the white patch and ``split`` the
#: ``exposure_split`` shares (used by ``split`` only).
EXPOSURE_SCHEMES: Registry = Registry("capture.exposure", "exposure scheme")


@EXPOSURE_SCHEMES.register("single")
def _single(saturation_s, architecture, split=()):
    return np.full(len(saturation_s), saturation_s.min())


@EXPOSURE_SCHEMES.register("optimal")
def _optimal(saturation_s, architecture, split=()):
    return saturation_s


@EXPOSURE_SCHEMES.register("balanced")
def _balanced(saturation_s, architecture, split=()):
    # the paper (5.1): "FSC with total exposure equal to the CFA exposure duration" — one single time
    return saturation_s * (saturation_s.min() / architecture.capture_time_s(saturation_s))


#: The schemes that need nothing but the white patch (``split`` needs its designed shares): what a comparison of
#: every architecture and scheme runs.
METERED_SCHEMES = ("single", "optimal", "balanced")


@EXPOSURE_SCHEMES.register("split")
def _split(saturation_s, architecture, split=()):
    if len(split) != len(saturation_s):
        raise SpectracamError(f"capture.exposure_split = {list(split)}: the 'split' scheme needs one share per channel "
                              f"({len(saturation_s)}: {', '.join(architecture.channels)}), each in (0, 1]")
    return np.minimum(saturation_s.min() * np.asarray(split, float), saturation_s)


def saturation_times_s(white_rate_e_per_s: np.ndarray, sensor: SensorSpec, white_fill: float = 1.0,
                       channels: Sequence[str] = ("R", "G", "B")) -> np.ndarray:
    """Time for each channel's mean photo + dark charge on the white patch to reach ``white_fill·q_max``, s.  A channel
    that receives no light, or whose well the dark current fills, has no meaningful exposure: one
    clear error.

    Parameters
    ----------
    white_rate_e_per_s : ndarray
        ``(N,)`` each channel's mean photo-electron rate on the white patch, e⁻/s.
    sensor : SensorSpec
        The sensor (full well q_max, e⁻; dark rate, e⁻/s).
    white_fill : float
        The share of the full well the white's mean charge reaches.
    channels : sequence of str
        The channels' names, for the errors.

    Returns
    -------
    ndarray
        ``(N,)`` s.

    Raises
    ------
    SpectracamError
        A channel with no light, or one whose dark current outruns its light (:data:`MIN_PHOTO_SHARE`).
    """
    white = np.asarray(white_rate_e_per_s, float)
    for k, w in zip(channels, white):
        if not np.isfinite(w) or w <= 0:
            raise SpectracamError(f"exposure: channel {k} receives no light on the white patch ({w:g} e-/s); the "
                                  "filters or the illuminant leave it dark, so no exposure can be metered")
        if w < MIN_PHOTO_SHARE * (w + sensor.dark_rate_e_per_s):
            raise SpectracamError(f"exposure: channel {k}'s dark current ({sensor.dark_rate_e_per_s:g} e-/s) fills the "
                                  f"well faster than its light ({w:g} e-/s): less than {100 * MIN_PHOTO_SHARE:g} % of "
                                  "the charge would be signal; raise the light level or lower the dark current")
    return white_fill * sensor.q_max_e / (white + sensor.dark_rate_e_per_s)


def exposure_times_s(scheme: str, white_rate_e_per_s: np.ndarray, sensor: SensorSpec, architecture: Architecture,
                     white_fill: float = 1.0, split: Sequence[float] = ()) -> np.ndarray:
    """Per-channel exposure times ``(N,)`` in seconds for the architecture under a scheme, metered so
    that the white's mean charge reaches ``white_fill`` of the full well — of the largest charge the sensor's
    read-out encodes (``headroom`` × the well, :mod:`spectracam.sensor.readout`): a high-dynamic-range read-out
    exposes longer, for the shadows, and keeps the white within its range.

    Parameters
    ----------
    scheme : str
        A registered scheme (:data:`EXPOSURE_SCHEMES`): ``"single"``, ``"optimal"``, ``"balanced"`` or ``"split"``.
    white_rate_e_per_s : ndarray
        ``(N,)`` each channel's mean photo-electron rate on the white patch, e⁻/s.
    sensor : SensorSpec
        The sensor (full well, dark rate, read-out).
    architecture : Architecture
        The architecture (its channels and capture time).
    white_fill : float
        The share of the full well the white's mean charge reaches (``capture.white_fill``).
    split : sequence of float
        The ``split`` scheme's shares, one per channel in (0, 1].

    Returns
    -------
    ndarray
        ``(N,)`` s.

    Examples
    --------
    >>> from spectracam.architecture.base import make_architecture
    >>> s = SensorSpec(q_max_e=100.0, dark_current=False)
    >>> exposure_times_s("balanced", [100.0, 200.0, 50.0], s, make_architecture("fsc")).round(4).tolist()
    [0.1429, 0.0714, 0.2857]
    """
    saturation = saturation_times_s(white_rate_e_per_s, sensor, white_fill, architecture.channels)
    if sensor.readout != "single":   # a high-dynamic-range read-out encodes up to ``headroom`` × a single read's rate
        from spectracam.sensor.readout import READOUTS

        saturation = saturation * READOUTS[sensor.readout].headroom(sensor)
    return EXPOSURE_SCHEMES[scheme](saturation, architecture, tuple(split))
