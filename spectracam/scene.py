"""The scene description: dataclasses, TOML loading and validation.

A scene file has the tables ``[chart]``, ``[illuminant]``, ``[wavelengths]``, ``[image]`` and
``[render]`` (all optional, defaults below) and an optional top-level ``name``.  Any unknown key,
wrong type or out-of-range value raises :class:`ConfigError` naming the field, the value and what
is allowed.
"""
from __future__ import annotations

import dataclasses
import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .architecture import ARCHITECTURES, CFA_PATTERNS
from .capture import CameraSpec
from .chart import DATASETS, ChartSpec, dataset_range_nm
from .color import ADAPTATIONS, DEMOSAIC_METHODS, DISPLAYS, ProcessingSpec
from .metrics import DELTA_E_METHODS, SNR_COMBINATIONS
from .exposure import EXPOSURE_SCHEMES
from .filters import CAMERAS, FILTER_KINDS, QE_KINDS, FilterSpec
from .optics import IRRADIANCE_FORMS, OpticsSpec
from .sensor import FPN_READINGS, SHOT_NOISE_MODELS, SensorSpec
from .errors import ConfigError
from .illuminant import TEMPERATURE_RANGE_K, IlluminantSpec
from .spectra import CIE_RANGE_NM, WavelengthGrid

VARIANTS = ("auto", "llvm", "scalar", "cuda")
#: Fewest pixels across a patch's mask: a 4×4 mask still holds 4 pixels of each Bayer colour.
MIN_PATCH_PX = 4


@dataclass(frozen=True)
class ImageSpec:
    width: int = 640
    height: int = 480


@dataclass(frozen=True)
class RenderSpec:
    #: Samples per pixel per band.  Each sample carries 4 wavelengths inside its band; 4 spp gives
    #: ~0.2 % per-pixel noise on the chart (see tools/bench_render.py).
    samples_per_pixel: int = 4
    variant: str = "auto"
    #: The one seed that fixes every random draw downstream of this scene.
    seed: int = 0


@dataclass(frozen=True)
class Scene:
    name: str = "Macbeth ColorChecker"
    chart: ChartSpec = field(default_factory=ChartSpec)
    illuminant: IlluminantSpec = field(default_factory=IlluminantSpec)
    grid: WavelengthGrid = field(default_factory=lambda: WavelengthGrid(np.arange(400.0, 701.0, 10.0)))
    image: ImageSpec = field(default_factory=ImageSpec)
    render: RenderSpec = field(default_factory=RenderSpec)
    camera: CameraSpec = field(default_factory=CameraSpec)
    processing: ProcessingSpec = field(default_factory=ProcessingSpec)

    def to_dict(self) -> dict:
        """A plain, JSON-serialisable description that round-trips through :func:`parse_scene`."""
        ill = self.illuminant
        ill_d: dict = {"type": ill.kind, "white_luminance_cd_m2": ill.white_luminance_cd_m2}
        if ill.kind == "blackbody":
            ill_d["temperature_K"] = ill.temperature_K
        else:
            ill_d["name"] = ill.name
        return {
            "name": self.name,
            "chart": dataclasses.asdict(self.chart),
            "illuminant": ill_d,
            "wavelengths": {"centres_nm": [float(x) for x in self.grid.centres_nm]},
            "image": dataclasses.asdict(self.image),
            "render": dataclasses.asdict(self.render),
            **camera_tables(self.camera),
            "processing": dataclasses.asdict(self.processing),
        }

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), sort_keys=True)

    def replace(self, **sections) -> "Scene":
        return dataclasses.replace(self, **sections)


# --------------------------------------------------------------------------------------------
# validation


class _Table:
    """One TOML table being read: takes known keys, then complains about any left over."""

    def __init__(self, data, path: str, source: str | None):
        if not isinstance(data, dict):
            raise ConfigError(path, data, "must be a table", source)
        self.data, self.path, self.source = dict(data), path, source

    def field_name(self, key: str) -> str:
        return f"{self.path}.{key}" if self.path else key

    def error(self, key: str, value, allowed: str) -> ConfigError:
        return ConfigError(self.field_name(key), value, allowed, self.source)

    def has(self, key: str) -> bool:
        return key in self.data

    def number(self, key, default, lo=-math.inf, hi=math.inf, *, lo_open=False, unit="") -> float:
        v = self.data.pop(key, default)
        u = f" {unit}" if unit else ""
        rng = f"{'>' if lo_open else '≥'} {lo:g}" if hi == math.inf else f"between {lo:g} and {hi:g}"
        allowed = f"must be a number {rng}{u}"
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise self.error(key, v, allowed)
        if v < lo or v > hi or (lo_open and v == lo):
            raise self.error(key, v, allowed)
        return float(v)

    def integer(self, key, default, lo, hi=None) -> int:
        v = self.data.pop(key, default)
        allowed = f"must be an integer ≥ {lo}" if hi is None else f"must be an integer between {lo} and {hi}"
        if isinstance(v, bool) or not isinstance(v, int) or v < lo or (hi is not None and v > hi):
            raise self.error(key, v, allowed)
        return int(v)

    def boolean(self, key, default) -> bool:
        v = self.data.pop(key, default)
        if not isinstance(v, bool):
            raise self.error(key, v, "must be true or false")
        return v

    def numbers(self, key, default, n, lo=-math.inf, *, increasing=False, unit="") -> tuple:
        v = self.data.pop(key, default)
        u = f" {unit}" if unit else ""
        allowed = f"must be a list of {n} numbers ≥ {lo:g}{u}" + (", increasing" if increasing else "")
        ok = isinstance(v, (list, tuple)) and len(v) == n and all(
            isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) and x >= lo for x in v)
        if not ok or (increasing and any(b <= a for a, b in zip(v, v[1:]))):
            raise self.error(key, v, allowed)
        return tuple(float(x) for x in v)

    def choice(self, key, default, choices) -> str:
        v = self.data.pop(key, default)
        if v not in choices:
            raise self.error(key, v, "must be one of " + ", ".join(repr(c) for c in choices))
        return v

    def string(self, key, default) -> str:
        v = self.data.pop(key, default)
        if not isinstance(v, str):
            raise self.error(key, v, "must be a string")
        return v

    def table(self, key) -> "_Table":
        return _Table(self.data.pop(key, {}), self.field_name(key), self.source)

    def done(self) -> None:
        for key in self.data:
            raise self.error(key, self.data[key], "unknown key")


def _parse_chart(t: _Table) -> ChartSpec:
    d = ChartSpec()
    spec = ChartSpec(
        dataset=t.choice("dataset", d.dataset, DATASETS),
        patch_size_mm=t.number("patch_size_mm", d.patch_size_mm, 0, lo_open=True, unit="mm"),
        gap_mm=t.number("gap_mm", d.gap_mm, 0, unit="mm"),
        border_mm=t.number("border_mm", d.border_mm, 0, unit="mm"),
        surround_reflectance=t.number("surround_reflectance", d.surround_reflectance, 0, 1),
        mask_margin=t.number("mask_margin", d.mask_margin, 0, 0.45),
    )
    t.done()
    return spec


def _parse_illuminant(t: _Table) -> IlluminantSpec:
    kind = t.choice("type", "blackbody", ("blackbody", "cie"))
    temperature = name = None
    if kind == "blackbody":
        temperature = t.number("temperature_K", 5000.0, *TEMPERATURE_RANGE_K, unit="K")
    else:
        import colour

        name = t.string("name", "D65")
        if name not in colour.SDS_ILLUMINANTS:
            raise t.error("name", name, "must be a CIE illuminant colour-science ships, e.g. D65, D50, A, FL2")
    if t.has("white_luminance_cd_m2") and t.has("illuminance_lux"):
        raise t.error("illuminance_lux", t.data["illuminance_lux"],
                      "give either white_luminance_cd_m2 or illuminance_lux, not both")
    if t.has("illuminance_lux"):
        level = t.number("illuminance_lux", None, 0, lo_open=True, unit="lx") / math.pi
    else:
        level = t.number("white_luminance_cd_m2", IlluminantSpec.white_luminance_cd_m2, 0,
                         lo_open=True, unit="cd/m²")
    t.done()
    return IlluminantSpec(kind=kind, temperature_K=temperature, name=name, white_luminance_cd_m2=level)


def _parse_grid(t: _Table) -> WavelengthGrid:
    if t.has("centres_nm"):
        c = t.data.pop("centres_nm")
        ok = isinstance(c, list) and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in c)
        if not ok or len(c) == 0:
            raise t.error("centres_nm", c, "must be a non-empty list of wavelengths in nm")
        arr = np.asarray(c, dtype=float)
        if np.any(np.diff(arr) <= 0):
            raise t.error("centres_nm", c, "must be strictly increasing")
        for k in ("start_nm", "stop_nm", "step_nm"):
            if t.has(k):
                raise t.error(k, t.data[k], "give either centres_nm or start_nm/stop_nm/step_nm, not both")
    else:
        start = t.number("start_nm", 400.0, unit="nm")
        stop = t.number("stop_nm", 700.0, unit="nm")
        step = t.number("step_nm", 10.0, 0, lo_open=True, unit="nm")
        if stop < start:
            raise t.error("stop_nm", stop, f"must be ≥ start_nm ({start:g}); the grid would be empty")
        n = int(math.floor((stop - start) / step + 1e-9)) + 1
        arr = start + step * np.arange(n)
    t.done()
    if arr.size == 1:
        raise ConfigError(t.path, arr.tolist(), "needs at least two wavelengths", t.source)
    grid = WavelengthGrid(arr)
    lo, hi = grid.edges_nm[0], grid.edges_nm[-1]
    if lo < CIE_RANGE_NM[0] or hi > CIE_RANGE_NM[1]:
        raise ConfigError(t.path, f"{arr[0]:g}–{arr[-1]:g} nm",
                          f"bands must lie within {CIE_RANGE_NM[0]:g}–{CIE_RANGE_NM[1]:g} nm (CIE 1931 range); "
                          f"these span {lo:g}–{hi:g} nm", t.source)
    return grid


CAMERA_TABLES = ("optics", "filters", "sensor", "capture")


def camera_tables(camera: CameraSpec) -> dict:
    """The ``[optics]``, ``[filters]``, ``[sensor]`` and ``[capture]`` tables describing a camera."""
    return {"optics": dataclasses.asdict(camera.optics),
            "filters": {k: list(v) if isinstance(v, tuple) else v for k, v in dataclasses.asdict(camera.filters).items()},
            "sensor": dataclasses.asdict(camera.sensor),
            "capture": {"architecture": camera.architecture, "exposure": camera.exposure,
                        "cfa_pattern": camera.cfa_pattern}}


def _parse_camera(top: _Table) -> CameraSpec:
    o, d = top.table("optics"), OpticsSpec()
    optics = OpticsSpec(f_number=o.number("f_number", d.f_number, 0.5, 64.0),
                        transmittance=o.number("transmittance", d.transmittance, 0, 1, lo_open=True),
                        irradiance_form=o.choice("irradiance_form", d.irradiance_form, IRRADIANCE_FORMS))
    o.done()
    f, d = top.table("filters"), FilterSpec()
    filters = FilterSpec(kind=f.choice("kind", d.kind, FILTER_KINDS),
                         cutoffs_nm=f.numbers("cutoffs_nm", d.cutoffs_nm, 2, 0, increasing=True, unit="nm"),
                         centres_nm=f.numbers("centres_nm", d.centres_nm, 3, 0, unit="nm"),
                         fwhm_nm=f.numbers("fwhm_nm", d.fwhm_nm, 3, 1e-3, unit="nm"),
                         camera=f.choice("camera", d.camera, CAMERAS),
                         qe=f.choice("qe", d.qe, QE_KINDS),
                         qe_peak=f.number("qe_peak", d.qe_peak, 0, 1, lo_open=True))
    f.done()
    t, d = top.table("sensor"), SensorSpec()
    sensor = SensorSpec(
        q_max_e=t.number("q_max_e", d.q_max_e, 1, 1e9, unit="e-"),
        read_noise_e=t.number("read_noise_e", d.read_noise_e, 0, 1e6, unit="e-"),
        dark_current_e_per_s_um2=t.number("dark_current_e_per_s_um2", d.dark_current_e_per_s_um2, 0, 1e9),
        adc_bits=t.integer("adc_bits", d.adc_bits, 1, 24),
        fpn_fraction=t.number("fpn_fraction", d.fpn_fraction, 0, 1),
        fpn_reading=t.choice("fpn_reading", d.fpn_reading, FPN_READINGS),
        prnu_fraction=t.number("prnu_fraction", d.prnu_fraction, 0, 1),
        pixel_pitch_um=t.number("pixel_pitch_um", d.pixel_pitch_um, 0.1, 1000, unit="µm"),
        fill_factor=t.number("fill_factor", d.fill_factor, 0, 1, lo_open=True),
        conversion_gain_uV_per_e=t.number("conversion_gain_uV_per_e", d.conversion_gain_uV_per_e, 0, lo_open=True),
        shot_noise_model=t.choice("shot_noise_model", d.shot_noise_model, SHOT_NOISE_MODELS),
        **{k: t.boolean(k, getattr(d, k)) for k in
           ("shot_noise", "dark_current", "read_noise", "fpn", "quantization", "clipping")})
    t.done()
    c, d = top.table("capture"), CameraSpec()
    camera = CameraSpec(optics=optics, filters=filters, sensor=sensor,
                        architecture=c.choice("architecture", d.architecture, tuple(ARCHITECTURES)),
                        exposure=c.choice("exposure", d.exposure, EXPOSURE_SCHEMES),
                        cfa_pattern=c.choice("cfa_pattern", d.cfa_pattern, CFA_PATTERNS))
    c.done()
    if camera.exposure != "single" and not ARCHITECTURES[camera.architecture].independent_exposures:
        raise c.error("exposure", camera.exposure,
                      f"the {camera.architecture} architecture has one exposure for all channels; use 'single'")
    return camera


def _parse_processing(t: _Table) -> ProcessingSpec:
    d = ProcessingSpec()
    spec = ProcessingSpec(demosaic=t.choice("demosaic", d.demosaic, DEMOSAIC_METHODS),
                          display=t.choice("display", d.display, DISPLAYS),
                          adaptation=t.choice("adaptation", d.adaptation, ADAPTATIONS),
                          gamut_clip=t.boolean("gamut_clip", d.gamut_clip),
                          delta_e=t.choice("delta_e", d.delta_e, DELTA_E_METHODS),
                          snr_combination=t.choice("snr_combination", d.snr_combination, SNR_COMBINATIONS))
    t.done()
    return spec


def parse_processing(data: dict, source: str | None = None, base: ProcessingSpec | None = None) -> ProcessingSpec:
    """A processing spec from a ``[processing]``-style dict over ``base``."""
    merged = dataclasses.asdict(base or ProcessingSpec())
    merged.update(data)
    return _parse_processing(_Table(merged, "processing", source))


def parse_camera(data: dict, source: str | None = None, base: CameraSpec | None = None) -> CameraSpec:
    """A camera from ``[optics]``/``[filters]``/``[sensor]``/``[capture]`` tables; keys not given keep
    the values of ``base`` (e.g. the scene file's camera)."""
    merged = camera_tables(base or CameraSpec())
    top = _Table(data, "", source)
    for name in CAMERA_TABLES:
        merged[name].update(top.table(name).data)
    top.done()
    return _parse_camera(_Table(merged, "", source))


def parse_scene(data: dict, source: str | None = None) -> Scene:
    """Validate a parsed TOML/JSON dict and build a :class:`Scene`."""
    top = _Table(data, "", source)
    name = top.string("name", Scene.name)
    chart = _parse_chart(top.table("chart"))
    illuminant = _parse_illuminant(top.table("illuminant"))
    grid = _parse_grid(top.table("wavelengths"))
    img = top.table("image")
    image = ImageSpec(width=img.integer("width", ImageSpec.width, 8, 16384),
                      height=img.integer("height", ImageSpec.height, 8, 16384))
    img.done()
    r = top.table("render")
    render = RenderSpec(samples_per_pixel=r.integer("samples_per_pixel", RenderSpec.samples_per_pixel, 1, 4096),
                        variant=r.choice("variant", RenderSpec.variant, VARIANTS),
                        seed=r.integer("seed", RenderSpec.seed, 0, 2**31 - 1))
    r.done()
    camera = _parse_camera(top)
    processing = _parse_processing(top.table("processing"))
    top.done()
    from .chart import patch_boxes

    smallest = min(min(r.stop - r.start, c.stop - c.start) for r, c in patch_boxes(chart, image.width, image.height))
    if smallest < MIN_PATCH_PX:
        raise ConfigError("image", f"{image.width}x{image.height}",
                          f"too small: the smallest patch mask is {smallest} px across, at least {MIN_PATCH_PX} "
                          "are needed to meter and score a patch", source)
    d_lo, d_hi = dataset_range_nm(chart.dataset)
    if grid.edges_nm[0] < d_lo or grid.edges_nm[-1] > d_hi:
        raise ConfigError("wavelengths", f"{grid.centres_nm[0]:g}–{grid.centres_nm[-1]:g} nm",
                          f"bands span {grid.edges_nm[0]:g}–{grid.edges_nm[-1]:g} nm, beyond the reflectance "
                          f"data of {chart.dataset!r} ({d_lo:g}–{d_hi:g} nm)", source)
    return Scene(name=name, chart=chart, illuminant=illuminant, grid=grid, image=image, render=render, camera=camera,
                 processing=processing)


def read_toml(path: str | Path, what: str) -> dict:
    """Parse a TOML file; an unreadable or invalid file is one ConfigError naming ``what``."""
    p = Path(path)
    try:
        text = p.read_text()
    except OSError as e:
        raise ConfigError(what, str(p), f"cannot be read ({e.strerror})") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ConfigError(what, str(p), f"is not valid TOML ({e})") from None


def load_scene(path: str | Path) -> Scene:
    """Read and validate a TOML scene file."""
    return parse_scene(read_toml(path, "scene file"), source=str(path))


def load_camera_config(path: str | Path, base: CameraSpec | None = None) -> CameraSpec:
    """Read a camera config file (the scene file's camera tables only), over ``base``."""
    return parse_camera(read_toml(path, "config file"), source=str(path), base=base)
