"""Benchmark of rodcad's net design (no CAD): design files' nets with the default catalog's
hub hardware, from the loaded design to the checked equilibrium, printing a table.

Cases: a 13 x 13 grid (196 nodes) on a paraboloid, 40 mm cells, anchored along its border
(exact) and at its corners (no masses balance it: the best fit, refined); a 200-node radial
net (8 rings of 25 spokes, a steep funnel hung from its outer ring); the three examples. Each is
timed from the design (rodcad.design.net.plan: hubs and rods laid on the target, sockets
turned so the hubs balance, masses by optimize.design_net, the exact equilibrium from the
target and the multi-start: 8 starts up to 50 nodes, 400 / n beyond, 2 for these 200-node nets); ``rodcad build --no-cad`` adds about 2.5 s of imports
(the catalog loader pulls in the CAD kernel) and 1 s for the files.

Usage: python benchmarks/bench_net_design.py [--repeat 1]
Target (issue 27): a 200-node net's design (no CAD) under 10 s on 2 cores.
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from rodcad.design.loader import load_design  # noqa: E402
from rodcad.design.net.check import design_net_plan  # noqa: E402
from rodcad.design.net.plan import plan_net  # noqa: E402

GRID = """design: 1
name: grid-{anchored}
net:
  surface: {{z: "0.0008 * ((x - 260)**2 + (y - 260)**2) - 110", x: [0, 520], y: [0, 520], u: 13, v: 13}}
  anchored: {anchored}
"""

RADIAL = """design: 1
name: funnel
net:
  radial: {rings: 8, spokes: 25, radius: [200, 295], z: "2.5 * (r - 295)"}
  anchored: outer
"""


def design_timed(text: str, repeat: int):
    """A design file's text through the net design (no CAD) ``repeat`` times: (the design, the
    last NetCheck, the median seconds)."""
    d = load_design(ROOT / "examples" / "bench.yaml", text=text)
    times, c = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        c = design_net_plan(plan_net(d.net, d.catalog), seed=0)
        times.append(time.perf_counter() - t0)
    return d, c, float(np.median(times))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=1)
    args = ap.parse_args(argv)
    print(f"# {platform.machine()}, python {platform.python_version()}, numpy {np.__version__}")
    cases = [(f"grid 13x13, {a}", GRID.format(anchored=a)) for a in ("boundary", "corners")]
    cases.append(("radial 8 x 25", RADIAL))
    cases += [(f"examples/{n}.yaml", (ROOT / "examples" / f"{n}.yaml").read_text())
              for n in ("dome", "lampshade", "collar")]
    print(f"{'case':>26} {'nodes':>5} {'rods':>5} {'median s':>9} {'statics':>7} {'on tgt':>6} {'ok':>3} "
          f"{'err/size':>9} {'kkt':>8} {'starts':>6} {'others':>6}")
    for name, text in cases:
        d, c, median = design_timed(text, args.repeat)
        eq = c.equilibrium
        print(f"{name:>26} {d.net.n:>5} {d.net.m:>5} {median:>9.2f} "
              f"{'exact' if c.design.statics.exact else 'fit':>7} {'y' if c.rel_size <= 1e-6 else 'n':>6} "
              f"{'y' if c.ok else 'n':>3} {c.rel_size:>9.2e} {eq.kkt_residual:>8.1e} {eq.n_starts:>6} "
              f"{len(eq.alternatives):>6}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
