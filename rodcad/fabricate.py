"""Fabrication: cavities and ball sockets so every printed rod has its designed mass.

The data flow for one rod (type + target mass), one step per function:

    type     -> achievable_intervals(): once per type (disk-cached), every
                               symmetric ball subset of the type's socket layout
                               and the cavity volumes its layouts can remove:
                               the reachable masses, narrow bands above the solid
    target   -> _plan():       clip to the type's mass range [m_min, m_max]
                               (:mod:`rodcad.massrange`); look up the ball
                               sockets and the cavity volume left to remove in
                               that table (a target in a gap: the nearest
                               reachable mass, reported)
             -> _cavities():   cavity centres by Poisson-disk (blue-noise) dart
                               throwing on a seeded candidate pool, every dart
                               thrown with all its mirror images about the
                               centre of mass; the symmetric lattice of
                               :mod:`rodcad.massrange` is the fallback when the
                               blue-noise layouts cannot remove enough
             -> _build():      the cavity radius tuned by a Newton/secant root
                               solve on the exact B-rep volume (the analytic
                               volume is the start; 1-2 booleans), walls measured
                               on the B-rep (BRepExtrema), mass and centre of mass
                               from the B-rep plus the balls
    chain    -> fabricate_chain(): identical (type, mass) built once, distinct
                               rods in worker processes (one task per type),
                               disk-cached
             -> write_rod_files(), write_assembly(): STEP/STL, checked on re-read

Void shapes (all printable without support in the print orientation, see
:data:`rodcad.massrange.VOIDS`): cavities are spheres cut flat at 45 degrees
('capped'), sockets are 'silos' (half sphere + cylinder, flat bridged roof)
all standing on one print layer, so one pause serves all balls. Every layout
is symmetric about the rod's centre of mass (mirrors across x, y and z, or
the half turn about the com axis with the z mirror; sockets are raised by
:func:`rodcad.massrange.ball_offset` so socket and ball together act at their
site), so the centre of mass stays where the design assumes.

Print orientation: every rod lies on its side, the rod frame's -y face on the
bed and +y up (:data:`rodcad.geometry.PRINT_ROTATION`): hinge layers and pin
holes then build without support. Curved rods have no flat side but their
chain-plane faces, which would leave the tongue knuckle in mid-air; they print
on their side too, resting on the lowest point of their arc (a slicer adds a
little support under the rising ends; see :attr:`FabricatedRod.print_note`).

Units: mm, mm^3, g; densities g/cm^3.
"""

from __future__ import annotations

import math
import shutil
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rodcad.cache import DiskCache, make_key
from rodcad.massrange import (
    MASSRANGE_VERSION,
    MIN_CAVITY_RADIUS,
    UP,
    _images,
    sphere_layout,
    void_volume,
)
from rodcad.parallel import default_jobs, worker_pool

if TYPE_CHECKING:  # pragma: no cover
    from rodcad.catalog import RodType

__all__ = [
    "FABRICATE_VERSION",
    "MASS_TOL",
    "achievable_intervals",
    "chain_intervals",
    "ChainFabrication",
    "FabricatedRod",
    "FabricationError",
    "fabricate_chain",
    "fabricate_rod",
    "mass_colors",
    "write_assembly",
    "write_rod_files",
]

#: Bump when results change (invalidates cached fabrication plans).
FABRICATE_VERSION = "3"

#: Bump when the tables of reachable masses change (:func:`achievable_intervals`).
INTERVALS_VERSION = "1"

#: Relative mass error the issue allows (0.1 %); the root solve aims 100x tighter.
MASS_TOL = 1e-3

#: Relative tolerance of the B-rep root solve on the mass.
SOLVE_TOL = 1e-6

#: Targets this close (relative) to the plain solid's mass are built solid.
SOLID_TOL = 1e-4

#: Candidate cavity sites per symmetry group (orbit representatives); each is
#: also projected onto every mirror plane / axis so symmetric sites exist.
POOL_SIZE = 160

#: Design radii tried for cavity layouts shrink by this factor.
RADIUS_FACTOR = 0.87

#: Gaps between reachable masses narrower than this (relative) are bridged:
#: a target there is built at the nearest reachable mass (within half of it).
GAP_MERGE = 5e-4

#: Relative slack on the edges of the reachable intervals (round-off).
EDGE_TOL = 1e-7

_CAPPED_K = void_volume("capped", 1.0)


class FabricationError(RuntimeError):
    """A fabricated solid or an exported file failed a check."""


# --------------------------------------------------------------------------- results


@dataclass
class FabricatedRod:
    """One printed rod as built.

    Attributes:
        index: chain position (0-based, as in design.json).
        type_name: rod type.
        target_mass: mass asked for (g), before clipping to the range.
        mass: as-built mass (g): plastic volume x density + balls.
        com: as-built centre of mass (along, perp) in the rod frame (mm).
        plastic_volume: printed volume (mm^3) from the final B-rep.
        filament_mass: plastic mass (g).
        cavity_count: number of cavities.
        cavity_radius: their radius (mm), 0 without cavities.
        ball_count: number of metal balls.
        ball_diameter: ball diameter (mm) or None without balls.
        pause_z: print height (mm above the bed) of the (lowest) socket
            roofs: pause when the print reaches it, drop the balls in, resume;
            None without balls.
        pause_zs: every distinct roof height (mm), lowest first: sockets in
            several rows need one pause per row.
        mass_error: (mass - clipped target) / clipped target.
        in_range: whether the target was achievable.
        message: '' or why not, and what would be needed.
        solid: final solid in the rod frame (build123d ``Solid``).
        cavity_centers: (n, 3) cavity centres (mm, rod frame).
        socket_centers: (k, 3) socket centres (mm, rod frame) = ball centres.
        socket_radius: socket radius (mm), 0 without balls.
        min_wall: thinnest wall measured on the B-rep around the voids (mm;
            inf without voids).
        layout: how the cavities were placed: 'poisson/<symmetry>',
            'lattice/<symmetry>' or ''.
        print_matrix: 4x4 placing the rod-frame solid on the bed (mm).
        file_stem: 'NN_TYPE' (NN the 0-based index, two digits or more).
        print_note: remark on the print orientation ('' for flat-lying rods).
        thickness: rod thickness along the hinge axes (mm), the pin length.
        pin_diameter: hinge pin diameter (mm).
    """

    index: int
    type_name: str
    target_mass: float
    mass: float
    com: tuple[float, float]
    plastic_volume: float
    filament_mass: float
    cavity_count: int
    cavity_radius: float
    ball_count: int
    ball_diameter: float | None
    pause_z: float | None
    mass_error: float
    in_range: bool
    message: str
    solid: Any = field(repr=False)
    cavity_centers: np.ndarray = field(repr=False)
    socket_centers: np.ndarray = field(repr=False)
    socket_radius: float = 0.0
    min_wall: float = math.inf
    layout: str = ""
    print_matrix: np.ndarray = field(default_factory=lambda: np.eye(4), repr=False)
    file_stem: str = ""
    print_note: str = ""
    thickness: float = 0.0
    pin_diameter: float = 0.0
    pause_zs: tuple[float, ...] = ()


@dataclass
class ChainFabrication:
    """Every rod of a chain as built.

    Attributes:
        rods: one per chain position (identical rods share their solid).
        problems: one sentence per out-of-range rod.
        distinct: how many distinct rods were built.
        time_s: wall time (s).
    """

    rods: list[FabricatedRod]
    problems: list[str]
    distinct: int = 0
    time_s: float = 0.0


# --------------------------------------------------------------------------- cavity layouts


@dataclass(frozen=True)
class _Pool:
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


def _distinct(points: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    out: list[np.ndarray] = []
    for p in points:
        if all(np.linalg.norm(p - q) > tol for q in out):
            out.append(p)
    return np.array(out)


@lru_cache(maxsize=64)
def _pool(rod: RodType, symmetry: str, seed: int) -> _Pool:
    """The candidate pool: orbit representatives drawn uniformly in the
    fundamental domain of ``symmetry`` about the com, each also projected onto
    the group's mirror planes and axes (so orbits of 1, 2, 4 sites exist)."""
    from rodcad.geometry import Clearance, mass_properties

    solid = rod.solid()
    com = np.array(mass_properties(solid).center)
    clearance = Clearance(solid)
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
    images = tuple(_distinct(np.concatenate([p[None], *_images(p[None], com, symmetry)])) for p in pts)
    flat = np.concatenate(images)
    clr = clearance(flat)
    sizes = np.array([len(im) for im in images])
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    cmin = np.minimum.reduceat(clr, starts)
    intra = np.array([np.min([np.linalg.norm(a - b) for i, a in enumerate(im) for b in im[i + 1:]])
                      if len(im) > 1 else math.inf for im in images])
    return _Pool(images, cmin, intra, rng.permutation(len(images)))


def _silo_distance(points: np.ndarray, centers: np.ndarray, radius: float) -> np.ndarray:
    """Distance (mm) from points to the nearest silo socket (0 inside one)."""
    pts = np.atleast_2d(points)
    if len(centers) == 0:
        return np.full(len(pts), math.inf)
    d = pts[:, None, :] - np.asarray(centers)[None, :, :]  # (n, k, 3)
    h = d @ UP
    radial = np.linalg.norm(d - h[..., None] * UP, axis=-1)
    ball = np.maximum(np.linalg.norm(d, axis=-1) - radius, 0.0)
    cyl = np.hypot(np.maximum(radial - radius, 0.0), np.maximum(np.maximum(-h, h - radius), 0.0))
    return np.minimum(ball, cyl).min(axis=1)


@dataclass(frozen=True)
class _CavityLayout:
    centers: np.ndarray
    radius: float  # analytic radius removing the wanted volume
    bound: float  # largest radius the sites are checked for
    layout: str


_THROWS: dict[tuple[int, float, float, bytes, float], list[np.ndarray]] = {}


def _dart_throw(pool: _Pool, radius: float, wall: float, sockets: np.ndarray, socket_r: float) -> list[np.ndarray]:
    """Poisson-disk dart throwing of symmetric orbits: returns the accepted
    orbits (their distinct points) in acceptance order (memoised)."""
    key = (id(pool), radius, wall, np.asarray(sockets, dtype=float).tobytes(), socket_r)
    if key not in _THROWS:
        if len(_THROWS) > 4096:
            _THROWS.clear()
        _THROWS[key] = _throw(pool, radius, wall, sockets, socket_r)
    return _THROWS[key]


def _throw(pool: _Pool, radius: float, wall: float, sockets: np.ndarray, socket_r: float) -> list[np.ndarray]:
    need = radius + wall
    spacing = 2 * radius + wall
    ok = (pool.clearance >= need) & (pool.intra >= spacing - 1e-9)
    accepted: list[np.ndarray] = []
    placed = np.zeros((0, 3))
    for i in pool.order:
        if not ok[i]:
            continue
        im = pool.images[i]
        if len(sockets) and _silo_distance(im, sockets, socket_r).min() < need:
            continue
        if len(placed) and np.min(np.linalg.norm(im[:, None, :] - placed[None], axis=-1)) < spacing:
            continue
        accepted.append(im)
        placed = np.concatenate([placed, im])
    return accepted


def _radii(rod: RodType) -> list[float]:
    g = rod.geometry
    r = min(g.height, g.thickness) / 2 - rod.material.min_wall
    out = []
    while r >= MIN_CAVITY_RADIUS - 1e-12:
        out.append(r)
        r *= RADIUS_FACTOR
    return out


def _cavities(rod: RodType, volume: float, sockets: np.ndarray, socket_r: float, seed: int) -> _CavityLayout | None:
    """Symmetric cavities removing ``volume`` (mm^3), as few and as large as
    possible: Poisson-disk layouts first, the symmetric lattice as fallback.

    For each design radius r_d, the layout's sites fit cavities up to r_d; a
    prefix of its orbits (in dart order) with n sites removes ``volume`` with
    radius r = (volume / (n k))^(1/3) <= r_d. The largest such r wins.
    """
    from rodcad.geometry import Clearance, mass_properties

    wall = rod.material.min_wall
    best: _CavityLayout | None = None
    for symmetry in ("mirror-xyz", "point-xy"):
        pool = _pool(rod, symmetry, seed)
        for rd in _radii(rod):
            if best is not None and rd <= best.radius:
                break
            orbits = _dart_throw(pool, rd, wall, sockets, socket_r)
            n = 0
            for j, orb in enumerate(orbits):
                n += len(orb)
                r = (volume / (n * _CAPPED_K)) ** (1 / 3)
                if r <= rd + 1e-12:
                    if r >= MIN_CAVITY_RADIUS and (best is None or r > best.radius + 1e-12):
                        best = _CavityLayout(np.concatenate(orbits[: j + 1]), r, rd, f"poisson/{symmetry}")
                    break
    if best is not None:
        return best
    # Fallback: the deterministic lattice (it reaches the catalog's m_min).
    solid = rod.solid()
    com = mass_properties(solid).center
    clr = Clearance(solid)

    def clearance(p: np.ndarray) -> np.ndarray:
        return np.minimum(clr(p), _silo_distance(p, sockets, socket_r))

    info = rod.mass_info()
    radii = sorted(set(_radii(rod)) | ({info.cavity_radius} if info.cavity_radius > 0 else set()), reverse=True)
    for rd in radii:
        lay = sphere_layout(clearance, clr.bounds, com, rd, wall, void="capped")
        if lay.count == 0:
            continue
        r = (volume / (lay.count * _CAPPED_K)) ** (1 / 3)
        if r <= rd * (1 + 1e-9) and r >= MIN_CAVITY_RADIUS and (best is None or r > best.radius):
            best = _CavityLayout(lay.centers, min(r, rd), rd, f"lattice/{lay.symmetry}")
    return best


# --------------------------------------------------------------------------- planning


@lru_cache(maxsize=64)
def _socket_layout(rod: RodType) -> Any:
    """The type's largest symmetric socket layout (the one behind m_max; the
    ball half of :func:`rodcad.massrange.layouts`)."""
    from rodcad.geometry import Clearance, mass_properties
    from rodcad.massrange import SphereLayout, ball_offset, max_ball_layout

    if rod.balls is None:
        return SphereLayout.empty()
    solid = rod.solid()
    clearance = Clearance(solid)
    lift = ball_offset(rod.balls.socket_diameter / 2, rod.balls.mass, rod.material.density)
    return max_ball_layout(clearance, clearance.bounds, mass_properties(solid).center, rod.balls.socket_diameter,
                           rod.material.min_wall, void="silo", raise_by=lift)


def _orbits(points: np.ndarray, center: Sequence[float], symmetry: str) -> list[np.ndarray]:
    """Split a symmetric point set into orbits (index arrays), sorted by size then position."""
    left = list(range(len(points)))
    out = []
    while left:
        i = left[0]
        imgs = [points[i]] + list(_images(points[i][None], center, symmetry))
        orb = sorted({j for j in left for q in imgs if np.linalg.norm(points[j] - np.ravel(q)) < 1e-6})
        out.append(np.array(orb))
        left = [j for j in left if j not in orb]
    return out


def _fmt(x: float) -> str:
    return f"{x:.3f}"


def _merge(pieces: Sequence[tuple[float, float]], gap: float = 0.0) -> list[tuple[float, float]]:
    """Sorted union of closed intervals; gaps narrower than ``gap`` x the mass are bridged."""
    out: list[list[float]] = []
    for a, b in sorted(pieces):
        if out and a <= out[-1][1] * (1 + gap):
            out[-1][1] = max(out[-1][1], b)
        else:
            out.append([a, b])
    return [(float(a), float(b)) for a, b in out]


def _ball_options(rod: RodType) -> list[tuple[float, np.ndarray, float]]:
    """(mass without cavities, socket centres, socket radius) per symmetric ball
    subset, the plain solid first, sorted by mass then ball count."""
    info = rod.mass_info()
    rho = rod.material.density / 1000.0
    ms = info.volume * rho
    options: list[tuple[float, np.ndarray, float]] = [(ms, np.zeros((0, 3)), 0.0)]
    if rod.balls is None:
        return options
    balls = _socket_layout(rod)
    if not balls.count:
        return options
    rs = balls.radius
    net = rod.balls.mass - void_volume("silo", rs) * rho
    sites = balls.centers - UP * (balls.centers[0] @ UP - info.com[1])
    orbs = _orbits(sites, (info.com[0], info.com[1], 0.0), balls.symmetry)
    for mask in range(1, 2 ** len(orbs)):
        idx = np.concatenate([orbs[b] for b in range(len(orbs)) if mask >> b & 1])
        options.append((ms + len(idx) * net, balls.centers[np.sort(idx)], rs))
    options.sort(key=lambda o: (o[0], len(o[1])))
    return options


def _removable(rod: RodType, sockets: np.ndarray, socket_r: float, seed: int,
               lattice_counts: dict[float, int] | None = None) -> list[tuple[float, float]]:
    """The cavity volumes (mm^3) :func:`_cavities` can remove beside these
    sockets, as sorted disjoint intervals (exactly its acceptance rule: a
    prefix of j orbits with n_j sites is used for volumes in
    (n_{j-1} k r_d^3, n_j k r_d^3] and needs a radius >= MIN_CAVITY_RADIUS).

    The symmetric-lattice fallback is included too (it reaches the catalog's
    m_min), except for radii where even the lattice without sockets
    (``lattice_counts``: radius -> cavities, filled in when given empty) could
    not remove more than the Poisson layouts: leaving reachable masses out only
    makes the table conservative, never wrong.
    """
    wall = rod.material.min_wall
    k_min = _CAPPED_K * MIN_CAVITY_RADIUS**3
    pieces: list[tuple[float, float]] = []
    for symmetry in ("mirror-xyz", "point-xy"):
        pool = _pool(rod, symmetry, seed)
        for rd in _radii(rod):
            n_prev = 0
            for orb in _dart_throw(pool, rd, wall, sockets, socket_r):
                n = n_prev + len(orb)
                lo, hi = max(n * k_min, n_prev * _CAPPED_K * rd**3), n * _CAPPED_K * rd**3
                if lo < hi:
                    pieces.append((lo, hi))
                n_prev = n
    top = max((b for _, b in pieces), default=0.0)
    if True:
        from rodcad.geometry import Clearance, mass_properties

        solid = rod.solid()
        com = mass_properties(solid).center
        clr = Clearance(solid)

        def clearance(p: np.ndarray) -> np.ndarray:
            return np.minimum(clr(p), _silo_distance(p, sockets, socket_r))

        info = rod.mass_info()
        radii = sorted(set(_radii(rod)) | ({info.cavity_radius} if info.cavity_radius > 0 else set()),
                       reverse=True)
        for rd in radii:
            if lattice_counts is not None and len(sockets) and rd in lattice_counts \
                    and lattice_counts[rd] * _CAPPED_K * rd**3 <= top:
                continue
            lay = sphere_layout(clearance, clr.bounds, com, rd, wall, void="capped")
            if lattice_counts is not None and not len(sockets):
                lattice_counts[rd] = lay.count
            if lay.count:
                pieces.append((lay.count * k_min, lay.count * _CAPPED_K * rd**3))
    # a hair inside every edge, so that the edges themselves solve
    return [(a * (1 + 1e-9), b * (1 - 1e-9)) for a, b in _merge(pieces) if b * (1 - 1e-9) > a * (1 + 1e-9)]


def _intervals_key(rod: RodType, seed: int) -> str:
    from rodcad.catalog import GEOMETRY_VERSION

    return make_key("fabint", INTERVALS_VERSION, FABRICATE_VERSION, MASSRANGE_VERSION, GEOMETRY_VERSION,
                    POOL_SIZE, RADIUS_FACTOR, MIN_CAVITY_RADIUS, SOLID_TOL, GAP_MERGE,
                    asdict(rod.geometry), asdict(rod.material),
                    asdict(rod.balls) if rod.balls is not None else None, int(seed))


def _compute_table(rod: RodType, seed: int) -> dict[str, Any]:
    """Every ball option with the masses its cavities reach, and the merged
    achievable intervals (numbers only; JSON-serialisable)."""
    info = rod.mass_info()
    rho = rod.material.density / 1000.0
    options = []
    pieces: list[tuple[float, float]] = []
    counts: dict[float, int] = {}
    for mass_k, socks, rs in _ball_options(rod):  # the ball-free rod first
        reach = [(mass_k - b * rho, mass_k - a * rho) for a, b in _removable(rod, socks, rs, seed, counts)]
        options.append({"mass": mass_k, "sockets": socks.tolist(), "socket_radius": rs,
                         "pieces": [list(p) for p in sorted(reach)]})
        pieces += reach + [(mass_k * (1 - SOLID_TOL), mass_k * (1 + SOLID_TOL))]
    intervals = []
    for a, b in _merge(pieces, GAP_MERGE):
        # the catalog's extremes are built (within round-off) when reached
        a = info.m_min if abs(a - info.m_min) <= EDGE_TOL * info.m_min else max(a, info.m_min)
        b = info.m_max if abs(b - info.m_max) <= EDGE_TOL * info.m_max else min(b, info.m_max)
        if a <= b:
            intervals.append([a, b])
    return {"options": options, "intervals": intervals, "m_min": info.m_min, "m_max": info.m_max}


def _table(rod: RodType, seed: int, cache: DiskCache | None = None) -> dict[str, Any]:
    """:func:`_compute_table`, from the disk cache when possible."""
    cache = cache if cache is not None else DiskCache()
    key = _intervals_key(rod, seed)
    hit = cache.get("fabint", key)
    if isinstance(hit, dict) and "options" in hit and "intervals" in hit:
        return hit
    table = _compute_table(rod, seed)
    cache.put("fabint", key, table)
    return table


def achievable_intervals(rod: RodType, *, seed: int = 0, cache: DiskCache | None = None) -> list[tuple[float, float]]:
    """The masses (g) this rod type can really be built at, as sorted disjoint intervals.

    Without balls the rod reaches [m_min, solid mass] (cavities); with k balls,
    from k balls and the most cavities that fit beside them up to k balls and
    no cavities. Above the solid mass these are narrow bands (a ball adds far
    more than the cavities beside the sockets can remove), so the catalog's
    [m_min, m_max] is not continuous. Gaps narrower than :data:`GAP_MERGE` x the
    mass (where the smallest printable cavity is still too big) are bridged:
    such targets are built at the nearest reachable mass, within that
    tolerance, and are not reported as problems.

    :func:`fabricate_rod` and :func:`fabricate_chain` plan with the same table,
    so a target inside an interval builds within :data:`MASS_TOL` and one in a
    gap is built at the nearest interval edge and reported (``in_range=False``).
    Computed once per type (and seed) and cached on disk.

    Args:
        rod: the rod type.
        seed: seed of the Poisson-disk layouts (as for :func:`fabricate_chain`).
        cache: disk cache (default :class:`DiskCache`).

    Returns:
        [(lo, hi), ...] in g, ascending, within the type's [m_min, m_max];
        e.g. ``achievable_intervals(cat['free-20'])[0] == (m_min, ~solid mass)``.
    """
    return [(float(a), float(b)) for a, b in _table(rod, seed, cache)["intervals"]]


def chain_intervals(types: Sequence[RodType], *, seed: int = 0, jobs: int | None = None,
                    cache: DiskCache | None = None) -> dict[str, list[tuple[float, float]]]:
    """:func:`achievable_intervals` of several rod types (name -> intervals),
    the uncached ones computed in ``jobs`` worker processes (default: the CPUs)."""
    cache = cache if cache is not None else DiskCache()
    uniq = list({rod.name: rod for rod in types}.values())
    todo = [rod for rod in uniq if not isinstance(cache.get("fabint", _intervals_key(rod, seed)), dict)]
    jobs = max(1, min(jobs or default_jobs(), len(todo))) if todo else 1
    if jobs > 1:
        pool = worker_pool(jobs)
        try:
            for rod, table in zip(todo, pool.map(_table_star, [(rod, seed) for rod in todo], chunksize=1)):
                cache.put("fabint", _intervals_key(rod, seed), table)
        finally:
            pool.shutdown()
    return {rod.name: achievable_intervals(rod, seed=seed, cache=cache) for rod in uniq}


def _table_star(args: tuple[RodType, int]) -> dict[str, Any]:
    rod, seed = args
    return _compute_table(rod, seed)


def _plan(rod: RodType, target: float, seed: int, table: dict[str, Any] | None = None) -> dict[str, Any]:
    """Sockets, cavities and messages for one rod (numbers only, no B-rep booleans).

    The ball subset and the cavity volume come from the type's table of
    reachable masses (:func:`achievable_intervals`); one cavity layout search
    follows for the chosen subset.
    """
    info = rod.mass_info()
    rho = rod.material.density / 1000.0
    table = table if table is not None else _compute_table(rod, seed)
    m_lo, m_hi = info.m_min, info.m_max
    message = ""
    m = float(target)
    if m < m_lo * (1 - 1e-12):
        short = (m_lo - m) / rho
        message = (f"target {_fmt(target)} g is {_fmt(m_lo - m)} g ({(m_lo - m) / m_lo:.1%}) below the lightest "
                   f"printable {rod.name} ({_fmt(m_lo)} g with {info.cavity_count} cavities); it would need "
                   f"{short:.0f} mm^3 more cavity volume than the walls allow (a lighter type, a thinner "
                   "minimum wall or a lighter material)")
        m = m_lo
    elif m > m_hi * (1 + 1e-12):
        extra = m - m_hi
        if rod.balls is not None:
            rs = rod.balls.socket_diameter / 2
            net = rod.balls.mass - void_volume("silo", rs) * rho
            need = f"about {math.ceil(extra / net)} more {rod.balls.diameter:g} mm balls than fit ({info.ball_count})"
        else:
            need = "metal balls, which this catalog does not give it"
        message = (f"target {_fmt(target)} g is {_fmt(extra)} g ({extra / m_hi:.1%}) above the heaviest printable "
                   f"{rod.name} ({_fmt(m_hi)} g); it would need {need}, denser balls or a larger section")
        m = m_hi
    options = table["options"]

    def exact(mass: float) -> tuple[int, float] | None:
        """(option, cavity volume) building ``mass`` as the original search would: the
        lightest ball subset that is solid at it or whose cavities reach it."""
        for i, opt in enumerate(options):
            mass_k = opt["mass"]
            if mass_k < mass * (1 - SOLID_TOL):
                continue
            if mass_k - mass <= SOLID_TOL * mass:
                return i, 0.0
            if any(a <= mass <= b for a, b in opt["pieces"]):
                return i, (mass_k - mass) / rho
        return None

    build = m
    found = exact(m)
    if found is None:  # the nearest reachable mass: a piece edge or a ball count's solid mass
        cands = [(abs(o["mass"] - m), o["mass"]) for o in options]
        cands += [(abs(min(max(m, a), b) - m), min(max(m, a), b)) for o in options for a, b in o["pieces"]]
        build = min(cands)[1]
        found = exact(build)
        assert found is not None
        inside = (any(a * (1 - EDGE_TOL) <= m <= b * (1 + EDGE_TOL) for a, b in table["intervals"])
                  or abs(build - m) <= 1e-6 * m)  # an interval edge met to round-off
        if not inside:
            message = (message + "; " if message else "") + (
                f"{_fmt(m)} g lies in a gap between the ball counts of {rod.name} (balls come in symmetric "
                f"groups and the cavities beside them cannot bridge it); built at {_fmt(build)} g with "
                f"{len(options[found[0]]['sockets'])} balls")
            m = build
    i, remove = found
    opt = options[i]
    socks = np.array(opt["sockets"], dtype=float).reshape(-1, 3)
    rs = float(opt["socket_radius"])
    cav = _cavities(rod, remove, socks, rs, seed) if remove > 0 else None
    if remove > 0 and cav is None:  # pragma: no cover - the table says it fits
        raise FabricationError(f"{rod.name}: no cavity layout removes {remove:.3f} mm^3 beside "
                               f"{len(socks)} balls, although the table of reachable masses says one does")
    return {
        "mass": m,
        "build_mass": build,
        "sockets": socks.tolist(),
        "socket_radius": rs if len(socks) else 0.0,
        "cavities": [] if cav is None else cav.centers.tolist(),
        "cavity_radius": 0.0 if cav is None else cav.radius,
        "cavity_bound": 0.0 if cav is None else cav.bound,
        "layout": "" if cav is None else cav.layout,
        "message": message,
    }


# --------------------------------------------------------------------------- building


def _build(rod: RodType, plan: dict[str, Any]) -> tuple[Any, float, dict[str, Any]]:
    """The B-rep for a plan, with the cavity radius root-solved on its volume.

    Returns:
        (solid, cavity radius, measurements).
    """
    from rodcad import geometry

    rho = rod.material.density / 1000.0
    plain = rod.solid()
    socks = np.array(plan["sockets"], dtype=float).reshape(-1, 3)
    cavs = np.array(plan["cavities"], dtype=float).reshape(-1, 3)
    rs = float(plan["socket_radius"])
    n_balls = len(socks)
    metal = n_balls * rod.balls.mass if n_balls and rod.balls is not None else 0.0
    target = float(plan.get("build_mass", plan["mass"]))

    def make(r: float) -> Any:
        groups = [("silo", socks, rs)] if n_balls else []
        if len(cavs):
            groups.append(("capped", cavs, r))
        return geometry.with_voids(plain, groups, rod.name)

    r = float(plan["cavity_radius"])
    solid = make(r)
    volume = geometry.mass_properties(solid).volume
    booleans = 1
    if len(cavs):
        bound = float(plan["cavity_bound"])
        for _ in range(4):  # Newton on the B-rep volume, analytic derivative
            err = (volume * rho + metal - target) / target
            if abs(err) <= SOLVE_TOL:
                break
            dm_dr = -rho * len(cavs) * 3 * _CAPPED_K * r * r
            r = min(r - err * target / dm_dr, bound)
            solid = make(r)
            volume = geometry.mass_properties(solid).volume
            booleans += 1
    props = geometry.mass_properties(solid)
    voids = (geometry.void_solids("silo", socks, rs) if n_balls else []) + \
        (geometry.void_solids("capped", cavs, r) if len(cavs) else [])
    wall = math.inf
    if voids:
        to_faces, between = geometry.void_walls(plain, voids, rod.material.min_wall + 1.0)
        wall = min(float(to_faces.min()), between)
    c = np.array(props.center) * props.volume * rho
    if n_balls:
        c = c + rod.balls.mass * socks.sum(axis=0)  # type: ignore[union-attr]
    mass = props.volume * rho + metal
    com = c / mass
    return solid, r, {"volume": props.volume, "mass": mass, "com": [float(com[0]), float(com[1])],
                      "min_wall": wall, "booleans": booleans}


def _key(rod: RodType, target: float, seed: int) -> str:
    from rodcad.catalog import GEOMETRY_VERSION

    return make_key("fab", FABRICATE_VERSION, MASSRANGE_VERSION, GEOMETRY_VERSION, POOL_SIZE, RADIUS_FACTOR,
                    asdict(rod.geometry), asdict(rod.material),
                    asdict(rod.balls) if rod.balls is not None else None, round(float(target), 9), int(seed))


def _fabricate_star(args: tuple[RodType, float, int, dict[str, Any] | None]) -> dict[str, Any]:
    """Worker: plan, build, root-solve and measure one rod; returns numbers only."""
    rod, target, seed, table = args
    plan = _plan(rod, target, seed, table)
    _, r, meas = _build(rod, plan)
    plan["cavity_radius"] = r
    plan["measured"] = meas
    return plan


def _type_star(args: tuple[RodType, list[float], int, dict[str, Any] | None]) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """Worker: the type's table of reachable masses (unless given), then every
    rod of that type (the type's candidate pools are built once per worker)."""
    rod, targets, seed, table = args
    table = table if table is not None else _compute_table(rod, seed)
    return table, [_fabricate_star((rod, m, seed, table)) for m in targets]


def fabricate_rod(rod: RodType, target: float, *, index: int = 0, seed: int = 0,
                  cache: DiskCache | None = None, _plan_data: dict[str, Any] | None = None) -> FabricatedRod:
    """Fabricate one rod (see :func:`fabricate_chain`)."""
    from rodcad import geometry

    cache = cache if cache is not None else DiskCache()
    plan = _plan_data
    if plan is None:
        key = _key(rod, target, seed)
        plan = cache.get("fab", key)
        if plan is None:
            plan = _fabricate_star((rod, target, seed, _table(rod, seed, cache)))
            cache.put("fab", key, plan)
    return _assemble_result(rod, target, index, plan, geometry)


def _assemble_result(rod: RodType, target: float, index: int, plan: dict[str, Any], geometry: Any) -> FabricatedRod:
    """Rebuild the solid from a solved plan (one boolean) and collect the numbers."""
    rho = rod.material.density / 1000.0
    socks = np.array(plan["sockets"], dtype=float).reshape(-1, 3)
    cavs = np.array(plan["cavities"], dtype=float).reshape(-1, 3)
    rs = float(plan["socket_radius"])
    r = float(plan["cavity_radius"])
    groups = ([("silo", socks, rs)] if len(socks) else []) + ([("capped", cavs, r)] if len(cavs) else [])
    solid = geometry.with_voids(rod.solid(), groups, rod.name)
    meas = plan["measured"]
    volume = geometry.mass_properties(solid).volume
    if abs(volume - meas["volume"]) > 1e-6 * meas["volume"]:
        raise FabricationError(f"rod {index} ({rod.name}): rebuilt volume {volume} differs from the solved "
                               f"{meas['volume']} mm^3")
    wall = rod.material.min_wall
    if meas["min_wall"] < wall - 1e-6:
        raise FabricationError(f"rod {index} ({rod.name}): a wall of {meas['min_wall']:.3f} mm around a void is "
                               f"thinner than the minimum {wall} mm")
    pm = geometry.print_matrix(solid)
    roofs: list[float] = []
    for z in sorted(socks @ UP + rs + pm[2, 3]):  # rod +y is bed +Z
        if not roofs or z - roofs[-1] > 1e-6:
            roofs.append(float(z))
    pause = roofs[0] if roofs else None
    goal = float(plan["mass"])
    mass = float(meas["mass"])
    if abs(mass - goal) > MASS_TOL * goal:
        raise FabricationError(f"rod {index} ({rod.name}): built {mass:.4f} g for {goal:.4f} g")
    note = ""
    if rod.geometry.curvature != 0:
        g = rod.geometry
        rho_c = 1 / abs(g.curvature)
        sag = rho_c * (1 - math.cos(math.radians(abs(g.half_angle_deg))))
        note = (f"curved: rests on its arc's lowest point, the ends rise {sag:.1f} mm (the underside overhangs up "
                f"to {abs(g.half_angle_deg):.0f} deg from the bed; add support under the ends)")
    return FabricatedRod(
        index=index, type_name=rod.name, target_mass=float(target), mass=mass,
        com=(float(meas["com"][0]), float(meas["com"][1])), plastic_volume=float(meas["volume"]),
        filament_mass=float(meas["volume"]) * rho, cavity_count=len(cavs), cavity_radius=r if len(cavs) else 0.0,
        ball_count=len(socks), ball_diameter=rod.balls.diameter if len(socks) and rod.balls else None,
        pause_z=pause, mass_error=(mass - goal) / goal, in_range=not plan["message"], message=plan["message"],
        solid=solid, cavity_centers=cavs, socket_centers=socks, socket_radius=rs if len(socks) else 0.0,
        min_wall=float(meas["min_wall"]), layout=plan["layout"], print_matrix=pm,
        file_stem=f"{index:02d}_{rod.name}", print_note=note, thickness=rod.geometry.thickness,
        pin_diameter=rod.geometry.hinge.pin_diameter, pause_zs=tuple(roofs))


def fabricate_chain(types: Sequence[RodType], masses: Sequence[float], *, seed: int = 0, jobs: int | None = None,
                    progress: Callable[[int, int], None] | None = None,
                    cache: DiskCache | None = None) -> ChainFabrication:
    """Cavities and ball sockets for every rod of a chain, built on the B-rep.

    Identical rods (same type, same target mass to 1 microgram) are built
    once and share their solid; distinct ones are solved in ``jobs`` worker
    processes (default: the CPUs) and cached on disk. Out-of-range targets are
    clipped to the type's range, built, and reported in ``problems``.

    Args:
        types: rod type per chain position.
        masses: target mass per position (g).
        seed: seed of the Poisson-disk layouts (same input, same output).
        jobs: worker processes.
        progress: called with (done, total) distinct rods.
        cache: disk cache (default :class:`DiskCache`).

    Returns:
        The :class:`ChainFabrication`; e.g. ``all(abs(r.mass_error) < 1e-3 for r in fab.rods)``.

    Raises:
        FabricationError: a built rod failed its checks (mass, walls, rebuild).
    """
    from rodcad import geometry

    t0 = time.perf_counter()
    if len(types) != len(masses):
        raise ValueError(f"{len(types)} rod types but {len(masses)} masses")
    cache = cache if cache is not None else DiskCache()
    keys: dict[tuple[str, float], int] = {}
    distinct: list[tuple[RodType, float]] = []
    where: list[int] = []
    for rod, m in zip(types, masses):
        k = (rod.name, round(float(m), 6))
        if k not in keys:
            keys[k] = len(distinct)
            distinct.append((rod, float(m)))
        where.append(keys[k])
    plans: list[dict[str, Any] | None] = []
    todo: list[int] = []
    for i, (rod, m) in enumerate(distinct):
        hit = cache.get("fab", _key(rod, m, seed))
        plans.append(hit)
        if hit is None:
            todo.append(i)
    done = len(distinct) - len(todo)
    if progress:
        progress(done, len(distinct))
    # One task per rod type (its table of reachable masses, then its rods), so
    # each worker builds a type's candidate pools once; a type with more than
    # its share of the rods is split so every worker has work.
    by_type: dict[str, list[int]] = {}
    for i in todo:
        by_type.setdefault(distinct[i][0].name, []).append(i)
    jobs = max(1, min(jobs or default_jobs(), len(todo))) if todo else 1
    share = max(1, math.ceil(len(todo) / jobs)) if len(by_type) < jobs else len(todo)
    tasks: list[list[int]] = []
    for idx in by_type.values():
        tasks += [idx[k:k + share] for k in range(0, len(idx), share)]
    tasks.sort(key=len, reverse=True)
    tables: dict[str, dict[str, Any] | None] = {}
    for idx in tasks:
        rod = distinct[idx[0]][0]
        if rod.name not in tables:
            hit = cache.get("fabint", _intervals_key(rod, seed))
            tables[rod.name] = hit if isinstance(hit, dict) and "options" in hit else None
    pool = worker_pool(jobs) if jobs > 1 and len(tasks) > 1 else None
    try:
        args = [(distinct[idx[0]][0], [distinct[i][1] for i in idx], seed, tables[distinct[idx[0]][0].name])
                for idx in tasks]
        results = pool.map(_type_star, args, chunksize=1) if pool is not None else map(_type_star, args)
        for idx, (table, res) in zip(tasks, results):
            rod = distinct[idx[0]][0]
            if tables[rod.name] is None:
                tables[rod.name] = table
                cache.put("fabint", _intervals_key(rod, seed), table)
            for i, plan in zip(idx, res):
                plans[i] = plan
                cache.put("fab", _key(distinct[i][0], distinct[i][1], seed), plan)
                done += 1
                if progress:
                    progress(done, len(distinct))
    finally:
        if pool is not None:
            pool.shutdown()
    built = [_assemble_result(rod, m, 0, plans[i], geometry) for i, (rod, m) in enumerate(distinct)]  # type: ignore[arg-type]
    rods: list[FabricatedRod] = []
    problems: list[str] = []
    for index, (rod, m) in enumerate(zip(types, masses)):
        b = built[where[index]]
        fr = FabricatedRod(**{**b.__dict__, "index": index, "target_mass": float(m),
                              "file_stem": f"{index:02d}_{rod.name}"})
        rods.append(fr)
        if fr.message:
            problems.append(f"Rod {index} ({rod.name}): {fr.message}.")
    return ChainFabrication(rods, problems, len(distinct), time.perf_counter() - t0)


# --------------------------------------------------------------------------- files


def _check_files(step: Path, stl: Path, volume: float) -> None:
    import trimesh

    from rodcad import geometry

    back = geometry.import_step(step)
    if not geometry.is_valid_solid(back):
        raise FabricationError(f"{step} does not re-import as a valid solid")
    if abs(back.volume - volume) > 1e-6 * volume:
        raise FabricationError(f"{step} re-imports with volume {back.volume:.4f} instead of {volume:.4f} mm^3")
    mesh = trimesh.load(str(stl), force="mesh")
    if not mesh.is_watertight:
        # OCCT's sphere poles give zero-area triangles: drop them and rewrite.
        mesh.update_faces(mesh.nondegenerate_faces())
        mesh.remove_unreferenced_vertices()
        mesh.merge_vertices()
        if mesh.is_watertight:
            mesh.export(str(stl), file_type="stl")
            mesh = trimesh.load(str(stl), force="mesh")
    if not mesh.is_watertight:
        raise FabricationError(f"{stl} is not watertight")
    if abs(mesh.volume - volume) > MASS_TOL * volume:
        raise FabricationError(f"{stl} encloses {mesh.volume:.3f} mm^3, the solid {volume:.3f} mm^3 "
                               f"({(mesh.volume - volume) / volume:+.2%})")


def write_rod_files(fab: ChainFabrication, outdir: Path) -> list[Path]:
    """Write outdir/rods/NN_TYPE.step and .stl for every chain position.

    NN is the rod's 0-based index (as in design.json), two digits or more.
    The solids are in print orientation on the bed (rod frame +y up, the -y
    face on Z = 0, see :data:`rodcad.geometry.PRINT_ROTATION`). Rods that share
    a solid are written and checked once, then copied. Checks: the STEP
    re-imports as one valid solid of the same volume (1e-6), the STL is
    watertight and encloses the B-rep's volume within 0.1 %.

    Returns:
        The paths written (STEP, STL per rod).

    Raises:
        FabricationError: a check failed.
    """
    from rodcad import geometry

    rods_dir = Path(outdir) / "rods"
    rods_dir.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    first: dict[int, tuple[Path, Path]] = {}
    for r in fab.rods:
        step = rods_dir / f"{r.file_stem}.step"
        stl = rods_dir / f"{r.file_stem}.stl"
        src = first.get(id(r.solid))
        if src is None:
            on_bed = geometry.transformed(r.solid, r.print_matrix)
            geometry.export_step(on_bed, step, r.file_stem)
            geometry.export_stl(on_bed, stl)
            _check_files(step, stl, r.plastic_volume)
            first[id(r.solid)] = (step, stl)
        else:
            shutil.copyfile(src[0], step)
            shutil.copyfile(src[1], stl)
        written += [step, stl]
    return written


def mass_colors(masses: Sequence[float]) -> list[tuple[float, float, float]]:
    """(r, g, b) per mass from blue (lightest) to red (heaviest) (matplotlib 'coolwarm')."""
    import matplotlib

    m = np.asarray(masses, dtype=float)
    lo, hi = float(m.min()), float(m.max())
    t = (m - lo) / (hi - lo) if hi - lo > 1e-12 * max(hi, 1.0) else np.full(len(m), 0.5)
    cmap = matplotlib.colormaps["coolwarm"]
    return [tuple(float(c) for c in cmap(v)[:3]) for v in t]


def rod_matrices(points: np.ndarray) -> list[np.ndarray]:
    """4x4 placement of each rod frame: origin at points[i], x towards points[i+1], z = +z."""
    pts = np.asarray(points, dtype=float)
    out = []
    for p, q in zip(pts[:-1], pts[1:]):
        d = q - p
        c, s = d / np.hypot(*d)
        m = np.eye(4)
        m[:2, :2] = [[c, -s], [s, c]]
        m[:2, 3] = p
        out.append(m)
    return out


def write_assembly(fab: ChainFabrication, points: np.ndarray, path: Path, *, name: str = "chain") -> Path:
    """Write the chain in its simulated pose as a STEP assembly.

    Each rod is a solid named 'NN_TYPE' (its rods/ file stem), placed with its
    frame origin at ``points[i]`` and x along points[i] -> points[i+1] (chain
    plane xy, y up, hinge axes along z), coloured by mass from blue (lightest)
    to red (heaviest); every joint gets a pin 'pin_NN' (pin diameter, through
    the rod thickness).

    Args:
        fab: the fabricated chain.
        points: (N+1, 2) joint positions (mm).
        path: destination file.
        name: root assembly name.
    """
    from rodcad import geometry

    pts = np.asarray(points, dtype=float)
    if pts.shape != (len(fab.rods) + 1, 2):
        raise ValueError(f"points must have shape ({len(fab.rods) + 1}, 2), not {pts.shape}")
    colors = mass_colors([r.mass for r in fab.rods])
    nodes: list[Any] = []
    for r, m, col in zip(fab.rods, rod_matrices(pts), colors):
        nodes.append(geometry.AssemblyPart(r.file_stem, r.solid, m, col))
    for j, p in enumerate(pts):
        rod = fab.rods[min(j, len(fab.rods) - 1)]
        hinge_t, pin_d = _pin_size(rod)
        m = np.eye(4)
        m[:2, 3] = p
        m[2, 3] = -hinge_t / 2
        nodes.append(geometry.AssemblyPart(f"pin_{j:02d}", geometry.pin_solid(pin_d, hinge_t), m,
                                           (0.75, 0.75, 0.78)))
    return geometry.export_assembly(path, nodes, name)


def _pin_size(rod: FabricatedRod) -> tuple[float, float]:
    """(length, diameter) of a pin through a rod (its thickness, the pin diameter)."""
    return rod.thickness, rod.pin_diameter
