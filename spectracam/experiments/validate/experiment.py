"""Real cameras checked against their published colour matrices, offline (``spectracam validate``).

For every shipped camera with a published XYZ(D65)→camera matrix ``M``
(:data:`spectracam.architecture.cameras.PUBLISHED_MATRICES`), the ColorChecker is rendered under CIE D65 and
captured by that camera's measured curves with every noise source off (a ``cfa/single`` capture
metered on the white patch, no clipping); each patch's raw rates are the means of its own sites.

* **Neutral**: the white patch's raw ``R/G`` and ``B/G`` against ``M·XYZ_white`` — the raw values the
  real camera records for that patch as its matrix implies.  For a camera whose gains were
  published with its curves (the Canon) this is an independent check of the curves; for one whose
  gains were restored from this very matrix (the Nikon) it checks only the restoration (it was
  fitted on a perfect white under D65, not on the patch).
* **ΔE*ab with the published matrix**: ``XYZ = M⁻¹·raw``, scaled so that the white patch has its own
  luminance (exposure normalised on a grey card, as a photographer does), against the scene's XYZ,
  CIELAB relative to the D65 white — the matrix was fitted by Adobe on other data, so this is a
  score on colours the conversion was not fitted on.
* **ΔE*ab of the least-squares fit**: a 3×3 fitted on the same 24 patches and scored on them — a
  *training* score, shown beside it as the lower bound a linear conversion reaches.

Beside these, the cameras' own measurements shipped by Debian packages, where installed
(:mod:`spectracam.experiments.validate.white_balance`): the simulated neutral under the light of each firmware
white-balance preset (darktable's ``wb_presets.json``) and RawTherapee's measured DCP profiles' matrices
against spectracam's fits; skipped, with the reason, where the files are absent.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, TypedDict

import numpy as np

from spectracam.architecture.cameras import CAMERAS, PUBLISHED_MATRICES, d65_response, energy_sensitivities, library_curves, library_table
from spectracam.scene.chart import WHITE_PATCH
from spectracam.core.errors import ConfigError
from spectracam.core.cielab import delta_e, xyz_to_lab
from spectracam.experiments.validate.scene import SCENE_OVERRIDES, validation_scene  # noqa: F401

if TYPE_CHECKING:
    from collections.abc import Sequence
    from pathlib import Path

    from matplotlib.figure import Figure

    from spectracam.architecture.cameras import PublishedMatrix
    from spectracam.pipeline.scene_file import Scene

__all__ = ["ValidateResult", "camera_row", "parse_matrix", "raw_patch_rates", "run_validate", "user_camera",
           "validate_camera", "validate_figure", "validate_markdown", "write_validate_outputs"]



def user_camera(camera_file: str | Path, matrix: Sequence[float], unit: str = "relative",
                gains: Sequence[float] | None = None,
                gains_kept: bool = False) -> tuple[Scene, PublishedMatrix, str, tuple | None]:
    """``(scene, PublishedMatrix, gains note, (wl, curves) as read or None)`` of a user's camera: the CSV of
    ``filters.camera_file`` and its published XYZ(D65)→camera ``matrix`` (9 numbers), checked by the same
    rules as a scene's (:mod:`spectracam.architecture.filters`); the matrix also restores the gains of per-channel-normalised
    curves, as for the shipped cameras.

    Parameters
    ----------
    camera_file : str or Path
        The CSV of the camera's curves.
    matrix : sequence of float
        9 numbers, row-major (:func:`parse_matrix`).
    unit : str
        ``filters.camera_unit`` of the curves.
    gains : sequence of float or None
        ``filters.camera_gains``; None: none given.
    gains_kept : bool
        ``filters.camera_gains_kept``.

    Returns
    -------
    tuple
        The validation scene, the matrix, how the gains were set, and ``(wl, curves)`` when the curves are relative
        and peak-normalised (else None).
    """
    from pathlib import Path

    from spectracam.architecture.cameras import PublishedMatrix, file_gains, load_camera_csv, peak_normalised

    wl, rows = load_camera_csv(Path(camera_file), "--camera-file")
    filters = {"camera": "file", "camera_curve_nm": wl, "camera_curve": rows, "camera_unit": unit,
               "camera_xyz_to_camera": tuple(matrix), "camera_gains": tuple(gains or ()),
               "camera_gains_kept": bool(gains_kept)}
    scene = validation_scene(str(camera_file), filters, (wl[0], wl[-1]))
    spec = scene.camera.filters
    w, v = np.asarray(spec.camera_curve_nm), np.asarray(spec.camera_curve)
    g = file_gains(spec, w, v)
    if spec.camera_gains:
        note = f"given (camera_gains R {g[0]:.4g}, G {g[1]:.4g}, B {g[2]:.4g})"
    elif np.any(g != 1.0):
        note = (f"restored: the D65 neutral of the given matrix (gains R {g[0] / g[1]:.3f}, G 1, B {g[2] / g[1]:.3f} "
                "on the per-channel-normalised curves)")
    else:
        note = "as in the file" + (" (camera_gains_kept)" if spec.camera_gains_kept else "")
    m = PublishedMatrix(Path(camera_file).name, spec.camera_xyz_to_camera, "given (--matrix)")
    equal = (w, v) if unit == "relative" and peak_normalised(v) else None
    return scene, m, note, equal


def raw_patch_rates(scene: Scene, renderer: str) -> np.ndarray:
    """``(24, 3)`` raw rates (e⁻/s) of the patches from a real render and noise-free capture.

    Parameters
    ----------
    scene : Scene
        A validation scene.
    renderer : str

    Returns
    -------
    ndarray
        ``(24, 3)`` e⁻/s: each patch's mean DN over the exposure time.
    """
    from spectracam.pipeline import capture
    from spectracam.scene.reference import ChartReference
    from spectracam.render import render
    from spectracam.evaluation.score import channel_stats

    cube = render(scene, renderer)
    raw = capture(cube, scene=scene)
    means, _ = channel_stats(raw, ChartReference.of(scene).boxes)
    return means / np.asarray(raw.exposure_times_s)[None, :]


def validate_camera(name: str, renderer: str = "analytic") -> dict:
    """One shipped camera's row: simulated and published neutral, ΔE*ab with the published matrix and the fit.

    Parameters
    ----------
    name : str
        A camera of the shipped library with a published matrix.
    renderer : str

    Returns
    -------
    dict
        :func:`camera_row`'s.
    """
    curves = library_curves(name)
    equal = (curves.wavelengths_nm, curves.values) if curves.per_channel else None
    return camera_row(name, validation_scene(name), PUBLISHED_MATRICES[curves.matrix],
                      curves.gains_note if curves.per_channel else "as published", equal, renderer)


def camera_row(name: str, scene: Scene, matrix: PublishedMatrix, gains_note: str, equal_gains: tuple | None,
               renderer: str = "analytic") -> dict:
    """A camera's row (module docstring); ``equal_gains``: ``(wl, curves)`` normalised per channel, whose white
    at equal gains is shown beside (what ignoring the lost gains would give), or None.

    Parameters
    ----------
    name : str
    scene : Scene
        Its validation scene.
    matrix : PublishedMatrix
    gains_note : str
        How the curves' gains were set.
    equal_gains : tuple or None
    renderer : str

    Returns
    -------
    dict
        The white patch's R/G and B/G simulated and published (and their error, %), the ΔE*ab of the published
        matrix and of the fit (mean, max, per patch).
    """
    from spectracam.scene.reference import ChartReference

    ref = ChartReference.of(scene)
    rates = raw_patch_rates(scene, renderer)
    sim = rates[WHITE_PATCH] / rates[WHITE_PATCH][1]
    pub = matrix.neutral(ref.patch_xyz[WHITE_PATCH])
    lab_scene = xyz_to_lab(ref.patch_xyz, ref.white_xyz)
    est = rates @ np.linalg.inv(matrix.matrix).T
    est *= ref.patch_xyz[WHITE_PATCH, 1] / est[WHITE_PATCH, 1]
    de_pub = delta_e(xyz_to_lab(est, ref.white_xyz), lab_scene, "cie1976")
    fit, *_ = np.linalg.lstsq(rates, ref.patch_xyz, rcond=None)
    de_fit = delta_e(xyz_to_lab(rates @ fit, ref.white_xyz), lab_scene, "cie1976")
    row = {"camera": name, "model": matrix.model, "matrix_xyz_to_camera": list(matrix.xyz_to_camera),
           "matrix_source": matrix.source, "gains": gains_note,
           "white_RG_simulated": float(sim[0]), "white_BG_simulated": float(sim[2]),
           "white_RG_published": float(pub[0]), "white_BG_published": float(pub[2]),
           "white_RG_error_percent": float(100 * (sim[0] / pub[0] - 1)),
           "white_BG_error_percent": float(100 * (sim[2] / pub[2] - 1)),
           "delta_e_published_mean": float(de_pub.mean()), "delta_e_published_max": float(de_pub.max()),
           "delta_e_fit_mean": float(de_fit.mean()), "delta_e_fit_max": float(de_fit.max()),
           "delta_e_published_per_patch": de_pub.round(4).tolist(), "delta_e_fit_per_patch": de_fit.round(4).tolist(),
           "patch_names": list(ref.names)}
    if equal_gains is not None:  # what the defect gave: the channels at equal gains, on the white patch
        from spectracam.scene.chart import patch_reflectances

        r = d65_response(*equal_gains, patch_reflectances(scene.chart)[WHITE_PATCH][1])
        row["white_RG_equal_gains"], row["white_BG_equal_gains"] = float(r[0]), float(r[2])
    return row


class _ValidateKeys(TypedDict):
    renderer: str
    illuminant: str
    chart: str
    definitions: dict[str, str]
    cameras: list[dict]
    library: list[dict]


class ValidateResult(_ValidateKeys, total=False):
    """What :func:`run_validate` returns, validate.json's keys but ``command``: a row per camera
    (:func:`camera_row`), the library as ``spectracam cameras`` lists it (the base's keys, always there), and,
    for the shipped cameras (not a user's), ``real_camera_data``: the cameras' own measurements, or why they
    were skipped."""

    real_camera_data: dict


def run_validate(renderer: str = "analytic", user: dict | None = None) -> ValidateResult:
    """Every shipped camera with a published matrix, and the library as ``spectracam cameras`` lists it; with
    ``user`` (the keyword arguments of :func:`user_camera`), that camera alone, checked the same way.

    Parameters
    ----------
    renderer : str
    user : dict or None

    Returns
    -------
    ValidateResult
        validate.json's keys but ``command``.
    """
    from spectracam.experiments.validate.white_balance import run_validate_wb

    if user is not None:
        scene, matrix, note, equal = user_camera(**user)
        rows = [camera_row(str(user["camera_file"]), scene, matrix, note, equal, renderer)]
        names = []
    else:
        names = [n for n in CAMERAS if library_curves(n).matrix in PUBLISHED_MATRICES and _usable(n)]
        rows = [validate_camera(n, renderer) for n in names]
    out = {"renderer": renderer, "illuminant": "CIE D65", "chart": validation_scene(CAMERAS[0]).chart.dataset,
            "definitions": {
                "neutral": "raw R/G and B/G of the ColorChecker's white patch (noise-free capture) against "
                           "M·XYZ(white patch) of the published XYZ(D65)→camera matrix M",
                "delta_e_published": "CIE 1976 ΔE*ab of XYZ = M⁻¹·raw (scaled to the white patch's Y) against the "
                                     "scene's XYZ, CIELAB relative to D65; M was not fitted on these patches",
                "delta_e_fit": "CIE 1976 ΔE*ab of a 3×3 least-squares fit raw→XYZ on the same 24 patches (a training "
                               "score)"},
            "cameras": rows, "library": library_table()}
    if user is None:  # the cameras' own measurements from Debian packages (darktable, rawtherapee-data), or why skipped
        out["real_camera_data"] = run_validate_wb(names)
    return out


def parse_matrix(text: str) -> tuple:
    """9 numbers (an XYZ(D65)→camera matrix, row-major) from ``--matrix``: the numbers themselves, separated by
    commas, spaces or brackets, or the path of a text file that holds them (``#`` lines skipped).

    Parameters
    ----------
    text : str
        ``--matrix``.

    Returns
    -------
    tuple of float
        The 9 numbers.

    Raises
    ------
    ConfigError
        When it is not 9 finite numbers, or names a file that is not a readable regular text file.
    """
    import os
    import re
    import stat
    from pathlib import Path

    source = text
    if os.path.exists(text):
        p = Path(text)
        if not stat.S_ISREG(p.stat().st_mode):
            raise ConfigError("--matrix", text, "must be 9 numbers or a regular text file holding them")
        try:
            source = p.read_bytes()[:100_000].decode("utf-8")
        except (OSError, UnicodeDecodeError) as e:
            raise ConfigError("--matrix", text, f"cannot be read as a text file ({e})") from None
        source = "\n".join(r for r in source.splitlines() if not r.lstrip().startswith("#"))
    parts = [x for x in re.split(r"[\s,;\[\]()]+", source) if x]
    try:
        nums = [float(x) for x in parts]
    except ValueError:
        nums = []
    if len(nums) != 9 or not np.all(np.isfinite(nums)):
        raise ConfigError("--matrix", text[:200], "must be 9 finite numbers — the camera's XYZ(D65)→camera matrix, "
                                                  "row-major (rows R, G, B), e.g. Adobe's ColorMatrix2 ×10⁴ as dcraw "
                                                  "tabulates it — or a text file holding them")
    return tuple(nums)


def _usable(name: str) -> bool:
    try:
        energy_sensitivities(name)
        return True
    except ConfigError:
        return False


def validate_markdown(result: dict, command: str) -> str:
    """validate.md: the cameras' rows as a table, the definitions, the real cameras' own data and the library.

    Parameters
    ----------
    result : dict
        :func:`run_validate`'s.
    command : str
        The command, recorded at the top.

    Returns
    -------
    str
    """
    lines = ["# Real cameras against their published matrices", "", f"`{command}`", "",
             f"Chart: {result['chart']} under {result['illuminant']}, noise-free, renderer {result['renderer']}.", "",
             "| camera | gains | white R/G sim / published | B/G sim / published | ΔE*ab published M (mean / max) "
             "| ΔE*ab LS fit, training (mean / max) |", "|---|---|---|---|---|---|"]
    for r in result["cameras"]:
        lines.append(f"| {r['camera']} | {r['gains']} | {r['white_RG_simulated']:.3f} / {r['white_RG_published']:.3f} "
                     f"({r['white_RG_error_percent']:+.1f} %) | {r['white_BG_simulated']:.3f} / "
                     f"{r['white_BG_published']:.3f} ({r['white_BG_error_percent']:+.1f} %) | "
                     f"{r['delta_e_published_mean']:.2f} / {r['delta_e_published_max']:.2f} | "
                     f"{r['delta_e_fit_mean']:.2f} / {r['delta_e_fit_max']:.2f} |")
    for r in result["cameras"]:
        if "white_RG_equal_gains" in r:
            lines += ["", f"{r['camera']} read as shipped (each channel normalised to a peak of 1, so at equal "
                          f"gains): its white would read R/G {r['white_RG_equal_gains']:.3f}, B/G "
                          f"{r['white_BG_equal_gains']:.3f} against the published {r['white_RG_published']:.3f}, "
                          f"{r['white_BG_published']:.3f} — the gains must be restored."]
    lines += ["", "## Definitions", ""] + [f"* **{k}**: {v}" for k, v in result["definitions"].items()]
    if "real_camera_data" in result:  # white-balance presets and DCP profiles (validate_wb)
        from spectracam.experiments.validate.white_balance import wb_markdown

        lines += [""] + wb_markdown(result["real_camera_data"])
    lines += ["", "## The library", "", "| camera | range, nm | normalisation | gains | published matrix | source |",
              "|---|---|---|---|---|---|"]
    for c in result["library"]:
        lines.append(f"| {c['name']} | {c['range_nm'][0]:g}–{c['range_nm'][1]:g} | {c['normalisation']} | {c['gains']} "
                     f"| {c['published_matrix'] or '–'} | {c['source']} |")
    return "\n".join(lines) + "\n"


def validate_figure(result: dict) -> Figure:
    """The neutral under D65 (simulated against published R/G, B/G) and the per-patch ΔE*ab of the published matrix
    (bars) and the fit (ticks), per camera.

    Parameters
    ----------
    result : dict
        :func:`run_validate`'s.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from spectracam.io.plots import pyplot

    plt = pyplot()
    rows = result["cameras"]
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.4), gridspec_kw={"width_ratios": [1.3, 2.2]})
    x = np.arange(len(rows))
    for j, (key, label) in enumerate((("RG", "R/G"), ("BG", "B/G"))):
        axes[0].bar(x + (j - 0.5) * 0.4 - 0.1, [r[f"white_{key}_simulated"] for r in rows], 0.2,
                    label=f"{label} simulated", color=["#c0392b", "#2c6fbb"][j])
        axes[0].bar(x + (j - 0.5) * 0.4 + 0.1, [r[f"white_{key}_published"] for r in rows], 0.2,
                    label=f"{label} published M", color=["#e6a09a", "#9dbbe0"][j])
    axes[0].set_xticks(x, [r["model"].replace(" ", "\n", 1) for r in rows], fontsize=8)
    axes[0].set_ylabel("white patch raw, relative to G")
    axes[0].set_title("neutral under D65")
    axes[0].legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2)
    names = rows[0]["patch_names"] if rows else []
    px = np.arange(len(names))
    for i, r in enumerate(rows):
        w = 0.8 / max(len(rows), 1)
        axes[1].bar(px + i * w - 0.4 + w / 2, r["delta_e_published_per_patch"], w * 0.9,
                    label=f"{r['model']}: published M (mean {r['delta_e_published_mean']:.2f})")
        axes[1].plot(px + i * w - 0.4 + w / 2, r["delta_e_fit_per_patch"], "k_", ms=6,
                     label="LS fit, training" if i == 0 else None)
    axes[1].set_xticks(px, names, rotation=70, fontsize=7)
    axes[1].set_ylabel("ΔE*ab (CIE 1976)")
    axes[1].set_title("simulated raw converted by each camera's published matrix")
    axes[1].legend(fontsize=8)
    fig.tight_layout()
    return fig


def write_validate_outputs(out_dir: str | Path, result: dict, command: str) -> list:
    """validate.json, validate.md and validate.png/.svg, atomically.

    Parameters
    ----------
    out_dir : str or Path
    result : dict
        :func:`run_validate`'s.
    command : str

    Returns
    -------
    list of Path
        The files written.
    """
    from spectracam.io.report import write_figure_json_markdown

    return write_figure_json_markdown(out_dir, "validate", validate_figure(result), "validate.json", result, command,
                                      "validate.md", validate_markdown(result, command))
