"""Measured camera sensitivities: a library of real cameras, a user's own curves, and their true gains.

A camera's spectral sensitivity ``S_k(λ)`` is what its raw channel ``k`` records per unit of light
at ``λ``.  Published sets come in one of three units (``CAMERA_UNITS``):

``relative``              per unit radiant energy, arbitrary scale (the NPL set of Darrodi et al. 2015
                          and rawtoaces' curves: raw = ∫S_k(λ)·L(λ)dλ with L in W·…·nm⁻¹);
``A/W``                   absolute responsivity, photocurrent per watt;
``electrons_per_photon``  absolute quantum efficiency.

spectracam counts photons, so each becomes a responsivity in electrons per photon: ``S·hc/(qλ)`` for
A/W, as given for electrons per photon, and ``∝ S/λ`` for relative curves, scaled so that the
largest value over all channels is the filter spec's ``qe_peak`` — the channels keep their measured
*relative* gains.  (That the published curves are per unit energy is checked, not assumed: the
Canon's curves, which were published with their gains, give the white the neutral its published
matrix implies within 2 % read per energy, and miss it by 13 % in R/G read per photon.)

Some sets are normalised to a peak of 1 *per channel*, which throws the gains away.  Such a set is
restored here from a published reference — the neutral ``n = M·XYZ(D65)`` that the camera's
published XYZ(D65)→camera matrix ``M`` implies for a perfect white under CIE D65: the gains
``g_k`` make the curves' response to D65 equal ``n`` — or, with no reference, refused with one line.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from spectracam.core.errors import ConfigError
from spectracam.core.spectra import PLANCK_H_J_S, SPEED_OF_LIGHT_M_S

if TYPE_CHECKING:
    from spectracam.architecture.filters import FilterSpec

__all__ = ["CAMERAS", "CAMERA_UNITS", "ELEMENTARY_CHARGE_C", "FROM_FILE", "PEAK_TOLERANCE",
           "PUBLISHED_MATRICES", "SINGULAR_CONDITION", "CameraCurves", "PublishedMatrix", "camera_curves_of",
           "channel_condition", "check_covers", "d65_response", "d65_white_xyz", "energy_sensitivities",
           "file_gains", "library_curves", "library_table", "load_camera_csv", "peak_normalised",
           "restored_gains", "to_electrons_per_photon"]

#: Units a camera's curves may be given in (module docstring).
CAMERA_UNITS = ("relative", "A/W", "electrons_per_photon")
#: Elementary charge, C (CODATA 2018, exact): A/W → electrons per photon is ``S·hc/(qλ)``.
ELEMENTARY_CHARGE_C = 1.602176634e-19
#: ``filters.camera`` for curves read from ``filters.camera_file``.
FROM_FILE = "file"


@dataclass(frozen=True)
class PublishedMatrix:
    """A camera's published XYZ(D65) → camera-raw matrix (rows R, G, B), as Adobe's DNG Converter
    gives it (``ColorMatrix2``, calibration illuminant D65) and dcraw/LibRaw tabulate it ×10⁴."""

    model: str
    xyz_to_camera: tuple  # 9 numbers, row-major
    source: str

    @property
    def matrix(self) -> np.ndarray:
        return np.asarray(self.xyz_to_camera, float).reshape(3, 3)

    def neutral(self, white_xyz: np.ndarray) -> np.ndarray:
        """The raw response ``M·XYZ`` to a neutral of chromaticity ``white_xyz``, G = 1.

        Parameters
        ----------
        white_xyz : ndarray
            ``(3,)`` CIE 1931 XYZ of the neutral (any scale).

        Returns
        -------
        ndarray
            ``(3,)`` the raw R, G, B response, G = 1.
        """
        n = self.matrix @ np.asarray(white_xyz, float)
        return n / n[1]


#: Published matrices, ×10⁴ as tabulated (the numbers carry over; nothing else does).  The Canon's and
#: the Nikon's appear identically in dcraw's ``adobe_coeff`` table (D. Coffin, dcraw.c, rev. 1.477),
#: LibRaw's ``src/tables/colordata.cpp`` and darktable's ``src/external/adobe_coeff.c``: Adobe DNG
#: Converter's ColorMatrix2 (D65) for the camera (the Canon's also as decimals in colour-hdri's test of
#: a real 5D Mark II DNG; RawTherapee's camconst.json has -7799 for its fourth number since 2021).
PUBLISHED_MATRICES = {
    "Canon EOS 5D Mark II": PublishedMatrix(
        "Canon EOS 5D Mark II", (4716, 603, -830, -7798, 15474, 2480, -1496, 1937, 6651),
        "Adobe DNG Converter ColorMatrix2 (D65), as tabulated ×10⁴ in dcraw's adobe_coeff, LibRaw "
        "src/tables/colordata.cpp and darktable src/external/adobe_coeff.c"),
    "Nikon D5100": PublishedMatrix(
        "Nikon D5100", (8198, -2239, -724, -4871, 12389, 2798, -1043, 2050, 7181),
        "Adobe DNG Converter ColorMatrix2 (D65), as tabulated ×10⁴ in dcraw's adobe_coeff, LibRaw "
        "src/tables/colordata.cpp and darktable src/external/adobe_coeff.c"),
    # Adobe publishes no matrix for any Foveon Merrill; LibRaw's own (its colordata.cpp, "Merrills + SD1",
    # tagged /* LibRaw */, since LibRaw 0.16, 2013: one matrix for the SD1, SD1 Merrill and DP1-3 Merrill)
    # is the published reference used.  It puts the white's bottom (R) and middle (G) layers 1.9 and 0.8
    # stops below the top (B), as J. Kasson measured on dpreview's DP1 Merrill raw of a white patch
    # ("Why Foveon images are so noisy", blog.kasson.com: middle a bit less than a stop below the top,
    # bottom about two).
    "Sigma SD1 Merrill": PublishedMatrix(
        "Sigma SD1 Merrill", (5133, -1895, -353, 4978, 744, 144, 3837, 3069, 2777),
        "LibRaw's own matrix (src/tables/colordata.cpp, 'Merrills + SD1', tagged LibRaw; Adobe publishes none "
        "for the Merrills); consistent with J. Kasson's layer ratios measured on a DP1 Merrill raw of a white"),
}


@dataclass(frozen=True)
class CameraCurves:
    """One camera's measured sensitivities as published, and what is known about their scale."""

    name: str
    wavelengths_nm: np.ndarray  # (n,), increasing
    values: np.ndarray  # (n, 3): R, G, B in ``unit``
    unit: str
    source: str
    #: How the publication scaled the data: "relative gains kept" or "each channel to a peak of 1".
    normalisation: str
    #: The published matrix of this camera (a key of PUBLISHED_MATRICES), or None.
    matrix: str | None = None
    #: True when the channels were normalised one by one, so their gains must be restored.
    per_channel: bool = False

    @property
    def range_nm(self) -> tuple[float, float]:
        return float(self.wavelengths_nm[0]), float(self.wavelengths_nm[-1])

    @property
    def gains_note(self) -> str:
        """How the channels' relative gains were obtained (``spectracam cameras`` prints it)."""
        if not self.per_channel:
            return "as published"
        if self.matrix:
            g = restored_gains(self.name)
            return (f"restored: the D65 neutral of the {self.matrix} published matrix "
                    f"(gains R {g[0]:.3f}, G 1, B {g[2]:.3f} on the per-channel-normalised curves)")
        return "lost (each channel normalised) and no published reference: refused"


def _colour_dataset(name: str) -> tuple[np.ndarray, np.ndarray]:
    from spectracam.core import colour_data

    return colour_data.camera_sensitivities(name)


def _rawtoaces_canon() -> tuple[np.ndarray, np.ndarray]:
    from spectracam.core import colour_data

    path = colour_data.colour_package_file("characterisation", "datasets", "rawtoaces",
                                           "CANON_EOS_5DMark_II_RGB_Sensitivities.csv")
    d = np.loadtxt(path, delimiter=",", skiprows=1)
    return d[:, 0], d[:, 1:4]


_NPL = ("M. M. Darrodi, G. Finlayson, T. Goodman, M. Mackiewicz, 'Reference data set for camera spectral "
        "sensitivity estimation', J. Opt. Soc. Am. A 32(3), 381-391 (2015); shipped by colour-science "
        "(MSDS_CAMERA_SENSITIVITIES)")
#: name → (loader, source, normalisation, published matrix, per-channel normalised)
_LIBRARY = {
    "Nikon 5100 (NPL)": (lambda: _colour_dataset("Nikon 5100 (NPL)"), _NPL, "each channel to a peak of 1",
                         "Nikon D5100", True),
    "Sigma SDMerill (NPL)": (lambda: _colour_dataset("Sigma SDMerill (NPL)"), _NPL, "each channel to a peak of 1",
                             "Sigma SD1 Merrill", True),
    "Canon EOS 5D Mark II (rawtoaces)": (
        _rawtoaces_canon, "Academy rawtoaces, CANON_EOS_5DMark_II_RGB_Sensitivities.csv (shipped by colour-science, "
        "colour/characterisation/datasets/rawtoaces)", "relative gains kept (G peak 1)", "Canon EOS 5D Mark II",
        False),
}
#: Every camera ``filters.camera`` can name (plus "file" for ``filters.camera_file``).
CAMERAS = tuple(_LIBRARY)


@lru_cache(maxsize=None)
def library_curves(name: str) -> CameraCurves:
    """The shipped camera ``name`` as published (gains not yet restored).

    Parameters
    ----------
    name : str
        One of :data:`CAMERAS`.

    Returns
    -------
    CameraCurves
        Its curves in the ``"relative"`` unit (per unit energy), with source and normalisation.
    """
    loader, source, norm, matrix, per_channel = _LIBRARY[name]
    wl, v = loader()
    return CameraCurves(name, wl, v, "relative", source, norm, matrix, per_channel)


def d65_white_xyz() -> np.ndarray:
    """XYZ of CIE D65 (CIE 1931 2°, Y = 1), from its tabulated spectrum at 1 nm over 360–830 nm."""
    from spectracam.core import colour_data
    from spectracam.core.spectra import cie_1931_cmfs

    wl, cmfs = cie_1931_cmfs()
    E = np.interp(wl, *colour_data.illuminant_sd("D65"))
    xyz = np.trapezoid(E[:, None] * cmfs, wl, axis=0)
    return xyz / xyz[1]


def d65_response(wl: np.ndarray, values: np.ndarray,
                 reflectance: Callable[[np.ndarray], np.ndarray] | None = None) -> np.ndarray:
    """Raw response ``∫S_k·ρ·E_D65 dλ`` (energy sensitivities ``values`` on ``wl``) to a surface of
    reflectance ``ρ`` (a spectrum; default a perfect white) under CIE D65, at 1 nm, G = 1.

    Parameters
    ----------
    wl : ndarray
        ``(n,)`` wavelengths, nm, increasing.
    values : ndarray
        ``(n, 3)`` energy sensitivities R, G, B.
    reflectance : callable, optional
        ρ(λ nm) → reflectance; None: a perfect white.

    Returns
    -------
    ndarray
        ``(3,)`` R, G, B response, G = 1.
    """
    from spectracam.core import colour_data

    lam = np.arange(np.ceil(wl[0]), np.floor(wl[-1]) + 1.0)
    E = np.interp(lam, *colour_data.illuminant_sd("D65")) * (1.0 if reflectance is None else reflectance(lam))
    S = np.stack([np.interp(lam, wl, values[:, k]) for k in range(3)], axis=-1)
    r = np.trapezoid(S * E[:, None], lam, axis=0)
    return r / r[1]


@lru_cache(maxsize=None)
def restored_gains(name: str) -> np.ndarray:
    """Per-channel gains ``(3,)`` (G = 1) that give a per-channel-normalised camera the D65 neutral its
    published matrix implies (module docstring); ones for a camera published with its gains.

    Parameters
    ----------
    name : str
        One of :data:`CAMERAS`.

    Returns
    -------
    ndarray
        ``(3,)`` gains, G = 1.

    Raises
    ------
    ConfigError
        A per-channel-normalised camera without a published matrix.
    """
    c = library_curves(name)
    if not c.per_channel:
        return np.ones(3)
    if c.matrix is None:
        raise ConfigError("filters.camera", name, "its curves are normalised to a peak of 1 per channel, so the gains "
                          "between channels are lost, and no published matrix restores them; choose another "
                          "camera, or give its curves with their gains in filters.camera_file")
    return PUBLISHED_MATRICES[c.matrix].neutral(d65_white_xyz()) / d65_response(c.wavelengths_nm, c.values)


def energy_sensitivities(name: str) -> tuple[np.ndarray, np.ndarray]:
    """``(wavelengths_nm, (n, 3))``: a shipped camera's relative energy sensitivities with its true
    (restored) gains, G's peak 1.

    Parameters
    ----------
    name : str
        One of :data:`CAMERAS`.

    Returns
    -------
    wavelengths_nm : ndarray
        ``(n,)``, nm.
    values : ndarray
        ``(n, 3)`` relative energy sensitivities R, G, B.
    """
    c = library_curves(name)
    v = c.values * restored_gains(name)[None, :]
    return c.wavelengths_nm, v / v[:, 1].max()


def to_electrons_per_photon(wl_nm: np.ndarray, values: np.ndarray, unit: str, qe_peak: float) -> np.ndarray:
    """``(n, 3)`` responsivities in electrons per photon from curves in ``unit`` (module docstring);
    relative curves are scaled to a peak of ``qe_peak`` over all channels.

    Parameters
    ----------
    wl_nm : ndarray
        ``(n,)`` wavelengths, nm.
    values : ndarray
        ``(n, 3)`` the curves.
    unit : str
        One of ``CAMERA_UNITS``: ``"relative"`` (per unit energy), ``"A/W"`` or ``"electrons_per_photon"``.
    qe_peak : float
        The largest quantum efficiency of relative curves, electrons per photon.

    Returns
    -------
    ndarray
        ``(n, 3)`` electrons per photon.
    """
    lam = np.asarray(wl_nm, float)[:, None]
    if unit == "electrons_per_photon":
        return np.asarray(values, float)
    if unit == "A/W":
        return np.asarray(values, float) * PLANCK_H_J_S * SPEED_OF_LIGHT_M_S / (ELEMENTARY_CHARGE_C * lam * 1e-9)
    per_photon = np.asarray(values, float) / lam  # energy sensitivity × λ/hc, up to a constant
    return per_photon * (qe_peak / per_photon.max())


#: Relative tolerance within which three channel peaks count as equal, i.e. normalised one by one
#: (measured curves published with their gains differ by far more: the Canon's peaks are 0.48/1/0.69).
PEAK_TOLERANCE = 1e-3


def peak_normalised(values: np.ndarray) -> bool:
    """True when the three channels of ``(n, 3)`` curves share one peak value (to 1, 100 … one by one):
    their relative gains were thrown away (module docstring).

    Parameters
    ----------
    values : ndarray
        ``(n, 3)`` curves.

    Returns
    -------
    bool
        Whether the peaks agree within :data:`PEAK_TOLERANCE`.
    """
    peaks = np.asarray(values, float).max(axis=0)
    return bool(peaks.max() > 0 and (peaks.max() - peaks.min()) <= PEAK_TOLERANCE * peaks.max())


def file_gains(spec: FilterSpec, wl_nm: np.ndarray, values: np.ndarray) -> np.ndarray:
    """``(3,)`` multipliers of a ``filters.camera_file``'s R, G, B columns: ``camera_gains`` as given; else, for
    relative curves normalised per channel, the gains that give the D65 neutral of ``camera_xyz_to_camera``
    (as :func:`restored_gains` does for shipped cameras); else ones (the curves keep their gains).

    Parameters
    ----------
    spec : FilterSpec
        The ``[filters]`` table (``camera_gains``, ``camera_xyz_to_camera``, ``camera_unit``, ``camera_gains_kept``).
    wl_nm : ndarray
        ``(n,)`` the file's wavelengths, nm.
    values : ndarray
        ``(n, 3)`` the file's R, G, B curves.

    Returns
    -------
    ndarray
        ``(3,)`` multipliers.
    """
    if spec.camera_gains:
        return np.asarray(spec.camera_gains, float)
    if (spec.camera_xyz_to_camera and spec.camera_unit == "relative" and not spec.camera_gains_kept
            and peak_normalised(values)):
        m = PublishedMatrix("camera_file", tuple(spec.camera_xyz_to_camera), "filters.camera_xyz_to_camera")
        return m.neutral(d65_white_xyz()) / d65_response(np.asarray(wl_nm, float), np.asarray(values, float))
    return np.ones(3)


#: A condition number beyond this is a singular matrix in double precision (its channels are linearly dependent).
SINGULAR_CONDITION = 1e12


def channel_condition(wl_nm: np.ndarray, values: np.ndarray) -> float:
    """Condition number of ``(n, 3)`` curves resampled at 1 nm over their range, each channel scaled to a sum of
    1 (white-balanced on an equal-energy white): how much a colour conversion must amplify noise in its worst
    direction against its best (∞ for identical or all-zero channels; the shipped cameras 1.9–11).

    Parameters
    ----------
    wl_nm : ndarray
        ``(n,)`` wavelengths, nm, increasing.
    values : ndarray
        ``(n, 3)`` curves.

    Returns
    -------
    float
        The 2-norm condition number; ∞ beyond :data:`SINGULAR_CONDITION`.
    """
    wl = np.asarray(wl_nm, float)
    lam = np.arange(wl[0], wl[-1] + 0.5, 1.0) if wl[-1] - wl[0] >= 2 else wl
    q = np.stack([np.interp(lam, wl, np.asarray(values, float)[:, k]) for k in range(3)], axis=1)
    s = q.sum(axis=0)
    if not np.all(s > 0):
        return float("inf")
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        kappa = float(np.linalg.cond(q / s[None, :]))
    return kappa if np.isfinite(kappa) and kappa < SINGULAR_CONDITION else float("inf")


def camera_curves_of(spec: FilterSpec) -> tuple[np.ndarray, np.ndarray, str]:
    """``(wavelengths_nm, (n, 3) electrons per photon, what)`` of a filter spec's camera (a file's curves
    times :func:`file_gains`).

    Parameters
    ----------
    spec : FilterSpec
        The ``[filters]`` table: ``camera`` (a shipped one, or ``"file"`` with ``camera_curve_nm``/``camera_curve``)
        and ``qe_peak``.

    Returns
    -------
    wavelengths_nm : ndarray
        ``(n,)``, nm.
    responsivities : ndarray
        ``(n, 3)`` R, G, B, electrons per photon.
    what : str
        The field errors name: ``"filters.camera"`` or ``"filters.camera_file"``.
    """
    if spec.camera == FROM_FILE:
        wl = np.asarray(spec.camera_curve_nm, float)
        v = np.asarray(spec.camera_curve, float)
        R = to_electrons_per_photon(wl, v * file_gains(spec, wl, v)[None, :], spec.camera_unit, spec.qe_peak)
        return wl, R, "filters.camera_file"
    wl, v = energy_sensitivities(spec.camera)
    return wl, to_electrons_per_photon(wl, v, "relative", spec.qe_peak), "filters.camera"


def check_covers(spec: FilterSpec, wl_nm: np.ndarray, lo_nm: float, hi_nm: float, what: str) -> None:
    """Refuse curves that do not cover the scene's wavelength range (zero outside would be a guess).

    Parameters
    ----------
    spec : FilterSpec
        The ``[filters]`` table (its camera's name for the error).
    wl_nm : ndarray
        The curves' wavelengths, nm, increasing.
    lo_nm, hi_nm : float
        The scene's bands' span, nm.
    what : str
        The field the error names.

    Raises
    ------
    ConfigError
        The curves start above ``lo_nm`` or end below ``hi_nm``.
    """
    if wl_nm[0] > lo_nm + 1e-9 or wl_nm[-1] < hi_nm - 1e-9:
        value = spec.camera if what == "filters.camera" else f"{wl_nm[0]:g}–{wl_nm[-1]:g} nm"
        raise ConfigError(what, value, f"its curves cover {wl_nm[0]:g}–{wl_nm[-1]:g} nm but the scene's bands span "
                          f"{lo_nm:g}–{hi_nm:g} nm; narrow [wavelengths] (start_nm/stop_nm) to the curves' range")


def load_camera_csv(path: str | Path, what: str = "filters.camera_file") -> tuple[tuple, tuple]:
    """``(wavelengths_nm, rows of (R, G, B))`` from a CSV: a header row is allowed, ``#`` comments,
    comma- or whitespace-separated; exactly four columns (wavelength in nm, then R, G, B).  Every
    number is checked: finite, non-negative, increasing wavelengths, at least 2 rows (else a ConfigError).

    Parameters
    ----------
    path : str or Path
        The CSV file.
    what : str
        The field errors name.

    Returns
    -------
    tuple of (tuple of float, tuple of tuple of float)
        The wavelengths, nm, increasing; ``(R, G, B)`` per wavelength, ≥ 0, in the file's unit.
    """
    from spectracam.core.files import regular_file

    p = regular_file(path, what)
    try:
        text = p.read_bytes().decode("utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise ConfigError(what, str(p), f"cannot be read as a text file ({e.strerror if isinstance(e, OSError) else e})") \
            from None
    rows = [r.replace(",", " ").split() for r in text.splitlines() if r.strip() and not r.lstrip().startswith("#")]
    if rows:
        try:
            float(rows[0][0])
        except ValueError:
            rows = rows[1:]  # a header
    data = []
    for i, r in enumerate(rows):
        try:
            if len(r) != 4:
                raise ValueError(f"{len(r)} columns")
            data.append([float(x) for x in r])
        except ValueError as e:
            raise ConfigError(what, str(p), f"row {i + 1}: need 4 numbers — wavelength (nm), R, G, B ({e})") from None
    a = np.array(data, float).reshape(-1, 4)
    if len(a) < 2:
        raise ConfigError(what, str(p), f"has {len(a)} rows; need ≥ 2 rows of wavelength (nm), R, G, B")
    if not np.all(np.isfinite(a)):
        i = int(np.flatnonzero(~np.all(np.isfinite(a), axis=1))[0])
        raise ConfigError(what, str(p), f"row {i + 1} is not finite ({a[i].tolist()}); every value must be a number")
    if np.any(np.diff(a[:, 0]) <= 0):
        i = int(np.flatnonzero(np.diff(a[:, 0]) <= 0)[0])
        raise ConfigError(what, str(p), f"wavelengths must increase: {a[i, 0]:g} nm is followed by {a[i + 1, 0]:g} nm")
    if a[0, 0] <= 0:
        raise ConfigError(what, str(p), f"wavelengths are in nm and > 0; the first is {a[0, 0]:g}")
    if np.any(a[:, 1:] < 0):
        i = int(np.flatnonzero(np.any(a[:, 1:] < 0, axis=1))[0])
        raise ConfigError(what, str(p), f"sensitivities must be ≥ 0; row {i + 1} ({a[i, 0]:g} nm) has {a[i, 1:].tolist()}")
    if not np.all(a[:, 1:].max(axis=0) > 0):
        raise ConfigError(what, str(p), "every channel (R, G, B) needs a sensitivity > 0 somewhere")
    return tuple(a[:, 0].tolist()), tuple(tuple(r) for r in a[:, 1:].tolist())


def library_table() -> list[dict]:
    """One row per shipped camera: name, range, source, normalisation, gains and published matrix."""
    rows = []
    for name in CAMERAS:
        c = library_curves(name)
        gains, usable = c.gains_note, not (c.per_channel and c.matrix is None)
        m = PUBLISHED_MATRICES.get(c.matrix) if c.matrix else None
        rows.append({"name": name, "range_nm": list(c.range_nm), "unit": c.unit, "normalisation": c.normalisation,
                     "gains": gains, "usable": usable, "published_matrix": m.model if m else None,
                     "matrix_source": m.source if m else None, "source": c.source})
    return rows
