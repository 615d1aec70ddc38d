"""The chain problem and what every model of it shares.

Conventions (``shared/design/physics.md``): rods ``0..N-1`` with chord angles
``theta_i`` from +x, joint points ``p_0 = A .. p_N = B``, bends
``phi_j = theta_{j+1} - theta_j``, gravity along -y, each rod's centre of mass
``(along, perp)`` in its own frame. Lengths and masses are in the caller's units;
angles in radians; forces in mass x the unit of ``g``, moments in force x length.

Holds the validated problem (:class:`Chain`), its rigid groups for an active set
(:class:`Groups`), the result type of every model (:class:`EquilibriumResult`, with the
status table :data:`MESSAGES`) and the statics checks the exact model
(:mod:`optimize.equilibrium`) and the paper's penalty model (:mod:`optimize.penalty`)
both use: joint moments, the KKT residual, the second-order stability test and the
symmetric sag starting guess.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from optimize import validate as val

__all__ = [
    "ANGLE_TOL",
    "MESSAGES",
    "MOMENT_TOL",
    "Chain",
    "EquilibriumResult",
    "Groups",
    "is_stable",
    "kkt_residual",
    "multipliers",
    "sag_guess",
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


def multipliers(chain: Chain, theta: np.ndarray, lam: complex):
    """Per-rod generalised force f_k, joint moments mu_j and the end moment mu_{N-1}.

    Args:
        chain: the problem.
        theta: (N,) chord angles in radians.
        lam: the reaction (H, V) at B as the complex number H + iV (force).

    Returns:
        (mu, mu_end, curvature): (N-1,) moments each joint must carry (force x length;
        zero at free joints in equilibrium), the end moment mu_{N-1} (zero in
        equilibrium), and (N,) the per-rod second derivatives of the Lagrangian.
    """
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
    mu, mu_end, _ = mult if mult is not None else multipliers(chain, theta, lam)
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


def is_stable(chain: Chain, theta: np.ndarray, lam: complex, side: np.ndarray, mult=None) -> bool:
    """Second-order check on the tangent space of closure and the binding limits.

    Joints at a limit with a vanishing moment are treated as free (a conservative
    check). For group angles psi the Lagrangian Hessian is diagonal, D_G; with the
    closure Jacobian C (2 x n) the inertia identity
    In(Z'DZ) = In(D) + In(-C D^-1 C') - (m, m, 0) decides it in O(n).
    """
    mu, _, curv = mult if mult is not None else multipliers(chain, theta, lam)
    binding = (side != 0) & (chain.fixed | (np.abs(mu) > 1e3 * MOMENT_TOL * chain.moment_scale))
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
    """Primal (free joints outside limits) and dual (wrong-sign moments) violations."""
    phi = np.diff(theta)
    lo, hi = chain.limits[:, 0], chain.limits[:, 1]
    free = side == 0
    over = free & (phi > hi + ANGLE_TOL)
    under = free & (phi < lo - ANGLE_TOL)
    primal = np.where(over, phi - hi, np.where(under, lo - phi, 0.0))
    mu, _, _ = multipliers(chain, theta, lam)
    movable = ~chain.fixed
    tol = MOMENT_TOL * chain.moment_scale
    wrong = np.where((side < 0) & movable & (mu < -tol), -mu, 0.0)
    wrong = np.where((side > 0) & movable & (mu > tol), mu, wrong)
    return primal, np.where(over, 1, np.where(under, -1, 0)), wrong / chain.moment_scale
