"""A rod's ends: the end faces outside the hinge zone and the pinned hinge (numbers only;
re-exported by :mod:`rodcad.catalog.model`)."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["EndShape", "Hinge"]


@dataclass(frozen=True)
class EndShape:
    """Shape of one rod end outside the hinge zone (the part that limits bending).

    The end face is two planes, one for the top (+y) half and one for the bottom
    half of the section, each parallel to the hinge axis. Each passes through
    the point ``setback`` mm back from the hinge axis along the rod's centreline
    tangent and is tilted by its chamfer angle: positive tilts the face away from
    the partner rod (cuts the corner back, more room to bend that way), negative
    tilts it toward the partner (the corner reaches past the hinge plane, so the
    joint stops before straight). Two facing square ends with setback s each and
    the pin at mid-height of a section of height h collide at
    ``2 * atan(2 s / h)``; faces with zero setback meet flush exactly at the sum
    of their chamfers.

    Attributes:
        setback: distance from the hinge axis to the face on the centreline (mm).
        top_chamfer: tilt of the top (+y) half face (deg).
        bottom_chamfer: tilt of the bottom (-y) half face (deg).
    """

    setback: float
    top_chamfer: float
    bottom_chamfer: float


@dataclass(frozen=True)
class Hinge:
    """Pinned hinge geometry shared by both ends of a rod (after scaling).

    The rod's thickness (z) is split into three layers: a middle *tongue* layer
    of ``tongue_thickness`` and two outer *fork prong* layers, separated by
    ``layer_gap``. One end of the rod carries the tongue knuckle, the other the
    fork (``layout``); a knuckle is a disc of ``knuckle_radius`` around the hinge
    axis with a pin hole of ``pin_diameter + pin_clearance``. Around each hinge
    axis, the layers the partner's knuckle occupies are cleared out to
    ``knuckle_radius + radial_gap`` (the *hinge zone*), so nothing inside the
    hinge zone ever collides; bending is limited by the end faces outside it.

    Attributes:
        layout: 'tongue-fork' (tongue at the first joint) or 'fork-tongue'.
        pin_diameter: diameter of the pin, which is not part of the rods (mm).
        pin_clearance: pin hole diameter minus pin diameter (mm).
        knuckle_radius: outer radius of the knuckles (mm).
        tongue_thickness: thickness of the middle layer (mm).
        layer_gap: axial clearance between tongue and prongs (mm).
        radial_gap: clearance around a partner's knuckle (mm).
    """

    layout: str
    pin_diameter: float
    pin_clearance: float
    knuckle_radius: float
    tongue_thickness: float
    layer_gap: float
    radial_gap: float

    @property
    def hole_diameter(self) -> float:
        """Diameter of the pin hole (mm)."""
        return self.pin_diameter + self.pin_clearance

    @property
    def zone_radius(self) -> float:
        """Radius of the hinge zone around each axis (mm)."""
        return self.knuckle_radius + self.radial_gap

    def knuckle(self, joint: int) -> str:
        """'tongue' or 'fork': the knuckle at the first (0) or second (1) joint."""
        first, second = self.layout.split("-")
        return first if joint == 0 else second
