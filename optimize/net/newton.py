"""Newton's method on the KKT system of a hanging net: restoration, descent, stability.

The equilibrium is a stable minimum of the potential energy U subject to every rod's
length, ``c_e = |P_1 - P_0| - L_e = 0`` (:mod:`optimize.net.model`). The iteration keeps
every iterate on the constraint manifold:

1. *Restoration*: from the start, Levenberg-Marquardt steps on ``|c|^2`` (minimum-norm
   steps, so the start moves as little as it must) until every rod has its length to
   round-off.
2. *Descent*: a Newton step of the KKT system, ``(H + mu D + rho J'J) dy = -r`` with
   ``r = grad U + J' lam`` and ``lam`` the least-squares multipliers (Tikhonov-regularised:
   a statically indeterminate net, a rank-deficient J, gets the tensions of minimum
   ``sum L_e lam_e^2``, those of equally stiff rods in the stiff limit). For large ``rho``
   this is the KKT step regularised by ``1/rho`` in its (2, 2) block; ``J'J`` does not
   care whether rows of J are dependent (closed loops, rods between anchors), so no rank
   decision is needed. The matrix is factored by a sparse LU with symmetric, diagonal
   pivoting (an LDL^T), whose pivots give its inertia: ``mu`` grows until it is positive
   definite (the step then descends; where it had to grow, steps are capped to a rod
   length and half a radian), and shrinks again as the iteration converges. The trial
   point is projected back onto the manifold with the same factors (a chord iteration; a
   Gauss-Newton restoration where that fails), and an Armijo line search on U, computed
   from coordinate differences, decides the step length; at round-off, where U is flat,
   a full step that halves the KKT residual is taken.
3. *Stability*: ``H`` positive definite on the tangent space ``null(J)`` is decided by
   Debreu's lemma, ``H + rho J'J`` positive definite for a large ``rho``, read from the
   same pivots; exact symmetries (a part hung from one vertical line of anchors turns
   about it, a node body spins about the line of its pivots) are held fixed by one unknown
   each (:func:`optimize.net.deriv.gauge_rows`). A KKT point that is not stable is left
   along its most negative curvature (a dense eigensolver up to :data:`DENSE_EIG_NVAR`
   unknowns, ARPACK above, an LDL^T pivot where ARPACK fails), and the descent resumes;
   so is a descent that creeps by proximal steps along a curvature too flat to leave
   (:data:`CREEP`). ``max_escapes=0`` reports the first KKT point as it is, stable or not
   (a design check asks that of its target).

Each iteration costs one or a few sparse factorizations of an ``nvar x nvar`` matrix with
the net's sparsity (``nvar`` = 3 per free node, + 3 per free node body).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from optimize.gram import Gram
from optimize.net.deriv import Hess, NetEval, assemble, energy_change, evaluate, gauge_rows, hessian
from optimize.net.model import Net, NetState

__all__ = ["Factor", "Outcome", "descend", "factor", "is_stable", "kkt_residual", "multipliers", "newton_matrix",
           "pd_factor", "restore", "spd_lu"]

#: The penalty weight rho of the regularised KKT step, in units of the force scale / length.
RHO = 1e6
#: Relative KKT residual the descent aims at, and the one that counts as converged.
TARGET = 1e-14
CONVERGED = 1e-10
#: A descent that has needed a proximal weight (negative curvature) and not halved its KKT
#: residual in CREEP iterations, below CREEP_KKT, leaves along the most negative curvature as
#: from an unstable equilibrium: the proximal steps along a curvature that flat are too short.
CREEP = 6
CREEP_KKT = 1e-5


def _force_scale(net: Net, lam: np.ndarray | None) -> float:
    """The larger of the net's weight and its largest |tension|: what round-off scales with."""
    big = float(np.max(np.abs(lam), initial=0.0)) if lam is not None else 0.0
    return max(net.weight, big)


def multipliers(net: Net, ev: NetEval) -> np.ndarray:
    """(m,) least-squares multipliers (tensions) of minimum sum L_e lam_e^2.

    Iterated Tikhonov on ``J' lam = -grad U``: exact where J has full row rank; where it
    has not (a self-stress: tensions the net's statics leave open), the weighted minimum
    norm, i.e. the tensions of rods of equal axial stiffness EA in the limit EA -> inf.
    """
    J = ev.J
    if net.nvar == 0:
        return np.zeros(net.m)
    if ev.pattern.gram is None:  # J J' on J's pattern (the same matrix as (J @ J.T).tocsc())
        ev.pattern.gram = Gram(J, reverse=False)
    sums = ev.pattern.gram.sums(data=J.data)  # J J' summed once for both matrices
    JJ = ev.pattern.gram.assemble(sums)
    w = net.lengths / net.mean_length
    eps = 1e-10 * max(float(JJ.diagonal().max(initial=0.0)), 1e-300)
    lu = spd_lu(ev.pattern.gram.assemble(sums, eps * w))  # (JJ + diags(eps w)).tocsc()
    rhs = -(J @ ev.grad)
    lam = lu.solve(rhs)
    for _ in range(3):
        lam = lam + lu.solve(rhs - JJ @ lam)
    return lam


def kkt_residual(net: Net, ev: NetEval, lam: np.ndarray) -> tuple[float, np.ndarray]:
    """(relative KKT residual, r = grad U + J' lam).

    The largest of: the force imbalance at a free node over the force scale (the larger of
    the weight and the largest |tension|), the moment imbalance of a free node body over
    that scale times the mean rod length, and each rod's length error over its length.
    """
    r = ev.grad + ev.jt(lam)
    F = _force_scale(net, lam)
    nf = int(np.count_nonzero(net.pos_idx >= 0))
    scale = np.full(net.nvar, F)
    scale[3 * nf:] *= net.mean_length
    res = float(np.max(np.abs(r) / scale, initial=0.0))
    res = max(res, float(np.max(np.abs(ev.c) / net.lengths, initial=0.0)))
    return res, r


#: The line search restores a step by Levenberg-Marquardt only where no rod's length is off
#: by more than this (over its length) after the step.
RESTORE_FROM = 1.0


@dataclass
class Factor:
    """A factorization of K = H + mu D + rho (J'J + gauge), positive definite."""

    lu: object
    rho: float
    mu: float
    ev: NetEval  # the evaluation K was assembled at (its J)

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self.lu.solve(b)


def spd_lu(A: sp.spmatrix):
    """Sparse LU of a symmetric positive definite (or quasi-definite) matrix with a
    fill-reducing symmetric order and symmetric, diagonal pivoting (a Cholesky, an LDL^T, in
    effect: far less fill than partial pivoting)."""
    return splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})


def pd_factor(K: sp.spmatrix):
    """An LDL^T-like factorization of symmetric K when K is positive definite, else None."""
    try:
        lu = spd_lu(K)
    except RuntimeError:  # an exactly zero pivot: singular
        return None
    d = lu.U.diagonal()
    if not np.array_equal(lu.perm_r, lu.perm_c) or not np.all(d > 0) or not np.all(np.isfinite(d)):
        return None
    small = 1e-14 * float(np.max(np.abs(K.diagonal()), initial=0.0))  # round-off of the pivots
    if np.min(d) <= small:
        return None
    return lu


def newton_matrix(net: Net, hess, ev: NetEval, gauge: np.ndarray, mu: float, rho: float, s_h: float):
    """K = H + mu s_h D + rho s_h (J'J + the gauge rows' squares), CSC."""
    diag = net.var_scale * (mu * s_h)
    diag[gauge] += rho * s_h
    return assemble(net, hess, ev, rho=rho * s_h, diag=diag)


def factor(net: Net, hess, ev: NetEval, gauge: np.ndarray, s_h: float, mu0: float = 0.0, rho: float = RHO):
    """Factor K with a proximal weight mu >= mu0 (relative, in s_h) that makes it positive
    definite: (Factor, mu). mu runs 0, 1e-6, 1e-5, ... (times s_h); where K needed more
    than mu0 (H has negative curvature on the tangent space), ten times the first weight
    that works, so that the step along that curvature stays of the size mu sets, not of
    the size of what little curvature is left."""
    mu = mu0
    raised = False
    for _ in range(24):
        lu = pd_factor(newton_matrix(net, hess, ev, gauge, mu, rho, s_h))
        if lu is not None:
            if raised:
                mu *= 10
                lu = pd_factor(newton_matrix(net, hess, ev, gauge, mu, rho, s_h)) or lu
            return Factor(lu, rho * s_h, mu, ev), mu
        mu = 1e-6 if mu == 0 else mu * 10
        raised = True
    raise FloatingPointError("no proximal weight made the Newton matrix positive definite")


def is_stable(net: Net, state: NetState, ev: NetEval, lam: np.ndarray) -> bool:
    """Second-order sufficiency: H positive definite on the tangent space of the
    constraints, modulo the net's exact symmetries (Debreu's lemma, read from the pivots
    of an LDL^T of H + rho J'J for rho of 1e6 and 1e10 times the force scale / length)."""
    if net.nvar == 0:
        return True
    hess = hessian(net, state, ev, lam)
    gauge = gauge_rows(net, state, ev)
    s_h = _force_scale(net, lam) / net.mean_length
    for rho in (RHO, 1e10):
        if pd_factor(newton_matrix(net, hess, ev, gauge, 0.0, rho, s_h)) is not None:
            return True
    return False


#: Up to this many unknowns the direction of most negative curvature comes from a dense
#: symmetric eigensolver (LAPACK's, exact and the same on every run); above, from ARPACK's
#: shift-invert. ARPACK far from the spectrum cannot always separate close negative
#: curvatures (a saddle with two of -0.68 and -0.68): it then stops without converging, and
#: whether it did went either way on round-off.
DENSE_EIG_NVAR = 1000


def _negative_direction(net: Net, state: NetState, ev: NetEval, lam: np.ndarray):
    """A unit direction of negative curvature of K = H + rho J'J (None if none): the most
    negative one (a dense eigensolver up to :data:`DENSE_EIG_NVAR` unknowns, ARPACK above), or
    where ARPACK does not converge, one read from an LDL^T of K (:func:`_pivot_direction`)."""
    from scipy.sparse.linalg import eigsh

    hess = hessian(net, state, ev, lam)
    gauge = gauge_rows(net, state, ev)
    s_h = _force_scale(net, lam) / net.mean_length
    K = newton_matrix(net, hess, ev, gauge, 0.0, RHO, s_h)
    if K.shape[0] <= DENSE_EIG_NVAR:
        from scipy.linalg import LinAlgError, eigh

        try:
            vals, vecs = eigh(K.toarray(), subset_by_index=[0, 0])
        except (LinAlgError, ValueError):  # (a non-finite K: no direction)
            return None
        return vecs[:, 0] if vals[0] < 0 else None
    bound = float(abs(K).sum(axis=1).max())
    try:
        v0 = np.random.default_rng(0).standard_normal(K.shape[0])  # (ARPACK's own start is random)
        vals, vecs = eigsh(K, k=1, sigma=-2 * bound, which="LM", maxiter=2000, v0=v0)
    except Exception:  # noqa: BLE001 - ARPACK's failures are many: the factorization's direction then
        return _pivot_direction(K)
    if vals[0] >= 0:
        return None
    return vecs[:, 0]


def _pivot_direction(K: sp.spmatrix):
    """A unit direction v with v'Kv < 0 from a symmetric LDL^T of K (P K P' = L D L'): for the
    most negative pivot d_k, v = P' L'^-1 e_k gives v'Kv = d_k. None where the factorization
    pivots off the diagonal or no pivot is negative."""
    from scipy.sparse.linalg import spsolve_triangular

    try:
        lu = spd_lu(K)
    except RuntimeError:
        return None
    d = lu.U.diagonal()
    if not np.array_equal(lu.perm_r, lu.perm_c) or not np.all(np.isfinite(d)) or d.min() >= 0:
        return None
    L = sp.csr_matrix(lu.L)
    scale = np.empty_like(d)
    scale[lu.perm_c] = np.abs(K.diagonal())  # (K's diagonal in the factor's order)
    k = int(np.argmin(d / np.maximum(scale, 1e-300)))
    e = np.zeros(K.shape[0])
    e[k] = 1.0
    try:
        w = spsolve_triangular(L.T.tocsr(), e, lower=False, unit_diagonal=True)
    except (np.linalg.LinAlgError, ValueError):
        return None
    v = w[lu.perm_c]
    if not np.all(np.isfinite(v)):
        return None
    return v / np.linalg.norm(v)


@dataclass
class Outcome:
    """Where the iteration ended."""

    state: NetState
    ev: NetEval
    lam: np.ndarray
    kkt: float
    status: int
    nit: int = 0
    nrestore: int = 0
    nfactor: int = 0
    escapes: int = 0


def _violation(net: Net, ev: NetEval) -> float:
    return float(np.max(np.abs(ev.c) / net.lengths, initial=0.0))


def _feasible_tol(net: Net, state: NetState) -> float:
    """Relative length error that round-off allows at these coordinates."""
    size = float(np.max(np.abs(state.x), initial=0.0)) + float(np.max(net.lengths))
    return 64 * np.finfo(float).eps * size / float(np.min(net.lengths))


def restore(net: Net, state: NetState, max_iter: int = 200, nu: float = 1e-3) -> tuple[NetState, NetEval, bool, int]:
    """Levenberg-Marquardt on ``sum c_e^2`` from ``state``: (state, eval, feasible, iterations).

    ``nu`` is the first damping (relative to J'J's entries, which are of order one): small
    near the manifold (Gauss-Newton, quadratic), larger from a far start."""
    ev = evaluate(net, state)
    tol = _feasible_tol(net, state)
    if net.nvar == 0:
        return state, ev, _violation(net, ev) <= tol, 0
    cost = float(ev.c @ ev.c)
    zero = Hess(np.zeros((net.m, net.loc.shape[1], net.loc.shape[1])), np.zeros((0, 3, 3)))
    for it in range(1, max_iter + 1):
        if _violation(net, ev) <= tol:
            return state, ev, True, it - 1
        g = ev.jt(ev.c)
        improved = False
        for _ in range(30):
            A = assemble(net, zero, ev, rho=1.0, diag=nu * net.var_scale)
            try:
                dy = -spd_lu(A).solve(g)
            except RuntimeError:
                nu *= 10
                continue
            trial = state.moved(net, dy)
            tev = evaluate(net, trial, full=False)
            tcost = float(tev.c @ tev.c)
            if tcost < cost:
                state, ev, cost = trial, evaluate(net, trial), tcost
                nu = max(nu / 10, 1e-12)
                improved = True
                break
            nu *= 10
        if not improved:
            break
    return state, ev, _violation(net, ev) <= tol, it


def _project(net: Net, state: NetState, fac: Factor, tol: float, max_iter: int = 20):
    """Back onto the manifold with the step's factors: (state, eval, ok).

    A chord iteration: the Jacobian stays the one ``fac`` was assembled with (a fresh one
    would put part of ``J' c`` across the tangent space, where ``rho`` amplifies it)."""
    ev = evaluate(net, state, full=False)
    viol = _violation(net, ev)
    ok = viol <= tol
    for _ in range(max_iter):
        if ok:
            break
        d = -fac.solve(fac.rho * fac.ev.jt(ev.c))
        trial = state.moved(net, d)
        tev = evaluate(net, trial, full=False)
        tv = _violation(net, tev)
        state, ev = trial, tev
        ok = tv <= tol
        if not ok and not tv < 0.9 * viol:
            break
        viol = tv
    return state, ev, ok


def descend(net: Net, state: NetState, *, max_iter: int = 200, max_escapes: int = 3,
            patience: int | None = None) -> Outcome:
    """From a feasible ``state``: Newton descent to a stable KKT point (see the module).

    ``patience``: stop (status 3) when the KKT residual has not halved in this many
    iterations (None: run to ``max_iter``)."""
    ev = evaluate(net, state)
    lam = multipliers(net, ev)
    kkt, r = kkt_residual(net, ev, lam)
    nfactor = 0
    escapes = 0
    asked = 0  # creeps asked for a way down
    mu = 0.0
    status = 1
    it = 0
    stall = 0
    best = (kkt, 0)  # (KKT residual, iteration) where it last fell to half the mark before
    first = 1.0  # the line search's first step: up from the last one accepted (see below)
    while it < max_iter:
        down = None
        if kkt <= TARGET or (kkt <= CONVERGED and stall >= 2):
            if escapes < max_escapes and not is_stable(net, state, ev, lam):
                down = _way_down(net, state, ev, lam)
            if down is None:
                status = 0
                break
        elif mu > 0 and stall >= CREEP and kkt <= CREEP_KKT and escapes < max_escapes and asked < max_escapes:
            # creeping by a proximal step along negative curvature too flat to leave in a step
            # (a hub balanced upside down whose centre of mass lies a hair off its spin axis)
            asked += 1  # (each ask costs an eigensolve: as many as the escapes allowed, found or not)
            down = _way_down(net, state, ev, lam)
            stall = 0  # (none found: on for another CREEP iterations before asking again)
        if down is not None:
            escapes += 1
            state, ev, lam, kkt, r = down
            mu, stall, first = 0.0, 0, 1.0
            best = (kkt, it)  # (patience counts from the escape: a new descent)
            continue
        if patience is not None and it - best[1] >= patience:
            status = 3
            break
        it += 1
        hess = hessian(net, state, ev, lam)
        gauge = gauge_rows(net, state, ev)
        s_h = _force_scale(net, lam) / net.mean_length
        fac, mu = factor(net, hess, ev, gauge, s_h, mu0=mu)
        nfactor += 1
        dy = -fac.solve(r)
        if mu > 0:
            dy = _capped(net, dy)
        slope = float(r @ dy)
        tol = _feasible_tol(net, state)
        alpha = first
        accepted = False
        for _ in range(40):
            moved = state.moved(net, alpha * dy)
            trial, tev, ok = _project(net, moved, fac, tol)
            if not ok and alpha >= 0.1 and _violation(net, evaluate(net, moved, full=False)) <= RESTORE_FROM:
                # the chord iteration fails where J turns fast (a flat net whose rods swing
                # out of its plane): Levenberg-Marquardt with fresh Jacobians (not from a step
                # that stretched a rod past twice its length: rarely back within its
                # iterations, while a shorter step costs one projection)
                trial, tev, ok, _ = restore(net, moved, max_iter=30, nu=1e-8)
            if ok:
                drop = energy_change(net, state, ev, trial, tev)
                if drop <= 1e-4 * alpha * slope:
                    accepted = True
                    break
                if alpha == 1.0 and kkt <= 1e-6:
                    # near the minimum the energy is flat to round-off: Newton's full step
                    # counts when it halves the KKT residual
                    tev = evaluate(net, trial)
                    if kkt_residual(net, tev, multipliers(net, tev))[0] <= 0.5 * kkt:
                        accepted = True
                        break
            alpha *= 0.5
        if not accepted:
            if kkt <= CONVERGED:
                stall = 2  # at round-off already: stop here
                continue
            if mu < 1e3:
                mu = max(mu * 100, 1e-4)  # a shorter, more gradient-like step
                continue
            status = 3
            break
        # far from the equilibrium the full Newton step can move nodes by rod lengths: the next
        # search starts at four times the step just taken (a failed try of a long step costs a
        # restoration of tens of factorizations), back to the full step within a few iterations
        first = min(1.0, 4.0 * alpha)
        old = kkt
        state, ev = trial, (tev if tev.grad is not None else evaluate(net, trial))
        lam = multipliers(net, ev)
        kkt, r = kkt_residual(net, ev, lam)
        stall = stall + 1 if kkt > 0.5 * old else 0
        if kkt <= 0.5 * best[0]:
            best = (kkt, it)
        mu = mu / 10 if mu > 1e-6 else 0.0
    if status == 1 and kkt <= CONVERGED:
        status = 0
    return Outcome(state, ev, lam, kkt, status, nit=it, nfactor=nfactor, escapes=escapes)


def _way_down(net: Net, state: NetState, ev: NetEval, lam: np.ndarray):
    """(state, ev, lam, kkt, r) a step down along the most negative curvature from ``state``
    (:func:`_negative_direction`, :func:`_escape`), or None where there is none."""
    v = _negative_direction(net, state, ev, lam)
    moved = _escape(net, state, ev, v) if v is not None else None
    if moved is None:
        return None
    state, ev = moved
    lam = multipliers(net, ev)
    kkt, r = kkt_residual(net, ev, lam)
    return state, ev, lam, kkt, r


def _capped(net: Net, dy: np.ndarray) -> np.ndarray:
    """The step scaled down (direction kept) so that no node moves more than a mean rod
    length and no body turns more than half a radian: used where H has negative curvature
    (the proximal weight mu is on), whose steps the quadratic model does not bound."""
    nf = int(np.count_nonzero(net.pos_idx >= 0))
    pos = float(np.max(np.abs(dy[:3 * nf]), initial=0.0)) / net.mean_length
    rot = float(np.max(np.abs(dy[3 * nf:]), initial=0.0)) / 0.5
    big = max(pos, rot)
    return dy / big if big > 1 else dy


def _escape(net: Net, state: NetState, ev: NetEval, v: np.ndarray):
    """A feasible point lower than ``state`` along +-v (scaled to a tenth of a rod), or None."""
    nf = int(np.count_nonzero(net.pos_idx >= 0))
    pos = np.abs(v[:3 * nf]).max(initial=0.0)
    rot = np.abs(v[3 * nf:]).max(initial=0.0) * net.mean_length
    big = max(pos, rot)
    if big == 0:
        return None
    step = v * (0.1 * net.mean_length / big)
    best = None
    for sign in (1.0, -1.0):
        trial, tev, ok = restore(net, state.moved(net, sign * step))[:3]
        if ok and energy_change(net, state, ev, trial, tev) < 0 and (best is None or tev.energy < best[1].energy):
            best = (trial, tev)
    return best
