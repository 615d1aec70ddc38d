"""Speed of the exact equilibrium solver (issue 2 targets).

Prints a table: N, case, median wall time per solve, active limits, Newton
iterations, KKT residual. Targets: N = 1000 free joints under 5 ms; N = 100
with about a third of the limits active under 20 ms; growth for free joints no
worse than N log N.

The "compressed" case (issue 15): K random limited chains of 6-15 rods with offset
centres of mass, stops on one or both sides, fused joints and often close anchors, so
that in some of them a rigid piece pushes. It prints the median and largest time per
solve over all K and over those the dual exchange alone cannot solve, and how many of
the K took which path (exchange, active-set descent, SLSQP fallback).

Run:  python benchmarks/bench_equilibrium.py [--repeat 7] [--compressed 400]
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

from optimize import solve_equilibrium


def chain(n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    lengths = rng.uniform(0.8, 1.2, n)
    masses = rng.uniform(0.5, 2.0, n)
    com = np.column_stack([lengths * rng.uniform(0.45, 0.55, n), lengths * rng.uniform(-0.05, 0.05, n)])
    span = 0.7 * lengths.sum()
    return lengths, masses, com, np.zeros(2), np.array([span, 0.1 * span])


def limited(n: int, seed: int = 0, fraction: float = 1 / 3):
    """Stops on the sagging side, set so that about `fraction` of them bind."""
    lengths, masses, com, a, b = chain(n, seed)
    free = solve_equilibrium(lengths, masses, a, b, com=com)
    phi = free.bends
    hi = np.full(n - 1, np.inf)
    # stop the joints with the largest bends a little below their free bend
    order = np.argsort(-phi)
    k = int(round(fraction * (n - 1)))
    hi[order[:k]] = 0.8 * phi[order[:k]]
    limits = np.column_stack([np.full(n - 1, -np.inf), hi])
    return lengths, masses, com, a, b, limits


def compressed_chain(seed: int):
    """A random limited chain around a known configuration (tests/test_compression.py)."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(6, 16))
    lengths = rng.uniform(0.5, 1.5, n)
    masses = rng.uniform(0.1, 5.0, n)
    com = np.column_stack([rng.uniform(0.2, 0.8, n) * lengths, rng.uniform(-0.3, 0.3, n) * lengths])
    spread = rng.choice([0.3, 0.6, 1.0])
    phi = rng.uniform(-spread, spread, n - 1) + rng.uniform(0, 0.4)
    theta = rng.uniform(-1.5, 0.0) + np.concatenate([[0.0], np.cumsum(phi)])
    b = np.array([lengths @ np.cos(theta), lengths @ np.sin(theta)])
    kind = rng.choice(5, n - 1, p=[0.3, 0.2, 0.2, 0.2, 0.1])  # free, lo, hi, both, fused
    lo = np.where(np.isin(kind, (1, 3)), phi - rng.uniform(0, 0.5, n - 1), -np.inf)
    hi = np.where(np.isin(kind, (2, 3)), phi + rng.uniform(0, 0.5, n - 1), np.inf)
    lo = np.where(kind == 4, phi, lo)
    hi = np.where(kind == 4, phi, hi)
    return lengths, masses, com, np.column_stack([lo, hi]), np.zeros(2), b


def compressed(k: int) -> None:
    times, hard, paths, failed = [], [], {}, 0
    for seed in range(k):
        l, m, c, lim, a, b = compressed_chain(seed)
        t0 = time.perf_counter()
        r = solve_equilibrium(l, m, a, b, com=c, limits=lim)
        t = time.perf_counter() - t0
        path = r.info.get("path", "slsqp" if r.info.get("used_nlp") else "exchange")
        paths[path] = paths.get(path, 0) + 1
        times.append(t)
        if path != "exchange":
            hard.append(t)
        failed += not (r.success and r.stable)
    times, hard = 1e3 * np.array(times), 1e3 * np.array(hard)
    print(f"\ncompressed: {k} random limited chains (6-15 rods; stops, fused joints, close anchors)")
    print(f"  all:               median {np.median(times):7.2f} ms   max {times.max():7.1f} ms")
    if hard.size:
        print(f"  not the exchange:  median {np.median(hard):7.2f} ms   max {hard.max():7.1f} ms   "
              f"({hard.size} chains)")
    print("  paths: " + ", ".join(f"{p} {n}" for p, n in sorted(paths.items()))
          + f";  needed SLSQP: {paths.get('slsqp', 0)} of {k};  not solved (success and stable): {failed}")


def timed(fn, repeat: int) -> tuple[float, object]:
    times, res = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--compressed", type=int, default=400, help="random chains in the compressed case")
    args = ap.parse_args()
    print(f"# {platform.processor() or platform.machine()}, python {platform.python_version()}, "
          f"numpy {np.__version__}")
    print(f"{'N':>6} {'case':<14} {'median ms':>10} {'active':>7} {'nit':>4} {'newton':>7} "
          f"{'kkt':>9} {'ok':>3} {'target':>10}")
    free_times = {}
    for n in (10, 100, 1000, 10000):
        l, m, c, a, b = chain(n)
        t, r = timed(lambda: solve_equilibrium(l, m, a, b, com=c), args.repeat)
        free_times[n] = t
        target = "< 5 ms" if n == 1000 else ""
        print(f"{n:>6} {'free':<14} {1e3 * t:>10.3f} {0:>7} {r.nit:>4} {r.nnewton:>7} "
              f"{r.kkt_residual:>9.1e} {'y' if r.success else 'n':>3} {target:>10}")
    for n in (10, 100, 1000):
        l, m, c, a, b, lim = limited(n)
        t, r = timed(lambda: solve_equilibrium(l, m, a, b, com=c, limits=lim), args.repeat)
        target = "< 20 ms" if n == 100 else ""
        print(f"{n:>6} {'1/3 limited':<14} {1e3 * t:>10.3f} {int(np.count_nonzero(r.active)):>7} "
              f"{r.nit:>4} {r.nnewton:>7} {r.kkt_residual:>9.1e} {'y' if r.success else 'n':>3} "
              f"{target:>10}")
    ns = sorted(free_times)
    print("\nfree-joint growth, time(N) / time(N/10) against N log N ratio:")
    for lo_n, hi_n in zip(ns, ns[1:]):
        ratio = free_times[hi_n] / free_times[lo_n]
        nlogn = hi_n * np.log(hi_n) / (lo_n * np.log(lo_n))
        print(f"  {lo_n:>5} -> {hi_n:<6} x{ratio:6.2f}   (N log N: x{nlogn:5.2f})")
    if args.compressed:
        compressed(args.compressed)


if __name__ == "__main__":
    main()
