"""Rods and hardware laid on a net's target.

:func:`plan_net` lays the catalog's node hardware on the target (a hub at every node, each
rod's pivot ``pivot_radius`` from the hub's centre along the rod's target direction; a point
node: the node itself), gives every rod its pivot-to-pivot length and its mass bounds
(:meth:`rodcad.catalog.net.node.NodeHardware.rod_numbers`) and every node its hub's mass and
centre of mass, after making the drawn net buildable (short edges collapsed:
:mod:`rodcad.design.net.collapse`; long ones cut into rods in line: :mod:`rodcad.design.net.joints`),
and refuses (:class:`rodcad.errors.DesignLimit`, exit 1) what is left that no hardware can do
(nodes whose rods meet closer than the largest hub's sockets allow). :func:`replan`
moves the pivots (the hubs' sockets, :mod:`rodcad.design.net.hubs`) and updates the rest;
:func:`mass_segments` are the masses a rod can be built at.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from rodcad.catalog.net.bend import NetRodArc, bent_rod_com, bent_swing_deg, rod_arc
from rodcad.catalog.net.node import NetRodNumbers, NodeHardware
from rodcad.design.net.collapse import added_anchors, collapse_until_buildable, collapses
from rodcad.design.net.joints import SagLimit, hang_joints, merge_close, pieces, split_long
from rodcad.design.net.target import NetTarget
from rodcad.errors import DesignLimit

__all__ = ["NetPlan", "POINT_WIDTH", "SPLICE_MARGIN", "fill_lengths", "length_range", "mass_segments",
           "node_directions", "plan_net", "replan", "resized", "rod_bounds", "rod_numbers"]

#: A spliced rod's pieces are each at most this share of the longest rod the catalog prints:
#: the margin :func:`_first_count` keeps for rods in line (the sockets turned lengthen rods).
SPLICE_MARGIN = 0.97


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
        node_pivot: (n,) each node's hub's pivot radius (mm; the catalog's hub family,
            :meth:`hub`), or None: the catalog's one size.
        merged: groups of drawn nodes nearly on top of each other merged into one hub
            (:func:`rodcad.design.net.joints.merge_close`).
        collapsed: the hubs short edges collapsed into (:mod:`rodcad.design.net.collapse`).
        between_anchors: rods a collapse left out because they joined two anchors.
        added_anchors: anchor points added midway between two drawn anchors, (node, (a, b)),
            where two rods to them met tighter than the largest hub allows
            (:func:`rodcad.design.net.collapse.join_anchor_pairs`).
        spread: drawn nodes moved a little so that the family's largest hub holds rods drawn
            to meet too close, or a rod drawn too short reaches the shortest printed, (node, mm
            moved) (:mod:`rodcad.design.net.spread`; the planner's last resort).
        pieces: (m,) the printed pieces each rod is spliced from (:mod:`rodcad.catalog.net.splice`;
            1: one piece), or None: every rod one piece.
        node_cone: (n,) each hub's socket cone (deg) within the catalog's ``cone_range``
            (:mod:`rodcad.design.net.cones`), or None: the catalog's ``cone_deg`` at every hub.
        pushing: (m,) the rods the design lets push (rigid rods whose hubs hold them either way,
            where no masses balance the net in tension: :mod:`rodcad.design.net.pushing`), or
            None: as the target says (:attr:`may_push`).
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
    node_pivot: np.ndarray | None = None
    merged: list = field(default_factory=list)
    collapsed: list = field(default_factory=list)
    between_anchors: int = 0
    added_anchors: list = field(default_factory=list)
    spread: list = field(default_factory=list)
    pieces: np.ndarray | None = None
    node_cone: np.ndarray | None = None
    pushing: np.ndarray | None = None

    @property
    def may_push(self) -> bool | np.ndarray:
        """The rods the designs let push: :attr:`pushing` where set, else every rod with
        ``compression: true`` and none otherwise (the statics' ``allow_compression``)."""
        return self.target.any_may_push if self.pushing is None else self.pushing

    def mass_design(self, g: float, **kw):
        """:func:`optimize.design_net_masses` at the target with this plan's lengths, mass bounds,
        hubs (masses, centres of mass, pivots), rods' centres of mass for the statics and the
        rods it lets push (:attr:`may_push`); ``kw`` sets any of them otherwise (``bounds``,
        ``com``, ``allow_compression``) and the rest of that function's keywords."""
        from optimize import design_net_masses

        t = self.target
        bounds = kw.pop("bounds", self.bounds)
        args = dict(node_masses=self.node_masses, node_com=self.node_com, pivots=self.pivots, com=self.statics_com,
                    allow_compression=self.may_push, g=g)
        return design_net_masses(t.positions, t.edges, self.lengths, bounds, t.anchored, **{**args, **kw})

    def hub(self, k: int, pivot_radius: float | None = None) -> NodeHardware:
        """Node ``k``'s hub: the family's size with its pivot radius (:attr:`node_pivot`, or
        ``pivot_radius``: the size it would be) and its sockets' cone (:attr:`node_cone`)."""
        hw = self.hardware
        if not hw.is_hub:
            return hw
        if pivot_radius is not None:
            hw = hw.sized(float(pivot_radius))
        elif self.node_pivot is not None:
            hw = hw.sized(float(self.node_pivot[k]))
        return hw if self.node_cone is None else hw.coned(float(self.node_cone[k]))

    def hub_key(self, k: int) -> tuple:
        """What node ``k``'s hub (:meth:`hub`) depends on."""
        return (None if self.node_pivot is None else float(self.node_pivot[k]),
                None if self.node_cone is None else float(self.node_cone[k]))

    @property
    def end_pivot(self) -> np.ndarray:
        """(m, 2) the pivot radius of the hub at each rod's two ends (mm)."""
        if self.node_pivot is None:
            return np.full((self.target.m, 2), self.hardware.pivot)
        return self.node_pivot[self.target.edges]

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
    def rod_pieces(self) -> np.ndarray:
        """(m,) the pieces each rod is printed in (1 where it is not spliced)."""
        return np.ones(self.target.m, int) if self.pieces is None else np.asarray(self.pieces, int)

    @property
    def piece_lengths(self) -> np.ndarray:
        """(m,) each rod's share of pivot-to-pivot length per printed piece (mm): what the
        catalog's length window bounds."""
        return np.asarray(self.lengths, float) / self.rod_pieces

    def numbers(self, lengths=None) -> list[NetRodNumbers]:
        """Each rod's numbers at ``lengths`` (mm; default its own): a bent rod's at its fill
        length, a spliced rod's over its pieces."""
        lengths = self.lengths if lengths is None else lengths
        return rod_numbers(self.hardware, lengths, self.target.bends, self.pieces)

    @property
    def fill_lengths(self) -> np.ndarray:
        """(m,) the straight length each rod weighs and is filled as (its own when straight)."""
        return fill_lengths(self.hardware, self.lengths, self.target.bends)

    @property
    def end_swing_limits(self) -> np.ndarray:
        """(m, 2) how far each rod may turn in the socket at each of its ends (deg): its hub's
        swing, less where a bent rod's tilted end face comes nearer the hub
        (:func:`rodcad.catalog.net.bend.bent_swing_deg`). Each hub's own swing (a bisection) is
        found once per size and cone, not once per rod end."""
        sizes: dict[tuple, tuple[NodeHardware, float]] = {}
        out = np.full((self.target.m, 2), np.inf)
        for e, a in enumerate(self.arcs):
            for c, k in enumerate(self.target.edges[e]):
                key = self.hub_key(int(k))
                if key not in sizes:
                    hw = self.hub(int(k))
                    sizes[key] = (hw, hw.swing_deg)
                hw, swing = sizes[key]
                out[e, c] = swing if a is None else min(swing, bent_swing_deg(hw, a))
        return out

    @property
    def swing_limits(self) -> np.ndarray:
        """(m,) how far each rod may turn in its sockets (deg): the lesser of its two ends'
        (:attr:`end_swing_limits`)."""
        return self.end_swing_limits.min(axis=1)

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


def rod_numbers(hw, lengths, bends, pieces=None) -> list[NetRodNumbers]:
    """Per rod, its numbers (:meth:`rodcad.catalog.net.node.NodeHardware.rod_numbers`) at its fill
    length, over its ``pieces`` (None: one each)."""
    flen = fill_lengths(hw, lengths, bends)
    ks = np.ones(len(flen), int) if pieces is None else np.asarray(pieces, int)
    return [hw.rod_numbers(float(L), int(k)) for L, k in zip(flen, ks)]


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


def plan_net(target: NetTarget, catalog, *, tolerance: float | None = None, hang: bool = False,
             g: float = 9.81, whole: frozenset[int] = frozenset(), splice_whole: bool = False,
             spread: bool = True) -> NetPlan:
    """Hardware, lengths, mass bounds and hub masses for a net's target, the drawn net made
    buildable first (:mod:`rodcad.design.net.joints`, :mod:`rodcad.design.net.collapse`,
    :mod:`rodcad.design.net.sizing`): nodes nearly on top of each other merged into one hub,
    edges shorter than the shortest rod between the smallest hubs collapsed (their two nodes
    one hub on the drawn surface or edges), edges longer than the longest rod cut
    into rods in line joined by two-rod joints, and every node given the hub of the
    catalog's family its rods fit.

    Args:
        target: the net as drawn (or generated).
        catalog: the catalog (its node hardware and the rods' length range).
        tolerance: the design's tolerance (None: 1 %), which bounds how far a merge moves nodes.
        hang: put the joints at the funicular sag below their chords (:func:`rodcad.design.net.
            joints.hang_joints`, from the statics of the net as drawn) instead of on the target
            surface (a generated net) or the edge.
        g: gravity (for ``hang``).
        whole: drawn edges to be one rod each, not rods in line, their end hubs made larger
            (within the family) to take what the rod cannot (:func:`_whole_floor`); where the
            family's largest hubs do not, they are cut into rods in line as the others.
        splice_whole: every straight edge of ``whole`` spliced (:mod:`rodcad.catalog.net.splice`)
            between the hubs its nodes get anyway, none between larger hubs (where larger hubs
            would leave another of their rods too short).
        spread: where rods meet too close for the largest hub or are too short between their
            hubs, move nodes within the tolerance (:mod:`rodcad.design.net.spread`) before
            refusing; False refuses (for a caller with another way to try first).

    Raises:
        DesignLimit: what no hardware in the catalog can do (every such rod and node named,
            with the hardware that would do it).
    """
    from rodcad.design.fit import DEFAULT_TOLERANCE
    from rodcad.design.net.sizing import size_hubs
    from rodcad.design.net.spread import SPREAD_SHARE

    hw: NodeHardware = catalog.node
    tol = DEFAULT_TOLERANCE if tolerance is None else float(tolerance)
    lo, hi = length_range(catalog)
    lo_hw = max(lo, hw.shortest_rod())
    rp_min = hw.pivot_limits[0] if hw.is_hub else 0.0
    merged: list[list[int]] = []
    t = target
    if hw.is_hub:
        t, merged = merge_close(t, lo_hw + 2 * rp_min, tol)
    t, between = collapse_until_buildable(t, hw, lo_hw, hi)
    drawn_at = t.positions
    # the most a node may move to spread rods drawn too close or too short (mm): only where
    # nothing else the planner does (rods in line, hubs of their own size) holds them
    budget = SPREAD_SHARE * tol * t.size if spread else 0.0
    moved = np.zeros(0, dtype=np.int64)
    base = t
    counts = np.full(base.m, max(int(t.refine_edges), 1))  # (net.refine of explicit edges)
    one, floor, spliced = _whole_floor(base, hw, hi, whole, splice_whole)
    counts[one | spliced] = 1
    rp_base = size_hubs(base, hw, lo_hw, hi, floor)[0]
    for _ in range(4):  # the pieces on a surface are not all alike: split further where one is still long
        # (the first and last joints set in by how much larger their end hubs are than a joint's)
        t, parent = split_long(base, counts, rp_base[base.edges] - rp_min)
        node_pivot, problems = size_hubs(t, hw, lo_hw, hi, np.concatenate([floor, np.zeros(t.n - base.n)]))
        rp_base = node_pivot[: base.n]
        lengths = _lengths(t, node_pivot)
        pieces = np.where(spliced[parent], np.ceil(lengths / (SPLICE_MARGIN * hi) - 1e-12), 1).astype(int)
        long = np.flatnonzero(lengths / np.maximum(pieces, 1) > hi * (1 + 1e-9))
        if not long.size:
            break
        grow = np.unique(parent[long])
        if one[grow].any():  # pragma: no cover - (_whole_floor makes them fit)
            raise DesignLimit(f"drawn edges {sorted(set(grow[one[grow]].tolist()))} stay longer than the longest rod "
                              "with the family's largest hubs")
        counts[grow] = np.maximum(counts[grow] + 1, [_first_count(base, e, node_pivot, rp_min, hi) for e in grow])
    if problems and not long.size:  # rods too close or too short once the long edges are cut: nodes spread
        floor_t = np.concatenate([floor, np.zeros(t.n - base.n)])
        wide, rp_wide, left, also = _spread(t, hw, budget - _moved(t, drawn_at), lo_hw, hi, floor_t)
        len_wide = _lengths(wide, rp_wide)
        if also.size and not np.any(len_wide / np.maximum(pieces, 1) > hi * (1 + 1e-9)):
            t, node_pivot, problems, lengths = wide, rp_wide, left, len_wide
            base = dataclasses.replace(base, positions=t.positions[: base.n].copy())
            moved = np.union1d(moved, also)
    bends = t.bends
    if np.any(bends > 0):
        flat = [int(e) for e in np.flatnonzero(bends > 0) if lengths[e] - 2 * hw.end_offset <= 0
                or bent_swing_deg(hw, rod_arc(hw, float(lengths[e]), float(bends[e]))) <= 0]
        if flat:
            problems.append(f"{len(flat)} bent rod(s) would touch their hub with the edge of their body's end face "
                            f"(square to the arc, tilted off square to the chord): rods {flat[:8]} bent "
                            f"{', '.join(f'{bends[e]:.3g}' for e in flat[:8])}; bend them less, or a catalog with a "
                            "larger node.gap")
    if problems:
        raise DesignLimit("; ".join(problems) + _coarser(target, hw, lo_hw))
    if hang and t.joints is not None and len(t.joints):
        t = _hung(t, base, parent, counts, hw, node_pivot, g, pieces)
        # the joints moved, and with them the angles their rods meet the hubs at: the hubs sized again
        # (never smaller), so that every two sockets keep their wall
        node_pivot, problems = size_hubs(t, hw, lo_hw, hi, node_pivot)
        if problems:  # rods the sag brought too close or made too short: the drawn nodes spread
            # (the joints stay at their sag)
            t, node_pivot, problems, also = _spread(t, hw, budget - _moved(t, drawn_at), lo_hw, hi, node_pivot,
                                                    fixed=t.joint_mask)
            moved = np.union1d(moved, also)
        if problems:
            src = base.source if base.source is not None else np.arange(base.m)
            raise SagLimit("with the two-rod joints at their funicular sag, " + "; ".join(problems),
                           frozenset(int(src[e]) for e in np.flatnonzero(counts > 1)))
    plan = _plan(t, hw, node_pivot, (lo_hw, hi), pieces if np.any(pieces > 1) else None)
    plan.merged = merged
    plan.collapsed = collapses(base, merged)
    plan.between_anchors = between
    plan.added_anchors = added_anchors(base)
    plan.spread = [(int(k), float(np.linalg.norm(t.positions[k] - drawn_at[k]))) for k in moved if k < len(drawn_at)]
    return plan


def _moved(t: NetTarget, drawn_at: np.ndarray) -> float:
    """The farthest any of the first ``len(drawn_at)`` nodes of ``t`` is from its point in
    ``drawn_at`` (mm): how far the spread has moved a node so far."""
    return float(np.max(np.linalg.norm(t.positions[: len(drawn_at)] - drawn_at, axis=1), initial=0.0))


def _spread(t: NetTarget, hw: NodeHardware, budget: float, shortest: float, longest: float, floor: np.ndarray,
            fixed: np.ndarray | None = None) -> tuple[NetTarget, np.ndarray, list[str], np.ndarray]:
    """Up to three rounds of :func:`rodcad.design.net.spread.spread_tight` and :func:`size_hubs`:
    the nodes moved until every node's rods fit the family's largest hub and every rod is at
    least ``shortest`` between its hubs as sized, within ``budget`` (mm) in all. Returns (target,
    node pivot radii, problems left, nodes moved)."""
    from rodcad.design.net.sizing import size_hubs
    from rodcad.design.net.spread import spread_tight

    start = t.positions.copy()
    moved = np.zeros(0, dtype=np.int64)
    node_pivot, problems = size_hubs(t, hw, shortest, longest, floor)
    for _ in range(3):
        if not problems:
            break
        ends = node_pivot[t.edges].sum(axis=1)
        short = t.edge_lengths - ends < shortest * (1 - 1e-9)
        least = np.where(short, shortest * (1 + 1e-6) + ends, 0.0)
        wide, also = spread_tight(t, hw, budget - _moved(t, start), fixed=fixed, least_length=least)
        if not also.size:
            break
        t, moved = wide, np.union1d(moved, also)
        node_pivot, problems = size_hubs(t, hw, shortest, longest, floor)
    return t, node_pivot, problems, moved


def resized(plan: NetPlan, node_pivot: np.ndarray) -> NetPlan:
    """The plan with hubs of pivot radii ``node_pivot`` (mm; each node's cone kept): its
    sockets back on the lines between the node points, its rods' lengths, bounds and hubs'
    masses following."""
    new = _plan(plan.target, plan.hardware, np.asarray(node_pivot, float), plan.length_range, plan.pieces)
    new = dataclasses.replace(new, merged=plan.merged, collapsed=plan.collapsed, between_anchors=plan.between_anchors,
                              added_anchors=plan.added_anchors, spread=plan.spread, node_cone=plan.node_cone)
    return replan(new, new.pivots) if plan.node_cone is not None else new


def _whole_floor(base: NetTarget, hw: NodeHardware, longest: float, whole: frozenset[int],
                 splice_all: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The edges of ``base`` on the drawn edges ``whole`` that one rod between larger hubs of
    the family spans (node to node at most the longest rod plus two of the largest pivot
    radii), (n,) the least pivot radius each node then needs: half of what the edge is
    longer than the longest rod, at each end (mm), and the straight edges of ``whole`` beyond
    that reach: one rigid rod each, spliced from pieces (:mod:`rodcad.catalog.net.splice`);
    ``splice_all``: every straight edge of ``whole`` spliced, no hub made larger."""
    one = np.zeros(base.m, dtype=bool)
    floor = np.zeros(base.n)
    if not whole or not hw.is_hub:
        return one, floor, one.copy()
    src = base.source if base.source is not None else np.arange(base.m)
    d = base.edge_lengths
    half = (d - SPLICE_MARGIN * longest) / 2
    chosen = np.isin(src, sorted(whole))
    one = chosen & (half <= hw.pivot_limits[1]) & (not splice_all)
    for e in np.flatnonzero(one):
        for k in base.edges[e]:
            floor[k] = max(floor[k], half[e])
    return one, floor, chosen & ~one & (base.bends <= 0)


def _coarser(t: NetTarget, hw: NodeHardware, shortest: float) -> str:
    """For a generated net drawn too fine: the cells whose edges the catalog can make ('' else)."""
    if t.kind not in ("surface", "radial") or not t.shape:
        return ""
    d = t.edge_lengths
    need = shortest + 2 * (hw.pivot_limits[0] if hw.is_hub else 0.0)
    if d.min() >= need:
        return ""
    f = float(d.min()) / need
    a, b = (max(1, int(np.floor(x * f))) for x in t.shape)
    keys = "net.surface.u and v" if t.kind == "surface" else "net.radial.rings and spokes"
    return (f"; the same surface with about {a} x {b} ({keys}, or fewer) would keep its edges at least "
            f"{need:.3g} mm long")


def _first_count(base: NetTarget, e: int, node_pivot: np.ndarray, rp_min: float, hi: float) -> int:
    """The pieces edge ``e`` of ``base`` needs with its end hubs' pivots and joints of the
    smallest hubs: ``k (hi + 2 rp_min) >= d - rp_i - rp_j + 2 rp_min``."""
    i, j = (int(x) for x in base.edges[e])
    d = float(np.linalg.norm(base.positions[j] - base.positions[i]))
    free = d - node_pivot[i] - node_pivot[j] + 2 * rp_min
    return pieces(free, SPLICE_MARGIN * hi + 2 * rp_min)


def _lengths(t: NetTarget, node_pivot: np.ndarray) -> np.ndarray:
    d = t.edge_lengths
    return d - node_pivot[t.edges[:, 0]] - node_pivot[t.edges[:, 1]]


def _rod_axes(t: NetTarget, node_pivot: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each rod's unit direction node to node (m, 3), its pivots from its two nodes (m, 2, 3)
    with the nodes' pivot radii ``node_pivot`` (mm) and its pivot-to-pivot length (m,)."""
    d = t.edge_lengths
    u = (t.positions[t.edges[:, 1]] - t.positions[t.edges[:, 0]]) / d[:, None]
    r = node_pivot[t.edges]
    return u, np.stack([r[:, :1] * u, -r[:, 1:] * u], axis=1), d - r.sum(axis=1)


def _plan(t: NetTarget, hw: NodeHardware, node_pivot: np.ndarray, window: tuple[float, float],
          pieces: np.ndarray | None = None) -> NetPlan:
    """The plan on a buildable target with each node's pivot radius (and its rods' pieces)."""
    edges, n = t.edges, t.n
    u, pivots, lengths = _rod_axes(t, node_pivot)
    degree = np.bincount(edges.ravel(), minlength=n)
    rods = rod_numbers(hw, lengths, t.bends, pieces)
    bounds = np.array([rn.mass_range for rn in rods], float)
    plan = NetPlan(t, hw, pivots, lengths, rods, bounds, np.zeros(n), np.zeros((n, 3)), window, degree,
                   node_pivot=np.asarray(node_pivot, float), pieces=pieces)
    dirs: list[list[np.ndarray]] = [[] for _ in range(n)]
    for e, (i, j) in enumerate(edges):
        dirs[i].append(u[e])
        dirs[j].append(-u[e])
    for k in range(n):
        plan.node_masses[k], plan.node_com[k] = plan.hub(k).hub_mass(np.asarray(dirs[k]).reshape(-1, 3))
    return plan


def node_directions(t: NetTarget, pivots: np.ndarray) -> list[np.ndarray]:
    """Per node, (k, 3) unit directions of its rods' pivots from it."""
    dirs: list[list[np.ndarray]] = [[] for _ in range(t.n)]
    for e, (i, j) in enumerate(t.edges):
        for c, k in ((0, i), (1, j)):
            p = pivots[e, c]
            nrm = float(np.linalg.norm(p))
            dirs[k].append(p / nrm if nrm > 0 else np.zeros(3))
    return [np.asarray(x, float).reshape(-1, 3) for x in dirs]


def _hung(t: NetTarget, base: NetTarget, src: np.ndarray, counts: np.ndarray, hw: NodeHardware,
          node_pivot: np.ndarray, g: float, pieces: np.ndarray) -> NetTarget:
    """The joints moved to their funicular sag, from the statics of ``base`` with each split
    edge one rod of its pieces' mass ranges and joints (:func:`rodcad.design.net.joints.hang_joints`)."""
    from optimize import design_net_masses

    rp = node_pivot[: base.n]
    _, pivots, lengths = _rod_axes(base, rp)
    full = _lengths(t, node_pivot)
    jm = t.joint_mask
    joint_mass = np.array([hw.sized(node_pivot[k]).hub_mass(np.array([[1.0, 0, 0], [-1.0, 0, 0]]))[0]
                           if jm[k] else 0.0 for k in range(t.n)])
    per_joint = float(joint_mass[jm].mean() if jm.any() else 0.0)
    bounds = np.zeros((base.m, 2))
    for e in range(base.m):
        rods = np.flatnonzero(src == e)
        for q in rods:
            bounds[e] += hw.rod_numbers(float(full[q]), int(pieces[q])).mass_range
        bounds[e] += (len(rods) - 1) * per_joint
    node_masses = np.zeros(base.n)
    dirs = node_directions(base, pivots)
    for k in range(base.n):
        node_masses[k] = hw.sized(rp[k]).hub_mass(dirs[k])[0]
    st = design_net_masses(base.positions, base.edges, lengths, bounds, base.anchored, node_masses=node_masses,
                           pivots=pivots, allow_compression=base.any_may_push, g=g, forces_only=True)
    T = st.tensions[src]
    per_piece = np.array([(st.masses[src[q]] - (counts[src[q]] - 1) * per_joint) / counts[src[q]]
                          for q in range(t.m)])
    return hang_joints(t, T, per_piece, joint_mass, g)


#: A buildable interval narrower than this (relative) is one mass; it is given this width
#: below it (the mass design's programs need a width; a microgram in a gram).
POINT_WIDTH = 1e-6


def mass_segments(hw, length: float, pieces: int = 1) -> list[tuple[float, float]]:
    """The masses a rod (of ``pieces``) can be built at (:meth:`rodcad.catalog.net.node.
    NodeHardware.rod_intervals`) as disjoint segments, ascending; a single mass given
    :data:`POINT_WIDTH` below it."""
    segs: list[list[float]] = []
    for _, lo, hi in sorted(hw.rod_intervals(length, int(pieces)), key=lambda x: x[1]):
        if hi - lo < POINT_WIDTH * hi:
            lo = hi * (1 - POINT_WIDTH)
        if segs and lo <= segs[-1][1]:
            segs[-1][1] = max(segs[-1][1], hi)
        else:
            segs.append([lo, hi])
    return [(a, b) for a, b in segs]


def replan(plan: NetPlan, pivots: np.ndarray) -> NetPlan:
    """The plan with new pivots: lengths, mass bounds and hub centres of mass follow."""
    t = plan.target
    ends = t.positions[t.edges] + pivots
    lengths = np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)
    rods = plan.numbers(lengths)
    node_com = np.zeros((t.n, 3))
    node_masses = plan.node_masses.copy()
    for k, dk in enumerate(node_directions(t, pivots)):
        node_masses[k], node_com[k] = plan.hub(k).hub_mass(dk)
    bounds = rod_bounds(plan, lengths, rods)
    return dataclasses.replace(plan, pivots=pivots, lengths=lengths, rods=rods, bounds=bounds,
                               node_masses=node_masses, node_com=node_com, com=None)


def rod_bounds(plan: NetPlan, lengths: np.ndarray, rods: list[NetRodNumbers] | None = None) -> np.ndarray:
    """(m, 2) the plan's rods' mass bounds (g) at pivot-to-pivot ``lengths`` (mm): their whole
    mass range, or the segment of buildable masses the plan holds them to (``segment``)."""
    hw = plan.hardware
    flen = fill_lengths(hw, lengths, plan.target.bends)
    if rods is None:
        rods = plan.numbers(lengths)
    bounds = np.array([r.mass_range for r in rods], float)
    if plan.segment is not None:
        for e, (L, k) in enumerate(zip(flen, plan.rod_pieces)):
            segs = mass_segments(hw, float(L), int(k))
            bounds[e] = segs[min(int(plan.segment[e]), len(segs) - 1)]
    return bounds
