"""What the model is shown: for one scene's light, the chart (conversion fit and metering) and the colour sets
scored, as the constant arrays of :class:`~spectracam.design.model.LightModel`.

The conversion is fitted on the scene's ColorChecker, as the capture → score pipeline fits it
(:func:`spectracam.score.conversion_matrix`), and the exposure metered on its white patch; the colour sets are
the chart itself (``chart``) or measured reflectance libraries (:mod:`spectracam.reflectances`) under the same
light, their truth the CIE 1931 colorimetry of :func:`spectracam.reference.library_colours`.
"""
from __future__ import annotations

import numpy as np

from ..chart import WHITE_PATCH
from ..metrics import xyz_to_lab
from ..optics import radiance_to_photon_irradiance
from ..reference import ChartReference, library_colours
from ..score import conversion_target_rgb
from .model import ColourSet, LightModel

#: The colour-set name that means the scene's own chart.
CHART = "chart"


def photon_weights(scene, camera) -> np.ndarray:
    """``(B,)`` factor from band radiance to photo-electrons per second per unit responsivity: the optics'
    photon irradiance × band width × pixel area (paper 3.2-3.3; :func:`spectracam.camera.band_weights`)."""
    grid = scene.grid
    return radiance_to_photon_irradiance(grid, camera.optics) * grid.widths_nm * camera.sensor.pixel_area_um2 * 1e-12


def light_model(scene, camera, processing, sets=(CHART,), label: str | None = None) -> LightModel:
    """The :class:`LightModel` of a chart scene for ``camera`` with the colour ``sets`` (``chart`` or library
    names)."""
    ref = ChartReference.of(scene)
    g = photon_weights(scene, camera)
    chart_w = ref.patch_radiance * g[None, :]
    out = {}
    for name in sets:
        if name == CHART:
            out[name] = ColourSet(name, chart_w, xyz_to_lab(ref.patch_xyz, ref.white_xyz))
        else:
            c = library_colours(name, scene.illuminant, scene.grid)
            out[name] = ColourSet(name, c.radiance * g[None, :], xyz_to_lab(c.xyz, c.white_xyz))
    return LightModel(label or scene.illuminant.label, chart_w, conversion_target_rgb(ref, processing),
                      chart_w[WHITE_PATCH], out)
