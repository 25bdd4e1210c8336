"""The optics and filters across the field (issue 37, items 1 and 3): relative illumination, chief-ray angle,
image circle, lensfun's vignetting, the dichroic coating's shift with angle, a tilted wheel and the CFA dye's path.
Every expected value is a closed form written here, independently of the modules."""
from __future__ import annotations

import math

import numpy as np
import pytest

from spectracam.architecture.angle import (coating_cutoff_nm, dye_path_factor, dye_transmittance,
                                           prism_incidence_deg, shift_curve, tilted_incidence_deg, wheel_filter_curve)
from spectracam.core.errors import ConfigError
from spectracam.optics.field import (LENSFUN_DIR, FieldSpec, chief_ray_angle_deg, exit_pupil_illumination,
                                     field_maps, half_diagonal_mm, image_height_mm, lensfun_vignetting,
                                     pixel_positions_mm, relative_illumination)

SHAPE, PITCH_UM = (41, 61), 10.0          # odd: the middle pixel sits on the axis


def _heights(shape=SHAPE, pitch_um=PITCH_UM):
    """Image heights written out again: pixel centres on a grid of pitch p around the middle."""
    h, w = shape
    yy, xx = np.mgrid[0:h, 0:w].astype(float)
    return np.sqrt(((xx - (w - 1) / 2) * pitch_um / 1000) ** 2 + ((yy - (h - 1) / 2) * pitch_um / 1000) ** 2)


def _corner_mm(shape=SHAPE, pitch_um=PITCH_UM):
    return pitch_um / 1000 * math.sqrt(shape[0] ** 2 + shape[1] ** 2) / 2


# ------------------------------------------------------------------ positions and the defaults
def test_pixel_positions_step_by_the_pitch_and_follow_the_optical_centre():
    x, y = pixel_positions_mm(SHAPE, PITCH_UM)
    assert x.dtype == np.float64 and x.shape == SHAPE
    assert np.allclose(np.diff(x, axis=1), 0.01) and np.allclose(np.diff(y, axis=0), 0.01)
    assert x[20, 30] == 0.0 and y[20, 30] == 0.0
    xs, ys = pixel_positions_mm(SHAPE, PITCH_UM, (0.05, -0.02))
    assert np.allclose(xs, x - 0.05) and np.allclose(ys, y + 0.02)
    assert np.allclose(image_height_mm(SHAPE, PITCH_UM), _heights())
    assert half_diagonal_mm(SHAPE, PITCH_UM) == pytest.approx(_corner_mm())


def test_defaults_are_on_axis_everywhere():
    spec = FieldSpec()
    maps = field_maps(SHAPE, PITCH_UM, spec)
    assert spec.on_axis
    assert np.array_equal(maps.illumination, np.ones(SHAPE)) and np.array_equal(maps.cra_deg, np.zeros(SHAPE))


@pytest.mark.parametrize("spec", [
    FieldSpec(relative_illumination="cos4", cra_corner_deg=30),
    FieldSpec(relative_illumination="exit_pupil", exit_pupil_mm=5.0),
    FieldSpec(relative_illumination="exit_pupil", exit_pupil_mm=5.0, exit_pupil_form="disk"),
    FieldSpec(relative_illumination="pa", pa_k=(-0.5, 0.1, -0.05)),
    FieldSpec(relative_illumination="table", illumination_height_mm=(0, 1), illumination_curve=(1, 0.5)),
    FieldSpec(chief_ray="exit_pupil", exit_pupil_mm=4.0, relative_illumination="cos4", image_circle_diameter_mm=0.5),
])
def test_a_centred_pixel_at_normal_incidence_is_exactly_one(spec):
    maps = field_maps(SHAPE, PITCH_UM, spec, f_number=2.0)
    assert maps.illumination[20, 30] == 1.0 and maps.cra_deg[20, 30] == 0.0
    assert not spec.on_axis


# ------------------------------------------------------------------ relative illumination
def test_relative_illumination_is_cos4_of_the_chief_ray_on_a_flat_field():
    spec = FieldSpec(relative_illumination="cos4", cra_corner_deg=30.0)
    flat_e = 1234.5                                  # a uniform irradiance, any unit
    shaded = flat_e * field_maps(SHAPE, PITCH_UM, spec).illumination
    theta = np.radians(30.0 * _heights() / _corner_mm())
    expected = flat_e * np.cos(theta) ** 4
    assert np.max(np.abs(shaded / expected - 1)) < 1e-3
    assert np.min(shaded) / flat_e < 0.6             # the corner (30° there) really is dark: cos⁴ 28° ≈ 0.6


def test_exit_pupil_form_is_cos4_of_the_angle_the_pupil_subtends():
    z = 4.0
    h = np.linspace(0, 6, 31)
    small = exit_pupil_illumination(h, z)
    assert np.allclose(small, np.cos(np.arctan(h / z)) ** 4, rtol=1e-12, atol=0)
    spec = FieldSpec(relative_illumination="exit_pupil", exit_pupil_mm=z)
    assert np.allclose(relative_illumination(h, spec, 1.0), small, rtol=1e-12)
    # the chief ray from the exit pupil: tan θ = h/z, and cos⁴ of it is the same curve
    spec_cra = FieldSpec(relative_illumination="cos4", chief_ray="exit_pupil", exit_pupil_mm=z)
    assert np.allclose(relative_illumination(h, spec_cra, 1.0), small, rtol=1e-12)


def _disc_irradiance(rho: float, alpha: float, n: int = 1200) -> float:
    """Irradiance on a plane at unit distance from a Lambertian disc of radius α parallel to it, at lateral
    offset ρ, by direct integration: E = ∫∫ z²/d⁴ dA (z = 1), midpoint rule in polar coordinates."""
    r = (np.arange(n) + 0.5) / n * alpha
    phi = (np.arange(2 * n) + 0.5) / (2 * n) * 2 * np.pi
    rr, pp = np.meshgrid(r, phi)
    d2 = 1.0 + (rr * np.cos(pp) - rho) ** 2 + (rr * np.sin(pp)) ** 2
    return float(np.sum(rr / d2**2) * (alpha / n) * (2 * np.pi / (2 * n)))


@pytest.mark.parametrize("f_number", [1.4, 2.8])
def test_exit_pupil_disk_form_matches_the_integrated_pupil(f_number):
    z = 10.0
    alpha = 1 / (2 * f_number)
    h = np.array([0.0, 2.0, 5.0, 9.0])
    got = exit_pupil_illumination(h, z, f_number)
    expected = np.array([_disc_irradiance(v / z, alpha) for v in h]) / _disc_irradiance(0.0, alpha)
    assert np.allclose(got, expected, rtol=1e-3)
    # a small pupil tends to cos⁴
    assert np.allclose(exit_pupil_illumination(h, z, 64.0), np.cos(np.arctan(h / z)) ** 4, rtol=1e-3)


def test_image_circle_darkens_only_outside_it():
    spec = FieldSpec(image_circle_diameter_mm=0.4)
    ri = field_maps(SHAPE, PITCH_UM, spec).illumination
    inside = _heights() <= 0.2
    assert np.all(ri[inside] == 1.0) and np.all(ri[~inside] == 0.0) and inside.sum() < ri.size


def test_measured_table_and_pa_polynomial():
    spec = FieldSpec(relative_illumination="table", illumination_height_mm=(0.0, 1.0, 2.0),
                     illumination_curve=(1.0, 0.8, 0.5))
    assert np.allclose(relative_illumination([0.5, 1.5, 3.0], spec, 2.0), [0.9, 0.65, 0.5])
    k = (-0.3, 0.1, -0.02)
    spec = FieldSpec(relative_illumination="pa", pa_k=k, pa_radius_mm=2.0)
    r = np.array([0.0, 0.5, 1.0])
    assert np.allclose(relative_illumination(2.0 * r, spec, 9.9), 1 + k[0] * r**2 + k[1] * r**4 + k[2] * r**6)


# ------------------------------------------------------------------ chief-ray angle
def test_cra_linear_reaches_the_stated_angle_at_the_corner():
    spec = FieldSpec(cra_corner_deg=25.0)
    corner = _corner_mm()
    assert np.allclose(chief_ray_angle_deg([0, corner / 2, corner], spec, corner), [0, 12.5, 25.0])
    spec = FieldSpec(cra_corner_deg=20.0, cra_corner_mm=3.0)
    assert np.allclose(chief_ray_angle_deg([1.5, 3.0], spec, corner), [10.0, 20.0])
    maps = field_maps(SHAPE, PITCH_UM, FieldSpec(cra_corner_deg=25.0))
    assert np.allclose(maps.cra_deg, 25.0 * _heights() / corner)


def test_cra_table_interpolates_and_holds_its_ends():
    spec = FieldSpec(chief_ray="table", cra_height_mm=(0.0, 1.0, 2.0), cra_table_deg=(0.0, 20.0, 30.0))
    assert np.allclose(chief_ray_angle_deg([0.5, 1.5, 5.0], spec, 2.0), [10.0, 25.0, 30.0])


# ------------------------------------------------------------------ filters across the field
def test_coating_shift_equals_its_formula():
    lam0, n_eff = np.array([500.0, 600.0]), 1.8
    for theta in (0.0, 10.0, 25.0, 40.0):
        expected = lam0 * np.sqrt(1 - np.sin(np.radians(theta)) ** 2 / n_eff**2)
        assert np.allclose(coating_cutoff_nm(lam0, theta, n_eff), expected, rtol=1e-12)
    assert np.array_equal(coating_cutoff_nm(lam0, 0.0), lam0)          # λ(0) = λ₀ exactly


def test_shift_curve_moves_an_edge_by_the_law_and_is_the_identity_at_its_design_angle():
    wl = np.arange(380.0, 781.0, 0.5)
    edge = 1 / (1 + np.exp(-(wl - 600.0) / 5.0))                       # a long-pass edge at 600 nm
    shifted = shift_curve(wl, edge, np.array([0.0, 20.0]), n_eff=1.7)
    assert shifted.shape == (2, wl.size) and np.array_equal(shifted[0], edge)
    half = np.interp(0.5, shifted[1], wl)                               # the 50 % point
    assert half == pytest.approx(600.0 * math.sqrt(1 - math.sin(math.radians(20)) ** 2 / 1.7**2), abs=0.05)
    assert np.array_equal(shift_curve(wl, edge, 15.0, design_aoi_deg=15.0), edge)


def test_prism_and_wheel_angles():
    phi = np.array([-12.0, 0.0, 7.0])
    # a splitter at normal design incidence inside glass shifts exactly as the air law says
    inside = shift_curve([400, 700], [0, 1], prism_incidence_deg(phi, 0.0, 1.52), n0=1.52)
    assert np.allclose(inside, shift_curve([400, 700], [0, 1], phi), atol=1e-12)
    # a tilted wheel: |τ + φ| in the plane of the tilt; untilted: the ray's angle to the axis
    assert np.allclose(tilted_incidence_deg(10.0, np.array([-10.0, 0.0, 5.0])), [0.0, 10.0, 15.0])
    fx, fy = 3.0, 4.0
    assert tilted_incidence_deg(0.0, fx, fy) == pytest.approx(
        math.degrees(math.atan(math.hypot(math.tan(math.radians(fx)), math.tan(math.radians(fy))))))
    wl, t = np.array([400.0, 550.0, 700.0]), np.array([0.1, 0.9, 0.2])
    assert np.array_equal(wheel_filter_curve(wl, t, 0.0, 0.0), t)


def test_dye_path_law():
    t = np.array([0.0, 0.05, 0.5, 0.9, 1.0])
    assert np.array_equal(dye_transmittance(t, 0.0), t)                 # identity at normal incidence
    assert dye_path_factor(0.0) == 1.0
    theta = 30.0
    path = 1 / math.cos(math.asin(math.sin(math.radians(theta)) / 1.55))
    assert np.allclose(dye_transmittance(t, theta), t**path, rtol=1e-12)
    both = dye_transmittance(t, np.array([[0.0, theta]]))
    assert both.shape == (1, 2, t.size) and np.all(both[0, 1] <= both[0, 0])


# ------------------------------------------------------------------ lensfun
LENS = "Canon EF 50mm f/1.8 II"   # lensfun's "Canon EF 50mm f/1.8 MkII", full-frame calibration on a Canon 5D


@pytest.mark.skipif(not LENSFUN_DIR.is_dir(), reason=f"no lensfun database at {LENSFUN_DIR} "
                                                     "(Debian package liblensfun-data-v1)")
def test_lensfun_returns_the_published_coefficients():
    v = lensfun_vignetting(LENS, 50, 2.8)           # slr-canon.xml: k1 = -0.1193, k2 = -0.4620, k3 = 0.0523
    assert v.k == (-0.1193, -0.4620, 0.0523) and v.how == "exact" and v.crop_factor == 1.0
    wide = lensfun_vignetting(LENS, 50, 1.8, distance_m=10)  # k1 = -1.4745, k2 = 1.1285, k3 = -0.4284
    assert wide.k == (-1.4745, 1.1285, -0.4284)
    assert v.radius_mm == pytest.approx(math.hypot(36, 24) / 2)
    # the corner of the calibrated frame: V(1) = 1 + k1 + k2 + k3
    spec = wide.field()
    assert relative_illumination(wide.radius_mm, spec, 1.0) == pytest.approx(1 - 1.4745 + 1.1285 - 0.4284)
    # between f/2 and f/2.8 the coefficients lie between the two stored ones
    mid = lensfun_vignetting(LENS, 50, 2.4)
    assert mid.how == "interpolated" and -0.6486 < mid.k[0] < -0.1193
    aps_c = lensfun_vignetting(LENS, 50, 2.0, crop_factor=1.6)
    assert aps_c.crop_factor == 1.622 and aps_c.k == (-0.1158, -0.4426, 0.2807)


@pytest.mark.skipif(not LENSFUN_DIR.is_dir(), reason=f"no lensfun database at {LENSFUN_DIR}")
def test_lensfun_unknown_lens_is_one_line():
    with pytest.raises(ConfigError) as e:
        lensfun_vignetting("No Such Lens 1mm f/0.1", 1, 1)
    assert "lensfun.lens" in str(e.value) and "\n" not in str(e.value)


# ------------------------------------------------------------------ bad values
@pytest.mark.parametrize("kwargs, field", [
    ({"relative_illumination": "cos5"}, "optics.relative_illumination"),
    ({"cra_corner_deg": -1.0}, "optics.cra_corner_deg"),
    ({"cra_corner_deg": 95.0}, "optics.cra_corner_deg"),
    ({"relative_illumination": "exit_pupil"}, "optics.exit_pupil_mm"),
    ({"exit_pupil_mm": 0.0}, "optics.exit_pupil_mm"),
    ({"exit_pupil_form": "huge"}, "optics.exit_pupil_form"),
    ({"chief_ray": "table"}, "optics.cra_height_mm"),
    ({"chief_ray": "table", "cra_height_mm": (0, 1), "cra_table_deg": (0, 1, 2)}, "optics.cra_table_deg"),
    ({"chief_ray": "table", "cra_height_mm": (1, 0), "cra_table_deg": (0, 1)}, "optics.cra_height_mm"),
    ({"relative_illumination": "table", "illumination_height_mm": (0, 1), "illumination_curve": (1, 3)},
     "optics.illumination_curve"),
    ({"relative_illumination": "pa", "pa_k": (0.1, 0.2)}, "optics.pa_k"),
    ({"image_circle_diameter_mm": -2.0}, "optics.image_circle_diameter_mm"),
    ({"optical_centre_mm": (0.0,)}, "optics.optical_centre_mm"),
])
def test_bad_field_values_are_one_line_config_errors(kwargs, field):
    with pytest.raises(ConfigError) as e:
        FieldSpec(**kwargs)
    msg = str(e.value)
    assert msg.startswith(field + " = ") and "\n" not in msg


def test_bad_filter_values_are_one_line_config_errors():
    cases = [(lambda: coating_cutoff_nm(600, 30, n_eff=0.4), "coating.n_eff"),
             (lambda: coating_cutoff_nm(600, 95), "coating.aoi_deg"),
             (lambda: dye_transmittance([0.5, 1.2], 10), "dye.transmittance"),
             (lambda: shift_curve([500, 400], [0, 1], 10), "coating.wavelengths_nm"),
             (lambda: FieldSpec.from_dict({"cra_corner": 3}), "optics.cra_corner")]
    for call, field in cases:
        with pytest.raises(ConfigError) as e:
            call()
        assert str(e.value).startswith(field) and "\n" not in str(e.value)
