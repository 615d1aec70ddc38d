"""Benchmark of a net's full CAD build (issue 33, light output), printing a table.

Runs ``rodcad build DESIGN -o OUT`` in a fresh process (the whole command: design, solids,
checks, STEP/STL/3MF, report, 3D view) from a source tree (default: this checkout; pass
``--source DIR`` for another, e.g. an exported older commit to compare with), times it, and
sums the bytes written per file type. Extra arguments after ``--`` go to ``rodcad build``
(``--jobs 2``, ``--scheduler ADDRESS``).

Usage:
    python benchmarks/bench_net_cad.py [--design benchmarks/data/grid8.yaml] [--source DIR]
        [--out /tmp/bench-net-cad] [-- --jobs 2]

Target (issue 33): the 8 x 8 grid's build writes at most a tenth of the bytes of the build
before the issue, in at most half its time, on 2 cores.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def sizes(folder: Path) -> tuple[Counter, Counter]:
    """(bytes, files) per file suffix under ``folder``."""
    b, n = Counter(), Counter()
    for p in folder.rglob("*"):
        if p.is_file():
            b[p.suffix or p.name] += p.stat().st_size
            n[p.suffix or p.name] += 1
    return b, n


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    extra: list[str] = []
    if "--" in argv:
        k = argv.index("--")
        argv, extra = argv[:k], argv[k + 1:]
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--design", default=str(ROOT / "benchmarks" / "data" / "grid8.yaml"))
    ap.add_argument("--source", default=str(ROOT), help="source tree to run rodcad from")
    ap.add_argument("--out", default="/tmp/bench-net-cad", help="output folder (replaced)")
    args = ap.parse_args(argv)
    out = Path(args.out)
    if out.exists():
        shutil.rmtree(out)
    env = dict(os.environ, PYTHONPATH=str(Path(args.source).resolve()))
    cmd = [sys.executable, "-c", "import sys; from rodcad.cli import main; sys.exit(main())",
           "build", str(Path(args.design).resolve()), "-o", str(out), *extra]
    t = time.perf_counter()
    proc = subprocess.run(cmd, env=env, cwd=str(Path(args.source).resolve()), capture_output=True, text=True)
    wall = time.perf_counter() - t
    if proc.returncode != 0:
        print(proc.stdout[-3000:], proc.stderr[-3000:], sep="\n")
        print(f"rodcad build exited {proc.returncode}")
        return 1
    b, n = sizes(out)
    data = json.loads((out / "design.json").read_text())
    bom = data.get("cad", {}).get("parts")
    print(f"# {Path(args.design).name} from {args.source} {' '.join(extra)}")
    print(f"# {platform.node()} {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
          f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}")
    print(f"{'type':<10} {'files':>6} {'MB':>10}")
    for suffix in sorted(b, key=lambda s: -b[s]):
        print(f"{suffix:<10} {n[suffix]:>6} {b[suffix] / 1e6:>10.3f}")
    print(f"{'total':<10} {sum(n.values()):>6} {sum(b.values()) / 1e6:>10.3f}")
    print(f"wall time {wall:.1f} s")
    if bom is not None:
        print(f"distinct printed parts {len(bom)}, printed {sum(p['count'] for p in bom)} times in all")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
