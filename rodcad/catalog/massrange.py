"""Mass properties and the achievable mass range of a rod type.

A rod's mass is tuned by removing plastic (closed spherical cavities) or by
adding metal (balls in closed sockets, inserted at a print pause). This module
computes, from the rod's exact geometry (:mod:`rodcad.catalog.fastgeom`: the solid's volume,
centre of mass and clearance in closed form, equal to the B-rep's to round-off):

* the plain solid's volume, mass and centre of mass;
* ``m_min``: the solid less the most plastic that equal spherical cavities can
  remove while keeping the catalog's minimum wall from every face (outer faces
  and pin holes) and between cavities;
* ``m_max``: the solid with the most balls it can hold (socket = ball diameter
  + fit clearance, minimum wall around every socket), plus the plastic left.

Layouts are deterministic: sphere centres on a lattice (cubic, or hexagonal
rows in the chain plane) of pitch ``2 r + wall`` centred on the rod's centre of
mass, keeping a site only when all its mirror images fit too (mirror planes through the centre of mass across x, y
and z, or the point reflection through the com axis combined with the z
mirror; whichever keeps more). The removed or added volume is then centred on
the centre of mass, so **the com does not move across the mass range**.

The voids are the printable shapes :mod:`rodcad.cad.rods` cuts (see
:data:`VOIDS`): cavities are spheres capped flat at 45 degrees, sockets are
"silos" (half sphere + cylinder with a bridged roof) standing on one print
layer, raised slightly so socket and ball together keep the com.

The building blocks (:func:`lattice_sites`, :func:`symmetric_subset`,
:func:`sphere_layout`, :func:`max_cavity_layout`, :func:`max_ball_layout`,
:class:`rodcad.cad.collision.Clearance`) are meant to be reused by the fabrication
step that places the real cavities (e.g. Poisson-disk sampling in the same core
with a tuned radius). Units: mm, mm^3, g; densities g/cm^3.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING

from rodcad.catalog.cache import DiskCache, make_key
from rodcad.catalog.chamber import CHAMBER_VERSION, fill_numbers
from rodcad.parallel import cached_map

if TYPE_CHECKING:  # pragma: no cover
    from rodcad.catalog.model import RodType
from rodcad.fabrication.layout import (
    MIN_CAVITY_RADIUS,
    RADIUS_STEP,
    SphereLayout,
    ball_offset,
    max_ball_layout,
    max_cavity_layout,
)

__all__ = ['MASSRANGE_VERSION', 'MassInfo', 'ball_layout', 'cavity_layout', 'layouts', 'compute_mass_info', 'is_cached', 'mass_info', 'mass_infos']


#: Bump when results change (invalidates cached mass ranges).
#: 2: printable void shapes (capped cavities, silo sockets on one print layer).
#: 3: clearance, volume and centre of mass from the end geometry (rodcad.catalog.fastgeom,
#:    exact) instead of kernel queries: the same layouts but for ties at the last digit.
MASSRANGE_VERSION = "3"


@dataclass(frozen=True)
class MassInfo:
    """Mass properties and mass range of a rod type.

    Attributes:
        volume: plastic volume of the plain solid (mm^3).
        solid_mass: mass of the plain solid (g).
        com: centre of mass (along, perp) in the rod frame (mm); the same over
            the whole mass range (layouts are symmetric about it).
        m_min: lightest achievable mass, with the most cavities (g) (with a fill: the
            largest chamber, empty).
        m_max: heaviest achievable mass, with the most balls (g) (with a fill: the largest
            chamber, filled).
        cavity_radius: radius of the cavities at m_min (mm), 0 if none fit.
        cavity_count: number of cavities at m_min.
        ball_count: number of balls at m_max.
        ball_kind: which of the rod's ball kinds (:attr:`RodType.ball_kinds`) gives m_max.
        kind_max: per ball kind, (balls that fit, heaviest mass with them) (g).
    """

    volume: float
    solid_mass: float
    com: tuple[float, float]
    m_min: float
    m_max: float
    cavity_radius: float
    cavity_count: int
    ball_count: int
    ball_kind: int = 0
    kind_max: tuple[tuple[int, float], ...] = ()

    @property
    def mass_range(self) -> tuple[float, float]:
        """Achievable mass [m_min, m_max] (g): cavities to metal balls."""
        return (self.m_min, self.m_max)

    def to_json(self) -> dict[str, object]:
        out = asdict(self)
        if len(self.kind_max) <= 1:  # one ball kind: the format cached before kinds existed
            out.pop("ball_kind")
            out.pop("kind_max")
        return out

    @classmethod
    def from_json(cls, data: dict[str, object]) -> MassInfo:
        data = dict(data)
        data["com"] = tuple(data["com"])  # type: ignore[arg-type]
        data["kind_max"] = tuple((int(n), float(m)) for n, m in data.get("kind_max", ()))  # type: ignore[union-attr]
        return cls(**data)  # type: ignore[arg-type]


def _key(rod: RodType) -> str:
    from rodcad.catalog.model import GEOMETRY_VERSION

    return make_key("mass", MASSRANGE_VERSION, GEOMETRY_VERSION, MIN_CAVITY_RADIUS, RADIUS_STEP,
                    rod.geometry.key_data(), rod.material.key_data(),
                    rod.balls_json(),
                    *(() if rod.fill is None else ("fill", CHAMBER_VERSION, asdict(rod.fill))))


def layouts(rod: RodType) -> tuple[SphereLayout, SphereLayout]:
    """The cavity layout at m_min ('capped' voids) and the ball socket layout
    at m_max ('silo' voids, raised by :func:`ball_offset`) of a rod type (its first ball
    kind; :func:`ball_layout` for another)."""
    return cavity_layout(rod), ball_layout(rod)


def cavity_layout(rod: RodType) -> SphereLayout:
    """The cavity layout at m_min ('capped' voids): the most volume the walls allow."""
    from rodcad.catalog.fastgeom import RodClearance, rod_mass_properties

    _, center = rod_mass_properties(rod.geometry)
    clearance = RodClearance(rod.geometry)
    return max_cavity_layout(clearance, clearance.bounds, center, rod.material.min_wall, void="capped")


def ball_layout(rod: RodType, kind: int = 0) -> SphereLayout:
    """The most sockets of ball kind ``kind`` the rod holds (empty without balls)."""
    from rodcad.catalog.fastgeom import RodClearance, rod_mass_properties

    if not rod.ball_kinds:
        return SphereLayout.empty()
    balls = rod.ball_kinds[kind]
    _, center = rod_mass_properties(rod.geometry)
    clearance = RodClearance(rod.geometry)
    rs = balls.socket_diameter / 2
    lift = ball_offset(rs, balls.mass, rod.material.density)
    return max_ball_layout(clearance, clearance.bounds, center, balls.socket_diameter, rod.material.min_wall,
                           void="silo", raise_by=lift)


def compute_mass_info(rod: RodType) -> MassInfo:
    """Compute :class:`MassInfo` from the B-rep (no cache)."""
    from rodcad.cad.solids import type_solid  # (build123d: imported where a rod type's range is computed)
    from rodcad.catalog.fastgeom import rod_mass_properties

    type_solid(rod)  # the solid must build (a GeometryError names what is wrong)
    volume, center = rod_mass_properties(rod.geometry)
    if rod.fill is not None:  # one chamber, empty to filled (rodcad.catalog.chamber)
        solid, com, (lo, hi) = fill_numbers(rod)
        return MassInfo(float(volume), float(solid), (float(com[0]), float(com[1])), float(lo), float(hi),
                        0.0, 0, 0)
    rho = rod.material.density / 1000.0  # g/mm^3
    solid_mass = volume * rho
    m_max, count, kind = solid_mass, 0, 0
    cavities = cavity_layout(rod)
    kind_max = []
    for k in range(len(rod.ball_kinds)):  # the heaviest over the ball kinds
        balls = ball_layout(rod, k)
        m_k = (volume - balls.volume) * rho + balls.count * rod.ball_kinds[k].mass if balls.count else solid_mass
        kind_max.append((int(balls.count), float(m_k)))
        if balls.count and m_k > m_max:
            m_max, count, kind = m_k, balls.count, k
    m_min = (volume - cavities.volume) * rho
    return MassInfo(float(volume), float(solid_mass), (float(center[0]), float(center[1])), float(m_min),
                    float(m_max), float(cavities.radius), int(cavities.count), int(count), kind, tuple(kind_max))


def is_cached(rod: RodType, cache: DiskCache) -> bool:
    """Whether the mass information of ``rod`` is in the disk cache."""
    return cache.get("mass", _key(rod)) is not None


def mass_info(rod: RodType, *, cache: DiskCache | None = None) -> MassInfo:
    """:class:`MassInfo` of a rod type, from this process's memory or the disk cache when
    possible."""
    key = _key(rod)
    known = _KNOWN.get(key)
    if known is not None:
        return known
    cache = cache if cache is not None else DiskCache()
    hit = cache.get("mass", key)
    info = None
    if hit is not None:
        try:
            info = MassInfo.from_json(hit)
        except (TypeError, KeyError, ValueError):
            pass
    if info is None:
        info = compute_mass_info(rod)
        cache.put("mass", key, info.to_json())
    if len(_KNOWN) >= 4096:
        _KNOWN.clear()
    _KNOWN[key] = info
    return info


#: :func:`mass_info` by its cache key, this process's (the fabrication asks for it often).
_KNOWN: dict[str, MassInfo] = {}


def _compute_star(rod: RodType) -> dict[str, object]:
    return compute_mass_info(rod).to_json()


def mass_infos(rods: Sequence[RodType], *, jobs: int | None = None, cache: DiskCache | None = None,
               progress: Callable[[int, int], None] | None = None) -> dict[str, MassInfo]:
    """:class:`MassInfo` of several rod types (name -> info), computing the
    uncached ones in ``jobs`` processes (default: the number of CPUs)."""
    cache = cache if cache is not None else DiskCache()
    results = cached_map(_compute_star, list(rods), [_key(r) for r in rods], kind="mass", cache=cache, jobs=jobs,
                         progress=progress, usable=_usable)
    return {r.name: MassInfo.from_json(res) for r, res in zip(rods, results)}


def _usable(hit: object) -> bool:
    """A cached mass info in the current format."""
    try:
        MassInfo.from_json(hit)  # type: ignore[arg-type]
    except (TypeError, KeyError, ValueError, AttributeError):
        return False
    return True
