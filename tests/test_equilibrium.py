"""The exact equilibrium solver against closed forms, invariants and hand statics."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from optimize import find_equilibria, solve_equilibrium
from optimize.chain.model import Chain, is_stable

G = 9.81


def rod_forces(res, masses, g=G):
    """Force on rod k at its far joint p_{k+1} (from rod k+1, or anchor B), walking back from B."""
    n = len(masses)
    forces = np.empty((n, 2))
    f = np.array(res.reaction, dtype=float)
    for k in range(n - 1, -1, -1):
        forces[k] = f
        f = f - np.array([0.0, masses[k] * g])  # rod k's near end carries its weight too
    return forces


def cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def com_points(res, lengths, com):
    t = np.column_stack([np.cos(res.angles), np.sin(res.angles)])
    n = np.column_stack([-t[:, 1], t[:, 0]])
    return res.points[:-1] + com[:, :1] * t + com[:, 1:] * n


def balance_residual(res, lengths, masses, com, g=G):
    """Largest force and moment imbalance over all rods, relative to weight x length.

    Rod k feels: at p_{k+1} the force F_k, at p_k the force -F_{k-1} (or A's reaction),
    its weight at its centre of mass, and the stop moments +tau_{k-1} and -tau_k at
    its two joints (tau_j = res.moments[j], acting to increase phi_j).
    """
    n = len(masses)
    F = rod_forces(res, masses, g)
    near = np.vstack([res.reaction_a[None, :], -F[:-1]])  # force at p_k on rod k
    weight = np.column_stack([np.zeros(n), -masses * g])
    force_res = np.abs(F + near + weight).max()
    c = com_points(res, lengths, com)
    tau = np.concatenate([[0.0], res.moments, [0.0]])
    moment = (
        cross(res.points[1:] - res.points[:-1], F)
        + cross(c - res.points[:-1], weight)
        + tau[:-1]
        - tau[1:]
    )
    scale = g * masses.sum() * lengths.sum()
    return max(force_res * lengths.sum(), np.abs(moment).max()) / scale


# --------------------------------------------------------------------------- closed forms


def test_discrete_catenary_tangents_linear():
    n, l, m = 12, 1.0, 0.7
    res = solve_equilibrium(np.full(n, l), np.full(n, m), (0, 0), (8, 1.5))
    assert res.success and res.stable and res.kkt_residual < 1e-12
    tans = np.tan(res.angles)
    # tan(theta_{i+1}) - tan(theta_i) = g (m_i + m_{i+1}) / (2 H)
    np.testing.assert_allclose(np.diff(tans), G * m / res.reaction[0], rtol=1e-10, atol=0)
    np.testing.assert_allclose(res.points[-1], (8, 1.5), atol=1e-13)


def test_catenary_unequal_masses_closed_form():
    rng = np.random.default_rng(3)
    m = rng.uniform(0.2, 5.0, 9)
    res = solve_equilibrium(np.ones(9), m, (0, 0), (6, -2))
    assert res.success
    expected = G * (m[:-1] + m[1:]) / (2 * res.reaction[0])
    np.testing.assert_allclose(np.diff(np.tan(res.angles)), expected, rtol=1e-10)


def test_two_rod_v_by_hand():
    l1, l2, m1, m2 = 1.3, 0.8, 2.0, 0.5
    a, b = np.array([0.0, 0.0]), np.array([1.5, 0.4])
    res = solve_equilibrium([l1, l2], [m1, m2], a, b)
    # joint position: intersection of two circles, the lower one
    d = np.linalg.norm(b - a)
    x = (d * d + l1 * l1 - l2 * l2) / (2 * d)
    h = np.sqrt(l1 * l1 - x * x)
    u = (b - a) / d
    nrm = np.array([-u[1], u[0]])
    cands = [a + x * u + h * nrm, a + x * u - h * nrm]
    joint = min(cands, key=lambda p: p[1])
    np.testing.assert_allclose(res.points[1], joint, atol=1e-12)
    # reaction at B by hand: moments of rod 2 about the joint and of the chain about A
    p1 = joint
    c1, c2 = a + (p1 - a) / 2, p1 + (b - p1) / 2
    # (b - p1) x (H, V) = (c2 - p1) x (0, m2 g);  (b - a) x (H, V) = sum (c_i - a) x (0, m_i g)
    M = np.array([[-(b - p1)[1], (b - p1)[0]], [-(b - a)[1], (b - a)[0]]])
    rhs = np.array([(c2 - p1)[0] * m2 * G, (c1 - a)[0] * m1 * G + (c2 - a)[0] * m2 * G])
    np.testing.assert_allclose(res.reaction, np.linalg.solve(M, rhs), rtol=1e-10)


def test_three_rod_symmetric_by_hand():
    l, big_l, m, big_m, span = 1.0, 1.5, 0.4, 2.5, 2.6
    res = solve_equilibrium([l, big_l, l], [m, big_m, m], (0, 0), (span, 0))
    alpha = np.arccos((span - big_l) / (2 * l))
    np.testing.assert_allclose(res.angles, [-alpha, 0.0, alpha], atol=1e-12)
    # vertical reaction: half the weight; horizontal from tan(a) = g (m + M) / (2 H)
    np.testing.assert_allclose(res.reaction[1], G * (2 * m + big_m) / 2, rtol=1e-12)
    np.testing.assert_allclose(res.reaction[0], G * (m + big_m) / (2 * np.tan(alpha)), rtol=1e-10)


def test_locked_middle_joint_moment_by_hand():
    # four equal rods, level anchors, the middle joint stopped at beta (it would bend more)
    m, beta, span = 1.0, 0.2, 3.0
    limits = [[-np.inf, np.inf], [-np.inf, beta], [-np.inf, np.inf]]
    res = solve_equilibrium(np.ones(4), np.full(4, m), (0, 0), (span, 0), limits=limits)
    assert res.success and res.stable
    assert res.active.tolist() == [0, 1, 0]
    a = np.arccos((span - 2 * np.cos(beta / 2)) / 2)
    np.testing.assert_allclose(res.angles, [-a, -beta / 2, beta / 2, a], atol=1e-12)
    # left half: A's reaction (-H, 2 m g); rod 0's moment about p1 is zero (free joint)
    p = res.points
    c0 = (p[0] + p[1]) / 2
    c1 = (p[1] + p[2]) / 2
    v_a = 2 * m * G
    # (A - p1) x (-H, v_a) + (c0 - p1) x (0, -m g) = 0, solve for H
    r = p[0] - p[1]
    h = -(r[0] * v_a + (c0 - p[1])[0] * (-m * G)) / r[1]
    np.testing.assert_allclose(res.reaction[0], h, rtol=1e-10)
    # left half about p2: the stop's moment on rod 1 is -moments[1] and balances the rest
    ra = np.array([-h, v_a])
    weight = np.array([0.0, -m * G])
    rest = cross(p[0] - p[2], ra) + cross(c0 - p[2], weight) + cross(c1 - p[2], weight)
    np.testing.assert_allclose(res.moments[1], rest, rtol=1e-10)
    assert res.moments[1] < 0  # the stop pushes phi down: the joint wants to sag further
    com = np.column_stack([np.full(4, 0.5), np.zeros(4)])
    assert balance_residual(res, np.ones(4), np.full(4, m), com) < 1e-12


def test_taut_chain_is_straight_line():
    res = solve_equilibrium([1.0, 2.0, 1.5], [1, 1, 1], (0, 0), (4.5 * 0.6, 4.5 * 0.8))
    assert res.success and res.status == 4
    np.testing.assert_allclose(res.angles, np.arctan2(0.8, 0.6))
    np.testing.assert_allclose(res.points[-1], (2.7, 3.6), atol=1e-12)
    bad = solve_equilibrium([1, 1], [1, 1], (0, 0), (2, 0), limits=[[0.1, 0.5]])
    assert not bad.success and bad.status == 5


# --------------------------------------------------------------------------- invariants

chains = st.integers(2, 14).flatmap(
    lambda n: st.tuples(
        st.lists(st.floats(0.3, 2.0), min_size=n, max_size=n),
        st.lists(st.floats(0.05, 20.0), min_size=n, max_size=n),
        st.lists(st.floats(-0.3, 0.3), min_size=n, max_size=n),
        st.lists(st.floats(0.1, 0.9), min_size=n, max_size=n),
        st.floats(0.2, 0.95),
        st.floats(-1.2, 1.2),
    )
)


def build(sample):
    lengths, masses, perp, along, reach, tilt = sample
    lengths, masses = np.array(lengths), np.array(masses)
    com = np.column_stack([np.array(along) * lengths, np.array(perp) * lengths])
    span = reach * lengths.sum()
    if span < 2 * lengths.max() - lengths.sum():
        span = 0.5 * (2 * lengths.max() - lengths.sum() + lengths.sum())
    b = span * np.array([np.cos(tilt), np.sin(tilt)])
    return lengths, masses, com, np.array([0.3, -0.2]), np.array([0.3, -0.2]) + b


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(chains, st.floats(1e-3, 1e3))
def test_mass_scaling_leaves_shape(sample, scale):
    lengths, masses, com, a, b = build(sample)
    r1 = solve_equilibrium(lengths, masses, a, b, com=com)
    r2 = solve_equilibrium(lengths, masses * scale, a, b, com=com)
    assert r1.success and r2.success
    np.testing.assert_allclose(r2.points, r1.points, atol=1e-9 * lengths.sum())
    np.testing.assert_allclose(r2.reaction, r1.reaction * scale, rtol=1e-8, atol=1e-9)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(chains)
def test_mirror_symmetry(sample):
    lengths, masses, com, a, b = build(sample)
    r = solve_equilibrium(lengths, masses, a, b, com=com)
    # mirror x -> -x and read the chain from the other end
    mirror = np.array([-1.0, 1.0])
    com_m = np.column_stack([lengths[::-1] - com[::-1, 0], com[::-1, 1]])
    rm = solve_equilibrium(lengths[::-1], masses[::-1], b * mirror, a * mirror, com=com_m)
    assert r.success and rm.success
    np.testing.assert_allclose(rm.points[::-1] * mirror, r.points, atol=1e-9 * lengths.sum())


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(chains)
def test_force_and_moment_balance_rod_by_rod(sample):
    lengths, masses, com, a, b = build(sample)
    r = solve_equilibrium(lengths, masses, a, b, com=com)
    assert r.success and r.stable and r.kkt_residual < 1e-9
    assert np.hypot(*(r.points[-1] - b)) < 1e-12 * lengths.sum()
    assert balance_residual(r, lengths, masses, com) < 1e-10


# --------------------------------------------------------------------------- joint limits


def feasible_limited_chain(rng, n):
    """A random chain with limits built around a known feasible configuration."""
    lengths = rng.uniform(0.5, 1.5, n)
    masses = rng.uniform(0.1, 5.0, n)
    com = np.column_stack([rng.uniform(0.2, 0.8, n) * lengths, rng.uniform(-0.2, 0.2, n) * lengths])
    theta = np.cumsum(np.concatenate([[rng.uniform(-1.2, -0.2)], rng.uniform(-0.2, 0.6, n - 1)]))
    phi = np.diff(theta)
    a = np.zeros(2)
    b = a + np.array([lengths @ np.cos(theta), lengths @ np.sin(theta)])
    lo = np.where(rng.random(n - 1) < 0.5, -np.inf, phi - rng.uniform(0, 0.5, n - 1))
    hi = np.where(rng.random(n - 1) < 0.3, np.inf, phi + rng.uniform(0, 0.3, n - 1))
    return lengths, masses, com, np.column_stack([lo, hi]), a, b


@pytest.mark.parametrize("seed", range(40))
def test_limited_chains_reach_exact_kkt_from_any_start(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 25))
    lengths, masses, com, limits, a, b = feasible_limited_chain(rng, n)
    starts = [None, rng.choice([-1, 0, 1], n - 1), np.ones(n - 1, int)]
    for active0 in starts:
        r = solve_equilibrium(lengths, masses, a, b, com=com, limits=limits, active0=active0)
        assert r.success, r.message
        assert r.kkt_residual < 1e-9
        phi = r.bends
        assert np.all(phi >= limits[:, 0] - 1e-12) and np.all(phi <= limits[:, 1] + 1e-12)
        assert np.hypot(*(r.points[-1] - b)) < 1e-12 * lengths.sum()
        assert balance_residual(r, lengths, masses, com) < 1e-9
        on_lo, on_hi = r.active < 0, r.active > 0
        assert np.all(r.moments[on_lo] >= -1e-9) and np.all(r.moments[on_hi] <= 1e-9)
        np.testing.assert_allclose(phi[on_hi], limits[on_hi, 1], atol=1e-12)


def test_straight_stop_locks_a_run():
    n = 8
    limits = np.tile([-np.inf, np.inf], (n - 1, 1))
    limits[2:5, 1] = 0.0  # joints 2..4 cannot sag: rods 2..5 form a straight run
    r = solve_equilibrium(np.ones(n), np.ones(n), (0, 0), (5.5, 0), limits=limits)
    assert r.success and r.stable
    np.testing.assert_allclose(r.bends[2:5], 0.0, atol=1e-14)
    assert np.all(r.moments[2:5] < 0)
    pts = r.points[2:7]
    assert np.abs(cross(pts[1:] - pts[0], np.tile(pts[-1] - pts[0], (4, 1)))).max() < 1e-12


def test_concave_arch_held_by_stops_found():
    # every joint may bend at most 0.1 rad sagging: the only way to reach B is an arch
    r = solve_equilibrium(np.ones(3), np.ones(3), (0, 0), (2, 0), limits=[[-np.inf, 0.1]] * 2)
    assert r.success and r.stable and r.kkt_residual < 1e-9
    assert r.points[1:-1, 1].min() > 0  # above the anchors
    assert r.reaction[0] < 0  # compressed


def test_rigid_joint_lo_equals_hi():
    limits = [[-np.inf, np.inf], [-0.4, -0.4], [-np.inf, np.inf]]
    r = solve_equilibrium(np.ones(4), np.ones(4), (0, 0), (2.8, 0), limits=limits)
    assert r.success
    np.testing.assert_allclose(r.bends[1], -0.4, atol=1e-14)


def test_infeasible_limits_explained():
    n = 10
    r = solve_equilibrium(np.ones(n), np.ones(n), (0, 0), (5, -1), limits=[[-0.2, 0.0]] * (n - 1))
    assert not r.success and r.status == 3
    assert "still spans" in r.message


# --------------------------------------------------------------------------- stability


def test_inverted_free_chain_is_unstable():
    n = 6
    lengths, masses = np.ones(n), np.ones(n)
    r = solve_equilibrium(lengths, masses, (0, 0), (4, 0))
    chain = Chain.from_args(lengths, masses, (0, 0), (4, 0))
    lam = complex(*r.reaction)
    side = np.zeros(n - 1, int)
    assert is_stable(chain, r.angles, lam, side)
    # the same shape flipped upward is an equilibrium of the arch with the reaction
    # reversed in H; it satisfies stationarity but is a maximum
    up = -r.angles
    lam_up = complex(-lam.real, lam.imag)
    from optimize.chain.equilibrium import kkt_residual

    assert kkt_residual(chain, up, lam_up, side) < 1e-9
    assert not is_stable(chain, up, lam_up, side)


def test_multistart_counts():
    free = find_equilibria(np.ones(5), np.ones(5), (0, 0), (3, 0), n_starts=6, seed=1)
    assert free.n_distinct == 1 and free.counts == [6]
    arch = find_equilibria(np.ones(3), np.ones(3), (0, 0), (2, 0), limits=[[-np.inf, 0.1]] * 2,
                           n_starts=12, seed=1)
    assert arch.n_distinct == 2  # the arch leans left or right, mirror images
    p0, p1 = arch.equilibria[0].points, arch.equilibria[1].points
    np.testing.assert_allclose(p1[::-1, 0], 2 - p0[:, 0], atol=1e-9)
    again = find_equilibria(np.ones(3), np.ones(3), (0, 0), (2, 0), limits=[[-np.inf, 0.1]] * 2,
                            n_starts=12, seed=1)
    assert again.counts == arch.counts


# --------------------------------------------------------------------------- penalty model


def test_penalty_model_leaves_closure_error_that_shrinks_with_weight():
    n = 10
    exact = solve_equilibrium(np.ones(n), np.ones(n), (0, 0), (6, 1))
    errors = []
    for w in (1e2, 1e3, 1e4):
        r = solve_equilibrium(np.ones(n), np.ones(n), (0, 0), (6, 1), model="penalty",
                              penalty_weight=w)
        assert r.model == "penalty" and "closure_error" in r.message
        errors.append(r.closure_error)
        assert np.abs(r.points - exact.points).max() < 30 * r.closure_error
    assert errors[0] > 5 * errors[1] > 25 * errors[2] > 0
    assert exact.closure_error < 1e-13


# --------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(lengths=[1, -1]), r"lengths\[1\] must be positive"),
        (dict(lengths=[1, 0]), r"lengths\[1\] must be positive"),
        (dict(masses=[1, 0]), r"masses\[1\] must be positive"),
        (dict(masses=[1, np.nan]), r"masses\[1\] is not finite"),
        (dict(masses=[1, 1, 1]), r"masses has 3 entries but the chain has 2 rods"),
        (dict(anchor_b=[1, 2, 3]), r"anchor_b must have shape \(2,\)"),
        (dict(anchor_a=[np.nan, 0]), r"anchor_a must be finite"),
        (dict(com=[[0.5, 0]]), r"com must have shape \(2, 2\)"),
        (dict(limits=[[0.5, 0.1]]), r"limits\[0\] has lo > hi"),
        (dict(limits=[[np.nan, 0.1]]), r"limits\[0, 0\] is NaN"),
        (dict(limits=[[0, 1], [0, 1]]), r"limits must have shape \(1, 2\)"),
        (dict(g=0), r"g must be positive"),
        (dict(anchor_b=[2.5, 0]), r"anchors are 0.5 farther apart than the chain is long"),
        (dict(lengths=[3, 1], anchor_b=[1, 0]), r"anchors are too close: rod 0"),
        (dict(model="springs"), r"model must be 'exact' or 'penalty'"),
    ],
)
def test_bad_input_names_the_argument(kwargs, match):
    args = dict(lengths=[1, 1], masses=[1, 1], anchor_a=[0, 0], anchor_b=[1.5, 0])
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        solve_equilibrium(
            args.pop("lengths"), args.pop("masses"), args.pop("anchor_a"), args.pop("anchor_b"),
            **args,
        )


def test_large_chain_closure_to_round_off():
    n = 10000
    rng = np.random.default_rng(0)
    r = solve_equilibrium(rng.uniform(0.5, 1.5, n), rng.uniform(0.1, 2, n), (0, 0), (6000, 500))
    assert r.success and r.kkt_residual < 1e-9
    assert r.closure_error < 1e-11 * 10000


@pytest.mark.parametrize("tilt", [0.0, 0.2, -0.5])
def test_slack_chain_whose_bottom_rod_spans_the_anchors(tilt):
    # five unit rods, anchors one unit apart: two rods hang straight down from each
    # anchor and the middle rod lies parallel to AB, unloaded (a kink of the dual)
    a = np.array([0.3, -0.2])
    b = a + np.array([np.cos(tilt), np.sin(tilt)])
    r = solve_equilibrium(np.ones(5), np.ones(5), a, b)
    assert r.success and r.stable
    assert r.closure_error < 1e-11
    np.testing.assert_allclose(r.points[2] - r.points[0], [0, -2], atol=1e-6)
    np.testing.assert_allclose(r.points[3] - r.points[2], b - a, atol=1e-6)
