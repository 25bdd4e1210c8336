"""``spectracam white-balance``: the white-balance estimators' angular errors per sensor (a self-contained
click command, registered lazily by :mod:`spectracam.cli`)."""
from __future__ import annotations

import click

from spectracam.experiments.options import (RegistryChoice, check_writable, output_option, progress_log,
                                            quiet_option, set_option, timed_step, view_option)

__all__ = ["white_balance_cmd"]


def _analytic_renderer_option(f):
    """``--renderer`` as :data:`~spectracam.experiments.options.renderer_option`, the closed form by default (a
    render does not depend on the sensor, and the white-balance statistics need many)."""
    from spectracam.render import RENDERERS

    return click.option("--renderer", type=RegistryChoice(RENDERERS, "--renderer"), default="analytic",
                        show_default=True, help="The closed form or Mitsuba (Monte Carlo).")(f)


@click.command("white-balance", short_help="The white-balance estimators' angular errors per sensor.")
@output_option("Directory to write results.json, report.md and white_balance.png/.svg into.")
@click.option("--quick", is_flag=True, help="A first look: 160x120 pixels and 1 noise seed.")
@click.option("--seeds", type=click.IntRange(1, 100), default=None,
              help="Noise seeds per case [default: 3; 1 with --quick].")
@_analytic_renderer_option
@set_option
@quiet_option
@view_option
def white_balance_cmd(out_dir, quick, seeds, renderer, sets, quiet):
    """Every white-balance estimator but the oracle on the same captures — the paper's camera, each shipped measured
    camera and a Luther camera, each on the ColorChecker, Mondrian, dead leaves and photograph under 16 lights
    (blackbodies 2700–7500 K, CIE D50/D65/D75, FL2/FL7/FL11, LED-B1/B3/BH1/V1): recovery and reproduction angular
    errors, their mean, median and 95th percentile per sensor; results.json, report.md, white_balance.png/.svg.
    --set PATH=VALUE changes every case's scene (e.g. sensor.read_noise_e=5, processing.white_balance_p=4)."""
    from spectracam.experiments.white_balance.experiment import plan, run_white_balance, summary_line, write_white_balance_outputs
    from spectracam.pipeline import check_memory

    run = plan(quick=quick, seeds=seeds, renderer=renderer, sets=sets)   # every scene validated before any work
    check_memory(run.scenes[run.sensors[0].key]["photo"], copies=4, what=", a render and its captures per worker")
    check_writable(out_dir)
    log = progress_log(quiet)
    step = timed_step(log)
    step(f"{len(run.sensors)} sensors × {run.cases_per_sensor} scene × light cases × {run.seeds} "
         f"seed(s), renderer {renderer}")
    result = run_white_balance(run, log=step, progress=not quiet)
    command = "spectracam white-balance -o " + str(out_dir) + (" --quick" if quick else "") \
        + (f" --seeds {seeds}" if seeds else "") + (f" --renderer {renderer}" if renderer != "analytic" else "") \
        + "".join(f" --set {s}" for s in sets)
    paths = write_white_balance_outputs(out_dir, result, command)
    for s in run.sensors:
        log(summary_line(result, s.key))
    log("wrote " + ", ".join(str(p) for p in paths if p.suffix != ".svg"))
