"""A net's print files: every part a user prints (rods and hub parts) in PrusaSlicer
projects, through the chains' code (:mod:`rodcad.cad.printfile`): print.3mf (print-2.3mf,
... when one bed is not enough: plates split by the printer's bed only; each distinct part one
object placed once per member), rods/rod-NNN.3mf and hubs/<part>.3mf (one per distinct part), each with the catalog's print profile (100 % infill) and a pause
(M601, its message naming the rods) at every layer where steel balls go into a rod.

Orientation. A rod lies along the bed's x axis on its round body (its axis ``rod_diameter
/ 2`` above the bed); its end balls (narrower than the body) and the underside of the body
need support from the bed (``support_material`` on for the rod, on the build plate only, so
none is printed inside its cavity or ball sockets). A hub half lies on its flat cut face
(:mod:`rodcad.cad.net.hub`); a hub left whole (its sockets off every plane) on support. A bent
rod (:mod:`rodcad.cad.net.bent`) is turned a quarter turn about its chord so that its arc lies
flat on the bed (:data:`FLAT_ARC`), its steel balls' centres at its axis's height as on a straight rod.

Steel balls. A rod's ball sockets are spheres on its axis (the mass model's,
:meth:`rodcad.catalog.net.node.NodeHardware.rod_numbers`). A sphere only lets its ball in near
its widest section, so the print pauses before the layer sliced at the sockets' centres'
height (the print then stands within half a layer of it, where the opening is
``2 sqrt(rs^2 - (h/2)^2)`` across, wider than the ball for a 0.2 mm layer); the ball lies in
the lower half and the upper half of the socket prints over it, the ball carrying the
overhang. At the pause the ball stands up to ``d - rs`` (about 2.9 mm) above the print: the
projects keep travel over the printed layer (``avoid_crossing_perimeters``,
:func:`rodcad.cad.slicer.slicer_config`), never across a ball, and in the next layers the
nozzle prints each socket's wall within about ``clearance / 2`` of the ball's side: a ball
seated off-centre can be touched; the rod's socket is round because
a flat-roofed silo (the chains' socket) does not fit inside a 9 mm round rod with its walls.

Units: mm, g.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rodcad.cad.mesh import TriangleMesh, read_stl
from rodcad.cad.net.solids import ball_positions
from rodcad.cad.net.bent import bent_socket_centres
from rodcad.cad.printfile import write_print_files
from rodcad.catalog.net.splice import piece_extents

__all__ = ["NetPrintPart", "net_print_parts", "write_net_print_files"]

#: A bent rod's print matrix: a quarter turn about x, its arc (in the rod frame's xz plane,
#: bowing toward -z) into the bed's plane, its balls' centres at its axis's height.
FLAT_ARC = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]])

#: What a rod asks of PrusaSlicer besides support (per object).
ROD_SETTINGS = {"support_material_buildplate_only": "1"}


@dataclass
class NetPrintPart:
    """One printed part of a net as :mod:`rodcad.cad.printfile` takes it (the attributes a
    :class:`rodcad.cad.rods.FabricatedRod` has that plates and pauses read).

    Attributes:
        index: its place on the plates' order (rods first, then hub parts).
        solid: the part in its own frame (build123d ``Solid``).
        plastic_volume: the solid's volume (mm^3).
        print_matrix: 4x4 placing the solid on the bed (mm).
        file_stem: 'rod-003', 'hub-002-a', ...
        print_folder: 'rods' or 'hubs' (its own project's folder).
        print_tag: its tag in pause messages ('003' for rod 3).
        socket_roofs: the heights (after ``print_matrix``) to pause just before, one per
            steel ball: the sockets' centres (mm).
        ball_count, ball_diameter, ball_name: its steel balls.
        print_note: how it prints ('' without support).
        print_settings: PrusaSlicer per-object settings.
        copies: how many to print (its members); copy_tags: each copy's tag in pause messages.
        mesh_deflection: (linear mm, angular rad) of its mesh (:func:`rodcad.cad.mesh.print_deflection`).
        mesh: its mesh in its own frame, the one its STL holds (built and checked by its task,
            :func:`rodcad.cad.net.build.build_group`), or None: meshed from ``solid``.
    """

    index: int
    solid: object
    plastic_volume: float
    print_matrix: np.ndarray
    file_stem: str
    print_folder: str
    print_tag: str = ""
    socket_roofs: tuple = ()
    ball_count: int = 0
    ball_diameter: float | None = None
    ball_name: str = ""
    print_note: str = ""
    print_settings: dict = field(default_factory=dict)
    socket_centers: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    socket_radius: float = 0.0
    socket_height: float = 0.0
    pause_zs: tuple = ()
    fill_mass: float = 0.0
    copies: int = 1
    copy_tags: tuple = ()
    mesh_deflection: tuple | None = None
    mesh: TriangleMesh | None = None


def net_print_parts(check, solids, *, ball_name: str = "") -> list[NetPrintPart]:
    """Every distinct part of a built net to print, each with its count (``solids.parts``,
    :mod:`rodcad.cad.net.parts`): its rods (lying along x on their body) and its hub parts (the
    halves of a split hub, each on its flat face by its own print matrix,
    :mod:`rodcad.cad.net.hub`; a hub left whole on support). The plates place each part once
    per member (its ``copies``), each copy's pauses named after its member's rod.

    Args:
        check: the designed net (:class:`rodcad.design.net.check.NetCheck`).
        solids: its solids (:class:`rodcad.cad.net.solids.NetSolids`).
        ball_name: the steel balls' name in pause messages.
    """
    plan = check.plan
    parts = []
    for part in (p for p in solids.parts if p.kind == "rod"):
        e = part.members[0]
        for i, (s, mesh) in enumerate(zip(part.solids, _meshes(part, solids.deflection))):
            parts.append(_rod_part(plan, solids, part, e, i, s, mesh, ball_name))
    for part in (p for p in solids.parts if p.kind == "hub"):
        whole = len(part.solids) == 1
        for s, matrix, mesh in zip(part.solids, part.print_matrices, _meshes(part, solids.deflection)):
            parts.append(NetPrintPart(
                len(solids.rods) + len(parts), s, float(s.volume), np.asarray(matrix, float), s.label, "hubs",
                print_note=("a sphere: support from the bed" if whole else ""),
                print_settings=dict(ROD_SETTINGS) if whole else {},
                copies=part.count, copy_tags=tuple(f"hub {i:03d}" for i in part.members),
                mesh_deflection=tuple(solids.deflection), mesh=mesh))
    return parts


def _rod_part(plan, solids, part, e: int, i: int, s, mesh, ball_name: str) -> NetPrintPart:
    """Rod ``e``'s part (piece ``i`` of a spliced rod, :mod:`rodcad.cad.net.splice`) to print:
    along x on its round body (a bent rod turned so that its arc lies flat on the bed), its steel
    balls' sockets where its solid has them."""
    hw = plan.hardware
    arc = plan.arcs[e]
    L = float(plan.lengths[e])
    piece, end = "", "the end balls"
    if plan.rod_pieces[e] > 1:  # solid 0 its end pieces (two), 1 its middle ones
        fills = solids.rod_fills[e]  # (as part_specs built it)
        _, _, z0, z1 = piece_extents(hw, L, len(fills))[i]
        k = int(fills[i][0])
        centres = np.column_stack([ball_positions(hw, L, k, (z0 + z1) / 2), np.zeros((k, 2))])
        end = "the end ball" if i == 0 else "nothing else"
        what = "an end piece" if i == 0 else "a middle piece"
        matrix, note = np.eye(4), (f"{what} of a rod spliced from {len(fills)}: glue a dowel pin into its bore(s) "
                                   "and into the next piece's; it lies on its round body along x")
        piece = chr(ord("a") + i)
    elif arc is None:
        k = int(solids.rod_balls[e]) if solids.rod_balls else 0
        centres = np.column_stack([ball_positions(hw, L, k), np.zeros((k, 2))])
        matrix, note = np.eye(4), "lies on its round body along x"
    else:  # turned about x so that its arc lies in the bed's plane (the bow toward +y)
        k = int(solids.rod_balls[e]) if solids.rod_balls else 0
        centres = bent_socket_centres(hw, arc, k)
        matrix, note = FLAT_ARC.copy(), "lies on its round body, its arc flat on the bed"
    return NetPrintPart(
            e, s, float(s.volume), matrix, s.label, "rods", f"{e:03d}{piece}",
            socket_roofs=tuple(0.0 for _ in range(k)), ball_count=k,
            ball_diameter=float(hw.insert_diameter) if k else None, ball_name=ball_name if k else "",
            print_note=f"{note}: support from the bed under the body and {end}",
            print_settings=dict(ROD_SETTINGS),
            socket_centers=centres if k else np.zeros((0, 3)),
            socket_radius=(hw.insert_diameter + hw.insert_clearance) / 2 if k else 0.0,
            copies=part.prints(i), copy_tags=tuple(f"{j:03d}{piece}" for j in part.members
                                                   for _ in range(part.prints(i) // part.count)),
            mesh_deflection=tuple(solids.deflection), mesh=mesh)


def _meshes(part, deflection) -> list:
    """Each of a part's printed solids' mesh, read from the STL its task wrote (None where it
    has none: meshed again from the solid)."""
    return [read_stl(files[".stl"], float(deflection[0])) if ".stl" in files else None
            for files in (part.files or [{} for _ in part.solids])]


def write_net_print_files(check, solids, outdir: str | Path, *, printer=None, profile=None,
                          ball_name: str = "", progress=None) -> list[str]:
    """print.3mf (and print-2.3mf, ...), rods/rod-NNN.3mf and hubs/<part>.3mf of a built net
    (:func:`rodcad.cad.printfile.write_print_files`; ``progress(done, total)`` hears each
    file written).

    Returns:
        The files written, relative to ``outdir``.
    """
    outdir = Path(outdir)
    parts = net_print_parts(check, solids, ball_name=ball_name)
    paths = write_print_files(parts, outdir, printer=printer, profile=profile, progress=progress)
    return [str(Path(p).relative_to(outdir)) for p in paths]
