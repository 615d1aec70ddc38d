"""The anchor fixture: one printed part holding both anchor pins of a chain, with a stop
for each end rod the design lets it hold, and a hanging hole or two screw holes.

The fixture lives in the chain's frame (mm): chain plane xy, y up, hinge axes along z,
the rods between z = -thickness/2 and +thickness/2. It is a plate of thickness
``2 T`` (``T = thickness/2 + layer_gap + cheek``, the width of a fork lug of
:class:`rodcad.design.frame.LugSpec`) whose outline is the rounded convex hull of the
anchors, the stops and the mount holes:

* the outer layers ``|z| > thickness/2 + layer_gap`` (the *cheeks*, front and back) are
  whole: no rod reaches them;
* in the rods' layer, ``|z| <= thickness/2 + layer_gap``, a *slot* is cut at each anchor:
  the wedge from the anchor that the end rod's body sweeps while it turns away from its
  stop by up to ``swing_deg`` (both ways at a bare pin), a few degrees wider, outside the
  knuckle; so the rod clears the body at rest and when it lifts off its stop;
* around each anchor, the layers the rod's knuckle uses are cleared out to the rod's
  hinge-zone radius, and the fixture keeps the other knuckle (made by
  :func:`rodcad.cad.frame.lug_parts`): at A (the first rod has a tongue there) a fork of
  two prongs outside the tongue, at B (the last rod has a fork there) a tongue in the
  middle layer; a pin hole of the rod's ``hole_diameter`` through the whole plate;
* a *stop* per finite angle bound: a round peg of ``stop_radius`` through the whole
  plate (it bridges the cheeks across the slot), touching the end rod's side face
  ``stop_gap`` away when the rod's angle is at the bound, on the side the rod would turn
  past it;
* a mount: ``'hole'`` (default), one hanging hole for a nail or hook ``hang_height``
  above the anchors' midpoint; or ``'screws'``, two screw holes ``hang_height`` above
  the anchors, for screwing the back face to a wall.

Printing: lying on its back face (z = -T on the bed), the front cheek spans the slots
and needs support there (the slots are open to the outline, so the support comes out).
The pins are separate parts, ``2 T`` long (:func:`fixture_width`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from build123d import Solid

from rodcad.cad.collision import DistanceTo
from rodcad.cad.export import placed, rod_matrices, rod_matrix
from rodcad.cad.frame import bar_parts, lug_parts, one_part
from rodcad.cad.solids import (
    CONTACT_TOL,
    GeometryError,
    cylinder_solid,
    is_valid_solid,
    prism_solid,
    type_solid,
)
from rodcad.catalog.model import RodType
from rodcad.design.frame import LugSpec

__all__ = ['FixtureStop', 'check_fixture', 'end_rod_matrix', 'fixture_solid', 'fixture_stops', 'fixture_width', 'placed_rods']

#: A stopped rod at rest is in contact when the fixture is at most this far (mm).
CONTACT = 0.05
#: Overlap volumes at or below this count as none (mm^3).
OVERLAP_TOL = 1e-3


@dataclass(frozen=True)
class FixtureStop:
    """One stop of the fixture, in numbers (chain plane, mm).

    Attributes:
        anchor: 0 at A (the first rod), 1 at B (the last rod).
        bound: 'hi' (the rod cannot turn counter-clockwise past ``angle``) or 'lo'
            (not clockwise).
        angle: the bound on the rod's chord angle (rad).
        center: the peg's axis (x, y).
        radius: the peg's radius.
        contact: the point on the rod's face the peg touches (x, y).
    """

    anchor: int
    bound: str
    angle: float
    center: tuple[float, float]
    radius: float
    contact: tuple[float, float]


def _rod_origin(anchors: np.ndarray, k: int, rod: RodType, theta: float) -> np.ndarray:
    """The rod frame's origin (its first joint) when the rod at anchor k has chord angle theta."""
    if k == 0:
        return anchors[0]
    return anchors[1] - rod.length * np.array([math.cos(theta), math.sin(theta)])


def end_rod_matrix(anchors: Any, k: int, rod: RodType, theta: float) -> np.ndarray:
    """Rod frame -> chain plane of the first (k = 0, at A) or last (k = 1, at B) rod at
    chord angle ``theta`` (rad)."""
    a = np.asarray(anchors, dtype=float)
    return rod_matrix(_rod_origin(a, k, rod, theta), theta)


def _face(rod: RodType, joint: int, dist: float, side: int) -> tuple[np.ndarray, np.ndarray]:
    """Centreline point ``dist`` (arc length) from the joint and the unit normal toward
    ``side`` (+1: the rod frame's +y face), in the rod frame."""
    g = rod.geometry
    k = g.curvature
    psi = math.radians(g.half_angle_deg)
    total = g.length if k == 0 else 2 * psi / k
    s = dist if joint == 0 else total - dist
    phi = -psi + k * s
    if k == 0:
        c = np.array([s, 0.0])
    else:
        c = np.array([(math.sin(phi) + math.sin(psi)) / k, (math.cos(psi) - math.cos(phi)) / k])
    return c, side * np.array([-math.sin(phi), math.cos(phi)])


def _limits(end_limits: Any) -> np.ndarray:
    if end_limits is None:
        return np.array([[-math.inf, math.inf]] * 2)
    lim = np.asarray(end_limits, dtype=float)
    if lim.shape != (2, 2):
        raise GeometryError(f"end_limits must be a (2, 2) array [lo, hi] per anchor, not shape {lim.shape}")
    for k in (0, 1):
        if np.isnan(lim[k]).any() or lim[k, 0] > lim[k, 1]:
            raise GeometryError(f"end_limits at anchor {'AB'[k]}: lo {lim[k, 0]} must be <= hi {lim[k, 1]}")
    return lim


def fixture_stops(anchors: Any, first_rod: RodType, last_rod: RodType, end_limits: Any, *,
                  stop_radius: float = 3.0, stop_gap: float = 0.01) -> list[FixtureStop]:
    """The stop pegs for every finite bound in ``end_limits`` (see :func:`fixture_solid`).

    A peg touches the rod's side face (the one leading when the rod turns past the bound:
    at A the rod frame's +y face for 'hi'; at B its -y face for 'hi'), exactly
    ``stop_gap`` away at the bound, at an arc length from the anchor just past the end
    face's chamfer: placed from the section (exact for straight and arc-shaped bodies of the
    family's section), then moved along the face's normal to ``stop_gap`` from the rod's solid
    (a graduated body's face is not always where its section puts it).
    """
    a = np.asarray(anchors, dtype=float)
    lim = _limits(end_limits)
    out = []
    for k, rod in ((0, first_rod), (1, last_rod)):
        g = rod.geometry
        for bound, theta in (("lo", lim[k, 0]), ("hi", lim[k, 1])):
            if not math.isfinite(theta):
                continue
            side = (1 if bound == "hi" else -1) * (1 if k == 0 else -1)
            end = g.first if k == 0 else g.second
            chamfer = end.top_chamfer if side > 0 else end.bottom_chamfer
            # the side face's offset from the centreline: a graduated body's top is its own
            face = g.body_top if side > 0 and g.graduated else g.height / 2
            # past the end face (its chamfer rises to the face's height; a lower body steps
            # down behind the end blocks' reach)
            dist = end.setback + max(face, g.height / 2) * max(math.tan(math.radians(chamfer)), 0.0) + stop_radius + 1
            if face < g.height / 2:
                dist = max(dist, float(g.end_reach[k]) + stop_radius + 1.0)
            if dist > 0.8 * g.length:
                raise GeometryError(f"rod {rod.name!r} is too short for a stop beside its end face")
            c, n = _face(rod, k, dist, side)
            m = end_rod_matrix(a, k, rod, float(theta))
            center = m[:2, :2] @ (c + n * (face + stop_gap + stop_radius)) + m[:2, 3]
            touch = m[:2, :2] @ (c + n * face) + m[:2, 3]
            # measured on the solid: where the body's face is not where the section says (a
            # curved graduated body rising to its end faces), the peg moves along the normal
            # until it is stop_gap from the rod at its bound
            body = placed(type_solid(rod), m)
            normal = m[:2, :2] @ n
            for _ in range(3):
                gap = DistanceTo(cylinder_solid(tuple(center), stop_radius, -g.thickness, g.thickness))(body)
                if gap <= 1e-9 or abs(gap - stop_gap) <= 1e-6:
                    break
                center = center - normal * (gap - stop_gap)
                touch = touch - normal * (gap - stop_gap)
            out.append(FixtureStop(k, bound, float(theta), (float(center[0]), float(center[1])),
                                   float(stop_radius), (float(touch[0]), float(touch[1]))))
    return out


def fixture_width(first_rod: RodType, last_rod: RodType) -> float:
    """The fixture's thickness along the pins (mm): the length of each anchor pin."""
    return 2 * max(_half_width(r) for r in (first_rod, last_rod))


#: How far past an end rod's own reach its slot is cut where a slot out past the whole
#: fixture would cut the rods' layer through (mm).
SLOT_MARGIN = 3.0

def _half_width(rod: RodType) -> float:
    g = rod.geometry
    h = g.hinge
    cheek = (g.thickness - h.tongue_thickness) / 2 - h.layer_gap
    if cheek <= 0:
        raise GeometryError(f"rod {rod.name!r}: the hinge leaves no room for fork prongs")
    return g.max_thickness / 2 + h.layer_gap + cheek  # a graduated body may be thicker than its ends


def _extent(rod: RodType, joint: int) -> tuple[float, float, float]:
    """The directions (rad) the rod's body takes from its joint's axis outside the knuckle,
    relative to the chord pointing into the rod, and its reach: (min, max, farthest mm)."""
    verts, _ = type_solid(rod).tessellate(0.02, 0.05)
    pts = np.array([[v.X, v.Y] for v in verts])
    rel = pts - (np.array([0.0, 0.0]) if joint == 0 else np.array([rod.length, 0.0]))
    r = np.hypot(rel[:, 0], rel[:, 1])
    rel = rel[r > rod.geometry.hinge.knuckle_radius + 1e-6]
    ang = np.arctan2(rel[:, 1], rel[:, 0]) - (0.0 if joint == 0 else math.pi)
    ang = (ang + math.pi) % (2 * math.pi) - math.pi
    return float(ang.min()), float(ang.max()), float(r.max())


def _sweep(lim: np.ndarray, k: int, rest: float | None, swing: float) -> tuple[float, float]:
    """The range of chord angles (rad) the fixture keeps clear for the rod at anchor k."""
    lo, hi = lim[k]
    if rest is None:
        rest = hi if math.isfinite(hi) else lo if math.isfinite(lo) else (-math.pi / 2 if k == 0 else math.pi / 2)
    return max(lo, rest - swing), min(hi, rest + swing)


def _hull(points: np.ndarray) -> np.ndarray:
    """Convex hull of 2D points, counter-clockwise (monotone chain); 1 or 2 points if degenerate."""
    pts = sorted({(round(float(x), 9), round(float(y), 9)) for x, y in points})
    if len(pts) <= 2:
        return np.array(pts)

    def cross(o: tuple, a: tuple, b: tuple) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower: list = []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 1e-9:
            lower.pop()
        lower.append(p)
    upper: list = []
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 1e-9:
            upper.pop()
        upper.append(p)
    return np.array(lower[:-1] + upper[:-1])


def _wedge(apex: np.ndarray, a0: float, a1: float, reach: float, inner: float, z0: float, z1: float) -> Solid:
    """The sector from ``apex`` between directions a0 < a1 (rad) out past ``reach``, without
    the disc of radius ``inner`` around the apex."""
    n = max(2, math.ceil((a1 - a0) / math.radians(20)))
    far = reach / math.cos((a1 - a0) / n / 2)
    ring = [apex + far * np.array([math.cos(a), math.sin(a)]) for a in np.linspace(a0, a1, n + 1)]
    sector = prism_solid([apex, *ring], z0, z1)
    return one_part(sector.cut(cylinder_solid(apex, inner, z0 - 1, z1 + 1)), "shaping a rod's slot", "fixture")


def _lug(name: str, anchor: np.ndarray, rod: RodType, joint: int, toward: np.ndarray) -> LugSpec:
    """The fixture's knuckle at an anchor as a lug, its arm straight toward ``toward``."""
    g = rod.geometry
    loc = np.eye(4)
    loc[:2, 3] = anchor
    d = toward - anchor
    elbow = float(np.hypot(*d))
    s = 1.0 if d[1] > 0 else -1.0
    tilt = math.degrees(math.atan2(d[0], s * d[1])) if elbow > 0 else 0.0
    knuckle = "fork" if g.hinge.knuckle(joint) == "tongue" else "tongue"
    return LugSpec(name, loc, knuckle, g.thickness, g.hinge, s * elbow * math.cos(math.radians(tilt)),
                   tilt, elbow)


def fixture_solid(anchors: Any, first_rod: RodType, last_rod: RodType, end_limits: Any, *,
                  rest_angles: Sequence[float] | None = None, swing_deg: float = 30.0,
                  stop_radius: float = 3.0, stop_gap: float = 0.01, rim: float = 2.5,
                  mount: str = "hole", hang_diameter: float = 5.0, screw_diameter: float = 3.5,
                  hang_height: float | None = None, min_wall: float = 1.0, pin_holes: Any = None,
                  hole_diameters: Sequence[float] | None = None) -> Solid:
    """The anchor fixture of a chain: one printed solid holding both anchor pins (see the
    module docstring for its shape).

    Args:
        anchors: (2, 2) A and B in the chain plane (mm).
        first_rod: the first rod's type (its first joint is at A).
        last_rod: the last rod's type (its second joint is at B).
        end_limits: (2, 2) [lo, hi] bounds (rad) on the chord angles of the first and the
            last rod (``-inf``/``inf``: none), or None for two bare pins. A rod with a
            finite bound gets a stop; at rest it sits on it.
        rest_angles: chord angles (rad) of the first and last rod at rest; default: the
            finite bound (``hi`` if both are finite), at a bare pin the rod hanging straight
            down.
        swing_deg: how far the end rods may turn away from rest (or from their stop)
            without touching the fixture (deg).
        pin_holes: (2, 2) the anchor pins' holes' centres minus A and B (mm), or None (on
            them): the pin-play compensation puts them where the loaded pins sit on A and B.
        hole_diameters: (2,) the anchor pins' holes (mm; the joint hardware's), or None: the
            end rods' own.
        stop_radius: radius of the stop pegs (mm).
        stop_gap: the gap between a stop and the rod resting on it (mm).
        rim: material around the knuckles, stops and mount holes (mm).
        mount: 'hole' (one hanging hole above the anchors' midpoint) or 'screws' (one
            screw hole above each anchor).
        hang_diameter: the hanging hole's diameter (mm).
        screw_diameter: the screw holes' diameter (mm).
        hang_height: height of the mount holes above the anchors' midpoint (mm); default
            the knuckle's hinge-zone radius plus the outline's radius.
        min_wall: least material between the two knuckles (mm).

    Returns:
        A valid build123d Solid labelled 'fixture'.

    Raises:
        GeometryError: bad input (anchors too close for both knuckles, a rod sweeping over
            the other anchor's knuckle, bad ``end_limits``) or a boolean step that leaves no
            single valid solid.
    """
    a = np.asarray(anchors, dtype=float)
    if a.shape != (2, 2):
        raise GeometryError(f"anchors must be (2, 2): A and B in the chain plane, not shape {a.shape}")
    lim = _limits(end_limits)
    rods = (first_rod, last_rod)
    hinges = [r.geometry.hinge for r in rods]
    half = max(_half_width(r) for r in rods)
    dist = float(np.hypot(*(a[1] - a[0])))
    need = max(hinges[0].zone_radius + hinges[1].knuckle_radius,
               hinges[1].zone_radius + hinges[0].knuckle_radius) + min_wall
    if dist < need:
        raise GeometryError(f"the anchors are {dist:.1f} mm apart: the fixture's two knuckles need at "
                            f"least {need:.1f} mm between the pins")
    if mount not in ("hole", "screws"):
        raise GeometryError(f"mount must be 'hole' or 'screws', not {mount!r}")
    stops = fixture_stops(a, first_rod, last_rod, lim, stop_radius=stop_radius, stop_gap=stop_gap)
    hole_d = hang_diameter if mount == "hole" else screw_diameter
    # the outline's radius around every centre
    radius = max(*(h.knuckle_radius for h in hinges), stop_radius if stops else 0.0, hole_d / 2) + rim
    if hang_height is None:
        hang_height = max(h.zone_radius for h in hinges) + radius
    up = np.array([0.0, hang_height])
    mid = a.mean(axis=0)
    mounts = [mid + up] if mount == "hole" else [a[0] + up, a[1] + up]

    # the slots the end rods sweep, and a check that neither sweeps the other knuckle
    swing = math.radians(swing_deg)
    slots = []
    for k, rod in enumerate(rods):
        rest = None if rest_angles is None else float(rest_angles[k])
        t0, t1 = _sweep(lim, k, rest, swing)
        e0, e1, far = _extent(rod, k)
        margin = math.radians(3.0)
        base = 0.0 if k == 0 else math.pi
        w0, w1 = t0 + base + e0 - margin, t1 + base + e1 + margin
        if w1 - w0 > math.radians(350):
            raise GeometryError(f"the {'first' if k == 0 else 'last'} rod sweeps all around anchor "
                                f"{'AB'[k]}: give it a rest angle or a smaller swing")
        other = a[1 - k] - a[k]
        beta = math.atan2(other[1], other[0])
        spread = math.asin(min(1.0, (hinges[1 - k].zone_radius + min_wall) / dist))
        off = (beta - (w0 + w1) / 2 + math.pi) % (2 * math.pi) - math.pi
        if abs(off) < (w1 - w0) / 2 + spread and dist < far + hinges[1 - k].zone_radius + min_wall:
            raise GeometryError(f"the {'first' if k == 0 else 'last'} rod, turning between "
                                f"{math.degrees(t0):.1f} and {math.degrees(t1):.1f} deg, would sweep over "
                                f"anchor {'BA'[k]}'s knuckle")
        slots.append((w0, w1, far))

    # the outline: rounded hull of the anchors, the stops and the mounts
    centres = np.array([a[0], a[1], *[s.center for s in stops], *mounts])
    hull = _hull(centres)
    z0, z1 = -half, half
    if len(hull) >= 3:
        parts = bar_parts(np.vstack([hull, hull[:1]]), radius, z0, z1) + [prism_solid(hull, z0, z1)]
    else:
        parts = bar_parts(np.vstack([hull, hull[::-1][:1]]), radius, z0, z1)
        parts.append(cylinder_solid(hull[-1], radius, z0, z1))
    toward = centres.mean(axis=0)
    for k, rod in enumerate(rods):
        parts += [placed(s, m.location) for m in [_lug(f"fixture.{'AB'[k]}", a[k], rod, k, toward)]
                  for s in lug_parts(m)]
    body = one_part(parts[0].fuse(*parts[1:]).clean(), "joining the fixture's outline and knuckles", "fixture")

    # room for the rods: knuckle zones and slots in the rods' layer
    reach = float(np.max(np.hypot(*(centres - a[0]).T))) + dist + 2 * radius + 10.0

    def room(own: bool) -> list[Solid]:
        """The cuts: each slot out past the whole fixture, or (``own``) out past its rod."""
        cuts = []
        for k, rod in enumerate(rods):
            g = rod.geometry
            h = g.hinge
            layer = g.max_thickness / 2 + h.layer_gap  # the rod's layer: its ends and its (graduated) body
            at = h.tongue_thickness / 2
            if h.knuckle(k) == "tongue":  # the fixture's fork: room for the rod's tongue
                cuts.append(cylinder_solid(a[k], h.zone_radius, -at - h.layer_gap, at + h.layer_gap))
            else:  # the fixture's tongue: room for the rod's prongs
                cuts.append(cylinder_solid(a[k], h.zone_radius, at, layer))
                cuts.append(cylinder_solid(a[k], h.zone_radius, -layer, -at))
            w0, w1, far = slots[k]
            cuts.append(_wedge(a[k], w0, w1, far + SLOT_MARGIN if own else reach, h.knuckle_radius, -layer, layer))
        return cuts

    cleared = body.cut(*room(False)).clean()
    if len(cleared.solids()) > 1:  # the slots cut the rods' layer through: top and bottom apart
        cleared = body.cut(*room(True)).clean()  # each slot only as far as its own rod reaches
    body = one_part(cleared, "clearing room for the end rods", "fixture")

    if stops:
        pegs = [cylinder_solid(s.center, s.radius, z0, z1) for s in stops]
        body = one_part(body.fuse(*pegs).clean(), "adding the stops", "fixture")
    shift = np.zeros((2, 2)) if pin_holes is None else np.asarray(pin_holes, float).reshape(2, 2)
    dia = [h.hole_diameter for h in hinges] if hole_diameters is None else [float(v) for v in hole_diameters]
    holes = [cylinder_solid(a[k] + shift[k], dia[k] / 2, z0 - 1, z1 + 1) for k in (0, 1)]
    holes += [cylinder_solid(p, hole_d / 2, z0 - 1, z1 + 1) for p in mounts]
    body = one_part(body.cut(*holes).clean(), "drilling the pin and mount holes", "fixture")
    body.label = "fixture"
    return body


def placed_rods(points: Any, rods: Sequence[RodType]) -> list[tuple[Solid, str]]:
    """The chain's plain rod solids at rest in the chain plane, named 'rod_NN' (rod i with
    its rod frame at joint p_i, x along p_i -> p_{i+1}), for :func:`check_fixture`."""
    return [(placed(type_solid(rod), m), f"rod_{i:02d}")
            for i, (rod, m) in enumerate(zip(rods, rod_matrices(np.asarray(points, dtype=float))))]


def _about(anchor: np.ndarray, angle: float) -> np.ndarray:
    """4x4 rotation by ``angle`` (rad) about the z axis through ``anchor``."""
    m = rod_matrix((0.0, 0.0), angle)
    m[:2, 3] = anchor - m[:2, :2] @ anchor
    return m


def _overlap(a: Solid, b: Solid) -> float:
    common = a.intersect(b)
    return 0.0 if common is None else float(sum(s.volume for s in common.solids()))


def check_fixture(fixture: Solid, rods_at_rest: Sequence[tuple[Solid, str]], *, anchors: Any = None,
                  end_limits: Any = None, build_volume: Sequence[float] | None = None,
                  contact: float = CONTACT, overlap_tol: float = OVERLAP_TOL) -> list[str]:
    """What is wrong with a fixture, in words (empty when all is well).

    Checks: one valid solid; no rod at rest overlaps it by more than ``overlap_tol``
    (mm^3; rods whose boxes are apart from the fixture's are skipped); with
    ``end_limits``, each end rod with a finite bound touches it at rest (at most
    ``contact`` mm away) and, with ``anchors`` too, overlaps it when turned 1 deg past
    its bound about its anchor; the bounding box against the printer's ``build_volume``
    (in some axis-aligned orientation).

    Args:
        fixture: the fixture solid (chain plane).
        rods_at_rest: (solid placed in the chain plane, name) of every rod in chain
            order: the first is the rod at A, the last the rod at B.
        anchors: (2, 2) A and B (mm).
        end_limits: (2, 2) [lo, hi] (rad) per anchor, or None.
        build_volume: (x, y, z) of the printer (mm), or None.
    """
    problems: list[str] = []
    if not is_valid_solid(fixture):
        return ["the fixture is not one valid solid"]
    bb = fixture.bounding_box()
    lo = np.array([bb.min.X, bb.min.Y, bb.min.Z]) - 1.0
    hi = np.array([bb.max.X, bb.max.Y, bb.max.Z]) + 1.0
    near = DistanceTo(fixture)
    gaps: dict[int, float] = {}
    for i, (rod, name) in enumerate(rods_at_rest):
        rb = rod.bounding_box()
        if np.any(np.array([rb.min.X, rb.min.Y, rb.min.Z]) > hi) or np.any(
                np.array([rb.max.X, rb.max.Y, rb.max.Z]) < lo):
            gaps[i] = math.inf
            continue
        gaps[i] = near(rod)
        if gaps[i] <= CONTACT_TOL:
            v = _overlap(fixture, rod)
            if v > overlap_tol:
                problems.append(f"{name} overlaps the fixture at rest ({v:.3f} mm^3)")
    if end_limits is not None and rods_at_rest:
        lim = _limits(end_limits)
        a = None if anchors is None else np.asarray(anchors, dtype=float)
        for k, i in ((0, 0), (1, len(rods_at_rest) - 1)):
            bounds = [s for s, b in ((1.0, lim[k, 1]), (-1.0, lim[k, 0])) if math.isfinite(b)]
            if not bounds:
                continue
            rod, name = rods_at_rest[i]
            if gaps[i] > contact:
                problems.append(f"{name} does not rest on the fixture's stop at {'AB'[k]} "
                                f"({gaps[i]:.3f} mm away)")
            if a is not None:
                past = [_overlap(fixture, placed(rod, _about(a[k], s * math.radians(1.0)))) for s in bounds]
                if max(past) <= overlap_tol:
                    problems.append(f"the fixture does not stop {name} at {'AB'[k]}: turned 1 deg past "
                                    "its bound it still clears the fixture")
    if build_volume is not None:
        size = np.array([bb.size.X, bb.size.Y, bb.size.Z])
        vol = np.asarray(build_volume, dtype=float)
        if not np.all(np.sort(size) <= np.sort(vol) + 1e-9):
            problems.append(f"the fixture ({size[0]:.0f} x {size[1]:.0f} x {size[2]:.0f} mm) does not fit "
                            f"the printer's build volume {vol[0]:.0f} x {vol[1]:.0f} x {vol[2]:.0f} mm")
    return problems
