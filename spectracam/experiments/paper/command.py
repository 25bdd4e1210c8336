"""``spectracam paper``: the paper's Figures 4, 5a, 5b and 6 reproduced (a self-contained click command,
registered lazily by :mod:`spectracam.cli`)."""
from __future__ import annotations

import click

from spectracam.experiments.options import (check_writable, default_experiment, experiment_option, given,
                                            no_cache_option, output_option, progress_log, quiet_option,
                                            renderer_option, set_option, timed_step, view_option)

__all__ = ["paper_cmd"]


@click.command("paper", short_help="Reproduce the paper's Figures 4, 5a, 5b and 6.")
@output_option("Directory to write the figures, results.json, report.md and the case files into.")
@experiment_option()
@renderer_option
@click.option("--quick", is_flag=True, help="A first look: 160x120 pixels instead of the scene's size.")
@no_cache_option
@click.option("--save-cubes", is_flag=True, help="Also write every light's spectral radiance cube into DIR/cases "
              "(~37 MB each; they are in the render cache).")
@set_option
@quiet_option
@view_option
def paper_cmd(out_dir, experiment_file, renderer, quick, no_cache, save_cubes, sets, quiet):
    """Reproduce the paper's Figures 4, 5a, 5b and 6: figures, results.json, report.md, case files."""
    from spectracam.experiments.paper.experiment import load_experiment, quick_scene, run_paper
    from spectracam.experiments.paper.report import write_paper_outputs

    from spectracam.pipeline import check_memory

    path = experiment_file or default_experiment()
    exp = load_experiment(path, sets)
    base = quick_scene(exp.base, quick)
    check_memory(base, copies=len(exp.temperatures_K) + 1, what=f", {len(exp.temperatures_K) + 1} lights held at once")
    check_writable(out_dir)
    log = progress_log(quiet)
    step = timed_step(log)
    results, cases, cubes = run_paper(exp, renderer=renderer, quick=quick, use_cache=not no_cache, step=step,
                                      log=log, progress=not quiet)
    command = "spectracam paper -o " + str(out_dir) + given("--experiment", "experiment_file", experiment_file) \
        + (f" --renderer {renderer}" if renderer != "mitsuba" else "") + (" --quick" if quick else "") \
        + "".join(f" --set {s}" for s in sets)
    write_paper_outputs(out_dir, results, cases, cubes, command, step, save_cubes=save_cubes)
    for c in results["claims"]:
        log(f"  {c['verdict']:<10} {c['claim']}: {c['measured']}")
    step(f"done: {out_dir}/report.md (figures fig4-6.png/.svg, results.json, cases/ with every capture's raw.exr "
         "and rendered.exr)")
