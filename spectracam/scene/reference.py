"""The chart reference: what the scene is, computed once, for every stage that needs the truth.

From a scene's chart, illuminant, wavelength grid and image size: each patch's band-averaged
radiance ``L = E·S/π`` (paper 3.1), its CIE 1931 XYZ (Y = 1 for a perfect white diffuser), the
illuminant's white, the patch names and scoring boxes — and, per camera, the noise-free photo-
electron rates of every patch.  Metering, the colour-conversion fit, the DNG matrices and scoring
all read this one object; nothing downstream climbs back to the renderer.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from typing import TYPE_CHECKING, Protocol

import numpy as np

from spectracam.scene.chart import WHITE_PATCH, ChartSpec, patch_boxes, patch_reflectances
from spectracam.scene.illuminant import IlluminantSpec, spectral_irradiance
from spectracam.scene.reflectances import load as load_library
from spectracam.core.spectra import WavelengthGrid, band_average, band_sample_points, cie_1931_cmfs

if TYPE_CHECKING:
    from numpy.typing import DTypeLike

    from spectracam.pipeline.scene_file import Scene

__all__ = ["LIBRARY_CHUNK", "LIBRARY_POINTS_PER_BAND", "TARGET_ROWS", "XYZ_STEP_NM", "ChartCell", "ChartReference",
           "LibraryColours", "RatedCamera", "TargetReference", "chart_cells", "colorimetry", "library_colours",
           "light_map", "material_radiance", "observer_grid"]


class RatedCamera(Protocol):
    """What the reference asks of a camera (:class:`spectracam.camera.CameraSpec` is one): its parts, which key the
    memo, and its noise-free photo-electron rates.  The camera stage sits above the scene, so the reference names
    the questions instead of importing the stage."""

    optics: object
    filters: object
    sensor: object
    capture: object

    def photo_electron_rates(self, radiance: np.ndarray, grid: WavelengthGrid) -> np.ndarray:
        """``(…, N)`` photo-electron rates, e⁻/s, of band-averaged radiance ``(…, B)`` on ``grid``.

        Parameters
        ----------
        radiance : ndarray
            ``(…, B)`` band-averaged spectral radiance, W·m⁻²·sr⁻¹·nm⁻¹.
        grid : WavelengthGrid
            The bands.

        Returns
        -------
        ndarray
            ``(…, N)`` e⁻/s per pixel, one per channel.
        """


#: Wavelength step of the reference colorimetry, nm: fine enough that the XYZ of every patch is
#: converged (0.1 nm and 1 nm differ by < 1e-4 ΔE*ab), whatever the scene's band width.
XYZ_STEP_NM = 0.1


def material_radiance(chart: ChartSpec, illuminant: IlluminantSpec,
                      grid: WavelengthGrid) -> tuple[list[str], np.ndarray, np.ndarray]:
    """``(names, patches (24, B), surround (B,))``: band-averaged radiance of each patch and of the
    surround, W·m⁻²·sr⁻¹·nm⁻¹, ``L(λ) = E(λ)·S(λ)/π`` for a Lambertian surface facing the light.

    Parameters
    ----------
    chart : ChartSpec
        The chart (its reflectances and the surround's reflectance).
    illuminant : IlluminantSpec
        The light, at its absolute level.
    grid : WavelengthGrid
        The bands.

    Returns
    -------
    names : list of str
        The 24 patch names.
    patches : ndarray
        ``(24, B)`` float64, W·m⁻²·sr⁻¹·nm⁻¹.
    surround : ndarray
        ``(B,)`` float64, W·m⁻²·sr⁻¹·nm⁻¹.
    """
    E = spectral_irradiance(illuminant)
    names, rows = [], []
    for name, rho in patch_reflectances(chart):
        names.append(name)
        rows.append(band_average(lambda lam, rho=rho: E(lam) * rho(lam) / np.pi, grid))
    surround = chart.surround_reflectance * band_average(lambda lam: E(lam) / np.pi, grid)
    return names, np.array(rows), surround


@dataclass(frozen=True, eq=False)
class ChartReference:
    """The truth about one chart scene; build it with :meth:`of`."""

    chart: ChartSpec
    illuminant: IlluminantSpec
    grid: WavelengthGrid
    width_px: int
    height_px: int
    names: tuple
    patch_radiance: np.ndarray  # (24, B)
    surround_radiance: np.ndarray  # (B,)
    patch_xyz: np.ndarray  # (24, 3), Y = 1 for a perfect white diffuser
    white_xyz: np.ndarray  # (3,), the illuminant's white, Y = 1
    boxes: tuple  # ((rows, cols) slices) of each patch's scoring mask
    _rates: dict = field(default_factory=dict, repr=False)
    #: ``(rows, cols)``: the cell of the image the chart is laid out in (a light group's, :func:`chart_cells`); None:
    #: the whole image.
    cell: tuple | None = None

    def local(self) -> "ChartReference":
        """This chart as if its cell were the whole image (boxes in the cell's pixels): the chart's own layout, for a
        computation on the cell's crop (the S-CIELAB truth)."""
        if self.cell is None:
            return self
        rows, cols = self.cell
        return _local_reference(self, rows.start, rows.stop, cols.start, cols.stop)

    @classmethod
    def of(cls, scene: Scene) -> "ChartReference":
        """The reference of a scene (memoised on chart, light, grid and image: sweeps and noise
        trials score the same scene many times).  A chart scene of several light groups
        (:mod:`spectracam.scene.lights`) has one chart per group: this is the brightest group's
        (:func:`chart_cells`), boxes in image pixels — what the exposure is metered on and scored by default.

        Parameters
        ----------
        scene : Scene
            The scene (its chart, illuminant, light groups, wavelength grid and image size).

        Returns
        -------
        ChartReference
            The chart's reference (shared: do not change it).
        """
        lights = getattr(scene, "lights", ())
        if len(lights) > 1 and not scene.target.textured:
            from spectracam.scene.lights import brightest

            return chart_cells(scene)[brightest(lights)].reference
        return _reference(scene.chart, scene.illuminant, scene.grid, scene.image.width, scene.image.height)

    def lit_by(self, illuminant: IlluminantSpec) -> "ChartReference":
        """The same chart, grid and image under another light (memoised as :meth:`of`): the DNG's
        calibrations under CIE A and D65.

        Parameters
        ----------
        illuminant : IlluminantSpec
            The other light.

        Returns
        -------
        ChartReference
            The chart's reference under it.
        """
        return _reference(self.chart, illuminant, self.grid, self.width_px, self.height_px)

    @property
    def white_box(self) -> tuple[slice, slice]:
        """The white patch's pixels: where exposure is metered (paper 4.5)."""
        return self.boxes[WHITE_PATCH]

    def patch_rates(self, camera: RatedCamera) -> np.ndarray:
        """Noise-free photo-electron rates ``(24, N)`` (e⁻/s) of the patches for a camera: the input of
        the colour-conversion fit (paper 3.5) and of the DNG matrices.

        Parameters
        ----------
        camera : RatedCamera
            The camera (memoised on its optics, filters, sensor and architecture).

        Returns
        -------
        ndarray
            ``(24, N)`` float64, e⁻/s, N the camera's channels.
        """
        key = (camera.optics, camera.filters, camera.sensor, camera.capture.architecture)
        if key not in self._rates:
            chart = self.patch_radiance[None].astype(np.float32)
            self._rates[key] = camera.photo_electron_rates(chart, self.grid)[0].astype(np.float64)
        return self._rates[key]

    def matches(self, scene: dict) -> str | None:
        """``None`` if a recorded scene (a dict) has this chart, light and grid, else the first table
        that differs.

        Parameters
        ----------
        scene : dict
            A scene as recorded in an output's metadata (its ``chart``, ``illuminant`` and ``wavelengths`` tables).

        Returns
        -------
        str or None
            ``"chart"``, ``"illuminant"`` or ``"wavelengths"``; None when all three match.
        """
        mine = {"chart": self.chart.to_dict(), "illuminant": self.illuminant.to_dict(),
                "wavelengths": {"centres_nm": list(self.grid.centres_nm)}}
        for table, value in mine.items():
            if scene.get(table) != value:
                return table
        return None


def observer_grid(lo_nm: float, hi_nm: float) -> tuple[np.ndarray, np.ndarray]:
    """``(λ (n,), x̄ȳz̄ (n, 3))``: the CIE 1931 observer on the reference colorimetry's grid over
    ``[lo_nm, hi_nm]`` (:data:`XYZ_STEP_NM`), shared by the chart and any other reflectances.

    Parameters
    ----------
    lo_nm, hi_nm : float
        The range, nm.

    Returns
    -------
    lam, xyz_bar : ndarray
        ``(n,)`` wavelengths, nm, and ``(n, 3)`` colour-matching functions interpolated linearly on them.
    """
    lam = np.linspace(lo_nm, hi_nm, int(round((hi_nm - lo_nm) / XYZ_STEP_NM)) + 1)
    wl, cmfs = cie_1931_cmfs()
    return lam, np.stack([np.interp(lam, wl, cmfs[:, k]) for k in range(3)], axis=-1)


def colorimetry(chart: ChartSpec, illuminant: IlluminantSpec, lo_nm: float,
                hi_nm: float) -> tuple[np.ndarray, np.ndarray]:
    """``(patch XYZ (24, 3), white XYZ (3,))`` of the chart over ``[lo_nm, hi_nm]``: the CIE 1931
    integrals ``∫(E·S/π)·x̄ȳz̄ dλ / ∫(E/π)·ȳ dλ``, numerator and denominator over the same range, so
    a perfect white diffuser has Y = 1 exactly (the white's Y = 1) — the scene's colour as the
    camera sees it (it sees only the scene's range), by the trapezoid rule at :data:`XYZ_STEP_NM`,
    independent of the bands.  (Before issue 17 the white was integrated over 360–830 nm, so a
    perfect white read Y = 0.9989–0.9996 on a 400–700 nm scene.)

    Parameters
    ----------
    chart : ChartSpec
        The chart (its reflectances).
    illuminant : IlluminantSpec
        The light.
    lo_nm, hi_nm : float
        The range integrated over, nm (the scene's).

    Returns
    -------
    patches, white : ndarray
        ``(24, 3)`` and ``(3,)`` float64 XYZ, relative to the white's Y.
    """
    lam, xyz_bar = observer_grid(lo_nm, hi_nm)
    white_radiance = spectral_irradiance(illuminant)(lam) / np.pi
    rho = np.stack([r(lam) for _, r in patch_reflectances(chart)])  # (24, n)
    white = np.trapezoid(white_radiance[:, None] * xyz_bar, lam, axis=0)
    patches = np.trapezoid((rho * white_radiance)[:, :, None] * xyz_bar[None], lam, axis=1) / white[1]
    return patches, white / white[1]


@lru_cache(maxsize=64)
def _reference(chart, illuminant, grid, width_px, height_px) -> ChartReference:
    names, patches, surround = material_radiance(chart, illuminant, grid)
    patch_xyz, white_xyz = colorimetry(chart, illuminant, float(grid.edges_nm[0]), float(grid.edges_nm[-1]))
    return ChartReference(chart, illuminant, grid, width_px, height_px, tuple(names), patches, surround, patch_xyz,
                          white_xyz, tuple(patch_boxes(chart, width_px, height_px)))


@dataclass(frozen=True, eq=False)
class ChartCell:
    """One chart of a light-group scene (:mod:`spectracam.scene.lights`): the group's name, index and light, the
    cell's pixels (``rows``, ``cols``) and the chart's truth under that light, ``reference``, whose ``boxes`` (the 24
    patches' scoring boxes) are in image pixels."""

    name: str
    index: int
    illuminant: IlluminantSpec
    rows: slice
    cols: slice
    reference: ChartReference

    @property
    def boxes(self) -> tuple:
        """``(rows, cols)`` slices of each patch's scoring pixels, in the image."""
        return self.reference.boxes

    @property
    def white_box(self) -> tuple[slice, slice]:
        """The cell's white patch, in the image."""
        return self.reference.white_box

    @property
    def white_luminance_cd_m2(self) -> float:
        """Luminance of a perfect white diffuser under the cell's light, cd/m²."""
        return self.illuminant.white_luminance_cd_m2


def chart_cells(scene: Scene) -> list[ChartCell]:
    """The charts of a chart scene, one per light group, in the order of ``[[lights]]``.

    Parameters
    ----------
    scene : Scene
        A scene whose target is the chart; without light groups, its one chart (the whole image, named
        ``"illuminant"``) under ``scene.illuminant``.

    Returns
    -------
    list of ChartCell
        Each group's cell of the image, its 24 patch boxes in image pixels and its :class:`ChartReference` (patch
        radiance ``E_g·S/π``, XYZ with Y = 1 for a white diffuser under the group's light).

    Raises
    ------
    ConfigError
        A textured target (its light groups light labels, not cells: :func:`light_map`).
    """
    from spectracam.core.errors import ConfigError

    if scene.target.textured:
        raise ConfigError("target.kind", scene.target.kind, "has no chart cells: a textured target's light groups "
                          "light its labels (spectracam.scene.reference.light_map)")
    W, H = scene.image.width, scene.image.height
    if not scene.lights:
        return [ChartCell("illuminant", 0, scene.illuminant, slice(0, H), slice(0, W), ChartReference.of(scene))]
    return list(_chart_cells(scene.chart, scene.lights, scene.grid, W, H, scene.image.lights_columns))


@lru_cache(maxsize=64)
def _local_reference(ref: ChartReference, r0: int, r1: int, c0: int, c1: int) -> ChartReference:
    import dataclasses

    return dataclasses.replace(ref, width_px=c1 - c0, height_px=r1 - r0, cell=None, _rates={},
                               boxes=tuple((slice(r.start - r0, r.stop - r0), slice(c.start - c0, c.stop - c0))
                                           for r, c in ref.boxes))


def _offset(box: tuple[slice, slice], rows: slice, cols: slice) -> tuple[slice, slice]:
    r, c = box
    return slice(r.start + rows.start, r.stop + rows.start), slice(c.start + cols.start, c.stop + cols.start)


@lru_cache(maxsize=16)
def _chart_cells(chart, lights, grid, width_px, height_px, columns) -> tuple[ChartCell, ...]:
    import dataclasses

    from spectracam.scene.lights import cell_columns, cell_slices

    columns = cell_columns(len(lights), width_px, height_px, chart.board_size_mm, columns)
    cells = []
    for k, (group, (rows, cols)) in enumerate(zip(lights, cell_slices(len(lights), width_px, height_px, columns))):
        local = _reference(chart, group.illuminant, grid, cols.stop - cols.start, rows.stop - rows.start)
        ref = dataclasses.replace(local, width_px=width_px, height_px=height_px,
                                  boxes=tuple(_offset(b, rows, cols) for b in local.boxes), cell=(rows, cols),
                                  _rates={})
        cells.append(ChartCell(group.name, k, group.illuminant, rows, cols, ref))
    return tuple(cells)


def light_map(scene: Scene) -> np.ndarray:
    """``(H, W)`` int32: the light group that lights each pixel (its index in ``scene.lights``).

    A chart scene: the group of the pixel's cell (-1 in unlit cells left over in the grid's last row).  A
    textured target: the group lighting most of the pixel's texels (the lowest index on ties).  Without light
    groups: 0 everywhere.

    Parameters
    ----------
    scene : Scene
        The scene.

    Returns
    -------
    ndarray
        ``(H, W)`` int32 group indices.
    """
    W, H = scene.image.width, scene.image.height
    K = len(scene.lights)
    if K == 0:
        return np.zeros((H, W), np.int32)
    if not scene.target.textured:
        out = np.full((H, W), -1, np.int32)
        for cell in chart_cells(scene):
            out[cell.rows, cell.cols] = cell.index
        return out
    ref = TargetReference.of(scene)
    s = ref.supersampling
    texel_groups = ref.groups[ref.labels]
    counts = np.stack([(texel_groups == k).reshape(H, s, W, s).sum(axis=(1, 3)) for k in range(K)])
    return counts.argmax(axis=0).astype(np.int32)


#: Points per band of the band averages (0.5 nm in a 10-nm band): the chart's 200 give the same
#: conversion error within 7e-5 ΔE*ab on the chart's own patches.
LIBRARY_POINTS_PER_BAND = 20
#: Samples handled at once (memory: ~100 MB of reflectances on the 0.1-nm colorimetry grid).
LIBRARY_CHUNK = 4096


@dataclass(frozen=True, eq=False)
class LibraryColours:
    """A library under one light on one wavelength grid: what a camera is shown and the truth."""

    library: str
    names: tuple
    radiance: np.ndarray     # (n, B) band-averaged, W·m⁻²·sr⁻¹·nm⁻¹
    xyz: np.ndarray          # (n, 3), Y = 1 for a perfect white diffuser
    white_xyz: np.ndarray    # (3,), the light's white, Y = 1


@lru_cache(maxsize=16)
def library_colours(library: str, illuminant: IlluminantSpec, grid: WavelengthGrid) -> LibraryColours:
    """Band radiance and CIE 1931 XYZ of every sample of ``library`` under ``illuminant`` (memoised).

    Parameters
    ----------
    library : str
        A reflectance library's name or ``file:PATH`` (:func:`spectracam.scene.reflectances.load`); it must cover
        the grid's range.
    illuminant : IlluminantSpec
        The light, at its absolute level.
    grid : WavelengthGrid
        The bands.

    Returns
    -------
    LibraryColours
        ``(n, B)`` radiance (W·m⁻²·sr⁻¹·nm⁻¹) and ``(n, 3)`` XYZ with Y = 1 for a perfect white diffuser (shared:
        do not change it).
    """
    lo, hi = float(grid.edges_nm[0]), float(grid.edges_nm[-1])
    rset = load_library(library)
    rset.check_covers(lo, hi)
    E = spectral_irradiance(illuminant)
    lam_b = band_sample_points(grid, LIBRARY_POINTS_PER_BAND)                 # (B, P + 1)
    e_b = E(lam_b) / np.pi
    # the chart's colorimetry (spectracam.scene.reference.colorimetry): trapezoids at its 0.1 nm (1 nm moved
    # the chart's conversion error by up to 0.008 ΔE*ab), as one (n, L) @ (L, 3) product per chunk
    lam, xyz_bar = observer_grid(lo, hi)
    trapezoid = np.full(lam.size, lam[1] - lam[0])
    trapezoid[[0, -1]] *= 0.5
    weights = (E(lam) / np.pi)[:, None] * xyz_bar * trapezoid[:, None]          # (L, 3)
    white = weights.sum(axis=0)
    radiance = np.empty((len(rset), len(grid.centres_nm)))
    xyz = np.empty((len(rset), 3))
    for a in range(0, len(rset), LIBRARY_CHUNK):
        sl = slice(a, a + LIBRARY_CHUNK)
        y = rset.at(lam_b.ravel(), sl).reshape(-1, *lam_b.shape) * e_b[None]
        radiance[sl] = 0.5 * (y[..., 1:] + y[..., :-1]).mean(axis=-1)
        xyz[sl] = rset.at(lam, sl) @ weights
    return LibraryColours(library, rset.sample_names, radiance, xyz / white[1], white / white[1])


#: Pixel rows handled at once when a target's texels are averaged into pixels (memory: rows × s² × W
#: texels of one (n, k) table row each).
TARGET_ROWS = 32


@dataclass(frozen=True, eq=False)
class TargetReference:
    """The truth about a textured target (:mod:`spectracam.scene.target`): its label image and, per label,
    the band radiance ``E·S/π`` and CIE 1931 XYZ under the scene's light (the last label is the
    surround, a flat ``chart.surround_reflectance``).  Build it with :meth:`of`.

    With light groups (:mod:`spectracam.scene.lights`) each label is lit by its group's light ``E_g``
    (``groups[label]``, a seeded draw): its radiance is ``E_g·S/π`` and its XYZ is relative to the white of the
    brightest group (a white diffuser under group g has Y = L_g / L_max), whose white is ``white_xyz``."""

    library: str
    names: tuple                 # (n,) sample names; label n is the surround
    labels: np.ndarray           # (H·s, W·s) int32
    supersampling: int
    radiance: np.ndarray         # (n + 1, B)
    xyz: np.ndarray              # (n + 1, 3), Y = 1 for a perfect white diffuser
    white_xyz: np.ndarray        # (3,)
    groups: np.ndarray | None = None   # (n + 1,) int32, each label's light group; None without light groups

    @classmethod
    def of(cls, scene: Scene) -> "TargetReference":
        """The reference of a scene's target (memoised on target, light, grid, image, surround and light groups).

        Parameters
        ----------
        scene : Scene
            The scene.

        Returns
        -------
        TargetReference
            Its texel labels, the samples' radiance and colours (shared: do not change it).
        """
        return _target_reference(scene.target, scene.illuminant, scene.grid, scene.image.width, scene.image.height,
                                 scene.chart.surround_reflectance, getattr(scene, "lights", ()))

    @property
    def surround(self) -> int:
        return len(self.names)

    @property
    def shape_px(self) -> tuple[int, int]:
        h, w = self.labels.shape
        return h // self.supersampling, w // self.supersampling

    def pixel_mean(self, table: np.ndarray, dtype: DTypeLike = np.float64) -> np.ndarray:
        """``(H, W, k)``: each pixel's mean of ``table[label]`` (``table`` ``(n + 1, k)``) over its
        s × s texels — the exact area-weighted mix, which a box-filtered render of the target converges to.

        Parameters
        ----------
        table : ndarray
            ``(n + 1, k)``: a row per sample, the surround's last (radiance per band, XYZ ...).
        dtype : DTypeLike
            The type to average in and return.

        Returns
        -------
        ndarray
            ``(H, W, k)`` of ``dtype``, in the table's unit.
        """
        s = self.supersampling
        H, W = self.shape_px
        table = np.asarray(table, dtype)
        out = np.empty((H, W, table.shape[1]), dtype)
        for i in range(0, H, TARGET_ROWS):
            j = min(i + TARGET_ROWS, H)
            block = table[self.labels[i * s:j * s]]                    # (rows·s, W·s, k)
            out[i:j] = block.reshape(j - i, s, W, s, -1).mean(axis=(1, 3))
        return out

    def pixel_labels(self) -> np.ndarray:
        """``(H, W)`` int32: the label of every pixel whose texels all show one label, -1 where they mix."""
        s = self.supersampling
        H, W = self.shape_px
        blocks = self.labels.reshape(H, s, W, s)
        lo, hi = blocks.min(axis=(1, 3)), blocks.max(axis=(1, 3))
        return np.where(lo == hi, lo, -1).astype(np.int32)

    def mean_radiance(self) -> np.ndarray:
        """``(B,)`` the whole image's mean radiance (each label weighted by its texel count)."""
        counts = np.bincount(self.labels.ravel(), minlength=self.surround + 1)
        return counts @ self.radiance / counts.sum()


def _label_table(colours: LibraryColours, illuminant: IlluminantSpec, grid: WavelengthGrid,
                 surround_reflectance: float) -> tuple[np.ndarray, np.ndarray]:
    """``(radiance (n + 1, B), xyz (n + 1, 3))`` of the library's samples and the surround under one light."""
    E = spectral_irradiance(illuminant)
    white_radiance = band_average(lambda lam: E(lam) / np.pi, grid, LIBRARY_POINTS_PER_BAND)
    radiance = np.vstack([colours.radiance, surround_reflectance * white_radiance[None]])
    xyz = np.vstack([colours.xyz, surround_reflectance * colours.white_xyz[None]])
    return radiance, xyz


@lru_cache(maxsize=4)
def _target_reference(target, illuminant, grid, width_px, height_px, surround_reflectance,
                      lights=()) -> TargetReference:
    from spectracam.scene.illuminant import IlluminantSpec
    from spectracam.core.cielab import xyz_to_lab
    from spectracam.scene.target import texel_labels

    colours = library_colours(target.library, illuminant, grid)
    lab_d65 = None
    if target.kind == "photo":   # the photograph's colours are matched under D65 (target.py)
        d65 = library_colours(target.library, IlluminantSpec("cie", None, "D65", 100.0), grid)
        lab_d65 = xyz_to_lab(d65.xyz, d65.white_xyz)
    n = len(colours.names)
    labels = texel_labels(target, width_px, height_px, n, lab_d65)
    radiance, xyz = _label_table(colours, illuminant, grid, surround_reflectance)
    groups = None
    if lights:   # each label under its group's light; XYZ relative to the brightest group's white
        from spectracam.scene.lights import brightest, label_groups

        groups = label_groups(target.seed, n + 1, len(lights))
        top = lights[brightest(lights)].white_luminance_cd_m2
        for k, group in enumerate(lights):
            rad_k, xyz_k = _label_table(library_colours(target.library, group.illuminant, grid), group.illuminant,
                                        grid, surround_reflectance)
            mine = groups == k
            radiance[mine], xyz[mine] = rad_k[mine], xyz_k[mine] * (group.white_luminance_cd_m2 / top)
    return TargetReference(target.library, colours.names, labels, target.supersampling, radiance, xyz,
                           colours.white_xyz, groups)
