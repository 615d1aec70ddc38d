"""The reachable-mass tables of rods printed to order (issue 34: under 3 s per distinct rod
type): each type's table (:func:`rodcad.fabrication.intervals.compute_table`, and the one-row
alternates a chain's build asks for with it) computed from nothing, one type at a time, in
this process. The types: the semicircle's three (README's first command) and a seeded sample
of the default catalog's family (lengths, curvatures and scales drawn over its ranges).

    PYTHONPATH=. python benchmarks/bench_tables.py [--n 6] [--seed 0]

Prints a table: the type, its ball options, the seconds for its table, and a last row with
the largest and the median.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

#: The semicircle's three rod types (length mm, curvature 1/mm, scale), as README's first
#: command plans them.
SEMICIRCLE = [(51.763608458837815, 0.009999489832780796, s) for s in (1.04, 1.270783016132191, 1.5)]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=6, help="seeded types besides the semicircle's")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)

    from rodcad.catalog.loader import load_catalog
    from rodcad.fabrication.intervals import _table_star

    cat = load_catalog("pla-parametric")
    fam = cat.family("rod")
    rng = np.random.default_rng(args.seed)
    params = list(SEMICIRCLE)
    (lo_l, hi_l), (lo_k, hi_k) = fam.ranges.length, fam.ranges.curvature
    while len(params) < len(SEMICIRCLE) + args.n:
        length = float(rng.uniform(lo_l, hi_l))
        curvature = float(rng.uniform(lo_k, hi_k))
        try:
            s0, s1 = cat.scale_range("rod", length, curvature)
        except Exception:  # (a length and curvature the family cannot print: drawn again)
            continue
        params.append((length, curvature, float(rng.uniform(s0, s1))))
    from rodcad.errors import InputError

    rows = []
    for length, curvature, scale in params:
        rod = cat.rod("rod", length, curvature, scale=scale)
        t0 = time.perf_counter()
        try:
            table = _table_star((rod, 0))
        except InputError:  # (a section the family cannot print at that bend: not a type a design gets)
            continue
        rows.append((rod.name, len(table["options"]), time.perf_counter() - t0))
    print("| rod type | ball options | table s |\n|---|---:|---:|")
    for name, k, s in rows:
        print(f"| {name} | {k} | {s:.2f} |")
    secs = [s for _, _, s in rows]
    print(f"| largest / median | | {max(secs):.2f} / {statistics.median(secs):.2f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
