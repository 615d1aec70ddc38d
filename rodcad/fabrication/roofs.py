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
(:func:`rodcad.fabrication.cavities.raised_sockets`): the cylinder above the ball grows up
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
and single rows rise until the wall over them or the cavity volume ends them. Rods with a filled shot chamber
pause at its roof: their layers are fixed points the others may join.

Units: mm, g.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from rodcad.catalog.cache import DiskCache
from rodcad.catalog.chamber import plan_chamber
from rodcad.catalog.fastgeom import RodClearance
from rodcad.fabrication.cavities import raised_rows, socket_rows
from rodcad.fabrication.intervals import chain_intervals, interval_table
from rodcad.fabrication.layers import LayerGrid
from rodcad.fabrication.layout import UP
from rodcad.fabrication.plan import MIN_REMOVE, choose_balls

if TYPE_CHECKING:  # pragma: no cover
    from rodcad.catalog.model import RodType

__all__ = ["RoofSpan", "roof_spans", "share_layers", "shared_roofs"]


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
    """The layers each row of a rod of ``mass`` g can pause before, lowest row first (empty:
    it has no pause).

    A row's span ends where raising its roof further would leave less than the minimum wall
    to the rod's faces or to the sockets of another row (kept as laid out: the row above a
    raised one only rises with its own roof), or would take more plastic than the cavities
    have to give: that volume is split among the rows that can rise, by their socket counts.

    Args:
        rod: the rod type.
        mass: its target mass (g).
        layers: the print's layers.
        table: the type's table of reachable masses (None for a rod with a fill).
    """
    floor = RodClearance(rod.geometry).bounds[0][1]
    if rod.fill is not None:
        chamber, _, _ = plan_chamber(rod, mass)
        if chamber is None or not chamber.filled:
            return []
        k = layers.bridging_layer(chamber.roof_y - floor)
        return [RoofSpan(k, k, floor)]
    if table is None:
        return []
    choice = choose_balls(rod, mass, table)
    socks, rs = choice.sockets, choice.socket_radius
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
            raised = raised_rows(rod, socks, rs, choice.kind, roofs) if top > plain[j] else None
            if raised is None or float(raised[1][rows[j]].max()) > tallest:
                break
            last += 1
        return RoofSpan(first, last, floor)

    walls = [reach(j, math.inf) for j in range(len(rows))]
    movable = [j for j, s in enumerate(walls) if s.last > s.first]
    give = max(choice.remove - MIN_REMOVE, 0.0)  # cavity volume the taller sockets may take over
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
                 keep: Collection[int] = ()) -> list[tuple[float, ...] | None]:
    """Per chain position, where to put its sockets' roofs (mm along the print's up, rod
    frame), one per row of sockets, lowest first (a raised row's roof: the top of the layer
    below the one that bridges it; a row kept as laid out: -inf), or None to keep
    every row as laid out, so that the chain pauses on the fewest layers
    (:func:`share_layers`, every row of every rod one span).

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
    rows: list[list[RoofSpan]] = []
    memo: dict[tuple[str, float], list[RoofSpan]] = {}
    for i, (rod, m) in enumerate(zip(types, masses)):
        key = (rod.name, round(float(m), 6))
        if i in keep:
            rows.append([])
            continue
        if key not in memo:
            memo[key] = roof_spans(rod, float(m), layers, tables.get(rod.name))
        rows.append(memo[key])
    flat = [s for spans in rows for s in spans]
    chosen = iter(share_layers(flat))
    out: list[tuple[float, ...] | None] = []
    for spans in rows:
        ks = [next(chosen) for _ in spans]
        if all(k == s.first for s, k in zip(spans, ks)):
            out.append(None)
            continue
        out.append(tuple(layers.top(k - 1) + s.floor if k != s.first else -math.inf for s, k in zip(spans, ks)))
    return out
