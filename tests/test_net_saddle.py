"""Unstable equilibria: reported as such from a design's target, left for a stable one otherwise.

Truth: closed forms. A chain of rods standing straight up from its anchor is an equilibrium (every
rod's weight along its neighbours) and an unstable one, with two equal negative curvatures (it
may tip toward x or y): the case ARPACK's shift-invert could not separate. Hanging straight down
is its only stable equilibrium, node k at -k L below the anchor.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import optimize.net.newton as newton
from optimize import solve_net

L = 30.0


def _upright(n: int):
    pts = np.array([[0.0, 0.0, k * L] for k in range(n + 1)])
    edges = np.column_stack([np.arange(n), np.arange(1, n + 1)])
    return pts, edges, np.full(n, L), np.linspace(1.0, 2.0, n)


def _hangs_down(res, n: int) -> None:
    want = np.array([[0.0, 0.0, -k * L] for k in range(n + 1)])
    assert res.success and res.stable and res.escapes >= 1
    # (the solver's KKT tolerance is round-off: the rods' lengths hold to 1e-9 of a length)
    np.testing.assert_allclose(res.positions, want, atol=1e-6 * L)


@pytest.mark.parametrize("n", [1, 3])
def test_an_upright_chain_is_an_unstable_equilibrium_the_check_reports_and_the_solver_leaves(n):
    pts, edges, lengths, masses = _upright(n)
    kept = solve_net(pts, edges, lengths, masses, [0], leave_unstable=False)
    assert kept.success and not kept.stable and kept.escapes == 0
    np.testing.assert_allclose(kept.positions, pts, atol=1e-9 * L)
    assert "not stable" in kept.message
    fallen = solve_net(pts, edges, lengths, masses, [0])  # (the default: where the net falls to)
    _hangs_down(fallen, n)
    assert fallen.energy < kept.energy


def test_the_sparse_eigensolver_and_its_fallback_leave_the_saddle_the_same_way(monkeypatch):
    """Nets above DENSE_EIG_NVAR unknowns take ARPACK's direction, or where ARPACK fails, one read
    from the factorization's most negative pivot: each leaves the saddle for the hanging chain."""
    n = 4
    pts, edges, lengths, masses = _upright(n)
    monkeypatch.setattr(newton, "DENSE_EIG_NVAR", 0)
    _hangs_down(solve_net(pts, edges, lengths, masses, [0]), n)

    def failing(*args, **kwargs):
        raise RuntimeError("ARPACK did not converge")

    monkeypatch.setattr("scipy.sparse.linalg.eigsh", failing)
    _hangs_down(solve_net(pts, edges, lengths, masses, [0]), n)


def test_the_pivot_direction_has_negative_curvature():
    """v'Kv = d_k < 0 for the LDL^T's most negative pivot d_k; None for a definite K."""
    rng = np.random.default_rng(3)
    indefinite = 0
    for seed in range(6):
        A = sp.random(80, 80, density=0.05, random_state=seed)
        K = (A + A.T + sp.diags(rng.uniform(0.5, 2.0, 80))).tocsc()
        K = K - sp.diags(np.where(np.arange(80) == seed * 7, 4.0, 0.0))
        lowest = np.linalg.eigvalsh(K.toarray())[0]
        v = newton._pivot_direction(K)
        if lowest < 0:
            indefinite += 1
            assert v is not None and np.isclose(np.linalg.norm(v), 1.0) and v @ (K @ v) < 0
    assert indefinite >= 3
    definite = (sp.diags(rng.uniform(1.0, 2.0, 30)) + 0.1 * sp.eye(30, k=1) + 0.1 * sp.eye(30, k=-1)).tocsc()
    assert newton._pivot_direction(definite) is None
