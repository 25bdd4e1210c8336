"""Renderers for spatial targets: the image plane sampled finer than the pixel pitch.

Both renderers return a :class:`SubpixelCube`: band-averaged spectral radiance (W·m⁻²·sr⁻¹·nm⁻¹) of
every *sub-pixel*, ``supersampling`` × ``supersampling`` per pixel, averaged over the sub-pixel's area
(a box filter), on the scene's band grid — what :mod:`spectracam.experiments.spatial.optics` turns into pixel
irradiance.

* ``analytic`` — the closed form of each target (:meth:`~spectracam.experiments.spatial.targets.Target.coverage`):
  ``L_b = Σ_m coverage_m · E_b·S_m,b/π``. The camera is a pinhole: a thin lens's defocus is a
  frequency-domain filter of the optics stage where the whole target lies at one depth.
* ``mitsuba`` — Mitsuba 3 (spectral variant) renders the target's shapes with a ``perspective``
  camera, or a ``thinlens`` camera (aperture radius ``f/2N``, focus distance) when any of the target
  is out of focus, so defocus across a tilted chart is real. As :mod:`spectracam.render.mitsuba`, one
  scene and one compiled kernel serve every band (each band's spectra mapped into a fixed reference
  window and updated in place), and the scene is kept and reused for every camera that looks at the
  same target with the same film (only the camera's parameters change).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from spectracam.scene.illuminant import IlluminantSpec, spectral_irradiance
from spectracam.core.spectra import WavelengthGrid, band_average, band_sample_points
from spectracam.experiments.spatial.geometry import CameraGeometry
from spectracam.experiments.spatial.targets import Target

if TYPE_CHECKING:
    from collections.abc import Callable

RENDERERS = ("mitsuba", "analytic")


@dataclass
class SubpixelCube:
    """Band-averaged radiance ``(H·ss, W·ss, B)`` float32 of the sub-pixels of ``geometry``'s image."""

    radiance: np.ndarray
    wavelengths_nm: np.ndarray
    supersampling: int
    geometry: CameraGeometry
    metadata: dict = field(default_factory=dict)

    @property
    def grid(self) -> WavelengthGrid:
        return WavelengthGrid(np.asarray(self.wavelengths_nm, float))

    def pixel_average(self) -> np.ndarray:
        """``(H, W, B)`` radiance averaged over each whole pixel (the ideal image, no optics)."""
        ss = self.supersampling
        h, w, b = self.radiance.shape
        return self.radiance.reshape(h // ss, ss, w // ss, ss, b).mean(axis=(1, 3), dtype=np.float64)

    def band_limited(self) -> np.ndarray:
        """``(H, W, B)`` radiance of the scene band-limited to the pixel grid's Nyquist frequency by an
        ideal low-pass (every spatial frequency below 0.5 cy/px along each axis kept, all above removed)
        and sampled at the pixel centres: the reference against which aliasing counts (Shannon: the
        most of the scene any sampling at this pitch can represent). The sub-pixels' box average is
        divided out (``sinc(f/ss)`` ≥ 0.97 below the Nyquist frequency at ``ss`` ≥ 4, ≥ 0.90 at 2), and the
        image is taken as periodic (the margin the optics stage adds absorbs the wrap-around)."""
        from scipy import fft

        ss = self.supersampling
        hs, ws, nb = self.radiance.shape
        h, w = hs // ss, ws // ss
        ky, kx = np.fft.fftfreq(hs, 1.0 / ss), np.fft.rfftfreq(ws, 1.0 / ss)        # cy/px
        keep_y = np.flatnonzero(np.abs(ky) < 0.5)
        keep_x = np.flatnonzero(kx < 0.5)
        delta = 0.5 - 0.5 / ss        # pixel centre i + ½ against sub-pixel centre (i·ss + ½)/ss, px
        fy, fx = ky[keep_y][:, None], kx[keep_x][None, :]
        gain = np.exp(2j * np.pi * (fy + fx) * delta) / (np.sinc(fy / ss) * np.sinc(fx / ss)) / ss**2
        iy = np.where(ky[keep_y] >= 0, ky[keep_y] * h, ky[keep_y] * h + h).round().astype(int)
        out = np.empty((h, w, nb), np.float64)
        for b in range(nb):
            spectrum = fft.rfft2(self.radiance[:, :, b].astype(np.float64), workers=-1)[np.ix_(keep_y, keep_x)]
            small = np.zeros((h, w // 2 + 1), complex)
            small[iy, :keep_x.size] = spectrum * gain
            out[:, :, b] = fft.irfft2(small, s=(h, w), workers=-1)
        return out


def material_radiance(target: Target, illuminant: IlluminantSpec, grid: WavelengthGrid) -> np.ndarray:
    """``(n_materials, B)`` band-averaged radiance ``E·S/π`` of each material lit along its normal.

    Parameters
    ----------
    target : Target
        Its materials' reflectances S(λ).
    illuminant : IlluminantSpec
        The light's spectral irradiance E(λ).
    grid : WavelengthGrid
        The bands, nm.

    Returns
    -------
    ndarray
        ``(n_materials, B)`` W·m⁻²·sr⁻¹·nm⁻¹ (a Lambertian surface).
    """
    E = spectral_irradiance(illuminant)
    return np.stack([band_average(lambda lam, S=S: E(lam) * S(lam) / np.pi, grid) for _, S in target.materials()])


def render_analytic(target: Target, geometry: CameraGeometry, illuminant: IlluminantSpec, grid: WavelengthGrid,
                    supersampling: int) -> SubpixelCube:
    """The closed form: each sub-pixel mixes the materials in proportion to the area they cover.

    Parameters
    ----------
    target : Target
    geometry : CameraGeometry
        The camera (a pinhole: no defocus here; see :func:`defocus_diameter_um`).
    illuminant : IlluminantSpec
    grid : WavelengthGrid
    supersampling : int
        Sub-pixels per pixel along each axis.

    Returns
    -------
    SubpixelCube
        ``(H·s, W·s, B)`` float32 radiance, W·m⁻²·sr⁻¹·nm⁻¹.
    """
    cov = target.coverage(geometry, supersampling).astype(np.float32)          # (M, Hs, Ws)
    L = material_radiance(target, illuminant, grid).astype(np.float32)         # (M, B)
    cube = np.tensordot(cov, L, axes=([0], [0]))                               # (Hs, Ws, B)
    return SubpixelCube(np.ascontiguousarray(cube, np.float32), np.asarray(grid.centres_nm, float), supersampling,
                        geometry, {"renderer": "analytic", "camera": "pinhole"})


def needs_thinlens(target: Target, geometry: CameraGeometry) -> bool:
    """Is any part of the target away from the focus distance (so a thin lens blurs it)?

    Parameters
    ----------
    target : Target
        Its depth range, where it has one (a tilted chart); else it lies at the object distance.
    geometry : CameraGeometry

    Returns
    -------
    bool
    """
    depth = getattr(target, "depth_range_mm", None)
    if depth is None:
        return abs(geometry.object_distance_mm - geometry.focus) > 1e-9 * geometry.focus
    lo, hi = depth(geometry)
    return not (abs(lo - geometry.focus) < 1e-9 and abs(hi - geometry.focus) < 1e-9)


# Mitsuba scenes kept for reuse: key → (mi scene, params, shape material indices)
_SCENES: dict = {}


def _camera_params(mi, geometry: CameraGeometry):
    T = mi.ScalarTransform4f
    return T().look_at(origin=[0, 0, geometry.object_distance_mm], target=[0, 0, 0], up=[0, 1, 0])


def build_scene(mi, target: Target, geometry: CameraGeometry, supersampling: int, spp: int, width_nm: float,
           thinlens: bool):
    from spectracam.render.mitsuba import POINTS_PER_BAND, REFERENCE_WINDOW_NM, regular_spectrum

    placeholder = np.ones(POINTS_PER_BAND + 1)
    sensor = {"type": "thinlens" if thinlens else "perspective", "fov": geometry.horizontal_fov_deg, "fov_axis": "x",
              "to_world": _camera_params(mi, geometry),
              "near_clip": 1e-2, "far_clip": 10 * geometry.object_distance_mm + 1e4,
              "film": {"type": "specfilm", "width": geometry.width_px * supersampling,
                       "height": geometry.height_px * supersampling, "component_format": "float32",
                       "rfilter": {"type": "box"},
                       "band": {"type": "irregular",
                                "wavelengths": f"{REFERENCE_WINDOW_NM}, {REFERENCE_WINDOW_NM + width_nm}",
                                "values": f"{1 / width_nm}, {1 / width_nm}"}},
              "sampler": {"type": "independent", "sample_count": spp}}
    if thinlens:
        sensor.update(aperture_radius=geometry.aperture_radius_mm, focus_distance=geometry.focus)
    d = {"type": "scene", "integrator": {"type": "direct", "emitter_samples": 1, "bsdf_samples": 0},
         "sensor": sensor,
         "light": {"type": "directional", "direction": target.light_direction(),
                   "irradiance": regular_spectrum(placeholder, width_nm)}}
    materials = {}
    for key, shape, m in target.mitsuba_shapes(mi, geometry):
        bsdf = {"type": "diffuse", "reflectance": regular_spectrum(placeholder, width_nm)}
        if isinstance(m, tuple):   # (material 0, material 1, blend weight bitmap): a blend of two diffuse BSDFs
            m0, m1, weights = m
            bsdf = {"type": "blendbsdf", "bsdf_0": dict(bsdf), "bsdf_1": dict(bsdf),
                    "weight": {"type": "bitmap", "data": mi.TensorXf(np.ascontiguousarray(weights)[..., None]),
                               "raw": True, "filter_type": "bilinear", "wrap_mode": "clamp"}}
            materials[f"{key}/0"], materials[f"{key}/1"] = m0, m1
            d[key] = {**shape, "bsdf": bsdf}
            continue
        if isinstance(shape, dict):
            d[key] = {**shape, "bsdf": bsdf}
        else:  # a triangle mesh (vertices, faces) made here, with its BSDF
            V, F = shape
            props = mi.Properties()
            props["bsdf"] = mi.load_dict(bsdf)
            mesh = mi.Mesh(key, V.shape[0], F.shape[0], props=props)
            p = mi.traverse(mesh)
            p["vertex_positions"] = mi.Float(np.ascontiguousarray(V).ravel())
            p["faces"] = mi.UInt32(np.ascontiguousarray(F).ravel())
            p.update()
            d[key] = mesh
        materials[key] = m
    scene = mi.load_dict(d, optimize=False)
    return scene, mi.traverse(scene), materials


def reflectance_param(key: str) -> str:
    """The Mitsuba parameter of a material key of :func:`build_scene`: ``"dark"`` → the shape's diffuse
    reflectance, ``"plate/1"`` → the second BSDF of the shape's blend."""
    shape, _, nested = key.partition("/")
    return f"{shape}.bsdf.bsdf_{nested}.reflectance.values" if nested else f"{shape}.bsdf.reflectance.values"


def render_mitsuba(target: Target, geometry: CameraGeometry, illuminant: IlluminantSpec, grid: WavelengthGrid,
                   supersampling: int, samples_per_pixel: int = 4, seed: int = 0, variant: str = "auto",
                   log: Callable[[str], object] | None = None, thinlens: bool | None = None) -> SubpixelCube:
    """Mitsuba 3 render of the target, ``samples_per_pixel`` per sub-pixel and band; ``thinlens``: the
    camera (default: a thin lens where any of the target is out of focus, else a perspective pinhole).

    Parameters
    ----------
    target : Target
        Its shapes and materials.
    geometry : CameraGeometry
        The camera's view of it: film, field of view, aperture and focus.
    illuminant : IlluminantSpec
        The light, along the target's normal.
    grid : WavelengthGrid
        The bands, nm; evenly spaced.
    supersampling : int
        Sub-pixels per pixel along each axis.
    samples_per_pixel : int
        Samples per sub-pixel and band.
    seed : int
        Each band's render is seeded from it (:func:`spectracam.render.mitsuba.band_seed`).
    variant : str
        Mitsuba's variant (``"auto"``: chosen for this machine).
    log : callable or None
        ``log(line)``: when a scene is built.
    thinlens : bool or None
        A thin-lens camera (True) or a perspective pinhole (False); None: :func:`needs_thinlens`.

    Returns
    -------
    SubpixelCube
        Radiance, W·m⁻²·sr⁻¹·nm⁻¹, with the variant, camera, samples and seed in its metadata.

    Raises
    ------
    SpectracamError
        When the bands are not evenly spaced.
    """
    from spectracam.core.errors import SpectracamError
    from spectracam.render.mitsuba import activate_variant, select_variant

    variant_name, reason = select_variant(variant)
    mi = activate_variant(variant_name)
    widths = grid.widths_nm
    ref_width = float(widths.max())
    if not np.allclose(widths, ref_width):
        raise SpectracamError(f"wavelengths: Mitsuba renders evenly spaced grids only (bands are "
                              f"{widths.min():g}–{ref_width:g} nm wide)")
    thinlens = needs_thinlens(target, geometry) if thinlens is None else bool(thinlens)
    scene, params, materials = _scene_for_camera(mi, target, geometry, supersampling, samples_per_pixel, ref_width,
                                                 thinlens, variant_name, log)
    shape = (geometry.height_px * supersampling, geometry.width_px * supersampling)
    cube = _render_bands(mi, scene, params, materials, target, illuminant, grid, shape, seed)
    meta = {"renderer": "mitsuba", "variant": variant_name, "variant_reason": reason,
            "camera": "thinlens" if thinlens else "perspective", "samples_per_subpixel": samples_per_pixel,
            "seed": seed, "mitsuba_version": mi.__version__}
    return SubpixelCube(cube, np.asarray(grid.centres_nm, float), supersampling, geometry, meta)


def _scene_for_camera(mi, target: Target, geometry: CameraGeometry, supersampling: int, samples_per_pixel: int,
                      ref_width: float, thinlens: bool, variant_name: str, log: Callable[[str], object] | None):
    """The target's Mitsuba scene (kept in ``_SCENES``, rebuilt for another field of view) with this
    geometry's camera set: ``(scene, params, materials)``."""
    key = (repr(target.to_dict()), geometry.width_px, geometry.height_px, supersampling, samples_per_pixel,
           ref_width, thinlens, variant_name)
    if key not in _SCENES:
        if log:
            log(f"Mitsuba: building the {target.name} scene ({variant_name}, "
                f"{'thinlens' if thinlens else 'perspective'} camera)")
        _SCENES[key] = build_scene(mi, target, geometry, supersampling, samples_per_pixel, ref_width, thinlens)
        # the shapes' size depends on the field of view: built for this geometry; later geometries of the
        # same framing differ only in the camera
        _SCENES[key] = (*_SCENES[key], geometry.field_of_view_mm)
    scene, params, materials, fov_mm = _SCENES[key]
    if not np.allclose(fov_mm, geometry.field_of_view_mm, rtol=1e-9):
        scene, params, materials = build_scene(mi, target, geometry, supersampling, samples_per_pixel, ref_width, thinlens)
        _SCENES[key] = (scene, params, materials, geometry.field_of_view_mm)
    params["sensor.to_world"] = _camera_params(mi, geometry)
    params["sensor.x_fov"] = geometry.horizontal_fov_deg
    if thinlens:
        params["sensor.aperture_radius"] = geometry.aperture_radius_mm
        params["sensor.focus_distance"] = geometry.focus
    params["sensor.far_clip"] = 10 * geometry.object_distance_mm + 1e4
    params.update()
    return scene, params, materials


def _render_bands(mi, scene, params, materials: dict, target: Target, illuminant: IlluminantSpec,
                  grid: WavelengthGrid, shape: tuple[int, int], seed: int) -> np.ndarray:
    """``(Hs, Ws, B)`` float32: one render per band, the light's and the materials' spectra of that band set in
    the scene's parameters."""
    from spectracam.render.mitsuba import POINTS_PER_BAND, band_seed

    E = spectral_irradiance(illuminant)
    spectra = [S for _, S in target.materials()]
    lam = band_sample_points(grid, POINTS_PER_BAND)
    Hs, Ws, B = *shape, len(grid)
    cube = np.empty((Hs, Ws, B), np.float32)
    Float = type(params["light.irradiance.values"])
    for b in range(B):
        params["light.irradiance.values"] = Float(E(lam[b]).astype(np.float32))
        for k, m in materials.items():
            params[reflectance_param(k)] = Float(np.asarray(spectra[m](lam[b]), np.float32))
        params.update()
        img = mi.render(scene, params, seed=band_seed(seed, b))
        cube[:, :, b] = np.asarray(img)[:, :, 0]
    return cube


def render_target(renderer: str, target: Target, geometry: CameraGeometry, illuminant: IlluminantSpec,
                  grid: WavelengthGrid, supersampling: int, samples_per_pixel: int = 4, seed: int = 0,
                  variant: str = "auto", log: Callable[[str], object] | None = None) -> SubpixelCube:
    """Render with ``renderer`` (``"mitsuba"`` or ``"analytic"``).

    Parameters
    ----------
    renderer : str
    target : Target
    geometry : CameraGeometry
    illuminant : IlluminantSpec
    grid : WavelengthGrid
    supersampling : int
        Sub-pixels per pixel along each axis.
    samples_per_pixel, seed : int
        Mitsuba's samples per sub-pixel and band, and its seed.
    variant : str
        Mitsuba's variant (``"auto"``: chosen for this machine).
    log : callable or None
        Mitsuba's notices.

    Returns
    -------
    SubpixelCube
        Radiance, W·m⁻²·sr⁻¹·nm⁻¹.

    Raises
    ------
    ConfigError
        For another renderer.
    """
    from spectracam.core.errors import ConfigError

    if renderer == "analytic":
        return render_analytic(target, geometry, illuminant, grid, supersampling)
    if renderer == "mitsuba":
        return render_mitsuba(target, geometry, illuminant, grid, supersampling, samples_per_pixel, seed, variant, log)
    raise ConfigError("renderer", renderer, "must be one of " + ", ".join(RENDERERS))


def defocus_diameter_um(target: Target, geometry: CameraGeometry, cube: SubpixelCube) -> float:
    """Blur-disc diameter the optics stage must still apply, µm: the thin lens's defocus of a target at
    one depth when the renderer did not render it (the analytic pinhole); 0 otherwise.

    Parameters
    ----------
    target : Target
    geometry : CameraGeometry
    cube : SubpixelCube
        Its metadata say which camera rendered it.

    Returns
    -------
    float
        µm.
    """
    if cube.metadata.get("camera") == "thinlens" or getattr(target, "depth_range_mm", None) is not None:
        return 0.0
    return float(geometry.blur_diameter_um(geometry.object_distance_mm))


__all__ = ["RENDERERS", "SubpixelCube", "defocus_diameter_um", "material_radiance", "needs_thinlens",
           "render_analytic", "render_mitsuba", "render_target"]
