"""The motion experiment: when does the field-sequential camera's SNR advantage become a perceptual loss?

A slanted edge between two ColorChecker neutrals (:class:`~spectracam.experiments.spatial.targets.SlantedEdge`,
5°, 4:1) moves horizontally at a sweep of speeds (px/ms on the sensor; mm/s in the scene in
results.json) while each design captures it — ``cfa/single``, ``prism/optimal``, ``fsc/optimal``,
``fsc/balanced`` — with a global and with a rolling shutter. The exposure times are the paper's
(white-patch metering, :mod:`spectracam.sensor.exposure`) at the paper's light level (``cfa/single`` needs
28 ms at 5000 K), the windows those of :mod:`.timing`, the image the time integral of Mitsuba slices
(:mod:`.render`) through the spatial optics (diffraction, pixel aperture), recorded by the
architecture's own ``record`` **with the paper's sensor noise**, demosaicked, converted to the display
and scored against the same design's noise-free still capture (the edge at rest at the capture's
middle instant, t = 0) and against the static scene there:

* ``breakup_width_px`` — :func:`.metrics.edge_channels`: how far apart the motion moves the colour
  channels' edges, to a fraction of a pixel: each camera channel's edge in the noise-free moving capture
  (its 50 % crossing, profiles binned along the slanted edge) against the same channel's in the design's
  own noise-free *still* capture (the edge at rest; the same exposures, demosaicking and conversion), the
  spread of those shifts (``channel_edge_shift_px``, per channel): colour breakup from the motion alone,
  0 at rest whatever the design's demosaicking false colour, ``v·(t_last − t_first)`` for frames in
  sequence (t: each window's middle), 0 for one shared window; ``edge_blur_px``: the channels' mean
  10–90 % rise (the blur, kept apart); ``breakup_threshold_width_px``: the width over which the chroma
  the motion adds exceeds ``breakup_threshold`` (the headline before issue 34: it counts blur and cannot
  read below two 0.5 px bins);
* ``false_colour_still`` — that still capture's chroma against the camera's conversion of the ideal image
  within 2 px of the edge, √(Δa*² + Δb*²): demosaicking false colour, its own metric;
* ``scielab_delta_e`` / ``cielab_delta_e`` — mean S-CIELAB / CIELAB ΔE*ab within ``zone_half_width_px``
  of the edge of the noisy capture against that still capture: what motion and noise add to the
  camera's own still photograph (at rest: the noise alone); mean over ``seeds`` noise seeds, ``_sd``
  their spread, ``scielab_delta_e_by_seed`` each;
* ``scielab_delta_e_scene`` / ``cielab_delta_e_scene`` / ``breakup_width_scene_px`` /
  ``breakup_threshold_width_scene_px`` — the same against the ideal image of the scene (the channels' edges
  against the scene's edge) (they also hold the conversion's constant error and the demosaicking false
  colour: what an observer comparing with the scene sees);
* ``mtf50_cy_per_px`` — e-SFR of the displayed luminance across the edge, as ISO 12233:2017 states it
  (``esfr_correct_binning``: with the binning correction the standard lacks);
* ``snr_db`` — the paper's SNR of the design (chart patches, combined over channels) with the same
  light, exposure and noise: a flat patch's SNR does not depend on the motion.

The answer — the speed at which ``fsc/optimal``'s S-CIELAB error (against its own still capture) first
exceeds ``cfa/single``'s — is interpolated between the swept speeds (linearly in speed), for the mean
over seeds and for each seed (mean and 95 % interval).

A run goes one way: :func:`prepare` (the scene, the framing, the moving target) → per design
:func:`design_model` → per shutter and speed :func:`render_at_speed` → :func:`capture` (per seed
:func:`capture_at_seed`) → :func:`score_case` (per seed :func:`score_capture`) → a :class:`MotionRow`.
"""
from __future__ import annotations

import contextlib
import math
import time
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, TypedDict

import numpy as np

from spectracam.camera import photo_electron_rates
from spectracam.scene.chart import WHITE_PATCH
from spectracam.core.errors import SpectracamError
from spectracam.sensor.exposure import exposure_times_s
from spectracam.core.cielab import delta_e, xyz_to_lab
from spectracam.scene.reference import ChartReference
from spectracam.core.spec import Spec
from spectracam.experiments.spatial import optics as sopt
from spectracam.experiments.spatial.capture import Conversion, process, radiance_to_display_xyz, record, white_rate
from spectracam.experiments.spatial.geometry import CameraGeometry
from spectracam.evaluation.scielab import samples_per_degree, scielab
from spectracam.experiments.spatial.targets import SlantedEdge
from spectracam.experiments.motion import metrics as mm
from spectracam.experiments.motion.motion import Motion
from spectracam.experiments.motion.render import RENDER_MODES, MovingScene, channel_rates, ideal_radiance, integrate
from spectracam.experiments.motion.timing import TimingSpec, capture_timing

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Iterator, Sequence

    from spectracam.camera import CameraSpec
    from spectracam.experiments.motion.timing import CaptureTiming
    from spectracam.pipeline.scene_file import Scene

__all__ = ["CAPTURE_OVER_CFA_EXPOSURE", "DESIGNS", "MEMORY_PER_SUBPIXEL_BYTES", "SCORE_BORDER_PX",
           "SEED_METRICS", "Capture", "DesignModel", "MotionEstimate", "MotionResult", "MotionRow", "MotionSetup",
           "MotionSpec", "StillReference", "calibrated_scene", "capture", "capture_at_seed", "case_speeds",
           "check_motion_memory", "crossing", "crossing_speeds", "design_model", "design_snr_db",
           "edge_distance_moving", "finite_or_none", "load_motion", "mean_or_none", "motion_camera",
           "motion_estimate", "prepare", "render_at_speed", "run_motion", "score_capture", "score_case",
           "sd_or_none", "seed_crossings", "series", "speed_mm_per_s", "still_reference", "sweep_speeds",
           "timed"]

DESIGNS = ("cfa/single", "prism/optimal", "fsc/optimal", "fsc/balanced")
SCORE_BORDER_PX = 4


@dataclass(frozen=True)
class MotionSpec(Spec):
    """The experiment's own parameters (top-level keys of ``--set``); each default with its reason."""

    #: From still to where fsc/optimal's ~120 ms smear the edge over ~40 px (a third of the image).
    speeds_px_per_ms: tuple = (0.0, 0.0025, 0.005, 0.01, 0.02, 0.03, 0.04, 0.06, 0.08, 0.16, 0.32)
    designs: tuple = DESIGNS
    rolling_shutter: tuple = (False, True)
    #: Direction of the motion in the object plane, degrees from +x (0: across the near-vertical edge).
    direction_deg: float = 0.0
    angular_velocity_deg_per_s: float = 0.0
    shake_rms_px: float = 0.0
    #: The paper's 10 µm pixel at f/1.4, a 12 mm lens (the spatial experiment's first case).
    pixel_pitch_um: float = 10.0
    f_number: float = 1.4
    focal_length_mm: float = 12.0
    object_pixel_mm: float = 0.5
    edge_size_px: tuple = (128, 128)
    edge_angle_deg: float = 5.0
    supersampling: int = 4
    #: Samples per sub-pixel of one capture, shared by its slices (16 per sub-pixel = 256 per pixel).
    samples_per_subpixel: int = 16
    #: The image moves at most this far between slices (0.25 px: the midpoint rule's error on a ramp is
    #: below 0.1 % of the step).
    max_step_px: float = 0.25
    #: A fixed number of slices per capture instead (0: from max_step_px).
    slices: int = 0
    render_mode: str = "materials"
    order: str = "RGB"
    readout_gap_ms: float = 1.0
    line_time_us: float = 30.0
    prism_alignment: str = "start"
    #: The paper's light level: cfa/single needs 28 ms on the white patch at the scene's illuminant
    #: (0: keep the scene's illuminant.white_luminance_cd_m2).
    cfa_exposure_ms: float = 28.0
    #: The paper's sensor noise (shot, dark, read, FPN, 8-bit ADC): the SNR advantage is the point.
    noise: bool = True
    #: Added chroma (ΔE*ab) above which a pixel counts as broken up: about twice a just-noticeable difference.
    breakup_threshold: float = 2.0
    #: S-CIELAB and CIELAB are averaged within this many pixels of the edge.
    zone_half_width_px: float = 24.0
    #: The e-SFR (MTF50) as ISO 12233:2017 states it (false). The binning correction (true) is not part of
    #: ISO 12233:2017; it adds about +1.6–2.3 % to the MTF50 of a sharp still edge (prism and fsc at rest in the
    #: default run; the CFA's +1.2 %), less as the motion blurs it (+0.1 % at 0.16 px/ms). What it corrects:
    #: the docstring of spectracam/evaluation/esfr.py.
    esfr_correct_binning: bool = False
    viewing_distance_m: float = 0.5
    display_pixel_pitch_mm: float = 25.4 / 120
    seed: int = 0
    #: Noise seeds per capture (seed, seed + 1, …): every noisy metric is their mean, with its spread, and the
    #: crossing speed is given per seed with a 95 % interval (noise off: one capture).
    seeds: int = 3

    def validate(self) -> None:
        v = self.speeds_px_per_ms
        if not isinstance(v, tuple) or not v or any(not isinstance(x, (int, float)) or isinstance(x, bool)
                                                    or not math.isfinite(x) or x < 0 for x in v):
            raise self.error("speeds_px_per_ms", "must be a non-empty list of finite numbers ≥ 0 (px/ms)")
        object.__setattr__(self, "speeds_px_per_ms", tuple(sorted(float(x) for x in v)))
        from spectracam.camera import split_design

        if not isinstance(self.designs, tuple) or not self.designs:
            raise self.error("designs", "must be a non-empty list of 'arch/scheme'")
        for d in self.designs:
            split_design(d, "designs")
        if not isinstance(self.rolling_shutter, tuple) or not self.rolling_shutter or \
                any(not isinstance(x, bool) for x in self.rolling_shutter):
            raise self.error("rolling_shutter", "must be a list of true/false, e.g. [false, true]")
        self.number("direction_deg", -360.0, 360.0, unit="°")
        self.number("angular_velocity_deg_per_s", -1e4, 1e4, unit="°/s")
        self.number("shake_rms_px", 0.0, 50.0, unit="px")
        self.number("pixel_pitch_um", 0.1, 100.0, unit="µm")
        self.number("f_number", 0.5, 64.0)
        self.number("focal_length_mm", 1.0, 1000.0, unit="mm")
        self.number("object_pixel_mm", 1e-4, 1e3, lo_open=True, unit="mm")
        self.numbers("edge_size_px", 2, 32.0, unit="px")
        object.__setattr__(self, "edge_size_px", tuple(int(x) for x in self.edge_size_px))
        self.number("edge_angle_deg", 2.0, 10.0, unit="°")
        self.integer("supersampling", 1, 16)
        self.integer("samples_per_subpixel", 1, 4096)
        self.number("max_step_px", 0.01, 4.0, unit="px")
        self.integer("slices", 0, 100000)
        self.choice("render_mode", RENDER_MODES)
        TimingSpec(self.order, self.readout_gap_ms, False, self.line_time_us, self.prism_alignment)
        self.number("cfa_exposure_ms", 0.0, 1e4, unit="ms")
        self.boolean("noise", "esfr_correct_binning")
        self.number("breakup_threshold", 0.0, 100.0, lo_open=True)
        self.number("zone_half_width_px", 1.0, 1e4, unit="px")
        self.number("viewing_distance_m", 0.0, 100.0, lo_open=True, unit="m")
        self.number("display_pixel_pitch_mm", 0.0, 100.0, lo_open=True, unit="mm")
        self.integer("seed", 0, 2**31 - 1)
        self.integer("seeds", 1, 50)

    def timing(self, rolling: bool) -> TimingSpec:
        """The windows' settings of this run, with a global or a rolling shutter.

        Parameters
        ----------
        rolling : bool
            A rolling shutter (each row ``line_time_us`` after the one above).

        Returns
        -------
        TimingSpec
            :attr:`order`, :attr:`readout_gap_ms`, the shutter, :attr:`line_time_us`, :attr:`prism_alignment`.
        """
        return TimingSpec(self.order, self.readout_gap_ms, bool(rolling), self.line_time_us, self.prism_alignment)

    def quick(self) -> "MotionSpec":
        """A first look: a 64 × 64 edge (object pixels twice as large), 8 speeds, 8 samples per sub-pixel."""
        return self.replace(edge_size_px=tuple(max(32, x // 2) for x in self.edge_size_px),
                            object_pixel_mm=self.object_pixel_mm * 2,
                            speeds_px_per_ms=(0.0, 0.005, 0.01, 0.02, 0.03, 0.04, 0.08, 0.16),
                            samples_per_subpixel=min(self.samples_per_subpixel, 8),
                            zone_half_width_px=min(self.zone_half_width_px, 16.0))


def load_motion(sets: Iterable[str | tuple[str, object]] = (), quick: bool = False) -> tuple[MotionSpec, Scene]:
    """``(MotionSpec, Scene)`` from ``--set`` overrides over the paper's camera and light
    (:func:`spectracam.pipeline.scene_file.paper_scene`), as the spatial experiment reads them.

    Parameters
    ----------
    sets : iterable of str or (str, object)
        ``--set``: top-level keys are :class:`MotionSpec`'s, tables the scene's.
    quick : bool
        :meth:`MotionSpec.quick`'s sizes (where ``--set`` does not choose them) and 20 nm bands.

    Returns
    -------
    spec : MotionSpec
        The experiment's parameters.
    scene : Scene
        The paper's scene with the tables of ``sets``.

    Raises
    ------
    ConfigError
        On an unknown key or table, or an invalid value.
    """
    from spectracam.pipeline.scene_file import paper_scene
    from spectracam.experiments.spatial.experiment import load_spec_and_scene

    return load_spec_and_scene(MotionSpec, sets, quick, base_scene=paper_scene())


def calibrated_scene(scene: Scene, spec: MotionSpec) -> Scene:
    """The scene at the light level where cfa/single needs ``cfa_exposure_ms`` (paper: 28 ms at 5000 K).

    Parameters
    ----------
    scene : Scene
        The scene (its chart, light and camera).
    spec : MotionSpec
        Its ``cfa_exposure_ms`` (0: the scene unchanged), pixel pitch, f-number and noise.

    Returns
    -------
    Scene
        Its illuminant's white luminance, cd/m², scaled so that cfa/single's white patch fills the well to
        ``white_fill`` in ``cfa_exposure_ms``.

    Raises
    ------
    SpectracamError
        When dark current alone would fill the well sooner.
    """
    if spec.cfa_exposure_ms == 0:
        return scene
    cam = motion_camera(scene, spec).with_design("cfa/single")
    ref = ChartReference.of(scene)
    white = ref.patch_rates(cam)[WHITE_PATCH]
    s = cam.sensor
    need = cam.capture.white_fill * s.q_max_e / (spec.cfa_exposure_ms * 1e-3) - s.dark_rate_e_per_s
    if need <= 0:
        raise SpectracamError(f"cfa_exposure_ms = {spec.cfa_exposure_ms:g}: dark current alone fills the well sooner")
    level = scene.illuminant.white_luminance_cd_m2 * need / white.max()
    return scene.replace(illuminant=scene.illuminant.replace(white_luminance_cd_m2=float(level)))


def motion_camera(scene: Scene, spec: MotionSpec) -> CameraSpec:
    """The scene's camera with the run's pixel pitch and f-number; without noise where ``spec.noise`` is off.

    Parameters
    ----------
    scene : Scene
        Its camera.
    spec : MotionSpec
        ``pixel_pitch_um``, ``f_number``, ``noise``.

    Returns
    -------
    CameraSpec
        Before a design is chosen.
    """
    cam = scene.camera
    sensor = cam.sensor.replace(pixel_pitch_um=float(spec.pixel_pitch_um))
    if not spec.noise:
        sensor = sensor.off("shot_noise", "dark_current", "read_noise", "fpn", "quantization")
    return cam.replace(sensor=sensor, optics=cam.optics.replace(f_number=float(spec.f_number)))


def design_snr_db(scene: Scene, camera: CameraSpec, design: str, seed: int) -> float | None:
    """The paper's SNR of a design (chart patches, 160 × 120 px, closed-form render) under the scene's light.

    Parameters
    ----------
    scene : Scene
        Its light and chart.
    camera : CameraSpec
        The motion camera (:func:`motion_camera`).
    design : str
        ``arch/scheme``.
    seed : int
        The noise seed.

    Returns
    -------
    float or None
        The combined SNR over the channels, dB (:func:`spectracam.pipeline.simulate`'s summary).
    """
    from spectracam.pipeline import simulate
    from spectracam.pipeline.scene_file import ImageSpec

    sc = scene.replace(image=ImageSpec(160, 120), camera=camera.with_design(design))
    return simulate(sc, "analytic", seed)[2].summary.snr_combined_db


#: Bytes a motion run holds at its peak per rendered sub-pixel (margin included): a part per band
#: (the ideal sub-pixel cube, float32) and a part that is not (each channel group's time-integrated
#: basis in float64, the optical transfers and FFTs, the images kept for the report).  Measured with
#: `/usr/bin/time -v` on 64- and 160-px edges, 15 and 30 bands: 356 + 42.5·bands above the
#: interpreter's own; about 10 % added.
MEMORY_PER_SUBPIXEL_BYTES = (400.0, 48.0)


#: A field-sequential capture lasts about this many times the CFA's exposure (three exposures of about
#: 1.5× the CFA's with readout gaps: fsc/optimal 130 ms against cfa/single's 28 ms at 5000 K): the
#: longest capture, for the estimate of the slices before the exposures are metered.
CAPTURE_OVER_CFA_EXPOSURE = 5.0


@dataclass(frozen=True)
class MotionEstimate:
    """What a motion run will cost, known before any work (:func:`motion_estimate`)."""

    bytes: float                     # peak memory, bytes
    slice_renders: int               # slice renders, at most (shared positions make fewer)
    cases: int

    def line(self) -> str:
        return (f"motion: {self.cases} cases, at most about {self.slice_renders} slice renders, "
                f"about {self.bytes / 2**30:.1f} GiB at the peak")


def motion_estimate(spec: MotionSpec, scene: Scene) -> MotionEstimate:
    """The peak memory and the slice renders of a run, before any work.  Memory: the measured bytes per
    sub-pixel (:data:`MEMORY_PER_SUBPIXEL_BYTES`, the default run's cache of rendered poses included) plus, with a
    set number of ``slices``, the cache those poses fill (each pose ``K × sub-pixels`` float32, up to
    :data:`~.render.BASIS_CACHE_BYTES`).  Renders: per case ``slices``, or (0) the slices of the step
    ``max_step_px`` over the longest capture (:data:`CAPTURE_OVER_CFA_EXPOSURE` × the CFA's exposure), at least
    :data:`~.render.MIN_SLICES_PER_WINDOW` per window of three.

    Parameters
    ----------
    spec : MotionSpec
        The run.
    scene : Scene
        Its wavelength grid (bands, and the longest wavelength for the margin).

    Returns
    -------
    MotionEstimate
        Peak memory, bytes, the slice renders at most, and the cases.
    """
    from spectracam.experiments.motion.render import BASIS_CACHE_BYTES, MIN_SLICES_PER_WINDOW

    m = sopt.margin_px(spec.pixel_pitch_um, spec.f_number, scene.grid.edges_nm[-1])
    w, h = spec.edge_size_px
    subpixels = (w + 2 * m) * (h + 2 * m) * spec.supersampling ** 2
    fixed, per_band = MEMORY_PER_SUBPIXEL_BYTES
    need = subpixels * (fixed + per_band * len(scene.grid))
    speeds = case_speeds(spec)
    cases = len(spec.designs) * len(spec.rolling_shutter) * len(speeds)
    capture_ms = CAPTURE_OVER_CFA_EXPOSURE * (spec.cfa_exposure_ms or 28.0)
    if spec.slices:
        per_case = [spec.slices if v > 0 else 1 for v in speeds]
        K = 2 if spec.render_mode == "materials" else len(scene.grid)
        need += min(BASIS_CACHE_BYTES, sum(per_case) * len(spec.designs) * len(spec.rolling_shutter)
                    * K * subpixels * 4)
    else:
        per_case = [max(3 * MIN_SLICES_PER_WINDOW, math.ceil(v * capture_ms / spec.max_step_px)) if v > 0 else 1
                    for v in speeds]
    return MotionEstimate(float(need), int(sum(per_case) * len(spec.designs) * len(spec.rolling_shutter)), cases)


def check_motion_memory(spec: MotionSpec, scene: Scene) -> MotionEstimate:
    """Refuse, before any work, a motion run larger than the memory this process may use; its estimate.

    Parameters
    ----------
    spec : MotionSpec
        The run.
    scene : Scene
        Its wavelength grid.

    Returns
    -------
    MotionEstimate
        :func:`motion_estimate`'s.

    Raises
    ------
    SpectracamError
        When the estimate is more than the memory available.
    """
    from spectracam.pipeline import check_bytes

    est = motion_estimate(spec, scene)
    m = sopt.margin_px(spec.pixel_pitch_um, spec.f_number, scene.grid.edges_nm[-1])
    w, h = spec.edge_size_px
    slices = f", slices = {spec.slices} (their cached poses)" if spec.slices else ""
    check_bytes(est.bytes, f"edge_size_px = [{w}, {h}] (+{m} px margin) at supersampling = {spec.supersampling} with "
                f"{len(scene.grid)} bands{slices}",
                "use a smaller edge, less supersampling, fewer bands" + (" or fewer slices" if slices else ""))
    return est


# -- the result rows ------------------------------------------------------------------------------

#: The scores measured on every noise seed's capture: a row holds their mean, their spread (``_sd``).
SEED_METRICS = ("scielab_delta_e", "cielab_delta_e", "scielab_delta_e_scene", "cielab_delta_e_scene",
                "mtf50_cy_per_px")


@dataclass(frozen=True)
class MotionRow:
    """One case — a design at an image speed with a shutter — and its scores (the module docstring
    says what each means). :meth:`to_dict` is the row of ``results.json``; the field names are its keys."""

    #: The case: design ``arch/scheme``, image speed on the sensor and in the scene, shutter.
    design: str
    speed_px_per_ms: float
    speed_mm_per_s: float
    rolling_shutter: bool
    #: Colour breakup (noise-free captures): the spread of the channels' edge positions moved by the motion
    #: alone (px, sub-pixel; None where an edge was not found), the largest added chroma (ΔE*ab), the spread
    #: against the scene's edge; the still capture's demosaicking false colour (ΔE*ab).
    breakup_width_px: float | None
    max_added_chroma: float
    breakup_width_scene_px: float | None
    false_colour_still: float
    #: Each channel's edge moved by the motion (px along +x, the architecture's channel order), the channels'
    #: mean 10–90 % rise (px: the blur, apart from the breakup), and the width over which the added chroma
    #: exceeds ``breakup_threshold`` (px, in 0.5 px bins; before issue 34 the breakup width), against the still
    #: capture and against the scene.
    channel_edge_shift_px: tuple
    edge_blur_px: float | None
    breakup_threshold_width_px: float
    breakup_threshold_width_scene_px: float
    #: Means over the noise seeds (ΔE*ab; cycles/pixel); None where a seed gave no value (no usable edge).
    scielab_delta_e: float | None
    cielab_delta_e: float | None
    scielab_delta_e_scene: float | None
    cielab_delta_e_scene: float | None
    mtf50_cy_per_px: float | None
    #: Their spread over the seeds (sample standard deviation; None with one seed).
    scielab_delta_e_sd: float | None
    cielab_delta_e_sd: float | None
    scielab_delta_e_scene_sd: float | None
    cielab_delta_e_scene_sd: float | None
    mtf50_cy_per_px_sd: float | None
    #: S-CIELAB per seed, and the seeds.
    scielab_delta_e_by_seed: tuple
    seeds: tuple
    #: The design's chart SNR with the paper's noise (None with the noise off).
    snr_db: float | None
    #: Time: the image's travel during the capture, the capture time, each channel's exposure, and the
    #: time slices that sampled it (:class:`.render.Integrated`).
    blur_px: float
    capture_time_ms: float
    exposure_ms: tuple
    slices: int
    slice_dt_ms: float
    samples_per_slice: int

    def to_dict(self) -> dict:
        """The row of ``results.json`` (tuples as lists)."""
        return {f.name: (list(v) if isinstance(v := getattr(self, f.name), tuple) else v) for f in fields(self)}

    __iter__ = None   # not a mapping: iterate over to_dict()


# -- the steps of a run: set-up, one design, one speed, one capture, one score --------------------

@dataclass(frozen=True)
class MotionSetup:
    """What every case shares: the calibrated scene, its chart reference, the framing, the moving
    target and its ideal image, and where the scores are taken."""

    spec: MotionSpec
    scene: object                    # the scene at the calibrated light level
    reference: ChartReference
    camera: object                   # the motion camera, before a design is chosen
    geometry: CameraGeometry         # the image (no margin)
    margin_px: int                   # rendered around it for the optics
    moving: MovingScene
    ideal: np.ndarray                # (H, W, B) band radiance of the target at rest (t = 0)
    optics: sopt.OpticsSettings
    samples_per_degree: float        # S-CIELAB's
    valid: np.ndarray                # (H, W) scored pixels (SCORE_BORDER_PX left out)
    edge_columns: np.ndarray         # (H,) where the edge at rest crosses each row
    seeds: tuple                     # noise seeds (noise off: one)


@dataclass(frozen=True)
class DesignModel:
    """One design: its camera (noisy and noise-free), conversion, exposure times and its references."""

    design: str
    camera: object
    quiet_camera: object
    conversion: Conversion
    white_rate: np.ndarray           # metered photo-electron rates of the white patch
    times_s: tuple                   # exposure per channel
    ideal_xyz: np.ndarray            # the scene at rest, display XYZ
    own_xyz: np.ndarray              # the camera's conversion of the ideal image (no optics, no sensor)
    snr_db: float | None


@dataclass(frozen=True)
class Capture:
    """A design's capture of the target at one speed: one per noise seed and a noise-free twin."""

    noisy: tuple                     # ((camera rates (H, W, N), display XYZ (H, W, 3)), ...) per seed
    quiet_xyz: np.ndarray
    quiet_rates: np.ndarray          # the noise-free twin's camera rates (H, W, N)


@dataclass(frozen=True)
class StillReference:
    """The design's noise-free still capture (the motion metrics' reference) and its false colour."""

    xyz: np.ndarray
    false_colour: float
    #: Its channels' edge profiles (:func:`.metrics.channel_profiles`): ``(d (n,), profiles (n, N))``.
    profiles: tuple


@contextlib.contextmanager
def timed(timings: dict, stage: str) -> Iterator[None]:
    """Add the block's wall time to ``timings[stage]``.

    Parameters
    ----------
    timings : dict
        Stage → wall time, s.
    stage : str
        The stage, already a key of ``timings``.

    Yields
    ------
    None
        The block runs here.
    """
    t0 = time.perf_counter()
    try:
        yield
    finally:
        timings[stage] += time.perf_counter() - t0


def prepare(spec: MotionSpec, scene: Scene, renderer: str, log: Callable[[str], object] | None,
            timings: dict) -> MotionSetup:
    """The calibrated scene, the framing, the moving target and its ideal image (the render stage).

    Parameters
    ----------
    spec : MotionSpec
        The run.
    scene : Scene
        The scene before calibration (:func:`calibrated_scene`).
    renderer : str
        ``"mitsuba"`` or ``"analytic"``.
    log : callable or None
        ``log(line)``: the renderer's notices.
    timings : dict
        Stage → wall time, s; added to.

    Returns
    -------
    MotionSetup
        What every case shares.
    """
    scene = calibrated_scene(scene, spec)
    w, h = spec.edge_size_px
    geometry = CameraGeometry.framing(w * spec.object_pixel_mm, spec.focal_length_mm, spec.f_number,
                                      spec.pixel_pitch_um, w, h)
    m = sopt.margin_px(spec.pixel_pitch_um, spec.f_number, scene.grid.edges_nm[-1])
    target = SlantedEdge(angle_deg=spec.edge_angle_deg, dataset=scene.chart.dataset)
    with timed(timings, "render"):
        moving = MovingScene(target, geometry.with_margin(m), scene.illuminant, scene.grid, spec.supersampling,
                             renderer, spec.render_mode, scene.render.variant, spec.seed, log)
        ideal = ideal_radiance(moving, spec.samples_per_subpixel, m)
    b = SCORE_BORDER_PX
    valid = np.zeros((h, w), bool)
    valid[b:-b, b:-b] = True
    return MotionSetup(
        spec=spec, scene=scene, reference=ChartReference.of(scene), camera=motion_camera(scene, spec),
        geometry=geometry, margin_px=m, moving=moving, ideal=ideal, optics=sopt.OpticsSettings(),
        samples_per_degree=samples_per_degree(spec.viewing_distance_m, spec.display_pixel_pitch_mm * 1e-3),
        valid=valid, edge_columns=mm.edge_columns(w, h, target.x0_px, spec.edge_angle_deg),
        seeds=tuple(spec.seed + i for i in range(spec.seeds if spec.noise else 1)))  # noise-free: one is all there is


def design_model(setup: MotionSetup, design: str, timings: dict) -> DesignModel:
    """A design's camera, conversion (fitted on the chart), exposure times, references and SNR.

    Parameters
    ----------
    setup : MotionSetup
        What every case shares (:func:`prepare`).
    design : str
        ``arch/scheme``.
    timings : dict
        Stage → wall time, s; added to.

    Returns
    -------
    DesignModel
        The SNR None with the noise off.
    """
    spec, scene = setup.spec, setup.scene
    camera = setup.camera.with_design(design)
    with timed(timings, "snr"):
        snr = design_snr_db(scene, camera, design, spec.seed) if spec.noise else None
    conv = Conversion.fit(setup.reference, camera, scene.processing)
    white = white_rate(setup.reference, camera)
    times = exposure_times_s(camera.capture.exposure, white, camera.sensor, camera.architecture(),
                             camera.capture.white_fill, camera.capture.exposure_split)
    own_xyz = photo_electron_rates(setup.ideal.astype(np.float32), scene.grid, camera).astype(np.float64) \
        @ conv.matrix @ conv.rgb_to_xyz.T
    quiet = camera.replace(sensor=camera.sensor.off("shot_noise", "dark_current", "read_noise", "fpn", "quantization"))
    return DesignModel(design, camera, quiet, conv, white, times,
                       radiance_to_display_xyz(setup.ideal, scene.grid, scene.illuminant.white_luminance_cd_m2, conv),
                       own_xyz, snr)


def case_speeds(spec: MotionSpec) -> tuple:
    """The speeds captured: the swept ones, after a still capture (0) if the sweep does not start at rest.

    Parameters
    ----------
    spec : MotionSpec
        Its ``speeds_px_per_ms`` (sorted).

    Returns
    -------
    tuple of float
        px/ms, 0 first.
    """
    return ((0.0,) if spec.speeds_px_per_ms[0] > 0 else ()) + spec.speeds_px_per_ms


def speed_mm_per_s(spec: MotionSpec, v_px_per_ms: float) -> float:
    """An image speed on the sensor as the object's speed in the scene.

    Parameters
    ----------
    spec : MotionSpec
        Its ``object_pixel_mm``.
    v_px_per_ms : float
        The image's speed on the sensor, px/ms.

    Returns
    -------
    float
        mm/s on the object plane.
    """
    return v_px_per_ms * 1e3 * spec.object_pixel_mm


def render_at_speed(setup: MotionSetup, dm: DesignModel, timing: CaptureTiming, v_px_per_ms: float,
                    timings: dict) -> tuple[np.ndarray, dict]:
    """The target moving at ``v_px_per_ms`` through the design's windows and the optics:
    ``(time-averaged photo-electron rates (H, W, N), how the time was sliced)``.

    Parameters
    ----------
    setup : MotionSetup
        What every case shares (:func:`prepare`).
    dm : DesignModel
        The design (:func:`design_model`).
    timing : CaptureTiming
        The design's windows, per rendered row (margin included).
    v_px_per_ms : float
        The image's speed on the sensor, px/ms.
    timings : dict
        Stage → wall time, s; added to.

    Returns
    -------
    rates : ndarray, shape (H, W, N)
        e⁻/s per pixel and channel.
    slicing : dict
        ``slices``, ``slice_dt_ms``, ``samples_per_slice`` (:class:`~.render.Integrated`'s info).
    """
    spec = setup.spec
    vmm = speed_mm_per_s(spec, v_px_per_ms)
    direction = math.radians(spec.direction_deg)
    motion = Motion(velocity_mm_per_s=(vmm * math.cos(direction), vmm * math.sin(direction)),
                    angular_velocity_deg_per_s=spec.angular_velocity_deg_per_s,
                    shake_rms_px=spec.shake_rms_px, seed=spec.seed)
    with timed(timings, "render"):
        integ = integrate(setup.moving, motion, timing, spec.max_step_px, spec.slices, spec.samples_per_subpixel)
    with timed(timings, "optics"):
        rates = channel_rates(setup.moving, integ, dm.camera, setup.optics, setup.margin_px)
    return rates, integ.info


def capture_at_seed(setup: MotionSetup, dm: DesignModel, rates: np.ndarray, seed: int,
                    camera: CameraSpec | None = None) -> tuple[np.ndarray, np.ndarray]:
    """One capture of the rates by the design (its noise at ``seed``), processed to the display:
    ``(camera rates (H, W, N), display XYZ (H, W, 3))``.

    Parameters
    ----------
    setup : MotionSetup
        What every case shares (:func:`prepare`).
    dm : DesignModel
        The design (:func:`design_model`).
    rates : ndarray, shape (H, W, N)
        Photo-electron rates, e⁻/s (:func:`render_at_speed`).
    seed : int
        The noise seed.
    camera : CameraSpec or None
        Records instead of the design's camera (its noise-free twin).

    Returns
    -------
    cam_rates : ndarray, shape (H, W, N)
        The demosaicked, exposure-normalised camera rates.
    xyz : ndarray, shape (H, W, 3)
        Display XYZ, white Y = 1.
    """
    raw = record(rates, camera or dm.camera, dm.white_rate, seed, dm.times_s)
    return process(raw, setup.scene.processing, dm.conversion, setup.reference)


def capture(setup: MotionSetup, dm: DesignModel, rates: np.ndarray, timings: dict) -> Capture:
    """The design's captures of the rates: one per noise seed, and the noise-free twin (noise off: the same).

    Parameters
    ----------
    setup : MotionSetup
        What every case shares (:func:`prepare`).
    dm : DesignModel
        The design (:func:`design_model`).
    rates : ndarray, shape (H, W, N)
        Photo-electron rates, e⁻/s (:func:`render_at_speed`).
    timings : dict
        Stage → wall time, s; added to.

    Returns
    -------
    Capture
        The noisy captures and the noise-free twin's XYZ and camera rates.
    """
    with timed(timings, "capture"):
        noisy = tuple(capture_at_seed(setup, dm, rates, sd) for sd in setup.seeds)
    with timed(timings, "processing"):
        quiet = noisy[0] if not setup.spec.noise else \
            capture_at_seed(setup, dm, rates, setup.spec.seed, dm.quiet_camera)
    return Capture(noisy, quiet[1], quiet[0])


def still_reference(setup: MotionSetup, dm: DesignModel, still_xyz: np.ndarray, still_rates: np.ndarray
                    ) -> StillReference:
    """The noise-free still capture, its false colour within 2 px of the edge, against the camera's
    conversion of the ideal image (√(Δa*² + Δb*²)), and its channels' edge profiles.

    Parameters
    ----------
    setup : MotionSetup
        What every case shares (:func:`prepare`).
    dm : DesignModel
        The design (:func:`design_model`).
    still_xyz : ndarray, shape (H, W, 3)
        The noise-free capture at rest, display XYZ.
    still_rates : ndarray, shape (H, W, N)
        Its camera rates.

    Returns
    -------
    StillReference
        The capture, its false colour (ΔE*ab, mean over the scored pixels within 2 px of the edge), its profiles.
    """
    h, w = setup.valid.shape
    dist = mm.edge_distance((h, w), setup.edge_columns)
    zone = mm.edge_zone(dist, 2.0) & setup.valid
    lab_s, lab_o = (xyz_to_lab(a, dm.conversion.display_white) for a in (still_xyz, dm.own_xyz))
    return StillReference(still_xyz, float(np.hypot(*(lab_s - lab_o)[..., 1:].transpose(2, 0, 1))[zone].mean()),
                          mm.channel_profiles(still_rates, dist, setup.valid))


def score_capture(setup: MotionSetup, dm: DesignModel, still: StillReference, xyz: np.ndarray,
                  zone: np.ndarray) -> tuple[dict, np.ndarray, tuple[np.ndarray, np.ndarray]]:
    """One seed's capture scored: ``({metric: value} for SEED_METRICS, S-CIELAB map against the still
    capture (H, W), (e-SFR frequencies, SFR))``.

    Parameters
    ----------
    setup : MotionSetup
        What every case shares (:func:`prepare`).
    dm : DesignModel
        The design (:func:`design_model`).
    still : StillReference
        The design's noise-free still capture.
    xyz : ndarray, shape (H, W, 3)
        The capture, display XYZ.
    zone : ndarray of bool, shape (H, W)
        The scored pixels near the edge, where the ΔE*ab are averaged.

    Returns
    -------
    scores : dict
        :data:`SEED_METRICS` → value (ΔE*ab; MTF50 cycles/px, NaN without a usable edge).
    scielab_map : ndarray, shape (H, W)
        S-CIELAB ΔE*ab against the still capture.
    esfr : tuple of ndarray
        ``(frequencies cycles/px, SFR)``.
    """
    white, spd = dm.conversion.display_white, setup.samples_per_degree
    lab = xyz_to_lab(xyz, white)
    scielab_map = scielab(still.xyz, xyz, white, spd)
    f, sfr, mtf50 = mm.mtf_along_motion(xyz, SCORE_BORDER_PX, correct_binning=setup.spec.esfr_correct_binning)
    scores = {"scielab_delta_e": float(scielab_map[zone].mean()),
              "cielab_delta_e": float(delta_e(lab, xyz_to_lab(still.xyz, white))[zone].mean()),
              "scielab_delta_e_scene": float(scielab(dm.ideal_xyz, xyz, white, spd)[zone].mean()),
              "cielab_delta_e_scene": float(delta_e(lab, xyz_to_lab(dm.ideal_xyz, white))[zone].mean()),
              "mtf50_cy_per_px": mtf50}
    return scores, scielab_map, (f, sfr)


def edge_distance_moving(setup: MotionSetup, timing: CaptureTiming, v_px_per_ms: float) -> np.ndarray:
    """``(H, W)`` distance from the edge, px: each row's later window shifts a uniformly moving edge
    (rolling shutter).

    Parameters
    ----------
    setup : MotionSetup
        What every case shares (:func:`prepare`).
    timing : CaptureTiming
        The design's windows, per rendered row (margin included).
    v_px_per_ms : float
        The image's speed on the sensor, px/ms.

    Returns
    -------
    ndarray, shape (H, W)
        px, positive to the right; each row shifted by ``v·(row delay − mean row delay)`` along the motion's x.
    """
    h, w = setup.valid.shape
    delay = timing.row_delay_s[setup.margin_px:setup.margin_px + h]
    shift = v_px_per_ms * 1e3 * math.cos(math.radians(setup.spec.direction_deg)) * (delay - delay.mean())
    return mm.edge_distance((h, w), setup.edge_columns + shift)


def score_case(setup: MotionSetup, dm: DesignModel, timing: CaptureTiming, still: StillReference,
               v_px_per_ms: float, cap: Capture, slicing: dict, rolling: bool) -> tuple[MotionRow, dict, dict]:
    """A case scored: ``(MotionRow, its e-SFR curve (first seed), its images (first seed))``.

    Parameters
    ----------
    setup : MotionSetup
        What every case shares (:func:`prepare`).
    dm : DesignModel
        The design (:func:`design_model`).
    timing : CaptureTiming
        The design's windows, per rendered row (margin included).
    still : StillReference
        The design's noise-free still capture.
    v_px_per_ms : float
        The image's speed on the sensor, px/ms.
    cap : Capture
        The captures at that speed.
    slicing : dict
        How the time was sliced (:func:`render_at_speed`).
    rolling : bool
        The shutter.

    Returns
    -------
    row : MotionRow
        The case's scores.
    curve : dict
        The first seed's e-SFR (80 frequencies at most).
    images : dict
        The first seed's display XYZ, camera rates, added chroma profile, S-CIELAB map and scored zone.
    """
    spec = setup.spec
    dist = edge_distance_moving(setup, timing, v_px_per_ms)
    zone = mm.edge_zone(dist, spec.zone_half_width_px) & setup.valid
    (d, chroma), (d_s, chroma_s), edge, edge_scene = _breakup(setup, dm, still, cap, dist)
    cam_rates, xyz = cap.noisy[0]
    scored = [score_capture(setup, dm, still, x, zone) for _, x in cap.noisy]
    per_seed = {k: [s[k] for s, _, _ in scored] for k in SEED_METRICS}
    _, scielab_map, (f, sfr) = scored[0]          # the first seed's map and curve are the ones drawn
    row = MotionRow(
        design=dm.design, speed_px_per_ms=v_px_per_ms, speed_mm_per_s=speed_mm_per_s(spec, v_px_per_ms),
        rolling_shutter=bool(rolling), breakup_width_px=finite_or_none(edge.separation_px),
        max_added_chroma=float(np.nanmax(np.append(chroma, 0.0))),
        breakup_width_scene_px=finite_or_none(edge_scene.separation_px),
        false_colour_still=still.false_colour,
        channel_edge_shift_px=tuple(finite_or_none(x) for x in edge.shift_px),
        edge_blur_px=finite_or_none(edge.blur_px),
        breakup_threshold_width_px=mm.breakup_threshold_width_px(d, chroma, spec.breakup_threshold),
        breakup_threshold_width_scene_px=mm.breakup_threshold_width_px(d_s, chroma_s, spec.breakup_threshold),
        **{k: mean_or_none(v) for k, v in per_seed.items()},
        **{f"{k}_sd": sd_or_none(v) for k, v in per_seed.items()},
        scielab_delta_e_by_seed=tuple(per_seed["scielab_delta_e"]), seeds=setup.seeds, snr_db=dm.snr_db,
        blur_px=v_px_per_ms * 1e3 * timing.capture_time_s, capture_time_ms=1e3 * timing.capture_time_s,
        exposure_ms=tuple((1e3 * np.asarray(dm.times_s)).tolist()), **slicing)
    curve = {"design": dm.design, "speed_px_per_ms": v_px_per_ms, "rolling_shutter": bool(rolling),
             "frequencies_cy_per_px": f[:80].tolist(), "sfr": sfr[:80].tolist()}
    images = {"xyz": xyz.astype(np.float32), "cam_rates": cam_rates.astype(np.float32), "chroma": (d, chroma),
              "scielab": np.where(setup.valid, scielab_map, np.nan).astype(np.float32), "zone": zone}
    return row, curve, images


def _breakup(setup: MotionSetup, dm: DesignModel, still: StillReference, cap: Capture,
             dist: np.ndarray) -> tuple[tuple, tuple, mm.EdgeChannels, mm.EdgeChannels]:
    """:func:`score_case`'s colour breakup: the added chroma profiles against the still capture (noise-free) and
    against the camera's own ideal image (first seed), and the channels' edges against the still capture's and
    against the scene's."""
    spec = setup.spec
    white = dm.conversion.display_white
    # colour breakup: the motion alone (noise-free moving capture against the noise-free still one)
    d, chroma = mm.chroma_profile(cap.quiet_xyz, still.xyz, white, dist, 0.5, spec.zone_half_width_px, setup.valid)
    xyz = cap.noisy[0][1]
    d_s, chroma_s = mm.chroma_profile(xyz, dm.own_xyz, white, dist, 0.5, spec.zone_half_width_px, setup.valid)
    # the channels' edges, to a fraction of a pixel: moved by the motion (against the still capture's) and
    # against the scene's edge (d = 0), both located with the still capture's plateaus
    d_e, still_prof = still.profiles
    d_m, moving_prof = mm.channel_profiles(cap.quiet_rates, dist, setup.valid)
    if d_m.shape != d_e.shape or not np.allclose(d_m, d_e):   # a rolling shutter moves the bins: re-bin the still
        moving_prof = _rebin(d_m, moving_prof, d_e)
    edge = mm.edge_channels(d_e, moving_prof, still_prof)
    edge_scene = mm.edge_channels(d_e, moving_prof, still_prof, relative=False)
    return (d, chroma), (d_s, chroma_s), edge, edge_scene


def sweep_speeds(setup: MotionSetup, dm: DesignModel, timing: CaptureTiming, rolling: bool,
                 timings: dict) -> Iterator[tuple[MotionRow, dict, dict]]:
    """Every speed of one design and shutter: yields ``(row, curve, images)`` per swept speed.

    Parameters
    ----------
    setup : MotionSetup
        What every case shares (:func:`prepare`).
    dm : DesignModel
        The design (:func:`design_model`).
    timing : CaptureTiming
        The design's windows, per rendered row (margin included).
    rolling : bool
        The shutter.
    timings : dict
        Stage → wall time, s; added to.

    Yields
    ------
    tuple
        :func:`score_case`'s, per swept speed; the still capture (speed 0) is the reference of all.
    """
    still = None
    for v in case_speeds(setup.spec):
        rates, slicing = render_at_speed(setup, dm, timing, v, timings)
        cap = capture(setup, dm, rates, timings)
        if still is None:   # the first speed is 0: the still reference
            still = still_reference(setup, dm, cap.quiet_xyz, cap.quiet_rates)
        if v not in setup.spec.speeds_px_per_ms:
            continue        # the still reference only
        with timed(timings, "metrics"):
            case = score_case(setup, dm, timing, still, v, cap, slicing, rolling)
        yield case


class MotionResult(TypedDict):
    """What :func:`run_motion` returns.  The writer (:func:`spectracam.experiments.motion.report.write_outputs`)
    makes results.json of it without ``images`` and ``mtf_curves`` (those go to the case files and
    mtf_curves.json), ``rows`` as dicts, ``display_white`` as a list, and ``figures``, ``case_files`` and
    ``command`` added.  ``images``: (design, speed px/ms, rolling shutter) or (design, ``"ideal"``) → that case's
    arrays; ``exposure_timing``: the design's name, ``" rolling"`` appended for the rolling shutter → its
    :class:`~.timing.CaptureTiming` as a dict."""

    rows: list[MotionRow]
    mtf_curves: list[dict]
    images: dict[tuple, dict]
    timings: dict[str, float]
    exposure_timing: dict[str, dict]
    display_white: np.ndarray
    renderer: str
    render_metadata: dict
    slice_renders: int
    answer: dict
    parameters: dict
    wall_s: float


def run_motion(spec: MotionSpec, scene: Scene, renderer: str = "mitsuba", log: Callable[[str], object] | None = None,
               keep_images: bool = True, progress: bool = False) -> MotionResult:
    """Every design × speed × shutter. Returns ``{"rows": [MotionRow], "images", "timings", ...}``.
    ``progress``: a bar over the cases on a terminal (:mod:`spectracam.core.progress`).

    Parameters
    ----------
    spec : MotionSpec
        The run.
    scene : Scene
        The scene (:func:`load_motion`), before calibration.
    renderer : str
        ``"mitsuba"`` or ``"analytic"``.
    log : callable or None
        ``log(line)``: each design and shutter done.
    keep_images : bool
        Keep every case's images (for the report's figures and case files).
    progress : bool
        A bar over the cases.

    Returns
    -------
    MotionResult
        The rows, curves, images, timings, the crossing speeds and the parameters.
    """
    from spectracam.core.progress import bar

    log = log or (lambda msg: None)
    t_start = time.perf_counter()
    timings = dict.fromkeys(("render", "optics", "capture", "processing", "metrics", "snr"), 0.0)
    setup = prepare(spec, scene, renderer, log, timings)
    rows, images, curves, timing_info = [], {}, [], {}
    with bar(total=len(spec.designs) * len(spec.rolling_shutter) * len(spec.speeds_px_per_ms),
             desc="motion cases", unit="case", progress=progress) as cases:
        for design in spec.designs:
            dm = design_model(setup, design, timings)
            for rolling in spec.rolling_shutter:
                timing = capture_timing(dm.camera.architecture(), dm.times_s, spec.timing(rolling),
                                        setup.moving.geometry.height_px, -setup.margin_px)
                timing_info[f"{design}{' rolling' if rolling else ''}"] = timing.to_dict()
                for row, curve, case_images in sweep_speeds(setup, dm, timing, rolling, timings):
                    rows.append(row)
                    curves.append(curve)
                    if keep_images:
                        images[(design, row.speed_px_per_ms, bool(rolling))] = case_images
                    cases.update(1)
                log(f"[{time.perf_counter() - t_start:6.1f} s] {design}{' rolling shutter' if rolling else ''}: "
                    f"{len(spec.speeds_px_per_ms)} speeds ({setup.moving.renders} slice renders so far)")
            if keep_images:
                images[(design, "ideal")] = {"xyz": dm.ideal_xyz.astype(np.float32)}
    return {"rows": rows, "mtf_curves": curves, "images": images, "timings": timings,
            "exposure_timing": timing_info, "display_white": dm.conversion.display_white, "renderer": renderer,
            "render_metadata": setup.moving.metadata, "slice_renders": setup.moving.renders,
            "answer": crossing_speeds(rows),
            "parameters": {"motion": spec.to_dict(), "scene": setup.scene.to_dict(),
                           "geometry": setup.geometry.to_dict(),
                           "white_luminance_cd_m2": setup.scene.illuminant.white_luminance_cd_m2,
                           "samples_per_degree": setup.samples_per_degree},
            "wall_s": time.perf_counter() - t_start}


def finite_or_none(x: float | None) -> float | None:
    """``x`` as a float, or None where it is None, NaN or infinite.

    Parameters
    ----------
    x : float or None
        A value.

    Returns
    -------
    float or None
        For results.json (strict JSON has no NaN).
    """
    return float(x) if x is not None and np.isfinite(x) else None


def _rebin(d_from: np.ndarray, profiles: np.ndarray, d_to: np.ndarray) -> np.ndarray:
    """Profiles on bins ``d_from`` read at ``d_to`` (linear; NaN outside)."""
    out = np.full((d_to.size, profiles.shape[1]), np.nan)
    for k in range(profiles.shape[1]):
        ok = np.isfinite(profiles[:, k])
        out[:, k] = np.interp(d_to, d_from[ok], profiles[ok, k], left=np.nan, right=np.nan)
    return out


def mean_or_none(values: Sequence[float | None]) -> float | None:
    """The mean of ``values``; None where one is None or not finite, or there is none.

    Parameters
    ----------
    values : sequence of float or None
        One per seed.

    Returns
    -------
    float or None
        The mean.
    """
    v = [x for x in values if x is not None and np.isfinite(x)]
    return float(np.mean(v)) if len(v) == len(values) and v else None


def sd_or_none(values: Sequence[float | None]) -> float | None:
    """The sample standard deviation (ddof = 1) of ``values``; None where one is None or not finite, or there are
    fewer than two.

    Parameters
    ----------
    values : sequence of float or None
        One per seed.

    Returns
    -------
    float or None
        The spread.
    """
    v = [x for x in values if x is not None and np.isfinite(x)]
    return float(np.std(v, ddof=1)) if len(v) == len(values) and len(v) > 1 else None


# -- the answer: where the field-sequential error crosses the CFA's --------------------------------

def series(rows: Iterable[MotionRow], design: str, rolling: bool, metric: str) -> tuple[np.ndarray, np.ndarray]:
    """``(speeds, values)`` of one design and shutter, by speed; a missing value is NaN (``metric``: a
    :class:`MotionRow` field).

    Parameters
    ----------
    rows : iterable of MotionRow
        The run's rows.
    design : str
        ``arch/scheme``.
    rolling : bool
        The shutter.
    metric : str
        A :class:`MotionRow` field.

    Returns
    -------
    speeds : ndarray
        px/ms, ascending.
    values : ndarray
        The metric at each.
    """
    rs = sorted((r for r in rows if r.design == design and r.rolling_shutter == rolling),
                key=lambda r: r.speed_px_per_ms)
    values = [getattr(r, metric) for r in rs]
    return np.array([r.speed_px_per_ms for r in rs]), np.array([np.nan if x is None else x for x in values])


def crossing(speeds: np.ndarray, a: np.ndarray, b: np.ndarray) -> dict:
    """Where ``a − b`` (ΔE of the field-sequential design minus the CFA's) first turns positive.

    Parameters
    ----------
    speeds : ndarray
        px/ms, ascending.
    a, b : ndarray
        The two designs' values at each speed.

    Returns
    -------
    dict
        ``speed_px_per_ms`` (interpolated linearly between the swept speeds; 0 where ``a`` is worse at the
        first, None where it never is), ``status`` and, where it crosses, the two speeds ``between``.
    """
    diff = a - b
    if diff.size == 0:
        return {"speed_px_per_ms": None, "status": "no data"}
    if diff[0] > 0:
        return {"speed_px_per_ms": 0.0, "status": "worse already when still"}
    for i in range(1, diff.size):
        if diff[i] > 0:
            s = speeds[i - 1] + (speeds[i] - speeds[i - 1]) * (-diff[i - 1]) / (diff[i] - diff[i - 1])
            return {"speed_px_per_ms": float(s), "status": "crosses", "between": [float(speeds[i - 1]), float(speeds[i])]}
    return {"speed_px_per_ms": None, "status": f"better at every swept speed (up to {speeds[-1]:g} px/ms)"}


def seed_crossings(rows: Sequence[MotionRow], design: str, other: str, rolling: bool) -> dict:
    """The S-CIELAB crossing of ``design`` over ``other`` per noise seed (common random numbers: both see
    the same seeds), their mean and a 95 % Student-t interval; a seed that never crosses makes the
    interval open (``None``).

    Parameters
    ----------
    rows : sequence of MotionRow
        The run's rows.
    design, other : str
        The field-sequential design and the one it is compared with.
    rolling : bool
        The shutter.

    Returns
    -------
    dict
        ``by_seed_px_per_ms``; ``mean_px_per_ms`` and ``ci95_px_per_ms`` where every seed (two or more) crosses;
        empty without rows.
    """
    from scipy import stats

    def by_seed(d):
        rs = sorted((r for r in rows if r.design == d and r.rolling_shutter == rolling),
                    key=lambda r: r.speed_px_per_ms)
        return np.array([r.speed_px_per_ms for r in rs]), np.array([r.scielab_delta_e_by_seed for r in rs])

    s, a = by_seed(design)
    _, c = by_seed(other)
    n = min(a.shape[0], c.shape[0])
    if n == 0 or a.ndim != 2 or a.shape[1] < 1:
        return {}
    per = [crossing(s[:n], a[:n, j], c[:n, j])["speed_px_per_ms"] for j in range(min(a.shape[1], c.shape[1]))]
    out = {"by_seed_px_per_ms": per}
    if len(per) > 1 and all(p is not None for p in per):
        m, sd = float(np.mean(per)), float(np.std(per, ddof=1))
        h = float(stats.t.ppf(0.975, len(per) - 1) * sd / np.sqrt(len(per)))
        out.update(mean_px_per_ms=m, ci95_px_per_ms=[m - h, m + h])
    return out


def crossing_speeds(rows: Sequence[MotionRow]) -> dict:
    """For each field-sequential design and shutter: the speed at which its S-CIELAB error around the
    edge exceeds cfa/single's (and the same for CIELAB).

    Parameters
    ----------
    rows : sequence of MotionRow
        The run's rows.

    Returns
    -------
    dict
        Design (``" rolling"`` appended for the rolling shutter) → its crossings (:func:`crossing`, with
        :func:`seed_crossings` for S-CIELAB) and the still errors; and from which speed fsc/balanced beats
        fsc/optimal.  Empty without cfa/single.
    """
    out = {}
    designs = sorted({r.design for r in rows})
    if "cfa/single" not in designs:
        return out
    shutters = sorted({r.rolling_shutter for r in rows})
    for d in designs:
        if d == "cfa/single":
            continue
        for rolling in shutters:
            s, a = series(rows, d, rolling, "scielab_delta_e")
            _, c = series(rows, "cfa/single", rolling, "scielab_delta_e")
            _, a2 = series(rows, d, rolling, "cielab_delta_e")
            _, c2 = series(rows, "cfa/single", rolling, "cielab_delta_e")
            n = min(a.size, c.size)
            out[f"{d}{' rolling' if rolling else ''}"] = {
                "design": d, "rolling_shutter": rolling,
                "scielab": {**crossing(s[:n], a[:n], c[:n]), **seed_crossings(rows, d, "cfa/single", rolling)},
                "cielab": crossing(s[:n], a2[:n], c2[:n]),
                "still_scielab": [float(a[0]), float(c[0])]}
    for rolling in shutters:   # from which speed balanced beats optimal
        s, o = series(rows, "fsc/optimal", rolling, "scielab_delta_e")
        _, b = series(rows, "fsc/balanced", rolling, "scielab_delta_e")
        if o.size and o.size == b.size:
            out[f"balanced beats optimal{' rolling' if rolling else ''}"] = {"scielab": crossing(s, o, b)}
    return out
