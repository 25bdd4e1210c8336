"""Real cameras (issue 17): measured curves with their true gains, a user's own curves, validation
against published camera matrices, and spectral images from any tool captured."""
import json
import subprocess
import sys

import numpy as np
import pytest

from spectracam.architecture.cameras import (CAMERAS, PUBLISHED_MATRICES, d65_white_xyz, energy_sensitivities, library_curves,
                                restored_gains, to_electrons_per_photon)
from spectracam.core.errors import ConfigError
from spectracam.architecture.filters import FilterSpec, responsivities
from spectracam.core.spectra import WavelengthGrid

CLI = [sys.executable, "-m", "spectracam"]
SMALL = ["--set", "image.width=160", "--set", "image.height=120"]
GRID = WavelengthGrid(np.arange(405.0, 700.0, 10.0))


def run(*args, cwd=None):
    return subprocess.run([*CLI, *map(str, args)], capture_output=True, text=True, cwd=cwd)


def one_line_error(r, *parts):
    assert r.returncode == 2, (r.returncode, r.stderr)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("spectracam: error:"), r.stderr
    for p in parts:
        assert p in lines[0], (p, lines[0])


# ---------------------------------------------------------------- true gains
def d65_response(wl, S):
    """∫S_k·D65 dλ at 1 nm, G = 1 (independent of the module's helper)."""
    import colour

    sd = colour.SDS_ILLUMINANTS["D65"]
    lam = np.arange(wl[0], wl[-1] + 1)
    r = np.array([np.trapezoid(np.interp(lam, wl, S[:, k]) * np.interp(lam, sd.wavelengths, sd.values), lam)
                  for k in range(3)])
    return r / r[1]


def test_nikon_gains_are_restored_to_its_published_d65_neutral():
    wl, S = energy_sensitivities("Nikon 5100 (NPL)")
    M = np.array(PUBLISHED_MATRICES["Nikon D5100"].xyz_to_camera, float).reshape(3, 3)
    n = M @ d65_white_xyz()
    np.testing.assert_allclose(d65_response(wl, S), n / n[1], rtol=1e-9)
    # the defect: the shipped curves, each normalised to a peak of 1, put R/G 32 % and B/G 4 % too high
    raw = library_curves("Nikon 5100 (NPL)")
    equal = d65_response(raw.wavelengths_nm, raw.values)
    assert equal[0] / (n[0] / n[1]) > 1.3 and equal[2] / (n[2] / n[1]) > 1.03
    assert restored_gains("Nikon 5100 (NPL)")[1] == 1.0


def test_published_curves_are_per_unit_energy():
    """The Canon's curves keep their gains: read per unit energy its white under D65 has the neutral its
    published matrix implies within 2 %; read per photon R/G would be 13 % off (why relative curves are
    treated as energy sensitivities)."""
    wl, S = energy_sensitivities("Canon EOS 5D Mark II (rawtoaces)")
    assert restored_gains("Canon EOS 5D Mark II (rawtoaces)").tolist() == [1.0, 1.0, 1.0]
    pub = PUBLISHED_MATRICES["Canon EOS 5D Mark II"].neutral(d65_white_xyz())
    per_energy = d65_response(wl, S)
    per_photon = d65_response(wl, S * wl[:, None])
    assert np.all(np.abs(per_energy / pub - 1) < 0.02), per_energy
    assert abs(per_photon[0] / pub[0] - 1) > 0.10


def test_sigma_layers_sit_where_a_real_merrill_puts_them():
    """Restored from LibRaw's Merrill matrix: under D65 the bottom (R) and middle (G) layers sit 1.9 and
    0.8 stops below the top (B) — Kasson's reading of a DP1 Merrill raw of a white patch: the middle a
    bit less than a stop below the top, the bottom about two (±0.5 stop here)."""
    wl, S = energy_sensitivities("Sigma SDMerill (NPL)")
    r = d65_response(wl, S)
    stops = np.log2(r[2] / r)
    assert stops[1] == pytest.approx(0.8, abs=0.5) and stops[0] == pytest.approx(1.9, abs=0.5), stops


def test_a_camera_without_gains_or_reference_is_refused(monkeypatch):
    from spectracam.architecture import cameras

    entry = cameras._LIBRARY["Sigma SDMerill (NPL)"]
    monkeypatch.setitem(cameras._LIBRARY, "Sigma SDMerill (NPL)", (*entry[:3], None, True))
    cameras.library_curves.cache_clear()
    cameras.restored_gains.cache_clear()
    try:
        with pytest.raises(ConfigError, match="normalised to a peak of 1 per channel.*no published matrix"):
            restored_gains("Sigma SDMerill (NPL)")
        rows = {c["name"]: c for c in cameras.library_table()}
        assert not rows["Sigma SDMerill (NPL)"]["usable"] and "refused" in rows["Sigma SDMerill (NPL)"]["gains"]
    finally:
        cameras.library_curves.cache_clear()
        cameras.restored_gains.cache_clear()
    r = run("cameras", "--json")
    rows = {c["name"]: c for c in json.loads(r.stdout)}
    assert set(rows) == set(CAMERAS) and all(c["usable"] for c in rows.values())
    assert rows["Nikon 5100 (NPL)"]["gains"].startswith("restored")
    assert rows["Canon EOS 5D Mark II (rawtoaces)"]["gains"] == "as published"
    table = run("cameras")
    assert table.returncode == 0 and "LibRaw" in table.stdout and "camera_file" in table.stdout


def test_camera_curves_must_cover_the_scene_and_exclude_a_second_qe():
    sigma_range = WavelengthGrid(np.arange(405.0, 700.0, 10.0))
    spec = FilterSpec(kind="camera", camera="file", camera_curve_nm=(400.0, 550.0, 680.0),
                      camera_curve=((0.1, 0.2, 0.9), (0.3, 0.8, 0.2), (0.6, 0.3, 0.1)))
    with pytest.raises(ConfigError, match="cover 400–680 nm but the scene's bands span 400–700 nm"):
        responsivities(spec, sigma_range)
    with pytest.raises(ConfigError, match="filters.qe = 'photodiode': measured camera curves already include"):
        FilterSpec(kind="camera", qe="photodiode")
    with pytest.raises(ConfigError, match="filters.camera = 'file': needs filters.camera_file"):
        FilterSpec(kind="camera", camera="file")


# ---------------------------------------------------------------- a user's curves
def canon_csv(path, unit_scale=1.0):
    wl, S = energy_sensitivities("Canon EOS 5D Mark II (rawtoaces)")
    rows = "\n".join(f"{w:g},{a * unit_scale:.9g},{b * unit_scale:.9g},{c * unit_scale:.9g}" for w, (a, b, c) in zip(wl, S))
    path.write_text("# Canon EOS 5D Mark II, rawtoaces\nwavelength_nm,R,G,B\n" + rows + "\n")
    return path


def test_a_csv_of_a_shipped_camera_gives_the_same_responsivities(tmp_path):
    from spectracam.pipeline.scene_file import resolve_curve_files

    data = resolve_curve_files({"filters": {"camera_file": str(canon_csv(tmp_path / "c.csv"))}}, tmp_path)
    assert data["filters"]["camera"] == "file" and data["filters"]["kind"] == "camera"
    mine = FilterSpec(**data["filters"])
    shipped = FilterSpec(kind="camera", camera="Canon EOS 5D Mark II (rawtoaces)")
    np.testing.assert_allclose(responsivities(mine, GRID), responsivities(shipped, GRID), rtol=1e-6)
    assert json.loads(json.dumps(mine.to_dict()))["camera_curve"][0] == list(mine.camera_curve[0])  # recorded


def test_absolute_units_convert_in_closed_form():
    wl = np.array([400.0, 550.0, 700.0])
    v = np.array([[0.1, 0.2, 0.3]] * 3)
    aw = to_electrons_per_photon(wl, v, "A/W", 0.5)
    # QE = R·hc/(qλ): 1239.84198 nm·A/W per unit QE
    np.testing.assert_allclose(aw[1], v[1] * 1239.84198 / 550.0, rtol=1e-8)
    np.testing.assert_array_equal(to_electrons_per_photon(wl, v, "electrons_per_photon", 0.5), v)
    rel = to_electrons_per_photon(wl, v, "relative", 0.5)
    assert rel.max() == pytest.approx(0.5) and rel[0, 2] / rel[2, 2] == pytest.approx(700 / 400)


BAD_CSVS = {
    "unsorted": ("wl,R,G,B\n500,1,1,1\n450,1,1,1\n600,1,1,1\n", "wavelengths must increase"),
    "nan": ("wl,R,G,B\n400,1,1,1\n500,nan,1,1\n700,1,1,1\n", "not finite"),
    "negative": ("wl,R,G,B\n400,1,1,1\n500,-0.1,1,1\n700,1,1,1\n", "must be ≥ 0"),
    "short": ("wl,R,G,B\n400,1,1,1\n", "need ≥ 2 rows"),
    "columns": ("wl,R,G\n400,1,1\n700,1,1\n", "need 4 numbers"),
    "narrow": ("wl,R,G,B\n450,0.1,0.4,0.9\n550,0.4,0.8,0.3\n650,0.7,0.3,0.1\n", "cover 450–650 nm"),
    "dark": ("wl,R,G,B\n400,1,0,1\n700,1,0,1\n", "needs a sensitivity > 0"),
}


@pytest.mark.parametrize("case", sorted(BAD_CSVS))
def test_a_bad_camera_file_is_one_line(tmp_path, case):
    text, message = BAD_CSVS[case]
    (tmp_path / "c.csv").write_text(text)
    r = run("simulate", "scenes/d65.toml", "-o", tmp_path / "out", "--renderer", "analytic", *SMALL,
            "--set", f'filters.camera_file="{tmp_path / "c.csv"}"')
    one_line_error(r, "filters.camera_file", message)
    assert not (tmp_path / "out").exists()


def test_unknown_unit_and_impossible_qe_are_one_line(tmp_path):
    csv = canon_csv(tmp_path / "c.csv")
    r = run("simulate", "scenes/d65.toml", "-o", tmp_path / "o", "--renderer", "analytic", *SMALL,
            "--set", f'filters.camera_file="{csv}"', "--set", 'filters.camera_unit="W/m2"')
    one_line_error(r, "filters.camera_unit = 'W/m2'", "relative")
    r = run("simulate", "scenes/d65.toml", "-o", tmp_path / "o", "--renderer", "analytic", *SMALL,
            "--set", f'filters.camera_file="{canon_csv(tmp_path / "d.csv", 2.0)}"', "--set", 'filters.camera_unit="A/W"')
    one_line_error(r, "filters.camera_unit = 'A/W'", "electrons per photon", "≤ 1")


def test_the_three_units_describe_the_same_camera_when_they_should(tmp_path):
    """The same camera written in each unit gives identical captures: relative energy curves S, the
    electrons per photon they mean (S/λ scaled to qe_peak), and the A/W of those (QE·qλ/hc)."""
    from spectracam.pipeline import simulate
    from spectracam.pipeline.scene_file import parse_scene, resolve_curve_files

    wl, S = energy_sensitivities("Canon EOS 5D Mark II (rawtoaces)")
    qe = S / wl[:, None]
    qe *= 0.5 / qe.max()  # qe_peak's default
    aw = qe * wl[:, None] / 1239.84198
    files = {}
    for unit, v in (("relative", S), ("electrons_per_photon", qe), ("A/W", aw)):
        path = tmp_path / f"{unit.replace('/', '_')}.csv"
        path.write_text("wl,R,G,B\n" + "\n".join(f"{w:g},{a!r},{b!r},{c!r}" for w, (a, b, c) in zip(wl, v)) + "\n")
        files[unit] = path
    out = {}
    for unit, path in files.items():
        data = resolve_curve_files({"image": {"width": 160, "height": 120}, "illuminant": {"type": "cie", "name": "D65"},
                                    "filters": {"camera_file": str(path), "camera_unit": unit},
                                    "sensor": {"shot_noise": False, "read_noise": False, "fpn": False,
                                               "dark_current": False, "quantization": False}}, tmp_path)
        _, raw, score = simulate(parse_scene(data), "analytic")
        out[unit] = (raw.exposure_times_s[0], score.summary.delta_e_mean)
    for unit in ("electrons_per_photon", "A/W"):
        assert out[unit][0] == pytest.approx(out["relative"][0], rel=1e-6), unit
        assert out[unit][1] == pytest.approx(out["relative"][1], rel=1e-6), unit


# ---------------------------------------------------------------- validate against published matrices
def test_validate_reproduces_the_published_neutrals_and_matrices(tmp_path):
    r = run("validate", "-o", tmp_path / "v", "--renderer", "analytic")
    assert r.returncode == 0, r.stderr
    res = json.loads((tmp_path / "v" / "validate.json").read_text())
    rows = {c["model"]: c for c in res["cameras"]}
    assert set(rows) == {"Canon EOS 5D Mark II", "Nikon D5100", "Sigma SD1 Merrill"}
    for c in rows.values():  # the bar: the neutral within 3 %
        assert abs(c["white_RG_error_percent"]) < 3 and abs(c["white_BG_error_percent"]) < 3, c["model"]
    # the README's numbers (measured; ±0.05): the published matrix on the simulated raw, and the fit (training)
    assert rows["Canon EOS 5D Mark II"]["delta_e_published_mean"] == pytest.approx(3.52, abs=0.05)
    assert rows["Canon EOS 5D Mark II"]["delta_e_published_max"] == pytest.approx(7.65, abs=0.05)
    assert rows["Nikon D5100"]["delta_e_published_mean"] == pytest.approx(1.87, abs=0.05)
    assert rows["Nikon D5100"]["delta_e_fit_mean"] == pytest.approx(1.62, abs=0.05)
    assert rows["Nikon D5100"]["white_RG_equal_gains"] > 1.3 * rows["Nikon D5100"]["white_RG_published"]
    assert rows["Sigma SD1 Merrill"]["delta_e_published_mean"] == pytest.approx(12.92, abs=0.05)
    # the cameras' own data from Debian packages (tests/test_validate_wb.py): tables, or the reason they were skipped
    md = (tmp_path / "v" / "validate.md").read_text()
    for key, title in (("wb_presets", "White-balance presets"), ("dcp_profiles", "DCP profiles")):
        part = res["real_camera_data"][key]
        assert part["status"] in ("ok", "skipped") and title in md
        assert (part["status"] == "ok") == ("cameras" in part) and (part["status"] == "ok") != ("reason" in part)
    for f in ("validate.md", "validate.png", "validate.svg"):
        assert (tmp_path / "v" / f).stat().st_size > 1000


# ---------------------------------------------------------------- any spectral image in
@pytest.fixture(scope="module")
def chart_exr(tmp_path_factory):
    d = tmp_path_factory.mktemp("exr")
    r = run("render", "scenes/d65.toml", "-o", d, "--renderer", "analytic", *SMALL, "--quiet")
    assert r.returncode == 0, r.stderr
    return d / "radiance.exr"


def rewrite(src, dst, attrs=None, scale=1.0, drop_spectracam=False):
    from spectracam.io.exr import read_exr, write_exr

    ch, at = read_exr(src)
    keep = {k: v for k, v in at.items() if k in ("spectralLayoutVersion", "emissiveUnits") or
            (k.startswith("spectracam") and not drop_spectracam)}
    keep.update(attrs or {})
    keep = {k: v for k, v in keep.items() if v is not None}
    write_exr(dst, {k: (v * scale if k.startswith("S0.") else v) for k, v in ch.items()}, keep)
    return dst


def test_a_stripped_spectral_exr_captures_with_a_config(tmp_path, chart_exr):
    from spectracam.io.exr import read_exr, read_raw_exr

    f = rewrite(chart_exr, tmp_path / "s.exr", drop_spectracam=True)
    (tmp_path / "cam.toml").write_text('[capture]\narchitecture = "prism"\nexposure = "optimal"\n')
    r = run("capture", f, "-o", tmp_path / "c", "--config", tmp_path / "cam.toml")
    assert r.returncode == 0, r.stderr
    assert "ΔE per patch and SNR are skipped" in r.stderr
    raw = read_raw_exr(tmp_path / "c" / "raw.exr")
    assert raw.scene is None and raw.design == "prism/optimal" and raw.metering == {"kind": "brightest"}
    assert {p.name for p in (tmp_path / "c").iterdir()} == {"raw.exr", "raw.dng", "rendered.exr", "rendered.png"}
    # the brightest neutral of the chart is its white patch: the same exposure as the chart's own metering
    r2 = run("capture", chart_exr, "-o", tmp_path / "n", "--config", tmp_path / "cam.toml")
    assert r2.returncode == 0, r2.stderr
    native = read_raw_exr(tmp_path / "n" / "raw.exr")
    np.testing.assert_allclose(raw.exposure_times_s, native.exposure_times_s, rtol=0.01)
    _, at = read_exr(tmp_path / "c" / "rendered.exr")
    assert json.loads(at["spectracamParameters"])["metering"] == {"kind": "brightest"}


# colour-science's Fichet 2021 writer aligns its own CMFs and illuminant to the image's 10-nm shape for the file's
# preview and says so: the second tool's message about its own preview, not about the spectra it writes
@pytest.mark.filterwarnings("ignore:Aligning:colour.utilities.ColourRuntimeWarning")
def test_colour_sciences_spectral_exr_is_captured(tmp_path):
    """A second tool writes the file: colour-science's Fichet 2021 writer, through OpenImageIO."""
    colour = pytest.importorskip("colour")
    pytest.importorskip("OpenImageIO")
    from spectracam.io.exr import read_raw_exr
    from spectracam.sensor import adc_inverse

    wl = np.arange(380.0, 781.0, 10.0)
    sd = colour.SDS_ILLUMINANTS["D65"]
    E = np.interp(wl, sd.wavelengths, sd.values) * 0.01  # W·m⁻²·sr⁻¹·nm⁻¹
    h, w = 24, 32
    img = np.empty((h, w, wl.size), np.float32)
    img[:, :16] = E * 0.8  # a grey half (neutral under D65)
    img[:, 16:] = E * np.where(wl > 600, 0.7, 0.05)  # a red half, brighter in R
    msds = colour.MultiSpectralDistributions(img.reshape(-1, wl.size).T, wl, labels=[str(i) for i in range(h * w)])
    spec = colour.io.Specification_Fichet2021(is_emissive=True, attributes=None)  # None: the writer adds emissiveUnits
    colour.io.write_spectral_image_Fichet2021(msds, str(tmp_path / "c.exr"), "float32", spec, shape=(h, w, wl.size))
    camera = ["--set", "capture.architecture=prism", "--set", "capture.exposure=optimal", "--set",
              "sensor.shot_noise=false", "--set", "sensor.fpn=false", "--set", "sensor.read_noise=false",
              "--set", "sensor.dark_current=false"]
    r = run("capture", tmp_path / "c.exr", "-o", tmp_path / "c", *camera)
    assert r.returncode == 0, r.stderr
    assert "bands outside 380–730 nm dropped" in r.stderr  # the chart the conversion is fitted on stops at 730
    raw = read_raw_exr(tmp_path / "c" / "raw.exr")
    assert raw.metering == {"kind": "brightest"}
    # metered on the grey half: each channel's mean charge there reaches 95 % of the well
    e = adc_inverse(raw.digital, raw.camera.sensor)[:, 2:-2, 2:14].mean(axis=(1, 2))
    np.testing.assert_allclose(e, 0.95 * raw.camera.sensor.q_max_e, rtol=0.01)
    # the same image without emissiveUnits (colour's default specification) is refused: the scale is unknown
    colour.io.write_spectral_image_Fichet2021(msds, str(tmp_path / "n.exr"), "float32",
                                              colour.io.Specification_Fichet2021(is_emissive=True), shape=(h, w, wl.size))
    one_line_error(run("capture", tmp_path / "n.exr", "-o", tmp_path / "n"), "has no emissiveUnits", "--units")
    r = run("capture", tmp_path / "n.exr", "-o", tmp_path / "n", "--units", "mW.m^-2.sr^-1", *camera)
    assert r.returncode == 0, r.stderr
    # in mW the same numbers are 1000x less light: 1000x the exposure
    np.testing.assert_allclose(read_raw_exr(tmp_path / "n" / "raw.exr").exposure_times_s, 1e3 * raw.exposure_times_s,
                               rtol=1e-4)


@pytest.mark.parametrize("edit, message", [
    ({"spectracamScene": "3000K"}, "contradict the scene it records (3000 K blackbody"),
    ({"scale": 1.5}, "contradict the scene it records"),
    ({"spectracamScene": "ohta"}, "contradict the scene it records"),
    ({"emissiveUnits": "photons.s^-1.m^-2.sr^-1"}, "emissiveUnits = 'photons.s^-1.m^-2.sr^-1'"),
])
def test_a_file_that_contradicts_its_scene_is_refused(tmp_path, chart_exr, edit, message):
    from spectracam.io.exr import read_exr

    _, at = read_exr(chart_exr)
    scene = json.loads(at["spectracamScene"])
    attrs = {}
    if edit.get("spectracamScene") == "3000K":
        scene["illuminant"] = {"type": "blackbody", "temperature_K": 3000.0, "white_luminance_cd_m2": 100.0}
        attrs["spectracamScene"] = json.dumps(scene)
    elif edit.get("spectracamScene") == "ohta":
        scene["chart"]["dataset"] = "ColorChecker N Ohta"
        attrs["spectracamScene"] = json.dumps(scene)
    elif "emissiveUnits" in edit:
        attrs["emissiveUnits"] = edit["emissiveUnits"]
    f = rewrite(chart_exr, tmp_path / "x.exr", attrs, scale=edit.get("scale", 1.0))
    one_line_error(run("capture", f, "-o", tmp_path / "c"), message)
    assert not (tmp_path / "c").exists()


def test_metering_on_a_region_a_level_and_the_patch(chart_exr):
    """Python API: a region equal to the white patch's box meters exactly as the patch; a white luminance
    L meters a perfect white diffuser of L under the scene light in closed form (cfa/single: the channel
    with the highest rate ends the exposure)."""
    from spectracam.camera import band_weights
    from spectracam.io.exr import read_radiance_exr
    from spectracam.sensor.metering import white_radiance_of
    from spectracam.pipeline import capture, scene_of
    from spectracam.scene.reference import ChartReference

    cube, _ = read_radiance_exr(chart_exr)
    scene = scene_of(cube)
    patch = capture(cube)
    r, c = ChartReference.of(scene).white_box
    box = capture(cube, white=f"{c.start},{r.start},{c.stop},{r.stop}")
    np.testing.assert_allclose(box.exposure_times_s, patch.exposure_times_s, rtol=1e-12)
    level = capture(cube, white="100")
    s = scene.camera.sensor
    rate = white_radiance_of(scene, cube.grid, 100.0) @ band_weights(scene.camera, cube.grid).astype(float)
    np.testing.assert_allclose(level.exposure_times_s, 0.95 * s.q_max_e / (rate.max() + s.dark_rate_e_per_s),
                               rtol=1e-6)
    for bad, msg in (("0", "white luminance"), ("1,2,3", "X0,Y0,X1,Y1"), ("5,5,2,9", "0 ≤ X0 < X1"),
                     ("0,0,9999,9", "outside the 160x120 image"), ("grey", "must be 'patch'")):
        with pytest.raises(ConfigError, match=msg):
            capture(cube, white=bad)


# ---------------------------------------------------------------- a user's curves must keep their gains (issue 34)
NIKON_M = "8198,-2239,-724,-4871,12389,2798,-1043,2050,7181"


def nikon_npl_csv(path, columns=(0, 1, 2)):
    """colour-science's Nikon 5100 (NPL) curves as published — each channel normalised to a peak of 1 — as the
    README's camera CSV (``columns`` picks the file's R, G, B from the curves' channels)."""
    import colour

    m = colour.MSDS_CAMERA_SENSITIVITIES["Nikon 5100 (NPL)"]
    v = np.asarray(m.values)[:, list(columns)]
    path.write_text("wavelength_nm,R,G,B\n" + "\n".join(f"{w:g},{a:.9g},{b:.9g},{c:.9g}" for w, (a, b, c)
                                                         in zip(m.wavelengths, v)) + "\n")
    return path


def test_peak_normalised_curves_are_refused_naming_the_fix(tmp_path):
    csv = nikon_npl_csv(tmp_path / "n.csv")
    r = run("simulate", "scenes/d65.toml", "-o", tmp_path / "o", "--renderer", "analytic", *SMALL,
            "--set", f'filters.camera_file="{csv}"')
    one_line_error(r, "filters.camera_file", "peaks [1.0, 1.0, 1.0]", "gains between them are lost",
                   "filters.camera_gains", "filters.camera_xyz_to_camera", "filters.camera_gains_kept = true")
    assert not (tmp_path / "o").exists()
    # the same refusal for any common peak (a percentage), none for curves with their gains (the Canon's)
    wl, S = energy_sensitivities("Nikon 5100 (NPL)")
    with pytest.raises(ConfigError, match="all peak at the same value"):
        FilterSpec(kind="camera", camera="file", camera_curve_nm=tuple(wl), camera_curve=tuple(map(tuple, 100 * S /
                                                                                                   S.max(0))))
    FilterSpec(kind="camera", camera="file", camera_curve_nm=tuple(wl), camera_curve=tuple(map(tuple, S)))


def test_a_matrix_or_gains_restore_a_user_camera_to_the_shipped_one(tmp_path):
    """The Nikon's NPL curves with Adobe's matrix (or with the gains it implies) are the shipped Nikon exactly;
    kept at equal gains on request, the D65 white reads R/G 0.582 where the matrix implies 0.443 (the defect,
    made explicit)."""
    from spectracam.architecture.cameras import d65_response
    from spectracam.pipeline.scene_file import resolve_curve_files

    csv = nikon_npl_csv(tmp_path / "n.csv")
    shipped = responsivities(FilterSpec(kind="camera", camera="Nikon 5100 (NPL)"), GRID)
    m = tuple(float(x) for x in NIKON_M.split(","))
    g = restored_gains("Nikon 5100 (NPL)")
    for extra in ({"camera_xyz_to_camera": m}, {"camera_xyz_to_camera": [list(m[:3]), list(m[3:6]), list(m[6:])]},
                  {"camera_gains": list(g * 7.0)}):
        data = resolve_curve_files({"filters": {"camera_file": str(csv), **extra}}, tmp_path)
        np.testing.assert_allclose(responsivities(FilterSpec(**data["filters"]), GRID), shipped, rtol=1e-6)
    data = resolve_curve_files({"filters": {"camera_file": str(csv), "camera_gains_kept": True}}, tmp_path)
    kept = FilterSpec(**data["filters"])
    r = d65_response(np.asarray(kept.camera_curve_nm), np.asarray(kept.camera_curve))
    assert r[0] == pytest.approx(0.582, abs=0.002)
    assert PUBLISHED_MATRICES["Nikon D5100"].neutral(d65_white_xyz())[0] == pytest.approx(0.441, abs=0.001)


@pytest.mark.parametrize("extra, message", [
    ({"camera_gains": [1, 0, 1]}, "filters.camera_gains = [1, 0, 1]: must be 3 finite numbers > 0"),
    ({"camera_gains": [1, 1]}, "must be 3 finite numbers > 0"),
    ({"camera_xyz_to_camera": [1, 2, 3]}, "must be 9 finite numbers"),
    ({"camera_xyz_to_camera": [1, 0, 0, 1, 0, 0, 0, 0, 1]}, "must be an invertible 3×3 matrix"),
    ({"camera_xyz_to_camera": [-1, 0, 0, 0, 1, 0, 0, 0, 1]}, "every channel of a white must be > 0"),
    ({"camera_gains": [1, 1, 1], "camera_xyz_to_camera": [1, 0, 0, 0, 1, 0, 0, 0, 1]}, "not both"),
    ({"kind": "block", "camera_gains_kept": True}, "filters.kind = 'block': curves are given"),
    ({"camera_gains_kept": "yes"}, "filters.camera_gains_kept = 'yes': must be true or false"),
])
def test_bad_gain_options_are_one_line(tmp_path, extra, message):
    from spectracam.pipeline.scene_file import resolve_curve_files

    data = resolve_curve_files({"filters": {"camera_file": str(nikon_npl_csv(tmp_path / "n.csv")), **extra}}, tmp_path)
    with pytest.raises(ConfigError, match=message.replace("[", "\\[").replace("]", "\\]")):
        FilterSpec(**data["filters"])


def test_gain_options_need_a_camera_file():
    with pytest.raises(ConfigError, match="filters.camera_gains.*applies only to a camera of your own"):
        FilterSpec(kind="camera", camera_gains=(1.0, 1.0, 1.0))


def test_camera_file_with_block_filters_is_refused_not_ignored(tmp_path):
    csv = canon_csv(tmp_path / "c.csv")
    r = run("simulate", "scenes/d65.toml", "-o", tmp_path / "o", "--renderer", "analytic", *SMALL,
            "--set", f'filters.camera_file="{csv}"', "--set", "filters.kind=block")
    one_line_error(r, "filters.kind = 'block'", "filters.kind must be 'camera'")


def test_identical_channels_are_refused_in_one_line(tmp_path):
    """Three copies of one channel cannot form a colour (before issue 34: LinAlgError: Singular matrix)."""
    csv = nikon_npl_csv(tmp_path / "same.csv", columns=(1, 1, 1))
    r = run("simulate", "scenes/d65.toml", "-o", tmp_path / "o", "--renderer", "analytic", *SMALL,
            "--set", f'filters.camera_file="{csv}"', "--set", "filters.camera_gains_kept=true")
    one_line_error(r, "filters.camera_file", "channels are so alike", "allowed ≤ 100")
    assert not (tmp_path / "o").exists()


def test_channel_condition_of_the_shipped_cameras():
    from spectracam.architecture.cameras import channel_condition

    k = {n: channel_condition(library_curves(n).wavelengths_nm, library_curves(n).values) for n in CAMERAS}
    assert k["Nikon 5100 (NPL)"] == pytest.approx(1.93, abs=0.01)
    assert k["Canon EOS 5D Mark II (rawtoaces)"] == pytest.approx(2.07, abs=0.01)
    assert k["Sigma SDMerill (NPL)"] == pytest.approx(11.4, abs=0.05)
    wl = np.arange(400.0, 701.0)
    assert channel_condition(wl, np.stack([np.exp(-((wl - 550) / 40) ** 2)] * 3, axis=1)) == float("inf")


def test_validate_checks_a_users_camera_as_a_shipped_one(tmp_path):
    """The Nikon's NPL curves and Adobe's matrix given on the command line give the shipped Nikon's row."""
    csv = nikon_npl_csv(tmp_path / "n.csv")
    (tmp_path / "m.txt").write_text("# Nikon D5100, Adobe ColorMatrix2 x 1e4\n[[8198, -2239, -724],\n"
                                    "[-4871, 12389, 2798], [-1043, 2050, 7181]]\n")
    r = run("validate", "-o", tmp_path / "v", "--renderer", "analytic", "--camera-file", csv, "--matrix",
            tmp_path / "m.txt")
    assert r.returncode == 0, r.stderr
    res = json.loads((tmp_path / "v" / "validate.json").read_text())
    (row,) = res["cameras"]
    assert row["white_RG_simulated"] == pytest.approx(0.444, abs=0.001)
    assert row["white_RG_published"] == pytest.approx(0.443, abs=0.001)
    assert row["delta_e_published_mean"] == pytest.approx(1.87, abs=0.05)
    assert row["delta_e_fit_mean"] == pytest.approx(1.62, abs=0.05)
    assert row["white_RG_equal_gains"] > 1.3 * row["white_RG_published"]
    assert row["gains"].startswith("restored") and "real_camera_data" not in res
    assert "equal gains" in (tmp_path / "v" / "validate.md").read_text()


@pytest.mark.parametrize("args, message", [
    (["--matrix", "1,2,3"], "--matrix = '1,2,3': must be 9 finite numbers"),
    ([], "--camera-file and --matrix go together"),
    (["--matrix", NIKON_M, "--camera-gains", "1,x,1"], "filters.camera_gains"),
    (["--matrix", "0,0,0,0,0,0,0,0,0"], "must be an invertible 3×3 matrix"),
])
def test_validate_refuses_bad_user_input_in_one_line(tmp_path, args, message):
    csv = nikon_npl_csv(tmp_path / "n.csv")
    one_line_error(run("validate", "-o", tmp_path / "v", "--camera-file", csv, *args), message)
    assert not (tmp_path / "v").exists()
