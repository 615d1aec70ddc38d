"""Each node's hub from the catalog's family, and what no hub can do, in words.

A hub's pivot radius sets two things that pull opposite ways: the least angle its rods may
meet at (sockets ``min_wall`` apart, bodies clear: larger hubs let rods meet closer,
:meth:`rodcad.catalog.net.node.NodeHardware.pivot_for_angle`) and how much of an edge its rods
lose to the hubs (a rod is its edge less both hubs' pivot radii: smaller hubs leave longer
rods). :func:`size_hubs` gives every drawn node the catalog's nominal hub where its rods
fit it, a larger one where they meet tighter, and the least its angles allow where an edge
would be too short (a planner's joint gets the least its angles allow: it is lighter, and
sags less); what no size can do is reported with the hardware that would.
"""

from __future__ import annotations

import numpy as np

from rodcad.catalog.net.node import NodeHardware
from rodcad.design.net.target import NetTarget

__all__ = ["least_angles", "short_edges", "size_hubs"]


def least_angles(t: NetTarget) -> np.ndarray:
    """(n,) the least angle between two rods at each node (deg; 180 where fewer than two)."""
    pos, edges = t.positions, t.edges
    d = pos[edges[:, 1]] - pos[edges[:, 0]]
    u = d / np.linalg.norm(d, axis=1, keepdims=True)
    dirs: list[list[np.ndarray]] = [[] for _ in range(t.n)]
    for e, (i, j) in enumerate(edges):
        dirs[i].append(u[e])
        dirs[j].append(-u[e])
    out = np.full(t.n, 180.0)
    for k, dk in enumerate(dirs):
        if len(dk) < 2:
            continue
        D = np.asarray(dk)
        cos = np.clip(D @ D.T, -1, 1)
        np.fill_diagonal(cos, -1)
        out[k] = float(np.degrees(np.arccos(cos.max())))
    return out


def size_hubs(t: NetTarget, hw: NodeHardware, shortest: float, longest: float,
              floor: np.ndarray | None = None) -> tuple[np.ndarray, list[str]]:
    """Each node's pivot radius and what no hub of the catalog can do.

    Args:
        t: the target (with the planner's joints).
        hw: the catalog's node hardware (a family or one size; a point node: every pivot 0).
        shortest, longest: the rods' pivot-to-pivot window (mm).
        floor: (n,) the least pivot radius per node (mm; a long edge made one rod between
            larger hubs), or None.

    Returns:
        (node pivot radii (n,) mm, problems in words: empty when every rod is printable and
        every node's rods fit its hub; rods longer than ``longest`` are the caller's).
    """
    n = t.n
    if not hw.is_hub:
        return np.zeros(n), _short_rods(t, np.zeros(n), shortest, hw)
    lo, hi = hw.pivot_limits
    ang = least_angles(t)
    need = np.array([hw.pivot_for_angle(a) if a < 180 else lo for a in ang])
    need = np.maximum(need, lo)
    jm = t.joint_mask
    rp = np.where(jm, need, np.maximum(need, hw.pivot_radius))
    rp = np.minimum(rp, max(hi, lo))
    if floor is not None:
        rp = np.maximum(rp, floor)
    for _ in range(3):  # a short rod's nodes get the least hubs their angles allow
        short = short_edges(t, rp, shortest)
        if not short.size:
            break
        ends = np.unique(t.edges[short])
        rp[ends] = np.minimum(rp[ends], np.minimum(need[ends], max(hi, lo)))
        if floor is not None:
            rp = np.maximum(rp, floor)
    problems = []
    tight = np.flatnonzero(need > hi * (1 + 1e-9))
    if tight.size:
        order = tight[np.argsort(ang[tight])]
        worst = order[0]
        problems.append(
            f"at {tight.size} node(s) rods meet closer than the catalog's largest hub allows "
            f"({hw.sized(hi).min_angle_deg:.3g} deg at pivot radius {hi:g} mm): "
            + ", ".join(f"node {k} at {ang[k]:.3g} deg" for k in order[:6])
            + f"; a hub of pivot radius {need[worst]:.3g} mm (diameter {2 * (need[worst] + hw.shell):.3g} mm, "
            f"node.pivot_radius.max and node.diameter.max) would hold node {worst}'s rods")
    problems += _short_rods(t, rp, shortest, hw)
    return rp, problems


def short_edges(t: NetTarget, rp: np.ndarray, shortest: float) -> np.ndarray:
    """The edges of ``t`` whose rod, between hubs of pivot radii ``rp`` (n,) at their nodes, is
    shorter than ``shortest`` (mm, pivot to pivot) (indices)."""
    return np.flatnonzero(t.edge_lengths - rp[t.edges].sum(axis=1) < shortest * (1 - 1e-9))


def _short_rods(t: NetTarget, rp: np.ndarray, shortest: float, hw: NodeHardware) -> list[str]:
    d = t.edge_lengths
    L = d - rp[t.edges].sum(axis=1)
    short = short_edges(t, rp, shortest)
    if not short.size:
        return []
    order = short[np.argsort(L[short])]
    ends = hw.shortest_rod()
    worst = order[0]
    what = (f"rods from {max(L[worst], 0):.3g} mm pivot to pivot (the rod family's length.min) would do it"
            if L[worst] >= ends else
            f"no rod with these ends would: its ball ends alone take {ends:.3g} mm (a smaller node.ball, a "
            "smaller node.gap, or point nodes, node.kind: point, would)")
    src = t.source if t.source is not None else np.arange(t.m)
    return [f"{short.size} rod(s) would be shorter than the {shortest:g} mm the catalog prints even with the "
            "smallest hubs their nodes' angles allow: "
            + ", ".join(f"rod {e} (drawn edge {src[e]}, nodes {t.edges[e, 0]}-{t.edges[e, 1]}, {d[e]:.3g} mm apart, "
                        f"hubs of pivot radius {rp[t.edges[e, 0]]:.3g} and {rp[t.edges[e, 1]]:.3g} mm) "
                        f"{L[e]:.3g} mm" for e in order[:4])
            + f"; {what}, or the nodes drawn further apart (a net.refine with fewer cells)"]
