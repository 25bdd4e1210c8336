"""Bridges to colour-science: spectracam's spectra as ``colour`` objects, for its plotting, colorimetry
and characterisation tools."""
from __future__ import annotations

import numpy as np

from spectracam.camera import CameraSpec, camera_responsivities
from spectracam.core.spectra import WavelengthGrid

__all__ = ["camera_sensitivities", "patch_spectra"]


def patch_spectra(scene):
    """The chart's 24 patch radiances (band averages on the scene's grid, W·m⁻²·sr⁻¹·nm⁻¹) as a
    ``colour.MultiSpectralDistributions`` labelled with the patch names.

    >>> from spectracam import parse_scene
    >>> patch_spectra(parse_scene({})).shape.interval
    10.0
    """
    import colour

    from spectracam.core.errors import expect
    from spectracam.scene.reference import ChartReference
    from spectracam.pipeline.scene_file import Scene

    expect(scene, Scene, "patch_spectra(scene)")
    ref = ChartReference.of(scene)
    return colour.MultiSpectralDistributions(ref.patch_radiance.T, np.asarray(scene.grid.centres_nm),
                                             labels=list(ref.names), name=f"{scene.name}: patch radiance")


def camera_sensitivities(camera: CameraSpec, grid: WavelengthGrid):
    """The camera's responsivities R_k(λ) (filter × QE, electrons per photon; paper 3.3) on ``grid`` as
    ``colour.characterisation.RGB_CameraSensitivities``.

    >>> from spectracam.camera import CameraSpec
    >>> s = camera_sensitivities(CameraSpec(), WavelengthGrid(np.arange(405.0, 700.0, 10.0)))
    >>> s.labels
    ['red', 'green', 'blue']
    """
    import colour

    from spectracam.core.errors import expect

    expect(camera, CameraSpec, "camera_sensitivities(camera)")
    expect(grid, WavelengthGrid, "camera_sensitivities(grid)")
    R = camera_responsivities(camera, grid)
    channels = camera.architecture().channels
    if channels != ("R", "G", "B"):   # other channels (R Y B, C Y M, R G B W, …): named by their letters
        return colour.MultiSpectralDistributions(R.T, np.asarray(grid.centres_nm), labels=list(channels),
                                                 name=f"spectracam {camera.design} channels")
    return colour.characterisation.RGB_CameraSensitivities(R.T, np.asarray(grid.centres_nm),
                                                           labels=("red", "green", "blue"),
                                                           name=f"spectracam {camera.filters.kind} filters × "
                                                                f"{camera.filters.qe} QE")
