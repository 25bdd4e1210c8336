"""Metrics of a moving edge: colour-breakup width, S-CIELAB around the edge, the MTF along the motion.

All take the displayed image as display XYZ (white Y = 1, :func:`spectracam.spatial.capture.process`)
and the edge's known position: for the slanted edge at the reference pose, the column (in pixels,
pixel c spanning ``[c, c + 1]``) where the edge crosses each row, plus — with a rolling shutter — the
shift ``v·(row delay − mean row delay)`` each row's later window gives a uniformly moving edge.

* :func:`chroma_profile` / :func:`breakup_width_px` — the chroma the camera adds, ``(a*, b*)`` of the
  image minus that of the same camera's rendering of the ideal image (its colour conversion's constant
  tint removed), averaged along the edge in bins of ``bin_px`` of horizontal distance from it (the
  ISO 12233 way of supersampling an edge; averaging a* and b* before taking the chroma lets the noise
  cancel), and the *breakup width*: the pixels of distance over which that chroma exceeds a threshold
  (default 2 ΔE*ab: about twice a just-noticeable difference).
* :func:`edge_zone` — the pixels within ``half_width_px`` of the edge, where S-CIELAB and CIELAB are
  averaged (:func:`spectracam.spatial.scielab.scielab`).
* MTF along the motion: the ISO 12233:2017 e-SFR (:func:`spectracam.spatial.esfr.esfr`) of the displayed
  luminance across the edge (the edge is 5° from the vertical, the motion horizontal); a uniform motion
  of L pixels during the exposure multiplies it by ``|sinc(f·L)|`` (:func:`motion_mtf`).
"""
from __future__ import annotations

import math

import numpy as np

from ..metrics import xyz_to_lab
from ..spatial.esfr import NoEdge, esfr


def edge_columns(width_px: int, height_px: int, x0_px: float, angle_deg: float, shift_px=0.0) -> np.ndarray:
    """``(H,)`` column where a slanted edge (:class:`~spectracam.spatial.targets.SlantedEdge` through
    object pixel ``x0_px``, angle from the vertical) crosses each row's centre, plus ``shift_px``."""
    y = height_px / 2 - np.arange(height_px) - 0.5
    return width_px / 2 + x0_px - math.tan(math.radians(angle_deg)) * y + np.asarray(shift_px, float)


def edge_distance(shape, columns: np.ndarray) -> np.ndarray:
    """``(H, W)`` horizontal distance of every pixel centre from the edge, px (positive to the right)."""
    h, w = shape[:2]
    return (np.arange(w) + 0.5)[None, :] - columns[:, None]


def chroma_profile(xyz: np.ndarray, own_xyz: np.ndarray, white, distance: np.ndarray, bin_px: float = 0.5,
                   half_width_px: float = 48.0, valid: np.ndarray | None = None):
    """``(d, chroma)``: bin centres (px from the edge) and the chroma the camera adds in each bin."""
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


def breakup_width_px(d: np.ndarray, chroma: np.ndarray, threshold: float = 2.0) -> float:
    """Pixels of distance across the edge over which the added chroma exceeds ``threshold``."""
    bin_px = float(d[1] - d[0]) if d.size > 1 else 1.0
    return float(np.count_nonzero(np.nan_to_num(chroma) > threshold) * bin_px)


def edge_zone(distance: np.ndarray, half_width_px: float) -> np.ndarray:
    return np.abs(distance) <= half_width_px


def mtf_along_motion(xyz: np.ndarray, border_px: int = 4, correct_binning: bool = False):
    """e-SFR of the displayed luminance Y across the edge: ``(frequencies, sfr, mtf50)``; empty
    curves and a NaN MTF50 where noise or blur leave no usable edge (:class:`~spectracam.spatial.esfr.NoEdge`).
    As ISO 12233:2017 states it by default; ``correct_binning``: with the binning correction, which is
    not part of the standard (:func:`spectracam.spatial.esfr.esfr`)."""
    b = border_px
    try:
        r = esfr(np.asarray(xyz)[b:-b, b:-b, 1], correct_binning=correct_binning)
    except NoEdge:
        return np.zeros(0), np.zeros(0), float("nan")
    return r.frequencies_cy_per_px, r.sfr, float(r.mtf50_cy_per_px)


def motion_mtf(f_cy_per_px, blur_px: float, angle_deg: float = 0.0) -> np.ndarray:
    """Transfer of a uniform motion of ``blur_px`` along x, seen across an edge ``angle_deg`` from the
    vertical: ``|sinc(f·L·cos a)|``."""
    return np.abs(np.sinc(np.asarray(f_cy_per_px, float) * blur_px * math.cos(math.radians(angle_deg))))


__all__ = ["breakup_width_px", "chroma_profile", "edge_columns", "edge_distance", "edge_zone", "motion_mtf",
           "mtf_along_motion"]
