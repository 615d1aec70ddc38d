"""The friction coupon's solids and files: the stand and the wheel
(:mod:`rodcad.catalog.coupon` has every dimension and the physics), each checked after every
boolean, written as one STEP assembly of named solids, an STL each on the bed and a
PrusaSlicer project with both on one plate.

Frames: the assembly frame of :class:`rodcad.catalog.coupon.CouponGeometry` (pin axis = z,
+y up). The stand prints upright (base on the bed: :func:`rodcad.cad.export.print_matrix`,
its pin holes lying flat like the rods'), the wheel flat on its back face (its cups open
upward). Units: mm.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from build123d import Face, Solid, Vector, Wire

from rodcad.cad.export import AssemblyPart, assembly_leaves, export_assembly, export_stl, print_matrix, transformed
from rodcad.cad.mesh import DEFLECTION, mesh_solid
from rodcad.cad.slicer import SlicerObject, bed, write_3mf
from rodcad.cad.solids import GeometryError, cylinder_solid, is_valid_solid, one_solid, prism_solid
from rodcad.catalog.coupon import (
    ENGRAVE,
    CouponError,
    CouponGeometry,
    number_polygons,
    pointer_polygon,
    tick_polygons,
)

__all__ = ["STAND_SETTINGS", "CouponBuild", "build_coupon", "build_stand", "build_wheel", "check_coupon_files",
           "write_coupon"]

#: Per-object slicer settings of the stand: nothing weighs it, so it need not be solid.
STAND_SETTINGS = {"fill_density": "25%"}
#: Colours in the STEP assembly.
_COLORS = {"stand": (0.6, 0.6, 0.65), "wheel": (0.95, 0.55, 0.1)}


def _yz_prism(points: Sequence[tuple[float, float]], x0: float, x1: float) -> Solid:
    """A (z, y) polygon extruded along x from x0 to x1."""
    wire = Wire.make_polygon([Vector(x0, y, z) for z, y in points], close=True)
    return Solid.extrude(Face(wire), Vector(x1 - x0, 0, 0))


def _box(x0: float, x1: float, y0: float, y1: float, z0: float, z1: float) -> Solid:
    return prism_solid([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], z0, z1)


def build_wheel(geom: CouponGeometry) -> Solid:
    """The wheel in the assembly frame, its rider ray straight down: a disc with a pointer at
    each end of the rider line, the option's tongue hole and a cup per pocket, open to the
    front (+z).

    Raises:
        GeometryError: a step leaves no single valid solid.
    """
    z0, z1 = geom.z_back, geom.z_front
    disc = cylinder_solid((0.0, 0.0), geom.wheel_radius, z0, z1)
    pointers = []
    for angle in (0.0, 180.0):
        a, tip, b = (np.array(p) for p in pointer_polygon(geom, angle))
        inward = 3.0  # the sides run on into the disc: they cross its edge, not touch it at a vertex
        pts = [a - inward * (tip - a) / np.linalg.norm(tip - a), tip, b - inward * (tip - b) / np.linalg.norm(tip - b)]
        pointers.append(prism_solid([tuple(p) for p in pts], z0, z1))
    wheel = one_solid(disc.fuse(*pointers).clean(), "adding the wheel's pointers")
    wheel = one_solid(wheel.cut(cylinder_solid((0.0, 0.0), geom.option.tongue_hole / 2, z0 - 1, z1 + 1)),
                      "boring the wheel's hole")
    cups = [cylinder_solid(p.center, geom.cup_diameter / 2, z0 + geom.floor, z1 + 1) for p in geom.pockets]
    wheel = one_solid(wheel.cut(*cups).clean(), "cutting the ball cups")
    wheel.label = "wheel"
    return wheel


def build_stand(geom: CouponGeometry) -> Solid:
    """The stand in the assembly frame: base, dial plate with its engraved scale and the back
    knuckle, the front post with its knuckle, gussets, and the pin hole through both.

    Raises:
        GeometryError: a step leaves no single valid solid.
    """
    rd, rk, h = geom.dial_radius, geom.knuckle_radius, geom.axis_height
    y_bed, y_top = -h - geom.base, -h
    zb, zf = geom.back_outer, geom.front_outer
    base = _box(-rd, rd, y_bed, y_top, zb - 22.0, zf + 18.0)
    plate = cylinder_solid((0.0, 0.0), rd, zb, geom.dial_face).fuse(
        _box(-rd, rd, y_bed, 0.0, zb, geom.dial_face))
    plate = one_solid(plate.intersect(_box(-rd - 1, rd + 1, y_bed, rd + 1, zb - 1, geom.dial_face + 1)),
                      "shaping the dial plate")
    w = geom.post_width / 2
    post = [_box(-w, w, y_bed, 0.0, geom.post_face, zf), cylinder_solid((0.0, 0.0), w, geom.post_face, zf)]
    knuckles = [cylinder_solid((0.0, 0.0), rk, geom.dial_face - 0.5, geom.z_back - geom.layer_gap),
                cylinder_solid((0.0, 0.0), rk, geom.z_front + geom.layer_gap, geom.post_face + 0.5)]
    gussets = [_yz_prism([(zb + 0.5, y_top - 0.5), (zb - 20.0, y_top - 0.5), (zb + 0.5, y_top + 30.0)], x, x + 4.0)
               for x in (-rd + 8.0, rd - 12.0)]
    gussets.append(_yz_prism([(zf - 0.5, y_top - 0.5), (zf + 14.0, y_top - 0.5), (zf - 0.5, y_top + 20.0)], -2.0, 2.0))
    stand = one_solid(base.fuse(plate, *post, *knuckles, *gussets).clean(), "joining the stand")
    stand = one_solid(stand.cut(cylinder_solid((0.0, 0.0), geom.option.fork_hole / 2, zb - 1, zf + 1)),
                      "boring the pin holes")
    marks = tick_polygons(geom) + [s for n in number_polygons(geom) for s in n]
    tools = [prism_solid(p, geom.dial_face - ENGRAVE, geom.dial_face + 0.5) for p in marks]
    stand = one_solid(stand.cut(*tools).clean(), "engraving the angle scale")
    stand.label = "stand"
    return stand


def _wheel_matrix(geom: CouponGeometry, wheel: Solid) -> np.ndarray:
    """The wheel flat on its back face, its box from the origin."""
    bb = wheel.bounding_box()
    m = np.eye(4)
    m[:3, 3] = (-bb.min.X, -bb.min.Y, -geom.z_back)
    return m


@dataclass
class CouponBuild:
    """A built coupon.

    Attributes:
        geometry: its numbers.
        stand, wheel: the solids in the assembly frame.
        wheel_volume: the wheel's B-rep volume (mm^3).
        wheel_mass: the wheel with its hardware (g), from that volume.
        files: what was written, by name.
    """

    geometry: CouponGeometry
    stand: Solid
    wheel: Solid
    wheel_volume: float
    wheel_mass: float
    files: dict[str, Path] = field(default_factory=dict)


def build_coupon(geom: CouponGeometry) -> CouponBuild:
    """Both solids, the wheel's volume checked against the closed form.

    Raises:
        GeometryError: a solid fails, or the wheel's B-rep volume is off its closed form.
    """
    wheel = build_wheel(geom)
    stand = build_stand(geom)
    v = float(wheel.volume)
    if abs(v - geom.wheel_volume()) > 1e-6 * v:
        raise GeometryError(f"the wheel's solid holds {v:.4f} mm^3, its closed form {geom.wheel_volume():.4f}")
    return CouponBuild(geom, stand, wheel, v, geom.wheel_mass(v))


def _plate(build: CouponBuild, printer, gap: float = 10.0) -> list[SlicerObject]:
    """Both parts on one bed: the stand behind, the wheel in front, centred as a block."""
    meshes = []
    for name, solid, m in (("stand", build.stand, print_matrix(build.stand)),
                           ("wheel", build.wheel, _wheel_matrix(build.geometry, build.wheel))):
        mesh = mesh_solid(transformed(solid, m))
        v = mesh.vertices - mesh.vertices.min(axis=0)
        meshes.append((name, v, mesh.triangles))
    (bx, by, bz), _ = bed(printer)
    sizes = [v.max(axis=0) for _, v, _ in meshes]
    width = max(s[0] for s in sizes)
    depth = sizes[0][1] + gap + sizes[1][1]
    if width > bx - 10 or depth > by - 10 or max(s[2] for s in sizes) > bz:
        raise CouponError(f"the coupon ({width:.0f} x {depth:.0f} mm on the bed) does not fit the printer's "
                          f"{bx:g} x {by:g} mm bed")
    y0 = (by - depth) / 2
    out = []
    for (name, v, tri), s, y in zip(meshes, sizes, (y0, y0 + sizes[0][1] + gap)):
        placed = v + np.array([(bx - s[0]) / 2, y, 0.0])
        out.append(SlicerObject(name, placed, tri, settings=STAND_SETTINGS if name == "stand" else {}))
    return out


def write_coupon(build: CouponBuild, folder: Path, *, profile=None, printer=None) -> dict[str, Path]:
    """Write coupon.step (the stand and the wheel as assembled, named solids), stand.stl and
    wheel.stl (on the bed, as they print) and coupon.3mf (both on one plate, the catalog's
    print profile; the stand at :data:`STAND_SETTINGS`), then check them
    (:func:`check_coupon_files`).

    Returns:
        The paths, by name ('step', 'stand.stl', 'wheel.stl', '3mf').
    """
    folder = Path(folder)
    g = build.geometry
    files = {"step": folder / "coupon.step"}
    export_assembly(files["step"], [AssemblyPart(n, s, np.eye(4), _COLORS[n])
                                    for n, s in (("stand", build.stand), ("wheel", build.wheel))],
                    name=f"coupon-{g.option.name}")
    for name, solid, m in (("stand", build.stand, print_matrix(build.stand)),
                           ("wheel", build.wheel, _wheel_matrix(g, build.wheel))):
        files[f"{name}.stl"] = export_stl(transformed(solid, m), folder / f"{name}.stl")
    files["3mf"] = write_3mf(folder / "coupon.3mf", _plate(build, printer), {}, profile=profile, printer=printer)
    check_coupon_files(files, {"stand": float(build.stand.volume), "wheel": build.wheel_volume})
    build.files = files
    return files


def check_coupon_files(files: dict[str, Path], volumes: dict[str, float], deflection: float = DEFLECTION) -> None:
    """The written coupon checked: the STEP re-imports as the named solids, each valid with
    its volume (to 1e-6); each STL, read back by trimesh, is watertight with that volume to
    within ``deflection`` times the solid's area; the 3MF is there.

    Raises:
        GeometryError: what is wrong.
    """
    import trimesh

    back = {label: s for label, s in assembly_leaves(files["step"])}
    if sorted(back) != sorted(volumes):
        raise GeometryError(f"{files['step']} holds {sorted(back)}, expected {sorted(volumes)}")
    for name, volume in volumes.items():
        s = back[name]
        if not is_valid_solid(s):
            raise GeometryError(f"{files['step']}: the {name} does not re-import as a valid solid")
        if abs(s.volume - volume) > 1e-6 * volume:
            raise GeometryError(f"{files['step']}: the {name} re-imports with {s.volume:.4f} mm^3, not {volume:.4f}")
        mesh = trimesh.load(str(files[f"{name}.stl"]), force="mesh")
        if not mesh.is_watertight:
            raise GeometryError(f"{files[f'{name}.stl']} is not watertight")
        if abs(mesh.volume - volume) > deflection * s.area:
            raise GeometryError(f"{files[f'{name}.stl']} encloses {mesh.volume:.3f} mm^3, the solid {volume:.3f}")
    if not files["3mf"].is_file():
        raise GeometryError(f"{files['3mf']} was not written")

