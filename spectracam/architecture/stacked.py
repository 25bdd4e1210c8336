"""Stacked photodiodes (Foveon type): colour from the depth at which silicon absorbs.

n photodiodes lie one under another in every pixel, with no colour filter; each collects the
carriers generated in its depth window ``[z_k, z_{k+1}]`` below a surface dead layer ``[0, z_0]``
(``filters.stacked_depths_um``).  With Beer–Lambert absorption in silicon and the air/silicon
reflectance ``R`` (M. A. Green, Sol. Energy Mater. Sol. Cells 92 (2008) 1305: :mod:`spectracam.architecture.silicon`),

    QE_k(λ) = (1 − R(λ))·(exp(−α(λ)·z_k) − exp(−α(λ)·z_{k+1})) × IR cut(λ),

the collection-depth model of :func:`spectracam.architecture.silicon.photodiode_qe` applied per window (sharp
window edges; one pass of the light, no microlens or coating).  The layers sum to one photodiode
collecting from ``z_0`` to the deepest boundary (a test).  ``IR cut`` is the filter in front of the
sensor that the camera carries (``filters.stacked_ir_cut_nm``, a logistic edge) times the optional
``filters.ir_cut_nm`` every architecture shares (two filters in series).

**Defaults: the Sigma SD1 Merrill, with its IR-cut filter.**  Depths ``[0.245, 1.15, 2.61, 4.34]`` µm
and an IR cut at 655 nm, 10 nm from 90 % to 10 %.  The depths are *effective* collection windows
(carrier diffusion moves them away from the metallurgical junctions, which the model does not
resolve), fitted to two published sets of numbers for the SD1 Merrill: the shapes of its three curves
measured at NPL (Darrodi, Finlayson, Goodman, Mackiewicz, JOSA A 32 (2015) 381; colour-science's
"Sigma SDMerill (NPL)"), and the ratio of its layers' raw responses to a D65 white implied by LibRaw's
XYZ→camera matrix for the SD1/DP Merrill (``colordata.cpp``: bottom : middle : top = 0.267 : 0.578 : 1).
The measured curves fall from 92 % to 18 % of their peaks between 650 and 660 nm: that is the camera's
IR-cut (dust-protector) filter, which every SD1 Merrill carries in front of the sensor, not silicon —
silicon's absorption changes slowly there — so the filter is part of the default; with no IR cut the
best depths reach correlations of only 0.76/0.86/0.93 (the bottom layer cannot fall off in the red).

Units: the model's QE is per photon; the NPL curves are per unit energy (as :mod:`spectracam.architecture.cameras`
reads every relative camera curve: ``S/λ`` is per photon).  The fit compares them per photon (the
curves converted with :func:`spectracam.architecture.cameras.to_electrons_per_photon`), on the NPL's 400–680 nm,
and the white on the scenes' 400–700 nm bands under CIE D65.  Result (``tests/test_architectures.py``):
correlations 0.981/0.978/0.992 (bottom/middle/top; 0.984/0.984/0.993 compared per unit energy instead),
peaks 640/570/480 nm against the curves' 630/540/480 nm per photon (per energy 640/600/490 against
630/590/480; the measured middle curve is flat within 5 % from 520 to 590 nm per photon, so its peak is
poorly defined), white 0.269 : 0.583 : 1.  The junction depths often quoted for the Foveon X3 (about 0.2, 0.6
and 2 µm; not found in a primary source here) give peaks 530/450/400 nm: they are not where the
carriers are collected from.  (The defaults before issue 34, ``[0.33, 1.34, 3.08, 6.0]`` µm, were fitted
per photon against per-energy curves with an IR cut no scene set: as shipped, with no IR cut, the
bottom layer peaked at 680 nm and correlated 0.67/0.69/0.87.)

**Layers that cannot form a colour image are refused** (:func:`check_layers`, at validation): fewer
than three layers or more than four (a colour needs three channels; a DNG holds four colour planes at
most); a layer whose response to a white is below :data:`MIN_WHITE_FRACTION` of the strongest layer's;
or layers so alike that the colour conversion must amplify noise beyond :data:`MAX_CONDITION`.

One exposure for all layers (they integrate together); every layer its own photodiode — the
sensor's well, dark current and read noise, its own fixed pattern.  The layers' curves overlap
strongly, so the colour conversion has large off-diagonal terms and amplifies noise: the rendered
SNR and the per-pixel ΔE show it.
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from spectracam.architecture.base import ARCHITECTURES, Architecture, PlanesLayout
from spectracam.core.spectra import band_average
from spectracam.architecture.layers import (LAYER_COUNTS, MAX_CONDITION, MIN_WHITE_FRACTION, check_layers,  # noqa: F401
                                           layer_diagnostics, layer_names, layer_qe, stacked_cut)

if TYPE_CHECKING:
    from spectracam.architecture.filters import FilterSpec
    from spectracam.camera import CameraSpec
    from spectracam.core.spectra import WavelengthGrid
    from spectracam.sensor import SensorSpec
    from spectracam.sensor.kernels import SpectralRates

__all__ = ["LAYER_COUNTS", "MAX_CONDITION", "MIN_WHITE_FRACTION", "StackedPhotodiodes", "check_layers",
           "layer_diagnostics", "layer_names", "layer_qe", "stacked_cut"]


@ARCHITECTURES.register("stacked")
class StackedPhotodiodes(Architecture):
    """Photodiodes stacked in each pixel, exposed together (module docstring).

    Parameters
    ----------
    cfa_pattern : str
        Unused by the layers (no mosaic); kept as every architecture takes it.
    fixed_pattern : str
        As :class:`~spectracam.architecture.base.Architecture`'s; ``"physical"``: each layer's photodiode its own.
    layers : int
        The number of photodiodes in the stack, 3 or 4 (:data:`LAYER_COUNTS`; :meth:`configure` sets it from the
        camera's depths).
    """

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

    #: Not made of the filters of ``[filters]``: each channel is a depth window in silicon.
    primaries = None

    @staticmethod
    def depths_um(filters: FilterSpec) -> tuple[float, ...]:
        """The window boundaries below the surface, µm, as a camera gives them: ``filters.stacked_depths_um`` of
        the scene file (a dead layer, then the bottom of each layer from the top; validated with the filters,
        :func:`~spectracam.architecture.layers.check_layers`).

        Parameters
        ----------
        filters : FilterSpec
            The ``[filters]`` table.

        Returns
        -------
        tuple of float
            ``(z_0, z_1, …, z_n)``, µm, increasing: the dead layer's bottom, then each layer's, the top layer first.
        """
        return tuple(filters.stacked_depths_um)

    @staticmethod
    def with_depths(filters: FilterSpec, depths_um: Sequence[float]) -> FilterSpec:
        """``filters`` with other window boundaries (validated as a scene file's).

        Parameters
        ----------
        filters : FilterSpec
            The ``[filters]`` table.
        depths_um : sequence of float
            The new boundaries, µm (as :meth:`depths_um` gives them).

        Returns
        -------
        FilterSpec
            A copy with ``stacked_depths_um`` replaced.
        """
        return filters.replace(stacked_depths_um=tuple(float(v) for v in depths_um))

    @classmethod
    def design_variables(cls) -> str:
        """The filter design varies the window boundaries (:meth:`depths_um`), not filters."""
        return "depths"

    def configure(self, camera: CameraSpec) -> "StackedPhotodiodes":
        return type(self)(self.cfa_pattern, self.fixed_pattern, len(self.depths_um(camera.filters)) - 1)

    def responsivities(self, filters: FilterSpec, grid: WavelengthGrid) -> np.ndarray:
        """``(n, B)`` band-averaged layer QE × IR cuts (400 points a band).

        Parameters
        ----------
        filters : FilterSpec
            The ``[filters]`` table: the depths and the IR cuts.
        grid : WavelengthGrid
            The bands.

        Returns
        -------
        ndarray
            ``(n, B)`` electrons per photon, the bottom layer first.
        """
        cut = stacked_cut(filters)
        depths = self.depths_um(filters)

        def layer(k):
            return lambda lam: layer_qe(lam, depths)[k] * (1.0 if cut is None else cut(lam))

        return np.stack([band_average(layer(k), grid, 400) for k in range(len(depths) - 1)])

    def capture_time_s(self, times_s: np.ndarray) -> float:
        return float(times_s[0])

    def record(self, rates: np.ndarray | SpectralRates, times_s: np.ndarray, sensor: SensorSpec,
               seed: int) -> tuple[np.ndarray, np.ndarray]:
        return self.record_planes(rates, times_s, sensor, seed,
                                 self.channel_patterns(sensor, rates.shape[:2], seed, drawn=False))
