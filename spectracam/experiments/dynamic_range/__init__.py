"""Which architecture and read-out keep colour across a high-dynamic-range scene (issue 36, item 5).

``experiment.py`` is the run (spec → run → result), ``command.py`` the command line.
"""
__all__: list = []
