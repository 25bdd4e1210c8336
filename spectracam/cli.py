"""The ``spectracam`` command line."""
from __future__ import annotations

import sys
import time
from pathlib import Path

import click

from . import __version__
from .errors import SpectracamError
from .render import RENDERERS


class _Group(click.Group):
    """Turns a :class:`SpectracamError` into one line on stderr and exit status 2."""

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except SpectracamError as e:
            click.echo(f"spectracam: error: {e}", err=True)
            sys.exit(2)


@click.group(cls=_Group)
@click.version_option(__version__, prog_name="spectracam")
def main():
    """Simulate colour image sensors on a rendered Macbeth chart (Catrysse, Wandell & El Gamal, 1999)."""


def _log(quiet: bool):
    return (lambda msg: None) if quiet else (lambda msg: click.echo(msg, err=True))


@main.command("render")
@click.argument("scene_file", type=click.Path(dir_okay=False, path_type=Path))
@click.option("-o", "--output", "out_dir", required=True, type=click.Path(file_okay=False, path_type=Path),
              help="Directory to write radiance.exr into.")
@click.option("--renderer", type=click.Choice(RENDERERS), default="mitsuba", show_default=True)
@click.option("--quiet", is_flag=True, help="No progress or notices.")
def render_cmd(scene_file: Path, out_dir: Path, renderer: str, quiet: bool):
    """Render SCENE_FILE into DIR/radiance.exr (spectral EXR, W·m⁻²·sr⁻¹·nm⁻¹ per band)."""
    from .io.exr import write_radiance_exr
    from .render import render
    from .scene import load_scene

    scene = load_scene(scene_file)  # validates before anything is written
    log = _log(quiet)
    t0 = time.perf_counter()
    cube = render(scene, renderer=renderer, progress=not quiet, log=log)
    path = write_radiance_exr(out_dir / "radiance.exr", cube, scene)
    h, w, b = cube.shape
    log(f"wrote {path} ({w}x{h} px, {b} bands, {renderer}, {time.perf_counter() - t0:.2f} s)")


@main.command("inspect")
@click.argument("file", type=click.Path(exists=True, dir_okay=False, path_type=Path))
def inspect_cmd(file: Path):
    """Print channels, size, recorded parameters and per-channel min/mean/max of an EXR file."""
    from .io.exr import describe

    click.echo(describe(file))


if __name__ == "__main__":
    main()
