"""Motion: time-resolved rendering, field-sequential colour breakup and the rolling shutter.

The paper's conclusion weighs the field-sequential camera's SNR advantage against "the temporal
disadvantages of FSC": its three colour frames are taken one after another, so anything that moves
lands in a different place in each. Here a target of :mod:`spectracam.experiments.spatial` moves during the
capture (:mod:`.motion`), each architecture opens its channels' exposure windows at its own times
(:mod:`.timing`), Mitsuba renders the scene at time slices by moving the target's transform only
(:mod:`.render`), each channel integrates the slices inside its window, and the result is scored
(:mod:`.metrics`) by the colour-breakup width, S-CIELAB and the MTF along the motion
(:mod:`.experiment`, ``spectracam motion``).
"""
from __future__ import annotations

from spectracam.experiments.motion.motion import Motion
from spectracam.experiments.motion.timing import CaptureTiming, TimingSpec, capture_timing

__all__ = ["CaptureTiming", "Motion", "TimingSpec", "capture_timing"]
