"""Shapes people draw (issue 24): the default catalog and no constraints, as a newcomer writes them.

    python benchmarks/bench_drawn.py [--n 200] [--seed 0] [--parallel 1] [--timeout 60] [--kinds heart,drop]

Every shape of :func:`drawn_shapes.family` (closed outlines hung from two points near their
top, open curves with concave bends) is written as a plain polyline design file and built
with ``rodcad build FILE -o OUT --no-cad -q`` in its own process (a wall-clock timeout
catches a run that does not end). Per shape: the exit code, the time, and how far the
hanging rods' centrelines are from the drawn curve over the target's size (the larger of
span, width and height), read from OUT/design.json, or OUT.best-fit/design.json for an
exit 1. The promise: each shape either hangs within 1 % of its size (exit 0) or exits 1
with its reason; none exits 0 further off, no traceback, no internal error, none over 60 s.

Prints a table per shape kind and the distribution (median, 90th percentile, worst, share
of exit 1, time).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from drawn_shapes import KINDS, design_text, family  # noqa: E402

TOLERANCE = 0.01


def run_one(shape, folder: Path, timeout: float) -> dict:
    """Build one shape; its exit code, time, fit over size and the first line of stderr."""
    design = folder / f"{shape.name}.yaml"
    design.write_text(design_text(shape), encoding="utf-8")
    out = folder / shape.name
    t0 = time.perf_counter()
    try:
        p = subprocess.run([sys.executable, "-m", "rodcad.cli", "build", str(design), "-o", str(out), "--no-cad",
                            "-q"], capture_output=True, text=True, timeout=timeout)
        code, err = p.returncode, p.stderr
    except subprocess.TimeoutExpired:
        code, err = "timeout", ""
    dt = time.perf_counter() - t0
    fit = None
    for folder_ in (out, out.with_name(out.name + ".best-fit")):
        j = folder_ / "design.json"
        if j.is_file():
            data = json.loads(j.read_text())
            fit = data["curve"]["max_mm"] / shape.size
            break
    lines = [ln for ln in err.splitlines() if ln.strip()]
    return dict(name=shape.name, kind=shape.kind, code=code, time=dt, fit=fit,
                traceback="Traceback" in err, internal="internal error" in err,
                why=lines[-1][:160] if lines else "")


def verdict(r: dict) -> str:
    """ok: within 1 % (exit 0); honest: exit 1 with a reason; BAD otherwise."""
    if r["code"] == 0:
        return "ok" if r["fit"] is not None and r["fit"] <= TOLERANCE * (1 + 1e-9) else "BAD exit 0, off"
    if r["code"] == 1 and not r["internal"] and not r["traceback"]:
        return "honest exit 1"
    if r["code"] == "timeout":
        return "BAD timeout"
    return f"BAD exit {r['code']}" + (" internal" if r["internal"] else "")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--parallel", type=int, default=1, help="shapes built at once (1 for honest times)")
    ap.add_argument("--timeout", type=float, default=60.0)
    ap.add_argument("--kinds", default="", help="only these kinds (comma-separated)")
    ap.add_argument("--json", type=Path, help="write every row to this file")
    args = ap.parse_args()
    shapes = family(args.n, args.seed)
    if args.kinds:
        keep = set(args.kinds.split(","))
        shapes = [s for s in shapes if s.kind in keep]
    print(f"# bench_drawn: {len(shapes)} shapes (seed {args.seed}), {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} CPUs, {time.strftime('%Y-%m-%d')}, parallel {args.parallel}")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        with ThreadPoolExecutor(args.parallel) as pool:
            rows = list(pool.map(lambda s: run_one(s, folder, args.timeout), shapes))
    print(f"\n| shape | exit | fit / size | time s | verdict | last line of stderr |\n|---|---|---|---|---|---|")
    for r in rows:
        fit = "-" if r["fit"] is None else f"{100 * r['fit']:.3g} %"
        print(f"| {r['name']} | {r['code']} | {fit} | {r['time']:.1f} | {verdict(r)} | {r['why']} |")
    print("\n| kind | shapes | within 1 % | exit 1 | bad | median fit | worst fit | max time s |\n"
          "|---|---|---|---|---|---|---|---|")
    for kind in [k for k in KINDS if any(r["kind"] == k for r in rows)] + ["all"]:
        rs = [r for r in rows if kind in ("all", r["kind"])]
        fits = [r["fit"] for r in rs if r["fit"] is not None]
        ok = sum(verdict(r) == "ok" for r in rs)
        ex1 = sum(verdict(r) == "honest exit 1" for r in rs)
        bad = sum(verdict(r).startswith("BAD") for r in rs)
        med = f"{100 * statistics.median(fits):.3g} %" if fits else "-"
        worst = f"{100 * max(fits):.3g} %" if fits else "-"
        print(f"| {kind} | {len(rs)} | {ok} | {ex1} | {bad} | {med} | {worst} | {max(r['time'] for r in rs):.1f} |")
    fits = np.array([r["fit"] for r in rows if r["fit"] is not None])
    times = np.array([r["time"] for r in rows])
    if fits.size:
        print(f"\nfit / size over all shapes: median {100 * np.median(fits):.3g} %, 90th percentile "
              f"{100 * np.percentile(fits, 90):.3g} %, worst {100 * fits.max():.3g} %; exit 1: "
              f"{sum(r['code'] == 1 for r in rows)} of {len(rows)}; time median {np.median(times):.1f} s, "
              f"90th percentile {np.percentile(times, 90):.1f} s, max {times.max():.1f} s")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
