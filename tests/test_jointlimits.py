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

import rodcad.catalog.jointlimits as jl
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


def _plain_march(left, right, bound=180.0):
    """The search without its quick tests: the full overlap test at every 1-degree step of
    the march, then the same bisection (what joint_limits must return, to the bit)."""
    pair = jl._Pair(left, right)
    mid = (left.half_angle_deg + right.half_angle_deg
           + (left.second.top_chamfer + right.first.top_chamfer
              - left.second.bottom_chamfer - right.first.bottom_chamfer) / 2)
    start = next(s for s in [mid, 0.0] + [s * k * 5.0 for k in range(1, 36) for s in (1, -1)]
                 if not pair.overlaps(s))
    out = []
    for direction in (-1.0, 1.0):
        a = start
        while True:
            b = a + direction * jl.MARCH_DEG
            if abs(b) >= bound:
                b = direction * bound
                if not pair.overlaps(b):
                    out.append(None)
                    break
            if pair.overlaps(b):
                while abs(b - a) > jl.BISECT_DEG:
                    m = (a + b) / 2
                    a, b = (a, m) if pair.overlaps(m) else (m, b)
                out.append(a)
                break
            a = b
    lo, hi = out
    return (None if lo is None else lo + SAFETY_DEG, None if hi is None else hi - SAFETY_DEG)


@pytest.mark.parametrize("seed", range(3))
def test_the_quick_tests_change_no_limit(seed):
    """The march's quick tests (strides over steps proved clear, thinned samples against a
    grown outline) only skip steps the full test would pass: the limits are the plain
    march's, to the bit, on the family's end-of-range pairs (``sample_pairs``: stops at the
    ends of the stop range, graduated rods) and on random rods printed to order (lengths,
    curvatures, scales, top and bottom stops)."""
    from rodcad.catalog.geometry import max_curvature
    from rodcad.catalog.printed import sample_pairs

    cat = load_catalog("pla-parametric")
    fam = cat.printed_families[0]
    rng = np.random.default_rng(200 + seed)
    pairs = [(a.geometry, b.geometry) for a, b in sample_pairs(cat, fam)] if seed == 0 else []
    for _ in range(6):
        length = [float(rng.uniform(30, 60)) for _ in range(2)]
        k = [float(rng.uniform(-1, 1) * max_curvature(x)) for x in length]
        s = [float(rng.uniform(0.6, 1.4)) for _ in range(2)]
        kind = rng.integers(3)
        c = float(rng.uniform(-40, 40))
        ends = [{}, {}] if kind == 0 else ([{"second_stop": c}, {"first_stop": c}] if kind == 1 else
                                          [{"second_under": -abs(c) / 2}, {"first_under": -abs(c) / 2}])
        try:
            a = cat.rod(fam.name, length[0], k[0], scale=s[0], **ends[0])
            b = cat.rod(fam.name, length[1], k[1], scale=s[1], **ends[1])
        except ValueError:  # a scale this rod's length cannot take
            continue
        pairs.append((a.geometry, b.geometry))
    assert len(pairs) >= 4
    for left, right in pairs:
        try:
            want = _plain_march(left, right)
        except StopIteration:  # overlapping at every start: joint_limits says so
            with pytest.raises(ValueError):
                joint_limits(left, right)
            continue
        assert joint_limits(left, right) == want


def test_a_pair_takes_few_full_tests():
    """What the quick tests are for (counted, not timed): a pair needs about the bisection's
    full tests, not a full test at every degree of the march."""
    cat = load_catalog("pla-pinned")
    g = cat["arc-30"].geometry
    calls = [0]
    full = jl._Pair.overlaps

    def counted(self, phi, near=None):
        calls[0] += 1
        return full(self, phi, near)

    jl._Pair.overlaps = counted
    try:
        got = joint_limits(g, g)
    finally:
        jl._Pair.overlaps = full
    assert got == _plain_march(g, g) and math.isfinite(got[1])
    assert calls[0] < 120


@pytest.mark.parametrize("name", ["arc-30", "straight-40"])
def test_the_samples_near_a_contact_decide_as_all_of_them(name):
    """The bisection tests only the samples that can reach the other outline within its
    bracket (:meth:`_Pair.near`): over the degree before each contact, and past it, they
    overlap exactly where all the samples do, and they are a small part of them."""
    g = load_catalog("pla-pinned")[name].geometry
    pair = jl._Pair(g, g)
    for limit, sign in zip(joint_limits(g, g), (-1.0, 1.0)):
        if limit is None:
            continue
        contact = limit + sign * jl.SAFETY_DEG
        a, b = contact - sign * 1.0, contact + sign * 0.5
        near = pair.near(a, b - a)
        assert 0 < len(near[0]) + len(near[1]) < 0.2 * (len(pair.right_pts) + len(pair.left_pts))
        decided = [(pair.overlaps(m, near), pair.overlaps(m)) for m in np.linspace(a, b, 61)]
        assert all(x == y for x, y in decided) and decided[0] == (False, False) and decided[-1] == (True, True)
