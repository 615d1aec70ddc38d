"""The layout ARCHITECTURE.md describes, checked on the source.

The import graph is built from the source (module-level and function-level
imports alike): it has no cycle; only :mod:`rodcad.cad` imports build123d or OCP;
:mod:`optimize` never imports rodcad (nor the CAD kernel); no module imports another
module's private (``_x``) name; no module is over 600 lines.

The two kinds of structure: a net's modules live in ``net`` packages (no other module's
name starts with ``net``); :mod:`optimize.chain` and :mod:`optimize.net` never import each
other and share only the top-level modules of :mod:`optimize`; a rodcad role's ``net``
subpackage takes nothing chain-only from another role; the chain's and the net's pipelines
never import each other. Every ``rodcad.x.y`` / ``optimize.x`` path ARCHITECTURE.md names
exists.
"""

from __future__ import annotations

import ast
import functools
import re
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


@functools.lru_cache(maxsize=None)
def _imports(name: str, path: Path) -> list[tuple[str, list[str], int]]:
    """(imported module, names imported from it, line) for every import in the file (read
    once per session: several tests walk every module)."""
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


# --------------------------------------------------------------------------- chains and nets

#: The top-level modules of :mod:`optimize` besides its two kinds: what both use.
SHARED_OPTIMIZE = ("optimize.boxqp", "optimize.distance", "optimize.gram", "optimize.validate")

#: rodcad's role packages (each may have a ``net`` subpackage); the other top-level modules
#: and packages (errors, yamlio, yamlspec, parallel, progress, outdir, ...) are shared.
ROLES = ("catalog", "design", "fabrication", "cad", "check", "outputs", "commands", "pipeline")

#: What the net's pipeline takes from a role's modules outside its net subpackage, and why.
#: Modules of a role package that both kinds use (not chain-only), with the reason.
SHARED_ACROSS_KINDS = {
    "rodcad.cad.viewmesh": "the 3D view's coarse meshes of any solid, a chain's or a net's (and where a net's "
                           "solids stand, as assembly.step puts them)",
    "rodcad.outputs.view": "assembly.glb and view.html of every kind of build",
}

PIPELINE_NET_SHARED = {
    **SHARED_ACROSS_KINDS,
    "rodcad.design.model": "the validated design file (Design), of every kind",
    "rodcad.outputs.design_json": "print_profile, the print profile both kinds' masses assume, is the "
                                  "chain's design.json module's (moving it is no part of the layout)",
}


def _in(name: str, package: str) -> bool:
    return name == package or name.startswith(package + ".")


def _is_net(name: str) -> bool:
    return "net" in name.split(".")


def test_only_net_packages_hold_modules_named_net():
    """A net's X is under a ``net`` package: no other module's name starts with "net"."""
    bad = [name for name in MODULES if any(p.startswith("net") and p != "net" for p in name.split("."))]
    assert bad == []


def test_chain_and_net_numerics_share_only_the_top_of_optimize():
    graph = _graph()
    top = {m for m in MODULES if m.count(".") == 1 and m.split(".")[0] == "optimize"}
    assert top == {"optimize.chain", "optimize.net", *SHARED_OPTIMIZE}, "a new top-level optimize module: " \
        "shared by both kinds (add it to SHARED_OPTIMIZE) or one kind's (move it into optimize/chain or optimize/net)"
    bad = []
    for kind, other in (("optimize.chain", "optimize.net"), ("optimize.net", "optimize.chain")):
        for name in (m for m in MODULES if _in(m, kind)):
            bad += [f"{name} -> {t}" for t in sorted(graph[name]) if _in(t, "optimize") and not _in(t, kind)
                    and t not in SHARED_OPTIMIZE and t != "optimize"]
            bad += [f"{name} -> {t} (the package exports both kinds)" for t in graph[name] if t == "optimize"]
    for name in SHARED_OPTIMIZE:
        bad += [f"{name} -> {t}" for t in sorted(graph[name]) if _in(t, "optimize.chain") or _in(t, "optimize.net")]
    assert bad == []


def test_net_subpackages_take_nothing_chain_only_from_another_role():
    """A rodcad role's ``net`` subpackage imports, beyond its own role, only the other roles'
    net subpackages and the role packages themselves, rodcad's shared top-level modules, and
    optimize's public API, its shared modules and :mod:`optimize.net` (never :mod:`optimize.chain`)."""
    graph = _graph()
    bad = []
    for name in sorted(MODULES):
        parts = name.split(".")
        if parts[0] != "rodcad" or len(parts) < 3 or parts[2] != "net" or parts[1] == "pipeline":
            continue
        role = ".".join(parts[:2])
        for t in sorted(graph[name]):
            tp = t.split(".")
            if tp[0] == "optimize":
                ok = not _in(t, "optimize.chain")
            else:
                ok = _is_net(t) or _in(t, role) or len(tp) == 2 or tp[1] not in ROLES or t in SHARED_ACROSS_KINDS
            if not ok:
                bad.append(f"{name} -> {t}")
    assert bad == []


def test_the_chain_and_net_pipelines_never_import_each_other():
    graph = _graph()
    chain_side = ("rodcad.pipeline.chain", "rodcad.pipeline.chandelier")
    bad = [f"{c} -> {t}" for c in chain_side for t in graph[c] if _is_net(t)]
    bad += [f"rodcad.pipeline.net -> {t}" for t in graph["rodcad.pipeline.net"] if _in(t, "optimize.chain")
            or t in chain_side]
    # from the role packages: their net subpackages, the packages themselves and the shared modules named
    for t in sorted(graph["rodcad.pipeline.net"]):
        tp = t.split(".")
        if tp[0] == "rodcad" and len(tp) > 2 and tp[1] in ROLES and tp[1] != "pipeline" and not _is_net(t) \
                and t not in PIPELINE_NET_SHARED:
            bad.append(f"rodcad.pipeline.net -> {t}")
    assert bad == []


#: A dotted path in ARCHITECTURE.md (``rodcad.design.plan``, ``optimize.net.solve``,
#: ``rodcad.design.plan.catalog_arrays``).
DOTTED = re.compile(r"(?<![\w.])(?:rodcad|optimize)(?:\.[A-Za-z_]\w*)+")


def _top_names(path: Path) -> set[str]:
    """Names a module defines or imports at its top level (and its classes' attributes)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    out: set[str] = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            out.add(node.name)
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            out |= {n.id for tg in targets for n in ast.walk(tg) if isinstance(n, ast.Name)}
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            out |= {(a.asname or a.name).split(".")[0] for a in node.names}
    return out


def test_every_path_architecture_md_names_exists():
    """Every ``rodcad.x.y`` / ``optimize.x`` path on the page is a module, or a name its
    longest module prefix defines (a function, class or constant)."""
    text = (ROOT / "ARCHITECTURE.md").read_text(encoding="utf-8")
    bad = []
    for path in sorted(set(DOTTED.findall(text))):
        parts = path.split(".")
        k = max(k for k in range(1, len(parts) + 1) if ".".join(parts[:k]) in MODULES)
        module = ".".join(parts[:k])
        if k < len(parts) and parts[k] not in _top_names(MODULES[module]):
            bad.append(path)
    assert bad == [], f"ARCHITECTURE.md names what the code does not have: {bad}"


def test_the_path_check_finds_a_missing_path():
    assert DOTTED.findall("(`rodcad.design.netplan`, optimize.chain.model.Chain; rodcad)") == [
        "rodcad.design.netplan", "optimize.chain.model.Chain"]
    assert "netplan" not in _top_names(MODULES["rodcad.design"])
    assert "Chain" in _top_names(MODULES["optimize.chain.model"])
