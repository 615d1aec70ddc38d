"""Implicit-differentiation Jacobian of the equilibrium against central differences."""

from __future__ import annotations

import numpy as np
import pytest

from optimize import solve_equilibrium
from optimize.equilibrium import Chain
from optimize.sensitivity import shape_jacobian


def fd_jacobian(l, m, a, b, com, lim, h=1e-6):
    n = len(m)
    J = np.zeros((n + 1, 2, n))
    for k in range(n):
        mp, mm = m.copy(), m.copy()
        mp[k] += h * m[k]
        mm[k] -= h * m[k]
        pp = solve_equilibrium(l, mp, a, b, com=com, limits=lim).points
        pm = solve_equilibrium(l, mm, a, b, com=com, limits=lim).points
        J[:, :, k] = (pp - pm) / (2 * h * m[k])
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
