"""Node hardware of a net and its rods, as numbers (no CAD): geometry, masses, free play.

A net's node joins three or more rods, each free to turn in every direction. Two kinds:

* ``hub`` (the default): a printed sphere (``diameter``) with one ball socket per rod. Each
  rod ends in a ball (``ball``, printed with the rod) whose centre is the rod's pivot, at
  ``pivot_radius`` from the hub's centre along the rod's target direction. The socket is a
  sphere ``ball + clearance`` across; it opens outward in a cone of half-angle ``cone_deg``
  with its apex at the ball's centre, narrow enough at the socket's surface to hold the
  ball, wide enough for the rod's ``neck`` to swing. The hub is a rigid body whose pose the
  solver finds (:func:`optimize.solve_net` with pivots), with its own mass and centre of
  mass (:meth:`NodeHardware.hub_mass`).
* ``point``: the rods pivot about one point (a jump ring or a small shackle treated as a
  point), of ``mass`` g.

Rods of a net are round (``rod_diameter``), printed to order: a cylindrical body between a
neck and a ball at each end (hub), or a plain cylinder pivot to pivot (point). Their masses
in closed form (:meth:`NodeHardware.rod_numbers`): solid; the lightest with one coaxial
cavity leaving ``min_wall`` all round; the heaviest with the catalog's steel balls in a row
of closed sockets along the axis. In between, fewer balls and a shorter cavity make any
mass (rodcad's rods lighten and weigh down the same way).

Free play: each socket is ``clearance`` wider than its ball. Under load the ball bears on
the socket on the side the rod pulls it, its centre ``clearance / 2`` from the socket's
centre along that force. rodcad prints each socket's centre that far back from the pivot
against the design's pivot force (:func:`socket_centres`), so the loaded balls sit on the
designed pivots exactly; a rod without load rattles by up to ``clearance / 2``.

Volumes: spheres, cylinders and spherical caps in closed form; the socket's cone inside
the hub sphere (apex off the hub's centre) by a 1D integral over the cone's polar angle
(Gauss-Legendre, 48 points: round-off for this smooth integrand). Units: mm, g, g/cm^3.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from rodcad.catalog.net.splice import Splice, splice_fill, splice_intervals, splice_numbers
from rodcad.catalog.stock import DEFAULT_MODULUS

__all__ = ["DEFAULT_NODE", "NODE_KINDS", "NetRodNumbers", "NodeHardware", "largest_clear_turn", "least_angle_deg",
           "node_hardware", "socket_centres"]

#: Node kinds a catalog's ``node.kind`` may name.
NODE_KINDS = ("hub", "point")

#: What a catalog without a ``node:`` block gets (the shipped pla-parametric's values).
DEFAULT_NODE = {"kind": "hub", "diameter": 24.0, "pivot_radius": 7.5, "ball": 6.0, "clearance": 0.3,
                "cone_deg": 55.0, "neck": 3.0, "rod_diameter": 9.0, "gap": 3.0, "mass": 0.5,
                "name": "printed hub with ball sockets"}

_GL_X, _GL_W = np.polynomial.legendre.leggauss(48)



def least_angle_deg(directions: np.ndarray) -> float:
    """The least angle between two of ``directions`` ((k, 3), any lengths) (deg; 180 for fewer than two)."""
    d = np.asarray(directions, float).reshape(-1, 3)
    if d.shape[0] < 2:
        return 180.0
    d = d / np.linalg.norm(d, axis=1, keepdims=True)
    cos = np.clip(d @ d.T, -1.0, 1.0)
    np.fill_diagonal(cos, -1.0)
    return float(np.degrees(np.arccos(cos.max())))


def largest_clear_turn(clear) -> float:
    """The largest turn ``phi`` in [0, 90] deg with ``clear(phi)`` (radians in; clear at
    every smaller turn, as a face nearing a sphere is), by bisection to 1e-4 rad; 0 when
    not clear at rest."""
    if not clear(0.0):
        return 0.0
    lo, hi = 0.0, math.pi / 2
    if clear(hi):
        return 90.0
    while hi - lo > 1e-4:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if clear(mid) else (lo, mid)
    return math.degrees(lo)

@dataclass(frozen=True)
class NetRodNumbers:
    """One net rod's numbers.

    Attributes:
        length: pivot to pivot (mm).
        body_length: the round body between the two necks (mm).
        solid_mass: the rod printed solid (g).
        mass_range: (lightest with the cavity, heaviest with the steel balls) (g).
        balls: steel balls the heaviest rod holds.
    """

    length: float
    body_length: float
    solid_mass: float
    mass_range: tuple[float, float]
    balls: int


@dataclass(frozen=True)
class NodeHardware:
    """A catalog's node hardware (see the module docstring for the geometry).

    Attributes:
        kind: 'hub' or 'point'.
        name: free text.
        diameter: hub sphere diameter (mm).
        pivot_radius: a rod's ball centre from the hub's centre (mm).
        ball: diameter of the ball each rod ends in (mm).
        clearance: socket diameter minus ball diameter (mm).
        cone_deg: half-angle of each socket's opening cone (deg).
        neck: diameter of the rod's neck between its ball and its body (mm).
        rod_diameter: the net rods' body diameter (mm).
        gap: between the hub's surface and a rod body's end face, along the rod (mm).
        mass: a point node's mass (g).
        density: the printing material's density (g/cm^3).
        min_wall: the thinnest wall printed (mm).
        insert_diameter, insert_density, insert_clearance: the steel balls that weigh rods
            down (mm, g/cm^3, mm); diameter 0 for none.
        pivot_range: the hub family's (smallest, largest) pivot radius (mm), or None.
        cone_range: the (narrowest, widest) socket cone a hub may be printed with (deg), or
            None: every hub's cone ``cone_deg``. A hub whose rods turn further than its sockets
            let them gets a wider cone (:meth:`cone_for_turn`, :meth:`widest_cone`).
        splice: the dowel pins a rod longer than the catalog prints is spliced on
            (:mod:`rodcad.catalog.net.splice`).
        modulus: the rods' Young's modulus (GPa; the material's): :meth:`buckling_load`.
    """

    kind: str
    name: str
    diameter: float
    pivot_radius: float
    ball: float
    clearance: float
    cone_deg: float
    neck: float
    rod_diameter: float
    gap: float
    mass: float
    density: float
    min_wall: float
    insert_diameter: float = 0.0
    insert_density: float = 0.0
    insert_clearance: float = 0.0
    pivot_range: tuple[float, float] | None = None
    cone_range: tuple[float, float] | None = None
    splice: Splice = field(default_factory=Splice)
    modulus: float = DEFAULT_MODULUS

    # ------------------------------------------------------------------ the hub family
    @property
    def family(self) -> bool:
        """Hubs of several sizes (``pivot_range``), else one size."""
        return self.is_hub and self.pivot_range is not None and self.pivot_range[1] > self.pivot_range[0]

    @property
    def shell(self) -> float:
        """The hub's wall outside its pivots, ``radius - pivot_radius`` (mm): every size of the
        family keeps it, so a rod's end (ball, neck, the gap to its body) is the same whatever
        hub it enters and the rods stay symmetric."""
        return self.radius - self.pivot_radius

    @property
    def pivot_limits(self) -> tuple[float, float]:
        """(smallest, largest) pivot radius of the family (mm); the one size twice."""
        return self.pivot_range if self.family else (self.pivot_radius, self.pivot_radius)

    def sized(self, pivot_radius: float) -> "NodeHardware":
        """The family's hub of ``pivot_radius`` (mm; its diameter follows: the same shell)."""
        rp = float(pivot_radius)
        if rp == self.pivot_radius:
            return self
        return replace(self, pivot_radius=rp, diameter=2 * (rp + self.shell))

    def pivot_for_angle(self, angle_deg: float) -> float:
        """The least pivot radius (mm) whose sockets keep ``min_wall`` apart and whose rods'
        bodies clear each other at rods ``angle_deg`` apart (:attr:`min_angle_deg`, inverted
        in closed form); may lie outside the family."""
        if not self.is_hub:
            return 0.0
        half = math.radians(max(angle_deg, 1e-6)) / 2
        sockets = (2 * self.socket_radius + self.min_wall) / (2 * math.sin(half))
        bodies = (self.rod_diameter / 2) / math.tan(half) - self.gap - self.shell
        return max(sockets, bodies, self.pivot_limits[0] if self.family else 0.0)

    # ------------------------------------------------------------------ the cone family
    @property
    def cone_limits(self) -> tuple[float, float]:
        """(narrowest, widest) socket cone of the family (deg); ``cone_deg`` twice for one cone."""
        return self.cone_range if self.is_hub and self.cone_range is not None else (self.cone_deg, self.cone_deg)

    def coned(self, cone_deg: float) -> "NodeHardware":
        """This hub with its sockets' cones ``cone_deg`` wide (half-angle, deg)."""
        c = float(cone_deg)
        return self if c == self.cone_deg else replace(self, cone_deg=c)

    @property
    def neck_angle_deg(self) -> float:
        """The neck's half-width seen from the ball's centre at the socket's rim (deg): a rod turns
        ``cone_deg`` less this before its neck touches the cone."""
        return math.degrees(math.asin(min(1.0, (self.neck / 2) / self.socket_radius)))

    def cone_for_turn(self, turn_deg: float) -> float:
        """The narrowest cone of the family that lets a rod turn ``turn_deg`` from its socket's axis
        (deg; the widest where none does; never narrower than this hub's own)."""
        lo, hi = self.cone_limits
        return float(min(max(self.cone_deg, lo, turn_deg + self.neck_angle_deg), hi))

    def cone_lip_deg(self, cone_deg: float | None = None) -> float:
        """The angle, seen from the hub's centre, between a socket's axis and its lip (where its
        cone of ``cone_deg``, default this hub's, meets the socket sphere and holds the ball)
        and a neighbour's cone at the same distance from the centre, plus ``min_wall`` there
        (deg): two sockets this far apart each keep their lip whole."""
        a = math.radians(self.cone_deg if cone_deg is None else cone_deg)
        rp, rs = self.pivot_radius, self.socket_radius
        lip = math.atan2(rs * math.sin(a), rp + rs * math.cos(a))
        rho = math.hypot(rp + rs * math.cos(a), rs * math.sin(a))
        t = -rp * math.cos(a) + math.sqrt(max(rho ** 2 - (rp * math.sin(a)) ** 2, 0.0))
        reach = math.atan2(t * math.sin(a), rp + t * math.cos(a))
        return math.degrees(lip + reach + self.min_wall / rho)

    def widest_cone(self, directions: np.ndarray) -> float:
        """The widest cone of the family (deg) whose openings, for sockets along ``directions``
        ((k, 3) unit vectors), leave each socket's lip whole (:meth:`cone_lip_deg`); this hub's
        own where even that one does not (the hub is then as it was planned)."""
        lo, hi = self.cone_limits
        own = self.cone_deg
        if hi <= own:
            return own
        room = least_angle_deg(directions)
        if self.cone_lip_deg(hi) <= room:
            return hi
        if self.cone_lip_deg(own) > room:
            return own
        a, b = own, hi  # the lip's angle grows with the cone: bisect to 0.01 deg
        while b - a > 0.01:
            c = 0.5 * (a + b)
            a, b = (c, b) if self.cone_lip_deg(c) <= room else (a, c)
        return a

    # ------------------------------------------------------------------ geometry
    @property
    def is_hub(self) -> bool:
        return self.kind == "hub"

    @property
    def radius(self) -> float:
        """Hub radius (mm)."""
        return self.diameter / 2

    @property
    def pivot(self) -> float:
        """A rod's pivot from the node point (mm): ``pivot_radius`` for a hub, 0 for a point."""
        return self.pivot_radius if self.is_hub else 0.0

    @property
    def socket_radius(self) -> float:
        return (self.ball + self.clearance) / 2

    @property
    def swing_deg(self) -> float:
        """How far a rod turns from its socket's axis, in every direction, before its neck
        touches the cone (deg); 180 for a point node."""
        if not self.is_hub:
            return 180.0
        return min(self.cone_deg - self.neck_angle_deg, self.body_swing_deg)

    @property
    def body_swing_deg(self) -> float:
        """How far a rod turns about its pivot before its body's end face touches the hub
        (deg, to 0.01 deg; 90 at most)."""
        if not self.is_hub:
            return 180.0
        e, r = self.end_offset, self.rod_diameter / 2

        def clear(phi: float) -> bool:
            d = np.array([math.cos(phi), math.sin(phi)])
            n = np.array([-math.sin(phi), math.cos(phi)])
            p = np.array([self.pivot_radius, 0.0]) + e * d
            return bool(min(np.linalg.norm(p + r * n), np.linalg.norm(p - r * n)) >= self.radius)

        return largest_clear_turn(clear)

    @property
    def end_offset(self) -> float:
        """From a rod's pivot to its body's end face (mm): out of the hub plus ``gap``."""
        return (self.radius - self.pivot_radius + self.gap) if self.is_hub else 0.0

    @property
    def min_angle_deg(self) -> float:
        """The least angle between two rods at a node: their sockets keep ``min_wall``
        between them and their bodies do not touch (deg); 0 for a point node."""
        if not self.is_hub:
            return 0.0
        d = self.pivot_radius + self.end_offset
        bodies = 2 * math.atan2(self.rod_diameter / 2, d)
        return max(self.socket_angle_deg, math.degrees(bodies))

    @property
    def socket_angle_deg(self) -> float:
        """The least angle between two sockets' directions from the hub's centre that keeps
        ``min_wall`` between them (deg; 0 for a point node). A socket turned to balance its hub
        (:mod:`rodcad.design.net.spacing`) keeps it too."""
        if not self.is_hub:
            return 0.0
        return math.degrees(2 * math.asin(min(1.0, (2 * self.socket_radius + self.min_wall) / (2 * self.pivot_radius))))

    # ------------------------------------------------------------------ volumes
    def _cone(self) -> tuple[float, float]:
        """(volume, axial centroid from the hub centre) of one socket's opening cone between
        the socket sphere and the hub's surface (mm^3, mm)."""
        R, rp, rs = self.radius, self.pivot_radius, self.socket_radius
        a = math.radians(self.cone_deg)
        beta = 0.5 * a * (_GL_X + 1)
        w = 0.5 * a * _GL_W
        t = -rp * np.cos(beta) + np.sqrt(R**2 - (rp * np.sin(beta)) ** 2)
        t = np.maximum(t, rs)
        vol = 2 * math.pi * float(np.sum(w * (t**3 - rs**3) / 3 * np.sin(beta)))
        mom = 2 * math.pi * float(np.sum(w * (t**4 - rs**4) / 4 * np.cos(beta) * np.sin(beta)))
        return vol, rp + (mom / vol if vol > 0 else 0.0)

    def hub_mass(self, directions: np.ndarray) -> tuple[float, np.ndarray]:
        """A hub's mass and centre of mass for sockets along ``directions``.

        Args:
            directions: (k, 3) unit vectors from the hub's centre to each rod's pivot.

        Returns:
            (mass g, centre of mass (3,) from the hub's centre, same frame); a point node:
            (``mass``, zeros).
        """
        if not self.is_hub:
            return self.mass, np.zeros(3)
        d = np.asarray(directions, float).reshape(-1, 3)
        v_sock = 4 / 3 * math.pi * self.socket_radius**3
        v_cone, c_cone = self._cone()
        v = 4 / 3 * math.pi * self.radius**3 - d.shape[0] * (v_sock + v_cone)
        moment = -(v_sock * self.pivot_radius + v_cone * c_cone) * d.sum(axis=0)
        return self.density * v / 1000.0, moment / v

    @property
    def end_volume(self) -> float:
        """One rod end's plastic outside its body: the ball and the neck to the body's face
        (mm^3; 0 for a point node's plain rod)."""
        if not self.is_hub:
            return 0.0
        rb, s = self.ball / 2, self.neck / 2
        t0 = math.sqrt(max(rb**2 - s**2, 0.0))
        h = rb - t0
        cap = math.pi * h**2 * (3 * rb - h) / 3
        return 4 / 3 * math.pi * rb**3 + math.pi * s**2 * (self.end_offset - t0) - cap

    def zone_balls(self, zone: float) -> int:
        """The steel balls a row of closed sockets takes in a body ``zone`` mm long."""
        r, w = self.rod_diameter / 2, self.min_wall
        ds = self.insert_diameter + self.insert_clearance
        if self.insert_diameter > 0 and 2 * r >= ds + 2 * w and zone > ds + 2 * w:
            return int((zone - w) // (ds + w))
        return 0

    def zone_intervals(self, volume: float, zone: float) -> list[tuple[int, float, float]]:
        """The masses a body of plastic ``volume`` (mm^3) can be built at with its balls and
        cavity in a ``zone`` mm long: per steel-ball count ``k``, (k, lightest g, heaviest g)
        (:meth:`rod_intervals`)."""
        rho = self.density / 1000.0
        ds = self.insert_diameter + self.insert_clearance
        vs = math.pi / 6 * ds ** 3
        mb = self.insert_density * math.pi / 6 * self.insert_diameter ** 3 / 1000.0
        rc, w = self.rod_diameter / 2 - self.min_wall, self.min_wall
        out = []
        for k in range(self.zone_balls(zone) + 1):
            row = k * ds + max(k - 1, 0) * w
            room = 2 * max((zone - row) / 2 - 2 * w, 0.0) if k else max(zone - 2 * w, 0.0)
            hi = rho * (volume - k * vs) + k * mb
            out.append((k, hi - rho * math.pi * max(rc, 0.0) ** 2 * room, hi))
        return out

    def rod_numbers(self, length: float, pieces: int = 1) -> NetRodNumbers:
        """A net rod's masses for a pivot-to-pivot ``length`` (mm); see the module. A rod of
        ``pieces`` > 1 is spliced (:func:`rodcad.catalog.net.splice.splice_numbers`)."""
        if pieces > 1:
            return NetRodNumbers(*splice_numbers(self, length, pieces))
        rho = self.density / 1000.0
        body = length - 2 * self.end_offset if self.is_hub else length
        v = 2 * self.end_volume + math.pi * (self.rod_diameter / 2) ** 2 * max(body, 0.0)
        iv = self.zone_intervals(v, body)
        solid = rho * v
        return NetRodNumbers(float(length), float(body), solid, (iv[0][1], max(solid, iv[-1][2])), iv[-1][0])

    def rod_intervals(self, length: float, pieces: int = 1) -> list[tuple[int, float, float]]:
        """The masses a rod of ``length`` can be built at: per steel-ball count ``k`` (0 up to
        what fits), (k, lightest g, heaviest g). The balls sit in a row at mid-length, the cavity
        (two equal coaxial cylinders beside the row, or one at mid-length without balls,
        ``min_wall`` from everything) takes the plastic off, as :mod:`rodcad.cad.net.solids` builds
        it. A short rod has little room beside its balls: its intervals leave gaps. A spliced
        rod (``pieces`` > 1): :func:`rodcad.catalog.net.splice.splice_intervals`."""
        if pieces > 1:
            return splice_intervals(self, length, pieces)
        rn = self.rod_numbers(length)
        return self.zone_intervals(rn.solid_mass / (self.density / 1000.0), rn.body_length)

    def rod_fill(self, length: float, mass: float, pieces: int = 1) -> tuple[int, float, float]:
        """How a rod of ``length`` is made to weigh ``mass`` (:meth:`rod_intervals`).

        Returns:
            (balls, cavity volume mm^3, the mass it comes to g): the fewest balls whose
            interval holds ``mass``, else the interval that comes nearest; a spliced rod's
            summed over its pieces (:func:`rodcad.catalog.net.splice.splice_fill` for each's).
        """
        if pieces > 1:
            fills, got = splice_fill(self, length, mass, pieces)
            return sum(b for b, _ in fills), sum(c for _, c in fills), got
        rho = self.density / 1000.0
        best = None
        for k, lo, hi in self.rod_intervals(length):
            got = min(max(mass, lo), hi)
            if best is None or abs(got - mass) < best[0] - 1e-12:
                best = (abs(got - mass), k, (hi - got) / rho, got)
        assert best is not None
        return best[1], best[2], best[3]

    def buckling_load(self, length: float) -> float:
        """The force (mN, as the solver's tensions: g x m/s^2) at which a rod of pivot-to-pivot
        ``length`` (mm) pushed along its axis buckles: Euler's pinned-pinned load ``pi^2 E I / L^2``
        of its body's section with the largest cavity it can hold (a tube ``min_wall`` thick, the
        weakest it is printed; a spliced rod's steel pin is stiffer than the plastic round it)."""
        r = self.rod_diameter / 2
        rc = max(r - self.min_wall, 0.0)
        inertia = math.pi / 4 * (r ** 4 - rc ** 4)  # mm^4
        return math.pi ** 2 * self.modulus * 1e3 * inertia / max(float(length), 1e-9) ** 2 * 1e3

    def shortest_rod(self) -> float:
        """The shortest rod the hardware makes (mm): both ends and a body of two walls."""
        return 2 * self.end_offset + 2 * self.min_wall

    # ------------------------------------------------------------------ checks
    def problems(self) -> list[tuple[str, str]]:
        """(key, message) for hardware that cannot be printed or does not hold its rods."""
        out: list[tuple[str, str]] = []
        if not self.is_hub:
            return out
        R, rp, rs, w = self.radius, self.pivot_radius, self.socket_radius, self.min_wall
        if rp + rs + w > R + 1e-9:
            out.append(("pivot_radius", f"a socket ({2 * rs:g} mm across at {rp:g} mm from the centre) leaves less "
                        f"than the {w:g} mm wall inside the {self.diameter:g} mm hub: make the hub larger or the "
                        "pivot radius smaller"))
        if rp - rs < w / 2:
            out.append(("pivot_radius", f"the sockets ({2 * rs:g} mm across) reach the hub's centre: make the "
                        "pivot radius larger"))
        lip = rs * math.sin(math.radians(self.cone_deg))
        if lip > self.ball / 2 - 0.1:
            out.append(("cone_deg", f"the opening is {2 * lip:.3g} mm across where it meets the socket: it would let "
                        f"the {self.ball:g} mm ball out (keep it 0.2 mm narrower: a smaller cone)"))
        if self.neck >= self.ball:
            out.append(("neck", f"the neck ({self.neck:g} mm) must be thinner than the ball ({self.ball:g} mm)"))
        elif self.swing_deg < 5.0:
            out.append(("cone_deg", f"the rods could turn only {self.swing_deg:.3g} deg in their sockets: widen the "
                        "cone or thin the neck"))
        if self.neck < 2 * w:
            out.append(("neck", f"the neck ({self.neck:g} mm) is thinner than two walls ({2 * w:g} mm)"))
        if self.rod_diameter < self.neck:
            out.append(("rod_diameter", f"the rod ({self.rod_diameter:g} mm) is thinner than its neck"))
        return out + self.splice.problems(self.rod_diameter, w)


def socket_centres(pivots: np.ndarray, forces: np.ndarray, clearance: float) -> np.ndarray:
    """Where to print each socket's centre so that the loaded ball sits on its pivot.

    Args:
        pivots: (k, 3) the designed pivots from the node point (hub frame, mm).
        forces: (k, 3) the force each rod exerts on its ball at the design (hub frame).
        clearance: socket diameter minus ball diameter (mm).

    Returns:
        (k, 3) socket centres: each pivot moved ``clearance / 2`` against its force (a
        rod without force keeps its pivot).
    """
    f = np.asarray(forces, float)
    norm = np.linalg.norm(f, axis=1, keepdims=True)
    unit = np.divide(f, norm, out=np.zeros_like(f), where=norm > 0)
    return np.asarray(pivots, float) - 0.5 * clearance * unit


def _size(value) -> tuple[float, float | None, float | None]:
    """A ``diameter``, ``pivot_radius`` or ``cone_deg`` as written: (nominal, min, max); a number is one size."""
    if isinstance(value, dict):
        lo, hi = float(value["min"]), float(value["max"])
        return float(value.get("nominal", lo)), lo, hi
    return float(value), None, None


def node_hardware(block: dict, rod, v) -> NodeHardware | None:
    """A catalog's ``node`` block (schema-checked; unset keys from :data:`DEFAULT_NODE`) as
    hardware in the material of ``rod`` (a :class:`rodcad.catalog.model.RodType`), its
    first ball kind weighing the net rods down; problems reported at ``node.<key>``.

    ``diameter`` and ``pivot_radius`` are each a number (one size) or ``{min, max}`` with an
    optional ``nominal`` (the size a node gets where its rods fit it; default min): a family
    of hubs that keep the nominal hub's wall outside their pivots (:attr:`NodeHardware.shell`),
    between the two ranges. ``cone_deg`` likewise: the sockets' cone, the nominal where the rods'
    turns fit it, wider where they do not (:attr:`NodeHardware.cone_range`)."""
    d = {**DEFAULT_NODE, **block}
    splice = Splice(**{k: float(x) for k, x in (block.get("splice") or {}).items()})
    balls = rod.balls
    dia, dlo, dhi = _size(d["diameter"])
    rp, plo, phi = _size(d["pivot_radius"])
    cone, clo, chi = _size(d["cone_deg"])
    pivot_range = None
    for key, nom, lo, hi in (("diameter", dia, dlo, dhi), ("pivot_radius", rp, plo, phi), ("cone_deg", cone, clo, chi)):
        if lo is not None and not lo <= nom <= hi:
            v.report_at(f"node.{key}", f"expected min <= nominal <= max, got {lo:g}, {nom:g}, {hi:g}",
                        fallback="node")
            return None
    if dlo is not None or plo is not None:
        shell = dia / 2 - rp
        lo = max(plo if plo is not None else rp, (dlo / 2 - shell) if dlo is not None else -math.inf)
        hi = min(phi if phi is not None else rp, (dhi / 2 - shell) if dhi is not None else math.inf)
        if plo is None:  # a diameter range alone: the pivots follow it
            lo, hi = dlo / 2 - shell, dhi / 2 - shell
        if hi < lo - 1e-9:
            v.report_at("node", f"no hub keeps the {shell:g} mm wall outside its pivots within both ranges "
                        "(diameter = 2 (pivot_radius + wall))", fallback="node")
            return None
        pivot_range = (float(lo), float(hi))
    hw = NodeHardware(kind=d["kind"], name=d["name"], diameter=dia,
                      pivot_radius=rp, ball=float(d["ball"]), clearance=float(d["clearance"]),
                      cone_deg=cone, neck=float(d["neck"]), rod_diameter=float(d["rod_diameter"]),
                      gap=float(d["gap"]), mass=float(d["mass"]), density=rod.material.density,
                      min_wall=rod.material.min_wall, insert_diameter=balls.diameter if balls else 0.0,
                      insert_density=balls.density if balls else 0.0,
                      insert_clearance=balls.clearance if balls else 0.0, pivot_range=pivot_range,
                      cone_range=(clo, chi) if clo is not None else None, splice=splice,
                      modulus=float(rod.material.modulus))
    bad = hw.problems()
    if (hw.family or hw.cone_range is not None) and not bad:  # every size and cone must hold its balls too
        for end in hw.pivot_limits:
            for c in sorted(set(hw.cone_limits)):
                for key, message in hw.sized(end).coned(c).problems():
                    what = " and ".join(([f"pivot radius {end:g} mm"] if hw.family else [])
                                        + ([f"cone {c:g} deg"] if hw.cone_range is not None else []))
                    bad.append((key, f"the family's hub of {what}: {message}"))
        bad = list(dict.fromkeys(bad))
    for key, message in bad:
        given = key.split(".")[-1] in (block.get("splice") or {}) if key.startswith("splice.") else key in block
        v.report_at(f"node.{key}" if given else "node", message if given else f"{key}: {message}", fallback="node")
    return None if bad else hw
