"""Triangle meshes of solids for printing: one tessellation for every STL and 3MF rodcad writes.

OCCT's BRepMesh is asked for an absolute linear deflection (no point of the mesh farther
than ``deflection`` mm from the solid's surface), not one relative to each face's size
(build123d's exporters' choice, which leaves a 45 mm rod's curved faces 0.05-0.4 mm off
and its volume up to 0.3 % short). The faces' triangulations are then joined into one
closed mesh: the vertices of an edge shared by two faces, computed from each face's
surface, are welded (they differ by nanometres), the zero-area triangles OCCT leaves at
sphere poles are dropped, and the result is checked closed and oriented (every edge in
exactly two triangles, once each way) with a volume within ``deflection`` times the
solid's area of the solid's.

Units: mm.
"""

from __future__ import annotations

import math
import os
import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from build123d import Solid

from rodcad.cad.solids import GeometryError

__all__ = ["DEFLECTION", "ANGULAR", "PRINT_ANGLE_DEG", "PRINT_LAYER_SHARE", "WELD", "TriangleMesh",
           "closed_oriented", "mesh_solid", "print_deflection", "read_stl", "write_stl"]

#: Linear deflection of every mesh rodcad writes (mm, absolute: a fifth of a 0.05 mm print
#: resolution): a mesh's volume is then within this times the solid's area of the solid's
#: (about 4e-3 of a rod's volume; measured on rods with cavities, 7e-5).
DEFLECTION = 0.01
#: Angular deflection (rad); loose, so that the linear deflection decides.
ANGULAR = 0.5
#: The default linear deflection of the meshes a net's parts are printed from, as a share of
#: the layer height (:func:`print_deflection`).
PRINT_LAYER_SHARE = 0.15
#: Their default angular deflection (degrees; 0.2 rad).
PRINT_ANGLE_DEG = 11.459


def print_deflection(printer=None, layer_height: float = 0.2) -> tuple[float, float]:
    """(linear mm, angular rad) deflection of the STL and 3MF meshes a part is printed from:
    the catalog printer's ``mesh_deflection`` and ``mesh_angle`` where it sets them, else
    ``PRINT_LAYER_SHARE`` of the layer height and ``PRINT_ANGLE_DEG``.

    Why these defaults. The slicer prints the mesh, not the solid: its facets must not show
    and must not starve the part of plastic. A 0.2 mm layer leaves ridges about 0.05 mm deep
    on every wall and the nozzle (0.4 mm) rounds corners further, so a chord 0.03 mm off the
    surface (0.15 of the layer) cannot be seen. The mesh lies inside a convex surface, so it
    holds less plastic than the solid: measured on a grid net's parts (9 mm rods, a 24 mm
    hub whole and in halves) with 0.03 mm and 0.2 rad, 0.24-0.30 % less, a tenth of the
    print's 3 % mass tolerance (the angular bound is what keeps a 9 mm rod's body at 31
    facets round; with 0.5 rad it was 0.6-1.1 % light). Finer meshes cost size and time for
    nothing the print shows: 0.0015 mm (the earlier rods' setting) wrote 8 times the
    triangles for 0.04 % of volume. Masses, centres of mass and every check are taken from
    the exact B-rep, never from a mesh.
    """
    lin = getattr(printer, "mesh_deflection", None)
    ang = getattr(printer, "mesh_angle", None)
    lin = float(lin) if lin is not None else PRINT_LAYER_SHARE * float(layer_height)
    return lin, math.radians(float(ang if ang is not None else PRINT_ANGLE_DEG))


#: Vertices closer than this (mm) are one vertex: a face narrower than it (a flush stop face
#: chamfered by 1e-5 degrees is 2e-6 mm wide) collapses onto its edges instead of leaving
#: slivers a 3MF reader rejects. The rods' smallest features (layer gaps) are 0.3 mm.
WELD = 1e-4


@dataclass(frozen=True)
class TriangleMesh:
    """A closed, oriented triangle mesh.

    Attributes:
        vertices: (n, 3) float, mm.
        triangles: (m, 3) vertex indices, counter-clockwise seen from outside.
        deflection: the largest distance (mm) of the mesh from the solid's surface.
    """

    vertices: np.ndarray
    triangles: np.ndarray
    deflection: float

    @property
    def volume(self) -> float:
        """Enclosed volume (mm^3), by the divergence theorem."""
        a, b, c = (self.vertices[self.triangles[:, k]] for k in range(3))
        return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)

    def moved(self, matrix) -> TriangleMesh:
        """The mesh under a rigid 4 x 4 transform."""
        m = np.asarray(matrix, dtype=float)
        return TriangleMesh(self.vertices @ m[:3, :3].T + m[:3, 3], self.triangles, self.deflection)


def _face_triangles(solid: Solid) -> tuple[np.ndarray, np.ndarray]:
    """Every face's triangulation, concatenated: (nodes (n, 3), triangles (m, 3)),
    oriented outward."""
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_REVERSED
    from OCP.TopLoc import TopLoc_Location

    nodes, tris, offset = [], [], 0
    for face in solid.faces():
        loc = TopLoc_Location()
        tri = BRep_Tool.Triangulation_s(face.wrapped, loc)
        if tri is None:
            raise GeometryError("a face of the solid has no triangulation")
        tr = loc.Transformation()
        n = tri.NbNodes()
        nodes.append(np.array([tri.Node(i).Transformed(tr).Coord() for i in range(1, n + 1)], dtype=float))
        t = np.array([tri.Triangle(i).Get() for i in range(1, tri.NbTriangles() + 1)], dtype=np.int64) - 1
        if face.wrapped.Orientation() == TopAbs_REVERSED:
            t = t[:, ::-1]
        tris.append(t + offset)
        offset += n
    if not nodes:
        raise GeometryError("the solid has no faces to mesh")
    return np.vstack(nodes), np.vstack(tris)


def _weld(points: np.ndarray, tol: float) -> np.ndarray:
    """An index per point: points within ``tol`` of each other (transitively) share one."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    pairs = cKDTree(points).query_pairs(tol, output_type="ndarray").reshape(-1, 2)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(points), len(points)))
    return connected_components(graph, directed=False)[1]


def closed_oriented(triangles: np.ndarray) -> bool:
    """Every directed edge once, and its reverse once: closed and consistently oriented."""
    e = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    key = e[:, 0] * (int(e.max()) + 1) + e[:, 1]
    rev = e[:, 1] * (int(e.max()) + 1) + e[:, 0]
    return bool(np.unique(key).size == key.size and np.array_equal(np.sort(key), np.sort(rev)))


def mesh_solid(solid: Solid, *, deflection: float = DEFLECTION, angular: float = ANGULAR) -> TriangleMesh:
    """The solid as one closed, oriented triangle mesh (module docstring).

    The solid's own triangulation, if any, is replaced and then dropped again, so later
    meshing of the same solid starts afresh.

    Args:
        solid: what to mesh.
        deflection: largest distance (mm) of the mesh from the surface.
        angular: angular deflection (rad).

    Raises:
        GeometryError: the mesh does not close, or its volume is off the solid's by more
            than ``deflection`` times its area.
    """
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.BRepTools import BRepTools

    BRepTools.Clean_s(solid.wrapped)
    try:
        BRepMesh_IncrementalMesh(solid.wrapped, float(deflection), False, float(angular), True).Perform()
        nodes, tris = _face_triangles(solid)
    finally:
        BRepTools.Clean_s(solid.wrapped)
    label = _weld(nodes, WELD)
    _, first = np.unique(label, return_index=True)
    vertices = nodes[first]
    t = label[tris]
    keep = (t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 2] != t[:, 0])
    t = t[keep]
    mesh = TriangleMesh(vertices, t, float(deflection))
    if not closed_oriented(t):
        raise GeometryError(f"the mesh of {solid.label or 'a solid'} does not close after welding")
    volume, area = float(solid.volume), float(solid.area)
    if abs(mesh.volume - volume) > deflection * area:
        raise GeometryError(f"the mesh of {solid.label or 'a solid'} encloses {mesh.volume:.4f} mm^3, the solid "
                            f"{volume:.4f} mm^3: more than its deflection ({deflection:g} mm) times its area")
    return mesh


def read_stl(data: bytes, deflection: float = DEFLECTION) -> TriangleMesh:
    """The mesh of a binary STL that :func:`write_stl` wrote (``deflection``: the one it was
    meshed with), its vertices rejoined: a welded mesh's corners are written as the same
    float32 numbers wherever they recur, and distinct ones lie :data:`WELD` apart (far above
    float32's 1e-5 mm at a metre), so equal numbers are one vertex and nothing else is.

    Raises:
        GeometryError: the data is not a binary STL, or its mesh is not closed and oriented.
    """
    if len(data) < 84:
        raise GeometryError("not a binary STL: shorter than its header")
    (count,) = struct.unpack_from("<I", data, 80)
    rec = np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
    if len(data) != 84 + count * rec.itemsize:
        raise GeometryError(f"not a binary STL of {count} triangles: {len(data)} bytes")
    corners = np.ascontiguousarray(np.frombuffer(data, dtype=rec, count=count, offset=84)["v"].reshape(-1, 3))
    key = corners.view(np.dtype((np.void, corners.itemsize * 3))).ravel()  # a corner's 12 bytes
    _, first, index = np.unique(key, return_index=True, return_inverse=True)
    order = np.argsort(first)  # vertices in the order the STL first names them (as meshed: it packs tighter)
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    vertices = corners[first[order]]
    t = rank[index.ravel()].reshape(-1, 3).astype(np.int64)
    if not closed_oriented(t):
        raise GeometryError("the STL's mesh is not closed and oriented")
    return TriangleMesh(vertices.astype(float), t, float(deflection))


def write_stl(mesh: TriangleMesh, path: str | os.PathLike[str], name: str = "rodcad") -> Path:
    """Write a binary STL (mm)."""
    path = Path(path)
    v = mesh.vertices[mesh.triangles]  # (m, 3, 3)
    normal = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    norm = np.linalg.norm(normal, axis=1, keepdims=True)
    normal = np.divide(normal, norm, out=np.zeros_like(normal), where=norm > 0)
    rec = np.zeros(len(v), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
    rec["n"], rec["v"] = normal, v
    header = name.encode("ascii", "replace")[:80].ljust(80, b" ")
    with open(path, "wb") as f:
        f.write(header)
        f.write(struct.pack("<I", len(v)))
        f.write(rec.tobytes())
    return path
