"""Spatial metrics against closed forms and published parameters: ISO 12233 e-SFR, S-CIELAB."""
import doctest
import importlib

import colour
import numpy as np
import pytest
from scipy import ndimage
from scipy.optimize import brentq
from scipy.special import ndtr

from spectracam.core.cielab import delta_e, xyz_to_lab
from spectracam.experiments.spatial import (SCIELAB_FILTERS, XYZ_TO_OPPONENT, XYZ_TO_OPPONENT_AS_PRINTED, esfr,
                                samples_per_degree, scielab, scielab_filter, scielab_kernels)

# the package re-exports the functions under the submodules' names, so fetch the modules themselves
esfr_module = importlib.import_module("spectracam.evaluation.esfr")
scielab_module = importlib.import_module("spectracam.evaluation.scielab")

# ----------------------------------------------------------------------------------------------- e-SFR

SIGMA = 0.6  # px, Gaussian PSF


def slanted_edge(rows=100, cols=64, angle_deg=5.0, sigma=SIGMA, lo=0.2, hi=0.8, n_sub=16, x0=None):
    """Pixel values of a straight edge blurred by a Gaussian PSF and integrated over each pixel's area.

    The blurred edge at signed distance d from the edge line is lo + (hi - lo) Φ(d / σ); each pixel is its
    mean over n_sub × n_sub points of the pixel footprint (midpoint rule). Contrast hi/lo = 4:1 by default
    (ISO 12233:2017). The edge passes through (x0, rows/2) at angle_deg from the vertical, its column
    increasing with the row.
    """
    t = np.radians(angle_deg)
    x0 = cols / 2 - 0.3 if x0 is None else x0
    sub = (np.arange(n_sub) + 0.5) / n_sub - 0.5
    r = np.arange(rows)[:, None, None, None] + sub[None, None, :, None]
    c = np.arange(cols)[None, :, None, None] + sub[None, None, None, :]
    d = (c - x0) * np.cos(t) - (r - rows / 2) * np.sin(t)
    return lo + (hi - lo) * ndtr(d / sigma).mean(axis=(2, 3))


def closed_form_mtf(f, sigma=SIGMA):
    """|MTF| of the Gaussian PSF times the pixel aperture: exp(-2π²σ²f²) |sinc f|."""
    return np.exp(-2 * np.pi**2 * sigma**2 * f**2) * np.abs(np.sinc(f))


MTF50_CLOSED = brentq(lambda f: closed_form_mtf(f) - 0.5, 0.05, 0.9)  # 0.28072 cy/px


@pytest.fixture(scope="module")
def edge_5deg():
    return slanted_edge()


def test_esfr_matches_closed_form_with_binning_correction(edge_5deg):
    res = esfr(edge_5deg, correct_binning=True)
    f, sfr = res.frequencies_cy_per_px, res.sfr
    assert res.orientation == "vertical"
    assert res.edge_angle_deg == pytest.approx(5.0, abs=0.01)
    assert f[0] == 0 and sfr[0] == pytest.approx(1.0) and f[-1] >= 1.0
    band = f <= 0.5
    assert band.sum() > 20
    np.testing.assert_array_less(np.abs(sfr[band] / closed_form_mtf(f[band]) - 1), 0.01)   # measured: ≤ 0.45 %
    assert np.abs(sfr - closed_form_mtf(f)).max() < 0.005                                  # to 1 cy/px: 7e-4
    assert res.mtf50_cy_per_px == pytest.approx(MTF50_CLOSED, rel=0.01)                    # measured: +0.08 %


@pytest.mark.parametrize("rows, angle", [(100, 5.0), (80, 4.0), (128, 7.5)])
def test_esfr_uses_a_whole_number_of_phase_cycles(rows, angle):
    """ISO 12233 (and sfrmat) keep floor(rows·tanθ)/tanθ rows, so that every quarter-pixel bin is filled
    equally often (100 rows at 5°: 8 cycles in 91.4 rows → 91)."""
    res = esfr(slanted_edge(rows=rows, angle_deg=angle), correct_binning=True)
    t = np.tan(np.radians(angle))
    assert res.rows_used == round(np.floor(rows * t) / t)


def test_esfr_window_is_centred_on_the_line_spread_and_spans_the_region():
    """A wide blur (σ = 2 px) whose line spread reaches the window's skirts: the SFR must not depend on
    where the edge lies in the region (the window follows the LSF's peak) and must match the closed
    form (a window of half the width loses the tails: +0.026 at low frequency)."""
    sigma = 2.0
    out = []
    for x0 in (31.7, 18.3, 44.6):
        res = esfr(slanted_edge(sigma=sigma, x0=x0), correct_binning=True)
        f = res.frequencies_cy_per_px
        band = f <= 0.5
        assert np.abs(res.sfr[band] - closed_form_mtf(f[band], sigma)).max() < 0.01   # measured: ≤ 0.0066
        out.append(res.sfr[band])
    for other in out[1:]:
        assert np.abs(other - out[0]).max() < 5e-4                                     # measured: ≤ 1e-4


def test_esfr_iso_default_is_within_the_binning_loss(edge_5deg):
    # the standard's algorithm averages the ESF over 1/4-pixel bins: sinc(f cosθ/4) = -2.5 % at 0.5 cy/px
    res = esfr(edge_5deg)
    f, sfr = res.frequencies_cy_per_px, res.sfr
    err = sfr / closed_form_mtf(f) - 1
    assert np.abs(err[f <= 0.3]).max() < 0.01          # measured: 0.67 %
    assert np.abs(err[f <= 0.5]).max() < 0.03          # measured: 1.95 %
    assert res.mtf50_cy_per_px == pytest.approx(MTF50_CLOSED, rel=0.01)  # measured: -0.42 %
    assert res.bin_width_px == pytest.approx(np.cos(np.radians(5.0)) / 4, rel=1e-4)


@pytest.mark.parametrize("angle", [-7.0, 3.0, 10.0])
def test_esfr_near_horizontal_edge(angle):
    img = slanted_edge(rows=64, cols=100, angle_deg=angle).T  # a near-horizontal edge
    res = esfr(img, correct_binning=True)
    assert res.orientation == "horizontal"
    assert res.edge_angle_deg == pytest.approx(angle, abs=0.01)
    f = res.frequencies_cy_per_px
    band = f <= 0.5
    # the closed form of the brief ignores the aperture's sinc(f sinθ) along the normal: 0.4 % at 10°, 0.5 cy/px
    np.testing.assert_array_less(np.abs(res.sfr[band] / closed_form_mtf(f[band]) - 1), 0.01)
    assert res.mtf50_cy_per_px == pytest.approx(MTF50_CLOSED, rel=0.01)


def test_esfr_transpose_and_polarity_invariant(edge_5deg):
    ref = esfr(edge_5deg)
    for img in (edge_5deg.T, 1.0 - edge_5deg):
        res = esfr(img)
        np.testing.assert_allclose(res.sfr, ref.sfr, atol=1e-9)
        assert res.edge_angle_deg == pytest.approx(ref.edge_angle_deg, abs=1e-9)
    flipped = esfr(edge_5deg[::-1])  # the other slant: other rows are kept, so other sample phases
    assert flipped.edge_angle_deg == pytest.approx(-ref.edge_angle_deg, abs=1e-3)
    np.testing.assert_allclose(flipped.sfr, ref.sfr, atol=0.01)


def test_esfr_quadratic_fit_of_a_straight_edge_agrees(edge_5deg):
    lin, quad = esfr(edge_5deg), esfr(edge_5deg, fit_order=2)
    assert quad.mtf50_cy_per_px == pytest.approx(lin.mtf50_cy_per_px, rel=1e-3)


def test_esfr_with_noise_stays_close(edge_5deg):
    noisy = edge_5deg + np.random.default_rng(3).normal(0.0, 0.002, edge_5deg.shape)
    assert esfr(noisy).mtf50_cy_per_px == pytest.approx(MTF50_CLOSED, rel=0.03)


@pytest.mark.parametrize("name, image, says", [
    ("uniform", np.full((60, 60), 0.4), "no edge"),
    ("noise", np.random.default_rng(0).normal(0.5, 0.05, (60, 60)), "no edge"),
    ("too small", slanted_edge(rows=6, cols=6), "too small"),
    ("one row", np.linspace(0, 1, 64), "2-D"),
    ("colour", np.zeros((20, 20, 3)), "2-D"),
    ("nan", np.where(slanted_edge() > 0.5, np.nan, 0.2), "NaN"),
    ("no slant", slanted_edge(angle_deg=0.0), "too close to the pixel axis"),
    ("edge off the region", slanted_edge(x0=1.0), "leaves the region"),
])
def test_esfr_bad_input_raises_one_line(name, image, says):
    with pytest.raises(ValueError, match=says) as err:
        esfr(image)
    assert "\n" not in str(err.value) and str(err.value).startswith("e-SFR: ")


# --------------------------------------------------------------------------------------------- S-CIELAB

# Zhang & Wandell, "A spatial extension of CIELAB for digital color-image reproduction", J. Soc. Inf.
# Display 5(1), 61-63 (1997) (SID Digest 1996): (weight, spread in degrees) of exp(-(x²+y²)/s²).
PUBLISHED_FILTERS = {
    "luminance": [(0.921, 0.0283), (0.105, 0.133), (-0.108, 4.336)],
    "red_green": [(0.531, 0.0392), (0.330, 0.494)],
    "blue_yellow": [(0.488, 0.0536), (0.371, 0.386)],
}
# ibid.: O1 = 0.279X + 0.72Y - 0.107Z, O2 = -0.449X + 0.29Y - 0.077Z, O3 = 0.086X - 0.59Y + 0.501Z
PUBLISHED_OPPONENT = [[0.279, 0.72, -0.107], [-0.449, 0.29, -0.077], [0.086, -0.59, 0.501]]
# ISETCam metrics/scielab/cmatrix.m ('xyz2opp', CIE 1931 2°), from X. Zhang's 1996-98 distribution
ISETCAM_XYZ2OPP = np.array([[278.7336, 721.8031, -106.5520],
                            [-448.7736, 289.8056, 77.1569],
                            [85.9513, -589.9859, 501.1089]]) / 1000
# Zhang's distribution (ISETCam separableFilters.m, scGaussianParameters.m 'distribution'): weights
# normalised to sum 1, spreads as full widths at half maximum
DISTRIBUTION = {
    "luminance": [(0.05, 1.00327), (0.225, 0.114416), (7.0, -0.117686)],
    "red_green": [(0.0685, 0.616725), (0.826, 0.383275)],
    "blue_yellow": [(0.0920, 0.567885), (0.6451, 0.432115)],
}
D65 = np.array([0.95047, 1.0, 1.08883])


def test_filter_parameters_are_the_published_ones():
    assert {k: [tuple(c) for c in v] for k, v in SCIELAB_FILTERS.items()} == PUBLISHED_FILTERS
    np.testing.assert_array_equal(XYZ_TO_OPPONENT_AS_PRINTED, PUBLISHED_OPPONENT)
    np.testing.assert_allclose(XYZ_TO_OPPONENT, ISETCAM_XYZ2OPP, rtol=1e-12)
    # the code's matrix rounds to the printed one except the sign of O2's Z coefficient (see the module)
    diff = np.abs(XYZ_TO_OPPONENT - np.asarray(PUBLISHED_OPPONENT))
    diff[1, 2] = abs(abs(XYZ_TO_OPPONENT[1, 2]) - 0.077)
    assert diff.max() < 0.0025


def test_weights_match_the_reference_distribution():
    for ch, comps in PUBLISHED_FILTERS.items():
        w = np.array([c[0] for c in comps])
        np.testing.assert_allclose(w / w.sum(), [c[1] for c in DISTRIBUTION[ch]], atol=5e-4)
        # the distribution's spreads are the full widths at half maximum (2√ln2 s) of the paper's Gaussians
        ratio = np.array([c[0] for c in DISTRIBUTION[ch]]) / np.array([c[1] for c in comps])
        np.testing.assert_allclose(ratio, 2 * np.sqrt(np.log(2)), rtol=0.07)


@pytest.mark.parametrize("spd", [10.0, 41.23, 64.0, 101.0, 224.0])
def test_kernels_sum_to_one_and_are_the_documented_sums(spd):
    kernels = scielab_kernels(spd)
    n = 2 * int(np.ceil(spd / 2)) - 1
    x = np.arange(n) - (n - 1) / 2
    r2 = x[:, None] ** 2 + x[None, :] ** 2
    for kern, comps in zip(kernels, PUBLISHED_FILTERS.values()):
        assert kern.shape == (n, n) and n % 2 == 1
        assert kern.sum() == pytest.approx(1.0, abs=1e-12)
        np.testing.assert_allclose(kern, kern.T, atol=1e-18)
        expected = sum(w * np.exp(-r2 / (s * spd) ** 2) / np.exp(-r2 / (s * spd) ** 2).sum() for w, s in comps)
        np.testing.assert_allclose(kern, expected / expected.sum(), rtol=1e-10, atol=1e-16)


def test_separable_filtering_equals_2d_convolution():
    rng = np.random.default_rng(5)
    img = rng.uniform(0.05, 0.9, (40, 36, 3))
    spd = 23.0
    opp = img @ XYZ_TO_OPPONENT.T
    expected = np.stack([ndimage.convolve(opp[..., c], k, mode="wrap") for c, k in enumerate(scielab_kernels(spd))], -1)
    expected = expected @ np.linalg.inv(XYZ_TO_OPPONENT).T
    np.testing.assert_allclose(scielab_filter(img, spd, boundary="wrap"), expected, atol=1e-12)


@pytest.mark.parametrize("method", ["cie1976", "ciede2000"])
@pytest.mark.parametrize("spd, size", [(40.0, 32), (101.0, 16)])  # 16 px is smaller than the 101-px kernel
def test_uniform_field_gives_cielab_exactly(method, spd, size):
    c1, c2 = np.array([0.31, 0.27, 0.12]), np.array([0.20, 0.22, 0.30])
    a, b = np.broadcast_to(c1, (size, size + 3, 3)), np.broadcast_to(c2, (size, size + 3, 3))
    expected = float(delta_e(xyz_to_lab(c1, D65), xyz_to_lab(c2, D65), method))
    for boundary in ("reflect", "wrap"):
        d = scielab(a, b, D65, spd, delta_e=method, boundary=boundary)
        assert d.shape == (size, size + 3)
        np.testing.assert_allclose(d, expected, rtol=0, atol=1e-9)


def _lab_to_xyz(lab):
    return colour.Lab_to_XYZ(lab, colour.XYZ_to_xy(D65)) * D65[1]


def test_chromatic_grating_is_attenuated_far_more_than_luminance():
    # the same CIELAB amplitude (5 units along L*, a* or b*) on a mid-grey, against the uniform grey
    spd, n = 64.0, 128
    grey = np.array([50.0, 0.0, 0.0])
    ref = np.broadcast_to(_lab_to_xyz(grey), (n, n, 3))

    def mean_de(axis, cpd, spatial=True):
        lab = np.tile(grey, (n, n, 1))
        lab[..., axis] += 5.0 * np.sin(2 * np.pi * cpd * np.arange(n) / spd)[None, :]
        xyz = _lab_to_xyz(lab)
        if not spatial:
            return float(delta_e(xyz_to_lab(ref, D65), xyz_to_lab(xyz, D65)).mean())
        return float(scielab(ref, xyz, D65, spd, boundary="wrap").mean())

    cielab = mean_de(0, 8.0, spatial=False)              # 2/π · 5 = 3.18, whatever the frequency
    lum, rg, by = (mean_de(axis, 8.0) for axis in range(3))
    assert lum < cielab and rg < lum / 3 and by < lum / 3  # measured: 2.04, 0.65, 0.37 at 8 cy/deg
    assert mean_de(1, 0.5) > 0.8 * cielab                  # the same red-green grating, coarse: 2.82
    assert mean_de(1, 16.0) < 0.05 * cielab                # fine: 0.06 (luminance: 0.49)


def test_samples_per_degree():
    # ISETCam scParams: 120 dpi viewed at 0.5 m → "about 41" samples per degree
    assert round(samples_per_degree(0.5, 25.4e-3 / 120)) == 41
    assert samples_per_degree(1.0, 1e-4) == pytest.approx(np.pi / 180 * 1.0 / 1e-4, rel=1e-6)
    assert samples_per_degree(2.0, 1e-4) == pytest.approx(2 * samples_per_degree(1.0, 1e-4), rel=1e-6)
    with pytest.raises(ValueError, match="positive"):
        samples_per_degree(0.0, 1e-4)


@pytest.mark.parametrize("kwargs, says", [
    (dict(xyz2=np.zeros((8, 9, 3))), "differ in shape"),
    (dict(xyz1=np.zeros((8, 8)), xyz2=np.zeros((8, 8))), "rows, cols, 3"),
    (dict(white_xyz=[0.95, 0.0, 1.09]), "white_xyz"),
    (dict(samples_per_degree=-3.0), "samples_per_degree"),
    (dict(boundary="zero"), "boundary"),
    (dict(delta_e="cie1994"), "cie1976"),
])
def test_scielab_bad_input(kwargs, says):
    args = dict(xyz1=np.full((8, 8, 3), 0.3), xyz2=np.full((8, 8, 3), 0.3), white_xyz=D65, samples_per_degree=20.0)
    args.update(kwargs)
    with pytest.raises(ValueError, match=says):
        scielab(**args)


@pytest.mark.parametrize("module", [esfr_module, scielab_module], ids=["esfr", "scielab"])
def test_doctests(module):
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0


def test_standard_esfr_is_the_closed_form_times_the_binning_loss(edge_5deg):
    """ISO 12233:2017 as stated averages the ESF over bins Δ = cos θ / 4 px wide, which multiplies the SFR by
    sinc(f·Δ): the standard's e-SFR is that expectation within 0.5 % up to 0.5 cy/px, and so is its MTF50."""
    res = esfr(edge_5deg)
    f, sfr = res.frequencies_cy_per_px, res.sfr
    expected = closed_form_mtf(f) * np.sinc(f * res.bin_width_px)
    band = f <= 0.5
    np.testing.assert_array_less(np.abs(sfr[band] / expected[band] - 1), 0.005)
    mtf50_expected = brentq(lambda x: closed_form_mtf(x) * np.sinc(x * res.bin_width_px) - 0.5, 0.05, 0.9)
    assert res.mtf50_cy_per_px == pytest.approx(mtf50_expected, rel=0.005)
    assert esfr(edge_5deg, correct_binning=True).mtf50_cy_per_px > res.mtf50_cy_per_px
