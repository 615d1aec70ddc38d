"""Nets of hundreds to thousands of rods designed without CAD: the whole `rodcad build --no-cad`.

Each net is a design file written to a folder and built by the command line in a fresh
process (imports, the design and every file it writes included), timed as a whole and step
by step (the progress lines the build prints), with its peak memory (the process's largest
resident set, ``getrusage``). Nets (the default catalog, no switches):

- ``grid10``, ``grid22``, ``grid33``: u x u grids of 40 mm cells on a paraboloid, the border
  anchored (rods between two border nodes are left out): 220, 1,012 and 2,112 rods;
- ``web``: 12 rings of 100 spokes, a shallow cone hung from its outer ring: 2,200 rods.

The equilibrium is then checked from design.json alone, independently of the solver: every
free node's force balance recomputed in plain numpy from the written rods' ends, tensions and
masses and the hubs' masses, over the force scale; each hub's moment balance about its node
point; every rod's length from its written ends.

Nets of 2,000 rods or more (``--independent``) are then solved again by a method of their own
(:mod:`net_balance`: the balance equations by Newton with a finite-difference Jacobian, no
rodcad code) from perturbed starts, and the largest node distance from rodcad's equilibrium
is reported.

Usage: python benchmarks/bench_net_scale.py [--nets grid10 grid22 grid33 web] [--keep DIR]
[--independent RODS]
Target (issue 33): a net of 2,000+ rods designs without CAD in under 60 s on 2 cores.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))

from net_balance import balance, force_scale, read_net, solve_balance  # noqa: E402  (benchmarks/)

NETS = {
    "grid10": {"surface": {"z": "0.0015 * ((x - 200)**2 + (y - 200)**2) - 60", "x": [0, 400], "y": [0, 400],
                           "u": 10, "v": 10}, "anchored": "boundary"},
    "grid22": {"surface": {"z": "0.001 * ((x - 440)**2 + (y - 440)**2) - 200", "x": [0, 880], "y": [0, 880],
                           "u": 22, "v": 22}, "anchored": "boundary"},
    "grid33": {"surface": {"z": "0.00075 * ((x - 660)**2 + (y - 660)**2) - 300", "x": [0, 1320], "y": [0, 1320],
                           "u": 33, "v": 33}, "anchored": "boundary"},
    "web": {"radial": {"rings": 12, "spokes": 100, "radius": [570, 1180], "z": "0.5 * (r - 1180)"},
            "anchored": "outer"},
}

#: The child process: the command line's main, then its peak memory (kB) on stderr's last line.
CHILD = ("import resource, sys; from rodcad.cli import main; rc = main(sys.argv[1:]); "
         "print('MAXRSS', resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, file=sys.stderr); sys.exit(rc)")


def design_yaml(name: str) -> str:
    """The design file of one of :data:`NETS`."""
    net = NETS[name]
    kind = "surface" if "surface" in net else "radial"
    body = "\n".join(f"    {k}: {json.dumps(v)}" for k, v in net[kind].items())
    return f"design: 1\nname: {name}\nnet:\n  {kind}:\n{body}\n  anchored: {net['anchored']}\nseed: 0\n"


def build(name: str, folder: Path) -> dict:
    """Build one net in a fresh process: wall and CPU time, steps, peak memory, exit code."""
    src = folder / f"{name}.yaml"
    src.write_text(design_yaml(name))
    out = folder / name
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    t0, r0 = time.perf_counter(), os.times()
    p = subprocess.run([sys.executable, "-c", CHILD, "build", str(src), "-o", str(out), "--no-cad"],
                       capture_output=True, text=True, env=env)
    r1 = os.times()
    steps = [(m.group(1), float(m.group(2))) for m in re.finditer(r"^  (.+?): done \(([\d.]+) s\)$", p.stderr, re.M)]
    rss = re.search(r"^MAXRSS (\d+)$", p.stderr, re.M)
    return {"name": name, "rc": p.returncode, "wall": time.perf_counter() - t0,
            "cpu": (r1.children_user - r0.children_user) + (r1.children_system - r0.children_system),
            "steps": steps, "rss_mb": int(rss.group(1)) / 1024 if rss else float("nan"),
            "out": out if p.returncode == 0 else Path(str(out) + ".best-fit"), "stderr": p.stderr}


def check_balance(path: Path, g: float = 9.81) -> dict:
    """The written equilibrium's force and hub moment balance, recomputed in plain numpy.

    Rod e pulls its pivot at node i with T_e u_e (u_e from that pivot toward the other) and
    hangs its weight g m_e on its two pivots by the lever rule (``1 - t`` and ``t`` with ``t =
    along / L``: straight rods, their centre of mass on the axis); a hub adds its own weight
    at its centre of mass (its rotation times its body-frame ``com``). A free node's residual
    is the sum of those forces, a hub's moment residual the sum of their moments about its
    node point (:func:`net_balance.balance`, the rods' ends as written). Returns the largest of
    each over the force scale (the larger of the largest tension and the net's weight; moments
    over that times the mean rod length)."""
    d = json.loads((path / "design.json").read_text())
    net = read_net(path)
    force, moment, dl = balance(net, net.x, net.rotations, net.ends[:, 0], net.ends[:, 1], net.tensions, g)
    free = ~net.anchored
    scale = force_scale(net, g)
    return {"force": float(np.max(np.linalg.norm(force[free], axis=1)) / scale),
            "moment": float(np.max(np.linalg.norm(moment[free], axis=1)) / (scale * float(net.lengths.mean()))),
            "length": float(np.max(np.abs(dl) / net.lengths)), "rods": len(net.edges), "nodes": len(net.x),
            "kkt": d["net"]["kkt_residual"], "error_rel": d["net"]["error"]["max_rel_size"],
            "stable": d["net"]["stable"], "starts": d["net"]["alternatives"]["starts"],
            "alternatives": d["net"]["alternatives"]["count"]}


def independent(path: Path, seeds=(0, 1)) -> list[dict]:
    """The written net solved again by :func:`net_balance.solve_balance` (Newton on the balance
    equations, finite-difference Jacobian) from perturbed starts, one per seed."""
    net = read_net(path)
    return [dict(solve_balance(net, seed=s), seed=s, size=net.size) for s in seeds]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nets", nargs="+", default=list(NETS), choices=list(NETS))
    ap.add_argument("--keep", type=Path, help="build into this folder (kept) instead of a temporary one")
    ap.add_argument("--independent", type=int, default=2000, metavar="RODS",
                    help="solve the nets of at least this many rods again independently (net_balance; 0: all)")
    args = ap.parse_args(argv)
    print(f"# {platform.machine()}, {os.cpu_count()} cores, python {platform.python_version()}, "
          f"numpy {np.__version__}; {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}", flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        folder = args.keep or Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        rows = []
        for name in args.nets:
            r = build(name, folder)
            if not (r["out"] / "design.json").exists():
                print(r["stderr"], file=sys.stderr)
            r["check"] = check_balance(r["out"]) if (r["out"] / "design.json").exists() else None
            if r["check"] and r["check"]["rods"] >= args.independent:
                r["independent"] = independent(r["out"])
            print(f"  {name}: exit {r['rc']}, {r['wall']:.1f} s", file=sys.stderr, flush=True)
            rows.append(r)
        print("\n| net | rods | nodes | exit | wall s | CPU s | peak MB | steps (s) |")
        print("|---|---|---|---|---|---|---|---|")
        for r in rows:
            c = r["check"] or {}
            steps = "; ".join(f"{s.split(' (')[0].split(',')[0]} {t:.1f}" for s, t in r["steps"])
            print(f"| {r['name']} | {c.get('rods', '-')} | {c.get('nodes', '-')} | {r['rc']} | {r['wall']:.1f} | "
                  f"{r['cpu']:.1f} | {r['rss_mb']:.0f} | {steps} |")
        print("\nThe written equilibrium checked from design.json in plain numpy (largest over the free nodes):\n")
        print("| net | force imbalance / scale | hub moment / (scale x rod) | rod length error | solver's KKT | "
              "off target / size | stable | starts, other shapes |")
        print("|---|---|---|---|---|---|---|---|")
        for r in rows:
            c = r["check"]
            if c:
                print(f"| {r['name']} | {c['force']:.2g} | {c['moment']:.2g} | {c['length']:.2g} | {c['kkt']:.2g} | "
                      f"{c['error_rel']:.3g} | {c['stable']} | {c['starts']}, {c['alternatives']} |")
        print("\nThe written equilibrium solved again independently (benchmarks/net_balance.py: Newton on the "
              "balance equations with a finite-difference Jacobian) from perturbed starts:\n")
        print("| net | seed | start off (mm) | Newton steps | scaled residual | off rodcad's equilibrium (mm) | "
              "/ size | tensions off (rel) | wall s |")
        print("|---|---|---|---|---|---|---|---|---|")
        for r in rows:
            for q in r.get("independent", []):
                print(f"| {r['name']} | {q['seed']} | {q['started']:.3g} | {q['steps']} "
                      f"{'' if q['converged'] else '(not converged)'} | {q['residual']:.2g} | {q['distance']:.2g} | "
                      f"{q['distance'] / q['size']:.2g} | {q['tension_change']:.2g} | {q['wall']:.1f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
