"""``spectracam validate`` and ``spectracam cameras``: the shipped measured cameras checked against their
published matrices, and listed (self-contained click commands, registered lazily by :mod:`spectracam.cli`)."""
from __future__ import annotations

from pathlib import Path

import click

from spectracam.core.errors import ConfigError
from spectracam.experiments.options import (check_writable, output_option, progress_log, quiet_option,
                                            renderer_option, view_option)

__all__ = ["cameras_cmd", "validate_cmd"]


@click.command("cameras", short_help="List the measured cameras filters.camera can name.")
@click.option("--json", "as_json", is_flag=True, help="Print the library as JSON instead of a table.")
def cameras_cmd(as_json: bool):
    """List the measured cameras filters.camera can name: range, source, normalisation and how their channels'
    gains were obtained (filters.camera_file takes any other camera's curves)."""
    import json

    from spectracam.architecture.cameras import library_table

    rows = library_table()
    if as_json:
        click.echo(json.dumps(rows, indent=1))
        return
    for r in rows:
        click.echo(f"{r['name']}{'' if r['usable'] else '   [refused: gains unknown]'}")
        click.echo(f"    range {r['range_nm'][0]:g}–{r['range_nm'][1]:g} nm, {r['unit']} (per unit energy); "
                   f"{r['normalisation']}")
        click.echo(f"    gains: {r['gains']}")
        if r["published_matrix"]:
            click.echo(f"    published XYZ(D65)→camera matrix: {r['published_matrix']} ({r['matrix_source']})")
        click.echo(f"    source: {r['source']}")
    click.echo("Own curves: filters.camera_file = \"curves.csv\" (wavelength nm, R, G, B) with filters.camera_unit = "
               "relative | A/W | electrons_per_photon.")


@click.command("validate", short_help="Check the shipped cameras against published matrices.")
@output_option("Directory to write validate.json, validate.md and validate.png/.svg into.")
@renderer_option
@click.option("--camera-file", type=click.Path(exists=True, dir_okay=False, path_type=Path), default=None,
              help="Check your own camera instead: its curves as filters.camera_file takes them (wavelength nm, R, G, B).")
@click.option("--matrix", default=None, metavar="9 NUMBERS|FILE",
              help="With --camera-file: its published XYZ(D65)→camera matrix, row-major (e.g. Adobe's ColorMatrix2 "
                   "×10⁴), or a text file holding it; it also restores the gains of per-channel-normalised curves.")
@click.option("--camera-unit", type=click.Choice(["relative", "A/W", "electrons_per_photon"]), default="relative",
              show_default=True, help="With --camera-file: the curves' unit (filters.camera_unit).")
@click.option("--camera-gains", default=None, metavar="R,G,B",
              help="With --camera-file: the channels' gains (filters.camera_gains) instead of restoring them.")
@click.option("--gains-kept", is_flag=True, help="With --camera-file: its equal channel peaks are real "
                                                 "(filters.camera_gains_kept).")
@quiet_option
@view_option
def validate_cmd(out_dir, renderer, camera_file, matrix, camera_unit, camera_gains, gains_kept, quiet):
    """Check every shipped camera with a published XYZ(D65)→camera matrix: the simulated white's R/G and B/G against
    the matrix's neutral, and ΔE*ab of the published matrix on the simulated raw (beside a least-squares fit's).
    With --camera-file and --matrix, check your own camera the same way."""
    from spectracam.experiments.validate.experiment import parse_matrix, run_validate, write_validate_outputs

    user, command = None, f"spectracam validate -o {out_dir} --renderer {renderer}"
    if (camera_file is None) != (matrix is None) or (camera_file is None and (camera_gains or gains_kept)):
        raise ConfigError("--camera-file" if camera_file is None else "--matrix", str(camera_file or matrix or camera_gains),
                          "--camera-file and --matrix go together (your camera's curves and its published "
                          "XYZ(D65)→camera matrix); --camera-unit, --camera-gains and --gains-kept need them")
    if camera_file is not None:
        gains = None
        if camera_gains:
            try:
                gains = tuple(float(x) for x in camera_gains.replace(",", " ").split())
            except ValueError:
                gains = (camera_gains,)
        user = {"camera_file": camera_file, "matrix": parse_matrix(matrix), "unit": camera_unit, "gains": gains,
                "gains_kept": gains_kept}
        command += f" --camera-file {camera_file} --matrix '{matrix}' --camera-unit {camera_unit}" + \
            (f" --camera-gains {camera_gains}" if camera_gains else "") + (" --gains-kept" if gains_kept else "")
    check_writable(out_dir)
    result = run_validate(renderer, user)
    paths = write_validate_outputs(out_dir, result, command)
    log = progress_log(quiet)
    for r in result["cameras"]:
        log(f"  {r['camera']}: white R/G {r['white_RG_simulated']:.3f} (published {r['white_RG_published']:.3f}, "
            f"{r['white_RG_error_percent']:+.1f} %), B/G {r['white_BG_simulated']:.3f} (published "
            f"{r['white_BG_published']:.3f}, {r['white_BG_error_percent']:+.1f} %); ΔE*ab with the published matrix "
            f"{r['delta_e_published_mean']:.2f} mean / {r['delta_e_published_max']:.2f} max (LS fit, training: "
            f"{r['delta_e_fit_mean']:.2f} / {r['delta_e_fit_max']:.2f})")
    wb = result.get("real_camera_data", {}).get("wb_presets", {})
    if wb.get("status") != "ok" and user is None:
        log(f"  white-balance presets: skipped ({wb.get('reason', 'not run')})")
    for cam in wb.get("cameras", []):
        if not cam.get("presets"):
            log(f"  {cam['camera']}: no firmware preset in darktable's file to compare with")
            continue
        log(f"  {cam['camera']} against its firmware presets (simulated / preset R/G, B/G): " + "; ".join(
            f"{p['preset']} {p['RG_simulated']:.3f}/{p['RG_preset']:.3f}, {p['BG_simulated']:.3f}/{p['BG_preset']:.3f}"
            for p in cam.get("presets", [])))
    log("wrote " + ", ".join(str(p) for p in paths if p.suffix != ".svg"))
