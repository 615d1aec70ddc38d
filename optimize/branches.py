"""Rigid groups on either branch: the exact equilibrium when some piece is compressed.

For a fixed active set (joints held at a limit) each rigid group G turns along its
load ``W_G = P_G lambda - Q_G`` (branch +1, the minimiser of the Lagrangian in the
group's angle) or against it (branch -1: the piece pushes, e.g. an arch held up by
its stops). The convex dual Newton of :mod:`optimize.equilibrium` handles branch +1
only; this module handles the rest:

* :func:`descend`: a primal active-set Newton method over (side, branch) that reaches a
  stable KKT point from a start within milliseconds, made exact by
* :func:`branch_newton`: Newton on the closure for a given side and branch per group;
* :func:`polish_nlp`: the last resort, SLSQP from several starts, each result polished
  by :func:`polish_point`.
"""

from __future__ import annotations

import numpy as np

from optimize.chain import Chain, Groups, multipliers, violations

__all__ = ["branch_newton", "descend", "polish_nlp", "polish_point"]


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
        options={"maxiter": 1000, "ftol": 1e-15},
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
        x = _nlp_point(chain, start)
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


def polish_point(chain: Chain, x: np.ndarray):
    """Exact KKT point on the active set and branches of a near-solution x."""
    lo, hi = chain.limits[:, 0], chain.limits[:, 1]
    phi = np.diff(x)
    side = np.where(phi <= lo + 1e-7, -1, np.where(phi >= hi - 1e-7, 1, 0))
    side = np.where(chain.fixed, -1, side)
    groups = Groups(chain, side)
    if not groups.reachable(chain.span):
        return None
    # group angles, then the reaction by least squares on the group stationarity,
    # which is linear in lam: Im(conj(P lam - Q) e^{i psi}) = 0
    psi = np.angle(np.add.reduceat(np.exp(1j * (x - groups.offsets)), groups.starts))
    e = np.exp(1j * psi)
    Pe, Qe = np.conj(groups.P) * e, np.conj(groups.Q) * e
    # Im(conj(P) conj(lam) e) = Im(Pe) H - Re(Pe) V ... written out for (H, V):
    M = np.column_stack([Pe.imag, -Pe.real])
    rhs = Qe.imag
    sol, *_ = np.linalg.lstsq(M, rhs, rcond=None)
    lam = complex(sol[0], sol[1])
    got = _on_branches(chain, groups, lam, e)
    if got is None:
        return None
    theta, lam, k = got
    return theta, lam, side, k


def _on_branches(chain: Chain, groups: Groups, lam: complex, e: np.ndarray):
    """Newton on the closure with each group kept on the branch it has at angles ``e``
    (e^{i psi} per group): (angles, reaction, iterations), or None when it fails."""
    W = groups.P * lam - groups.Q
    signs = np.where((np.conj(W) * e).real >= 0, 1.0, -1.0)
    lam, W, k, ok = branch_newton(groups.P, groups.Q, chain.d, signs, lam, chain.total_length)
    if not ok:
        return None
    return groups.angles(W, signs), lam, k



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


def _feasible_start(chain: Chain, theta0: np.ndarray) -> np.ndarray:
    """theta0 with its bends clipped to the limits, turned so that its chord points at B."""
    lo, hi = chain.limits[:, 0], chain.limits[:, 1]
    phi = np.clip(np.diff(theta0), lo, hi)
    theta = np.concatenate([[0.0], np.cumsum(phi)])
    chord = np.sum(chain.lengths * np.exp(1j * theta))
    return theta + (np.angle(chain.d) - np.angle(chord) if abs(chord) > 0 else theta0[0])


def descend(chain: Chain, theta0: np.ndarray, max_iter: int = 300):
    """A stable KKT point by a primal active-set Newton method over (side, branch).

    The joints held at a limit (side) make rigid groups with angles psi; on that set
    each iteration is a Newton (SQP) step on the group angles and the reaction, with the
    exact Lagrangian Hessian diag(D_G) (D_G < 0: group G on the compressed branch) where
    it is positive definite on the closure's tangent space, and |D_G| where it is not.
    Bends stay within their limits: a step that would cross one stops on it and the
    joint joins the side; a held joint whose moment has the wrong sign is released once
    its set is solved. An l1 merit function (energy + rho |closure miss|) decides step
    lengths, so the iteration descends and does not cycle. The point found fixes side
    and branches, and :func:`branch_newton` makes it exact.

    Returns:
        (theta, lam, side, iterations) or None when it finds no KKT point.
    """
    lo, hi = chain.limits[:, 0], chain.limits[:, 1]
    theta = _feasible_start(chain, theta0)
    phi = np.diff(theta)
    side = np.where(chain.fixed | (phi <= lo), -1, np.where(phi >= hi, 1, 0))
    scale = chain.moment_scale
    force = chain.g * chain.total_mass
    length = chain.total_length
    lam = None
    rho = 0.0
    polish_at = 1e-5
    stuck = 0
    groups, grouped = None, None
    for it in range(1, max_iter + 1):
        if grouped is None or not np.array_equal(grouped, side):
            groups, grouped = Groups(chain, side), side.copy()
        e, chord, miss, grad_u, J = _group_state(chain, groups, theta)
        jr, ji = J.real, J.imag
        if lam is None:  # least-squares multipliers: grad U = Re(conj(lam) J)
            sol, *_ = np.linalg.lstsq(np.column_stack([jr, ji]), grad_u, rcond=None)
            lam = complex(sol[0], sol[1])
        D = (np.conj(groups.P * lam - groups.Q) * e).real
        pd = _reduced_pd(D, jr, ji)
        lam_new, delta = _qp_step(D if pd else np.abs(D), jr, ji, grad_u, miss, scale)
        rho = max(rho, 2.0 * abs(lam_new) + 1e-3 * force)
        if pd and float(grad_u @ delta) - rho * abs(miss) >= 0:
            # exact curvature, but not a descent direction of the merit: convexify
            lam_new, delta = _qp_step(np.abs(D), jr, ji, grad_u, miss, scale)
            rho = max(rho, 2.0 * abs(lam_new) + 1e-3 * force)
        step_norm = float(np.max(np.abs(delta)))
        if not np.isfinite(step_norm) or abs(lam_new) > 1e9 * force:
            return None
        if step_norm <= polish_at and abs(miss) <= 1e-7 * length:
            # near a KKT point of this set: make it exact, then release a wrong-sign
            # moment or hold a crossed limit, or stop
            exact = _exact(chain, theta, lam_new, side, it)
            if exact is None:
                polish_at *= 0.01
            else:
                theta_x, lam_x, _, k = exact
                primal, pside, dual = violations(chain, theta_x, lam_x, side)
                if not primal.any() and not dual.any():
                    return exact
                side = side.copy()
                if dual.any():
                    side[int(np.argmax(dual))] = 0
                    lam = lam_x
                else:
                    j = int(np.argmax(primal))
                    side[j] = pside[j]
                    theta = _snap(theta, j, hi[j] if side[j] > 0 else lo[j])
                    lam = lam_new
                    side = _keep_reachable(chain, side, theta, lam, j)
                phi = np.diff(theta)
                continue
        if step_norm <= 1e-10 and abs(miss) > 1e-7 * length:
            # this set cannot close the chain: let go of the joint held the least firmly
            side = _keep_reachable(chain, side, theta, lam_new, -1, force=True)
            if side is None:
                return None
            lam = lam_new
            continue
        # longest step within the limits of the free joints
        dphi = np.diff(delta[groups.gid])
        free = side == 0
        with np.errstate(divide="ignore", invalid="ignore"):
            room = np.where(dphi > 0, (hi - phi) / dphi, np.where(dphi < 0, (lo - phi) / dphi, np.inf))
        room = np.where(free, np.maximum(room, 0.0), np.inf)
        blocking = int(np.argmin(room)) if room.size else -1
        t_max = float(room[blocking]) if room.size else np.inf
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
                fixed = _correct(chain, groups, trial, side, lo, hi)
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
        if hit:
            side = side.copy()
            side[blocking] = 1 if dphi[blocking] > 0 else -1
            theta = _snap(theta, blocking, hi[blocking] if side[blocking] > 0 else lo[blocking])
            side = _keep_reachable(chain, side, theta, lam_new, blocking)
        if side is None:
            return None
        stuck = stuck + 1 if t * shrink * step_norm <= 1e-14 else 0
        if stuck > chain.n:
            return None  # limits taken and let go without moving: no way on from here
        phi = np.diff(theta)
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


def _keep_reachable(chain: Chain, side: np.ndarray, theta, lam, keep: int, force: bool = False):
    """side, or when its rigid groups cannot reach anchor B (or force), side with the held
    joint whose moment holds it least firmly let go (never keep, never a fused joint).
    None when no single release helps."""
    if not force and Groups(chain, side).reachable(chain.span):
        return side
    mu = multipliers(chain, theta, lam)[0]
    firm = np.where(side < 0, mu, -mu)  # > 0: the stop pushes the right way
    order = np.argsort(firm)
    for j in order:
        if side[j] == 0 or chain.fixed[j] or j == keep:
            continue
        new = side.copy()
        new[j] = 0
        if Groups(chain, new).reachable(chain.span):
            return new
    return None


def _merit(chain: Chain, theta: np.ndarray, rho: float) -> float:
    """Energy (up to a constant) plus rho times the closure miss."""
    e = np.exp(1j * theta)
    u = chain.c_cos @ e.real + chain.c_sin @ e.imag
    return float(u + rho * abs(chain.lengths @ e - chain.d))


def _snap(theta: np.ndarray, j: int, bound: float) -> np.ndarray:
    """theta with bend j set exactly to bound (the rods after joint j turned)."""
    out = theta.copy()
    out[j + 1:] += bound - (theta[j + 1] - theta[j])
    return out


def _correct(chain, groups, theta, side, lo, hi):
    """theta moved by the least change of group angles that closes the
    linearised miss there; None when that crosses a limit of a free joint."""
    e = np.exp(1j * theta[groups.starts])
    J = 1j * np.conj(groups.P) * e
    miss = np.sum(chain.lengths * np.exp(1j * theta)) - chain.d
    jr, ji = J.real, J.imag
    y = _solve2(jr @ jr, jr @ ji, ji @ ji, -np.array([miss.real, miss.imag]))
    out = theta + (jr * y[0] + ji * y[1])[groups.gid]
    phi = np.diff(out)
    if np.any((side == 0) & ((phi > hi) | (phi < lo))):
        return None
    return out


def _exact(chain: Chain, theta: np.ndarray, lam: complex, side: np.ndarray, it: int):
    """The exact KKT point on the side and branches of a converged descent."""
    groups = Groups(chain, side)
    got = _on_branches(chain, groups, lam, np.exp(1j * theta[groups.starts]))
    if got is None:
        return None
    out, lam, k = got
    out += 2 * np.pi * np.round((theta[0] - out[0]) / (2 * np.pi))
    if np.max(np.abs(np.angle(np.exp(1j * (out - theta))))) > 1e-3:
        return None  # Newton went to another branch point: not this one
    return out, lam, side, it + k
