"""Building every rod: cavities and ball sockets cut into the exact B-rep so every printed rod
has its designed mass, and the rods' STEP/STL files and assembly.

The data flow for one rod (type + target mass), one step per function (the numbers in
:mod:`rodcad.fabrication`, the solids here):

    type     -> achievable_intervals(): once per type (disk-cached), every symmetric ball
                               subset of the type's socket layout and the cavity volumes its
                               layouts can remove: the reachable masses, narrow bands above
                               the solid
    target   -> plan_rod():       clip to the type's mass range [m_min, m_max]
                               (:mod:`rodcad.catalog.massrange`); look up the ball sockets and
                               the cavity volume left to remove in that table (a target in a
                               gap: the nearest reachable mass, reported)
             -> place_cavities():   cavity centres by Poisson-disk (blue-noise) dart throwing
                               on a seeded candidate pool, every dart thrown with all its
                               mirror images about the centre of mass; the symmetric lattice
                               of :mod:`rodcad.catalog.massrange` is the fallback when the
                               blue-noise layouts cannot remove enough
             -> _build():      the cavity radius tuned by a Newton/secant root solve on the
                               exact B-rep volume (the analytic volume is the start; 1-2
                               booleans), walls measured on the B-rep (BRepExtrema), mass and
                               centre of mass from the B-rep plus the balls
    chain    -> fabricate_chain(): identical (type, mass, holes) built once, distinct
                               rods in worker processes (one task per type), disk-cached
             -> rodcad.cad.chainfiles: STEP/STL, checked on re-read, and the assembly

Void shapes (all printable without support in the print orientation, see
:data:`rodcad.fabrication.layout.VOIDS`): cavities are spheres cut flat at 45 degrees ('capped'),
sockets are 'silos' (half sphere + cylinder, flat bridged roof) standing in rows, one pause per
row; given the print's layers, :func:`fabricate_chain` raises rows' roofs onto layers the chain's
other rods share (:mod:`rodcad.fabrication.roofs`), so a plate of them pauses seldom. Every layout is symmetric about the rod's centre of mass (mirrors across x, y and z, or the
half turn about the com axis with the z mirror; sockets are raised by
:func:`rodcad.fabrication.layout.ball_offset` so socket and ball together act at their site), so
the centre of mass stays where the design assumes.

Print orientation: every rod lies on its side, the rod frame's -y face on the bed and +y up
(:data:`rodcad.cad.export.PRINT_ROTATION`): hinge layers and pin holes build without support.
Curved rods rest on their arc's lowest point (:attr:`FabricatedRod.print_note`). The pin holes
may sit off the hinge axes (``holes``: the pin-play compensation). Units: mm, mm^3, g; g/cm^3.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from rodcad.catalog.cache import DiskCache, make_key
from rodcad.catalog.massrange import MASSRANGE_VERSION
from rodcad.fabrication.layout import UP
from rodcad.parallel import default_jobs, kept, worker_pool

if TYPE_CHECKING:  # pragma: no cover
    from rodcad.catalog.model import RodType
    from rodcad.fabrication.layers import LayerGrid
from rodcad.cad.export import check_files, print_matrix, rod_matrices
from rodcad.cad.solids import (NO_SHIFT, OWN_SIZES, Holes, PortableSolid, Sizes, hole_volume_change, mass_properties,
                               share_type_solid, type_solid, with_voids)
from rodcad.colors import mass_colors
from rodcad.fabrication.cavities import (
    CAPPED_K,
    FABRICATE_VERSION,
    MASS_TOL,
    POOL_SIZE,
    RADIUS_FACTOR,
    SOLVE_TOL,
    FabricationError,
)
from rodcad.fabrication.intervals import compute_table, interval_table, intervals_key
from rodcad.fabrication.plan import Measurement, RodPlan, RoofPlan, plan_rod
from rodcad.fabrication.roofs import shared_roofs

__all__ = [
    "ChainFabrication",
    "check_files",
    "fabricate_chain",
    "fabricate_rod",
    "FabricatedRod",
    "mass_colors",
    "rod_matrices",
]


@dataclass
class FabricatedRod:
    """One printed rod as built.

    Attributes:
        index: chain position (0-based, as in design.json).
        type_name: rod type.
        target_mass: mass asked for (g), before clipping to the range.
        mass: as-built mass (g): plastic volume x density + balls.
        com: as-built centre of mass (along, perp) in the rod frame (mm).
        plastic_volume: printed volume (mm^3) from the final B-rep.
        filament_mass: plastic mass (g).
        cavity_count: number of cavities.
        cavity_radius: their radius (mm), 0 without cavities.
        ball_count: number of metal balls.
        ball_diameter: ball diameter (mm) or None without balls.
        pause_z: print height (mm above the bed) of the (lowest) socket
            roofs: pause when the print reaches it, drop the balls in, resume;
            None without balls.
        pause_zs: every distinct roof height (mm), lowest first: sockets in
            several rows need one pause per row.
        mass_error: (mass - clipped target) / clipped target.
        in_range: whether the target was achievable.
        message: '' or why not, and what would be needed.
        solid: final solid in the rod frame (build123d ``Solid``).
        cavity_centers: (n, 3) cavity centres (mm, rod frame).
        socket_centers: (k, 3) socket centres (mm, rod frame) = ball centres.
        socket_radius: socket radius (mm), 0 without balls.
        min_wall: thinnest wall measured on the B-rep around the voids (mm;
            inf without voids).
        layout: how the cavities were placed: 'poisson/<symmetry>',
            'lattice/<symmetry>' or ''.
        print_matrix: 4x4 placing the rod-frame solid on the bed (mm).
        file_stem: 'NN_TYPE' (NN the 0-based index, two digits or more).
        print_note: remark on the print orientation ('' for flat-lying rods).
        thickness: rod thickness along the hinge axes (mm), the pin length.
        pin_diameter: hinge pin diameter (mm).
        socket_height: the sockets' flat roofs above their centres (mm); 0: the socket
            radius (plain silos); a tuple: one per socket (rows raised unequally). Raised
            roofs share a print layer with the chain's others (:mod:`rodcad.fabrication.roofs`).
        fill_mass: grams of shot poured into the chamber at ``pause_z`` (rods with a fill).
        fill_name: what the shot is ('' without).
        chamber_volume: the chamber's volume (mm^3; 0 without).
        ball_name: the kind of the balls (catalog name, e.g. 'tungsten carbide ball 6 mm';
            '' without balls).
        ball_mass_each: mass of one ball (g; 0 without balls).
        holes: each pin hole's centre minus its hinge axis (mm, rod frame): the pin-play
            compensation (:func:`rodcad.cad.solids.build_rod`).
        hole_sizes: each pin hole's diameter where the joint hardware's differs from the
            hinge's own (mm; None: the hinge's own).
        mesh: the closed mesh its STL was written from, in the rod frame (None until
            :func:`rodcad.cad.chainfiles.write_rod_files` wrote it): the print files place it
            instead of meshing the solid again.
    """

    index: int
    type_name: str
    target_mass: float
    mass: float
    com: tuple[float, float]
    plastic_volume: float
    filament_mass: float
    cavity_count: int
    cavity_radius: float
    ball_count: int
    ball_diameter: float | None
    pause_z: float | None
    mass_error: float
    in_range: bool
    message: str
    solid: Any = field(repr=False)
    cavity_centers: np.ndarray = field(repr=False)
    socket_centers: np.ndarray = field(repr=False)
    socket_radius: float = 0.0
    min_wall: float = math.inf
    layout: str = ""
    print_matrix: np.ndarray = field(default_factory=lambda: np.eye(4), repr=False)
    file_stem: str = ""
    print_note: str = ""
    thickness: float = 0.0
    pin_diameter: float = 0.0
    pause_zs: tuple[float, ...] = ()
    fill_mass: float = 0.0
    fill_name: str = ""
    chamber_volume: float = 0.0
    ball_name: str = ""
    ball_mass_each: float = 0.0
    socket_height: float | tuple[float, ...] = 0.0
    holes: Holes = NO_SHIFT
    hole_sizes: Sizes = OWN_SIZES
    mesh: Any = field(default=None, repr=False, compare=False)


@dataclass
class ChainFabrication:
    """Every rod of a chain as built.

    Attributes:
        rods: one per chain position (identical rods share their solid).
        pieces: runs of fused rods printed as one solid each (``FabricatedPiece``).
        problems: one sentence per out-of-range rod.
        distinct: how many distinct rods were built.
        time_s: wall time (s).
    """

    rods: list[FabricatedRod]
    problems: list[str]
    distinct: int = 0
    time_s: float = 0.0
    pieces: list[Any] = field(default_factory=list)  # fused runs as one solid (rodcad.cad.pieces)

    @property
    def parts(self) -> list[FabricatedRod]:
        """What is printed, by first rod: every piece (fused rods, see :mod:`rodcad.cad.pieces`)
        and every rod in none."""
        inside = {i for p in self.pieces for i in range(p.first, p.last + 1)}
        return sorted([*self.pieces, *(r for r in self.rods if r.index not in inside)], key=lambda r: r.index)


def _build(rod: RodType, plan: RodPlan) -> tuple[Any, float, Measurement]:
    """The B-rep for a plan, with the cavity radius root-solved on its volume.

    Returns:
        (solid, cavity radius, measurements).
    """
    from rodcad.cad.collision import void_walls
    from rodcad.cad.solids import mass_properties, void_solids, with_voids

    rho = rod.material.density / 1000.0
    plain = type_solid(rod)
    socks, cavs = plan.sockets, plan.cavities
    n_balls = len(socks)
    kind = rod.ball_kinds[plan.ball_kind] if n_balls else None
    metal = n_balls * kind.mass if kind is not None else 0.0
    target = plan.build_mass

    def make(r: float) -> Any:
        return with_voids(plain, plan.silo_groups(r), rod.name)

    r = plan.cavity_radius
    solid = make(r)
    volume = mass_properties(solid).volume
    booleans = 1
    if len(cavs):
        bound = plan.cavity_bound
        for _ in range(4):  # Newton on the B-rep volume, analytic derivative
            err = (volume * rho + metal - target) / target
            if abs(err) <= SOLVE_TOL:
                break
            dm_dr = -rho * len(cavs) * 3 * CAPPED_K * r * r
            r = min(r - err * target / dm_dr, bound)
            solid = make(r)
            volume = mass_properties(solid).volume
            booleans += 1
    props = mass_properties(solid)
    voids = [v for group in plan.silo_groups(r) for v in void_solids(*group)]
    wall = math.inf
    if voids:
        to_faces, between = void_walls(plain, voids, rod.material.min_wall + 1.0)
        wall = min(float(to_faces.min()), between)
    c = np.array(props.center) * props.volume * rho
    if kind is not None:
        c = c + kind.mass * socks.sum(axis=0)
    mass = props.volume * rho + metal
    com = c / mass
    return solid, r, Measurement(float(props.volume), float(mass), (float(com[0]), float(com[1])), float(wall),
                                 booleans)


def _key(rod: RodType, target: float, seed: int, roof: RoofPlan | None = None) -> str:
    from rodcad.catalog.model import GEOMETRY_VERSION

    raised = () if roof is None else roof.key()
    return make_key("fab", FABRICATE_VERSION, MASSRANGE_VERSION, GEOMETRY_VERSION, POOL_SIZE, RADIUS_FACTOR,
                    rod.geometry.key_data(), rod.material.key_data(),
                    rod.balls_json(), round(float(target), 9), int(seed), *raised)


def _fabricate_star(args: tuple[RodType, float, int, dict[str, Any] | None, RoofPlan | None]
                    ) -> dict[str, Any]:
    """Worker: plan, build, root-solve and measure one rod (its sockets' roofs raised to
    ``roof`` where given, kept plain where the B-rep then measures a wall under the
    minimum); returns numbers only."""
    rod, target, seed, table, roof = args
    plan = plan_rod(rod, target, seed, table, roof=roof)
    _, plan.cavity_radius, plan.measured = _build(rod, plan)
    if plan.socket_height and plan.measured.min_wall < rod.material.min_wall - 1e-6:
        plan = plan_rod(rod, target, seed, table)
        _, plan.cavity_radius, plan.measured = _build(rod, plan)
    return plan.to_json()


def _type_star(args: tuple[RodType, list[tuple[float, RoofPlan | None, Holes, Sizes]], int, dict[str, Any] | None]
               ) -> tuple[dict[str, Any], list[tuple[dict[str, Any], FabricatedRod]], PortableSolid]:
    """Worker: the type's table of reachable masses (unless given), then every
    rod of that type (the type's candidate pools are built once per worker): its solved
    plan and the rod built from it with its pin holes (:func:`_assemble_result`; the solid
    comes back pickled, BinTools' exact B-rep); and the type's plain solid (the anchor
    fixture's checks place it)."""
    rod, targets, seed, table = args
    table = table if table is not None else compute_table(rod, seed)
    out = []
    for m, roof, holes, sizes in targets:
        plan = _fabricate_star((rod, m, seed, table, roof))
        built = _assemble_result(rod, m, 0, plan, holes, sizes)
        out.append((plan, dataclasses.replace(built, solid=PortableSolid(built.solid))))
    return table, out, PortableSolid(type_solid(rod))


def fabricate_rod(rod: RodType, target: float, *, index: int = 0, seed: int = 0,
                  cache: DiskCache | None = None, _plan_data: dict[str, Any] | None = None) -> FabricatedRod:
    """Fabricate one rod (see :func:`fabricate_chain`)."""

    if rod.fill is not None:
        return FabricatedRod(**{**_filled_result(rod, target).__dict__, "index": index,
                                "file_stem": f"{index:02d}_{rod.name}"})
    cache = cache if cache is not None else DiskCache()
    plan = _plan_data
    if plan is None:
        key = _key(rod, target, seed)
        plan = cache.get("fab", key)
        if plan is None:
            plan = _fabricate_star((rod, target, seed, interval_table(rod, seed, cache), None))
            cache.put("fab", key, plan)
    return _assemble_result(rod, target, index, plan)


def _assemble_result(rod: RodType, target: float, index: int, data: dict[str, Any],
                     holes: Holes = NO_SHIFT, sizes: Sizes = OWN_SIZES) -> FabricatedRod:
    """Rebuild the solid from a solved plan (one boolean; the pin holes moved by ``holes``,
    which keeps the volume and moves the centre of mass a little, and of the diameters
    ``sizes``, the joint hardware's, which change the volume by the knuckles' annuli) and
    collect the numbers."""
    plan = RodPlan.from_json(data)
    rho = rod.material.density / 1000.0
    socks, cavs, rs, r = plan.sockets, plan.cavities, plan.socket_radius, plan.cavity_radius
    solid = with_voids(type_solid(rod, holes, sizes), plan.silo_groups(), rod.name)
    meas = plan.measured
    if meas is None:
        raise FabricationError(f"rod {index} ({rod.name}): its plan was never built")
    props = mass_properties(solid)
    volume = props.volume
    cut = hole_volume_change(rod.geometry, sizes)  # 0 for the hinge's own holes
    if abs(volume - (meas.volume - cut)) > 1e-6 * meas.volume:
        raise FabricationError(f"rod {index} ({rod.name}): rebuilt volume {volume} differs from the solved "
                               f"{meas.volume} mm^3" + (f" less its hardware's holes' {cut:.4g} mm^3" if cut else ""))
    wall = rod.material.min_wall
    if meas.min_wall < wall - 1e-6:
        raise FabricationError(f"rod {index} ({rod.name}): a wall of {meas.min_wall:.3f} mm around a void is "
                               f"thinner than the minimum {wall} mm")
    kind = rod.ball_kinds[plan.ball_kind] if len(socks) else None
    com = meas.com
    metal = kind.mass * len(socks) if kind else 0.0
    if holes != NO_SHIFT or sizes != OWN_SIZES:  # measured again: the plan's solid had its own holes on the axes
        c = np.array(props.center[:2]) * volume * rho + (kind.mass * socks.sum(axis=0)[:2] if kind else 0.0)
        com = (float(c[0] / (volume * rho + metal)), float(c[1] / (volume * rho + metal)))
    pm = print_matrix(solid)
    roofs: list[float] = []
    for z in sorted(socks @ UP + plan.socket_tops + pm[2, 3]):  # rod +y is bed +Z
        if not roofs or z - roofs[-1] > 1e-6:
            roofs.append(float(z))
    pause = roofs[0] if roofs else None
    goal = plan.mass - cut * rho  # the plan's mass is for the hinge's own holes
    mass = meas.mass if not cut else volume * rho + metal
    if abs(mass - goal) > MASS_TOL * goal:
        raise FabricationError(f"rod {index} ({rod.name}): built {mass:.4f} g for {goal:.4f} g")
    note = _print_note(rod)
    return FabricatedRod(
        index=index, type_name=rod.name, target_mass=float(target), mass=mass,
        com=com, plastic_volume=volume, filament_mass=volume * rho, cavity_count=len(cavs), cavity_radius=r if len(cavs) else 0.0,
        ball_count=len(socks), ball_diameter=kind.diameter if kind is not None else None,
        ball_name=kind.name if kind is not None else "", ball_mass_each=kind.mass if kind is not None else 0.0,
        pause_z=pause, mass_error=(mass - goal) / goal, in_range=not plan.message, message=plan.message,
        solid=solid, cavity_centers=cavs, socket_centers=socks, socket_radius=rs if len(socks) else 0.0,
        min_wall=meas.min_wall, layout=plan.layout, print_matrix=pm,
        file_stem=f"{index:02d}_{rod.name}", print_note=note, thickness=rod.geometry.thickness,
        pin_diameter=rod.geometry.hinge.pin_diameter, pause_zs=tuple(roofs), socket_height=plan.socket_height,
        holes=holes, hole_sizes=sizes)


def _filled_result(rod: RodType, target: float, holes: Holes = NO_SHIFT, sizes: Sizes = OWN_SIZES) -> FabricatedRod:
    """A rod with a fill: its chamber cut, checked and measured (:mod:`rodcad.cad.filled`), its
    pin holes moved by ``holes`` and of the joint hardware's ``sizes``."""
    from rodcad.cad.filled import build_filled

    b = build_filled(rod, target, holes, sizes)
    if b.min_wall < rod.material.min_wall - 1e-6:
        raise FabricationError(f"{rod.name}: a wall of {b.min_wall:.3f} mm around its chamber is thinner than "
                               f"the minimum {rod.material.min_wall} mm")
    if abs(b.mass - b.goal) > MASS_TOL * b.goal:
        raise FabricationError(f"{rod.name}: built {b.mass:.4f} g for {b.goal:.4f} g")
    pm = print_matrix(b.solid)
    c = b.chamber
    pause = None if c is None or not c.filled else float(c.roof_y + pm[2, 3])  # rod +y is bed +Z
    rho = rod.material.density / 1000.0
    return FabricatedRod(
        index=0, type_name=rod.name, target_mass=float(target), mass=b.mass, com=b.com, plastic_volume=b.volume,
        filament_mass=b.volume * rho, cavity_count=0, cavity_radius=0.0, ball_count=0, ball_diameter=None,
        pause_z=pause, mass_error=(b.mass - b.goal) / b.goal, in_range=not b.message, message=b.message,
        solid=b.solid, cavity_centers=np.zeros((0, 3)), socket_centers=np.zeros((0, 3)), min_wall=b.min_wall,
        layout="chamber/filled" if c is not None and c.filled else ("chamber/empty" if c is not None else ""),
        print_matrix=pm, file_stem=f"00_{rod.name}", print_note=_print_note(rod), thickness=rod.geometry.thickness,
        pin_diameter=rod.geometry.hinge.pin_diameter, pause_zs=() if pause is None else (pause,),
        fill_mass=c.fill_mass if c is not None else 0.0, fill_name=rod.fill.name if rod.fill else "",
        chamber_volume=c.volume if c is not None else 0.0, holes=holes, hole_sizes=sizes)


def _print_note(rod: RodType) -> str:
    """How a curved rod lies on the bed ('' for a straight one)."""
    g = rod.geometry
    if g.curvature == 0:
        return ""
    sag = (1 - math.cos(math.radians(abs(g.half_angle_deg)))) / abs(g.curvature)
    return (f"curved: rests on its arc's lowest point, the ends rise {sag:.1f} mm (the underside overhangs up "
            f"to {abs(g.half_angle_deg):.0f} deg from the bed; add support under the ends)")


def fabricate_chain(types: Sequence[RodType], masses: Sequence[float], *, seed: int = 0, jobs: int | None = None,
                    progress: Callable[[int, int], None] | None = None,
                    cache: DiskCache | None = None, layers: LayerGrid | None = None,
                    keep_roofs: Collection[int] = (), holes: Sequence[Holes] | None = None,
                    sizes: Sequence[Sizes] | None = None) -> ChainFabrication:
    """Cavities and ball sockets for every rod of a chain, built on the B-rep.

    Identical rods (same type, same target mass to 1 microgram) are built
    once and share their solid; distinct ones are solved in ``jobs`` worker
    processes (default: the CPUs) and cached on disk. Out-of-range targets are
    clipped to the type's range, built, and reported in ``problems``. Given the
    print's ``layers``, the sockets' roofs are raised onto as few shared layers as the
    rods allow (:func:`rodcad.fabrication.roofs.shared_roofs`), so the chain's prints
    pause seldom; masses and centres of mass stay.

    Args:
        types: rod type per chain position.
        masses: target mass per position (g).
        seed: seed of the Poisson-disk layouts (same input, same output).
        jobs: worker processes.
        progress: called with (done, total) distinct rods.
        cache: disk cache (default :class:`DiskCache`).
        layers: the print's layers (None: every socket as laid out).
        keep_roofs: positions whose sockets stay as laid out (the rods of fused pieces).
        holes: per position, its pin holes' offsets (:func:`rodcad.cad.solids.build_rod`).
        sizes: per position, its pin holes' diameters (the joint hardware's; None: the
            hinge's own). ``masses`` are for the rods with their own holes (the rods'
            tables'); a built rod weighs that less the plastic its hardware's holes take.

    Returns:
        The :class:`ChainFabrication`; e.g. ``all(abs(r.mass_error) < 1e-3 for r in fab.rods)``.

    Raises:
        FabricationError: a built rod failed its checks (mass, walls, rebuild).
    """

    t0 = time.perf_counter()
    if len(types) != len(masses):
        raise ValueError(f"{len(types)} rod types but {len(masses)} masses")
    cache = cache if cache is not None else DiskCache()
    roofs: list[RoofPlan | None] = [None] * len(types) if layers is None else shared_roofs(
        types, masses, layers, seed=seed, jobs=jobs, cache=cache, keep=keep_roofs)
    keys: dict[tuple[Any, ...], int] = {}
    distinct: list[tuple[RodType, float, RoofPlan | None]] = []
    moved: list[tuple[Holes, Sizes]] = []  # per distinct rod, its holes (not part of the plan)
    where: list[int] = []
    for rod, m, roof, hl, sz in zip(types, masses, roofs, holes or [NO_SHIFT] * len(types),
                                    sizes or [OWN_SIZES] * len(types)):
        sz = tuple(None if d is None or abs(d - rod.geometry.hinge.hole_diameter) < 1e-9 else float(d) for d in sz)
        k = (rod.name, round(float(m), 6), None if roof is None else roof.key(), hl, sz)
        if k not in keys:
            keys[k] = len(distinct)
            distinct.append((rod, float(m), roof))
            moved.append((hl, sz))
        where.append(keys[k])
    plans: list[dict[str, Any] | None] = []
    todo: list[int] = []
    for i, (rod, m, roof) in enumerate(distinct):
        hit = None if rod.fill is not None else cache.get("fab", _key(rod, m, seed, roof))
        plans.append(hit)
        if hit is None and rod.fill is None:  # a rod with a fill is built below, in one boolean
            todo.append(i)
    done = len(distinct) - len(todo)
    if progress:
        progress(done, len(distinct))
    # One task per rod type (its table of reachable masses, then its rods), so
    # each worker builds a type's candidate pools once; a type with more than
    # its share of the rods is split so every worker has work.
    by_type: dict[str, list[int]] = {}
    for i in todo:
        by_type.setdefault(distinct[i][0].name, []).append(i)
    jobs = max(1, min(jobs or default_jobs(), len(todo))) if todo else 1
    share = max(1, math.ceil(len(todo) / jobs)) if len(by_type) < jobs else len(todo)
    tasks: list[list[int]] = []
    homes: list[str] = []  # a type's first task runs where its table was made (kept workers)
    for name, idx in by_type.items():
        tasks += [idx[k:k + share] for k in range(0, len(idx), share)]
        homes += [name if k == 0 else f"{name} #{k}" for k in range(0, len(idx), share)]
    order = sorted(range(len(tasks)), key=lambda t: -len(tasks[t]))
    tasks, homes = [tasks[t] for t in order], [homes[t] for t in order]
    tables: dict[str, dict[str, Any] | None] = {}
    for idx in tasks:
        rod = distinct[idx[0]][0]
        if rod.name not in tables:
            hit = cache.get("fabint", intervals_key(rod, seed))
            tables[rod.name] = hit if isinstance(hit, dict) and "options" in hit else None
    assembled: dict[int, FabricatedRod] = {}  # distinct rods built with their holes where their plans were made
    workers = kept() if jobs > 1 and len(tasks) > 1 else None
    pool = worker_pool(jobs) if jobs > 1 and len(tasks) > 1 and workers is None else None
    try:
        args = [(distinct[idx[0]][0], [(*distinct[i][1:], *moved[i]) for i in idx], seed,
                 tables[distinct[idx[0]][0].name]) for idx in tasks]
        if workers is not None:
            results: Any = workers.map(_type_star, args, homes)
        else:
            results = pool.map(_type_star, args, chunksize=1) if pool is not None else map(_type_star, args)
        for idx, (table, res, plain) in zip(tasks, results):
            rod = distinct[idx[0]][0]
            if workers is not None or pool is not None:  # built in a worker: this process has none yet
                share_type_solid(rod, plain.restore())
            if tables[rod.name] is None:
                tables[rod.name] = table
                cache.put("fabint", intervals_key(rod, seed), table)
            for i, (plan, rod_built) in zip(idx, res):
                plans[i] = plan
                assembled[i] = dataclasses.replace(rod_built, solid=rod_built.solid.restore())
                cache.put("fab", _key(*distinct[i][:2], seed, distinct[i][2]), plan)
                done += 1
                if progress:
                    progress(done, len(distinct))
    finally:
        if pool is not None:
            pool.shutdown()
    built = [_filled_result(rod, m, *moved[i]) if rod.fill is not None else
             assembled[i] if i in assembled else _assemble_result(rod, m, 0, plans[i], *moved[i])
             for i, (rod, m, _) in enumerate(distinct)]
    rods: list[FabricatedRod] = []
    problems: list[str] = []
    for index, (rod, m) in enumerate(zip(types, masses)):
        b = built[where[index]]
        fr = FabricatedRod(**{**b.__dict__, "index": index, "target_mass": float(m),
                              "file_stem": f"{index:02d}_{rod.name}"})
        rods.append(fr)
        if fr.message:
            problems.append(f"Rod {index} ({rod.name}): {fr.message}.")
    return ChainFabrication(rods, problems, len(distinct), time.perf_counter() - t0)
