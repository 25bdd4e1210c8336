"""The planar Macbeth ColorChecker: measured reflectances, geometry, and per-patch pixel masks.

Geometry is in millimetres on the chart plane, origin at the board centre, x to the right, y up.
Patches are numbered 0..23 in the standard reading order, row by row from the top-left
("dark skin") to the bottom-right ("black").
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from spectracam.core.spec import Spec
from spectracam.core.spectra import Spectrum, tabulated

__all__ = ["DATASETS", "WHITE_PATCH", "ChartSpec", "View", "dataset_range_nm", "patch_boxes",
           "patch_coverage", "patch_masks", "patch_means", "patch_names_and_data", "patch_rectangles_mm",
           "patch_reflectances"]

ROWS, COLUMNS = 4, 6

#: Reflectance datasets colour-science ships for the ColorChecker Classic (24 patches, standard order).
DATASETS = ("BabelColor Average", "ColorChecker N Ohta")
#: Index of the white patch ("white 9.5 (.05 D)") in the standard ColorChecker order: metering
#: (paper 4.5) and the DNG's neutral use it.
WHITE_PATCH = 18


@dataclass(frozen=True)
class ChartSpec(Spec):
    """What the scene file's ``[chart]`` table describes."""

    TABLE = "chart"

    dataset: str = "BabelColor Average"
    #: Defaults approximate the X-Rite ColorChecker Classic (279 × 216 mm board).
    patch_size_mm: float = 38.0
    gap_mm: float = 6.0
    border_mm: float = 12.0
    #: Reflectance of the board and of everything outside it: the Classic's black frame is ~4 %.
    surround_reflectance: float = 0.04
    #: Fraction of the patch side trimmed from each edge before a pixel counts as the patch's own.
    mask_margin: float = 0.15

    def validate(self) -> None:
        self.choice("dataset", DATASETS)
        self.number("patch_size_mm", 0, lo_open=True, unit="mm")
        self.number("gap_mm", 0, unit="mm")
        self.number("border_mm", 0, unit="mm")
        self.number("surround_reflectance", 0, 1)
        self.number("mask_margin", 0, 0.45)

    @property
    def board_size_mm(self) -> tuple[float, float]:
        w = COLUMNS * self.patch_size_mm + (COLUMNS - 1) * self.gap_mm + 2 * self.border_mm
        h = ROWS * self.patch_size_mm + (ROWS - 1) * self.gap_mm + 2 * self.border_mm
        return w, h


def patch_names_and_data(dataset: str) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """``[(name, wavelengths_nm, reflectance)]`` for the 24 patches, from colour-science.

    Parameters
    ----------
    dataset : str
        A key of colour-science's ``SDS_COLOURCHECKERS``.

    Returns
    -------
    list of (str, ndarray, ndarray)
        Each patch's name, its measured wavelengths (nm) and reflectances (0…1), in the standard order.
    """
    from spectracam.core import colour_data

    out = colour_data.sd_set(f"colourchecker/{dataset}")
    if len(out) != ROWS * COLUMNS:
        raise ValueError(f"dataset {dataset!r} has {len(out)} patches, expected 24")
    return out


def dataset_range_nm(dataset: str) -> tuple[float, float]:
    """The wavelengths a chart dataset's reflectances are measured over.

    Parameters
    ----------
    dataset : str
        A key of colour-science's ``SDS_COLOURCHECKERS``.

    Returns
    -------
    tuple of float
        The first patch's first and last measured wavelength, nm.
    """
    wl = patch_names_and_data(dataset)[0][1]
    return float(wl[0]), float(wl[-1])


def patch_reflectances(chart: ChartSpec) -> list[tuple[str, Spectrum]]:
    """The 24 reflectance spectra, piecewise-linear between the measured samples.

    Parameters
    ----------
    chart : ChartSpec
        The chart (its ``dataset``).

    Returns
    -------
    list of (str, Spectrum)
        Each patch's name and its reflectance as a function of wavelength in nm (zero outside the data).
    """
    return [(n, tabulated(wl, r)) for n, wl, r in patch_names_and_data(chart.dataset)]


def patch_rectangles_mm(chart: ChartSpec) -> np.ndarray:
    """``(24, 4)`` rectangles ``x0, x1, y0, y1`` (mm, chart plane), standard patch order.

    Parameters
    ----------
    chart : ChartSpec
        The chart's geometry (patch size, gap, border, mm), centred on the origin, y up.

    Returns
    -------
    ndarray
        ``(24, 4)`` float64, mm.
    """
    bw, bh = chart.board_size_mm
    pitch = chart.patch_size_mm + chart.gap_mm
    rects = []
    for r in range(ROWS):
        for c in range(COLUMNS):
            x0 = -bw / 2 + chart.border_mm + c * pitch
            y1 = bh / 2 - chart.border_mm - r * pitch
            rects.append((x0, x0 + chart.patch_size_mm, y1 - chart.patch_size_mm, y1))
    return np.array(rects)


@dataclass(frozen=True)
class View:
    """The region of the chart plane that the image shows: square pixels, board fitted and centred."""

    width_px: int
    height_px: int
    pixel_mm: float

    @classmethod
    def fit(cls, chart: ChartSpec, width_px: int, height_px: int) -> "View":
        """The view of an image of ``width_px`` × ``height_px`` pixels with the whole board fitted in it.

        Parameters
        ----------
        chart : ChartSpec
            The chart (its board size, mm).
        width_px, height_px : int
            The image's size, pixels.

        Returns
        -------
        View
            Square pixels of ``max(board width / width_px, board height / height_px)`` mm: the board fills the
            image along its tighter axis.
        """
        bw, bh = chart.board_size_mm
        return cls(width_px, height_px, max(bw / width_px, bh / height_px))

    @property
    def size_mm(self) -> tuple[float, float]:
        return self.width_px * self.pixel_mm, self.height_px * self.pixel_mm

    def pixel_edges_mm(self) -> tuple[np.ndarray, np.ndarray]:
        """Column edges (x, left to right) and row edges (y, top to bottom) of the pixel grid."""
        w, h = self.size_mm
        x = -w / 2 + self.pixel_mm * np.arange(self.width_px + 1)
        y = h / 2 - self.pixel_mm * np.arange(self.height_px + 1)
        return x, y


def _overlap(edges_lo: np.ndarray, edges_hi: np.ndarray, a: float, b: float) -> np.ndarray:
    return np.clip(np.minimum(edges_hi, b) - np.maximum(edges_lo, a), 0.0, None)


def patch_coverage(chart: ChartSpec, view: View) -> tuple[np.ndarray, np.ndarray]:
    """Separable pixel-area coverage of each patch: ``cy (24, H)`` and ``cx (24, W)``, each in [0, 1].

    The fraction of pixel (i, j) covered by patch p is ``cy[p, i] * cx[p, j]`` (axis-aligned
    rectangles), which is also the expected value of a box-filtered Monte Carlo render.

    Parameters
    ----------
    chart : ChartSpec
        The chart's geometry.
    view : View
        The pixels on the chart plane.

    Returns
    -------
    cy, cx : ndarray
        ``(24, H)`` and ``(24, W)`` float64 fractions of each row's and column's pixel extent inside each patch.
    """
    xe, ye = view.pixel_edges_mm()
    rects = patch_rectangles_mm(chart)
    cx = np.stack([_overlap(xe[:-1], xe[1:], x0, x1) for x0, x1, _, _ in rects]) / view.pixel_mm
    # rows run top to bottom: pixel i spans [ye[i+1], ye[i]]
    cy = np.stack([_overlap(ye[1:], ye[:-1], y0, y1) for _, _, y0, y1 in rects]) / view.pixel_mm
    return cy, cx


def patch_boxes(chart: ChartSpec, width_px: int, height_px: int) -> list[tuple[slice, slice]]:
    """``(rows, cols)`` slices of the pixels lying wholly inside each patch shrunk by ``mask_margin``.

    Later stages score patches on these pixels only, away from edges where pixels mix materials.
    Slices are views: a patch statistic never copies the image.

    Parameters
    ----------
    chart : ChartSpec
        The chart (its geometry and ``mask_margin``, a fraction of the patch side).
    width_px, height_px : int
        The image's size, pixels.

    Returns
    -------
    list of (slice, slice)
        24 ``(rows, cols)`` slices in the standard patch order; an empty pair where no pixel fits.
    """
    view = View.fit(chart, width_px, height_px)
    xe, ye = view.pixel_edges_mm()
    inset = chart.mask_margin * chart.patch_size_mm
    boxes = []
    for x0, x1, y0, y1 in patch_rectangles_mm(chart):
        cols = np.flatnonzero((xe[:-1] >= x0 + inset) & (xe[1:] <= x1 - inset))
        rows = np.flatnonzero((ye[1:] >= y0 + inset) & (ye[:-1] <= y1 - inset))
        if rows.size == 0 or cols.size == 0:
            boxes.append((slice(0, 0), slice(0, 0)))
        else:
            boxes.append((slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1)))
    return boxes


def patch_masks(chart: ChartSpec, width_px: int, height_px: int) -> np.ndarray:
    """``(24, H, W)`` boolean masks of the pixels of :func:`patch_boxes`.

    Parameters
    ----------
    chart : ChartSpec
        The chart.
    width_px, height_px : int
        The image's size, pixels.

    Returns
    -------
    ndarray
        ``(24, height_px, width_px)`` bool, True on each patch's scored pixels.
    """
    masks = np.zeros((ROWS * COLUMNS, height_px, width_px), dtype=bool)
    for p, box in enumerate(patch_boxes(chart, width_px, height_px)):
        masks[(p, *box)] = True
    return masks


def patch_means(image: np.ndarray, boxes: list[tuple[slice, slice]]) -> np.ndarray:
    """``(24, ...)`` float64 mean of each patch's pixels of an ``(H, W, ...)`` image.

    Parameters
    ----------
    image : ndarray
        ``(H, W, ...)``, any trailing axes (bands, channels).
    boxes : list of (slice, slice)
        The patches' pixels (:func:`patch_boxes`).

    Returns
    -------
    ndarray
        ``(len(boxes), ...)`` float64 means, in the image's unit.
    """
    return np.stack([image[r, c].mean(axis=(0, 1), dtype=np.float64) for r, c in boxes])
