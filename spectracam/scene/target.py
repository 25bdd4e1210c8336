"""Textured targets: what is in front of the camera when it is not the ColorChecker.

A target is a **label image** on a grid of texels, ``supersampling`` texels across each pixel side:
every texel shows one sample of a measured reflectance library (:mod:`spectracam.scene.reflectances`), or the
flat grey surround.  The label image *is* the target, as a print is at its resolution: both renderers
see it (Mitsuba as a nearest-neighbour texture, the closed form as the mean of each pixel's texels),
and the truth of every pixel is the area-weighted mix of the samples it shows.  Kinds (``[target]``):

* ``chart`` — the ColorChecker of ``[chart]`` (the default; not textured).
* ``samples`` — a chart of the library's samples (all, or those listed in ``samples``), row by row,
  ``columns`` across (0: as square as the image allows), each a square of ``1 − gap`` of its cell on
  the surround (``chart.surround_reflectance``).
* ``mondrian`` — axis-aligned rectangles (at most ``count``; 0: until every texel is covered), sides uniform in ``[size_min_px,
  size_max_px]``, centres uniform over the image widened by ``size_max_px``, each a sample drawn
  uniformly from the library; the first drawn lies on top (E. H. Land, "The retinex theory of color
  vision", Sci. Am. 237(6), 1977: the "colour Mondrian").
* ``dead_leaves`` — occluding discs (at most ``count``; 0: until every texel is covered), the first drawn on top, radii of density ∝
  ``r^-exponent`` on ``[size_min_px, size_max_px]`` (exponent 3: scale invariant, as natural images;
  A. B. Lee, D. Mumford, J. Huang, Int. J. Comput. Vis. 41, 2001; F. Cao, F. Guichard, H. Hornung,
  Proc. SPIE 7537, 2010, the texture chart ISO 19567-2 builds on), centres uniform, each disc a sample
  drawn uniformly from the library.  Texels still bare after ``count`` shapes show one more sample
  drawn for the background.
* ``photo`` — an RGB photograph (``photo``: a file, or ``grace_hopper``, a public-domain portrait
  shipped with the package) centre-cropped to the image's aspect, box-averaged in linear light to the
  texel grid, each texel the library sample whose CIELAB under CIE D65 is nearest (ΔE*ab) to the
  photograph's sRGB colour: a measured spectrum for every colour, the lookup method of spectral
  reconstruction (exact for colours in the library, the nearest metamer's neighbour otherwise).

Every random draw comes from ``seed`` (the target's own: the same print whatever noise seed a capture
uses).  Layouts are rasterised by texel centre; discs and rectangles by a compiled loop over shapes.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from spectracam.core.errors import ConfigError, SpectracamError
from spectracam.core.registry import Registry
from spectracam.core.spec import Spec

__all__ = ["BATCH", "MAX_PHOTO_PIXELS", "MAX_SHAPES", "MAX_TEXELS", "SHIPPED_PHOTOS", "TARGET_KINDS", "TargetSpec",
           "file_sha256", "photo_path", "power_law", "resolve_target_files", "texel_labels"]

#: Target kinds (module docstring): name → function ``(spec, shape, n_samples, library_lab) → labels``, the label image
#: ``(rows, columns)`` int32 on a texel grid of ``shape`` (:func:`texel_labels`).  A kind's place in this order is part
#: of its painted targets' seed: a new kind is registered after these.
TARGET_KINDS: Registry = Registry("target.kind", "target kind")
#: The photograph shipped with the package: Grace Hopper, U.S. Navy portrait, public domain (the copy
#: matplotlib ships as sample data, matplotlib PR #1599), reduced to 160 × 188 px.
SHIPPED_PHOTOS = {"grace_hopper": "grace_hopper_160.png"}
#: Most texels a target may have (a 4096 × 4096 texture per band: 64 MiB of float32).
MAX_TEXELS = 1 << 26
#: Shapes drawn per compiled call while a dead-leaves or Mondrian target is painted.
BATCH = 8192
#: Most shapes a target may draw (a 4096² texel dead-leaves target with the default 2-px smallest
#: radius is covered after about 200 000).
MAX_SHAPES = 100_000_000


@dataclass(frozen=True)
class TargetSpec(Spec):
    """The ``[target]`` table (module docstring)."""

    TABLE = "target"

    kind: str = "chart"
    #: The samples' library; ``file:PATH`` is relative to the scene file.  CIE 224:2017's 99 samples
    #: span natural and manufactured colours evenly and ship with colour-science.
    library: str = "cfi99"
    #: Texels per pixel side: edges fall inside pixels, whose truth is the mix (4: 16 texels a pixel).
    supersampling: int = 4
    seed: int = 0
    #: ``samples``: library indices to show (empty: all), columns (0: automatic), gap between squares
    #: as a fraction of the cell.
    samples: tuple = ()
    columns: int = 0
    gap: float = 0.2
    #: ``mondrian`` / ``dead_leaves``: most shapes (0: as many as it takes to cover every texel, at
    #: most :data:`MAX_SHAPES`), their size range (rectangle sides, disc radii) in pixels, and the dead
    #: leaves' radius exponent.
    count: int = 0
    size_min_px: float = 2.0
    size_max_px: float = 100.0
    exponent: float = 3.0
    #: ``photo``: a shipped photograph's name or ``file:PATH`` (relative to the scene file), and the
    #: file's SHA-256 (recorded when the spec is made; a file that no longer has it is refused).
    photo: str = "grace_hopper"
    photo_sha256: str = ""
    #: How the image is looked at, for S-CIELAB: one image pixel per display pixel of 120 dpi seen from
    #: 0.5 m (ISETCam's default, 41 pixels per degree; the same as ``spectracam spatial``).
    viewing_distance_m: float = 0.5
    display_pixel_pitch_mm: float = 25.4 / 120
    #: A sample's region is scored on its pixels at least this far (px) from any other sample: away
    #: from edges, where demosaicking mixes neighbours.
    interior_margin_px: int = 2

    def validate(self) -> None:
        from spectracam.scene.reflectances import LIBRARIES

        self.choice("kind", TARGET_KINDS)
        lib = self.library
        if not isinstance(lib, str) or not (lib in LIBRARIES or (lib.startswith("file:") and len(lib) > 5)):
            raise self.error("library", "must be one of " + ", ".join(LIBRARIES) + " or 'file:PATH'")
        self.integer("supersampling", 1, 16)
        self.integer("seed", 0, 2**31 - 1)
        if not isinstance(self.samples, tuple) or not all(isinstance(i, int) and not isinstance(i, bool) and i >= 0
                                                          for i in self.samples):
            raise self.error("samples", "must be a list of sample indices ≥ 0 (empty: every sample)",
                             list(self.samples) if isinstance(self.samples, tuple) else self.samples)
        self.integer("columns", 0, 4096)
        self.number("gap", 0.0, 0.9)
        self.integer("count", 0, MAX_SHAPES)
        self.number("size_min_px", 0.0, 4096.0, lo_open=True, unit="px")
        self.number("size_max_px", 0.0, 4096.0, lo_open=True, unit="px")
        if self.size_max_px < self.size_min_px:
            raise self.error("size_max_px", f"must be ≥ size_min_px ({self.size_min_px:g} px)")
        self.number("exponent", 1.0, 6.0)
        if not isinstance(self.photo, str) or not (self.photo in SHIPPED_PHOTOS
                                                   or (self.photo.startswith("file:") and len(self.photo) > 5)):
            raise self.error("photo", "must be " + ", ".join(map(repr, SHIPPED_PHOTOS)) + " or 'file:PATH' (an "
                             "image file: PNG, JPEG, TIFF...)")
        self.string("photo_sha256")
        if self.kind == "photo":   # the file the target is made from: recorded, and a changed one refused
            path = photo_path(self.photo)
            digest = file_sha256(path, "target.photo")
            if self.photo_sha256 and self.photo_sha256 != digest:
                raise self.error("photo", f"{path} has changed since the scene was recorded (SHA-256 {digest[:12]}…, "
                                 f"the scene says {self.photo_sha256[:12]}…)")
            object.__setattr__(self, "photo_sha256", digest)
        self.number("viewing_distance_m", 0.0, 100.0, lo_open=True, unit="m")
        self.number("display_pixel_pitch_mm", 0.0, 100.0, lo_open=True, unit="mm")
        self.integer("interior_margin_px", 0, 64)

    @property
    def textured(self) -> bool:
        return self.kind != "chart"

    def texel_shape(self, width_px: int, height_px: int) -> tuple[int, int]:
        """``(rows, columns)`` of the texel grid.

        Parameters
        ----------
        width_px, height_px : int
            The image's size, pixels.

        Returns
        -------
        tuple of int
            ``(height_px·s, width_px·s)``, s the supersampling.
        """
        return height_px * self.supersampling, width_px * self.supersampling

    def check_size(self, width_px: int, height_px: int) -> None:
        """Refuse a textured target of more than :data:`MAX_TEXELS` texels at this image size.

        Parameters
        ----------
        width_px, height_px : int
            The image's size, pixels.
        """
        h, w = self.texel_shape(width_px, height_px)
        if self.textured and h * w > MAX_TEXELS:
            raise ConfigError("target.supersampling", self.supersampling,
                              f"{width_px}x{height_px} px × {self.supersampling}² texels is {h * w} texels, more "
                              f"than {MAX_TEXELS} (a 4096² texture); use a smaller supersampling or image")


def photo_path(photo: str) -> Path:
    """The file of a shipped photograph or of ``file:PATH``.

    Parameters
    ----------
    photo : str
        A key of :data:`SHIPPED_PHOTOS`, or ``file:PATH``.

    Returns
    -------
    Path
        The image file.
    """
    if photo in SHIPPED_PHOTOS:
        from importlib.resources import files

        return Path(str(files("spectracam") / "data" / SHIPPED_PHOTOS[photo]))
    return Path(photo[5:])


def file_sha256(path: Path, what: str) -> str:
    """The file's SHA-256, read once per version of the file (a scene is validated several times a run).

    Parameters
    ----------
    path : Path
        The file.
    what : str
        The field that named it, for the error.

    Returns
    -------
    str
        The hex digest.
    """
    from spectracam.core.files import regular_file

    regular_file(path, what)
    try:
        st = path.stat()
        return _sha256(str(path), st.st_mtime_ns, st.st_size)
    except OSError as e:
        raise ConfigError(what, str(path), f"cannot be read ({e.strerror})") from None


@lru_cache(maxsize=8)
def _sha256(path: str, mtime_ns: int, size: int) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def resolve_target_files(table: dict, base_dir: Path) -> dict:
    """A ``[target]`` table with its ``file:`` paths made absolute against the scene file's directory.

    Parameters
    ----------
    table : dict
        The ``[target]`` table (not changed); its ``library`` and ``photo`` may be ``file:`` paths.
    base_dir : Path
        The scene file's directory.

    Returns
    -------
    dict
        A copy with relative ``file:`` paths resolved.
    """
    t = dict(table)
    for key in ("library", "photo"):
        v = t.get(key)
        if isinstance(v, str) and v.startswith("file:") and len(v) > 5 and not Path(v[5:]).is_absolute():
            t[key] = "file:" + str((Path(base_dir) / v[5:]).resolve())
    return t


# -- layouts: (texel rows, texel columns) int32 labels; n = the surround -------------------------------

def _samples_layout(spec: TargetSpec, n: int, shape: tuple[int, int]) -> np.ndarray:
    """The library chart: squares of ``1 − gap`` of their cell, row by row, centred in the image."""
    chosen = np.arange(n) if not spec.samples else np.asarray(spec.samples)
    if chosen.max(initial=0) >= n:
        raise ConfigError("target.samples", list(spec.samples), f"indices must be below the library's {n} samples")
    h, w = shape
    k = chosen.size
    cols = spec.columns or max(1, int(np.ceil(np.sqrt(k * w / h))))
    rows = int(np.ceil(k / cols))
    cell = min(w / cols, h / rows)
    x0, y0 = (w - cols * cell) / 2, (h - rows * cell) / 2
    inset = spec.gap * cell / 2
    yc, xc = np.arange(h) + 0.5 - y0, np.arange(w) + 0.5 - x0      # texel centres from the grid's corner
    r, c = np.floor(yc / cell).astype(int), np.floor(xc / cell).astype(int)
    in_r = (r >= 0) & (r < rows) & (yc - r * cell >= inset) & (yc - r * cell < cell - inset)
    in_c = (c >= 0) & (c < cols) & (xc - c * cell >= inset) & (xc - c * cell < cell - inset)
    idx = r[:, None] * cols + c[None, :]
    inside = in_r[:, None] & in_c[None, :] & (idx < k)
    labels = np.full(shape, n, np.int32)
    labels[inside] = chosen[idx[inside]]
    return labels


def power_law(u: np.ndarray, lo: float, hi: float, a: float) -> np.ndarray:
    """Radii of density ∝ ``r^-a`` on ``[lo, hi]`` from uniforms ``u`` in [0, 1) (the inverse CDF).

    Parameters
    ----------
    u : ndarray
        Uniform draws in [0, 1).
    lo, hi : float
        The range of radii (> 0), in the caller's unit.
    a : float
        The exponent (1: log-uniform).

    Returns
    -------
    ndarray
        Radii, the shape of ``u``.
    """
    if abs(a - 1.0) < 1e-12:
        return lo * (hi / lo) ** u
    return (lo ** (1 - a) + u * (hi ** (1 - a) - lo ** (1 - a))) ** (1 / (1 - a))


def _paint(kind: str, spec: TargetSpec, n: int, shape: tuple[int, int]) -> np.ndarray:
    """Occluding shapes, the first drawn on top, until every texel is covered or ``count`` are drawn;
    texels still bare then show one more sample drawn for the background (said in the docs)."""
    from spectracam.scene._paint import paint_shapes

    s = spec.supersampling
    h, w = shape
    rng = np.random.default_rng(np.random.SeedSequence([spec.seed, TARGET_KINDS.names.index(kind)]))
    labels = np.full(shape, -1, np.int32)
    lo, hi = spec.size_min_px * s, spec.size_max_px * s
    bare, drawn = h * w, 0
    most = spec.count or MAX_SHAPES
    while bare and drawn < most:
        m = min(BATCH, most - drawn)
        cx = rng.uniform(-hi, w + hi, m)
        cy = rng.uniform(-hi, h + hi, m)
        if kind == "dead_leaves":
            half_w = half_h = power_law(rng.uniform(0.0, 1.0, m), lo, hi, spec.exponent)
        else:
            half_w, half_h = rng.uniform(lo, hi, m) / 2, rng.uniform(lo, hi, m) / 2
        colour = rng.integers(0, n, m).astype(np.int32)
        bare = paint_shapes(labels, cx, cy, half_w, half_h, colour, kind == "dead_leaves", bare)
        drawn += m
    if bare:
        labels[labels < 0] = rng.integers(0, n)
    return labels


#: Most pixels a photograph may have: 8192 × 8192 (64 Mpx, as many as the largest texel grid, MAX_TEXELS); it
#: is box-filtered down to the texel grid anyway, and decoding it takes 16 bytes a colour a pixel.  A header
#: declaring more (a "decompression bomb", PIL's DecompressionBombError) is refused before any pixel is read.
MAX_PHOTO_PIXELS = 1 << 26
_TIFF_MAGIC = (b"II*\x00", b"MM\x00*", b"II+\x00", b"MM\x00+")


def _photo_error(path: Path, why: str) -> SpectracamError:
    return SpectracamError(f"target.photo = {str(path)!r}: {why}")


def _check_photo_size(path: Path, width: int, height: int) -> None:
    if width * height > MAX_PHOTO_PIXELS:
        raise _photo_error(path, f"{width}x{height} px ({width * height / 1e6:.0f} Mpx) is larger than the "
                           f"{MAX_PHOTO_PIXELS} px (8192x8192) a photograph may have; reduce it first")


def _read_float_tiff(path: Path) -> np.ndarray:
    """A TIFF PIL cannot read (floating-point RGB: PIL reads float only as one channel) with tifffile:
    ``(h, w)`` or ``(h, w, samples)``, its size checked before its pixels are read."""
    import tifffile

    try:
        with tifffile.TiffFile(path) as tif:
            page = tif.pages[0]
            axes, shape = page.axes, page.shape
            h = shape[axes.index("Y")] if "Y" in axes else 0
            w = shape[axes.index("X")] if "X" in axes else 0
            _check_photo_size(path, w, h)
            arr = page.asarray()
    except SpectracamError:
        raise
    except Exception as e:  # noqa: BLE001 - tifffile's errors for a damaged file are of many types
        why = str(e).splitlines()[0] if str(e) else type(e).__name__
        raise _photo_error(path, f"not a TIFF file tifffile can read ({why})") from None
    if "S" in axes and axes.index("S") < axes.index("Y"):    # planar configuration: samples first
        arr = np.moveaxis(arr, axes.index("S"), -1)
    if arr.dtype.kind != "f":
        raise _photo_error(path, f"a TIFF of {arr.dtype} samples PIL cannot read; give 8- or 16-bit integer or "
                           "32-bit float RGB")
    return arr


def _read_photo(path: Path) -> np.ndarray:
    """Linear sRGB ``(h, w, 3)`` in 0–1 of an image file: 8- or 16-bit (sRGB-encoded: decoded here), or a
    floating-point TIFF (linear light already, 1 = white: read as is, its values checked); one line if it
    is not one, or is larger than :data:`MAX_PHOTO_PIXELS` (checked on its header, before its pixels)."""
    from spectracam.core.files import regular_file

    path = regular_file(path, "target.photo")
    arr, floating = _decode_photo(path, _file_magic(path))
    arr = _photo_rgb(path, arr)
    return _checked_linear(path, arr) if floating else _srgb_decoded(arr)


def _file_magic(path: Path) -> bytes:
    """The file's first 4 bytes (a TIFF's signature: :data:`_TIFF_MAGIC`)."""
    try:
        with open(path, "rb") as f:
            return f.read(4)
    except FileNotFoundError:
        raise _photo_error(path, "no such file") from None
    except OSError as e:
        raise _photo_error(path, f"cannot be read ({e.strerror})") from None


def _decode_photo(path: Path, magic: bytes) -> tuple[np.ndarray, bool]:
    """``(pixels, floating)``: the image as PIL decodes it — or tifffile, a floating-point RGB TIFF PIL cannot read —
    and whether it is floating point (linear light); its size checked on its header first."""
    import warnings

    from PIL import Image, UnidentifiedImageError

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            with Image.open(path) as im:
                _check_photo_size(path, *im.size)
                im.load()
                if im.mode == "F":   # 32-bit float (one channel): linear light; convert("RGB") would clip it to 0/1
                    return np.asarray(im, dtype=np.float64), True
                return np.asarray(im.convert("RGB") if im.mode not in ("I;16", "I;16B", "RGB") else im), False
    except FileNotFoundError:
        raise _photo_error(path, "no such file") from None
    except Image.DecompressionBombError as e:   # a header declaring more pixels than PIL will decode at all
        import re

        m = re.search(r"\((\d+) pixels\)", str(e))
        size = f"{int(m.group(1)) / 1e6:.0f} Mpx" if m else "more pixels than PIL decodes"
        raise _photo_error(path, f"declares {size}, larger than the {MAX_PHOTO_PIXELS} px (8192x8192) a photograph "
                           "may have; reduce it first") from None
    except UnidentifiedImageError as e:
        if magic not in _TIFF_MAGIC:
            raise _photo_error(path, f"not an image file PIL can read ({e}); give a PNG, JPEG or TIFF") from None
        return _read_float_tiff(path).astype(np.float64), True
    except (OSError, SyntaxError, ValueError) as e:
        raise _photo_error(path, f"not an image file PIL can read ({e}); give a PNG, JPEG or TIFF") from None


def _photo_rgb(path: Path, arr: np.ndarray) -> np.ndarray:
    """``(h, w, 3)``: grey repeated, alpha dropped; one line for any other shape or one under 2×2 pixels."""
    if arr.ndim == 2:
        arr = np.repeat(arr[:, :, None], 3, axis=2)
    if arr.ndim != 3 or arr.shape[2] not in (1, 3, 4):
        raise _photo_error(path, f"an image of shape {arr.shape}; give grey, RGB or RGBA")
    if arr.shape[2] == 1:
        arr = np.repeat(arr, 3, axis=2)
    arr = arr[:, :, :3]
    if arr.shape[0] < 2 or arr.shape[1] < 2:
        raise _photo_error(path, f"{arr.shape[1]}x{arr.shape[0]} px; at least 2x2 needed")
    return arr


def _checked_linear(path: Path, arr: np.ndarray) -> np.ndarray:
    """A floating-point image: linear light, 1 = a perfect white, as is; nothing is clipped unsaid."""
    if not np.all(np.isfinite(arr)):
        raise _photo_error(path, "a floating-point image with NaN or infinite values")
    lo, hi = float(arr.min()), float(arr.max())
    if lo < 0 or hi > 1:
        raise _photo_error(path, f"a floating-point image is read as linear light 0–1 (1 = white); this one "
                           f"spans {lo:.4g}–{hi:.4g}: scale it into 0–1")
    return np.ascontiguousarray(arr, dtype=np.float64)


def _srgb_decoded(arr: np.ndarray) -> np.ndarray:
    """8- or 16-bit sRGB-encoded values as linear light 0–1 (IEC 61966-2-1 decoding)."""
    encoded = arr.astype(np.float64) / (65535.0 if arr.dtype == np.uint16 or arr.max() > 255 else 255.0)
    return np.where(encoded <= 0.04045, encoded / 12.92, ((encoded + 0.055) / 1.055) ** 2.4)


def _box_resize(img: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Centre-crop ``img`` to the aspect of ``shape`` and resample it there, each output the mean
    (in linear light) of the input it covers (PIL's box filter, per channel in 32-bit float)."""
    from PIL import Image

    h, w = shape
    ih, iw = img.shape[:2]
    if iw * h > ih * w:     # wider than the target: crop the sides
        cw = ih * w / h
        box = ((iw - cw) / 2, 0.0, (iw + cw) / 2, float(ih))
    else:
        ch = iw * h / w
        box = (0.0, (ih - ch) / 2, float(iw), (ih + ch) / 2)
    out = np.empty((h, w, 3), np.float32)
    for k in range(3):
        plane = Image.fromarray(np.ascontiguousarray(img[:, :, k], np.float32), mode="F")
        out[:, :, k] = np.asarray(plane.resize((w, h), Image.Resampling.BOX, box=box))
    return out


def _photo_layout(spec: TargetSpec, shape: tuple[int, int], library_lab: np.ndarray) -> np.ndarray:
    """Each texel the library sample nearest in CIELAB (D65) to the photograph's colour there."""
    from scipy.spatial import cKDTree

    from spectracam.core.cielab import xyz_to_lab

    linear = _box_resize(_read_photo(photo_path(spec.photo)), shape)
    # nearest neighbours of the distinct colours only (a photograph has far fewer than texels), at 1/4096
    code = np.round(np.clip(linear, 0, 1) * 4095).astype(np.int64)
    key = (code[..., 0] << 24) | (code[..., 1] << 12) | code[..., 2]
    uniq, inverse = np.unique(key.ravel(), return_inverse=True)
    rgb = np.stack([(uniq >> 24) & 4095, (uniq >> 12) & 4095, uniq & 4095], axis=-1) / 4095.0
    from spectracam.core import colour_data

    to_xyz = colour_data.srgb_matrix("RGB_to_XYZ")
    xyz = rgb @ to_xyz.T                 # D65, Y = 1 for white
    lab = xyz_to_lab(xyz, to_xyz.sum(axis=1))
    _, nearest = cKDTree(library_lab).query(lab)
    return nearest.astype(np.int32)[inverse].reshape(shape)


def texel_labels(spec: TargetSpec, width_px: int, height_px: int, n_samples: int,
                 library_lab: np.ndarray | None = None) -> np.ndarray:
    """The label image ``(H·s, W·s)`` int32, read-only: a library index per texel, ``n_samples`` for
    the surround.  ``library_lab`` (``photo`` only): the samples' CIELAB ``(n, 3)`` under D65.

    Parameters
    ----------
    spec : TargetSpec
        The target (its kind, supersampling and seed).
    width_px, height_px : int
        The image's size, pixels.
    n_samples : int
        The library's size.
    library_lab : ndarray or None
        ``(n_samples, 3)`` CIELAB of the samples; a ``photo`` target needs it.

    Returns
    -------
    ndarray
        ``(height_px·s, width_px·s)`` int32, read-only.
    """
    spec.check_size(width_px, height_px)
    shape = spec.texel_shape(width_px, height_px)
    labels = TARGET_KINDS[spec.kind](spec, shape, n_samples, library_lab)
    labels.setflags(write=False)
    return labels


# -- the kinds, registered in the order of their seeds ------------------------------------------------

@TARGET_KINDS.register("chart")
def _chart(spec: TargetSpec, shape, n_samples: int, library_lab) -> np.ndarray:
    """The ColorChecker of ``[chart]``: no texel grid (the chart's own geometry draws it)."""
    raise SpectracamError(f"target.kind = {spec.kind!r}: the ColorChecker is not a textured target")


@TARGET_KINDS.register("samples")
def _samples(spec: TargetSpec, shape, n_samples: int, library_lab) -> np.ndarray:
    """The library's samples as a chart (:func:`_samples_layout`)."""
    return _samples_layout(spec, n_samples, shape)


def _painted(spec: TargetSpec, shape, n_samples: int, library_lab) -> np.ndarray:
    """Occluding rectangles (``mondrian``) or discs (``dead_leaves``): :func:`_paint`."""
    return _paint(spec.kind, spec, n_samples, shape)


TARGET_KINDS.register("mondrian", _painted)
TARGET_KINDS.register("dead_leaves", _painted)


@TARGET_KINDS.register("photo")
def _photo(spec: TargetSpec, shape, n_samples: int, library_lab) -> np.ndarray:
    """A photograph, each texel its nearest library sample (:func:`_photo_layout`)."""
    return _photo_layout(spec, shape, np.asarray(library_lab, float))
