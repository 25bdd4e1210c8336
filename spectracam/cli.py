"""The ``spectracam`` command line: the click group and how it runs a command (staged outputs, one-line
errors, signals, ``--view``).  Every command lives in a ``command.py`` beside the code it runs and is
imported only when asked for (``_Group.LAZY``); the options they share are in
:mod:`spectracam.experiments.options`."""
from __future__ import annotations

import sys
from pathlib import Path

import click

from spectracam._version import __version__
from spectracam.core.errors import SpectracamError
from spectracam.experiments.options import VIEW_REQUEST, progress_log

__all__ = ["main"]


def _interrupted(signum, frame):
    """SIGINT, SIGTERM, SIGHUP (what batch schedulers send at a time limit): remove every temporary
    file, say so in one line and exit with 128 + the signal's number, wherever the work was — in an
    import, a Mitsuba render or a write."""
    import os
    import signal

    from spectracam.core.processes import is_main, terminate_children   # imported by main() before the handler

    if not is_main():  # a forked worker: its parent cleans up and reports
        os._exit(128 + signum)
    signal.signal(signum, signal.SIG_IGN)  # a second signal must not interrupt the cleanup
    terminate_children()
    try:   # the signal may come while one of these modules is being imported: then nothing of it has run yet
        from spectracam.core.files import remove_unfinished
    except ImportError:
        remove_unfinished = None   # no file staged yet: the writer's module is not even loaded
    if remove_unfinished is not None:
        remove_unfinished()
    try:
        from spectracam.core.progress import on_terminal
    except ImportError:
        on_terminal = sys.stderr.isatty
    if on_terminal():  # a progress bar may be drawn on this line: clear it
        sys.stderr.write("\r\x1b[K")
    sys.stderr.write(f"spectracam: interrupted ({signal.Signals(signum).name}); nothing written\n")
    sys.stderr.flush()
    os._exit(128 + signum)


class _Group(click.Group):
    """Every command's outputs appear together or not at all (:func:`spectracam.core.files.staged`).
    Bad input is one line and exit status 2; a fault of the environment (a disk full, a directory
    not writable) one line and exit status 1; SIGINT, SIGTERM and SIGHUP remove every temporary
    file and exit with 128 + the signal's number."""

    def main(self, *args, **kwargs):
        """A usage error (an unknown option, a value out of its range) is one line and exit 2 too.
        The signal handlers are installed first, so a signal during the imports is handled too."""
        import signal

        from spectracam.core.processes import mark_main

        mark_main()
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            signal.signal(sig, _interrupted)
        try:
            rv = super().main(*args, standalone_mode=False, **kwargs)
            if Path(sys.argv[0]).name in ("spectracam", "__main__.py"):  # the program itself, about to exit
                for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):  # done and written: a late signal
                    signal.signal(sig, signal.SIG_IGN)  # must not kill the exit (rc −15 with complete outputs)
        except click.exceptions.Abort:
            click.echo("spectracam: interrupted (SIGINT); nothing written", err=True)
            sys.exit(130)
        except click.ClickException as e:
            click.echo(f"spectracam: error: {e.format_message()}", err=True)
            sys.exit(e.exit_code)
        sys.exit(rv if isinstance(rv, int) else 0)

    #: Every command: its name → (the module it lives in beside the code it runs, the click command there),
    #: imported only when it is run or listed (Mitsuba, scipy, Dask and the figures load with the command
    #: that needs them).
    LAZY = {
        "architectures": ("spectracam.experiments.architectures.command", "architectures_cmd"),
        "cameras": ("spectracam.experiments.validate.command", "cameras_cmd"),
        "capture": ("spectracam.experiments.simulate.command", "capture_cmd"),
        "consistency": ("spectracam.experiments.consistency.command", "consistency_cmd"),
        "datasheet": ("spectracam.experiments.datasheet.command", "datasheet_cmd"),
        "design": ("spectracam.experiments.design.command", "design_cmd"),
        "dynamic-range": ("spectracam.experiments.dynamic_range.command", "dynamic_range_cmd"),
        "field": ("spectracam.experiments.field.command", "field_cmd"),
        "emva": ("spectracam.experiments.emva.command", "emva_cmd"),
        "inspect": ("spectracam.experiments.simulate.command", "inspect_cmd"),
        "motion": ("spectracam.experiments.motion.command", "motion_cmd"),
        "paper": ("spectracam.experiments.paper.command", "paper_cmd"),
        "plot-sweep": ("spectracam.experiments.sweep.command", "plot_sweep_cmd"),
        "render": ("spectracam.experiments.simulate.command", "render_cmd"),
        "score": ("spectracam.experiments.simulate.command", "score_cmd"),
        "simulate": ("spectracam.experiments.simulate.command", "simulate_cmd"),
        "spatial": ("spectracam.experiments.spatial.command", "spatial_cmd"),
        "sweep": ("spectracam.experiments.sweep.command", "sweep_cmd"),
        "validate": ("spectracam.experiments.validate.command", "validate_cmd"),
        "view": ("spectracam.view.command", "view_cmd"),
        "white-balance": ("spectracam.experiments.white_balance.command", "white_balance_cmd"),
    }

    def format_epilog(self, ctx, formatter):
        """The shipped files a file argument may name, listed as this installation has them."""
        from spectracam.experiments.options import shipped_summary

        with formatter.section("Shipped files"):
            formatter.write_text(shipped_summary())

    def list_commands(self, ctx):
        return sorted([*super().list_commands(ctx), *self.LAZY])

    def get_command(self, ctx, name):
        if name in self.LAZY:
            import importlib

            module, attr = self.LAZY[name]
            return getattr(importlib.import_module(module), attr)
        return super().get_command(ctx, name)

    def invoke(self, ctx):
        import signal

        from spectracam.core.files import stage_outputs, staged

        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            signal.signal(sig, _interrupted)
        try:
            with staged():
                try:
                    rv = super().invoke(ctx)
                except BaseException:
                    from spectracam.core.progress import close_bars

                    close_bars()  # the error's one line starts a line of its own
                    raise
                request = ctx.meta.pop(VIEW_REQUEST, None)
                outputs = stage_outputs() if request is not None else None
            if request is not None:
                _write_page(*request, outputs)
            return rv
        except SpectracamError as e:
            click.echo(f"spectracam: error: {e}", err=True)
            sys.exit(2)
        except BrokenPipeError:  # the reader went away (`spectracam cameras | head`): stop quietly, as tools do
            import os

            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            sys.exit(141)
        except OSError as e:
            where = f" {e.filename}" if getattr(e, "filename", None) else ""
            click.echo(f"spectracam: error: cannot read or write{where}: {e.strerror or e}", err=True)
            sys.exit(1)
        except MemoryError:  # whatever no estimate foresaw: one line, nothing written
            click.echo("spectracam: error: out of memory; use a smaller image, fewer bands, cells or slices (the "
                       "estimates are in pipeline.check_memory)", err=True)
            sys.exit(1)
        except KeyboardInterrupt:  # raised by code, not by the signal (handled above)
            click.echo("spectracam: interrupted; nothing written", err=True)
            sys.exit(128 + signal.SIGINT)


def _write_page(out_dir: Path, quiet: bool, outputs: tuple[list, list]) -> None:
    """``--view``: write DIR/index.html once the command's outputs are in place under their names; should
    it fail (a full disk, a signal), the outputs the command just wrote are removed too
    (:func:`spectracam.core.files.staged_after`)."""
    from spectracam.core.files import staged_after
    from spectracam.view import write_view

    with staged_after(outputs):
        write_view(out_dir, log=progress_log(quiet))  # its log says what it wrote


@click.group(cls=_Group, context_settings={"max_content_width": 120})
@click.version_option(__version__, prog_name="spectracam")
def main():
    """Simulate colour image sensors on a rendered Macbeth chart (Catrysse, Wandell & El Gamal, 1999)."""


if __name__ == "__main__":
    main()
