"""Implicit-differentiation Jacobian of the equilibrium against central differences."""

from __future__ import annotations

import numpy as np
import pytest

from optimize import solve_equilibrium
from optimize.chain.equilibrium import Chain
from optimize.chain.sensitivity import shape_jacobian


def fd_jacobian(l, m, a, b, com, lim, h=1e-6, end_limits=None):
    n = len(m)
    J = np.zeros((n + 1, 2, n))
    for k in range(n):
        mp, mm = m.copy(), m.copy()
        mp[k] += h * m[k]
        mm[k] -= h * m[k]
        rp = solve_equilibrium(l, mp, a, b, com=com, limits=lim, end_limits=end_limits)
        rm = solve_equilibrium(l, mm, a, b, com=com, limits=lim, end_limits=end_limits)
        assert np.array_equal(rp.active, rm.active)  # the derivative holds on one active set
        J[:, :, k] = (rp.points - rm.points) / (2 * h * m[k])
    return J


@pytest.mark.parametrize("seed", range(6))
def test_jacobian_matches_finite_differences(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 12))
    l = rng.uniform(0.8, 1.2, n)
    m = rng.uniform(0.5, 2.0, n)
    com = np.column_stack([l * rng.uniform(0.4, 0.6, n), l * rng.uniform(-0.1, 0.1, n)])
    a, b = np.zeros(2), np.array([0.7 * l.sum(), rng.uniform(-1, 1)])
    free = solve_equilibrium(l, m, a, b, com=com)
    lim = np.tile([-np.inf, np.inf], (n - 1, 1))
    if seed % 2:  # half the cases with binding stops: the derivative on the active set
        j = rng.choice(n - 1, size=max(1, n // 3), replace=False)
        lim[j, 1] = 0.7 * free.bends[j]
    res = solve_equilibrium(l, m, a, b, com=com, limits=lim)
    assert res.success
    J = shape_jacobian(Chain.from_args(l, m, a, b, com, lim), res)
    Jfd = fd_jacobian(l, m, a, b, com, lim)
    assert np.abs(J[[0, -1]]).max() == 0.0
    np.testing.assert_allclose(J, Jfd, atol=1e-7 * np.abs(Jfd).max())
    # scaling every mass leaves the shape: J m = 0
    np.testing.assert_allclose(J @ m, 0.0, atol=1e-10 * np.abs(J).max() * m.sum())


@pytest.mark.parametrize("seed", range(4))
def test_jacobian_with_anchor_stops_matches_finite_differences(seed):
    """A rod held by an anchor stop does not turn: the Jacobian of the set with the held end
    rods (one or both) against central differences, which keep the same anchor stops held."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(4, 12))
    l = rng.uniform(0.8, 1.2, n)
    m = rng.uniform(0.5, 2.0, n)
    com = np.column_stack([l * rng.uniform(0.4, 0.6, n), l * rng.uniform(-0.1, 0.1, n)])
    a, b = np.zeros(2), np.array([0.7 * l.sum(), rng.uniform(-1, 1)])
    free = solve_equilibrium(l, m, a, b, com=com)
    lim = np.tile([-np.inf, np.inf], (n - 1, 1))
    j = rng.choice(n - 1, size=max(1, n // 3), replace=False)
    lim[j, 1] = 0.7 * free.bends[j]
    e = np.array([[free.angles[0] + 0.2, np.inf], [-np.inf, np.inf]])
    if seed % 2:
        e[1, 1] = free.angles[-1] - 0.2
    res = solve_equilibrium(l, m, a, b, com=com, limits=lim, end_limits=e)
    assert res.success and res.info["end_active"][0] == -1 and res.info["end_active"][1] == seed % 2
    J = shape_jacobian(Chain.from_args(l, m, a, b, com, lim, 9.81, e), res)
    Jfd = fd_jacobian(l, m, a, b, com, lim, end_limits=e)
    np.testing.assert_allclose(J[1], 0.0, atol=1e-12)  # p_1 sits on the held first rod
    np.testing.assert_allclose(J, Jfd, atol=1e-7 * np.abs(Jfd).max())
    np.testing.assert_allclose(J @ m, 0.0, atol=1e-10 * np.abs(J).max() * m.sum())
