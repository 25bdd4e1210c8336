"""The pipeline from Python in one call per stage, each finding what it needs in what came before.

``render(scene) → RadianceCube → capture(cube) → RawCapture → score(raw) → ChartScore``.  A cube
records its scene, a capture records its scene and camera, so each call needs only the previous
result; explicit arguments win over what is recorded.  The stage functions themselves
(:func:`spectracam.capture.capture`, :func:`spectracam.score.score`) take everything explicitly.
"""
from __future__ import annotations

import numpy as np

from .camera import CameraSpec
from .capture import RawCapture
from .capture import capture as capture_stage
from .color import ProcessingSpec
from .errors import SpectracamError
from .reference import ChartReference
from .render import RadianceCube, render
from .scene import Scene
from .score import ChartScore
from .score import score as score_stage
from .sensor import SensorSpec


def scene_of(obj, what: str = "cube") -> Scene:
    """The scene a cube or capture records."""
    recorded = obj.metadata.get("scene") if isinstance(obj, RadianceCube) else getattr(obj, "scene", None)
    if recorded is None:
        raise SpectracamError(f"{what}: records no scene, so the chart (for metering and scoring) is unknown; "
                              "pass scene=")
    return Scene.from_dict(recorded, source=f"the scene recorded in the {what}")


def capture(cube: RadianceCube, camera: CameraSpec | None = None, seed: int | None = None, *,
            scene: Scene | None = None, sensor: SensorSpec | None = None, design: str | None = None) -> RawCapture:
    """Capture a cube.  The camera, seed and chart default to those of ``scene`` (default: the scene
    the cube records); ``sensor`` and ``design`` (``"arch/scheme"``) replace the camera's parts."""
    if cube.metadata.get("renderer") is None:  # made by hand, not rendered or read (both checked)
        cube.check()
    scene = scene or scene_of(cube)
    check_cube_matches(cube, scene)
    camera = camera or scene.camera
    if sensor is not None:
        camera = camera.replace(sensor=sensor)
    if design is not None:
        camera = camera.with_design(design)
    seed = scene.render.seed if seed is None else seed
    return capture_stage(cube, camera, seed, ChartReference.of(scene).white_box)


def check_cube_matches(cube: RadianceCube, scene: Scene, source: str = "cube") -> None:
    """Refuse a cube whose bands or size contradict the scene it is captured as."""
    h, w, b = cube.radiance.shape
    if (w, h) != (scene.image.width, scene.image.height):
        raise SpectracamError(f"{source}: {w}x{h} pixels, but its scene says {scene.image.width}x{scene.image.height}")
    if b != len(scene.grid) or not np.allclose(cube.wavelengths_nm, scene.grid.centres_nm, rtol=0, atol=1e-6):
        raise SpectracamError(f"{source}: {b} bands at {float(cube.wavelengths_nm[0]):g}…"
                              f"{float(cube.wavelengths_nm[-1]):g} nm, but its scene's grid has {len(scene.grid)} "
                              f"bands at {scene.grid.centres_nm[0]:g}…{scene.grid.centres_nm[-1]:g} nm")


#: How much memory a run needs beside the radiance cube itself, in cubes: the renderer's film and
#: the capture's (H, W, 3) float32 planes and scoring's float64 images (measured: ~1.5 cubes).
MEMORY_PER_CUBE = 2.5


def check_memory(scene: Scene) -> None:
    """Refuse, before any work, a scene whose cube would not fit in the memory available."""
    need = scene.image.width * scene.image.height * len(scene.grid) * 4 * MEMORY_PER_CUBE
    try:
        with open("/proc/meminfo") as f:
            info = {line.split(":")[0]: int(line.split()[1]) * 1024 for line in f}
        avail = info.get("MemAvailable")
    except (OSError, ValueError, IndexError):
        return  # not Linux: no estimate
    if avail is not None and need > avail:
        raise SpectracamError(f"image = {scene.image.width}x{scene.image.height} with {len(scene.grid)} bands: needs "
                              f"about {need / 2**30:.1f} GiB, {avail / 2**30:.1f} GiB available; use a smaller image "
                              "or fewer bands")


def score(raw: RawCapture, scene: Scene | None = None, processing: ProcessingSpec | None = None,
          delta_e_reference: str = "scene") -> ChartScore:
    """Score a capture against its scene (default: the scene it records), with ``processing``
    (default: the scene's)."""
    scene = scene or scene_of(raw, "capture")
    return score_stage(raw, ChartReference.of(scene), processing or scene.processing, delta_e_reference)


def simulate(scene: Scene, renderer: str = "mitsuba", seed: int | None = None):
    """render → capture → score: ``(cube, raw, score)``."""
    cube = render(scene, renderer)
    raw = capture(cube, seed=seed, scene=scene)
    return cube, raw, score(raw, scene)
