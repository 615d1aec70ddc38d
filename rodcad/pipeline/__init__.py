"""The pipelines: a design file in, designed, checked and fabricated structures out.

Every kind of structure takes the same steps (load, plan, design, check, fabricate, build,
write) through its own module, which sequences them and owns none: a chain
(:mod:`.chain`), a chandelier of chains on a frame (:mod:`.chandelier`, each chain through
the chain's steps) and a net (:mod:`.net`). What they share, the staged output folder with
its progress, design.json and report.md, is :mod:`.folder`; :func:`run` (:mod:`.kinds`)
takes any design through build, then write, and is what ``rodcad build`` calls.
"""

import importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # (for readers and type checkers; at run time each is imported when first asked for)
    from rodcad.pipeline.chain import N_STARTS, TAPS, as_built, build, build_fixture_for, simulate, write_outputs
    from rodcad.pipeline.chandelier import build_chandelier, write_chandelier_outputs
    from rodcad.pipeline.kinds import Run, kind_of, run
    from rodcad.pipeline.net import NetBuild, build_net, write_net_outputs
    from rodcad.results import AsBuilt, BuildResult, ChandelierBuild

#: Where each name lives (imported when first asked for: a net's or a chain's pipeline
#: without CAD does not import the CAD kernel the other's module level needs).
_WHERE = {
    "N_STARTS": "chain", "TAPS": "chain", "as_built": "chain", "build": "chain",
    "build_fixture_for": "chain", "simulate": "chain", "write_outputs": "chain",
    "build_chandelier": "chandelier", "write_chandelier_outputs": "chandelier",
    "Run": "kinds", "kind_of": "kinds", "run": "kinds",
    "NetBuild": "net", "build_net": "net", "write_net_outputs": "net",
}
_RESULTS = ("AsBuilt", "BuildResult", "ChandelierBuild")


def __getattr__(name: str):
    if name in _WHERE:
        value = getattr(importlib.import_module(f"rodcad.pipeline.{_WHERE[name]}"), name)
    elif name in _RESULTS:
        value = getattr(importlib.import_module("rodcad.results"), name)
    else:
        raise AttributeError(f"module 'rodcad.pipeline' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))


__all__ = [
    "N_STARTS",
    "TAPS",
    "AsBuilt",
    "BuildResult",
    "ChandelierBuild",
    "NetBuild",
    "Run",
    "as_built",
    "build",
    "build_chandelier",
    "build_fixture_for",
    "build_net",
    "kind_of",
    "run",
    "simulate",
    "write_chandelier_outputs",
    "write_net_outputs",
    "write_outputs",
]
