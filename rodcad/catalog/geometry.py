"""A rod's shape as numbers (no CAD): :class:`RodGeometry`, everything that shapes its solid after
scaling, with the stable digest the disk caches key on (:func:`json_digest`,
:data:`GEOMETRY_VERSION`) and the largest curvature a rod is printed with (:func:`max_curvature`).

Part of the catalog data model (:mod:`rodcad.catalog.model`, which exports these names too);
the solid itself is :func:`rodcad.cad.solids.type_solid`. Rod frame and conventions as there:
millimetres and degrees, the first hinge axis through the origin, the second through
(length, 0, 0), top is +y.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass
from typing import Any

from rodcad.catalog.ends import EndShape, Hinge

__all__ = ["GEOMETRY_VERSION", "MAX_ARC_HALF_ANGLE_DEG", "RodGeometry", "json_digest", "max_curvature"]


def json_digest(data: Any) -> str:
    """SHA-256 of a JSON-serialisable value (keys sorted): a stable cache key."""
    text = json.dumps(data, sort_keys=True, separators=(",", ":"), default=repr)
    return hashlib.sha256(text.encode()).hexdigest()


#: Version of how :mod:`rodcad.cad` turns a :class:`RodGeometry` into a solid. Bump it with any
#: change there: it is part of every disk-cache key (here: cache hits need not import the kernel).
GEOMETRY_VERSION = "1"

#: Largest half-angle of a curved rod's arc (the arc spans at most twice this).
MAX_ARC_HALF_ANGLE_DEG = 60.0


def max_curvature(length: float) -> float:
    """The largest |curvature| (1/mm) a rod of this length is printed with: an arc of
    2 x MAX_ARC_HALF_ANGLE_DEG through both pins."""
    return math.sin(math.radians(MAX_ARC_HALF_ANGLE_DEG)) * 2 / length


@dataclass(frozen=True)
class RodGeometry:
    """Everything that shapes a rod's solid (mm, deg), after scaling.

    Attributes:
        length: distance between the hinge axes (mm).
        height: section height in y, in the chain plane (mm).
        thickness: section thickness in z, along the hinge axes (mm).
        curvature: signed curvature of the body's centreline arc through both
            hinge axes (1/mm). Positive turns counter-clockwise going from the
            first to the second joint, so the arc bulges toward -y (like a
            sagging chain) and the centre of mass lies below the chord.
        hinge: the hinge geometry.
        first: end shape at the first joint (origin).
        second: end shape at the second joint (length, 0, 0).
        body_height: a graduated rod's body height between its hinge ends (mm), or None:
            ``height`` throughout. The body keeps its bottom (-y) face at -height/2, the
            face a rod is printed on, so a body of another height changes only its top:
            a lower body keeps the family's ``height`` within ``end_reach`` of each hinge
            axis (the end faces and stops stay the family's, a step down behind them); a
            higher body is higher up to its end faces (they reach higher).
        body_thickness: a graduated rod's body thickness (mm), or None: ``thickness``
            throughout. Within ``end_reach`` of each hinge axis the rod keeps the
            family's ``thickness`` (the hinge layers): a thinner body at its fork end
            (which holds the prongs), a thicker body at both ends.
        end_reach: (first, second) how far behind each hinge axis, along the centreline,
            the rod keeps the family's section (mm); None for a rod of one section.
    """

    length: float
    height: float
    thickness: float
    curvature: float
    hinge: Hinge
    first: EndShape
    second: EndShape
    body_height: float | None = None
    body_thickness: float | None = None
    end_reach: tuple[float, float] | None = None

    @property
    def graduated(self) -> bool:
        """Whether the body's section differs from the hinge ends' (a scaled rod)."""
        return self.end_reach is not None and (self.body_h != self.height or self.body_t != self.thickness)

    @property
    def body_h(self) -> float:
        """The body's height (mm)."""
        return self.height if self.body_height is None else self.body_height

    @property
    def body_t(self) -> float:
        """The body's thickness (mm)."""
        return self.thickness if self.body_thickness is None else self.body_thickness

    @property
    def body_top(self) -> float:
        """The body's top (+y) offset from the centreline (mm): -height/2 + body height."""
        return -self.height / 2 + self.body_h

    @property
    def max_height(self) -> float:
        """The largest section height anywhere on the rod (mm)."""
        return max(self.height, self.body_h)

    @property
    def max_thickness(self) -> float:
        """The largest thickness anywhere on the rod (mm)."""
        return max(self.thickness, self.body_t)

    @property
    def stub(self) -> float:
        """How far the raw body continues past each hinge axis before the end cuts (mm)."""
        return 1.2 * self.max_height + 2.0

    def frame(self, joint: int) -> tuple[tuple[float, float], tuple[float, float], tuple[float, float]]:
        """Pin position P, outward tangent u and the rod's +y normal v at a joint (0 or 1)."""
        psi = math.radians(self.half_angle_deg)
        if joint == 0:
            p, fx, fy = (0.0, 0.0), math.cos(-psi), math.sin(-psi)
            u = (-fx, -fy)
        else:
            p, fx, fy = (self.length, 0.0), math.cos(psi), math.sin(psi)
            u = (fx, fy)
        return p, u, (-fy, fx)

    def end_blocks(self) -> list[tuple[tuple[float, float], ...]]:
        """Per joint, the rectangle (4 corners, counter-clockwise or not) that holds the
        rod's end within ``end_reach`` of that joint's axis: one side on the line across the
        centreline ``end_reach`` behind the axis (through the arc's centre on a curved rod),
        the rest far beyond the end. Empty for a rod of one section."""
        if self.end_reach is None:
            return []
        hmax = self.max_height
        out = []
        k = self.curvature
        for joint, d in ((0, self.end_reach[0]), (1, self.end_reach[1])):
            p, u, _ = self.frame(joint)
            if k == 0:
                q = (p[0] - u[0] * d, p[1] - u[1] * d)
                t = u
            else:
                psi = abs(math.radians(self.half_angle_deg))
                c = (self.length / 2, math.copysign(1 / abs(k), k) * math.cos(psi))
                beta = k * d if joint == 0 else -k * d
                cb, sb = math.cos(beta), math.sin(beta)
                w = (p[0] - c[0], p[1] - c[1])
                q = (c[0] + cb * w[0] - sb * w[1], c[1] + sb * w[0] + cb * w[1])
                t = (cb * u[0] - sb * u[1], sb * u[0] + cb * u[1])
            e = (-t[1], t[0])
            rl = d + 2 * self.stub + 2 * hmax
            rw = 2 * hmax + self.stub + d
            out.append(((q[0] + e[0] * rw, q[1] + e[1] * rw), (q[0] - e[0] * rw, q[1] - e[1] * rw),
                        (q[0] - e[0] * rw + t[0] * rl, q[1] - e[1] * rw + t[1] * rl),
                        (q[0] + e[0] * rw + t[0] * rl, q[1] + e[1] * rw + t[1] * rl)))
        return out

    def cut_reach(self, side: int, tan_chamfer: float) -> float:
        """How far from the centreline the prism cutting an end face reaches (mm): past the
        side (``side`` +1 top, -1 bottom) and the arc bending away behind the face; on a
        graduated rod whose top is the inner side of its arc (curvature > 0), up to that
        side's height at the rod's middle, so that the two ends' cuts leave no island of it."""
        reach = (max(self.height / 2, self.body_top) if side > 0 else self.height / 2) + 1.0
        behind = reach * max(tan_chamfer, 0.0)
        reach += behind**2 * abs(self.curvature) / 2 + 1.0
        if side > 0 and self.graduated and self.curvature > 0 and tan_chamfer > 0:
            rho = 1 / self.curvature
            psi = abs(math.radians(self.half_angle_deg))
            reach = max(reach, rho - (rho - self.body_top) * math.cos(psi) + 1.0)
        return reach

    def key_data(self) -> dict[str, Any]:
        """Every parameter as plain data for cache keys: a rod of one section gives the
        same data as before graduated rods existed (its shipped seeds stay valid)."""
        data = asdict(self)
        for k in ("body_height", "body_thickness", "end_reach"):
            if data[k] is None:
                del data[k]
        return data

    @property
    def half_angle_deg(self) -> float:
        """Signed angle between the chord and the body's tangent at the second
        joint (deg); the tangent at the first joint is at minus this angle."""
        return math.degrees(math.asin(max(-1.0, min(1.0, self.curvature * self.length / 2))))

    def interface(self, joint: int) -> tuple[Any, ...]:
        """What must match for another rod's hinge to mate with ``joint`` (0 or 1)."""
        h = self.hinge
        return (self.thickness, h.pin_diameter, h.pin_clearance, h.knuckle_radius,
                h.tongue_thickness, h.layer_gap, h.radial_gap)

    def digest(self) -> str:
        """Stable hash of every parameter (used for disk caches)."""
        return json_digest(self.key_data())
