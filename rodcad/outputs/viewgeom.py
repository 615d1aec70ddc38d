"""The 3D view's geometry as numbers: the parts of a scene and the simple meshes drawn where no
solid was built (``--no-cad``): a chain rod as its printed outline (its arc and rounded ends)
extruded by its thickness, tubes along net rods' centrelines, spheres for hubs, cylinders for
pins and anchors.

A :class:`ViewScene` is what :mod:`rodcad.outputs.view` writes to ``assembly.glb`` and
``view.html``: named parts, each a mesh (shared by every part that has the same ``key``: glTF
instancing, so a net of thousands of equal rods stays light) placed by a 4 x 4 matrix (which
may scale a unit mesh), its colour, and the design's numbers for the side panel.

Units: mm; meshes are (vertices (n, 3) float, faces (m, 3) int), counter-clockwise seen from
outside. Vertices are shared only where the surface is smooth: the viewer averages the faces'
normals at a shared vertex, so an edge between faces that do not share vertices stays sharp.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["Mesh", "ViewPart", "ViewScene", "Y_UP", "cylinder", "merge", "rod_slab", "sphere", "tube",
           "unit_cylinder"]

#: Rotation taking a z-up world (nets, chandeliers) to glTF's y-up: (x, y, z) -> (x, z, -y).
Y_UP = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0], [0, -1.0, 0, 0], [0, 0, 0, 1.0]])


@dataclass(frozen=True)
class Mesh:
    """A triangle mesh: ``vertices`` (n, 3) mm, ``faces`` (m, 3) vertex indices."""

    vertices: np.ndarray
    faces: np.ndarray

    @property
    def triangles(self) -> int:
        return int(len(self.faces))


@dataclass
class ViewPart:
    """One named part of the view (a node of assembly.glb).

    Attributes:
        name: the node's name (the part's name in design.json and assembly.step).
        group: the kind it belongs to ('rods', 'hubs', 'pins', 'anchors', 'frame', 'fixture', or
            a chandelier's chain name); a node of the glb groups its parts.
        key: the mesh it draws; parts with one key share one mesh (and colour).
        mesh: that mesh (needed for the first part of a key only).
        matrix: 4 x 4 placement of the mesh in the design's frame (mm; may scale a unit mesh).
        color: (r, g, b) in 0..1 (sRGB).
    """

    name: str
    group: str
    key: str
    mesh: Mesh | None
    matrix: np.ndarray
    color: tuple[float, float, float]


@dataclass
class ViewScene:
    """Everything the view shows.

    Attributes:
        name: the design's name.
        parts: the parts, in the order of their tables.
        up: 4 x 4 from the design's frame to glTF's y-up frame (identity for a chain, whose
            plane is xy with y up; :data:`Y_UP` for z-up nets and chandeliers).
        panel: the side panel's numbers (:func:`rodcad.outputs.viewscene` builds them from
            design.json): title, summary rows, legend, tables.
        view: the initial camera: yaw and pitch (deg) about the structure's centre.
    """

    name: str
    parts: list[ViewPart] = field(default_factory=list)
    up: np.ndarray = field(default_factory=lambda: np.eye(4))
    panel: dict[str, Any] = field(default_factory=dict)
    view: dict[str, float] = field(default_factory=lambda: {"yaw": -25.0, "pitch": 12.0})

    @property
    def meshes(self) -> dict[str, Mesh]:
        """Each key's mesh (the first part's that has one)."""
        out: dict[str, Mesh] = {}
        for p in self.parts:
            if p.key not in out and p.mesh is not None:
                out[p.key] = p.mesh
        return out


def merge(meshes: list[Mesh]) -> Mesh:
    """One mesh of several (their vertices kept apart)."""
    v, f, n = [], [], 0
    for m in meshes:
        v.append(np.asarray(m.vertices, float))
        f.append(np.asarray(m.faces, np.int64) + n)
        n += len(m.vertices)
    return Mesh(np.vstack(v), np.vstack(f))


def _ring_faces(a: int, b: int, k: int) -> np.ndarray:
    """Quads between two closed rings of ``k`` vertices starting at ``a`` and ``b`` (b after a
    along the axis; counter-clockwise rings seen from the axis' end), as triangles facing out."""
    i = np.arange(k)
    j = (i + 1) % k
    return np.concatenate([np.column_stack([a + i, b + j, b + i]), np.column_stack([a + i, a + j, b + j])])


def tube(path: np.ndarray, radius: float, sections: int = 12, caps: bool = True) -> Mesh:
    """A round tube of ``radius`` along a polyline ``path`` (k, 3), its rings turned with the
    path (parallel transport), with flat caps at both ends."""
    p = np.asarray(path, float)
    p = p[np.r_[True, np.linalg.norm(np.diff(p, axis=0), axis=1) > 1e-9]]  # no repeated points
    if len(p) < 2:
        return Mesh(np.zeros((0, 3)), np.zeros((0, 3), np.int64))
    seg = np.diff(p, axis=0)
    seg /= np.linalg.norm(seg, axis=1, keepdims=True)
    # at a vertex the mean of its two segments' directions; where they are opposite (a path
    # that turns back: a frame's bar drawn there and back) the incoming one
    t = np.vstack([seg[:1], seg[:-1] + seg[1:], seg[-1:]])
    flat = np.linalg.norm(t, axis=1) < 1e-9
    t[flat] = np.vstack([seg[:1], seg])[flat]
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    ref = np.array([0.0, 0.0, 1.0]) if abs(t[0, 2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    u = np.cross(t[0], ref)
    u /= np.linalg.norm(u)
    ang = np.linspace(0, 2 * np.pi, sections, endpoint=False)
    rings = []
    for k in range(len(p)):
        if k:
            u = u - np.dot(u, t[k]) * t[k]
            u /= np.linalg.norm(u)
        w = np.cross(t[k], u)
        rings.append(p[k] + radius * (np.outer(np.cos(ang), u) + np.outer(np.sin(ang), w)))
    verts = list(rings)
    faces = [_ring_faces(k * sections, (k + 1) * sections, sections) for k in range(len(p) - 1)]
    n = len(p) * sections
    if caps:  # their own vertices: a sharp edge at the rim
        for k, sign in ((0, -1), (len(p) - 1, 1)):
            verts += [rings[k], p[k][None]]
            c = n + sections
            i = np.arange(sections)
            j = (i + 1) % sections
            tri = np.column_stack([np.full(sections, c), n + i, n + j])
            faces.append(tri if sign > 0 else tri[:, ::-1])
            n += sections + 1
    return Mesh(np.vstack(verts), np.vstack(faces))


def cylinder(p0, p1, radius: float, sections: int = 12) -> Mesh:
    """A closed cylinder of ``radius`` from ``p0`` to ``p1``."""
    return tube(np.array([p0, p1], float), radius, sections)


def unit_cylinder(radius: float, sections: int = 12) -> Mesh:
    """A closed cylinder of ``radius`` from (0, 0, 0) to (1, 0, 0): a straight rod of any
    length, scaled along x by its node's matrix."""
    return cylinder([0.0, 0, 0], [1.0, 0, 0], radius, sections)


def sphere(radius: float, rings: int = 8, segments: int = 14) -> Mesh:
    """A UV sphere of ``radius`` about the origin."""
    th = np.linspace(0, np.pi, rings + 1)[1:-1]
    ph = np.linspace(0, 2 * np.pi, segments, endpoint=False)
    body = np.stack([np.outer(np.sin(th), np.cos(ph)), np.outer(np.sin(th), np.sin(ph)),
                     np.outer(np.cos(th), np.ones_like(ph))], axis=-1).reshape(-1, 3)
    verts = np.vstack([[0, 0, 1.0], body, [0, 0, -1.0]]) * radius
    i = np.arange(segments)
    j = (i + 1) % segments
    faces = [np.column_stack([np.zeros(segments, int), 1 + i, 1 + j])]
    for r in range(rings - 2):
        a, b = 1 + r * segments, 1 + (r + 1) * segments
        faces.append(np.column_stack([a + i, b + i, b + j]))
        faces.append(np.column_stack([a + i, b + j, a + j]))
    last = len(verts) - 1
    a = 1 + (rings - 2) * segments
    faces.append(np.column_stack([np.full(segments, last), a + j, a + i]))
    return Mesh(verts, np.vstack(faces))


def rod_slab(centre: np.ndarray, height: float, thickness: float, cap_segments: int = 8) -> Mesh:
    """A chain rod as printed, simply: its outline in the chain plane (the band of ``height``
    about its centreline ``centre`` (k, 2), an arc or chord from joint to joint, rounded about
    both joints) extruded by ``thickness`` along z, centred on the plane.

    Args:
        centre: (k, 2) the centreline, first joint to second (mm).
        height: the body's height in the chain plane (mm).
        thickness: along the hinge axes (mm).
        cap_segments: segments of each rounded end.
    """
    c = np.asarray(centre, float)
    t = np.gradient(c, axis=0) if len(c) > 2 else np.repeat([c[-1] - c[0]], len(c), axis=0)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    n = np.column_stack([-t[:, 1], t[:, 0]])  # left of the direction of travel
    h = height / 2
    left, right = c + h * n, c - h * n
    phi = np.linspace(0, np.pi, cap_segments + 1)[1:-1]
    end = c[-1] + h * (np.outer(np.cos(phi), n[-1]) + np.outer(np.sin(phi), t[-1]))  # left -> right about q
    start = c[0] + h * (np.outer(np.cos(phi), -n[0]) + np.outer(np.sin(phi), -t[0]))  # right -> left about p
    loop = np.vstack([left, end, right[::-1], start])  # clockwise: the body on the right
    k = len(c)
    # the face: quads across the band, fans about the joints
    tris = [np.column_stack([np.arange(k - 1), np.arange(1, k), 2 * k + cap_segments - 2 - np.arange(1, k)]),
            np.column_stack([np.arange(k - 1), 2 * k + cap_segments - 2 - np.arange(1, k),
                             2 * k + cap_segments - 1 - np.arange(1, k)])]
    fan_q = np.arange(k - 1, k + cap_segments)  # left[-1], end..., right[-1]
    fan_p = np.r_[np.arange(2 * k + cap_segments - 2, len(loop)), 0]  # right[0], start..., left[0]
    for fan in (fan_q, fan_p):
        tris.append(np.column_stack([np.full(len(fan) - 2, fan[0]), fan[1:-1], fan[2:]]))
    face = np.vstack(tris)  # clockwise in xy: seen from -z
    m = len(loop)
    z = thickness / 2
    top = np.column_stack([loop, np.full(m, z)])
    bottom = np.column_stack([loop, np.full(m, -z)])
    i = np.arange(m)
    j = (i + 1) % m
    # the side: the loop runs clockwise seen from +z, so (bottom i, top i, top j) faces out
    side = np.concatenate([np.column_stack([2 * m + i, 3 * m + i, 3 * m + j]),
                           np.column_stack([2 * m + i, 3 * m + j, 2 * m + j])])
    faces = np.vstack([face[:, ::-1], m + face, side])
    return Mesh(np.vstack([top, bottom, bottom, top]), faces)


def arc_segments(curvature: float, length: float, step_deg: float = 8.0) -> int:
    """Segments enough for a rod's arc (about ``step_deg`` each; 1 for a straight rod)."""
    turn = abs(float(curvature)) * float(length)
    return max(1, int(math.ceil(math.degrees(turn) / step_deg)))
