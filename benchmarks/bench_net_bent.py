"""Benchmark of bent net rods (issue 27): design time and error of nets whose rods are printed
bent, and of the same nets straight, printing a table; with ``--cad`` also the solids.

Cases (the default catalog's hubs): the lampshade and a 13 x 13 grid hung from its border,
straight and with every rod bent 0.12 (``net.bend``); the strip of tests/test_net_bent.py bent
0.08 and 0.12 (short rods whose buildable masses have gaps: the best fit where they do not
reach). Each is timed from the design (rodcad.design.net.plan and rodcad.design.net.check: hubs and rods laid
on the target, sockets turned, bounds narrowed to buildable masses, for a bent net the masses
and centres of mass iterated to a fixed point, optimize.design_net, the exact equilibrium from
the target and the multi-start). Columns: the design's error over the net's size, the largest
centre of mass off a chord (mm), the rounds of the fixed point. With ``--cad``: the bowed
lampshade's solids (rodcad.cad.net.solids.build_net_solids) and the net re-solved with the solids'
masses and centres of mass.

Usage: python benchmarks/bench_net_bent.py [--repeat 1] [--cad]
"""

from __future__ import annotations

import argparse
import platform
import re
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench_net_design import design_timed  # noqa: E402 - the same timing of a net design

GRID = """design: 1
name: grid
net:
  surface: {z: "0.0008 * ((x - 260)**2 + (y - 260)**2) - 110", x: [0, 520], y: [0, 520], u: 13, v: 13}
  anchored: boundary
"""

STRIP = """design: 1
name: strip
net:
  surface: {z: "0.003 * (x - 150)**2 - 67.5", x: [0, 300], y: [0, 60], u: 5, v: 1}
  anchored: ends
"""


def _bent(text: str, bend: float) -> str:
    return re.sub(r"(\n  anchored: [^\n]*\n)", rf"\1  bend: {bend}\n", text, count=1)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--cad", action="store_true", help="also build the bowed lampshade's solids")
    args = ap.parse_args(argv)
    print(f"# {platform.machine()}, python {platform.python_version()}, numpy {np.__version__}")
    lamp = (ROOT / "examples" / "lampshade.yaml").read_text()
    cases = [("lampshade, straight", lamp), ("lampshade, bend 0.12", _bent(lamp, 0.12)),
             ("grid 13x13 boundary, straight", GRID), ("grid 13x13 boundary, bend 0.12", _bent(GRID, 0.12)),
             ("strip, bend 0.08", _bent(STRIP, 0.08)), ("strip, bend 0.12", _bent(STRIP, 0.12))]
    print(f"{'case':>32} {'nodes':>5} {'rods':>5} {'median s':>9} {'statics':>7} {'ok':>3} {'err/size':>9} "
          f"{'kkt':>8} {'com off mm':>10} {'rounds':>6}")
    bowed = None
    for name, text in cases:
        d, c, median = design_timed(text, args.repeat)
        eq = c.equilibrium
        com = c.plan.rod_com(c.masses)
        rounds = next((re.search(r"\((\d+) round", n).group(1) for n in c.notes if "printed bent" in n), "-")
        print(f"{name:>32} {d.net.n:>5} {d.net.m:>5} {median:>9.2f} "
              f"{'exact' if c.design.statics.exact else 'fit':>7} {'y' if c.ok else 'n':>3} {c.rel_size:>9.2e} "
              f"{eq.kkt_residual:>8.1e} {float(np.abs(com[:, 1]).max()):>10.3f} {rounds:>6}")
        if name == "lampshade, bend 0.12":
            bowed = c
    if args.cad and bowed is not None:
        from rodcad.cad.net.build import build_net_solids

        t0 = time.perf_counter()
        s = build_net_solids(bowed)
        print(f"# bowed lampshade solids: {len(s.rods)} rods, {len(s.hubs)} hubs in {time.perf_counter() - t0:.1f} s; "
              f"as built {s.error_mm:.3g} mm ({s.rel_size:.2e} of its size) from the design; rod masses as built / "
              f"designed - 1: max {float(np.max(np.abs(s.rod_masses / bowed.masses - 1))):.1e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
