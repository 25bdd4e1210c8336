"""Colour filters and sensor quantum efficiency → spectral responsivities R_k(λ) (paper, section 3.3).

``R_k(λ) = filter transmittance_k(λ) × QE(λ)`` in electrons per photon, band-averaged on the
scene's wavelength grid, channels in the order R, G, B.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from spectracam.core.errors import ConfigError
from spectracam.core.registry import Registry
from spectracam.core.spec import Spec, check_curve
from spectracam.architecture.cameras import CAMERA_UNITS, CAMERAS, FROM_FILE
from spectracam.core.spectra import (Spectrum, WavelengthGrid, band_average, cmf_band_weights, logistic_cut,
                                     logistic_scale_nm, tabulated)
from spectracam.architecture.layers import LAYER_COUNTS, MAX_CONDITION, check_layers

__all__ = ["CHANNELS", "FILTER_KINDS", "QE_MODELS", "SILICON_QE_SHAPE", "FilterSpec", "clear_responsivity", "ir_cut",
           "load_curve", "quantum_efficiency", "responsivities"]

CHANNELS = ("R", "G", "B")
#: Filter kinds: name → function ``(spec, grid) → (3, n_bands)`` band-averaged responsivities.
FILTER_KINDS: Registry = Registry("filters.kind", "filter kind")
#: Quantum-efficiency models: name → function ``spec → QE(λ)`` (a vectorised spectrum).
QE_MODELS: Registry = Registry("filters.qe", "quantum-efficiency model")

#: A silicon-like external QE of a front-illuminated CMOS photodiode without IR-cut filter: low in
#: the blue (shallow absorption, surface recombination), peaking near 550–650 nm, falling into the
#: red.  Shape after typical published curves (e.g. Theuwissen, "Solid-State Imaging with
#: Charge-Coupled Devices", 1995, Fig. 4.9); scaled by ``qe_peak``.
SILICON_QE_SHAPE = (
    (380.0, 400.0, 450.0, 500.0, 550.0, 600.0, 650.0, 700.0, 750.0, 800.0, 850.0),
    (0.25, 0.35, 0.60, 0.80, 0.95, 1.00, 0.97, 0.88, 0.75, 0.60, 0.45),
)


@dataclass(frozen=True)
class FilterSpec(Spec):
    #: "block" (the paper, 4.3: ideal pass bands), "gaussian" (centres, FWHM), "transmittance" (tabulated),
    #: "camera", or "xyz":
    #: the CIE 1931 colour-matching functions in quantal form, x̄ȳz̄(λ)·(555 nm/λ), times the QE — with
    #: ``qe = "flat"`` a camera that meets the Luther condition exactly (its photon counts are a
    #: linear transform of XYZ).
    TABLE = "filters"

    kind: str = "block"
    #: Block filter cutoffs, nm: blue below the first, green between, red above (paper: 490, 610).
    cutoffs_nm: tuple[float, float] = (490.0, 610.0)
    #: Block filters' edges: 0 — ideal steps (the paper's); > 0 — logistic edges rising from 10 % to 90 % over
    #: this many nm, 50 % at each cutoff (a real dichroic or dye edge; the design's smooth block filters).
    edge_width_nm: float = 0.0
    #: "transmittance" filters: wavelengths (nm) and rows of (R, G, B) transmittances in [0, 1], linear between
    #: them, 0 outside (a designed or measured filter set; the sensor's QE and IR cut multiply them).
    transmittance_nm: tuple = ()
    transmittance: tuple = ()
    #: Gaussian filters: centres and full widths at half maximum for R, G, B, nm.
    centres_nm: tuple[float, float, float] = (610.0, 540.0, 460.0)
    fwhm_nm: tuple[float, float, float] = (60.0, 60.0, 60.0)
    #: A measured camera (``spectracam cameras`` lists them, with their gains' origin), or "file":
    #: the curves of ``camera_file``, which a scene/config file names and which is read into
    #: ``camera_curve_nm``/``camera_curve`` (the data are recorded, not the path).
    camera: str = "Nikon 5100 (NPL)"
    camera_curve_nm: tuple = ()
    #: rows of (R, G, B) sensitivities, one per wavelength of ``camera_curve_nm``
    camera_curve: tuple = ()
    #: Unit of ``camera_file``'s curves: "relative" (per unit radiant energy, arbitrary scale, gains
    #: between channels as given; scaled to a peak of ``qe_peak`` electrons per photon), "A/W", or
    #: "electrons_per_photon" (absolute: used as given).
    camera_unit: str = "relative"
    #: "flat" or "silicon" (:data:`SILICON_QE_SHAPE`).
    qe: str = "flat"
    #: Peak quantum efficiency, electrons per photon.  The paper states none; 0.5 is typical of
    #: front-illuminated CMOS photodiodes of the paper's time (0.3–0.6).
    qe_peak: float = 0.5
    #: "photodiode" QE: depth below the surface from which carriers are collected, µm.  A CMOS
    #: photodiode of the late 1990s (0.35–0.5 µm processes: shallow junctions, epitaxial layers of a
    #: few µm) collects from ~2–4 µm; 3 µm by default.
    collection_depth_um: float = 3.0
    #: "data" QE: a measured curve (wavelength nm, QE), e.g. read from ``qe_file`` in a scene file.
    qe_curve_nm: tuple = ()
    qe_curve: tuple = ()
    #: IR-cut filter: wavelength of 50 % transmittance, nm (None: no IR-cut filter, as the paper).
    ir_cut_nm: float | None = None
    #: IR-cut filter: width of its edge from 90 % to 10 % transmittance, nm (a logistic edge).
    ir_cut_width_nm: float = 20.0
    #: Stacked photodiodes (architecture "stacked"): the boundaries of the collection windows below
    #: the surface, µm — a surface dead layer, then one window per photodiode from the top (4 numbers
    #: for 3 layers, 5 for 4).  Defaults fitted, with the IR cut below, to the Sigma SD1 Merrill
    #: (spectracam.architecture.stacked); layers that cannot form a colour image are refused.
    stacked_depths_um: tuple = (0.245, 1.15, 2.61, 4.34)
    #: The IR-cut filter in front of a stacked sensor, 50 % point, nm ("none": no filter): the SD1 Merrill's,
    #: read off NPL's measured curves (they fall from 92 % to 18 % of their peaks between 650 and 660 nm).
    #: Only the stacked architecture reads it; ``ir_cut_nm``, if set, is a second filter in series.
    stacked_ir_cut_nm: float | None = 655.0
    #: Its edge from 90 % to 10 % transmittance, nm (the measured curves: about 10 nm).
    stacked_ir_cut_width_nm: float = 10.0
    #: ``camera_file`` curves normalised to a peak of 1 per channel lose their gains: give them here
    #: (R, G, B multipliers of the file's columns) ...
    camera_gains: tuple = ()
    #: ... or the camera's published XYZ(D65)→camera matrix (9 numbers, row-major, e.g. Adobe's ColorMatrix2
    #: ×10⁴ as dcraw tabulates it), from whose D65 neutral the gains are restored as for the shipped cameras
    #: (spectracam.architecture.cameras); with curves that keep their gains it is only what ``spectracam validate`` checks.
    camera_xyz_to_camera: tuple = ()
    #: ... or say that the file's equal channel peaks are real (its gains are as measured).
    camera_gains_kept: bool = False

    def validate(self) -> None:
        self.choice("kind", FILTER_KINDS)
        self.numbers("cutoffs_nm", 2, 0, increasing=True, unit="nm")
        self.number("edge_width_nm", 0, 200, unit="nm")
        _check_transmittance(self)
        self.numbers("centres_nm", 3, 0, unit="nm")
        self.numbers("fwhm_nm", 3, 1e-3, unit="nm")
        if self.camera != FROM_FILE:
            self.choice("camera", (*CAMERAS, FROM_FILE))
        self.choice("camera_unit", CAMERA_UNITS)
        _check_camera_curve(self)
        if self.kind == "camera" and self.qe != "flat":
            raise self.error("qe", "measured camera curves already include the sensor's quantum efficiency; with "
                                   "kind = 'camera' use qe = 'flat' (qe_peak sets the curves' peak)")
        self.choice("qe", QE_MODELS)
        self.number("qe_peak", 0, 1, lo_open=True)
        self.number("collection_depth_um", 0.01, 1000, unit="µm")
        check_curve(self, "qe_curve_nm", "qe_curve", required=self.qe == "data")
        if self.ir_cut_nm is not None:
            self.number("ir_cut_nm", 300, 1200, unit="nm")
        self.number("ir_cut_width_nm", 0.1, 500, unit="nm")
        if isinstance(self.stacked_ir_cut_nm, str) and self.stacked_ir_cut_nm.lower() == "none":
            object.__setattr__(self, "stacked_ir_cut_nm", None)
        if self.stacked_ir_cut_nm is not None:
            if not isinstance(self.stacked_ir_cut_nm, (int, float)) or isinstance(self.stacked_ir_cut_nm, bool):
                raise self.error("stacked_ir_cut_nm", "must be a number between 300 and 1200 nm, or \"none\"")
            self.number("stacked_ir_cut_nm", 300, 1200, unit="nm")
        self.number("stacked_ir_cut_width_nm", 0.1, 500, unit="nm")
        depths = self.stacked_depths_um
        lo, hi = LAYER_COUNTS[0] + 1, LAYER_COUNTS[-1] + 1
        if not isinstance(depths, (tuple, list)) or not lo <= len(depths) <= hi:
            raise self.error("stacked_depths_um", f"must be {lo} or {hi} depths in µm (a dead layer, then the bottom of "
                                                  f"each of {LAYER_COUNTS[0]} or {LAYER_COUNTS[-1]} stacked photodiodes: "
                                                  "a colour needs three layers, a DNG holds four colour planes at most)",
                             list(depths) if isinstance(depths, (tuple, list)) else depths)
        self.numbers("stacked_depths_um", len(depths), 0, increasing=True, unit="µm")
        if self.stacked_depths_um[-1] > 100:
            raise self.error("stacked_depths_um", "the deepest window must end within 100 µm of the surface",
                             list(self.stacked_depths_um))
        check_layers(self)


def _check_transmittance(spec: FilterSpec) -> None:
    """``kind = "transmittance"`` needs ≥ 2 increasing wavelengths, each with 3 transmittances in [0, 1]."""
    wl, rows = spec.transmittance_nm, spec.transmittance
    if spec.kind != "transmittance":
        if wl or rows:
            raise spec.error("transmittance", "transmittances are given, so filters.kind must be 'transmittance'", "…")
        return
    try:
        w, a = np.asarray(wl, float), np.asarray(rows, float)
        ok = w.ndim == 1 and w.size >= 2 and a.shape == (w.size, 3)
    except (TypeError, ValueError):
        ok = False
    if not ok or not np.all(np.isfinite(w)) or not np.all(np.isfinite(a)) or np.any(np.diff(w) <= 0):
        raise spec.error("transmittance", "must be ≥ 2 increasing wavelengths (transmittance_nm), each with a row of "
                                          "3 finite transmittances (R, G, B)", "…")
    if a.min() < 0 or a.max() > 1:
        raise spec.error("transmittance", "transmittances must lie in [0, 1]", [float(a.min()), float(a.max())])
    object.__setattr__(spec, "transmittance_nm", tuple(w.tolist()))
    object.__setattr__(spec, "transmittance", tuple(tuple(r) for r in a.tolist()))


def _check_camera_curve(spec: FilterSpec) -> None:
    """``camera = "file"`` needs curves (wavelengths and rows of R, G, B), and curves need it."""
    wl, rows = spec.camera_curve_nm, spec.camera_curve
    spec.boolean("camera_gains_kept")
    if spec.camera != FROM_FILE:
        if wl or rows:
            raise spec.error("camera_curve", f"curves are given, so filters.camera must be {FROM_FILE!r}", "…")
        for name in ("camera_gains", "camera_xyz_to_camera"):
            if getattr(spec, name):
                raise spec.error(name, "applies only to a camera of your own (filters.camera_file)",
                                 list(getattr(spec, name)))
        return
    if spec.kind != "camera":  # the curves would be read and then ignored
        raise spec.error("kind", "curves are given (filters.camera_file), so filters.kind must be 'camera' (or leave "
                                 "kind out: camera_file implies it)")
    if not wl:
        raise spec.error("camera", "needs filters.camera_file (a CSV: wavelength nm, R, G, B)")
    try:
        w = np.asarray(wl, float)
        a = np.asarray(rows, float)
        ok = w.ndim == 1 and a.shape == (w.size, 3) and w.size >= 2
    except (TypeError, ValueError):
        ok = False
    if not ok or not np.all(np.isfinite(w)) or not np.all(np.isfinite(a)) or np.any(np.diff(w) <= 0) or np.any(a < 0):
        raise spec.error("camera_curve", "must be ≥ 2 increasing wavelengths (nm), each with 3 finite "
                                         "sensitivities ≥ 0 (R, G, B)", "…")
    object.__setattr__(spec, "camera_curve_nm", tuple(w.tolist()))
    object.__setattr__(spec, "camera_curve", tuple(tuple(r) for r in a.tolist()))
    _check_camera_gains(spec, w, a)
    if spec.camera_unit != "relative":  # absolute curves: no photodiode gives more than 1 electron a photon
        from spectracam.architecture.cameras import to_electrons_per_photon

        qe = to_electrons_per_photon(w, a, spec.camera_unit, spec.qe_peak)
        if qe.max() > 1.0:
            i, k = np.unravel_index(int(np.argmax(qe)), qe.shape)
            raise spec.error("camera_unit", f"the curves in this unit mean {qe.max():.3g} electrons per photon "
                                            f"({'RGB'[k]} at {w[i]:g} nm); a quantum efficiency is ≤ 1 — is the unit "
                                            "'relative'?")


def _check_camera_gains(spec: FilterSpec, w: np.ndarray, a: np.ndarray) -> None:
    """A user's curves keep their gains between channels, or say how to get them (spectracam.architecture.cameras):
    ``camera_gains`` (3 numbers > 0), ``camera_xyz_to_camera`` (9 numbers, an invertible matrix whose D65 neutral
    is positive), or ``camera_gains_kept``; curves in "relative" units whose three channels peak at the same value
    (peak-normalised, each to 1 or 100 …) with none of these are refused.  Then the channels must be able to
    form a colour: their condition number (spectracam.architecture.cameras.channel_condition) at most that of the stacked
    sensor's bound."""
    from spectracam.architecture.cameras import channel_condition, file_gains, peak_normalised

    gains, matrix = spec.camera_gains, spec.camera_xyz_to_camera
    if gains:
        ok = (isinstance(gains, tuple) and len(gains) == 3 and all(_is_real(g) for g in gains)
              and all(0 < g < float("inf") for g in gains))
        if not ok:
            raise spec.error("camera_gains", "must be 3 finite numbers > 0 (the R, G, B columns' multipliers)",
                             list(gains) if isinstance(gains, tuple) else gains)
        object.__setattr__(spec, "camera_gains", tuple(float(g) for g in gains))
    if matrix:
        flat = matrix
        if isinstance(matrix, tuple) and len(matrix) == 3 and all(isinstance(r, (tuple, list)) for r in matrix):
            flat = tuple(x for r in matrix for x in r)  # a 3×3 table
        ok = isinstance(flat, tuple) and len(flat) == 9 and all(_is_real(x) for x in flat) \
            and np.all(np.isfinite(np.asarray(flat, float)))
        if not ok:
            raise spec.error("camera_xyz_to_camera", "must be 9 finite numbers: the XYZ(D65)→camera matrix, row-major "
                                                     "(rows R, G, B)", list(matrix) if isinstance(matrix, tuple) else matrix)
        m = np.asarray(flat, float).reshape(3, 3)
        if np.linalg.cond(m) > 1e8:
            raise spec.error("camera_xyz_to_camera", "must be an invertible 3×3 matrix (this one is singular)", list(flat))
        from spectracam.architecture.cameras import d65_white_xyz

        n = m @ d65_white_xyz()
        if not np.all(n > 0):
            raise spec.error("camera_xyz_to_camera", f"gives the D65 white a raw neutral {np.round(n, 4).tolist()}: every "
                                                     "channel of a white must be > 0 — is it XYZ→camera, rows R, G, B?",
                             list(flat))
        object.__setattr__(spec, "camera_xyz_to_camera", tuple(float(x) for x in flat))
    if gains and matrix:
        raise spec.error("camera_gains", "give the gains or the matrix to restore them from (camera_xyz_to_camera), "
                                         "not both", list(gains))
    if spec.camera_unit == "relative" and peak_normalised(a) and not (gains or matrix or spec.camera_gains_kept):
        raise spec.error("camera_file", "its three channels all peak at the same value, so they were normalised one "
                                        "by one and the gains between them are lost (a D65 white would read wrong); "
                                        "give filters.camera_gains = [R, G, B], or filters.camera_xyz_to_camera = "
                                        "[9 numbers] (the camera's published XYZ(D65)→camera matrix, to restore them "
                                        "from), or filters.camera_gains_kept = true if the equal peaks are real",
                         f"{w[0]:g}–{w[-1]:g} nm, peaks {np.round(a.max(axis=0), 6).tolist()}")
    g = file_gains(spec, w, a)
    kappa = channel_condition(w, a * g[None, :])
    if kappa > MAX_CONDITION:
        shown = "∞" if kappa == float("inf") else format(kappa, ".3g")
        raise spec.error("camera_file", f"its channels are so alike (condition number {shown}; identical channels "
                                        f"give ∞) that no colour conversion can separate them; allowed ≤ "
                                        f"{MAX_CONDITION:g} (the shipped cameras: 1.9–11)",
                         f"{w[0]:g}–{w[-1]:g} nm")


def _is_real(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def load_curve(path: str | Path, what: str) -> tuple[tuple, tuple]:
    """``(wavelengths_nm, values)`` from a CSV (two columns, ``#`` comments, an optional header) or a
    TOML file (``wavelength_nm = [...]``, ``values = [...]``).

    Parameters
    ----------
    path : str or Path
        The file (``.toml`` read as TOML, anything else as CSV).
    what : str
        The field that named it, for the error.

    Returns
    -------
    tuple of (tuple, tuple)
        Wavelengths, nm, and the values (checked, and made floats, by the spec that holds them).
    """
    from pathlib import Path

    from spectracam.core.files import regular_file

    p = regular_file(path, what)
    try:
        text = p.read_bytes().decode("utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise ConfigError(what, str(p), f"cannot be read as a text file ({e})") from None
    try:
        if p.suffix.lower() == ".toml":
            import tomllib

            d = tomllib.loads(text)
            return tuple(d["wavelength_nm"]), tuple(d["values"])
        rows = [r for r in text.splitlines() if r.strip() and not r.lstrip().startswith("#")]
        if rows and not rows[0].replace(",", " ").split()[0].replace(".", "", 1).isdigit():
            rows = rows[1:]  # a header
        data = np.array([[float(x) for x in r.replace(",", " ").split()[:2]] for r in rows])
        return tuple(data[:, 0].tolist()), tuple(data[:, 1].tolist())
    except (KeyError, ValueError, IndexError, TypeError) as e:  # tomllib's errors are ValueErrors
        raise ConfigError(what, str(p), f"is not a curve: two columns wavelength_nm, value ({e})") from None


def ir_cut(spec: FilterSpec) -> Spectrum | None:
    """Transmittance of the IR-cut filter: a logistic edge, 50 % at ``ir_cut_nm``, 90 % → 10 % over
    ``ir_cut_width_nm``; 1 everywhere without one.

    Parameters
    ----------
    spec : FilterSpec
        The ``[filters]`` table.

    Returns
    -------
    Spectrum or None
        The transmittance as a function of wavelength in nm; None without an IR cut (``ir_cut_nm`` unset).
    """
    if spec.ir_cut_nm is None:
        return None
    return logistic_cut(spec.ir_cut_nm, spec.ir_cut_width_nm)


@QE_MODELS.register("flat")
def _flat_qe(spec: FilterSpec):
    """The same QE, ``qe_peak``, at every wavelength."""
    return lambda lam: np.full_like(np.asarray(lam, float), spec.qe_peak)


@QE_MODELS.register("silicon")
def _silicon_qe(spec: FilterSpec):
    """:data:`SILICON_QE_SHAPE` scaled to ``qe_peak``."""
    wl, shape = SILICON_QE_SHAPE
    return tabulated(wl, np.asarray(shape) * spec.qe_peak)


@QE_MODELS.register("photodiode")
def _photodiode_qe(spec: FilterSpec):
    """A silicon photodiode collecting carriers from the surface to ``collection_depth_um``:
    (1 − R)(1 − exp(−α·d)) with Green's (2008) absorption and reflectance (spectracam.architecture.silicon),
    scaled to a peak of ``qe_peak`` over 380–780 nm (the paper gives no QE; its shape is the point)."""
    from spectracam.architecture.silicon import photodiode_qe

    peak = photodiode_qe(np.arange(380.0, 781.0), spec.collection_depth_um).max()
    return lambda lam: photodiode_qe(np.asarray(lam, float), spec.collection_depth_um) * (spec.qe_peak / peak)


@QE_MODELS.register("data")
def _data_qe(spec: FilterSpec):
    """A measured curve (``qe_curve_nm``, ``qe_curve``), linear between samples, 0 outside."""
    return tabulated(spec.qe_curve_nm, spec.qe_curve)


def quantum_efficiency(spec: FilterSpec) -> Spectrum:
    """QE(λ) of the registered model ``spec.qe`` times the IR-cut filter's transmittance, if any:
    electrons per photon reaching the sensor (before the colour filters).

    Parameters
    ----------
    spec : FilterSpec
        The ``[filters]`` table (``qe``, its parameters, the IR cut).

    Returns
    -------
    Spectrum
        Electrons per photon as a function of wavelength in nm.
    """
    qe = QE_MODELS[spec.qe](spec)
    cut = ir_cut(spec)
    return qe if cut is None else (lambda lam: qe(lam) * cut(lam))


def clear_responsivity(spec: FilterSpec, grid: WavelengthGrid) -> np.ndarray:
    """``(n_bands,)`` band-averaged QE × IR cut: the responsivity of a pixel with no colour filter
    (transmittance 1; a W pixel), electrons per photon.

    Parameters
    ----------
    spec : FilterSpec
        The ``[filters]`` table (QE model, IR cut).
    grid : WavelengthGrid
        The bands.

    Returns
    -------
    ndarray
        ``(n_bands,)``, electrons per photon.
    """
    return band_average(quantum_efficiency(spec), grid, 400)


def _smooth(transmittance):
    """Responsivities of smooth filters: band average of transmittance_k(λ)·QE(λ), 400 points a band."""

    def responsivity(spec: FilterSpec, grid: WavelengthGrid) -> np.ndarray:
        qe = quantum_efficiency(spec)
        return np.stack([band_average(lambda lam, t=transmittance(spec, k): t(lam) * qe(lam), grid, 400)
                         for k in range(3)])

    return responsivity


def _gaussian_transmittance(spec: FilterSpec, k: int):
    """A Gaussian of peak 1 centred on ``centres_nm[k]`` with full width ``fwhm_nm[k]`` at half maximum."""
    c, sigma = spec.centres_nm[k], spec.fwhm_nm[k] / (2 * np.sqrt(2 * np.log(2)))
    return lambda lam: np.exp(-0.5 * ((lam - c) / sigma) ** 2)


FILTER_KINDS.register("gaussian", _smooth(_gaussian_transmittance))


def _tabulated_transmittance(spec: FilterSpec, k: int):
    """Column k of ``transmittance``, linear between ``transmittance_nm``, 0 outside."""
    return tabulated(spec.transmittance_nm, [row[k] for row in spec.transmittance])


FILTER_KINDS.register("transmittance", _smooth(_tabulated_transmittance))


def _soft_block_transmittance(spec: FilterSpec, k: int):
    """Block filters with logistic edges (``edge_width_nm``): R above the second cutoff, G between, B below."""
    s = logistic_scale_nm(spec.edge_width_nm)
    c1, c2 = spec.cutoffs_nm

    def rise(lam, c):
        return 1.0 / (1.0 + np.exp(-(np.asarray(lam, float) - c) / s))

    return [lambda lam: rise(lam, c2), lambda lam: rise(lam, c1) * (1.0 - rise(lam, c2)),
            lambda lam: 1.0 - rise(lam, c1)][k]


@FILTER_KINDS.register("camera")
def _camera(spec: FilterSpec, grid: WavelengthGrid) -> np.ndarray:
    """A measured camera's responsivities in electrons per photon with the channels' true gains
    (:mod:`spectracam.architecture.cameras`), times the IR-cut filter if one is added; the curves must cover
    the scene's bands."""
    from spectracam.architecture.cameras import camera_curves_of, check_covers

    wl, R, what = camera_curves_of(spec)
    check_covers(spec, wl, float(grid.edges_nm[0]), float(grid.edges_nm[-1]), what)
    cut = ir_cut(spec)
    return np.stack([band_average(lambda lam, k=k: tabulated(wl, R[:, k])(lam) * (1.0 if cut is None else cut(lam)),
                                  grid, 400) for k in range(3)])


def _block_responsivity(spec: FilterSpec, grid: WavelengthGrid, k: int) -> np.ndarray:
    """Exact band average of an ideal pass band × QE: QE integrated over the overlap only, so a
    band that straddles a cutoff gets exactly its overlapping fraction."""
    lo_c, hi_c = [(spec.cutoffs_nm[1], np.inf), spec.cutoffs_nm, (-np.inf, spec.cutoffs_nm[0])][k]
    e = grid.edges_nm
    lo, hi = np.maximum(e[:-1], lo_c), np.minimum(e[1:], hi_c)
    t = np.linspace(0.0, 1.0, 401)
    lam = lo[:, None] + (hi - lo)[:, None] * t[None, :]
    qe = quantum_efficiency(spec)(lam)
    mean_qe = 0.5 * (qe[:, 1:] + qe[:, :-1]).mean(axis=1)
    return np.where(hi > lo, mean_qe * (hi - lo) / (e[1:] - e[:-1]), 0.0)


@FILTER_KINDS.register("block")
def _block(spec: FilterSpec, grid: WavelengthGrid) -> np.ndarray:
    """Ideal pass bands (paper 4.3): blue below the first cutoff, green between, red above; with
    ``edge_width_nm`` > 0, logistic edges instead of steps."""
    if spec.edge_width_nm > 0:
        return _smooth(_soft_block_transmittance)(spec, grid)
    return np.stack([_block_responsivity(spec, grid, k) for k in range(3)])


@FILTER_KINDS.register("xyz")
def _xyz(spec: FilterSpec, grid: WavelengthGrid) -> np.ndarray:
    """Quantal CIE 1931 CMFs on the band grid: photon counts Σ L_b·(λ_b/hc)·R_b·Δλ_b are then exactly
    proportional to the X, Y, Z that cmf_band_weights gives for the same cube."""
    avg = (cmf_band_weights(grid) / grid.widths_nm[:, None]).T  # band-averaged x̄ȳz̄, (3, B)
    quantal = avg * (555.0 / np.asarray(grid.centres_nm, float))[None, :]
    return quantal / quantal.max() * quantum_efficiency(spec)(np.asarray(grid.centres_nm, float))[None, :]


def responsivities(spec: FilterSpec, grid: WavelengthGrid) -> np.ndarray:
    """``(3, n_bands)`` band-averaged R_k(λ), electrons per photon, channels R, G, B (paper 3.3).

    >>> R = responsivities(FilterSpec(), WavelengthGrid(np.arange(400.0, 701.0, 10.0)))
    >>> R.shape, float(R[:, 15].sum())  # at 550 nm only green passes, with QE 0.5
    ((3, 31), 0.5)

    Parameters
    ----------
    spec : FilterSpec
        The ``[filters]`` table.
    grid : WavelengthGrid
        The bands.

    Returns
    -------
    ndarray
        ``(3, n_bands)``, electrons per photon (memoised: do not change it).
    """
    key = (spec, grid)
    try:
        cached = _RESPONSIVITIES.get(key)
    except TypeError:                      # a spec holding something unhashable: computed each time
        return FILTER_KINDS[spec.kind](spec, grid)
    if cached is None:
        cached = np.asarray(FILTER_KINDS[spec.kind](spec, grid), dtype=float)
        if len(_RESPONSIVITIES) >= _RESPONSIVITIES_SIZE:
            _RESPONSIVITIES.pop(next(iter(_RESPONSIVITIES)))
        _RESPONSIVITIES[key] = cached
    return cached.copy()


#: Responsivities already computed, (FilterSpec, WavelengthGrid) → (3, B): a paper run asks for the same filters on the
#: same grid thousands of times (each capture, metering, conversion fit and held-out score), and a block filter's exact
#: band average integrates the QE on 401 points per band (issue 38: 3.7 s of a 24 s ``paper --quick``).  Each caller
#: gets its own copy.
_RESPONSIVITIES: dict = {}
_RESPONSIVITIES_SIZE = 256
