"""A spliced net rod's solids (:mod:`rodcad.catalog.net.splice`): the whole rod, as it hangs,
and the pieces it is printed in.

The rod is built whole (:func:`rodcad.cad.net.solids.rod_body`), each piece's balls and cavity
cut in its zone (:func:`rodcad.cad.net.solids.fill_voids`) and at every cut a closed bore
``2 depth`` long for the dowel pin; the pieces are the whole rod's parts between the cut
planes (a slab each), so their volumes add up to the whole's and each ends in a blind hole.
"""

from __future__ import annotations

from build123d import Plane, Solid

from rodcad.cad.net.solids import fill_voids, rod_body
from rodcad.cad.solids import one_solid
from rodcad.catalog.net.splice import piece_extents

__all__ = ["piece_label", "spliced_rod", "spliced_rod_solids"]


def piece_label(name: str, i: int) -> str:
    """Piece ``i``'s name: 'rod-003-a', 'rod-003-b', ..."""
    return f"{name}-{chr(ord('a') + i)}"


def spliced_rod(hw, length: float, fills, name: str = "rod") -> Solid:
    """A spliced rod whole along +x, its pivots at x = 0 and ``length``, labelled ``name``.

    Args:
        hw: the node hardware (its ``splice``).
        length: pivot to pivot (mm).
        fills: per piece, (steel balls, cavity volume mm^3)
            (:func:`rodcad.catalog.net.splice.splice_fill`).
    """
    sp = hw.splice
    ext = piece_extents(hw, length, len(fills))
    voids = []
    for (x0, x1, z0, z1), (balls, cavity) in zip(ext, fills):
        voids += fill_voids(hw, z0, z1, int(balls), float(cavity))
    for x0, *_ in ext[1:]:
        voids.append(Solid.make_cylinder(sp.hole_radius, 2 * sp.depth, Plane((x0 - sp.depth, 0, 0), z_dir=(1, 0, 0))))
    whole = one_solid(rod_body(hw, length).cut(*voids), "cutting a spliced rod's cavities, ball sockets and pin bores")
    whole.label = name
    return whole


def spliced_rod_solids(hw, length: float, fills, name: str = "rod") -> tuple[Solid, list[Solid]]:
    """A spliced rod (:func:`spliced_rod`) and the pieces it is printed in.

    Returns:
        (the whole rod, labelled ``name``; its pieces, ``name-a``, ``name-b``, ...).
    """
    whole = spliced_rod(hw, length, fills, name)
    ext = piece_extents(hw, length, len(fills))
    big = hw.ball + hw.rod_diameter  # (beyond the rod's ends and sides)
    pieces = []
    for i, (x0, x1, _, _) in enumerate(ext):
        a = x0 - (big if i == 0 else 0.0)
        b = x1 + (big if i == len(ext) - 1 else 0.0)
        slab = Solid.make_box(b - a, 2 * big, 2 * big, Plane((a, -big, -big)))
        piece = one_solid(whole.intersect(slab), f"cutting piece {i + 1} of a spliced rod")
        piece.label = piece_label(name, i)
        pieces.append(piece)
    return whole, pieces
