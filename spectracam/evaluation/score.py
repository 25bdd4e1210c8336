"""From a raw capture to a displayed image and its score (paper, sections 3.5, 3.6 and 5).

Digital numbers become electrons (:func:`~spectracam.sensor.adc_inverse`), the expected dark charge
is subtracted (a dark-frame calibration; the fixed pattern stays), a mosaic is demosaicked, each
channel is divided by its exposure time, and the 3×3 matrix fitted on the chart reference maps the
result to linear display RGB.  Everything here dispatches on the capture's layout.
"""
from __future__ import annotations

import dataclasses
import sys
from dataclasses import dataclass
from functools import lru_cache
from collections.abc import Sequence
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from spectracam.architecture.base import MosaicLayout
from spectracam.camera.capture import RawCapture
from spectracam.scene.chart import WHITE_PATCH
from spectracam.processing.color import ProcessingSpec, demosaic, display_rgb_to_xyz
from spectracam.core.errors import SpectracamError
from spectracam.core.cielab import SNR_COMBINATIONS, combine_snr_db, delta_e, snr_db, xyz_to_lab
from spectracam.processing import develop, oracle_block
from spectracam.processing.calibration import conversion_matrix, conversion_target_rgb  # noqa: F401  (the paper's 3.5)
from spectracam.scene.reference import ChartReference
from spectracam.sensor import adc_full_scale_dn, adc_inverse

if TYPE_CHECKING:
    from spectracam.scene.reference import TargetReference

__all__ = ["DELTA_E_REFERENCES", "EXPOSURE_MATCH_TOLERANCE", "LAB_CHUNK_PIXELS", "SCIELAB_CHUNK_PIXELS",
           "SUMMARY_METRICS", "ChartScore", "ChartSummary", "PatchScore", "camera_rates", "channel_stats",
           "chart_scielab_map", "chart_truth_xyz", "check_exposure_matches", "check_raw", "developed_rgb",
           "display_rgb", "recorded_electrons", "score", "score_region"]

#: What a per-pixel ΔE is measured against: the scene (the default), or the noise-free rendering of
#: the same camera (the conversion error removed; how the paper's Figure 6 isolates the noise steps).
DELTA_E_REFERENCES = ("scene", "camera")


def _finite(x) -> float | None:
    return float(x) if np.isfinite(x) else None


def _mean_or_none(values) -> float | None:
    return None if any(v is None for v in values) else float(np.mean(values))


@dataclass(frozen=True)
class PatchScore:
    """One patch: scene and rendered CIELAB, ΔE (per-pixel mean, of the mean colour, of the
    conversion alone) and SNR per channel and combined.  An SNR is ``None`` when it has no finite
    value: noise-free (σ = 0: infinite), or undefined — the channel's mean dark-subtracted signal is
    ≤ 0 under noise, so 20·log10(μ/σ) has no value; ``snr_undefined`` names those channels, so the
    two cases never read alike."""

    patch: int
    name: str
    scene_lab: tuple
    rendered_lab: tuple
    delta_e_mean: float
    delta_e_of_mean: float
    delta_e_conversion: float
    snr_R_db: float | None
    snr_G_db: float | None
    snr_B_db: float | None
    snr_combined_db: float | None
    pixels: int
    snr_undefined: tuple = ()
    #: Every recorded channel's SNR by name (R, G, B; R, Y, B; C, Y, M; R, G, B, W; …): the R/G/B
    #: fields above are ``None`` for a channel the architecture does not record.
    snr_by_channel_db: dict = dataclasses.field(default_factory=dict)
    #: 20·log10(Y/σ_Y) of the rendered luminance: the channels' measured means and noise carried
    #: through the exposure normalisation and the colour conversion to display luminance, the channels
    #: independent (so the conversion's noise amplification counts and no demosaicker's smoothing
    #: does; docs/metrics.md).
    snr_rendered_db: float | None = None
    #: The mean per-pixel S-CIELAB ΔE over the patch's scored pixels (:func:`chart_scielab_map`).
    s_cielab_mean: float | None = None


@dataclass(frozen=True)
class ChartSummary:
    """Chart averages and the capture's timing: exactly what sweeps record and the paper reads."""

    delta_e_mean: float
    delta_e_of_mean: float
    delta_e_conversion: float
    snr_combined_db: float | None
    snr_R_db: float | None
    snr_G_db: float | None
    snr_B_db: float | None
    capture_time_ms: float
    #: The channel's exposure time (``None`` when the architecture records no such channel).
    exposure_R_ms: float | None
    exposure_G_ms: float | None
    exposure_B_ms: float | None
    #: How many patch-channel SNRs are undefined (mean signal ≤ 0 under noise); a channel's chart SNR
    #: above is ``None`` then, and ``None`` with a count of 0 means noise-free.
    snr_undefined_patches: int = 0
    #: The patches' mean rendered-luminance SNR (:attr:`PatchScore.snr_rendered_db`).
    snr_rendered_db: float | None = None
    #: 95th percentile of the per-pixel ΔE (processing.delta_e) over every patch's pixels.
    delta_e_p95: float | None = None
    #: The chart average of each patch's mean per-pixel CIEDE2000 (beside ΔE*ab whatever processing.delta_e is).
    delta_e2000_mean: float | None = None
    #: The white balance's recovery and reproduction angular errors, degrees (0 for the oracle;
    #: spectracam.processing.white_balance).
    awb_recovery_deg: float | None = None
    awb_reproduction_deg: float | None = None
    #: S-CIELAB (Zhang & Wandell; :func:`chart_scielab_map`): the rendered image and the scene's truth image through
    #: the eye's filters at processing.viewing_distance_m and display_pixel_pitch_mm, then ΔE (processing.delta_e) per
    #: pixel on the same pixels as delta_e_mean: the chart average of each patch's mean, and the 95th percentile over
    #: every patch's pixels.  Always against the scene.
    s_cielab_mean: float | None = None
    s_cielab_p95: float | None = None
    #: The white patch's rendered luminance SNR (:attr:`PatchScore.snr_rendered_db` of chart.WHITE_PATCH): what the
    #: usability rule reads (spectracam.evaluation.usability); ``None``: noise-free or undefined.
    snr_white_rendered_db: float | None = None


#: The metrics a sweep can record: every field of :class:`ChartSummary`.
SUMMARY_METRICS = tuple(f.name for f in dataclasses.fields(ChartSummary))


@dataclass(frozen=True, eq=False)
class ChartScore:
    """A capture scored against its scene: typed results, the displayed image and the ΔE map."""

    summary: ChartSummary
    patches: tuple[PatchScore, ...]
    parameters: dict  # scene, camera, processing, seed, definitions, conversion matrix
    rendered_rgb: np.ndarray  # (H, W, 3) linear display RGB
    delta_e_map: np.ndarray  # (H, W), NaN outside the patches' masks
    #: The conversion's noise-free error on the 24 patches it was fitted on (spectracam.evaluation.heldout.summary).
    training: dict | None = None
    #: The same on colours it was not fitted on (processing.held_out), or None.
    held_out: dict | None = None
    #: The neutral the camera used, the true one and the angular errors (spectracam.processing.develop).
    white_balance: dict | None = None
    #: The oracle camera's and the developed camera's scores side by side (spectracam.pipeline.both_ways).
    both_ways: dict | None = None

    def to_dict(self) -> dict:
        """The strict-JSON report (report.json)."""
        out = {"parameters": self.parameters, "patches": [dataclasses.asdict(p) for p in self.patches],
               "chart": dataclasses.asdict(self.summary)}
        if self.white_balance is not None:
            out["white_balance"] = self.white_balance
        if self.both_ways is not None:
            out["both_ways"] = self.both_ways
        if self.training is not None:
            out["training"] = self.training
        if self.held_out is not None:
            out["held_out"] = self.held_out
        return out


def recorded_electrons(raw: RawCapture) -> tuple[np.ndarray, np.ndarray]:
    """Dark-subtracted electrons in the capture's layout, and the dark charge subtracted per channel.

    Parameters
    ----------
    raw : RawCapture
        The capture (its digital numbers, sensor and exposure times).

    Returns
    -------
    electrons : ndarray
        Photo-electrons (ADC inverted, dark charge subtracted), e⁻: ``(H, W)`` for a mosaic, ``(N, H, W)`` for
        planes.
    dark : ndarray
        ``(N,)`` the dark charge subtracted per channel, e⁻ (dark rate × exposure time).
    """
    s = raw.camera.sensor
    e = adc_inverse(raw.digital, s)
    dark = s.dark_rate_e_per_s * np.asarray(raw.exposure_times_s)
    if isinstance(raw.layout, MosaicLayout):
        return e - dark[0], dark
    return e - dark[:, None, None], dark


def camera_rates(raw: RawCapture, processing: ProcessingSpec, reference: ChartReference | None = None) -> np.ndarray:
    """``(H, W, N)`` photo-electrons per second per channel: lens shading corrected (``processing.shading``, on the
    raw channels before demosaicking, with tables calibrated for the camera on ``reference``'s wavelengths and picked
    by its light's colour temperature: :func:`spectracam.processing.shading.shading_gain_maps`), demosaicked and
    exposure-normalised.

    Parameters
    ----------
    raw : RawCapture
        The capture.
    processing : ProcessingSpec
        The colour processing (demosaicking, conversion, display, ΔE formula).
    reference : ChartReference, optional
        The chart the shading tables are calibrated on (needed when ``processing.shading`` is not ``"none"``).

    Returns
    -------
    ndarray
        ``(H, W, N)`` float, e⁻/s.
    """
    e, _ = recorded_electrons(raw)
    if processing.shading != "none":
        from spectracam.processing.calibration import light_cct_K
        from spectracam.processing.shading import correct_shading, shading_gain_maps

        if reference is None:
            raise SpectracamError(f"processing.shading = {processing.shading!r}: the correction needs the scene's "
                                  "chart reference (its wavelengths and light); pass reference=")
        gains = shading_gain_maps(raw.camera, reference.grid, e.shape[-2:], processing,
                                  light_cct_K(reference.illuminant) if processing.shading == "cct" else None)
        e = correct_shading(e, raw.layout, gains)
    times = np.asarray(raw.exposure_times_s, float)
    if isinstance(raw.layout, MosaicLayout):   # divided as the compiled bilinear pass writes (no second pass)
        return demosaic(e, raw.layout, processing.demosaic, divisor=times)
    rgb = np.moveaxis(e, 0, -1)
    rgb /= times[None, None, :]  # in place: a 12-Mpx image holds 290 MB
    return rgb


def channel_stats(raw: RawCapture, boxes: Sequence[tuple[slice, slice]]) -> tuple[np.ndarray, np.ndarray]:
    """Mean and std ``(24, N)`` of the recorded (dark-subtracted) electrons of each channel's own
    pixels in each box (for a mosaic: every site of the channel in the tile, both greens of a Bayer).
    The electrons of each box only (:func:`recorded_electrons`' values there): no full-size image is made.

    Parameters
    ----------
    raw : RawCapture
        The capture.
    boxes : sequence of (slice, slice)
        ``(rows, cols)`` of each patch's scoring box, pixels.

    Returns
    -------
    means, stds : ndarray
        ``(n_boxes, N)`` mean and standard deviation, e⁻ (a std of 0 where every pixel holds one code).
    """
    s = raw.camera.sensor
    dark = s.dark_rate_e_per_s * np.asarray(raw.exposure_times_s)
    n = len(raw.layout.channels)
    means, stds = np.zeros((len(boxes), n)), np.zeros((len(boxes), n))
    if isinstance(raw.layout, MosaicLayout):
        th, tw = raw.layout.tile_shape
        sites = raw.layout.sites()
        for group in _alike_boxes(boxes, th, tw).values():   # boxes of one size and tile phase, reduced together
            e = np.stack([adc_inverse(raw.digital[boxes[p]], s) for p in group]) - dark[0]
            r, c = boxes[group[0]]
            for k in range(n):
                parts = [e[:, (dy - r.start) % th::th, (dx - c.start) % tw::tw] for dy, dx, kk in sites if kk == k]
                pix = np.concatenate([a.reshape(len(group), a.shape[1] * a.shape[2]) for a in parts], axis=1)
                means[group, k], stds[group, k] = pix.mean(axis=1), pix.std(axis=1)
                # one code everywhere (a coarse ADC): no noise, not rounding's 1e-13
                stds[np.asarray(group)[pix.max(axis=1) == pix.min(axis=1)], k] = 0.0
        return means, stds
    for p, (r, c) in enumerate(boxes):
        block = (adc_inverse(raw.digital[:, r, c], s) - dark[:, None, None]).reshape(n, -1)
        means[p], stds[p] = block.mean(axis=1), block.std(axis=1)
        stds[p][block.max(axis=1) == block.min(axis=1)] = 0.0
    return means, stds


def _alike_boxes(boxes: Sequence[tuple[slice, slice]], th: int, tw: int) -> dict:
    """Box indices grouped by ``(rows, cols, row phase, column phase)`` in the mosaic's ``th × tw`` tile: each
    group's pixels of one channel stack into one ``(boxes, pixels)`` array, in the order each box alone gives them,
    so a row's mean and std are the box's own (one NumPy reduction per group, not per box: 0.8 s of a quick paper
    run's 270 scores in per-box calls)."""
    groups: dict = {}
    for p, (r, c) in enumerate(boxes):
        key = (r.stop - r.start, c.stop - c.start, r.start % th, c.start % tw)
        groups.setdefault(key, []).append(p)
    return groups


def check_raw(raw: RawCapture) -> None:
    """Refuse a capture that no sensor could have recorded: digital numbers that are not finite or lie
    outside the ADC's codes, a layout that does not match the array, exposure times that are not > 0.

    Parameters
    ----------
    raw : RawCapture
        The capture.

    Raises
    ------
    SpectracamError
        One line naming what is impossible.
    """
    s = raw.camera.sensor
    d = raw.digital
    want, n = (2 if isinstance(raw.layout, MosaicLayout) else 3), len(raw.layout.channels)
    if d.ndim != want or (want == 3 and d.shape[0] != n):
        raise SpectracamError(f"capture: a {type(raw.layout).__name__} holds "
                              f"{'(H, W)' if want == 2 else f'({n}, H, W)'} digital numbers; got {d.shape}")
    top = adc_full_scale_dn(s)
    bad = ~np.isfinite(d) | (d < 0) | (d > top)
    if bad.any():
        raise SpectracamError(f"capture: {int(bad.sum())} digital numbers are not finite or outside the "
                              f"{s.adc_bits}-bit ADC's 0…{top:g} (e.g. {d[bad].flat[0]!r})")
    t = np.asarray(raw.exposure_times_s, float)
    if t.shape != (n,) or not np.all(np.isfinite(t)) or np.any(t <= 0):
        raise SpectracamError(f"capture: exposure times must be {n} finite times > 0 s, one per channel "
                              f"{', '.join(raw.layout.channels)}; got {t.tolist()}")


def display_rgb(raw: RawCapture, reference: ChartReference, processing: ProcessingSpec) -> tuple[np.ndarray, np.ndarray]:
    """``(rendered (H, W, 3) linear display RGB, conversion matrix)`` (:func:`developed_rgb` without its white-balance
    block).

    Parameters
    ----------
    raw : RawCapture
        The capture.
    reference : ChartReference
        The chart the conversion is fitted on.
    processing : ProcessingSpec
        The colour processing (demosaicking, conversion, display, ΔE formula).

    Returns
    -------
    rgb : ndarray
        ``(H, W, 3)`` linear display RGB, white = 1.
    matrix : ndarray
        ``(N, 3)`` the conversion applied to the rates.
    """
    rgb, M, _ = developed_rgb(raw, reference, processing)
    return rgb, M


def developed_rgb(raw: RawCapture, reference: ChartReference, processing: ProcessingSpec,
                  target_reference: TargetReference | None = None) -> tuple[np.ndarray, np.ndarray, dict]:
    """``(rendered (H, W, 3) linear display RGB, conversion matrix, white-balance block)``: demosaicked,
    exposure-normalised rates through the conversion — for the paper's camera (``processing.told_the_light``) the one
    fitted on ``reference`` under its own light (which need not be the captured scene: a spectral image from another
    tool is shown through the chart's conversion); for a camera that finds its own white, the matrix it develops from
    this image (:func:`spectracam.processing.develop`).

    Parameters
    ----------
    raw : RawCapture
        The capture.
    reference : ChartReference
        The chart the conversion is fitted on (or the camera calibrated on).
    processing : ProcessingSpec
        The colour processing (demosaicking, conversion, display, ΔE formula).
    target_reference : TargetReference, optional
        A textured target's truth, for the white-balance block's true neutral.

    Returns
    -------
    rgb : ndarray
        ``(H, W, 3)`` linear display RGB, white = 1 (clipped to 0–1 with ``processing.gamut_clip``).
    matrix : ndarray
        ``(N, 3)`` the conversion applied to the rates (e⁻/s → display RGB).
    white_balance : dict
        The neutral used, the true one and their angular errors.
    """
    rgb = camera_rates(raw, processing, reference)
    if processing.told_the_light:
        M = conversion_matrix(reference, raw.camera, processing)
        block = oracle_block(reference, raw.camera, processing)
    else:
        dev = develop(rgb, raw, reference, processing, target_reference)
        M, block = dev.matrix, dev.white_balance
    if rgb.shape[-1] == 3:   # in place, a band of rows at a time: no second full-size image
        for i in range(0, rgb.shape[0], 256):
            rgb[i:i + 256] = rgb[i:i + 256] @ M
    else:                    # N ≠ 3 channels: into a new (H, W, 3) image, band by band
        rgb = np.concatenate([rgb[i:i + 256] @ M for i in range(0, rgb.shape[0], 256)])
    if processing.gamut_clip:
        np.clip(rgb, 0.0, 1.0, out=rgb)
    return rgb, M, block


#: How far a chart capture's exposure times may lie from those its scene's white patch meters (the
#: render's patch means match the reference to 1e-6 since issue 17; older Mitsuba renders to 0.1 %).
EXPOSURE_MATCH_TOLERANCE = 0.01


def check_exposure_matches(raw: RawCapture, reference: ChartReference) -> None:
    """A capture metered on its chart's white patch must have the exposure times that patch gives for
    its camera: a recorded scene edited to another light or level, or a capture of other pixels, is
    refused instead of being scored against the wrong truth.

    Parameters
    ----------
    raw : RawCapture
        The capture.
    reference : ChartReference
        The chart whose white patch meters the exposure.

    Raises
    ------
    SpectracamError
        Exposure times other than those the white patch gives.
    """
    from spectracam.scene.chart import WHITE_PATCH
    from spectracam.sensor.exposure import exposure_times_s

    if raw.scene is None or raw.metering is not None:
        return
    cam = raw.camera
    if not cam.optics.on_axis or cam.pixel.any_on:
        return   # metered where the white patch lies in the field (issue 37); the reference is the field's centre
    try:
        want = exposure_times_s(cam.capture.exposure, reference.patch_rates(cam)[WHITE_PATCH], cam.sensor,
                                cam.architecture(), cam.capture.white_fill, cam.capture.exposure_split)
    except SpectracamError:
        return  # the scene's light cannot be metered at all: other checks speak
    got = np.asarray(raw.exposure_times_s, float)
    worst = float(np.max(np.abs(got / want - 1)))
    if worst > EXPOSURE_MATCH_TOLERANCE:
        raise SpectracamError(f"capture: its exposure times ({', '.join(f'{1e3 * t:.4g}' for t in got)} ms) are not "
                              f"those its recorded scene's white patch meters ({', '.join(f'{1e3 * t:.4g}' for t in want)}"
                              f" ms under {reference.illuminant.label}, {reference.illuminant.white_luminance_cd_m2:g} "
                              "cd/m²); the scene or the capture was edited, or another scene was captured")


#: Pixels whose CIELAB is computed in one call: few calls (each has a fixed cost) without a
#: full-image Lab (a 12-Mpx chart's masks in one call held 0.25 cubes more than the image).
LAB_CHUNK_PIXELS = 1 << 20


def _box_labs(rgb: np.ndarray, boxes, M_disp: np.ndarray, display_white: np.ndarray):
    """CIELAB ``(h, w, 3)`` of each box's pixels in turn, computed for runs of boxes of at most
    :data:`LAB_CHUNK_PIXELS` pixels (or one box) at a time."""
    i = 0
    while i < len(boxes):
        j, n = i, 0
        while j < len(boxes) and (j == i or n + _pixels(boxes[j]) <= LAB_CHUNK_PIXELS):
            n += _pixels(boxes[j])
            j += 1
        lab = xyz_to_lab(np.concatenate([rgb[r, c].reshape(-1, 3) for r, c in boxes[i:j]]) @ M_disp.T, display_white)
        start = 0
        for r, c in boxes[i:j]:
            yield lab[start:start + _pixels((r, c))].reshape(r.stop - r.start, c.stop - c.start, 3)
            start += _pixels((r, c))
        i = j


#: Pixels whose CIEDE2000 is computed in one call: colour-science's formula has a fixed cost per call (6480 calls,
#: one per patch and case, were 5.9 s of a 24 s ``paper --quick``) and about 30 full-size temporaries per call.
DELTA_E_2000_CHUNK_PIXELS = 1 << 18


def _box_delta_es(rgb: np.ndarray, boxes, M_disp: np.ndarray, display_white: np.ndarray, against: np.ndarray,
                  method: str, de_map: np.ndarray):
    """``[(mean ΔE of the method, mean CIEDE2000)]`` of each box against ``against[p]``, writing each pixel's ΔE of
    the method into ``de_map``: in one compiled pass over the boxes (:func:`_box_delta_es_fused`) or, without the
    kernels, with colour-science's formulas on runs of boxes (:func:`_box_delta_es_arrays`)."""
    from spectracam.core.cielab import DELTA_E_CODES, _kernels

    mod = _kernels() if method in DELTA_E_CODES else None
    if mod is not None and rgb.dtype in (np.float32, np.float64) and rgb.ndim == 3 and de_map.dtype == np.float32:
        return _box_delta_es_fused(mod, rgb, boxes, M_disp, display_white, against, method, de_map)
    out = []
    for (r, c), (de, de_2000) in zip(boxes, _box_delta_es_arrays(rgb, boxes, M_disp, display_white, against,
                                                                    method)):
        de_map[r, c] = de
        out.append((float(de.mean()), de_2000))
    return out


def _box_delta_es_fused(mod, rgb, boxes, M_disp, display_white, against, method, de_map):
    """:func:`_box_delta_es` by the compiled kernel (``core/_numba_colour.py: box_kernel``): the display RGB → XYZ
    → CIELAB → ΔE of every box's pixels in one pass, boxes shared out among the threads, sums in float64."""
    from spectracam.core.cielab import DELTA_E_CODES, lab_white
    from spectracam.core.parallel import run_bands

    spans = np.array([[r.start, r.stop, c.start, c.stop] for r, c in boxes], np.int64).reshape(-1, 4)
    m = np.ascontiguousarray(np.asarray(M_disp, float) / float(np.asarray(display_white, float)[1]))
    ref = np.ascontiguousarray(np.asarray(against, float).reshape(-1, 3))
    sums = np.zeros((len(spans), 2))
    code = np.int64(DELTA_E_CODES[method])
    wn = lab_white(display_white)
    run_bands(mod.box_kernel, len(spans), lambda a, b: (np.int64(a), np.int64(b), rgb, spans, m, wn, ref, code,
                                                        de_map, sums))
    n = (spans[:, 1] - spans[:, 0]) * (spans[:, 3] - spans[:, 2])
    return [(float(s0 / k), float(s1 / k)) if k > 0 else (float("nan"), float("nan")) for (s0, s1), k in zip(sums, n)]


def _box_delta_es_arrays(rgb: np.ndarray, boxes, M_disp: np.ndarray, display_white: np.ndarray, against: np.ndarray,
                         method: str):
    """Per box in turn: ``(per-pixel ΔE of the method (h, w), mean CIEDE2000 over the box)`` against ``against[p]``,
    the ΔE of boxes computed together in runs of at most :data:`DELTA_E_2000_CHUNK_PIXELS` pixels (or one box)."""
    pending: list = []

    def flush():
        labs = np.concatenate([lab.reshape(-1, 3) for _, lab in pending])
        refs = np.repeat(np.stack([against[p] for p, _ in pending]), [lab.shape[0] * lab.shape[1]
                                                                      for _, lab in pending], axis=0)
        de_all = delta_e(labs, refs, method)
        de2000_all = de_all if method == "ciede2000" else delta_e(labs, refs, "ciede2000")
        out, start = [], 0
        for _, lab in pending:
            n = lab.shape[0] * lab.shape[1]
            out.append((de_all[start:start + n].reshape(lab.shape[:2]), float(np.mean(de2000_all[start:start + n]))))
            start += n
        pending.clear()
        return out

    size = 0
    for p, lab_box in enumerate(_box_labs(rgb, boxes, M_disp, display_white)):
        n = lab_box.shape[0] * lab_box.shape[1]
        if pending and size + n > DELTA_E_2000_CHUNK_PIXELS:
            yield from flush()
            size = 0
        pending.append((p, lab_box))
        size += n
    if pending:
        yield from flush()


def _pixels(box) -> int:
    r, c = box
    return (r.stop - r.start) * (c.stop - c.start)


def chart_truth_xyz(reference: ChartReference, rows: slice, cols: slice) -> np.ndarray:
    """``(h, w, 3)`` CIE 1931 XYZ of the scene's pixels ``[rows, cols]`` under its light (the light's white has Y = 1):
    each patch's reference colour (``reference.patch_xyz``) over the part of the pixel it covers
    (:func:`spectracam.scene.chart.patch_coverage`, what a box-filtered render converges to), the surround's
    (``chart.surround_reflectance`` × the white) over the rest.

    Parameters
    ----------
    reference : ChartReference
        The chart under its light.
    rows, cols : slice
        The pixels, in the image.

    Returns
    -------
    ndarray
        ``(h, w, 3)`` XYZ.
    """
    from spectracam.scene.chart import View, patch_coverage

    cy, cx = patch_coverage(reference.chart, View.fit(reference.chart, reference.width_px, reference.height_px))
    surround = reference.chart.surround_reflectance * np.asarray(reference.white_xyz, float)
    step = np.asarray(reference.patch_xyz, float) - surround                     # (24, 3)
    cy, cx = cy[:, rows], cx[:, cols]
    # (h, w·3): Σ_p cy·cx·(XYZ_p − XYZ_s)
    mix = cy.T @ (cx[:, :, None] * step[:, None, :]).reshape(len(step), -1)
    return surround + mix.reshape(cy.shape[1], cx.shape[1], 3)


#: Pixels of the chart's S-CIELAB filtered at once: a band of rows (with the kernel's reach above and below) at a
#: time, so a 12-Mpx chart never holds a full-size opponent image; a 640×480 chart is one band.  2¹⁹ (was 2²⁰): the
#: band's float64 temporaries were a 12-Mpx score's peak (0.16 of the cube above what the score holds, against 0.11
#: then; issue 38's 1.5 × the cube).  A band's output rows are this over the box's width and the reach either side;
#: its input adds the reach above and below (no second margin since issue 38's fifth session, which had added as
#: much again).
SCIELAB_CHUNK_PIXELS = 1 << 19


def _scored_mask(reference: ChartReference) -> np.ndarray:
    mask = np.zeros((reference.height_px, reference.width_px), bool)
    for r, c in reference.boxes:
        mask[r, c] = True
    return mask


class _ScielabBands(NamedTuple):
    """Where the chart's S-CIELAB is computed: the scored pixels' bounding box (``rows``, ``cols``), its bands of
    rows, and the image's rows and columns each band's filters read (its own, then ``reach`` either side: its
    neighbours' pixels inside the image, reflected beyond its edges as ``numpy.pad(mode="symmetric")``)."""

    rows: slice
    cols: slice
    bands: list
    rows_in: list
    cols_in: np.ndarray


def _scielab_bands(reference: ChartReference, spd: float) -> _ScielabBands:
    """The scored pixels' bounding box cut into bands of at most :data:`SCIELAB_CHUNK_PIXELS` extended pixels:
    filtering a band's extended input gives its rows exactly as filtering the whole image would (to the FFT's
    rounding)."""
    from spectracam.evaluation.scielab import reflected_indices, scielab_reach

    reach = scielab_reach(spd)
    boxes = [(r, c) for r, c in reference.boxes if r.stop > r.start and c.stop > c.start]
    r0, r1 = min(r.start for r, _ in boxes), max(r.stop for r, _ in boxes)
    c0, c1 = min(c.start for _, c in boxes), max(c.stop for _, c in boxes)
    band = max(1, SCIELAB_CHUNK_PIXELS // (c1 - c0 + 2 * reach))
    bands = [slice(lo, min(lo + band, r1)) for lo in range(r0, r1, band)]
    rows_in = [reflected_indices(b.start - reach, b.stop + reach, reference.height_px) for b in bands]
    return _ScielabBands(slice(r0, r1), slice(c0, c1), bands, rows_in,
                         reflected_indices(c0 - reach, c1 + reach, reference.width_px))


class _Fused(NamedTuple):
    """The compiled colour kernels (``core/_numba_colour.py``) and what the chart's S-CIELAB passes them: the filtered
    opponent values to CIELAB (``to_lab``, scaled by the white's Y) and the white as the kernels take it."""

    mod: object
    to_lab: np.ndarray
    white: np.ndarray


def _fused(white: np.ndarray, method: str | None = None) -> _Fused | None:
    """The kernels for the chart's S-CIELAB against the display ``white``, or None: no numba (or
    ``SPECTRACAM_FUSED=0``), or a ΔE formula ``method`` the kernels do not compute (NumPy and colour-science then)."""
    from spectracam.core.cielab import DELTA_E_CODES, _kernels, lab_white
    from spectracam.evaluation.scielab import OPPONENT_TO_XYZ

    mod = _kernels() if method is None or method in DELTA_E_CODES else None
    if mod is None:
        return None
    return _Fused(mod, np.ascontiguousarray(OPPONENT_TO_XYZ / float(white[1])), lab_white(white))


def _band_opponent(img: np.ndarray, rows_in: np.ndarray, cols_in: np.ndarray, to_opponent: np.ndarray,
                   fused: _Fused | None) -> np.ndarray:
    """``(len(rows_in), len(cols_in), 3)`` float64: ``to_opponent @`` the image's pixels at the extended band's
    rows and columns, in one compiled pass where the kernels run."""
    from spectracam.core.parallel import run_bands

    if fused is None or img.dtype not in (np.float32, np.float64):
        return img[rows_in[:, None], cols_in] @ to_opponent.T
    out = np.empty((len(rows_in), len(cols_in), 3))
    m = np.ascontiguousarray(to_opponent, float)
    run_bands(fused.mod.gather_kernel, len(rows_in),
              lambda a, b: (np.int64(a), np.int64(b), img, rows_in, cols_in, m, out))
    return out


def _kept_offsets(keep: np.ndarray, start: int) -> np.ndarray:
    """``(rows + 1,)`` int64: the row-major rank of each row's first kept pixel, from ``start``."""
    return start + np.concatenate([[0], np.cumsum(keep.sum(axis=1))]).astype(np.int64)


def _kept_lab(f: np.ndarray, keep: np.ndarray, white: np.ndarray, fused: _Fused | None, out: np.ndarray,
              start: int) -> int:
    """Writes into ``out[start:]`` the CIELAB (against ``white``) of the filtered opponent values ``f`` ``(h, w, 3)``
    at its ``keep`` pixels, in row-major order; returns the index after the last."""
    from spectracam.core.parallel import run_bands
    from spectracam.evaluation.scielab import OPPONENT_TO_XYZ

    if fused is None:
        lab = xyz_to_lab(f[keep] @ OPPONENT_TO_XYZ.T, white)
        out[start:start + len(lab)] = lab
        return start + len(lab)
    keep = np.ascontiguousarray(keep)
    offsets = _kept_offsets(keep, start)
    run_bands(fused.mod.masked_lab_kernel, len(keep), lambda a, b: (np.int64(a), np.int64(b), f, keep, offsets,
                                                                    fused.to_lab, fused.white, out))
    return int(offsets[-1])


def _truth_factors(reference: ChartReference, rows: slice, cols: slice, to_opponent: np.ndarray,
                   spd: float) -> tuple[np.ndarray, list]:
    """The scene's truth (:func:`chart_truth_xyz`) through ``to_opponent`` and the S-CIELAB filters at the pixels
    ``[rows, cols]``, by separation (issue 38; no FFT, no opponent image): ``(base (3,), [(down, across)] per
    channel)`` with the filtered channel ``c`` = ``base[c] + down_c[:, y].T @ across_c``.

    The truth is the surround's colour plus, for each patch ``p``, its step from the surround times the product of
    its row and column coverages, ``cy_p(y)·cx_p(x)``; each kernel is ``Σ_i w_i g_i g_iᵀ`` summing to 1
    (:func:`spectracam.evaluation.scielab.scielab_components`) and the image's reflection about its edges is the
    reflection of each coverage about its ends.  So a channel's filtered truth is its surround value plus
    ``Σ_i w_i Σ_p step_p (g_i ⋆ cy_p)(y) (g_i ⋆ cx_p)(x)``: 1-D filters of the 24 coverages and one matrix product
    per channel; the same numbers as filtering the truth image (to the rounding of float64)."""
    from numpy.lib.stride_tricks import sliding_window_view

    from spectracam.evaluation.scielab import reflected_indices, scielab_components, scielab_reach
    from spectracam.scene.chart import View, patch_coverage

    cy, cx = patch_coverage(reference.chart, View.fit(reference.chart, reference.width_px, reference.height_px))
    r = scielab_reach(spd)
    surround = reference.chart.surround_reflectance * np.asarray(reference.white_xyz, float)
    step = (np.asarray(reference.patch_xyz, float) - surround) @ to_opponent.T        # (24, 3) opponent steps
    ywin = sliding_window_view(cy[:, reflected_indices(rows.start - r, rows.stop + r, cy.shape[1])], 2 * r + 1, axis=1)
    xwin = sliding_window_view(cx[:, reflected_indices(cols.start - r, cols.stop + r, cx.shape[1])], 2 * r + 1, axis=1)
    factors = []
    for c, (weights, gaussians) in enumerate(scielab_components(spd)):
        down = np.concatenate([(ywin @ g) * (w * step[:, c])[:, None] for w, g in zip(weights, gaussians)])
        factors.append((down, np.concatenate([xwin @ g for g in gaussians])))
    return to_opponent @ surround, factors


def _truth_band_filtered(base: np.ndarray, factors: list, rows: slice) -> np.ndarray:
    """``(rows, cols, 3)``: the filtered truth's band ``rows`` (relative to the factors' first row), from
    :func:`_truth_factors`."""
    planes = np.empty((3, rows.stop - rows.start, factors[0][1].shape[1]))
    for c, (down, across) in enumerate(factors):
        np.matmul(down[:, rows].T, across, out=planes[c])
        planes[c] += base[c]
    return np.moveaxis(planes, 0, -1)


@lru_cache(maxsize=2)
def _truth_scielab_lab(reference: ChartReference, display: str, adaptation: str, spd: float) -> np.ndarray:
    """``(n, 3)``: CIELAB against the display white of the scene's truth image carried to the display white
    (``processing.adaptation``) and through the S-CIELAB filters (:func:`_truth_band_filtered`), at the scored pixels
    in row-major order, written band by band into one array.  Memoised: every capture of a scene (designs, seeds,
    noise steps) is scored against the same truth."""
    from spectracam.evaluation.scielab import XYZ_TO_OPPONENT
    from spectracam.processing.color import adaptation_matrix

    M_disp = display_rgb_to_xyz(display)
    white = M_disp.sum(axis=1)
    to_opponent = XYZ_TO_OPPONENT @ adaptation_matrix(reference.white_xyz, white, adaptation)
    at = _scielab_bands(reference, spd)
    base, factors = _truth_factors(reference, at.rows, at.cols, to_opponent, spd)
    mask, fused = _scored_mask(reference), _fused(white)
    lab = np.empty((int(mask[at.rows, at.cols].sum()), 3))
    start = 0
    for rows in at.bands:
        f = _truth_band_filtered(base, factors, slice(rows.start - at.rows.start, rows.stop - at.rows.start))
        start = _kept_lab(f, mask[rows, at.cols], white, fused, lab, start)
    assert start == len(lab)
    lab.flags.writeable = False
    return lab


def _band_delta_e(opp: np.ndarray, keep: np.ndarray, spd: float, white: np.ndarray, truth: np.ndarray, start: int,
                  method: str, out: np.ndarray, rows: slice, cols: slice, fused: _Fused | None) -> int:
    """Writes into ``out[rows, cols]`` the S-CIELAB ΔE (``method``) of a band at its ``keep`` pixels against the
    truth's CIELAB from row-major rank ``start``; returns the rank after the band's last kept pixel."""
    from spectracam.core.cielab import DELTA_E_CODES
    from spectracam.core.parallel import run_bands
    from spectracam.evaluation.scielab import filter_extended_opponent

    if fused is None:
        lab = np.empty((int(keep.sum()), 3))
        _kept_lab(filter_extended_opponent(opp, spd), keep, white, None, lab, 0)
        block = out[rows, cols]
        block[keep] = delta_e(lab, truth[start:start + len(lab)], method)
        out[rows, cols] = block
        return start + len(lab)
    f = filter_extended_opponent(opp, spd)
    keep = np.ascontiguousarray(keep)
    offsets = _kept_offsets(keep, start)
    code = np.int64(DELTA_E_CODES[method])
    run_bands(fused.mod.masked_delta_e_kernel, len(keep),
              lambda a, b: (np.int64(a), np.int64(b), f, keep, offsets, fused.to_lab, fused.white, truth, code, out,
                            np.int64(rows.start), np.int64(cols.start)))
    return int(offsets[-1])


def chart_scielab_map(rgb: np.ndarray, reference: ChartReference, processing: ProcessingSpec) -> np.ndarray:
    """``(H, W)`` float32 S-CIELAB ΔE (Zhang & Wandell 1997; :mod:`spectracam.evaluation.scielab`) of a chart's
    rendering, NaN outside the patches' scoring boxes (the pixels the per-pixel ΔE is scored on).

    The rendered display XYZ (``rgb`` through the display) and the scene's truth (:func:`chart_truth_xyz`, carried to
    the display white by ``processing.adaptation``, as the target scores do) pass through the same opponent-channel
    filters sampled at ``processing.samples_per_degree`` (the viewing distance and the display's pixel pitch, one
    image pixel per display pixel); then CIELAB against the display white and ΔE (``processing.delta_e``) per pixel.
    On a uniform area (wider than the filters' 1° support) it equals the per-pixel ΔE (with the default XYZ-scaling
    adaptation, exactly); noise is averaged as the eye averages it.  Separable Gaussians on the scored pixels'
    bounding box and the filters' reach only, a band of rows at a time; no random numbers.

    Parameters
    ----------
    rgb : ndarray
        ``(H, W, 3)`` the rendering, linear display RGB (white = 1).
    reference : ChartReference
        The chart under its light (the truth and the scoring boxes).
    processing : ProcessingSpec
        The colour processing (demosaicking, conversion, display, ΔE formula).

    Returns
    -------
    ndarray
        ``(H, W)`` float32 S-CIELAB ΔE.
    """
    if reference.cell is not None:   # one chart of several (a light group's): filtered on its own cell
        rows, cols = reference.cell
        out = np.full(rgb.shape[:2], np.nan, np.float32)
        out[rows, cols] = chart_scielab_map(np.ascontiguousarray(rgb[rows, cols]), reference.local(), processing)
        return out
    from spectracam.evaluation.scielab import XYZ_TO_OPPONENT

    spd = processing.samples_per_degree
    M_disp = display_rgb_to_xyz(processing.display)
    white = M_disp.sum(axis=1)
    to_opponent = XYZ_TO_OPPONENT @ M_disp
    truth = _truth_scielab_lab(reference, processing.display, processing.adaptation, spd)
    at = _scielab_bands(reference, spd)
    mask, fused = _scored_mask(reference), _fused(white, processing.delta_e)
    out = np.full(mask.shape, np.nan, np.float32)
    start = 0
    for rows, rows_in in zip(at.bands, at.rows_in):
        start = _band_delta_e(_band_opponent(rgb, rows_in, at.cols_in, to_opponent, fused), mask[rows, at.cols], spd,
                              white, truth, start, processing.delta_e, out, rows, at.cols, fused)
    return out


def score(raw: RawCapture, reference: ChartReference, processing: ProcessingSpec,
          delta_e_reference: str = "scene") -> ChartScore:
    """Render a capture on the display and score it against the chart reference (see the module docstring).

    Parameters
    ----------
    raw : RawCapture
        The capture, of the chart ``reference`` describes (same image size, scene and metered exposure).
    reference : ChartReference
        The chart's truth: each patch's radiance and CIE 1931 XYZ, the light's white, the patches' scoring boxes.
    processing : ProcessingSpec
        How the capture is developed and displayed: demosaicking, white balance, conversion, display, ΔE formula.
    delta_e_reference : {"scene", "camera"}
        ``"camera"`` scores per-pixel ΔE against the noise-free rendering of the same camera instead
        (:data:`DELTA_E_REFERENCES`); ``delta_e_of_mean`` and ``delta_e_conversion`` are always against the
        scene.

    Returns
    -------
    ChartScore
        The summary, per-patch scores (CIELAB, ΔE, SNR), the rendered linear display RGB, the ΔE map and the
        conversion's errors on the colours it was and was not fitted on.

    Raises
    ------
    SpectracamError
        An unknown ``delta_e_reference``, an impossible capture, another image size, another scene, or exposure
        times the chart's white patch does not meter.

    References
    ----------
    .. [Catrysse1999] see docs/references.md; sections 3.5, 3.6 and 5.
    .. [CIE015] see docs/references.md; CIE 1976 L*a*b*.
    .. [Zhang1997] see docs/references.md; the S-CIELAB map.
    """
    _check_scorable(raw, reference, delta_e_reference)
    h, w = raw.digital.shape[-2:]
    chart_rates = reference.patch_rates(raw.camera)
    M_disp = display_rgb_to_xyz(processing.display)
    rgb, M, wb = developed_rgb(raw, reference, processing)
    colours = _chart_colours(reference, chart_rates, M, M_disp, delta_e_reference)
    de_map = np.full((h, w), np.nan, np.float32)
    patches, de2000, sc_map = _patch_scores(raw, reference, processing, rgb, M, colours, de_map)
    summary = _chart_summary(raw, patches, de_map, de2000, sc_map, wb)
    del sc_map   # not kept: freed before the rendering is narrowed to float32 below
    parameters = _score_parameters(raw, processing, delta_e_reference, M)
    training, held_out = _held_out_blocks(raw, reference, processing, M, patches)
    held = [rgb]
    del rgb      # the only reference is in held: narrowed in its own buffer
    return ChartScore(summary, tuple(patches), parameters, _narrowed_to_float32(held), de_map, training, held_out, wb)


#: Elements narrowed at a time by :func:`_narrowed_to_float32` (a 4-MB float64 temporary).
NARROW_CHUNK = 1 << 19


def _narrowed_to_float32(held: list) -> np.ndarray:
    """``rgb.astype(np.float32)`` for the one array in ``held`` (taken out of it), made in ``rgb``'s own buffer where
    ``rgb`` is a C-contiguous float64 array that owns its data and nothing else refers to it (its reference count:
    no other name, container or view): each chunk of values is written, as float32, over the first
    half of the buffer (a chunk never reaches values not yet read), then the buffer is shrunk to that half
    (``realloc``).  The score's last full-size allocation was the float32 copy beside the float64 image, its resident
    peak (issue 38: 0.1 of a 12-Mpx cube).  The values are ``astype``'s.  Otherwise (a view, another dtype, another
    reference): ``astype``, the float64 image left as it was."""
    rgb = held.pop()
    alone = object()   # held by one local name, as rgb is: its count is what "nothing else refers to it" reads as on
    #                    this interpreter (the argument's own reference is counted or not depending on the version)
    if rgb.dtype != np.float64 or not rgb.flags.c_contiguous or not rgb.flags.owndata or rgb.size < 2 \
            or sys.getrefcount(rgb) > sys.getrefcount(alone):
        return rgb.astype(np.float32)
    shape, size = rgb.shape, rgb.size
    flat = rgb.reshape(-1)
    narrow = flat.view(np.float32)
    for a in range(0, size, NARROW_CHUNK):
        b = min(a + NARROW_CHUNK, size)
        narrow[a:b] = flat[a:b]              # reads the chunk (a temporary) before writing over bytes [4a, 4b)
    del flat, narrow
    # no other reference or view (checked above, by the reference count numpy's own check reads; that check is
    # fooled by a profiler's reference to the bound method, so it is not asked again)
    rgb.resize(((size + 1) // 2,), refcheck=False)
    return rgb.view(np.float32)[:size].reshape(shape)


def score_region(raw: RawCapture, rates: np.ndarray, reference: ChartReference,
                 processing: ProcessingSpec) -> tuple[list, list, list]:
    """The told-the-light score of one chart of a scene that holds several, each under its own light group
    (issue 36): the conversion fitted on this chart's noise-free rates under its own light and level (paper 3.5),
    so each chart is rendered against its own white, as an eye adapted to that part of the scene sees it.

    Parameters
    ----------
    raw : RawCapture
        The capture of the whole scene.
    rates : ndarray
        ``(H, W, N)`` its exposure-normalised camera rates, e⁻/s (:func:`camera_rates`), shared by every chart.
    reference : ChartReference
        This chart's truth under its light (:func:`spectracam.scene.reference.chart_cells`); its boxes lie in the
        capture's pixel coordinates, and its S-CIELAB is filtered on its cell alone (:func:`chart_scielab_map`).
    processing : ProcessingSpec
        Display, ΔE formula, S-CIELAB viewing, SNR combination.

    Returns
    -------
    patches : list of PatchScore
        Per patch: ΔE (``processing.delta_e``), S-CIELAB, SNRs, as :func:`score` gives them.
    delta_e_2000 : list of float
        Each patch's mean CIEDE2000.
    delta_e_camera : list of float
        Each patch's mean per-pixel ΔE (``processing.delta_e``) against this camera's own noise-free rendering of it
        (``delta_e_reference = "camera"``): what the capture loses, the conversion's own error aside.

    References
    ----------
    .. [Catrysse1999] see docs/references.md; sections 3.5 and 3.6.
    """
    M = conversion_matrix(reference, raw.camera, processing)
    rgb = np.concatenate([rates[i:i + 256] @ M for i in range(0, rates.shape[0], 256)]).astype(np.float32)
    if processing.gamut_clip:
        np.clip(rgb, 0.0, 1.0, out=rgb)
    M_disp = display_rgb_to_xyz(processing.display)
    colours = _chart_colours(reference, reference.patch_rates(raw.camera), M, M_disp, "scene")
    de_map = np.full(rates.shape[:2], np.nan, np.float32)
    patches, de2000, _ = _patch_scores(raw, reference, processing, rgb, M, colours, de_map)
    de_camera = [float(np.mean(delta_e(lab, colours.conversion_lab[p], processing.delta_e)))
                 for p, lab in enumerate(_box_labs(rgb, reference.boxes, M_disp, colours.display_white))]
    return patches, de2000, de_camera


def _check_scorable(raw: RawCapture, reference: ChartReference, delta_e_reference: str) -> None:
    """Refuse a capture that cannot be scored against ``reference``: a bad ΔE reference, an impossible capture,
    another image size, another scene or exposure times its white patch does not meter."""
    if delta_e_reference not in DELTA_E_REFERENCES:
        raise SpectracamError(f"delta_e_reference = {delta_e_reference!r}: must be one of "
                              + ", ".join(map(repr, DELTA_E_REFERENCES)))
    check_raw(raw)
    h, w = raw.digital.shape[-2:]
    if (w, h) != (reference.width_px, reference.height_px):
        raise SpectracamError(f"image = {w}x{h}: the capture does not match the scene "
                              f"({reference.width_px}x{reference.height_px})")
    if raw.scene is not None and (table := reference.matches(raw.scene)) is not None:
        raise SpectracamError(f"{table} = {str(raw.scene.get(table))[:120]}: the capture was taken of another scene "
                              f"than the one it is scored against")
    check_exposure_matches(raw, reference)


class _ChartColours(NamedTuple):
    """The display (RGB → XYZ matrix, white) and the patches' CIELAB: the scene's, the noise-free conversion's, and
    the one per-pixel ΔE is measured against (:data:`DELTA_E_REFERENCES`)."""

    M_disp: np.ndarray
    display_white: np.ndarray
    scene_lab: np.ndarray
    conversion_lab: np.ndarray
    against: np.ndarray


def _chart_colours(reference: ChartReference, chart_rates: np.ndarray, M: np.ndarray, M_disp: np.ndarray,
                   delta_e_reference: str) -> _ChartColours:
    """The scene's patch CIELAB (against its light's white) and the conversion's (the chart's rates through ``M``,
    against the display white; paper 3.5)."""
    display_white = M_disp.sum(axis=1)
    scene_lab = xyz_to_lab(reference.patch_xyz, reference.white_xyz)
    conversion_lab = xyz_to_lab(chart_rates @ M @ M_disp.T, display_white)
    against = scene_lab if delta_e_reference == "scene" else conversion_lab
    return _ChartColours(M_disp, display_white, scene_lab, conversion_lab, against)


def _patch_snrs(means: np.ndarray, stds: np.ndarray, luminance: np.ndarray, times_s: np.ndarray, combination: str):
    """``(per channel, combined, rendered luminance)`` SNR of one patch, dB (paper 5): infinite noise-free,
    undefined (NaN) when a mean is ≤ 0; the rendered one carries each channel's rate (e⁻/t) to display luminance."""
    with np.errstate(divide="ignore", invalid="ignore"):
        snr = snr_db(means, stds)
        combined = combine_snr_db(means, stds, combination)
        rendered = snr_db(luminance @ (means / times_s), np.linalg.norm(luminance * stds / times_s))
    return snr, combined, rendered


def _patch_scores(raw: RawCapture, reference: ChartReference, processing: ProcessingSpec, rgb: np.ndarray,
                  M: np.ndarray, colours: _ChartColours, de_map: np.ndarray) -> tuple[list, list, np.ndarray]:
    """``(patch scores, each patch's mean CIEDE2000, S-CIELAB map)``, filling ``de_map`` with the per-pixel ΔE."""
    method, boxes, channels = processing.delta_e, reference.boxes, raw.layout.channels
    M_disp, display_white, scene_lab, against = colours.M_disp, colours.display_white, colours.scene_lab, \
        colours.against
    means, stds = channel_stats(raw, boxes)
    # display luminance per unit of each channel's rate, and each channel's exposure (rates = e⁻/t)
    luminance = M @ M_disp[1]
    times_s = np.asarray(raw.exposure_times_s, float)
    mean_labs = xyz_to_lab(np.stack([rgb[r, c].reshape(-1, 3).mean(axis=0) for r, c in boxes]) @ M_disp.T,
                           display_white)
    sc_map = chart_scielab_map(rgb, reference, processing)
    per_box = _box_delta_es(rgb, boxes, M_disp, display_white, against, method, de_map)
    of_mean = delta_e(mean_labs, scene_lab, method)                      # each patch's, in one call
    of_conversion = delta_e(colours.conversion_lab, scene_lab, method)
    patches, de2000 = [], []
    for p, (r, c), (de_mean, de_2000) in zip(range(len(boxes)), boxes, per_box):
        de2000.append(de_2000)
        snr, combined, rendered = _patch_snrs(means[p], stds[p], luminance, times_s, processing.snr_combination)
        by_name = dict(zip(channels, snr))
        patches.append(PatchScore(
            patch=p, name=reference.names[p], scene_lab=tuple(scene_lab[p].round(4).tolist()),
            rendered_lab=tuple(mean_labs[p].round(4).tolist()), delta_e_mean=de_mean,
            delta_e_of_mean=float(of_mean[p]), delta_e_conversion=float(of_conversion[p]),
            **{f"snr_{k}_db": _finite(by_name[k]) if k in by_name else None for k in "RGB"},
            snr_combined_db=_finite(combined), pixels=int((r.stop - r.start) * (c.stop - c.start)),
            snr_undefined=tuple(k for k, m, sd in zip(channels, means[p], stds[p]) if m <= 0 and sd > 0),
            snr_by_channel_db={k: _finite(v) for k, v in by_name.items()}, snr_rendered_db=_finite(rendered),
            s_cielab_mean=float(sc_map[r, c].mean(dtype=np.float64))))
    return patches, de2000, sc_map


def _p95(values: np.ndarray) -> float:
    """The 95th percentile of a map's scored (not NaN) values, as ``np.nanpercentile`` gives it (linear
    interpolation), NaN when none is scored: the NaN pixels dropped by one mask, not ``nanpercentile``'s copies
    (a third of its time at 12 Mpx)."""
    kept = values[~np.isnan(values)]
    return float(np.percentile(kept, 95)) if kept.size else float("nan")


def _chart_summary(raw: RawCapture, patches: list, de_map: np.ndarray, de2000: list, sc_map: np.ndarray,
                   wb: dict) -> ChartSummary:
    """The chart averages of the patch scores, the capture's timing and the white balance's errors."""
    channels = raw.layout.channels
    times_ms = 1e3 * np.asarray(raw.exposure_times_s, float)
    return ChartSummary(
        delta_e_mean=float(np.mean([p.delta_e_mean for p in patches])),
        delta_e_of_mean=float(np.mean([p.delta_e_of_mean for p in patches])),
        delta_e_conversion=float(np.mean([p.delta_e_conversion for p in patches])),
        snr_combined_db=_mean_or_none([p.snr_combined_db for p in patches]),
        **{f"snr_{k}_db": _mean_or_none([getattr(p, f"snr_{k}_db") for p in patches]) for k in "RGB"},
        capture_time_ms=1e3 * float(raw.capture_time_s),
        **{f"exposure_{k}_ms": float(times_ms[channels.index(k)]) if k in channels else None for k in "RGB"},
        snr_undefined_patches=int(sum(len(p.snr_undefined) for p in patches)),
        snr_rendered_db=_mean_or_none([p.snr_rendered_db for p in patches]),
        delta_e_p95=_p95(de_map), delta_e2000_mean=float(np.mean(de2000)),
        awb_recovery_deg=wb["recovery_deg"], awb_reproduction_deg=wb["reproduction_deg"],
        s_cielab_mean=float(np.mean([p.s_cielab_mean for p in patches])),
        s_cielab_p95=_p95(sc_map), snr_white_rendered_db=patches[WHITE_PATCH].snr_rendered_db)


def _score_parameters(raw: RawCapture, processing: ProcessingSpec, delta_e_reference: str, M: np.ndarray) -> dict:
    """The report's ``parameters`` block: what was scored, how, and the definitions of the SNR and S-CIELAB."""
    return {
        "scene": raw.scene, "camera": raw.camera.to_dict(), "processing": processing.to_dict(), "seed": raw.seed,
        "delta_e_reference": delta_e_reference, "conversion_matrix": M.tolist(),
        "snr_definition": "20*log10(mean/std) of the dark-subtracted electrons of each channel's own pixels in "
                          "the patch mask; combined: "
                          + (SNR_COMBINATIONS[processing.snr_combination].__doc__ or processing.snr_combination),
        "s_cielab": {"viewing_distance_m": processing.viewing_distance_m,
                     "display_pixel_pitch_mm": processing.display_pixel_pitch_mm,
                     "samples_per_degree": processing.samples_per_degree,
                     "definition": "S-CIELAB (Zhang & Wandell 1997): the rendered display XYZ and the scene's truth "
                                   "(each patch's reference XYZ over its pixel area, the surround's elsewhere, carried "
                                   "to the display white) through the eye's opponent-channel filters, then "
                                   f"{processing.delta_e} per pixel on the patches' scored pixels; docs/metrics.md"},
    }


def _held_out_blocks(raw: RawCapture, reference: ChartReference, processing: ProcessingSpec, M: np.ndarray,
                     patches: list) -> tuple[dict | None, dict | None]:
    """``(training, held_out)``: the conversion's noise-free error on the chart it was fitted on and on the colours of
    ``processing.held_out`` (both None when that is "none")."""
    if processing.held_out == "none":
        return None, None
    from spectracam.evaluation.heldout import held_out_block
    from spectracam.evaluation.heldout import summary as error_summary

    training = error_summary([p.delta_e_conversion for p in patches], "the chart (training: the conversion is "
                             "fitted on it)")
    held_out = held_out_block(processing.held_out, reference.illuminant, reference.grid, raw.camera, M, processing)
    return training, held_out
