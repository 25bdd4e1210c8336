"""Real cameras' measured curves checked against their published matrices, and the white balance against real cameras' own estimates.

``experiment.py`` is the run (spec → run → result), ``command.py`` the command line; the names of
:mod:`.experiment` are reachable here too (``spectracam.experiments.validate.X``, the module's old name).
"""
from spectracam.experiments import experiment_names

__all__: list = []
__getattr__ = experiment_names(__name__)
