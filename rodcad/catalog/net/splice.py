"""Rigid in-line splices: a net rod longer than the catalog prints, made of printed pieces
glued end to end on steel dowel pins.

A drawn edge whose two-rod joints cannot hang (their rods pull slack, or the net is too light
to kink them below their chords) and that one rod between the family's largest hubs does not
span is built as one straight, rigid rod of ``k`` pieces (:func:`rodcad.design.net.plan.plan_net`'s
``whole``). The rod's pivot-to-pivot length ``L`` is cut square to its axis at ``j L / k``
(each piece's share, ``L / k``, within the lengths the catalog prints); the two faces of each
cut are bored coaxially ``depth`` deep (half the pin and :data:`GLUE_GAP`) for a steel dowel pin
(``pin_diameter`` x ``pin_length``, e.g. ISO 8734 3 x 16) glued into both.

Numbers in closed form (cylinders; the hub ends as :meth:`rodcad.catalog.net.node.NodeHardware.rod_numbers`):
each piece lightens and weighs down as a one-piece rod does, inside its own *zone* (its body
between its hub end's face or a hole's bottom and the next): its steel balls in a row at the
zone's middle, its cavity (``min_wall`` from everything) beside them. The two end pieces are
alike (one turned end for end), the middle pieces alike, and alike pieces are filled alike, so
the rod is symmetric about its middle: its centre of mass lies at mid-length on its axis, as a
one-piece rod's, and the statics treat it as one rod of the pieces' and pins' summed mass.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["DEFAULT_SPLICE", "GLUE_GAP", "Splice", "piece_extents", "splice_fill", "splice_intervals",
           "splice_numbers"]

#: What a catalog without a ``node.splice`` block gets: a 3 x 16 mm steel dowel pin (ISO 8734)
#: in 3.1 mm holes.
DEFAULT_SPLICE = {"pin_diameter": 3.0, "pin_length": 16.0, "pin_density": 7.85, "clearance": 0.1}

#: Each hole is this much deeper than half the pin (mm): room for glue and for the pin's
#: chamfers, so the two faces close on each other.
GLUE_GAP = 0.5


@dataclass(frozen=True)
class Splice:
    """The splice hardware: a steel dowel pin glued into a coaxial hole in each face.

    Attributes:
        pin_diameter, pin_length: the pin (mm).
        pin_density: its material (g/cm^3).
        clearance: hole diameter minus pin diameter (mm).
    """

    pin_diameter: float = DEFAULT_SPLICE["pin_diameter"]
    pin_length: float = DEFAULT_SPLICE["pin_length"]
    pin_density: float = DEFAULT_SPLICE["pin_density"]
    clearance: float = DEFAULT_SPLICE["clearance"]

    @property
    def hole_radius(self) -> float:
        return (self.pin_diameter + self.clearance) / 2

    @property
    def depth(self) -> float:
        """Each face's hole depth (mm)."""
        return self.pin_length / 2 + GLUE_GAP

    @property
    def pin_mass(self) -> float:
        """One pin (g)."""
        return self.pin_density * math.pi / 4 * self.pin_diameter ** 2 * self.pin_length / 1000.0

    def problems(self, rod_diameter: float, min_wall: float) -> list[tuple[str, str]]:
        """(key, message) for a splice the rods cannot hold."""
        out = []
        if self.hole_radius + min_wall > rod_diameter / 2 + 1e-9:
            out.append(("splice.pin_diameter", f"a {2 * self.hole_radius:.3g} mm hole for the pin leaves less than "
                        f"the {min_wall:g} mm wall in the {rod_diameter:g} mm rod: a thinner pin"))
        return out


def piece_extents(hw, length: float, pieces: int) -> list[tuple[float, float, float, float]]:
    """Per piece, (x0, x1, z0, z1): its share of the rod along its axis (mm from the first
    pivot; the first piece from the pivot, the last to the other) and its zone, the body its
    balls and cavity go in (from its hub end's body face or a hole's bottom to the next)."""
    k, e, h = int(pieces), hw.end_offset, hw.splice.depth
    out = []
    for i in range(k):
        x0, x1 = length * i / k, length * (i + 1) / k
        out.append((x0, x1, e if i == 0 else x0 + h, length - e if i == k - 1 else x1 - h))
    return out


def _piece_volume(hw, x0: float, x1: float, first: bool, last: bool) -> float:
    """A piece's plastic with its holes, before balls and cavity (mm^3)."""
    r, sp = hw.rod_diameter / 2, hw.splice
    body0 = hw.end_offset if first else x0
    body1 = x1 - hw.end_offset if last else x1
    v = math.pi * r ** 2 * (body1 - body0) + (first + last) * hw.end_volume
    return v - (2 - first - last) * math.pi * sp.hole_radius ** 2 * sp.depth


def _kinds(hw, length: float, pieces: int) -> list[tuple[int, float, float]]:
    """The pieces by kind: (how many, plastic volume mm^3, zone length mm): the two ends, then the
    middle pieces (none for two)."""
    ext = piece_extents(hw, length, pieces)
    x0, x1, z0, z1 = ext[0]
    out = [(2, _piece_volume(hw, x0, x1, True, False), z1 - z0)]
    if pieces > 2:
        x0, x1, z0, z1 = ext[1]
        out.append((pieces - 2, _piece_volume(hw, x0, x1, False, False), z1 - z0))
    return out


def _combined(hw, kinds: list[tuple[int, float, float]], pieces: int) -> list[tuple[int, float, float, list]]:
    """Every choice of steel balls per kind of piece (:func:`_kinds`), alike pieces alike, fewest
    balls first: (the rod's balls in all, its lightest and heaviest mass with its pins g, per kind
    its (balls, lightest, heaviest))."""
    per = [hw.zone_intervals(v, z) for _, v, z in kinds]
    pins = (pieces - 1) * hw.splice.pin_mass
    choices: list[tuple] = [()]
    for opts in per:
        choices = [c + (o,) for c in choices for o in opts]
    out = [(sum(n * iv[0] for (n, _, _), iv in zip(kinds, c)),
            pins + sum(n * iv[1] for (n, _, _), iv in zip(kinds, c)),
            pins + sum(n * iv[2] for (n, _, _), iv in zip(kinds, c)), list(c)) for c in choices]
    return sorted(out, key=lambda x: x[0])  # (stable: alike totals keep their order)


def splice_intervals(hw, length: float, pieces: int) -> list[tuple[int, float, float]]:
    """The masses a spliced rod can be built at: per choice of balls, (its balls in all,
    lightest g, heaviest g), pins included."""
    return [(total, lo, hi) for total, lo, hi, _ in _combined(hw, _kinds(hw, length, pieces), pieces)]


def splice_numbers(hw, length: float, pieces: int) -> tuple[float, float, float, tuple[float, float], int]:
    """A spliced rod's numbers, its pins' steel in every mass: (length, body length mm, solid
    mass g, mass range g, most steel balls), as :class:`rodcad.catalog.net.node.NetRodNumbers`."""
    kinds = _kinds(hw, length, pieces)
    solid = (pieces - 1) * hw.splice.pin_mass + hw.density / 1000.0 * sum(n * v for n, v, _ in kinds)
    iv = _combined(hw, kinds, pieces)
    top = max(iv, key=lambda x: x[2])
    return (float(length), float(length - 2 * hw.end_offset), solid, (min(x[1] for x in iv), max(x[2] for x in iv)),
            int(top[0]))


def splice_fill(hw, length: float, mass: float, pieces: int) -> tuple[list[tuple[int, float]], float]:
    """How a spliced rod is made to weigh ``mass`` (g): the choice with the fewest balls whose
    range holds it (else the nearest), each kind's mass the same share of its own range.

    Returns:
        (per piece in order, (balls, cavity volume mm^3)), the mass it comes to (g).
    """
    rho = hw.density / 1000.0
    best = None
    for _, lo, hi, ivs in _combined(hw, _kinds(hw, length, pieces), pieces):  # (fewest balls first: they win ties)
        got = min(max(mass, lo), hi)
        if best is None or abs(got - mass) < best[0] - 1e-12:
            best = (abs(got - mass), got, lo, hi, ivs)
    assert best is not None
    _, got, lo, hi, ivs = best
    s = (got - lo) / (hi - lo) if hi > lo else 1.0
    fills = [(b, (h_ - (l_ + s * (h_ - l_))) / rho) for b, l_, h_ in ivs]
    end = fills[0]
    mid = fills[1] if len(fills) > 1 else end
    return [end if i in (0, pieces - 1) else mid for i in range(pieces)], float(got)
