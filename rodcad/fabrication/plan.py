"""The fabrication plan of one rod: which balls and which cavities give its designed mass.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from rodcad.fabrication.layout import MIN_CAVITY_RADIUS, void_volume

if TYPE_CHECKING:  # pragma: no cover
    from rodcad.catalog.model import RodType
from rodcad.catalog.massrange import mass_info
from rodcad.fabrication.cavities import (
    CAPPED_K,
    EDGE_TOL,
    SOLID_TOL,
    FabricationError,
    place_cavities,
    raised_rows,
)
from rodcad.fabrication.intervals import compute_table, fmt_mass

__all__ = ["BallChoice", "MIN_REMOVE", "Measurement", "RodPlan", "RoofPlan", "choose_balls", "plan_rod", "socket_tops"]

#: Least cavity volume (mm^3) a rod must keep removing for its sockets' roofs to be raised
#: (the taller sockets take that plastic instead): room for eight of the smallest cavities.
MIN_REMOVE = 8 * CAPPED_K * MIN_CAVITY_RADIUS**3


@dataclass(frozen=True)
class Measurement:
    """What the B-rep of a planned rod measured.

    Attributes:
        volume: plastic volume (mm^3).
        mass: plastic plus metal (g).
        com: centre of mass (along, perp) in the rod frame (mm).
        min_wall: thinnest wall around a void (mm; inf without voids).
        booleans: B-rep booleans the cavity-radius solve took.
    """

    volume: float
    mass: float
    com: tuple[float, float]
    min_wall: float
    booleans: int


@dataclass
class RodPlan:
    """How one rod gets its mass: ball sockets and cavities (numbers only; the disk cache
    keeps :meth:`to_json`).

    Attributes:
        mass: the mass to build (g): the target, clipped to the type's range and moved
            out of a gap between ball counts.
        build_mass: the reachable mass the layout was chosen for (g).
        sockets: (K, 3) ball socket centres in the rod frame (mm).
        socket_radius: socket radius (mm; 0 without balls).
        cavities: (C, 3) cavity centres (mm).
        cavity_radius: cavity radius (mm), root-solved on the B-rep volume once built.
        cavity_bound: largest radius the layout allows (mm).
        layout: how the cavities were laid out ('poisson/mirror-xyz', 'lattice/...', '').
        message: why the built mass differs from the target, or ''.
        measured: the B-rep's measurements, once built.
        ball_kind: which of the rod's ball kinds the sockets hold (:attr:`RodType.ball_kinds`).
        socket_height: the sockets' flat roofs above their centres (mm); 0: the socket
            radius (the plain silo, see :data:`rodcad.fabrication.layout.VOIDS`); a tuple:
            one per socket, where the rows of a rod with several were raised unequally.
    """

    mass: float
    build_mass: float
    sockets: np.ndarray
    socket_radius: float
    cavities: np.ndarray
    cavity_radius: float
    cavity_bound: float
    layout: str
    message: str
    measured: Measurement | None = None
    ball_kind: int = 0
    socket_height: float | tuple[float, ...] = 0.0

    @property
    def socket_tops(self) -> np.ndarray:
        """Per socket, its roof above its centre (mm)."""
        return socket_tops(self.socket_height, self.socket_radius, len(self.sockets))

    def silo_groups(self, cavity_radius: float | None = None) -> list[tuple[Any, ...]]:
        """The voids to cut (:func:`rodcad.cad.solids.with_voids`): the sockets, one group
        per roof height, then the cavities (of ``cavity_radius``, default the plan's)."""
        tops = self.socket_tops
        groups: list[tuple[Any, ...]] = [("silo", self.sockets[tops == h], self.socket_radius, float(h))
                                         for h in sorted(set(tops.tolist()))]
        r = self.cavity_radius if cavity_radius is None else cavity_radius
        return groups + ([("capped", self.cavities, r)] if len(self.cavities) else [])

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "mass": self.mass, "build_mass": self.build_mass, "sockets": self.sockets.tolist(),
            "socket_radius": self.socket_radius, "cavities": self.cavities.tolist(),
            "cavity_radius": self.cavity_radius, "cavity_bound": self.cavity_bound, "layout": self.layout,
            "message": self.message, "ball_kind": self.ball_kind,
        }
        if self.socket_height:
            h = self.socket_height
            out["socket_height"] = list(h) if isinstance(h, tuple) else h
        if self.measured is not None:
            out["measured"] = {**asdict(self.measured), "com": list(self.measured.com)}
        return out

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> RodPlan:
        meas = data.get("measured")
        return cls(
            mass=float(data["mass"]), build_mass=float(data.get("build_mass", data["mass"])),
            sockets=np.array(data["sockets"], dtype=float).reshape(-1, 3),
            socket_radius=float(data["socket_radius"]),
            cavities=np.array(data["cavities"], dtype=float).reshape(-1, 3),
            cavity_radius=float(data["cavity_radius"]), cavity_bound=float(data["cavity_bound"]),
            layout=str(data["layout"]), message=str(data["message"]),
            measured=None if meas is None else Measurement(
                float(meas["volume"]), float(meas["mass"]), (float(meas["com"][0]), float(meas["com"][1])),
                float(meas["min_wall"]), int(meas["booleans"])),
            ball_kind=int(data.get("ball_kind", 0)), socket_height=_height(data.get("socket_height", 0.0)))


def _height(value: Any) -> float | tuple[float, ...]:
    return tuple(float(v) for v in value) if isinstance(value, (list, tuple)) else float(value)


def socket_tops(height: float | Sequence[float], radius: float, count: int) -> np.ndarray:
    """Per socket, its roof above its centre (mm): ``height`` (one for all, or one per
    socket; 0: the plain silo's, the ``radius``)."""
    if isinstance(height, (list, tuple, np.ndarray)) and len(height):
        return np.asarray(height, dtype=float).reshape(count)
    return np.full(count, float(height or radius))


@dataclass(frozen=True)
class RoofPlan:
    """Where a rod's socket roofs go so that the chain pauses seldom
    (:func:`rodcad.fabrication.roofs.shared_roofs`).

    Attributes:
        roofs: per row of sockets, lowest first (:func:`rodcad.fabrication.cavities.socket_rows`),
            its roof (mm along the print's up, rod frame); -inf keeps the row's plain roof.
        sockets: the plain socket centres to use instead of the designed layout's ((K, 3) as
            nested tuples, mm: as many balls of the same kind in one row,
            :func:`rodcad.fabrication.intervals.row_alternates`), or None.
    """

    roofs: tuple[float, ...]
    sockets: tuple[tuple[float, float, float], ...] | None = None

    def key(self) -> tuple[Any, ...]:
        """Hashable, rounded: what the fabrication cache keys on ("rows": raised roofs keep
        the centre of mass off the com's height too, :func:`rodcad.fabrication.layout.tall_silo`'s
        ``give_at``; plans cached before it are not reused)."""
        roofs = tuple(round(float(r), 9) for r in self.roofs)
        if self.sockets is None:
            return ("rows", *roofs)
        return ("rows", *roofs, tuple(tuple(round(float(v), 9) for v in s) for s in self.sockets))


@dataclass(frozen=True)
class BallChoice:
    """The balls a rod gets for its target mass, and what the cavities must remove beside them.

    Attributes:
        mass: the mass to build (g): the target, clipped to the type's range and moved out
            of a gap between ball counts.
        build_mass: the reachable mass the layout is chosen for (g).
        message: why ``mass`` differs from the target, or ''.
        sockets: (K, 3) socket centres of the plain silos (mm, rod frame).
        socket_radius: mm (0 without balls).
        kind: the ball kind (:attr:`RodType.ball_kinds`).
        remove: the cavity volume (mm^3) that makes ``build_mass`` beside the plain silos.
    """

    mass: float
    build_mass: float
    message: str
    sockets: np.ndarray
    socket_radius: float
    kind: int
    remove: float


def choose_balls(rod: RodType, target: float, table: dict[str, Any]) -> BallChoice:
    """The ball subset and the cavity volume for ``target`` g from the type's table of
    reachable masses (:func:`rodcad.fabrication.intervals.compute_table`): the target is
    clipped to the type's range, and one in a gap between ball counts is moved to the
    nearest reachable mass (the message says so)."""
    info = mass_info(rod)
    rho = rod.material.density / 1000.0
    m_lo, m_hi = info.m_min, info.m_max
    message = ""
    m = float(target)
    if m < m_lo * (1 - 1e-12):
        short = (m_lo - m) / rho
        message = (f"target {fmt_mass(target)} g is {fmt_mass(m_lo - m)} g ({(m_lo - m) / m_lo:.1%}) below the lightest "
                   f"printable {rod.name} ({fmt_mass(m_lo)} g with {info.cavity_count} cavities); it would need "
                   f"{short:.0f} mm^3 more cavity volume than the walls allow (a lighter type, a thinner "
                   "minimum wall or a lighter material)")
        m = m_lo
    elif m > m_hi * (1 + 1e-12):
        extra = m - m_hi
        if rod.balls is not None:
            heavy = rod.ball_kinds[info.ball_kind]
            rs = heavy.socket_diameter / 2
            net = heavy.mass - void_volume("silo", rs) * rho
            need = (f"about {math.ceil(extra / net)} more {heavy.diameter:g} mm {heavy.name or 'balls'} than fit "
                    f"({info.ball_count})")
        else:
            need = "metal balls, which this catalog does not give it"
        message = (f"target {fmt_mass(target)} g is {fmt_mass(extra)} g ({extra / m_hi:.1%}) above the heaviest printable "
                   f"{rod.name} ({fmt_mass(m_hi)} g); it would need {need}, denser balls or a larger section")
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
                f"{fmt_mass(m)} g lies in a gap between the ball counts of {rod.name} (balls come in symmetric "
                f"groups and the cavities beside them cannot bridge it); built at {fmt_mass(build)} g with "
                f"{len(options[found[0]]['sockets'])} balls")
            m = build
    i, remove = found
    opt = options[i]
    socks = np.array(opt["sockets"], dtype=float).reshape(-1, 3)
    rs = float(opt["socket_radius"]) if len(socks) else 0.0
    return BallChoice(m, build, message, socks, rs, int(opt.get("kind", 0)), float(remove))


def plan_rod(rod: RodType, target: float, seed: int, table: dict[str, Any] | None = None, *,
             roof: RoofPlan | None = None) -> RodPlan:
    """Sockets, cavities and messages for one rod (numbers only, no B-rep booleans).

    The ball subset and the cavity volume come from the type's table of
    reachable masses (:func:`choose_balls`); one cavity layout search
    follows for the chosen subset.

    Args:
        rod: the rod type.
        target: its mass (g).
        seed: seed of the cavity layouts.
        table: the type's table of reachable masses (computed when None).
        roof: where the sockets' flat roofs should be (:class:`RoofPlan`: one per row, and
            the sockets in one row instead of the designed rows where it names them); None
            for the designed sockets as laid out. The raised sockets
            (:func:`rodcad.fabrication.cavities.raised_rows`) take the plastic above the
            balls that the cavities would otherwise remove, so the mass and the centre of
            mass stay; where the rod's walls or its cavity volume do not allow it, or no
            cavity layout removes what is left, the plain sockets are kept (the designed
            ones where the row's cavities fail too).
    """
    table = table if table is not None else compute_table(rod, seed)
    choice = choose_balls(rod, target, table)
    socks, rs, remove = choice.sockets, choice.socket_radius, choice.remove
    height: float | tuple[float, ...] = 0.0
    cav = None
    if roof is not None and roof.sockets is not None:  # the same balls in one row
        row = np.asarray(roof.sockets, dtype=float).reshape(-1, 3)
        cav = place_cavities(rod, remove, row, rs, seed) if remove > 0 else None
        socks = row if cav is not None or remove <= 0 else socks
        cav = None
    raised = None if roof is None else raised_rows(rod, socks, rs, choice.kind, list(roof.roofs))
    if raised is not None and float(raised[1].max()) > rs + 1e-9:
        left = remove - math.pi * rs * rs * float(np.sum(raised[1] - rs))
        tops = tuple(float(h) for h in raised[1])
        cav = place_cavities(rod, left, raised[0], rs, seed,
                             socket_h=tops[0] if np.ptp(raised[1]) <= 1e-12 else tops) if left >= MIN_REMOVE else None
        if cav is not None:
            socks, remove = raised[0], left
            height = tops[0] if np.ptp(raised[1]) <= 1e-12 else tops
    if cav is None:
        cav = place_cavities(rod, remove, socks, rs, seed) if remove > 0 else None
    if remove > 0 and cav is None:  # pragma: no cover - the table says it fits
        raise FabricationError(f"{rod.name}: no cavity layout removes {remove:.3f} mm^3 beside "
                               f"{len(socks)} balls, although the table of reachable masses says one does")
    return RodPlan(
        mass=choice.mass, build_mass=choice.build_mass, sockets=socks, socket_radius=rs,
        cavities=np.zeros((0, 3)) if cav is None else np.asarray(cav.centers, dtype=float).reshape(-1, 3),
        cavity_radius=0.0 if cav is None else cav.radius, cavity_bound=0.0 if cav is None else cav.bound,
        layout="" if cav is None else cav.layout, message=choice.message, ball_kind=choice.kind,
        socket_height=height)
