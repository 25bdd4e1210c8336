"""``spectracam dynamic-range``: which architecture and read-out keep colour across a high-dynamic-range scene (a
self-contained click command, registered lazily by :mod:`spectracam.cli`)."""
from __future__ import annotations

import click

from spectracam.experiments.options import (RegistryChoice, check_writable, output_option, progress_log,
                                            quiet_option, set_option, timed_step, view_option)

__all__ = ["dynamic_range_cmd"]


def _renderer_option(f):
    from spectracam.render import RENDERERS

    return click.option("--renderer", type=RegistryChoice(RENDERERS, "--renderer"), default="analytic",
                        show_default=True, help="The closed form or Mitsuba (Monte Carlo); the scenes are rendered "
                        "once, so Mitsuba costs little more.")(f)


@click.command("dynamic-range", short_help="Which architecture and read-out keep colour in an HDR scene.")
@output_option("Directory to write results.json, report.md and dynamic_range.png/.svg into.")
@click.option("--quick", is_flag=True, help="A first look: small images, 1 seed, 25 and 105 °C.")
@click.option("--seeds", type=click.IntRange(1, 100), default=None, help="Noise seeds per case [default: 3; 1 with "
              "--quick].")
@click.option("--design", "designs", multiple=True, metavar="ARCH/EXPOSURE",
              help="A design to compare (repeatable) [default: cfa/single, prism/optimal, fsc/optimal].")
@click.option("--readout", "readouts", multiple=True, metavar="NAME",
              help="A read-out to compare (repeatable) [default: every one].")
@click.option("--temperature", "temperatures", multiple=True, type=float, metavar="°C",
              help="A die temperature (repeatable) [default: 25, 65, 105; 25, 105 with --quick].")
@_renderer_option
@set_option
@quiet_option
@view_option
def dynamic_range_cmd(out_dir, quick, seeds, designs, readouts, temperatures, renderer, sets, quiet):
    """Every design × read-out × die temperature on the shipped high-dynamic-range scenes (hdr_ladder: charts from
    0.01 to 100 000 cd/m²; hdr_charts: sun and shade): ΔE*ab, CIEDE2000, S-CIELAB and SNR of every chart, with one
    exposure for the scene and with each chart's own, at a hand-held limit of 1/30 s; the luminance range each keeps
    with ΔE*ab below 3.  --set PATH=VALUE changes every scene (e.g. sensor.readout_samples=16)."""
    from spectracam.experiments.dynamic_range.experiment import (DESIGNS, plan, run_dynamic_range, summary_lines,
                                                                 write_dynamic_range_outputs)
    from spectracam.pipeline import check_memory

    run = plan(quick=quick, seeds=seeds, renderer=renderer, sets=sets, designs=tuple(designs) or DESIGNS,
               readouts=tuple(readouts) or None, temperatures_C=tuple(temperatures) or None)
    check_memory(run.scenes["ladder"], copies=4, what=", a render and its captures")
    check_writable(out_dir)
    log = progress_log(quiet)
    step = timed_step(log)
    step(f"{len(run.designs)} designs × {len(run.readouts)} read-outs × {len(run.temperatures_C)} temperatures × "
         f"{run.seeds} seed(s), renderer {renderer}")
    result = run_dynamic_range(run, log=step, progress=not quiet)
    command = "spectracam dynamic-range -o " + str(out_dir) + (" --quick" if quick else "") \
        + (f" --seeds {seeds}" if seeds else "") + "".join(f" --design {d}" for d in designs) \
        + "".join(f" --readout {r}" for r in readouts) + "".join(f" --temperature {t:g}" for t in temperatures) \
        + (f" --renderer {renderer}" if renderer != "analytic" else "") + "".join(f" --set {s}" for s in sets)
    paths = write_dynamic_range_outputs(out_dir, result, command)
    for line in summary_lines(result):
        log(line)
    log("wrote " + ", ".join(str(p) for p in paths if p.suffix != ".svg"))
