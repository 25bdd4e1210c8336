"""Stacked photodiodes (Foveon type): colour from the depth at which silicon absorbs.

n photodiodes lie one under another in every pixel, with no colour filter; each collects the
carriers generated in its depth window ``[z_k, z_{k+1}]`` below a surface dead layer ``[0, z_0]``
(``filters.stacked_depths_um``).  With Beer–Lambert absorption in silicon and the air/silicon
reflectance ``R`` (M. A. Green, Sol. Energy Mater. Sol. Cells 92 (2008) 1305: :mod:`spectracam.silicon`),

    QE_k(λ) = (1 − R(λ))·(exp(−α(λ)·z_k) − exp(−α(λ)·z_{k+1})) × IR cut(λ),

the collection-depth model of :func:`spectracam.silicon.photodiode_qe` applied per window (sharp
window edges; one pass of the light, no microlens or coating).  The layers sum to one photodiode
collecting from ``z_0`` to the deepest boundary (a test).

Defaults, ``[0.33, 1.34, 3.08, 6.0]`` µm: *effective* collection windows (carrier diffusion moves
them away from the metallurgical junctions, which the model does not resolve), fitted with a 6 µm
deepest boundary and a 655 nm IR cut (the measured camera's curves fall to half between 650 and
660 nm) to two published sets of numbers for the Sigma SD1 Merrill: the shapes of its three curves
measured at NPL (Darrodi, Finlayson, Goodman, Mackiewicz, JOSA A 32 (2015) 381; colour-science's
"Sigma SDMerill (NPL)"; peaks 630/590/480 nm) and the ratio of its layers' raw responses to a D65
white implied by LibRaw's XYZ→camera matrix for the SD1/DP Merrill (``colordata.cpp``:
bottom : middle : top = 0.267 : 0.578 : 1).  The fit gives peaks 630/590/490 nm, correlations
0.984/0.982/0.990 and 0.30 : 0.60 : 1.  The junction depths often quoted for the Foveon X3 (about
0.2, 0.6 and 2 µm; not found in a primary source here) give peaks 530/450/400 nm, correlating
0.48/−0.02/−0.11 with the measured camera: they are not where the carriers are collected from.

One exposure for all layers (they integrate together); every layer its own photodiode — the
sensor's well, dark current and read noise, its own fixed pattern.  The layers' curves overlap
strongly, so the colour conversion has large off-diagonal terms and amplifies noise: the rendered
SNR and the per-pixel ΔE show it.
"""
from __future__ import annotations

import numpy as np

from ..architecture import ARCHITECTURES, Architecture, PlanesLayout
from ..spectra import band_average


def layer_qe(wavelength_nm, depths_um) -> np.ndarray:
    """``(n, len(λ))`` QE of each photodiode, bottom first (so three layers are R, G, B), electrons
    per incident photon, without IR cut; ``depths_um`` the n + 1 window boundaries (module docstring)."""
    from ..silicon import absorption_coefficient_per_um, reflectance

    lam = np.asarray(wavelength_nm, float)
    alpha = absorption_coefficient_per_um(lam)
    reaching = np.stack([np.exp(-alpha * z) for z in depths_um])      # fraction of photons reaching depth z
    return ((1.0 - reflectance(lam)) * (reaching[:-1] - reaching[1:]))[::-1]


def layer_names(n: int) -> tuple[str, ...]:
    """Three layers are R, G, B (bottom, middle, top); other counts L1 (bottom) … Ln (top)."""
    return ("R", "G", "B") if n == 3 else tuple(f"L{k + 1}" for k in range(n))


@ARCHITECTURES.register("stacked")
class StackedPhotodiodes(Architecture):
    """Photodiodes stacked in each pixel, exposed together (module docstring)."""

    name = "stacked"
    independent_exposures = False
    sensors = 3  # one photodiode per layer: a fixed pattern each

    def __init__(self, cfa_pattern: str = "RGGB", fixed_pattern: str = "physical", layers: int = 3):
        super().__init__(cfa_pattern, fixed_pattern)
        self.layers = layers

    @property
    def layout(self):
        return PlanesLayout("layers", "the photodiodes stacked in each pixel, bottom first, exposed together",
                            layer_names(self.layers))

    def configure(self, camera) -> "StackedPhotodiodes":
        return type(self)(self.cfa_pattern, self.fixed_pattern, len(camera.filters.stacked_depths_um) - 1)

    def responsivities(self, filters, grid) -> np.ndarray:
        """``(n, B)`` band-averaged layer QE × IR cut (400 points a band)."""
        from ..filters import ir_cut

        cut = ir_cut(filters)
        depths = filters.stacked_depths_um

        def layer(k):
            return lambda lam: layer_qe(lam, depths)[k] * (1.0 if cut is None else cut(lam))

        return np.stack([band_average(layer(k), grid, 400) for k in range(len(depths) - 1)])

    def capture_time_s(self, times_s):
        return float(times_s[0])

    def record(self, rates, times_s, sensor, seed):
        return self.record_planes(rates, times_s, sensor, seed,
                                 self.channel_patterns(sensor, rates.shape[:2], seed, drawn=False))
