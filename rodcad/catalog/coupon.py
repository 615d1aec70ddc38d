"""The friction coupon as numbers (no CAD): its dimensions for one joint-hardware option of a
catalog, and the statics that turn a reading into the friction coefficient ``mu``.

The coupon (built by :mod:`rodcad.cad.coupon`, ``rodcad calibrate friction``):

* a **stand**: a flat base, a dial plate standing on it (the back prong of a fork) and a
  narrow post in front (the front prong), both with the option's ``fork_hole`` on one
  horizontal pin axis, ``tongue + 2 layer_gap`` apart at the pin like a rod's fork (the
  family's prongs: a pin as long as the rods' hinge is thick fits), printed upright so its
  holes print like the rods' (their hinge axes lie flat too); an angle scale engraved on the
  dial around the pin axis: ticks every 2 degrees, longer every 10, numbered 0 to 90 on
  each side of the top;
* a **wheel**: a flat disc hung on the pin between the prongs (the tongue: the option's
  ``tongue_hole``, a sleeve or bearings pressed in), point-symmetric so it balances about
  its hole, with a pointer at each end of its rider line and open cups for the catalog's
  steel balls: on the rider line at :attr:`CouponGeometry.rider_radii`, and ballast pairs
  off it (every cup has a partner opposite at the same radius: two balls of a pair load the
  pin without a moment). A ball lies in its cup against the cup's lower wall: a shift
  straight down, which moves no moment arm.

Statics. A rider of mass ``m`` at radius ``R`` on the balanced wheel (mass ``M`` with its
hardware, ``B`` of ballast) turned until the rider is ``beta`` from straight below stays
put while ``m g R sin(beta) <= mu W r + T``, ``W = (M + m + B) g`` the pin's load, ``r`` the
pin's radius and ``T`` a load-independent drag. The largest angle that holds gives
``mu = m R sin(beta) / ((M + m + B) r)`` (T = 0); readings at two or more loads separate
``mu`` and ``T`` (:func:`fit_friction`, least squares). ``mu`` is thus the holding moment
over ``W r``: exactly the number rodcad's joint model takes (``PinOption.capacity``); for a
pin bearing on a hole ``r_h`` wide with Coulomb coefficient ``mu_c`` it is
``(r_h / r) sin(atan(mu_c))`` (the friction circle, :func:`coulomb_coefficient`).

Units: mm, g, degrees, N mm (torques); g in m/s^2.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rodcad.catalog.pins import PinOption

__all__ = ["CouponError", "CouponGeometry", "FrictionFit", "G", "Pocket", "Reading", "angle_for",
           "coulomb_coefficient", "coupon_geometry", "default_rider", "digit_polygons", "fit_friction",
           "mu_from_angle", "number_polygons", "pointer_polygon", "tick_polygons"]

#: Standard gravity (m/s^2).
G = 9.81
#: Gap between the wheel's faces and the stand away from the pin (mm): the pin's play lets
#: a 5.6 mm hub on a 0.2 mm clearance tilt 0.036 rad, 1.5 mm at the pointers' tips.
FACE_CLEARANCE = 2.0
#: How far a ball may stand proud of the wheel's front face (mm).
BALL_PROUD = 1.0
#: The pointers reach this far past the disc (mm).
POINTER = 6.0
#: Angle scale: a tick every STEP degrees, numbered every NUMBER_STEP, up to LIMIT on each side.
TICK_STEP = 2
NUMBER_STEP = 10
LIMIT = 90
#: Ticks: (length, width) mm of the plain ticks, every fifth degree and every tenth.
TICKS = ((3.0, 0.6), (4.5, 0.6), (6.0, 0.9))
#: Engraving depth (mm).
ENGRAVE = 0.6
#: 7-segment digits: height, width, stroke, gap between digits (mm).
DIGIT = (5.0, 3.0, 0.7, 1.0)
#: Readable angles (deg): the rider radius chosen puts the option's mid-range reading in here.
READABLE = (10.0, 60.0)
#: The angle a default rider radius aims at (deg).
TARGET_ANGLE = 30.0
#: Angles at which a reading can still be told apart: half a 2 degree tick.
READ_ERROR = 1.0

_SEGMENTS = {"0": "abcdef", "1": "bc", "2": "abged", "3": "abgcd", "4": "fgbc", "5": "afgcd", "6": "afgedc",
             "7": "abc", "8": "abcdefg", "9": "abcdfg"}


class CouponError(ValueError):
    """The option does not fit a coupon of the catalog's numbers (the message says why)."""


@dataclass(frozen=True)
class Pocket:
    """A ball cup in the wheel.

    Attributes:
        radius: from the pin axis (mm).
        angle: from the rider ray (the ray the rider pockets lie on, straight down as drawn),
            counter-clockwise seen from the front (deg).
        rider: on the rider line (a rider goes in one of these).
    """

    radius: float
    angle: float
    rider: bool = False

    @property
    def center(self) -> tuple[float, float]:
        """(x, y) in the wheel as drawn (mm): the rider ray points to -y."""
        a = math.radians(self.angle)
        return (self.radius * math.sin(a), -self.radius * math.cos(a))


@dataclass(frozen=True)
class CouponGeometry:
    """Every dimension of one coupon (mm), in the assembly frame: the pin axis is the z axis
    through the origin, +z toward the front (the post), +y up, the wheel's faces at
    ``z = -+thickness / 2``.

    Attributes:
        catalog: the catalog's name. option: the joint hardware measured.
        tongue, layer_gap, prong, knuckle_radius, radial_gap: the family's hinge.
        min_wall: the material's thinnest wall. density: the material (g/cm^3).
        ball_diameter, ball_mass, cup_diameter: the catalog's balls and their cups.
        thickness: the wheel's (the tongue's, or more where its cups need it).
        floor: under each cup. wheel_radius: the disc's. pointer_tip: the pointers' radius.
        pointer_half: half the pointers' width where they leave the disc.
        rider_radii: the cups on the rider line, inner first.
        pockets: every cup (rider line and ballast, in pairs).
        tick_radius: the scale's inner radius. number_radius: its numbers' centres.
        dial_radius: the dial plate's top. axis_height: the pin above the base's top.
        base: the base's thickness. post_width: the front post's.
    """

    catalog: str
    option: PinOption
    tongue: float
    layer_gap: float
    prong: float
    knuckle_radius: float
    radial_gap: float
    min_wall: float
    density: float
    ball_diameter: float
    ball_mass: float
    cup_diameter: float
    thickness: float
    floor: float
    wheel_radius: float
    pointer_tip: float
    pointer_half: float
    rider_radii: tuple[float, ...]
    pockets: tuple[Pocket, ...]
    tick_radius: float
    number_radius: float
    dial_radius: float
    axis_height: float
    base: float
    post_width: float
    clearance: float = FACE_CLEARANCE

    @property
    def z_back(self) -> float:
        """The wheel's back face (toward the dial; it prints on it)."""
        return -self.thickness / 2

    @property
    def z_front(self) -> float:
        """The wheel's front face (the cups open here)."""
        return self.thickness / 2

    @property
    def dial_face(self) -> float:
        """The dial plate's engraved face (z)."""
        return self.z_back - self.clearance

    @property
    def back_outer(self) -> float:
        """The dial plate's back face (z): the back prong's outer face, no thinner than two
        walls."""
        return min(self.z_back - self.layer_gap - self.prong, self.dial_face - 2 * self.min_wall)

    @property
    def post_face(self) -> float:
        """The front post's inner face (z)."""
        return self.z_front + self.clearance

    @property
    def front_outer(self) -> float:
        """The front post's outer face (z)."""
        return max(self.z_front + self.layer_gap + self.prong, self.post_face + 2 * self.min_wall)

    @property
    def pin_length(self) -> float:
        """A pin through both prongs (mm)."""
        return self.front_outer - self.back_outer

    @property
    def cup_depth(self) -> float:
        return self.thickness - self.floor

    @property
    def hub(self) -> float:
        """The wheel's thickness at its hole (the tongue's, or the wheel's where that is more)."""
        return self.thickness

    @property
    def hardware_mass(self) -> float:
        """The sleeve or bearings pressed into the wheel (g)."""
        return self.option.parts_mass(self.hub)

    @property
    def ballast_pairs(self) -> int:
        """Pairs of cups that take ballast (all but the rider's own pair)."""
        return len(self.pockets) // 2 - 1

    def wheel_volume(self) -> float:
        """The wheel's plastic (mm^3), in closed form: the disc and its two pointers less the
        hole and the cups (equal to the B-rep's to round-off)."""
        r, t = self.wheel_radius, self.thickness
        d = math.asin(self.pointer_half / r)
        # each pointer: the triangle on the chord less the disc's segment under it
        pointer = r * math.sin(d) * (self.pointer_tip - r * math.cos(d)) - r * r * (2 * d - math.sin(2 * d)) / 2
        area = math.pi * r * r - math.pi * (self.option.tongue_hole / 2) ** 2 + 2 * pointer
        return t * area - len(self.pockets) * math.pi * (self.cup_diameter / 2) ** 2 * self.cup_depth

    def wheel_mass(self, volume: float | None = None) -> float:
        """The wheel as it turns (g): its plastic (``volume`` mm^3, default
        :meth:`wheel_volume`) at the material's density and 100 % infill, and its hardware."""
        v = self.wheel_volume() if volume is None else volume
        return v * self.density / 1000.0 + self.hardware_mass


def _ceil(x: float, step: float = 1.0) -> float:
    return step * math.ceil(round(x / step, 9))


def coupon_geometry(catalog, option: PinOption) -> CouponGeometry:
    """The coupon for ``option`` with the numbers of ``catalog`` (its first type's hinge,
    material and balls).

    Raises:
        CouponError: the option's hardware does not fit (its sleeve longer than the wheel's
            hub, its hole through the stand's knuckles).
    """
    rod = catalog.types[0]
    g, hinge, balls, mat = rod.geometry, rod.geometry.hinge, rod.balls, rod.material
    if balls is None:
        raise CouponError(f"catalog {catalog.name!r} has no steel balls for the rider")
    tongue, gap, rk, wall = hinge.tongue_thickness, hinge.layer_gap, hinge.knuckle_radius, mat.min_wall
    prong = max((g.thickness - tongue - 2 * gap) / 2, wall)
    layer = float(catalog.print_settings.get("layer_height", 0.2))
    floor = _ceil(max(0.6, 3 * layer), layer)
    cup = balls.socket_diameter
    ball_r = balls.diameter / 2
    thickness = round(max(tongue, floor + balls.diameter - BALL_PROUD, floor + ball_r + 0.5), 6)
    if option.fork_hole / 2 + wall > rk + 1e-9:
        raise CouponError(f"its {option.fork_hole:g} mm fork hole leaves less than a {wall:g} mm wall in the "
                          f"{2 * rk:g} mm knuckles")
    if option.sleeved and option.sleeve_length(thickness) > thickness + 1e-9:
        raise CouponError(f"its {option.sleeve_length(thickness):g} mm of {option.kind}s are longer than the "
                          f"wheel's {thickness:g} mm hub")
    proud = floor + balls.diameter - thickness  # a ball above the front face
    cap = math.sqrt(max(ball_r ** 2 - (ball_r - proud) ** 2, 0.0)) if proud > 0 else 0.0
    r_min = _ceil(max(rk + hinge.radial_gap + cap, option.tongue_hole / 2 + wall + cup / 2))
    step = _ceil(cup + wall)
    riders = tuple(r_min + k * step for k in range(4))
    wheel_r = _ceil(riders[-1] + cup / 2 + wall + 0.5)
    pockets = [Pocket(r, a, True) for r in riders for a in (0.0, 180.0)]
    for a in (90.0, 45.0, 135.0):
        r = r_min
        while r <= riders[-1] + 1e-9:
            p = Pocket(r, a)
            if all(math.dist(p.center, q.center) >= cup + wall - 1e-9 for q in pockets):
                pockets += [p, Pocket(r, a + 180.0)]
            r += step / 2
    tip = wheel_r + POINTER
    ticks = tip + 1.0
    h, w, _, dgap = DIGIT
    half_diag = math.hypot((2 * w + dgap) / 2, h / 2)
    numbers = _ceil(ticks + TICKS[-1][0] + 1.0 + half_diag, 0.5)
    return CouponGeometry(
        catalog=catalog.name, option=option, tongue=tongue, layer_gap=gap, prong=prong, knuckle_radius=rk,
        radial_gap=hinge.radial_gap, min_wall=wall, density=mat.density, ball_diameter=balls.diameter,
        ball_mass=balls.mass, cup_diameter=cup, thickness=thickness, floor=floor, wheel_radius=wheel_r,
        pointer_tip=tip, pointer_half=4.0, rider_radii=riders, pockets=tuple(pockets), tick_radius=ticks,
        number_radius=numbers, dial_radius=_ceil(numbers + half_diag + 2.0), axis_height=_ceil(tip + 4.0),
        base=4.0, post_width=2 * rk + 4.0)


# --------------------------------------------------------------------------- the scale


def _rotate(points: Sequence[tuple[float, float]], angle_from_top: float, radius: float) -> list[tuple[float, float]]:
    """Points given as (tangential, radial-from-``radius``) around the direction
    ``angle_from_top`` degrees clockwise from +y, as (x, y)."""
    a = math.radians(angle_from_top)
    ur, ut = (math.sin(a), math.cos(a)), (math.cos(a), -math.sin(a))
    return [(ut[0] * s + ur[0] * (radius + t), ut[1] * s + ur[1] * (radius + t)) for s, t in points]


def tick_polygons(geom: CouponGeometry) -> list[list[tuple[float, float]]]:
    """The scale's ticks as xy rectangles on the dial face: one every :data:`TICK_STEP`
    degrees from -LIMIT to +LIMIT of the top."""
    out = []
    for deg in range(-LIMIT, LIMIT + 1, TICK_STEP):
        length, width = TICKS[2 if deg % NUMBER_STEP == 0 else 1 if deg % 5 == 0 else 0]
        half = width / 2
        out.append(_rotate([(-half, 0.0), (half, 0.0), (half, length), (-half, length)], deg, geom.tick_radius))
    return out


def digit_polygons(text: str, center: tuple[float, float]) -> list[list[tuple[float, float]]]:
    """``text`` (digits) as 7-segment strokes, upright, centred on ``center`` (xy
    rectangles, overlapping at the corners)."""
    h, w, s, gap = DIGIT
    x0 = center[0] - (len(text) * w + (len(text) - 1) * gap) / 2
    y0 = center[1] - h / 2
    out = []
    for k, ch in enumerate(text):
        x = x0 + k * (w + gap)
        boxes = {"a": (0, h - s, w, h), "b": (w - s, h / 2 - s / 2, w, h), "c": (w - s, 0, w, h / 2 + s / 2),
                 "d": (0, 0, w, s), "e": (0, 0, s, h / 2 + s / 2), "f": (0, h / 2 - s / 2, s, h),
                 "g": (0, h / 2 - s / 2, w, h / 2 + s / 2)}
        for seg in _SEGMENTS[ch]:
            a, b, c, d = boxes[seg]
            out.append([(x + a, y0 + b), (x + c, y0 + b), (x + c, y0 + d), (x + a, y0 + d)])
    return out


def number_polygons(geom: CouponGeometry) -> list[list[list[tuple[float, float]]]]:
    """The scale's numbers (0 at the top, 10 ... LIMIT on each side), one list of strokes each."""
    out = []
    for deg in range(-LIMIT, LIMIT + 1, NUMBER_STEP):
        a = math.radians(deg)
        c = (geom.number_radius * math.sin(a), geom.number_radius * math.cos(a))
        out.append(digit_polygons(str(abs(deg)), c))
    return out


def pointer_polygon(geom: CouponGeometry, angle: float) -> list[tuple[float, float]]:
    """A pointer on the wheel as drawn, along the ray ``angle`` degrees from the rider ray:
    the triangle on a chord of the disc ``2 pointer_half`` wide, its tip at ``pointer_tip``."""
    r = geom.wheel_radius
    d = math.asin(geom.pointer_half / r)
    pts = []
    for rad, off in ((r, -d), (geom.pointer_tip, 0.0), (r, d)):
        a = math.radians(angle) + off
        pts.append((rad * math.sin(a), -rad * math.cos(a)))
    return pts


# --------------------------------------------------------------------------- statics


def mu_from_angle(angle: float, *, rider_mass: float, rider_radius: float, load_mass: float, pin_radius: float,
                  torque: float = 0.0, g: float = G) -> float:
    """The friction coefficient a reading gives.

    Args:
        angle: the largest angle that holds, the rider from straight below (deg).
        rider_mass: g. rider_radius: mm. load_mass: all the pin carries: wheel, hardware,
            rider and ballast (g). pin_radius: where the pin turns (mm).
        torque: the load-independent drag to take off (N mm).

    >>> round(mu_from_angle(30, rider_mass=1, rider_radius=30, load_mass=30, pin_radius=1.5), 6)
    0.333333
    """
    moment = rider_mass * g * rider_radius * math.sin(math.radians(angle)) / 1000.0
    return (moment - torque) / (load_mass * g * pin_radius / 1000.0)


def angle_for(mu: float, *, rider_mass: float, rider_radius: float, load_mass: float, pin_radius: float,
              torque: float = 0.0, g: float = G) -> float:
    """The largest angle (deg) a rider holds at with friction ``mu`` and drag ``torque``
    (N mm): the inverse of :func:`mu_from_angle`; NaN where it holds at every angle (the
    friction moment beats the rider's at 90 degrees)."""
    s = (mu * load_mass * pin_radius + torque * 1000.0 / g) / (rider_mass * rider_radius)
    return math.degrees(math.asin(s)) if 0 <= s <= 1 else math.nan


def coulomb_coefficient(mu: float, pin_radius: float, hole_radius: float) -> float:
    """The Coulomb coefficient of a pin of ``pin_radius`` bearing on a hole of
    ``hole_radius`` (a line contact) that holds the moment ``mu W pin_radius``: the friction
    circle, ``mu r = r_h sin(atan(mu_c))``. NaN where none does."""
    s = mu * pin_radius / hole_radius
    return math.tan(math.asin(s)) if 0 <= s < 1 else math.nan


def default_rider(geom: CouponGeometry, wheel_mass: float | None = None) -> tuple[float, float]:
    """(rider radius, angle) for the option's mid-range friction and drag: the cup on the
    rider line whose reading comes closest to :data:`TARGET_ANGLE` among those within
    :data:`READABLE`, else the one closest to that range (the innermost for bearings: they
    hold a few degrees)."""
    o = geom.option
    mu, torque = sum(o.friction) / 2, sum(o.torque) / 2
    load = (geom.wheel_mass() if wheel_mass is None else wheel_mass) + geom.ball_mass

    def angle(r: float) -> float:
        a = angle_for(mu, rider_mass=geom.ball_mass, rider_radius=r, load_mass=load, pin_radius=o.radius,
                      torque=torque)
        return 90.0 if math.isnan(a) else a

    def miss(r: float) -> tuple[float, float]:
        a = angle(r)
        outside = max(READABLE[0] - a, a - READABLE[1], 0.0)
        return (outside, abs(a - TARGET_ANGLE))

    best = min(geom.rider_radii, key=miss)
    return best, angle(best)


@dataclass(frozen=True)
class Reading:
    """One reading.

    Attributes:
        angle: the largest angle that held, the rider from straight below (deg).
        rider_radius: mm. rider_mass: g. load_mass: all the pin carries (g).
    """

    angle: float
    rider_radius: float
    rider_mass: float
    load_mass: float

    def moment(self, g: float = G) -> float:
        """The rider's moment at the angle (N mm)."""
        return self.rider_mass * g * self.rider_radius * math.sin(math.radians(self.angle)) / 1000.0


@dataclass(frozen=True)
class FrictionFit:
    """Friction from readings.

    Attributes:
        mu: the friction coefficient (the least-squares fit).
        torque: the load-independent drag (N mm): fitted where the readings span two loads
            or more (``separated``), else 0.
        separated: the readings span two loads, so mu and the drag are told apart.
        per_reading: each reading's mu (its drag taken off).
        errors: each reading's mu error for :data:`READ_ERROR` degrees of reading error.
        rms: root-mean-square moment residual (N mm).
        message: what was fitted, in words.
    """

    mu: float
    torque: float
    separated: bool
    per_reading: tuple[float, ...]
    errors: tuple[float, ...]
    rms: float
    message: str

    @property
    def friction(self) -> tuple[float, float]:
        """(lo, hi) over the readings."""
        return (min(self.per_reading), max(self.per_reading))


def fit_friction(readings: Sequence[Reading], pin_radius: float, *, g: float = G) -> FrictionFit:
    """Fit ``m g R sin(beta) = mu W r + T`` to readings (least squares in the moments).

    With every reading at one load, ``T`` cannot be told from ``mu W r``: it is taken as 0
    and ``mu`` is the readings' mean. A fitted ``T`` below 0 (noise) is taken as 0 too.

    >>> rs = [Reading(angle_for(0.2, rider_mass=1, rider_radius=20, load_mass=w, pin_radius=1, torque=0.01),
    ...               20, 1, w) for w in (20, 40)]
    >>> f = fit_friction(rs, 1.0); round(f.mu, 9), round(f.torque, 9)
    (0.2, 0.01)
    """
    if not readings:
        raise ValueError("no readings")
    b = np.array([r.moment(g) for r in readings])
    wr = np.array([r.load_mass * g * pin_radius / 1000.0 for r in readings])
    separated = float(np.ptp(wr)) > 1e-6 * float(wr.max())
    torque = 0.0
    if separated:
        (mu, torque), *_ = np.linalg.lstsq(np.column_stack([wr, np.ones_like(wr)]), b, rcond=None)
        if torque < 0:
            message = (f"the fitted drag ({torque:.2g} N mm) is below 0, within the readings' noise: taken as 0")
            torque = 0.0
        else:
            message = f"mu and the drag fitted to {len(readings)} readings at {len(set(np.round(wr, 9)))} loads"
            if len(readings) == 2:
                message += " (two readings fit exactly: repeat them for a spread)"
    else:
        message = f"{len(readings)} reading{'s' if len(readings) != 1 else ''} at one load: no drag told apart"
    per = (b - torque) / wr
    if not separated or torque == 0.0:
        mu = float(np.sum(wr * b) / np.sum(wr * wr))
    errors = [r.rider_mass * g * r.rider_radius * math.cos(math.radians(r.angle)) / 1000.0
              * math.radians(READ_ERROR) / w for r, w in zip(readings, wr)]
    rms = float(np.sqrt(np.mean((wr * mu + torque - b) ** 2)))
    return FrictionFit(float(mu), float(torque), separated, tuple(float(x) for x in per),
                       tuple(float(e) for e in errors), rms, message)
