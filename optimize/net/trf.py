"""Bounded nonlinear least squares with a sparse Jacobian: SciPy's trust region reflective
with each step's Gauss-Newton direction solved by one sparse factorization.

:func:`optimize.net.sockets.balance_sockets` solves a hub net's socket turns, masses and
tensions together: a few hundred to a few thousand balance rows, more unknowns than rows,
ill-conditioned. ``scipy.optimize.least_squares(method="trf", tr_solver="lsmr")`` finds each
step's Gauss-Newton direction by LSMR, which there ran 850-1,000 iterations a step, each 0.3 ms
of Python around a sparse product of a few microseconds: 14-19 s for one solve of a 178-rod
net. :func:`trf` is that same algorithm (SciPy's ``trf_bounds``: Coleman-Li scaling, the
Jacobian's column scale, the step in the plane of the scaled gradient and the Gauss-Newton
direction, the reflected and the gradient steps, SciPy's trust-radius update and termination
tests, all through SciPy's own helpers) with the direction, the regularized least squares

    min |J_h p - f|^2 + |D p|^2,   J_h = J diag(d),   D^2 = diag_h + reg,

that LSMR approximates, solved exactly from its quasi-definite augmented system
``[[D^2, J_h^T], [J_h, -I]] [p; y] = [0; f]`` by one sparse LU with symmetric pivots and iterative
refinement (partial pivoting where that does not converge; no dense step: it stays sparse at a
2,000-rod net's size). Where that system is singular to the factorization,
the step falls back to LSMR as SciPy takes it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.linalg import norm
from scipy.linalg import qr
from scipy.optimize._lsq.common import (CL_scaling_vector, build_quadratic_1d, check_termination,
                                        compute_grad, compute_jac_scale, make_strictly_feasible,
                                        minimize_quadratic_1d, regularized_lsq_operator,
                                        right_multiplied_operator, solve_trust_region_2d, update_tr_radius)
from scipy.optimize._lsq.trf import select_step
from scipy.sparse.linalg import lsmr, splu

from optimize.net.newton import spd_lu

__all__ = ["TrfResult", "gauss_newton_direction", "trf"]

#: The regularization's floor relative to the largest squared column of ``J_h`` (about 1 with
#: the Jacobian's column scale): where a variable has none (free, away from its bounds, no
#: trust-region term), the direction is the least-norm one LSMR's zero start converges to.
FLOOR = 1e-12


@dataclass
class TrfResult:
    """What :func:`trf` ends with.

    Attributes:
        x: the solution.
        cost: half the sum of its squared residuals.
        nfev: residual evaluations.
        status: SciPy's: 1 gradient, 2 ftol, 3 xtol, 4 both, 0 max_nfev, -2 stopped by the callback.
        fallbacks: steps whose direction LSMR took (the sparse factorization singular).
    """

    x: np.ndarray
    cost: float
    nfev: int
    status: int
    fallbacks: int


def gauss_newton_direction(J_h, f: np.ndarray, lam2: np.ndarray) -> tuple[np.ndarray, bool]:
    """``argmin |J_h p - f|^2 + sum(lam2 p^2)`` (``J_h`` sparse, ``lam2 >= 0``) from the
    augmented system by one sparse LU; returns (p, True), or (nan, False) where the
    factorization finds the system singular."""
    J_h = sp.csr_matrix(J_h)
    r, n = J_h.shape
    colmax = float(np.max(np.asarray(J_h.multiply(J_h).sum(axis=0)), initial=0.0))
    lam2 = np.maximum(lam2, FLOOR * max(colmax, 1e-300))
    K = sp.bmat([[sp.diags(lam2), J_h.T], [J_h, -sp.eye(r)]], format="csc")
    b = np.concatenate([np.zeros(n), f])
    p = _quasi_definite_solve(K, b)
    if p is None:  # the symmetric pivots too small to trust: partial pivoting
        try:
            p = splu(K).solve(b)
        except RuntimeError:
            return np.full(n, np.nan), False
    p = p[:n]
    return p, bool(np.all(np.isfinite(p)))


#: Relative residual of the augmented system at which the symmetric factorization's solution
#: counts as solved (a few hundred times round-off on the system's scale).
REFINED = 1e-13


def _quasi_definite_solve(K: sp.csc_matrix, b: np.ndarray, refine: int = 4) -> np.ndarray | None:
    """Solve the quasi-definite ``K x = b`` by a sparse LU with symmetric, diagonal pivoting
    and a fill-reducing symmetric ordering (an LDL^T: a quasi-definite matrix has one for every
    symmetric permutation, Vanderbei 1995), a fifth of partial pivoting's fill, then iterative
    refinement; None where the residual does not fall to :data:`REFINED` (tiny pivots of a
    nearly singular system), for the caller's partial pivoting."""
    try:
        lu = spd_lu(K)
    except RuntimeError:
        return None
    x = lu.solve(b)
    scale = float(abs(K).max()) * float(np.max(np.abs(x), initial=0.0)) + float(np.max(np.abs(b), initial=0.0))
    for _ in range(refine + 1):
        if not np.all(np.isfinite(x)):
            return None
        res = b - K @ x
        if float(np.max(np.abs(res), initial=0.0)) <= REFINED * scale:
            return x
        x = x + lu.solve(res)
    return None


def trf(fun, jac, x0, lb, ub, *, ftol: float = 1e-8, xtol: float = 1e-8, gtol: float = 1e-8,
        max_nfev: int | None = None, callback=None) -> TrfResult:
    """Minimize ``0.5 |fun(x)|^2`` within ``lb <= x <= ub`` as ``scipy.optimize.least_squares(
    fun, x0, jac=jac, bounds=(lb, ub), method="trf", x_scale="jac", tr_solver="lsmr")`` does,
    each step's direction solved exactly (module docstring).

    Args:
        fun: x -> residuals (r,).
        jac: x -> their Jacobian, scipy sparse (r, n).
        x0: (n,) the start (moved strictly inside the bounds).
        lb, ub: (n,) the bounds (some finite).
        ftol, xtol, gtol: SciPy's termination tolerances.
        max_nfev: evaluations at most (None: 100 n).
        callback: cost -> True to stop (after each iteration), or None.

    Returns:
        TrfResult.
    """
    lb = np.asarray(lb, float)
    ub = np.asarray(ub, float)
    x = make_strictly_feasible(np.asarray(x0, float), lb, ub)
    f = np.asarray(fun(x), float)
    J = sp.csr_matrix(jac(x))
    nfev = 1
    m, n = J.shape
    cost = 0.5 * float(f @ f)
    g = compute_grad(J, f)
    scale, scale_inv = compute_jac_scale(J)
    v, dv = CL_scaling_vector(x, g, lb, ub)
    v[dv != 0] *= scale_inv[dv != 0]
    Delta = norm(x * scale_inv / v ** 0.5)
    if Delta == 0:
        Delta = 1.0
    max_nfev = 100 * n if max_nfev is None else max_nfev
    f_augmented = np.zeros(m + n)
    status = None
    fallbacks = 0
    while True:
        v, dv = CL_scaling_vector(x, g, lb, ub)
        g_norm = norm(g * v, ord=np.inf)
        if g_norm < gtol:
            status = 1
        if status is not None or nfev == max_nfev:
            break
        v[dv != 0] *= scale_inv[dv != 0]
        d = v ** 0.5 * scale
        diag_h = g * dv * scale
        g_h = d * g
        J_h = J @ sp.diags(d)
        a, b = build_quadratic_1d(J_h, g_h, -g_h, diag=diag_h)
        ag_value = minimize_quadratic_1d(a, b, 0, Delta / norm(g_h))[1]
        reg = -ag_value / Delta ** 2
        gn_h, ok = gauss_newton_direction(J_h, f, diag_h + reg)
        if not ok:  # (SciPy's own step)
            fallbacks += 1
            f_augmented[:m] = f
            op = regularized_lsq_operator(right_multiplied_operator(J, d), (diag_h + reg) ** 0.5)
            gn_h = lsmr(op, f_augmented)[0]
        S, _ = qr(np.vstack((g_h, gn_h)).T, mode="economic")
        JS = J_h @ S
        B_S = JS.T @ JS + (S.T * diag_h) @ S
        g_S = S.T @ g_h
        theta = max(0.995, 1 - g_norm)
        actual_reduction = -1.0
        while actual_reduction <= 0 and nfev < max_nfev:
            p_S, _ = solve_trust_region_2d(B_S, g_S, Delta)
            p_h = S @ p_S
            p = d * p_h
            step, step_h, predicted_reduction = select_step(x, J_h, diag_h, g_h, p, p_h, d, Delta, lb, ub, theta)
            x_new = make_strictly_feasible(x + step, lb, ub, rstep=0)
            f_new = np.asarray(fun(x_new), float)
            nfev += 1
            step_h_norm = norm(step_h)
            if not np.all(np.isfinite(f_new)):
                Delta = 0.25 * step_h_norm
                continue
            cost_new = 0.5 * float(f_new @ f_new)
            actual_reduction = cost - cost_new
            Delta_new, ratio = update_tr_radius(Delta, actual_reduction, predicted_reduction, step_h_norm,
                                                step_h_norm > 0.95 * Delta)
            status = check_termination(actual_reduction, cost, norm(step), norm(x), ratio, ftol, xtol)
            if status is not None:
                break
            Delta = Delta_new
        if actual_reduction > 0:
            x, f, cost = x_new, f_new, cost_new
            J = sp.csr_matrix(jac(x))
            g = compute_grad(J, f)
            scale, scale_inv = compute_jac_scale(J, scale_inv)
        if callback is not None and callback(cost):
            status = -2
            break
    return TrfResult(x, cost, nfev, 0 if status is None else int(status), fallbacks)
