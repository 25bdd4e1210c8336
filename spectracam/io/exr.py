"""OpenEXR files: spectral radiance (Fichet, Pacanowski & Wilkie, JCGT 10(3), 2021) and generic I/O.

Spectral layout: one float32 channel per band named ``S0.<λ>nm`` with a comma as the decimal
separator (``S0.550,000000nm``), attributes ``spectralLayoutVersion = "1.0"`` and
``emissiveUnits = "W.m^-2.sr^-1"``, plus R, G, B preview channels so ordinary viewers show an image.
Every file spectracam writes carries ``spectracam*`` attributes recording what made it.  Numbers are
typed EXR attributes (``int``, ``float``, ``double`` — a one-element float64 array —, ``v3d``), so
OpenImageIO, ``exrheader`` and other tools read them as numbers; JSON text is kept for the nested
structures only (scene, camera, layout, render metadata).
"""
from __future__ import annotations

import contextlib
import json
import os
import re
import sys
import types
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from spectracam._version import __version__
from spectracam.architecture.base import MosaicLayout, PlanesLayout
from spectracam.camera import CameraSpec
from spectracam.camera.capture import RawCapture, capture_time_s
from spectracam.core.errors import ConfigError, SpectracamError
from spectracam.render import RadianceCube
from spectracam.core.spectra import K_M_LM_PER_W, WavelengthGrid, cmf_band_weights
from spectracam.core.files import atomic_write

if TYPE_CHECKING:
    from spectracam.sensor import SensorSpec

__all__ = ["EMISSIVE_UNITS", "PREVIEW_NOTE", "SPECTRAL_CHANNEL", "SPECTRAL_LAYOUT_VERSION",
           "attribute_number", "check_raw_attributes", "describe", "dn_scale_offset", "double",
           "emissive_scale", "json_object_attribute", "layout_from_dict", "layout_to_dict",
           "parse_spectral_channel", "preview_rgb", "radiance_attributes", "raw_attributes",
           "raw_channel_names", "read_exr", "read_exr_header", "read_radiance_bands", "read_radiance_exr", "read_raw_exr",
           "spectral_channel_name", "write_exr", "write_radiance_exr", "write_raw_exr"]

SPECTRAL_CHANNEL = re.compile(r"^S0\.(\d+(?:,\d+)?)nm$")
SPECTRAL_LAYOUT_VERSION = "1.0"
#: Fichet 2021's unit string for emissive channels (per nm is implied by the layout).
EMISSIVE_UNITS = "W.m^-2.sr^-1"
PREVIEW_NOTE = ("R,G,B: linear sRGB (ITU-R BT.709 primaries) of the CIE 1931 XYZ of each pixel, scaled so that "
                "Y = 1 is the luminance of a perfect white diffuser under the scene illuminant; no white balance")


def spectral_channel_name(wavelength_nm: float) -> str:
    """The channel name of a band in Fichet 2021's spectral layout: ``S0.<λ>nm``, six decimals after a comma.

    Parameters
    ----------
    wavelength_nm : float
        The band's centre wavelength, nm.

    Returns
    -------
    str
        E.g. ``"S0.550,000000nm"`` for 550 nm.
    """
    return "S0." + f"{wavelength_nm:.6f}".replace(".", ",") + "nm"


def parse_spectral_channel(name: str) -> float | None:
    """The wavelength a spectral channel's name gives (:data:`SPECTRAL_CHANNEL`), None for any other channel.

    Parameters
    ----------
    name : str
        An EXR channel name, e.g. ``"S0.550,000000nm"`` or ``"R"``.

    Returns
    -------
    float or None
        The wavelength, nm; None when the name is not ``S0.<λ>nm``.
    """
    m = SPECTRAL_CHANNEL.match(name)
    return float(m.group(1).replace(",", ".")) if m else None


def double(x: float) -> np.ndarray:
    """A value the OpenEXR binding writes as a ``double`` attribute (a Python float becomes a 32-bit
    ``float``); reading gives it back as the same one-element array.

    Parameters
    ----------
    x : float
        The number.

    Returns
    -------
    ndarray
        ``(1,)`` float64.
    """
    return np.array([float(x)], dtype=np.float64)


def attribute_number(value: str | float | np.ndarray) -> float:
    """A numeric attribute as a Python float, whether typed (float, double, one-element array) or,
    in files written before the attributes were typed, JSON text.

    Parameters
    ----------
    value : str, float or ndarray
        The attribute as the OpenEXR binding reads it.

    Returns
    -------
    float
        Its (first) number.
    """
    if isinstance(value, str):
        value = json.loads(value)
    return float(np.asarray(value, dtype=np.float64).reshape(-1)[0])


def json_object_attribute(attrs: dict, name: str, src: str) -> dict | None:
    """A header attribute that holds a JSON object (``spectracamScene``, ``spectracamRender``,
    ``spectracamCamera``, ``spectracamMetering``) as a dict, None when absent; text that is not JSON, or
    JSON that is not an object (``'[1, 2, 3]'``, a number, a string), is a damaged file: one line naming
    the attribute, never a TypeError where the scene is rebuilt from it.

    Parameters
    ----------
    attrs : dict
        The file's header attributes.
    name : str
        The attribute's name.
    src : str
        The file, as the error names it.

    Returns
    -------
    dict or None
        The parsed object; None when the file has no such attribute.

    Raises
    ------
    SpectracamError
        The attribute is not JSON, or not a JSON object.
    """
    if name not in attrs:
        return None
    value = attrs[name]
    try:
        parsed = json.loads(value) if isinstance(value, (str, bytes)) else value
    except ValueError as e:
        raise SpectracamError(f"file = {src!r}: attribute {name} is damaged (not JSON: {e})") from None
    if not isinstance(parsed, dict):
        shown = value if len(str(value)) <= 60 else str(value)[:57] + "..."
        kind = {list: "an array", str: "a string", bool: "a boolean", type(None): "null"}.get(type(parsed), "a number")
        raise SpectracamError(f"file = {src!r}: attribute {name} = {shown!r} is damaged (a JSON object of tables "
                              f"is expected, this is {kind})")
    return parsed


def write_exr(path: str | Path, channels: dict[str, np.ndarray], attributes: dict, half: bool = False) -> Path:
    """Write float32 (or, with ``half``, float16) channels and attributes; the file appears complete or
    not at all (temp + rename).
    A dict becomes JSON text; every other value is written as the OpenEXR binding types it (str →
    string, int → int, float → float, :func:`double` → double, float64 (3,) → v3d, float32 (3, 3) →
    m33f, an 8-tuple under ``chromaticities`` → chromaticities).

    Parameters
    ----------
    path : str or Path
        The file to write.
    channels : dict of str to ndarray
        Channel name → ``(H, W)`` pixels (any float dtype; converted, contiguous).
    attributes : dict
        Header attributes, typed as above.
    half : bool
        Store the pixels as float16 instead of float32.

    Returns
    -------
    Path
        The file written.
    """
    import OpenEXR

    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    for k, v in attributes.items():
        header[k] = json.dumps(v) if isinstance(v, dict) else v
    # OpenEXR's Python binding silently writes wrong pixels from a non-contiguous view (a slice): always copy.
    data = {k: np.ascontiguousarray(v, dtype=np.float16 if half else np.float32) for k, v in channels.items()}
    return atomic_write(path, lambda tmp: OpenEXR.File(header, data).write(tmp))


def read_exr(path: str | Path) -> tuple[dict[str, np.ndarray], dict]:
    """All channels (name → (H, W) array) and header attributes of a single-part EXR file.

    Parameters
    ----------
    path : str or Path
        A regular file.

    Returns
    -------
    channels : dict of str to ndarray
        Channel name → ``(H, W)`` pixels, in the file's type (float16 or float32).
    attributes : dict
        The header attributes as the OpenEXR binding reads them.

    Raises
    ------
    SpectracamError
        Not a regular file, or not a readable OpenEXR file (one line; a readable file's library warnings still
        reach stderr).
    """
    import OpenEXR

    from spectracam.core.files import regular_file

    regular_file(path, "file")  # a FIFO would block OpenEXR's open for ever
    try:
        with _library_output_held() as held:
            f = OpenEXR.File(str(path), separate_channels=True)
            # a file cut short opens, then fails on its pixels (ValueError: "file has 0 parts")
            channels = {name: np.asarray(c.pixels) for name, c in f.channels().items()}
            header = dict(f.header())
    except Exception as e:  # OpenEXR raises a bare RuntimeError/OSError/ValueError with a long message
        raise SpectracamError(f"file = {str(path)!r}: not a readable OpenEXR file ({str(e).splitlines()[0]})") from None
    if held.text:  # a readable file's warnings still reach the user
        sys.stderr.write(held.text)
    return channels, header


def read_exr_header(path: str | Path) -> dict:
    """The header attributes of a single-part EXR file, without its pixels (``dataWindow``: ((x0, y0), (x1, y1))).

    Parameters
    ----------
    path : str or Path
        A regular file.

    Returns
    -------
    dict
        The header attributes.

    Raises
    ------
    SpectracamError
        Not a regular file, or not a readable OpenEXR file.
    """
    import OpenEXR

    from spectracam.core.files import regular_file

    regular_file(path, "file")
    try:
        with _library_output_held():
            return dict(OpenEXR.File(str(path), header_only=True).header())
    except Exception as e:  # as read_exr: one line
        raise SpectracamError(f"file = {str(path)!r}: not a readable OpenEXR file ({str(e).splitlines()[0]})") from None


@contextlib.contextmanager
def _library_output_held():
    """Hold what the OpenEXR C library prints on file descriptors 1 and 2 while a file is read: a
    damaged file then gives spectracam's one-line error instead of the library's messages as well."""
    import tempfile

    held = types.SimpleNamespace(text="")
    for stream in (sys.stdout, sys.stderr):
        stream.flush()
    with tempfile.TemporaryFile() as tmp:
        saved = [os.dup(1), os.dup(2)]
        try:
            os.dup2(tmp.fileno(), 1)
            os.dup2(tmp.fileno(), 2)
            yield held
        finally:
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for fd in saved:
                os.close(fd)
            tmp.seek(0)
            held.text = tmp.read().decode(errors="replace")


def preview_rgb(radiance: np.ndarray, grid: WavelengthGrid, white_luminance_cd_m2: float) -> np.ndarray:
    """Linear sRGB preview ``(H, W, 3)``; see :data:`PREVIEW_NOTE`.

    Parameters
    ----------
    radiance : ndarray
        ``(H, W, B)`` band-averaged spectral radiance, W·m⁻²·sr⁻¹·nm⁻¹.
    grid : WavelengthGrid
        The bands (their CIE 1931 colour-matching weights integrate the radiance to XYZ).
    white_luminance_cd_m2 : float
        The luminance of a perfect white diffuser under the scene illuminant, cd·m⁻²: it maps to Y = 1.

    Returns
    -------
    ndarray
        ``(H, W, 3)`` linear sRGB (ITU-R BT.709 primaries), unclipped.
    """
    from spectracam.core import colour_data

    xyz = np.tensordot(radiance, cmf_band_weights(grid), axes=([-1], [0])) * (K_M_LM_PER_W / white_luminance_cd_m2)
    m = colour_data.srgb_matrix("XYZ_to_RGB")
    return np.tensordot(xyz, m, axes=([-1], [1]))


def radiance_attributes(cube: RadianceCube) -> dict:
    """The spectral layout's attributes and everything that made the cube (its scene included).

    Parameters
    ----------
    cube : RadianceCube
        A cube recording its scene (``cube.metadata["scene"]``) and render metadata.

    Returns
    -------
    dict
        The header attributes :func:`write_radiance_exr` writes: ``spectralLayoutVersion``, ``emissiveUnits`` and
        the ``spectracam*`` attributes (renderer, variant, samples per pixel, seed, scene and render as JSON, the
        preview note).
    """
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
    """Write a radiance cube as a spectral EXR with an RGB preview and the scene it came from.

    Parameters
    ----------
    path : str or Path
        The file to write (it appears complete or not at all: temp file, then rename).
    cube : RadianceCube
        Band-averaged radiance, W·m⁻²·sr⁻¹·nm⁻¹, one ``S0.<λ>nm`` channel per band; it must record its scene
        (``cube.metadata["scene"]``), whose white luminance scales the preview (:data:`PREVIEW_NOTE`).

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    OSError
        The file cannot be written (naming the path).

    References
    ----------
    .. [Fichet2021] see docs/references.md; the spectral layout.
    .. [BT709] see docs/references.md; the preview's primaries.
    """
    channels = {spectral_channel_name(w): cube.radiance[:, :, i] for i, w in enumerate(cube.wavelengths_nm)}
    level = cube.metadata["scene"]["illuminant"]["white_luminance_cd_m2"]
    rgb = preview_rgb(cube.radiance, cube.grid, level)
    channels.update({"R": rgb[..., 0], "G": rgb[..., 1], "B": rgb[..., 2]})
    return write_exr(path, channels, radiance_attributes(cube))


#: SI prefixes Fichet's ``emissiveUnits`` may carry on the watt (W.m^-2.sr^-1 per nm, the layout's unit).
_EMISSIVE_PREFIX = {"": 1.0, "k": 1e3, "m": 1e-3, "u": 1e-6, "µ": 1e-6, "n": 1e-9}
_EMISSIVE_UNITS = re.compile(r"^\s*(k|m|u|µ|n)?W\s*\.\s*m\^-2\s*\.\s*sr\^-1\s*$")


def emissive_scale(units: object, source: str) -> float:
    """Factor turning a spectral EXR's emissive values into W·m⁻²·sr⁻¹·nm⁻¹, from its ``emissiveUnits``
    (Fichet 2021: ``W.m^-2.sr^-1``, per nm implied; an SI prefix on the watt is accepted).  Anything else
    — photon units, a relative scale, no unit at all — cannot be converted: one line.

    Parameters
    ----------
    units : object
        The ``emissiveUnits`` attribute (or the ``--units`` given for a file without one); None when absent.
    source : str
        The file, as the error names it.

    Returns
    -------
    float
        1 for ``W.m^-2.sr^-1``; 10³, 10⁻³, 10⁻⁶ or 10⁻⁹ for a k, m, µ (u) or n prefix.

    Raises
    ------
    SpectracamError
        A unit that is not spectral radiance, or none.
    """
    m = _EMISSIVE_UNITS.match(units) if isinstance(units, str) else None
    if m is None:
        what = "has no emissiveUnits attribute" if units is None else f"emissiveUnits = {units!r}"
        raise SpectracamError(f"file = {source!r}: {what}; spectracam needs spectral radiance, "
                              f"{EMISSIVE_UNITS} per nm (an SI prefix on W allowed), to simulate absolute exposure — "
                              "pass --units if the file's values are in such a unit")
    return _EMISSIVE_PREFIX[m.group(1) or ""]


def read_radiance_exr(path: str | Path, units: str | None = None) -> tuple[RadianceCube, dict]:
    """Read a spectral EXR (Fichet 2021 layout, from spectracam or any other tool) into a :class:`RadianceCube`.

    A file is input from outside, so its radiance is checked (finite, ≥ 0) here.

    Parameters
    ----------
    path : str or Path
        The file.
    units : str, optional
        Stands in for the ``emissiveUnits`` of a file without one (e.g. ``"W.m^-2.sr^-1"``; an SI prefix on the
        watt is accepted); the file's own attribute wins.

    Returns
    -------
    cube : RadianceCube
        Radiance in W·m⁻²·sr⁻¹·nm⁻¹, bands sorted by wavelength; its metadata holds the recorded render
        parameters and scene when the file has them.
    attributes : dict
        The file's header attributes.

    Raises
    ------
    SpectracamError
        Not a readable OpenEXR file or not a regular file (ConfigError), no spectral channels, a unit that is not
        spectral radiance (photon units, a relative scale, none at all), a damaged ``spectracam*`` attribute, or
        radiance that is not finite and ≥ 0.

    References
    ----------
    .. [Fichet2021] see docs/references.md
    """
    wavelengths, bands, meta, attrs = read_radiance_bands(path, units)
    cube = RadianceCube(np.stack(bands, axis=-1), wavelengths, meta)
    del bands
    return cube.check(str(path)), attrs


def read_radiance_bands(path: str | Path, units: str | None = None) -> tuple[np.ndarray, list, dict, dict]:
    """A spectral EXR's bands one plane each, not stacked into a cube (:func:`read_radiance_exr` stacks them; a
    reader that integrates them band by band, such as ``capture --channel-planes``, holds the file's planes only).

    Parameters
    ----------
    path : str or Path
        The file.
    units : str, optional
        As :func:`read_radiance_exr`.

    Returns
    -------
    wavelengths : ndarray
        ``(B,)`` band centres, nm, increasing.
    bands : list of ndarray
        ``B`` planes ``(H, W)`` float32, W·m⁻²·sr⁻¹·nm⁻¹ (not yet checked finite and ≥ 0).
    metadata : dict
        The recorded render parameters and ``"scene"``, as a cube's.
    attributes : dict
        The file's header attributes.

    Raises
    ------
    SpectracamError
        As :func:`read_radiance_exr`, but for the radiance's values.
    """
    channels, attrs = read_exr(path)
    names = sorted((w, n) for n in channels if (w := parse_spectral_channel(n)) is not None)
    if not names:
        raise SpectracamError(f"file = {str(path)!r}: has no spectral channels S0.<λ>nm; not a spectral EXR")
    scale = emissive_scale(attrs.get("emissiveUnits", units), str(path))
    bands = []
    for _, n in names:   # each band float32 (half floats too), scaled in float32 as the stacked cube was
        band = channels.pop(n).astype(np.float32, copy=False)
        bands.append(band if scale == 1.0 else (band * np.float32(scale)).astype(np.float32))
    meta = json_object_attribute(attrs, "spectracamRender", str(path)) or {}
    scene = json_object_attribute(attrs, "spectracamScene", str(path))
    if scene is not None:
        meta["scene"] = scene
    return np.array([w for w, _ in names]), bands, meta, attrs


def describe(path: str | Path) -> str:
    """What a person wants to know about an EXR file: size, channels, recorded parameters, statistics.

    Parameters
    ----------
    path : str or Path
        An EXR file (any, not only spectracam's).

    Returns
    -------
    str
        Lines: the size and channel count, every non-standard attribute (JSON sorted, numbers as numbers), each
        channel's min, mean and max (spectral bands first, by wavelength), and the other parts of a multi-part file.
    """
    channels, attrs = read_exr(path)
    (x0, y0), (x1, y1) = attrs["dataWindow"]
    lines = [f"{path}", f"  size: {x1 - x0 + 1} x {y1 - y0 + 1} pixels, {len(channels)} channels"]
    known = {"channels", "compression", "dataWindow", "displayWindow", "lineOrder", "pixelAspectRatio",
             "screenWindowCenter", "screenWindowWidth", "type"}
    lines.append("  attributes:")
    for k in sorted(a for a in attrs if a not in known):
        v = attrs[k]
        if isinstance(v, np.ndarray):  # double (one element), v3d, m33f: numbers, not an array repr
            v = f"{v.item():.17g}" if v.size == 1 else " ".join(f"{x:.9g}" for x in v.ravel())
        elif isinstance(v, float):
            v = f"{v:.9g}"
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
    lines += _other_parts(path)
    return "\n".join(lines)


def _other_parts(path) -> list[str]:
    """A multi-part file: every part after the first (shown above), by name, size and channels."""
    import OpenEXR

    try:
        with _library_output_held():
            parts = OpenEXR.File(str(path)).parts
    except Exception:  # already read once above; a part list that cannot be read adds nothing
        return []
    if len(parts) < 2:
        return []
    out = [f"  this file has {len(parts)} parts; the statistics above are part 0's. The others:"]
    for i, part in enumerate(parts[1:], start=1):
        out.append(f"    part {i} {part.name()!r}: {part.width()} x {part.height()} pixels, channels "
                   + ", ".join(sorted(part.channels)))
    return out


def layout_to_dict(layout: MosaicLayout | PlanesLayout) -> dict:
    """The layout as JSON; ``channels`` only when they are not R, G, B (files before issue 20 had none).

    Parameters
    ----------
    layout : MosaicLayout or PlanesLayout
        The capture's layout.

    Returns
    -------
    dict
        ``{"kind": "mosaic", "tile", "pattern"}`` or ``{"kind": "planes", "planes", "description"}``, with
        ``"channels"`` when not R, G, B.

    Raises
    ------
    SpectracamError
        Another kind of layout (it has no raw EXR form).
    """
    channels = getattr(layout, "channels", ("R", "G", "B"))
    extra = {} if channels == ("R", "G", "B") else {"channels": list(channels)}
    if isinstance(layout, MosaicLayout):
        return {"kind": "mosaic", "tile": [list(row) for row in layout.tile], "pattern": layout.pattern, **extra}
    if isinstance(layout, PlanesLayout):
        return {"kind": "planes", "planes": layout.kind, "description": layout.description, **extra}
    raise SpectracamError(f"capture: a {type(layout).__name__} layout has no raw EXR form (a mosaic or planes); "
                          "register its writer before writing it")  # never written as something it is not


def layout_from_dict(d: dict, source: str) -> MosaicLayout | PlanesLayout:
    """The layout a raw EXR's ``spectracamLayout`` records (:func:`layout_to_dict`'s inverse), checked.

    Parameters
    ----------
    d : dict
        The parsed ``spectracamLayout`` attribute.
    source : str
        The file, as the error names it.

    Returns
    -------
    MosaicLayout or PlanesLayout
        The layout (R, G, B channels when ``d`` names none).

    Raises
    ------
    SpectracamError
        Not a layout spectracam wrote: a missing field, a tile index outside the channels, or a pattern that
        contradicts the tile.
    """
    try:
        channels = tuple(str(c) for c in d.get("channels", ("R", "G", "B")))
        if d["kind"] == "mosaic":
            layout = MosaicLayout(tuple(tuple(int(k) for k in row) for row in d["tile"]), channels)
            if any(not 0 <= k < len(channels) for row in layout.tile for k in row):
                raise ValueError("a tile index outside the channels")
            if d.get("pattern", layout.pattern) != layout.pattern:   # redundant: it must agree with the tile
                raise SpectracamError(f"file = {source!r}: spectracamLayout's pattern {d['pattern']!r} contradicts "
                                      f"its tile {d['tile']!r} ({layout.pattern}); the file is damaged or was edited")
            return layout
        if d["kind"] == "planes":
            return PlanesLayout(str(d["planes"]), str(d["description"]), channels)
    except (KeyError, TypeError, ValueError, AttributeError):
        pass
    raise SpectracamError(f"file = {source!r}: spectracamLayout = {d!r} is not a layout spectracam wrote")


def raw_channel_names(layout: MosaicLayout | PlanesLayout) -> list[str]:
    """One channel "Y" for a mosaic (viewers show it as a grey mosaic), else one per plane, by name.

    Parameters
    ----------
    layout : MosaicLayout or PlanesLayout
        The capture's layout.

    Returns
    -------
    list of str
        ``["Y"]`` for a mosaic, else the layout's channel names (``["R", "G", "B"]``, …).
    """
    return ["Y"] if isinstance(layout, MosaicLayout) else list(layout.channels)


def dn_scale_offset(sensor: SensorSpec) -> tuple[float, float]:
    """``(scale, offset)`` of a raw EXR's pixels: ``value = (DN − offset)/scale`` with offset = the black
    level and scale = ``2ⁿ − 1 − black level``, so black reads 0 and the top code 1.0 in any EXR viewer;
    both are float32 numbers (the attributes' type), used as such to write and to read.

    Parameters
    ----------
    sensor : SensorSpec
        The sensor (its ADC bits and black level, DN).

    Returns
    -------
    scale : float
        ``2ⁿ − 1 −`` black level, DN.
    offset : float
        The black level, DN.
    """
    black = float(np.float32(sensor.black_level_dn))
    return float(np.float32(2**sensor.adc_bits - 1 - black)), black


def raw_attributes(raw: RawCapture) -> dict:
    """The header attributes of a raw EXR: every parameter that produced the capture (see :func:`write_raw_exr`).

    Parameters
    ----------
    raw : RawCapture
        The capture.

    Returns
    -------
    dict
        The ``spectracam*`` attributes: the pixel scale and offset (:func:`dn_scale_offset`), ADC bits,
        architecture, exposure scheme, layout, exposure times and capture time (s), the camera as JSON, the ADC's
        full swing (V = g·q_max, paper 3.4), the seed, the CFA pattern or the frames, and the scene and metering
        when known.
    """
    cam = raw.camera
    scale, offset = dn_scale_offset(cam.sensor)
    attrs = {
        "spectracamVersion": __version__,
        "spectracamKind": "raw",
        "spectracamUnits": f"(DN - spectracamDnOffset)/spectracamDnScale: digital numbers "
                           f"0..{2**cam.sensor.adc_bits - 1} ({cam.sensor.adc_bits}-bit ADC; "
                           f"{cam.sensor.quantization_step_e:g} e- per DN) with the black level ({offset:g} DN) at 0 "
                           "and the top code at 1",
        "spectracamDnScale": scale,
        "spectracamDnOffset": offset,
        "spectracamAdcBits": int(cam.sensor.adc_bits),
        "spectracamArchitecture": cam.capture.architecture,
        "spectracamExposure": cam.capture.exposure,
        "spectracamLayout": json.dumps(layout_to_dict(raw.layout)),
        # R, G, B exposure times (a JSON {channel: s} for other channels) and the capture time, s
        "spectracamExposureTimesS": _exposure_attribute(raw),
        "spectracamCaptureTimeS": double(raw.capture_time_s),
        "spectracamCamera": json.dumps(cam.to_dict(), sort_keys=True),
        # V = g·Q + V_FPN (paper 3.4): the ADC's full scale, g·q_max, in volts
        "spectracamFullSwingV": double(cam.sensor.conversion_gain_uV_per_e * 1e-6 * cam.sensor.q_max_e),
        "spectracamSeed": int(raw.seed),
    }
    if isinstance(raw.layout, MosaicLayout):
        attrs["spectracamCfaPattern"] = raw.layout.pattern
    else:
        attrs["spectracamFrames"] = raw.layout.description
    if raw.scene is not None:
        attrs["spectracamScene"] = json.dumps(raw.scene, sort_keys=True)
    if raw.metering is not None:
        attrs["spectracamMetering"] = json.dumps(raw.metering, sort_keys=True)
    if raw.rates != "cube":   # a capture of channel planes (issue 38) says so; a cube's files are as before
        attrs["spectracamRates"] = raw.rates
    return attrs


def write_raw_exr(path: str | Path, raw: RawCapture) -> Path:
    """Write what the sensor recorded with every parameter that produced it.

    Parameters
    ----------
    path : str or Path
        The file to write (temp file, then rename).
    raw : RawCapture
        The capture.  Its digital numbers are stored as ``(DN − black level)/(2ⁿ − 1 − black level)``
        (:func:`dn_scale_offset`), so a viewer at its default exposure shows the mosaic or planes from black (0)
        to full scale (1); :func:`read_raw_exr` gives the digital numbers back exactly.

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    OSError
        The file cannot be written (naming the path).
    """
    scale, offset = dn_scale_offset(raw.camera.sensor)
    digital = (np.asarray(raw.digital, dtype=np.float64) - offset) / scale
    planes = [digital] if isinstance(raw.layout, MosaicLayout) else list(digital)
    return write_exr(path, dict(zip(raw_channel_names(raw.layout), planes)), raw_attributes(raw))


def _exposure_attribute(raw: RawCapture):
    """R, G, B exposure times as a typed v3d (double precision); other channels as JSON ``{name: s}``
    (``repr`` of a float round-trips exactly)."""
    channels = raw.layout.channels
    if channels == ("R", "G", "B"):
        return np.asarray(raw.exposure_times_s, dtype=np.float64).reshape(3)
    return json.dumps({c: float(t) for c, t in zip(channels, raw.exposure_times_s)})


def _exposure_times(value, channels=("R", "G", "B")) -> np.ndarray:
    """Exposure times of ``channels`` from the typed v3d attribute (R, G, B) or the JSON ``{"R": …}``."""
    if isinstance(value, str):
        value = json.loads(value)
        return np.array([float(value[c]) for c in channels])
    times = np.asarray(value, dtype=np.float64).reshape(-1)
    if times.shape != (len(channels),):
        raise ValueError(f"spectracamExposureTimesS = {value!r}: not {len(channels)} times")
    return times


def _digital_numbers(values: np.ndarray, attrs: dict, camera: CameraSpec) -> np.ndarray:
    """Digital numbers from stored values: ``value·scale + offset``, rounded to the ADC's integer codes
    when it quantises (which makes the round trip exact: the float32 quotient is within 2⁻²⁴ of the
    code's); float32 like the capture's.  Files without the attributes hold the numbers themselves."""
    if "spectracamDnScale" not in attrs:
        return values
    scale, offset = attribute_number(attrs["spectracamDnScale"]), attribute_number(attrs["spectracamDnOffset"])
    dn = values.astype(np.float64) * scale + offset
    if camera.sensor.quantization:
        dn = np.round(dn)
    return dn.astype(np.float32)


def check_raw_attributes(attrs: dict, camera: CameraSpec, layout: MosaicLayout | PlanesLayout, times: np.ndarray,
                         capture_time: float,
                         src: str) -> None:
    """Every redundant attribute of a raw EXR must agree with the recorded camera: the pixel scale and
    offset, the ADC's bits, the architecture and exposure scheme, the CFA pattern; the exposure times
    must be finite and > 0 and give the recorded capture time.  A damaged or edited file is refused
    in one line instead of being scored as something else.

    Parameters
    ----------
    attrs : dict
        The file's header attributes.
    camera : CameraSpec
        The camera the file records.
    layout : MosaicLayout or PlanesLayout
        The layout the file records.
    times : ndarray
        The recorded exposure time per channel, s.
    capture_time : float
        The recorded capture time, s.
    src : str
        The file, as the error names it.

    Raises
    ------
    SpectracamError
        An attribute that disagrees or is damaged.
    """
    def refuse(name, value, why):
        raise SpectracamError(f"file = {src!r}: {name} = {value!r} {why}; the file is damaged or was edited")

    if not (np.all(np.isfinite(times)) and np.all(times > 0)):
        refuse("spectracamExposureTimesS", times.tolist(), "must be finite times > 0 s, one per channel")
    arch = camera.architecture()
    want_capture = float(capture_time_s(arch, times, camera.sensor))
    if not (np.isfinite(capture_time) and abs(capture_time - want_capture) <= 1e-9 * max(want_capture, 1e-300)):
        refuse("spectracamCaptureTimeS", capture_time, f"contradicts its exposure times ({want_capture:.9g} s for "
               f"{camera.capture.architecture})")
    try:
        if "spectracamDnScale" in attrs or "spectracamDnOffset" in attrs:
            scale, offset = dn_scale_offset(camera.sensor)
            for name, want in (("spectracamDnScale", scale), ("spectracamDnOffset", offset)):
                got = attribute_number(attrs[name])
                if not got == want:
                    refuse(name, got, f"contradicts the recorded camera ({camera.sensor.adc_bits}-bit ADC, black level "
                           f"{camera.sensor.black_level_dn:g} DN: {want:g})")
        checks = (("spectracamAdcBits", lambda v: int(attribute_number(v)) == camera.sensor.adc_bits,
                   camera.sensor.adc_bits),
                  ("spectracamArchitecture", lambda v: v == camera.capture.architecture, camera.capture.architecture),
                  ("spectracamExposure", lambda v: v == camera.capture.exposure, camera.capture.exposure),
                  ("spectracamCfaPattern", lambda v: isinstance(layout, MosaicLayout) and v == layout.pattern,
                   getattr(layout, "pattern", None)))
        for name, ok, want in checks:
            if name in attrs and not ok(attrs[name]):
                refuse(name, attrs[name], f"contradicts the recorded camera ({want!r})")
    except (TypeError, ValueError, KeyError) as e:
        raise SpectracamError(f"file = {src!r}: a raw capture's attribute is damaged ({e})") from None


def read_raw_exr(path: str | Path) -> RawCapture:
    """Read a raw EXR back into a :class:`~spectracam.camera.capture.RawCapture` (without expected electrons).

    Parameters
    ----------
    path : str or Path
        A raw capture spectracam wrote (:func:`write_raw_exr`).

    Returns
    -------
    RawCapture
        The digital numbers exactly as captured, with the camera, layout, exposure times, seed, scene and
        metering the file records; ``expected_e`` is None.

    Raises
    ------
    SpectracamError
        Not a readable OpenEXR file, not a spectracam raw capture, missing channels, or an attribute that is
        missing, damaged or contradicts the recorded camera (ConfigError for a layout other than the recorded
        architecture's).
    """
    src = str(path)
    channels, attrs = read_exr(path)
    if attrs.get("spectracamKind") != "raw":
        raise SpectracamError(f"file = {src!r}: not a spectracam raw capture (spectracamKind = "
                              f"{attrs.get('spectracamKind')!r})")
    for name in ("spectracamCamera", "spectracamScene", "spectracamMetering"):
        json_object_attribute(attrs, name, src)   # a JSON object each, or one line here
    try:
        cam = json.loads(attrs["spectracamCamera"])
        layout = layout_from_dict(json.loads(attrs["spectracamLayout"]), src)
        times = _exposure_times(attrs["spectracamExposureTimesS"], layout.channels)
        capture_time = attribute_number(attrs["spectracamCaptureTimeS"])
        seed = int(attrs["spectracamSeed"])
        scene = json.loads(attrs["spectracamScene"]) if "spectracamScene" in attrs else None
        metering = json.loads(attrs["spectracamMetering"]) if "spectracamMetering" in attrs else None
        rates = attrs.get("spectracamRates", "cube")
        if rates not in ("cube", "channel planes"):
            raise ValueError(f"spectracamRates = {str(rates)[:40]!r}, not 'cube' or 'channel planes'")
    except (KeyError, TypeError, ValueError) as e:
        raise SpectracamError(f"file = {src!r}: a raw capture's attribute is missing or damaged ({e})") from None
    camera = CameraSpec.from_dict(cam, source=src)
    names = raw_channel_names(layout)
    if set(names) - set(channels):
        raise SpectracamError(f"file = {src!r}: a {layout_to_dict(layout)['kind']} capture needs channels "
                              f"{', '.join(names)}; it has {', '.join(sorted(channels))}")
    arch_layout = camera.architecture().layout
    if arch_layout != layout:
        raise ConfigError("spectracamLayout", layout_to_dict(layout), f"does not match the recorded architecture "
                          f"{camera.capture.architecture!r} ({layout_to_dict(arch_layout)})", src)
    check_raw_attributes(attrs, camera, layout, times, capture_time, src)
    digital = channels["Y"] if len(names) == 1 else np.stack([channels[c] for c in names])
    try:
        digital = _digital_numbers(digital, attrs, camera)
    except (KeyError, TypeError, ValueError) as e:
        raise SpectracamError(f"file = {src!r}: spectracamDnScale/spectracamDnOffset are damaged ({e})") from None
    return RawCapture(digital=digital, expected_e=None, exposure_times_s=times, capture_time_s=capture_time,
                      layout=layout, camera=camera, seed=seed, scene=scene, metering=metering, rates=rates)
