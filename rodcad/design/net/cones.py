"""Socket cones chosen per hub: a hub whose rods turn further than its sockets let them gets
wider cones, within the catalog's ``node.cone_deg`` range.

A hub's sockets open outward in a cone (:mod:`rodcad.catalog.net.node`); a rod turns in its
socket until its neck touches the cone. The hubs' sockets are turned so that every hub balances
at the target (:mod:`rodcad.design.net.hubs`), so the rods meet them a little off their axes,
and where the net's rods meet a hub at awkward angles, by more than the nominal cone lets them.
Such a hub is printed with wider cones: the widest the catalog's range and its neighbours'
openings, which must leave each socket's lip whole, allow
(:meth:`rodcad.catalog.net.node.NodeHardware.widest_cone`). That is what the design's refinement
keeps the rods' turns within (:func:`widest_swing_limits`): widened only as far as its rods
turned (and a degree), a hub made lighter by the wider cone let the net designed again turn them
further still, round after round (a strip with diagonals went 55 -> 61.9 -> 63.1 deg and never
held them).
A wider cone takes plastic out of the hub, so the hub is lighter and its centre of mass moves:
the net is designed again with the new hubs, round after round (:data:`CONE_ROUNDS`) while
some rod still turns too far, each round widening from the last. Where no cone of the catalog
builds (or it has one), the hubs whose rods turn too far are made larger within the family
instead (:func:`rodcad.design.net.spacing.grown_hubs`): a larger hub balances with its sockets
turned less, so its rods meet them nearer their axes; where they still turn further than its
sockets let them, but less far, the larger hub's cones are widened too (it has room for wider
ones between its sockets).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from rodcad.catalog.net.bend import bent_swing_deg
from rodcad.design.net.plan import NetPlan, replan

__all__ = ["CONE_ROUNDS", "widen_cones", "widest_swing_limits"]

#: Rounds of cones widened and the net designed again (each round designs the net once).
CONE_ROUNDS = 3


def widest_swing_limits(plan: NetPlan) -> np.ndarray:
    """(m, 2) how far each rod of ``plan`` could turn in the socket at each of its ends with its
    hub's widest cone (deg): the widest of the catalog's range that leaves every socket's lip
    whole (:meth:`~rodcad.catalog.net.node.NodeHardware.widest_cone`, the most :func:`widen_cones`
    may widen it to), less where a bent rod's end face comes nearer; the plan's own
    (:attr:`~rodcad.design.net.plan.NetPlan.end_swing_limits`) where the catalog has one cone.
    What the design's refinement keeps the rods' turns within: a turn beyond the planned cone
    is this module's to widen it for."""
    out = plan.end_swing_limits
    hw = plan.hardware
    if not hw.is_hub or hw.cone_limits[1] <= hw.cone_deg:
        return out
    arcs = plan.arcs
    for k, at in enumerate(plan.target.node_ends()):
        if not at:
            continue
        hub = plan.hub(k)
        wide = hub.widest_cone(_socket_axes(plan, at))
        if wide <= hub.cone_deg:
            continue
        hub = hub.coned(wide)
        swing = hub.swing_deg
        for e, c in at:
            a = arcs[e]
            out[e, c] = max(out[e, c], swing if a is None else min(swing, bent_swing_deg(hub, a)))
    return out


def _socket_axes(plan: NetPlan, at) -> np.ndarray:
    """(k, 3) the unit axes of a hub's sockets, its rod ends ``at`` ((rod, end) pairs)."""
    dirs = np.array([plan.pivots[e, c] for e, c in at], float).reshape(-1, 3)
    return dirs / np.maximum(np.linalg.norm(dirs, axis=1, keepdims=True), 1e-12)


def _swing_only(check) -> bool:
    """The design fails on nothing but rods turning too far in their sockets."""
    return (check.meets_tolerance and check.in_tension and not check.out_of_window.size
            and bool(check.over_swing.size))


def _excess(check) -> float:
    """How much further than its socket lets it the worst rod end turns (deg; 0 if none)."""
    over = check.over_swing
    if not over.size:
        return 0.0
    e, c = over[:, 0], over[:, 1]
    return float(np.max(check.swing_deg[e, c] - check.plan.end_swing_limits[e, c]))


def _needed_cones(check, planned: NetPlan) -> np.ndarray | None:
    """(n,) each hub's cone for the next round (deg), None where no hub's changes."""
    plan = check.plan
    t = plan.target
    cones = (planned.node_cone.copy() if planned.node_cone is not None
             else np.full(t.n, planned.hardware.cone_deg, float))
    need = np.zeros(t.n, bool)  # (hubs whose rods turn too far for their cones)
    limits = plan.end_swing_limits
    for e, c in check.over_swing:
        k = int(t.edges[e, c])
        if limits[e, c] < plan.hub(k).swing_deg - 1e-9:  # (a bent rod's end face limits it, not the cone)
            continue
        need[k] = True
    new = cones.copy()
    ends = t.node_ends()
    for k in np.flatnonzero(need):
        new[k] = max(cones[k], planned.hub(int(k)).widest_cone(_socket_axes(plan, ends[k])))
    return new if np.any(new > cones + 1e-9) else None


def _grown_for_swing(check, design: Callable[[NetPlan], object]):
    """The design with the hubs whose rods turn too far made larger within the catalog's family
    (:func:`rodcad.design.net.spacing.grown_hubs`; their cones as planned, then widened where the
    rods turn less far but still too far), where that builds: a larger hub balances with its
    sockets turned less, so its rods meet them nearer their axes. None where the family has one
    size or that design does not build either."""
    from rodcad.design.net.plan import resized
    from rodcad.design.net.spacing import grown_hubs

    planned = check.planned
    if not _swing_only(check) or not planned.hardware.family:
        return None
    hubs = np.unique(check.plan.target.edges[check.over_swing[:, 0], check.over_swing[:, 1]])
    grown = grown_hubs(planned, hubs)
    if grown is None:
        return None
    cur = design(resized(planned, grown))
    if not cur.ok and _swing_only(cur) and _excess(cur) < _excess(check):
        cur = widen_cones(cur, design, grow=False)  # (nearer: the larger hubs' cones widened too)
    if not cur.ok:
        return None
    cur.carry(check).chose(f"{hubs.size} hub(s) are larger than their rods' angles need: a larger hub balances with "
                           "its sockets turned less, so its rods meet them nearer their axes (the catalog's cones "
                           "let them turn no further).")
    return cur


def widen_cones(check, design: Callable[[NetPlan], object], rounds: int = CONE_ROUNDS, grow: bool = True):
    """The design with wider socket cones at the hubs whose rods turn too far (module
    docstring); where no cone of the catalog lets them (or it has one), with those hubs larger
    within the family (:func:`_grown_for_swing`); else ``check`` itself where the design fails
    on anything else, or the try that came closest.

    Args:
        check: a :class:`rodcad.design.net.check.NetCheck` with its ``planned`` plan.
        design: designs a plan (:func:`rodcad.design.net.check.design_net_plan` with the
            design's settings).
        rounds: rounds at most.
        grow: where no cone lets them, try the hubs larger (False: cones only).
    """
    planned = check.planned
    if planned is None or not planned.hardware.is_hub:
        return check
    if planned.hardware.cone_limits[1] <= planned.hardware.cone_deg:  # (one cone: larger hubs, if any)
        return (_grown_for_swing(check, design) if grow else None) or check
    best, cur = check, check
    for _ in range(rounds):
        if not _swing_only(cur):
            break
        cones = _needed_cones(cur, planned)
        if cones is None:
            break
        planned = replan(dataclasses.replace(planned, node_cone=cones), planned.pivots)
        cur = design(planned)
        if cur.ok:
            best = cur
            break
        if _swing_only(cur) and _excess(cur) < _excess(best):
            best = cur
    if not best.ok and grow:
        grown = _grown_for_swing(check, design)
        if grown is not None:
            return grown
    if best is check:
        return check
    best.carry(check)
    if best.ok:
        cones = best.plan.node_cone
        nominal = best.plan.hardware.cone_deg
        wide = int(np.count_nonzero(cones > nominal + 1e-9))
        best.chose(f"{wide} hub(s) have their sockets' cones opened wider than the catalog's nominal "
                   f"{nominal:g} deg (up to {float(cones.max()):.3g} deg, within its node.cone_deg range), so that "
                   f"their rods turn as the design hangs them (at most {float(best.swing_deg.max()):.3g} deg); a "
                   "wider cone lightens its hub, and the net was designed again with it.")
    return best
