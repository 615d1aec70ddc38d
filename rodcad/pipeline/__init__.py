"""The pipelines: a design file in, designed, checked and fabricated structures out.

Every kind of structure takes the same steps (load, plan, design, check, fabricate, build,
write) through its own module, which sequences them and owns none: a chain
(:mod:`.chain`), a chandelier of chains on a frame (:mod:`.chandelier`, each chain through
the chain's steps) and a net (:mod:`.net`). What they share, the staged output folder with
its progress, design.json and report.md, is :mod:`.folder`; :func:`run` (:mod:`.kinds`)
takes any design through build, then write, and is what ``rodcad build`` calls.
"""

from rodcad.pipeline.chain import (
    N_STARTS,
    TAPS,
    as_built,
    build,
    build_fixture_for,
    simulate,
    write_outputs,
)
from rodcad.pipeline.chandelier import build_chandelier, write_chandelier_outputs
from rodcad.pipeline.kinds import Run, kind_of, run
from rodcad.pipeline.net import NetBuild, build_net, write_net_outputs
from rodcad.results import AsBuilt, BuildResult, ChandelierBuild

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
