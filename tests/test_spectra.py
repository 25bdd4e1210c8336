import numpy as np
import pytest

from spectracam.core.spectra import (WavelengthGrid, band_average, cmf_band_weights, energy_to_photons,
                                planck_radiance)

SIGMA_SB = 5.670374419e-8  # W m^-2 K^-4, CODATA 2018
WIEN_B_M_K = 2.897771955e-3


def test_planck_integrates_to_stefan_boltzmann():
    lam = np.geomspace(50.0, 2e6, 400_001)
    exitance = np.pi * np.trapezoid(planck_radiance(lam, 5000.0), lam)
    assert exitance == pytest.approx(SIGMA_SB * 5000.0**4, rel=1e-4)


@pytest.mark.parametrize("T", [3000.0, 7000.0])
def test_planck_peak_obeys_wien(T):
    lam = np.linspace(100.0, 3000.0, 290_001)
    peak = lam[np.argmax(planck_radiance(lam, T))]
    assert peak == pytest.approx(WIEN_B_M_K / T * 1e9, abs=0.02)


def test_grid_edges_and_widths():
    g = WavelengthGrid(np.arange(400.0, 701.0, 10.0))
    assert g.edges_nm[0] == 395.0 and g.edges_nm[-1] == 705.0
    np.testing.assert_allclose(g.widths_nm, 10.0)


def test_band_average_exact_for_linear_and_quadratic():
    g = WavelengthGrid(np.array([400.0, 410.0, 430.0]))  # uneven: edges 395, 405, 420, 440
    np.testing.assert_allclose(band_average(lambda x: 2 * x + 1, g), 2 * np.array([400, 412.5, 430]) + 1)
    e = g.edges_nm
    exact = (e[1:] ** 3 - e[:-1] ** 3) / 3 / np.diff(e)
    np.testing.assert_allclose(band_average(lambda x: x**2, g, 2000), exact, rtol=1e-7)


def test_photon_conversion_closed_form():
    # 1 W at 555 nm carries λ/(hc) = 2.7939e18 photons per second
    assert energy_to_photons(1.0, 555.0) == pytest.approx(2.79394e18, rel=1e-5)


def test_cmf_band_weights_integrate_ybar():
    g = WavelengthGrid(np.arange(361.0, 830.0, 1.0))
    w = cmf_band_weights(g)
    # ∫ȳ dλ over the CIE range is 106.857 nm (colour-science's 1 nm table)
    assert w[:, 1].sum() == pytest.approx(106.857, rel=2e-4)
