"""One entry for every kind of structure: :func:`run` takes a design through the same steps
whatever it holds (a chain, a chandelier of chains, a net): build it, then write its folder
(OUTDIR, or OUTDIR.best-fit beside it when the build misses its tolerance). The kinds differ
only in the functions behind those two steps, their pipeline modules' (looked up when called).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rodcad.design.model import Design
from rodcad.outdir import best_fit_folder
from rodcad.pipeline import chain, chandelier, net
from rodcad.progress import Progress

__all__ = ["Run", "kind_of", "run"]


def kind_of(design: Design) -> str:
    """The kind of structure a design holds: "chandelier", "net" or "chain"."""
    if design.chandelier is not None:
        return "chandelier"
    if design.net is not None:
        return "net"
    return "chain"


@dataclass
class Run:
    """What :func:`run` built and wrote.

    Attributes:
        kind: "chain", "chandelier" or "net".
        result: the build (:class:`rodcad.results.BuildResult`,
            :class:`rodcad.results.ChandelierBuild` or :class:`rodcad.pipeline.net.NetBuild`).
        outdir: the folder written: the OUTDIR asked for, or OUTDIR.best-fit beside it.
        ok: the result met its tolerance (and went to OUTDIR).
        data: the data written to design.json.
    """

    kind: str
    result: Any
    outdir: Path
    ok: bool
    data: dict[str, Any]


def run(design: Design, outdir: str | Path, *, cad: bool | None = None, method: str | None = None,
        seed: int | None = None, jobs: int | None = None, progress: Progress | None = None) -> Run:
    """Build any design and write its folder: ``outdir`` when the build meets its tolerance,
    else ``outdir``'s best-fit folder (:func:`rodcad.outdir.best_fit_folder`; ``outdir`` is
    then left as it was).

    Args:
        design: a validated design (a target, a chandelier or a net).
        outdir: the output folder.
        cad: build the solids (default: the design's fabrication.cad).
        method: inverse-design method (default: the design's; chains and chandeliers).
        seed: seed (default: the design's).
        jobs: worker processes (chains and chandeliers; a net chooses its own).
        progress: where to report progress (default: silent).

    Raises:
        InputError: the design cannot be built as given.
        DesignLimit: rods the catalog cannot print, nodes too crowded for the hubs (nets).
    """
    kind = kind_of(design)
    if kind == "chandelier":
        result = chandelier.build_chandelier(design, method=method, seed=seed, cad=cad, jobs=jobs,
                                             progress=progress)
        ok, write = result.meets_tolerance, chandelier.write_chandelier_outputs
    elif kind == "net":
        result = net.build_net(design, seed=seed, cad=design.cad if cad is None else cad, progress=progress)
        ok, write = result.ok, net.write_net_outputs
    else:
        result = chain.build(design, method=method, seed=seed, cad=cad, jobs=jobs, progress=progress)
        ok, write = result.ok, chain.write_outputs
    target = Path(outdir) if ok else best_fit_folder(Path(outdir))
    data = write(result, target, progress=progress)
    return Run(kind, result, target, bool(ok), data)
