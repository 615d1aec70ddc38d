"""The catalog data model: parameterized rod families expanded into named rod types.

A catalog (``catalogs/*.yaml``) is the single source for the simulator (joint
limits, mass ranges, centres of mass) and the CAD (exact rod solids). This module
holds its data, numbers only: no CAD call (a rod's shape, :class:`RodGeometry`, in
:mod:`rodcad.catalog.geometry`; its ends and hinge in :mod:`rodcad.catalog.ends`; material,
balls, shot and printer in :mod:`rodcad.catalog.stock`: exported here too). It is read and
validated by :mod:`rodcad.catalog.loader`; the solids are :func:`rodcad.cad.solids.type_solid`, and
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
from collections.abc import Iterator, Sequence
from dataclasses import asdict, dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

from rodcad.catalog.sections import end_reach, graduated, max_body_scale

from rodcad.catalog.ends import EndShape, Hinge
from rodcad.catalog.geometry import GEOMETRY_VERSION, MAX_ARC_HALF_ANGLE_DEG, RodGeometry, json_digest, max_curvature
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


#: The catalog format this code reads (the ``catalog:`` key).
CATALOG_FORMAT = 1


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
