"""From a raw capture to a displayed image and its score (paper, sections 3.5, 3.6 and 5).

The scene reference is the closed-form radiance of each patch (render/analytic.py), so a capture
can be scored from its raw file alone.  Digital numbers become electrons (mid-step
dequantisation), the expected dark charge is subtracted (a dark-frame calibration; the fixed
pattern stays), the colour filter array is demosaicked, each channel is divided by its exposure
time, and the fitted 3×3 matrix maps the result to linear display RGB.
"""
from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass

import numpy as np

from .architecture import bayer_sites
from .capture import WHITE_PATCH, photo_electron_rates
from .chart import patch_boxes
from .color import ProcessingSpec, adaptation_matrix, demosaic, display_rgb_to_xyz, fit_conversion
from .metrics import combine_snr_db, delta_e, snr_db, xyz_to_lab
from .render import RadianceCube
from .spectra import K_M_LM_PER_W, cmf_band_weights


def _finite(x) -> float | None:
    return float(x) if np.isfinite(x) else None


def _mean_or_none(values) -> float | None:
    return None if any(v is None for v in values) else float(np.mean(values))


@dataclass
class Score:
    report: dict
    rendered_rgb: np.ndarray  # (H, W, 3) linear display RGB
    delta_e_map: np.ndarray  # (H, W), NaN outside the patches' masks


_REFERENCE_CACHE: dict[str, tuple] = {}


def scene_reference(scene) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Patch radiance ``(24, B)``, patch XYZ ``(24, 3)`` and illuminant white XYZ, Y = 1 for a
    perfect white diffuser on the scene's wavelength grid (memoised on the chart, light and grid:
    sweeps and noise trials score the same scene many times)."""
    d = scene.to_dict()
    key = json.dumps([d["chart"], d["illuminant"], d["wavelengths"]], sort_keys=True)
    if key not in _REFERENCE_CACHE:
        if len(_REFERENCE_CACHE) > 64:
            _REFERENCE_CACHE.clear()
        _REFERENCE_CACHE[key] = _scene_reference(scene)
    return _REFERENCE_CACHE[key]


def _scene_reference(scene) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    from .render.analytic import material_radiance

    _, patches, _ = material_radiance(scene)
    W = cmf_band_weights(scene.grid) * (K_M_LM_PER_W / scene.illuminant.white_luminance_cd_m2)
    from .illuminant import spectral_irradiance
    from .spectra import band_average

    white = band_average(lambda lam: spectral_irradiance(scene.illuminant)(lam) / np.pi, scene.grid) @ W
    return patches, patches @ W, white / white[1]


def chart_photo_rates(scene, camera) -> np.ndarray:
    """Noise-free photo-electron rates ``(24, 3)`` (e⁻/s) of the chart's patches for a camera, from
    the closed-form patch radiance: the colour-conversion fit's input (paper 3.5)."""
    patches, _, _ = scene_reference(scene)
    chart = RadianceCube(patches[None].astype(np.float32), np.asarray(scene.grid.centres_nm, float))
    return photo_electron_rates(chart, camera)[0].astype(np.float64)


def white_patch_rates(scene, camera) -> np.ndarray:
    return chart_photo_rates(scene, camera)[WHITE_PATCH]


def recorded_electrons(raw) -> tuple[np.ndarray, np.ndarray]:
    """Dark-subtracted electrons in the capture's layout, and the dark charge subtracted per channel."""
    s = raw.camera.sensor
    e = (raw.digital + (0.5 if s.quantization else 0.0)) * s.quantization_step_e
    dark = s.dark_rate_e_per_s * np.asarray(raw.exposure_times_s)
    if raw.digital.ndim == 2:
        return e - dark[0], dark
    return e - dark[:, None, None], dark


def camera_rates(raw, processing: ProcessingSpec) -> np.ndarray:
    """``(H, W, 3)`` photo-electrons per second per channel: demosaicked and exposure-normalised."""
    e, _ = recorded_electrons(raw)
    rgb = demosaic(e, raw.cfa_pattern, processing.demosaic) if e.ndim == 2 else np.moveaxis(e, 0, -1)
    return rgb / np.asarray(raw.exposure_times_s)[None, None, :]


def channel_stats(raw, boxes) -> tuple[np.ndarray, np.ndarray]:
    """Mean and std ``(24, 3)`` of the recorded (dark-subtracted) electrons of each channel's own pixels."""
    e, _ = recorded_electrons(raw)
    means, stds = np.zeros((len(boxes), 3)), np.zeros((len(boxes), 3))
    for p, (r, c) in enumerate(boxes):
        if e.ndim == 2:
            sites = bayer_sites(raw.cfa_pattern)
            for k in range(3):  # all tile sites of the channel (both greens)
                pix = np.concatenate([e[r, c][(r.start + dy) % 2::2, (c.start + dx) % 2::2].ravel()
                                      for dy, dx, kk in sites if kk == k])
                means[p, k], stds[p, k] = pix.mean(), pix.std()
        else:
            block = e[:, r, c].reshape(3, -1)
            means[p], stds[p] = block.mean(axis=1), block.std(axis=1)
    return means, stds


def score(raw, scene, processing: ProcessingSpec | None = None, reference: str = "scene") -> Score:
    """Render a capture on the display and score it against the scene; see the module docstring.

    ``reference="camera"`` scores per-pixel ΔE against the noise-free rendering of the same camera
    instead (the conversion error removed): how the paper's error budget isolates the noise steps.
    ``delta_e_of_mean`` and ``delta_e_conversion`` are always against the scene.
    """
    processing = processing or scene.processing
    delta_e_method, snr_combination = processing.delta_e, processing.snr_combination
    camera = raw.camera
    _, scene_xyz, white_xyz = scene_reference(scene)
    chart_rates = chart_photo_rates(scene, camera)
    M_disp = display_rgb_to_xyz(processing.display)
    display_white = M_disp.sum(axis=1)
    to_display_xyz = adaptation_matrix(white_xyz, display_white, processing.adaptation)
    target_rgb = scene_xyz @ to_display_xyz.T @ np.linalg.inv(M_disp).T
    M = fit_conversion(chart_rates, target_rgb)

    rgb = camera_rates(raw, processing) @ M
    if processing.gamut_clip:
        np.clip(rgb, 0.0, 1.0, out=rgb)
    lab = xyz_to_lab(rgb @ M_disp.T, display_white)
    scene_lab = xyz_to_lab(scene_xyz, white_xyz)
    conversion_lab = xyz_to_lab(chart_rates @ M @ M_disp.T, display_white)

    h, w = rgb.shape[:2]
    boxes = patch_boxes(scene.chart, w, h)
    de_map = np.full((h, w), np.nan)
    means, stds = channel_stats(raw, boxes)
    rows = []
    from .chart import patch_names_and_data

    names = [n for n, _, _ in patch_names_and_data(scene.chart.dataset)]
    mean_labs = xyz_to_lab(np.stack([rgb[r, c].reshape(-1, 3).mean(axis=0) for r, c in boxes]) @ M_disp.T,
                           display_white)
    for p, (r, c) in enumerate(boxes):
        de = delta_e(lab[r, c], (scene_lab if reference == "scene" else conversion_lab)[p], delta_e_method)
        de_map[r, c] = de
        mean_lab = mean_labs[p]
        with np.errstate(divide="ignore"):  # a noise-free capture has infinite SNR: reported as null
            snr = snr_db(means[p], stds[p])
            combined = combine_snr_db(means[p], stds[p], snr_combination)
        rows.append({
            "patch": p, "name": names[p],
            "scene_lab": scene_lab[p].round(4).tolist(), "rendered_lab": mean_lab.round(4).tolist(),
            "delta_e_mean": float(de.mean()), "delta_e_of_mean": float(delta_e(mean_lab, scene_lab[p], delta_e_method)),
            "delta_e_conversion": float(delta_e(conversion_lab[p], scene_lab[p], delta_e_method)),
            "snr_db": dict(zip("RGB", map(_finite, snr))),
            "snr_combined_db": _finite(combined),
            "pixels": int((r.stop - r.start) * (c.stop - c.start)),
        })
    report = {
        "parameters": {
            "scene": scene.to_dict(), "camera": camera.to_dict(), "processing": dataclasses.asdict(processing),
            "delta_e_method": delta_e_method, "delta_e_reference": reference, "snr_combination": snr_combination, "seed": raw.seed,
            "exposure_times_ms": dict(zip("RGB", (1e3 * np.asarray(raw.exposure_times_s)).tolist())),
            "capture_time_ms": 1e3 * raw.capture_time_s,
            "conversion_matrix": M.tolist(),
            "snr_definition": "20*log10(mean/std) of the dark-subtracted electrons of each channel's own pixels in "
                              "the patch mask; combined: " + ("10*log10(sum mean^2 / sum std^2) over R, G, B"
                                                             if snr_combination == "power" else "mean of the channel dB"),
        },
        "patches": rows,
        "chart": {
            "delta_e_mean": float(np.mean([r["delta_e_mean"] for r in rows])),
            "delta_e_of_mean": float(np.mean([r["delta_e_of_mean"] for r in rows])),
            "delta_e_conversion": float(np.mean([r["delta_e_conversion"] for r in rows])),
            "snr_db": {k: _mean_or_none([r["snr_db"][k] for r in rows]) for k in "RGB"},
            "snr_combined_db": _mean_or_none([r["snr_combined_db"] for r in rows]),
        },
    }
    return Score(report, rgb.astype(np.float32), de_map.astype(np.float32))
