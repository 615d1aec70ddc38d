"""Rods drawn a little too close for the largest hub, or a little too short for the shortest
rod, are made buildable by moving nodes within the tolerance (issue 33,
:mod:`rodcad.design.net.spread`), not refused; what needs more is still refused naming the
hub that would hold it; and a net the solver cannot hang says what would.

Truth: the angle between two rods and an edge's length from the node points themselves (not
the planner's numbers), bounds on the least move from the geometry of a turning rod, the
fit measured against the points as drawn.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rodcad.catalog.loader import load_catalog
from rodcad.design.net.choose import design_drawn_net
from rodcad.design.net.plan import plan_net
from rodcad.design.net.spread import MARGIN_DEG, SPREAD_SHARE, spread_tight
from rodcad.design.net.target import NetTarget
from rodcad.errors import DesignLimit
from rodcad.outputs.net.report import planner_summary

L = 60.0  # the two rods' length (mm)


@pytest.fixture(scope="module")
def cat():
    return load_catalog("pla-parametric")


def _vee(angle_deg: float) -> NetTarget:
    """A narrow V hung from two anchors: free node 0 at the bottom, its two rods to free nodes
    1 and 2 ``angle_deg`` apart, each of those hung by a steeper rod from an anchor (3, 4)."""
    h = math.radians(angle_deg) / 2
    x = np.array([[0.0, 0.0, 0.0], [L * math.sin(h), 0.0, L * math.cos(h)], [-L * math.sin(h), 0.0, L * math.cos(h)]])
    x = np.vstack([x, x[1] + [4.0, 0.0, 55.0], x[2] + [-4.0, 0.0, 55.0]])
    return NetTarget("nodes", x, np.array([[0, 1], [0, 2], [1, 3], [2, 4]]), np.array([3, 4]))


def _angle(p: np.ndarray, q: int, i: int, j: int) -> float:
    u, v = p[i] - p[q], p[j] - p[q]
    return math.degrees(math.acos(u @ v / (np.linalg.norm(u) * np.linalg.norm(v))))


def test_rods_a_little_too_close_are_spread_by_the_least_move_and_the_fit_counts_it(cat):
    hw = cat.node
    limit = hw.sized(hw.pivot_limits[1]).min_angle_deg
    short_by = 0.4
    t = _vee(limit - short_by)
    with pytest.raises(DesignLimit, match="largest hub allows"):  # the last resort, not taken when asked not to
        plan_net(t, cat, spread=False)
    plan = plan_net(t, cat)
    p = plan.target.positions
    assert _angle(p, 0, 1, 2) >= limit + MARGIN_DEG - 1e-6
    assert plan.hub(0).problems() == []
    moved = {k: mm for k, mm in plan.spread}
    assert set(moved) <= {0, 1, 2} and moved  # anchors stay
    np.testing.assert_array_equal(p[3:5], t.positions[3:5])
    worst = max(moved.values())
    # the least move: turning both rods by half the angle wanted moves their far ends by at most
    # L x (want - drawn) / 2; no move under a quarter of that opens the angle so far
    want = math.radians(short_by + MARGIN_DEG)
    assert L * want / 4 * (1 - 1e-3) <= worst <= L * want / 2 * (1 + 1e-3)
    assert worst <= SPREAD_SHARE * 0.01 * t.size
    for k, mm in moved.items():
        assert mm == pytest.approx(float(np.linalg.norm(p[k] - t.positions[k])), rel=1e-9)
    # the fit is against the points drawn, so a node moved is a node off its target
    nodes, points = plan.target.fit_pairs
    drawn = nodes < 5
    np.testing.assert_allclose(points[drawn], t.positions[nodes[drawn]])
    assert "moved up to" in planner_summary(plan)
    check = design_drawn_net(t, cat, seed=0)
    assert check.ok, check.limit()
    assert check.error_mm >= worst - 1e-6
    assert check.rel_size <= check.tolerance


def test_rods_far_too_close_are_refused_naming_the_hub(cat):
    t = _vee(15.0)
    out, moved = spread_tight(t, cat.node, SPREAD_SHARE * 0.01 * t.size)
    assert out is t and moved.size == 0
    with pytest.raises(DesignLimit, match=r"pivot radius .* mm \(diameter .* node\.pivot_radius\.max"):
        plan_net(t, cat)


def test_an_edge_a_little_short_is_lengthened_and_the_angles_kept(cat):
    hw = cat.node
    t = _vee(60.0)
    need = np.zeros(t.m)
    d0 = t.edge_lengths[2]
    need[2] = d0 + 0.3  # the rod from node 1 to its anchor must be 0.3 mm longer
    out, moved = spread_tight(t, hw, 1.0, least_length=need)
    assert moved.tolist() == [1]  # only node 1 is free on that edge; its move is the least: 0.3 mm
    d = out.edge_lengths
    assert d[2] >= d0 + 0.3 - 1e-6
    assert float(np.linalg.norm(out.positions[1] - t.positions[1])) == pytest.approx(0.3, rel=1e-3)
    assert _angle(out.positions, 0, 1, 2) >= hw.sized(hw.pivot_limits[1]).min_angle_deg
    # beyond the budget: left as drawn
    need[2] = d0 + 5.0
    same, none = spread_tight(t, hw, 1.0, least_length=need)
    assert same is t and none.size == 0


def test_a_net_the_solver_cannot_hang_says_why_the_masses_could_not(cat):
    """Where the designed net has no equilibrium, the exit line leads with the statics' reason (the
    nodes whose rods cannot hold them, and what would), then what the solver did not find, with no
    'inf %' (as on the level-3 icosphere halves, whose solves stop at the iteration limit)."""
    import dataclasses

    check = design_drawn_net(_vee(60.0), cat, seed=0)
    lost = dataclasses.replace(check.design.equilibrium, success=False, message="Iteration limit reached.")
    failed = dataclasses.replace(check, design=dataclasses.replace(check.design, equilibrium=lost),
                                 why="No masses at all balance this target: move node 0.")
    line = failed.limit()
    assert line.startswith("cannot rest on its target (tolerance 1 %): No masses at all balance this target: move "
                           "node 0. With the best fit's masses")
    assert line.endswith("did not find where it comes to rest (Iteration limit reached.)") and "inf" not in line
    alone = dataclasses.replace(failed, why="").limit()
    assert alone.startswith("could not be solved") and alone.endswith("(Iteration limit reached.)")


def test_the_spread_is_bounded(cat, monkeypatch):
    """More tight nodes than the spread moves at once: the net is left as drawn, not searched
    without bound."""
    import rodcad.design.net.spread as spread

    hw = cat.node
    t = _vee(hw.sized(hw.pivot_limits[1]).min_angle_deg - 0.4)
    assert spread_tight(t, hw, 10.0)[1].size  # three free nodes: spread
    monkeypatch.setattr(spread, "MAX_MOVED", 2)
    out, moved = spread_tight(t, hw, 10.0)
    assert out is t and moved.size == 0
