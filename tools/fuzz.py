"""Fuzz spectracam's command line with damaged files, wrong values and faults; count what goes wrong.

    python3 tools/fuzz.py [--cases 120] [--seed 0] [--jobs 2]

Cases: damaged EXR files, wrong scene values, unwritable outputs, garbage TOML, camera curve files
(issue 17: unsorted, NaN, negative, short, narrow, units), spectral EXRs from elsewhere (stripped,
contradicting their scene, units, --white), the validate/cameras commands, SIGTERM mid-run, textured
targets (issue 19: their values, damaged photographs and measured SPD files), and the architectures of
issue 20 (stacked depths, schemes and demosaickers that do not apply, the architectures command), and the
page of issue 23 (``view DIR`` on bad directories, ``--view`` under faults), and issue 34's new user: each of ten
faults in its bad form (case_user_faults), the same inputs in their valid forms, which must be accepted with their
files written (case_valid), and results checked for physical possibility (case_physical, impossible_outputs); issue
38's snapshot of colour-science's tables damaged, missing or unwritable (case_colour_tables: every run succeeds).
``--only user_faults,valid,physical`` runs only those classes.

Each case runs one real command in a fresh directory and is judged:
  traceback      a Python traceback on stderr (every failure must be one line);
  partial files  a failed command left something in its output directory (temporary files included);
  silent wrong   the command succeeded on input known to be bad, or wrote a non-finite number;
  valid refused  a valid input (case_valid, case_physical) was refused, or a file it must write is missing;
  impossible     a ΔE < 0, non-finite or > 400, a non-finite SNR, an exposure time <= 0, a digital number
                 outside [0, 2^bits - 1], a charge above the full well (impossible_outputs).
The last line prints the counts; every one must be 0.
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
          "sensor.black_level_DN", "sensor.adc_full_scale_V", "sensor.dsnu_fraction", "sensor.temperature_C",
          "sensor.dark_reference_C", "sensor.dark_current_law", "sensor.dark_doubling_K", "sensor.read_noise_uV", "filters.cutoffs_nm",
          "filters.qe", "filters.collection_depth_um", "filters.stacked_depths_um", "optics.f_number", "capture.architecture",
          "capture.exposure", "processing.demosaic", "wavelengths.step_nm", "chart.mask_margin", "sensor.nosuch",
          "filters.camera", "filters.camera_unit", "capture.white_fill", "capture.metering", "capture.metering_target",
          "capture.metering_percentile", "processing.camera", "processing.white_balance", "processing.white_balance_p",
          "processing.white_balance_sigma_px", "processing.white_balance_training", "processing.calibration",
          "processing.tone_curve", "processing.viewing_distance_m", "processing.display_pixel_pitch_mm",
          "filters.stacked_ir_cut_nm", "filters.stacked_ir_cut_width_nm", "filters.camera_gains",
          "filters.camera_xyz_to_camera", "filters.camera_gains_kept", "sensor.hot_pixel_fraction",
          "sensor.hot_pixel_mean_factor", "sensor.readout", "sensor.readout_samples", "sensor.readout_estimator",
          "sensor.motion_threshold_sigma", "sensor.dual_gain_ratio", "sensor.dual_gain_switch", "sensor.split_ratio",
          "sensor.split_small_well_fraction", "sensor.bracketing_frames", "sensor.bracketing_ratio",
          "sensor.companding_bits", "optics.relative_illumination", "optics.exit_pupil_mm", "optics.exit_pupil_form",
          "optics.illumination_height_mm", "optics.illumination_curve", "optics.pa_k", "optics.pa_radius_mm",
          "optics.chief_ray", "optics.cra_corner_deg", "optics.cra_corner_mm", "optics.cra_height_mm",
          "optics.cra_table_deg", "optics.image_circle_diameter_mm", "optics.optical_centre_mm", "pixel.microlens",
          "pixel.stack_height_um", "pixel.stack_index", "pixel.aperture_fraction", "pixel.spot",
          "pixel.microlens_shift_fraction", "pixel.optical_crosstalk", "pixel.electrical_crosstalk",
          "pixel.field_free_depth_um", "pixel.diffusion_length_um", "pixel.filter_angle", "pixel.nosuch",
          "processing.shading", "processing.shading_temperatures_K", "processing.shading_grid",
          "processing.shading_method"]
VALUES = ["0", "-1", "1e308", "nan", "inf", "-inf", "1.5", "true", '"text"', "[1, 2]", "[]", "{}", "3", "7",
          "2147483648", "0.001", "bilinear", "fsc", "optimal", "photodiode", "developed", "percentile", "grey_edge",
          "dual_illuminant", "corrected_moments", "colorchecker24", "filmic", '"none"', "[5.9, 5.95, 6.0, 6.05]",
          "[1, 0, 1]", "[0.0001, 0.0002, 0.0003, 100]", '"multiple_capture"', '"dual_gain"', '"split_pixel"',
          '"bracketing"', '"last_sample"', "12", "1024", "1025", "0.999", '"cos4"', '"exit_pupil"', '"pa"', '"disk"',
          "85", "[-0.3, 0.1, 0.0]", "[0, 0.5, 1]", '"tophat"', '"gaussian"', "25"]


#: A case that runs longer than this hangs (counted as such, then killed).
HANG_S = 240


def _limits(fsize: int | None = None, address_space: int | None = None):
    """A preexec function setting a file-size limit (a full disk: writes fail with EFBIG, which Python
    does not turn into SIGXFSZ) and/or an address-space limit (prlimit --as)."""
    def apply():
        import resource

        os.setsid()  # its own process group: the harness can signal the group and find orphans
        if fsize is not None:
            resource.setrlimit(resource.RLIMIT_FSIZE, (fsize, fsize))
        if address_space is not None:
            resource.setrlimit(resource.RLIMIT_AS, (address_space, address_space))
    return apply


def group_members(pgid: int) -> list[int]:
    """Live processes of a process group (Linux /proc): what is left of a command after it ended."""
    out = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                stat = (d / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(stat[2]) == pgid and stat[0] != "Z":
                out.append(int(d.name))
    return out


def run(args, cwd, timeout=HANG_S, opts=None):
    """Run one command; ``opts``: ``kill`` (seconds, then SIGTERM or ``signal``; ``group``: to the whole
    process group), ``fsize`` and ``address_space`` limits, ``drop_caps`` (run without capabilities
    when root), ``env`` (variables to set).  Returns the result and whether processes of
    its group outlived it (orphans) or it hung."""
    import signal
    import time

    opts = opts or {}
    prefix = []
    if opts.get("drop_caps") and os.geteuid() == 0 and shutil.which("setpriv"):
        # root writes anywhere (CAP_DAC_OVERRIDE): without capabilities the permission bits hold for it too
        prefix = ["setpriv", "--bounding-set=-all", "--inh-caps=-all"]
    env = {**os.environ, **opts["env"]} if "env" in opts else None
    p = subprocess.Popen(prefix + CMD + [str(a) for a in args], cwd=cwd, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, env=env,
                         preexec_fn=_limits(opts.get("fsize"), opts.get("address_space")))
    hung = False
    if "kill" in opts:
        time.sleep(opts["kill"])
        sig = opts.get("signal", signal.SIGTERM)
        try:
            os.killpg(p.pid, sig) if opts.get("group") else p.send_signal(sig)
        except ProcessLookupError:
            pass
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        hung = True
        os.killpg(p.pid, signal.SIGKILL)
        out, err = p.communicate()
    rc = p.returncode
    if rc < 0 and "\nwrote " in "\n" + err:  # it had finished (files renamed) when the signal landed
        rc = 0
    deadline = time.time() + 3
    orphans = group_members(p.pid)
    while orphans and time.time() < deadline:
        time.sleep(0.1)
        orphans = group_members(p.pid)
    for pid in orphans:
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass
    return subprocess.CompletedProcess(p.args, rc, out, err), bool(orphans), hung


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


def absurd_outputs(out: Path) -> bool:
    """Finite but impossible numbers in a report: an SNR in dB above the 8-24-bit ADC's reach (> 200 dB; the
    datasheet's linear SNRs and signals in electrons at SNR 10 are not dB), a
    ΔE*ab above 500, a negative ΔE or time."""
    for p in out.rglob("*.json"):
        try:
            d = json.loads(p.read_text())
        except ValueError:
            continue
        stack = [d]
        while stack:
            x = stack.pop()
            if isinstance(x, dict):
                for k, v in x.items():
                    if isinstance(v, (int, float)) and not isinstance(v, bool):
                        if ("snr" in k and k.endswith("_db") and v > 200) or (k.startswith("delta_e") and not 0 <= v <= 500) or \
                                (k.endswith(("_ms", "_s")) and v < 0):
                            return True
                    else:
                        stack.append(v)
            elif isinstance(x, list):
                stack.extend(x)
    return False


def snapshot(out: Path) -> dict:
    """What an output directory holds before a command: path → (size, mtime)."""
    return {p: (p.stat().st_size, p.stat().st_mtime_ns) for p in out.rglob("*")} if out.exists() else {}


#: What an interrupted or refused sweep may leave on purpose: its journal and header, so that
#: ``--resume`` continues it (and the same command without --resume is refused, not overwritten).
SWEEP_JOURNAL = ("sweep.json", "results.jsonl")


def judge(r, out: Path, known_bad: bool, before: dict | None = None, command: str = "") -> dict:
    """Tracebacks; leftovers (files a failed command made or changed — a sweep's journal aside —
    and temporary files); silent wrong results; an error that is not exactly one ``spectracam:`` line,
    the last (progress lines before it are fine)."""
    lines = r.stderr.strip().splitlines()
    said = [x for x in lines if x.startswith(("spectracam: error:", "spectracam: interrupted"))]
    one_line = len(said) == 1 and lines[-1] == said[0]
    if r.returncode < 0 and not lines:  # killed by the signal while Python itself started: no line can be written
        one_line = True
    before = before or {}
    left = [p for p in out.rglob("*")] if out.exists() else []
    made = [p for p in left if p.is_file() and before.get(p) != (p.stat().st_size, p.stat().st_mtime_ns)
            and not (command == "sweep" and p.name in SWEEP_JOURNAL)]
    # `view` reads a directory it did not write (possibly damaged on purpose): only its page is its own
    scan = command != "view"
    res = {"traceback": "Traceback" in r.stderr,
           "partial": r.returncode != 0 and bool(made),
           "silent_wrong": r.returncode == 0 and (known_bad or (scan and (non_finite_outputs(out)
                                                                          or absurd_outputs(out)))),
           "multi_line": r.returncode != 0 and not one_line}
    res["temporaries"] = any(p.name.startswith(".tmp") for p in left)
    res["partial"] = res["partial"] or res["temporaries"]
    return res


SWEEP = ('base_scene = "s.toml"\nrenderer = "analytic"\ntrials = 2\nseed = 3\n'
         'metrics = ["delta_e_mean", "snr_combined_db"]\n[axes]\n"sensor.read_noise_e" = [10, 20, 30]\n')


def make_base(d: Path):
    (d / "s.toml").write_text(SCENE)
    (d / "sw.toml").write_text(SWEEP)
    os.environ["SPECTRACAM_TABLES"] = str(d / "tables")   # every case's commands read one snapshot, made here
    for cmd in (["render", "s.toml", "-o", "r", "--renderer", "analytic", "--quiet"],
                ["capture", "r/radiance.exr", "-o", "c", "--quiet"],
                ["sweep", "sw.toml", "-o", "sw", "--serial", "--quiet"]):
        r, _, _ = run(cmd, d)
        assert r.returncode == 0, r.stderr
    assert list((d / "tables").glob("colour-science-*.npz")), "make_base: no snapshot of colour-science's tables"


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


def case_reflectances(rng, d: Path):
    """The held-out library (issue 19): a wrong name, a missing file, or a CSV of spectra that is cut,
    ragged, binary, in percent, non-finite, decreasing or short of the scene's range."""
    kind = rng.choice(["name", "missing", "cut", "ragged", "binary", "percent", "nan", "decreasing", "short", "good",
                       "sweep_none"])
    if kind == "sweep_none":   # a sweep asking for held-out metrics with the held-out library switched off
        (d / "ho.toml").write_text(SWEEP.replace('metrics = ["delta_e_mean", "snr_combined_db"]',
                                                 'metrics = ["held_out_delta_e_mean"]'))
        return (["sweep", "ho.toml", "-o", "out", "--serial", "--quiet", "--set", "processing.held_out=none"], False,
                "held_out sweep_none")
    rows = "wavelength_nm,a,b\n380,0.1,0.2\n580,0.3,0.4\n780,0.5,0.6\n"
    text = {"cut": rows[: rng.randrange(1, len(rows))], "ragged": rows + "790,0.1\n",
            "percent": rows.replace("0.", "9"), "nan": rows.replace("0.4", "nan"),
            "decreasing": "wavelength_nm,a\n780,0.1\n380,0.2\n", "short": "wavelength_nm,a\n450,0.1\n650,0.2\n",
            "good": rows}.get(kind)
    if kind == "binary":
        (d / "r.csv").write_bytes(os.urandom(rng.randrange(1, 3000)))
    elif text is not None:
        (d / "r.csv").write_text(text)
    value = {"name": rng.choice(["CFI99", "munsell", "", "file:"]), "missing": "file:nope.csv"}.get(kind, "file:r.csv")
    cmd = ["simulate", "s.toml", "-o", "out", "--renderer", "analytic", "--quiet", "--set",
           f"processing.held_out={value}"]
    return cmd, False, f"held_out {kind}: {value}"


def case_environment(rng, d: Path):
    """Outputs that cannot be written."""
    (d / "afile").write_text("x")
    target = rng.choice(["afile/sub", "/dev/null", "/proc/version/x"])
    return ["simulate", "s.toml", "-o", target, "--renderer", "analytic"], False, f"-o {target}"


def case_read_only(rng, d: Path):
    """A read-only output directory (written into, or a new one made inside it), or a read-only render
    cache (documented never to stop a run), with root's capabilities dropped so that the permission
    bits hold as for any user."""
    cmd = rng.choice([["render", "s.toml", "--renderer", "analytic"], ["simulate", "s.toml", "--renderer", "analytic"],
                      ["capture", "r/radiance.exr"], ["score", "c/raw.exr"], ["emva"],
                      ["paper", "--quick", "--renderer", "analytic"], ["sweep", "sw.toml", "--serial"],
                      ["validate", "--renderer", "analytic"], ["motion", "--quick", "--renderer", "analytic"],
                      ["motion", "--quick", "--renderer", "analytic", "--no-images"]])
    where = rng.choice(["out", "out/new", "cache"])
    if where == "cache":
        (d / "cache").mkdir(mode=0o555)
        os.chmod(d / "cache", 0o555)
        return ([cmd[0], "-o", "out", *cmd[1:], "--quiet"], False, f"read-only render cache: {cmd[0]}",
                {"drop_caps": True, "env": {"SPECTRACAM_CACHE": str(d / "cache" / "renders")}})
    (d / "out").mkdir()
    os.chmod(d / "out", 0o555)
    return [cmd[0], "-o", where, *cmd[1:]], False, f"read-only -o {where}: {cmd[0]}", {"drop_caps": True}


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
    bad, what, scale = False, "stripped", None
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
        if scale == 1e3 and units == "mW.m^-2.sr^-1":   # ×1000 in milliwatts is the recorded radiance: right
            bad = False
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


def case_full_disk(rng, d: Path):
    """Every write beyond a few kB fails (RLIMIT_FSIZE: EFBIG, as a full disk), for a command that writes."""
    cmd = rng.choice([["render", "s.toml", "-o", "out", "--renderer", "analytic"],
                      ["simulate", "s.toml", "-o", "out", "--renderer", "analytic"],
                      ["capture", "r/radiance.exr", "-o", "out"], ["score", "c/raw.exr", "-o", "out"],
                      ["emva", "-o", "out"], ["validate", "-o", "out", "--renderer", "analytic"],
                      ["paper", "--quick", "--renderer", "analytic", "-o", "out"]])
    size = rng.choice([0, 2_000, 20_000, 200_000])
    return cmd, False, f"full disk ({size} B files): {cmd[0]}", {"fsize": size}


def case_memory_limit(rng, d: Path):
    """An address-space limit (prlimit --as) under a scene or sweep too large for it."""
    limit = rng.choice([2, 3, 4]) * 2**30
    w = rng.choice([3000, 6000, 9000])
    cmd = rng.choice([["render", "s.toml", "-o", "out", "--renderer", "analytic"],
                      ["simulate", "s.toml", "-o", "out", "--renderer", "analytic"],
                      ["paper", "-o", "out", "--renderer", "analytic"], ["motion"]])
    if cmd == ["motion"]:   # a moving edge w px wide, rendered at 4 sub-pixels a side, under the same limit
        w //= 4
        cmd = ["motion", "--quick", "-o", "out", "--renderer", "analytic", "--set", f"edge_size_px=[{w}, {w}]"] \
            + rng.choice([[], ["--no-images"]])
    else:
        cmd += ["--set", f"image.width={w}", "--set", f"image.height={w * 3 // 4}"]
    return cmd, False, f"memory limit {limit >> 30} GiB, {w} px: {cmd[0]}", {"address_space": limit}


def case_raw_attributes(rng, d: Path):
    """A raw EXR whose attributes are damaged or contradict each other or its scene, scored."""
    import numpy as np

    from spectracam.io.exr import double, read_exr, write_exr

    ch, at = read_exr(d / "c" / "raw.exr")
    keep = {k: v for k, v in at.items() if k.startswith("spectracam")}
    scene = json.loads(keep["spectracamScene"])
    edit = rng.choice(["scale0", "offset", "bits", "pattern", "arch", "capture_time", "times", "scene_light",
                       "scene_level", "camera_json", "layout_json"])
    if edit == "scale0":
        keep["spectracamDnScale"] = 0.0
    elif edit == "offset":
        keep["spectracamDnOffset"] = 3.0
    elif edit == "bits":
        keep["spectracamAdcBits"] = 12
    elif edit == "pattern":
        keep["spectracamCfaPattern"] = "BGGR"
    elif edit == "arch":
        keep["spectracamArchitecture"] = "fsc"
    elif edit == "capture_time":
        keep["spectracamCaptureTimeS"] = double(rng.choice([-1.0, 0.0, 1e9]))
    elif edit == "times":
        keep["spectracamExposureTimesS"] = np.array([0.01, -0.01, 0.01])
    elif edit == "scene_light":
        scene["illuminant"] = {"type": "blackbody", "temperature_K": 3000.0, "white_luminance_cd_m2": 100.0}
        keep["spectracamScene"] = json.dumps(scene)
    elif edit == "scene_level":
        scene["illuminant"]["white_luminance_cd_m2"] = 37.0
        keep["spectracamScene"] = json.dumps(scene)
    elif edit == "camera_json":
        keep["spectracamCamera"] = "{not json"
    else:
        keep["spectracamLayout"] = json.dumps({"kind": "mosaic", "tile": [[0, 1], [1, 2]], "pattern": "RGBG"})
    write_exr(d / "bad.exr", ch, keep)
    return ["score", "bad.exr", "-o", "out"], True, f"raw attribute {edit}: score"


def case_journal(rng, d: Path):
    """A sweep journal with rows that cannot belong, a damaged sweep.json, or a bad sweep file, resumed."""
    shutil.copytree(d / "sw", d / "out")
    j = d / "out" / "results.jsonl"
    lines = j.read_text().splitlines()
    row = json.loads(lines[0])
    edit = rng.choice(["cell", "trial", "dup", "nan", "text", "param", "seed", "garbage", "meta", "axis_nan",
                       "axis_tiny"])
    cmd, bad = ["sweep", "sw.toml", "-o", "out", "--serial", "--resume", "--quiet"], False
    if edit in ("cell", "trial", "nan", "text", "param", "seed"):
        row.update({"cell": 9999} if edit == "cell" else {"trial": 99} if edit == "trial" else
                   {"delta_e_mean": float("nan")} if edit == "nan" else {"delta_e_mean": "five"} if edit == "text"
                   else {"sensor.read_noise_e": 0.0} if edit == "param" else {"seed": 1})
        lines[0] = json.dumps(row)
    elif edit == "dup":
        lines.append(lines[0])
    elif edit == "garbage":
        lines.insert(1, "{garbage")
    elif edit == "meta":
        (d / "out" / "sweep.json").write_text("{damaged")
        bad = True
    elif edit in ("axis_nan", "axis_tiny"):
        stop, step = ("nan", 10) if edit == "axis_nan" else (20, "1e-300")
        (d / "sw.toml").write_text(SWEEP.replace("[10, 20, 30]", f"{{ start = 10, stop = {stop}, step = {step} }}"))
        bad = True
    j.write_text("\n".join(lines) + "\n")
    return cmd, bad, f"sweep journal: {edit}"


def case_experiment_values(rng, d: Path):
    """Wrong values for the experiments' own keys (emva, spatial, motion, consistency, paper, sweep)."""
    cases = [
        (["emva", "-o", "out", "--channel", "R"], True), (["emva", "-o", "out", "--wavelength", "nan"], True),
        (["emva", "-o", "out", "--wavelength", "1000"], True),
        (["emva", "-o", "out", "--set", "sensor.q_max_e=1"], False),
        (["motion", "--quick", "-o", "out", "--set", "speeds_px_per_ms=[nan]"], True),
        (["motion", "--quick", "-o", "out", "--set", "speeds_px_per_ms=[-1]"], True),
        (["motion", "--quick", "-o", "out", "--set", "nosuch=1"], True),
        (["spatial", "--quick", "-o", "out", "--set", "pixel_pitches_um[7]=3"], True),
        (["spatial", "--quick", "-o", "out", "--set", "targets=['nosuch']"], True),
        (["spatial", "--quick", "-o", "out", "--set", "olpf_separations_px=[-1]"], True),
        (["spatial", "--quick", "-o", "out", "--set", "olpf_separations_px=[99]"], True),
        (["spatial", "--quick", "-o", "out", "--set", "olpf_separations_px=[]"], True),
        (["spatial", "--quick", "-o", "out", "--set", "designs=['nosuch/single']"], True),
        (["spatial", "--quick", "-o", "out", "--set", "designs=[]"], True),
        (["spatial", "--quick", "-o", "out", "--set", "designs=['rgbw/single']", "--set", "demosaics=['menon2007']"],
         True),
        (["motion", "--quick", "-o", "out", "--set", "designs=['stacked/optimal']"], True),
        (["motion", "--quick", "-o", "out", "--set", "seeds=0"], True),
        (["motion", "--quick", "-o", "out", "--set", "seeds=2.5"], True),
        (["consistency", "-o", "out", "--set", "temperatures_K=[]"], True),
        (["paper", "--quick", "-o", "out", "--set", "light.white_luminance_cd_m2=-5"], True),
        (["paper", "--quick", "-o", "out", "--set", "temperatures_K=[1e9]"], True),
        (["sweep", "sw.toml", "-o", "out", "--scheduler", "http://127.0.0.1:9"], True),
        (["sweep", "sw.toml", "-o", "out", "--scheduler", "tcp://127.0.0.1:1"], True),
        (["render", "s.toml", "-o", ""], True),
    ]
    cmd, bad = rng.choice(cases)
    return cmd, bad, " ".join(cmd)


def case_group_signal(rng, d: Path):
    """SIGTERM/SIGHUP/SIGINT to the command or to its whole process group mid-run: no leftovers, no orphans."""
    import signal

    cmd = rng.choice([["paper", "--quick", "--renderer", "analytic", "-o", "out"],
                      ["sweep", "sw.toml", "-o", "out", "--quiet"],
                      ["simulate", "s.toml", "-o", "out", "--renderer", "analytic"],
                      ["validate", "-o", "out", "--renderer", "analytic"]])
    sig = rng.choice([signal.SIGTERM, signal.SIGHUP, signal.SIGINT])
    group = rng.random() < 0.5
    after = rng.choice([0.5, 1.5, 3.0, 5.0])
    return cmd, False, f"{sig.name} to {'group' if group else 'process'} after {after} s: {cmd[0]}", \
        {"kill": after, "signal": sig, "group": group}


def case_scheduler_peer(rng, d: Path):
    """A --scheduler address whose peer is not Dask (an HTTP server, a peer that talks first), loopback only."""
    import socket
    import threading

    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(4)
    talk = rng.random() < 0.5

    def serve():
        try:
            c, _ = srv.accept()
            if talk:
                c.sendall(b"\xff" * 64 + b"SSH-2.0-OpenSSH\r\n")
            threading.Timer(20, c.close).start()
        except OSError:
            pass
        finally:
            threading.Timer(25, srv.close).start()

    threading.Thread(target=serve, daemon=True).start()
    return (["sweep", "sw.toml", "-o", "out", "--scheduler", f"tcp://127.0.0.1:{srv.getsockname()[1]}", "--quiet"],
            True, f"scheduler peer that {'talks' if talk else 'is silent'}")


TARGET_FIELDS = ["kind", "library", "supersampling", "seed", "samples", "columns", "gap", "count", "size_min_px",
                 "size_max_px", "exponent", "photo", "photo_sha256", "viewing_distance_m", "display_pixel_pitch_mm",
                 "interior_margin_px", "nosuch"]
TARGET_VALUES = VALUES + ['"dead_leaves"', '"mondrian"', '"samples"', '"photo"', '"chart"', '"cfi99"', '"file:r.csv"',
                          '"grace_hopper"', '"file:p.png"', "[0, 98]", "[99]", "16", "17", "100000000"]


def case_target(rng, d: Path):
    """A textured target (issue 19): a wrong [target] value, a damaged photograph, a damaged measured SPD
    file, SIGTERM or a full disk part-way through, or a capture scored against another target."""
    kind = rng.choice(["dead_leaves", "mondrian", "samples", "photo"])
    (d / "t.toml").write_text(SCENE + f'[target]\nkind = "{kind}"\nsize_max_px = 20\n')
    base = ["simulate", "t.toml", "-o", "out", "--quiet"] + (["--renderer", "analytic"] if rng.random() < 0.7 else [])
    how = rng.choice(["value", "value", "photo", "spd", "signal", "full_disk", "other_target"])
    if how == "value":
        field, value = rng.choice(TARGET_FIELDS), rng.choice(TARGET_VALUES)
        (d / "p.png").write_bytes((d / "r.csv").read_bytes() if (d / "r.csv").exists() else b"not an image")
        return base + ["--set", f"target.{field}={value}"], False, f"{kind}: --set target.{field}={value}"
    if how == "photo":
        import io

        import numpy as np
        from PIL import Image

        buf = io.BytesIO()
        pixels = np.full((rng.choice([1, 4, 40]), 30, 3), rng.randrange(256), np.uint8)
        Image.fromarray(pixels).save(buf, format=rng.choice(["PNG", "JPEG", "TIFF"]))
        data = bytearray(buf.getvalue())
        damage = rng.choice(["truncated", "flipped", "empty", "text", "whole"])
        if damage == "truncated":
            data = data[: rng.randrange(0, len(data))]
        elif damage == "flipped":
            for _ in range(rng.choice([1, 8, 64])):
                data[rng.randrange(len(data))] = rng.randrange(256)
        elif damage == "empty":
            data = bytearray()
        elif damage == "text":
            data = bytearray(b"P3\n# not what it says\n")
        (d / "p.png").write_bytes(bytes(data))
        return (["simulate", "t.toml", "-o", "out", "--quiet", "--renderer", "analytic", "--set", 'target.kind="photo"',
                 "--set", 'target.photo="file:p.png"'], False, f"photo {damage}")
    if how == "spd":
        rows = "wavelength_nm,power\n380,1\n550,2\n780,1.5\n"
        damage = rng.choice(["cut", "negative", "nan", "decreasing", "micrometres", "binary", "zeros", "short", "good"])
        text = {"cut": rows[: rng.randrange(1, len(rows))], "negative": rows.replace("2", "-2"),
                "nan": rows.replace("2", "nan"), "decreasing": "780,1\n550,1\n380,1\n",
                "micrometres": "0.38,1\n0.55,1\n0.78,1\n", "zeros": "380,0\n550,0\n780,0\n",
                "short": "450,1\n550,1\n650,1\n", "good": rows}.get(damage)
        if text is None:
            (d / "l.csv").write_bytes(os.urandom(rng.randrange(1, 2000)))
        else:
            (d / "l.csv").write_text(text)
        return base + ["--set", 'illuminant.file="l.csv"'], False, f"{kind} under a measured SPD ({damage})"
    if how == "signal":
        after = rng.choice([0.5, 1.5, 3.0])
        return base, False, f"{kind}: SIGTERM after {after} s", after
    if how == "full_disk":
        size = rng.choice([0, 2_000, 20_000, 200_000])
        return base, False, f"{kind}: full disk ({size} B files)", {"fsize": size}
    r, _, _ = run(["simulate", "t.toml", "-o", "first", "--renderer", "analytic", "--quiet"], d)
    assert r.returncode == 0, r.stderr
    return (["score", "first/raw.exr", "-o", "out", "--set", f"target.seed={rng.randrange(1, 9)}"], True,
            f"{kind} scored as another target")


def case_architectures(rng, d: Path):
    """Issue 20: the new architectures' options and the architectures command — bad values, exposure
    schemes that do not apply, demosaickers that cannot, a full disk, SIGTERM part-way."""
    cases = [
        (["simulate", "s.toml", "-o", "out", "--renderer", "analytic", "--arch", "stacked", "--exposure", "optimal"],
         True),
        (["simulate", "s.toml", "-o", "out", "--renderer", "analytic", "--arch", "rgbw", "--demosaic", "menon2007"],
         True),
        (["simulate", "s.toml", "-o", "out", "--renderer", "analytic", "--arch", "stacked", "--set",
          "filters.stacked_depths_um=[1, 0.5, 2]"], True),
        (["simulate", "s.toml", "-o", "out", "--renderer", "analytic", "--arch", "stacked", "--set",
          "filters.stacked_depths_um=[0.3, nan, 2]"], True),
        (["simulate", "s.toml", "-o", "out", "--renderer", "analytic", "--arch", "stacked", "--set",
          "filters.stacked_depths_um=[0.3]"], True),
        (["simulate", "s.toml", "-o", "out", "--renderer", "analytic", "--arch", "stacked", "--set",
          "filters.stacked_depths_um=[0.3, 1, 2, 1e9]"], True),
        (["simulate", "s.toml", "-o", "out", "--renderer", "analytic", "--arch", rng.choice(["ryyb", "cmy", "quad_bayer",
                                                                                            "rgbw", "stacked"])], False),
        (["capture", "r/radiance.exr", "-o", "out", "--arch", "nosuch"], True),
        (["architectures", "-o", "out", "--quick", "--renderer", "analytic", "--seeds", "0"], True),
        (["architectures", "-o", "out", "--quick", "--renderer", "analytic", "--seeds", "x"], True),
        (["architectures", "-o", "out", "--quick", "--renderer", "analytic", "--set", "temperatures_K=[]"], True),
        (["architectures", "-o", "out", "--quick", "--renderer", "nosuch"], True),
    ]
    cmd, bad = rng.choice(cases)
    fault = rng.choice(["none", "none", "disk", "signal"])
    if fault == "disk" and not bad:
        return cmd, False, f"full disk: {' '.join(cmd)}", {"fsize": rng.choice([0, 20_000])}
    if fault == "signal" and not bad:
        return cmd, False, f"SIGTERM: {' '.join(cmd)}", rng.choice([0.5, 1.5, 3.0])
    return cmd, bad, " ".join(cmd)


def _with_fault(rng, cmd: list, bad: bool):
    """A case's command as it is (a known-bad one), or a good one run under a full disk or SIGTERM at random."""
    fault = rng.choice(["none", "disk", "signal"])
    if fault == "disk" and not bad:
        return cmd, False, f"full disk: {' '.join(cmd)}", {"fsize": rng.choice([0, 20_000, 200_000])}
    if fault == "signal" and not bad:
        return cmd, False, f"SIGTERM: {' '.join(cmd)}", rng.choice([1.0, 3.0, 6.0])
    return cmd, bad, " ".join(cmd)


def case_spacetime(rng, d: Path):
    """Issue 21: spatial's new keys (targets, references, e-SFR, seeds, zone plates) and motion's e-SFR option
    — bad values; a small spatial run that writes every case's EXR/PNG/error map under a full disk or SIGTERM."""
    small = ["spatial", "-o", "out", "--quick", "--renderer", "analytic", "--set", "pixel_pitches_um=[10]",
             "--set", "f_numbers=[1.4]", "--set", "designs=['cfa/single', 'fsc/optimal']", "--set", "demosaics=['bilinear']"]
    cases = [
        (small + ["--set", "reference='nosuch'"], True), (small + ["--set", "esfr_correct_binning=2"], True),
        (small + ["--set", "seeds=0"], True), (small + ["--set", "seeds=1.5"], True),
        (small + ["--set", "zone_plate_size_px=[8, 8]"], True), (small + ["--set", "zone_plate_max_cy_per_px=-1"], True),
        (small + ["--set", "zone_plate_max_cy_per_px=nan"], True), (small + ["--set", "targets=['edge_nosuch']"], True),
        (small + ["--set", "targets=[]"], True),
        (["motion", "--quick", "-o", "out", "--renderer", "analytic", "--set", "esfr_correct_binning='yes'"], True),
        (small + ["--set", "targets=['zone_plate', 'edge_red_cyan']"], False),
        (small + ["--set", "targets=['zone_plate_chroma', 'edge']", "--set", "noise=true", "--set", "seeds=2",
                  "--set", "reference='footprint'", "--set", "esfr_correct_binning=true"], False),
    ]
    return _with_fault(rng, *rng.choice(cases))


def case_design(rng, d: Path):
    """Issue 22: design files with bad values, damaged or missing (one line, exit 2); a quick design under a full
    disk or SIGTERM (nothing half-written)."""
    quick = ["design", "design.toml", "-o", "out", "--quick", "--set", "renderer='analytic'", "--set",
             "max_iterations=3", "--set", "designs=['cfa/single']"]
    bad_file = d / "bad_design.toml"
    text = rng.choice(["lights = [3000\n", "\x00\xff\xfe", "designs = 3\n", "filters = 'depths'\n",
                       "experiment = 'nosuch.toml'\n", "held_out = 'file:nosuch.csv'\n", "snr_weight = -1\n",
                       "image_px = [320]\n", "start_cutoffs_nm = [610, 490]\n"])
    bad_file.write_bytes(text.encode("latin-1"))
    cases = [
        (quick + ["--set", "lights=[]"], True), (quick + ["--set", "lights=['D99']"], True),
        (quick + ["--set", "designs=['cfa/optimal']"], True), (quick + ["--set", "designs=['stacked/split']"], True),
        (quick + ["--set", "filters='nosuch'"], True), (quick + ["--set", "training='nosuch'"], True),
        (quick + ["--set", "knot_step_nm=nan"], True), (quick + ["--set", "min_transmittance=2"], True),
        (quick + ["--set", "seeds=0"], True), (quick + ["--set", "max_iterations=0"], True),
        (quick + ["--set", "tolerance=0"], True), (quick + ["--set", "nosuch=1"], True),
        (["design", str(bad_file), "-o", "out"], True), (["design", "nosuch.toml", "-o", "out"], True),
        (quick + ["--set", "white_balance='corrected_moments'"], True), (quick + ["--set", "white_balance_p=0"], True),
        (quick + ["--set", "developed=2"], True),
        (quick + ["--set", "white_balance='shades_of_grey'", "--set", "developed=false"], False),
        (quick, False), (quick + ["--set", "filters='block'", "--set", "designs=['fsc/split', 'stacked/single']"], False),
    ]
    return _with_fault(rng, *rng.choice(cases))


def case_view(rng, d: Path):
    """Issue 23: ``spectracam view DIR`` on a directory that is missing, a file, empty, unreadable, holds only
    foreign files or a damaged output — and on real outputs under a full disk or a signal; ``--view`` on commands
    that write a directory, under the same faults (the page belongs to the outputs: all or nothing)."""
    kind = rng.choice(["missing", "file", "empty", "unreadable", "foreign", "damaged", "good", "flag"])
    if kind == "missing":
        return ["view", "nosuch"], True, "view: a missing directory"
    if kind == "file":
        (d / "afile").write_text("x")
        return ["view", "afile"], True, "view: a file"
    (d / "out").mkdir()
    if kind == "empty":
        return ["view", "out"], True, "view: an empty directory"
    if kind == "unreadable":   # mode 000 while the command runs (one() sets and restores it)
        shutil.copytree(d / "c", d / "out", dirs_exist_ok=True)
        return ["view", "out"], True, "view: an unreadable directory", {"drop_caps": True, "chmod": 0o000}
    if kind == "foreign":
        (d / "out" / "notes.txt").write_text("not spectracam's")
        (d / "out" / "picture.png").write_bytes(os.urandom(rng.randrange(1, 2000)))
        return ["view", "out"], True, "view: only foreign files"
    source = rng.choice(["r", "c", "sw"])
    if kind == "damaged":
        shutil.copytree(d / source, d / "out", dirs_exist_ok=True)
        victim = rng.choice([p for p in (d / "out").iterdir() if p.is_file()])
        data = victim.read_bytes()
        victim.write_bytes(data[: rng.randrange(0, max(1, len(data)))])
        return ["view", "out"], False, f"view: {source}'s outputs, {victim.name} truncated"
    if kind == "good":
        shutil.copytree(d / source, d / "out", dirs_exist_ok=True)
        return _with_fault(rng, ["view", "out"], False)
    (d / "out").rmdir()
    cmd = rng.choice([["simulate", "s.toml", "-o", "out", "--renderer", "analytic", "--view"],
                      ["render", "s.toml", "-o", "out", "--renderer", "analytic", "--view", "--quiet"],
                      ["capture", "r/radiance.exr", "-o", "out", "--view"],
                      ["score", "c/raw.exr", "-o", "out", "--view"],
                      ["sweep", "sw.toml", "-o", "out", "--serial", "--view"],
                      ["emva", "-o", "out", "--view"],
                      ["paper", "--quick", "--renderer", "analytic", "-o", "out", "--view"],
                      ["plot-sweep", "out", "--view"]])
    if cmd[0] == "plot-sweep":
        shutil.copytree(d / "sw", d / "out")
    return _with_fault(rng, cmd, False)


def case_developed(rng, d: Path):
    """Issue 33: the camera that finds its own white — bad metering/white-balance/calibration values, contradicting
    combinations (a trained estimator whose training set is the scored chart, so nothing is left to train on; an
    empty or damaged training CSV), and good developed runs (simulate, capture + score, a sweep over the white
    balance) under a full disk or SIGTERM."""
    dev = ["--set", "processing.camera='developed'"]
    sim = ["simulate", "s.toml", "-o", "out", "--renderer", "analytic", "--quiet"]
    empty = d / "empty.csv"
    empty.write_text(rng.choice(["wavelength_nm\n", "wavelength_nm,a\n400,0.5\n", "", "\x00\xff",
                                 "wavelength_nm,a,b\n400,0.5\n700,x,0.2\n"]))
    sweep = d / "wb_sweep.toml"
    sweep.write_text((d / "sw.toml").read_text().split("[axes]")[0] + '[scene]\nprocessing = { camera = "developed" }\n'
                     '[axes]\n"processing.white_balance" = ["grey_world", "grey_edge"]\n')
    cases = [
        (sim + ["--set", "processing.camera='nosuch'"], True),
        (sim + ["--set", "processing.white_balance='max_rgb'"], True),
        (sim + ["--set", "processing.calibration='triple'"], True),
        (sim + ["--set", "capture.metering='spot'"], True),
        (sim + ["--set", "capture.metering_percentile=101"], True),
        (sim + ["--set", "capture.metering_target=0"], True),
        (sim + ["--set", "processing.white_balance_p=nan"], True),
        (sim + dev + ["--set", "processing.white_balance_training='colorchecker24'"], True),
        (sim + dev + ["--set", f"processing.white_balance_training='file:{empty}'"], True),
        (sim + dev, False),
        (sim + dev + ["--set", "processing.white_balance='grey_edge'", "--set", "capture.metering='average'"], False),
        (sim + ["--set", "processing.white_balance='white_patch'", "--set", "processing.calibration='dual_illuminant'"],
         False),
        (["capture", "r/radiance.exr", "-o", "out", "--quiet"] + dev, False),
        (["score", "c/raw.exr", "-o", "out", "--quiet"] + dev, False),
        (["sweep", str(sweep), "-o", "out", "--serial", "--quiet"], False),
    ]
    return _with_fault(rng, *rng.choice(cases))


def case_white_balance(rng, d: Path):
    """Issue 33: ``spectracam white-balance`` — bad --seeds, --renderer and --set values, a trained estimator whose
    training set is too small once the scored colours are removed, a grid the Sigma's curves leave one band of; a
    small quick run under a full disk or SIGTERM (nothing half-written)."""
    quick = ["white-balance", "-o", "out", "--quick", "--set", "image.width=64", "--set", "image.height=48"]
    (d / "tiny_library.csv").write_text("wavelength_nm,a,b,c\n380,0.1,0.5,0.9\n580,0.2,0.5,0.8\n780,0.3,0.5,0.7\n")
    cases = [
        (quick + ["--seeds", "0"], True), (quick + ["--seeds", "x"], True), (quick + ["--seeds", "1e9"], True),
        (quick + ["--renderer", "nosuch"], True), (quick + ["--set", "sensor.nosuch=1"], True),
        (quick + ["--set", "processing.white_balance_p=0"], True),
        (quick + ["--set", "processing.white_balance_sigma_px=nan"], True),
        (quick + ["--set", "processing.white_balance_training='nosuch'"], True),
        (quick + ["--set", "processing.white_balance_training='cfi99'"], True),
        (quick + ["--set", "processing.white_balance_training='file:nosuch.csv'"], True),
        (quick + ["--set", "processing.white_balance_training='file:tiny_library.csv'"], True),
        (quick + ["--set", "wavelengths.start_nm=670"], True), (quick + ["--set", "image.width=0"], True),
        (quick + ["--set", "illuminant.white_luminance_cd_m2=-1"], True),
        (quick, False), (quick + ["--seeds", "2", "--set", "processing.white_balance_p=2"], False),
    ]
    return _with_fault(rng, *rng.choice(cases))


# -- issue 34: what a new user hits — faults refused in one line, valid inputs accepted, results possible ------

SPD_CSV = "wavelength_nm,value\n380,1\n500,2\n780,1.5\n"
SIM = ["--renderer", "analytic", "--quiet"]


def _photo_scene(d: Path, photo: str) -> str:
    (d / "ph.toml").write_text(f'[target]\nkind = "photo"\nphoto = "file:{photo}"\nlibrary = "cfi99"\nsupersampling = 1\n'
                               '[image]\nwidth = 64\nheight = 48\n')
    return "ph.toml"


def _png_declaring(path: Path, width: int, height: int) -> None:
    """A PNG whose header declares width × height pixels and holds almost nothing (a decompression bomb)."""
    import struct
    import zlib

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
                     + chunk(b"IDAT", zlib.compress(b"\0" * 16)) + chunk(b"IEND", b""))


def case_user_faults(rng, d: Path):
    """Issue 34, item 7: each fault a new user hit, in its bad form — refused in one line (exit 2), never a traceback
    or a hang: (1) illuminant.type contradicting --set illuminant.file, (2) a PNG declaring 20000² px, a float TIFF
    out of 0–1, (3) a number for spatial's olpf_separations_px, (4) view of a report.json that is a list, (5) an EXR
    whose spectracamScene is '[1, 2, 3]', (6) plot-sweep naming an axis its table lacks, (7) a sweep over more cells
    than --max-cells, (8) a FIFO as any input file, (9) a bare scene name matching a local and a shipped file, (10) a
    design file's experiment naming no experiment."""
    import numpy as np

    (d / "spd.csv").write_text(SPD_CSV)
    fault = rng.choice(["illuminant_file", "photo_bomb", "float_tiff", "olpf", "view_list", "exr_scene", "plot_axis",
                        "max_cells", "fifo", "shadowed", "design_experiment"])
    if fault == "illuminant_file":
        return ["render", "s.toml", "-o", "out", *SIM, "--set", "illuminant.type=cie", "--set",
                "illuminant.file=spd.csv"], True, "34.1 illuminant.type contradicts --set illuminant.file"
    if fault == "photo_bomb":
        _png_declaring(d / "bomb.png", 20000, 20000)
        return ["render", _photo_scene(d, "bomb.png"), "-o", "out", *SIM], True, "34.2 a PNG declaring 20000x20000 px"
    if fault == "float_tiff":
        import tifffile

        tifffile.imwrite(d / "hdr.tif", np.full((48, 64, 3), rng.choice([3.0, -0.5, np.nan]), np.float32),
                         photometric="rgb")
        return ["render", _photo_scene(d, "hdr.tif"), "-o", "out", *SIM], True, "34.2 a float TIFF outside 0-1"
    if fault == "olpf":
        v = rng.choice(["1", "'x'", "[]", "[1, 'a']", "[9]"])
        return ["spatial", "-o", "out", "--quick", "--renderer", "analytic", "--set", f"olpf_separations_px={v}"], True, \
            f"34.3 spatial olpf_separations_px={v}"
    if fault == "view_list":
        (d / "out").mkdir()
        (d / "out" / "report.json").write_text(rng.choice(["[1, 2, 3]", "3", '"text"', "null"]))
        return ["view", "out"], True, "34.4 view: report.json not an object"
    if fault == "exr_scene":
        from spectracam.io.exr import read_exr, write_exr

        ch, at = read_exr(d / "r" / "radiance.exr")
        keep = {k: v for k, v in at.items() if k in ("spectralLayoutVersion", "emissiveUnits") or k.startswith("spectracam")}
        keep[rng.choice(["spectracamScene", "spectracamRender"])] = rng.choice(["[1, 2, 3]", "3", '"x"', "null"])
        write_exr(d / "bad.exr", ch, keep)
        return ["capture", "bad.exr", "-o", "out", "--quiet"], True, "34.5 EXR scene attribute not an object"
    if fault == "plot_axis":
        shutil.copytree(d / "sw", d / "out")
        meta = json.loads((d / "out" / "sweep.json").read_text())
        meta["axes"][0][0] = "optics.f_number"
        (d / "out" / "sweep.json").write_text(json.dumps(meta))
        return ["plot-sweep", "out"], True, "34.6 plot-sweep: an axis the table lacks"
    if fault == "max_cells":
        return ["sweep", "sw.toml", "-o", "out", "--serial", "--quiet", "--max-cells", "2"], True, \
            "34.7 a sweep over more cells than --max-cells"
    if fault == "fifo":
        name = rng.choice(["f.toml", "f.exr", "f.csv", "f.png"])
        os.mkfifo(d / name)
        cmd = {"f.toml": rng.choice([["simulate", "f.toml", "-o", "out"], ["sweep", "f.toml", "-o", "out"],
                                     ["design", "f.toml", "-o", "out"]]),
               "f.exr": rng.choice([["capture", "f.exr", "-o", "out"], ["score", "f.exr", "-o", "out"],
                                    ["inspect", "f.exr"]]),
               "f.csv": ["render", "s.toml", "-o", "out", *SIM, "--set", rng.choice(
                   ["illuminant.file=f.csv", 'filters.camera_file="f.csv"', "processing.held_out=file:f.csv"])],
               "f.png": ["render", _photo_scene(d, "f.png"), "-o", "out", *SIM]}[name]
        return cmd, True, f"34.8 a FIFO as {name}: {cmd[0]}"
    if fault == "shadowed":
        (d / "d65.toml").write_text(SCENE)
        return ["render", "d65", "-o", "out", *SIM], True, "34.9 d65 names ./d65.toml and the shipped d65"
    (d / "dz.toml").write_text(f'experiment = "{rng.choice(["nosuch", "d65", "paper.tom"])}"\n')
    return ["design", "dz.toml", "-o", "out", "--quick"], True, "34.10 a design file's experiment names none"


#: Issue 34: camera files whose channels lost their gains or cannot form a colour (refused unless a fix is given).
PEAK_NORMALISED_CSV = "wl,R,G,B\n380,0.1,0.2,1\n500,0.3,1,0.5\n600,1,0.6,0.1\n780,0.4,0.1,0.05\n"
IDENTICAL_CSV = "wl,R,G,B\n380,0.1,0.1,0.1\n550,0.9,0.9,0.9\n780,0.2,0.2,0.2\n"
#: Adobe's ColorMatrix2 of the Nikon D5100 (×10⁴, as dcraw tabulates it): a valid XYZ→camera matrix.
NIKON_MATRIX = "8198,-2239,-724,-4871,12389,2798,-1043,2050,7181"


def case_honest_scores(rng, d: Path):
    """Issue 34's new options: stacked depths that cannot form a colour image, the stacked IR cut, a user's
    peak-normalised or degenerate curves and their fixes (gains, a matrix, kept), ``validate`` on a user's camera,
    the design's ``objective``, the S-CIELAB viewing geometry, and a motion run too large for memory."""
    (d / "peak.csv").write_text(PEAK_NORMALISED_CSV)
    (d / "same.csv").write_text(IDENTICAL_CSV)
    (d / "m.txt").write_text(NIKON_MATRIX.replace(",", " ") + "\n")
    (d / "bad_m.txt").write_bytes(rng.choice([b"", b"1 2 3\n", b"\x00\xff\xfe", b"nan " * 9]))
    sim = ["simulate", "s.toml", "-o", "out", "--renderer", "analytic", "--quiet"]
    stacked = sim + ["--set", "capture.architecture='stacked'"]
    cam = sim + ["--set", "filters.camera_file='peak.csv'"]
    val = ["validate", "-o", "out", "--renderer", "analytic"]
    design = ["design", "design.toml", "-o", "out", "--quick", "--set", "renderer='analytic'", "--set",
              "max_iterations=3", "--set", "designs=['cfa/single']"]
    cases = [
        (stacked + ["--set", "filters.stacked_depths_um=[5.9, 5.95, 6.0, 6.05]"], True),
        (stacked + ["--set", "filters.stacked_depths_um=[0.0001, 0.0002, 0.0003, 100]"], True),
        (stacked + ["--set", "filters.stacked_depths_um=[0.2, 1.0, 3.0]"], True),
        (stacked + ["--set", "filters.stacked_depths_um=[0.2, 0.6, 1.2, 2.0, 3.0, 4.0, 5.0]"], True),
        (stacked + ["--set", "filters.stacked_ir_cut_nm=" + rng.choice(["-5", "1e9", "nan", "true", "'off'"])], True),
        (stacked + ["--set", f"filters.stacked_ir_cut_width_nm={rng.choice(['0', '-1', '1e6'])}"], True),
        (stacked + ["--set", "filters.stacked_ir_cut_nm='none'"], False), (stacked, False),
        (cam, True), (sim + ["--set", "filters.camera_file='same.csv'"], True),
        (cam + ["--set", "filters.kind='block'"], True),
        (cam + ["--set", f"filters.camera_gains={rng.choice(['[1, 0, 1]', '[1, 1]', '[inf, 1, 1]'])}"], True),
        (cam + ["--set", "filters.camera_xyz_to_camera=[1, 2, 3, 4, 5, 6, 7, 8]"], True),
        (cam + ["--set", "filters.camera_gains_kept='yes'"], True),
        (cam + ["--set", "filters.camera_gains=[0.5, 1, 0.8]", "--set", f"filters.camera_xyz_to_camera=[{NIKON_MATRIX}]"],
         True),
        (sim + ["--set", "filters.camera_gains=[0.5, 1, 0.8]"], True),
        (cam + ["--set", "filters.camera_gains=[0.5, 1, 0.8]"], False),
        (cam + ["--set", f"filters.camera_xyz_to_camera=[{NIKON_MATRIX}]"], False),
        (cam + ["--set", "filters.camera_gains_kept=true"], False),
        (val + ["--camera-file", "peak.csv"], True), (val + ["--matrix", NIKON_MATRIX], True),
        (val + ["--camera-file", "peak.csv", "--matrix", "bad_m.txt"], True),
        (val + ["--camera-file", "peak.csv", "--matrix", "1,2,3,4,5,6,7,8"], True),
        (val + ["--camera-file", "peak.csv", "--matrix", "out"], True),
        (val + ["--camera-file", "peak.csv", "--matrix", "m.txt", "--camera-gains", "1,x"], True),
        (val + ["--camera-file", "peak.csv", "--matrix", "m.txt"], False),
        (design + ["--set", "objective=" + rng.choice(["'nosuch'", "1", "true", "[1]", "''", "'s-cielab'"])], True),
        (design + ["--set", "objective='s_cielab'"], False),
        (sim + ["--set", f"processing.viewing_distance_m={rng.choice(['0', '-1', 'nan', '1e9'])}"], True),
        (sim + ["--set", "processing.viewing_distance_m=2.0", "--set", "processing.display_pixel_pitch_mm=0.1"], False),
        (["architectures", "-o", "out", "--quick", rng.choice(["--min-white-snr-db", "--max-s-cielab"]),
          rng.choice(["99", "nan", "-inf", "0.1", "x"])], True),
    ]
    cmd, bad = rng.choice(cases)
    if rng.random() < 0.1:   # a motion run whose slice renders cannot fit: refused up front, nothing written
        return (["motion", "--quick", "-o", "out", "--renderer", "analytic", "--set", "slices=100000"], False,
                "motion slices=100000 under 2 GiB", {"address_space": 2 * 2**30})
    return _with_fault(rng, cmd, bad)


def case_valid(rng, d: Path):
    """Issue 34: valid but unusual inputs must be accepted — exit 0 and the expected files present: each fault of
    case_user_faults in its valid form (illuminant.file via --set on a blackbody and a CIE scene, a float TIFF and a
    16-bit PNG photograph, spatial's OLPF list, view and plot-sweep of real outputs, a capture of a recorded EXR, a
    sweep with its progress, a local scene file by path, and ``experiment = "paper"`` in a design file)."""
    import numpy as np

    (d / "spd.csv").write_text(SPD_CSV)
    kind = rng.choice(["illuminant_file", "float_tiff", "png16", "olpf", "view", "capture", "plot", "sweep",
                       "local_scene", "design_experiment"])
    if kind == "illuminant_file":
        scene = rng.choice(["s.toml", "d65", "blackbody_3000K"])
        return (["simulate", scene, "-o", "out", *SIM, "--set", "image.width=64", "--set", "image.height=48", "--set",
                 "illuminant.file=spd.csv"], False, f"valid: --set illuminant.file on {scene}",
                {"expect": ["out/radiance.exr", "out/raw.exr", "out/report.json"], "physical": True})
    if kind in ("float_tiff", "png16"):
        from PIL import Image

        linear = np.clip(np.random.default_rng(rng.randrange(1000)).random((48, 64, 3)), 0.0, 1.0).astype(np.float32)
        if kind == "float_tiff":
            import tifffile

            tifffile.imwrite(d / "p.tif", linear, photometric="rgb")
            name = "p.tif"
        else:
            Image.fromarray((linear[..., 0] * 65535).astype(np.uint16)).save(d / "p.png")
            name = "p.png"
        return ["simulate", _photo_scene(d, name), "-o", "out", *SIM], False, f"valid: a {kind} photograph", \
            {"expect": ["out/radiance.exr", "out/raw.exr", "out/report.json"], "physical": True}
    if kind == "olpf":
        return (["spatial", "-o", "out", "--quick", "--renderer", "analytic", "--set", "pixel_pitches_um=[10]",
                 "--set", "f_numbers=[1.4]", "--set", "designs=['cfa/single']", "--set", "demosaics=['bilinear']",
                 "--set", "olpf_separations_px=[0, 1]", "--set", "targets=['edge']"], False,
                "valid: spatial olpf_separations_px=[0, 1]", {"expect": ["out/report.md"], "physical": True})
    if kind == "view":
        shutil.copytree(d / rng.choice(["r", "c", "sw"]), d / "out")
        return ["view", "out"], False, "valid: view of real outputs", {"expect": ["out/index.html"]}
    if kind == "capture":
        return ["capture", "r/radiance.exr", "-o", "out", "--quiet"], False, "valid: capture of a recorded EXR", \
            {"expect": ["out/raw.exr"], "physical": True}
    if kind == "plot":
        shutil.copytree(d / "sw", d / "out")
        return ["plot-sweep", "out"], False, "valid: plot-sweep", {"expect": ["out/plots/delta_e_mean.png"]}
    if kind == "sweep":
        return ["sweep", "sw.toml", "-o", "out", "--serial"], False, "valid: a sweep with its progress", \
            {"expect": ["out/results.parquet", "out/results.csv", "out/sweep.json"], "physical": True}
    if kind == "local_scene":
        (d / "d65.toml").write_text(SCENE)
        return ["simulate", rng.choice(["./d65.toml", "d65.toml"]), "-o", "out", *SIM], False, \
            "valid: a local d65.toml by path", {"expect": ["out/report.json", "out/raw.exr"], "physical": True}
    (d / "dz.toml").write_text('experiment = "paper"\n')
    return (["design", "dz.toml", "-o", "out", "--quick", "--set", "renderer='analytic'", "--set", "max_iterations=2",
             "--set", "designs=['cfa/single']", "--quiet"], False, "valid: experiment = \"paper\" in a design file",
            {"expect": ["out/results.json"]})


def case_physical(rng, d: Path):
    """Issue 34: results must be physically possible (:func:`impossible_outputs`) on quick runs of every kind — a
    simulate under another design, ADC, light or noise switch; a capture and a score of the base files."""
    sets = rng.choice([["capture.design=fsc/optimal"], ["capture.design=prism/balanced"], ["sensor.adc_bits=12"],
                       ["sensor.adc_bits=6"], ["illuminant.type=cie", "illuminant.name=A"],
                       ["illuminant.white_luminance_cd_m2=5"], ["sensor.read_noise=false", "sensor.shot_noise=false"],
                       ["optics.f_number=8"], ["illuminant.white_luminance_cd_m2=3000"]])
    cmd = rng.choice([["simulate", "s.toml", "-o", "out", *SIM] + [a for s in sets for a in ("--set", s)],
                      ["capture", "r/radiance.exr", "-o", "out", "--quiet", "--seed", str(rng.randrange(100))],
                      ["score", "c/raw.exr", "-o", "out", "--quiet"]])
    expect = {"simulate": ["out/report.json", "out/raw.exr"], "capture": ["out/raw.exr"],
              "score": ["out/report.json"]}[cmd[0]]
    return cmd, False, f"physical: {' '.join(cmd[:2])} {' '.join(sets) if cmd[0] == 'simulate' else ''}", \
        {"expect": expect, "physical": True}


#: The largest ΔE*ab a result may hold: L* spans 0–100 and a*, b* of any colour a display or a surface shows stay
#: within about ±200, so two such colours are never more than ~400 apart; a larger one is a wrong number.
DELTA_E_BOUND = 400.0


def impossible_outputs(out: Path) -> str:
    """What is physically impossible in a run's outputs ("" if nothing): in reports, a ΔE that is negative,
    non-finite or above :data:`DELTA_E_BOUND`, an SNR that is not finite (null: noise-free, allowed), an exposure or
    capture time ≤ 0; in raw EXRs, digital numbers outside [0, 2^bits − 1], charges (DN − black level)/K above the
    full well or a mean charge below 0, exposure times ≤ 0."""
    import math

    import numpy as np

    for p in out.rglob("*.json"):
        try:
            d = json.loads(p.read_text())
        except ValueError:
            continue
        stack = [("", d)]
        while stack:
            key, x = stack.pop()
            if isinstance(x, dict):
                stack.extend(x.items())
            elif isinstance(x, list):
                stack.extend((key, v) for v in x)
            elif isinstance(x, (int, float)) and not isinstance(x, bool) and isinstance(key, str):
                k = key.lower()
                if (k.startswith(("delta_e", "s_cielab")) or k.endswith("delta_e")) and \
                        not (math.isfinite(x) and 0 <= x <= DELTA_E_BOUND):
                    return f"{p.name}: {key} = {x} (ΔE must be finite, 0–{DELTA_E_BOUND:g})"
                if "snr" in k and not math.isfinite(x):
                    return f"{p.name}: {key} = {x} (an SNR must be finite)"
                if k.startswith(("exposure", "capture_time")) and k.endswith(("_s", "_ms")) and \
                        not (math.isfinite(x) and x > 0):
                    return f"{p.name}: {key} = {x} (an exposure time must be > 0)"
    from spectracam.io.exr import read_raw_exr

    for p in out.rglob("raw.exr"):
        raw = read_raw_exr(p)
        s = raw.camera.sensor
        dn = np.asarray(raw.digital, np.float64)
        if dn.min() < 0 or dn.max() > 2**s.adc_bits - 1:
            return f"{p}: digital numbers {dn.min():g}–{dn.max():g} outside 0–{2**s.adc_bits - 1}"
        charge = (dn - s.black_level_dn) * s.quantization_step_e
        if charge.max() > s.q_max_e * (1 + 1e-6) or charge.mean() < 0:
            return f"{p}: charges up to {charge.max():g} e (full well {s.q_max_e:g}), mean {charge.mean():g} e"
        t = np.asarray(raw.exposure_times_s, np.float64)
        if not (np.all(np.isfinite(t)) and np.all(t > 0) and raw.capture_time_s > 0):
            return f"{p}: exposure times {t.tolist()} s"
    return ""


LIGHT = '[[lights]]\nname = "{name}"\nilluminant = {{ type = "cie", name = "D65", white_luminance_cd_m2 = {L} }}\n'


def _lights_scene(rng) -> tuple[str, bool]:
    """A two-light chart scene, often damaged: ``(text, known bad)``."""
    good = SCENE.replace("width = 64", "width = 256").replace("height = 48", "height = 96") \
        + LIGHT.format(name="sun", L=1e4) + LIGHT.format(name="shade", L=1.0)
    bad = [
        good.replace("white_luminance_cd_m2 = 1.0", "white_luminance_cd_m2 = " + rng.choice(["0", "-1", "nan"])),
        good.replace('"shade"', '"sun"'), good.replace('"shade"', '""'),
        good.replace("[[lights]]\nname = \"sun\"", "[[lights]]\nname = \"sun\"\ntype = \"cie\""),
        good + "[image]\nlights_columns = " + rng.choice(["-1", "65", "1.5"]) + "\n",
        good + '[illuminant]\ntype = "cie"\nname = "A"\n',
        SCENE + "".join(LIGHT.format(name=f"g{i}", L=10.0 ** (i % 5)) for i in range(rng.choice([8, 65]))),
        SCENE + "lights = 3\n",
        good.replace("white_luminance_cd_m2 = 1.0", "white_luminance_cd_m2 = 1.0, illuminance_lux = 3.0"),
    ]
    if rng.random() < 0.3:
        return good, False
    return rng.choice(bad), True


READOUT_FIELDS = ["readout_samples", "dual_gain_ratio", "split_ratio", "bracketing_frames", "bracketing_ratio",
                  "companding_bits", "motion_threshold_sigma", "dual_gain_switch", "split_small_well_fraction"]


def case_dynamic_range(rng, d: Path):
    """Issue 36: light-group scenes (damaged or not), the read-outs and hot pixels on a capture, the datasheet and
    the dynamic-range commands with bad values, under a full disk or SIGTERM."""
    text, bad_scene = _lights_scene(rng)
    (d / "hdr.toml").write_text(text)
    sim = ["simulate", "hdr.toml", "-o", "out", "--renderer", "analytic", "--quiet"]
    readout = rng.choice(["multiple_capture", "dual_gain", "split_pixel", "bracketing"])
    ds = ["datasheet", "-o", "out", "--quick"]
    dr = ["dynamic-range", "-o", "out", "--quick", "--design", "cfa/single", "--readout", "single", "--temperature",
          "25"]
    cases = [
        (sim, bad_scene),
        (sim + ["--set", f"sensor.readout='{readout}'", "--set", f"sensor.companding_bits={rng.choice([12, 16])}"],
         bad_scene),
        (sim + ["--set", f"sensor.readout='{readout}'", "--set", "sensor." + rng.choice(READOUT_FIELDS) + "="
                + rng.choice(["0", "-1", "nan", "1e9", "'x'"])], True),
        (sim + ["--set", f"sensor.hot_pixel_fraction={rng.choice(['-0.1', '2', 'nan'])}"], True),
        (sim + ["--set", "sensor.hot_pixel_fraction=0.01"], bad_scene),
        (ds + ["--set", "sensor.readout=" + rng.choice(["'bogus'", "1", "[]"])], True),
        (ds + ["--set", "sensor.temperature_C=400"], True), (ds + ["--seed", "-1"], True),
        (ds + ["--set", "sensor.q_max_e=0"], True), (ds + ["--scene", "nosuch"], True),
        (["datasheet", "-o", ""], True),
        (ds + ["--set", f"sensor.readout='{readout}'"], False),
        (dr[:4] + ["--readout", rng.choice(["nosuch", "", "single,dual_gain"])], True),
        (dr[:4] + ["--design", rng.choice(["cfa/optimal", "nosuch/single", "cfa/nosuch", "/single"])], True),
        (dr[:4] + ["--temperature", rng.choice(["400", "nan", "-200", "x"])], True),
        (dr + ["--set", "sensor.readout_samples=0"], True), (dr + ["--seeds", "0"], True),
        (dr, False),
    ]
    cmd, bad = rng.choice(cases)
    return _with_fault(rng, cmd, bad)


def case_field(rng, d: Path):
    """Issue 37: the lens-shading correction on a shaded capture (good and bad values, damaged scene files) and the
    field command with bad values, under a full disk or SIGTERM."""
    text, bad_scene = _lights_scene(rng)
    (d / "hdr.toml").write_text(text)
    shaded = ["--set", "optics.relative_illumination='cos4'", "--set", "optics.cra_corner_deg=20",
              "--set", "pixel.microlens=true", "--set", "sensor.pixel_pitch_um=1.4"]
    sim = ["simulate", "d65", "-o", "out", "--renderer", "analytic", "--quiet", "--set", "image.width=64",
           "--set", "image.height=48"] + shaded
    fld = ["field", "-o", "out", "--quick", "--design", "cfa/single", "--shift", "1", "--correction", "single",
           "--set", "image.width=64", "--set", "image.height=48"]
    correction = rng.choice(["single", "cct"])
    cases = [
        (sim + ["--set", f"processing.shading='{correction}'"], False),
        (sim + ["--set", f"processing.shading='{correction}'", "--set", "processing.shading_method='cell_mean'"],
         False),
        (sim + ["--set", "processing.shading=" + rng.choice(["'bogus'", "1", "[]", "true"])], True),
        (sim + ["--set", "processing.shading_temperatures_K=" + rng.choice(["[5000, 3000]", "[]", "[500]", "['x']",
                                                                           "[3000, 1e9]"])], True),
        (sim + ["--set", "processing.shading_grid=" + rng.choice(["[1, 16]", "[12]", "[12, 1000]", "[12.5, 16]",
                                                                  "'x'"])], True),
        (["simulate", "hdr.toml", "-o", "out", "--renderer", "analytic", "--quiet", "--set",
          "processing.shading='single'"] + shaded, bad_scene),
        (fld, False),
        (fld[:4] + ["--correction", rng.choice(["nosuch", "", "none,single"])], True),
        (fld[:4] + ["--shift", rng.choice(["-1", "3", "nan", "x"])], True),
        (fld[:4] + ["--cra", rng.choice(["0", "-5", "90", "nan", "x"])], True),
        (fld[:4] + ["--pitch", rng.choice(["0", "-1", "nan", "x"])], True),
        (fld[:4] + ["--design", rng.choice(["cfa/optimal", "nosuch/single", "/single"])], True),
        (fld + ["--set", rng.choice(["processing.shading='cct'", "pixel.microlens_shift_fraction=0.5",
                                     "optics.cra_corner_deg=10", "sensor.pixel_pitch_um=2"])], True),
        (fld + ["--set", "optics.relative_illumination='none'", "--set", "optics.cra_corner_deg=0"], True),
        (fld + ["--seeds", "0"], True), (["field", "-o", ""], True),
    ]
    cmd, bad = rng.choice(cases)
    return _with_fault(rng, cmd, bad)


def case_channel_planes(rng, d: Path):
    """Issue 38: ``simulate --channel-planes`` and ``capture --channel-planes`` on good chart scenes (analytic, Mitsuba,
    another design) under a full disk, SIGTERM or a memory limit, and on what they refuse (a textured target, light
    groups, an off-axis field, another white, a file that is not a spectracam radiance, a bad value beside it)."""
    text, _ = _lights_scene(rng)
    (d / "hdr.toml").write_text(text)
    sim = ["simulate", "s.toml", "-o", "out", "--quiet", "--channel-planes"]
    cases = [
        (sim + ["--renderer", "analytic"], False),
        (sim + ["--renderer", "mitsuba"], False),
        (sim + ["--renderer", "analytic", "--arch", rng.choice(["stacked", "fsc", "rgbw", "cmy"])], False),
        (sim + ["--renderer", "analytic", "--set", 'target.kind="photo"'], True),
        (["simulate", "hdr.toml", "-o", "out", "--quiet", "--channel-planes", "--renderer", "analytic"], True),
        (sim + ["--renderer", rng.choice(["nosuch", ""])], True),
        (sim + ["--renderer", "analytic", "--set", f"image.width={rng.choice(['0', '-1', 'nan'])}"], True),
        (sim + ["--renderer", "analytic", "--set", "optics.relative_illumination='cos4'"], True),
        (sim + ["--channel-planes=yes"], True),
        (["capture", "r/radiance.exr", "-o", "out", "--quiet", "--channel-planes"], False),
        (["capture", "r/radiance.exr", "-o", "out", "--quiet", "--channel-planes", "--arch", "stacked"], False),
        (["capture", "r/radiance.exr", "-o", "out", "--quiet", "--channel-planes", "--white",
          rng.choice(["brightest", "0,0,8,8", "100"])], True),
        (["capture", rng.choice(["s.toml", "nosuch.exr", "r"]), "-o", "out", "--quiet", "--channel-planes"], True),
    ]
    cmd, bad = rng.choice(cases)
    if not bad and cmd[0] == "simulate" and rng.random() < 0.25:   # 6000 x 4500: ~7.5 GiB, above a 4 GiB limit
        return cmd + ["--set", "image.width=6000", "--set", "image.height=4500"], False, \
            f"memory limit 4 GiB: {' '.join(cmd)}", {"address_space": 4 * 2**30}
    return _with_fault(rng, cmd, bad)


def case_colour_tables(rng, d: Path):
    """Issue 38: the snapshot of colour-science's tables (spectracam.core.colour_data, ``$SPECTRACAM_TABLES``) missing,
    truncated, garbage, empty, a directory where it should be, a file where its folder should be, its folder
    read-only, or a full disk as it is written: a cache never stops a run, so every command succeeds with its files;
    where the folder can be written, a whole snapshot is left there (never a temporary file)."""
    from importlib import metadata

    tables = d / "case_tables"   # this case's own folder (d / "tables" holds make_base's good snapshot)
    name = f"colour-science-{metadata.version('colour-science')}.npz"
    snap = tables / name
    kind = rng.choice(["missing", "truncated", "garbage", "empty", "directory", "file_for_folder", "read_only",
                       "full_disk"])
    good = (d / "tables" / name).read_bytes()
    opts = {"env": {"SPECTRACAM_TABLES": str(tables)}, "physical": True,
            "expect": ["out/radiance.exr", "out/raw.exr", "out/report.json"]}
    if kind in ("truncated", "garbage", "empty", "read_only", "full_disk"):
        tables.mkdir()
        garbage = bytes(rng.randrange(256) for _ in range(2048))
        snap.write_bytes({"truncated": good[: rng.randrange(1, len(good))], "garbage": garbage}.get(kind, b""))
    if kind == "directory":
        snap.mkdir(parents=True)
    if kind == "file_for_folder":
        tables.write_text("a file where the folder should be")
    if kind == "read_only":
        os.chmod(tables, 0o555)
        opts["drop_caps"] = True
    if kind == "full_disk":
        opts["fsize"] = 300_000   # the tiny scene's files fit; the snapshot (~0.6 MB) does not
    if kind in ("missing", "truncated", "garbage", "empty"):
        opts["expect"].append(str(snap.relative_to(d)))
    cmd = rng.choice([["simulate", "s.toml", "-o", "out", *SIM], ["simulate", "d65", "-o", "out", *SIM, "--set",
                      "image.width=64", "--set", "image.height=48"]])
    return cmd, False, f"colour tables {kind}: {cmd[0]} {cmd[1]}", opts


CASES = [case_damaged_file, case_scene_value, case_environment, case_garbage_text, case_camera_file, case_foreign_exr,
         case_new_commands, case_signal, case_full_disk, case_memory_limit, case_raw_attributes, case_journal,
         case_experiment_values, case_group_signal, case_scheduler_peer, case_read_only, case_reflectances,
         case_target, case_architectures, case_spacetime, case_design, case_view, case_developed,
         case_white_balance, case_user_faults, case_valid, case_physical, case_honest_scores, case_dynamic_range,
         case_field, case_channel_planes, case_colour_tables]


def one(i: int, seed: int, base: Path, cycle: bool = False, classes=None) -> tuple[str, dict]:
    rng = random.Random(seed * 100003 + i)
    classes = classes or CASES
    with tempfile.TemporaryDirectory() as t:
        d = Path(t)
        shutil.copytree(base, d, dirs_exist_ok=True)
        make = classes[i % len(classes)] if cycle else rng.choice(classes)
        cmd, known_bad, label, *extra = make(rng, d)
        opts = extra[0] if extra and isinstance(extra[0], dict) else ({"kill": extra[0]} if extra else {})
        before = snapshot(d / "out")
        if "chmod" in opts:
            os.chmod(d / "out", opts["chmod"])
        r, orphans, hung = run(cmd, d, opts=opts)
        if "chmod" in opts:
            os.chmod(d / "out", 0o755)
        res = judge(r, d / "out", known_bad, before, cmd[0]) | {"status": r.returncode, "stderr": r.stderr[-400:]}
        if "expect" in opts:   # a valid input: accepted, and what it writes is there
            missing = [p for p in opts["expect"] if not (d / p).exists()]
            res["valid_refused"] = r.returncode != 0 or bool(missing)
            if missing and r.returncode == 0:
                res["stderr"] = f"missing {', '.join(missing)}; " + res["stderr"]
        if opts.get("physical") and r.returncode == 0:
            why = impossible_outputs(d / "out")
            res["impossible"] = bool(why)
            if why:
                res["stderr"] = why + "; " + res["stderr"]
        return label, res | {"orphans": orphans, "hang": hung, "command": cmd[0]}


KINDS = ("traceback", "partial", "silent_wrong", "multi_line", "orphans", "hang", "valid_refused", "impossible")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=300)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--random-classes", action="store_true",
                    help="draw each case's class at random [default: every class in turn]")
    ap.add_argument("--only", default=None, metavar="CLASS,...",
                    help="run only these classes, e.g. user_faults,valid,physical [default: all]")
    a = ap.parse_args(argv)
    classes = CASES
    if a.only:
        by_name = {c.__name__.removeprefix("case_"): c for c in CASES}
        unknown = [n for n in a.only.split(",") if n not in by_name]
        if unknown:
            ap.error(f"--only: no class {', '.join(unknown)}; classes: {', '.join(by_name)}")
        classes = [by_name[n] for n in a.only.split(",")]
    kept = os.environ.get("SPECTRACAM_TABLES")
    try:
        with tempfile.TemporaryDirectory() as t:
            base = Path(t)
            make_base(base)
            with ThreadPoolExecutor(a.jobs) as ex:
                results = list(ex.map(lambda i: one(i, a.seed, base, cycle=not a.random_classes, classes=classes),
                                      range(a.cases)))
    finally:   # make_base pointed the variable at its folder: a caller in this process (the tests) gets its own back
        if kept is None:
            os.environ.pop("SPECTRACAM_TABLES", None)
        else:
            os.environ["SPECTRACAM_TABLES"] = kept
    counts = {k: sum(bool(r.get(k)) for _, r in results) for k in KINDS}
    for label, r in results:
        if any(r.get(k) for k in KINDS):
            print(f"  {label}: status {r['status']}, " + ", ".join(k for k in KINDS if r.get(k)) + f"\n    {r['stderr']}")
    print(f"{'command':<12} {'cases':>5} {'ok':>4} {'refused':>7} " + " ".join(f"{k:>12}" for k in KINDS))
    for cmd in sorted({r["command"] for _, r in results}):
        rs = [r for _, r in results if r["command"] == cmd]
        ok = sum(r["status"] == 0 for r in rs)
        print(f"{cmd:<12} {len(rs):>5} {ok:>4} {len(rs) - ok:>7} " + " ".join(f"{sum(bool(r.get(k)) for r in rs):>12}"
                                                                        for k in KINDS))
    ok = sum(r["status"] == 0 for _, r in results)
    print(f"fuzz: {len(results)} cases ({ok} succeeded, {len(results) - ok} refused), {counts['traceback']} tracebacks, "
          f"{counts['partial']} partial files, {counts['silent_wrong']} silent wrong results, "
          f"{counts['multi_line']} multi-line errors, {counts['orphans']} orphans, {counts['hang']} hangs, "
          f"{counts['valid_refused']} valid inputs refused, {counts['impossible']} impossible results")
    return 1 if any(counts.values()) else 0


if __name__ == "__main__":
    sys.exit(main())
