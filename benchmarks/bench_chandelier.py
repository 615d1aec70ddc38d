"""Chandelier (issue 7): six chains of 12+ rods around a ring, designed and built as one assembly.

Six festoons hang below a ring of radius 100 mm (shipped catalog pla-pinned);
each chain gets its own catenary target (lengths 250..300 mm, so the six
problems are distinct and nothing is shared), laid with 20 mm rods (12-15 per
chain; --any-length lets the planner mix the catalog's lengths). Times, per stage: the catalog's
arrays (disk-cached), the design of all chains (jobs = 1 and --jobs), the frame
(ring + 12 lugs: the solid and its checks, every rod against the frame), the 3D
preview; with --cad also the fabrication of every rod (cavities and ball
sockets, disk-cached: use a fresh RODCAD_CACHE_DIR for a cold figure) and the
STEP assembly of frame and chains.

Run:  python benchmarks/bench_chandelier.py [--jobs 2] [--cad] [--any-length] [--out DIR]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from rodcad.cad.chandelier import build_frame, chandelier_nodes
from rodcad.catalog.loader import load_catalog
from rodcad.design.chandelier import design_chandelier, ring
from rodcad.design.frame import frame_outline, plan_frame
from rodcad.design.model import Constraints
from rodcad.design.plan import catalog_arrays
from rodcad.outputs.preview3d import preview_3d
from rodcad.parallel import default_jobs

LENGTHS = (250, 260, 270, 280, 290, 300)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", type=int, default=default_jobs(), help="worker processes")
    ap.add_argument("--cad", action="store_true", help="also fabricate every rod and write assembly.step")
    ap.add_argument("--any-length", action="store_true", help="let the planner mix rod lengths")
    ap.add_argument("--out", default=None, help="directory for preview.png / assembly.step (default: a temp dir)")
    args = ap.parse_args(argv)
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="bench-chandelier-"))
    out.mkdir(parents=True, exist_ok=True)

    stages: list[tuple[str, float]] = []

    def stage(name: str, t0: float) -> None:
        stages.append((name, time.perf_counter() - t0))

    t = time.perf_counter()
    cat = load_catalog("pla-pinned")
    arrays = catalog_arrays(cat, jobs=args.jobs)
    stage("catalog arrays (cached)", t)
    placements = ring(6, 100.0, 0.0)
    targets = [{"form": "catenary", "length": float(L)} for L in LENGTHS]
    for jobs in sorted({1, args.jobs}):
        t = time.perf_counter()
        design = design_chandelier(cat, placements, targets, method="refine", seed=0, jobs=jobs,
                                     arrays=arrays,
                                     constraints=None if args.any_length else Constraints(lengths=(20.0,)))
        stage(f"design 6 chains, jobs={jobs}", t)
    t = time.perf_counter()
    plan = plan_frame("ring", placements, cat, design.chains)
    frame, check = build_frame(plan, cat, design.chains)
    stage("frame: solid + checks", t)
    t = time.perf_counter()
    preview_3d(out / "preview.png", design.chains, frame_outline(plan), title="bench chandelier")
    stage("3D preview", t)
    if args.cad:
        from rodcad.cad.export import export_assembly
        from rodcad.cad.rods import fabricate_chain

        t = time.perf_counter()
        fabs = [fabricate_chain([cat[n] for n in c.type_names], c.masses, seed=0, jobs=args.jobs)
                for c in design.chains]
        stage("fabricate every rod", t)
        t = time.perf_counter()
        nodes = chandelier_nodes(frame, design.chains, cat, frame_plan=plan,
                                   rod_solid=lambda ci, i: fabs[ci].rods[i].solid)
        export_assembly(out / "assembly.step", nodes, "chandelier")
        stage("assembly.step", t)

    print(f"chains: {len(design.chains)}, distinct problems: {design.n_distinct}, rods: {design.bom.n_rods}")
    print(f"{'chain':<9} {'rods':>4} {'mass g':>7} {'max mm':>8} {'max/span':>9} stable unique")
    for r in design.errors():
        print(f"{r['name']:<9} {r['n_rods']:>4} {r['mass_g']:>7.2f} {r['max_mm']:>8.3f} "
              f"{r['max_rel_span']:>9.2e} {'y' if r['stable'] else 'n':>6} {'y' if r['unique'] else 'n':>6}")
    bom = design.bom
    print("bill of materials: " + ", ".join(f"{n} x {k}" for k, n in bom.rods_by_type.items())
          + f"; {bom.total_mass:.1f} g of rods; {bom.pins} pins + {bom.anchor_pins} lug pins")
    print(f"frame: {check.size[0]:.0f} x {check.size[1]:.0f} x {check.size[2]:.1f} mm, valid "
          f"{check.valid}, fits printer {check.fits_printer}, rods checked {len(check.clearances)}, "
          f"closest {min(d for *_, d in check.clearances):.2f} mm, problems: {check.problems or 'none'}")
    if args.cad:
        bad = [p for f in fabs for p in f.problems]
        print(f"fabrication: {sum(f.distinct for f in fabs)} distinct rods built, {len(bad)} masses "
              f"out of reach{': ' + bad[0] if bad else ''}")
    print(f"\n{'stage':<28} {'s':>8}")
    for name, s in stages:
        print(f"{name:<28} {s:>8.2f}")
    print(f"\nfiles in {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
