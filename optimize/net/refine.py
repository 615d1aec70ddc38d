"""A net's masses refined through the exact solver toward the fit the verdict measures.

Where no masses within their bounds balance a net at its target (the statics' best fit), the
net hangs somewhat off it, and its verdict is the *largest* distance of what it measures from
where it was drawn: each node (or the point it is measured against, :class:`NetFit`) and each
rod's two pivots, which a node body's turn moves as much as its node point. A least-squares
refinement of the node points alone lowers neither: it trades the worst point for many small
ones, and a hub that turns 15 deg to balance moves its rods' ends by millimetres it does not see.

:func:`refine_masses` minimises that largest distance itself: sequential linear programming
with a trust region (the minimax form of a Gauss-Newton step). At the current masses each
distance ``e_i`` is linearised through the equilibrium's derivatives with respect to the
masses (implicit differentiation of its KKT system: node points and node bodies' turns,
:func:`equilibrium_derivatives`), ``e_i + g_i . dm``; the step is the linear program
``min t  s.t.  e_i + g_i . dm <= t`` over the points within half the largest distance, ``dm``
within the mass bounds and a box of ``rho`` times their widths. Each step is checked by the
solver from the target, the start the design's verdict solves from (a net with hubs may have
more than one stable equilibrium near its target, and a path of small steps, each solved from
the last, can follow one that the verdict's solve does not reach: the masses are judged by the
equilibrium they will be judged by), and kept only where the largest distance falls; ``rho``
grows where the prediction held and shrinks where it did not.

A rod turns in its hub's socket as the net moves, and the socket lets it turn only so far
(``swing``: each rod end's limit). Each end's turn from its socket's axis is linearised the same
way (the socket's axis turns with its body, the rod's direction with both its pivots); each
step's program keeps the ends that turn within half their limit of it within their limits (an
end already beyond its limit at the start, no further beyond), and a step whose equilibrium
turns a rod past that is not kept.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.optimize import linprog

from optimize.net.deriv import evaluate, gauge_rows, hessian
from optimize.net.model import Net, NetState, cross
from optimize.net.newton import RHO, newton_matrix, pd_factor

__all__ = ["ACTIVE", "NetFit", "Swing", "equilibrium_derivatives", "fit_distances", "net_fit", "refine_masses",
           "swing_angles"]

#: Points whose distance is at least this share of the largest enter each step's program (the
#: others are checked by the solver like every point: a step that raises one past the largest
#: is not kept).
ACTIVE = 0.5
#: The trust region's first box (a share of each mass's bound width) and the smallest tried.
RHO_START = 0.25
RHO_LEAST = 1e-4


@dataclass(frozen=True)
class Swing:
    """How far each rod may turn in the socket at each of its ends.

    Attributes:
        pivots: (m, 2, 3) each rod end's pivot from its node point, in the node body's frame
            (its direction is the socket's axis).
        limits: (m, 2) the largest turn of the rod from that axis (rad); inf: no limit (a
            point node's end).
    """

    pivots: np.ndarray
    limits: np.ndarray


def swing_angles(res, swing: Swing, edges: np.ndarray) -> np.ndarray:
    """(m, 2) each rod's turn from its sockets' axes at the equilibrium ``res`` (rad): the angle
    between the socket's axis (its pivot's direction, turned with its body) and the rod's
    direction from that pivot to the other."""
    out = np.zeros(swing.limits.shape)
    for k in (0, 1):
        axis = np.einsum("mab,mb->ma", res.rotations[edges[:, k]], swing.pivots[:, k])
        axis /= np.maximum(np.linalg.norm(axis, axis=1, keepdims=True), 1e-300)
        rod = res.ends[:, 1 - k] - res.ends[:, k]
        rod /= np.linalg.norm(rod, axis=1, keepdims=True)
        out[:, k] = np.arccos(np.clip(np.sum(axis * rod, axis=1), -1.0, 1.0))
    return out


def _swing_gradient(res, swing: Swing, edges: np.ndarray, derivs, ends: np.ndarray) -> np.ndarray:
    """(len(ends), m) d(turn) / d(masses) of the rod ends ``ends`` ((q, 2): rod, end): the socket's
    axis turns with its body (``dw x axis``), the rod's direction with its two pivots."""
    dw = derivs[1]
    rod, end = ends[:, 0], ends[:, 1]
    node, other = edges[rod, end], edges[rod, 1 - end]
    axis = np.einsum("qab,qb->qa", res.rotations[node], swing.pivots[rod, end])
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    p0, p1 = res.ends[rod, end], res.ends[rod, 1 - end]
    d = p1 - p0
    length = np.linalg.norm(d, axis=1)
    u = d / length[:, None]
    du = _moved(res, derivs, other, p1) - _moved(res, derivs, node, p0)
    du = (du - u[:, :, None] * np.einsum("qc,qcm->qm", u, du)[:, None, :]) / length[:, None, None]
    da = np.cross(dw[node], axis[:, :, None], axisa=1, axisb=1, axisc=1)
    dcos = np.einsum("qc,qcm->qm", u, da) + np.einsum("qc,qcm->qm", axis, du)
    cos = np.clip(np.sum(axis * u, axis=1), -1.0, 1.0)
    return -dcos / np.maximum(np.sqrt(1.0 - cos ** 2), 1e-12)[:, None]


@dataclass(frozen=True)
class NetFit:
    """What a net's fit measures: node ``nodes[i]`` against ``points[i]``, and each rod's pivots
    against ``ends`` (None: the nodes only, e.g. point nodes, whose pivots are the node points).

    Attributes:
        nodes: (k,) node indices (a node may appear more than once, e.g. a hub merged from
            several drawn nodes, measured against each).
        points: (k, 3) where each is measured against (mm).
        ends: (m, 2, 3) each rod's pivots at the target (mm), or None.
    """

    nodes: np.ndarray
    points: np.ndarray
    ends: np.ndarray | None = None


def net_fit(target_positions, edges, pivots=None, rotations=None, fit_nodes=None, fit_points=None,
            fit_ends=None) -> NetFit:
    """The fit of a design call's arguments: ``fit_nodes`` against ``fit_points`` (default:
    every node against its target point) and the pivots against ``fit_ends`` (default: where
    ``pivots`` put them at the target, turned by ``rotations``; none for point nodes)."""
    x = np.asarray(target_positions, float)
    if fit_nodes is None:
        nodes, points = np.arange(x.shape[0]), x
    else:
        nodes, points = np.asarray(fit_nodes, int), np.asarray(fit_points, float)
    ends = fit_ends
    if ends is None and pivots is not None:
        p = np.asarray(pivots, float)
        if np.any(p != 0):
            e = np.asarray(edges, int)
            if rotations is not None:
                R = np.asarray(rotations, float)
                p = np.stack([np.einsum("mab,mb->ma", R[e[:, k]], p[:, k]) for k in (0, 1)], axis=1)
            ends = x[e] + p
    return NetFit(nodes, points, None if ends is None else np.asarray(ends, float))


def fit_distances(res, fit: NetFit) -> np.ndarray:
    """(k [+ 2 m],) each measured point's distance from where it was drawn (mm): the nodes, then
    the rods' pivots (end 0, end 1 of rod 0, ...)."""
    return np.linalg.norm(_offsets(res, fit), axis=1)


def _offsets(res, fit: NetFit) -> np.ndarray:
    """(k [+ 2 m], 3) each measured point less where it was drawn, in :func:`fit_distances`' order."""
    d = [res.positions[fit.nodes] - fit.points]
    if fit.ends is not None:
        d.append((res.ends - fit.ends).reshape(-1, 3))
    return np.concatenate(d)


def _moved(res, derivs, node: np.ndarray, point: np.ndarray) -> np.ndarray:
    """(q, 3, m) d(point) / d(masses) of points ``point`` (q, 3) carried by the bodies of nodes
    ``node``: the node point's derivative and the body's turn times the arm from it."""
    dx, dw = derivs
    arm = point - res.positions[node]
    return dx[node] + np.cross(dw[node], arm[:, :, None], axisa=1, axisb=1, axisc=1)


def equilibrium_derivatives(net: Net, state: NetState, tensions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """d(node points) / d(rod masses) and d(node bodies' turns) / d(rod masses) at a stable
    equilibrium, each (n, 3, m) (mm per g, rad per g; zero at anchored nodes and at point nodes'
    turns). Implicit differentiation of the KKT system ``grad U + J' lam = 0, c = 0``:
    ``[[H, J'], [J, 0]] [dy; dlam] = -[dG/dm; 0]``, solved in its regularised form
    ``(H + rho J'J) dy = -dG/dm`` (the symmetries held, as in the solver).

    Raises:
        FloatingPointError: the equilibrium is not stable (its shape has no derivative).
    """
    ev = evaluate(net, state)
    lam = np.asarray(tensions, float)
    dx = np.zeros((net.n, 3, net.m))
    dw = np.zeros((net.n, 3, net.m))
    if net.nvar == 0:
        return dx, dw
    hess = hessian(net, state, ev, lam)
    gauge = gauge_rows(net, state, ev)
    s_h = max(net.weight, float(np.max(np.abs(lam), initial=0.0))) / net.mean_length
    lu = None
    for rho in (RHO, 1e10):
        lu = pd_factor(newton_matrix(net, hess, ev, gauge, 0.0, rho, s_h))
        if lu is not None:
            break
    if lu is None:
        raise FloatingPointError("the equilibrium is not stable: its shape has no derivative")
    # dG/dm_e: rod e's weight shares per unit mass, at its pivots
    t = net.along / net.lengths
    frac = np.column_stack([1 - t - ev.q, t + ev.q]) * net.g
    GP = np.zeros((net.m, 2, 3))
    GP[:, :, 2] = frac
    local = np.empty((net.m, net.loc.shape[1]))
    if net.per_end == 3:
        local[:] = GP.reshape(net.m, 6)
    else:
        for k in (0, 1):
            local[:, 6 * k:6 * k + 3] = GP[:, k]
            local[:, 6 * k + 3:6 * k + 6] = cross(ev.a[:, k], GP[:, k])
    keep = net.loc >= 0
    cols = np.broadcast_to(np.arange(net.m)[:, None], net.loc.shape)
    G = sp.csc_matrix((local[keep], (net.loc[keep], cols[keep])), shape=(net.nvar, net.m)).toarray()
    dy = -lu.solve(G)
    free = np.flatnonzero(net.pos_idx >= 0)
    dx[free] = dy[net.pos_idx[free][:, None] + np.arange(3)]
    turns = np.flatnonzero(net.rot_idx >= 0)
    dw[turns] = dy[net.rot_idx[turns][:, None] + np.arange(3)]
    return dx, dw


def _fit_jacobian(res, fit: NetFit, edges: np.ndarray, derivs: tuple[np.ndarray, np.ndarray],
                  rows: np.ndarray) -> np.ndarray:
    """(len(rows), 3, m) d(measured point) / d(masses) for the points ``rows`` of
    :func:`fit_distances`' order: a node's its node point's; a pivot's its node point's and its
    body's turn times the arm ``ends - node point``."""
    dx = derivs[0]
    k = fit.nodes.size
    out = np.empty((rows.size, 3, dx.shape[2]))
    on_node = rows < k
    out[on_node] = dx[fit.nodes[rows[on_node]]]
    if np.any(~on_node):
        rod, end = np.divmod(rows[~on_node] - k, 2)
        out[~on_node] = _moved(res, derivs, edges[rod, end], res.ends[rod, end])
    return out


def refine_masses(solve, net_of, masses0, bounds: np.ndarray, fit: NetFit, edges, max_evals: int,
                  callback=None, swing: Swing | None = None) -> tuple[np.ndarray, object, dict]:
    """Masses within ``bounds`` whose equilibrium's largest fit distance is least (see the
    module), from ``masses0``.

    Args:
        solve: masses -> the equilibrium from the target (a ``NetResult``).
        net_of: (result, masses) -> (Net, NetState) at that equilibrium (its derivatives').
        masses0: the start (the statics' best fit).
        bounds: (m, 2) mass bounds.
        fit: what the fit measures.
        edges: (m, 2) the rods' nodes.
        max_evals: solver evaluations at most (the start's included).
        callback: called with a line of text at each evaluation, or None.
        swing: how far the rods may turn in their sockets (None: no limit).

    Returns:
        (the masses, their equilibrium, info: ``fit_error`` (the start's largest distance, mm),
        ``refined_error`` (the result's), ``refine_nfev``, ``refine_improved``).
    """
    lo, hi = bounds[:, 0], bounds[:, 1]
    width = np.maximum(hi - lo, 1e-12 * np.maximum(hi, 1e-300))
    edges = np.asarray(edges, int)
    m = np.clip(np.asarray(masses0, float), lo, hi)
    res = solve(m)
    nfev = 1

    def distances(r):
        if not (r.success and r.stable):
            return None
        return fit_distances(r, fit)

    e = distances(res)
    if e is None:
        return m, res, {"refine_nfev": nfev, "fit_error": np.inf, "refined_error": np.inf, "refine_improved": False}
    first = float(e.max())
    if swing is not None:  # (an end beyond its limit at the start may not turn further)
        cap = np.maximum(swing.limits, swing_angles(res, swing, edges))

    def within(r) -> bool:
        return swing is None or bool(np.all(swing_angles(r, swing, edges) <= cap + 1e-12))

    rho = RHO_START
    derivs = None
    while nfev < max_evals and rho >= RHO_LEAST and e.max() > 0:
        if derivs is None:
            net, state = net_of(res, m)
            try:
                derivs = equilibrium_derivatives(net, state, res.tensions)
            except FloatingPointError:
                break
        rows = np.flatnonzero(e >= ACTIVE * e.max())
        J = _fit_jacobian(res, fit, edges, derivs, rows)
        unit = _offsets(res, fit)[rows] / e[rows][:, None]
        grad = np.einsum("ic,icm->im", unit, J)
        M = m.size
        A_ub, b_ub = np.hstack([grad, -np.ones((rows.size, 1))]), -e[rows]
        if swing is not None:  # (the ends within half their limit of it)
            turn = swing_angles(res, swing, edges)
            near = np.argwhere(np.isfinite(cap) & (turn >= cap - 0.5 * swing.limits))
            if near.size:
                gs = _swing_gradient(res, swing, edges, derivs, near)
                A_ub = np.vstack([A_ub, np.hstack([gs, np.zeros((near.shape[0], 1))])])
                b_ub = np.r_[b_ub, cap[near[:, 0], near[:, 1]] - turn[near[:, 0], near[:, 1]]]
        box = np.column_stack([np.maximum(lo - m, -rho * width), np.minimum(hi - m, rho * width)])
        lp = linprog(np.r_[np.zeros(M), 1.0], A_ub=A_ub, b_ub=b_ub, bounds=[*map(tuple, box), (0.0, None)],
                     method="highs")
        if lp.status != 0:
            break
        step, predicted = lp.x[:M], float(lp.x[-1])
        gain = float(e.max()) - predicted
        if gain <= 1e-6 * e.max():
            break  # (no step within the bounds lowers the largest distance, to first order)
        if callback is not None:
            callback(f"refining the masses through the solver: evaluation {nfev + 1} of at most {max_evals}")
        x = np.clip(m + step, lo, hi)
        trial = solve(x)
        nfev += 1
        et = distances(trial)
        if et is not None and et.max() < e.max() and within(trial):
            ratio = (float(e.max()) - float(et.max())) / gain
            m, res, e, derivs = x, trial, et, None
            rho = min(1.0, 2 * rho) if ratio > 0.75 else (0.5 * rho if ratio < 0.25 else rho)
        else:
            rho *= 0.25
    info = {"refine_nfev": nfev, "fit_error": first, "refined_error": float(e.max()),
            "refine_improved": bool(e.max() < first)}
    return m, res, info
