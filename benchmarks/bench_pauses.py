"""Pauses of graduated chains (issue 23): how many layers a chain's print pauses on, and the
as-built error, for the examples and a few seeded drawn shapes.

Each design is built with CAD (``rodcad build``, one job after the other); the table reads
design.json: the distinct pause layers over every rod's socket roofs (each roof's bridging
layer, :meth:`rodcad.fabrication.layers.LayerGrid.pause_z`, as print.3mf pauses), the rows of
sockets (distinct roof heights summed over the rods), and the as-built error (the chain
re-simulated with the solids' masses and centres of mass, max joint distance to the target).

    python benchmarks/bench_pauses.py --out /tmp/pauses [--shapes 4 --seed 0] [--only semicircle,heart]

Run it once on the code to compare and once on this one (same cache, same seeds).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from drawn_shapes import design_text, family  # noqa: E402

from rodcad.fabrication.layers import LayerGrid  # noqa: E402

EXAMPLES = ("semicircle", "heart", "necklace", "garland")


def pauses(design: dict) -> tuple[int, int, list[float]]:
    """(distinct pause layers, socket rows over all rods, the pause heights) of a build."""
    prof = design.get("print", {})
    grid = LayerGrid(float(prof.get("layer_height", 0.2)), float(prof.get("first_layer_height", prof.get("layer_height", 0.2))))
    zs: set[float] = set()
    rows = 0
    for r in design["rods"]:
        f = r.get("fabrication") or {}
        roofs = [float(z) for z in f.get("pause_zs_mm") or []]
        rows += len(roofs)
        zs |= {grid.pause_z(z) for z in roofs}
    return len(zs), rows, sorted(zs)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--shapes", type=int, default=4)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--only", default="")
    args = ap.parse_args()
    root = Path(__file__).resolve().parent.parent
    args.out.mkdir(parents=True, exist_ok=True)
    jobs = [(name, root / "examples" / f"{name}.yaml") for name in EXAMPLES]
    for s in family(args.shapes, args.seed):
        path = args.out / f"{s.name}.yaml"
        path.write_text(design_text(s))
        jobs.append((s.name, path))
    only = {x for x in args.only.split(",") if x}
    print("| design | rods | socket rows | pauses | pause heights (mm) | as-built max mm | build s |")
    print("|---|---|---|---|---|---|---|")
    for name, path in jobs:
        if only and name not in only:
            continue
        out = args.out / name
        t0 = time.perf_counter()
        run = subprocess.run([str(Path(sys.executable).parent / "rodcad"), "build", str(path), "-o", str(out)],
                             capture_output=True, text=True)
        dt = time.perf_counter() - t0
        target = out if run.returncode == 0 else Path(f"{out}.best-fit")
        if not (target / "design.json").exists():
            why = (run.stderr.strip().splitlines() or [""])[-1][:120].replace("|", "/")
            print(f"| {name} | - | - | - | exit {run.returncode}: {why} | - | {dt:.0f} |", flush=True)
            continue
        d = json.loads((target / "design.json").read_text())
        n, rows, zs = pauses(d)
        err = (d.get("as_built") or {}).get("error", {}).get("max_mm")
        mark = "" if run.returncode == 0 else f" (exit {run.returncode}, best fit)"
        print(f"| {name}{mark} | {len(d['rods'])} | {rows} | {n} | {', '.join(f'{z:g}' for z in zs)} | "
              f"{'-' if err is None else f'{err:.2g}'} | {dt:.0f} |", flush=True)


if __name__ == "__main__":
    main()
