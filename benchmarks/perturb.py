"""Designs perturbed as another CPU's floating point might perturb them (issue 34's determinism
checks): shared by tests/test_determinism.py (a seeded sample of the examples) and
benchmarks/bench_determinism.py (every example, several seeds)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

__all__ = ["CHAIN_EXAMPLES", "COUNTS", "choice_differences", "perturbed"]

#: The chain examples (nets: tests/test_net_build.py; the chandelier: tests/test_chandelier.py;
#: chain.yaml is for ``rodcad simulate``).
CHAIN_EXAMPLES = sorted(p for p in (Path(__file__).resolve().parents[1] / "examples").glob("*.yaml")
                        if p.stem not in ("chain", "chandelier") and "\nnet:" not in p.read_text())

#: Keys whose numbers are counts or code, not measures (left as they are).
COUNTS = ("sides", "samples", "rods", "count", "seed", "design", "y")  # y: an expression

NUMBER = re.compile(r"(?<![\w.])-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?(?![\w.])")


def perturbed(text: str, rel: float, seed: int) -> str:
    """The design text with every number of its anchors and target block scaled by
    1 + rel * N(0, 1) (zeros stay zero)."""
    rng = np.random.default_rng(seed)
    out, in_target = [], False
    for line in text.splitlines():
        body = line.split("#", 1)[0]
        key = body.strip().split(":", 1)[0]
        if not line.startswith((" ", "\t")):
            in_target = key == "target"
        if (key == "anchors" or in_target) and key not in COUNTS:
            body = NUMBER.sub(lambda m: repr(float(m.group(0)) * (1 + rel * rng.standard_normal())), body)
            line = body + ("#" + line.split("#", 1)[1] if "#" in line else "")
        out.append(line)
    return "\n".join(out) + "\n"


def choice_differences(base, r) -> tuple[list[str], float, float]:
    """How a perturbed build ``r`` differs from ``base`` (two chain BuildResults): (the discrete
    choices that changed, the largest joint move over the span, the largest relative mass change).
    The choices are the rod types, the joints on stops, the lengths (to 1e-9) and stability."""
    span = float(np.hypot(*np.subtract(*base.design.anchors)))
    changed = []
    if r.type_names != base.type_names:
        changed.append("rod types")
    if r.plan.added_stops != base.plan.added_stops:
        changed.append("joints on stops")
    if len(r.lengths) != len(base.lengths) or not np.allclose(r.lengths, base.lengths, rtol=1e-9, atol=0):
        changed.append("lengths")
    if r.equilibrium.stable != base.equilibrium.stable:
        changed.append("stability")
    if changed:
        return changed, float("inf"), float("inf")
    move = float(np.max(np.abs(r.equilibrium.points - base.equilibrium.points))) / span
    mass = float(np.max(np.abs(np.asarray(r.masses) / np.asarray(base.masses) - 1)))
    return changed, move, mass
