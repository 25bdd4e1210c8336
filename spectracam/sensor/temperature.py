"""Dark current against the die's temperature (issue 36): the paper's dark current is the value at a reference
temperature, 25 °C unless stated (the paper gives none; 25 °C is where sensor datasheets quote it), and a law
carries it to the sensor's temperature.

Three laws, named by ``sensor.dark_current_law``:

``generation``  thermal generation in the depletion region (Shockley–Read–Hall), proportional to the intrinsic
                carrier density: ``I(T) ∝ T^{3/2} · exp(−E_g(T) / 2kT)`` — the mechanism that dominates a
                silicon photodiode near room temperature [Sze2007]_ (the default);
``diffusion``   diffusion from the neutral regions, proportional to its square: ``I(T) ∝ T³ · exp(−E_g(T) / kT)``,
                which dominates when hot [Sze2007]_;
``doubling``    the datasheet's rule, ``I(T) = I_ref · 2^{(T − T_ref)/T_d}`` with a doubling temperature ``T_d``
                (``sensor.dark_doubling_K``; by default the generation law's own at the reference temperature,
                :func:`local_doubling_K`: 8.3 K at 25 °C).

Silicon's band gap follows Varshni's form with Thurmond's constants, ``E_g(T) = 1.170 eV − 4.73e-4 eV/K · T² /
(T + 636 K)`` (1.124 eV at 300 K) [Thurmond1975]_.  Every law gives exactly 1 at the reference temperature, so a
sensor at its reference records the paper's dark current unchanged.

.. [Sze2007] see docs/references.md; S. M. Sze, K. K. Ng, *Physics of Semiconductor Devices*, 3rd ed., ch. 2 and 13.
.. [Thurmond1975] see docs/references.md.
"""
from __future__ import annotations

import math

from spectracam.core.registry import Registry

__all__ = ["BOLTZMANN_EV_PER_K", "DARK_CURRENT_LAWS", "KELVIN", "SILICON_GAP_0K_EV", "VARSHNI_ALPHA_EV_PER_K",
           "VARSHNI_BETA_K", "dark_current_factor", "local_doubling_K", "silicon_band_gap_ev"]

#: Boltzmann's constant, eV/K (CODATA 2018, exact in the SI).
BOLTZMANN_EV_PER_K = 8.617333262e-5
#: 0 °C in kelvin.
KELVIN = 273.15
#: Silicon's band gap at 0 K and Varshni's constants, Thurmond (1975).
SILICON_GAP_0K_EV = 1.170
VARSHNI_ALPHA_EV_PER_K = 4.73e-4
VARSHNI_BETA_K = 636.0


def silicon_band_gap_ev(T_K: float) -> float:
    """Silicon's band gap at ``T_K`` kelvin, eV: ``E_g(0) − α T² / (T + β)`` (Varshni's form, Thurmond's constants).

    Parameters
    ----------
    T_K : float
        Temperature, K.

    Returns
    -------
    float
        E_g, eV (1.124 at 300 K).
    """
    return SILICON_GAP_0K_EV - VARSHNI_ALPHA_EV_PER_K * T_K**2 / (T_K + VARSHNI_BETA_K)


def _activated(power: float, gap_share: float):
    """``I(T)/I(T_ref)`` for ``I ∝ T^power · exp(−gap_share · E_g(T) / kT)``."""
    def ratio(T_K: float, ref_K: float, doubling_K: float | None = None) -> float:
        def log_i(T):
            return power * math.log(T) - gap_share * silicon_band_gap_ev(T) / (BOLTZMANN_EV_PER_K * T)
        return math.exp(log_i(T_K) - log_i(ref_K))
    return ratio


#: Laws: name → ``(T_K, reference_K, doubling_K or None) → I(T)/I(T_ref)``.
DARK_CURRENT_LAWS: Registry = Registry("sensor.dark_current_law", "dark-current temperature law")
DARK_CURRENT_LAWS.register("generation", _activated(1.5, 0.5))
DARK_CURRENT_LAWS.register("diffusion", _activated(3.0, 1.0))


def local_doubling_K(ref_K: float, law: str = "generation") -> float:
    """The temperature rise that doubles the dark current of ``law`` at ``ref_K``: ``ln 2 / (d ln I / dT)``, the
    derivative taken by central differences of ±0.01 K (the law is smooth: the error is below 1e-6 K).

    Parameters
    ----------
    ref_K : float
        The reference temperature, K.
    law : str
        A registered law: ``"generation"``, ``"diffusion"`` or ``"doubling"``.

    Returns
    -------
    float
        The doubling temperature, K (8.3 K for the generation law at 25 °C).
    """
    f, h = DARK_CURRENT_LAWS[law], 0.01
    return math.log(2.0) * 2 * h / math.log(f(ref_K + h, ref_K) / f(ref_K - h, ref_K))


@DARK_CURRENT_LAWS.register("doubling")
def _doubling(T_K: float, ref_K: float, doubling_K: float | None = None) -> float:
    """``2^((T − T_ref)/T_d)``; ``T_d`` by default the generation law's at the reference."""
    d = local_doubling_K(ref_K) if doubling_K is None else doubling_K
    return 2.0 ** ((T_K - ref_K) / d)


def dark_current_factor(law: str, temperature_C: float, reference_C: float, doubling_K: float | None = None) -> float:
    """``I(T)/I(T_ref)`` of ``law``: exactly 1.0 at the reference temperature.

    Parameters
    ----------
    law : str
        A registered law: ``"generation"``, ``"diffusion"`` or ``"doubling"``.
    temperature_C : float
        The die's temperature, °C.
    reference_C : float
        The temperature the dark current is given at, °C.
    doubling_K : float or None
        The doubling law's T_d, K; None: the generation law's own at the reference.

    Returns
    -------
    float
        The factor on the reference dark current (∞ when it overflows).
    """
    if temperature_C == reference_C:
        return 1.0
    try:
        return float(DARK_CURRENT_LAWS[law](temperature_C + KELVIN, reference_C + KELVIN, doubling_K))
    except OverflowError:
        return math.inf
