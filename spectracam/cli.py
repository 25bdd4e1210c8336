"""The ``spectracam`` command line: arguments → the same loaders as Python → the library."""
from __future__ import annotations

import dataclasses

import sys
import time
from pathlib import Path

import click

from spectracam._version import __version__
from spectracam.experiments.options import (VIEW_REQUEST, ShippedFile, as_given, camera_options, check_writable, flag_overrides,
                          output_option, processing_options, progress_log, quiet_option, renderer_option, set_option,
                          view_option)
from spectracam.core.errors import ConfigError, SpectracamError


def _interrupted(signum, frame):
    """SIGINT, SIGTERM, SIGHUP (what batch schedulers send at a time limit): remove every temporary
    file, say so in one line and exit with 128 + the signal's number, wherever the work was — in an
    import, a Mitsuba render or a write."""
    import os
    import signal

    from spectracam.core.files import remove_unfinished
    from spectracam.core.processes import is_main, terminate_children

    if not is_main():  # a forked worker: its parent cleans up and reports
        os._exit(128 + signum)
    signal.signal(signum, signal.SIG_IGN)  # a second signal must not interrupt the cleanup
    terminate_children()
    remove_unfinished()
    from spectracam.core.progress import on_terminal

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

    #: Commands that live with their stage, imported only when asked for (scipy, Mitsuba scenes):
    #: the spatial comparison (issue 13) and motion (issue 14).
    LAZY = {"spatial": ("spectracam.experiments.spatial.command", "spatial_cmd"),
            "motion": ("spectracam.experiments.motion.command", "motion_cmd")}

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


def _given(flag: str, name: str, value) -> str:
    """`` FLAG VALUE`` for the command a report records, as the user wrote it (a shipped file's name stays a
    name); empty when the option was not given."""
    return f" {flag} {as_given(name, value)}" if value else ""


def _scene(data: dict, source: str, config_file=None, flags=(), sets=()):
    """A Scene from a scene dict with the config file's camera tables, the flags and ``--set``."""
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


# ------------------------------------------------------------------------------------------------


@main.command("render", short_help="Render a scene into a spectral EXR.")
@click.argument("scene_file", type=ShippedFile("scene file"))
@output_option("Directory to write radiance.exr into.")
@renderer_option
@set_option
@quiet_option
@view_option
def render_cmd(scene_file: Path, out_dir: Path, renderer: str, sets, quiet: bool):
    """Render SCENE_FILE into DIR/radiance.exr (spectral EXR, W·m⁻²·sr⁻¹·nm⁻¹ per band).

    SCENE_FILE is a path, or the name of a scene shipped with spectracam (d65, blackbody_3000K …
    blackbody_7000K, cfi99, mondrian, dead_leaves, photo), with or without .toml."""
    from spectracam.io.exr import write_radiance_exr
    from spectracam.render import render
    from spectracam.pipeline.scene_file import read_toml

    from spectracam.pipeline import check_memory

    scene = _scene(read_toml(scene_file, "scene file"), str(scene_file), sets=sets)  # validated before any work
    check_memory(scene)
    check_writable(out_dir)
    log = progress_log(quiet)
    t0 = time.perf_counter()
    cube = render(scene, renderer=renderer, progress=not quiet, log=log)
    path = write_radiance_exr(out_dir / "radiance.exr", cube)
    h, w, b = cube.shape
    log(f"wrote {path} ({w}x{h} px, {b} bands, {renderer}, {time.perf_counter() - t0:.2f} s)")


def _write_capture(out_dir: Path, raw, scene) -> list[Path]:
    from spectracam.io.dng import write_dng
    from spectracam.io.exr import write_raw_exr
    from spectracam.scene.reference import ChartReference

    # every layout has a DNG: a CFA mosaic, or LinearRaw for three planes (prism, field-sequential); an ADC of
    # more bits than a DNG reader takes is in raw.exr only, and the command says so
    from spectracam.io.dng import DNG_MAX_BITS

    paths = [write_raw_exr(out_dir / "raw.exr", raw)]
    if raw.camera.sensor.adc_bits > DNG_MAX_BITS:
        click.echo(f"raw.dng not written: a {raw.camera.sensor.adc_bits}-bit capture does not fit a DNG that raw "
                   f"developers read (at most {DNG_MAX_BITS} bits); it is in raw.exr", err=True)
        return paths
    reference, neutral = ChartReference.of(scene), None
    if not scene.processing.told_the_light and raw.scene is not None:   # AsShotNeutral: the camera's own white
        from spectracam.processing import develop
        from spectracam.evaluation.score import camera_rates

        target = None
        if scene.target.textured:
            from spectracam.scene.reference import TargetReference

            target = TargetReference.of(scene)
        neutral = develop(camera_rates(raw, scene.processing), raw, reference, scene.processing, target).neutral
    return paths + [write_dng(out_dir / "raw.dng", raw, reference, neutral_rates=neutral)]


@main.command("capture", short_help="Capture a spectral EXR with a simulated sensor.")
@click.argument("radiance_file", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@output_option("Directory to write raw.exr and raw.dng into (and rendered.exr/.png for a spectral image from another tool).")
@camera_options
@click.option("--white", default=None, metavar="patch|brightest|X0,Y0,X1,Y1|L",
              help="Where exposure is metered: the chart's white patch (spectracam scenes' default), the brightest "
                   "neutral (other files' default), a pixel region, or a white luminance L in cd/m² under the "
                   "scene illuminant.")
@click.option("--units", default=None, metavar="UNIT",
              help="Radiance unit of a spectral EXR that states none (emissiveUnits), e.g. W.m^-2.sr^-1 (per nm).")
@set_option
@quiet_option
@view_option
def capture_cmd(radiance_file: Path, out_dir: Path, arch, exposure, config_file, seed, white, units, sets, quiet):
    """Capture a spectral RADIANCE_FILE (spectracam's, or a Fichet-layout EXR from any tool) with a simulated
    sensor; write DIR/raw.exr and DIR/raw.dng."""
    from spectracam.io.exr import read_radiance_exr
    from spectracam.sensor.metering import parse_white
    from spectracam.pipeline import capture, capture_spectral_image, check_cube_matches, stand_in_scene

    white_spec = parse_white(white) if white is not None else None  # checked before the file is read
    cube, _ = read_radiance_exr(radiance_file, units)  # checked as it is read
    log = progress_log(quiet)
    flags = flag_overrides(arch=arch, exposure=exposure)
    recorded = "scene" in cube.metadata
    if recorded:
        scene = _scene(cube.metadata["scene"], str(radiance_file), config_file, flags, sets)
        check_cube_matches(cube, scene, str(radiance_file))
    else:  # a spectral image from another tool: the stand-in scene holds the camera and the conversion's chart
        from spectracam.pipeline import STAND_IN_SCENE

        data = _scene(dict(STAND_IN_SCENE), str(radiance_file), config_file, flags, sets).to_dict()
        data.pop("wavelengths")  # the image's own bands
        cube, scene = stand_in_scene(cube, data, str(radiance_file))
        if "bands_dropped_outside_nm" in cube.metadata:
            lo, hi = cube.metadata["bands_dropped_outside_nm"]
            log(f"{radiance_file}: bands outside {lo:g}–{hi:g} nm dropped (the chart the conversion is fitted on has "
                "no reflectance data there)")
    check_writable(out_dir)
    raw = capture(cube, seed=seed, scene=scene, white=white_spec) if recorded else \
        capture_spectral_image(cube, scene, seed, white_spec)
    paths = _write_capture(out_dir, raw, scene)
    if raw.scene is None:
        paths += _write_display(out_dir, raw, scene)
        log(f"{radiance_file} records no spectracam chart scene: ΔE per patch and SNR are skipped (no chart truth); "
            f"exposure metered on {raw.metering['kind']} white; rendered through the conversion fitted on the "
            f"{scene.chart.dataset} chart under {scene.illuminant.label}")
    times = ", ".join(f"{c} {1e3 * t:.2f} ms" for c, t in zip(raw.layout.channels, raw.exposure_times_s))
    log(f"{raw.design}: exposures {times}; capture time {1e3 * raw.capture_time_s:.2f} ms")
    log("wrote " + ", ".join(map(str, paths)))


def _write_display(out_dir: Path, raw, scene) -> list[Path]:
    """rendered.exr and rendered.png of a capture without a chart truth (no score)."""
    from spectracam.io.report import srgb_preview, write_display_exr, write_png
    from spectracam.scene.reference import ChartReference
    from spectracam.evaluation.score import display_rgb

    rgb, M = display_rgb(raw, ChartReference.of(scene), scene.processing)
    params = {"scene": None, "conversion_fitted_on": scene.to_dict(), "camera": raw.camera.to_dict(),
              "processing": scene.processing.to_dict(), "seed": raw.seed, "metering": raw.metering,
              "conversion_matrix": M.tolist()}
    return [write_display_exr(out_dir / "rendered.exr", rgb.astype("float32"), params),
            write_png(out_dir / "rendered.png", srgb_preview(rgb, scene.processing.display,
                                                                     tone_curve=scene.processing.tone_curve))]


def _score_and_write(raw, scene, out_dir: Path, log, cube=None):
    from spectracam.io.report import write_score_outputs
    from spectracam.pipeline import both_ways, score

    result = score(raw, scene)
    result = dataclasses.replace(result, both_ways=both_ways(raw, scene, cube, result))   # report.json's two blocks
    if scene.target.textured:
        from spectracam.io.report import write_target_outputs

        paths = write_target_outputs(out_dir, result)
        h, t = result.held_out, result.training
        what = "colours it was fitted on" if h["fitted_on_these"] else "colours it was not fitted on"
        log(f"{raw.design}: {h['kind']} of {h['library']} ({what}), {h['pixels']} pixels, {h['samples']} samples: "
            f"ΔE*ab per pixel mean {h['delta_e_mean']:.2f}, 95th percentile {h['delta_e_p95']:.2f}; S-CIELAB mean "
            f"{h['s_cielab_mean']:.2f} (the conversion on the chart it was fitted on: {t['delta_e_mean']:.2f})")
        _log_both_ways(result.both_ways, log)
        log("wrote " + ", ".join(map(str, paths)))
        return
    paths = write_score_outputs(out_dir, result)
    c = result.summary
    log(f"{raw.design}: mean ΔE*ab {c.delta_e_mean:.2f} per pixel, {c.delta_e_of_mean:.2f} of patch means "
        f"({c.delta_e_conversion:.2f} from the conversion alone); SNR "
        + ("∞ (noise-free)" if c.snr_combined_db is None else f"{c.snr_combined_db:.1f} dB"))
    _log_both_ways(result.both_ways, log)
    if result.held_out is not None:
        h = result.held_out
        log(f"conversion on colours it was not fitted on ({h['library']}, {h['samples']} samples): mean ΔE "
            f"{h['delta_e_mean']:.2f}, 95th percentile {h['delta_e_p95']:.2f} (on the chart it was fitted on: "
            f"{result.training['delta_e_mean']:.2f}, {result.training['delta_e_p95']:.2f})")
    log("wrote " + ", ".join(map(str, paths)))


def _log_both_ways(bw: dict, log) -> None:
    o, d = bw["oracle"], bw["developed"]

    def pair(key: str, unit: str = "") -> str:   # a score may be undefined (None): an image with no signal
        return " / ".join("undefined" if c.get(key) is None else f"{c[key]:.2f}{unit}" for c in (o, d))

    log(f"oracle camera (told the light) / developed camera (finds its own white): mean ΔE*ab "
        f"{pair('delta_e_mean')}, S-CIELAB {pair('s_cielab_mean')}, CIEDE2000 {pair('delta_e2000_mean')}; the "
        f"developed camera's white is "
        + ("undefined" if d.get("awb_recovery_deg") is None else f"{d['awb_recovery_deg']:.2f}°")
        + f" off (metering: {bw['metering']})")


@main.command("score", short_help="Render a raw capture on a display and score it.")
@click.argument("raw_file", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option("--scene", "scene_file", type=ShippedFile("scene file"), default=None,
              help="The scene the capture was taken of (its [processing] table applies): a path or a shipped "
                   "scene's name [default: the scene the raw file records].")
@output_option("Directory to write rendered.exr/.png, delta_e.png and report.json/.csv into.")
@processing_options
@set_option
@quiet_option
@view_option
def score_cmd(raw_file, scene_file, out_dir, demosaic, display, adaptation, delta_e, gamut_clip, sets, quiet):
    """Render RAW_FILE on a display and score it: rendered.exr/.png, delta_e.png, report.json/.csv."""
    from spectracam.io.exr import read_raw_exr
    from spectracam.pipeline.scene_file import read_toml

    raw = read_raw_exr(raw_file)
    if scene_file is not None:
        data, source = read_toml(scene_file, "scene file"), str(scene_file)
    elif raw.scene is not None:
        data, source = raw.scene, f"the scene recorded in {raw_file}"
    else:
        raise SpectracamError(f"file = {str(raw_file)!r}: records no scene; pass --scene SCENE.toml")
    flags = flag_overrides(demosaic=demosaic, display=display, adaptation=adaptation, delta_e=delta_e,
                            gamut_clip=gamut_clip)
    scene = _scene(data, source, flags=flags, sets=sets)
    check_writable(out_dir)
    _score_and_write(raw, scene, out_dir, progress_log(quiet))


@main.command("simulate", short_help="Render, capture and score a scene in one go.")
@click.argument("scene_file", type=ShippedFile("scene file"))
@output_option("Directory to write every file of render, capture and score into.")
@renderer_option
@camera_options
@processing_options
@set_option
@quiet_option
@view_option
def simulate_cmd(scene_file, out_dir, renderer, arch, exposure, config_file, seed, demosaic, display, adaptation,
                 delta_e, gamut_clip, sets, quiet):
    """Render → capture → score SCENE_FILE in one go; writes every file of the three steps.

    SCENE_FILE is a path, or the name of a scene shipped with spectracam (d65, blackbody_3000K …
    blackbody_7000K, cfi99, mondrian, dead_leaves, photo), with or without .toml."""
    from spectracam.io.exr import write_radiance_exr
    from spectracam.pipeline import capture
    from spectracam.render import render
    from spectracam.pipeline.scene_file import read_toml

    flags = flag_overrides(arch=arch, exposure=exposure, demosaic=demosaic, display=display, adaptation=adaptation,
                            delta_e=delta_e, gamut_clip=gamut_clip)
    from spectracam.pipeline import check_memory

    scene = _scene(read_toml(scene_file, "scene file"), str(scene_file), config_file, flags, sets)
    check_memory(scene)
    check_writable(out_dir)
    log = progress_log(quiet)
    cube = render(scene, renderer=renderer, progress=not quiet, log=log)
    write_radiance_exr(out_dir / "radiance.exr", cube)
    raw = capture(cube, seed=seed, scene=scene)
    _write_capture(out_dir, raw, scene)
    _score_and_write(raw, scene, out_dir, log, cube)


@main.command("paper", short_help="Reproduce the paper's Figures 4, 5a, 5b and 6.")
@output_option("Directory to write the figures, results.json, report.md and the case files into.")
@click.option("--experiment", "experiment_file", type=ShippedFile("experiment file"), default=None,
              help="Experiment file: a path or a shipped one's name [default: paper, scenes/paper.toml shipped with "
                   "spectracam].")
@renderer_option
@click.option("--quick", is_flag=True, help="A first look: 160x120 pixels instead of the scene's size.")
@click.option("--no-cache", is_flag=True, help="Render again even if the render cache has the scene.")
@click.option("--save-cubes", is_flag=True, help="Also write every light's spectral radiance cube into DIR/cases "
              "(~37 MB each; they are in the render cache).")
@set_option
@quiet_option
@view_option
def paper_cmd(out_dir, experiment_file, renderer, quick, no_cache, save_cubes, sets, quiet):
    """Reproduce the paper's Figures 4, 5a, 5b and 6: figures, results.json, report.md, case files."""
    from spectracam.experiments.paper.experiment import load_experiment, quick_scene, run_paper
    from spectracam.experiments.paper.report import write_paper_outputs

    from spectracam.pipeline import check_memory

    path = experiment_file or default_experiment()
    exp = load_experiment(path, sets)
    base = quick_scene(exp.base, quick)
    check_memory(base, copies=len(exp.temperatures_K) + 1, what=f", {len(exp.temperatures_K) + 1} lights held at once")
    check_writable(out_dir)
    log = progress_log(quiet)
    t0 = time.perf_counter()
    step = lambda msg: log(f"[{time.perf_counter() - t0:6.1f} s] {msg}")  # noqa: E731
    results, cases, cubes = run_paper(exp, renderer=renderer, quick=quick, use_cache=not no_cache, step=step,
                                      log=log, progress=not quiet)
    command = "spectracam paper -o " + str(out_dir) + _given("--experiment", "experiment_file", experiment_file) \
        + (f" --renderer {renderer}" if renderer != "mitsuba" else "") + (" --quick" if quick else "") \
        + "".join(f" --set {s}" for s in sets)
    write_paper_outputs(out_dir, results, cases, cubes, command, step, save_cubes=save_cubes)
    for c in results["claims"]:
        log(f"  {c['verdict']:<10} {c['claim']}: {c['measured']}")
    step(f"done: {out_dir}/report.md (figures fig4-6.png/.svg, results.json, cases/ with every capture's raw.exr "
         "and rendered.exr)")


@main.command("architectures", short_help="Compare every architecture at the paper's camera and light.")
@output_option("Directory to write results.json, report.md and the figures into.")
@click.option("--experiment", "experiment_file", type=ShippedFile("experiment file"), default=None,
              help="Experiment file whose camera, chart and light are used: a path or a shipped one's name "
                   "[default: paper, scenes/paper.toml].")
@renderer_option
@click.option("--quick", is_flag=True, help="A first look: 160x120 pixels and 2 noise seeds.")
@click.option("--seeds", type=click.IntRange(1, 100), default=None,
              help="Noise seeds per case [default: 5; 2 with --quick].")
@click.option("--no-cache", is_flag=True, help="Render again even if the render cache has the scene.")
@click.option("--min-white-snr-db", type=float, default=None,
              help="A case whose white patch's rendered SNR is below this is no usable image and never a winner "
                   "[default: 20, ISO 12232's 'acceptable' SNR 10].")
@click.option("--max-s-cielab", type=float, default=None,
              help="A case whose mean S-CIELAB ΔE*ab is above this is no usable image [default: 40, a flat grey "
                   "image of the chart's mean lightness].")
@set_option
@quiet_option
@view_option
def architectures_cmd(out_dir, experiment_file, renderer, quick, seeds, no_cache, min_white_snr_db, max_s_cielab,
                      sets, quiet):
    """Every registered architecture and exposure scheme at the paper's camera, light and noise, at 1, 1/10
    and 1/100 of its light: SNR, ΔE (training and held-out), capture time; then each architecture on the
    slanted edge and star (MTF50, false colour, S-CIELAB; with and without an optical low-pass filter) and
    on a moving edge (colour breakup); results.json, report.md, figures."""
    from spectracam.experiments.architectures.experiment import SEEDS, ArchitecturesRun, designs, run_architectures, \
        write_architectures_outputs
    from spectracam.experiments.paper.experiment import load_experiment, quick_scene
    from spectracam.pipeline import check_memory

    exp = load_experiment(experiment_file or default_experiment(), sets)
    from spectracam.evaluation.usability import UsabilitySpec

    limits = {k: v for k, v in (("min_white_snr_db", min_white_snr_db), ("max_s_cielab_mean", max_s_cielab))
              if v is not None}
    usability = UsabilitySpec.from_dict(limits, "the command line") if limits else UsabilitySpec()
    run = ArchitecturesRun(exp, quick=quick, seeds=seeds or (2 if quick else SEEDS), usability=usability)
    base = quick_scene(exp.base, quick)
    check_memory(base, copies=2, what=", two lights and a scaled copy held at once")
    check_writable(out_dir)
    log = progress_log(quiet)
    t0 = time.perf_counter()
    step = lambda msg: log(f"[{time.perf_counter() - t0:6.1f} s] {msg}")  # noqa: E731
    step(f"{len(designs())} designs: {', '.join(designs())}")
    results = run_architectures(run, renderer=renderer, use_cache=not no_cache, step=step, log=log,
                                progress=not quiet)
    command = "spectracam architectures -o " + str(out_dir) \
        + _given("--experiment", "experiment_file", experiment_file) \
        + (f" --renderer {renderer}" if renderer != "mitsuba" else "") + (" --quick" if quick else "") \
        + (f" --seeds {seeds}" if seeds else "") \
        + (f" --min-white-snr-db {min_white_snr_db:g}" if min_white_snr_db is not None else "") \
        + (f" --max-s-cielab {max_s_cielab:g}" if max_s_cielab is not None else "") + "".join(f" --set {s}" for s in sets)
    write_architectures_outputs(out_dir, results, command, step)
    for w in results["winners"]:
        log(f"  {w['illuminant']:>7} {w['light_factor']:>5g}x  {w['metric']:<16} "
            + (f"{w['design']:<18} {w['value']:.3g}" if w["design"] is not None else w.get("note", "no usable image")))


@main.command("emva", short_help="Measure the simulated camera by EMVA 1288.")
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
    scene = _scene(data, source, config_file, (), sets)
    check_writable(out_dir)
    result = run_emva(scene.camera, EmvaSetup(channel=channel, wavelength_nm=wavelength_nm, seed=seed))
    command = "spectracam emva -o " + str(out_dir) + _given("--scene", "scene_file", scene_file) \
        + (f" --config {config_file}" if config_file else "") + f" --channel {channel} --wavelength {wavelength_nm:g}" \
        + f" --seed {seed}" + "".join(f" --set {s}" for s in sets)
    paths = write_emva_outputs(out_dir, result, command)
    log = progress_log(quiet)
    num = lambda x: "–" if x is None else f"{x:.5g}"  # noqa: E731
    for k, v in result["measured"].items():
        log(f"  {k:<26} configured {num(result['configured'][k]):>10}   measured {num(v):>10}")
    log("wrote " + ", ".join(str(p) for p in paths if p.suffix != ".svg"))


@main.command("cameras", short_help="List the measured cameras filters.camera can name.")
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


@main.command("validate", short_help="Check the shipped cameras against published matrices.")
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


def _analytic_renderer_option(f):
    """``--renderer`` as :data:`renderer_option`, the closed form by default (a render does not depend on the
    sensor, and the white-balance statistics need many)."""
    from spectracam.experiments.options import RegistryChoice
    from spectracam.render import RENDERERS

    return click.option("--renderer", type=RegistryChoice(RENDERERS, "--renderer"), default="analytic",
                        show_default=True, help="The closed form or Mitsuba (Monte Carlo).")(f)


@main.command("white-balance", short_help="The white-balance estimators' angular errors per sensor.")
@output_option("Directory to write results.json, report.md and white_balance.png/.svg into.")
@click.option("--quick", is_flag=True, help="A first look: 160x120 pixels and 1 noise seed.")
@click.option("--seeds", type=click.IntRange(1, 100), default=None,
              help="Noise seeds per case [default: 3; 1 with --quick].")
@_analytic_renderer_option
@set_option
@quiet_option
@view_option
def white_balance_cmd(out_dir, quick, seeds, renderer, sets, quiet):
    """Every white-balance estimator but the oracle on the same captures — the paper's camera, each shipped measured
    camera and a Luther camera, each on the ColorChecker, Mondrian, dead leaves and photograph under 16 lights
    (blackbodies 2700–7500 K, CIE D50/D65/D75, FL2/FL7/FL11, LED-B1/B3/BH1/V1): recovery and reproduction angular
    errors, their mean, median and 95th percentile per sensor; results.json, report.md, white_balance.png/.svg.
    --set PATH=VALUE changes every case's scene (e.g. sensor.read_noise_e=5, processing.white_balance_p=4)."""
    from spectracam.experiments.white_balance.experiment import plan, run_white_balance, summary_line, write_white_balance_outputs
    from spectracam.pipeline import check_memory

    run = plan(quick=quick, seeds=seeds, renderer=renderer, sets=sets)   # every scene validated before any work
    check_memory(run.scenes[run.sensors[0].key]["photo"], copies=4, what=", a render and its captures per worker")
    check_writable(out_dir)
    log = progress_log(quiet)
    t0 = time.perf_counter()
    step = lambda msg: log(f"[{time.perf_counter() - t0:6.1f} s] {msg}")  # noqa: E731
    step(f"{len(run.sensors)} sensors × {run.cases_per_sensor} scene × light cases × {run.seeds} "
         f"seed(s), renderer {renderer}")
    result = run_white_balance(run, log=step, progress=not quiet)
    command = "spectracam white-balance -o " + str(out_dir) + (" --quick" if quick else "") \
        + (f" --seeds {seeds}" if seeds else "") + (f" --renderer {renderer}" if renderer != "analytic" else "") \
        + "".join(f" --set {s}" for s in sets)
    paths = write_white_balance_outputs(out_dir, result, command)
    for s in run.sensors:
        log(summary_line(result, s.key))
    log("wrote " + ", ".join(str(p) for p in paths if p.suffix != ".svg"))


@main.command("consistency", short_help="Map which readings of the paper reproduce its claims.")
@output_option("Directory to write consistency.json, consistency.md and the map (PNG, SVG) into.")
@click.option("--experiment", "experiment_file", type=ShippedFile("experiment file"), default=None,
              help="Experiment file: a path or a shipped one's name [default: paper, scenes/paper.toml shipped with "
                   "spectracam].")
@renderer_option
@click.option("--full", is_flag=True, help="The scene's full image size instead of 160x120.")
@set_option
@quiet_option
@view_option
def consistency_cmd(out_dir, experiment_file, renderer, full, sets, quiet):
    """Which readings of the paper's open choices reproduce which of its claims: a map and a table."""
    from spectracam.experiments.consistency.experiment import run_consistency, write_consistency_outputs
    from spectracam.experiments.paper.experiment import load_experiment

    exp = load_experiment(experiment_file or default_experiment(), sets)
    from spectracam.pipeline import check_memory

    if full:  # the quick map is 160x120: nothing to estimate
        check_memory(exp.base, copies=len(exp.temperatures_K) + 1, what=f", {len(exp.temperatures_K) + 1} lights")
    check_writable(out_dir)
    log = progress_log(quiet)
    result = run_consistency(exp, renderer=renderer, quick=not full, log=log, progress=not quiet)
    command = "spectracam consistency -o " + str(out_dir) \
        + _given("--experiment", "experiment_file", experiment_file) + f" --renderer {renderer}" \
        + (" --full" if full else "") + "".join(f" --set {s}" for s in sets)
    paths = write_consistency_outputs(out_dir, result, command)
    log(f"{len(result['rows'])} readings in {result['seconds']:.0f} s; wrote " + ", ".join(
        str(p) for p in paths if p.suffix != ".svg"))


@main.command("sweep", short_help="Run a design-space sweep, a row per cell and trial.")
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


@main.command("plot-sweep", short_help="Plot a finished sweep: one figure per metric.")
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


def default_experiment() -> Path:
    """The paper's experiment file shipped with spectracam (scenes/paper.toml)."""
    from spectracam.pipeline.scene_file import shipped_scene_file

    try:
        return shipped_scene_file("paper.toml")
    except ConfigError:
        raise SpectracamError("experiment = scenes/paper.toml: not shipped with this installation; "
                              "pass --experiment FILE") from None


@main.command("design", short_help="Design each architecture's filters by gradient.")
@click.argument("spec_file", metavar="SPEC.toml", type=ShippedFile("design file"))
@output_option("Directory to write results.json, report.md, curves.csv and the figures into.")
@click.option("--quick", is_flag=True, help="A first look in under 2 minutes: 2 lights, 3 designs (cfa, prism, "
              "fsc with its exposure split) trained on the ColorChecker, 20-nm knots, 25 iterations, 2 seeds at "
              "160x120 pixels.")
@set_option
@quiet_option
@view_option
def design_cmd(spec_file, out_dir, quick, sets, quiet):
    """Design each architecture's filters (or stacked depths, IR-cut edge, exposure split) by gradient: minimise
    the expected ΔE*ab under the sensor's noise over a training library × lights with Dr.Jit's gradients; score
    on held-out colours; verify by Monte Carlo through capture → score; compare with the paper's filters, the
    grid's best block pair and the Luther camera.  SPEC.toml: a design file, or the name of a shipped one
    (design, with or without .toml)."""
    from spectracam.experiments.design.report import write_design_outputs
    from spectracam.experiments.design.run import run_design, setup
    from spectracam.experiments.design.spec import load_design

    spec, base_dir = load_design(spec_file, sets, quick=quick)
    st = setup(spec, base_dir)
    check_writable(out_dir)
    log = progress_log(quiet)
    t0 = time.perf_counter()
    step = lambda msg: log(f"[{time.perf_counter() - t0:6.1f} s] {msg}")  # noqa: E731
    step(f"{len(spec.designs)} designs ({spec.filters} filters) on {spec.training} × {len(spec.lights)} lights")
    results = run_design(spec, base_dir, log=step, st=st, progress=not quiet)
    command = f"spectracam design {as_given('spec_file', spec_file)} -o {out_dir}" + (" --quick" if quick else "") \
        + "".join(f" --set {s}" for s in sets)
    write_design_outputs(out_dir, results, command, step)
    for name, e in results["designs"].items():
        mc, paper = e["monte_carlo_delta_e"], e["paper_filters"]
        log(f"  {name:<18} held-out ΔE {paper['held_out_delta_e']:.2f} → {e['held_out_delta_e']:.2f}; chart "
            f"expected {e['predicted_delta_e']['chart']:.2f}, Monte Carlo {mc['mean']:.2f} ± {mc['std']:.2f}")


@main.command("inspect", short_help="Print an EXR file's channels, parameters and statistics.")
@click.argument("file", type=click.Path(exists=True, dir_okay=False, path_type=Path))
def inspect_cmd(file: Path):
    """Print channels, size, recorded parameters and per-channel min/mean/max of an EXR file."""
    from spectracam.io.exr import describe

    click.echo(describe(file))


@main.command("view", short_help="Write DIR/index.html, an interactive page of DIR.")
@click.argument("out_dir", metavar="DIR", type=click.Path(exists=True, file_okay=False, path_type=Path))
@quiet_option
def view_cmd(out_dir: Path, quiet: bool):
    """Write DIR/index.html: one self-contained interactive page of what a spectracam command wrote into DIR
    (any command's output directory); print the page's path.  Every command that writes a directory does
    the same with --view."""
    from spectracam.view import write_view

    page = write_view(out_dir, log=progress_log(quiet))
    click.echo(str(page))


if __name__ == "__main__":
    main()
