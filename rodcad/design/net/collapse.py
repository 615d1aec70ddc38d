"""Short edges collapsed: two nodes too close for any rod between hubs become one hub.

A drawn edge shorter than the shortest rod between the smallest hubs its nodes' angles allow
(:func:`rodcad.design.net.sizing.size_hubs`) cannot be a rod. Of the ways to build it anyway,
the planner collapses the edge, as mesh simplification does: its two nodes become one hub
(:func:`collapse_short`), and the rods they had become that hub's rods (two rods that now
join the same two nodes are one rod: the drawing had a triangle the hub now fills). Why this
and not the others:

* It works for every way a net is drawn (explicit nodes and edges, an OBJ mesh, a generated
  grid or rings and spokes) and changes the drawing only where the hardware cannot follow it:
  every other node stays where it was drawn, and every anchor stays where the user put it
  (a free node merges into its anchor; two anchors are never merged, and an edge between two
  anchors needs no rod at all: the anchors hold both its ends).
* A coarser density of a generated net (fewer cells on the same surface) moves every node
  of the net to fix a few short edges (a radial net's inner ring is short while its outer one
  is not), and does nothing for a net drawn node by node.
* A rigid multi-node hub (one printed part spanning the short edge) keeps both nodes, but
  it carries moments between the rods of its two nodes (a rigid body of six degrees of
  freedom whose balance about the edge's axis is a new equation the sockets' turning must
  meet), and it is a new kind of part to build: not done.

Where the hub is. On what the user drew, so that the fit measures the net against the
drawing: the anchor where the group holds one; on a generated net's surface, the surface
point under the group's centroid; otherwise the point of the group's drawn edges nearest its
centroid (a point of the drawn edges lies on the drawn mesh). The fit then measures the hub
against that point (:attr:`rodcad.design.net.target.NetTarget.fit_pairs`), as it measures a
planner's two-rod joint against the surface or edge it lies on; each node merged away is at
most half a short edge from the hub that replaces it, and the report says which nodes were
merged and by how much they moved (:class:`Collapse`).

Which edges. Edges collapse in rounds, shortest first, each round a matching (no node in two
collapses a round), because a hub's angles and so its size change when it gains rods: after
each round the hubs are sized again and the edges still short collapse in the next. A ring
of equal short edges so becomes every other node merged with its neighbour (a ring of half
as many hubs), not one hub for the whole ring (:func:`collapse_until_buildable`, the
planner's step).

What would keep them. A net scaled keeps its angles, and so its hubs: where the collapse leaves
nothing to hang, the refusal says how much larger the net drawn would have no short edge, or
from what length printed rods would do (:func:`short_edges_would`); where what it leaves
misses its target, the one line of the miss says the same (:func:`collapse_hint`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from rodcad.catalog.net.node import NodeHardware
from rodcad.design.net.joints import ReindexedSurface, drawn_target
from rodcad.design.net.sizing import short_edges, size_hubs
from rodcad.design.net.target import NetTarget
from rodcad.errors import DesignLimit

__all__ = ["Collapse", "added_anchors", "anchor_pairs", "collapse_short", "collapses", "drawn_nodes",
           "join_anchor_pairs", "collapse_hint", "collapse_until_buildable", "kept_larger", "short_edges_would",
           "tight_triangles"]

#: Rounds of collapses at most (each merges at least one pair; nets of thousands of nodes
#: stop far sooner: a round takes every short edge it can).
MAX_ROUNDS = 200


@dataclass(frozen=True)
class Collapse:
    """One hub that short edges collapsed into.

    Attributes:
        node: the hub's node in the planned target (planner's joints come after it).
        drawn: the drawn nodes it stands for (indices of the net as drawn).
        point: (3,) where it is (mm): on the drawn surface, edges or at the anchor.
        moved_mm: the largest distance of a drawn node from ``point`` (mm).
        anchored: it is an anchor (free nodes merged into it).
    """

    node: int
    drawn: tuple[int, ...]
    point: tuple[float, float, float]
    moved_mm: float
    anchored: bool


def drawn_nodes(t: NetTarget) -> np.ndarray:
    """(drawn n,) the node of ``t`` each drawn node is (before the planner's joints)."""
    drawn = drawn_target(t)
    if t.drawn is None:
        return np.arange(t.n)
    if t.node_of_drawn is not None:
        return t.node_of_drawn
    return np.asarray(t.fit_nodes[: drawn.n], int)


def collapse_short(t: NetTarget, short_edges) -> tuple[NetTarget, int]:
    """One round: the short edges ``short_edges`` (indices of ``t``'s edges) collapsed as a
    matching, shortest first (module docstring). Returns (the target, the number of rods
    between two anchors left out this round). ``t`` is the net before any two-rod joint."""
    edges = t.edges
    anchored = t.anchored_mask
    d = t.edge_lengths
    short = np.asarray(short_edges, int)
    short = short[np.argsort(d[short], kind="stable")]
    label = np.arange(t.n)
    used = np.zeros(t.n, dtype=bool)
    drop = np.zeros(t.m, dtype=bool)
    for e in short:
        i, j = (int(x) for x in edges[e])
        if anchored[i] and anchored[j]:
            drop[e] = True  # (the anchors hold both ends: no rod)
            continue
        if used[i] or used[j]:
            continue
        used[i] = used[j] = True
        keep, gone = (i, j) if anchored[i] or (not anchored[j] and i < j) else (j, i)
        label[gone] = keep
    out, between = _rebuilt(t, label, drop)
    return out, int(drop.sum()) + between


def _rebuilt(t: NetTarget, label: np.ndarray, drop: np.ndarray) -> tuple[NetTarget, int]:
    """``t`` with node ``k`` merged into node ``label[k]`` (a node whose label is itself
    keeps it) and the edges ``drop`` left out; with the number of rods left out because a free
    node merged into an anchor made them join two anchors."""
    drawn = drawn_target(t)
    to_node = drawn_nodes(t)
    keep = np.flatnonzero(label == np.arange(t.n))
    index = np.full(t.n, -1)
    index[keep] = np.arange(keep.size)
    new = index[label]
    of_drawn = new[to_node]
    positions = t.positions[keep].copy()
    merged = np.flatnonzero(np.bincount(new, minlength=keep.size) > 1)
    anchored_new = np.zeros(keep.size, dtype=bool)
    anchored_new[new[t.anchored]] = True
    for k in merged:
        members = np.flatnonzero(of_drawn == k)
        positions[k] = _placed(t, drawn, members, bool(anchored_new[k]), int(keep[k]))
    e2 = np.sort(new[t.edges], axis=1)
    ok = (e2[:, 0] != e2[:, 1]) & ~drop
    between = ok & anchored_new[e2].all(axis=1) & np.isin(e2, merged).any(axis=1)
    ok &= ~between
    _, first = np.unique(e2[ok], axis=0, return_index=True)
    rods = np.flatnonzero(ok)[np.sort(first)]
    # the fit: a node merged here against its point on the drawing; the rest as before
    fn, fp = t.fit_pairs
    fn = new[fn]
    mine = np.isin(fn, merged)
    fit_nodes = np.concatenate([fn[~mine], merged])
    fit_points = np.vstack([fp[~mine], positions[merged]])
    source = np.arange(t.m) if t.source is None else t.source
    surface = t.surface
    if surface is not None:
        surface = ReindexedSurface(surface, keep)
    return dataclasses.replace(t, positions=positions, edges=e2[rods], anchored=np.flatnonzero(anchored_new),
                               rod_bends=None if t.rod_bends is None else t.rod_bends[rods],
                               fit_nodes=fit_nodes, fit_points=fit_points, source=source[rods], drawn=drawn,
                               surface=surface, node_of_drawn=of_drawn), int(between.sum())


def _placed(t: NetTarget, drawn: NetTarget, members: np.ndarray, anchored: bool, near: int) -> np.ndarray:
    """Where the hub of the drawn nodes ``members`` goes: at its anchor, on the surface under
    their centroid, or on their drawn edges nearest it (module docstring)."""
    pts = drawn.positions[members]
    if anchored:  # (the node kept is the anchor)
        return t.positions[near].copy()
    c = pts.mean(axis=0)
    if t.surface is not None:
        return np.array([c[0], c[1], float(np.asarray(t.surface(c[0:1], c[1:2], near), float).ravel()[0])])
    inside = np.isin(drawn.edges, members).all(axis=1)
    best, out = np.inf, pts[0].copy()
    for a, b in drawn.positions[drawn.edges[inside]]:
        ab = b - a
        s = float(np.clip((c - a) @ ab / float(ab @ ab), 0.0, 1.0))
        q = a + s * ab
        dist = float(np.linalg.norm(q - c))
        if dist < best:
            best, out = dist, q
    return out


def collapses(t: NetTarget, near: list[list[int]] = ()) -> list[Collapse]:
    """The hubs of ``t`` that collapsed short edges (each standing for two or more drawn
    nodes), leaving out the groups ``near`` (:func:`rodcad.design.net.joints.merge_close`'s)."""
    if t.node_of_drawn is None:
        return []
    drawn = drawn_target(t)
    out = []
    skip = {tuple(sorted(g)) for g in near}
    for k in np.flatnonzero(np.bincount(t.node_of_drawn, minlength=t.n) > 1):
        members = np.flatnonzero(t.node_of_drawn == k)
        if tuple(int(x) for x in members) in skip:
            continue
        p = t.positions[k]
        moved = float(np.max(np.linalg.norm(drawn.positions[members] - p, axis=1)))
        out.append(Collapse(int(k), tuple(int(x) for x in members), (float(p[0]), float(p[1]), float(p[2])), moved,
                            bool(t.anchored_mask[k])))
    return out


def tight_triangles(t: NetTarget, least_deg: float) -> np.ndarray:
    """Edges ``a``-``b`` whose two nodes a third node's rods reach at less than ``least_deg``
    (deg: what the catalog's largest hub allows): a thin triangle, whose collapse (``a`` and
    ``b`` one hub) makes the two rods one. Edges between two anchors are left out."""
    pos, edges = t.positions, t.edges
    index = {(int(min(i, j)), int(max(i, j))): e for e, (i, j) in enumerate(edges)}
    nbrs: list[list[int]] = [[] for _ in range(t.n)]
    for i, j in edges:
        nbrs[int(i)].append(int(j))
        nbrs[int(j)].append(int(i))
    anchored = t.anchored_mask
    cos_least = np.cos(np.radians(least_deg))
    out = set()
    for k, nb in enumerate(nbrs):
        if len(nb) < 2:
            continue
        u = pos[nb] - pos[k]
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        cos = u @ u.T
        for p, q in zip(*np.nonzero(np.triu(cos > cos_least, 1))):
            a, b = sorted((nb[p], nb[q]))
            e = index.get((a, b))
            if e is not None and not (anchored[a] and anchored[b]):
                out.add(e)
    return np.array(sorted(out), int)


def anchor_pairs(t: NetTarget, least_deg: float) -> list[tuple[int, int]]:
    """Pairs of rods (e1, e2) from a free node to two anchors at less than ``least_deg`` (deg),
    tightest first, no rod in two pairs: :func:`join_anchor_pairs` makes each one rod."""
    pos, edges = t.positions, t.edges
    anchored = t.anchored_mask
    at: list[list[int]] = [[] for _ in range(t.n)]
    for e, (i, j) in enumerate(edges):
        if anchored[i] != anchored[j]:
            at[int(j) if anchored[i] else int(i)].append(e)
    cands = []
    for k, rods in enumerate(at):
        if len(rods) < 2:
            continue
        far = [int(edges[e, 1] if edges[e, 0] == k else edges[e, 0]) for e in rods]
        u = pos[far] - pos[k]
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        cos = np.clip(u @ u.T, -1, 1)
        for p, q in zip(*np.nonzero(np.triu(cos > np.cos(np.radians(least_deg)), 1))):
            cands.append((float(cos[p, q]), rods[p], rods[q]))
    used: set[int] = set()
    out = []
    for _, e1, e2 in sorted(cands, key=lambda c: -c[0]):
        if e1 not in used and e2 not in used:
            used |= {e1, e2}
            out.append((e1, e2))
    return out


def join_anchor_pairs(t: NetTarget, pairs: list[tuple[int, int]]) -> NetTarget:
    """Each pair of rods (e1, e2) from a free node to two anchors made one rod to a new anchor
    point midway between the two (on a generated net's surface: its frame): two rods that meet tighter than the largest hub allows and
    end on two anchors cannot be told apart by a hub, and their pulls, nearly parallel, are
    one pull toward the fixture between them (the drawn anchors stay where they are, and the
    report names the points added)."""
    drawn = drawn_target(t)
    pos, edges = t.positions, t.edges
    anchored = t.anchored_mask
    new_pos, new_edges, drop = [], edges.copy(), np.zeros(t.m, dtype=bool)
    near = list(range(t.n))
    for e1, e2 in pairs:
        k = int(edges[e1, 1] if anchored[edges[e1, 0]] else edges[e1, 0])
        a = int(edges[e1, 0] + edges[e1, 1] - k)
        b = int(edges[e2, 0] + edges[e2, 1] - k)
        node = t.n + len(new_pos)
        mid = 0.5 * (pos[a] + pos[b])
        if t.surface is not None:  # (a generated net's frame follows its surface)
            mid[2] = float(np.asarray(t.surface(mid[0:1], mid[1:2], a), float).ravel()[0])
        new_pos.append(mid)
        new_edges[e1] = (k, node)
        drop[e2] = True
        near.append(a)
    pts = np.asarray(new_pos, float).reshape(-1, 3)
    ids = np.arange(t.n, t.n + len(new_pos))
    fn, fp = t.fit_pairs
    source = np.arange(t.m) if t.source is None else t.source
    return dataclasses.replace(
        t, positions=np.vstack([pos, pts]), edges=new_edges[~drop], anchored=np.concatenate([t.anchored, ids]),
        rod_bends=None if t.rod_bends is None else t.rod_bends[~drop], fit_nodes=np.concatenate([fn, ids]),
        fit_points=np.vstack([fp, pts]), source=source[~drop], drawn=drawn, node_of_drawn=drawn_nodes(t),
        surface=None if t.surface is None else ReindexedSurface(t.surface, np.asarray(near)))


def added_anchors(t: NetTarget) -> list[tuple[int, tuple[int, int]]]:
    """The anchor points :func:`join_anchor_pairs` added: (node, the two drawn anchors it is
    midway between)."""
    if t.node_of_drawn is None:
        return []
    drawn = drawn_target(t)
    mine = np.setdiff1d(t.anchored, t.node_of_drawn)
    da = drawn.anchored
    out = []
    for k in mine:
        d = np.linalg.norm(drawn.positions[da] - t.positions[k], axis=1)
        a, b = (int(da[x]) for x in np.argsort(d)[:2]) if da.size >= 2 else (int(da[0]), int(da[0]))
        out.append((int(k), (min(a, b), max(a, b))))
    return out


def collapse_until_buildable(t: NetTarget, hw: NodeHardware, shortest: float, longest: float) -> tuple[NetTarget, int]:
    """The net with every edge shorter than the shortest rod between the smallest hubs its
    nodes' angles allow collapsed (:mod:`rodcad.design.net.collapse`), and every thin
    triangle whose rods meet tighter than the largest hub allows, round by round until none
    is left. Returns (the net, rods left out between two anchors)."""
    between = 0
    least = hw.sized(hw.pivot_limits[1]).min_angle_deg if hw.is_hub else 0.0  # (the largest hub's)
    drawn, first = t, None
    for _ in range(MAX_ROUNDS):
        rp, _ = size_hubs(t, hw, shortest, longest)
        short = short_edges(t, rp, shortest)
        thin = tight_triangles(t, least) if hw.is_hub else np.zeros(0, int)  # (rods meeting tighter than
        if first is None:  # the largest hub allows)
            first, first_short = (short.size, np.setdiff1d(thin, short).size), (rp, short)
        short = np.union1d(short, thin)
        if not short.size:
            pairs = anchor_pairs(t, least) if hw.is_hub else []
            if not pairs:
                break
            t = join_anchor_pairs(t, pairs)
            continue
        t, dropped = collapse_short(t, short)
        between += dropped
        if t.m == 0 or t.anchored_mask.all():
            what = [f"{first[0]} of the {drawn.m} drawn edge(s) are shorter than the shortest rod between the "
                    f"smallest hubs their nodes allow ({shortest:g} mm pivot to pivot; the shortest drawn "
                    f"{float(drawn.edge_lengths.min()):.3g} mm node to node)"] if first[0] else []
            if first[1]:
                what.append(f"{first[1]} close a triangle whose rods meet tighter than the largest hub allows "
                            f"({least:.3g} deg)")
            raise DesignLimit(" and ".join(what) + ": collapsed into one hub each, they leave nothing to hang (every "
                              "rod left would join two anchors); draw the net larger, or with fewer cells"
                              + short_edges_would(drawn, hw, *first_short, shortest))
    return t, between


def short_edges_would(t: NetTarget, hw: NodeHardware, rp: np.ndarray, short: np.ndarray, shortest: float) -> str:
    """What would make the drawn edges ``short`` of ``t`` rods, between the hubs of pivot radii
    ``rp`` their nodes' angles need (a net scaled keeps its angles, and so its hubs): the net
    drawn so much larger, or rods printed from the shortest such edge leaves ('' for none)."""
    if not short.size:
        return ""
    d = t.edge_lengths[short]
    ends = rp[t.edges[short]].sum(axis=1)
    larger = float(np.max((shortest + ends) / d))
    text = f" (drawn {math.ceil(1000 * (larger - 1)) / 10:g} % larger, every such rod would be {shortest:g} mm or more)"
    rod = math.floor(10 * float(np.min(d - ends))) / 10
    if rod >= hw.shortest_rod():
        text += (f", or a catalog whose rods print from {rod:g} mm pivot to pivot (the rod family's length.min, "
                 f"{shortest:g} mm)")
    return text


def collapse_hint(plan) -> str:
    """For a net that misses its target after drawn nodes were collapsed into hubs (a
    :class:`rodcad.design.net.plan.NetPlan`'s ``collapsed``): how many, and how much larger the
    net drawn would keep them (:func:`kept_larger`; '' where it would not keep every one)."""
    would, short = kept_larger(plan)
    if not would:
        return ""
    n = sum(len(c.drawn) for c in plan.collapsed)
    return (f"; {n} drawn nodes were collapsed into {len(plan.collapsed)} hub(s), {short} drawn edge(s) being "
            f"shorter than a rod between their hubs: the net drawn larger keeps them{would}")


def kept_larger(plan) -> tuple[str, int]:
    """How much larger the net drawn would keep the drawn nodes the plan collapsed for edges
    shorter than a rod between their hubs (:func:`short_edges_would`, from the drawn net's hubs:
    a net scaled keeps its angles), and how many such edges: ('', 0) where none was collapsed
    for a short edge, nodes drawn on top of each other were merged, or the drawn net has a
    triangle whose rods meet tighter than the largest hub allows (its collapse stays at any
    size)."""
    if not plan.collapsed or plan.merged:
        return "", 0
    drawn = drawn_target(plan.target)
    hw, (lo, hi) = plan.hardware, plan.length_range
    if hw.is_hub and tight_triangles(drawn, hw.sized(hw.pivot_limits[1]).min_angle_deg).size:
        return "", 0
    rp, _ = size_hubs(drawn, hw, lo, hi)
    short = short_edges(drawn, rp, lo)
    return short_edges_would(drawn, hw, rp, short, lo), int(short.size)
