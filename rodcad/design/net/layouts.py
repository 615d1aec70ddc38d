"""Nets generated from a few numbers: a grid over a surface z(x, y), rings and spokes, the
edges of an OBJ mesh. Numbers only (mm, z up); the design file's checks are in
:mod:`rodcad.design.net.target`.

Every generator returns a :class:`NetLayout`: node positions, edges (one rod each) and the
named node sets a design file's ``anchored`` keyword picks from (``corners``, ``boundary``,
``ends``, ``outer``, ``inner``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

__all__ = ["NetLayout", "ObjError", "grid_layout", "mesh_layout", "radial_layout", "read_obj", "subdivide_faces"]


@dataclass
class NetLayout:
    """Nodes and rods laid out in space.

    Attributes:
        positions: (n, 3) node positions (mm, z up).
        edges: (m, 2) node indices of each rod, i < j.
        sets: named node sets (sorted index arrays) that ``anchored`` keywords name.
        shape: (u, v) cells of a grid, (rings, spokes) of a radial net, () otherwise.
        surface: z(x, y, near) of a generated surface (mm), or None (set by the design file's
            checks: :attr:`rodcad.design.net.target.NetTarget.surface`).
    """

    positions: np.ndarray
    edges: np.ndarray
    sets: dict[str, np.ndarray] = field(default_factory=dict)
    shape: tuple[int, ...] = ()
    surface: Callable | None = None


def grid_layout(zfun: Callable[[np.ndarray, np.ndarray], np.ndarray], x: tuple[float, float],
                y: tuple[float, float], u: int, v: int) -> NetLayout:
    """A grid of ``u`` x ``v`` cells over the rectangle ``x`` x ``y`` on the surface z(x, y).

    Node ``iy * (u + 1) + ix`` sits at (x_ix, y_iy, z(x_ix, y_iy)); rods run along the grid
    lines: first every row's x-direction rods, then the y-direction ones. Sets: ``corners``
    (4 nodes), ``boundary`` (the border), ``ends`` (the first and the last column: a strip
    hung from its two ends).
    """
    xs = np.linspace(x[0], x[1], u + 1)
    ys = np.linspace(y[0], y[1], v + 1)
    X, Y = np.meshgrid(xs, ys)
    Z = np.asarray(zfun(X, Y), float) * np.ones_like(X)
    pos = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
    idx = np.arange((u + 1) * (v + 1)).reshape(v + 1, u + 1)
    ex = np.column_stack([idx[:, :-1].ravel(), idx[:, 1:].ravel()])
    ey = np.column_stack([idx[:-1, :].ravel(), idx[1:, :].ravel()])
    border = np.zeros_like(idx, dtype=bool)
    border[0, :] = border[-1, :] = border[:, 0] = border[:, -1] = True
    sets = {
        "corners": np.unique([idx[0, 0], idx[0, -1], idx[-1, 0], idx[-1, -1]]),
        "boundary": np.flatnonzero(border.ravel()),
        "ends": np.unique(np.concatenate([idx[:, 0], idx[:, -1]])),
    }
    return NetLayout(pos, np.vstack([ex, ey]).astype(int), sets, (u, v))


def radial_layout(zfun: Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray], rings: int,
                  spokes: int, radius: tuple[float, float], *, sweep_deg: float = 360.0,
                  start_deg: float = 0.0) -> NetLayout:
    """Rings and spokes: ``rings`` circles of nodes from ``radius[0]`` to ``radius[1]`` (a
    centre node when ``radius[0]`` is 0), joined around each ring and outward along
    ``spokes`` directions.

    With ``sweep_deg`` < 360 the net is a sector: ``spokes`` directions from ``start_deg`` to
    ``start_deg + sweep_deg`` and no rod closing each ring. ``zfun(r, a, x, y)`` gives z (mm)
    from the radius, the angle (rad) and the plan position. Sets: ``outer`` and ``inner``
    (the outermost and innermost ring; the centre node for a net with one), ``boundary``
    (outer ring, plus the sector's first and last spokes), ``ends`` (a sector's first and last
    spokes).
    """
    closed = sweep_deg >= 360.0 - 1e-9
    centre = radius[0] <= 0.0
    if centre:
        r = radius[1] * np.arange(1, rings + 1) / rings
    else:
        r = np.linspace(radius[0], radius[1], rings) if rings > 1 else np.array([radius[1]])
    if closed:
        a = np.radians(start_deg) + 2 * np.pi * np.arange(spokes) / spokes
    else:
        a = np.radians(start_deg + np.linspace(0.0, sweep_deg, spokes))
    R, A = np.meshgrid(r, a, indexing="ij")
    X, Y = R * np.cos(A), R * np.sin(A)
    Z = np.asarray(zfun(R, A, X, Y), float) * np.ones_like(R)
    pos = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
    c = 0
    if centre:
        z0 = float(np.asarray(zfun(np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(1)), float).ravel()[0])
        pos = np.vstack([[0.0, 0.0, z0], pos])
        c = 1
    node = lambda k, s: c + k * spokes + s  # noqa: E731
    edges = []
    for k in range(rings):
        last = spokes if closed else spokes - 1
        edges += [(node(k, s), node(k, (s + 1) % spokes)) for s in range(last)]
    for k in range(rings - 1):
        edges += [(node(k, s), node(k + 1, s)) for s in range(spokes)]
    if centre:
        edges += [(0, node(0, s)) for s in range(spokes)]
    edges = np.sort(np.array(edges, int), axis=1)
    outer = np.array([node(rings - 1, s) for s in range(spokes)])
    inner = np.array([0]) if centre else np.array([node(0, s) for s in range(spokes)])
    sets = {"outer": outer, "inner": np.sort(inner)}
    if not closed:
        ends = np.array([node(k, s) for k in range(rings) for s in (0, spokes - 1)])
        sets["ends"] = np.unique(ends)
        sets["boundary"] = np.unique(np.concatenate([outer, ends] + ([inner] if not centre else [])))
    else:
        sets["boundary"] = outer
    return NetLayout(pos, edges, {k: np.unique(v) for k, v in sets.items()}, (rings, spokes))


class ObjError(ValueError):
    """A problem in an OBJ file, at a line and column of it."""

    def __init__(self, line: int, column: int, message: str) -> None:
        super().__init__(message)
        self.line, self.column, self.message = line, column, message


#: Largest OBJ read (vertices); a net of rods is never that fine.
MAX_OBJ_VERTICES = 20000


def read_obj(text: str) -> tuple[np.ndarray, list[list[int]], list[int]]:
    """The vertices (mm) and faces (0-based vertex indices) of Wavefront OBJ text.

    Reads ``v x y z`` and ``f a b c ...`` (``a``, ``a/t``, ``a/t/n``, ``a//n``; negative
    indices count back from the last vertex); other statements are skipped.

    Returns:
        (vertices (V, 3), faces, the line of each face).

    Raises:
        ObjError: every problem found, the first with its line and column (the others
            joined into its message).
    """
    verts: list[list[float]] = []
    faces: list[list[int]] = []
    face_lines: list[int] = []
    problems: list[ObjError] = []
    for ln, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0]
        parts = line.split()
        if not parts:
            continue
        col = raw.index(parts[0]) + 1
        if parts[0] == "v":
            try:
                xyz = [float(t) for t in parts[1:4]]
            except ValueError:
                problems.append(ObjError(ln, col, "a vertex needs three numbers: v x y z"))
                continue
            if len(xyz) < 3 or not np.all(np.isfinite(xyz)):
                problems.append(ObjError(ln, col, "a vertex needs three finite numbers: v x y z"))
                continue
            verts.append(xyz)
            if len(verts) > MAX_OBJ_VERTICES:
                raise ObjError(ln, col, f"more than {MAX_OBJ_VERTICES} vertices: too fine for a net of rods")
        elif parts[0] == "f":
            face: list[int] = []
            bad = False
            for tok in parts[1:]:
                tcol = col + line[col - 1:].index(tok) if tok in line else col
                try:
                    k = int(tok.split("/")[0])
                except ValueError:
                    problems.append(ObjError(ln, tcol, f"{tok!r} is not a vertex index"))
                    bad = True
                    break
                k = k - 1 if k > 0 else len(verts) + k
                if not 0 <= k < len(verts):
                    problems.append(ObjError(ln, tcol, f"vertex {tok} is not defined above this face "
                                             f"({len(verts)} vertices so far)"))
                    bad = True
                    break
                face.append(k)
            if bad:
                continue
            if len(face) < 3:
                problems.append(ObjError(ln, col, "a face needs at least three vertices"))
                continue
            faces.append(face)
            face_lines.append(ln)
    if problems:
        first = problems[0]
        if len(problems) > 1:
            rest = "; ".join(f"line {p.line}: {p.message}" for p in problems[1:6])
            first = ObjError(first.line, first.column, f"{first.message} (also {rest})")
        raise first
    if not faces:
        raise ObjError(1, 1, "no faces ('f' lines): the rods are the edges of the mesh's faces")
    return np.asarray(verts, float).reshape(-1, 3), faces, face_lines


def mesh_layout(vertices: np.ndarray, faces: list[list[int]]) -> NetLayout:
    """Nodes at the vertices the faces use, a rod along every face edge (shared edges once).

    Sets: ``boundary`` (the nodes on edges of one face only).
    """
    count: dict[tuple[int, int], int] = {}
    for f in faces:
        for a, b in zip(f, f[1:] + f[:1]):
            if a == b:
                continue
            key = (min(a, b), max(a, b))
            count[key] = count.get(key, 0) + 1
    used = np.unique(np.array([k for e in count for k in e], int))
    new = np.full(vertices.shape[0], -1)
    new[used] = np.arange(used.size)
    keys = sorted(count)
    edges = np.array([[new[a], new[b]] for a, b in keys], int).reshape(-1, 2)
    border = np.unique(np.array([new[k] for e in keys if count[e] == 1 for k in e], int))
    return NetLayout(vertices[used].copy(), edges, {"boundary": border}, ())


def subdivide_faces(vertices: np.ndarray, faces: list[list[int]], n: int) -> tuple[np.ndarray, list[list[int]]]:
    """Every face cut into ``n`` x ``n``: a triangle into ``n**2`` triangles on its barycentric
    grid (midpoint subdivision for ``n = 2``), a quad into ``n**2`` quads on its bilinear grid,
    a larger polygon fanned into triangles first. The new vertices lie on the faces (flat);
    a vertex shared by faces is one vertex (merged where they coincide).

    Returns:
        (vertices (V', 3), faces).
    """
    if n <= 1:
        return vertices, faces
    pts: list[np.ndarray] = []
    out: list[list[int]] = []
    for f in faces:
        P = vertices[f]
        if len(f) == 4:
            idx = {}
            for i in range(n + 1):
                for j in range(n + 1):
                    a, b = i / n, j / n
                    idx[i, j] = len(pts)
                    pts.append((1 - a) * (1 - b) * P[0] + a * (1 - b) * P[1] + a * b * P[2] + (1 - a) * b * P[3])
            out += [[idx[i, j], idx[i + 1, j], idx[i + 1, j + 1], idx[i, j + 1]] for i in range(n) for j in range(n)]
            continue
        for q in range(1, len(f) - 1):  # a triangle, or a fan of them
            A, B, C = P[0], P[q], P[q + 1]
            idx = {}
            for i in range(n + 1):
                for j in range(n + 1 - i):
                    idx[i, j] = len(pts)
                    pts.append(A + (B - A) * i / n + (C - A) * j / n)
            for i in range(n):
                for j in range(n - i):
                    out.append([idx[i, j], idx[i + 1, j], idx[i, j + 1]])
                    if i + j < n - 1:
                        out.append([idx[i + 1, j], idx[i + 1, j + 1], idx[i, j + 1]])
    X = np.asarray(pts, float)
    scale = max(float(np.max(np.abs(X))), 1.0)
    key = np.round(X / (1e-9 * scale)).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    inverse = np.asarray(inverse).ravel()
    return X[first], [[int(inverse[k]) for k in face] for face in out]
