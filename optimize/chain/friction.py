"""Pin friction: the band of shapes a chain can rest in around its equilibrium.

A pin of radius r carrying a force F lets its joint hold any moment up to ``mu |F| r``
(Coulomb friction, ``mu`` ~ 0.2-0.4 for PLA on steel). So the chain need not come to rest at
the energy minimum: it can rest wherever, at every pin, the moment the statics asks of the
pin stays within that capacity.

Method (exact for the statics linearised at the equilibrium)
-------------------------------------------------------------
Around the equilibrium, the chain's angles move by q (radians). The potential energy is the
quadratic ``f.q + q'Hq/2`` (H the Hessian of the Lagrangian, f its gradient: the moments the
active stops carry), the closure is ``C q = 0``, every stop and anchor stop a half-space
``a_r.q >= b_r`` (fused joints equalities). Friction moments ``m`` (one per pin, ``|m_k| <=
tau_k``) act as generalised forces ``w = E m``. A configuration is at rest iff it minimises
``f.q + q'Hq/2 - w.q`` over the constraints for some admissible ``m``: the rest set is the
image of the box of friction moments under that (piecewise-linear, continuous) solution map,
connected, and exactly computable:

* On one *cell* (a set S of stops that hold) the map is affine, from one KKT solve with S
  as equalities; the cell is the polytope of ``m`` where the stops in S push the right way and
  the others are not passed.
* If the whole box lies in the equilibrium's own cell (checked in closed form) the rest set is
  a zonotope and each joint's largest displacement is the largest norm over its vertices,
  enumerated exactly.
* Otherwise the cells the box meets are explored from the equilibrium's (neighbours across
  every facet the box reaches, found by linear programs) and each joint's largest displacement
  over each cell is the largest norm over the vertices of the cell's image polygon, found by
  support linear programs refined until no edge moves.

The displacement is the Euclidean distance of a joint from its equilibrium position (caller's
length unit). The linearisation's error is second order in the band's angles (about
``band / size`` of the band).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linprog

from optimize.chain import Chain
from optimize.chain.endlimits import as_end_limits, limit_turn
from optimize.chain.equilibrium import EquilibriumResult, solve_equilibrium
from optimize.chain.pins import joint_forces

__all__ = ["FrictionBand", "friction_band", "friction_capacity"]

#: Cells explored at most (each a set of stops that hold) before the band is reported as a
#: lower bound (``FrictionBand.exhaustive`` False).
MAX_CELLS = 64

#: Polygon searches (each some ten support linear programs) at most; past them a joint's
#: largest displacement over a cell is the bound of the cell's affine map over the whole box
#: (never below the exact value: ``FrictionBand.tight`` False). Counted, not timed: the same
#: chain gives the same band on every machine.
MAX_POLYGONS = 150


@dataclass
class FrictionBand:
    """The band of shapes pin friction lets the chain rest in.

    Attributes:
        band: the largest displacement of any joint over the band (length).
        per_joint: (N+1,) each joint's largest displacement over the band (0 at the anchors).
        capacity: (N+1,) the friction moment each pin can hold (force x length; 0 at fused
            joints, which have no pin).
        extreme_moments: (N+1, N+1) for each joint, friction moments (one per pin) at which
            the rest shape puts that joint furthest out.
        extreme_shapes: (N+1, N+1, 2) those rest shapes' joints (linearised).
        response: (N+1, 2, N+1) joint displacement per unit friction moment at each pin, in
            the equilibrium's own cell (length / moment).
        cells: how many cells (sets of holding stops) the band spans; 1 = a zonotope.
        exhaustive: every cell the box of friction moments meets was explored.
        method: how the band was computed.
        tight: every joint's value is its exact maximum (False: some are upper bounds, past
            :data:`MAX_POLYGONS` polygon searches).
    """

    band: float
    per_joint: np.ndarray
    capacity: np.ndarray
    extreme_moments: np.ndarray
    extreme_shapes: np.ndarray
    response: np.ndarray
    cells: int
    exhaustive: bool
    method: str
    tight: bool = True


def friction_capacity(reaction, masses, *, mu: float, pin_radius, g: float = 9.81) -> np.ndarray:
    """The friction moment each pin can hold, ``mu |F_j| r_j`` (N+1,), F_j its joint force
    (:func:`optimize.chain.pins.joint_forces`).

    Args:
        reaction: (2,) the reaction (H, V) at B. masses: (N,).
        mu: friction coefficient (PLA on steel ~0.2-0.4).
        pin_radius: a number or (N+1,) per pin (anchors included), length.
        g: gravitational acceleration.
    """
    F = joint_forces(reaction, masses, g=g)
    r = np.broadcast_to(np.asarray(pin_radius, dtype=float), (F.shape[0],))
    if mu < 0 or np.any(r < 0):
        raise ValueError("mu and pin_radius must be >= 0")
    return mu * np.hypot(F[:, 0], F[:, 1]) * r


class _Linear:
    """The linearised statics at an equilibrium: Hessian, gradient, closure and stop rows."""

    def __init__(self, chain: Chain, res: EquilibriumResult, ends: np.ndarray | None):
        n = chain.n
        theta = res.angles
        lam = complex(*res.reaction)
        z = lam - chain.sigma
        e = np.exp(1j * theta)
        self.f = chain.lengths * (np.conj(z) * e).imag  # gradient of the Lagrangian
        self.H = np.diag(chain.lengths * (np.conj(z) * e).real)
        step = 1j * chain.lengths * e  # d(rod vector)/d(theta)
        self.C = np.vstack([step.real, step.imag])
        tri = np.tril(np.ones((n + 1, n)), -1)  # joint j moves with the rods before it
        self.Jp = np.stack([tri * step.real, tri * step.imag], axis=1)  # (N+1, 2, N)
        self.E = np.zeros((n, n + 1))
        self.E[0, 0] = 1.0
        self.E[n - 1, n] += 1.0
        for j in range(1, n):
            self.E[j, j], self.E[j - 1, j] = 1.0, -1.0
        # rows a.q >= b of every finite bound, equality rows of fused joints
        rows, rhs, held = [], [], []
        eq_rows = []
        phi = np.angle(np.exp(1j * np.diff(theta)))  # bends in (-pi, pi]
        lo, hi = chain.limits[:, 0], chain.limits[:, 1]
        for j in range(n - 1):
            a = np.zeros(n)
            a[j + 1], a[j] = 1.0, -1.0
            if lo[j] == hi[j]:
                eq_rows.append(a)
                continue
            if np.isfinite(lo[j]):
                rows.append(a), rhs.append(lo[j] - phi[j]), held.append(res.active[j] < 0)
            if np.isfinite(hi[j]):
                rows.append(-a), rhs.append(phi[j] - hi[j]), held.append(res.active[j] > 0)
        end_active = res.info.get("end_active", np.zeros(2, dtype=int))
        if ends is not None:
            for k, idx in ((0, 0), (1, n - 1)):
                t = theta[idx] - limit_turn(theta[idx], ends[k])
                a = np.zeros(n)
                a[idx] = 1.0
                if np.isfinite(ends[k, 0]):
                    rows.append(a), rhs.append(ends[k, 0] - t), held.append(end_active[k] < 0)
                if np.isfinite(ends[k, 1]):
                    rows.append(-a), rhs.append(t - ends[k, 1]), held.append(end_active[k] > 0)
        self.A = np.array(rows).reshape(-1, n)
        self.b = np.array(rhs, dtype=float)
        self.b[np.array(held, dtype=bool)] = 0.0  # on the bound (to round-off)
        self.held0 = np.array(held, dtype=bool)
        self.Aeq = np.array(eq_rows).reshape(-1, n)
        self.n = n

    def cell(self, S: np.ndarray):
        """The affine rest map on the cell where the rows S hold: q = G w + q0, and the
        multipliers of the rows S, y = Y w + y0 (>= 0 where they push the right way)."""
        n = self.n
        B = np.vstack([self.C, self.Aeq, self.A[S]])
        k = B.shape[0]
        K = np.block([[self.H, -B.T], [B, np.zeros((k, k))]])
        rhs_w = np.vstack([np.eye(n), np.zeros((k, n))])
        rhs_0 = np.concatenate([-self.f, np.zeros(2 + self.Aeq.shape[0]), self.b[S]])
        sol = np.linalg.solve(K, np.column_stack([rhs_w, rhs_0]))
        G, q0 = sol[:n, :n], sol[:n, n]
        ny = 2 + self.Aeq.shape[0]
        Y, y0 = sol[n + ny:, :n], sol[n + ny:, n]
        return G, q0, Y, y0

    def validity(self, S: np.ndarray):
        """The cell S as ``V m + v0 >= 0`` over friction moments m, and its affine map
        q = Gm m + q0."""
        G, q0, Y, y0 = self.cell(S)
        Gm = G @ self.E
        out = ~S
        V = np.vstack([Y @ self.E, self.A[out] @ Gm])
        v0 = np.concatenate([y0, self.A[out] @ q0 - self.b[out]])
        return V, v0, Gm, q0


def _zonotope_max(A: np.ndarray, tau: np.ndarray, c=None):
    """Largest norm over {c + A m : |m_k| <= tau_k} (A is 2 x K) and the m at that vertex.

    The vertices are ``c + sum_k sign(g_k . e) g_k`` for directions e between consecutive
    normals of the generators g_k = tau_k A[:, k]; each arc between them is tried once."""
    c = np.zeros(2) if c is None else c
    g = A * tau
    keep = np.hypot(g[0], g[1]) > 0
    if not keep.any():
        return float(np.hypot(*c)), np.zeros(tau.size)
    ang = np.arctan2(g[1, keep], g[0, keep])
    cuts = np.sort(np.concatenate([ang + np.pi / 2, ang - np.pi / 2]) % (2 * np.pi))
    mids = 0.5 * (cuts + np.roll(cuts, -1))
    mids[-1] += np.pi  # the arc that wraps through 2 pi
    e = np.vstack([np.cos(mids), np.sin(mids)])
    signs = np.sign(g.T @ e)  # (K, arcs)
    verts = g @ signs + c[:, None]
    k = int(np.argmax(np.hypot(verts[0], verts[1])))
    return float(np.hypot(*verts[:, k])), tau * signs[:, k]


def _lp_support(direction, A, V, v0, tau):
    """max direction . (A m) over {|m| <= tau, V m + v0 >= 0}: (value, m) or None."""
    res = linprog(-(direction @ A), A_ub=-V, b_ub=v0, bounds=list(zip(-tau, tau)), method="highs")
    if res.status != 0:
        return None
    return -res.fun, res.x


def _polygon_max(A, c, V, v0, tau, toward=0.0, rel_tol=1e-9):
    """Largest norm over the image {A m + c} (a polygon) of the polytope {|m| <= tau,
    V m + v0 >= 0}: support points (vertices) in sorted directions; between two directions the
    polygon lies within the two support lines, so where their crossing is no further out than
    the best vertex the interval is done, else the segment's normal is queried (one more vertex,
    or the segment is an edge). Starts from four directions, the first ``toward`` (rad).
    Exact to ``rel_tol``; returns (norm, m) or None (empty)."""
    def support(angle):
        d = np.array([np.cos(angle), np.sin(angle)])
        got = _lp_support(d, A, V, v0, tau)
        return None if got is None else (angle, A @ got[1] + c, got[1])

    pts = [support(toward + t) for t in np.arange(4) * np.pi / 2]
    if any(p is None for p in pts):
        return None
    best = max(pts, key=lambda p: np.hypot(*p[1]))
    scale = max(1e-300, float(np.hypot(*best[1])))
    i = 0
    while i < len(pts) and len(pts) < 400:
        (t0, x0, _), (t1, x1, _) = pts[i], pts[(i + 1) % len(pts)]
        t1 = t1 + 2 * np.pi if t1 <= t0 else t1
        edge = x1 - x0
        if np.hypot(*edge) <= rel_tol * scale:
            i += 1
            continue
        e0, e1 = np.array([np.cos(t0), np.sin(t0)]), np.array([np.cos(t1), np.sin(t1)])
        corner = np.linalg.solve(np.vstack([e0, e1]), [e0 @ x0, e1 @ x1])  # the support lines meet
        if np.hypot(*corner) <= np.hypot(*best[1]) + rel_tol * scale:
            i += 1
            continue
        tn = np.arctan2(-edge[0], edge[1])  # outward normal (directions increase CCW)
        tn = tn + 2 * np.pi * np.ceil((t0 - tn) / (2 * np.pi))
        p = support(tn)
        if p is None or p[1] @ np.array([np.cos(tn), np.sin(tn)]) <= (
                x0 @ np.array([np.cos(tn), np.sin(tn)]) + rel_tol * scale) or not (t0 < tn < t1):
            i += 1  # the segment is an edge of the polygon: its ends are the candidates
            continue
        pts.insert(i + 1, (tn, p[1], p[2]))  # angles stay increasing (the last may pass 2 pi)
        if np.hypot(*p[1]) > np.hypot(*best[1]):
            best = p
    return float(np.hypot(*best[1])), best[2]


def friction_band(
    lengths,
    masses,
    anchor_a,
    anchor_b,
    *,
    mu: float | None = None,
    pin_radius=None,
    capacity=None,
    com=None,
    limits=None,
    end_limits=None,
    g: float = 9.81,
    result: EquilibriumResult | None = None,
) -> FrictionBand:
    """The band of shapes in which pin friction lets the chain rest (module docstring: method).

    Args:
        lengths, masses, anchor_a, anchor_b, com, limits, end_limits, g: the chain, as for
            :func:`optimize.solve_equilibrium` (lengths in the caller's unit, e.g. mm).
        mu, pin_radius: friction coefficient and pin radius (a number or (N+1,) per pin,
            length): the capacities are ``mu |F_j| r_j`` from the equilibrium's joint forces.
        capacity: (N+1,) friction moment per pin (force x length) instead of mu, pin_radius.
        result: the chain's equilibrium if already solved (of these arguments).

    Returns:
        FrictionBand.

    Raises:
        ValueError: bad arguments, or an equilibrium that was not found or is not stable.
    """
    chain = Chain.from_args(lengths, masses, anchor_a, anchor_b, com, limits, g)
    ends = as_end_limits(end_limits)
    if result is None:
        result = solve_equilibrium(chain.lengths, chain.masses, chain.anchor_a, chain.anchor_b,
                                   com=chain.com, limits=chain.limits, end_limits=ends, g=chain.g)
    if not (result.success and result.stable) or not np.all(np.isfinite(result.reaction)):
        raise ValueError(f"the friction band needs a stable, slack equilibrium: {result.message}")
    n = chain.n
    if capacity is None:
        if mu is None or pin_radius is None:
            raise ValueError("give mu and pin_radius, or capacity")
        tau = friction_capacity(result.reaction, chain.masses, mu=mu, pin_radius=pin_radius, g=chain.g)
    else:
        tau = np.broadcast_to(np.asarray(capacity, dtype=float), (n + 1,)).copy()
        if np.any(~np.isfinite(tau) | (tau < 0)):
            raise ValueError("capacity must be finite and >= 0")
    tau = tau.copy()
    tau[1:-1][chain.fixed] = 0.0  # a fused joint has no pin
    lin = _Linear(chain, result, ends)
    S0 = lin.held0.copy()
    V, v0, Gm, q0 = lin.validity(S0)
    response = np.einsum("jdk,km->jdm", lin.Jp, Gm)
    tol = 1e-10 * max(1.0, float(np.abs(v0).max(initial=0.0)))
    regular = bool(np.all(v0 - np.abs(V) @ tau >= -tol))
    per = np.zeros(n + 1)
    ext_m = np.zeros((n + 1, n + 1))
    tight = True
    if regular:
        for j in range(1, n):
            per[j], ext_m[j] = _zonotope_max(response[j], tau)
        cells, exhaustive = 1, True
        method = ("linearised statics; the friction moments' box lies in the equilibrium's "
                  "cell: zonotope, exact vertex enumeration")
    else:
        explored = _explore(lin, S0, tau)
        cells, exhaustive = len(explored), len(explored) < MAX_CELLS
        searches = 0
        for S, (V, v0, Gm, q0) in explored:
            vtol = 1e-10 * max(1.0, float(np.abs(v0).max(initial=0.0)))
            for j in range(1, n):
                A, c = lin.Jp[j] @ Gm, lin.Jp[j] @ q0
                # the cell's affine map over the whole box bounds it; where that bound's
                # vertex lies in the cell it is the cell's maximum, else linear programs
                bound, m = _zonotope_max(A, tau, c)
                if bound <= per[j]:
                    continue
                if np.all(V @ m + v0 >= -vtol):
                    got = (bound, m)
                elif searches >= MAX_POLYGONS:  # the work's bound: the cell's map over the whole box
                    got, tight = (bound, m), False
                else:
                    searches += 1
                    far = A @ m + c
                    got = _polygon_max(A, c, V, v0, tau, toward=float(np.arctan2(far[1], far[0])))
                if got is not None and got[0] > per[j]:
                    per[j], ext_m[j] = got
        method = (f"linearised statics with {cells} cells of holding stops: per joint and cell "
                  "the zonotope vertex where it lies in the cell, else support linear programs "
                  "to the exact polygon vertices" + ("" if tight else f"; past {MAX_POLYGONS} polygon searches, "
                                                     "upper bounds (the cells' maps over the whole box)"))
    shapes = result.points[None] + np.stack([_shape(lin, ext_m[j], S0) for j in range(n + 1)])
    return FrictionBand(band=float(per.max()), per_joint=per, capacity=tau, extreme_moments=ext_m,
                        extreme_shapes=shapes, response=response, cells=cells, exhaustive=exhaustive,
                        method=method, tight=tight)


def _shape(lin: _Linear, m: np.ndarray, S0: np.ndarray) -> np.ndarray:
    """Joint displacements (N+1, 2) at rest under friction moments m (the cell that holds)."""
    S = S0.copy()
    for _ in range(4 * lin.b.size + 4):
        V, v0, Gm, q0 = lin.validity(S)
        slack = V @ m + v0
        if np.all(slack >= -1e-9 * max(1.0, float(np.abs(v0).max(initial=0.0)))):
            return np.einsum("jdk,k->jd", lin.Jp, Gm @ m + q0)
        i = int(np.argmin(slack))
        held = np.flatnonzero(S)
        free = np.flatnonzero(~S)
        if i < held.size:
            S[held[i]] = False
        else:
            S[free[i - held.size]] = True
    return np.einsum("jdk,k->jd", lin.Jp, Gm @ m + q0)


def _explore(lin: _Linear, S0: np.ndarray, tau: np.ndarray):
    """The cells the box of friction moments meets, from the equilibrium's across facets."""
    seen = {S0.tobytes()}
    queue = [S0]
    out = []
    while queue and len(out) < MAX_CELLS:
        S = queue.pop(0)
        V, v0, Gm, q0 = lin.validity(S)
        bounds = list(zip(-tau, tau))
        feasible = linprog(np.zeros(tau.size), A_ub=-V, b_ub=v0, bounds=bounds, method="highs")
        if feasible.status != 0:
            continue
        out.append((S, (V, v0, Gm, q0)))
        held = np.flatnonzero(S)
        free = np.flatnonzero(~S)
        scale = max(1.0, float(np.abs(v0).max(initial=0.0)))
        for i in range(V.shape[0]):
            if v0[i] - np.abs(V[i]) @ tau >= 0:
                continue  # this facet lies beyond the box
            res = linprog(V[i], A_ub=-V, b_ub=v0, bounds=bounds, method="highs")
            if res.status != 0 or res.fun + v0[i] > 1e-9 * scale:
                continue
            T = S.copy()
            if i < held.size:
                T[held[i]] = False
            else:
                T[free[i - held.size]] = True
            if T.tobytes() not in seen:
                seen.add(T.tobytes())
                queue.append(T)
    return out
