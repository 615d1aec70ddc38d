"""Why no masses balance a net's target, in words: the nodes whose rods cannot hold them, or the
hubs that no turn of their sockets balances (:func:`imbalance`, for the design's notes and its
exit line)."""

from __future__ import annotations

import numpy as np

from optimize import NetDesign, net_statics
from rodcad.design.net.plan import NetPlan, replan
from rodcad.design.net.pushing import held_rods

__all__ = ["hubs_fail", "imbalance"]


def imbalance(plan: NetPlan, design: NetDesign, g: float, lines: np.ndarray) -> str:
    """Where the statics' best fit leaves the largest imbalance, when no masses at all (any
    positive mass, rods pushing or not) balance the target; with hubs whose rods' pulls, their
    sockets on the lines between the node points (``lines``), can hold every node, what fails
    is the hubs' balance about their centres, and the text says so."""
    t = plan.target
    st = net_statics(t.positions, t.edges, plan.lengths, t.anchored, node_masses=plan.node_masses,
                     node_com=plan.node_com, pivots=plan.pivots, com=plan.statics_com, g=g)
    res = np.abs(st.residual(design.statics.tensions, design.statics.masses))
    force = st.rows[:, 1] < 3
    if plan.hardware.is_hub and _forces_balance(replan(plan, lines), g):
        # the rods' pulls can hold every node: what fails is every hub balancing about its centre
        worst = _worst(st.rows[~force, 0], res[~force], t.n)
        return (f"No masses balance this target with the hubs' sockets as turned: the rods' pulls can hold every "
                f"node, but no turn of the sockets was found that lets every hub balance about its centre as well "
                f"within the rods' mass ranges (the largest moment imbalance is at node(s) {worst}). A target "
                "nearer the shape such hubs hang in, or point nodes (the catalog's node kind: point), would "
                "reach it.")
    worst = _worst(st.rows[force, 0], res[force], t.n)
    text = (f"No masses at all balance this target: some nodes' rods cannot pull them in every direction the "
            f"load needs (the largest imbalance is at node(s) {worst}).")
    if t.kind == "surface" and t.anchored_as in ("corners", "ends"):
        text += (" A grid drawn over a rectangle and hung from its corners cannot hang in it: its straight border "
                 "has nothing to pull it outward (a hanging net's border curves inward in plan); anchor the "
                 "border (anchored: boundary), or give a target whose border curves.")
    elif _pushing_would(plan, g):
        text += (" The rods the hubs hold could hold them by pushing, but a hub its rods push about as hard as "
                 "the others pull it turns on its ball sockets (below the rim of a bowl hung from its widest ring "
                 "the hoops push as hard as the meridians pull): anchors there (a ring of anchored nodes below the "
                 "rim), or the net hung from above its widest part, would hold it.")
    else:
        text += " Move those nodes toward where their rods and the weights can hold them, or anchor them."
    return text


def _pushing_would(plan: NetPlan, g: float) -> bool:
    """Whether the rods the hubs hold (:func:`rodcad.design.net.pushing.held_rods`), let push as
    hard as it takes with their hubs' turning left aside, balance the nodes' forces where the
    design kept them in tension (``compression`` unset)."""
    if plan.target.compression is not None or plan.pushing is not None or not held_rods(plan).any():
        return False
    return hubs_fail(plan, g)


def hubs_fail(plan: NetPlan, g: float) -> bool:
    """Whether the nodes' forces balance at the target with the rods the hardware lets push
    (those the hubs hold, :func:`rodcad.design.net.pushing.held_rods`, where ``compression`` is
    unset), the hubs' turning left aside: where no masses balance such a net, what fails is its
    hubs turning on their ball sockets, not its shape (:mod:`rodcad.design.net.glued`)."""
    t = plan.target
    push = held_rods(plan) if t.compression is None else bool(t.compression)
    return plan.hardware.is_hub and _forces_balance(plan, g, push=push, stiff_hubs=False)


def _worst(nodes: np.ndarray, res: np.ndarray, n: int) -> list[int]:
    """Up to 8 nodes with the largest residual, largest first."""
    per_node = np.zeros(n)
    np.maximum.at(per_node, nodes, res)
    order = np.argsort(-per_node, kind="stable")[:8]
    return [int(k) for k in order if per_node[k] > 1e-6 * max(per_node.max(), 1e-300)]


def _forces_balance(plan: NetPlan, g: float, push=None, stiff_hubs: bool = True) -> bool:
    """Whether some positive masses (within the bounds or beyond them), every rod in tension but
    those that may push (``push``: a mask, or None: the plan's :attr:`~rodcad.design.net.plan.
    NetPlan.may_push`), balance the nodes' forces at the target, leaving the hubs' moments aside
    (and, ``stiff_hubs`` False, how a pushed hub turns: :func:`optimize.design_net_masses`)."""
    fo = plan.mass_design(g, allow_compression=plan.may_push if push is None else push, forces_only=True,
                          stiff_hubs=stiff_hubs)
    return bool(fo.exact or (np.all(np.isfinite(fo.beyond)) and fo.needs_compression.size == 0))
