"""optimize.net.trf: SciPy's trust region reflective with each step's direction by a sparse
factorization. Checked against SciPy's least_squares on problems with one solution, and the
direction against a dense least squares."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.optimize import least_squares

from optimize.net.trf import gauss_newton_direction, trf


def _problem(seed: int, m: int, n: int):
    """Residuals ``A x + 0.3 E sin(x) - b`` (smooth; m >= n: one minimizer) with a sparse A."""
    rng = np.random.default_rng(seed)
    E = sp.eye(m, n, format="csr")
    A = sp.random(m, n, density=0.3, random_state=seed, format="csr") + E
    b = rng.normal(size=m)

    def fun(x):
        return A @ x + 0.3 * (E @ np.sin(x)) - b

    def jac(x):
        return sp.csr_matrix(A + 0.3 * E @ sp.diags(np.cos(x)))

    return fun, jac


@pytest.mark.parametrize("seed", range(6))
def test_the_same_minimizer_as_scipy_within_the_bounds(seed):
    m, n = 40, 25
    fun, jac = _problem(seed, m, n)
    free = least_squares(fun, np.zeros(n), jac=jac, method="trf", tr_solver="lsmr", x_scale="jac",
                         ftol=1e-14, xtol=1e-14, gtol=1e-14)
    # bounds that cut the free minimizer: some end on them
    lo = np.where(np.arange(n) % 3 == 0, free.x + 0.2 * np.abs(free.x) + 0.05, -np.inf)
    hi = np.where(np.arange(n) % 3 == 1, free.x - 0.2 * np.abs(free.x) - 0.05, np.inf)
    x0 = np.clip(np.zeros(n), lo + 1e-3, hi - 1e-3)
    ref = least_squares(fun, x0, jac=jac, bounds=(lo, hi), method="trf", tr_solver="lsmr", x_scale="jac",
                        ftol=1e-15, xtol=1e-15, gtol=1e-15, tr_options={"atol": 1e-14, "btol": 1e-14})
    ours = trf(fun, jac, x0, lo, hi, ftol=1e-15, xtol=1e-15, gtol=1e-15)
    assert ours.status in (1, 2, 3, 4) and ours.fallbacks == 0
    assert np.all(ours.x >= lo) and np.all(ours.x <= hi)
    # the cost is convex near its minimizer (m > n, A well conditioned): one answer, to the tolerance
    assert ours.cost <= ref.cost * (1 + 1e-9) + 1e-14
    assert np.max(np.abs(ours.x - ref.x)) < 1e-6
    assert np.any(np.isclose(ours.x, lo, atol=1e-8)) or np.any(np.isclose(ours.x, hi, atol=1e-8))


def test_an_underdetermined_system_is_solved_near_its_start():
    """More unknowns than equations (as a hub net's joint solve): the residuals vanish."""
    fun, jac = _problem(7, 20, 45)
    lo, hi = np.full(45, -2.0), np.full(45, 2.0)
    r = trf(fun, jac, np.zeros(45), lo, hi, ftol=1e-14, xtol=1e-14, gtol=1e-14)
    assert np.max(np.abs(fun(r.x))) < 1e-10
    assert np.all(np.abs(r.x) < 2.0)


@pytest.mark.parametrize("zeros", [False, True])
def test_the_direction_is_the_regularized_least_squares(zeros):
    rng = np.random.default_rng(3)
    J = sp.random(30, 50, density=0.2, random_state=3, format="csr")
    f = rng.normal(size=30)
    lam2 = rng.uniform(0.1, 2.0, 50)
    if zeros:  # no regularization on some unknowns: the least-norm direction there
        lam2[::4] = 0.0
    p, ok = gauss_newton_direction(J, f, lam2)
    assert ok
    # dense: the normal equations, least norm where singular
    A = np.vstack([J.toarray(), np.diag(np.sqrt(lam2))])
    ref = np.linalg.lstsq(A, np.concatenate([f, np.zeros(50)]), rcond=None)[0]
    assert np.max(np.abs(p - ref)) < 1e-6 * max(1.0, np.max(np.abs(ref)))


def test_a_stalled_solve_stops_when_the_callback_says():
    fun, jac = _problem(1, 40, 25)
    costs = []

    def stop(cost):
        costs.append(cost)
        return len(costs) >= 2

    r = trf(fun, jac, np.zeros(25), np.full(25, -10.0), np.full(25, 10.0), ftol=1e-15, xtol=1e-15, gtol=1e-15,
            callback=stop)
    assert r.status == -2 and len(costs) == 2


def test_a_system_the_symmetric_pivots_cannot_factor_goes_to_partial_pivoting():
    """The direction's augmented system is quasi-definite, which the symmetric LDL^T solves to
    round-off after refinement; a singular system, which it cannot solve, returns None for the
    caller's partial pivoting."""
    from optimize.net.trf import REFINED, _quasi_definite_solve

    rng = np.random.default_rng(5)
    J = sp.random(40, 60, density=0.1, random_state=5, format="csr")
    K = sp.bmat([[sp.diags(rng.uniform(1e-12, 2.0, 60)), J.T], [J, -sp.eye(40)]], format="csc")
    b = rng.normal(size=100)
    x = _quasi_definite_solve(K, b)
    assert x is not None
    assert np.max(np.abs(K @ x - b)) <= REFINED * (abs(K).max() * np.max(np.abs(x)) + np.max(np.abs(b)))
    singular = sp.csc_matrix(np.array([[1.0, 1.0], [1.0, 1.0]]))
    assert _quasi_definite_solve(singular, np.array([1.0, 2.0])) is None
