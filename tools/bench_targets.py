"""Benchmark: a 1-Mpx dead-leaves target (30 bands, measured spectra per pixel) against the chart, both
rendered by Mitsuba at the same size and samples per pixel (issue 19 target: at most 3x the chart's time).

    python3 tools/bench_targets.py [--size 1024] [--repeats 3] [--kinds dead_leaves,mondrian,photo]

Warm timings (one small render of each first compiles the kernels), the median of ``--repeats``, each
kind's ratio to the chart timed in the same run.  A target's time includes drawing its layout (the label
image is memoised, so it is drawn in the first repeat only: that time is printed on its own).
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=1024, help="pixels across and down (default 1024: 1.05 Mpx)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--kinds", default="dead_leaves")
    args = ap.parse_args()

    from spectracam.scene.reference import TargetReference
    from spectracam.render import render
    from spectracam.pipeline.scene_file import Scene

    def scene(kind: str, size: int) -> Scene:
        target = {} if kind == "chart" else {"target": {"kind": kind}}
        return Scene.from_dict({**target, "image": {"width": size, "height": size},
                                "wavelengths": {"start_nm": 400, "stop_nm": 700, "step_nm": 10},
                                "illuminant": {"type": "cie", "name": "D65"}})

    kinds = ["chart", *args.kinds.split(",")]
    for k in kinds:                     # compile every kernel first
        render(scene(k, 64), "mitsuba")
    s0 = scene("chart", args.size)
    print(f"{args.size}x{args.size} px, {len(s0.grid)} bands, {s0.render.samples_per_pixel} samples per pixel, "
          f"variant {render(scene('chart', 64), 'mitsuba').metadata['variant']}")
    times = {}
    for k in kinds:
        sc = scene(k, args.size)
        if k != "chart":
            t0 = time.perf_counter()
            TargetReference.of(sc)
            print(f"  {k}: layout and truth drawn in {time.perf_counter() - t0:.2f} s (once; memoised)")
        runs = []
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            render(sc, "mitsuba")
            runs.append(time.perf_counter() - t0)
        times[k] = statistics.median(runs)
    for k in kinds:
        ratio = "" if k == "chart" else f"   {times[k] / times['chart']:.2f}x the chart (target ≤ 3x)"
        print(f"{k:>12}: {times[k]:6.2f} s{ratio}")


if __name__ == "__main__":
    main()
