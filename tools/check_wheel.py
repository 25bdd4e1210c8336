"""Build spectracam's wheel, install it into a fresh virtual environment that cannot see this checkout, and run
commands that name shipped files from a directory outside the checkout.

    python3 tools/check_wheel.py [--keep]

The new environment is made without the project's packages and without pip's dependency resolution (the
machine may be offline): the wheel is installed with ``--no-deps``, and its dependencies come from this
project's own environment through a ``.pth`` file that names that environment's site-packages — a plain path
line, so the editable install's finder there (which would import this checkout) is never run.  Each command runs
from an empty temporary directory with ``PYTHONPATH`` unset.  Checks: ``spectracam`` is imported from the new
environment; ``simulate d65`` and ``simulate scenes/d65.toml`` (the README's spelling), ``render d65.toml``,
``sweep cfa_cutoffs`` (refused by ``--max-cells 20``, after its base scene was read from the wheel),
``paper --quick`` (its default experiment), ``design design --quick`` (the design file and the experiment it
names), a bad name (one line listing what ships), and ``view`` on an output directory.  Prints one line per
check, the time of each step, and exits 1 if any check failed.
"""
from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SMALL = ["--renderer", "analytic", "--set", "image.width=64", "--set", "image.height=48"]


def checks() -> list[tuple[str, list[str], callable]]:
    """(label, spectracam arguments, judge(result, cwd) → None or what is wrong)."""
    def wrote(*files):
        def judge(r, cwd):
            missing = [f for f in files if not (cwd / f).is_file()]
            return None if r.returncode == 0 and not missing else f"rc {r.returncode}, missing {missing}"
        return judge

    def refused(*words):
        def judge(r, cwd):
            lines = r.stderr.strip().splitlines()
            ok = r.returncode == 2 and len(lines) == 1 and all(w in lines[0] for w in words)
            return None if ok else f"rc {r.returncode}: {r.stderr.strip()[-300:]}"
        return judge

    return [
        ("simulate d65", ["simulate", "d65", "-o", "a", *SMALL, "--quiet"], wrote("a/report.json", "a/raw.dng")),
        ("simulate scenes/d65.toml", ["simulate", "scenes/d65.toml", "-o", "b", *SMALL, "--quiet"],
         wrote("b/report.json")),
        ("render d65.toml", ["render", "d65.toml", "-o", "c", *SMALL, "--quiet"], wrote("c/radiance.exr")),
        ("sweep cfa_cutoffs (base scene read from the wheel)", ["sweep", "cfa_cutoffs", "-o", "d", "--max-cells", "20", "--quiet"],
         refused("162 cells", "--max-cells")),
        ("paper --quick (the shipped experiment)", ["paper", "--quick", "--renderer", "analytic", "-o", "e", "--quiet"],
         wrote("e/results.json")),
        ("design design --quick (the design file and its experiment)",
         ["design", "design", "--quick", "-o", "f", "--quiet", "--set", "renderer='analytic'", "--set",
          "designs=['cfa/single']", "--set", "max_iterations=2", "--set", "seeds=1"], wrote("f/results.json")),
        ("a name that is not shipped", ["simulate", "nosuch", "-o", "g"], refused("no such file", "d65", "shipped")),
        ("view of an output directory", ["view", "a"], wrote("a/index.html")),
    ]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--keep", action="store_true", help="keep the temporary directory (its path is printed)")
    a = ap.parse_args(argv)
    tmp = Path(tempfile.mkdtemp(prefix="spectracam-wheel-"))
    failed = 0
    made_build = not (ROOT / "build").exists()   # setuptools builds in the checkout's build/: leave none behind
    try:
        t = time.perf_counter()
        build = [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(tmp / "wheel"), str(ROOT)]
        if subprocess.run(build).returncode != 0:  # offline: build with this environment's setuptools
            subprocess.run(build + ["--no-build-isolation"], check=True)
        wheel = next((tmp / "wheel").glob("spectracam-*.whl"))
        print(f"built {wheel.name} ({time.perf_counter() - t:.1f} s)")
        t = time.perf_counter()
        venv = tmp / "venv"
        base = getattr(sys, "_base_executable", sys.executable)
        subprocess.run([base, "-m", "venv", str(venv)], check=True)
        py = venv / "bin" / "python"
        site = Path(subprocess.run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                                   check=True, capture_output=True, text=True).stdout.strip())
        (site / "zz_project_dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
        subprocess.run([str(py), "-m", "pip", "install", "-q", "--no-deps", "--no-index", str(wheel)], check=True)
        print(f"installed into a fresh venv with the project's dependencies on its path ({time.perf_counter() - t:.1f} s)")
        env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
        env["SPECTRACAM_CACHE"] = str(tmp / "cache")
        work = tmp / "work"
        work.mkdir()
        where = subprocess.run([str(py), "-c", "import spectracam; print(spectracam.__file__)"], cwd=work, env=env,
                               capture_output=True, text=True)
        imported = Path(where.stdout.strip())
        ok = where.returncode == 0 and venv in imported.parents and ROOT not in imported.parents
        failed += not ok
        print(f"{'ok  ' if ok else 'FAIL'} spectracam imported from {imported}")
        for label, args, judge in checks():
            t = time.perf_counter()
            r = subprocess.run([str(venv / "bin" / "spectracam"), *args], cwd=work, env=env, capture_output=True,
                               text=True, timeout=600)
            wrong = judge(r, work)
            failed += wrong is not None
            print(f"{'ok  ' if wrong is None else 'FAIL'} {label} ({time.perf_counter() - t:.1f} s)"
                  + ("" if wrong is None else f": {wrong}"))
    finally:
        if made_build:
            shutil.rmtree(ROOT / "build", ignore_errors=True)
        if a.keep:
            print(f"kept {tmp}")
        else:
            shutil.rmtree(tmp, ignore_errors=True)
    print(f"check_wheel: {failed} check(s) failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
