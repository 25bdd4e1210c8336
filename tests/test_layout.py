"""The layout of issue 35, held: stages import only downward, no import loops, no function over 60 lines,
``__all__`` in every public module, a command line that only parses, the old module names for one release."""
import importlib
import sys
import textwrap
import warnings
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
import layout  # noqa: E402


def _tree(tmp_path, files: dict) -> Path:
    for name, text in files.items():
        p = tmp_path / "spectracam" / name
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(textwrap.dedent(text))
    return tmp_path


def test_every_module_is_in_a_stage_and_no_import_runs_back_up():
    assert layout.unplaced() == []
    assert layout.upward_imports() == []


def test_the_checker_finds_an_upward_import_and_a_loop_it_is_shown(tmp_path):
    root = _tree(tmp_path, {
        "__init__.py": "",
        "core/__init__.py": "", "core/errors.py": "",
        "scene/__init__.py": "", "scene/chart.py": "def f():\n    from spectracam.evaluation import score\n",
        "evaluation/__init__.py": "", "evaluation/score.py": "from spectracam.scene import chart\n",
        "sensor/__init__.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from spectracam.camera import x\n",
        "camera/__init__.py": "",
    })
    assert layout.upward_imports(root) == ["spectracam.scene.chart:2 -> spectracam.evaluation.score"]
    assert layout.unplaced(root) == []
    (root / "spectracam" / "helpers.py").write_text("")
    assert layout.unplaced(root) == ["spectracam.helpers"]
    assert layout.loops(root) == [["spectracam.evaluation.score", "spectracam.scene.chart"]]


def test_no_import_loops():
    assert layout.loops() == []


def test_no_function_over_60_lines_outside_compiled_kernels():
    assert layout.long_functions() == []


def test_the_checker_counts_a_long_function(tmp_path):
    body = "\n".join(f"    x{i} = {i}" for i in range(60))
    root = _tree(tmp_path, {"__init__.py": "", "core/__init__.py": "", "core/a.py": f"def f():\n{body}\n"})
    assert layout.long_functions(root) == [("spectracam/core/a.py:f", 61)]


def test_every_public_module_says_what_it_exports():
    assert layout.without_all() == []


def test_every_name_in_all_exists():
    missing = []
    for name in layout.modules():
        if name.rsplit(".", 1)[-1].startswith("_") and not name.endswith("__init__"):
            continue
        mod = importlib.import_module(name)
        missing += [f"{name}.{n}" for n in getattr(mod, "__all__", ()) if not hasattr(mod, n)]
    assert missing == []


def test_the_command_line_only_parses():
    assert len((ROOT / "spectracam" / "cli.py").read_text().splitlines()) <= 250


def test_the_package_says_it_is_typed():
    assert (ROOT / "spectracam" / "py.typed").is_file()
    assert "py.typed" in (ROOT / "pyproject.toml").read_text()


def test_an_old_module_name_is_the_new_module_with_a_warning():
    from spectracam import _aliases

    new = importlib.import_module("spectracam.evaluation.heldout")
    sys.modules.pop("spectracam.heldout", None)
    with pytest.warns(DeprecationWarning, match="spectracam.heldout moved to spectracam.evaluation.heldout"):
        old = importlib.import_module("spectracam.heldout")
    assert old is new
    with pytest.warns(DeprecationWarning, match="spectracam.scene.load_scene moved"):
        from spectracam.scene import load_scene
    from spectracam.pipeline.scene_file import load_scene as moved
    assert load_scene is moved
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        for old_name, new_name in _aliases.OLD_MODULES.items():
            assert importlib.import_module(old_name) is importlib.import_module(new_name), old_name


def test_old_names_never_replace_the_faces_functions():
    import spectracam

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        importlib.import_module("spectracam.capture")
        importlib.import_module("spectracam.score")
    assert callable(spectracam.capture) and callable(spectracam.score)
    assert spectracam.score.__module__ == "spectracam.pipeline"
