"""``rodcad simulate DESIGN.yaml [--json]``: the equilibrium of an explicit chain.

The design file's ``chain`` lists rod types and masses from anchor A to B; the
joint limits come from the catalog's rod geometry. Prints a table (or JSON with
``--json``: the ``rods``, ``simulated`` and, when the design has a target with
one joint per rod end, ``error`` parts of design.json).
"""

from __future__ import annotations

import argparse
import json
import math

from rodcad.design.loader import load_design
from rodcad.progress import Progress

__all__ = ["register", "run"]


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = sub.add_parser(
        "simulate",
        help="hang the design's explicit chain (rod types and masses) and print its equilibrium",
        description="Solve the exact equilibrium of the chain given explicitly in the design file "
        "(rod types and masses), with joint limits from the catalog's rods; check stability and "
        "look for other stable equilibria.",
    )
    p.add_argument("design", metavar="DESIGN.yaml", help="design file with a 'chain'")
    p.add_argument("--json", action="store_true", help="print JSON (design.json's rods, simulated, error)")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from rodcad import pipeline
    from rodcad.outputs.design_json import design_json
    from rodcad.outputs.report import summary_text

    design = load_design(args.design)
    result = pipeline.simulate(design, progress=Progress(quiet=args.json))
    data = design_json(result)
    if args.json:
        keep = ("name", "units", "catalog", "anchors", "rods", "simulated", "error", "notes")
        print(json.dumps({k: data[k] for k in keep}, indent=2, allow_nan=False))
        return 0 if result.equilibrium.success else 1
    eq = result.equilibrium
    print(f"rodcad simulate: {design.name}: {result.n} rods, catalog {design.catalog.name}")
    print(f"{'#':>3} {'type':<16} {'mass g':>8} {'x mm':>9} {'y mm':>9} {'angle deg':>10} {'bend deg':>9} "
          f"{'limits deg':>16}")
    for i in range(result.n):
        bend = f"{math.degrees(eq.bends[i]):9.3f}" if i < result.n - 1 else " " * 9
        lim = data["rods"][i]["limits_deg"]
        lim_s = "" if lim is None else f"{'free' if lim[0] is None else f'{lim[0]:.1f}'} .. " \
                                       f"{'free' if lim[1] is None else f'{lim[1]:.1f}'}"
        print(f"{i:>3} {result.type_names[i]:<16} {result.masses[i]:8.3f} {eq.points[i][0]:9.2f} "
              f"{eq.points[i][1]:9.2f} {math.degrees(eq.angles[i]):10.3f} {bend} {lim_s:>16}")
    print(f"    {'end':<16} {'':>8} {eq.points[-1][0]:9.2f} {eq.points[-1][1]:9.2f}")
    print(summary_text(result, None).split("\n", 1)[1])
    return 0 if eq.success else 1
