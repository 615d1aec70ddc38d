"""rodcad: computational design and fabrication of hanging rod chains and nets.

The numerics live in the sibling package :mod:`optimize` (numpy/scipy only); this package
owns YAML input, rod catalogs, planning, CAD, export, reports and the CLI.

From Python (the same functions the command line calls)::

    import rodcad

    design = rodcad.load("examples/semicircle.yaml")            # or rodcad.design_from({...})
    result = rodcad.build(design, cad=False)                   # a chain, chandelier or net
    print(result.ok, result.equilibrium.points)                # the hanging shape (mm)
    data = rodcad.write(result, "outputs/semicircle")          # design.json, report.md, views
    run = rodcad.run(design, "outputs/semicircle")             # build + write, as `rodcad build`

Names (imported when first used, so ``import rodcad`` stays light): :func:`load`,
:func:`design_from`, :func:`build`, :func:`write`, :func:`run`, :func:`kind_of`; the types
``Design``, ``BuildResult``, ``ChandelierBuild``, ``NetBuild``, ``Run``; the errors
``InputError`` (bad input, exit 2) and ``DesignLimit`` (what the catalog cannot do, exit 1).
"""

from __future__ import annotations

from importlib import import_module
from pathlib import Path
from typing import Any

__version__ = "0.1.0"

__all__ = ["BuildResult", "ChandelierBuild", "Design", "DesignLimit", "InputError", "NetBuild", "Run", "build",
           "design_from", "kind_of", "load", "run", "write"]

_LAZY = {
    "Design": ("rodcad.design.model", "Design"),
    "BuildResult": ("rodcad.results", "BuildResult"),
    "ChandelierBuild": ("rodcad.results", "ChandelierBuild"),
    "NetBuild": ("rodcad.pipeline.net", "NetBuild"),
    "Run": ("rodcad.pipeline.kinds", "Run"),
    "run": ("rodcad.pipeline.kinds", "run"),
    "kind_of": ("rodcad.pipeline.kinds", "kind_of"),
    "InputError": ("rodcad.errors", "InputError"),
    "DesignLimit": ("rodcad.errors", "DesignLimit"),
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        module, attr = _LAZY[name]
        return getattr(import_module(module), attr)
    raise AttributeError(f"module 'rodcad' has no attribute {name!r}")


def load(path: str | Path):
    """The design file at ``path``, validated (its catalog loaded, its target built).

    Raises:
        InputError: every problem, as ``FILE:LINE:COL: key.path: message``.
    """
    from rodcad.design.loader import load_design

    return load_design(path)


def design_from(data: dict[str, Any] | str, *, name: str = "design.yaml", folder: str | Path = "."):
    """A design from Python objects: ``data`` is what a design file holds, as a dict (or its
    YAML text); relative paths in it (a catalog file) are taken from ``folder``. Problems
    name ``folder/name`` and the line of the YAML the dict is written as.

    Example: ``rodcad.design_from({"design": 1, "name": "arc", "anchors": [[0, 0], [200, 0]],
    "target": {"form": "semicircle"}})``.
    """
    import yaml

    from rodcad.design.loader import load_design

    text = data if isinstance(data, str) else yaml.safe_dump(data, sort_keys=False)
    return load_design(Path(folder) / name, text=text)


def build(design, *, cad: bool | None = None, method: str | None = None, seed: int | None = None,
          jobs: int | None = None, scheduler: str | None = None, progress: bool = False):
    """Design (and with ``cad``, build the solids of) any design: a chain's
    :class:`BuildResult`, a chandelier's :class:`ChandelierBuild` or a net's :class:`NetBuild`
    (:func:`rodcad.pipeline.kinds.build`). Nothing is written (see :func:`write`).
    ``progress`` prints the steps to stderr; ``scheduler``: a Dask scheduler's address to build a
    net's parts on (``jobs``: a local cluster of that many workers)."""
    from rodcad.pipeline.kinds import build as build_any
    from rodcad.progress import Progress

    return build_any(design, cad=cad, method=method, seed=seed, jobs=jobs, scheduler=scheduler,
                     progress=Progress(quiet=not progress))


def write(result, outdir: str | Path) -> dict[str, Any]:
    """Write a build's folder (design.json, report.md, previews, the 3D view and, with CAD,
    STEP/STL/3MF) to ``outdir``, atomically; returns the design.json data
    (:func:`rodcad.pipeline.kinds.write`)."""
    from rodcad.pipeline.kinds import write as write_any

    return write_any(result, outdir)
