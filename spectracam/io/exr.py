"""OpenEXR files: spectral radiance (Fichet, Pacanowski & Wilkie, JCGT 10(3), 2021) and generic I/O.

Spectral layout: one float32 channel per band named ``S0.<λ>nm`` with a comma as the decimal
separator (``S0.550,000000nm``), attributes ``spectralLayoutVersion = "1.0"`` and
``emissiveUnits = "W.m^-2.sr^-1"``, plus R, G, B preview channels so ordinary viewers show an image.
Every file spectracam writes carries ``spectracam*`` attributes recording what made it.
"""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np

from .. import __version__
from ..architecture import MosaicLayout, PlanesLayout
from ..camera import CameraSpec
from ..capture import RawCapture
from ..errors import ConfigError, SpectracamError
from ..render import RadianceCube
from ..spectra import K_M_LM_PER_W, WavelengthGrid, cmf_band_weights
from .files import atomic_write

SPECTRAL_CHANNEL = re.compile(r"^S0\.(\d+(?:,\d+)?)nm$")
SPECTRAL_LAYOUT_VERSION = "1.0"
#: Fichet 2021's unit string for emissive channels (per nm is implied by the layout).
EMISSIVE_UNITS = "W.m^-2.sr^-1"
PREVIEW_NOTE = ("R,G,B: linear sRGB (ITU-R BT.709 primaries) of the CIE 1931 XYZ of each pixel, scaled so that "
                "Y = 1 is the luminance of a perfect white diffuser under the scene illuminant; no white balance")


def spectral_channel_name(wavelength_nm: float) -> str:
    return "S0." + f"{wavelength_nm:.6f}".replace(".", ",") + "nm"


def parse_spectral_channel(name: str) -> float | None:
    m = SPECTRAL_CHANNEL.match(name)
    return float(m.group(1).replace(",", ".")) if m else None


def write_exr(path: str | Path, channels: dict[str, np.ndarray], attributes: dict) -> Path:
    """Write float32 channels and attributes; the file appears complete or not at all (temp + rename)."""
    import OpenEXR

    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    for k, v in attributes.items():
        header[k] = v if isinstance(v, (str, int)) else (json.dumps(v) if isinstance(v, (dict, list)) else v)
    # OpenEXR silently writes wrong pixels from non-contiguous views (DESIGN.md): always copy.
    data = {k: np.ascontiguousarray(v, dtype=np.float32) for k, v in channels.items()}
    return atomic_write(path, lambda tmp: OpenEXR.File(header, data).write(tmp))


def read_exr(path: str | Path) -> tuple[dict[str, np.ndarray], dict]:
    """All channels (name → (H, W) array) and header attributes of a single-part EXR file."""
    import OpenEXR

    try:
        f = OpenEXR.File(str(path), separate_channels=True)
    except Exception as e:  # OpenEXR raises a bare RuntimeError/OSError with a long message
        raise SpectracamError(f"file = {str(path)!r}: not a readable OpenEXR file ({str(e).splitlines()[0]})") from None
    channels = {name: np.asarray(c.pixels) for name, c in f.channels().items()}
    return channels, dict(f.header())


def preview_rgb(radiance: np.ndarray, grid: WavelengthGrid, white_luminance_cd_m2: float) -> np.ndarray:
    """Linear sRGB preview ``(H, W, 3)``; see :data:`PREVIEW_NOTE`."""
    import colour

    xyz = np.tensordot(radiance, cmf_band_weights(grid), axes=([-1], [0])) * (K_M_LM_PER_W / white_luminance_cd_m2)
    m = np.asarray(colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB)
    return np.tensordot(xyz, m, axes=([-1], [1]))


def radiance_attributes(cube: RadianceCube) -> dict:
    """The spectral layout's attributes and everything that made the cube (its scene included)."""
    meta = {k: v for k, v in cube.metadata.items() if k != "scene"}
    scene = cube.metadata["scene"]
    return {
        "spectralLayoutVersion": SPECTRAL_LAYOUT_VERSION,
        "emissiveUnits": EMISSIVE_UNITS,
        "spectracamVersion": __version__,
        "spectracamKind": "radiance",
        "spectracamUnits": "band-averaged spectral radiance, W.m^-2.sr^-1.nm^-1",
        "spectracamRenderer": str(meta.get("renderer")),
        "spectracamVariant": str(meta.get("variant")),
        "spectracamSamplesPerPixel": int(meta["samples_per_pixel"]) if meta.get("samples_per_pixel") else 0,
        "spectracamSeed": int(scene["render"]["seed"]),
        "spectracamScene": json.dumps(scene, sort_keys=True),
        "spectracamRender": json.dumps(meta, sort_keys=True, default=str),
        "spectracamPreview": PREVIEW_NOTE,
    }


def write_radiance_exr(path: str | Path, cube: RadianceCube) -> Path:
    """Write a radiance cube as a spectral EXR with an RGB preview and the scene it came from
    (``cube.metadata["scene"]``)."""
    channels = {spectral_channel_name(w): cube.radiance[:, :, i] for i, w in enumerate(cube.wavelengths_nm)}
    level = cube.metadata["scene"]["illuminant"]["white_luminance_cd_m2"]
    rgb = preview_rgb(cube.radiance, cube.grid, level)
    channels.update({"R": rgb[..., 0], "G": rgb[..., 1], "B": rgb[..., 2]})
    return write_exr(path, channels, radiance_attributes(cube))


def read_radiance_exr(path: str | Path) -> tuple[RadianceCube, dict]:
    """Read a spectral EXR back into a :class:`RadianceCube` (bands sorted by wavelength) and its attributes."""
    channels, attrs = read_exr(path)
    bands = sorted((w, n) for n in channels if (w := parse_spectral_channel(n)) is not None)
    if not bands:
        raise SpectracamError(f"file = {str(path)!r}: has no spectral channels S0.<λ>nm; not a spectral EXR")
    cube = np.stack([channels[n] for _, n in bands], axis=-1)
    meta = json.loads(attrs["spectracamRender"]) if "spectracamRender" in attrs else {}
    if "spectracamScene" in attrs:
        meta["scene"] = json.loads(attrs["spectracamScene"])
    return RadianceCube(cube, np.array([w for w, _ in bands]), meta), attrs


def describe(path: str | Path) -> str:
    """What a person wants to know about an EXR file: size, channels, recorded parameters, statistics."""
    channels, attrs = read_exr(path)
    (x0, y0), (x1, y1) = attrs["dataWindow"]
    lines = [f"{path}", f"  size: {x1 - x0 + 1} x {y1 - y0 + 1} pixels, {len(channels)} channels"]
    known = {"channels", "compression", "dataWindow", "displayWindow", "lineOrder", "pixelAspectRatio",
             "screenWindowCenter", "screenWindowWidth", "type"}
    lines.append("  attributes:")
    for k in sorted(a for a in attrs if a not in known):
        v = attrs[k]
        if isinstance(v, str) and v.startswith("{"):
            try:
                v = json.dumps(json.loads(v), sort_keys=True)
            except ValueError:
                pass
        lines.append(f"    {k}: {v}")
    spectral = sorted((w, n) for n in channels if (w := parse_spectral_channel(n)) is not None)
    others = sorted(n for n in channels if parse_spectral_channel(n) is None)
    order = [n for _, n in spectral] + others
    lines.append(f"  {'channel':<20} {'min':>12} {'mean':>12} {'max':>12}")
    for n in order:
        c = channels[n]
        lines.append(f"  {n:<20} {c.min():>12.6g} {c.mean(dtype=np.float64):>12.6g} {c.max():>12.6g}")
    return "\n".join(lines)


def layout_to_dict(layout) -> dict:
    if isinstance(layout, MosaicLayout):
        return {"kind": "mosaic", "tile": [list(row) for row in layout.tile], "pattern": layout.pattern}
    return {"kind": "planes", "planes": layout.kind, "description": layout.description}


def layout_from_dict(d: dict, source: str):
    try:
        if d["kind"] == "mosaic":
            return MosaicLayout(tuple(tuple(int(k) for k in row) for row in d["tile"]))
        if d["kind"] == "planes":
            return PlanesLayout(str(d["planes"]), str(d["description"]))
    except (KeyError, TypeError, ValueError):
        pass
    raise SpectracamError(f"file = {source!r}: spectracamLayout = {d!r} is not a layout spectracam wrote")


def raw_channel_names(layout) -> list[str]:
    """One channel "Y" for a mosaic (viewers show it as a grey mosaic), else R, G, B."""
    return ["Y"] if isinstance(layout, MosaicLayout) else ["R", "G", "B"]


def raw_attributes(raw: RawCapture) -> dict:
    cam = raw.camera
    attrs = {
        "spectracamVersion": __version__,
        "spectracamKind": "raw",
        "spectracamUnits": f"digital numbers, 0..{2**cam.sensor.adc_bits - 1} ({cam.sensor.adc_bits}-bit ADC; "
                           f"{cam.sensor.quantization_step_e:g} e- per DN)",
        "spectracamArchitecture": cam.capture.architecture,
        "spectracamExposure": cam.capture.exposure,
        "spectracamLayout": json.dumps(layout_to_dict(raw.layout)),
        "spectracamExposureTimesS": json.dumps(dict(zip("RGB", map(float, raw.exposure_times_s)))),
        "spectracamCaptureTimeS": json.dumps(float(raw.capture_time_s)),
        "spectracamCamera": json.dumps(cam.to_dict(), sort_keys=True),
        # V = g·Q + V_FPN (paper 3.4): the ADC's full scale, g·q_max, in volts
        "spectracamFullSwingV": json.dumps(cam.sensor.conversion_gain_uV_per_e * 1e-6 * cam.sensor.q_max_e),
        "spectracamSeed": int(raw.seed),
    }
    if isinstance(raw.layout, MosaicLayout):
        attrs["spectracamCfaPattern"] = raw.layout.pattern
    else:
        attrs["spectracamFrames"] = raw.layout.description
    if raw.scene is not None:
        attrs["spectracamScene"] = json.dumps(raw.scene, sort_keys=True)
    return attrs


def write_raw_exr(path: str | Path, raw: RawCapture) -> Path:
    """Write what the sensor recorded (digital numbers) with every parameter that produced it."""
    planes = [raw.digital] if isinstance(raw.layout, MosaicLayout) else list(raw.digital)
    return write_exr(path, dict(zip(raw_channel_names(raw.layout), planes)), raw_attributes(raw))


def read_raw_exr(path: str | Path) -> RawCapture:
    """Read a raw EXR back into a :class:`~spectracam.capture.RawCapture` (without expected electrons)."""
    src = str(path)
    channels, attrs = read_exr(path)
    if attrs.get("spectracamKind") != "raw":
        raise SpectracamError(f"file = {src!r}: not a spectracam raw capture (spectracamKind = "
                              f"{attrs.get('spectracamKind')!r})")
    try:
        cam = json.loads(attrs["spectracamCamera"])
        layout = layout_from_dict(json.loads(attrs["spectracamLayout"]), src)
        times = json.loads(attrs["spectracamExposureTimesS"])
        times = np.array([float(times[c]) for c in "RGB"])
        capture_time = float(json.loads(attrs["spectracamCaptureTimeS"]))
        seed = int(attrs["spectracamSeed"])
        scene = json.loads(attrs["spectracamScene"]) if "spectracamScene" in attrs else None
    except (KeyError, TypeError, ValueError) as e:
        raise SpectracamError(f"file = {src!r}: a raw capture's attribute is missing or damaged ({e})") from None
    camera = CameraSpec.from_dict(cam, source=src)
    names = raw_channel_names(layout)
    if set(names) - set(channels):
        raise SpectracamError(f"file = {src!r}: a {layout_to_dict(layout)['kind']} capture needs channels "
                              f"{', '.join(names)}; it has {', '.join(sorted(channels))}")
    arch_layout = camera.capture.make_architecture().layout
    if arch_layout != layout:
        raise ConfigError("spectracamLayout", layout_to_dict(layout), f"does not match the recorded architecture "
                          f"{camera.capture.architecture!r} ({layout_to_dict(arch_layout)})", src)
    digital = channels["Y"] if len(names) == 1 else np.stack([channels[c] for c in names])
    return RawCapture(digital=digital, expected_e=None, exposure_times_s=times, capture_time_s=capture_time,
                      layout=layout, camera=camera, seed=seed, scene=scene)
