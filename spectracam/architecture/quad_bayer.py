"""Quad Bayer: a Bayer array of 2×2 same-colour blocks (Sony IMX586, 2018; most phone sensors since).

Every site of a Bayer tile of ``cfa_pattern`` becomes a 2×2 block of that colour, a 4×4 tile.  In low
light phones bin each block into one pixel (a Bayer image at half resolution); at full resolution
they remosaic to Bayer.  Here it is one full-resolution exposure through the filters of
``[filters]``; the Bayer demosaickers remosaic it first (:func:`spectracam.processing.color.remosaic_to_bayer`),
``bilinear`` and ``patch`` work on its own 4×4 tile.
"""
from __future__ import annotations

from spectracam.architecture.base import ARCHITECTURES, MosaicArchitecture, MosaicLayout

__all__ = ["QuadBayer"]


@ARCHITECTURES.register("quad_bayer")
class QuadBayer(MosaicArchitecture):
    """One sensor, one exposure, a Quad Bayer colour filter array (module docstring)."""

    name = "quad_bayer"

    def tile_for(self, cfa_pattern: str) -> tuple[tuple[int, ...], ...]:
        bayer = MosaicLayout.bayer(cfa_pattern).tile
        return tuple(tuple(bayer[y // 2][x // 2] for x in range(4)) for y in range(4))
