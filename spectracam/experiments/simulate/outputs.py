"""What the single-stage commands write and say: a capture's raw.exr and raw.dng, the display rendering of a
capture without a chart truth, and a score's files with its one-line summaries."""
from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import TYPE_CHECKING

import click

if TYPE_CHECKING:
    from collections.abc import Callable

    from spectracam.camera.capture import RawCapture
    from spectracam.pipeline.scene_file import Scene
    from spectracam.render import RadianceCube

__all__ = ["score_and_write", "write_capture", "write_display"]


def write_capture(out_dir: Path, raw: RawCapture, scene: Scene) -> list[Path]:
    """DIR/raw.exr and, where a DNG reader takes its bits, DIR/raw.dng (with the camera's own white).

    Parameters
    ----------
    out_dir : Path
    raw : RawCapture
        The capture (DN).
    scene : Scene
        Its scene: the chart reference, and the processing that says whether the camera finds its own white.

    Returns
    -------
    list of Path
        raw.exr, and raw.dng unless the ADC has more bits than a DNG reader takes or the read-out is not
        ``single`` (then a line on stderr says so).
    """
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
    if raw.camera.sensor.readout != "single":
        click.echo(f"raw.dng not written: the {raw.camera.sensor.readout} read-out's merged high-dynamic-range word is "
                   "not an ADC's codes, which a DNG's white level and linearisation describe; it is in raw.exr", err=True)
        return paths
    reference, neutral = ChartReference.of(scene), None
    if not scene.processing.told_the_light and raw.scene is not None:   # AsShotNeutral: the camera's own white
        from spectracam.processing import develop
        from spectracam.evaluation.score import camera_rates

        target = None
        if scene.target.textured:
            from spectracam.scene.reference import TargetReference

            target = TargetReference.of(scene)
        neutral = develop(camera_rates(raw, scene.processing, reference), raw, reference, scene.processing, target).neutral
    return paths + [write_dng(out_dir / "raw.dng", raw, reference, neutral_rates=neutral)]


def write_display(out_dir: Path, raw: RawCapture, scene: Scene) -> list[Path]:
    """rendered.exr and rendered.png of a capture without a chart truth (no score).

    Parameters
    ----------
    out_dir : Path
    raw : RawCapture
    scene : Scene
        Its chart (the conversion is fitted on it) and processing.

    Returns
    -------
    list of Path
        rendered.exr (linear display RGB, with its parameters) and rendered.png (sRGB preview).
    """
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


def score_and_write(raw: RawCapture, scene: Scene, out_dir: Path, log: Callable[[str], object],
                    cube: RadianceCube | None = None) -> None:
    """Score a capture, write its files (a chart's or a textured target's) and log what it scored.

    Parameters
    ----------
    raw : RawCapture
    scene : Scene
    out_dir : Path
    log : callable
        ``log(line)``: the scores and the files written.
    cube : RadianceCube or None
        The render, for the developed camera's own capture (:func:`spectracam.pipeline.both_ways`).
    """
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
