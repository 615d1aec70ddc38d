"""Fast joint limits from the end geometry against the B-rep interference search.

For every joinable pair of each shipped catalog: the fast function's limits
(:func:`rodcad.catalog.jointlimits.joint_limits`) against the B-rep search's (the shipped
seeds, themselves checked against fresh searches by the tests), the worst deviation, and
whether it ever allows more bend than the solids; then the time per pair of both methods
(the B-rep search run afresh on a few pairs, without cache).

    python benchmarks/bench_jointlimits.py [--brep-sample 4]
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time

from rodcad.catalog.jointlimits import joint_limits
from rodcad.catalog.limits import TOLERANCE_DEG, all_pair_limits, compute_pair_limits
from rodcad.catalog.loader import load_catalog
from rodcad.catalog.paths import shipped_catalogs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--brep-sample", type=int, default=4, help="pairs per catalog searched afresh on the B-rep")
    args = ap.parse_args()
    print(f"# {platform.machine()}, python {platform.python_version()}, {os.cpu_count()} CPUs")
    print(f"{'catalog':<14} {'pairs':>5} {'worst dev deg':>13} {'looser':>6} {'fast ms/pair':>12} "
          f"{'B-rep s/pair':>12} {'speed-up':>8}")
    for name in shipped_catalogs():
        cat = load_catalog(name)
        ref = all_pair_limits(cat)
        worst, looser, t_fast = 0.0, 0, 0.0
        for (left, right), r in ref.items():
            t0 = time.perf_counter()
            fast = joint_limits(cat[left].geometry, cat[right].geometry)
            t_fast += time.perf_counter() - t0
            for side, (a, b) in enumerate(zip(fast, r.limits_deg)):
                if a is None or b is None:
                    looser += (a is None) != (b is None)
                    continue
                worst = max(worst, abs(a - b))
                looser += (b - a if side == 0 else a - b) > TOLERANCE_DEG / 2
        with tempfile.TemporaryDirectory() as tmp:
            os.environ["RODCAD_CACHE_DIR"] = tmp
            sample = list(ref)[: args.brep_sample]
            t0 = time.perf_counter()
            for left, right in sample:
                compute_pair_limits(cat[left].geometry, cat[right].geometry,
                                    min(cat[left].material.min_wall, cat[right].material.min_wall))
            t_brep = (time.perf_counter() - t0) / max(len(sample), 1)
        ms = 1000 * t_fast / len(ref)
        print(f"{name:<14} {len(ref):>5} {worst:>13.4f} {looser:>6} {ms:>12.1f} {t_brep:>12.2f} "
              f"{t_brep * 1000 / ms:>7.0f}x")


if __name__ == "__main__":
    main()
