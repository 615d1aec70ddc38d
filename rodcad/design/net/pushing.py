"""Rods that push where the hardware holds them, where no masses balance the net in tension.

A net designed with every rod in tension hangs like a cloth. Not every drawn shape can: a bowl
hung from its rim (an icosphere's lower half anchored at its equator) carries its weight by
meridians in tension and, below the rim, by hoops in compression, as a membrane does (where
gravity runs along the surface its hoop force equals minus its meridional one). With
``net.compression`` unset the hardware decides: a rigid rod between two hubs (one printed
piece, or pieces spliced on dowel pins) is held by its ball sockets either way and may push, a
rod at a ball joint between two rods (a planner's joint, or a drawn node of two rods) may not
(two pushing rods fold there), and point nodes hold none.

The planner designs every net with its rods in tension; last, where the net it keeps does not
balance exactly so, and its nodes' forces balance only with the held rods pushing
(:func:`with_pushing`), the net is designed again with them let push and kept where it hangs
better (:func:`rodcad.design.net.choose.design_drawn_net`). The check then judges each pushing
rod against its buckling load, and the net's stability (the exact equilibrium's curvatures;
:attr:`rodcad.design.net.check.NetCheck.unheld`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["held_rods", "with_pushing"]


def held_rods(plan) -> np.ndarray:
    """(m,) the rods the hardware holds either way: rigid rods between two hubs, neither end a
    ball joint between two rods (a planner's joint or a free node of two rods); none on point
    nodes."""
    t = plan.target
    if not plan.hardware.is_hub:
        return np.zeros(t.m, dtype=bool)
    degree = np.bincount(t.edges.ravel(), minlength=t.n)
    hinge = t.joint_mask | (~t.anchored_mask & (degree <= 2))
    return ~hinge[t.edges].any(axis=1)


def with_pushing(plan, g: float = 9.81):
    """``plan`` with :attr:`~rodcad.design.net.plan.NetPlan.pushing` set to the rods the hardware
    holds (:func:`held_rods`) where no masses balance its nodes' forces with every rod in tension
    but some do with those rods pushing; ``plan`` unchanged where the target says
    (``compression`` true or false), on point nodes, and where tension balances or pushing does
    not help. The hubs' moments are left aside (their sockets are turned for them afterwards)."""
    t = plan.target
    if t.compression is not None or not plan.hardware.is_hub:
        return plan
    held = held_rods(plan)
    if not held.any():
        return dataclasses.replace(plan, pushing=None)

    def forces(push) -> bool:
        return plan.mass_design(g, allow_compression=push, forces_only=True, explain=False).exact

    if forces(False) or not forces(held):
        return dataclasses.replace(plan, pushing=None)
    return dataclasses.replace(plan, pushing=held)
