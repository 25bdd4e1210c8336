"""The score's compiled kernels (issue 38) give colour-science's, SciPy's and colour-demosaicing's numbers.

CIELAB, ΔE*ab and CIEDE2000 (``core/_numba_colour.py``), the per-box ΔE pass of the chart score and the bilinear
Bayer demosaicking (``processing/_numba_demosaic.py``) are checked against the libraries they replace, on inputs
that reach every branch (colours below CIE's ε, greys whose hue is undefined, hue differences across 0°, every
Bayer phase, odd image sizes), and a whole chart score against the same score with ``SPECTRACAM_FUSED=0``.
"""
import numpy as np
import pytest

from spectracam.core import cielab
from spectracam.core.cielab import FUSED_MIN_COLOURS, delta_e, rgb_to_lab, xyz_to_lab
from test_reference_values import load_sharma_table


@pytest.fixture
def fused():
    if cielab._kernels() is None:
        pytest.skip("the compiled colour kernels (numba) are not available here")


def colour_lab(xyz, white):
    import colour

    white = np.asarray(white, float)
    return colour.XYZ_to_Lab(np.asarray(xyz, float) / white[1], colour.XYZ_to_xy(white / white[1]))


def hard_colours(n, seed=0):
    """``n`` XYZ colours, a tenth of them so dark that CIE's lightness function takes its linear part."""
    rng = np.random.default_rng(seed)
    xyz = rng.random((n, 3)) * 1.1
    xyz[: n // 10] *= 1e-3
    xyz[n // 10: n // 10 + 3] = 0.0
    return xyz


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_lab_is_colour_sciences(fused, dtype):
    white = np.array([0.9505, 1.0, 1.089])
    xyz = hard_colours(2 * FUSED_MIN_COLOURS).astype(dtype)
    got = xyz_to_lab(xyz, white)
    assert got.shape == xyz.shape and got.dtype == np.float64
    np.testing.assert_allclose(got, colour_lab(xyz, white), rtol=0, atol=1e-12)
    # an image (H, W, 3) keeps its shape; a white of any Y scale
    img = xyz[: 64 * 128].reshape(64, 128, 3) * 7.0
    np.testing.assert_allclose(xyz_to_lab(img, 7.0 * white), colour_lab(img, 7.0 * white), rtol=0, atol=1e-12)


def test_rgb_to_lab_is_the_matrix_then_lab(fused):
    rng = np.random.default_rng(2)
    rgb = rng.random((FUSED_MIN_COLOURS + 5, 3))
    M = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
    white = M.sum(axis=1)
    np.testing.assert_allclose(rgb_to_lab(rgb, M, white), colour_lab(rgb @ M.T, white), rtol=0, atol=1e-11)
    small = rgb[:10]   # below the kernels' size: the array formulas, the same numbers
    np.testing.assert_allclose(rgb_to_lab(small, M, white), colour_lab(small @ M.T, white), rtol=0, atol=1e-12)


def test_ciede2000_kernel_on_sharmas_pairs(fused):
    table = load_sharma_table()
    reps = -(-FUSED_MIN_COLOURS // len(table))
    lab1, lab2, want = (np.tile(table[:, 0:3], (reps, 1)), np.tile(table[:, 3:6], (reps, 1)),
                        np.tile(table[:, 6], reps))
    got = delta_e(lab1, lab2, "ciede2000")
    assert got.shape == want.shape
    assert np.abs(got - want).max() <= 1e-4   # the table's four decimals


@pytest.mark.parametrize("method", ["cie1976", "ciede2000"])
def test_delta_e_kernels_are_colour_sciences(fused, method, monkeypatch):
    import colour

    rng = np.random.default_rng(3)
    n = FUSED_MIN_COLOURS * 2
    lab1 = np.column_stack([rng.random(n) * 100, rng.normal(0, 40, n), rng.normal(0, 40, n)])
    lab2 = lab1 + rng.normal(0, 3, (n, 3))
    lab1[:50, 1:] = 0.0                          # greys: hue undefined (0 by convention), C'1·C'2 = 0
    lab2[50:100, 1] = -np.abs(lab2[50:100, 1])   # hues either side of 180° and 0°
    lab1[50:100, 2], lab2[50:100, 2] = 1e-3, -1e-3
    ref = (np.linalg.norm(lab1 - lab2, axis=-1) if method == "cie1976"
           else colour.delta_E(lab1, lab2, method="CIE 2000"))
    np.testing.assert_allclose(delta_e(lab1, lab2, method), ref, rtol=0, atol=1e-10)
    one = np.array([50.0, 3.0, -4.0])   # every colour against one
    ref_one = (np.linalg.norm(lab1 - one, axis=-1) if method == "cie1976"
               else colour.delta_E(lab1, one, method="CIE 2000"))
    np.testing.assert_allclose(delta_e(lab1, one, method), ref_one, rtol=0, atol=1e-10)
    monkeypatch.setenv("SPECTRACAM_FUSED", "0")   # the switch: colour-science's own, the same numbers
    assert cielab._kernels() is None
    np.testing.assert_allclose(delta_e(lab1, lab2, method), ref, rtol=0, atol=1e-12)


@pytest.mark.parametrize("pattern", ["RGGB", "GRBG", "BGGR", "GBRG"])
@pytest.mark.parametrize("shape", [(2, 2), (3, 2), (7, 9), (120, 160), (1100, 37)])
def test_bilinear_bayer_is_colour_demosaicings(fused, pattern, shape):
    import colour_demosaicing as cd

    from spectracam.architecture.base import MosaicLayout
    from spectracam.processing.color import demosaic

    mosaic = np.random.default_rng(4).random(shape) * 1000
    want = cd.demosaicing_CFA_Bayer_bilinear(mosaic, pattern)
    for m in (mosaic, mosaic.astype(np.float32)):
        got = demosaic(m, MosaicLayout.bayer(pattern), "bilinear")
        ref = want if m.dtype == np.float64 else cd.demosaicing_CFA_Bayer_bilinear(m, pattern)
        assert got.shape == (*shape, 3) and got.dtype == np.float64
        np.testing.assert_allclose(got, ref, rtol=1e-15, atol=0)


@pytest.mark.parametrize("method", ["cie1976", "ciede2000"])
def test_a_chart_score_is_the_same_without_the_kernels(fused, method, monkeypatch):
    """The whole chart score — the box ΔE pass, S-CIELAB's CIELAB and ΔE, the demosaicking — against the same
    capture scored with ``SPECTRACAM_FUSED=0`` (colour-science, colour-demosaicing)."""
    from conftest import small_scene
    from spectracam import capture, render, score

    scene = small_scene(image={"width": 240, "height": 180}, processing={"delta_e": method})
    raw = capture(render(scene, "analytic"), scene=scene)
    a = score(raw, scene)
    monkeypatch.setenv("SPECTRACAM_FUSED", "0")
    b = score(raw, scene)
    from dataclasses import asdict

    for key, va in asdict(a.summary).items():
        vb = getattr(b.summary, key)
        if isinstance(va, float):
            assert va == pytest.approx(vb, rel=1e-10, abs=1e-12), key
    for pa, pb in zip(a.patches, b.patches):
        assert pa.delta_e_mean == pytest.approx(pb.delta_e_mean, rel=1e-10)
        assert pa.s_cielab_mean == pytest.approx(pb.s_cielab_mean, rel=1e-9)
    np.testing.assert_allclose(a.delta_e_map, b.delta_e_map, rtol=1e-6, equal_nan=True)
    assert np.isnan(a.delta_e_map).sum() == np.isnan(b.delta_e_map).sum() > 0


@pytest.mark.parametrize("n", [1, 2, 7, 1000, 100_000])
def test_the_p95_of_a_map_is_nanpercentiles(n):
    """The summary's 95th percentiles (ΔE and S-CIELAB maps, NaN off the scored pixels) drop the NaNs by one mask
    and take ``np.percentile``: exactly ``np.nanpercentile``'s value, and NaN for a map with nothing scored."""
    import warnings

    from spectracam.evaluation.score import _p95

    rng = np.random.default_rng(n)
    a = rng.gamma(2.0, 1.5, (n, 3)).astype(np.float32)
    a[rng.random((n, 3)) < 0.6] = np.nan
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)   # nanpercentile of all-NaN warns; _p95 returns NaN quietly
        want = float(np.nanpercentile(a, 95))
    got = _p95(a)
    assert (np.isnan(want) and np.isnan(got)) or got == want
    assert np.isnan(_p95(np.full((4, 5), np.nan, np.float32)))


@pytest.mark.parametrize("shape", [(1, 1, 3), (3, 5, 3), (301, 7, 3), (700, 1000, 3)])
def test_the_rendering_is_narrowed_to_float32_in_its_own_buffer(shape, monkeypatch):
    """The score's float32 rendering is ``astype``'s values, made without a second full-size image (issue 38: the
    score's resident peak): it lives in the float64 image's own buffer, shrunk to half; chunks smaller than the
    image are exercised."""
    from spectracam.evaluation import score as S

    monkeypatch.setattr(S, "NARROW_CHUNK", 1000)
    held = [np.random.default_rng(1).normal(size=shape) * 1e3]   # the list is the only reference, as in score()
    want = held[0].astype(np.float32)
    got = S._narrowed_to_float32(held)
    assert got.dtype == np.float32 and got.shape == shape and got.flags.c_contiguous
    np.testing.assert_array_equal(got, want)
    root = got
    while root.base is not None:
        root = root.base
    assert root.dtype == np.float64 and root.size == (want.size + 1) // 2   # the old buffer, shrunk; not a copy


def test_narrowing_leaves_an_image_others_refer_to_alone():
    """A view of the float64 image elsewhere (or a view as the image): ``astype``, the image unchanged."""
    from spectracam.evaluation import score as S

    a = np.random.default_rng(2).random((40, 30, 3))
    copy = a.copy()
    got = S._narrowed_to_float32([a])            # one other reference: this test's name
    np.testing.assert_array_equal(got, copy.astype(np.float32))
    np.testing.assert_array_equal(a, copy)
    view = a[5:]
    got = S._narrowed_to_float32([a])
    np.testing.assert_array_equal(got, copy.astype(np.float32))
    np.testing.assert_array_equal(a, copy)
    assert view.base is a
    got = S._narrowed_to_float32([view])
    np.testing.assert_array_equal(got, copy[5:].astype(np.float32))
    np.testing.assert_array_equal(a, copy)


@pytest.mark.parametrize("architecture", ["cfa", "quad_bayer", "rgbw", "fsc"])
def test_channel_statistics_of_alike_boxes_reduced_together_are_each_boxs_own(architecture):
    """Boxes of one size and tile phase are reduced in one NumPy call (issue 38): each box's mean and std equal the
    same reductions over that box's own pixels of the channel, bit for bit, for boxes of many sizes and phases,
    repeated boxes among them."""
    from conftest import small_scene
    from spectracam import capture, render
    from spectracam.architecture.base import MosaicLayout
    from spectracam.evaluation.score import channel_stats
    from spectracam.sensor import adc_inverse

    scene = small_scene(image={"width": 96, "height": 72}, capture={"architecture": architecture})
    raw = capture(render(scene, "analytic"), scene=scene)
    rng = np.random.default_rng(4)
    boxes = [(slice(r, r + h), slice(c, c + w)) for r, c, h, w in zip(rng.integers(0, 60, 30), rng.integers(0, 80, 30),
                                                                        rng.integers(4, 12, 30), rng.integers(4, 12, 30))]
    boxes += [(slice(9, 17), slice(21, 29))] * 3
    means, stds = channel_stats(raw, boxes)
    s, layout = raw.camera.sensor, raw.layout
    dark = s.dark_rate_e_per_s * np.asarray(raw.exposure_times_s)
    for p, (r, c) in enumerate(boxes):
        for k in range(len(layout.channels)):
            if isinstance(layout, MosaicLayout):
                th, tw = layout.tile_shape
                e = adc_inverse(raw.digital[r, c], s) - dark[0]
                pix = np.concatenate([e[(dy - r.start) % th::th, (dx - c.start) % tw::tw].ravel()
                                      for dy, dx, kk in layout.sites() if kk == k])
            else:
                pix = (adc_inverse(raw.digital[k, r, c], s) - dark[k]).ravel()
            assert means[p, k] == pix.mean() and stds[p, k] == (0.0 if pix.max() == pix.min() else pix.std()), (p, k)


def test_narrowing_under_a_profiler_and_a_tracer():
    """Under cProfile (whose reference to the bound method once made ``ndarray.resize``'s own check refuse, after the
    values were narrowed) and under a tracer (coverage's way), the narrowing gives ``astype``'s values."""
    import cProfile
    import sys

    from spectracam.evaluation import score as S

    a = np.random.default_rng(5).random((64, 48, 3))
    want = a.astype(np.float32)
    held = [a]
    del a
    np.testing.assert_array_equal(cProfile.Profile().runcall(S._narrowed_to_float32, held), want)
    held = [want.astype(np.float64)]
    sys.settrace(lambda frame, event, arg: None)
    try:
        got = S._narrowed_to_float32(held)
    finally:
        sys.settrace(None)
    np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("kernels", ["1", "0"])
@pytest.mark.parametrize("method,layout", [("bilinear", "GRBG"), ("bilinear", "BGGR"), ("malvar2004", "RGGB"),
                                           ("patch", "GRBG")])
def test_demosaicking_with_a_divisor_is_demosaicking_then_dividing(kernels, method, layout, monkeypatch):
    """The exposure normalisation divided in as the compiled bilinear pass writes (issue 38) gives, bit for bit,
    the demosaicked image divided afterwards; so do the other methods and the path without the kernels."""
    from spectracam.architecture.base import MosaicLayout
    from spectracam.processing.color import demosaic

    monkeypatch.setenv("SPECTRACAM_FUSED", kernels)
    lay = MosaicLayout.bayer(layout)
    mosaic = np.random.default_rng(6).random((64, 48)) * 3000
    times = np.array([0.0123, 0.0301, 0.00711])[:len(lay.channels)]
    want = demosaic(mosaic, lay, method) / times[None, None, :]
    np.testing.assert_array_equal(demosaic(mosaic, lay, method, divisor=times), want)
