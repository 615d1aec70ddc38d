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
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
from build123d import CenterOf, Plane, Solid, Vector, Wire, Face, export_step as _export_step
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
    "Clearance",
    "GeometryError",
    "MassProperties",
    "PairScene",
    "Probe",
    "build_rod",
    "collision_proxy",
    "export_step",
    "hinge_zone",
    "import_step",
    "is_valid_solid",
    "mass_properties",
    "rod_solid",
    "with_spherical_voids",
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
