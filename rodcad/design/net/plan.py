"""Rods and hardware laid on a net's target.

:func:`plan_net` lays the catalog's node hardware on the target (a hub at every node, each
rod's pivot ``pivot_radius`` from the hub's centre along the rod's target direction; a point
node: the node itself), gives every rod its pivot-to-pivot length and its mass bounds
(:meth:`rodcad.catalog.net.node.NodeHardware.rod_numbers`) and every node its hub's mass and
centre of mass, and refuses (:class:`rodcad.errors.DesignLimit`, exit 1) rods the catalog
cannot print and nodes whose rods meet closer than the hub's sockets allow. :func:`replan`
moves the pivots (the hubs' sockets, :mod:`rodcad.design.net.hubs`) and updates the rest;
:func:`mass_segments` are the masses a rod can be built at.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rodcad.catalog.net.bend import NetRodArc, bent_rod_com, bent_swing_deg, rod_arc
from rodcad.catalog.net.node import NetRodNumbers, NodeHardware
from rodcad.design.net.target import NetTarget
from rodcad.errors import DesignLimit

__all__ = ["NetPlan", "POINT_WIDTH", "fill_lengths", "length_range", "mass_segments", "plan_net", "replan", "rod_bounds"]


@dataclass
class NetPlan:
    """Rods and hardware laid on a net's target.

    Attributes:
        target: the net's target.
        hardware: the catalog's node hardware.
        pivots: (m, 2, 3) each rod's pivot at its node i and j, from the node point (mm; the
            hub's frame, which is the world frame at the target).
        lengths: (m,) pivot-to-pivot lengths (mm).
        rods: each rod's numbers (solid mass, mass range, steel balls).
        bounds: (m, 2) mass bounds (g).
        node_masses: (n,) hub (or point part) masses (g).
        node_com: (n, 3) hubs' centres of mass from the node point (mm, hub frame).
        length_range: (min, max) rod lengths the catalog prints (mm).
        degree: (n,) rods at each node.
        segment: (m,) which segment of buildable masses each rod's bounds are (:func:`mass_segments`),
            or None: the whole range (see :func:`rodcad.design.net.hubs.buildable_bounds`).
        com: (m, 3) each rod's centre of mass (along, below the chord, 0) (mm) the statics use
            (:meth:`rod_com` of the masses designed last; straight rods at mid-length).
    """

    target: NetTarget
    hardware: NodeHardware
    pivots: np.ndarray
    lengths: np.ndarray
    rods: list[NetRodNumbers]
    bounds: np.ndarray
    node_masses: np.ndarray
    node_com: np.ndarray
    length_range: tuple[float, float]
    degree: np.ndarray
    segment: np.ndarray | None = None
    com: np.ndarray | None = None

    @property
    def target_ends(self) -> np.ndarray:
        """(m, 2, 3) the rods' pivots at the target (mm)."""
        return self.target.positions[self.target.edges] + self.pivots

    @property
    def arcs(self) -> list[NetRodArc | None]:
        """Each rod's arc (:mod:`rodcad.catalog.net.bend`), None where it is straight."""
        return [rod_arc(self.hardware, float(L), float(b)) for L, b in zip(self.lengths, self.target.bends)]

    @property
    def bent(self) -> bool:
        return bool(np.any(self.target.bends > 0))

    @property
    def fill_lengths(self) -> np.ndarray:
        """(m,) the straight length each rod weighs and is filled as (its own when straight)."""
        return fill_lengths(self.hardware, self.lengths, self.target.bends)

    @property
    def swing_limits(self) -> np.ndarray:
        """(m,) how far each rod may turn in its sockets (deg): a bent rod's tilted end face
        comes nearer the hub (:func:`rodcad.catalog.net.bend.bent_swing_deg`)."""
        hw = self.hardware
        return np.array([hw.swing_deg if a is None else min(hw.swing_deg, bent_swing_deg(hw, a))
                         for a in self.arcs], float)

    def rod_com(self, masses) -> np.ndarray:
        """(m, 3) each rod's centre of mass at ``masses`` (g): (along, below the chord, 0) mm,
        in closed form (:func:`rodcad.catalog.net.bend.bent_rod_com`); straight: (L / 2, 0, 0)."""
        out = np.zeros((self.target.m, 3))
        out[:, 0] = self.lengths / 2
        for e, a in enumerate(self.arcs):
            if a is not None:
                out[e] = bent_rod_com(self.hardware, a, float(masses[e]))[0]
        return out

    @property
    def statics_com(self) -> np.ndarray | None:
        """The centres of mass the statics use: :attr:`com` for a bent net, else None (on the axis
        at mid-length)."""
        if not self.bent:
            return None
        return self.com if self.com is not None else self.rod_com(self.bounds.mean(axis=1))


def fill_lengths(hw, lengths, bends) -> np.ndarray:
    """(m,) per rod, the straight length it weighs and is filled as (:mod:`rodcad.catalog.net.bend`)."""
    out = np.asarray(lengths, float).copy()
    for e, (L, b) in enumerate(zip(lengths, bends)):
        a = rod_arc(hw, float(L), float(b))
        if a is not None:
            out[e] = a.fill_length
    return out


def length_range(catalog) -> tuple[float, float]:
    """The rod lengths a catalog prints for a net (mm): its first family printed to order's
    range, else the span of its rod types' lengths."""
    fams = catalog.printed_families
    if fams:
        return tuple(float(x) for x in fams[0].ranges.length)  # type: ignore[return-value]
    lengths = [t.length for t in catalog]
    return float(min(lengths)), float(max(lengths))


def plan_net(target: NetTarget, catalog) -> NetPlan:
    """Hardware, lengths, mass bounds and hub masses for a net's target.

    Raises:
        DesignLimit: rods shorter or longer than the catalog prints, or rods meeting at a
            node closer than its hub's sockets allow (every such rod and node named).
    """
    hw: NodeHardware = catalog.node
    pos, edges = target.positions, target.edges
    n, m = target.n, target.m
    d = pos[edges[:, 1]] - pos[edges[:, 0]]
    dist = np.linalg.norm(d, axis=1)
    u = d / dist[:, None]
    r = hw.pivot
    pivots = np.stack([r * u, -r * u], axis=1)
    lengths = dist - 2 * r
    lo, hi = length_range(catalog)
    lo_hw = max(lo, hw.shortest_rod())
    problems = []
    short = np.flatnonzero(lengths < lo_hw * (1 - 1e-9))
    long = np.flatnonzero(lengths > hi * (1 + 1e-9))
    extra = f" (node to node: {2 * r:g} mm more, the hubs)" if r else ""
    if short.size:
        problems.append(f"{short.size} rod(s) would be shorter than the {lo_hw:g} mm the catalog prints: "
                        f"rods {short[:8].tolist()} need {', '.join(f'{x:.4g}' for x in lengths[short[:8]])} mm "
                        f"pivot to pivot{extra}; use fewer cells or draw the net larger")
    if long.size:
        problems.append(f"{long.size} rod(s) would be longer than the {hi:g} mm the catalog prints: rods "
                        f"{long[:8].tolist()} need {', '.join(f'{x:.4g}' for x in lengths[long[:8]])} mm; use more "
                        "cells or draw the net smaller")
    degree = np.bincount(edges.ravel(), minlength=n)
    # directions of the rods at every node (from the node toward the rod's other end)
    dirs: list[list[np.ndarray]] = [[] for _ in range(n)]
    for e, (i, j) in enumerate(edges):
        dirs[i].append(u[e])
        dirs[j].append(-u[e])
    if hw.is_hub:
        need = hw.min_angle_deg
        worst = []
        for k in range(n):
            if len(dirs[k]) < 2:
                continue
            D = np.asarray(dirs[k])
            cos = np.clip(D @ D.T, -1, 1)
            np.fill_diagonal(cos, -1)
            ang = float(np.degrees(np.arccos(cos.max())))
            if ang < need - 1e-9:
                worst.append((ang, k))
        if worst:
            worst.sort()
            problems.append(f"at {len(worst)} node(s) rods meet closer than the hub's sockets allow ({need:.3g} deg): "
                            + ", ".join(f"node {k} at {a:.3g} deg" for a, k in worst[:6])
                            + "; a larger hub (node.diameter and node.pivot_radius) or a net with wider angles")
    bends = target.bends
    if np.any(bends > 0):
        flat = [int(e) for e in np.flatnonzero(bends > 0) if lengths[e] - 2 * hw.end_offset <= 0
                or bent_swing_deg(hw, rod_arc(hw, float(lengths[e]), float(bends[e]))) <= 0]
        if flat:
            problems.append(f"{len(flat)} bent rod(s) would touch their hub with the edge of their body's end face "
                            f"(square to the arc, tilted off square to the chord): rods {flat[:8]} bent "
                            f"{', '.join(f'{bends[e]:.3g}' for e in flat[:8])}; bend them less, or a catalog with a "
                            "larger node.gap")
    if problems:
        raise DesignLimit("; ".join(problems))
    rods = [hw.rod_numbers(float(L)) for L in fill_lengths(hw, lengths, bends)]
    bounds = np.array([rn.mass_range for rn in rods], float)
    node_masses = np.zeros(n)
    node_com = np.zeros((n, 3))
    for k in range(n):
        mass, com = hw.hub_mass(np.asarray(dirs[k]).reshape(-1, 3))
        node_masses[k] = mass
        node_com[k] = com
    return NetPlan(target, hw, pivots, lengths, rods, bounds, node_masses, node_com, (lo_hw, hi), degree)


#: A buildable interval narrower than this (relative) is one mass; it is given this width
#: below it (the mass design's programs need a width; a microgram in a gram).
POINT_WIDTH = 1e-6


def mass_segments(hw, length: float) -> list[tuple[float, float]]:
    """The masses a rod can be built at (:meth:`rodcad.catalog.net.node.NodeHardware.rod_intervals`)
    as disjoint segments, ascending; a single mass given :data:`POINT_WIDTH` below it."""
    segs: list[list[float]] = []
    for _, lo, hi in sorted(hw.rod_intervals(length), key=lambda x: x[1]):
        if hi - lo < POINT_WIDTH * hi:
            lo = hi * (1 - POINT_WIDTH)
        if segs and lo <= segs[-1][1]:
            segs[-1][1] = max(segs[-1][1], hi)
        else:
            segs.append([lo, hi])
    return [(a, b) for a, b in segs]


def replan(plan: NetPlan, pivots: np.ndarray) -> NetPlan:
    """The plan with new pivots: lengths, mass bounds and hub centres of mass follow."""
    t, hw = plan.target, plan.hardware
    ends = t.positions[t.edges] + pivots
    lengths = np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)
    flen = fill_lengths(hw, lengths, t.bends)
    rods = [hw.rod_numbers(float(L)) for L in flen]
    node_com = np.zeros((t.n, 3))
    node_masses = plan.node_masses.copy()
    dirs: list[list[np.ndarray]] = [[] for _ in range(t.n)]
    for e, (i, j) in enumerate(t.edges):
        dirs[i].append(pivots[e, 0] / np.linalg.norm(pivots[e, 0]))
        dirs[j].append(pivots[e, 1] / np.linalg.norm(pivots[e, 1]))
    for k in range(t.n):
        node_masses[k], node_com[k] = hw.hub_mass(np.asarray(dirs[k]).reshape(-1, 3))
    bounds = rod_bounds(plan, lengths, rods)
    return NetPlan(t, hw, pivots, lengths, rods, bounds, node_masses, node_com, plan.length_range, plan.degree,
                   plan.segment)


def rod_bounds(plan: NetPlan, lengths: np.ndarray, rods: list[NetRodNumbers] | None = None) -> np.ndarray:
    """(m, 2) the plan's rods' mass bounds (g) at pivot-to-pivot ``lengths`` (mm): their whole
    mass range, or the segment of buildable masses the plan holds them to (``segment``)."""
    hw = plan.hardware
    flen = fill_lengths(hw, lengths, plan.target.bends)
    if rods is None:
        rods = [hw.rod_numbers(float(L)) for L in flen]
    bounds = np.array([r.mass_range for r in rods], float)
    if plan.segment is not None:
        for e, L in enumerate(flen):
            segs = mass_segments(hw, float(L))
            bounds[e] = segs[min(int(plan.segment[e]), len(segs) - 1)]
    return bounds
