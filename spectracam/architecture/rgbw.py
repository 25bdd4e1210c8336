"""RGBW: half the pixels panchromatic (W, no colour filter), the other half R, G, B — Kodak's
"CFA 2.0" (J. T. Compton, J. F. Hamilton, "Image sensor with improved light sensitivity", US patent
application 2007/0024931, Eastman Kodak; RGBW sensors since in automotive and low-light cameras).

The W pixels collect the light of all three filters (about 3× a primary's on a white) and so fill
their wells first: under the ``single`` exposure it is W that ends the exposure, and R, G, B get
less time than in a Bayer camera (the exposure metering's rule, spectracam.sensor.exposure).  Four channels:
the colour conversion is a 4×3 least-squares fit; the Bayer demosaickers do not apply (``bilinear``,
the periodic-mosaic interpolator, and ``patch`` do).  The tile, W on a checkerboard, colours in
diagonal pairs:

    W B W G
    B W G W
    W G W R
    G W R W

``cfa_pattern`` does not apply (one arrangement).  W = QE × IR cut.
"""
from __future__ import annotations

from spectracam.architecture.base import ARCHITECTURES, MosaicArchitecture

__all__ = ["TILE", "RedGreenBlueWhite"]

#: Kodak CFA 2.0, row by row, as indices into R, G, B, W.
TILE = ((3, 2, 3, 1), (2, 3, 1, 3), (3, 1, 3, 0), (1, 3, 0, 3))


@ARCHITECTURES.register("rgbw")
class RedGreenBlueWhite(MosaicArchitecture):
    """One sensor, one exposure, R, G, B and panchromatic W pixels (module docstring)."""

    name = "rgbw"
    channel_names = ("R", "G", "B", "W")
    primaries = ("R", "G", "B", "W")

    def tile_for(self, cfa_pattern: str) -> tuple[tuple[int, ...], ...]:
        return TILE
