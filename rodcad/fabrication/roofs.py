"""Socket roofs on shared print layers: a chain's rods pause on as few layers as they allow.

Each rod's ball sockets stand in rows, each row on one print layer (:mod:`rodcad.fabrication.layout`;
a thick graduated rod holds its balls in two rows, one above the other, symmetric about its
centre of mass), and rods of different sections put their rows at different heights on the bed: a socket's site is
the rod's centre of mass (its sockets are laid out symmetrically about it), and the bed is
under the rod's lowest point. A curved rod rests on its arc: the more it bulges downward
the deeper its arc reaches below its centre of mass (the heart's 16 mm rods, curvatures
from -0.002 to 0.017 /mm, put their roofs between 11.26 and 12.21 mm above the bed: five
0.2 mm layers, five pauses).

A roof can be raised without moving the rod's mass or centre of mass
(:func:`rodcad.fabrication.cavities.raised_rows`): the cylinder above the ball grows up
to the new roof, the socket rises with it just enough that ball and socket still act at
their site, and the plastic the taller socket takes is the cavities' to give back
(:func:`rodcad.fabrication.plan.plan_rod`). How far is bounded by the wall over the socket
and by the cavity volume the rod has to give (a rod without cavities keeps its roof).

:func:`shared_roofs` picks the layers: each row of each rod is one span, and can pause before
any layer from its own (the layer bridging its plain roof) up to the highest its bounds allow (a raised roof lies
exactly on a layer top, midway between two slicing planes); the fewest layers that serve
every rod are found greedily (interval stabbing: take the highest lowest-layer still
unserved, serve every row that can reach it, repeat), and each row takes the lowest chosen
layer it can reach, so roofs rise as little as they can. A lower row rises until its roof is
a minimum wall below the row above it: the socket lattice's pitch is two radii and a wall,
so a row directly under another cannot rise at all (its pause is fixed), while the top row
and single rows rise until the wall over them or the cavity volume ends them. A rod whose balls stand in
two rows may hold as many in one row at its centre of mass instead (same mass, its own cavity
reach: :func:`rodcad.fabrication.intervals.row_alternates`), one span where it had two, and
where that pauses less it does (the semicircle's six graduated rods: five layers, with every
row a span four, with one row where offered one). Rods with a filled shot chamber
pause at its roof: their layers are fixed points the others may join.

Units: mm, g.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from rodcad.catalog.cache import DiskCache
from rodcad.catalog.chamber import plan_chamber
from rodcad.catalog.fastgeom import RodClearance
from rodcad.fabrication.cavities import EDGE_TOL, SOLID_TOL, raised_rows, socket_rows
from rodcad.fabrication.intervals import chain_intervals, interval_table, row_alternates
from rodcad.fabrication.layers import LayerGrid
from rodcad.fabrication.layout import UP
from rodcad.fabrication.plan import MIN_REMOVE, RoofPlan, choose_balls

if TYPE_CHECKING:  # pragma: no cover
    from rodcad.catalog.model import RodType

__all__ = ["MAX_CHOICES", "RoofSpan", "roof_options", "roof_spans", "row_spans", "share_layers", "shared_roofs"]


@dataclass(frozen=True)
class RoofSpan:
    """The print layers one rod can pause before.

    Attributes:
        first: the layer that bridges its sockets as laid out (or its chamber's roof).
        last: the highest layer its raised roofs can reach (``first`` when fixed).
        floor: the bed's height in the rod frame (mm along the print's up): a bed height
            z is ``z + floor`` in the rod frame.
    """

    first: int
    last: int
    floor: float


def roof_spans(rod: RodType, mass: float, layers: LayerGrid, table: dict | None) -> list[RoofSpan]:
    """The layers each row of a rod of ``mass`` g (its designed sockets) can pause before,
    lowest row first (empty: it has no pause; see :func:`row_spans`).

    Args:
        rod: the rod type.
        mass: its target mass (g).
        layers: the print's layers.
        table: the type's table of reachable masses (None for a rod with a fill).
    """
    return roof_options(rod, mass, layers, table)[0][1]


def roof_options(rod: RodType, mass: float, layers: LayerGrid, table: dict | None,
                 alternates: Sequence[dict] = ()) -> list[tuple[np.ndarray | None, list[RoofSpan]]]:
    """The ways a rod of ``mass`` g can hold its balls, each with its rows' spans: first the
    designed sockets (None), then each of ``alternates``
    (:func:`rodcad.fabrication.intervals.row_alternates`: as many balls of the same kind in
    one row, for the same mass without cavities) whose cavities reach the mass (its socket
    centres, mm)."""
    floor = RodClearance(rod.geometry).bounds[0][1]
    if rod.fill is not None:
        chamber, _, _ = plan_chamber(rod, mass)
        if chamber is None or not chamber.filled:
            return [(None, [])]
        k = layers.bridging_layer(chamber.roof_y - floor)
        return [(None, [RoofSpan(k, k, floor)])]
    if table is None:
        return [(None, [])]
    choice = choose_balls(rod, mass, table)
    socks, rs, kind, remove = choice.sockets, choice.socket_radius, choice.kind, choice.remove
    out: list[tuple[np.ndarray | None, list[RoofSpan]]] = [(None, row_spans(rod, socks, rs, kind, remove, layers))]
    if len(socket_rows(socks)) < 2:
        return out
    for alt in alternates:
        row = np.asarray(alt["sockets"], dtype=float).reshape(-1, 3)
        if len(row) != len(socks) or int(alt["kind"]) != kind or abs(float(alt["socket_radius"]) - rs) > 1e-9:
            continue
        solid = abs(alt["mass"] - choice.build_mass) <= SOLID_TOL * choice.build_mass and remove <= 0
        if solid or any(a * (1 - EDGE_TOL) <= choice.build_mass <= b * (1 + EDGE_TOL) for a, b in alt["pieces"]):
            out.append((row, row_spans(rod, row, rs, kind, remove, layers)))
    return out


def row_spans(rod: RodType, sockets: np.ndarray, socket_r: float, kind: int, remove: float,
              layers: LayerGrid) -> list[RoofSpan]:
    """The layers each row of these sockets can pause before, lowest row first.

    A row's span ends where raising its roof further would leave less than the minimum wall
    to the rod's faces or to the sockets of another row (kept as laid out: the row above a
    raised one only rises with its own roof), or would take more plastic than the cavities
    (``remove`` mm^3 beside the plain sockets) have to give: that volume is split among the
    rows that can rise, by their socket counts.
    """
    floor = RodClearance(rod.geometry).bounds[0][1]
    socks, rs = np.asarray(sockets, dtype=float).reshape(-1, 3), socket_r
    if not len(socks):
        return []
    rows = socket_rows(socks)
    plain = [float(socks[idx[0]] @ UP) + rs for idx in rows]

    def reach(j: int, tallest: float) -> RoofSpan:
        first = layers.bridging_layer(plain[j] - floor)
        last = first
        while last < first + 1000:  # the walls over the sockets end it long before
            top = layers.top(last) + floor  # a roof on this layer's top is bridged by the next
            roofs = [top if i == j else plain[i] for i in range(len(rows))]
            raised = raised_rows(rod, socks, rs, kind, roofs) if top > plain[j] else None
            if raised is None or float(raised[1][rows[j]].max()) > tallest:
                break
            last += 1
        return RoofSpan(first, last, floor)

    walls = [reach(j, math.inf) for j in range(len(rows))]
    movable = [j for j, s in enumerate(walls) if s.last > s.first]
    give = max(remove - MIN_REMOVE, 0.0)  # cavity volume the taller sockets may take over
    count = sum(len(rows[j]) for j in movable)
    return [reach(j, rs + give / (count * math.pi * rs * rs)) if j in movable else walls[j]
            for j in range(len(rows))]


def share_layers(spans: Sequence[RoofSpan | None]) -> list[int | None]:
    """The layer each span pauses before, on the fewest layers that serve them all (see the
    module's doc); None where the span is None."""
    left = sorted((i for i, s in enumerate(spans) if s is not None), key=lambda i: -spans[i].first)
    chosen: list[int] = []
    while left:
        k = spans[left[0]].first
        chosen.append(k)
        left = [i for i in left if not spans[i].first <= k <= spans[i].last]
    out: list[int | None] = []
    for s in spans:
        out.append(None if s is None else min(k for k in chosen if s.first <= k <= s.last))
    return out


def shared_roofs(types: Sequence[RodType], masses: Sequence[float], layers: LayerGrid, *, seed: int = 0,
                 jobs: int | None = None, cache: DiskCache | None = None,
                 keep: Collection[int] = ()) -> list[RoofPlan | None]:
    """Per chain position, where to put its sockets' roofs (:class:`RoofPlan`: per row of
    sockets, lowest first, the top of the layer below the one that bridges it, or -inf to keep
    the row as laid out; and the sockets in one row instead of the designed rows where that
    pauses less), or None to keep the designed sockets as laid out, so that the chain pauses
    on the fewest layers (:func:`share_layers`, every row of every rod one span).

    Where a rod's balls stand in two rows, the same balls in one row
    (:func:`rodcad.fabrication.intervals.row_alternates`) are tried too: every combination
    for up to :data:`MAX_CHOICES` distinct rods with a choice, else one rod at a time while
    it helps; the fewest layers win, then the fewest rods off their designed layout.

    Args:
        types: rod type per chain position.
        masses: target mass per position (g).
        layers: the print's layers (:class:`rodcad.fabrication.layers.LayerGrid`).
        seed: seed of the cavity layouts (the tables of reachable masses).
        jobs: worker processes for the tables not yet cached.
        cache: disk cache.
        keep: positions whose sockets stay as laid out and take no part (the rods of a
            fused piece, whose print orientation is the piece's).
    """
    cache = cache if cache is not None else DiskCache()
    balls = [rod for i, rod in enumerate(types) if rod.fill is None and rod.balls is not None and i not in keep]
    if balls:
        chain_intervals(balls, seed=seed, jobs=jobs, cache=cache)
    tables = {rod.name: interval_table(rod, seed, cache) for rod in balls}
    memo: dict[tuple[str, float], list[tuple[np.ndarray | None, list[RoofSpan]]]] = {}
    where: list[tuple[str, float] | None] = []
    for i, (rod, m) in enumerate(zip(types, masses)):
        key = (rod.name, round(float(m), 6))
        if i in keep:
            where.append(None)
            continue
        if key not in memo:
            table = tables.get(rod.name)
            multi = table is not None and any(np.ptp(np.reshape(o["sockets"], (-1, 3)) @ UP) > 1e-6
                                              for o in table["options"] if len(o["sockets"]))
            alts = row_alternates(rod, seed, cache) if multi else []
            memo[key] = roof_options(rod, float(m), layers, table, alts)
        where.append(key)
    free = [k for k, opts in memo.items() if len(opts) > 1]

    def layout(pick: dict[tuple[str, float], int]) -> tuple[tuple[int, int], list[int | None]]:
        spans = [s for k in where if k is not None for s in memo[k][pick.get(k, 0)][1]]
        got = share_layers(spans)
        return (len({k for k in got if k is not None}), sum(1 for v in pick.values() if v)), got

    if len(free) <= MAX_CHOICES:
        picks = [dict(zip(free, c)) for c in itertools.product(*(range(len(memo[k])) for k in free))]
        pick = min(picks, key=lambda p: layout(p)[0])
    else:
        pick = {}
        for k in free:
            trial = min(({**pick, k: v} for v in range(len(memo[k]))), key=lambda p: layout(p)[0])
            pick = trial
    chosen = iter(layout(pick)[1])
    out: list[RoofPlan | None] = []
    for k in where:
        if k is None:
            out.append(None)
            continue
        row, spans = memo[k][pick.get(k, 0)]
        ks = [next(chosen) for _ in spans]
        if row is None and all(j == s.first for s, j in zip(spans, ks)):
            out.append(None)
            continue
        out.append(RoofPlan(tuple(layers.top(j - 1) + s.floor if j != s.first else -math.inf
                                  for s, j in zip(spans, ks)),
                            None if row is None else tuple(tuple(float(v) for v in p) for p in row)))
    return out


#: Distinct rods with a choice of socket layouts up to which every combination is tried.
MAX_CHOICES = 10
