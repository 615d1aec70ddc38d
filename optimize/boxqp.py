"""A convex quadratic program with sparse equality constraints and simple bounds.

    minimise  1/2 x' diag(q) x + c' x   subject to   A x = b,   lo <= x <= hi

with ``q >= 0`` (a separable objective, as the central mass design needs) and bounds that
may be infinite. scipy has no QP solver, so this is a primal-dual interior-point method
(Mehrotra's predictor-corrector) whose Newton systems reduce to the sparse normal
equations ``A D A' dy = r`` with D diagonal, factored by a sparse LU; a small dual
regularisation keeps them nonsingular when rows of A are dependent. The interior point
is then *polished*: the bounds it ends on are held, and the equality-constrained problem
on the other unknowns is solved exactly (a linear KKT system), so ``A x = b`` holds to
round-off.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from optimize.gram import Gram

__all__ = ["BoxQPResult", "box_qp"]


@dataclass
class BoxQPResult:
    """Solution of :func:`box_qp`.

    Attributes:
        x: the minimiser; y: multipliers of A x = b.
        success: converged (primal and dual residuals and gap below tolerance).
        nit: interior-point iterations; polished: the active-set polish succeeded.
        residual: max |A x - b| at the returned x.
        message: outcome in words.
    """

    x: np.ndarray
    y: np.ndarray
    success: bool
    nit: int
    polished: bool
    residual: float
    message: str


def _slack(x: np.ndarray, bound: np.ndarray, has: np.ndarray, sign: float) -> np.ndarray:
    """``sign * (x - bound)`` where ``has`` (1 elsewhere), never below the spacing of floats at
    the bound: an interior point that round-off puts on (or past) a bound keeps a slack as
    small as the arithmetic resolves, so its barrier terms stay finite."""
    out = np.ones_like(x)
    b = bound[has]
    out[has] = np.maximum(sign * (x[has] - b), np.spacing(np.maximum(np.abs(b), 1.0)))
    return out


def _ratio(num: np.ndarray, den: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """``num / den`` where ``mask``, 0 elsewhere (the division is done only where masked)."""
    return np.divide(num, den, out=np.zeros(np.broadcast(num, den).shape), where=mask)


def _step_to_boundary(v: np.ndarray, dv: np.ndarray) -> float:
    neg = dv < 0
    return float(np.min(-v[neg] / dv[neg])) if neg.any() else np.inf


def box_qp(q, c, A, b, lo, hi, *, tol: float = 1e-10, max_iter: int = 100) -> BoxQPResult:
    """Solve the QP of the module docstring (problem data should be scaled to order one).

    Args:
        q: (n,) the objective's diagonal, >= 0.
        c: (n,) the linear term.
        A: (k, n) sparse (or dense) equality matrix; b: (k,).
        lo, hi: (n,) bounds, -inf / inf where there is none; lo < hi where finite.
        tol: relative tolerance on the residuals and the complementarity gap.
        max_iter: interior-point iterations at most.

    Returns:
        BoxQPResult.
    """
    A = sp.csr_matrix(A)
    q, c, b = (np.asarray(v, float) for v in (q, c, b))
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    k, n = A.shape
    has_lo, has_hi = np.isfinite(lo), np.isfinite(hi)
    # start in the middle of the box (one unit inside a one-sided bound)
    x = np.zeros(n)
    both = has_lo & has_hi
    x[both] = 0.5 * (lo[both] + hi[both])
    x[has_lo & ~has_hi] = lo[has_lo & ~has_hi] + 1.0
    x[~has_lo & has_hi] = hi[~has_lo & has_hi] - 1.0
    y = np.zeros(k)
    zl = np.where(has_lo, 1.0, 0.0)
    zu = np.where(has_hi, 1.0, 0.0)
    At = A.T.tocsr()
    normal = Gram(A)
    scale = 1.0 + max(float(np.max(np.abs(b), initial=0.0)), float(np.max(np.abs(c), initial=0.0)))
    reg = 1e-12
    success = False
    it = 0
    for it in range(1, max_iter + 1):
        sl = _slack(x, lo, has_lo, 1.0)
        su = _slack(x, hi, has_hi, -1.0)
        rd = q * x + c - At @ y - zl + zu          # dual residual
        rp = b - A @ x                              # primal residual
        nb = int(has_lo.sum() + has_hi.sum())
        mu = float((np.sum(sl * zl * has_lo) + np.sum(su * zu * has_hi)) / max(nb, 1))
        if np.max(np.abs(rp), initial=0.0) <= tol * scale and np.max(np.abs(rd), initial=0.0) <= tol * scale \
                and mu <= tol * scale:
            success = True
            break
        d = q + _ratio(zl, sl, has_lo) + _ratio(zu, su, has_hi) + reg
        N = normal.matrix(1.0 / d, reg * scale)
        try:
            lu = splu(N, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
        except RuntimeError:
            reg *= 100
            continue

        # Newton system: d dx - A' dy = -rd + (zl-terms), A dx = rp
        def newton(target_l, target_u):
            rl = np.where(has_lo, target_l - sl * zl, 0.0)   # desired change in sl*zl
            ru = np.where(has_hi, target_u - su * zu, 0.0)
            rhs_x = -rd + _ratio(rl, sl, has_lo) - _ratio(ru, su, has_hi)
            dy = lu.solve(rp - A @ (rhs_x / d))
            dx = (rhs_x + At @ dy) / d
            dzl = _ratio(rl - zl * dx, sl, has_lo)
            dzu = _ratio(ru + zu * dx, su, has_hi)
            return dx, dy, dzl, dzu

        # predictor (affine scaling)
        dx, dy, dzl, dzu = newton(0.0, 0.0)
        ap = min(1.0, _step_to_boundary(sl[has_lo], dx[has_lo]), _step_to_boundary(su[has_hi], -dx[has_hi]))
        ad = min(1.0, _step_to_boundary(zl[has_lo], dzl[has_lo]), _step_to_boundary(zu[has_hi], dzu[has_hi]))
        mu_aff = float((np.sum(((sl + ap * dx) * (zl + ad * dzl))[has_lo])
                        + np.sum(((su - ap * dx) * (zu + ad * dzu))[has_hi])) / max(nb, 1))
        sigma = (mu_aff / mu) ** 3 if mu > 0 else 0.0
        # corrector with centring
        tl = sigma * mu - dx * dzl
        tu = sigma * mu + dx * dzu
        dx, dy, dzl, dzu = newton(tl, tu)
        ap = min(1.0, 0.995 * _step_to_boundary(sl[has_lo], dx[has_lo]), 0.995 * _step_to_boundary(su[has_hi], -dx[has_hi]))
        ad = min(1.0, 0.995 * _step_to_boundary(zl[has_lo], dzl[has_lo]), 0.995 * _step_to_boundary(zu[has_hi], dzu[has_hi]))
        x = x + ap * dx
        y = y + ad * dy
        zl = zl + ad * dzl
        zu = zu + ad * dzu
    x, polished = _polish(q, c, A, b, lo, hi, x, zl, zu)
    residual = float(np.max(np.abs(A @ x - b), initial=0.0))
    msg = "converged" if success else f"stopped after {it} iterations"
    return BoxQPResult(x=x, y=y, success=success, nit=it, polished=polished, residual=residual,
                       message=msg + (", polished" if polished else ""))


def _polish(q, c, A, b, lo, hi, x, zl, zu):
    """Hold the bounds the interior point ends on and solve the rest exactly."""
    width = np.where(np.isfinite(hi - lo), hi - lo, 1.0)
    at_lo = np.isfinite(lo) & ((x - lo) < 1e-7 * np.maximum(width, 1.0)) & (zl > 1e-9)
    at_hi = np.isfinite(hi) & ((hi - x) < 1e-7 * np.maximum(width, 1.0)) & (zu > 1e-9)
    fixed = at_lo | at_hi
    xf = np.where(at_lo, lo, np.where(at_hi, hi, x))
    free = ~fixed
    Af = A[:, free].tocsc()
    rhs_b = b - A[:, fixed] @ xf[fixed]
    qf = q[free] + 1e-12
    k = A.shape[0]
    K = sp.bmat([[sp.diags(qf), -Af.T], [Af, -1e-13 * sp.identity(k)]]).tocsc()
    try:
        lu = splu(K)
        sol = lu.solve(np.concatenate([-c[free], rhs_b]))
        for _ in range(2):  # iterative refinement of the regularised system
            res = np.concatenate([-c[free], rhs_b]) - K @ sol
            res[free.sum():] -= 1e-13 * sol[free.sum():]
            sol = sol + lu.solve(res)
    except RuntimeError:
        return x, False
    cand = xf.copy()
    cand[free] = sol[:int(free.sum())]
    tolb = 1e-12 * np.maximum(np.abs(cand), 1.0)
    ok = np.all(cand >= lo - tolb) & np.all(cand <= hi + tolb) & np.all(np.isfinite(cand))
    if not ok:
        # keep the interior point, made exact on A x = b by a least-change correction
        r = b - A @ x
        AAt = (A @ A.T + 1e-14 * sp.identity(k)).tocsc()
        try:
            cand = x + A.T @ splu(AAt).solve(r)
        except RuntimeError:
            return x, False
        if np.all(cand >= lo - tolb) and np.all(cand <= hi + tolb):
            return np.clip(cand, lo, hi), False
        return x, False
    return np.clip(cand, lo, hi), True
