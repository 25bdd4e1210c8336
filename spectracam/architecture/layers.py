"""The layers of a stacked-photodiode sensor (:mod:`spectracam.architecture.stacked`): each layer's
quantum efficiency from its depth window in silicon, the filters in front of them, and the check that
refuses layers which cannot form a colour image.  Below the filters (whose ``stacked_depths_um`` it
checks) and the architecture (which records through it), so neither imports the other.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from spectracam.core.spectra import Spectrum, logistic_cut, logistic_scale_nm

if TYPE_CHECKING:
    from spectracam.architecture.filters import FilterSpec

__all__ = ["LAYER_COUNTS", "MAX_CONDITION", "MIN_WHITE_FRACTION", "check_layers", "layer_diagnostics", "layer_names",
           "layer_qe", "stacked_cut"]


def layer_qe(wavelength_nm: ArrayLike, depths_um: ArrayLike) -> np.ndarray:
    """``(n, len(λ))`` QE of each photodiode, bottom first (so three layers are R, G, B), electrons
    per incident photon, without IR cut; ``depths_um`` the n + 1 window boundaries (module docstring).

    Parameters
    ----------
    wavelength_nm : array_like
        Wavelengths, nm.
    depths_um : array_like
        The n + 1 boundaries of the collection windows below the surface, µm, increasing.

    Returns
    -------
    ndarray
        ``(n, len(wavelength_nm))``, electrons per incident photon.
    """
    from spectracam.architecture.silicon import absorption_coefficient_per_um, reflectance

    lam = np.asarray(wavelength_nm, float)
    alpha = absorption_coefficient_per_um(lam)
    reaching = np.stack([np.exp(-alpha * z) for z in depths_um])      # fraction of photons reaching depth z
    return ((1.0 - reflectance(lam)) * (reaching[:-1] - reaching[1:]))[::-1]


#: A layer whose response to a white is below this fraction of the strongest layer's is refused: the exposure
#: is metered so that the strongest layer fills its well, so such a layer records the white in under 1 % of full
#: swing — on the paper's sensor (131 072 e⁻ well, 8-bit ADC: 512 e⁻ a code) at most 1 311 e⁻, 2.6 codes, which
#: quantisation alone (σ = 148 e⁻) leaves at SNR < 9 for the white and < 2 for an 18 % grey: no colour.  A real
#: Foveon's weakest layer (the SD1 Merrill's bottom one) gets 27 % of the top's.
MIN_WHITE_FRACTION = 0.01
#: The largest condition number of the layers' white-balanced responsivities per unit energy (each layer
#: scaled to 1 on an equal-energy white, sampled at 1 nm over 400–700 nm, times the IR cuts; the measure
#: :func:`spectracam.architecture.cameras.channel_condition` applies to a camera file).  It bounds how much the colour
#: conversion can amplify the layers' relative noise in its worst direction against its best (for
#: ``x = A⁺r``: ‖δx‖/‖x‖ ≤ κ‖δr‖/‖r‖).  The measured SD1 Merrill curves have κ = 11, the default depths
#: 14, the paper's block filters 1.2; 100 spends 40 dB of a raw SNR whose ceiling on the paper's sensor is
#: 51 dB (a full 131 072 e⁻ well), and the depth sets measured beyond it (e.g. [3, 3.5, 4, 4.5] µm, κ = 450)
#: render the d65 chart below 0 dB luminance SNR — noise larger than the picture.
MAX_CONDITION = 100.0
#: Layer counts a stacked camera may have (``len(filters.stacked_depths_um) − 1``): three channels at least
#: for a colour, four at most for a DNG's colour planes.
LAYER_COUNTS = (3, 4)


def stacked_cut(filters: FilterSpec) -> Spectrum | None:
    """Transmittance ``λ → T`` of the filters in front of the stacked sensor: its own IR cut
    (``stacked_ir_cut_nm``, edge ``stacked_ir_cut_width_nm``) times the shared ``ir_cut_nm`` if set; None
    when there is neither.

    Parameters
    ----------
    filters : FilterSpec
        The ``[filters]`` table.

    Returns
    -------
    Spectrum or None
        The transmittance as a function of wavelength in nm.
    """
    shared = None if filters.ir_cut_nm is None else logistic_cut(filters.ir_cut_nm, filters.ir_cut_width_nm)
    if filters.stacked_ir_cut_nm is None:
        return shared
    s, c = logistic_scale_nm(filters.stacked_ir_cut_width_nm), filters.stacked_ir_cut_nm

    def cut(lam):
        own = 1.0 / (1.0 + np.exp((np.asarray(lam, float) - c) / s))
        return own if shared is None else own * shared(lam)

    return cut


def layer_diagnostics(filters: FilterSpec) -> tuple[np.ndarray, float]:
    """``(white fraction of each layer (bottom first; the strongest = 1), condition number)`` of the
    layers × IR cuts on 400–700 nm at 1 nm under an equal-energy white (:data:`MAX_CONDITION`).

    Parameters
    ----------
    filters : FilterSpec
        The ``[filters]`` table.

    Returns
    -------
    tuple of (ndarray, float)
        Each layer's share of the white relative to the strongest, and the condition number (inf when a layer
        collects nothing).
    """
    lam = np.arange(400.0, 701.0)
    cut = stacked_cut(filters)
    q = layer_qe(lam, filters.stacked_depths_um) * (1.0 if cut is None else cut(lam))
    q = q * lam  # electrons per unit energy: an equal-energy white's photon flux ∝ λ
    white = q.sum(axis=1)
    if not np.all(white > 0):
        return white / max(white.max(), 1e-300), float("inf")
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        kappa = float(np.linalg.cond((q / white[:, None]).T))
    return white / white.max(), kappa if np.isfinite(kappa) and kappa < 1e12 else float("inf")


def check_layers(filters: FilterSpec) -> None:
    """Refuse ``filters.stacked_depths_um`` whose layers cannot form a colour image (module docstring),
    in one line naming the field, the value and what is allowed.

    Parameters
    ----------
    filters : FilterSpec
        The ``[filters]`` table (the stacked sensor's depths and IR cuts).
    """
    from spectracam.core.errors import ConfigError

    depths = list(filters.stacked_depths_um)
    field = "filters.stacked_depths_um"
    frac, kappa = layer_diagnostics(filters)
    names = layer_names(len(frac))
    if frac.min() < MIN_WHITE_FRACTION:
        k = int(np.argmin(frac))
        raise ConfigError(field, depths, f"layer {names[k]} (window {depths[len(depths) - 2 - k]:g}–"
                          f"{depths[len(depths) - 1 - k]:g} µm) collects {frac[k]:.2g} of the strongest layer's charge "
                          f"from a white; every layer needs ≥ {MIN_WHITE_FRACTION:g} of it to record a colour")
    if kappa > MAX_CONDITION:
        shown = "∞" if kappa == float("inf") else format(kappa, ".3g")
        raise ConfigError(field, depths, f"the layers' responses are so alike (condition number {shown}) that the "
                          f"colour conversion would amplify their noise beyond any picture; allowed ≤ {MAX_CONDITION:g} "
                          "(the SD1 Merrill's measured curves: 11) — spread the windows over the depths where "
                          "blue, green and red are absorbed (about 0.2–5 µm)")


def layer_names(n: int) -> tuple[str, ...]:
    """Three layers are R, G, B (bottom, middle, top); other counts L1 (bottom) … Ln (top).

    Parameters
    ----------
    n : int
        The number of layers.

    Returns
    -------
    tuple of str
        The layers' channel names, bottom first.
    """
    return ("R", "G", "B") if n == 3 else tuple(f"L{k + 1}" for k in range(n))
