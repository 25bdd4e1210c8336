"""``spectracam emva``: the simulated camera measured by EMVA 1288 (a self-contained click command, registered
lazily by :mod:`spectracam.cli`)."""
from __future__ import annotations

from pathlib import Path

import click

from spectracam.experiments.options import (ShippedFile, check_writable, given, output_option, progress_log,
                                            quiet_option, scene_from, set_option, view_option)

__all__ = ["emva_cmd"]


@click.command("emva", short_help="Measure the simulated camera by EMVA 1288.")
@output_option("Directory to write emva.json, datasheet.md and the photon-transfer, SNR and linearity plots into.")
@click.option("--scene", "scene_file", type=ShippedFile("scene file"), default=None,
              help="Scene file whose camera is measured, a path or a shipped scene's name [default: the paper's "
                   "camera].")
@click.option("--config", "config_file", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="TOML with [optics], [filters], [sensor], [capture] tables, over the scene's camera.")
@click.option("--channel", type=click.Choice(["R", "G", "B"]), default="G", show_default=True,
              help="Colour channel measured (its filter in front of the sensor).")
@click.option("--wavelength", "wavelength_nm", type=click.FloatRange(300, 1100), default=540.0, show_default=True,
              help="Wavelength of the monochromatic light, nm.")
@click.option("--seed", type=click.IntRange(0, 2**31 - 1), default=0, show_default=True, help="Noise seed.")
@set_option
@quiet_option
@view_option
def emva_cmd(out_dir, scene_file, config_file, channel, wavelength_nm, seed, sets, quiet):
    """Characterise the simulated camera by EMVA 1288 (Release 4.0, linear): datasheet and plots."""
    from spectracam.experiments.emva.experiment import EmvaSetup, run_emva, write_emva_outputs
    from spectracam.pipeline.scene_file import read_toml

    data, source = (read_toml(scene_file, "scene file"), str(scene_file)) if scene_file else ({}, "command line")
    scene = scene_from(data, source, config_file, (), sets)
    check_writable(out_dir)
    result = run_emva(scene.camera, EmvaSetup(channel=channel, wavelength_nm=wavelength_nm, seed=seed))
    command = "spectracam emva -o " + str(out_dir) + given("--scene", "scene_file", scene_file) \
        + (f" --config {config_file}" if config_file else "") + f" --channel {channel} --wavelength {wavelength_nm:g}" \
        + f" --seed {seed}" + "".join(f" --set {s}" for s in sets)
    paths = write_emva_outputs(out_dir, result, command)
    log = progress_log(quiet)
    num = lambda x: "–" if x is None else f"{x:.5g}"  # noqa: E731
    for k, v in result["measured"].items():
        log(f"  {k:<26} configured {num(result['configured'][k]):>10}   measured {num(v):>10}")
    log("wrote " + ", ".join(str(p) for p in paths if p.suffix != ".svg"))
