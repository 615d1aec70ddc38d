"""Rigid groups on either branch: the exact equilibrium when some piece is compressed.

For a fixed active set (joints held at a limit) each rigid group G turns along its
load ``W_G = P_G lambda - Q_G`` (branch +1, the minimiser of the Lagrangian in the
group's angle) or against it (branch -1: the piece pushes, e.g. an arch held up by
its stops). The convex dual Newton of :mod:`optimize.chain.equilibrium` handles branch +1
only; this module handles the rest:

* :func:`descend`: a primal active-set Newton method over (side, branch) that reaches a
  stable KKT point from a start within milliseconds, made exact by
* :func:`branch_newton`: Newton on the closure for a given side and branch per group;
* :func:`polish_nlp`: the last resort, SLSQP from several starts, each result polished
  by :func:`polish_point`.

Anchor stops (bounds on the end rods' angles) are stops like the joints': the active set
here is the (N+1,) array of :class:`optimize.chain.model.ActiveSet`, a held anchor stop fixes its
group's angle (no Newton step moves it), a free end rod's angle blocks a step at its bound,
and a fixture moment of the wrong sign lets it go.
"""

from __future__ import annotations

import numpy as np

from optimize.chain.model import ActiveSet, Chain, Groups, fixture_moments, multipliers, violations
from optimize.chain.dual import rigid_reaction
from optimize.chain.endlimits import limit_turn, near, reach

__all__ = ["branch_newton", "descend", "polish_nlp", "polish_point", "reach_start"]


def _nlp_point(chain: Chain, theta0: np.ndarray) -> np.ndarray | None:
    """SLSQP on the angles: a feasible local minimum to restart from when exchanges fail."""
    from scipy.optimize import minimize

    l = chain.lengths
    c_sin, c_cos = chain.c_sin, chain.c_cos
    dx, dy = chain.d.real, chain.d.imag
    lo, hi = chain.limits[:, 0], chain.limits[:, 1]
    n = chain.n
    D = np.zeros((n - 1, n))
    D[np.arange(n - 1), np.arange(n - 1)] = -1.0
    D[np.arange(n - 1), np.arange(1, n)] = 1.0
    has_lo, has_hi = np.isfinite(lo), np.isfinite(hi)
    A = np.vstack([D[has_lo], -D[has_hi]])
    b = np.concatenate([lo[has_lo], -hi[has_hi]])
    for k, rod in ((0, 0), (1, n - 1)):  # anchor stops on the turn of the start's end angles
        lim = reach(chain.end_limits[k]) + limit_turn(theta0[rod], chain.end_limits[k])
        row = np.zeros((1, n))
        row[0, rod] = 1.0
        if np.isfinite(lim[0]):
            A, b = np.vstack([A, row]), np.append(b, lim[0])
        if np.isfinite(lim[1]):
            A, b = np.vstack([A, -row]), np.append(b, -lim[1])
    cons = [
        {
            "type": "eq",
            "fun": lambda t: np.array([l @ np.cos(t) - dx, l @ np.sin(t) - dy]),
            "jac": lambda t: np.vstack([-l * np.sin(t), l * np.cos(t)]),
        }
    ]
    if A.shape[0]:
        cons.append({"type": "ineq", "fun": lambda t: A @ t - b, "jac": lambda t: A})
    res = minimize(
        lambda t: float(c_sin @ np.sin(t) + c_cos @ np.cos(t)),
        theta0,
        jac=lambda t: c_sin * np.cos(t) - c_cos * np.sin(t),
        constraints=cons,
        method="SLSQP",
        options={"maxiter": min(500, 100 + 10 * n), "ftol": 1e-15},  # runs that take more do not converge
    )
    return res.x if np.all(np.isfinite(res.x)) else None


def branch_newton(P, Q, d, signs, lam, length_scale, max_iter=100):
    """Solve sum_G s_G conj(P_G) W_G/|W_G| = d for lam, each group on branch s_G = +-1.

    With every s_G = +1 this is the convex dual problem; a group with s_G = -1 points
    against its load (a compressed arch held by limits). Newton on the 2 x 2 residual
    with step halving on its norm. Returns (lam, W, iterations, converged).
    """
    absP = np.abs(P)
    safeP = np.where(absP > 0, absP, 1.0)

    def residual(lam):
        W = P * lam - Q
        r = np.maximum(np.abs(W), 1e-300)
        return W, r, np.sum(signs * np.conj(P) * W / r) - d

    W, r, F = residual(lam)
    tol = 64 * np.finfo(float).eps * length_scale
    for it in range(1, max_iter + 1):
        if abs(F) <= tol:
            return lam, W, it - 1, True
        a = signs * absP * absP / r
        v = (W / r) * np.conj(P) / safeP
        vx, vy = v.real, v.imag
        jxx, jyy, jxy = np.sum(a * vy * vy), np.sum(a * vx * vx), -np.sum(a * vx * vy)
        det = jxx * jyy - jxy * jxy
        if not np.isfinite(det) or abs(det) < 1e-300:
            break
        step = complex(-(jyy * F.real - jxy * F.imag) / det, -(jxx * F.imag - jxy * F.real) / det)
        t = 1.0
        while t > 1e-10:
            W1, r1, F1 = residual(lam + t * step)
            if abs(F1) < abs(F):
                break
            t *= 0.5
        else:
            return lam, W, it, abs(F) <= 1e-9 * length_scale
        lam, W, r, F = lam + t * step, W1, r1, F1
    return lam, W, max_iter, abs(F) <= 1e-9 * length_scale


def _fallback_starts(chain: Chain, theta: np.ndarray, count: int = 6):
    """Starting angles for the SLSQP fallback: the last iterate, its bends clipped to the
    limits (and mirrored), then seeded random bends within the limits."""
    lo, hi = chain.limits[:, 0], chain.limits[:, 1]
    phi = np.diff(theta)
    rng = np.random.default_rng(12345)
    yield theta
    for bends in (phi, -phi):
        clipped = np.clip(bends, lo, hi)
        yield theta[0] + np.concatenate([[0.0], np.cumsum(clipped)])
    box_lo, box_hi = np.maximum(lo, -np.pi / 2), np.minimum(hi, np.pi / 2)
    box_lo, box_hi = np.minimum(box_lo, box_hi), np.maximum(box_lo, box_hi)
    for _ in range(count):
        bends = rng.uniform(box_lo, box_hi)
        t = np.concatenate([[0.0], np.cumsum(bends)])
        yield t - np.average(t, weights=chain.lengths) + np.angle(chain.d)


def polish_nlp(chain: Chain, theta0: np.ndarray):
    """The lowest exact KKT point found through SLSQP local minima from a few starts.

    Each SLSQP result fixes an active set and a branch per rigid group; a Newton
    solve then makes it exact. Returns (theta, lam, side, newton iterations) or None.
    """
    best, best_energy = None, np.inf
    for start in _fallback_starts(chain, theta0):
        feasible = _feasible_start(chain, start)  # SLSQP fares badly from outside the limits
        x = _nlp_point(chain, start if feasible is None else feasible)
        if x is None:
            continue
        polished = polish_point(chain, x)
        if polished is not None:
            theta, lam, side, _ = polished
            primal, _, dual = violations(chain, theta, lam, side)
            energy = chain.energy(theta)
            if not primal.any() and not dual.any() and energy < best_energy - 1e-12 * abs(energy):
                best, best_energy = polished, energy
    return best


def _extended(chain: Chain):
    """Bounds of the joints and anchor stops in chain order: (N+1,) lo, hi and fused."""
    e = chain.end_limits
    lo = np.concatenate([[e[0, 0]], chain.limits[:, 0], [e[1, 0]]])
    hi = np.concatenate([[e[0, 1]], chain.limits[:, 1], [e[1, 1]]])
    fused = np.concatenate([[chain.end_fixed[0]], chain.fixed, [chain.end_fixed[1]]])
    return lo, hi, fused


def _positions(chain: Chain, theta: np.ndarray, turns=None) -> np.ndarray:
    """(N+1,) what each stop bounds: theta_0, the bends, theta_{N-1}, the end angles less
    ``turns`` (2,) whole turns (default: on their limits' nearest turns, :func:`near`)."""
    if turns is None:
        ends = [near(theta[0], chain.end_limits[0]), near(theta[-1], chain.end_limits[1])]
    else:
        ends = [theta[0] - turns[0], theta[-1] - turns[1]]
    return np.concatenate([[ends[0]], np.diff(theta), [ends[1]]])


def _active_at(chain: Chain, x: np.ndarray, tol: float) -> np.ndarray:
    """(N+1,) the stops x rests on (within tol rad) or is past; fused stops held."""
    lo, hi, fused = _extended(chain)
    pos = _positions(chain, x)
    return np.where(fused | (pos <= lo + tol), -1, np.where(pos >= hi - tol, 1, 0))


def polish_point(chain: Chain, x: np.ndarray):
    """Exact KKT point on the active set and branches of a near-solution x.

    Returns (theta, lam, act, newton iterations) with act the (N+1,) active set, or None.
    """
    act = _active_at(chain, x, 1e-7)
    aset = ActiveSet(chain, act)
    if aset.closes_rigidly(chain):
        free = aset.free
        theta = aset.angles(np.angle(aset.d / np.conj(aset.groups.P[free])) if free.any() else np.zeros(0))
        return theta, rigid_reaction(chain, theta, act), act, 0
    if not aset.reachable():
        return None
    groups, free = aset.groups, aset.free
    # group angles, then the reaction by least squares on the free groups' stationarity,
    # which is linear in lam: Im(conj(P lam - Q) e^{i psi}) = 0
    psi = np.angle(np.add.reduceat(np.exp(1j * (x - groups.offsets)), groups.starts))
    e = np.exp(1j * psi)
    Pe, Qe = np.conj(groups.P[free]) * e[free], np.conj(groups.Q[free]) * e[free]
    # Im(conj(P) conj(lam) e) = Im(Pe) H - Re(Pe) V ... written out for (H, V):
    M = np.column_stack([Pe.imag, -Pe.real])
    rhs = Qe.imag
    sol, *_ = np.linalg.lstsq(M, rhs, rcond=None)
    lam = complex(sol[0], sol[1])
    got = _on_branches(chain, aset, lam, e)
    if got is None:
        return None
    theta, lam, k = got
    return theta, lam, act, k


def _on_branches(chain: Chain, aset: ActiveSet, lam: complex, e: np.ndarray):
    """Newton on the closure with each free group kept on the branch it has at angles ``e``
    (e^{i psi} per group): (angles, reaction, iterations), or None when it fails."""
    free = aset.free
    P, Q = aset.groups.P[free], aset.groups.Q[free]
    W = P * lam - Q
    signs = np.where((np.conj(W) * e[free]).real >= 0, 1.0, -1.0)
    lam, W, k, ok = branch_newton(P, Q, aset.d, signs, lam, chain.total_length)
    if not ok:
        return None
    return aset.angles(np.angle(signs * W)), lam, k


def _group_state(chain: Chain, groups: Groups, theta: np.ndarray):
    """Per group: e^{i psi}, chord, then the closure miss, dU/dpsi and d(closure)/dpsi."""
    e = np.exp(1j * theta[groups.starts])
    chord = np.conj(groups.P) * e
    miss = chord.sum() - chain.d
    grad_u = -(np.conj(groups.Q) * e).imag
    return e, chord, miss, grad_u, 1j * chord



def _reduced_pd(D: np.ndarray, jr: np.ndarray, ji: np.ndarray) -> bool:
    """Is diag(D) positive definite on the null space of the 2 x m closure Jacobian (jr, ji)?

    Inertia identity: n_neg(Z'DZ) = n_neg(D) + n_pos(J D^-1 J') - rank(J), rank 2 here.
    """
    if np.all(D > 0):
        return True
    if np.any(D == 0):
        return False
    sxy = np.sum(jr * ji / D)
    eig = np.linalg.eigvalsh(np.array([[np.sum(jr * jr / D), sxy], [sxy, np.sum(ji * ji / D)]]))
    if np.any(np.abs(eig) <= 1e-12 * np.max(np.abs(eig))):
        return False
    return int(np.count_nonzero(D < 0)) + int(np.count_nonzero(eig > 0)) == 2



def _feasible_start(chain: Chain, theta0: np.ndarray) -> np.ndarray | None:
    """theta0 with its bends clipped to the limits, turned so that its chord points at B,
    then within the end limits: turned into the first rod's, and bent (the least change of
    the bends within their limits) into the last rod's. None when no bends can do that."""
    lo, hi = chain.limits[:, 0], chain.limits[:, 1]
    phi = np.clip(np.diff(theta0), lo, hi)
    theta = np.concatenate([[0.0], np.cumsum(phi)])
    chord = np.sum(chain.lengths * np.exp(1j * theta))
    theta = theta + (np.angle(chain.d) - np.angle(chord) if abs(chord) > 0 else theta0[0])
    if not chain.end_limited.any():
        return theta
    # the least turn that puts the last rod within its limit, within the turns that keep the
    # first rod within its own (clear of the half turn where near() wraps round)
    (elo0, ehi0), (elo1, ehi1) = reach(chain.end_limits[0], 0.1), reach(chain.end_limits[1], 1e-9)
    t0, t1 = near(theta[0], chain.end_limits[0]), near(theta[-1], chain.end_limits[1])
    if elo0 <= t0 <= ehi0:
        r_lo, r_hi = elo0 - t0, ehi0 - t0
    else:  # the least turn into the first rod's limit
        r_lo = r_hi = float(np.clip(0.0, elo0 - t0, ehi0 - t0))
    theta = theta + float(np.clip(np.clip(0.0, elo1 - t1, ehi1 - t1), r_lo, r_hi))
    t1 = near(theta[-1], chain.end_limits[1])
    if elo1 <= t1 <= ehi1:
        return theta
    # bend: phi - nu clipped to the limits, nu by bisection so the last angle reaches its limit
    target = float(np.clip(t1, elo1, ehi1)) - t1 + float(np.sum(phi))

    def total(nu):
        return float(np.sum(np.clip(phi - nu, lo, hi)))

    sign = 1.0 if total(0.0) > target else -1.0
    far = 1.0
    while sign * (total(sign * far) - target) > 0:
        far *= 2
        if far > 64:
            return None  # the limits keep the last rod's angle out of its range
    a, b = 0.0, sign * far
    for _ in range(100):
        mid = 0.5 * (a + b)
        if sign * (total(mid) - target) > 0:
            a = mid
        else:
            b = mid
    bends = np.clip(phi - b, lo, hi)
    return theta[0] + np.concatenate([[0.0], np.cumsum(bends)])


def reach_start(chain: Chain, theta0: np.ndarray) -> np.ndarray | None:
    """The configuration nearest ``theta0`` (from its bends clipped to the limits) that reaches
    anchor B: L-BFGS-B on the squared gap to B over the first rod's angle (within its anchor
    stops' reach) and the bends (within their limits). None where it ends short of B by more
    than round-off over the chain's length. A start on the limits that closes the chain, for
    :func:`descend` where the exchanges' iterates and the hanging shape leave it on kinks (which
    of them do depends on the last bits of the machine's arithmetic)."""
    from scipy.optimize import minimize

    l = chain.lengths
    first = reach(chain.end_limits[0])
    lo = np.concatenate([[first[0]], chain.limits[:, 0]])
    hi = np.concatenate([[first[1]], chain.limits[:, 1]])
    t0 = near(theta0[0], chain.end_limits[0]) if chain.end_limited[0] else theta0[0]
    x0 = np.clip(np.concatenate([[t0], np.diff(theta0)]), lo, hi)

    def gap(x):
        t = np.cumsum(x)
        e = np.exp(1j * t)
        r = np.sum(l * e) - chain.d
        grad_t = 2 * (r.real * (-l * e.imag) + r.imag * (l * e.real))  # d|r|^2 / d theta_k
        return float(abs(r) ** 2), np.cumsum(grad_t[::-1])[::-1]  # theta_k = sum of x_0..x_k

    bounds = [(a if np.isfinite(a) else None, b if np.isfinite(b) else None) for a, b in zip(lo, hi)]
    res = minimize(gap, x0, jac=True, method="L-BFGS-B", bounds=bounds,
                   options={"ftol": 0.0, "gtol": 0.0, "maxiter": 200 + 20 * chain.n})
    scale = float(l.sum())
    if not np.all(np.isfinite(res.x)) or gap(res.x)[0] > (1e-10 * scale) ** 2:
        return None
    t = np.cumsum(res.x)
    return t - t0 + theta0[0] if chain.end_limited[0] else t


def descend(chain: Chain, theta0: np.ndarray, max_iter: int = 300):
    """A stable KKT point by a primal active-set Newton method over (side, branch).

    The joints held at a limit (side) make rigid groups with angles psi; on that set
    each iteration is a Newton (SQP) step on the group angles and the reaction, with the
    exact Lagrangian Hessian diag(D_G) (D_G < 0: group G on the compressed branch) where
    it is positive definite on the closure's tangent space, and |D_G| where it is not.
    Bends stay within their limits and end rods within their anchor stops: a step that
    would cross one stops on it and the stop joins the set (a held anchor stop fixes its
    group's angle); a held stop whose moment has the wrong sign is released once its set
    is solved. An l1 merit function (energy + rho |closure miss|) decides step lengths,
    so the iteration descends and does not cycle. The point found fixes the set and the
    branches, and :func:`branch_newton` makes it exact.

    Returns:
        (theta, lam, act, iterations) with act the (N+1,) active set
        (:class:`optimize.chain.model.ActiveSet`), or None when it finds no KKT point.
    """
    lo, hi, fused = _extended(chain)
    theta = _feasible_start(chain, theta0)
    if theta is None:
        return None
    act = _active_at(chain, theta, 0.0)
    # the end angles are followed continuously from the turns they start on
    turns = (limit_turn(theta[0], chain.end_limits[0]), limit_turn(theta[-1], chain.end_limits[1]))
    mid = np.array([np.mean(e[np.isfinite(e)]) if np.isfinite(e).any() else np.inf for e in chain.end_limits])
    scale = chain.moment_scale
    force = chain.g * chain.total_mass
    length = chain.total_length
    lam = None
    rho = 0.0
    polish_at = 1e-5
    stuck = 0
    aset, grouped = None, None
    for it in range(1, max_iter + 1):
        if grouped is None or not np.array_equal(grouped, act):
            aset, grouped = ActiveSet(chain, act), act.copy()
        groups, mv = aset.groups, aset.free
        e, chord, miss, grad_u, J = _group_state(chain, groups, theta)
        jr, ji = J.real[mv], J.imag[mv]
        if lam is None:  # least-squares multipliers: grad U = Re(conj(lam) J) on the movable groups
            sol, *_ = np.linalg.lstsq(np.column_stack([jr, ji]), grad_u[mv], rcond=None)
            lam = complex(sol[0], sol[1])
        D = (np.conj(groups.P * lam - groups.Q) * e).real[mv]
        pd = _reduced_pd(D, jr, ji)
        lam_new, dm = _qp_step(D if pd else np.abs(D), jr, ji, grad_u[mv], miss, scale)
        rho = max(rho, 2.0 * abs(lam_new) + 1e-3 * force)
        if pd and float(grad_u[mv] @ dm) - rho * abs(miss) >= 0:
            # exact curvature, but not a descent direction of the merit: convexify
            lam_new, dm = _qp_step(np.abs(D), jr, ji, grad_u[mv], miss, scale)
            rho = max(rho, 2.0 * abs(lam_new) + 1e-3 * force)
        delta = np.zeros(mv.size)
        delta[mv] = dm
        step_norm = float(np.max(np.abs(delta)))
        if not np.isfinite(step_norm) or abs(lam_new) > 1e9 * force:
            return None
        if step_norm <= polish_at and abs(miss) <= 1e-7 * length:
            # near a KKT point of this set: make it exact, then release a wrong-sign
            # moment or hold a crossed limit, or stop
            exact = _exact(chain, theta, lam_new, act, it)
            if exact is None:
                polish_at *= 0.01
            else:
                theta_x, lam_x, _, k = exact
                primal, pside, dual = violations(chain, theta_x, lam_x, act)
                if not primal.any() and not dual.any():
                    return exact
                act = act.copy()
                if dual.any():
                    act[int(np.argmax(dual))] = 0
                    lam = lam_x
                else:
                    j = int(np.argmax(primal))
                    act[j] = pside[j]
                    theta = _snap(chain, aset, theta, j, hi[j] if act[j] > 0 else lo[j], turns)
                    lam = lam_new
                    act = _keep_reachable(chain, act, theta, lam, j)
                if act is None:
                    return None
                continue
        if step_norm <= 1e-10 and abs(miss) > 1e-7 * length:
            # this set cannot close the chain: let go of the stop held the least firmly
            act = _keep_reachable(chain, act, theta, lam_new, -1, force=True)
            if act is None:
                return None
            lam = lam_new
            continue
        # longest step within the limits of the free joints and end rods
        pos = _positions(chain, theta, turns)
        rate = np.concatenate([[delta[0]], np.diff(delta[groups.gid]), [delta[-1]]])
        with np.errstate(divide="ignore", invalid="ignore"):
            room = np.where(rate > 0, (hi - pos) / rate, np.where(rate < 0, (lo - pos) / rate, np.inf))
            # an end angle may not pass half a turn from its limit's middle: there the
            # convention of optimize.chain.endlimits.near puts it on the other side of the stop
            wrap = np.where(rate[[0, -1]] > 0, (mid + np.pi - pos[[0, -1]]) / rate[[0, -1]],
                            np.where(rate[[0, -1]] < 0, (mid - np.pi - pos[[0, -1]]) / rate[[0, -1]], np.inf))
        room = np.where(act == 0, np.maximum(room, 0.0), np.inf)
        blocking = int(np.argmin(room))
        t_max = float(room[blocking])
        wrap = np.where(chain.end_limited & (act[[0, -1]] == 0), np.maximum(wrap, 0.0), np.inf)
        if wrap.min() < t_max:
            blocking, t_max = -1, float(wrap.min())  # stop short of the wrap, hold nothing
        shrink = min(1.0, 0.5 / step_norm)  # at most about 30 degrees per step
        merit = _merit(chain, theta, rho)
        slope = float(grad_u @ delta) * shrink - rho * abs(miss) * shrink
        t = min(1.0, t_max / shrink) if shrink > 0 else 0.0
        hit = t_max <= shrink
        tol = 1e-13 * (abs(merit) + force * length)
        soc = t == 1.0
        while True:
            trial = theta + t * shrink * delta[groups.gid]
            m_trial = _merit(chain, trial, rho)
            if m_trial <= merit + 1e-4 * t * slope + tol or t < 1e-10:
                break
            if soc:  # second-order correction of the closure (Maratos effect)
                soc = False
                fixed = _correct(chain, aset, trial, act, turns)
                if fixed is not None:
                    m_fix = _merit(chain, fixed, rho)
                    if m_fix <= merit + 1e-4 * slope + tol:
                        trial, hit = fixed, False
                        break
            t *= 0.5
            hit = False
        if t < 1e-10 and not hit:
            return None
        theta = trial
        if hit and blocking >= 0:
            act = act.copy()
            act[blocking] = 1 if rate[blocking] > 0 else -1
            theta = _snap(chain, aset, theta, blocking, hi[blocking] if act[blocking] > 0 else lo[blocking], turns)
            act = _keep_reachable(chain, act, theta, lam_new, blocking)
        if act is None:
            return None
        stuck = stuck + 1 if t * shrink * step_norm <= 1e-14 else 0
        if stuck > chain.n:
            return None  # limits taken and let go without moving: no way on from here
        lam = lam_new
    return None


def _qp_step(D, jr, ji, grad_u, miss, scale):
    """Newton (SQP) step on the working set: D delta = Re(conj(lam) J) - grad U, J delta = -miss.

    Returns (lam, delta): the new reaction estimate and the change of the group angles.
    """
    D = np.where(np.abs(D) > 1e-9 * scale, D, 1e-9 * scale)
    rhs = np.array([np.sum(jr * grad_u / D) - miss.real, np.sum(ji * grad_u / D) - miss.imag])
    sol = _solve2(np.sum(jr * jr / D), np.sum(jr * ji / D), np.sum(ji * ji / D), rhs)
    return complex(sol[0], sol[1]), (jr * sol[0] + ji * sol[1] - grad_u) / D



def _solve2(sxx, sxy, syy, rhs):
    """Solve the symmetric 2 x 2 system [[sxx, sxy], [sxy, syy]] x = rhs (least squares if singular)."""
    det = sxx * syy - sxy * sxy
    if abs(det) > 1e-13 * (sxx * sxx + syy * syy + 2 * sxy * sxy):
        return np.array([(syy * rhs[0] - sxy * rhs[1]) / det, (sxx * rhs[1] - sxy * rhs[0]) / det])
    sol, *_ = np.linalg.lstsq(np.array([[sxx, sxy], [sxy, syy]]), rhs, rcond=1e-12)
    return sol



def _keep_reachable(chain: Chain, act: np.ndarray, theta, lam, keep: int, force: bool = False):
    """act, or when its rigid groups cannot reach anchor B (or force), act with the held
    stop whose moment holds it least firmly let go (never keep, never a fused stop).
    None when no single release helps."""
    if not force and ActiveSet(chain, act).feasible(chain):
        return act
    mu0, mu_end, _ = multipliers(chain, theta, lam)
    mu, fixtures, _ = fixture_moments(chain, mu0, mu_end, act)
    m = np.concatenate([[fixtures[0]], mu, [fixtures[1]]])
    firm = np.where(act < 0, m, -m)  # > 0: the stop pushes the right way
    fused = _extended(chain)[2]
    for j in np.argsort(firm):
        if act[j] == 0 or fused[j] or j == keep:
            continue
        new = act.copy()
        new[j] = 0
        if ActiveSet(chain, new).feasible(chain):
            return new
    return None


def _merit(chain: Chain, theta: np.ndarray, rho: float) -> float:
    """Energy (up to a constant) plus rho times the closure miss."""
    e = np.exp(1j * theta)
    u = chain.c_cos @ e.real + chain.c_sin @ e.imag
    return float(u + rho * abs(chain.lengths @ e - chain.d))



def _snap(chain: Chain, aset: ActiveSet, theta: np.ndarray, j: int, bound: float, turns) -> np.ndarray:
    """theta with stop j of the (N+1,) active set exactly on bound (end angles less
    ``turns``). The rods turned are the part of the chain no anchor stop holds: for a joint
    the rods after it (or before it, or the free group next to it), for an end rod the
    whole chain, or its group alone when the other end rod is held."""
    out = theta.copy()
    gid, held, ends = aset.groups.gid, aset.held, aset.ends
    if j in (0, chain.n):
        k, rod = (0, 0) if j == 0 else (1, -1)
        turn = bound - (theta[rod] - turns[k])
        if ends[1 - k]:
            out[gid == gid[rod]] += turn
            return out
        return out + turn
    turn = bound - (theta[j] - theta[j - 1])
    if not ends[1]:
        out[j:] += turn
    elif not ends[0]:
        out[:j] -= turn
    elif not held[gid[j]]:
        out[gid == gid[j]] += turn
    else:
        out[gid == gid[j - 1]] -= turn
    return out


def _correct(chain: Chain, aset: ActiveSet, theta: np.ndarray, act: np.ndarray, turns):
    """theta moved by the least change of the movable groups' angles that closes the
    linearised miss there; None when that crosses a limit of a free joint or end rod."""
    groups, mv = aset.groups, aset.free
    e = np.exp(1j * theta[groups.starts])
    J = np.where(mv, 1j * np.conj(groups.P) * e, 0.0)
    miss = np.sum(chain.lengths * np.exp(1j * theta)) - chain.d
    jr, ji = J.real, J.imag
    y = _solve2(jr @ jr, jr @ ji, ji @ ji, -np.array([miss.real, miss.imag]))
    out = theta + (jr * y[0] + ji * y[1])[groups.gid]
    lo, hi, _ = _extended(chain)
    pos = _positions(chain, out, turns)
    if np.any((act == 0) & ((pos > hi) | (pos < lo))):
        return None
    return out


def _exact(chain: Chain, theta: np.ndarray, lam: complex, act: np.ndarray, it: int):
    """The exact KKT point on the set and branches of a converged descent."""
    aset = ActiveSet(chain, act)
    if aset.reachable():
        got = _on_branches(chain, aset, lam, np.exp(1j * theta[aset.groups.starts]))
    elif aset.closes_rigidly(chain):
        free = aset.free
        rigid = aset.angles(np.angle(aset.d / np.conj(aset.groups.P[free])) if free.any() else np.zeros(0))
        got = rigid, rigid_reaction(chain, rigid, act), 0
    else:
        got = None
    if got is None:
        return None
    out, lam, k = got
    out += 2 * np.pi * np.round((theta[0] - out[0]) / (2 * np.pi))
    if np.max(np.abs(np.angle(np.exp(1j * (out - theta))))) > 1e-3:
        return None  # Newton went to another branch point: not this one
    return out, lam, act, it + k
