"""Fused pieces: the rods of a run of fused joints (``constraints: {fuse: stops}``, the plan's
``fused`` (first, last) runs, joints with lo == hi) printed as ONE solid.

Each rod of a piece is fabricated on its own (:func:`rodcad.cad.rods.fabricate_chain`: its
cavities, ball sockets and mass); :func:`fuse_piece` places their solids, voids included,
in the FIRST rod's frame at their rest bends and unites them. At every fused joint a
*bridge* makes the piece robustly one solid and needs no pin: an annulus around the joint's
axis, out to the knuckle radius and through the whole thickness, fills the layer gaps
between the tongue and the fork; the pin hole is then widened by just the volume the
annulus added. Both are symmetric about the axis and about the chain plane, so the bridge
moves neither the mass nor the centre of mass: the piece weighs what its rods weigh, with
their centre of mass, and the chain hangs as designed (checked on the B-rep after the
booleans, to :data:`MASS_REL` and :data:`COM_MM`).

Print orientation: the piece lies on its side like a rod (:func:`rodcad.cad.export.print_matrix`),
turned about the hinge axis so the rods holding balls lean as little as possible from
upright. A socket whose rod leans by alpha has a tilted flat roof; its pause comes before
the first layer that reaches the roof's lowest point, ``centre + h cos alpha - r sin alpha``
above the socket's centre (h the roof's height above the centre along the socket's axis,
r its radius; at least the centre: the ball always drops in whole).

Units: mm, mm^3, g.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from rodcad.cad.export import placed, print_matrix, rod_matrices
from rodcad.cad.rods import ChainFabrication, FabricatedRod
from rodcad.cad.solids import cylinder_solid, is_valid_solid, mass_properties, one_solid
from rodcad.fabrication.cavities import FabricationError
from rodcad.fabrication.plan import socket_tops

if TYPE_CHECKING:  # pragma: no cover
    from rodcad.catalog.model import RodType

__all__ = ["COM_MM", "FabricatedPiece", "MASS_REL", "PieceRefused", "as_printed_rods", "fuse_piece", "fuse_pieces",
           "piece_stem"]

#: Largest relative difference between a piece's B-rep mass and its rods' masses.
MASS_REL = 1e-7
#: Largest distance (mm) between a piece's B-rep centre of mass and its rods' one. The bridge
#: is symmetric about the joint's axis, but where it fills part of a cavity of a short rod
#: (its voids reach the knuckle) the plastic it adds is not: the piece's own centre of mass
#: is then what the as-built check uses (:func:`as_printed_rods`).
COM_MM = 0.05


class PieceRefused(FabricationError):
    """These rods cannot be one printed piece (a design matter, not a kernel failure)."""


@dataclass
class FabricatedPiece(FabricatedRod):
    """Rods ``first`` to ``last`` printed as one solid: every field of a
    :class:`~rodcad.cad.rods.FabricatedRod` for the whole piece, in the frame of its first rod
    (``index`` = ``first``), plus:

    Attributes:
        first, last: chain positions of its first and last rods.
        rods: the rods it is made of, as fabricated (each in its own frame).
        placements: per rod, 4x4 rod frame -> piece frame (mm).
        bridges: per fused joint, (x, y) of its axis in the piece frame (mm).
        socket_roofs: per socket, the height (mm above the bed, print matrix) of the first
            layer that reaches its roof.
        turn_deg: how far the piece is turned about the hinge axis on the bed (deg).
    """

    first: int = 0
    last: int = 0
    rods: list[FabricatedRod] = field(default_factory=list, repr=False)
    placements: list[np.ndarray] = field(default_factory=list, repr=False)
    bridges: list[tuple[float, float]] = field(default_factory=list)
    socket_roofs: tuple[float, ...] = ()
    turn_deg: float = 0.0


def piece_stem(first: int, last: int) -> str:
    """The file stem of a piece: 'NN-MM_piece' (0-based rod indices, two digits or more)."""
    return f"{first:02d}-{last:02d}_piece"


def _turn(angle: float) -> np.ndarray:
    """4x4 rotation by ``angle`` (rad) about the z (hinge) axis."""
    m = np.eye(4)
    c, s = math.cos(angle), math.sin(angle)
    m[:2, :2] = [[c, -s], [s, c]]
    return m


def _bridge(solid: Any, rod: RodType, axis: np.ndarray, k: int) -> Any:
    """The piece with the fused joint at ``axis`` (x, y) bridged: the annulus fills the layer
    gaps out to the knuckle radius, then the pin hole is widened by the volume it added."""
    hg, t = rod.geometry.hinge, rod.geometry.thickness
    before = mass_properties(solid).volume
    rh, rk = hg.hole_diameter / 2, hg.knuckle_radius
    ring = one_solid(cylinder_solid(axis, rk, -t / 2, t / 2).cut(cylinder_solid(axis, rh, -t, t)), "an annulus")
    solid = one_solid(solid.fuse(ring).clean(), f"bridging fused joint {k}")
    added = mass_properties(solid).volume - before
    widened = math.sqrt(rh * rh + max(added, 0.0) / (math.pi * t))  # solid all through, out to rk, now
    if widened >= rk - 0.5:
        raise FabricationError(f"fused joint {k}: bridging it leaves less than 0.5 mm of knuckle around the pin hole")
    if widened > rh:
        solid = one_solid(solid.cut(cylinder_solid(axis, widened, -t, t)).clean(), f"widening fused joint {k}'s hole")
    return solid


def _roofs(piece_to_bed: np.ndarray, rods: Sequence[FabricatedRod], mats: Sequence[np.ndarray]) -> list[float]:
    """Per socket, the bed height of the first layer that reaches its (tilted) roof."""
    out = []
    for r, m in zip(rods, mats):
        socks = np.asarray(r.socket_centers, float).reshape(-1, 3)
        if not len(socks):
            continue
        to_bed = piece_to_bed @ m
        up = to_bed[:3, :3] @ np.array([0.0, 1.0, 0.0])  # the rod's +y: the silo's axis
        cos_a = float(up[2])
        top = socket_tops(r.socket_height, r.socket_radius, len(socks))  # roofs above the centres, along the axis
        lift = np.maximum(0.0, top * cos_a - r.socket_radius * math.sqrt(max(0.0, 1 - cos_a * cos_a)))
        out += [float(z) for z in socks @ to_bed[2, :3] + to_bed[2, 3] + lift]
    return out


def _common(rods: Sequence[FabricatedRod], label: str) -> None:
    """Refuse what one piece cannot hold: shot chambers, or balls of several kinds."""
    if any(r.fill_mass > 0 or r.chamber_volume > 0 for r in rods):
        raise PieceRefused(f"{label}: a rod with a fill chamber cannot be part of a fused piece (its chamber "
                               "would lean in the piece's print orientation); fuse without such rods")
    kinds = {(r.ball_diameter, r.ball_name, r.ball_mass_each) for r in rods if r.ball_count}
    if len(kinds) > 1:
        raise PieceRefused(f"{label}: its rods hold balls of {len(kinds)} kinds "
                               f"({', '.join(sorted(str(k[1] or k[0]) for k in kinds))}); one print pause "
                               "message per piece needs one kind")


def fuse_piece(rods: Sequence[FabricatedRod], points: np.ndarray, types: Sequence[RodType]) -> FabricatedPiece:
    """One solid of the fabricated ``rods`` of a fused run (see the module's doc).

    Args:
        rods: the run's rods as fabricated, in chain order (at least two).
        points: (len(rods) + 1, 2) their joints at rest (mm): the fused bends.
        types: the rod types (their hinges give the bridges).

    Returns:
        The piece; e.g. ``abs(p.mass - sum(r.mass for r in rods)) < 1e-6 * p.mass``.

    Raises:
        GeometryError: a boolean gave no single valid solid.
        FabricationError: the piece's mass or centre of mass is not its rods'.
        PieceRefused: the rods cannot be one piece (a fill chamber, balls of several kinds).
    """
    first, last = rods[0].index, rods[-1].index
    label = f"piece of rods {first}-{last}"
    pts = np.asarray(points, float)
    if len(rods) < 2 or pts.shape != (len(rods) + 1, 2):
        raise ValueError(f"{label}: {len(rods)} rods need ({len(rods) + 1}, 2) points, not {pts.shape}")
    _common(rods, label)
    world = rod_matrices(pts)
    inv0 = np.linalg.inv(world[0])
    mats = [inv0 @ w for w in world]
    solid = rods[0].solid
    for k in range(1, len(rods)):
        solid = one_solid(solid.fuse(placed(rods[k].solid, mats[k])).clean(), f"uniting {label}'s rods")
    bridges = []
    for k in range(1, len(rods)):
        axis = (inv0 @ np.array([*pts[k], 0.0, 1.0]))[:2]
        solid = _bridge(solid, types[k - 1], axis, rods[k - 1].index)
        bridges.append((float(axis[0]), float(axis[1])))
    if not is_valid_solid(solid):
        raise FabricationError(f"{label}: not one valid solid")
    solid.label = piece_stem(first, last)
    rho = rods[0].filament_mass / rods[0].plastic_volume
    props = mass_properties(solid)

    def frame(a: np.ndarray, m: np.ndarray) -> np.ndarray:
        a = np.asarray(a, float).reshape(-1, 3)
        return a @ m[:3, :3].T + m[:3, 3]

    socks = [frame(r.socket_centers, m) for r, m in zip(rods, mats)]
    metal = sum(r.ball_count * r.ball_mass_each for r in rods)
    moment = props.volume * rho * np.array(props.center[:2])
    moment += sum(r.ball_mass_each * s[:, :2].sum(axis=0) for r, s in zip(rods, socks) if len(s))
    mass = props.volume * rho + metal
    com = moment / mass
    want = sum(r.mass for r in rods)
    want_com = sum(r.mass * frame([*r.com, 0.0], m)[0, :2] for r, m in zip(rods, mats)) / want
    if abs(mass - want) > MASS_REL * want or np.hypot(*(com - want_com)) > COM_MM:
        raise FabricationError(f"{label}: the united solid weighs {mass:.6f} g with its centre of mass at "
                               f"({com[0]:.5f}, {com[1]:.5f}) mm, its rods {want:.6f} g at ({want_com[0]:.5f}, "
                               f"{want_com[1]:.5f}) mm")
    # lie on the side; turned so the rods with balls (else all rods) lean least from upright
    lean = [math.atan2(m[1, 0], m[0, 0]) for r, m in zip(rods, mats) if r.ball_count] or \
        [math.atan2(m[1, 0], m[0, 0]) for m in mats]
    turn = _turn(-(max(lean) + min(lean)) / 2)
    pm = print_matrix(placed(solid, turn)) @ turn
    roofs = sorted(_roofs(pm, rods, mats))
    levels: list[float] = []
    for z in roofs:
        if not levels or z - levels[-1] > 1e-6:
            levels.append(z)
    most = max(abs(x - (max(lean) + min(lean)) / 2) for x in lean)
    note = "; ".join(dict.fromkeys(r.print_note for r in rods if r.print_note))
    if len(mats) > 1 and max(abs(math.atan2(m[1, 0], m[0, 0])) for m in mats) > 1e-9:
        note = "; ".join(filter(None, [f"one piece of rods {first}-{last}, bent at its fused joints: it rests on "
                                       "its lowest point; add support under the parts that rise", note]))
    if most > math.radians(45) and levels:
        note += f"; its ball sockets lean up to {math.degrees(most):.0f} deg from upright"
    goal = sum(r.target_mass for r in rods)
    return FabricatedPiece(
        index=first, type_name=f"piece {first}-{last}", target_mass=goal, mass=mass, com=(float(com[0]), float(com[1])),
        plastic_volume=props.volume, filament_mass=props.volume * rho,
        cavity_count=sum(r.cavity_count for r in rods), cavity_radius=max(r.cavity_radius for r in rods),
        ball_count=sum(r.ball_count for r in rods),
        ball_diameter=next((r.ball_diameter for r in rods if r.ball_count), None),
        pause_z=levels[0] if levels else None, mass_error=(mass - want) / want,
        in_range=all(r.in_range for r in rods), message="; ".join(r.message for r in rods if r.message),
        solid=solid, cavity_centers=np.vstack([frame(r.cavity_centers, m) for r, m in zip(rods, mats)]),
        socket_centers=np.vstack(socks), socket_radius=max(r.socket_radius for r in rods),
        min_wall=min(r.min_wall for r in rods), layout="piece", print_matrix=pm, file_stem=piece_stem(first, last),
        print_note=note, thickness=max(r.thickness for r in rods), pin_diameter=rods[0].pin_diameter,
        pause_zs=tuple(levels), ball_name=next((r.ball_name for r in rods if r.ball_count), ""),
        ball_mass_each=next((r.ball_mass_each for r in rods if r.ball_count), 0.0),
        first=first, last=last, rods=list(rods), placements=mats, bridges=bridges, socket_roofs=tuple(roofs),
        turn_deg=math.degrees(-(max(lean) + min(lean)) / 2))


def fuse_pieces(fab: ChainFabrication, fused: Sequence[tuple[int, int]], points: np.ndarray,
                types: Sequence[RodType]) -> list[FabricatedPiece]:
    """Every fused run (first, last) of a chain as one piece (:func:`fuse_piece`), with the
    chain's joints ``points`` (N+1, 2) at rest; sets ``fab.pieces``."""
    pts = np.asarray(points, float)
    fab.pieces = [fuse_piece(fab.rods[a:b + 1], pts[a:b + 2], types[a:b + 1]) for a, b in fused]
    return fab.pieces


def as_printed_rods(fab: ChainFabrication) -> list[FabricatedRod]:
    """The chain's rods with the numbers of what is printed: a fused piece's rods keep their
    masses, and each rod's centre of mass moves by the difference between the piece's B-rep
    centre of mass and its rods' together (the same shift in the piece frame for all: the
    piece is one rigid body, so only its total mass and centre of mass shape the chain)."""
    out = list(fab.rods)
    for piece in fab.pieces:
        rods = piece.rods
        want = sum(r.mass for r in rods)
        mats = piece.placements
        have = sum(r.mass * (m[:2, :2] @ np.asarray(r.com, float) + m[:2, 3]) for r, m in zip(rods, mats)) / want
        shift = np.asarray(piece.com, float) - have  # piece frame
        for r, m in zip(rods, mats):
            com = np.asarray(r.com, float) + m[:2, :2].T @ shift  # into the rod's frame
            out[r.index] = replace(out[r.index], com=(float(com[0]), float(com[1])))
    return out
