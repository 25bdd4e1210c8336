"""The pipeline from Python in one call per stage, each finding what it needs in what came before.

``render(scene) → RadianceCube → capture(cube) → RawCapture → score(raw) → ChartScore``.  A cube
records its scene, a capture records its scene and camera, so each call needs only the previous
result; explicit arguments win over what is recorded.  The stage functions themselves
(:func:`spectracam.capture.capture`, :func:`spectracam.score.score`) take everything explicitly.
"""
from __future__ import annotations

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
    scene = scene or scene_of(cube)
    camera = camera or scene.camera
    if sensor is not None:
        camera = camera.replace(sensor=sensor)
    if design is not None:
        camera = camera.with_design(design)
    seed = scene.render.seed if seed is None else seed
    return capture_stage(cube, camera, seed, ChartReference.of(scene).white_box)


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
