"""Rendering a textured target (:mod:`spectracam.target`): the closed form and Mitsuba.

The target is a Lambertian plane facing the light, filling the view; texel (i, j) has the reflectance
of the sample its label names.  Closed form: each pixel's band radiance is the mean of ``E·S/π`` over
its s × s texels (:meth:`~spectracam.reference.TargetReference.pixel_mean`).  Mitsuba: one rectangle
with a nearest-neighbour ``bitmap`` texture of the texel grid; per band the light is the band average
``Ē`` and each texel's value the light-weighted band average ``⟨E·S⟩/⟨E⟩`` of its sample (as the
chart's patches, :mod:`spectracam.render.mitsuba`), so a pixel inside one sample is exact and the
Monte Carlo of the box-filtered pixel footprint is left only where samples meet.  Values are updated
per band in the one compiled scene.
"""
from __future__ import annotations

import numpy as np

from ..illuminant import spectral_irradiance
from ..reference import TargetReference
from ..spectra import band_average
from . import RadianceCube


def render_target_analytic(scene) -> RadianceCube:
    ref = TargetReference.of(scene)
    cube = ref.pixel_mean(ref.radiance, np.float32)
    meta = {"renderer": "analytic", "variant": None, "samples_per_pixel": None, "seed": scene.render.seed}
    return RadianceCube(cube, np.asarray(scene.grid.centres_nm, float), meta)


def render_target_mitsuba(scene, progress: bool = False, log=None) -> RadianceCube:
    from .mitsuba import POINTS_PER_BAND, activate_variant, band_scene, band_seed, even_band_width_nm, select_variant

    variant, reason = select_variant(scene.render.variant)
    if log:
        log(f"Mitsuba variant {variant} ({reason})")
    mi = activate_variant(variant)
    grid = scene.grid
    width_nm = even_band_width_nm(grid)
    ref = TargetReference.of(scene)
    W, H, B = scene.image.width, scene.image.height, len(grid)
    E = spectral_irradiance(scene.illuminant)
    light_band = band_average(E, grid)                                     # ⟨E⟩ per band
    with np.errstate(invalid="ignore", divide="ignore"):                   # ⟨E·S⟩/⟨E⟩: 0 where there is no light
        rho = np.nan_to_num(ref.radiance * np.pi / light_band[None]).astype(np.float32)   # (n + 1, B)
    labels = ref.labels[::-1]          # a bitmap's first row is the top of the texture's v axis: the bottom row
    d = band_scene(mi, scene, W, width_nm)          # the view is W × H units: one unit per pixel
    d["target"] = {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale([W / 2, H / 2, 1]),
                   "bsdf": {"type": "diffuse", "reflectance": {
                       "type": "bitmap", "data": mi.TensorXf(rho[labels, 0][..., None]), "raw": True,
                       "filter_type": "nearest", "wrap_mode": "clamp"}}}
    mi_scene = mi.load_dict(d, optimize=False)
    params = mi.traverse(mi_scene)
    Float = type(params["light.irradiance.values"])
    cube = np.empty((H, W, B), dtype=np.float32)
    from ..progress import bar

    for b in bar(range(B), desc="render bands", unit="band", progress=progress):
        params["light.irradiance.values"] = Float(np.full(POINTS_PER_BAND + 1, light_band[b], np.float32))
        params["target.bsdf.reflectance.data"] = mi.TensorXf(rho[labels, b][..., None])
        params.update()
        img = mi.render(mi_scene, params, seed=band_seed(scene.render.seed, b))
        cube[:, :, b] = np.asarray(img)[:, :, 0]
    meta = {"renderer": "mitsuba", "variant": variant, "variant_reason": reason,
            "samples_per_pixel": scene.render.samples_per_pixel, "seed": scene.render.seed,
            "within_band": "light-weighted", "mitsuba_version": mi.__version__}
    return RadianceCube(cube, np.asarray(grid.centres_nm, float), meta)
