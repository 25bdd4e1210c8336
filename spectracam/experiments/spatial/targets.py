"""Spatial targets: geometry in millimetres with measured spectral reflectances.

Each target is a set of *materials* (a name and a reflectance spectrum) laid out in the world of
:mod:`spectracam.experiments.spatial.geometry` (the object plane ``z = 0``, x right, y up, the camera on ``+z``),
and says, for a camera, which fraction of every (sub-)pixel's footprint each material covers
(:meth:`Target.coverage`, the closed form the analytic renderer uses) and which Mitsuba shapes make
it (:meth:`Target.mitsuba_shapes`). Every surface is Lambertian and lit along its normal, so a
material of reflectance ``S`` has radiance ``E·S/π`` seen from anywhere.

* :class:`SlantedEdge` — ISO 12233:2017 slanted edge: a straight edge about 5° from the vertical
  between two of the ColorChecker's neutral patches, ``neutral 6.5 (.44 D)`` and
  ``neutral 3.5 (1.05 D)``: measured reflectances 0.352 and 0.088 (400–700 nm means), a 4.0:1 contrast
  (the standard's 4:1). Closed form: the exact area of each pixel on the bright side.
* :class:`SiemensStar` — a binary Siemens star of ``cycles`` bright/dark sector pairs, the same two
  neutrals, on the bright neutral. Closed form: coverage by ``oversampling²`` points per sub-pixel.
* :class:`ColouredEdge` — the same slanted edge between two chromatic ColorChecker patches (red/cyan,
  blue/yellow, dark/light skin, foliage/blue sky): the verdict on demosaicking with colour contrast,
  where one channel may see almost no step.
* :class:`ZonePlate` — a circular zone plate ``w = ½ + ½ cos(π k r²)`` blending two materials (the two
  neutrals: luminance; magenta and cyan, L* 51.0 and 51.8: chroma), whose local frequency ``k·r`` rises
  linearly to ``max_frequency_cy_per_px`` at ``radius_px`` (the Nyquist frequency at half the radius):
  everything beyond is aliased by a sensor without a low-pass filter. Closed form: the blend weight at
  ``oversampling²`` points per sub-pixel; Mitsuba: a ``blendbsdf`` weighted by a bitmap of ``w``.
* :class:`TiltedChart` — the ColorChecker (:mod:`spectracam.scene.chart` geometry and reflectances) turned
  by ``tilt_deg`` about the vertical axis through its centre: perspective, and defocus across the
  field with a thin lens. Closed form: pinhole projection (no defocus) by ray–plane intersection, ``oversampling²`` rays per sub-pixel.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from spectracam.scene.chart import ChartSpec, patch_names_and_data, patch_rectangles_mm
from spectracam.core.spectra import tabulated
from spectracam.experiments.spatial.geometry import CameraGeometry

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence
    from types import ModuleType

    from numpy.typing import ArrayLike

__all__ = ["LIFT_MM", "ColouredEdge", "SiemensStar", "SlantedEdge", "Target", "TiltedChart", "ZonePlate",
           "neutral_materials", "object_points", "oversampled_mean", "patch_materials"]

#: The ColorChecker patches of the edge and the star: 0.352 / 0.088 mean reflectance, 4.0:1 (ISO 12233:2017).
BRIGHT_NEUTRAL, DARK_NEUTRAL = "neutral 6.5 (.44 D)", "neutral 3.5 (1.05 D)"
#: Height of a patch above its board along the normal, mm (as the flat chart's renderer).
LIFT_MM = 0.01


def neutral_materials(dataset: str = "BabelColor Average") -> list:
    """``[(name, reflectance)]`` of :data:`DARK_NEUTRAL` and :data:`BRIGHT_NEUTRAL`, in that order.

    Parameters
    ----------
    dataset : str
        The ColorChecker reflectance data set (:func:`spectracam.scene.chart.patch_names_and_data`).

    Returns
    -------
    list of (str, callable)
        Each patch's name and its reflectance as a function of wavelength, nm.
    """
    return patch_materials((DARK_NEUTRAL, BRIGHT_NEUTRAL), dataset)


def patch_materials(names: Sequence[str], dataset: str = "BabelColor Average") -> list:
    """``[(name, reflectance)]`` of the named ColorChecker patches, in that order.

    Parameters
    ----------
    names : sequence of str
        ColorChecker patch names, e.g. ``"red"``.
    dataset : str
        The ColorChecker reflectance data set (:func:`spectracam.scene.chart.patch_names_and_data`).

    Returns
    -------
    list of (str, callable)
        Each patch's name and its reflectance as a function of wavelength, nm.

    Raises
    ------
    ValueError
        For a name that is no patch of the data set.
    """
    data = {n: (wl, r) for n, wl, r in patch_names_and_data(dataset)}
    missing = [n for n in names if n not in data]
    if missing:
        raise ValueError(f"no ColorChecker patch named {missing[0]!r}; the patches are " + ", ".join(map(repr, data)))
    return [(n, tabulated(*data[n])) for n in names]


def object_points(geometry: CameraGeometry, supersampling: int, oversampling: int) -> tuple[np.ndarray, np.ndarray]:
    """Object-plane coordinates X (cols), Y (rows) of ``oversampling²`` points in every sub-pixel, mm:
    arrays ``(Ws, os)`` and ``(Hs, os)`` → broadcast by the caller. Pinhole projection onto z = 0.

    Parameters
    ----------
    geometry : CameraGeometry
        The sensor's pixels and the magnification.
    supersampling : int
        Sub-pixels per pixel along each axis.
    oversampling : int
        Points per sub-pixel along each axis (``os``).

    Returns
    -------
    X : ndarray, shape (Ws, os)
        x of the points of every sub-pixel column, mm.
    Y : ndarray, shape (Hs, os)
        y of the points of every sub-pixel row, mm (y up, top row first).
    """
    k = geometry.object_distance_mm / geometry.image_distance_mm
    s = geometry.pixel_pitch_mm / supersampling
    u, w = geometry.pixel_centres_mm(supersampling)
    off = ((np.arange(oversampling) + 0.5) / oversampling - 0.5) * s
    return (u[:, None] + off[None, :]) * k, (w[:, None] - off[None, :]) * k  # (Ws, os), (Hs, os)


def oversampled_mean(fn: Callable[[np.ndarray, np.ndarray], np.ndarray], X: np.ndarray, Y: np.ndarray,
                     oversampling: int) -> np.ndarray:
    """``(Hs, Ws)`` float64 mean of ``fn(x, y)`` over the ``oversampling²`` points of every sub-pixel
    (:func:`object_points`' X and Y, in the units ``fn`` takes).

    Parameters
    ----------
    fn : callable
        ``fn(x (1, Ws), y (Hs, 1))`` → ``(Hs, Ws)`` values at the points.
    X : ndarray, shape (Ws, os)
        The points' x.
    Y : ndarray, shape (Hs, os)
        The points' y.
    oversampling : int
        ``os``, points per sub-pixel along each axis.

    Returns
    -------
    ndarray, shape (Hs, Ws)
        The mean over each sub-pixel's points.
    """
    acc = np.zeros((Y.shape[0], X.shape[0]), np.float64)
    for i in range(oversampling):
        for j in range(oversampling):
            acc += fn(X[None, :, j], Y[:, i, None])
    acc /= oversampling**2
    return acc


class Target:
    """A target: materials, their coverage of every sub-pixel, and its Mitsuba shapes."""

    name = ""
    #: Does the target hold only neutral materials (so any chroma at its edges is false colour)?
    neutral = True

    def materials(self) -> list:
        """``[(name, reflectance spectrum)]``."""
        raise NotImplementedError

    def coverage(self, geometry: CameraGeometry, supersampling: int) -> np.ndarray:
        """``(n_materials, Hs, Ws)`` fraction of each sub-pixel's footprint covered by each material.

        Parameters
        ----------
        geometry : CameraGeometry
            The camera's view of the target.
        supersampling : int
            Sub-pixels per pixel along each axis.

        Returns
        -------
        ndarray, shape (n_materials, Hs, Ws)
            Fractions 0 to 1, in the order of :meth:`materials`; they sum to 1 in every sub-pixel.
        """
        raise NotImplementedError

    def mitsuba_shapes(self, mi: ModuleType, geometry: CameraGeometry) -> list:
        """``[(key, shape, material index)]``: a shape is a Mitsuba shape dict, or a triangle mesh
        ``(vertices (n, 3) float32, faces (m, 3) uint32)``; the renderer gives each its BSDF.

        Parameters
        ----------
        mi : ModuleType
            Mitsuba, its variant set.
        geometry : CameraGeometry
            The camera's view of the target (the shapes cover its field of view), world units mm.

        Returns
        -------
        list of (str, dict or tuple, int or tuple)
            Each shape's key, the shape, and the index of its material in :meth:`materials` (a blend:
            ``(material 0, material 1, weight bitmap)``).
        """
        raise NotImplementedError

    def light_direction(self) -> list:
        """Direction the light travels (towards the target), along the target's normal."""
        return [0.0, 0.0, -1.0]

    def region(self, geometry: CameraGeometry) -> np.ndarray:
        """``(H, W)`` boolean: the pixels the target's scores average over.

        Parameters
        ----------
        geometry : CameraGeometry
            The camera's view of the target.

        Returns
        -------
        ndarray of bool, shape (H, W)
            Here every pixel.
        """
        return np.ones((geometry.height_px, geometry.width_px), bool)

    def to_dict(self) -> dict:
        return {"type": self.name, **{k: v for k, v in vars(self).items() if not k.startswith("_")}}


@dataclass
class SlantedEdge(Target):
    """A straight edge ``angle_deg`` from the vertical through the object point ``(x0_px, 0)`` (in object
    pixels from the centre), dark on the left, bright on the right; its column grows with the row."""

    angle_deg: float = 5.0
    x0_px: float = 0.3
    dataset: str = "BabelColor Average"
    name = "edge"

    def materials(self) -> list:
        return neutral_materials(self.dataset)

    def _line(self, geometry):
        t = math.tan(math.radians(self.angle_deg))
        return self.x0_px * geometry.object_pixel_mm, t   # edge: x = x0 - t·y (y up, so x grows down the image)

    def coverage(self, geometry: CameraGeometry, supersampling: int) -> np.ndarray:
        x0, t = self._line(geometry)
        k = geometry.object_distance_mm / geometry.image_distance_mm
        s = geometry.pixel_pitch_mm / supersampling * k
        u, w = geometry.pixel_centres_mm(supersampling)
        xb = (u * k + s / 2)[None, :]
        ya, yb = (w * k - s / 2)[:, None], (w * k + s / 2)[:, None]
        width = s

        def G(z):  # antiderivative of clip(z, 0, width)
            z = np.asarray(z, float)
            return np.where(z <= 0, 0.0, np.where(z <= width, 0.5 * z**2, 0.5 * width**2 + width * (z - width)))

        if abs(t) < 1e-12:
            bright = np.clip(xb - x0, 0, width) / width * np.ones_like(ya)
        else:  # bright width at height y: clip(xb - (x0 - t y), 0, w), linear in y with slope t
            bright = (G(xb - x0 + t * yb) - G(xb - x0 + t * ya)) / (t * s * width)
        bright = np.clip(bright, 0.0, 1.0)
        return np.stack([1.0 - bright, bright])

    def mitsuba_shapes(self, mi: ModuleType, geometry: CameraGeometry) -> list:
        T = mi.ScalarTransform4f
        fw, fh = geometry.field_of_view_mm
        big = 4.0 * max(fw, fh)
        x0, _ = self._line(geometry)
        # the bright half-plane: a big rectangle whose left side is the edge, turned about the edge's point (x0, 0)
        bright = T().translate([x0, 0.0, LIFT_MM]) @ T().rotate([0, 0, 1], self.angle_deg) \
            @ T().translate([big / 2, 0.0, 0.0]) @ T().scale([big / 2, big / 2, 1])
        return [("dark", {"type": "rectangle", "to_world": T().scale([big, big, 1])}, 0),
                ("bright", {"type": "rectangle", "to_world": bright}, 1)]


@dataclass
class ColouredEdge(SlantedEdge):
    """:class:`SlantedEdge` between two ColorChecker patches: ``patches[0]`` on the left, ``patches[1]`` on
    the right (for the e-SFR the polarity does not matter: each channel's step is taken as it comes)."""

    patches: tuple = ("red", "cyan")
    name = "coloured edge"
    neutral = False

    def materials(self) -> list:
        return patch_materials(self.patches, self.dataset)


@dataclass
class ZonePlate(Target):
    """A circular zone plate centred on the optical axis: material 1 with weight
    ``w(r) = ½ + ½ cos(π k r²)``, material 0 with ``1 - w``, ``r`` in object pixels, ``k =
    max_frequency_cy_per_px / radius_px`` so the local frequency ``k·r`` reaches ``max_frequency_cy_per_px``
    at ``radius_px``; scored inside ``radius_px``."""

    patches: tuple = (DARK_NEUTRAL, BRIGHT_NEUTRAL)
    radius_px: float = 64.0
    max_frequency_cy_per_px: float = 1.0
    oversampling: int = 4
    #: Bitmap texels per object pixel for Mitsuba's blend weight: 16 samples per cycle at 1 cy/px, where
    #: bilinear interpolation of the cosine is within 0.5 % of its amplitude.
    texels_per_px: int = 16
    dataset: str = "BabelColor Average"
    name = "zone plate"

    @property
    def neutral(self):
        return set(self.patches) <= {DARK_NEUTRAL, BRIGHT_NEUTRAL, "white 9.5 (.05 D)", "neutral 8 (.23 D)",
                                     "neutral 5 (.70 D)", "black 2 (1.5 D)"}

    def materials(self) -> list:
        return patch_materials(self.patches, self.dataset)

    def weight(self, x_px: ArrayLike, y_px: ArrayLike) -> np.ndarray:
        """Blend weight of material 1 at object-plane points (object pixels from the centre).

        Parameters
        ----------
        x_px, y_px : array_like
            The points' coordinates, object pixels from the centre (broadcast together).

        Returns
        -------
        ndarray
            ``w = ½ + ½ cos(π k r²)``, 0 to 1.
        """
        k = self.max_frequency_cy_per_px / self.radius_px
        return 0.5 + 0.5 * np.cos(np.pi * k * (np.square(x_px) + np.square(y_px)))

    def coverage(self, geometry: CameraGeometry, supersampling: int) -> np.ndarray:
        X, Y = object_points(geometry, supersampling, self.oversampling)
        w = oversampled_mean(self.weight, X / geometry.object_pixel_mm, Y / geometry.object_pixel_mm, self.oversampling)
        return np.stack([1.0 - w, w])

    def weight_bitmap(self, geometry: CameraGeometry) -> tuple[np.ndarray, float]:
        """``(n, n)`` float32 blend weights at the texel centres of a square 1.1 × the field of view's larger
        side, row 0 at the top (+y) — what :meth:`mitsuba_shapes`' rectangle shows (a bitmap's first row is its
        top).

        Parameters
        ----------
        geometry : CameraGeometry
            Its field of view and object pixel, mm.

        Returns
        -------
        weights : ndarray, shape (n, n)
            float32, :attr:`texels_per_px` texels per object pixel over a square 1.1 × the larger side of
            the field of view.
        half_mm : float
            Half the square's side, mm.
        """
        fw, fh = geometry.field_of_view_mm
        half_px = 0.5 * 1.1 * max(fw, fh) / geometry.object_pixel_mm
        n = int(np.ceil(2 * half_px * self.texels_per_px))
        c = (np.arange(n) + 0.5) / n * 2 * half_px - half_px
        return self.weight(c[None, :], -c[:, None]).astype(np.float32), half_px * geometry.object_pixel_mm

    def mitsuba_shapes(self, mi: ModuleType, geometry: CameraGeometry) -> list:
        weights, half_mm = self.weight_bitmap(geometry)
        rect = {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale([half_mm, half_mm, 1])}
        return [("plate", rect, (0, 1, weights))]

    def region(self, geometry: CameraGeometry) -> np.ndarray:
        u, w = geometry.pixel_centres_mm()
        k = geometry.object_distance_mm / geometry.image_distance_mm / geometry.object_pixel_mm
        return (u[None, :] * k) ** 2 + (w[:, None] * k) ** 2 <= self.radius_px ** 2

    def nyquist_radius_px(self, frequency_cy_per_px: float = 0.5) -> float:
        """Radius (object pixels) where the local frequency is ``frequency_cy_per_px``.

        Parameters
        ----------
        frequency_cy_per_px : float
            cycles per object pixel (0.5: the sensor's Nyquist frequency).

        Returns
        -------
        float
            Object pixels from the centre.
        """
        return frequency_cy_per_px / self.max_frequency_cy_per_px * self.radius_px


@dataclass
class SiemensStar(Target):
    """A binary Siemens star: ``cycles`` dark sectors alternating with bright ones, radius ``radius_px``
    object pixels, on the bright material; the first dark sector starts at angle 0 (the +x axis)."""

    cycles: int = 36
    radius_px: float = 120.0
    oversampling: int = 4
    arc_segments: int = 16
    dataset: str = "BabelColor Average"
    name = "star"

    def materials(self) -> list:
        return neutral_materials(self.dataset)

    def _dark(self, x, y, radius):
        phi = np.mod(np.arctan2(y, x), 2 * np.pi)
        sector = np.floor(phi / (np.pi / self.cycles)).astype(np.int64)
        return (sector % 2 == 0) & (x * x + y * y <= radius * radius)

    def coverage(self, geometry: CameraGeometry, supersampling: int) -> np.ndarray:
        X, Y = object_points(geometry, supersampling, self.oversampling)
        R = self.radius_px * geometry.object_pixel_mm
        dark = oversampled_mean(lambda x, y: self._dark(x, y, R), X, Y, self.oversampling)
        return np.stack([dark, 1.0 - dark])

    def mitsuba_shapes(self, mi: ModuleType, geometry: CameraGeometry) -> list:
        T = mi.ScalarTransform4f
        fw, fh = geometry.field_of_view_mm
        R = self.radius_px * geometry.object_pixel_mm
        n, m = self.cycles, self.arc_segments
        verts, faces = [[0.0, 0.0, LIFT_MM]], []
        for c in range(n):                   # dark sector c spans [2c, 2c+1]·π/n
            a0 = 2 * c * np.pi / n
            first = len(verts)
            for j in range(m + 1):
                a = a0 + (np.pi / n) * j / m
                verts.append([R * math.cos(a), R * math.sin(a), LIFT_MM])
            faces += [[0, first + j, first + j + 1] for j in range(m)]
        mesh = (np.asarray(verts, np.float32), np.asarray(faces, np.uint32))
        big = 4.0 * max(fw, fh)
        return [("background", {"type": "rectangle", "to_world": T().scale([big, big, 1])}, 1), ("star", mesh, 0)]

    def region(self, geometry: CameraGeometry) -> np.ndarray:
        u, w = geometry.pixel_centres_mm()
        k = geometry.object_distance_mm / geometry.image_distance_mm
        R = self.radius_px * geometry.object_pixel_mm
        return (u[None, :] * k) ** 2 + (w[:, None] * k) ** 2 <= (0.95 * R) ** 2


@dataclass
class TiltedChart(Target):
    """The ColorChecker of ``chart`` turned by ``tilt_deg`` about the vertical axis through its centre
    (the right side away from the camera); the board's surround reflectance everywhere else on its plane."""

    tilt_deg: float = 40.0
    chart: ChartSpec = ChartSpec()
    oversampling: int = 4
    name = "chart"
    neutral = False

    def to_dict(self) -> dict:
        return {"type": self.name, "tilt_deg": self.tilt_deg, "chart": self.chart.to_dict(),
                "oversampling": self.oversampling}

    def materials(self) -> list:
        const = self.chart.surround_reflectance
        return [(n, tabulated(wl, r)) for n, wl, r in patch_names_and_data(self.chart.dataset)] + \
            [("surround", lambda lam: np.full(np.shape(lam), const))]

    @property
    def _axes(self):
        a = math.radians(self.tilt_deg)
        return np.array([math.cos(a), 0.0, -math.sin(a)]), np.array([math.sin(a), 0.0, math.cos(a)])  # e_x, normal

    def chart_coordinates(self, geometry: CameraGeometry, u: ArrayLike,
                          w: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Chart-plane coordinates (mm) and distance along the optical axis (mm) of the points seen at
        sensor positions ``(u, w)`` mm (broadcast): ray from the lens centre through the object-plane point.

        Parameters
        ----------
        geometry : CameraGeometry
            The object and image distances, mm.
        u, w : array_like
            Sensor positions, mm from the optical axis (u right, w up).

        Returns
        -------
        xc, yc : ndarray
            The points' coordinates on the chart, mm from its centre.
        depth : ndarray
            Their distance from the lens along the optical axis, mm.
        """
        ex, n = self._axes
        k = geometry.object_distance_mm / geometry.image_distance_mm
        d = geometry.object_distance_mm
        Dx, Dy, Dz = np.asarray(u) * k, np.asarray(w) * k, -d
        t = -(n[2] * d) / (n[0] * Dx + n[2] * Dz)   # C = (0, 0, d); plane n·X = 0
        X, Y, Z = t * Dx, t * Dy, d + t * Dz
        return X * ex[0] + Z * ex[2], Y, d - Z

    def _material_at(self, xc, yc):
        """Material index (0–23 a patch, 24 the surround) at chart coordinates: the patches lie on a
        regular grid, so the lookup is arithmetic."""
        from spectracam.scene.chart import COLUMNS, ROWS

        ch = self.chart
        bw, bh = ch.board_size_mm
        pitch = ch.patch_size_mm + ch.gap_mm
        u = (np.asarray(xc) - (-bw / 2 + ch.border_mm)) / pitch
        v = ((bh / 2 - ch.border_mm) - np.asarray(yc)) / pitch
        c, r = np.floor(u), np.floor(v)
        inside = ((u - c) * pitch < ch.patch_size_mm) & ((v - r) * pitch < ch.patch_size_mm) \
            & (c >= 0) & (c < COLUMNS) & (r >= 0) & (r < ROWS)
        return np.where(inside, r * COLUMNS + c, ROWS * COLUMNS).astype(np.int64)

    def coverage(self, geometry: CameraGeometry, supersampling: int) -> np.ndarray:
        s = geometry.pixel_pitch_mm / supersampling
        u, w = geometry.pixel_centres_mm(supersampling)
        o = self.oversampling
        off = ((np.arange(o) + 0.5) / o - 0.5) * s
        n = w.size * u.size
        pix = np.arange(n).reshape(w.size, u.size)
        counts = np.zeros(25 * n)
        for i in range(o):
            xc, yc, _ = self.chart_coordinates(geometry, u[None, None, :] + off[:, None, None], w[None, :, None] - off[i])
            idx = self._material_at(xc, yc) * n + pix[None]
            counts += np.bincount(idx.ravel(), minlength=25 * n)
        return (counts / o**2).reshape(25, w.size, u.size).astype(np.float32)

    def mitsuba_shapes(self, mi: ModuleType, geometry: CameraGeometry) -> list:
        T = mi.ScalarTransform4f
        fw, fh = geometry.field_of_view_mm
        big = 4.0 * max(fw, fh, *self.chart.board_size_mm)
        turn = T().rotate([0, 1, 0], self.tilt_deg)
        shapes = [("board", {"type": "rectangle", "to_world": turn @ T().scale([big, big, 1])}, 24)]
        for p, (x0, x1, y0, y1) in enumerate(patch_rectangles_mm(self.chart)):
            shapes.append((f"patch{p:02d}", {"type": "rectangle", "to_world": turn @ T().translate(
                [(x0 + x1) / 2, (y0 + y1) / 2, LIFT_MM]) @ T().scale([(x1 - x0) / 2, (y1 - y0) / 2, 1])}, p))
        return shapes

    def light_direction(self) -> list:
        return (-self._axes[1]).tolist()

    def patch_masks(self, geometry: CameraGeometry) -> np.ndarray:
        """``(24, H, W)``: pixels whose four corners all lie inside the patch shrunk by the chart's
        ``mask_margin`` (the flat chart's scoring masks, through the perspective).

        Parameters
        ----------
        geometry : CameraGeometry
            The camera's view of the chart.

        Returns
        -------
        ndarray of bool, shape (24, H, W)
            One mask per patch, in the chart's order.
        """
        p = geometry.pixel_pitch_mm
        u, w = geometry.pixel_centres_mm()
        inset = self.chart.mask_margin * self.chart.patch_size_mm
        masks = np.ones((24, w.size, u.size), bool)
        for du in (-p / 2, p / 2):
            for dw in (-p / 2, p / 2):
                xc, yc, _ = self.chart_coordinates(geometry, u[None, :] + du, w[:, None] + dw)
                for q, (x0, x1, y0, y1) in enumerate(patch_rectangles_mm(self.chart)):
                    masks[q] &= (xc >= x0 + inset) & (xc <= x1 - inset) & (yc >= y0 + inset) & (yc <= y1 - inset)
        return masks

    def region(self, geometry: CameraGeometry) -> np.ndarray:
        return self.patch_masks(geometry).any(axis=0)

    def depth_range_mm(self, geometry: CameraGeometry) -> tuple[float, float]:
        """Nearest and farthest distance (along the axis) of the chart's board corners.

        Parameters
        ----------
        geometry : CameraGeometry
            Its object distance, mm.

        Returns
        -------
        tuple of float
            ``(nearest, farthest)``, mm.
        """
        bw, _ = self.chart.board_size_mm
        ex, _ = self._axes
        z = [geometry.object_distance_mm - sx * bw / 2 * ex[2] for sx in (-1, 1)]
        return min(z), max(z)
