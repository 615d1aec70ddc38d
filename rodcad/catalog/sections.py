"""Graduated rods' sections: how far a rod keeps its family's section behind each hinge axis,
the rod with its body's section scaled, and the largest body scale a rod's ends allow
(numbers only; :class:`rodcad.catalog.model.RodGeometry` describes the fields read here).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

__all__ = ["CURVED_BODY", "end_reach", "graduated", "max_body_scale"]

#: ``g`` below is a :class:`rodcad.catalog.model.RodGeometry` (not imported: model imports this).
RodGeometry = Any


def end_reach(g: RodGeometry, min_wall: float) -> tuple[float, float]:
    """How far behind each hinge axis a graduated rod keeps its family's section (mm): past
    its top end face's far corner (a lower body steps down only behind it, so the end faces
    and stops stay whole) and past the hinge zone, plus the minimum wall."""
    out = []
    for e in (g.first, g.second):
        corner = e.setback + g.height / 2 * max(math.tan(math.radians(e.top_chamfer)), 0.0)
        out.append(max(corner, e.setback, g.hinge.zone_radius) + min_wall)
    return (out[0], out[1])


def graduated(g: RodGeometry, scale: float, min_wall: float) -> RodGeometry:
    """The rod ``g`` (the family's section) with its body's section scaled by ``scale``
    (see :class:`RodGeometry`: the hinge ends stay ``g``'s)."""
    if scale == 1.0:
        return g
    return dataclasses.replace(g, body_height=g.height * scale, body_thickness=g.thickness * scale,
                               end_reach=end_reach(g, min_wall))


#: A curved graduated rod's body is at most this fraction of its arc's radius high.
CURVED_BODY = 0.8


def max_body_scale(g: RodGeometry, min_wall: float) -> float:
    """The largest body scale (at least 1) at which a rod of ``g``'s length, curvature and ends
    keeps at least ``min_wall`` of top edge between its two top end faces (a higher body
    makes them reach higher; on a curved rod the chord of the top side), and a curved rod's
    body at most :data:`CURVED_BODY` of its radius high. A lower body keeps the family's ends: every scale up to 1."""
    # a face leaning forward (negative chamfer) reaches over the partner as far as one leaning
    # back cuts into the top: count both
    tans = sum(abs(math.tan(math.radians(e.top_chamfer))) for e in (g.first, g.second))
    setbacks = g.first.setback + g.second.setback
    if g.curvature == 0:
        arc, bend = g.length, 0.0
    else:  # the chord of the top side's arc (the inner side's for k > 0): shorter than its arc
        arc, bend = g.length, g.length * g.curvature
    # the top side at offset w spans (L - L k w); the faces take setback + w tan(chamfer)
    den = tans + bend
    scale = math.inf
    if den > 0:
        w = (arc - setbacks - min_wall) / den
        scale = (w + g.height / 2) / g.height
    if g.curvature:  # a body higher than 0.8 of its radius leaves too tight an inner side
        scale = min(scale, CURVED_BODY * (1 / abs(g.curvature)) / g.height)
    return max(1.0, scale)
