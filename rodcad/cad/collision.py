"""Collision and clearance queries on rod solids: the pair scene the joint-limit search
probes, and the clearance field the cavity and insert layouts are checked against.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from build123d import Solid
from OCP.BRep import BRep_Builder
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
from OCP.BRepClass3d import BRepClass3d_SolidClassifier
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.gp import gp_Ax1, gp_Dir, gp_Pnt, gp_Trsf, gp_Vec
from OCP.TopAbs import TopAbs_IN, TopAbs_ON
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS_Compound

from rodcad.cad.solids import CONTACT_TOL, GeometryError, collision_proxy, rod_solid
from rodcad.catalog.model import RodGeometry

__all__ = [
    "Clearance",
    "DistanceTo",
    "faces_compound",
    "first_vertex",
    "PairScene",
    "Probe",
    "solid_distance",
    "void_walls",
]


def faces_compound(solid: Solid) -> TopoDS_Compound:
    builder = BRep_Builder()
    comp = TopoDS_Compound()
    builder.MakeCompound(comp)
    for f in solid.faces():
        builder.Add(comp, f.wrapped)
    return comp


def first_vertex(solid: Solid) -> np.ndarray:
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
        self._left_faces = faces_compound(lp)
        self._right_faces = faces_compound(rp)
        self._left_cls = BRepClass3d_SolidClassifier(lp.wrapped)
        self._right_cls = BRepClass3d_SolidClassifier(rp.wrapped)
        self._left_vertex = first_vertex(lp)
        self._right_vertex = first_vertex(rp)
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
        self._ext.LoadS1(faces_compound(solid))
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


def solid_distance(a: Solid, b: object) -> float:
    """Smallest distance between two shapes (BRepExtrema, mm); 0 if they touch."""
    ext = BRepExtrema_DistShapeShape(a.wrapped, b.wrapped if hasattr(b, "wrapped") else b)  # type: ignore[attr-defined]
    if not ext.IsDone():  # pragma: no cover - kernel failure
        raise GeometryError("distance query failed")
    return float(ext.Value())


class DistanceTo:
    """Distance from one fixed solid (e.g. the frame) to others placed near it (mm).

    Returns 0 when the solids touch, interfere or one holds the other.
    """

    def __init__(self, solid: Solid) -> None:
        self._ext = BRepExtrema_DistShapeShape()
        self._ext.LoadS1(faces_compound(solid))
        self._cls = BRepClass3d_SolidClassifier(solid.wrapped)

    def __call__(self, other: Solid) -> float:
        self._ext.LoadS2(faces_compound(other))
        if not self._ext.Perform() or not self._ext.IsDone():  # pragma: no cover - kernel failure
            raise GeometryError("distance query failed")
        d = float(self._ext.Value())
        if d <= CONTACT_TOL:
            return 0.0
        v = first_vertex(other)
        self._cls.Perform(gp_Pnt(*v), 1e-7)
        if self._cls.State() in (TopAbs_IN, TopAbs_ON):
            return 0.0
        return d


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
    faces = faces_compound(solid)
    to_faces = np.array([solid_distance(v, faces) for v in voids])
    between = math.inf
    boxes = [v.bounding_box() for v in voids]
    for i in range(len(voids)):
        for j in range(i + 1, len(voids)):
            a, b = boxes[i], boxes[j]
            gap = max(a.min.X - b.max.X, b.min.X - a.max.X, a.min.Y - b.max.Y, b.min.Y - a.max.Y,
                      a.min.Z - b.max.Z, b.min.Z - a.max.Z)
            if gap <= near:
                between = min(between, solid_distance(voids[i], voids[j]))
    return to_faces, between
