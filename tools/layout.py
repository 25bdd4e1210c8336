"""The package's layout, measured: modules per folder, imports that run back up the stages, import
loops, functions over 60 lines and modules without ``__all__`` (docs/architecture.md).

    python3 tools/layout.py            # the counts, and every offender by name

The stages, lowest first, are :data:`STAGES`: a module may import from its own stage or a lower one,
never a higher one (an import inside a function counts too; one under ``if TYPE_CHECKING:`` does not,
as it never runs).  The package's face, ``spectracam/__init__.py``, re-exports from every stage and is
not a stage.  ``tests/test_layout.py`` holds the tree to these counts.
"""
from __future__ import annotations

import ast
import sys
from collections import Counter
from pathlib import Path

#: The stages in the order data flows through them, lowest first.  An architecture tells the sensor
#: where and when to integrate, so ``sensor`` (the pixel, its noise and the exposure control) sits
#: below ``architecture``; ``camera`` assembles optics, architecture and sensor into one capture.  ``_aliases`` (the
#: old module names, one release) imports nothing of the package by statement: it finds modules by name.
STAGES = ("_version", "_aliases", "core", "scene", "optics", "render", "sensor", "architecture", "camera",
          "processing", "evaluation", "io", "pipeline", "experiments", "view", "cli", "__main__")
#: Longest function allowed outside compiled kernels, lines (the issue's bound).
MAX_FUNCTION_LINES = 60
#: Compiled kernels (numba): one loop each, kept whole so the compiler sees it.
COMPILED = ("spectracam/sensor/_numba_kernels.py", "spectracam/scene/_paint.py")

ROOT = Path(__file__).resolve().parents[1]


def modules(root: Path = ROOT) -> dict[str, Path]:
    """Every module of the package by dotted name."""
    out = {}
    for p in sorted((root / "spectracam").rglob("*.py")):
        parts = list(p.relative_to(root).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = p
    return out


def stage(name: str) -> str | None:
    """The stage of a dotted module name (None for the package's face)."""
    parts = name.split(".")
    return parts[1] if len(parts) > 1 else None


def _is_type_checking(node: ast.If) -> bool:
    t = node.test
    return (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING") or \
        (isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING")


def imports(name: str, path: Path, mods: dict[str, Path]) -> list[tuple[str, int]]:
    """``(imported module, line)`` for every spectracam import that runs, at any depth."""
    ispkg = path.name == "__init__.py"
    found = []

    def resolve(node):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = name.split(".")[: len(name.split(".")) - (node.level - (1 if ispkg else 0))]
                b = ".".join(base + ([node.module] if node.module else []))
            else:
                b = node.module or ""
            return [f"{b}.{a.name}" if f"{b}.{a.name}" in mods else b for a in node.names]
        return [a.name for a in node.names]

    def visit(n):
        for c in ast.iter_child_nodes(n):
            if isinstance(c, ast.If) and _is_type_checking(c):
                for o in c.orelse:
                    visit(o)
                continue
            if isinstance(c, (ast.Import, ast.ImportFrom)):
                for t in resolve(c):
                    while t and t not in mods:
                        t = t.rpartition(".")[0]
                    if t and t != name and t.startswith("spectracam"):
                        found.append((t, c.lineno))
            visit(c)

    visit(ast.parse(path.read_text()))
    return found


def upward_imports(root: Path = ROOT) -> list[str]:
    """Imports from a lower stage to a higher one, as ``module:line -> module``."""
    mods = modules(root)
    out = []
    for name, path in mods.items():
        s = stage(name)
        if s is None:
            continue
        for t, line in imports(name, path, mods):
            ts = stage(t)
            if s not in STAGES or (ts is not None and ts not in STAGES):
                continue  # not placed in a stage (see unplaced()): an earlier release's tree, or a new module
            if ts is None or STAGES.index(ts) > STAGES.index(s):
                out.append(f"{name}:{line} -> {t}")
    return out


def unplaced(root: Path = ROOT) -> list[str]:
    """Modules outside every stage of :data:`STAGES` (a new top-level module or folder must be given one)."""
    return [n for n in modules(root) if stage(n) is not None and stage(n) not in STAGES]


def loops(root: Path = ROOT) -> list[list[str]]:
    """Import loops between modules (strongly connected components of more than one module; a
    package's face importing its own submodules is not a loop unless a submodule imports it back)."""
    mods = modules(root)
    graph = {n: sorted({t for t, _ in imports(n, p, mods)} - {"spectracam"}) for n, p in mods.items()}
    index, low, on, stack, out, counter = {}, {}, set(), [], [], [0]

    def strong(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, []):
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in graph:
        if v not in index:
            strong(v)
    return out


def long_functions(root: Path = ROOT, limit: int = MAX_FUNCTION_LINES) -> list[tuple[str, int]]:
    """``(path:function, lines)`` of every function longer than ``limit`` lines (docstring included)."""
    out = []
    for name, path in modules(root).items():
        rel = str(path.relative_to(root))
        if rel in COMPILED:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1
                if n > limit:
                    out.append((f"{rel}:{node.name}", n))
    return sorted(out, key=lambda x: -x[1])


def without_all(root: Path = ROOT) -> list[str]:
    """Public modules (no leading underscore, not ``__main__``) that define no ``__all__``."""
    out = []
    for name, path in modules(root).items():
        if any(p.startswith("_") and p != "__init__" for p in path.relative_to(root).with_suffix("").parts):
            continue
        tree = ast.parse(path.read_text())
        has = any(isinstance(n, (ast.Assign, ast.AnnAssign)) and any(
            isinstance(t, ast.Name) and t.id == "__all__" for t in (n.targets if isinstance(n, ast.Assign) else [n.target]))
            for n in tree.body)
        if not has:
            out.append(str(path.relative_to(root)))
    return out


def per_folder(root: Path = ROOT) -> Counter:
    """Modules per folder of the package."""
    return Counter(str(p.parent.relative_to(root)) for p in modules(root).values())


def main() -> None:
    root = Path(sys.argv[1]).resolve() if len(sys.argv) > 1 else ROOT
    mods = modules(root)
    print(f"{len(mods)} modules, {sum(len(p.read_text().splitlines()) for p in mods.values())} lines")
    for folder, n in sorted(per_folder(root).items()):
        print(f"  {n:3d}  {folder}/")
    un = unplaced(root)
    print(f"modules in no stage: {len(un)}" + (" (a tree laid out before the stages: the next count is of the "
                                                "placed modules only)" if un else ""))
    up = upward_imports(root)
    print(f"imports running back up the stages: {len(up)}")
    for u in up:
        print("  ", u)
    lp = loops(root)
    print(f"import loops: {len(lp)}")
    for c in lp:
        print("  ", " <-> ".join(c))
    lf = long_functions(root)
    print(f"functions over {MAX_FUNCTION_LINES} lines (compiled kernels aside): {len(lf)}")
    for f, n in lf:
        print(f"  {n:4d}  {f}")
    wa = without_all(root)
    print(f"public modules without __all__: {len(wa)}")


if __name__ == "__main__":
    main()
