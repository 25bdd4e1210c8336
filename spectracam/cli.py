"""The ``spectracam`` command line."""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import click

from . import __version__
from .errors import SpectracamError
from .architecture import ARCHITECTURES
from .exposure import EXPOSURE_SCHEMES
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


def _with_design(camera, arch, exposure):
    """The camera with --arch/--exposure applied, validated like a config file (cfa + optimal is refused)."""
    from .scene import camera_tables, parse_camera

    flags = {k: v for k, v in (("architecture", arch), ("exposure", exposure)) if v}
    if not flags:
        return camera
    tables = camera_tables(camera)
    tables["capture"].update(flags)
    return parse_camera(tables, source="command line")


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


@main.command("capture")
@click.argument("radiance_file", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option("-o", "--output", "out_dir", required=True, type=click.Path(file_okay=False, path_type=Path),
              help="Directory to write raw.exr (and raw.dng for the colour filter array) into.")
@click.option("--arch", type=click.Choice(list(ARCHITECTURES)), default=None,
              help="Colour architecture [default: the scene's, else cfa].")
@click.option("--exposure", type=click.Choice(EXPOSURE_SCHEMES), default=None,
              help="Exposure control [default: the scene's, else single].")
@click.option("--config", "config_file", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="TOML with [optics], [filters], [sensor], [capture] tables, over the scene's.")
@click.option("--seed", type=int, default=None, help="Noise seed [default: the scene's render.seed].")
@click.option("--quiet", is_flag=True, help="No notices.")
def capture_cmd(radiance_file: Path, out_dir: Path, arch, exposure, config_file, seed, quiet):
    """Capture a spectral RADIANCE_FILE with a simulated sensor; write DIR/raw.exr (+ raw.dng for cfa)."""

    from .capture import capture
    from .io.dng import write_dng
    from .io.exr import read_radiance_exr, write_raw_exr
    from .scene import load_camera_config, parse_scene

    cube, attrs = read_radiance_exr(radiance_file)
    if "scene" not in cube.metadata:
        raise SpectracamError(f"file = {str(radiance_file)!r}: records no scene (spectracamScene), so the white "
                              "patch for exposure metering is unknown; render it with spectracam")
    scene = parse_scene(cube.metadata["scene"], source=str(radiance_file))
    camera = load_camera_config(config_file, base=scene.camera) if config_file else scene.camera
    camera = _with_design(camera, arch, exposure)
    seed = scene.render.seed if seed is None else seed
    raw = capture(cube, seed=seed, camera=camera, scene=scene)
    paths = [write_raw_exr(out_dir / "raw.exr", raw)]
    if raw.architecture == "cfa":
        paths.append(write_dng(out_dir / "raw.dng", raw))
    times = ", ".join(f"{c} {1e3 * t:.2f} ms" for c, t in zip("RGB", raw.exposure_times_s))
    _log(quiet)(f"{raw.architecture}/{raw.exposure}: exposures {times}; capture time {1e3 * raw.capture_time_s:.2f} ms")
    _log(quiet)("wrote " + ", ".join(map(str, paths)))


def _processing_options(f):
    from .color import ADAPTATIONS, DEMOSAIC_METHODS, DISPLAYS
    from .metrics import DELTA_E_METHODS

    f = click.option("--demosaic", type=click.Choice(DEMOSAIC_METHODS), default=None,
                     help="Demosaicking of the colour filter array [default: the scene's, else bilinear].")(f)
    f = click.option("--display", type=click.Choice(DISPLAYS), default=None, help="Display model [default: crt].")(f)
    f = click.option("--adaptation", type=click.Choice(ADAPTATIONS), default=None,
                     help="How scene XYZ is carried to the display white [default: xyz_scaling].")(f)
    f = click.option("--delta-e", "delta_e", type=click.Choice(DELTA_E_METHODS), default=None,
                     help="Colour difference formula [default: cie1976].")(f)
    f = click.option("--gamut-clip/--no-gamut-clip", default=None, help="Clip display RGB to [0, 1].")(f)
    return f


def _processing(scene, demosaic, display, adaptation, delta_e, gamut_clip):
    from .scene import parse_processing

    flags = {k: v for k, v in dict(demosaic=demosaic, display=display, adaptation=adaptation, delta_e=delta_e,
                                   gamut_clip=gamut_clip).items() if v is not None}
    return parse_processing(flags, source="command line", base=scene.processing)


def _score_and_write(raw, scene, processing, out_dir: Path, log):
    from .io.report import write_score_outputs
    from .score import score

    result = score(raw, scene, processing)
    paths = write_score_outputs(out_dir, result, processing)
    c = result.report["chart"]
    log(f"{raw.architecture}/{raw.exposure}: mean ΔE*ab {c['delta_e_mean']:.2f} per pixel, {c['delta_e_of_mean']:.2f} "
        f"of patch means ({c['delta_e_conversion']:.2f} from the conversion alone); SNR "
        + ("∞ (noise-free)" if c["snr_combined_db"] is None else f"{c['snr_combined_db']:.1f} dB"))
    log("wrote " + ", ".join(map(str, paths)))


@main.command("score")
@click.argument("raw_file", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option("--scene", "scene_file", required=True, type=click.Path(dir_okay=False, path_type=Path),
              help="The scene the capture was taken of (its [processing] table applies).")
@click.option("-o", "--output", "out_dir", required=True, type=click.Path(file_okay=False, path_type=Path))
@_processing_options
@click.option("--quiet", is_flag=True)
def score_cmd(raw_file, scene_file, out_dir, demosaic, display, adaptation, delta_e, gamut_clip, quiet):
    """Render RAW_FILE on a display and score it: rendered.exr/.png, delta_e.png, report.json/.csv."""
    from .io.exr import read_raw_exr
    from .scene import load_scene

    scene = load_scene(scene_file)
    processing = _processing(scene, demosaic, display, adaptation, delta_e, gamut_clip)
    raw = read_raw_exr(raw_file)
    h, w = raw.digital.shape[-2:]
    if (w, h) != (scene.image.width, scene.image.height):
        raise SpectracamError(f"image = {w}x{h}: the capture does not match scene {str(scene_file)!r} "
                              f"({scene.image.width}x{scene.image.height})")
    recorded = raw.metadata.get("scene")
    if recorded is not None:
        given = scene.to_dict()
        for table in ("chart", "illuminant", "wavelengths"):
            if recorded.get(table) != given[table]:
                raise SpectracamError(f"{table} = {json.dumps(given[table], sort_keys=True)[:120]}: scene "
                                      f"{str(scene_file)!r} is not the scene the capture recorded "
                                      f"({json.dumps(recorded.get(table), sort_keys=True)[:120]})")
    _score_and_write(raw, scene, processing, out_dir, _log(quiet))


@main.command("simulate")
@click.argument("scene_file", type=click.Path(dir_okay=False, path_type=Path))
@click.option("-o", "--output", "out_dir", required=True, type=click.Path(file_okay=False, path_type=Path))
@click.option("--arch", type=click.Choice(list(ARCHITECTURES)), default=None)
@click.option("--exposure", type=click.Choice(EXPOSURE_SCHEMES), default=None)
@click.option("--renderer", type=click.Choice(RENDERERS), default="mitsuba", show_default=True)
@_processing_options
@click.option("--quiet", is_flag=True)
def simulate_cmd(scene_file, out_dir, arch, exposure, renderer, demosaic, display, adaptation, delta_e, gamut_clip,
                 quiet):
    """Render → capture → score SCENE_FILE in one go; writes every file of the three steps."""
    from .capture import capture
    from .io.dng import write_dng
    from .io.exr import write_radiance_exr, write_raw_exr
    from .render import render
    from .scene import load_scene

    scene = load_scene(scene_file)
    camera = scene.camera
    camera = _with_design(camera, arch, exposure)
    processing = _processing(scene, demosaic, display, adaptation, delta_e, gamut_clip)
    log = _log(quiet)
    cube = render(scene, renderer=renderer, progress=not quiet, log=log)
    write_radiance_exr(out_dir / "radiance.exr", cube, scene)
    raw = capture(cube, seed=scene.render.seed, camera=camera, scene=scene)
    write_raw_exr(out_dir / "raw.exr", raw)
    if raw.architecture == "cfa":
        write_dng(out_dir / "raw.dng", raw)
    _score_and_write(raw, scene, processing, out_dir, log)


@main.command("paper")
@click.option("-o", "--output", "out_dir", required=True, type=click.Path(file_okay=False, path_type=Path))
@click.option("--experiment", "experiment_file", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Experiment file [default: scenes/paper.toml shipped with spectracam].")
@click.option("--renderer", type=click.Choice(RENDERERS), default="mitsuba", show_default=True)
@click.option("--quick", is_flag=True, help="A first look: 160x120 pixels instead of the scene's size.")
@click.option("--no-cache", is_flag=True, help="Render again even if the render cache has the scene.")
@click.option("--quiet", is_flag=True)
def paper_cmd(out_dir, experiment_file, renderer, quick, no_cache, quiet):
    """Reproduce the paper's Figures 4, 5a, 5b and 6: figures, results.json, report.md, case files."""
    import time

    from .experiments.paper import load_experiment, run_paper
    from .experiments.report import write_paper_outputs

    path = experiment_file or default_experiment()
    exp = load_experiment(path)
    log = _log(quiet)
    t0 = time.perf_counter()
    step = lambda msg: log(f"[{time.perf_counter() - t0:6.1f} s] {msg}")
    results, cases, cubes = run_paper(exp, renderer=renderer, quick=quick, use_cache=not no_cache, step=step,
                                      log=log, progress=not quiet)
    command = "spectracam paper -o " + str(out_dir) + (f" --experiment {experiment_file}" if experiment_file else "") \
        + (f" --renderer {renderer}" if renderer != "mitsuba" else "") + (" --quick" if quick else "")
    write_paper_outputs(out_dir, results, cases, cubes, command, step)
    for c in results["claims"]:
        log(f"  {c['verdict']:<10} {c['claim']}: {c['measured']}")
    step(f"done: {out_dir}/report.md")


@main.command("sweep")
@click.argument("sweep_file", type=click.Path(dir_okay=False, path_type=Path))
@click.option("-o", "--output", "out_dir", required=True, type=click.Path(file_okay=False, path_type=Path))
@click.option("--scheduler", default=None, help="Address of a running Dask scheduler, tcp://HOST:PORT "
              "[default: a local cluster of processes made for the run].")
@click.option("--workers", type=click.IntRange(1, 1024), default=None, help="Local cluster size [default: cores].")
@click.option("--serial", is_flag=True, help="Run the cells in this process, without Dask.")
@click.option("--resume", is_flag=True, help="Continue an interrupted sweep in DIR, skipping finished cells.")
@click.option("--quiet", is_flag=True)
def sweep_cmd(sweep_file, out_dir, scheduler, workers, serial, resume, quiet):
    """Run every cell of SWEEP_FILE on Dask; results.parquet/.csv/.jsonl in DIR, a row per cell and trial."""
    from .experiments.sweep import load_sweep, run_sweep

    if serial and scheduler:
        raise SpectracamError("--serial and --scheduler: choose one")
    sweep = load_sweep(sweep_file)
    t = run_sweep(sweep, out_dir, scheduler=scheduler, workers=workers, serial=serial, resume=resume,
                  progress=not quiet, log=_log(quiet))
    _log(quiet)(f"{t['new_cells']} of {t['cells']} cells computed in {t['wall_s']:.1f} s "
                f"(cell compute {t['compute_s']:.1f} s); tables in {out_dir}")


@main.command("plot-sweep")
@click.argument("out_dir", type=click.Path(exists=True, file_okay=False, path_type=Path))
@click.option("--x", "x_axis", default=None, help="Axis on the x axis [default: the last varying axis].")
@click.option("--line", "line_axis", default=None, help="Axis drawn as one line per value.")
@click.option("--panel", "panel_axis", default=None, help="Axis drawn as one panel per value.")
@click.option("--metric", "metrics", multiple=True, help="Metric(s) to plot [default: all recorded].")
def plot_sweep_cmd(out_dir, x_axis, line_axis, panel_axis, metrics):
    """Plot a finished sweep: DIR/plots/<metric>.png and .svg."""
    from .experiments.sweep_plot import plot_sweep

    paths = plot_sweep(out_dir, x_axis, line_axis, panel_axis, list(metrics) or None)
    click.echo("wrote " + ", ".join(str(p) for p in paths if p.suffix == ".png"))


def default_experiment() -> Path:
    """scenes/paper.toml of this checkout (the README's main job)."""
    here = Path(__file__).resolve().parent.parent / "scenes" / "paper.toml"
    if not here.exists():
        raise SpectracamError("experiment = scenes/paper.toml: not found next to the package; pass --experiment FILE")
    return here


@main.command("inspect")
@click.argument("file", type=click.Path(exists=True, dir_okay=False, path_type=Path))
def inspect_cmd(file: Path):
    """Print channels, size, recorded parameters and per-channel min/mean/max of an EXR file."""
    from .io.exr import describe

    click.echo(describe(file))


if __name__ == "__main__":
    main()
