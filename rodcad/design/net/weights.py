"""Hubs made heavier where the net's node weights keep it from balancing.

A hanging net's shape is set by the loads at its nodes: its rods' weight shares and its hubs'
weights. The planner sizes each hub for its rods (larger where they meet at tight angles), so
a net can come out with a few heavy hubs among light ones; the rods' masses, a few grams wide,
cannot make up a hub's tens, and no masses balance the target. A hub larger than its rods need
weighs more (the family's sizes are one shell, :meth:`rodcad.catalog.net.node.NodeHardware.sized`),
so the light hubs are made larger: :func:`optimize.node_mass_needs` finds the least weight to add
at the free hubs (each up to the largest size its rods leave room for) for masses within their
bounds to balance the nodes' forces, each such hub gets the size that weighs that much more,
and the net is designed again (:func:`weigh_hubs`), round after round (the sizes move the rods'
pivots, lengths and bounds a little). Joints between two rods keep their size: their weight
sets where they sag.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from rodcad.errors import DesignLimit

__all__ = ["WEIGH_ROUNDS", "weigh_hubs", "weighed_pivots"]

#: Rounds of hubs weighed and the net designed again, at most.
WEIGH_ROUNDS = 2

#: A hub grows where the weight it needs is at least this share of its own.
WEIGH_LEAST = 0.01


def _mass(plan, k: int, dirs: np.ndarray, rp: float) -> float:
    return plan.hub(k, rp).hub_mass(dirs)[0]


def _room(plan, spare: np.ndarray) -> np.ndarray:
    """(n,) the largest pivot radius each node's hub may take with its neighbours' as planned,
    within the family: each rod's two pivot radii at most its ``spare`` (node to node, less the
    catalog's shortest rod per piece)."""
    t = plan.target
    rp = plan.node_pivot
    cap = np.full(t.n, float(plan.hardware.pivot_limits[1]))
    for c in (0, 1):
        np.minimum.at(cap, t.edges[:, c], spare - rp[t.edges[:, 1 - c]])
    return np.maximum(cap, rp)


def weighed_pivots(planned, g: float) -> np.ndarray | None:
    """(n,) ``planned``'s pivot radii with its light free hubs larger by what they must weigh for
    the net to balance (:func:`optimize.node_mass_needs`, with the sockets on the lines between
    the node points: the design turns them for the weights it is given), or None where no such
    weights balance it or none is needed.

    Args:
        planned: the plan as given to the design.
        g: gravitational acceleration.
    """
    from optimize import node_mass_needs

    from rodcad.design.net.plan import node_directions

    t = planned.target
    rp = planned.node_pivot
    free = ~t.anchored_mask & ~t.joint_mask & (planned.degree >= 2)
    spare = t.edge_lengths - planned.length_range[0] * planned.rod_pieces
    cap = _room(planned, spare)
    dirs = node_directions(t, planned.pivots)
    extra = np.zeros(t.n)
    for k in np.flatnonzero(free & (cap > rp + 1e-9)):
        extra[k] = max(_mass(planned, int(k), dirs[k], float(cap[k])) - planned.node_masses[k], 0.0)
    if not np.any(extra > 0):
        return None
    need = node_mass_needs(t.positions, t.edges, planned.lengths, planned.bounds, t.anchored, extra,
                           node_masses=planned.node_masses, node_com=planned.node_com, pivots=planned.pivots,
                           com=planned.statics_com, allow_compression=t.any_may_push, g=g, sag=t.joint_mask)
    if need is None:
        return None
    need = need[0]
    grow = np.flatnonzero(need > WEIGH_LEAST * planned.node_masses)
    if not grow.size:
        return None
    out = rp.copy()
    for k in grow:  # the size that weighs that much more (a hub's mass grows with its size)
        want = planned.node_masses[k] + need[k]
        lo, hi = float(rp[k]), float(cap[k])
        for _ in range(40):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if _mass(planned, int(k), dirs[k], mid) < want else (lo, mid)
        out[k] = hi
    # two grown hubs at the ends of one rod: each takes its share of the room between them
    short = (t.edge_lengths - out[t.edges].sum(axis=1)) / planned.rod_pieces < planned.length_range[0] - 1e-9
    for e in np.flatnonzero(short):
        a, b = t.edges[e]
        over = out[a] + out[b] - spare[e]
        ga, gb = out[a] - rp[a], out[b] - rp[b]
        if ga + gb > 0:
            out[a] -= over * ga / (ga + gb)
            out[b] -= over * gb / (ga + gb)
    return out if np.any(out > rp + 1e-9) else None


def weigh_hubs(check, design: Callable, rank: Callable, g: float = 9.81, rounds: int = WEIGH_ROUNDS):
    """``check``, or where no masses balance its hub net (the statics' best fit off the tolerance)
    but heavier light hubs would (:func:`weighed_pivots`), the net designed again with those hubs
    larger, round after round, the best by ``rank`` kept.

    Args:
        check: a :class:`rodcad.design.net.check.NetCheck` with its ``planned`` plan.
        design: designs a plan (:func:`rodcad.design.net.check.design_net_plan` with the design's settings).
        rank: orders checks, better greater (:func:`rodcad.design.net.choose._rank`).
        g: gravitational acceleration.
        rounds: rounds at most.
    """
    from rodcad.design.net.plan import resized

    best, cur = check, check
    for _ in range(rounds):
        planned = cur.planned
        if (planned is None or planned.node_pivot is None or not planned.hardware.family or cur.ok
                or cur.design.statics.exact):
            break
        rp = weighed_pivots(planned, g)
        if rp is None:
            break
        try:
            cur = design(resized(planned, rp))
        except DesignLimit:
            break
        if rank(cur) > rank(best):
            best = cur
    if best is not check:
        grown = np.flatnonzero(best.plan.node_pivot > check.planned.node_pivot + 1e-9)
        best.carry(check).chose(
            f"{grown.size} hub(s) (nodes {grown[:8].tolist()}) are larger than their rods need, to weigh more: the "
            "net's other hubs, sized for their rods' angles, weigh more than the rods' masses can make up, and no "
            f"masses balanced the target (it hung {100 * check.rel_size:.3g} % of its size off it). A hub's weight "
            "is a load that shapes the net, as a rod's is.")
    return best
