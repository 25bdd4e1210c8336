"""Adobe DNG 1.4 for every capture, so ordinary raw developers open and develop it.

Written with tifffile as one uncompressed image: a colour-filter-array mosaic (PhotometricInterpretation
32803, CFA tags; any tile of the DNG CFA colours R, G, B, C, M, Y, W — RYYB, CYYM and the four-colour
RGBW among them, with ``CFAPlaneColor`` naming the planes) or, for full planes (prism,
field-sequential, stacked, and :func:`dng_image`'s RGBW), LinearRaw (34892, one sample per plane; DNG
has three or four colour planes, so other counts have no DNG form).  With N colour planes, ``ColorMatrix1`` is N×3 and ``AsShotNeutral``
N long (DNG 1.4: ColorPlanes × 3).  Tags:

* ``BlackLevel`` = the sensor's pedestal (``camera.sensor.black_level_dn``), ``WhiteLevel`` = 2ⁿ − 1.
* ``AsShotNeutral`` = the camera's response to the scene white: the expected photo-electrons of each
  channel for a perfect white diffuser under the scene illuminant with the capture's exposure times,
  normalised to a maximum of 1 (for a prism or field-sequential capture with optimal exposures it is
  close to (1, 1, 1): the exposures, metered on the white patch, already balance the white).
* ``ColorMatrix1`` (XYZ → camera): the inverse of the least-squares fit, on the chart reference's
  24 patches, from the camera's noise-free responses to the patches' CIE 1931 XYZ under the scene
  illuminant, constrained so that the camera's white maps exactly onto the illuminant's XYZ; normalised
  so that ``ColorMatrix1 · XYZ_white = AsShotNeutral`` (maximum 1).  ``CalibrationIlluminant1`` is the
  scene illuminant (its EXIF LightSource code, 255 "other" for a blackbody).  This is what DNG 1.4
  chapter 6 asks of a single matrix: the as-shot neutral, mapped through the inverse matrix, is the
  illuminant's white, so a reader that follows the specification recovers the scene illuminant and
  adapts from it.
* ``Make`` "spectracam", ``Model`` "simulated <design> sensor", ``UniqueCameraModel``; in an Exif IFD
  (where LibRaw, exiv2 and exiftool look for them) ``ExposureTime`` (the capture time), ``FNumber``,
  ``ISOSpeedRatings`` with ``SensitivityType`` 3 (ISO speed): ISO 12232's saturation-based speed
  ``S_sat = 78/H_sat``, ``H_sat = k_v·L_sat·t`` lux·s, the focal-plane exposure of the luminance that
  first fills a channel (:func:`saturation_exposure_lux_s`).

What LibRaw (0.22, ``src/metadata/tiff.cpp`` and ``utils_dcraw.cpp``) does with these: it ignores
``CalibrationIlluminant1`` when there is one matrix and treats ``ColorMatrix1`` as a D65 matrix
(``cam_xyz_coeff``: rows normalised so that sRGB's D65 white gives camera (1, 1, 1)); with
``use_camera_wb`` it multiplies each channel by ``1/AsShotNeutral`` (a von Kries step in camera space
that carries the as-shot white onto D65, whatever the matrix), then applies the inverse of the
normalised matrix.  So the scene white always develops neutral; the other colours are adapted to D65 in
the camera's own channel space.  darktable (``src/common/exif.cc``) reads ``ColorMatrix1`` through exiv2
and carries it to D65 with a Bradford matrix for the named calibration illuminants (none for 255,
"other"), then white-balances with ``AsShotNeutral`` in the same way.  ``ForwardMatrix1`` is parsed but
not used in LibRaw's processing, and darktable's matrix path does not read it, so none is written.
LibRaw reads ``BlackLevel`` as an integer (a fractional one is truncated); the pedestal is written as the
integer the ADC adds (see ``mid_step`` in :func:`write_dng` for the half code a flooring ADC leaves).
"""
from __future__ import annotations

import io
import json
import struct
from pathlib import Path

import numpy as np

from .. import __version__
from ..architecture import MosaicLayout, PlanesLayout
from ..capture import RawCapture
from ..errors import SpectracamError
from .files import atomic_write

#: DNG CFAPattern colour codes.
_CFA_CODE = {"R": 0, "G": 1, "B": 2, "C": 3, "M": 4, "Y": 5, "W": 6}
#: EXIF LightSource codes for DNG CalibrationIlluminant1 (255 = other).
_ILLUMINANT_CODE = {"A": 17, "B": 18, "C": 19, "D55": 20, "D65": 21, "D75": 22, "D50": 23}
#: The Make tag of every file spectracam writes.
MAKE = "spectracam"
#: ISO 12232 saturation-based speed constant: S_sat = 78 / H_sat (H_sat in lux·s).
ISO_SATURATION_CONSTANT = 78.0


def camera_model(raw: RawCapture) -> str:
    """The Model tag: ``"simulated cfa/single sensor"``."""
    return f"simulated {raw.design} sensor"


def white_radiance(reference) -> np.ndarray:
    """Band-averaged radiance ``(B,)`` of a perfect white diffuser under the scene illuminant, E/π."""
    from ..illuminant import white_diffuser_radiance

    return white_diffuser_radiance(reference.illuminant, reference.grid)


def white_rates(camera, reference) -> np.ndarray:
    """Noise-free photo-electron rates ``(3,)`` (e⁻/s) of a perfect white diffuser under the scene
    illuminant (no dark charge)."""
    from ..camera import photo_electron_rates

    rad = white_radiance(reference)[None].astype(np.float32)
    return photo_electron_rates(rad, reference.grid, camera)[0].astype(np.float64)


def camera_white(raw: RawCapture, reference) -> np.ndarray:
    """Expected photo-electrons ``(3,)`` of each channel for a perfect white diffuser with the
    capture's exposure times: the camera's response to the scene white."""
    return white_rates(raw.camera, reference) * np.asarray(raw.exposure_times_s, float)


def as_shot_neutral(raw: RawCapture, reference) -> np.ndarray:
    """DNG ``AsShotNeutral``: :func:`camera_white` normalised to a maximum of 1."""
    w = camera_white(raw, reference)
    return w / w.max()


def _white_preserving_fit(A: np.ndarray, Y: np.ndarray, a: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``B`` ``(m, k)`` minimising ``‖A·Bᵀ − Y‖²`` subject to ``B·a = y`` exactly (one Lagrange
    multiplier per output row); ``A`` ``(n, k)`` inputs, ``Y`` ``(n, m)`` targets."""
    k = A.shape[1]
    K = np.zeros((k + 1, k + 1))
    K[:k, :k] = 2 * A.T @ A
    K[:k, k] = K[k, :k] = a
    rows = [np.linalg.solve(K, np.concatenate([2 * A.T @ Y[:, j], [y[j]]]))[:k] for j in range(Y.shape[1])]
    return np.array(rows)


def camera_to_xyz_matrix(raw: RawCapture, reference) -> np.ndarray:
    """3×3 ``B`` with ``XYZ ≈ B·camera``: least squares over the chart reference's 24 patches
    (camera = expected photo-electrons with the capture's exposure times), the camera's white mapped
    exactly onto the illuminant's white (Y = 1)."""
    cam = reference.patch_rates(raw.camera) * np.asarray(raw.exposure_times_s, float)[None, :]
    return _white_preserving_fit(cam, reference.patch_xyz, camera_white(raw, reference), reference.white_xyz)


def xyz_to_camera_matrix(raw: RawCapture, reference) -> np.ndarray:
    """DNG ``ColorMatrix1``: the inverse of :func:`camera_to_xyz_matrix`, normalised so that the
    illuminant's white maps onto :func:`as_shot_neutral` (maximum 1).  With other than three channels
    (N×3: no inverse) the least-squares fit from the patches' XYZ to the camera, white preserved."""
    n = len(raw.layout.channels)
    if n == 3:
        M = np.linalg.inv(camera_to_xyz_matrix(raw, reference))
    else:
        cam = reference.patch_rates(raw.camera) * np.asarray(raw.exposure_times_s, float)[None, :]
        M = _white_preserving_fit(reference.patch_xyz, cam, reference.white_xyz, camera_white(raw, reference))
    return M / (M @ reference.white_xyz).max()


def calibration_illuminant_code(reference) -> int:
    """EXIF LightSource code of the scene illuminant (255, "other", for a blackbody or an unlisted one)."""
    ill = reference.illuminant
    return _ILLUMINANT_CODE.get(ill.name, 255) if ill.kind == "cie" else 255


def saturation_exposure_lux_s(raw: RawCapture, reference) -> float:
    """ISO 12232 ``H_sat``: the focal-plane luminous exposure, lux·s, at which the first channel clips
    for a neutral (illuminant-coloured) object, with the exposure time written as ``ExposureTime``
    (the capture time).

    ``H_sat = E_v(L_sat)·t_capture``.  A perfect white diffuser (luminance ``L_w``) gives channel k
    ``w_k·t_k`` photo-electrons plus ``i_d·t_k`` dark ones; the channel clips at
    ``q_sat = min(q_max, (2ⁿ − black level)/K)`` (the well, or the ADC's top code), so the luminance
    that first clips is ``L_sat = L_w·min_k (q_sat − i_d·t_k)/(w_k·t_k)``.  The focal-plane
    illuminance of a luminance L is ``E_v = k_v·L`` with ``k_v`` the lens's image-irradiance factor
    (``π/(4N²)`` paraxial, ``π/(1 + 4N²)`` exact) times its transmittance, averaged over the white's
    spectrum weighted by ȳ(λ)."""
    from ..optics import radiance_to_photon_irradiance
    from ..spectra import cmf_band_weights, energy_to_photons

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


def saturation_iso(raw: RawCapture, reference) -> float:
    """ISO 12232 saturation-based speed ``S_sat = 78 / H_sat`` (:func:`saturation_exposure_lux_s`)
    for the capture's exposure: with the white metered to full scale it is
    ``78 / (k_v·L_white patch·t)``, e.g. ``78·4N² / (π·L·t)`` for the paraxial lens."""
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
_TYPES = {"SHORT": (3, "H"), "LONG": (4, "I"), "RATIONAL": (5, "II"), "UNDEFINED": (7, "B")}


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
    write theirs (:func:`spectracam.color.remosaic_to_bayer`); a four-channel mosaic of a wider tile
    (RGBW) as LinearRaw of its channels interpolated by :func:`spectracam.color.periodic_bilinear`.
    ``note`` says which, for the file's description; raw.exr always holds the mosaic as recorded."""
    layout = raw.layout
    if isinstance(layout, PlanesLayout) or layout.tile_shape == (2, 2):
        return np.asarray(raw.digital), layout, None
    from ..color import periodic_bilinear, remosaic_to_bayer

    if len(layout.channels) == 3:
        mosaic, pattern = remosaic_to_bayer(raw.digital, layout)
        return mosaic, MosaicLayout.bayer(pattern), f"the {layout.pattern} mosaic remosaicked to {pattern} Bayer"
    planes = np.moveaxis(periodic_bilinear(raw.digital, layout), -1, 0)
    return planes, PlanesLayout("sensors", f"the {layout.pattern} mosaic interpolated to full planes",
                                layout.channels), f"the {layout.pattern} mosaic interpolated to LinearRaw planes " \
                                                  f"{', '.join(layout.channels)} (bilinear, periodic)"


def dng_tags(raw: RawCapture, reference=None, mid_step: bool = False, layout=None) -> list:
    """The tifffile ``extratags`` of a capture's DNG (see the module docstring and :func:`write_dng`);
    ``layout``: the layout the DNG holds (:func:`dng_image`; default the capture's)."""
    layout = layout or raw.layout
    bits = raw.camera.sensor.adc_bits
    black = raw.camera.sensor.black_level_dn
    if mid_step:  # linear values 2·DN + 1: the centre of each code, in half-DN units
        black, white = 2 * black, 2 ** (bits + 1) - 1
    else:
        white = 2**bits - 1
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
        tags += [(50721, 10, 3 * n, _srational(xyz_to_camera_matrix(raw, reference).ravel()), True),  # ColorMatrix1
                 (50778, 3, 1, calibration_illuminant_code(reference), True),  # CalibrationIlluminant1
                 (50728, 5, n, _rational(as_shot_neutral(raw, reference)), True)]  # AsShotNeutral
    return tags


def exif_entries(raw: RawCapture, reference=None) -> list[tuple[int, str, tuple]]:
    """The Exif IFD: ExposureTime, FNumber, ISOSpeedRatings + SensitivityType 3 (ISO speed), ExifVersion."""
    entries = [(33434, "RATIONAL", _exposure_rational(float(raw.capture_time_s))),
               (33437, "RATIONAL", _rational([raw.camera.optics.f_number])),
               (36864, "UNDEFINED", tuple(b"0230"))]
    if reference is not None:
        iso = int(np.clip(round(saturation_iso(raw, reference)), 1, 65535))
        entries += [(34855, "SHORT", (iso,)), (34864, "SHORT", (3,))]
    return entries


#: The most bits per sample a DNG is written with: LibRaw (and so darktable, RawTherapee's reader
#: aside) refuses 32-bit samples, and nothing between 16 and 32 is an integer type.
DNG_MAX_BITS = 16


def write_dng(path: str | Path, raw: RawCapture, reference=None, mid_step: bool = False) -> Path:
    """Write a capture as DNG (temp file, then rename): a CFA mosaic, or LinearRaw for three planes;
    with the chart ``reference``, the colour matrix, the as-shot neutral and the ISO too.

    ``mid_step``: add a ``LinearizationTable`` mapping code DN to ``2·DN + 1`` (BlackLevel ``2·b``,
    WhiteLevel ``2ⁿ⁺¹ − 1``), so developers take each code at the centre of its quantisation step, as
    :func:`~spectracam.sensor.adc_inverse` does.  The ADC floors, so a code's mean signal is half a DN
    above its value; with few DN per channel (8 bits, dark patches, a channel that a white balance
    multiplies by 2) that half DN tints greys — about +0.2 b* on the chart's light greys of an 8-bit
    CFA at 5000 K.  Off by default: BlackLevel and WhiteLevel are then the ADC's own codes, and
    LibRaw's ``raw_image`` the digital numbers themselves.  Only for ADCs of up to 15 bits."""
    import tifffile

    bits = raw.camera.sensor.adc_bits
    if bits > DNG_MAX_BITS:
        raise SpectracamError(f"sensor.adc_bits = {bits}: a DNG holds at most {DNG_MAX_BITS} bits per sample for the "
                              "raw developers that read it (LibRaw refuses more); the capture is in raw.exr")
    if mid_step and bits > 15:
        raise SpectracamError(f"sensor.adc_bits = {bits}: a mid-step LinearizationTable needs 15 bits or fewer")
    white_level = 2**bits - 1
    if not isinstance(raw.layout, (MosaicLayout, PlanesLayout)):
        raise SpectracamError(f"capture.architecture = {raw.camera.capture.architecture!r}: its layout "
                              f"{type(raw.layout).__name__} has no DNG form")
    if isinstance(raw.layout, PlanesLayout) and len(raw.layout.channels) not in (3, 4):
        raise SpectracamError(f"capture: {len(raw.layout.channels)} full planes ({', '.join(raw.layout.channels)}) "
                              "have no DNG form (a DNG has three or four colour planes); the capture is in raw.exr")
    image, layout, note = dng_image(raw)
    if isinstance(layout, MosaicLayout):
        photometric = 32803
    else:
        image, photometric = np.moveaxis(image, 0, -1), 34892
    dtype = np.uint16
    data = np.ascontiguousarray(np.clip(np.round(image), 0, white_level).astype(dtype))
    description = json.dumps({"spectracam": __version__, "design": raw.design,
                              "exposure_times_s": list(map(float, raw.exposure_times_s)),
                              "capture_time_s": float(raw.capture_time_s), "seed": raw.seed,
                              "camera": raw.camera.to_dict(), "scene": raw.scene,
                              **({"dng_image": note} if note else {})}, sort_keys=True)
    buf = io.BytesIO()
    tifffile.imwrite(buf, data, photometric=photometric, planarconfig="contig" if data.ndim == 3 else None,
                     compression=None, extratags=dng_tags(raw, reference, mid_step, layout), metadata=None, subfiletype=0,
                     description=description, software=f"spectracam {__version__}", byteorder="<")
    return atomic_write(path, _append_exif_ifd(buf.getvalue(), exif_entries(raw, reference)))
