"""Graduated rods (issue 26): closed forms and fast limits against the solids, and mass spans.

Sweeps rods of the default catalog over (length, curvature, scale, ends), seeded:

* volume and centre of mass in closed form (rodcad.catalog.fastgeom) against the B-rep's;
* joint limits from the end geometry (rodcad.catalog.jointlimits) against the B-rep search
  (rodcad.catalog.limits), neighbours of different scales, free ends and flush stops;
* per length, the mass span of straight rods over the scale range: the lightest (lowest
  scale, most cavities) to the heaviest (highest scale the length takes, most 6 mm balls),
  from the mass table and the closed forms.

    python benchmarks/bench_graduated.py [--rods 40] [--pairs 30] [--seed 0]
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np

from rodcad.cad.solids import GeometryError, build_rod, mass_properties
from rodcad.catalog.fastgeom import rod_mass_properties
from rodcad.catalog.jointlimits import joint_limits
from rodcad.catalog.limits import TOLERANCE_DEG, compute_pair_limits
from rodcad.catalog.loader import load_catalog
from rodcad.catalog.model import max_curvature
from rodcad.catalog.printed import mass_table, table_lengths
from rodcad.catalog.scaling import mass_span


def _rod(cat, rng, stop_end=None):
    r = cat.family("rod").ranges
    length = float(rng.uniform(*r.length))
    kmax = min(max(abs(r.curvature[0]), abs(r.curvature[1])), max_curvature(length))
    k = float(rng.choice([0.0, rng.uniform(-kmax, kmax)]))
    ends = {}
    if stop_end is not None:
        ends[stop_end] = float(rng.uniform(-40, 40))
    s0, s1 = cat.scale_range("rod", length, k, **ends)
    scale = float(rng.uniform(s0, s1))
    return length, k, scale, ends


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rods", type=int, default=40)
    ap.add_argument("--pairs", type=int, default=30)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    cat = load_catalog("pla-parametric")
    print(f"# {platform.machine()}, python {platform.python_version()}, {os.cpu_count()} CPUs, seed {args.seed}")
    worst_v, worst_c, t_fast, t_brep = 0.0, 0.0, 0.0, 0.0
    for _ in range(args.rods):
        length, k, scale, ends = _rod(cat, rng, rng.choice([None, "first_stop", "second_under"]))
        g = cat.rod("rod", length, k, scale=scale, **ends).geometry
        try:  # the family's own rod of these parameters (scale 1) may make no solid either
            build_rod(cat.rod("rod", length, k, **ends).geometry)
        except GeometryError:
            continue
        t0 = time.perf_counter()
        vol, com = rod_mass_properties(g)
        t1 = time.perf_counter()
        b = mass_properties(build_rod(g))
        t2 = time.perf_counter()
        t_fast += t1 - t0
        t_brep += t2 - t1
        worst_v = max(worst_v, abs(vol - b.volume) / b.volume)
        worst_c = max(worst_c, float(np.max(np.abs(np.array(com) - b.center))) / length)
    print(f"mass properties, {args.rods} rods: worst volume rel {worst_v:.1e}, worst com / length {worst_c:.1e}; "
          f"closed form {1000 * t_fast / args.rods:.1f} ms, B-rep build + GProp {1000 * t_brep / args.rods:.0f} ms per rod")
    worst, looser, t_fast, t_brep, n, stop_off, skipped, done = 0.0, 0, 0.0, 0.0, 0, 0.0, 0, 0
    for i in range(args.pairs):
        stop = float(rng.uniform(-60, 80)) if i % 2 else None
        la, ka, sa, _ = _rod(cat, rng)
        lb, kb, sb, _ = _rod(cat, rng)
        if stop is None:
            a = cat.rod("rod", la, ka, scale=sa).geometry
            b = cat.rod("rod", lb, kb, scale=sb).geometry
        else:  # the scales drawn within the ranges of the rods with their stop ends
            ga, gb = cat.rod("rod", la, ka).geometry, cat.rod("rod", lb, kb).geometry
            c = min(max((stop - ga.half_angle_deg - gb.half_angle_deg) / 2, -40.0), 45.0)
            stop = 2 * c + ga.half_angle_deg + gb.half_angle_deg
            sa = float(rng.uniform(*cat.scale_range("rod", la, ka, second_stop=c)))
            sb = float(rng.uniform(*cat.scale_range("rod", lb, kb, first_stop=c)))
            a = cat.rod("rod", la, ka, scale=sa, second_stop=c).geometry
            b = cat.rod("rod", lb, kb, scale=sb, first_stop=c).geometry
        try:  # some random stops on some rods are not the family's (no solid, or no free bend)
            build_rod(a), build_rod(b)
            joint_limits(a, b)
        except (GeometryError, ValueError):
            skipped += 1
            continue
        t0 = time.perf_counter()
        fast = joint_limits(a, b)
        t1 = time.perf_counter()
        r = compute_pair_limits(a, b, 1.2)
        t2 = time.perf_counter()
        t_fast += t1 - t0
        t_brep += t2 - t1
        done += 1
        if stop is not None:  # the flush faces stop the joint at the bend they are printed for
            stop_off = max(stop_off, abs(r["hi"] - stop) if r["hi"] is not None else float("inf"))
        for side, (x, y) in enumerate(zip(fast, (r["lo"], r["hi"]))):
            if x is None or y is None:
                looser += (x is None) != (y is None)
                continue
            n += 1
            worst = max(worst, abs(x - y))
            looser += (y - x if side == 0 else x - y) > TOLERANCE_DEG / 2
    print(f"joint limits, {args.pairs} pairs of different scales ({n} limits, half of the pairs on a flush stop): "
          f"worst deviation {worst:.4f} deg, looser than the solids {looser}; fast {1000 * t_fast / done:.0f} ms, "
          f"B-rep search {t_brep / done:.2f} s per pair; flush stops on the solids at most {stop_off:.4f} deg "
          f"off their bend; {skipped} pairs skipped (no solid)")
    table = mass_table(cat.family("rod"))
    print(f"{'length mm':>9} {'scales':>13} {'lightest g':>10} {'heaviest g':>10} {'span':>6}")
    for length in table_lengths(cat.family("rod")):
        s0, s1 = cat.scale_range("rod", length)
        lo, hi = mass_span(cat, "rod", table, length)
        print(f"{length:9.0f} {s0:6.3g}-{s1:<6.3g} {lo:10.2f} {hi:10.2f} {hi / lo:5.2f}:1")


if __name__ == "__main__":
    main()
