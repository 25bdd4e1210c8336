"""Faults a new user hits (issue 34, item 7): each refused in one line (exit 2), or accepted as meant — never a
traceback, a hang or a silently wrong result."""
import json
import os
import struct
import subprocess
import sys
import zlib
from pathlib import Path

import numpy as np
import pytest

from spectracam.core.errors import ConfigError, SpectracamError

ROOT = Path(__file__).resolve().parent.parent
CLI = [sys.executable, "-m", "spectracam"]
SMALL = ["--set", "image.width=64", "--set", "image.height=48"]
SPD = "wavelength_nm,value\n380,1\n500,2\n780,1.5\n"


def run(*args, cwd=None, timeout=120):
    return subprocess.run([*CLI, *map(str, args)], capture_output=True, text=True, cwd=cwd, timeout=timeout)


def one_line(r, code, *parts):
    assert r.returncode == code, (r.returncode, r.stderr)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("spectracam: error:"), r.stderr
    assert "Traceback" not in r.stderr
    for p in parts:
        assert p in lines[0], (p, lines[0])
    return lines[0]


# -- 1. --set illuminant.file switches the illuminant -------------------------------------------------------

def test_set_illuminant_file_drops_the_other_types_keys_the_user_did_not_set():
    from spectracam.pipeline.overrides import apply_overrides

    cie = {"illuminant": {"type": "cie", "name": "D65", "white_luminance_cd_m2": 50.0}}
    assert apply_overrides(cie, ["illuminant.file=spd.csv"]) == \
        {"illuminant": {"type": "measured", "white_luminance_cd_m2": 50.0, "file": "spd.csv"}}
    bb = {"illuminant": {"type": "blackbody", "temperature_K": 3000}}
    assert apply_overrides(bb, ["illuminant.file=spd.csv"])["illuminant"] == {"type": "measured", "file": "spd.csv"}
    # a key the user set in the same overrides stays, before or after the switch
    got = apply_overrides(bb, ['illuminant.name="my lamp"', "illuminant.file=spd.csv"])["illuminant"]
    assert got == {"type": "measured", "name": "my lamp", "file": "spd.csv"}
    got = apply_overrides(bb, ["illuminant.type=cie", "illuminant.name=A"])["illuminant"]
    assert got == {"type": "cie", "name": "A"}
    got = apply_overrides(bb, ["illuminant.temperature_K=4000", "illuminant.type=blackbody"])["illuminant"]
    assert got == {"type": "blackbody", "temperature_K": 4000}


@pytest.mark.parametrize("scene", ["d65.toml", "blackbody_5000K.toml"])
def test_set_illuminant_file_works_on_a_cie_or_blackbody_scene(tmp_path, scene):
    from spectracam.pipeline.scene_file import load_scene

    (tmp_path / "spd.csv").write_text(SPD)
    s = load_scene(ROOT / "scenes" / scene, [f"illuminant.file={tmp_path / 'spd.csv'}"])
    assert s.illuminant.kind == "measured" and s.illuminant.name == "spd.csv"
    assert s.illuminant.values == (1.0, 2.0, 1.5) and s.illuminant.white_luminance_cd_m2 == 100.0


def test_set_illuminant_file_on_the_command_line(tmp_path):
    (tmp_path / "spd.csv").write_text(SPD)
    r = run("render", "d65", "-o", "out", "--renderer", "analytic", "--quiet", *SMALL, "--set", "illuminant.file=spd.csv",
            cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    from spectracam.io.exr import read_exr_header

    scene = json.loads(read_exr_header(tmp_path / "out" / "radiance.exr")["spectracamScene"])
    assert scene["illuminant"]["type"] == "measured" and scene["illuminant"]["values"] == [1.0, 2.0, 1.5]
    # a type the user set that contradicts the file: one line naming both
    r = run("render", "d65", "-o", "out2", "--renderer", "analytic", *SMALL, "--set", "illuminant.type=cie",
            "--set", "illuminant.file=spd.csv", cwd=tmp_path)
    one_line(r, 2, "illuminant.type = 'cie'", "illuminant.file")


# -- 2. photographs: too large, floating point --------------------------------------------------------------

def _png_header_only(path: Path, width: int, height: int) -> None:
    """A PNG whose header declares width × height pixels (and holds almost no data)."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"\0" * 16))
                     + chunk(b"IEND", b""))


def _photo_scene(d: Path, photo: str) -> Path:
    p = d / "photo_scene.toml"
    p.write_text(f'[target]\nkind = "photo"\nphoto = "file:{photo}"\nlibrary = "cfi99"\nsupersampling = 1\n'
                 '[illuminant]\ntype = "cie"\nname = "D65"\n[image]\nwidth = 64\nheight = 48\n')
    return p


@pytest.mark.parametrize("size", [(20000, 20000), (10000, 9000)])
def test_a_photo_too_large_is_refused_in_one_line_naming_the_limit(tmp_path, size):
    from spectracam.scene.target import MAX_PHOTO_PIXELS, _read_photo

    _png_header_only(tmp_path / "huge.png", *size)
    with pytest.raises(SpectracamError, match=f"larger than the {MAX_PHOTO_PIXELS} px"):
        _read_photo(tmp_path / "huge.png")
    if size[0] == 20000:   # past PIL's own limit: a DecompressionBombError traceback before
        r = run("render", _photo_scene(tmp_path, "huge.png"), "-o", "out", "--renderer", "analytic", cwd=tmp_path)
        one_line(r, 2, "target.photo", "huge.png", "400 Mpx", str(MAX_PHOTO_PIXELS))
        assert not (tmp_path / "out").exists()


def test_a_float_tiff_is_read_as_linear_light(tmp_path):
    import tifffile
    from PIL import Image

    from spectracam.scene.target import _read_photo

    linear = np.zeros((40, 60, 3), np.float32)
    linear[..., 0], linear[..., 1], linear[..., 2] = 0.8, 0.4, 0.1
    linear[:20, :30] = 0.02
    tifffile.imwrite(tmp_path / "rgb.tif", linear, photometric="rgb")                                     # PIL cannot open it
    tifffile.imwrite(tmp_path / "planar.tif", np.moveaxis(linear, -1, 0), photometric="rgb", planarconfig="separate")
    Image.fromarray(linear[..., 1], mode="F").save(tmp_path / "grey.tif")                # PIL's mode F
    for name in ("rgb.tif", "planar.tif"):
        np.testing.assert_allclose(_read_photo(tmp_path / name), linear, rtol=1e-6)
    grey = _read_photo(tmp_path / "grey.tif")   # it was clipped to black (0) by convert("RGB")
    np.testing.assert_allclose(grey, np.repeat(linear[..., 1:2], 3, axis=2), rtol=1e-6)
    # the same colours as a 16-bit sRGB-encoded PNG give the same linear light
    enc = np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * linear ** (1 / 2.4) - 0.055)
    png16 = np.round(enc * 65535).astype(np.uint16)
    Image.fromarray(png16[..., 0]).save(tmp_path / "r16.png")
    np.testing.assert_allclose(_read_photo(tmp_path / "r16.png")[..., 0], linear[..., 0], atol=1e-4)


def test_a_float_tiff_out_of_range_is_refused(tmp_path):
    import tifffile

    from spectracam.scene.target import _read_photo

    tifffile.imwrite(tmp_path / "hdr.tif", np.full((8, 8, 3), 3.0, np.float32), photometric="rgb")
    with pytest.raises(SpectracamError, match="linear light 0–1.*spans 3–3"):
        _read_photo(tmp_path / "hdr.tif")
    tifffile.imwrite(tmp_path / "nan.tif", np.full((8, 8, 3), np.nan, np.float32), photometric="rgb")
    with pytest.raises(SpectracamError, match="NaN"):
        _read_photo(tmp_path / "nan.tif")


def test_a_float_tiff_photo_renders_its_colours_not_black(tmp_path):
    import tifffile

    tifffile.imwrite(tmp_path / "grey.tif", np.full((48, 64, 3), 0.5, np.float32), photometric="rgb")
    r = run("render", _photo_scene(tmp_path, "grey.tif"), "-o", "out", "--renderer", "analytic", "--quiet",
            cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    from spectracam.io.exr import read_exr

    ch, _ = read_exr(tmp_path / "out" / "radiance.exr")
    cube = np.stack([v for k, v in sorted(ch.items()) if k.startswith("S0.")], -1)
    # a 50 % grey under 100 cd/m² D65: about half the white diffuser's radiance, nowhere near black
    from spectracam.scene.illuminant import IlluminantSpec, white_diffuser_radiance
    from spectracam.pipeline.scene_file import _default_grid

    white = white_diffuser_radiance(IlluminantSpec("cie", None, "D65", 100.0), _default_grid())
    ratio = float(cube.mean() / white.mean())
    assert 0.35 < ratio < 0.65, ratio


# -- 3. a number where spatial wants a list -----------------------------------------------------------------

def test_spatial_olpf_separations_given_a_number_is_one_line(tmp_path):
    r = run("spatial", "-o", tmp_path / "o", "--quick", "--renderer", "analytic", "--set", "olpf_separations_px=1")
    one_line(r, 2, "olpf_separations_px = 1", "must be a non-empty list", "e.g. [0.0, 1.0]")
    from spectracam.experiments.spatial.experiment import load_spatial

    for field in ("pixel_pitches_um", "f_numbers", "misregistrations_px"):
        with pytest.raises(ConfigError, match=f"{field} = 2: must be a non-empty list"):
            load_spatial([f"{field}=2"], quick=True)


# -- 4. view on a report.json that is not an object ---------------------------------------------------------

def test_view_of_a_report_json_that_is_a_list_is_one_line(tmp_path):
    (tmp_path / "d").mkdir()
    (tmp_path / "d" / "report.json").write_text("[1, 2, 3]")
    r = run("view", tmp_path / "d")
    one_line(r, 2, "report.json", "not a spectracam report", "holds an array")
    assert not (tmp_path / "d" / "index.html").exists()


# -- 5. a radiance EXR whose recorded scene is not a table ----------------------------------------------------

@pytest.mark.parametrize("value", ["[1, 2, 3]", "3", '"text"', "null"])
def test_an_exr_whose_scene_attribute_is_not_an_object_is_one_line(tmp_path, value):
    from spectracam.io.exr import read_radiance_exr, spectral_channel_name, write_exr

    channels = {spectral_channel_name(w): np.full((8, 8), 0.01, np.float32) for w in np.arange(405.0, 700.0, 10.0)}
    write_exr(tmp_path / "bad.exr", channels, {"spectralLayoutVersion": "1.0", "emissiveUnits": "W.m^-2.sr^-1",
                                               "spectracamKind": "radiance", "spectracamScene": value})
    with pytest.raises(SpectracamError, match="attribute spectracamScene .* is damaged"):
        read_radiance_exr(tmp_path / "bad.exr")
    if value == "[1, 2, 3]":
        r = run("capture", tmp_path / "bad.exr", "-o", tmp_path / "out")
        one_line(r, 2, "spectracamScene = '[1, 2, 3]'", "a JSON object of tables is expected", "an array")
        assert not (tmp_path / "out").exists()


# -- 6. plot-sweep on a sweep.json naming an axis the table lacks -------------------------------------------

def test_plot_sweep_with_an_axis_the_table_lacks_is_one_line(tmp_path):
    import pyarrow as pa
    import pyarrow.parquet as pq

    d = tmp_path / "sw"
    d.mkdir()
    rows = [{"cell": i, "trial": 0, "axis:sensor.read_noise_e": v, "delta_e_mean": 1.0 + i} for i, v in
            enumerate([10, 20, 30])]
    pq.write_table(pa.Table.from_pylist(rows), d / "results.parquet")
    meta = {"axes": [["optics.f_number", [1.4, 2.0]]], "metrics": ["delta_e_mean"], "trials": 1}
    (d / "sweep.json").write_text(json.dumps(meta))
    r = run("plot-sweep", d)
    one_line(r, 2, "names the axis 'optics.f_number'", "its axes: sensor.read_noise_e")
    meta["axes"] = [["sensor.read_noise_e", [10, 20, 30]]]
    meta["metrics"] = ["snr_combined_db"]
    (d / "sweep.json").write_text(json.dumps(meta))
    from spectracam.experiments.sweep.plot import load_results

    with pytest.raises(SpectracamError, match="names the metric 'snr_combined_db'"):
        load_results(d)
    meta["axes"] = [1, 2]
    (d / "sweep.json").write_text(json.dumps(meta))
    with pytest.raises(SpectracamError, match="damaged"):
        load_results(d)
    assert not (d / "plots").exists()


# -- 7. a long sweep says how far it is and how long it will take -------------------------------------------

class _Clock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


def test_a_counter_says_cells_done_rate_and_time_left_when_no_bar_is_drawn():
    from spectracam.core.progress import Counter

    said = []
    c = Counter(99_999, desc="sweep cells", unit="cell", log=said.append)
    assert c.bar.disable   # pytest's stderr is no terminal: lines instead of a bar
    c._clock = clock = _Clock()
    c.t0 = c.last = 0.0
    clock.t = 5.0   # the first cell pays for compiling: not counted in the rate
    c.update()
    assert said == []
    for _ in range(100):
        clock.t += 0.1
        c.update()
    import re

    assert re.fullmatch(r"sweep cells: 999\d\d cells to go, estimated 2 h 46 min \(10 cells/s\)", said[0]), said
    while clock.t < 70:
        clock.t += 0.1
        c.update()
    assert said[1].startswith("sweep cells: ") and " of 99999 cells, 10 cells/s, about 2 h " in said[1], said
    assert said[-1].endswith(" left") and len(said) == 3, said   # one line every 30 s
    c.close()
    quiet = []
    q = Counter(10, desc="x", unit="cell", log=quiet.append, progress=False, estimate_after_n=1, announce_over_s=0)
    for _ in range(10):
        q.update()
    assert quiet == []   # --quiet: nothing at all


def test_a_sweep_logs_its_estimate_and_progress(tmp_path, monkeypatch):
    import spectracam.core.progress as progress
    from spectracam.experiments.sweep.experiment import load_sweep, run_sweep

    class Eager(progress.Counter):   # the thresholds of a long sweep, reached by a short one
        def __init__(self, *a, **kw):
            super().__init__(*a, **{**kw, "every_s": 0.0, "estimate_after_n": 1, "announce_over_s": 0.0})

    monkeypatch.setattr(progress, "Counter", Eager)
    (tmp_path / "s.toml").write_text("[image]\nwidth = 64\nheight = 48\n")
    (tmp_path / "sw.toml").write_text('base_scene = "s.toml"\nrenderer = "analytic"\nmetrics = ["delta_e_mean"]\n'
                                      '[axes]\n"sensor.read_noise_e" = [10, 20, 30, 40]\n')
    said = []
    sweep = load_sweep(tmp_path / "sw.toml", log=said.append)
    run_sweep(sweep, tmp_path / "out", serial=True, log=said.append)
    text = "\n".join(said)
    assert "validating cells: 2 cells to go, estimated" in text, text
    assert "sweep cells: 2 cells to go, estimated" in text and "sweep cells: 3 of 4 cells" in text, text
    assert "about" in text and "left" in text


# -- 8. a FIFO given as an input file -------------------------------------------------------------------------

FIFO_CASES = {
    "scene TOML": (["simulate", "fifo.toml", "-o", "out"], "scene file = 'fifo.toml'"),
    "radiance EXR": (["capture", "fifo.exr", "-o", "out"], "file = 'fifo.exr'"),
    "raw EXR": (["score", "fifo.exr", "-o", "out"], "file = 'fifo.exr'"),
    "SPD CSV": (["render", "d65", "-o", "out", "--set", "illuminant.file=fifo.csv"], "illuminant.file = "),
    "camera CSV": (["render", "d65", "-o", "out", "--set", 'filters.camera_file="fifo.csv"'], "fifo.csv"),
    "reflectances": (["simulate", "d65", "-o", "out", "--set", "processing.held_out=file:fifo.csv"], "fifo.csv"),
    "sweep file": (["sweep", "fifo.toml", "-o", "out"], "sweep file = 'fifo.toml'"),
    "design file": (["design", "fifo.toml", "-o", "out"], "design file = 'fifo.toml'"),
    "photo": (["render", "photo_scene.toml", "-o", "out"], "fifo.png"),
}


@pytest.mark.parametrize("case", list(FIFO_CASES))
def test_a_fifo_as_an_input_file_is_refused_not_waited_on(tmp_path, case):
    args, part = FIFO_CASES[case]
    for name in ("fifo.toml", "fifo.exr", "fifo.csv", "fifo.png"):
        os.mkfifo(tmp_path / name)
    _photo_scene(tmp_path, "fifo.png")
    r = run(*args, cwd=tmp_path, timeout=60)   # before the fix: blocked for ever
    one_line(r, 2, part, "is a FIFO (named pipe), not a regular file")
    assert not (tmp_path / "out").exists()


def test_regular_file_refuses_every_kind_of_non_file(tmp_path):
    from spectracam.core.files import regular_file

    os.mkfifo(tmp_path / "p")
    with pytest.raises(ConfigError, match="is a FIFO"):
        regular_file(tmp_path / "p", "scene file")
    with pytest.raises(ConfigError, match="is a character device"):
        regular_file("/dev/zero", "file")
    with pytest.raises(ConfigError, match="is a directory"):
        regular_file(tmp_path, "file")
    (tmp_path / "f").write_text("x")
    os.symlink(tmp_path / "f", tmp_path / "link")
    assert regular_file(tmp_path / "link", "file") == tmp_path / "link"
    assert regular_file(tmp_path / "missing", "file") == tmp_path / "missing"   # the caller says "no such file"


def test_view_and_plot_sweep_skip_or_refuse_a_fifo(tmp_path):
    d = tmp_path / "sw"
    d.mkdir()
    (d / "results.parquet").write_bytes(b"")
    os.mkfifo(d / "sweep.json")
    one_line(run("plot-sweep", d, timeout=60), 2, "sweep.json", "is a FIFO")
    (tmp_path / "v").mkdir()
    os.mkfifo(tmp_path / "v" / "report.json")   # never opened: not a file the page reads
    one_line(run("view", tmp_path / "v", timeout=60), 2, "holds nothing spectracam wrote")


def test_a_fifo_in_place_of_a_sweeps_journal_is_refused(tmp_path):
    (tmp_path / "s.toml").write_text("[image]\nwidth = 64\nheight = 48\n")
    (tmp_path / "sw.toml").write_text('base_scene = "s.toml"\nrenderer = "analytic"\nmetrics = ["delta_e_mean"]\n'
                                      '[axes]\n"sensor.read_noise_e" = [10, 20]\n')
    (tmp_path / "out").mkdir()
    os.mkfifo(tmp_path / "out" / "results.jsonl")
    one_line(run("sweep", "sw.toml", "-o", "out", "--serial", "--quiet", cwd=tmp_path, timeout=60), 2, "results.jsonl",
             "is a FIFO")


# -- 9. a local scene file with a shipped scene's name ------------------------------------------------------

def test_a_bare_name_matching_a_local_and_a_shipped_scene_is_ambiguous(tmp_path, monkeypatch):
    from spectracam.experiments.options import resolve_shipped, shipped_files

    monkeypatch.chdir(tmp_path)
    shipped = shipped_files("scene file")["d65"]
    assert resolve_shipped("d65") == shipped   # no local file: the shipped scene
    (tmp_path / "d65.toml").write_text("[image]\nwidth = 64\nheight = 48\n")
    with pytest.raises(ConfigError, match=r"ambiguous: names both d65.toml here and the shipped scene d65 .*"
                                          r"write ./d65.toml for yours or scenes/d65 for the shipped one"):
        resolve_shipped("d65")
    assert resolve_shipped("./d65.toml") == Path("./d65.toml")   # a path is a file
    assert resolve_shipped("d65.toml") == Path("d65.toml")
    assert resolve_shipped("scenes/d65") == shipped              # the shipped one, said so
    monkeypatch.chdir(shipped.parent)                            # the shipped directory itself: one file
    assert resolve_shipped("d65").resolve() == shipped.resolve()


def test_the_ambiguous_scene_name_on_the_command_line(tmp_path):
    (tmp_path / "d65.toml").write_text("[image]\nwidth = 64\nheight = 48\n")
    r = run("render", "d65", "-o", "out", "--renderer", "analytic", cwd=tmp_path)
    one_line(r, 2, "scene file = 'd65'", "ambiguous", "d65.toml here", "shipped scene d65")
    assert not (tmp_path / "out").exists()


# -- 10. experiment = "paper" in a design file ----------------------------------------------------------------

def test_a_design_files_experiment_takes_names_as_the_flag_does(tmp_path):
    from spectracam.experiments.options import resolve_shipped
    from spectracam.experiments.design.run import experiment_path

    flag = resolve_shipped("paper", "experiment file")
    for value in ("paper", "paper.toml", "scenes/paper", "scenes/paper.toml"):
        assert experiment_path(value, tmp_path) == flag, value
    (tmp_path / "mine.toml").write_text("x = 1\n")
    assert experiment_path("mine.toml", tmp_path) == tmp_path / "mine.toml"   # relative to the design file
    with pytest.raises(ConfigError, match="experiment = 'nosuch'.*not the name of a shipped experiment "
                                          r"\(shipped: paper\)"):
        experiment_path("nosuch", tmp_path)
    with pytest.raises(ConfigError, match="experiment = 'd65'"):   # a scene is no experiment, as for the flag
        experiment_path("d65", tmp_path)


def test_a_design_file_with_experiment_paper_sets_up(tmp_path):
    from spectracam.experiments.design.run import setup
    from spectracam.experiments.design.spec import load_design

    (tmp_path / "d.toml").write_text('experiment = "paper"\nlights = [5000]\ndesigns = ["cfa/single"]\n')
    spec, base_dir = load_design(tmp_path / "d.toml", quick=True)
    s = setup(spec, base_dir)
    assert len(s.scenes) == 2 and s.level_cd_m2 > 0   # --quick's two lights
