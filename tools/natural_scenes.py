"""The shipped natural scenes (issue 19) through the paper's three designs: the README's table and picture.

    python3 tools/natural_scenes.py [--seeds 0,1,2] [--picture docs/natural_scenes.png]

Each scene (scenes/cfi99.toml, mondrian.toml, dead_leaves.toml, photo.toml) is rendered once by Mitsuba, then
captured by the Bayer CFA, the dichroic prism and field-sequential colour (each with the paper's optimal
exposure where it has one) at every seed and scored per pixel against its known spectra.  Prints, per scene
and design, the mean ± standard deviation over seeds of: per-pixel ΔE*ab (mean, 95th percentile), S-CIELAB
mean, the samples' ΔE of their interior mean, and (noise-free) the conversion's error on the same samples;
the conversion's training error on the chart is printed once per scene.  The picture shows, per scene, the
truth (sRGB of the known spectra), the CFA's rendering and its per-pixel ΔE*ab.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
SCENES = ("cfi99", "mondrian", "dead_leaves", "photo")
DESIGNS = ("cfa/single", "prism/optimal", "fsc/optimal")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--picture", default=None, help="write the picture here (PNG)")
    args = ap.parse_args()
    seeds = [int(s) for s in args.seeds.split(",")]

    from spectracam.processing.color import adaptation_matrix, display_rgb_to_xyz
    from spectracam.io.report import srgb_preview
    from spectracam.pipeline import capture, score
    from spectracam.scene.reference import TargetReference
    from spectracam.render import render
    from spectracam.pipeline.scene_file import load_scene

    keys = ("delta_e_mean", "delta_e_p95", "s_cielab_mean", "sample_delta_e_of_mean_mean",
            "sample_delta_e_conversion_mean")
    print("| scene | light | design | ΔE*ab per pixel, mean | 95th pct | S-CIELAB mean | samples' ΔE of mean | "
          "conversion alone | training (chart) |")
    print("|---|---|---|---|---|---|---|---|---|")
    panels = []
    for name in SCENES:
        scene = load_scene(ROOT / "scenes" / f"{name}.toml")
        cube = render(scene, "mitsuba")
        for design in DESIGNS:
            s = scene.replace(camera=scene.camera.with_design(design))
            rows = []
            for seed in seeds:
                result = score(capture(cube, seed=seed, scene=s), s)
                rows.append([result.held_out[k] for k in keys])
                if design == "cfa/single" and seed == seeds[0]:
                    shown = result
            m, sd = np.mean(rows, axis=0), np.std(rows, axis=0)
            cells = " | ".join(f"{a:.2f} ± {b:.2f}" for a, b in zip(m[:4], sd[:4]))
            print(f"| {name} | {scene.illuminant.label} | {design} | {cells} | {m[4]:.2f} | "
                  f"{result.training['delta_e_mean']:.2f} |")
        ref = TargetReference.of(scene)
        M_disp = display_rgb_to_xyz(scene.processing.display)
        to_display = adaptation_matrix(ref.white_xyz, M_disp.sum(axis=1), scene.processing.adaptation)
        truth_rgb = ref.pixel_mean(ref.xyz) @ to_display.T @ np.linalg.inv(M_disp).T
        panels.append((scene.name, srgb_preview(truth_rgb, scene.processing.display),
                       srgb_preview(shown.rendered_rgb, scene.processing.display), shown.delta_e_map,
                       shown.held_out["delta_e_mean"]))
    if args.picture:
        from spectracam.io.plots import pyplot, save_figure

        plt = pyplot()
        fig, axes = plt.subplots(3, len(panels), figsize=(3.4 * len(panels), 8.4),
                                 gridspec_kw={"hspace": 0.12, "wspace": 0.05})
        for j, (title, truth, shown_rgb, de, mean) in enumerate(panels):
            axes[0, j].imshow(truth)
            axes[0, j].set_title(title, fontsize=8)
            axes[1, j].imshow(shown_rgb)
            im = axes[2, j].imshow(de, cmap=plt.get_cmap("magma").with_extremes(bad="#d0d0d0"), vmin=0, vmax=20,
                                   interpolation="nearest")
            axes[2, j].set_title(f"seed {seeds[0]}: mean {mean:.2f}", fontsize=8)
        for i, label in enumerate(("the scene (its known spectra)", "Bayer CFA, rendered", "ΔE*ab per pixel")):
            axes[i, 0].set_ylabel(label, fontsize=9)
        for ax in axes.ravel():
            ax.set_xticks([])
            ax.set_yticks([])
        bar = fig.colorbar(im, cax=axes[2, -1].inset_axes([1.04, 0.0, 0.05, 1.0]), extend="max")
        bar.set_label("ΔE*ab (fixed 0–20)", fontsize=8)
        save_figure(fig, Path(args.picture))
        print(f"wrote {args.picture}")


if __name__ == "__main__":
    main()
