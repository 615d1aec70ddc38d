"""Exact static equilibrium of a planar chain of rigid rods hung between two anchors.

Conventions (``shared/design/physics.md``): rods ``0..N-1`` with chord angles
``theta_i`` from +x, joint points ``p_0 = A .. p_N = B``, bends
``phi_j = theta_{j+1} - theta_j``, gravity along -y, each rod's centre of mass
``(along, perp)`` in its own frame.

Method
------
With the closure multiplier ``lambda = (H, V)`` (the support reaction at B), the
Lagrangian separates rod by rod::

    L = sum_k -l_k Re(conj(lambda - sigma_k) e^{i theta_k}) + lambda . (B - A)
    sigma_k = g (m_k perp_k / l_k  +  i (S_k + m_k along_k / l_k)),  S_k = sum_{i>k} m_i

(complex numbers stand for planar vectors). Rods joined by joints held at a
limit form rigid groups; a group with first-rod angle ``psi`` and offsets
``o_k`` contributes ``-Re(conj(P_G lambda - Q_G) e^{i psi})`` with constants
``P_G = sum l_k e^{-i o_k}``, ``Q_G = sum l_k e^{-i o_k} sigma_k``. Minimising
over every ``psi`` gives the dual function, a weighted Fermat-Weber problem::

    Psi(lambda) = sum_G |P_G lambda - Q_G| - Re(conj(B - A) lambda)

which is convex in the two unknowns (H, V); its gradient is the closure
residual. Damped Newton on ``Psi`` therefore converges from any start, each
iteration costing O(number of groups), and the minimiser is the global minimum
of the potential energy for that set of locked joints (Lagrangian sufficiency).
The set of joints held at a limit is found by an active-set iteration (primal
and dual violations exchanged all at once, then one at a time if that cycles,
then an SLSQP fallback that only proposes an active set to restart from), so
the final point satisfies the KKT conditions exactly: closure to round-off,
limits as hard inequalities, and joint moments of the right sign.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from optimize import _validate as val

__all__ = ["EquilibriumResult", "solve_equilibrium", "kkt_residual", "MESSAGES"]

#: Status codes and their messages (one table, as in scipy.optimize).
MESSAGES = {
    0: "Equilibrium found: closure exact, limits respected, KKT conditions satisfied.",
    1: "Active-set iteration limit reached before the KKT conditions held.",
    2: "Dual Newton solve did not converge (degenerate chain: a rod with no net load).",
    3: "No configuration satisfies the joint limits and reaches anchor B.",
    4: "Chain exactly taut: the equilibrium is the straight line (tension unbounded).",
    5: "Chain exactly taut, but the joint limits exclude the straight line.",
    6: "Penalty model (paper Eq. 1-3): a minimum of the penalised energy; the far end "
    "misses its anchor by closure_error.",
    7: "Penalty model: the minimiser stopped before convergence.",
}

# Relative tolerances of the active-set test (angles in rad, moments relative to
# total weight x total length). They are far below the reported KKT target 1e-9.
_ANGLE_TOL = 1e-11
_MOMENT_TOL = 1e-11


@dataclass
class EquilibriumResult:
    """The equilibrium of a hanging chain.

    Attributes:
        points: (N+1, 2) joint positions, ``points[0] = A``, ``points[-1]`` on B to round-off.
        angles: (N,) chord angles theta_i in radians.
        reaction: (2,) support reaction (H, V) that anchor B exerts on the chain,
            in mass x length / time^2 of the caller's units times ``g``.
        reaction_a: (2,) the reaction at anchor A.
        moments: (N-1,) moment carried by each joint's limit stop (0 where the joint
            is free). Positive pushes phi up (a stop at lo), negative pushes it down.
        active: (N-1,) -1 where the joint rests on lo, +1 on hi, 0 where it is free.
        kkt_residual: relative KKT residual (closure, stationarity, feasibility, sign).
        closure_error: distance from the chain's far end to B (caller's length unit).
        energy: potential energy g * sum m_i y(com_i).
        stable: second-order check: the Hessian of the Lagrangian is positive
            definite on the tangent space of the active constraints.
        success, status, message: outcome, with ``message = MESSAGES[status]`` plus detail.
        nit: active-set iterations; nnewton: dual Newton iterations in total.
        model: "exact" or "penalty".
    """

    points: np.ndarray
    angles: np.ndarray
    reaction: np.ndarray
    reaction_a: np.ndarray
    moments: np.ndarray
    active: np.ndarray
    kkt_residual: float
    closure_error: float
    energy: float
    stable: bool
    success: bool
    status: int
    message: str
    nit: int = 0
    nnewton: int = 0
    model: str = "exact"
    info: dict = field(default_factory=dict)

    @property
    def bends(self) -> np.ndarray:
        """(N-1,) bend angles phi_j in radians."""
        return np.diff(self.angles)

    def __repr__(self) -> str:  # pragma: no cover - convenience
        return (
            f"EquilibriumResult(success={self.success}, stable={self.stable}, "
            f"kkt_residual={self.kkt_residual:.2e}, nit={self.nit}, "
            f"active={int(np.count_nonzero(self.active))}, message={self.message!r})"
        )


@dataclass
class Chain:
    """A validated chain problem (arrays in, arrays out; no units attached)."""

    lengths: np.ndarray
    masses: np.ndarray
    com: np.ndarray
    limits: np.ndarray
    anchor_a: np.ndarray
    anchor_b: np.ndarray
    g: float

    def __post_init__(self) -> None:
        l, m = self.lengths, self.masses
        self.n = l.size
        self.total_length = float(l.sum())
        self.total_mass = float(m.sum())
        dvec = self.anchor_b - self.anchor_a
        self.d = complex(dvec[0], dvec[1])
        self.span = abs(self.d)
        after = np.cumsum(m[::-1])[::-1] - m  # S_k: mass of the rods after k
        along, perp = self.com[:, 0], self.com[:, 1]
        self.sigma = self.g * (m * perp / l + 1j * (after + m * along / l))
        self.fixed = self.limits[:, 0] == self.limits[:, 1]
        self.moment_scale = self.g * self.total_mass * self.total_length
        # U(theta) = sum(c_sin sin theta + c_cos cos theta) + const
        self.c_sin = self.g * (after * l + m * along)
        self.c_cos = self.g * m * perp

    @classmethod
    def from_args(cls, lengths, masses, anchor_a, anchor_b, com=None, limits=None, g=9.81):
        lengths = val.as_positive_vector("lengths", lengths)
        masses = val.as_positive_vector("masses", masses, lengths.size)
        return cls(
            lengths=lengths,
            masses=masses,
            com=val.as_com(com, lengths),
            limits=val.as_limits(limits, lengths.size),
            anchor_a=val.as_point("anchor_a", anchor_a),
            anchor_b=val.as_point("anchor_b", anchor_b),
            g=val.as_gravity(g),
        )

    def energy(self, theta: np.ndarray) -> float:
        l, m = self.lengths, self.masses
        y_joint = self.anchor_a[1] + np.concatenate([[0.0], np.cumsum(l * np.sin(theta))[:-1]])
        y_com = y_joint + self.com[:, 0] * np.sin(theta) + self.com[:, 1] * np.cos(theta)
        return float(self.g * np.dot(m, y_com))

    def points(self, theta: np.ndarray) -> np.ndarray:
        steps = self.lengths[:, None] * np.column_stack([np.cos(theta), np.sin(theta)])
        return self.anchor_a + np.vstack([np.zeros(2), np.cumsum(steps, axis=0)])


class _Groups:
    """Rigid groups of rods for one active set (joints held at a limit)."""

    def __init__(self, chain: Chain, side: np.ndarray):
        lo, hi = chain.limits[:, 0], chain.limits[:, 1]
        locked = side != 0
        phi_fix = np.where(side < 0, lo, np.where(side > 0, hi, 0.0))
        self.starts = np.flatnonzero(np.concatenate([[True], ~locked]))
        self.gid = np.concatenate([[0], np.cumsum(~locked)])
        cum = np.concatenate([[0.0], np.cumsum(phi_fix)])
        self.offsets = cum - cum[self.starts][self.gid]
        w = chain.lengths * np.exp(-1j * self.offsets)
        self.P = np.add.reduceat(w, self.starts)
        self.Q = np.add.reduceat(w * chain.sigma, self.starts)
        self.chords = np.abs(self.P)

    def reachable(self, span: float) -> bool:
        total = self.chords.sum()
        longest = self.chords.max()
        margin = 1e-12 * total
        return bool(span < total - margin and span > 2.0 * longest - total + margin)

    def angles(self, W: np.ndarray, signs=None) -> np.ndarray:
        """Rod angles with every group turned along (or, sign -1, against) its load W.

        Bends at free joints are taken in (-pi, pi]: a chain cannot fold through itself.
        """
        psi = np.angle(W if signs is None else signs * W)
        return np.unwrap(psi[self.gid] + self.offsets)


def _initial_reaction(chain: Chain) -> complex:
    """A rough (H, V): the two-bar V with the whole weight hung at mid-span."""
    weight = chain.g * chain.total_mass
    slack = np.sqrt(max(chain.total_length**2 - chain.span**2, 1e-6 * chain.total_length**2))
    h = 0.5 * weight * chain.d.real / slack
    if abs(h) < 1e-3 * weight:
        h = 1e-3 * weight
    return complex(h, 0.5 * weight + 0.5 * weight * chain.d.imag / slack)


def _dual_newton(P, Q, d, lam, length_scale, max_iter=200):
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
        t = 1.0
        while True:
            trial = lam + t * step
            W1, r1, u1, g1, psi1 = evaluate(trial)
            if psi1 <= psi + 1e-4 * t * slope:
                break
            noise = 1e3 * np.finfo(float).eps * (abs(psi) + abs(psi1))
            if abs(psi1 - psi) <= noise and abs(g1) < gn:
                break  # the energy change is below round-off: judge by the gradient
            if t < 1e-12:
                break
            t *= 0.5
        lam, W, r, u, grad, psi = trial, W1, r1, u1, g1, psi1
        if abs(grad) < best_gn * 0.999:
            best_gn = abs(grad)
            stall = 0
        else:
            stall += 1
            if stall >= 3 and best_gn <= 1e-9 * length_scale:
                return lam, W, it, True  # at the floor of round-off
            if stall >= 20:
                break
    return lam, W, max_iter, abs(grad) <= 1e-9 * length_scale


def _close_at_kink(chain: Chain, groups: _Groups, W: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Exact closure when the dual optimum sits next to a kink.

    When one group carries almost no load (|W_G| -> 0, e.g. a bottom rod that spans a
    slack chain exactly horizontally) Newton converges slowly and stops a little short.
    That group's angle is then undetermined by statics; turn it so the chain closes.
    """
    chords = np.add.reduceat(chain.lengths * np.exp(1j * theta), groups.starts)
    miss = chords.sum() - chain.d
    if abs(miss) <= 1e-14 * chain.total_length:
        return theta
    load = np.abs(W) / np.maximum(groups.chords, 1e-300)
    g = int(np.argmin(load))
    need = chain.d - (chords.sum() - chords[g])
    if abs(abs(need) - groups.chords[g]) > 1e-6 * chain.total_length:
        return theta  # not a kink: leave it to the KKT check
    turn = np.angle(need / chords[g])
    in_g = groups.gid == g
    out = theta.copy()
    out[in_g] += turn
    return np.unwrap(out)


def _multipliers(chain: Chain, theta: np.ndarray, lam: complex):
    """Per-rod generalised force f_k, joint moments mu_j and the end moment mu_{N-1}."""
    z = lam - chain.sigma
    e = np.exp(1j * theta)
    f = chain.lengths * (np.conj(z) * e).imag
    cum = -np.cumsum(f)
    curvature = chain.lengths * (np.conj(z) * e).real
    return cum[:-1], float(cum[-1]), curvature


def kkt_residual(
    chain: Chain, theta: np.ndarray, lam: complex, side: np.ndarray, mult=None
) -> float:
    """Relative KKT residual of a configuration for a given active set.

    The largest of: closure error / total length; moments at free joints and the
    end moment / (g * total mass * total length); limit violation (rad); wrong-sign
    moments at active limits (same scale).
    """
    closure = abs(np.sum(chain.lengths * np.exp(1j * theta)) - chain.d) / chain.total_length
    mu, mu_end, _ = mult if mult is not None else _multipliers(chain, theta, lam)
    scale = chain.moment_scale
    free = side == 0
    stat = max(np.max(np.abs(mu[free]), initial=0.0), abs(mu_end)) / scale
    phi = np.diff(theta)
    lo, hi = chain.limits[:, 0], chain.limits[:, 1]
    feas = np.max(np.maximum(lo - phi, phi - hi), initial=0.0)
    feas = max(feas, 0.0)
    movable = ~chain.fixed
    sign = np.max(
        np.concatenate([-mu[(side < 0) & movable], mu[(side > 0) & movable], [0.0]])
    ) / scale
    return float(max(closure, stat, feas, max(sign, 0.0)))


def _is_stable(chain: Chain, theta: np.ndarray, lam: complex, side: np.ndarray, mult=None) -> bool:
    """Second-order check on the tangent space of closure and the binding limits.

    Joints at a limit with a vanishing moment are treated as free (a conservative
    check). For group angles psi the Lagrangian Hessian is diagonal, D_G; with the
    closure Jacobian C (2 x n) the inertia identity
    In(Z'DZ) = In(D) + In(-C D^-1 C') - (m, m, 0) decides it in O(n).
    """
    mu, _, curv = mult if mult is not None else _multipliers(chain, theta, lam)
    binding = (side != 0) & (chain.fixed | (np.abs(mu) > 1e3 * _MOMENT_TOL * chain.moment_scale))
    starts = np.flatnonzero(np.concatenate([[True], ~binding]))
    D = np.add.reduceat(curv, starts)
    chords = np.add.reduceat(chain.lengths * np.exp(1j * theta), starts)
    cols = 1j * chords  # d(closure)/d(psi_G)
    C = np.vstack([cols.real, cols.imag])
    scale = np.max(np.abs(D)) if D.size else 1.0
    rank = np.linalg.matrix_rank(C, tol=1e-12 * chain.total_length)
    if np.any(np.abs(D) <= 1e-9 * scale):
        # an unloaded group: the inertia identity needs D invertible, so project
        # explicitly (dense, affordable for the few hundred groups where this occurs)
        if D.size > 500:
            return False
        from scipy.linalg import null_space

        Z = null_space(C, rcond=1e-12)
        if Z.shape[1] == 0:
            return True
        eig = np.linalg.eigvalsh(Z.T @ (D[:, None] * Z))
        return bool(eig.min() > 1e-9 * scale)
    if D.size <= rank:
        return True  # the closure leaves no freedom: an isolated configuration
    n_neg_d = int(np.count_nonzero(D < 0))
    if n_neg_d == 0:
        return True
    S = -(C / D) @ C.T
    eig = np.linalg.eigvalsh(S)
    if np.any(np.abs(eig) <= 1e-12 * np.max(np.abs(eig))):
        return False
    return n_neg_d + int(np.count_nonzero(eig < 0)) - rank == 0


def _violations(chain: Chain, theta: np.ndarray, lam: complex, side: np.ndarray):
    """Primal (free joints outside limits) and dual (wrong-sign moments) violations."""
    phi = np.diff(theta)
    lo, hi = chain.limits[:, 0], chain.limits[:, 1]
    free = side == 0
    over = free & (phi > hi + _ANGLE_TOL)
    under = free & (phi < lo - _ANGLE_TOL)
    primal = np.where(over, phi - hi, np.where(under, lo - phi, 0.0))
    mu, _, _ = _multipliers(chain, theta, lam)
    movable = ~chain.fixed
    tol = _MOMENT_TOL * chain.moment_scale
    wrong = np.where((side < 0) & movable & (mu < -tol), -mu, 0.0)
    wrong = np.where((side > 0) & movable & (mu > tol), mu, wrong)
    return primal, np.where(over, 1, np.where(under, -1, 0)), wrong / chain.moment_scale


def _taut(chain: Chain) -> EquilibriumResult:
    angle = np.angle(chain.d)
    theta = np.full(chain.n, angle)
    lo, hi = chain.limits[:, 0], chain.limits[:, 1]
    ok = bool(np.all((lo <= 0) & (hi >= 0)))
    pts = chain.points(theta)
    pts[-1] = chain.anchor_b
    inf = np.full(2, np.inf)
    return EquilibriumResult(
        points=pts,
        angles=theta,
        reaction=inf,
        reaction_a=inf,
        moments=np.zeros(chain.n - 1),
        active=np.zeros(chain.n - 1, dtype=int),
        kkt_residual=0.0 if ok else float(np.max(np.maximum(lo, -hi))),
        closure_error=0.0,
        energy=chain.energy(theta),
        stable=ok,
        success=ok,
        status=4 if ok else 5,
        message=MESSAGES[4 if ok else 5],
    )


def _check_reach(chain: Chain) -> None:
    """Raise ValueError when no configuration of the rods can reach anchor B."""
    total = chain.total_length
    if chain.span > total * (1 + 1e-12):
        raise ValueError(
            f"anchors are {chain.span - total:.6g} farther apart than the chain is long "
            f"(|B - A| = {chain.span:.6g}, total rod length = {total:.6g})"
        )
    k = int(np.argmax(chain.lengths))
    rest = total - chain.lengths[k]
    if chain.span < chain.lengths[k] - rest - 1e-12 * total:
        raise ValueError(
            f"anchors are too close: rod {k} (length {chain.lengths[k]:.6g}) is longer than "
            f"the other rods together ({rest:.6g}) plus the anchor distance ({chain.span:.6g})"
        )


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


def _branch_newton(P, Q, d, signs, lam, length_scale, max_iter=100):
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


def _sag_guess(chain: Chain) -> np.ndarray:
    """A symmetric two-slope sag between the anchors (knows nothing of the answer)."""
    drop = np.arccos(min(1.0, chain.span / chain.total_length))
    half = np.arange(chain.n) < chain.n / 2
    return np.angle(chain.d) + np.where(half, -drop, drop)


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


def _polish_nlp(chain: Chain, theta0: np.ndarray):
    """The lowest exact KKT point found through SLSQP local minima from a few starts.

    Each SLSQP result fixes an active set and a branch per rigid group; a Newton
    solve then makes it exact. Returns (theta, lam, side, newton iterations) or None.
    """
    best, best_energy = None, np.inf
    for start in _fallback_starts(chain, theta0):
        x = _nlp_point(chain, start)
        if x is None:
            continue
        polished = _polish_point(chain, x)
        if polished is not None:
            theta, lam, side, _ = polished
            primal, _, dual = _violations(chain, theta, lam, side)
            energy = chain.energy(theta)
            if not primal.any() and not dual.any() and energy < best_energy - 1e-12 * abs(energy):
                best, best_energy = polished, energy
    return best


def _polish_point(chain: Chain, x: np.ndarray):
    """Exact KKT point on the active set and branches of a near-solution x."""
    lo, hi = chain.limits[:, 0], chain.limits[:, 1]
    phi = np.diff(x)
    side = np.where(phi <= lo + 1e-7, -1, np.where(phi >= hi - 1e-7, 1, 0))
    side = np.where(chain.fixed, -1, side)
    groups = _Groups(chain, side)
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
    W = groups.P * lam - groups.Q
    signs = np.where((np.conj(W) * e).real >= 0, 1.0, -1.0)
    lam, W, k, ok = _branch_newton(groups.P, groups.Q, chain.d, signs, lam, chain.total_length)
    if not ok:
        return None
    theta = groups.angles(W, signs)
    return theta, lam, side, k


def _solve_exact(chain: Chain, active0, max_iter: int) -> EquilibriumResult:
    n = chain.n
    lo, hi = chain.limits[:, 0], chain.limits[:, 1]
    side = np.zeros(n - 1, dtype=int)
    if active0 is not None:
        a0 = np.asarray(active0, dtype=int)
        if a0.shape != (n - 1,) or not np.all(np.isin(a0, (-1, 0, 1))):
            raise ValueError(f"active0 must have shape ({n - 1},) with entries -1, 0 or 1")
        side = np.where((a0 < 0) & np.isfinite(lo), -1, np.where((a0 > 0) & np.isfinite(hi), 1, 0))
    side = np.where(chain.fixed, -1, side)
    if not _Groups(chain, side).reachable(chain.span):
        side = np.where(chain.fixed, -1, 0)
        if not _Groups(chain, side).reachable(chain.span):
            raise ValueError(
                "the rigid joints (lo == hi) leave no configuration that reaches anchor B"
            )

    lam = _initial_reaction(chain)
    visited: set[bytes] = set()
    mode = "exchange"
    nnewton = 0
    status = 1
    used_nlp = False
    theta = None
    last = None
    it = 0
    for it in range(1, max_iter + 1):
        groups = _Groups(chain, side)
        lam_try, W, k, converged = _dual_newton(
            groups.P, groups.Q, chain.d, lam, chain.total_length
        )
        nnewton += k
        if not converged:
            # a kink where the unloaded group just fits the gap: closure decides its angle
            theta_k = _close_at_kink(chain, groups, W, groups.angles(W))
            if kkt_residual(chain, theta_k, lam_try, side) < 1e-10:
                converged = True
        if not converged:
            # the dual optimum sits on a kink: a rigid group with no net load, whose
            # minimum lies on another branch. Step back and change one joint at a time.
            if last is None or mode == "single":
                status = 2
                break
            mode = "single"
            side, theta, lam, primal, pside, dual = last
            new = _next_active_set(chain, side, primal, pside, dual, mode)
            if new is None:
                status = 3
                break
            side = new
            continue
        lam = lam_try
        theta = _close_at_kink(chain, groups, W, groups.angles(W))
        primal, pside, dual = _violations(chain, theta, lam, side)
        last = (side, theta, lam, primal, pside, dual)
        if not primal.any() and not dual.any():
            status = 0
            break
        key = side.tobytes()
        if key in visited and mode == "exchange":
            mode = "single"  # exchanging everything at once cycles: go one joint at a time
            visited = set()
        elif key in visited:
            status = 3  # cycles one joint at a time too: fall back below
            break
        visited.add(key)
        new = _next_active_set(chain, side, primal, pside, dual, mode)
        if new is None:
            status = 3  # every single change leaves anchor B out of reach: fall back below
            break
        side = new

    if status != 0:
        if theta is None:  # not even the first dual solve converged
            theta = _sag_guess(chain)
        polished = _polish_nlp(chain, theta)
        used_nlp = True
        if polished is not None:
            theta, lam, side, k = polished
            nnewton += k
            status = 0
        else:
            status = 3
    return _assemble(chain, theta, lam, side, status, it, nnewton, used_nlp)


def _next_active_set(chain, side, primal, pside, dual, mode):
    """The next active set: all violations exchanged at once, or the worst one alone."""
    if mode == "exchange":
        new = side.copy()
        new[dual > 0] = 0
        new[primal > 0] = pside[primal > 0]
        if _Groups(chain, new).reachable(chain.span):
            return new
    # one change at a time: add the worst reachable primal violator, else drop the worst dual
    for j in np.argsort(-primal):
        if primal[j] <= 0:
            break
        new = side.copy()
        new[j] = pside[j]
        if _Groups(chain, new).reachable(chain.span):
            return new
    if dual.any():
        new = side.copy()
        new[int(np.argmax(dual))] = 0
        return new
    return None


def _reach_hint(chain: Chain) -> str:
    """Why the limits may keep B out of reach: the chain curled as far as its limits
    allow, either way, still spans farther than the anchors are apart."""
    chords = []
    for bound in (chain.limits[:, 1], chain.limits[:, 0]):
        if not np.all(np.isfinite(bound)) or abs(np.sum(bound)) > np.pi:
            return ""
        theta = np.concatenate([[0.0], np.cumsum(bound)])
        chords.append(abs(np.sum(chain.lengths * np.exp(1j * theta))))
    if min(chords) <= chain.span:
        return ""
    return (
        f" Bent to every upper limit the chain still spans {chords[0]:.6g}, to every lower "
        f"limit {chords[1]:.6g}, more than |B - A| = {chain.span:.6g}: move the anchors "
        "closer or allow more bending."
    )


def _assemble(chain, theta, lam, side, status, nit, nnewton, used_nlp) -> EquilibriumResult:
    mult = _multipliers(chain, theta, lam)
    moments = np.where(side != 0, mult[0], 0.0)
    pts = chain.points(theta)
    closure = float(np.hypot(*(pts[-1] - chain.anchor_b)))
    kkt = kkt_residual(chain, theta, lam, side, mult)
    success = status == 0 and kkt < 1e-9
    if status == 0 and not success:
        status = 1
    stable = _is_stable(chain, theta, lam, side, mult) if status in (0, 1) else False
    message = MESSAGES[status]
    if status == 3:
        message += _reach_hint(chain)
    if used_nlp and status == 0:
        message += " (active set found through the SLSQP fallback)"
    reaction = np.array([lam.real, lam.imag])
    weight = chain.g * chain.total_mass
    return EquilibriumResult(
        points=pts,
        angles=theta,
        reaction=reaction,
        reaction_a=np.array([-lam.real, weight - lam.imag]),
        moments=moments,
        active=side.copy(),
        kkt_residual=kkt,
        closure_error=closure,
        energy=chain.energy(theta),
        stable=stable,
        success=success,
        status=status,
        message=message,
        nit=nit,
        nnewton=nnewton,
        model="exact",
        info={"used_nlp": used_nlp},
    )


def solve_equilibrium(
    lengths,
    masses,
    anchor_a,
    anchor_b,
    *,
    com=None,
    limits=None,
    g: float = 9.81,
    model: str = "exact",
    active0=None,
    max_iter: int | None = None,
    penalty_weight: float = 1e3,
    collision_weight: float = 1.0,
) -> EquilibriumResult:
    """Static equilibrium of a chain of rigid rods hung between anchors A and B.

    Args:
        lengths: (N,) pin-to-pin rod lengths, positive.
        masses: (N,) rod masses, positive (only their ratios shape the chain).
        anchor_a: (2,) the left anchor A = p_0.
        anchor_b: (2,) the right anchor B = p_N.
        com: (N, 2) centres of mass (along, perp) in each rod's frame; None = (l/2, 0).
        limits: (N-1, 2) bend limits [lo, hi] in radians for phi_j; a row of
            (-inf, inf) is a free joint, lo == hi a rigid one. None = all free.
        g: gravitational acceleration (> 0), along -y.
        model: "exact" (default; closure and limits as hard constraints) or
            "penalty" (the paper's Eq. 1-3, for comparison).
        active0: optional (N-1,) initial active set (-1 lo, 0 free, +1 hi).
        max_iter: cap on active-set iterations (default 10 + 4 N).
        penalty_weight: penalty model only: lambda_1 in units of total weight / total length.
        collision_weight: penalty model only: lambda_2 in units of total weight x total length.

    Returns:
        EquilibriumResult.

    Raises:
        ValueError: bad arguments (naming the argument) or anchors no configuration can reach.

    Example:
        >>> r = solve_equilibrium([1, 1], [1, 1], (0, 0), (1.2, 0))
        >>> bool(r.success and abs(r.points[1, 1] + 0.8) < 1e-12)
        True
    """
    chain = Chain.from_args(lengths, masses, anchor_a, anchor_b, com, limits, g)
    if model not in ("exact", "penalty"):
        raise ValueError(f"model must be 'exact' or 'penalty', got {model!r}")
    _check_reach(chain)
    if chain.span >= chain.total_length * (1 - 1e-12):
        return _taut(chain)
    if model == "penalty":
        from optimize.penalty import solve_penalty

        return solve_penalty(chain, penalty_weight, collision_weight)
    if max_iter is None:
        max_iter = 10 + 4 * chain.n
    return _solve_exact(chain, active0, max_iter)
