"""colour-science's tables kept on disk (spectracam.core.colour_data): the same numbers as the live package, bit for
bit; the closed forms computed here against colour-science's functions; the snapshot rebuilt when damaged or stale;
a command that needs nothing else from colour-science does not import it."""
import os
import subprocess
import sys
from pathlib import Path

import colour
import numpy as np
import pytest

from spectracam.core import colour_data

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture
def fresh(tmp_path, monkeypatch):
    """The module as a new process sees it: no tables in memory, its snapshot folder ``tmp_path``."""
    monkeypatch.setenv("SPECTRACAM_TABLES", str(tmp_path))
    monkeypatch.setattr(colour_data, "_TABLES", None)
    yield tmp_path
    monkeypatch.setattr(colour_data, "_TABLES", None)


def _same(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.dtype == b.dtype and np.array_equal(a, b)


def test_every_table_is_colour_sciences_bit_for_bit():
    names = colour_data.illuminant_names()
    assert names == tuple(colour.SDS_ILLUMINANTS)
    for name in names:
        wl, v = colour_data.illuminant_sd(name)
        assert _same(wl, np.asarray(colour.SDS_ILLUMINANTS[name].wavelengths, float)), name
        assert _same(v, np.asarray(colour.SDS_ILLUMINANTS[name].values, float)), name
    ccs = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]
    for name in ccs:
        assert _same(colour_data.illuminant_xy(name), np.asarray(ccs[name], float)), name
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    wl, v = colour_data.cmfs_1931()
    assert _same(wl, np.asarray(cmfs.wavelengths, float)) and _same(v, np.asarray(cmfs.values, float))
    assert _same(colour_data.cmfs_1931_380_780_5(),
                 np.asarray(cmfs.copy().align(colour.SpectralShape(380, 780, 5)).values, float))
    for dataset, sds in colour.SDS_COLOURCHECKERS.items():
        got = colour_data.sd_set(f"colourchecker/{dataset}")
        assert [n for n, _, _ in got] == list(sds), dataset
        for (n, w, r), sd in zip(got, sds.values()):
            assert _same(w, np.asarray(sd.wavelengths, float)) and _same(r, np.asarray(sd.values, float)), n
    for key, sds in (("tcs14", dict(list(colour.quality.datasets.SDS_TCS["CIE 1995"].items())[:14])),
                     ("vs15", colour.quality.datasets.SDS_VS["NIST CQS 9.0"])):
        got = colour_data.sd_set(key)
        assert [n for n, _, _ in got] == list(sds) and len(got) == {"tcs14": 14, "vs15": 15}[key]
        for (n, w, r), sd in zip(got, sds.values()):
            assert _same(w, np.asarray(sd.wavelengths, float)) and _same(r, np.asarray(sd.values, float)), n
    from colour.quality.cfi2017 import load_TCS_CIE2017

    for key, msds in (("cfi99", load_TCS_CIE2017(colour.SpectralShape(380, 780, 5))),
                      ("rawtoaces190", colour.characterisation.read_training_data_rawtoaces_v1())):
        labels, wl, v = colour_data.sample_set(key)
        assert labels == tuple(msds.labels) and _same(wl, np.asarray(msds.wavelengths, float))
        assert _same(v, np.asarray(msds.values, float))
    prim = colour.MSDS_DISPLAY_PRIMARIES["Typical CRT Brainard 1997"]
    wl, v = colour_data.display_primaries("Typical CRT Brainard 1997")
    assert _same(wl, np.asarray(prim.wavelengths, float)) and _same(v, np.asarray(prim.values, float))
    for name, msds in colour.MSDS_CAMERA_SENSITIVITIES.items():
        wl, v = colour_data.camera_sensitivities(name)
        assert _same(wl, np.asarray(msds.wavelengths, float)) and _same(v, np.asarray(msds.values, float)), name
    path = colour_data.colour_package_file("characterisation", "datasets", "rawtoaces",
                                           "CANON_EOS_5DMark_II_RGB_Sensitivities.csv")
    assert path.is_file() and path.parent.parent.parent.parent == Path(colour.__file__).parent
    srgb = colour.RGB_COLOURSPACES["sRGB"]
    assert _same(colour_data.srgb_matrix("RGB_to_XYZ"), np.asarray(srgb.matrix_RGB_to_XYZ, float))
    assert _same(colour_data.srgb_matrix("XYZ_to_RGB"), np.asarray(srgb.matrix_XYZ_to_RGB, float))
    for t in colour_data.CAT_TRANSFORMS:
        assert _same(colour_data.cat_matrix(t), np.asarray(colour.adaptation.CHROMATIC_ADAPTATION_TRANSFORMS[t], float))
    from colour.temperature.robertson1968 import DATA_ISOTEMPERATURE_LINES_ROBERTSON1968

    assert _same(colour_data.robertson_table(), np.asarray(DATA_ISOTEMPERATURE_LINES_ROBERTSON1968, float))


def test_a_table_handed_out_is_a_copy():
    wl, v = colour_data.illuminant_sd("D65")
    v[:] = -1.0
    assert colour_data.illuminant_sd("D65")[1].min() > 0


@pytest.mark.parametrize("ask", [lambda: colour_data.illuminant_sd("D66"), lambda: colour_data.illuminant_xy("D66"),
                                 lambda: colour_data.sd_set("colourchecker/nosuch"), lambda: colour_data.sd_set("cmfs"),
                                 lambda: colour_data.sample_set("tcs14"), lambda: colour_data.srgb_matrix("RGB"),
                                 lambda: colour_data.cat_matrix("CAT02"), lambda: colour_data.display_primaries("LCD"),
                                 lambda: colour_data.camera_sensitivities("Nikon D70")])
def test_an_unknown_name_is_a_key_error(ask):
    with pytest.raises(KeyError):
        ask()


@pytest.mark.parametrize("transform", colour_data.CAT_TRANSFORMS)
def test_von_kries_matrix_is_colour_sciences(transform):
    rng = np.random.default_rng(3)
    for _ in range(300):
        w, wr = rng.uniform(0.2, 1.5, 3), rng.uniform(0.2, 1.5, 3)
        assert _same(colour_data.von_kries_matrix(w, wr, transform),
                     colour.adaptation.matrix_chromatic_adaptation_VonKries(w, wr, transform=transform))
    w = np.array([0.9505, 1.0, 1.089])
    assert np.allclose(colour_data.von_kries_matrix(w, w, transform), np.eye(3), atol=1e-15)


def test_uv_and_robertson_cct_are_colour_sciences():
    """Inside the table (1667 K … ∞), beyond both its ends and off the locus; one point and many at once."""
    rng = np.random.default_rng(4)
    xy = np.column_stack([rng.uniform(0.05, 0.75, 5000), rng.uniform(0.05, 0.6, 5000)])
    xy = np.vstack([xy, [[0.3127, 0.3290], [0.44757, 0.40745], [0.6, 0.38], [0.24, 0.22]]])
    uv = colour_data.xy_to_uv(xy)
    assert _same(uv, colour.xy_to_UCS_uv(xy))
    assert _same(colour_data.uv_to_cct_robertson(uv), colour.temperature.uv_to_CCT(uv, method="Robertson 1968"))
    for p in uv[::250]:
        assert _same(colour_data.uv_to_cct_robertson(p), colour.temperature.uv_to_CCT(p, method="Robertson 1968"))
    # D65 and A: their published CCTs, 6504 K and 2856 K
    cct = colour_data.uv_to_cct_robertson(colour_data.xy_to_uv([[0.3127, 0.3290], [0.44757, 0.40745]]))[:, 0]
    assert abs(cct[0] - 6504) < 5 and abs(cct[1] - 2856) < 3


def test_srgb_encoding_is_colour_sciences():
    x = np.concatenate([np.random.default_rng(5).uniform(-0.2, 1.3, 50000), [0.0, 0.0031308, 0.0031309, 1.0]])
    assert _same(colour_data.srgb_encode(x), colour.cctf_encoding(x, "sRGB"))


def test_the_snapshot_is_written_once_and_read_back(fresh):
    path = colour_data.snapshot_path()
    assert path.parent == fresh and path.name == f"colour-science-{colour.__version__}.npz" and not path.exists()
    built = colour_data.tables()
    assert path.exists() and not [p for p in fresh.iterdir() if p.name.startswith(".tmp")]
    read = colour_data._read(path)
    assert read.keys() == built.keys() and all(_same(read[k], built[k]) for k in built)
    stamp = path.stat().st_mtime_ns
    colour_data._TABLES = None
    colour_data.tables()
    assert path.stat().st_mtime_ns == stamp   # read, not written again


def _damage(path, how):
    data = path.read_bytes()
    if how == "truncated":
        path.write_bytes(data[: len(data) // 2])
    elif how == "garbage":
        path.write_bytes(b"not a zip file at all")
    elif how == "empty":
        path.write_bytes(b"")
    elif how == "short_data":   # a whole zip whose index points past its numbers
        with np.load(path) as npz:
            np.savez(path, data=npz["data"][:100], index=npz["index"])
    elif how == "older_schema":
        t = colour_data._read(path)
        t["meta/schema"] = np.array(colour_data.SCHEMA - 1.0)
        np.savez(path, **colour_data._pack(t))
    elif how == "other_version":
        t = colour_data._read(path)
        t["meta/colour_version"] = np.array("0.0.1")
        np.savez(path, **colour_data._pack(t))
    elif how == "a_table_missing":
        t = colour_data._read(path)
        del t["robertson/table"]
        np.savez(path, **colour_data._pack(t))


@pytest.mark.parametrize("how", ["truncated", "garbage", "empty", "short_data", "older_schema", "other_version",
                                 "a_table_missing"])
def test_a_damaged_or_stale_snapshot_is_rebuilt(fresh, how):
    colour_data.tables()
    path = colour_data.snapshot_path()
    _damage(path, how)
    assert colour_data._read(path) is None
    colour_data._TABLES = None
    t = colour_data.tables()
    assert colour_data._read(path) is not None and _same(t["robertson/table"], colour_data.robertson_table())
    assert _same(colour_data.illuminant_sd("D65")[1], np.asarray(colour.SDS_ILLUMINANTS["D65"].values, float))


@pytest.mark.parametrize("key", ["illuminants/3/values", "colourchecker/BabelColor Average/23/wl", "cat/CAT16",
                                 "cameras/1/values"])
def test_a_snapshot_without_one_of_its_tables_is_not_whole(fresh, key):
    t = dict(colour_data.tables())
    assert colour_data._whole(t)
    del t[key]
    assert not colour_data._whole(t)


def test_a_folder_that_cannot_be_written_leaves_the_tables_in_memory(fresh, monkeypatch):
    blocked = fresh / "file"
    blocked.write_text("a file where the folder should be")
    monkeypatch.setenv("SPECTRACAM_TABLES", str(blocked / "tables"))
    assert _same(colour_data.cmfs_1931()[0], np.arange(360.0, 831.0))
    assert blocked.read_text() == "a file where the folder should be"


def test_no_place_for_the_snapshot_leaves_the_tables_in_memory(fresh, monkeypatch):
    """No version metadata to name the file by (or no home folder): the run goes on, nothing is written."""
    def nowhere():
        raise RuntimeError("Could not determine home directory.")

    monkeypatch.setattr(colour_data, "snapshot_path", nowhere)
    assert _same(colour_data.robertson_table()[0], np.asarray(colour_data._build()["robertson/table"][0]))
    assert not list(fresh.iterdir())


def test_the_folder_follows_xdg_then_home(monkeypatch, tmp_path):
    monkeypatch.delenv("SPECTRACAM_TABLES", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert colour_data.snapshot_path().parent == tmp_path / "spectracam" / "tables"
    monkeypatch.setenv("XDG_CACHE_HOME", "relative/ignored")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert colour_data.snapshot_path().parent == tmp_path / "home" / ".cache" / "spectracam" / "tables"


SMALL_SCENE = """
name = "tiny"
[illuminant]
type = "cie"
name = "D65"
[image]
width = 64
height = 48
"""

WATCH = """
import runpy, sys
sys.argv = ["spectracam"] + sys.argv[1:]
try:
    runpy.run_module("spectracam", run_name="__main__")
finally:
    print("COLOUR IMPORTED" if "colour" in sys.modules else "COLOUR NOT IMPORTED", file=sys.stderr)
"""


def test_simulate_does_not_import_colour_science_once_the_snapshot_is_made(tmp_path):
    """The point of the snapshot (issue 38): 1.4–2.4 s of import saved on every run."""
    (tmp_path / "s.toml").write_text(SMALL_SCENE)
    (tmp_path / "watch.py").write_text(WATCH)
    env = {**os.environ, "SPECTRACAM_TABLES": str(tmp_path / "tables"), "PYTHONPATH": str(ROOT)}
    runs = []
    for out in ("a", "b"):
        r = subprocess.run([sys.executable, "watch.py", "simulate", "s.toml", "-o", out, "--renderer", "analytic"],
                           cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
        assert r.returncode == 0, r.stderr
        runs.append(r.stderr.strip().splitlines()[-1])
    assert runs == ["COLOUR IMPORTED", "COLOUR NOT IMPORTED"]   # the first run makes the snapshot
    assert (tmp_path / "a" / "report.json").read_bytes() == (tmp_path / "b" / "report.json").read_bytes()
