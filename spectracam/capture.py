"""The sensor back end in one call: radiance cube → optics → responsivities → exposure → sensor.

``ρ_k = A·T_k·∫E_q(λ)·R_k(λ)dλ`` (paper, 3.3) is computed for every pixel and channel with one
matrix product over the bands; the architecture then samples and records it.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from .architecture import make_architecture
from .chart import patch_boxes, patch_means
from .exposure import exposure_times_s
from .filters import FilterSpec, responsivities
from .optics import OpticsSpec, radiance_to_photon_irradiance
from .sensor import SensorSpec
from .spectra import K_M_LM_PER_W, cmf_band_weights

#: Index of the white patch ("white 9.5 (.05 D)") in the standard ColorChecker order.
WHITE_PATCH = 18


@dataclass(frozen=True)
class CameraSpec:
    """Everything between the scene and the digital numbers."""

    optics: OpticsSpec = field(default_factory=OpticsSpec)
    filters: FilterSpec = field(default_factory=FilterSpec)
    sensor: SensorSpec = field(default_factory=SensorSpec)
    architecture: str = "cfa"
    exposure: str = "single"
    cfa_pattern: str = "RGGB"

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


@dataclass
class RawCapture:
    """What the sensor recorded.

    ``digital``: digital numbers, ``(H, W)`` mosaic for the CFA, ``(3, H, W)`` planes (prism) or
    frames (field-sequential) otherwise; ``expected_e``: the same layout, noise-free electrons
    (photo + dark); ``exposure_times_s``: per channel R, G, B; ``capture_time_s``: total.
    """

    digital: np.ndarray
    expected_e: np.ndarray | None
    exposure_times_s: np.ndarray
    capture_time_s: float
    architecture: str
    exposure: str
    cfa_pattern: str | None
    camera: CameraSpec
    seed: int
    white_rate_e_per_s: np.ndarray
    #: Noise-free photo-electron rates ``(24, 3)`` of each patch's masked pixels, e⁻/s, and the
    #: patches' CIE 1931 XYZ (Y = 1 for a perfect white diffuser), when the chart geometry is known.
    patch_rates_e_per_s: np.ndarray | None = None
    patch_xyz: np.ndarray | None = None
    metadata: dict = field(default_factory=dict)


def photo_electron_rates(cube, camera: CameraSpec) -> np.ndarray:
    """``(H, W, 3)`` photo-electrons per second per pixel for each channel, float32.

    Optics, photon conversion, responsivity, band width and pixel area are folded into one
    ``(n_bands, 3)`` weight matrix, so the cube is read once and never copied.
    """
    to_photons = radiance_to_photon_irradiance(cube.wavelengths_nm, camera.optics)  # (B,)
    R = responsivities(camera.filters, cube.grid)  # (3, B) e⁻/photon
    area_m2 = camera.sensor.pixel_area_um2 * 1e-12
    weights = (R * (to_photons * cube.grid.widths_nm * area_m2)[None, :]).T.astype(np.float32)  # (B, 3)
    h, w, b = cube.radiance.shape
    return (cube.radiance.reshape(h * w, b) @ weights).reshape(h, w, 3)


def capture(cube, sensor: SensorSpec | None = None, architecture: str | None = None, exposure: str | None = None,
            seed: int = 0, *, camera: CameraSpec | None = None, white_mask: np.ndarray | None = None,
            scene=None) -> RawCapture:
    """Capture a radiance cube.  ``sensor``, ``architecture`` and ``exposure`` override those of
    ``camera`` (default: the paper's camera, cfa/single).  The white patch for metering comes from
    ``white_mask``, else from the chart geometry of ``scene`` (or of the scene recorded in the
    cube's metadata)."""
    camera = camera or CameraSpec()
    camera = dataclasses.replace(camera, sensor=sensor or camera.sensor, architecture=architecture or camera.architecture,
                                 exposure=exposure or camera.exposure)
    arch = make_architecture(camera.architecture, camera.cfa_pattern)
    rates = photo_electron_rates(cube, camera)
    h, w, _ = rates.shape
    patch_rates = patch_xyz = None
    if white_mask is None:
        if scene is None:
            from .scene import parse_scene

            scene = parse_scene(cube.metadata["scene"])
        boxes = patch_boxes(scene.chart, w, h)
        patch_rates = patch_means(rates, boxes)
        patch_xyz = (patch_means(cube.radiance, boxes) @ cmf_band_weights(cube.grid)
                     * (K_M_LM_PER_W / scene.illuminant.white_luminance_cd_m2))
        white_rate = patch_rates[WHITE_PATCH]
    else:
        white_rate = rates[white_mask].mean(axis=0, dtype=np.float64)
    times = exposure_times_s(camera.exposure, white_rate, camera.sensor, arch)
    digital, expected = arch.record(rates, times, camera.sensor, seed)
    return RawCapture(digital=digital, expected_e=expected, exposure_times_s=times,
                      capture_time_s=arch.capture_time_s(times), architecture=arch.name, exposure=camera.exposure,
                      cfa_pattern=camera.cfa_pattern if arch.name == "cfa" else None, camera=camera, seed=seed,
                      white_rate_e_per_s=white_rate, patch_rates_e_per_s=patch_rates, patch_xyz=patch_xyz,
                      metadata={"scene": scene.to_dict()} if scene is not None else {})
