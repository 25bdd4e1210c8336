"""Metrics of a moving edge: colour-breakup width, S-CIELAB around the edge, the MTF along the motion.

All take the displayed image as display XYZ (white Y = 1, :func:`spectracam.experiments.spatial.capture.process`)
and the edge's known position: for the slanted edge at the reference pose, the column (in pixels,
pixel c spanning ``[c, c + 1]``) where the edge crosses each row, plus — with a rolling shutter — the
shift ``v·(row delay − mean row delay)`` each row's later window gives a uniformly moving edge.

* :func:`channel_profiles` / :func:`edge_channels` / :func:`breakup_width_px` — the breakup to a fraction of
  a pixel: each camera channel's edge profile, supersampled along the slanted edge (ISO 12233:2017, 4×
  bins), normalised by the still edge's plateaus and located at its 50 % crossing; the breakup is the spread
  of the channels' positions (a uniform motion over a window centred at t_k moves a symmetric edge
  profile by v·t_k: field-sequential frames spread by v·(t_last − t_first), one shared window by 0), the
  blur each channel's 10–90 % rise, apart.
* :func:`chroma_profile` / :func:`breakup_threshold_width_px` — the chroma the camera adds, ``(a*, b*)`` of the
  image minus that of the same camera's rendering of the ideal image (its colour conversion's constant
  tint removed), averaged along the edge in bins of ``bin_px`` of horizontal distance from it (the
  ISO 12233 way of supersampling an edge; averaging a* and b* before taking the chroma lets the noise
  cancel), and the *threshold width*: the pixels of distance over which that chroma exceeds a threshold
  (default 2 ΔE*ab: about twice a just-noticeable difference; the breakup width before issue 34).
* :func:`edge_zone` — the pixels within ``half_width_px`` of the edge, where S-CIELAB and CIELAB are
  averaged (:func:`spectracam.evaluation.scielab.scielab`).
* MTF along the motion: the ISO 12233:2017 e-SFR (:func:`spectracam.evaluation.esfr.esfr`) of the displayed
  luminance across the edge (the edge is 5° from the vertical, the motion horizontal); a uniform motion
  of L pixels during the exposure multiplies it by ``|sinc(f·L)|`` (:func:`motion_mtf`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from spectracam.core.cielab import xyz_to_lab
from spectracam.evaluation.esfr import NoEdge, esfr

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

#: Bins of the channels' edge profiles, px: ISO 12233's 4× supersampling of a slanted edge.
EDGE_BIN_PX = 0.25
#: A still edge's plateaus are taken this far from it, px (the optics' and demosaicking's reach: the
#: diffraction margin of f/1.4 at 10 µm is 2–3 px, bilinear demosaicking 1 px).
PLATEAU_CLEAR_PX = 6.0


def edge_columns(width_px: int, height_px: int, x0_px: float, angle_deg: float,
                 shift_px: ArrayLike = 0.0) -> np.ndarray:
    """``(H,)`` column where a slanted edge (:class:`~spectracam.experiments.spatial.targets.SlantedEdge` through
    object pixel ``x0_px``, angle from the vertical) crosses each row's centre, plus ``shift_px``.

    Parameters
    ----------
    width_px, height_px : int
        The image's size W and H, px.
    x0_px : float
        Where the edge crosses the image's middle row, object px from the centre column.
    angle_deg : float
        The edge's angle from the vertical, degrees.
    shift_px : float or array_like, shape (H,)
        Added to every row's column, px (a rolling shutter's per-row shift of a moving edge).

    Returns
    -------
    ndarray, shape (H,)
        The edge's column at each row's centre, px (pixel c spans ``[c, c + 1]``).
    """
    y = height_px / 2 - np.arange(height_px) - 0.5
    return width_px / 2 + x0_px - math.tan(math.radians(angle_deg)) * y + np.asarray(shift_px, float)


def edge_distance(shape: tuple[int, ...], columns: np.ndarray) -> np.ndarray:
    """``(H, W)`` horizontal distance of every pixel centre from the edge, px (positive to the right).

    Parameters
    ----------
    shape : tuple of int
        The image's shape; its first two entries are H and W.
    columns : ndarray, shape (H,)
        The edge's column in each row, px (:func:`edge_columns`).

    Returns
    -------
    ndarray, shape (H, W)
        Distance of each pixel centre from the edge, px.
    """
    h, w = shape[:2]
    return (np.arange(w) + 0.5)[None, :] - columns[:, None]


def chroma_profile(xyz: np.ndarray, own_xyz: np.ndarray, white: ArrayLike, distance: np.ndarray,
                   bin_px: float = 0.5, half_width_px: float = 48.0,
                   valid: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(d, chroma)``: bin centres (px from the edge) and the chroma the camera adds in each bin.

    Parameters
    ----------
    xyz : ndarray, shape (H, W, 3)
        The displayed image, display XYZ (white Y = 1).
    own_xyz : ndarray, shape (H, W, 3)
        The same camera's rendering of the ideal image, display XYZ: its (a*, b*) are subtracted.
    white : array_like, shape (3,)
        The white's XYZ, for CIELAB.
    distance : ndarray, shape (H, W)
        Each pixel's horizontal distance from the edge, px (:func:`edge_distance`).
    bin_px : float
        Width of a bin of distance, px.
    half_width_px : float
        Only pixels within this distance of the edge are binned, px.
    valid : ndarray of bool, shape (H, W), optional
        Only these pixels are binned (None: all).

    Returns
    -------
    d : ndarray
        The bins' centres, px from the edge.
    chroma : ndarray
        The chroma of each bin's mean (Δa*, Δb*), ΔE*ab; NaN where a bin holds no pixel.
    """
    lab = xyz_to_lab(xyz, white)
    own = xyz_to_lab(own_xyz, white)
    da, db = lab[..., 1] - own[..., 1], lab[..., 2] - own[..., 2]
    ok = np.abs(distance) <= half_width_px
    if valid is not None:
        ok &= valid
    edges = np.arange(-half_width_px, half_width_px + bin_px / 2, bin_px)
    idx = np.digitize(distance[ok], edges) - 1
    n = edges.size - 1
    cnt = np.bincount(idx, minlength=n)[:n]
    sa = np.bincount(idx, da[ok], minlength=n)[:n]
    sb = np.bincount(idx, db[ok], minlength=n)[:n]
    with np.errstate(invalid="ignore", divide="ignore"):
        chroma = np.hypot(sa / cnt, sb / cnt)
    return (edges[:-1] + edges[1:]) / 2, np.where(cnt > 0, chroma, np.nan)


def breakup_threshold_width_px(d: np.ndarray, chroma: np.ndarray, threshold: float = 2.0) -> float:
    """Pixels of distance across the edge over which the added chroma exceeds ``threshold`` (before issue 34
    the headline breakup width: it counts in whole bins, so it cannot read below about 2 px, and it counts
    blur and demosaicking of a blurred edge as breakup; kept as a perceptual companion).

    Parameters
    ----------
    d : ndarray
        The bins' centres, px from the edge, evenly spaced (:func:`chroma_profile`).
    chroma : ndarray
        The added chroma in each bin, ΔE*ab (NaN counts as none).
    threshold : float
        ΔE*ab above which a bin counts.

    Returns
    -------
    float
        The number of bins over ``threshold`` times the bin width, px.
    """
    bin_px = float(d[1] - d[0]) if d.size > 1 else 1.0
    return float(np.count_nonzero(np.nan_to_num(chroma) > threshold) * bin_px)


def channel_profiles(rates: np.ndarray, distance: np.ndarray, valid: np.ndarray | None = None,
                     bin_px: float = EDGE_BIN_PX) -> tuple[np.ndarray, np.ndarray]:
    """``(d (n,), profiles (n, N))``: each channel's mean value in bins of ``bin_px`` of horizontal distance from
    the edge over the whole scored image (the ISO 12233 supersampled edge profile, one per channel); NaN where a
    bin holds no pixel.

    Parameters
    ----------
    rates : ndarray, shape (H, W, N)
        The capture's N channels.
    distance : ndarray, shape (H, W)
        Each pixel's horizontal distance from the edge, px (:func:`edge_distance`).
    valid : ndarray of bool, shape (H, W), optional
        Only these pixels are binned (None: all).
    bin_px : float
        Width of a bin, px.

    Returns
    -------
    d : ndarray, shape (n,)
        The bins' centres, px from the edge.
    profiles : ndarray, shape (n, N)
        Each channel's mean in each bin.
    """
    rates = np.asarray(rates, float)
    ok = np.ones(distance.shape, bool) if valid is None else np.asarray(valid, bool)
    dist = distance[ok]
    lo = math.floor(dist.min() / bin_px) * bin_px
    n = max(1, int(math.ceil((dist.max() - lo) / bin_px)))
    idx = np.minimum(((dist - lo) / bin_px).astype(np.int64), n - 1)
    cnt = np.bincount(idx, minlength=n)
    vals = rates[ok]                                                   # (pixels, N)
    sums = np.stack([np.bincount(idx, vals[:, k], minlength=n) for k in range(vals.shape[1])], axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        prof = sums / cnt[:, None]
    return lo + bin_px * (np.arange(n) + 0.5), np.where(cnt[:, None] > 0, prof, np.nan)


def plateaus(d: np.ndarray, profiles: np.ndarray, clear_px: float = PLATEAU_CLEAR_PX) -> tuple[np.ndarray, np.ndarray]:
    """``(left (N,), right (N,))``: each channel's level on either side of a still edge, the mean of its profile
    further than ``clear_px`` from the edge (NaN where the profile does not reach that far).

    Parameters
    ----------
    d : ndarray, shape (n,)
        The bins' centres, px from the edge.
    profiles : ndarray, shape (n, N)
        Each channel's edge profile (:func:`channel_profiles`).
    clear_px : float
        Only bins further than this from the edge count, px.

    Returns
    -------
    left, right : ndarray, shape (N,)
        Each channel's mean level left (d < −clear_px) and right (d > clear_px) of the edge.
    """
    with np.errstate(invalid="ignore"):
        left = np.nanmean(np.where((d < -clear_px)[:, None], profiles, np.nan), axis=0) if (d < -clear_px).any() \
            else np.full(profiles.shape[1], np.nan)
        right = np.nanmean(np.where((d > clear_px)[:, None], profiles, np.nan), axis=0) if (d > clear_px).any() \
            else np.full(profiles.shape[1], np.nan)
    return left, right


def crossings(d: np.ndarray, profiles: np.ndarray, left: np.ndarray, right: np.ndarray, level: float) -> np.ndarray:
    """``(N,)``: where each channel's profile, normalised to 0 on the left plateau and 1 on the right
    (``(p − left)/(right − left)``), crosses ``level``, interpolated linearly between bins; where it crosses more
    than once (noise, overshoot), the mean of its crossings; NaN where it never does or the step is flat.

    Parameters
    ----------
    d : ndarray, shape (n,)
        The bins' centres, px from the edge.
    profiles : ndarray, shape (n, N)
        Each channel's edge profile (:func:`channel_profiles`); bins where any channel is NaN are dropped.
    left, right : ndarray, shape (N,)
        Each channel's plateaus (:func:`plateaus`).
    level : float
        The normalised level to find, 0 to 1 (0.5: the edge; 0.1 and 0.9: its rise).

    Returns
    -------
    ndarray, shape (N,)
        Each channel's crossing, px from the edge.
    """
    keep = np.all(np.isfinite(profiles), axis=1)
    d, p = d[keep], profiles[keep]
    step = right - left
    with np.errstate(invalid="ignore", divide="ignore"):
        u = (p - left) / step - level                                  # (n, N)
    a, b = u[:-1], u[1:]
    hit = ((a < 0) & (b >= 0)) | ((a > 0) & (b <= 0))                  # a sign change between bins i and i + 1
    with np.errstate(invalid="ignore", divide="ignore"):
        x = d[:-1, None] + (d[1:] - d[:-1])[:, None] * a / (a - b)
        out = np.nansum(np.where(hit, x, 0.0), axis=0) / hit.sum(axis=0)
    return np.where((hit.sum(axis=0) > 0) & (np.abs(step) > 0), out, np.nan)


@dataclass(frozen=True)
class EdgeChannels:
    """The channels of a capture of a moving edge, each located to a fraction of a pixel (:func:`edge_channels`)."""

    #: Each channel's edge (its 50 % crossing) moved from where the reference shows it, px along +x.
    shift_px: tuple
    #: The breakup: the spread of those shifts, max − min (px); NaN where a channel's edge was not found.
    separation_px: float
    #: Each channel's 10–90 % rise distance (px), and their mean: the blur, apart from the breakup.
    rise_px: tuple
    blur_px: float


def edge_channels(d: np.ndarray, moving: np.ndarray, reference: np.ndarray | None = None, relative: bool = True,
                  clear_px: float = PLATEAU_CLEAR_PX) -> EdgeChannels:
    """Locate each channel's edge in the moving capture's profiles (:func:`channel_profiles`), normalised by the
    plateaus of the ``reference`` capture's (the same camera's still capture: the same exposures, so the same
    levels, and a sharp edge whose plateaus are reached within ``clear_px``): the shift of each channel's 50 %
    crossing from the reference's (``relative=False`` or without a reference: from the true edge, d = 0), their
    spread (the breakup), and each channel's 10–90 % rise (the blur).  A uniform motion at v over a window centred at t_k
    moves channel k's edge profile by v·t_k without changing its symmetry, so its 50 % crossing moves by exactly
    v·t_k whatever the window's length and the optics' (symmetric) blur: the breakup reads v·(t_last − t_first)
    for frames in sequence and 0 for one shared window.

    Parameters
    ----------
    d : ndarray, shape (n,)
        The bins' centres, px from the edge (:func:`channel_profiles`).
    moving : ndarray, shape (n, N)
        The moving capture's channel profiles.
    reference : ndarray, shape (n, N), optional
        The still capture's, on the same bins; its plateaus normalise both (None: the moving capture's own).
    relative : bool
        Shifts from the reference's crossings (False: from d = 0).
    clear_px : float
        The plateaus are taken further than this from the edge, px.

    Returns
    -------
    EdgeChannels
        Each channel's shift and rise, their spread (the breakup) and the mean rise (the blur), px.
    """
    base = reference if reference is not None else moving
    left, right = plateaus(d, base, clear_px)
    x = crossings(d, moving, left, right, 0.5)
    x0 = crossings(d, reference, left, right, 0.5) if reference is not None and relative else np.zeros_like(x)
    shift = x - x0
    rise = np.abs(crossings(d, moving, left, right, 0.9) - crossings(d, moving, left, right, 0.1))
    sep = float(np.max(shift) - np.min(shift)) if np.all(np.isfinite(shift)) else float("nan")
    blur = float(np.mean(rise)) if np.all(np.isfinite(rise)) else float("nan")
    return EdgeChannels(tuple(float(v) for v in shift), sep, tuple(float(v) for v in rise), blur)


def breakup_width_px(d: np.ndarray, moving: np.ndarray, reference: np.ndarray | None = None) -> float:
    """The colour breakup of a moving edge, px: the spread of the channels' edge positions, each located to a
    fraction of a pixel (:func:`edge_channels`).

    Parameters
    ----------
    d : ndarray, shape (n,)
        The bins' centres, px from the edge (:func:`channel_profiles`).
    moving : ndarray, shape (n, N)
        The moving capture's channel profiles.
    reference : ndarray, shape (n, N), optional
        The still capture's, on the same bins (None: plateaus of ``moving``, shifts from d = 0).

    Returns
    -------
    float
        max − min of the channels' shifts, px; NaN where a channel's edge was not found.
    """
    return edge_channels(d, moving, reference).separation_px


def edge_zone(distance: np.ndarray, half_width_px: float) -> np.ndarray:
    """The pixels within ``half_width_px`` of the edge, where S-CIELAB and CIELAB are averaged.

    Parameters
    ----------
    distance : ndarray, shape (H, W)
        Each pixel's horizontal distance from the edge, px (:func:`edge_distance`).
    half_width_px : float
        px.

    Returns
    -------
    ndarray of bool, shape (H, W)
        ``|distance| <= half_width_px``.
    """
    return np.abs(distance) <= half_width_px


def mtf_along_motion(xyz: np.ndarray, border_px: int = 4,
                     correct_binning: bool = False) -> tuple[np.ndarray, np.ndarray, float]:
    """e-SFR of the displayed luminance Y across the edge: ``(frequencies, sfr, mtf50)``; empty
    curves and a NaN MTF50 where noise or blur leave no usable edge (:class:`~spectracam.evaluation.esfr.NoEdge`).
    As ISO 12233:2017 states it by default; ``correct_binning``: with the binning correction, which is
    not part of the standard (:func:`spectracam.evaluation.esfr.esfr`).

    Parameters
    ----------
    xyz : ndarray, shape (H, W, 3)
        The displayed image, display XYZ.
    border_px : int
        Pixels cropped from every side before the edge is measured.
    correct_binning : bool
        Apply the binning correction.

    Returns
    -------
    frequencies : ndarray
        cycles/px.
    sfr : ndarray
        The e-SFR at each frequency.
    mtf50 : float
        cycles/px.
    """
    b = border_px
    try:
        r = esfr(np.asarray(xyz)[b:-b, b:-b, 1], correct_binning=correct_binning)
    except NoEdge:
        return np.zeros(0), np.zeros(0), float("nan")
    return r.frequencies_cy_per_px, r.sfr, float(r.mtf50_cy_per_px)


def motion_mtf(f_cy_per_px: ArrayLike, blur_px: float, angle_deg: float = 0.0) -> np.ndarray:
    """Transfer of a uniform motion of ``blur_px`` along x, seen across an edge ``angle_deg`` from the
    vertical: ``|sinc(f·L·cos a)|``.

    Parameters
    ----------
    f_cy_per_px : array_like
        Frequencies across the edge, cycles/px.
    blur_px : float
        L, the motion during the exposure, px.
    angle_deg : float
        The edge's angle from the vertical, degrees.

    Returns
    -------
    ndarray
        ``f_cy_per_px``'s shape.
    """
    return np.abs(np.sinc(np.asarray(f_cy_per_px, float) * blur_px * math.cos(math.radians(angle_deg))))


__all__ = ["EdgeChannels", "breakup_threshold_width_px", "breakup_width_px", "channel_profiles", "chroma_profile",
           "crossings", "edge_channels", "plateaus", "edge_columns", "edge_distance", "edge_zone", "motion_mtf",
           "mtf_along_motion"]
