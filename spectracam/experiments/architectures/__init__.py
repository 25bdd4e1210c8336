"""Today's architectures beside the paper's three: every design under D65 and 3000 K, scored on the chart, in space, in time and on natural scenes.

``experiment.py`` is the run (spec → run → result), ``command.py`` the command line; the names of
:mod:`.experiment` are reachable here too (``spectracam.experiments.architectures.X``, the module's old name).
"""
from spectracam.experiments import experiment_names

__all__: list = []
__getattr__ = experiment_names(__name__)
