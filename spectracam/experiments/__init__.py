"""The experiments: one folder per question the simulator answers, each with its ``experiment.py`` (the
spec, the run, its result and writers) and its ``command.py`` (the command line that parses into them).
"""
from __future__ import annotations

from importlib import import_module

__all__ = ["experiment_names"]


def experiment_names(package: str):
    """A package face's ``__getattr__`` (PEP 562) that finds a name in the package's ``experiment`` module on
    first use: ``spectracam.experiments.paper.run_paper`` (the module's name before issue 35) stays valid,
    and the command's start-up does not import the experiment before it runs."""

    def __getattr__(name: str):
        if name.startswith("__"):
            raise AttributeError(name)
        return getattr(import_module(f"{package}.experiment"), name)

    return __getattr__
