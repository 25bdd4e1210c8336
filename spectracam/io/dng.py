"""Adobe DNG 1.4 for colour-filter-array captures, so ordinary raw developers open the mosaic.

Written with tifffile as a single uncompressed CFA image (PhotometricInterpretation 32803) with the
DNG tags a reader needs: CFA pattern, black and white levels, ColorMatrix1 (XYZ → camera) and
AsShotNeutral.  The colour matrix is the least-squares fit of the camera's noise-free patch
responses to the patches' CIE 1931 XYZ under the scene illuminant (DNG spec 1.4, chapter 6),
normalised so the illuminant's white gives a maximum camera value of 1.
"""
from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

import numpy as np

from .. import __version__
from ..capture import WHITE_PATCH
from ..errors import SpectracamError

#: DNG CFAPattern colour codes.
_CFA_CODE = {"R": 0, "G": 1, "B": 2}
#: EXIF LightSource codes for DNG CalibrationIlluminant1 (255 = other).
_ILLUMINANT_CODE = {"A": 17, "D55": 20, "D65": 21, "D75": 22, "D50": 23}


def xyz_to_camera_matrix(raw) -> np.ndarray | None:
    """3×3 M with camera ≈ M·XYZ, fitted on the chart; ``None`` when the chart was not available."""
    if raw.patch_rates_e_per_s is None or raw.patch_xyz is None:
        return None
    cam = raw.patch_rates_e_per_s * raw.exposure_times_s[None, :]  # electrons per patch and channel
    M, *_ = np.linalg.lstsq(raw.patch_xyz, cam, rcond=None)  # XYZ (24,3) @ M (3,3) ≈ cam
    M = M.T
    return M / (M @ _white_xyz(raw.patch_xyz)).max()


def _white_xyz(patch_xyz: np.ndarray) -> np.ndarray:
    """XYZ of the illuminant's white at Y = 1, taken from the (near-neutral) white patch."""
    w = patch_xyz[WHITE_PATCH]
    return w / w[1]


def _srational(values, denom=1_000_000):
    return tuple(v for x in values for v in (int(round(x * denom)), denom))


def _rational(values, denom=1_000_000):
    return tuple(v for x in values for v in (max(int(round(x * denom)), 0), denom))


def write_dng(path: str | Path, raw) -> Path:
    """Write a colour-filter-array capture as DNG (temp file, then rename)."""
    import tifffile

    if raw.architecture != "cfa" or raw.digital.ndim != 2:
        raise SpectracamError(f"capture.architecture = {raw.architecture!r}: DNG holds colour-filter-array mosaics only")
    bits = raw.camera.sensor.adc_bits
    white_level = 2**bits - 1
    mosaic = np.ascontiguousarray(np.clip(np.round(raw.digital), 0, white_level).astype(np.uint16))
    tags = [
        (50706, 1, 4, (1, 4, 0, 0), True),  # DNGVersion
        (50707, 1, 4, (1, 1, 0, 0), True),  # DNGBackwardVersion
        (50708, 2, 0, f"spectracam {__version__} simulated CMOS sensor", True),  # UniqueCameraModel
        (33421, 3, 2, (2, 2), True),  # CFARepeatPatternDim
        (33422, 1, 4, tuple(_CFA_CODE[c] for c in raw.cfa_pattern), True),  # CFAPattern
        (50710, 1, 3, (0, 1, 2), True),  # CFAPlaneColor
        (50711, 3, 1, 1, True),  # CFALayout: rectangular
        (50714, 4, 1, 0, True),  # BlackLevel: no offset in this sensor model
        (50717, 4, 1, white_level, True),  # WhiteLevel
    ]
    M = xyz_to_camera_matrix(raw)
    if M is not None:
        scene = raw.metadata.get("scene", {})
        ill = scene.get("illuminant", {})
        code = _ILLUMINANT_CODE.get(ill.get("name"), 255) if ill.get("type") == "cie" else 255
        neutral = M @ _white_xyz(raw.patch_xyz)
        tags += [(50721, 10, 9, _srational(M.ravel()), True),  # ColorMatrix1
                 (50778, 3, 1, code, True),  # CalibrationIlluminant1
                 (50728, 5, 3, _rational(neutral / neutral.max()), True)]  # AsShotNeutral
    description = json.dumps({"spectracam": __version__, "architecture": raw.architecture, "exposure": raw.exposure,
                              "exposure_times_s": list(map(float, raw.exposure_times_s)), "seed": raw.seed,
                              "camera": raw.camera.to_dict(), "scene": raw.metadata.get("scene")}, sort_keys=True)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=".dng", dir=path.parent)
    os.close(fd)
    try:
        tifffile.imwrite(tmp, mosaic, photometric=32803, compression=None, extratags=tags, metadata=None,
                         subfiletype=0, description=description, software=f"spectracam {__version__}")
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return path
