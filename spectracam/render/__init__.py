"""Renderers: a scene becomes a :class:`RadianceCube` of band-averaged spectral radiance.

Two renderers produce the same type for the same scene: ``mitsuba`` (Mitsuba 3, spectral variant,
Monte Carlo) and ``analytic`` (closed form).  Tests hold the two against each other.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import SpectracamError
from ..spectra import WavelengthGrid

RENDERERS = ("mitsuba", "analytic")


@dataclass
class RadianceCube:
    """Band-averaged spectral radiance ``(H, W, n_bands)`` in W·m⁻²·sr⁻¹·nm⁻¹, float32."""

    radiance: np.ndarray
    wavelengths_nm: np.ndarray
    metadata: dict = field(default_factory=dict)

    @property
    def grid(self) -> WavelengthGrid:
        return WavelengthGrid(np.asarray(self.wavelengths_nm, dtype=float))

    @property
    def shape(self) -> tuple[int, int, int]:
        return tuple(self.radiance.shape)  # type: ignore[return-value]


def render(scene, renderer: str = "mitsuba", progress: bool = False, log=None) -> RadianceCube:
    """Render ``scene`` with the named renderer; ``log`` (a callable) receives one-line notices."""
    if renderer == "analytic":
        from .analytic import render_analytic

        cube = render_analytic(scene)
    elif renderer == "mitsuba":
        from .mitsuba import render_mitsuba

        cube = render_mitsuba(scene, progress=progress, log=log)
    else:
        raise SpectracamError(f"renderer = {renderer!r}: must be one of {', '.join(RENDERERS)}")
    cube.metadata["scene"] = scene.to_dict()  # later stages find the chart geometry here
    return cube
