"""Issue 37, item 4: the lens-shading correction in the processing chain (``processing.shading``).  Calibrated and
applied under the same light it leaves a flat field flat to 0.1 %; a mosaic's gains reach each pixel through its own
channel; the default records nothing new; bad values are one line."""
import json
import math

import numpy as np
import pytest

from spectracam.architecture.base import MosaicLayout
from spectracam.core.errors import ConfigError, SpectracamError
from spectracam.processing.color import ProcessingSpec
from spectracam.processing.shading import (calibrate_gain_tables, calibration_light, correct_shading, flat_field,
                                           residual_colour_shading, shading_gain_maps)
from spectracam.processing.calibration import light_cct_K

SHAPE = (96, 128)


def _scene(design="cfa/single", cra=20.0, pixel=None, pitch=10.0):
    from spectracam.pipeline.scene_file import parse_scene, read_toml, shipped_scene_file

    data = read_toml(shipped_scene_file("d65.toml"), "d65")
    arch, scheme = design.split("/")
    data = {**data, "optics": {"relative_illumination": "cos4", "cra_corner_deg": cra},
            "capture": {"architecture": arch, "exposure": scheme}, "sensor": {"pixel_pitch_um": pitch},
            "image": {"width": SHAPE[1], "height": SHAPE[0]}}
    if pixel:
        data["pixel"] = pixel
    return parse_scene(data, "test")


@pytest.mark.parametrize("design", ["cfa/single", "prism/optimal"])
def test_calibrated_and_applied_under_the_same_light_a_flat_field_stays_flat_to_0_1_percent(design):
    # the criterion: microlens and crosstalk off, cos⁴ to 20° at the corner, libcamera's 12 × 16 grid
    scene = _scene(design)
    cam, layout = scene.camera, scene.camera.architecture().layout
    light = calibration_light(2960.0)
    flat = flat_field(cam, scene.grid, SHAPE, light)
    assert flat.min() < 0.82 * flat.max()                                    # it was shaded: cos⁴ 20° = 0.78
    gains = shading_gain_maps(cam, scene.grid, SHAPE, ProcessingSpec(shading="single",
                                                                     shading_temperatures_K=(2960.0,)))
    corrected = correct_shading(flat.copy(), layout, gains)
    r = residual_colour_shading(corrected, layout=layout if isinstance(layout, MosaicLayout) else None)
    assert max(r["max_channel_deviation"]) < 1e-3
    assert max(r["max_colour_deviation"]) < 1e-3


def test_a_mosaic_pixel_gets_its_own_channels_gain():
    scene = _scene()
    layout = scene.camera.architecture().layout
    gains = np.stack([np.full(SHAPE, g, np.float32) for g in (2.0, 3.0, 5.0)])
    e = np.ones(SHAPE, np.float32)
    out = correct_shading(e, layout, gains)
    channel = layout.channel_index(SHAPE)
    np.testing.assert_array_equal(out, np.array([2.0, 3.0, 5.0], np.float32)[channel])
    planes = correct_shading(np.ones((3, *SHAPE)), scene.camera.with_design("prism/optimal").architecture().layout,
                             gains)
    np.testing.assert_array_equal(planes[:, 0, 0], [2.0, 3.0, 5.0])


def test_cct_tables_at_a_calibrated_temperature_are_that_temperatures_and_clamp_beyond():
    scene = _scene("prism/optimal", cra=25.0, pixel={"filter_angle": True})
    cam = scene.camera
    cct = ProcessingSpec(shading="cct")
    at_4850 = shading_gain_maps(cam, scene.grid, SHAPE, cct, 4850.0)
    single_4850 = shading_gain_maps(cam, scene.grid, SHAPE, ProcessingSpec(shading="single",
                                                                           shading_temperatures_K=(4850.0,)))
    np.testing.assert_allclose(at_4850, single_4850, rtol=1e-6)
    np.testing.assert_array_equal(shading_gain_maps(cam, scene.grid, SHAPE, cct, 9000.0),
                                  shading_gain_maps(cam, scene.grid, SHAPE, cct, 5930.0))
    # the dichroic coatings move with the angle: the tables depend on the light
    assert not np.allclose(shading_gain_maps(cam, scene.grid, SHAPE, cct, 2960.0), at_4850, rtol=1e-3)


def test_the_calibration_lights_and_their_colour_temperatures():
    assert calibration_light(2960.0).kind == "blackbody"
    d = calibration_light(6500.0)
    assert d.kind == "measured" and "daylight" in d.name
    assert light_cct_K(d) == pytest.approx(6500.0, abs=15)                   # Robertson's CCT of the D series
    assert light_cct_K(calibration_light(2960.0)) == 2960.0
    import colour

    from spectracam.scene.illuminant import IlluminantSpec
    assert light_cct_K(IlluminantSpec(kind="cie", name="D65")) == pytest.approx(6504, abs=10)  # CIE 15: 6504 K
    with pytest.raises(ConfigError):
        calibration_light(500.0)
    assert colour is not None


def test_the_default_records_nothing_new_and_bad_values_are_one_line():
    assert not any(k.startswith("shading") for k in ProcessingSpec().to_dict())
    assert ProcessingSpec(shading="cct").to_dict()["shading"] == "cct"
    for kw, field in (({"shading": "bogus"}, "processing.shading"),
                      ({"shading_temperatures_K": (5000.0, 3000.0)}, "processing.shading_temperatures_K"),
                      ({"shading_temperatures_K": (500.0,)}, "processing.shading_temperatures_K"),
                      ({"shading_grid": (1, 16)}, "processing.shading_grid"),
                      ({"shading_grid": (12.5, 16)}, "processing.shading_grid"),
                      ({"shading_method": "nosuch"}, "processing.shading_method")):
        with pytest.raises(ConfigError) as e:
            ProcessingSpec(**kw)
        assert field in str(e.value) and "\n" not in str(e.value)


def test_the_correction_without_a_reference_is_one_line():
    from spectracam.camera.capture import capture
    from spectracam.evaluation.score import camera_rates
    from spectracam.render import render

    scene = _scene()
    raw = capture(render(scene, "analytic"), scene.camera, 0, white_radiance=np.ones(len(scene.grid)) * 0.05)
    with pytest.raises(SpectracamError, match="reference"):
        camera_rates(raw, ProcessingSpec(shading="single"))


def test_simulate_with_the_correction_scores_the_corners_closer_to_the_axis(tmp_path):
    """A shaded, crosstalking 1.4 µm camera: the chart's patches lose colour to the field, the correction gives most
    of it back (the paper's camera, told the light)."""
    from spectracam.pipeline import capture as capture_api, render, score

    pixel = {"microlens": True, "optical_crosstalk": True, "electrical_crosstalk": True, "filter_angle": True,
             "microlens_shift_fraction": 1.0}
    scene = _scene("cfa/single", cra=25.0, pixel=pixel, pitch=1.4)
    cube = render(scene)
    raw = capture_api(cube, scene=scene, seed=0)
    none = score(raw, scene=scene)
    fixed = score(raw, scene=scene, processing=scene.processing.replace(shading="single"))
    lum = [p.rendered_lab[0] for p in none.patches]
    lum_fixed = [p.rendered_lab[0] for p in fixed.patches]
    assert lum_fixed[18] > lum[18] + 3                                      # the white patch, off-centre, brightened
    assert fixed.summary.delta_e_mean < none.summary.delta_e_mean
    assert json.dumps(fixed.parameters)                                    # what it recorded is JSON
    assert math.isfinite(fixed.summary.delta_e_mean)


@pytest.mark.parametrize("shape, method", [((20, 20), "cell_mean"), ((30, 30), "cell_mean"), ((16, 16), "fit"),
                                           ((30, 30), "fit")])
def test_a_mosaic_too_small_for_the_grid_is_one_line_not_nan_gains(shape, method):
    """A Bayer channel has a quarter to a half of the pixels: the 12 × 16 grid needs 48 × 64 of them."""
    from spectracam.processing.shading import ShadingSpec

    layout = _scene().camera.architecture().layout
    flat = np.random.default_rng(0).uniform(0.9, 1.1, shape)
    with pytest.raises(ConfigError) as e:
        calibrate_gain_tables(flat, ShadingSpec(method=method), layout)
    assert "processing.shading_grid" in str(e.value) and "\n" not in str(e.value)
    tables = calibrate_gain_tables(np.random.default_rng(0).uniform(0.9, 1.1, (48, 64)), ShadingSpec(method=method),
                                   layout)
    assert np.all(np.isfinite(tables.gains)) and np.all(tables.gains > 0)


def test_an_indexed_set_reaches_the_unrecorded_shading_lists():
    from spectracam.pipeline.scene_file import load_scene

    s = load_scene("d65", ["processing.shading_grid[0]=8", "processing.shading_temperatures_K[1]=5000",
                           "optics.optical_centre_mm[0]=0.5"])
    assert s.processing.shading_grid == (8, 16) and s.processing.shading_temperatures_K == (2960.0, 5000.0, 5930.0)
    assert s.camera.optics.optical_centre_mm == (0.5, 0.0)
