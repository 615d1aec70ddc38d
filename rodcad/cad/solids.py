"""Exact rod solids and the kernel queries on them (build123d / OCP).

This is the only module of rodcad that imports build123d or OCP; everything
else works with the plain parameters of :class:`rodcad.catalog.model.RodGeometry` and
the results returned here.

A rod is built in the rod frame (first hinge axis through the origin, second
through (length, 0, 0), axes along +z, chain plane xy) as:

1. the body: a bar of section height x thickness along the centreline (a
   straight segment, or an arc of the given curvature through both hinge axes,
   continued by straight tangent stubs past them);
2. the end faces: per end, a top (+y) and a bottom half-plane through the point
   ``setback`` behind the hinge axis, tilted by the chamfer angles
   (:class:`rodcad.catalog.model.EndShape`); everything beyond them is cut off;
3. the hinge: a tongue knuckle (disc of ``knuckle_radius`` in the middle layer)
   at one end and a fork (two discs in the outer layers) at the other; around
   each axis the layers the partner's knuckle uses are cleared out to the
   hinge-zone radius ``knuckle_radius + radial_gap``, so two joined rods never
   touch inside the hinge zone at any angle;
4. the pin holes (pins are separate parts).

Every boolean step is followed by a validity check. All lengths in mm, angles in
degrees unless a name says ``_rad``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np
from build123d import CenterOf, Edge, Face, Location, Plane, Solid, Vector, Wire

from rodcad.catalog.model import RodGeometry, RodType
from rodcad.errors import InputError

__all__ = [
    "PortableSolid",
    "share_type_solid",
    "CONTACT_TOL",
    "build_rod",
    "collision_proxy",
    "cylinder_solid",
    "GeometryError",
    "hinge_zone",
    "is_valid_solid",
    "Holes",
    "mass_properties",
    "MassProperties",
    "NO_SHIFT",
    "one_solid",
    "prism_solid",
    "rod_solid",
    "type_solid",
    "void_solids",
    "void_template",
    "with_spherical_voids",
    "with_voids",
    "hole_volume_change",
    "OWN_SIZES",
    "Sizes",
]


#: Distances at or below this count as contact (mm).
CONTACT_TOL = 1e-6

#: Pin holes moved off the hinge axes, ((dx0, dy0), (dx1, dy1)) mm in the rod frame.
Holes = tuple[tuple[float, float], tuple[float, float]]

#: Both pin holes on their hinge axes.
NO_SHIFT: Holes = ((0.0, 0.0), (0.0, 0.0))

#: The pin holes' diameters at the first and second joint (mm); None: the hinge's own
#: (``pin_diameter + pin_clearance``). Joint hardware with a sleeve or bearings has a wider
#: hole in its tongue, a thinner pin thinner holes (:mod:`rodcad.catalog.pins`).
Sizes = tuple[float | None, float | None]

#: Both pin holes the hinge's own.
OWN_SIZES: Sizes = (None, None)


def hole_volume_change(g: RodGeometry, sizes: Sizes) -> float:
    """Plastic (mm^3) the holes ``sizes`` remove beyond the hinge's own holes (negative where
    they are narrower): each hole cuts its knuckle's layers only (the tongue's, or the
    fork's two prongs), the rest of the hinge zone being clear already."""
    hg = g.hinge
    d0 = hg.hole_diameter
    out = 0.0
    for joint, d in enumerate(sizes):
        if d is None:
            continue
        layer = hg.tongue_thickness if hg.knuckle(joint) == "tongue" else \
            g.thickness - hg.tongue_thickness - 2 * hg.layer_gap
        out += math.pi / 4 * (d * d - d0 * d0) * layer
    return out


class GeometryError(ValueError):
    """The parameters make no valid solid."""


def prism_solid(points: Sequence[Sequence[float]], z0: float, z1: float) -> Solid:
    """Extrude a closed xy polygon from z0 to z1."""
    wire = Wire.make_polygon([Vector(p[0], p[1], z0) for p in points], close=True)
    return Solid.extrude(Face(wire), Vector(0, 0, z1 - z0))


def cylinder_solid(center: Sequence[float], radius: float, z0: float, z1: float) -> Solid:
    return Solid.make_cylinder(radius, z1 - z0, Plane((center[0], center[1], z0)))


def one_solid(shape: object, step: str) -> Solid:
    """The single valid solid ``shape`` should be after ``step``."""
    solids = shape.solids()  # type: ignore[attr-defined]
    if len(solids) != 1:
        raise GeometryError(f"{step} leaves {len(solids)} separate pieces instead of one rod")
    solid = solids[0]
    if not solid.is_valid:
        raise GeometryError(f"{step} gives an invalid solid")
    return solid


def _frame(g: RodGeometry, joint: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pin position P, outward tangent u and the rod's +y normal v at a joint."""
    p, u, v = g.frame(joint)
    return np.array(p), np.array(u), np.array(v)


def _stub_length(g: RodGeometry) -> float:
    """How far the raw body continues past each hinge axis before the end cut."""
    return g.stub


def _band(g: RodGeometry, lo: float, hi: float, z0: float, z1: float) -> Solid:
    """The raw bar between offsets ``lo`` and ``hi`` (mm, toward +y) from the centreline,
    from z0 to z1: a straight bar, or the band around the arc, plus straight stubs past the axes."""
    L = g.length
    stub = _stub_length(g)
    if g.curvature == 0:
        return Solid.make_box(L + 2 * stub, hi - lo, z1 - z0, Plane((-stub, lo, z0)))
    # one outline (stub, arc, stub on each side) extruded once: no seam where the arc meets
    # its stubs, which a cut through the hinge axis would otherwise leave as a sliver
    rho = 1 / abs(g.curvature)
    sigma = 1 if g.curvature > 0 else -1
    psi = math.radians(abs(g.half_angle_deg))
    mid_y = sigma * rho * math.cos(psi) - sigma * rho  # the centreline arc's middle
    p0, u0, v0 = _frame(g, 0)
    p1, u1, v1 = _frame(g, 1)

    def pt(x: np.ndarray) -> Vector:
        return Vector(float(x[0]), float(x[1]), z0)

    edges = []
    for side in (1, -1):
        a, b = (p0, p1) if side > 0 else (p1, p0)
        ua, va, ub, vb = (u0, v0, u1, v1) if side > 0 else (u1, v1, u0, v0)
        off, other = (hi, lo) if side > 0 else (lo, hi)
        mid = np.array([L / 2, mid_y + off])
        edges.append(Edge.make_line(pt(a + ua * stub + va * off), pt(a + va * off)))
        edges.append(Edge.make_three_point_arc(pt(a + va * off), pt(mid), pt(b + vb * off)))
        edges.append(Edge.make_line(pt(b + vb * off), pt(b + ub * stub + vb * off)))
        edges.append(Edge.make_line(pt(b + ub * stub + vb * off), pt(b + ub * stub + vb * other)))
    return one_solid(Solid.extrude(Face(Wire(edges)), Vector(0, 0, z1 - z0)), "the curved body")


def _blocks(g: RodGeometry, joints: Sequence[int], z0: float, z1: float) -> list[Solid]:
    """Prisms holding the rod's ends within ``end_reach`` of the given joints' axes."""
    rects = g.end_blocks()
    return [prism_solid(rects[j], z0, z1) for j in joints]


def _outline(g: RodGeometry, z0: float, z1: float, blocks: Sequence[int] = (0, 1)) -> Solid:
    """The body's outline in the chain plane (before the end cuts) from z0 to z1: a rod of
    one section is its band; a lower body is its band plus the family's band within the end
    blocks of ``blocks``; a higher body its band."""
    lo = -g.height / 2
    body = _band(g, lo, max(g.body_top, g.height / 2) if g.body_h > g.height else g.body_top, z0, z1)
    if g.body_h >= g.height or not blocks:
        return body
    fam = _band(g, lo, g.height / 2, z0, z1)
    ends = [one_solid(fam.intersect(b), "the family's section at a hinge end") for b in _blocks(g, blocks, z0, z1)]
    return one_solid(body.fuse(*ends).clean(), "joining a graduated body to its hinge ends")


def _body(g: RodGeometry) -> Solid:
    """The raw bar (every layer), before the end cuts."""
    t = g.thickness
    if not g.graduated:
        return _band(g, -g.height / 2, g.height / 2, -t / 2, t / 2)
    bt = g.body_t
    m = min(t, bt) / 2
    core = _outline(g, -m, m)
    if bt == t:
        return core
    hg = g.hinge
    extra = []
    for z0, z1 in ((m, max(t, bt) / 2), (-max(t, bt) / 2, -m)):
        if bt < t:  # the family's thickness at the fork ends (they hold the prongs)
            forks = [j for j in (0, 1) if hg.knuckle(j) == "fork"]
            fam = _band(g, -g.height / 2, g.height / 2, z0, z1)
            extra += [one_solid(fam.intersect(b), "a fork end's layers") for b in _blocks(g, forks, z0, z1)]
        else:  # a thicker body clear of both hinge ends
            part = _outline(g, z0, z1)
            extra.append(one_solid(part.cut(*_blocks(g, (0, 1), z0, z1)), "a thicker body's outer layers"))
    return one_solid(core.fuse(*extra).clean(), "layering a graduated body")


def _end_cuts(g: RodGeometry) -> list[Solid]:
    """Prisms removing everything beyond the end faces (top and bottom, both ends)."""
    t = g.max_thickness
    out = []
    for joint, end in ((0, g.first), (1, g.second)):
        p, u, v = _frame(g, joint)
        stub = _stub_length(g) + 1.0 + end.setback  # past the raw stub's end, whatever the setback
        for side, chamfer in ((1, end.top_chamfer), (-1, end.bottom_chamfer)):
            a = p - end.setback * u
            n = side * v
            tan_b = math.tan(math.radians(chamfer))
            reach = g.cut_reach(side, tan_b)  # covers the arc bending away
            top = a + n * reach - u * reach * tan_b
            pts = [a, a + u * stub, a + u * stub + n * reach, top]
            out.append(prism_solid(pts, -t, t))
    return out


def build_rod(g: RodGeometry, name: str = "", holes: Holes = NO_SHIFT, sizes: Sizes = OWN_SIZES) -> Solid:
    """Build a rod's exact B-rep solid in the rod frame.

    Args:
        g: the rod's geometry.
        name: label of the solid (becomes the STEP product name).
        holes: each pin hole's centre minus its hinge axis, ((dx0, dy0), (dx1, dy1)) in the
            rod frame (mm): the pin-play compensation (:mod:`rodcad.design.asprinted`), at most
            the clearance's half, inside the knuckle. The body, knuckles and hinge zones stay
            on the hinge axes, where the loaded pins put them.
        sizes: each pin hole's diameter (:data:`Sizes`; mm): the joint hardware's. A hole
            must leave the material's minimum wall in its knuckle (the planner's choice does).

    Returns:
        A valid build123d ``Solid``.

    Raises:
        GeometryError: when a step gives no single valid solid.
    """
    t = g.thickness
    tm = g.max_thickness
    hg = g.hinge
    a = hg.tongue_thickness / 2
    gap = hg.layer_gap
    body = _body(g)
    for cut in _end_cuts(g):
        body = one_solid(body.cut(cut), "cutting the end faces (chamfers too steep for this length "
                          "and curvature?)")
    knuckles = []
    for joint in (0, 1):
        p, _, _ = _frame(g, joint)
        if hg.knuckle(joint) == "tongue":
            knuckles.append(cylinder_solid(p, hg.knuckle_radius, -a, a))
        else:
            knuckles.append(cylinder_solid(p, hg.knuckle_radius, a + gap, t / 2))
            knuckles.append(cylinder_solid(p, hg.knuckle_radius, -t / 2, -a - gap))
    body = one_solid(body.fuse(*knuckles).clean(), "adding the knuckles")
    clear = []
    for joint in (0, 1):
        p, _, _ = _frame(g, joint)
        r = hg.zone_radius
        if hg.knuckle(joint) == "tongue":  # room for the partner's fork prongs
            clear.append(cylinder_solid(p, r, a, tm / 2 + 1))
            clear.append(cylinder_solid(p, r, -tm / 2 - 1, -a))
        else:  # slot for the partner's tongue
            clear.append(cylinder_solid(p, r, -a - gap, a + gap))
        d = hg.hole_diameter if sizes[joint] is None else sizes[joint]
        clear.append(cylinder_solid(p + np.asarray(holes[joint], float), d / 2, -tm / 2 - 1, tm / 2 + 1))
    for cut in clear:
        body = one_solid(body.cut(cut), "clearing the hinge zones and pin holes")
    body = one_solid(body.clean(), "cleaning up")
    body.label = name
    return body


@lru_cache(maxsize=128)
def rod_solid(g: RodGeometry, name: str = "", holes: Holes = NO_SHIFT, sizes: Sizes = OWN_SIZES) -> Solid:
    """:func:`build_rod`, cached per process. Do not modify the result."""
    return build_rod(g, name, holes, sizes)


def hinge_zone(g: RodGeometry, joint: int) -> Solid:
    """The full-thickness cylinder of the hinge zone around a joint's axis."""
    p, _, _ = _frame(g, joint)
    t = g.max_thickness
    return cylinder_solid(p, g.hinge.zone_radius, -t, t)


@lru_cache(maxsize=128)
def collision_proxy(g: RodGeometry, joint: int) -> Solid:
    """The rod without the hinge zone around ``joint`` (0 or 1).

    Two rods joined at that hinge interfere exactly when their proxies do: by
    construction, inside the hinge zone one rod only has material in the layers
    the other rod has cleared, at every angle, and material inside the zone
    cannot meet material outside it. The proxies are smaller and, unlike the
    full solids, their distance is not stuck at the layer gap, which lets the
    limit search take safe steps.
    """
    return one_solid(rod_solid(g).cut(hinge_zone(g, joint)).clean(), "cutting the hinge zone")


@dataclass(frozen=True)
class MassProperties:
    """Exact B-rep mass properties of a solid of uniform density.

    Attributes:
        volume: mm^3.
        center: centre of mass (x, y, z) in mm.
    """

    volume: float
    center: tuple[float, float, float]


class PortableSolid:
    """A solid as bytes that cross between processes (OCCT's BinTools: the exact B-rep; a
    solid from a boolean keeps a history that does not pickle), without the meshes the
    sending process made of it (they would change the receiver's STL). :meth:`restore` gives it
    back with its label."""

    def __init__(self, solid: Solid) -> None:
        import io

        from OCP.BinTools import BinTools, BinTools_FormatVersion

        out = io.BytesIO()  # no meshes: the solid arrives as it was built, meshed where it is used
        BinTools.Write_s(solid.wrapped, out, False, False, BinTools_FormatVersion.BinTools_FormatVersion_CURRENT)
        self.data = out.getvalue()
        self.label = solid.label

    def restore(self) -> Solid:
        from build123d.persistence import deserialize_shape

        solid = Solid(deserialize_shape(self.data))
        solid.label = self.label
        return solid


def mass_properties(solid: Solid) -> MassProperties:
    """Volume and centre of mass from the B-rep (build123d / OCP GProp)."""
    c = solid.center(CenterOf.MASS)
    return MassProperties(float(solid.volume), (float(c.X), float(c.Y), float(c.Z)))


def with_spherical_voids(solid: Solid, centers: np.ndarray, radius: float, name: str = "") -> Solid:
    """The solid with closed spherical voids (cavities or ball sockets) cut out.

    Args:
        solid: the rod solid.
        centers: (n, 3) sphere centres (mm); the spheres must lie inside.
        radius: sphere radius (mm).
        name: label of the result.

    Raises:
        GeometryError: if the result is not one valid solid.
    """
    spheres = [Solid.make_sphere(radius, Plane((float(x), float(y), float(z)))) for x, y, z in centers]
    if not spheres:
        return solid
    result = one_solid(solid.cut(*spheres), "cutting spherical voids")
    result.label = name or solid.label
    return result


def is_valid_solid(shape: object) -> bool:
    """True for a single valid closed solid."""
    try:
        solids = shape.solids()  # type: ignore[attr-defined]
    except AttributeError:
        return False
    return len(solids) == 1 and bool(solids[0].is_valid)


def precise_volume(solid: Solid, eps: float = 1e-9) -> float:
    """The solid's volume integrated by OCC to a relative accuracy ``eps`` (mm^3); build123d's
    ``volume`` integrates with a fixed rule, off by up to a few 1e-6 of a hub's volume (and
    differently for the same solid re-read from STEP)."""
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(solid.wrapped, props, eps, True)
    return float(props.Mass())


def void_template(kind: str, radius: float, height: float | None = None) -> Solid:
    """One void of shape ``kind`` around the origin (see :data:`rodcad.fabrication.layout.VOIDS`).

    The print's up direction is the rod frame's +y: 'capped' is the sphere cut
    flat at y = +-r/sqrt(2) (overhangs at most 45 degrees, a bridged roof of
    diameter r sqrt(2)); 'silo' is the lower half sphere plus a cylinder of the
    same radius from y = 0 to y = r, or to y = ``height`` (a flat roof bridged over the
    ball); 'sphere' is the plain sphere.

    Args:
        kind: 'sphere', 'capped' or 'silo'.
        radius: mm.
        height: a silo's roof above its centre (mm; default the radius).
    """
    sphere = Solid.make_sphere(radius)
    if kind == "sphere":
        return sphere
    if kind == "capped":
        h = radius / math.sqrt(2)
        slab = Solid.make_box(2 * radius + 2, 2 * h, 2 * radius + 2, Plane((-radius - 1, -h, -radius - 1)))
        return one_solid(sphere.intersect(slab), "capping a cavity")
    if kind == "silo":
        up = Plane((0, 0, 0), x_dir=(1, 0, 0), z_dir=(0, 1, 0))
        top = radius if height is None else float(height)
        return one_solid(sphere.fuse(Solid.make_cylinder(radius, top, up)).clean(), "shaping a ball socket")
    raise GeometryError(f"unknown void shape {kind!r}")


def void_solids(kind: str, centers: np.ndarray, radius: float, height: float | None = None) -> list[Solid]:
    """Voids of one shape and radius (a silo's roof ``height`` above its centre) placed at
    ``centers`` ((n, 3), mm)."""
    if len(centers) == 0:
        return []
    tpl = void_template(kind, radius, height)
    return [tpl.moved(Location((float(x), float(y), float(z)))) for x, y, z in np.asarray(centers, dtype=float)]


def with_voids(solid: Solid, voids: Sequence[tuple[Any, ...]], name: str = "") -> Solid:
    """The solid with closed voids cut out, each checked to stay closed.

    Args:
        solid: the rod solid.
        voids: (shape, centres (n, 3), radius) groups, or (shape, centres, radius, silo
            height), see :func:`void_template`.
        name: label of the result (default: the solid's).

    Raises:
        GeometryError: the result is not one valid solid, or a void broke the
            surface or merged with another (the shell count is off).
    """
    tools = [v for kind, centers, radius, *height in voids for v in void_solids(kind, centers, radius, *height)]
    if not tools:
        return solid
    result = one_solid(solid.cut(*tools), "cutting the cavities and ball sockets")
    shells = len(result.shells())
    if shells != 1 + len(tools):
        raise GeometryError(f"cutting {len(tools)} closed voids leaves {shells - 1} inner surfaces: a void "
                            "breaks an outer face or touches another")
    result.label = name or solid.label
    return result




def type_solid(rod: RodType, holes: Holes = NO_SHIFT, sizes: Sizes = OWN_SIZES) -> Solid:
    """The exact B-rep solid of a catalog rod type in the rod frame, labelled with the
    type's name (its pin holes moved by ``holes``, see :func:`build_rod`). Built once per
    process.

    Raises:
        InputError: when the parameters make no valid solid (pointing at the family
            in the catalog).
    """
    given = _GIVEN.get((rod.geometry, rod.name, holes, sizes))
    if given is not None:
        return given
    try:
        return rod_solid(rod.geometry, rod.name, holes, sizes)
    except GeometryError as err:
        raise InputError([rod.origin.problem(f"rod type {rod.name!r}: {err}")]) from None


def share_type_solid(rod: RodType, solid: Solid) -> None:
    """Take ``solid`` as this process's :func:`type_solid` of ``rod`` (plain holes): the one
    a worker built (:class:`PortableSolid`), instead of building it again here."""
    if len(_GIVEN) >= 128:
        _GIVEN.clear()
    _GIVEN[(rod.geometry, rod.name, NO_SHIFT, OWN_SIZES)] = solid


#: Type solids built elsewhere (:func:`share_type_solid`), by :func:`rod_solid`'s arguments.
_GIVEN: dict[tuple[Any, ...], Solid] = {}
