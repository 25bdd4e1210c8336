"""``spectracam render``, ``capture``, ``score``, ``simulate`` and ``inspect``: one case through one stage, or
through every stage in one go (self-contained click commands, registered lazily by :mod:`spectracam.cli`)."""
from __future__ import annotations

import time
from pathlib import Path

import click

from spectracam.core.errors import SpectracamError
from spectracam.experiments.options import (ShippedFile, camera_options, check_writable, flag_overrides,
                                            output_option, processing_options, progress_log, quiet_option,
                                            renderer_option, scene_from, set_option, view_option)
from spectracam.experiments.simulate.outputs import score_and_write, write_capture, write_display

__all__ = ["capture_cmd", "inspect_cmd", "render_cmd", "score_cmd", "simulate_cmd"]


@click.command("render", short_help="Render a scene into a spectral EXR.")
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

    scene = scene_from(read_toml(scene_file, "scene file"), str(scene_file), sets=sets)  # validated before any work
    check_memory(scene)
    check_writable(out_dir)
    log = progress_log(quiet)
    t0 = time.perf_counter()
    cube = render(scene, renderer=renderer, progress=not quiet, log=log)
    path = write_radiance_exr(out_dir / "radiance.exr", cube)
    h, w, b = cube.shape
    log(f"wrote {path} ({w}x{h} px, {b} bands, {renderer}, {time.perf_counter() - t0:.2f} s)")


@click.command("capture", short_help="Capture a spectral EXR with a simulated sensor.")
@click.argument("radiance_file", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@output_option("Directory to write raw.exr and raw.dng into (and rendered.exr/.png for a spectral image from another tool).")
@camera_options
@click.option("--white", default=None, metavar="patch|brightest|X0,Y0,X1,Y1|L",
              help="Where exposure is metered: the chart's white patch (spectracam scenes' default), the brightest "
                   "neutral (other files' default), a pixel region, or a white luminance L in cd/m² under the "
                   "scene illuminant.")
@click.option("--units", default=None, metavar="UNIT",
              help="Radiance unit of a spectral EXR that states none (emissiveUnits), e.g. W.m^-2.sr^-1 (per nm).")
@click.option("--channel-planes", is_flag=True,
              help="Integrate the file's bands one at a time into the camera's channel planes, never stacking them "
                   "into a cube (a spectracam chart scene of one light, metered on its white patch).")
@set_option
@quiet_option
@view_option
def capture_cmd(radiance_file: Path, out_dir: Path, arch, exposure, config_file, seed, white, units, channel_planes,
                sets, quiet):
    """Capture a spectral RADIANCE_FILE (spectracam's, or a Fichet-layout EXR from any tool) with a simulated
    sensor; write DIR/raw.exr and DIR/raw.dng."""
    from spectracam.sensor.metering import parse_white
    from spectracam.pipeline import capture, capture_spectral_image

    white_spec = parse_white(white) if white is not None else None  # checked before the file is read
    log = progress_log(quiet)
    flags = flag_overrides(arch=arch, exposure=exposure)
    if channel_planes:
        from spectracam.pipeline import check_planes_white

        check_planes_white(white_spec)   # before the file is read
        cube, scene = _planes_of(radiance_file, units, config_file, flags, sets)
        recorded = True
    else:
        cube, scene, recorded = _cube_of(radiance_file, units, config_file, flags, sets, log)
    check_writable(out_dir)
    raw = capture(cube, seed=seed, scene=scene, white=white_spec) if recorded else \
        capture_spectral_image(cube, scene, seed, white_spec)
    paths = write_capture(out_dir, raw, scene)
    if raw.scene is None:
        paths += write_display(out_dir, raw, scene)
        log(f"{radiance_file} records no spectracam chart scene: ΔE per patch and SNR are skipped (no chart truth); "
            f"exposure metered on {raw.metering['kind']} white; rendered through the conversion fitted on the "
            f"{scene.chart.dataset} chart under {scene.illuminant.label}")
    times = ", ".join(f"{c} {1e3 * t:.2f} ms" for c, t in zip(raw.layout.channels, raw.exposure_times_s))
    log(f"{raw.design}: exposures {times}; capture time {1e3 * raw.capture_time_s:.2f} ms")
    log("wrote " + ", ".join(map(str, paths)))


def _cube_of(radiance_file: Path, units, config_file, flags, sets, log):
    """``(cube, scene, recorded)`` of a spectral EXR: its own scene (checked against its pixels) or, for a file from
    another tool, the stand-in scene and the cube's bands inside the chart's data."""
    from spectracam.io.exr import read_radiance_exr
    from spectracam.pipeline import STAND_IN_SCENE, check_cube_matches, stand_in_scene

    cube, _ = read_radiance_exr(radiance_file, units)  # checked as it is read
    if "scene" in cube.metadata:
        scene = scene_from(cube.metadata["scene"], str(radiance_file), config_file, flags, sets)
        check_cube_matches(cube, scene, str(radiance_file))
        return cube, scene, True
    # a spectral image from another tool: the stand-in scene holds the camera and the conversion's chart
    data = scene_from(dict(STAND_IN_SCENE), str(radiance_file), config_file, flags, sets).to_dict()
    data.pop("wavelengths")  # the image's own bands
    cube, scene = stand_in_scene(cube, data, str(radiance_file))
    if "bands_dropped_outside_nm" in cube.metadata:
        lo, hi = cube.metadata["bands_dropped_outside_nm"]
        log(f"{radiance_file}: bands outside {lo:g}–{hi:g} nm dropped (the chart the conversion is fitted on has "
            "no reflectance data there)")
    return cube, scene, False


def _planes_of(radiance_file: Path, units, config_file, flags, sets):
    """``(channel planes, scene)`` of a spectracam spectral EXR: its bands integrated one at a time into the scene
    camera's channel planes (:func:`spectracam.pipeline.integrate_planes`), checked against its scene."""
    from spectracam.io.exr import read_radiance_bands
    from spectracam.pipeline import check_planes_match, integrate_planes

    wavelengths, bands, meta, _ = read_radiance_bands(radiance_file, units)
    if "scene" not in meta:
        raise SpectracamError(f"file = {str(radiance_file)!r}: records no spectracam scene; --channel-planes "
                              "integrates a spectracam chart scene's radiance (capture a file from another tool "
                              "without it)")
    scene = scene_from(meta["scene"], str(radiance_file), config_file, flags, sets)
    if scene.target.textured or len(scene.lights) > 1:
        raise SpectracamError(f"file = {str(radiance_file)!r}: --channel-planes captures a chart scene of one light; "
                              "capture this file without it")
    if len(wavelengths) != len(scene.grid):
        raise SpectracamError(f"{radiance_file}: {len(wavelengths)} bands, but its scene's grid has "
                              f"{len(scene.grid)}")
    planes = integrate_planes(wavelengths, bands, meta, scene.camera, str(radiance_file))
    del bands
    check_planes_match(planes, scene, str(radiance_file))
    return planes, scene


@click.command("score", short_help="Render a raw capture on a display and score it.")
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
    scene = scene_from(data, source, flags=flags, sets=sets)
    check_writable(out_dir)
    score_and_write(raw, scene, out_dir, progress_log(quiet))


@click.command("simulate", short_help="Render, capture and score a scene in one go.")
@click.argument("scene_file", type=ShippedFile("scene file"))
@output_option("Directory to write every file of render, capture and score into.")
@renderer_option
@click.option("--channel-planes", is_flag=True,
              help="Integrate each band into the camera's channel planes as it is rendered: the same capture without "
                   "the spectral cube (no radiance.exr; a chart scene of one light).")
@camera_options
@processing_options
@set_option
@quiet_option
@view_option
def simulate_cmd(scene_file, out_dir, renderer, channel_planes, arch, exposure, config_file, seed, demosaic, display,
                 adaptation, delta_e, gamut_clip, sets, quiet):
    """Render → capture → score SCENE_FILE in one go; writes every file of the three steps.

    SCENE_FILE is a path, or the name of a scene shipped with spectracam (d65, blackbody_3000K …
    blackbody_7000K, cfi99, mondrian, dead_leaves, photo), with or without .toml."""
    from spectracam.io.exr import write_radiance_exr
    from spectracam.pipeline import capture, check_memory, render_planes
    from spectracam.render import render
    from spectracam.pipeline.scene_file import read_toml

    flags = flag_overrides(arch=arch, exposure=exposure, demosaic=demosaic, display=display, adaptation=adaptation,
                            delta_e=delta_e, gamut_clip=gamut_clip)
    scene = scene_from(read_toml(scene_file, "scene file"), str(scene_file), config_file, flags, sets)
    check_memory(scene, channel_planes=channel_planes)
    check_writable(out_dir)
    log = progress_log(quiet)
    if channel_planes:   # refused in one line before any file is written: a textured target, light groups …
        cube = render_planes(scene, renderer, progress=not quiet, log=log)
        log("radiance.exr not written: --channel-planes integrated each band into the camera's "
            f"{'/'.join(cube.metadata['channel_planes']['channels'])} planes as it was rendered (no spectral cube)")
    else:
        cube = render(scene, renderer=renderer, progress=not quiet, log=log)
        write_radiance_exr(out_dir / "radiance.exr", cube)
    raw = capture(cube, seed=seed, scene=scene)
    write_capture(out_dir, raw, scene)
    score_and_write(raw, scene, out_dir, log, cube)


@click.command("inspect", short_help="Print an EXR file's channels, parameters and statistics.")
@click.argument("file", type=click.Path(exists=True, dir_okay=False, path_type=Path))
def inspect_cmd(file: Path):
    """Print channels, size, recorded parameters and per-channel min/mean/max of an EXR file."""
    from spectracam.io.exr import describe

    click.echo(describe(file))
