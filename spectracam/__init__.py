"""spectracam: compare colour architectures for image sensors by physical simulation.

Implements and extends Catrysse, Wandell & El Gamal, "Comparative analysis of color
architectures for image sensors", Proc. SPIE 3650 (1999).
"""
from spectracam._version import __version__  # noqa: E402

from spectracam.camera import CameraSpec  # noqa: E402
from spectracam.camera.capture import RawCapture  # noqa: E402
from spectracam.pipeline import capture, render, score, simulate  # noqa: E402
from spectracam.scene.reference import ChartReference  # noqa: E402
from spectracam.render import RadianceCube  # noqa: E402
from spectracam.pipeline.scene_file import Scene, load_scene, parse_scene  # noqa: E402
from spectracam.evaluation.score import ChartScore  # noqa: E402
from spectracam.sensor import SensorSpec  # noqa: E402
from spectracam.pipeline.bridges import camera_sensitivities, patch_spectra  # noqa: E402
from spectracam.io.exr import read_radiance_exr, read_raw_exr, write_radiance_exr, write_raw_exr  # noqa: E402
from spectracam.io.dng import write_dng  # noqa: E402
from spectracam import _aliases  # noqa: E402

_aliases.install()

__all__ = ["CameraSpec", "ChartReference", "ChartScore", "RadianceCube", "RawCapture", "Scene", "SensorSpec",
           "__version__", "camera_sensitivities", "capture", "load_scene", "parse_scene", "patch_spectra",
           "read_radiance_exr", "read_raw_exr", "render", "score", "simulate", "write_dng", "write_radiance_exr",
           "write_raw_exr"]
