"""spectracam: compare colour architectures for image sensors by physical simulation.

Implements and extends Catrysse, Wandell & El Gamal, "Comparative analysis of color
architectures for image sensors", Proc. SPIE 3650 (1999).
"""
__version__ = "0.1.0"

from .camera import CameraSpec  # noqa: E402
from .capture import RawCapture  # noqa: E402
from .pipeline import capture, score, simulate  # noqa: E402
from .reference import ChartReference  # noqa: E402
from .render import RadianceCube, render  # noqa: E402
from .scene import Scene, load_scene, parse_scene  # noqa: E402
from .score import ChartScore  # noqa: E402
from .sensor import SensorSpec  # noqa: E402

__all__ = ["CameraSpec", "ChartReference", "ChartScore", "RadianceCube", "RawCapture", "Scene", "SensorSpec",
           "__version__", "capture", "load_scene", "parse_scene", "render", "score", "simulate"]
