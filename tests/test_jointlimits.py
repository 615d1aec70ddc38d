"""The fast joint-limit function against the exact B-rep interference search.

:func:`rodcad.catalog.jointlimits.joint_limits` computes a pair's limits from the end
geometry in the chain plane. It must never allow more bend than the solids, and stay
within 0.05 degrees of the B-rep search: on every pair of both shipped catalogs (straight,
curved, free, flush, convex and concave ends) and on random parameter points.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from rodcad.catalog.jointlimits import SAFETY_DEG, joint_limits
from rodcad.catalog.limits import TOLERANCE_DEG, all_pair_limits, compute_pair_limits
from rodcad.catalog.loader import load_catalog
from rodcad.catalog.model import EndShape

CHECK = Path(__file__).with_name("data") / "pla-weighted.check.json"
#: The B-rep search brackets each contact to TOLERANCE_DEG and reports the middle.
BREP_SLACK = TOLERANCE_DEG / 2 + 1e-9


def _agrees(fast, brep, where):
    for side, (a, b) in enumerate(zip(fast, brep)):
        assert (a is None) == (b is None), (where, fast, brep)
        if a is None:
            continue
        assert abs(a - b) <= 0.05, (where, side, a, b)
        looser = b - a if side == 0 else a - b  # more bend than the solids allow
        assert looser <= BREP_SLACK, (where, side, a, b)


def test_every_pair_of_pla_weighted_agrees_with_the_solids():
    cat = load_catalog("pla-weighted")
    pairs = json.loads(CHECK.read_text())["pairs"]
    assert len(pairs) == len(cat) ** 2
    worst = 0.0
    for p in pairs:
        fast = joint_limits(cat[p["left"]].geometry, cat[p["right"]].geometry)
        _agrees(fast, p["limits_deg"], (p["left"], p["right"]))
        worst = max(worst, max(abs(a - b) for a, b in zip(fast, p["limits_deg"]) if a is not None))
    assert worst <= SAFETY_DEG + 0.003  # the B-rep table is rounded to 1e-3 deg


def test_every_pair_of_pla_pinned_agrees_with_the_solids():
    """pla-pinned has curved (arc) rods and concave stops on both ends."""
    cat = load_catalog("pla-pinned")
    brep = all_pair_limits(cat, jobs=2)  # from the B-rep search (the shipped seeds, checked by test_seed_cache)
    assert any(t.curvature != 0 for t in cat)
    for (left, right), r in brep.items():
        assert r.assemblable
        _agrees(joint_limits(cat[left].geometry, cat[right].geometry), r.limits_deg, (left, right))


def test_flush_stops_meet_at_the_sum_of_their_chamfers_and_half_angles():
    """What lets a stop angle be printed to order: flush faces (setback 0) with top
    chamfers c1, c2 on rods whose arcs end at half angles psi1, psi2 stop at
    c1 + c2 + psi1 + psi2 (the chord bend at which the end tangents meet at c1 + c2)."""
    base = load_catalog("pla-weighted")["straight-30"].geometry
    rng = np.random.default_rng(0)
    for _ in range(12):
        c1, c2 = rng.uniform(-12, 20, 2)
        k1, k2 = rng.choice([0.0, 0.004, -0.004, 0.008], 2)
        left = replace(base, curvature=float(k1), second=EndShape(0.0, float(c1), 55.0))
        right = replace(base, curvature=float(k2), first=EndShape(0.0, float(c2), 55.0))
        hi = joint_limits(left, right)[1]
        want = c1 + c2 + left.half_angle_deg + right.half_angle_deg
        assert hi == pytest.approx(want - SAFETY_DEG, abs=1e-4), (c1, c2, k1, k2)


@pytest.mark.parametrize("seed", range(8))
def test_random_end_geometries_agree_with_a_fresh_b_rep_search(seed):
    """Parameter points no catalog ships: setbacks, chamfers and curvatures at random."""
    base = load_catalog("pla-weighted")["free-30"].geometry
    rng = np.random.default_rng(100 + seed)

    def end():
        return EndShape(float(rng.choice([0.0, rng.uniform(0.1, 2.0)])), float(rng.uniform(-15, 45)),
                        float(rng.uniform(20, 45)))

    left = replace(base, length=40.0, curvature=float(rng.choice([0.0, rng.uniform(-0.01, 0.01)])), second=end())
    right = replace(base, length=40.0, curvature=float(rng.choice([0.0, rng.uniform(-0.01, 0.01)])), first=end())
    brep = compute_pair_limits(left, right, 1.2)
    assert brep["assemblable"]
    _agrees(joint_limits(left, right), (brep["lo"], brep["hi"]), seed)


def test_it_is_fast():
    import time

    cat = load_catalog("pla-pinned")
    g = cat["arc-30"].geometry
    t0 = time.perf_counter()
    for _ in range(5):
        joint_limits(g, g)
    assert (time.perf_counter() - t0) / 5 < 0.5  # about 20 ms; the B-rep search takes about 1 s
    assert math.isfinite(joint_limits(g, g)[1])
