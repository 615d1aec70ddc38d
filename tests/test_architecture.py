"""The layout ARCHITECTURE.md describes, checked on the source.

The import graph is built from the source (module-level and function-level
imports alike): it has no cycle; only :mod:`rodcad.cad` imports build123d or OCP;
:mod:`optimize` never imports rodcad (nor the CAD kernel); no module imports another
module's private (``_x``) name; no module is over 600 lines.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("rodcad", "optimize")
MAX_LINES = 600
CAD_KERNEL = ("build123d", "OCP")


def _modules() -> dict[str, Path]:
    out = {}
    for pkg in PACKAGES:
        for path in sorted((ROOT / pkg).rglob("*.py")):
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(parts)] = path
    return out


MODULES = _modules()


def _imports(name: str, path: Path) -> list[tuple[str, list[str], int]]:
    """(imported module, names imported from it, line) for every import in the file."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    is_pkg = path.name == "__init__.py"
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(a.name, [], node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                here = name.split(".") if is_pkg else name.split(".")[:-1]
                here = here[: len(here) - (node.level - 1)]
                base = ".".join(here + ([base] if base else []))
            names = [a.name for a in node.names]
            out.append((base, names, node.lineno))
            # `from pkg import submodule` imports the submodule
            out += [(f"{base}.{n}", [], node.lineno) for n in names if f"{base}.{n}" in MODULES]
    return out


def _graph() -> dict[str, set[str]]:
    graph: dict[str, set[str]] = {m: set() for m in MODULES}
    for name, path in MODULES.items():
        for target, _, _ in _imports(name, path):
            # importing a.b.c runs a and a.b first
            parts = target.split(".")
            for k in range(1, len(parts) + 1):
                t = ".".join(parts[:k])
                if t in MODULES and t != name and not name.startswith(t + "."):
                    graph[name].add(t)
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
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

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_the_import_graph_has_no_cycle():
    assert _cycles(_graph()) == []


def test_the_cycle_finder_finds_a_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_only_the_cad_package_imports_the_cad_kernel():
    bad = [f"{name}:{line}: {target}" for name, path in MODULES.items() if not name.startswith("rodcad.cad")
           for target, _, line in _imports(name, path) if target.split(".")[0] in CAD_KERNEL]
    assert bad == []


def test_optimize_never_imports_rodcad():
    bad = [f"{name}:{line}: {target}" for name, path in MODULES.items() if name.split(".")[0] == "optimize"
           for target, _, line in _imports(name, path) if target.split(".")[0] == "rodcad"]
    assert bad == []


def test_no_private_name_crosses_a_module_border():
    bad = [f"{name}:{line}: from {target} import {n}" for name, path in MODULES.items()
           for target, names, line in _imports(name, path)
           for n in names if n.startswith("_") and not n.startswith("__") and target.split(".")[0] in PACKAGES]
    assert bad == []


@pytest.mark.parametrize("name", sorted(MODULES))
def test_module_size(name):
    lines = MODULES[name].read_text(encoding="utf-8").count("\n")
    assert lines <= MAX_LINES, f"{name} has {lines} lines: it has two roles, split it"
