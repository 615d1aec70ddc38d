"""Graduated rods for the planner: a rod's mass range over its scale, and the scale for a mass.

A family with a scale range (:class:`rodcad.catalog.model.Ranges`) prints each rod's body at
its own scale while the hinge ends stay the family's (:class:`rodcad.catalog.model.RodGeometry`).
A rod's plain mass and centre of mass are closed-form functions of (length, curvature, scale,
ends) (:func:`rodcad.catalog.fastgeom.rod_mass_properties`, equal to the B-rep's to
round-off); its mass range [m_min, m_max] comes from the family's mass table over length and
scale (:func:`rodcad.catalog.printed.mass_table`, read conservatively). Both grow with the
scale, so the scales at which a wanted mass lies inside a rod's range form one interval, found
by bisection:

    table = mass_table(catalog.family("rod"))
    choice = scale_for_mass(catalog, "rod", table, 40.0, 12.0, curvature=0.01)
    if choice is not None:
        rod = choice.rod                       # Catalog.rod(..., scale=choice.scale)
        m_min, m_max = choice.numbers.mass_range
    lightest, heaviest = mass_span(catalog, "rod", table, 40.0)

Units: mm, 1/mm, g, deg.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

from rodcad.catalog.model import Catalog, RodType
from rodcad.catalog.printed import MassTable, RodNumbers, rod_numbers

__all__ = ["ScaleChoice", "mass_span", "numbers_at", "scale_for_mass", "SCALE_GRID"]

#: Scales are chosen on a grid of 1 / SCALE_GRID (the range's ends too): a thousandth, 16 um
#: on a 16 mm section, below what a printer resolves; the rods' names round the scale to it, so
#: two rods of one name and length are one solid.
SCALE_GRID = 1000


@dataclass(frozen=True)
class ScaleChoice:
    """The scale a rod is printed at for a wanted mass.

    Attributes:
        scale: the chosen scale: where the wanted mass is nearest the middle of the rod's
            mass range (the middle grows with the scale).
        rod: the rod at ``scale``.
        numbers: its solid mass, centre of mass and mass range.
        scales: (lowest, highest) scale at which the wanted mass lies in the rod's range,
            found when first asked (two more bisections).
    """

    scale: float
    rod: RodType
    numbers: RodNumbers
    bounds: Callable[[], tuple[float, float]] = field(repr=False, compare=False)

    @cached_property
    def scales(self) -> tuple[float, float]:
        return self.bounds()


def numbers_at(catalog: Catalog, family: str, table: MassTable, length: float, scale: float,
               curvature: float = 0.0, **ends: Any) -> tuple[RodType, RodNumbers]:
    """The rod of these parameters at ``scale`` and its numbers (solid mass, com, mass range).

    ``ends``: Catalog.rod's first_stop, second_stop, first_under, second_under."""
    rod = catalog.rod(family, length, curvature, scale=scale, **ends)
    fam = catalog.family(family)
    assert fam.template is not None
    return rod, rod_numbers(rod, table, fam.template)


def mass_span(catalog: Catalog, family: str, table: MassTable, length: float, curvature: float = 0.0,
              **ends: Any) -> tuple[float, float]:
    """The lightest and heaviest mass a rod of these parameters reaches over the scales it
    can be printed at (:meth:`Catalog.scale_range`): (m_min at the lowest scale, m_max at the
    highest) (g)."""
    lo, hi = catalog.scale_range(family, length, curvature, **ends)
    return (numbers_at(catalog, family, table, length, lo, curvature, **ends)[1].mass_range[0],
            numbers_at(catalog, family, table, length, hi, curvature, **ends)[1].mass_range[1])


def _bisect(f: Any, lo: float, hi: float) -> float:
    """The first scale of the grid between lo and hi (lo, the grid's points strictly between,
    hi) at which the increasing ``f`` is not negative (f(lo) < 0 <= f(hi)), by halving.

    Halving, not a faster root finder: a rod's mass range is not a smooth function of its scale
    (ball sockets come in whole numbers), and Brent's method found another crossing (the
    semicircle's 22 g rods at scale 1.189 instead of 1.271)."""
    k0, k1 = math.floor(lo * SCALE_GRID + 1e-9) + 1, math.ceil(hi * SCALE_GRID - 1e-9) - 1
    points = [lo, *(k / SCALE_GRID for k in range(k0, k1 + 1)), hi]
    a, b = 0, len(points) - 1
    while b - a > 1:
        m = (a + b) // 2
        if f(points[m]) < 0:
            a = m
        else:
            b = m
    return points[b]


def scale_for_mass(catalog: Catalog, family: str, table: MassTable, length: float, mass: float,
                   curvature: float = 0.0, **ends: Any) -> ScaleChoice | None:
    """The scale at which a rod of these parameters can be made at ``mass`` (g), or None when
    no scale of its range reaches it (see :func:`mass_span`).

    The chosen scale puts ``mass`` nearest the middle of the rod's range (cavities and balls
    then have room either way): where the middle of the range crosses ``mass``, by one
    bisection over the scale range. Where the range there does not hold ``mass`` (the range
    jumps where the mass table's scales are), the crossing is sought again between the
    lowest and the highest scale whose range holds it (:attr:`ScaleChoice.scales`).
    """
    s_lo, s_hi = catalog.scale_range(family, length, curvature, **ends)

    seen: dict[float, tuple[RodType, RodNumbers]] = {}

    def at(s: float) -> tuple[RodType, RodNumbers]:
        if s not in seen:
            seen[s] = numbers_at(catalog, family, table, length, s, curvature, **ends)
        return seen[s]

    def rng(s: float) -> tuple[float, float]:
        return at(s)[1].mass_range

    lo_range, hi_range = rng(s_lo), rng(s_hi)
    if mass < lo_range[0] or mass > hi_range[1]:
        return None

    def holds(s: float) -> bool:
        m0, m1 = rng(s)
        return m0 - 1e-9 <= mass <= m1 + 1e-9

    def bounds() -> tuple[float, float]:
        a = s_lo if mass <= lo_range[1] else _bisect(lambda s: rng(s)[1] - mass, s_lo, s_hi)
        b = s_hi if mass >= hi_range[0] else _bisect(lambda s: rng(s)[0] - mass, s_lo, s_hi)
        return a, b

    mid = lambda s: sum(rng(s)) / 2 - mass  # noqa: E731
    s = s_lo if mid(s_lo) >= 0 else s_hi if mid(s_hi) <= 0 else _bisect(mid, s_lo, s_hi)
    if not holds(s):
        a, b = bounds()
        if a > b:  # a gap between the ranges of neighbouring scales (not expected)
            return None
        s = a if mid(a) >= 0 else b if mid(b) <= 0 else _bisect(mid, a, b)
        if not holds(s):
            return None
    rod, nums = at(s)
    return ScaleChoice(s, rod, nums, bounds)
