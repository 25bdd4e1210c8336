"""Issue 37, items 2 and 3 in the capture: the pixel's response to the chief ray's angle (microlens, crosstalk) and the
filters' angle shifts, tabulated per tile site and chief-ray angle (spectracam.camera.field) and used per pixel."""
import math
import subprocess
import sys

import numpy as np
import pytest

from spectracam.architecture.filters import FilterSpec
from spectracam.camera import CameraSpec, band_weights
from spectracam.camera.capture import capture
from spectracam.camera.field import _angle_kernels, field_band_weights, field_rates
from spectracam.core.errors import SpectracamError
from spectracam.core.spectra import WavelengthGrid
from spectracam.optics import OpticsSpec
from spectracam.optics.field import field_maps
from spectracam.render.cube import RadianceCube
from spectracam.sensor import SensorSpec
from spectracam.sensor.angle import PixelAngleSpec, effective_responsivities

GRID = WavelengthGrid(np.arange(405.0, 700.0, 10.0))
WL = np.asarray(GRID.centres_nm)
#: A small pixel, where crosstalk matters.
SMALL = SensorSpec(pixel_pitch_um=1.55)
CROSSTALK = PixelAngleSpec(optical_crosstalk=True, electrical_crosstalk=True, aperture_fraction=0.8)
BOX = (slice(10, 20), slice(14, 26))


def _cube(h=31, w=41, seed=1):
    rng = np.random.default_rng(seed)
    return RadianceCube(rng.uniform(0.002, 0.02, (h, w, WL.size)).astype(np.float32),
                        WL, {"renderer": "test"})


@pytest.mark.parametrize("design", ["cfa/single", "prism/optimal", "fsc/optimal"])
def test_the_default_camera_captures_bit_identically_to_band_weights_alone(design):
    from spectracam.camera.capture import capture_time_s
    from spectracam.sensor.exposure import exposure_times_s
    from spectracam.sensor.kernels import SpectralRates

    cam = CameraSpec().with_design(design)
    cube = _cube()
    raw = capture(cube, cam, seed=7, metering_box=BOX)
    arch = cam.architecture()
    rates = SpectralRates(cube.radiance, band_weights(cam, cube.grid))
    times = exposure_times_s(cam.capture.exposure, rates.mean(*BOX), cam.sensor, arch, cam.capture.white_fill,
                             cam.capture.exposure_split)
    digital, expected = arch.record(rates, times, cam.sensor, 7)
    np.testing.assert_array_equal(raw.exposure_times_s, times)
    np.testing.assert_array_equal(raw.digital, digital)
    np.testing.assert_array_equal(raw.expected_e, expected)
    assert raw.capture_time_s == capture_time_s(arch, times, cam.sensor)
    assert "pixel" not in cam.to_dict()


@pytest.mark.parametrize("electrical", [False, True])
def test_a_centred_pixel_at_normal_incidence_is_todays_response(electrical):
    # electrical crosstalk mixes charge at every angle: the measured responsivities already hold its normal-incidence
    # share, so only its change with the angle is added (camera.field._compute_weights)
    pixel = PixelAngleSpec(microlens=True, optical_crosstalk=True, microlens_shift_fraction=0.5,
                           electrical_crosstalk=electrical)
    for design in ("cfa/single", "prism/optimal"):
        cam = CameraSpec(optics=OpticsSpec(cra_corner_deg=25.0), sensor=SMALL, pixel=pixel).with_design(design)
        table = field_band_weights(cam, GRID, [0.0, 12.0, 25.0], [-180.0, -90.0, 0.0, 45.0])
        bw = band_weights(cam, GRID)
        columns = [0, 1, 1, 2] if design.startswith("cfa") else [0, 1, 2]  # RGGB sites / R, G, B planes
        for a in range(4):
            np.testing.assert_array_equal(table[0, a], bw[:, columns])      # exactly today's weights
        assert not np.allclose(table[-1, 0], bw[:, columns])               # and not at the corner
        cube = _cube()
        maps = field_maps(cube.radiance.shape[:2], cam.sensor.pixel_pitch_um, cam.optics, cam.optics.f_number)
        assert maps.cra_deg[15, 20] == 0.0
        rates = field_rates(cube.radiance, GRID, cam, maps)
        today = cube.radiance[15, 20].astype(np.float64) @ bw.astype(np.float64)
        k = cam.architecture().layout.channel_index((31, 41))[15, 20] if design.startswith("cfa") else slice(None)
        np.testing.assert_allclose(rates[15, 20, k], today[k], rtol=1e-6)


def test_crosstalk_conserves_charge_on_a_uniform_field():
    cam = CameraSpec(sensor=SMALL, pixel=CROSSTALK.replace(electrical_crosstalk=False))
    cra, az = np.array([0.0, 10.0, 20.0, 30.0]), np.array([0.0, 30.0, 135.0])
    kernel = _angle_kernels(cam, GRID, cra, az)                             # (4, 3, B, 3, 3)
    R = cam.architecture().responsivities(cam.filters, GRID)
    tile = [[0, 1], [1, 2]]
    for i in range(cra.size):
        eff = effective_responsivities(tile, R, kernel[i])                  # (3, 2, 2, B)
        total = eff.sum((-3, -2))                                           # all four sites, per band
        kept = R[np.array(tile)].sum((0, 1))[None, :] * kernel[i].sum((-2, -1))
        np.testing.assert_allclose(total, kept, rtol=1e-9)                  # moved between sites, never lost
    table = field_band_weights(cam, GRID, cra, az).astype(np.float64)
    factor = band_weights(cam.replace(pixel=PixelAngleSpec()), GRID).astype(np.float64).sum(1) / R.sum(0)
    np.testing.assert_allclose(table.sum(-1), (R[np.array(tile)].sum((0, 1)) * kernel.sum((-2, -1))) * factor,
                               rtol=1e-6)                                  # the float32 table keeps it too


def _leak(cam, band_mask, own_site, cra):
    table = field_band_weights(cam, GRID, cra, [0.0, 45.0])
    light = table[:, :, band_mask, :].sum(2)                                # (n_cra, n_az, 4 sites)
    others = light.sum(-1) - light[..., own_site]
    return others / light[..., own_site]


def test_red_light_leaks_into_green_and_blue_sites_with_the_angle_and_more_than_blue():
    cam = CameraSpec(sensor=SMALL, pixel=CROSSTALK)
    cra = [0.0, 10.0, 20.0, 30.0]
    red, blue = WL >= 620, WL <= 480
    red_leak, blue_leak = _leak(cam, red, 0, cra), _leak(cam, blue, 3, cra)
    assert np.all(np.diff(red_leak, axis=0) > 0)                           # rising with the CRA
    assert np.all(red_leak[1:] > blue_leak[1:])                            # long wavelengths leak more
    optical = cam.replace(pixel=CROSSTALK.replace(electrical_crosstalk=False))
    assert np.all(field_band_weights(optical, GRID, cra, [0.0])[0, 0][red][:, [1, 2, 3]] == 0)  # none at 0°
    table = field_band_weights(cam, GRID, cra, [0.0])
    assert table[-1, 0][red][:, 3].sum() > table[1, 0][red][:, 3].sum() > 0  # the B site's red charge


def test_a_microlens_shift_for_the_stated_cra_keeps_the_corner_acceptance():
    corner = 25.0
    pixel = PixelAngleSpec(microlens=True, microlens_shift_fraction=1.0)
    cam = CameraSpec(sensor=SMALL, pixel=pixel)
    table = field_band_weights(cam, GRID, [0.0, corner], [0.0, 37.0])
    np.testing.assert_allclose(table[1], table[0], rtol=1e-6)
    unshifted = field_band_weights(cam.replace(pixel=pixel.replace(microlens_shift_fraction=0.0)), GRID,
                                   [0.0, corner], [0.0])
    assert np.all(unshifted[1] < 0.99 * unshifted[0] + 1e-30)              # centred microlenses lose light


def test_the_prism_coating_moves_a_plane_to_shorter_wavelengths_at_the_corner():
    grid = WavelengthGrid(np.arange(400.0, 701.0, 1.0))
    cam = CameraSpec(filters=FilterSpec(edge_width_nm=20.0), pixel=PixelAngleSpec(filter_angle=True),
                     optics=OpticsSpec(cra_corner_deg=25.0)).with_design("prism/optimal")
    theta = 25.0
    table = field_band_weights(cam, grid, [0.0, theta], [0.0])[:, 0, :, 1].astype(np.float64)  # the G plane
    lam = np.asarray(grid.centres_nm)

    def falling_edge(w):
        t = w / w.max()
        i = np.nonzero((t[:-1] >= 0.5) & (t[1:] < 0.5))[0][-1]
        return lam[i] + (t[i] - 0.5) / (t[i] - t[i + 1]) * (lam[i + 1] - lam[i])

    l0, lc = falling_edge(table[0]), falling_edge(table[1])
    expected = l0 * math.sqrt(1 - math.sin(math.radians(theta)) ** 2 / 1.7**2)
    assert abs(l0 - 610.0) < 0.5 and lc < l0 - 10
    assert lc == pytest.approx(expected, abs=0.1)


@pytest.mark.parametrize("table, match", [
    ({"microlens": "yes"}, "pixel.microlens"),
    ({"stack_height_um": -1.0}, "pixel.stack_height_um"),
    ({"spot": "round"}, "pixel.spot"),
    ({"filter_angle": 1}, "pixel.filter_angle"),
    ({"lens": 1}, "pixel.lens"),
])
def test_bad_pixel_values_are_one_line_errors(table, match):
    with pytest.raises(SpectracamError, match=match) as e:
        CameraSpec.from_dict({"pixel": table})
    assert "\n" not in str(e.value)


def test_simulate_with_the_microlens_on_runs(tmp_path):
    out = subprocess.run([sys.executable, "-m", "spectracam", "simulate", "d65", "-o", str(tmp_path / "run"),
                          "--renderer", "analytic", "--set", "image.width=64", "--set", "image.height=48",
                          "--set", "optics.cra_corner_deg=25", "--set", "pixel.microlens=true"],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
