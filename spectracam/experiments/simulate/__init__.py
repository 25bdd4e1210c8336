"""One case through every stage: ``spectracam render``, ``capture``, ``score``, ``simulate`` (the three in one
go) and ``inspect``, the commands that run single stages of the pipeline.

``command.py`` is the command line, ``outputs.py`` what those commands write and say.
"""
from __future__ import annotations

__all__: list = []
