"""Lattices of sites about a centre and their symmetric subsets: the points of a cubic or
hexagonal lattice inside a box, each point's image under a symmetry group's flips (from the
lattice's indices, or by a search for any point set), the sites whose every image is a site
too; and the bounded memos that keep them (the same lattice is asked about for every ball
option of a rod)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

__all__ = ["LATTICES", "SYMMETRIES", "BoundedMemo", "lattice_image_map", "lattice_sites", "memo_key",
           "symmetric_images", "symmetric_subset"]


#: Symmetry groups a layout may have, each keeping its centroid on the com:
#: 'mirror-xyz' (mirrors across x, y and z through the com) and 'point-xy'
#: (half turn about the com axis parallel to z, plus the z mirror).
SYMMETRIES = ("mirror-xyz", "point-xy")


#: Lattices tried: 'cubic', and 'hex' (hexagonal rows in the chain plane,
#: stacked along z), which fits two staggered rows where a square grid fits one.
LATTICES = ("cubic", "hex")


def lattice_sites(bounds: tuple[Sequence[float], Sequence[float]], center: Sequence[float], pitch: float,
                  offset: Sequence[float], kind: str = "cubic") -> np.ndarray:
    """Points of a lattice of nearest-neighbour distance ``pitch`` inside ``bounds``.

    The lattice is ``center + (i + ox) a1 + (j + oy) a2 + (k + oz) a3`` with
    a1 = (p, 0, 0), a3 = (0, 0, p) and a2 = (0, p, 0) ('cubic') or
    (p/2, p sqrt(3)/2, 0) ('hex'). With offsets 0 or 0.5 it is symmetric under
    the half turn about ``center`` (and, for some offsets, under mirrors).

    Args:
        bounds: ((xmin, ymin, zmin), (xmax, ymax, zmax)) in mm.
        center: the lattice's centre of symmetry (mm).
        pitch: nearest-neighbour distance (mm).
        offset: (ox, oy, oz) in lattice units.
        kind: 'cubic' or 'hex'.

    Returns:
        (n, 3) array of points.
    """
    if kind not in LATTICES:
        raise ValueError(f"unknown lattice {kind!r} (expected one of {', '.join(LATTICES)})")
    key = (tuple(map(float, bounds[0])), tuple(map(float, bounds[1])), tuple(map(float, center)), float(pitch),
           tuple(map(float, offset)), kind)
    return _SITES.get(key, lambda: _lattice_sites(bounds, center, pitch, offset, kind))


class BoundedMemo:
    """Values computed once by key, the whole memo emptied when it holds ``size`` entries (it
    only ever saves time). Arrays it keeps are made read-only: every caller shares them."""

    def __init__(self, size: int) -> None:
        self.size = size
        self._values: dict = {}

    def get(self, key, compute):
        """The value for ``key``, from ``compute()`` the first time."""
        hit = self._values.get(key)
        if hit is None:
            hit = compute()
            if isinstance(hit, np.ndarray):
                hit.setflags(write=False)
            if len(self._values) >= self.size:
                self._values.clear()
            self._values[key] = hit
        return hit

    def __len__(self) -> int:
        return len(self._values)


#: :func:`lattice_sites` by its arguments (every ball option of a rod asks for the same).
_SITES = BoundedMemo(4096)


def _lattice_sites(bounds, center, pitch: float, offset, kind: str) -> np.ndarray:
    lo = np.asarray(bounds[0], dtype=float)
    hi = np.asarray(bounds[1], dtype=float)
    c = np.asarray(center, dtype=float)
    if np.any(hi < lo):
        return np.zeros((0, 3))
    a2y = pitch * (math.sqrt(3) / 2 if kind == "hex" else 1.0)
    a2x = pitch / 2 if kind == "hex" else 0.0

    def span(lo_: float, hi_: float, step: float, off: float) -> np.ndarray:
        return np.arange(math.floor(lo_ / step - off) - 1, math.ceil(hi_ / step - off) + 2) + off

    js = span(lo[1] - c[1], hi[1] - c[1], a2y, offset[1])
    ks = span(lo[2] - c[2], hi[2] - c[2], pitch, offset[2])
    shift = abs(a2x) * (np.abs(js).max() if len(js) else 0)
    is_ = span(lo[0] - c[0] - shift, hi[0] - c[0] + shift, pitch, offset[0])
    ii, jj, kk = np.meshgrid(is_, js, ks, indexing="ij")
    pts = np.stack([c[0] + ii * pitch + jj * a2x, c[1] + jj * a2y, c[2] + kk * pitch], axis=-1).reshape(-1, 3)
    inside = np.all((pts >= lo - 1e-9) & (pts <= hi + 1e-9), axis=1)
    return pts[inside]


#: The sign flips about the centre that make each symmetry group (the identity left out).
_FLIPS = {
    "mirror-xyz": ((-1, 1, 1), (1, -1, 1), (-1, -1, 1), (1, 1, -1), (-1, 1, -1), (1, -1, -1), (-1, -1, -1)),
    "point-xy": ((-1, -1, 1), (1, 1, -1), (-1, -1, -1)),
}


def _flips(symmetry: str) -> tuple[tuple[int, int, int], ...]:
    if symmetry not in _FLIPS:
        raise ValueError(f"unknown symmetry {symmetry!r} (expected one of {', '.join(SYMMETRIES)})")
    return _FLIPS[symmetry]


def symmetric_images(points: np.ndarray, center: Sequence[float], symmetry: str) -> list[np.ndarray]:
    c = np.asarray(center, dtype=float)
    return [(points - c) * np.asarray(f) + c for f in _flips(symmetry)]


def memo_key(points: np.ndarray, *rest) -> tuple:
    """A memo key for a point array (its shape and a digest of its bytes) and some scalars."""
    import hashlib

    pts = np.ascontiguousarray(points, dtype=float)
    return (pts.shape, hashlib.blake2b(pts.tobytes(), digest_size=16).digest(), *rest)


#: Image maps of :func:`symmetric_subset` by point set (the same lattice is asked about for
#: every ball option of a rod: only which points are feasible changes).
_IMAGE_MAPS = BoundedMemo(2048)


def _image_map(points: np.ndarray, center: Sequence[float], symmetry: str, tol: float) -> np.ndarray:
    """(flips, n) index of each point's image under each flip of ``symmetry`` among
    ``points`` (within ``tol``), or -1 where it has none; memoised by point set."""
    c = np.asarray(center, dtype=float)

    def compute() -> np.ndarray:
        from scipy.spatial import cKDTree

        flips = np.asarray(_flips(symmetry), dtype=float)
        images = ((points - c)[None, :, :] * flips[:, None, :] + c).reshape(-1, 3)  # all flips, one query
        dist, near = cKDTree(points).query(images, distance_upper_bound=tol)
        return np.where(np.isfinite(dist), near, -1).reshape(len(flips), len(points))

    return _IMAGE_MAPS.get(memo_key(points, tuple(c.tolist()), symmetry, tol), compute)


def lattice_image_map(bounds: tuple[Sequence[float], Sequence[float]], center: Sequence[float], pitch: float,
                      offset: Sequence[float], kind: str, symmetry: str) -> np.ndarray:
    """The image map (:func:`symmetric_subset`'s ``near``: (flips, n), the index of each
    point's image under each flip of ``symmetry``, -1 where it has none) of the points
    ``lattice_sites(bounds, center, pitch, offset, kind)``, from their lattice indices instead
    of a search: under a flip about the lattice's centre a lattice point goes to the lattice
    point whose doubled indices are the flipped ones, if the bounds keep it. Offsets must be
    0 or half a step. Memoised by the arguments."""
    key = (tuple(map(float, bounds[0])), tuple(map(float, bounds[1])), tuple(map(float, center)), float(pitch),
           tuple(map(float, offset)), kind, symmetry)

    def compute() -> np.ndarray:
        if any(2 * o != round(2 * o) for o in offset):
            raise ValueError(f"lattice offsets must be 0 or half a step, not {tuple(offset)}")
        flips = np.asarray(_flips(symmetry), dtype=np.int64)
        indexed = _LATTICE_GRIDS.get(key[:-1], lambda: _lattice_grid(bounds, center, pitch, offset, kind))
        if indexed is None:
            return np.zeros((len(flips), 0), dtype=np.int64)
        ii, jj, kk, lo, shape, grid = indexed
        out = np.full((len(flips), len(ii)), -1, dtype=np.int64)
        for n, (fx, fy, fz) in enumerate(flips):
            if kind == "hex":  # x - cx = ii p / 2 + jj p / 4, flipped: ii' = fx ii + jj (fx - fy) / 2
                twice = 2 * fx * ii + jj * (fx - fy)
                ok = twice % 2 == 0
                fi = twice // 2
            else:
                ok = np.ones(len(ii), dtype=bool)
                fi = fx * ii
            img = np.stack([fi, fy * jj, fz * kk], axis=1) - lo
            ok &= np.all((img >= 0) & (img < shape), axis=1)
            out[n, ok] = grid[tuple(img[ok].T)]
        return out

    return _LATTICE_MAPS.get(key, compute)


#: :func:`lattice_image_map` by its arguments.
_LATTICE_MAPS = BoundedMemo(4096)


def _lattice_grid(bounds, center, pitch: float, offset, kind: str):
    """The doubled lattice indices (ii, jj, kk) of ``lattice_sites(...)``'s points, their least
    index, the index box's shape and the grid of point numbers over it (-1 where none); None
    for no points. Shared by the symmetries' image maps."""
    points = lattice_sites(bounds, center, pitch, offset, kind)
    if not len(points):
        return None
    rel = points - np.asarray(center, dtype=float)
    a2x, a2y = (pitch / 2, pitch * math.sqrt(3) / 2) if kind == "hex" else (0.0, pitch)
    jj = np.rint(2 * rel[:, 1] / a2y).astype(np.int64)  # doubled indices: 2 (j + oy), ...
    kk = np.rint(2 * rel[:, 2] / pitch).astype(np.int64)
    ii = np.rint(2 * (rel[:, 0] - jj / 2 * a2x) / pitch).astype(np.int64)
    idx = np.stack([ii, jj, kk], axis=1)
    lo = idx.min(axis=0)
    shape = idx.max(axis=0) - lo + 1
    grid = np.full(tuple(shape), -1, dtype=np.int64)
    grid[tuple((idx - lo).T)] = np.arange(len(idx))
    return ii, jj, kk, lo, shape, grid


#: :func:`_lattice_grid` by its arguments (both symmetries' maps use one).
_LATTICE_GRIDS = BoundedMemo(1024)


def symmetric_subset(points: np.ndarray, feasible: np.ndarray, center: Sequence[float], symmetry: str,
                     tol: float = 1e-6, *, near: np.ndarray | None = None) -> np.ndarray:
    """Mask of the feasible points whose every image under ``symmetry`` is a
    feasible point too; the kept set is invariant, so its centroid is ``center``.

    Args:
        points: (n, 3) candidate points.
        feasible: (n,) bool, which points may hold a sphere.
        center: the centre of symmetry (mm).
        symmetry: one of :data:`SYMMETRIES`.
        tol: distance within which an image matches a point (mm).
        near: the points' image map (:func:`lattice_image_map`), if known.
    """
    feasible = np.asarray(feasible, dtype=bool)
    if len(points) == 0:
        return np.zeros(0, dtype=bool)
    keep = feasible.copy()
    if not keep.any():
        return keep
    if near is None:
        near = _image_map(np.asarray(points, dtype=float), center, symmetry, tol)
    keep &= ((near >= 0) & feasible[np.maximum(near, 0)]).all(axis=0)
    return keep
