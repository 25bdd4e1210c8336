from pathlib import Path

import numpy as np
import pytest

from spectracam.scene.chart import ChartSpec, View, patch_coverage, patch_masks, patch_rectangles_mm
from spectracam.core.errors import ConfigError
from spectracam.scene.illuminant import IlluminantSpec, irradiance_scale, spectral_irradiance
from spectracam.pipeline.scene_file import load_scene, parse_scene
from spectracam.core.spectra import K_M_LM_PER_W, cie_1931_cmfs

SCENES = sorted(p for p in (Path(__file__).parent.parent / "scenes").glob("*.toml") if p.stem not in ("paper", "design"))  # experiment and design files


def test_shipped_scenes_cover_the_papers_illuminants():
    names = {p.stem for p in SCENES}
    assert {"blackbody_3000K", "blackbody_4000K", "blackbody_5000K", "blackbody_6000K", "blackbody_7000K",
            "d65"} <= names
    for p in SCENES:
        s = load_scene(p)
        assert len(s.grid) == 30 and s.grid.centres_nm[0] == 405 and s.grid.centres_nm[-1] == 695
        assert s.grid.edges_nm[0] == 400 and s.grid.edges_nm[-1] == 700  # the stated range, exactly


def test_scene_round_trips_through_to_dict():
    s = parse_scene({"illuminant": {"type": "cie", "name": "D65", "illuminance_lux": 1000.0}})
    again = parse_scene(s.to_dict())
    assert again.to_dict() == s.to_dict()
    assert s.illuminant.white_luminance_cd_m2 == pytest.approx(1000.0 / np.pi)


@pytest.mark.parametrize("data, field, fragment", [
    ({"colour": 1}, "colour", "unknown key"),
    ({"illuminant": {"temprature_K": 5000}}, "illuminant.temprature_K", "unknown key"),
    ({"illuminant": {"temperature_K": "hot"}}, "illuminant.temperature_K", "between 1000 and 40000"),
    ({"illuminant": {"temperature_K": 200}}, "illuminant.temperature_K", "between 1000 and 40000"),
    ({"illuminant": {"white_luminance_cd_m2": 0}}, "illuminant.white_luminance_cd_m2", "> 0"),
    ({"illuminant": {"illuminance_lux": -5}}, "illuminant.illuminance_lux", "> 0"),
    ({"illuminant": {"type": "cie", "name": "D99"}}, "illuminant.name", "CIE illuminant"),
    ({"illuminant": {"type": "laser"}}, "illuminant.type", "'blackbody', 'cie'"),
    ({"wavelengths": {"start_nm": 700, "stop_nm": 400}}, "wavelengths.stop_nm", "empty"),
    ({"wavelengths": {"centres_nm": []}}, "wavelengths.centres_nm", "non-empty"),
    ({"wavelengths": {"centres_nm": [500, 450, 600]}}, "wavelengths.centres_nm", "strictly increasing"),
    ({"wavelengths": {"start_nm": 350, "stop_nm": 700}}, "wavelengths", "CIE 1931 range"),
    ({"wavelengths": {"start_nm": 380, "stop_nm": 780}}, "wavelengths", "BabelColor Average"),
    ({"chart": {"dataset": "Pantone"}}, "chart.dataset", "'BabelColor Average'"),
    ({"chart": {"surround_reflectance": 1.5}}, "chart.surround_reflectance", "between 0 and 1"),
    ({"image": {"width": 640.5}}, "image.width", "integer"),
    ({"image": {"width": 24, "height": 18}}, "image", "too small"),
    ({"render": {"samples_per_pixel": 0}}, "render.samples_per_pixel", "integer"),
    ({"render": {"variant": "optix"}}, "render.variant", "'auto', 'llvm', 'scalar', 'cuda'"),
])
def test_bad_input_names_field_value_and_allowed(data, field, fragment):
    with pytest.raises(ConfigError) as e:
        parse_scene(data, source="s.toml")
    msg = str(e.value)
    assert msg.startswith(f"s.toml: {field} = ") and fragment in msg and "\n" not in msg


def test_ohta_dataset_allows_wider_grid():
    s = parse_scene({"chart": {"dataset": "ColorChecker N Ohta"}, "wavelengths": {"start_nm": 380, "stop_nm": 780}})
    assert len(s.grid) == 40 and s.grid.edges_nm[0] == 380 and s.grid.edges_nm[-1] == 780
    with pytest.raises(ConfigError, match="must divide the range 400–700 nm into whole bands"):
        parse_scene({"wavelengths": {"step_nm": 7}})


@pytest.mark.parametrize("spec", [IlluminantSpec("blackbody", 3000.0, None, 250.0),
                                  IlluminantSpec("cie", None, "D65", 250.0)])
def test_illuminant_level_is_white_diffuser_luminance(spec):
    wl, cmfs = cie_1931_cmfs()
    E = spectral_irradiance(spec)(wl)
    assert K_M_LM_PER_W * np.trapezoid(E / np.pi * cmfs[:, 1], wl) == pytest.approx(250.0, rel=1e-12)
    assert irradiance_scale(spec) > 0


def test_chart_layout_standard_order():
    rects = patch_rectangles_mm(ChartSpec())
    cx, cy = (rects[:, 0] + rects[:, 1]) / 2, (rects[:, 2] + rects[:, 3]) / 2
    assert cx[0] < cx[5] and cy[0] > cy[18]  # dark skin top-left, white bottom-left
    assert cx[23] == cx[5] and cy[23] == cy[18]  # black bottom-right


@pytest.mark.parametrize("size", [(640, 480), (160, 120), (301, 97)])
def test_masks_lie_inside_their_patch_with_margin(size):
    chart = ChartSpec()
    w, h = size
    masks = patch_masks(chart, w, h)
    assert masks.shape == (24, h, w)
    assert masks.sum(axis=0).max() == 1  # disjoint
    cy, cx = patch_coverage(chart, View.fit(chart, w, h))
    for p in range(24):
        assert masks[p].sum() > 0
        cover = cy[p][:, None] * cx[p][None, :]
        assert np.allclose(cover[masks[p]], 1.0, rtol=0, atol=1e-12)  # whole pixels of the patch only
        # the margin: no masked pixel is adjacent to a partially covered one
        rows, cols = np.nonzero(masks[p])
        assert np.allclose(cover[rows.min() - 1:rows.max() + 2, cols.min() - 1:cols.max() + 2], 1.0, rtol=0, atol=1e-12)


def test_coverage_sums_to_patch_area():
    chart = ChartSpec()
    view = View.fit(chart, 333, 211)
    cy, cx = patch_coverage(chart, view)
    area_px = cy.sum(axis=1) * cx.sum(axis=1) * view.pixel_mm**2
    np.testing.assert_allclose(area_px, chart.patch_size_mm**2, rtol=1e-12)
