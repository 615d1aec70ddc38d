"""Drawn strips whose hubs weigh unevenly (issue 33's weighed hubs, :mod:`rodcad.design.net.weights`):
a seeded sample of strips with zig-zag diagonals hung from their two ends (the drawn-net family's
generator, :func:`net_family._strip`, with its own seed and ranges), each designed with the
default catalog and no switches, then again with the weighing step left out. A row per strip:
its size, the outcome and fit each way, the hubs the weighing grew, seconds.

    PYTHONPATH=. python benchmarks/weighed_strips.py [--seed 7] [--n 16]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import net_family  # noqa: E402

from rodcad.design.loader import load_design  # noqa: E402
from rodcad.errors import DesignLimit  # noqa: E402


def _design(path: Path, weigh: bool):
    import rodcad.design.net.choose as choose
    from rodcad.pipeline.net import build_net

    kept = choose.weigh_hubs
    if not weigh:
        choose.weigh_hubs = lambda check, *a, **k: check
    t0 = time.perf_counter()
    try:
        c = build_net(load_design(path)).check
        return c, time.perf_counter() - t0
    except DesignLimit as err:
        return str(err), time.perf_counter() - t0
    finally:
        choose.weigh_hubs = kept


def _cell(c) -> str:
    if isinstance(c, str):
        return "refused"
    return f"{'designed' if c.ok else 'exit 1'} {100 * c.rel_size:.3g} %"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--n", type=int, default=16)
    a = ap.parse_args(argv)
    rng = np.random.default_rng(a.seed)
    print("| strip | L x W mm, bays, sag | without weighing | with (default) | hubs grown | s (without / with) |")
    print("|---|---|---|---|---|---:|")
    counts = {"without": 0, "with": 0}
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(a.n):
            L, W = float(rng.uniform(150, 640)), float(rng.uniform(20, 90))
            bays = int(np.clip(round(L / net_family._edge(rng)), 4, 12))
            sag = float(L * rng.uniform(0.08, 0.3))
            m = net_family._strip(None, i, (L, W, bays, sag, True))
            path = Path(tmp) / f"{m.name}.yaml"
            path.write_text(m.yaml)
            off, s_off = _design(path, False)
            on, s_on = _design(path, True)
            note = "" if isinstance(on, str) else next((n for n in on.notes if "to weigh more" in n), "")
            grown = note.split(" are larger")[0] if note else ""
            counts["without"] += int(not isinstance(off, str) and off.ok)
            counts["with"] += int(not isinstance(on, str) and on.ok)
            print(f"| {m.name} | {L:.0f} x {W:.0f}, {bays}, {sag:.0f} | {_cell(off)} | {_cell(on)} | {grown} | "
                  f"{s_off:.1f} / {s_on:.1f} |", flush=True)
    print(f"\ndesigned within 1 %: {counts['without']} of {a.n} without weighing, {counts['with']} with")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
