"""CMY: a complementary (subtractive) colour filter array, cyan, yellow, yellow, magenta in each 2×2
tile (the Kodak DCS 620x's "CYYM" array, 2000).

Each complementary filter passes two of the three primaries, so it collects about twice the light of
a primary filter; recovering R, G, B takes differences (R = (Y + M − C)/2 …), which amplifies noise:
more signal, more conversion gain.  C = G + B, Y = R + G, M = R + B of ``[filters]`` (capped at the
unfiltered QE: :func:`~spectracam.architecture.base.complementary`); yellow, the brightest, takes the Bayer
diagonal of ``cfa_pattern`` (channels in the order C, Y, M), so the Bayer demosaickers work on it.
CMYG (a green replacing one yellow, the camcorders' interline CCDs read in pairs) is not included:
its reason — a luminance/chroma read-out of interlaced video — does not arise in a still camera.
"""
from __future__ import annotations

from spectracam.architecture.base import ARCHITECTURES, MosaicArchitecture

__all__ = ["CyanYellowMagenta"]


@ARCHITECTURES.register("cmy")
class CyanYellowMagenta(MosaicArchitecture):
    """One sensor, one exposure, a C Y Y M colour filter array (module docstring)."""

    name = "cmy"
    channel_names = ("C", "Y", "M")
    primaries = ("GB", "RG", "RB")
