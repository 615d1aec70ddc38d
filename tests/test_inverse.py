"""Inverse design: exact where physics allows, bounded best fit where fabrication limits."""

from __future__ import annotations

import numpy as np
import pytest

from optimize import solve_equilibrium
from optimize.chain.assign import assign_types, joint_mismatch
from optimize.chain.discretize import discretize
from optimize.chain.inverse import InverseProblem, design, statics_matrix


def reachable_problem(seed=0, n=12, com_perp=0.0):
    rng = np.random.default_rng(seed)
    lengths = np.full(n, 30.0)
    m_true = rng.uniform(2, 8, n)
    com = np.column_stack([lengths / 2, com_perp * lengths * rng.uniform(-1, 1, n)])
    eq = solve_equilibrium(lengths, m_true, (0, 0), (250, 20), com=com)
    return InverseProblem(eq.points, lengths, np.tile([1.0, 10.0], (n, 1)), com=com), m_true


@pytest.mark.parametrize("perp", [0.0, 0.08])
def test_reachable_target_recovered_exactly(perp):
    prob, m_true = reachable_problem(com_perp=perp)
    for method in ("exact", "refine"):
        res = design(prob, method)
        assert res.exact and res.success, res.message
        assert res.distance.max_rel_span < 1e-12
        assert res.statics_residual < 1e-12
        lo, hi = prob.mass_bounds.T
        assert np.all(res.masses >= lo) and np.all(res.masses <= hi)
        # the true masses satisfy the same statics: masses are determined up to the
        # statics' null space (scale plus one free parameter for free joints)
        A, _, _ = statics_matrix(prob)
        for m in (res.masses, m_true):
            x = np.linalg.lstsq(A[:, prob.n:], -A[:, :prob.n] @ m, rcond=None)[0]
            assert np.abs(A[:, :prob.n] @ m + A[:, prob.n:] @ x).max() < 1e-9 * np.abs(A).max() * m.sum()


def test_exact_is_fast_and_refine_not_needed():
    prob, _ = reachable_problem(n=40, seed=3)
    res = design(prob, "refine")
    assert res.exact and res.time_s < 0.1 and res.nfev <= 2


def semicircle_problem(n=16, bounds=(1.0, 30.0)):
    ang = np.linspace(np.pi, 2 * np.pi, n + 1)
    pts = 100 * np.column_stack([np.cos(ang), np.sin(ang)])
    chord = 200 * np.sin(np.pi / n / 2)
    return InverseProblem(pts, np.full(n, chord), np.tile(bounds, (n, 1)))


def test_semicircle_bounded_best_fit_refine_beats_exact_start():
    prob = semicircle_problem()
    start = design(prob, "exact")
    ref = design(prob, "refine", max_nfev=300)
    assert not ref.exact
    assert ref.distance.max_rel_span < 0.5 * start.distance.max_rel_span
    assert np.any(ref.at_bounds != 0)  # fabrication limits are what stops it
    assert "best fit" in ref.message and "bound" in ref.message


def test_wide_bounds_make_the_semicircle_nearly_reachable():
    tight = design(semicircle_problem(bounds=(1.0, 30.0)), "refine", max_nfev=300)
    wide = design(semicircle_problem(bounds=(1.0, 3000.0)), "refine", max_nfev=300)
    assert wide.distance.max_rel_span < 0.2 * tight.distance.max_rel_span


def test_concave_target_needs_a_stop():
    # a chain whose joint 3 rests on a concave stop (-6 degrees): its shape is the target
    n = 8
    l = np.full(n, 20.0)
    m = np.array([2.0, 2.5, 3.0, 1.0, 1.0, 3.0, 2.5, 2.0])
    limits = np.tile([-np.inf, np.inf], (n - 1, 1))
    limits[3, 1] = np.radians(-6.0)
    eq = solve_equilibrium(l, m, (0, 0), (110, 10), limits=limits)
    assert eq.success and eq.active[3] == 1
    bounds = np.tile([0.5, 20.0], (n, 1))
    free = InverseProblem(eq.points, l, bounds)
    r_free = design(free, "refine", max_nfev=200)
    assert not r_free.exact  # no masses make free joints hold a concave bend
    stopped = InverseProblem(eq.points, l, bounds, limits=limits)
    r_stop = design(stopped, "exact")
    assert r_stop.exact, r_stop.message
    assert r_stop.equilibrium.active[3] == 1 and r_stop.equilibrium.moments[3] < 0
    assert r_stop.distance.max_rel_span < 1e-9 < r_free.distance.max_rel_span


def test_assign_types_puts_stops_where_the_target_needs_moments():
    top = np.radians([50.0, 0.0, -10.0])  # free, straight, concave-20 chamfers
    lim = np.zeros((3, 3, 2))
    for i in range(3):
        for j in range(3):
            lim[i, j] = [-np.radians(100), top[i] + top[j]]
    bends = np.radians([10, 12, 0, 0, 0, 15, 20, -20, -20, 30])
    types, limits, cost = assign_types(bends, np.ones((11, 3), bool), lim)
    assert cost < 1e-9
    assert list(types[2:6]) == [1, 1, 1, 1]  # a straight run of straight-stop rods
    assert list(types[7:10]) == [2, 2, 2]  # -20 = -10 + -10
    np.testing.assert_allclose(limits[[2, 3, 4], 1], 0.0)
    np.testing.assert_allclose(np.degrees(limits[[7, 8], 1]), -20.0)
    # a straight run straight into a concave bend cannot be served by types with equal ends
    _, _, cost = assign_types(np.radians([0, 0, -20]), np.ones((4, 3), bool), lim)
    assert cost > 0.1


def test_infeasible_anchors_explained():
    curve = np.array([[0.0, 0.0], [50.0, -10.0], [100.0, 0.0]])
    with pytest.raises(ValueError, match="farther apart than the chain is long|fits the piece|cannot close"):
        discretize(curve, [200.0])


def test_discretize_semicircle_and_triangle_corner():
    ang = np.linspace(np.pi, 2 * np.pi, 400)
    semi = 100 * np.column_stack([np.cos(ang), np.sin(ang)])
    d = discretize(semi, [20, 30, 40])
    np.testing.assert_allclose(np.hypot(*np.diff(d.points, axis=0).T), d.lengths, rtol=1e-9)
    np.testing.assert_allclose(d.points[[0, -1]], semi[[0, -1]], atol=1e-9)
    assert d.joint_error < 2.0 and d.curve_error < 4.0
    tri = np.array([[0.0, 0.0], [90.0, -120.0], [180.0, 0.0]])  # sides 150: 5 x 30
    d = discretize(tri, [20, 30, 40], preferred=30)
    assert d.corners == [5]
    np.testing.assert_allclose(d.points[5], [90.0, -120.0], atol=1e-6)
    assert d.joint_error < 1e-6


@pytest.mark.parametrize("method", ["pso", "guided-pso"])
def test_pso_methods_deterministic_under_seed(method):
    prob = semicircle_problem(n=8)
    r1 = design(prob, method, seed=7, max_nfev=200)
    r2 = design(prob, method, seed=7, max_nfev=200)
    r3 = design(prob, method, seed=8, max_nfev=200)
    np.testing.assert_array_equal(r1.masses, r2.masses)
    assert not np.array_equal(r1.masses, r3.masses)
    assert r1.nfev <= 201


def test_bad_problem_input():
    with pytest.raises(ValueError, match="discretise the target"):
        InverseProblem(np.array([[0, 0], [1, 0], [2, 0.5]]), [1.0, 1.0], [[1, 2], [1, 2]])
    with pytest.raises(ValueError, match=r"mass_bounds\[1\]"):
        InverseProblem(np.array([[0, 0], [1, 0], [2, 0]]), [1.0, 1.0], [[1, 2], [3, 2]])
    prob, _ = reachable_problem()
    with pytest.raises(ValueError, match="method must be one of"):
        design(prob, "annealing")


def test_mixed_end_types_let_stops_meet_free_corners_and_concave_stops():
    # ends: F free (top chamfer 50), S stop (0), C concave (-20); types (first, second)
    ends = {"F": 50.0, "S": 0.0, "C": -20.0}
    kinds = [("F", "F"), ("S", "S"), ("S", "F"), ("F", "S"), ("C", "S")]
    t = len(kinds)
    lim = np.zeros((t, t, 2))
    for i, (_, second) in enumerate(kinds):
        for k, (first, _) in enumerate(kinds):
            lim[i, k] = [-np.radians(100), np.radians(ends[second] + ends[first])]
    # a straight run, a 90 degree corner, a straight run bending -20 into another
    bends = np.radians([0, 0, 90, 0, 0, -20, 0])
    types, limits, cost = assign_types(bends, np.ones((8, t), bool), lim)
    assert cost < 1e-9
    assert [kinds[k] for k in types[2:4]] == [("S", "F"), ("F", "S")]  # free ends at the corner
    assert kinds[types[6]] == ("C", "S")
    np.testing.assert_allclose(np.degrees(limits[:, 1]), [0, 0, 100, 0, 0, -20, 0], atol=1e-9)
    np.testing.assert_array_equal(joint_mismatch(bends, limits), 0.0)


def test_joint_mismatch_counts_degrees_and_flags_the_impossible():
    bends = np.radians([0.0, -20.0, 30.0, 0.0, 40.0])
    limits = np.radians([[-100, 0.0], [-100, 0.0], [-100, 100], [-100, 100], [-100, 38]])
    limits = np.vstack([limits, [np.inf, -np.inf]])  # a pair that cannot be joined
    out = np.degrees(joint_mismatch(np.append(bends, 0.0), limits))
    np.testing.assert_allclose(out[:4], [0.0, 20.0, 0.0, 100.0])
    assert np.isinf(out[4]) and np.isinf(out[5])  # beyond the limit; unjoinable
