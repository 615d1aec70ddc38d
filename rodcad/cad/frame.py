"""Frame solids of a chandelier (rings, bars, hinge lugs) and pins.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from build123d import Plane, Solid

from rodcad.cad.export import placed
from rodcad.cad.solids import GeometryError, cylinder_solid, one_solid, prism_solid

__all__ = ['bar_parts', 'frame_solid', 'lug_parts', 'one_part', 'pin_solid']


def pin_solid(diameter: float, length: float) -> Solid:
    """A hinge pin: a cylinder of ``diameter`` along +z from z = 0 to ``length`` (mm)."""
    return cylinder_solid((0.0, 0.0), diameter / 2, 0.0, length)


def one_part(shape: object, step: str, part: str = "frame") -> Solid:
    """:func:`rodcad.cad.solids.one_solid` for a printed part other than a rod (its
    messages name the ``part``)."""
    try:
        return one_solid(shape, step)
    except GeometryError as err:
        raise GeometryError(str(err).replace("one rod", f"one {part}")) from None


def bar_parts(points: np.ndarray, radius: float, z0: float, z1: float) -> list[Solid]:
    """A round-ended bar of half-width ``radius`` along an xy polyline, from z0 to z1
    (separate solids; no round end at the last point)."""
    parts = [cylinder_solid(points[0], radius, z0, z1)]
    for p, q in zip(points[:-1], points[1:]):
        d = q - p
        length = float(np.hypot(*d))
        if length < 1e-9:
            continue
        n = np.array([-d[1], d[0]]) / length * radius
        parts.append(prism_solid([p + n, q + n, q - n, p - n], z0, z1))
        parts.append(cylinder_solid(q, radius, z0, z1))
    return parts[:-1] if len(parts) > 1 else parts  # no round end at the member


def lug_parts(lug: object) -> list[Solid]:
    """The lug's knuckle and arm as separate solids in its lug frame (see ``LugSpec``).

    Tongue: the middle layer ``|z| <= tongue_thickness / 2`` (the rod's fork takes
    the outer layers). Fork (a clevis): two prong discs of ``knuckle_radius`` from
    ``tongue_thickness / 2 + layer_gap`` out to the cheeks, and the arm in two
    cheeks from ``thickness / 2 + layer_gap`` outward (``cheek`` thick), outside the
    rod's thickness, so the rod clears it at every angle.
    """
    h = lug.hinge  # type: ignore[attr-defined]
    t = float(lug.thickness)  # type: ignore[attr-defined]
    kr = h.knuckle_radius
    a = h.tongue_thickness / 2
    gap = h.layer_gap
    pts = np.asarray(lug.arm_points(), dtype=float)  # type: ignore[attr-defined]
    if lug.knuckle == "tongue":  # type: ignore[attr-defined]
        return bar_parts(pts, kr, -a, a)
    if lug.knuckle != "fork":  # type: ignore[attr-defined]
        raise GeometryError(f"lug knuckle must be 'fork' or 'tongue', not {lug.knuckle!r}")  # type: ignore[attr-defined]
    c = float(lug.cheek)  # type: ignore[attr-defined]
    if c <= 0:
        raise GeometryError("the hinge leaves no room for fork prongs")
    zo = t / 2 + gap
    parts = [cylinder_solid((0, 0), kr, a + gap, zo + c), cylinder_solid((0, 0), kr, -zo - c, -a - gap)]
    return parts + bar_parts(pts, kr, zo, zo + c) + bar_parts(pts, kr, -zo - c, -zo)


def _members(kind: str, p: dict) -> list[Solid]:
    w, t = float(p["width"]), float(p["thickness"])
    if kind == "ring":
        cx, cy = p["center"]
        r = float(p["radius"])
        outer = cylinder_solid((cx, cy), r + w / 2, p["z"], p["z"] + t)
        if r - w / 2 <= 0:
            return [outer]
        return [one_part(outer.cut(cylinder_solid((cx, cy), r - w / 2, p["z"] - 1, p["z"] + t + 1)),
                         "cutting the ring's hole")]
    if kind == "two_rings":
        c = np.asarray(p["center"], dtype=float)
        hub = cylinder_solid(c, p["hub_radius"], p["hub_z"], p["hub_z"] + t)
        rr = float(p["ring_radius"])
        ring = cylinder_solid(c, rr + w / 2, p["ring_z"], p["ring_z"] + t)
        if rr - w / 2 > 0:
            ring = one_part(ring.cut(cylinder_solid(c, rr - w / 2, p["ring_z"] - 1, p["ring_z"] + t + 1)),
                            "cutting the bottom ring's hole")
        out = [hub, ring]
        sd = float(p["strut_diameter"])
        for k in range(int(p["struts"])):
            ang = math.radians(p["strut_start_deg"]) + 2 * math.pi * k / int(p["struts"])
            u = np.array([math.cos(ang), math.sin(ang)])
            p0 = np.array([*(c + (p["hub_radius"] - sd / 2) * u), p["hub_z"] + t / 2])
            p1 = np.array([*(c + rr * u), p["ring_z"] + t / 2])
            d = p1 - p0
            length = float(np.linalg.norm(d))
            out.append(Solid.make_cylinder(sd / 2, length, Plane(tuple(p0), z_dir=tuple(d / length))))
        return out
    if kind == "bars":
        v = np.asarray(p["vertices"], dtype=float)
        edges = [(0, 1)] if len(v) == 2 else [(i, (i + 1) % len(v)) for i in range(len(v))]
        out = [cylinder_solid(x[:2], w / 2, x[2] - t / 2, x[2] + t / 2) for x in v]
        for i, j in edges:
            e = v[j] - v[i]
            length = float(np.linalg.norm(e))
            u = e / length
            side = np.cross([0.0, 0.0, 1.0], u)
            side /= np.linalg.norm(side)
            up = np.cross(u, side)
            origin = v[i] - side * w / 2 - up * t / 2
            out.append(Solid.make_box(length, w, t, Plane(tuple(origin), x_dir=tuple(u), z_dir=tuple(up))))
        return out
    raise GeometryError(f"unknown frame kind {kind!r}; one of ring, two_rings, bars")


def frame_solid(kind: str, params: dict, lugs: Sequence[object]) -> Solid:
    """The chandelier frame: its members plus a hinge lug at every anchor, one solid.

    Members (``params``, mm):

    * ``'ring'``: a flat annulus, ``center`` (x, y), centre-line ``radius``,
      ``width``, ``thickness``, bottom face at height ``z``;
    * ``'two_rings'``: a hub disc (``hub_radius``, bottom face at ``hub_z``) and an
      annulus (``ring_radius`` centre line, bottom face at ``ring_z``), both
      ``width`` x ``thickness``, joined by ``struts`` round struts of
      ``strut_diameter`` starting at ``strut_start_deg`` around ``center``;
    * ``'bars'``: flat bars ``width`` (horizontal) x ``thickness`` between
      consecutive ``vertices`` (their mid-line points, a closed polygon for 3 or
      more), with a round node at each vertex.

    Lugs: objects like :class:`rodcad.design.frame.LugSpec` (``location`` 4x4 lug
    frame -> world, ``knuckle``, ``thickness``, ``hinge``, ``cheek``, ``width``,
    ``arm_points()``), built by :func:`lug_parts` and moved into place; every
    lug's arm ends on the mid-plane of its member. Each lug gets a pin hole of its
    ``pin_hole`` diameter along the lug frame's z axis, through ``hole_offset`` (the
    anchor, or where the loaded pin puts it on the anchor).

    Raises:
        GeometryError: a boolean step leaves no single valid solid (e.g. a lug arm
            that misses its member, named in the message).
    """
    members = _members(kind, params)
    body = members[0]
    if len(members) > 1:
        body = one_part(body.fuse(*members[1:]).clean(), f"joining the {kind} frame's members")
    for lug in lugs:
        parts = [placed(s, lug.location) for s in lug_parts(lug)]  # type: ignore[attr-defined]
        body = one_part(body.fuse(*parts).clean(),
                            f"joining lug {lug.name} to the frame (does its arm reach a member?)")  # type: ignore[attr-defined]
    holes = []
    for lug in lugs:
        half = float(lug.width) / 2 + 1.0  # type: ignore[attr-defined]
        hole = cylinder_solid(tuple(lug.hole_offset), lug.pin_hole / 2, -half, half)  # type: ignore[attr-defined]
        holes.append(placed(hole, lug.location))  # type: ignore[attr-defined]
    if holes:
        body = one_part(body.cut(*holes).clean(), "drilling the lugs' pin holes")
    body.label = "frame"
    return body
