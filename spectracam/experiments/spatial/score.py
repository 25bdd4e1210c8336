"""Scoring one processed image of a spatial target: the metrics, each against a stated reference.

Two references (docs/metrics.md, "Spatial"):

* the **scene reference** — the target's radiance band-limited to the sensor's Nyquist frequency by an
  ideal low-pass and sampled at the pixel centres (:meth:`~spectracam.experiments.spatial.render.SubpixelCube.band_limited`;
  ``reference = "footprint"``: each pixel's box footprint instead), carried to the display white as the
  paper scores colour: what any camera of this pitch could at best show, so aliasing counts as error;
* the **own reference** — the same camera's noise-free rendering of that reference image (its colour
  conversion applied to the reference's photo-electron rates): the conversion's constant error removed,
  so what is left is spatial (optics, sampling, demosaicking, misregistration, aliasing) and noise;
* the **optics reference** — the same camera's noise-free image through the same lens, pixel aperture and
  low-pass filter with every channel sampled at every pixel centre (no mosaic, no misregistration): what
  is left against it is what sampling, demosaicking and misregistration made (and noise).

Metrics are a registry (:data:`SPATIAL_METRICS`): each says which targets it applies to.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Callable

import numpy as np

from spectracam.core.cielab import delta_e, xyz_to_lab
from spectracam.core.registry import Registry
from spectracam.evaluation.esfr import NoEdge, esfr
from spectracam.experiments.spatial.geometry import CameraGeometry
from spectracam.evaluation.scielab import scielab
from spectracam.experiments.spatial.targets import SlantedEdge, Target, TiltedChart, ZonePlate

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from spectracam.evaluation.esfr import ESFRResult

__all__ = ["EDGE_ZONE_PX", "SCALAR_METRICS", "SCORE_BORDER_PX", "SPATIAL_METRICS", "Metric",
           "ScoringContext", "SpatialRow", "mtf_curves", "score_image", "seed_summary"]

#: Pixels cut from every side before scoring: demosaicking's border rows and columns.
SCORE_BORDER_PX = 4
#: Half-width of the edge zone, px: pixels this close to a change of the reference's L* (> 1 per pixel).
EDGE_ZONE_PX = 2


@dataclass
class ScoringContext:
    """One processed image (display XYZ, white Y = 1) with its references and what the metrics share."""

    target: Target
    geometry: CameraGeometry
    xyz: np.ndarray               # the design's displayed image
    reference_xyz: np.ndarray     # the scene reference (band-limited or footprint), at the display white
    own_xyz: np.ndarray           # the camera's noise-free rendering of the reference image
    optics_xyz: np.ndarray        # the camera's noise-free image, every channel at every pixel (no mosaic)
    camera_rates: np.ndarray      # (H, W, N) processed channel rates, for the per-channel e-SFR
    white: np.ndarray             # display white XYZ
    samples_per_degree: float
    channels: tuple = ("R", "G", "B")
    esfr_correct_binning: bool = False

    @cached_property
    def region(self) -> np.ndarray:
        b = SCORE_BORDER_PX
        r = self.target.region(self.geometry).copy()
        r[:b], r[-b:], r[:, :b], r[:, -b:] = False, False, False, False
        return r

    @cached_property
    def lab(self):
        return xyz_to_lab(self.xyz, self.white)

    @cached_property
    def lab_reference(self):
        return xyz_to_lab(self.reference_xyz, self.white)

    @cached_property
    def lab_own(self):
        return xyz_to_lab(self.own_xyz, self.white)

    @cached_property
    def lab_optics(self):
        return xyz_to_lab(self.optics_xyz, self.white)

    @cached_property
    def scielab_map(self) -> np.ndarray:
        return scielab(self.reference_xyz, self.xyz, self.white, self.samples_per_degree)

    @cached_property
    def scielab_own_map(self) -> np.ndarray:
        """S-CIELAB ΔE*ab against the own reference: the spatial (and noise) error map."""
        return scielab(self.own_xyz, self.xyz, self.white, self.samples_per_degree)

    @cached_property
    def edge_zone(self) -> np.ndarray:
        """Pixels within :data:`EDGE_ZONE_PX` of a change of the reference's L* (> 1 per pixel)."""
        from scipy import ndimage

        g = np.hypot(*np.gradient(self.lab_reference[..., 0]))
        return ndimage.binary_dilation(g > 1.0, iterations=EDGE_ZONE_PX) & self.region

    def esfr(self, image: ArrayLike) -> ESFRResult | None:
        """The e-SFR of ``image`` cropped by the border, or None where it holds no usable edge.

        Parameters
        ----------
        image : array_like
            ``(H, W)`` one plane (luminance Y or a channel's rates); :data:`SCORE_BORDER_PX` cut from each side.

        Returns
        -------
        ESFRResult or None
            :func:`spectracam.evaluation.esfr.esfr`'s, with this context's binning correction.
        """
        b = SCORE_BORDER_PX
        try:
            return esfr(np.asarray(image)[b:-b, b:-b], correct_binning=self.esfr_correct_binning)
        except NoEdge:
            return None

    @cached_property
    def esfr_luminance(self):
        return self.esfr(self.xyz[..., 1])

    @cached_property
    def esfr_channels(self) -> dict:
        return {c: self.esfr(self.camera_rates[..., k]) for k, c in enumerate(self.channels)}


def _every_target(target: Target) -> bool:
    """The default of :attr:`Metric.applies`: a metric that applies to every target.

    Parameters
    ----------
    target : Target
        Any target.

    Returns
    -------
    bool
        True.
    """
    return True


@dataclass(frozen=True)
class Metric:
    """A spatial metric: what it measures, against which reference, the targets it applies to."""

    doc: str
    compute: Callable[[ScoringContext], object]
    applies: Callable[[Target], bool] = _every_target


#: name → :class:`Metric`; the row fields of :class:`SpatialRow` with the same names.
SPATIAL_METRICS: Registry[Metric] = Registry("spatial.metrics", "spatial metric")


def _mean(values, mask):
    return float(values[mask].mean()) if mask.any() else None


def _finite(x):
    return float(x) if x is not None and np.isfinite(x) else None


def _is_edge(t):
    return isinstance(t, SlantedEdge)


SPATIAL_METRICS.register("cielab_delta_e", Metric(
    "mean CIELAB ΔE*ab per pixel over the region, against the scene reference",
    lambda c: _mean(delta_e(c.lab, c.lab_reference), c.region)))
SPATIAL_METRICS.register("scielab_delta_e", Metric(
    "mean S-CIELAB ΔE*ab over the region, against the scene reference (includes the conversion's error)",
    lambda c: _mean(c.scielab_map, c.region)))
SPATIAL_METRICS.register("cielab_delta_e_spatial", Metric(
    "mean CIELAB ΔE*ab against the own reference (spatial error and noise alone)",
    lambda c: _mean(delta_e(c.lab, c.lab_own), c.region)))
SPATIAL_METRICS.register("scielab_delta_e_spatial", Metric(
    "mean S-CIELAB ΔE*ab against the own reference", lambda c: _mean(c.scielab_own_map, c.region)))
SPATIAL_METRICS.register("scielab_delta_e_spatial_p95", Metric(
    "95th percentile of the S-CIELAB ΔE*ab map against the own reference",
    lambda c: float(np.percentile(c.scielab_own_map[c.region], 95)) if c.region.any() else None))
SPATIAL_METRICS.register("false_colour", Metric(
    "neutral targets: mean chroma difference √(Δa*² + Δb*²) against the own reference in the edge zone",
    lambda c: _mean(np.hypot(*(c.lab - c.lab_own)[..., 1:].transpose(2, 0, 1)), c.edge_zone),
    lambda t: t.neutral))
SPATIAL_METRICS.register("edge_delta_e", Metric(
    "slanted edges: mean CIELAB ΔE*ab against the optics reference in the edge zone (the colour error sampling, "
    "demosaicking and misregistration made at the edge)",
    lambda c: _mean(delta_e(c.lab, c.lab_optics), c.edge_zone), _is_edge))
SPATIAL_METRICS.register("mtf50_cy_per_px", Metric(
    "slanted edges: frequency where the e-SFR of the displayed luminance Y falls to 0.5 (None: no usable edge)",
    lambda c: None if c.esfr_luminance is None else _finite(c.esfr_luminance.mtf50_cy_per_px), _is_edge))
SPATIAL_METRICS.register("mtf50_channels_cy_per_px", Metric(
    "slanted edges: MTF50 of each processed channel (None where the channel sees no usable step)",
    lambda c: {k: None if r is None else _finite(r.mtf50_cy_per_px) for k, r in c.esfr_channels.items()},
    _is_edge))
SPATIAL_METRICS.register("patch_delta_e", Metric(
    "tilted chart: mean over the patches of their mean CIELAB ΔE*ab against the scene reference",
    lambda c: float(np.mean([delta_e(c.lab, c.lab_reference)[m].mean()
                             for m in c.target.patch_masks(c.geometry) if m.any()])),
    lambda t: isinstance(t, TiltedChart)))


def _zone_plate_annulus(c: ScoringContext, beyond: bool) -> np.ndarray:
    u, w = c.geometry.pixel_centres_mm()
    k = c.geometry.object_distance_mm / c.geometry.image_distance_mm / c.geometry.object_pixel_mm
    r = np.hypot(u[None, :] * k, w[:, None] * k)
    nyq = c.target.nyquist_radius_px()
    return c.region & ((r > nyq) if beyond else (r <= nyq))


SPATIAL_METRICS.register("aliasing_delta_e", Metric(
    "zone plates: mean S-CIELAB ΔE*ab against the own reference where the plate's frequency exceeds the "
    "Nyquist frequency (the reference is flat there: what is left is aliasing)",
    lambda c: _mean(c.scielab_own_map, _zone_plate_annulus(c, True)), lambda t: isinstance(t, ZonePlate)))
SPATIAL_METRICS.register("passband_delta_e", Metric(
    "zone plates: mean S-CIELAB ΔE*ab against the own reference where the frequency is below Nyquist",
    lambda c: _mean(c.scielab_own_map, _zone_plate_annulus(c, False)), lambda t: isinstance(t, ZonePlate)))

#: Metrics with one number per image (the others are per-channel dicts).
SCALAR_METRICS = tuple(n for n in SPATIAL_METRICS if n != "mtf50_channels_cy_per_px")


def score_image(ctx: ScoringContext) -> dict:
    """``{metric: value}`` of every registered metric (None where it does not apply to the target).

    Parameters
    ----------
    ctx : ScoringContext
        The image, its reference and target.

    Returns
    -------
    dict
        Metric name (of :data:`SPATIAL_METRICS`) → value.
    """
    return {name: (m.compute(ctx) if m.applies(ctx.target) else None) for name, m in SPATIAL_METRICS.items()}


def mtf_curves(ctx: ScoringContext) -> dict | None:
    """The e-SFR of Y and of every channel (edges), each cut to Y's frequencies; None for other targets.

    Parameters
    ----------
    ctx : ScoringContext

    Returns
    -------
    dict or None
        ``frequencies_cy_per_px``, ``Y`` and each channel's SFR (empty where no edge was found), ``edge_angle_deg``.
    """
    if not _is_edge(ctx.target):
        return None
    lum = ctx.esfr_luminance
    n_y = 0 if lum is None else lum.sfr.size
    curves = {"Y": [] if lum is None else lum.sfr.tolist()}
    for k, r in ctx.esfr_channels.items():
        curves[k] = [] if r is None else r.sfr[:min(r.sfr.size, n_y)].tolist()
    return {"frequencies_cy_per_px": [] if lum is None else lum.frequencies_cy_per_px.tolist(), **curves,
            "edge_angle_deg": None if lum is None else lum.edge_angle_deg}


@dataclass(frozen=True)
class SpatialRow:
    """The scores of one design on one case (pixel pitch × f-number) and target: the metrics of
    :data:`SPATIAL_METRICS` (means over the noise seeds; None where a metric does not apply), their 95 %
    intervals over the seeds (Student t; only with noise and more than one seed), capture time, defocus."""

    design: str
    demosaic: str | None
    misregistration_px: float
    olpf_separation_px: float
    label: str
    pixel_pitch_um: float
    f_number: float
    target: str
    metrics: dict
    capture_time_ms: float
    defocus_max_um: float
    seeds: int = 1
    interval95: dict = field(default_factory=dict)
    by_seed: dict = field(default_factory=dict)

    def __getattr__(self, name):   # row.mtf50_cy_per_px, row.false_colour, …: the metrics by name
        metrics = self.__dict__.get("metrics", {})
        if name in metrics:
            return metrics[name]
        raise AttributeError(name)

    def to_dict(self) -> dict:
        """The row as results.json holds it: metrics flattened, intervals as ``<metric>_ci95``."""
        out = {"design": self.design, "demosaic": self.demosaic, "misregistration_px": self.misregistration_px,
               "olpf_separation_px": self.olpf_separation_px, "label": self.label,
               "pixel_pitch_um": self.pixel_pitch_um, "f_number": self.f_number, "target": self.target,
               **self.metrics, "capture_time_ms": self.capture_time_ms, "defocus_max_um": self.defocus_max_um,
               "seeds": self.seeds}
        out.update({f"{k}_ci95": v for k, v in self.interval95.items()})
        if self.by_seed:
            out["by_seed"] = self.by_seed
        return out


def seed_summary(per_seed: list[dict]) -> tuple[dict, dict, dict]:
    """``(means, 95 % intervals, values by seed)`` of the scalar metrics of several seeds' scores
    (the per-channel MTF50s: means only). With one seed: its values and no intervals.

    Parameters
    ----------
    per_seed : list of dict
        :func:`score_image`'s per seed (the same keys).

    Returns
    -------
    tuple of (dict, dict, dict)
        Means; 95 % Student-t intervals ``[low, high]`` of the mean; the values by seed.
    """
    from scipy import stats

    if len(per_seed) == 1:
        return dict(per_seed[0]), {}, {}
    means, intervals, by_seed = {}, {}, {}
    n = len(per_seed)
    t = float(stats.t.ppf(0.975, n - 1))
    for name in per_seed[0]:
        vals = [s[name] for s in per_seed]
        if name == "mtf50_channels_cy_per_px" and vals[0] is not None:
            means[name] = {k: _mean_or_none([v[k] for v in vals]) for k in vals[0]}
            continue
        if any(v is None for v in vals):
            means[name] = _mean_or_none(vals)
            continue
        a = np.asarray(vals, float)
        m, half = float(a.mean()), t * float(a.std(ddof=1)) / np.sqrt(n)
        means[name], intervals[name], by_seed[name] = m, [m - half, m + half], a.tolist()
    return means, intervals, by_seed


def _mean_or_none(values):
    v = [x for x in values if x is not None]
    return float(np.mean(v)) if v else None
