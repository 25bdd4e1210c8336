"""The architectures spatially: sample, record and process an image of photo-electron rates.

A *spatial design* is an architecture/exposure design of the registry (``cfa/single``,
``prism/optimal``, ``fsc/optimal``, ``rgbw/single``, …), the demosaicking method when its layout is a
mosaic, an optical low-pass filter's spot separation (mosaics; 0 for none), and a misregistration of
its sensors in pixels (the prism: each sensor is glued to the prism with some error; the paper says
the prism "requires precise alignment"). The misregistration is a sub-pixel shift of where the red
and blue sensors sample the image relative to the green one — :func:`misregistration_shifts`: red by
``+m`` along x, blue by ``+m`` along y — applied by the optics stage before sampling
(:class:`spectracam.experiments.spatial.optics.OpticsSettings`).

Recording uses the architecture's own ``record`` (the registry's; ``sensor.expose`` with its fixed
patterns) after metering on the ColorChecker's white patch under the same light (paper 4.5);
processing is :func:`spectracam.evaluation.score.camera_rates` (dark subtraction, demosaicking by layout, exposure
normalisation) and the 3×3 conversion fitted on the chart (paper 3.5) to the display's XYZ.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from spectracam.architecture.base import MosaicLayout
from spectracam.camera import CameraSpec
from spectracam.camera.capture import RawCapture, capture_time_s
from spectracam.scene.chart import WHITE_PATCH
from spectracam.processing.color import ProcessingSpec, adaptation_matrix, display_rgb_to_xyz, fit_conversion
from spectracam.sensor.exposure import exposure_times_s
from spectracam.scene.reference import ChartReference
from spectracam.evaluation.score import camera_rates
from spectracam.core.spectra import K_M_LM_PER_W, cmf_band_weights

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from spectracam.core.spectra import WavelengthGrid

__all__ = ["Conversion", "SpatialDesign", "misregistration_shifts", "process", "radiance_to_display_xyz",
           "record", "white_rate"]


@dataclass(frozen=True)
class SpatialDesign:
    """One design of the spatial comparison."""

    design: str                       # "arch/scheme", e.g. "cfa/single"
    demosaic: str | None = None       # for a mosaic layout
    misregistration_px: float | None = None   # for separate sensors (a prism); None where it does not apply
    olpf_separation_px: float = 0.0   # a 4-spot optical low-pass filter's spot separation (0: none)

    @property
    def label(self) -> str:
        s = self.design
        if self.demosaic:
            s += f" {self.demosaic}"
        if self.olpf_separation_px > 0:
            s += f" OLPF {self.olpf_separation_px:g} px"
        if self.misregistration_px is not None:
            s += f" {'aligned' if self.misregistration_px == 0 else f'misaligned {self.misregistration_px:g} px'}"
        return s


def misregistration_shifts(m_px: float | None) -> tuple:
    """Sampling offsets (dx, dy) px of the R, G, B sensors: red ``+m`` along x, blue ``+m`` along y
    (``()``: every channel at the pixel centre).

    Parameters
    ----------
    m_px : float or None
        The misregistration, px; 0 or None: none.

    Returns
    -------
    tuple
        ``((m, 0), (0, 0), (0, m))``, or ``()``.
    """
    if not m_px:
        return ()
    return ((float(m_px), 0.0), (0.0, 0.0), (0.0, float(m_px)))


@dataclass(frozen=True)
class Conversion:
    """Camera rates → display XYZ, fitted on the chart; the scene's XYZ → the display white's."""

    matrix: np.ndarray            # camera rates (e⁻/s) → linear display RGB
    rgb_to_xyz: np.ndarray        # display RGB → XYZ (white Y = 1)
    display_white: np.ndarray
    scene_white: np.ndarray
    scene_to_display: np.ndarray  # XYZ under the scene's white → under the display's (the adaptation)

    @classmethod
    def fit(cls, reference: ChartReference, camera: CameraSpec, processing: ProcessingSpec) -> "Conversion":
        """The conversion fitted on the chart's noise-free rates to its XYZ carried to the display white (paper 3.5).

        Parameters
        ----------
        reference : ChartReference
            The chart's XYZ, white and noise-free rates.
        camera : CameraSpec
        processing : ProcessingSpec
            Its display and chromatic adaptation.

        Returns
        -------
        Conversion
        """
        M_disp = display_rgb_to_xyz(processing.display)
        white = M_disp.sum(axis=1)
        adapt = adaptation_matrix(reference.white_xyz, white, processing.adaptation)
        target = reference.patch_xyz @ adapt.T @ np.linalg.inv(M_disp).T
        M = fit_conversion(reference.patch_rates(camera), target)
        return cls(M, M_disp, white, np.asarray(reference.white_xyz, float), adapt)


def white_rate(reference: ChartReference, camera: CameraSpec) -> np.ndarray:
    """Noise-free photo-electron rates (N,) of the ColorChecker's white patch: where exposure is metered.

    Parameters
    ----------
    reference : ChartReference
    camera : CameraSpec

    Returns
    -------
    ndarray
        ``(N,)`` e⁻/s.
    """
    return reference.patch_rates(camera)[WHITE_PATCH]


def record(rates: np.ndarray, camera: CameraSpec, metered_rate: np.ndarray, seed: int,
           times: ArrayLike | None = None) -> RawCapture:
    """Expose an ``(H, W, N)`` rate image with the camera's architecture and exposure scheme (or the
    exposure ``times`` given: a noise-free twin of a noisy capture keeps the noisy one's times).

    Parameters
    ----------
    rates : ndarray
        ``(H, W, N)`` photo-electron rates, e⁻/s.
    camera : CameraSpec
    metered_rate : ndarray
        ``(N,)`` the metered white's rates, e⁻/s (:func:`white_rate`).
    seed : int
        The noise seed.
    times : array_like or None
        ``(N,)`` exposure times, s; None: metered by the camera's scheme.

    Returns
    -------
    RawCapture
    """
    arch = camera.architecture()
    if times is None:
        times = exposure_times_s(camera.capture.exposure, metered_rate, camera.sensor, arch, camera.capture.white_fill,
                                 camera.capture.exposure_split)
    digital, expected = arch.record(np.ascontiguousarray(rates, np.float32), times, camera.sensor, seed)
    return RawCapture(digital=digital, expected_e=expected, exposure_times_s=times,
                      capture_time_s=capture_time_s(arch, times, camera.sensor), layout=arch.layout, camera=camera,
                      seed=seed,
                      metered_rate_e_per_s=np.asarray(metered_rate, float))


def process(raw: RawCapture, processing: ProcessingSpec, conversion: Conversion,
            reference: ChartReference | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(camera rates (H, W, N) e⁻/s, display XYZ (H, W, 3), white Y = 1)`` of a capture; ``reference``: the scene's
    chart reference, whose wavelengths and light a lens-shading correction (``processing.shading``) is calibrated
    for.

    Parameters
    ----------
    raw : RawCapture
    processing : ProcessingSpec
        Demosaicking (bilinear for full planes, where it is unused) and shading correction.
    conversion : Conversion
    reference : ChartReference or None

    Returns
    -------
    tuple of ndarray
        The camera rates and the display XYZ.
    """
    if not isinstance(raw.layout, MosaicLayout):
        processing = processing.replace(demosaic="bilinear")  # unused for planes
    rates = camera_rates(raw, processing, reference)
    xyz = rates @ conversion.matrix @ conversion.rgb_to_xyz.T
    return rates, xyz


def radiance_to_display_xyz(radiance: np.ndarray, grid: WavelengthGrid, white_luminance_cd_m2: float,
                            conversion: Conversion) -> np.ndarray:
    """XYZ (white Y = 1) of band-averaged radiance ``(..., B)``, carried to the display white: the ideal
    rendering S-CIELAB and CIELAB compare against.

    Parameters
    ----------
    radiance : ndarray
        ``(..., B)`` W·m⁻²·sr⁻¹·nm⁻¹.
    grid : WavelengthGrid
        The bands, nm.
    white_luminance_cd_m2 : float
        The scene white's luminance, cd/m² (Y = 1 there).
    conversion : Conversion
        Its adaptation to the display white.

    Returns
    -------
    ndarray
        ``(..., 3)`` XYZ.
    """
    xyz = K_M_LM_PER_W * (np.asarray(radiance, float) @ cmf_band_weights(grid)) / white_luminance_cd_m2
    return xyz @ conversion.scene_to_display.T
