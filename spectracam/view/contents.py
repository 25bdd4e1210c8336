"""What an output directory holds, found by what spectracam writes: cases (radiance.exr, raw.exr and
rendered.exr of one shot, together in a directory, or a lone rendering such as spatial's
``cases/<size>/<target>/<design>.exr``), figures (PNG, GIF), reports (report.md, report.json,
results.json, report.csv, results.parquet) and the parameters that made them."""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

from spectracam.core.errors import SpectracamError

__all__ = ["MAX_CASES", "MAX_FIGURES", "SHOT_FILES", "Contents", "find_contents"]

#: The files of one shot, by role.
SHOT_FILES = {"radiance": "radiance.exr", "raw": "raw.exr", "rendered": "rendered.exr"}
#: Interactive cases one page carries at most (the rest are listed; their figures are still shown).
MAX_CASES = 48
#: Figures one page embeds at most (the rest are listed by name).
MAX_FIGURES = 400


@dataclass
class Contents:
    directory: Path
    kind: str = ""                                   # simulate, paper, spatial, … (a guess named on the page)
    cases: list = field(default_factory=list)        # (name, {role: Path})
    more_cases: list = field(default_factory=list)   # names beyond MAX_CASES
    figures: list = field(default_factory=list)      # Paths of PNG/GIF
    more_figures: list = field(default_factory=list)
    markdown: list = field(default_factory=list)     # report.md files, and the top level's .md (datasheet.md)
    json_files: list = field(default_factory=list)   # report.json / results.json, and the top level's .json
    tables: list = field(default_factory=list)       # report.csv, results.parquet
    parameters: dict | None = None


def _kind_of(d: Path, results: dict | None) -> str:
    names = {p.name for p in d.iterdir()}
    if results and isinstance(results.get("experiment"), str):
        return results["experiment"]
    for kind, marker in (("paper", "fig4.png"), ("spatial", "mtf.png"), ("motion", "breakup_scielab.png"),
                         ("architectures", "architectures.png"), ("design", "curves.png"),
                         ("consistency", "consistency.png"), ("sweep", "results.parquet"),
                         ("emva", "emva.json")):
        if marker in names:
            return kind
    if {"radiance.exr", "raw.exr", "rendered.exr"} <= names:
        return "simulate"
    for kind, marker in (("render", "radiance.exr"), ("capture", "raw.exr"), ("score", "rendered.exr")):
        if marker in names:
            return kind
    return "output"


def _is_rendering(path: Path) -> bool:
    """Is ``path`` an EXR spectracam wrote (its header says, the pixels are not read)?"""
    from spectracam.io.exr import read_exr_header

    try:
        return read_exr_header(path).get("spectracamKind") in ("rendered", "raw", "radiance")
    except SpectracamError:  # an unreadable or foreign EXR is simply not a case
        return False


def find_contents(directory: Path) -> Contents:
    """Everything the page can show in ``directory`` (one clear line when it is not one to show).

    Parameters
    ----------
    directory : Path
        An output directory a spectracam command wrote.

    Returns
    -------
    Contents
        Its cases (shots with their EXR files), figures, reports, tables and JSON files, and which command wrote it.

    Raises
    ------
    SpectracamError
        A directory that does not exist, is a file, cannot be read, holds a damaged top-level JSON file or nothing
        spectracam wrote.
    """
    d = Path(directory)
    if not d.exists():
        raise SpectracamError(f"directory = {str(d)!r}: does not exist")
    if not d.is_dir():
        raise SpectracamError(f"directory = {str(d)!r}: is a file; give the output directory a command wrote")
    c = Contents(directory=d)
    try:
        files = sorted(p for p in d.rglob("*") if p.is_file() and p.name != "index.html"
                       and not any(part.startswith(".") for part in p.relative_to(d).parts))
    except OSError as e:
        raise SpectracamError(f"directory = {str(d)!r}: cannot be read ({e.strerror})") from None
    shots = _sort_files(files, d, c)
    # a sweep writes results.csv beside results.parquet: one table
    c.tables = [t for t in c.tables if not (t.suffix == ".csv" and t.with_suffix(".parquet") in c.tables)]
    ordered = sorted(shots.items(), key=lambda kv: (len(kv[0].relative_to(d).parts), str(kv[0])))
    names = [(str(k.relative_to(d)) if k != d else ".", v) for k, v in ordered]
    c.cases, c.more_cases = names[:MAX_CASES], [n for n, _ in names[MAX_CASES:]]
    c.figures, c.more_figures = c.figures[:MAX_FIGURES], c.figures[MAX_FIGURES:]
    results = _top_results(c, d)
    c.kind = _kind_of(d, results if isinstance(results, dict) else None)
    # figures and tables alone (any PNG or CSV) are not enough: spectracam's EXR files, reports or results
    if not (c.cases or c.markdown or c.json_files or any(t.suffix == ".parquet" for t in c.tables)):
        raise SpectracamError(f"directory = {str(d)!r}: holds nothing spectracam wrote (no spectracam EXR, report or "
                              "results file)")
    return c


def _sort_files(files: list[Path], d: Path, c: Contents) -> dict[Path, dict]:
    """Each file of ``d`` into ``c``'s figures, markdown, JSON files and tables; returns the shots: directory (or a
    rendering's path without its suffix) → role → EXR file."""
    shots: dict[Path, dict] = {}
    for p in files:
        rel = p.relative_to(d)
        if p.name in SHOT_FILES.values():
            role = next(k for k, v in SHOT_FILES.items() if v == p.name)
            shots.setdefault(p.parent, {})[role] = p
        elif p.suffix.lower() == ".exr" and _is_rendering(p):
            shots[p.with_suffix("")] = {"rendered": p}
        elif p.suffix.lower() in (".png", ".gif"):
            c.figures.append(p)
        elif p.name == "report.md" or (p.suffix == ".md" and len(rel.parts) == 1):
            c.markdown.append(p)
        elif p.name in ("report.json", "results.json") or (p.suffix == ".json" and len(rel.parts) == 1):
            c.json_files.append(p)
        elif p.name in ("report.csv", "results.parquet") or (p.suffix == ".csv" and len(rel.parts) == 1):
            c.tables.append(p)
    return shots


def _top_results(c: Contents, d: Path) -> object:
    """The last top-level JSON file's content (None without one), its ``parameters`` into ``c``; a damaged file, or
    a report.json that is not an object, refused in one line."""
    results = None
    for p in c.json_files:
        if p.parent == d:
            try:
                results = json.loads(p.read_text())
            except (OSError, ValueError) as e:
                raise SpectracamError(f"file = {str(p)!r}: is not JSON ({e})") from None
            if p.name == "report.json" and not isinstance(results, dict):   # the page reads its tables by name
                kind = {list: "an array", str: "a string", bool: "a boolean", type(None): "null"}.get(type(results),
                                                                                                    "a number")
                raise SpectracamError(f"file = {str(p)!r}: is not a spectracam report (a JSON object of tables is "
                                      f"expected; this file holds {kind})")
            if isinstance(results, dict):
                c.parameters = results.get("parameters") or c.parameters
    return results
