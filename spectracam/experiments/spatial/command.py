"""``spectracam spatial``: the spatial comparison of the architectures (a self-contained click command,
registered lazily by :mod:`spectracam.cli`)."""
from __future__ import annotations

import time
from pathlib import Path

import click

from spectracam.experiments.options import (check_target_renderer, check_writable, log_report, output_option,
                                            progress_log, quiet_option, renderer_option, set_option, target_command,
                                            view_option)

__all__ = ["spatial_cmd"]


@click.command("spatial", short_help="Compare the architectures' spatial fidelity: MTF, colour.")
@output_option("Directory to write results.json, mtf_curves.json, report.md, the figures and maps/ into.")
@click.option("--quick", is_flag=True, help="A first look: half-size images, 20-nm bands, 2 samples per sub-pixel.")
@renderer_option
@click.option("--no-maps", is_flag=True, help="Skip cases/: every design's image of every case and target (EXR, PNG, error map).")
@set_option
@quiet_option
@view_option
def spatial_cmd(out_dir: Path, quick: bool, renderer: str, no_maps: bool, sets, quiet: bool):
    """Spatial comparison: slanted edge, Siemens star and tilted chart through diffraction, the pixel
    aperture and each design (CFA + demosaicking, prism aligned/misaligned, FSC); e-SFR MTF50, false
    colour, S-CIELAB; results.json, figures, report.md."""
    from spectracam.experiments.spatial.experiment import load_spatial, run_spatial
    from spectracam.experiments.spatial.report import answer, write_outputs

    spec, scene = load_spatial(sets, quick=quick)   # validated before any work
    check_target_renderer(renderer, "spatial targets")
    check_writable(out_dir)
    log = progress_log(quiet)
    t0 = time.perf_counter()
    result = run_spatial(spec, scene, renderer=renderer, log=log, progress=not quiet)
    paths = write_outputs(out_dir, result, target_command("spatial", out_dir, quick, renderer, sets), maps=not no_maps)
    log_report(log, t0, answer(result), paths, out_dir)
