"""Benchmark: Mitsuba render of the 640x480, 31-band chart (issue 2 targets: ≤ 3 s warm, ≤ 10 s cold).

    python3 tools/bench_render.py [--scene scenes/blackbody_5000K.toml] [--repeats 3]

cold = a fresh Python process whose drjit kernel cache is empty (HOME points at a new temporary
directory, so ~/.drjit is new): import, variant probe, scene build, kernel compilation, 31 bands.
warm = the same render again in a process that has already rendered once.
Also prints the per-pixel Monte Carlo noise of the render against the analytic cube, and times the
band-constant, light-weighted spectra (issue 17) against the previous sampled spectra in the same run
(target: no more than 2x the time, with the per-pixel noise gone).
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

_COLD = """
import time, sys
t0 = time.perf_counter()
from spectracam import load_scene, render
cube = render(load_scene(sys.argv[1]), "mitsuba")
print(time.perf_counter() - t0, cube.metadata["variant"])
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default=str(ROOT / "scenes" / "blackbody_5000K.toml"))
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()

    import numpy as np

    from spectracam import load_scene, render
    from spectracam.scene.chart import patch_masks

    scene = load_scene(args.scene)
    colds = []
    for _ in range(args.repeats):
        with tempfile.TemporaryDirectory() as home:
            env = dict(os.environ, HOME=home, PYTHONPATH=str(ROOT))
            t0 = time.perf_counter()
            out = subprocess.run([sys.executable, "-c", _COLD, args.scene], env=env, capture_output=True,
                                 text=True, check=True).stdout.split()
            colds.append((time.perf_counter() - t0, float(out[0]), out[1]))
    render(scene, "mitsuba")  # compile
    warms = []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        cube = render(scene, "mitsuba")
        warms.append(time.perf_counter() - t0)
    ref = render(scene, "analytic")
    masks = patch_masks(scene.chart, scene.image.width, scene.image.height)

    def noise_of(c):
        return np.median([np.std(c.radiance[m] / ref.radiance[m], axis=0).mean() for m in masks])

    from spectracam.render.mitsuba import render_mitsuba

    noise = noise_of(cube)
    render_mitsuba(scene, within_band="sampled")  # warm
    sampled_t, weighted_t = [], []
    for _ in range(args.repeats):  # interleaved: the machine's drift hits both alike
        t0 = time.perf_counter()
        sampled = render_mitsuba(scene, within_band="sampled")
        sampled_t.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        render_mitsuba(scene, within_band="light-weighted")
        weighted_t.append(time.perf_counter() - t0)

    h, w, b = cube.shape
    print(f"scene {args.scene}: {w}x{h} px, {b} bands, {scene.render.samples_per_pixel} spp, variant {colds[0][2]}")
    print(f"cold (fresh process, empty kernel cache): best {min(c[0] for c in colds):.2f} s wall "
          f"[in-process {min(c[1] for c in colds):.2f} s]  (target ≤ 10 s)")
    print(f"warm (same process, second render):      best {min(warms):.2f} s, median {sorted(warms)[len(warms) // 2]:.2f} s  (target ≤ 3 s)")
    print(f"throughput warm: {w * h * b / min(warms) / 1e6:.1f} M pixel-bands/s")
    print(f"per-pixel Monte Carlo noise vs analytic (median over patches): {100 * noise:.5f} %")
    print(f"light-weighted band spectra vs the previous sampled spectra (same run, best of {args.repeats}): time ratio "
          f"{min(weighted_t) / min(sampled_t):.2f} (target ≤ 2), per-pixel noise {100 * noise:.5f} % vs "
          f"{100 * noise_of(sampled):.3f} %")


if __name__ == "__main__":
    main()
