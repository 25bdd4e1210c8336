"""What a renderer is asked for (the ``[render]`` table) and what it returns: a cube of band-averaged
spectral radiance.  Below the renderers, which all return one, and the registry that picks them."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from spectracam.core.spec import Spec
from spectracam.core.spectra import WavelengthGrid

__all__ = ["VARIANTS", "ChannelPlanes", "RadianceCube", "RenderSpec", "add_band"]

#: Mitsuba variants a scene may ask for; ``auto`` picks the fastest that renders here.
VARIANTS = ("auto", "llvm", "scalar", "cuda")


@dataclass(frozen=True)
class RenderSpec(Spec):
    """The ``[render]`` table."""

    TABLE = "render"

    #: Samples per pixel per band.  The chart's spectra are constant inside each band (light-weighted
    #: band averages, render/mitsuba.py), so samples only anti-alias the patch edges: a patch's pixels
    #: carry no render noise (1e-7 relative, float32; 0.28 % before issue 17; tools/bench_render.py).
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

    def check(self, source: str = "radiance") -> "RadianceCube":
        """Refuse a cube that is not a physical radiance: wrong shape, NaN/inf or negative values
        (one line naming where: the first bad band and how many pixels).

        Parameters
        ----------
        source : str
            Where the cube came from (a file, a function), as the error names it.

        Returns
        -------
        RadianceCube
            This cube, when it is one.
        """
        from spectracam.core.errors import SpectracamError

        r = self.radiance
        wl = np.asarray(self.wavelengths_nm, float)
        if r.ndim != 3 or r.shape[2] != wl.size or wl.size < 1:
            raise SpectracamError(f"{source}: a radiance cube is (H, W, bands) with one wavelength per band; got "
                                  f"{r.shape} and {wl.size} wavelengths")
        if not np.all(np.isfinite(wl)) or np.any(np.diff(wl) <= 0):
            raise SpectracamError(f"{source}: band wavelengths must be finite and increasing")
        lo, hi = r.min(initial=0.0), r.max(initial=0.0)  # two passes; the details only on failure
        if np.isfinite(lo) and np.isfinite(hi) and lo >= 0:
            return self
        for what, bad in (("not finite (NaN or inf)", ~np.isfinite(r)), ("negative", r < 0)):
            count = np.count_nonzero(bad, axis=(0, 1))
            if count.any():
                b = int(np.flatnonzero(count)[0])
                raise SpectracamError(f"{source}: radiance is {what} in {int(count.sum())} values; first in band "
                                      f"{wl[b]:g} nm ({int(count[b])} pixels); a radiance is finite and ≥ 0")
        return self


@dataclass
class ChannelPlanes:
    """The radiance integrated over wavelength against ``N`` weight functions while it is rendered, so the
    ``(H, W, n_bands)`` cube is never held (issue 38): ``planes[..., k] = Σ_b L_b · weights[b, k]``, float32.

    With a camera's band weights (:func:`spectracam.camera.band_weights`) the planes are its photo-electron rates
    ``ρ_k = A·T_k·∫E_q(λ)·R_k(λ)dλ`` in e⁻/s at every pixel (paper 3.3), what the sensor's pass would compute from
    the cube, for that one camera only.  ``weights`` is the ``(n_bands, N)`` matrix used; ``metadata`` records how
    it was made, as a cube's does (``metadata["scene"]``, and ``metadata["channel_planes"]``: the camera's
    channels).  A renderer accumulates each band's image into the planes as it is rendered: memory ``N/n_bands``
    of the cube's."""

    planes: np.ndarray
    wavelengths_nm: np.ndarray
    weights: np.ndarray
    metadata: dict = field(default_factory=dict)

    @property
    def grid(self) -> WavelengthGrid:
        return WavelengthGrid(np.asarray(self.wavelengths_nm, dtype=float))

    @property
    def shape(self) -> tuple[int, int, int]:
        return tuple(self.planes.shape)  # type: ignore[return-value]


def add_band(planes: np.ndarray, band: np.ndarray, weights_row: np.ndarray) -> None:
    """Add one band's image into ``(N, H, W)`` float32 planes in place: ``planes[k] += weights_row[k] · band``, one
    contiguous multiply-add pass per plane (how :class:`ChannelPlanes` are integrated, band after band, by the
    renderer and by ``capture --channel-planes``).

    Parameters
    ----------
    planes : ndarray
        ``(N, H, W)`` float32 accumulators.
    band : ndarray
        ``(H, W)`` float32 band-averaged radiance, W·m⁻²·sr⁻¹·nm⁻¹.
    weights_row : ndarray
        ``(N,)`` that band's weights (a row of the camera's band weights).
    """
    for k in range(planes.shape[0]):
        planes[k] += np.float32(weights_row[k]) * band
