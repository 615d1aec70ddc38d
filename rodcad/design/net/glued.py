"""A band of hubs held by rods glued rigid toward the anchors, where the net cannot hang there.

Not every drawn net hangs from the nodes it is anchored at. A bowl hung from its widest ring
(an icosphere's lower half anchored at its equator) has its surface vertical at the rim: there
the hoops push as hard as the meridians pull (:mod:`rodcad.design.net.pushing`), and a hub
pushed about as hard as it is pulled turns freely on its ball sockets. No masses hang it there;
anchors below the rim would hold it. Rods glued into their sockets at both ends hold a hub as
an anchor does: a glued rod from a hub held rigidly is a rigid arm, and the hub at its far end,
glued to it, is held, position and orientation.

So, last, where no masses balance the net the planner kept though its nodes' forces balance with
the held rods pushing (what fails is its hubs turning: :func:`rodcad.design.net.imbalance.
hubs_fail`; glue holds hubs, it does not stand in for the anchors a shape needs), the hubs within
one ring of the anchors (rods counted per drawn edge), then two, are held by gluing the rods that
join each of them toward the anchors (:func:`glued_plan`), and the net designed again; the first that hangs
within its tolerance, every check passing, is kept (:func:`rodcad.design.net.choose.
design_drawn_net`). The band stays a small part of the net (:data:`GLUE_SHARE`): the rest
hangs, its shape the design's. The glued hubs are not hung on the frame; the report and
design.json name them and their glued rods, and the assembly glues them first.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

__all__ = ["GLUE_RINGS", "GLUE_SHARE", "glued_plan", "rings_from_anchors"]

#: Rings of hubs below the anchors held by glued rods, at most (each designs the net again).
GLUE_RINGS = 2
#: The glued hubs are at most this share of the free nodes, so that most of the net hangs: a net
#: held mostly by glue would be a rigid sculpture, not a hanging net.
GLUE_SHARE = 1 / 2


def rings_from_anchors(t) -> np.ndarray:
    """(n,) each node's distance from the nearest anchor in drawn edges: a rod counts as its
    share of the drawn edge it lies on (the planner's two-rod joints halve an edge), so the
    first ring is the drawn nodes one edge from the anchors and the joints before them."""
    src = np.arange(t.m) if t.source is None else np.asarray(t.source)
    share = 1.0 / np.bincount(src, minlength=int(src.max()) + 1)[src]
    a, b = np.sort(t.edges, axis=1).T
    order = np.lexsort((share, b, a))  # (two rods between the same nodes: the shorter step, not the sum)
    first = np.ones(order.size, dtype=bool)
    first[1:] = (np.diff(a[order]) != 0) | (np.diff(b[order]) != 0)
    keep = order[first]
    graph = sp.csr_matrix((share[keep], (a[keep], b[keep])), shape=(t.n, t.n))
    return np.asarray(dijkstra(graph, directed=False, indices=t.anchored, min_only=True))


def glued_plan(plan, rings: int):
    """``plan`` with the free nodes within ``rings`` drawn edges of its anchors held by glued
    rods (:attr:`rodcad.design.net.target.NetTarget.glued`): each glued rod joins a glued node
    to one nearer the anchors, so every glued node hangs on a rigid arm of them; None where no
    free node is that near, every free node would be, or the band would be more than
    :data:`GLUE_SHARE` of the free nodes."""
    t = plan.target
    d = rings_from_anchors(t)
    free = ~t.anchored_mask
    glue = free & (d <= rings + 1e-9)
    if not glue.any() or glue.sum() > GLUE_SHARE * free.sum() or glue.sum() == free.sum():
        return None
    i, j = t.edges[:, 0], t.edges[:, 1]
    toward = (glue[i] & (d[j] < d[i] - 1e-9)) | (glue[j] & (d[i] < d[j] - 1e-9))
    held = t.anchored_mask | glue
    target = dataclasses.replace(t, anchored=np.flatnonzero(held), glued=np.flatnonzero(glue),
                                 glued_rods=np.flatnonzero(toward))
    return dataclasses.replace(plan, target=target, pushing=None)
