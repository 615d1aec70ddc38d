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

The "anchor stops" case (issue 24): chains with both anchors stopped and stops along them
(the "1/3 limited" chains, their first rod held 0.2 rad above and their last rod 0.2 rad
below where they rest on the joint stops alone), N = 10 to 1000; target N = 300 under 1 s.
Then hearts hung from their cusp with anchor stops, as the planner designed them
(benchmarks/data/*.json, from ``rodcad build benchmarks/data/NAME.yaml --no-cad``; 30, 20, 120
and 300 rods, the 20-rod one a user's polyline): one solve, and the multi-start
(find_equilibria, default n_starts); targets: the 300-rod heart (both end rods held, 297
joints on stops) solved under 1 s, the 30-rod heart's multi-start under 2 s. Only the public API is used, so the same script times other versions.

The plain case (issue 34): the free chain against a plain numpy reaction Newton written in this
script (:func:`plain_newton`), timed on the same chains in the same run; target N = 1000 at most
0.5x.

Run:  python benchmarks/bench_equilibrium.py [--repeat 7] [--compressed 400] [--anchor-stops 1]
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np

from optimize import find_equilibria, solve_equilibrium

DATA = Path(__file__).resolve().parent / "data"


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


def end_limited(n: int, seed: int = 0):
    """A "1/3 limited" chain with both anchors stopped: the first rod held 0.2 rad above, the
    last 0.2 rad below where they rest on the joint stops alone (both anchor stops bind)."""
    lengths, masses, com, a, b, limits = limited(n, seed)
    held = solve_equilibrium(lengths, masses, a, b, com=com, limits=limits)
    ends = np.array([[held.angles[0] + 0.2, np.inf], [-np.inf, held.angles[-1] - 0.2]])
    return lengths, masses, com, a, b, limits, ends


def load_chain(name: str):
    """A chain saved in benchmarks/data/NAME.json: lengths, masses, com, a, b, limits, ends."""
    data = json.loads((DATA / f"{name}.json").read_text())

    def rad(rows):
        return np.array([[-np.inf if r[0] is None else r[0], np.inf if r[1] is None else r[1]] for r in rows])

    a, b = (np.array(p, float) for p in data["anchors"])
    return (np.array(data["lengths"]), np.array(data["masses"]), np.array(data["com"]), a, b,
            rad(data["limits"]), rad(data["end_limits"]))


def anchor_stops(repeat: int) -> None:
    print(f"\nanchor stops: both end rods held, stops along the chain")
    print(f"{'N':>6} {'case':<22} {'median ms':>10} {'stops':>6} {'ends':>5} {'nit':>4} {'path':>9} "
          f"{'kkt':>9} {'ok':>3} {'target':>10}")
    for n in (10, 30, 100, 300, 1000):
        l, m, c, a, b, lim, e = end_limited(n)
        t, r = timed(lambda: solve_equilibrium(l, m, a, b, com=c, limits=lim, end_limits=e), repeat)
        target = "< 1 s" if n == 300 else ""
        print(f"{n:>6} {'1/3 limited, both held':<22} {1e3 * t:>10.2f} {int(np.count_nonzero(r.active)):>6} "
              f"{int(np.count_nonzero(r.info.get('end_active', 0))):>5} {r.nit:>4} {r.info.get('path', '?'):>9} "
              f"{r.kkt_residual:>9.1e} {'y' if r.success and r.stable else 'n':>3} {target:>10}")
    for name in ("heart30", "user-heart", "heart120", "heart300"):
        l, m, c, a, b, lim, e = load_chain(name)
        t, r = timed(lambda: solve_equilibrium(l, m, a, b, com=c, limits=lim, end_limits=e), repeat)
        target = "< 1 s" if name == "heart300" else ""
        print(f"{l.size:>6} {name + ', one solve':<22} {1e3 * t:>10.2f} {int(np.count_nonzero(r.active)):>6} "
              f"{int(np.count_nonzero(r.info.get('end_active', 0))):>5} {r.nit:>4} {r.info.get('path', '?'):>9} "
              f"{r.kkt_residual:>9.1e} {'y' if r.success and r.stable else 'n':>3} {target:>10}")
        t, multi = timed(lambda: find_equilibria(l, m, a, b, com=c, limits=lim, end_limits=e), max(1, repeat // 3))
        target = "< 2 s" if name == "heart30" else ""
        print(f"{l.size:>6} {name + ', multi-start':<22} {1e3 * t:>10.2f} {'':>6} {'':>5} {multi.n_starts:>4} "
              f"{'':>9} {'':>9} {'y' if multi.n_failed == 0 else 'n':>3} {target:>10}   "
              f"{multi.n_distinct} stable shape(s), counts {multi.counts}, {multi.n_failed} failed")


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


def plain_newton(lengths, masses, com, a, b, g=9.81, tol=1e-12, max_iter=100):
    """A plain numpy reaction Newton for the free chain (the yardstick of issue 34): the
    anchor's reaction F0 = (Fx, Fy) as the unknown; each rod's angle from its moment balance
    under the force its far pin carries, theta = atan2(P, -Q) (the stable branch); Newton
    with the analytic 2 x 2 Jacobian and a backtracking line search on the closure residual,
    from the two-bar guess (the whole weight, half of it up)."""
    l = np.asarray(lengths, float)
    m = np.asarray(masses, float)
    ca, cb = np.asarray(com, float).T
    goal = np.asarray(b, float) - np.asarray(a, float)
    W = g * np.cumsum(m)  # the weight left of pin i + 1
    mga, mgb = g * m * ca, g * m * cb
    scale = l.sum()

    def residual(F):
        P = -l * (F[1] - W) - mga
        Q = l * F[0] + mgb
        th = np.arctan2(P, -Q)
        return np.array([l @ np.cos(th), l @ np.sin(th)]) - goal, th, P, Q

    F = np.array([-W[-1], 0.5 * W[-1]])
    r, th, P, Q = residual(F)
    for it in range(max_iter):
        if np.hypot(*r) <= tol * scale:
            return th, it
        rho2 = P * P + Q * Q
        s, c = np.sin(th), np.cos(th)
        dx, dy = P * l / rho2, Q * l / rho2
        J = np.array([[-(l * s) @ dx, -(l * s) @ dy], [(l * c) @ dx, (l * c) @ dy]])
        step = np.linalg.solve(J, -r)
        t = 1.0
        while True:
            r2, th2, P2, Q2 = residual(F + t * step)
            if np.hypot(*r2) < np.hypot(*r) or t < 1e-8:
                break
            t *= 0.5
        F, r, th, P, Q = F + t * step, r2, th2, P2, Q2
    raise RuntimeError("the plain Newton did not converge")


def against_plain(repeat: int) -> None:
    """The free chain: rodcad's solver against the plain reaction Newton, same chains, same
    run (target, issue 34: N = 1000 at most 0.5x)."""
    print("\nfree chain against a plain numpy reaction Newton (same chains, same run):")
    print(f"{'N':>6} {'plain ms':>9} {'nit':>4} {'rodcad ms':>10} {'ratio':>6} {'path':>6} {'max angle diff':>15} {'target':>8}")
    for n in (10, 100, 1000, 10000):
        l, m, c, a, b = chain(n)
        tp, (th, it) = timed(lambda: plain_newton(l, m, c, a, b), max(repeat, 50))
        to, r = timed(lambda: solve_equilibrium(l, m, a, b, com=c), max(repeat, 50))
        diff = float(np.abs(np.angle(np.exp(1j * (th - r.angles)))).max())
        target = "<= 0.5" if n == 1000 else ""
        print(f"{n:>6} {1e3 * tp:>9.3f} {it:>4} {1e3 * to:>10.3f} {to / tp:>6.2f} {r.info['path']:>6} {diff:>15.1e} "
              f"{target:>8}")


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
    ap.add_argument("--anchor-stops", type=int, default=1, help="run the anchor-stop cases (0: skip)")
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
    against_plain(args.repeat)
    if args.anchor_stops:
        anchor_stops(args.repeat)
    if args.compressed:
        compressed(args.compressed)


if __name__ == "__main__":
    main()
