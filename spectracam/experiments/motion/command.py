"""``spectracam motion``: a moving edge captured by each architecture (a self-contained click command,
registered lazily by :mod:`spectracam.cli`)."""
from __future__ import annotations

import time
from pathlib import Path

import click

from spectracam.experiments.options import (check_target_renderer, check_writable, log_report, output_option,
                                            progress_log, quiet_option, renderer_option, set_option, target_command,
                                            view_option)

__all__ = ["motion_cmd"]


@click.command("motion", short_help="Colour breakup of a moving edge, per architecture.")
@output_option("Directory to write results.json, mtf_curves.json, report.md, the figures and fsc_frames.gif into.")
@click.option("--quick", is_flag=True, help="A first look: a 64×64 edge, 20-nm bands, 8 speeds, 8 samples per sub-pixel.")
@renderer_option
@click.option("--no-images", is_flag=True, help="Skip images/ and maps/: every case's EXR, PNG and error map (the "
              "figures, results.json and report.md are written).")
@set_option
@quiet_option
@view_option
def motion_cmd(out_dir: Path, quick: bool, renderer: str, no_images: bool, sets, quiet: bool):
    """Motion: a neutral slanted edge moving at a sweep of speeds, captured by cfa/single, prism/optimal,
    fsc/optimal and fsc/balanced with a global and a rolling shutter (time slices rendered by Mitsuba);
    colour-breakup width, S-CIELAB, MTF along the motion, SNR; results.json, figures, report.md."""
    from spectracam.experiments.motion.experiment import check_motion_memory, load_motion, run_motion
    from spectracam.experiments.motion.report import answer, write_outputs

    spec, scene = load_motion(sets, quick=quick)   # validated before any work
    check_target_renderer(renderer, "moving targets")
    estimate = check_motion_memory(spec, scene)
    check_writable(out_dir)
    log = progress_log(quiet)
    log(estimate.line())
    t0 = time.perf_counter()
    result = run_motion(spec, scene, renderer=renderer, log=log, progress=not quiet)
    command = target_command("motion", out_dir, quick, renderer, sets) + (" --no-images" if no_images else "")
    paths = write_outputs(out_dir, result, command, images=not no_images)
    log_report(log, t0, answer(result), paths, out_dir)
