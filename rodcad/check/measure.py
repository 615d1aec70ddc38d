"""Each rod of a build as it is now: read, checked, measured, compared with design.json.

Per rod (:func:`read_rods`): its STEP file (or its solid in an assembly STEP, matched by
name) is read and must be one valid closed solid; it is brought back to the rod frame (the
inverse of its print matrix, or of its placement in the hanging chain for an assembly);
its plastic volume and centre of volume come from the B-rep, the inserts design.json
records are added (metal balls at their centres, the shot of a fill chamber at its centre), and the rod counts as *edited* when its mass moved by
more than :data:`EDIT_MASS_REL` (relative) or its centre of mass by more than
:data:`EDIT_COM_MM`. Its pin holes must still be where the chain needs them: along z
through (0, 0) and (length, 0) of the rod frame a pin must pass
(:func:`rodcad.cad.reread.pin_hole`: no material within the pin's radius) and material must
still surround the hole (at least :data:`MIN_AROUND` of what the rod type has there).

:func:`joint_overlaps` then checks the joints next to edited rods on the solids: at the
chain's new bend, and just inside the design's joint limits, the two rods must not overlap.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rodcad.cad.export import rod_matrices
from rodcad.cad.reread import (
    PinHole,
    hinge_reference,
    hole_radii,
    measure,
    moved,
    pair_overlap,
    pin_hole,
    read_assembly_rods,
    read_rod_step,
    shape_problem,
)
from rodcad.cad.solids import GeometryError
from rodcad.catalog.model import RodType
from rodcad.check.built import BuiltChain, BuiltRod
from rodcad.errors import InputError, Problem

__all__ = [
    "EDIT_COM_MM",
    "EDIT_MASS_REL",
    "JointOverlap",
    "LIMIT_MARGIN_DEG",
    "MIN_AROUND",
    "RodReading",
    "joint_overlaps",
    "read_rods",
]

#: A rod whose mass moved by more than this (relative) counts as edited.
EDIT_MASS_REL = 1e-6

#: ... or whose centre of mass moved by more than this (mm).
EDIT_COM_MM = 1e-4

#: Material a pin passes through, at most (mm^3): round-off of the boolean.
BLOCKED_TOL = 1e-3

#: Least fraction of the rod type's material around a pin hole an edited rod keeps.
MIN_AROUND = 0.9

#: Joint limits are checked this far inside (deg): at the limit itself the rods touch.
LIMIT_MARGIN_DEG = 0.05


@dataclass
class RodReading:
    """One rod as it is now.

    Attributes:
        index: chain position.
        file: the file it was read from.
        solid: the solid in the rod frame (a build123d ``Solid``).
        volume: plastic volume (mm^3).
        mass: plastic plus the recorded balls (g).
        com: (along, perp) centre of mass (mm, rod frame).
        edited: mass or centre of mass differ from design.json's as-built ones.
        mass_change: (mass - built mass) / built mass.
        com_shift: distance of the centre of mass from the built one (mm).
        pins: what is around its first and second pin holes.
    """

    index: int
    file: Path
    solid: Any
    volume: float
    mass: float
    com: np.ndarray
    edited: bool
    mass_change: float
    com_shift: float
    pins: tuple[PinHole, PinHole]


@dataclass(frozen=True)
class JointOverlap:
    """Two neighbouring rods that overlap at a bend.

    Attributes:
        joint: the joint between rods ``joint`` and ``joint + 1`` (design.json's ``limits_deg``
            of rod ``joint``).
        bend_deg: the bend tested (deg).
        where: 'pose' (the chain's new equilibrium bend), 'lo' or 'hi' (just inside a limit).
        overlap: shared volume (mm^3).
    """

    joint: int
    bend_deg: float
    where: str
    overlap: float

    def sentence(self) -> str:
        if self.where == "pose":
            return (f"rods {self.joint} and {self.joint + 1} overlap by {self.overlap:.3g} mm^3 at the bend the chain "
                    f"would now hang at ({self.bend_deg:.2f} deg): the edited rods collide there, so the chain "
                    "cannot hang as simulated; take material off where they meet")
        side = "lower" if self.where == "lo" else "upper"
        return (f"rods {self.joint} and {self.joint + 1} overlap by {self.overlap:.3g} mm^3 just inside the joint's "
                f"{side} limit ({self.bend_deg:.2f} deg): the edit narrowed how far the joint can bend")


def _inserts(rod: BuiltRod, m: np.ndarray) -> tuple[float, np.ndarray]:
    """Mass (g) and first moment (g mm, (along, perp)) of the inserts design.json records (metal
    balls at their centres, the shot of a fill chamber at its centre), in the frame the 4x4
    ``m`` takes the rod's frame to."""
    first = np.zeros(2)
    k = len(rod.ball_centers)
    if k:
        first += rod.ball_mass / k * (rod.ball_centers @ m[:2, :3].T + m[:2, 3]).sum(axis=0)
    if rod.fill_mass and rod.fill_center is not None:
        first += rod.fill_mass * (m[:2, :2] @ np.asarray(rod.fill_center, float) + m[:2, 3])
    return rod.ball_mass + rod.fill_mass, first


def _measured(rods: list[tuple[BuiltRod, np.ndarray]], volume: float, center: tuple[float, float, float],
              density: float) -> tuple[float, np.ndarray]:
    """Mass (g) and (along, perp) centre of mass of plastic plus the recorded inserts of the
    rods (each with its 4x4 rod frame -> measured frame)."""
    mass = volume * density
    first = mass * np.array(center[:2], float)
    for rod, m in rods:
        extra, moment = _inserts(rod, m)
        mass += extra
        first = first + moment
    return mass, first / mass


def _label_index(label: str) -> int | None:
    m = re.match(r"\s*(\d+)(?:-\d+)?_", label)
    return int(m.group(1)) if m else None


def _assembly_solids(built: BuiltChain, path: Path) -> tuple[dict[int, Any], list[Problem]]:
    """Rod index -> solid in the rod frame, from an assembly STEP in the built pose."""
    try:
        parts = read_assembly_rods(path)
    except GeometryError as err:
        return {}, [Problem(str(path), 0, 0, "", str(err))]
    mats = rod_matrices(built.simulated)
    found: dict[int, list[Any]] = {}
    for label, solid in parts:
        i = _label_index(label)
        if i is None or i >= built.n:
            continue
        want = built.rods[i].stem.replace(".", "_")
        if not label.replace(".", "_").startswith(want):
            continue
        found.setdefault(i, []).append(solid)
    out: dict[int, Any] = {}
    problems = []
    for r in built.rods:
        solids = found.get(r.index if r.piece is None else r.piece[0], [])  # a piece: at its first rod
        if len(solids) != 1:
            problems.append(Problem(str(path), 0, 0, r.stem, f"{len(solids)} solids named {r.stem!r}; the assembly "
                                    "must hold each rod once, named as rodcad named it"))
            continue
        bad = shape_problem(solids[0])
        if bad:
            problems.append(Problem(str(path), 0, 0, r.stem, bad))
            continue
        out[r.index] = moved(solids[0], np.linalg.inv(mats[r.index]))
    return out, problems


def _read_one(rod: BuiltRod, solid: Any | None, density: float,
              reference: Callable[..., tuple[PinHole, PinHole]], rtype: RodType,
              source: Path | None = None) -> RodReading | str:
    """Measure one rod (``solid`` already in the rod frame, read from ``source``, or None:
    read its STEP file); a string says what is wrong with it."""
    if solid is None:
        if not rod.file.is_file():
            return "is missing (every rod's STEP file must be there; restore it from the build)"
        try:
            solid = moved(read_rod_step(rod.file), np.linalg.inv(rod.print_matrix))
        except GeometryError as err:
            return str(err)
    volume, center = measure(solid)
    mass, com = _measured([(rod, np.eye(4))], volume, center, density)
    change = (mass - rod.mass) / rod.mass
    shift = float(np.hypot(*(com - rod.com)))
    edited = abs(change) > EDIT_MASS_REL or shift > EDIT_COM_MM
    pins = _pins(rod, solid, rtype, reference(rtype, rod.hole_sizes) if edited else None)
    if isinstance(pins, str):
        return pins
    return RodReading(rod.index, source or rod.file, solid, volume, mass, com, edited, change, shift, pins)


def _pins(rod: BuiltRod, solid: Any, rtype: RodType, ref: tuple[PinHole, PinHole] | None,
          ends: tuple[int, ...] = (0, 1)) -> tuple[PinHole, PinHole] | str:
    """What is around the rod's pin holes at ``ends`` (``ref``: the rod type's, None for an
    unchanged solid), or what is wrong with them."""
    g = rtype.geometry
    pins = []
    radii = hole_radii(rtype, rod.hole_sizes)
    for k, x in enumerate((0.0, rod.length)):
        if ref is None or k not in ends:  # an unchanged solid keeps its holes: skip the booleans
            pins.append(PinHole(0.0, math.nan))
            continue
        p = pin_hole(solid, x, pin_radius=radii[k][0], hole_radius=radii[k][1],
                     knuckle_radius=g.hinge.knuckle_radius, thickness=g.thickness)
        which = ("first", "(0, 0)") if k == 0 else ("second", f"({rod.length:.3f}, 0)")
        if p.blocked > BLOCKED_TOL:
            return (f"its {which[0]} pin hole is blocked: {p.blocked:.3g} mm^3 of material where the "
                    f"{2 * radii[k][0]:g} mm pin goes (along z through {which[1]} of the rod frame); the hole "
                    "was filled or moved. Keep the rod where it was saved: its placement is how rodcad finds "
                    "the holes")
        if p.around < MIN_AROUND * ref[k].around:
            return (f"its {which[0]} pin hole lost the material around it ({100 * p.around / ref[k].around:.0f} % "
                    f"of the design's within 1 mm of the hole, along z through {which[1]} of the rod frame): the "
                    "hole moved or the knuckle was cut away")
        pins.append(p)
    return pins[0], pins[1]


def _read_piece(rods: list[BuiltRod], solid: Any | None, density: float,
                reference: Callable[..., tuple[PinHole, PinHole]], rtypes: list[RodType],
                source: Path | None = None) -> list[RodReading] | str:
    """Measure a fused piece as a whole (``solid`` in its first rod's frame, or None: read
    the piece's STEP file once). For the re-simulation its rods keep their built mass
    proportions, scaled to the measured total, and their centres of mass move by one common
    offset in the chain plane, so the piece's centre of mass is the measured one: all a
    rigid piece's equilibrium depends on. Only its outer pin holes are checked."""
    first = rods[0]
    to_first = np.linalg.inv(first.print_matrix)
    if solid is None:
        if not first.file.is_file():
            return "is missing (every piece's STEP file must be there; restore it from the build)"
        try:
            solid = moved(read_rod_step(first.file), to_first)
        except GeometryError as err:
            return str(err)
    mats = [to_first @ r.print_matrix for r in rods]  # rod frame -> the first rod's
    volume, center = measure(solid)
    mass, com = _measured(list(zip(rods, mats)), volume, center, density)
    built = np.array([r.mass for r in rods], float)
    c0 = sum(r.mass * (m[:2, :2] @ r.com + m[:2, 3]) for r, m in zip(rods, mats)) / built.sum()
    scale, offset = mass / built.sum(), com - c0
    change, shift = float(scale - 1), float(np.hypot(*offset))
    edited = abs(change) > EDIT_MASS_REL or shift > EDIT_COM_MM
    out = []
    for k, (r, m, rtype) in enumerate(zip(rods, mats, rtypes)):
        own = moved(solid, np.linalg.inv(m))  # the piece in this rod's frame
        ends = tuple(e for e, outer in ((0, k == 0), (1, k == len(rods) - 1)) if outer)
        pins = _pins(r, own, rtype, reference(rtype, r.hole_sizes) if edited and ends else None, ends)
        if isinstance(pins, str):
            return f"rod {r.index}: {pins}"
        out.append(RodReading(r.index, source or r.file, own, volume * r.mass / built.sum(), r.mass * scale,
                              r.com + m[:2, :2].T @ offset, edited, change, shift, pins))
    return out


def read_rods(built: BuiltChain, types: list[RodType], *, assembly: Path | None = None) -> list[RodReading]:
    """Read, check and measure every rod of a build (see the module's doc).

    Args:
        built: the build's design.json.
        types: the rod type per position (:func:`rodcad.check.types.chain_types`).
        assembly: read the rods from this assembly STEP (in the pose design.json's
            ``simulated.points`` gives, as ``assembly.step`` is written) instead of rods/*.step.

    Raises:
        InputError: a file that is missing or not one valid closed solid, or a rod whose pin
            holes moved or vanished (every problem, each naming its file).
    """
    solids: dict[int, Any] = {}
    problems: list[Problem] = []
    if assembly is not None:
        solids, problems = _assembly_solids(built, assembly)
    refs: dict[tuple, tuple[PinHole, PinHole]] = {}

    def ref(rtype: RodType, sizes=(None, None)) -> tuple[PinHole, PinHole]:
        key = (rtype.name, tuple(sizes))
        if key not in refs:
            refs[key] = hinge_reference(rtype, sizes)
        return refs[key]

    out: list[RodReading] = []
    for rod, rtype in zip(built.rods, types):
        if assembly is not None and rod.index not in solids:
            continue
        if rod.piece is None:
            got: RodReading | list[RodReading] | str = _read_one(rod, solids.get(rod.index), built.density, ref,
                                                                 rtype, assembly)
        elif rod.index == rod.piece[0]:  # a fused piece: read and measured once, as a whole
            a, b = rod.piece
            got = _read_piece(built.rods[a:b + 1], solids.get(rod.index), built.density, ref, types[a:b + 1],
                              assembly)
        else:
            continue
        if isinstance(got, str):
            where = str(assembly) if assembly is not None else str(rod.file)
            problems.append(Problem(where, 0, 0, rod.stem if assembly is not None else "", got))
        else:
            out += got if isinstance(got, list) else [got]
    if problems:
        raise InputError(problems)
    return out


def _test_bends(lo: float, hi: float, pose: float) -> list[tuple[str, float]]:
    """(where, bend deg) to test at a joint with limits [lo, hi] (deg, +-inf where free)."""
    m = LIMIT_MARGIN_DEG
    at = float(np.clip(pose, lo + m, hi - m)) if hi - lo > 2 * m else pose
    tests = [("pose", at)]
    for where, limit in (("lo", lo + m), ("hi", hi - m)):
        if math.isfinite(limit) and hi - lo > 2 * m and abs(limit - at) > 1e-9:  # a joint on a stop: tested once
            tests.append((where, limit))
    return tests


def joint_overlaps(built: BuiltChain, readings: list[RodReading], bends_deg: np.ndarray) -> list[JointOverlap]:
    """The joints next to an edited rod where the two rods overlap, at the chain's new
    bend or just inside a design limit (every other joint is as designed)."""
    out = []
    lim = np.degrees(built.limits)
    for j in range(built.n - 1):
        a, b = readings[j], readings[j + 1]
        if not (a.edited or b.edited) or built.rods[j].piece is not None and built.rods[j].piece == built.rods[j + 1].piece:
            continue  # unchanged, or fused inside one piece
        for where, phi in _test_bends(lim[j, 0], lim[j, 1], float(bends_deg[j])):
            v = pair_overlap(a.solid, b.solid, built.rods[j].length, phi)
            if v > 0:
                out.append(JointOverlap(j, phi, where, v))
    return out
