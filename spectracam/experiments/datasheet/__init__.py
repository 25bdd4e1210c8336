"""The figures a sensor datasheet quotes, computed from the simulated sensor (issue 36): EMVA 1288 dynamic range and
SNR per read-out, SNR 1/10 in lux, ISO 12232 speeds, ISO 15739 visual noise, ISO 17321-1 SMI, the chart's ΔE.

``experiment.py`` is the run (spec → run → result), ``report.py`` its files, ``command.py`` the command line; the
names of :mod:`.experiment` are reachable here too.
"""
from spectracam.experiments import experiment_names

__all__: list = []
__getattr__ = experiment_names(__name__)
