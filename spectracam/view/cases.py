"""One case of an output directory — a radiance cube, a raw capture and a rendering of one shot — read
back from its EXR files into what the page shows and probes.

The page holds every ``stride``-th pixel of each image (``stride`` = 1 up to :data:`PROBE_VALUES`
spectral values per case), exactly as the files hold them: a probe at a kept pixel returns the
file's float32 values, not an average.  Colorimetry follows the score (paper 3.6, docs/metrics.md):

* scene CIELAB: CIE 1931 XYZ of the pixel's band-averaged radiance (Y = 1 for a perfect white
  diffuser under the scene's light), white = that diffuser's XYZ;
* rendered CIELAB: the display's XYZ of the rendered linear RGB, white = the display white;
* error map: ΔE*ab (CIE 1976) of the two at each pixel — against the pixel's own radiance where the
  case has radiance.exr, else against the chart reference's patch colour inside each patch (NaN
  elsewhere), as ``score`` measures it.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from spectracam.core.errors import SpectracamError

__all__ = ["CHANNEL_COLOURS", "PAGE_VALUES", "Case", "load_case", "rgba", "srgb8", "tile_stride"]

#: 4-byte values (spectra, digital numbers, CIELAB, image pixels) a page's cases carry at most: 6 M
#: (24 MB; 32 MB as base64), shared equally among them.
PAGE_VALUES = 6_000_000
#: The display colour of each channel letter of a raw capture (DNG CFA colours; others grey).
CHANNEL_COLOURS = {"R": (1.0, 0.15, 0.1), "G": (0.1, 0.8, 0.15), "B": (0.15, 0.3, 1.0), "C": (0.0, 0.8, 0.85),
                   "M": (0.85, 0.1, 0.8), "Y": (0.9, 0.8, 0.0), "W": (0.85, 0.85, 0.85)}


@dataclass
class Case:
    """What the page shows of one shot.  Images are ``(h, w)`` uint32 RGBA, top row first, of every
    ``stride``-th pixel of the ``width`` × ``height`` files; per-pixel arrays are float32 ``(h, w, …)``."""

    name: str
    width: int
    height: int
    stride: int
    images: dict = field(default_factory=dict)       # scene, raw, rendered → RGBA; error → float32 ΔE
    spectra: np.ndarray | None = None                # (h, w, B) W·m⁻²·sr⁻¹·nm⁻¹
    wavelengths_nm: list = field(default_factory=list)
    dn: np.ndarray | None = None                     # (h, w, N) digital numbers (NaN: not recorded)
    dn_channel: np.ndarray | None = None             # (h, w) uint8: a mosaic's channel at each kept pixel
    channels: list = field(default_factory=list)
    scene_lab: np.ndarray | None = None
    rendered_lab: np.ndarray | None = None
    rendered_rgb: np.ndarray | None = None           # (h, w, 3) float32 linear display RGB, rendered.exr's values
    display_to_xyz: list | None = None               # 3 × 3: display RGB → XYZ (white Y = 1), rendered L*a*b*'s
    responsivities: dict = field(default_factory=dict)  # channel → (B,) e⁻/photon; "QE × IR cut" too
    notes: list = field(default_factory=list)
    design: str = ""
    #: The chart's patches the score measures: ``[name, x0, y0, x1, y1]`` in the files' pixels (x1, y1 exclusive).
    patches: list = field(default_factory=list)


def _stride(width: int, height: int, bands: int, share: float = 1.0) -> int:
    """The smallest stride keeping a case within ``share`` of :data:`PAGE_VALUES`: per kept pixel its
    spectrum, up to 4 digital numbers, two CIELAB triples, ΔE and 4 image pixels."""
    per_pixel = bands + 4 + 3 + 3 + 1 + 4
    s = 1
    while -(-width // s) * -(-height // s) * per_pixel > share * PAGE_VALUES and s < max(width, height):
        s += 1
    return s


def tile_stride(stride: int, tile_shape: tuple[int, int] | None) -> int:
    """The smallest stride ≥ ``stride`` that shares no factor with the mosaic's tile (1 stays 1): every ``s``-th pixel of
    a 2 × 2 Bayer tile with an even ``s`` is always the same site (a page drew a Bayer capture red only), with an odd
    ``s`` the kept pixels step through every site, so every channel is drawn and probed.

    Parameters
    ----------
    stride : int
        The stride the page's budget asks for, ≥ 1.
    tile_shape : tuple of int or None
        The mosaic's tile ``(rows, columns)``; None for a capture without one (every pixel has every channel).

    Returns
    -------
    int
        The stride to keep, ≥ ``stride``.
    """
    import math

    s = int(stride)
    if s <= 1 or tile_shape is None:
        return s
    while any(math.gcd(s, int(n)) != 1 for n in tile_shape):
        s += 1
    return s


def srgb8(linear: np.ndarray) -> np.ndarray:
    """8-bit sRGB of linear RGB (clipped to [0, 1]; NaN as 0), colour-science's sRGB encoding, as rendered.png.

    Parameters
    ----------
    linear : ndarray
        ``(…, 3)`` linear RGB, white = 1.

    Returns
    -------
    ndarray
        The same shape, uint8 (IEC 61966-2-1's transfer function, rounded).
    """
    from spectracam.core import colour_data

    x = np.clip(np.nan_to_num(linear, nan=0.0), 0.0, 1.0)
    return (np.clip(colour_data.srgb_encode(x), 0, 1) * 255 + 0.5).astype(np.uint8)


def rgba(rgb8: np.ndarray) -> np.ndarray:
    """``(h, w, 3)`` uint8 → ``(h, w)`` uint32 RGBA, opaque (Bokeh's image_rgba).

    Parameters
    ----------
    rgb8 : ndarray
        ``(h, w, 3)`` uint8 RGB.

    Returns
    -------
    ndarray
        ``(h, w)`` uint32, each pixel's R, G, B, A bytes in memory order, A = 255.
    """
    h, w, _ = rgb8.shape
    out = np.empty((h, w, 4), np.uint8)
    out[..., :3], out[..., 3] = rgb8, 255
    return out.view(np.uint32)[..., 0]


def _scene_of(params: dict | None):
    from spectracam.pipeline.scene_file import parse_scene

    if not params:
        return None
    try:
        return parse_scene(params)
    except SpectracamError:
        return None


def _radiance(case: Case, cube):
    """Spectra, preview and scene CIELAB of the radiance cube."""
    from spectracam.scene.illuminant import white_diffuser_radiance
    from spectracam.core.cielab import xyz_to_lab
    from spectracam.core.spectra import K_M_LM_PER_W, cmf_band_weights

    s = case.stride
    rad = np.asarray(cube.radiance[::s, ::s], np.float32)
    grid = cube.grid
    case.spectra, case.wavelengths_nm = rad, list(grid.centres_nm)
    scene = _scene_of(cube.metadata.get("scene"))
    w = cmf_band_weights(grid) * K_M_LM_PER_W
    if scene is not None:
        white = white_diffuser_radiance(scene.illuminant, grid) @ w
    else:  # no recorded light: the brightest 1 % of the image is the white
        y = rad.reshape(-1, rad.shape[-1]) @ w[:, 1]
        white = np.array([0.9505, 1.0, 1.089]) * max(float(np.percentile(y, 99)), 1e-30)
        case.notes.append("radiance.exr records no light: the preview's white is the image's 99th percentile")
    xyz = np.tensordot(rad.astype(np.float64), w, axes=([-1], [0])) / white[1]
    case.scene_lab = xyz_to_lab(xyz, white / white[1]).astype(np.float32)
    from spectracam.core import colour_data

    m = colour_data.srgb_matrix("XYZ_to_RGB")
    case.images["scene"] = rgba(srgb8(np.tensordot(xyz, m, axes=([-1], [1]))))
    return scene, grid


def _raw(case: Case, path: Path, grid):
    """Digital numbers (one channel per pixel of a mosaic, N of planes) and a picture of them: each
    pixel in its channel's colour, brightness DN / top code."""
    from spectracam.architecture.base import MosaicLayout
    from spectracam.camera import camera_responsivities
    from spectracam.architecture.filters import clear_responsivity
    from spectracam.io.exr import read_raw_exr

    raw = read_raw_exr(path) if isinstance(path, (str, Path)) else path
    s = case.stride
    layout = raw.layout
    channels = list(layout.channels)
    top = float(2**raw.camera.sensor.adc_bits - 1)
    case.channels, case.design = channels, raw.design
    colours = np.array([CHANNEL_COLOURS.get(c, (0.7, 0.7, 0.7)) for c in channels])
    if isinstance(layout, MosaicLayout):
        dn = np.asarray(raw.digital, np.float32)[::s, ::s]
        h, w = raw.digital.shape
        index = layout.channel_index((h, w))[::s, ::s]
        case.dn_channel = index.astype(np.uint8)
        case.dn = np.full(dn.shape + (len(channels),), np.nan, np.float32)
        np.put_along_axis(case.dn, index[..., None], dn[..., None], axis=-1)
        picture = colours[index] * (dn / top)[..., None]
    else:
        case.dn = np.moveaxis(np.asarray(raw.digital, np.float32)[:, ::s, ::s], 0, -1)
        picture = np.clip((case.dn / top) @ colours / max(colours.sum(axis=0).max(), 1.0), 0, 1)
    case.images["raw"] = rgba(srgb8(picture))
    if grid is None:
        scene = _scene_of(raw.scene)
        grid = scene.grid if scene is not None else None
    if grid is not None:
        R = camera_responsivities(raw.camera, grid)
        case.responsivities = {c: R[k].tolist() for k, c in enumerate(channels)}
        case.responsivities["QE × IR cut"] = clear_responsivity(raw.camera.filters, grid).tolist()
        if not case.wavelengths_nm:
            case.wavelengths_nm = list(grid.centres_nm)
    return raw


def _rendered(case: Case, path: Path):
    """Rendered CIELAB (display white) and the sRGB picture of the display's colours."""
    from spectracam.processing.color import display_rgb_to_xyz
    from spectracam.io.exr import read_exr
    from spectracam.io.report import srgb_preview
    from spectracam.core.cielab import xyz_to_lab

    channels, attrs = read_exr(path)
    if attrs.get("spectracamKind") != "rendered" or not {"R", "G", "B"} <= set(channels):
        raise SpectracamError(f"file = {str(path)!r}: not a spectracam rendering (spectracamKind = "
                              f"{attrs.get('spectracamKind')!r})")
    params = json.loads(attrs.get("spectracamParameters", "{}"))
    display = (params.get("processing") or {}).get("display", "crt")
    s = case.stride
    case.rendered_rgb = np.stack([np.asarray(channels[c][::s, ::s], np.float32) for c in "RGB"], axis=-1)
    rgb = case.rendered_rgb.astype(np.float64)
    M = display_rgb_to_xyz(display)
    case.display_to_xyz = M.tolist()
    xyz = rgb @ M.T
    case.rendered_lab = xyz_to_lab(xyz, M.sum(axis=1)).astype(np.float32)
    tone = (params.get("processing") or {}).get("tone_curve", "srgb")
    case.images["rendered"] = rgba(srgb_preview(rgb, display, tone_curve=tone))  # as rendered.png shows it
    return params


def _chart_lab(case: Case, scene) -> np.ndarray | None:
    """Scene CIELAB from the chart reference inside each patch (NaN elsewhere): the score's truth."""
    from spectracam.core.cielab import xyz_to_lab
    from spectracam.scene.reference import ChartReference

    if scene is None or getattr(scene, "target", None) is not None and scene.target.textured:
        return None
    ref = ChartReference.of(scene)
    lab = np.full((case.height, case.width, 3), np.nan, np.float32)
    patch_lab = xyz_to_lab(ref.patch_xyz, ref.white_xyz)
    for p, (r, c) in enumerate(ref.boxes):
        lab[r, c] = patch_lab[p]
    return lab[::case.stride, ::case.stride]


def _chart_patches(scene) -> list:
    """``[name, x0, y0, x1, y1]`` of each patch box the score measures (the probe names the patch under the
    pointer), or ``[]`` for a scene that is not a chart."""
    from spectracam.scene.reference import ChartReference

    if scene is None or getattr(scene, "target", None) is not None and scene.target.textured:
        return []
    try:
        ref = ChartReference.of(scene)
    except Exception:  # noqa: BLE001 - a scene the page cannot lay out still shows its pixels, unnamed
        return []
    return [[str(name), int(c.start), int(r.start), int(c.stop), int(r.stop)] for name, (r, c) in zip(ref.names,
                                                                                                      ref.boxes)]


def load_case(name: str, radiance: Path | None, raw: Path | None, rendered: Path | None, share: float = 1.0) -> Case:
    """A case from its files (any of them may be missing), every ``stride``-th pixel (:func:`tile_stride`).

    Parameters
    ----------
    name : str
        The case's name on the page (its directory relative to the output directory, ``"."`` for the top).
    radiance, raw, rendered : Path or None
        Its spectracam ``radiance.exr``, ``raw.exr`` and ``rendered.exr`` (None where it has none).
    share : float
        Its fraction of the page's budget of values, :data:`PAGE_VALUES` (1: the whole budget).

    Returns
    -------
    Case
    """
    from spectracam.io.exr import read_exr_header, read_radiance_exr

    cube = read_radiance_exr(radiance)[0] if radiance is not None else None
    if cube is not None:
        height, width, bands = cube.shape
    else:
        first = raw if raw is not None else rendered
        if first is None:
            raise SpectracamError(f"case {name!r}: no file")
        (x0, y0), (x1, y1) = read_exr_header(first)["dataWindow"]  # the size only: the pixels are read once, below
        height, width, bands = int(y1 - y0 + 1), int(x1 - x0 + 1), 0
    raw_capture = None
    tile = None
    if raw is not None:
        from spectracam.architecture.base import MosaicLayout
        from spectracam.io.exr import read_raw_exr

        raw_capture = read_raw_exr(raw)
        tile = raw_capture.layout.tile_shape if isinstance(raw_capture.layout, MosaicLayout) else None
    case = Case(name=name, width=int(width), height=int(height),
                stride=tile_stride(_stride(width, height, bands, share), tile))
    scene, grid = (None, None)
    if cube is not None:
        scene, grid = _radiance(case, cube)
    capture = _raw(case, raw_capture, grid) if raw_capture is not None else None
    params = _rendered(case, rendered) if rendered is not None else None
    if case.rendered_lab is not None:
        truth = case.scene_lab
        if truth is None and capture is not None:  # a captured chart shot (paper's cases): the score's truth
            recorded = (params or {}).get("scene") or capture.scene
            scene = _scene_of(recorded)
            truth = _chart_lab(case, scene) if scene is not None else None
            case.scene_lab = truth
            if truth is not None:
                case.notes.append("no radiance.exr: scene L*a*b* is the chart reference's patch colour "
                                  "(inside the patches only)")
        if truth is not None and truth.shape == case.rendered_lab.shape:
            case.images["error"] = np.linalg.norm(case.rendered_lab - truth, axis=-1).astype(np.float32)
    recorded = (params or {}).get("scene") or (capture.scene if capture is not None else None)
    case.patches = _chart_patches(_scene_of(recorded)) if recorded else []
    if case.stride > 1:
        case.notes.append(f"1 pixel in {case.stride} along each axis is shown and probed (the files hold "
                          f"{width} × {height})")
    return case
