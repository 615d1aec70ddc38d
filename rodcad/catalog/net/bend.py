"""Bent net rods as numbers (no CAD): the arc, the masses and the centre of mass in closed form.

A net rod may be printed bent (``net.bend`` of a design file): its round body follows a
circular arc instead of the straight line between its ends. Everything else stays as on a
straight rod (:mod:`rodcad.catalog.net.node`): the ball at each pivot and the neck along the
rod's chord (the line between its pivots, which is the hub socket's axis at the target), so
the hubs and their sockets do not change.

Geometry, in the rod's frame (origin the first pivot, x toward the second pivot, ``length``
``L`` away; the bow toward -z). The body's centreline is the arc through ``A0 = (e, 0, 0)``
and ``A1 = (L - e, 0, 0)`` (``e`` the end offset: where a straight rod's body starts; 0 for
a point node), its chord ``c = L - 2 e``, bowing ``sagitta = bend x c`` below it at mid-length:
radius ``R = (c^2 / 4 + sagitta^2) / (2 sagitta)``, half-angle ``psi = 2 atan(2 bend)``
(the chain rods' convention, :func:`rodcad.catalog.model.max_curvature`: at most
``MAX_ARC_HALF_ANGLE_DEG``), centre ``(L / 2, 0, R - sagitta)``. The body is the tube of the
rod's radius about that arc, cut square to the arc at ``A0`` and ``A1`` (a torus segment);
each neck runs along x from its ball to the body's tilted end face and on into the body.

Masses. A torus segment's volume is its section times its centreline's length (Pappus), so a
bent rod weighs what a straight rod of *fill length* ``L_f = arc length + 2 e`` weighs, and it
is filled the same way along its arc: its steel balls in a row at mid-arc, its cavity (tubes of
radius ``r - min_wall`` about the arc, cut square to it) beside them
(:meth:`rodcad.catalog.net.node.NodeHardware.rod_fill` of ``L_f``). The straight rod's axial
coordinate ``x`` becomes the arc length ``x - e`` from ``A0``.

Centre of mass. By symmetry at mid-length; below the chord by the first moments of the parts
over the mass (closed form: a tube segment of section radius ``a`` between arc angles
``t0 .. t1`` has ``int rho cos(t) dV = pi a^2 (R^2 + a^2 / 4)(sin t1 - sin t0)``; a neck cut
by the tilted face gains a wedge above and loses one below: ``-tan(psi) pi s^4 / 4``).

Physics. A rod on ball joints turns freely about its chord, so its centre of mass hangs as
low as it can: the bow hangs in the vertical plane through the chord, below it (bowed up is
an unstable equilibrium). The bow's size is chosen; its plane is not.

Walls. The walls are measured along the arc: on the inside of the bend the cavity's end walls
are thinner by the factor ``1 - (r - min_wall) / R`` and the gaps between steel balls by
``O((gap / R)^2)``.

Units: mm, g, rad unless a name says ``_deg``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rodcad.catalog.model import MAX_ARC_HALF_ANGLE_DEG
from rodcad.catalog.net.node import largest_clear_turn

__all__ = ["MAX_BEND", "NetRodArc", "ball_row", "bent_rod_com", "bent_swing_deg", "rod_arc"]

#: The largest bend (sagitta over chord): an arc of 2 x MAX_ARC_HALF_ANGLE_DEG.
MAX_BEND = math.tan(math.radians(MAX_ARC_HALF_ANGLE_DEG) / 2) / 2


@dataclass(frozen=True)
class NetRodArc:
    """A bent net rod's centreline (see the module docstring).

    Attributes:
        length: pivot to pivot, L (mm).
        bend: sagitta over chord of the body's arc.
        offset: from a pivot to the body's end, e (mm).
        chord: the body's chord, L - 2 e (mm).
        sagitta: how far the arc bows below its chord at mid-length (mm).
        radius: the arc's radius R (mm).
        half_angle: psi (rad).
    """

    length: float
    bend: float
    offset: float
    chord: float
    sagitta: float
    radius: float
    half_angle: float

    @property
    def arc_length(self) -> float:
        """The body's centreline length (mm)."""
        return 2 * self.radius * self.half_angle

    @property
    def fill_length(self) -> float:
        """The straight rod's length that weighs the same and is filled the same (mm)."""
        return self.arc_length + 2 * self.offset

    @property
    def centre(self) -> np.ndarray:
        """The arc's centre in the rod frame (mm)."""
        return np.array([self.length / 2, 0.0, self.radius - self.sagitta])

    def angle(self, x) -> np.ndarray:
        """Arc angle (rad, -psi at A0) of straight-rod coordinates ``x`` (mm from the first pivot)."""
        return -self.half_angle + (np.asarray(x, float) - self.offset) / self.radius

    def point(self, x) -> np.ndarray:
        """(..., 3) the arc's points at straight-rod coordinates ``x`` (rod frame, mm)."""
        t = self.angle(x)
        c = self.centre
        return np.stack([c[0] + self.radius * np.sin(t), np.zeros_like(t), c[2] - self.radius * np.cos(t)], axis=-1)

    def tangent(self, x) -> np.ndarray:
        """(..., 3) the arc's unit tangents (toward the second pivot) at ``x``."""
        t = self.angle(x)
        return np.stack([np.cos(t), np.zeros_like(t), np.sin(t)], axis=-1)

    def depth(self, x) -> np.ndarray:
        """How far below the chord the arc is at ``x`` (mm)."""
        return -self.point(x)[..., 2]


def rod_arc(hw, length: float, bend: float) -> NetRodArc | None:
    """The arc of a rod of ``length`` (pivot to pivot, mm) bent by ``bend``; None when straight.

    Raises:
        ValueError: a bend outside [0, MAX_BEND], or a rod with no body to bend.
    """
    if not 0 <= bend <= MAX_BEND * (1 + 1e-12):
        raise ValueError(f"bend must be within [0, {MAX_BEND:.4g}], got {bend!r}")
    if bend == 0:
        return None
    e = hw.end_offset
    c = float(length) - 2 * e
    if c <= 0:
        raise ValueError(f"a rod of {length:g} mm has no body to bend")
    s = bend * c
    R = (c * c / 4 + s * s) / (2 * s)
    return NetRodArc(float(length), float(bend), e, c, s, R, 2 * math.atan(2 * bend))


def _tube(arc: NetRodArc, a: float, t0: float, t1: float) -> tuple[float, float]:
    """(volume, first moment of depth below the chord) of the tube of section radius ``a``
    about the arc between angles t0 and t1, cut square to it (mm^3, mm^4)."""
    area = math.pi * a * a
    vol = area * arc.radius * (t1 - t0)
    mom = area * (arc.radius ** 2 + a * a / 4) * (math.sin(t1) - math.sin(t0)) - (arc.radius - arc.sagitta) * vol
    return vol, mom


def bent_rod_com(hw, arc: NetRodArc, mass: float) -> tuple[np.ndarray, float]:
    """A bent rod's centre of mass for a designed ``mass`` (filled as
    :meth:`rodcad.catalog.net.node.NodeHardware.rod_fill` fills a rod of ``arc.fill_length``).

    Returns:
        ((along, depth, 0) mm: at mid-length, ``depth`` below the chord, the form
        :func:`optimize.solve_net`'s ``com`` takes; the mass it comes to, g).
    """
    L = arc.length
    k, cavity, got = hw.rod_fill(arc.fill_length, mass)
    rho = hw.density / 1000.0
    r, w = hw.rod_diameter / 2, hw.min_wall
    psi = arc.half_angle
    _, m_body = _tube(arc, r, -psi, psi)
    m_plastic = m_body
    if hw.is_hub:  # the necks' wedges at the tilted end faces (balls and necks on the chord)
        m_plastic += 2 * (-math.tan(psi) * math.pi * (hw.neck / 2) ** 4 / 4)
    moment = rho * m_plastic
    ds = hw.insert_diameter + hw.insert_clearance
    vs = math.pi / 6 * ds ** 3
    mb = hw.insert_density * math.pi / 6 * hw.insert_diameter ** 3 / 1000.0
    Lf = arc.fill_length
    xs = ball_row(hw, Lf, k)
    moment += float(np.sum((mb - rho * vs) * arc.depth(xs)))
    area = math.pi * (r - w) ** 2
    if cavity > 1e-3 * area:
        row = k * ds + max(k - 1, 0) * w
        spans = []
        if k:
            each = cavity / 2 / area
            for sgn in (-1.0, 1.0):
                start = Lf / 2 + sgn * (row / 2 + w)
                spans.append((start, start + each) if sgn > 0 else (start - each, start))
        else:
            lc = cavity / area
            spans.append((Lf / 2 - lc / 2, Lf / 2 + lc / 2))
        for x0, x1 in spans:
            moment -= rho * _tube(arc, r - w, float(arc.angle(x0)), float(arc.angle(x1)))[1]
    return np.array([L / 2, moment / got, 0.0]), float(got)


def ball_row(hw, length: float, balls: int) -> np.ndarray:
    """(balls,) the steel balls' straight-rod coordinates (mm from the first pivot): a row at
    mid-length, ``min_wall`` apart (on a bent rod, along its arc: pass its fill length)."""
    ds = hw.insert_diameter + hw.insert_clearance
    row = balls * ds + max(balls - 1, 0) * hw.min_wall
    return np.array([length / 2 - row / 2 + ds / 2 + j * (ds + hw.min_wall) for j in range(balls)], float)


def bent_swing_deg(hw, arc: NetRodArc | None) -> float:
    """How far a rod turns about its pivot, in every direction, before its body's end face
    touches the hub (deg, to 0.01 deg; 90 at most; 0: it touches at rest). A bent rod's end
    face is square to its arc, tilted by ``psi`` from square to the chord: one edge comes
    nearer the hub, whichever way the rod rolls. A straight rod: ``hw.body_swing_deg``."""
    if arc is None or not hw.is_hub:
        return hw.body_swing_deg
    e, r, psi = hw.end_offset, hw.rod_diameter / 2, arc.half_angle

    def clear(phi: float) -> bool:
        # in the plane of the chord and the face's tilt, both ways: phi turns the rod, the face
        # edges at the face centre +- r along the face (tilted psi from square)
        for tilt in (psi, -psi):
            d = np.array([math.cos(phi), math.sin(phi)])
            n = np.array([-math.sin(phi + tilt), math.cos(phi + tilt)])
            p = np.array([hw.pivot_radius, 0.0]) + e * d
            if min(np.linalg.norm(p + r * n), np.linalg.norm(p - r * n)) < hw.radius:
                return False
        return True

    return largest_clear_turn(clear)
