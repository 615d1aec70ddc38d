"""The catalog data model: parameterized rod families expanded into named rod types.

A catalog (``catalogs/*.yaml``) is the single source for the simulator (joint
limits, mass ranges, centres of mass) and the CAD (exact rod solids). This module
holds its data, numbers only: no CAD call. It is read and validated by
:mod:`rodcad.catalog.loader`; the solids are :func:`rodcad.cad.solids.type_solid`, and
the numbers derived from them :mod:`rodcad.catalog.limits` (joint limits) and
:func:`rodcad.catalog.massrange.mass_info` (mass range, centre of mass).

The format, in short (``catalogs/pla-pinned.yaml`` is a commented example, and
``catalogs/catalog.schema.json`` the generated JSON Schema)::

    catalog: 1                  # format version
    name: pla-pinned
    printer: {build_volume: [220, 220, 250], nozzle: 0.4}   # optional
    defaults: {...}             # any family key; every family inherits it
    families:
      - name: free
        length: [20, 30, 40]    # pin to pin, mm; a list makes several types
        scale: 1                # multiplies the cross-section and knuckles
        curvature: 0            # 1/mm, signed; > 0 bulges toward -y
        section: {height: 10, thickness: 8}
        joint: {pin_diameter: 1.75, pin_clearance: 0.25, knuckle_radius: 3.5,
                tongue_thickness: 2.8, layer_gap: 0.3, radial_gap: 0.4}
        ends: {setback: 0.2, top_chamfer: 50, bottom_chamfer: 50}
        material: {name: PLA, density: 1.24, min_wall: 1.2}
        balls: {diameter: 5, density: 7.85, clearance: 0.2}

Rod types are named ``<family>-<length>`` (plus ``-s<scale>`` / ``-k<curvature>``
when a family lists several scales / curvatures); they are listed family by
family, then by length, scale and curvature in the order written.

A family *printed to order* gives ranges instead of lists (``catalogs/pla-parametric.yaml``)::

      - name: rod
        length: {min: 20, max: 60}          # any length: each rod gets its own
        curvature: {min: -0.05, max: 0.05}  # any curvature in the range
        stops: {min: -90, max: 90}          # stop angles printed at the bend (deg)

It lists two reference types (its shortest and longest straight rod); a design makes the
rods it needs with :meth:`Catalog.rod` (see :mod:`rodcad.design.printed`).

Conventions: millimetres, grams, degrees; densities in g/cm^3. Rod frame: the
first hinge axis through the origin, the second through (length, 0, 0), axes
along +z, chain plane xy. Top means +y. A chamfer angle tilts an end face away
from the partner rod (positive) or toward it (negative); see :class:`EndShape`.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from collections.abc import Iterator, Sequence
from dataclasses import asdict, dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

from rodcad.catalog.sections import end_reach, graduated, max_body_scale

from rodcad.catalog.ends import EndShape, Hinge
from rodcad.catalog.stock import Balls, Fill, Material, Origin, Printer
from rodcad.yamlio import suggest

__all__ = [
    "CATALOG_FORMAT",
    "GEOMETRY_VERSION",
    "MAX_ARC_HALF_ANGLE_DEG",
    "max_curvature",
    "Balls",
    "Catalog",
    "EndShape",
    "end_reach",
    "Family",
    "graduated",
    "max_body_scale",
    "Fill",
    "Hinge",
    "json_digest",
    "Material",
    "mm_pos",
    "Origin",
    "Printer",
    "Ranges",
    "RodGeometry",
    "RodType",
]


def json_digest(data: Any) -> str:
    """SHA-256 of a JSON-serialisable value (keys sorted): a stable cache key."""
    text = json.dumps(data, sort_keys=True, separators=(",", ":"), default=repr)
    return hashlib.sha256(text.encode()).hexdigest()


#: The catalog format this code reads (the ``catalog:`` key).
CATALOG_FORMAT = 1

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


@dataclass(frozen=True)
class RodType:
    """One rod type of a catalog: a family with one length, scale and curvature.

    Attributes:
        name: unique within the catalog, e.g. 'free-30'.
        family: family name.
        length: pin to pin (mm).
        scale: cross-section scale factor.
        curvature: signed curvature (1/mm), positive bulges toward -y.
        geometry: everything that shapes the solid.
        material: printing material.
        balls: metal balls it may hold, or None.
        origin: where the type's family (or length) is written in the catalog.
        fill: loose shot its chamber may hold (rods printed to order), or None.
        heavier: further ball kinds, in the catalog's order of preference after ``balls``:
            a rod uses one kind, a later one only where the kinds before cannot make it
            heavy enough (see :attr:`ball_kinds`).
        friction: friction coefficient of the pins in its holes (the catalog's
            ``joint.friction``; the friction band, :mod:`rodcad.design.asprinted`).
    """

    name: str
    family: str
    length: float
    scale: float
    curvature: float
    geometry: RodGeometry
    material: Material
    balls: Balls | None
    origin: Origin = field(compare=False, repr=False)
    fill: Fill | None = None
    heavier: tuple[Balls, ...] = ()
    friction: float = 0.3

    @property
    def ball_kinds(self) -> tuple[Balls, ...]:
        """Every ball kind this rod may hold, ``balls`` first (empty without balls)."""
        return () if self.balls is None else (self.balls, *self.heavier)

    def balls_json(self) -> Any:
        """The ball kinds as plain data (cache keys): None, one kind's dict, or a list."""
        if self.balls is None:
            return None
        return asdict(self.balls) if not self.heavier else [asdict(b) for b in self.ball_kinds]

    def with_kind(self, k: int) -> RodType:
        """This rod with ball kind ``k`` only (the kind a fabricated rod holds)."""
        kinds = self.ball_kinds
        if not kinds or (k == 0 and not self.heavier):
            return self
        return dataclasses.replace(self, balls=kinds[k], heavier=())


@dataclass(frozen=True)
class Ranges:
    """What a family of rods printed to order leaves to the design (mm, 1/mm, deg).

    Attributes:
        length: (min, max) pin-to-pin length.
        curvature: (min, max) signed curvature; (0, 0) for straight rods only.
        stops: (min, max) stop angles the design may print at a joint (flush ends whose
            top chamfers add up to the bend), or None: the family's own ends only.
        resolution: every length a multiple of this (mm), or None: as designed.
        scale: (min, max) scale of the body's section (graduated rods: the hinge ends stay
            the family's, see :class:`RodGeometry`), or None: the family's section only.
    """

    length: tuple[float, float]
    curvature: tuple[float, float]
    stops: tuple[float, float] | None
    resolution: float | None = None
    scale: tuple[float, float] | None = None


@dataclass(frozen=True)
class Family:
    """A family as written (after defaults): its name, types and origin.

    A family printed to order (``ranges`` set) lists two reference types, its shortest
    and longest straight rod with the family's own ends; the design makes the rods it
    needs with :meth:`Catalog.rod`, from ``template``.
    """

    name: str
    description: str
    type_names: tuple[str, ...]
    origin: Origin = field(compare=False, repr=False)
    ranges: Ranges | None = None
    template: RodType | None = field(default=None, compare=False, repr=False)

    @property
    def printed_to_order(self) -> bool:
        return self.ranges is not None


def _fmt(x: float, digits: int) -> str:
    text = f"{round(x, digits):.{digits}f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


@dataclass(frozen=True)
class Catalog:
    """A validated catalog.

    Attributes:
        name: catalog name.
        description: free text.
        path: the file it was loaded from (None if built in code).
        types: rod types in catalog order.
        families: families in catalog order.
        printer: the printer it is sized for, if given.
        print_settings: the catalog's ``print`` block (layer height, perimeters, ...), the
            profile every mass assumes besides 100 % infill.
        node: the hardware at a net's nodes (:class:`rodcad.catalog.net.node.NodeHardware`).
        pins: the joint hardware a chain's joints choose from (:class:`rodcad.catalog.pins.PinMenu`).
    """

    name: str
    description: str
    path: Path | None
    types: tuple[RodType, ...]
    families: tuple[Family, ...]
    printer: Printer | None = None
    print_settings: dict[str, Any] = field(default_factory=dict, compare=False)
    node: Any = field(default=None, compare=False)  # rodcad.catalog.net.node.NodeHardware (nets)
    pins: Any = field(default=None, compare=False)  # rodcad.catalog.pins.PinMenu (chains' joints)

    @cached_property
    def _by_name(self) -> dict[str, RodType]:
        return {t.name: t for t in self.types}

    @property
    def names(self) -> list[str]:
        """Type names in catalog order."""
        return [t.name for t in self.types]

    def __iter__(self) -> Iterator[RodType]:
        return iter(self.types)

    def __len__(self) -> int:
        return len(self.types)

    def __contains__(self, name: object) -> bool:
        return name in self._by_name

    def __getitem__(self, name: str) -> RodType:
        """The rod type called ``name``.

        Raises:
            KeyError: with a did-you-mean suggestion.
        """
        try:
            return self._by_name[name]
        except KeyError:
            raise KeyError(f"unknown rod type {name!r}{suggest(name, self.names)}") from None

    def type(self, name_or_type: str | RodType) -> RodType:
        """Look up a type by name (a RodType is returned as is)."""
        return name_or_type if isinstance(name_or_type, RodType) else self[name_or_type]

    def family(self, name: str) -> Family:
        """The family called ``name``."""
        for f in self.families:
            if f.name == name:
                return f
        raise KeyError(f"unknown rod family {name!r}{suggest(name, [f.name for f in self.families])}")

    @property
    def printed_families(self) -> list[Family]:
        """The families printed to order (with ranges), in catalog order."""
        return [f for f in self.families if f.ranges is not None]

    def rod(self, family: str, length: float, curvature: float = 0.0, *, scale: float = 1.0,
            first_stop: float | None = None, second_stop: float | None = None,
            first_under: float | None = None, second_under: float | None = None) -> RodType:
        """A rod of a family printed to order with its own parameters.

        Args:
            family: the family's name (it must have ranges).
            length: pin to pin (mm).
            curvature: signed curvature (1/mm).
            scale: scale of the body's section (a family with a ``scale`` range; 1 is the
                family's section): height and thickness times ``scale``, the hinge ends
                (knuckles, pins, end faces) the family's, so any rod joins any other
                (:class:`RodGeometry`). Within :meth:`scale_range`.
            first_stop, second_stop: top chamfer (deg) of a flush stop end (setback 0) at the
                first / second joint (the joint cannot bend further), or None.
            first_under, second_under: bottom chamfer (deg) of a flush end whose bottom
                face stops the joint from straightening further, or None.

        An end without a stop is the family's own. The name encodes the parameters:
        ``<family>-<length>[-s<scale>][-k<curvature x 1000>][-a<first top>][-b<second top>]
        [-c<first bottom>][-d<second bottom>]`` (chamfers of the stop faces), rounded to
        0.001 (no ``-s`` at scale 1); the rod itself keeps the exact values.

        Raises:
            ValueError: the family is not printed to order, or the scale is outside its range.
        """
        fam = self.family(family)
        if fam.template is None:
            raise ValueError(f"rod family {family!r} is not printed to order (it has no ranges)")
        t = fam.template
        g = t.geometry
        scale = float(scale)
        assert fam.ranges is not None
        rs = fam.ranges.scale
        if rs is None and scale != t.scale:
            raise ValueError(f"rod family {family!r} has one scale ({t.scale:g}); give it a scale range "
                             f"{{min, max}} for rods of scale {scale:g}")
        if rs is not None and not rs[0] - 1e-9 <= scale <= rs[1] + 1e-9:
            raise ValueError(f"scale {scale:g} is outside rod family {family!r}'s range {rs[0]:g} to {rs[1]:g}")

        def end(own: EndShape, top: float | None, under: float | None) -> EndShape:
            if top is None and under is None:
                return own
            return EndShape(0.0, own.top_chamfer if top is None else float(top),
                            own.bottom_chamfer if under is None else float(under))

        first = end(g.first, first_stop, first_under)
        second = end(g.second, second_stop, second_under)
        geom = RodGeometry(float(length), g.height, g.thickness, float(curvature), g.hinge, first, second)
        if rs is not None and scale != 1.0:
            geom = graduated(geom, scale, t.material.min_wall)
        name = f"{family}-{_fmt(length, 3)}"
        if rs is not None and scale != 1.0:
            name += f"-s{_fmt(scale, 3)}"
        if curvature:
            name += f"-k{_fmt(curvature * 1000, 3)}"
        for tag, value in (("a", first_stop), ("b", second_stop), ("c", first_under), ("d", second_under)):
            if value is not None:
                name += f"-{tag}{_fmt(value, 3)}"
        return RodType(name, family, float(length), scale if rs is not None else t.scale, float(curvature), geom,
                       t.material, t.balls, t.origin, t.fill, t.heavier, t.friction)

    def scale_range(self, family: str, length: float, curvature: float = 0.0, *,
                    first_stop: float | None = None, second_stop: float | None = None,
                    first_under: float | None = None, second_under: float | None = None) -> tuple[float, float]:
        """The scales a rod of these parameters can be printed at: the family's scale range,
        above which its top end faces would leave less than the minimum wall of top edge
        between them (:func:`max_body_scale`). (1, 1) for a family without a scale range."""
        fam = self.family(family)
        if fam.template is None or fam.ranges is None:
            raise ValueError(f"rod family {family!r} is not printed to order (it has no ranges)")
        rs = fam.ranges.scale
        if rs is None:
            return (fam.template.scale, fam.template.scale)
        rod = self.rod(family, length, curvature, scale=1.0 if rs[0] <= 1 <= rs[1] else rs[0],
                       first_stop=first_stop, second_stop=second_stop, first_under=first_under,
                       second_under=second_under)
        top = max_body_scale(rod.geometry, rod.material.min_wall)
        return (rs[0], max(rs[0], min(rs[1], top)))

    def with_types(self, types: Sequence[RodType]) -> Catalog:
        """This catalog with rods made to order added (a name already known is kept).

        Raises:
            ValueError: a new rod has the name of a different rod.
        """
        extra: list[RodType] = []
        known = dict(self._by_name)
        for t in types:
            old = known.get(t.name)
            if old is None:
                known[t.name] = t
                extra.append(t)
            elif old != t:
                raise ValueError(f"two different rods are both named {t.name!r}")
        if not extra:
            return self
        return dataclasses.replace(self, types=self.types + tuple(extra))

    def can_join(self, left: str | RodType, right: str | RodType) -> bool:
        """Whether ``right`` can follow ``left`` in a chain: the knuckle at the
        left rod's second joint mates with the one at the right rod's first
        (a tongue with a fork, of identical hinge dimensions)."""
        a, b = self.type(left).geometry, self.type(right).geometry
        return (a.hinge.knuckle(1) != b.hinge.knuckle(0)) and a.interface(1) == b.interface(0)

    def pairs(self) -> list[tuple[RodType, RodType]]:
        """Every ordered pair (left, right) that can be joined, in catalog order."""
        return [(a, b) for a in self.types for b in self.types if self.can_join(a, b)]


mm_pos = dict(exclusive_minimum=0, unit="mm")
