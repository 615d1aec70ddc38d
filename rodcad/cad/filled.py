"""Rods with a fill chamber, built on the B-rep (see :mod:`rodcad.catalog.chamber`).

The chamber's cells (boxes in the rod frame, centred on the centre of mass) are cut from the
rod's solid in one boolean, checked to leave one valid solid with one closed inner shell per
cell; the walls around them are measured on the B-rep (BRepExtrema), and the as-built mass
and centre of mass come from the B-rep's plastic plus the shot that fills the cells (when
filled). Units: mm, mm^3, g.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from build123d import Plane, Solid

from rodcad.catalog.chamber import Chamber, plan_chamber
from rodcad.cad.solids import (NO_SHIFT, OWN_SIZES, GeometryError, Holes, Sizes, hole_volume_change, mass_properties,
                               one_solid, type_solid)

if TYPE_CHECKING:  # pragma: no cover
    from rodcad.catalog.model import RodType

__all__ = ["FilledRod", "build_filled", "chamber_solids"]


@dataclass
class FilledRod:
    """One rod with its chamber, as built.

    Attributes:
        solid: the rod's B-rep with the chamber cut (rod frame).
        chamber: the chamber (None: the plain solid).
        volume: plastic volume from the B-rep (mm^3).
        mass: plastic (B-rep volume x density) plus shot (g).
        com: (along, perp) centre of mass (mm), B-rep plus shot.
        min_wall: thinnest wall around the cells, measured on the B-rep (mm; inf without).
        goal: the mass the chamber was sized for (the target clipped to the range, g).
        message: '' or why the target was clipped.
    """

    solid: Any
    chamber: Chamber | None
    volume: float
    mass: float
    com: tuple[float, float]
    min_wall: float
    goal: float
    message: str


def chamber_solids(chamber: Chamber) -> list[Solid]:
    """The chamber's cells as solids in the rod frame: a box, or a stepped cell's nested boxes
    fused into one solid (checked: one valid solid per cell)."""
    out = []
    for cell in chamber.cell_boxes():
        boxes = [Solid.make_box(x1 - x0, y1 - y0, z1 - z0, Plane((x0, y0, z0))) for (x0, y0, z0), (x1, y1, z1) in cell]
        out.append(boxes[0] if len(boxes) == 1 else one_solid(boxes[0].fuse(*boxes[1:]).clean(),
                                                              "fusing a stepped chamber cell"))
    return out


def build_filled(rod: RodType, target: float, holes: Holes = NO_SHIFT, sizes: Sizes = OWN_SIZES) -> FilledRod:
    """The rod of ``target`` g (clipped to its range) with its chamber, measured on the B-rep,
    its pin holes moved by ``holes`` and of the joint hardware's ``sizes``
    (:func:`rodcad.cad.solids.build_rod`; ``target`` is for the hinge's own holes, the goal
    then less the plastic the hardware's holes take).

    Raises:
        GeometryError: the cut is not one valid solid with a closed cell per box.
    """
    from rodcad.cad.collision import void_walls

    assert rod.fill is not None
    chamber, goal, message = plan_chamber(rod, target)
    plain = type_solid(rod, holes, sizes)
    rho = rod.material.density / 1000.0
    goal -= hole_volume_change(rod.geometry, sizes) * rho
    if chamber is None:
        props = mass_properties(plain)
        return FilledRod(plain, None, props.volume, props.volume * rho, (props.center[0], props.center[1]),
                         math.inf, goal, message)
    cells = chamber_solids(chamber)
    solid = one_solid(plain.cut(*cells), "cutting the fill chamber")
    if len(solid.shells()) != 1 + len(cells):
        raise GeometryError(f"rod {rod.name!r}: cutting {len(cells)} chamber cells leaves "
                            f"{len(solid.shells()) - 1} inner surfaces: a cell breaks an outer face")
    solid.label = rod.name
    props = mass_properties(solid)
    to_faces, between = void_walls(plain, cells, rod.material.min_wall + 1.0)
    wall = min(float(to_faces.min()), between)
    shot = chamber.fill_mass
    plastic = props.volume * rho
    mass = plastic + shot
    cx, cy = chamber.center  # the shot's centroid: every cell's centre, mirrored across z = 0
    com = ((props.center[0] * plastic + cx * shot) / mass, (props.center[1] * plastic + cy * shot) / mass)
    return FilledRod(solid, chamber, props.volume, mass, com, wall, goal, message)
