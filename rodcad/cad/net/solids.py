"""The solids of a net: printed hubs with ball sockets, round rods with ball ends, cavities and
steel-ball sockets (the geometry of rodcad.catalog.net.node); what a built net holds
(:class:`NetSolids`, its distinct parts :class:`NetPart`). Built, written and assembled by
:mod:`rodcad.cad.net.build`.

Hub ``k`` (its own frame: origin the node point, axes the hub's at the target) is a sphere
less, per rod, a socket sphere ``ball + clearance`` across at its printed centre (the pivot
set back against the rod's pull, design.json's ``sockets``) and the opening cone (apex there,
half-angle ``cone_deg``, along the pivot's direction from the hub's centre). Rod ``e`` (its
frame: x from its pivot at node i to its pivot at node j, ``length`` apart) is a ball at each
pivot, a neck to the body, the round body, and inside it the steel balls' closed sockets in a
row at mid-length plus the cavity that trims the plastic to the designed mass (two equal
coaxial cylinders beside the row, or one at mid-length): symmetric, so its centre of mass stays
at mid-length.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from build123d import Axis, Edge, Face, Location, Plane, Solid, Wire

from rodcad.cad.export import export_step, import_step
from rodcad.cad.net.hub import split_plane
from rodcad.cad.solids import GeometryError, one_solid
from rodcad.design.net.frames import place, rod_matrix

__all__ = ["AS_BUILT_KKT", "NetPart", "NetSolids", "ball_positions", "end_ball", "fill_voids", "hub_solid",
           "net_rod_solid", "rod_body", "whole_hub"]


def _plane(origin, direction) -> Plane:
    """A plane at ``origin`` whose z axis is ``direction`` (its x axis any perpendicular)."""
    d = np.asarray(direction, float)
    d = d / np.linalg.norm(d)
    x = np.cross(d, [0.0, 0.0, 1.0]) if abs(d[2]) < 0.9 else np.cross(d, [1.0, 0.0, 0.0])
    x /= np.linalg.norm(x)
    return Plane(tuple(float(v) for v in origin), x_dir=tuple(float(v) for v in x), z_dir=tuple(float(v) for v in d))


def _socket_tool(rs: float, cone_deg: float, h: float) -> Solid:
    """A socket sphere of radius ``rs`` at the origin and its opening cone (apex at the origin,
    half-angle ``cone_deg``, along +z to z = ``h``) as one solid of revolution (no boolean)."""
    a = math.radians(cone_deg)
    ti, ri = rs * math.cos(a), rs * math.sin(a)
    top = h * math.tan(a)
    edges = [
        Edge.make_three_point_arc((0.0, 0.0, -rs), (rs, 0.0, 0.0), (ri, 0.0, ti)),
        Edge.make_line((ri, 0.0, ti), (top, 0.0, h)),
        Edge.make_line((top, 0.0, h), (0.0, 0.0, h)),
        Edge.make_line((0.0, 0.0, h), (0.0, 0.0, -rs)),
    ]
    face = Face(Wire(edges))
    return Solid.revolve(face, 360, Axis.Z)


def hub_solid(hw, sockets: np.ndarray, name: str = "hub", *, pole=None) -> Solid:
    """One hub: a sphere less a socket and an opening cone per rod.

    Args:
        hw: the :class:`rodcad.catalog.net.node.NodeHardware` (a hub).
        sockets: (k, 3) the sockets' printed centres in the hub's frame (mm); each opens
            along its centre's direction from the hub's centre.
        pole: the sphere's polar axis (its parametrisation only; default z): the normal of
            the plane the hub is cut along (:mod:`rodcad.cad.net.hub`), so that the cut meets
            no pole and the seam crosses it (a cut through the poles leaves faces that
            do not mesh closed).
    """
    tool = _socket_tool(hw.socket_radius, hw.cone_deg, hw.radius + 1.0)
    solid = Solid.make_sphere(hw.radius) if pole is None else Solid.make_sphere(hw.radius, _plane((0, 0, 0), pole))
    for c in np.asarray(sockets, float).reshape(-1, 3):
        placed = tool.moved(Location(_plane(c, c / np.linalg.norm(c))))
        solid = one_solid(solid.cut(placed).clean(), "cutting the hub's sockets")
    solid.label = name
    return solid


def whole_hub(hw, sockets: np.ndarray, name: str = "hub") -> Solid:
    """A hub printed whole (:func:`hub_solid`) whose STEP file re-imports as the solid built.

    The sphere's parametrisation (its pole) is free for a hub that is not cut; with some poles
    a socket's faces come back from STEP wrongly trimmed (a valid solid one socket fuller: 485
    mm^3 on a hung grid's hub), so the poles z, x, y and the sockets' plane normal are tried in
    turn until the solid's STEP round trip keeps its volume (to 1e-6)."""
    import tempfile

    socks = np.asarray(sockets, float).reshape(-1, 3)
    poles = [None, (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), split_plane(socks)[0]]
    with tempfile.TemporaryDirectory() as tmp:
        for pole in poles:
            s = hub_solid(hw, socks, name=name, pole=pole)
            path = Path(tmp) / "hub.step"
            export_step(s, path, name=name)
            if abs(import_step(path).volume - s.volume) <= 1e-6 * s.volume:
                return s
    raise GeometryError(f"{name}: no parametrisation of its sphere writes to STEP as built")


def end_ball(hw, x0: float, d: float) -> Solid:
    """A rod's end ball at ``x0`` on its axis, its neck leaving along ``d`` (+1 or -1, along x).

    The sphere's pole lies on the neck's axis, so the neck takes the pole away: with the pole
    across the neck (build123d's default z), FreeCAD 0.20 read every rod's STEP one ball's
    volume short (113.1 mm^3 for the 6 mm ball: the trimmed sphere face integrated as a hole),
    though OCC's own re-import agreed; with the pole on the neck both read it whole."""
    return Solid.make_sphere(hw.ball / 2, Plane((x0, 0, 0), z_dir=(d, 0, 0)))


def ball_positions(hw, length: float, balls: int, centre: float | None = None) -> np.ndarray:
    """(balls,) the steel balls' centres along a net rod (mm from its first pivot, on its
    axis): a row at mid-length (or at ``centre``), ``min_wall`` apart."""
    ds = hw.insert_diameter + hw.insert_clearance
    row = balls * ds + max(balls - 1, 0) * hw.min_wall
    c = length / 2 if centre is None else float(centre)
    return np.array([c - row / 2 + ds / 2 + k * (ds + hw.min_wall) for k in range(balls)], float)


def rod_body(hw, length: float) -> Solid:
    """A net rod's plastic before its voids, along +x, its pivots at x = 0 and ``length``: the
    round body, and for a hub's rod a ball (:func:`end_ball`) and a neck at each end."""
    r, e = hw.rod_diameter / 2, hw.end_offset
    parts = [Solid.make_cylinder(r, length - 2 * e, Plane((e, 0, 0), z_dir=(1, 0, 0)))]
    if hw.is_hub:
        for x0, d in ((0.0, 1.0), (length, -1.0)):
            parts.append(end_ball(hw, x0, d))
            parts.append(Solid.make_cylinder(hw.neck / 2, e + 0.5, Plane((x0, 0, 0), z_dir=(d, 0, 0))))
    return parts[0] if len(parts) == 1 else one_solid(parts[0].fuse(*parts[1:]).clean(), "joining a rod's ends")


def fill_voids(hw, z0: float, z1: float, balls: int, cavity: float) -> list[Solid]:
    """The voids that fill a rod's body between ``z0`` and ``z1`` along x (mm) to its mass: the
    steel balls' closed sockets in a row at the middle and the cavity (volume mm^3), two equal
    coaxial cylinders beside the row, or one at the middle
    (:meth:`rodcad.catalog.net.node.NodeHardware.zone_intervals`)."""
    r, w = hw.rod_diameter / 2, hw.min_wall
    c = (z0 + z1) / 2
    ds = hw.insert_diameter + hw.insert_clearance
    row = balls * ds + max(balls - 1, 0) * w
    voids = [Solid.make_sphere(ds / 2, Plane((float(cx), 0, 0))) for cx in ball_positions(hw, 0.0, balls, c)]
    area = math.pi * (r - w) ** 2
    if cavity > 1e-3 * area:  # (a cavity shorter than a thousandth of a mm is none)
        if balls:
            each = cavity / 2 / area
            for sgn in (-1.0, 1.0):
                start = c + sgn * (row / 2 + w)
                voids.append(Solid.make_cylinder(r - w, each, Plane((start if sgn > 0 else start - each, 0, 0),
                                                                    z_dir=(1, 0, 0))))
        else:
            lc = cavity / area
            voids.append(Solid.make_cylinder(r - w, lc, Plane((c - lc / 2, 0, 0), z_dir=(1, 0, 0))))
    return voids


def net_rod_solid(hw, length: float, balls: int, cavity: float, name: str = "rod") -> Solid:
    """One net rod along +x, its pivots at x = 0 and x = ``length``.

    Args:
        hw: the node hardware (ball, neck, rod diameter, walls, steel balls).
        length: pivot to pivot (mm).
        balls: steel balls in closed sockets in a row at mid-length.
        cavity: the cavity's volume (mm^3): two equal coaxial cylinders beside the balls,
            or one at mid-length (:meth:`rodcad.catalog.net.node.NodeHardware.rod_fill`).
    """
    solid = rod_body(hw, length)
    voids = fill_voids(hw, hw.end_offset, length - hw.end_offset, balls, cavity)
    if voids:
        solid = one_solid(solid.cut(*voids), "cutting a rod's cavity and ball sockets")
    solid.label = name
    return solid


#: The as-built net's equilibrium is read where the solver stopped short of round-off (its
#: iteration limit) when its KKT residual (the largest force imbalance over the largest
#: tension) is at most this: a millionth of a tension leaves a stable net microns from its
#: rest (a taut saddle grid stalled at 2.3e-8, 7.6e-5 mm from the design it re-solved).
AS_BUILT_KKT = 1e-6


@dataclass
class NetPart:
    """One distinct part of a net, built once (:mod:`rodcad.cad.net.parts`).

    Attributes:
        kind: 'rod' or 'hub'.
        label: its name, its first member's ('rod-003', 'hub-012').
        members: the rods' (or nodes') indices it is printed for.
        rotations: per member, R (3 x 3): the member is ``solids`` turned by R (hub frame).
        solids: what is printed (a rod; a hub whole, or its halves 'a' and 'b'), in the first
            member's frame, labelled ``<label>``, ``<label>-a``, ...
        print_matrices: per solid, its 4 x 4 onto the bed.
        files: per solid, {'.step': bytes, '.stl': bytes}, checked.
        mesh_volumes: per solid, its STL's volume (mm^3).
        split_reason: a hub printed whole: why ('' else).
        copies: per solid, how many each member needs (empty: one each; :class:`rodcad.cad.net.parts.
            PartResult`).
        whole: what hangs where it is not ``solids[0]``: a spliced rod's pieces joined (None else).
    """

    kind: str
    label: str
    members: list
    rotations: list
    solids: list
    print_matrices: list
    files: list
    mesh_volumes: list
    split_reason: str = ""
    copies: list = field(default_factory=list)
    whole: object = None

    @property
    def hanging(self):
        """The solid assembly.step places for each member: a rod whole (spliced: its pieces
        joined), else the first printed solid."""
        return self.whole if self.whole is not None else self.solids[0]

    @property
    def count(self) -> int:
        return len(self.members)

    def prints(self, i: int) -> int:
        """How many of solid ``i`` to print: its copies for every member."""
        return self.count * (int(self.copies[i]) if self.copies else 1)


@dataclass
class NetSolids:
    """The solids of a designed net and the net as built from them.

    Attributes:
        hubs: one solid per node (hub frame; None for a node no rod reaches), or [] for point
            nodes.
        rods: one solid per rod (rod frame).
        rod_masses: (m,) as built: plastic from the solid plus its steel balls (g).
        node_masses: (n,) hubs as built (g); node_com: (n, 3) their centres of mass (mm).
        as_built: the equilibrium with these masses (optimize.NetResult).
        error_mm, rel_size: its nodes and pivots against the design's simulated ones (NaN
            where the solver stopped with a KKT residual above :data:`AS_BUILT_KKT`).
        rod_balls: steel balls in each rod.
        hub_splits: per hub, its printed parts (:class:`rodcad.cad.net.hub.HubSplit`: two
            halves through its sockets' centres, where they take the balls).
        rod_com: (m, 3) each rod's centre of mass as built (rod frame, mm): a bent rod's measured
            on its solid (bowing toward -z), a straight rod's at mid-length.
        parts: the distinct parts (:class:`NetPart`), each written once; ``rods``, ``hubs`` and
            ``hub_splits`` hold every member's instance of them (shapes shared).
        deflection: (linear mm, angular rad) of the parts' STL and 3MF meshes.
        rod_fills: per rod, a spliced rod's pieces' (balls, cavity mm^3) as built (() for one piece).
    """

    hubs: list
    rods: list
    rod_masses: np.ndarray
    node_masses: np.ndarray
    node_com: np.ndarray
    as_built: object = None
    error_mm: float = float("nan")
    rel_size: float = float("nan")
    files: list = field(default_factory=list)
    rod_balls: list = field(default_factory=list)
    hub_splits: list = field(default_factory=list)
    rod_com: np.ndarray | None = None
    parts: list = field(default_factory=list)
    deflection: tuple = (0.03, 0.2)
    rod_fills: list = field(default_factory=list)

    @property
    def hub_parts(self) -> list:
        """Every printed hub part as (solid in its hub's frame, 4x4 laying it on the bed, needs
        support): the halves of each split hub on their cut faces, a hub left whole on support."""
        return [(p, m, not h.split) for h in self.hub_splits for p, m in zip(h.parts, h.print_matrices)]
