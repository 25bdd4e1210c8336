"""Spatial optics: from sub-pixel radiance to each pixel's photo-electron rate, per channel.

For every band b the sub-pixel radiance image is filtered, in the frequency domain, by

* the **diffraction-limited OTF** of a circular pupil at the band's centre wavelength (incoherent,
  aberration-free): ``OTF(ν) = (2/π)(acos ν − ν·√(1 − ν²))`` for ``ν = ρ·λ·N < 1`` (0 beyond), with ρ
  the radial spatial frequency in the image plane and N the f-number (Goodman, *Introduction to
  Fourier Optics*, 3rd ed., eq. 6-32);
* optionally a thin lens's **defocus** of a target at one depth, the OTF of a uniform blur disc of
  diameter c: ``2·J₁(πcρ)/(πcρ)`` (geometric optics) — the Mitsuba thinlens camera renders defocus
  itself and passes c = 0;

then weighted into the architecture's channels by :func:`spectracam.camera.band_weights` (the paper's
``π/(4N²)·T·λ/hc·R_k·Δλ·A``, so the result is photo-electrons per second per pixel). Each channel is
then

* optionally spread by a **birefringent optical low-pass filter** (off by default, as in the paper): two
  crystal plates split every ray into four spots on a square of side d (:func:`olpf_otf`);
* integrated over the pixel's **light-sensitive aperture**, a centred square of side
  ``pitch·√(fill factor)``: the transfer ``sinc(fx·a)·sinc(fy·a)``, divided by the sub-pixel box
  ``sinc(fx·s)·sinc(fy·s)`` the renderer's box filter already applied (for a full fill factor the two
  together are the exact sum of the pixel's sub-pixels);
* **sampled at the pitch** at each pixel's centre, displaced by the channel's misregistration (a
  prism's sensors: a sub-pixel shift, applied as a phase ramp before sampling);
* optionally multiplied by the **cos⁴ fall-off** of the off-axis irradiance.

Frequency-domain filtering is periodic: the renderer draws a margin around the image, wide enough
for the optics (:func:`margin_px`), that is cut away after sampling.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.fft as sfft
from scipy.special import j1

from spectracam.camera import CameraSpec, band_weights
from spectracam.experiments.spatial.geometry import CameraGeometry

if TYPE_CHECKING:
    from collections.abc import Sequence

    from numpy.typing import ArrayLike

    from spectracam.core.spectra import WavelengthGrid

__all__ = ["MARGIN_PX", "WRAP_TOLERANCE", "OpticsSettings", "aperture_mtf", "channel_mtf_closed_form",
           "channel_spectra", "defocus_otf", "diffraction_otf", "margin_px", "olpf_otf", "pixel_rates",
           "sample_channels"]

#: The fewest pixels rendered around the image on each side (room for a misregistration of up to 4 px).
MARGIN_PX = 8

#: Share of a line's light that may wrap round the periodic image from its far side.  The line spread of
#: a circular pupil falls as 1/x² far out (the kink of its OTF, 1 − (4/π)·λN·|ρ|, at ρ = 0), so the light
#: beyond a distance x is 2·λN/(π³·x) of the whole (checked against the numerical line spread).
WRAP_TOLERANCE = 0.01


def margin_px(pixel_pitch_um: float, f_number: float, wavelength_max_nm: float, shift_px: float = 0.0) -> int:
    """Pixels to render around the image on each side so that at most :data:`WRAP_TOLERANCE` of the
    diffraction line spread wraps round from the far side (at least :data:`MARGIN_PX`).

    Parameters
    ----------
    pixel_pitch_um : float
        µm.
    f_number : float
    wavelength_max_nm : float
        The longest band's wavelength, nm (the widest line spread).
    shift_px : float
        A channel's sampling shift, px, added.

    Returns
    -------
    int
        Pixels.

    Examples
    --------
    >>> margin_px(2.0, 8.0, 700.0), margin_px(2.0, 32.0, 700.0), margin_px(10.0, 1.4, 700.0)
    (19, 73, 8)
    """
    reach_um = 2 * wavelength_max_nm * 1e-3 * f_number / (np.pi ** 3 * WRAP_TOLERANCE)
    return max(MARGIN_PX, int(np.ceil(reach_um / pixel_pitch_um + abs(shift_px))))


def diffraction_otf(rho_cy_per_um: ArrayLike, wavelength_nm: float, f_number: float) -> np.ndarray:
    """Diffraction-limited OTF of a circular pupil at radial frequency ρ (cycles/µm in the image plane).

    Parameters
    ----------
    rho_cy_per_um : array_like
        Radial frequencies, cycles/µm.
    wavelength_nm : float
        nm.
    f_number : float

    Returns
    -------
    ndarray
        ``rho``'s shape, 1 at 0 and 0 from the cut-off 1/(λN) on.

    Examples
    --------
    >>> diffraction_otf(np.array([0.0, 1 / (0.55 * 8)]), 550.0, 8.0).round(6).tolist()
    [1.0, 0.0]
    """
    nu = np.asarray(rho_cy_per_um, float) * (wavelength_nm * 1e-3) * f_number
    nu = np.clip(nu, 0.0, 1.0)
    return (2 / np.pi) * (np.arccos(nu) - nu * np.sqrt(1 - nu * nu))


def defocus_otf(rho_cy_per_um: ArrayLike, blur_diameter_um: float) -> np.ndarray:
    """OTF of a uniform disc of diameter c (geometric defocus): ``2·J₁(πcρ)/(πcρ)``, 1 at ρ = 0.

    Parameters
    ----------
    rho_cy_per_um : array_like
        Radial frequencies, cycles/µm.
    blur_diameter_um : float
        c, µm.

    Returns
    -------
    ndarray
        ``rho``'s shape (negative between its zeros).
    """
    x = np.pi * float(blur_diameter_um) * np.asarray(rho_cy_per_um, float)
    out = np.ones_like(x)
    nz = x > 1e-9
    out[nz] = 2 * j1(x[nz]) / x[nz]
    return out


def olpf_otf(fx_cy_per_px: ArrayLike, fy_cy_per_px: ArrayLike, separation_px: float) -> np.ndarray:
    """OTF of a 4-spot birefringent low-pass filter: two plates (split along x, then along y) turn a
    point into four equal spots at ``(±d/2, ±d/2)`` around it, so ``OTF = cos(π·fx·d)·cos(π·fy·d)``
    (real: the spots are centred on the point); first zero at ``1/(2d)`` — the Nyquist frequency for
    d = one pixel (Hecht, *Optics*, 4th ed., §8.4 on birefringent displacement; the usual camera OLPF).

    Parameters
    ----------
    fx_cy_per_px, fy_cy_per_px : array_like
        Frequencies, cycles/pixel (broadcast together).
    separation_px : float
        d, pixels.

    Returns
    -------
    ndarray
        The real OTF.

    Examples
    --------
    >>> olpf_otf(np.array([0.0, 0.5, 1.0]), 0.0, 1.0).round(12).tolist()
    [1.0, 0.0, -1.0]
    """
    d = float(separation_px)
    return np.cos(np.pi * np.asarray(fx_cy_per_px, float) * d) * np.cos(np.pi * np.asarray(fy_cy_per_px, float) * d)


def aperture_mtf(fx_cy_per_px: ArrayLike, fy_cy_per_px: ArrayLike, fill_factor: float = 1.0) -> np.ndarray:
    """Transfer of a centred square light-sensitive area of ``fill_factor`` of the pixel: ``sinc·sinc``.

    Parameters
    ----------
    fx_cy_per_px, fy_cy_per_px : array_like
        Frequencies, cycles/pixel (broadcast together).
    fill_factor : float
        The area's share of the pixel (its side √fill_factor pixels).

    Returns
    -------
    ndarray
        Signed (negative beyond the first zero).
    """
    a = float(np.sqrt(fill_factor))
    return np.sinc(np.asarray(fx_cy_per_px) * a) * np.sinc(np.asarray(fy_cy_per_px) * a)


def channel_mtf_closed_form(f_cy_per_px: ArrayLike, angle_deg: float, pitch_um: float, f_number: float,
                            wavelengths_nm: Sequence[float], weights: ArrayLike, fill_factor: float = 1.0,
                            olpf_separation_px: float = 0.0) -> np.ndarray:
    """The MTF a channel should show along the normal of an edge ``angle_deg`` from a pixel axis: the
    circular-aperture OTF at each band weighted by the channel's signal in that band (``weights``,
    e.g. band weight × the edge's radiance step), times the pixel aperture's sinc (and the optical
    low-pass filter's cosines) along that direction.

    Parameters
    ----------
    f_cy_per_px : array_like
        Frequencies along the edge's normal, cycles/pixel.
    angle_deg : float
        The normal's angle from the pixel's x axis, degrees.
    pitch_um : float
        µm.
    f_number : float
    wavelengths_nm : sequence of float
        The bands' wavelengths, nm.
    weights : array_like
        ``(B,)`` the channel's signal per band.
    fill_factor : float
    olpf_separation_px : float
        0: no low-pass filter.

    Returns
    -------
    ndarray
        ``f``'s shape, the MTF (≥ 0).
    """
    f = np.asarray(f_cy_per_px, float)
    w = np.asarray(weights, float)
    otf = np.stack([diffraction_otf(f / pitch_um, lam, f_number) for lam in wavelengths_nm])  # (B, F)
    t = np.radians(angle_deg)
    fx, fy = f * np.cos(t), f * np.sin(t)
    return (w @ otf) / w.sum() * np.abs(aperture_mtf(fx, fy, fill_factor) * olpf_otf(fx, fy, olpf_separation_px))


@dataclass(frozen=True)
class OpticsSettings:
    """The spatial optics of one camera: what :func:`pixel_rates` applies."""

    diffraction: bool = True
    #: Blur-disc diameter of a thin lens's defocus still to apply, µm (0: in focus, or rendered).
    defocus_um: float = 0.0
    cos4: bool = False
    #: Per channel (in the architecture's order): where that channel's sensor samples, (dx, dy) pixels,
    #: x right, y down; channels beyond the tuple sample at the pixel centre.
    shifts_px: tuple = ()
    #: Spot separation of a 4-spot birefringent optical low-pass filter, pixels (0: none, the paper's camera).
    olpf_separation_px: float = 0.0


def channel_spectra(radiance: np.ndarray, wavelengths_nm: Sequence[float], supersampling: int, camera: CameraSpec,
                    grid: WavelengthGrid, settings: OpticsSettings, workers: int | None = None,
                    weights: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[int, int]]:
    """The 2-D spectra ``(N, Hs, Ws//2+1)`` of each channel's photo-electron rate image after the
    per-band optics (diffraction, defocus), before the pixel aperture; ``(spectra, fy, fx, (Hs, Ws))``
    with the frequencies in cycles per sub-pixel.  ``weights`` ``(B, N)``: band weights to use instead
    of the camera's own (several architectures' channels at once share the per-band transforms).

    Parameters
    ----------
    radiance : ndarray
        ``(Hs, Ws, B)`` sub-pixel radiance, W·m⁻²·sr⁻¹·nm⁻¹.
    wavelengths_nm : sequence of float
        The bands' wavelengths, nm.
    supersampling : int
        Sub-pixels per pixel along each axis.
    camera : CameraSpec
        Its pixel pitch (µm), f-number and band weights.
    grid : WavelengthGrid
    settings : OpticsSettings
        Diffraction on or off, defocus (µm).
    workers : int or None
        scipy.fft's workers.
    weights : ndarray or None
        ``(B, N)``; None: the camera's.

    Returns
    -------
    tuple
        ``(spectra, fy, fx, (Hs, Ws))``.
    """
    Hs, Ws, B = radiance.shape
    pitch = camera.sensor.pixel_pitch_um
    s_um = pitch / supersampling
    fy = sfft.fftfreq(Hs)[:, None]
    fx = sfft.rfftfreq(Ws)[None, :]
    rho = np.sqrt(fx**2 + fy**2) / s_um                           # cycles/µm
    W = np.asarray(band_weights(camera, grid) if weights is None else weights, np.float64)   # (B, N)
    common = defocus_otf(rho, settings.defocus_um) if settings.defocus_um > 0 else None
    out = np.zeros((W.shape[1], Hs, fx.shape[1]), np.complex128)
    chunk = 8
    for b0 in range(0, B, chunk):
        bands = range(b0, min(B, b0 + chunk))
        F = sfft.rfft2(radiance[:, :, b0:bands.stop], axes=(0, 1), workers=workers)   # (Hs, Wf, nb)
        for i, b in enumerate(bands):
            H = diffraction_otf(rho, wavelengths_nm[b], camera.optics.f_number) if settings.diffraction else 1.0
            if common is not None:
                H = H * common
            Fb = F[:, :, i] * H
            for k in range(W.shape[1]):
                if W[b, k] != 0.0:
                    out[k] += W[b, k] * Fb
    return out, fy, fx, (Hs, Ws)


def sample_channels(spectra: np.ndarray, fy: np.ndarray, fx: np.ndarray, shape: tuple[int, int], supersampling: int,
                    fill_factor: float, shifts_px: Sequence[tuple[float, float]], margin_px: int,
                    workers: int | None = None, olpf_separation_px: float = 0.0) -> np.ndarray:
    """``(H, W, N)`` rates: each channel's spectrum through the optical low-pass filter (if any) and the
    pixel aperture, shifted to its sampling positions (``shifts_px`` per channel, missing ones 0),
    back to space and sampled at the pixel centres; ``margin_px`` cut from every side.

    Parameters
    ----------
    spectra, fy, fx : ndarray
        :func:`channel_spectra`'s spectra and frequencies (cycles per sub-pixel).
    shape : tuple of int
        ``(Hs, Ws)``.
    supersampling : int
    fill_factor : float
        The pixel aperture's share of the pixel.
    shifts_px : sequence of (float, float)
        Per channel ``(dx, dy)`` px.
    margin_px : int
    workers : int or None
    olpf_separation_px : float
        0: no low-pass filter.

    Returns
    -------
    ndarray
        ``(H, W, N)`` float32, e⁻/s.
    """
    ss = supersampling
    aperture = aperture_mtf(fx * ss, fy * ss, fill_factor) / (np.sinc(fx) * np.sinc(fy))
    if olpf_separation_px > 0:
        aperture = aperture * olpf_otf(fx * ss, fy * ss, olpf_separation_px)
    out = []
    for k in range(len(spectra)):
        dx, dy = shifts_px[k] if k < len(shifts_px) else (0.0, 0.0)
        delta_x = (ss - 1) / 2 + dx * ss       # sub-pixels from sample index j·ss to the sampling point
        delta_y = (ss - 1) / 2 + dy * ss
        phase = np.exp(2j * np.pi * (fx * delta_x + fy * delta_y))
        img = sfft.irfft2(spectra[k] * aperture * phase, s=shape, workers=workers)
        px = img[::ss, ::ss]
        out.append(px[margin_px:px.shape[0] - margin_px, margin_px:px.shape[1] - margin_px])
    return np.ascontiguousarray(np.stack(out, axis=-1), np.float32)


def pixel_rates(radiance: np.ndarray, wavelengths_nm: Sequence[float], supersampling: int, camera: CameraSpec,
                grid: WavelengthGrid, geometry: CameraGeometry, settings: OpticsSettings = OpticsSettings(),
                margin_px: int = MARGIN_PX, workers: int | None = None) -> np.ndarray:
    """``(H, W, N)`` photo-electrons per second per pixel of each channel (float32) from the sub-pixel
    radiance ``(Hs, Ws, B)`` of an image with ``margin_px`` extra pixels on every side; ``geometry`` is
    the camera without the margin (for cos⁴).

    Parameters
    ----------
    radiance : ndarray
        ``(Hs, Ws, B)`` W·m⁻²·sr⁻¹·nm⁻¹.
    wavelengths_nm : sequence of float
    supersampling : int
    camera : CameraSpec
    grid : WavelengthGrid
    geometry : CameraGeometry
    settings : OpticsSettings
    margin_px : int
    workers : int or None
        scipy.fft's workers.

    Returns
    -------
    ndarray
        ``(H, W, N)`` float32, e⁻/s.
    """
    spectra, fy, fx, shape = channel_spectra(radiance, wavelengths_nm, supersampling, camera, grid, settings, workers)
    rates = sample_channels(spectra, fy, fx, shape, supersampling, camera.sensor.fill_factor, settings.shifts_px, margin_px,
                            workers, settings.olpf_separation_px)
    if settings.cos4:
        rates *= geometry.off_axis_cos4()[:, :, None].astype(np.float32)
    return rates
