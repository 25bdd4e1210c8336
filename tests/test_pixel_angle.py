"""The pixel's response to angle (microlens acceptance, optical and electrical crosstalk, CFA mixing) and lens-shading
correction with the Raspberry Pi HQ camera's shipped tables (issue 37, items 2, 4 and 6)."""
import numpy as np
import pytest

import spectracam.architecture.silicon as si
from spectracam.core.errors import ConfigError, SpectracamError
from spectracam.processing.shading import (ShadingSpec, apply_gain_tables, calibrate_gain_tables,
                                           find_libcamera_tuning, interpolate_tables_by_cct, ShadingTables,
                                           luminance_and_colour_tables, read_libcamera_alsc,
                                           residual_colour_shading, table_figures)
from spectracam.sensor.angle import (PixelAngleSpec, apply_crosstalk, crosstalk_kernel, effective_responsivities,
                                     identity_kernel, microlens_acceptance, microlens_shift_um, pixel_angle_response)

WL = np.arange(400.0, 701.0, 10.0)
ALPHA = si.absorption_coefficient_per_um(WL)
N_SI = np.interp(WL, si._table().wavelength_nm, si._table().n)
RGGB = [[0, 1], [1, 2]]
#: A small back-side-illuminated-like pixel, where crosstalk matters (the IMX477's pitch is 1.55 µm).
SMALL = dict(pixel_pitch_um=1.55, collection_depth_um=3.0, f_number=2.8)
ALL_ON = PixelAngleSpec(microlens=True, optical_crosstalk=True, electrical_crosstalk=True, aperture_fraction=0.8)


def _responsivities():
    lam = WL[None, :]
    centres = np.array([[610.0], [540.0], [460.0]])
    return 0.5 * np.exp(-0.5 * ((lam - centres) / 35.0) ** 2)


def _leak(kernel):
    return kernel.sum((-2, -1)) - kernel[..., 1, 1]


def test_charge_is_conserved_by_crosstalk():
    k = crosstalk_kernel(25.0, WL, ALPHA, N_SI, ALL_ON, azimuth_deg=35.0, **SMALL)  # (B, 3, 3)
    q = np.full((20, 30), 1000.0)
    for b in (0, 15, 30):
        out = apply_crosstalk(q, k[b])
        assert out.sum() == pytest.approx(q.sum() * k[b].sum(), rel=1e-12)
        unit = k[b] / k[b].sum()
        assert apply_crosstalk(q, unit).sum() == pytest.approx(q.sum(), rel=1e-12)
        np.testing.assert_allclose(apply_crosstalk(q, unit)[5:-5, 5:-5], 1000.0, rtol=1e-12)
    per_pixel = np.broadcast_to(k[20], (20, 30, 3, 3))
    rng = np.random.default_rng(0)
    q2 = rng.uniform(0, 1000, (20, 30))
    assert apply_crosstalk(q2, per_pixel).sum() == pytest.approx((q2 * k[20].sum()).sum(), rel=1e-12)


def test_centred_pixel_at_normal_incidence_with_crosstalk_off_is_todays_response():
    R = _responsivities()
    for spec in (PixelAngleSpec(), PixelAngleSpec(microlens=True)):
        k = pixel_angle_response(0.0, WL, ALPHA, N_SI, spec, **SMALL)
        np.testing.assert_array_equal(k, identity_kernel((), WL.size))
        eff = effective_responsivities(RGGB, R, k)
        np.testing.assert_array_equal(eff, R[np.array(RGGB)])
    off = pixel_angle_response(np.array([0.0, 20.0, 35.0]), WL, ALPHA, N_SI, PixelAngleSpec(), **SMALL)
    np.testing.assert_array_equal(off, identity_kernel((3,), WL.size))  # all off: unchanged across the field


def test_microlens_acceptance_is_one_at_normal_incidence_and_falls_with_angle():
    spec = PixelAngleSpec(microlens=True)
    theta = np.array([0.0, 5.0, 10.0, 20.0, 30.0])
    acc = microlens_acceptance(theta, WL, spec, pixel_pitch_um=1.55, f_number=2.8)
    np.testing.assert_array_equal(acc[0], 1.0)
    assert np.all(np.diff(acc, axis=0) < 0)
    # the stated model: the fraction of a Gaussian spot inside the opening, displaced by h·tan(asin(sin θ/n))
    from scipy.special import erf
    from spectracam.sensor.angle import spot_sigma_um
    s = spot_sigma_um(550.0, spec, pixel_pitch_um=1.55, f_number=2.8)
    d, half = 4.0 * np.tan(np.arcsin(np.sin(np.radians(10.0)) / 1.46)), 0.5 * 0.5 * 1.55
    inside = lambda c: 0.5 * (erf((half - c) / (np.sqrt(2) * s)) + erf((half + c) / (np.sqrt(2) * s)))  # noqa: E731
    assert microlens_acceptance(10.0, [550.0], spec, pixel_pitch_um=1.55, f_number=2.8)[0] == \
        pytest.approx(inside(d) / inside(0.0), rel=1e-12)
    top = microlens_acceptance(theta, WL, PixelAngleSpec(microlens=True, spot="tophat"), pixel_pitch_um=1.55)
    assert top[0, 0] == 1.0 and np.all(np.diff(top, axis=0) <= 1e-12) and top[2, 0] < 1


def test_microlens_shift_cancels_a_stated_cra():
    spec = PixelAngleSpec(microlens=True)
    for cra in (10.0, 25.0):
        shift = microlens_shift_um(cra, spec)
        assert shift == pytest.approx(4.0 * np.tan(np.arcsin(np.sin(np.radians(cra)) / 1.46)), rel=1e-12)
        with_shift = microlens_acceptance(cra, WL, spec, pixel_pitch_um=1.55, f_number=2.8, shift_um=shift,
                                          azimuth_deg=30.0)
        np.testing.assert_allclose(with_shift, 1.0, rtol=0, atol=1e-12)
        without = microlens_acceptance(cra, WL, spec, pixel_pitch_um=1.55, f_number=2.8)
        assert np.all(without < 0.99)


def test_crosstalk_grows_with_wavelength_and_with_angle():
    spec = PixelAngleSpec(optical_crosstalk=True, aperture_fraction=0.8)
    theta = np.array([0.0, 10.0, 20.0, 30.0])
    k = crosstalk_kernel(theta, WL, ALPHA, N_SI, spec, **SMALL)
    leak = _leak(k) / k.sum((-2, -1))  # (4, B) fraction of the collected charge in the neighbours
    blue, red = np.searchsorted(WL, 450.0), np.searchsorted(WL, 650.0)
    assert leak[0].max() < 1e-12  # normal incidence, spot inside the opening: no optical crosstalk
    assert np.all(np.diff(leak[:, red]) >= 0) and np.all(np.diff(leak[1:, red]) > 0)
    assert np.all(np.diff(leak[:, blue]) >= 0)
    assert np.all(leak[2:, red] > leak[2:, blue] + 0.03)  # red, absorbed deeper, leaks more (from 20°)
    assert leak[3, red] > 0.05
    assert np.all(k[1:, :, :, 2].sum(-1) >= k[1:, :, :, 0].sum(-1))  # towards the image height (azimuth 0: +x)
    el = crosstalk_kernel(0.0, WL, ALPHA, N_SI, PixelAngleSpec(electrical_crosstalk=True), **SMALL)
    assert _leak(el)[red] > _leak(el)[blue] > 0  # diffusion: deeper carriers, more spread


def test_cfa_colour_mixing_follows_the_kernel():
    R = _responsivities()
    k = pixel_angle_response(25.0, WL, ALPHA, N_SI, ALL_ON, azimuth_deg=0.0, **SMALL)
    eff = effective_responsivities(RGGB, R, k)
    assert eff.shape == (2, 2, WL.size)
    # the red site (0, 0) gains green light from its left and right neighbours (columns ±1 are G)
    g_in = R[1] * (k[:, 1, 0] + k[:, 1, 2]) + R[1] * (k[:, 0, 1] + k[:, 2, 1]) + R[2] * (
        k[:, 0, 0] + k[:, 0, 2] + k[:, 2, 0] + k[:, 2, 2])
    np.testing.assert_allclose(eff[0, 0], R[0] * k[:, 1, 1] + g_in, rtol=1e-12)
    # summed over a tile, the recorded charge is the tile's generated charge × the kernel's sum (nothing lost)
    np.testing.assert_allclose(eff.sum((0, 1)), R[np.array(RGGB)].sum((0, 1)) * k.sum((-2, -1)), rtol=1e-12)


def _field(shape=(240, 320)):
    h, w = shape
    y, x = np.mgrid[0:h, 0:w]
    return np.hypot((x - (w - 1) / 2) / ((w - 1) / 2), (y - (h - 1) / 2) / ((h - 1) / 2)) / np.sqrt(2)


def test_shading_correction_under_the_same_light_leaves_a_flat_field_flat():
    r = _field()
    base = np.cos(np.radians(30.0) * r) ** 4  # cos⁴ fall-off to a CRA of 30° at the corner
    flat = np.stack([base * (1 - 0.1 * r**2), base, base * (1 - 0.02 * r**2)]) * 100
    fine = calibrate_gain_tables(flat, ShadingSpec(grid_rows=32, grid_columns=32))  # PiSP's 32×32 grid
    res = residual_colour_shading(apply_gain_tables(flat, fine))
    assert max(res["max_channel_deviation"]) < 1e-3
    coarse = calibrate_gain_tables(flat)  # libcamera's VC4 16×12: bilinear cannot follow cos⁴ better than ~0.5 %
    res = residual_colour_shading(apply_gain_tables(flat, coarse))
    assert max(res["max_channel_deviation"]) < 5e-3
    mild = np.cos(np.radians(15.0) * r) ** 4 * np.ones((3, 1, 1))
    res = residual_colour_shading(apply_gain_tables(mild, calibrate_gain_tables(mild)))
    assert max(res["max_channel_deviation"]) < 1e-3


def test_shading_correction_under_another_light_leaves_colour_shading():
    r = _field()
    base = np.cos(np.radians(25.0) * r) ** 4
    warm = np.stack([base * (1 - 0.10 * r**2), base, base * (1 - 0.02 * r**2)])  # red falls off more under it
    cool = np.stack([base * (1 - 0.04 * r**2), base, base * (1 - 0.01 * r**2)])
    tables = calibrate_gain_tables(warm, ShadingSpec(grid_rows=32, grid_columns=32))
    res = residual_colour_shading(apply_gain_tables(cool, tables))
    assert res["max_colour_deviation"][1] == 0.0
    assert res["corner_colour_ratio"][0] == pytest.approx((1 - 0.04) / (1 - 0.10), rel=2e-3)  # R/G too high
    assert res["max_colour_deviation"][0] > 0.05 and res["max_colour_deviation"][2] > 0.005
    same = residual_colour_shading(apply_gain_tables(warm * np.array([2.0, 1.0, 0.5])[:, None, None], tables))
    assert max(same["max_colour_deviation"]) < 1e-3  # a channel's scale (white balance) is not shading
    by_cct = {3000.0: tables, 6000.0: calibrate_gain_tables(cool, ShadingSpec(grid_rows=32, grid_columns=32))}
    mid = interpolate_tables_by_cct(by_cct, 4500.0)
    np.testing.assert_allclose(mid.gains, 0.5 * (by_cct[3000.0].gains + by_cct[6000.0].gains), rtol=1e-12)
    assert interpolate_tables_by_cct(by_cct, 9000.0) is by_cct[6000.0]
    lum, colour = luminance_and_colour_tables(tables)
    assert lum.min() == 1.0 and np.all(colour[1] == 1.0) and colour[0, 0, 0] > colour[0, 16, 16]


def test_imx477_tables():
    path = find_libcamera_tuning("imx477")
    if path is None:
        pytest.skip("the Raspberry Pi HQ camera's tuning file (Debian package libcamera-ipa) is not installed: "
                    "apt-get install libcamera-ipa")
    alsc = read_libcamera_alsc(path)
    lum = table_figures(alsc.luminance_lut)
    print(f"\n{path}: luminance_lut corner {lum['corners']}, centre {lum['centre']:.3f}, min {lum['min']:.3f}")
    # the 1.55 / 1.01: the top-left cell is 1.548, the central four average 1.012 (minimum 1.009)
    assert lum["corners"][0] == pytest.approx(1.55, abs=0.005) and lum["centre"] == pytest.approx(1.01, abs=0.005)
    assert 1.5 < lum["corner_over_centre"] < 1.65 and alsc.luminance_strength == 0.5
    assert sorted(alsc.cr_by_cct) == sorted(alsc.cb_by_cct) == [2960.0, 4850.0, 5930.0]
    for ct in alsc.cr_by_cct:
        cr, cb = table_figures(alsc.cr_by_cct[ct]), table_figures(alsc.cb_by_cct[ct])
        print(f"  {ct:.0f} K: Cr centre {cr['centre']:.3f} corner/centre {cr['corner_over_centre']:.4f}; "
              f"Cb centre {cb['centre']:.3f} corner/centre {cb['corner_over_centre']:.4f}")
        assert cr["corner_over_centre"] > 1.01  # red needs more gain at the corners than green
        assert cb["corner_over_centre"] < 1.0  # blue needs less
    cr = [alsc.cr_by_cct[ct][5:7, 7:9].mean() for ct in sorted(alsc.cr_by_cct)]
    cb = [alsc.cb_by_cct[ct][5:7, 7:9].mean() for ct in sorted(alsc.cb_by_cct)]
    assert np.all(np.diff(cr) > 0) and np.all(np.diff(cb) < 0)  # the white balance's R/G and B/G by CCT


@pytest.mark.parametrize("call, match", [
    (lambda: PixelAngleSpec(stack_index=0.5), "pixel.stack_index = 0.5"),
    (lambda: PixelAngleSpec(spot="airy"), "pixel.spot"),
    (lambda: PixelAngleSpec(aperture_fraction=0), "pixel.aperture_fraction"),
    (lambda: PixelAngleSpec.from_dict({"microlens": "yes"}), "pixel.microlens"),
    (lambda: microlens_acceptance(95.0, WL, PixelAngleSpec(microlens=True), pixel_pitch_um=1.55), "theta_deg"),
    (lambda: microlens_acceptance(np.nan, WL, PixelAngleSpec(microlens=True), pixel_pitch_um=1.55), "theta_deg"),
    (lambda: crosstalk_kernel(10.0, WL, -ALPHA, N_SI, ALL_ON, **SMALL), "alpha_per_um"),
    (lambda: crosstalk_kernel(10.0, WL, ALPHA, N_SI, ALL_ON, pixel_pitch_um=0, collection_depth_um=3), "pixel_pitch"),
    (lambda: apply_crosstalk(np.ones((4, 4)), np.ones((2, 2))), "kernel"),
    (lambda: effective_responsivities([[0, 3]], _responsivities(), identity_kernel((), WL.size)), "tile"),
    (lambda: ShadingSpec(grid_rows=1), "shading.grid_rows"),
    (lambda: ShadingSpec(calibration_temperatures_K=(5000, 3000)), "shading.calibration_temperatures_K"),
    (lambda: ShadingSpec(method="spline"), "shading.method"),
    (lambda: calibrate_gain_tables(np.zeros((3, 40, 40))), "flat"),
    (lambda: interpolate_tables_by_cct({}, 5000.0), "tables_by_cct"),
    (lambda: interpolate_tables_by_cct({5000.0: ShadingTables(np.ones((3, 2, 2)))}, float("nan")), "cct_K"),
])
def test_bad_values_are_one_line_errors(call, match):
    with pytest.raises(ConfigError, match=match) as e:
        call()
    assert "\n" not in str(e.value)


def test_bad_tuning_files_are_one_line_errors(tmp_path):
    cases = {"missing.json": None, "text.json": "not json", "none.json": '{"algorithms": [{"rpi.awb": {}}]}',
             "short.json": '{"rpi.alsc": {"luminance_lut": [1, 2, 3]}}'}
    for name, text in cases.items():
        p = tmp_path / name
        if text is not None:
            p.write_text(text)
        with pytest.raises(SpectracamError) as e:
            read_libcamera_alsc(p)
        assert "\n" not in str(e.value) and str(p) in str(e.value)
