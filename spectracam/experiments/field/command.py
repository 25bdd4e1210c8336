"""``spectracam field``: which architecture keeps colour uniform to the corner, and with which microlens shift (a
self-contained click command, registered lazily by :mod:`spectracam.cli`)."""
from __future__ import annotations

import click

from spectracam.experiments.options import (RegistryChoice, check_writable, output_option, progress_log,
                                            quiet_option, set_option, timed_step, view_option)

__all__ = ["field_cmd"]


def _renderer_option(f):
    from spectracam.render import RENDERERS

    return click.option("--renderer", type=RegistryChoice(RENDERERS, "--renderer"), default="analytic",
                        show_default=True, help="The closed form or Mitsuba (Monte Carlo) for the chart.")(f)


@click.command("field", short_help="Which architecture keeps colour uniform to the corner.")
@output_option("Directory to write results.json, report.md, field.png/.svg and field_maps.png/.svg into.")
@click.option("--quick", is_flag=True, help="A first look: 320×240, 1 seed, microlens shifts 0 and 1.")
@click.option("--seeds", type=click.IntRange(1, 100), default=None, help="Noise seeds per case [default: 2; 1 with "
              "--quick].")
@click.option("--design", "designs", multiple=True, metavar="ARCH/EXPOSURE",
              help="A design to compare (repeatable) [default: cfa/single, prism/optimal, fsc/optimal].")
@click.option("--shift", "shifts", multiple=True, type=float, metavar="FRACTION",
              help="A microlens shift, as a fraction of what centres the corner's chief ray (repeatable) "
                   "[default: 0, 0.5, 1; 0, 1 with --quick].")
@click.option("--correction", "corrections", multiple=True, metavar="NAME",
              help="A lens-shading correction: none, single, cct (repeatable) [default: every one].")
@click.option("--cra", "cra_deg", type=float, default=25.0, show_default=True, metavar="DEGREES",
              help="The chief ray's angle at the sensor's corner (linear in image height; cos⁴ fall-off).")
@click.option("--pitch", "pitches", multiple=True, type=float, metavar="µm",
              help="A pixel pitch (repeatable) [default: 1.4 (a phone-class module) and 10 (the paper's sensor); 1.4 "
                   "with --quick].")
@_renderer_option
@set_option
@quiet_option
@view_option
def field_cmd(out_dir, quick, seeds, designs, shifts, corrections, cra_deg, pitches, renderer, sets, quiet):
    """Every design × microlens shift × lens-shading correction on a flat grey and on the ColorChecker filling the
    field of a lens whose chief ray reaches --cra degrees at the corner: the flat grey's colour from the centre to the
    corner (ΔE*ab from the centre's colour, luminance, S-CIELAB) and each chart patch's ΔE*ab from the same design on
    the axis.  --set PATH=VALUE changes the scene (e.g. pixel.stack_height_um=2.5)."""
    from spectracam.experiments.field.experiment import (DESIGNS, plan, run_field, summary_lines,
                                                         write_field_outputs)
    from spectracam.pipeline import check_memory

    run = plan(quick=quick, seeds=seeds, renderer=renderer, sets=sets, designs=tuple(designs) or DESIGNS,
               shifts=tuple(shifts) or None, corrections=tuple(corrections) or None, cra_deg=cra_deg,
               pitches_um=tuple(pitches) or None)
    check_memory(run.scene, copies=6, what=", a render, the flat field and their captures")
    check_writable(out_dir)
    log = progress_log(quiet)
    step = timed_step(log)
    step(f"{len(run.designs)} designs × {len(run.pitches_um)} pixel pitches × {len(run.shifts)} microlens shifts × {len(run.corrections)} corrections × "
         f"{run.seeds} seed(s), CRA {run.cra_corner_deg:g}° at the corner, renderer {renderer}")
    result = run_field(run, log=step, progress=not quiet)
    command = "spectracam field -o " + str(out_dir) + (" --quick" if quick else "") \
        + (f" --seeds {seeds}" if seeds else "") + "".join(f" --design {d}" for d in designs) \
        + "".join(f" --shift {s:g}" for s in shifts) + "".join(f" --correction {c}" for c in corrections) \
        + (f" --cra {cra_deg:g}" if cra_deg != 25.0 else "") + "".join(f" --pitch {p:g}" for p in pitches) \
        + (f" --renderer {renderer}" if renderer != "analytic" else "") + "".join(f" --set {s}" for s in sets)
    paths = write_field_outputs(out_dir, result, command)
    for line in summary_lines(result):
        log(line)
    log("wrote " + ", ".join(str(p) for p in paths if p.suffix != ".svg"))
