"""A bent net rod's solid: its round body along an arc between the balls at its pivots.

The geometry is :mod:`rodcad.catalog.net.bend`'s (numbers only; here the B-rep): in the rod's
frame (x from its first pivot to its second, ``length`` apart) the body is the tube of the
rod's radius about the arc through the body's ends on the chord, bowing toward -z, cut square
to the arc (a torus segment: a disc revolved about the arc's axis); each end is a ball at its
pivot and a neck along x from the ball into the body's tilted end face. Inside, the steel
balls' spherical sockets sit on the arc in a row at mid-arc and the cavity is one or two tube
segments of radius ``rod_diameter / 2 - min_wall`` beside them, as on a straight rod measured
along the arc. Placed with its frame's z up (:func:`rodcad.cad.net.solids.write_net_files`), the
rod bows down in the vertical plane through its chord: the pose it hangs in.
"""

from __future__ import annotations

import math

import numpy as np
from build123d import Axis, Face, Plane, Solid, Wire

from rodcad.cad.net.solids import end_ball
from rodcad.cad.solids import one_solid
from rodcad.catalog.net.bend import NetRodArc, ball_row

__all__ = ["bent_rod_solid", "bent_socket_centres"]


def _tube(arc: NetRodArc, radius: float, t0: float, t1: float) -> Solid:
    """The tube of ``radius`` about the arc between arc angles t0 < t1 (rad), cut square to it."""
    c = arc.centre
    p = c + arc.radius * np.array([math.sin(t0), 0.0, -math.cos(t0)])
    tangent = (math.cos(t0), 0.0, math.sin(t0))
    disc = Face(Wire.make_circle(radius, Plane(tuple(float(v) for v in p), z_dir=tangent)))
    # a turn about -y increases the arc angle (x = sin t, z = -cos t about the centre)
    axis = Axis(tuple(float(v) for v in c), (0.0, -1.0, 0.0))
    return Solid.revolve(disc, math.degrees(t1 - t0), axis)


def bent_socket_centres(hw, arc: NetRodArc, balls: int) -> np.ndarray:
    """(balls, 3) the steel balls' centres on the arc (rod frame, mm)."""
    return arc.point(ball_row(hw, arc.fill_length, balls)).reshape(-1, 3)


def bent_rod_solid(hw, arc: NetRodArc, balls: int, cavity: float, name: str = "rod") -> Solid:
    """One bent net rod in its frame (see the module docstring).

    Args:
        hw: the node hardware (ball, neck, rod diameter, walls, steel balls).
        arc: the rod's arc (:func:`rodcad.catalog.net.bend.rod_arc`).
        balls: steel balls in closed sockets in a row at mid-arc.
        cavity: the cavity's volume (mm^3), as
            :meth:`rodcad.catalog.net.node.NodeHardware.rod_fill` of the arc's fill length gives it.
    """
    r, w = hw.rod_diameter / 2, hw.min_wall
    psi, L, Lf = arc.half_angle, arc.length, arc.fill_length
    parts = [_tube(arc, r, -psi, psi)]
    if hw.is_hub:
        e = hw.end_offset
        reach = e + (hw.neck / 2) * math.tan(psi) + 0.5  # past the tilted face everywhere
        for x0, d in ((0.0, 1.0), (L, -1.0)):
            parts.append(end_ball(hw, x0, d))
            parts.append(Solid.make_cylinder(hw.neck / 2, reach, Plane((x0, 0, 0), z_dir=(d, 0, 0))))
    solid = parts[0] if len(parts) == 1 else one_solid(parts[0].fuse(*parts[1:]).clean(), "joining a bent rod's ends")
    ds = hw.insert_diameter + hw.insert_clearance
    voids = [Solid.make_sphere(ds / 2, Plane(tuple(float(v) for v in c)))
             for c in bent_socket_centres(hw, arc, balls)]
    area = math.pi * (r - w) ** 2
    if cavity > 1e-3 * area:
        row = balls * ds + max(balls - 1, 0) * w
        if balls:
            each = cavity / 2 / area
            spans = [(Lf / 2 + row / 2 + w, Lf / 2 + row / 2 + w + each), (Lf / 2 - row / 2 - w - each, Lf / 2 - row / 2 - w)]
        else:
            lc = cavity / area
            spans = [(Lf / 2 - lc / 2, Lf / 2 + lc / 2)]
        for x0, x1 in spans:
            voids.append(_tube(arc, r - w, float(arc.angle(x0)), float(arc.angle(x1))))
    if voids:
        solid = one_solid(solid.cut(*voids), "cutting a bent rod's cavity and ball sockets")
    solid.label = name
    return solid
