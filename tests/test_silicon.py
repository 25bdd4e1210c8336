"""Silicon optical constants (Green 2008) and the collection-depth photodiode QE model."""
import doctest
from importlib.resources import files

import numpy as np
import pytest

import spectracam.architecture.silicon as si
from spectracam.architecture.silicon import absorption_coefficient_per_um, photodiode_qe, reflectance

#: Green (2008)'s tabulated α, 1/cm, as transcribed independently to three figures in
#: github.com/NedJWestern/Loss-Analysis, constants/Si_alpha_Green_2008.dat (commit e315383).
GREEN_2008_ALPHA_PER_CM = {400: 9.30e4, 450: 2.41e4, 550: 6.39e3, 630: 3.28e3, 640: 3.03e3,
                           700: 1.89e3, 800: 8.50e2, 1000: 6.40e1}

#: Measured α of silicon at 633 nm, 1/cm: 3105 ± 62 (Geist, Schaefer, Song, Wang & Zalewski,
#: "An accurate value for the absorption coefficient of silicon at 633 nm", J. Res. NIST 95 (1990)
#: 549), independent of Green's table. Handbook values of ~3.8e3 /cm predate it and are ~20 % high.
GEIST_1990_ALPHA_633_PER_CM = 3105.0


def _csv_table():
    text = (files("spectracam") / "data" / "silicon_green2008.csv").read_text(encoding="utf-8")
    rows = [ln for ln in text.splitlines() if ln and not ln.startswith("#")]
    assert rows[0] == "wavelength_nm,alpha_per_cm,n,k"
    return np.loadtxt(rows[1:], delimiter=",").T


def test_data_file_is_consistent_and_covers_the_visible():
    wl, alpha_cm, n, k = _csv_table()
    np.testing.assert_array_equal(wl, np.arange(250.0, 1451.0, 10.0))
    # α = 4πk/λ (λ in cm) on every row, to the 5 significant figures written.
    np.testing.assert_allclose(alpha_cm, 4 * np.pi * k / (wl * 1e-7), rtol=1e-4)
    assert np.all(np.diff(alpha_cm[wl >= 370]) < 0)  # α falls monotonically across the visible and NIR


@pytest.mark.parametrize("wl, published", sorted(GREEN_2008_ALPHA_PER_CM.items()))
def test_alpha_at_table_nodes_matches_green_2008(wl, published):
    assert absorption_coefficient_per_um(float(wl)) * 1e4 == pytest.approx(published, rel=0.005)


def test_alpha_at_633_nm():
    a633 = float(absorption_coefficient_per_um(633.0)) * 1e4
    # Log-linear interpolation between Green's 630 and 640 nm values, in closed form: 3.203e3 /cm.
    expected = 3.28e3 * (3.03e3 / 3.28e3) ** 0.3
    assert a633 == pytest.approx(expected, rel=0.02)
    assert 3.03e3 < a633 < 3.28e3
    # An independent measurement: Green 2008 is ~3 % above it, the old ~3.8e3 handbook value ~20 %.
    assert a633 == pytest.approx(GEIST_1990_ALPHA_633_PER_CM, rel=0.05)


def test_interpolation_is_linear_in_log_alpha():
    a = absorption_coefficient_per_um([550.0, 555.0, 560.0])
    assert a[1] == pytest.approx(np.sqrt(a[0] * a[2]), rel=1e-12)  # geometric, not arithmetic, mean


def test_reflectance_of_silicon_at_600_nm():
    assert float(reflectance(600.0)) == pytest.approx(0.35, abs=0.02)


def test_reflectance_is_fresnel_of_the_tabulated_n_k():
    wl, _, n, k = _csv_table()
    sel = (wl >= 300) & (wl <= 1100)
    expected = ((n - 1) ** 2 + k**2) / ((n + 1) ** 2 + k**2)
    np.testing.assert_allclose(reflectance(wl[sel]), expected[sel], rtol=2e-4)


def test_deep_diode_collects_everything_that_enters():
    # 1/α(500 nm) ≈ 0.9 µm, so 100 µm leaves exp(-111) ≈ 0.
    assert float(photodiode_qe(500.0, 100.0)) == pytest.approx(1 - float(reflectance(500.0)), rel=1e-12)
    assert float(photodiode_qe(500.0, 100.0, reflectance_loss=False)) == pytest.approx(1.0, rel=1e-12)


@pytest.mark.parametrize("wl", [450.0, 550.0, 700.0, 900.0])
def test_thin_diode_is_linear_in_depth(wl):
    d = 1e-3  # µm, so α·d ≤ 0.0024 (at 450 nm)
    alpha = float(absorption_coefficient_per_um(wl))
    qe = float(photodiode_qe(wl, d))
    linear = (1 - float(reflectance(wl))) * alpha * d
    assert qe == pytest.approx(linear, rel=alpha * d)  # next term is -(α·d)/2 relative
    assert qe < linear


def test_dead_layer_removes_the_surface_slab():
    wl = np.array([400.0, 450.0, 550.0, 650.0])
    full = photodiode_qe(wl, 3.0)
    surface = photodiode_qe(wl, 0.2)
    np.testing.assert_allclose(photodiode_qe(wl, 3.0, surface_dead_layer_um=0.2), full - surface, rtol=1e-12)
    np.testing.assert_array_equal(photodiode_qe(wl, 0.5, surface_dead_layer_um=0.5), 0.0)
    # A dead layer costs the blue (absorbed in the first ~0.1–0.4 µm) more than the red.
    loss = 1 - photodiode_qe(wl, 3.0, surface_dead_layer_um=0.2) / full
    assert np.all(np.diff(loss) < 0)


def test_red_response_depends_on_collection_depth():
    wl = np.arange(550.0, 701.0, 10.0)
    shallow = photodiode_qe(wl, 2.0)  # shallow-collection CMOS photodiode
    deep = photodiode_qe(wl, 20.0)
    assert np.all(np.diff(shallow) < 0)  # falls from green to red
    assert shallow[-1] / shallow[0] < 0.5  # 1/α(700) ≈ 5.3 µm ≫ 2 µm: weak red
    # 20 µm absorbs ~98 % even at 700 nm, so the deep diode is nearly flat (its slight rise
    # comes from the falling reflectance, 0.367 → 0.337).
    assert deep[-1] / deep[0] == pytest.approx(1.0, abs=0.05)
    assert deep[-1] > deep[0]
    # Without reflection loss the deep diode still falls slightly to the red: 1 - exp(-α·20 µm).
    ar = photodiode_qe(wl, 20.0, reflectance_loss=False)
    np.testing.assert_allclose(ar, 1 - np.exp(-absorption_coefficient_per_um(wl) * 20.0), rtol=1e-12)
    assert ar[-1] < ar[0]


def test_broadcasting_over_depths():
    qe = photodiode_qe(np.array([450.0, 650.0]), np.array([[1.0], [5.0], [20.0]]))
    assert qe.shape == (3, 2)
    assert np.all(np.diff(qe, axis=0) >= 0)  # deeper collection never collects less


@pytest.mark.parametrize("bad", [249.0, 1451.0, np.nan, [500.0, 1500.0]])
def test_out_of_range_wavelengths_raise(bad):
    for f in (absorption_coefficient_per_um, reflectance, lambda w: photodiode_qe(w, 2.0)):
        with pytest.raises(ValueError):
            f(bad)


@pytest.mark.parametrize("depth, dead", [(-1.0, 0.0), (1.0, 2.0), (1.0, -0.1)])
def test_invalid_depths_raise(depth, dead):
    with pytest.raises(ValueError):
        photodiode_qe(550.0, depth, surface_dead_layer_um=dead)


def test_doctests():
    result = doctest.testmod(si, optionflags=doctest.ELLIPSIS)
    assert result.attempted >= 3 and result.failed == 0
