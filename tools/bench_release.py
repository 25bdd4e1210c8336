"""Benchmark: the same commands at HEAD and at an earlier commit, interleaved, CPU and wall — "no slower than the last
release" (issue 38).

    python3 tools/bench_release.py [--against f466af9] [--repeats 3] [--only NAME,...]

The earlier commit is checked out into a git worktree (``git worktree add --detach``; removed at the end); both
trees' modules are compiled to bytecode first (``compileall``, as an installed package's are), and both run with this
interpreter and its packages, each with ``PYTHONPATH`` at its own tree, from an empty working directory, one command
of each tree in turn (so a machine that slows down slows both alike), each with its own empty render cache
(``SPECTRACAM_CACHE``) so neither reads the other's renders. HEAD reads colour-science's tables from their snapshot
in the user's cache (``spectracam.core.colour_data``), as every run after the first one after an install does; when
there is none yet, HEAD's first run makes it (about 3 s, once), which the median of three runs leaves out.

Commands (``--only`` picks some):

* ``paper-quick``  — ``spectracam paper -o OUT --quick --renderer analytic``
* ``simulate-d65`` — ``spectracam simulate TREE/scenes/d65.toml -o OUT --renderer analytic``
* ``capture-step`` — the capture stage alone: ``spectracam.camera.capture.capture`` of a 12-Mpx, 30-band cube (the
  best of 3 calls, after one warm-up call, timed inside the process and printed by it; its CPU is the process's
  CPU over those calls).
* ``startup``      — ``spectracam simulate --help``.

For each it prints the medians of HEAD and of the earlier commit, wall and CPU (user + system of the child), and
the ratios HEAD / earlier: the figure to hold at ≤ 1.0.
"""
from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

#: The capture step, timed inside the process (the cube is made once; best of 3 after a warm-up call).
CAPTURE_SNIPPET = r"""
import resource, time, numpy as np
try:                                   # the layout by stage (since issue 26)
    from spectracam.camera import CameraSpec
    from spectracam.camera.capture import capture
    from spectracam.render.cube import RadianceCube
except ImportError:                    # the flat layout of earlier releases
    from spectracam.camera import CameraSpec
    from spectracam.capture import capture
    from spectracam.render import RadianceCube
grid = np.arange(405.0, 700.0, 10.0)
cube = RadianceCube(np.random.default_rng(0).uniform(1e-3, 1e-2, (3000, 4000, grid.size)).astype(np.float32), grid, {})
cam, box = CameraSpec(), (slice(1400, 1600), slice(1900, 2100))
capture(cube, cam, 0, box)
best, cpu0 = float("inf"), resource.getrusage(resource.RUSAGE_SELF)
for seed in range(1, 4):
    t = time.perf_counter(); capture(cube, cam, seed, box); best = min(best, time.perf_counter() - t)
cpu1 = resource.getrusage(resource.RUSAGE_SELF)
print("BENCH", best, (cpu1.ru_utime - cpu0.ru_utime + cpu1.ru_stime - cpu0.ru_stime) / 3)
"""

COMMANDS = {
    "paper-quick": ["-m", "spectracam", "paper", "-o", "{out}", "--quick", "--renderer", "analytic"],
    "simulate-d65": ["-m", "spectracam", "simulate", "{tree}/scenes/d65.toml", "-o", "{out}", "--renderer", "analytic"],
    "capture-step": ["-c", CAPTURE_SNIPPET],
    "startup": ["-m", "spectracam", "simulate", "--help"],
}


def run_once(tree: Path, name: str, work: Path) -> tuple[float, float]:
    """(wall s, CPU s) of one command of ``tree``; for the capture step the process's own timing of the stage."""
    out = work / f"out-{name}"
    shutil.rmtree(out, ignore_errors=True)
    cache = work / "cache"
    shutil.rmtree(cache, ignore_errors=True)
    env = {**os.environ, "PYTHONPATH": str(tree), "SPECTRACAM_CACHE": str(cache), "PYTHONDONTWRITEBYTECODE": "1"}
    args = [sys.executable] + [a.replace("{out}", str(out)).replace("{tree}", str(tree)) for a in COMMANDS[name]]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(args, cwd=work, env=env, capture_output=True, text=True, timeout=1800)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise SystemExit(f"bench_release: {name} failed in {tree} (exit {proc.returncode}): "
                         + (proc.stderr.strip().splitlines() or ["no message"])[-1])
    cpu = after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime
    if name == "capture-step":
        line = next(x for x in proc.stdout.splitlines() if x.startswith("BENCH"))
        _, wall_s, cpu_s = line.split()
        return float(wall_s), float(cpu_s)
    return wall, cpu


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--against", default="f466af9", help="the earlier commit (default: the previous release)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--only", default=None, metavar="NAME,...", help="some of: " + ", ".join(COMMANDS))
    args = ap.parse_args()
    names = list(COMMANDS) if args.only is None else [n.strip() for n in args.only.split(",")]
    for n in names:
        if n not in COMMANDS:
            raise SystemExit(f"bench_release: --only {n!r}: not a command; one of {', '.join(COMMANDS)}")
    if args.repeats < 1:
        raise SystemExit(f"bench_release: --repeats {args.repeats}: must be ≥ 1")
    rev = subprocess.run(["git", "rev-parse", "--short", args.against], cwd=ROOT, capture_output=True, text=True)
    if rev.returncode != 0:
        raise SystemExit(f"bench_release: --against {args.against!r}: not a commit of this repository")
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout
    dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=ROOT, capture_output=True,
                           text=True).stdout.strip()
    with tempfile.TemporaryDirectory(prefix="bench-release-") as tmp:
        old = Path(tmp) / "old"
        subprocess.run(["git", "worktree", "add", "--detach", "-q", str(old), rev.stdout.strip()], cwd=ROOT,
                       check=True)
        try:
            trees = {"HEAD": ROOT, args.against: old}
            # Both trees' modules compiled to bytecode first, as an installed package's are: the runs are made with
            # PYTHONDONTWRITEBYTECODE, so a fresh worktree would otherwise compile its sources in every run while
            # this one read the __pycache__ its earlier runs left (so, before issue 38's sixth session, every old
            # run's CPU included compiling its sources)
            for tree in trees.values():
                subprocess.run([sys.executable, "-m", "compileall", "-q", str(tree / "spectracam")], check=True)
            print(f"HEAD {head.strip()}{' (with uncommitted changes)' if dirty else ''} against {args.against} "
                  f"({rev.stdout.strip()}); {args.repeats} interleaved runs each; {os.cpu_count()} CPUs")
            print(f"{'command':14s} {'HEAD wall':>10s} {'old wall':>10s} {'ratio':>6s}   {'HEAD CPU':>9s} "
                  f"{'old CPU':>9s} {'ratio':>6s}")
            for name in names:
                got: dict = {k: [] for k in trees}
                for _ in range(args.repeats):
                    for label, tree in trees.items():
                        work = Path(tmp) / f"work-{'head' if tree == ROOT else 'old'}"
                        work.mkdir(exist_ok=True)
                        got[label].append(run_once(tree, name, work))
                hw, hc = (statistics.median(x[i] for x in got["HEAD"]) for i in (0, 1))
                ow, oc = (statistics.median(x[i] for x in got[args.against]) for i in (0, 1))
                print(f"{name:14s} {hw:9.2f}s {ow:9.2f}s {hw / ow:6.2f}   {hc:8.2f}s {oc:8.2f}s {hc / oc:6.2f}",
                      flush=True)
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(old)], cwd=ROOT, check=False)


if __name__ == "__main__":
    main()
