"""colour-science's published tables, read without importing colour-science on every run.

``import colour`` costs 1.4–2.4 s on a 2-core machine (colour-science 0.4.7 imports its plotting, with matplotlib,
and SciPy's interpolation and pandas): more than the whole computation of ``spectracam simulate`` on the default
scene (issue 38). What the commands read from it are published tables — the CIE 1931 colour-matching functions, the
CIE and other illuminants, the ColorChecker and other reflectance sets, the sRGB and CRT primaries, the measured
cameras' sensitivities, the chromatic adaptation transforms' matrices and Robertson's (1968) isotemperature lines —
so they are taken from colour-science once per installed version and kept in
``<tables>/colour-science-<version>.npz`` (:func:`snapshot_path`, 0.6 MB). A run reads that file (0.05 s) and never
imports colour-science unless it needs something else from it.

The file is colour-science's own arrays, float64 bit for bit (``tests/test_colour_data.py`` compares every table with
the live package). It is written atomically; one whose version or layout does not match, or that cannot be read
whole, is rebuilt from colour-science; a folder that cannot be written leaves the tables in memory for the run (a
cache never stops a run).

Four small closed forms that the commands apply to their own values are computed here, each tested bit for bit
against colour-science's function of the same name: :func:`von_kries_matrix`
(``colour.adaptation.matrix_chromatic_adaptation_VonKries``), :func:`xy_to_uv` (``colour.xy_to_UCS_uv``),
:func:`uv_to_cct_robertson` (``colour.temperature.uv_to_CCT(method="Robertson 1968")``) and :func:`srgb_encode`
(``colour.cctf_encoding(..., "sRGB")``, IEC 61966-2-1).

Location: ``$SPECTRACAM_TABLES``, else ``$XDG_CACHE_HOME/spectracam/tables`` (an absolute one), else
``~/.cache/spectracam/tables``.
"""
from __future__ import annotations

import json
import os
import threading
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["SCHEMA", "camera_sensitivities", "cat_matrix", "cmfs_1931", "cmfs_1931_380_780_5", "colour_package_file",
           "colour_version", "display_primaries", "illuminant_names", "illuminant_sd", "illuminant_xy",
           "robertson_table", "sample_set", "sd_set", "snapshot_path", "srgb_encode", "srgb_matrix", "tables",
           "uv_to_cct_robertson", "von_kries_matrix", "xy_to_uv"]

#: The snapshot's layout; bumped whenever :func:`_build` stores something new or stores it differently, so an older
#: file is rebuilt, never misread.
SCHEMA = 2   # 2: the measured cameras' sensitivities (MSDS_CAMERA_SENSITIVITIES)

#: The observer every table here is for (colour-science's key).
OBSERVER = "CIE 1931 2 Degree Standard Observer"
#: Sets of spectral distributions kept whole (colour-science's dicts of ``SpectralDistribution``), by our key.
_SD_SETS = ("colourchecker/", "tcs14", "vs15")
#: The chromatic adaptation transforms whose matrices are kept (colour-science's ``CHROMATIC_ADAPTATION_TRANSFORMS``).
CAT_TRANSFORMS = ("Bradford", "CAT16")
#: Display primaries kept (colour-science's ``MSDS_DISPLAY_PRIMARIES``).
DISPLAY_PRIMARIES = ("Typical CRT Brainard 1997",)

_LOCK = threading.Lock()
_TABLES: dict[str, np.ndarray] | None = None


def colour_version() -> str:
    """The installed colour-science's version, from its distribution metadata (colour-science is not imported).

    Returns
    -------
    str
        E.g. ``"0.4.7"``.
    """
    from importlib import metadata

    return metadata.version("colour-science")


def snapshot_path() -> Path:
    """Where the tables of the installed colour-science are kept.

    Returns
    -------
    Path
        ``<tables>/colour-science-<version>.npz`` (the folder: see the module's docstring).
    """
    from spectracam.core.files import user_cache_dir

    env = os.environ.get("SPECTRACAM_TABLES")
    folder = Path(env) if env else user_cache_dir() / "tables"
    return folder / f"colour-science-{colour_version()}.npz"


def _put_sds(out: dict, key: str, sds) -> None:
    """A dict of colour-science ``SpectralDistribution`` stored as names and, per entry, wavelengths and values."""
    names = list(sds)
    out[f"{key}/names"] = np.array([str(n) for n in names])
    for i, n in enumerate(names):
        out[f"{key}/{i}/wl"] = np.array(sds[n].wavelengths, dtype=float)
        out[f"{key}/{i}/values"] = np.array(sds[n].values, dtype=float)


def _put_msds(out: dict, key: str, msds) -> None:
    """A colour-science ``MultiSpectralDistributions`` stored as its labels, wavelengths and ``(n_wl, n)`` values."""
    out[f"{key}/names"] = np.array([str(n) for n in msds.labels])
    out[f"{key}/wl"] = np.array(msds.wavelengths, dtype=float)
    out[f"{key}/values"] = np.array(msds.values, dtype=float)


def _build() -> dict[str, np.ndarray]:
    """Every table, from colour-science (the one place here that imports it)."""
    import colour
    from colour.quality.cfi2017 import load_TCS_CIE2017
    from colour.temperature.robertson1968 import DATA_ISOTEMPERATURE_LINES_ROBERTSON1968

    out: dict[str, np.ndarray] = {"meta/colour_version": np.array(colour_version()), "meta/schema": np.array(SCHEMA)}
    _put_sds(out, "illuminants", colour.SDS_ILLUMINANTS)
    ccs = colour.CCS_ILLUMINANTS[OBSERVER]
    out["illuminant_xy/names"] = np.array([str(n) for n in ccs])
    out["illuminant_xy/values"] = np.array([np.asarray(ccs[n], dtype=float) for n in ccs])
    cmfs = colour.MSDS_CMFS[OBSERVER]
    out["cmfs/wl"] = np.array(cmfs.wavelengths, dtype=float)
    out["cmfs/values"] = np.array(cmfs.values, dtype=float)
    out["cmfs_380_780_5/values"] = np.array(cmfs.copy().align(colour.SpectralShape(380, 780, 5)).values, dtype=float)
    for name in colour.SDS_COLOURCHECKERS:
        _put_sds(out, f"colourchecker/{name}", colour.SDS_COLOURCHECKERS[name])
    _put_sds(out, "tcs14", dict(list(colour.quality.datasets.SDS_TCS["CIE 1995"].items())[:14]))
    _put_sds(out, "vs15", colour.quality.datasets.SDS_VS["NIST CQS 9.0"])
    _put_msds(out, "cfi99", load_TCS_CIE2017(colour.SpectralShape(380, 780, 5)))
    _put_msds(out, "rawtoaces190", colour.characterisation.read_training_data_rawtoaces_v1())
    for name in DISPLAY_PRIMARIES:
        _put_msds(out, f"display/{name}", colour.MSDS_DISPLAY_PRIMARIES[name])
    out["cameras/names"] = np.array([str(n) for n in colour.MSDS_CAMERA_SENSITIVITIES])
    for i, name in enumerate(colour.MSDS_CAMERA_SENSITIVITIES):
        _put_msds(out, f"cameras/{i}", colour.MSDS_CAMERA_SENSITIVITIES[name])
    srgb = colour.RGB_COLOURSPACES["sRGB"]
    out["srgb/RGB_to_XYZ"] = np.array(srgb.matrix_RGB_to_XYZ, dtype=float)
    out["srgb/XYZ_to_RGB"] = np.array(srgb.matrix_XYZ_to_RGB, dtype=float)
    for name in CAT_TRANSFORMS:
        out[f"cat/{name}"] = np.array(colour.adaptation.CHROMATIC_ADAPTATION_TRANSFORMS[name], dtype=float)
    out["robertson/table"] = np.array(DATA_ISOTEMPERATURE_LINES_ROBERTSON1968, dtype=float)
    return out


def _pack(t: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The tables as two arrays: every number in one float64 vector, and a JSON index of where each table lies
    (its offset and shape) or, for names, the strings themselves (one read, not one per table)."""
    index, chunks, offset = {}, [], 0
    for key, a in t.items():
        if a.dtype.kind in "US":
            index[key] = {"str": a.tolist()}
        else:
            index[key] = {"at": offset, "shape": list(a.shape)}
            chunks.append(np.asarray(a, float).ravel())
            offset += a.size
    return {"data": np.concatenate(chunks), "index": np.array(json.dumps(index))}


def _required() -> tuple[str, ...]:
    """The tables every snapshot holds (a set of spectra: its names; each entry is checked by :func:`_whole`)."""
    keys = ["illuminants/names", "illuminant_xy/names", "illuminant_xy/values", "cmfs/wl", "cmfs/values",
            "cmfs_380_780_5/values", "tcs14/names", "vs15/names", "srgb/RGB_to_XYZ", "srgb/XYZ_to_RGB",
            "robertson/table", "cameras/names"]
    keys += [f"{k}/{part}" for k in ("cfi99", "rawtoaces190") for part in ("names", "wl", "values")]
    keys += [f"display/{n}/{part}" for n in DISPLAY_PRIMARIES for part in ("names", "wl", "values")]
    keys += [f"cat/{n}" for n in CAT_TRANSFORMS]
    return tuple(keys)


def _whole(t: dict[str, np.ndarray]) -> bool:
    """Whether ``t`` holds every table the accessors read, each set of spectra with every entry's two arrays."""
    if any(k not in t for k in _required()):
        return False
    for key, names in t.items():
        group = key[: -len("/names")]
        if key.endswith("/names") and (group == "illuminants" or group.startswith(_SD_SETS)):
            if any(f"{group}/{i}/{part}" not in t for i in range(names.size) for part in ("wl", "values")):
                return False
    return all(f"cameras/{i}/{part}" in t for i in range(t["cameras/names"].size) for part in ("wl", "values"))


def _unpack(packed: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The tables from :func:`_pack`'s two arrays (each a view of the one vector)."""
    data, index = packed["data"], json.loads(str(packed["index"]))
    t = {}
    for key, where in index.items():
        if "str" in where:
            t[key] = np.array(where["str"])
        else:
            n = int(np.prod(where["shape"]))
            if where["at"] + n > data.size:
                raise ValueError(f"table {key} lies past the end of the numbers")
            t[key] = data[where["at"]:where["at"] + n].reshape(where["shape"])
    return t


def _read(path: Path) -> dict[str, np.ndarray] | None:
    """The snapshot at ``path`` if it is whole and of this colour-science and :data:`SCHEMA`; else ``None``."""
    try:
        with np.load(path, allow_pickle=False) as npz:
            t = _unpack({"data": npz["data"], "index": npz["index"]})
        if str(t["meta/colour_version"]) != colour_version() or int(t["meta/schema"]) != SCHEMA:
            return None
        return t if _whole(t) else None
    except Exception:  # noqa: BLE001 - missing, truncated, not a zip, a missing key: rebuilt, never misread
        return None


def tables() -> dict[str, np.ndarray]:
    """Every table, read once per process: from the snapshot, else from colour-science (and the snapshot written).

    Returns
    -------
    dict of str to ndarray
        The tables by key (do not modify them: the accessors below return copies).
    """
    global _TABLES
    with _LOCK:
        if _TABLES is None:
            try:
                path = snapshot_path()
            except Exception:  # noqa: BLE001 - no version metadata or no home folder: the tables stay in memory
                path = None
            t = None if path is None else _read(path)
            if t is None:
                packed = _pack(_build())
                t = _unpack(packed)   # the same arrays, and the same types, as a later read of the file
                if path is not None:
                    from spectracam.core.files import atomic_write

                    try:
                        path.parent.mkdir(parents=True, exist_ok=True)
                        atomic_write(path, lambda tmp: np.savez(tmp, **packed), now=True)
                    except OSError:   # a read-only or full cache never stops a run: the tables stay in memory
                        pass
            _TABLES = t
        return _TABLES


def _get(key: str) -> np.ndarray:
    return tables()[key].copy()


def _sds(key: str) -> list[tuple[str, np.ndarray, np.ndarray]]:
    t = tables()
    return [(str(n), t[f"{key}/{i}/wl"].copy(), t[f"{key}/{i}/values"].copy())
            for i, n in enumerate(t[f"{key}/names"])]


def illuminant_names() -> tuple[str, ...]:
    """The names of colour-science's ``SDS_ILLUMINANTS`` (CIE and other lights), in its order.

    Returns
    -------
    tuple of str
        E.g. ``("A", "B", "C", "D50", ...)``.
    """
    return tuple(str(n) for n in tables()["illuminants/names"])


def illuminant_sd(name: str) -> tuple[np.ndarray, np.ndarray]:
    """A light of colour-science's ``SDS_ILLUMINANTS``.

    Parameters
    ----------
    name : str
        One of :func:`illuminant_names`.

    Returns
    -------
    wavelengths : ndarray
        ``(n,)`` nm.
    values : ndarray
        ``(n,)`` relative spectral power.
    """
    names = illuminant_names()
    if name not in names:
        raise KeyError(name)
    i = names.index(name)
    return _get(f"illuminants/{i}/wl"), _get(f"illuminants/{i}/values")


def illuminant_xy(name: str) -> np.ndarray:
    """A light's CIE 1931 chromaticity (colour-science's ``CCS_ILLUMINANTS`` for the 2° observer).

    Parameters
    ----------
    name : str
        A key of that table (``"D65"``, ``"A"``, ...).

    Returns
    -------
    ndarray
        ``(2,)`` x, y.
    """
    names = [str(n) for n in tables()["illuminant_xy/names"]]
    if name not in names:
        raise KeyError(name)
    return _get("illuminant_xy/values")[names.index(name)]


def cmfs_1931() -> tuple[np.ndarray, np.ndarray]:
    """The CIE 1931 2° colour-matching functions (colour-science's ``MSDS_CMFS``, 360–830 nm by 1 nm).

    Returns
    -------
    wavelengths : ndarray
        ``(n,)`` nm.
    values : ndarray
        ``(n, 3)`` x̄ȳz̄.
    """
    return _get("cmfs/wl"), _get("cmfs/values")


def cmfs_1931_380_780_5() -> np.ndarray:
    """The same functions aligned by colour-science to 380–780 nm by 5 nm (``.align(SpectralShape(380, 780, 5))``).

    Returns
    -------
    ndarray
        ``(81, 3)`` x̄ȳz̄.
    """
    return _get("cmfs_380_780_5/values")


def sd_set(key: str) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """A set of spectral distributions, each with its own wavelengths.

    Parameters
    ----------
    key : str
        ``"colourchecker/<dataset>"`` (colour-science's ``SDS_COLOURCHECKERS``), ``"tcs14"`` (the first 14 of CIE
        13.3's test colour samples, ``SDS_TCS["CIE 1995"]``) or ``"vs15"`` (``SDS_VS["NIST CQS 9.0"]``).

    Returns
    -------
    list of (str, ndarray, ndarray)
        Each entry's name, wavelengths (nm) and values, in colour-science's order.
    """
    if not key.startswith(_SD_SETS) or f"{key}/names" not in tables():
        raise KeyError(key)
    return _sds(key)


def sample_set(key: str) -> tuple[tuple[str, ...], np.ndarray, np.ndarray]:
    """A set of samples on one wavelength grid.

    Parameters
    ----------
    key : str
        ``"cfi99"`` (CIE 2017's 99 test colour samples at 380–780 nm by 5 nm, ``load_TCS_CIE2017``) or
        ``"rawtoaces190"`` (``read_training_data_rawtoaces_v1``).

    Returns
    -------
    names : tuple of str
    wavelengths : ndarray
        ``(n_wl,)`` nm.
    values : ndarray
        ``(n_wl, n)``.
    """
    if key not in ("cfi99", "rawtoaces190"):
        raise KeyError(key)
    t = tables()
    return tuple(str(n) for n in t[f"{key}/names"]), _get(f"{key}/wl"), _get(f"{key}/values")


def display_primaries(name: str) -> tuple[np.ndarray, np.ndarray]:
    """A display's primaries' spectra (colour-science's ``MSDS_DISPLAY_PRIMARIES``; :data:`DISPLAY_PRIMARIES`).

    Parameters
    ----------
    name : str
        The display's key.

    Returns
    -------
    wavelengths : ndarray
        ``(n,)`` nm.
    values : ndarray
        ``(n, 3)`` R, G, B.
    """
    if name not in DISPLAY_PRIMARIES:
        raise KeyError(name)
    return _get(f"display/{name}/wl"), _get(f"display/{name}/values")


def camera_sensitivities(name: str) -> tuple[np.ndarray, np.ndarray]:
    """A measured camera's spectral sensitivities (colour-science's ``MSDS_CAMERA_SENSITIVITIES``).

    Parameters
    ----------
    name : str
        Its key (``"Nikon 5100 (NPL)"``, ``"Sigma SDMerill (NPL)"``).

    Returns
    -------
    wavelengths : ndarray
        ``(n,)`` nm.
    values : ndarray
        ``(n, 3)`` R, G, B, as published.
    """
    names = [str(n) for n in tables()["cameras/names"]]
    if name not in names:
        raise KeyError(name)
    i = names.index(name)
    return _get(f"cameras/{i}/wl"), _get(f"cameras/{i}/values")


def colour_package_file(*parts: str) -> Path:
    """A data file shipped inside the installed colour-science, found without importing it.

    Parameters
    ----------
    *parts : str
        The path below the package's folder, e.g. ``"characterisation", "datasets", "rawtoaces", "x.csv"``.

    Returns
    -------
    Path
        Its path (not checked for existence).
    """
    from importlib.util import find_spec

    spec = find_spec("colour")   # a top-level package's spec: found, not executed
    if spec is None or spec.origin is None:
        raise ModuleNotFoundError("colour-science is not installed")
    return Path(spec.origin).parent.joinpath(*parts)


def srgb_matrix(direction: str) -> np.ndarray:
    """IEC 61966-2-1 sRGB's matrix, as colour-science's ``RGB_COLOURSPACES["sRGB"]`` holds it.

    Parameters
    ----------
    direction : str
        ``"RGB_to_XYZ"`` or ``"XYZ_to_RGB"``.

    Returns
    -------
    ndarray
        ``(3, 3)``.
    """
    if direction not in ("RGB_to_XYZ", "XYZ_to_RGB"):
        raise KeyError(direction)
    return _get(f"srgb/{direction}")


def cat_matrix(transform: str) -> np.ndarray:
    """A chromatic adaptation transform's XYZ → cone-response matrix (:data:`CAT_TRANSFORMS`).

    Parameters
    ----------
    transform : str
        ``"Bradford"`` (Lam 1985) or ``"CAT16"`` (Li et al. 2017).

    Returns
    -------
    ndarray
        ``(3, 3)``.
    """
    if transform not in CAT_TRANSFORMS:
        raise KeyError(transform)
    return _get(f"cat/{transform}")


def robertson_table() -> np.ndarray:
    """Robertson's (1968) isotemperature lines: ``(31, 4)`` rows of reciprocal megakelvin, u, v and the slope t."""
    return _get("robertson/table")


def _safe_divide(a, b):
    """``a / b`` with a NaN or infinite quotient read as 0 (colour-science's default ``sdiv`` mode)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.nan_to_num(np.asarray(a, float) / b, nan=0, posinf=0, neginf=0)


def von_kries_matrix(xyz_w: np.ndarray, xyz_wr: np.ndarray, transform: str) -> np.ndarray:
    """The von Kries adaptation matrix from white ``xyz_w`` to white ``xyz_wr`` in a transform's cone space:
    M⁻¹ · diag(M·XYZ_wr / M·XYZ_w) · M (full adaptation; Bradford [Lam1985]_, CAT16 [Li2017]_: see
    docs/references.md).

    Parameters
    ----------
    xyz_w, xyz_wr : ndarray
        ``(3,)`` XYZ of the source and the destination white.
    transform : str
        One of :data:`CAT_TRANSFORMS`.

    Returns
    -------
    ndarray
        ``(3, 3)``.

    Examples
    --------
    >>> m = von_kries_matrix(np.array([0.95047, 1.0, 1.08883]), np.array([0.96422, 1.0, 0.82521]), "Bradford")
    >>> np.round(m @ np.array([0.95047, 1.0, 1.08883]), 5).tolist()
    [0.96422, 1.0, 0.82521]
    """
    m = cat_matrix(transform)
    rgb_w = np.matmul(m, np.asarray(xyz_w, float)[..., None])[..., 0]
    rgb_wr = np.matmul(m, np.asarray(xyz_wr, float)[..., None])[..., 0]
    d = _safe_divide(rgb_wr, rgb_w)
    return np.matmul(np.matmul(np.linalg.inv(m), d[..., None] * np.eye(3)), m)


def xy_to_uv(xy: ArrayLike) -> np.ndarray:
    """CIE 1960 UCS u, v of CIE 1931 x, y: u = 4x / (−2x + 12y + 3), v = 6y / (−2x + 12y + 3).

    Parameters
    ----------
    xy : array_like
        ``(..., 2)``.

    Returns
    -------
    ndarray
        ``(..., 2)``.
    """
    xy = np.asarray(xy, float)
    x, y = xy[..., 0], xy[..., 1]
    d = 12 * y - 2 * x + 3
    return np.stack([_safe_divide(4 * x, d), _safe_divide(6 * y, d)], axis=-1)


def uv_to_cct_robertson(uv: ArrayLike) -> np.ndarray:
    """Correlated colour temperature and distance from the Planckian locus by Robertson's method (1968).

    The point is placed between the two isotemperature lines of :func:`robertson_table` whose signed distances to
    it change sign; its reciprocal temperature is interpolated between theirs in proportion to those distances
    (Wyszecki & Stiles, *Color Science*, 2nd ed., 3.11) [Robertson1968]_ (see docs/references.md). Beyond the
    table's ends the last pair is used.

    Parameters
    ----------
    uv : array_like
        ``(..., 2)`` CIE 1960 UCS.

    Returns
    -------
    ndarray
        ``(..., 2)``: the CCT (K) and D_uv.
    """
    uv = np.asarray(uv, float)
    shape = uv.shape
    u = uv.reshape(-1, 2)[:, 0:1]
    v = uv.reshape(-1, 2)[:, 1:2]
    mired, u_l, v_l, slope = (robertson_table()[:, k] for k in range(4))
    norm = np.hypot(1.0, slope)
    du_l, dv_l = 1.0 / norm, slope / norm        # each line's unit direction
    # The signed distance of the point to each line after the first.
    dist = -(u - u_l[1:]) * dv_l[1:] + (v - v_l[1:]) * du_l[1:]
    crossed = dist <= 0
    i = np.where(crossed.any(axis=1), crossed.argmax(axis=1) + 1, 30)
    rows = np.arange(i.size)
    here = -np.minimum(dist[rows, i - 1], 0.0)
    before = dist[rows, i - 2]
    f = np.where(i == 1, 0.0, np.where(i > 1, here / (before + here), 0.0))
    cct = _safe_divide(1.0e6, mired[i - 1] * f + mired[i] * (1 - f))
    u_i = u_l[i - 1] * f + u_l[i] * (1 - f)
    v_i = v_l[i - 1] * f + v_l[i] * (1 - f)
    du_i = du_l[i] * (1 - f) + du_l[i - 1] * f
    dv_i = dv_l[i] * (1 - f) + dv_l[i - 1] * f
    length = np.hypot(du_i, dv_i)
    du_i, dv_i = du_i / length, dv_i / length
    d_uv = (u.ravel() - u_i) * du_i + (v.ravel() - v_i) * dv_i
    return np.stack([cct, -d_uv], axis=-1).reshape(shape)


def srgb_encode(linear: ArrayLike) -> np.ndarray:
    """IEC 61966-2-1's encoding (its inverse EOTF): 12.92·L up to L = 0.0031308, else 1.055·L^(1/2.4) − 0.055
    (a negative L by its magnitude, sign kept) [IEC61966-2-1]_ (see docs/references.md).

    Parameters
    ----------
    linear : array_like
        Linear sRGB.

    Returns
    -------
    ndarray
        Encoded values.

    Examples
    --------
    >>> srgb_encode(np.array([0.0, 0.0031308, 0.18, 1.0])).round(4).tolist()
    [0.0, 0.0404, 0.4614, 1.0]
    """
    L = np.asarray(linear, float)
    return np.where(L <= 0.0031308, L * 12.92, 1.055 * (np.sign(L) * np.abs(L) ** (1 / 2.4)) - 0.055)
