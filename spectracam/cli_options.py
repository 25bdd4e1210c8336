"""Command-line options shared by spectracam's commands (and by commands that live with their stage,
such as ``spectracam spatial``): registry-backed choices, --set, -o, --quiet, and the checks every
command makes before it works."""
from __future__ import annotations

from pathlib import Path

import click

from .architecture import ARCHITECTURES
from .color import ADAPTATIONS, DEMOSAIC_METHODS, DISPLAYS
from .errors import SpectracamError
from .exposure import EXPOSURE_SCHEMES
from .metrics import DELTA_E_METHODS
from .render import RENDERERS


class RegistryChoice(click.ParamType):
    """A name from a registry, read when the command runs, so registered plug-ins are accepted; an
    unknown name is the registry's one-line error."""

    name = "name"

    def __init__(self, registry, option: str):
        self.registry, self.option = registry, option

    def get_metavar(self, param, ctx=None):
        return "[" + "|".join(self.registry.names) + "]"

    def convert(self, value, param, ctx):
        return self.registry.check(value, self.option)


def progress_log(quiet: bool):
    return (lambda msg: None) if quiet else (lambda msg: click.echo(msg, err=True))


# ------------------------------------------------------------------------------------------------
# shared options: every flag is an override of a scene-file field, applied in the order
# scene file < --config < flags < --set

_SET_HELP = ("Override a field of the scene (or experiment/sweep) file: PATH=VALUE, e.g. sensor.adc_bits=12, "
             "filters.cutoffs_nm[1]=600, capture.design=fsc/optimal; VALUE is TOML, a bare word a string. Repeatable.")


class _OutputDir(click.Path):
    """A directory to write into; an empty name (which would write into the current directory) is refused."""

    def convert(self, value, param, ctx):
        if isinstance(value, str) and not value.strip():
            self.fail("must name a directory (an empty name would write into the current directory)", param, ctx)
        return super().convert(value, param, ctx)


def output_option(help_text: str):
    return click.option("-o", "--output", "out_dir", required=True, type=_OutputDir(file_okay=False, path_type=Path),
                        help=help_text)


set_option = click.option("--set", "sets", multiple=True, metavar="PATH=VALUE", help=_SET_HELP)
quiet_option = click.option("--quiet", is_flag=True, help="No progress or notices on stderr.")
renderer_option = click.option("--renderer", type=RegistryChoice(RENDERERS, "--renderer"), default="mitsuba",
                                show_default=True, help="Mitsuba (Monte Carlo) or the closed form.")


def camera_options(f):
    f = click.option("--seed", type=click.IntRange(0, 2**31 - 1), default=None,
                     help="Noise seed [default: the scene's render.seed].")(f)
    f = click.option("--config", "config_file", type=click.Path(dir_okay=False, path_type=Path), default=None,
                     help="TOML with [optics], [filters], [sensor], [capture] tables, over the scene's.")(f)
    f = click.option("--exposure", type=RegistryChoice(EXPOSURE_SCHEMES, "--exposure"), default=None,
                     help="Exposure control [default: the scene's capture.exposure].")(f)
    f = click.option("--arch", type=RegistryChoice(ARCHITECTURES, "--arch"), default=None,
                     help="Colour architecture [default: the scene's capture.architecture].")(f)
    return f


def processing_options(f):
    f = click.option("--gamut-clip/--no-gamut-clip", default=None, help="Clip display RGB to [0, 1].")(f)
    f = click.option("--delta-e", "delta_e", type=RegistryChoice(DELTA_E_METHODS, "--delta-e"), default=None,
                     help="Colour difference formula [default: the scene's, else cie1976].")(f)
    f = click.option("--adaptation", type=RegistryChoice(ADAPTATIONS, "--adaptation"), default=None,
                     help="How scene XYZ is carried to the display white [default: xyz_scaling].")(f)
    f = click.option("--display", type=RegistryChoice(DISPLAYS, "--display"), default=None,
                     help="Display model [default: the scene's, else crt].")(f)
    f = click.option("--demosaic", type=RegistryChoice(DEMOSAIC_METHODS, "--demosaic"), default=None,
                     help="Demosaicking of a mosaic [default: the scene's, else bilinear].")(f)
    return f


def flag_overrides(**flags) -> list[tuple[str, object]]:
    """``(path, value)`` overrides of the flags given on the command line."""
    paths = {"arch": "capture.architecture", "exposure": "capture.exposure", "demosaic": "processing.demosaic",
             "display": "processing.display", "adaptation": "processing.adaptation", "delta_e": "processing.delta_e",
             "gamut_clip": "processing.gamut_clip"}
    return [(paths[k], v) for k, v in flags.items() if v is not None]


def check_writable(out_dir: Path) -> None:
    """Refuse before any work when the output directory could not be made or written (nothing is
    created here: a run that fails later leaves no empty directory behind)."""
    import os

    p = out_dir.absolute()
    while not p.exists():
        p = p.parent
    if not p.is_dir():
        raise SpectracamError(f"output = {str(out_dir)!r}: {str(p)!r} is a file, not a directory")
    if not os.access(p, os.W_OK | os.X_OK):
        raise SpectracamError(f"output = {str(out_dir)!r}: {str(p)!r} is not writable")
