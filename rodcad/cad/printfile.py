"""Slicer files: every rod to print as a PrusaSlicer project (print.3mf) with the print
settings the masses assume and a pause at every ball-insert layer, and one plain 3MF per
rod for other slicers.

The meshes are tessellated to an absolute deflection (:func:`rodcad.cad.mesh.mesh_solid`,
the tessellation of the STLs too) and written by lib3mf (through build123d's Mesher); the PrusaSlicer metadata files are then added to the
zip archive:

- ``Metadata/Slic3r_PE.config``: the print settings, one ``; key = value`` line each
  (PrusaSlicer reads them bottom up and stops at the first line of another form, so the
  file starts with a header line);
- ``Metadata/Prusa_Slicer_custom_gcode_per_print_z.xml``: the pauses,
  ``<code print_z=.. type="1" extruder="1" color="" extra="message" gcode="M601"/>``
  (type 1 is ``CustomGCode::PausePrint``) and ``<mode value="SingleExtruder"/>``;
- ``Metadata/Slic3r_PE_model.config``: each object's name (PrusaSlicer names the only
  object of a foreign 3MF after the file otherwise) and, for rods that rest on their
  arc (:attr:`FabricatedRod.print_note`), support under the rising ends.

Pauses. PrusaSlicer slices layer k (top ``print_z``, height h) at ``print_z - h/2`` and
emits the pause of a ``print_z`` after moving up to the first layer at or above it, before
printing that layer. A socket of roof height r (mm above the bed) is open in every layer
sliced below r and bridged in the first layer sliced at or above it, so its pause is the
top of that layer: the smallest layer top z with ``z - h/2 >= r``
(:meth:`PrintProfile.pause_z`). At the pause the print stands at least at ``r - h/2``, the
balls lie in the open sockets, and the next layer closes them. A pause holds for the whole
bed, so rods whose pause heights differ never share a plate: rods are grouped by their
set of pause heights and each group is shelf-packed on as many plates (files
``print.3mf``, ``print-2.3mf``, ...) as it needs.

Mass. With 100 % infill the slicer extrudes the sliced area times the layer height, less
the corners its rounded-rectangle extrusions leave between perimeters and infill:
``h^2 (1 - pi/4)`` per perimeter edge and layer. ``infill_overlap`` is set to exactly that
over the perimeter width (PrusaSlicer's automatic width, 1.125 x the nozzle), 9.5 % for a
0.2 mm layer and a 0.4 mm nozzle; PrusaSlicer's own default, 25 %, over-extrudes rods by
1-2.5 %. Bridges are laid at the layer height (``thick_bridges = 0``; thick ones would
sag extra plastic into sockets and cavities), and there is no elephant-foot or XY size
compensation. Sliced alone, the shipped catalogs' rods then use filament within 1 % of
their designed plastic mass (tests/test_printfile.py). Support is off but for rods that
rest on their arc (a non-empty ``print_note``): the slicer's support under their rising
ends is plastic printed beside the rod, not part of it.

Units: mm, g, g/cm^3.
"""

from __future__ import annotations

import io
import math
import zipfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any
from xml.sax.saxutils import quoteattr

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from rodcad.cad.rods import FabricatedRod
    from rodcad.catalog.model import Printer

__all__ = ["DEFAULT_BUILD_VOLUME", "DEFAULT_NOZZLE", "PrintProfile", "Placement", "Plate", "plan_plates",
           "rod_pauses", "plate_paths", "slicer_config", "pause_xml", "write_print_3mf", "write_rod_3mf",
           "write_print_files", "CONFIG_FILE", "PAUSES_FILE", "MODEL_CONFIG_FILE"]

#: Build volume (x, y, z, mm) assumed when the catalog names no printer.
DEFAULT_BUILD_VOLUME = (220.0, 220.0, 250.0)
#: Nozzle diameter (mm) assumed when the catalog names no printer.
DEFAULT_NOZZLE = 0.4
CONFIG_FILE = "Metadata/Slic3r_PE.config"
PAUSES_FILE = "Metadata/Prusa_Slicer_custom_gcode_per_print_z.xml"
MODEL_CONFIG_FILE = "Metadata/Slic3r_PE_model.config"
#: Largest relative difference allowed between a mesh's volume and its solid's.
VOLUME_TOL = 5e-3
#: Heights closer than this (mm) are one height.
Z_TOL = 1e-6


@dataclass(frozen=True)
class PrintProfile:
    """The print settings written into the project (the ones the masses assume).

    Attributes:
        material: filament type, e.g. 'PLA'.
        density: filament density (g/cm^3).
        infill: infill fraction (1.0 = solid, what every designed mass assumes).
        layer_height: layer height (mm).
        first_layer_height: first layer height (mm); None = ``layer_height``.
        perimeters: perimeter loops.
        filament_diameter: mm.
        temperature: nozzle temperature (deg C).
        bed_temperature: bed temperature (deg C).
        pause_gcode: the G-code of a pause (``pause_print_gcode``).
    """

    material: str = "PLA"
    density: float = 1.24
    infill: float = 1.0
    layer_height: float = 0.2
    first_layer_height: float | None = None
    perimeters: int = 2
    filament_diameter: float = 1.75
    temperature: float = 215.0
    bed_temperature: float = 60.0
    pause_gcode: str = "M601"

    def __post_init__(self) -> None:
        problems = []
        if not self.layer_height > 0:
            problems.append(f"layer_height must be > 0 mm, not {self.layer_height}")
        if self.first_layer_height is not None and not self.first_layer_height > 0:
            problems.append(f"first_layer_height must be > 0 mm, not {self.first_layer_height}")
        if not 0 < self.infill <= 1:
            problems.append(f"infill must be in (0, 1], not {self.infill}")
        if not self.density > 0:
            problems.append(f"density must be > 0 g/cm^3, not {self.density}")
        if not self.filament_diameter > 0:
            problems.append(f"filament_diameter must be > 0 mm, not {self.filament_diameter}")
        if self.perimeters < 0 or int(self.perimeters) != self.perimeters:
            problems.append(f"perimeters must be a whole number >= 0, not {self.perimeters}")
        if problems:
            raise ValueError("; ".join(problems))

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any] | PrintProfile | None) -> PrintProfile:
        """A profile from a dict such as design.json's ``print`` (unknown keys, e.g. 'note',
        are ignored; missing ones take the defaults)."""
        if isinstance(data, PrintProfile):
            return data
        names = {f.name for f in fields(cls)}
        return cls(**{k: v for k, v in (data or {}).items() if k in names and v is not None})

    @property
    def first_layer(self) -> float:
        """The first layer's height (mm)."""
        return float(self.first_layer_height if self.first_layer_height is not None else self.layer_height)

    def layer_top(self, k: int) -> float:
        """Top (print_z) of layer k (0 = the first layer), mm."""
        return round(self.first_layer + k * self.layer_height, 6)

    def pause_z(self, roof: float) -> float:
        """The print_z to pause at for a socket whose roof is ``roof`` mm above the bed:
        the top of the first layer sliced (at mid-height) at or above the roof, i.e. the
        layer that bridges the socket; the pause comes before it is printed."""
        h1, h = self.first_layer, float(self.layer_height)
        if h1 / 2 >= roof - Z_TOL:
            return self.layer_top(0)
        k = max(1, math.ceil((roof - Z_TOL - h1 + h / 2) / h - 1e-9))
        return self.layer_top(k)

    def infill_overlap(self, nozzle: float) -> float:
        """The infill/perimeter overlap (fraction of the perimeter width) that fills the
        corners the rounded extrusions leave: ``h (1 - pi/4) / (1.125 nozzle)``."""
        return float(self.layer_height) * (1 - math.pi / 4) / (1.125 * nozzle)


@dataclass
class Placement:
    """One rod on a plate.

    Attributes:
        rod: the fabricated rod.
        offset: (x, y) added to the rod's bed coordinates (after ``rotated``), mm.
        rotated: turned 90 degrees about the bed's Z axis (to fit the bed).
        size: (x, y, z) of its box on the bed as placed, mm.
        pauses: {print_z: balls inserted at that pause}.
    """

    rod: FabricatedRod
    offset: tuple[float, float]
    rotated: bool
    size: tuple[float, float, float]
    pauses: dict[float, int] = field(default_factory=dict)

    @property
    def box(self) -> tuple[float, float, float, float]:
        """(x0, y0, x1, y1) of its footprint on the bed, mm."""
        x, y = self.offset
        return (x, y, x + self.size[0], y + self.size[1])


@dataclass
class Plate:
    """One bed load: rods that pause at the same heights.

    Attributes:
        placements: the rods on it, by chain index.
        pauses: {print_z: message} for the whole plate.
    """

    placements: list[Placement]
    pauses: dict[float, str]


@dataclass
class _Mesh:
    vertices: np.ndarray  # (n, 3) on the bed, from (0, 0, 0)
    triangles: np.ndarray  # (m, 3)
    z_shift: float  # how far the mesh was lowered onto the bed (mm)


def _bed(printer: Printer | None) -> tuple[tuple[float, float, float], float]:
    if printer is None:
        return DEFAULT_BUILD_VOLUME, DEFAULT_NOZZLE
    x, y, z = (float(v) for v in printer.build_volume)
    return (x, y, z), float(printer.nozzle)


def _mesh(rod: FabricatedRod) -> _Mesh:
    """The rod's solid on the bed (its print matrix), tessellated to an absolute deflection
    (:func:`rodcad.cad.mesh.mesh_solid`: closed, within the deflection times its area of the
    solid's volume), moved onto Z = 0 (where a slicer drops it)."""
    from rodcad.cad.export import transformed
    from rodcad.cad.mesh import mesh_solid

    mesh = mesh_solid(transformed(rod.solid, rod.print_matrix))
    v = mesh.vertices.copy()
    if abs(mesh.volume - rod.plastic_volume) > VOLUME_TOL * rod.plastic_volume:
        raise ValueError(f"rod {rod.file_stem}: its mesh encloses {mesh.volume:.2f} mm^3, the solid "
                         f"{rod.plastic_volume:.2f} mm^3")
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
    return [float(z) + rod.socket_radius for z in socks @ m[2, :3] + m[2, 3]]


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


def _message(placements: Sequence[Placement], z: float) -> str:
    """What to do at the pause at ``z``: e.g. 'insert 4 balls of 6 mm (2 in each of rods
    00, 03)', 'pour 12.5 g of tungsten shot into rod 04'."""
    by_d: dict[tuple[float, str], list[tuple[str, int]]] = {}
    parts, pours = [], []
    for p in placements:
        tag = p.rod.file_stem.split("_")[0]
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
    """Group the rods by their pause heights and shelf-pack each group on the bed.

    Each rod keeps its print orientation; it is turned 90 degrees about Z only when that
    is what makes it fit. Rows run along x, ``gap`` mm apart, ``margin`` mm from the bed's
    edges; a group that does not fit one bed goes on several plates. Each plate's rods
    are centred on the bed as a block. Plates come in the order of their first rod.

    Raises:
        ValueError: a rod fits the printer in no orientation on its side.
    """
    return _plan(rods, PrintProfile.from_mapping(profile), printer, gap, margin, {})


def _plan(rods: Sequence[FabricatedRod], prof: PrintProfile, printer: Printer | None, gap: float, margin: float,
          meshes: dict[int, _Mesh]) -> list[Plate]:
    (bx, by, bz), _ = _bed(printer)
    groups: dict[tuple[float, ...], list[tuple[FabricatedRod, dict[float, int], tuple[float, ...]]]] = {}
    for rod in rods:
        mesh = meshes.get(id(rod.solid))
        if mesh is None:
            mesh = meshes[id(rod.solid)] = _mesh(rod)
        size = tuple(float(s) for s in mesh.vertices.max(axis=0))
        if size[2] > bz + Z_TOL:
            raise ValueError(f"rod {rod.file_stem} is {size[2]:.1f} mm tall on its side; the printer builds "
                             f"{bz:g} mm")
        pauses = rod_pauses(rod, prof, mesh.z_shift)
        groups.setdefault(tuple(pauses), []).append((rod, pauses, size))
    ux, uy = bx - 2 * margin, by - 2 * margin
    plates: list[Plate] = []
    for key in sorted(groups, key=lambda k: min(r.index for r, _, _ in groups[k])):
        items = []
        for rod, pauses, (sx, sy, sz) in groups[key]:
            if sx <= ux + Z_TOL and sy <= uy + Z_TOL:
                items.append((rod, pauses, False, (sx, sy, sz)))
            elif sy <= ux + Z_TOL and sx <= uy + Z_TOL:
                items.append((rod, pauses, True, (sy, sx, sz)))
            else:
                raise ValueError(f"rod {rod.file_stem} ({sx:.1f} x {sy:.1f} mm on the bed) does not fit the "
                                 f"printer's {bx:g} x {by:g} mm bed less {margin:g} mm margins")
        items.sort(key=lambda it: (-it[3][1], it[0].index))
        current: list[Placement] = []
        x = y = row = 0.0
        for rod, pauses, rotated, size in items:
            if current and x + size[0] > ux + Z_TOL:  # next row
                x, y, row = 0.0, y + row + gap, 0.0
            if current and y + size[1] > uy + Z_TOL:  # next plate
                plates.append(_plate(current, bx, by))
                current, x, y, row = [], 0.0, 0.0, 0.0
            current.append(Placement(rod, (x, y), rotated, size, pauses))
            x += size[0] + gap
            row = max(row, size[1])
        plates.append(_plate(current, bx, by))
    return plates


def _plate(placements: list[Placement], bx: float, by: float) -> Plate:
    x1 = max(p.box[2] for p in placements)
    y1 = max(p.box[3] for p in placements)
    dx, dy = (bx - x1) / 2, (by - y1) / 2
    for p in placements:
        p.offset = (round(p.offset[0] + dx, 4), round(p.offset[1] + dy, 4))
    placements.sort(key=lambda p: p.rod.index)
    return Plate(placements, {z: _message(placements, z) for z in sorted(placements[0].pauses)})


def plate_paths(path: str | Path, count: int) -> list[Path]:
    """print.3mf, print-2.3mf, ... for ``count`` plates."""
    path = Path(path)
    return [path if k == 0 else path.with_name(f"{path.stem}-{k + 1}{path.suffix}") for k in range(count)]


def slicer_config(profile: Mapping[str, Any] | PrintProfile | None = None, printer: Printer | None = None) -> str:
    """Metadata/Slic3r_PE.config: the print settings as PrusaSlicer reads them."""
    p = PrintProfile.from_mapping(profile)
    (bx, by, bz), nozzle = _bed(printer)

    def num(v: float) -> str:
        return f"{float(v):.6g}"

    settings = {
        "printer_technology": "FFF",
        "bed_shape": f"0x0,{num(bx)}x0,{num(bx)}x{num(by)},0x{num(by)}",
        "max_print_height": num(bz),
        "nozzle_diameter": num(nozzle),
        "gcode_flavor": "marlin2",
        "gcode_label_objects": "1",
        "filament_type": p.material,
        "filament_density": num(p.density),
        "filament_diameter": num(p.filament_diameter),
        "extrusion_multiplier": "1",
        "temperature": num(p.temperature),
        "first_layer_temperature": num(p.temperature),
        "bed_temperature": num(p.bed_temperature),
        "first_layer_bed_temperature": num(p.bed_temperature),
        "layer_height": num(p.layer_height),
        "first_layer_height": num(p.first_layer),
        "perimeters": str(int(p.perimeters)),
        "fill_density": f"{round(p.infill * 100, 4):g}%",
        "fill_pattern": "rectilinear",
        "solid_fill_pattern": "rectilinear",
        "infill_every_layers": "1",
        "infill_overlap": f"{round(p.infill_overlap(nozzle) * 100, 1):g}%",
        "thick_bridges": "0",
        "elefant_foot_compensation": "0",
        "xy_size_compensation": "0",
        "support_material": "0",
        "complete_objects": "0",
        "skirts": "1",
        "skirt_distance": "3",
        "skirt_height": "1",
        "brim_width": "0",
        "pause_print_gcode": p.pause_gcode,
    }
    lines = ["; generated by rodcad: the print settings every designed rod mass assumes"]
    lines += [f"; {k} = {v}" for k, v in sorted(settings.items())]
    return "\n".join(lines) + "\n"


def pause_xml(pauses: Mapping[float, str], pause_gcode: str = "M601") -> str:
    """Metadata/Prusa_Slicer_custom_gcode_per_print_z.xml: one pause (type 1) per print_z."""
    lines = ['<?xml version="1.0" encoding="utf-8"?>', "<custom_gcodes_per_print_z>"]
    for z, msg in sorted(pauses.items()):
        lines.append(f'<code print_z="{z:.6g}" type="1" extruder="1" color="" extra={quoteattr(msg)} '
                     f"gcode={quoteattr(pause_gcode)}/>")
    lines += ['<mode value="SingleExtruder"/>', "</custom_gcodes_per_print_z>"]
    return "\n".join(lines) + "\n"


def _model_config(objects: Sequence[tuple[int, str, int, bool]]) -> str:
    """Metadata/Slic3r_PE_model.config: (resource id, name, triangles, support) per object."""
    lines = ['<?xml version="1.0" encoding="UTF-8"?>', "<config>"]
    for rid, name, ntri, support in objects:
        lines.append(f' <object id="{rid}" instances_count="1">')
        lines.append(f'  <metadata type="object" key="name" value={quoteattr(name)}/>')
        if support:  # a rod resting on its arc: support under the rising ends
            lines.append('  <metadata type="object" key="support_material" value="1"/>')
        lines.append(f'  <volume firstid="0" lastid="{ntri - 1}">')
        lines.append(f'   <metadata type="volume" key="name" value={quoteattr(name)}/>')
        lines.append("  </volume>")
        lines.append(" </object>")
    lines.append("</config>")
    return "\n".join(lines) + "\n"


def _package(objects: Sequence[tuple[str, np.ndarray, np.ndarray]]) -> tuple[bytes, list[tuple[int, str, int]]]:
    """A 3MF package (lib3mf, through build123d's Mesher) of named meshes, each a build item
    with the identity transform. Returns (bytes, [(resource id, name, triangles)])."""
    from build123d import Mesher
    from lib3mf import Lib3MF

    mesher = Mesher()
    model = mesher.model
    identity = mesher.wrapper.GetIdentityTransform()
    info = []
    for name, vertices, triangles in objects:
        mo = model.AddMeshObject()
        mo.SetName(name)
        v = np.ascontiguousarray(vertices, dtype=np.float32)
        t = np.ascontiguousarray(triangles, dtype=np.uint32)
        mo.SetGeometry(list((Lib3MF.Position * len(v)).from_buffer_copy(v.tobytes())),
                       list((Lib3MF.Triangle * len(t)).from_buffer_copy(t.tobytes())))
        mo.SetType(Lib3MF.ObjectType.Model)
        if not mo.IsManifoldAndOriented():
            raise ValueError(f"{name}: the mesh is not closed and oriented")
        model.AddBuildItem(mo, identity)
        info.append((int(mo.GetModelResourceID()), name, len(t)))
    return bytes(model.QueryWriter("3mf").WriteToBuffer()), info


def _write_zip(path: Path, package: bytes, extra: Mapping[str, str]) -> Path:
    """Copy lib3mf's package to ``path`` (through a temporary file) with the metadata files added."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".part")
    with zipfile.ZipFile(io.BytesIO(package)) as src, \
            zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as out:
        for item in src.infolist():
            if item.filename not in extra:
                out.writestr(item, src.read(item.filename), compress_type=zipfile.ZIP_DEFLATED)
        for name, text in extra.items():
            out.writestr(name, text)
    tmp.replace(path)
    return path


def _placed_vertices(mesh: _Mesh, placement: Placement) -> np.ndarray:
    v = mesh.vertices
    if placement.rotated:  # a quarter turn about Z, (x, y) -> (-y, x), back into x >= 0
        v = np.column_stack([v[:, 1].max() - v[:, 1], v[:, 0], v[:, 2]])
    return v + np.array([placement.offset[0], placement.offset[1], 0.0])


def _write_plates(rods: Sequence[FabricatedRod], path: str | Path, printer: Printer | None, prof: PrintProfile,
                  gap: float, margin: float, meshes: dict[int, _Mesh]) -> list[Path]:
    plates = _plan(rods, prof, printer, gap, margin, meshes)
    paths = plate_paths(path, len(plates))
    config = slicer_config(prof, printer)
    for plate, out in zip(plates, paths):
        objects = [(p.rod.file_stem, _placed_vertices(meshes[id(p.rod.solid)], p), meshes[id(p.rod.solid)].triangles)
                   for p in plate.placements]
        package, info = _package(objects)
        support = [bool(p.rod.print_note) for p in plate.placements]
        extra = {CONFIG_FILE: config,
                 MODEL_CONFIG_FILE: _model_config([(*i, s) for i, s in zip(info, support)])}
        if plate.pauses:
            extra[PAUSES_FILE] = pause_xml(plate.pauses, prof.pause_gcode)
        _write_zip(out, package, extra)
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
    default: what every designed mass assumes); a pause (M601) at every ball-insert layer
    in ``Metadata/Prusa_Slicer_custom_gcode_per_print_z.xml``, its message saying how
    many balls go into which rods. Rods whose pause heights differ go to different
    plates: ``path`` (print.3mf), then print-2.3mf, ...; files of an earlier run beyond
    the last plate are removed.

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


def write_rod_3mf(rod: FabricatedRod, path: str | Path) -> Path:
    """Write one rod as a plain 3MF (no slicer settings): one object named by its rod file
    stem, in print orientation on the bed (the geometry of rods/NN_TYPE.stl)."""
    mesh = _mesh(rod)
    package, _ = _package([(rod.file_stem, mesh.vertices, mesh.triangles)])
    return _write_zip(Path(path), package, {})


def write_print_files(rods: Sequence[FabricatedRod], outdir: str | Path, *, printer: Printer | None = None,
                      profile: Mapping[str, Any] | PrintProfile | None = None) -> list[Path]:
    """Write OUTDIR/print.3mf (and print-2.3mf, ... when one bed is not enough; see
    :func:`write_print_3mf`) and OUTDIR/rods/NN_TYPE.3mf for every rod
    (:func:`write_rod_3mf`), each distinct solid tessellated once.

    Returns:
        The paths written: the plates, then the rods' 3MF files.
    """
    outdir = Path(outdir)
    meshes: dict[int, _Mesh] = {}
    written = _write_plates(rods, outdir / "print.3mf", printer, PrintProfile.from_mapping(profile), 5.0, 5.0,
                            meshes)
    for rod in rods:  # rods sharing a solid share its mesh, each under its own name
        mesh = meshes[id(rod.solid)]
        package, _ = _package([(rod.file_stem, mesh.vertices, mesh.triangles)])
        written.append(_write_zip(outdir / "rods" / f"{rod.file_stem}.3mf", package, {}))
    return written
