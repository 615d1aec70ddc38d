"""Socket roofs on shared print layers: a chain's rods pause on as few layers as they allow.

Each rod's ball sockets stand in one row on one print layer (:mod:`rodcad.fabrication.layout`),
but rods of one section put that row at different heights on the bed: a socket's site is
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

:func:`shared_roofs` picks the layers: each rod can pause before any layer from its own
(the layer bridging its plain roof) up to the highest its bounds allow (a raised roof lies
exactly on a layer top, midway between two slicing planes); the fewest layers that serve
every rod are found greedily (interval stabbing: take the highest lowest-layer still
unserved, serve every rod that can reach it, repeat), and each rod takes the lowest chosen
layer it can reach, so roofs rise as little as they can. Rods with a filled shot chamber
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
from rodcad.fabrication.cavities import raised_sockets
from rodcad.fabrication.intervals import chain_intervals, interval_table
from rodcad.fabrication.layers import LayerGrid
from rodcad.fabrication.layout import UP
from rodcad.fabrication.plan import MIN_REMOVE, choose_balls

if TYPE_CHECKING:  # pragma: no cover
    from rodcad.catalog.model import RodType

__all__ = ["RoofSpan", "roof_span", "share_layers", "shared_roofs"]


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


def roof_span(rod: RodType, mass: float, layers: LayerGrid, table: dict | None) -> RoofSpan | None:
    """The layers a rod of ``mass`` g can pause before (None: it has no pause).

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
            return None
        k = layers.bridging_layer(chamber.roof_y - floor)
        return RoofSpan(k, k, floor)
    if table is None:
        return None
    choice = choose_balls(rod, mass, table)
    socks, rs = choice.sockets, choice.socket_radius
    if not len(socks):
        return None
    roof = float((socks @ UP).max()) + rs
    first = layers.bridging_layer(roof - floor)
    if np.ptp(socks @ UP) > 1e-9:  # several rows: each keeps its layer
        return RoofSpan(first, first, floor)
    give = choice.remove - MIN_REMOVE  # cavity volume the taller sockets may take over
    tallest = rs + max(give, 0.0) / (len(socks) * math.pi * rs * rs)
    last = first
    while last < first + 1000:  # the wall over the sockets ends it long before
        top = layers.top(last) + floor  # a roof on this layer's top is bridged by the next
        raised = raised_sockets(rod, socks, rs, choice.kind, top) if top > roof else None
        if raised is None or raised[1] > tallest:
            break
        last += 1
    return RoofSpan(first, last, floor)


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
                 keep: Collection[int] = ()) -> list[float | None]:
    """Per chain position, where to put its sockets' roofs (mm along the print's up, rod
    frame: the top of the layer below the one that bridges them), or None to keep them as
    laid out, so that the chain pauses on the fewest layers (:func:`share_layers`).

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
    spans: list[RoofSpan | None] = []
    memo: dict[tuple[str, float], RoofSpan | None] = {}
    for i, (rod, m) in enumerate(zip(types, masses)):
        key = (rod.name, round(float(m), 6))
        if i in keep:
            spans.append(None)
            continue
        if key not in memo:
            memo[key] = roof_span(rod, float(m), layers, tables.get(rod.name))
        spans.append(memo[key])
    out: list[float | None] = []
    for span, k in zip(spans, share_layers(spans)):
        out.append(None if span is None or k is None or k == span.first else layers.top(k - 1) + span.floor)
    return out
