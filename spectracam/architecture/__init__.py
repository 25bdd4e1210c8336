"""Colour architectures (paper, section 2): the registry and every architecture, with the filters,
silicon and measured cameras their channels are made of.

:mod:`~spectracam.architecture.base` holds the :class:`Architecture` type, its layouts, the registry
:data:`ARCHITECTURES` and the paper's three (CFA, dichroic prism, field-sequential); each later
architecture is one module here that registers itself on import.  This face imports them all, so
``ARCHITECTURES`` is complete once ``spectracam.architecture`` is imported.  A new architecture is a
new module in this folder and one line below.
"""
from spectracam.architecture.base import (ARCHITECTURES, CFA_PATTERNS, FIXED_PATTERN_CHOICES, PLANE_KINDS,
                                          Architecture, ColourFilterArray, DichroicPrism, FieldSequential,
                                          MosaicArchitecture, MosaicLayout, PlanesLayout, complementary,
                                          make_architecture)
from spectracam.architecture import cmy, quad_bayer, rgbw, ryyb, stacked  # noqa: F401  (each registers itself)

__all__ = ["ARCHITECTURES", "CFA_PATTERNS", "FIXED_PATTERN_CHOICES", "PLANE_KINDS", "Architecture",
           "ColourFilterArray", "DichroicPrism", "FieldSequential", "MosaicArchitecture", "MosaicLayout",
           "PlanesLayout", "complementary", "make_architecture"]
