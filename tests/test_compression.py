"""Rigid pieces in compression: the exact active-set descent over (side, branch).

When a rigid group has to push (its angle points against its load, the other branch of
|P_G lambda - Q_G|), the dual exchange cannot reach the equilibrium; the solver then
descends over joint sides and group branches (:func:`optimize.chain.branches.descend`) and
makes the point exact. These tests check the result against statics (KKT conditions,
rod-by-rod balance), the second-order test, and that SLSQP was not needed. Agreement
with MuJoCo is in ``test_equilibrium_mujoco.py``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from test_equilibrium import balance_residual

from optimize import solve_equilibrium
from optimize.chain.branches import descend, reach_start
from optimize.chain.model import Chain, Groups, is_stable, kkt_residual, sag_guess, violations

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from bench_equilibrium import compressed_chain  # noqa: E402  (the benchmark's random chains)

__all__ = ["branches", "compressed_chain"]


def branches(res, lengths, masses, com, limits, a, b):
    """+1 per rigid group turned along its load, -1 per group that pushes against it."""
    chain = Chain.from_args(lengths, masses, a, b, com, limits)
    groups = Groups(chain, res.active)
    W = groups.P * complex(*res.reaction) - groups.Q
    return np.sign((np.conj(W) * np.exp(1j * res.angles[groups.starts])).real)


def assert_exact_equilibrium(res, lengths, masses, com, limits, a, b):
    span_scale = lengths.sum()
    assert res.success and res.stable, res.message
    assert res.kkt_residual < 1e-9
    assert np.hypot(*(res.points[-1] - b)) < 1e-12 * span_scale
    phi = res.bends
    assert np.all(phi >= limits[:, 0] - 1e-12) and np.all(phi <= limits[:, 1] + 1e-12)
    movable = limits[:, 0] < limits[:, 1]
    assert np.all(res.moments[(res.active < 0) & movable] >= -1e-9)
    assert np.all(res.moments[(res.active > 0) & movable] <= 1e-9)
    assert np.all(res.moments[res.active == 0] == 0)
    # independent statics: force and moment balance of every rod, stops included
    assert balance_residual(res, lengths, masses, com) < 1e-9


def test_random_compressed_chains_solved_exactly_without_slsqp():
    paths = []
    pushing = 0
    for seed in range(100):
        lengths, masses, com, limits, a, b = compressed_chain(seed)
        res = solve_equilibrium(lengths, masses, a, b, com=com, limits=limits)
        assert_exact_equilibrium(res, lengths, masses, com, limits, a, b)
        paths.append(res.info["path"])
        if res.info["path"] == "descent":
            assert "active-set descent" in res.message and not res.info["used_nlp"]
            pushing += bool(np.any(branches(res, lengths, masses, com, limits, a, b) < 0))
    assert paths.count("slsqp") == 0
    assert paths.count("descent") >= 10  # the exchange alone fails on these
    assert pushing >= 8  # and most of them have a rigid piece that pushes


@pytest.mark.parametrize("seed", [47, 74, 185, 316, 375])
def test_descent_from_the_symmetric_sag(seed):
    # the descent alone, from a start that knows nothing of the answer
    lengths, masses, com, limits, a, b = compressed_chain(seed)
    chain = Chain.from_args(lengths, masses, a, b, com, limits)
    found = descend(chain, sag_guess(chain))
    assert found is not None
    theta, lam, side, _ = found
    primal, _, dual = violations(chain, theta, lam, side)
    assert not primal.any() and not dual.any()
    assert kkt_residual(chain, theta, lam, side) < 1e-9
    assert is_stable(chain, theta, lam, side)


@pytest.mark.parametrize("seed", [55, 47, 185])
def test_reach_start_closes_the_chain_within_the_limits(seed):
    # the descent's last starts: each of the usual ones moved to the nearest shape that reaches
    # B within the limits (seed 55's usual starts all ended on kinks on an AVX2 machine)
    lengths, masses, com, limits, a, b = compressed_chain(seed)
    chain = Chain.from_args(lengths, masses, a, b, com, limits)
    theta = reach_start(chain, sag_guess(chain))
    assert theta is not None
    end = np.asarray(a, float) + np.array([lengths @ np.cos(theta), lengths @ np.sin(theta)])
    assert np.linalg.norm(end - b) <= 1e-9 * lengths.sum()
    bends = np.diff(theta)
    assert np.all(bends >= limits[:, 0] - 1e-12) and np.all(bends <= limits[:, 1] + 1e-12)
    res = solve_equilibrium(lengths, masses, a, b, com=com, limits=limits)
    assert res.success and res.stable and res.info["path"] in ("exchange", "descent")


@pytest.mark.parametrize("seed", [14, 47, 185, 328])
def test_compressed_shape_independent_of_mass_scale(seed):
    lengths, masses, com, limits, a, b = compressed_chain(seed)
    r1 = solve_equilibrium(lengths, masses, a, b, com=com, limits=limits)
    r2 = solve_equilibrium(lengths, masses * 37.0, a, b, com=com, limits=limits)
    assert r1.info["path"] == r2.info["path"] == "descent"
    np.testing.assert_allclose(r2.points, r1.points, atol=1e-9 * lengths.sum())
    np.testing.assert_allclose(r2.reaction, 37.0 * r1.reaction, rtol=1e-7, atol=1e-9)


def test_common_cases_keep_the_exchange():
    rng = np.random.default_rng(5)
    n = 12
    lengths, masses = rng.uniform(0.8, 1.2, n), rng.uniform(0.5, 2.0, n)
    free = solve_equilibrium(lengths, masses, (0, 0), (8, 1))
    assert free.info["path"] == "free" and free.success  # every joint free: the closed-form fast path
    hi = np.full(n - 1, np.inf)
    big = np.argsort(-free.bends)[: (n - 1) // 3]
    hi[big] = 0.8 * free.bends[big]  # stops a little below the largest free bends
    limits = np.column_stack([np.full(n - 1, -np.inf), hi])
    limited = solve_equilibrium(lengths, masses, (0, 0), (8, 1), limits=limits)
    assert limited.info["path"] == "exchange" and limited.success
    assert np.count_nonzero(limited.active) > 0
