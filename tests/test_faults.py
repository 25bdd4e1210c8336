"""Faults (issue 18): a full disk, signals to a command with workers, damaged or contradicting raw
attributes, an output blocked by a directory — each one line, nothing half-written, no orphan."""
import glob
import json
import os
import resource
import signal
import subprocess
import sys
import time

import pytest

CLI = [sys.executable, "-m", "spectracam"]
SMALL = ["--set", "image.width=160", "--set", "image.height=120"]


def run(*args, cwd=None, preexec_fn=None):
    return subprocess.run([*CLI, *map(str, args)], capture_output=True, text=True, cwd=cwd, preexec_fn=preexec_fn)


def one_line(r, code, *parts):
    assert r.returncode == code, (r.returncode, r.stderr)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("spectracam: error:"), r.stderr
    for p in parts:
        assert p in lines[0], (p, lines[0])


def small_files_only():
    """A file-size limit (RLIMIT_FSIZE) of 20 kB: every larger write fails with EFBIG as on a full disk
    (Python ignores SIGXFSZ), without needing root to mount a small file system."""
    resource.setrlimit(resource.RLIMIT_FSIZE, (20_000, 20_000))


@pytest.fixture(scope="module")
def raw_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("raw")
    assert run("render", "scenes/d65.toml", "-o", d / "r", "--renderer", "analytic", *SMALL, "--quiet").returncode == 0
    assert run("capture", d / "r" / "radiance.exr", "-o", d / "c", "--quiet").returncode == 0
    return d


def test_a_full_disk_is_one_line_and_leaves_nothing(tmp_path):
    r = run("render", "scenes/d65.toml", "-o", tmp_path / "o", "--renderer", "analytic", *SMALL,
            preexec_fn=small_files_only)
    one_line(r, 1, "cannot read or write", "radiance.exr")
    assert not (tmp_path / "o").exists()


def test_a_full_render_cache_never_stops_a_run(tmp_path):
    from conftest import small_scene
    from spectracam.io.cache import cached_render, render_key

    # an entry blocked by a directory: rendered, said, and the run goes on
    scene = small_scene()
    (tmp_path / "c1" / f"{render_key(scene, 'analytic')[0]}.exr").mkdir(parents=True)
    notes = []
    cube, hit = cached_render(scene, "analytic", log=notes.append, directory=tmp_path / "c1")
    assert not hit and cube.shape == (120, 160, 30) and any("render cache not written" in n for n in notes), notes
    # a cache on a full disk (every file over 20 kB fails): paper goes on without it
    env = dict(os.environ, SPECTRACAM_CACHE=str(tmp_path / "cache"))
    r = subprocess.run([*CLI, "paper", "--quick", "--renderer", "analytic", "-o", tmp_path / "p",
                        "--set", "temperatures_K=[5000]", "--set", "designs=['cfa/single']"],
                       capture_output=True, text=True, env=env, preexec_fn=small_files_only)
    # the cache's 200 kB entries cannot be written: said, not fatal; the outputs (small enough) are
    if r.returncode == 0:
        assert "render cache not written" in r.stderr and (tmp_path / "p" / "results.json").exists()
    else:  # an output over the limit: one error line (after the progress lines), exit 1, nothing left
        assert r.returncode == 1 and "Traceback" not in r.stderr, r.stderr
        errors = [x for x in r.stderr.splitlines() if x.startswith("spectracam: error:")]
        assert len(errors) == 1 and r.stderr.strip().splitlines()[-1] == errors[0], r.stderr
        assert "cannot read or write " + str(tmp_path / "p") in errors[0]
        assert "render cache not written" in r.stderr and not (tmp_path / "p").exists()


def test_a_directory_in_the_way_of_an_output_leaves_nothing(tmp_path, raw_dir):
    out = tmp_path / "S"
    (out / "rendered.png").mkdir(parents=True)
    r = run("score", raw_dir / "c" / "raw.exr", "-o", out)
    one_line(r, 1, "rendered.png", "a directory is in the way")
    assert "wrote" not in r.stdout + r.stderr
    assert sorted(p.name for p in out.iterdir()) == ["rendered.png"]  # nothing else, no temporary file


def children(pid: int) -> set:
    kids = set()
    for f in glob.glob(f"/proc/{pid}/task/*/children"):
        try:
            kids |= {int(x) for x in open(f).read().split()}
        except OSError:
            pass
    return kids


def alive(pid: int) -> bool:
    try:
        return open(f"/proc/{pid}/stat").read().split()[2] != "Z"
    except OSError:
        return False


@pytest.mark.skipif(not os.path.exists("/proc/self/task"), reason="needs Linux /proc to see child processes")
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP])
def test_a_signal_to_paper_leaves_no_orphaned_worker(tmp_path, sig):
    p = subprocess.Popen([*CLI, "paper", "--quick", "--renderer", "analytic", "-o", tmp_path / "P"],
                         stderr=subprocess.PIPE, text=True)
    t0, kids = time.time(), set()
    while time.time() - t0 < 90 and not kids and p.poll() is None:
        kids = children(p.pid)
        time.sleep(0.01)
    assert kids, "the paper run forked no worker to test"
    time.sleep(0.2)
    kids |= children(p.pid)
    p.send_signal(sig)
    err = p.communicate(timeout=60)[1]
    assert p.returncode == 128 + sig and err.strip().splitlines()[-1].startswith("spectracam: interrupted"), err
    deadline = time.time() + 5
    while time.time() < deadline and any(alive(k) for k in kids):
        time.sleep(0.05)
    assert not any(alive(k) for k in kids), "orphaned workers"
    assert not (tmp_path / "P").exists()


def damaged(raw_dir, tmp_path, **edits):
    """The capture's raw EXR with attributes replaced (None removes one)."""
    from spectracam.io.exr import read_exr, write_exr

    ch, at = read_exr(raw_dir / "c" / "raw.exr")
    keep = {k: v for k, v in at.items() if k.startswith("spectracam")}
    for k, v in edits.items():
        keep[k] = v
    path = tmp_path / "bad.exr"
    write_exr(path, ch, {k: v for k, v in keep.items() if v is not None})
    return path


@pytest.mark.parametrize("edit, message", [
    ({"spectracamDnScale": 0.0}, "spectracamDnScale = 0.0 contradicts the recorded camera"),
    ({"spectracamDnOffset": 3.0}, "spectracamDnOffset = 3.0 contradicts"),
    ({"spectracamAdcBits": 12}, "spectracamAdcBits = 12 contradicts the recorded camera (8)"),
    ({"spectracamCfaPattern": "BGGR"}, "spectracamCfaPattern = 'BGGR' contradicts"),
    ({"spectracamArchitecture": "fsc"}, "spectracamArchitecture = 'fsc' contradicts"),
    ({"spectracamCaptureTimeS": -1.0}, "spectracamCaptureTimeS"),
    ({"spectracamExposureTimesS": [0.01, -0.01, 0.01]}, "spectracamExposureTimesS"),
])
def test_damaged_raw_attributes_are_refused(tmp_path, raw_dir, edit, message):
    import numpy as np

    from spectracam.io.exr import double

    k, v = next(iter(edit.items()))
    if k == "spectracamCaptureTimeS":
        v = double(v)
    elif k == "spectracamExposureTimesS":
        v = np.asarray(v, np.float64)
    elif isinstance(v, float):
        v = float(np.float32(v))
    r = run("score", damaged(raw_dir, tmp_path, **{k: v}), "-o", tmp_path / "o")
    one_line(r, 2, message)
    assert not (tmp_path / "o").exists()


def test_a_raw_whose_scene_was_edited_is_not_scored_against_it(tmp_path, raw_dir):
    from spectracam.io.exr import read_exr

    _, at = read_exr(raw_dir / "c" / "raw.exr")
    scene = json.loads(at["spectracamScene"])
    scene["illuminant"] = {"type": "blackbody", "temperature_K": 3000.0, "white_luminance_cd_m2": 100.0}
    r = run("score", damaged(raw_dir, tmp_path, spectracamScene=json.dumps(scene)), "-o", tmp_path / "o")
    one_line(r, 2, "exposure times", "3000 K blackbody")
    scene["illuminant"] = {"type": "cie", "name": "D65", "white_luminance_cd_m2": 50.0}  # another level
    r = run("score", damaged(raw_dir, tmp_path, spectracamScene=json.dumps(scene)), "-o", tmp_path / "o")
    one_line(r, 2, "exposure times", "50 cd/m²")


@pytest.mark.parametrize("x, signed", [(7200.0, False), (1e-12, False), (1 / 250, False), (5e9, False),
                                       (0.0283, False), (-123.456, True), (3.3e-9, True), (1e6 + 0.5, False)])
def test_dng_rationals_fit_their_fields(x, signed):
    """A 2-hour exposure, a 1e-12 s one, huge and tiny matrix entries: every (S)RATIONAL fits 32 bits
    (31 signed) — tifffile's struct.error before — and is as close as the field allows."""
    from spectracam.io.dng import _fraction

    top = 2**31 - 1 if signed else 2**32 - 1
    n, d = _fraction(x, signed)
    assert 1 <= d <= top and abs(n) <= top
    lo = 1.0 / top
    if lo <= abs(x) <= top:
        assert n / d == pytest.approx(x, rel=1e-6, abs=1e-6)
    else:
        assert n / d == pytest.approx(min(max(abs(x), lo), top) * (1 if x > 0 else -1))


def test_long_exposures_and_wide_adcs_write_valid_files(tmp_path):
    rawpy = pytest.importorskip("rawpy")
    from spectracam.io.exr import read_raw_exr

    # a light so dim that the exposure is ~2 hours: the DNG's ExposureTime field holds it
    r = run("simulate", "scenes/d65.toml", "-o", tmp_path / "dim", "--renderer", "analytic", *SMALL,
            "--set", "illuminant.white_luminance_cd_m2=1e-5", "--set", "sensor.dark_current=false", "--quiet")
    assert r.returncode == 0, r.stderr
    t = read_raw_exr(tmp_path / "dim" / "raw.exr").capture_time_s
    assert t > 4295  # beyond 2^32 µs
    with rawpy.imread(str(tmp_path / "dim" / "raw.dng")) as raw:
        assert raw.raw_image.shape == (120, 160)
    # a 24-bit ADC: no DNG reader takes it; raw.exr holds it, and the command says so in one line
    r = run("simulate", "scenes/d65.toml", "-o", tmp_path / "wide", "--renderer", "analytic", *SMALL,
            "--set", "sensor.adc_bits=24", "--quiet")
    assert r.returncode == 0 and "raw.dng not written" in r.stderr, r.stderr
    assert (tmp_path / "wide" / "raw.exr").exists() and not (tmp_path / "wide" / "raw.dng").exists()


def test_emva_refuses_a_dark_channel_in_one_line(tmp_path):
    one_line(run("emva", "-o", tmp_path / "e", "--channel", "R"), 2, "--channel = 'R'", "does not respond", "611 nm")
    one_line(run("emva", "-o", tmp_path / "e", "--wavelength", "nan"), 2, "--wavelength = nan")
    assert not (tmp_path / "e").exists()


def test_set_reaches_every_documented_key_and_wins(tmp_path):
    """--set comes last: over a sweep file's own [scene] table, over an experiment's light, and a
    quick look keeps what --set chose; upper-case keys and top-level list elements are reachable."""
    from spectracam.experiments.paper.experiment import load_experiment
    from spectracam.experiments.sweep.experiment import cell_scene, load_sweep
    from spectracam.experiments.motion.experiment import load_motion
    from spectracam.pipeline.scene_file import shipped_scene_file
    from spectracam.experiments.spatial.experiment import SpatialSpec, load_spec_and_scene

    sweep = load_sweep("scenes/sweeps/cfa_cutoffs.toml", ["image.width=160", "image.height=120"])
    first = cell_scene(sweep, sweep.cells()[0], 0)
    assert (first.image.width, first.image.height) \
        == (160, 120)  # the sweep file's [scene] says 320x240
    paper = shipped_scene_file("paper.toml")
    exp = load_experiment(paper, ["temperatures_K=[3000, 6000]", "light.white_luminance_cd_m2=50"])
    assert exp.temperatures_K == (3000.0, 6000.0) and exp.white_luminance_cd_m2 == 50 and exp.cfa_exposure_ms is None
    assert load_experiment(paper, ["temperatures_K[1]=4500"]).temperatures_K[1] == 4500
    with pytest.raises(Exception, match="not both"):
        load_experiment(paper, ["light.white_luminance_cd_m2=50", "light.cfa_exposure_ms=20"])
    spec, _ = load_motion(["speeds_px_per_ms=[0.0, 0.07]"], quick=True)
    assert spec.speeds_px_per_ms == (0.0, 0.07)  # quick() would choose 8 speeds
    for bad in ("[nan]", "[inf]", "[-1]"):
        with pytest.raises(Exception, match="finite numbers ≥ 0"):
            load_motion([f"speeds_px_per_ms={bad}"])
    spec, _ = load_spec_and_scene(SpatialSpec, ["pixel_pitches_um[1]=3"])
    assert spec.pixel_pitches_um[1] == 3.0


def test_an_empty_output_name_is_refused(tmp_path):
    r = run("render", "scenes/d65.toml", "-o", "", "--renderer", "analytic", *SMALL, cwd=None)
    assert r.returncode == 2 and "must name a directory" in r.stderr and not os.path.exists("radiance.exr")


#: Random123's published known answers for Philox4x32-10 (kat_vectors): counter c0..c3, key k0 k1 → output.
PHILOX_KAT = [
    ((0, 0, 0, 0), (0, 0), (0x6627E8D5, 0xE169C58D, 0xBC57AC4C, 0x9B00DBD8)),
    ((0xFFFFFFFF,) * 4, (0xFFFFFFFF,) * 2, (0x408F276D, 0x41C83B0E, 0xA20BC7C6, 0x6D5451FD)),
    ((0x243F6A88, 0x85A308D3, 0x13198A2E, 0x03707344), (0xA4093822, 0x299F31D0),
     (0xD16CFE09, 0x94FDCCEB, 0x5001E420, 0x24126EA1)),
]


@pytest.mark.parametrize("counter, key, want", PHILOX_KAT)
def test_philox_matches_random123s_known_answers(counter, key, want):
    """Both Philox implementations (the numba kernel's and the NumPy twin) against the published vectors:
    a wrong multiplier, Weyl constant, round count or word order fails here."""
    import numpy as np

    from spectracam.sensor.kernels import philox_np

    pytest.importorskip("numba")
    from spectracam.sensor._numba_kernels import philox

    got = philox(*(np.uint64(c) for c in counter), *(np.uint64(k) for k in key))
    assert [int(x) for x in got] == list(want)
    if counter[3] == 0:  # the NumPy twin's counters are (index low, index high, draw, 0)
        index = np.array([counter[0] | (counter[1] << 32)], np.uint64)
        assert [int(x[0]) for x in philox_np(index, key, counter[2])] == list(want)


def test_a_memory_limit_is_met_with_one_line_before_any_work(tmp_path):
    """The estimate reads the process's own address-space limit (prlimit --as), not only the machine's
    free memory (issue 18: a 6000x6000 render under a 4 GiB limit died with a traceback)."""
    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (4 * 2**30, 4 * 2**30))

    r = run("render", "scenes/d65.toml", "-o", tmp_path / "o", "--renderer", "analytic",
            "--set", "image.width=6000", "--set", "image.height=6000", preexec_fn=limit)
    one_line(r, 2, "6000x6000", "address-space limit")
    assert not (tmp_path / "o").exists()
    # motion has its own estimate (its sub-pixel renders, not the scene's image): a 1000-px edge
    r = run("motion", "--quick", "-o", tmp_path / "m", "--renderer", "analytic", "--set", "edge_size_px=[1000, 1000]",
            preexec_fn=limit)
    one_line(r, 2, "edge_size_px = [1000, 1000]", "address-space limit")
    assert not (tmp_path / "m").exists()


def test_motion_memory_does_not_grow_with_its_slices(monkeypatch):
    """Each slice's share of every row is found when the slice is rendered, and the rendered poses kept
    for reuse are bounded (issue 18: a (rows × slices) table per channel group — 1.4 GB at slices =
    100000 — and every pose's render kept died with MemoryError)."""
    import tracemalloc
    from spectracam.experiments.motion import render
    from spectracam.experiments.motion.motion import Motion
    from spectracam.experiments.motion.render import MovingScene, integrate
    from spectracam.experiments.motion.timing import TimingSpec, capture_timing
    from spectracam.architecture.base import make_architecture
    from spectracam.pipeline.scene_file import load_scene
    from spectracam.experiments.spatial.geometry import CameraGeometry
    from spectracam.experiments.spatial.targets import SlantedEdge

    scene = load_scene("scenes/d65.toml")
    g = CameraGeometry.framing(16.0, 12.0, 1.4, 10.0, 16, 16)
    ms = MovingScene(SlantedEdge(), g, scene.illuminant, scene.grid, 2, "analytic")
    monkeypatch.setattr(render, "BASIS_CACHE_BYTES", 50 * ms.basis((0.0, 0.0, 0.0)).nbytes)
    timing = capture_timing(make_architecture("fsc"), [0.02, 0.01, 0.03], TimingSpec(), g.height_px)
    peaks = []
    for n in (100, 2000):
        tracemalloc.start()
        integrate(ms, Motion(velocity_mm_per_s=(1.0, 0.0)), timing, slices=n)
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    assert peaks[1] < 1.5 * peaks[0], peaks


def test_a_sweep_cell_that_cannot_be_metered_is_refused_before_it_runs(tmp_path):
    (tmp_path / "s.toml").write_text(
        'base_scene = "' + os.path.abspath("scenes/blackbody_5000K.toml") + '"\nrenderer = "analytic"\ntrials = 1\n'
        '[scene]\nimage = { width = 96, height = 72 }\n[axes]\n"filters.cutoffs_nm[1]" = [600, 720]\n')
    r = run("sweep", tmp_path / "s.toml", "-o", tmp_path / "o", "--serial", "--quiet")
    one_line(r, 2, "cell 1", "channel R receives no light")
    assert not (tmp_path / "o").exists()


def test_the_fused_backend_never_hides_a_fault(monkeypatch, capsys):
    """Only numba's own compile errors switch the fused kernels off (said once on stderr); any other
    exception in a kernel — a bug, bad data — reaches the caller (issue 18: it was swallowed and the
    backend silently switched itself off)."""
    numba = pytest.importorskip("numba")
    from spectracam.sensor import kernels

    mod = kernels._numba()
    if mod is None:
        pytest.skip("the fused backend does not run here")
    monkeypatch.setitem(kernels._STATE, "module", mod)

    def bug(*args):
        raise IndexError("a planted bug")

    monkeypatch.setattr(mod, "capture_kernel", bug)
    with pytest.raises(IndexError, match="planted"):
        kernels._run("capture_kernel", 4, lambda a, b: ())
    assert kernels._STATE["module"] is mod  # still on

    def no_compile(*args):
        raise numba.core.errors.TypingError("cannot type this here")

    monkeypatch.setattr(mod, "capture_kernel", no_compile)
    assert kernels._run("capture_kernel", 4, lambda a, b: ()) is False
    assert kernels._STATE["module"] is None and "using the NumPy path" in capsys.readouterr().err


def test_a_forked_child_captures_with_its_own_thread_pool():
    """A child forked after the parent used the kernels' thread pool captures the same raw (issue 18:
    the parent's pool has no threads in the child, and a capture there hung)."""
    import numpy as np
    from spectracam import pipeline
    from spectracam.pipeline.scene_file import load_scene

    scene = load_scene("scenes/blackbody_5000K.toml", ["image.width=96", "image.height=64"])
    cube = pipeline.render(scene, "analytic")
    parent = pipeline.capture(cube, seed=3, scene=scene).digital
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:                                                     # the child: capture, report, leave
        os.close(read)
        try:
            child = pipeline.capture(cube, seed=3, scene=scene).digital
            os.write(write, b"same" if np.array_equal(child, parent) else b"differs")
        finally:
            os._exit(0)
    os.close(write)
    deadline = time.monotonic() + 60
    while os.waitpid(pid, os.WNOHANG) == (0, 0):
        if time.monotonic() > deadline:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            pytest.fail("the forked child's capture hung")
        time.sleep(0.05)
    assert os.read(read, 16) == b"same"
    os.close(read)


def test_layouts_are_what_they_say():
    """A mistyped plane kind is refused (it was timed as simultaneous), and a layout with no raw form
    is not written as "planes"."""
    from spectracam.architecture.base import PlanesLayout
    from spectracam.core.errors import SpectracamError
    from spectracam.io.exr import layout_to_dict

    with pytest.raises(SpectracamError, match="layout kind = 'frame'"):
        PlanesLayout("frame", "three frames")
    with pytest.raises(SpectracamError, match="no raw EXR form"):
        layout_to_dict(object())
    with pytest.raises(Exception, match="targets = 'nosuch': must be one of 'edge', 'edge_red_cyan'"):
        from spectracam.experiments.spatial.experiment import SPATIAL_TARGETS

        SPATIAL_TARGETS.get("nosuch")


def test_a_false_flag_on_the_command_line_is_applied(tmp_path):
    """--no-gamut-clip over a scene that clips must turn clipping off (a flag whose value is False is
    still a flag: a slip that tests `if value` instead of `is not None` drops it)."""
    (tmp_path / "s.toml").write_text("[image]\nwidth = 160\nheight = 120\n[processing]\ngamut_clip = true\n")
    for flag, want in (("--no-gamut-clip", False), ("--gamut-clip", True)):
        r = run("simulate", tmp_path / "s.toml", "-o", tmp_path / flag, "--renderer", "analytic", flag, "--quiet")
        assert r.returncode == 0, r.stderr
        params = json.loads((tmp_path / flag / "report.json").read_text())["parameters"]
        assert params["processing"]["gamut_clip"] is want


def test_an_undefined_snr_is_not_read_as_noise_free():
    """Issue 18: SNR None meant both noise-free and undefined.  A dim blue under warm light leaves the
    dark-subtracted blue mean of dark patches ≤ 0: those are counted and named; a noise-free capture
    counts none."""
    from conftest import small_scene
    from spectracam.pipeline import capture, score
    from spectracam.render import render

    scene = small_scene(illuminant={"temperature_K": 2000, "white_luminance_cd_m2": 2.0},
                        sensor={"read_noise_e": 2000.0})
    cube = render(scene, "analytic")
    s = score(capture(cube, seed=0, scene=scene), scene).to_dict()
    undefined = [p for p in s["patches"] if p["snr_undefined"]]
    assert undefined and s["chart"]["snr_undefined_patches"] == sum(len(p["snr_undefined"]) for p in undefined)
    assert all(p["snr_B_db"] is None for p in undefined if "B" in p["snr_undefined"])
    quiet = scene.replace(camera=scene.camera.replace(sensor=scene.camera.sensor.off(
        "shot_noise", "dark_current", "read_noise", "fpn", "quantization")))
    s0 = score(capture(cube, seed=0, scene=quiet), quiet).to_dict()
    assert s0["chart"]["snr_B_db"] is None and s0["chart"]["snr_undefined_patches"] == 0


def test_emva_refuses_an_unmeasurable_camera_in_its_own_terms(tmp_path):
    r = run("emva", "-o", tmp_path / "e", "--set", "sensor.black_level_DN=128", "--set", "sensor.fpn_fraction=0.9")
    one_line(r, 2, "cannot be measured as EMVA 1288 prescribes", "darkest exposure step", "[sensor]")
    assert not (tmp_path / "e").exists()


def test_a_dask_worker_killed_mid_sweep_is_retried_by_the_cluster(tmp_path):
    """SIGKILL to one worker of the sweep's local cluster while cells remain: the nanny starts a new
    worker, the lost task runs again (TASK_RETRIES), and the sweep ends with every cell × trial once
    (issue 18: a FutureCancelledError traceback and 66 of 486 rows)."""
    psutil = pytest.importorskip("psutil")
    root = os.path.abspath("scenes/blackbody_5000K.toml")
    (tmp_path / "s.toml").write_text(
        f'base_scene = "{root}"\nrenderer = "analytic"\ntrials = 2\nseed = 0\nmetrics = ["delta_e_mean"]\n'
        '[scene]\nimage = { width = 320, height = 240 }\n[axes]\n'
        '"filters.cutoffs_nm[0]" = { start = 450, stop = 530, step = 10 }\n'
        '"filters.cutoffs_nm[1]" = { start = 570, stop = 650, step = 10 }\n')
    journal = tmp_path / "o" / "results.jsonl"
    proc = subprocess.Popen([*CLI, "sweep", str(tmp_path / "s.toml"), "-o", str(tmp_path / "o"), "--workers", "2",
                             "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while not (journal.exists() and journal.read_bytes().count(b"\n") >= 4):
            assert proc.poll() is None and time.monotonic() < deadline, "the sweep ended before a worker could be killed"
            time.sleep(0.02)
        workers = [p for p in psutil.Process(proc.pid).children(recursive=True)
                   if "spawn_main" in " ".join(p.cmdline())]
        assert workers, "no Dask worker process found"
        workers[0].kill()
        at_kill = journal.read_bytes().count(b"\n")
        _, err = proc.communicate(timeout=180)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert at_kill < 162, "every row was written before the kill: nothing was tested"
    assert proc.returncode == 0, err
    rows = [json.loads(line) for line in journal.read_text().splitlines()]
    assert sorted((r["cell"], r["trial"]) for r in rows) == [(c, t) for c in range(81) for t in range(2)]


def test_a_patch_on_one_code_has_no_noise_not_300_db(tmp_path):
    """A 3-bit ADC puts every pixel of most patches on one code: their SNR is that of a noise-free
    signal (None, "∞"), not 20·log10(mean / rounding's 1e-13) = 315 dB (found by the fault harness)."""
    r = run("simulate", "scenes/d65.toml", "-o", tmp_path / "o", "--renderer", "analytic", *SMALL,
            "--set", "sensor.adc_bits=3", "--quiet")
    assert r.returncode == 0, r.stderr
    report = json.loads((tmp_path / "o" / "report.json").read_text())
    snrs = [v for p in report["patches"] for k, v in p.items() if k.startswith("snr_") and isinstance(v, float)]
    assert snrs and max(snrs) < 200, max(snrs)
