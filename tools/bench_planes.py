"""Benchmark: a capture rendered into the camera's channel planes against the same capture of the band cube.

    python3 tools/bench_planes.py [--width 4000 --height 3000] [--renderer analytic|mitsuba] [--repeats 3]

Issue 38 asks, for one fixed camera, for a render that integrates each band into the camera's channel planes as it
is rendered (:func:`spectracam.pipeline.render_planes`, ``simulate --channel-planes``), with its memory and time
against the band cube measured.  Each way runs in a fresh process, ``--repeats`` times (best time):
  cube:   render (H, W, B) → capture → score;
  planes: render_planes (H, W, N) → capture → score.
Printed per way: each stage's time, the render + capture peak (tracemalloc: every NumPy allocation alive at the peak;
and the resident-set high-water mark above the loaded process, VmHWM) and the score's; then planes / cube for each,
and how far the two captures agree: the fraction of digital numbers that differ (the rates differ by float32 rounding,
so a pixel on a quantisation step's edge may land one DN apart) and the scores' mean ΔE*ab and S-CIELAB.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))


def child(way: str, width: int, height: int, renderer: str, repeats: int) -> dict:
    """One way, in this process: times (best of ``repeats``), peaks, and the capture's digital numbers' digest."""
    import tracemalloc

    import numpy as np

    from bench_capture import _reset_hwm, _scene, _vm
    from spectracam.pipeline import capture, render, render_planes, score

    scene = _scene(width, height, False)
    small = _scene(160, 120, False)
    make = (lambda s: render_planes(s, renderer)) if way == "planes" else (lambda s: render(s, renderer))
    score(capture(make(small), scene=small), small)    # imports, kernels, tables
    out = {"render_s": [], "capture_s": [], "score_s": []}
    for i in range(repeats):
        if i == repeats - 1:
            base = _vm("VmRSS")
            _reset_hwm()
            tracemalloc.start()
        t0 = time.perf_counter()
        made = make(scene)
        t1 = time.perf_counter()
        raw = capture(made, scene=scene)
        t2 = time.perf_counter()
        if i == repeats - 1:
            out["render_capture_peak"] = tracemalloc.get_traced_memory()[1]
            hwm = _vm("VmHWM")
            out["render_capture_rss"] = None if None in (hwm, base) else hwm - base
            tracemalloc.reset_peak()
        result = score(raw, scene)
        t3 = time.perf_counter()
        if i == repeats - 1:
            out["score_peak"] = tracemalloc.get_traced_memory()[1]
            tracemalloc.stop()
        out["render_s"].append(t1 - t0)
        out["capture_s"].append(t2 - t1)
        out["score_s"].append(t3 - t2)
        del made
    out["cube_bytes"] = width * height * len(scene.grid) * 4
    np.save(os.environ["BENCH_PLANES_DN"], raw.digital)
    out["delta_e_mean"] = result.summary.delta_e_mean
    out["s_cielab_mean"] = result.summary.s_cielab_mean
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--width", type=int, default=4000)
    ap.add_argument("--height", type=int, default=3000)
    ap.add_argument("--renderer", default="analytic", choices=("analytic", "mitsuba"))
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--child", choices=("cube", "planes"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(json.dumps(child(args.child, args.width, args.height, args.renderer, args.repeats)))
        return
    import tempfile

    import numpy as np

    res, dn = {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        for way in ("cube", "planes"):
            path = os.path.join(tmp, f"{way}.npy")
            r = subprocess.run([sys.executable, os.path.abspath(__file__), "--child", way, "--width", str(args.width),
                                "--height", str(args.height), "--renderer", args.renderer, "--repeats",
                                str(args.repeats)], capture_output=True, text=True, env={**os.environ,
                                                                                         "BENCH_PLANES_DN": path})
            if r.returncode != 0:
                sys.exit(f"{way} run failed: {r.stderr.strip().splitlines()[-1:]}")
            res[way] = json.loads(r.stdout.strip().splitlines()[-1])
            dn[way] = np.load(path)
    c = res["cube"]["cube_bytes"]
    print(f"{args.width}x{args.height}, {args.renderer} renderer, best of {args.repeats}; float32 cube "
          f"{c / 2**30:.2f} GiB")
    for way, m in res.items():
        rss = m["render_capture_rss"]
        print(f"  {way:6s}: render {min(m['render_s']):.2f} s, capture {min(m['capture_s']):.3f} s, score "
              f"{min(m['score_s']):.2f} s; render+capture peak {m['render_capture_peak'] / c:.2f} cubes "
              f"(resident {'n/a' if rss is None else f'{rss / c:.2f}'}), score peak {m['score_peak'] / c:.2f} cubes")
    a, b = res["cube"], res["planes"]
    ratio = {k: min(b[k]) / min(a[k]) for k in ("render_s", "capture_s", "score_s")}
    print(f"planes / cube: render {ratio['render_s']:.2f}, capture {ratio['capture_s']:.2f}, score "
          f"{ratio['score_s']:.2f}; render+capture peak memory "
          f"{b['render_capture_peak'] / a['render_capture_peak']:.2f}"
          + ("" if None in (a["render_capture_rss"], b["render_capture_rss"]) else
             f" (resident {b['render_capture_rss'] / a['render_capture_rss']:.2f})"))
    print(f"agreement: {np.mean(dn['cube'] != dn['planes']):.2e} of digital numbers differ (max "
          f"{np.abs(dn['cube'] - dn['planes']).max():g} DN); mean ΔE*ab {a['delta_e_mean']:.6f} / "
          f"{b['delta_e_mean']:.6f}, S-CIELAB {a['s_cielab_mean']:.6f} / {b['s_cielab_mean']:.6f}")


if __name__ == "__main__":
    main()
