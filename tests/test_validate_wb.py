"""Real cameras' own measurements from Debian packages (issue 33 item 5): darktable's white-balance presets and
RawTherapee's DCP profiles against the shipped cameras, in ``spectracam validate``."""
import json
import struct

import numpy as np
import pytest

from spectracam.experiments.validate import white_balance as vw
from spectracam.experiments.validate.white_balance import (DataFileError, DcpProfile, PresetLight, effective_cct, light_spec,
                                                load_wb_presets, preset_neutral, presets_at_zero_tuning, read_dcp,
                                                simulated_neutral)
from spectracam.scene.illuminant import IlluminantSpec

SHIPPED = ["Nikon 5100 (NPL)", "Sigma SDMerill (NPL)", "Canon EOS 5D Mark II (rawtoaces)"]


# ---------------------------------------------------------------- a DCP written here, read back
def tiff(entries, bo="<", magic=0x4352, sort=True):
    """A one-IFD TIFF-structured file: ``entries`` = [(tag, type, values)] (type 2 ASCII str, 3 SHORT, 4 LONG,
    10 SRATIONAL as (num, den) pairs flattened, 11 FLOAT)."""
    fmt = {3: "H", 4: "I", 10: "i", 11: "f"}
    entries = sorted(entries) if sort else entries
    ifd_at = 8
    data_at = ifd_at + 2 + 12 * len(entries) + 4
    ifd, extra = struct.pack(bo + "H", len(entries)), b""
    for tag, typ, values in entries:
        if typ == 2:
            payload, count = values.encode() + b"\0", len(values) + 1
        else:
            payload = struct.pack(bo + fmt[typ] * len(values), *values)
            count = len(values) // (2 if typ == 10 else 1)
        if len(payload) <= 4:
            field = payload.ljust(4, b"\0")
        else:
            field = struct.pack(bo + "I", data_at + len(extra))
            extra += payload + (b"\0" if len(payload) % 2 else b"")
        ifd += struct.pack(bo + "HHI", tag, typ, count) + field
    head = (b"II" if bo == "<" else b"MM") + struct.pack(bo + "HI", magic, ifd_at)
    return head + ifd + struct.pack(bo + "I", 0) + extra


def srational(m, den=10000):
    return [v for x in np.ravel(m) for v in (int(round(x * den)), den)]


CM1 = np.array([[1.047, -0.2851, -0.0502], [-0.4637, 1.4663, 0.377], [-0.024, 0.1001, 0.7514]])
CM2 = np.array([[0.5957, -0.0667, -0.0863], [-0.5129, 1.3024, 0.2313], [-0.0577, 0.12, 0.6706]])
FM1 = np.array([[0.5902, 0.1415, 0.2327], [0.2694, 0.6575, 0.0731], [0.0002, 0.0288, 0.7961]])
HSM = [0.5, 1.25, 1.0] * 6  # 3 hue × 2 sat × 1 val divisions


def dcp_entries():
    return [(50708, 2, "Test Cam"), (50721, 10, srational(CM1)), (50722, 10, srational(CM2)), (50778, 3, [17]),
            (50779, 3, [21]), (50936, 2, "Test profile"), (50964, 10, srational(FM1)), (50937, 4, [3, 2, 1]),
            (50938, 11, HSM), (50939, 11, HSM)]


@pytest.mark.parametrize("bo", ["<", ">"])
def test_dcp_reader_reads_a_hand_built_profile_in_both_byte_orders(tmp_path, bo):
    f = tmp_path / "t.dcp"
    f.write_bytes(tiff(dcp_entries(), bo))
    p = read_dcp(f)
    assert p.unique_camera_model == "Test Cam" and p.profile_name == "Test profile"
    (c1, m1, f1), (c2, m2, f2) = p.calibrations
    assert (c1, c2) == (17, 21)
    np.testing.assert_allclose(m1, CM1, atol=1e-12)
    np.testing.assert_allclose(m2, CM2, atol=1e-12)
    np.testing.assert_allclose(f1, FM1, atol=1e-12)
    assert f2 is None
    assert p.hue_sat_map[0] == (3, 2, 1) and p.hue_sat_map[1][1][:, 1] == pytest.approx([1.25] * 6)


def test_dcp_neutral_interpolates_the_color_matrices_in_inverse_cct():
    p = DcpProfile("x", "X", None, None, [(17, CM1, None), (21, CM2, None)])
    w = np.array([0.95, 1.0, 1.09])
    for T, M in ((2856.0, CM1), (2000.0, CM1), (6504.0, CM2), (9000.0, CM2)):  # clamped outside
        n = M @ w
        np.testing.assert_allclose(p.neutral(w, T), n / n[1], rtol=1e-12)
    n = 0.5 * (CM1 + CM2) @ w  # halfway in mired
    np.testing.assert_allclose(p.neutral(w, 2 / (1 / 2856 + 1 / 6504)), n / n[1], rtol=1e-12)


@pytest.mark.parametrize("case, match", [
    ("magic42", "magic number"), ("truncated", "run past the end|does not fit"), ("unsorted", "ascending order"),
    ("no_ci2", "ColorMatrix2 without CalibrationIlluminant2"), ("zero_den", "denominator 0"),
    ("cm_8", "must be 9"), ("no_cm1", "no ColorMatrix1"), ("hsm_count", "ProfileHueSatMapData1 must be 18")])
def test_dcp_reader_is_strict(tmp_path, case, match):
    e = dcp_entries()
    kw = {}
    if case == "magic42":
        kw["magic"] = 42
    elif case == "unsorted":
        kw["sort"] = False
        e = e[::-1]
    elif case == "no_ci2":
        e = [x for x in e if x[0] != 50779]
    elif case == "zero_den":
        e = [(t, ty, v if t != 50721 else v[:-1] + [0]) for t, ty, v in e]
    elif case == "cm_8":
        e = [(t, ty, v if t != 50721 else v[:-2]) for t, ty, v in e]
    elif case == "no_cm1":
        e = [x for x in e if x[0] not in (50721, 50778)]
    elif case == "hsm_count":
        e = [(t, ty, v if t != 50938 else v[:-3]) for t, ty, v in e]
    data = tiff(e, **kw)
    if case == "truncated":
        data = data[:-40]
    f = tmp_path / "bad.dcp"
    f.write_bytes(data)
    with pytest.raises(DataFileError, match=match):
        read_dcp(f)


# ---------------------------------------------------------------- darktable's presets
def write_presets(path, presets, version=1):
    path.write_text(json.dumps({"version": version, "wb_presets": [
        {"maker": "Canon", "models": [{"model": "EOS Test", "presets": presets}]}]}))
    return path


def test_presets_at_tuning_zero_and_their_neutral(tmp_path):
    f = write_presets(tmp_path / "wb.json", [
        {"name": "Daylight", "tuning": -1, "channels": [2.5, 1, 1.5, 0]},
        {"name": "Daylight", "channels": [2.0, 1, 1.6, 0]},  # no tuning: 0
        {"name": "Daylight", "tuning": 1, "channels": [1.5, 1, 1.7, 0]},
        {"name": "Shade", "tuning": 0, "channels": [2.4, 1.2, 1.2, 0]}])
    p = presets_at_zero_tuning(load_wb_presets(f), "Canon", "EOS Test")
    assert p == {"Daylight": (2.0, 1.0, 1.6), "Shade": (2.4, 1.2, 1.2)}
    np.testing.assert_allclose(preset_neutral(p["Daylight"]), [0.5, 1.0, 1 / 1.6])
    np.testing.assert_allclose(preset_neutral(p["Shade"]), [0.5, 1.0, 1.0])  # G ≠ 1 normalised
    assert presets_at_zero_tuning(load_wb_presets(f), "Canon", "EOS Other") == {}


@pytest.mark.parametrize("presets, version, match", [
    ([{"name": "Daylight", "channels": [2.0, 1, 1.6]}], 1, "channels must be 4 numbers"),
    ([{"name": "Daylight", "channels": [2.0, 0, 1.6, 0]}], 1, "finite and > 0"),
    ([{"name": "Daylight", "tuning": "0", "channels": [2.0, 1, 1.6, 0]}], 1, "tuning must be an integer"),
    ([{"channels": [2.0, 1, 1.6, 0]}], 1, "\"name\""),
    ([], 2, "version"),
])
def test_preset_parsing_is_strict(tmp_path, presets, version, match):
    with pytest.raises(DataFileError, match=match):
        load_wb_presets(write_presets(tmp_path / "wb.json", presets, version))


def test_two_different_tuning_zero_entries_are_refused(tmp_path):
    f = write_presets(tmp_path / "wb.json", [{"name": "Flash", "channels": [2.0, 1, 1.6, 0]},
                                             {"name": "Flash", "tuning": 0, "channels": [2.1, 1, 1.6, 0]}])
    with pytest.raises(DataFileError, match="two different entries"):
        presets_at_zero_tuning(load_wb_presets(f), "Canon", "EOS Test")


# ---------------------------------------------------------------- the simulated neutral
def test_constant_curves_are_refused_as_no_colour_camera(tmp_path):
    """A camera whose quantum efficiencies are constant (0.3, 0.5, 0.2) counts the same photons in every channel: its
    neutral would be (0.6, 1, 0.4) under any light, but its channels are proportional, so no conversion can make a
    colour of them (issue 34: refused in one line, condition number ∞, instead of a LinAlgError later). The neutral
    arithmetic itself is held to colour-science's integral by the next test."""
    from pathlib import Path

    from spectracam.core.errors import ConfigError
    from spectracam.pipeline.scene_file import parse_scene, resolve_curve_files

    p = tmp_path / "flat.csv"
    p.write_text("wl,R,G,B\n" + "\n".join(f"{w:g},0.3,0.5,0.2" for w in np.arange(380, 781, 5.0)) + "\n")
    with pytest.raises(ConfigError, match="condition number ∞") as e:
        parse_scene(resolve_curve_files({"filters": {"camera_file": str(p), "camera_unit": "electrons_per_photon",
                                                     "qe": "flat"}}, Path(tmp_path)))
    assert "\n" not in str(e.value)


@pytest.mark.parametrize("camera", ["Canon EOS 5D Mark II (rawtoaces)", "Nikon 5100 (NPL)"])
def test_neutral_equals_colour_sciences_integral(camera):
    """Photo-electrons of relative (per-energy) curves ∝ ∫S·E dλ: colour-science's CIE A and D65 at 1 nm over the
    scene's 400–700 nm agree with the simulated camera's 10-nm bands within 0.1 %."""
    import colour

    from spectracam.architecture.cameras import energy_sensitivities
    from spectracam.experiments.validate.experiment import validation_scene

    scene = validation_scene(camera)
    wl, S = energy_sensitivities(camera)
    for name in ("A", "D65"):
        sd = colour.SDS_ILLUMINANTS[name].copy().align(colour.SpectralShape(400, 700, 1))
        lam = np.asarray(sd.wavelengths)
        r = np.array([np.trapezoid(np.interp(lam, wl, S[:, k]) * sd.values, lam) for k in range(3)])
        n = simulated_neutral(scene, IlluminantSpec(kind="cie", temperature_K=None, name=name))
        np.testing.assert_allclose(n, r / r[1], rtol=1e-3)


def test_effective_temperature_recovers_a_known_light():
    from spectracam.experiments.validate.experiment import validation_scene

    scene = validation_scene("Nikon 5100 (NPL)")
    for light, T in ((PresetLight("daylight", "daylight", 5500.0), 6300.0),
                     (PresetLight("tungsten", "planckian", 3000.0), 3400.0)):
        target = simulated_neutral(scene, light_spec(light, T))
        got, rms = effective_cct(lambda ill: simulated_neutral(scene, ill), light, target)
        assert got == pytest.approx(T, rel=2e-3) and rms < 1e-3


# ---------------------------------------------------------------- skipped without the files, in validate's report
def test_missing_files_skip_with_the_reason_and_validate_still_reports(tmp_path, monkeypatch):
    from spectracam.experiments.validate.experiment import validate_markdown

    monkeypatch.setattr(vw, "data_prefixes", lambda: [tmp_path / "nowhere"])
    part = vw.run_validate_wb(SHIPPED)
    for key, pkg in (("wb_presets", "darktable"), ("dcp_profiles", "rawtherapee-data")):
        assert part[key]["status"] == "skipped" and pkg in part[key]["reason"], part[key]
    md = validate_markdown({"renderer": "analytic", "illuminant": "CIE D65", "chart": "x", "cameras": [],
                            "definitions": {}, "library": [], "real_camera_data": part}, "spectracam validate")
    assert md.count("Skipped: ") == 2 and "White-balance presets" in md and "DCP profiles" in md
    json.dumps(part, allow_nan=False)


# ---------------------------------------------------------------- the real files (Debian packages)
@pytest.fixture(scope="module")
def real():
    if vw.find_wb_presets() is None or vw.find_dcp_dir() is None:
        pytest.skip("darktable's wb_presets.json or rawtherapee-data's DCP profiles are not installed (Debian "
                    "packages darktable, rawtherapee-data; `bash tools/setup.sh --test` unpacks them where apt-get may "
                    "run)")
    part = vw.run_validate_wb(SHIPPED)
    json.dumps(part, allow_nan=False)
    wb = {c["model"]: c for c in part["wb_presets"]["cameras"]}
    dcp = {c["model"]: c for c in part["dcp_profiles"]["cameras"]}
    return part, wb, dcp


def rows(cam):
    return {r["preset"]: r for r in cam["presets"]}


def test_nikon_daylight_cloudy_shade_match_the_firmware_within_3_percent(real):
    _, wb, _ = real
    nikon = rows(wb["Nikon D5100"])
    for name in ("Direct Sunlight", "Cloudy", "Shade"):
        r = nikon[name]
        assert abs(r["RG_error_percent"]) < 3 and abs(r["BG_error_percent"]) < 3, r
    # the colour temperatures the firmware's presets stand for, found from the simulated camera, are the manual's
    for name, T in (("Direct Sunlight", 5200), ("Cloudy", 6000), ("Shade", 8000), ("Incandescent", 3000)):
        assert nikon[name]["effective_K_simulated"] == pytest.approx(T, rel=0.03), name


def test_the_nikon_flash_preset_is_a_6600_K_daylight_not_the_manuals_5400_K(real):
    """Measured, not tuned: the firmware's Flash multipliers are the neutral of CIE daylight near 6580 K — by the
    simulated camera and by Adobe's matrix alike, 0.1 % from the daylight locus — so at the manual's 5400 K the
    simulated neutral misses them by ~10 %.  (If this fails, the curves or the file changed: re-check the report.)"""
    _, wb, _ = real
    r = rows(wb["Nikon D5100"])["Flash"]
    assert 6300 < r["effective_K_simulated"] < 6900 and 6300 < r["effective_K_published_matrix"] < 6900
    assert r["effective_rms_percent_simulated"] < 0.5
    assert not r["within_3_percent"]


def test_canon_presets_sit_warm_of_their_nominal_lights_by_every_independent_measure(real):
    """The Canon's daylight-family presets are the neutrals of daylight 250–700 K warmer than the manual's
    temperatures — by the simulated camera (curves published with their gains) and by Adobe's matrix — and at the
    light the preset stands for the simulated neutral is within 1.5 % rms of the firmware's; at the nominal
    lights the B/G misses by 4.9–6.7 %, so the issue's 3 % target does not hold for the Canon."""
    _, wb, _ = real
    canon = rows(wb["Canon EOS 5D Mark II"])
    for name, T in (("Daylight", 5200), ("Cloudy", 6000), ("Shade", 7000), ("Flash", 6000)):
        r = canon[name]
        assert 250 < T - r["effective_K_simulated"] < 700 and 250 < T - r["effective_K_published_matrix"] < 700, r
        assert abs(r["effective_K_simulated"] - r["effective_K_published_matrix"]) < 150, r
        assert r["effective_rms_percent_simulated"] < 1.5
        assert abs(r["RG_error_percent"]) < 3.5 and 3 < r["BG_error_percent"] < 7.5, r
        assert abs(r["RG_dcp_error_percent"]) < 6.5 and 0 < r["BG_dcp_error_percent"] < 9.5, r  # the DCP agrees
        assert abs(r["RG_shape_error_percent"]) < 2 and abs(r["BG_shape_error_percent"]) < 2, r


def test_dcp_matrices_against_spectracams_fits(real):
    _, _, dcp = real
    assert "skipped" in dcp["Sigma SD1 Merrill"]
    canon = {c["illuminant"]: c for c in dcp["Canon EOS 5D Mark II"]["calibrations"]}
    nikon = {c["illuminant"]: c for c in dcp["Nikon D5100"]["calibrations"]}
    assert set(canon) == {"Standard light A", "D50"} and set(nikon) == {"D55"}
    for c in (canon["D50"], nikon["D55"]):  # near daylight the neutrals agree within 2.5 % and the chart within 3 ΔE
        q = c["neutral_ratio_dcp_over_simulated"]
        assert abs(q[0] - 1) < 0.025 and abs(q[2] - 1) < 0.025 and q[1] == 1.0, q
        assert c["delta_e_between_mean"] < 3.0 and c["delta_e_spectracam_mean"] < 2.0
    # under CIE A the Canon's curves and RawTherapee's ColorMatrix1 disagree: documented in the report
    q = canon["Standard light A"]["neutral_ratio_dcp_over_simulated"]
    assert q[0] > 1.1 and q[2] < 0.87
    assert canon["Standard light A"]["delta_e_between_mean"] > 10
