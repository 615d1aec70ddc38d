"""Re-reading rods after manual edits (``rodcad check``): the kernel side.

A person opens a build's STEP files in FreeCAD (or any CAD), changes a rod and saves it
again. :mod:`rodcad.check` decides what that means for the chain; the solids are read,
checked, placed and measured here:

- :func:`read_rod_step` reads one rod file and says what is wrong with it, if anything
  (not one solid, not valid, not closed);
- :func:`read_assembly_rods` reads the leaf solids of an assembly STEP with their names
  and placements (``assembly.step`` exported back from FreeCAD);
- :func:`moved` places a solid by a rigid 4x4 matrix (e.g. the inverse of a rod's print
  matrix, from the bed back to the rod frame);
- :func:`pin_hole` measures whether a pin still passes along a joint axis and how much
  material still surrounds it;
- :func:`pair_overlap` is the volume two neighbouring rods share at a bend angle.

Units: mm, mm^3, degrees.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from build123d import Solid
from build123d import import_step as _b3d_import_step
from OCP.BRep import BRep_Tool
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.gp import gp_Ax1, gp_Dir, gp_Pnt, gp_Trsf, gp_Vec
from OCP.TopLoc import TopLoc_Location

from rodcad.cad.export import assembly_leaves, export_step, export_stl, transformed
from rodcad.cad.solids import NO_SHIFT, OWN_SIZES, GeometryError, cylinder_solid, mass_properties, type_solid
from rodcad.catalog.model import RodType

__all__ = [
    "PinHole",
    "hinge_reference",
    "hole_radii",
    "measure",
    "moved",
    "pair_overlap",
    "pin_hole",
    "read_assembly_rods",
    "read_rod_step",
    "shape_problem",
    "write_rod_step",
    "write_rod_stl",
]


#: Overlaps (mm^3) at or below this are round-off of the boolean, not material.
OVERLAP_TOL = 1e-3


def _shape_problem(solid: Solid) -> str:
    """'' for a valid closed solid, else what is wrong with it (in words)."""
    try:
        if not solid.is_valid or not BRepCheck_Analyzer(solid.wrapped).IsValid():
            return "the solid is not valid (faces that cross or do not meet)"
        open_shells = [s for s in solid.shells() if not BRep_Tool.IsClosed_s(s.wrapped)]
        if open_shells:
            return f"the solid is not closed ({len(open_shells)} open shell(s)): a face is missing"
        if not solid.volume > 0:
            return f"the solid encloses no volume ({solid.volume:.3g} mm^3): its faces point inwards or it is empty"
    except Exception as err:  # noqa: BLE001 - the kernel's own errors, reported as a bad file
        return f"the kernel cannot check the solid ({type(err).__name__}: {err})"
    return ""


def read_rod_step(path: str | os.PathLike[str]) -> Solid:
    """Read one rod back from a STEP file: exactly one valid, closed solid.

    Args:
        path: the STEP file (e.g. ``OUTDIR/rods/01_free-40.step``), in whatever placement
            it was saved.

    Returns:
        The solid, as placed in the file (label: the STEP product name).

    Raises:
        GeometryError: the file cannot be read, holds no solid or several, or its solid is
            not valid or not closed (the message says which, in words).
    """
    path = Path(path)
    try:
        shape = _b3d_import_step(path)
    except Exception as err:  # noqa: BLE001 - any reader failure is a bad file
        raise GeometryError(f"cannot be read as STEP ({type(err).__name__}: {err})") from None
    try:
        solids = shape.solids()
    except Exception:  # noqa: BLE001
        solids = []
    if len(solids) != 1:
        shells = len(shape.shells()) if hasattr(shape, "shells") else 0
        what = (f"{len(solids)} solids" if solids else
                f"no closed solid ({shells} open shell(s) or faces only)" if shells else "no solid")
        raise GeometryError(f"holds {what}; a rod file must hold exactly one closed solid (fuse the pieces, "
                            "or close the surface, before saving)")
    solid = solids[0]
    problem = _shape_problem(solid)
    if problem:
        raise GeometryError(problem)
    solid.label = getattr(shape, "label", "") or solid.label
    return solid


def read_assembly_rods(path: str | os.PathLike[str]) -> list[tuple[str, Solid]]:
    """The leaf solids of an assembly STEP as (name, solid), depth first, each with its
    placement in the assembly baked into its geometry.

    Raises:
        GeometryError: the file cannot be read.
    """
    try:
        leaves = assembly_leaves(path)
    except Exception as err:  # noqa: BLE001
        raise GeometryError(f"cannot be read as STEP ({type(err).__name__}: {err})") from None
    return [(label or str(s.label or ""), s) for label, s in leaves]


def shape_problem(solid: Solid) -> str:
    """'' for a valid closed solid, else what is wrong with it (for solids read from an
    assembly; :func:`read_rod_step` checks its own)."""
    return _shape_problem(solid)


def moved(solid: Solid, matrix: np.ndarray) -> Solid:
    """A copy of ``solid`` moved by the rigid 4x4 ``matrix`` (geometry baked in)."""
    return transformed(solid, np.asarray(matrix, dtype=float))


def measure(solid: Solid) -> tuple[float, tuple[float, float, float]]:
    """(volume mm^3, centre of the volume (x, y, z) mm) from the B-rep."""
    props = mass_properties(solid)
    return props.volume, props.center


@dataclass(frozen=True)
class PinHole:
    """What is around one joint axis of a rod (rod frame, axis along z through (x, 0)).

    Attributes:
        blocked: material volume (mm^3) inside the pin's radius, through the whole rod
            thickness: 0 where the pin passes.
        around: the fraction of a thin tube just outside the hole (to 1 mm beyond it, or
            halfway to the knuckle's rim) that is material, over the rod's thickness.
    """

    blocked: float
    around: float


def _volume(shape: object) -> float:
    if shape is None:
        return 0.0
    try:
        return float(sum(s.volume for s in shape.solids()))  # type: ignore[attr-defined]
    except Exception:  # noqa: BLE001 - an empty or degenerate common
        return 0.0


def _tube(x: float, r0: float, r1: float, half: float) -> Solid:
    outer = cylinder_solid((x, 0.0), r1, -half, half)
    return outer.cut(cylinder_solid((x, 0.0), r0, -half - 1.0, half + 1.0))


def pin_hole(solid: Solid, x: float, *, pin_radius: float, hole_radius: float, knuckle_radius: float,
             thickness: float) -> PinHole:
    """Whether a pin of ``pin_radius`` passes through ``solid`` along the z axis through
    (x, 0), and how much material surrounds the hole (see :class:`PinHole`).

    The pin's cylinder runs 1 mm past both faces of the rod; the tube starts 0.01 mm
    outside the hole's radius.
    """
    half = thickness / 2 + 1.0
    blocked = _volume(solid.intersect(cylinder_solid((x, 0.0), pin_radius, -half, half)))
    r0 = hole_radius + 0.01
    r1 = min(hole_radius + 1.0, (hole_radius + knuckle_radius) / 2)
    tube = _tube(x, r0, r1, half)
    around = _volume(solid.intersect(tube)) / max(float(tube.volume), 1e-12)
    return PinHole(blocked, around)


def hole_radii(rod: RodType, sizes=OWN_SIZES) -> tuple[tuple[float, float], tuple[float, float]]:
    """Per joint, (the radius of a pin that passes, the hole's radius) (mm): the hinge's own
    pin and hole, or the joint hardware's hole ``sizes`` (a pin 0.05 mm under its radius)."""
    h = rod.geometry.hinge
    out = []
    for d in sizes:
        hole = h.hole_diameter if d is None else float(d)
        out.append((min(h.pin_diameter, hole - 0.1) / 2, hole / 2))
    return out[0], out[1]


def hinge_reference(rod: RodType, sizes=OWN_SIZES) -> tuple[PinHole, PinHole]:
    """:func:`pin_hole` at both joints of the rod type's plain solid, as designed (no
    cavities or sockets: they stay clear of the hinges), with the joint hardware's holes
    ``sizes`` (:data:`rodcad.cad.solids.Sizes`)."""
    solid = type_solid(rod, NO_SHIFT, tuple(sizes))
    g = rod.geometry
    out = []
    for x, (pin, hole) in zip((0.0, g.length), hole_radii(rod, sizes)):
        out.append(pin_hole(solid, x, pin_radius=pin, hole_radius=hole, knuckle_radius=g.hinge.knuckle_radius,
                            thickness=g.thickness))
    return out[0], out[1]


def _bend(axis_x: float, phi_deg: float) -> gp_Trsf:
    move = gp_Trsf()
    move.SetTranslation(gp_Vec(axis_x, 0, 0))
    turn = gp_Trsf()
    turn.SetRotation(gp_Ax1(gp_Pnt(axis_x, 0, 0), gp_Dir(0, 0, 1)), math.radians(phi_deg))
    return turn.Multiplied(move)


def pair_overlap(left: Solid, right: Solid, axis_x: float, phi_deg: float) -> float:
    """Volume (mm^3) the rods ``left`` and ``right`` (each in its rod frame) share when
    joined at ``left``'s second joint, (axis_x, 0, 0), with the bend ``phi_deg`` (the
    right rod turned counter-clockwise about +z by it; 0 = straight). 0 when they only
    touch or are apart (round-off up to :data:`OVERLAP_TOL` counts as 0)."""
    placed = Solid(right.wrapped.Moved(TopLoc_Location(_bend(axis_x, phi_deg))))
    try:
        v = _volume(left.intersect(placed))
    except Exception as err:  # noqa: BLE001 - a kernel failure on the common
        raise GeometryError(f"the overlap of the rods at {phi_deg:.3f} deg cannot be computed ({err})") from None
    return 0.0 if v <= OVERLAP_TOL else v


def write_rod_step(solid: Solid, print_matrix: np.ndarray, step: Path, name: str) -> tuple[Path, Path]:
    """Write a rod-frame solid on the print bed (placed by ``print_matrix``) as
    ``step`` and the STL beside it; check that the STEP reads back as one valid solid of
    the same volume (1e-6).

    Returns:
        (STEP path, STL path).

    Raises:
        GeometryError: the file does not read back as written.
    """
    on_bed = transformed(solid, np.asarray(print_matrix, dtype=float))
    export_step(on_bed, step, name)
    stl = step.with_suffix(".stl")
    export_stl(on_bed, stl)
    back = read_rod_step(step)
    vol = float(on_bed.volume)
    if abs(float(back.volume) - vol) > 1e-6 * vol:
        raise GeometryError(f"{step} reads back with volume {back.volume:.4f} instead of {vol:.4f} mm^3")
    return step, stl


def write_rod_stl(solid: Solid, print_matrix: np.ndarray, path: Path) -> Path:
    """Write a rod-frame solid on the print bed (placed by ``print_matrix``) as an STL."""
    return export_stl(transformed(solid, np.asarray(print_matrix, dtype=float)), path)
