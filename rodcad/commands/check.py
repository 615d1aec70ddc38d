"""``rodcad check OUTDIR [--rebalance] [--json]``: the round trip after manual edits.

Re-reads the rods of an earlier ``rodcad build`` as they are now (OUTDIR/rods/*.step, or
``--assembly FILE`` for an assembly STEP exported back from a CAD program, rods matched by
name), checks each is one valid closed solid with its pin holes where the chain needs
them, measures its mass and centre of mass, re-simulates the chain and reports how far it
now hangs from the design and from the target. ``--preview FILE`` draws it.

``--rebalance`` keeps the edited rods as they are, re-designs the other rods' masses so
the chain hangs on its target again, rebuilds them and writes OUTDIR again (the changed
rods' STEP/STL, design.json, report.md, previews, assembly.step; staged, all or nothing).
When the edit cannot be balanced within the rods' mass ranges, OUTDIR is left as it was,
the best fit goes to OUTDIR.best-fit and the exit code is 1.

Exit codes: 0 done; 1 the chain cannot hang as simulated (rods overlap at the new bends,
no equilibrium) or the edit cannot be balanced; 2 bad input (not a build's output folder,
a rod file that is not one valid closed solid, pin holes moved or gone), nothing written.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from rodcad.errors import InputError, Problem
from rodcad.outdir import OutputFolderError, check_output_folder
from rodcad.progress import Progress

__all__ = ["register", "run"]


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = sub.add_parser(
        "check",
        help="re-read a build's rods after manual edits, re-simulate the chain (and re-balance it)",
        description="Re-read the rods of an earlier `rodcad build` as they are now (edited in FreeCAD or any "
        "CAD), check their solids and pin holes, measure their masses and centres of mass and re-simulate "
        "the chain; --rebalance re-designs the unedited rods so the chain hangs on its target again.",
    )
    p.add_argument("outdir", metavar="OUTDIR", help="output folder of `rodcad build` (built with CAD)")
    p.add_argument("--rebalance", action="store_true",
                   help="keep the edited rods, re-design and rebuild the others, write OUTDIR again")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--assembly", metavar="FILE",
                   help="read the rods from this assembly STEP (rods named NN_TYPE, in the built pose) "
                   "instead of OUTDIR/rods/*.step")
    p.add_argument("--preview", metavar="FILE", help="draw the re-simulated chain to FILE (PNG, SVG, PDF)")
    p.add_argument("--jobs", type=int, metavar="N", help="worker processes (default: number of CPUs)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress, only the summary")
    p.set_defaults(handler=run)


def _folders(args: argparse.Namespace) -> list[Path]:
    """The folders a re-balance may write, checked before any work."""
    out = Path(args.outdir)
    problems = []
    folders = [out, out.with_name(out.name + ".best-fit")]
    for folder in folders:
        try:
            check_output_folder(folder)
        except OutputFolderError as err:
            problems.append(Problem(str(folder), 0, 0, "OUTDIR", str(err)))
    if problems:
        raise InputError(problems)
    return folders


def _preview_path(raw: str) -> Path:
    path = Path(raw)
    if not path.parent.is_dir():
        raise InputError([Problem(raw, 0, 0, "--preview", f"the folder {path.parent} does not exist")])
    if path.suffix.lower() not in (".png", ".svg", ".pdf"):
        raise InputError([Problem(raw, 0, 0, "--preview", "give a .png, .svg or .pdf file")])
    if path.is_dir():
        raise InputError([Problem(raw, 0, 0, "--preview", "is a folder; give a file")])
    return path


def _text(res: Any) -> str:
    b = res.built
    lines = [f"rodcad check: {b.data.get('name') or b.outdir.name}: {b.n} rods re-read from "
             f"{b.outdir}, {len(res.edited)} edited ({res.time_s:.1f} s)",
             f"{'#':>3} {'rod':<34} {'built g':>9} {'now g':>9} {'change':>9} {'com moved':>10}  edited"]
    for r, rod in zip(res.readings, b.rods):
        lines.append(f"{r.index:>3} {rod.stem:<34} {rod.mass:9.4f} {r.mass:9.4f} {100 * r.mass_change:+8.3f}% "
                     f"{r.com_shift:8.4f}mm  {'yes' if r.edited else 'no'}")
    d, t = res.vs_design, res.vs_target
    lines.append(f"  vs design  max {d.max:.3g} mm ({100 * d.max_rel_span:.3g} % of the span)")
    lines.append(f"  vs target  max {t.max:.3g} mm ({100 * t.max_rel_span:.3g} % of the span)")
    lines += [f"  note: {n}" for n in res.notes]
    return "\n".join(lines)


def _rebalance_json(rb: Any, written: Path | None) -> dict[str, Any]:
    return {"balanced": bool(rb.ok), "redesigned": list(rb.redesigned),
            "masses": [float(m) for m in rb.masses], "com": [[float(x), float(y)] for x, y in rb.com],
            "as_built": {"points": [[float(x), float(y)] for x, y in rb.as_built.points],
                         "stable": bool(rb.as_built.stable), "error": rb.vs_target.as_dict(),
                         "error_vs_design": rb.vs_design.as_dict()},
            "allowed_rel_span": float(rb.allowed), "notes": list(rb.notes),
            "written": None if written is None else str(written)}


def run(args: argparse.Namespace) -> int:
    from rodcad.check.built import load_built
    from rodcad.check.recheck import check, check_json

    progress = Progress(quiet=args.quiet or args.json)
    load_built(args.outdir)  # bad input first, before anything else is looked at
    folders = _folders(args) if args.rebalance else []
    preview = _preview_path(args.preview) if args.preview else None
    if args.jobs is not None and args.jobs < 1:
        raise InputError([Problem("--jobs", 0, 0, "--jobs", "must be 1 or more")])
    res = check(args.outdir, assembly=args.assembly, progress=progress)
    out: dict[str, Any] = check_json(res)
    code = 0 if res.ok else 1
    rb = None
    written = None
    if args.rebalance:
        code, rb, written = _rebalance(res, args, folders, progress)
        out["notes"] = list(res.notes)  # with what the re-balance says
        out["rebalance"] = None if rb is None else _rebalance_json(rb, written)
    if preview is not None:
        from rodcad.check.write import plot_check

        plot_check(res, preview, rb=rb)
        out["preview"] = str(preview)
    if args.json:
        print(json.dumps(out, indent=2, allow_nan=False))
    else:
        print(_text(res))
        if rb is not None:
            print("\n".join(f"  rebalance: {n}" for n in rb.notes))
            if written is not None:
                print(f"  files     {written}/ (design.json, report.md, preview.png, assembly.step, "
                      f"{len(rb.fabricated)} rod(s) rebuilt)")
    if code and rb is not None and not rb.ok:
        print(f"rodcad: the edit cannot be balanced within the rods' mass ranges; {args.outdir} left as it was, "
              f"the best fit is in {written}", file=sys.stderr)
    return code


def _rebalance(res: Any, args: argparse.Namespace, folders: list[Path], progress: Progress
               ) -> tuple[int, Any, Path | None]:
    from rodcad.check.rebalance import rebalance
    from rodcad.check.write import write_rebalanced

    if not res.edited:
        res.notes.append("--rebalance: no rod was edited, nothing to re-balance; OUTDIR left as it was")
        return (0 if res.ok else 1), None, None
    if res.blocked or not res.equilibrium.success:
        res.notes.append("--rebalance: the edited chain cannot hang as simulated (see above); fix the edit first. "
                         "OUTDIR left as it was")
        return 1, None, None
    if len(res.edited) == res.built.n:
        res.notes.append("--rebalance: every rod was edited, none is left to re-balance the chain with; OUTDIR "
                         "left as it was")
        return 1, None, None
    pieces = sorted({r.piece for r in res.built.rods if r.piece is not None})
    if pieces:
        res.notes.append("--rebalance: this chain has fused pieces (rods " + ", ".join(f"{a}-{b}" for a, b in pieces)
                         + "), which the re-balance cannot re-design and re-fuse yet; rebuild with `rodcad build` "
                         "instead. OUTDIR left as it was")
        return 1, None, None
    rb = rebalance(res, jobs=args.jobs, progress=progress)
    target = folders[0] if rb.ok else folders[1]
    with progress.step(f"writing {target} (re-designed rods, design.json, report.md, previews, assembly)"):
        write_rebalanced(res, rb, target, from_assembly=args.assembly is not None)
    return (0 if rb.ok else 1), rb, target
