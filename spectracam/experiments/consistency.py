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

import numpy as np

from ..camera import CameraSpec
from ..color import ProcessingSpec
from .claims import evaluate
from .paper import PaperExperiment, calibrated_luminance, comparison, scenes_for

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


def run_consistency(exp: PaperExperiment, renderer: str = "analytic", quick: bool = True, log=lambda m: None) -> dict:
    """Every reading's claims.  Radiance is rendered once per wavelength grid and scaled to each
    reading's calibrated light level (rendering is linear in the light)."""
    from ..render import render
    from ..scene import parse_grid

    t0 = time.perf_counter()
    cube_sets: dict = {}
    rows = []
    for i, reading in enumerate(readings()):
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
            "claims": claim_ids, "rows": rows, "summary": summary, "best": best,
            "best_score": list(score(rows[best])), "seconds": time.perf_counter() - t0}


VERDICT_VALUE = {"reproduced": 2, "partly": 1, "not": 0}


def consistency_figure(result: dict):
    """A map: one row per reading, one column per claim, coloured by verdict."""
    from matplotlib.colors import ListedColormap

    from ..io.plots import pyplot

    plt = pyplot()
    rows, claims = result["rows"], result["claims"]
    M = np.array([[VERDICT_VALUE[r["verdicts"][c]] for c in claims] for r in rows])
    labels = [", ".join(str(v) for v in r["reading"].values()) for r in rows]
    fig, ax = plt.subplots(figsize=(9.5, 0.16 * len(rows) + 2.2))
    cmap = ListedColormap(["#d9d9d9", "#9ecae1", "#2171b5"])
    ax.imshow(M, cmap=cmap, vmin=0, vmax=2, aspect="auto", interpolation="nearest")
    ax.set_xticks(range(len(claims)), claims, rotation=45, ha="right", fontsize=7)
    ax.set_yticks(range(len(rows)), labels, fontsize=5)
    b = result["best"]
    ax.add_patch(plt.Rectangle((-0.5, -0.5), len(claims), 1, fill=False, ec="black", lw=1.5))
    ax.add_patch(plt.Rectangle((-0.5, b - 0.5), len(claims), 1, fill=False, ec="tab:red", lw=1.5, ls="--"))
    handles = [plt.Rectangle((0, 0), 1, 1, color=cmap(i)) for i in (2, 1, 0)]
    handles += [plt.Rectangle((0, 0), 1, 1, fill=False, ec="black"), plt.Rectangle((0, 0), 1, 1, fill=False,
                                                                                    ec="tab:red", ls="--")]
    ax.legend(handles, ["reproduced", "partly", "not", "the experiment's reading", "most claims reproduced"],
              loc="upper left", bbox_to_anchor=(1.01, 1), fontsize=7, title="verdict", title_fontsize=7)
    ax.set_title("The paper's claims under each reading of its open choices\n"
                 "QE, FPN < 1 %, FPN across channels, ADC at code 0; then one choice at a time", fontsize=8)
    fig.tight_layout()
    return fig


def consistency_markdown(result: dict, command: str) -> str:
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


def write_consistency_outputs(out_dir, result: dict, command: str) -> list:
    import json
    from pathlib import Path

    from ..io.files import atomic_write
    from ..io.plots import save_figure

    out = Path(out_dir)
    paths = save_figure(consistency_figure(result), out / "consistency.png", out / "consistency.svg", dpi=130)
    paths.append(atomic_write(out / "consistency.json",
                              json.dumps({**result, "command": command}, indent=1, allow_nan=False).encode()))
    paths.append(atomic_write(out / "consistency.md", consistency_markdown(result, command).encode()))
    return paths
