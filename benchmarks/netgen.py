"""Nets for tests and benchmarks: grids over a surface, radial nets, seeded jitter.

Every generator returns a :class:`NetSpec`: node positions (mm, z up), edges, rod lengths
(the distances of those positions, so the positions are a configuration of the rods) and
the anchored nodes. Importable by the tests (``tests/conftest.py`` puts this folder on
``sys.path``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

__all__ = ["NetSpec", "grid_net", "plan_pivots", "radial_net", "jitter", "random_grid", "random_masses"]


@dataclass
class NetSpec:
    """A net laid out in space.

    Attributes:
        positions: (n, 3) node positions, mm.
        edges: (m, 2) node indices of each rod.
        lengths: (m,) the positions' pivot distances, mm.
        anchored: (k,) anchored node indices, ascending.
        shape: (u, v) cells for a grid, (rings, spokes) for a radial net.
    """

    positions: np.ndarray
    edges: np.ndarray
    lengths: np.ndarray
    anchored: np.ndarray
    shape: tuple[int, int] = (0, 0)

    @property
    def n(self) -> int:
        return self.positions.shape[0]

    @property
    def m(self) -> int:
        return self.edges.shape[0]

    @property
    def size(self) -> float:
        """The largest extent of the positions."""
        return float(np.max(np.ptp(self.positions, axis=0)))


def _lengths(positions: np.ndarray, edges: np.ndarray) -> np.ndarray:
    return np.linalg.norm(positions[edges[:, 1]] - positions[edges[:, 0]], axis=1)


def plan_pivots(spec: NetSpec, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Node bodies for ``spec``'s nodes: each rod's pivots ``radius`` out from its nodes along
    the rod's direction in plan (horizontal). Returns ((m, 2, 3) pivots, (m,) the rods'
    pivot-to-pivot lengths at the positions)."""
    pos, e = spec.positions, spec.edges
    d = pos[e[:, 1]] - pos[e[:, 0]]
    d[:, 2] = 0
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    piv = np.stack([radius * d, -radius * d], axis=1)
    return piv, np.linalg.norm(pos[e[:, 1]] + piv[:, 1] - pos[e[:, 0]] - piv[:, 0], axis=1)


def grid_net(u: int, v: int, *, x=(0.0, 160.0), y=(0.0, 160.0), z=None, anchored="corners",
             boundary_rods: bool = True) -> NetSpec:
    """A rectangular grid of u x v cells on the surface z(x, y).

    Node ``iy * (u + 1) + ix`` sits at (x_ix, y_iy, z(x_ix, y_iy)); rods run along the grid
    lines (first the x-direction rods, row by row, then the y-direction ones).

    Args:
        u, v: cells along x and along y (>= 1).
        x, y: the rectangle's extent (mm).
        z: callable z(x, y) on arrays (mm); None = the plane z = 0.
        anchored: "corners", "boundary", or a list of node indices.
        boundary_rods: with anchored "boundary", keep the rods between two boundary nodes
            (rigid links between anchors); False leaves them out.
    """
    xs = np.linspace(x[0], x[1], u + 1)
    ys = np.linspace(y[0], y[1], v + 1)
    X, Y = np.meshgrid(xs, ys)
    Z = np.zeros_like(X) if z is None else np.asarray(z(X, Y), float) * np.ones_like(X)
    pos = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
    idx = np.arange((u + 1) * (v + 1)).reshape(v + 1, u + 1)
    ex = np.column_stack([idx[:, :-1].ravel(), idx[:, 1:].ravel()])
    ey = np.column_stack([idx[:-1, :].ravel(), idx[1:, :].ravel()])
    edges = np.vstack([ex, ey])
    border = np.zeros_like(idx, dtype=bool)
    border[0, :] = border[-1, :] = border[:, 0] = border[:, -1] = True
    if isinstance(anchored, str):
        if anchored == "corners":
            anch = np.array(sorted({idx[0, 0], idx[0, -1], idx[-1, 0], idx[-1, -1]}))
        elif anchored == "boundary":
            anch = np.flatnonzero(border.ravel())
            if not boundary_rods:
                both = border.ravel()[edges].all(axis=1)
                edges = edges[~both]
        else:
            raise ValueError(f"anchored must be 'corners', 'boundary' or a list, got {anchored!r}")
    else:
        anch = np.unique(np.asarray(anchored, int))
    return NetSpec(pos, edges, _lengths(pos, edges), anch, (u, v))


def radial_net(rings: int, spokes: int, *, radius: float = 80.0, z=None, centre: bool = True,
               anchored="outer") -> NetSpec:
    """Rings and spokes: ``rings`` circles of ``spokes`` nodes, joined around and outward.

    Node 0 is the centre (when ``centre``); ring k (1..rings) at radius k * radius / rings
    holds nodes ``c + (k - 1) * spokes + s``.

    Args:
        rings, spokes: circles (>= 1) and nodes per circle (>= 3).
        radius: the outer ring's radius (mm).
        z: callable z(r) (mm) of the radius; None = flat.
        centre: a centre node joined to the first ring by spokes.
        anchored: "outer" (the outer ring), "centre", or a list of node indices.
    """
    c = 1 if centre else 0
    r = radius * np.arange(1, rings + 1) / rings
    phi = 2 * np.pi * np.arange(spokes) / spokes
    R, P = np.meshgrid(r, phi, indexing="ij")
    zf = (lambda rr: np.zeros_like(rr)) if z is None else z
    pts = np.column_stack([(R * np.cos(P)).ravel(), (R * np.sin(P)).ravel(), np.asarray(zf(R), float).ravel()])
    if centre:
        pts = np.vstack([[0.0, 0.0, float(np.asarray(zf(np.zeros(1)), float).ravel()[0])], pts])
    ring = lambda k, s: c + k * spokes + (s % spokes)  # noqa: E731
    edges = []
    for k in range(rings):
        edges += [(ring(k, s), ring(k, s + 1)) for s in range(spokes)]
    for k in range(rings - 1):
        edges += [(ring(k, s), ring(k + 1, s)) for s in range(spokes)]
    if centre:
        edges += [(0, ring(0, s)) for s in range(spokes)]
    edges = np.array(edges, int)
    if isinstance(anchored, str):
        if anchored == "outer":
            anch = np.array([ring(rings - 1, s) for s in range(spokes)])
        elif anchored == "centre":
            if not centre:
                raise ValueError("anchored='centre' needs centre=True")
            anch = np.array([0])
        else:
            raise ValueError(f"anchored must be 'outer', 'centre' or a list, got {anchored!r}")
    else:
        anch = np.unique(np.asarray(anchored, int))
    if isinstance(anchored, str) and anchored == "outer":
        both = np.isin(edges, anch).all(axis=1)
        edges = edges[~both]  # the outer ring between anchors: no rods
    return NetSpec(pts, edges, _lengths(pts, edges), np.sort(anch), (rings, spokes))


def jitter(spec: NetSpec, amount: float, *, seed: int) -> NetSpec:
    """The net with its free nodes moved at random (uniform in a cube of +-amount mm) and
    its lengths re-measured; anchors stay."""
    rng = np.random.default_rng(seed)
    pos = spec.positions.copy()
    free = np.ones(spec.n, dtype=bool)
    free[spec.anchored] = False
    pos[free] += rng.uniform(-amount, amount, (int(free.sum()), 3))
    return replace(spec, positions=pos, lengths=_lengths(pos, spec.edges))


def random_grid(seed: int, *, max_cells: int = 8, anchored: str = "corners", rod=(20.0, 60.0)) -> NetSpec:
    """A random grid net: u, v in 2..max_cells cells, rods of about ``rod`` mm, on a random
    sagging surface, jittered; anchored at the corners or the boundary."""
    rng = np.random.default_rng(seed)
    u, v = (int(k) for k in rng.integers(2, max_cells + 1, 2))
    cell = rng.uniform(rod[0] * 1.1, rod[1] * 0.85)
    w, h = u * cell, v * cell
    depth = rng.uniform(0.15, 0.45) * max(w, h)
    tilt = rng.uniform(-0.15, 0.15, 2)

    def z(x, y):
        return depth * (((x - w / 2) / (w / 2)) ** 2 + ((y - h / 2) / (h / 2)) ** 2 - 2) / 2 + tilt[0] * x + tilt[1] * y

    spec = grid_net(u, v, x=(0.0, w), y=(0.0, h), z=z, anchored=anchored)
    spec = jitter(spec, 0.08 * cell, seed=seed + 1)
    return spec


def random_masses(spec: NetSpec, seed: int, *, lo: float = 1.0, hi: float = 4.0) -> np.ndarray:
    """(m,) rod masses uniform in [lo, hi] (g), seeded."""
    return np.random.default_rng(seed).uniform(lo, hi, spec.m)
