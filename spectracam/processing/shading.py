"""Lens-shading correction as a camera does it (issue 37, item 4), and the Raspberry Pi HQ camera's tables (item 6).

A camera flattens its lens's fall-off with **per-channel gain tables on a coarse grid** — libcamera's Raspberry Pi
ALSC ("automatic lens shading correction") uses 16×12 cells on the VC4 ISP [libcamera] — interpolated bilinearly to
every pixel.  The tables are calibrated on a flat field under one light (:func:`calibrate_gain_tables`) or under a
few, and the camera picks the table of the light it estimates by linear interpolation in colour temperature, clamped
at the calibrated ends, as libcamera's ALSC does (:func:`interpolate_tables_by_cct`).  Applied under another light
(:func:`apply_gain_tables`), a table calibrated for one spectrum leaves a **residual colour shading** wherever the
channels' fall-off depends on wavelength (crosstalk, microlens diffraction, an interference IR-cut filter's edge
moving with angle): :func:`residual_colour_shading` reports it as per-channel ratio maps.

Calibration, two ways (``method``):

``fit``        the table's node values (at the grid's corners, bilinear in between) are fitted by linear least
               squares so that gain × flat field is the channel's centre level at every pixel: the best a bilinear
               table can flatten the calibration image (flat to 0.1 % for smooth fall-off on a 16×12 grid);
``cell_mean``  libcamera's camera tuning tool's reading: each cell's gain is the centre level over the cell's mean,
               placed at the cell's centre (extrapolated linearly beyond the outer centres).

:func:`read_libcamera_alsc` reads a Raspberry Pi tuning file's ``rpi.alsc`` block (version 1 or 2 files): the
``luminance_lut`` (the luminance fall-off correction, a 16×12 gain table), ``luminance_strength``, and the colour
tables ``calibrations_Cr`` / ``calibrations_Cb`` at each calibrated colour temperature (the R and B gains relative to
G, including the white balance's ratio at that light).  :func:`table_figures` gives their corner/centre figures.

References: see ``docs/references.md`` ([libcamera], [RPiTuning]).
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from spectracam.core.errors import ConfigError, SpectracamError
from spectracam.core.spec import Spec

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from spectracam.architecture.base import MosaicLayout, PlanesLayout
    from spectracam.camera import CameraSpec
    from spectracam.core.spectra import WavelengthGrid
    from spectracam.processing.color import ProcessingSpec
    from spectracam.scene.illuminant import IlluminantSpec

__all__ = ["ALSC_CELLS", "DAYLIGHT_FROM_K", "LIBCAMERA_TUNING_DIRS", "PLACEMENTS", "SHADING_CORRECTIONS", "SHADING_METHODS",
           "AlscTuning", "ShadingSpec", "ShadingTables", "apply_gain_tables", "calibrate_gain_tables", "calibration_light",
           "channel_planes", "correct_shading", "flat_field", "tile_planes", "shading_gain_maps",
           "find_libcamera_tuning", "interpolate_table", "interpolate_tables_by_cct", "interpolation_matrix",
           "luminance_and_colour_tables", "read_libcamera_alsc", "residual_colour_shading", "table_figures"]

#: libcamera's Raspberry Pi (VC4) ALSC grid: 12 rows × 16 columns of cells.
ALSC_CELLS = (12, 16)
#: Where a table's nodes lie: at the cells' centres (libcamera) or on a grid spanning the image's corner pixels.
PLACEMENTS = ("centres", "corners")
#: Calibration methods (module docstring).
SHADING_METHODS = ("fit", "cell_mean")
#: What the camera corrects with: nothing (today), one table (calibrated under one light), or tables at several
#: colour temperatures interpolated by the estimated one.
SHADING_CORRECTIONS = ("none", "single", "cct")
#: Where Debian's ``libcamera-ipa`` puts the Raspberry Pi tuning files (newer: ``rpi/vc4``; 0.0.x: ``raspberrypi``).
LIBCAMERA_TUNING_DIRS = ("/usr/share/libcamera/ipa/rpi/vc4", "/usr/share/libcamera/ipa/raspberrypi")


@dataclass(frozen=True)
class ShadingSpec(Spec):
    """The camera's lens-shading correction; ``correction = "none"`` (today: no off-axis model, nothing to correct)."""

    TABLE = "shading"

    #: "none", "single" or "cct" (:data:`SHADING_CORRECTIONS`).
    correction: str = "none"
    #: Colour temperatures of the flat fields the tables are calibrated under, K: libcamera's IMX477 tuning
    #: calibrates at 2960, 4850 and 5930 K [RPiTuning]; "single" uses the first.
    calibration_temperatures_K: tuple = (2960.0, 4850.0, 5930.0)
    #: The grid, rows × columns: libcamera's 12 × 16.
    grid_rows: int = 12
    grid_columns: int = 16
    #: "fit" or "cell_mean" (:data:`SHADING_METHODS`).
    method: str = "fit"

    def validate(self) -> None:
        self.choice("correction", SHADING_CORRECTIONS)
        t = self.calibration_temperatures_K
        ok = isinstance(t, tuple) and len(t) >= 1 and all(
            isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) and 1000 <= x <= 25000
            for x in t) and all(b > a for a, b in zip(t, t[1:]))
        if not ok:
            raise self.error("calibration_temperatures_K", "must be a list of increasing colour temperatures between "
                             "1000 and 25000 K", list(t) if isinstance(t, tuple) else t)
        object.__setattr__(self, "calibration_temperatures_K", tuple(float(x) for x in t))
        self.integer("grid_rows", 2, 256)
        self.integer("grid_columns", 2, 256)
        self.choice("method", SHADING_METHODS)


@dataclass(frozen=True, eq=False)
class ShadingTables:
    """Per-channel gain tables ``(N, rows, columns)`` and where their nodes lie (:data:`PLACEMENTS`)."""

    gains: np.ndarray
    placement: str = "corners"


def _planes(planes, name: str = "planes") -> np.ndarray:
    p = np.asarray(planes, dtype=float)
    if p.ndim != 3 or min(p.shape[1:]) < 2:
        raise ConfigError(name, f"shape {p.shape}", "must be (channels, H, W) planes of at least 2×2 pixels")
    if not np.all(np.isfinite(p)) or np.any(p <= 0):
        raise ConfigError(name, "values ≤ 0 or not finite", "a flat field must be finite and > 0 in every channel")
    return p


def interpolation_matrix(n_px: int, n_nodes: int, placement: str = "corners") -> np.ndarray:
    """Linear interpolation weights from a row of table nodes to a row of pixels.

    Parameters
    ----------
    n_px : int
        Pixels along the axis.
    n_nodes : int
        Nodes along the axis (≥ 2).
    placement : str
        "corners": node k at pixel ``k·(n_px − 1)/(n_nodes − 1)``; "centres": node k at the centre of cell k of
        ``n_nodes`` equal cells, extrapolated linearly beyond the first and last centres (libcamera's cells).

    Returns
    -------
    numpy.ndarray
        ``(n_px, n_nodes)``, each row summing to 1 with at most two non-zero weights (negative where extrapolated).

    References
    ----------
    .. [libcamera] see docs/references.md (ALSC cells).
    """
    if placement not in PLACEMENTS:
        raise ConfigError("placement", placement, "must be one of " + ", ".join(map(repr, PLACEMENTS)))
    x = np.arange(n_px, dtype=float)
    if placement == "corners":
        pos = x * (n_nodes - 1) / max(n_px - 1, 1)
    else:
        pos = (x + 0.5) * n_nodes / n_px - 0.5
    k = np.clip(np.floor(pos).astype(int), 0, n_nodes - 2)
    f = pos - k
    m = np.zeros((n_px, n_nodes))
    m[np.arange(n_px), k] = 1 - f
    m[np.arange(n_px), k + 1] += f
    return m


def interpolate_table(table: ArrayLike, shape: tuple[int, int], placement: str = "corners") -> np.ndarray:
    """A coarse table ``(..., rows, columns)`` interpolated bilinearly to ``(..., H, W)``.

    Parameters
    ----------
    table : array_like
        ``(..., rows, columns)`` gains.
    shape : tuple of int
        The image's ``(H, W)``.
    placement : str
        :data:`PLACEMENTS`.

    Returns
    -------
    numpy.ndarray
        ``(..., H, W)``: ``Wy @ T @ Wxᵀ`` (bilinear interpolation is separable).

    References
    ----------
    .. [libcamera] see docs/references.md.
    """
    t = np.asarray(table, dtype=float)
    wy = interpolation_matrix(shape[0], t.shape[-2], placement)
    wx = interpolation_matrix(shape[1], t.shape[-1], placement)
    return wy @ t @ wx.T


def _centre_level(plane: np.ndarray) -> float:
    """Mean of the central box (1/8 of each side, at least two pixels) of one plane (NaN: not this channel's pixel)."""
    h, w = plane.shape
    bh, bw = max(2, h // 8), max(2, w // 8)
    return float(np.nanmean(plane[(h - bh) // 2:(h + bh) // 2, (w - bw) // 2:(w + bw) // 2]))


def _fit_nodes(plane: np.ndarray, target: float, rows: int, cols: int) -> np.ndarray:
    """Least-squares node values ``T`` minimising ``Σ (plane·(Wy T Wxᵀ) − target)²`` over the plane's pixels that are
    not NaN (a mosaic's channel: only its own sites), by the normal equations."""
    known = np.isfinite(plane)
    p = np.where(known, plane, 0.0)
    wy = interpolation_matrix(plane.shape[0], rows)
    wx = interpolation_matrix(plane.shape[1], cols)
    m1 = np.einsum("ij,jb,jd->ibd", p**2, wx, wx)  # (H, cols, cols)
    ata = np.einsum("ia,ic,ibd->abcd", wy, wy, m1).reshape(rows * cols, rows * cols)
    atb = (wy.T @ (p * target) @ wx).reshape(-1)
    return np.linalg.solve(ata, atb).reshape(rows, cols)


def _cell_means(plane: np.ndarray, rows: int, cols: int) -> np.ndarray:
    ey = np.linspace(0, plane.shape[0], rows + 1).round().astype(int)
    ex = np.linspace(0, plane.shape[1], cols + 1).round().astype(int)
    return np.array([[np.nanmean(plane[ey[r]:ey[r + 1], ex[c]:ex[c + 1]]) for c in range(cols)] for r in range(rows)])


def channel_planes(mosaic: ArrayLike, layout: MosaicLayout) -> np.ndarray:
    """A mosaic's channels as full-size planes, each holding its own sites' values and NaN elsewhere (what a tuning
    tool reads of a raw flat field: no demosaicking, whose borders would enter the table).

    Parameters
    ----------
    mosaic : array_like
        ``(H, W)``.
    layout : MosaicLayout

    Returns
    -------
    numpy.ndarray
        ``(N, H, W)`` float64.
    """
    m = np.asarray(mosaic, dtype=float)
    channel = layout.channel_index(m.shape)
    return np.stack([np.where(channel == k, m, np.nan) for k in range(len(layout.channels))])


def calibrate_gain_tables(flat: ArrayLike, spec: ShadingSpec | None = None,
                          layout: MosaicLayout | None = None) -> ShadingTables:
    """Per-channel gain tables from a flat field: gain × flat = the channel's centre level.

    Parameters
    ----------
    flat : array_like
        ``(N, H, W)`` the flat field's channel planes, > 0 (NaN where a channel has no pixel); or, with ``layout`` a
        :class:`~spectracam.architecture.base.MosaicLayout`, the raw ``(H, W)`` mosaic (each channel fitted on its own
        sites, :func:`channel_planes`).
    spec : ShadingSpec, optional
        Grid size and method (default :class:`ShadingSpec`'s 12 × 16, "fit").
    layout : MosaicLayout, optional
        The mosaic's tile, when ``flat`` is a mosaic.

    Returns
    -------
    ShadingTables
        ``(N, rows, columns)`` gains; "fit" at the grid's corners, "cell_mean" at the cells' centres.

    References
    ----------
    .. [libcamera] see docs/references.md (the tuning tool's cell means).
    """
    spec = spec or ShadingSpec()
    if layout is not None and np.ndim(flat) == 2:
        flat = channel_planes(flat, layout)
    p = np.asarray(flat, dtype=float)
    if p.ndim != 3 or min(p.shape[1:]) < 2:
        raise ConfigError("flat", f"shape {p.shape}", "must be (channels, H, W) planes of at least 2×2 pixels")
    known = p[np.isfinite(p)]
    if known.size == 0 or np.any(known <= 0) or np.any(np.isinf(p)):
        raise ConfigError("flat", "values ≤ 0 or not finite", "a flat field must be finite and > 0 in every channel")
    for k, c in enumerate(p):   # every channel needs two of its own pixels per node along each side
        known = np.isfinite(c)
        rows, cols = int(known.any(axis=1).sum()), int(known.any(axis=0).sum())
        if rows < 2 * spec.grid_rows or cols < 2 * spec.grid_columns:
            raise ConfigError("processing.shading_grid", [spec.grid_rows, spec.grid_columns],
                              f"needs two pixels of each channel per node along each side; channel {k} has "
                              f"{rows} rows × {cols} columns of pixels in this {p.shape[1]} × {p.shape[2]} image: "
                              "a larger image or a coarser grid")
    targets = [_centre_level(c) for c in p]
    if spec.method == "fit":
        try:
            gains = np.stack([_fit_nodes(c, t, spec.grid_rows, spec.grid_columns) for c, t in zip(p, targets)])
        except np.linalg.LinAlgError:
            gains = np.full((1,), np.nan)   # a node no pixel constrains: refused below
        placement = "corners"
    else:
        gains = np.stack([t / _cell_means(c, spec.grid_rows, spec.grid_columns) for c, t in zip(p, targets)])
        placement = "centres"
    if not np.all(np.isfinite(gains)) or np.any(gains <= 0):
        raise ConfigError("processing.shading_grid", [spec.grid_rows, spec.grid_columns],
                          f"gives gains that are not finite and > 0 on this {p.shape[1]} × {p.shape[2]} flat field: "
                          "a coarser grid")
    return ShadingTables(gains, placement)


def apply_gain_tables(planes: ArrayLike, tables: ShadingTables) -> np.ndarray:
    """The planes ``(N, H, W)`` times their channels' interpolated gains.

    Parameters
    ----------
    planes : array_like
        ``(N, H, W)`` channel planes.
    tables : ShadingTables
        ``(N, rows, columns)`` gains.

    Returns
    -------
    numpy.ndarray
        ``(N, H, W)`` corrected planes.

    References
    ----------
    .. [libcamera] see docs/references.md.
    """
    p = np.asarray(planes, dtype=float)
    if p.ndim != 3 or p.shape[0] != tables.gains.shape[0]:
        raise ConfigError("planes", f"shape {p.shape}", f"must be ({tables.gains.shape[0]}, H, W) for these tables")
    return p * interpolate_table(tables.gains, p.shape[1:], tables.placement)


def interpolate_tables_by_cct(tables_by_cct: dict, cct_K: float) -> ShadingTables:
    """The tables at a colour temperature: linear in CCT between the two calibrated neighbours, clamped at the ends
    (libcamera's Raspberry Pi ALSC).

    Parameters
    ----------
    tables_by_cct : dict
        ``{CCT in K: ShadingTables}``, all with the same shape and placement.
    cct_K : float
        The estimated colour temperature, K.

    Returns
    -------
    ShadingTables

    References
    ----------
    .. [libcamera] see docs/references.md (ALSC's calibration tables by colour temperature).
    """
    if not tables_by_cct:
        raise ConfigError("tables_by_cct", {}, "must hold tables at one colour temperature at least")
    if not isinstance(cct_K, (int, float)) or isinstance(cct_K, bool) or not math.isfinite(cct_K) or cct_K <= 0:
        raise ConfigError("cct_K", cct_K, "must be a colour temperature > 0 K")
    cts = sorted(tables_by_cct)
    if cct_K <= cts[0] or len(cts) == 1:
        return tables_by_cct[cts[0]]
    if cct_K >= cts[-1]:
        return tables_by_cct[cts[-1]]
    i = int(np.searchsorted(cts, cct_K)) - 1
    a, b = tables_by_cct[cts[i]], tables_by_cct[cts[i + 1]]
    p = (cct_K - cts[i]) / (cts[i + 1] - cts[i])
    return ShadingTables(a.gains * (1 - p) + b.gains * p, a.placement)


def tile_planes(mosaic: ArrayLike, layout: MosaicLayout) -> np.ndarray:
    """A mosaic's channels at one value per tile: each channel's mean over its sites in the tile (both greens of a
    Bayer tile), ``(N, H // th, W // tw)`` (a partial last tile is left out).

    Parameters
    ----------
    mosaic : array_like
        ``(H, W)``.
    layout : MosaicLayout

    Returns
    -------
    numpy.ndarray
        ``(N, H // th, W // tw)`` float64.
    """
    m = np.asarray(mosaic, dtype=float)
    th, tw = layout.tile_shape
    h, w = (m.shape[0] // th) * th, (m.shape[1] // tw) * tw
    tiles = m[:h, :w].reshape(h // th, th, w // tw, tw)
    tile = np.asarray(layout.tile)
    return np.stack([np.mean([tiles[:, dy, :, dx] for dy, dx in zip(*np.nonzero(tile == k))], axis=0)
                     for k in range(len(layout.channels))])


def residual_colour_shading(corrected: ArrayLike, reference_channel: int = 1,
                            layout: MosaicLayout | None = None) -> dict:
    """The shading a correction leaves: each channel and each colour ratio against its value at the centre.

    Parameters
    ----------
    corrected : array_like
        ``(N, H, W)`` corrected planes of a flat field; or, with ``layout`` a mosaic's, the corrected ``(H, W)`` raw
        mosaic, read one value per tile (:func:`tile_planes`).
    reference_channel : int
        The channel colour ratios are taken against (1: G of R, G, B).
    layout : MosaicLayout, optional
        The mosaic's tile, when ``corrected`` is a mosaic.

    Returns
    -------
    dict
        ``channel_ratio`` ``(N, H, W)`` (each channel over its centre level), ``colour_ratio`` ``(N, H, W)``
        ((channel / reference) over its centre value: R/G and B/G maps), ``max_channel_deviation`` and
        ``max_colour_deviation`` (N lists of max |ratio − 1|), ``corner_colour_ratio`` (N lists of the mean of the
        four corner pixels' colour ratios).

    References
    ----------
    .. [libcamera] see docs/references.md (ALSC's Cr, Cb: R and B against G).
    """
    if layout is not None and np.ndim(corrected) == 2:
        corrected = tile_planes(corrected, layout)
    p = _planes(corrected, "corrected")
    if not isinstance(reference_channel, int) or not 0 <= reference_channel < p.shape[0]:
        raise ConfigError("reference_channel", reference_channel, f"must be a channel index 0…{p.shape[0] - 1}")
    channel = p / np.array([_centre_level(c) for c in p])[:, None, None]
    colour = channel / channel[reference_channel]
    colour = colour / np.array([_centre_level(c) for c in colour])[:, None, None]
    corners = colour[:, [0, 0, -1, -1], [0, -1, 0, -1]].mean(axis=1)
    return {"channel_ratio": channel, "colour_ratio": colour,
            "max_channel_deviation": np.abs(channel - 1).max(axis=(1, 2)).tolist(),
            "max_colour_deviation": np.abs(colour - 1).max(axis=(1, 2)).tolist(),
            "corner_colour_ratio": corners.tolist()}


def luminance_and_colour_tables(tables: ShadingTables, reference_channel: int = 1) -> tuple:
    """libcamera's split of per-channel tables: a luminance table (the reference channel's gains, minimum 1) and the
    other channels' gains relative to it (Cr = R/G, Cb = B/G for R, G, B).

    Parameters
    ----------
    tables : ShadingTables
    reference_channel : int

    Returns
    -------
    tuple
        ``(luminance (rows, columns), colour (N, rows, columns))`` with colour[reference] ≡ 1.

    References
    ----------
    .. [libcamera] see docs/references.md.
    """
    g = tables.gains
    lum = g[reference_channel] / g[reference_channel].min()
    return lum, g / g[reference_channel]


@dataclass(frozen=True, eq=False)
class AlscTuning:
    """A Raspberry Pi tuning file's ``rpi.alsc`` block: tables ``(12, 16)``, colour tables by CCT (K)."""

    path: str
    luminance_lut: np.ndarray
    luminance_strength: float
    cr_by_cct: dict
    cb_by_cct: dict


def find_libcamera_tuning(sensor: str = "imx477") -> Path | None:
    """The installed Raspberry Pi tuning file of ``sensor`` (Debian's ``libcamera-ipa``), or None.

    Parameters
    ----------
    sensor : str
        The sensor's name as the file names it ("imx477": the Raspberry Pi HQ camera).

    Returns
    -------
    pathlib.Path or None

    References
    ----------
    .. [RPiTuning] see docs/references.md.
    """
    for d in LIBCAMERA_TUNING_DIRS:
        p = Path(d) / f"{sensor}.json"
        if p.is_file():
            return p
    return None


def _alsc_block(data, path) -> dict:
    if isinstance(data, dict) and isinstance(data.get("algorithms"), list):  # version 2.0
        for algo in data["algorithms"]:
            if isinstance(algo, dict) and "rpi.alsc" in algo:
                return algo["rpi.alsc"]
    elif isinstance(data, dict) and "rpi.alsc" in data:  # version 1.0
        return data["rpi.alsc"]
    raise SpectracamError(f"{path}: no rpi.alsc block (not a Raspberry Pi tuning file?)")


def _grid(values, path, what: str) -> np.ndarray:
    a = np.asarray(values, dtype=float) if isinstance(values, list) else np.array([])
    if a.size != ALSC_CELLS[0] * ALSC_CELLS[1] or not np.all(np.isfinite(a)) or np.any(a <= 0):
        raise SpectracamError(f"{path}: {what} must be {ALSC_CELLS[0] * ALSC_CELLS[1]} positive numbers, got "
                              f"{a.size}")
    return a.reshape(ALSC_CELLS)


def _by_cct(block: dict, key: str, path) -> dict:
    out = {}
    for entry in block.get(key, []):
        if not isinstance(entry, dict) or not isinstance(entry.get("ct"), (int, float)):
            raise SpectracamError(f"{path}: {key} entries must be {{\"ct\": K, \"table\": [...]}}")
        out[float(entry["ct"])] = _grid(entry.get("table"), path, f"{key} at {entry['ct']} K")
    return dict(sorted(out.items()))


def read_libcamera_alsc(path: str | Path) -> AlscTuning:
    """Read the ``rpi.alsc`` block of a Raspberry Pi (libcamera) tuning file.

    Parameters
    ----------
    path : str or pathlib.Path
        The JSON tuning file (e.g. :func:`find_libcamera_tuning`'s).

    Returns
    -------
    AlscTuning
        ``luminance_lut`` ``(12, 16)``, ``luminance_strength``, and ``cr_by_cct`` / ``cb_by_cct``: ``{K: (12, 16)}``.

    Raises
    ------
    SpectracamError
        One line, if the file is missing, not JSON, or its block is malformed.

    References
    ----------
    .. [RPiTuning] see docs/references.md.
    """
    p = Path(path)
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise SpectracamError(f"{p}: cannot read a tuning file ({type(e).__name__}: {e})") from None
    block = _alsc_block(data, p)
    strength = block.get("luminance_strength", 1.0)
    if not isinstance(strength, (int, float)) or not math.isfinite(strength):
        raise SpectracamError(f"{p}: rpi.alsc.luminance_strength must be a number, got {strength!r}")
    return AlscTuning(str(p), _grid(block.get("luminance_lut"), p, "rpi.alsc.luminance_lut"), float(strength),
                      _by_cct(block, "calibrations_Cr", p), _by_cct(block, "calibrations_Cb", p))


def table_figures(table: ArrayLike) -> dict:
    """Corner and centre figures of a 12 × 16 (or any) gain table.

    Parameters
    ----------
    table : array_like
        ``(rows, columns)`` gains.

    Returns
    -------
    dict
        ``centre`` (mean of the central 2×2 cells), ``corners`` (the four corner cells), ``corner_mean``,
        ``corner_over_centre`` (mean corner / centre), ``min``, ``max``.

    References
    ----------
    .. [RPiTuning] see docs/references.md.
    """
    t = np.asarray(table, dtype=float)
    r, c = t.shape
    centre = float(t[(r - 1) // 2:r // 2 + 1, (c - 1) // 2:c // 2 + 1].mean())
    corners = [float(t[0, 0]), float(t[0, -1]), float(t[-1, 0]), float(t[-1, -1])]
    return {"centre": centre, "corners": corners, "corner_mean": float(np.mean(corners)),
            "corner_over_centre": float(np.mean(corners)) / centre, "min": float(t.min()), "max": float(t.max())}


# -- the camera's own calibration and its correction (issue 37, item 4) ------------------------------------------------

#: Below this colour temperature a calibration light is Planckian, at and above it CIE daylight of that temperature:
#: the rule for the reference illuminants of CIE 13.3 (colour rendering), 5000 K.
DAYLIGHT_FROM_K = 5000.0
#: Gain maps already computed: key → (N, H, W) float32 (read-only).
_GAIN_CACHE: dict = {}
_GAIN_CACHE_SIZE = 4


def calibration_light(cct_K: float, white_luminance_cd_m2: float = 100.0) -> IlluminantSpec:
    """The flat field's light at a colour temperature: a blackbody below :data:`DAYLIGHT_FROM_K`, CIE daylight
    (the D series at that CCT, colour-science's ``sd_CIE_illuminant_D_series``) from it on.

    Parameters
    ----------
    cct_K : float
        Correlated colour temperature, K (1000–25000).
    white_luminance_cd_m2 : float
        Its level (a gain table does not depend on it).

    Returns
    -------
    spectracam.scene.illuminant.IlluminantSpec

    References
    ----------
    .. [CIE13.3] see docs/references.md (Planckian below 5000 K, daylight above, as reference illuminants).
    """
    from spectracam.scene.illuminant import IlluminantSpec

    if not isinstance(cct_K, (int, float)) or isinstance(cct_K, bool) or not 1000 <= cct_K <= 25000:
        raise ConfigError("cct_K", cct_K, "must be a colour temperature between 1000 and 25000 K")
    if cct_K < DAYLIGHT_FROM_K:
        return IlluminantSpec(kind="blackbody", temperature_K=float(cct_K), white_luminance_cd_m2=white_luminance_cd_m2)
    import colour

    xy = colour.temperature.CCT_to_xy_CIE_D(float(cct_K))   # a measured CCT, as libcamera's tuning states its lights
    sd = colour.sd_CIE_illuminant_D_series(xy)
    return IlluminantSpec(kind="measured", name=f"CIE daylight {cct_K:g} K", temperature_K=None,
                          wavelengths_nm=tuple(float(w) for w in sd.wavelengths),
                          values=tuple(max(float(v), 0.0) for v in sd.values), white_luminance_cd_m2=white_luminance_cd_m2)


def flat_field(camera: CameraSpec, grid: WavelengthGrid, shape: tuple[int, int],
               illuminant: IlluminantSpec) -> np.ndarray:
    """The camera's noise-free raw image of a perfect white diffuser filling the field, photo-electrons per second.

    Every pixel sees the same radiance E(λ)/π; what it records is that times the lens's relative illumination
    (:func:`spectracam.camera.capture.field_radiance`) through its own site's weights at its chief-ray angle
    (:func:`spectracam.camera.field.field_rates`: microlens, crosstalk, the filters' angle shifts).  The mean of many
    frames of a real calibration tends to it.

    Parameters
    ----------
    camera : CameraSpec
    grid : WavelengthGrid
    shape : tuple of int
        ``(H, W)`` pixels.
    illuminant : IlluminantSpec
        The flat field's light.

    Returns
    -------
    numpy.ndarray
        In the layout's shape, float64: a mosaic ``(H, W)``, planes ``(N, H, W)``.
    """
    from spectracam.architecture.base import MosaicLayout
    from spectracam.camera.capture import field_radiance
    from spectracam.camera.field import field_rates
    from spectracam.optics.field import field_maps
    from spectracam.scene.illuminant import white_diffuser_radiance

    h, w = shape
    white = white_diffuser_radiance(illuminant, grid).astype(np.float32)
    radiance = field_radiance(np.broadcast_to(white, (h, w, white.size)), camera)
    maps = None if camera.optics.on_axis else field_maps((h, w), camera.sensor.pixel_pitch_um, camera.optics,
                                                        camera.optics.f_number)
    rates = field_rates(np.ascontiguousarray(radiance, np.float32), grid, camera, maps).astype(np.float64)
    if isinstance(camera.architecture().layout, MosaicLayout):
        return rates.sum(axis=-1)
    return np.moveaxis(rates, -1, 0)


def _gain_key(camera, grid, shape, processing, cct_K) -> str:
    return json.dumps([camera.to_dict(), camera.pixel.to_dict(), list(map(float, grid.centres_nm)), list(shape),
                       processing.to_dict(), None if cct_K is None else round(float(cct_K), 3)], sort_keys=True,
                      default=str)


def shading_gain_maps(camera: CameraSpec, grid: WavelengthGrid, shape: tuple[int, int], processing: ProcessingSpec,
                      cct_K: float | None = None) -> np.ndarray:
    """The camera's lens-shading gains at every pixel, per channel: its tables calibrated on flat fields
    (:func:`flat_field`) under ``processing.shading_temperatures_K`` (:func:`calibration_light`), the one of the
    first (``"single"``) or the ones interpolated to ``cct_K`` (``"cct"``, :func:`interpolate_tables_by_cct`), each
    interpolated bilinearly to ``shape``.

    Parameters
    ----------
    camera : CameraSpec
    grid : WavelengthGrid
    shape : tuple of int
    processing : ProcessingSpec
        ``shading`` (not "none"), ``shading_temperatures_K``, ``shading_grid``, ``shading_method``, ``demosaic``.
    cct_K : float, optional
        The light's colour temperature (needed by ``"cct"``).

    Returns
    -------
    numpy.ndarray
        ``(N, H, W)`` float32 gains (read-only; memoised).
    """
    spec = processing.shading_spec()
    if spec.correction == "none":
        raise ConfigError("processing.shading", "none", "names no correction: there are no gains to compute")
    if spec.correction == "cct" and cct_K is None:
        raise ConfigError("cct_K", None, "processing.shading = 'cct' needs the light's colour temperature")
    key = _gain_key(camera, grid, shape, processing, cct_K if spec.correction == "cct" else None)
    if key not in _GAIN_CACHE:
        temps = spec.calibration_temperatures_K if spec.correction == "cct" else spec.calibration_temperatures_K[:1]
        layout = camera.architecture().layout
        tables = {t: calibrate_gain_tables(flat_field(camera, grid, shape, calibration_light(t)), spec, layout)
                  for t in temps}
        chosen = interpolate_tables_by_cct(tables, float(cct_K)) if spec.correction == "cct" else tables[temps[0]]
        gains = interpolate_table(chosen.gains, shape, chosen.placement).astype(np.float32)
        gains.setflags(write=False)
        if len(_GAIN_CACHE) >= _GAIN_CACHE_SIZE:
            _GAIN_CACHE.pop(next(iter(_GAIN_CACHE)))
        _GAIN_CACHE[key] = gains
    return _GAIN_CACHE[key]


def correct_shading(electrons: np.ndarray, layout: MosaicLayout | PlanesLayout, gains: np.ndarray) -> np.ndarray:
    """Raw electrons times their channel's gain, in place: a mosaic ``(H, W)`` pixel by pixel with its own channel's
    gain (before demosaicking, as an ISP's lens-shading block does), planes ``(N, H, W)`` plane by plane.

    Parameters
    ----------
    electrons : numpy.ndarray
        The recorded, dark-subtracted electrons in the layout's shape.
    layout : MosaicLayout or PlanesLayout
    gains : numpy.ndarray
        ``(N, H, W)`` (:func:`shading_gain_maps`).

    Returns
    -------
    numpy.ndarray
        ``electrons``, corrected.
    """
    from spectracam.architecture.base import MosaicLayout

    if isinstance(layout, MosaicLayout):
        channel = layout.channel_index(electrons.shape)
        electrons *= np.take_along_axis(gains, channel[None], axis=0)[0]
    else:
        electrons *= gains
    return electrons
