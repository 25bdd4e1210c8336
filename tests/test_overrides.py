"""One override mechanism (--set) on every command that reads a file, the atomic writer, and the
doctests of the public stage functions."""
import doctest
import importlib
import json
import os
import stat
import subprocess
import sys

import pytest
from click.testing import CliRunner

from spectracam.cli import main
from spectracam.core.errors import ConfigError
from spectracam.io.exr import read_raw_exr, read_radiance_exr
from spectracam.core.files import atomic_write
from spectracam.pipeline.overrides import apply_overrides, parse_assignment, parse_value

SCENE = "[image]\nwidth = 96\nheight = 72\n"


@pytest.mark.parametrize("text, value", [("3", 3), ("1.5", 1.5), ("true", True), ("[490, 600]", [490, 600]),
                                         ('"D65"', "D65"), ("malvar2004", "malvar2004"), ("fsc/optimal", "fsc/optimal")])
def test_values_are_toml_or_bare_words(text, value):
    assert parse_value(text) == value


def test_paths():
    assert apply_overrides({}, ["filters.cutoffs_nm[1]=600"], defaults=lambda: {"filters": {"cutoffs_nm": [490, 610]}}) \
        == {"filters": {"cutoffs_nm": [490, 600]}}
    assert apply_overrides({"name": "a"}, ["name=b"]) == {"name": "b"}
    for bad in ("sensor.adc_bits", "1sensor.x=1", "a.b.c=1", "sensor.=1", "x[1]y=2"):
        with pytest.raises(ConfigError, match="must be PATH=VALUE"):
            parse_assignment(bad)
    # keys in either case, and an element of a top-level list (issue 18: temperatures_K, pixel_pitches_um[1])
    assert apply_overrides({"temperatures_K": [3000, 5000]}, ["temperatures_K[1]=6000"]) == {"temperatures_K": [3000, 6000]}
    assert apply_overrides({}, ["pixel_pitches_um[1]=3"], defaults=lambda: {"pixel_pitches_um": [10, 2]}) \
        == {"pixel_pitches_um": [10, 3]}
    with pytest.raises(ConfigError, match="speeds is not a list with an element 0"):
        apply_overrides({}, ["speeds[0]=1"])
    with pytest.raises(ConfigError, match=r"filters.cutoffs_nm is not a list with an element 5"):
        apply_overrides({"filters": {"cutoffs_nm": [1, 2]}}, ["filters.cutoffs_nm[5]=3"])


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("set")
    (d / "s.toml").write_text(SCENE)
    r = CliRunner().invoke(main, ["render", str(d / "s.toml"), "-o", str(d / "r"), "--renderer", "analytic", "--quiet",
                                  "--set", "illuminant.temperature_K=4000"])
    assert r.exit_code == 0, r.output
    return d


def test_set_on_render_capture_score_simulate(files, tmp_path):
    cube, _ = read_radiance_exr(files / "r" / "radiance.exr")
    assert cube.metadata["scene"]["illuminant"]["temperature_K"] == 4000.0
    run = CliRunner().invoke
    r = run(main, ["capture", str(files / "r" / "radiance.exr"), "-o", str(tmp_path / "c"), "--quiet",
                   "--set", "sensor.adc_bits=10", "--set", "capture.design=fsc/optimal"])
    assert r.exit_code == 0, r.output
    raw = read_raw_exr(tmp_path / "c" / "raw.exr")
    assert raw.camera.sensor.adc_bits == 10 and raw.design == "fsc/optimal"
    r = run(main, ["score", str(tmp_path / "c" / "raw.exr"), "-o", str(tmp_path / "s"), "--quiet",
                   "--set", "processing.delta_e=ciede2000"])
    assert r.exit_code == 0, r.output
    assert json.loads((tmp_path / "s" / "report.json").read_text())["parameters"]["processing"]["delta_e"] == "ciede2000"
    r = run(main, ["simulate", str(files / "s.toml"), "-o", str(tmp_path / "m"), "--renderer", "analytic", "--quiet",
                   "--set", "capture.design=prism/balanced", "--set", "filters.cutoffs_nm[1]=600", "--seed", "5"])
    assert r.exit_code == 0, r.output
    raw = read_raw_exr(tmp_path / "m" / "raw.exr")
    assert raw.design == "prism/balanced" and raw.camera.filters.cutoffs_nm == (490.0, 600.0) and raw.seed == 5


@pytest.mark.parametrize("setting, message", [
    ("sensor.adc_bits=0", "sensor.adc_bits = 0: must be an integer between 1 and 24"),
    ("sensor.nosuch=1", "sensor.nosuch = 1: unknown key"),
    ("processing.demosaic=ahd", "processing.demosaic = 'ahd': must be one of"),
    ("capture.design=cfa/optimal", "the cfa architecture has one exposure"),
    ("filters.cutoffs_nm[4]=1", "filters.cutoffs_nm is not a list with an element 4"),
    ("sensor.adc_bits", "must be PATH=VALUE"),
])
def test_bad_set_is_one_line_and_writes_nothing(files, tmp_path, setting, message):
    r = subprocess.run([sys.executable, "-m", "spectracam", "simulate", str(files / "s.toml"), "-o",
                        str(tmp_path / "out"), "--renderer", "analytic", "--set", setting],
                       capture_output=True, text=True)
    assert r.returncode == 2 and message in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert not (tmp_path / "out").exists()


def test_set_on_paper_and_sweep(tmp_path):
    from pathlib import Path

    from spectracam.experiments.paper.experiment import load_experiment
    from spectracam.experiments.sweep.experiment import load_sweep

    scenes = Path(__file__).resolve().parent.parent / "scenes"
    exp = load_experiment(scenes / "paper.toml", ["wavelengths.step_nm=20", "designs=['cfa/single']",
                                                  "light.cfa_exposure_ms=20", "sensor.read_noise_e=5"])
    assert len(exp.base.grid) == 15 and exp.designs == ("cfa/single",) and exp.cfa_exposure_ms == 20
    assert exp.base.camera.sensor.read_noise_e == 5
    with pytest.raises(ConfigError, match="designs"):
        load_experiment(scenes / "paper.toml", ["designs=['cfa/optimal']"])
    sw = load_sweep(scenes / "sweeps" / "cfa_cutoffs.toml", ["trials=2", "sensor.read_noise_e=5"])
    assert sw.trials == 2 and sw.base["sensor"]["read_noise_e"] == 5


@pytest.mark.parametrize("mask, mode", [(0o022, 0o644), (0o077, 0o600)])
def test_atomic_write_gives_files_the_umask(tmp_path, mask, mode):
    old = os.umask(mask)
    try:
        p = atomic_write(tmp_path / "a.json", b"{}")
        q = atomic_write(tmp_path / "b.bin", lambda tmp: open(tmp, "wb").write(b"x"))
    finally:
        os.umask(old)
    assert stat.S_IMODE(p.stat().st_mode) == mode and stat.S_IMODE(q.stat().st_mode) == mode
    assert [f.name for f in tmp_path.iterdir() if f.name.startswith(".tmp")] == []


@pytest.mark.parametrize("module", ["core.registry", "core.spec", "core.spectra", "scene.illuminant", "optics",
                                    "architecture.filters", "sensor", "architecture.base", "sensor.exposure", "camera",
                                    "processing.color", "core.cielab", "pipeline.overrides", "pipeline.bridges"])
def test_doctests(module):
    m = importlib.import_module(f"spectracam.{module}")
    result = doctest.testmod(m, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
