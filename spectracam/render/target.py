"""Rendering a textured target (:mod:`spectracam.scene.target`): the closed form and Mitsuba.

The target is a Lambertian plane facing the light, filling the view; texel (i, j) has the reflectance
of the sample its label names.  Closed form: each pixel's band radiance is the mean of ``E·S/π`` over
its s × s texels (:meth:`~spectracam.scene.reference.TargetReference.pixel_mean`).  Mitsuba: one rectangle
with a nearest-neighbour ``bitmap`` texture of the texel grid; per band the light is the band average
``Ē`` and each texel's value the light-weighted band average ``⟨E·S⟩/⟨E⟩`` of its sample (as the
chart's patches, :mod:`spectracam.render.mitsuba`), so a pixel inside one sample is exact.  Values
are updated per band in the one compiled scene.

Sample positions (issue 34).  Every band is traced through the *same* positions in each pixel, so an
edge pixel's spectrum is a convex mixture of its texels' spectra with one set of weights for every
band.  Before, each band drew new positions (``independent`` sampler, a new seed per band): at 4 spp
an edge pixel's weights differed band to band (rms 25 % per band, uncorrelated), its spectrum was no
mixture of the spectra it shows.  Which positions: the texture is constant on each texel and the
film's box filter averages over the pixel, so the pixel integral is *exactly* the mean over its
s × s texel centres (the midpoint rule is exact for a function constant on each cell).  The default
sampler (``"texels"``) is therefore Mitsuba's ``stratified`` sampler with s² samples per pixel and
no jitter, whose samples are the centres of an s × s grid of strata (Mitsuba 3 documentation,
"Stratified sampler"; Pharr, Jakob & Humphreys, PBRT 3rd ed., 7.3): one ray per texel centre, and
the render equals the closed form to float32 rounding everywhere, edges included (scene
``render.samples_per_pixel`` does not apply; it costs s² rays per pixel, 3.5× the default 4-spp
render's time at s = 4).  Why not the Monte Carlo with one seed: a coverage estimated from 4 random
positions is off by up to ±0.25 in every band *together*, so against the area-weighted truth the
colour error grows (dead leaves 640×480, field-sequential, every sensor noise off, per-pixel ΔE*ab
mean / max: closed form 6.82 / 24.5; per-band seeds 7.26 / 43.8; one seed 7.90 / 91.8; texel
centres 6.82 / 24.5).  ``sampler="independent"`` keeps it (``render.samples_per_pixel`` random
positions, the seed :func:`texture_seed` for every band) to show the Monte Carlo's behaviour.
"""
from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from spectracam.core.errors import SpectracamError
from spectracam.scene.illuminant import spectral_irradiance
from spectracam.scene.reference import TargetReference
from spectracam.core.spectra import band_average
from spectracam.render.analytic import lights_metadata
from spectracam.render.cube import RadianceCube

if TYPE_CHECKING:
    from spectracam.pipeline.scene_file import Scene

__all__ = ["SAMPLERS", "TEXTURE_SEED_STREAM", "render_target_analytic", "render_target_mitsuba",
           "texture_seed"]


#: Where a textured Mitsuba render places each pixel's samples, the same in every band (module docstring):
#: "texels" — one at each texel centre (exact); "independent" — ``render.samples_per_pixel`` random positions.
SAMPLERS = ("texels", "independent")
#: The seed-sequence stream of :func:`texture_seed` (the sensor uses 1 and 2: spectracam.sensor).
TEXTURE_SEED_STREAM = 34


def texture_seed(seed: int) -> int:
    """The one 32-bit Mitsuba sampler seed of every band of a textured render from the scene's ``seed``
    (its own stream of the seed sequence, apart from the sensor's noise streams).

    Parameters
    ----------
    seed : int
        The scene's ``render.seed``.

    Returns
    -------
    int
        The sampler seed, 0 … 2³² − 1.
    """
    return int(np.random.SeedSequence([seed, TEXTURE_SEED_STREAM]).generate_state(1)[0])


def render_target_analytic(scene: Scene) -> RadianceCube:
    """A textured target's radiance cube in closed form: each pixel the mean of its texels' ``E·S/π`` (with light
    groups, each label's ``E_g·S/π`` under its group's light).

    Parameters
    ----------
    scene : Scene
        A scene with a textured target.

    Returns
    -------
    RadianceCube
        ``(H, W, B)`` float32 band-averaged radiance, W·m⁻²·sr⁻¹·nm⁻¹.
    """
    ref = TargetReference.of(scene)
    cube = ref.pixel_mean(ref.radiance, np.float32)
    meta = {"renderer": "analytic", "variant": None, "samples_per_pixel": None, "seed": scene.render.seed,
            **lights_metadata(scene)}
    return RadianceCube(cube, np.asarray(scene.grid.centres_nm, float), meta)


def render_target_mitsuba(scene: Scene, progress: bool = False, log: Callable[[str], object] | None = None,
                          sampler: str = "texels") -> RadianceCube:
    """A textured target's radiance cube rendered by Mitsuba band by band, one sampler seed for every band.

    Parameters
    ----------
    scene : Scene
        A scene with a textured target.
    progress : bool
        Draw a bar over the bands.
    log : callable or None
        Receives one-line notices (the Mitsuba variant chosen).
    sampler : str
        ``"texels"``: one unjittered sample at each texel's centre; ``"independent"``: the scene's samples per pixel.

    Returns
    -------
    RadianceCube
        ``(H, W, B)`` float32 band-averaged radiance, W·m⁻²·sr⁻¹·nm⁻¹, with the render's metadata.
    """
    from spectracam.render.mitsuba import (POINTS_PER_BAND, band_scene, load_scene, open_variant, render_bands,
                                           render_metadata)

    if sampler not in SAMPLERS:
        raise SpectracamError(f"sampler = {sampler!r}: must be one of " + ", ".join(map(repr, SAMPLERS)))
    mi, variant, reason, width_nm = open_variant(scene, log)
    grid = scene.grid
    ref = TargetReference.of(scene)
    W, H = scene.image.width, scene.image.height
    groups = _group_tables(scene, ref)
    light_band, rho = groups[0]
    labels = ref.labels[::-1]          # a bitmap's first row is the top of the texture's v axis: the bottom row
    d = band_scene(mi, scene, W, width_nm)          # the view is W × H units: one unit per pixel
    spp = scene.render.samples_per_pixel
    if sampler == "texels":                          # s × s strata, samples at their centres: the texel centres
        spp = ref.supersampling ** 2
        d["sensor"]["sampler"] = {"type": "stratified", "sample_count": spp, "jitter": False}
    d["target"] = {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale([W / 2, H / 2, 1]),
                   "bsdf": {"type": "diffuse", "reflectance": {
                       "type": "bitmap", "data": mi.TensorXf(rho[labels, 0][..., None]), "raw": True,
                       "filter_type": "nearest", "wrap_mode": "clamp"}}}
    mi_scene, params = load_scene(mi, d)
    Float = type(params["light.irradiance.values"])
    seed = texture_seed(scene.render.seed)          # one seed for every band: the positions repeat (docstring)

    def set_band(b, k=0):
        light_band, rho = groups[k]
        params["light.irradiance.values"] = Float(np.full(POINTS_PER_BAND + 1, light_band[b], np.float32))
        params["target.bsdf.reflectance.data"] = mi.TensorXf(rho[labels, b][..., None])

    if len(groups) == 1:
        cube = render_bands(mi, mi_scene, params, scene, set_band, lambda b: seed, progress)
        more = lights_metadata(scene)
    else:   # one render per light group, the other groups' labels black, summed (light groups)
        cube = sum(render_bands(mi, mi_scene, params, scene, lambda b, k=k: set_band(b, k), lambda b: seed, progress)
                   for k in range(len(groups)))
        more = {"light_groups": "one render per group and band, summed", **lights_metadata(scene)}
    meta = render_metadata(mi, variant, reason, spp, scene.render.seed, "light-weighted", sampler=sampler,
                           sample_positions="the same in every band", **more)
    return RadianceCube(cube, np.asarray(grid.centres_nm, float), meta)


def _group_tables(scene, ref: TargetReference) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per light group (one without groups): ``(⟨E_g⟩ per band (B,), ρ̄ (n + 1, B) float32)``, the light's band
    average and each label's light-weighted band reflectance ``⟨E_g·S⟩/⟨E_g⟩`` — 0 for the labels of the other
    groups, so one render with group g's light shows only its labels."""
    lights = [scene.illuminant] if not scene.lights else [g.illuminant for g in scene.lights]
    out = []
    for k, illuminant in enumerate(lights):
        light_band = band_average(spectral_irradiance(illuminant), scene.grid)       # ⟨E⟩ per band
        with np.errstate(invalid="ignore", divide="ignore"):                        # ⟨E·S⟩/⟨E⟩: 0 without light
            rho = np.nan_to_num(ref.radiance * np.pi / light_band[None]).astype(np.float32)   # (n + 1, B)
        if ref.groups is not None:
            rho[ref.groups != k] = 0.0
        out.append((light_band, rho))
    return out
