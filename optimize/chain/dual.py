"""One active set: the equilibrium with given joints and anchor stops held, by the convex dual.

For an active set (:class:`optimize.chain.model.ActiveSet`) every rigid group that no fixture
holds turns along its load ``W_G = P_G lambda - Q_G``; minimising the Lagrangian over
those angles leaves the dual function of the closure multiplier lambda = (H, V)::

    Psi(lambda) = sum_{free G} |P_G lambda - Q_G| - Re(conj(d) lambda)

with ``d`` = B - A minus the chords of the groups held by anchor stops (their angles are
fixed, so their chords are constants). Psi is convex; its gradient is the closure residual,
and damped Newton (:func:`dual_newton`) minimises it from any start in O(groups) per step.

A set whose free groups cannot move (at most one free group, the chain closed exactly by
the held ones: a piece fused between two fixtures, say) is statically indeterminate:
:func:`rigid_reaction` picks the smallest reaction for which every held stop and fixture
pushes the right way, by a small linear program.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass, replace

import numpy as np

from optimize.chain.model import ActiveSet, Chain, kkt_residual

__all__ = [
    "SET_CACHE",
    "SetSolution",
    "close_at_kink",
    "dual_newton",
    "initial_reaction",
    "rigid_reaction",
    "solve_set",
]

#: How many answers of :func:`solve_set` are kept: a multi-start's starts and the planner's
#: repeated checks of one chain walk through the same active sets from the same reactions,
#: and the answer is a function of (chain, set, start) alone (the least recently used goes).
SET_CACHE = 4096

_solved: OrderedDict[bytes, SetSolution | None] = OrderedDict()


@dataclass
class SetSolution:
    """The equilibrium for one active set.

    Attributes:
        theta: (N,) rod angles (radians).
        lam: the reaction (H, V) at B as H + iV (force).
        W: the free groups' loads P lambda - Q (None for a rigid set).
        newton: dual Newton iterations.
        converged: the dual solve converged (or closed at a kink), or the rigid set's
            statics were found.
    """

    theta: np.ndarray
    lam: complex
    W: np.ndarray | None
    newton: int
    converged: bool


def initial_reaction(chain: Chain) -> complex:
    """A rough (H, V): the two-bar V with the whole weight hung at mid-span."""
    weight = chain.g * chain.total_mass
    slack = np.sqrt(max(chain.total_length**2 - chain.span**2, 1e-6 * chain.total_length**2))
    h = 0.5 * weight * chain.d.real / slack
    if abs(h) < 1e-3 * weight:
        h = 1e-3 * weight
    return complex(h, 0.5 * weight + 0.5 * weight * chain.d.imag / slack)


def dual_newton(P, Q, d, lam, length_scale, max_iter=200):
    """Minimise Psi(lam) = sum|P lam - Q| - Re(conj(d) lam) by damped Newton.

    Returns (lam, W = P lam - Q, iterations, converged).
    """
    absP = np.abs(P)
    absP2 = absP * absP
    safeP = np.where(absP > 0, absP, 1.0)
    tol = 64 * np.finfo(float).eps * length_scale
    tiny = 1e-300

    def evaluate(lam):
        W = P * lam - Q
        r = np.abs(W)
        rs = np.maximum(r, tiny)
        u = W / rs
        grad = np.sum(np.conj(P) * u) - d
        psi = float(r.sum() - (np.conj(d) * lam).real)
        return W, rs, u, grad, psi

    W, r, u, grad, psi = evaluate(lam)
    best_gn = abs(grad)
    stall = 0
    load_scale = float(np.max(np.abs(Q) / safeP)) if Q.size else 0.0
    for it in range(1, max_iter + 1):
        gn = abs(grad)
        if gn <= tol:
            return lam, W, it - 1, True
        a = absP2 / r
        v = u * np.conj(P) / safeP
        vx, vy = v.real, v.imag
        hxx = float(np.sum(a * vy * vy))
        hyy = float(np.sum(a * vx * vx))
        hxy = -float(np.sum(a * vx * vy))
        det = hxx * hyy - hxy * hxy
        trace = hxx + hyy
        if not np.isfinite(det) or det <= 1e-14 * trace * trace:
            reg = 1e-8 * trace + tiny
            hxx += reg
            hyy += reg
            det = hxx * hyy - hxy * hxy
        gx, gy = grad.real, grad.imag
        step = complex(-(hyy * gx - hxy * gy) / det, -(hxx * gy - hxy * gx) / det)
        slope = (np.conj(grad) * step).real
        trial = lam + step
        W1, r1, u1, g1, psi1 = evaluate(trial)
        if not _accepted(psi, psi1, 1.0, slope, lambda: abs(g1) < gn):
            # backtracking by halves down to 2^-40, Psi at several step lengths at once (the
            # steps of a near-piecewise-linear Psi are cut 7-8 times on average): the first
            # one that decreases Psi enough is taken
            k = 1 + _first_accepted(P, Q, d, lam, step, psi, slope, lambda x: abs(evaluate(x)[3]) < gn)
            trial = lam + 0.5**k * step
            W1, r1, u1, g1, psi1 = evaluate(trial)
        lam, W, r, u, grad, psi = trial, W1, r1, u1, g1, psi1
        k = int(np.argmin(r / safeP))
        if r[k] <= 1e-6 * load_scale * safeP[k]:
            # near a group's kink (W_k = 0): is lam_k = Q_k / P_k the minimum? It is when
            # the rest's gradient lies within the subdifferential |P_k| of that term.
            lam_k = Q[k] / P[k]
            W_k = P * lam_k - Q
            W_k[k] = 0.0
            u_k = W_k / np.maximum(np.abs(W_k), tiny)
            if abs(np.sum(np.conj(P) * u_k) - d) <= absP[k] * (1 + 1e-12):
                return lam_k, W_k, it, False
        if abs(grad) < best_gn * 0.999:
            best_gn = abs(grad)
            stall = 0
        else:
            stall += 1
            if stall >= 3 and best_gn <= 1e-9 * length_scale:
                return lam, W, it, True  # at the floor of round-off
            if stall >= 20:
                break
            if stall >= 5 and r[k] <= 1e-10 * load_scale * safeP[k]:
                lam = Q[k] / P[k]  # no load left on group k: the minimum sits on its kink
                return lam, P * lam - Q, it, False
    return lam, W, max_iter, abs(grad) <= 1e-9 * length_scale


#: The line search halves a step down to 2^-HALVINGS of the Newton step, evaluating Psi at
#: BATCH lengths in one array operation (a step is cut 7-8 times on average).
HALVINGS = 40
BATCH = 8


def _accepted(psi: float, psi1: float, t: float, slope: float, gradient_falls) -> bool:
    """Armijo's test on Psi at step length ``t``; where the change of Psi is below its
    round-off, whether the gradient's norm falls (``gradient_falls()``)."""
    if psi1 <= psi + 1e-4 * t * slope:
        return True
    noise = 1e3 * np.finfo(float).eps * (abs(psi) + abs(psi1))
    return abs(psi1 - psi) <= noise and gradient_falls()


def _first_accepted(P, Q, d, lam: complex, step: complex, psi: float, slope: float, gradient_falls) -> int:
    """Index k (0-based, step length 2^-(k+1)) of the first halved step that
    :func:`_accepted` takes, or the last one: Psi at :data:`BATCH` lengths at a time in one
    array operation. ``gradient_falls(lam)`` is asked only where Psi's change is round-off."""
    for first in range(0, HALVINGS, BATCH):
        ts = 0.5 ** np.arange(first + 1, min(first + BATCH, HALVINGS) + 1)
        lams = lam + ts * step
        psis = np.abs(P[None, :] * lams[:, None] - Q[None, :]).sum(axis=1) - (np.conj(d) * lams).real
        for j, t in enumerate(ts):
            if _accepted(psi, float(psis[j]), float(t), slope, lambda: gradient_falls(lam + t * step)):
                return first + j
    return HALVINGS - 1


def close_at_kink(chain: Chain, aset: ActiveSet, W: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Exact closure when the dual optimum sits next to a kink.

    When one free group carries almost no load (|W_G| -> 0, e.g. a bottom rod that spans a
    slack chain exactly horizontally) Newton converges slowly and stops a little short.
    That group's angle is then undetermined by statics; turn it so the chain closes.
    """
    groups = aset.groups
    chords = np.add.reduceat(chain.lengths * np.exp(1j * theta), groups.starts)
    miss = chords.sum() - chain.d
    if abs(miss) <= 1e-14 * chain.total_length or not W.size:
        return theta
    free = np.flatnonzero(aset.free)
    load = np.abs(W) / np.maximum(groups.chords[free], 1e-300)
    g = int(free[np.argmin(load)])
    need = chain.d - (chords.sum() - chords[g])
    if abs(abs(need) - groups.chords[g]) > 1e-6 * chain.total_length:
        return theta  # not a kink: leave it to the KKT check
    turn = np.angle(need / chords[g])
    out = theta.copy()
    out[groups.gid == g] += turn
    return np.unwrap(out)


def rigid_reaction(chain: Chain, theta: np.ndarray, act: np.ndarray) -> complex:
    """The reaction at B of a set that cannot move (:meth:`ActiveSet.closes_rigidly`).

    Such a set is statically indeterminate: the free joints' moments are zero (linear
    equations in H, V and the first fixture's moment M_0) and every held stop and fixture
    must push the right way (inequalities). Of those the linear program takes the one whose
    fixtures carry the least moment (|M_0| + |M_1|), then the smallest |H| + |V|; when none
    exists, the least-squares solution of the equations, whose wrong-sign moments then tell
    the active-set iteration which stop to let go.

    Args:
        chain: the problem.
        theta: (N,) the set's rod angles (radians).
        act: (N+1,) the active set.

    Returns:
        lam = H + iV (force).
    """
    from scipy.optimize import linprog

    side, ends = act[1:-1], act[[0, -1]]
    l, e = chain.lengths, np.exp(1j * theta)
    weight, length = chain.g * chain.total_mass, chain.total_length
    # cum_j = a_j H + b_j V + c_j: the joint moments with no fixture (optimize.chain.model.multipliers)
    a = -np.cumsum(l * e.imag) * weight
    b = np.cumsum(l * e.real) * weight
    c = np.cumsum(l * (np.conj(chain.sigma) * e).imag)
    scale = weight * length
    # unknowns x = (H / weight, V / weight, M_0 / scale); rows in units of weight x length
    rows = np.column_stack([a, b, np.full(chain.n, scale)]) / scale
    const = c / scale  # mu_j = rows[j] . x + const[j]; M_1 = -(rows[N-1] . x + const[N-1])
    eq = [j for j in range(chain.n - 1) if side[j] == 0] + ([chain.n - 1] if not ends[1] else [])
    ub_rows, ub_rhs = [], []
    for j in range(chain.n - 1):
        if side[j] and not chain.fixed[j]:  # side_j * mu_j <= 0
            ub_rows.append(side[j] * rows[j])
            ub_rhs.append(-side[j] * const[j])
    if ends[0] and not chain.end_fixed[0]:
        ub_rows.append(np.array([0.0, 0.0, float(ends[0])]))
        ub_rhs.append(0.0)
    if ends[1] and not chain.end_fixed[1]:  # ends_1 * M_1 <= 0
        ub_rows.append(-ends[1] * rows[-1])
        ub_rhs.append(ends[1] * const[-1])
    m0_bounds = (None, None) if ends[0] else (0.0, 0.0)
    # x = (h, v, m0, th, tv, t0, t1) with th >= |h|, tv >= |v|, t0 >= |M_0|, t1 >= |M_1|:
    # the fixtures carry as little as the statics allow, then the pins' reaction is least
    k = len(ub_rows)
    A_ub = np.zeros((k + 8, 7))
    A_ub[:k, :3] = np.array(ub_rows).reshape(-1, 3)
    b_ub = np.concatenate([ub_rhs, np.zeros(8)])
    for i, (col, t) in enumerate(((0, 3), (1, 4), (2, 5))):
        A_ub[k + 2 * i, [col, t]] = [1.0, -1.0]
        A_ub[k + 2 * i + 1, [col, t]] = [-1.0, -1.0]
    A_ub[k + 6, :3], A_ub[k + 6, 6], b_ub[k + 6] = -rows[-1], -1.0, const[-1]  # -M_1 <= t1
    A_ub[k + 7, :3], A_ub[k + 7, 6], b_ub[k + 7] = rows[-1], -1.0, -const[-1]  # M_1 <= t1
    A_eq = np.hstack([rows[eq], np.zeros((len(eq), 4))]) if eq else None
    b_eq = -const[eq] if eq else None
    big = 1e9
    cost = np.array([0, 0, 0, 1e-3, 1e-3, 1.0, 1.0])
    res = linprog(cost, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=b_eq,
                  bounds=[(-big, big), (-big, big), m0_bounds] + [(0, None)] * 4, method="highs")
    if res.status == 0:
        x = res.x
    else:
        cols = [0, 1, 2] if ends[0] else [0, 1]
        x = np.zeros(3)
        if eq:
            x[cols], *_ = np.linalg.lstsq(rows[eq][:, cols], -const[eq], rcond=None)
    return complex(x[0] * weight, x[1] * weight)


def _problem_key(chain: Chain, aset: ActiveSet, lam: complex) -> bytes:
    """Every number the set's solution depends on, to the bit (the chain's arrays, its
    gravity, the active set, the starting reaction)."""
    arrays = (chain.lengths, chain.masses, chain.com, chain.limits, chain.anchor_a, chain.anchor_b,
              chain.end_limits, np.array([chain.g]), np.array([lam], complex), aset.act)
    return b"|".join(f"{a.dtype.str}{a.shape}".encode() + np.ascontiguousarray(a).tobytes() for a in arrays)


def _copy(sol: SetSolution | None) -> SetSolution | None:
    if sol is None:
        return None
    return replace(sol, theta=sol.theta.copy(), W=None if sol.W is None else sol.W.copy())


def solve_set(chain: Chain, aset: ActiveSet, lam: complex) -> SetSolution | None:
    """The equilibrium for one active set: every free group along its load (kept: the
    same question again is answered from :data:`SET_CACHE`, the same answer).

    Args:
        chain: the problem.
        aset: the active set (joints and anchor stops held).
        lam: the starting reaction (H + iV) for the dual Newton.

    Returns:
        SetSolution, or None when the set cannot close the chain.
    """
    key = _problem_key(chain, aset, lam)
    if key in _solved:
        _solved.move_to_end(key)
        return _copy(_solved[key])
    sol = _solve_set(chain, aset, lam)
    _solved[key] = _copy(sol)
    if len(_solved) > SET_CACHE:
        _solved.popitem(last=False)
    return sol


def _solve_set(chain: Chain, aset: ActiveSet, lam: complex) -> SetSolution | None:
    if aset.reachable():
        free = aset.free
        P, Q = aset.groups.P[free], aset.groups.Q[free]
        lam_new, W, k, converged = dual_newton(P, Q, aset.d, lam, chain.total_length)
        theta = close_at_kink(chain, aset, W, aset.angles(np.angle(W)))
        if not converged:
            # a kink where the unloaded group just fits the gap: closure decides its angle
            converged = kkt_residual(chain, theta, lam_new, aset.act) < 1e-10
        return SetSolution(theta, lam_new, W, k, converged)
    if aset.closes_rigidly(chain):
        free = aset.free
        psi = np.angle(aset.d / np.conj(aset.groups.P[free])) if free.any() else np.zeros(0)
        theta = aset.angles(psi)
        return SetSolution(theta, rigid_reaction(chain, theta, aset.act), None, 0, True)
    return None
