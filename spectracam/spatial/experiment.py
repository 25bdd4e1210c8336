"""The spatial experiment: the paper's next step ("incorporate spatial factors to understand how the
elimination of demosaicing provides a spatial advantage for FSC").

For each pixel pitch × f-number (a *case*) and each target (slanted edge, Siemens star, tilted
ColorChecker) the target is rendered on a sub-pixel grid (:mod:`.render`), filtered by the optics and
sampled by each design (:mod:`.optics`, :mod:`.capture`) — ``cfa/single`` with each demosaicking
method, ``prism/optimal`` aligned and misaligned, ``fsc/optimal`` — processed to the display and
scored against the ideal image (each pixel's footprint of the scene, no optics, no sampling):

* ``mtf50_cy_per_px`` — ISO 12233:2017 e-SFR of the displayed luminance Y on the slanted edge (with
  :func:`~spectracam.spatial.esfr.esfr`'s binning correction), where it falls to 0.5; per channel too;
* ``false_colour`` — on neutral targets, the mean chroma error ``√(Δa*² + Δb*²)`` in the edge zone
  (pixels within 2 px of where the ideal image's L* changes) against the same camera's rendering of
  the ideal image: colour the spatial processing made, not the colour conversion's constant tint;
* ``scielab_delta_e`` — mean S-CIELAB ΔE*ab (Zhang & Wandell 1997) over the target's region, against
  the ideal image of the scene (so it includes the conversion error the paper measures);
* ``cielab_delta_e`` — mean per-pixel CIELAB ΔE*ab over the same region (no spatial filtering);
* ``scielab_delta_e_spatial``, ``cielab_delta_e_spatial`` — the same against the camera's own
  rendering of the ideal image: the spatial error alone (optics, sampling, demosaicking, misregistration).

The ideal image is each pixel's footprint of the scene (the renderer's radiance averaged over the
pixel: no optics, no sampling); its XYZ is carried to the display white as the paper scores colour.

Stages are timed (render, optics, capture, processing, metrics) per target.
"""
from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from ..camera import CAMERA_TABLES, CameraSpec, band_weights, photo_electron_rates
from ..color import DEMOSAIC_METHODS
from ..errors import ConfigError
from ..metrics import delta_e, xyz_to_lab
from ..reference import ChartReference
from ..spec import Spec
from . import optics as sopt
from .capture import (Conversion, SpatialDesign, misregistration_shifts, process, radiance_to_display_xyz, record,
                      white_rate)
from .esfr import NoEdge, esfr
from .geometry import CameraGeometry
from .render import SubpixelCube, defocus_diameter_um, material_radiance, render_target
from .scielab import samples_per_degree, scielab
from .targets import SiemensStar, SlantedEdge, Target, TiltedChart

TARGETS = ("edge", "star", "chart")
STAGES = ("render", "optics", "capture", "processing", "metrics")
#: Pixels cut from every side before scoring: demosaicking's border rows and columns.
SCORE_BORDER_PX = 4


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
    #: Turned 40° about the vertical axis: the right edge is ~90 mm farther than the left.
    chart_tilt_deg: float = 40.0
    chart_field_mm: float = 300.0
    #: Object-plane size of a pixel for the edge and the star (their scale does not matter: they are in focus).
    object_pixel_mm: float = 0.5
    #: Sensor noise of the paper's camera (off: the spatial artefacts alone, noise-free and unquantised).
    noise: bool = False
    cos4: bool = False
    #: S-CIELAB viewing: one image pixel per display pixel of 120 dpi seen from 0.5 m (ISETCam's default, 41 px/°).
    viewing_distance_m: float = 0.5
    display_pixel_pitch_mm: float = 25.4 / 120
    seed: int = 0

    def validate(self) -> None:
        self.numbers("pixel_pitches_um", len(self.pixel_pitches_um), 0.1, lo_open=True, unit="µm")
        self.numbers("f_numbers", len(self.f_numbers), 0.5, unit="")
        for name, allowed in (("targets", TARGETS), ("demosaics", DEMOSAIC_METHODS.names)):
            v = getattr(self, name)
            if not isinstance(v, tuple) or not v or any(x not in allowed for x in v):
                raise self.error(name, "must be a non-empty list of " + ", ".join(map(repr, allowed)),
                                 list(v) if isinstance(v, tuple) else v)
        if "patch" in self.demosaics:
            raise self.error("demosaics", "'patch' reads flat patches only; use bilinear, malvar2004, menon2007",
                             list(self.demosaics))
        from ..camera import split_design

        if not isinstance(self.designs, tuple) or not self.designs:
            raise self.error("designs", "must be a non-empty list of 'arch/scheme', e.g. ['cfa/single', 'fsc/optimal']",
                             list(self.designs) if isinstance(self.designs, tuple) else self.designs)
        for d in self.designs:
            split_design(d, "designs")
        self.numbers("olpf_separations_px", len(self.olpf_separations_px), 0.0, unit="px")
        if not self.olpf_separations_px or any(x > sopt.MARGIN_PX / 2 for x in self.olpf_separations_px):
            raise self.error("olpf_separations_px", f"must be a non-empty list of separations from 0 to "
                             f"{sopt.MARGIN_PX / 2:g} px (0: no filter)", list(self.olpf_separations_px))
        self.numbers("misregistrations_px", len(self.misregistrations_px), 0.0, unit="px")
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
        for name in ("edge_size_px", "star_size_px", "chart_size_px"):
            self.numbers(name, 2, 32.0, unit="px")
            object.__setattr__(self, name, tuple(int(x) for x in getattr(self, name)))
        self.number("edge_angle_deg", 2.0, 10.0, unit="°")
        self.integer("star_cycles", 4, 720)
        self.number("chart_tilt_deg", 0.0, 70.0, unit="°")
        self.number("chart_field_mm", 10.0, 10000.0, unit="mm")
        self.number("object_pixel_mm", 1e-4, 1e3, lo_open=True, unit="mm")
        self.boolean("noise", "cos4")
        self.number("viewing_distance_m", 0.0, 100.0, lo_open=True, unit="m")
        self.number("display_pixel_pitch_mm", 0.0, 100.0, lo_open=True, unit="mm")
        self.integer("seed", 0, 2**31 - 1)
        self.spatial_designs()   # a mosaic no demosaicking method takes is refused here

    @property
    def samples_per_degree(self) -> float:
        return samples_per_degree(self.viewing_distance_m, self.display_pixel_pitch_mm * 1e-3)

    def spatial_designs(self) -> list[SpatialDesign]:
        """Each design of ``designs``: a mosaic with every demosaicking method that takes it and every
        optical low-pass filter; separate sensors (a prism) at every misregistration; anything else once."""
        from ..architecture import MosaicLayout, PlanesLayout
        from ..color import demosaic_applies

        out = []
        for design in self.designs:
            arch = CameraSpec().with_design(design).architecture()
            layout = arch.layout
            if isinstance(layout, MosaicLayout):
                methods = [dm for dm in self.demosaics if demosaic_applies(dm, layout)]
                if not methods:
                    raise self.error("demosaics", f"none of them takes {design}'s {len(layout.channels)}-channel "
                                     "mosaic; add 'bilinear' (any periodic mosaic)", list(self.demosaics))
                out += [SpatialDesign(design, dm, None, o) for dm in methods for o in self.olpf_separations_px]
            elif isinstance(layout, PlanesLayout) and layout.kind == "sensors":
                out += [SpatialDesign(design, None, m) for m in self.misregistrations_px]
            else:
                out.append(SpatialDesign(design))
        return out

    def quick(self) -> "SpatialSpec":
        """A first look: every case, target and design at half the image size (and 20-nm bands, see
        :func:`load_spatial`), 2 samples per sub-pixel."""
        half = lambda t: tuple(max(32, int(x) // 2) for x in t)  # noqa: E731
        return self.replace(edge_size_px=half(self.edge_size_px), star_size_px=half(self.star_size_px),
                            chart_size_px=half(self.chart_size_px), star_cycles=max(4, self.star_cycles // 2),
                            samples_per_subpixel=min(self.samples_per_subpixel, 2),
                            star_samples_per_subpixel=min(self.star_samples_per_subpixel, 2),
                            object_pixel_mm=self.object_pixel_mm * 2)


#: Tables of a scene file the experiment takes its light, bands, camera and processing from.
SCENE_KEYS = ("illuminant", "wavelengths", "chart", "render", *CAMERA_TABLES, "processing")


def load_spatial(sets=(), quick: bool = False):
    """``(SpatialSpec, Scene)`` from ``--set`` overrides: top-level keys are the experiment's, tables
    (``illuminant``, ``wavelengths``, ``sensor``, ``optics``, ``filters``, ``processing``, …) the scene's."""
    return load_spec_and_scene(SpatialSpec, sets, quick)


def load_spec_and_scene(spec_cls, sets=(), quick: bool = False, base_scene=None):
    """``(spec_cls spec, Scene)`` from ``--set`` overrides (the spatial and the motion experiments):
    top-level keys are the experiment's, tables the scene's (over ``base_scene``'s tables when given,
    else the defaults); ``quick``: the spec's ``quick()`` and 20-nm bands."""
    from ..overrides import apply_overrides
    from ..scene import Scene

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


def make_target(name: str, spec: SpatialSpec, scene) -> tuple[Target, tuple[int, int], float]:
    """The target, its image size (width, height) and the object-plane field width it is framed to, mm."""
    if name == "edge":
        w, h = spec.edge_size_px
        return SlantedEdge(angle_deg=spec.edge_angle_deg, dataset=scene.chart.dataset), (w, h), w * spec.object_pixel_mm
    if name == "star":
        w, h = spec.star_size_px
        return (SiemensStar(cycles=spec.star_cycles, radius_px=0.47 * min(w, h), dataset=scene.chart.dataset), (w, h),
                w * spec.object_pixel_mm)
    if name == "chart":
        w, h = spec.chart_size_px
        return TiltedChart(tilt_deg=spec.chart_tilt_deg, chart=scene.chart), (w, h), spec.chart_field_mm
    raise ConfigError("targets", name, "must be one of " + ", ".join(map(repr, TARGETS)))  # never a silent chart


def case_camera(scene, spec: SpatialSpec, pitch_um: float, f_number: float) -> CameraSpec:
    cam = scene.camera
    sensor = cam.sensor.replace(pixel_pitch_um=float(pitch_um))
    if not spec.noise:
        sensor = sensor.off("shot_noise", "dark_current", "read_noise", "fpn", "quantization")
    return cam.replace(sensor=sensor, optics=cam.optics.replace(f_number=float(f_number)))


def _edge_zone(lab_ideal: np.ndarray, width_px: int = 2) -> np.ndarray:
    from scipy import ndimage

    L = lab_ideal[..., 0]
    g = np.hypot(*np.gradient(L))
    return ndimage.binary_dilation(g > 1.0, iterations=width_px)


def score_image(target: Target, geometry: CameraGeometry, xyz: np.ndarray, ideal_xyz: np.ndarray,
                own_xyz: np.ndarray, cam_rates: np.ndarray, white: np.ndarray, spd: float,
                channels=("R", "G", "B")) -> dict:
    """The metrics of one processed image (display XYZ) against the ideal image of the scene
    (``ideal_xyz``) and against the same camera's rendering of that ideal image (``own_xyz``: its colour
    conversion error without any spatial error) — see the module."""
    b = SCORE_BORDER_PX
    region = target.region(geometry).copy()
    region[:b], region[-b:], region[:, :b], region[:, -b:] = False, False, False, False
    lab = xyz_to_lab(xyz, white)
    lab_i = xyz_to_lab(ideal_xyz, white)
    lab_o = xyz_to_lab(own_xyz, white)
    de = delta_e(lab, lab_i)
    sc = scielab(ideal_xyz, xyz, white, spd)
    sc_o = scielab(own_xyz, xyz, white, spd)
    out = {"cielab_delta_e": float(de[region].mean()), "scielab_delta_e": float(sc[region].mean()),
           "cielab_delta_e_spatial": float(delta_e(lab, lab_o)[region].mean()),
           "scielab_delta_e_spatial": float(sc_o[region].mean()),
           "scielab_delta_e_spatial_p95": float(np.percentile(sc_o[region], 95)), "false_colour": None,
           "mtf50_cy_per_px": None, "_scielab_map": sc_o, "_region": region}
    if target.neutral:   # chroma the camera's own rendering of the ideal image does not have, at the edges
        zone = _edge_zone(lab_i) & region
        out["false_colour"] = float(np.hypot(*(lab - lab_o)[..., 1:].transpose(2, 0, 1))[zone].mean())
    if isinstance(target, TiltedChart):
        masks = target.patch_masks(geometry)
        out["patch_delta_e"] = float(np.mean([de[m].mean() for m in masks if m.any()]))
    if isinstance(target, SlantedEdge):
        crop = (slice(b, -b), slice(b, -b))
        lum = _esfr_or_none(xyz[crop][..., 1])
        out["mtf50_cy_per_px"] = None if lum is None else _finite(lum.mtf50_cy_per_px)
        curves = {"Y": [] if lum is None else lum.sfr}
        out["mtf50_channels_cy_per_px"] = {}
        for k, c in enumerate(channels):   # a channel may see too weak a step for an e-SFR: no MTF, not an abort
            r = _esfr_or_none(cam_rates[crop][..., k])
            n = min(r.sfr.size, len(curves["Y"])) if r is not None else 0
            curves[c] = [] if r is None else r.sfr[:n]
            out["mtf50_channels_cy_per_px"][c] = None if r is None else _finite(r.mtf50_cy_per_px)
        out["_mtf"] = {"frequencies_cy_per_px": [] if lum is None else lum.frequencies_cy_per_px, **curves,
                       "edge_angle_deg": None if lum is None else lum.edge_angle_deg}
    return out


def run_spatial(spec: SpatialSpec, scene, renderer: str = "mitsuba", log=None, keep_images: bool = True) -> dict:
    """Run every case × target × design. Returns ``{"rows", "mtf_curves", "timings", "images", ...}``."""
    log = log or (lambda msg: None)
    grid = scene.grid
    ref = ChartReference.of(scene)
    spd = spec.samples_per_degree
    timings = {t: dict.fromkeys(STAGES, 0.0) for t in spec.targets}
    rows, curves, images, closed = [], [], {}, {}
    designs = spec.spatial_designs()
    renders: dict = {}
    t_start = time.perf_counter()
    for pitch in spec.pixel_pitches_um:
        # one margin per pitch (flat targets are rendered once per pitch): wide enough for the slowest lens
        margin = max(sopt.margin_px(pitch, N, grid.edges_nm[-1], max(spec.misregistrations_px))
                     for N in spec.f_numbers)
        for N in spec.f_numbers:
            base = case_camera(scene, spec, pitch, N)
            columns, design_columns = channel_columns(base, grid, spec.designs)   # the case's band weights
            for tname in spec.targets:
                target, (w, h), field_mm = make_target(tname, spec, scene)
                geometry = CameraGeometry.framing(field_mm, spec.focal_length_mm, N, pitch, w, h)
                if isinstance(target, TiltedChart):
                    geometry = dataclasses.replace(geometry, focus_distance_mm=geometry.object_distance_mm)
                big = geometry.with_margin(margin)
                # -- render (flat targets in focus look the same at every f-number: one render per pitch)
                t0 = time.perf_counter()
                key = (tname, pitch, N if isinstance(target, TiltedChart) else None)
                ss = spec.chart_supersampling if tname == "chart" else spec.supersampling
                spp = spec.star_samples_per_subpixel if tname == "star" else spec.samples_per_subpixel
                if key not in renders:
                    renders[key] = render_target(renderer, target, big, scene.illuminant, grid, ss, spp,
                                                 spec.seed + len(renders), scene.render.variant, log)
                cube: SubpixelCube = renders[key]
                t1 = time.perf_counter()
                timings[tname]["render"] += t1 - t0
                # -- optics, per band, shared by every design of this case: each distinct channel once
                settings = sopt.OpticsSettings(defocus_um=defocus_diameter_um(target, big, cube), cos4=spec.cos4)
                spectra, fy, fx, shape = sopt.channel_spectra(cube.radiance, cube.wavelengths_nm, ss,
                                                              base, grid, settings, workers=-1, weights=columns)
                ideal = cube.pixel_average()[margin:-margin, margin:-margin]
                t2 = time.perf_counter()
                timings[tname]["optics"] += t2 - t1
                sampled: dict = {}
                case = {"pixel_pitch_um": float(pitch), "f_number": float(N), "target": tname}
                if tname == "edge":
                    L = material_radiance(target, scene.illuminant, grid)
                    Wb = band_weights(base, grid)[:, 1] * (L[1] - L[0])
                    f = np.linspace(0, 1, 201)
                    closed[(pitch, N)] = {o: sopt.channel_mtf_closed_form(f, spec.edge_angle_deg, pitch, N, grid.centres_nm,
                                                                          Wb, base.sensor.fill_factor, o)
                                          for o in {0.0, *spec.olpf_separations_px}}
                    closed[(pitch, N)]["f"] = f
                for d in designs:
                    camera = base.with_design(d.design)
                    processing = scene.processing.replace(demosaic=d.demosaic or scene.processing.demosaic)
                    t2 = time.perf_counter()
                    shifts = misregistration_shifts(d.misregistration_px)
                    cols = design_columns[d.design]
                    key = (cols, shifts, d.olpf_separation_px)
                    if key not in sampled:
                        rates = sopt.sample_channels(spectra[list(cols)], fy, fx, shape, ss, base.sensor.fill_factor,
                                                     shifts, margin, workers=-1, olpf_separation_px=d.olpf_separation_px)
                        if spec.cos4:
                            rates *= geometry.off_axis_cos4()[:, :, None].astype(np.float32)
                        sampled[key] = rates
                    rates = sampled[key]
                    t3 = time.perf_counter()
                    timings[tname]["optics"] += t3 - t2
                    conv = Conversion.fit(ref, camera, processing)
                    raw = record(rates, camera, white_rate(ref, camera), spec.seed)
                    t4 = time.perf_counter()
                    timings[tname]["capture"] += t4 - t3
                    cam_rates, xyz = process(raw, processing, conv)
                    ideal_xyz = radiance_to_display_xyz(ideal, grid, scene.illuminant.white_luminance_cd_m2, conv)
                    own_xyz = photo_electron_rates(ideal.astype(np.float32), grid, camera).astype(np.float64) \
                        @ conv.matrix @ conv.rgb_to_xyz.T
                    t5 = time.perf_counter()
                    timings[tname]["processing"] += t5 - t4
                    m = score_image(target, geometry, xyz, ideal_xyz, own_xyz, cam_rates, conv.display_white, spd,
                                    raw.layout.channels)
                    timings[tname]["metrics"] += time.perf_counter() - t5
                    row = {"design": d.design, "demosaic": d.demosaic,
                           "misregistration_px": float(d.misregistration_px or 0.0),
                           "olpf_separation_px": float(d.olpf_separation_px), "label": d.label, **case,
                           **{k: v for k, v in m.items() if not k.startswith("_")},
                           "capture_time_ms": 1e3 * raw.capture_time_s,
                           "defocus_max_um": _max_defocus(target, geometry)}
                    rows.append(row)
                    if "_mtf" in m:
                        curves.append({"label": d.label, **case, "design": d.design, "demosaic": d.demosaic,
                                       "misregistration_px": float(d.misregistration_px or 0.0),
                                       "olpf_separation_px": float(d.olpf_separation_px),
                                       **{k: (v.tolist() if isinstance(v, np.ndarray) else v)
                                          for k, v in m["_mtf"].items()}})
                    if keep_images:
                        images[(pitch, N, tname, d.label)] = {"xyz": xyz.astype(np.float32),
                                                              "scielab": m["_scielab_map"].astype(np.float32),
                                                              "region": m["_region"]}
                if keep_images:
                    images[(pitch, N, tname, "ideal")] = {"xyz": ideal_xyz.astype(np.float32)}
                log(f"[{time.perf_counter() - t_start:6.1f} s] {pitch:g} µm, f/{N:g}, {tname}: "
                    f"{len(designs)} designs scored")
    return {"rows": rows, "mtf_curves": curves, "timings": timings, "images": images,
            "closed_form": {f"{p:g}um_f{n:g}": {"frequencies_cy_per_px": v["f"].tolist(), "G": v[0.0].tolist()}
                            | {f"G OLPF {o:g} px": v[o].tolist() for o in spec.olpf_separations_px if o > 0}
                            for (p, n), v in closed.items()},
            "display_white": Conversion.fit(ref, case_camera(scene, spec, spec.pixel_pitches_um[0],
                                                             spec.f_numbers[0]), scene.processing).display_white,
            "samples_per_degree": spd, "renderer": renderer,
            "render_metadata": {f"{k[0]}_{k[1]:g}um" + (f"_f{k[2]:g}" if k[2] else ""): v.metadata
                                for k, v in renders.items()},
            "parameters": {"spatial": spec.to_dict(), "scene": scene.to_dict(),
                           "fill_factor": scene.camera.sensor.fill_factor,
                           "misregistration": "red sensor shifted +m px along x, blue +m px along y, before sampling",
                           "olpf": "4-spot birefringent filter: spots at (±d/2, ±d/2) px, OTF cos(π fx d)·cos(π fy d)"},
            "wall_s": time.perf_counter() - t_start}


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


def _esfr_or_none(image):
    try:
        return esfr(image, correct_binning=True)
    except NoEdge:
        return None


def _finite(x):
    return float(x) if np.isfinite(x) else None


def _max_defocus(target: Target, geometry: CameraGeometry) -> float:
    if isinstance(target, TiltedChart):
        lo, hi = target.depth_range_mm(geometry)
        return float(max(geometry.blur_diameter_um(lo), geometry.blur_diameter_um(hi)))
    return float(geometry.blur_diameter_um(geometry.object_distance_mm))
