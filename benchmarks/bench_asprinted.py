"""As printed: pin play, pin friction and mass tolerance on the shipped examples (issue 25).

For every example chain (built with ``rodcad build examples/X.yaml -o DIR/X --no-cad`` unless
DIR/X/design.json exists) this prints, in mm and in % of the target's size (the larger of
span, width and height of the target joints):

* model:  the design's own error, simulated joints vs target joints (design.json error.max_mm);
* play:   the chain with every pin bearing in its holes (optimize.solve_pin_play, the catalog's
          pin clearance), rods printed at the design lengths: largest joint distance from the
          target;
* l-c:    the same with the rule of thumb: spacing = l - c, centre of mass c/2 nearer the first
          hole;
* comp:   with the exact compensation (optimize.compensate_pin_play);
* fric:   the friction band (optimize.friction_band, mu 0.3, pin radius 1.5 mm): the largest
          joint displacement over the shapes the chain can rest in;
* mass:   the 95 % mass band (optimize.mass_band, tol 0.03: +-3 % per rod, 95 %).

Then the solve times (median of --repeat): solve_equilibrium, solve_pin_play, friction_band,
mass_band.

    python benchmarks/bench_asprinted.py [--dir /tmp/ap] [--repeat 5] [examples ...]
"""

from __future__ import annotations

import argparse
import json
import platform
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from optimize import (compensate_pin_play, friction_band, mass_band, solve_equilibrium,
                      solve_pin_play)

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ["catenary", "garland", "garland-rise", "heart", "necklace", "polygon", "semicircle",
            "semicircle-weights", "triangle"]


def design_of(name: str, folder: Path) -> dict:
    out = folder / name
    if not (out / "design.json").exists():
        subprocess.run([sys.executable, "-m", "rodcad.cli", "build", str(ROOT / "examples" / f"{name}.yaml"),
                        "-o", str(out), "--no-cad", "-q"], check=True, cwd=ROOT)
    return json.loads((out / "design.json").read_text())


def clearance_of(catalog: str) -> float:
    text = (ROOT / "catalogs" / f"{catalog}.yaml").read_text()
    return float(re.search(r"pin_clearance:\s*([0-9.]+)", text).group(1))


def chain_of(d: dict) -> dict:
    rods = d["rods"]

    def rad(pair):
        if pair is None:
            return [-np.inf, np.inf]
        return [-np.inf if pair[0] is None else np.radians(pair[0]), np.inf if pair[1] is None else np.radians(pair[1])]

    ends = np.array([rad(p) for p in d["anchor_limits_deg"]])
    return dict(lengths=np.array([r["length"] for r in rods]), masses=np.array([r["mass"] for r in rods]),
                com=np.array([r["com"] for r in rods]), limits=np.array([rad(r["limits_deg"]) for r in rods[:-1]]),
                end_limits=None if np.all(np.isinf(ends)) else ends,
                a=np.array(d["anchors"][0], float), b=np.array(d["anchors"][1], float),
                target=np.array(d["target"]["points"], float), simulated=np.array(d["simulated"]["points"], float))


def median_time(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return float(np.median(times))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("examples", nargs="*", default=EXAMPLES)
    ap.add_argument("--dir", default="/tmp/ap", type=Path)
    ap.add_argument("--repeat", default=5, type=int)
    ap.add_argument("--mu", default=0.3, type=float)
    ap.add_argument("--pin-radius", default=1.5, type=float)
    ap.add_argument("--tol", default=0.03, type=float)
    args = ap.parse_args(argv)
    print(f"# {platform.machine()}, python {platform.python_version()}, numpy {np.__version__}")
    print(f"# friction mu {args.mu}, pin radius {args.pin_radius} mm; mass tolerance +-{100 * args.tol:.0f} % (95 %)")
    head = (f"{'example':19s} {'N':>3s} {'c mm':>5s} {'size':>6s} | {'model':>15s} | {'play':>15s} | "
            f"{'l-c':>15s} | {'comp':>15s} | {'fric':>15s} | {'mass 95%':>15s}")
    print(head)
    print("-" * len(head))
    timing = []
    for name in args.examples:
        d = design_of(name, args.dir)
        ch = chain_of(d)
        n = ch["lengths"].size
        c = clearance_of(d["catalog"])
        tgt = ch["target"]
        size = max(float(np.ptp(tgt[:, 0])), float(np.ptp(tgt[:, 1])), float(np.hypot(*(ch["b"] - ch["a"]))))
        kw = dict(com=ch["com"], limits=ch["limits"], end_limits=ch["end_limits"])
        st = solve_equilibrium(ch["lengths"], ch["masses"], ch["a"], ch["b"], **kw)

        def off(points):
            return float(np.linalg.norm(points - tgt, axis=1).max())

        model = float(d["error"]["max_mm"])
        play = solve_pin_play(ch["lengths"], ch["masses"], ch["a"], ch["b"], clearance=c, **kw)
        rule_com = ch["com"] - np.array([0.5 * c, 0.0])
        rule = solve_pin_play(ch["lengths"] - c, ch["masses"], ch["a"], ch["b"], clearance=c, com=rule_com,
                              limits=ch["limits"], end_limits=ch["end_limits"])
        comp = compensate_pin_play(st.points, ch["masses"], st.reaction, clearance=c, **kw)
        printed = solve_pin_play(comp.spacings, ch["masses"], ch["a"], ch["b"], clearance=c, com=comp.com,
                                 limits=comp.limits, end_limits=comp.end_limits)
        fb = friction_band(ch["lengths"], ch["masses"], ch["a"], ch["b"], mu=args.mu, pin_radius=args.pin_radius,
                           result=st, **kw)
        mb = mass_band(ch["lengths"], ch["masses"], ch["a"], ch["b"], tol=args.tol, result=st, **kw)
        ok = all(r.success for r in (st, play, rule, printed))

        def cell(mm):
            return f"{mm:7.3f} {100 * mm / size:6.3f}%"

        print(f"{name:19s} {n:3d} {c:5.2f} {size:6.1f} | {cell(model)} | {cell(off(play.points))} | "
              f"{cell(off(rule.points))} | {cell(off(printed.points))} | {cell(fb.band)} | {cell(mb.band)}"
              + ("" if ok else "  (a solve failed)") + ("" if fb.cells == 1 else f"  friction: {fb.cells} cells"))
        timing.append((name, n,
                       median_time(lambda: solve_equilibrium(ch["lengths"], ch["masses"], ch["a"], ch["b"], **kw), args.repeat),
                       median_time(lambda: solve_pin_play(ch["lengths"], ch["masses"], ch["a"], ch["b"], clearance=c, **kw),
                                   args.repeat),
                       median_time(lambda: friction_band(ch["lengths"], ch["masses"], ch["a"], ch["b"], mu=args.mu,
                                                         pin_radius=args.pin_radius, result=st, **kw), args.repeat),
                       median_time(lambda: mass_band(ch["lengths"], ch["masses"], ch["a"], ch["b"], tol=args.tol,
                                                     result=st, **kw), args.repeat),
                       play.info["path"]))
    print()
    print(f"{'example':19s} {'N':>3s} {'equilibrium ms':>15s} {'pin play ms':>12s} {'path':>12s} "
          f"{'friction ms':>12s} {'mass band ms':>13s}")
    for name, n, t_eq, t_pp, t_fb, t_mb, path in timing:
        print(f"{name:19s} {n:3d} {1e3 * t_eq:15.2f} {1e3 * t_pp:12.2f} {path:>12s} {1e3 * t_fb:12.2f} {1e3 * t_mb:13.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
