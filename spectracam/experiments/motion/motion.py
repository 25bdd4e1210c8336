"""A moving target: translation and rotation at constant velocity, and optional camera shake.

World coordinates are those of :mod:`spectracam.experiments.spatial.geometry` (millimetres, the object plane
``z = 0``, x right, y up, the camera on ``+z``). A *pose* ``(dx_mm, dy_mm, angle_deg)`` turns the
target by ``angle_deg`` about the optical axis (counter-clockwise seen from the camera) and then
moves it by ``(dx, dy)`` in its plane. The pose at time ``t`` (seconds, ``t = 0`` the middle of the
capture, where every pose is the identity) is ``v·t`` and ``ω·t`` plus the shake.

Camera shake is modelled as what it does to the image of a flat target at one distance: a small
translation of the image. It is a seeded two-dimensional Gaussian random walk on a grid of
``shake_step_ms``, linearly interpolated, its mean over the capture removed and scaled so that its rms
distance from that mean is ``shake_rms_px`` sensor pixels (so the number stated is the number one
measures in the image).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from collections.abc import Sequence

    from numpy.typing import ArrayLike

from spectracam.core.spec import Spec


@dataclass(frozen=True)
class Motion(Spec):
    """Constant-velocity motion of a target, and camera shake."""

    TABLE = "motion"
    #: Velocity of the target in its plane, mm/s (x right, y up).
    velocity_mm_per_s: tuple = (0.0, 0.0)
    #: Angular velocity about the optical axis, degrees/s (counter-clockwise seen from the camera).
    angular_velocity_deg_per_s: float = 0.0
    #: rms distance of the shake path from its mean position over the capture, sensor pixels (0: none).
    shake_rms_px: float = 0.0
    #: Time step of the shake's random walk, ms: a hand's tremor has most of its power below ~20 Hz.
    shake_step_ms: float = 1.0
    seed: int = 0

    def validate(self) -> None:
        self.numbers("velocity_mm_per_s", 2, unit="mm/s")
        self.number("angular_velocity_deg_per_s", -1e5, 1e5, unit="°/s")
        self.number("shake_rms_px", 0.0, 1e3, unit="px")
        self.number("shake_step_ms", 0.0, 1e3, lo_open=True, unit="ms")
        self.integer("seed", 0, 2**31 - 1)

    @property
    def still(self) -> bool:
        return (not any(self.velocity_mm_per_s) and self.angular_velocity_deg_per_s == 0.0
                and self.shake_rms_px == 0.0)

    # -- shake ----------------------------------------------------------------------------------
    def _shake_grid(self, span_s, object_pixel_mm: float):
        """``(t (n,), path (n, 2) mm)`` of the shake's random walk over ``span_s``."""
        t0, t1 = span_s
        step = self.shake_step_ms * 1e-3
        n = max(2, int(math.ceil((t1 - t0) / step)) + 1)
        t = t0 + step * np.arange(n)
        rng = np.random.default_rng([self.seed, 0x5A4E])
        path = np.cumsum(rng.standard_normal((n, 2)), axis=0)
        path -= path.mean(axis=0)
        rms = math.sqrt(float((path**2).sum(axis=1).mean()))
        path *= (self.shake_rms_px * object_pixel_mm / rms) if rms > 0 else 0.0
        return t, path

    def shake_mm(self, t_s: ArrayLike, span_s: Sequence[float], object_pixel_mm: float) -> np.ndarray:
        """``(n, 2)`` shake displacement (mm in the object plane) at times ``t_s``.

        Parameters
        ----------
        t_s : array_like
            Times, s (0: the middle of the capture).
        span_s : sequence of float
            ``(t0, t1)`` s, the span the random walk covers (its mean over the span is 0).
        object_pixel_mm : float
            One sensor pixel's size on the object plane, mm (scales ``shake_rms_px``).

        Returns
        -------
        ndarray
            ``(n, 2)`` mm (x, y), interpolated linearly along the walk; zeros without shake.
        """
        t_s = np.atleast_1d(np.asarray(t_s, float))
        if self.shake_rms_px == 0.0:
            return np.zeros((t_s.size, 2))
        tg, path = self._shake_grid(span_s, object_pixel_mm)
        return np.stack([np.interp(t_s, tg, path[:, i]) for i in range(2)], axis=1)

    # -- poses ----------------------------------------------------------------------------------
    def poses(self, t_s: ArrayLike, span_s: Sequence[float] = (0.0, 0.0), object_pixel_mm: float = 1.0) -> np.ndarray:
        """``(n, 3)`` poses ``(dx_mm, dy_mm, angle_deg)`` at times ``t_s`` (s, 0 = the middle of the
        capture); ``span_s`` and ``object_pixel_mm`` place and scale the shake.

        Parameters
        ----------
        t_s : array_like
            Times, s.
        span_s : sequence of float
            ``(t0, t1)`` s of the shake's walk.
        object_pixel_mm : float
            One sensor pixel on the object plane, mm.

        Returns
        -------
        ndarray
            ``(n, 3)``: translation (mm) and rotation (degrees) of the target at each time.
        """
        t = np.atleast_1d(np.asarray(t_s, float))
        v = np.asarray(self.velocity_mm_per_s, float)
        out = np.zeros((t.size, 3))
        out[:, :2] = t[:, None] * v[None, :] + self.shake_mm(t, span_s, object_pixel_mm)
        out[:, 2] = self.angular_velocity_deg_per_s * t
        return out

    def max_image_speed_px_per_s(self, object_pixel_mm: float, radius_px: float,
                                 span_s: Sequence[float] = (0.0, 0.0)) -> float:
        """How fast any image point within ``radius_px`` of the axis moves at most, px/s: ``|v| + |ω|·r``
        plus the fastest step of the shake's (piecewise linear) path over ``span_s``.

        Parameters
        ----------
        object_pixel_mm : float
            One sensor pixel on the object plane, mm.
        radius_px : float
            The farthest image point from the axis, px.
        span_s : sequence of float
            ``(t0, t1)`` s of the shake's walk.

        Returns
        -------
        float
            px/s, an upper bound.
        """
        s = float(np.hypot(*self.velocity_mm_per_s)) / object_pixel_mm
        s += abs(math.radians(self.angular_velocity_deg_per_s)) * radius_px
        if self.shake_rms_px > 0:
            _, path = self._shake_grid(span_s, object_pixel_mm)
            step = np.hypot(*np.diff(path, axis=0).T).max() / object_pixel_mm
            s += float(step) / (self.shake_step_ms * 1e-3)
        return s


def pose_matrix(pose: Sequence[float]) -> np.ndarray:
    """``(3, 3)`` homogeneous 2-D matrix of a pose: rotate by the angle, then translate.

    Parameters
    ----------
    pose : sequence of float
        ``(dx_mm, dy_mm, angle_deg)``.

    Returns
    -------
    ndarray
        ``(3, 3)`` float64.
    """
    dx, dy, a = (float(x) for x in pose)
    c, s = math.cos(math.radians(a)), math.sin(math.radians(a))
    return np.array([[c, -s, dx], [s, c, dy], [0.0, 0.0, 1.0]])


def pose_key(pose: Sequence[float], nd: int = 9) -> tuple:
    """A hashable key of a pose (rounded to 1e-9 mm / degree): equal poses share a render.

    Parameters
    ----------
    pose : sequence of float
        ``(dx_mm, dy_mm, angle_deg)``.
    nd : int
        Decimal places kept.

    Returns
    -------
    tuple of float
        The rounded pose (−0.0 made 0.0).
    """
    return tuple(round(float(x), nd) + 0.0 for x in pose)


__all__ = ["Motion", "pose_key", "pose_matrix"]
