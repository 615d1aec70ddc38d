"""Hub sockets and rod masses balanced together: one bounded nonlinear least squares.

At a net's target each free hub (a rigid body with ball sockets at ``pivot_radius`` from its
centre) must balance its rods' pulls and weight shares and its own weight, forces and
moments. With the sockets fixed the balance is linear in the rods' tensions and masses
(:mod:`optimize.net.statics`); turning the sockets on their sphere changes the rods'
directions, the weight shares' arms and the hub's centre of mass. The turns that balance a
hub are not unique, and a turn chosen hub by hub (the least turn for given forces) may need
masses outside what the rods can be built at. :func:`balance_sockets` solves the turns, the
masses (within their bounds) and the tensions (>= 0 unless compression is allowed) together:
SciPy's trust region reflective least squares (:func:`optimize.net.trf.trf`: each step's
direction by a sparse factorization, not LSMR; the exact sparse Jacobian: a rod's unknowns
reach its two nodes' rows; unknowns scaled by the Jacobian's columns) on every free hub's
force and moment balance, from the sockets given (the turns being a few degrees, it stays near
them). Finite differences over the rods' node pattern took 30-60 evaluations a
Jacobian and, with fixed scales, crawled where masses sit at their bounds.

Each socket turns from ``p0`` (``pivots``, unit direction ``d0``) to ``r (d0 + a b1 + c b2) /
|d0 + a b1 + c b2|`` with ``b1, b2`` a tangent basis at ``d0`` and ``|a|, |c| <= tan(max_turn_deg)``:
two unknowns per socket of a free hub; an anchored hub
holds any moment and keeps its sockets. A hub's centre of mass follows its sockets:
``node_com = socket_com * sum of its sockets' unit directions`` (hollow sockets on a solid
ball: the centre of mass moves away from them, ``socket_com < 0``).

Units: mm, g, forces in g x the unit of ``g``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from optimize.net.model import cross
from optimize.net.pushing import push_mask
from optimize.net.trf import trf

__all__ = ["FIXED_TURN", "STALL_COST", "STALL_DROP", "STALL_ITERS", "SocketBalance", "SocketProblem", "balance_sockets",
           "socket_problem"]

#: A solve whose cost (half the squared imbalances over the force scale) is still above STALL_COST
#: and fell by less than STALL_DROP of itself over the last STALL_ITERS iterations stops there:
#: bounds hold it far from balancing (a strip's joint solve crawled 150 more iterations from 5.67
#: to 5.66), and the statics at its sockets judge it as they would at the 200th.
STALL_COST = 1e-6
STALL_DROP = 1e-2
STALL_ITERS = 20

#: A socket whose turn is bounded by this little (deg) stays where it starts (no unknowns).
FIXED_TURN = 1e-6


@dataclass
class SocketBalance:
    """Sockets, masses and tensions that balance every free hub at the target.

    Attributes:
        pivots: (m, 2, 3) the turned sockets' pivots from their node points (mm).
        masses: (m,) rod masses (g), within their bounds.
        tensions: (m,) rod tensions (force).
        node_com: (n, 3) the hubs' centres of mass for those sockets (mm).
        residual: largest imbalance over the force scale (one mid-bound rod's weight; moments
            over that times the mean rod length).
        turn_deg: largest turn of a socket from where it started (degrees).
        nfev: the least squares' evaluations.
    """

    pivots: np.ndarray
    masses: np.ndarray
    tensions: np.ndarray
    node_com: np.ndarray
    residual: float
    turn_deg: float
    nfev: int


@dataclass
class SocketProblem:
    """:func:`balance_sockets`' least squares (see :func:`socket_problem`).

    Attributes:
        fun: x -> every free hub's force (over the force scale) and moment (over that times
            the mean rod length) imbalance, (6 x free hubs,).
        jac: x -> the exact Jacobian of ``fun`` (scipy sparse).
        x0, lo, hi: the start and the bounds: each turning socket's two turns, the tensions
            over the force scale, each mass's place in its bounds (0..1).
        unpack: x -> (pivots (m, 2, 3), tensions, masses).
        hub_com: pivots -> (n, 3) the hubs' centres of mass.
    """

    fun: object
    jac: object
    x0: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    unpack: object
    hub_com: object


class _Stall:
    """:func:`optimize.net.trf.trf`'s callback that stops a stalled solve (:data:`STALL_COST`)."""

    def __init__(self) -> None:
        self.costs: list[float] = []

    def __call__(self, cost: float) -> bool:
        c = self.costs
        c.append(float(cost))
        return len(c) > STALL_ITERS and c[-1] > STALL_COST and c[-1] > (1 - STALL_DROP) * c[-1 - STALL_ITERS]


def balance_sockets(target_positions, edges, pivots, mass_bounds, anchored, *, node_masses, socket_com,
                    masses0, tensions0, start=None, max_turn_deg: float = 15.0, bound_slopes=None, com=None,
                    allow_compression: bool | np.ndarray = False, g: float = 9.81, max_nfev: int = 200,
                    tol: float = 1e-13) -> SocketBalance:
    """Socket turns, rod masses and tensions that balance every free hub (see the module).

    Args:
        target_positions: (n, 3) node points (mm).
        edges: (m, 2) rods' node indices.
        pivots: (m, 2, 3) the sockets the turns are measured from (from the node points, mm;
            nonzero), e.g. on the lines between the node points.
        mass_bounds: (m, 2) rod mass bounds (g) at the lengths of the sockets the solve starts from.
        anchored: (n,) bool mask or indices of anchored nodes.
        node_masses: (n,) hub masses (g).
        socket_com: (n,) a hub's centre of mass per unit sum of its sockets' directions (mm).
        masses0, tensions0: (m,) the start (g, force), e.g. the statics' best fit.
        start: (m, 2, 3) the sockets to start from (None: ``pivots``); an anchored hub's stay
            there.
        max_turn_deg: each socket turns at most this far from ``pivots`` about each of two
            axes across it (deg; a hub balanced by large turns would put its rods beyond what
            their sockets let them swing): one number, or (m, 2) per socket (its turn is then
            at most ``atan(sqrt(2) tan(max_turn_deg))`` from ``pivots``; one bounded by
            :data:`FIXED_TURN` or less stays at ``start``).
        bound_slopes: (m, 2) d(mass bounds)/d(pivot-to-pivot length) (g/mm): a rod's bounds
            follow its length as its sockets turn (a rod with steel balls may be buildable in a
            range a few micrograms wide), or None: fixed bounds.
        com: (m, 3) rods' centres of mass (along the chord, off it, 0) (mm), or None: at
            mid-length on the axis.
        allow_compression: let tensions go negative: every rod's (True) or those of an (m,) mask.
        g: gravitational acceleration.
        max_nfev: the least squares' evaluations at most.
        tol: its ``ftol``/``xtol``/``gtol``.

    Returns:
        SocketBalance.
    """
    pr = socket_problem(target_positions, edges, pivots, mass_bounds, anchored, node_masses=node_masses,
                        socket_com=socket_com, masses0=masses0, tensions0=tensions0, start=start,
                        max_turn_deg=max_turn_deg, bound_slopes=bound_slopes, com=com,
                        allow_compression=allow_compression, g=g)
    ls = trf(pr.fun, pr.jac, pr.x0, pr.lo, pr.hi, ftol=tol, xtol=tol, gtol=tol, max_nfev=max_nfev,
             callback=_Stall())
    P, T, mass = pr.unpack(ls.x)
    P0 = np.asarray(pivots, float)
    r = np.linalg.norm(P0, axis=2)
    res = float(np.max(np.abs(pr.fun(ls.x)), initial=0.0))
    cos = np.sum(P * P0, axis=2) / (r * np.linalg.norm(P, axis=2))
    turn_deg = float(np.degrees(np.arccos(np.clip(cos, -1, 1))).max())
    return SocketBalance(P, mass, T, pr.hub_com(P), res, turn_deg, int(ls.nfev))


def socket_problem(target_positions, edges, pivots, mass_bounds, anchored, *, node_masses, socket_com,
                   masses0, tensions0, start=None, max_turn_deg: float = 15.0, bound_slopes=None, com=None,
                   allow_compression: bool | np.ndarray = False, g: float = 9.81) -> SocketProblem:
    """The least squares :func:`balance_sockets` solves: its residuals, their exact sparse
    Jacobian, the start and the bounds (arguments as :func:`balance_sockets`)."""
    X = np.asarray(target_positions, float)
    E = np.asarray(edges, int)
    P0 = np.asarray(pivots, float)
    n, m = X.shape[0], E.shape[0]
    anch = np.zeros(n, bool)
    a_in = np.asarray(anchored)
    if a_in.dtype == bool:
        anch[:] = a_in
    else:
        anch[a_in.astype(int)] = True
    bounds = np.broadcast_to(np.asarray(mass_bounds, float), (m, 2))
    M = np.asarray(node_masses, float)
    kappa = np.asarray(socket_com, float)
    r = np.linalg.norm(P0, axis=2)
    free = ~anch
    turns = np.minimum(np.broadcast_to(np.asarray(max_turn_deg, float), (m, 2)), 89.0)
    turn = free[E] & (turns > FIXED_TURN)           # (m, 2) sockets that may turn
    ns = int(turn.sum())
    # tangent bases at the start
    d0 = P0 / r[..., None]
    helper = np.where(np.abs(d0[..., 2:3]) < 0.9, [0.0, 0.0, 1.0], [1.0, 0.0, 0.0])
    b1 = np.cross(d0, helper)
    b1 /= np.linalg.norm(b1, axis=2, keepdims=True)
    b2 = np.cross(d0, b1)
    base = P0 if start is None else np.asarray(start, float)  # (the sockets that do not turn stay there)
    L0 = np.linalg.norm(X[E[:, 1]] + base[:, 1] - X[E[:, 0]] - base[:, 0], axis=1)  # where the bounds hold
    lmean = float(L0.mean())
    slopes = np.zeros((m, 2)) if bound_slopes is None else np.asarray(bound_slopes, float)
    m_ref = float(np.exp(np.mean(np.log(bounds.mean(axis=1)))))
    F = g * m_ref
    rfree = np.flatnonzero(free)
    row = np.full(n, -1)
    row[rfree] = np.arange(rfree.size)
    nr = 6 * rfree.size
    com_arr = None if com is None else np.asarray(com, float)
    z = np.array([0.0, 0.0, 1.0])

    def unpack(x):
        ang = x[:2 * ns].reshape(ns, 2)
        P = base.copy()
        v = d0[turn] + ang[:, :1] * b1[turn] + ang[:, 1:] * b2[turn]
        P[turn] = r[turn][:, None] * v / np.linalg.norm(v, axis=1, keepdims=True)
        T = x[2 * ns:2 * ns + m] * F
        L = np.linalg.norm(X[E[:, 1]] + P[:, 1] - X[E[:, 0]] - P[:, 0], axis=1)
        b = bounds + slopes * (L - L0)[:, None]  # the bounds at the rods' lengths
        mass = b[:, 0] + x[2 * ns + m:] * (b[:, 1] - b[:, 0])
        return P, T, mass

    def hub_com(P):
        s = np.zeros((n, 3))
        np.add.at(s, E[:, 0], P[:, 0] / r[:, 0, None])
        np.add.at(s, E[:, 1], P[:, 1] / r[:, 1, None])
        return kappa[:, None] * s

    def fun(x):
        P, T, mass = unpack(x)
        ends = X[E] + P
        d = ends[:, 1] - ends[:, 0]
        L = np.linalg.norm(d, axis=1)
        u = d / L[:, None]
        if com_arr is None:
            f = np.full((m, 2), 0.5)
        else:
            t = com_arr[:, 0] / L
            off = np.linalg.norm(com_arr[:, 1:], axis=1)
            s = u[:, 2]
            q = off * s / (L * np.sqrt(np.maximum(1 - s * s, 1e-300)))
            f = np.column_stack([1 - t - q, t + q])
        force = np.zeros((n, 3))
        moment = np.zeros((n, 3))
        for k, sign in ((0, 1.0), (1, -1.0)):
            Fk = sign * T[:, None] * u - (g * mass * f[:, k])[:, None] * z
            np.add.at(force, E[:, k], Fk)
            np.add.at(moment, E[:, k], cross(P[:, k], Fk))
        w = -g * M[:, None] * z
        force += w
        moment += cross(hub_com(P), w)
        return np.concatenate([force[rfree] / F, moment[rfree] / (F * lmean)], axis=1).ravel()

    sidx = np.full((m, 2), -1)
    sidx[turn] = np.arange(ns)
    eye = np.eye(3)

    def jac(x):
        """The exact Jacobian (sparse): a rod's turns, tension and mass reach its two nodes' rows, a
        socket's turn its own hub's centre of mass too."""
        P, T, mass = unpack(x)
        ang = x[:2 * ns].reshape(ns, 2)
        ends = X[E] + P
        d = ends[:, 1] - ends[:, 0]
        L = np.linalg.norm(d, axis=1)
        u = d / L[:, None]
        du = (eye - u[:, :, None] * u[:, None, :]) / L[:, None, None]      # du/dd (m, 3, 3)
        width = (bounds[:, 1] - bounds[:, 0]) + (slopes[:, 1] - slopes[:, 0]) * (L - L0)
        theta = x[2 * ns + m:]
        dmass_dd = (slopes[:, 0] + theta * (slopes[:, 1] - slopes[:, 0]))[:, None] * u  # via L
        if com_arr is None:
            f = np.full((m, 2), 0.5)
            df1 = np.zeros((m, 3))
        else:
            t_ = com_arr[:, 0] / L
            off = np.linalg.norm(com_arr[:, 1:], axis=1)
            s = u[:, 2]
            root = np.sqrt(np.maximum(1 - s * s, 1e-300))
            q = off * s / (L * root)
            f = np.column_stack([1 - t_ - q, t_ + q])
            df1 = (-(t_ + q) / L)[:, None] * u + (off / (L * root ** 3))[:, None] * du[:, 2, :]
        rows, cols, vals = [], [], []

        def put(node_rows, col, block):  # block (m, 6) at the rods' node rows, column col (m,)
            ok = (node_rows >= 0) & (col >= 0)
            rr = 6 * node_rows[ok, None] + np.arange(6)
            rows.append(rr.ravel())
            cols.append(np.repeat(col[ok], 6))
            vals.append(block[ok].ravel())

        # tangent of each turning socket's pivot: dP/d(a, c) (ns, 3, 2)
        if ns:
            v = d0[turn] + ang[:, :1] * b1[turn] + ang[:, 1:] * b2[turn]
            nv = np.linalg.norm(v, axis=1)
            nrm = v / nv[:, None]
            proj = (eye - nrm[:, :, None] * nrm[:, None, :]) * (r[turn] / nv)[:, None, None]
            dP = np.stack([proj @ b1[turn][..., None], proj @ b2[turn][..., None]], axis=2)[..., 0]
            dPf = np.zeros((m, 2, 3, 2))
            dPf[turn] = dP
        scale = np.array([1.0 / F] * 3 + [1.0 / (F * lmean)] * 3)
        for k, sign in ((0, 1.0), (1, -1.0)):
            nrow = row[E[:, k]]
            fk = f[:, k]
            dfk = df1 if k == 1 else -df1
            Fk = sign * T[:, None] * u - (g * mass * fk)[:, None] * z
            # dFk/dd (m, 3, 3): the tension along the rod's turning direction, the weight share's
            # change with the rod's length (its mass bounds) and tilt (its centre of mass's share)
            A = sign * T[:, None, None] * du
            A[:, 2, :] -= g * (fk[:, None] * dmass_dd + mass[:, None] * dfk)
            Sk = _skews(P[:, k])
            dFT = sign * F * u
            put(nrow, 2 * ns + np.arange(m), np.concatenate([dFT, np.einsum("mij,mj->mi", Sk, dFT)], axis=1) * scale)
            dFth = np.zeros((m, 3))
            dFth[:, 2] = -g * fk * width
            put(nrow, 2 * ns + m + np.arange(m), np.concatenate([dFth, np.einsum("mij,mj->mi", Sk, dFth)], axis=1) * scale)
            if not ns:
                continue
            for c in (0, 1):
                dF = (A if c == 1 else -A) @ dPf[:, c]                      # (m, 3, 2)
                dM = Sk @ dF
                if c == k:
                    dM = dM - _skews(Fk) @ dPf[:, c]
                for j in (0, 1):
                    col = np.where(sidx[:, c] >= 0, 2 * sidx[:, c] + j, -1)
                    put(nrow, col, np.concatenate([dF[:, :, j], dM[:, :, j]], axis=1) * scale)
        if ns:  # a hub's centre of mass follows its sockets: d(cross(kappa P / r, w))
            for c in (0, 1):
                node = E[:, c]
                w = -g * M[node, None] * z
                blk = -(kappa[node] / r[:, c])[:, None, None] * _skews(w) @ dPf[:, c]
                for j in (0, 1):
                    col = np.where(sidx[:, c] >= 0, 2 * sidx[:, c] + j, -1)
                    put(row[node], col, np.concatenate([np.zeros((m, 3)), blk[:, :, j]], axis=1) * scale)
        return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(nr, nx))

    nx = 2 * ns + 2 * m
    # unknowns: turns (2 per socket), tensions / F, each mass's place in its bounds (0..1)
    width = bounds[:, 1] - bounds[:, 0]
    theta0 = np.where(width > 0, (np.asarray(masses0, float) - bounds[:, 0]) / np.where(width > 0, width, 1.0), 0.5)
    T0 = np.asarray(tensions0, float) / F
    push = push_mask(allow_compression, m)
    T0 = np.where(push, T0, np.maximum(T0, 1e-9))
    inner = 1e-9
    lo = np.concatenate([np.full(2 * ns, -np.inf), np.where(push, -np.inf, 0.0), np.full(m, inner)])
    hi = np.concatenate([np.full(2 * ns, np.inf), np.full(m, np.inf), np.full(m, 1 - inner)])
    cap = np.repeat(np.tan(np.radians(turns))[turn], 2).reshape(ns, 2)
    ang0 = np.zeros((ns, 2))
    if start is not None:
        ds = np.asarray(start, float)[turn]
        ds = ds / np.linalg.norm(ds, axis=1, keepdims=True)
        along = np.sum(ds * d0[turn], axis=1, keepdims=True)
        ang0 = np.column_stack([np.sum(ds * b1[turn], axis=1), np.sum(ds * b2[turn], axis=1)]) / along
    ang0 = np.clip(ang0, -cap * (1 - 1e-9), cap * (1 - 1e-9))
    lo[:2 * ns], hi[:2 * ns] = -cap.ravel(), cap.ravel()
    x0 = np.concatenate([ang0.ravel(), T0, np.clip(theta0, 2 * inner, 1 - 2 * inner)])
    return SocketProblem(fun, jac, x0, lo, hi, unpack, hub_com)


def _skews(a: np.ndarray) -> np.ndarray:
    """(k, 3, 3) the cross-product matrices of (k, 3) vectors: ``_skews(a)[i] @ b == cross(a[i], b)``."""
    S = np.zeros(a.shape[:-1] + (3, 3))
    S[..., 0, 1], S[..., 0, 2] = -a[..., 2], a[..., 1]
    S[..., 1, 0], S[..., 1, 2] = a[..., 2], -a[..., 0]
    S[..., 2, 0], S[..., 2, 1] = -a[..., 1], a[..., 0]
    return S
