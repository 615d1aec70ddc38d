"""Writing and reading solids: STEP (single solids and named, coloured assemblies), STL,
print orientation and placement matrices.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from build123d import Color, Compound, Location, Solid
from build123d import export_step as _export_step
from build123d import import_step as _import_step
from OCP.gp import gp_Trsf
from OCP.TopLoc import TopLoc_Location

from rodcad.cad.mesh import ANGULAR, DEFLECTION, mesh_solid, write_stl
from rodcad.cad.solids import GeometryError

__all__ = ['export_step', 'import_step', 'matrix_location', 'transformed', 'PRINT_ROTATION', 'print_matrix', 'export_stl', 'AssemblyPart', 'AssemblyGroup', 'export_assembly', 'assembly_leaves', 'read_assembly', 'placed', 'check_files', 'export_instanced_assembly']


def export_step(solid: Solid, path: str | os.PathLike[str], name: str | None = None) -> Path:
    """Write a solid to a STEP file (mm), its product named after the solid.

    Args:
        solid: what to write.
        path: destination file.
        name: product name (default: the solid's label).

    Returns:
        The path written.
    """
    if name is not None:
        solid.label = name
    path = Path(path)
    if not _export_step(solid, path):  # pragma: no cover - writer failure
        raise OSError(f"could not write {path}")
    return path


def import_step(path: str | os.PathLike[str]) -> Solid:
    """Read a single-solid STEP file back (label = product name).

    Raises:
        GeometryError: the file does not hold exactly one solid.
    """
    shape = _import_step(Path(path))
    solids = shape.solids()
    if len(solids) != 1:
        raise GeometryError(f"{path} holds {len(solids)} solids, expected 1")
    solid = solids[0]
    solid.label = shape.label or solid.label
    return solid


def matrix_location(matrix: np.ndarray) -> Location:
    """The build123d Location of a rigid 4x4 matrix (mm)."""
    m = np.asarray(matrix, dtype=float)
    t = gp_Trsf()
    t.SetValues(*(float(x) for x in m[:3, :4].reshape(-1)))
    return Location(TopLoc_Location(t))


def transformed(solid: Solid, matrix: np.ndarray) -> Solid:
    """A copy of ``solid`` with the rigid 4x4 ``matrix`` baked into its geometry."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform

    m = np.asarray(matrix, dtype=float)
    t = gp_Trsf()
    t.SetValues(*(float(x) for x in m[:3, :4].reshape(-1)))
    out = Solid(BRepBuilderAPI_Transform(solid.wrapped, t, True).Shape())
    out.label = solid.label
    return out


#: Rotation taking the rod frame to the print bed: +y (rod) -> +Z (printer),
#: +z (rod, the hinge axes) -> -Y, x stays x; the rod lies on its -y face.
PRINT_ROTATION = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])


def print_matrix(solid: Solid) -> np.ndarray:
    """4x4 matrix placing a rod-frame solid on the bed: rotated by
    :data:`PRINT_ROTATION` and moved so its bounding box starts at (0, 0, 0)
    (Z = 0 is the bed)."""
    m = np.eye(4)
    m[:3, :3] = PRINT_ROTATION
    bb = solid.bounding_box()
    corners = np.array([[x, y, z] for x in (bb.min.X, bb.max.X) for y in (bb.min.Y, bb.max.Y)
                        for z in (bb.min.Z, bb.max.Z)]) @ PRINT_ROTATION.T
    m[:3, 3] = -corners.min(axis=0)
    return m


def export_stl(solid: Solid, path: str | os.PathLike[str], *, tolerance: float = DEFLECTION,
               angular_tolerance: float = ANGULAR) -> Path:
    """Write a binary STL (mm) of the solid, meshed to an absolute deflection, closed and
    checked (:func:`rodcad.cad.mesh.mesh_solid`).

    Args:
        solid: what to write.
        path: destination.
        tolerance: linear deflection of the mesh (mm, absolute).
        angular_tolerance: angular deflection (rad).
    """
    return write_stl(mesh_solid(solid, deflection=tolerance, angular=angular_tolerance), path,
                     name=solid.label or "rodcad")


@dataclass
class AssemblyPart:
    """A named solid in an assembly.

    Attributes:
        name: label (the STEP product / instance name).
        solid: the solid in its own frame.
        location: rigid 4x4 placement (mm) relative to the parent.
        color: (r, g, b) in 0..1, or None.
    """

    name: str
    solid: Solid
    location: np.ndarray
    color: tuple[float, float, float] | None = None


@dataclass
class AssemblyGroup:
    """A named sub-assembly.

    Attributes:
        name: label.
        children: parts and groups.
        location: rigid 4x4 placement (mm) relative to the parent (default identity).
    """

    name: str
    children: Sequence[AssemblyPart | AssemblyGroup]
    location: np.ndarray = field(default_factory=lambda: np.eye(4))


def _assembly_node(node: AssemblyPart | AssemblyGroup) -> Compound | Solid:
    if isinstance(node, AssemblyPart):
        from OCP.BRepBuilderAPI import BRepBuilderAPI_Copy

        # A copy per part: parts sharing one TShape would be merged into one
        # product by the writer (one name, one colour, placements lost).
        shape = Solid(BRepBuilderAPI_Copy(node.solid.wrapped).Shape())
        shape.label = node.name
        if node.color is not None:
            shape.color = Color(*(float(c) for c in node.color))
        shape.location = matrix_location(node.location)
        return shape
    kids = [_assembly_node(c) for c in node.children]
    comp = Compound(children=kids, label=node.name)
    comp.location = matrix_location(node.location)
    return comp


def export_assembly(path: str | os.PathLike[str], nodes: Sequence[AssemblyPart | AssemblyGroup],
                    name: str = "assembly") -> Path:
    """Write a STEP assembly: named, coloured solids placed by 4x4 matrices in
    named groups (written through build123d's XCAF exporter: product names,
    colours and placements survive; identical solids are written once and
    instanced).

    Args:
        path: destination file.
        nodes: parts and groups of the top level.
        name: label of the root assembly.

    Returns:
        The path written.
    """
    root = Compound(children=[_assembly_node(n) for n in nodes], label=name)
    path = Path(path)
    if not _export_step(root, path):  # pragma: no cover - writer failure
        raise OSError(f"could not write {path}")
    return path


def assembly_leaves(path: str | os.PathLike[str]) -> list[tuple[str, Solid]]:
    """The leaf solids of a STEP file, depth first, as (label of the leaf shape, solid), each
    with its placement in the assembly in its geometry (build123d's XCAF importer)."""
    root = _import_step(Path(path))
    out: list[tuple[str, Solid]] = []

    def walk(shape: object) -> None:
        kids = list(getattr(shape, "children", ()) or ())
        if kids:
            for k in kids:
                walk(k)
            return
        for s in shape.solids():  # type: ignore[attr-defined]
            out.append((getattr(shape, "label", "") or "", s))

    walk(root)
    if len({label for label, _ in out}) < len(out):  # shared products: name each leaf by its instance
        named = _instance_leaves(Path(path))
        if len(named) == len(out):
            return named
    return out


def _instance_leaves(path: Path) -> list[tuple[str, Solid]]:
    """The leaf solids of a STEP assembly, depth first, each named by its instance (the
    NEXT_ASSEMBLY_USAGE_OCCURRENCE's name; the product's where it has none) and placed, read
    through OCC's XCAF document: a product instanced several times
    (:func:`export_instanced_assembly`) gives one leaf per instance."""
    from OCP.collections import Sequence_TDF_Label
    from OCP.STEPCAFControl import STEPCAFControl_Reader
    from OCP.TCollection import TCollection_AsciiString, TCollection_ExtendedString
    from OCP.TDataStd import TDataStd_Name
    from OCP.TDF import TDF_Label
    from OCP.TDocStd import TDocStd_Document
    from OCP.XCAFDoc import XCAFDoc_DocumentTool, XCAFDoc_ShapeTool

    reader = STEPCAFControl_Reader()
    reader.SetNameMode(True)
    reader.ReadFile(str(path))
    doc = TDocStd_Document(TCollection_ExtendedString("XmlOcaf"))
    reader.Transfer(doc)
    tool = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())

    def name(label) -> str:
        attr = TDataStd_Name()
        found = label.FindAttribute(TDataStd_Name.GetID_s(), attr)
        return TCollection_AsciiString(attr.Get()).ToCString() if found else ""

    out: list[tuple[str, Solid]] = []

    def walk(label, loc: TopLoc_Location, own: str) -> None:
        if XCAFDoc_ShapeTool.IsAssembly_s(label):
            comps = Sequence_TDF_Label()
            XCAFDoc_ShapeTool.GetComponents_s(label, comps, False)
            for i in range(1, comps.Length() + 1):
                c, ref = comps.Value(i), TDF_Label()
                XCAFDoc_ShapeTool.GetReferredShape_s(c, ref)
                walk(ref, loc.Multiplied(XCAFDoc_ShapeTool.GetLocation_s(c)), name(c) or name(ref))
            return
        for s in Compound(XCAFDoc_ShapeTool.GetShape_s(label).Moved(loc)).solids():
            s.label = own or name(label)
            out.append((s.label, s))

    free = Sequence_TDF_Label()
    tool.GetFreeShapes(free)
    for i in range(1, free.Length() + 1):
        walk(free.Value(i), TopLoc_Location(), name(free.Value(i)))
    return out


def read_assembly(path: str | os.PathLike[str]) -> list[tuple[str, float]]:
    """The leaf solids of a STEP file as (label, volume mm^3), depth first."""
    return [(label or s.label, float(s.volume)) for label, s in assembly_leaves(path)]


def _trsf_of(matrix: np.ndarray) -> gp_Trsf:
    """gp_Trsf of a rigid 4x4 matrix."""
    m = np.asarray(matrix, dtype=float)
    t = gp_Trsf()
    t.SetValues(*(float(x) for x in m[:3, :4].reshape(-1)))
    return t


def placed(solid: Solid, matrix: np.ndarray) -> Solid:
    """A copy of ``solid`` moved by the rigid 4x4 ``matrix`` (geometry baked in, label kept)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform

    shape = BRepBuilderAPI_Transform(solid.wrapped, _trsf_of(matrix), True).Shape()
    out = Solid(shape)
    out.label = solid.label
    return out


def rod_matrix(origin: Sequence[float], theta: float) -> np.ndarray:
    """Rod frame -> chain-plane frame (4x4): the rod's first joint at ``origin`` (x, y), its
    chord at angle ``theta`` (rad) from +x, hinge axes along +z."""
    c, s = math.cos(theta), math.sin(theta)
    m = np.eye(4)
    m[:2, :2] = [[c, -s], [s, c]]
    m[:2, 3] = origin
    return m


def rod_matrices(points: np.ndarray) -> list[np.ndarray]:
    """:func:`rod_matrix` of every rod of a chain with joints ``points`` (N+1, 2): rod i at
    p_i, x along p_i -> p_{i+1}."""
    p = np.asarray(points, dtype=float)
    d = np.diff(p, axis=0)
    return [rod_matrix(p[i], math.atan2(d[i, 1], d[i, 0])) for i in range(len(d))]


def check_files(step: Path, stl: Path, volume: float, deflection: float = DEFLECTION, *,
                coarse: bool = False, precise: bool = False) -> None:
    """A written solid checked: the STEP re-imports as one valid solid of the same volume (to
    1e-6 of it; ``precise``: both volumes integrated to 1e-9, ``volume`` by
    :func:`rodcad.cad.solids.precise_volume`, where build123d's fixed rule is itself a few 1e-6
    off, as on a hub's many spherical and conical faces) and the STL, read back by trimesh, is watertight with that volume to within its accuracy: ``deflection``
    (mm, the STL's absolute linear deflection) times the solid's area, and (unless ``coarse``:
    a mesh as coarse as the print allows, :func:`rodcad.cad.mesh.print_deflection`) within
    :data:`rodcad.fabrication.cavities.MASS_TOL` of it.

    Raises:
        FabricationError: what is wrong.
    """
    import trimesh

    from rodcad.cad.solids import is_valid_solid, precise_volume
    from rodcad.fabrication.cavities import MASS_TOL, FabricationError

    back = import_step(step)
    if not is_valid_solid(back):
        raise FabricationError(f"{step} does not re-import as a valid solid")
    got = precise_volume(back) if precise else back.volume
    if abs(got - volume) > 1e-6 * volume:
        raise FabricationError(f"{step} re-imports with volume {got:.4f} instead of {volume:.4f} mm^3")
    mesh = trimesh.load(str(stl), force="mesh")
    if not mesh.is_watertight:
        raise FabricationError(f"{stl} is not watertight")
    bound = deflection * back.area if coarse else min(MASS_TOL * volume, deflection * back.area)
    if abs(mesh.volume - volume) > bound:
        raise FabricationError(f"{stl} encloses {mesh.volume:.3f} mm^3, the solid {volume:.3f} mm^3 "
                               f"({(mesh.volume - volume) / volume:+.2%})")


def export_instanced_assembly(path: str | os.PathLike[str], parts: Sequence[AssemblyPart],
                              name: str = "assembly") -> Path:
    """Write a STEP assembly in which parts holding the same ``solid`` object are one product
    (its shape written once, named after its first part, coloured by it) placed as several
    named instances (NEXT_ASSEMBLY_USAGE_OCCURRENCE), each at its own 4 x 4 placement: a
    net's equal rods and hubs. Written with OCC's XCAF document directly (build123d's exporter
    merges shared shapes into one placement).

    Args:
        path: destination file.
        parts: the instances (AssemblyPart: instance name, shared solid in its own frame,
            placement, colour).
        name: the root assembly's name.

    Returns:
        The path written.
    """
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.Interface import Interface_Static
    from OCP.Message import Message, Message_Gravity
    from OCP.Quantity import Quantity_Color, Quantity_TOC_RGB
    from OCP.STEPCAFControl import STEPCAFControl_Writer
    from OCP.STEPControl import STEPControl_AsIs
    from OCP.TCollection import TCollection_ExtendedString
    from OCP.TDataStd import TDataStd_Name
    from OCP.TDocStd import TDocStd_Document
    from OCP.XCAFDoc import XCAFDoc_ColorType, XCAFDoc_DocumentTool

    doc = TDocStd_Document(TCollection_ExtendedString("XmlOcaf"))
    shapes = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())
    colors = XCAFDoc_DocumentTool.ColorTool_s(doc.Main())
    root = shapes.NewShape()
    TDataStd_Name.Set_s(root, TCollection_ExtendedString(name))
    products: dict[int, object] = {}
    for part in parts:
        label = products.get(id(part.solid))
        if label is None:
            shape = part.solid.wrapped.Located(TopLoc_Location())
            label = products[id(part.solid)] = shapes.AddShape(shape, False)
            TDataStd_Name.Set_s(label, TCollection_ExtendedString(part.name))
            if part.color is not None:
                colors.SetColor(label, Quantity_Color(*(float(c) for c in part.color), Quantity_TOC_RGB),
                                XCAFDoc_ColorType.XCAFDoc_ColorSurf)
        comp = shapes.AddComponent(root, label, TopLoc_Location(_trsf_of(part.location)))
        TDataStd_Name.Set_s(comp, TCollection_ExtendedString(part.name))
    shapes.UpdateAssemblies()
    for printer in Message.DefaultMessenger_s().Printers():  # no transfer statistics on the console
        printer.SetTraceLevel(Message_Gravity.Message_Fail)
    Interface_Static.SetCVal_s("write.step.unit", "MM")
    writer = STEPCAFControl_Writer()
    writer.SetColorMode(True)
    writer.SetNameMode(True)
    writer.Transfer(doc, STEPControl_AsIs)
    path = Path(path)
    if writer.Write(str(path)) != IFSelect_RetDone:  # pragma: no cover - writer failure
        raise OSError(f"could not write {path}")
    return path
