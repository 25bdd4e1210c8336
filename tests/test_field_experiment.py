"""Issue 37, item 5: ``spectracam field`` — a flat grey and the chart across the field of a shaded lens, per design,
microlens shift and lens-shading correction."""
import json
import math
import subprocess
import sys

import numpy as np
import pytest

from spectracam.core.errors import SpectracamError
from spectracam.experiments.field.experiment import (RADIAL_BINS, plan, radial_bins, run_field,
                                                     write_field_outputs)

SETS = ("image.width=160", "image.height=120")


@pytest.fixture(scope="module")
def result():
    run = plan(quick=True, designs=("cfa/single", "prism/optimal"), shifts=(0.0, 1.0),
               corrections=("none", "single", "cct"), sets=SETS)
    return run_field(run, log=lambda *a: None, progress=False)


def _row(result, design, shift, correction):
    return next(r for r in result["rows"] if r["design"] == design and r["microlens_shift_fraction"] == shift
                and r["correction"] == correction)


def test_the_rings_cover_the_image_from_centre_to_corner():
    rings = radial_bins((120, 160))
    assert rings[60, 80] == 0 and rings[0, 0] == rings[-1, -1] == RADIAL_BINS - 1
    assert np.all(np.bincount(rings.ravel()) > 0)


def test_without_correction_the_corner_is_darker_than_cos4_and_the_shift_gives_light_back(result):
    none0, none1 = _row(result, "cfa/single", 0.0, "none"), _row(result, "cfa/single", 1.0, "none")
    # the outer ring's mean relative height is about 0.95: cos⁴ of 0.95 × 25° alone is 0.70
    assert none1["flat_luminance_ratio"][-1] < 0.75
    assert none0["flat_luminance_ratio"][-1] < 0.5 * none1["flat_luminance_ratio"][-1]  # 1.4 µm, centred lenses
    assert none0["flat_delta_e_centre"][0] == 0.0
    assert np.all(np.diff(none0["flat_luminance_ratio"]) < 0)


def test_the_correction_flattens_the_grey_and_brings_the_chart_back_to_the_axis(result):
    for design in ("cfa/single", "prism/optimal"):
        none, cct = _row(result, design, 1.0, "none"), _row(result, design, 1.0, "cct")
        assert abs(cct["flat_luminance_ratio"][-1] - 1) < 0.02
        assert cct["flat_corner_delta_e_centre"] < 0.2 * none["flat_corner_delta_e_centre"]
        assert cct["chart_outer_delta_e_axis"] < 0.5 * none["chart_outer_delta_e_axis"]


def test_a_table_from_another_light_leaves_the_prisms_coatings_shift(result):
    # calibrated at 2960 K, applied at 6504 K: the dichroic edges moved with the angle differently under each light
    single, cct = _row(result, "prism/optimal", 1.0, "single"), _row(result, "prism/optimal", 1.0, "cct")
    assert single["flat_corner_delta_ab_centre"] > 3 * cct["flat_corner_delta_ab_centre"]
    assert abs(single["flat_luminance_ratio"][-1] - 1) > 0.03


def test_outputs_are_written_and_strict_json(result, tmp_path):
    paths = write_field_outputs(tmp_path, result, "spectracam field -o x --quick")
    names = {p.name for p in paths}
    assert {"results.json", "report.md", "field.png", "field.svg", "field_maps.png", "field_maps.svg"} <= names
    data = json.loads((tmp_path / "results.json").read_text())
    assert "maps" not in data and data["command"].startswith("spectracam field")
    assert len(data["rows"]) == 2 * 1 * 2 * 3
    row = data["rows"][0]
    assert len(row["flat_delta_e_centre"]) == RADIAL_BINS and len(row["chart_delta_e_axis"]) == 24
    assert all(math.isfinite(x) for x in row["chart_delta_e_ab"])
    assert "| cfa/single | 1.4 |" in (tmp_path / "report.md").read_text()


@pytest.mark.parametrize("kwargs, match", [
    ({"corrections": ("nosuch",)}, "--correction"),
    ({"cra_deg": 0.0}, "--cra"), ({"cra_deg": float("nan")}, "--cra"),
    ({"sets": ("processing.shading='cct'",)}, "--correction"),
    ({"sets": ("pixel.microlens_shift_fraction=0.5",)}, "--shift"),
    ({"sets": ("sensor.pixel_pitch_um=2",)}, "--pitch"),
    ({"shifts": (3.0,)}, "microlens_shift_fraction"), ({"shifts": (-1.0,)}, "microlens_shift_fraction"),
    ({"pitches_um": (0.0,)}, "pixel_pitch_um"),
    ({"designs": ("cfa/optimal",)}, "design"),
    ({"sets": ("optics.relative_illumination='none'", "optics.cra_corner_deg=0")}, None),
])
def test_bad_values_are_one_line_before_any_work(kwargs, match):
    with pytest.raises(SpectracamError) as e:
        plan(quick=True, **kwargs)
    assert "\n" not in str(e.value)
    if match:
        assert match in str(e.value)


def test_the_command_runs_and_says_what_it_wrote(tmp_path):
    out = subprocess.run([sys.executable, "-m", "spectracam", "field", "-o", str(tmp_path / "f"), "--quick",
                          "--design", "fsc/optimal", "--correction", "none", "--correction", "single",
                          "--shift", "1", "--set", "image.width=96", "--set", "image.height=72"],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert "most uniform" in out.stdout + out.stderr
    data = json.loads((tmp_path / "f" / "results.json").read_text())
    assert data["parameters"]["pixel_pitches_um"] == [1.4] and len(data["rows"]) == 2
    assert "--set image.width=96" in data["command"]


def test_a_full_run_is_checked_against_the_measurements(tmp_path):
    """Without --quick the run also fits the IMX477's luminance table and a lensfun lens, and reports them."""
    from spectracam.processing.shading import find_libcamera_tuning

    run = plan(seeds=1, designs=("cfa/single",), shifts=(1.0,), corrections=("none",), pitches_um=(10.0,), sets=SETS)
    result = run_field(run, log=lambda *a: None, progress=False)
    measured = result["measured"]
    assert set(measured) >= {"imx477", "lensfun"}
    if find_libcamera_tuning("imx477") is None:
        assert measured["imx477"] is None and "imx477_not_run" in measured
    else:
        fitted = measured["imx477"]["fitted"]
        assert abs(fitted["achieved"] / fitted["measured_target"] - 1) < 0.01
    write_field_outputs(tmp_path, result, "spectracam field -o x")
    assert "Checked against real measurements" in (tmp_path / "report.md").read_text()
    assert json.loads((tmp_path / "results.json").read_text())["measured"].keys() == measured.keys()
