"""One entry for every kind of structure: :func:`run` takes a design through the same steps
whatever it holds (a chain, a chandelier of chains, a net): build it, then write its folder
(OUTDIR, or OUTDIR.best-fit beside it when the build misses its tolerance). The kinds differ
only in the functions behind those two steps, their pipeline modules' (looked up when called).
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rodcad.design.model import Design
from rodcad.outdir import best_fit_folder
from rodcad.progress import Progress
from rodcad.results import ChandelierBuild

__all__ = ["Run", "build", "kind_of", "run", "write"]


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
        seed: int | None = None, jobs: int | None = None, scheduler: str | None = None,
        progress: Progress | None = None) -> Run:
    """Build any design and write its folder: ``outdir`` when the build meets its tolerance,
    else ``outdir``'s best-fit folder (:func:`rodcad.outdir.best_fit_folder`; ``outdir`` is
    then left as it was).

    Args:
        design: a validated design (a target, a chandelier or a net).
        outdir: the output folder.
        cad: build the solids (default: the design's fabrication.cad).
        method: inverse-design method (default: the design's; chains and chandeliers).
        seed: seed (default: the design's).
        jobs: worker processes (a net's: a Dask local cluster of that many).
        scheduler: a Dask scheduler's address to build a net's parts on.
        progress: where to report progress (default: silent).

    Raises:
        InputError: the design cannot be built as given.
        DesignLimit: rods the catalog cannot print, nodes too crowded for the hubs (nets).
    """
    result = build(design, cad=cad, method=method, seed=seed, jobs=jobs, scheduler=scheduler, progress=progress)
    ok = result.meets_tolerance if isinstance(result, ChandelierBuild) else result.ok
    target = Path(outdir) if ok else best_fit_folder(Path(outdir))
    data = write(result, target, progress=progress, jobs=jobs)
    return Run(kind_of(design), result, target, bool(ok), data)


def build(design: Design, *, cad: bool | None = None, method: str | None = None, seed: int | None = None,
          jobs: int | None = None, scheduler: str | None = None, progress: Progress | None = None) -> Any:
    """Build any design (arguments as :func:`run`'s), writing nothing: a chain's
    :class:`rodcad.results.BuildResult`, a chandelier's :class:`rodcad.results.ChandelierBuild`
    or a net's :class:`rodcad.pipeline.net.NetBuild`."""
    kind = kind_of(design)
    if kind == "chandelier":
        return _pipeline("chandelier").build_chandelier(design, method=method, seed=seed, cad=cad, jobs=jobs,
                                                        progress=progress)
    if kind == "net":
        return _pipeline("net").build_net(design, seed=seed, cad=design.cad if cad is None else cad, jobs=jobs,
                                          scheduler=scheduler, progress=progress)
    return _pipeline("chain").build(design, method=method, seed=seed, cad=cad, jobs=jobs, progress=progress)


def write(result: Any, outdir: str | Path, *, progress: Progress | None = None,
          jobs: int | None = None) -> dict[str, Any]:
    """Write what :func:`build` returned to ``outdir`` (staged: all or nothing); the data
    written to design.json. ``jobs``: worker processes for a chain's or a chandelier's files
    (default: :func:`rodcad.parallel.default_jobs`; 1: all here)."""
    net = _pipeline("net")
    if isinstance(result, net.NetBuild):
        return net.write_net_outputs(result, outdir, progress=progress)
    if isinstance(result, ChandelierBuild):
        return _pipeline("chandelier").write_chandelier_outputs(result, outdir, progress=progress, jobs=jobs)
    return _pipeline("chain").write_outputs(result, outdir, progress=progress, jobs=jobs)


def _pipeline(kind: str):
    """The pipeline module of a kind, imported when first used (a run of one kind does not
    load the others')."""
    return importlib.import_module(f"rodcad.pipeline.{kind}")
