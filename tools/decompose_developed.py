"""Where the developed camera's error comes from, step by step, on the paper's chart (issue 33).

    python3 tools/decompose_developed.py [--temperatures 3000,5000,7000] [--designs cfa/single,fsc/optimal]
        [--renderer analytic|mitsuba] [--seed 0]

For each light and design, the chart's mean per-pixel ΔE*ab (one seed; the paper's camera and light level) of:

1. the oracle: exposure on the white patch, white and conversion under the scene's own light (the paper's);
2. the DNG calibration alone: two matrices (CIE A, D65) interpolated by the CCT of the *true* neutral, the true
   white's level (``processing.calibration = "dual_illuminant"``, ``white_balance = "oracle"``);
3. + the estimated white: the trained estimator (``corrected_moments``), still the true white's level;
4. + the metered level: the developed camera as it runs — percentile metering, its implied white shown at Y = 1.

Steps 2 and 3 are computed on the developed camera's own capture with its recorded metered level replaced by the
true white's (``RawCapture.metered_rate_e_per_s = None``: :func:`spectracam.processing.develop` then uses the true
neutral's level); step 4 is what ``both_ways`` reports.
"""
from __future__ import annotations

import argparse
import dataclasses
import sys


def main(argv=None) -> int:
    from spectracam import pipeline
    from spectracam.camera.capture import capture
    from spectracam.experiments.paper.experiment import calibrated_luminance, load_experiment, scenes_for
    from spectracam.pipeline import camera_processing
    from spectracam.processing import metered_camera
    from spectracam.scene.reference import ChartReference
    from spectracam.pipeline.scene_file import shipped_scene_file
    from spectracam.evaluation.score import score

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--temperatures", default="3000,5000,7000")
    ap.add_argument("--designs", default="cfa/single,fsc/optimal,prism/optimal")
    ap.add_argument("--renderer", default="analytic", choices=("analytic", "mitsuba"))
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args(argv)
    exp = load_experiment(shipped_scene_file("paper.toml"))
    level = calibrated_luminance(exp, exp.base.camera)
    temps = [t.strip() for t in a.temperatures.split(",") if t.strip()]
    designs = [d.strip() for d in a.designs.split(",") if d.strip()]
    scenes = scenes_for(dataclasses.replace(exp, temperatures_K=tuple(float(t) for t in temps)), level, False)
    print(f"chart mean per-pixel ΔE*ab, {a.renderer} renderer, seed {a.seed}, the paper's camera at "
          f"{level:.1f} cd/m²")
    print(f"{'light':>6} {'design':<15} {'oracle':>7} {'DNG cal.':>9} {'+ est. white':>13} {'+ metered level':>16}")
    for T in temps:
        scene = scenes[f"{float(T):g}"]
        cube = pipeline.render(scene, a.renderer)
        ref = ChartReference.of(scene)
        developed = camera_processing(scene.processing, "developed")
        for design in designs:
            oracle = score(capture(cube, scene.camera.with_design(design), a.seed, ref.white_box), ref,
                           scene.processing).summary.delta_e_mean
            raw = capture(cube, metered_camera(scene.camera.with_design(design), developed), a.seed, ref.white_box)
            told_level = dataclasses.replace(raw, metered_rate_e_per_s=None)
            cal = score(told_level, ref, developed.replace(white_balance="oracle")).summary.delta_e_mean
            est = score(told_level, ref, developed).summary.delta_e_mean
            full = score(raw, ref, developed).summary.delta_e_mean
            print(f"{T:>5}K {design:<15} {oracle:7.2f} {cal:9.2f} {est:13.2f} {full:16.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
