"""Every chain example planned again with its anchors and target perturbed by 1e-12 (relative),
as another CPU's floating point might, for several seeds, and built twice: the sweep behind
tests/test_determinism.py (which runs a seeded sample of the examples). A row per example and
seed: whether the discrete choices held, how far the joints and masses moved, and whether two
runs wrote the same design.json.

    python benchmarks/bench_determinism.py [--seeds 1 2 3]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from perturb import CHAIN_EXAMPLES as EXAMPLES  # noqa: E402
from perturb import choice_differences, perturbed  # noqa: E402

from rodcad import pipeline  # noqa: E402
from rodcad.design.loader import load_design  # noqa: E402

#: The joints may move by the perturbation amplified by the chord walk; masses by 1e-5.
MOVE_TOL, MASS_TOL = 1e-8, 1e-5


def _design_json(example: Path, out: Path) -> str:
    written = pipeline.run(load_design(example), out, cad=False)
    data = json.loads((written.outdir / "design.json").read_text())
    data.pop("time_s", None)
    data.get("inverse", {}).pop("time_s", None)
    return json.dumps(data, sort_keys=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    args = ap.parse_args(argv)
    print("| example | seed | choices | joints moved (of span) | masses moved | design.json twice | s |")
    print("|---|---|---|---|---|---|---|")
    bad = 0
    with tempfile.TemporaryDirectory() as tmp:
        for example in EXAMPLES:
            t0 = time.perf_counter()
            text = example.read_text()
            base = pipeline.build(load_design(example), cad=False)
            same = _design_json(example, Path(tmp) / f"{example.stem}-a") == \
                _design_json(example, Path(tmp) / f"{example.stem}-b")
            for seed in args.seeds:
                r = pipeline.build(load_design(example, text=perturbed(text, 1e-12, seed)), cad=False)
                changed, move, mass = choice_differences(base, r)
                ok = not changed and move <= MOVE_TOL and mass <= MASS_TOL and same
                bad += not ok
                print(f"| {example.stem} | {seed} | {'held' if not changed else ', '.join(changed) + ' changed'} | "
                      f"{move:.2g} | {mass:.2g} | {'same' if same else 'DIFFERENT'} | "
                      f"{time.perf_counter() - t0:.1f} |", flush=True)
    print(f"\n{len(EXAMPLES) * len(args.seeds) - bad} of {len(EXAMPLES) * len(args.seeds)} held "
          f"(joints within {MOVE_TOL:g} of the span, masses within {MASS_TOL:g}, design.json the same)")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
