"""Time each stage of the spatial experiment (render, optics, capture, processing, metrics) per target.

    python3 tools/bench_spatial.py [--quick] [--renderer mitsuba|analytic] [--set PATH=VALUE ...]

Runs the experiment in this process (no output files) and prints a table of seconds per stage and
target, then the total. A second pass (``--warm``) times it again with Mitsuba's kernels compiled.
Last, the scene reference's cost: the Nyquist band-limited reference against the pixel-footprint average
on one edge-sized sub-pixel cube (as a ratio, timed in the same run).
"""
from __future__ import annotations

import argparse
import time


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--renderer", default="mitsuba", choices=("mitsuba", "analytic"))
    ap.add_argument("--warm", action="store_true", help="run twice; report the second (kernels compiled)")
    ap.add_argument("--set", dest="sets", action="append", default=[])
    a = ap.parse_args()

    from spectracam.experiments.spatial.experiment import STAGES, load_spatial, run_spatial

    spec, scene = load_spatial(a.sets, quick=a.quick)
    for i in range(2 if a.warm else 1):
        t0 = time.perf_counter()
        res = run_spatial(spec, scene, renderer=a.renderer, keep_images=False)
        wall = time.perf_counter() - t0
    print(f"spatial experiment, renderer {a.renderer}{', quick' if a.quick else ''}{', warm' if a.warm else ''}: "
          f"{len(res['rows'])} rows, {wall:.1f} s")
    print(f"{'target':<18}" + "".join(f"{s:>12}" for s in STAGES) + f"{'total':>12}")
    for t, st in res["timings"].items():
        print(f"{t:<18}" + "".join(f"{st[s]:12.2f}" for s in STAGES) + f"{sum(st.values()):12.2f}")
    tot = {s: sum(st[s] for st in res["timings"].values()) for s in STAGES}
    print(f"{'all':<18}" + "".join(f"{tot[s]:12.2f}" for s in STAGES) + f"{sum(tot.values()):12.2f}")
    reference_cost(spec, scene)


def reference_cost(spec, scene, repeats: int = 5) -> None:
    """Seconds of ``band_limited()`` and ``pixel_average()`` on a cube of the edge's size with margin."""
    import numpy as np

    from spectracam.experiments.spatial.render import SubpixelCube

    ss = spec.supersampling
    w, h = (x + 2 * 16 for x in spec.edge_size_px)
    rng = np.random.default_rng(0)
    cube = SubpixelCube(rng.random((h * ss, w * ss, len(scene.grid)), dtype=np.float32),
                        np.asarray(scene.grid.centres_nm), ss, None)
    t = {}
    for name in ("pixel_average", "band_limited"):
        t0 = time.perf_counter()
        for _ in range(repeats):
            getattr(cube, name)()
        t[name] = (time.perf_counter() - t0) / repeats
    print(f"reference on a {w}×{h} px cube ({ss}×{ss} sub-pixels, {len(scene.grid)} bands): footprint "
          f"{t['pixel_average']:.3f} s, Nyquist {t['band_limited']:.3f} s = {t['band_limited'] / t['pixel_average']:.1f}× "
          "the footprint")


if __name__ == "__main__":
    main()
