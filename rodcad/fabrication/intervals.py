"""Masses a rod type can really be built at: per ball count, the interval that cavities
beside the balls reach; the union over ball counts, merged (disk-cached tables). A rod with
a ``fill`` reaches its whole range continuously (:mod:`rodcad.catalog.chamber`): no table.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from rodcad.catalog.cache import DiskCache, make_key
from rodcad.catalog.chamber import fill_numbers
from rodcad.catalog.massrange import MASSRANGE_VERSION
from rodcad.fabrication.layout import MIN_CAVITY_RADIUS, UP, void_volume
from rodcad.parallel import cached_map

if TYPE_CHECKING:  # pragma: no cover
    from rodcad.catalog.model import RodType
from rodcad.catalog.massrange import mass_info
from rodcad.fabrication.cavities import (
    CAPPED_K,
    EDGE_TOL,
    FABRICATE_VERSION,
    POOL_SIZE,
    RADIUS_FACTOR,
    SOLID_TOL,
    cavity_pool,
    cavity_radii,
    dart_throw,
    lattice_layouts_many,
    orbits,
    row_layout,
    socket_layout,
)

__all__ = [
    "GAP_MERGE",
    "INTERVALS_VERSION",
    "ROWS",
    "achievable_intervals",
    "chain_intervals",
    "compute_table",
    "fmt_mass",
    "interval_table",
    "intervals_key",
    "removable_volumes",
    "removable_volumes_many",
    "row_alternates",
]


#: Bump when the tables of reachable masses change (:func:`achievable_intervals`).
INTERVALS_VERSION = "1"


#: Gaps between reachable masses narrower than this (relative) are bridged:
#: a target there is built at the nearest reachable mass (within half of it).
GAP_MERGE = 5e-4


def fmt_mass(x: float) -> str:
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


def _ball_options(rod: RodType) -> list[tuple[float, np.ndarray, float, int]]:
    """(mass without cavities, socket centres, socket radius, ball kind) per symmetric ball
    subset, the plain solid first, sorted by mass then ball count. Every subset of the
    first ball kind; of each further kind (:attr:`RodType.ball_kinds`) only the subsets
    heavier than every option of the kinds before (a kind is used where those cannot reach)."""
    info = mass_info(rod)
    rho = rod.material.density / 1000.0
    ms = info.volume * rho
    options: list[tuple[float, np.ndarray, float, int]] = [(ms, np.zeros((0, 3)), 0.0, 0)]
    for kind, balls_k in enumerate(rod.ball_kinds):
        balls = socket_layout(rod.with_kind(kind))
        if not balls.count:
            continue
        top = max(o[0] for o in options)
        rs = balls.radius
        net = balls_k.mass - void_volume("silo", rs) * rho
        sites = balls.centers - UP * (balls.centers[0] @ UP - info.com[1])
        orbs = orbits(sites, (info.com[0], info.com[1], 0.0), balls.symmetry)
        for mask in _ball_masks(orbs, sites, (info.com[0], info.com[1], 0.0)):
            idx = np.concatenate([orbs[b] for b in range(len(orbs)) if mask >> b & 1])
            mass_k = ms + len(idx) * net
            if kind == 0 or mass_k > top:
                options.append((mass_k, balls.centers[np.sort(idx)], rs, kind))
    options.sort(key=lambda o: (o[0], len(o[1]), o[3]))
    return options


#: A rod with at most this many symmetric orbits of ball sockets is tried with every subset
#: of them; a larger one (a thick graduated rod holds up to twenty balls) with the nested
#: subsets only, filled from the centre of mass outward and from the ends inward (each
#: option costs a cavity search: 2^orbits of them would take minutes per rod).
MAX_FREE_ORBITS = 5


def _ball_masks(orbs: list[np.ndarray], sites: np.ndarray, com) -> list[int]:
    """The subsets of orbits tried (bit masks): all of them for up to :data:`MAX_FREE_ORBITS`
    orbits, else the nested ones (orbits by their distance from the centre of mass: the
    nearest k, and the furthest k, for every k)."""
    if len(orbs) <= MAX_FREE_ORBITS:
        return list(range(1, 2 ** len(orbs)))
    dist = [float(np.mean(np.linalg.norm(sites[o] - np.asarray(com, float), axis=1))) for o in orbs]
    order = sorted(range(len(orbs)), key=lambda b: (dist[b], b))
    masks: list[int] = []
    for seq in (order, order[::-1]):
        m = 0
        for b in seq:
            m |= 1 << b
            if m not in masks:
                masks.append(m)
    return masks


def removable_volumes(rod: RodType, sockets: np.ndarray, socket_r: float, seed: int,
               lattice_counts: dict[float, int] | None = None) -> list[tuple[float, float]]:
    """The cavity volumes (mm^3) :func:`place_cavities` can remove beside these
    sockets, as sorted disjoint intervals (exactly its acceptance rule: a
    prefix of j orbits with n_j sites is used for volumes in
    (n_{j-1} k r_d^3, n_j k r_d^3] and needs a radius >= MIN_CAVITY_RADIUS).

    The symmetric-lattice fallback is included too (it reaches the catalog's
    m_min), except for radii where even the lattice without sockets
    (``lattice_counts``: radius -> cavities, filled in when given empty) could
    not remove more than the Poisson layouts: leaving reachable masses out only
    makes the table conservative, never wrong.
    """
    return removable_volumes_many(rod, [(sockets, socket_r)], seed, lattice_counts)[0]


def removable_volumes_many(rod: RodType, options: Sequence[tuple[np.ndarray, float]], seed: int,
                           lattice_counts: dict[float, int] | None = None) -> list[list[tuple[float, float]]]:
    """:func:`removable_volumes` of several ball options ((sockets, socket radius) each) of
    one rod, the same numbers, their lattices laid once (:func:`lattice_layouts_many`).
    ``lattice_counts`` is filled in by the options without sockets, which are laid first."""
    wall = rod.material.min_wall
    k_min = CAPPED_K * MIN_CAVITY_RADIUS**3
    options = [(np.asarray(s, dtype=float).reshape(-1, 3), float(r)) for s, r in options]
    pieces: list[list[tuple[float, float]]] = [[] for _ in options]
    for j, (sockets, socket_r) in enumerate(options):
        for symmetry in ("mirror-xyz", "point-xy"):
            pool = cavity_pool(rod, symmetry, seed)
            for rd in cavity_radii(rod):
                n_prev = 0
                for orb in dart_throw(pool, rd, wall, sockets, socket_r):
                    n = n_prev + len(orb)
                    lo, hi = max(n * k_min, n_prev * CAPPED_K * rd**3), n * CAPPED_K * rd**3
                    if lo < hi:
                        pieces[j].append((lo, hi))
                    n_prev = n
    top = [max((b for _, b in p), default=0.0) for p in pieces]

    def known(j: int, rd: float) -> bool:  # the lattice without sockets could not remove more
        return (lattice_counts is not None and len(options[j][0]) > 0 and rd in lattice_counts
                and lattice_counts[rd] * CAPPED_K * rd**3 <= top[j])

    bare = [j for j, o in enumerate(options) if not len(o[0])]
    for group in (bare, [j for j in range(len(options)) if j not in bare]):
        if not group:
            continue
        for rd, lays in lattice_layouts_many(rod, [options[j] for j in group], lambda i, rd: known(group[i], rd)):
            for j, lay in zip(group, lays):
                if lay is None:
                    continue
                if lattice_counts is not None and not len(options[j][0]):
                    lattice_counts[rd] = lay.count
                if lay.count:
                    pieces[j].append((lay.count * k_min, lay.count * CAPPED_K * rd**3))
    # a hair inside every edge, so that the edges themselves solve
    return [[(a * (1 + 1e-9), b * (1 - 1e-9)) for a, b in _merge(p) if b * (1 - 1e-9) > a * (1 + 1e-9)]
            for p in pieces]


def intervals_key(rod: RodType, seed: int) -> str:
    from rodcad.catalog.model import GEOMETRY_VERSION

    return make_key("fabint", INTERVALS_VERSION, FABRICATE_VERSION, MASSRANGE_VERSION, GEOMETRY_VERSION,
                    POOL_SIZE, RADIUS_FACTOR, MIN_CAVITY_RADIUS, SOLID_TOL, GAP_MERGE,
                    rod.geometry.key_data(), rod.material.key_data(),
                    rod.balls_json(), int(seed))


def compute_table(rod: RodType, seed: int) -> dict[str, Any]:
    """Every ball option with the masses its cavities reach, and the merged
    achievable intervals (numbers only; JSON-serialisable)."""
    info = mass_info(rod)
    rho = rod.material.density / 1000.0
    options = []
    pieces: list[tuple[float, float]] = []
    counts: dict[float, int] = {}
    balls = _ball_options(rod)  # the ball-free rod first
    volumes = removable_volumes_many(rod, [(socks, rs) for _, socks, rs, _ in balls], seed, counts)
    for (mass_k, socks, rs, kind), removable in zip(balls, volumes):
        reach = [(mass_k - b * rho, mass_k - a * rho) for a, b in removable]
        options.append({"mass": mass_k, "sockets": socks.tolist(), "socket_radius": rs, "kind": kind,
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


def interval_table(rod: RodType, seed: int, cache: DiskCache | None = None) -> dict[str, Any]:
    """:func:`compute_table`, from the disk cache when possible."""
    cache = cache if cache is not None else DiskCache()
    key = intervals_key(rod, seed)
    hit = cache.get("fabint", key)
    if isinstance(hit, dict) and "options" in hit and "intervals" in hit:
        return hit
    table = compute_table(rod, seed)
    cache.put("fabint", key, table)
    return table


def row_alternates(rod: RodType, seed: int, cache: DiskCache | None = None, *,
                   table: dict[str, Any] | None = None) -> list[dict[str, Any]]:
    """For the type's ball options in several rows, the options of as many balls of the same
    kind in one row (:func:`rodcad.fabrication.cavities.row_layout`): the same mass without
    cavities, one pause instead of two. Entries as the table's ``options`` (mass, sockets,
    socket_radius, kind, pieces: the masses their cavities reach); disk-cached. Empty for a
    type whose options all stand in one row.

    Args:
        rod: the rod type.
        seed: seed of the cavity layouts (as for :func:`compute_table`).
        cache: disk cache.
        table: the type's table of reachable masses (default :func:`interval_table`); one
            given is not cached.
    """
    if rod.fill is not None or rod.balls is None:
        return []
    cache = cache if cache is not None else DiskCache()
    key = make_key("fabrow", intervals_key(rod, seed))
    hit = cache.get("fabrow", key) if table is None else None
    if isinstance(hit, list):
        return hit
    given = table is not None
    table = table if given else interval_table(rod, seed, cache)
    if not given and isinstance(table.get(ROWS), list):  # found with the table (:func:`chain_intervals`)
        cache.put("fabrow", key, table[ROWS])
        return table[ROWS]
    wanted = {(len(o["sockets"]), int(o["kind"])) for o in table["options"]
              if len(o["sockets"]) and np.ptp(np.asarray(o["sockets"], float).reshape(-1, 3) @ UP) > 1e-6}
    info = mass_info(rod)
    rho = rod.material.density / 1000.0
    ms = info.volume * rho
    com = (info.com[0], info.com[1], 0.0)
    out: list[dict[str, Any]] = []
    for kind, balls_k in enumerate(rod.ball_kinds):
        if not any(k == kind for _, k in wanted):
            continue
        row = row_layout(rod.with_kind(kind))
        if not row.count:
            continue
        rs = row.radius
        net = balls_k.mass - void_volume("silo", rs) * rho
        sites = row.centers - UP * (row.centers[0] @ UP - info.com[1])
        orbs = orbits(sites, com, row.symmetry)
        seen: set[int] = set()
        for mask in _ball_masks(orbs, sites, com):
            idx = np.sort(np.concatenate([orbs[b] for b in range(len(orbs)) if mask >> b & 1]))
            if (len(idx), kind) not in wanted or len(idx) in seen:
                continue
            seen.add(len(idx))
            socks = row.centers[idx]
            out.append({"mass": ms + len(idx) * net, "sockets": socks.tolist(), "socket_radius": rs, "kind": kind})
    volumes = removable_volumes_many(rod, [(o["sockets"], o["socket_radius"]) for o in out], seed)
    for o, removable in zip(out, volumes):
        o["pieces"] = [list(p) for p in sorted((o["mass"] - b * rho, o["mass"] - a * rho) for a, b in removable)]
    if not given:
        cache.put("fabrow", key, out)
    return out


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
    if rod.fill is not None:  # one chamber, its length set per rod: every mass of the range
        return [fill_numbers(rod)[2]]
    return [(float(a), float(b)) for a, b in interval_table(rod, seed, cache)["intervals"]]


def chain_intervals(types: Sequence[RodType], *, seed: int = 0, jobs: int | None = None,
                    cache: DiskCache | None = None) -> dict[str, list[tuple[float, float]]]:
    """:func:`achievable_intervals` of several rod types (name -> intervals),
    the uncached ones computed in ``jobs`` worker processes (default: the CPUs)."""
    from rodcad.catalog.fastgeom import rod_mass_properties

    cache = cache if cache is not None else DiskCache()
    uniq = list({rod.name: rod for rod in types}.values())
    # rods with a fill need no table; the largest first (the longest to compute: the workers end together)
    tabled = sorted((rod for rod in uniq if rod.fill is None), key=lambda rod: -rod_mass_properties(rod.geometry)[0])
    cached_map(_table_star, [(rod, seed) for rod in tabled], [intervals_key(rod, seed) for rod in tabled], kind="fabint",
               cache=cache, jobs=jobs, usable=lambda hit: isinstance(hit, dict), homes=[rod.name for rod in tabled])
    return {rod.name: achievable_intervals(rod, seed=seed, cache=cache) for rod in uniq}


#: The key under which a table computed by :func:`chain_intervals` carries the type's
#: :func:`row_alternates` (found in the same worker, from the same cavity pools; the
#: fabrication asks for them when it shares the sockets' roofs). A table without it (cached
#: before, or from :func:`compute_table`) has them computed when asked.
ROWS = "row_alternates"


def _table_star(args: tuple[RodType, int]) -> dict[str, Any]:
    rod, seed = args
    table = compute_table(rod, seed)
    table[ROWS] = row_alternates(rod, seed, table=table)
    return table
