"""Renderers: a scene becomes a :class:`RadianceCube` of band-averaged spectral radiance.

Two registered renderers produce the same type for the same scene: ``mitsuba`` (Mitsuba 3,
spectral variant, Monte Carlo) and ``analytic`` (closed form).  Tests hold the two against each
other.  A new renderer is a function ``(scene, progress, log) → RadianceCube`` registered in
:data:`RENDERERS`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..registry import Registry
from ..spec import Spec
from ..spectra import WavelengthGrid

#: Renderers: name → function ``(scene, progress: bool, log) → RadianceCube``.
RENDERERS: Registry = Registry("renderer", "renderer")
#: Mitsuba variants a scene may ask for; ``auto`` picks the fastest that renders here.
VARIANTS = ("auto", "llvm", "scalar", "cuda")


@dataclass(frozen=True)
class RenderSpec(Spec):
    """The ``[render]`` table."""

    TABLE = "render"

    #: Samples per pixel per band.  Each sample carries 4 wavelengths inside its band; 4 spp gives
    #: ~0.2 % per-pixel noise on the chart (see tools/bench_render.py).
    samples_per_pixel: int = 4
    variant: str = "auto"
    #: The one seed that fixes every random draw downstream of this scene.
    seed: int = 0

    def validate(self) -> None:
        self.integer("samples_per_pixel", 1, 4096)
        self.choice("variant", VARIANTS)
        self.integer("seed", 0, 2**31 - 1)


@dataclass
class RadianceCube:
    """Band-averaged spectral radiance ``(H, W, n_bands)`` in W·m⁻²·sr⁻¹·nm⁻¹, float32; ``metadata``
    records how it was made, and ``metadata["scene"]`` the scene (a dict) it shows."""

    radiance: np.ndarray
    wavelengths_nm: np.ndarray
    metadata: dict = field(default_factory=dict)

    @property
    def grid(self) -> WavelengthGrid:
        return WavelengthGrid(np.asarray(self.wavelengths_nm, dtype=float))

    @property
    def shape(self) -> tuple[int, int, int]:
        return tuple(self.radiance.shape)  # type: ignore[return-value]


@RENDERERS.register("mitsuba")
def _mitsuba(scene, progress=False, log=None):
    from .mitsuba import render_mitsuba

    return render_mitsuba(scene, progress=progress, log=log)


@RENDERERS.register("analytic")
def _analytic(scene, progress=False, log=None):
    from .analytic import render_analytic

    return render_analytic(scene)


def render(scene, renderer: str = "mitsuba", progress: bool = False, log=None) -> RadianceCube:
    """Render ``scene`` with the registered renderer; ``log`` (a callable) receives one-line notices."""
    cube = RENDERERS[renderer](scene, progress=progress, log=log)
    cube.metadata["scene"] = scene.to_dict()  # later stages find the chart geometry here
    return cube
