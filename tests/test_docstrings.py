"""Every public function and method is documented in numpydoc sections and fully typed (issue 39).

Public: a name in a public module's ``__all__`` (the modules tools/mkdocs_hooks.py puts in the API reference), and
the methods, classmethods and staticmethods a public class of spectracam defines itself (not its properties, not its
dunders; an ``__init__`` written by hand is held to the class docstring, numpydoc's place for it; one a dataclass
generates is not).  A name re-exported by several modules is checked once, where it is defined.

Every one is fully annotated (each parameter and the return; ``self``/``cls`` aside).  Each with parameters has a
``Parameters`` (or ``Other Parameters``) section naming every parameter, ``*args``/``**kwargs`` included, and no
parameter the signature lacks, and a ``Returns`` (or ``Yields``) section when it returns a value (its return
annotation is not ``None``).  The sections are read by griffe's numpy parser, the one mkdocstrings renders the API
reference with.
"""
from __future__ import annotations

import ast
import importlib
import inspect
import logging
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
from mkdocs_hooks import public_modules  # noqa: E402

#: Modules whose public functions may still lack their sections and annotations: none since issue 39 finished them.
#: The test fails on a module outside this list with something missing, and on a module in it with nothing left to fix.
NOT_YET: list[str] = []


def _callables():
    """``(defining module, qualified name, function, docstring holder)`` of every public function and method."""
    seen, out = set(), []
    for m in public_modules():
        mod = importlib.import_module(m)
        for name in mod.__all__:
            obj = getattr(mod, name)
            if id(obj) in seen:
                continue
            seen.add(id(obj))
            if inspect.isclass(obj) and obj.__module__.startswith("spectracam"):
                out += _methods(obj)
            elif callable(obj) and getattr(obj, "__module__", "").startswith("spectracam"):
                fn = inspect.unwrap(getattr(obj, "py_func", obj))   # a Numba dispatcher, an lru_cache: the function
                if inspect.isfunction(fn):
                    out.append((fn.__module__, fn.__qualname__, fn, fn.__doc__))
    return out


def _methods(cls):
    out = []
    for name, member in vars(cls).items():
        fn = member.__func__ if isinstance(member, (staticmethod, classmethod)) else member
        if (not inspect.isfunction(fn) or fn.__code__.co_filename == "<string>"    # dataclass-made __init__ etc.
                or not fn.__module__.startswith("spectracam")):                     # a Protocol's __init__
            continue
        if name == "__init__":
            out.append((cls.__module__, fn.__qualname__, fn, f"{cls.__doc__ or ''}\n\n{fn.__doc__ or ''}"))
        elif not name.startswith("_"):   # an override without a docstring has its base's (inspect.getdoc)
            out.append((cls.__module__, fn.__qualname__, fn, inspect.getdoc(getattr(cls, name))))
    return out


def _sections(doc: str) -> dict[str, list[str]]:
    """Section kind -> the names it lists (griffe's numpy parser)."""
    from griffe import Docstring

    logging.getLogger("griffe").setLevel(logging.ERROR)
    out: dict[str, list[str]] = {}
    for s in Docstring(inspect.cleandoc(doc), parser="numpy").parse():
        kind = s.kind.value
        items = s.value if isinstance(s.value, list) else []
        out.setdefault(kind, []).extend(getattr(x, "name", "") for x in items)
    return out


def _returns_value(fn) -> bool:
    ann = inspect.signature(fn).return_annotation
    if ann is not inspect.Signature.empty:
        return ann not in (None, "None", "NoReturn", "typing.NoReturn")
    tree = ast.parse(textwrap.dedent(inspect.getsource(fn)))
    body = tree.body[0]
    nested = {id(n) for f in ast.walk(body) if f is not body and isinstance(f, (ast.FunctionDef, ast.Lambda,
                                                                             ast.AsyncFunctionDef))
              for n in ast.walk(f)}
    return any(isinstance(n, (ast.Yield, ast.YieldFrom)) or (isinstance(n, ast.Return) and n.value is not None)
               for n in ast.walk(body) if id(n) not in nested)


def problems(fn, doc: str | None, is_init: bool = False) -> list[str]:
    """What the function's docstring and annotations lack (empty: nothing)."""
    sig = inspect.signature(fn)
    params = list(sig.parameters.values())
    if params and params[0].name in ("self", "cls") and "." in fn.__qualname__:
        params = params[1:]
    out = []
    unannotated = [p.name for p in params if p.annotation is inspect.Parameter.empty]
    if unannotated:
        out.append(f"parameters without annotation: {unannotated}")
    if not is_init and sig.return_annotation is inspect.Signature.empty:
        out.append("no return annotation")
    if not params:              # no parameters: the summary line says what it gives; annotations only
        return out
    sections = _sections(doc or "")
    documented = {n.lstrip("*") for n in sections.get("parameters", []) + sections.get("other parameters", [])}
    names = {p.name for p in params}
    if names - documented:
        out.append(f"not in a Parameters section: {sorted(names - documented)}")
    if documented - names:
        out.append(f"documented but not parameters: {sorted(documented - names)}")
    if not is_init and _returns_value(fn) and not ({"returns", "yields"} & set(sections)):
        out.append("no Returns section")
    return out


def report() -> dict[str, list[str]]:
    """Defining module -> ``"qualname: problem; problem"`` for every public callable with something missing."""
    out: dict[str, list[str]] = {}
    for module, qualname, fn, doc in _callables():
        p = problems(fn, doc, is_init=qualname.endswith(".__init__"))
        if p:
            out.setdefault(module, []).append(f"{qualname}: {'; '.join(p)}")
    return out


@pytest.fixture(scope="module")
def found():
    return report()


def test_the_checker_sees_what_it_should():
    def good(x: float, *rest: int, scale: float = 1.0) -> float:
        """Scale.

        Parameters
        ----------
        x : float
            A length, m.
        *rest : int
            More.
        scale : float
            The factor.

        Returns
        -------
        float
            ``x`` scaled.
        """
        return x * scale

    def bad(x, y: int):
        """Add."""
        return x + y

    assert problems(good, good.__doc__) == []
    assert problems(bad, bad.__doc__) == ["parameters without annotation: ['x']", "no return annotation",
                                          "not in a Parameters section: ['x', 'y']", "no Returns section"]


def test_every_public_function_has_numpydoc_sections_and_annotations(found):
    n = len(_callables())
    assert n > 900, n                 # 991 when the test was written
    bad = {m: v for m, v in found.items() if m not in NOT_YET}
    assert not bad, "\n".join(f"{m}: {len(v)}\n  " + "\n  ".join(v) for m, v in sorted(bad.items()))


def test_the_list_of_modules_not_yet_done_holds_only_such_modules(found):
    done = [m for m in NOT_YET if m not in found]
    assert not done, f"nothing left to fix in {done}: take them out of NOT_YET"
