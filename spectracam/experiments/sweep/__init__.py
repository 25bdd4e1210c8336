"""Design-space sweeps: a grid of scene overrides run serially or on Dask, with their plots.

``experiment.py`` is the run (spec → run → result), ``command.py`` the command line; the names of
:mod:`.experiment` are reachable here too (``spectracam.experiments.sweep.X``, the module's old name).
"""
from spectracam.experiments import experiment_names

__all__: list = []
__getattr__ = experiment_names(__name__)
