import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from spectracam.io.exr import read_radiance_exr

SMALL_SCENE = """
name = "tiny"
[illuminant]
type = "blackbody"
temperature_K = 4000
[image]
width = 64
height = 48
"""


def run(*args):
    return subprocess.run([sys.executable, "-m", "spectracam", *args], capture_output=True, text=True, timeout=300)


def test_render_writes_spectral_exr_and_inspect_reads_it(tmp_path):
    scene = tmp_path / "tiny.toml"
    scene.write_text(SMALL_SCENE)
    r = run("render", str(scene), "-o", str(tmp_path / "out"))
    assert r.returncode == 0, r.stderr
    assert "Mitsuba variant" in r.stderr and "wrote" in r.stderr
    cube, attrs = read_radiance_exr(tmp_path / "out" / "radiance.exr")
    assert cube.shape == (48, 64, 30) and attrs["spectracamRenderer"] == "mitsuba"
    q = run("render", str(scene), "-o", str(tmp_path / "an"), "--renderer", "analytic", "--quiet")
    assert q.returncode == 0 and q.stderr == ""
    analytic, _ = read_radiance_exr(tmp_path / "an" / "radiance.exr")
    assert np.abs(cube.radiance.mean() / analytic.radiance.mean() - 1) < 0.005
    i = run("inspect", str(tmp_path / "out" / "radiance.exr"))
    assert i.returncode == 0 and "S0.695,000000nm" in i.stdout and "spectracamSeed: 0" in i.stdout


def test_bad_scene_is_one_line_exit_2_and_no_output(tmp_path):
    scene = tmp_path / "bad.toml"
    scene.write_text(SMALL_SCENE.replace("4000", "100"))
    out = tmp_path / "out"
    r = run("render", str(scene), "-o", str(out))
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "illuminant.temperature_K = 100" in lines[0] and "between 1000 and 40000" in lines[0]
    assert not out.exists()


def test_missing_scene_file_is_clear(tmp_path):
    r = run("render", str(tmp_path / "nope.toml"), "-o", str(tmp_path / "o"))
    assert r.returncode == 2 and "no such file" in r.stderr and "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1


# -- shipped files by name, from any directory (issue 23) ---------------------------------------------------------

def test_shipped_files_are_found_by_name(tmp_path, monkeypatch):
    from spectracam.experiments.options import resolve_shipped
    from spectracam.pipeline.scene_file import shipped_dir
    from spectracam.core.errors import ConfigError

    monkeypatch.chdir(tmp_path)   # outside the checkout: scenes/d65.toml is no path here
    root = shipped_dir()
    for given, want in (("d65", "d65.toml"), ("d65.toml", "d65.toml"), ("scenes/d65.toml", "d65.toml"),
                        ("blackbody_3000K", "blackbody_3000K.toml")):
        assert resolve_shipped(given, "scene file") == root / want
    for given in ("cfa_cutoffs", "cfa_cutoffs.toml", "sweeps/cfa_cutoffs", "scenes/sweeps/cfa_cutoffs.toml"):
        assert resolve_shipped(given, "sweep file") == root / "sweeps" / "cfa_cutoffs.toml"
    assert resolve_shipped("paper", "experiment file") == root / "paper.toml"
    assert resolve_shipped("design.toml", "design file") == root / "design.toml"
    own = tmp_path / "d65.toml"   # a path that exists wins over a shipped name
    own.write_text(SMALL_SCENE)
    assert resolve_shipped(own, "scene file") == own
    for given, what in (("nosuch", "scene file"), ("d65", "sweep file"), ("cfa_cutoffs", "scene file"),
                        ("paper", "scene file")):
        with pytest.raises(ConfigError) as e:
            resolve_shipped(given, what)
        msg = str(e.value)
        assert "no such file" in msg and "\n" not in msg
        listed = msg.split("(shipped: ")[1]
        assert ("cfa_cutoffs" in listed) == (what == "sweep file") and ("d65" in listed) == (what == "scene file")


def test_shipped_scene_by_name_from_another_directory(tmp_path):
    r = subprocess.run([sys.executable, "-m", "spectracam", "render", "d65", "-o", "out", "--renderer", "analytic",
                        "--set", "image.width=64", "--set", "image.height=48", "--quiet"], cwd=tmp_path,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0 and r.stderr == "", r.stderr
    cube, attrs = read_radiance_exr(tmp_path / "out" / "radiance.exr")
    assert cube.shape == (48, 64, 30) and "D65" in attrs["spectracamScene"]
    bad = subprocess.run([sys.executable, "-m", "spectracam", "simulate", "nosuch", "-o", "o"], cwd=tmp_path,
                         capture_output=True, text=True, timeout=300)
    lines = bad.stderr.strip().splitlines()
    assert bad.returncode == 2 and len(lines) == 1 and "nosuch" in lines[0] and "d65" in lines[0]
    assert not (tmp_path / "o").exists()


def test_help_texts_are_whole():
    from click.testing import CliRunner

    from spectracam.cli import main

    top = run("--help")
    commands = top.stdout.split("Commands:")[1]
    assert top.returncode == 0 and "..." not in commands and "Shipped files" in commands
    names = main.list_commands(None)
    assert {"render", "simulate", "sweep", "design", "view", "spatial", "motion"} <= set(names)
    runner = CliRunner()
    for name in names:
        cmd = main.get_command(None, name)
        assert cmd.short_help and len(cmd.short_help) <= 62 and not cmd.short_help.endswith("..."), name
        assert cmd.short_help in top.stdout.replace("\n ", " ") or cmd.short_help[:40] in top.stdout, name
        r = runner.invoke(cmd, ["--help"], prog_name=f"spectracam {name}", terminal_width=120)
        assert r.exit_code == 0 and "..." not in r.output, (name, r.output)


# -- progress bars: on a terminal, not in a pipe ----------------------------------------------------------------

def _pty_stderr(args, timeout=300):
    """Run spectracam with stderr on a fresh pseudo-terminal (size 0 × 0, as `script` from a pipe gives) and
    return what it drew there.  TQDM_MININTERVAL=0: every step is drawn, however fast the machine (tqdm
    otherwise redraws at most every 0.1 s, and a small render can finish in two redraws)."""
    import os
    import select

    master, slave = os.openpty()
    p = subprocess.Popen([sys.executable, "-m", "spectracam", *args], stdout=subprocess.DEVNULL, stderr=slave,
                         stdin=subprocess.DEVNULL, env={**os.environ, "TQDM_MININTERVAL": "0"})
    os.close(slave)
    out = b""
    while True:
        ready, _, _ = select.select([master], [], [], timeout)
        if not ready:
            p.kill()
            break
        try:
            chunk = os.read(master, 65536)
        except OSError:   # EIO: the child closed its end
            break
        if not chunk:
            break
        out += chunk
    p.wait(timeout=timeout)
    os.close(master)
    return p.returncode, out.decode(errors="replace")


def test_progress_bar_on_a_terminal_and_none_in_a_pipe(tmp_path):
    import re

    scene = tmp_path / "tiny.toml"
    scene.write_text(SMALL_SCENE)
    rc, drawn = _pty_stderr(["render", str(scene), "-o", str(tmp_path / "tty")])
    assert rc == 0, drawn
    states = {int(n) for n in re.findall(r"render bands:\s+\d+%\|[^|]*\|\s*(\d+)/30", drawn)}
    assert len(states) > 2 and min(states) == 0, drawn   # drawn from the start, and it moved
    assert "wrote" in drawn
    piped = run("render", str(scene), "-o", str(tmp_path / "pipe"))
    assert piped.returncode == 0 and "render bands" not in piped.stderr and "\r" not in piped.stderr
    rc, drawn = _pty_stderr(["render", str(scene), "-o", str(tmp_path / "quiet"), "--quiet"])
    assert rc == 0 and drawn == "", drawn


# -- --view on every command that writes a directory, and `spectracam view DIR` ---------------------------------

#: Every command that writes an output directory (issue 23): each takes --view.
WRITERS = ("render", "capture", "score", "simulate", "paper", "architectures", "emva", "validate", "consistency",
           "sweep", "plot-sweep", "design", "spatial", "motion")

FAKE_VIEW = """
import json, sys
from pathlib import Path
import spectracam.view

def write_view(directory, log=None):
    directory = Path(directory)
    seen = sorted(p.name for p in directory.iterdir())
    page = directory / "index.html"
    page.write_text(json.dumps(seen))
    if log:
        log(f"wrote {page}")
    return page

spectracam.view.write_view = write_view
from spectracam.cli import main
sys.argv = ["spectracam", *sys.argv[1:]]
main()
"""


def test_view_flag_on_every_writing_command():
    from spectracam.cli import main

    for name in WRITERS:
        params = {p.name for p in main.get_command(None, name).params}
        assert "view" in params and "out_dir" in params, name


def test_view_flag_writes_the_page_after_the_outputs(tmp_path):
    import json

    fake = tmp_path / "fake_view.py"
    fake.write_text(FAKE_VIEW)
    scene = tmp_path / "tiny.toml"
    scene.write_text(SMALL_SCENE)

    def cli(*args):
        return subprocess.run([sys.executable, str(fake), *args], capture_output=True, text=True, timeout=300,
                              cwd=tmp_path)

    r = cli("simulate", str(scene), "-o", "out", "--renderer", "analytic", "--view")
    assert r.returncode == 0, r.stderr
    seen = json.loads((tmp_path / "out" / "index.html").read_text())   # what the page saw: every output, final names
    assert {"radiance.exr", "raw.exr", "raw.dng", "report.json", "rendered.png"} <= set(seen)
    assert not [s for s in seen if s.startswith(".tmp")]
    assert r.stderr.strip().splitlines()[-1] == f"wrote {Path('out') / 'index.html'}"
    q = cli("render", str(scene), "-o", "q", "--renderer", "analytic", "--view", "--quiet")
    assert q.returncode == 0 and q.stderr == "" and (tmp_path / "q" / "index.html").exists()
    no = cli("render", str(scene), "-o", "no", "--renderer", "analytic")
    assert no.returncode == 0 and not (tmp_path / "no" / "index.html").exists()
    bad = cli("render", str(scene), "-o", "bad", "--renderer", "analytic", "--view", "--set", "image.width=0")
    assert bad.returncode == 2 and not (tmp_path / "bad").exists()   # a refused command writes no page either
    v = cli("view", "out")
    assert v.returncode == 0 and v.stdout.strip() == str(Path("out") / "index.html")
    for missing in ("nosuch", str(scene)):   # not a directory
        m = cli("view", missing)
        assert m.returncode == 2 and len(m.stderr.strip().splitlines()) == 1, m.stderr


# -- the sweep's tables open in pandas ------------------------------------------------------------------------

SWEEP = ('base_scene = "tiny.toml"\nrenderer = "analytic"\ntrials = 2\nseed = 3\n'
         'metrics = ["delta_e_mean", "snr_combined_db", "capture_time_ms"]\n[axes]\n'
         '"sensor.read_noise_e" = [10, 20, 30]\n"capture.design" = ["cfa/single", "fsc/optimal"]\n')


def test_pandas_reads_the_sweep_tables_as_the_sweep_reports_them(tmp_path):
    import json

    pd = pytest.importorskip("pandas")
    (tmp_path / "tiny.toml").write_text(SMALL_SCENE)
    (tmp_path / "sw.toml").write_text(SWEEP)
    r = run("sweep", str(tmp_path / "sw.toml"), "-o", str(tmp_path / "out"), "--serial", "--quiet")
    assert r.returncode == 0, r.stderr
    reported = sorted((json.loads(line) for line in (tmp_path / "out" / "results.jsonl").read_text().splitlines()),
                      key=lambda row: (row["cell"], row["trial"]))
    frame = pd.read_parquet(tmp_path / "out" / "results.parquet")
    assert len(frame) == len(reported) == 3 * 2 * 2
    assert list(frame.columns) == list(dict.fromkeys(k for row in reported for k in row))
    for row, (_, got) in zip(reported, frame.iterrows()):
        for k, v in row.items():
            assert got[k] == v or (v is None and pd.isna(got[k])), (k, v, got[k])
    assert frame["snr_combined_db"].dtype.kind == "f" and frame["cell"].dtype.kind == "i"
    assert sorted(frame["axis:capture.design"].unique()) == ["cfa/single", "fsc/optimal"]
    csv = pd.read_csv(tmp_path / "out" / "results.csv")
    assert list(csv.columns) == list(frame.columns)
    np.testing.assert_allclose(csv["delta_e_mean"], frame["delta_e_mean"], rtol=1e-12)
