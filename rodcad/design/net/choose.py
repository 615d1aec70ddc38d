"""Where the planner's joints hang: the choice per net, checked against the physics.

A generated net's joints go on its target surface first (:func:`rodcad.design.net.plan.
plan_net`), where the design's masses can kink the rods to it; a net given by its edges
(explicit nodes, a mesh) has no surface between its nodes, and a joint on a straight edge
cannot hang (:mod:`rodcad.design.net.joints`): its joints go to the funicular sag below the
edge. Where the surface's joints leave the net off its tolerance, the funicular sag is
designed too and the better fit kept. Where two-rod joints still cannot hang within the
tolerance (their edge barely pulls, or the net is too light to kink it), their drawn edges are
planned again as one rod each between hubs of the family made larger, each taking half of what
the edge is longer than the longest rod (:func:`rodcad.design.net.plan.plan_net`'s ``whole``),
where the family's largest hubs reach, and beyond that reach one rigid rod spliced from printed
pieces on dowel pins (:mod:`rodcad.catalog.net.splice`; also where larger hubs would leave
another of their rods too short), round after round (:data:`RETRIES`), the better design kept;
what still cannot hang is refused with the hardware that would hold it. Last, hubs whose rods
turn further than their sockets let them get wider cones (:mod:`rodcad.design.net.cones`), after
the hubs whose sockets' spacing keeps the net from balancing are made larger
(:func:`rodcad.design.net.spacing.grow_tight_hubs`) and hubs of two rods that balance only
upside down lighter (:mod:`rodcad.design.net.inverted`); and rods that the hubs' turned sockets
lengthen or shorten out of the catalog's lengths by a little have their hubs resized to bring
them back (:func:`in_window`). Where the net still misses its tolerance because its hubs, sized
for their rods, weigh too unevenly for the rods' masses to make up, the light ones are made larger
to weigh what the balance asks (:mod:`rodcad.design.net.weights`) and the last steps run again.
Last of all, where no masses balance the net in tension, the rods its hubs hold are let push
(:mod:`rodcad.design.net.pushing`), and where none balance it still, the hubs next to its anchors
are held by rods glued at both ends (:mod:`rodcad.design.net.glued`).
"""

from __future__ import annotations

import functools

import numpy as np

from rodcad.design.net.check import NetCheck, design_net_plan, with_multistart
from rodcad.design.net.check import rank as _rank
from rodcad.design.net.cones import widen_cones
from rodcad.design.net.glued import GLUE_RINGS, glued_plan
from rodcad.design.net.imbalance import hubs_fail
from rodcad.design.net.inverted import lighten_inverted
from rodcad.design.net.joints import SagLimit
from rodcad.design.net.spacing import grow_tight_hubs
from rodcad.design.net.weights import weigh_hubs
from rodcad.design.net.plan import plan_net
from rodcad.design.net.pushing import with_pushing
from rodcad.design.net.target import NetTarget
from rodcad.errors import DesignLimit

__all__ = ["RETRIES", "WINDOW_REACH", "WINDOW_ROUNDS", "design_drawn_net", "in_window", "slack_joints", "weak_edges"]

#: Rounds of drawn edges made one rod where their joints cannot hang: each round adds the edges
#: whose joints the last round's design could not hang either, and the rounds stop where none is
#: added (bounded: each round designs the net again). A joint made to hang by another edge's rod
#: may come off it in the next design: drawn meshes took four and five rounds.
RETRIES = 6

#: Rods that leave the catalog's lengths by at most this (mm), with the hubs' sockets turned, are
#: brought back by resizing their hubs (:func:`in_window`; farther is the plan's to say)...
WINDOW_REACH = 2.0
#: ...in this many rounds at most (each designs the net again).
WINDOW_ROUNDS = 2


def design_drawn_net(target: NetTarget, catalog, *, g: float = 9.81, seed: int = 0,
                     tolerance: float | None = None, n_starts: int | None = None, note=None) -> NetCheck:
    """The drawn net planned (:func:`rodcad.design.net.plan.plan_net`) and designed
    (:func:`rodcad.design.net.check.design_net_plan`), its joints where they hang best.

    ``note`` (a progress step's) hears how the design goes.

    Raises:
        DesignLimit: what no hardware in the catalog can do.
    """
    # each way of building the net is solved from its target alone; the multi-start looks for
    # other stable shapes of the one kept (with_multistart: the same as if each had run it)
    design = functools.partial(design_net_plan, g=g, seed=seed, tolerance=tolerance, n_starts=1, note=note)
    check = _pushed(_designed(target, catalog, design, g=g, tolerance=tolerance), design, g)
    check = _glued(check, design, g)
    return with_multistart(check, n_starts, seed=seed, note=note)


def _pushed(check: NetCheck, design, g: float) -> NetCheck:
    """``check``, or where no masses balance its net exactly with every rod in tension, the net
    designed again with the rods its hubs hold let push (:mod:`rodcad.design.net.pushing`),
    where that balances its nodes and hangs better (:func:`rank`). Last, on the plan the steps
    above kept: a design in tension is kept wherever it hangs as well."""
    planned = check.planned
    if planned is None or (check.ok and check.design.statics.exact):
        return check
    pushed = with_pushing(planned, g)
    if pushed.pushing is None:
        return check
    other = design(pushed)
    if _rank(other) <= _rank(check):
        return check
    other.carry(check).chose(f"Designed with every rod in tension the net hung {100 * check.rel_size:.3g} % of its "
                             "size off its target; it was designed again with the rigid rods between its hubs let "
                             "push where they must, each hub they push kept from turning, and hangs nearer.")
    return other


def _glued(check: NetCheck, design, g: float) -> NetCheck:
    """``check``, or where no masses balance its net (its statics are not exact) though its nodes'
    forces balance (what fails is its hubs turning: :func:`rodcad.design.net.imbalance.hubs_fail`),
    the first band of hubs held by rods glued toward the anchors (:mod:`rodcad.design.net.glued`:
    one ring of hubs, then two) with which the net, designed again, passes every check. Each band
    is designed first as planned, and only where neither passes so are they fitted (the steps
    above: hubs resized, cones widened, rods let push) in the same order. Last, on the plan the
    steps above kept."""
    planned = check.planned
    if check.ok or check.design.statics.exact or planned is None or not hubs_fail(planned, g):
        return check
    bands = []
    for rings in range(1, GLUE_RINGS + 1):
        plan = glued_plan(planned, rings)
        if plan is None:
            break
        bands.append((rings, design(plan)))
        if bands[-1][1].ok:
            return _kept_glued(bands[-1][1], rings, check)
    tried = []
    for rings, first in bands:
        other = _pushed(_fallen(_hardware_fitted(first, design, g), design), design, g)
        if other.ok:
            return _kept_glued(other, rings, check)
        tried.append(f"{rings} ring(s) of hubs ({other.plan.target.glued.size}): {other.limit().rstrip('.')}")
    if tried:
        check.notes.append("Held by rods glued at both ends toward the anchors (rodcad.design.net.glued), the net still "
                           "missed: with " + "; with ".join(tried) + ".")
        if check.why:
            check.why += (f" The hubs next to the anchors held by rods glued at both ends (up to {len(tried)} ring(s)) "
                          "did not bring it within the tolerance either (report.md).")
    return check


def _kept_glued(other: NetCheck, rings: int, check: NetCheck) -> NetCheck:
    t = other.plan.target
    other.carry(check).chose(
        f"Hung from its anchors alone the net {check.limit().rstrip('.')}. The {t.glued.size} hub(s) within {rings} "
        f"drawn edge(s) of the anchors are held by gluing the {t.glued_rods.size} rod(s) that join them toward the "
        "anchors into their sockets at both ends (a rigid band that holds each such hub as an anchor does), and the "
        "rest of the net hangs.")
    return other


def _designed(target: NetTarget, catalog, design, *, g: float, tolerance: float | None) -> NetCheck:
    on_surface = target.surface is not None
    try:
        plan = plan_net(target, catalog, tolerance=tolerance, hang=not on_surface, g=g)
        sagged = None
    except SagLimit as exc:  # (the joints' sag leaves rods too short: those edges one rod each)
        plan = _whole_plan(target, catalog, tolerance, g, exc.edges)
        if plan is None:
            raise
        sagged = exc
    check = design(plan)
    if sagged is not None:
        k = plan.rod_pieces
        check.chose(f"The two-rod joints on drawn edge(s) {sorted(sagged.edges)[:8]}, hung at their funicular sag, "
                    f"would leave rods the catalog cannot print ({sagged}); those edges are one rod each"
                    + (f" ({int(np.count_nonzero(k > 1))} of them spliced rigidly from printed pieces on steel dowel "
                       "pins)" if np.any(k > 1) else "") + ", between hubs of the family made larger to take what the "
                    "rod cannot.")
    joints = plan.target.joints
    if joints is None or not len(joints) or check.ok:
        return _fallen(_hardware_fitted(check, design, g), design)
    unsagged = ""  # (why the joints stay on the surface, where their sag's plan does not build)
    if on_surface:
        try:
            other = design(plan_net(target, catalog, tolerance=tolerance, hang=True, g=g))
        except DesignLimit as exc:  # (the surface's plan stands, whatever design is kept: told why)
            other = None
            unsagged = (f"The two-rod joints stay on the target surface: at their funicular sag below their chords "
                        f"the net does not build ({exc}).")
        if other is not None and _rank(other) > _rank(check):
            other.chose("The two-rod joints hang at the funicular sag below their chords: on the target "
                               f"surface the net hung {100 * check.rel_size:.3g} % of its size off it.")
            check = other
    tried: frozenset[int] = frozenset() if sagged is None else sagged.edges  # (those stay one rod each)
    last = check
    for _ in range(RETRIES):  # joints that cannot hang: their edges one rod (between larger hubs, or spliced)
        # (the joints left where the last try's could not hang either: in line with their rods, say)
        weak = frozenset(weak_edges(check)) | frozenset(weak_edges(last)) | tried
        if check.ok or weak == tried:
            break
        tried = weak
        plan = _whole_plan(target, catalog, tolerance, g, weak, hang=not on_surface)
        if plan is None:
            break
        other = last = design(plan)
        if _rank(other) > _rank(check):
            k = plan.rod_pieces
            spliced = (f" ({int(np.count_nonzero(k > 1))} of them, longer than one rod between the family's largest "
                       f"hubs, spliced rigidly from {int(k.max())} printed pieces on steel dowel pins)"
                       if np.any(k > 1) else "")
            # (what kept the try with the joints from hanging: off the tolerance, or on it but unstable)
            other.chose(f"The two-rod joints on drawn edge(s) {sorted(weak)[:8]} could not hang on the target: "
                               f"with them the net {check.limit()}; those edges are one rod each{spliced}, between "
                               "hubs of the family made larger to take what the rod cannot.")
            check = other
    if unsagged:
        check.chose(unsagged)
    check = _hardware_fitted(check, design, g)
    check = _fallen(check, design)
    if not check.ok:
        why = slack_joints(check, None if last is check else last)
        if why:
            check.why = why + (" " + check.why if check.why else "")
            check.notes.append(why)
    return check


def _whole_plan(target: NetTarget, catalog, tolerance: float | None, g: float, whole: frozenset[int],
                hang: bool = True):
    """The net planned with the drawn edges ``whole`` one rod each (:func:`plan_net`'s ``whole``),
    or None where no such plan builds: between larger hubs first; where those leave another rod
    too short, spliced between the hubs their nodes get anyway; nodes moved within the tolerance
    only where neither holds them."""
    for how in ({"spread": False}, {"splice_whole": True, "spread": False}, {"splice_whole": True}):
        try:
            return plan_net(target, catalog, tolerance=tolerance, hang=hang, g=g, whole=whole, **how)
        except DesignLimit:
            continue
    return None


def _fallen(check: NetCheck, design) -> NetCheck:
    """``check``, or where its target is an unstable equilibrium of the designed net that no
    hardware mended, the stable shape the net falls to from it where that is within the
    tolerance (the net hangs there, not on the target); else ``check`` told how far it falls."""
    eq = check.equilibrium
    if check.ok or not eq.success or eq.stable or check.planned is None:
        return check
    fallen = design(check.planned, fall=True)
    low = fallen.equilibrium
    if not (low.success and low.stable):
        return check
    if fallen.ok:
        fallen.carry(check).chose(f"The target is an equilibrium of the designed net, but not a stable one: the net "
                                  f"falls from it to a stable shape {100 * fallen.rel_size:.3g} % of its size off the "
                                  "target, within the tolerance: that shape is the design's.")
        return fallen
    check.falls_to = fallen.rel_size
    return check


def _hardware_fitted(check: NetCheck, design, g: float) -> NetCheck:
    """The last steps of :func:`design_drawn_net`: hubs grown where their sockets' spacing keeps the
    net from balancing, hubs of two rods that balance upside down made lighter, cones widened (or
    hubs grown) where rods turn too far, hubs resized where rods leave the printed lengths; where
    the net still misses, light hubs made heavier (larger) where the hubs' weights keep it from
    balancing, and the steps after the spacing's again. ``design`` designs a plan with the
    design's settings."""
    first = _fitted(grow_tight_hubs(check, design, _rank), design)
    if first.ok:
        return first
    weighed = weigh_hubs(first, design, _rank, g)  # (last: a net the steps above design is kept as they left it)
    if weighed is first:
        return first
    again = _fitted(weighed, design)
    return again if _rank(again) > _rank(first) else first


def _fitted(check: NetCheck, design) -> NetCheck:
    check = lighten_inverted(check, design, _rank)
    return in_window(widen_cones(check, design), design)


def in_window(check: NetCheck, design, rounds: int = WINDOW_ROUNDS) -> NetCheck:
    """``check``, or where its rods, with the hubs' sockets turned, leave the lengths the catalog
    prints by a little (:data:`WINDOW_REACH`), the net designed again with each such rod's end hubs
    resized within the catalog's family by half its excess and as much again (a larger hub
    shortens its rods, a smaller one lengthens them), round after round, the first that builds
    kept (or, if none does, the check itself).

    Args:
        check: a :class:`rodcad.design.net.check.NetCheck` with its ``planned`` plan.
        design: designs a plan (:func:`rodcad.design.net.check.design_net_plan` with the design's settings).
        rounds: rounds at most.
    """
    from rodcad.design.net.plan import resized

    cur = check
    for _ in range(rounds):
        planned = cur.planned
        out = cur.out_of_window
        if (cur.ok or planned is None or not planned.hardware.family or not out.size or not cur.meets_tolerance
                or not cur.in_tension):
            return check
        lo, hi = planned.length_range
        L = cur.plan.piece_lengths
        excess = np.where(L > hi, L - hi, np.where(L < lo, L - lo, 0.0))  # (mm per piece; < 0: short)
        if np.max(np.abs(excess[out])) > WINDOW_REACH:
            return check
        rp = planned.node_pivot.copy()
        plo, phi = planned.hardware.pivot_limits
        t = planned.target
        for e in out:  # (a rod of k pieces: each end hub takes k times half its excess, and as much again)
            for k in t.edges[e]:
                rp[k] = float(np.clip(rp[k] + excess[e] * planned.rod_pieces[e], plo, phi))
        if np.allclose(rp, planned.node_pivot):
            return check
        cur = design(resized(planned, rp))
        if cur.ok:
            cur.carry(check).chose(f"{out.size} rod(s) would have left the {lo:g}-{hi:g} mm the catalog prints once "
                                   "the hubs' sockets were turned to balance them: their hubs were resized within "
                                   "the family to keep them in, and the net designed again.")
            return cur
    return check


def _in_line(t) -> np.ndarray:
    """(n,) the joints whose two rods' node points lie within a degree of one line."""
    out = np.zeros(t.n, dtype=bool)
    for k in t.joints:
        ends = [int(x) for e in np.flatnonzero((t.edges == k).any(axis=1)) for x in t.edges[e] if x != k]
        if len(ends) == 2:
            u, v = t.positions[ends[0]] - t.positions[k], t.positions[ends[1]] - t.positions[k]
            cos = float(u @ v) / float(np.linalg.norm(u) * np.linalg.norm(v))
            out[k] = cos < -np.cos(np.radians(1.0))
    return out


def _weak(check: NetCheck) -> np.ndarray:
    """(m,) the rods on two-rod joints that hang off the tolerance or pull slack (module
    docstring), none where the net has no joints or no equilibrium."""
    from rodcad.design.net.check import SLACK

    t = check.plan.target
    T = check.equilibrium.tensions
    if t.joints is None or not len(t.joints) or not np.all(np.isfinite(T)):
        return np.zeros(t.m, dtype=bool)
    jm = t.joint_mask
    far = jm & (check.node_error > check.tolerance * t.size)  # joints that hang off the tolerance
    if not check.equilibrium.stable:  # joints in line with their rods balance only inverted; where none
        # is, the unstable mode is one of the joints' all the same (a ball between two rods is the net's hinge)
        line = _in_line(t)
        far |= line if line[jm].any() else jm
    return far[t.edges].any(axis=1) | (jm[t.edges].any(axis=1) & (T <= SLACK * float(np.max(np.abs(T), initial=0.0))))


def weak_edges(check: NetCheck) -> list[int]:
    """The drawn edges whose two-rod joints cannot hang on the target within the tolerance."""
    t = check.plan.target
    src = t.source if t.source is not None else np.arange(t.m)
    return sorted({int(x) for x in src[_weak(check)]})


def slack_joints(check: NetCheck, tried: NetCheck | None = None) -> str:
    """Where two-rod joints cannot hang (their rods slack or pushing at the design), in words with
    the hardware that would hold them: a rod as long as the edge, or a rigid in-line splice, and
    how the net hung when the planner ``tried`` them so (the last such design, None: not tried)."""
    plan = check.plan
    t = plan.target
    T = check.equilibrium.tensions
    if t.joints is None or not len(t.joints) or not np.all(np.isfinite(T)):
        return ""
    weak = _weak(check)
    if not weak.any():
        return ""
    share = float(np.max(T[weak])) / float(np.max(np.abs(T), initial=1e-300))
    src = t.source if t.source is not None else np.arange(t.m)
    edges = sorted({int(x) for x in src[weak]})
    d = np.array([_hub_to_hub(t, src, e) for e in edges])
    big = plan.hardware.pivot_limits[1]
    need = float(d.max() - 2 * big)
    why = ("they lie in line with their rods (no kink below their chords: they balance only inverted, an "
           "unstable equilibrium)" if not check.equilibrium.stable else
           f"their rods pull with at most {100 * max(share, 0):.2g} % of the net's largest tension (a slack rung "
           "or diagonal)" if share < 0.1 else
           f"the net is too light to pull them straighter: its tension holds a joint's weight (hub and rods) only "
           f"{float(np.max(check.node_error[t.joint_mask])):.3g} mm below its chord")
    return (f"The two-rod joints on {len(edges)} drawn edge(s) ({edges[:8]}) cannot hang on the target within the "
            f"tolerance ({check.tolerance * t.size:.3g} mm): {why}; a ball joint between two rods carries its weight "
            f"only by a kink below its chord. "
            + (f"A rod of {need:.4g} mm between the family's largest hubs (pivot radius {big:g} mm; the rod family's "
               "length.max)" if need > plan.length_range[1] else
               f"One rod each ({need:.4g} mm between the family's largest hubs, pivot radius {big:g} mm)")
            + " or a rigid in-line splice (node.splice) would hold them"
            + (f"; planned so (one rod each, spliced where longer), the net {tried.limit().rstrip('.')}"
               if tried is not None else "") + ".")


def _hub_to_hub(t: NetTarget, src: np.ndarray, edge: int) -> float:
    """How far apart the hubs at the ends of drawn edge ``edge``'s rods in line are (mm): the
    built net's, where a collapse moved a drawn node into a hub elsewhere; as drawn where its
    rods do not make one line between two hubs."""
    rods = np.flatnonzero(src == edge)
    nodes, counts = np.unique(t.edges[rods], return_counts=True)
    ends = nodes[counts == 1]
    if len(ends) == 2 and not t.joint_mask[ends].any():
        return float(np.linalg.norm(t.positions[ends[1]] - t.positions[ends[0]]))
    drawn = t.drawn if t.drawn is not None else t
    return float(np.linalg.norm(drawn.positions[drawn.edges[edge, 1]] - drawn.positions[drawn.edges[edge, 0]]))
