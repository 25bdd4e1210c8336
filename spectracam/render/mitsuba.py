"""Mitsuba 3 renderer (spectral variant) for the chart scene, built programmatically.

How bands are rendered
----------------------
``specfilm`` draws each path's wavelengths from the response it was *built* with and does not
re-derive that distribution when the response is updated, and a newly built scene compiles a new
kernel (~0.1 s each).  So the scene is built once, with a film whose single channel is a box of
height 1/w over a fixed reference window ``[REFERENCE_WINDOW_NM, +w]``, and every spectrum in it
(illuminant irradiance, 24 reflectances) is a spectrum over that window whose values are *updated
per band*, so one compiled kernel serves every band.

What each band holds: the film records ``(1/w)∫ E·S/π dλ`` over the window.  Were the light and the
reflectances handed over as they vary inside the band, every path would sample one wavelength of
the product ``E(λ)·S(λ)`` and the pixel would carry its Monte Carlo spread (0.2–0.5 % per pixel at
4 samples, measured: it showed as 0.07 ΔE in Figure 6's noise-free step).  Instead the light is the
band average ``Ē = ⟨E⟩`` and each surface's reflectance the light-weighted band average
``S̄ = ⟨E·S⟩/⟨E⟩`` — both constant over the window — so ``Ē·S̄/π = ⟨E·S⟩/π`` is exactly the band
average the film records, with no spread from sampling wavelengths (``S̄`` is a weighted mean of
``S``, so it stays in [0, 1]).  Nothing in this scene depends on wavelength except the spectra
(Lambertian BSDFs, a delta-direction light), so the remapping is exact; what Monte Carlo is left is
the pixel footprint (anti-aliasing at the patch edges), whose expectation is the analytic
renderer's area-weighted mix.
"""
from __future__ import annotations

import weakref

import ctypes.util
import glob
import os
import subprocess
import sys
from collections.abc import Callable
from functools import lru_cache
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np

from spectracam.scene.chart import View, patch_rectangles_mm, patch_reflectances
from spectracam.core.errors import SpectracamError
from spectracam.scene.illuminant import spectral_irradiance
from spectracam.core.spectra import band_average, band_sample_points
from spectracam.render.analytic import lights_metadata
from spectracam.render.cube import ChannelPlanes, RadianceCube, add_band

if TYPE_CHECKING:
    from spectracam.core.spectra import WavelengthGrid
    from spectracam.pipeline.scene_file import Scene
    from spectracam.scene.reference import ChartCell

__all__ = ["CAMERA_DISTANCE_MM", "PATCH_LIFT_MM", "POINTS_PER_BAND", "REFERENCE_WINDOW_NM", "VARIANT_NAMES",
           "WITHIN_BAND", "activate_variant", "band_scene", "band_seed", "build_lights_scene", "build_scene",
           "even_band_width_nm", "find_libllvm19", "load_scene", "open_variant", "probe_variant", "regular_spectrum",
           "render_bands", "render_lights_mitsuba", "render_metadata", "render_mitsuba", "run_probe",
           "select_variant"]

#: Start of the reference wavelength window every band is mapped into (any visible value works).
REFERENCE_WINDOW_NM = 500.0
#: Linear segments per band in the spectra handed to Mitsuba (0.5 nm for 10 nm bands).
POINTS_PER_BAND = 20
#: Height of the patches above the board, mm, so that the board never pokes through a patch.
PATCH_LIFT_MM = 0.01
#: Distance of the orthographic camera from the chart, mm (irrelevant to the image).
CAMERA_DISTANCE_MM = 1000.0

VARIANT_NAMES = {"llvm": "llvm_ad_spectral", "scalar": "scalar_spectral", "cuda": "cuda_ad_spectral"}

_LLVM19_GLOBS = ("/usr/lib/x86_64-linux-gnu/libLLVM-19.so*", "/usr/lib/aarch64-linux-gnu/libLLVM-19.so*",
                 "/usr/lib/llvm-19/lib/libLLVM*.so*", "/usr/lib64/libLLVM-19.so*")

_PROBE = r"""
import mitsuba as mi, numpy as np, sys
mi.set_variant(sys.argv[1])
box = {'type': 'irregular', 'wavelengths': '500, 510', 'values': '0.1, 0.1'}
s = mi.load_dict({'type': 'scene', 'integrator': {'type': 'direct'},
    'sensor': {'type': 'orthographic', 'film': {'type': 'specfilm', 'width': 4, 'height': 4, 'b': box,
               'component_format': 'float32'}, 'to_world': mi.ScalarTransform4f().look_at(
               origin=[0, 0, 1], target=[0, 0, 0], up=[0, 1, 0])},
    'r': {'type': 'rectangle', 'to_world': mi.ScalarTransform4f().scale(3),
          'bsdf': {'type': 'diffuse', 'reflectance': {'type': 'uniform', 'value': 0.5}}},
    'e': {'type': 'directional', 'direction': [0, 0, -1], 'irradiance': {'type': 'uniform', 'value': 3.14159265}}})
v = float(np.mean(np.array(mi.render(s))))
sys.exit(0 if abs(v - 0.5) < 1e-3 else 3)
"""


def find_libllvm19() -> str | None:
    """Path of a libLLVM 19 shared library on this machine, if any (drjit 1.5 needs libLLVM 19; with libLLVM 15
    the first render aborts the process)."""
    for pattern in _LLVM19_GLOBS:
        hits = sorted(glob.glob(pattern))
        if hits:
            return hits[0]
    return None


def _jit_env() -> dict:
    env = dict(os.environ)
    if "DRJIT_LIBLLVM_PATH" not in env:
        lib = find_libllvm19()
        if lib:
            env["DRJIT_LIBLLVM_PATH"] = lib
    return env


def run_probe(variant: str, env: dict) -> bool:
    """Render a 4x4 test scene with ``variant`` in a subprocess with ``env``; True if it gives the right value.

    A subprocess, because with the wrong libLLVM (drjit 1.5 needs 19; 15 aborts) the first render aborts the
    whole process.

    Parameters
    ----------
    variant : str
        A Mitsuba variant (``"llvm_ad_spectral"``).
    env : dict
        The subprocess's environment (where drjit finds libLLVM).

    Returns
    -------
    bool
        True if the test render ran and gave the right value within 300 s.
    """
    try:
        r = subprocess.run([sys.executable, "-c", _PROBE, variant], env=env, capture_output=True, timeout=300)
    except (subprocess.TimeoutExpired, OSError):
        return False
    return r.returncode == 0


@lru_cache(maxsize=None)
def probe_variant(variant: str) -> bool:
    """Does ``variant`` actually render here (probed once per process)?

    Parameters
    ----------
    variant : str
        A Mitsuba variant.

    Returns
    -------
    bool
        :func:`run_probe`'s answer with the libLLVM drjit should use.
    """
    return run_probe(variant, _jit_env())


def _gpu_present() -> bool:
    return bool(ctypes.util.find_library("cuda")) or os.path.exists("/dev/nvidia0")


def select_variant(requested: str) -> tuple[str, str]:
    """Resolve ``auto|llvm|scalar|cuda`` to a Mitsuba variant that renders here, and say why.

    Parameters
    ----------
    requested : str
        ``render.variant``: ``"auto"`` (CUDA if a GPU renders, else LLVM if it renders, else scalar) or a backend
        asked for by name (refused in one line where it does not render).

    Returns
    -------
    tuple of str
        The Mitsuba variant and the reason it was chosen.
    """
    if requested == "auto":
        if _gpu_present() and probe_variant(VARIANT_NAMES["cuda"]):
            return VARIANT_NAMES["cuda"], "auto: a CUDA GPU renders"
        if probe_variant(VARIANT_NAMES["llvm"]):
            return VARIANT_NAMES["llvm"], "auto: no working CUDA GPU; the LLVM backend renders"
        return VARIANT_NAMES["scalar"], ("auto: no working CUDA GPU and the LLVM backend does not render "
                                         "(it needs libLLVM 19: install Debian's libllvm19 or set "
                                         "DRJIT_LIBLLVM_PATH); falling back to the slow scalar variant")
    name = VARIANT_NAMES[requested]
    if requested != "scalar" and not probe_variant(name):
        hint = ("it needs libLLVM 19: install Debian's libllvm19 or set DRJIT_LIBLLVM_PATH" if requested == "llvm"
                else "no working CUDA GPU/driver")
        raise SpectracamError(f"render.variant = {requested!r}: {name} does not render on this machine ({hint}); "
                              "use 'auto' or 'scalar'")
    return name, f"requested: {requested}"


def activate_variant(variant: str) -> ModuleType:
    """Mitsuba, imported with drjit pointed at a libLLVM 19 where one is found, with ``variant`` set.

    Parameters
    ----------
    variant : str
        A Mitsuba variant that renders here (:func:`select_variant`).

    Returns
    -------
    ModuleType
        The ``mitsuba`` module.
    """
    env = _jit_env()
    if "DRJIT_LIBLLVM_PATH" in env:
        os.environ.setdefault("DRJIT_LIBLLVM_PATH", env["DRJIT_LIBLLVM_PATH"])
    import mitsuba as mi

    if mi.variant() != variant:
        mi.set_variant(variant)
    return mi


def regular_spectrum(values: np.ndarray, width_nm: float) -> dict:
    """A Mitsuba ``regular`` spectrum of ``values`` spread evenly over the reference window.

    Parameters
    ----------
    values : ndarray
        The values, from the window's start to its end.
    width_nm : float
        The window's width (the bands' width), nm.

    Returns
    -------
    dict
        The spectrum's plug-in dictionary.
    """
    return {"type": "regular", "wavelength_min": REFERENCE_WINDOW_NM,
            "wavelength_max": REFERENCE_WINDOW_NM + width_nm,
            "values": ", ".join(f"{v:.9g}" for v in values)}


def even_band_width_nm(grid: WavelengthGrid) -> float:
    """The one band width of an evenly spaced grid (every band is mapped into one reference window).

    Parameters
    ----------
    grid : WavelengthGrid
        The scene's bands (bands of unequal width are refused).

    Returns
    -------
    float
        The width, nm.
    """
    widths = grid.widths_nm
    width_nm = float(widths.max())
    if not np.allclose(widths, width_nm):
        raise SpectracamError(f"wavelengths: Mitsuba renders evenly spaced grids only (bands are "
                              f"{widths.min():g}–{width_nm:g} nm wide)")
    return width_nm


def band_scene(mi: ModuleType, scene: Scene, view_width: float, width_nm: float) -> dict:
    """What every band render shares: the direct integrator, an orthographic camera looking down at a
    view ``view_width`` wide (the image's aspect) with a one-band ``specfilm`` over the reference window,
    and a directional light whose irradiance is updated per band.

    Parameters
    ----------
    mi : ModuleType
        Mitsuba, its variant set.
    scene : Scene
        The scene (image size, samples per pixel).
    view_width : float
        The view's width in world units.
    width_nm : float
        The bands' width, nm.

    Returns
    -------
    dict
        The scene dictionary's integrator, sensor and light.
    """
    T = mi.ScalarTransform4f
    return {
        "type": "scene",
        "integrator": {"type": "direct", "emitter_samples": 1, "bsdf_samples": 0},
        "sensor": {
            "type": "orthographic",
            # Mitsuba's orthographic camera images x ∈ [-1, 1], y ∈ [-1/aspect, 1/aspect], scaled by
            # to_world: a uniform scale of half the view width gives square pixels.
            "to_world": T().look_at(origin=[0, 0, CAMERA_DISTANCE_MM], target=[0, 0, 0], up=[0, 1, 0])
            @ T().scale([view_width / 2, view_width / 2, 1]),
            "film": {"type": "specfilm", "width": scene.image.width, "height": scene.image.height,
                     "component_format": "float32", "rfilter": {"type": "box"},
                     "band": {"type": "irregular",
                              "wavelengths": f"{REFERENCE_WINDOW_NM}, {REFERENCE_WINDOW_NM + width_nm}",
                              "values": f"{1 / width_nm}, {1 / width_nm}"}},
            "sampler": {"type": "independent", "sample_count": scene.render.samples_per_pixel},
        },
        "light": {"type": "directional", "direction": [0, 0, -1],
                  "irradiance": regular_spectrum(np.ones(POINTS_PER_BAND + 1), width_nm)},
    }


def build_scene(mi: ModuleType, scene: Scene, width_nm: float) -> dict:
    """The Mitsuba scene dictionary: board, 24 patches, a directional light, an orthographic camera.

    Parameters
    ----------
    mi : ModuleType
        Mitsuba, its variant set.
    scene : Scene
        A chart scene; world units are mm of the chart plane.
    width_nm : float
        The bands' width, nm.

    Returns
    -------
    dict
        The scene dictionary (placeholder spectra, set per band).
    """
    view = View.fit(scene.chart, scene.image.width, scene.image.height)
    vw, vh = view.size_mm
    T = mi.ScalarTransform4f
    placeholder = np.ones(POINTS_PER_BAND + 1)
    d = band_scene(mi, scene, vw, width_nm)
    d["board"] = {"type": "rectangle", "to_world": T().scale([vw, vh, 1]),
                  "bsdf": {"type": "diffuse", "reflectance": regular_spectrum(placeholder, width_nm)}}
    for p, (x0, x1, y0, y1) in enumerate(patch_rectangles_mm(scene.chart)):
        d[f"patch{p:02d}"] = {
            "type": "rectangle",
            "to_world": T().translate([(x0 + x1) / 2, (y0 + y1) / 2, PATCH_LIFT_MM]) @ T().scale([(x1 - x0) / 2, (y1 - y0) / 2, 1]),
            "bsdf": {"type": "diffuse", "reflectance": regular_spectrum(placeholder, width_nm)},
        }
    return d


def band_seed(seed: int, band: int) -> int:
    """Independent, reproducible 32-bit sampler seed for each band of one render.

    Parameters
    ----------
    seed : int
        The scene's ``render.seed``.
    band : int
        The band's index.

    Returns
    -------
    int
        The sampler seed, 0 … 2³² − 1.
    """
    return int(np.random.SeedSequence([seed, band]).generate_state(1)[0])


#: How the spectra vary inside a band: "light-weighted" (constant ⟨E⟩ and ⟨E·S⟩/⟨E⟩: no sampling
#: noise, the default) or "sampled" (E(λ) and S(λ) as they vary: each path samples one wavelength,
#: the method before issue 17, kept for tools/bench_render.py and the tests that measure the noise).
WITHIN_BAND = ("light-weighted", "sampled")


#: The variant each log was last told of, so a run that renders several scenes says it once.
_SAID: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def _said(log):
    try:
        return _SAID.get(log)
    except TypeError:
        return None


def open_variant(scene: Scene, log: Callable[[str], object] | None = None) -> tuple[ModuleType, str, str, float]:
    """``(mi, variant, reason, band width nm)``: Mitsuba with the variant ``scene.render.variant`` resolves
    to active (said to ``log``), and the one band width of ``scene``'s grid (evenly spaced grids only).

    Parameters
    ----------
    scene : Scene
        The scene (its ``render.variant`` and wavelength grid).
    log : callable or None
        Told the variant, once per log and variant.

    Returns
    -------
    tuple of (ModuleType, str, str, float)
        Mitsuba, the variant, why it was chosen, and the bands' width in nm.
    """
    variant, reason = select_variant(scene.render.variant)
    if log and _said(log) != variant:   # once per log and variant: a paper run renders six lights
        log(f"Mitsuba variant {variant} ({reason})")
        try:
            _SAID[log] = variant
        except TypeError:                # a log that cannot be weakly referenced: said every time
            pass
    mi = activate_variant(variant)
    return mi, variant, reason, even_band_width_nm(scene.grid)


def load_scene(mi: ModuleType, d: dict) -> tuple[object, object]:
    """``(mi_scene, params)`` of a scene dictionary.  optimize=False: the loader would otherwise merge
    rectangles with identical placeholder BSDFs into one mesh, and their spectra could no longer be
    updated per band.

    Parameters
    ----------
    mi : ModuleType
        Mitsuba, its variant set.
    d : dict
        The scene dictionary.

    Returns
    -------
    mi_scene : mitsuba.Scene
        The loaded scene.
    params : mitsuba.SceneParameters
        Its parameters (``mi.traverse``), updated per band.
    """
    mi_scene = mi.load_dict(d, optimize=False)
    return mi_scene, mi.traverse(mi_scene)


def render_bands(mi: ModuleType, mi_scene: object, params: object, scene: Scene, set_band: Callable[[int], object],
                 seed: Callable[[int], int], progress: bool = False,
                 weights: np.ndarray | None = None) -> np.ndarray:
    """The ``(H, W, B)`` float32 cube of ``scene``'s image and grid from the one compiled scene: per
    band ``b``, ``set_band(b)`` writes its spectra into ``params``, then one render with sampler seed
    ``seed(b)``.  With ``weights``, each band's image is added into the planes as it is rendered instead: no cube is
    held (:class:`spectracam.render.cube.ChannelPlanes`).

    Parameters
    ----------
    mi : ModuleType
        Mitsuba, its variant set.
    mi_scene : mitsuba.Scene
        The loaded scene.
    params : mitsuba.SceneParameters
        Its parameters.
    scene : Scene
        The scene (image size, bands).
    set_band : callable
        Writes band ``b``'s spectra into ``params``.
    seed : callable
        Band index → sampler seed.
    progress : bool
        Draw a bar over the bands.
    weights : ndarray or None
        ``(B, N)``: ``planes[k] += weights[b, k] · L_b`` for each band ``b`` as it is rendered.

    Returns
    -------
    ndarray
        ``(H, W, B)`` float32 band-averaged radiance, W·m⁻²·sr⁻¹·nm⁻¹; with ``weights``, the ``(N, H, W)`` float32
        planes.
    """
    from spectracam.core.progress import bar

    H, W, B = scene.image.height, scene.image.width, len(scene.grid)
    if weights is None:
        out = np.empty((H, W, B), dtype=np.float32)
    else:
        w = np.asarray(weights, np.float32)
        out = np.zeros((w.shape[1], H, W), dtype=np.float32)
    # a bar on a terminal only; a log (stderr redirected) gets the one line the caller writes per stage
    for b in bar(range(B), desc="render bands", unit="band", progress=progress):
        set_band(b)
        params.update()
        img = np.asarray(mi.render(mi_scene, params, seed=seed(b)))[:, :, 0]
        if weights is None:
            out[:, :, b] = img
            continue
        add_band(out, img, w[b])
    return out


def render_metadata(mi: ModuleType, variant: str, reason: str, samples_per_pixel: int, seed: int, within_band: str,
                    **more: object) -> dict:
    """A Mitsuba cube's ``metadata`` (``more``: the caller's own entries, before the version).

    Parameters
    ----------
    mi : ModuleType
        Mitsuba (its version is recorded).
    variant, reason : str
        The variant and why it was chosen.
    samples_per_pixel, seed : int
        The sampler's samples per pixel and the scene's seed.
    within_band : str
        How spectra were handled within a band (``"light-weighted"`` or ``"sampled"``).
    **more : object
        The caller's own entries.

    Returns
    -------
    dict
        The metadata.
    """
    return {"renderer": "mitsuba", "variant": variant, "variant_reason": reason,
            "samples_per_pixel": samples_per_pixel, "seed": seed, "within_band": within_band, **more,
            "mitsuba_version": mi.__version__}


def _no_planes(scene: Scene) -> ChannelPlanes:
    """Refuse channel planes of a scene of light groups (each group is rendered and summed per band)."""
    raise SpectracamError(f"lights = {len(scene.lights)} light groups: channel planes are rendered for one light")


def render_mitsuba(scene: Scene, progress: bool = False, log: Callable[[str], object] | None = None,
                   within_band: str = "light-weighted",
                   weights: np.ndarray | None = None) -> RadianceCube | ChannelPlanes:
    """The chart scene's radiance cube by Mitsuba (module docstring); a scene of several light groups by
    :func:`render_lights_mitsuba`.

    Parameters
    ----------
    scene : Scene
        A chart scene.
    progress : bool
        Draw a bar over the bands.
    log : callable or None
        Told the Mitsuba variant chosen.
    within_band : str
        ``"light-weighted"`` (light-weighted band-average reflectances: exact) or ``"sampled"`` (spectra sampled).
    weights : ndarray or None
        ``(B, N)``, one light: each band added into channel planes as it is rendered (:func:`render_bands`).

    Returns
    -------
    RadianceCube or ChannelPlanes
        ``(H, W, B)`` float32 band-averaged radiance, W·m⁻²·sr⁻¹·nm⁻¹; with ``weights``, ``(H, W, N)`` planes.
    """
    if within_band not in WITHIN_BAND:
        raise SpectracamError(f"within_band = {within_band!r}: must be one of " + ", ".join(map(repr, WITHIN_BAND)))
    if len(scene.lights) > 1:
        return render_lights_mitsuba(scene, progress, log, within_band) if weights is None else _no_planes(scene)
    mi, variant, reason, ref_width = open_variant(scene, log)
    mi_scene, params = load_scene(mi, build_scene(mi, scene, ref_width))
    E = spectral_irradiance(scene.illuminant)
    reflectances = patch_reflectances(scene.chart)
    lam = band_sample_points(scene.grid, POINTS_PER_BAND)  # (B, N+1), for "sampled"
    light_band = band_average(E, scene.grid)  # ⟨E⟩ per band (B,)
    # light-weighted band-average reflectances ⟨E·S⟩/⟨E⟩ (module docstring); 0 where the light is 0
    with np.errstate(invalid="ignore", divide="ignore"):
        rho_band = [np.nan_to_num(band_average(lambda lam, rho=rho: E(lam) * rho(lam), scene.grid) / light_band)
                    for _, rho in reflectances]
    Float = type(params["board.bsdf.reflectance.values"])  # mi.Float, or a buffer type in scalar variants
    params["board.bsdf.reflectance.values"] = Float(np.full(POINTS_PER_BAND + 1, scene.chart.surround_reflectance))

    def set_band(b):
        if within_band == "sampled":
            params["light.irradiance.values"] = Float(E(lam[b]).astype(np.float32))
            for p, (_, rho) in enumerate(reflectances):
                params[f"patch{p:02d}.bsdf.reflectance.values"] = Float(rho(lam[b]).astype(np.float32))
        else:
            params["light.irradiance.values"] = Float(np.full(POINTS_PER_BAND + 1, light_band[b], np.float32))
            for p, rho in enumerate(rho_band):
                params[f"patch{p:02d}.bsdf.reflectance.values"] = Float(np.full(POINTS_PER_BAND + 1, rho[b],
                                                                                np.float32))

    out = render_bands(mi, mi_scene, params, scene, set_band, lambda b: band_seed(scene.render.seed, b), progress,
                       weights)
    meta = render_metadata(mi, variant, reason, scene.render.samples_per_pixel, scene.render.seed, within_band,
                           **lights_metadata(scene))
    if weights is None:
        return RadianceCube(out, np.asarray(scene.grid.centres_nm, float), meta)
    return ChannelPlanes(np.moveaxis(out, 0, -1).copy(), np.asarray(scene.grid.centres_nm, float),
                         np.asarray(weights, float), meta)


def build_lights_scene(mi: ModuleType, scene: Scene, cells: list[ChartCell], width_nm: float) -> dict:
    """The Mitsuba scene of a light-group chart scene: per cell (:func:`spectracam.scene.reference.chart_cells`) a
    board covering the cell and 24 patches, the chart fitted and centred in the cell as the one-chart scene is in
    the image; one directional light.  World units are pixels (the view is the image, W × H units), origin at
    the image centre, y up.

    Parameters
    ----------
    mi : ModuleType
        Mitsuba, its variant set.
    scene : Scene
        The scene.
    cells : list of ChartCell
        Its chart cells.
    width_nm : float
        The bands' width, nm.

    Returns
    -------
    dict
        The scene dictionary (spectra to be set per band).
    """
    W, H = scene.image.width, scene.image.height
    T = mi.ScalarTransform4f
    d = band_scene(mi, scene, W, width_nm)
    black = {"type": "diffuse", "reflectance": {"type": "uniform", "value": 0.0}}   # a regular spectrum may not be 0
    for k, cell in enumerate(cells):
        cw, ch = cell.cols.stop - cell.cols.start, cell.rows.stop - cell.rows.start
        mm = View.fit(scene.chart, cw, ch).pixel_mm
        cx, cy = (cell.cols.start + cell.cols.stop - W) / 2, (H - cell.rows.start - cell.rows.stop) / 2
        d[f"board{k:02d}"] = {"type": "rectangle", "bsdf": dict(black),
                              "to_world": T().translate([cx, cy, 0]) @ T().scale([cw / 2, ch / 2, 1])}
        for p, (x0, x1, y0, y1) in enumerate(patch_rectangles_mm(scene.chart)):
            d[f"g{k:02d}p{p:02d}"] = {
                "type": "rectangle",
                "to_world": T().translate([cx + (x0 + x1) / 2 / mm, cy + (y0 + y1) / 2 / mm, PATCH_LIFT_MM])
                @ T().scale([(x1 - x0) / 2 / mm, (y1 - y0) / 2 / mm, 1]), "bsdf": dict(black)}
    return d


def _group_spectra(scene, illuminant) -> tuple[np.ndarray, np.ndarray]:
    """``(⟨E⟩ (B,), ⟨E·S⟩/⟨E⟩ (24, B))``: the light's band averages and the patches' light-weighted band
    reflectances under ``illuminant``, as :func:`render_mitsuba` sets them (0 where the light is 0)."""
    E = spectral_irradiance(illuminant)
    light_band = band_average(E, scene.grid)
    with np.errstate(invalid="ignore", divide="ignore"):
        rho = np.array([np.nan_to_num(band_average(lambda lam, rho=rho: E(lam) * rho(lam), scene.grid) / light_band)
                        for _, rho in patch_reflectances(scene.chart)])
    return light_band, rho


def render_lights_mitsuba(scene: Scene, progress: bool = False, log: Callable[[str], object] | None = None,
                          within_band: str = "light-weighted") -> RadianceCube:
    """A light-group chart scene by Mitsuba: per band, one render per group — its light on, every surface of the
    other groups black (reflectance 0) — summed (rendering is linear: the "light groups" of production
    renderers); the same band seed for every group.  Surfaces are uniform spectra (a band's light-weighted
    reflectance is constant over the band; a regular spectrum cannot be 0), so ``within_band`` is
    "light-weighted" only.

    Parameters
    ----------
    scene : Scene
        A chart scene of several light groups.
    progress : bool
        Draw a bar over the bands.
    log : callable or None
        Told the Mitsuba variant chosen.
    within_band : str
        ``"light-weighted"`` (the only one allowed here).

    Returns
    -------
    RadianceCube
        ``(H, W, B)`` float32 band-averaged radiance, W·m⁻²·sr⁻¹·nm⁻¹.
    """
    from spectracam.core.progress import bar
    from spectracam.scene.reference import chart_cells

    if within_band != "light-weighted":
        raise SpectracamError(f"within_band = {within_band!r}: a scene of light groups renders 'light-weighted' only")
    mi, variant, reason, width_nm = open_variant(scene, log)
    cells = chart_cells(scene)
    mi_scene, params = load_scene(mi, build_lights_scene(mi, scene, cells, width_nm))
    Float = type(params["light.irradiance.values"])
    spectra = [_group_spectra(scene, cell.illuminant) for cell in cells]
    surround = scene.chart.surround_reflectance

    def value(v: float):   # from a buffer, not a literal: a literal is compiled into the kernel (one kernel a value)
        return Float(np.array([v], np.float32))

    def light_group(b: int, k: int, on: bool) -> None:
        params[f"board{k:02d}.bsdf.reflectance.value"] = value(surround if on else 0.0)
        for p in range(24):
            params[f"g{k:02d}p{p:02d}.bsdf.reflectance.value"] = value(spectra[k][1][p, b] if on else 0.0)
        if on:
            params["light.irradiance.values"] = Float(np.full(POINTS_PER_BAND + 1, spectra[k][0][b], np.float32))

    H, W, B = scene.image.height, scene.image.width, len(scene.grid)
    cube = np.zeros((H, W, B), dtype=np.float32)
    for b in bar(range(B), desc="render bands", unit="band", progress=progress):
        for k in range(len(cells)):
            if spectra[k][0][b] <= 0:   # no light in this band: the group adds nothing
                continue
            light_group(b, k, True)
            params.update()
            cube[:, :, b] += np.asarray(mi.render(mi_scene, params, seed=band_seed(scene.render.seed, b)))[:, :, 0]
            light_group(b, k, False)
    meta = render_metadata(mi, variant, reason, scene.render.samples_per_pixel, scene.render.seed, within_band,
                           light_groups="one render per group and band, summed", **lights_metadata(scene))
    return RadianceCube(cube, np.asarray(scene.grid.centres_nm, float), meta)
