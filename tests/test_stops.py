"""Stops where the masses cannot hold a target: which joints need them
(:func:`optimize.chain.stops.needed_stops`), moving the joints onto the stop angles
(:func:`optimize.chain.discretize.refit`), choosing the types (``assign_types(need_stop=)``),
and the resulting design checked against MuJoCo."""

from __future__ import annotations

import dataclasses

import mujoco_chain
import numpy as np
import pytest

from optimize import InverseProblem, design, solve_equilibrium
from optimize.chain.assign import assign_types
from optimize.chain.discretize import discretize, refit
from optimize.chain.statics import exact_masses
from optimize.chain.stops import needed_stops

A, B = np.array([0.0, 0.0]), np.array([200.0, 0.0])
FREE = np.radians([-110.0, 110.0])


def _semicircle(n: int = 400) -> np.ndarray:
    t = np.linspace(np.pi, 2 * np.pi, n)
    return np.column_stack([100 + 100 * np.cos(t), 100 * np.sin(t)])


def _problem(bounds=(8.0, 12.0)) -> tuple[np.ndarray, InverseProblem]:
    curve = _semicircle()
    disc = discretize(curve, [40.0])
    n = disc.lengths.size
    return curve, InverseProblem(disc.points, disc.lengths, np.tile(bounds, (n, 1)),
                                 limits=np.tile(FREE, (n - 1, 1)))


def test_masses_alone_cannot_hold_a_semicircle_within_narrow_bounds():
    _, p = _problem()
    assert not exact_masses(p)[2]
    r = design(p, "refine")
    assert not r.exact and r.distance.max_rel_span > 1e-2  # the bounded best fit is far off


def test_no_stops_needed_when_the_bounds_are_wide():
    _, p = _problem(bounds=(0.1, 1000.0))
    assert exact_masses(p)[2]
    assert needed_stops(p).size == 0


def test_needed_stops_make_the_target_an_equilibrium_within_bounds():
    _, p = _problem()
    need = needed_stops(p)
    assert need is not None and 0 < need.size < p.n - 1
    lim = p.limits.copy()
    lim[need, 1] = np.diff(p.angles)[need]  # stops exactly at the target bends
    q = dataclasses.replace(p, limits=lim)
    r = design(q, "refine")
    assert r.exact and r.distance.max_rel_span < 1e-9, r.message
    lo, hi = q.mass_bounds.T
    assert np.all((r.masses >= lo) & (r.masses <= hi))
    eq = r.equilibrium
    assert np.all(eq.active[need] == 1) and np.all(eq.moments[need] <= 0)  # pushing back on sag


def test_no_candidates_and_unreachable_is_none():
    _, p = _problem()
    assert needed_stops(p, candidates=[]) is None


def test_refit_holds_the_fixed_bends_exactly_and_closes_on_b():
    curve, p = _problem()
    fixed = {1: np.radians(20.0), 2: np.radians(20.0), 3: np.radians(15.0)}
    d = refit(curve, p.target, p.lengths, fixed)
    assert d is not None
    steps = np.diff(d.points, axis=0)
    np.testing.assert_allclose(np.hypot(*steps.T), p.lengths, rtol=1e-12)
    bends = np.diff(np.unwrap(np.arctan2(steps[:, 1], steps[:, 0])))
    for j, v in fixed.items():
        assert bends[j] == pytest.approx(v, abs=1e-12)
    np.testing.assert_array_equal(d.points[0], p.target[0])  # the anchors stay put
    np.testing.assert_array_equal(d.points[-1], p.target[-1])
    assert 0 < d.curve_error < 15.0  # close to the circle, not on it


def test_refit_of_one_rigid_piece_is_none():
    curve, p = _problem()
    everything = {j: float(b) for j, b in enumerate(np.diff(p.angles))}
    assert refit(curve, p.target, p.lengths, everything) is None


def test_assign_need_stop_picks_the_nearest_stop_angle():
    # types: 0 free ends, 1 stops at 10 deg with itself, 2 at 20 deg with itself
    lim = np.tile(FREE, (3, 3, 1))
    lim[1, 1, 1], lim[2, 2, 1], lim[1, 2, 1], lim[2, 1, 1] = np.radians([10, 20, 15, 15])
    bends = np.radians([18.0, 19.0, 40.0])
    allowed = np.ones((4, 3), dtype=bool)
    free_types, _, _ = assign_types(bends, allowed, lim)
    assert free_types.tolist() == [0, 0, 0, 0]  # convex bends need no stop by themselves
    types, limits, cost = assign_types(bends, allowed, lim, need_stop=[True, True, False])
    assert types[:3].tolist() == [2, 2, 2]
    np.testing.assert_allclose(np.degrees(limits[:2, 1]), [20.0, 20.0])
    assert cost == pytest.approx(np.radians(3.0), abs=1e-9)
    assert np.degrees(limits[2, 1]) > 40  # the free joint stays free
    with pytest.raises(ValueError, match="need_stop"):
        assign_types(bends, allowed, lim, need_stop=[True])


def test_stop_design_hangs_there_in_mujoco():
    """The semicircle on 20-degree stops: the designed masses, simulated by MuJoCo from
    another shape, come to rest on the target with the stops engaged."""
    curve, p = _problem()
    need = needed_stops(p)
    d = refit(curve, p.target, p.lengths, {int(j): np.radians(20.0) for j in need})
    lim = p.limits.copy()
    bends = np.diff(np.unwrap(np.arctan2(*np.diff(d.points, axis=0).T[::-1])))
    lim[need, 1] = bends[need]
    q = dataclasses.replace(p, target=d.points, limits=lim)
    r = design(q, "refine")
    assert r.success
    start = solve_equilibrium(q.lengths, np.ones(q.n), A, B, limits=lim)
    sim = mujoco_chain.settle_chain(q.lengths, r.masses, A, B, limits=lim, angles0=start.angles)
    assert sim["converged"] and sim["limit_violation"] < 1e-6
    err = np.max(np.hypot(*(sim["points"] - r.equilibrium.points).T))
    assert err < 1e-5 * 200.0
