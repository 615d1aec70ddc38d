"""Exact rod solids and the kernel queries on them (build123d / OCP).

This is the only module of rodcad that imports build123d or OCP; everything
else works with the plain parameters of :class:`rodcad.catalog.RodGeometry` and
the results returned here.

A rod is built in the rod frame (first hinge axis through the origin, second
through (length, 0, 0), axes along +z, chain plane xy) as:

1. the body: a bar of section height x thickness along the centreline (a
   straight segment, or an arc of the given curvature through both hinge axes,
   continued by straight tangent stubs past them);
2. the end faces: per end, a top (+y) and a bottom half-plane through the point
   ``setback`` behind the hinge axis, tilted by the chamfer angles
   (:class:`rodcad.catalog.EndShape`); everything beyond them is cut off;
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
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np
from build123d import CenterOf, Color, Compound, Location, Plane, Solid, Vector, Wire, Face, export_step as _export_step
from build123d import import_step as _import_step
from OCP.BRep import BRep_Builder
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
from OCP.BRepClass3d import BRepClass3d_SolidClassifier
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.gp import gp_Ax1, gp_Dir, gp_Pnt, gp_Trsf, gp_Vec
from OCP.TopAbs import TopAbs_IN, TopAbs_ON
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS_Compound

from rodcad.catalog import GEOMETRY_VERSION, RodGeometry

__all__ = [
    "GEOMETRY_VERSION",
    "PRINT_ROTATION",
    "AssemblyGroup",
    "AssemblyPart",
    "Clearance",
    "GeometryError",
    "MassProperties",
    "PairScene",
    "Probe",
    "build_rod",
    "collision_proxy",
    "export_assembly",
    "export_step",
    "export_stl",
    "hinge_zone",
    "import_step",
    "is_valid_solid",
    "mass_properties",
    "matrix_location",
    "print_matrix",
    "read_assembly",
    "rod_solid",
    "shape_distance",
    "transformed",
    "void_solids",
    "void_template",
    "void_walls",
    "with_spherical_voids",
    "with_voids",
]

#: Distances at or below this count as contact (mm).
CONTACT_TOL = 1e-6


class GeometryError(ValueError):
    """The parameters make no valid solid."""


# --------------------------------------------------------------------------- building


def _prism(points: Sequence[Sequence[float]], z0: float, z1: float) -> Solid:
    """Extrude a closed xy polygon from z0 to z1."""
    wire = Wire.make_polygon([Vector(p[0], p[1], z0) for p in points], close=True)
    return Solid.extrude(Face(wire), Vector(0, 0, z1 - z0))


def _cylinder(center: Sequence[float], radius: float, z0: float, z1: float) -> Solid:
    return Solid.make_cylinder(radius, z1 - z0, Plane((center[0], center[1], z0)))


def _one_solid(shape: object, step: str) -> Solid:
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
    psi = math.radians(g.half_angle_deg)
    if joint == 0:
        p = np.array([0.0, 0.0])
        forward = np.array([math.cos(-psi), math.sin(-psi)])
        u = -forward
    else:
        p = np.array([g.length, 0.0])
        forward = np.array([math.cos(psi), math.sin(psi)])
        u = forward
    v = np.array([-forward[1], forward[0]])
    return p, u, v


def _stub_length(g: RodGeometry) -> float:
    """How far the raw body continues past each hinge axis before the end cut."""
    return 1.2 * g.height + 2.0


def _body(g: RodGeometry) -> Solid:
    """The raw bar: centreline segment or arc plus straight stubs past the axes."""
    h, t, L = g.height, g.thickness, g.length
    stub = _stub_length(g)
    z0, z1 = -t / 2, t / 2
    if g.curvature == 0:
        return Solid.make_box(L + 2 * stub, h, t, Plane((-stub, -h / 2, z0)))
    rho = 1 / abs(g.curvature)
    sigma = 1 if g.curvature > 0 else -1
    psi = math.radians(abs(g.half_angle_deg))
    centre = (L / 2, sigma * rho * math.cos(psi))
    # The arc runs from the first axis to the second, around -90 deg (sigma=+1)
    # or +90 deg (sigma=-1) as seen from the centre.
    mid = -90.0 if sigma > 0 else 90.0
    start = mid - math.degrees(psi)
    s = math.radians(start)
    plane = Plane((centre[0], centre[1], z0), x_dir=(math.cos(s), math.sin(s), 0), z_dir=(0, 0, 1))
    outer = Solid.make_cylinder(rho + h / 2, t, plane, angle=2 * math.degrees(psi))
    inner = Solid.make_cylinder(rho - h / 2, t + 2, Plane((centre[0], centre[1], z0 - 1)))
    band = _one_solid(outer.cut(inner), "the curved body")
    parts = [band]
    for joint in (0, 1):
        p, u, v = _frame(g, joint)
        a, b = p - v * h / 2, p + v * h / 2
        parts.append(_prism([a, a + u * stub, b + u * stub, b], z0, z1))
    return _one_solid(parts[0].fuse(*parts[1:]).clean(), "the curved body with its stubs")


def _end_cuts(g: RodGeometry) -> list[Solid]:
    """Prisms removing everything beyond the end faces (top and bottom, both ends)."""
    h, t = g.height, g.thickness
    stub = _stub_length(g) + 1.0
    out = []
    for joint, end in ((0, g.first), (1, g.second)):
        p, u, v = _frame(g, joint)
        a = p - end.setback * u
        for side, chamfer in ((1, end.top_chamfer), (-1, end.bottom_chamfer)):
            n = side * v
            tan_b = math.tan(math.radians(chamfer))
            reach = h / 2 + 1.0
            behind = reach * max(tan_b, 0.0)
            reach += behind**2 * abs(g.curvature) / 2 + 1.0  # covers the arc bending away
            top = a + n * reach - u * reach * tan_b
            pts = [a, a + u * stub, a + u * stub + n * reach, top]
            out.append(_prism(pts, -t, t))
    return out


def build_rod(g: RodGeometry, name: str = "") -> Solid:
    """Build a rod's exact B-rep solid in the rod frame.

    Args:
        g: the rod's geometry.
        name: label of the solid (becomes the STEP product name).

    Returns:
        A valid build123d ``Solid``.

    Raises:
        GeometryError: when a step gives no single valid solid.
    """
    t = g.thickness
    hg = g.hinge
    a = hg.tongue_thickness / 2
    gap = hg.layer_gap
    body = _body(g)
    for cut in _end_cuts(g):
        body = _one_solid(body.cut(cut), "cutting the end faces (chamfers too steep for this length "
                          "and curvature?)")
    knuckles = []
    for joint in (0, 1):
        p, _, _ = _frame(g, joint)
        if hg.knuckle(joint) == "tongue":
            knuckles.append(_cylinder(p, hg.knuckle_radius, -a, a))
        else:
            knuckles.append(_cylinder(p, hg.knuckle_radius, a + gap, t / 2))
            knuckles.append(_cylinder(p, hg.knuckle_radius, -t / 2, -a - gap))
    body = _one_solid(body.fuse(*knuckles).clean(), "adding the knuckles")
    clear = []
    for joint in (0, 1):
        p, _, _ = _frame(g, joint)
        r = hg.zone_radius
        if hg.knuckle(joint) == "tongue":  # room for the partner's fork prongs
            clear.append(_cylinder(p, r, a, t / 2 + 1))
            clear.append(_cylinder(p, r, -t / 2 - 1, -a))
        else:  # slot for the partner's tongue
            clear.append(_cylinder(p, r, -a - gap, a + gap))
        clear.append(_cylinder(p, hg.hole_diameter / 2, -t / 2 - 1, t / 2 + 1))
    for cut in clear:
        body = _one_solid(body.cut(cut), "clearing the hinge zones and pin holes")
    body = _one_solid(body.clean(), "cleaning up")
    body.label = name
    return body


@lru_cache(maxsize=128)
def rod_solid(g: RodGeometry, name: str = "") -> Solid:
    """:func:`build_rod`, cached per process. Do not modify the result."""
    return build_rod(g, name)


def hinge_zone(g: RodGeometry, joint: int) -> Solid:
    """The full-thickness cylinder of the hinge zone around a joint's axis."""
    p, _, _ = _frame(g, joint)
    t = g.thickness
    return _cylinder(p, g.hinge.zone_radius, -t, t)


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
    return _one_solid(rod_solid(g).cut(hinge_zone(g, joint)).clean(), "cutting the hinge zone")


# --------------------------------------------------------------------------- mass


@dataclass(frozen=True)
class MassProperties:
    """Exact B-rep mass properties of a solid of uniform density.

    Attributes:
        volume: mm^3.
        center: centre of mass (x, y, z) in mm.
    """

    volume: float
    center: tuple[float, float, float]


def mass_properties(solid: Solid) -> MassProperties:
    """Volume and centre of mass from the B-rep (build123d / OCP GProp)."""
    c = solid.center(CenterOf.MASS)
    return MassProperties(float(solid.volume), (float(c.X), float(c.Y), float(c.Z)))


# --------------------------------------------------------------------------- queries


def _faces_compound(solid: Solid) -> TopoDS_Compound:
    builder = BRep_Builder()
    comp = TopoDS_Compound()
    builder.MakeCompound(comp)
    for f in solid.faces():
        builder.Add(comp, f.wrapped)
    return comp


def _first_vertex(solid: Solid) -> np.ndarray:
    v = solid.vertices()[0]
    return np.array([v.X, v.Y, v.Z])


@dataclass(frozen=True)
class Probe:
    """Result of one interference query at a bend angle.

    Attributes:
        phi: bend angle (deg).
        distance: distance between the two rods' collision proxies (mm); 0 when
            they touch or interfere.
        rate: d(distance)/d(phi) estimated from the closest points (mm per
            radian); negative while the rods approach each other. 0 if unknown.
    """

    phi: float
    distance: float
    rate: float

    @property
    def contact(self) -> bool:
        return self.distance <= CONTACT_TOL


class PairScene:
    """Two adjacent rods and their shared hinge, for interference queries.

    The left rod stays in its frame; the right rod's first hinge axis sits on
    the left rod's second, (left.length, 0, 0), and the right rod is turned by
    the bend angle phi about that axis (+z): phi > 0 turns it counter-clockwise,
    closing the gap on the top (+y) side of the joint.

    Args:
        left: geometry of the left rod.
        right: geometry of the right rod.
    """

    def __init__(self, left: RodGeometry, right: RodGeometry) -> None:
        self.left = left
        self.right = right
        self.axis_x = left.length
        lp = collision_proxy(left, 1)
        rp = collision_proxy(right, 0)
        self._left_faces = _faces_compound(lp)
        self._right_faces = _faces_compound(rp)
        self._left_cls = BRepClass3d_SolidClassifier(lp.wrapped)
        self._right_cls = BRepClass3d_SolidClassifier(rp.wrapped)
        self._left_vertex = _first_vertex(lp)
        self._right_vertex = _first_vertex(rp)
        self._ext = BRepExtrema_DistShapeShape()
        self._ext.LoadS1(self._left_faces)
        bb = rp.bounding_box()
        corners = [(x, y) for x in (bb.min.X, bb.max.X) for y in (bb.min.Y, bb.max.Y)]
        #: Largest distance of the right rod's material from the hinge axis (mm).
        self.reach = max(math.hypot(x, y) for x, y in corners)
        self.evaluations = 0

    def _trsf(self, phi: float) -> gp_Trsf:
        move = gp_Trsf()
        move.SetTranslation(gp_Vec(self.axis_x, 0, 0))
        turn = gp_Trsf()
        turn.SetRotation(gp_Ax1(gp_Pnt(self.axis_x, 0, 0), gp_Dir(0, 0, 1)), math.radians(phi))
        return turn.Multiplied(move)

    def probe(self, phi: float) -> Probe:
        """Distance between the rods at bend ``phi`` (deg), with its rate."""
        self.evaluations += 1
        trsf = self._trsf(phi)
        placed = self._right_faces.Moved(TopLoc_Location(trsf))
        ext = self._ext
        ext.LoadS2(placed)
        if not ext.Perform() or not ext.IsDone():  # pragma: no cover - kernel failure
            raise GeometryError(f"distance query failed at {phi} deg")
        d = ext.Value()
        if d <= CONTACT_TOL:
            return Probe(phi, 0.0, 0.0)
        # Disjoint boundaries: the solids are apart unless one holds the other.
        rv = gp_Pnt(*self._right_vertex).Transformed(trsf)
        self._left_cls.Perform(rv, 1e-7)
        lv = gp_Pnt(*self._left_vertex).Transformed(trsf.Inverted())
        self._right_cls.Perform(lv, 1e-7)
        if self._left_cls.State() in (TopAbs_IN, TopAbs_ON) or self._right_cls.State() in (TopAbs_IN, TopAbs_ON):
            return Probe(phi, 0.0, 0.0)
        rate = math.inf
        for i in range(1, ext.NbSolution() + 1):
            pl = ext.PointOnShape1(i)
            pr = ext.PointOnShape2(i)
            n = np.array([pr.X() - pl.X(), pr.Y() - pl.Y(), pr.Z() - pl.Z()]) / d
            vel = np.array([-pr.Y(), pr.X() - self.axis_x, 0.0])  # d(point)/d(phi), per radian
            rate = min(rate, float(n @ vel))
        return Probe(phi, float(d), 0.0 if not math.isfinite(rate) else rate)

    def interferes(self, phi: float, *, full: bool = False) -> bool:
        """Whether the rods interfere (or touch) at ``phi``.

        Args:
            phi: bend angle (deg).
            full: test the complete solids (hinge knuckles and all) with a
                boolean common instead of the proxies' distance (slow; for
                checking the proxies).
        """
        if not full:
            return self.probe(phi).contact
        left = rod_solid(self.left)
        right = rod_solid(self.right)
        placed = Solid(right.wrapped.Moved(TopLoc_Location(self._trsf(phi))))
        common = left.intersect(placed)
        volume = sum(s.volume for s in common.solids()) if common is not None else 0.0
        return volume > 1e-9


class Clearance:
    """Distance from points to a solid's boundary, signed (negative outside).

    The building block for placing cavities and ball sockets: a sphere of radius
    r around p fits inside with a wall w exactly when ``clearance(p) >= r + w``.

    Args:
        solid: the solid (pin holes and all: they are boundary too).
    """

    def __init__(self, solid: Solid) -> None:
        self._ext = BRepExtrema_DistShapeShape()
        self._ext.LoadS1(_faces_compound(solid))
        self._cls = BRepClass3d_SolidClassifier(solid.wrapped)
        bb = solid.bounding_box()
        #: Axis-aligned bounds ((xmin, ymin, zmin), (xmax, ymax, zmax)) in mm.
        self.bounds = ((bb.min.X, bb.min.Y, bb.min.Z), (bb.max.X, bb.max.Y, bb.max.Z))

    def __call__(self, points: np.ndarray) -> np.ndarray:
        """Signed clearance of each point (array of shape (n, 3)) in mm."""
        pts = np.atleast_2d(np.asarray(points, dtype=float))
        out = np.empty(len(pts))
        for i, (x, y, z) in enumerate(pts):
            p = gp_Pnt(float(x), float(y), float(z))
            self._ext.LoadS2(BRepBuilderAPI_MakeVertex(p).Vertex())
            self._ext.Perform()
            d = self._ext.Value()
            self._cls.Perform(p, 1e-9)
            out[i] = d if self._cls.State() == TopAbs_IN else -d
        return out


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
    result = _one_solid(solid.cut(*spheres), "cutting spherical voids")
    result.label = name or solid.label
    return result


def is_valid_solid(shape: object) -> bool:
    """True for a single valid closed solid."""
    try:
        solids = shape.solids()  # type: ignore[attr-defined]
    except AttributeError:
        return False
    return len(solids) == 1 and bool(solids[0].is_valid)


# --------------------------------------------------------------------------- STEP


def export_step(solid: Solid, path: str | os.PathLike[str], name: str | None = None) -> Path:
    """Write a solid to a STEP file (mm), its product named after the solid.

    Args:
        solid: what to write.
        path: destination file.
        name: product name (default: the solid's label).

    Returns:
        The path written.
    """
    if name is not None:
        solid.label = name
    path = Path(path)
    if not _export_step(solid, path):  # pragma: no cover - writer failure
        raise OSError(f"could not write {path}")
    return path


def import_step(path: str | os.PathLike[str]) -> Solid:
    """Read a single-solid STEP file back (label = product name).

    Raises:
        GeometryError: the file does not hold exactly one solid.
    """
    shape = _import_step(Path(path))
    solids = shape.solids()
    if len(solids) != 1:
        raise GeometryError(f"{path} holds {len(solids)} solids, expected 1")
    solid = solids[0]
    solid.label = shape.label or solid.label
    return solid


# --------------------------------------------------------------------------- printable voids, print pose, STL


def void_template(kind: str, radius: float) -> Solid:
    """One void of shape ``kind`` around the origin (see :data:`rodcad.massrange.VOIDS`).

    The print's up direction is the rod frame's +y: 'capped' is the sphere cut
    flat at y = +-r/sqrt(2) (overhangs at most 45 degrees, a bridged roof of
    diameter r sqrt(2)); 'silo' is the lower half sphere plus a cylinder of the
    same radius from y = 0 to y = r (a flat roof bridged over the ball);
    'sphere' is the plain sphere.

    Args:
        kind: 'sphere', 'capped' or 'silo'.
        radius: mm.
    """
    sphere = Solid.make_sphere(radius)
    if kind == "sphere":
        return sphere
    if kind == "capped":
        h = radius / math.sqrt(2)
        slab = Solid.make_box(2 * radius + 2, 2 * h, 2 * radius + 2, Plane((-radius - 1, -h, -radius - 1)))
        return _one_solid(sphere.intersect(slab), "capping a cavity")
    if kind == "silo":
        up = Plane((0, 0, 0), x_dir=(1, 0, 0), z_dir=(0, 1, 0))
        return _one_solid(sphere.fuse(Solid.make_cylinder(radius, radius, up)).clean(), "shaping a ball socket")
    raise GeometryError(f"unknown void shape {kind!r}")


def void_solids(kind: str, centers: np.ndarray, radius: float) -> list[Solid]:
    """Voids of one shape and radius placed at ``centers`` ((n, 3), mm)."""
    if len(centers) == 0:
        return []
    tpl = void_template(kind, radius)
    return [tpl.moved(Location((float(x), float(y), float(z)))) for x, y, z in np.asarray(centers, dtype=float)]


def with_voids(solid: Solid, voids: Sequence[tuple[str, np.ndarray, float]], name: str = "") -> Solid:
    """The solid with closed voids cut out, each checked to stay closed.

    Args:
        solid: the rod solid.
        voids: (shape, centres (n, 3), radius) groups, see :func:`void_template`.
        name: label of the result (default: the solid's).

    Raises:
        GeometryError: the result is not one valid solid, or a void broke the
            surface or merged with another (the shell count is off).
    """
    tools = [v for kind, centers, radius in voids for v in void_solids(kind, centers, radius)]
    if not tools:
        return solid
    result = _one_solid(solid.cut(*tools), "cutting the cavities and ball sockets")
    shells = len(result.shells())
    if shells != 1 + len(tools):
        raise GeometryError(f"cutting {len(tools)} closed voids leaves {shells - 1} inner surfaces: a void "
                            "breaks an outer face or touches another")
    result.label = name or solid.label
    return result


def shape_distance(a: Solid, b: object) -> float:
    """Smallest distance between two shapes (BRepExtrema, mm); 0 if they touch."""
    ext = BRepExtrema_DistShapeShape(a.wrapped, b.wrapped if hasattr(b, "wrapped") else b)  # type: ignore[attr-defined]
    if not ext.IsDone():  # pragma: no cover - kernel failure
        raise GeometryError("distance query failed")
    return float(ext.Value())


def void_walls(solid: Solid, voids: Sequence[Solid], near: float) -> tuple[np.ndarray, float]:
    """Measured walls around voids, from the B-rep.

    Args:
        solid: the plain rod (its faces are the outer faces and pin holes).
        voids: the void solids (placed).
        near: only void pairs whose bounding boxes come within this distance (mm)
            are measured against each other.

    Returns:
        (distance of each void to the solid's faces (mm), smallest distance
        between two voids (mm, inf for fewer than two)).
    """
    faces = _faces_compound(solid)
    to_faces = np.array([shape_distance(v, faces) for v in voids])
    between = math.inf
    boxes = [v.bounding_box() for v in voids]
    for i in range(len(voids)):
        for j in range(i + 1, len(voids)):
            a, b = boxes[i], boxes[j]
            gap = max(a.min.X - b.max.X, b.min.X - a.max.X, a.min.Y - b.max.Y, b.min.Y - a.max.Y,
                      a.min.Z - b.max.Z, b.min.Z - a.max.Z)
            if gap <= near:
                between = min(between, shape_distance(voids[i], voids[j]))
    return to_faces, between


def matrix_location(matrix: np.ndarray) -> Location:
    """The build123d Location of a rigid 4x4 matrix (mm)."""
    m = np.asarray(matrix, dtype=float)
    t = gp_Trsf()
    t.SetValues(*(float(x) for x in m[:3, :4].reshape(-1)))
    return Location(TopLoc_Location(t))


def transformed(solid: Solid, matrix: np.ndarray) -> Solid:
    """A copy of ``solid`` with the rigid 4x4 ``matrix`` baked into its geometry."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform

    m = np.asarray(matrix, dtype=float)
    t = gp_Trsf()
    t.SetValues(*(float(x) for x in m[:3, :4].reshape(-1)))
    out = Solid(BRepBuilderAPI_Transform(solid.wrapped, t, True).Shape())
    out.label = solid.label
    return out


#: Rotation taking the rod frame to the print bed: +y (rod) -> +Z (printer),
#: +z (rod, the hinge axes) -> -Y, x stays x; the rod lies on its -y face.
PRINT_ROTATION = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])


def print_matrix(solid: Solid) -> np.ndarray:
    """4x4 matrix placing a rod-frame solid on the bed: rotated by
    :data:`PRINT_ROTATION` and moved so its bounding box starts at (0, 0, 0)
    (Z = 0 is the bed)."""
    m = np.eye(4)
    m[:3, :3] = PRINT_ROTATION
    bb = solid.bounding_box()
    corners = np.array([[x, y, z] for x in (bb.min.X, bb.max.X) for y in (bb.min.Y, bb.max.Y)
                        for z in (bb.min.Z, bb.max.Z)]) @ PRINT_ROTATION.T
    m[:3, 3] = -corners.min(axis=0)
    return m


def export_stl(solid: Solid, path: str | os.PathLike[str], *, tolerance: float = 0.002,
               angular_tolerance: float = 0.1) -> Path:
    """Write a binary STL (mm).

    Args:
        solid: what to write.
        path: destination.
        tolerance: linear deflection of the mesh (mm).
        angular_tolerance: angular deflection (rad).
    """
    from build123d import export_stl as _export_stl

    path = Path(path)
    if not _export_stl(solid, str(path), tolerance=tolerance, angular_tolerance=angular_tolerance):
        raise OSError(f"could not write {path}")  # pragma: no cover - writer failure
    return path


# --------------------------------------------------------------------------- assemblies


@dataclass
class AssemblyPart:
    """A named solid in an assembly.

    Attributes:
        name: label (the STEP product / instance name).
        solid: the solid in its own frame.
        location: rigid 4x4 placement (mm) relative to the parent.
        color: (r, g, b) in 0..1, or None.
    """

    name: str
    solid: Solid
    location: np.ndarray
    color: tuple[float, float, float] | None = None


@dataclass
class AssemblyGroup:
    """A named sub-assembly.

    Attributes:
        name: label.
        children: parts and groups.
        location: rigid 4x4 placement (mm) relative to the parent (default identity).
    """

    name: str
    children: Sequence[AssemblyPart | AssemblyGroup]
    location: np.ndarray = field(default_factory=lambda: np.eye(4))


def _assembly_node(node: AssemblyPart | AssemblyGroup) -> Compound | Solid:
    if isinstance(node, AssemblyPart):
        from OCP.BRepBuilderAPI import BRepBuilderAPI_Copy

        # A copy per part: parts sharing one TShape would be merged into one
        # product by the writer (one name, one colour, placements lost).
        shape = Solid(BRepBuilderAPI_Copy(node.solid.wrapped).Shape())
        shape.label = node.name
        if node.color is not None:
            shape.color = Color(*(float(c) for c in node.color))
        shape.location = matrix_location(node.location)
        return shape
    kids = [_assembly_node(c) for c in node.children]
    comp = Compound(children=kids, label=node.name)
    comp.location = matrix_location(node.location)
    return comp


def export_assembly(path: str | os.PathLike[str], nodes: Sequence[AssemblyPart | AssemblyGroup],
                    name: str = "assembly") -> Path:
    """Write a STEP assembly: named, coloured solids placed by 4x4 matrices in
    named groups (written through build123d's XCAF exporter: product names,
    colours and placements survive; identical solids are written once and
    instanced).

    Args:
        path: destination file.
        nodes: parts and groups of the top level.
        name: label of the root assembly.

    Returns:
        The path written.
    """
    root = Compound(children=[_assembly_node(n) for n in nodes], label=name)
    path = Path(path)
    if not _export_step(root, path):  # pragma: no cover - writer failure
        raise OSError(f"could not write {path}")
    return path


def read_assembly(path: str | os.PathLike[str]) -> list[tuple[str, float]]:
    """The leaf solids of a STEP file as (label, volume mm^3), depth first
    (read back through build123d's XCAF importer)."""
    root = _import_step(Path(path))
    out: list[tuple[str, float]] = []

    def walk(shape: object) -> None:
        kids = list(getattr(shape, "children", ()) or ())
        if kids:
            for k in kids:
                walk(k)
            return
        for s in shape.solids():  # type: ignore[attr-defined]
            out.append((getattr(shape, "label", "") or s.label, float(s.volume)))

    walk(root)
    return out


# ---- chandelier frame ------------------------------------------------------------------
# The printed frame a chandelier's chains hang from (see rodcad.chandelier, which
# lays it out in numbers). Owned by the chandelier work; keep additions above this line.


def _trsf_of(matrix: np.ndarray) -> gp_Trsf:
    """gp_Trsf of a rigid 4x4 matrix."""
    m = np.asarray(matrix, dtype=float)
    t = gp_Trsf()
    t.SetValues(*(float(x) for x in m[:3, :4].reshape(-1)))
    return t


def placed(solid: Solid, matrix: np.ndarray) -> Solid:
    """A copy of ``solid`` moved by the rigid 4x4 ``matrix`` (geometry baked in, label kept)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform

    shape = BRepBuilderAPI_Transform(solid.wrapped, _trsf_of(matrix), True).Shape()
    out = Solid(shape)
    out.label = solid.label
    return out


def pin_solid(diameter: float, length: float) -> Solid:
    """A hinge pin: a cylinder of ``diameter`` along +z from z = 0 to ``length`` (mm)."""
    return _cylinder((0.0, 0.0), diameter / 2, 0.0, length)


def _frame_piece(shape: object, step: str) -> Solid:
    try:
        return _one_solid(shape, step)
    except GeometryError as err:
        raise GeometryError(str(err).replace("one rod", "one frame")) from None


def _arm(points: np.ndarray, radius: float, z0: float, z1: float) -> list[Solid]:
    """A round-ended bar of half-width ``radius`` along an xy polyline, from z0 to z1."""
    parts = [_cylinder(points[0], radius, z0, z1)]
    for p, q in zip(points[:-1], points[1:]):
        d = q - p
        length = float(np.hypot(*d))
        if length < 1e-9:
            continue
        n = np.array([-d[1], d[0]]) / length * radius
        parts.append(_prism([p + n, q + n, q - n, p - n], z0, z1))
        parts.append(_cylinder(q, radius, z0, z1))
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
        return _arm(pts, kr, -a, a)
    if lug.knuckle != "fork":  # type: ignore[attr-defined]
        raise GeometryError(f"lug knuckle must be 'fork' or 'tongue', not {lug.knuckle!r}")  # type: ignore[attr-defined]
    c = float(lug.cheek)  # type: ignore[attr-defined]
    if c <= 0:
        raise GeometryError("the hinge leaves no room for fork prongs")
    zo = t / 2 + gap
    parts = [_cylinder((0, 0), kr, a + gap, zo + c), _cylinder((0, 0), kr, -zo - c, -a - gap)]
    return parts + _arm(pts, kr, zo, zo + c) + _arm(pts, kr, -zo - c, -zo)


def _members(kind: str, p: dict) -> list[Solid]:
    w, t = float(p["width"]), float(p["thickness"])
    if kind == "ring":
        cx, cy = p["center"]
        r = float(p["radius"])
        outer = _cylinder((cx, cy), r + w / 2, p["z"], p["z"] + t)
        if r - w / 2 <= 0:
            return [outer]
        return [_frame_piece(outer.cut(_cylinder((cx, cy), r - w / 2, p["z"] - 1, p["z"] + t + 1)),
                             "cutting the ring's hole")]
    if kind == "two_rings":
        c = np.asarray(p["center"], dtype=float)
        hub = _cylinder(c, p["hub_radius"], p["hub_z"], p["hub_z"] + t)
        rr = float(p["ring_radius"])
        ring = _cylinder(c, rr + w / 2, p["ring_z"], p["ring_z"] + t)
        if rr - w / 2 > 0:
            ring = _frame_piece(ring.cut(_cylinder(c, rr - w / 2, p["ring_z"] - 1, p["ring_z"] + t + 1)),
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
        out = [_cylinder(x[:2], w / 2, x[2] - t / 2, x[2] + t / 2) for x in v]
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

    Lugs: objects like :class:`rodcad.chandelier.LugSpec` (``location`` 4x4 lug
    frame -> world, ``knuckle``, ``thickness``, ``hinge``, ``cheek``, ``width``,
    ``arm_points()``), built by :func:`lug_parts` and moved into place; every
    lug's arm ends on the mid-plane of its member. Each lug gets a pin hole of the
    hinge's ``hole_diameter`` whose axis is the lug frame's z axis through its
    origin (the anchor).

    Raises:
        GeometryError: a boolean step leaves no single valid solid (e.g. a lug arm
            that misses its member, named in the message).
    """
    members = _members(kind, params)
    body = members[0]
    if len(members) > 1:
        body = _frame_piece(body.fuse(*members[1:]).clean(), f"joining the {kind} frame's members")
    for lug in lugs:
        parts = [placed(s, lug.location) for s in lug_parts(lug)]  # type: ignore[attr-defined]
        body = _frame_piece(body.fuse(*parts).clean(),
                            f"joining lug {lug.name} to the frame (does its arm reach a member?)")  # type: ignore[attr-defined]
    holes = []
    for lug in lugs:
        half = float(lug.width) / 2 + 1.0  # type: ignore[attr-defined]
        hole = _cylinder((0.0, 0.0), lug.hinge.hole_diameter / 2, -half, half)  # type: ignore[attr-defined]
        holes.append(placed(hole, lug.location))  # type: ignore[attr-defined]
    if holes:
        body = _frame_piece(body.cut(*holes).clean(), "drilling the lugs' pin holes")
    body.label = "frame"
    return body


class DistanceTo:
    """Distance from one fixed solid (e.g. the frame) to others placed near it (mm).

    Returns 0 when the solids touch, interfere or one holds the other.
    """

    def __init__(self, solid: Solid) -> None:
        self._ext = BRepExtrema_DistShapeShape()
        self._ext.LoadS1(_faces_compound(solid))
        self._cls = BRepClass3d_SolidClassifier(solid.wrapped)

    def __call__(self, other: Solid) -> float:
        self._ext.LoadS2(_faces_compound(other))
        if not self._ext.Perform() or not self._ext.IsDone():  # pragma: no cover - kernel failure
            raise GeometryError("distance query failed")
        d = float(self._ext.Value())
        if d <= CONTACT_TOL:
            return 0.0
        v = _first_vertex(other)
        self._cls.Perform(gp_Pnt(*v), 1e-7)
        if self._cls.State() in (TopAbs_IN, TopAbs_ON):
            return 0.0
        return d
