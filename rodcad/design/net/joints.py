"""The planner's edits of a drawn net: nodes merged, long edges cut into rods in line.

A user draws a net (with a mesh tool, by hand, or generated); the planner makes it buildable
with the catalog's rods and hubs before the masses are designed
(:func:`rodcad.design.net.plan.plan_net`):

* **Nodes nearly on top of each other** (closer than the shortest rod between the smallest
  hubs) become one hub at their midpoint (:func:`merge_close`), where that moves each less
  than :data:`MERGE_SHARE` of the tolerance; the fit measures the merged hub against each
  node drawn.
* **An edge longer than the longest rod** becomes ``k`` rods in line, joined by ``k - 1``
  two-rod joints (:func:`split_long`): the catalog's hub with two sockets.

The physics of a two-rod joint. A ball joint carries no moment, and its two rods turn freely
about it. In a hanging net the joint's own weight and half of each rod's weight hang on it,
pulled by the two rods' tensions only; force balance at the joint,
``T1 u1 + T2 u2 = W z``, has three components. Along the horizontal normal to the chord's
vertical plane it holds when the joint lies in that plane (rods and weight coplanar); in the
plane it needs the rods to kink: a joint on the straight chord (``u1 = -u2``) balances a
weight only if the chord is vertical. So the joint hangs *below* the chord, like a link of a
hanging chain, by the funicular sag: with the rods' tension ``T`` along the chord and the
loads ``P`` (joint plus a rod's weight) at fractions ``a_j = j / k`` of it, the joint hangs
``sag_j = P L S_j / T`` below the chord (``L`` the chord length, ``S_j = sum_i min(a_i, a_j)
(1 - max(a_i, a_j))``: the moment of a simply supported beam over its horizontal tension).
Counting for the inverse design: each split adds one rod (two unknowns: tension, mass) and
one node whose balance is two equations in the plane (the third holds by symmetry of the
plane): the design stays as determined as it was, and solves the joint like any node.

Where the joint's target is: on the target surface of a generated net (the surface point
under a point of the chord, in the chord's vertical plane, the joints spaced evenly along that
curve; for a hanging net below the chord), where the design's masses can make the rods kink
that much; or at the funicular sag below the drawn edge (:func:`hang_joints`, the tension
from the statics of the net as drawn), measured against the drawn edge (or surface): the fit
counts the sag. A joint that cannot hang within the tolerance (a rod without tension, a rise)
is left to the fit, which then says so.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from rodcad.design.net.target import NetTarget
from rodcad.errors import DesignLimit

__all__ = ["MAX_SAG", "MERGE_SHARE", "ReindexedSurface", "SLACK", "SagLimit", "drawn_target", "hang_joints", "merge_close",
           "pieces", "split_long"]

#: Nodes merge into one hub only where that moves each by at most this share of the
#: tolerance (of the net's size).
MERGE_SHARE = 0.5
#: A run whose tension is within this share of the net's largest is slack: no funicular sag.
SLACK = 1e-3
#: A funicular sag deeper than this share of the edge is no small kink: the joints stay drawn.
MAX_SAG = 0.25


class SagLimit(DesignLimit):
    """Two-rod joints hung at their funicular sag leave rods the catalog cannot print, or too
    close for the largest hub: ``edges``, the drawn edges cut into rods in line, which the
    caller may plan as one rod each instead (:func:`rodcad.design.net.plan.plan_net`'s
    ``whole``)."""

    def __init__(self, message: str, edges: frozenset[int]):
        super().__init__(message)
        self.edges = edges


@dataclasses.dataclass(frozen=True)
class ReindexedSurface:
    """A surface z(x, y, near) whose ``near`` is a node of a net with nodes merged: passed on
    as the node ``keep[near]`` of the net before (a radial net reads its angle near it)."""

    surface: object
    keep: np.ndarray

    def __call__(self, x, y, near):
        return self.surface(x, y, int(self.keep[near]))  # type: ignore[operator]


def drawn_target(t: NetTarget) -> NetTarget:
    """The target as drawn (before the planner's edits)."""
    return t if t.drawn is None else t.drawn


def merge_close(t: NetTarget, shortest: float, tolerance: float) -> tuple[NetTarget, list[list[int]]]:
    """Nodes joined by an edge shorter than ``shortest`` (mm, node to node: the shortest rod
    between the smallest hubs) merged into one hub at their midpoint where each moves at most
    :data:`MERGE_SHARE` x ``tolerance`` x size. Returns (the target, the merged groups of
    drawn nodes); the target itself when nothing merges."""
    pos, edges = t.positions, t.edges
    d = t.edge_lengths
    limit = MERGE_SHARE * tolerance * t.size
    parent = np.arange(t.n)

    def root(k: int) -> int:
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    for e in np.flatnonzero(d < shortest):
        i, j = root(int(edges[e, 0])), root(int(edges[e, 1]))
        if i != j:
            parent[max(i, j)] = min(i, j)
    groups: dict[int, list[int]] = {}
    for k in range(t.n):
        groups.setdefault(root(k), []).append(k)
    merged = [g for g in groups.values() if len(g) > 1]
    merged = [g for g in merged if np.max(np.linalg.norm(pos[g] - pos[g].mean(axis=0), axis=1)) <= limit]
    if not merged:
        return t, []
    new = np.arange(t.n)
    for g in merged:
        new[g] = g[0]
    keep = np.unique(new)
    index = np.full(t.n, -1)
    index[keep] = np.arange(keep.size)
    new = index[new]
    positions = pos[keep].copy()
    for g in merged:
        positions[new[g[0]]] = pos[g].mean(axis=0)
    e2 = np.sort(new[edges], axis=1)
    ok = e2[:, 0] != e2[:, 1]
    _, first = np.unique(e2[ok], axis=0, return_index=True)
    rods = np.flatnonzero(ok)[np.sort(first)]
    anchored = np.unique(new[t.anchored])
    out = dataclasses.replace(t, positions=positions, edges=e2[rods], anchored=anchored,
                              surface=None if t.surface is None else ReindexedSurface(t.surface, keep),
                              rod_bends=None if t.rod_bends is None else t.rod_bends[rods],
                              fit_nodes=new.copy(), fit_points=pos.copy(), source=rods,
                              drawn=drawn_target(t))
    return out, merged


def pieces(length: float, longest: float) -> int:
    """The rods in line an edge of ``length`` (mm, node to node, less what the hubs take)
    needs so that none is longer than ``longest`` (mm)."""
    return max(1, int(math.ceil(length / longest - 1e-9)))


def split_long(t: NetTarget, counts: np.ndarray, offsets: np.ndarray | None = None) -> tuple[NetTarget, np.ndarray]:
    """Each edge ``e`` cut into ``counts[e]`` rods in line joined by two-rod joints (module
    docstring): on the target surface under the chord for a generated net, on the edge
    otherwise. Rods keep their edge's index (its first piece) and bend; the other pieces
    follow at the end, in order; the fit measures each joint against where it was put.
    The joints are spaced evenly along the line they go on: the chord, or on a surface the
    surface's curve under it (spaced evenly under the chord, the pieces of an edge that climbs
    a steepening surface came out uneven: some too long for the catalog, and cut finer, others
    too short). ``offsets`` (m, 2): how much further (mm, along that line) the first and the
    last joint sit from the edge's two nodes than the pieces between joints are long (an end
    hub larger than a joint's by that much leaves every rod of the edge as long; None: equal
    pieces).
    Returns (the target, (m,) the edge of ``t`` each rod lies on)."""
    counts = np.asarray(counts, int)
    if np.all(counts <= 1):
        return t, np.arange(t.m)
    pos, edges = t.positions, t.edges
    new_pos = [pos]
    new_edges = edges.copy()
    extra, src, joints, extra_b, parent = [], [], [], [], []
    n = t.n
    fit_nodes = list(range(n)) if t.fit_nodes is None else list(t.fit_nodes)
    fit_points = list(pos) if t.fit_points is None else list(t.fit_points)
    source = np.arange(t.m) if t.source is None else t.source
    for e in np.flatnonzero(counts > 1):
        i, j = int(edges[e, 0]), int(edges[e, 1])
        k = int(counts[e])
        a = np.arange(1, k)[:, None] / k
        # the joints along the line they go on: the chord, or on a surface the surface's curve
        # under it, measured along that curve (its pieces alike where it is steeper at one end)
        if t.surface is None:
            d = float(np.linalg.norm(pos[j] - pos[i]))
        else:
            u, curve = _under(t, i, j)
            arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(curve, axis=0), axis=1))])
            d = float(arc[-1])
        if offsets is not None:
            o = np.clip(offsets[e], 0.0, None)
            if o.sum() < 0.5 * d:
                a = (o[0] + a * (d - o.sum())) / d
        if t.surface is None:
            pts = pos[i] + a * (pos[j] - pos[i])
        else:
            pts = pos[i] + np.interp(a[:, 0] * d, arc, u)[:, None] * (pos[j] - pos[i])
            pts[:, 2] = np.asarray(t.surface(pts[:, 0], pts[:, 1], i), float) * np.ones(k - 1)
        ids = list(range(n, n + k - 1))
        n += k - 1
        new_pos.append(pts)
        joints += ids
        fit_nodes += ids
        fit_points += list(pts)
        chain = [i] + ids + [j]
        new_edges[e] = (chain[0], chain[1])
        for q in range(1, k):
            extra.append((chain[q], chain[q + 1]))
            src.append(source[e])
            parent.append(e)
            extra_b.append(0.0 if t.rod_bends is None else float(t.rod_bends[e]))
    edges_out = np.vstack([new_edges, np.array(extra, int).reshape(-1, 2)])
    bends = t.rod_bends
    if bends is not None:
        bends = np.concatenate([bends, np.asarray(extra_b, float)])
    old_joints = [] if t.joints is None else list(t.joints)
    out = dataclasses.replace(t, positions=np.vstack(new_pos), edges=edges_out, rod_bends=bends,
                              fit_nodes=np.asarray(fit_nodes, int), fit_points=np.asarray(fit_points, float),
                              source=np.concatenate([source, np.asarray(src, int)]),
                              joints=np.asarray(old_joints + joints, int), drawn=drawn_target(t))
    return out, np.concatenate([np.arange(t.m), np.asarray(parent, int)])


#: Points of the surface's curve under an edge's chord that :func:`split_long` measures along.
UNDER_SAMPLES = 257


def _under(t: NetTarget, i: int, j: int) -> tuple[np.ndarray, np.ndarray]:
    """(the chord's parameters from node ``i`` (0) to ``j`` (1), the target surface's points
    under them): the curve a generated net's joints between the two go on."""
    u = np.linspace(0.0, 1.0, UNDER_SAMPLES)
    pts = t.positions[i] + u[:, None] * (t.positions[j] - t.positions[i])
    pts[1:-1, 2] = np.asarray(t.surface(pts[1:-1, 0], pts[1:-1, 1], i), float) * np.ones(UNDER_SAMPLES - 2)
    return u, pts


def hang_joints(t: NetTarget, tensions: np.ndarray, masses: np.ndarray, joint_mass: np.ndarray, g: float) -> NetTarget:
    """The joints' targets moved to the funicular sag below their chord (module docstring).

    Args:
        t: the split target (:func:`split_long`).
        tensions: (m,) each rod's tension in the statics of the net with the joints' pieces
            hanging as one (force, g x ``g``); a run of pieces is one chord.
        masses: (m,) each rod's mass there (g).
        joint_mass: (n,) each node's hub mass (g).
        g: gravity.

    Returns:
        The target with the joints' positions moved; their fit points stay where they were
        drawn, so the fit counts the sag. Runs without tension keep their points.
    """
    if t.joints is None or not len(t.joints):
        return t
    pos = t.positions.copy()
    jm = t.joint_mask
    top = float(np.max(np.abs(tensions[np.isfinite(tensions)]), initial=0.0))
    for chain in _runs(t):
        rods = [e for e, _, _ in chain]
        nodes = [chain[0][1]] + [b for _, _, b in chain]
        T = float(np.mean(tensions[rods]))
        k = len(rods)
        A, B = pos[nodes[0]], pos[nodes[-1]]
        L = float(np.linalg.norm(B - A))
        if not np.isfinite(T) or T <= SLACK * top or L <= 0:
            continue  # (no pull to hang from: the joints stay where drawn, and the fit says so)
        a = np.arange(1, k) / k
        P = g * (float(np.mean(masses[rods])) + joint_mass[nodes[1:-1]])
        sags = [float(np.sum(P * np.minimum(a, a[q]) * (1 - np.maximum(a, a[q])))) * L / T for q in range(k - 1)]
        if max(sags) > MAX_SAG * L:
            continue  # (not a small kink: the run cannot hang near its edge)
        for q, node in enumerate(nodes[1:-1]):
            if jm[node]:
                pos[node] = A + a[q] * (B - A) - np.array([0.0, 0.0, sags[q]])
    return dataclasses.replace(t, positions=pos)


def _runs(t: NetTarget) -> list[list[tuple[int, int, int]]]:
    """The runs of rods in line through the joints: per run, (rod, from node, to node) from
    one end node to the other."""
    jm = t.joint_mask
    at: dict[int, list[int]] = {}
    for e, (i, j) in enumerate(t.edges):
        for k in (int(i), int(j)):
            if jm[k]:
                at.setdefault(k, []).append(e)
    seen: set[int] = set()
    runs = []
    for e, (i, j) in enumerate(t.edges):
        i, j = int(i), int(j)
        if e in seen or jm[i] or not jm[j]:
            continue
        run, prev, cur, rod = [], i, j, e
        while True:
            seen.add(rod)
            run.append((rod, prev, cur))
            if not jm[cur]:
                break
            nxt = [r for r in at[cur] if r != rod]
            if not nxt:
                break
            rod = nxt[0]
            a, b = (int(x) for x in t.edges[rod])
            prev, cur = cur, (b if a == cur else a)
        runs.append(run)
    return runs
