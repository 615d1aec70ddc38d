"""The free chain's fast path (optimize.chain.free) against the general exact solver: every joint
and anchor pin free, seeded random chains of every shape the general solver takes (anchors
level, sloped, B left of A, nearly one above the other, nearly taut; offset centres of mass),
the same equilibrium to round-off; and it is the path a free chain takes."""

from __future__ import annotations

import numpy as np
import pytest

from optimize import solve_equilibrium
from optimize.chain import Chain
from optimize.chain.equilibrium import _check_reach, _solve_exact
from optimize.chain.free import catenary_reaction, solve_free


def _random_chain(rng, n):
    lengths = rng.uniform(0.3, 2.0, n)
    masses = rng.uniform(0.1, 3.0, n)
    com = np.column_stack([lengths * rng.uniform(0.2, 0.8, n), lengths * rng.uniform(-0.2, 0.2, n)])
    total = lengths.sum()
    kind = rng.integers(5)
    if kind == 0:  # level
        d = np.array([rng.uniform(0.1, 0.9), 0.0])
    elif kind == 1:  # sloped
        ang = rng.uniform(-1.2, 1.2)
        d = rng.uniform(0.1, 0.9) * np.array([np.cos(ang), np.sin(ang)])
    elif kind == 2:  # B left of A
        ang = np.pi + rng.uniform(-1.0, 1.0)
        d = rng.uniform(0.1, 0.9) * np.array([np.cos(ang), np.sin(ang)])
    elif kind == 3:  # nearly one above the other
        d = rng.uniform(0.1, 0.9) * np.array([rng.uniform(-1e-4, 1e-4), 1.0])
    else:  # nearly taut
        ang = rng.uniform(-0.5, 0.5)
        d = (1 - 10 ** rng.uniform(-6, -2)) * np.array([np.cos(ang), np.sin(ang)])
    a = rng.uniform(-5, 5, 2)
    return lengths, masses, com, a, a + d * total


@pytest.mark.parametrize("seed", range(4))
def test_the_fast_path_finds_the_general_solvers_equilibrium(seed):
    rng = np.random.default_rng(seed)
    checked = fast_ones = 0
    for n in (2, 3, 5, 12, 40, 300) * 3:
        lengths, masses, com, a, b = _random_chain(rng, n)
        chain = Chain.from_args(lengths, masses, a, b, com, None, 9.81, None)
        try:
            _check_reach(chain)  # a long rod the others cannot fold back
        except ValueError:
            continue
        if chain.span >= chain.total_length * (1 - 1e-12):
            continue
        checked += 1
        fast = solve_free(chain)
        ref = _solve_exact(chain, None, None, 10 + 4 * n, True, None)
        assert ref.success
        if fast is None:  # the fast path may hand a case over to the general solver
            continue
        fast_ones += 1
        assert fast.success and fast.kkt_residual < 1e-9
        scale = chain.total_length
        assert np.max(np.abs(fast.points - ref.points)) <= 1e-9 * scale, (seed, n)
        assert np.max(np.abs(np.angle(np.exp(1j * (fast.angles - ref.angles))))) <= 1e-8
        np.testing.assert_allclose(np.diff(fast.angles), np.diff(ref.angles), atol=1e-8)  # same unwrapping
        weight = 9.81 * masses.sum()
        force = max(weight, float(np.abs(ref.reaction).max()))  # a nearly taut chain pulls hard
        assert np.max(np.abs(fast.reaction - ref.reaction)) <= 1e-8 * force
        assert np.max(np.abs(fast.reaction_a - ref.reaction_a)) <= 1e-8 * force
        assert abs(fast.energy - ref.energy) <= 1e-9 * weight * scale + 1e-12 * abs(ref.energy)
        assert fast.stable == ref.stable
        assert not fast.active.any() and fast.active.shape == ref.active.shape
    assert checked >= 10 and fast_ones >= 0.5 * checked, (checked, fast_ones)  # kinks go to the general solver


def test_a_free_chain_takes_the_fast_path_and_limits_do_not():
    rng = np.random.default_rng(7)
    lengths, masses, com, a, b = _random_chain(rng, 30)
    b = a + np.array([0.6 * lengths.sum(), 0.0])
    free = solve_equilibrium(lengths, masses, a, b, com=com)
    assert free.info["path"] == "free" and free.success and free.stable
    limits = np.tile([-np.inf, np.inf], (29, 1))
    limits[10] = [-0.01, 0.01]
    held = solve_equilibrium(lengths, masses, a, b, com=com, limits=limits)
    assert held.info["path"] != "free"
    open_rows = solve_equilibrium(lengths, masses, a, b, com=com, limits=np.tile([-np.inf, np.inf], (29, 1)))
    assert open_rows.info["path"] == "free"  # rows of (-inf, inf) are free joints


def test_the_catenary_start_is_the_catenary():
    """A uniform chain of many short rods hangs as the catenary of its length and weight:
    the start's reaction is that chain's (to the discretisation's O(1/N^2))."""
    n = 400
    lengths, masses = np.full(n, 1.0 / n), np.full(n, 1.0 / n)
    a, b = np.zeros(2), np.array([0.6, 0.2])
    chain = Chain.from_args(lengths, masses, a, b, None, None, 9.81, None)
    guess = catenary_reaction(chain)
    res = solve_equilibrium(lengths, masses, a, b)
    assert abs(guess - complex(*res.reaction)) <= 1e-4 * 9.81
