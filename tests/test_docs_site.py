"""The documentation site (issue 39): every doctest of the package runs; the site builds from docs/ with MkDocs in
strict mode (a broken link or anchor, an unreadable docstring or a page outside the nav fails it), its API
reference lists every public module and name, the example notebooks are executed into it, and headless Chromium
draws every page with no console error."""
from __future__ import annotations

import doctest
import functools
import http.server
import importlib
import os
import re
import subprocess
import sys
import threading
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
from mkdocs_hooks import public_modules  # noqa: E402

MODULES = public_modules()


def test_the_api_reference_covers_every_public_module():
    names = set(MODULES)
    assert {"spectracam", "spectracam.core.cielab", "spectracam.evaluation.score", "spectracam.sensor.kernels",
            "spectracam.experiments.field.experiment"} <= names
    assert not [m for m in names if any(p.startswith("_") for p in m.split("."))]
    on_disk = {p for p in (ROOT / "spectracam").rglob("*.py") if not any(q.startswith("_") and q != "__init__.py"
                                                                          for q in p.relative_to(ROOT).parts)}
    assert len(names) == len(on_disk)


@pytest.mark.parametrize("module", MODULES)
def test_doctests(module, monkeypatch, tmp_path):
    """Every ``>>>`` example in the package's docstrings, run from an empty directory (94 examples)."""
    monkeypatch.chdir(tmp_path)
    mod = importlib.import_module(module)
    result = doctest.testmod(mod, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE, report=False)
    assert result.failed == 0, f"{module}: {result.failed} of {result.attempted} examples failed (python -m doctest)"


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    pytest.importorskip("mkdocs", reason="MkDocs is not installed (tools/setup.sh --docs or --test)")
    pytest.importorskip("mkdocstrings", reason="mkdocstrings is not installed (tools/setup.sh --docs or --test)")
    out = tmp_path_factory.mktemp("site")
    r = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-d", str(out)], cwd=ROOT,
                       capture_output=True, text=True, timeout=600,
                       env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
    assert r.returncode == 0, r.stderr[-3000:]
    return out


@pytest.mark.slow
def test_the_site_builds_strictly_with_every_public_name(site):
    pages = sorted(site.rglob("*.html"))
    assert len(pages) >= len(MODULES) + 20
    for m in MODULES:
        assert (site / "api" / f"{m}.html").is_file(), m
    # every name in a module's __all__ has its own entry on the module's page
    for m in ("spectracam.core.cielab", "spectracam.evaluation.score", "spectracam.processing.color"):
        html = (site / "api" / f"{m}.html").read_text()
        for name in importlib.import_module(m).__all__:
            assert re.search(rf'id="{re.escape(m)}\.{re.escape(name)}"', html), (m, name)
    guide = (site / "guide" / "paper.html").read_text()
    assert "Figure 6" in guide and "../fig4.png" in guide


@pytest.fixture(scope="module")
def served(site):
    """The built site on a loopback HTTP server (the search index is fetched, which file:// forbids)."""
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(site))
    handler.log_message = lambda *a, **k: None
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    yield f"http://127.0.0.1:{server.server_address[1]}"
    server.shutdown()


@pytest.mark.slow
def test_chromium_draws_every_page(site, served, browser):
    bad = []
    for page in sorted(site.rglob("*.html")):
        rel = page.relative_to(site).as_posix()
        browser.get_log("browser")
        browser.get(f"{served}/{rel}")
        title = browser.execute_script("const h = document.querySelector('article h1, h1'); "
                                       "return h ? h.textContent.trim() : ''")
        height = browser.execute_script("return document.body.scrollHeight")
        errors = [e["message"] for e in browser.get_log("browser") if e["level"] == "SEVERE"]
        broken = browser.execute_script("return [...document.images].filter(i => i.complete && !i.naturalWidth)"
                                        ".map(i => i.src)")
        if rel != "404.html" and (not title or height < 300 or errors or broken):
            bad.append((rel, title, height, errors[:2], broken[:2]))
    assert not bad, bad[:5]


@pytest.mark.slow
def test_every_notebook_is_a_page_drawn_with_its_figures_and_no_error(site, served, browser):
    """examples/*.ipynb executed into the site (tools/mkdocs_notebooks.py): a page per notebook in the nav, its
    figures drawn by Chromium, its outputs there and no error output."""
    notebooks = sorted(p.stem for p in (ROOT / "examples").glob("*.ipynb"))
    assert len(notebooks) == 3
    index = (site / "examples" / "index.html").read_text()
    for stem in notebooks:
        html = (site / "examples" / f"{stem}.html").read_text()
        assert f'href="{stem}.html"' in index and f'href="{stem}.ipynb"' in html, stem
        assert (site / "examples" / f"{stem}.ipynb").read_bytes() == (ROOT / "examples" / f"{stem}.ipynb").read_bytes()
        assert "nb-stdout" in html and "nb-result" in html and "<span class=\"kn\">import</span>" in html, stem
        assert "nb-error" not in html and "nb-stderr" not in html and "Traceback" not in html, stem
        browser.get(f"{served}/examples/{stem}.html")
        drawn = browser.execute_script(
            "return [...document.querySelectorAll('article img')].filter(i => i.src.includes('/examples/"
            f"{stem}/cell')).map(i => i.complete ? i.naturalWidth : 0)")
        assert drawn and all(w > 100 for w in drawn), (stem, drawn)
        errors = browser.execute_script("return document.querySelectorAll('.nb-error, .nb-stderr').length")
        assert errors == 0, stem
    # the numbers are the notebook's own: the paper's 28 ms at 5000 K, as compare_architectures prints it
    assert "cfa/single at 5000 K: 28.0 ms" in (site / "examples" / "compare_architectures.html").read_text()


def test_the_readme_is_a_front_page_whose_links_resolve():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 200
    links = re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", text)
    assert len(links) >= 20
    missing = [link for link in links if "://" not in link and not (ROOT / link).exists()]
    assert not missing, missing
    for command in ("bash tools/setup.sh && .venv/bin/python -m spectracam paper -o out/paper",
                    "bash tools/setup.sh --test && .venv/bin/python -m pytest -q", 'pytest -q -m "not slow"',
                    "mkdocs build --strict"):
        assert command in text, command
