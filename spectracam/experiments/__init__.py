"""Experiments built on the pipeline: the paper's figures (paper.py) and, later, sweeps."""
