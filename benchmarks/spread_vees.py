"""Narrow V nets drawn a little tighter than the default catalog's largest hub allows (issue 33's
spread, :mod:`rodcad.design.net.spread`): a seeded sample of V-shaped chains hung from two
anchors, their bottom node's two rods 0.05-2.5 deg under the largest hub's least angle, some
with a rod hanging below; each designed with the default catalog and no switches. A row per
net: the angle drawn (deg), the outcome (designed within 1 %, exit 1, or refused naming the hub
that would hold it), the fit (% of the size), how far the spread moved each node (mm), seconds.

    PYTHONPATH=. python benchmarks/spread_vees.py
"""

from __future__ import annotations

import math
import sys
import time
import traceback
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from rodcad.catalog.loader import load_catalog  # noqa: E402
from rodcad.design.net.choose import design_drawn_net  # noqa: E402
from rodcad.design.net.target import NetTarget  # noqa: E402
from rodcad.errors import DesignLimit  # noqa: E402


def vee(rng, limit: float) -> tuple[float, NetTarget]:
    """One V: (its angle drawn, the target)."""
    ang = limit - rng.uniform(0.05, 2.5)
    length = rng.uniform(45, 80)
    h = math.radians(ang) / 2
    x = np.array([[0.0, 0.0, 0.0], [length * math.sin(h), 0.0, length * math.cos(h)],
                  [-length * math.sin(h), 0.0, length * math.cos(h)]])
    up, dx = rng.uniform(40, 70), rng.uniform(1, 8)
    x = np.vstack([x, x[1] + [dx, 0.0, up], x[2] + [-dx, 0.0, up]])
    edges = [[0, 1], [0, 2], [1, 3], [2, 4]]
    if rng.random() < 0.5:  # a rod hanging below the bottom node
        x = np.vstack([x, [0.0, 0.0, -rng.uniform(40, 60)]])
        edges.append([0, 5])
    return ang, NetTarget("nodes", x, np.array(edges), np.array([3, 4]))


def main(n: int = 16, seed: int = 42) -> int:
    cat = load_catalog("pla-parametric")
    hw = cat.node
    limit = hw.sized(hw.pivot_limits[1]).min_angle_deg
    rng = np.random.default_rng(seed)
    print(f"largest hub's least angle {limit:.3f} deg\n| net | angle deg | outcome | fit % | moved mm | s | why |\n"
          "|---:|---:|---|---:|---|---:|---|")
    for i in range(n):
        ang, t = vee(rng, limit)
        t0 = time.perf_counter()
        try:
            c = design_drawn_net(t, cat, seed=0)
            row = ("designed" if c.ok else "exit 1", f"{100 * c.rel_size:.3g}",
                   ", ".join(f"{mm:.2f}" for _, mm in c.plan.spread), "" if c.ok else c.limit()[:90])
        except DesignLimit as err:
            row = ("refused", "", "", str(err)[:90])
        except Exception:  # a traceback is a defect: shown in the table
            row = ("TRACEBACK", "", "", traceback.format_exc(limit=-2).replace("\n", " ")[:200])
        print(f"| {i} | {ang:.2f} | {row[0]} | {row[1]} | {row[2]} | {time.perf_counter() - t0:.1f} | {row[3]} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
