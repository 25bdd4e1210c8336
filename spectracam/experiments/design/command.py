"""``spectracam design``: each architecture's filters designed by gradient (a self-contained click command,
registered lazily by :mod:`spectracam.cli`)."""
from __future__ import annotations

import click

from spectracam.experiments.options import (ShippedFile, as_given, check_writable, output_option, progress_log,
                                            quiet_option, set_option, timed_step, view_option)

__all__ = ["design_cmd"]


@click.command("design", short_help="Design each architecture's filters by gradient.")
@click.argument("spec_file", metavar="SPEC.toml", type=ShippedFile("design file"))
@output_option("Directory to write results.json, report.md, curves.csv and the figures into.")
@click.option("--quick", is_flag=True, help="A first look in under 2 minutes: 2 lights, 3 designs (cfa, prism, "
              "fsc with its exposure split) trained on the ColorChecker, 20-nm knots, 25 iterations, 2 seeds at "
              "160x120 pixels.")
@set_option
@quiet_option
@view_option
def design_cmd(spec_file, out_dir, quick, sets, quiet):
    """Design each architecture's filters (or stacked depths, IR-cut edge, exposure split) by gradient: minimise
    the expected ΔE*ab under the sensor's noise over a training library × lights with Dr.Jit's gradients; score
    on held-out colours; verify by Monte Carlo through capture → score; compare with the paper's filters, the
    grid's best block pair and the Luther camera.  SPEC.toml: a design file, or the name of a shipped one
    (design, with or without .toml)."""
    from spectracam.experiments.design.report import write_design_outputs
    from spectracam.experiments.design.run import run_design, setup
    from spectracam.experiments.design.spec import load_design

    spec, base_dir = load_design(spec_file, sets, quick=quick)
    st = setup(spec, base_dir)
    check_writable(out_dir)
    log = progress_log(quiet)
    step = timed_step(log)
    step(f"{len(spec.designs)} designs ({spec.filters} filters) on {spec.training} × {len(spec.lights)} lights")
    results = run_design(spec, base_dir, log=step, st=st, progress=not quiet)
    command = f"spectracam design {as_given('spec_file', spec_file)} -o {out_dir}" + (" --quick" if quick else "") \
        + "".join(f" --set {s}" for s in sets)
    write_design_outputs(out_dir, results, command, step)
    for name, e in results["designs"].items():
        mc, paper = e["monte_carlo_delta_e"], e["paper_filters"]
        log(f"  {name:<18} held-out ΔE {paper['held_out_delta_e']:.2f} → {e['held_out_delta_e']:.2f}; chart "
            f"expected {e['predicted_delta_e']['chart']:.2f}, Monte Carlo {mc['mean']:.2f} ± {mc['std']:.2f}")
