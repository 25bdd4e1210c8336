"""Renderers: a scene becomes a :class:`RadianceCube` of band-averaged spectral radiance.

Two registered renderers produce the same type for the same scene: ``mitsuba`` (Mitsuba 3,
spectral variant, Monte Carlo) and ``analytic`` (closed form).  Tests hold the two against each
other.  A new renderer is a function ``(scene, progress, log) → RadianceCube`` registered in
:data:`RENDERERS`.
"""
from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from spectracam.core.registry import Registry
from spectracam.render.cube import VARIANTS, ChannelPlanes, RadianceCube, RenderSpec

if TYPE_CHECKING:
    from spectracam.pipeline.scene_file import Scene

__all__ = ["RENDERERS", "VARIANTS", "ChannelPlanes", "RadianceCube", "RenderSpec", "render", "render_planes"]

#: Renderers: name → function ``(scene, progress: bool, log) → RadianceCube``.
RENDERERS: Registry = Registry("renderer", "renderer")


@RENDERERS.register("mitsuba")
def _mitsuba(scene, progress=False, log=None):
    from spectracam.render.mitsuba import render_mitsuba

    if scene.target.textured:
        from spectracam.render.target import render_target_mitsuba

        return render_target_mitsuba(scene, progress=progress, log=log)
    return render_mitsuba(scene, progress=progress, log=log)


@RENDERERS.register("analytic")
def _analytic(scene, progress=False, log=None):
    from spectracam.render.analytic import render_analytic

    if scene.target.textured:
        from spectracam.render.target import render_target_analytic

        return render_target_analytic(scene)
    return render_analytic(scene)


def render(scene: Scene, renderer: str = "mitsuba", progress: bool = False,
           log: Callable[[str], object] | None = None) -> RadianceCube:
    """Render ``scene`` with the registered renderer; ``log`` (a callable) receives one-line notices.

    Parameters
    ----------
    scene : Scene
        What is in front of the camera: target, light, geometry, bands, image size, render settings.
    renderer : str
        A name in :data:`RENDERERS`: ``"mitsuba"`` (spectral Monte Carlo) or ``"analytic"`` (closed form).
    progress : bool
        Draw a bar over the bands (on a terminal).
    log : callable or None
        Receives one-line notices (e.g. the Mitsuba variant chosen); None: none.

    Returns
    -------
    RadianceCube
        ``(H, W, B)`` float32 band-averaged spectral radiance, W·m⁻²·sr⁻¹·nm⁻¹; its metadata records the
        renderer and the scene.
    """
    cube = RENDERERS[renderer](scene, progress=progress, log=log)
    cube.metadata["scene"] = scene.to_dict()  # later stages find the chart geometry here
    return cube


def render_planes(scene: Scene, weights: np.ndarray, renderer: str = "mitsuba", progress: bool = False,
                  log: Callable[[str], object] | None = None) -> ChannelPlanes:
    """Render ``scene`` straight into :class:`ChannelPlanes`: each band integrated into the planes as it is rendered,
    the ``(H, W, B)`` cube never held (issue 38).

    Parameters
    ----------
    scene : Scene
        A chart scene of one light.
    weights : ndarray
        ``(B, N)`` weights of the scene's bands, e.g. a camera's band weights (:func:`spectracam.camera.band_weights`,
        e⁻/s per W·m⁻²·sr⁻¹·nm⁻¹).
    renderer : {"mitsuba", "analytic"}
        The renderer; any other is refused.
    progress : bool
        Draw a bar over the bands (Mitsuba).
    log : callable or None
        Told the Mitsuba variant chosen.

    Returns
    -------
    ChannelPlanes
        ``(H, W, N)`` float32 ``Σ_b L_b · weights[b, k]``, recording the scene in ``metadata["scene"]``.

    Raises
    ------
    SpectracamError
        Another renderer, a textured target or a scene of several light groups, in one line.
    """
    from spectracam.core.errors import SpectracamError

    RENDERERS[renderer]   # an unknown renderer: the registry's one line
    if renderer not in ("mitsuba", "analytic"):
        raise SpectracamError(f"renderer = {renderer!r}: channel planes are rendered by 'mitsuba' or 'analytic' only")
    if scene.target.textured:
        raise SpectracamError(f"target = {scene.target.kind!r}: channel planes are rendered for a chart scene only; "
                              "render the radiance cube")
    if len(scene.lights) > 1:
        raise SpectracamError(f"lights = {len(scene.lights)} light groups: channel planes are rendered for a scene of "
                              "one light; render the radiance cube")
    if renderer == "analytic":
        from spectracam.render.analytic import render_analytic_planes

        planes = render_analytic_planes(scene, weights)
    else:
        from spectracam.render.mitsuba import render_mitsuba

        planes = render_mitsuba(scene, progress=progress, log=log, weights=weights)
    planes.metadata["scene"] = scene.to_dict()
    return planes
