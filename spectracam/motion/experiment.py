"""The motion experiment: when does the field-sequential camera's SNR advantage become a perceptual loss?

A slanted edge between two ColorChecker neutrals (:class:`~spectracam.spatial.targets.SlantedEdge`,
5°, 4:1) moves horizontally at a sweep of speeds (px/ms on the sensor; mm/s in the scene in
results.json) while each design captures it — ``cfa/single``, ``prism/optimal``, ``fsc/optimal``,
``fsc/balanced`` — with a global and with a rolling shutter. The exposure times are the paper's
(white-patch metering, :mod:`spectracam.exposure`) at the paper's light level (``cfa/single`` needs
28 ms at 5000 K), the windows those of :mod:`.timing`, the image the time integral of Mitsuba slices
(:mod:`.render`) through the spatial optics (diffraction, pixel aperture), recorded by the
architecture's own ``record`` **with the paper's sensor noise**, demosaicked, converted to the display
and scored against the same design's noise-free still capture (the edge at rest at the capture's
middle instant, t = 0) and against the static scene there:

* ``breakup_width_px`` — :func:`.metrics.breakup_width_px`: the width over which the chroma added to the
  design's own noise-free *still* capture (the edge at rest; the same exposures, demosaicking and
  conversion) by its noise-free moving capture exceeds ``breakup_threshold``: colour breakup from the
  motion alone, 0 at rest whatever the design's demosaicking false colour;
* ``false_colour_still`` — that still capture's chroma against the camera's conversion of the ideal image
  within 2 px of the edge, √(Δa*² + Δb*²): demosaicking false colour, its own metric;
* ``scielab_delta_e`` / ``cielab_delta_e`` — mean S-CIELAB / CIELAB ΔE*ab within ``zone_half_width_px``
  of the edge of the noisy capture against that still capture: what motion and noise add to the
  camera's own still photograph (at rest: the noise alone); mean over ``seeds`` noise seeds, ``_sd``
  their spread, ``scielab_delta_e_by_seed`` each;
* ``scielab_delta_e_scene`` / ``cielab_delta_e_scene`` / ``breakup_width_scene_px`` — the same against the
  ideal image of the scene (they also hold the conversion's constant error and the demosaicking false
  colour: what an observer comparing with the scene sees);
* ``mtf50_cy_per_px`` — e-SFR of the displayed luminance across the edge;
* ``snr_db`` — the paper's SNR of the design (chart patches, combined over channels) with the same
  light, exposure and noise: a flat patch's SNR does not depend on the motion.

The answer — the speed at which ``fsc/optimal``'s S-CIELAB error (against its own still capture) first
exceeds ``cfa/single``'s — is interpolated between the swept speeds (linearly in speed), for the mean
over seeds and for each seed (mean and 95 % interval).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..camera import photo_electron_rates
from ..chart import WHITE_PATCH
from ..errors import SpectracamError
from ..exposure import exposure_times_s
from ..metrics import delta_e, xyz_to_lab
from ..reference import ChartReference
from ..spec import Spec
from ..spatial import optics as sopt
from ..spatial.capture import Conversion, process, radiance_to_display_xyz, record, white_rate
from ..spatial.geometry import CameraGeometry
from ..spatial.scielab import samples_per_degree, scielab
from ..spatial.targets import SlantedEdge
from . import metrics as mm
from .motion import Motion
from .render import RENDER_MODES, MovingScene, channel_rates, ideal_radiance, integrate
from .timing import TimingSpec, capture_timing

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
        from ..camera import split_design

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
        self.boolean("noise")
        self.number("breakup_threshold", 0.0, 100.0, lo_open=True)
        self.number("zone_half_width_px", 1.0, 1e4, unit="px")
        self.number("viewing_distance_m", 0.0, 100.0, lo_open=True, unit="m")
        self.number("display_pixel_pitch_mm", 0.0, 100.0, lo_open=True, unit="mm")
        self.integer("seed", 0, 2**31 - 1)
        self.integer("seeds", 1, 50)

    def timing(self, rolling: bool) -> TimingSpec:
        return TimingSpec(self.order, self.readout_gap_ms, bool(rolling), self.line_time_us, self.prism_alignment)

    def quick(self) -> "MotionSpec":
        """A first look: a 64 × 64 edge (object pixels twice as large), 8 speeds, 8 samples per sub-pixel."""
        return self.replace(edge_size_px=tuple(max(32, x // 2) for x in self.edge_size_px),
                            object_pixel_mm=self.object_pixel_mm * 2,
                            speeds_px_per_ms=(0.0, 0.005, 0.01, 0.02, 0.03, 0.04, 0.08, 0.16),
                            samples_per_subpixel=min(self.samples_per_subpixel, 8),
                            zone_half_width_px=min(self.zone_half_width_px, 16.0))


def load_motion(sets=(), quick: bool = False):
    """``(MotionSpec, Scene)`` from ``--set`` overrides over the paper's camera and light
    (:func:`spectracam.scene.paper_scene`), as the spatial experiment reads them."""
    from ..scene import paper_scene
    from ..spatial.experiment import load_spec_and_scene

    return load_spec_and_scene(MotionSpec, sets, quick, base_scene=paper_scene())


def calibrated_scene(scene, spec: MotionSpec):
    """The scene at the light level where cfa/single needs ``cfa_exposure_ms`` (paper: 28 ms at 5000 K)."""
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


def motion_camera(scene, spec: MotionSpec):
    cam = scene.camera
    sensor = cam.sensor.replace(pixel_pitch_um=float(spec.pixel_pitch_um))
    if not spec.noise:
        sensor = sensor.off("shot_noise", "dark_current", "read_noise", "fpn", "quantization")
    return cam.replace(sensor=sensor, optics=cam.optics.replace(f_number=float(spec.f_number)))


def design_snr_db(scene, camera, design: str, seed: int) -> float | None:
    """The paper's SNR of a design (chart patches, 160 × 120 px, closed-form render) under the scene's light."""
    from ..pipeline import simulate
    from ..scene import ImageSpec

    sc = scene.replace(image=ImageSpec(160, 120), camera=camera.with_design(design))
    return simulate(sc, "analytic", seed)[2].summary.snr_combined_db


#: Bytes a motion run holds at its peak per rendered sub-pixel (margin included): a part per band
#: (the ideal sub-pixel cube, float32) and a part that is not (each channel group's time-integrated
#: basis in float64, the optical transfers and FFTs, the images kept for the report).  Measured with
#: `/usr/bin/time -v` on 64- and 160-px edges, 15 and 30 bands: 356 + 42.5·bands above the
#: interpreter's own; about 10 % added.
MEMORY_PER_SUBPIXEL_BYTES = (400.0, 48.0)


def check_motion_memory(spec: MotionSpec, scene) -> None:
    """Refuse, before any work, a motion run larger than the memory this process may use."""
    from ..pipeline import check_bytes

    m = sopt.margin_px(spec.pixel_pitch_um, spec.f_number, scene.grid.edges_nm[-1])
    w, h = spec.edge_size_px
    subpixels = (w + 2 * m) * (h + 2 * m) * spec.supersampling ** 2
    fixed, per_band = MEMORY_PER_SUBPIXEL_BYTES
    check_bytes(subpixels * (fixed + per_band * len(scene.grid)),
                f"edge_size_px = [{w}, {h}] (+{m} px margin) at supersampling = {spec.supersampling} with "
                f"{len(scene.grid)} bands", "use a smaller edge, less supersampling or fewer bands")


def run_motion(spec: MotionSpec, scene, renderer: str = "mitsuba", log=None, keep_images: bool = True) -> dict:
    """Every design × speed × shutter. Returns ``{"rows", "images", "timings", ...}``."""
    log = log or (lambda msg: None)
    t_start = time.perf_counter()
    scene = calibrated_scene(scene, spec)
    grid = scene.grid
    ref = ChartReference.of(scene)
    base = motion_camera(scene, spec)
    w, h = spec.edge_size_px
    geometry = CameraGeometry.framing(w * spec.object_pixel_mm, spec.focal_length_mm, spec.f_number,
                                      spec.pixel_pitch_um, w, h)
    m = sopt.margin_px(spec.pixel_pitch_um, spec.f_number, grid.edges_nm[-1])
    big = geometry.with_margin(m)
    target = SlantedEdge(angle_deg=spec.edge_angle_deg, dataset=scene.chart.dataset)
    timings = dict.fromkeys(("render", "optics", "capture", "processing", "metrics", "snr"), 0.0)
    t0 = time.perf_counter()
    moving = MovingScene(target, big, scene.illuminant, grid, spec.supersampling, renderer, spec.render_mode,
                         scene.render.variant, spec.seed, log)
    ideal = ideal_radiance(moving, spec.samples_per_subpixel, m)
    timings["render"] += time.perf_counter() - t0
    settings = sopt.OpticsSettings()
    spd = samples_per_degree(spec.viewing_distance_m, spec.display_pixel_pitch_mm * 1e-3)
    b = SCORE_BORDER_PX
    valid = np.zeros((h, w), bool)
    valid[b:-b, b:-b] = True
    cols0 = mm.edge_columns(w, h, target.x0_px, spec.edge_angle_deg)
    rows, images, curves, snr, timing_info = [], {}, [], {}, {}
    direction = math.radians(spec.direction_deg)
    seeds = [spec.seed + i for i in range(spec.seeds if spec.noise else 1)]   # noise-free: one is all there is
    for design in spec.designs:
        t0 = time.perf_counter()
        camera = base.with_design(design)
        snr[design] = design_snr_db(scene, camera, design, spec.seed) if spec.noise else None
        timings["snr"] += time.perf_counter() - t0
        conv = Conversion.fit(ref, camera, scene.processing)
        white = white_rate(ref, camera)
        arch = camera.architecture()
        times = exposure_times_s(camera.capture.exposure, white, camera.sensor, arch, camera.capture.white_fill)
        ideal_xyz = radiance_to_display_xyz(ideal, grid, scene.illuminant.white_luminance_cd_m2, conv)
        own_xyz = photo_electron_rates(ideal.astype(np.float32), grid, camera).astype(np.float64) \
            @ conv.matrix @ conv.rgb_to_xyz.T
        quiet = camera.replace(sensor=camera.sensor.off("shot_noise", "dark_current", "read_noise", "fpn",
                                                        "quantization"))
        for rolling in spec.rolling_shutter:
            timing = capture_timing(arch, times, spec.timing(rolling), big.height_px, -m)
            timing_info[f"{design}{' rolling' if rolling else ''}"] = timing.to_dict()
            still = None      # the design's noise-free still capture (display XYZ): the motion metrics' reference
            for v in ((0.0,) if spec.speeds_px_per_ms[0] > 0 else ()) + spec.speeds_px_per_ms:
                vmm = v * 1e3 * spec.object_pixel_mm
                motion = Motion(velocity_mm_per_s=(vmm * math.cos(direction), vmm * math.sin(direction)),
                                angular_velocity_deg_per_s=spec.angular_velocity_deg_per_s,
                                shake_rms_px=spec.shake_rms_px, seed=spec.seed)
                t1 = time.perf_counter()
                integ = integrate(moving, motion, timing, spec.max_step_px, spec.slices, spec.samples_per_subpixel)
                t2 = time.perf_counter()
                rates = channel_rates(moving, integ, camera, settings, m)
                t3 = time.perf_counter()
                noisy = [process(record(rates, camera, white, sd, times), scene.processing, conv) for sd in seeds]
                cam_rates, xyz = noisy[0]
                t4 = time.perf_counter()
                quiet_xyz = xyz if not spec.noise else process(record(rates, quiet, white, spec.seed, times),
                                                               scene.processing, conv)[1]
                t5 = time.perf_counter()
                if still is None:
                    still = quiet_xyz
                    zone_still = mm.edge_zone(mm.edge_distance((h, w), cols0), 2.0) & valid
                    lab_s, lab_o = (xyz_to_lab(a, conv.display_white) for a in (still, own_xyz))
                    false_colour_still = float(np.hypot(*(lab_s - lab_o)[..., 1:].transpose(2, 0, 1))[zone_still].mean())
                if v not in spec.speeds_px_per_ms:
                    continue   # the still reference only
                # the edge's columns: each row's later window shifts a uniformly moving edge (rolling shutter)
                delay = timing.row_delay_s[m:m + h]
                shift = v * 1e3 * math.cos(direction) * (delay - delay.mean())
                dist = mm.edge_distance((h, w), cols0 + shift)
                zone = mm.edge_zone(dist, spec.zone_half_width_px) & valid
                # colour breakup: the motion alone (noise-free moving capture against the noise-free still one)
                d, chroma = mm.chroma_profile(quiet_xyz, still, conv.display_white, dist, 0.5,
                                              spec.zone_half_width_px, valid)
                d_s, chroma_s = mm.chroma_profile(xyz, own_xyz, conv.display_white, dist, 0.5,
                                                  spec.zone_half_width_px, valid)
                per_seed = {k: [] for k in ("scielab_delta_e", "cielab_delta_e", "scielab_delta_e_scene",
                                            "cielab_delta_e_scene", "mtf50_cy_per_px")}
                lab_still = xyz_to_lab(still, conv.display_white)
                lab_ideal = xyz_to_lab(ideal_xyz, conv.display_white)
                for _, x in noisy:
                    lab = xyz_to_lab(x, conv.display_white)
                    per_seed["scielab_delta_e"].append(float(scielab(still, x, conv.display_white, spd)[zone].mean()))
                    per_seed["cielab_delta_e"].append(float(delta_e(lab, lab_still)[zone].mean()))
                    per_seed["scielab_delta_e_scene"].append(float(scielab(ideal_xyz, x, conv.display_white, spd)[zone].mean()))
                    per_seed["cielab_delta_e_scene"].append(float(delta_e(lab, lab_ideal)[zone].mean()))
                    f_s, sfr_s, mtf50_s = mm.mtf_along_motion(x, b)
                    per_seed["mtf50_cy_per_px"].append(mtf50_s)
                    if x is xyz:   # the first seed's curve is the one drawn
                        f, sfr = f_s, sfr_s
                t6 = time.perf_counter()
                for k, dt in zip(("render", "optics", "capture", "processing", "metrics"),
                                 (t2 - t1, t3 - t2, t4 - t3, t5 - t4, t6 - t5)):
                    timings[k] += dt
                row = {"design": design, "speed_px_per_ms": v, "speed_mm_per_s": vmm, "rolling_shutter": bool(rolling),
                       "breakup_width_px": mm.breakup_width_px(d, chroma, spec.breakup_threshold),
                       "max_added_chroma": float(np.nanmax(np.append(chroma, 0.0))),
                       "breakup_width_scene_px": mm.breakup_width_px(d_s, chroma_s, spec.breakup_threshold),
                       "false_colour_still": false_colour_still,
                       **{k: _mean_or_none(vals) for k, vals in per_seed.items()},
                       **{f"{k}_sd": _sd_or_none(vals) for k, vals in per_seed.items()},
                       "scielab_delta_e_by_seed": per_seed["scielab_delta_e"], "seeds": list(seeds),
                       "snr_db": snr[design],
                       "blur_px": v * 1e3 * timing.capture_time_s,
                       "capture_time_ms": 1e3 * timing.capture_time_s,
                       "exposure_ms": (1e3 * np.asarray(times)).tolist(), **integ.info}
                rows.append(row)
                curves.append({"design": design, "speed_px_per_ms": v, "rolling_shutter": bool(rolling),
                               "frequencies_cy_per_px": f[:80].tolist(), "sfr": sfr[:80].tolist()})
                if keep_images:
                    images[(design, v, bool(rolling))] = {"xyz": xyz.astype(np.float32),
                                                          "cam_rates": cam_rates.astype(np.float32),
                                                          "chroma": (d, chroma)}
            log(f"[{time.perf_counter() - t_start:6.1f} s] {design}{' rolling shutter' if rolling else ''}: "
                f"{len(spec.speeds_px_per_ms)} speeds ({moving.renders} slice renders so far)")
        if keep_images:
            images[(design, "ideal")] = {"xyz": ideal_xyz.astype(np.float32)}
    return {"rows": rows, "mtf_curves": curves, "images": images, "timings": timings,
            "exposure_timing": timing_info, "display_white": conv.display_white, "renderer": renderer,
            "render_metadata": moving.metadata, "slice_renders": moving.renders,
            "answer": crossing_speeds(rows),
            "parameters": {"motion": spec.to_dict(), "scene": scene.to_dict(), "geometry": geometry.to_dict(),
                           "white_luminance_cd_m2": scene.illuminant.white_luminance_cd_m2,
                           "samples_per_degree": spd},
            "wall_s": time.perf_counter() - t_start}


def _mean_or_none(values):
    v = [x for x in values if x is not None and np.isfinite(x)]
    return float(np.mean(v)) if len(v) == len(values) and v else None


def _sd_or_none(values):
    v = [x for x in values if x is not None and np.isfinite(x)]
    return float(np.std(v, ddof=1)) if len(v) == len(values) and len(v) > 1 else None


def _get(rows, design, rolling, key):
    rs = sorted((r for r in rows if r["design"] == design and r["rolling_shutter"] == rolling),
                key=lambda r: r["speed_px_per_ms"])
    return np.array([r["speed_px_per_ms"] for r in rs]), np.array([np.nan if r[key] is None else r[key] for r in rs])


def crossing(speeds, a, b) -> dict:
    """Where ``a − b`` (ΔE of the field-sequential design minus the CFA's) first turns positive."""
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


def seed_crossings(rows, design: str, other: str, rolling: bool) -> dict:
    """The S-CIELAB crossing of ``design`` over ``other`` per noise seed (common random numbers: both see
    the same seeds), their mean and a 95 % Student-t interval; a seed that never crosses makes the
    interval open (``None``)."""
    from scipy import stats

    def series(d):
        rs = sorted((r for r in rows if r["design"] == d and r["rolling_shutter"] == rolling),
                    key=lambda r: r["speed_px_per_ms"])
        return np.array([r["speed_px_per_ms"] for r in rs]), np.array([r["scielab_delta_e_by_seed"] for r in rs])

    s, a = series(design)
    _, c = series(other)
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


def crossing_speeds(rows) -> dict:
    """For each field-sequential design and shutter: the speed at which its S-CIELAB error around the
    edge exceeds cfa/single's (and the same for CIELAB)."""
    out = {}
    designs = sorted({r["design"] for r in rows})
    if "cfa/single" not in designs:
        return out
    for d in designs:
        if d == "cfa/single":
            continue
        for rolling in sorted({r["rolling_shutter"] for r in rows}):
            s, a = _get(rows, d, rolling, "scielab_delta_e")
            _, c = _get(rows, "cfa/single", rolling, "scielab_delta_e")
            _, a2 = _get(rows, d, rolling, "cielab_delta_e")
            _, c2 = _get(rows, "cfa/single", rolling, "cielab_delta_e")
            n = min(a.size, c.size)
            out[f"{d}{' rolling' if rolling else ''}"] = {
                "design": d, "rolling_shutter": rolling,
                "scielab": {**crossing(s[:n], a[:n], c[:n]), **seed_crossings(rows, d, "cfa/single", rolling)},
                "cielab": crossing(s[:n], a2[:n], c2[:n]),
                "still_scielab": [float(a[0]), float(c[0])]}
    for rolling in sorted({r["rolling_shutter"] for r in rows}):   # from which speed balanced beats optimal
        s, o = _get(rows, "fsc/optimal", rolling, "scielab_delta_e")
        _, b = _get(rows, "fsc/balanced", rolling, "scielab_delta_e")
        if o.size and o.size == b.size:
            out[f"balanced beats optimal{' rolling' if rolling else ''}"] = {"scielab": crossing(s, o, b)}
    return out
