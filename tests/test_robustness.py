"""Bad files, faults and signals (issue 11): one clear line, the right exit status, nothing written.

Every case runs the real command line; a case fails on a traceback, on a second line of error, on
the wrong exit status, or on any file left in the output directory (temporary ones included)."""
import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from spectracam.io.exr import read_exr, write_exr

SCENE = "[image]\nwidth = 64\nheight = 48\n"


def run(*args, timeout=300, **kw):
    return subprocess.run([sys.executable, "-m", "spectracam", *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, **kw)


def one_line(r, status=2, *fragments):
    assert r.returncode == status, (r.returncode, r.stderr)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("spectracam: ") and "Traceback" not in r.stderr, r.stderr
    for f in fragments:
        assert f in lines[0], lines[0]


def nothing_in(path):
    assert not path.exists() or list(path.rglob("*")) == [], list(path.rglob("*"))


@pytest.fixture(scope="module")
def good(tmp_path_factory):
    d = tmp_path_factory.mktemp("good")
    (d / "s.toml").write_text(SCENE)
    assert run("render", d / "s.toml", "-o", d / "r", "--renderer", "analytic", "--quiet").returncode == 0
    assert run("capture", d / "r" / "radiance.exr", "-o", d / "c", "--quiet").returncode == 0
    assert run("capture", d / "r" / "radiance.exr", "-o", d / "p", "--arch", "prism", "--quiet").returncode == 0
    return d


def edited_exr(src, dst, edit_channels=None, edit_attrs=None):
    channels, attrs = read_exr(src)
    keep = {k: v for k, v in attrs.items() if k.startswith("spectr") or k == "emissiveUnits"}
    if edit_channels:
        edit_channels(channels)
    if edit_attrs:
        edit_attrs(keep)
    write_exr(dst, channels, keep)
    return dst


def _nan(ch):
    k = sorted(ch)[5]
    ch[k] = ch[k].copy()
    ch[k][3, 4] = np.nan


def _negative(ch):
    for k in sorted(k for k in ch if k.startswith("S0."))[:3]:
        ch[k] = ch[k].copy()
        ch[k][:8, :8] = -1.0


def _drop_band(ch):
    del ch[sorted(k for k in ch if k.startswith("S0."))[4]]


@pytest.mark.parametrize("edit, fragment", [(_nan, "not finite"), (_negative, "negative"),
                                            (_drop_band, "bands")], ids=["nan", "negative", "grid"])
def test_bad_radiance_is_refused(good, tmp_path, edit, fragment):
    bad = edited_exr(good / "r" / "radiance.exr", tmp_path / "bad.exr", edit)
    one_line(run("capture", bad, "-o", tmp_path / "out"), 2, fragment)
    nothing_in(tmp_path / "out")


@pytest.mark.parametrize("case", ["dn_range", "cfa_planes", "no_camera", "no_channel", "bad_times"])
def test_bad_raw_files_are_refused(good, tmp_path, case):
    src = good / ("p" if case in ("cfa_planes", "no_channel") else "c") / "raw.exr"

    def channels(ch):
        if case == "dn_range":
            ch["Y"] = ch["Y"] * 1000.0 + 1e6
        if case == "no_channel":
            ch.pop("G", None)

    def attrs(a):
        if case == "cfa_planes":
            a["spectracamCamera"] = a["spectracamCamera"].replace('"architecture": "prism"', '"architecture": "cfa"')
            a["spectracamCamera"] = a["spectracamCamera"].replace('"exposure": "optimal"', '"exposure": "single"')
        if case == "no_camera":
            del a["spectracamCamera"]
        if case == "bad_times":
            a["spectracamExposureTimesS"] = json.dumps({"R": -1.0, "G": 0.01, "B": float("nan")})

    bad = edited_exr(src, tmp_path / "raw.exr", channels, attrs)
    one_line(run("score", bad, "-o", tmp_path / "out"), 2)
    nothing_in(tmp_path / "out")


@pytest.mark.parametrize("cut", [100, 3000, 20000])
def test_truncated_exr(good, tmp_path, cut):
    data = (good / "r" / "radiance.exr").read_bytes()
    (tmp_path / "t.exr").write_bytes(data[:cut])
    one_line(run("capture", tmp_path / "t.exr", "-o", tmp_path / "out"), 2)
    one_line(run("inspect", tmp_path / "t.exr"), 2)
    nothing_in(tmp_path / "out")


@pytest.mark.parametrize("what", ["scene", "config", "experiment", "sweep"])
def test_binary_garbage_as_a_text_file(good, tmp_path, what):
    g = tmp_path / "g.toml"
    g.write_bytes(os.urandom(2000))
    args = {"scene": ("render", g, "-o", tmp_path / "o"),
            "config": ("capture", good / "r" / "radiance.exr", "-o", tmp_path / "o", "--config", g),
            "experiment": ("paper", "-o", tmp_path / "o", "--experiment", g),
            "sweep": ("sweep", g, "-o", tmp_path / "o")}[what]
    one_line(run(*args), 2, "UTF-8")
    nothing_in(tmp_path / "o")


@pytest.mark.parametrize("seed, ok", [("-1", False), ("2147483648", False), ("1099511627776", False),
                                      ("2147483647", True)])
def test_one_seed_range_recorded_exactly(good, tmp_path, seed, ok):
    r = run("capture", good / "r" / "radiance.exr", "-o", tmp_path / "c", "--seed", seed, "--quiet")
    if not ok:
        one_line(r, 2, "--seed")
        return
    assert r.returncode == 0, r.stderr
    from spectracam.io.exr import read_raw_exr

    first = read_raw_exr(tmp_path / "c" / "raw.exr")
    assert first.seed == int(seed)
    # the recorded seed reproduces the file
    assert run("capture", good / "r" / "radiance.exr", "-o", tmp_path / "d", "--seed", str(first.seed),
               "--quiet").returncode == 0
    np.testing.assert_array_equal(read_raw_exr(tmp_path / "d" / "raw.exr").digital, first.digital)


def test_output_below_a_file_or_a_device(good, tmp_path):
    (tmp_path / "file").write_text("x")
    one_line(run("simulate", good / "s.toml", "-o", tmp_path / "file" / "sub", "--renderer", "analytic"), 2, "file")
    one_line(run("simulate", good / "s.toml", "-o", "/dev/null", "--renderer", "analytic"), 2)


def test_disk_full_while_writing_leaves_nothing(good, tmp_path, monkeypatch):
    # the third file of simulate fails as a full disk would: one line, exit 1, none of its outputs
    from click.testing import CliRunner

    import spectracam.core.files as files
    from spectracam.cli import main

    real, n = files.atomic_write, {"calls": 0}

    def failing(path, content, now=False):
        n["calls"] += 1
        if n["calls"] == 3:
            raise OSError(28, "No space left on device", str(path))
        return real(path, content, now)

    monkeypatch.setattr(files, "atomic_write", failing)
    for mod in ("spectracam.io.exr", "spectracam.io.dng", "spectracam.io.report", "spectracam.io.plots"):
        monkeypatch.setattr(f"{mod}.atomic_write", failing, raising=False)
    r = CliRunner().invoke(main, ["simulate", str(good / "s.toml"), "-o", str(tmp_path / "o"), "--renderer",
                                  "analytic", "--quiet"])
    assert r.exit_code == 1 and "No space left on device" in r.output and "Traceback" not in r.output, r.output
    nothing_in(tmp_path / "o")


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP, signal.SIGINT])
def test_signals_leave_nothing(good, tmp_path, sig):
    scene = tmp_path / "big.toml"
    scene.write_text("[image]\nwidth = 640\nheight = 480\n[render]\nsamples_per_pixel = 64\n")
    p = subprocess.Popen([sys.executable, "-m", "spectracam", "simulate", str(scene), "-o", str(tmp_path / "o"),
                          "--quiet"], stderr=subprocess.PIPE, text=True, env={**os.environ, "SPECTRACAM_CACHE":
                                                                              str(tmp_path / "cache")})
    time.sleep(4)
    p.send_signal(sig)
    _, err = p.communicate(timeout=120)
    assert p.returncode == 128 + sig, (p.returncode, err)
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    nothing_in(tmp_path / "o")
    assert not list((tmp_path / "cache").glob(".tmp*")) if (tmp_path / "cache").exists() else True


def test_render_cache_verifies_its_pixels(tmp_path):
    from conftest import small_scene
    from spectracam.io.cache import cached_render, render_key

    s = small_scene(image={"width": 64, "height": 48})
    cube, hit = cached_render(s, "analytic", directory=tmp_path)
    key, _ = render_key(s, "analytic")
    # edit the pixels, keep the attributes: the entry no longer matches its checksum
    edited_exr(tmp_path / f"{key}.exr", tmp_path / f"{key}.exr",
               lambda ch: ch.__setitem__(sorted(ch)[3], ch[sorted(ch)[3]] * 2))
    again, hit = cached_render(s, "analytic", directory=tmp_path)
    assert not hit
    np.testing.assert_array_equal(again.radiance, cube.radiance)


def test_sweep_journal_survives_damage_and_foreign_rows(tmp_path):
    from pathlib import Path

    from spectracam.experiments.sweep.experiment import load_sweep, run_sweep

    root = Path(__file__).resolve().parent.parent / "scenes"
    (tmp_path / "sw.toml").write_text(f'base_scene = "{root}/blackbody_5000K.toml"\nrenderer = "analytic"\n'
                                      '[scene.image]\nwidth = 96\nheight = 72\n'
                                      '[axes]\n"sensor.read_noise_e" = [10, 20, 30]\n')
    sweep = load_sweep(tmp_path / "sw.toml")
    run_sweep(sweep, tmp_path / "o", serial=True, progress=False)
    j = tmp_path / "o" / "results.jsonl"
    lines = j.read_text().splitlines()
    foreign = json.loads(lines[0])
    foreign.update(sweep="0" * 16, cell=1)
    j.write_text("\n".join([lines[0], "", "{garbage", json.dumps(foreign)]) + "\n")
    warnings = []
    t = run_sweep(sweep, tmp_path / "o", serial=True, resume=True, progress=False, log=warnings.append)
    assert t["new_cells"] == 2 and any("damaged or from another sweep" in w for w in warnings)
    rows = [json.loads(x) for x in j.read_text().splitlines() if x.startswith("{\"sweep\": \"" + sweep.digest)]
    assert sorted((r["cell"], r["trial"]) for r in rows) == [(0, 0), (1, 0), (2, 0)]
    (tmp_path / "o" / "sweep.json").write_text("{damaged")
    from spectracam.core.errors import SpectracamError

    with pytest.raises(SpectracamError, match="sweep.json is damaged"):
        run_sweep(sweep, tmp_path / "o", serial=True, resume=True, progress=False)


def test_unreachable_scheduler_fails_fast(tmp_path):
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent / "scenes"
    t = time.perf_counter()
    r = run("sweep", root / "sweeps" / "cfa_cutoffs.toml", "-o", tmp_path / "o", "--scheduler", "tcp://127.0.0.1:1",
            "--quiet", "--set", "image.width=96", "--set", "image.height=72", "--set", "renderer=analytic")
    assert time.perf_counter() - t < 60
    one_line(r, 2, "--scheduler = 'tcp://127.0.0.1:1': cannot connect")
    assert not (tmp_path / "o").exists()  # refused before anything is written (issue 18)


@pytest.mark.parametrize("peer", ["http", "garbage", "address"])
def test_a_scheduler_that_is_not_dask_is_refused_within_the_handshake_timeout(tmp_path, peer):
    """Issue 18: an HTTP server (it sends nothing) hung the sweep > 300 s; a peer sending other bytes
    was read as a 3 EiB message; a malformed address gave a traceback.  Loopback only."""
    import socket
    import threading
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent / "scenes"
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(4)
    port = srv.getsockname()[1]

    def serve():
        try:
            while True:
                c, _ = srv.accept()
                if peer == "garbage":
                    c.sendall(b"\xff" * 64 + b"SSH-2.0-OpenSSH\r\n")
                threading.Timer(30, c.close).start()
        except OSError:
            pass

    threading.Thread(target=serve, daemon=True).start()
    address = f"tcp://127.0.0.1:{port}" if peer != "address" else "http://127.0.0.1:8786"
    t = time.perf_counter()
    try:
        r = run("sweep", root / "sweeps" / "cfa_cutoffs.toml", "-o", tmp_path / "o", "--scheduler", address, "--quiet",
                "--set", "renderer=analytic")
    finally:
        srv.close()
    assert time.perf_counter() - t < 30
    one_line(r, 2, "--scheduler", "must be a Dask scheduler's address" if peer == "address" else "not a Dask scheduler")
    assert not (tmp_path / "o").exists()


def test_the_fault_harness_finds_nothing_in_one_case_of_every_class(capsys):
    """tools/fuzz.py's fast subset (issue 18): one case of each fault class — damaged and foreign files,
    wrong values, unwritable and read-only outputs (capabilities dropped), full disks, memory limits, contradicting attributes, journal
    damage, signals to the process and its group, non-Dask schedulers — with zero tracebacks, leftovers,
    silent wrong results, multi-line errors, orphans and hangs."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tools"))
    import fuzz

    n = len(fuzz.CASES)
    status = fuzz.main(["--cases", str(n), "--seed", "11", "--jobs", "2"])
    out = capsys.readouterr().out
    assert status == 0, out
    assert f"fuzz: {n} cases" in out and "0 tracebacks, 0 partial files, 0 silent wrong results" in out, out


def test_the_render_cache_follows_xdg_cache_home(monkeypatch, tmp_path):
    """``$SPECTRACAM_CACHE`` first, then the XDG user cache (an absolute ``$XDG_CACHE_HOME``), then ~/.cache."""
    from pathlib import Path

    from spectracam.io.cache import cache_dir

    monkeypatch.delenv("SPECTRACAM_CACHE", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cache_dir() == tmp_path / "xdg" / "spectracam" / "renders"
    monkeypatch.setenv("XDG_CACHE_HOME", "relative/dir")          # the specification: relative paths are ignored
    assert cache_dir() == Path.home() / ".cache" / "spectracam" / "renders"
    monkeypatch.delenv("XDG_CACHE_HOME")
    assert cache_dir() == Path.home() / ".cache" / "spectracam" / "renders"
    monkeypatch.setenv("SPECTRACAM_CACHE", str(tmp_path / "own"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cache_dir() == tmp_path / "own"
