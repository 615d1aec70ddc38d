"""The pipelines: a design file in, designed, checked and fabricated structures out.

One module per kind: a chain (and, inside it for now, a chandelier) in :mod:`.chain`, a
net in :mod:`.net`.
"""

from rodcad.pipeline.chain import (
    N_STARTS,
    TAPS,
    AsBuilt,
    BuildResult,
    ChandelierBuild,
    as_built,
    build,
    build_chandelier,
    build_fixture_for,
    simulate,
    write_chandelier_outputs,
    write_outputs,
)
from rodcad.pipeline.net import NetBuild, build_net, write_net_outputs

__all__ = [
    "N_STARTS",
    "TAPS",
    "AsBuilt",
    "BuildResult",
    "ChandelierBuild",
    "NetBuild",
    "as_built",
    "build",
    "build_chandelier",
    "build_fixture_for",
    "build_net",
    "simulate",
    "write_chandelier_outputs",
    "write_net_outputs",
    "write_outputs",
]
