"""Command-line options shared by spectracam's commands (each command lives in a ``command.py`` beside
the code it runs, registered by :mod:`spectracam.cli`): registry-backed choices, --set, -o, --quiet, the
scene a command's flags make, the command a report records, and the checks every command makes before
it works."""
from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from spectracam.architecture.base import ARCHITECTURES
from spectracam.processing.color import ADAPTATIONS, DEMOSAIC_METHODS, DISPLAYS
from spectracam.core.errors import ConfigError, SpectracamError
from spectracam.sensor.exposure import EXPOSURE_SCHEMES
from spectracam.core.cielab import DELTA_E_METHODS
from spectracam.render import RENDERERS

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Sequence

    from spectracam.core.registry import Registry
    from spectracam.pipeline.scene_file import Scene

__all__ = ["EXPERIMENT_HELP", "RegistryChoice", "ShippedFile", "VIEW_HELP", "VIEW_REQUEST", "as_given", "camera_options",
           "check_target_renderer", "check_writable", "default_experiment", "experiment_option", "flag_overrides",
           "given", "log_report", "no_cache_option", "output_option", "processing_options", "progress_log",
           "quiet_option", "renderer_option", "resolve_shipped", "scene_from", "set_option", "shipped_files",
           "shipped_named", "shipped_summary", "target_command", "timed_step"]


class RegistryChoice(click.ParamType):
    """A name from a registry, read when the command runs, so registered plug-ins are accepted; an
    unknown name is the registry's one-line error.

    Parameters
    ----------
    registry : Registry
        The registry whose names are accepted (e.g. ``ARCHITECTURES``, ``RENDERERS``).
    option : str
        The option's flag (``"--arch"``), named in the error for an unknown name.
    """

    name = "name"

    def __init__(self, registry: Registry[Any], option: str):
        self.registry, self.option = registry, option

    def get_metavar(self, param: click.Parameter, ctx: click.Context | None = None) -> str:
        """The registry's names as ``--help`` shows them, ``[a|b|c]``.

        Parameters
        ----------
        param : click.Parameter
            The option (unused).
        ctx : click.Context or None
            The command's context (unused).

        Returns
        -------
        str
            The names, ``|``-separated in brackets.
        """
        return "[" + "|".join(self.registry.names) + "]"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> str:
        """The name given, checked against the registry.

        Parameters
        ----------
        value : object
            What was typed.
        param : click.Parameter or None
            The option (unused).
        ctx : click.Context or None
            The command's context (unused).

        Returns
        -------
        str
            The registered name.

        Raises
        ------
        ConfigError
            When the registry has no such name.
        """
        return self.registry.check(value, self.option)


def progress_log(quiet: bool) -> Callable[[str], None]:
    """One-line notices on stderr (none with ``--quiet``); a line printed while a progress bar is drawn
    goes above the bar instead of through it.

    Parameters
    ----------
    quiet : bool
        ``--quiet``: notices are dropped.

    Returns
    -------
    callable
        ``log(msg)``: :func:`spectracam.core.progress.note`, or one that prints nothing.
    """
    if quiet:
        return lambda msg: None
    from spectracam.core.progress import note

    return note


# ------------------------------------------------------------------------------------------------
# shipped files by name: `spectracam simulate d65`, `sweep cfa_cutoffs`, `design design` from any install

#: The shipped files each kind of argument may name (besides a path): sweeps live in sweeps/; the
#: experiment and the design file are one each; every other shipped file is a scene.
_SHIPPED_ONLY = {"experiment file": ("paper",), "design file": ("design",)}


def shipped_files(what: str) -> dict[str, Path]:
    """``name → path`` of the shipped files an argument of kind ``what`` may name (``"scene file"``,
    ``"sweep file"``, ``"experiment file"``, ``"design file"``); a sweep's name is ``sweeps/NAME``.

    Parameters
    ----------
    what : str
        The kind of file argument.

    Returns
    -------
    dict of str to Path
        Sorted by path; empty when this installation ships no files.
    """
    from spectracam.pipeline.scene_file import shipped_dir

    root = shipped_dir()
    if root is None:
        return {}
    out = {}
    for p in sorted(root.rglob("*.toml")):
        name = p.relative_to(root).with_suffix("").as_posix()
        if (what == "sweep file") != name.startswith("sweeps/"):
            continue
        if what in _SHIPPED_ONLY and name not in _SHIPPED_ONLY[what]:
            continue
        if what == "scene file" and name in {n for v in _SHIPPED_ONLY.values() for n in v}:
            continue
        out[name] = p
    return out


def shipped_named(value: str | Path, what: str = "scene file") -> Path | None:
    """The shipped file of kind ``what`` that ``value`` names — with or without ``.toml``, with or without
    the checkout's ``scenes/`` — or None.  (``--experiment paper`` and a design file's ``experiment =
    "paper"`` both name files through this.)

    Parameters
    ----------
    value : str or Path
        The name as given.
    what : str
        The kind of file argument (see :func:`shipped_files`).

    Returns
    -------
    Path or None
        The shipped file; None when ``value`` names none.
    """
    shipped = shipped_files(what)
    name = str(value).strip().removeprefix("./").removeprefix("scenes/").removesuffix(".toml")
    if name in shipped:
        return shipped[name]
    return {k.rsplit("/", 1)[-1]: v for k, v in shipped.items()}.get(name)


def resolve_shipped(value: str | Path, what: str = "scene file") -> Path:
    """A path that exists, else the shipped file ``value`` names — with or without ``.toml``, with or
    without the checkout's ``scenes/`` (``d65``, ``scenes/d65.toml``, ``cfa_cutoffs``,
    ``scenes/sweeps/cfa_cutoffs.toml``); else one line listing what ships.

    A bare name (no ``/``, no ``.toml``) of a shipped file when ``NAME.toml`` is also in the working
    directory (``d65`` with a ``d65.toml`` here) is refused as ambiguous, naming both: neither may silently
    win, because the command a report records keeps the name as typed (``spectracam simulate d65``) and
    must mean one file wherever it is run again.  ``./d65.toml`` (a
    path) says the local file, ``scenes/d65`` the shipped one.

    Parameters
    ----------
    value : str or Path
        A path or a shipped file's name.
    what : str
        The kind of file argument (see :func:`shipped_files`); names it in the errors.

    Returns
    -------
    Path
        The existing path, or the shipped file.

    Raises
    ------
    ConfigError
        When ``value`` is ambiguous, or neither a path nor a shipped file's name.
    """
    p = Path(value)
    if p.exists():
        return p
    text = str(value).strip()
    found = shipped_named(value, what)
    local = Path(text + ".toml")
    if found is not None and "/" not in text and not text.endswith(".toml") and local.is_file() \
            and local.resolve() != found.resolve():
        kind = what.split()[0]
        raise ConfigError(what, text, f"ambiguous: names both {local} here and the shipped {kind} {text} ({found}); "
                          f"write ./{local} for yours or scenes/{text} for the shipped one")
    if found is not None:
        return found
    kind = what.split()[0]
    names = ", ".join(k.rsplit("/", 1)[-1] for k in shipped_files(what)) or "none in this installation"
    raise ConfigError(what, str(value), f"no such file, and not the name of a shipped {kind} (shipped: {names})")


class ShippedFile(click.ParamType):
    """A TOML file argument: a path, or the name of a file shipped with spectracam (:func:`resolve_shipped`).

    Parameters
    ----------
    what : str
        The kind of file argument (``"scene file"``, ``"experiment file"``, …; see :func:`shipped_files`).
    """

    name = "file"

    def __init__(self, what: str):
        self.what = what

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Path:
        """The file ``value`` names, by :func:`resolve_shipped`; the text as given is kept for :func:`as_given`.

        Parameters
        ----------
        value : object
            What was typed.
        param : click.Parameter or None
            The argument; with ``ctx``, the text is recorded under its name.
        ctx : click.Context or None
            The command's context, whose ``meta`` keeps the text.

        Returns
        -------
        Path
            The existing path or the shipped file.
        """
        path = resolve_shipped(value, self.what)
        if ctx is not None and param is not None:
            ctx.meta.setdefault(_GIVEN, {})[param.name] = str(value)
        return path


_GIVEN = "spectracam.given"


def as_given(name: str, value: object) -> str:
    """How the user wrote the :class:`ShippedFile` parameter ``name`` (a shipped file's name stays a name
    in the command a report records), else ``str(value)``.

    Parameters
    ----------
    name : str
        The parameter's name (``"scene_file"``).
    value : object
        Its converted value, used when nothing was recorded.

    Returns
    -------
    str
        The text as typed, else ``str(value)``.
    """
    ctx = click.get_current_context(silent=True)
    given = ctx.meta.get(_GIVEN, {}).get(name) if ctx is not None else None
    return given if given is not None else str(value)


def shipped_summary() -> str:
    """One paragraph for ``spectracam --help``: what a file argument may name."""
    kinds = [(what, list(shipped_files(what))) for what in ("scene file", "sweep file", "experiment file",
                                                             "design file")]
    listed = "; ".join(f"{what.split()[0]}s: " + ", ".join(n.rsplit("/", 1)[-1] for n in names)
                       for what, names in kinds if names)
    return ("A scene, sweep, experiment or design file argument is a path, or the name of a file shipped with "
            "spectracam, with or without .toml (spectracam simulate d65 -o out) — "
            + (listed or "none shipped") + ".")


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


def output_option(help_text: str) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """``-o/--output DIR`` (required): the directory a command writes into, as a Path; an empty name is refused.

    Parameters
    ----------
    help_text : str
        The option's ``--help`` line.

    Returns
    -------
    callable
        The click decorator; the command receives ``out_dir``.
    """
    return click.option("-o", "--output", "out_dir", required=True, type=_OutputDir(file_okay=False, path_type=Path),
                        help=help_text)


def view_option(f):
    """``--view``: after the command's outputs are written, also write DIR/index.html (``spectracam view``).
    The request is recorded here and carried out by the command group once the outputs are in place
    (``spectracam.cli``'s group, in its ``invoke``), so the page sees the files under their final names."""
    import functools

    @functools.wraps(f)
    def wrapper(*args, view: bool = False, **kwargs):
        if view:
            ctx = click.get_current_context()
            ctx.meta[VIEW_REQUEST] = (Path(kwargs["out_dir"]), bool(kwargs.get("quiet", False)))
        return f(*args, **kwargs)

    return click.option("--view", is_flag=True, help=VIEW_HELP)(wrapper)


#: Where a command's ``--view`` request waits for the group (``ctx.meta`` is shared by nested contexts).
VIEW_REQUEST = "spectracam.view"
VIEW_HELP = "Also write DIR/index.html, an interactive page (spectracam view)."


set_option = click.option("--set", "sets", multiple=True, metavar="PATH=VALUE", help=_SET_HELP)
quiet_option = click.option("--quiet", is_flag=True, help="No progress or notices on stderr.")
renderer_option = click.option("--renderer", type=RegistryChoice(RENDERERS, "--renderer"), default="mitsuba",
                                show_default=True, help="Mitsuba (Monte Carlo) or the closed form.")


def _stacked(*options):
    """One decorator of several options, listed in ``--help`` in the order given."""
    def apply(f: Callable[..., Any]) -> Callable[..., Any]:
        """Add the options to a command.

        Parameters
        ----------
        f : callable
            The command function.

        Returns
        -------
        callable
            ``f`` with each option applied, the first listed first in ``--help``.
        """
        for option in reversed(options):
            f = option(f)
        return f

    return apply


#: --arch, --exposure, --config and --seed: the camera of a scene file, overridden.
camera_options = _stacked(
    click.option("--arch", type=RegistryChoice(ARCHITECTURES, "--arch"), default=None,
                 help="Colour architecture [default: the scene's capture.architecture]."),
    click.option("--exposure", type=RegistryChoice(EXPOSURE_SCHEMES, "--exposure"), default=None,
                 help="Exposure control [default: the scene's capture.exposure]."),
    click.option("--config", "config_file", type=click.Path(dir_okay=False, path_type=Path), default=None,
                 help="TOML with [optics], [filters], [sensor], [capture] tables, over the scene's."),
    click.option("--seed", type=click.IntRange(0, 2**31 - 1), default=None,
                 help="Noise seed [default: the scene's render.seed]."))

#: --demosaic, --display, --adaptation, --delta-e and --gamut-clip: the scene file's [processing], overridden.
processing_options = _stacked(
    click.option("--demosaic", type=RegistryChoice(DEMOSAIC_METHODS, "--demosaic"), default=None,
                 help="Demosaicking of a mosaic [default: the scene's, else bilinear]."),
    click.option("--display", type=RegistryChoice(DISPLAYS, "--display"), default=None,
                 help="Display model [default: the scene's, else crt]."),
    click.option("--adaptation", type=RegistryChoice(ADAPTATIONS, "--adaptation"), default=None,
                 help="How scene XYZ is carried to the display white [default: xyz_scaling]."),
    click.option("--delta-e", "delta_e", type=RegistryChoice(DELTA_E_METHODS, "--delta-e"), default=None,
                 help="Colour difference formula [default: the scene's, else cie1976]."),
    click.option("--gamut-clip/--no-gamut-clip", default=None, help="Clip display RGB to [0, 1]."))

#: ``--experiment``'s help where the whole experiment file is used (paper, consistency).
EXPERIMENT_HELP = ("Experiment file: a path or a shipped one's name [default: paper, scenes/paper.toml shipped with "
                   "spectracam].")


def experiment_option(help_text: str = EXPERIMENT_HELP) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """``--experiment FILE``: a path or a shipped experiment's name (:func:`default_experiment` when not given).

    Parameters
    ----------
    help_text : str
        The option's ``--help`` line.

    Returns
    -------
    callable
        The click decorator; the command receives ``experiment_file`` (a Path, or None when not given).
    """
    return click.option("--experiment", "experiment_file", type=ShippedFile("experiment file"), default=None,
                        help=help_text)


no_cache_option = click.option("--no-cache", is_flag=True, help="Render again even if the render cache has the scene.")


def flag_overrides(**flags: object) -> list[tuple[str, object]]:
    """``(path, value)`` overrides of the flags given on the command line.

    Parameters
    ----------
    **flags : object
        ``arch``, ``exposure``, ``demosaic``, ``display``, ``adaptation``, ``delta_e``, ``gamut_clip``; None: not given.

    Returns
    -------
    list of (str, object)
        The scene-file path (``"capture.architecture"``) and value of each flag given, in the order passed.
    """
    paths = {"arch": "capture.architecture", "exposure": "capture.exposure", "demosaic": "processing.demosaic",
             "display": "processing.display", "adaptation": "processing.adaptation", "delta_e": "processing.delta_e",
             "gamut_clip": "processing.gamut_clip"}
    return [(paths[k], v) for k, v in flags.items() if v is not None]


def check_writable(out_dir: Path) -> None:
    """Refuse before any work when the output directory could not be made or written (nothing is
    created here: a run that fails later leaves no empty directory behind).

    Parameters
    ----------
    out_dir : Path
        The output directory; it or its nearest existing parent is checked.

    Raises
    ------
    SpectracamError
        When that parent is a file, or not writable.
    """
    import os

    p = out_dir.absolute()
    while not p.exists():
        p = p.parent
    if not p.is_dir():
        raise SpectracamError(f"output = {str(out_dir)!r}: {str(p)!r} is a file, not a directory")
    if not os.access(p, os.W_OK | os.X_OK):
        raise SpectracamError(f"output = {str(out_dir)!r}: {str(p)!r} is not writable")


# ------------------------------------------------------------------------------------------------
# what several commands do alike: the scene their flags make, the command a report records, the log


def scene_from(data: dict, source: str, config_file: str | Path | None = None,
               flags: Iterable[tuple[str, object]] = (), sets: Sequence[str] = ()) -> Scene:
    """A Scene from a scene dict with the config file's camera tables, the flags and ``--set``.

    Parameters
    ----------
    data : dict
        The scene file's tables as read.
    source : str
        The scene file's path or name: relative curve files are read beside it; errors name it.
    config_file : str or Path or None
        ``--config``: TOML whose camera tables update the scene's, table by table.
    flags : iterable of (str, object)
        The flags' overrides (:func:`flag_overrides`), applied after the config file.
    sets : sequence of str
        ``--set PATH=VALUE``, applied last.

    Returns
    -------
    Scene
        The parsed scene.

    Raises
    ------
    ConfigError
        When the config file has a table other than a camera table, or any override is invalid.
    """
    from spectracam.camera import CAMERA_TABLES
    from spectracam.pipeline.overrides import apply_overrides
    from spectracam.pipeline.scene_file import Scene, parse_scene, read_toml, resolve_curve_files

    here = Path(source).parent if Path(source).is_file() else Path.cwd()  # where file paths are relative to
    data = resolve_curve_files(data, here)
    if config_file is not None:
        config = read_toml(config_file, "config file")
        for k, v in config.items():
            if k not in CAMERA_TABLES or not isinstance(v, dict):
                raise ConfigError(k, v, "a config file has the camera tables " + ", ".join(CAMERA_TABLES),
                                  str(config_file))
            data = {**data, k: {**data.get(k, {}), **v}}
        data = resolve_curve_files(data, Path(config_file).parent)
        Scene.from_dict(data, source=str(config_file))  # the config file's own errors name it
    data = apply_overrides(data, flags, source="command line")
    defaults = lambda: parse_scene(data, source).to_dict()  # noqa: E731  lists a --set element refers to
    data = resolve_curve_files(apply_overrides(data, sets, defaults=defaults), Path.cwd())
    return parse_scene(data, source if not (flags or sets) else f"{source} with the command line's options")


def default_experiment() -> Path:
    """The paper's experiment file shipped with spectracam (scenes/paper.toml)."""
    from spectracam.pipeline.scene_file import shipped_scene_file

    try:
        return shipped_scene_file("paper.toml")
    except ConfigError:
        raise SpectracamError("experiment = scenes/paper.toml: not shipped with this installation; "
                              "pass --experiment FILE") from None


def given(flag: str, name: str, value: object) -> str:
    """`` FLAG VALUE`` for the command a report records, as the user wrote it (a shipped file's name stays a
    name); empty when the option was not given.

    Parameters
    ----------
    flag : str
        The flag as written (``"--experiment"``).
    name : str
        The parameter's name (:func:`as_given`).
    value : object
        Its value; falsy: not given.

    Returns
    -------
    str
        ``" FLAG VALUE"``, or ``""``.
    """
    return f" {flag} {as_given(name, value)}" if value else ""


def timed_step(log: Callable[[str], object]) -> Callable[[str], object]:
    """``log``, each line stamped with the seconds since this call (``[  12.3 s] …``).

    Parameters
    ----------
    log : callable
        ``log(msg)``, e.g. :func:`progress_log`'s.

    Returns
    -------
    callable
        ``log(msg)`` that prefixes the elapsed time, s.
    """
    t0 = time.perf_counter()
    return lambda msg: log(f"[{time.perf_counter() - t0:6.1f} s] {msg}")


def check_target_renderer(renderer: str, what: str) -> None:
    """The spatial and moving targets are rendered by Mitsuba or the closed form, no other renderer.

    Parameters
    ----------
    renderer : str
        ``--renderer``.
    what : str
        The targets, named in the error (``"spatial targets"``).

    Raises
    ------
    ConfigError
        When ``renderer`` is neither ``"mitsuba"`` nor ``"analytic"``.
    """
    if renderer not in ("mitsuba", "analytic"):
        raise ConfigError("--renderer", renderer, f"{what} are rendered by 'mitsuba' or 'analytic'")


def target_command(name: str, out_dir: Path, quick: bool, renderer: str, sets: Iterable[str]) -> str:
    """The command a spatial or motion report records: ``spectracam NAME -o DIR`` and the options given.

    Parameters
    ----------
    name : str
        The command (``"spatial"``, ``"motion"``).
    out_dir : Path
        ``-o``.
    quick : bool
        ``--quick``.
    renderer : str
        ``--renderer``; recorded unless ``"mitsuba"`` (the default).
    sets : iterable of str
        ``--set PATH=VALUE``.

    Returns
    -------
    str
        The command line.
    """
    return f"spectracam {name} -o {out_dir}" + (" --quick" if quick else "") \
        + (f" --renderer {renderer}" if renderer != "mitsuba" else "") + "".join(f" --set {s}" for s in sets)


def log_report(log: Callable[[str], object], t0: float, lines: Iterable[str], paths: Sequence[object],
               out_dir: Path) -> None:
    """A report's answer, line by line, then how many files were written in how long, and where the report is.

    Parameters
    ----------
    log : callable
        ``log(msg)``.
    t0 : float
        ``time.perf_counter()`` when the command started, s.
    lines : iterable of str
        The answer's lines.
    paths : sequence
        The files written (only counted).
    out_dir : Path
        The output directory, where ``report.md`` is.
    """
    for line in lines:
        log(line)
    log(f"[{time.perf_counter() - t0:6.1f} s] wrote {len(paths)} files; report: {Path(out_dir) / 'report.md'}")
