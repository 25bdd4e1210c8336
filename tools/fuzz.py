"""Fuzz spectracam's command line with damaged files, wrong values and faults; count what goes wrong.

    python3 tools/fuzz.py [--cases 120] [--seed 0] [--jobs 2]

Cases: damaged EXR files, wrong scene values, unwritable outputs, garbage TOML, camera curve files
(issue 17: unsorted, NaN, negative, short, narrow, units), spectral EXRs from elsewhere (stripped,
contradicting their scene, units, --white), the validate/cameras commands, and SIGTERM mid-run.

Each case runs one real command in a fresh directory and is judged:
  traceback      a Python traceback on stderr (every failure must be one line);
  partial files  a failed command left something in its output directory (temporary files included);
  silent wrong   the command succeeded on input known to be bad, or wrote a non-finite number.
The last line prints the counts; all three must be 0.
"""
from __future__ import annotations

import argparse
import json
import os
import random
import shutil
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

SCENE = "[image]\nwidth = 64\nheight = 48\n"
CMD = [sys.executable, "-m", "spectracam"]
#: Scene fields and the kinds of wrong values tried for them.
FIELDS = ["illuminant.temperature_K", "illuminant.white_luminance_cd_m2", "image.width", "render.seed",
          "render.samples_per_pixel", "sensor.q_max_e", "sensor.adc_bits", "sensor.read_noise_e",
          "sensor.black_level_DN", "sensor.adc_full_scale_V", "sensor.dsnu_fraction", "filters.cutoffs_nm",
          "filters.qe", "filters.collection_depth_um", "optics.f_number", "capture.architecture",
          "capture.exposure", "processing.demosaic", "wavelengths.step_nm", "chart.mask_margin", "sensor.nosuch",
          "filters.camera", "filters.camera_unit", "capture.white_fill"]
VALUES = ["0", "-1", "1e308", "nan", "inf", "-inf", "1.5", "true", '"text"', "[1, 2]", "[]", "{}", "3", "7",
          "2147483648", "0.001", "bilinear", "fsc", "optimal", "photodiode"]


def run(args, cwd, timeout=300):
    return subprocess.run(CMD + [str(a) for a in args], cwd=cwd, capture_output=True, text=True, timeout=timeout)


def run_killed(args, cwd, after_s: float):
    """Run a command and send it SIGTERM after ``after_s`` (a scheduler's time limit); its result."""
    import signal
    import time

    p = subprocess.Popen(CMD + [str(a) for a in args], cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True)
    time.sleep(after_s)
    p.send_signal(signal.SIGTERM)
    out, err = p.communicate(timeout=300)
    rc = p.returncode
    if rc < 0 and "\nwrote " in "\n" + err:  # it had finished (files renamed) when the signal landed
        rc = 0
    return subprocess.CompletedProcess(p.args, rc, out, err)


def non_finite_outputs(out: Path) -> bool:
    """Does any output hold a NaN/inf (JSON tokens, or EXR pixels)?"""
    for p in out.rglob("*.json"):
        try:
            json.loads(p.read_text(), parse_constant=lambda c: (_ for _ in ()).throw(ValueError(c)))
        except ValueError:
            return True
    import numpy as np

    from spectracam.io.exr import read_exr

    for p in out.rglob("*.exr"):
        channels, _ = read_exr(p)
        if any(not np.all(np.isfinite(c)) for c in channels.values()):
            return True
    return False


def judge(r, out: Path, known_bad: bool) -> dict:
    err = r.stderr.strip().splitlines()
    if r.returncode < 0 and not err:  # killed by the signal while Python itself started: no line can be written
        err = ["(killed before spectracam ran)"]
    left = [p for p in out.rglob("*")] if out.exists() else []
    res = {"traceback": "Traceback" in r.stderr,
           "partial": r.returncode != 0 and bool(left),
           "silent_wrong": r.returncode == 0 and (known_bad or non_finite_outputs(out)),
           "multi_line": r.returncode != 0 and len(err) != 1}
    res["temporaries"] = any(p.name.startswith(".tmp") for p in left)
    res["partial"] = res["partial"] or res["temporaries"]
    return res


def make_base(d: Path):
    (d / "s.toml").write_text(SCENE)
    assert run(["render", "s.toml", "-o", "r", "--renderer", "analytic", "--quiet"], d).returncode == 0
    assert run(["capture", "r/radiance.exr", "-o", "c", "--quiet"], d).returncode == 0


def case_damaged_file(rng, d: Path):
    """A radiance or raw EXR truncated or with bytes flipped, fed to capture/score/inspect."""
    kind = rng.choice(["r/radiance.exr", "c/raw.exr"])
    data = bytearray((d / kind).read_bytes())
    if rng.random() < 0.5:
        data = data[: rng.randrange(0, len(data))]
        how = f"truncated to {len(data)} bytes"
    else:
        for _ in range(rng.choice([1, 4, 64])):
            i = rng.randrange(len(data))
            data[i] = rng.randrange(256)
        how = "bytes flipped"
    (d / "bad.exr").write_bytes(bytes(data))
    cmd = {"r/radiance.exr": ["capture", "bad.exr", "-o", "out"], "c/raw.exr": ["score", "bad.exr", "-o", "out"]}[kind]
    if rng.random() < 0.3:
        cmd = ["inspect", "bad.exr"]
    return cmd, False, f"{kind} {how}: {cmd[0]}"


def case_scene_value(rng, d: Path):
    """A scene field set to a random (often wrong) value, simulated."""
    field, value = rng.choice(FIELDS), rng.choice(VALUES)
    return (["simulate", "s.toml", "-o", "out", "--renderer", "analytic", "--quiet", "--set", f"{field}={value}"],
            False, f"--set {field}={value}")


def case_environment(rng, d: Path):
    """Outputs that cannot be written."""
    (d / "afile").write_text("x")
    target = rng.choice(["afile/sub", "/dev/null", "/proc/version/x"])
    return ["simulate", "s.toml", "-o", target, "--renderer", "analytic"], False, f"-o {target}"


def case_garbage_text(rng, d: Path):
    """Binary garbage or a cut file where a TOML file is expected."""
    g = d / "g.toml"
    g.write_bytes(os.urandom(rng.randrange(1, 4000)) if rng.random() < 0.5 else SCENE.encode()[: rng.randrange(1, 30)])
    cmd = rng.choice([["render", "g.toml", "-o", "out"], ["paper", "-o", "out", "--experiment", "g.toml"],
                      ["sweep", "g.toml", "-o", "out"], ["capture", "r/radiance.exr", "-o", "out", "--config",
                                                         "g.toml"]])
    return cmd, False, f"garbage TOML: {cmd[0]}"


#: Camera curve files (issue 17): (content, known bad).  Every bad one must be refused in one line.
CAMERA_CSVS = [
    ("wl,R,G,B\n380,0.1,0.2,0.3\n550,0.5,1,0.4\n780,0.2,0.1,0.05\n", False),
    ("wl,R,G,B\n500,1,1,1\n450,1,1,1\n780,1,1,1\n", True),  # unsorted
    ("wl,R,G,B\n380,1,1,1\n500,nan,1,1\n780,1,1,1\n", True),
    ("wl,R,G,B\n380,1,1,1\n500,inf,1,1\n780,1,1,1\n", True),
    ("wl,R,G,B\n380,1,1,1\n500,-0.1,1,1\n780,1,1,1\n", True),
    ("wl,R,G,B\n380,1,1,1\n", True),  # too short
    ("wl,R,G\n380,1,1\n780,1,1\n", True),  # three columns
    ("wl,R,G,B\n450,1,1,1\n650,1,1,1\n", True),  # does not cover 400-700 nm
    ("wl,R,G,B\n380,1,0,1\n780,1,0,1\n", True),  # a dark channel
    ("", True), ("\x00\xff\xfe garbage", True), ("wl,R,G,B\n-5,1,1,1\n780,1,1,1\n", True),
]


def case_camera_file(rng, d: Path):
    """A camera's curves (filters.camera_file) damaged, in a unit, or missing; or a camera name."""
    text, bad = rng.choice(CAMERA_CSVS)
    (d / "cam.csv").write_bytes(text.encode("latin-1"))
    sets = ["--set", 'filters.camera_file="cam.csv"' if rng.random() < 0.9 else 'filters.camera_file="nosuch.csv"']
    if sets[1].endswith('nosuch.csv"'):
        bad = True
    unit = rng.choice(["relative", "A/W", "electrons_per_photon", "W/m2", ""])
    if unit:
        sets += ["--set", f'filters.camera_unit="{unit}"']
        bad = bad or unit == "W/m2"
    if rng.random() < 0.2:
        name = rng.choice(["Nikon 5100 (NPL)", "Sigma SDMerill (NPL)", "Canon EOS 5D Mark II (rawtoaces)", "Nokia"])
        sets = ["--set", "filters.kind=camera", "--set", f'filters.camera="{name}"']
        bad = name == "Nokia" or name.startswith("Sigma")  # the Sigma's curves stop at 680 nm
    return ["simulate", "s.toml", "-o", "out", "--renderer", "analytic", "--quiet", *sets], bad, \
        f"camera file {text[:24]!r} {' '.join(sets[1::2])}"


def case_foreign_exr(rng, d: Path):
    """A spectral EXR from elsewhere (spectracam attributes stripped), a contradicting one, or bad metering."""
    import numpy as np

    from spectracam.io.exr import read_exr, write_exr

    ch, at = read_exr(d / "r" / "radiance.exr")
    keep = {k: v for k, v in at.items() if k in ("spectralLayoutVersion", "emissiveUnits") or k.startswith("spectracam")}
    bad, what = False, "stripped"
    r = rng.random()
    if r < 0.35:
        keep = {k: v for k, v in keep.items() if not k.startswith("spectracam")}
    elif r < 0.55:
        scale = rng.choice([0.5, 1.3, 1e3])
        ch = {k: (v * np.float32(scale) if k.startswith("S0.") else v) for k, v in ch.items()}
        bad, what = True, f"pixels x{scale} under their recorded scene"
    elif r < 0.7:
        scene = json.loads(keep["spectracamScene"])
        scene["illuminant"] = {"type": "blackbody", "temperature_K": 3000.0, "white_luminance_cd_m2": 100.0}
        keep["spectracamScene"] = json.dumps(scene)
        bad, what = True, "a 3000 K label"
    units = rng.choice([None, "W.m^-2.sr^-1", "mW.m^-2.sr^-1", "photons", "", "drop"])
    if units == "drop":
        keep.pop("emissiveUnits", None)
        bad, what = True, what + ", no emissiveUnits"
    elif units is not None:
        keep["emissiveUnits"] = units
        bad, what = bad or units in ("photons", ""), what + f", emissiveUnits {units!r}"
    write_exr(d / "f.exr", ch, keep)
    cmd = ["capture", "f.exr", "-o", "out", "--quiet"]
    white = rng.choice([None, "brightest", "patch", "100", "0", "-3", "1,2,3,4", "0,0,9999,9", "nan", "x"])
    if white is not None:
        cmd += ["--white", white]
        stripped = "spectracamScene" not in keep
        bad = bad or white in ("0", "-3", "0,0,9999,9", "nan", "x") or (white == "patch" and stripped)
        what += f", --white {white}"
    return cmd, bad, f"foreign EXR: {what}"


def case_new_commands(rng, d: Path):
    """validate and cameras (issue 17) with unwritable outputs or bad options."""
    (d / "afile").write_text("x")
    cmd = rng.choice([["validate", "-o", "afile/sub"], ["validate", "-o", "/proc/version/x"],
                      ["validate", "-o", "out", "--renderer", "nosuch"], ["cameras", "--nosuch"],
                      ["validate", "-o", "out", "--renderer", "analytic"]])
    return cmd, False, " ".join(cmd)


def case_signal(rng, d: Path):
    """SIGTERM part-way through a command of issue 17 (capture of a foreign file, validate, a camera file)."""
    (d / "cam.csv").write_text(CAMERA_CSVS[0][0])
    cmd = rng.choice([["validate", "-o", "out", "--renderer", "analytic"],
                      ["capture", "r/radiance.exr", "-o", "out", "--white", "brightest"],
                      ["simulate", "s.toml", "-o", "out", "--renderer", "analytic", "--set",
                       'filters.camera_file="cam.csv"']])
    after = rng.choice([0.3, 0.8, 1.5, 2.5])
    return cmd, False, f"SIGTERM after {after} s: {' '.join(cmd)}", after


CASES = [case_damaged_file, case_scene_value, case_environment, case_garbage_text, case_camera_file, case_foreign_exr,
         case_new_commands, case_signal]


def one(i: int, seed: int, base: Path) -> tuple[str, dict]:
    rng = random.Random(seed * 100003 + i)
    with tempfile.TemporaryDirectory() as t:
        d = Path(t)
        shutil.copytree(base, d, dirs_exist_ok=True)
        make = rng.choice(CASES)
        cmd, known_bad, label, *kill = make(rng, d)
        r = run_killed(cmd, d, kill[0]) if kill else run(cmd, d)
        return label, judge(r, d / "out", known_bad) | {"status": r.returncode, "stderr": r.stderr[-400:]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=120)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as t:
        base = Path(t)
        make_base(base)
        with ThreadPoolExecutor(a.jobs) as ex:
            results = list(ex.map(lambda i: one(i, a.seed, base), range(a.cases)))
    counts = {k: sum(r[k] for _, r in results) for k in ("traceback", "partial", "silent_wrong", "multi_line")}
    for label, r in results:
        if r["traceback"] or r["partial"] or r["silent_wrong"] or r["multi_line"]:
            print(f"  {label}: status {r['status']}, " + ", ".join(k for k in counts if r[k]) + f"\n    {r['stderr']}")
    ok = sum(r["status"] == 0 for _, r in results)
    print(f"fuzz: {len(results)} cases ({ok} succeeded, {len(results) - ok} refused), {counts['traceback']} tracebacks, "
          f"{counts['partial']} partial files, {counts['silent_wrong']} silent wrong results, "
          f"{counts['multi_line']} multi-line errors")


if __name__ == "__main__":
    main()
