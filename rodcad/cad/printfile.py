"""Slicer files: every rod to print as a PrusaSlicer project (print.3mf) with the print
settings the masses assume and a pause at every insert layer, and one project per rod
(rods/NN_TYPE.3mf) that slices alone the same way.

Plates. All rods are shelf-packed together on the printer's bed (:func:`plan_plates`); a
chain that does not fit one bed goes on several plates (files ``print.3mf``,
``print-2.3mf``, ...). A plate pauses at every height at which one of its rods needs a
pause, each pause's message naming exactly the rods (and the balls or the shot) whose
inserts go in there; the other rods print on through it (their sockets, if any, close at
another pause). Each rod's own project (:func:`write_rod_3mf`) is a plate of that rod
alone: the same print settings and that rod's pauses.

Pauses. PrusaSlicer slices layer k (top ``print_z``, height h) at ``print_z - h/2`` and
emits the pause of a ``print_z`` after moving up to the first layer at or above it, before
printing that layer. A socket of roof height r (mm above the bed) is open in every layer
sliced below r and bridged in the first layer sliced at or above it, so its pause is the
top of that layer: the smallest layer top z with ``z - h/2 >= r``
(:meth:`PrintProfile.pause_z`, :class:`rodcad.fabrication.layers.LayerGrid`). At the pause
the print stands at least at ``r - h/2``, the balls lie in the open sockets, and the next
layer closes them. The fabrication puts the roofs of a chain's sockets on as few layers as
the rods allow (:mod:`rodcad.fabrication.roofs`), so a plate pauses seldom.

The meshes are tessellated by OCC (welded, checked closed), or, for a part that brings its
mesh (a net's, the one its STL holds), placed from it; the print settings,
pauses and object names are PrusaSlicer's metadata files (:mod:`rodcad.cad.slicer`).
Sliced alone, the shipped catalogs' rods use filament within 1 % of their designed
plastic mass (tests/test_printfile.py). Support is off but for rods that rest on their
arc (a non-empty ``print_note``): the slicer's support under their rising ends is plastic
printed beside the rod, not part of it.

Units: mm, g, g/cm^3.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rodcad.cad.slicer import (
    CONFIG_FILE,
    DEFAULT_BUILD_VOLUME,
    DEFAULT_NOZZLE,
    MODEL_CONFIG_FILE,
    PAUSES_FILE,
    PrintProfile,
    SlicerObject,
    bed,
    pause_xml,
    slicer_config,
    write_3mf,
)
from rodcad.fabrication.layers import Z_TOL
from rodcad.fabrication.plan import socket_tops

if TYPE_CHECKING:  # pragma: no cover
    from rodcad.cad.rods import FabricatedRod
    from rodcad.catalog.model import Printer

__all__ = ["DEFAULT_BUILD_VOLUME", "DEFAULT_NOZZLE", "PrintProfile", "Placement", "Plate", "plan_plates",
           "rod_pauses", "plate_paths", "slicer_config", "pause_xml", "write_print_3mf", "write_rod_3mf",
           "write_print_files", "CONFIG_FILE", "PAUSES_FILE", "MODEL_CONFIG_FILE"]

#: Largest relative difference allowed between a mesh's volume and its solid's.
VOLUME_TOL = 5e-3


@dataclass
class Placement:
    """One rod on a plate.

    Attributes:
        rod: the fabricated rod.
        offset: (x, y) added to the rod's bed coordinates (after ``rotated``), mm.
        rotated: turned 90 degrees about the bed's Z axis (to fit the bed).
        size: (x, y, z) of its box on the bed as placed, mm.
        pauses: {print_z: balls inserted at that pause}.
        copy: which of the part's ``copies`` this is (a net's equal parts: one solid, printed
            once per member).
    """

    rod: FabricatedRod
    offset: tuple[float, float]
    rotated: bool
    size: tuple[float, float, float]
    pauses: dict[float, int] = field(default_factory=dict)
    copy: int = 0

    @property
    def box(self) -> tuple[float, float, float, float]:
        """(x0, y0, x1, y1) of its footprint on the bed, mm."""
        x, y = self.offset
        return (x, y, x + self.size[0], y + self.size[1])


@dataclass
class Plate:
    """One bed load.

    Attributes:
        placements: the rods on it, by chain index.
        pauses: {print_z: message} for the whole plate: every height at which one of its
            rods pauses, the message naming the rods whose inserts go in there.
    """

    placements: list[Placement]
    pauses: dict[float, str]


@dataclass
class _Mesh:
    vertices: np.ndarray  # (n, 3) on the bed, from (0, 0, 0)
    triangles: np.ndarray  # (m, 3)
    z_shift: float  # how far the mesh was lowered onto the bed (mm)


def _mesh(rod: FabricatedRod) -> _Mesh:
    """The rod's solid on the bed (its print matrix), tessellated to an absolute deflection
    (:func:`rodcad.cad.mesh.mesh_solid`: closed, oriented, within the deflection times its
    area of the solid's volume), moved onto Z = 0 (where a slicer drops it). A part that
    carries its ``mesh`` already (a net's: its STL's, meshed and checked where it was built)
    is placed by its print matrix instead of being meshed again; either mesh's volume is
    checked against the solid's."""
    from rodcad.cad.export import transformed
    from rodcad.cad.mesh import mesh_solid

    known = getattr(rod, "mesh", None)
    defl = getattr(rod, "mesh_deflection", None)  # a net part's: as coarse as the print allows
    if known is not None:
        mesh = known.moved(rod.print_matrix)
    elif defl is None:
        mesh = mesh_solid(transformed(rod.solid, rod.print_matrix))
    else:
        mesh = mesh_solid(transformed(rod.solid, rod.print_matrix), deflection=defl[0], angular=defl[1])
    if abs(mesh.volume - rod.plastic_volume) > VOLUME_TOL * rod.plastic_volume:
        raise ValueError(f"rod {rod.file_stem}: its mesh encloses {mesh.volume:.2f} mm^3, the solid "
                         f"{rod.plastic_volume:.2f} mm^3")
    v = mesh.vertices.copy()
    lo = v.min(axis=0)
    v -= lo
    return _Mesh(v, mesh.triangles.astype(np.int64), float(lo[2]))


def _roofs(rod: FabricatedRod) -> list[float]:
    """Every socket's roof height on the bed (mm, print matrix), one per ball."""
    socks = np.asarray(rod.socket_centers, dtype=float).reshape(-1, 3)
    if getattr(rod, "socket_roofs", ()):  # a fused piece: its rods' roofs lean (rodcad.cad.pieces)
        return [float(z) for z in rod.socket_roofs]
    if not len(socks):
        return [float(z) for z in rod.pause_zs][:rod.ball_count] if rod.ball_count else []
    m = np.asarray(rod.print_matrix, dtype=float)
    tops = socket_tops(getattr(rod, "socket_height", 0.0), rod.socket_radius, len(socks))  # above the centres
    return [float(z) for z in socks @ m[2, :3] + m[2, 3] + tops]


def _fill(rod: FabricatedRod) -> tuple[float, str]:
    """(grams, name) of the shot poured into the rod's closed chamber at its pause (0 without)."""
    return float(getattr(rod, "fill_mass", 0.0) or 0.0), str(getattr(rod, "fill_name", "") or "shot")


def rod_pauses(rod: FabricatedRod, profile: Mapping[str, Any] | PrintProfile | None = None,
               z_shift: float = 0.0) -> dict[float, int]:
    """{print_z: balls inserted} of one rod: the layer to pause before
    (:meth:`PrintProfile.pause_z`) per socket roof and, for a rod whose chamber is filled
    with shot, per chamber roof (``pause_zs``; 0 balls); ``z_shift`` (mm) is how far the
    rod was lowered onto the bed."""
    prof = PrintProfile.from_mapping(profile)
    out: dict[float, int] = {}
    for r in _roofs(rod):
        z = prof.pause_z(r - z_shift)
        out[z] = out.get(z, 0) + 1
    if _fill(rod)[0] > 0 and not rod.ball_count:
        for r in rod.pause_zs:
            out.setdefault(prof.pause_z(float(r) - z_shift), 0)
    return dict(sorted(out.items()))


def _rod_tag(tag: str) -> str:
    """'rod 03' for a rod's file tag, 'piece 01-04' for a fused piece's."""
    return f"piece {tag}" if "-" in tag else f"rod {tag}"


def _tag(rod: FabricatedRod, copy: int = 0) -> str:
    """A part's tag in pause messages: its copy's ``copy_tags`` entry or its ``print_tag`` (a net
    rod's number), else its file stem's first field ('03' of '03_rod')."""
    tags = getattr(rod, "copy_tags", ())
    if tags:
        return str(tags[copy])
    return str(getattr(rod, "print_tag", "") or rod.file_stem.split("_")[0])


def _message(placements: Sequence[Placement], z: float) -> str:
    """What to do at the pause at ``z``: e.g. 'insert 4 balls of 6 mm (2 in each of rods
    00, 03)', 'pour 12.5 g of tungsten shot into rod 04'."""
    by_d: dict[tuple[float, str], list[tuple[str, int]]] = {}
    parts, pours = [], []
    for p in placements:
        tag = _tag(p.rod, getattr(p, "copy", 0))
        n = p.pauses.get(z, 0)
        if n:
            kind = (float(p.rod.ball_diameter or 0.0), str(getattr(p.rod, "ball_name", "") or ""))
            by_d.setdefault(kind, []).append((tag, n))
        grams, name = _fill(p.rod)
        if z in p.pauses and grams > 0 and not n:
            pours.append(f"pour {grams:.2f} g of {name} into {_rod_tag(tag)}")
    for (d, name), rods in sorted(by_d.items()):
        total = sum(n for _, n in rods)
        counts = {n for _, n in rods}
        if len(rods) == 1:
            who = _rod_tag(rods[0][0])
        elif len(counts) == 1:
            who = f"{counts.pop()} in each of rods {', '.join(s for s, _ in rods)}"
        else:
            who = ", ".join(f"{n} in {_rod_tag(s)}" for s, n in rods)
        what = f" [{name}]" if name else ""
        parts.append(f"insert {total} ball{'s' if total != 1 else ''} of {d:g} mm ({who}){what}")
    return "; ".join(parts + pours)


def plan_plates(rods: Sequence[FabricatedRod], *, printer: Printer | None = None,
                profile: Mapping[str, Any] | PrintProfile | None = None, gap: float = 5.0,
                margin: float = 5.0) -> list[Plate]:
    """Shelf-pack every rod on the printer's bed, on as many plates as the bed needs.

    Each rod keeps its print orientation; it is turned 90 degrees about Z only when that
    is what makes it fit. Rows run along x, ``gap`` mm apart, ``margin`` mm from the bed's
    edges, the rods deepest along y first; when the bed is full the next plate begins.
    Each plate's rods are centred on the bed as a block, and the plate pauses at every
    height one of its rods needs (:func:`rod_pauses`), each message naming the rods whose
    inserts go in at that height.

    Raises:
        ValueError: a rod fits the printer in no orientation on its side.
    """
    return _plan(rods, PrintProfile.from_mapping(profile), printer, gap, margin, {})


def _plan(rods: Sequence[FabricatedRod], prof: PrintProfile, printer: Printer | None, gap: float, margin: float,
          meshes: dict[int, _Mesh], single: bool = False) -> list[Plate]:
    """:func:`plan_plates`, each rod ``copies`` times (once if ``single``)."""
    (bx, by, bz), _ = bed(printer)
    ux, uy = bx - 2 * margin, by - 2 * margin
    items = []
    for rod in rods:
        mesh = meshes.get(id(rod.solid))
        if mesh is None:
            mesh = meshes[id(rod.solid)] = _mesh(rod)
        sx, sy, sz = (float(s) for s in mesh.vertices.max(axis=0))
        if sz > bz + Z_TOL:
            raise ValueError(f"rod {rod.file_stem} is {sz:.1f} mm tall on its side; the printer builds {bz:g} mm")
        pauses = rod_pauses(rod, prof, mesh.z_shift)
        if sx <= ux + Z_TOL and sy <= uy + Z_TOL:
            fit = (False, (sx, sy, sz))
        elif sy <= ux + Z_TOL and sx <= uy + Z_TOL:
            fit = (True, (sy, sx, sz))
        else:
            raise ValueError(f"rod {rod.file_stem} ({sx:.1f} x {sy:.1f} mm on the bed) does not fit the "
                             f"printer's {bx:g} x {by:g} mm bed less {margin:g} mm margins")
        copies = 1 if single else int(getattr(rod, "copies", 1) or 1)
        items += [(rod, dict(pauses), *fit, c) for c in range(copies)]
    items.sort(key=lambda it: (-it[3][1], it[0].index, it[4]))
    plates: list[Plate] = []
    current: list[Placement] = []
    x = y = row = 0.0
    for rod, pauses, rotated, size, copy in items:
        if current and x + size[0] > ux + Z_TOL:  # next row
            x, y, row = 0.0, y + row + gap, 0.0
        if current and y + size[1] > uy + Z_TOL:  # next plate
            plates.append(_plate(current, bx, by))
            current, x, y, row = [], 0.0, 0.0, 0.0
        current.append(Placement(rod, (x, y), rotated, size, pauses, copy))
        x += size[0] + gap
        row = max(row, size[1])
    if current:
        plates.append(_plate(current, bx, by))
    return plates


def _plate(placements: list[Placement], bx: float, by: float) -> Plate:
    x1 = max(p.box[2] for p in placements)
    y1 = max(p.box[3] for p in placements)
    dx, dy = (bx - x1) / 2, (by - y1) / 2
    for p in placements:
        p.offset = (round(p.offset[0] + dx, 4), round(p.offset[1] + dy, 4))
    placements.sort(key=lambda p: (p.rod.index, p.copy))
    heights = sorted({z for p in placements for z in p.pauses})
    return Plate(placements, {z: _message(placements, z) for z in heights})


def plate_paths(path: str | Path, count: int) -> list[Path]:
    """print.3mf, print-2.3mf, ... for ``count`` plates."""
    path = Path(path)
    return [path if k == 0 else path.with_name(f"{path.stem}-{k + 1}{path.suffix}") for k in range(count)]


def _placed_vertices(mesh: _Mesh, placement: Placement) -> np.ndarray:
    v = mesh.vertices
    if placement.rotated:  # a quarter turn about Z, (x, y) -> (-y, x), back into x >= 0
        v = np.column_stack([v[:, 1].max() - v[:, 1], v[:, 0], v[:, 2]])
    return v + np.array([placement.offset[0], placement.offset[1], 0.0])


def _placement_matrix(mesh: _Mesh, placement: Placement) -> np.ndarray:
    """4 x 4 taking the mesh (on the bed from the origin) where :func:`_placed_vertices` puts it."""
    m = np.eye(4)
    if placement.rotated:  # (x, y) -> (ymax - y, x)
        m[:2, :2] = [[0.0, -1.0], [1.0, 0.0]]
        m[0, 3] = float(mesh.vertices[:, 1].max())
    m[:2, 3] += placement.offset
    return m


def _write_plate(plate: Plate, path: Path, printer: Printer | None, prof: PrintProfile,
                 meshes: dict[int, _Mesh]) -> Path:
    """The plate's project: a rod of one copy an object of its own; a part with ``copies`` one
    object (one mesh) with a build item per copy on this plate."""
    objects, shared = [], {}
    for p in plate.placements:
        mesh = meshes[id(p.rod.solid)]
        settings = dict(getattr(p.rod, "print_settings", None) or {})
        if int(getattr(p.rod, "copies", 1) or 1) == 1:
            objects.append(SlicerObject(p.rod.file_stem, _placed_vertices(mesh, p), mesh.triangles,
                                        bool(p.rod.print_note), settings))
            continue
        if id(p.rod) not in shared:
            shared[id(p.rod)] = len(objects)
            objects.append(SlicerObject(p.rod.file_stem, mesh.vertices, mesh.triangles, bool(p.rod.print_note),
                                        settings, []))
        objects[shared[id(p.rod)]].instances.append(_placement_matrix(mesh, p))
    return write_3mf(path, objects, plate.pauses, profile=prof, printer=printer)


def _write_plates(rods: Sequence[FabricatedRod], path: str | Path, printer: Printer | None, prof: PrintProfile,
                  gap: float, margin: float, meshes: dict[int, _Mesh],
                  progress: Callable[[int, int], None] | None = None, total: int = 0) -> list[Path]:
    plates = _plan(rods, prof, printer, gap, margin, meshes)
    paths = plate_paths(path, len(plates))
    for k, (plate, out) in enumerate(zip(plates, paths), 1):
        _write_plate(plate, out, printer, prof, meshes)
        if progress is not None:
            progress(k, len(plates) + total)
    k = len(paths) + 1
    while (stale := plate_paths(path, k)[-1]).exists():  # plates of an earlier, longer run
        stale.unlink()
        k += 1
    return paths


def write_print_3mf(rods: Sequence[FabricatedRod], path: str | Path, *, printer: Printer | None = None,
                    profile: Mapping[str, Any] | PrintProfile | None = None, gap: float = 5.0,
                    margin: float = 5.0) -> list[Path]:
    """Write the PrusaSlicer project(s) of every rod to print.

    One object per rod (chain position) named by its rod file stem ('NN_TYPE'), in its
    print orientation, shelf-packed without overlaps on the printer's bed
    (:func:`plan_plates`; default bed 220 x 220 x 250 mm); the print settings of
    ``profile`` and the printer in ``Metadata/Slic3r_PE.config`` (100 % infill by
    default: what every designed mass assumes); a pause (M601) at every insert layer of
    any of its rods in ``Metadata/Prusa_Slicer_custom_gcode_per_print_z.xml``, its
    message saying how many balls go into which rods (or how much shot into which).
    Rods that do not fit one bed go on further plates: ``path`` (print.3mf), then
    print-2.3mf, ...; files of an earlier run beyond the last plate are removed.

    Args:
        rods: the fabricated rods (:class:`rodcad.cad.rods.FabricatedRod`).
        path: the first file.
        printer: the catalog's printer (None: 220 x 220 x 250 mm, 0.4 mm nozzle).
        profile: print settings: a dict such as design.json's ``print`` (material,
            density, infill, layer_height, perimeters, ...; other keys are ignored) or a
            :class:`PrintProfile`.
        gap: mm between rods on the bed.
        margin: mm between rods and the bed's edges.

    Returns:
        The files written, one per plate.

    Raises:
        ValueError: a rod does not fit the printer, or a profile value is invalid.
    """
    return _write_plates(rods, path, printer, PrintProfile.from_mapping(profile), gap, margin, {})


def write_rod_3mf(rod: FabricatedRod, path: str | Path, *, printer: Printer | None = None,
                  profile: Mapping[str, Any] | PrintProfile | None = None) -> Path:
    """Write one rod as a PrusaSlicer project of its own: the rod alone, named by its file
    stem, in print orientation, centred on the printer's bed, with the print settings of
    ``profile`` (100 % infill by default), that rod's pauses (messages naming its inserts)
    and, for a rod resting on its arc, support (see :func:`write_print_3mf`)."""
    prof = PrintProfile.from_mapping(profile)
    meshes: dict[int, _Mesh] = {}
    (plate,) = _plan([rod], prof, printer, 5.0, 5.0, meshes, single=True)
    return _write_plate(plate, Path(path), printer, prof, meshes)


def write_print_files(rods: Sequence[FabricatedRod], outdir: str | Path, *, printer: Printer | None = None,
                      profile: Mapping[str, Any] | PrintProfile | None = None,
                      progress: Callable[[int, int], None] | None = None) -> list[Path]:
    """Write OUTDIR/print.3mf (and print-2.3mf, ... when one bed is not enough; see
    :func:`write_print_3mf`) and OUTDIR/rods/NN_TYPE.3mf for every rod, each a project of
    that rod alone with the same settings and its own pauses (:func:`write_rod_3mf`); each
    distinct solid is tessellated once. A part with a ``print_folder`` (e.g. a net's hub
    parts: 'hubs') has its own project there instead of in rods/. ``progress(done, total)``
    hears each file written (the plates, then the rods' projects).

    Returns:
        The paths written: the plates, then the rods' 3MF files.
    """
    outdir = Path(outdir)
    prof = PrintProfile.from_mapping(profile)
    meshes: dict[int, _Mesh] = {}
    written = _write_plates(rods, outdir / "print.3mf", printer, prof, 5.0, 5.0, meshes, progress, len(rods))
    plates = len(written)
    for k, rod in enumerate(rods, 1):  # rods sharing a solid share its mesh, each under its own name
        (plate,) = _plan([rod], prof, printer, 5.0, 5.0, meshes, single=True)
        folder = str(getattr(rod, "print_folder", "") or "rods")
        written.append(_write_plate(plate, outdir / folder / f"{rod.file_stem}.3mf", printer, prof, meshes))
        if progress is not None:
            progress(plates + k, plates + len(rods))
    return written
