"""Rods drawn a little too close for the catalog's largest hub, or a little too short between
their hubs, made buildable by moving nodes a little: the planner's last resort.

At a node whose two rods meet at an angle under the largest hub's least angle (its sockets
would not keep their wall, or the rods' bodies would touch), no hub of the family holds them
as drawn; a rod shorter than the shortest printed between the hubs its nodes need is not
printed. Where the angle or the length is short by a little, moving the nodes around by a
small fraction of the net's size fixes it: :func:`spread_tight` finds the least such move
(the sum of the nodes' squared displacements, anchors and the given nodes fixed) that leaves
every two rods at every node it touches at least :data:`MARGIN_DEG` over that least angle
and every such edge as long as it must be, and takes it when no node moves more than the
budget the planner gives (:data:`SPREAD_SHARE` of the design's tolerance x the net's size in
all, :func:`rodcad.design.net.plan.plan_net`). The fit then measures each moved node against
the point drawn for it, so the move counts against the design, never hidden from it. A node
that needs more is left as drawn and refused with the hub that would hold it
(:func:`rodcad.design.net.sizing.size_hubs`).
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.optimize import minimize

from rodcad.catalog.net.node import NodeHardware
from rodcad.design.net.sizing import least_angles
from rodcad.design.net.target import NetTarget

__all__ = ["MARGIN_DEG", "MAX_MOVED", "SPREAD_SHARE", "spread_tight"]

#: Each node may move at most this share of the tolerance x the net's size (the rest of the
#: tolerance is the design's).
SPREAD_SHARE = 0.5

#: Rods are spread to this much over the largest hub's least angle (deg): round-off and the
#: joints' sag after the spread stay clear of the limit.
MARGIN_DEG = 0.05

#: Pairs of rods nearer than this over the limit (deg) are watched while nodes move.
WATCH_DEG = 15.0

#: At most this many nodes are moved at once (the least move is found with finite-difference
#: gradients of the constraints: its time grows with their square); a net with more tight
#: nodes than this is left as drawn (and refused with the hardware that would hold it).
MAX_MOVED = 60


def spread_tight(t: NetTarget, hw: NodeHardware, budget: float, *, fixed: np.ndarray | None = None,
                 least_length: np.ndarray | None = None) -> tuple[NetTarget, np.ndarray]:
    """The target with the nodes around every too-tight node (and at both ends of every
    too-short edge) moved the least that lets the family's largest hub hold its rods and
    every such edge reach its length, where no node moves more than ``budget``.

    Args:
        t: the target (the planner's so far).
        hw: the catalog's node hardware.
        budget: the most any node may move (mm).
        fixed: (n,) nodes that must not move besides the anchors (e.g. the planner's joints,
            whose place their sag sets), or None.
        least_length: (m,) the least node-to-node length of each edge (mm; 0 for none), or
            None: only the angles.

    Returns:
        (target, moved nodes): the target itself and an empty array when nothing needs or
        allows a move; else the nodes moved (their fit against where they were drawn).
    """
    none = np.zeros(0, dtype=np.int64)
    if not hw.is_hub or t.m < 2 or budget <= 0:
        return t, none
    limit = hw.sized(hw.pivot_limits[1]).min_angle_deg
    ang = least_angles(t)
    tight = np.flatnonzero(ang < limit)
    least = np.zeros(t.m) if least_length is None else np.asarray(least_length, dtype=float)
    short = np.flatnonzero(t.edge_lengths < least)
    tight = np.union1d(tight, t.edges[short].ravel()).astype(np.int64)
    if not tight.size:
        return t, none
    want = np.radians(limit + MARGIN_DEG)
    pos0, edges = t.positions, t.edges
    stay = np.zeros(t.n, dtype=bool)
    stay[t.anchored] = True
    if fixed is not None:
        stay |= np.asarray(fixed, dtype=bool)
    nbrs: list[set[int]] = [set() for _ in range(t.n)]
    for i, j in edges:
        nbrs[int(i)].add(int(j))
        nbrs[int(j)].add(int(i))
    near = set(tight.tolist())
    for k in tight:
        near |= nbrs[int(k)]
    free = np.array(sorted(k for k in near if not stay[k]), dtype=np.int64)
    if not free.size or free.size > MAX_MOVED:
        return t, none
    watch = set(free.tolist())
    for k in free:
        watch |= nbrs[int(k)]
    # every pair of rods at a watched node that a small move could bring under the limit
    pairs = []
    for q in sorted(watch):
        others = sorted(nbrs[q])
        for a in range(len(others)):
            for b in range(a + 1, len(others)):
                i, j = others[a], others[b]
                u, v = pos0[i] - pos0[q], pos0[j] - pos0[q]
                cos = u @ v / (np.linalg.norm(u) * np.linalg.norm(v))
                if np.degrees(np.arccos(np.clip(cos, -1, 1))) < limit + WATCH_DEG:
                    pairs.append((q, i, j))
    P = np.array(pairs, dtype=np.int64).reshape(-1, 3)
    scale = float(np.median(t.edge_lengths))
    cos_want = np.cos(want)

    def place(x: np.ndarray) -> np.ndarray:
        pos = pos0.copy()
        pos[free] += x.reshape(-1, 3) * scale
        return pos

    E = t.edges[short]

    def margins(x: np.ndarray) -> np.ndarray:
        pos = place(x)
        u, v = pos[P[:, 1]] - pos[P[:, 0]], pos[P[:, 2]] - pos[P[:, 0]]
        cos = np.sum(u * v, axis=1) / (np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1))
        # >= 0: the pair at least ``want`` apart; each short edge as long as it must be
        reach = (np.linalg.norm(pos[E[:, 1]] - pos[E[:, 0]], axis=1) - least[short]) / scale
        return np.concatenate([cos_want - cos, reach])

    x0 = np.zeros(3 * free.size)
    res = minimize(lambda x: float(x @ x), x0, jac=lambda x: 2 * x, method="SLSQP",
                   constraints=[{"type": "ineq", "fun": margins}], options={"maxiter": 200, "ftol": 1e-14})
    x = res.x
    if not np.all(np.isfinite(x)) or np.min(margins(x)) < -1e-9:
        return t, none
    move = np.linalg.norm(x.reshape(-1, 3), axis=1) * scale
    if move.max() > budget:
        return t, none
    pos = place(x)
    out = dataclasses.replace(t, positions=pos, drawn=t if t.drawn is None else t.drawn)
    moved = free[move > 1e-9 * scale]
    if t.fit_nodes is None:  # every node against where it was drawn
        out = dataclasses.replace(out, fit_nodes=np.arange(t.n), fit_points=pos0.copy())
    return out, moved
