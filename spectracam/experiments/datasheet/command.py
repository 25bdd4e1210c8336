"""``spectracam datasheet``: the simulated sensor's datasheet (a self-contained click command, registered lazily by
:mod:`spectracam.cli`)."""
from __future__ import annotations

import click

from spectracam.experiments.options import (ShippedFile, check_writable, given, output_option, progress_log,
                                            quiet_option, scene_from, set_option, view_option)

__all__ = ["datasheet_cmd"]


@click.command("datasheet", short_help="A sensor datasheet of the simulated camera.")
@output_option("Directory to write datasheet.md, results.json and snr.png/snr.svg into.")
@click.option("--quick", is_flag=True, help="A few seconds: smaller frames, fewer photon-transfer steps.")
@click.option("--scene", "scene_file", type=ShippedFile("scene file"), default=None,
              help="Scene file whose camera is measured, a path or a shipped scene's name [default: the paper's].")
@click.option("--seed", type=click.IntRange(0, 2**31 - 1), default=0, show_default=True, help="Noise seed.")
@set_option
@quiet_option
@view_option
def datasheet_cmd(out_dir, quick, scene_file, seed, sets, quiet):
    """EMVA 1288 dynamic range and SNR for every read-out, SNR 1/10 in lux, ISO 12232 speeds, ISO 15739 visual
    noise, ISO 17321-1 SMI and the chart's ΔE*ab and CIEDE2000 of the configured camera.  With --set
    sensor.readout=NAME only that read-out is measured; otherwise all five."""
    from spectracam.experiments.datasheet.experiment import DatasheetSpec, run_datasheet
    from spectracam.experiments.datasheet.report import write_datasheet_outputs
    from spectracam.pipeline.scene_file import read_toml

    data, source = (read_toml(scene_file, "scene file"), str(scene_file)) if scene_file else ({}, "command line")
    scene = scene_from(data, source, None, (), sets)
    check_writable(out_dir)
    named = any(s.split("=", 1)[0].strip() == "sensor.readout" for s in sets)
    spec = DatasheetSpec(quick=quick, seed=seed, readouts=(scene.camera.sensor.readout,) if named else None)
    result = run_datasheet(scene, spec)
    command = "spectracam datasheet -o " + str(out_dir) + (" --quick" if quick else "") \
        + given("--scene", "scene_file", scene_file) + f" --seed {seed}" + "".join(f" --set {s}" for s in sets)
    paths = write_datasheet_outputs(out_dir, result, command)
    log = progress_log(quiet)
    for name, r in result["readouts"].items():
        dr = "–" if r["dynamic_range_db"] is None else f"{r['dynamic_range_db']:.1f} dB"
        log(f"  {name:<17} DR {dr:>9}   saturation {r['saturation_e']:.4g} e-")
    for note in result["notes"]:
        log("  note: " + note)
    log("wrote " + ", ".join(str(p) for p in paths if p.suffix != ".svg"))
