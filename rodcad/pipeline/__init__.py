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

#: Where each name lives, imported when first asked for (each kind's module imports the CAD
#: kernel only where it builds solids: a run without CAD never loads it).
_WHERE = {
    **dict.fromkeys(("N_STARTS", "TAPS", "as_built", "build", "build_fixture_for", "simulate", "write_outputs"),
                    "rodcad.pipeline.chain"),
    **dict.fromkeys(("build_chandelier", "write_chandelier_outputs"), "rodcad.pipeline.chandelier"),
    **dict.fromkeys(("Run", "kind_of", "run"), "rodcad.pipeline.kinds"),
    **dict.fromkeys(("NetBuild", "build_net", "write_net_outputs"), "rodcad.pipeline.net"),
    **dict.fromkeys(("AsBuilt", "BuildResult", "ChandelierBuild"), "rodcad.results"),
}

__all__ = sorted(_WHERE)


def __getattr__(name: str):
    if name not in _WHERE:
        raise AttributeError(f"module 'rodcad.pipeline' has no attribute {name!r}")
    value = getattr(importlib.import_module(_WHERE[name]), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
