"""Anchor stops in the active set, checked against truth.

Random limited chains whose end rods rest on (or are kept off) anchor stops: the solver's
result must be an exact KKT point (closure, lengths, joint and end limits, the sign of every
stop's and fixture's moment, every rod in force and moment balance with the fixtures'
moments), agree with MuJoCo (the anchor stops as the range of the first hinge and a limited
tendon over all hinges for the last rod), and, on small chains, be the lowest of the stable
equilibria a brute-force enumeration of held end rods finds (``endlimits_reference``: the
method the solver used before, every choice tried). No timing here: the speed targets are
measured by ``benchmarks/bench_equilibrium.py``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from endlimits_reference import held_end_candidates
from test_equilibrium import com_points, cross, rod_forces

from optimize import find_equilibria, solve_equilibrium
from optimize.chain.endlimits import limit_turn

G = 9.81


def limited_chain(seed: int, n_range=(4, 16)):
    """A random chain with stops along it and anchor stops, feasible by construction: every
    bound admits a reference shape (the same chain hanging with other masses) and most lie
    between it and the free shape, which they exclude (one-sided stops and anchor stops,
    either side; windows; now and then a fused joint). Returns lengths, masses, com,
    limits, end_limits, a, b."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(*n_range))
    lengths = rng.uniform(0.8, 1.2, n)
    masses = rng.uniform(0.3, 3.0, n)
    com = np.column_stack([lengths * rng.uniform(0.35, 0.65, n), lengths * rng.uniform(-0.1, 0.1, n)])
    tilt = rng.uniform(-0.4, 0.4)
    span = rng.uniform(0.55, 0.85) * lengths.sum()
    a, b = np.zeros(2), span * np.array([math.cos(tilt), math.sin(tilt)])
    free = solve_equilibrium(lengths, masses, a, b, com=com)
    ref = solve_equilibrium(lengths, rng.uniform(0.3, 3.0, n), a, b, com=com)

    def bound(x_ref, x_free, kind):
        """[lo, hi] admitting x_ref: between it and x_free (1), a window (2), fused (3)."""
        if kind == 1:
            x = x_ref + rng.uniform(0.1, 0.9) * (x_free - x_ref)
            return [-np.inf, x] if x_free > x_ref else [x, np.inf]
        if kind == 2:
            return [x_ref - rng.uniform(0.02, 0.3), x_ref + rng.uniform(0.02, 0.3)]
        if kind == 3:
            return [x_ref, x_ref]
        return [-np.inf, np.inf]

    limits = np.array([bound(r, f, rng.choice(4, p=[0.45, 0.35, 0.12, 0.08]))
                       for r, f in zip(ref.bends, free.bends)]).reshape(n - 1, 2)
    ends = np.array([bound(ref.angles[rod], free.angles[rod], rng.choice(3, p=[0.2, 0.55, 0.25]))
                     for rod in (0, -1)])
    return lengths, masses, com, limits, ends, a, b


def assert_exact_with_anchor_stops(res, lengths, masses, com, limits, ends, a, b):
    """The KKT conditions and every rod's balance, computed here from the result's numbers."""
    length, weight = lengths.sum(), masses.sum() * G
    assert res.success and res.kkt_residual < 1e-9, res.message
    assert np.hypot(*(res.points[-1] - b)) < 1e-12 * length
    np.testing.assert_allclose(np.hypot(*np.diff(res.points, axis=0).T), lengths, rtol=1e-12)
    phi = res.bends
    assert np.all(phi >= limits[:, 0] - 1e-12) and np.all(phi <= limits[:, 1] + 1e-12)
    held, fixture = res.info["end_active"], res.info["end_moments"]
    tol = 1e-9 * weight * length
    for k, rod in ((0, 0), (1, -1)):
        t = res.angles[rod] - limit_turn(res.angles[rod], ends[k])
        assert ends[k, 0] - 1e-12 <= t <= ends[k, 1] + 1e-12
        if held[k]:
            assert t == pytest.approx(ends[k, 0] if held[k] < 0 else ends[k, 1], abs=1e-12)
            if ends[k, 0] < ends[k, 1]:
                assert -held[k] * fixture[k] >= -tol  # the fixture pushes the rod back in
        else:
            assert fixture[k] == 0.0
    movable = limits[:, 0] < limits[:, 1]
    on = res.active != 0
    np.testing.assert_allclose(phi[on], np.where(res.active < 0, limits[:, 0], limits[:, 1])[on], atol=1e-12)
    assert np.all(res.moments[(res.active < 0) & movable] >= -tol)
    assert np.all(res.moments[(res.active > 0) & movable] <= tol)
    assert np.all(res.moments[res.active == 0] == 0)
    # rod by rod: forces, and moments about each rod's first pin, the fixtures' included
    F = rod_forces(res, masses, G)
    near = np.vstack([res.reaction_a[None, :], -F[:-1]])
    w = np.column_stack([np.zeros(len(masses)), -masses * G])
    assert np.abs(F + near + w).max() < 1e-9 * weight
    tau = np.concatenate([[fixture[0]], res.moments, [-fixture[1]]])
    c = com_points(res, lengths, com)
    moment = cross(res.points[1:] - res.points[:-1], F) + cross(c - res.points[:-1], w) + tau[:-1] - tau[1:]
    assert np.abs(moment).max() < tol


def test_random_chains_with_anchor_stops_are_exact_equilibria():
    held = {0: 0, 1: 0, 2: 0}
    for seed in range(60):
        lengths, masses, com, limits, ends, a, b = limited_chain(seed)
        res = solve_equilibrium(lengths, masses, a, b, com=com, limits=limits, end_limits=ends)
        assert res.stable, (seed, res.message)
        assert_exact_with_anchor_stops(res, lengths, masses, com, limits, ends, a, b)
        held[int(np.count_nonzero(res.info["end_active"]))] += 1
    assert held[1] >= 10 and held[2] >= 10 and held[0] >= 3  # the cases exercise each


@pytest.mark.parametrize("seed", range(40))
def test_small_chains_match_every_choice_of_held_ends(seed):
    """The lowest stable equilibrium the brute force finds, over every held/free choice at
    both ends and, below them, at the joints next to held rods, is the solver's."""
    lengths, masses, com, limits, ends, a, b = limited_chain(1000 + seed, n_range=(3, 7))
    res = solve_equilibrium(lengths, masses, a, b, com=com, limits=limits, end_limits=ends)
    candidates = held_end_candidates(lengths, masses, a, b, com, limits, ends, G)
    if not candidates:
        pytest.skip("no choice of held ends gives a stable equilibrium the reference can solve")
    best = min(candidates, key=lambda c: c.energy)
    scale = masses.sum() * G * lengths.sum()
    assert res.success and res.stable, res.message
    assert res.energy == pytest.approx(best.energy, abs=1e-9 * scale)
    np.testing.assert_allclose(np.exp(1j * res.angles), np.exp(1j * best.angles), atol=1e-9)
    np.testing.assert_array_equal(res.info["end_active"], best.held)
    np.testing.assert_allclose(res.info["end_moments"], best.moments, atol=1e-9 * scale)
    np.testing.assert_allclose(res.reaction, best.reaction, atol=1e-9 * masses.sum() * G)


@pytest.mark.parametrize("seed", [2, 3, 6, 8, 15, 19])
def test_anchor_stops_with_stops_along_the_chain_agree_with_mujoco(seed):
    """Released 0.01 rad off the solver's shape, MuJoCo (the first hinge's range, a limited
    tendon over every hinge for the last rod) comes back to it within 1e-5 of the span."""
    pytest.importorskip("mujoco")
    from mujoco_chain import settle_chain

    lengths, masses, com, limits, ends, a, b = limited_chain(seed)
    res = solve_equilibrium(lengths, masses, a, b, com=com, limits=limits, end_limits=ends)
    assert res.success and res.stable, res.message
    assert res.info["end_active"].any()  # the case exercises an anchor stop
    theta = np.unwrap(res.angles)  # MuJoCo's angles are continuous along the chain
    e = ends.copy()
    for k, t in ((0, theta[0]), (1, theta[-1])):
        e[k] += limit_turn(t, e[k])
    mj_limits = limits.copy()
    fused = limits[:, 0] == limits[:, 1]
    mj_limits[fused] += np.array([-1e-8, 1e-8])  # MuJoCo cannot hold a range of zero width
    e[e[:, 0] == e[:, 1]] += np.array([-1e-8, 1e-8])
    rng = np.random.default_rng(seed)
    sim = settle_chain(lengths, masses, a, b, com=com, limits=mj_limits, end_limits=e,
                       angles0=theta + rng.normal(0.0, 0.01, lengths.size))
    span = np.hypot(*(b - a))
    assert sim["converged"] and sim["end_error"] < 1e-6 * span
    err = np.max(np.hypot(*(sim["points"] - res.points).T))
    assert err < 1e-5 * span, f"max joint distance {err / span:.2e} of the span"


def test_rigid_chain_between_two_fixtures():
    """Every joint fused and both end rods fixed (lo == hi): the shape is fully determined,
    the statics are not; the solver returns the shape, closure met, with statics that
    balance every rod and fixtures that carry no more than they must."""
    rng = np.random.default_rng(3)
    n = 6
    lengths, masses = rng.uniform(0.8, 1.2, n), rng.uniform(0.5, 2.0, n)
    com = np.column_stack([lengths / 2, np.zeros(n)])
    theta = np.array([1.2, 0.6, -0.3, -1.2, -2.0, -2.6])
    tip = np.sum(lengths * np.exp(1j * theta))
    a, b = np.zeros(2), np.array([tip.real, tip.imag])
    phi = np.diff(theta)
    limits = np.column_stack([phi, phi])
    ends = np.array([[theta[0], theta[0]], [theta[-1], theta[-1]]])
    res = solve_equilibrium(lengths, masses, a, b, com=com, limits=limits, end_limits=ends)
    assert res.success and res.stable
    np.testing.assert_allclose(res.angles, theta, atol=1e-12)
    assert_exact_with_anchor_stops(res, lengths, masses, com, limits, ends, a, b)
    # pinned at A and B the rigid body needs no fixture moment: the pins carry it
    assert np.abs(res.info["end_moments"]).max() < 1e-9 * masses.sum() * G * lengths.sum()
    # a shape the two fixtures' angles do not close is out of reach: said, not guessed
    bad = ends.copy()
    bad[1] += 0.1
    with pytest.raises(ValueError, match="no configuration"):
        solve_equilibrium(lengths, masses, a, b, com=com, limits=limits, end_limits=bad)


def test_three_hinged_halves_with_fixtures():
    """Two fused halves pinned at A, B and each other (one free joint) are determinate; with
    the fixtures stopping the end rods at the same angles, from either side, the shape stays
    and the fixtures carry nothing."""
    rng = np.random.default_rng(3)
    n = 6
    lengths, masses = rng.uniform(0.8, 1.2, n), rng.uniform(0.5, 2.0, n)
    com = np.column_stack([lengths / 2, np.zeros(n)])
    theta = np.array([1.2, 0.6, -0.3, -1.2, -2.0, -2.6])
    tip = np.sum(lengths * np.exp(1j * theta))
    a, b = np.zeros(2), np.array([tip.real, tip.imag])
    limits = np.column_stack([np.diff(theta), np.diff(theta)])
    limits[2] = [-np.inf, np.inf]
    for s0, s1 in ((-1, -1), (-1, 1), (1, 1)):
        ends = np.array([[theta[0], np.inf] if s0 < 0 else [-np.inf, theta[0]],
                         [theta[-1], np.inf] if s1 < 0 else [-np.inf, theta[-1]]])
        res = solve_equilibrium(lengths, masses, a, b, com=com, limits=limits, end_limits=ends)
        assert res.stable
        assert_exact_with_anchor_stops(res, lengths, masses, com, limits, ends, a, b)
        np.testing.assert_allclose(res.angles, theta, atol=1e-9)
        assert np.abs(res.info["end_moments"]).max() < 1e-9 * masses.sum() * G * lengths.sum()


def test_multistart_starts_from_held_end_rods():
    """The multi-start also starts with the end rods held: a chain whose first rod may rest
    on either bound of a window finds the stable shapes from both."""
    lengths, masses, com, limits, ends, a, b = limited_chain(7)
    multi = find_equilibria(lengths, masses, a, b, com=com, limits=limits, end_limits=ends, n_starts=8, seed=0)
    assert multi.n_distinct >= 1 and multi.n_failed == 0
    for eq in multi.equilibria:
        assert_exact_with_anchor_stops(eq, lengths, masses, com, limits, ends, a, b)
    again = find_equilibria(lengths, masses, a, b, com=com, limits=limits, end_limits=ends, n_starts=8, seed=0)
    assert again.counts == multi.counts  # seeded: same starts, same result
