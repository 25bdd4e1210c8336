"""``spectracam consistency``: which readings of the paper's open choices reproduce which of its claims (a
self-contained click command, registered lazily by :mod:`spectracam.cli`)."""
from __future__ import annotations

import click

from spectracam.experiments.options import (check_writable, default_experiment, experiment_option, given,
                                            output_option, progress_log, quiet_option, renderer_option, set_option,
                                            view_option)

__all__ = ["consistency_cmd"]


@click.command("consistency", short_help="Map which readings of the paper reproduce its claims.")
@output_option("Directory to write consistency.json, consistency.md and the map (PNG, SVG) into.")
@experiment_option()
@renderer_option
@click.option("--full", is_flag=True, help="The scene's full image size instead of 160x120.")
@set_option
@quiet_option
@view_option
def consistency_cmd(out_dir, experiment_file, renderer, full, sets, quiet):
    """Which readings of the paper's open choices reproduce which of its claims: a map and a table."""
    from spectracam.experiments.consistency.experiment import run_consistency, write_consistency_outputs
    from spectracam.experiments.paper.experiment import load_experiment

    exp = load_experiment(experiment_file or default_experiment(), sets)
    from spectracam.pipeline import check_memory

    if full:  # the quick map is 160x120: nothing to estimate
        check_memory(exp.base, copies=len(exp.temperatures_K) + 1, what=f", {len(exp.temperatures_K) + 1} lights")
    check_writable(out_dir)
    log = progress_log(quiet)
    result = run_consistency(exp, renderer=renderer, quick=not full, log=log, progress=not quiet)
    command = "spectracam consistency -o " + str(out_dir) \
        + given("--experiment", "experiment_file", experiment_file) + f" --renderer {renderer}" \
        + (" --full" if full else "") + "".join(f" --set {s}" for s in sets)
    paths = write_consistency_outputs(out_dir, result, command)
    log(f"{len(result['rows'])} readings in {result['seconds']:.0f} s; wrote " + ", ".join(
        str(p) for p in paths if p.suffix != ".svg"))
