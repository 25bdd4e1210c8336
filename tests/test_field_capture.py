"""Issue 37, first part: the lens's relative illumination reaches the capture.  On a flat field with the microlens and
crosstalk off, a capture's noise-free charge across the image is cos⁴ of the chief ray's angle (and the exit-pupil
form), to 0.1 %; a camera on the axis records exactly what it did before."""
import math

import numpy as np
import pytest

from spectracam.camera import CameraSpec
from spectracam.camera.capture import capture, field_radiance
from spectracam.optics import OpticsSpec
from spectracam.render.cube import RadianceCube
from spectracam.sensor import SensorSpec

H, W, PITCH_UM = 61, 81, 10.0


def _flat_capture(optics, design="prism/optimal"):
    grid = np.arange(405.0, 700.0, 10.0)
    cube = RadianceCube(np.full((H, W, grid.size), 0.01, np.float32), grid, {"renderer": "test"})
    sensor = SensorSpec(pixel_pitch_um=PITCH_UM, adc_bits=12).off("shot_noise", "read_noise", "fpn", "dark_current",
                                                                  "quantization", "clipping")
    cam = CameraSpec(optics=optics, sensor=sensor).with_design(design)
    return capture(cube, cam, seed=0, metering_box=(slice(H // 2 - 2, H // 2 + 3), slice(W // 2 - 2, W // 2 + 3)))


def _height_mm():
    y, x = np.mgrid[0:H, 0:W].astype(float)
    return np.hypot((x - (W - 1) / 2) * PITCH_UM / 1000, (y - (H - 1) / 2) * PITCH_UM / 1000)


def test_a_flat_field_falls_off_as_cos4_of_the_chief_ray_angle():
    raw = _flat_capture(OpticsSpec(relative_illumination="cos4", cra_corner_deg=30.0))
    e = raw.expected_e[1]                               # the green sensor of the prism, noise-free
    h = _height_mm()
    corner_mm = math.hypot(W, H) * PITCH_UM / 1000 / 2  # the sensor's corner: half its diagonal
    theta = np.radians(30.0 * h / corner_mm)            # linear chief-ray angle, 30° at the corner
    np.testing.assert_allclose(e / e[H // 2, W // 2], np.cos(theta) ** 4, rtol=1e-3)
    assert e[0, 0] / e[H // 2, W // 2] < math.cos(math.radians(30)) ** 4 * 1.03   # the corner pixel's centre: ~29.6°


def test_the_exit_pupil_form_is_cos4_of_the_angle_from_the_exit_pupil():
    z = 20.0
    raw = _flat_capture(OpticsSpec(relative_illumination="exit_pupil", exit_pupil_mm=z))
    e = raw.expected_e[0]
    np.testing.assert_allclose(e / e[H // 2, W // 2], np.cos(np.arctan(_height_mm() / z)) ** 4, rtol=1e-3)


def test_on_the_axis_the_capture_is_todays_and_the_record_unchanged():
    on_axis = OpticsSpec()
    assert on_axis.on_axis and on_axis.to_dict() == {"f_number": 1.4, "transmittance": 1.0,
                                                     "irradiance_form": "paraxial", "transmittance_curve_nm": [],
                                                     "transmittance_curve": []}
    cube = np.ones((4, 5, 3), np.float32)
    assert field_radiance(cube, CameraSpec()) is cube   # not even a copy
    a = _flat_capture(on_axis, "cfa/single")
    for dy in (0, 1):                                   # every site of the Bayer tile the same across the image
        for dx in (0, 1):
            site = a.expected_e[dy::2, dx::2]
            assert np.all(site == site[0, 0])


def test_outside_the_image_circle_there_is_no_light():
    raw = _flat_capture(OpticsSpec(relative_illumination="cos4", cra_corner_deg=20.0,
                                   image_circle_diameter_mm=0.6))
    e = raw.expected_e[1]
    outside = _height_mm() > 0.3 + 1e-9
    assert outside.any() and np.all(e[outside] == 0.0) and np.all(e[~outside] > 0.0)


def test_a_shaded_camera_simulates_and_its_raw_file_scores(tmp_path):
    """The white patch is metered where it lies in the field, not at the chart reference's centre: the capture's
    exposure is not refused as another scene's, through simulate and again from the written raw.exr."""
    from click.testing import CliRunner

    from spectracam.cli import main

    sets = ["image.width=160", "image.height=120", "optics.cra_corner_deg=30", "optics.relative_illumination=cos4",
            "pixel.microlens=true", "pixel.optical_crosstalk=true"]
    r = CliRunner().invoke(main, ["simulate", "d65", "-o", str(tmp_path / "s"), "--renderer", "analytic", "--quiet",
                                  *[x for s in sets for x in ("--set", s)]])
    assert r.exit_code == 0, r.output
    r = CliRunner().invoke(main, ["score", str(tmp_path / "s" / "raw.exr"), "-o", str(tmp_path / "t"), "--quiet"])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "t" / "report.json").stat().st_size > 0


def test_the_field_adds_no_slow_import_to_the_camera_stage():
    """The pixel's angle response needs SciPy's erf only when it is on: importing the camera stage (every command's
    start-up does) must not import SciPy, whose import costs as much as the rest of the start-up."""
    import subprocess
    import sys

    code = "import sys, spectracam.camera, spectracam.camera.capture; print('scipy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"
