"""``spectracam view DIR``: the interactive page of an output directory (a self-contained click command,
registered lazily by :mod:`spectracam.cli`)."""
from __future__ import annotations

from pathlib import Path

import click

from spectracam.experiments.options import progress_log, quiet_option

__all__ = ["view_cmd"]


@click.command("view", short_help="Write DIR/index.html, an interactive page of DIR.")
@click.argument("out_dir", metavar="DIR", type=click.Path(exists=True, file_okay=False, path_type=Path))
@quiet_option
def view_cmd(out_dir: Path, quiet: bool):
    """Write DIR/index.html: one self-contained interactive page of what a spectracam command wrote into DIR
    (any command's output directory); print the page's path.  Every command that writes a directory does
    the same with --view."""
    from spectracam.view import write_view

    page = write_view(out_dir, log=progress_log(quiet))
    click.echo(str(page))
