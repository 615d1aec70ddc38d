"""Joint limits from the exact rod solids, cached on disk.

For an ordered pair of rod types (left, right) joined at the left rod's second
hinge, the *limits* are the bend interval [lo, hi] (deg) in which the two solids
do not interfere: phi = theta_right - theta_left, positive closing the top (+y)
side of the joint (a sagging chain bends positive). They come from the B-rep:
the right rod's solid is turned about the shared hinge axis
(:class:`rodcad.cad.collision.PairScene`) and the first contact on each side of a
free starting angle is bracketed and refined to :data:`TOLERANCE_DEG`.

The search (:func:`search_limits`) is plain numerics on a distance oracle:

* start from a free angle: straight (0) if the rods can be straight, else the
  middle of the bend range the end shapes were designed for, else a 5 degree
  scan;
* march toward each side with steps that cannot skip a contact: a step never
  moves any point of the right rod by more than the current distance plus two
  of the thinnest walls (conservative advancement), and a Newton step on the
  distance (its rate comes from the closest points) closes in on the contact;
* refine the bracket [last free, first contact] by safeguarded Newton and
  bisection until it is narrower than the tolerance; report its middle.

A side on which nothing collides before +-180 degrees reports None (null in
JSON). Results are stored in the disk cache (:mod:`rodcad.catalog.cache`) under a hash
of both rods' geometry and the code versions, so a second run is instant.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Protocol

from rodcad.catalog.cache import DiskCache, make_key
from rodcad.parallel import cached_map

if TYPE_CHECKING:  # pragma: no cover
    from rodcad.catalog.model import Catalog, RodGeometry, RodType

__all__ = ['LIMITS_VERSION', 'TOLERANCE_DEG', 'MAX_STEP_DEG', 'SCAN_STEP_DEG', 'ProbeLike', 'NoFreeAngle', 'PairLimits', 'search_limits', 'nominal_middle', 'is_cached', 'pair_limits_detail', 'pair_limits', 'all_pair_limits']


#: Bump when the search changes results (invalidates cached limits).
LIMITS_VERSION = "1"


#: Width of the final bracket around each contact angle (deg); the reported
#: limit is its middle, so it is within half of this of the true contact.
TOLERANCE_DEG = 0.005


#: Largest single step of the march (deg).
MAX_STEP_DEG = 10.0


#: Step of the fallback scan for a free starting angle (deg).
SCAN_STEP_DEG = 5.0


class ProbeLike(Protocol):
    phi: float
    distance: float
    rate: float

    @property
    def contact(self) -> bool: ...


class NoFreeAngle(RuntimeError):
    """The two rods interfere at every angle tried: they cannot be joined."""


@dataclass(frozen=True)
class PairLimits:
    """Joint limits of one ordered pair of rod types.

    Attributes:
        left: left rod type's name.
        right: right rod type's name.
        lo: lower bend limit (deg), None if nothing collides down to -180.
        hi: upper bend limit (deg), None if nothing collides up to 180.
        assemblable: False when the rods interfere at every angle (then lo and
            hi are None and the pair cannot be joined).
        evaluations: kernel distance queries used (0 when from the cache).
        seconds: time spent computing (0 when from the cache).
        cached: whether the result came from the disk cache.
    """

    left: str
    right: str
    lo: float | None
    hi: float | None
    assemblable: bool = True
    evaluations: int = 0
    seconds: float = 0.0
    cached: bool = False

    @property
    def limits_deg(self) -> tuple[float | None, float | None]:
        """(lo, hi) in degrees."""
        return (self.lo, self.hi)

    @property
    def limits_rad(self) -> tuple[float, float]:
        """(lo, hi) in radians, with -inf / inf for a free side (simulator form)."""
        lo = -math.inf if self.lo is None else math.radians(self.lo)
        hi = math.inf if self.hi is None else math.radians(self.hi)
        return (lo, hi)


def search_limits(
    probe: Callable[[float], ProbeLike],
    *,
    reach: float,
    wall: float,
    starts: Sequence[float] = (0.0,),
    tol: float = TOLERANCE_DEG,
    bound: float = 180.0,
) -> tuple[float | None, float | None]:
    """Find the contact angles on both sides of a free starting angle.

    Args:
        probe: distance oracle: bend (deg) -> probe with ``distance`` (mm, 0
            at contact), ``rate`` (d distance / d phi in mm per radian,
            negative while approaching) and ``contact``.
        reach: upper bound on the distance of any moving point from the hinge
            axis (mm); makes steps safe.
        wall: thinnest wall of either body (mm). A step moves no point of
            the turning body by more than the current distance plus two walls,
            so neither body can pass through the other unnoticed.
        starts: angles (deg) to try, in order, for the free start; a scan
            every 5 degrees follows.
        tol: width of the final bracket (deg).
        bound: the search stops at +-bound (deg) and reports None there.

    Returns:
        (lo, hi) in degrees, each None when no contact before -bound / +bound.

    Raises:
        NoFreeAngle: no free angle was found.
    """
    start = _free_start(probe, starts, bound)
    hi = _march(probe, start, +1, reach, wall, tol, bound)
    lo = _march(probe, start, -1, reach, wall, tol, bound)
    return lo, hi


def _free_start(probe: Callable[[float], ProbeLike], starts: Sequence[float], bound: float) -> ProbeLike:
    tried: set[float] = set()
    scan = [k * SCAN_STEP_DEG for k in range(1, int(bound / SCAN_STEP_DEG))]
    candidates = list(starts) + [s * x for x in scan for s in (1, -1)]
    for phi in candidates:
        phi = max(-bound + 1e-9, min(bound - 1e-9, phi))
        if round(phi, 9) in tried:
            continue
        tried.add(round(phi, 9))
        p = probe(phi)
        if not p.contact:
            return p
    raise NoFreeAngle(f"the rods interfere at every angle tried ({len(tried)} angles)")


def _march(
    probe: Callable[[float], ProbeLike], start: ProbeLike, s: int, reach: float, wall: float, tol: float, bound: float
) -> float | None:
    """Walk from a free angle in direction s until the first contact."""
    cur = start
    max_step = math.radians(MAX_STEP_DEG)
    while True:
        if s * cur.phi >= bound - 1e-12:
            return None
        d = cur.distance
        cap = min((d + 2 * wall) / reach, max_step)
        approach = -s * cur.rate  # mm per radian of motion, > 0 when closing
        if approach > 0:
            step = min(cap, max(d / approach, d / reach, math.radians(tol) / 2))
        else:
            step = cap
        nxt = cur.phi + s * math.degrees(step)
        nxt = min(nxt, bound) if s > 0 else max(nxt, -bound)
        p = probe(nxt)
        if p.contact:
            return _refine(probe, cur, nxt, s, tol)
        cur = p


def _refine(probe: Callable[[float], ProbeLike], safe: ProbeLike, hit: float, s: int, tol: float) -> float:
    """Shrink [safe, hit] (free, contact) below ``tol`` and return its middle.

    Each round aims a Newton step on the distance a quarter tolerance short of
    the predicted contact and, when that angle is free, pokes half a tolerance
    further: when the prediction is good the bracket closes in two probes;
    otherwise the round falls back to bisection.
    """
    a, b = safe, hit
    while abs(b - a.phi) > tol:
        width = abs(b - a.phi)
        approach = -s * a.rate
        m = None
        if approach > 0:
            aim = a.phi + s * (math.degrees(a.distance / approach) - tol / 4)
            if 0 < s * (aim - a.phi) < width:
                m = aim
        if m is None:
            m = (a.phi + b) / 2
        pm = probe(m)
        if pm.contact:
            b = m
            continue
        a = pm
        poke = m + s * tol / 2
        if s * (b - poke) > 0:
            pp = probe(poke)
            if pp.contact:
                b = poke
            else:
                a = pp
    return (a.phi + b) / 2


def nominal_middle(left: RodGeometry, right: RodGeometry) -> float:
    """The middle of the bend range the end shapes were designed for (deg).

    Flush faces through the axes would meet at the sum of the chamfers; the
    bodies' tangents line up at the sum of the arcs' half angles.
    """
    hi = left.second.top_chamfer + right.first.top_chamfer
    lo = -(left.second.bottom_chamfer + right.first.bottom_chamfer)
    return left.half_angle_deg + right.half_angle_deg + (hi + lo) / 2


def _cache_key(left: RodGeometry, right: RodGeometry, wall: float) -> str:
    from rodcad.catalog.model import GEOMETRY_VERSION

    return make_key("pair-limits", LIMITS_VERSION, GEOMETRY_VERSION, TOLERANCE_DEG,
                    left.key_data(), right.key_data(), wall)


def compute_pair_limits(left: RodGeometry, right: RodGeometry, wall: float) -> dict[str, object]:
    """Run the search on the exact solids (in this process)."""
    from rodcad.cad.collision import PairScene

    t0 = time.perf_counter()
    scene = PairScene(left, right)
    starts = (0.0, nominal_middle(left, right))
    try:
        lo, hi = search_limits(scene.probe, reach=scene.reach, wall=wall, starts=starts)
        ok = True
    except NoFreeAngle:
        lo = hi = None
        ok = False
    return {"lo": lo, "hi": hi, "assemblable": ok, "evaluations": scene.evaluations,
            "seconds": time.perf_counter() - t0}


def _compute_star(args: tuple[RodGeometry, RodGeometry, float]) -> dict[str, object]:
    return compute_pair_limits(*args)


def _wall(left: RodType, right: RodType) -> float:
    return min(left.material.min_wall, right.material.min_wall)


def _from_result(left: str, right: str, r: dict[str, object], cached: bool) -> PairLimits:
    return PairLimits(
        left, right,
        r["lo"],  # type: ignore[arg-type]
        r["hi"],  # type: ignore[arg-type]
        bool(r["assemblable"]),
        0 if cached else int(r["evaluations"]),  # type: ignore[arg-type]
        0.0 if cached else float(r["seconds"]),  # type: ignore[arg-type]
        cached,
    )


def is_cached(left: RodType, right: RodType, cache: DiskCache) -> bool:
    """Whether the limits of (left, right) are in the disk cache."""
    return cache.get("limits", _cache_key(left.geometry, right.geometry, _wall(left, right))) is not None


def pair_limits_detail(
    catalog: Catalog, left: str | RodType, right: str | RodType, *, cache: DiskCache | None = None
) -> PairLimits:
    """Limits of one ordered pair, with how they were obtained.

    Args:
        catalog: the catalog holding both types.
        left: left rod type (or its name).
        right: right rod type (or its name).
        cache: disk cache (default: :class:`rodcad.catalog.cache.DiskCache` at the
            default location).

    Raises:
        KeyError: unknown type name.
        ValueError: the pair cannot be joined (their hinges do not mate).
    """
    a, b = catalog.type(left), catalog.type(right)
    if not catalog.can_join(a, b):
        raise ValueError(f"rod types {a.name!r} and {b.name!r} cannot be joined: their hinges do not mate")
    return all_pair_limits(catalog, pairs=[(a, b)], cache=cache, jobs=1)[(a.name, b.name)]


def pair_limits(
    catalog: Catalog, left: str | RodType, right: str | RodType, *, cache: DiskCache | None = None
) -> tuple[float | None, float | None]:
    """Joint limits (lo_deg, hi_deg) of the joint between ``left`` and ``right``.

    Each side is None when nothing collides up to +-180 degrees.

    Raises:
        KeyError: unknown type name.
        ValueError: the pair cannot be joined, or the rods interfere at every angle.
    """
    r = pair_limits_detail(catalog, left, right, cache=cache)
    if not r.assemblable:
        raise ValueError(f"rod types {r.left!r} and {r.right!r} interfere at every angle")
    return r.limits_deg


def all_pair_limits(
    catalog: Catalog,
    *,
    pairs: Iterable[tuple[RodType, RodType]] | None = None,
    jobs: int | None = None,
    cache: DiskCache | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> dict[tuple[str, str], PairLimits]:
    """Limits of every joinable ordered pair (or of the given pairs).

    Cached pairs are read from disk; the others are computed, in ``jobs``
    worker processes, and stored.

    Args:
        catalog: the catalog.
        pairs: which (left, right) pairs; default :meth:`Catalog.pairs`.
        jobs: worker processes (default: the number of CPUs); 1 computes here.
        cache: disk cache (default location when None).
        progress: called as progress(done, total) while computing.

    Returns:
        (left name, right name) -> :class:`PairLimits`, in pair order.
    """
    cache = cache if cache is not None else DiskCache()
    todo_pairs = list(pairs) if pairs is not None else catalog.pairs()
    args = [(a.geometry, b.geometry, _wall(a, b)) for a, b in todo_pairs]
    keys = [_cache_key(*arg) for arg in args]
    fresh: set[str] = set()
    results = cached_map(_compute_star, args, keys, kind="limits", cache=cache, jobs=jobs, progress=progress,
                         computed=fresh)
    return {(a.name, b.name): _from_result(a.name, b.name, r, key not in fresh)
            for (a, b), key, r in zip(todo_pairs, keys, results)}
