"""Which readings of the paper's unstated choices reproduce which of its claims.

The paper leaves open the sensor's quantum efficiency (and the photodiode's collection depth), how
"FPN < 1 %" is meant, whether the field-sequential frames and the prism's sensors share a fixed
pattern, whether its ADC clips the dark noise at code 0, the pixel size, the demosaicking, the
spectral range and the light level.  Each *reading* fixes one value of each; for every reading the
whole comparison (Figures 4-6) is rerun — the light recalibrated so that cfa/single needs the
paper's 28 ms at 5000 K, which the paper does state — and every claim is judged.  A factorial over
the four choices that move the verdicts most, plus one-at-a-time variations of the others, maps
the region where each claim holds.
"""
from __future__ import annotations

import itertools
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, TypedDict

import numpy as np

from spectracam.camera import CameraSpec
from spectracam.processing.color import ProcessingSpec
from spectracam.io.plots import OKABE_ITO
from spectracam.experiments.paper.claims import evaluate
from spectracam.experiments.paper.experiment import PaperExperiment, calibrated_luminance, comparison, scenes_for

if TYPE_CHECKING:
    from collections.abc import Callable
    from pathlib import Path

    from matplotlib.figure import Figure

__all__ = ["FACTORS", "ONE_AT_A_TIME", "VERDICT_VALUE", "ConsistencyResult", "Reading", "consistency_figure",
           "consistency_markdown", "readings", "run_consistency", "write_consistency_outputs"]

#: The factorial: choice → ((label, tables over the base camera/processing), ...); the first value is
#: the experiment's default reading.
FACTORS: dict[str, tuple] = {
    "QE": (("photodiode 2 µm", {"filters": {"qe": "photodiode", "collection_depth_um": 2.0}}),
           ("flat", {"filters": {"qe": "flat"}}),
           ("photodiode 3 µm", {"filters": {"qe": "photodiode", "collection_depth_um": 3.0}}),
           ("photodiode 5 µm", {"filters": {"qe": "photodiode", "collection_depth_um": 5.0}}),
           ("silicon-like shape", {"filters": {"qe": "silicon"}})),
    "FPN < 1 %": (("bound", {"sensor": {"fpn_reading": "bound"}}), ("rms", {"sensor": {"fpn_reading": "std"}})),
    "FPN across channels": (("physical", {"capture": {"fixed_pattern": "physical"}}),
                            ("shared", {"capture": {"fixed_pattern": "shared"}}),
                            ("independent", {"capture": {"fixed_pattern": "independent"}})),
    "ADC at code 0": (("black level", {}), ("clips the dark noise", {"sensor": {"black_level_DN": 0.0}})),
}
#: Choices varied one at a time from the default reading: (choice, label, tables, light scale).
ONE_AT_A_TIME: tuple = (
    ("pixel", "5 µm pixel", {"sensor": {"pixel_pitch_um": 5.0}}, 1.0),
    ("demosaicking", "per-tile", {"processing": {"demosaic": "patch"}}, 1.0),
    ("demosaicking", "Malvar 2004", {"processing": {"demosaic": "malvar2004"}}, 1.0),
    ("spectral range", "380–730 nm", {"wavelengths": {"start_nm": 380, "stop_nm": 730, "step_nm": 10}}, 1.0),
    ("light level", "10× less light (30 lx)", {}, 0.1),
)


@dataclass(frozen=True)
class Reading:
    """One reading of the open choices: ``values`` (choice → label) and the tables they set."""

    values: dict
    tables: dict = field(default_factory=dict)
    light_scale: float = 1.0


def _merge(*tables: dict) -> dict:
    out: dict = {}
    for t in tables:
        for k, v in t.items():
            out.setdefault(k, {}).update(v)
    return out


def readings() -> list[Reading]:
    """The factorial over :data:`FACTORS`, then :data:`ONE_AT_A_TIME` from the default reading."""
    names = list(FACTORS)
    default = {n: FACTORS[n][0][0] for n in names}
    out = [Reading(dict(zip(names, (lab for lab, _ in combo))), _merge(*(t for _, t in combo)))
           for combo in itertools.product(*FACTORS.values())]
    base_tables = _merge(*(FACTORS[n][0][1] for n in names))
    for choice, label, tables, scale in ONE_AT_A_TIME:
        out.append(Reading({**default, choice: label}, _merge(base_tables, tables), scale))
    return out


def _camera_and_processing(exp: PaperExperiment, tables: dict) -> tuple[CameraSpec, ProcessingSpec]:
    cam = CameraSpec.from_dict({k: v for k, v in tables.items() if k in ("optics", "filters", "sensor", "capture")},
                               "consistency", exp.base.camera)
    return cam, ProcessingSpec.from_dict(tables.get("processing", {}), "consistency", exp.base.processing)


class ConsistencyResult(TypedDict):
    """What :func:`run_consistency` returns, consistency.json's keys but ``command``: the claims' ids and text,
    a row per reading (its values, light, verdict and measurement per claim), how often each claim got each
    verdict, the index of the reading that reproduces the most (``best``) and its score (reproduced, partly)."""

    parameters: dict
    claims: list[str]
    claim_text: dict[str, str]
    rows: list[dict]
    summary: dict[str, dict[str, int]]
    best: int
    best_score: list[int]
    seconds: float


def run_consistency(exp: PaperExperiment, renderer: str = "analytic", quick: bool = True,
                    log: Callable[[str], object] = lambda m: None, progress: bool = False) -> ConsistencyResult:
    """Every reading's claims.  Radiance is rendered once per wavelength grid and scaled to each
    reading's calibrated light level (rendering is linear in the light).  ``progress``: a bar over the
    readings on a terminal.

    Parameters
    ----------
    exp : PaperExperiment
        The paper's experiment; each reading's tables go over its base camera and processing.
    renderer : str
    quick : bool
        160 × 120 px scenes.
    log : callable
        ``log(line)`` per reading.
    progress : bool

    Returns
    -------
    ConsistencyResult
        consistency.json's keys but ``command``.
    """
    from spectracam.core.progress import bar
    from spectracam.render import render
    from spectracam.pipeline.scene_file import parse_grid

    t0 = time.perf_counter()
    cube_sets: dict = {}
    rows = []
    for i, reading in enumerate(bar(readings(), desc="readings", unit="reading", progress=progress)):
        base = exp.base
        if "wavelengths" in reading.tables:
            base = base.replace(grid=parse_grid(reading.tables["wavelengths"]))
        e = PaperExperiment(**{**exp.__dict__, "base": base})
        camera, processing = _camera_and_processing(e, reading.tables)
        level = calibrated_luminance(e, camera) * reading.light_scale
        key = base.grid
        if key not in cube_sets:
            ref_level = 100.0
            cube_sets[key] = {k: (s, render(s, renderer)) for k, s in scenes_for(e, ref_level, quick).items()}
        r, _ = comparison(e, cube_sets[key], camera, processing, light_scale=level / 100.0)
        claims = evaluate(r)
        rows.append({"reading": reading.values, "light_scale": reading.light_scale,
                     "white_luminance_cd_m2": level, "verdicts": {c["id"]: c["verdict"] for c in claims},
                     "measured": {c["id"]: c["measured"] for c in claims}})
        log(f"reading {i + 1}: " + ", ".join(f"{k}: {v}" for k, v in reading.values.items()))
    claim_ids = list(rows[0]["verdicts"])
    score = lambda row: (sum(v == "reproduced" for v in row["verdicts"].values()),  # noqa: E731
                         sum(v == "partly" for v in row["verdicts"].values()))
    best = max(range(len(rows)), key=lambda i: (score(rows[i]), -i))
    summary = {cid: {v: sum(r["verdicts"][cid] == v for r in rows) for v in ("reproduced", "partly", "not")}
               for cid in claim_ids}
    return {"parameters": {"renderer": renderer, "quick": quick, "factors": {k: [lab for lab, _ in v]
                                                                             for k, v in FACTORS.items()},
                           "one_at_a_time": [[c, lab] for c, lab, _, _ in ONE_AT_A_TIME],
                           "light": "recalibrated per reading: cfa/single needs 28 ms at 5000 K"},
            "claims": claim_ids, "claim_text": {c["id"]: c["claim"] for c in claims}, "rows": rows,
            "summary": summary, "best": best,
            "best_score": list(score(rows[best])), "seconds": time.perf_counter() - t0}


VERDICT_VALUE = {"reproduced": 2, "partly": 1, "not": 0}


#: Points, every text of the consistency map but its title.
_FS = 8


def _width_in(s: str, bold: bool = False) -> float:
    """Width of a text's longest line at :data:`_FS` points, inches."""
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import TextPath

    prop = FontProperties(size=_FS, weight="bold" if bold else "normal")
    return max(TextPath((0, 0), t, size=_FS, prop=prop).get_extents().width if t.strip() else 0.0
               for t in s.split("\n")) / 72


def _label_columns(rows: list[dict]) -> tuple[list, list, list]:
    """``(factors, extra, columns)``: the factorial's choices (the first row's), each row's choices
    beyond them, and the row labels' columns ``(header, values)``."""
    import textwrap

    # The row labels: a column per choice of the factorial (the first row's), then, for the readings
    # that vary one other choice from the experiment's reading, that choice (the rest greyed: defaults).
    factors = list(rows[0]["reading"])
    extra = [{k: v for k, v in r["reading"].items() if k not in factors} for r in rows]
    columns = [(textwrap.fill(f, 13), [str(r["reading"].get(f, "")) for r in rows]) for f in factors]
    if any(extra):
        columns.append(("one choice\nchanged alone", ["; ".join(f"{k}: {v}" for k, v in e.items()) for e in extra]))
    return factors, extra, columns


@dataclass(frozen=True)
class _MapLayout:
    """Sizes of the consistency map's parts, in inches, and the key's wrapped lines."""

    gap: float
    col_w: list
    table_w: float
    map_w: float
    map_h: float
    code_band: float
    key_lines: list
    left: float
    bottom: float
    fig_w: float
    fig_h: float


def _map_layout(result: dict, columns: list) -> _MapLayout:
    """Lay the map out: the label table, the map, the claim codes, the legend and the key."""
    import textwrap

    rows, claims = result["rows"], result["claims"]
    # The claims' sentences, for the key, as run_consistency recorded them.
    sentences = dict(result.get("claim_text") or {})
    gap, pad = 0.16, 0.12  # inches between label columns, and before the map
    col_w = [max([_width_in(h, bold=True)] + [_width_in(v, bold=True) for v in vals]) for h, vals in columns]
    table_w = sum(col_w) + gap * (len(col_w) - 1) + pad

    # Layout, in inches.
    row_h, cell_w = 0.19, 0.52
    map_w, map_h = cell_w * len(claims), row_h * len(rows)
    code_band = max(_width_in(c) for c in claims) * 0.71 + 0.18
    header_h = max(h.count("\n") + 1 for h, _ in columns) * _FS * 1.3 / 72 + 0.08
    title_h = 0.55
    key_lines = [(c, textwrap.wrap(sentences.get(c, "(no description)"), 95)) for c in claims]
    key_h = (sum(len(t) for _, t in key_lines) + 1.6) * _FS * 1.35 / 72
    legend_w = 2.1
    left, top, bottom = 0.15 + table_w, title_h + max(code_band, header_h), code_band + 0.25 + key_h + 0.15
    fig_w = max(left + map_w + legend_w, 0.3 + max(_width_in(c, True) for c in claims) + 0.15
                + max(_width_in(line) for _, t in key_lines for line in t) + 0.3)
    fig_h = top + map_h + bottom
    return _MapLayout(gap, col_w, table_w, map_w, map_h, code_band, key_lines, left, bottom, fig_w, fig_h)


def consistency_figure(result: dict) -> Figure:
    """A map: one row per reading, one column per claim, coloured by verdict.  Left of it a table of
    the reading's choices under their names; the claim codes over and under the columns, explained
    in a key below.  Every text is at least 8 pt.

    Parameters
    ----------
    result : dict
        :func:`run_consistency`'s.

    Returns
    -------
    matplotlib.figure.Figure
        Sized to its rows and columns.
    """
    from spectracam.io.plots import pyplot

    plt = pyplot()
    rows, claims = result["rows"], result["claims"]
    M = np.array([[VERDICT_VALUE[r["verdicts"][c]] for c in claims] for r in rows])
    b = result["best"]
    factors, extra, columns = _label_columns(rows)
    lay = _map_layout(result, columns)
    fig = plt.figure(figsize=(lay.fig_w, lay.fig_h))
    ax = fig.add_axes((lay.left / lay.fig_w, lay.bottom / lay.fig_h, lay.map_w / lay.fig_w, lay.map_h / lay.fig_h))
    cmap = _draw_map(ax, M, claims)
    _draw_choice_table(ax, lay, columns, extra, len(factors), b)
    _draw_rules(ax, lay, rows, extra, factors)
    _map_legend(ax, cmap, len(claims), b, lay.map_w)
    fig.text(0.5, 1 - 0.12 / lay.fig_h, "The paper's claims (columns) under each reading of its open choices (rows)\n"
             f"every combination of the {len(factors)} choices named over the rows"
             + (", then one other choice at a time from the experiment's reading (the first row)" if any(extra)
                else ""), ha="center", va="top", fontsize=10)
    _draw_key(fig, lay, claims)
    return fig


def _draw_map(ax, M: np.ndarray, claims: list):
    """The verdicts as coloured cells, the claim codes over and under the columns; returns the colormap."""
    from matplotlib.colors import ListedColormap

    cmap = ListedColormap(["#d9d9d9", "#9ecae1", "#2171b5"])
    ax.imshow(M, cmap=cmap, vmin=0, vmax=2, aspect="auto", interpolation="nearest")
    ax.set_xticks(range(len(claims)), claims)
    ax.tick_params(axis="x", labelsize=_FS, top=True, labeltop=True)
    for t in ax.xaxis.get_major_ticks():
        t.label1.set(rotation=45, ha="right", rotation_mode="anchor")
        t.label2.set(rotation=45, ha="left", rotation_mode="anchor")
    ax.set_yticks([])
    return cmap


def _draw_choice_table(ax, lay: _MapLayout, columns: list, extra: list, n_factors: int, b: int) -> None:
    """The table of choices, in inches left of the map, one text per row and choice."""
    from matplotlib import transforms

    fig = ax.figure
    row_of = transforms.blended_transform_factory(ax.transAxes, ax.transData)
    x = -lay.table_w
    for j, ((header, vals), w) in enumerate(zip(columns, lay.col_w)):
        at = row_of + transforms.ScaledTranslation(x, 0, fig.dpi_scale_trans)
        ax.text(0, -0.5, header, transform=at + transforms.ScaledTranslation(0, 0.06, fig.dpi_scale_trans),
                ha="left", va="bottom", fontsize=_FS, fontweight="bold")
        for i, v in enumerate(vals):
            default = bool(extra[i]) and j < n_factors  # a one-at-a-time reading's unchanged choice
            ax.text(0, i, v, transform=at, ha="left", va="center", fontsize=_FS,
                    fontweight="bold" if i == 0 else "normal",
                    color=OKABE_ITO[1] if i == b else ("#8c8c8c" if default else "black"))
        x += w + lay.gap


def _draw_rules(ax, lay: _MapLayout, rows: list, extra: list, factors: list) -> None:
    """Rules: between the groups of the first choice, and before the one-at-a-time readings."""
    from matplotlib import transforms

    rule = dict(transform=transforms.blended_transform_factory(ax.transAxes, ax.transData), clip_on=False)
    for i in range(1, len(rows)):
        if extra[i] and not extra[i - 1]:
            ax.plot([-lay.table_w / lay.map_w, 1], [i - 0.5] * 2, color="black", lw=1.2, **rule)
        elif not extra[i] and rows[i]["reading"][factors[0]] != rows[i - 1]["reading"][factors[0]]:
            ax.plot([-lay.table_w / lay.map_w, 0], [i - 0.5] * 2, color="#b0b0b0", lw=0.6, **rule)
            ax.axhline(i - 0.5, color="white", lw=1.5)


def _map_legend(ax, cmap, n_claims: int, b: int, map_w: float) -> None:
    """Frame the experiment's reading and the best one, and explain the colours and frames right of the map."""
    from matplotlib.patches import Rectangle

    ax.add_patch(Rectangle((-0.5, -0.5), n_claims, 1, fill=False, ec="black", lw=1.8))
    ax.add_patch(Rectangle((-0.5, b - 0.5), n_claims, 1, fill=False, ec=OKABE_ITO[1], lw=1.8, ls="--"))
    handles = [Rectangle((0, 0), 1, 1, color=cmap(i)) for i in (2, 1, 0)]
    handles += [Rectangle((0, 0), 1, 1, fill=False, ec="black", lw=1.8),
                Rectangle((0, 0), 1, 1, fill=False, ec=OKABE_ITO[1], ls="--", lw=1.8)]
    ax.legend(handles, ["reproduced", "partly (direction\nholds, size not)", "not",
                        "the experiment's\nreading (bold)", "most claims\nreproduced (red)"],
              loc="upper left", bbox_to_anchor=(1 + 0.1 / map_w, 1.0), borderaxespad=0.0,
              fontsize=_FS, title="verdict", title_fontsize=_FS, frameon=False)


def _draw_key(fig, lay: _MapLayout, claims: list) -> None:
    """The key below the map: each claim code and its claim."""
    fig_w, fig_h = lay.fig_w, lay.fig_h
    y = lay.bottom - lay.code_band - 0.2
    fig.text(0.2 / fig_w, y / fig_h, "Claims (the columns):", ha="left", va="top", fontsize=_FS, fontweight="bold")
    code_w = max(_width_in(c, True) for c in claims) + 0.15
    y -= 1.6 * _FS * 1.35 / 72
    for code, text in lay.key_lines:
        fig.text(0.3 / fig_w, y / fig_h, code, ha="left", va="top", fontsize=_FS, fontweight="bold")
        for line in text:
            fig.text((0.3 + code_w) / fig_w, y / fig_h, line, ha="left", va="top", fontsize=_FS)
            y -= _FS * 1.35 / 72


def consistency_markdown(result: dict, command: str) -> str:
    """consistency.md: how often each claim holds, the reading that reproduces the most, and every reading's verdicts.

    Parameters
    ----------
    result : dict
        :func:`run_consistency`'s.
    command : str
        The command, recorded at the top.

    Returns
    -------
    str
        The markdown.
    """
    rows, claims = result["rows"], result["claims"]
    factors = list(rows[0]["reading"])
    lines = ["# The paper's claims across the readings of its open choices", "",
             f"Made by `{command}` ({result['parameters']['renderer']}, "
             f"{'160×120' if result['parameters']['quick'] else 'full size'}; light recalibrated per reading so that "
             "cfa/single needs 28 ms at 5000 K). "
             f"{len(rows)} readings, {result['seconds']:.0f} s.", "",
             "## How often each claim holds", "",
             "| claim | reproduced | partly | not |", "|---|---|---|---|"]
    for cid in claims:
        s = result["summary"][cid]
        lines.append(f"| {cid} | {s['reproduced']} | {s['partly']} | {s['not']} |")
    b = rows[result["best"]]
    lines += ["", f"Most claims reproduced ({result['best_score'][0]} reproduced, {result['best_score'][1]} partly): "
              + ", ".join(f"{k}: **{v}**" for k, v in b["reading"].items()), "",
              "## Every reading", "", "| " + " | ".join(factors + claims) + " |",
              "|" + "---|" * (len(factors) + len(claims))]
    short = {"reproduced": "✔", "partly": "~", "not": "✗"}
    for r in rows:
        lines.append("| " + " | ".join([str(r["reading"][f]) for f in factors]
                                       + [short[r["verdicts"][c]] for c in claims]) + " |")
    lines += ["", "✔ reproduced, ~ partly (direction holds, size does not), ✗ not.", "", "![map](consistency.png)", ""]
    return "\n".join(lines)


def write_consistency_outputs(out_dir: str | Path, result: dict, command: str) -> list:
    """consistency.png/.svg, consistency.json (the result with ``command``) and consistency.md.

    Parameters
    ----------
    out_dir : str or Path
    result : dict
        :func:`run_consistency`'s.
    command : str

    Returns
    -------
    list of Path
        The files written.
    """
    import json
    from pathlib import Path

    from spectracam.core.files import atomic_write
    from spectracam.io.plots import save_figure

    out = Path(out_dir)
    paths = save_figure(consistency_figure(result), out / "consistency.png", out / "consistency.svg")
    paths.append(atomic_write(out / "consistency.json",
                              json.dumps({**result, "command": command}, indent=1, allow_nan=False).encode()))
    paths.append(atomic_write(out / "consistency.md", consistency_markdown(result, command).encode()))
    return paths
