"""Every white-balance estimator on the same captures, per sensor, against the true neutral.

``experiment.py`` is the run (spec → run → result), ``command.py`` the command line; the names of
:mod:`.experiment` are reachable here too (``spectracam.experiments.white_balance.X``, the module's old name).
"""
from spectracam.experiments import experiment_names

__all__: list = []
__getattr__ = experiment_names(__name__)
