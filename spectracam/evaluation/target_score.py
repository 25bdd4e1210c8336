"""A textured target scored per pixel against its known spectra (training beside held-out).

The conversion (paper 3.5) is fitted on the ColorChecker under the scene's light and the exposure metered
on its white patch, as a camera maker calibrates; the target's colours are not the chart's, so every
pixel is a **held-out** colour (unless the target's library *is* the chart: ``fitted_on_these``).
Against the truth :class:`~spectracam.scene.reference.TargetReference` (each pixel the area-weighted mix of
the samples its footprint shows):

* per pixel: ``ΔE = ΔE(Lab_display(rgb·M_disp), Lab_scene(XYZ_truth))``, exactly the chart's per-pixel
  ΔE (rendered against the display white, the truth against the light's white), over every pixel that
  is not wholly surround; mean, 95th percentile, max;
* S-CIELAB (Zhang & Wandell, :mod:`spectracam.evaluation.scielab`) between the rendered XYZ and the truth
  carried to the display white by the processing's adaptation (with the default XYZ scaling, S-CIELAB
  equals the per-pixel ΔE on uniform areas), at the target's viewing geometry;
* per sample: the mean rendered colour of its interior pixels (at least ``interior_margin_px`` from any
  other sample and from the image border) against its truth (noise averaged out), and the noise-free
  conversion error of the same samples (:func:`spectracam.evaluation.heldout.conversion_errors`).

The *training* block is the conversion's noise-free error on the 24 chart patches it was fitted on.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from spectracam.camera.capture import RawCapture
from spectracam.processing.color import ProcessingSpec, adaptation_matrix, display_rgb_to_xyz
from spectracam.core.errors import SpectracamError
from spectracam.evaluation.heldout import conversion_errors
from spectracam.evaluation.heldout import summary as error_summary
from spectracam.core.cielab import delta_e, xyz_to_lab
from spectracam.scene.reference import ChartReference, TargetReference, library_colours
from spectracam.evaluation.score import check_exposure_matches, check_raw, developed_rgb

if TYPE_CHECKING:
    from spectracam.scene.target import TargetSpec

__all__ = ["CHART_LIBRARIES", "MIN_SAMPLE_PX", "SampleScore", "TargetScore", "score_target"]

#: Fewest interior pixels for a sample's mean colour to be scored.
MIN_SAMPLE_PX = 4
#: The chart datasets each library name measures (a target of these is the training set itself).
CHART_LIBRARIES = {"colorchecker24": "BabelColor Average", "colorchecker24_ohta": "ColorChecker N Ohta"}


@dataclass(frozen=True)
class SampleScore:
    """One sample of the target: its interior pixels' mean colour against its truth."""

    label: int
    name: str
    pixels: int
    scene_lab: tuple
    rendered_lab: tuple
    delta_e_of_mean: float
    delta_e_mean: float
    delta_e_conversion: float


@dataclass(frozen=True, eq=False)
class TargetScore:
    """A textured target's capture scored: the blocks of report.json, the images behind them."""

    parameters: dict
    training: dict
    held_out: dict
    samples: tuple
    capture_time_ms: float
    exposure_ms: tuple
    rendered_rgb: np.ndarray       # (H, W, 3) linear display RGB
    delta_e_map: np.ndarray        # (H, W), NaN on the surround
    scielab_map: np.ndarray        # (H, W), NaN on the surround
    #: The neutral the camera used, the true one and the angular errors (spectracam.processing.develop).
    white_balance: dict | None = None
    #: The oracle camera's and the developed camera's scores side by side (spectracam.pipeline.both_ways).
    both_ways: dict | None = None

    def to_dict(self) -> dict:
        return {"parameters": self.parameters, "training": self.training, "held_out": self.held_out,
                **({"white_balance": self.white_balance} if self.white_balance is not None else {}),
                **({"both_ways": self.both_ways} if self.both_ways is not None else {}),
                "capture": {"capture_time_ms": self.capture_time_ms,
                            **{f"exposure_{k}_ms": t for k, t in zip(self.parameters.get("channels", "RGB"),
                                                                     self.exposure_ms)}},
                "samples": [dataclasses.asdict(s) for s in self.samples]}


def _interior(pixel_labels: np.ndarray, margin: int) -> np.ndarray:
    """Pixels whose (2·margin + 1)² neighbourhood shows one label only, inside the image."""
    from scipy import ndimage

    if margin == 0:
        return pixel_labels >= 0
    size = 2 * margin + 1
    lo = ndimage.minimum_filter(pixel_labels, size=size, mode="constant", cval=-1)
    hi = ndimage.maximum_filter(pixel_labels, size=size, mode="constant", cval=-1)
    return (lo == hi) & (lo >= 0)


def _stats(values: np.ndarray) -> tuple[float, float, float]:
    return float(values.mean()), float(np.percentile(values, 95)), float(values.max())


def score_target(raw: RawCapture, chart: ChartReference, ref: TargetReference, target: TargetSpec, processing: ProcessingSpec
                 ) -> TargetScore:
    """Score a capture of a textured target (module docstring).

    Parameters
    ----------
    raw : RawCapture
        The capture of the target.
    chart : ChartReference
        The ColorChecker under the scene's light: the conversion's training set and the metering white.
    ref : TargetReference
        The target's truth per pixel (the area-weighted mix of the samples each pixel's footprint shows).
    target : TargetSpec
        The target (its library, layout, viewing geometry and interior margin).
    processing : ProcessingSpec
        Demosaicking, conversion, display and ΔE formula.

    Returns
    -------
    TargetScore
        The training, held-out and per-sample blocks, and the rendered RGB, ΔE and S-CIELAB maps.

    Raises
    ------
    SpectracamError
        A capture that cannot be scored against this target (another size, target or scene, or exposure times
        the chart's white patch does not meter).
    """
    _check_target_capture(raw, chart, ref, target)
    M_disp = display_rgb_to_xyz(processing.display)
    rgb, M, wb = developed_rgb(raw, chart, processing, ref)
    maps = _pixel_maps(rgb, ref, target, processing, M_disp)
    samples = _sample_scores(raw, chart, ref, target, processing, M, maps)
    training = _training_block(raw, chart, M, M_disp, processing.delta_e)
    held_out = _held_out_block(chart, ref, target, processing.delta_e, maps, samples, wb)
    parameters = {"scene": raw.scene, "camera": raw.camera.to_dict(), "processing": processing.to_dict(),
                  "seed": raw.seed, "conversion_matrix": M.tolist(), "samples_per_degree": maps.spd,
                  "definitions": __doc__.split("\n\n", 1)[1].strip()}
    if raw.layout.channels != ("R", "G", "B"):   # the exposure times' names (R, G, B when not given)
        parameters["channels"] = list(raw.layout.channels)
    times = tuple(float(1e3 * t) for t in raw.exposure_times_s)
    return TargetScore(parameters, training, held_out, tuple(samples), 1e3 * float(raw.capture_time_s), times,
                       rgb.astype(np.float32), maps.de_map, maps.sc_map, wb)


def _check_target_capture(raw: RawCapture, chart: ChartReference, ref: TargetReference, target) -> None:
    """Refuse a capture that cannot be scored against this target: an impossible capture, another image size, another
    target or scene, or exposure times the chart's white patch does not meter."""
    check_raw(raw)
    h, w = raw.digital.shape[-2:]
    if (h, w) != ref.shape_px:
        raise SpectracamError(f"image = {w}x{h}: the capture does not match the scene ({ref.shape_px[1]}x"
                              f"{ref.shape_px[0]})")
    if raw.scene is not None:
        if raw.scene.get("target") != target.to_dict():
            raise SpectracamError(f"target = {str(raw.scene.get('target'))[:120]}: the capture was taken of another "
                                  "target than the one it is scored against")
        if (table := chart.matches(raw.scene)) is not None:
            raise SpectracamError(f"{table} = {str(raw.scene.get(table))[:120]}: the capture was taken of another "
                                  "scene than the one it is scored against")
    check_exposure_matches(raw, chart)


class _PixelMaps(NamedTuple):
    """The per-pixel scores of a target's rendering and what they were computed from."""

    rendered_xyz: np.ndarray    # (H, W, 3) display XYZ of the rendering
    display_white: np.ndarray
    labels: np.ndarray          # (H, W) the sample each pixel shows most of (ref.surround: the surround)
    scored: np.ndarray          # (H, W) not wholly surround
    de_map: np.ndarray          # (H, W) float32 ΔE, NaN on the surround
    de2000: np.ndarray          # CIEDE2000: the (H, W) map, or the scored pixels' values
    sc_map: np.ndarray          # (H, W) float32 S-CIELAB ΔE, NaN on the surround
    spd: float                  # S-CIELAB samples per degree at the target's viewing geometry


def _pixel_maps(rgb: np.ndarray, ref: TargetReference, target, processing: ProcessingSpec,
                M_disp: np.ndarray) -> _PixelMaps:
    """Per-pixel ΔE (rendered against the display white, truth against the light's white) and S-CIELAB (the truth
    carried to the display white; Zhang & Wandell) of the rendering against the target's truth."""
    from spectracam.evaluation.scielab import samples_per_degree, scielab

    method = processing.delta_e
    display_white = M_disp.sum(axis=1)
    rendered_xyz = rgb.astype(np.float64) @ M_disp.T
    truth_xyz = ref.pixel_mean(ref.xyz)
    labels = ref.pixel_labels()
    scored = labels != ref.surround
    rendered_lab, truth_lab_px = xyz_to_lab(rendered_xyz, display_white), xyz_to_lab(truth_xyz, ref.white_xyz)
    de_map = delta_e(rendered_lab, truth_lab_px, method)
    de2000 = de_map if method == "ciede2000" else delta_e(rendered_lab[scored], truth_lab_px[scored], "ciede2000")
    to_display = adaptation_matrix(ref.white_xyz, display_white, processing.adaptation)
    spd = samples_per_degree(target.viewing_distance_m, target.display_pixel_pitch_mm * 1e-3)
    sc_map = scielab(rendered_xyz, truth_xyz @ to_display.T, display_white, spd, method)
    de_map = np.where(scored, de_map, np.nan).astype(np.float32)
    sc_map = np.where(scored, sc_map, np.nan).astype(np.float32)
    return _PixelMaps(rendered_xyz, display_white, labels, scored, de_map, de2000, sc_map, spd)


def _sample_scores(raw: RawCapture, chart: ChartReference, ref: TargetReference, target, processing: ProcessingSpec,
                   M: np.ndarray, maps: _PixelMaps) -> list:
    """Per sample with at least :data:`MIN_SAMPLE_PX` interior pixels: their mean colour against its truth, their mean
    per-pixel ΔE and the sample's noise-free conversion error."""
    method = processing.delta_e
    n = ref.surround
    inside = _interior(maps.labels, target.interior_margin_px) & maps.scored
    lab_in = maps.labels[inside]
    counts = np.bincount(lab_in, minlength=n + 1)
    sums = np.stack([np.bincount(lab_in, maps.rendered_xyz[inside][:, k], minlength=n + 1) for k in range(3)], axis=-1)
    de_sums = np.bincount(lab_in, maps.de_map[inside].astype(np.float64), minlength=n + 1)
    chosen = np.flatnonzero(counts[:n] >= MIN_SAMPLE_PX)
    colours = library_colours(ref.library, chart.illuminant, chart.grid)
    conv = conversion_errors(colours, raw.camera, chart.grid, M, processing)
    samples = []
    if chosen.size:
        mean_lab = xyz_to_lab(sums[chosen] / counts[chosen, None], maps.display_white)
        truth_lab = xyz_to_lab(ref.xyz[chosen], ref.white_xyz)
        of_mean = np.atleast_1d(delta_e(mean_lab, truth_lab, method))
        for i, lab_m, lab_t, d in zip(chosen, mean_lab, truth_lab, of_mean):
            samples.append(SampleScore(int(i), ref.names[i], int(counts[i]), tuple(lab_t.round(4).tolist()),
                                       tuple(lab_m.round(4).tolist()), float(d), float(de_sums[i] / counts[i]),
                                       float(conv[i])))
    return samples


def _training_block(raw: RawCapture, chart: ChartReference, M: np.ndarray, M_disp: np.ndarray, method: str) -> dict:
    """The training error: the conversion on the 24 patches it was fitted on (noise-free)."""
    display_white = M_disp.sum(axis=1)
    chart_lab = xyz_to_lab(chart.patch_xyz, chart.white_xyz)
    chart_conv = delta_e(xyz_to_lab(chart.patch_rates(raw.camera) @ M @ M_disp.T, display_white), chart_lab, method)
    return error_summary(np.asarray(chart_conv), "the chart (training: the conversion is fitted on it)")


def _held_out_block(chart: ChartReference, ref: TargetReference, target, method: str, maps: _PixelMaps, samples: list,
                    wb: dict) -> dict:
    """The held-out block: the per-pixel ΔE and S-CIELAB statistics over the scored pixels, and the samples'."""
    shown = np.unique(ref.labels)
    shown = shown[shown != ref.surround]
    scored, de2000 = maps.scored, maps.de2000
    de_px, sc_px = maps.de_map[scored], maps.sc_map[scored]
    if de_px.size == 0:
        raise SpectracamError("target: every pixel is the surround; there is nothing to score")
    held_out = {"library": ref.library, "kind": target.kind, "unit": "pixel", "pixels": int(de_px.size),
                "samples": int(shown.size),
                "fitted_on_these": CHART_LIBRARIES.get(ref.library) == chart.chart.dataset,
                **dict(zip(("delta_e_mean", "delta_e_p95", "delta_e_max"), _stats(de_px))),
                **dict(zip(("s_cielab_mean", "s_cielab_p95", "s_cielab_max"), _stats(sc_px))),
                "delta_e2000_mean": float(np.nanmean(de2000[scored] if method == "ciede2000" else de2000)),
                "awb_recovery_deg": wb["recovery_deg"], "awb_reproduction_deg": wb["reproduction_deg"],
                "samples_scored": len(samples)}
    for field in ("delta_e_of_mean", "delta_e_conversion"):
        if samples:
            mean, p95, _ = _stats(np.array([getattr(s, field) for s in samples]))
            held_out.update({f"sample_{field}_mean": mean, f"sample_{field}_p95": p95})
    return held_out
