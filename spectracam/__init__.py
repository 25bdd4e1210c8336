"""spectracam: compare colour architectures for image sensors by physical simulation.

Implements and extends Catrysse, Wandell & El Gamal, "Comparative analysis of color
architectures for image sensors", Proc. SPIE 3650 (1999).

The package's face (the names below) is loaded on first use (PEP 562): ``import spectracam`` and the command line's
start-up import no stage until one is asked for (issue 38: ``spectracam simulate --help`` had imported the whole
API, 0.42 s against the previous release's 0.24 s).
"""
import importlib as _importlib
import sys as _sys
import types as _types

from spectracam._version import __version__  # noqa: E402

#: Public name → the module it lives in.
_FACE = {
    "CameraSpec": "spectracam.camera", "RawCapture": "spectracam.camera.capture",
    "capture": "spectracam.pipeline", "render": "spectracam.pipeline", "score": "spectracam.pipeline",
    "simulate": "spectracam.pipeline", "render_planes": "spectracam.pipeline", "ChannelPlanes": "spectracam.render",
    "ChartReference": "spectracam.scene.reference",
    "RadianceCube": "spectracam.render", "Scene": "spectracam.pipeline.scene_file",
    "load_scene": "spectracam.pipeline.scene_file", "parse_scene": "spectracam.pipeline.scene_file",
    "ChartScore": "spectracam.evaluation.score", "SensorSpec": "spectracam.sensor",
    "camera_sensitivities": "spectracam.pipeline.bridges", "patch_spectra": "spectracam.pipeline.bridges",
    "read_radiance_exr": "spectracam.io.exr", "read_raw_exr": "spectracam.io.exr",
    "write_radiance_exr": "spectracam.io.exr", "write_raw_exr": "spectracam.io.exr", "write_dng": "spectracam.io.dng",
}

__all__ = sorted(["__version__", *_FACE])


class _Face(_types.ModuleType):
    """The package: its face's names resolved on first use; a subpackage or old module of the same name
    (``spectracam.render``, the old ``spectracam.capture`` and ``spectracam.score``) never replaces the function."""

    def __getattr__(self, name: str):
        if name in _FACE:
            value = getattr(_importlib.import_module(_FACE[name]), name)
            self.__dict__[name] = value
            return value
        raise AttributeError(f"module 'spectracam' has no attribute {name!r}")

    def __setattr__(self, name: str, value) -> None:
        if name in _FACE and isinstance(value, _types.ModuleType):
            return   # the import system binding a module of this name: the face's function stays
        super().__setattr__(name, value)

    def __dir__(self):
        return sorted(set(super().__dir__()) | set(_FACE))


_sys.modules[__name__].__class__ = _Face

from spectracam import _aliases  # noqa: E402

_aliases.install()
