"""Checked against real measurements (issue 37, item 6): the Raspberry Pi HQ camera's lens-shading tables and a
lensfun lens's vignetting (spectracam/experiments/field/measured.py)."""
from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

from spectracam.experiments.field.measured import (CALIBRATION_TEMPERATURES_K, LENSFUN_LENS, fit_cos4_corner,
                                                   fit_exit_pupil, imx477_reproduction, lensfun_reproduction,
                                                   measured_markdown)
from spectracam.optics.field import LENSFUN_DIR, cos4_illumination, exit_pupil_illumination
from spectracam.processing.shading import find_libcamera_tuning, read_libcamera_alsc, table_figures

#: The exit-pupil fit's rms residual to the Canon EF 50mm f/1.8 II's lensfun curve at f/8, as measured: 0.0018
#: (max 0.0078) over r = 0 … 1; cos⁴ of a fitted linear chief-ray angle: 0.0036; cos⁴ of the field angle, nothing
#: fitted: 0.018.  A fit stuck at a bound or on the wrong curve misses by ≥ 0.02.
EXIT_PUPIL_RMS_BOUND = 0.0025
COS4_RMS_BOUND = 0.005


def _tuning():
    path = find_libcamera_tuning("imx477")
    if path is None:
        pytest.skip("the Raspberry Pi HQ camera's tuning file imx477.json (Debian package libcamera-ipa) is not "
                    "installed: apt-get install libcamera-ipa")
    return path


def _lensfun():
    if not LENSFUN_DIR.is_dir():
        pytest.skip(f"lensfun's database is not installed at {LENSFUN_DIR} (Debian: apt-get install "
                    "liblensfun-data-v1)")


@pytest.fixture(scope="module")
def imx():
    path = _tuning()
    result = imx477_reproduction(path)
    f = result["fitted"]
    print(f"\nIMX477 fit: exit pupil {f['value']:.3f} mm (corner CRA {f['corner_cra_deg']:.2f}°), corner/centre "
          f"{f['achieved']:.4f} vs {f['measured_target']:.4f}, {f['evaluations']} evaluations, "
          f"{result['seconds']:.1f} s")
    for key, row in result["predicted"].items():
        print(f"  {key} K: Cr model {row['model_cr']:.4f} measured {row['measured_cr']:.4f}; "
              f"Cb model {row['model_cb']:.4f} measured {row['measured_cb']:.4f}")
    print(f"  agreement {result['agreement']}")
    return path, result


def test_imx477_fit_hits_the_tuning_files_luminance_gain(imx):
    path, result = imx
    f = result["fitted"]
    target = table_figures(read_libcamera_alsc(path).luminance_lut)["corner_over_centre"]
    assert f["measured_target"] == target and 1.5 < target < 1.65      # the file's own figure, as read
    assert abs(f["achieved"] / target - 1) < 0.01 and result["agreement"]["luminance_fit_within_1pct"]
    assert f["parameter"] == "optics.exit_pupil_mm" and 1.0 < f["value"] < 1000.0
    assert math.isclose(math.tan(math.radians(f["corner_cra_deg"])) * f["value"],
                        1.55e-3 * math.hypot(4056, 3040) / 2, rel_tol=1e-9)   # CRA = atan(h_corner / z)
    assert 0 < f["lens_corner_cell_illumination"] < 1


def test_imx477_predictions_are_finite_and_measured_numbers_are_the_files(imx):
    path, result = imx
    alsc = read_libcamera_alsc(path)
    assert sorted(float(k) for k in result["predicted"]) == list(CALIBRATION_TEMPERATURES_K)
    for key, row in result["predicted"].items():
        t = float(key)
        assert math.isfinite(row["model_cr"]) and math.isfinite(row["model_cb"])
        assert 0.8 < row["model_cr"] < 1.25 and 0.8 < row["model_cb"] < 1.25
        assert row["measured_cr"] == table_figures(alsc.cr_by_cct[t])["corner_over_centre"]
        assert row["measured_cb"] == table_figures(alsc.cb_by_cct[t])["corner_over_centre"]
    assert result["predicted"]["2960"]["measured_cr"] == pytest.approx(1.0205, abs=5e-4)
    assert result["predicted"]["5930"]["measured_cb"] == pytest.approx(0.9855, abs=5e-4)
    shape = result["luminance_shape"]
    assert np.shape(shape["model_table"]) == (12, 16) and math.isfinite(shape["rms_ratio_minus_1"])
    assert all(isinstance(v, bool) for v in result["agreement"].values())
    assert "optics.exit_pupil_mm" in result["parameters"] and "pixel" in result["parameters"]
    assert json.loads(json.dumps(result))["fitted"]["value"] == result["fitted"]["value"]   # plain numbers


def test_lensfun_fits_and_prediction():
    _lensfun()
    result = lensfun_reproduction(LENSFUN_LENS, 50.0, 8.0, 1.8)
    c, ep, c4 = result["calibration"], result["fitted"]["exit_pupil"], result["fitted"]["cos4"]
    print(f"\n{LENSFUN_LENS} f/{c['fit_aperture']:g}: exit pupil {ep['value']:.2f} mm rms {ep['rms']:.5f} max "
          f"{ep['max_abs']:.5f}; cos4 {c4['value']:.2f}° rms {c4['rms']:.5f}; baseline rms "
          f"{result['baseline']['cos4_field_angle']['rms']:.5f}; predicted f/1.8 corner "
          f"{result['predicted']['model_corner']:.3f} vs {result['predicted']['measured_corner']:.3f}")
    assert c["fit_how"] == c["predict_how"] == "exact" and c["crop_factor"] == 1.0
    assert ep["rms"] < EXIT_PUPIL_RMS_BOUND and not ep["at_bound"] and 30.0 < ep["value"] < 100.0
    assert c4["rms"] < COS4_RMS_BOUND and 10.0 < c4["value"] < 40.0
    assert result["baseline"]["cos4_field_angle"]["rms"] > ep["rms"]    # the fitted pupil beats a pupil at f
    p = result["predicted"]
    assert p["aperture"] == 1.8 and all(math.isfinite(p[k]) for k in ("model_corner", "measured_corner", "rms"))
    assert len(result["curves"]["r"]) == len(result["curves"]["exit_pupil_predicted"]) == 101
    json.dumps(result)


def test_exit_pupil_closed_forms():
    h = np.linspace(0.0, 20.0, 41)
    for f_number in (None, 1.4, 8.0):                    # a pupil at infinity: no fall-off
        np.testing.assert_allclose(exit_pupil_illumination(h, 1e9, f_number), 1.0, atol=1e-9)
    # the fit finds the distance that made a curve, and cos⁴'s angle likewise
    curve = exit_pupil_illumination(h, 37.0, 4.0)
    fit = fit_exit_pupil(h, curve, 4.0)
    assert fit["exit_pupil_mm"] == pytest.approx(37.0, rel=1e-5) and fit["rms"] < 1e-7 and not fit["at_bound"]
    assert fit_exit_pupil(h, np.ones_like(h), 4.0)["at_bound"]       # no fall-off: the pupil at the far bound
    r = np.linspace(0.0, 1.0, 51)
    c4 = fit_cos4_corner(r, cos4_illumination(20.0 * r))
    assert c4["cra_corner_deg"] == pytest.approx(20.0, abs=1e-5) and c4["rms"] < 1e-8


def test_markdown_without_data():
    text = measured_markdown(None, None)
    assert text.startswith("## Checked against real measurements") and "libcamera-ipa" in text
    assert "liblensfun-data-v1" in text


def test_markdown_with_both(imx):
    _lensfun()
    text = measured_markdown(imx[1], lensfun_reproduction())
    assert "| 2960 K |" in text and "exit pupil, predicted" in text and not re.search(r"\bnan\b", text)
