"""Closed-form radiance cube of the chart scene.

Every surface is Lambertian and faces the illuminant, so its radiance is ``L(λ) = E(λ)·S(λ)/π``
(paper, section 3.1: colour signal = illuminant × reflectance).  A pixel's value is the
area-weighted mix of the surfaces in its footprint, which is the expectation of a box-filtered
Monte Carlo render of the same scene.
"""
from __future__ import annotations

import numpy as np

from spectracam.scene.chart import View, patch_coverage
from spectracam.scene.reference import ChartReference
from spectracam.render.cube import RadianceCube

__all__ = ["render_analytic"]


def render_analytic(scene) -> RadianceCube:
    """The chart's radiance cube in closed form: each pixel mixes the surround and the patches in
    proportion to the area of its footprint they cover."""
    ref = ChartReference.of(scene)
    patches, surround = ref.patch_radiance, ref.surround_radiance
    view = View.fit(scene.chart, scene.image.width, scene.image.height)
    cy, cx = patch_coverage(scene.chart, view)
    cube = np.empty((scene.image.height, scene.image.width, len(scene.grid)), dtype=np.float32)
    cube[...] = surround.astype(np.float32)
    for p, contrast in enumerate((patches - surround[None, :]).astype(np.float32)):
        rows, cols = np.flatnonzero(cy[p]), np.flatnonzero(cx[p])  # the patch's bounding box only
        if rows.size and cols.size:
            r, c = slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1)
            cover = (cy[p, r, None] * cx[p, None, c]).astype(np.float32)
            cube[r, c] += cover[:, :, None] * contrast
    meta = {"renderer": "analytic", "variant": None, "samples_per_pixel": None, "seed": scene.render.seed}
    return RadianceCube(cube, np.asarray(scene.grid.centres_nm, float), meta)
