"""The chain problem and what every model of it shares.

Conventions (``shared/design/physics.md``): rods ``0..N-1`` with chord angles
``theta_i`` from +x, joint points ``p_0 = A .. p_N = B``, bends
``phi_j = theta_{j+1} - theta_j``, gravity along -y, each rod's centre of mass
``(along, perp)`` in its own frame. Lengths and masses are in the caller's units;
angles in radians; forces in mass x the unit of ``g``, moments in force x length.

Holds the validated problem (:class:`Chain`), its rigid groups for an active set
(:class:`Groups`), the result type of every model (:class:`EquilibriumResult`, with the
status table :data:`MESSAGES`) and the statics checks the exact model
(:mod:`optimize.chain.equilibrium`) and the paper's penalty model (:mod:`optimize.chain.penalty`)
both use: joint moments, the KKT residual, the second-order stability test and the
symmetric sag starting guess.

Anchor stops (bounds on theta_0 and theta_{N-1}, :mod:`optimize.chain.endlimits`) are part of the
same active set: an active set in chain order is an (N+1,) array, entry 0 the first rod's
anchor stop, entries 1..N-1 the joints, entry N the last rod's anchor stop
(:func:`optimize.chain.endlimits.as_active`; the functions here also take the (N-1,) joints alone,
both anchor stops free). :class:`ActiveSet` says which rigid groups a fixture holds.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from optimize import validate as val
from optimize.chain.endlimits import ANGLE_TOL as END_ANGLE_TOL
from optimize.chain.endlimits import as_active, as_end_limits, end_bound, near, no_end_limits

__all__ = [
    "ANGLE_TOL",
    "MESSAGES",
    "MOMENT_TOL",
    "ActiveSet",
    "Chain",
    "EquilibriumResult",
    "Groups",
    "fixture_moments",
    "is_stable",
    "kkt_residual",
    "multipliers",
    "sag_guess",
    "stable_on_closure",
    "violations",
]

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
ANGLE_TOL = 1e-11
MOMENT_TOL = 1e-11


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
    """A validated chain problem (arrays in, arrays out; no units attached).

    ``end_limits`` (2, 2): bounds [lo, hi] on theta_0 and theta_{N-1} (radians, rows of
    (-inf, inf) for bare pins; None is both bare).
    """

    lengths: np.ndarray
    masses: np.ndarray
    com: np.ndarray
    limits: np.ndarray
    anchor_a: np.ndarray
    anchor_b: np.ndarray
    g: float
    end_limits: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.end_limits is None:
            self.end_limits = no_end_limits()
        self.end_limited = np.isfinite(self.end_limits).any(axis=1)  # (2,) bool
        self.end_fixed = self.end_limits[:, 0] == self.end_limits[:, 1]
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
    def from_args(cls, lengths, masses, anchor_a, anchor_b, com=None, limits=None, g=9.81, end_limits=None):
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
            end_limits=as_end_limits(end_limits),
        )

    def energy(self, theta: np.ndarray) -> float:
        l, m = self.lengths, self.masses
        y_joint = self.anchor_a[1] + np.concatenate([[0.0], np.cumsum(l * np.sin(theta))[:-1]])
        y_com = y_joint + self.com[:, 0] * np.sin(theta) + self.com[:, 1] * np.cos(theta)
        return float(self.g * np.dot(m, y_com))

    def points(self, theta: np.ndarray) -> np.ndarray:
        steps = self.lengths[:, None] * np.column_stack([np.cos(theta), np.sin(theta)])
        return self.anchor_a + np.vstack([np.zeros(2), np.cumsum(steps, axis=0)])


class Groups:
    """Rigid groups of rods for one active set (joints held at a limit).

    Args:
        chain: the problem.
        side: (N-1,) -1 where a joint is held at lo, +1 at hi, 0 where it is free.

    Attributes:
        starts: first rod of each group; gid: (N,) group of each rod.
        offsets: (N,) rod angle minus its group's first-rod angle, in radians.
        P, Q: the group constants ``P_G = sum l_k e^{-i o_k}`` (length) and
            ``Q_G = sum l_k e^{-i o_k} sigma_k`` (moment), as complex numbers.
        chords: |P_G|, each group's pin-to-pin length.
    """

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


class ActiveSet:
    """The rigid groups of an active set, the anchor stops included, and which groups a
    fixture holds.

    A held anchor stop fixes the angle of the group containing its end rod: that group's
    chord is then a constant, and the free groups must span what it leaves of B - A.

    Args:
        chain: the problem.
        act: (N+1,) active set in chain order (or (N-1,) joints, both anchor stops free).

    Attributes:
        act, side, ends: the whole set, its (N-1,) joints and its (2,) anchor stops.
        groups: the :class:`Groups` of the joints held at a limit.
        held: (groups,) True where a fixture fixes the group's angle; free = ~held.
        psi_held: (groups,) the first-rod angle of each held group (radians; 0 elsewhere).
        consistent: False when both anchor stops hold one group at angles that differ.
        d: B - A minus the held groups' chords: what the free groups must span (complex).
    """

    def __init__(self, chain: Chain, act: np.ndarray):
        self.act = as_active(act, chain.n)
        self.side, self.ends = self.act[1:-1], self.act[[0, -1]]
        self.groups = g = Groups(chain, self.side)
        ng = g.starts.size
        held, psi = np.zeros(ng, dtype=bool), np.zeros(ng)
        self.consistent = True
        if self.ends[0]:
            held[0], psi[0] = True, end_bound(chain.end_limits[0], self.ends[0])
        if self.ends[1]:
            value = end_bound(chain.end_limits[1], self.ends[1]) - g.offsets[-1]
            if held[-1]:  # one group held at both ends: the two angles must agree
                self.consistent = abs(np.angle(np.exp(1j * (value - psi[-1])))) <= END_ANGLE_TOL
            else:
                held[-1], psi[-1] = True, value
        self.held, self.free, self.psi_held = held, ~held, psi
        fixed_chords = np.conj(g.P[held]) * np.exp(1j * psi[held])
        self.d = chain.d - complex(fixed_chords.sum())
        self.n_free = int(np.count_nonzero(self.free))

    def reachable(self) -> bool:
        """Can the free groups (two or more) span ``d`` with room to move?"""
        if not self.consistent or self.n_free < 2:
            return False
        chords = self.groups.chords[self.free]
        total, longest, span = chords.sum(), chords.max(), abs(self.d)
        margin = 1e-12 * total
        return bool(span < total - margin and span > 2.0 * longest - total + margin)

    def closes_rigidly(self, chain: Chain) -> bool:
        """Is this a set with at most one free group whose groups close the chain exactly
        (to 1e-9 of its length)? Its statics are then indeterminate (:mod:`optimize.chain.dual`)."""
        if not self.consistent or self.n_free > 1:
            return False
        chord = float(self.groups.chords[self.free].sum())
        return abs(abs(self.d) - chord) <= 1e-9 * chain.total_length

    def feasible(self, chain: Chain) -> bool:
        """Can the rods close the chain with these joints and anchor stops held?"""
        return self.reachable() or self.closes_rigidly(chain)

    def angles(self, psi_free: np.ndarray) -> np.ndarray:
        """(N,) rod angles from the free groups' angles (the held ones at their stops)."""
        psi = self.psi_held.copy()
        psi[self.free] = psi_free
        return np.unwrap(psi[self.groups.gid] + self.groups.offsets)


def multipliers(chain: Chain, theta: np.ndarray, lam: complex):
    """Per-rod generalised force f_k, joint moments mu_j and the end moment mu_{N-1}.

    Args:
        chain: the problem.
        theta: (N,) chord angles in radians.
        lam: the reaction (H, V) at B as the complex number H + iV (force).

    Returns:
        (mu, mu_end, curvature): (N-1,) moments each joint must carry with no anchor stop
        held (force x length; zero at free joints in equilibrium), the end moment mu_{N-1}
        (zero in equilibrium without anchor stops), and (N,) the per-rod second derivatives
        of the Lagrangian. :func:`fixture_moments` adds the anchor stops.
    """
    z = lam - chain.sigma
    e = np.exp(1j * theta)
    f = chain.lengths * (np.conj(z) * e).imag
    cum = -np.cumsum(f)
    curvature = chain.lengths * (np.conj(z) * e).real
    return cum[:-1], float(cum[-1]), curvature


def fixture_moments(chain: Chain, mu: np.ndarray, mu_end: float, act: np.ndarray):
    """Joint moments with the anchor fixtures' moments (positive pushes the angle up).

    Stationarity in theta_k gives mu_k = M_0 + mu'_k (mu' from :func:`multipliers`) and
    M_1 = -(M_0 + mu'_{N-1}). A held first rod's fixture moment M_0 follows from its
    group's balance (the moment at the first free joint is zero). With every joint held and
    both rods stopped the split between the fixtures is indeterminate: it is taken as even
    as the signs of the stops' moments allow.

    Args:
        chain: the problem.
        mu, mu_end: from :func:`multipliers`.
        act: (N+1,) or (N-1,) active set.

    Returns:
        (mu, fixtures, free_end): (N-1,) joint moments; (2,) fixture moments (zero where
        an anchor stop is free); the moment a free last rod would need (zero in
        equilibrium), force x length.
    """
    act = as_active(act, chain.n)
    side, ends = act[1:-1], act[[0, -1]]
    m0 = 0.0
    if ends[0]:
        free = np.flatnonzero(side == 0)
        if free.size:
            m0 = -float(mu[free[0]])
        elif not ends[1]:
            m0 = -mu_end
        else:
            m0 = _even_split(chain, mu, mu_end, side, ends)
    rest = -(m0 + mu_end)
    fixtures = np.array([m0, rest if ends[1] else 0.0])
    return mu + m0, fixtures, 0.0 if ends[1] else abs(rest)


def _even_split(chain: Chain, mu, mu_end, side, ends) -> float:
    """M_0 for a chain held rigid between two fixtures: the even split -mu_end / 2, moved
    into the interval where every stop's moment and both fixtures' have the right sign."""
    lo, hi = -np.inf, np.inf
    movable = ~chain.fixed
    # held at lo (side -1): M_0 + mu_j >= 0; at hi: M_0 + mu_j <= 0
    lo = max(lo, np.max(-mu[(side < 0) & movable], initial=-np.inf))
    hi = min(hi, np.min(-mu[(side > 0) & movable], initial=np.inf))
    if not chain.end_fixed[0]:
        lo, hi = (max(lo, 0.0), hi) if ends[0] < 0 else (lo, min(hi, 0.0))
    if not chain.end_fixed[1]:  # M_1 = -(M_0 + mu_end): >= 0 at lo, <= 0 at hi
        lo, hi = (lo, min(hi, -mu_end)) if ends[1] < 0 else (max(lo, -mu_end), hi)
    even = -0.5 * mu_end
    return float(np.clip(even, lo, hi)) if lo <= hi else even


def _end_angles(chain: Chain, theta: np.ndarray) -> np.ndarray:
    """(2,) theta_0 and theta_{N-1} on the turns of their end limits."""
    return np.array([near(theta[0], chain.end_limits[0]), near(theta[-1], chain.end_limits[1])])


def kkt_residual(
    chain: Chain, theta: np.ndarray, lam: complex, side: np.ndarray, mult=None
) -> float:
    """Relative KKT residual of a configuration for a given active set.

    The largest of: closure error / total length; moments at free joints and the
    end moment / (g * total mass * total length); limit violation (rad), end limits and
    held anchor stops off their bound included; wrong-sign moments at active limits and
    anchor stops (same scale).

    Args:
        side: (N+1,) active set with the anchor stops, or (N-1,) joints (stops free).
        mult: :func:`multipliers` at (theta, lam), if already computed.
    """
    act = as_active(side, chain.n)
    side, ends = act[1:-1], act[[0, -1]]
    closure = abs(np.sum(chain.lengths * np.exp(1j * theta)) - chain.d) / chain.total_length
    mu0, mu_end, _ = mult if mult is not None else multipliers(chain, theta, lam)
    mu, fixtures, free_end = fixture_moments(chain, mu0, mu_end, act)
    scale = chain.moment_scale
    free = side == 0
    stat = max(np.max(np.abs(mu[free]), initial=0.0), free_end) / scale
    phi = np.diff(theta)
    lo, hi = chain.limits[:, 0], chain.limits[:, 1]
    feas = max(np.max(np.maximum(lo - phi, phi - hi), initial=0.0), 0.0)
    t = _end_angles(chain, theta)
    elo, ehi = chain.end_limits[:, 0], chain.end_limits[:, 1]
    feas = max(feas, float(np.max(np.maximum(elo - t, t - ehi))))
    on = np.where(ends < 0, elo, ehi)
    if ends.any():
        feas = max(feas, float(np.max(np.abs(t - on)[ends != 0])))
    movable = ~chain.fixed
    sign = np.max(
        np.concatenate([-mu[(side < 0) & movable], mu[(side > 0) & movable],
                        -fixtures[(ends < 0) & ~chain.end_fixed], fixtures[(ends > 0) & ~chain.end_fixed], [0.0]])
    ) / scale
    return float(max(closure, stat, feas, max(sign, 0.0)))


def is_stable(chain: Chain, theta: np.ndarray, lam: complex, side: np.ndarray, mult=None) -> bool:
    """Second-order check on the tangent space of closure and the binding limits.

    Joints at a limit and anchor stops with a vanishing moment are treated as free (a
    conservative check); a binding anchor stop fixes its group's angle. For group angles
    psi the Lagrangian Hessian is diagonal, D_G; with the closure Jacobian C (2 x n) the
    inertia identity In(Z'DZ) = In(D) + In(-C D^-1 C') - (m, m, 0) decides it in O(n).

    Args:
        side: (N+1,) active set with the anchor stops, or (N-1,) joints (stops free).
    """
    act = as_active(side, chain.n)
    side, ends = act[1:-1], act[[0, -1]]
    mu0, mu_end, curv = mult if mult is not None else multipliers(chain, theta, lam)
    mu, fixtures, _ = fixture_moments(chain, mu0, mu_end, act)
    firm = 1e3 * MOMENT_TOL * chain.moment_scale
    binding = (side != 0) & (chain.fixed | (np.abs(mu) > firm))
    held = (ends != 0) & (chain.end_fixed | (np.abs(fixtures) > firm))
    starts = np.flatnonzero(np.concatenate([[True], ~binding]))
    D = np.add.reduceat(curv, starts)
    chords = np.add.reduceat(chain.lengths * np.exp(1j * theta), starts)
    moves = np.ones(D.size, dtype=bool)
    moves[0] &= not held[0]
    moves[-1] &= not held[1]
    D, chords = D[moves], chords[moves]
    if not D.size:
        return True  # every group held by the fixtures: nothing can move
    return stable_on_closure(D, 1j * chords, chain.total_length)


def stable_on_closure(D: np.ndarray, cols: np.ndarray, length_scale: float) -> bool:
    """Is the Hessian diag(D) positive definite on the null space of the closure Jacobian?

    Args:
        D: (n,) the Lagrangian's second derivatives in n independent angles (one per rigid
            body or group that turns freely), force x length.
        cols: (n,) complex, d(closure)/d(angle) of each (i times the body's chord), length.
        length_scale: the chain's length (rank tolerance).

    The inertia identity In(Z'DZ) = In(D) + In(-C D^-1 C') - (m, m, 0) (C the 2 x n
    Jacobian, m its rank) decides it in O(n); where some D vanishes (an unloaded body) the
    null space is projected explicitly.
    """
    if not D.size:
        return True
    C = np.vstack([cols.real, cols.imag])
    scale = np.max(np.abs(D))
    rank = np.linalg.matrix_rank(C, tol=1e-12 * length_scale)
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
    if rank < 2:  # the movable chords are parallel: one closure direction constrains them
        from scipy.linalg import null_space

        Z = null_space(C, rcond=1e-12)
        eig = np.linalg.eigvalsh(Z.T @ (D[:, None] * Z))
        return bool(eig.min() > 1e-9 * scale)
    S = -(C / D) @ C.T
    eig = np.linalg.eigvalsh(S)
    if np.any(np.abs(eig) <= 1e-12 * np.max(np.abs(eig))):
        return False
    return n_neg_d + int(np.count_nonzero(eig < 0)) - rank == 0


def sag_guess(chain: Chain) -> np.ndarray:
    """A symmetric two-slope sag between the anchors (knows nothing of the answer).

    Returns:
        (N,) chord angles in radians: the first half of the rods turned down from the
        line A-B, the second half up, by the angle a two-bar chain of the same total
        length makes with it.
    """
    drop = np.arccos(min(1.0, chain.span / chain.total_length))
    half = np.arange(chain.n) < chain.n / 2
    return np.angle(chain.d) + np.where(half, -drop, drop)


def violations(chain: Chain, theta: np.ndarray, lam: complex, side: np.ndarray):
    """Primal (free joints outside limits) and dual (wrong-sign moments) violations.

    Args:
        side: (N+1,) active set with the anchor stops, or (N-1,) joints (stops free).

    Returns:
        (primal, pside, dual), each of the shape of ``side``: how far a free joint (or end
        rod) is past a limit (rad), which limit (-1 lo, +1 hi), and how wrong a held
        stop's moment is (relative to the chain's weight x length).
    """
    joints_only = np.asarray(side).shape == (chain.n - 1,)
    act = as_active(side, chain.n)
    side, ends = act[1:-1], act[[0, -1]]
    phi = np.concatenate([[0.0], np.diff(theta), [0.0]])
    lo = np.concatenate([[-np.inf], chain.limits[:, 0], [-np.inf]])
    hi = np.concatenate([[np.inf], chain.limits[:, 1], [np.inf]])
    phi[[0, -1]] = _end_angles(chain, theta)
    lo[[0, -1]], hi[[0, -1]] = chain.end_limits[:, 0], chain.end_limits[:, 1]
    free = act == 0
    tol = np.full(act.size, ANGLE_TOL)
    tol[[0, -1]] = END_ANGLE_TOL
    over = free & (phi > hi + tol)
    under = free & (phi < lo - tol)
    primal = np.where(over, phi - hi, np.where(under, lo - phi, 0.0))
    mu0, mu_end, _ = multipliers(chain, theta, lam)
    mu, fixtures, _ = fixture_moments(chain, mu0, mu_end, act)
    m = np.concatenate([[fixtures[0]], mu, [fixtures[1]]])
    movable = ~np.concatenate([[chain.end_fixed[0]], chain.fixed, [chain.end_fixed[1]]])
    mtol = MOMENT_TOL * chain.moment_scale
    wrong = np.where((act < 0) & movable & (m < -mtol), -m, 0.0)
    wrong = np.where((act > 0) & movable & (m > mtol), m, wrong)
    out = (primal, np.where(over, 1, np.where(under, -1, 0)), wrong / chain.moment_scale)
    return tuple(x[1:-1] for x in out) if joints_only else out
