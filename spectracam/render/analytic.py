"""Closed-form radiance cube of the chart scene.

Every surface is Lambertian and faces the illuminant, so its radiance is ``L(λ) = E(λ)·S(λ)/π``
(paper, section 3.1: colour signal = illuminant × reflectance).  A pixel's value is the
area-weighted mix of the surfaces in its footprint, which is the expectation of a box-filtered
Monte Carlo render of the same scene.  A scene of several light groups (:mod:`spectracam.scene.lights`)
shows one chart per group, each in its own cell of the image under its own light ``E_g``: each cell is
the one-chart closed form of the cell's size (:func:`chart_block`); unlit cells are 0.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from spectracam.scene.chart import ChartSpec, View, patch_coverage
from spectracam.scene.reference import ChartReference, chart_cells
from spectracam.render.cube import ChannelPlanes, RadianceCube

if TYPE_CHECKING:
    from spectracam.pipeline.scene_file import Scene

__all__ = ["ANALYTIC_METADATA", "chart_block", "lights_metadata", "render_analytic", "render_analytic_planes"]


def chart_block(chart: ChartSpec, patches: np.ndarray, surround: np.ndarray, width_px: int,
                height_px: int) -> np.ndarray:
    """``(height_px, width_px, B)`` float32: one chart fitted and centred in an image of that size, each pixel
    mixing the surround and the patches in proportion to the area of its footprint they cover.

    Parameters
    ----------
    chart : ChartSpec
        The chart's geometry.
    patches : ndarray
        ``(24, B)`` band radiance of the patches, W·m⁻²·sr⁻¹·nm⁻¹.
    surround : ndarray
        ``(B,)`` band radiance of the board and everything outside it.
    width_px, height_px : int
        The image's (or a chart cell's) size.

    Returns
    -------
    ndarray
        The radiance block.
    """
    view = View.fit(chart, width_px, height_px)
    cy, cx = patch_coverage(chart, view)
    cube = np.empty((height_px, width_px, surround.shape[0]), dtype=np.float32)
    cube[...] = surround.astype(np.float32)
    for p, contrast in enumerate((patches - surround[None, :]).astype(np.float32)):
        rows, cols = np.flatnonzero(cy[p]), np.flatnonzero(cx[p])  # the patch's bounding box only
        if rows.size and cols.size:
            r, c = slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1)
            cover = (cy[p, r, None] * cx[p, None, c]).astype(np.float32)
            cube[r, c] += cover[:, :, None] * contrast
    return cube


def lights_metadata(scene: Scene) -> dict:
    """What a cube records of a scene's light groups: ``{"lights": [...]}`` (each group's table, and for a chart
    its cell's pixels), or nothing without light groups (the metadata of a one-light scene is unchanged).

    Parameters
    ----------
    scene : Scene
        The scene.

    Returns
    -------
    dict
        ``{}``, or ``{"lights": [table, ...]}`` with ``cell_px`` = [row start, row stop, column start, column stop].
    """
    if not scene.lights:
        return {}
    groups = [g.to_dict() for g in scene.lights]
    if not scene.target.textured:
        for g, cell in zip(groups, chart_cells(scene)):
            g["cell_px"] = [cell.rows.start, cell.rows.stop, cell.cols.start, cell.cols.stop]
    return {"lights": groups}


def render_analytic(scene: Scene) -> RadianceCube:
    """The chart's radiance cube in closed form: each pixel mixes the surround and the patches in
    proportion to the area of its footprint they cover; with light groups, one chart per group's cell.

    Parameters
    ----------
    scene : Scene
        A chart scene.

    Returns
    -------
    RadianceCube
        ``(H, W, B)`` float32 band-averaged radiance, W·m⁻²·sr⁻¹·nm⁻¹.
    """
    W, H, B = scene.image.width, scene.image.height, len(scene.grid)
    if len(scene.lights) > 1:
        cube = np.zeros((H, W, B), dtype=np.float32)
        for cell in chart_cells(scene):
            ref = cell.reference
            cube[cell.rows, cell.cols] = chart_block(scene.chart, ref.patch_radiance, ref.surround_radiance,
                                                     cell.cols.stop - cell.cols.start, cell.rows.stop - cell.rows.start)
    else:
        ref = ChartReference.of(scene)
        cube = chart_block(scene.chart, ref.patch_radiance, ref.surround_radiance, W, H)
    meta = {**ANALYTIC_METADATA, "seed": scene.render.seed, **lights_metadata(scene)}
    return RadianceCube(cube, np.asarray(scene.grid.centres_nm, float), meta)


#: What an analytic render records of how it was made (the seed is the scene's).
ANALYTIC_METADATA = {"renderer": "analytic", "variant": None, "samples_per_pixel": None}


def render_analytic_planes(scene: Scene, weights: np.ndarray) -> ChannelPlanes:
    """The chart's :class:`ChannelPlanes` in closed form: the pixels mix the patches' and the surround's integrated
    values ``radiance @ weights`` as the cube's pixels mix their spectra (the mixing is linear); no cube is made.

    Parameters
    ----------
    scene : Scene
        A chart scene of one light.
    weights : ndarray
        ``(B, N)`` weights of its bands (a camera's band weights: e⁻/s per W·m⁻²·sr⁻¹·nm⁻¹).

    Returns
    -------
    ChannelPlanes
        ``(H, W, N)`` float32 planes.
    """
    ref = ChartReference.of(scene)
    w = np.asarray(weights, np.float64)
    planes = chart_block(scene.chart, ref.patch_radiance @ w, ref.surround_radiance @ w, scene.image.width,
                         scene.image.height)
    return ChannelPlanes(planes, np.asarray(scene.grid.centres_nm, float), w,
                         {**ANALYTIC_METADATA, "seed": scene.render.seed})
