"""``rodcad build DESIGN.yaml``: design, check and fabricate a hanging chain.

Writes OUTDIR (default ``outputs/<design name>``): design.json, report.md,
preview.png and preview.svg, and unless ``--no-cad`` assembly.step plus
rods/*.step and rods/*.stl. Everything is written to a temporary folder first
and renamed into place at the end, so a failed or interrupted run leaves OUTDIR
as it was. When the rods hang further off the target curve than the design's
``tolerance`` (default 1 % of the target's size), OUTDIR is left alone, the best
achievable design goes to ``OUTDIR.best-fit``, one line says what limits it and
what would reach it, and the exit code is 1.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from rodcad.design.loader import load_design
from rodcad.design.model import METHOD_NAMES
from rodcad.errors import InputError, Problem
from rodcad.outdir import OutputFolderError, best_fit_folder, check_output_folder
from rodcad.progress import Progress

__all__ = ["register", "run"]


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = sub.add_parser(
        "build",
        help="design a chain for a target shape, check it and write STEP/STL files and a report",
        description="Choose rod types and masses so the chain hangs in the design's target shape, "
        "check the equilibrium (stability, other equilibria), cut cavities and ball sockets for every "
        "rod's mass and write the printable files, a report and previews.",
    )
    p.add_argument("design", metavar="DESIGN.yaml", help="design file")
    p.add_argument("-o", "--outdir", metavar="OUTDIR", help="output folder (default outputs/<design name>)")
    p.add_argument("--no-cad", action="store_true", help="design and check only: no solids, no STEP/STL")
    p.add_argument("--method", choices=METHOD_NAMES, help="inverse-design method (default: the design's)")
    p.add_argument("--seed", type=int, metavar="N", help="random seed (default: the design's)")
    p.add_argument("--jobs", type=int, metavar="N", help="worker processes (default: number of CPUs, at most "
                   "RODCAD_JOBS; a net's CAD: a Dask local cluster of N workers, by default when the net has enough "
                   "distinct parts)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="build a net's parts on this Dask scheduler's workers "
                   "(e.g. tcp://10.0.0.5:8786; they must import the same rodcad)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress, only the summary")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    progress = Progress(quiet=args.quiet)
    design = load_design(args.design)
    outdir = Path(args.outdir) if args.outdir else Path("outputs") / design.name
    problems = []
    for folder in (outdir, best_fit_folder(outdir)):  # before any work: never replace what rodcad did not write
        try:
            check_output_folder(folder)
        except (OutputFolderError, ValueError) as err:
            problems.append(Problem(str(folder), 0, 0, "-o" if args.outdir else "name", str(err)))
            break  # the best fit's folder sits beside OUTDIR: one problem says it
    if args.jobs is None:  # the default's cap from the environment, before any work
        from rodcad.parallel import default_jobs

        try:
            default_jobs()
        except InputError as err:
            problems.extend(err.problems)
    if problems:
        raise InputError(problems)
    if args.seed is not None and args.seed < 0:
        print("rodcad: --seed must be 0 or more", file=sys.stderr)
        return 2
    if args.jobs is not None and args.jobs < 1:
        print("rodcad: --jobs must be 1 or more", file=sys.stderr)
        return 2
    if args.scheduler is not None and not args.scheduler.strip():
        print("rodcad: --scheduler needs an address (tcp://HOST:PORT)", file=sys.stderr)
        return 2
    from rodcad import pipeline

    written = pipeline.run(design, outdir, cad=False if args.no_cad else None, method=args.method,
                           seed=args.seed, jobs=args.jobs, scheduler=args.scheduler, progress=progress)
    return _REPORTS[written.kind](written, design, outdir)


def _chain(written, design, outdir: Path) -> int:
    from rodcad.outputs.report import summary_text

    result, target = written.result, written.outdir
    print(summary_text(result, target))
    if not result.meets_tolerance:
        print(f"rodcad: {design.name} {result.limit().rstrip('.')}; {outdir} left as it was, the best fit is in "
              f"{target}", file=sys.stderr)
    elif not written.ok:
        print("rodcad: the anchor fixture is not fit to print: " + "; ".join(result.fixture_problems)
              + f"; {outdir} left as it was, the design and its fixture are in {target}", file=sys.stderr)
    return 0 if written.ok else 1


def _chandelier(written, design, outdir: Path) -> int:
    from rodcad.outputs.report import chandelier_summary

    b, target = written.result, written.outdir
    print(chandelier_summary(b, target))
    if not written.ok:
        tol = design.tolerance if design.tolerance is not None else 0.01
        off = [f"{ch.name} hangs {100 * f:.3g} % of its size off its curve" for ch, f in zip(b.result.chains, b.fits)
               if f > tol]
        print(f"rodcad: {'; '.join(off)} (tolerance {100 * tol:.3g} %); {outdir} left as it was, the best "
              f"achievable design is in {target}", file=sys.stderr)
        return 1
    return 0


def _net(written, design, outdir: Path) -> int:
    from rodcad.outputs.net.report import net_summary

    b, target = written.result, written.outdir
    print(net_summary(b.check, target))
    unsolved = b.solids is not None and math.isnan(b.solids.rel_size)  # rodcad's solver, not the design
    if b.solids is not None and not unsolved:
        stalled = (f" (the solver stopped at KKT residual {b.solids.as_built.kkt_residual:.2g}, short of "
                   "round-off: read where it stopped)") if b.as_built_stalled else ""
        print(f"as built (the solids' masses and centres of mass): {b.solids.error_mm:.3g} mm "
              f"({100 * b.solids.rel_size:.3g} % of its size) from the design{stalled}")
    if not b.check.ok:
        print(f"rodcad: {design.name} {b.limit().rstrip('.')}; {outdir} left as it was, the best fit is in {target}",
              file=sys.stderr)
        return 1
    if unsolved:
        print(f"rodcad: {design.name}: the net as built (the solids' masses) did not solve: rodcad's solver stopped "
              f"at KKT residual {b.solids.as_built.kkt_residual:.2g} ({b.solids.as_built.message}); this is rodcad's "
              f"failure, not the design's: please report it with the design file; {outdir} left as it was, the "
              f"design and its solids are in {target}", file=sys.stderr)
        return 1
    if not b.ok:
        print(f"rodcad: {design.name}: as built (the solids' masses) it hangs {100 * b.solids.rel_size:.3g} % of its "
              f"size from the design (tolerance {100 * b.check.tolerance:.3g} %); {outdir} left as it was, the "
              f"design and its solids are in {target}", file=sys.stderr)
        return 1
    return 0


#: What the command prints and returns after :func:`rodcad.pipeline.run`, per kind.
_REPORTS = {"chain": _chain, "chandelier": _chandelier, "net": _net}
