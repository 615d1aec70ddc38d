"""Statics of a chain at a target shape: linear in the masses.

At the target configuration every rod angle is known, so each rod's moment balance
is linear in the rod masses, the support reaction (H, V) at B and the moments at
joints resting on a limit (:func:`statics_matrix`). The exact inverse design
(:func:`exact_masses`), the stop planner (:mod:`optimize.chain.stops`) and the residual
reported for any design (:func:`statics_residual`) all work on that matrix, scaled by
:func:`scaled_statics`. Units: the caller's length and mass units, angles in radians,
forces in mass x the unit of ``g``, moments in force x length.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linprog, lsq_linear

from optimize.chain.endlimits import limit_turn
from optimize.chain.problem import InverseProblem

__all__ = [
    "LIMIT_TOL",
    "exact_masses",
    "extended_bends",
    "moment_signs",
    "scaled_statics",
    "statics_matrix",
    "statics_residual",
]

#: A target bend within this many radians of a limit counts as resting on it.
LIMIT_TOL = 1e-6


def extended_bends(problem: InverseProblem) -> tuple[np.ndarray, np.ndarray]:
    """The target's bends with the anchors as two more joints, and their limits.

    An anchor fixture that stops the first rod acts like a joint between a fixed bar along
    +x and rod 0 (bend theta_0, limit the end limit); at B like a joint between rod N-1 and
    a fixed bar along +x (bend -theta_{N-1}, limit [-hi, -lo]). Entry e of the result is
    joint e - 1: -1 for anchor A, 0..N-2 the joints, N-1 anchor B.

    Returns:
        (bends, limits): (N+1,) radians and (N+1, 2); free anchors have (-inf, inf). An
        end limit is compared with the target's end angle on the same branch (mod 2 pi).
    """
    theta = problem.angles
    lim = np.full((problem.n + 1, 2), [-np.inf, np.inf])
    lim[1:-1] = problem.limits
    bends = np.concatenate([[theta[0]], np.diff(theta), [-theta[-1]]])
    e = problem.end_limits
    if e is not None:
        for k, (rod, sgn) in enumerate(((0, 1.0), (-1, -1.0))):
            if np.all(np.isinf(e[k])):
                continue
            lo, hi = e[k] + limit_turn(theta[rod], e[k])  # the limit on the target angle's turn
            lim[0 if k == 0 else -1] = (lo, hi) if sgn > 0 else (-hi, -lo)
    return bends, lim


def statics_matrix(problem: InverseProblem):
    """Linear statics at the target: rows = rods, columns = [masses, H, V, stop moments].

    Rod k balances when l_k((H - s_k) sin t_k - (V - c_k) cos t_k) = mu_{k-1} - mu_k with
    s_k = g m_k perp_k / l_k and c_k = g (sum_{i>k} m_i + m_k along_k / l_k); mu_{-1} and
    mu_{N-1} are the anchor fixtures' moments (zero at a bare pin).

    Args:
        problem: the target joints, rod lengths, centres of mass, limits, end limits and
            ``g``. A joint (or an end rod) rests on a limit when its target bend (angle) is
            within :data:`LIMIT_TOL` radians of it.

    Returns:
        (A, stops, signs): A of shape (N, N + 2 + len(stops)), each row a rod's moment
        balance (force x length) as a linear map of the unknowns [masses (mass unit),
        H, V (force: mass x the unit of ``g``), stop moments (force x length)]; stops
        are the joints whose target bend rests on a limit, -1 and N-1 for an anchor
        fixture stopping the first or last rod (:func:`extended_bends`); signs +1 (lo:
        moment >= 0), -1 (hi: <= 0), 0 (rigid).
    """
    n, l, g = problem.n, problem.lengths, problem.g
    theta = problem.angles
    phi, lim = extended_bends(problem)
    lo, hi = lim[:, 0], lim[:, 1]
    on_hi = np.abs(phi - hi) <= LIMIT_TOL
    on_lo = np.abs(phi - lo) <= LIMIT_TOL
    stops = np.flatnonzero(on_hi | on_lo) - 1
    signs = np.where(on_hi & on_lo, 0, np.where(on_lo, 1, -1))[stops + 1]
    s, c = np.sin(theta), np.cos(theta)
    along, perp = problem.com[:, 0], problem.com[:, 1]
    A = np.zeros((n, n + 2 + stops.size))
    # mass terms: -l_k s_k' sin + l_k c_k' cos, with s_k, c_k linear in the masses
    idx = np.arange(n)
    A[idx, idx] += -g * perp * s + g * along * c
    upper = np.triu(np.ones((n, n)), k=1)  # [i > k]
    A[:, :n] += g * (l * c)[:, None] * upper
    A[:, n] = l * s
    A[:, n + 1] = -l * c
    for col, j in enumerate(stops):
        # f_k = mu_{k-1} - mu_k: moved left, rod j gets +mu_j, rod j+1 gets -mu_j
        if j >= 0:
            A[j, n + 2 + col] += 1.0
        if j + 1 < n:
            A[j + 1, n + 2 + col] -= 1.0
    return A, stops, signs


def moment_signs(signs: np.ndarray, lb: np.ndarray, ub: np.ndarray) -> None:
    """Sign bounds on stop moments, in place: >= 0 on a lo stop, <= 0 on a hi stop.

    Args:
        signs: (S,) the ``signs`` of :func:`statics_matrix`: +1 lo stop, -1 hi stop,
            0 rigid joint (either sign).
        lb: (S,) lower bounds on the stop moments (any unit: only zero is written).
        ub: (S,) upper bounds on the stop moments; both are changed in place.
    """
    lb[signs > 0] = 0.0
    ub[signs < 0] = 0.0


def scaled_statics(problem: InverseProblem, A: np.ndarray):
    """Row and column scaling of the statics matrix, for conditioning.

    ``(A * row[:, None]) * col[None, :]`` is dimensionless and of order one: rows are
    divided by l_k g m_ref N (force x length), mass columns multiplied by m_ref (the
    geometric mean of the mass bounds), the reaction columns by g m_ref N (force) and
    the stop-moment columns by g m_ref N times the mean rod length (force x length).
    A scaled unknown x gives the physical one as ``x * col``.

    Args:
        problem: the target, rods, mass bounds and ``g``.
        A: the matrix of :func:`statics_matrix` (its column count sets ``col``'s size).

    Returns:
        (row, col): (N,) row factors in 1 / (force x length) and (A.shape[1],) column
        factors in the unit of each unknown.
    """
    m_ref = float(np.exp(np.mean(np.log(problem.mass_bounds))))
    row = 1.0 / (problem.lengths * problem.g * m_ref * problem.n)
    col = np.ones(A.shape[1])
    col[: problem.n] = m_ref
    col[problem.n:] = problem.g * m_ref * problem.n
    col[problem.n + 2:] *= float(np.mean(problem.lengths))
    return row, col


def exact_masses(problem: InverseProblem):
    """Masses from the linear statics: an LP when the target is reachable, else bounded LSQ.

    The linear program keeps every mass as far inside its bounds as it can (it
    maximises the smallest relative distance to a bound) while the target balances
    with stop moments of the right sign.

    Args:
        problem: the target, rods, limits and mass bounds.

    Returns:
        (masses, residual, reachable, detail): (N,) masses in the caller's mass unit,
        within their bounds; the largest scaled (dimensionless, see
        :func:`scaled_statics`) moment imbalance of the target under them; True when
        the target is an equilibrium within the bounds; the method used, in words.
    """
    n = problem.n
    A, stops, signs = statics_matrix(problem)
    row, col = scaled_statics(problem, A)
    As = (A * row[:, None]) * col[None, :]
    lo_m, hi_m = problem.mass_bounds[:, 0], problem.mass_bounds[:, 1]
    nvar = A.shape[1]
    lb = np.full(nvar, -np.inf)
    ub = np.full(nvar, np.inf)
    lb[:n], ub[:n] = lo_m / col[:n], hi_m / col[:n]
    moment_signs(signs, lb[n + 2:], ub[n + 2:])
    # LP: maximise t, the smallest relative distance of a mass from its bounds
    rng_m = (hi_m - lo_m) / col[:n]
    c = np.zeros(nvar + 1)
    c[-1] = -1.0
    A_eq = np.hstack([As, np.zeros((n, 1))])
    A_ub = np.zeros((2 * n, nvar + 1))
    A_ub[:n, :n] = -np.eye(n)
    A_ub[:n, -1] = rng_m
    A_ub[n:, :n] = np.eye(n)
    A_ub[n:, -1] = rng_m
    b_ub = np.concatenate([-lb[:n], ub[:n]])
    bounds = list(zip(np.where(np.isfinite(lb), lb, None), np.where(np.isfinite(ub), ub, None)))
    bounds.append((0.0, 0.5))
    lp = linprog(c, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=np.zeros(n), bounds=bounds,
                 method="highs")
    if lp.status == 0:
        x = _central(As, lp.x[:nvar], lb, ub, n, float(lp.x[-1]) * (1 - CENTRAL_SLACK), rng_m)
        resid = float(np.max(np.abs(As @ x)))
        return x[:n] * col[:n], resid, True, "linear program: target is an equilibrium within bounds"
    # bounded least squares on the statics (scale fixed by m >= m_min > 0)
    ls = lsq_linear(As, np.zeros(n), bounds=(lb, ub), method="bvls", lsmr_tol="auto")
    x = ls.x
    resid = float(np.max(np.abs(As @ x)))
    return x[:n] * col[:n], resid, False, "bounded least squares on the statics (not reachable)"


#: The central masses keep this share of the linear program's margin from the bounds.
CENTRAL_SLACK = 1e-3


def _central(As: np.ndarray, x0: np.ndarray, lb: np.ndarray, ub: np.ndarray, n: int, margin: float,
             rng_m: np.ndarray) -> np.ndarray:
    """The one solution of the statics nearest the middle of every mass's bounds (relative
    to its range) that keeps ``margin`` of each range from both bounds.

    The linear program's optimum is a vertex of a face, and which vertex depends on the
    last digits of the input (the masses of a reachable target form a family: a common
    scale and, for free joints, one more parameter). This strictly convex problem, solved in
    the null space of the statics (so the target balances exactly), has a single answer that
    moves continuously with the input. Falls back to ``x0`` where it fails.
    """
    from scipy.linalg import null_space, qr
    from scipy.optimize import minimize

    N = null_space(As)
    if N.shape[1] == 0:
        return x0
    lo = lb.copy()
    hi = ub.copy()
    lo[:n] = lb[:n] + margin * rng_m
    hi[:n] = ub[:n] - margin * rng_m
    mid = (lb[:n] + ub[:n]) / 2
    z0 = N.T @ x0
    rows = np.flatnonzero(np.isfinite(lo))
    rows_hi = np.flatnonzero(np.isfinite(hi))
    Nm = N[:n] / rng_m[:, None]

    def fun(z: np.ndarray) -> tuple[float, np.ndarray]:
        r = Nm @ z - mid / rng_m
        return float(r @ r), 2 * Nm.T @ r

    cons = [{"type": "ineq", "fun": lambda z: N[rows] @ z - lo[rows], "jac": lambda z: N[rows]},
            {"type": "ineq", "fun": lambda z: hi[rows_hi] - N[rows_hi] @ z, "jac": lambda z: -N[rows_hi]}]
    # SLSQP only has to find which bounds the minimiser rests on: the polish below solves the
    # KKT system for them exactly
    res = minimize(fun, z0, jac=True, constraints=cons, method="SLSQP", options={"ftol": 1e-12, "maxiter": 200})
    z = res.x
    # polish: the constraints the solver ends on, held as equalities, give the minimiser to
    # round-off (a linear KKT system) instead of the solver's tolerance
    G = np.vstack([N[rows], -N[rows_hi]])
    h = np.concatenate([lo[rows], -hi[rows_hi]])
    scale = np.maximum(1.0, np.abs(h))
    active = np.flatnonzero(G @ z - h <= 1e-7 * scale)
    Ga, ha = G[active], h[active]
    if Ga.shape[0]:  # independent rows only
        q, r_, piv = qr(Ga.T, pivoting=True, mode="economic")
        rank = int(np.sum(np.abs(np.diag(r_)) > 1e-10 * max(1.0, abs(r_[0, 0]))))
        Ga, ha = Ga[np.sort(piv[:rank])], ha[np.sort(piv[:rank])]
    d, k = N.shape[1], Ga.shape[0]
    K = np.zeros((d + k, d + k))
    K[:d, :d] = 2 * Nm.T @ Nm
    K[:d, d:] = -Ga.T
    K[d:, :d] = Ga
    rhs = np.concatenate([2 * Nm.T @ (mid / rng_m), ha])
    try:
        sol = np.linalg.solve(K, rhs)
        zp = sol[:d]
        if np.all(G @ zp - h >= -1e-9 * scale) and np.all(sol[d:] >= -1e-9 * max(1.0, np.abs(sol[d:]).max(initial=0))):
            z = zp
    except np.linalg.LinAlgError:
        pass
    x = N @ z
    tol = 1e-9 * np.maximum(1.0, np.abs(x))
    # (the solver may stop short, e.g. "positive directional derivative" right at the
    # optimum: the polished point, when its KKT conditions hold, is the optimum anyway)
    if np.any(x < lb - tol) or np.any(x > ub + tol):
        return x0
    return x


def statics_residual(problem: InverseProblem, masses: np.ndarray) -> float:
    """Relative statics residual of the target for these masses (best reaction and moments).

    Args:
        problem: the target, rods and limits.
        masses: (N,) rod masses in the caller's mass unit.

    Returns:
        The largest scaled (dimensionless, see :func:`scaled_statics`) moment imbalance
        of the target's rods under the reaction and sign-correct stop moments that fit
        best (bounded linear least squares); zero to round-off when the target is an
        equilibrium of these masses.
    """
    n = problem.n
    A, stops, signs = statics_matrix(problem)
    row, col = scaled_statics(problem, A)
    As = (A * row[:, None]) * col[None, :]
    rest = As[:, n:]
    rhs = -As[:, :n] @ (masses / col[:n])
    lb = np.full(rest.shape[1], -np.inf)
    ub = np.full(rest.shape[1], np.inf)
    moment_signs(signs, lb[2:], ub[2:])
    sol = lsq_linear(rest, rhs, bounds=(lb, ub))
    return float(np.max(np.abs(rest @ sol.x - rhs)))
