"""Numbers of rods printed to order, as fast functions of their parameters.

A family printed to order (``length: {min, max}``, see :class:`rodcad.catalog.model.Ranges`)
makes a different rod for every place of every design, so the planner needs each rod's
centre of mass, mass range and joint limits in milliseconds, not from a B-rep search:

* volume and centre of mass: :func:`rodcad.catalog.fastgeom.rod_mass_properties` (the solid's
  layers integrated in the chain plane, checked against the B-rep in the tests);
* mass range: a table over the family's length range (:func:`mass_table`: the exact
  :func:`rodcad.catalog.massrange.mass_info` of the family's straight rod every
  :data:`TABLE_STEP` mm, disk-cached and shipped with the catalog's seed), read
  conservatively: the plastic cavities can remove and the metal the balls can add are each
  the smaller of the two table lengths around the rod's length (ball counts only grow with
  length), and a rod whose shape differs from the table's (curved, or with stop ends) keeps
  :data:`SHAPE_MARGIN` of them;
* joint limits: :func:`rodcad.catalog.jointlimits.joint_limits`; a stop printed to order
  sits where two flush faces meet, at the sum of their top chamfers and of the rods' half
  arc angles (:func:`stop_chamfer`).

What the rods really reach is known once they are built (``rodcad build`` re-designs the
masses on the achievable intervals of the real solids and re-simulates the chain with them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rodcad.catalog.fastgeom import rod_mass_properties
from rodcad.catalog.model import Catalog, Family, RodGeometry, RodType, graduated, max_curvature

__all__ = ["MassTable", "RodNumbers", "SCALE_STEP", "SHAPE_MARGIN", "TABLE_STEP", "mass_table", "rod_numbers",
           "sample_pairs", "stop_chamfer", "table_lengths", "table_scales"]

#: Spacing of the lengths at which a family's mass range is computed on the solids (mm).
TABLE_STEP = 5.0

#: A rod within this of a table length (mm) is read at it (its length up to round-off).
ON_GRID = 1e-6

#: Share of the table's removable and addable mass a rod of another shape than the table's
#: straight rod is credited with (curved bodies and stop ends leave a little less room).
SHAPE_MARGIN = 0.9


#: Spacing of the scales at which a graduated family's mass range is computed.
SCALE_STEP = 0.1


@dataclass(frozen=True)
class MassTable:
    """A family's mass range along its length range (straight rods, the family's ends) and,
    for graduated rods, its scale range.

    Attributes:
        lengths: (K,) table lengths (mm), from the range's min to its max.
        removable: (K,) or (K, S) fraction of the solid's mass the cavities can remove.
        addable: (K,) or (K, S) mass the balls can add, less the plastic their sockets take (g).
        scales: (S,) table scales (a family with a scale range), or None: one scale.
    """

    lengths: np.ndarray
    removable: np.ndarray
    addable: np.ndarray
    scales: np.ndarray | None = None

    def at(self, length: float, scale: float = 1.0) -> tuple[float, float]:
        """(removable fraction, addable g) for a rod of this length and scale: the smallest of
        the table entries around it (each grows with length and scale)."""
        ks = _around(self.lengths, length)
        if self.scales is None:
            return float(self.removable[ks].min()), float(self.addable[ks].min())
        ss = _around(self.scales, scale)
        return float(self.removable[np.ix_(ks, ss)].min()), float(self.addable[np.ix_(ks, ss)].min())


def _around(grid: np.ndarray, x: float) -> list[int]:
    """The grid index at ``x`` (to round-off), or the two around it (clamped at the ends)."""
    on = np.flatnonzero(np.abs(grid - x) <= ON_GRID)
    if on.size:
        return [int(on[0])]
    k = int(np.clip(np.searchsorted(grid, x, side="right") - 1, 0, grid.size - 1))
    return sorted({k, min(k + 1, grid.size - 1)})


@dataclass(frozen=True)
class RodNumbers:
    """What the planner needs of one rod.

    Attributes:
        solid_mass: the plain solid's mass (g).
        com: centre of mass (along, perp) in the rod frame (mm).
        mass_range: (m_min, m_max) (g).
    """

    solid_mass: float
    com: tuple[float, float]
    mass_range: tuple[float, float]


def table_lengths(family: Family) -> list[float]:
    """The lengths of a family's mass table: every TABLE_STEP mm and the range's ends."""
    assert family.ranges is not None
    lo, hi = family.ranges.length
    n = max(1, math.ceil((hi - lo) / TABLE_STEP - 1e-9))
    return [float(x) for x in np.linspace(lo, hi, n + 1)]


def table_scales(family: Family) -> list[float]:
    """The scales of a graduated family's mass table: the range's ends, scale 1 (the family's
    own rods, read exactly as without a scale range) and at most SCALE_STEP apart ([] for a
    family of one scale)."""
    assert family.ranges is not None
    if family.ranges.scale is None:
        return []
    lo, hi = family.ranges.scale
    knots = [lo] + ([1.0] if lo < 1.0 < hi else []) + [hi]
    out: list[float] = [lo]
    for a, b in zip(knots[:-1], knots[1:]):
        n = max(1, math.ceil((b - a) / SCALE_STEP - 1e-9))
        out += [float(x) for x in np.linspace(a, b, n + 1)[1:]]
    return out


def mass_table(family: Family, *, jobs: int | None = None) -> MassTable:
    """The family's mass table from the solids (disk-cached per rod)."""
    from dataclasses import replace

    from rodcad.catalog.massrange import mass_infos

    if family.template is None:
        raise ValueError(f"rod family {family.name!r} is not printed to order")
    t = family.template
    if t.fill is not None:  # its rods' ranges come from their chambers: no table to compute
        return MassTable(np.zeros(0), np.zeros(0), np.zeros(0))
    scales = table_scales(family)
    grid = [(x, s) for x in table_lengths(family) for s in (scales or [None])]

    def rod(x: float, s: float | None) -> RodType:
        g = replace(t.geometry, length=x, curvature=0.0)
        if s is None:
            return replace(t, name=f"{family.name}-table-{x:g}", length=x, curvature=0.0, geometry=g)
        return replace(t, name=f"{family.name}-table-{x:g}-s{s:g}", length=x, curvature=0.0, scale=s,
                       geometry=graduated(g, s, t.material.min_wall))

    rods = [rod(x, s) for x, s in grid]
    by_name = mass_infos(rods, jobs=jobs)
    infos = [by_name[r.name] for r in rods]
    removable = np.array([(i.solid_mass - i.m_min) / i.solid_mass for i in infos])
    addable = np.array([i.m_max - i.solid_mass for i in infos])
    lengths = np.array(table_lengths(family))
    if scales:
        shape = (lengths.size, len(scales))
        return MassTable(lengths, removable.reshape(shape), addable.reshape(shape), np.array(scales))
    return MassTable(lengths, removable, addable)


def _plain(g: RodGeometry, template: RodType) -> bool:
    t = template.geometry
    return g.curvature == 0 and g.first == t.first and g.second == t.second


def rod_numbers(rod: RodType, table: MassTable | None, template: RodType) -> RodNumbers:
    """Solid mass, centre of mass and mass range of a rod printed to order (a rod with a
    ``fill``: its chamber's range in closed form, :func:`rodcad.catalog.chamber.fill_numbers`;
    the table is not read and may be None)."""
    if rod.fill is not None:
        from rodcad.catalog.chamber import fill_numbers

        solid, com, rng = fill_numbers(rod)
        return RodNumbers(solid, com, rng)
    if table is None:
        raise ValueError(f"rod {rod.name!r}: a mass table is needed (it has no fill)")
    volume, (cx, cy, _) = rod_mass_properties(rod.geometry)
    solid = volume * rod.material.density / 1000.0
    removable, addable = table.at(rod.length, rod.scale)
    if not _plain(rod.geometry, template):
        removable, addable = removable * SHAPE_MARGIN, addable * SHAPE_MARGIN
    return RodNumbers(solid, (cx, cy), (solid * (1 - removable), solid + max(addable, 0.0)))


def stop_chamfer(bend_deg: float, left: RodGeometry, right: RodGeometry) -> float:
    """The top chamfer (deg) of each of the two flush ends (setback 0) that meet at a
    bend of ``bend_deg`` between the chords of ``left`` and ``right``: the faces meet when
    the tangents have turned by the sum of the chamfers, and the tangents turn by the
    bend less the two half arc angles at the joint."""
    return (bend_deg - left.half_angle_deg - right.half_angle_deg) / 2


def sample_pairs(catalog: Catalog, family: Family) -> list[tuple[RodType, RodType]]:
    """Rods of a family printed to order at the ends of its ranges, in joined pairs: two free
    ends, top stops at the ends of the stop range, bottom stops, a straight stop; where the
    fast joint-limit function is compared with the B-rep search (``rodcad catalog check``)."""
    r = family.ranges
    assert r is not None
    (l0, l1), (k0, k1) = r.length, r.curvature

    def rod(length: float, k: float, **ends: float) -> RodType:
        k = math.copysign(min(abs(k), max_curvature(length)), k)
        return catalog.rod(family.name, length, k, **ends)

    def graded(length: float, scale: float, **ends: float) -> RodType:
        return catalog.rod(family.name, length, 0.0, scale=scale, **ends)

    def chamfer(s: float, a: tuple[float, float], b: tuple[float, float]) -> float:
        c = stop_chamfer(s, rod(*a).geometry, rod(*b).geometry)
        return min(max(c, r.stops[0] / 2), r.stops[1] / 2) if r.stops else c

    pairs = [(rod(l0, k0), rod(l1, k1)), (rod(l1, k1), rod(l0, 0.0))]
    if r.stops is not None:
        for s, a, b in ((r.stops[1], (l0, k1), (l1, 0.0)), (r.stops[0], (l1, 0.0), (l0, k0)),
                        (0.0, (l0, 0.0), (l1, 0.0))):
            c = chamfer(s, a, b)
            pairs.append((rod(*a, second_stop=c), rod(*b, first_stop=c)))
        for s, a, b in ((r.stops[1] / 2, (l1, k1), (l0, k1)), (r.stops[0] / 2, (l0, 0.0), (l1, k0))):
            c = -chamfer(s, a, b)
            pairs.append((rod(*a, second_under=c), rod(*b, first_under=c)))
    if r.scale is not None:  # graduated rods: the thinnest next to the thickest, free and on stops
        s0, s1 = r.scale
        pairs += [(graded(l1, s0), graded(l1, s1)), (graded(l1, s1), graded(l1, s0))]
        if r.stops is not None:
            for s in (r.stops[1], r.stops[0] / 2):  # (a concave top stop at the range's end meets the
                # family's bottom faces too: the joint is fused there, tried above on curved rods)
                pairs.append((graded(l1, s1, second_stop=s / 2), graded(l1, s0, first_stop=s / 2)))
            c = -r.stops[1] / 4
            pairs.append((graded(l1, s0, second_under=c), graded(l1, s1, first_under=c)))
    return pairs
