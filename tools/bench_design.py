"""Design by gradient against the grid sweep, timed in the same run (ratios, since these machines are noisy).

    python3 tools/bench_design.py [--trials 3] [--renderer mitsuba|analytic] [--skip-freeform]

1. The grid: the shipped sweep ``sweeps/cfa_cutoffs.toml`` — cfa/single, block cutoffs 450–530 × 570–650 nm in
   10-nm steps, 3000 K and 6500 K, 3 trials, 320×240 px — every cell through capture → score (81 × 2 × 3 = 486
   pipeline runs); its best pair is the lowest chart ΔE*ab averaged over lights and trials.
2. The block design from the paper's 490/610 nm on the same camera, lights and chart (the training set is the
   chart, as the grid's score is), verified by Monte Carlo through the same pipeline (3 seeds per light).
3. A free-form design of one architecture (cfa/single) with the shipped design file's settings.
Prints the evaluations, seconds, the design's distance to the grid's best pair (nm) and ΔE difference, and the
ratios; the issue's targets: ≥ 50× fewer pipeline runs, ≤ 60 s for the block design, ≤ 5 min for free-form.
"""
from __future__ import annotations

import argparse
import time

import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=3)
    ap.add_argument("--renderer", default="mitsuba", choices=("mitsuba", "analytic"))
    ap.add_argument("--skip-freeform", action="store_true")
    a = ap.parse_args()

    from spectracam.io.cache import cached_render
    from spectracam.experiments.design.optimise import optimise
    from spectracam.experiments.design.problem import DesignProblem
    from spectracam.experiments.design.run import monte_carlo
    from spectracam.experiments.design.spec import DesignSpec, load_design
    from spectracam.experiments.paper.experiment import design_case
    from spectracam.experiments.sweep.experiment import trial_seed
    from spectracam.pipeline.scene_file import load_scene, shipped_scene_file

    base = load_scene(shipped_scene_file("blackbody_5000K.toml"), ["image.width=320", "image.height=240"])
    scenes = {T: base.replace(illuminant=base.illuminant.replace(temperature_K=float(T))) for T in (3000, 6500)}
    cubes = {f"{T}K": (s, cached_render(s, a.renderer)[0]) for T, s in scenes.items()}
    cam, proc = base.camera, base.processing

    t0 = time.perf_counter()
    grid, runs = {}, 0
    for c1 in range(450, 531, 10):
        for c2 in range(570, 651, 10):
            c = cam.replace(filters=cam.filters.replace(cutoffs_nm=(float(c1), float(c2))))
            des = []
            for scene, cube in cubes.values():
                for t in range(a.trials):
                    des.append(design_case(cube, scene, c, proc, "cfa/single", trial_seed(0, t))["delta_e"])
                    runs += 1
            grid[(c1, c2)] = float(np.mean(des))
    t_grid = time.perf_counter() - t0
    best = min(grid, key=grid.get)
    print(f"grid: {runs} pipeline runs in {t_grid:.1f} s; best pair {best[0]}/{best[1]} nm, chart ΔE {grid[best]:.3f} "
          f"(paper's 490/610: {grid[(490, 610)]:.3f})")

    t0 = time.perf_counter()
    spec = DesignSpec(filters="block", seeds=3)
    problem = DesignProblem("cfa/single", "block", spec, cam, proc, [s for s, _ in cubes.values()], "colorchecker24",
                            "cfi99")
    opt = optimise(problem, max_iterations=spec.max_iterations, tolerance=spec.tolerance)
    t_opt = time.perf_counter() - t0
    mc = monte_carlo(problem.camera_of(opt.x), cubes, proc, spec.seeds)
    t_design = time.perf_counter() - t0
    mc_runs = spec.seeds * len(cubes)
    dist = np.abs(opt.x - np.array(best, float))
    print(f"block design: {opt.evaluations} model evaluations ({opt.iterations} iterations) in {t_opt:.1f} s, then "
          f"{mc_runs} pipeline runs (Monte Carlo) — {t_design:.1f} s in all; cutoffs {opt.x[0]:.1f}/{opt.x[1]:.1f} nm")
    print(f"  distance to the grid's best pair: {dist[0]:.1f} and {dist[1]:.1f} nm (target ≤ 10); chart ΔE "
          f"{mc['mean']:.3f} ± {mc['std']:.3f} Monte Carlo, {mc['mean'] - grid[best]:+.3f} against the grid's best "
          f"(target ≤ +0.1)")
    print(f"  pipeline runs: grid / design = {runs} / {mc_runs} = {runs / mc_runs:.0f}× (target ≥ 50×); counting "
          f"every model evaluation as one run per light: {runs} / {opt.evaluations * len(cubes) + mc_runs} = "
          f"{runs / (opt.evaluations * len(cubes) + mc_runs):.1f}×")
    print(f"  time: grid / design = {t_grid:.1f} / {t_design:.1f} s = {t_grid / t_design:.1f}× (target ≤ 60 s)")

    if not a.skip_freeform:
        fspec, _ = load_design(shipped_scene_file("design.toml"), ["designs=['cfa/single']"])
        from spectracam.experiments.design.run import setup

        st = setup(fspec, shipped_scene_file("design.toml").parent)
        t0 = time.perf_counter()
        p = DesignProblem("cfa/single", "freeform", fspec, st.camera, st.processing, list(st.scenes), fspec.training,
                          fspec.held_out)
        o = optimise(p, max_iterations=fspec.max_iterations, tolerance=fspec.tolerance)
        t_free = time.perf_counter() - t0
        print(f"free-form cfa/single ({p.n_param} variables, {fspec.training} × {len(st.scenes)} lights): "
              f"{o.evaluations} evaluations in {t_free:.1f} s (target ≤ 300 s; {t_free / t_grid:.2f}× the grid's time)")


if __name__ == "__main__":
    main()
