"""The spatial experiment: the paper's next step ("incorporate spatial factors to understand how the
elimination of demosaicing provides a spatial advantage for FSC").

For each pixel pitch × f-number (a *case*) and each target of :data:`SPATIAL_TARGETS` (the neutral
slanted edge, four coloured slanted edges, a luminance and a chroma zone plate, a Siemens star, a tilted
ColorChecker) the target is rendered on a sub-pixel grid (:mod:`.render`), filtered by the optics and
sampled by each design (:mod:`.optics`, :mod:`.capture`) — every mosaic with each demosaicking method
with and without an optical low-pass filter, a prism aligned and misaligned, anything else once —
processed to the display and scored (:mod:`.score`) against the scene band-limited to the sensor's
Nyquist frequency (aliasing counts as error) and against the same camera's rendering of it (the
spatial error alone). With ``noise = true`` every design is captured with ``seeds`` noise seeds and
each metric is their mean with a 95 % interval.

The steps: :func:`render_case` (one render per target and pitch, per f-number for the tilted chart),
:func:`case_optics` (every distinct channel through the optics once), :func:`capture_design` (sampling,
recording, processing), :func:`score_design` (the metrics, over seeds). Stages are timed.
"""
from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, TypedDict

import numpy as np

from spectracam.camera import CAMERA_TABLES, CameraSpec, band_weights, photo_electron_rates
from spectracam.processing.color import DEMOSAIC_METHODS
from spectracam.core.errors import ConfigError
from spectracam.scene.reference import ChartReference
from spectracam.core.spec import Spec
from spectracam.experiments.spatial import optics as sopt
from spectracam.experiments.spatial.capture import (Conversion, SpatialDesign, misregistration_shifts, process, radiance_to_display_xyz, record,
                      white_rate)
from spectracam.core.registry import Registry
from spectracam.experiments.spatial.geometry import CameraGeometry
from spectracam.experiments.spatial.render import SubpixelCube, defocus_diameter_um, material_radiance, render_target
from spectracam.evaluation.scielab import samples_per_degree
from spectracam.experiments.spatial.score import SCORE_BORDER_PX, ScoringContext, SpatialRow, mtf_curves, score_image, seed_summary
from spectracam.experiments.spatial.targets import BRIGHT_NEUTRAL, DARK_NEUTRAL, ColouredEdge, SiemensStar, SlantedEdge, Target, TiltedChart, ZonePlate

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

    from spectracam.pipeline.scene_file import Scene

STAGES = ("render", "optics", "capture", "processing", "metrics")
#: The scene references a spatial image is scored against (docs/metrics.md): the scene band-limited to
#: the Nyquist frequency (aliasing counts), or each pixel's box footprint (aliasing invisible).
REFERENCES = ("nyquist", "footprint")
__all__ = ["SCORE_BORDER_PX", "SPATIAL_TARGETS", "SpatialResult", "SpatialSpec", "load_spatial", "run_spatial"]


@dataclass(frozen=True)
class TargetCase:
    """A target as one case frames it: the target, its image size (width, height) px, the object-plane
    field width it fills, mm, sub-pixels per pixel side and samples per sub-pixel."""

    target: Target
    size_px: tuple
    field_mm: float
    supersampling: int
    samples_per_subpixel: int


#: name → ``builder(spec, scene) -> TargetCase``: the targets ``targets`` may name.
SPATIAL_TARGETS: Registry = Registry("targets", "spatial target")


def _edge(patches=None):
    def build(spec, scene):
        w, h = spec.edge_size_px
        t = SlantedEdge(angle_deg=spec.edge_angle_deg, dataset=scene.chart.dataset) if patches is None else \
            ColouredEdge(angle_deg=spec.edge_angle_deg, dataset=scene.chart.dataset, patches=patches)
        return TargetCase(t, (w, h), w * spec.object_pixel_mm, spec.supersampling, spec.samples_per_subpixel)
    return build


def _zone_plate(patches):
    def build(spec, scene):
        w, h = spec.zone_plate_size_px
        t = ZonePlate(patches=patches, radius_px=0.5 * min(w, h), max_frequency_cy_per_px=spec.zone_plate_max_cy_per_px,
                      dataset=scene.chart.dataset)
        return TargetCase(t, (w, h), w * spec.object_pixel_mm, spec.supersampling, spec.samples_per_subpixel)
    return build


def _star(spec, scene):
    w, h = spec.star_size_px
    t = SiemensStar(cycles=spec.star_cycles, radius_px=0.47 * min(w, h), dataset=scene.chart.dataset)
    return TargetCase(t, (w, h), w * spec.object_pixel_mm, spec.supersampling, spec.star_samples_per_subpixel)


def _chart(spec, scene):
    w, h = spec.chart_size_px
    return TargetCase(TiltedChart(tilt_deg=spec.chart_tilt_deg, chart=scene.chart), (w, h), spec.chart_field_mm,
                      spec.chart_supersampling, spec.samples_per_subpixel)


SPATIAL_TARGETS.register("edge", _edge())                                    # the two neutrals, 4:1 (ISO 12233)
SPATIAL_TARGETS.register("edge_red_cyan", _edge(("red", "cyan")))            # opposite hues, L* 40.7 / 51.8
SPATIAL_TARGETS.register("edge_blue_yellow", _edge(("blue", "yellow")))      # opposite hues, L* 29.7 / 81.5
SPATIAL_TARGETS.register("edge_skin", _edge(("dark skin", "light skin")))    # a natural pair, small chroma step
SPATIAL_TARGETS.register("edge_foliage_sky", _edge(("foliage", "blue sky")))  # a natural pair, mostly chroma
SPATIAL_TARGETS.register("zone_plate", _zone_plate((DARK_NEUTRAL, BRIGHT_NEUTRAL)))   # luminance
SPATIAL_TARGETS.register("zone_plate_chroma", _zone_plate(("magenta", "cyan")))      # chroma: L* 51.0 / 51.8
SPATIAL_TARGETS.register("star", _star)
SPATIAL_TARGETS.register("chart", _chart)
TARGETS = SPATIAL_TARGETS.names


@dataclass(frozen=True)
class SpatialSpec(Spec):
    """The experiment's own parameters (top-level keys of ``--set``); each default with its reason."""

    #: The paper's 10 µm pixel, and a 2 µm pixel where diffraction at f/8 matters (Airy disc 10.7 µm at 550 nm).
    pixel_pitches_um: tuple = (10.0, 2.0)
    #: The paper's f/1.4, and f/8.
    f_numbers: tuple = (1.4, 8.0)
    targets: tuple = TARGETS
    #: The paper's three architectures with the paper's best exposure for each; any registered
    #: ``arch/scheme`` (``spectracam architectures`` runs them all).
    designs: tuple = ("cfa/single", "prism/optimal", "fsc/optimal")
    #: colour-demosaicing's three methods (the registry's ``patch`` is the paper's flat-patch reading).
    demosaics: tuple = ("bilinear", "malvar2004", "menon2007")
    #: The prism aligned, and misaligned by half a pixel (red along x, blue along y).
    misregistrations_px: tuple = (0.0, 0.5)
    #: Mosaics without (0, the paper's camera) and with a 4-spot birefringent optical low-pass filter of
    #: one pixel's spot separation (first zero at the Nyquist frequency: the usual choice).
    olpf_separations_px: tuple = (0.0, 1.0)
    #: A short lens makes the tilted chart's perspective visible (≈18° across the 10 µm sensor).
    focal_length_mm: float = 12.0
    #: Sub-pixels per pixel side: the renders' box filter is divided out exactly by the optics stage.
    supersampling: int = 4
    samples_per_subpixel: int = 4
    #: The star has no defocus to sample: 2 per sub-pixel (32 per pixel) leave ~0.1 % noise on flat areas.
    star_samples_per_subpixel: int = 2
    #: The tilted chart is scored by S-CIELAB on patches, not by its MTF: 2×2 sub-pixels (the optics stage
    #: divides the sub-pixel box out exactly) and 4 thin-lens samples each cut its renders fourfold.
    chart_supersampling: int = 2
    #: ISO 12233 region: 128 × 128 pixels around a 5° edge of 4:1 contrast.
    edge_size_px: tuple = (128, 128)
    edge_angle_deg: float = 5.0
    star_size_px: tuple = (256, 256)
    #: 36 cycles: the spokes reach the Nyquist frequency 36/π = 11.5 px from the centre.
    star_cycles: int = 36
    chart_size_px: tuple = (384, 256)
    #: The zone plates: 128 × 128 px, local frequency rising to 1 cy/px (twice Nyquist) at the inscribed radius.
    zone_plate_size_px: tuple = (128, 128)
    zone_plate_max_cy_per_px: float = 1.0
    #: Turned 40° about the vertical axis: the right edge is ~90 mm farther than the left.
    chart_tilt_deg: float = 40.0
    chart_field_mm: float = 300.0
    #: Object-plane size of a pixel for the edge and the star (their scale does not matter: they are in focus).
    object_pixel_mm: float = 0.5
    #: Sensor noise of the paper's camera (off: the spatial artefacts alone, noise-free and unquantised).
    noise: bool = False
    #: Noise seeds per design when ``noise`` is on (seed, seed + 1, …): each metric their mean with a 95 %
    #: Student-t interval; a noise-free capture is deterministic and taken once.
    seeds: int = 3
    #: The scene reference (see :data:`REFERENCES`): ``nyquist`` so that aliasing is scored.
    reference: str = "nyquist"
    #: ISO 12233:2017's e-SFR as the standard states it; true adds the binning correction of
    #: :func:`spectracam.evaluation.esfr.esfr` (not in the standard: +1.6–2.2 % MTF50 here).
    esfr_correct_binning: bool = False
    cos4: bool = False
    #: S-CIELAB viewing: one image pixel per display pixel of 120 dpi seen from 0.5 m (ISETCam's default, 41 px/°).
    viewing_distance_m: float = 0.5
    display_pixel_pitch_mm: float = 25.4 / 120
    seed: int = 0

    def _number_list(self, name: str, lo: float, allowed: str, **kw) -> None:
        """A non-empty list of numbers ≥ ``lo``; a single number (``--set olpf_separations_px=1``) or any other
        non-list is refused by name before its length is asked for (issue 34: it was a TypeError)."""
        v = getattr(self, name)
        if not isinstance(v, tuple) or not v:
            example = [float(x) for x in type(self).__dataclass_fields__[name].default]   # the default
            raise self.error(name, f"must be a non-empty list of {allowed}, e.g. {example}", list(v)
                             if isinstance(v, tuple) else v)
        self.numbers(name, len(v), lo, **kw)

    def validate(self) -> None:
        self._number_list("pixel_pitches_um", 0.1, "pixel pitches > 0.1 µm", lo_open=True, unit="µm")
        self._number_list("f_numbers", 0.5, "f-numbers ≥ 0.5", unit="")
        for name, allowed in (("targets", SPATIAL_TARGETS.names), ("demosaics", DEMOSAIC_METHODS.names)):
            v = getattr(self, name)
            if not isinstance(v, tuple) or not v or any(x not in allowed for x in v):
                raise self.error(name, "must be a non-empty list of " + ", ".join(map(repr, allowed)),
                                 list(v) if isinstance(v, tuple) else v)
        if "patch" in self.demosaics:
            raise self.error("demosaics", "'patch' reads flat patches only; use bilinear, malvar2004, menon2007",
                             list(self.demosaics))
        from spectracam.camera import split_design

        if not isinstance(self.designs, tuple) or not self.designs:
            raise self.error("designs", "must be a non-empty list of 'arch/scheme', e.g. ['cfa/single', 'fsc/optimal']",
                             list(self.designs) if isinstance(self.designs, tuple) else self.designs)
        for d in self.designs:
            split_design(d, "designs")
        self._number_list("olpf_separations_px", 0.0, f"separations from 0 to {sopt.MARGIN_PX / 2:g} px (0: no filter)",
                          unit="px")
        if any(x > sopt.MARGIN_PX / 2 for x in self.olpf_separations_px):
            raise self.error("olpf_separations_px", f"must be a non-empty list of separations from 0 to "
                             f"{sopt.MARGIN_PX / 2:g} px (0: no filter)", list(self.olpf_separations_px))
        self._number_list("misregistrations_px", 0.0, f"misregistrations from 0 to {sopt.MARGIN_PX / 2:g} px", unit="px")
        if any(m > sopt.MARGIN_PX / 2 for m in self.misregistrations_px):
            raise self.error("misregistrations_px", f"must be at most {sopt.MARGIN_PX / 2:g} px",
                             list(self.misregistrations_px))
        if not self.pixel_pitches_um or not self.f_numbers or not self.misregistrations_px:
            raise self.error("pixel_pitches_um", "pitches, f-numbers and misregistrations need one value each")
        self.number("focal_length_mm", 1.0, 1000.0, unit="mm")
        self.integer("supersampling", 1, 16)
        self.integer("samples_per_subpixel", 1, 1024)
        self.integer("star_samples_per_subpixel", 1, 1024)
        self.integer("chart_supersampling", 1, 16)
        for name in ("edge_size_px", "star_size_px", "chart_size_px", "zone_plate_size_px"):
            self.numbers(name, 2, 32.0, unit="px")
            object.__setattr__(self, name, tuple(int(x) for x in getattr(self, name)))
        self.number("edge_angle_deg", 2.0, 10.0, unit="°")
        self.integer("star_cycles", 4, 720)
        self.number("chart_tilt_deg", 0.0, 70.0, unit="°")
        self.number("chart_field_mm", 10.0, 10000.0, unit="mm")
        self.number("object_pixel_mm", 1e-4, 1e3, lo_open=True, unit="mm")
        self.boolean("noise", "cos4", "esfr_correct_binning")
        self.integer("seeds", 1, 1000)
        self.number("zone_plate_max_cy_per_px", 0.05, 4.0, unit="cy/px")
        if self.reference not in REFERENCES:
            raise self.error("reference", "must be one of " + ", ".join(map(repr, REFERENCES)), self.reference)
        self.number("viewing_distance_m", 0.0, 100.0, lo_open=True, unit="m")
        self.number("display_pixel_pitch_mm", 0.0, 100.0, lo_open=True, unit="mm")
        self.integer("seed", 0, 2**31 - 1)
        self.spatial_designs()   # a mosaic no demosaicking method takes is refused here

    @property
    def samples_per_degree(self) -> float:
        return samples_per_degree(self.viewing_distance_m, self.display_pixel_pitch_mm * 1e-3)

    def spatial_designs(self) -> list[SpatialDesign]:
        """Each design of ``designs`` with the variants its layout takes (:data:`DESIGN_VARIANTS`)."""
        out = []
        for design in self.designs:
            layout = CameraSpec().with_design(design).architecture().layout
            out += DESIGN_VARIANTS[variant_kind(layout)](self, design, layout)
        return out

    def quick(self) -> "SpatialSpec":
        """A first look: every case, target and design at half the image size (and 20-nm bands, see
        :func:`load_spatial`), 2 samples per sub-pixel."""
        half = lambda t: tuple(max(32, int(x) // 2) for x in t)  # noqa: E731
        return self.replace(edge_size_px=half(self.edge_size_px), star_size_px=half(self.star_size_px),
                            zone_plate_size_px=half(self.zone_plate_size_px),
                            chart_size_px=half(self.chart_size_px), star_cycles=max(4, self.star_cycles // 2),
                            samples_per_subpixel=min(self.samples_per_subpixel, 2),
                            star_samples_per_subpixel=min(self.star_samples_per_subpixel, 2),
                            object_pixel_mm=self.object_pixel_mm * 2)


#: How a design is varied in space, by its layout (:func:`variant_kind`): kind →
#: ``variants(spec, design, layout) -> [SpatialDesign]``.
DESIGN_VARIANTS: Registry = Registry("designs", "spatial design variants")


def variant_kind(layout) -> str:
    """``"mosaic"`` for a colour filter array, the planes' kind (``"sensors"``, ``"frames"``, ``"layers"``) else."""
    from spectracam.architecture.base import MosaicLayout

    if isinstance(layout, MosaicLayout):
        return "mosaic"
    return layout.kind if layout.kind in DESIGN_VARIANTS.names else "once"


@DESIGN_VARIANTS.register("mosaic")
def _mosaic_variants(spec: SpatialSpec, design: str, layout) -> list:
    """Every demosaicking method that takes the mosaic, each with every optical low-pass filter."""
    from spectracam.processing.color import demosaic_applies

    methods = [dm for dm in spec.demosaics if demosaic_applies(dm, layout)]
    if not methods:
        raise spec.error("demosaics", f"none of them takes {design}'s {len(layout.channels)}-channel "
                         "mosaic; add 'bilinear' (any periodic mosaic)", list(spec.demosaics))
    return [SpatialDesign(design, dm, None, o) for dm in methods for o in spec.olpf_separations_px]


@DESIGN_VARIANTS.register("sensors")
def _sensor_variants(spec: SpatialSpec, design: str, layout) -> list:
    """Separate sensors (a prism): every misregistration."""
    return [SpatialDesign(design, None, m) for m in spec.misregistrations_px]


@DESIGN_VARIANTS.register("once")
def _once(spec: SpatialSpec, design: str, layout) -> list:
    """Every channel at every pixel on one sensor (field-sequential frames, stacked layers): nothing to vary."""
    return [SpatialDesign(design)]


#: Tables of a scene file the experiment takes its light, bands, camera and processing from.
SCENE_KEYS = ("illuminant", "wavelengths", "chart", "render", *CAMERA_TABLES, "processing")


def load_spatial(sets: Sequence[str] = (), quick: bool = False) -> tuple[SpatialSpec, Scene]:
    """``(SpatialSpec, Scene)`` from ``--set`` overrides: top-level keys are the experiment's, tables
    (``illuminant``, ``wavelengths``, ``sensor``, ``optics``, ``filters``, ``processing``, …) the scene's,
    over the paper's camera and light (``scenes/paper.toml``, as ``spectracam paper`` and ``motion``).

    Parameters
    ----------
    sets : sequence of str
        ``--set PATH=VALUE``.
    quick : bool
        ``--quick``: the spec's quick variant and 20-nm bands.

    Returns
    -------
    tuple of (SpatialSpec, Scene)
        The validated spec and scene.
    """
    from spectracam.pipeline.scene_file import paper_scene

    return load_spec_and_scene(SpatialSpec, sets, quick, base_scene=paper_scene())   # the paper's camera


def load_spec_and_scene(spec_cls, sets=(), quick: bool = False, base_scene=None):
    """``(spec_cls spec, Scene)`` from ``--set`` overrides (the spatial and the motion experiments):
    top-level keys are the experiment's, tables the scene's (over ``base_scene``'s tables when given,
    else the defaults); ``quick``: the spec's ``quick()`` and 20-nm bands."""
    from spectracam.pipeline.overrides import apply_overrides
    from spectracam.pipeline.scene_file import Scene

    data = apply_overrides({}, sets, defaults=lambda: spec_cls().to_dict())  # key[i] sets one element
    own = {k: v for k, v in data.items() if not isinstance(v, dict)}
    tables = {k: v for k, v in data.items() if isinstance(v, dict)}
    for k in tables:
        if k not in SCENE_KEYS:
            raise ConfigError(k, tables[k], "unknown table; --set takes the experiment's keys ("
                              + ", ".join(f.name for f in dataclasses.fields(spec_cls)) + ") or the tables "
                              + ", ".join(SCENE_KEYS), "--set")
    spec = spec_cls.from_dict(own, "--set")
    if quick:  # the quick look's sizes, except what --set chose
        spec = spec.quick().replace(**{k: getattr(spec, k) for k in own})
        tables.setdefault("wavelengths", {"start_nm": 400, "stop_nm": 700, "step_nm": 20})
    scene = Scene.from_dict(tables, "--set", base=base_scene)   # a --set key changes one entry of the base
    return spec, scene




# ------------------------------------------------------------------------------------------------


def case_camera(scene, spec: SpatialSpec, pitch_um: float, f_number: float) -> CameraSpec:
    cam = scene.camera
    sensor = cam.sensor.replace(pixel_pitch_um=float(pitch_um))
    if not spec.noise:
        sensor = sensor.off("shot_noise", "dark_current", "read_noise", "fpn", "quantization")
    return cam.replace(sensor=sensor, optics=cam.optics.replace(f_number=float(f_number)))


@dataclass
class _Run:
    """What a run accumulates: rows, MTF curves, images, closed forms, renders, stage timings."""

    spec: SpatialSpec
    scene: object
    renderer: str
    log: object
    keep_images: bool
    reference: ChartReference
    designs: list
    timings: dict
    rows: list = dataclasses.field(default_factory=list)
    curves: list = dataclasses.field(default_factory=list)
    images: dict = dataclasses.field(default_factory=dict)
    closed: dict = dataclasses.field(default_factory=dict)
    renders: dict = dataclasses.field(default_factory=dict)

    def timed(self, target: str, stage: str, t0: float) -> float:
        t1 = time.perf_counter()
        self.timings[target][stage] += t1 - t0
        return t1


@dataclass(frozen=True)
class Case:
    """One pixel pitch × f-number: the camera without a design, its channels, the renders' margin."""

    pixel_pitch_um: float
    f_number: float
    camera: CameraSpec
    columns: np.ndarray          # (B, M) every distinct channel's band weights among the designs
    design_columns: dict         # design → column indices
    margin_px: int

    def as_dict(self) -> dict:
        return {"pixel_pitch_um": float(self.pixel_pitch_um), "f_number": float(self.f_number)}


class SpatialResult(TypedDict):
    """What :func:`run_spatial` returns (:func:`_result`).  The writer
    (:func:`spectracam.experiments.spatial.report.write_outputs`) makes results.json of it without ``images`` and
    ``mtf_curves`` (those go to the case files and mtf_curves.json), ``rows`` as dicts, ``display_white`` as a
    list, and ``figures`` and ``command`` added.  ``images``: (pitch µm, f-number, target, design label or
    ``"reference"``) → that image's arrays."""

    rows: list[SpatialRow]
    mtf_curves: list[dict]
    timings: dict[str, dict[str, float]]
    images: dict[tuple, dict]
    closed_form: dict[str, dict[str, list[float]]]
    display_white: np.ndarray
    samples_per_degree: float
    renderer: str
    render_metadata: dict[str, dict]
    parameters: dict
    wall_s: float


def run_spatial(spec: SpatialSpec, scene: Scene, renderer: str = "mitsuba", log: Callable[[str], object] | None = None,
                keep_images: bool = True, progress: bool = False) -> SpatialResult:
    """Run every case × target × design. Returns ``{"rows": [SpatialRow], "mtf_curves", "timings",
    "images", "closed_form", ...}``.  ``progress``: a bar over the cases' targets on a terminal.

    Parameters
    ----------
    spec : SpatialSpec
        Pixel pitches (µm), f-numbers, targets, designs, demosaickers, OLPFs, misregistrations.
    scene : Scene
        The camera, light and processing.
    renderer : str
        ``"mitsuba"`` or ``"analytic"``.
    log : callable or None
        ``log(line)`` per case.
    keep_images : bool
        Keep each case's images in the result (for the report's figures).
    progress : bool

    Returns
    -------
    SpatialResult
        The rows, MTF curves, timings, images (with ``keep_images``) and the closed-form checks.
    """
    from spectracam.core.progress import bar

    run = _Run(spec, scene, renderer, log or (lambda msg: None), keep_images, ChartReference.of(scene),
               spec.spatial_designs(), {t: dict.fromkeys(STAGES, 0.0) for t in spec.targets})
    t_start = time.perf_counter()
    with bar(total=len(spec.pixel_pitches_um) * len(spec.f_numbers) * len(spec.targets), desc="spatial cases",
             unit="target", progress=progress) as targets:
        for pitch in spec.pixel_pitches_um:
            # one margin per pitch (flat targets are rendered once per pitch): wide enough for the slowest lens
            margin = max(sopt.margin_px(pitch, N, scene.grid.edges_nm[-1], max(spec.misregistrations_px))
                         for N in spec.f_numbers)
            for N in spec.f_numbers:
                camera = case_camera(scene, spec, pitch, N)
                case = Case(float(pitch), float(N), camera, *channel_columns(camera, scene.grid, spec.designs),
                            margin)
                for tname in spec.targets:
                    run_target(run, case, tname)
                    run.log(f"[{time.perf_counter() - t_start:6.1f} s] {pitch:g} µm, f/{N:g}, {tname}: "
                            f"{len(run.designs)} designs scored")
                    targets.update(1)
    return _result(run, time.perf_counter() - t_start)


def render_case(run: _Run, case: Case, tname: str, tc: TargetCase, geometry: CameraGeometry) -> SubpixelCube:
    """The target's sub-pixel render with the case's margin: flat targets in focus look the same at every
    f-number (one render per pitch); the tilted chart is rendered per f-number (its defocus)."""
    key = (tname, case.pixel_pitch_um, case.f_number if isinstance(tc.target, TiltedChart) else None)
    if key not in run.renders:
        run.renders[key] = render_target(run.renderer, tc.target, geometry.with_margin(case.margin_px),
                                         run.scene.illuminant, run.scene.grid, tc.supersampling,
                                         tc.samples_per_subpixel, run.spec.seed + len(run.renders),
                                         run.scene.render.variant, run.log)
    return run.renders[key]


def reference_radiance(cube: SubpixelCube, reference: str, margin_px: int) -> np.ndarray:
    """``(H, W, B)`` scene reference radiance (see :data:`REFERENCES`), the margin cut off."""
    full = cube.band_limited() if reference == "nyquist" else cube.pixel_average()
    return full[margin_px:-margin_px, margin_px:-margin_px]


def run_target(run: _Run, case: Case, tname: str) -> None:
    """One target of one case through every design: render, optics, then capture and score each design."""
    spec, scene = run.spec, run.scene
    tc = SPATIAL_TARGETS.get(tname)(spec, scene)
    w, h = tc.size_px
    geometry = CameraGeometry.framing(tc.field_mm, spec.focal_length_mm, case.f_number, case.pixel_pitch_um, w, h)
    if isinstance(tc.target, TiltedChart):
        geometry = dataclasses.replace(geometry, focus_distance_mm=geometry.object_distance_mm)
    t0 = time.perf_counter()
    cube = render_case(run, case, tname, tc, geometry)
    t0 = run.timed(tname, "render", t0)
    settings = sopt.OpticsSettings(defocus_um=defocus_diameter_um(tc.target, geometry.with_margin(case.margin_px),
                                                                  cube), cos4=spec.cos4)
    spectra = sopt.channel_spectra(cube.radiance, cube.wavelengths_nm, tc.supersampling, case.camera, scene.grid,
                                   settings, workers=-1, weights=case.columns)
    reference = reference_radiance(cube, spec.reference, case.margin_px)
    # the reference's XYZ at the display white: the adaptation depends on the scene and the display, not
    # on the design, so it is computed once per target
    reference_xyz = radiance_to_display_xyz(reference, scene.grid, scene.illuminant.white_luminance_cd_m2,
                                            Conversion.fit(run.reference, case.camera, scene.processing))
    if isinstance(tc.target, SlantedEdge) and tname == "edge":
        run.closed[(case.pixel_pitch_um, case.f_number)] = closed_form_mtfs(run, case, tc.target)
    t0 = run.timed(tname, "optics", t0)
    sampled: dict = {}
    for d in run.designs:
        rates = sample_design(run, case, d, spectra, tc, geometry, sampled, tname)
        cosited = sample_design(run, case, SpatialDesign(d.design, olpf_separation_px=d.olpf_separation_px), spectra,
                                tc, geometry, sampled, tname)   # the optics reference's rates
        score_design(run, case, tname, tc.target, geometry, d, rates, reference, reference_xyz, cosited)
    if run.keep_images:
        run.images[(case.pixel_pitch_um, case.f_number, tname, "reference")] = {"xyz": reference_xyz.astype(np.float32)}


def sample_design(run: _Run, case: Case, d: SpatialDesign, spectra, tc: TargetCase, geometry, sampled: dict,
                  tname: str) -> np.ndarray:
    """``(H, W, N)`` photo-electron rates the design's pixels collect (each distinct channel set, shift and
    low-pass filter sampled once per target)."""
    t0 = time.perf_counter()
    spectra_, fy, fx, shape = spectra
    shifts = misregistration_shifts(d.misregistration_px)
    cols = case.design_columns[d.design]
    key = (cols, shifts, d.olpf_separation_px)
    if key not in sampled:
        rates = sopt.sample_channels(spectra_[list(cols)], fy, fx, shape, tc.supersampling,
                                     case.camera.sensor.fill_factor, shifts, case.margin_px, workers=-1,
                                     olpf_separation_px=d.olpf_separation_px)
        if run.spec.cos4:
            rates *= geometry.off_axis_cos4()[:, :, None].astype(np.float32)
        sampled[key] = rates
    run.timed(tname, "optics", t0)
    return sampled[key]


def score_design(run: _Run, case: Case, tname: str, target: Target, geometry: CameraGeometry, d: SpatialDesign,
                 rates: np.ndarray, reference: np.ndarray, reference_xyz: np.ndarray, cosited: np.ndarray) -> None:
    """Record, process and score one design (over the noise seeds) against the scene reference (``reference``
    radiance, ``reference_xyz`` at the display white), the own
    reference and the optics reference (``cosited``: every channel's noise-free rate at every pixel centre);
    append its row, MTF curves and images."""
    spec, scene = run.spec, run.scene
    camera = case.camera.with_design(d.design)
    processing = scene.processing.replace(demosaic=d.demosaic or scene.processing.demosaic)
    conv = Conversion.fit(run.reference, camera, processing)
    own_xyz = photo_electron_rates(reference.astype(np.float32), scene.grid, camera).astype(np.float64) \
        @ conv.matrix @ conv.rgb_to_xyz.T
    optics_xyz = cosited.astype(np.float64) @ conv.matrix @ conv.rgb_to_xyz.T
    scores, first = [], None
    for s in range(spec.seeds if spec.noise else 1):
        t0 = time.perf_counter()
        raw = record(rates, camera, white_rate(run.reference, camera), spec.seed + s)
        t0 = run.timed(tname, "capture", t0)
        cam_rates, xyz = process(raw, processing, conv, run.reference)
        t0 = run.timed(tname, "processing", t0)
        ctx = ScoringContext(target, geometry, xyz, reference_xyz, own_xyz, optics_xyz, cam_rates, conv.display_white,
                             spec.samples_per_degree, tuple(raw.layout.channels), spec.esfr_correct_binning)
        scores.append(score_image(ctx))
        first = first or (ctx, raw)
        run.timed(tname, "metrics", t0)
    ctx, raw = first
    means, intervals, by_seed = seed_summary(scores)
    row = SpatialRow(d.design, d.demosaic, float(d.misregistration_px or 0.0), float(d.olpf_separation_px), d.label,
                     case.pixel_pitch_um, case.f_number, tname, means, 1e3 * raw.capture_time_s,
                     _max_defocus(target, geometry), len(scores), intervals, by_seed)
    run.rows.append(row)
    curves = mtf_curves(ctx)
    if curves is not None:
        run.curves.append({"label": d.label, **case.as_dict(), "target": tname, "design": d.design,
                           "demosaic": d.demosaic, "misregistration_px": row.misregistration_px,
                           "olpf_separation_px": row.olpf_separation_px, **curves})
    if run.keep_images:
        run.images[(case.pixel_pitch_um, case.f_number, tname, d.label)] = {
            "xyz": ctx.xyz.astype(np.float32), "scielab": ctx.scielab_own_map.astype(np.float32),
            "region": ctx.region, "seed": spec.seed}


def closed_form_mtfs(run: _Run, case: Case, edge: SlantedEdge) -> dict:
    """Closed-form MTF (diffraction × pixel aperture × optional low-pass filter, :mod:`.optics`) of the
    edge's G channel and of the displayed luminance Y (the channels mixed by the colour conversion's Y row),
    weighted by the edge's radiance step in each band."""
    spec, grid = run.spec, run.scene.grid
    L = material_radiance(edge, run.scene.illuminant, grid)
    W = np.asarray(band_weights(case.camera, grid), np.float64) * (L[1] - L[0])[:, None]     # (B, N)
    conv = Conversion.fit(run.reference, case.camera, run.scene.processing)
    y_row = (conv.matrix @ conv.rgb_to_xyz.T)[:, 1]
    f = np.linspace(0, 1, 201)
    out = {"frequencies_cy_per_px": f.tolist()}
    for o in (0.0, *[x for x in spec.olpf_separations_px if x > 0]):
        tail = f" OLPF {o:g} px" if o > 0 else ""
        for name, weights in (("G", W[:, 1]), ("Y", W @ y_row)):
            out[name + tail] = sopt.channel_mtf_closed_form(f, spec.edge_angle_deg, case.pixel_pitch_um, case.f_number,
                                                            grid.centres_nm, weights, case.camera.sensor.fill_factor,
                                                            o).tolist()
    return out


def _result(run: _Run, wall_s: float) -> dict:
    spec, scene = run.spec, run.scene
    first = case_camera(scene, spec, spec.pixel_pitches_um[0], spec.f_numbers[0])
    return {"rows": run.rows, "mtf_curves": run.curves, "timings": run.timings, "images": run.images,
            "closed_form": {f"{p:g}um_f{n:g}": v for (p, n), v in run.closed.items()},
            "display_white": Conversion.fit(run.reference, first, scene.processing).display_white,
            "samples_per_degree": spec.samples_per_degree, "renderer": run.renderer,
            "render_metadata": {f"{k[0]}_{k[1]:g}um" + (f"_f{k[2]:g}" if k[2] else ""): v.metadata
                                for k, v in run.renders.items()},
            "parameters": {"spatial": spec.to_dict(), "scene": scene.to_dict(),
                           "fill_factor": scene.camera.sensor.fill_factor,
                           "reference": {"nyquist": "the scene band-limited to 0.5 cy/px by an ideal low-pass, sampled "
                                                    "at the pixel centres",
                                         "footprint": "each pixel's box footprint of the scene"}[spec.reference],
                           "misregistration": "red sensor shifted +m px along x, blue +m px along y, before sampling",
                           "olpf": "4-spot birefringent filter: spots at (±d/2, ±d/2) px, OTF cos(π fx d)·cos(π fy d)"},
            "wall_s": wall_s}


def channel_columns(camera: CameraSpec, grid, designs) -> tuple[np.ndarray, dict]:
    """``(weights (B, M), {design: column indices})``: every distinct channel responsivity among the
    designs once (the paper's three architectures share R, G, B; RGBW adds W; …)."""
    cols, index, out = [], {}, {}
    for design in designs:
        W = np.asarray(band_weights(camera.with_design(design), grid), np.float64)
        ids = []
        for k in range(W.shape[1]):
            key = W[:, k].tobytes()
            if key not in index:
                index[key] = len(cols)
                cols.append(W[:, k])
            ids.append(index[key])
        out[design] = tuple(ids)
    return np.stack(cols, axis=1), out


def _max_defocus(target: Target, geometry: CameraGeometry) -> float:
    if isinstance(target, TiltedChart):
        lo, hi = target.depth_range_mm(geometry)
        return float(max(geometry.blur_diameter_um(lo), geometry.blur_diameter_um(hi)))
    return float(geometry.blur_diameter_um(geometry.object_distance_mm))
