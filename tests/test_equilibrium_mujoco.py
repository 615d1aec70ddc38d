"""The exact equilibrium against MuJoCo, an independent engine.

MuJoCo simulates the same chain as rigid bodies on hinges, with joint ranges,
an equality constraint holding the far end on B and joint damping, from a
different valid configuration (the equilibrium of the same chain with other
masses) until it comes to rest. Both must agree within 1e-5 of the span.
"""

from __future__ import annotations

import mujoco_chain
import numpy as np
import pytest

from optimize import solve_equilibrium


def random_case(seed: int):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(4, 11))
    lengths = rng.uniform(0.8, 1.2, n)
    masses = rng.uniform(0.3, 3.0, n)
    com = np.column_stack([lengths * rng.uniform(0.35, 0.65, n), lengths * rng.uniform(-0.1, 0.1, n)])
    tilt = rng.uniform(-0.4, 0.4)
    span = rng.uniform(0.6, 0.8) * lengths.sum()
    a = np.array([0.0, 0.0])
    b = span * np.array([np.cos(tilt), np.sin(tilt)])
    free = solve_equilibrium(lengths, masses, a, b, com=com)
    # stops on the sagging side for a third of the joints, a little below their free bend,
    # and a concave stop elsewhere, so several limits end up active
    k = max(1, (n - 1) // 3)
    chosen = rng.choice(n - 1, size=k, replace=False)
    hi = np.full(n - 1, np.inf)
    hi[chosen] = free.bends[chosen] * rng.uniform(0.3, 0.8, k)
    lo = np.where(rng.random(n - 1) < 0.5, -np.inf, -rng.uniform(0.2, 1.0, n - 1))
    return lengths, masses, com, np.column_stack([lo, hi]), a, b


@pytest.mark.parametrize("seed", range(8))
def test_agrees_with_mujoco_on_limited_chains_with_offset_com(seed):
    lengths, masses, com, limits, a, b = random_case(seed)
    ours = solve_equilibrium(lengths, masses, a, b, com=com, limits=limits)
    assert ours.success and ours.stable, ours.message
    assert np.count_nonzero(ours.active) >= 1  # the case really exercises a limit
    # start MuJoCo elsewhere: the equilibrium of equal masses with the same limits
    start = solve_equilibrium(lengths, np.ones_like(masses), a, b, limits=limits)
    assert start.success
    sim = mujoco_chain.settle_chain(
        lengths, masses, a, b, com=com, limits=limits, angles0=start.angles
    )
    span = np.hypot(*(b - a))
    assert sim["converged"] and sim["end_error"] < 1e-6 * span
    assert sim["limit_violation"] < 1e-6
    err = np.max(np.hypot(*(sim["points"] - ours.points).T))
    assert err < 1e-5 * span, f"max joint distance {err / span:.2e} of the span"


def test_agrees_with_mujoco_free_offset_com():
    rng = np.random.default_rng(99)
    n = 7
    lengths = rng.uniform(0.8, 1.2, n)
    masses = rng.uniform(0.3, 3.0, n)
    com = np.column_stack([lengths * 0.5, lengths * rng.uniform(-0.15, 0.15, n)])
    a, b = np.zeros(2), np.array([4.0, 0.8])
    ours = solve_equilibrium(lengths, masses, a, b, com=com)
    start = solve_equilibrium(lengths, np.ones(n), a, b)
    sim = mujoco_chain.settle_chain(lengths, masses, a, b, com=com, angles0=start.angles)
    assert np.max(np.hypot(*(sim["points"] - ours.points).T)) < 1e-5 * np.hypot(*b)


@pytest.mark.parametrize("seed", [47, 74, 185, 316, 375])
def test_agrees_with_mujoco_when_a_rigid_piece_pushes(seed):
    # chains whose equilibrium has a rigid group on the compressed branch (pushing against
    # its load), found by the active-set descent, not SLSQP; some with fused joints
    from test_compression import branches, compressed_chain

    lengths, masses, com, limits, a, b = compressed_chain(seed)
    ours = solve_equilibrium(lengths, masses, a, b, com=com, limits=limits)
    assert ours.success and ours.stable and ours.kkt_residual < 1e-9, ours.message
    assert ours.info["path"] == "descent" and not ours.info["used_nlp"]
    assert np.any(branches(ours, lengths, masses, com, limits, a, b) < 0)
    # MuJoCo cannot hold a joint range of zero width: a fused joint gets +-1e-8 rad
    mj_limits = limits.copy()
    fused = limits[:, 0] == limits[:, 1]
    mj_limits[fused] += np.array([-1e-8, 1e-8])
    # start MuJoCo near our equilibrium, disturbed: it must come back (a stable rest)
    rng = np.random.default_rng(seed)
    start = ours.angles + rng.normal(0.0, 0.03, lengths.size)
    sim = mujoco_chain.settle_chain(lengths, masses, a, b, com=com, limits=mj_limits, angles0=start)
    span = np.hypot(*(b - a))
    assert sim["converged"] and sim["end_error"] < 1e-6 * span
    assert sim["limit_violation"] < 1e-6
    err = np.max(np.hypot(*(sim["points"] - ours.points).T))
    assert err < 1e-5 * span, f"max joint distance {err / span:.2e} of the span"
