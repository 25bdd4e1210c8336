"""Measured reflectance libraries, loadable by name, offline: the colours a conversion is judged on.

Every set is a table of measured spectral reflectance factors (0-1), one row per sample:

* shipped with colour-science (a dependency):

  - ``cfi99`` — the 99 colour evaluation samples of CIE 224:2017 (the CIE 2017 colour fidelity
    index), chosen to span natural and manufactured colours evenly; 380-780 nm, 5 nm.
  - ``rawtoaces190`` — the 190 training reflectances of the Academy's rawtoaces (ColorChecker,
    skin, foliage, paints...), 380-780 nm, 5 nm.
  - ``colorchecker24`` (BabelColor average), ``colorchecker24_ohta`` (N. Ohta), ``iso17321`` (ISO
    17321-1's 24) — the chart the conversion is fitted on, in three measurements.
  - ``tcs14`` — CIE 13.3's 14 test colour samples (CRI), ``vs15`` — NIST CQS's 15 samples.

* shipped with luxpy (optional, GPLv3, ``pip install luxpy``; read from its data files, never
  imported):

  - ``munsell1269`` — the 1269 Munsell matte chips (Univ. of Eastern Finland), 380-780 nm, 5 nm.
  - ``tm30_4880`` — the IES TM-30-15 library of 4880 measured samples (David et al. 2015),
    380-780 nm, 1 nm.
  - ``capbone100k`` — 114 120 measured reflectances as luxpy ships them (``capbone_100k_rfls``);
    400-700 nm, 10 nm.

* a user's CSV: ``file:PATH`` — first column wavelength (nm, increasing), one column per sample,
  a header row with the names.

Citations and licences are in :data:`CITATIONS`; every set's wavelengths must cover the scene's.
"""
from __future__ import annotations

import csv
import importlib.util
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from spectracam.core.errors import ConfigError, SpectracamError

__all__ = ["CITATIONS", "LIBRARIES", "LUXPY_LIBRARIES", "MAX_REFLECTANCE", "MIN_REFLECTANCE",
           "ReflectanceSet", "check_available", "load", "read_csv"]

#: Reflectances above this are refused: a measured, non-fluorescent surface stays below ~1.05.
MAX_REFLECTANCE = 1.5
#: Measurement noise leaves some dark samples slightly below 0 (rawtoaces: −2e-18): down to this they
#: are read as 0; below it the file is refused.
MIN_REFLECTANCE = -0.01

CITATIONS = {
    "cfi99": "CIE 224:2017, Colour fidelity index for accurate scientific use (colour-science's copy)",
    "rawtoaces190": "AMPAS rawtoaces training data, 190 patches (colour-science's copy; Apache 2.0)",
    "colorchecker24": "BabelColor ColorChecker average (D. Pascale, 2012; colour-science's copy)",
    "colorchecker24_ohta": "N. Ohta's ColorChecker measurement (colour-science's copy)",
    "iso17321": "ISO 17321-1:2012 Table D.1 ColorChecker reflectances (colour-science's copy)",
    "tcs14": "CIE 13.3-1995 test colour samples 1-14 (colour-science's copy)",
    "vs15": "NIST colour quality scale v9.0 samples VS1-VS15 (colour-science's copy)",
    "munsell1269": "Munsell Book of Color, matte, 1269 chips (Univ. of Eastern Finland; luxpy's copy, GPLv3)",
    "tm30_4880": "IES TM-30-15 4880-sample library (David et al., Opt. Express 23, 2015; luxpy's copy, GPLv3)",
    "capbone100k": "114 120 measured reflectances (luxpy's data file capbone_100k_rfls.npz, GPLv3)",
}
LIBRARIES = tuple(CITATIONS)


@dataclass(frozen=True, eq=False)
class ReflectanceSet:
    """``values[i, j]``: sample i's reflectance factor at ``wavelengths_nm[j]``."""

    name: str
    sample_names: tuple
    wavelengths_nm: np.ndarray
    values: np.ndarray
    citation: str

    def __len__(self) -> int:
        return self.values.shape[0]

    def at(self, lam_nm: np.ndarray, rows: slice = slice(None)) -> np.ndarray:
        """``(n, len(lam))`` reflectances of the samples ``rows``, linear between the measured
        wavelengths (the set must cover ``lam``: see :func:`check_covers`).

        Parameters
        ----------
        lam_nm : ndarray
            Wavelengths, nm.
        rows : slice
            Which samples.

        Returns
        -------
        ndarray
            ``(n, len(lam_nm))`` reflectances, 0…1.
        """
        lam = np.asarray(lam_nm, float)
        j = np.clip(np.searchsorted(self.wavelengths_nm, lam) - 1, 0, self.wavelengths_nm.size - 2)
        w0, w1 = self.wavelengths_nm[j], self.wavelengths_nm[j + 1]
        t = (lam - w0) / (w1 - w0)
        v = self.values[rows]
        return v[:, j] * (1 - t) + v[:, j + 1] * t

    def check_covers(self, lo_nm: float, hi_nm: float, what: str = "held_out") -> None:
        """Refuse (a one-line error naming ``what``) a set not measured over all of ``[lo_nm, hi_nm]``.

        Parameters
        ----------
        lo_nm, hi_nm : float
            The range the scene needs, nm.
        what : str
            The field that named the set.
        """
        w = self.wavelengths_nm
        if w[0] > lo_nm + 1e-9 or w[-1] < hi_nm - 1e-9:
            raise SpectracamError(f"{what} = {self.name!r}: measured over {w[0]:g}-{w[-1]:g} nm, the scene needs "
                                  f"{lo_nm:g}-{hi_nm:g} nm")


def _checked(name: str, names, wl, values, citation: str) -> ReflectanceSet:
    wl = np.asarray(wl, float)
    v = np.asarray(values, float)
    if wl.ndim != 1 or wl.size < 2 or not np.all(np.isfinite(wl)) or np.any(np.diff(wl) <= 0):
        raise SpectracamError(f"reflectances {name!r}: the wavelengths must be at least two finite, increasing "
                              f"numbers (nm)")
    if v.ndim != 2 or v.shape[1] != wl.size or v.shape[0] < 1:
        raise SpectracamError(f"reflectances {name!r}: {v.shape} values for {wl.size} wavelengths")
    bad = ~np.isfinite(v) | (v < MIN_REFLECTANCE) | (v > MAX_REFLECTANCE)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise SpectracamError(f"reflectances {name!r}: sample {names[i]!r} at {wl[j]:g} nm is {v[i, j]!r}; "
                              f"a reflectance factor is a finite number in 0-{MAX_REFLECTANCE:g}")
    return ReflectanceSet(name, tuple(str(n) for n in names), wl, np.clip(v, 0.0, None), citation)


def _from_colour_samples(name: str, key: str) -> ReflectanceSet:
    """A set colour-science holds on one grid (:func:`spectracam.core.colour_data.sample_set`)."""
    from spectracam.core import colour_data

    labels, wl, values = colour_data.sample_set(key)
    return _checked(name, list(labels), wl, values.T, CITATIONS[name])


def _from_colour_sds(name: str, key: str) -> ReflectanceSet:
    """A set colour-science holds as separate spectra (:func:`spectracam.core.colour_data.sd_set`), each
    interpolated onto the first one's wavelengths."""
    from spectracam.core import colour_data

    sds = colour_data.sd_set(key)
    wl = sds[0][1]
    rows = [np.interp(wl, w, v) for _, w, v in sds]
    return _checked(name, [n for n, _, _ in sds], wl, rows, CITATIONS[name])


def _luxpy_file(filename: str) -> Path:
    spec = importlib.util.find_spec("luxpy")   # its data, without importing luxpy (slow, needs matplotlib)
    if spec is None or not spec.submodule_search_locations:
        raise SpectracamError("luxpy is not installed: the libraries munsell1269, tm30_4880 and capbone100k are read "
                              "from its data files (pip install luxpy; GPLv3)")
    path = Path(list(spec.submodule_search_locations)[0]) / "data" / "rfls" / filename
    if not path.is_file():
        raise SpectracamError(f"luxpy's data file {path} is missing: reinstall luxpy")
    return path


def _luxpy_table(name: str, filename: str, key: str | None = None) -> ReflectanceSet:
    """luxpy's layout: the first row wavelengths, then one row per sample (``.npz``); its ``.dat`` files
    are the transpose (one row per wavelength, the first column the wavelength)."""
    path = _luxpy_file(filename)
    if key is not None:
        with np.load(path, allow_pickle=False) as z:
            table = np.asarray(z[key], float)
    else:
        table = np.loadtxt(path, delimiter=",").T
    return _checked(name, [f"{name}-{i + 1}" for i in range(table.shape[0] - 1)], table[0], table[1:], CITATIONS[name])


def read_csv(path: str | Path) -> ReflectanceSet:
    """:func:`_read_csv`, read once per version of the file (every sweep cell validates its scene).

    Parameters
    ----------
    path : str or Path
        A CSV of spectra: ``wavelength_nm``, then one column per sample.

    Returns
    -------
    ReflectanceSet
        The samples, named after the file.
    """
    from spectracam.core.files import regular_file

    regular_file(path, "reflectances file")
    try:
        st = Path(path).stat()
        version = (st.st_mtime_ns, st.st_size)
    except OSError:
        version = None   # _read_csv says what is wrong
    return _read_csv(str(path), version)


@lru_cache(maxsize=8)
def _read_csv(path: str, version) -> ReflectanceSet:
    """A user's reflectances: a header row (``wavelength_nm, name1, name2, ...``), then one row per
    wavelength; values are reflectance factors 0-1 (percentages are refused)."""
    p = Path(path)
    name = f"file:{path}"
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise SpectracamError(f"reflectances file {str(path)!r}: cannot be read ({e.__class__.__name__}: "
                              f"{getattr(e, 'strerror', None) or e})") from None
    rows = [r for r in csv.reader(text.splitlines()) if r and any(c.strip() for c in r)]
    if len(rows) < 3 or len(rows[0]) < 2:
        raise SpectracamError(f"reflectances file {str(path)!r}: needs a header row (wavelength_nm, then sample names) "
                              "and at least two rows of numbers")
    header = [c.strip() for c in rows[0]]
    for i, r in enumerate(rows[1:], 2):
        if len(r) != len(header):
            raise SpectracamError(f"reflectances file {str(path)!r}: line {i} has {len(r)} cells; every row must have "
                                  f"{len(header)} cells, like the header")
    try:
        table = np.array([[float(c) for c in r] for r in rows[1:]], float)
    except ValueError as e:
        raise SpectracamError(f"reflectances file {str(path)!r}: {e}; every cell below the header must be a "
                              "number") from None
    return _checked(name, header[1:], table[:, 0], table[:, 1:].T, f"the file {path}")


LUXPY_LIBRARIES = ("munsell1269", "tm30_4880", "capbone100k")


def check_available(name: str, what: str = "held_out") -> None:
    """Refuse, before any work, a library that cannot be read here (a missing file, luxpy absent).

    Parameters
    ----------
    name : str
        A library name or ``file:PATH`` (a CSV, read and checked now).
    what : str
        The field that named it, for the error.
    """
    if name.startswith("file:"):
        from spectracam.core.files import regular_file

        regular_file(name[5:], what)   # a FIFO is no missing file: said as what it is
        if not Path(name[5:]).is_file():
            raise SpectracamError(f"{what} = {name!r}: no such file (a CSV of spectra: wavelength_nm, then one "
                                  "column per sample)")
        read_csv(name[5:])   # small: every fault in it is found now, not after the render
    elif name in LUXPY_LIBRARIES:
        _luxpy_file("Munsell1269.dat")


@lru_cache(maxsize=16)
def _load_named(name: str) -> ReflectanceSet:
    if name in ("cfi99", "rawtoaces190"):   # CIE 2017's 99 at 380-780 nm by 5 nm; rawtoaces' training data
        return _from_colour_samples(name, name)
    if name in ("colorchecker24", "colorchecker24_ohta", "iso17321"):
        key = {"colorchecker24": "BabelColor Average", "colorchecker24_ohta": "ColorChecker N Ohta",
               "iso17321": "ISO 17321-1"}[name]
        return _from_colour_sds(name, f"colourchecker/{key}")
    if name in ("tcs14", "vs15"):   # CIE 13.3's first 14 samples; NIST CQS 9.0's 15
        return _from_colour_sds(name, name)
    if name == "munsell1269":
        return _luxpy_table(name, "Munsell1269.dat")
    if name == "tm30_4880":
        return _luxpy_table(name, "IESTM30_15_R4880.npz", "_IESTM30_R4880")
    if name == "capbone100k":
        return _luxpy_table(name, "capbone_100k_rfls.npz", "_CAPBONE_100K_RFL")
    raise AssertionError(name)


def load(name: str, what: str = "held_out", base_dir: Path | None = None) -> ReflectanceSet:
    """A library by name (:data:`LIBRARIES`) or ``file:PATH`` (relative to ``base_dir``).

    Parameters
    ----------
    name : str
        A key of :data:`LIBRARIES` or ``file:PATH``.
    what : str
        The field that named it, for the error.
    base_dir : Path or None
        The directory a relative ``file:`` path is taken from; None: the working directory.

    Returns
    -------
    ReflectanceSet
        The samples (read once per process).
    """
    if not isinstance(name, str):
        raise ConfigError(what, name, "a library name (" + ", ".join(LIBRARIES) + ") or 'file:PATH'")
    if name.startswith("file:"):
        path = Path(name[5:])
        if base_dir is not None and not path.is_absolute():
            path = base_dir / path
        return read_csv(path)
    if name not in LIBRARIES:
        raise ConfigError(what, name, "one of " + ", ".join(LIBRARIES) + ", or 'file:PATH' (a CSV of spectra)")
    return _load_named(name)
