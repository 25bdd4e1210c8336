"""Real cameras' own measurements, offline, from Debian packages (``spectracam validate``, issue 33 item 5).

Two tables, each for every shipped camera with measured curves and a published matrix model
(:data:`spectracam.architecture.cameras.PUBLISHED_MATRICES`), simulated with the noise-free camera of
:func:`spectracam.experiments.validate.scene.validation_scene` (the shipped chart scene, 400–700 nm at 10 nm):

* **White-balance presets** — darktable's ``wb_presets.json`` (Debian package ``darktable``) holds the
  firmware multipliers ``m`` of ~440 cameras, read from their raw files' maker notes.  A preset's neutral
  is ``1/m`` normalised to G; the simulated neutral is the camera's noise-free photo-electrons of a perfect
  white diffuser under the light the preset is made for (:data:`PRESET_LIGHTS`: the colour temperature the
  camera maker's manual gives for that preset, on the CIE daylight locus for daylight, cloudy, shade and
  flash, on the Planckian locus for tungsten/incandescent, and the CIE fluorescent lamp of the same name).
  Only the entry with fine-tuning 0 is read.  Beside the comparison, two numbers need no choice of light:
  the *shape* between lights (each preset's neutral relative to the camera's daylight preset, simulated
  against firmware: independent of the channels' gains) and the *effective* colour temperature of each
  preset (the temperature on the chosen light's locus whose simulated neutral is nearest to the preset's,
  and how near), also with the published XYZ(D65)→camera matrix in place of the curves.
* **DCP profiles** — RawTherapee's measured DNG camera profiles (Debian package ``rawtherapee-data``,
  :func:`read_dcp`): at each calibration illuminant the DCP's ``ColorMatrix`` (XYZ → camera) against the
  one spectracam fits for the same camera under the same light (:func:`spectracam.io.dng.xyz_to_camera_matrix`,
  as the DNG writer fits ``ColorMatrix1/2``), as (a) ΔE*ab on the 24 patches of the chart between their
  simulated camera responses converted to XYZ by either matrix (and each against the chart's true XYZ), (b)
  the ratio of the neutral each predicts for the illuminant's white; and the DCP's ``ForwardMatrix`` (white-
  balanced camera → XYZ D50) on the same responses against the truth adapted to D50 (Bradford).

Where the files are not installed, both tables are skipped with the reason (:func:`run_validate_wb`).
"""
from __future__ import annotations

import json
import math
import os
import struct
import sys
from dataclasses import dataclass, field
from functools import lru_cache, partial
from pathlib import Path
from types import SimpleNamespace
from typing import TYPE_CHECKING

import numpy as np

from spectracam.core.errors import SpectracamError

if TYPE_CHECKING:
    from collections.abc import Callable

    from numpy.typing import ArrayLike

    from spectracam.pipeline.scene_file import Scene
    from spectracam.scene.illuminant import IlluminantSpec

__all__ = ["CACHE_SUBDIR", "CALIBRATION_CCT_K", "CALIBRATION_LIGHTS", "DCP_DIR", "DCP_MAGIC", "DCP_TAGS",
           "DEFINITIONS", "EFFECTIVE_RANGE_K", "PRESET_LIGHTS", "PRESET_SOURCES", "TARGET_CATEGORIES",
           "WB_PRESETS_PATH", "DataFileError", "DcpProfile", "PresetLight", "data_prefixes", "daylight_spec",
           "dcp_rows", "effective_cct", "find_dcp_dir", "find_wb_presets", "light_cct", "light_spec",
           "load_wb_presets", "maker_model", "preset_neutral", "presets_at_zero_tuning", "read_dcp",
           "read_tiff_ifd0", "run_validate_wb", "simulated_neutral", "wb_markdown", "wb_preset_rows",
           "white_xyz"]

# ------------------------------------------------------------------------------------------ where the files are
#: The files' paths under an install prefix (Debian's is /usr).
WB_PRESETS_PATH = Path("share/darktable/wb_presets.json")
DCP_DIR = Path("share/rawtherapee/dcpprofiles")
#: Where ``tools/setup.sh --test`` unpacks the two packages' data files (``apt-get download`` + ``dpkg-deb``)
#: when they are not installed: under the virtual environment's prefix, the packages' own tree below it.
CACHE_SUBDIR = Path("share/spectracam/debian")


def data_prefixes() -> list[Path]:
    """Install prefixes searched, in order: the system's (``/usr``, ``/usr/local``), then the unpacked copy
    under this Python's prefix (``.venv/share/spectracam/debian/usr``) and under the user's cache
    (``~/.cache/spectracam/debian/usr``)."""
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return [Path("/usr"), Path("/usr/local"), Path(sys.prefix) / CACHE_SUBDIR / "usr",
            cache / "spectracam" / "debian" / "usr"]


def find_wb_presets() -> Path | None:
    """darktable's ``wb_presets.json`` in the first prefix that has it, or None."""
    for p in data_prefixes():
        if (p / WB_PRESETS_PATH).is_file():
            return p / WB_PRESETS_PATH
    return None


def find_dcp_dir() -> Path | None:
    """RawTherapee's ``dcpprofiles`` directory in the first prefix that has one with a ``.dcp``, or None."""
    for p in data_prefixes():
        d = p / DCP_DIR
        if d.is_dir() and any(d.glob("*.dcp")):
            return d
    return None


def _missing(what: str, rel: Path, package: str) -> str:
    return (f"{what} not found: no {rel} under {', '.join(str(p) for p in data_prefixes())} (Debian package "
            f"{package}; `bash tools/setup.sh --test` unpacks it into .venv/{CACHE_SUBDIR} where apt-get may run)")


# ------------------------------------------------------------------------------------------ darktable's presets
class DataFileError(SpectracamError):
    """A Debian data file (wb_presets.json, a .dcp) that does not have the structure it must have."""


def load_wb_presets(path: str | Path) -> dict:
    """``{(maker, model): [(name, tuning, (R, G, B) multipliers), ...]}`` from darktable's ``wb_presets.json``
    (``{"version": 1, "wb_presets": [{"maker", "models": [{"model", "presets": [{"name", "tuning"?,
    "channels": [R, G, B, G2]}]}]}]}``; a missing ``tuning`` is 0).  Every field is checked; the
    multipliers must be finite and > 0 (the fourth channel, unused by RGB cameras, is not read).

    Parameters
    ----------
    path : str or Path
        The file (:func:`find_wb_presets`).

    Returns
    -------
    dict
        ``(maker, model)`` → its presets in the file's order.

    Raises
    ------
    DataFileError
        When the file cannot be read as JSON or a field is missing or wrong.
    """
    p = Path(path)
    try:
        data = json.loads(p.read_bytes())
    except (OSError, ValueError) as e:
        raise DataFileError(f"{p}: cannot be read as JSON ({e})") from None

    def bad(where, what):
        return DataFileError(f"{p}: {where}: {what}")

    if not isinstance(data, dict) or data.get("version") != 1 or not isinstance(data.get("wb_presets"), list):
        raise bad("top level", "need {\"version\": 1, \"wb_presets\": [...]}")
    out: dict = {}
    for i, mk in enumerate(data["wb_presets"]):
        if not isinstance(mk, dict) or not isinstance(mk.get("maker"), str) or not isinstance(mk.get("models"), list):
            raise bad(f"wb_presets[{i}]", "need a \"maker\" string and a \"models\" list")
        for j, m in enumerate(mk["models"]):
            where = f"{mk['maker']} models[{j}]"
            if not isinstance(m, dict) or not isinstance(m.get("model"), str) or not isinstance(m.get("presets"), list):
                raise bad(where, "need a \"model\" string and a \"presets\" list")
            rows = out.setdefault((mk["maker"], m["model"]), [])
            for k, pr in enumerate(m["presets"]):
                w = f"{mk['maker']} {m['model']} presets[{k}]"
                if not isinstance(pr, dict) or not isinstance(pr.get("name"), str):
                    raise bad(w, "need a \"name\" string")
                tuning = pr.get("tuning", 0)
                if isinstance(tuning, bool) or not isinstance(tuning, int):
                    raise bad(w, f"tuning must be an integer, not {tuning!r}")
                ch = pr.get("channels")
                if not isinstance(ch, list) or len(ch) != 4 or not all(
                        isinstance(x, (int, float)) and not isinstance(x, bool) for x in ch):
                    raise bad(w, f"channels must be 4 numbers, not {ch!r}")
                rgb = tuple(float(x) for x in ch[:3])
                if not all(math.isfinite(x) and x > 0 for x in rgb):
                    raise bad(w, f"the R, G, B multipliers must be finite and > 0, not {list(rgb)}")
                rows.append((pr["name"], tuning, rgb))
    return out


def presets_at_zero_tuning(presets: dict, maker: str, model: str) -> dict:
    """``{name: (R, G, B) multipliers}`` of ``maker``/``model`` at fine-tuning 0 (empty if the model is not
    there); two different tuning-0 entries of one name are refused.

    Parameters
    ----------
    presets : dict
        :func:`load_wb_presets`' result.
    maker, model : str
        darktable's names (:func:`maker_model`).

    Returns
    -------
    dict
        Preset name → ``(R, G, B)`` multipliers.

    Raises
    ------
    DataFileError
        On two different tuning-0 entries of one name.
    """
    out: dict = {}
    for name, tuning, rgb in presets.get((maker, model), []):
        if tuning != 0:
            continue
        if name in out and out[name] != rgb:
            raise DataFileError(f"{maker} {model}: two different entries for {name!r} at tuning 0: {out[name]}, {rgb}")
        out[name] = rgb
    return out


def preset_neutral(multipliers: ArrayLike) -> np.ndarray:
    """The raw neutral a preset stands for: ``1/m`` per channel, G = 1.

    Parameters
    ----------
    multipliers : array_like, shape (3,)
        The preset's R, G, B multipliers.

    Returns
    -------
    ndarray, shape (3,)
        ``(R/G, 1, B/G)`` of the neutral.
    """
    n = 1.0 / np.asarray(multipliers, float)
    return n / n[1]


# ------------------------------------------------------------------------------------------ the presets' lights
@dataclass(frozen=True)
class PresetLight:
    """The light a firmware preset is made for."""

    category: str  # daylight, cloudy, shade, flash, tungsten, fluorescent
    family: str  # "daylight": CIE D series at cct_K; "planckian": blackbody at cct_K; "cie": the named lamp
    cct_K: float | None
    cie_name: str | None = None
    reason: str = ""

    @property
    def label(self) -> str:
        if self.family == "daylight":
            return f"CIE daylight {self.cct_K:g} K"
        if self.family == "planckian":
            return f"blackbody {self.cct_K:g} K"
        return f"CIE {self.cie_name}"


#: The categories the issue's 3 % target is about.
TARGET_CATEGORIES = ("daylight", "cloudy", "shade", "flash")

_CANON = ("Canon EOS instruction manuals' white-balance table (EOS 5D Mark II and its generation: Daylight approx. "
          "5200 K, Shade 7000 K, Cloudy 6000 K, Tungsten 3200 K, White fluorescent 4000 K, Flash 6000 K when the "
          "Speedlite sends no colour temperature)")
_NIKON = ("Nikon D5100 User's Manual, 'Color Temperature' (all figures approximate: incandescent 3000 K, direct "
          "sunlight 5200 K, flash 5400 K, cloudy 6000 K, shade 8000 K; fluorescent: sodium-vapor 2700 K, warm-white "
          "3000 K, white 3700 K, cool-white 4200 K, day white 5000 K, daylight 6500 K, high temp. mercury-vapor "
          "7200 K)")
_DAY = "on the CIE daylight locus (the D series), which daylight and a xenon flash follow"
_TUNG = "on the Planckian locus: an incandescent lamp is a thermal radiator (CIE A is one at 2856 K)"

#: ``{(maker, preset name): PresetLight}``: the colour temperature the maker's manual gives for the preset.
PRESET_LIGHTS = {
    ("Canon", "Daylight"): PresetLight("daylight", "daylight", 5200.0, reason=f"5200 K, {_DAY}"),
    ("Canon", "Cloudy"): PresetLight("cloudy", "daylight", 6000.0, reason=f"6000 K, {_DAY}"),
    ("Canon", "Shade"): PresetLight("shade", "daylight", 7000.0, reason=f"7000 K, {_DAY}"),
    ("Canon", "Flash"): PresetLight("flash", "daylight", 6000.0, reason=f"6000 K, {_DAY}"),
    ("Canon", "Tungsten"): PresetLight("tungsten", "planckian", 3200.0, reason=f"3200 K, {_TUNG}"),
    ("Canon", "Fluorescent"): PresetLight(
        "fluorescent", "cie", None, "FL2",
        reason="'white fluorescent' 4000 K: the Japanese 'white' (W, ~4200 K) tube is the class CIE calls cool white, "
               "FL2 (4230 K)"),
    ("Nikon", "Direct Sunlight"): PresetLight("daylight", "daylight", 5200.0, reason=f"5200 K, {_DAY}"),
    ("Nikon", "Cloudy"): PresetLight("cloudy", "daylight", 6000.0, reason=f"6000 K, {_DAY}"),
    ("Nikon", "Shade"): PresetLight("shade", "daylight", 8000.0, reason=f"8000 K, {_DAY}"),
    ("Nikon", "Flash"): PresetLight("flash", "daylight", 5400.0, reason=f"5400 K, {_DAY}"),
    ("Nikon", "Incandescent"): PresetLight("tungsten", "planckian", 3000.0, reason=f"3000 K, {_TUNG}"),
    ("Nikon", "Warm White Fluorescent"): PresetLight("fluorescent", "cie", None, "FL4",
                                                     reason="3000 K warm white: CIE FL4, warm white (2940 K)"),
    ("Nikon", "White Fluorescent"): PresetLight("fluorescent", "cie", None, "FL3",
                                                reason="3700 K white: CIE FL3, white (3450 K)"),
    ("Nikon", "Cool White Fluorescent"): PresetLight("fluorescent", "cie", None, "FL2",
                                                     reason="4200 K cool white: CIE FL2, cool white (4230 K)"),
    ("Nikon", "Daylight Fluorescent"): PresetLight("fluorescent", "cie", None, "FL1",
                                                   reason="6500 K daylight: CIE FL1, daylight (6430 K)"),
}
#: Manuals quoted per maker.
PRESET_SOURCES = {"Canon": _CANON, "Nikon": _NIKON}


def light_spec(light: PresetLight, cct_K: float | None = None) -> IlluminantSpec:
    """The :class:`~spectracam.scene.illuminant.IlluminantSpec` of ``light`` (at ``cct_K`` instead of its own, for
    the effective-temperature search).

    Parameters
    ----------
    light : PresetLight
        The preset's light.
    cct_K : float or None
        The temperature to use, K (None: the light's; ignored for a named CIE lamp).

    Returns
    -------
    IlluminantSpec
        A blackbody, the named CIE lamp, or CIE daylight (:func:`daylight_spec`).
    """
    from spectracam.scene.illuminant import IlluminantSpec

    T = float(cct_K if cct_K is not None else light.cct_K) if light.family != "cie" else None
    if light.family == "planckian":
        return IlluminantSpec(kind="blackbody", temperature_K=T)
    if light.family == "cie":
        return IlluminantSpec(kind="cie", temperature_K=None, name=light.cie_name)
    return daylight_spec(T)


@lru_cache(maxsize=512)
def daylight_spec(cct_K: float) -> IlluminantSpec:
    """CIE daylight (D series, CIE 015) at the correlated colour temperature ``cct_K`` (4000–25000 K), as a
    measured SPD.

    Parameters
    ----------
    cct_K : float
        K.

    Returns
    -------
    IlluminantSpec
        ``kind="measured"``: colour-science's D-series SPD at the daylight locus' chromaticity of ``cct_K``
        (negative values clipped to 0).
    """
    import colour

    from spectracam.scene.illuminant import IlluminantSpec

    sd = colour.sd_CIE_illuminant_D_series(colour.temperature.CCT_to_xy_CIE_D(float(cct_K)))
    return IlluminantSpec(kind="measured", temperature_K=None, name=f"CIE daylight {cct_K:g} K",
                          wavelengths_nm=tuple(float(x) for x in sd.wavelengths),
                          values=tuple(max(float(x), 0.0) for x in sd.values))


def simulated_neutral(scene: Scene, illuminant: IlluminantSpec) -> np.ndarray:
    """``(3,)`` the scene camera's noise-free photo-electrons of a perfect white diffuser under ``illuminant``
    (an IlluminantSpec) on the scene's wavelength grid — what the DNG writer's ``AsShotNeutral`` is made of
    (:func:`spectracam.io.dng.white_rates`) — normalised to G = 1.

    Parameters
    ----------
    scene : Scene
        Its camera and wavelength grid.
    illuminant : IlluminantSpec
        The light.

    Returns
    -------
    ndarray, shape (3,)
        ``(R/G, 1, B/G)``.
    """
    from spectracam.io.dng import white_rates

    n = white_rates(scene.camera, SimpleNamespace(illuminant=illuminant, grid=scene.grid))
    return n / n[1]


def white_xyz(illuminant: IlluminantSpec) -> np.ndarray:
    """XYZ (CIE 1931 2°, 360–830 nm, Y = 1) of a perfect white under ``illuminant``: the light's own white.

    Parameters
    ----------
    illuminant : IlluminantSpec
        The light.

    Returns
    -------
    ndarray, shape (3,)
        XYZ, Y = 1.
    """
    from spectracam.scene.illuminant import relative_spd
    from spectracam.core.spectra import cie_1931_cmfs

    wl, cmfs = cie_1931_cmfs()
    xyz = np.trapezoid(relative_spd(illuminant)(wl)[:, None] * cmfs, wl, axis=0)
    return xyz / xyz[1]


def _log_rms(n: np.ndarray, ref: np.ndarray) -> float:
    """rms over R/G and B/G of ``ln(n/ref)`` (≈ relative difference)."""
    d = np.log(np.asarray(n)[[0, 2]] / np.asarray(ref)[[0, 2]])
    return float(np.sqrt(np.mean(d**2)))


#: Ranges of the effective-temperature search, K: CIE daylight is defined from 4000 K.
EFFECTIVE_RANGE_K = {"daylight": (4000.0, 20000.0), "planckian": (1500.0, 12000.0)}


def effective_cct(neutral_of: Callable[[IlluminantSpec], np.ndarray], light: PresetLight,
                  target: np.ndarray) -> tuple[float, float] | None:
    """``(T, rms)``: the temperature on ``light``'s locus whose neutral (``neutral_of(IlluminantSpec)``) is
    nearest to ``target`` in log R/G and B/G, and the rms relative distance there; None for a named lamp.

    Parameters
    ----------
    neutral_of : callable
        A light → the neutral ``(3,)``, G = 1 (simulated, or of a published matrix).
    light : PresetLight
        Its locus (daylight or Planckian) and the range searched (:data:`EFFECTIVE_RANGE_K`).
    target : ndarray, shape (3,)
        The preset's neutral, G = 1.

    Returns
    -------
    tuple of float or None
        ``(T K, rms)``, the rms a fraction (×100: percent), searched in mired; None for a named CIE lamp.
    """
    if light.family not in EFFECTIVE_RANGE_K:
        return None
    from scipy.optimize import minimize_scalar

    lo, hi = EFFECTIVE_RANGE_K[light.family]
    f = lambda t: _log_rms(neutral_of(light_spec(light, round(1e6 / t, 3))), target)  # noqa: E731 (in mired)
    r = minimize_scalar(f, bounds=(1e6 / hi, 1e6 / lo), method="bounded", options={"xatol": 0.05})
    T = round(1e6 / r.x, 3)
    return T, _log_rms(neutral_of(light_spec(light, T)), target)


def _pct(a: float, b: float) -> float:
    return float(100.0 * (a / b - 1.0))


def maker_model(model: str) -> tuple[str, str]:
    """darktable's ``(maker, model)`` of a published matrix's model name: ``"Canon EOS 5D Mark II"`` →
    ``("Canon", "EOS 5D Mark II")``.

    Parameters
    ----------
    model : str
        The published matrix's model name.

    Returns
    -------
    tuple of str
        ``(maker, model)``: split at the first space.
    """
    maker, _, rest = model.partition(" ")
    return maker, rest


def _independence(curves, what: str) -> str:
    if not curves.per_channel:
        return (f"independent: the curves were published with their gains, so {what} tests the curves and their "
                "gains against the camera's own data")
    if what == "the white-balance presets":
        return (f"the absolute R/G, B/G test the gains restored from the {curves.matrix} published (Adobe) D65 "
                "matrix against the firmware (two independent sources near D65), not the curves' own gains; the "
                "shape between lights (ratios to the daylight preset, effective temperatures) is independent of "
                "the gains and tests the curves' shape")
    return (f"the gains were restored from Adobe's D65 matrix for the {curves.matrix}, not from this profile (a "
            "separate measurement), so the neutral ratio tests that restoration against an independent "
            "measurement and the ΔE tests the curves' shape")


def light_cct(light: PresetLight, illuminant: IlluminantSpec) -> float:
    """The light's correlated colour temperature, K: its own, or (a named lamp) that of its white (Ohno 2013).

    Parameters
    ----------
    light : PresetLight
        Its temperature, if it has one.
    illuminant : IlluminantSpec
        Its spectrum (:func:`light_spec`), for a named lamp.

    Returns
    -------
    float
        K.
    """
    if light.cct_K is not None:
        return float(light.cct_K)
    import colour

    uv = colour.xy_to_UCS_uv(colour.XYZ_to_xy(white_xyz(illuminant)))
    return float(colour.temperature.uv_to_CCT(uv, method="Ohno 2013")[0])


def wb_preset_rows(camera_name: str, presets: dict, dcp: "DcpProfile | None" = None) -> dict:
    """One camera's white-balance-preset table (:func:`run_validate_wb`); with the camera's DCP profile, the
    neutral its ColorMatrix predicts for each light beside it (:meth:`DcpProfile.neutral`).

    Parameters
    ----------
    camera_name : str
        A shipped camera with a published matrix model.
    presets : dict
        :func:`load_wb_presets`' result.
    dcp : DcpProfile or None
        The camera's DCP profile.

    Returns
    -------
    dict
        The camera, its darktable names, the presets' rows (see :data:`DEFINITIONS`) and those not compared;
        ``skipped`` where darktable has no preset for the model.
    """
    from spectracam.architecture.cameras import PUBLISHED_MATRICES, library_curves
    from spectracam.experiments.validate.scene import validation_scene

    curves = library_curves(camera_name)
    pm = PUBLISHED_MATRICES[curves.matrix]
    maker, model = maker_model(pm.model)
    out = {"camera": camera_name, "model": pm.model, "darktable_maker": maker, "darktable_model": model,
           "gains": curves.gains_note, "independence": _independence(curves, "the white-balance presets"),
           "lights_source": PRESET_SOURCES.get(maker), "presets": [], "not_compared": [],
           "dcp": None if dcp is None else dcp.path}
    found = presets_at_zero_tuning(presets, maker, model)
    if not found:
        out["skipped"] = f"wb_presets.json has no presets for {maker} {model}"
        return out
    scene = validation_scene(camera_name)
    sim_of = lambda ill: simulated_neutral(scene, ill)  # noqa: E731
    pub_of = lambda ill: pm.neutral(white_xyz(ill))  # noqa: E731
    base = None
    for name, mult in found.items():
        light = PRESET_LIGHTS.get((maker, name))
        if light is None:
            out["not_compared"].append(name)
            continue
        row, sim, pre = _preset_row(name, mult, light, sim_of, pub_of, dcp)
        if light.category == "daylight":
            base = (sim, pre)
        out["presets"].append(row)
    for row in out["presets"]:  # the shape between lights: independent of the channels' gains
        if base is None:
            break
        for k, c in ((0, "RG"), (2, "BG")):
            s = row[f"{c}_simulated"] / base[0][k]
            p = row[f"{c}_preset"] / base[1][k]
            row[f"{c}_shape_error_percent"] = _pct(s, p)
    return out


def _preset_row(name: str, mult: tuple, light: PresetLight, sim_of: Callable, pub_of: Callable,
                dcp: DcpProfile | None) -> tuple[dict, np.ndarray, np.ndarray]:
    """:func:`wb_preset_rows`' row of one preset, and its simulated and preset neutrals."""
    ill = light_spec(light)
    sim, pre, pub = sim_of(ill), preset_neutral(mult), pub_of(ill)
    row = {"preset": name, "category": light.category, "target": light.category in TARGET_CATEGORIES,
           "light": light.label, "light_reason": light.reason, "multipliers": list(mult),
           "RG_simulated": float(sim[0]), "BG_simulated": float(sim[2]),
           "RG_preset": float(pre[0]), "BG_preset": float(pre[2]),
           "RG_error_percent": _pct(sim[0], pre[0]), "BG_error_percent": _pct(sim[2], pre[2]),
           "RG_published_matrix": float(pub[0]), "BG_published_matrix": float(pub[2]),
           "RG_published_error_percent": _pct(pub[0], pre[0]), "BG_published_error_percent": _pct(pub[2], pre[2])}
    row["within_3_percent"] = bool(abs(row["RG_error_percent"]) < 3 and abs(row["BG_error_percent"]) < 3)
    if dcp is not None:
        nd = dcp.neutral(white_xyz(ill), light_cct(light, ill))
        row.update({"RG_dcp": float(nd[0]), "BG_dcp": float(nd[2]), "RG_dcp_error_percent": _pct(nd[0], pre[0]),
                    "BG_dcp_error_percent": _pct(nd[2], pre[2])})
    for key, of in (("simulated", sim_of), ("published_matrix", pub_of)):
        eff = effective_cct(of, light, pre)
        row[f"effective_K_{key}"] = None if eff is None else eff[0]
        row[f"effective_rms_percent_{key}"] = None if eff is None else 100 * eff[1]
    return row, sim, pre


# ------------------------------------------------------------------------------------------ DCP profiles
#: TIFF field types: code → (struct format of one value, size in bytes).
_TIFF_TYPES = {1: ("B", 1), 2: ("s", 1), 3: ("H", 2), 4: ("I", 4), 5: ("II", 8), 6: ("b", 1), 7: ("B", 1),
               8: ("h", 2), 9: ("i", 4), 10: ("ii", 8), 11: ("f", 4), 12: ("d", 8)}
#: DNG camera-profile tags read (DNG 1.4 specification, chapter 6).
DCP_TAGS = {"UniqueCameraModel": 50708, "ColorMatrix1": 50721, "ColorMatrix2": 50722,
            "CalibrationIlluminant1": 50778, "CalibrationIlluminant2": 50779, "ProfileName": 50936,
            "ProfileCopyright": 50942, "ForwardMatrix1": 50964, "ForwardMatrix2": 50965,
            "ProfileHueSatMapDims": 50937, "ProfileHueSatMapData1": 50938, "ProfileHueSatMapData2": 50939}
#: The DCP magic number: "RC" after the byte order (a DNG is 42).
DCP_MAGIC = 0x4352
#: EXIF LightSource codes of a CalibrationIlluminant with a standard spectrum: code → (name, IlluminantSpec
#: fields).  Others (1 "daylight", 4 "flash", 255 "other", ...) have no defined spectrum and are not compared.
CALIBRATION_LIGHTS = {17: ("Standard light A", {"kind": "cie", "name": "A"}),
                      18: ("Standard light B", {"kind": "cie", "name": "B"}),
                      19: ("Standard light C", {"kind": "cie", "name": "C"}),
                      20: ("D55", {"kind": "cie", "name": "D55"}), 21: ("D65", {"kind": "cie", "name": "D65"}),
                      22: ("D75", {"kind": "cie", "name": "D75"}), 23: ("D50", {"kind": "cie", "name": "D50"}),
                      24: ("ISO studio tungsten (3200 K)", {"kind": "blackbody", "temperature_K": 3200.0})}
#: The temperatures the DNG SDK gives the calibration illuminants for the 1/CCT interpolation (dng_color_spec).
CALIBRATION_CCT_K = {17: 2856.0, 18: 4874.0, 19: 6774.0, 20: 5503.0, 21: 6504.0, 22: 7504.0, 23: 5003.0, 24: 3200.0}


@dataclass(frozen=True)
class DcpProfile:
    """The parts of a DNG camera profile compared here."""

    path: str
    unique_camera_model: str
    profile_name: str | None
    copyright: str | None
    #: ``[(calibration illuminant code, ColorMatrix (3, 3) XYZ→camera, ForwardMatrix (3, 3) or None)]``
    calibrations: list = field(default_factory=list)
    #: ``[(hue, sat, val) divisions, [(n, 3) (hue shift °, saturation scale, value scale) per calibration]]``, or
    #: None: the HueSatMap the profile applies after its ForwardMatrix (read, not applied here)
    hue_sat_map: tuple | None = None

    def neutral(self, illuminant_xyz: np.ndarray, cct_K: float) -> np.ndarray:
        """The camera neutral ``CM·XYZ`` (G = 1) the profile predicts for a light of white ``illuminant_xyz`` and
        colour temperature ``cct_K``: with two calibrations their ColorMatrix interpolated linearly in 1/CCT
        between the calibration illuminants' temperatures, clamped outside (the DNG SDK's
        ``dng_color_spec::FindXYZtoCamera``; the light's temperature is known here, so no iteration).

        Parameters
        ----------
        illuminant_xyz : ndarray, shape (3,)
            The light's white, XYZ.
        cct_K : float
            The light's correlated colour temperature, K.

        Returns
        -------
        ndarray, shape (3,)
            ``(R/G, 1, B/G)``.
        """
        codes = [c for c, _, _ in self.calibrations]
        if len(self.calibrations) == 1 or codes[0] not in CALIBRATION_CCT_K or codes[1] not in CALIBRATION_CCT_K:
            cm = self.calibrations[0][1]
        else:
            (c1, m1, _), (c2, m2, _) = self.calibrations
            t1, t2 = CALIBRATION_CCT_K[c1], CALIBRATION_CCT_K[c2]
            w = float(np.clip((1 / cct_K - 1 / t2) / (1 / t1 - 1 / t2), 0.0, 1.0))
            cm = w * m1 + (1 - w) * m2
        n = cm @ np.asarray(illuminant_xyz, float)
        return n / n[1]


def read_tiff_ifd0(data: bytes, magic: int = DCP_MAGIC, what: str = "DCP") -> dict:
    """``{tag: value}`` of a classic TIFF-structured file's first IFD: ASCII as ``str``, (S)RATIONAL as
    float arrays (a zero denominator refused), other numbers as tuples.  Strict: byte order ``II``/``MM``,
    the given magic, every entry and value inside the file, known field types, tags in ascending order.

    Parameters
    ----------
    data : bytes
        The whole file.
    magic : int
        The magic number after the byte order (:data:`DCP_MAGIC`; a TIFF's or DNG's is 42).
    what : str
        The file, as errors name it.

    Returns
    -------
    dict
        Tag number → value.

    Raises
    ------
    DataFileError
        Where the file breaks one of those rules.
    """
    if len(data) < 8 or data[:2] not in (b"II", b"MM"):
        raise DataFileError(f"{what}: not a TIFF-structured file (no II/MM byte order)")
    bo = "<" if data[:2] == b"II" else ">"
    got, off = struct.unpack(bo + "HI", data[2:8])
    if got != magic:
        raise DataFileError(f"{what}: magic number {got:#06x}, expected {magic:#06x}")
    if off < 8 or off + 2 > len(data):
        raise DataFileError(f"{what}: IFD offset {off} outside the file ({len(data)} bytes)")
    (n,) = struct.unpack(bo + "H", data[off:off + 2])
    if n == 0 or off + 2 + 12 * n + 4 > len(data):
        raise DataFileError(f"{what}: IFD of {n} entries at {off} does not fit the file ({len(data)} bytes)")
    tags: dict = {}
    last = -1
    for i in range(n):
        tag, typ, count, raw = struct.unpack(bo + "HHI4s", data[off + 2 + 12 * i:off + 14 + 12 * i])
        if tag <= last:
            raise DataFileError(f"{what}: tag {tag} after {last}: IFD entries must be in ascending order, once each")
        last = tag
        if typ not in _TIFF_TYPES:
            raise DataFileError(f"{what}: tag {tag} has unknown field type {typ}")
        _, size = _TIFF_TYPES[typ]
        nbytes = size * count
        if nbytes <= 4:
            payload = raw[:nbytes]
        else:
            (at,) = struct.unpack(bo + "I", raw)
            if at + nbytes > len(data):
                raise DataFileError(f"{what}: tag {tag}: {nbytes} bytes at {at} run past the end ({len(data)} bytes)")
            payload = data[at:at + nbytes]
        tags[tag] = _tiff_value(payload, bo, typ, count, tag, what)
    return tags


def _tiff_value(payload: bytes, bo: str, typ: int, count: int, tag: int, what: str) -> str | np.ndarray | tuple:
    """:func:`read_tiff_ifd0`'s value of one entry from its bytes: ASCII as ``str``, (S)RATIONAL as a float array
    (a zero denominator refused), other numbers as a tuple."""
    if typ == 2:
        return payload.split(b"\0", 1)[0].decode("latin-1")
    fmt, _ = _TIFF_TYPES[typ]
    values = struct.unpack(bo + fmt[-1] * (len(fmt) * count), payload)
    if typ in (5, 10):
        num, den = np.array(values[0::2], float), np.array(values[1::2], float)
        if np.any(den == 0):
            raise DataFileError(f"{what}: tag {tag}: a rational with denominator 0")
        return num / den
    return values


def read_dcp(path: str | Path) -> DcpProfile:
    """A DNG camera profile (``.dcp``): its camera, and ColorMatrix/ForwardMatrix at each calibration
    illuminant.  Refused unless ColorMatrix1 and CalibrationIlluminant1 are there, each matrix is 9 SRATIONALs
    (3 colour planes), and a second ColorMatrix comes with its CalibrationIlluminant2.

    Parameters
    ----------
    path : str or Path
        The ``.dcp`` file.

    Returns
    -------
    DcpProfile
        With its HueSatMap where the profile has one (read, not applied).

    Raises
    ------
    DataFileError
        When the file cannot be read or breaks one of those rules.
    """
    p = Path(path)
    try:
        data = p.read_bytes()
    except OSError as e:
        raise DataFileError(f"{p}: cannot be read ({e.strerror})") from None
    tags = read_tiff_ifd0(data, DCP_MAGIC, str(p))
    t = DCP_TAGS
    matrix, illuminant = partial(_dcp_matrix, tags, p), partial(_dcp_short, tags, p)
    if not isinstance(tags.get(t["UniqueCameraModel"]), str):
        raise DataFileError(f"{p}: no UniqueCameraModel (ASCII)")
    cals = []
    for i in (1, 2):
        cm, fm, code = matrix(f"ColorMatrix{i}"), matrix(f"ForwardMatrix{i}"), illuminant(f"CalibrationIlluminant{i}")
        if cm is None:
            if i == 1:
                raise DataFileError(f"{p}: no ColorMatrix1")
            if fm is not None:
                raise DataFileError(f"{p}: ForwardMatrix2 without ColorMatrix2")
            continue
        if code is None:
            raise DataFileError(f"{p}: ColorMatrix{i} without CalibrationIlluminant{i}")
        cals.append((code, cm, fm))
    hsm = _hue_sat_map(tags, p, len(cals))
    name, cop = tags.get(t["ProfileName"]), tags.get(t["ProfileCopyright"])
    return DcpProfile(str(p), tags[t["UniqueCameraModel"]], name if isinstance(name, str) else None,
                      cop if isinstance(cop, str) else None, cals, hsm)


def _dcp_matrix(tags: dict, p: Path, name: str) -> np.ndarray | None:
    """:func:`read_dcp`'s ``(3, 3)`` matrix of the tag ``name`` (9 finite (S)RATIONALs), or None where it is not
    there."""
    v = tags.get(DCP_TAGS[name])
    if v is None:
        return None
    if not isinstance(v, np.ndarray) or v.shape != (9,) or not np.all(np.isfinite(v)):
        raise DataFileError(f"{p}: {name} must be 9 (S)RATIONALs (3 colour planes × XYZ)")
    return v.reshape(3, 3)


def _dcp_short(tags: dict, p: Path, name: str) -> int | None:
    """:func:`read_dcp`'s one SHORT of the tag ``name``, or None where it is not there."""
    v = tags.get(DCP_TAGS[name])
    if v is None:
        return None
    if not isinstance(v, tuple) or len(v) != 1:
        raise DataFileError(f"{p}: {name} must be one SHORT, not {v!r}")
    return int(v[0])


def _hue_sat_map(tags: dict, p: Path, calibrations: int) -> tuple | None:
    """:func:`read_dcp`'s HueSatMap: ``(divisions, [(n, 3) per calibration])``, or None where the profile has
    none."""
    t = DCP_TAGS
    dims = tags.get(t["ProfileHueSatMapDims"])
    if dims is None:
        return None
    if not isinstance(dims, tuple) or len(dims) != 3 or min(dims) < 1:
        raise DataFileError(f"{p}: ProfileHueSatMapDims must be 3 counts ≥ 1, not {dims!r}")
    maps = []
    for i in range(1, calibrations + 1):
        d = tags.get(t[f"ProfileHueSatMapData{i}"])
        if d is None or isinstance(d, (str, np.ndarray)) or len(d) != 3 * int(np.prod(dims)):
            raise DataFileError(f"{p}: ProfileHueSatMapData{i} must be {3 * int(np.prod(dims))} FLOATs "
                                f"(3 × the divisions {list(dims)})")
        maps.append(np.asarray(d, float).reshape(-1, 3))
    return (tuple(int(x) for x in dims), maps)


def _calibration_spec(code: int):
    from spectracam.scene.illuminant import IlluminantSpec

    return IlluminantSpec(**{"temperature_K": None, **CALIBRATION_LIGHTS[code][1]})


def _xyz_scaled(cam: np.ndarray, camera_to_xyz: np.ndarray, y_white: float) -> np.ndarray:
    """``camera_to_xyz·cam`` per patch, scaled so that the white patch has luminance ``y_white`` (exposure
    normalised on the white, as :func:`spectracam.experiments.validate.experiment.validate_camera` does)."""
    from spectracam.scene.chart import WHITE_PATCH

    xyz = cam @ camera_to_xyz.T
    return xyz * (y_white / xyz[WHITE_PATCH, 1])


def dcp_rows(camera_name: str, dcp: DcpProfile) -> dict:
    """One camera's DCP table (:func:`run_validate_wb`).

    Parameters
    ----------
    camera_name : str
        A shipped camera with a published matrix model.
    dcp : DcpProfile
        Its profile.

    Returns
    -------
    dict
        The camera, the profile, a row per calibration illuminant with a standard spectrum (matrices, ΔE*ab and
        neutrals: :data:`DEFINITIONS`) and those not compared.
    """
    from spectracam.architecture.cameras import PUBLISHED_MATRICES, library_curves
    from spectracam.scene.reference import ChartReference
    from spectracam.experiments.validate.scene import validation_scene

    curves = library_curves(camera_name)
    pm = PUBLISHED_MATRICES[curves.matrix]
    scene = validation_scene(camera_name)
    chart = ChartReference.of(scene)
    # what the DNG writer fits on: a capture's camera; cfa/single has one exposure time for every channel, and
    # normalise_color_matrix removes the time, so 1 s stands in for it
    raw = SimpleNamespace(camera=scene.camera, exposure_times_s=(1.0, 1.0, 1.0),
                          layout=SimpleNamespace(channels=("R", "G", "B")))
    out = {"camera": camera_name, "model": pm.model, "dcp": dcp.path, "unique_camera_model": dcp.unique_camera_model,
           "profile_name": dcp.profile_name, "profile_copyright": dcp.copyright, "gains": curves.gains_note,
           "independence": _independence(curves, "the DCP"), "calibrations": [], "not_compared": []}
    if dcp.hue_sat_map is not None:
        out["hue_sat_map_divisions"] = list(dcp.hue_sat_map[0])
        out["hue_sat_map_mean_sat_scale"] = [float(m[:, 1].mean()) for m in dcp.hue_sat_map[1]]
    for code, cm_dcp, fm in dcp.calibrations:
        if code not in CALIBRATION_LIGHTS:
            out["not_compared"].append(f"calibration illuminant {code} (no standard spectrum)")
            continue
        out["calibrations"].append(_calibration_row(code, cm_dcp, fm, scene, chart, raw, pm))
    return out


def _calibration_row(code: int, cm_dcp: np.ndarray, fm, scene, chart, raw, pm) -> dict:
    """One calibration of a DCP beside spectracam's fit under the same light: matrices, ΔE*ab and neutrals."""
    from spectracam.scene.chart import WHITE_PATCH
    from spectracam.io.dng import normalise_color_matrix, xyz_to_camera_matrix
    from spectracam.core.cielab import delta_e, xyz_to_lab

    ill = _calibration_spec(code)
    ref = chart.lit_by(ill)
    cm_sc = xyz_to_camera_matrix(raw, ref)
    cam = ref.patch_rates(scene.camera)  # (24, 3) noise-free raw of the chart under the calibration light
    y = float(ref.patch_xyz[WHITE_PATCH, 1])
    lab_true = xyz_to_lab(ref.patch_xyz, ref.white_xyz)
    xyz_dcp = _xyz_scaled(cam, np.linalg.inv(cm_dcp), y)
    xyz_sc = _xyz_scaled(cam, np.linalg.inv(cm_sc), y)
    lab_dcp, lab_sc = xyz_to_lab(xyz_dcp, ref.white_xyz), xyz_to_lab(xyz_sc, ref.white_xyz)
    de_between = delta_e(lab_dcp, lab_sc, "cie1976")
    de_dcp, de_sc = delta_e(lab_dcp, lab_true, "cie1976"), delta_e(lab_sc, lab_true, "cie1976")
    w_std = white_xyz(ill)  # the light's white as the profile's maker means it (360–830 nm)
    n_dcp = cm_dcp @ w_std
    n_dcp = n_dcp / n_dcp[1]
    n_sim = simulated_neutral(scene, ill)
    n_pub = pm.neutral(w_std)
    row = {"calibration_illuminant": code, "illuminant": CALIBRATION_LIGHTS[code][0],
           "color_matrix_dcp": normalise_color_matrix(cm_dcp).round(6).tolist(),
           "color_matrix_spectracam": cm_sc.round(6).tolist(),
           "delta_e_between_mean": float(de_between.mean()), "delta_e_between_max": float(de_between.max()),
           "delta_e_dcp_mean": float(de_dcp.mean()), "delta_e_dcp_max": float(de_dcp.max()),
           "delta_e_spectracam_mean": float(de_sc.mean()), "delta_e_spectracam_max": float(de_sc.max()),
           "neutral_dcp": n_dcp.tolist(), "neutral_simulated": n_sim.tolist(),
           "neutral_ratio_dcp_over_simulated": (n_dcp / n_sim).tolist(),
           "neutral_published_matrix": n_pub.tolist(),
           "neutral_ratio_dcp_over_published_matrix": (n_dcp / n_pub).tolist()}
    if fm is not None:  # white-balanced camera → XYZ D50: FM·diag(1/neutral)·camera (DNG 1.4, chapter 6)
        row.update(_forward_row(fm, ref, cam, n_sim, cm_sc, y))
    return row


def _forward_row(fm: np.ndarray, ref, cam: np.ndarray, n_sim: np.ndarray, cm_sc: np.ndarray, y: float) -> dict:
    """A DCP's ForwardMatrix alone against the chart's truth adapted to D50, and against spectracam's matrix."""
    import colour

    from spectracam.io.dng import D50_XYZ
    from spectracam.core.cielab import delta_e, xyz_to_lab

    bradford = colour.adaptation.matrix_chromatic_adaptation_VonKries(ref.white_xyz, D50_XYZ, "Bradford")
    lab_true50 = xyz_to_lab(ref.patch_xyz @ bradford.T, D50_XYZ)
    lab_fm = xyz_to_lab(_xyz_scaled(cam, fm @ np.diag(1.0 / n_sim), y), D50_XYZ)
    lab_sc50 = xyz_to_lab(_xyz_scaled(cam, bradford @ np.linalg.inv(cm_sc), y), D50_XYZ)
    de_fm, de_fm_between = delta_e(lab_fm, lab_true50, "cie1976"), delta_e(lab_fm, lab_sc50, "cie1976")
    return {"forward_matrix_dcp": fm.round(6).tolist(),
            "forward_delta_e_dcp_mean": float(de_fm.mean()), "forward_delta_e_dcp_max": float(de_fm.max()),
            "forward_delta_e_between_mean": float(de_fm_between.mean()),
            "forward_delta_e_between_max": float(de_fm_between.max())}


# ------------------------------------------------------------------------------------------ both tables
DEFINITIONS = {
    "preset neutral": "1/multiplier per channel, normalised to G, of darktable's wb_presets.json entry at fine-tuning "
                      "0 (the firmware's multipliers as the camera records them in its raw files)",
    "simulated neutral": "noise-free photo-electrons of a perfect white diffuser under the preset's light, R/G and "
                         "B/G, with the camera's measured curves on the validate scene's grid (400–700 nm, 10 nm)",
    "light": "the colour temperature the maker's manual gives for the preset, on the CIE daylight locus for "
             "daylight/cloudy/shade/flash, on the Planckian locus for tungsten/incandescent; the CIE lamp of the "
             "same name for fluorescent presets (a tube's spectrum varies: those rows are indicative only)",
    "error %": "100·(simulated/preset − 1), per ratio; the issue's target is within 3 % for the daylight, cloudy, "
               "shade and flash presets",
    "shape %": "the same with each neutral divided by its own daylight preset's: independent of the channels' gains",
    "effective K": "the temperature on the light's locus whose neutral (simulated camera, or the published XYZ(D65)→"
                   "camera matrix M) is nearest to the preset's, and the rms relative distance left there",
    "DCP ΔE between": "mean CIE 1976 ΔE*ab on the 24 patches between XYZ = CM_dcp⁻¹·raw and XYZ = "
                      "CM_spectracam⁻¹·raw (raw = the chart's noise-free simulated response under the calibration "
                      "illuminant, each scaled to the white patch's Y), CIELAB relative to the illuminant's white; "
                      "CM_spectracam is what the DNG writer fits (white-preserving least squares on the same chart, "
                      "a training fit)",
    "DCP neutral ratio": "CM_dcp·XYZ(illuminant white, 360–830 nm) normalised to G, divided by the simulated "
                         "neutral (= CM_spectracam's), per channel; beside it the same over the published "
                         "XYZ(D65)→camera matrix M's neutral (a D65 calibration: far from D65 only indicative)",
    "DCP forward ΔE": "FM·diag(1/simulated neutral)·raw against the chart's XYZ adapted to D50 by Bradford (DNG's "
                      "white-balanced camera → PCS path), CIELAB relative to D50",
}


def run_validate_wb(cameras: list[str]) -> dict:
    """``{"wb_presets": ..., "dcp_profiles": ...}`` for the shipped cameras ``cameras`` (usable, with a published
    matrix model); each part is ``{"status": "ok", ...}`` or ``{"status": "skipped", "reason": ...}``.

    Parameters
    ----------
    cameras : list of str
        Shipped cameras with a published matrix model.

    Returns
    -------
    dict
        ``wb_presets``, ``dcp_profiles`` and :data:`DEFINITIONS`.
    """
    from spectracam.architecture.cameras import PUBLISHED_MATRICES, library_curves

    out = {"definitions": DEFINITIONS}
    profiles: dict = {}
    d = find_dcp_dir()
    if d is None:
        out["dcp_profiles"] = {"status": "skipped", "reason": _missing("RawTherapee's DCP profiles", DCP_DIR,
                                                                         "rawtherapee-data")}
    else:
        rows = []
        for c in cameras:
            model = PUBLISHED_MATRICES[library_curves(c).matrix].model
            f = d / f"{model}.dcp"
            if not f.is_file():
                rows.append({"camera": c, "model": model, "skipped": f"no {f.name} in {d}"})
                continue
            prof = read_dcp(f)
            if prof.unique_camera_model != model:
                rows.append({"camera": c, "model": model, "skipped": f"{f.name} is for {prof.unique_camera_model!r}"})
                continue
            profiles[c] = prof
            rows.append(dcp_rows(c, prof))
        out["dcp_profiles"] = {"status": "ok", "directory": str(d), "package": "rawtherapee-data", "cameras": rows}
    path = find_wb_presets()
    if path is None:
        out["wb_presets"] = {"status": "skipped", "reason": _missing("darktable's wb_presets.json", WB_PRESETS_PATH,
                                                                       "darktable")}
    else:
        presets = load_wb_presets(path)
        out["wb_presets"] = {"status": "ok", "file": str(path), "package": "darktable", "lights": {
            f"{mk} {name}": {"light": lt.label, "reason": lt.reason} for (mk, name), lt in PRESET_LIGHTS.items()},
            "cameras": [wb_preset_rows(c, presets, profiles.get(c)) for c in cameras]}
    return {"wb_presets": out.pop("wb_presets"), **out}


def wb_markdown(part: dict) -> list[str]:
    """The markdown lines of both tables (part = :func:`run_validate_wb`'s result).

    Parameters
    ----------
    part : dict
        :func:`run_validate_wb`'s result.

    Returns
    -------
    list of str
        Markdown.
    """
    lines = _wb_preset_lines(part["wb_presets"])
    lines += ["## DCP profiles (RawTherapee)", ""]
    dc = part["dcp_profiles"]
    if dc["status"] != "ok":
        lines += [f"Skipped: {dc['reason']}.", ""]
        return lines
    lines += _dcp_table_lines(dc)
    lines += ["", "### Definitions (white balance and DCP)", ""]
    lines += [f"* **{k}**: {v}" for k, v in part["definitions"].items()]
    return lines + [""]


def _wb_preset_lines(wb: dict) -> list[str]:
    """The white-balance presets' section: each camera's table, or why the part was skipped."""
    lines = ["## White-balance presets (darktable's wb_presets.json)", ""]
    if wb["status"] != "ok":
        lines += [f"Skipped: {wb['reason']}.", ""]
    else:
        lines += [f"From `{wb['file']}` (Debian package {wb['package']}), fine-tuning 0.", ""]
        for cam in wb["cameras"]:
            lines += _wb_camera_lines(cam)
    return lines


def _wb_camera_lines(cam: dict) -> list[str]:
    """One camera's presets table (or why it was skipped)."""
    lines = [f"### {cam['camera']} ({cam['darktable_maker']} {cam['darktable_model']})", ""]
    if "skipped" in cam:
        lines += [f"Skipped: {cam['skipped']}.", ""]
        return lines
    lines += [f"Gains: {cam['gains']}. Which check is independent: {cam['independence']}.", "",
              f"Lights from the {cam['lights_source']}.", "",
              "| preset | light | R/G sim / preset (%) | B/G sim / preset (%) | ≤ 3 % | DCP R/G, B/G / "
              "preset (%) | shape R/G, B/G % | effective K, sim (rms %) | effective K, published M (rms %) |",
              "|---|---|---|---|---|---|---|---|---|"]
    for r in cam["presets"]:
        lines.append(_wb_preset_row(r))
    if cam["not_compared"]:
        lines += ["", "Not compared (no standard light of that name): " + ", ".join(cam["not_compared"]) + "."]
    lines.append("")
    return lines


def _wb_preset_row(r: dict) -> str:
    """One preset's row of a camera's presets table."""
    ok = ("yes" if r["within_3_percent"] else "**no**") if r["target"] else "(not in target)"
    shape = (f"{r['RG_shape_error_percent']:+.1f}, {r['BG_shape_error_percent']:+.1f}"
             if "RG_shape_error_percent" in r else "–")
    eff = [f"{r[f'effective_K_{k}']:.0f} ({r[f'effective_rms_percent_{k}']:.1f})"
           if r[f"effective_K_{k}"] is not None else "–" for k in ("simulated", "published_matrix")]
    dcp = (f"{r['RG_dcp']:.4f} ({r['RG_dcp_error_percent']:+.1f}), {r['BG_dcp']:.4f} "
           f"({r['BG_dcp_error_percent']:+.1f})" if "RG_dcp" in r else "–")
    return (f"| {r['preset']} | {r['light']} | {r['RG_simulated']:.4f} / {r['RG_preset']:.4f} "
            f"({r['RG_error_percent']:+.1f}) | {r['BG_simulated']:.4f} / {r['BG_preset']:.4f} "
            f"({r['BG_error_percent']:+.1f}) | {ok} | {dcp} | {shape} | {eff[0]} | {eff[1]} |")


def _dcp_table_lines(dc: dict) -> list[str]:
    """The DCP profiles' table, each camera's independence note and the HueSatMap caveat."""
    lines = [f"From `{dc['directory']}` (Debian package {dc['package']}).", "",
             "| camera | calibration | ΔE*ab DCP CM vs spectracam CM (mean / max) | ΔE*ab DCP CM / spectracam CM vs "
             "truth (mean) | neutral DCP / simulated (R, B) | neutral DCP / published M (R, B) | ΔE*ab DCP FM alone "
             "vs truth, D50 (mean / max) |", "|---|---|---|---|---|---|---|"]
    notes = []
    for cam in dc["cameras"]:
        if "skipped" in cam:
            lines.append(f"| {cam['camera']} | skipped: {cam['skipped']} | | | | | |")
            continue
        notes.append(f"* {cam['camera']}: {cam['independence']}.")
        for r in cam["calibrations"]:
            q, p = r["neutral_ratio_dcp_over_simulated"], r["neutral_ratio_dcp_over_published_matrix"]
            fm = (f"{r['forward_delta_e_dcp_mean']:.2f} / {r['forward_delta_e_dcp_max']:.2f}"
                  if "forward_delta_e_dcp_mean" in r else "– (no ForwardMatrix)")
            lines.append(f"| {cam['camera']} | {r['illuminant']} ({r['calibration_illuminant']}) | "
                         f"{r['delta_e_between_mean']:.2f} / {r['delta_e_between_max']:.2f} | "
                         f"{r['delta_e_dcp_mean']:.2f} / {r['delta_e_spectracam_mean']:.2f} | "
                         f"{q[0]:.3f}, {q[2]:.3f} | {p[0]:.3f}, {p[2]:.3f} | {fm} |")
    lines += [""] + notes
    sat = [f"{cam['camera']} {m:.2f}" for cam in dc["cameras"] for m in cam.get("hue_sat_map_mean_sat_scale", [])[:1]]
    if sat:
        lines += ["", "The ForwardMatrix is checked alone: these profiles apply a HueSatMap after it (mean saturation "
                      f"scale {', '.join(sat)}), so a ForwardMatrix alone renders colours desaturated by design and "
                      "its ΔE is no measure of the simulation."]
    return lines
