"""Hubs of two rods that balance only upside down, made lighter within the family.

A hub that holds two rods turns freely about the axis through its two pivots (the rods' balls
turn in their sockets), so it hangs stable only with its centre of mass below that axis. Where
the target kinks at a node by less than the hub's weight pulls its two rods' lines apart (a
heavy hub on a gently curving run of rods), the statics balance the hub by turning its sockets
(:func:`rodcad.design.net.hubs.orient_sockets`) until the rods' lines meet below its centre:
the hub then sits on top of its pivots' axis, an equilibrium but not a stable one (it flips
over, and the net hangs elsewhere). A lighter hub of the catalog's family, the smallest, needs
its rods' lines kinked less than the target kinks them: its sockets turn the other way, and it
hangs below its axis (:func:`lighten_inverted`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from rodcad.design.net.plan import resized
from rodcad.errors import DesignLimit

__all__ = ["inverted_hubs", "lighten_inverted"]


def inverted_hubs(check) -> np.ndarray:
    """The free hubs of two rods whose centre of mass lies above the axis through their two
    pivots at the design's equilibrium (node indices; none without an equilibrium or hubs).

    Args:
        check: a :class:`rodcad.design.net.check.NetCheck`.
    """
    plan, eq = check.plan, check.equilibrium
    t = plan.target
    if not eq.success or not plan.hardware.is_hub:
        return np.zeros(0, int)
    ends = t.node_ends()
    out = []
    for k in np.flatnonzero(~t.anchored_mask):
        if len(ends[k]) != 2:
            continue
        R = eq.rotations[k]
        p0, p1 = (R @ plan.pivots[e, c] for e, c in ends[k])
        com = R @ plan.node_com[k]
        u = p1 - p0
        span = float(np.linalg.norm(u))
        if span <= 0:
            continue
        u /= span
        d = (com - p0) - float((com - p0) @ u) * u  # (from the axis to the centre of mass)
        if d[2] > 1e-9 * span:
            out.append(int(k))
    return np.array(out, int)


def lighten_inverted(check, design: Callable, rank: Callable):
    """``check``, or where its equilibrium is not stable and hubs of two rods balance upside
    down (:func:`inverted_hubs`), the net designed again with those hubs the family's smallest,
    if that ranks better (``rank``: :func:`rodcad.design.net.choose._rank`).

    Args:
        check: a :class:`rodcad.design.net.check.NetCheck` with its ``planned`` plan.
        design: designs a plan (:func:`rodcad.design.net.check.design_net_plan` with the design's
            settings).
        rank: orders checks, better higher.
    """
    planned, eq = check.planned, check.equilibrium
    if check.ok or planned is None or planned.node_pivot is None or not eq.success or eq.stable:
        return check
    hubs = inverted_hubs(check)
    smallest = float(planned.hardware.pivot_limits[0])
    hubs = hubs[planned.node_pivot[hubs] > smallest * (1 + 1e-9)]
    if not hubs.size:
        return check
    rp = planned.node_pivot.copy()
    rp[hubs] = smallest
    try:
        cur = design(resized(planned, rp))
    except DesignLimit:  # (their rods, longer between smaller hubs, leave the lengths the catalog prints)
        return check
    if rank(cur) <= rank(check):
        return check
    cur.carry(check).chose(
        f"{hubs.size} hub(s) of two rods (nodes {hubs[:8].tolist()}) balanced only upside down: the target kinks "
        "there by less than their weight pulls their rods' lines apart, so their sockets were turned until the "
        "lines met below the hub's centre, which then sat above the axis through its two sockets (a hub turns "
        f"freely about it). They are the family's smallest (pivot radius {smallest:g} mm), lighter, and hang below "
        "that axis.")
    return cur
