"""What a catalog's rods are made of and printed on: material, metal balls, loose shot, the
printer, and where a value was written (numbers only; re-exported by
:mod:`rodcad.catalog.model`)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from rodcad.errors import Problem

__all__ = ["DEFAULT_MODULUS", "Balls", "Fill", "Material", "Origin", "Printer"]

#: A printed rod's Young's modulus when its catalog gives none (GPa): the low end of PLA, PETG and
#: ABS printed along their rods (about 1.5-3.5 GPa).
DEFAULT_MODULUS = 1.5


@dataclass(frozen=True)
class Material:
    """Printing material.

    Attributes:
        name: e.g. 'PLA'.
        density: g/cm^3 (PLA about 1.24).
        min_wall: thinnest wall printed reliably, also the least plastic kept
            around cavities and ball sockets (mm).
        modulus: Young's modulus of the printed part along its rods (GPa): what a pushing net
            rod's buckling load follows (:meth:`rodcad.catalog.net.node.NodeHardware.buckling_load`).
    """

    name: str
    density: float
    min_wall: float
    modulus: float = DEFAULT_MODULUS

    def key_data(self) -> dict:
        """What a rod's solids and masses depend on (cache keys): every field but the modulus,
        which only bounds how hard a net rod may push."""
        return {k: v for k, v in asdict(self).items() if k != "modulus"}


@dataclass(frozen=True)
class Balls:
    """Metal balls a rod may hold in closed sockets (inserted at a print pause).

    Attributes:
        diameter: ball diameter (mm).
        density: g/cm^3 (steel 7.85).
        clearance: socket diameter minus ball diameter (mm).
        name: free text, e.g. 'steel 5 mm'.
    """

    diameter: float
    density: float
    clearance: float
    name: str = ""

    @property
    def mass(self) -> float:
        """Mass of one ball (g)."""
        return math.pi / 6 * self.diameter**3 * self.density / 1000.0

    @property
    def socket_diameter(self) -> float:
        """Diameter of the spherical socket holding one ball (mm)."""
        return self.diameter + self.clearance


@dataclass(frozen=True)
class Fill:
    """Loose dense shot a rod's chamber may be filled with at a print pause (rods printed to
    order; see :mod:`rodcad.catalog.chamber`).

    Attributes:
        name: e.g. 'tungsten shot'.
        density: of the metal (g/cm^3): tungsten 19.3, lead 11.35, steel 7.85.
        packing: fraction of the chamber the shot fills (random loose packing of spheres
            about 0.6).
    """

    name: str
    density: float
    packing: float

    @property
    def effective_density(self) -> float:
        """Grams of shot per cm^3 of chamber (g/cm^3)."""
        return self.density * self.packing


@dataclass(frozen=True)
class Printer:
    """The printer a catalog is sized for.

    Attributes:
        build_volume: (x, y, z) of the build volume (mm).
        nozzle: nozzle diameter (mm).
        name: free text.
        mesh_deflection: the STL/3MF meshes' linear deflection (mm, absolute), or None for
            the default, a quarter of the print's layer height (:func:`rodcad.cad.mesh.print_deflection`).
        mesh_angle: their angular deflection (degrees), or None for the default.
    """

    build_volume: tuple[float, float, float]
    nozzle: float
    name: str = ""
    mesh_deflection: float | None = None
    mesh_angle: float | None = None


@dataclass(frozen=True)
class Origin:
    """Where something was defined, for problems found after loading."""

    file: str
    key: str
    line: int
    column: int

    def problem(self, message: str, key: str | None = None) -> Problem:
        return Problem(self.file, self.line, self.column, self.key if key is None else key, message)
