"""``spectracam architectures``: every architecture at the paper's camera and light (a self-contained click
command, registered lazily by :mod:`spectracam.cli`)."""
from __future__ import annotations

import click

from spectracam.experiments.options import (check_writable, default_experiment, experiment_option, given,
                                            no_cache_option, output_option, progress_log, quiet_option,
                                            renderer_option, set_option, timed_step, view_option)

__all__ = ["architectures_cmd"]


@click.command("architectures", short_help="Compare every architecture at the paper's camera and light.")
@output_option("Directory to write results.json, report.md and the figures into.")
@experiment_option("Experiment file whose camera, chart and light are used: a path or a shipped one's name "
                   "[default: paper, scenes/paper.toml].")
@renderer_option
@click.option("--quick", is_flag=True, help="A first look: 160x120 pixels and 2 noise seeds.")
@click.option("--seeds", type=click.IntRange(1, 100), default=None,
              help="Noise seeds per case [default: 5; 2 with --quick].")
@no_cache_option
@click.option("--min-white-snr-db", type=float, default=None,
              help="A case whose white patch's rendered SNR is below this is no usable image and never a winner "
                   "[default: 20, ISO 12232's 'acceptable' SNR 10].")
@click.option("--max-s-cielab", type=float, default=None,
              help="A case whose mean S-CIELAB ΔE*ab is above this is no usable image [default: 40, a flat grey "
                   "image of the chart's mean lightness].")
@set_option
@quiet_option
@view_option
def architectures_cmd(out_dir, experiment_file, renderer, quick, seeds, no_cache, min_white_snr_db, max_s_cielab,
                      sets, quiet):
    """Every registered architecture and exposure scheme at the paper's camera, light and noise, at 1, 1/10
    and 1/100 of its light: SNR, ΔE (training and held-out), capture time; then each architecture on the
    slanted edge and star (MTF50, false colour, S-CIELAB; with and without an optical low-pass filter) and
    on a moving edge (colour breakup); results.json, report.md, figures."""
    from spectracam.experiments.architectures.experiment import SEEDS, ArchitecturesRun, designs, run_architectures, \
        write_architectures_outputs
    from spectracam.experiments.paper.experiment import load_experiment, quick_scene
    from spectracam.pipeline import check_memory

    exp = load_experiment(experiment_file or default_experiment(), sets)
    from spectracam.evaluation.usability import UsabilitySpec

    limits = {k: v for k, v in (("min_white_snr_db", min_white_snr_db), ("max_s_cielab_mean", max_s_cielab))
              if v is not None}
    usability = UsabilitySpec.from_dict(limits, "the command line") if limits else UsabilitySpec()
    run = ArchitecturesRun(exp, quick=quick, seeds=seeds or (2 if quick else SEEDS), usability=usability)
    base = quick_scene(exp.base, quick)
    check_memory(base, copies=2, what=", two lights and a scaled copy held at once")
    check_writable(out_dir)
    log = progress_log(quiet)
    step = timed_step(log)
    step(f"{len(designs())} designs: {', '.join(designs())}")
    results = run_architectures(run, renderer=renderer, use_cache=not no_cache, step=step, log=log,
                                progress=not quiet)
    command = "spectracam architectures -o " + str(out_dir) \
        + given("--experiment", "experiment_file", experiment_file) \
        + (f" --renderer {renderer}" if renderer != "mitsuba" else "") + (" --quick" if quick else "") \
        + (f" --seeds {seeds}" if seeds else "") \
        + (f" --min-white-snr-db {min_white_snr_db:g}" if min_white_snr_db is not None else "") \
        + (f" --max-s-cielab {max_s_cielab:g}" if max_s_cielab is not None else "") + "".join(f" --set {s}" for s in sets)
    write_architectures_outputs(out_dir, results, command, step)
    for w in results["winners"]:
        log(f"  {w['illuminant']:>7} {w['light_factor']:>5g}x  {w['metric']:<16} "
            + (f"{w['design']:<18} {w['value']:.3g}" if w["design"] is not None else w.get("note", "no usable image")))
