"""Benchmark: the full `spectracam paper` run, time per stage (issue 5 target: ≤ 60 s warm).

    python3 tools/bench_paper.py [--renderer mitsuba|analytic]

Runs twice in this process into a temporary directory and render cache: first with an empty render
cache (Mitsuba renders included, kernels compiled), then again (renders served from the cache).
"""
from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--renderer", default="mitsuba", choices=("mitsuba", "analytic"))
    args = ap.parse_args()
    from spectracam.experiments.paper.experiment import load_experiment, run_paper
    from spectracam.experiments.paper.report import write_paper_outputs

    exp = load_experiment(ROOT / "scenes" / "paper.toml")
    with tempfile.TemporaryDirectory() as tmp:
        os.environ["SPECTRACAM_CACHE"] = str(Path(tmp) / "cache")
        for label in ("empty render cache", "renders cached"):
            t0 = time.perf_counter()
            results, cases, cubes = run_paper(exp, renderer=args.renderer)
            t = time.perf_counter()
            write_paper_outputs(Path(tmp) / "out", results, cases, cubes, "bench")
            t_write = time.perf_counter() - t
            total = time.perf_counter() - t0
            s = results["timings_s"]
            print(f"{label:>19}: total {total:5.1f} s = render {s['render_s']:.1f} + designs/budget "
                  f"{s['designs_and_budget_s']:.1f} + sensitivity ({len(exp.alternatives)} alternatives) "
                  f"{s['sensitivity_s']:.1f} + figures/report/case files {t_write:.1f}  (target ≤ 60 s)")


if __name__ == "__main__":
    main()
