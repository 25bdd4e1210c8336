"""MkDocs hook (mkdocs.yml ``hooks``): the API reference's pages, one per public module of spectracam, generated at
build time so that it always lists every public name (a module's ``__all__``, which tests/test_layout.py requires).

Each page is ``::: spectracam.<module>`` for mkdocstrings, which reads the numpydoc docstrings statically (griffe);
``api/index.md`` lists the modules stage by stage.  Nothing is written into docs/.

The example notebooks (examples/*.ipynb, committed without outputs) enter the site as executed pages under
"Examples": :mod:`mkdocs_notebooks` (beside this file) executes each with nbclient and writes it as Markdown with its
figures beside it.  Why not mkdocs-jupyter: it would be one more dependency (with nbconvert, and through it
jupyterlab-pygments, bleach, mistune ...) for what nbclient, nbformat and ipykernel already do here -- the example
tests run the notebooks with them -- plus a 100-line converter; and the pages stay ordinary Markdown, so the strict
build checks their links and images like every other page's.
"""
from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(Path(__file__).resolve().parent))
import mkdocs_notebooks  # noqa: E402
#: The stages in the order data flows through them (docs/architecture.md), then the rest.
STAGES = ["core", "scene", "optics", "render", "sensor", "architecture", "camera", "processing", "evaluation", "io",
          "pipeline", "view", "experiments"]


def public_modules() -> list[str]:
    """Every public module of the package: no part of its dotted name starts with ``_`` (``__init__`` names its
    package), in stage order."""
    out = []
    for path in sorted((ROOT / "spectracam").rglob("*.py")):
        parts = list(path.relative_to(ROOT).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        if any(p.startswith("_") for p in parts) or "__pycache__" in path.parts:
            continue
        out.append(".".join(parts))

    def order(name: str):
        stage = name.split(".")[1] if "." in name else ""
        return (STAGES.index(stage) if stage in STAGES else (-1 if not stage else len(STAGES)), name)

    return sorted(out, key=order)


def _index(modules: list[str]) -> str:
    lines = ["# API reference", "",
             "Every public module of spectracam, stage by stage in the order data flows (see "
             "[Architecture](../architecture.md)); each page lists the module's public names (its `__all__`) with "
             "their docstrings.  The package itself (`spectracam`) is the front door: `load_scene`, `render`, "
             "`capture`, `score`.", ""]
    stage = None
    for m in modules:
        s = m.split(".")[1] if "." in m else "spectracam"
        if s != stage:
            lines += ["", f"## {s}", ""]
            stage = s
        lines.append(f"- [`{m}`]({m}.md)")
    return "\n".join(lines) + "\n"


def on_config(config):
    """The API pages enter the nav under "API reference" (after its index), and the executed notebooks under
    "Examples" (after theirs), so the strict build also holds every page to be reachable."""
    for item in config["nav"]:
        if isinstance(item, dict) and "API reference" in item:
            item["API reference"] = ["api/index.md"] + [{m: f"api/{m}.md"} for m in public_modules()]
        if isinstance(item, dict) and "Examples" in item:
            item["Examples"] = ["examples/index.md"] + [f"examples/{nb.stem}.md" for nb in mkdocs_notebooks.notebooks()]
    return config


def on_files(files, config):
    from mkdocs.structure.files import File

    modules = public_modules()
    files.append(File.generated(config, "api/index.md", content=_index(modules)))
    for m in modules:
        files.append(File.generated(config, f"api/{m}.md", content=f"# `{m}`\n\n::: {m}\n"))
    for uri, content in mkdocs_notebooks.site_files():
        files.append(File.generated(config, uri, content=content))
    return files
