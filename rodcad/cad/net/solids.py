"""The solids of a net: printed hubs with ball sockets, round rods with ball ends, cavities and
steel-ball sockets, their files and the assembly (the geometry of rodcad.catalog.net.node).

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

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from build123d import Axis, CenterOf, Edge, Face, Location, Plane, Solid, Wire

from rodcad.cad.export import AssemblyPart, check_files, export_assembly, export_step, export_stl, import_step
from rodcad.cad.net.bent import bent_rod_solid, bent_socket_centres
from rodcad.cad.net.hub import HubSplit, split_hub, split_plane, splittable_sockets
from rodcad.cad.solids import GeometryError, one_solid
from rodcad.parallel import default_jobs, worker_pool

#: STL deflection of net parts (mm): a rod's 9 mm cylinder needs a finer mesh than a chain's
#: rods for its STL to hold the solid's volume well within 0.1 % (meshed to 0.004 mm it is
#: 0.1 % short); a hub (a larger sphere, its volume larger for its area) is meshed as a
#: chain's rods are, a finer mesh of its socket cones failing to weld closed.
ROD_DEFLECTION = 0.0015
HUB_DEFLECTION = 0.004

__all__ = ["AS_BUILT_KKT", "HUB_DEFLECTION", "PARTS_PER_WORKER", "ROD_DEFLECTION", "NetSolids", "ball_positions", "build_net_solids", "hub_solid", "net_rod_solid", "rod_matrix", "whole_hub",
           "write_net_files"]


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


def ball_positions(hw, length: float, balls: int) -> np.ndarray:
    """(balls,) the steel balls' centres along a net rod (mm from its first pivot, on its
    axis): a row at mid-length, ``min_wall`` apart."""
    ds = hw.insert_diameter + hw.insert_clearance
    row = balls * ds + max(balls - 1, 0) * hw.min_wall
    return np.array([length / 2 - row / 2 + ds / 2 + k * (ds + hw.min_wall) for k in range(balls)], float)


def net_rod_solid(hw, length: float, balls: int, cavity: float, name: str = "rod") -> Solid:
    """One net rod along +x, its pivots at x = 0 and x = ``length``.

    Args:
        hw: the node hardware (ball, neck, rod diameter, walls, steel balls).
        length: pivot to pivot (mm).
        balls: steel balls in closed sockets in a row at mid-length.
        cavity: the cavity's volume (mm^3): two equal coaxial cylinders beside the balls,
            or one at mid-length (:meth:`rodcad.catalog.net.node.NodeHardware.rod_fill`).
    """
    r, w = hw.rod_diameter / 2, hw.min_wall
    e = hw.end_offset
    body = length - 2 * e
    parts = [Solid.make_cylinder(r, body, Plane((e, 0, 0), z_dir=(1, 0, 0)))]
    if hw.is_hub:
        for x0, d in ((0.0, 1.0), (length, -1.0)):
            parts.append(Solid.make_sphere(hw.ball / 2, Plane((x0, 0, 0))))
            parts.append(Solid.make_cylinder(hw.neck / 2, e + 0.5, Plane((x0, 0, 0), z_dir=(d, 0, 0))))
    solid = parts[0] if len(parts) == 1 else one_solid(parts[0].fuse(*parts[1:]).clean(), "joining a rod's ends")
    ds = hw.insert_diameter + hw.insert_clearance
    row = balls * ds + max(balls - 1, 0) * w
    voids = [Solid.make_sphere(ds / 2, Plane((float(cx), 0, 0))) for cx in ball_positions(hw, length, balls)]
    area = math.pi * (r - w) ** 2
    if cavity > 1e-3 * area:  # (a cavity shorter than a thousandth of a mm is none)
        if balls:
            each = cavity / 2 / area
            for sgn in (-1.0, 1.0):
                start = length / 2 + sgn * (row / 2 + w)
                voids.append(Solid.make_cylinder(r - w, each, Plane((start if sgn > 0 else start - each, 0, 0),
                                                                    z_dir=(1, 0, 0))))
        else:
            lc = cavity / area
            voids.append(Solid.make_cylinder(r - w, lc, Plane((length / 2 - lc / 2, 0, 0), z_dir=(1, 0, 0))))
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

    @property
    def hub_parts(self) -> list:
        """Every printed hub part as (solid in its hub's frame, 4x4 laying it on the bed, needs
        support): the halves of each split hub on their cut faces, a hub left whole on support."""
        return [(p, m, not h.split) for h in self.hub_splits for p, m in zip(h.parts, h.print_matrices)]


def build_net_solids(check, *, progress=None) -> NetSolids:
    """Every hub and rod of a :class:`rodcad.design.net.check.NetCheck`, and the net re-solved
    with the solids' masses and centres of mass.

    Args:
        check: the designed net (each rod's balls and cavity from NodeHardware.rod_fill).
        progress: a progress step (``count``) or None.
    """
    from optimize import solve_net

    plan = check.plan
    t, hw = plan.target, plan.hardware
    ball_mass = hw.insert_density * math.pi / 6 * hw.insert_diameter ** 3 / 1000.0
    rho = hw.density / 1000.0
    rods, rod_masses, rod_balls = [], np.zeros(t.m), []
    total = t.m + (t.n if hw.is_hub else 0)
    arcs, flen = plan.arcs, plan.fill_lengths
    rod_com = np.column_stack([plan.lengths / 2, np.zeros((t.m, 2))])
    for e in range(t.m):
        k, cavity, _ = hw.rod_fill(float(flen[e]), float(check.masses[e]))
        if arcs[e] is None:
            s = net_rod_solid(hw, float(plan.lengths[e]), k, cavity, name=f"rod-{e:03d}")
        else:  # measured on the solid: its plastic's centre of mass and its steel balls
            s = bent_rod_solid(hw, arcs[e], k, cavity, name=f"rod-{e:03d}")
            moment = rho * s.volume * np.array(tuple(s.center(CenterOf.MASS)))
            moment += ball_mass * bent_socket_centres(hw, arcs[e], k).sum(axis=0)
            rod_com[e] = moment / (rho * s.volume + k * ball_mass)
        rods.append(s)
        rod_balls.append(int(k))
        rod_masses[e] = rho * s.volume + k * ball_mass
        if progress is not None:
            progress.count(e + 1, total)
    hubs, splits = [], []
    node_masses, node_com = plan.node_masses.copy(), plan.node_com.copy()
    if hw.is_hub:
        for k in range(t.n):
            at = [(e, c) for c in (0, 1) for e in np.flatnonzero(t.edges[:, c] == k)]
            socks = np.array([check.sockets[e, c] for e, c in at]).reshape(-1, 3)
            if not at:  # an anchor no rod reaches (a boundary-held grid's corner): no hub to print
                hubs.append(None)
                splits.append(HubSplit([], [], np.array([0.0, 0.0, 1.0]), 0.0, 0.0))
                continue
            piv = np.array([plan.pivots[e, c] for e, c in at]).reshape(-1, 3)
            socks, clear = splittable_sockets(socks, piv, hw.clearance, hw.ball)
            hwk = plan.hub(k)  # its own size of the catalog's hub family
            hwk = hwk if clear == hw.clearance else dataclasses.replace(hwk, clearance=clear)
            s = hub_solid(hwk, socks, name=f"hub-{k:03d}", pole=split_plane(socks)[0])
            split = split_hub(s, socks, hwk, s.label)
            if not split.split:  # printed whole: a sphere's parametrisation that writes to STEP as built
                s = whole_hub(hwk, socks, name=s.label)
                split.parts = [s]
            hubs.append(s)
            splits.append(split)
            node_masses[k] = rho * s.volume
            node_com[k] = np.array(tuple(s.center(CenterOf.MASS)))
            if progress is not None:
                progress.count(t.m + k + 1, total)
    eq = check.equilibrium
    res = solve_net(eq.positions, t.edges, plan.lengths, rod_masses, t.anchored, node_masses=node_masses,
                    node_com=node_com, pivots=plan.pivots, node_rotations0=eq.rotations,
                    com=rod_com if plan.bent else None)
    out = NetSolids(hubs, rods, rod_masses, node_masses, node_com, res, rod_balls=rod_balls, hub_splits=splits,
                    rod_com=rod_com)
    if res.success or (np.isfinite(res.kkt_residual) and res.kkt_residual <= AS_BUILT_KKT
                       and np.all(np.isfinite(res.positions))):
        err = max(float(np.max(np.linalg.norm(res.positions - eq.positions, axis=1))),
                  float(np.max(np.linalg.norm(res.ends - eq.ends, axis=2))))
        out.error_mm, out.rel_size = err, err / t.size
    return out


def _matrix(R: np.ndarray, origin: np.ndarray) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = R
    m[:3, 3] = origin
    return m


def rod_matrix(p0: np.ndarray, p1: np.ndarray) -> np.ndarray:
    """4 x 4: the rod frame (:func:`_rod_frame`) placed at its first pivot ``p0``, as
    assembly.step and the 3D view place a net's rods."""
    return _matrix(_rod_frame(p0, p1), p0)


def _rod_frame(p0: np.ndarray, p1: np.ndarray) -> np.ndarray:
    """The rod frame in the world: x along the chord, y horizontal, z = x cross y the upward
    side of the chord (a bent rod, bowing toward -z, hangs so)."""
    x = (p1 - p0) / np.linalg.norm(p1 - p0)
    y = np.cross([0.0, 0.0, 1.0], x)
    if np.linalg.norm(y) < 1e-9:
        y = np.cross([0.0, 1.0, 0.0], x)
    y /= np.linalg.norm(y)
    return np.column_stack([x, y, np.cross(x, y)])


#: Parts written per worker process at least (fewer: written in this process).
PARTS_PER_WORKER = 8


def _write_part(item) -> None:
    """Write one part's STEP and STL and check them (a worker process's task)."""
    solid, label, step, stl, defl = item
    export_step(solid, step, name=label)
    export_stl(solid, stl, tolerance=defl)
    check_files(step, stl, solid.volume, deflection=defl)


def write_net_files(check, solids: NetSolids, folder: Path, *, name: str, progress=None) -> list[str]:
    """rods/rod-NNN.step/.stl, hubs/hub-NNN-a.step/.stl and -b (each hub's halves; hub-NNN
    for a hub left whole) (each checked: the STEP re-imports as one valid solid of the same
    volume, the STL is watertight) and assembly.step: every part a named solid where the
    designed net hangs, rods coloured light (blue) to heavy (red)."""
    import matplotlib

    written, items = [], []
    hub_parts = [p for p, _, _ in solids.hub_parts] if solids.hub_splits else solids.hubs
    for sub, parts, defl in (("rods", solids.rods, ROD_DEFLECTION), ("hubs", hub_parts, HUB_DEFLECTION)):
        if parts:
            (folder / sub).mkdir(exist_ok=True)
        for s in parts:
            step, stl = folder / sub / f"{s.label}.step", folder / sub / f"{s.label}.stl"
            items.append((Solid(s.wrapped), s.label, step, stl, defl))  # the bare shape: it pickles
            written += [str(step.relative_to(folder)), str(stl.relative_to(folder))]
    jobs = max(1, min(default_jobs(), len(items) // PARTS_PER_WORKER))
    pool = worker_pool(jobs) if jobs > 1 else None
    try:
        done = pool.map(_write_part, items, chunksize=2) if pool is not None else map(_write_part, items)
        for k, _ in enumerate(done):
            if progress is not None:
                progress.count(k + 1, len(items))
    finally:
        if pool is not None:
            pool.shutdown()
    eq = check.equilibrium
    m = solids.rod_masses
    norm = matplotlib.colors.Normalize(float(m.min()), float(m.max()) if m.max() > m.min() else float(m.min()) + 1e-9)
    cmap = matplotlib.colormaps["coolwarm"]
    nodes = []
    for e, s in enumerate(solids.rods):
        p0, p1 = eq.ends[e]
        color = tuple(float(c) for c in cmap(norm(m[e]))[:3])
        nodes.append(AssemblyPart(s.label, s, rod_matrix(p0, p1), color))
    for k, s in enumerate(solids.hubs):
        for i, p in enumerate(solids.hub_splits[k].parts if solids.hub_splits else [s]):
            grey = 0.8 - 0.15 * i  # the halves of a hub in two greys
            nodes.append(AssemblyPart(p.label, p, _matrix(eq.rotations[k], eq.positions[k]), (grey, grey, grey)))
    if not nodes:  # pragma: no cover - a net has rods
        raise GeometryError("nothing to assemble")
    export_assembly(folder / "assembly.step", nodes, name=name)
    written.append("assembly.step")
    return written
