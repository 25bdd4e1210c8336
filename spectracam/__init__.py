"""spectracam: compare colour architectures for image sensors by physical simulation.

Implements and extends Catrysse, Wandell & El Gamal, "Comparative analysis of color
architectures for image sensors", Proc. SPIE 3650 (1999).
"""
__version__ = "0.1.0"

from .capture import CameraSpec, RawCapture, capture  # noqa: E402
from .score import score  # noqa: E402
from .sensor import SensorSpec  # noqa: E402
from .render import RadianceCube, render  # noqa: E402
from .scene import Scene, load_scene, parse_scene  # noqa: E402

__all__ = ["CameraSpec", "RadianceCube", "RawCapture", "SensorSpec", "capture", "score", "Scene", "__version__", "load_scene", "parse_scene", "render"]
