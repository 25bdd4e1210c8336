import subprocess
import sys

import numpy as np

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
    assert r.returncode == 2 and "cannot be read" in r.stderr and "Traceback" not in r.stderr
