"""CAD benchmark (issue 5): fabricate a 20-rod chain and write its files, cold fabrication cache.

    python benchmarks/bench_cad.py [--jobs 2] [--rods 20] [--seed 0]

Rods cycle over five types of the shipped catalog `pla-pinned`; masses are drawn
(seeded) from each type's achievable range, half lighter and half heavier than
solid. The catalog's mass ranges are computed first (a separate stage: `rodcad
catalog check` caches them); fabrication, STEP/STL and the assembly start from an
empty fabrication cache. Prints a table of stages and seconds.
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--rods", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)

    from rodcad.cad.chainfiles import write_assembly, write_rod_files
    from rodcad.cad.rods import fabricate_chain
    from rodcad.catalog.cache import DiskCache
    from rodcad.catalog.loader import load_catalog
    from rodcad.catalog.massrange import mass_infos

    rows: list[tuple[str, float]] = []
    t0 = time.perf_counter()
    cat = load_catalog("pla-pinned")
    names = ["free-30", "straight-20", "free-40", "arc-30", "concave20-30"]
    infos = mass_infos([cat[n] for n in names], jobs=args.jobs)
    rows.append(("catalog mass ranges (cached by catalog check)", time.perf_counter() - t0))

    rng = np.random.default_rng(args.seed)
    types, masses = [], []
    for i in range(args.rods):
        t = cat[names[i % len(names)]]
        info = infos[t.name]
        if i % 2 == 0:
            m = rng.uniform(info.m_min, info.solid_mass)
        else:  # heavy: on one of the ball counts' reachable masses
            m = info.m_max - rng.uniform(0, 0.02) * (info.m_max - info.solid_mass)
        if i in (4, 9):  # a repeated rod (built once)
            t, m = types[0], masses[0]
        types.append(t)
        masses.append(float(m))

    with tempfile.TemporaryDirectory() as tmp:
        cache = DiskCache(Path(tmp) / "cache")
        t1 = time.perf_counter()
        fab = fabricate_chain(types, masses, seed=args.seed, jobs=args.jobs, cache=cache)
        rows.append((f"fabricate ({fab.distinct} distinct rods, jobs {args.jobs})", time.perf_counter() - t1))
        t2 = time.perf_counter()
        write_rod_files(fab, Path(tmp) / "out")
        rows.append(("rods/*.step + *.stl, written and checked", time.perf_counter() - t2))
        t3 = time.perf_counter()
        lengths = np.array([t.length for t in types])
        ang = np.linspace(-1.2, 1.2, len(types))
        pts = np.concatenate([[[0.0, 0.0]], np.cumsum(np.c_[np.cos(ang), np.sin(ang)] * lengths[:, None], 0)])
        write_assembly(fab, pts, Path(tmp) / "out" / "assembly.step")
        rows.append(("assembly.step", time.perf_counter() - t3))
        t4 = time.perf_counter()
        fab2 = fabricate_chain(types, masses, seed=args.seed, jobs=args.jobs, cache=cache)
        rows.append(("fabricate again (warm cache)", time.perf_counter() - t4))
        assert [r.mass for r in fab2.rods] == [r.mass for r in fab.rods]
    total = sum(s for name, s in rows[1:4])

    print(f"# {platform.machine()}, python {platform.python_version()}, {os.cpu_count()} CPUs")
    print(f"{'stage':55s} {'seconds':>8s}")
    for name, s in rows:
        print(f"{name:55s} {s:8.2f}")
    print(f"{'end to end, cold fabrication cache (target < 60 s)':55s} {total:8.2f}")
    errs = np.array([abs(r.mass_error) for r in fab.rods])
    walls = [r.min_wall for r in fab.rods if np.isfinite(r.min_wall)]
    print(f"\nrods {len(fab.rods)}, distinct {fab.distinct}, cavities {sum(r.cavity_count for r in fab.rods)}, "
          f"balls {sum(r.ball_count for r in fab.rods)}; max |mass error| {errs.max():.1e} "
          f"(vs clipped target); thinnest wall {min(walls):.3f} mm; problems {len(fab.problems)}")
    for p in fab.problems:
        print("  " + p)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
