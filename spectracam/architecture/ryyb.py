"""RYYB: a Bayer array whose greens are yellow (Huawei P30, 2019, "RYYB SuperSpectrum").

A yellow filter passes red and green together, so the two yellow sites of every 2×2 tile collect
the light of both (about 40 % more signal on a white, Huawei's claim) at the price of a red–yellow
difference to recover green: more conversion gain, more chroma noise.  Y = R + G of ``[filters]``
(capped at the unfiltered QE: :func:`~spectracam.architecture.base.complementary`); the tile is the Bayer
tile of ``cfa_pattern`` with Y where G would be, so the Bayer demosaickers work on it.
"""
from __future__ import annotations

from spectracam.architecture.base import ARCHITECTURES, MosaicArchitecture

__all__ = ["RedYellowYellowBlue"]


@ARCHITECTURES.register("ryyb")
class RedYellowYellowBlue(MosaicArchitecture):
    """One sensor, one exposure, an R Y Y B colour filter array (module docstring)."""

    name = "ryyb"
    channel_names = ("R", "Y", "B")
    primaries = ("R", "RG", "B")
