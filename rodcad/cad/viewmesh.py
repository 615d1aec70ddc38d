"""Coarse triangle meshes of a build's solids for the 3D view (assembly.glb, view.html).

A view is not a print: each solid is tessellated to :data:`VIEW_DEFLECTION` (0.25 mm, against
the 0.01 mm of the STL files, :mod:`rodcad.cad.mesh`), only its outer shell (a rod's cavities
and closed ball sockets cannot be seen), each B-rep face keeping its own vertices so that the
viewer's normals stay sharp across the solid's edges. Solids that are the same shape (the same
B-rep, or equal volume, area and bounding box: a net's rods of one length and fill, the pins)
are meshed once and drawn as instances.

The parts are the nodes assembly.step is written from (:class:`rodcad.cad.export.AssemblyPart`
trees: the chain's rods and pins by :func:`rodcad.cad.chainfiles.chain_parts`, a chandelier's by
:func:`rodcad.cad.chandelier.chandelier_nodes`), flattened to world placements; a net's are
placed here as :func:`rodcad.cad.net.write_net_files` places them (rods by their pivots, hubs by
their bodies' rotations).

Units: mm.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from build123d import CenterOf, Solid

from rodcad.cad.export import AssemblyGroup, AssemblyPart

__all__ = ["VIEW_ANGULAR", "VIEW_DEFLECTION", "SolidMesh", "ViewMeshes", "net_view_nodes", "view_mesh"]

#: Linear deflection of the view's meshes (mm): with VIEW_ANGULAR, about 11 segments round a pin or a ball, 16 round a 20 mm rod.
VIEW_DEFLECTION = 0.25
#: Angular deflection (rad) of the view's meshes.
VIEW_ANGULAR = 0.6


def view_mesh(solid: Solid, *, deflection: float = VIEW_DEFLECTION,
              angular: float = VIEW_ANGULAR) -> tuple[np.ndarray, np.ndarray]:
    """The outer shell of ``solid`` as triangles: (vertices (n, 3), faces (m, 3)), each B-rep
    face with its own vertices, oriented outward. The solid's triangulation is dropped again
    afterwards (the STL files mesh it afresh, finely)."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepClass3d import BRepClass3d
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.BRepTools import BRepTools
    from OCP.TopAbs import TopAbs_FACE, TopAbs_REVERSED, TopAbs_SOLID
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS

    shape = solid.wrapped
    BRepTools.Clean_s(shape)
    nodes, tris, offset = [], [], 0
    try:
        BRepMesh_IncrementalMesh(shape, float(deflection), False, float(angular), True).Perform()
        shell = BRepClass3d.OuterShell_s(TopoDS.Solid(shape)) if shape.ShapeType() == TopAbs_SOLID else shape
        explorer = TopExp_Explorer(shell if not shell.IsNull() else shape, TopAbs_FACE)
        while explorer.More():
            face = TopoDS.Face(explorer.Current())
            explorer.Next()
            loc = TopLoc_Location()
            tri = BRep_Tool.Triangulation_s(face, loc)
            if tri is None:
                continue
            tr = loc.Transformation()
            n = tri.NbNodes()
            nodes.append(np.array([tri.Node(i).Transformed(tr).Coord() for i in range(1, n + 1)], float))
            t = np.array([tri.Triangle(i).Get() for i in range(1, tri.NbTriangles() + 1)], np.int64) - 1
            if face.Orientation() == TopAbs_REVERSED:
                t = t[:, ::-1]
            tris.append(t + offset)
            offset += n
    finally:
        BRepTools.Clean_s(shape)
    if not nodes:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    return np.vstack(nodes), np.vstack(tris)


@dataclass(frozen=True)
class SolidMesh:
    """One part of the view from a solid.

    Attributes:
        name: the part's name (its assembly.step name).
        group: the group it is drawn in (the assembly group's name, or the caller's).
        key: its mesh's key: parts with one key draw one mesh.
        vertices, faces: the mesh (the solid's own frame, mm).
        matrix: 4 x 4 placement in the assembly's frame (mm).
        color: (r, g, b) in 0..1, or None.
    """

    name: str
    group: str
    key: str
    vertices: np.ndarray
    faces: np.ndarray
    matrix: np.ndarray
    color: tuple[float, float, float] | None


class ViewMeshes:
    """Meshes of solids, each shape meshed once (:func:`view_mesh`)."""

    def __init__(self, deflection: float = VIEW_DEFLECTION) -> None:
        self.deflection = deflection
        self._by_solid: dict[int, tuple[Solid, str]] = {}  # the solid kept: its id stays its own
        self._by_size: dict[tuple, str] = {}
        self.meshes: dict[str, tuple[np.ndarray, np.ndarray]] = {}

    def key(self, solid: Solid) -> str:
        """The key of ``solid``'s mesh, meshing it if no equal shape was meshed before: the
        same solid, or one of the same volume, area, bounding box and centre of mass (a mirror
        image differs in its centre of mass)."""
        seen = self._by_solid.get(id(solid))
        if seen is not None:
            return seen[1]
        bb = solid.bounding_box()
        com = solid.center(CenterOf.MASS)
        size = tuple(round(float(x), 3) for x in (solid.volume, solid.area, bb.min.X, bb.min.Y, bb.min.Z, bb.max.X,
                                                     bb.max.Y, bb.max.Z, com.X, com.Y, com.Z))
        key = self._by_size.get(size)
        if key is None:
            key = f"solid-{len(self.meshes):04d}"
            self.meshes[key] = view_mesh(solid, deflection=self.deflection)
            self._by_size[size] = key
        self._by_solid[id(solid)] = (solid, key)
        return key

    def parts(self, nodes: Sequence[AssemblyPart | AssemblyGroup], group: str = "",
              parent: np.ndarray | None = None, prefix: str = "") -> list[SolidMesh]:
        """Every leaf of an assembly tree with its world placement; a group's parts are named
        ``<group>.<part>`` and drawn in that group."""
        base = np.eye(4) if parent is None else parent
        out: list[SolidMesh] = []
        for node in nodes:
            m = base @ np.asarray(node.location, float)
            if isinstance(node, AssemblyGroup):
                out += self.parts(node.children, node.name, m, f"{prefix}{node.name}.")
                continue
            key = self.key(node.solid)
            v, f = self.meshes[key]
            out.append(SolidMesh(prefix + node.name, group, key, v, f, m,
                                 None if node.color is None else tuple(float(c) for c in node.color)))
        return out


def net_view_nodes(solids, positions: np.ndarray, ends: np.ndarray, rotations: np.ndarray | None
                   ) -> tuple[list[AssemblyPart], list[AssemblyPart]]:
    """A built net's rods and hubs (hub halves) where a net with ``positions`` (n, 3), rod
    pivots ``ends`` (m, 2, 3) and node bodies' ``rotations`` (n, 3, 3) hangs, as
    write_net_files places them in assembly.step: a rod's frame at its first pivot, x along
    its chord, z the upward side of the chord (a bent rod bows toward -z); a hub's at its
    node, turned with its body. Colourless: the view colours them. Returns (rods, hubs)."""
    from rodcad.design.net.frames import rod_matrix

    rods = []
    for e, s in enumerate(solids.rods):
        p0, p1 = np.asarray(ends[e], float)
        rods.append(AssemblyPart(s.label, s, rod_matrix(p0, p1)))
    hubs = []
    for k, s in enumerate(solids.hubs):
        if s is None:
            continue
        m = np.eye(4)
        m[:3, :3] = np.eye(3) if rotations is None else rotations[k]
        m[:3, 3] = positions[k]
        halves = solids.hub_splits[k].parts if solids.hub_splits else [s]
        hubs += [AssemblyPart(p.label, p, m) for p in halves]
    return rods, hubs
