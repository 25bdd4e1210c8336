"""The camera's response across the field (issue 37, items 2 and 3): each tile site's band weights at each chief-ray
angle, and each pixel's photo-electron rate from them.

On the axis a pixel records its radiance times :func:`~spectracam.camera.band_weights`.  Off the axis the chief ray
reaches it at an angle θ (the lens's chief-ray angle, :func:`spectracam.optics.field.field_maps`) in the direction φ
of its image height, and what it records changes:

* a **mosaic** (one sensor behind a colour filter array): its own channel's responsivity × the microlens's
  acceptance, mixed with its neighbours' by the crosstalk kernel
  (:func:`~spectracam.sensor.angle.pixel_angle_response`, :func:`~spectracam.sensor.angle.effective_responsivities`:
  a locally uniform scene); with ``pixel.filter_angle`` the dyes absorb along the longer oblique path
  (:func:`~spectracam.architecture.angle.dye_transmittance`);
* **planes** (a prism's three sensors, a field-sequential sensor's frames, stacked photodiodes): every pixel of a plane
  is the same channel, so crosstalk mixes no colours — only the acceptance and the charge the silicon keeps (the
  kernel's sum) remain; with ``pixel.filter_angle`` the prism's dichroic coatings
  (:func:`~spectracam.architecture.angle.prism_incidence_deg`, :func:`~spectracam.architecture.angle.shift_curve`)
  and the wheel's interference filters (:func:`~spectracam.architecture.angle.wheel_filter_curve`, untilted) move to
  shorter wavelengths.  Stacked photodiodes keep their depths' responsivities.

The weights are tabulated on bins of θ (and of φ when the pixel's response depends on the direction) and
interpolated linearly between neighbouring bins, as ``w = w₀ + f·(w₁ − w₀)``, so a pixel that sits on a bin — the
centre at θ = 0 — gets that bin's weights exactly; at θ = 0 they are :func:`~spectracam.camera.band_weights`' own.
A filter's transmittance is read as its responsivity over the unfiltered pixel's
(:func:`~spectracam.architecture.filters.clear_responsivity`).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from spectracam.architecture.angle import (N_PRISM_GLASS, dye_transmittance, prism_incidence_deg, shift_curve,
                                           wheel_filter_curve)
from spectracam.architecture.base import MosaicLayout
from spectracam.architecture.filters import clear_responsivity
from spectracam.architecture.silicon import absorption_coefficient_per_um, refractive_index
from spectracam.camera import CameraSpec, camera_responsivities
from spectracam.optics import radiance_to_photon_irradiance
from spectracam.sensor.angle import effective_responsivities, microlens_shift_um, pixel_angle_response

if TYPE_CHECKING:
    from spectracam.architecture.base import PlanesLayout
    from spectracam.core.spectra import WavelengthGrid
    from spectracam.optics.field import FieldMaps

__all__ = ["AZIMUTH_BINS", "CRA_BINS", "field_active", "field_band_weights", "field_rates", "metered_field_rates",
           "site_index"]

#: Chief-ray-angle bins from 0 to the image's largest CRA.
CRA_BINS = 32
#: Azimuth bins over the full turn, when the pixel's response depends on the direction of the image height.
AZIMUTH_BINS = 16
#: Tables already computed: (camera, grid, bins) → weights.
_CACHE: dict = {}
_CACHE_SIZE = 16
#: Pixels per chunk of the per-pixel interpolation (bounds its memory).
_CHUNK_PIXELS = 1 << 16


def field_active(camera: CameraSpec, cra_deg: np.ndarray | None) -> bool:
    """Whether a capture must weight each pixel with its own field position.

    Parameters
    ----------
    camera : CameraSpec
        The camera (its ``pixel`` table).
    cra_deg : ndarray or None
        The image's chief-ray-angle map, degrees (None: on the axis).

    Returns
    -------
    bool
        True when the pixel's angle response is on or the chief ray is oblique somewhere.
    """
    return camera.pixel.any_on or (cra_deg is not None and float(np.max(cra_deg)) > 0)


def _filter_at_angle(camera: CameraSpec, grid, R: np.ndarray, cra: np.ndarray, layout) -> np.ndarray:
    """``(n_cra, N, B)`` the channels' responsivities with their filters at each chief-ray angle (θ = 0: ``R``)."""
    out = np.broadcast_to(R, (cra.size, *R.shape)).copy()
    kind = getattr(layout, "kind", None)
    if not camera.pixel.filter_angle or kind == "layers" or not np.any(cra > 0):
        return out
    clear = clear_responsivity(camera.filters, grid)
    T = np.divide(R, clear, out=np.zeros_like(R), where=clear > 0)
    wl = np.asarray(grid.centres_nm, float)
    if isinstance(layout, MosaicLayout):
        shifted = dye_transmittance(np.clip(T, 0.0, 1.0), cra[:, None])           # (n_cra, N, B)
    elif kind == "sensors":
        aoi = prism_incidence_deg(cra)
        shifted = np.stack([shift_curve(wl, T[k], aoi, n0=N_PRISM_GLASS) for k in range(len(R))], axis=1)
    else:
        shifted = np.stack([wheel_filter_curve(wl, T[k], 0.0, cra) for k in range(len(R))], axis=1)
    oblique = (cra > 0)[:, None, None]
    return np.where(oblique, shifted * clear, out)


def _angle_kernels(camera: CameraSpec, grid, cra: np.ndarray, azimuth: np.ndarray) -> np.ndarray:
    """``(n_cra, n_az, B, 3, 3)`` the pixel's transfer (acceptance × crosstalk) at each bin."""
    spec, wl = camera.pixel, np.asarray(grid.centres_nm, float)
    theta = np.broadcast_to(cra[:, None], (cra.size, azimuth.size))
    shift = spec.microlens_shift_fraction * microlens_shift_um(theta, spec)
    return pixel_angle_response(theta, wl, absorption_coefficient_per_um(wl), refractive_index(wl), spec,
                                pixel_pitch_um=camera.sensor.pixel_pitch_um,
                                collection_depth_um=camera.filters.collection_depth_um,
                                f_number=camera.optics.f_number, shift_um=shift,
                                azimuth_deg=np.broadcast_to(azimuth[None, :], theta.shape))


def _modelled(camera: CameraSpec, grid, R: np.ndarray, cra: np.ndarray, azimuth: np.ndarray, layout) -> np.ndarray:
    """``(n_cra, n_az, K, B)`` what each site (or plane) records per band by the pixel's model (filters at the angle,
    acceptance × crosstalk), before its normalisation to the measured responsivities."""
    R_theta = _filter_at_angle(camera, grid, R, cra, layout)                      # (n_cra, N, B)
    kernel = _angle_kernels(camera, grid, cra, azimuth)                           # (n_cra, n_az, B, 3, 3)
    if isinstance(layout, MosaicLayout):
        th, tw = layout.tile_shape
        eff = np.stack([effective_responsivities(layout.tile, R_theta[i], kernel[i]) for i in range(cra.size)])
        return eff.reshape(cra.size, azimuth.size, th * tw, -1)                  # (n_cra, n_az, K, B)
    return R_theta[:, None, :, :] * kernel.sum((-2, -1))[:, :, None, :]          # (n_cra, n_az, N, B)


def _compute_weights(camera: CameraSpec, grid, cra: np.ndarray, azimuth: np.ndarray) -> np.ndarray:
    """The table of :func:`field_band_weights`.  The camera's responsivities R_k(λ) are its pixel's at normal
    incidence, as a sensor's quantum efficiency is measured (EMVA 1288 illuminates the sensor on the axis with a beam
    of f/8 or slower); the model m(θ) gives how what each site records changes with the angle, so each site's weights
    are ``w(θ) = R_site + m(θ) − m(0)`` (never below 0), band by band.  Where the model alone changes nothing at
    normal incidence (microlens, optical crosstalk) this is m(θ) itself; electrical crosstalk, which mixes charge at
    every angle, is then counted only as its change with the angle, and the tile's charge total is kept as the model
    keeps it (unless the clip at 0 acts).  A first-order correction: the normal-incidence crosstalk the measured R
    holds is not scaled down with the microlens's acceptance at the corner (an error of about (1 − a)·(R − m(0)) for
    acceptance a; nothing where electrical crosstalk is off)."""
    layout = camera.architecture().layout
    R = np.asarray(camera_responsivities(camera, grid), float)                    # (N, B)
    per_site = _modelled(camera, grid, R, cra, azimuth, layout)
    normal = _modelled(camera, grid, R, np.zeros(1), azimuth, layout)[0]         # (n_az, K, B)
    if isinstance(layout, MosaicLayout):
        nominal = R[np.asarray([k for row in layout.tile for k in row])]          # (K, B): each site's channel
    else:
        nominal = R
    per_site = np.maximum(per_site + (nominal[None] - normal)[None], 0.0)
    per_site[cra == 0] = nominal                                                   # exactly, at normal incidence
    factor = radiance_to_photon_irradiance(grid, camera.optics) * grid.widths_nm * (
        camera.sensor.pixel_area_um2 * 1e-12)
    return np.swapaxes(per_site * factor, -1, -2).astype(np.float32)


def field_band_weights(camera: CameraSpec, grid: WavelengthGrid, cra_deg_bins: ArrayLike,
                       azimuth_deg_bins: ArrayLike = (0.0,)) -> np.ndarray:
    """Band weights of each tile site (or plane) at each chief-ray angle and azimuth.

    Parameters
    ----------
    camera : CameraSpec
        The camera: its architecture's layout, filters, optics, sensor and ``pixel`` table.
    grid : WavelengthGrid
        The bands of the radiance.
    cra_deg_bins : array_like
        ``(n_cra,)`` chief-ray angles, degrees, in [0, 90).
    azimuth_deg_bins : array_like
        ``(n_az,)`` directions of the image height, degrees (0: along a row, towards increasing column).

    Returns
    -------
    ndarray
        ``(n_cra, n_az, n_bands, K)`` float32: for a mosaic, ``K`` tile sites in row order (site ``dy·tw + dx``), each
        weighting the radiance into what that site records; for planes, ``K = N`` channels.  Where θ = 0 every
        column is :func:`~spectracam.camera.band_weights`' column of its channel, exactly.

    References
    ----------
    .. [Agranov2003] see docs/references.md (crosstalk and the CFA's colour mixing).
    .. [Smith2008] see docs/references.md (the coating's shift with angle).
    """
    cra = np.atleast_1d(np.asarray(cra_deg_bins, float))
    azimuth = np.atleast_1d(np.asarray(azimuth_deg_bins, float))
    key = (camera, np.asarray(grid.centres_nm, float).tobytes(), np.asarray(grid.widths_nm, float).tobytes(),
           cra.tobytes(), azimuth.tobytes())
    if key not in _CACHE:
        if len(_CACHE) >= _CACHE_SIZE:
            _CACHE.pop(next(iter(_CACHE)))
        table = _compute_weights(camera, grid, cra, azimuth)
        table.setflags(write=False)
        _CACHE[key] = table
    return _CACHE[key]


def site_index(layout: MosaicLayout | PlanesLayout, shape: tuple[int, int]) -> np.ndarray | None:
    """Each pixel's tile site in a mosaic layout.

    Parameters
    ----------
    layout : MosaicLayout or PlanesLayout
        The architecture's layout.
    shape : tuple of int
        ``(H, W)`` pixels.

    Returns
    -------
    ndarray or None
        ``(H, W)`` int64 site ``dy·tw + dx`` (the column of :func:`field_band_weights`); None for planes.
    """
    if not isinstance(layout, MosaicLayout):
        return None
    th, tw = layout.tile_shape
    rows, cols = np.arange(shape[0]) % th, np.arange(shape[1]) % tw
    return (rows[:, None] * tw + cols[None, :]).astype(np.int64)


def _bins(cra_deg: np.ndarray, azimuth_deg: np.ndarray, n_az: int):
    """The bin tables and each pixel's neighbouring bins and fractions: ``(cra bins, az bins, (c0, c1, fc),
    (a0, a1, fa))``."""
    top = float(cra_deg.max())
    cra_bins = np.linspace(0.0, top, CRA_BINS) if top > 0 else np.zeros(1)
    u = cra_deg / (top / (CRA_BINS - 1)) if top > 0 else np.zeros_like(cra_deg)
    c0 = np.clip(np.floor(u).astype(np.int64), 0, cra_bins.size - 1)
    c1 = np.minimum(c0 + 1, cra_bins.size - 1)
    fc = np.where(c1 > c0, u - c0, 0.0)
    step = 360.0 / n_az
    az_bins = -180.0 + step * np.arange(n_az)
    v = (azimuth_deg + 180.0) / step
    a0 = np.floor(v).astype(np.int64) % n_az
    a1 = (a0 + 1) % n_az
    fa = (v - np.floor(v)) if n_az > 1 else np.zeros_like(v)
    return cra_bins, az_bins, (c0, c1, fc), (a0, a1, fa)


def _interpolated_rates(radiance, table, sites, cra_idx, az_idx) -> np.ndarray:
    """Each pixel's rate(s): its radiance · the weights of its site (or every plane) interpolated between bins."""
    h, w, b = radiance.shape
    flat = radiance.reshape(-1, b)
    (c0, c1, fc), (a0, a1, fa) = [tuple(np.ravel(x) for x in t) for t in (cra_idx, az_idx)]
    s = None if sites is None else sites.ravel()
    k = table.shape[-1]
    out = np.empty((h * w,) if s is not None else (h * w, k), np.float32)
    for lo in range(0, h * w, _CHUNK_PIXELS):
        p = slice(lo, min(lo + _CHUNK_PIXELS, h * w))

        def pick(ci, ai):
            return table[ci[p], ai[p], :, s[p]] if s is not None else table[ci[p], ai[p]]

        f_a = fa[p].astype(np.float32)[:, None] if s is not None else fa[p].astype(np.float32)[:, None, None]
        f_c = fc[p].astype(np.float32).reshape(f_a.shape)
        lo_w = pick(c0, a0) + f_a * (pick(c0, a1) - pick(c0, a0))
        hi_w = pick(c1, a0) + f_a * (pick(c1, a1) - pick(c1, a0))
        wts = lo_w + f_c * (hi_w - lo_w)
        rad = flat[p].astype(np.float32, copy=False)
        out[p] = np.einsum("pb,pb->p", rad, wts) if s is not None else np.einsum("pb,pbk->pk", rad, wts)
    return out.reshape((h, w) if s is not None else (h, w, k))


def field_rates(radiance: np.ndarray, grid: WavelengthGrid, camera: CameraSpec, maps: FieldMaps | None) -> np.ndarray:
    """Photo-electron rates of each pixel at its place in the field.

    Parameters
    ----------
    radiance : ndarray
        ``(H, W, n_bands)`` radiance as the sensor receives it (already shaded by the relative illumination).
    grid : WavelengthGrid
        Its bands.
    camera : CameraSpec
        The camera.
    maps : FieldMaps or None
        The field's per-pixel maps (:func:`spectracam.optics.field.field_maps`); None: every pixel on the axis.

    Returns
    -------
    ndarray
        ``(H, W, N)`` float32 photo-electrons per second: for planes every channel of every pixel; for a mosaic each
        pixel's own channel (the one its site records, with its neighbours' light mixed in), the others 0 — the
        array an architecture's ``record`` samples.

    References
    ----------
    .. [Agranov2003] see docs/references.md.
    """
    h, w, _ = radiance.shape
    cra = np.zeros((h, w)) if maps is None else maps.cra_deg
    azimuth = np.zeros((h, w)) if maps is None else np.degrees(np.arctan2(maps.y_mm, maps.x_mm))
    layout = camera.architecture().layout
    n_az = AZIMUTH_BINS if camera.pixel.any_on else 1
    cra_bins, az_bins, cra_idx, az_idx = _bins(cra, azimuth, n_az)
    table = field_band_weights(camera, grid, cra_bins, az_bins)
    sites = site_index(layout, (h, w))
    rates = _interpolated_rates(radiance, table, sites, cra_idx, az_idx)
    if sites is None:
        return rates
    channel = np.asarray([k for row in layout.tile for k in row])[sites]
    out = np.zeros((h, w, len(layout.channels)), np.float32)
    np.put_along_axis(out, channel[..., None], rates[..., None], axis=-1)
    return out


def metered_field_rates(rates: np.ndarray, box: tuple[slice, slice], layout: MosaicLayout | PlanesLayout) -> np.ndarray:
    """The mean rate of each channel over a box of pixels (the white patch), from per-pixel rates
    (:func:`field_rates`): in a mosaic the mean over the box's pixels that record the channel.

    Parameters
    ----------
    rates : ndarray
        ``(H, W, N)`` per-pixel rates.
    box : tuple of slice
        Rows and columns of the box.
    layout : MosaicLayout or PlanesLayout
        The architecture's layout.

    Returns
    -------
    ndarray
        ``(N,)`` float64 mean rates.
    """
    part = rates[box].astype(np.float64)
    if not isinstance(layout, MosaicLayout):
        return part.mean(axis=(0, 1))
    channel = layout.channel_index(rates.shape[:2])[box]
    return np.array([part[..., k][channel == k].mean() if np.any(channel == k) else part[..., k].mean()
                     for k in range(rates.shape[-1])])
