"""Cavity layout of a printed rod: a pool of Poisson-disk (blue-noise) candidate centres,
dart throwing with a minimum wall, mirror-symmetric orbits, and the ball sockets' layout.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from functools import cached_property, lru_cache
from typing import TYPE_CHECKING, Any

import numpy as np

from rodcad.catalog.fastgeom import RodClearance
from rodcad.cad.solids import mass_properties
from rodcad.fabrication.layout import (
    MIN_CAVITY_RADIUS,
    UP,
    BoundedMemo,
    SphereLayout,
    ball_offset,
    max_ball_layout,
    silo_top_points,
    sphere_layouts,
    memo_key,
    symmetric_images,
    tall_silo,
    void_volume,
)

if TYPE_CHECKING:  # pragma: no cover
    from rodcad.catalog.model import RodType
from rodcad.cad.solids import type_solid
from rodcad.catalog.massrange import mass_info

__all__ = [
    "CAPPED_K",
    "EDGE_TOL",
    "FABRICATE_VERSION",
    "MASS_TOL",
    "POOL_SIZE",
    "RADIUS_FACTOR",
    "SOLID_TOL",
    "SOLVE_TOL",
    "SOCKET_CLEARANCE",
    "THROWS",
    "solid_clearance",
    "cavity_pool",
    "cavity_radii",
    "CavityPool",
    "dart_throw",
    "FabricationError",
    "lattice_layouts",
    "lattice_layouts_many",
    "orbits",
    "place_cavities",
    "raised_rows",
    "raised_sockets",
    "row_layout",
    "silo_distance",
    "silo_distances",
    "socket_layout",
    "socket_rows",
]


#: Relative mass error the issue allows (0.1 %); the root solve aims 100x tighter.
MASS_TOL = 1e-3


#: Relative tolerance of the B-rep root solve on the mass.
SOLVE_TOL = 1e-6


#: Candidate cavity sites per symmetry group (orbit representatives); each is
#: also projected onto every mirror plane / axis so symmetric sites exist.
POOL_SIZE = 160


#: Design radii tried for cavity layouts shrink by this factor.
RADIUS_FACTOR = 0.87


CAPPED_K = void_volume("capped", 1.0)


@dataclass(frozen=True)
class CavityPool:
    """Seeded candidate cavity sites of one rod type and symmetry group.

    Attributes:
        images: per candidate, its distinct images under the group ((g, 3) each).
        clearance: per candidate, the smallest solid clearance over its images.
        intra: per candidate, the smallest distance between its images (inf if one).
        order: the random order in which darts are thrown.
    """

    images: tuple[np.ndarray, ...]
    clearance: np.ndarray
    intra: np.ndarray
    order: np.ndarray

    @cached_property
    def flat(self) -> tuple[np.ndarray, np.ndarray]:
        """Every image of every candidate in one (M, 3) array, and where each candidate's start."""
        sizes = np.array([len(im) for im in self.images], dtype=int)
        return np.concatenate(self.images), np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(int)

    @cached_property
    def _rows(self) -> dict[int, np.ndarray]:
        return {}

    def apart(self, i: int) -> np.ndarray:
        """(n,): candidate ``i``'s distance from every candidate (their nearest images), kept
        for every radius the pool is thrown with (as :func:`_throw` measured it dart by dart:
        the square root of the least squared distance)."""
        row = self._rows.get(i)
        if row is None:
            flat, starts = self.flat
            d = self.images[i][:, None, :] - flat[None, :, :]
            d2 = np.minimum.reduceat(np.einsum("ijk,ijk->ij", d, d).min(axis=0), starts)
            row = self._rows[i] = np.sqrt(d2)
        return row


def _distinct_images(images: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """(n, g) mask of each candidate's images (n, g, 3) kept in order: an image is kept when it
    is further than ``tol`` from every image kept before it."""
    n, g, _ = images.shape
    keep = np.zeros((n, g), dtype=bool)
    for j in range(g):
        ok = np.ones(n, dtype=bool)
        for k in range(j):
            d = images[:, j] - images[:, k]
            ok &= ~keep[:, k] | (np.sqrt(np.einsum("ij,ij->i", d, d)) > tol)
        keep[:, j] = ok
    return keep


@lru_cache(maxsize=64)
def cavity_pool(rod: RodType, symmetry: str, seed: int) -> CavityPool:
    """The candidate pool: orbit representatives drawn uniformly in the
    fundamental domain of ``symmetry`` about the com, each also projected onto
    the group's mirror planes and axes (so orbits of 1, 2, 4 sites exist)."""

    solid = type_solid(rod)
    com = np.array(mass_properties(solid).center)
    clearance = RodClearance(rod.geometry)
    lo, hi = (np.array(b) for b in clearance.bounds)
    rng = np.random.default_rng([seed, 0 if symmetry == "mirror-xyz" else 1])
    dom_lo = lo.copy()
    dom_lo[2] = com[2]
    dom_lo[0] = com[0]
    if symmetry == "mirror-xyz":
        dom_lo[1] = com[1]
        subsets = [(), (0,), (1,), (2,), (0, 1), (0, 2), (1, 2), (0, 1, 2)]
    else:  # half turn about the com axis (z) + z mirror
        subsets = [(), (2,), (0, 1), (0, 1, 2)]
    reps = dom_lo + rng.random((POOL_SIZE, 3)) * (hi - dom_lo)
    cands = []
    for sub in subsets:
        p = reps.copy()
        for axis in sub:
            p[:, axis] = com[axis]
        cands.append(p)
    pts = np.concatenate(cands)
    every = np.stack([pts, *symmetric_images(pts, com, symmetry)], axis=1)  # (n, group, 3)
    images = tuple(every[k][keep] for k, keep in enumerate(_distinct_images(every)))
    flat = np.concatenate(images)
    clr = clearance(flat)
    sizes = np.array([len(im) for im in images])
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    cmin = np.minimum.reduceat(clr, starts)
    intra = np.array([np.min([np.linalg.norm(a - b) for i, a in enumerate(im) for b in im[i + 1:]])
                      if len(im) > 1 else math.inf for im in images])
    return CavityPool(images, cmin, intra, rng.permutation(len(images)))


assert np.array_equal(UP, [0.0, 1.0, 0.0])  # silo_distance takes the height along y


def silo_distance(points: np.ndarray, centers: np.ndarray, radius: float,
                  height: float | Sequence[float] | None = None) -> np.ndarray:
    """Distance (mm) from points to the nearest silo socket (0 inside one) whose roof is
    ``height`` above its centre (default: the radius; a sequence: one per socket)."""
    pts = np.atleast_2d(points)
    if len(centers) == 0:
        return np.full(len(pts), math.inf)
    return silo_distances(pts, centers, radius, height).min(axis=1)


def silo_distances(points: np.ndarray, centers: np.ndarray, radius: float | np.ndarray,
                   height: float | Sequence[float] | None = None) -> np.ndarray:
    """(n, k): each point's distance (mm) from each of k silo sockets (:func:`silo_distance`
    is its row minimum); ``radius`` a number or one per socket."""
    pts = np.atleast_2d(points)
    r = np.asarray(radius, dtype=float)
    top = r if height is None else np.asarray(height, dtype=float)
    c = np.asarray(centers, dtype=float).reshape(-1, 3)
    # UP is the y axis: the height along it and the radial distance from the socket's axis
    dx, h, dz = (pts[:, k, None] - c[None, :, k] for k in range(3))  # (n, k) each
    radial2 = dx * dx + dz * dz
    ball = np.maximum(np.sqrt(radial2 + h * h) - r, 0.0)
    cyl = np.hypot(np.maximum(np.sqrt(radial2) - r, 0.0), np.maximum(np.maximum(-h, h - top), 0.0))
    return np.minimum(ball, cyl)


@dataclass(frozen=True)
class _CavityLayout:
    centers: np.ndarray
    radius: float  # analytic radius removing the wanted volume
    bound: float  # largest radius the sites are checked for
    layout: str


def dart_throw(pool: CavityPool, radius: float, wall: float, sockets: np.ndarray, socket_r: float,
               socket_h: float | tuple[float, ...] | None = None) -> list[np.ndarray]:
    """Poisson-disk dart throwing of symmetric orbits: returns the accepted
    orbits (their distinct points) in acceptance order (memoised). The sockets' roofs are
    ``socket_h`` above their centres (default: their radius)."""
    key = (id(pool), radius, wall, np.asarray(sockets, dtype=float).tobytes(), socket_r, socket_h)
    return THROWS.get(key, lambda: _throw(pool, radius, wall, sockets, socket_r, socket_h))


#: Each pool candidate's distance from a set of ball sockets (:func:`_socket_clearance`).
SOCKET_CLEARANCE = BoundedMemo(1024)


def _socket_clearance(pool: CavityPool, sockets: np.ndarray, socket_r: float,
                      socket_h: float | tuple[float, ...] | None) -> np.ndarray:
    """Every candidate's (all its images') distance from the sockets: the same for every
    cavity radius the pool is thrown with (memoised)."""
    def compute() -> np.ndarray:
        flat, starts = pool.flat
        return np.minimum.reduceat(silo_distance(flat, sockets, socket_r, socket_h), starts)

    return SOCKET_CLEARANCE.get((id(pool), np.asarray(sockets, dtype=float).tobytes(), socket_r, socket_h), compute)


def _throw(pool: CavityPool, radius: float, wall: float, sockets: np.ndarray, socket_r: float,
           socket_h: float | tuple[float, ...] | None) -> list[np.ndarray]:
    need = radius + wall
    spacing = 2 * radius + wall
    ok = (pool.clearance >= need) & (pool.intra >= spacing - 1e-9)
    if len(sockets) and len(pool.images):  # clear of the ball sockets, all candidates at once
        ok &= _socket_clearance(pool, sockets, socket_r, socket_h) >= need
    accepted: list[np.ndarray] = []
    free = ok.copy()  # still allowed: feasible and at least ``spacing`` from every accepted one
    for i in pool.order:
        if not free[i]:
            continue
        accepted.append(pool.images[i])
        free &= pool.apart(i) >= spacing
    return accepted


def cavity_radii(rod: RodType) -> list[float]:
    g = rod.geometry
    r = min(g.max_height, g.max_thickness) / 2 - rod.material.min_wall  # a graduated body may be larger
    out = []
    while r >= MIN_CAVITY_RADIUS - 1e-12:
        out.append(r)
        r *= RADIUS_FACTOR
    return out


def place_cavities(rod: RodType, volume: float, sockets: np.ndarray, socket_r: float, seed: int,
                   socket_h: float | tuple[float, ...] | None = None) -> _CavityLayout | None:
    """Symmetric cavities removing ``volume`` (mm^3), as few and as large as
    possible: Poisson-disk layouts first, the symmetric lattice as fallback; clear of the
    sockets (roofs ``socket_h`` above their centres, one for all or one per socket; default
    their radius).

    For each design radius r_d, the layout's sites fit cavities up to r_d; a
    prefix of its orbits (in dart order) with n sites removes ``volume`` with
    radius r = (volume / (n k))^(1/3) <= r_d. The largest such r wins.
    """

    wall = rod.material.min_wall
    best: _CavityLayout | None = None
    for symmetry in ("mirror-xyz", "point-xy"):
        pool = cavity_pool(rod, symmetry, seed)
        for rd in cavity_radii(rod):
            if best is not None and rd <= best.radius:
                break
            orbits = dart_throw(pool, rd, wall, sockets, socket_r, socket_h)
            n = 0
            for j, orb in enumerate(orbits):
                n += len(orb)
                r = (volume / (n * CAPPED_K)) ** (1 / 3)
                if r <= rd + 1e-12:
                    if r >= MIN_CAVITY_RADIUS and (best is None or r > best.radius + 1e-12):
                        best = _CavityLayout(np.concatenate(orbits[: j + 1]), r, rd, f"poisson/{symmetry}")
                    break
    if best is not None:
        return best
    # Fallback: the deterministic lattice (it reaches the catalog's m_min).
    for rd, lay in lattice_layouts(rod, sockets, socket_r, socket_h=socket_h):
        if lay.count == 0:
            continue
        r = (volume / (lay.count * CAPPED_K)) ** (1 / 3)
        if r <= rd * (1 + 1e-9) and r >= MIN_CAVITY_RADIUS and (best is None or r > best.radius):
            best = _CavityLayout(lay.centers, min(r, rd), rd, f"lattice/{lay.symmetry}")
    return best


def lattice_layouts(rod: RodType, sockets: np.ndarray, socket_r: float, *,
                    socket_h: float | tuple[float, ...] | None = None) -> Iterator[tuple[float, SphereLayout]]:
    """The symmetric lattice cavity layouts beside these ball sockets (roofs ``socket_h``
    above their centres; default their radius), largest radius first (the fallback of
    :func:`place_cavities`: it reaches the catalog's m_min): :func:`lattice_layouts_many` of
    the one option, so that the tables of reachable masses lay exactly these."""
    for rd, (lay,) in lattice_layouts_many(rod, [(sockets, socket_r, socket_h)]):
        yield rd, lay


def lattice_layouts_many(rod: RodType, options: Sequence[tuple],
                         skip: Callable[[int, float], bool] = lambda j, radius: False
                         ) -> Iterator[tuple[float, list[SphereLayout | None]]]:
    """The symmetric lattice cavity layouts of several ball options of a rod at once: per
    cavity radius, largest first, one layout per option (None where ``skip(j, radius)``), the
    most cavities :func:`sphere_layout` fits where the solid leaves a wall and the option's
    sockets are a wall away (:func:`sphere_layouts`: the lattices, the solid's clearance and
    each socket's distance taken once for all the options).

    Args:
        rod: the rod type.
        options: (socket centres, socket radius) or (centres, radius, roofs) each; the roofs
            ``height`` above the centres, one for all or one per socket (default the radius).
        skip: asked once every option's layouts of the larger radii are known.
    """
    solid = type_solid(rod)
    com = mass_properties(solid).center
    clr = solid_clearance(rod)
    wall = rod.material.min_wall
    # every distinct socket once (options share them); per option, the indices of its own
    keys: dict[tuple[float, ...], int] = {}
    subsets: list[np.ndarray] = []
    for socks, rs, *roof in options:
        socks = np.asarray(socks, dtype=float).reshape(-1, 3)
        h = roof[0] if roof and roof[0] is not None else rs
        heights = np.broadcast_to(np.asarray(h, dtype=float), (len(socks),))
        subsets.append(np.array([keys.setdefault((*map(float, p), float(rs), float(hp)), len(keys))
                                 for p, hp in zip(socks, heights)], dtype=np.int64))
    table = np.array(list(keys), dtype=float).reshape(-1, 5)

    def regions(p: np.ndarray) -> np.ndarray:
        return silo_distances(p, table[:, :3], table[:, 3], table[:, 4])

    info = mass_info(rod)
    radii = sorted(set(cavity_radii(rod)) | ({info.cavity_radius} if info.cavity_radius > 0 else set()), reverse=True)
    for rd in radii:
        wanted = [j for j in range(len(options)) if not skip(j, rd)]
        found = sphere_layouts(clr, clr.bounds, com, rd, wall, regions, [subsets[j] for j in wanted], void="capped")
        out: list[SphereLayout | None] = [None] * len(options)
        for j, lay in zip(wanted, found):
            out[j] = lay
        yield rd, out


class _MemoClearance:
    """A :class:`RodClearance` that remembers its answers by point set: the lattices of
    :func:`lattice_layouts` are the same for every ball option of a rod (only the sockets'
    part of the clearance changes)."""

    def __init__(self, clearance: RodClearance) -> None:
        self._f = clearance
        self.bounds = clearance.bounds
        self._memo = BoundedMemo(1024)

    def __call__(self, points: np.ndarray) -> np.ndarray:
        return self._memo.get(memo_key(points), lambda: np.asarray(self._f(points)))


@lru_cache(maxsize=16)
def solid_clearance(rod: RodType) -> _MemoClearance:
    """The rod type's solid clearance (:class:`RodClearance`), memoised by point set."""
    return _MemoClearance(RodClearance(rod.geometry))


@lru_cache(maxsize=64)
def socket_layout(rod: RodType) -> Any:
    """The type's largest symmetric socket layout (the one behind m_max; the
    ball half of :func:`rodcad.catalog.massrange.layouts`)."""

    if rod.balls is None:
        return SphereLayout.empty()
    solid = type_solid(rod)
    clearance = RodClearance(rod.geometry)
    lift = ball_offset(rod.balls.socket_diameter / 2, rod.balls.mass, rod.material.density)
    return max_ball_layout(clearance, clearance.bounds, mass_properties(solid).center, rod.balls.socket_diameter,
                           rod.material.min_wall, void="silo", raise_by=lift)


@lru_cache(maxsize=64)
def row_layout(rod: RodType) -> Any:
    """The type's largest symmetric socket layout in one row, at the height of the centre of
    mass (a graduated rod's :func:`socket_layout` may stand in two rows, one pause each;
    this is its alternative for the same ball counts: one pause, which
    :mod:`rodcad.fabrication.roofs` may line up with the chain's others)."""
    if rod.balls is None:
        return SphereLayout.empty()
    solid = type_solid(rod)
    clearance = RodClearance(rod.geometry)
    rs, wall = rod.balls.socket_diameter / 2, rod.material.min_wall
    lift = ball_offset(rs, rod.balls.mass, rod.material.density)
    com = mass_properties(solid).center
    (x0, _, z0), (x1, _, z1) = clearance.bounds
    need = rs + wall + 1e-6  # the lattice keeps rs + wall inside its bounds: the row at the com is left
    row = ((x0, com[1] - need, z0), (x1, com[1] + need, z1))
    return max_ball_layout(clearance, row, com, rod.balls.socket_diameter, wall, void="silo", raise_by=lift)


def socket_rows(sockets: np.ndarray) -> list[np.ndarray]:
    """The sockets' rows (index arrays, lowest first): sockets whose centres stand at one
    height along :data:`UP` share a roof and a pause."""
    ys = np.asarray(sockets, dtype=float).reshape(-1, 3) @ UP
    rows: list[list[int]] = []
    for i in np.argsort(ys, kind="stable"):
        if rows and abs(ys[i] - ys[rows[-1][0]]) <= 1e-6:
            rows[-1].append(int(i))
        else:
            rows.append([int(i)])
    return [np.array(sorted(r)) for r in rows]


def raised_rows(rod: RodType, sockets: np.ndarray, socket_r: float, kind: int,
                roofs: Sequence[float]) -> tuple[np.ndarray, np.ndarray] | None:
    """The sockets (laid out by :func:`socket_layout`) with each row's flat roof raised to
    ``roofs[j]`` (mm along :data:`UP`, rod frame; rows lowest first, :func:`socket_rows`; a
    roof at or below the row's plain roof keeps it): each raised socket's cylinder reaches
    up to its roof and its centre rises with it so that socket and ball still act at their
    site, corrected for the plastic the cavities give back at the centre of mass
    (:func:`rodcad.fabrication.layout.tall_silo`): the rod's centre of mass stays put, row
    by row.

    Returns:
        (centres (K, 3), per socket the roof's height above its centre (K,)) in mm, or
        None where ``roofs`` does not name every row or a raised socket would leave less
        than the minimum wall to the rod's faces or to another socket.
    """
    socks = np.asarray(sockets, dtype=float).reshape(-1, 3)
    rows = socket_rows(socks)
    if not len(socks) or len(roofs) != len(rows):
        return None
    balls = rod.ball_kinds[kind]
    rho = rod.material.density
    give_at = float(mass_info(rod).com[1])  # the cavities' centroid
    out, heights = socks.copy(), np.full(len(socks), float(socket_r))
    raised: list[np.ndarray] = []
    for idx, roof in zip(rows, roofs):
        y = float(socks[idx[0]] @ UP)
        if roof <= y + socket_r + 1e-9:
            continue
        site = y - ball_offset(socket_r, balls.mass, rho)
        centre, height = tall_silo(site, socket_r, balls.mass, rho, float(roof), give_at=give_at)
        out[idx] = socks[idx] + UP * (centre - y)
        heights[idx] = height
        raised.append(idx)
    need = rod.material.min_wall + WALL_MARGIN
    clr = solid_clearance(rod)
    for idx in raised:
        top = silo_top_points(out[idx], socket_r, float(heights[idx[0]]))
        bottom = (out[idx][:, None, :] + _LOWER_HALF[None] * socket_r).reshape(-1, 3)  # a socket below the
        if min(clr(top).min(), clr(bottom).min()) < need:  # com sinks a little as its roof rises
            return None
        others = np.setdiff1d(np.arange(len(out)), idx)
        if len(others) and silo_distance(top, out[others], socket_r, heights[others]).min() < need:
            return None
    return out, heights


def _lower_half(n: int = 12) -> np.ndarray:
    """Unit vectors over the lower half sphere (about -:data:`UP`): its pole and n rings of 4 n,
    down to the equator."""
    th = np.linspace(0, 2 * math.pi, 4 * n, endpoint=False)
    rings = [np.stack([np.sin(a) * np.cos(th), -np.full_like(th, math.cos(a)), np.sin(a) * np.sin(th)], axis=1)
             for a in np.linspace(math.pi / 2, 0, n, endpoint=False)]
    return np.concatenate([-UP[None], *rings])


_LOWER_HALF = _lower_half()


def raised_sockets(rod: RodType, sockets: np.ndarray, socket_r: float, kind: int,
                   roof: float) -> tuple[np.ndarray, float] | None:
    """The sockets of one row with their flat roofs raised to ``roof`` (:func:`raised_rows`
    for a single row): (centres (K, 3), the roofs' height above the centres) in mm, or None
    where the sockets are not one row, the roof is below theirs, or the raised sockets would
    leave less than the minimum wall to the rod's faces.
    """
    socks = np.asarray(sockets, dtype=float).reshape(-1, 3)
    if len(socket_rows(socks)) != 1 or roof < float(socks[0] @ UP) + socket_r - 1e-9:
        return None
    got = raised_rows(rod, socks, socket_r, kind, [roof])
    return None if got is None else (got[0], float(got[1][0]))


#: Wall kept (mm) beyond the material's minimum where a socket's roof is raised: the sampled
#: check of :func:`raised_sockets` stands in for the B-rep's measurement.
WALL_MARGIN = 0.05


def orbits(points: np.ndarray, center: Sequence[float], symmetry: str) -> list[np.ndarray]:
    """Split a symmetric point set into orbits (index arrays), sorted by size then position."""
    left = list(range(len(points)))
    out = []
    while left:
        i = left[0]
        imgs = [points[i]] + list(symmetric_images(points[i][None], center, symmetry))
        orb = sorted({j for j in left for q in imgs if np.linalg.norm(points[j] - np.ravel(q)) < 1e-6})
        out.append(np.array(orb))
        left = [j for j in left if j not in orb]
    return out


#: Bump when results change (invalidates cached fabrication plans).
FABRICATE_VERSION = "3"


#: Targets this close (relative) to the plain solid's mass are built solid.
SOLID_TOL = 1e-4


#: Relative slack on the edges of the reachable intervals (round-off).
EDGE_TOL = 1e-7


class FabricationError(RuntimeError):
    """A fabricated solid or an exported file failed a check."""


#: Dart throws by pool, radius, wall and sockets (:func:`dart_throw`).
THROWS = BoundedMemo(4096)
