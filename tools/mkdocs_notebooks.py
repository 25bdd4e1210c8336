"""The example notebooks as pages of the documentation site (issue 39), for tools/mkdocs_hooks.py.

Each ``examples/<name>.ipynb`` (committed without outputs) is executed with nbclient in a Jupyter kernel of the
interpreter that builds the site, importing this checkout's package, from a temporary directory (so it writes nothing
into the checkout), and becomes ``examples/<name>.md``: markdown cells as they are, code cells as fenced Python, each
output after its cell -- text as a fenced block (class ``nb-stdout``, ``nb-stderr``, ``nb-result``; an error would be
``nb-error``, but a cell that raises fails the build instead), ``text/markdown`` as Markdown (the notebooks' tables),
figures (``image/png``) as files beside the page, ``examples/<name>/cell<i>-<k>.png``.  ``examples/index.md`` lists
them, and the notebook itself is offered for download.

Executing the three takes about a minute (they use 160x120-pixel scenes and the analytic renderer, their smallest
settings), so the executed notebook is cached under ``$XDG_CACHE_HOME/spectracam/notebooks`` (``~/.cache/...``),
keyed on the notebook's bytes *and* on the package's sources, scene files and data: a rebuild re-runs nothing, and a
page never shows what an older library computed.  Why a converter of our own and not mkdocs-jupyter: see
tools/mkdocs_hooks.py.
"""
from __future__ import annotations

import contextlib
import hashlib
import html
import json
import logging
import os
import re
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
log = logging.getLogger("mkdocs.hooks.notebooks")
#: Seconds a cell may run before the build fails.
CELL_TIMEOUT_S = 600
_ANSI = re.compile(r"\x1b\[[0-9;]*[A-Za-z]")


#: The order of the nav (docs/guide/getting-started.md's): the tour of one capture first; a notebook not named here
#: follows, by name.
ORDER = ["simulate_and_look", "compare_architectures", "own_camera"]


def notebooks() -> list[Path]:
    """The example notebooks, in :data:`ORDER`."""
    return sorted(EXAMPLES.glob("*.ipynb"), key=lambda p: (ORDER.index(p.stem) if p.stem in ORDER else len(ORDER),
                                                           p.stem))


def cache_dir() -> Path:
    """Where executed notebooks are kept: ``$XDG_CACHE_HOME/spectracam/notebooks``, else ``~/.cache/...``."""
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "spectracam" / "notebooks"


def library_digest() -> str:
    """SHA-256 over what a notebook's outputs depend on besides its own text: the package's Python sources, its data
    and the scene files (paths and bytes, in order)."""
    h = hashlib.sha256()
    files = [*(ROOT / "spectracam").rglob("*.py"), *(ROOT / "spectracam" / "data").rglob("*"), *(ROOT / "scenes").rglob("*")]
    for p in sorted(f for f in files if f.is_file() and "__pycache__" not in f.parts):
        h.update(str(p.relative_to(ROOT)).encode() + b"\0" + p.read_bytes() + b"\0")
    return h.hexdigest()


@contextlib.contextmanager
def _this_interpreter_as_python3(tmp: Path):
    """Kernel ``python3`` is this interpreter while the block runs (a kernelspec in a temporary JUPYTER_PATH, which
    comes before the user's and the system's)."""
    spec = tmp / "jupyter" / "kernels" / "python3"
    spec.mkdir(parents=True)
    (spec / "kernel.json").write_text(json.dumps({
        "argv": [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"],
        "display_name": "Python 3 (the site's build)", "language": "python"}))
    old = os.environ.get("JUPYTER_PATH")
    os.environ["JUPYTER_PATH"] = os.pathsep.join(filter(None, [str(tmp / "jupyter"), old]))
    try:
        yield
    finally:
        if old is None:
            os.environ.pop("JUPYTER_PATH", None)
        else:
            os.environ["JUPYTER_PATH"] = old


def execute(path: Path):
    """The notebook at ``path`` executed (an ``nbformat.NotebookNode``, outputs included; its execution time in
    ``metadata.spectracam_docs.seconds``), from the cache when it holds this notebook for this library."""
    try:
        import nbclient
        import nbformat
    except ImportError as e:
        raise SystemExit(f"the site executes examples/*.ipynb and needs nbclient, nbformat and ipykernel ({e}); "
                         "install them with `bash tools/setup.sh --docs`") from e
    key = hashlib.sha256(path.read_bytes() + library_digest().encode()).hexdigest()[:20]
    cached = cache_dir() / f"{path.stem}-{key}.ipynb"
    if cached.is_file():
        log.info("examples/%s: executed output from the cache (%s)", path.name, cached)
        return nbformat.read(cached, as_version=4)
    nb = nbformat.read(path, as_version=4)
    with tempfile.TemporaryDirectory(prefix="spectracam-docs-") as tmp, _this_interpreter_as_python3(Path(tmp)):
        work = Path(tmp) / "cwd"
        work.mkdir()
        env = {**os.environ, "TMPDIR": tmp, "PYTHONFAULTHANDLER": "1",   # a crashed kernel prints its stack
               "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}  # this checkout's
        t = time.perf_counter()
        nb = _run(nbclient, nb, path, work, env)
        seconds = time.perf_counter() - t
    log.info("examples/%s: executed in %.1f s", path.name, seconds)
    nb.metadata["spectracam_docs"] = {"seconds": round(seconds, 1), "key": key}
    cached.parent.mkdir(parents=True, exist_ok=True)
    for old in cached.parent.glob(f"{path.stem}-*.ipynb"):
        old.unlink()
    part = cached.with_suffix(".part")
    nbformat.write(nb, part)
    part.replace(cached)
    return nb


def _run(nbclient, nb, path: Path, work: Path, env: dict):
    """``nb`` executed in a new kernel (a copy; the kernel's log at ERROR: it warns on every start that its loopback
    TCP is unencrypted).  A cell's error stops the build with that error; a kernel that dies (its process ended:
    killed, out of memory or crashed, its stack on stderr) is started once more on a fresh copy, and a second death
    stops the build (a CI run of the test suite saw one death of own_camera.ipynb's kernel, never repeated here)."""
    import copy

    for attempt in (1, 2):
        run = copy.deepcopy(nb)
        try:
            nbclient.NotebookClient(run, kernel_name="python3", timeout=CELL_TIMEOUT_S,
                                    extra_arguments=["--IPKernelApp.log_level=ERROR"],
                                    resources={"metadata": {"path": str(work)}}).execute(env=env)
            return run
        except nbclient.exceptions.CellExecutionError as e:
            raise SystemExit(f"examples/{path.name} failed while the site was built:\n{_ANSI.sub('', str(e))}") from e
        except nbclient.exceptions.DeadKernelError as e:
            if attempt == 2:
                raise SystemExit(f"examples/{path.name}: its Jupyter kernel died twice while the site was built "
                                 "(its stack, if it crashed, is on stderr above)") from e
            log.info("examples/%s: its Jupyter kernel died (its stack, if it crashed, is on stderr); executed once "
                     "more", path.name)
    raise AssertionError("unreachable")


def _fence(text: str, cls: str) -> str:
    """``text`` in a fenced block longer than any run of backticks inside it, with class ``cls``."""
    ticks = "`" * max(3, 1 + max((len(m) for m in re.findall(r"`+", text)), default=0))
    lang = "python" if cls == "python" else f"{{.text .{cls}}}"
    return f"{ticks}{lang}\n{_ANSI.sub('', text).rstrip()}\n{ticks}"


def _outputs(cell, index: int, stem: str, images: dict[str, bytes]) -> list[str]:
    """Markdown for a code cell's outputs; figures go into ``images`` (site path -> PNG bytes)."""
    import base64

    out = []
    for k, o in enumerate(cell.get("outputs", [])):
        kind = o["output_type"]
        if kind == "stream":
            out.append(_fence(o["text"], f"nb-{o['name']}"))
        elif kind == "error":
            out.append(_fence("\n".join(o["traceback"]), "nb-error"))
        elif "image/png" in o["data"]:
            name = f"{stem}/cell{index}-{k}.png"
            images[f"examples/{name}"] = base64.b64decode(o["data"]["image/png"])
            out.append(f"![the figure cell {index} draws]({name})")
        elif "text/markdown" in o["data"]:
            out.append(o["data"]["text/markdown"])
        elif "text/plain" in o["data"]:
            out.append(_fence(o["data"]["text/plain"], "nb-result"))
    return out


def to_markdown(nb, stem: str) -> tuple[str, dict[str, bytes]]:
    """An executed notebook as a Markdown page and its figures (site path -> PNG bytes)."""
    images: dict[str, bytes] = {}
    blocks = []
    seconds = nb.metadata.get("spectracam_docs", {}).get("seconds")
    for i, cell in enumerate(nb.cells):
        if cell.cell_type == "markdown":
            blocks.append(cell.source)
        elif cell.cell_type == "code":
            blocks.append(_fence(cell.source, "python"))
            blocks += _outputs(cell, i, stem, images)
        if i == 0:
            blocks.append(f"*This page is [`{stem}.ipynb`]({stem}.ipynb) (examples/ in the repository), executed when "
                          f"the site was built{f', in {seconds:.0f} s' if seconds else ''}.*")
    return "\n\n".join(blocks) + "\n", images


def _title(path: Path) -> str:
    first = json.loads(path.read_text(encoding="utf-8"))["cells"][0]
    m = re.search(r"^# (.+)$", "".join(first["source"]), re.M)
    return m.group(1).strip() if m else path.stem


def site_files() -> list[tuple[str, str | bytes]]:
    """``(site path, content)`` of every generated file: the index, each executed page, its figures and the notebook
    itself."""
    files: list[tuple[str, str | bytes]] = []
    index = ["# Examples", "", "The Jupyter notebooks of the repository's `examples/`, executed when this site was "
             "built (tests/test_examples.py holds the numbers each computes to the library's own).  To run them "
             "yourself, install a front end into the environment (`.venv/bin/pip install jupyterlab`), then run "
             "`.venv/bin/jupyter lab examples/`; each page offers its notebook for download.", ""]
    for path in notebooks():
        page, images = to_markdown(execute(path), path.stem)
        files += [(f"examples/{path.stem}.md", page), (f"examples/{path.name}", path.read_bytes()),
                  *images.items()]
        index.append(f"- [{html.escape(_title(path), quote=False)}]({path.stem}.md)")
    return [("examples/index.md", "\n".join(index) + "\n"), *files]
