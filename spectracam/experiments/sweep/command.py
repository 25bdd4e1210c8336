"""``spectracam sweep`` and ``spectracam plot-sweep``: a design-space sweep run, and its figures (self-contained
click commands, registered lazily by :mod:`spectracam.cli`)."""
from __future__ import annotations

from pathlib import Path

import click

from spectracam.core.errors import SpectracamError
from spectracam.experiments.options import (ShippedFile, check_writable, output_option, progress_log, quiet_option,
                                            set_option, view_option)

__all__ = ["plot_sweep_cmd", "sweep_cmd"]


@click.command("sweep", short_help="Run a design-space sweep, a row per cell and trial.")
@click.argument("sweep_file", type=ShippedFile("sweep file"))
@output_option("Directory for results.jsonl/.parquet/.csv and sweep.json.")
@click.option("--scheduler", default=None, help="Address of a running Dask scheduler, tcp://HOST:PORT "
              "[default: a local cluster of processes made for the run].")
@click.option("--workers", type=click.IntRange(1, 1024), default=None, help="Local cluster size [default: cores].")
@click.option("--serial", is_flag=True, help="Run the cells in this process, without Dask.")
@click.option("--resume", is_flag=True, help="Continue an interrupted sweep in DIR, skipping finished cells.")
@click.option("--max-cells", type=click.IntRange(1), default=100_000, show_default=True,
              help="Refuse a sweep with more cells than this (each is validated before anything runs, ~1 ms a cell).")
@set_option
@quiet_option
@view_option
def sweep_cmd(sweep_file, out_dir, scheduler, workers, serial, resume, max_cells, sets, quiet):
    """Run every cell of SWEEP_FILE on Dask; results.parquet/.csv/.jsonl in DIR, a row per cell and trial.

    SWEEP_FILE is a path, or the name of a sweep shipped with spectracam (cfa_cutoffs,
    cfa_cutoffs_held_out), with or without .toml."""
    from spectracam.experiments.sweep.experiment import load_sweep, run_sweep

    if serial and scheduler:
        raise SpectracamError("--serial and --scheduler: choose one")
    sweep = load_sweep(sweep_file, sets, max_cells=max_cells, log=progress_log(quiet), progress=not quiet)
    from spectracam.pipeline import check_memory

    check_memory(sweep.largest_scene, copies=sweep.distinct_renders,
                 what=f", {sweep.distinct_renders} distinct render(s) held at once")
    check_writable(Path(out_dir))
    t = run_sweep(sweep, out_dir, scheduler=scheduler, workers=workers, serial=serial, resume=resume,
                  progress=not quiet, log=progress_log(quiet))
    progress_log(quiet)(f"{t['new_cells']} of {t['cells']} cells computed in {t['wall_s']:.1f} s "
                f"(cell compute {t['compute_s']:.1f} s); tables in {out_dir}")


@click.command("plot-sweep", short_help="Plot a finished sweep: one figure per metric.")
@click.argument("out_dir", type=click.Path(exists=True, file_okay=False, path_type=Path))
@click.option("--x", "x_axis", default=None, help="Axis on the x axis [default: the last varying axis].")
@click.option("--line", "line_axis", default=None, help="Axis drawn as one line per value.")
@click.option("--panel", "panel_axis", default=None, help="Axis drawn as one panel per value.")
@click.option("--metric", "metrics", multiple=True, help="Metric(s) to plot [default: all recorded].")
@view_option
def plot_sweep_cmd(out_dir, x_axis, line_axis, panel_axis, metrics):
    """Plot a finished sweep: DIR/plots/<metric>.png and .svg."""
    from spectracam.experiments.sweep.plot import plot_sweep

    paths = plot_sweep(out_dir, x_axis, line_axis, panel_axis, list(metrics) or None)
    click.echo("wrote " + ", ".join(str(p) for p in paths if p.suffix == ".png"))
