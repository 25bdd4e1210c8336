"""Issue 19: reflectance libraries and the conversion scored on colours it was not fitted on."""
import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

from spectracam.evaluation import heldout
from spectracam.scene import reflectances
from spectracam.camera import FilterSpec
from spectracam.core.errors import SpectracamError
from spectracam.scene.reference import ChartReference
from spectracam.pipeline.scene_file import load_scene, resolve_curve_files
from spectracam.evaluation.score import conversion_matrix
from spectracam.core.spectra import cie_1931_cmfs

SCENE = load_scene("scenes/d65.toml", ["image.width=160", "image.height=120"])

COUNTS = {"cfi99": 99, "rawtoaces190": 190, "colorchecker24": 24, "colorchecker24_ohta": 24, "iso17321": 24,
          "tcs14": 14, "vs15": 15, "munsell1269": 1269, "tm30_4880": 4880, "capbone100k": 114120}


@pytest.mark.parametrize("name", reflectances.LIBRARIES)
def test_every_library_loads_with_its_published_sample_count(name):
    if name in reflectances.LUXPY_LIBRARIES:
        if importlib.util.find_spec("luxpy") is None:   # read, never imported (its import needs matplotlib)
            pytest.skip("luxpy (GPLv3) is an optional dependency: pip install luxpy")
    s = reflectances.load(name)
    assert len(s) == COUNTS[name] and s.values.shape == (len(s), s.wavelengths_nm.size)
    assert s.values.min() >= 0 and s.values.max() <= reflectances.MAX_REFLECTANCE
    s.check_covers(400.0, 700.0)                                      # the default scene's range


def test_the_chart_as_a_library_reads_the_training_error():
    """The BabelColor chart through the held-out path (its own band averages, 20 points a band, and one
    matrix product for XYZ) gives the chart's own conversion error (200 points a band) — the two paths agree."""
    ref = ChartReference.of(SCENE)
    M = conversion_matrix(ref, SCENE.camera, SCENE.processing)
    e = heldout.conversion_errors(heldout.held_out_colours("colorchecker24", SCENE.illuminant, SCENE.grid),
                                  SCENE.camera, SCENE.grid, M, SCENE.processing)
    from spectracam.pipeline import capture, render, score
    cube = render(SCENE, "analytic")
    s = score(capture(cube, seed=0, scene=SCENE), SCENE)
    np.testing.assert_allclose(e, [p.delta_e_conversion for p in s.patches], atol=1e-3)   # measured: 7e-5
    assert s.training["delta_e_mean"] == pytest.approx(s.summary.delta_e_conversion)
    assert s.held_out["library"] == "cfi99" and s.held_out["samples"] == 99
    assert s.held_out["delta_e_mean"] > s.training["delta_e_mean"]     # the chart flatters this camera


def test_a_camera_with_the_observers_curves_converts_every_colour_exactly(tmp_path):
    """Luther's condition: a camera whose sensitivities are the CIE 1931 x̄ȳz̄ sees XYZ, so a 3×3
    conversion fitted on the chart is exact on any colour.  What is left is the band average of a
    product (the bands' midpoint rule), second order in the band width: 10-nm bands leave a mean of
    0.060 ΔE*ab on the 99 CIE 2017 samples, 5-nm bands a quarter of it (measured 0.0151)."""
    wl, cmfs = cie_1931_cmfs()
    keep = (wl >= 380) & (wl <= 780)
    rows = "\n".join(f"{w:g},{x:.9g},{y:.9g},{z:.9g}" for w, (x, y, z) in zip(wl[keep], cmfs[keep]))
    (tmp_path / "cmf.csv").write_text("wavelength_nm,R,G,B\n" + rows + "\n")
    data = resolve_curve_files({"filters": {"camera_file": str(tmp_path / "cmf.csv")}}, tmp_path)
    means = []
    for step in (10, 5):
        scene = load_scene("scenes/d65.toml", ["image.width=160", "image.height=120", f"wavelengths.step_nm={step}"])
        camera = scene.camera.replace(filters=FilterSpec(**data["filters"]))
        M = conversion_matrix(ChartReference.of(scene), camera, scene.processing)
        block = heldout.held_out_block("cfi99", scene.illuminant, scene.grid, camera, M, scene.processing)
        assert block["delta_e_max"] < 0.3, block                          # measured: 0.22, 0.056
        means.append(block["delta_e_mean"])
    assert 3.5 < means[0] / means[1] < 4.5, means                         # measured: 3.97
    # and a real camera is far from it
    ref = ChartReference.of(SCENE)
    real = heldout.held_out_block("cfi99", SCENE.illuminant, SCENE.grid, SCENE.camera,
                                  conversion_matrix(ref, SCENE.camera, SCENE.processing), SCENE.processing)
    assert real["delta_e_mean"] > 3


@pytest.mark.parametrize("text, says", [
    ("wavelength_nm,a\n400,0.1\n", "at least two rows"),
    ("wavelength_nm,a,b\n400,0.1,0.2\n700,0.5\n", "every row must have 3 cells"),
    ("wavelength_nm,a\n400,0.1\n700,x\n", "every cell below the header must be a number"),
    ("wavelength_nm,a\n400,10\n700,50\n", "a reflectance factor is a finite number in 0-1.5"),
    ("wavelength_nm,a\n700,0.1\n400,0.2\n", "increasing"),
    ("wavelength_nm,a\n450,0.1\n650,0.2\n", "measured over 450-650 nm, the scene needs 400-700 nm"),
])
def test_a_bad_reflectance_file_is_one_line(tmp_path, text, says):
    (tmp_path / "r.csv").write_text(text)
    with pytest.raises(SpectracamError, match=says.replace("(", r"\(")):
        heldout.held_out_colours(f"file:{tmp_path / 'r.csv'}", SCENE.illuminant, SCENE.grid)


def test_simulate_writes_training_and_held_out_blocks(tmp_path):
    import subprocess
    import sys

    r = subprocess.run([sys.executable, "-m", "spectracam", "simulate", "scenes/d65.toml", "-o", str(tmp_path / "s"),
                        "--renderer", "analytic", "--set", "image.width=160", "--set", "image.height=120",
                        "--set", "processing.held_out=vs15"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    report = json.loads((tmp_path / "s" / "report.json").read_text())
    assert report["held_out"]["library"] == "vs15" and report["held_out"]["samples"] == 15
    assert set(report["held_out"]) >= {"delta_e_mean", "delta_e_p95", "delta_e_max", "samples"}
    assert report["training"]["samples"] == 24
    assert "not fitted on (vs15, 15 samples)" in r.stderr
    r = subprocess.run([sys.executable, "-m", "spectracam", "simulate", "scenes/d65.toml", "-o", str(tmp_path / "n"),
                        "--renderer", "analytic", "--set", "image.width=160", "--set", "image.height=120",
                        "--set", "processing.held_out=none"], capture_output=True, text=True)
    assert r.returncode == 0 and "held_out" not in json.loads((tmp_path / "n" / "report.json").read_text())
    for bad, says in (("bogus", "must be one of cfi99"), ("file:missing.csv", "no such file")):
        r = subprocess.run([sys.executable, "-m", "spectracam", "simulate", "scenes/d65.toml", "-o", str(tmp_path / "b"),
                            "--renderer", "analytic", "--set", f"processing.held_out={bad}"], capture_output=True, text=True)
        assert r.returncode == 2 and says in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert not (tmp_path / "b").exists()


def test_a_sweep_of_held_out_metrics_without_a_library_is_refused_before_it_runs(tmp_path):
    import subprocess
    import sys

    (tmp_path / "s.toml").write_text(
        'base_scene = "' + str(Path("scenes/blackbody_5000K.toml").resolve()) + '"\nrenderer = "analytic"\n'
        'metrics = ["held_out_delta_e_mean"]\n[scene]\nimage = { width = 96, height = 72 }\n'
        '[axes]\n"sensor.read_noise_e" = [10, 20]\n')
    r = subprocess.run([sys.executable, "-m", "spectracam", "sweep", str(tmp_path / "s.toml"), "-o", str(tmp_path / "o"),
                        "--serial", "--set", "processing.held_out=none"], capture_output=True, text=True)
    assert r.returncode == 2 and "need processing.held_out (it is 'none' in cell 0)" in r.stderr, r.stderr
    assert not (tmp_path / "o").exists()
