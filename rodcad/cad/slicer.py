"""PrusaSlicer's side of the slicer files: the print profile the masses assume, the
metadata files PrusaSlicer reads from a 3MF project, and the 3MF package itself.

The package is written here, one zip archive compressed once: the 3MF core parts
(``[Content_Types].xml``, ``_rels/.rels`` and ``3D/3dmodel.model``, the meshes and build items,
:func:`model_xml`; lib3mf, which wrote them before, spent most of a big net's print files'
time converting vertices to and from Python objects, and its archive was then unpacked and
packed again to add) and the PrusaSlicer metadata files:

- ``Metadata/Slic3r_PE.config``: the print settings, one ``; key = value`` line each
  (PrusaSlicer reads them bottom up and stops at the first line of another form, so the
  file starts with a header line);
- ``Metadata/Prusa_Slicer_custom_gcode_per_print_z.xml``: the pauses,
  ``<code print_z=.. type="1" extruder="1" color="" extra="message" gcode="M601"/>``
  (type 1 is ``CustomGCode::PausePrint``; PrusaSlicer writes the message as ``M117``
  before the pause G-code) and ``<mode value="SingleExtruder"/>``;
- ``Metadata/Slic3r_PE_model.config``: each object's name (PrusaSlicer names the only
  object of a foreign 3MF after the file otherwise) and, for rods that rest on their
  arc, support under the rising ends.

Mass. With 100 % infill the slicer extrudes the sliced area times the layer height, less
the corners its rounded-rectangle extrusions leave between perimeters and infill:
``h^2 (1 - pi/4)`` per perimeter edge and layer. ``infill_overlap`` is set to exactly that
over the perimeter width (PrusaSlicer's automatic width, 1.125 x the nozzle), 9.5 % for a
0.2 mm layer and a 0.4 mm nozzle; PrusaSlicer's own default, 25 %, over-extrudes rods by
1-2.5 %. Bridges are laid at the layer height (``thick_bridges = 0``; thick ones would
sag extra plastic into sockets and cavities), and there is no elephant-foot or XY size
compensation. Support is off but where an object asks for it: the slicer's support
under a curved rod's rising ends is plastic printed beside the rod, not part of it.

Units: mm, g, g/cm^3.
"""

from __future__ import annotations

import math
import zipfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any
from xml.sax.saxutils import quoteattr

import numpy as np

from rodcad.cad.mesh import closed_oriented
from rodcad.fabrication.layers import LayerGrid

if TYPE_CHECKING:  # pragma: no cover
    from rodcad.catalog.model import Printer

__all__ = ["CONFIG_FILE", "CONTENT_TYPES", "DEFAULT_BUILD_VOLUME", "DEFAULT_NOZZLE", "MODEL_CONFIG_FILE",
           "MODEL_FILE", "PAUSES_FILE", "RELS", "PrintProfile", "SlicerObject", "bed", "model_config", "model_xml",
           "pause_xml", "slicer_config", "write_3mf"]

#: Build volume (x, y, z, mm) assumed when the catalog names no printer.
DEFAULT_BUILD_VOLUME = (220.0, 220.0, 250.0)
#: Nozzle diameter (mm) assumed when the catalog names no printer.
DEFAULT_NOZZLE = 0.4
CONFIG_FILE = "Metadata/Slic3r_PE.config"
PAUSES_FILE = "Metadata/Prusa_Slicer_custom_gcode_per_print_z.xml"
MODEL_CONFIG_FILE = "Metadata/Slic3r_PE_model.config"


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

    @property
    def layers(self) -> LayerGrid:
        """The layer tops this profile prints (:class:`rodcad.fabrication.layers.LayerGrid`)."""
        return LayerGrid(float(self.layer_height), self.first_layer)

    def layer_top(self, k: int) -> float:
        """Top (print_z) of layer k (0 = the first layer), mm."""
        return self.layers.top(k)

    def pause_z(self, roof: float) -> float:
        """The print_z to pause at for a socket whose roof is ``roof`` mm above the bed:
        the top of the first layer sliced (at mid-height) at or above the roof, i.e. the
        layer that bridges the socket; the pause comes before it is printed."""
        return self.layers.pause_z(roof)

    def infill_overlap(self, nozzle: float) -> float:
        """The infill/perimeter overlap (fraction of the perimeter width) that fills the
        corners the rounded extrusions leave: ``h (1 - pi/4) / (1.125 nozzle)``."""
        return float(self.layer_height) * (1 - math.pi / 4) / (1.125 * nozzle)


@dataclass(frozen=True)
class SlicerObject:
    """One object of a 3MF project: a closed mesh in bed coordinates.

    Attributes:
        name: the object's name (a rod's file stem).
        vertices: (n, 3) mm, on the bed.
        triangles: (m, 3) vertex indices.
        support: the slicer adds support under it (a rod resting on its arc).
        settings: further per-object settings (PrusaSlicer keys, e.g.
            ``support_material_buildplate_only``).
        instances: 4 x 4 placements of the mesh on the bed, one build item each (PrusaSlicer
            reads them as instances of one object: one mesh, printed that many times); empty:
            one item, the vertices already on the bed.
    """

    name: str
    vertices: np.ndarray
    triangles: np.ndarray
    support: bool = False
    settings: Mapping[str, str] = field(default_factory=dict)
    instances: Sequence[np.ndarray] = ()


def bed(printer: Printer | None) -> tuple[tuple[float, float, float], float]:
    """((x, y, z) build volume, nozzle diameter) of the printer (mm); the defaults without one."""
    if printer is None:
        return DEFAULT_BUILD_VOLUME, DEFAULT_NOZZLE
    x, y, z = (float(v) for v in printer.build_volume)
    return (x, y, z), float(printer.nozzle)


def slicer_config(profile: Mapping[str, Any] | PrintProfile | None = None, printer: Printer | None = None, *,
                  pauses: bool = False) -> str:
    """Metadata/Slic3r_PE.config: the print settings as PrusaSlicer reads them.

    ``pauses``: the project pauses to insert parts (steel balls, shot). Its travel moves then
    stay over the printed layer (``avoid_crossing_perimeters``): a net rod's steel ball stands
    up to 2.9 mm above the layer it went in at (:mod:`rodcad.cad.net.print_files`), and straight
    travel at the layer's height (no z lift) crossed the balls a hundred times before their
    tops were covered (a 2-ball rod sliced by PrusaSlicer 2.5); over the layer, never."""
    p = PrintProfile.from_mapping(profile)
    (bx, by, bz), nozzle = bed(printer)

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
        "avoid_crossing_perimeters": "1" if pauses else "0",
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


def model_config(objects: Sequence[tuple[Any, ...]]) -> str:
    """Metadata/Slic3r_PE_model.config: (resource id, name, triangles, support[, settings])
    per object."""
    lines = ['<?xml version="1.0" encoding="UTF-8"?>', "<config>"]
    for rid, name, ntri, support, *more in objects:
        count = int(more[1]) if len(more) > 1 else 1
        lines.append(f' <object id="{rid}" instances_count="{count}">')
        lines.append(f'  <metadata type="object" key="name" value={quoteattr(name)}/>')
        if support:  # a rod resting on its arc: support under the rising ends
            lines.append('  <metadata type="object" key="support_material" value="1"/>')
        for key, value in (more[0] if more else {}).items():
            lines.append(f'  <metadata type="object" key={quoteattr(str(key))} value={quoteattr(str(value))}/>')
        lines.append(f'  <volume firstid="0" lastid="{ntri - 1}">')
        lines.append(f'   <metadata type="volume" key="name" value={quoteattr(name)}/>')
        lines.append("  </volume>")
        lines.append(" </object>")
    lines.append("</config>")
    return "\n".join(lines) + "\n"


#: The 3MF package's fixed parts: its content types and its root relationship to the model.
CONTENT_TYPES = ('<?xml version="1.0" encoding="UTF-8"?>\n'
                 '<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">\n'
                 ' <Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/>\n'
                 ' <Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>\n'
                 ' <Default Extension="png" ContentType="image/png"/>\n'
                 '</Types>\n')
RELS = ('<?xml version="1.0" encoding="UTF-8"?>\n'
        '<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">\n'
        ' <Relationship Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel" '
        'Target="/3D/3dmodel.model" Id="rel0"/>\n'
        '</Relationships>\n')
MODEL_FILE = "3D/3dmodel.model"


def _transform(matrix: np.ndarray) -> str:
    """A rigid 4 x 4 as a build item's ``transform``: 3MF multiplies row vectors, so it lists
    the rotation's columns, then the translation."""
    m = np.asarray(matrix, float)
    return " ".join(f"{x:.9g}" for x in [*m[:3, :3].T.ravel(), *m[:3, 3]])


def _rows(fmt: str, values: np.ndarray) -> str:
    """``fmt`` once per row of ``values``, formatted in one pass."""
    return (fmt * len(values)) % tuple(values.ravel().tolist())


def model_xml(objects: Sequence[SlicerObject]) -> tuple[str, list[tuple[int, str, int]]]:
    """3D/3dmodel.model (the 3MF core specification's XML) of named meshes: each object one
    mesh resource and one build item per instance (without a transform where it has none: the
    vertices already on the bed). Vertices are written to 1e-6 mm, as lib3mf writes them.
    Returns (XML, [(resource id, name, triangles)]).

    Raises:
        ValueError: a mesh is not closed and oriented (every edge in two triangles, once each
            way: lib3mf's ``IsManifoldAndOriented``), or indexes a vertex it does not have.
    """
    out = ['<?xml version="1.0" encoding="UTF-8"?>\n<model unit="millimeter" xml:lang="en-US" '
           'xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02">\n <resources>\n']
    items, info = [], []
    for rid, obj in enumerate(objects, 1):
        v = np.asarray(obj.vertices, dtype=float).reshape(-1, 3)
        t = np.asarray(obj.triangles, dtype=np.int64).reshape(-1, 3)
        if not len(t) or t.min() < 0 or t.max() >= len(v) or not closed_oriented(t):
            raise ValueError(f"{obj.name}: the mesh is not closed and oriented")
        out.append(f'  <object id="{rid}" name={quoteattr(obj.name)} type="model">\n   <mesh>\n    <vertices>\n')
        out.append(_rows('     <vertex x="%.6f" y="%.6f" z="%.6f"/>\n', v))
        out.append("    </vertices>\n    <triangles>\n")
        out.append(_rows('     <triangle v1="%d" v2="%d" v3="%d"/>\n', t))
        out.append("    </triangles>\n   </mesh>\n  </object>\n")
        for m in obj.instances if len(obj.instances) else [None]:
            items.append(f'  <item objectid="{rid}"/>\n' if m is None else
                         f'  <item objectid="{rid}" transform="{_transform(m)}"/>\n')
        info.append((rid, obj.name, len(t)))
    out += [" </resources>\n <build>\n", *items, " </build>\n</model>\n"]
    return "".join(out), info


def write_3mf(path: str | Path, objects: Sequence[SlicerObject], pauses: Mapping[float, str], *,
              profile: Mapping[str, Any] | PrintProfile | None = None, printer: Printer | None = None) -> Path:
    """Write a PrusaSlicer project: the objects, the print settings of ``profile`` and the
    printer, each object's name and support, and a pause at every print_z of ``pauses``
    (with its message). Written through a temporary file, so an existing file is replaced
    whole or not at all.

    Returns:
        ``path``.
    """
    prof = PrintProfile.from_mapping(profile)
    model, info = model_xml(objects)
    files = {"[Content_Types].xml": CONTENT_TYPES, "_rels/.rels": RELS, MODEL_FILE: model,
             CONFIG_FILE: slicer_config(prof, printer, pauses=bool(pauses)),
             MODEL_CONFIG_FILE: model_config([(*i, o.support, o.settings, max(1, len(o.instances)))
                                               for i, o in zip(info, objects)])}
    if pauses:
        files[PAUSES_FILE] = pause_xml(pauses, prof.pause_gcode)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".part")
    with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as out:
        for name, text in files.items():
            out.writestr(name, text)
    tmp.replace(path)
    return path
