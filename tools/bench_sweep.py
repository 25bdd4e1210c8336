"""Benchmark: the example sweep (scenes/sweeps/cfa_cutoffs.toml), serially and on local Dask clusters.

    python3 tools/bench_sweep.py [--sweep FILE]

Prints cells per second serially and on local clusters of 1 and 2 worker processes, and the
engine's overhead per cell: (wall time between the cluster's start-up and its shut-down − Σ cell compute time
measured inside the tasks) / cells, on the 1-worker cluster, where the scheduler and driver have the other core and
nothing competes with the worker (issue 6 target: < 10 % of a cell's compute; issue 38: < 5 %).  The start-up
and the shut-down (closing the client and a local cluster) are once per run, not per cell: printed apart.  On the 2-worker
cluster the same figure also holds whatever the machine loses when two processes compute at once;
a pure-Python probe prints how much that is here.  Renders come from the render cache.
"""
from __future__ import annotations

import argparse
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _spin(_=None) -> float:
    t = time.perf_counter()
    s = 0.0
    for i in range(3_000_000):
        s += i * 0.5
    return time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sweep", default=str(ROOT / "scenes" / "sweeps" / "cfa_cutoffs.toml"))
    args = ap.parse_args()
    from spectracam.experiments.sweep.experiment import load_sweep, run_sweep

    alone = _spin()
    with ProcessPoolExecutor(2) as ex:
        together = max(ex.map(_spin, range(2)))
    sweep = load_sweep(args.sweep)
    with tempfile.TemporaryDirectory() as tmp:
        run_sweep(sweep, Path(tmp) / "warm", serial=True, progress=False, stop_after=2)  # renders into the cache
        runs = {"serial": run_sweep(sweep, Path(tmp) / "serial", serial=True, progress=False)}
        for w in (1, 2):
            runs[w] = run_sweep(sweep, Path(tmp) / f"dask{w}", workers=w, progress=False)
    n = runs["serial"]["cells"]
    print(f"sweep {args.sweep}: {n} cells x {sweep.trials} trials")
    print(f"this machine: two busy processes run at {alone / together:.2f}x the speed of one each "
          f"(pure-Python probe: {1e3 * alone:.0f} ms alone, {1e3 * together:.0f} ms side by side)")
    s = runs["serial"]
    print(f"serial:              {n / s['wall_s']:5.1f} cells/s  (mean cell compute {1e3 * s['compute_s'] / n:.1f} ms)")
    for w in (1, 2):
        d = runs[w]
        busy = d["wall_s"] - d["cluster_start_s"] - d["cluster_stop_s"]
        per_cell = d["compute_s"] / n
        overhead = (w * busy - d["compute_s"]) / n
        print(f"local cluster x{w}:    {n / d['wall_s']:5.1f} cells/s  ({n / busy:.1f} between {d['cluster_start_s']:.1f} s "
              f"start-up and {d['cluster_stop_s']:.1f} s shut-down); mean cell compute on a worker {1e3 * per_cell:.1f} ms; engine overhead per cell "
              f"{1e3 * overhead:.1f} ms = {100 * overhead / per_cell:.1f} %")


if __name__ == "__main__":
    main()
