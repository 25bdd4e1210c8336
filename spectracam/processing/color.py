"""Colour processing (paper, section 3.5): demosaic, exposure normalisation, the linear colour
conversion to a display, and the display model.

Target of the conversion: the display RGB that reproduces the scene's CIE 1931 XYZ carried to the
display white — by scaling XYZ (von Kries in XYZ, the default: CIELAB against each white is then
preserved exactly) or by a Bradford transform.  The 3×3 matrix is fitted by least squares on the
chart's noise-free camera responses (paper 3.5: "a linear transformation, found using conventional
methods").  Demosaicking dispatches on the capture's layout, never on the architecture's name.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from spectracam.architecture.base import MosaicLayout
from spectracam.core.errors import ConfigError
from spectracam.core.cielab import DELTA_E_METHODS, SNR_COMBINATIONS
from spectracam.core.registry import Registry
from spectracam.core.spec import Spec
from spectracam.processing.registries import CALIBRATIONS, CAMERAS, WHITE_BALANCE_METHODS

if TYPE_CHECKING:
    from spectracam.processing.shading import ShadingSpec

__all__ = ["ADAPTATIONS", "CONVERSION_RCOND", "CRT_PRIMARIES", "DEMOSAIC_BAND_ROWS", "DEMOSAIC_MARGIN",
           "DEMOSAIC_METHODS", "DISPLAYS", "SCIELAB_SAMPLES_PER_DEGREE", "ProcessingSpec", "adaptation_matrix",
           "demosaic", "demosaic_applies", "display_rgb_to_xyz", "fit_conversion", "periodic_bilinear",
           "remosaic_to_bayer", "samples_per_degree", "tile_replicate"]

#: colour-science's phosphor spectra of a typical CRT (Brainard 1997), the paper's "simple CRT display".
CRT_PRIMARIES = "Typical CRT Brainard 1997"

#: Demosaicking methods: name → function ``(mosaic (H, W), layout) → (H, W, N)``.
DEMOSAIC_METHODS: Registry = Registry("processing.demosaic", "demosaicking method")
#: Displays: name → function ``() → 3×3`` matrix from linear display RGB (white R=G=B=1) to XYZ, Y_white = 1.
DISPLAYS: Registry = Registry("processing.display", "display")
#: Chromatic adaptations: name → function ``(white_from, white_to) → 3×3`` matrix on XYZ.
ADAPTATIONS: Registry = Registry("processing.adaptation", "chromatic adaptation")


#: The samples per degree the chart's S-CIELAB accepts (ProcessingSpec.viewing_distance_m with display_pixel_pitch_mm).
#: 1: below it the 1° kernel support is one pixel and S-CIELAB is plain CIELAB; 300: above a 600-dpi print read
#: at 0.7 m (289) — a finer sampling than any display viewed normally (a 120-dpi monitor at 0.5 m: 41), and the
#: filters' cost grows with the number of samples in their support.
SCIELAB_SAMPLES_PER_DEGREE = (1.0, 300.0)


@dataclass(frozen=True)
class ProcessingSpec(Spec):
    TABLE = "processing"

    demosaic: str = "bilinear"
    display: str = "crt"
    adaptation: str = "xyz_scaling"
    #: Clip display RGB to [0, 1] before it is shown (off by default: the paper scores the linear
    #: conversion, and clipping would mix gamut limits into the conversion error).
    gamut_clip: bool = False
    #: "cie1976" (ΔE*ab, the paper's) or "ciede2000".
    delta_e: str = "cie1976"
    #: How the three channel SNRs combine: "power" (10·log10 Σμ²/Σσ²) or "mean_db".
    snr_combination: str = "power"
    #: The colours the conversion is also judged on, not fitted on (spectracam.evaluation.heldout): a library of
    #: spectracam.scene.reflectances, "file:PATH" (a CSV of spectra), or "none".  CIE 224:2017's 99 samples
    #: span natural and manufactured colours evenly and ship with colour-science.
    held_out: str = "cfi99"
    #: The whole camera (issue 33; spectracam.processing.CAMERAS): "oracle" (told the light: the paper's reading)
    #: or "developed" (percentile metering, a trained white-balance estimator, the DNG's dual-illuminant
    #: calibration).  Each step below is overridable; "auto" takes the camera's.
    camera: str = "oracle"
    #: How the light's neutral is found (spectracam.processing.white_balance): oracle, grey_world, white_patch,
    #: shades_of_grey, grey_edge, corrected_moments, or "auto".
    white_balance: str = "auto"
    #: Minkowski p of shades_of_grey and grey_edge (6: Finlayson & Trezzi 2004's best on their set).
    white_balance_p: float = 6.0
    #: grey_edge's Gaussian, pixels (van de Weijer et al. 2007 use σ = 1–2 on full-resolution images).
    white_balance_sigma_px: float = 1.0
    #: The reflectance library corrected_moments is trained on (never the scored scene's colours: those are
    #: removed).  rawtoaces' 190 (skin, foliage, paints and more) ships with colour-science.
    white_balance_training: str = "rawtoaces190"
    #: How camera space becomes XYZ given the neutral (spectracam.processing.calibration): scene_light,
    #: dual_illuminant, or "auto".
    calibration: str = "auto"
    #: How the written pictures (rendered.png, the page) map linear display RGB to 8 bits
    #: (spectracam.processing.tone): "srgb" (clipped, sRGB-encoded) or "filmic"; never inside a score.
    tone_curve: str = "srgb"
    #: How far the viewer's eye is from the display the chart's S-CIELAB (ChartSummary.s_cielab_*) assumes, metres:
    #: 0.5 m, a desk monitor at arm's length, the default of the reference S-CIELAB code (ISETCam's scParams) and of
    #: the textured targets (spectracam.scene.target.TargetSpec).
    viewing_distance_m: float = 0.5
    #: The display's pixel pitch, mm (one image pixel per display pixel): 25.4/120 mm, a 120-dpi monitor, the same
    #: default; with 0.5 m it gives 41.2 samples per degree (spectracam.evaluation.scielab.samples_per_degree).
    display_pixel_pitch_mm: float = 25.4 / 120
    #: Lens-shading correction (issue 37; spectracam.processing.shading): "none" (the paper's camera: nothing off the
    #: axis to correct), "single" (per-channel gain tables calibrated on a flat field under the first of
    #: ``shading_temperatures_K``) or "cct" (tables at each, interpolated in colour temperature to the light's, as
    #: libcamera's ALSC does).  Applied to the raw channels before demosaicking.
    shading: str = "none"
    #: The flat fields' colour temperatures, K: libcamera's IMX477 tuning calibrates at 2960, 4850 and 5930 K.
    shading_temperatures_K: tuple = (2960.0, 4850.0, 5930.0)
    #: The gain table's nodes, rows × columns: libcamera's Raspberry Pi ALSC grid, 12 × 16.
    shading_grid: tuple = (12, 16)
    #: How the table is calibrated: "fit" (least squares over every pixel) or "cell_mean" (the tuning tool's).
    shading_method: str = "fit"

    def validate_shading(self) -> None:
        """The ``shading*`` fields: one line naming the field, the value and what is allowed."""
        from spectracam.processing.shading import SHADING_CORRECTIONS, SHADING_METHODS, ShadingSpec

        self.choice("shading", SHADING_CORRECTIONS)
        self.choice("shading_method", SHADING_METHODS)
        g = self.shading_grid
        if not (isinstance(g, tuple) and len(g) == 2 and all(isinstance(x, int) and not isinstance(x, bool)
                                                              and 2 <= x <= 256 for x in g)):
            raise self.error("shading_grid", "must be [rows, columns], two integers between 2 and 256",
                             list(g) if isinstance(g, tuple) else g)
        try:
            spec = ShadingSpec(correction=self.shading, calibration_temperatures_K=self.shading_temperatures_K)
        except ConfigError as e:
            raise self.error("shading_temperatures_K", e.allowed, list(self.shading_temperatures_K)
                             if isinstance(self.shading_temperatures_K, tuple) else self.shading_temperatures_K) \
                from None
        object.__setattr__(self, "shading_temperatures_K", spec.calibration_temperatures_K)

    def shading_spec(self) -> ShadingSpec:
        """The correction as a :class:`spectracam.processing.shading.ShadingSpec`."""
        from spectracam.processing.shading import ShadingSpec

        return ShadingSpec(correction=self.shading, calibration_temperatures_K=self.shading_temperatures_K,
                           grid_rows=self.shading_grid[0], grid_columns=self.shading_grid[1],
                           method=self.shading_method)

    def to_dict(self) -> dict:
        """As :meth:`Spec.to_dict`, the ``shading*`` keys left out while they hold their defaults (no correction):
        a camera without it records exactly what it recorded before issue 37."""
        out = super().to_dict()
        base = ProcessingSpec.__dataclass_fields__
        for k in ("shading", "shading_temperatures_K", "shading_grid", "shading_method"):
            default = base[k].default
            if out[k] == (list(default) if isinstance(default, tuple) else default):
                del out[k]
        return out

    def validate(self) -> None:
        from spectracam.scene.reflectances import LIBRARIES

        self.choice("camera", tuple(CAMERAS))
        for name, registry in (("white_balance", WHITE_BALANCE_METHODS), ("calibration", CALIBRATIONS)):
            if getattr(self, name) != "auto":
                self.choice(name, registry)
        self.number("white_balance_p", 1.0, 64.0)
        from spectracam.processing.tone import TONE_CURVES

        self.choice("tone_curve", TONE_CURVES)
        self.number("white_balance_sigma_px", 0.3, 16.0)
        lib = self.white_balance_training
        if not isinstance(lib, str) or not (lib in LIBRARIES or (lib.startswith("file:") and len(lib) > 5)):
            raise self.error("white_balance_training", "must be one of " + ", ".join(LIBRARIES) + " or 'file:PATH'")
        if self.white_balance_method == "corrected_moments":
            from spectracam.scene.reflectances import check_available

            check_available(lib, "processing.white_balance_training")

        self.validate_shading()
        self.choice("demosaic", DEMOSAIC_METHODS)
        self.choice("display", DISPLAYS)
        self.choice("adaptation", ADAPTATIONS)
        self.boolean("gamut_clip")
        self.choice("delta_e", DELTA_E_METHODS)
        self.choice("snr_combination", SNR_COMBINATIONS)
        if not isinstance(self.held_out, str) or not (self.held_out in LIBRARIES or self.held_out == "none"
                                                      or (self.held_out.startswith("file:") and len(self.held_out) > 5)):
            raise self.error("held_out", "must be one of " + ", ".join(LIBRARIES) + ", 'file:PATH' or 'none'")
        from spectracam.scene.reflectances import check_available

        if self.held_out != "none":
            check_available(self.held_out, "processing.held_out")   # before any work: a missing file or luxpy
        # the eye's filters (S-CIELAB): an eye closer than 5 cm cannot focus (the near point is ~10 cm even in
        # childhood), 100 m is beyond any display; a pitch from 1 µm (a print at 25 000 dpi) to 10 mm (an LED wall)
        self.number("viewing_distance_m", 0.05, 100.0, unit="m")
        self.number("display_pixel_pitch_mm", 0.001, 10.0, unit="mm")
        # spectracam.evaluation.scielab.samples_per_degree's formula, here without its scipy import (0.5 s at start-up)
        spd = 1.0 / math.degrees(2.0 * math.atan(self.display_pixel_pitch_mm * 1e-3 / (2.0 * self.viewing_distance_m)))
        if not SCIELAB_SAMPLES_PER_DEGREE[0] <= spd <= SCIELAB_SAMPLES_PER_DEGREE[1]:
            lo, hi = SCIELAB_SAMPLES_PER_DEGREE
            raise self.error("viewing_distance_m", f"with display_pixel_pitch_mm = {self.display_pixel_pitch_mm:g} "
                             f"that is {spd:.3g} samples per degree; the S-CIELAB filters need between {lo:g} and "
                             f"{hi:g} (fewer: the 1° kernel is one pixel, S-CIELAB is CIELAB; more: a kernel of more "
                             "pixels than any display viewed normally gives, and its cost grows with it)")

    @property
    def samples_per_degree(self) -> float:
        """Display pixels per degree of visual angle at ``viewing_distance_m`` and ``display_pixel_pitch_mm``
        (:func:`samples_per_degree`): what the chart's S-CIELAB filters are sampled at."""
        return samples_per_degree(self.viewing_distance_m, self.display_pixel_pitch_mm * 1e-3)

    @property
    def white_balance_method(self) -> str:
        """``white_balance`` with ``auto`` resolved by ``camera``."""
        return CAMERAS[self.camera]["white_balance"] if self.white_balance == "auto" else self.white_balance

    @property
    def calibration_method(self) -> str:
        """``calibration`` with ``auto`` resolved by ``camera``."""
        return CAMERAS[self.camera]["calibration"] if self.calibration == "auto" else self.calibration

    @property
    def told_the_light(self) -> bool:
        """The paper's chain (oracle white, conversion fitted under the scene's light): computed as it always was."""
        return self.white_balance_method == "oracle" and self.calibration_method == "scene_light"


@DISPLAYS.register("srgb")
def _srgb() -> np.ndarray:
    """IEC 61966-2-1 sRGB primaries and D65 white."""
    from spectracam.core import colour_data

    return colour_data.srgb_matrix("RGB_to_XYZ")


@DISPLAYS.register("crt")
def _crt() -> np.ndarray:
    """The phosphor spectra of :data:`CRT_PRIMARIES` integrated against the CIE 1931 CMFs."""
    from spectracam.core import colour_data
    from spectracam.core.spectra import cie_1931_cmfs

    wl, cmfs = cie_1931_cmfs()
    prim_wl, prim = colour_data.display_primaries(CRT_PRIMARIES)
    spd = np.stack([np.interp(wl, prim_wl, prim[:, k], left=0, right=0) for k in range(3)])
    M = np.trapezoid(spd[:, :, None] * cmfs[None, :, :], wl, axis=1).T  # columns: XYZ of each primary
    return M / M[1].sum()


def display_rgb_to_xyz(display: str) -> np.ndarray:
    """3×3 matrix from linear display RGB (white R=G=B=1) to CIE 1931 XYZ with the white's Y = 1.

    Parameters
    ----------
    display : str
        A registered display: ``"srgb"`` (IEC 61966-2-1) or ``"crt"`` (the paper's CRT phosphors, 3.5).

    Returns
    -------
    ndarray
        ``(3, 3)``; its columns are the primaries' XYZ.

    Examples
    --------
    >>> round(float(display_rgb_to_xyz("srgb").sum(axis=1)[1]), 6)
    1.0
    """
    fn = DISPLAYS[display]
    key = (display, fn)   # a display registered again under its name is computed afresh
    if key not in _DISPLAY_MATRICES:   # memoised: a paper run asked 1190 times (0.7 s)
        _DISPLAY_MATRICES[key] = np.asarray(fn(), float)
    return _DISPLAY_MATRICES[key].copy()


_DISPLAY_MATRICES: dict = {}


@ADAPTATIONS.register("xyz_scaling")
def _xyz_scaling(white_from, white_to):
    """von Kries in XYZ: each of X, Y, Z scaled by the ratio of the whites."""
    return np.diag(np.asarray(white_to, float) / np.asarray(white_from, float))


@ADAPTATIONS.register("bradford")
def _bradford(white_from, white_to):
    """von Kries in the Bradford cone space (Lam 1985), colour-science's matrix
    (:func:`spectracam.core.colour_data.von_kries_matrix`, the same numbers as
    ``colour.adaptation.matrix_chromatic_adaptation_VonKries``)."""
    from spectracam.core import colour_data

    return colour_data.von_kries_matrix(white_from, white_to, "Bradford")


@ADAPTATIONS.register("cat16")
def _cat16(white_from, white_to):
    """von Kries in CAT16's sharpened cone space (Li et al., Color Res. Appl. 42(6) 2017; CIECAM16's), full
    adaptation, colour-science's matrix (:func:`spectracam.core.colour_data.von_kries_matrix`)."""
    from spectracam.core import colour_data

    return colour_data.von_kries_matrix(white_from, white_to, "CAT16")


def adaptation_matrix(white_from: np.ndarray, white_to: np.ndarray, method: str) -> np.ndarray:
    """3×3 matrix carrying XYZ seen under ``white_from`` to the corresponding XYZ under ``white_to``.

    Parameters
    ----------
    white_from, white_to : ndarray
        ``(3,)`` CIE 1931 XYZ of the source and destination whites.
    method : str
        A registered chromatic adaptation: ``"xyz_scaling"``, ``"bradford"`` or ``"cat16"`` (von Kries forms).

    Returns
    -------
    ndarray
        ``(3, 3)`` M with ``XYZ_to = M·XYZ_from``.

    Examples
    --------
    >>> adaptation_matrix(np.array([1.0, 1.0, 0.5]), np.array([1.0, 1.0, 1.0]), "xyz_scaling").diagonal().tolist()
    [1.0, 1.0, 2.0]
    """
    return ADAPTATIONS[method](white_from, white_to)


def periodic_bilinear(mosaic: np.ndarray, layout: MosaicLayout) -> np.ndarray:
    """Bilinear interpolation of any periodic mosaic, ``(H, W, N)``: each channel by normalised
    convolution (Knutsson & Westin, CVPR 1993) — the tent-weighted mean of the channel's own samples
    within one tile period (weights ``(1 − |dy|/t_h)(1 − |dx|/t_w)``), a site's own sample kept as
    recorded; the image is mirrored at its edges (scipy's ``mirror``, which keeps the tile's phase).
    On a Bayer tile this is colour-demosaicing's bilinear inside the image (a test holds it to 1e-12);
    on the outermost pixels that one overshoots (scipy's ``reflect`` edge counts an edge site twice),
    this one stays a weighted mean of samples.

    Parameters
    ----------
    mosaic : ndarray
        ``(H, W)`` the mosaic, one value per site (e⁻/s, DN or e⁻).
    layout : MosaicLayout
        Its tile.

    Returns
    -------
    ndarray
        ``(H, W, N)`` float, the channels in the layout's order.
    """
    from scipy.ndimage import correlate1d

    th, tw = layout.tile_shape
    index = layout.channel_index(mosaic.shape)
    m = np.asarray(mosaic, np.float64)

    def tent(t):
        d = np.arange(-(t - 1), t)
        return 1.0 - np.abs(d) / t

    ky, kx = tent(th), tent(tw)

    def smooth(a):
        return correlate1d(correlate1d(a, ky, axis=0, mode="mirror"), kx, axis=1, mode="mirror")

    out = np.empty((*m.shape, len(layout.channels)), np.float64)
    for k in range(len(layout.channels)):
        mask = (index == k).astype(np.float64)
        with np.errstate(invalid="ignore", divide="ignore"):
            out[..., k] = np.where(mask > 0, m, smooth(m * mask) / smooth(mask))
    return out


def remosaic_to_bayer(mosaic: np.ndarray, layout: MosaicLayout) -> tuple[np.ndarray, str]:
    """A three-channel mosaic of another tile (Quad Bayer's 4×4) as an RGGB Bayer mosaic: each Bayer
    site takes its channel from :func:`periodic_bilinear` (a site already of that channel keeps its
    sample); ``(mosaic, "RGGB")``.  The phones' own remosaic engines are proprietary; this one is
    the plain interpolating kind.

    Parameters
    ----------
    mosaic : ndarray
        ``(H, W)`` the mosaic, one value per site (e⁻/s, DN or e⁻).
    layout : MosaicLayout
        Its tile.

    Returns
    -------
    mosaic : ndarray
        ``(H, W)`` the RGGB Bayer mosaic.
    pattern : str
        ``"RGGB"``.
    """
    full = periodic_bilinear(mosaic, layout)
    bayer = MosaicLayout.bayer("RGGB")
    k = bayer.channel_index(mosaic.shape)
    return np.take_along_axis(full, k[..., None], axis=-1)[..., 0], "RGGB"


def _bayer(name: str, fn_name: str):
    """A colour-demosaicing method: on a 2×2 Bayer-geometry tile directly, on any other mosaic of
    three channels after :func:`remosaic_to_bayer`; a mosaic of four channels has no Bayer form."""

    def method(mosaic: np.ndarray, layout: MosaicLayout) -> np.ndarray:
        import colour_demosaicing as cd

        pattern = layout.bayer_pattern
        if pattern is None and len(layout.channels) == 3:
            mosaic, pattern = remosaic_to_bayer(mosaic, layout)
        if pattern is None:
            raise ConfigError("processing.demosaic", name, f"needs a mosaic of three channels; this capture's "
                              f"tile is {layout.pattern} ({len(layout.channels)} channels "
                              f"{', '.join(layout.channels)}); use 'bilinear' (any periodic mosaic) or 'patch'")
        return getattr(cd, fn_name)(mosaic, pattern)

    method.channels = 3
    return method


def demosaic_applies(method: str, layout: MosaicLayout) -> bool:
    """Whether a registered demosaicking method takes a mosaic of this layout (the Bayer methods need
    three channels; ``bilinear`` and ``patch`` take any).

    Parameters
    ----------
    method : str
        A registered demosaicking method.
    layout : MosaicLayout
        The mosaic's tile.

    Returns
    -------
    bool
        Whether ``method`` can demosaic it.
    """
    need = getattr(DEMOSAIC_METHODS[method], "channels", None)
    return need is None or need == len(layout.channels)


@DEMOSAIC_METHODS.register("bilinear")
def _bilinear(mosaic: np.ndarray, layout: MosaicLayout) -> np.ndarray:
    """Bilinear: colour-demosaicing's on a 2×2 Bayer-geometry tile, :func:`periodic_bilinear` on any
    other periodic mosaic (the two agree on a Bayer tile)."""
    if layout.bayer_pattern is not None:
        import colour_demosaicing as cd

        return cd.demosaicing_CFA_Bayer_bilinear(mosaic, layout.bayer_pattern)
    return periodic_bilinear(mosaic, layout)


DEMOSAIC_METHODS.register("malvar2004", _bayer("malvar2004", "demosaicing_CFA_Bayer_Malvar2004"))
DEMOSAIC_METHODS.register("menon2007", _bayer("menon2007", "demosaicing_CFA_Bayer_Menon2007"))


@DEMOSAIC_METHODS.register("patch")
def tile_replicate(mosaic: np.ndarray, layout: MosaicLayout) -> np.ndarray:
    """The paper's reading (it ignores spatial artefacts): every pixel of a tile gets the mean of the
    tile's own sites of each channel (for a Bayer tile: its R, B and the mean of its two G) — each
    channel from pixels of that channel only, never interpolated across tiles, so inside a patch's
    mask no other surface leaks in.  Pixels of a partial tile at the right/bottom edge stay 0.

    Parameters
    ----------
    mosaic : ndarray
        ``(H, W)`` the mosaic, one value per site (e⁻/s, DN or e⁻).
    layout : MosaicLayout
        Its tile.

    Returns
    -------
    ndarray
        ``(H, W, N)``, the channels in the layout's order.

    Examples
    --------
    >>> tile_replicate(np.array([[1.0, 2.0], [4.0, 8.0]]), MosaicLayout.bayer("RGGB"))[0, 0].tolist()
    [1.0, 3.0, 8.0]
    """
    h, w = mosaic.shape
    th, tw = layout.tile_shape
    n = len(layout.channels)
    H, W = h // th * th, w // tw * tw
    out = np.zeros((h, w, n), dtype=np.float64)
    acc = np.zeros((H // th, W // tw, n))
    cnt = np.zeros(n)
    for dy, dx, k in layout.sites():
        acc[:, :, k] += mosaic[dy:H:th, dx:W:tw]
        cnt[k] += 1
    acc /= cnt
    out[:H, :W] = np.repeat(np.repeat(acc, th, axis=0), tw, axis=1)
    return out


#: Demosaicking works on bands of this many rows (with :data:`DEMOSAIC_MARGIN` rows of context on
#: each side, discarded), so a 12-Mpx image never holds the methods' full-size intermediates.
DEMOSAIC_BAND_ROWS = 512
#: Rows of context a band needs: the methods' kernels reach at most 5 rows (Menon 2007's refinement).
DEMOSAIC_MARGIN = 8


def demosaic(mosaic: np.ndarray, layout: MosaicLayout, method: str, divisor: np.ndarray | None = None) -> np.ndarray:
    """Full-colour image from a mosaic of the given layout with a registered demosaicking method.

    Works band by band (band edges on whole tiles, :data:`DEMOSAIC_BAND_ROWS` rows with
    :data:`DEMOSAIC_MARGIN` of context): every output pixel sees exactly the neighbours it would in one pass
    over the whole image.

    Parameters
    ----------
    mosaic : ndarray
        ``(H, W)`` samples, one channel per site.
    layout : MosaicLayout
        The tile: which channel each site records.
    method : str
        A name in :data:`DEMOSAIC_METHODS`: ``"bilinear"`` (any periodic mosaic), ``"malvar2004"`` and
        ``"menon2007"`` (three-channel mosaics, remosaicked to Bayer first when not Bayer), or ``"patch"`` (the
        paper's reading: each tile's mean per channel).
    divisor : ndarray, optional
        ``(N,)``: each channel divided by its value (the exposure times: rates from electrons), in the compiled
        bilinear pass as it writes, after the others; the same values as dividing the result.

    Returns
    -------
    ndarray
        ``(H, W, N)`` full-colour image, one plane per channel of ``layout``.

    Raises
    ------
    ConfigError
        An unknown ``method``, or a Bayer method on a mosaic of four channels.

    References
    ----------
    .. [Malvar2004] see docs/references.md
    .. [Menon2007] see docs/references.md
    .. [Knutsson1993] see docs/references.md; the periodic bilinear interpolation (normalised convolution).
    .. [Catrysse1999] see docs/references.md; section 3.5.
    """
    fn = DEMOSAIC_METHODS[method]
    if method == "bilinear" and (fused := _bilinear_bayer_fused(mosaic, layout, divisor)) is not None:
        return fused
    out = _demosaic_bands(fn, mosaic, layout)
    if divisor is not None:
        out /= np.asarray(divisor, float)[None, None, :]
    return out


def _demosaic_bands(fn, mosaic: np.ndarray, layout: MosaicLayout) -> np.ndarray:
    """:func:`demosaic` band by band (or whole when the image is one band)."""
    h = mosaic.shape[0]
    step = DEMOSAIC_BAND_ROWS
    if h <= step + 2 * DEMOSAIC_MARGIN:
        return fn(mosaic, layout)
    th = layout.tile_shape[0]
    margin = -(-DEMOSAIC_MARGIN // th) * th
    out = np.empty((*mosaic.shape, len(layout.channels)), dtype=np.float64)
    for a in range(0, h, step):
        lo, hi = max(0, a - margin), min(h, a + step + margin)
        out[a:a + step] = fn(mosaic[lo:hi], layout)[a - lo:a - lo + min(step, h - a)]
    return out


def _bilinear_bayer_fused(mosaic: np.ndarray, layout: MosaicLayout,
                          divisor: np.ndarray | None = None) -> np.ndarray | None:
    """``bilinear`` on a Bayer mosaic in one compiled pass (``processing/_numba_demosaic.py``: colour-demosaicing's
    arithmetic, to the rounding of float64), or None: another mosaic, no numba, or ``SPECTRACAM_FUSED=0``."""
    from spectracam.core.cielab import _kernels

    if layout.bayer_pattern is None or mosaic.ndim != 2 or min(mosaic.shape) < 2 or _kernels() is None:
        return None
    try:
        from spectracam.processing import _numba_demosaic as mod
    except Exception:  # noqa: BLE001 - a numba that does not load: colour-demosaicing's
        return None
    from spectracam.core.parallel import run_bands

    cfa = mosaic if mosaic.dtype in (np.float32, np.float64) and mosaic.flags.c_contiguous else \
        np.ascontiguousarray(mosaic, np.float64)
    chan = np.array(["RGB".index(k) for k in layout.bayer_pattern], np.int64).reshape(2, 2)
    green = np.array([0, 1, 0], np.int64)
    out = np.empty((*cfa.shape, 3), np.float64)
    d = np.ones(3) if divisor is None else np.ascontiguousarray(divisor, np.float64).reshape(3)
    run_bands(mod.bilinear_bayer_kernel, cfa.shape[0],
              lambda a, b: (np.int64(a), np.int64(b), cfa, chan, green, mod._WEIGHTS, d, out))
    return out


def fit_conversion(camera: np.ndarray, target_rgb: np.ndarray) -> np.ndarray:
    """N×3 M minimising ‖camera·M − target‖² over the chart's patches (rows).

    More than three channels (R, G, B, W) are linearly dependent when W passes what R, G and B pass
    (the block filters: exactly), and plain least squares then spends huge opposite coefficients on
    the null direction, which noise multiplies: the channels are scaled to unit norm and singular
    values below :data:`CONVERSION_RCOND` of the largest are dropped — the minimum-norm matrix among
    the best fits.  Three channels are fitted exactly as the paper's (no truncation).

    Parameters
    ----------
    camera : ndarray
        ``(n, N)`` noise-free camera responses of the n patches, one column per channel.
    target_rgb : ndarray
        ``(n, 3)`` the display RGB each patch should be rendered as.

    Returns
    -------
    ndarray
        ``(N, 3)`` conversion matrix M: camera responses (rows) @ M gives display RGB.

    References
    ----------
    .. [Catrysse1999] see docs/references.md; section 3.5 ("a linear transformation, found using conventional
       methods").
    """
    if camera.shape[1] <= 3:
        M, *_ = np.linalg.lstsq(camera, target_rgb, rcond=None)
        return M
    scale = np.linalg.norm(camera, axis=0)
    M, *_ = np.linalg.lstsq(camera / scale, target_rgb, rcond=CONVERSION_RCOND)
    return M / scale[:, None]


#: Relative singular-value cut-off of a fit with more than three channels (:func:`fit_conversion`).
CONVERSION_RCOND = 1e-4


def samples_per_degree(viewing_distance_m: float, pixel_pitch_m: float) -> float:
    """Pixels per degree of visual angle at the centre of view: ``1 / (2 atan(p / 2d))`` in degrees.

    Parameters
    ----------
    viewing_distance_m : float
        Distance from the eye to the display (or print), metres.
    pixel_pitch_m : float
        Centre-to-centre distance of the pixels, metres.

    Returns
    -------
    float

    Examples
    --------
    ISETCam's default viewing (``scParams``: 120 dpi at 0.5 m), which it rounds to 41:

    >>> round(samples_per_degree(0.5, 25.4e-3 / 120), 2)
    41.23
    """
    d, p = float(viewing_distance_m), float(pixel_pitch_m)
    if not (d > 0 and p > 0 and np.isfinite(d) and np.isfinite(p)):
        raise ValueError(f"S-CIELAB: viewing distance {d!r} m and pixel pitch {p!r} m must be positive and finite")
    return float(1.0 / np.degrees(2.0 * np.arctan(p / (2.0 * d))))
