"""Sockets kept apart: the turns that balance a hub leave ``min_wall`` between its sockets.

A hub's sockets are planned on the lines between the node points, at least
:attr:`rodcad.catalog.net.node.NodeHardware.socket_angle_deg` apart (the hub is sized for it,
:mod:`rodcad.design.net.sizing`). Turning them to balance the hub (:mod:`rodcad.design.net.hubs`)
may bring two of them closer: the wall between them thins, and a few degrees more and the two
sockets run into each other, a hub no ball stays in. :func:`spaced_turn` finds a hub's least turn
that cancels its moments with every pair of sockets kept that far apart (SLSQP on the hub's own
few unknowns, where the least turn without that bound is too close); :func:`socket_clashes` names
the hubs whose sockets are closer all the same, which the design's check refuses. Where the
spacing keeps a net from balancing, the hubs it holds are made larger within the catalog's family
(:func:`grow_tight_hubs`): a larger hub's sockets are further apart in degrees for the same wall, and
each turns less for the same moment (its arm is longer).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize

from rodcad.catalog.net.node import least_angle_deg

__all__ = ["GROW", "GROW_ROUNDS", "SPACING_TOL", "TIGHT_DEG", "grow_tight_hubs", "grown_hubs", "socket_clashes",
           "spaced_turn", "tight_hubs", "too_close"]

#: Sockets this much closer than their least angle (deg) are still apart: round-off of the turns.
SPACING_TOL = 1e-6

#: A hub whose turned sockets come within this of their least angle (deg) is held by the spacing.
TIGHT_DEG = 0.5
#: Such a hub of a net that does not balance grows this much (its pivot radius, within the family)...
GROW = 1.3
#: ...round after round, at most this many (each designs the net again).
GROW_ROUNDS = 2


def too_close(a: np.ndarray, need_deg: float) -> bool:
    """Whether any two of the sockets along ``a`` ((k, 3), from the hub's centre) are closer
    than ``need_deg`` (deg, less :data:`SPACING_TOL`)."""
    return least_angle_deg(a) < need_deg - SPACING_TOL


def spaced_turn(axis: np.ndarray, f: np.ndarray, cw: np.ndarray, rad: float, need_deg: float,
                start: np.ndarray | None = None) -> np.ndarray:
    """A hub's sockets turned from ``axis`` as little as they can be (least squares of the
    change) so that the moments about its centre vanish, on the sphere of radius ``rad``, every
    two of them at least ``need_deg`` apart.

    Args:
        axis: (k, 3) the sockets where they are planned (the lines, ``rad`` long), far enough apart.
        f: (k, 3) the force each rod exerts at its socket.
        cw: (3,) the moment of the hub's own weight about its centre.
        rad: the hub's pivot radius (mm).
        need_deg: the least angle between two sockets (deg).
        start: (k, 3) where to start (default ``axis``).

    Returns:
        (k, 3) the sockets; where no turn within the spacing cancels the moments, the nearest
        to it that keeps the spacing (SLSQP's last point if it keeps it, else ``axis``).
    """
    axis = np.asarray(axis, float)
    k = axis.shape[0]
    f = np.asarray(f, float)
    fs = float(np.linalg.norm(f, axis=1).max()) * rad or 1.0
    A = np.hstack([-_skew(fq) for fq in f]) / fs  # moments: cw + A a (scaled)
    c = np.cos(np.radians(need_deg)) * rad * rad
    pairs = np.array([(i, j) for i in range(k) for j in range(i + 1, k)], int).reshape(-1, 2)

    def obj(x):
        d = x - axis.ravel()
        return float(d @ d) / rad ** 2, 2 * d / rad ** 2

    def moment(x):
        return cw / fs + A @ x

    def sphere(x):
        a = x.reshape(k, 3)
        return (np.sum(a * a, axis=1) - rad * rad) / rad ** 2

    def sphere_jac(x):
        a = x.reshape(k, 3)
        J = np.zeros((k, 3 * k))
        for i in range(k):
            J[i, 3 * i:3 * i + 3] = 2 * a[i] / rad ** 2
        return J

    def apart(x):
        a = x.reshape(k, 3)
        return (c - np.sum(a[pairs[:, 0]] * a[pairs[:, 1]], axis=1)) / rad ** 2

    def apart_jac(x):
        a = x.reshape(k, 3)
        J = np.zeros((len(pairs), 3 * k))
        for q, (i, j) in enumerate(pairs):
            J[q, 3 * i:3 * i + 3] = -a[j] / rad ** 2
            J[q, 3 * j:3 * j + 3] = -a[i] / rad ** 2
        return J

    x0 = (axis if start is None else np.asarray(start, float)).ravel()
    res = minimize(obj, x0, jac=True, method="SLSQP",
                   constraints=[{"type": "eq", "fun": moment, "jac": lambda x: A},
                                {"type": "eq", "fun": sphere, "jac": sphere_jac},
                                {"type": "ineq", "fun": apart, "jac": apart_jac}],
                   options={"maxiter": 200, "ftol": 1e-15})
    a = res.x.reshape(k, 3)
    a = a * (rad / np.linalg.norm(a, axis=1, keepdims=True))
    return a if not too_close(a, need_deg) else axis


def socket_clashes(plan) -> list[tuple[int, float, float]]:
    """(node, least angle between two of its sockets, the least its walls need) (deg) of every
    hub of ``plan`` whose sockets, as turned, are closer than its walls need."""
    t = plan.target
    if not plan.hardware.is_hub or t.m == 0:
        return []
    out = []
    for k, at in enumerate(t.node_ends()):
        if len(at) < 2:
            continue
        a = np.array([plan.pivots[e, c] for e, c in at], float)
        need = plan.hub(k).socket_angle_deg
        if too_close(a, need):
            out.append((k, least_angle_deg(a), need))
    return out


def tight_hubs(plan) -> np.ndarray:
    """The free hubs of ``plan`` whose turned sockets are within :data:`TIGHT_DEG` of their least angle."""
    t = plan.target
    out = []
    ends = t.node_ends()
    for k in np.flatnonzero(~t.anchored_mask & (plan.degree >= 2)):
        at = ends[k]
        a = np.array([plan.pivots[e, c] for e, c in at], float)
        if least_angle_deg(a) < plan.hub(int(k)).socket_angle_deg + TIGHT_DEG:
            out.append(int(k))
    return np.array(out, int)


def grown_hubs(planned, hubs: np.ndarray) -> np.ndarray | None:
    """(n,) the plan's pivot radii with ``hubs`` made :data:`GROW` times larger within the
    catalog's family, less where a rod would be left shorter than the catalog prints (halved,
    four times, then not grown at all); None where none grows."""
    rp = planned.node_pivot.copy()
    grown = rp.copy()
    grown[hubs] = np.minimum(rp[hubs] * GROW, planned.hardware.pivot_limits[1])
    lo = planned.length_range[0]
    t = planned.target
    for q in range(5):
        short = np.flatnonzero((t.edge_lengths - grown[t.edges].sum(axis=1)) / planned.rod_pieces < lo - 1e-9)
        if not short.size:
            break
        ends = np.unique(t.edges[short])
        grown[ends] = np.maximum(rp[ends], 0.5 * (rp[ends] + grown[ends])) if q < 4 else rp[ends]
    return grown if np.any(grown > rp + 1e-9) else None


def grow_tight_hubs(check, design, rank, rounds: int = GROW_ROUNDS):
    """Where a hub net does not balance (the statics' best fit off the tolerance) and some of its hubs' sockets
    are held apart by the spacing (:func:`tight_hubs`), those hubs made :data:`GROW` times larger
    (within the catalog's family, and no rod left shorter than the catalog prints) and the net designed
    again, round after round; the best by ``rank`` kept.

    Args:
        check: a :class:`rodcad.design.net.check.NetCheck` with its ``planned`` plan.
        design: designs a plan (:func:`rodcad.design.net.check.design_net_plan` with the design's settings).
        rank: orders checks, better greater (:func:`rodcad.design.net.choose`'s).
    """
    from rodcad.design.net.plan import resized

    best, cur = check, check
    for _ in range(rounds):
        planned = cur.planned
        if (planned is None or not planned.hardware.family or cur.ok or cur.meets_tolerance
                or not cur.equilibrium.success):
            break
        tight = tight_hubs(cur.plan)
        grown = grown_hubs(planned, tight) if tight.size else None
        if grown is None:
            break
        cur = design(resized(planned, grown))
        if rank(cur) > rank(best):
            best = cur
    if best is not check:
        n = int(np.count_nonzero(best.plan.node_pivot > check.planned.node_pivot + 1e-9))
        best.carry(check).chose(f"{n} hub(s) are larger than their rods' angles need: their sockets, turned to balance them, "
                          "would otherwise have come closer than their walls allow (a larger hub's sockets are further "
                          "apart, and each turns less).")
    return best


def _skew(a: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
