"""Adobe DNG 1.4 for colour-filter-array captures, so ordinary raw developers open the mosaic.

Written with tifffile as a single uncompressed CFA image (PhotometricInterpretation 32803) with the
DNG tags a reader needs: CFA pattern, black and white levels, ColorMatrix1 (XYZ → camera) and
AsShotNeutral.  The colour matrix is the least-squares fit of the camera's noise-free patch
responses (from the chart reference) to the patches' CIE 1931 XYZ under the scene illuminant (DNG
spec 1.4, chapter 6), normalised so the illuminant's white gives a maximum camera value of 1.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .. import __version__
from ..architecture import MosaicLayout
from ..capture import RawCapture
from ..errors import SpectracamError
from .files import atomic_write

#: DNG CFAPattern colour codes.
_CFA_CODE = {"R": 0, "G": 1, "B": 2}
#: EXIF LightSource codes for DNG CalibrationIlluminant1 (255 = other).
_ILLUMINANT_CODE = {"A": 17, "D55": 20, "D65": 21, "D75": 22, "D50": 23}


def xyz_to_camera_matrix(raw: RawCapture, reference) -> np.ndarray:
    """3×3 M with camera ≈ M·XYZ, fitted on the chart reference's patches."""
    cam = reference.patch_rates(raw.camera) * raw.exposure_times_s[None, :]  # electrons per patch and channel
    M, *_ = np.linalg.lstsq(reference.patch_xyz, cam, rcond=None)  # XYZ (24,3) @ M (3,3) ≈ cam
    M = M.T
    return M / (M @ reference.white_xyz).max()


def _srational(values, denom=1_000_000):
    return tuple(v for x in values for v in (int(round(x * denom)), denom))


def _rational(values, denom=1_000_000):
    return tuple(v for x in values for v in (max(int(round(x * denom)), 0), denom))


def write_dng(path: str | Path, raw: RawCapture, reference=None) -> Path:
    """Write a mosaic capture as DNG (temp file, then rename); with the chart ``reference``, the
    colour matrix and the as-shot neutral too."""
    import tifffile

    if not isinstance(raw.layout, MosaicLayout):
        raise SpectracamError(f"capture.architecture = {raw.camera.capture.architecture!r}: DNG holds mosaic "
                              "(colour-filter-array) captures only")
    bits = raw.camera.sensor.adc_bits
    white_level = 2**bits - 1
    mosaic = np.ascontiguousarray(np.clip(np.round(raw.digital), 0, white_level).astype(np.uint16))
    th, tw = raw.layout.tile_shape
    tags = [
        (50706, 1, 4, (1, 4, 0, 0), True),  # DNGVersion
        (50707, 1, 4, (1, 1, 0, 0), True),  # DNGBackwardVersion
        (50708, 2, 0, f"spectracam {__version__} simulated CMOS sensor", True),  # UniqueCameraModel
        (33421, 3, 2, (th, tw), True),  # CFARepeatPatternDim
        (33422, 1, th * tw, tuple(_CFA_CODE[c] for c in raw.layout.pattern), True),  # CFAPattern
        (50710, 1, 3, (0, 1, 2), True),  # CFAPlaneColor
        (50711, 3, 1, 1, True),  # CFALayout: rectangular
        (50714, 4, 1, 0, True),  # BlackLevel: no offset in this sensor model
        (50717, 4, 1, white_level, True),  # WhiteLevel
    ]
    if reference is not None:
        M = xyz_to_camera_matrix(raw, reference)
        ill = reference.illuminant
        code = _ILLUMINANT_CODE.get(ill.name, 255) if ill.kind == "cie" else 255
        neutral = M @ reference.white_xyz
        tags += [(50721, 10, 9, _srational(M.ravel()), True),  # ColorMatrix1
                 (50778, 3, 1, code, True),  # CalibrationIlluminant1
                 (50728, 5, 3, _rational(neutral / neutral.max()), True)]  # AsShotNeutral
    description = json.dumps({"spectracam": __version__, "design": raw.design,
                              "exposure_times_s": list(map(float, raw.exposure_times_s)), "seed": raw.seed,
                              "camera": raw.camera.to_dict(), "scene": raw.scene}, sort_keys=True)
    return atomic_write(path, lambda tmp: tifffile.imwrite(
        tmp, mosaic, photometric=32803, compression=None, extratags=tags, metadata=None, subfiletype=0,
        description=description, software=f"spectracam {__version__}"))
