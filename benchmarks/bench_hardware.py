"""Joint hardware per example: the friction band and the share of free joints with the
planner's choice of pins, bushings and bearings, against every joint on the family's own pin
(the hardware before the choice existed), both at the top of the parts' friction ranges.

    python benchmarks/bench_hardware.py [EXAMPLE ...]

Each example is designed without CAD (`pipeline.build(cad=False)`), once with the catalog's
menu and once with a menu of the family's own pin alone. Columns: the target's size (mm), the
friction band (mm and % of the size), the joints that hang freely (not resting on a stop at
the design) out of the interior joints, the hardware used, and the design time.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from rodcad import pipeline  # noqa: E402
from rodcad.catalog.pins import PinMenu  # noqa: E402
from rodcad.design.loader import load_design  # noqa: E402
from rodcad.design.shell import curve_size  # noqa: E402

EXAMPLES = ["semicircle", "necklace", "heart", "garland", "garland-rise", "semicircle-menu", "semicircle-weights",
            "triangle", "polygon", "catenary"]


def row(name: str, own_pin_only: bool) -> str:
    d = load_design(ROOT / "examples" / f"{name}.yaml")
    if own_pin_only:
        menu = d.catalog.pins
        d = dataclasses.replace(d, catalog=dataclasses.replace(d.catalog, pins=PinMenu((menu.base,), menu.safety,
                                                                                       menu.pressure, menu.base.name)))
    t0 = time.perf_counter()
    r = pipeline.build(d, cad=False)
    dt = time.perf_counter() - t0
    size = curve_size(r.plan.curve)
    fb = r.as_printed.friction if r.as_printed is not None else None
    band = float("nan") if fb is None else fb.band
    free = int(np.sum(r.equilibrium.active == 0)) if r.n > 1 else 0
    used = Counter(o.name for o in r.hardware.options if o is not None) if r.hardware is not None else {}
    parts = ", ".join(f"{c} {k}" for k, c in used.items())
    return (f"{name:20s} {'own pin' if own_pin_only else 'chosen':8s} {size:7.1f} | {band:7.3f} {100 * band / size:7.3f}% "
            f"| {free:3d}/{r.n - 1:<3d} {100 * free / max(r.n - 1, 1):5.0f}% | {dt:6.1f} s | {parts}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("examples", nargs="*", default=EXAMPLES)
    args = ap.parse_args()
    print(f"{'example':20s} {'hardware':8s} {'size mm':>7s} | {'band mm':>7s} {'% size':>8s} | {'free':>7s} {'share':>5s} "
          f"| {'time':>8s} | parts")
    for name in args.examples:
        for own in (True, False):
            print(row(name, own), flush=True)


if __name__ == "__main__":
    main()
