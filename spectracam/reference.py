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

import numpy as np

from .camera import CameraSpec, photo_electron_rates
from .chart import WHITE_PATCH, ChartSpec, patch_boxes, patch_reflectances
from .illuminant import IlluminantSpec, spectral_irradiance
from .spectra import WavelengthGrid, band_average, cie_1931_cmfs

#: Wavelength step of the reference colorimetry, nm: fine enough that the XYZ of every patch is
#: converged (0.1 nm and 1 nm differ by < 1e-4 ΔE*ab), whatever the scene's band width.
XYZ_STEP_NM = 0.1


def material_radiance(chart: ChartSpec, illuminant: IlluminantSpec, grid: WavelengthGrid):
    """``(names, patches (24, B), surround (B,))``: band-averaged radiance of each patch and of the
    surround, W·m⁻²·sr⁻¹·nm⁻¹, ``L(λ) = E(λ)·S(λ)/π`` for a Lambertian surface facing the light."""
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

    @classmethod
    def of(cls, scene) -> "ChartReference":
        """The reference of a scene (memoised on chart, light, grid and image: sweeps and noise
        trials score the same scene many times)."""
        return _reference(scene.chart, scene.illuminant, scene.grid, scene.image.width, scene.image.height)

    @property
    def white_box(self) -> tuple[slice, slice]:
        """The white patch's pixels: where exposure is metered (paper 4.5)."""
        return self.boxes[WHITE_PATCH]

    def patch_rates(self, camera: CameraSpec) -> np.ndarray:
        """Noise-free photo-electron rates ``(24, 3)`` (e⁻/s) of the patches for a camera: the input of
        the colour-conversion fit (paper 3.5) and of the DNG matrices."""
        key = (camera.optics, camera.filters, camera.sensor)
        if key not in self._rates:
            chart = self.patch_radiance[None].astype(np.float32)
            self._rates[key] = photo_electron_rates(chart, self.grid, camera)[0].astype(np.float64)
        return self._rates[key]

    def matches(self, scene: dict) -> str | None:
        """``None`` if a recorded scene (a dict) has this chart, light and grid, else the first table
        that differs."""
        mine = {"chart": self.chart.to_dict(), "illuminant": self.illuminant.to_dict(),
                "wavelengths": {"centres_nm": list(self.grid.centres_nm)}}
        for table, value in mine.items():
            if scene.get(table) != value:
                return table
        return None


def observer_grid(lo_nm: float, hi_nm: float) -> tuple[np.ndarray, np.ndarray]:
    """``(λ (n,), x̄ȳz̄ (n, 3))``: the CIE 1931 observer on the reference colorimetry's grid over
    ``[lo_nm, hi_nm]`` (:data:`XYZ_STEP_NM`), shared by the chart and any other reflectances."""
    lam = np.linspace(lo_nm, hi_nm, int(round((hi_nm - lo_nm) / XYZ_STEP_NM)) + 1)
    wl, cmfs = cie_1931_cmfs()
    return lam, np.stack([np.interp(lam, wl, cmfs[:, k]) for k in range(3)], axis=-1)


def colorimetry(chart: ChartSpec, illuminant: IlluminantSpec, lo_nm: float, hi_nm: float):
    """``(patch XYZ (24, 3), white XYZ (3,))`` of the chart over ``[lo_nm, hi_nm]``: the CIE 1931
    integrals ``∫(E·S/π)·x̄ȳz̄ dλ / ∫(E/π)·ȳ dλ``, numerator and denominator over the same range, so
    a perfect white diffuser has Y = 1 exactly (the white's Y = 1) — the scene's colour as the
    camera sees it (it sees only the scene's range), by the trapezoid rule at :data:`XYZ_STEP_NM`,
    independent of the bands.  (Before issue 17 the white was integrated over 360–830 nm, so a
    perfect white read Y = 0.9989–0.9996 on a 400–700 nm scene.)"""
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
