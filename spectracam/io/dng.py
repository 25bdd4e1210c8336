"""Adobe DNG 1.4 for every capture, so ordinary raw developers (LibRaw, darktable, RawTherapee) develop it right.

Written with tifffile as one uncompressed image: a colour-filter-array mosaic (PhotometricInterpretation
32803, CFA tags; any tile of the DNG CFA colours R, G, B, C, M, Y, W — RYYB, CYYM and the four-colour
RGBW among them, with ``CFAPlaneColor`` naming the planes) or, for full planes (prism,
field-sequential, stacked, and :func:`dng_image`'s RGBW), LinearRaw (34892, one sample per plane; DNG
has three or four colour planes, so other counts have no DNG form).  With N colour planes each
``ColorMatrix`` is N×3 and ``AsShotNeutral`` N long (DNG 1.4: ColorPlanes × 3).  Tags:

* Levels.  A CFA mosaic holds the ADC's codes: ``BlackLevel`` = the sensor's pedestal
  (``camera.sensor.black_level_dn``), ``WhiteLevel`` = 2ⁿ − 1.  LinearRaw holds the codes *minus the pedestal*
  (its whole DN, :func:`linear_raw_pedestal`), clipped at 0: ``BlackLevel`` 0 (or the pedestal's fraction of a
  DN), ``WhiteLevel`` = 2ⁿ − 1 − pedestal (:func:`dng_levels`).  Why: darktable 4.2 does not subtract a LinearRaw
  file's ``BlackLevel`` (its rawspeed "sraw" path scales by the white level only), so a pedestal left in the
  pixels is developed as signal, and the white balance multiplies it unequally: with the default 8-bit camera at
  3000 K the chart's black developed at L* 28.5 for 20.8 (prism/optimal), and a prism/single capture (its blue
  channel weak, so multiplied most) with a cast growing toward the black, a* −1.9 → −9.0 and b* −2.6 → −5.6 from
  grey 20 to the black.  What it costs: noise below the pedestal is clipped at 0 instead of kept negative, which
  raises the mean of the darkest pixels.  On the chart's darkest grey (black 2, ~3 % reflectance) of the default
  8-bit camera with prism/optimal or fsc/optimal exposures every channel holds ≥ 7.8 DN there and the clip adds
  ≤ 0.001 DN: nothing.  It matters only where a channel holds about a DN: prism/single's blue at 3000 K (1.3 DN)
  gains 0.64 DN and fsc/balanced's channels at 3000 K (0.9 DN) 0.73–0.76 DN — the camera's rendering of that
  patch moves from b* +6.4 to −4.5, or from L* −6.7 to +4.4, against its noise-free rendering (the flooring ADC's
  half code is the other half of it; ``tools/dng_developers.py`` prints this per capture).  LibRaw clips the same
  way after subtracting any ``BlackLevel``, so its development of the black did not change (fsc/balanced at
  3000 K: L* 25.91 before, 25.90 after).  raw.exr keeps the codes unclipped.  CFA files keep the pedestal in the
  pixels and in ``BlackLevel``: darktable subtracts it there (the black at 3000 K: L* 20.18 in darktable, 19.96
  in LibRaw, 20.28 in RawTherapee, the scene 20.83).
* ``AsShotNeutral`` = the camera's response to the scene white: the expected photo-electrons of each
  channel for a perfect white diffuser under the scene illuminant with the capture's exposure times,
  normalised to a maximum of 1 (for a prism or field-sequential capture with optimal exposures it is
  close to (1, 1, 1): the exposures, metered on the white patch, already balance the white).
* Two calibrations, always the same two standard illuminants whatever the scene's light:
  ``ColorMatrix1`` for CIE Standard Illuminant A (``CalibrationIlluminant1`` = 17) and ``ColorMatrix2`` for D65
  (``CalibrationIlluminant2`` = 21).  Each is XYZ → camera under *its* illuminant: the inverse of the
  least-squares fit, on the chart reference's 24 patches lit by that illuminant (same chart, wavelength grid
  and level as the scene), from the camera's noise-free responses — with the capture's own per-channel exposure
  times, since a prism or field-sequential capture gives its channels different times and the matrix lives in
  the file's raw camera space — to the patches' CIE 1931 XYZ, constrained so that the camera's white under that
  illuminant maps exactly onto the illuminant's white (N×3 for other than three planes: the fit from XYZ to the
  camera, the white kept the same way).  Each is then scaled as the DNG SDK does on reading
  (``dng_camera_profile::NormalizeColorMatrix``): the largest camera value of D50's white (the profile
  connection space, xy 0.3457, 0.3585) is 1, so readers that interpolate the two element by element (by
  inverse correlated colour temperature, as DNG 1.2+ asks) blend matrices of the same scale.  Before issue 23
  one matrix was written, fitted under the scene's light, with ``CalibrationIlluminant1`` = the scene's EXIF
  code — 255, "other", for a blackbody — which darktable 4.2 cannot use (see below).
* ``Make`` "spectracam", ``Model`` "simulated <design> sensor", ``UniqueCameraModel``; in an Exif IFD
  (where LibRaw, exiv2 and exiftool look for them) ``ExposureTime`` (the capture time), ``FNumber``,
  ``ISOSpeedRatings`` with ``SensitivityType`` 3 (ISO speed): ISO 12232's saturation-based speed
  ``S_sat = 78/H_sat``, ``H_sat = k_v·L_sat·t`` lux·s, the focal-plane exposure of the luminance that
  first fills a channel (:func:`saturation_exposure_lux_s`); ``DateTime`` and, in the Exif IFD,
  ``DateTimeOriginal``/``DateTimeDigitized`` with ``OffsetTime*`` "+00:00": when the file was written, UTC, or
  ``SOURCE_DATE_EPOCH`` where set (:func:`capture_datetime`).

What each developer does with these (``tools/dng_developers.py`` develops the default camera's cfa/single,
prism/optimal and fsc/optimal captures of the chart at 3000 K and 6500 K in all three; none of the three reads
``ColorMatrix1`` — replacing it by the identity leaves their output bit for bit the same — it is there for
readers that interpolate between the calibrations, as the DNG SDK does):

* LibRaw (0.22; ``src/metadata/tiff.cpp``, ``utils_dcraw.cpp``) keeps the last ``ColorMatrix`` it parses —
  ``ColorMatrix2``, the D65 one, which is what it assumes (``cam_xyz_coeff``: rows normalised so that sRGB's D65
  white gives camera (1, 1, 1)); with ``use_camera_wb`` it multiplies each channel by ``1/AsShotNeutral`` (a
  von Kries step in camera space that carries the as-shot white onto D65), then applies the inverse of the
  normalised matrix.  So the scene white always develops neutral; the other colours are adapted to D65 in the
  camera's own channel space.  It subtracts ``BlackLevel`` from CFA and LinearRaw alike, clipping at 0.
* darktable 4.2 (``src/common/exif.cc``) reads the matrices through exiv2 and takes the one whose
  ``CalibrationIlluminant`` is D65 (else the nearest above, carried to D65 with a Bradford matrix).  It has
  none for 255, "other": with the old single matrix the same file developed differently from run to run (28 of
  30 runs alike, legacy chromatic adaptation) and, with ``chromatic-adaptation=modern``, with the greys at
  a* −92…+137, b* −212…+88 (NaN for the CFA).  Legacy chromatic adaptation (what Debian's darktablerc ships)
  white-balances with ``AsShotNeutral`` and converts with ``ColorMatrix2`` as LibRaw does: on LinearRaw (no
  demosaicking to differ) its greys 20–24 match LibRaw's within 0.02.  Modern white-balances to the D65
  "camera reference" of ``ColorMatrix2`` and lets color calibration adapt from the illuminant it derives from
  ``AsShotNeutral``; there the white patch, metered to 95 % of the well, develops clipped, and darktable's
  highlight reconstruction makes a pixel or so of it differ between runs (16 and 20 of 30 alike in two series
  at prism/optimal 3000 K; a copy of the fsc/optimal file with every code halved develops identically 10 times of 10: it is the
  clipping, not the file).  It subtracts ``BlackLevel`` from CFA mosaics, not from LinearRaw (hence the levels
  above).
* RawTherapee 5.9 reads ``ColorMatrix2`` through its dcraw fork and the as-shot neutral for its "camera" white
  balance, and subtracts ``BlackLevel`` from CFA and LinearRaw alike: on LinearRaw its greys 20–24 match
  LibRaw's within 0.02.  It refused ("Error loading file") the CFA DNGs of 160×120, 200×150, 240×180, 256×120
  and 320×64 px and loaded 255×240, 256×192 and larger; LinearRaw of 160×120 loads.

What no file can change (the camera's own colour error on the chart's white, the developers' clip of
negative noise on a CFA's weak channel) and what the standard illuminants cost (all three developers convert
with the D65 matrix whatever the light) are measured by ``tools/dng_developers.py``; the figures are in the
user guide (`docs/guide/commands.md`, "Raw developers").

``ForwardMatrix1``/``ForwardMatrix2`` (issue 33; :func:`forward_matrices`) are written for readers that use them
(the DNG SDK, Adobe's converters, RawTherapee's DCP path): LibRaw parses them but does not use them, and darktable's
matrix path does not read them.  ``AsShotNeutral`` is the oracle's (the true white) for the oracle camera and the
camera's own estimate for a camera that finds its white (``processing.camera = "developed"``).  LibRaw reads ``BlackLevel`` as an integer (a fractional one is truncated); the pedestal
is written as the integer the ADC adds (see ``mid_step`` below for the half code a flooring ADC leaves).

``mid_step`` (:func:`write_dng`): add a ``LinearizationTable`` mapping pixel value p to ``2·p + 1`` (BlackLevel
``2·b``, WhiteLevel ``2ⁿ⁺¹ − 1``; LinearRaw: ``2·(b − ⌊b⌋)`` and ``2·(2ⁿ − 1 − ⌊b⌋) + 1``), so developers take each
code at the centre of its quantisation step, as :func:`~spectracam.sensor.adc_inverse` does.  The ADC floors, so a
code's mean signal is half a DN above its value; with few DN per channel (8 bits, dark patches, a channel that a
white balance multiplies by 2) that half DN tints greys — about +0.2 b* on the chart's light greys of an 8-bit CFA
at 5000 K.  Off by default: BlackLevel and WhiteLevel are then the ADC's own codes (LinearRaw: less the pedestal),
and LibRaw's ``raw_image`` the digital numbers themselves (of a CFA).  Only for ADCs of up to 15 bits.

References
----------
.. [DNG1.4] see docs/references.md; the file format, its camera-profile tags (chapter 6).
.. [ISO12232] see docs/references.md; the saturation-based ISO speed.
"""
from __future__ import annotations

import io
import json
import struct
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from spectracam._version import __version__
from spectracam.architecture.base import MosaicLayout, PlanesLayout
from spectracam.camera.capture import RawCapture
from spectracam.core.errors import SpectracamError
from spectracam.processing.calibration import D50_XYZ, constrained_lstsq, white_neutral  # D50: the DNG SDK's normalisation
from spectracam.core.files import atomic_write

if TYPE_CHECKING:
    import datetime

    from spectracam.camera import CameraSpec
    from spectracam.scene.reference import ChartReference

__all__ = ["CALIBRATION_ILLUMINANTS", "DNG_MAX_BITS", "EXIF_DATETIME", "ISO_SATURATION_CONSTANT", "MAKE",
           "as_shot_neutral", "calibration_reference", "camera_model", "camera_patches", "camera_to_xyz_matrix",
           "camera_white", "capture_datetime", "color_matrices", "dng_image", "dng_levels", "dng_tags", "exif_entries",
           "forward_matrices", "linear_raw_pedestal", "normalise_color_matrix", "saturation_exposure_lux_s",
           "saturation_iso", "white_radiance", "white_rates", "write_dng", "xyz_to_camera_matrix"]

#: DNG CFAPattern colour codes.
_CFA_CODE = {"R": 0, "G": 1, "B": 2, "C": 3, "M": 4, "Y": 5, "W": 6}
#: The DNG calibrations, ``(colour-science illuminant name, EXIF LightSource code)``: ColorMatrix1 under CIE
#: Standard Illuminant A (17), ColorMatrix2 under D65 (21), whatever the scene's light.
CALIBRATION_ILLUMINANTS = (("A", 17), ("D65", 21))
#: The Make tag of every file spectracam writes.
MAKE = "spectracam"
#: ISO 12232 saturation-based speed constant: S_sat = 78 / H_sat (H_sat in lux·s).
ISO_SATURATION_CONSTANT = 78.0


def camera_model(raw: RawCapture) -> str:
    """The Model tag: ``"simulated cfa/single sensor"``.

    Parameters
    ----------
    raw : RawCapture
        The capture (its design).

    Returns
    -------
    str
        ``"simulated <architecture>/<exposure> sensor"``.
    """
    return f"simulated {raw.design} sensor"


def white_radiance(reference: ChartReference) -> np.ndarray:
    """Band-averaged radiance ``(B,)`` of a perfect white diffuser under the scene illuminant, E/π.

    Parameters
    ----------
    reference : ChartReference
        The chart reference of the scene (its illuminant, grid and patches).

    Returns
    -------
    ndarray
        ``(B,)`` W·m⁻²·sr⁻¹·nm⁻¹.
    """
    from spectracam.scene.illuminant import white_diffuser_radiance

    return white_diffuser_radiance(reference.illuminant, reference.grid)


def white_rates(camera: CameraSpec, reference: ChartReference) -> np.ndarray:
    """Noise-free photo-electron rates ``(N,)`` (e⁻/s) of a perfect white diffuser under the scene
    illuminant (no dark charge): :func:`spectracam.processing.calibration.white_neutral`.

    Parameters
    ----------
    camera : CameraSpec
        The camera (responsivities, optics, pixel area).
    reference : ChartReference
        The chart reference of the scene (its illuminant, grid and patches).

    Returns
    -------
    ndarray
        ``(N,)`` photo-electron rates, e⁻/s, one per channel.
    """
    return white_neutral(reference.illuminant, reference.grid, camera)


def camera_white(raw: RawCapture, reference: ChartReference) -> np.ndarray:
    """Expected photo-electrons ``(3,)`` of each channel for a perfect white diffuser with the
    capture's exposure times: the camera's response to the scene white.

    Parameters
    ----------
    raw : RawCapture
        The capture (its camera and per-channel exposure times, s).
    reference : ChartReference
        The chart reference of the scene (its illuminant, grid and patches).

    Returns
    -------
    ndarray
        ``(N,)`` expected photo-electrons, e⁻, one per channel.
    """
    return white_rates(raw.camera, reference) * np.asarray(raw.exposure_times_s, float)


def as_shot_neutral(raw: RawCapture, reference: ChartReference, neutral_rates: np.ndarray | None = None) -> np.ndarray:
    """DNG ``AsShotNeutral``: :func:`camera_white` (the oracle's: the true white) normalised to a maximum of 1, or,
    given the camera's own estimate ``neutral_rates`` (e⁻/s, any scale; :func:`spectracam.processing.develop`),
    that estimate with the capture's exposure times, normalised the same way.

    Parameters
    ----------
    raw : RawCapture
        The capture (its camera and per-channel exposure times, s).
    reference : ChartReference
        The chart reference of the scene (its illuminant, grid and patches).
    neutral_rates : ndarray, optional
        ``(N,)`` the camera's estimate of the white's rates, e⁻/s (any scale); None: the oracle's.

    Returns
    -------
    ndarray
        ``(N,)`` the neutral, its maximum 1.
    """
    if neutral_rates is None:
        w = camera_white(raw, reference)
    else:
        w = np.asarray(neutral_rates, float) * np.asarray(raw.exposure_times_s, float)
    return w / w.max()


def forward_matrices(raw: RawCapture, reference: ChartReference) -> list[np.ndarray]:
    """``[ForwardMatrix1, ForwardMatrix2]`` (3×N, DNG orientation: XYZ_D50 = FM·balanced camera) under CIE A and
    D65: :func:`spectracam.processing.calibration.dual_illuminant_matrices` with Bradford adaptation to D50 (the
    DNG SDK's), each mapping the balanced neutral (1, …, 1) onto D50's white exactly.  The balanced camera space
    (camera / neutral) is the same for rates and for the file's exposures, so the rates' fit is the file's.

    Parameters
    ----------
    raw : RawCapture
        The capture (its camera and per-channel exposure times, s).
    reference : ChartReference
        The chart reference of the scene (its illuminant, grid and patches).

    Returns
    -------
    list of ndarray
        Two ``(3, N)`` matrices, under CIE A and under D65.
    """
    from spectracam.processing.calibration import dual_illuminant_matrices

    dual = dual_illuminant_matrices(reference, raw.camera, "bradford")
    return [np.ascontiguousarray(fm.T) for fm in dual.forward_matrices]


def calibration_reference(reference: ChartReference, name: str) -> ChartReference:
    """The chart reference of the same chart, wavelength grid, image and level under the CIE illuminant ``name``
    (a key of colour-science's ``SDS_ILLUMINANTS``: "A", "D65"); memoised, as :meth:`ChartReference.of` is.

    Parameters
    ----------
    reference : ChartReference
        The chart reference of the scene (its illuminant, grid and patches).
    name : str
        The CIE illuminant.

    Returns
    -------
    ChartReference
        The same chart lit by that illuminant at the same white luminance.
    """
    from spectracam.scene.illuminant import IlluminantSpec

    return reference.lit_by(IlluminantSpec(kind="cie", temperature_K=None, name=name,
                                           white_luminance_cd_m2=reference.illuminant.white_luminance_cd_m2))


def camera_patches(raw: RawCapture, reference: ChartReference) -> np.ndarray:
    """Expected photo-electrons ``(24, N)`` of the chart's patches under the reference's illuminant with the
    capture's per-channel exposure times: the camera's raw values of the chart, noise-free.

    Parameters
    ----------
    raw : RawCapture
        The capture (its camera and per-channel exposure times, s).
    reference : ChartReference
        The chart reference of the scene (its illuminant, grid and patches).

    Returns
    -------
    ndarray
        ``(24, N)`` expected photo-electrons, e⁻.
    """
    return reference.patch_rates(raw.camera) * np.asarray(raw.exposure_times_s, float)[None, :]


def camera_to_xyz_matrix(raw: RawCapture, reference: ChartReference) -> np.ndarray:
    """3×3 ``B`` with ``XYZ ≈ B·camera`` under the reference's illuminant: least squares over the chart
    reference's 24 patches (camera = expected photo-electrons with the capture's exposure times), the camera's
    white mapped exactly onto the illuminant's white (Y = 1).

    Parameters
    ----------
    raw : RawCapture
        The capture (its camera and per-channel exposure times, s).
    reference : ChartReference
        The chart reference of the scene (its illuminant, grid and patches).

    Returns
    -------
    ndarray
        ``(3, 3)`` ``B`` (camera electrons → CIE 1931 XYZ, the white at Y = 1).
    """
    return constrained_lstsq(camera_patches(raw, reference), reference.patch_xyz, camera_white(raw, reference),
                             reference.white_xyz).T


def normalise_color_matrix(M: np.ndarray) -> np.ndarray:
    """``M`` scaled as the DNG SDK's ``NormalizeColorMatrix`` does: the largest camera value of D50's white is 1.

    Parameters
    ----------
    M : ndarray
        ``(N, 3)`` XYZ → camera matrix.

    Returns
    -------
    ndarray
        ``(N, 3)`` ``M`` divided by the largest element of ``M·XYZ_D50``.
    """
    return M / (M @ D50_XYZ).max()


def xyz_to_camera_matrix(raw: RawCapture, reference: ChartReference) -> np.ndarray:
    """XYZ → camera under the reference's illuminant: the inverse of :func:`camera_to_xyz_matrix` (so the
    illuminant's white maps onto the camera's white), scaled by :func:`normalise_color_matrix`.  With other than
    three channels (N×3: no inverse) the least-squares fit from the patches' XYZ to the camera, white preserved.

    Parameters
    ----------
    raw : RawCapture
        The capture (its camera and per-channel exposure times, s).
    reference : ChartReference
        The chart reference of the scene (its illuminant, grid and patches).

    Returns
    -------
    ndarray
        ``(N, 3)`` XYZ → camera, normalised.
    """
    if len(raw.layout.channels) == 3:
        M = np.linalg.inv(camera_to_xyz_matrix(raw, reference))
    else:
        M = constrained_lstsq(reference.patch_xyz, camera_patches(raw, reference), reference.white_xyz,
                              camera_white(raw, reference)).T
    return normalise_color_matrix(M)


def color_matrices(raw: RawCapture, reference: ChartReference) -> list[tuple[int, np.ndarray]]:
    """``[(17, ColorMatrix1), (21, ColorMatrix2)]``: :func:`xyz_to_camera_matrix` under CIE A and under D65
    (:data:`CALIBRATION_ILLUMINANTS`), each fitted on the chart lit by that illuminant.

    Parameters
    ----------
    raw : RawCapture
        The capture (its camera and per-channel exposure times, s).
    reference : ChartReference
        The chart reference of the scene (its illuminant, grid and patches).

    Returns
    -------
    list of tuple of (int, ndarray)
        ``(EXIF LightSource code, (N, 3) ColorMatrix)`` for CIE A and D65.
    """
    return [(code, xyz_to_camera_matrix(raw, calibration_reference(reference, name)))
            for name, code in CALIBRATION_ILLUMINANTS]


def saturation_exposure_lux_s(raw: RawCapture, reference: ChartReference) -> float:
    """ISO 12232 ``H_sat``: the focal-plane luminous exposure, lux·s, at which the first channel clips
    for a neutral (illuminant-coloured) object, with the exposure time written as ``ExposureTime``
    (the capture time).

    ``H_sat = E_v(L_sat)·t_capture``.  A perfect white diffuser (luminance ``L_w``) gives channel k
    ``w_k·t_k`` photo-electrons plus ``i_d·t_k`` dark ones; the channel clips at
    ``q_sat = min(q_max, (2ⁿ − black level)/K)`` (the well, or the ADC's top code), so the luminance
    that first clips is ``L_sat = L_w·min_k (q_sat − i_d·t_k)/(w_k·t_k)``.  The focal-plane
    illuminance of a luminance L is ``E_v = k_v·L`` with ``k_v`` the lens's image-irradiance factor
    (``π/(4N²)`` paraxial, ``π/(1 + 4N²)`` exact) times its transmittance, averaged over the white's
    spectrum weighted by ȳ(λ).

    Parameters
    ----------
    raw : RawCapture
        The capture (its camera and per-channel exposure times, s).
    reference : ChartReference
        The chart reference of the scene (its illuminant, grid and patches).

    Returns
    -------
    float
        ``H_sat``, lux·s.
    """
    from spectracam.optics import radiance_to_photon_irradiance
    from spectracam.core.spectra import cmf_band_weights, energy_to_photons

    cam, s, grid = raw.camera, raw.camera.sensor, reference.grid
    times = np.asarray(raw.exposure_times_s, float)
    rad = white_radiance(reference)
    ybar = cmf_band_weights(grid)[:, 1]
    k_band = radiance_to_photon_irradiance(grid, cam.optics) / energy_to_photons(1.0, grid.centres_nm)
    k_v = float((rad * k_band * ybar).sum() / (rad * ybar).sum())
    q_sat = min(s.q_max_e, (2**s.adc_bits - s.black_level_dn) / s.system_gain_dn_per_e)
    w = white_rates(cam, reference)
    l_sat = reference.illuminant.white_luminance_cd_m2 * float(np.min((q_sat - s.dark_rate_e_per_s * times)
                                                                       / (w * times)))
    return k_v * l_sat * float(raw.capture_time_s)


def saturation_iso(raw: RawCapture, reference: ChartReference) -> float:
    """ISO 12232 saturation-based speed ``S_sat = 78 / H_sat`` (:func:`saturation_exposure_lux_s`)
    for the capture's exposure: with the white metered to full scale it is
    ``78 / (k_v·L_white patch·t)``, e.g. ``78·4N² / (π·L·t)`` for the paraxial lens.

    Parameters
    ----------
    raw : RawCapture
        The capture (its camera and per-channel exposure times, s).
    reference : ChartReference
        The chart reference of the scene (its illuminant, grid and patches).

    Returns
    -------
    float
        ``S_sat`` (unrounded; the Exif tag holds it rounded, 1–65535).
    """
    return ISO_SATURATION_CONSTANT / saturation_exposure_lux_s(raw, reference)


def _fraction(x: float, signed: bool, denom: int = 1_000_000) -> tuple[int, int]:
    """``x`` as a TIFF (S)RATIONAL: the closest fraction with denominator ≤ ``denom`` whose numerator
    and denominator fit 32 bits (signed: 31), clamped to the largest and smallest magnitudes the type
    holds — never a field that overflows (a 2-hour exposure, a 1e-12 s one)."""
    from fractions import Fraction

    top = 2**31 - 1 if signed else 2**32 - 1
    x = float(x)
    if not np.isfinite(x):
        raise SpectracamError(f"DNG: a rational field would be {x!r}; every value written must be finite")
    if not signed and x < 0:
        x = 0.0
    if abs(x) >= top:
        return (top if x > 0 else -top), 1
    if 0 < abs(x) < 1.0 / top:  # below the smallest non-zero rational: 1/top
        return (1 if x > 0 else -1), top
    d = max(1, min(top, int(top // max(abs(x), 1.0)), denom if abs(x) >= 1.0 / denom else top))
    f = Fraction(x).limit_denominator(d)
    return f.numerator, f.denominator


def _srational(values, denom=1_000_000):
    return tuple(v for x in values for v in _fraction(x, True, denom))


def _rational(values, denom=1_000_000):
    return tuple(v for x in values for v in _fraction(x, False, denom))


def _exposure_rational(t_s: float) -> tuple[int, int]:
    """An exposure time as a RATIONAL: 1/x s when that is exact to 6 digits, else the closest fraction
    that fits the field (µs/10⁶ in the usual range)."""
    inv = 1.0 / t_s
    if t_s < 1 and abs(round(inv) - inv) < 1e-6 * inv and round(inv) <= 2**32 - 1:
        return 1, int(round(inv))
    return _fraction(t_s, False)


#: TIFF field types: (code, struct format of one value).
_TYPES = {"ASCII": (2, "B"), "SHORT": (3, "H"), "LONG": (4, "I"), "RATIONAL": (5, "II"), "UNDEFINED": (7, "B")}


#: tifffile refuses to write the ExifIFD pointer (34665) itself: a placeholder with the next lower
#: tag number (unused, and sorting to the same place in the IFD) is written and renamed afterwards.
_EXIF_PLACEHOLDER = 34664


def _append_exif_ifd(data: bytes, entries: list[tuple[int, str, tuple]]) -> bytes:
    """Append an Exif IFD holding ``entries`` ``(tag, type, values)`` to a little-endian classic TIFF
    written with the :data:`_EXIF_PLACEHOLDER` tag, and turn that tag into the ExifIFD pointer (34665,
    LONG) to it."""
    import tifffile

    with tifffile.TiffFile(io.BytesIO(data)) as tif:
        if tif.byteorder != "<" or tif.is_bigtiff:
            raise SpectracamError("DNG: expected a little-endian classic TIFF from tifffile")
        entry = tif.pages[0].tags[_EXIF_PLACEHOLDER].offset
    out = bytearray(data)
    if len(out) % 2:
        out += b"\0"
    start = len(out)
    entries = sorted(entries)
    extra_at = start + 2 + 12 * len(entries) + 4
    ifd, extra = bytearray(struct.pack("<H", len(entries))), bytearray()
    for tag, kind, values in entries:
        code, fmt = _TYPES[kind]
        count = len(values) // (2 if kind == "RATIONAL" else 1)
        payload = struct.pack("<" + fmt[0] * len(values), *values)
        if len(payload) <= 4:
            field = payload.ljust(4, b"\0")
        else:
            field = struct.pack("<I", extra_at + len(extra))
            extra += payload + (b"\0" if len(payload) % 2 else b"")
        ifd += struct.pack("<HHI", tag, code, count) + field
    ifd += struct.pack("<I", 0)
    out += ifd + extra
    struct.pack_into("<HHII", out, entry, 34665, 4, 1, start)
    return bytes(out)


def _black_level_tag(black: float, count: int) -> tuple:
    """BlackLevel (50714): LONG when the pedestal is a whole number of DN (LibRaw reads a fractional
    one truncated), else RATIONAL."""
    if float(black).is_integer():
        return 50714, 4, count, (int(black),) * count, True
    return 50714, 5, count, _rational([black] * count), True


def dng_image(raw: RawCapture) -> tuple[np.ndarray, MosaicLayout | PlanesLayout, str | None]:
    """``(digital numbers, layout, note)`` as the DNG holds them.  A mosaic whose tile LibRaw can
    decode (its ``filters`` word holds tiles two columns wide: every 2×2 tile) is written as
    recorded; a three-channel mosaic of a wider tile (Quad Bayer) remosaicked to RGGB Bayer, as phones
    write theirs (:func:`spectracam.processing.color.remosaic_to_bayer`); a four-channel mosaic of a wider tile
    (RGBW) as LinearRaw of its channels interpolated by :func:`spectracam.processing.color.periodic_bilinear`.
    ``note`` says which, for the file's description; raw.exr always holds the mosaic as recorded.

    Parameters
    ----------
    raw : RawCapture
        The capture as recorded.

    Returns
    -------
    digital : ndarray
        ``(H, W)`` for a mosaic, ``(N, H, W)`` for planes; DN.
    layout : MosaicLayout or PlanesLayout
        The layout of ``digital``.
    note : str or None
        What was changed from the recording; None when nothing.
    """
    layout = raw.layout
    if isinstance(layout, PlanesLayout) or layout.tile_shape == (2, 2):
        return np.asarray(raw.digital), layout, None
    from spectracam.processing.color import periodic_bilinear, remosaic_to_bayer

    if len(layout.channels) == 3:
        mosaic, pattern = remosaic_to_bayer(raw.digital, layout)
        return mosaic, MosaicLayout.bayer(pattern), f"the {layout.pattern} mosaic remosaicked to {pattern} Bayer"
    planes = np.moveaxis(periodic_bilinear(raw.digital, layout), -1, 0)
    return planes, PlanesLayout("sensors", f"the {layout.pattern} mosaic interpolated to full planes",
                                layout.channels), f"the {layout.pattern} mosaic interpolated to LinearRaw planes " \
                                                  f"{', '.join(layout.channels)} (bilinear, periodic)"


def linear_raw_pedestal(raw: RawCapture, layout: MosaicLayout | PlanesLayout | None = None) -> int:
    """Digital numbers subtracted from the pixels of the DNG (then clipped at 0): for LinearRaw the pedestal's
    whole DN (darktable does not subtract a LinearRaw ``BlackLevel``; see the module docstring), for a CFA
    mosaic 0.  ``layout``: the layout the DNG holds (default the capture's).

    Parameters
    ----------
    raw : RawCapture
        The capture (its sensor's black level, DN).
    layout : MosaicLayout or PlanesLayout, optional
        The layout the DNG holds.

    Returns
    -------
    int
        The pedestal subtracted, DN.
    """
    layout = layout or raw.layout
    return 0 if isinstance(layout, MosaicLayout) else int(np.floor(raw.camera.sensor.black_level_dn))


def dng_levels(raw: RawCapture, layout: MosaicLayout | PlanesLayout | None = None,
               mid_step: bool = False) -> tuple[int, float, int]:
    """``(pedestal subtracted from the pixels, BlackLevel, WhiteLevel)`` of the DNG: a CFA mosaic ``(0, b,
    2ⁿ − 1)``; LinearRaw ``(⌊b⌋, b − ⌊b⌋, 2ⁿ − 1 − ⌊b⌋)`` (BlackLevel 0 for a whole-DN pedestal).  With
    ``mid_step`` the levels are in the LinearizationTable's half-DN units (value 2·pixel + 1): BlackLevel doubled,
    WhiteLevel 2·top + 1.

    Parameters
    ----------
    raw : RawCapture
        The capture (its ADC bits and black level).
    layout : MosaicLayout or PlanesLayout, optional
        The layout the DNG holds (default the capture's).
    mid_step : bool
        Give the levels in the LinearizationTable's half-DN units.

    Returns
    -------
    pedestal : int
        DN subtracted from the pixels.
    black_level : float
        The ``BlackLevel`` tag.
    white_level : int
        The ``WhiteLevel`` tag.
    """
    bits, b = raw.camera.sensor.adc_bits, raw.camera.sensor.black_level_dn
    offset = linear_raw_pedestal(raw, layout)
    black, top = b - offset, 2**bits - 1 - offset
    if mid_step:  # linear values 2·DN + 1: the centre of each code, in half-DN units
        return offset, 2 * black, 2 * top + 1
    return offset, black, top


def dng_tags(raw: RawCapture, reference: ChartReference | None = None, mid_step: bool = False,
             layout: MosaicLayout | PlanesLayout | None = None, neutral_rates: np.ndarray | None = None) -> list:
    """The tifffile ``extratags`` of a capture's DNG (see the module docstring and :func:`write_dng`).

    Parameters
    ----------
    raw : RawCapture
        The capture.
    reference : ChartReference, optional
        With the chart: ColorMatrix1/2, ForwardMatrix1/2, AsShotNeutral and the calibration illuminants too.
    mid_step : bool
        Add the LinearizationTable (levels in half-DN units, :func:`dng_levels`).
    layout : MosaicLayout or PlanesLayout, optional
        The layout the DNG holds (:func:`dng_image`); default the capture's.
    neutral_rates : ndarray, optional
        The camera's own estimate of the white for ``AsShotNeutral``, e⁻/s; default the oracle's.

    Returns
    -------
    list of tuple
        ``(tag, TIFF type, count, value, writeonce)`` per tag.
    """
    layout = layout or raw.layout
    bits = raw.camera.sensor.adc_bits
    _, black, white = dng_levels(raw, layout, mid_step)
    mosaic = isinstance(layout, MosaicLayout)
    channels = layout.channels
    n = len(channels)
    model = camera_model(raw)
    tags = [
        (271, 2, 0, MAKE, True),  # Make
        (272, 2, 0, model, True),  # Model
        (50706, 1, 4, (1, 4, 0, 0), True),  # DNGVersion
        (50707, 1, 4, (1, 1, 0, 0), True),  # DNGBackwardVersion
        (50708, 2, 0, f"{MAKE} {model}", True),  # UniqueCameraModel
        (50717, 4, 1, white, True),  # WhiteLevel
        (_EXIF_PLACEHOLDER, 4, 1, 0, True),  # becomes the ExifIFD pointer (34665)
    ]
    if mosaic:
        th, tw = layout.tile_shape
        tags += [(33421, 3, 2, (th, tw), True),  # CFARepeatPatternDim
                 (33422, 1, th * tw, tuple(_CFA_CODE[c] for c in layout.pattern), True),  # CFAPattern
                 (50710, 1, n, tuple(_CFA_CODE[c] for c in channels), True),  # CFAPlaneColor
                 (50711, 3, 1, 1, True),  # CFALayout: rectangular
                 _black_level_tag(black, 1)]
    else:
        tags += [_black_level_tag(black, n)]  # one per sample
    if mid_step:
        tags.append((50712, 3, 2**bits, tuple(range(1, 2 ** (bits + 1), 2)), True))  # LinearizationTable
    if reference is not None:
        (code1, cm1), (code2, cm2) = color_matrices(raw, reference)
        fm1, fm2 = forward_matrices(raw, reference)
        tags += [(50721, 10, 3 * n, _srational(cm1.ravel()), True),  # ColorMatrix1
                 (50722, 10, 3 * n, _srational(cm2.ravel()), True),  # ColorMatrix2
                 (50728, 5, n, _rational(as_shot_neutral(raw, reference, neutral_rates)), True),  # AsShotNeutral
                 (50778, 3, 1, code1, True),  # CalibrationIlluminant1: Standard Illuminant A
                 (50779, 3, 1, code2, True),  # CalibrationIlluminant2: D65
                 (50964, 10, 3 * n, _srational(fm1.ravel()), True),  # ForwardMatrix1
                 (50965, 10, 3 * n, _srational(fm2.ravel()), True)]  # ForwardMatrix2
    return tags


def exif_entries(raw: RawCapture, reference: ChartReference | None = None,
                 stamp: datetime.datetime | None = None) -> list[tuple[int, str, tuple]]:
    """The Exif IFD: ExposureTime, FNumber, ISOSpeedRatings + SensitivityType 3 (ISO speed), ExifVersion, and with
    ``stamp`` (a UTC datetime) DateTimeOriginal, DateTimeDigitized and their OffsetTime "+00:00".

    Parameters
    ----------
    raw : RawCapture
        The capture (its capture time, s, and f-number).
    reference : ChartReference, optional
        With the chart: the ISO speed (:func:`saturation_iso`) too.
    stamp : datetime.datetime, optional
        The capture's date and time, UTC (:func:`capture_datetime`).

    Returns
    -------
    list of tuple of (int, str, tuple)
        ``(tag, TIFF type, values)`` per entry.
    """
    entries = [(33434, "RATIONAL", _exposure_rational(float(raw.capture_time_s))),
               (33437, "RATIONAL", _rational([raw.camera.optics.f_number])),
               (36864, "UNDEFINED", tuple(b"0230"))]
    if stamp is not None:
        text = tuple(stamp.strftime(EXIF_DATETIME).encode() + b"\0")
        entries += [(36867, "ASCII", text), (36868, "ASCII", text),   # DateTimeOriginal, DateTimeDigitized
                    (36881, "ASCII", tuple(b"+00:00\0")), (36882, "ASCII", tuple(b"+00:00\0"))]  # OffsetTime*
    if reference is not None:
        iso = int(np.clip(round(saturation_iso(raw, reference)), 1, 65535))
        entries += [(34855, "SHORT", (iso,)), (34864, "SHORT", (3,))]
    return entries


#: The most bits per sample a DNG is written with: LibRaw (and so darktable, RawTherapee's reader
#: aside) refuses 32-bit samples, and nothing between 16 and 32 is an integer type.
DNG_MAX_BITS = 16


def _check_dng_form(raw: RawCapture, mid_step: bool) -> None:
    """Refuse, in one line, a capture that has no DNG form (see :func:`write_dng`'s Raises)."""
    bits = raw.camera.sensor.adc_bits
    if raw.camera.sensor.readout != "single":
        raise SpectracamError(f"sensor.readout = {raw.camera.sensor.readout!r}: its merged high-dynamic-range word is "
                              "not an ADC's codes, which a DNG describes; the capture is in raw.exr")
    if bits > DNG_MAX_BITS:
        raise SpectracamError(f"sensor.adc_bits = {bits}: a DNG holds at most {DNG_MAX_BITS} bits per sample for the "
                              "raw developers that read it (LibRaw refuses more); the capture is in raw.exr")
    if mid_step and bits > 15:
        raise SpectracamError(f"sensor.adc_bits = {bits}: a mid-step LinearizationTable needs 15 bits or fewer")
    if not isinstance(raw.layout, (MosaicLayout, PlanesLayout)):
        raise SpectracamError(f"capture.architecture = {raw.camera.capture.architecture!r}: its layout "
                              f"{type(raw.layout).__name__} has no DNG form")
    if isinstance(raw.layout, PlanesLayout) and len(raw.layout.channels) not in (3, 4):
        raise SpectracamError(f"capture: {len(raw.layout.channels)} full planes ({', '.join(raw.layout.channels)}) "
                              "have no DNG form (a DNG has three or four colour planes); the capture is in raw.exr")


def write_dng(path: str | Path, raw: RawCapture, reference: ChartReference | None = None, mid_step: bool = False,
              neutral_rates: np.ndarray | None = None) -> Path:
    """Write a capture as DNG (temp file, then rename): a CFA mosaic, or LinearRaw for three or four planes.

    Parameters
    ----------
    path : str or Path
        The file to write.
    raw : RawCapture
        The capture; LinearRaw holds its pixels less the pedestal (:func:`dng_levels`).
    reference : ChartReference, optional
        With the chart: the two colour and forward matrices (CIE A and D65), the as-shot neutral and the ISO too.
    mid_step : bool
        Add a ``LinearizationTable`` (p → ``2·p + 1``) so developers take each code at the centre of its
        quantisation step; only for ADCs of up to 15 bits.  Off by default (the module docstring's ``mid_step``).
    neutral_rates : ndarray, optional
        The as-shot neutral: the camera's own estimate (default: the oracle's).

    Returns
    -------
    Path

    Raises
    ------
    SpectracamError
        An ADC of more than 16 bits (15 with ``mid_step``), or a layout that has no DNG form."""
    import tifffile

    _check_dng_form(raw, mid_step)
    bits = raw.camera.sensor.adc_bits
    image, layout, note = dng_image(raw)
    if isinstance(layout, MosaicLayout):
        photometric = 32803
    else:
        image, photometric = np.moveaxis(image, 0, -1), 34892
    offset = linear_raw_pedestal(raw, layout)
    top = 2**bits - 1 - offset
    data = np.ascontiguousarray(np.clip(np.round(image) - offset, 0, top).astype(np.uint16))
    extra = {"dng_image": note} if note else {}
    if offset:
        extra["dng_pixels"] = f"digital numbers minus {offset} DN of the pedestal, clipped at 0 (raw.exr: unclipped)"
    description = json.dumps({"spectracam": __version__, "design": raw.design,
                              "exposure_times_s": list(map(float, raw.exposure_times_s)),
                              "capture_time_s": float(raw.capture_time_s), "seed": raw.seed,
                              "camera": raw.camera.to_dict(), "scene": raw.scene, **extra}, sort_keys=True)
    buf = io.BytesIO()
    stamp = capture_datetime()
    tifffile.imwrite(buf, data, photometric=photometric, planarconfig="contig" if data.ndim == 3 else None,
                     compression=None, extratags=dng_tags(raw, reference, mid_step, layout, neutral_rates), metadata=None, subfiletype=0,
                     description=description, software=f"spectracam {__version__}", byteorder="<",
                     datetime=stamp.strftime(EXIF_DATETIME))
    return atomic_write(path, _append_exif_ifd(buf.getvalue(), exif_entries(raw, reference, stamp)))


#: Exif's date and time form (Exif 2.3, DateTimeOriginal): 19 characters and a NUL.
EXIF_DATETIME = "%Y:%m:%d %H:%M:%S"


def capture_datetime() -> datetime.datetime:
    """When the DNG's capture was taken, UTC: the time it is written, or ``SOURCE_DATE_EPOCH`` (seconds since 1970,
    the reproducible-builds convention) where that is set, so that a file can be made byte for byte again.  Without
    a date LibRaw and the developers that use it show 1 January 1970."""
    import datetime as dt
    import os

    epoch = os.environ.get("SOURCE_DATE_EPOCH", "").strip()
    if epoch:
        try:
            return dt.datetime.fromtimestamp(int(epoch), dt.timezone.utc)
        except (ValueError, OverflowError, OSError):
            raise SpectracamError(f"SOURCE_DATE_EPOCH = {epoch!r}: must be whole seconds since 1970-01-01 UTC, "
                                  "such as 1767225600") from None
    return dt.datetime.now(dt.timezone.utc).replace(microsecond=0)
