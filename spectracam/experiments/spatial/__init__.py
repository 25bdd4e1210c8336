"""Spatial image-quality metrics: the ISO 12233 slanted-edge SFR and S-CIELAB.

Pure, vectorised numpy functions (scipy for the convolutions, colour-science for CIELAB):

* :func:`esfr` — ISO 12233:2017 edge-based spatial frequency response (e-SFR) of a slanted edge,
  :class:`ESFRResult`;
* :func:`scielab` — the S-CIELAB per-pixel colour difference of Zhang & Wandell (1997),
  with :func:`samples_per_degree`, :func:`scielab_kernels`, :func:`scielab_filter` and the published
  constants :data:`SCIELAB_FILTERS` and :data:`XYZ_TO_OPPONENT`.
"""
from __future__ import annotations

from spectracam.evaluation.esfr import ESFRResult, esfr
from spectracam.evaluation.scielab import (SCIELAB_FILTERS, XYZ_TO_OPPONENT, XYZ_TO_OPPONENT_AS_PRINTED, samples_per_degree,
                      scielab, scielab_filter, scielab_kernels)

__all__ = ["ESFRResult", "SCIELAB_FILTERS", "XYZ_TO_OPPONENT", "XYZ_TO_OPPONENT_AS_PRINTED", "esfr",
           "samples_per_degree", "scielab", "scielab_filter", "scielab_kernels"]
