"""The sensor back end in one call: radiance cube → optics → responsivities → exposure → sensor.

``ρ_k = A·T_k·∫E_q(λ)·R_k(λ)dλ`` (paper, 3.3) is the radiance times one ``(bands, 3)`` weight matrix
(:func:`~spectracam.camera.band_weights`); exposure is metered on the white patch (paper 4.5) from
the patch's mean spectrum; the architecture then samples and records it.  The rates are handed on
uncomputed (:class:`~spectracam.sensor.kernels.SpectralRates`): the fused sensor pass
(:mod:`spectracam.sensor.kernels`) reads the cube once and weights each pixel with the channel its site
records, noise and ADC in the same loop; without it they are computed as
:func:`~spectracam.camera.photo_electron_rates` does and recorded by the NumPy steps.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from spectracam.architecture.base import MosaicLayout, PlanesLayout
from spectracam.camera import CameraSpec, band_weights
from spectracam.core.errors import SpectracamError
from spectracam.render.cube import ChannelPlanes, RadianceCube
from spectracam.sensor.exposure import exposure_times_s
from spectracam.sensor.kernels import SpectralRates

if TYPE_CHECKING:
    from spectracam.architecture.base import Architecture
    from spectracam.sensor import SensorSpec

__all__ = ["PLANES_WEIGHT_RTOL", "RawCapture", "capture", "capture_time_s", "check_planes_camera",
           "check_planes_capturable", "field_radiance"]


@dataclass
class RawCapture:
    """What the sensor recorded.

    ``digital``: digital numbers in the layout's shape — ``(H, W)`` for a :class:`MosaicLayout`,
    ``(3, H, W)`` for a :class:`PlanesLayout`; ``expected_e``: the same layout, noise-free electrons
    (photo + dark), ``None`` when read from a file; ``exposure_times_s``: per channel R, G, B;
    ``capture_time_s``: total; ``metered_rate_e_per_s``: the white patch's mean photo-electron rates
    that set the exposure; ``scene``: the scene it was taken of, as recorded (a dict), if known.
    """

    digital: np.ndarray
    expected_e: np.ndarray | None
    exposure_times_s: np.ndarray
    capture_time_s: float
    layout: MosaicLayout | PlanesLayout
    camera: CameraSpec
    seed: int
    metered_rate_e_per_s: np.ndarray | None = None
    scene: dict | None = None
    #: How the white was metered when not on a chart scene's white patch (spectracam.sensor.metering).
    metering: dict | None = None
    #: What the rates were computed from: ``"cube"`` (the band cube through the camera's band weights, in the sensor's
    #: pass) or ``"channel planes"`` (:class:`~spectracam.render.ChannelPlanes`: the same rates summed over the bands
    #: beforehand, so a pixel on a quantisation step's edge may land one DN apart).
    rates: str = "cube"

    @property
    def design(self) -> str:
        return self.camera.design


def field_radiance(radiance: np.ndarray, camera: CameraSpec) -> np.ndarray:
    """The radiance as the sensor receives it across the field (issue 37): each pixel's spectrum times the lens's
    relative illumination there (:func:`spectracam.optics.field.field_maps`: cos⁴ of the chief ray's angle, the
    exit-pupil form, a measured curve or lensfun's polynomial; 0 outside the image circle).  On the axis (the
    default, the paper's camera) the cube itself, not a copy.

    Parameters
    ----------
    radiance : ndarray
        ``(H, W, B)`` band-averaged spectral radiance, W·m⁻²·sr⁻¹·nm⁻¹.
    camera : CameraSpec
        The camera (its optics' field and its sensor's pixel pitch).

    Returns
    -------
    ndarray
        ``(H, W, B)`` of the radiance's dtype, W·m⁻²·sr⁻¹·nm⁻¹.
    """
    if camera.optics.on_axis:
        return radiance
    from spectracam.optics.field import field_maps

    maps = field_maps(radiance.shape[:2], camera.sensor.pixel_pitch_um, camera.optics, camera.optics.f_number)
    return radiance * maps.illumination[..., None].astype(radiance.dtype)


def _rates(radiance: np.ndarray, grid, camera: CameraSpec, weights: np.ndarray):
    """The photo-electron rates to record: on the axis (the default) a :class:`SpectralRates`, computed in the
    sensor's fused pass; with the pixel's angle response on or an oblique chief ray, each pixel's rates at its place
    in the field (:func:`spectracam.camera.field.field_rates`), ``(H, W, N)``."""
    if not camera.pixel.any_on and camera.optics.on_axis:
        return SpectralRates(radiance, weights)  # computed in the sensor's pass
    from spectracam.camera.field import field_active, field_rates
    from spectracam.optics.field import field_maps

    maps = None if camera.optics.on_axis else field_maps(radiance.shape[:2], camera.sensor.pixel_pitch_um,
                                                          camera.optics, camera.optics.f_number)
    if not field_active(camera, None if maps is None else maps.cra_deg):
        return SpectralRates(radiance, weights)
    return field_rates(radiance, grid, camera, maps)


#: How closely a :class:`ChannelPlanes`' weights must be the capturing camera's band weights (relative, per
#: element against the largest): they were computed by the same function, so any camera difference shows far above.
PLANES_WEIGHT_RTOL = 1e-6


def check_planes_capturable(camera: CameraSpec) -> None:
    """Refuse, in one line naming the setting, a camera whose channel planes cannot stand for its cube: an off-axis
    field (relative illumination, an oblique chief ray, an image circle) or the pixel's angle response (microlens,
    crosstalk) weight each pixel's spectrum by its place in the field (:func:`_rates`).

    Parameters
    ----------
    camera : CameraSpec
        The camera that would capture the planes.

    Raises
    ------
    SpectracamError
        Naming each setting that needs the cube.
    """
    o, px = camera.optics, camera.pixel
    found = [f"optics.relative_illumination = {o.relative_illumination!r}"] if o.relative_illumination != "none" else []
    found += [f"optics.chief_ray = {o.chief_ray!r}"] if o.chief_ray != "linear" else []
    found += [f"optics.cra_corner_deg = {o.cra_corner_deg:g}"] if o.cra_corner_deg != 0 else []
    found += [f"optics.image_circle_diameter_mm = {o.image_circle_diameter_mm:g}"] \
        if o.image_circle_diameter_mm is not None else []
    found += [f"pixel.{k} = {getattr(px, k)!r}" for k in ("microlens", "optical_crosstalk", "electrical_crosstalk")
              if getattr(px, k)]
    if found or px.any_on or not o.on_axis:
        raise SpectracamError(f"channel planes: {', '.join(found) or 'the field or the pixel angle response'} weights "
                              "each pixel's spectrum by its place; allowed: an on-axis camera without a pixel angle "
                              "response; render the radiance cube instead")


def check_planes_camera(planes: ChannelPlanes, camera: CameraSpec) -> None:
    """Refuse channel planes integrated for another camera than ``camera`` (other filters, optics or pixel: its band
    weights differ), or a camera whose pixels see more than one spectrum's integral (the pixel's angle response, an
    off-axis field): those need each pixel's spectrum, i.e. the cube.

    Parameters
    ----------
    planes : ChannelPlanes
        Planes rendered for some camera (their ``weights``).
    camera : CameraSpec
        The camera about to capture them.

    Raises
    ------
    SpectracamError
        Weights other than ``camera``'s band weights (within :data:`PLANES_WEIGHT_RTOL`), or
        :func:`check_planes_capturable`'s refusal.
    """
    check_planes_capturable(camera)
    want = band_weights(camera, planes.grid).astype(np.float64)
    got = np.asarray(planes.weights, np.float64)
    if got.shape != want.shape or np.abs(got - want).max() > PLANES_WEIGHT_RTOL * np.abs(want).max():
        raise SpectracamError(f"channel planes: integrated with weights {got.shape} for another camera than the one "
                              f"capturing them ({camera.design}, {want.shape}); render them for this camera")


def _exposed(cube: RadianceCube | ChannelPlanes, camera: CameraSpec) -> tuple:
    """``(radiance as the sensor receives it, band weights (B, N), rates to record)``: of a cube, through the field
    and the camera's band weights (:func:`_rates`); of channel planes rendered for ``camera``, the planes themselves
    with identity weights (the fused pass then records them exactly; issue 38)."""
    if isinstance(cube, ChannelPlanes):
        check_planes_camera(cube, camera)
        return cube.planes, np.eye(cube.planes.shape[-1], dtype=np.float32), cube.planes
    weights = band_weights(camera, cube.grid)
    radiance = field_radiance(cube.radiance, camera)
    return radiance, weights, _rates(radiance, cube.grid, camera, weights)


def capture_time_s(arch: Architecture, times_s: np.ndarray, sensor: SensorSpec) -> float:
    """How long the capture takes, s: the architecture's sum or maximum of its exposures (paper 2), each exposure
    as long as the sensor's read-out takes for it (a bracketed exposure: its frames together).

    Parameters
    ----------
    arch : Architecture
        The architecture (how its exposures combine in time).
    times_s : ndarray
        Its exposure times, s.
    sensor : SensorSpec
        The sensor (its read-out scheme).

    Returns
    -------
    float
        The capture time, s.
    """
    if sensor.readout != "single":
        from spectracam.sensor.readout import READOUTS

        scheme = READOUTS[sensor.readout]
        times_s = np.array([scheme.capture_time_s(sensor, float(t)) for t in times_s])
    return arch.capture_time_s(times_s)


def capture(cube: RadianceCube | ChannelPlanes, camera: CameraSpec, seed: int,
            metering_box: tuple[slice, slice] | None = None, *,
            white_radiance: np.ndarray | None = None, metering: dict | None = None,
            time_limit_s: float | None = None) -> RawCapture:
    """Capture a :class:`~spectracam.render.RadianceCube` with ``camera``, the exposure metered first (paper 4.5).

    Parameters
    ----------
    cube : RadianceCube or ChannelPlanes
        The scene's band-averaged spectral radiance, W·m⁻²·sr⁻¹·nm⁻¹; or channel planes rendered for ``camera``
        (its rates; :func:`check_planes_camera`).
    camera : CameraSpec
        The camera: optics, filters, sensor, pixel, architecture and exposure scheme.
    seed : int
        Fixes every random draw (fixed pattern and temporal noise).
    metering_box : tuple of slice or None
        Rows and columns of the pixels whose mean rates meter the exposure (the white patch, paper 4.5).
    white_radiance : ndarray or None
        ``(B,)`` radiance of another white to meter on instead (:mod:`spectracam.sensor.metering`).
    metering : dict or None
        The record of that metering, kept in the capture.
    time_limit_s : float or None
        A hand-held limit, s: a camera that meters itself (``capture.metering`` average or percentile; it ignores
        the box and the white) shortens its exposures in proportion so that the capture lasts at most this.

    Returns
    -------
    RawCapture
        Digital numbers, expected electrons, exposure and capture times (s), layout, camera, seed and metering.
    """
    arch = camera.architecture()
    radiance, weights, rates = _exposed(cube, camera)
    if isinstance(cube, ChannelPlanes) and white_radiance is not None:   # its rates, through the planes' weights
        white_radiance = np.asarray(white_radiance, np.float64) @ np.asarray(cube.weights, np.float64)
    if camera.capture.metering not in ("auto", "white_patch"):   # the camera meters its own preview (issue 33)
        from spectracam.sensor.metering import metered_white_rates, metering_record

        white_rate = metered_white_rates(radiance, weights.astype(np.float64), camera.capture)
        metering = metering_record(camera.capture)
    elif white_radiance is not None:
        white_rate = np.asarray(white_radiance, np.float64) @ weights.astype(np.float64)
    elif isinstance(rates, SpectralRates):
        white_rate = rates.mean(*metering_box)
    elif isinstance(cube, ChannelPlanes):                # every pixel of the box, as SpectralRates.mean
        white_rate = cube.planes[metering_box].mean(axis=(0, 1), dtype=np.float64)
    else:                                                # each pixel's rate at its place in the field
        from spectracam.camera.field import metered_field_rates

        white_rate = metered_field_rates(rates, metering_box, arch.layout)
    times = exposure_times_s(camera.capture.exposure, white_rate, camera.sensor, arch, camera.capture.white_fill,
                             camera.capture.exposure_split)
    if time_limit_s is not None and metering is not None and metering.get("kind") == "camera":
        scale = min(1.0, time_limit_s / capture_time_s(arch, times, camera.sensor))
        times = times * scale
        metering = {**metering, "time_limit_ms": 1e3 * time_limit_s, "shortened_by": scale}
    digital, expected = arch.record(rates, times, camera.sensor, seed)
    return RawCapture(digital=digital, expected_e=expected, exposure_times_s=times,
                      capture_time_s=capture_time_s(arch, times, camera.sensor), layout=arch.layout, camera=camera,
                      seed=seed, metered_rate_e_per_s=white_rate, scene=cube.metadata.get("scene"), metering=metering,
                      rates="channel planes" if isinstance(cube, ChannelPlanes) else "cube")
