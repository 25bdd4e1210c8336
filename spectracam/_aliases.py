"""One release of the old module names (before the stages became packages, issue 35).

``import spectracam.score`` or ``from spectracam.filters import X`` still work for one release and
warn (DeprecationWarning) naming the new place; the next release removes them.  An old name is the
same module object as its new one (monkeypatching either patches both).  Old names that the package's
face binds to a function (``spectracam.capture``, ``spectracam.score``) load without a warning, and the
face never lets a module of those names replace the function (``spectracam.__init__._Face``).  The old scene-file
module's names (``from spectracam.scene import load_scene``) come from :data:`SCENE_FILE_NAMES`.
"""
from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings

__all__ = ["OLD_MODULES", "SCENE_FILE_NAMES", "install"]

#: Old dotted module name → where it lives now.
OLD_MODULES = {
    "spectracam._numba_kernels": "spectracam.sensor._numba_kernels",
    "spectracam._paint": "spectracam.scene._paint",
    "spectracam.architectures": "spectracam.architecture",
    "spectracam.architectures.cmy": "spectracam.architecture.cmy",
    "spectracam.architectures.quad_bayer": "spectracam.architecture.quad_bayer",
    "spectracam.architectures.rgbw": "spectracam.architecture.rgbw",
    "spectracam.architectures.ryyb": "spectracam.architecture.ryyb",
    "spectracam.architectures.stacked": "spectracam.architecture.stacked",
    "spectracam.bridges": "spectracam.pipeline.bridges",
    "spectracam.cache": "spectracam.io.cache",
    "spectracam.cameras": "spectracam.architecture.cameras",
    "spectracam.capture": "spectracam.camera.capture",
    "spectracam.chart": "spectracam.scene.chart",
    "spectracam.cli_options": "spectracam.experiments.options",
    "spectracam.color": "spectracam.processing.color",
    "spectracam.design": "spectracam.experiments.design",
    "spectracam.design.ad": "spectracam.experiments.design.ad",
    "spectracam.design.model": "spectracam.experiments.design.model",
    "spectracam.design.optimise": "spectracam.experiments.design.optimise",
    "spectracam.design.problem": "spectracam.experiments.design.problem",
    "spectracam.design.report": "spectracam.experiments.design.report",
    "spectracam.design.run": "spectracam.experiments.design.run",
    "spectracam.design.spec": "spectracam.experiments.design.spec",
    "spectracam.design.variables": "spectracam.experiments.design.variables",
    "spectracam.emva1288": "spectracam.evaluation.emva1288",
    "spectracam.errors": "spectracam.core.errors",
    "spectracam.experiments.architectures_report": "spectracam.experiments.architectures.report",
    "spectracam.experiments.architectures_spacetime": "spectracam.experiments.architectures.spacetime",
    "spectracam.experiments.claims": "spectracam.experiments.paper.claims",
    "spectracam.experiments.figures": "spectracam.experiments.paper.figures",
    "spectracam.experiments.report": "spectracam.experiments.paper.report",
    "spectracam.experiments.sweep_plot": "spectracam.experiments.sweep.plot",
    "spectracam.experiments.usability": "spectracam.evaluation.usability",
    "spectracam.experiments.validate_wb": "spectracam.experiments.validate.white_balance",
    "spectracam.exposure": "spectracam.sensor.exposure",
    "spectracam.filters": "spectracam.architecture.filters",
    "spectracam.heldout": "spectracam.evaluation.heldout",
    "spectracam.illuminant": "spectracam.scene.illuminant",
    "spectracam.io.files": "spectracam.core.files",
    "spectracam.kernels": "spectracam.sensor.kernels",
    "spectracam.metering": "spectracam.sensor.metering",
    "spectracam.metrics": "spectracam.core.cielab",
    "spectracam.motion": "spectracam.experiments.motion",
    "spectracam.motion.cases": "spectracam.experiments.motion.cases",
    "spectracam.motion.command": "spectracam.experiments.motion.command",
    "spectracam.motion.experiment": "spectracam.experiments.motion.experiment",
    "spectracam.motion.metrics": "spectracam.experiments.motion.metrics",
    "spectracam.motion.motion": "spectracam.experiments.motion.motion",
    "spectracam.motion.render": "spectracam.experiments.motion.render",
    "spectracam.motion.report": "spectracam.experiments.motion.report",
    "spectracam.motion.timing": "spectracam.experiments.motion.timing",
    "spectracam.overrides": "spectracam.pipeline.overrides",
    "spectracam.processes": "spectracam.core.processes",
    "spectracam.progress": "spectracam.core.progress",
    "spectracam.reference": "spectracam.scene.reference",
    "spectracam.reflectances": "spectracam.scene.reflectances",
    "spectracam.registry": "spectracam.core.registry",
    "spectracam.score": "spectracam.evaluation.score",
    "spectracam.silicon": "spectracam.architecture.silicon",
    "spectracam.spatial": "spectracam.experiments.spatial",
    "spectracam.spatial.capture": "spectracam.experiments.spatial.capture",
    "spectracam.spatial.command": "spectracam.experiments.spatial.command",
    "spectracam.spatial.esfr": "spectracam.evaluation.esfr",
    "spectracam.spatial.experiment": "spectracam.experiments.spatial.experiment",
    "spectracam.spatial.geometry": "spectracam.experiments.spatial.geometry",
    "spectracam.spatial.optics": "spectracam.experiments.spatial.optics",
    "spectracam.spatial.render": "spectracam.experiments.spatial.render",
    "spectracam.spatial.report": "spectracam.experiments.spatial.report",
    "spectracam.spatial.scielab": "spectracam.evaluation.scielab",
    "spectracam.spatial.score": "spectracam.experiments.spatial.score",
    "spectracam.spatial.targets": "spectracam.experiments.spatial.targets",
    "spectracam.spec": "spectracam.core.spec",
    "spectracam.spectra": "spectracam.core.spectra",
    "spectracam.target": "spectracam.scene.target",
    "spectracam.target_score": "spectracam.evaluation.target_score",
}
#: Names of the old ``spectracam.scene`` module (now :mod:`spectracam.pipeline.scene_file`; the name
#: ``spectracam.scene`` is the scene stage's package).
SCENE_FILE_NAMES = ("SCENE_TABLES", "ImageSpec", "Scene", "experiment_base_scene", "load_camera_config",
                    "load_scene", "paper_scene", "parse_grid", "parse_scene", "read_toml", "resolve_curve_files",
                    "shipped_dir", "shipped_scene_file")
#: Old names the face binds to functions of :mod:`spectracam.pipeline`.
_BOUND = ("spectracam.capture", "spectracam.score")


def _moved(old: str, new: str) -> None:
    warnings.warn(f"{old} moved to {new} (issue 35); the old name is removed in the next release",
                  DeprecationWarning, stacklevel=4)


class _Finder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds an old module name and loads it as the module at its new place."""

    def find_spec(self, fullname, path=None, target=None):
        if fullname in OLD_MODULES:
            return importlib.util.spec_from_loader(fullname, self)
        return None

    def create_module(self, spec):
        return None

    def exec_module(self, module) -> None:
        new = OLD_MODULES[module.__name__]
        if module.__name__ not in _BOUND:   # the face's own names: no warning (spectracam.capture is the function)
            _moved(module.__name__, new)
        sys.modules[module.__name__] = importlib.import_module(new)   # importlib returns this entry


def _scene_file_name(name: str):
    if name in SCENE_FILE_NAMES:
        _moved(f"spectracam.scene.{name}", f"spectracam.pipeline.scene_file.{name}")
        return getattr(importlib.import_module("spectracam.pipeline.scene_file"), name)
    raise AttributeError(f"module 'spectracam.scene' has no attribute {name!r}")


def install() -> None:
    """Register the old names (called once by the package's face)."""
    if not any(isinstance(f, _Finder) for f in sys.meta_path):
        sys.meta_path.insert(0, _Finder())  # before the path finder: an old package name must not load its files twice
    scene = importlib.import_module("spectracam.scene")
    scene.__getattr__ = _scene_file_name
