"""The pipeline from Python in one call per stage, each finding what it needs in what came before.

``render(scene) → RadianceCube → capture(cube) → RawCapture → score(raw) → ChartScore``.  A cube
records its scene, a capture records its scene and camera, so each call needs only the previous
result; explicit arguments win over what is recorded.  The stage functions themselves
(:func:`spectracam.camera.capture.capture`, :func:`spectracam.evaluation.score.score`) take everything explicitly.
"""
from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from spectracam.camera import CameraSpec
from spectracam.camera.capture import RawCapture
from spectracam.camera.capture import capture as capture_stage
from spectracam.processing.color import ProcessingSpec
from spectracam.core.errors import ArgumentTypeError, SpectracamError, expect, expect_integer
from spectracam.scene.reference import ChartReference
from spectracam.render import RENDERERS, ChannelPlanes, RadianceCube
from spectracam.render import render as render_stage
from spectracam.pipeline.scene_file import Scene
from spectracam.evaluation.score import ChartScore
from spectracam.evaluation.score import score as score_stage
from spectracam.sensor import SensorSpec

if TYPE_CHECKING:
    from spectracam.evaluation.target_score import TargetScore
    from spectracam.sensor.metering import WhiteSpec

__all__ = ["BOTH_WAYS_FIELDS", "MEMORY_PER_CUBE", "MEMORY_PER_PIXEL_PLANES", "RADIANCE_MATCH_TOLERANCE",
           "STAND_IN_SCENE", "Scene", "both_ways", "camera_processing", "capture", "capture_spectral_image",
           "check_bytes", "check_cube_matches", "check_memory", "check_planes_match", "check_planes_white",
           "integrate_planes", "memory_available", "render", "render_planes", "scene_of", "score", "score_row",
           "simulate", "stand_in_scene"]


def scene_of(obj: RadianceCube | ChannelPlanes | RawCapture, what: str = "cube") -> Scene:
    """The scene a cube or capture records.

    Parameters
    ----------
    obj : RadianceCube, ChannelPlanes or RawCapture
        What records it (a cube's or planes' ``metadata["scene"]``, a capture's ``scene``).
    what : str
        What ``obj`` is, as the error names it.

    Returns
    -------
    Scene
        The recorded scene, validated.

    Raises
    ------
    SpectracamError
        ``obj`` records no scene.
    """
    recorded = obj.metadata.get("scene") if isinstance(obj, (RadianceCube, ChannelPlanes)) \
        else getattr(obj, "scene", None)
    if recorded is None:
        raise SpectracamError(f"{what}: records no scene, so the chart (for metering and scoring) is unknown; "
                              "pass scene=")
    return Scene.from_dict(recorded, source=f"the scene recorded in the {what}")


def capture(cube: RadianceCube | ChannelPlanes, camera: CameraSpec | None = None, seed: int | None = None, *,
            scene: Scene | None = None, sensor: SensorSpec | None = None, design: str | None = None,
            white: str | WhiteSpec | None = None) -> RawCapture:
    """Capture a cube: expose the camera's sensor to it and record digital numbers.

    Parameters
    ----------
    cube : RadianceCube or ChannelPlanes
        A spectral image from any other tool (no recorded scene, no ``scene=``) is captured too: the camera is
        ``camera`` (default: spectracam's), the scene :func:`stand_in_scene`; it records no scene (nothing to score).
        Channel planes (:func:`render_planes`): by their camera, on the white patch (:func:`_capture_planes`).
    camera, seed, scene, sensor, design, white : optional
        The camera, seed and chart default to those of ``scene`` (default: the scene the cube records); ``sensor``
        and ``design`` (``"arch/scheme"``) replace the camera's parts; the exposure is metered on ``white``
        (:func:`spectracam.sensor.metering.parse_white`; default ``"brightest"``; for a chart scene the white patch).

    Returns
    -------
    RawCapture

    Raises
    ------
    SpectracamError
        An argument of the wrong type (ArgumentTypeError), or a cube whose bands or pixels contradict its scene."""
    from spectracam.sensor.metering import metered_radiance, parse_white

    expect(cube, (RadianceCube, ChannelPlanes), "capture(cube)")
    expect(camera, CameraSpec, "capture(camera)", optional=True)
    expect_integer(seed, "capture(seed)", optional=True)
    expect(scene, Scene, "capture(scene)", optional=True)
    expect(sensor, SensorSpec, "capture(sensor)", optional=True)
    expect(design, str, "capture(design)", "an 'architecture/exposure' name such as 'fsc/optimal'", optional=True)
    if isinstance(cube, ChannelPlanes):
        return _capture_planes(cube, camera, seed, scene, sensor, design, white)
    if cube.metadata.get("renderer") is None:  # made by hand, not rendered or read (both checked)
        cube.check()
    foreign = scene is None and cube.metadata.get("scene") is None
    if foreign:
        cube, scene = stand_in_scene(cube)
    else:
        scene = scene or scene_of(cube)
        check_cube_matches(cube, scene)
    camera = _capturing_camera(camera or scene.camera, None if foreign else scene, sensor, design)
    if foreign:
        return capture_spectral_image(cube, scene.replace(camera=camera), seed, white)
    seed = scene.render.seed if seed is None else seed
    white = parse_white(white if white is not None else "patch", "white")
    if white.kind == "patch" and scene.target.textured:   # the chart's white patch under the same light
        from spectracam.scene.chart import WHITE_PATCH

        return capture_stage(cube, camera, seed, white_radiance=ChartReference.of(scene).patch_radiance[WHITE_PATCH])
    if white.kind == "patch":
        return capture_stage(cube, camera, seed, ChartReference.of(scene).white_box)
    return capture_stage(cube, camera, seed, white_radiance=metered_radiance(cube, white, scene),
                         metering=white.to_dict())


def check_planes_white(white: str | WhiteSpec | None) -> None:
    """Refuse, in one line, a white other than the chart's white patch for channel planes: any other white (the
    brightest neutral, a region, a luminance) is found in the spectra, which the planes no longer hold.

    Parameters
    ----------
    white : str, WhiteSpec or None
        As :func:`capture`'s ``white`` (None: the white patch).

    Raises
    ------
    SpectracamError
        A white that is not the patch, named by its kind.
    """
    from spectracam.sensor.metering import parse_white

    if white is not None and (kind := parse_white(white, "white").kind) != "patch":
        raise SpectracamError(f"white = {kind!r}: channel planes are metered on the chart's white patch only "
                              "('patch'); capture the radiance cube to meter another white")


def _capture_planes(planes: ChannelPlanes, camera, seed, scene, sensor, design, white) -> RawCapture:
    """:func:`capture` of channel planes: the scene they record (or ``scene``), checked against them; the camera
    as for a cube (the stage refuses one they were not rendered for); metered on the chart's white patch only
    (any other white is found in the spectra, which the planes no longer hold)."""
    scene = scene or scene_of(planes, "channel planes")
    check_planes_match(planes, scene)
    check_planes_white(white)
    camera = _capturing_camera(camera or scene.camera, scene, sensor, design)
    seed = scene.render.seed if seed is None else seed
    return capture_stage(planes, camera, seed, ChartReference.of(scene).white_box)


def _capturing_camera(camera: CameraSpec, scene: Scene | None, sensor, design) -> CameraSpec:
    """The camera that captures: with a chart ``scene``, its ``capture.metering = "auto"`` made the metering of
    ``processing.camera`` (:func:`spectracam.processing.metered_camera`); ``sensor`` and ``design`` replace its
    parts."""
    if scene is not None:
        from spectracam.processing import metered_camera

        camera = metered_camera(camera, scene.processing)
    if sensor is not None:
        camera = camera.replace(sensor=sensor)
    if design is not None:
        camera = camera.with_design(design)
    return camera


def capture_spectral_image(cube: RadianceCube, stand_in: Scene, seed: int | None = None,
                           white: str | WhiteSpec | None = None) -> RawCapture:
    """Capture a spectral image that records no spectracam scene with ``stand_in``'s camera
    (:func:`stand_in_scene`), metered on ``white`` (default: the brightest neutral; there is no white
    patch).  The capture records no scene: there is no chart truth to score.

    Parameters
    ----------
    cube : RadianceCube
        The spectral image, W·m⁻²·sr⁻¹·nm⁻¹ (its bands inside the chart's data, :func:`stand_in_scene`).
    stand_in : Scene
        The scene standing in for it: its camera and seed.
    seed : int, optional
        The capture's noise seed (default: ``stand_in``'s).
    white : str or WhiteSpec, optional
        What the exposure is metered on (:func:`spectracam.sensor.metering.parse_white`): ``"brightest"``, a
        region ``X0,Y0,X1,Y1`` or a white luminance in cd/m²; not ``"patch"``.

    Returns
    -------
    RawCapture
        The capture, recording its metering and no scene.
    """
    from spectracam.sensor.metering import metered_radiance, parse_white

    white = parse_white(white if white is not None else "brightest", "white")
    white_radiance = metered_radiance(cube, white, None if white.kind == "patch" else stand_in)  # patch: refused
    seed = stand_in.render.seed if seed is None else seed
    return capture_stage(cube, stand_in.camera, seed, white_radiance=white_radiance, metering=white.to_dict())


#: What a spectral image from another tool is captured as (:func:`stand_in_scene`).
STAND_IN_SCENE = {"name": "spectral image (no spectracam scene): conversion fitted on the ColorChecker under CIE D65",
                  "illuminant": {"type": "cie", "name": "D65"}}


def stand_in_scene(cube: RadianceCube, data: dict | None = None, source: str = "a spectral image without a "
                   "spectracam scene") -> tuple[RadianceCube, Scene]:
    """``(cube, scene)`` for a spectral image that records no spectracam scene: the scene holds the
    camera and the chart-and-light the colour conversion and the DNG's matrices are fitted on
    (:data:`STAND_IN_SCENE`, i.e. the ColorChecker under D65, over ``data``); the cube keeps only the
    bands inside the chart's reflectance data (the conversion knows nothing beyond them).

    Parameters
    ----------
    cube : RadianceCube
        The spectral image.
    data : dict, optional
        Scene tables over :data:`STAND_IN_SCENE` (a camera, a chart, a light …).
    source : str
        What the scene came from, as errors name it.

    Returns
    -------
    cube : RadianceCube
        The image with only the bands inside the chart's reflectance data (the same object when all are).
    scene : Scene
        The stand-in scene, on the cube's wavelengths.

    Raises
    ------
    SpectracamError
        Fewer than two bands inside the chart's data.
    """
    from spectracam.scene.chart import ChartSpec, dataset_range_nm

    merged = {**STAND_IN_SCENE, **(data or {})}
    chart = ChartSpec.from_dict(merged.get("chart", {}), source)
    lo, hi = dataset_range_nm(chart.dataset)
    edges = cube.grid.edges_nm
    keep = (edges[:-1] >= lo - 1e-9) & (edges[1:] <= hi + 1e-9)
    if keep.sum() < 2:
        raise SpectracamError(f"{source}: its bands ({cube.wavelengths_nm[0]:g}–{cube.wavelengths_nm[-1]:g} nm) hold "
                              f"fewer than two inside {lo:g}–{hi:g} nm, the range of the chart the conversion is "
                              "fitted on")
    if not keep.all():
        cube = RadianceCube(np.ascontiguousarray(cube.radiance[:, :, keep]), np.asarray(cube.wavelengths_nm)[keep],
                            {**cube.metadata, "bands_dropped_outside_nm": [lo, hi]})
    merged["wavelengths"] = {"centres_nm": [float(c) for c in cube.wavelengths_nm]}
    return cube, Scene.from_dict(merged, source)


#: A recorded chart scene's pixels must match it: the largest relative rms difference allowed between
#: a patch's mean spectrum in the cube and the chart reference's.  Mitsuba's renders match to 1e-6
#: (issue 17); a 3000 K label on 5000 K pixels differs by ~30 %, the other chart dataset by up to 19 %.
RADIANCE_MATCH_TOLERANCE = 0.01


#: Rows and columns of a patch's box that :func:`check_cube_matches` reads, at most (evenly spaced): a render's pixels
#: inside a patch agree to about 1e-7 (docs/guide/performance.md), so 64 × 64 of them give its mean spectrum as all
#: would, against a tolerance of 1 %; the check no longer reads a 12-Mpx cube once more (0.22 s, 40 % of a capture;
#: issue 38).
PATCH_CHECK_SAMPLES = 64


def _sampled(s: slice) -> slice:
    """``s`` thinned to at most :data:`PATCH_CHECK_SAMPLES` evenly spaced indices."""
    n = s.stop - s.start
    return slice(s.start, s.stop, max(1, -(-n // PATCH_CHECK_SAMPLES)))


def check_cube_matches(cube: RadianceCube, scene: Scene, source: str = "cube", radiance: bool = True) -> None:
    """Refuse a cube whose bands or size contradict the scene it is captured as, or (``radiance``)
    whose pixels do: each patch's mean spectrum (on at most :data:`PATCH_CHECK_SAMPLES`² of its pixels) must be
    the chart reference's within
    :data:`RADIANCE_MATCH_TOLERANCE` (another light, level, chart or unit shows here).

    Parameters
    ----------
    cube : RadianceCube
        The cube.
    scene : Scene
        The scene it is captured as.
    source : str
        The cube, as errors name it.
    radiance : bool
        Also check the patches' mean spectra (not only the size and bands).

    Raises
    ------
    SpectracamError
        A size, band or radiance that contradicts the scene.
    """
    h, w, b = cube.radiance.shape
    if (w, h) != (scene.image.width, scene.image.height):
        raise SpectracamError(f"{source}: {w}x{h} pixels, but its scene says {scene.image.width}x{scene.image.height}")
    if b != len(scene.grid) or not np.allclose(cube.wavelengths_nm, scene.grid.centres_nm, rtol=0, atol=1e-6):
        raise SpectracamError(f"{source}: {b} bands at {float(cube.wavelengths_nm[0]):g}…"
                              f"{float(cube.wavelengths_nm[-1]):g} nm, but its scene's grid has {len(scene.grid)} "
                              f"bands at {scene.grid.centres_nm[0]:g}…{scene.grid.centres_nm[-1]:g} nm")
    if not radiance:
        return
    if scene.target.textured:
        from spectracam.scene.reference import TargetReference

        want = TargetReference.of(scene).mean_radiance()
        mean = cube.radiance.mean(axis=(0, 1), dtype=np.float64)
        err = float(np.sqrt(np.mean((mean - want) ** 2) / np.mean(want ** 2)))
        if err > RADIANCE_MATCH_TOLERANCE:
            raise SpectracamError(f"{source}: its pixels contradict the scene it records ({scene.target.kind} of "
                                  f"{scene.target.library} under {scene.illuminant.label}, "
                                  f"{scene.illuminant.white_luminance_cd_m2:g} cd/m²): the mean spectrum differs by "
                                  f"{100 * err:.1f} % rms from the target's, at most {100 * RADIANCE_MATCH_TOLERANCE:g} % "
                                  "is allowed; a file edited or from another scene is not captured as this one")
        return
    ref = ChartReference.of(scene)
    worst, patch = 0.0, 0
    for p, (r, c) in enumerate(ref.boxes):
        mean = cube.radiance[_sampled(r), _sampled(c)].mean(axis=(0, 1), dtype=np.float64)
        want = ref.patch_radiance[p]
        err = float(np.sqrt(np.mean((mean - want) ** 2) / np.mean(want ** 2)))
        if err > worst:
            worst, patch = err, p
    if worst > RADIANCE_MATCH_TOLERANCE:
        raise SpectracamError(f"{source}: its pixels contradict the scene it records ({scene.illuminant.label}, "
                              f"{scene.illuminant.white_luminance_cd_m2:g} cd/m², {scene.chart.dataset}): patch "
                              f"{patch} ({ref.names[patch]}) differs by {100 * worst:.1f} % rms from its radiance, "
                              f"at most {100 * RADIANCE_MATCH_TOLERANCE:g} % is allowed; a file edited or from "
                              "another scene is not captured as this one")


def check_planes_match(planes: ChannelPlanes, scene: Scene, source: str = "channel planes") -> None:
    """Refuse channel planes whose size, bands or pixels contradict ``scene``: each patch's mean (on at most
    :data:`PATCH_CHECK_SAMPLES`² of its pixels) must be the chart reference's radiance through the planes' weights
    within :data:`RADIANCE_MATCH_TOLERANCE` (rms over the channels, relative), as :func:`check_cube_matches` holds
    a cube's spectra.

    Parameters
    ----------
    planes : ChannelPlanes
        The planes (their weights and photo-electron rates).
    scene : Scene
        The scene they are captured as (a chart scene).
    source : str
        The planes, as errors name them.

    Raises
    ------
    SpectracamError
        A size, band, weight or radiance that contradicts the scene, or a textured target.
    """
    h, w, n = planes.planes.shape
    if (w, h) != (scene.image.width, scene.image.height):
        raise SpectracamError(f"{source}: {w}x{h} pixels, but its scene says {scene.image.width}x{scene.image.height}")
    weights = np.asarray(planes.weights, np.float64)
    if weights.shape != (len(scene.grid), n) or not np.allclose(planes.wavelengths_nm, scene.grid.centres_nm,
                                                                 rtol=0, atol=1e-6):
        raise SpectracamError(f"{source}: weights {weights.shape} over {len(planes.wavelengths_nm)} bands, but its "
                              f"scene's grid has {len(scene.grid)} bands and the planes {n} channels")
    if scene.target.textured:
        raise SpectracamError(f"{source}: channel planes are rendered for a chart scene only")
    ref = ChartReference.of(scene)
    want = ref.patch_radiance @ weights                                           # (24, N)
    got = np.stack([planes.planes[_sampled(r), _sampled(c)].mean(axis=(0, 1), dtype=np.float64) for r, c in ref.boxes])
    err = np.sqrt(np.mean((got - want) ** 2, axis=1) / np.maximum(np.mean(want ** 2, axis=1), 1e-300))
    if err.max() > RADIANCE_MATCH_TOLERANCE:
        p = int(err.argmax())
        raise SpectracamError(f"{source}: its pixels contradict the scene it records ({scene.illuminant.label}, "
                              f"{scene.chart.dataset}): patch {p} ({ref.names[p]}) differs by {100 * err[p]:.1f} % "
                              f"rms from its radiance through the weights, at most {100 * RADIANCE_MATCH_TOLERANCE:g} "
                              "% is allowed")


#: How much memory a run needs, in float32 radiance cubes: the cube, the renderer's film, the
#: capture's (H, W, 3) float32 planes and scoring's float64 images.  An independent measurement of
#: render → capture → score found a peak of 3.2 cubes (issue 18; the earlier 2.5 was too low): 3.5.
MEMORY_PER_CUBE = 3.5


def memory_available() -> tuple[float | None, str]:
    """Bytes this process may still allocate, and what limits it: the system's MemAvailable, or the
    process's own address-space limit (``ulimit -v``, ``prlimit --as``) less what it has mapped."""
    import resource

    avail, why = None, "available"
    try:
        with open("/proc/meminfo") as f:
            info = {line.split(":")[0]: int(line.split()[1]) * 1024 for line in f}
        avail = info.get("MemAvailable")
    except (OSError, ValueError, IndexError):
        pass  # not Linux
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft != resource.RLIM_INFINITY:
        try:
            with open("/proc/self/status") as f:
                vm = next(int(line.split()[1]) * 1024 for line in f if line.startswith("VmSize:"))
        except (OSError, StopIteration, ValueError):
            vm = 0
        left = max(soft - vm, 0)
        if avail is None or left < avail:
            avail, why = left, "left under this process's address-space limit"
    return avail, why


def check_bytes(need: float, what: str, advice: str) -> None:
    """Refuse, before any work, a run that needs ``need`` bytes when this process may not have them;
    ``what`` names the sizes that cost them, ``advice`` what to make smaller.

    Parameters
    ----------
    need : float
        The bytes the run needs.
    what : str
        What costs them (the error's first words).
    advice : str
        What to make smaller (the error's last words).

    Raises
    ------
    SpectracamError
        More than :func:`memory_available` gives.
    """
    avail, why = memory_available()
    if avail is not None and need > avail:
        raise SpectracamError(f"{what}: needs about {need / 2**30:.1f} GiB, {avail / 2**30:.1f} GiB {why}; {advice}")


def check_memory(scene: Scene, copies: float = 1.0, what: str = "", channel_planes: bool = False) -> None:
    """Refuse, before any work, a scene whose cubes (``copies`` of them held at once) would not fit in
    the memory available to this process; with ``channel_planes`` (:func:`render_planes`), what a run that holds the
    camera's planes instead of the cube needs (:data:`MEMORY_PER_PIXEL_PLANES`).

    Parameters
    ----------
    scene : Scene
        The scene (its image size and bands).
    copies : float
        Cubes held at once (each :data:`MEMORY_PER_CUBE` float32 cubes at its peak).
    what : str
        Added to the error's description of the sizes.
    channel_planes : bool
        Size a run that holds the channel planes instead of the cube.

    Raises
    ------
    SpectracamError
        Not enough memory.
    """
    px = scene.image.width * scene.image.height
    need = px * (MEMORY_PER_PIXEL_PLANES if channel_planes else len(scene.grid) * 4 * MEMORY_PER_CUBE) * copies
    check_bytes(need, f"image = {scene.image.width}x{scene.image.height} with {len(scene.grid)} bands{what}"
                + (" in channel planes" if channel_planes else ""), "use a smaller image or fewer bands")


#: Bytes per pixel a run that renders into channel planes needs at its peak: the planes, the captures of both cameras
#: and the score's float64 images, which dominate.  ``simulate d65 --channel-planes`` at 2000 × 1500 peaked 231 B/px
#: above its resident set once loaded (``/usr/bin/time -f %M``; the cube's run 343 B/px, 2.9 cubes of 30 bands).
MEMORY_PER_PIXEL_PLANES = 300


def score(raw: RawCapture, scene: Scene | None = None, processing: ProcessingSpec | None = None,
          delta_e_reference: str = "scene") -> ChartScore | TargetScore:
    """Score a capture against its scene: render it on the display and measure its colour errors.

    Parameters
    ----------
    raw : RawCapture
        The capture.
    scene : Scene, optional
        The scene it is scored against (default: the scene it records).
    processing : ProcessingSpec, optional
        The processing that renders it (default: the scene's).
    delta_e_reference : {"scene", "camera"}
        What per-pixel ΔE is measured against (:data:`spectracam.evaluation.score.DELTA_E_REFERENCES`); a
        textured target is scored against its scene only.

    Returns
    -------
    ChartScore or TargetScore
        A :class:`ChartScore`, or for a textured target a :class:`~spectracam.evaluation.target_score.TargetScore`
        (per pixel against its known spectra).

    Raises
    ------
    SpectracamError
        An argument of the wrong type (ArgumentTypeError), a capture that records no scene when none is given,
        ``delta_e_reference="camera"`` for a textured target, or a capture that does not match the scene.

    References
    ----------
    .. [Catrysse1999] see docs/references.md; sections 3.5, 3.6 and 5.
    .. [Zhang1997] see docs/references.md; S-CIELAB.
    """
    expect(raw, RawCapture, "score(raw)")
    expect(scene, Scene, "score(scene)", optional=True)
    expect(processing, ProcessingSpec, "score(processing)", optional=True)
    expect(delta_e_reference, str, "score(delta_e_reference)", "'scene' or 'camera'")
    scene = scene or scene_of(raw, "capture")
    if scene.target.textured:
        from spectracam.scene.reference import TargetReference
        from spectracam.evaluation.target_score import score_target

        if delta_e_reference != "scene":
            raise SpectracamError(f"delta_e_reference = {delta_e_reference!r}: a textured target is scored against "
                                  "its scene only")
        return score_target(raw, ChartReference.of(scene), TargetReference.of(scene), scene.target,
                            processing or scene.processing)
    return score_stage(raw, ChartReference.of(scene), processing or scene.processing, delta_e_reference)


def render(scene: Scene, renderer: str = "mitsuba", progress: bool = False,
           log: Callable[[str], object] | None = None) -> RadianceCube:
    """Render ``scene`` into a radiance cube with a registered renderer (:func:`spectracam.render.render`).

    Its arguments are checked here, at the API's boundary.

    Parameters
    ----------
    scene : Scene
        What to render: chart or textured target, light, wavelength grid, image size.
    renderer : str
        A registered renderer's name (:data:`spectracam.render.RENDERERS`): ``"mitsuba"`` (Mitsuba 3, spectral
        variant, Monte Carlo) or ``"analytic"`` (closed form).
    progress : bool
        Show a progress bar (Mitsuba: over the bands).
    log : callable, optional
        A function of one string that receives one-line notices.

    Returns
    -------
    RadianceCube
        Band-averaged spectral radiance ``(H, W, n_bands)``, W·m⁻²·sr⁻¹·nm⁻¹, recording the scene in
        ``metadata["scene"]``.

    Raises
    ------
    SpectracamError
        An argument of the wrong type (ArgumentTypeError), an unknown renderer (ConfigError), or a scene the
        renderer cannot render on this machine.

    References
    ----------
    .. [Catrysse1999] see docs/references.md; section 3.1 (the scene's radiance).
    .. [Mitsuba3] see docs/references.md
    """
    expect(scene, Scene, "render(scene)")
    expect(renderer, str, "render(renderer)", "a renderer's name: " + ", ".join(map(repr, RENDERERS.names)))
    if log is not None and not callable(log):
        raise ArgumentTypeError(f"render(log): got {type(log).__name__}; allowed: a function of one string, or None")
    return render_stage(scene, renderer, progress=progress, log=log)


def render_planes(scene: Scene, renderer: str = "mitsuba", progress: bool = False,
                  log: Callable[[str], object] | None = None,
                  camera: CameraSpec | None = None) -> ChannelPlanes:
    """Render ``scene`` straight into one camera's channel planes: its photo-electron rates at every pixel, each band
    integrated as it is rendered, so the ``(H, W, B)`` cube is never held (issue 38; ``N/B`` of its memory).

    Parameters
    ----------
    scene : Scene
        A chart scene of one light.
    renderer : {"mitsuba", "analytic"}
        The renderer, as for :func:`render`.
    progress : bool
        Show a progress bar (Mitsuba: over the bands).
    log : callable, optional
        A function of one string that receives one-line notices.
    camera : CameraSpec, optional
        The camera whose band weights (:func:`spectracam.camera.band_weights`) the bands are integrated against
        (default: the scene's); :func:`capture` refuses the planes for any other.

    Returns
    -------
    ChannelPlanes
        ``(H, W, N)`` float32 photo-electron rates, e⁻/s, recording the scene in ``metadata["scene"]``.

    Raises
    ------
    SpectracamError
        An argument of the wrong type, a renderer other than mitsuba or analytic, a textured target or a scene of
        several light groups (they render a cube).

    References
    ----------
    .. [Catrysse1999] see docs/references.md; section 3.3 (ρ_k = A·T_k·∫E_q(λ)·R_k(λ)dλ).
    """
    from spectracam.camera import band_weights
    from spectracam.camera.capture import check_planes_capturable
    from spectracam.render import render_planes as render_planes_stage

    expect(scene, Scene, "render_planes(scene)")
    expect(renderer, str, "render_planes(renderer)", "'mitsuba' or 'analytic'")
    expect(camera, CameraSpec, "render_planes(camera)", optional=True)
    camera = camera or scene.camera
    check_planes_capturable(camera)   # before any work
    planes = render_planes_stage(scene, band_weights(camera, scene.grid), renderer, progress=progress, log=log)
    planes.metadata["channel_planes"] = {"channels": list(camera.architecture().layout.channels),
                                         "camera": camera.to_dict(), "units": "e-/s (photo-electron rates)"}
    return planes


def integrate_planes(wavelengths_nm: np.ndarray, bands: list, metadata: dict, camera: CameraSpec,
                     source: str = "radiance") -> ChannelPlanes:
    """A spectral image's bands integrated one at a time into ``camera``'s channel planes (``capture
    --channel-planes``: the file's bands are never stacked into a cube), as :func:`render_planes` integrates them as
    they are rendered: ``planes[k] += weights[b, k] · L_b`` in float32, in band order.

    Parameters
    ----------
    wavelengths_nm : ndarray
        ``(B,)`` band centres, nm (:func:`spectracam.io.exr.read_radiance_bands`).
    bands : list of ndarray
        ``B`` planes ``(H, W)`` float32 radiance, W·m⁻²·sr⁻¹·nm⁻¹; each is checked finite and ≥ 0 as it is added.
    metadata : dict
        What the file recorded (its ``"scene"``), kept on the planes.
    camera : CameraSpec
        The camera whose band weights integrate them (:func:`check_planes_capturable` first).
    source : str
        The file's name, for the error lines.

    Returns
    -------
    ChannelPlanes
        ``(H, W, N)`` float32 photo-electron rates, e⁻/s.

    Raises
    ------
    SpectracamError
        A camera whose planes cannot stand for the spectrum, or a band that is not finite and ≥ 0 (named).
    """
    from spectracam.camera import band_weights
    from spectracam.camera.capture import check_planes_capturable
    from spectracam.core.spectra import WavelengthGrid
    from spectracam.render.cube import add_band

    check_planes_capturable(camera)
    wl = np.asarray(wavelengths_nm, float)
    w = band_weights(camera, WavelengthGrid(wl))
    planes = np.zeros((w.shape[1], *bands[0].shape), np.float32)
    for b, band in enumerate(bands):
        lo, hi = band.min(initial=0.0), band.max(initial=0.0)
        if not (np.isfinite(lo) and np.isfinite(hi) and lo >= 0):
            raise SpectracamError(f"{source}: radiance is not finite or negative in band {wl[b]:g} nm; a radiance is "
                                  "finite and ≥ 0")
        add_band(planes, band, w[b])
    return ChannelPlanes(np.moveaxis(planes, 0, -1).copy(), wl, w.astype(np.float64), dict(metadata))


def simulate(scene: Scene, renderer: str = "mitsuba", seed: int | None = None, channel_planes: bool = False
             ) -> tuple[RadianceCube | ChannelPlanes, RawCapture, ChartScore | TargetScore]:
    """render → capture → score: ``(cube, raw, score)``.

    Parameters
    ----------
    scene : Scene
        The scene; its camera, processing and seed are used.
    renderer : str
        A registered renderer's name, as for :func:`render`.
    seed : int, optional
        The capture's noise seed (default: the scene's).
    channel_planes : bool
        Render into the scene camera's channel planes (:func:`render_planes`) instead of the radiance cube: the same
        capture (within float32 rounding) without the cube's memory (the render and capture in about a sixth of it;
        the score's own images are the same); a chart scene of one light.

    Returns
    -------
    tuple of (RadianceCube or ChannelPlanes, RawCapture, ChartScore or TargetScore)
        What :func:`render` (or :func:`render_planes`), :func:`capture` and :func:`score` return.

    Raises
    ------
    SpectracamError
        An argument of the wrong type (ArgumentTypeError), or what the three stages raise.

    References
    ----------
    .. [Catrysse1999] see docs/references.md
    """
    expect(scene, Scene, "simulate(scene)")
    expect_integer(seed, "simulate(seed)", optional=True)
    expect(channel_planes, bool, "simulate(channel_planes)", "True or False")
    cube = render_planes(scene, renderer) if channel_planes else render(scene, renderer)
    raw = capture(cube, seed=seed, scene=scene)
    return cube, raw, score(raw, scene)


#: What every command reports for each camera, oracle and developed, side by side (issue 33).
BOTH_WAYS_FIELDS = ("delta_e_mean", "delta_e_p95", "delta_e2000_mean", "held_out_delta_e", "held_out_delta_e_p95",
                    "awb_recovery_deg", "awb_reproduction_deg", "metered_exposure_ms", "s_cielab_mean", "s_cielab_p95")


def score_row(result: ChartScore | TargetScore) -> dict:
    """The :data:`BOTH_WAYS_FIELDS` of a :class:`ChartScore` or a textured target's score (whose per-pixel scores are
    on colours the conversion was not fitted on); S-CIELAB beside the per-pixel ΔE in both (the chart's at
    processing.viewing_distance_m, the target's at its own viewing geometry).

    Parameters
    ----------
    result : ChartScore or TargetScore
        A score.

    Returns
    -------
    dict
        The :data:`BOTH_WAYS_FIELDS`, ΔE*ab and S-CIELAB ΔE, degrees and ms (None where a field is not defined).
    """
    if isinstance(result, ChartScore):
        c, held = result.summary, result.held_out or {}
        return {"delta_e_mean": c.delta_e_mean, "delta_e_p95": c.delta_e_p95, "delta_e2000_mean": c.delta_e2000_mean,
                "held_out_delta_e": held.get("delta_e_mean"), "held_out_delta_e_p95": held.get("delta_e_p95"),
                "awb_recovery_deg": c.awb_recovery_deg, "awb_reproduction_deg": c.awb_reproduction_deg,
                "metered_exposure_ms": c.capture_time_ms, "s_cielab_mean": c.s_cielab_mean,
                "s_cielab_p95": c.s_cielab_p95}
    h = result.held_out
    return {"delta_e_mean": h["delta_e_mean"], "delta_e_p95": h["delta_e_p95"],
            "delta_e2000_mean": h["delta_e2000_mean"], "held_out_delta_e": h.get("sample_delta_e_conversion_mean"),
            "held_out_delta_e_p95": h.get("sample_delta_e_conversion_p95"), "awb_recovery_deg": h["awb_recovery_deg"],
            "awb_reproduction_deg": h["awb_reproduction_deg"], "metered_exposure_ms": result.capture_time_ms,
            "s_cielab_mean": h["s_cielab_mean"], "s_cielab_p95": h["s_cielab_p95"]}


def camera_processing(processing: ProcessingSpec, camera: str) -> ProcessingSpec:
    """``processing`` as the named camera (spectracam.processing.CAMERAS) runs it: the scene's own chain when it is
    that camera (its overridden steps kept), else that camera's steps.

    Parameters
    ----------
    processing : ProcessingSpec
        The scene's processing.
    camera : str
        ``"oracle"`` or ``"developed"``.

    Returns
    -------
    ProcessingSpec
        ``processing`` itself, or a copy with the camera and its automatic white balance and calibration.
    """
    if processing.camera == camera:
        return processing
    return processing.replace(camera=camera, white_balance="auto", calibration="auto")


def both_ways(raw: RawCapture, scene: Scene, cube: RadianceCube | None = None,
              result: ChartScore | TargetScore | None = None) -> dict:
    """``{"oracle": row, "developed": row}`` (:func:`score_row`): the capture scored by the oracle camera and by the
    developed one.  With the ``cube``, each camera captures it with its own metering (same seed); without it (a raw
    file), both develop the same capture, metered as it was.  ``result``: the score of ``raw`` under the scene's own
    processing, reused for its camera's row.

    Parameters
    ----------
    raw : RawCapture
        The capture.
    scene : Scene
        Its scene.
    cube : RadianceCube, optional
        The radiance, captured again by each camera with its own metering.
    result : ChartScore or TargetScore, optional
        The score already computed under the scene's own processing.

    Returns
    -------
    dict
        ``"oracle"`` and ``"developed"``: a :func:`score_row` each; ``"metering"``: how the captures were metered.
    """
    out = {}
    for name in ("oracle", "developed"):
        processing = camera_processing(scene.processing, name)
        if result is not None and processing == scene.processing:
            out[name] = score_row(result)
            continue
        s = scene.replace(processing=processing)
        r = capture(cube, seed=raw.seed, scene=s) if cube is not None else raw
        out[name] = score_row(score(r, s, processing))
    out["metering"] = "each camera's own (captured anew)" if cube is not None else "as the capture was metered"
    return out
