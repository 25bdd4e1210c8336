"""The simulated camera measured as EMVA 1288 Release 4.0 prescribes: photon transfer, SNR, linearity, non-uniformities, a datasheet.

``experiment.py`` is the run (spec → run → result), ``command.py`` the command line; the names of
:mod:`.experiment` are reachable here too (``spectracam.experiments.emva.X``, the module's old name).
"""
from spectracam.experiments import experiment_names

__all__: list = []
__getattr__ = experiment_names(__name__)
