"""Independent mass properties of a solid from a mesh, with the mesh's own accuracy.

A test that checks rodcad's B-rep numbers against a mesh (trimesh on an STL) must allow
what the mesh cannot resolve, and no less. The kernel's ``tolerance`` (linear deflection)
is a request, not a guarantee: on a sphere BRepMesh leaves triangles whose midpoints sit
farther from the surface than asked. So the accuracy is measured on the mesh itself.

Every vertex of the mesh lies on the solid's surface. Over one triangle, the gap between
the flat triangle and the surface it spans is, to second order, a quadratic function that
vanishes at the three vertices; with barycentric coordinates ``lam`` it is
``sum_{i<j} c_ij lam_i lam_j`` with ``c_ij = 4 g(m_ij)``, ``g(m_ij)`` the gap at the midpoint
of edge ij. Its largest value over the triangle is at most ``sum g(m_ij)`` (each
``lam_i lam_j <= 1/4``). The gap at an edge midpoint is measured exactly: the distance
from the midpoint to the face's analytic surface (plane, cylinder, sphere, torus, cone).
Hence, for the mesh's volume and first moment,

    |V_mesh - V|            <= sum_t A_t (g_12 + g_23 + g_31)
    |S_mesh - S| about c    <= sum_t A_t (g_12 + g_23 + g_31) |x_t - c|

(``A_t`` the triangle's area, ``x_t`` its centroid). These are the bounds
:func:`measure` returns; they are of the order of the mesh's real error (on a sphere the
same sum over three, ``sum A_t (g_12 + g_23 + g_31) / 3``, is the error itself to
round-off), and they follow from the mesh drawn, on any machine.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np


@dataclass(frozen=True)
class MeshMeasure:
    """Volume and centre of volume of a solid measured on its mesh (trimesh), with bounds.

    Attributes:
        volume: the mesh's volume (mm^3).
        center: the mesh's centre of volume (mm, the solid's frame).
        volume_bound: |volume - the solid's volume| is at most this (mm^3).
        moment_bound: the mesh's first moment minus the solid's, both about ``about``, is
            at most this long (mm^4).
        about: the point the first moments are taken about (mm; the mesh's centre unless
            :func:`measure` was given one).
        triangles: how many triangles the mesh has.
    """

    volume: float
    center: np.ndarray
    volume_bound: float
    moment_bound: float
    triangles: int
    about: np.ndarray

    @property
    def center_bound(self) -> float:
        """A bound (mm) on |center - the solid's centre of volume|: about the centre the mesh's
        first moment is 0, so the solid's is at most ``moment_bound`` long (when ``about`` is
        the centre)."""
        if not np.allclose(self.about, self.center, rtol=0, atol=1e-12):
            raise ValueError("center_bound needs the moments about the mesh's centre (about=None)")
        return self.moment_bound / max(self.volume - self.volume_bound, 1e-300)


def _surface_distance(face):
    """A function of (n, 3) points: their distance (mm) to the face's analytic surface."""
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.GeomAbs import GeomAbs_Cone, GeomAbs_Cylinder, GeomAbs_Plane, GeomAbs_Sphere, GeomAbs_Torus

    s = BRepAdaptor_Surface(face.wrapped)
    kind = s.GetType()

    def axis(ax3):
        return np.array(ax3.Location().Coord()), np.array(ax3.Direction().Coord())

    if kind == GeomAbs_Plane:
        origin, normal = axis(s.Plane().Position())
        return lambda p: np.abs((p - origin) @ normal)
    if kind == GeomAbs_Sphere:
        centre, radius = np.array(s.Sphere().Location().Coord()), s.Sphere().Radius()
        return lambda p: np.abs(np.linalg.norm(p - centre, axis=1) - radius)
    if kind == GeomAbs_Cylinder:
        origin, d = axis(s.Cylinder().Position())
        radius = s.Cylinder().Radius()

        def cylinder(p):
            q = p - origin
            return np.abs(np.linalg.norm(q - np.outer(q @ d, d), axis=1) - radius)
        return cylinder
    if kind == GeomAbs_Torus:
        origin, d = axis(s.Torus().Position())
        major, minor = s.Torus().MajorRadius(), s.Torus().MinorRadius()

        def torus(p):
            q = p - origin
            z = q @ d
            return np.abs(np.hypot(np.linalg.norm(q - np.outer(z, d), axis=1) - major, z) - minor)
        return torus
    if kind == GeomAbs_Cone:
        origin, d = axis(s.Cone().Position())
        r0, half = s.Cone().RefRadius(), s.Cone().SemiAngle()

        def cone(p):  # distance in the meridian plane to the line r = r0 + z tan(half)
            q = p - origin
            z = q @ d
            r = np.linalg.norm(q - np.outer(z, d), axis=1)
            return np.abs((r - r0) * np.cos(half) - z * np.sin(half))
        return cone
    raise NotImplementedError(f"no exact distance to a surface of type {kind} (face of the solid)")


def _triangles(face) -> np.ndarray:
    """The face's triangulation as (m, 3, 3) corner coordinates (mm)."""
    from OCP.BRep import BRep_Tool
    from OCP.TopLoc import TopLoc_Location

    loc = TopLoc_Location()
    tri = BRep_Tool.Triangulation_s(face.wrapped, loc)
    if tri is None:
        raise ValueError("the face has no triangulation: mesh the solid first")
    tr = loc.Transformation()
    nodes = np.array([tri.Node(i + 1).Transformed(tr).Coord() for i in range(tri.NbNodes())])
    idx = np.array([tri.Triangle(i + 1).Get() for i in range(tri.NbTriangles())], dtype=int) - 1
    return nodes[idx]


def measure(solid, path: str | Path, *, tolerance: float, angular_tolerance: float = 0.05,
            about=None) -> MeshMeasure:
    """Mesh ``solid`` into an STL at ``path`` (build123d's exporter), read it with trimesh,
    and bound the mesh's error from the triangles the exporter drew (module docstring).

    Args:
        solid: a build123d Solid.
        path: where to write the STL.
        tolerance: linear deflection asked of the mesher (mm).
        angular_tolerance: angular deflection asked of the mesher (rad).
        about: (3,) the point to bound first moments about (mm); None = the mesh's centre.
    """
    import build123d
    import trimesh

    assert build123d.export_stl(solid, str(path), tolerance=tolerance, angular_tolerance=angular_tolerance)
    mesh = trimesh.load(str(path), force="mesh")
    volume, center = float(mesh.volume), np.asarray(mesh.center_mass, float)
    about = center if about is None else np.asarray(about, float)
    vb = mb = 0.0
    count = 0
    for face in solid.faces():  # the triangulation the STL was written from
        t = _triangles(face)
        count += len(t)
        dist = _surface_distance(face)
        a, b, c = t[:, 0], t[:, 1], t[:, 2]
        area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
        gap = dist((a + b) / 2) + dist((b + c) / 2) + dist((c + a) / 2)
        vb += float(np.sum(area * gap))
        mb += float(np.sum(area * gap * np.linalg.norm((a + b + c) / 3 - about, axis=1)))
    return MeshMeasure(volume, center, vb, mb, count, about)
