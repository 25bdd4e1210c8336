"""Where exposure is metered (paper 4.5): the radiance of "the white" the exposure control fills to
``capture.white_fill`` of the well.

For a spectracam chart scene it is the white patch.  A spectral image from another tool has no known
white, so the user states one (``--white`` on the command line, ``white=`` in Python):

``patch``          the chart's white patch (a spectracam chart scene only);
``X0,Y0,X1,Y1``    the mean of a region of pixels, columns X0…X1−1 and rows Y0…Y1−1;
``brightest``      the brightest neutral: among the pixels whose CIE 1976 u′v′ lies within
                   :data:`NEUTRAL_UV_TOLERANCE` of the scene illuminant's white, those at or above the
                   99th percentile of luminance (:data:`BRIGHTEST_SHARE`), averaged;
``<L>``            a number: a perfect white diffuser of luminance L cd/m² under the scene illuminant
                   (an explicit level, as an incident-light meter would give).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from spectracam.core.errors import ConfigError, SpectracamError
from spectracam.core.registry import Registry
from spectracam.core.spectra import cmf_band_weights

if TYPE_CHECKING:
    from spectracam.camera import CaptureSpec
    from spectracam.core.spectra import WavelengthGrid
    from spectracam.pipeline.scene_file import Scene
    from spectracam.render.cube import RadianceCube

__all__ = ["BRIGHTEST_SHARE", "METERING_METHODS", "METERING_STRIDE", "NEUTRAL_UV_TOLERANCE", "WhiteSpec",
           "metered_radiance", "metered_white_rates", "metering_record", "parse_white", "white_radiance_of"]

#: u′v′ distance from the illuminant's white within which a pixel counts as neutral: the
#: ColorChecker's greys lie within 0.0032 of D65's white and its least saturated colours (light skin,
#: bluish green) 0.045 away (measured), so 0.02 admits greys under a light somewhat off the stated one
#: and no coloured surface of the chart.
NEUTRAL_UV_TOLERANCE = 0.02
#: Share of the neutral pixels, the brightest, that are averaged for ``brightest``.
BRIGHTEST_SHARE = 0.01


@dataclass(frozen=True)
class WhiteSpec:
    """How the white is found: ``kind`` one of patch, box, brightest, level."""

    kind: str = "patch"
    box: tuple | None = None  # (x0, y0, x1, y1) pixels
    luminance_cd_m2: float | None = None

    def to_dict(self) -> dict:
        return {"kind": self.kind, **({"box": list(self.box)} if self.box else {}),
                **({"luminance_cd_m2": self.luminance_cd_m2} if self.luminance_cd_m2 is not None else {})}

    @property
    def text(self) -> str:
        if self.kind == "box":
            return ",".join(str(v) for v in self.box)
        return f"{self.luminance_cd_m2:g}" if self.kind == "level" else self.kind


def parse_white(text: str | WhiteSpec, field: str = "--white") -> WhiteSpec:
    """``patch``, ``brightest``, ``X0,Y0,X1,Y1`` or a luminance in cd/m² (module docstring).

    Parameters
    ----------
    text : str or WhiteSpec
        The option's text (a WhiteSpec is returned as it is).
    field : str
        The option or field, as errors name it.

    Returns
    -------
    WhiteSpec
        ``kind`` ``"patch"``, ``"brightest"``, ``"box"`` (pixels) or ``"level"`` (cd/m²).

    Raises
    ------
    ConfigError
        Anything else.
    """
    if isinstance(text, WhiteSpec):
        return text
    allowed = "must be 'patch', 'brightest', a region X0,Y0,X1,Y1 (pixels) or a white luminance in cd/m² (> 0)"
    if not isinstance(text, str):
        raise ConfigError(field, text, allowed)
    t = text.strip()
    if t in ("patch", "brightest"):
        return WhiteSpec(t)
    if "," in t:
        try:
            box = tuple(int(v) for v in t.split(","))
        except ValueError:
            raise ConfigError(field, text, allowed) from None
        if len(box) != 4 or box[0] < 0 or box[1] < 0 or box[2] <= box[0] or box[3] <= box[1]:
            raise ConfigError(field, text, "a region is X0,Y0,X1,Y1 with 0 ≤ X0 < X1 and 0 ≤ Y0 < Y1 (pixels)")
        return WhiteSpec("box", box=box)
    try:
        level = float(t)
    except ValueError:
        raise ConfigError(field, text, allowed) from None
    if not np.isfinite(level) or level <= 0:
        raise ConfigError(field, text, allowed)
    return WhiteSpec("level", luminance_cd_m2=level)


def _uv(xyz: np.ndarray) -> np.ndarray:
    """CIE 1976 u′v′ of XYZ (last axis); NaN where X + 15Y + 3Z = 0."""
    d = xyz[..., 0] + 15 * xyz[..., 1] + 3 * xyz[..., 2]
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.stack([4 * xyz[..., 0] / d, 9 * xyz[..., 1] / d], axis=-1)


def white_radiance_of(scene: Scene, grid: WavelengthGrid, luminance_cd_m2: float) -> np.ndarray:
    """Band-averaged radiance ``(B,)`` of a perfect white diffuser of the given luminance under the
    scene's illuminant, on ``grid``.

    Parameters
    ----------
    scene : Scene
        The scene (its illuminant and the white luminance it is given at).
    grid : WavelengthGrid
        The bands.
    luminance_cd_m2 : float
        The white's luminance, cd/m².

    Returns
    -------
    ndarray
        ``(B,)`` W·m⁻²·sr⁻¹·nm⁻¹.
    """
    from spectracam.scene.illuminant import white_diffuser_radiance

    return white_diffuser_radiance(scene.illuminant, grid) * (luminance_cd_m2 / scene.illuminant.white_luminance_cd_m2)


def metered_radiance(cube: RadianceCube, white: WhiteSpec, scene: Scene | None = None) -> np.ndarray:
    """The mean band-averaged radiance ``(B,)`` of the white (module docstring) in ``cube``.

    Parameters
    ----------
    cube : RadianceCube
        The radiance, W·m⁻²·sr⁻¹·nm⁻¹.
    white : WhiteSpec
        How the white is found (:func:`parse_white`).
    scene : Scene, optional
        The scene (a chart's for ``patch``; its light for ``brightest`` and ``level``).

    Returns
    -------
    ndarray
        ``(B,)`` float64, W·m⁻²·sr⁻¹·nm⁻¹.

    Raises
    ------
    SpectracamError
        A patch without a chart scene, a region outside the image, or no neutral pixel (ConfigError for the region).
    """
    r = cube.radiance
    h, w, _ = r.shape
    if white.kind == "patch":
        if scene is None:
            raise SpectracamError("--white = 'patch': this spectral image records no spectracam chart scene, so it "
                                  "has no white patch; use 'brightest', a region X0,Y0,X1,Y1 or a luminance in cd/m²")
        from spectracam.scene.reference import ChartReference

        rows, cols = ChartReference.of(scene).white_box
        return r[rows, cols].mean(axis=(0, 1), dtype=np.float64)
    if white.kind == "box":
        x0, y0, x1, y1 = white.box
        if x1 > w or y1 > h:
            raise ConfigError("--white", white.text, f"the region lies outside the {w}x{h} image")
        return r[y0:y1, x0:x1].mean(axis=(0, 1), dtype=np.float64)
    if white.kind == "level":
        return white_radiance_of(scene, cube.grid, white.luminance_cd_m2)
    # brightest neutral
    weights = cmf_band_weights(cube.grid)
    xyz = np.tensordot(r, weights.astype(np.float32), axes=([-1], [0]))
    light = white_radiance_of(scene, cube.grid, 1.0) @ weights
    duv = np.linalg.norm(_uv(xyz) - _uv(light)[None, None, :], axis=-1)
    neutral = (duv <= NEUTRAL_UV_TOLERANCE) & (xyz[..., 1] > 0)
    if not neutral.any():
        raise SpectracamError(f"--white = 'brightest': no pixel is neutral under {scene.illuminant.label} (u′v′ within "
                              f"{NEUTRAL_UV_TOLERANCE} of its white); state the light (--set illuminant…), a region "
                              "X0,Y0,X1,Y1 or a white luminance in cd/m²")
    Y = xyz[..., 1][neutral]
    chosen = neutral & (xyz[..., 1] >= np.quantile(Y, 1 - BRIGHTEST_SHARE))
    return r[chosen].mean(axis=0, dtype=np.float64)



# ---- The camera's own metering (issue 33): ``capture.metering`` -------------------------------------------------
#: Metering methods: name → function ``(preview rates (h, w, N) e⁻/s, capture spec) → implied white (N,) e⁻/s``: the
#: rates the camera takes for a perfect white diffuser, which the exposure scheme (single/optimal/balanced/split)
#: then fills to ``capture.white_fill`` of the well.  ``white_patch`` (the chart's white patch, the paper's reading,
#: an oracle: the camera could not identify it) is done by the pipeline from the chart reference, not from pixels.
METERING_METHODS: Registry = Registry("capture.metering", "metering method")
#: The camera meters on a preview: every :data:`METERING_STRIDE` th pixel along each axis (1/16 of the pixels), as a
#: camera's metering reads a reduced frame.
METERING_STRIDE = 4


@METERING_METHODS.register("white_patch")
def _white_patch_metering(preview, spec):
    """The chart's white patch (the pipeline passes its box; the oracle)."""
    raise SpectracamError("capture.metering = 'white_patch' is metered on the chart reference's white patch, "
                          "not on pixels")


@METERING_METHODS.register("average")
def _average_metering(preview, spec):
    """Average metering: the image's mean is taken as a grey of reflectance ``capture.metering_target`` (ISO 2720's
    18 % grey by default), so the implied white is ``mean/target`` per channel."""
    return preview.reshape(-1, preview.shape[-1]).mean(axis=0, dtype=np.float64) / spec.metering_target


@METERING_METHODS.register("percentile")
def _percentile_metering(preview, spec):
    """Highlight-protecting metering: each channel's ``capture.metering_percentile`` th percentile is taken as the
    white (so at most 100 − p % of the pixels exceed ``white_fill`` of the well in the channel that ends the
    exposure, the brightest)."""
    return np.percentile(preview.reshape(-1, preview.shape[-1]), spec.metering_percentile, axis=0).astype(np.float64)


def metered_white_rates(radiance: np.ndarray, weights: np.ndarray, spec: CaptureSpec) -> np.ndarray:
    """``(N,)`` the implied white's rates by ``spec.metering`` on the preview of a radiance cube ``(H, W, B)``
    through the camera's band weights ``(B, N)``.

    Parameters
    ----------
    radiance : ndarray
        ``(H, W, B)`` band-averaged radiance, W·m⁻²·sr⁻¹·nm⁻¹.
    weights : ndarray
        ``(B, N)`` the camera's band weights (radiance → e⁻/s).
    spec : CaptureSpec
        The ``[capture]`` table (``metering`` and its target or percentile).

    Returns
    -------
    ndarray
        ``(N,)`` e⁻/s.
    """
    preview = np.ascontiguousarray(radiance[::METERING_STRIDE, ::METERING_STRIDE])
    rates = preview.reshape(-1, preview.shape[-1]) @ weights
    return METERING_METHODS[spec.metering](rates.reshape(*preview.shape[:2], -1), spec)


def metering_record(spec: CaptureSpec) -> dict:
    """What a capture records of the camera's own metering.

    Parameters
    ----------
    spec : CaptureSpec
        The ``[capture]`` table.

    Returns
    -------
    dict
        ``kind``, ``method``, ``preview_stride`` and the method's target or percentile.
    """
    out = {"kind": "camera", "method": spec.metering, "preview_stride": METERING_STRIDE}
    if spec.metering == "average":
        out["target"] = spec.metering_target
    if spec.metering == "percentile":
        out["percentile"] = spec.metering_percentile
    return out
