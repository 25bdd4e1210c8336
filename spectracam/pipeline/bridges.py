"""Bridges to colour-science: spectracam's spectra as ``colour`` objects, for its plotting, colorimetry
and characterisation tools."""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from spectracam.camera import CameraSpec, camera_responsivities
from spectracam.core.spectra import WavelengthGrid

if TYPE_CHECKING:
    import colour

    from spectracam.pipeline.scene_file import Scene

__all__ = ["camera_sensitivities", "patch_spectra"]


def patch_spectra(scene: Scene) -> colour.MultiSpectralDistributions:
    """The chart's 24 patch radiances as a ``colour.MultiSpectralDistributions``.

    Parameters
    ----------
    scene : Scene
        The scene whose chart, light and wavelength grid give the radiances.

    Returns
    -------
    colour.MultiSpectralDistributions
        The 24 patch radiances (band averages on the scene's grid, W·m⁻²·sr⁻¹·nm⁻¹, ``L = E·S/π``), labelled with
        the patch names.

    Raises
    ------
    SpectracamError
        ``scene`` is not a :class:`~spectracam.pipeline.scene_file.Scene` (ArgumentTypeError).

    References
    ----------
    .. [Catrysse1999] see docs/references.md; section 3.1.

    Examples
    --------
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


def camera_sensitivities(camera: CameraSpec, grid: WavelengthGrid
                         ) -> colour.characterisation.RGB_CameraSensitivities | colour.MultiSpectralDistributions:
    """The camera's responsivities R_k(λ) on ``grid`` as ``colour.characterisation.RGB_CameraSensitivities``.

    Parameters
    ----------
    camera : CameraSpec
        The camera: its architecture's channels, filters and QE.
    grid : WavelengthGrid
        The bands, nm.

    Returns
    -------
    colour.characterisation.RGB_CameraSensitivities or colour.MultiSpectralDistributions
        R_k(λ) (filter × QE, electrons per photon; paper 3.3), band-averaged; a camera whose channels are not
        R, G, B (R Y B, C Y M, R G B W, …) gives a ``MultiSpectralDistributions`` labelled with their letters.

    Raises
    ------
    SpectracamError
        An argument of the wrong type (ArgumentTypeError).

    References
    ----------
    .. [Catrysse1999] see docs/references.md; section 3.3.

    Examples
    --------
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
