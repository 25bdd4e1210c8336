"""Camera geometry in physical units: a thin lens, a sensor of square pixels, and where things are.

World coordinates are millimetres: the camera's lens centre at ``(0, 0, d)`` looks along ``-z`` at the
object plane ``z = 0`` (x to the right of the image, y up), the plane a flat target lies in. The lens
is a thin lens of focal length ``f`` and f-number ``N`` (entrance pupil radius ``f / 2N``), focused at
``focus_distance_mm`` (default: the object distance), so the sensor sits at the image distance
``v = f·s / (s − f)`` behind it. An image point ``(u, w)`` mm on the sensor (upright, measured from the
optical axis) sees the object point ``(u, w)·d/v`` of a plane at distance ``d`` (pinhole projection
through the lens centre); a point at distance ``z ≠ s`` is blurred into a disc of diameter
``c = (f/N)·v·|1/z − 1/s|`` on the sensor.

>>> g = CameraGeometry(object_distance_mm=1000.0, focal_length_mm=50.0, f_number=2.0, pixel_pitch_um=10.0,
...                    width_px=400, height_px=300)
>>> round(g.image_distance_mm, 4), round(g.magnification, 6), round(g.object_pixel_mm, 4)
(52.6316, 0.052632, 0.19)
>>> round(g.horizontal_fov_deg, 3), round(g.aperture_radius_mm, 3)
(4.352, 12.5)
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

from spectracam.core.errors import ConfigError

__all__ = ["CameraGeometry"]


@dataclass(frozen=True)
class CameraGeometry:
    """A thin-lens camera of square pixels at a distance from the object plane.

    Attributes
    ----------
    object_distance_mm : float
        Distance from the lens to the object plane (``z = 0``), mm.
    focal_length_mm : float
        Focal length of the thin lens, mm.
    f_number : float
        Focal length / entrance-pupil diameter.
    pixel_pitch_um : float
        Centre-to-centre pixel distance, µm.
    width_px, height_px : int
        Pixels across and down.
    focus_distance_mm : float or None
        Distance the lens is focused at, mm (default: the object distance, so the object plane is sharp).
    """

    object_distance_mm: float
    focal_length_mm: float
    f_number: float
    pixel_pitch_um: float
    width_px: int
    height_px: int
    focus_distance_mm: float | None = None

    def __post_init__(self):
        for name in ("object_distance_mm", "focal_length_mm", "f_number", "pixel_pitch_um"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ConfigError(f"geometry.{name}", v, "must be a finite number > 0")
        for name in ("width_px", "height_px"):
            v = getattr(self, name)
            if not (isinstance(v, int) and 8 <= v <= 16384):
                raise ConfigError(f"geometry.{name}", v, "must be an integer from 8 to 16384")
        if self.focus <= self.focal_length_mm:
            raise ConfigError("geometry.focus_distance_mm", self.focus,
                              f"must exceed the focal length ({self.focal_length_mm:g} mm): nothing nearer is imaged")
        if self.object_distance_mm <= self.focal_length_mm:
            raise ConfigError("geometry.object_distance_mm", self.object_distance_mm,
                              f"must exceed the focal length ({self.focal_length_mm:g} mm)")

    @classmethod
    def framing(cls, field_width_mm: float, focal_length_mm: float, f_number: float, pixel_pitch_um: float,
                width_px: int, height_px: int) -> "CameraGeometry":
        """The camera whose image, focused on the object plane, spans ``field_width_mm`` across: the object
        distance ``d = f·(1 + 1/m)`` for the magnification ``m = sensor width / field width``.

        Parameters
        ----------
        field_width_mm : float
            The object plane's width the image spans, mm.
        focal_length_mm : float
            mm.
        f_number : float
        pixel_pitch_um : float
            µm.
        width_px, height_px : int
            The image's size, px.

        Returns
        -------
        CameraGeometry
            Focused on the object plane (no separate focus distance).

        Examples
        --------
        >>> g = CameraGeometry.framing(100.0, 25.0, 4.0, 5.0, 200, 100)
        >>> round(g.object_distance_mm, 3), round(g.field_of_view_mm[0], 6)
        (2525.0, 100.0)
        """
        m = width_px * pixel_pitch_um * 1e-3 / field_width_mm
        return cls(object_distance_mm=focal_length_mm * (1.0 + 1.0 / m), focal_length_mm=focal_length_mm,
                   f_number=f_number, pixel_pitch_um=pixel_pitch_um, width_px=width_px, height_px=height_px)

    @property
    def focus(self) -> float:
        """The focus distance, mm."""
        return float(self.object_distance_mm if self.focus_distance_mm is None else self.focus_distance_mm)

    @property
    def image_distance_mm(self) -> float:
        """Lens to sensor, mm: ``v = f·s/(s − f)`` for focus distance s."""
        f, s = self.focal_length_mm, self.focus
        return f * s / (s - f)

    @property
    def magnification(self) -> float:
        """Image size / object size on the object plane: ``v / d``."""
        return self.image_distance_mm / self.object_distance_mm

    @property
    def pixel_pitch_mm(self) -> float:
        return self.pixel_pitch_um * 1e-3

    @property
    def sensor_size_mm(self) -> tuple[float, float]:
        return self.width_px * self.pixel_pitch_mm, self.height_px * self.pixel_pitch_mm

    @property
    def object_pixel_mm(self) -> float:
        """Size of one pixel's footprint on the object plane, mm."""
        return self.pixel_pitch_mm / self.magnification

    @property
    def field_of_view_mm(self) -> tuple[float, float]:
        """Width and height of the object plane the image shows, mm."""
        w, h = self.sensor_size_mm
        return w / self.magnification, h / self.magnification

    @property
    def horizontal_fov_deg(self) -> float:
        """Full horizontal angle of view, degrees: ``2·atan(W/2v)``."""
        return math.degrees(2 * math.atan(self.sensor_size_mm[0] / (2 * self.image_distance_mm)))

    @property
    def aperture_radius_mm(self) -> float:
        """Entrance-pupil radius ``f / (2N)``, mm (Mitsuba's thinlens ``aperture_radius``)."""
        return self.focal_length_mm / (2 * self.f_number)

    def blur_diameter_um(self, distance_mm: ArrayLike) -> np.ndarray:
        """Diameter of the defocus disc on the sensor of a point at ``distance_mm`` from the lens, µm:
        ``(f/N)·v·|1/z − 1/s|`` (thin lens, geometric optics).

        Parameters
        ----------
        distance_mm : array_like
            The points' distances from the lens, mm.

        Returns
        -------
        ndarray
            The disc's diameter, µm, ``distance_mm``'s shape; 0 at the focus distance.

        Examples
        --------
        >>> g = CameraGeometry(1000.0, 50.0, 2.0, 10.0, 64, 64)
        >>> float(g.blur_diameter_um(1000.0)), round(float(g.blur_diameter_um(1100.0)), 3)
        (0.0, 119.617)
        """
        z = np.asarray(distance_mm, float)
        return 1e3 * (self.focal_length_mm / self.f_number) * self.image_distance_mm * np.abs(1.0 / z - 1.0 / self.focus)

    def pixel_centres_mm(self, supersampling: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """Sensor coordinates (u right, w up; mm from the optical axis) of the centres of the columns and
        rows of the (optionally supersampled) pixel grid; rows run top to bottom.

        Parameters
        ----------
        supersampling : int
            Samples per pixel along each axis.

        Returns
        -------
        u : ndarray
            ``(W·supersampling,)`` the columns' centres, mm.
        w : ndarray
            ``(H·supersampling,)`` the rows' centres, mm, top row first.
        """
        s = self.pixel_pitch_mm / supersampling
        W, H = self.width_px * supersampling, self.height_px * supersampling
        u = (np.arange(W) + 0.5 - W / 2) * s
        w = (H / 2 - np.arange(H) - 0.5) * s
        return u, w

    def off_axis_cos4(self) -> np.ndarray:
        """``(H, W)`` cos⁴ of the angle of each pixel centre's chief ray to the optical axis (natural
        vignetting of a thin lens; 1 on the axis)."""
        u, w = self.pixel_centres_mm()
        r2 = u[None, :] ** 2 + w[:, None] ** 2
        return (self.image_distance_mm**2 / (self.image_distance_mm**2 + r2)) ** 2

    def with_margin(self, margin_px: int) -> "CameraGeometry":
        """The same camera with ``margin_px`` more pixels on every side (the same centre and scale).

        Parameters
        ----------
        margin_px : int
            Pixels added on each side.

        Returns
        -------
        CameraGeometry
            ``2·margin_px`` wider and taller.
        """
        from dataclasses import replace

        return replace(self, width_px=self.width_px + 2 * margin_px, height_px=self.height_px + 2 * margin_px)

    def to_dict(self) -> dict:
        return {"object_distance_mm": self.object_distance_mm, "focal_length_mm": self.focal_length_mm,
                "f_number": self.f_number, "pixel_pitch_um": self.pixel_pitch_um, "width_px": self.width_px,
                "height_px": self.height_px, "focus_distance_mm": self.focus,
                "image_distance_mm": self.image_distance_mm, "magnification": self.magnification,
                "object_pixel_mm": self.object_pixel_mm, "field_of_view_mm": list(self.field_of_view_mm),
                "horizontal_fov_deg": self.horizontal_fov_deg, "aperture_radius_mm": self.aperture_radius_mm}
