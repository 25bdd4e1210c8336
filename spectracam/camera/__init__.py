"""The camera: optics, filters, sensor and how the channels are captured — everything between the
scene and the digital numbers — and its spectral response (paper, sections 3.2–3.4).

``ρ_k = A·∫E_q(λ)·R_k(λ)dλ`` per pixel and channel: optics, photon conversion, responsivity, band
width and pixel area fold into one ``(n_bands, 3)`` weight matrix (:func:`band_weights`).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from spectracam.architecture.base import ARCHITECTURES, CFA_PATTERNS, FIXED_PATTERN_CHOICES, Architecture, make_architecture
from spectracam.core.errors import ConfigError
from spectracam.sensor.exposure import EXPOSURE_SCHEMES
from spectracam.architecture.filters import FilterSpec
from spectracam.optics import OpticsSpec, radiance_to_photon_irradiance
from spectracam.sensor import SensorSpec
from spectracam.sensor.angle import PixelAngleSpec
from spectracam.core.spec import Spec
from spectracam.core.spectra import WavelengthGrid

__all__ = ["CAMERA_TABLES", "CameraSpec", "CaptureSpec", "band_weights", "camera_responsivities",
           "photo_electron_rates", "split_design"]

#: The tables of a scene or config file that describe the camera (``[pixel]``: the pixel's response to the angle of
#: incidence, issue 37; recorded only when it differs from its defaults).
CAMERA_TABLES = ("optics", "filters", "sensor", "capture", "pixel")


def split_design(design: str, field: str = "design") -> tuple[str, str]:
    """``"arch/scheme"`` → ``(arch, scheme)``, both registered (``"cfa"`` alone means ``cfa/single``).

    >>> split_design("fsc/balanced")
    ('fsc', 'balanced')

    Parameters
    ----------
    design : str
        ``"architecture/exposure"``.
    field : str
        The field or option that gave it, for the error.

    Returns
    -------
    tuple of str
        The architecture's and the exposure scheme's registered names.
    """
    if not isinstance(design, str):
        raise ConfigError(field, design, "must be a string 'architecture/exposure', e.g. 'fsc/optimal'")
    arch, _, scheme = design.partition("/")
    return ARCHITECTURES.check(arch, field), EXPOSURE_SCHEMES.check(scheme or "single", field)


@dataclass(frozen=True)
class CaptureSpec(Spec):
    """The ``[capture]`` table: architecture, exposure scheme, Bayer pattern."""

    TABLE = "capture"

    architecture: str = "cfa"
    exposure: str = "single"
    cfa_pattern: str = "RGGB"
    #: "physical" (prism: three sensors' patterns; field-sequential: one sensor's in all frames),
    #: "shared" or "independent" (the paper does not say how it modelled FPN across channels).
    fixed_pattern: str = "physical"
    #: Exposure metering (paper 4.5: the white patch "near saturation"): the fraction of the full
    #: well that the white patch's mean charge (photo + dark) reaches in the channel that meters the
    #: exposure.  0.95: the paper's noise at the white (σ ≈ 0.4 % of q_max: shot 0.28 %, FPN bound
    #: 0.29 %, quantisation 0.11 %) then clips no white pixel, and an FPN read as 1 % rms (σ ≈ 1.1 %)
    #: clips fewer than 1 in 10⁴; at 1.0 (before issue 17) half the white pixels clipped, which cut
    #: their noise and flattered SNR.  1.0 reproduces that reading.
    white_fill: float = 0.95
    #: The ``split`` exposure scheme's shares: each channel's exposure as a fraction (0, 1] of the single
    #: exposure's time, capped at its saturation (a designed split: ``spectracam design``).
    exposure_split: tuple = ()
    #: How the exposure is metered (issue 33; spectracam.sensor.metering.METERING_METHODS): "white_patch" (the chart's
    #: white patch: the paper's reading, an oracle), "average", "percentile", or "auto" (the camera's:
    #: processing.camera).
    metering: str = "auto"
    #: ``average`` metering: the reflectance the image's mean is taken to be (ISO 2720's 18 % grey).
    metering_target: float = 0.18
    #: ``percentile`` metering: the percentile of each channel taken as the white (99: 1 % of the pixels may
    #: exceed white_fill, so a few specular highlights do not darken the picture).
    metering_percentile: float = 99.0

    def validate(self) -> None:
        from spectracam.sensor.metering import METERING_METHODS

        if self.metering != "auto":
            self.choice("metering", METERING_METHODS)
        self.number("metering_target", 0.01, 1.0)
        self.number("metering_percentile", 50.0, 100.0)
        self.choice("architecture", ARCHITECTURES)
        self.choice("exposure", EXPOSURE_SCHEMES)
        self.choice("cfa_pattern", CFA_PATTERNS)
        self.choice("fixed_pattern", FIXED_PATTERN_CHOICES)
        self.number("white_fill", 0.01, 1)
        if self.exposure == "split" or self.exposure_split:
            split = self.exposure_split
            if self.exposure != "split":
                raise self.error("exposure_split", "shares are given, so capture.exposure must be 'split'", list(split))
            if (not isinstance(split, (tuple, list)) or not 2 <= len(split) <= 8
                    or not all(isinstance(x, (int, float)) and not isinstance(x, bool) and 0 < x <= 1 for x in split)):
                raise self.error("exposure_split", "must be one share in (0, 1] per channel", split)
            object.__setattr__(self, "exposure_split", tuple(float(x) for x in split))
        if self.exposure != "single" and not ARCHITECTURES[self.architecture].independent_exposures:
            raise self.error("exposure", f"the {self.architecture} architecture has one exposure for all channels; "
                                         "use 'single'")

    @property
    def design(self) -> str:
        return f"{self.architecture}/{self.exposure}"

    def make_architecture(self) -> Architecture:
        return make_architecture(self.architecture, self.cfa_pattern, self.fixed_pattern)


@dataclass(frozen=True)
class CameraSpec(Spec):
    """Everything between the scene and the digital numbers."""

    optics: OpticsSpec = field(default_factory=OpticsSpec)
    filters: FilterSpec = field(default_factory=FilterSpec)
    sensor: SensorSpec = field(default_factory=SensorSpec)
    capture: CaptureSpec = field(default_factory=CaptureSpec)
    #: The pixel's response to the angle of incidence (microlens, crosstalk, the filters' angle shifts; issue 37).
    pixel: PixelAngleSpec = field(default_factory=PixelAngleSpec)

    def validate(self) -> None:
        for name, kind in (("optics", OpticsSpec), ("filters", FilterSpec), ("sensor", SensorSpec),
                           ("capture", CaptureSpec), ("pixel", PixelAngleSpec)):
            if not isinstance(getattr(self, name), kind):
                raise ConfigError(name, getattr(self, name), f"must be a {kind.__name__}")

    def to_dict(self) -> dict:
        """As :meth:`Spec.to_dict`, the ``pixel`` table left out while it holds its defaults: a camera without it
        records exactly what it recorded before the table existed (its files and the render cache's keys)."""
        out = super().to_dict()
        if self.pixel == PixelAngleSpec():
            del out["pixel"]
        return out

    @classmethod
    def from_dict(cls, data: object, source: str | None = None, base: "CameraSpec | None" = None) -> "CameraSpec":
        """A camera from ``[optics]``/``[filters]``/``[sensor]``/``[capture]``/``[pixel]`` tables; keys not given
        keep the values of ``base`` (default: the paper's camera).

        Parameters
        ----------
        data : object
            A table of those tables (any may be left out); another key is refused.
        source : str or None
            Where the tables came from, for the error.
        base : CameraSpec or None
            The camera whose values fill what is not given; None: the paper's camera.

        Returns
        -------
        CameraSpec
            The validated camera.
        """
        base = base or cls()
        if not isinstance(data, dict):
            raise ConfigError("camera", data, "must be a table", source)
        for k in data:
            if k not in CAMERA_TABLES:
                raise ConfigError(k, data[k], "unknown table; a camera has " + ", ".join(CAMERA_TABLES), source)
        parts = {name: type(getattr(base, name)).from_dict(data.get(name, {}), source, base=getattr(base, name))
                 for name in CAMERA_TABLES}
        return cls(**parts)

    def architecture(self) -> Architecture:
        """The capture's architecture, configured by this camera (e.g. the number of stacked layers)."""
        return self.capture.make_architecture().configure(self)

    @property
    def design(self) -> str:
        """``"architecture/exposure"``, e.g. ``"cfa/single"``."""
        return self.capture.design

    def photo_electron_rates(self, radiance: np.ndarray, grid: WavelengthGrid) -> np.ndarray:
        """Noise-free photo-electron rates of this camera (:func:`photo_electron_rates`): what the scene's chart
        reference asks of a camera, without importing the camera stage it sits below.

        Parameters
        ----------
        radiance : ndarray
            ``(…, B)`` band-averaged spectral radiance, W·m⁻²·sr⁻¹·nm⁻¹.
        grid : WavelengthGrid
            The bands.

        Returns
        -------
        ndarray
            ``(…, N)`` photo-electrons per second per pixel, one per channel.
        """
        return photo_electron_rates(radiance, grid, self)

    def with_design(self, design: str, field: str = "design") -> "CameraSpec":
        """This camera with another ``"arch/scheme"`` design, validated (cfa + optimal is refused);
        an error names ``field``.

        Parameters
        ----------
        design : str
            ``"architecture/exposure"``, e.g. ``"fsc/optimal"`` (``"cfa"`` alone: ``cfa/single``).
        field : str
            The field or option that gave it, for the error.

        Returns
        -------
        CameraSpec
            A copy with the capture's architecture and exposure scheme replaced.
        """
        arch, scheme = split_design(design, field)
        try:
            return self.replace(capture=self.capture.replace(architecture=arch, exposure=scheme))
        except ConfigError as e:
            raise ConfigError(field, design, e.allowed) from None


def camera_responsivities(camera: CameraSpec, grid: WavelengthGrid) -> np.ndarray:
    """``(N, n_bands)`` band-averaged responsivities R_k(λ) of the channels the camera's architecture
    records, electrons per photon (paper 3.3): by default the three filters × QE × IR cut; an
    architecture with other channels (a W pixel, complementary filters, stacked photodiodes) says
    what they are.

    Parameters
    ----------
    camera : CameraSpec
        The camera (its filters and architecture).
    grid : WavelengthGrid
        The bands.

    Returns
    -------
    ndarray
        ``(N, n_bands)``, electrons per photon.
    """
    return camera.architecture().responsivities(camera.filters, grid)


def band_weights(camera: CameraSpec, grid: WavelengthGrid) -> np.ndarray:
    """Weights turning band-averaged radiance into photo-electrons per second per pixel, one column per channel.

    Parameters
    ----------
    camera : CameraSpec
        The camera: its optics (f-number N, transmittance T), channels' responsivities R_k(λ) and pixel area A.
    grid : WavelengthGrid
        The bands (centres λ and widths Δλ, nm) of the radiance.

    Returns
    -------
    ndarray
        ``(n_bands, N)`` float32 weights ``π/(4N²)·T·λ/(hc)·R_k(λ)·Δλ·A`` (paper 3.2–3.3; the paraxial form, or
        the optics' ``irradiance_form``), electrons per second per pixel per W·m⁻²·sr⁻¹·nm⁻¹.

    References
    ----------
    .. [Catrysse1999] see docs/references.md; sections 3.2 and 3.3.

    Examples
    --------
    >>> grid = WavelengthGrid(np.arange(400.0, 701.0, 10.0))
    >>> band_weights(CameraSpec(), grid).shape
    (31, 3)
    """
    to_photons = radiance_to_photon_irradiance(grid, camera.optics)  # (B,)
    R = camera_responsivities(camera, grid)  # (N, B) e⁻/photon
    area_m2 = camera.sensor.pixel_area_um2 * 1e-12
    return (R * (to_photons * grid.widths_nm * area_m2)[None, :]).T.astype(np.float32)


def photo_electron_rates(radiance: np.ndarray, grid: WavelengthGrid, camera: CameraSpec) -> np.ndarray:
    """Photo-electrons per second per pixel for each channel of band-averaged radiance.

    The cube is read once and never copied.

    Parameters
    ----------
    radiance : ndarray
        ``(..., n_bands)`` band-averaged radiance, W·m⁻²·sr⁻¹·nm⁻¹.
    grid : WavelengthGrid
        Its bands, nm.
    camera : CameraSpec
        The camera (:func:`band_weights`).

    Returns
    -------
    ndarray
        ``(..., N)`` float32 photo-electrons per second per pixel, one per channel.

    References
    ----------
    .. [Catrysse1999] see docs/references.md; sections 3.2 and 3.3.
    """
    weights = band_weights(camera, grid)
    shape = radiance.shape
    return (radiance.reshape(-1, shape[-1]) @ weights).reshape(*shape[:-1], weights.shape[1])
