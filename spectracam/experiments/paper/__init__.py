"""The paper's experiment (Catrysse, Wandell & El Gamal 1999, sections 4–5): every architecture and exposure scheme under 3000–7000 K and D65, Figures 4–6 and the claims.

``experiment.py`` is the run (spec → run → result), ``command.py`` the command line; the names of
:mod:`.experiment` are reachable here too (``spectracam.experiments.paper.X``, the module's old name).
"""
from spectracam.experiments import experiment_names

__all__: list = []
__getattr__ = experiment_names(__name__)
