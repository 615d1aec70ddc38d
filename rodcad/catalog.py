"""Rod catalogs: parameterized rod families expanded into named rod types.

A catalog (``catalogs/*.yaml``) is the single source for the simulator (joint
limits, mass ranges, centres of mass) and the CAD (exact rod solids). This
module reads and validates it; the CAD and the numbers derived from the CAD
live in :mod:`rodcad.geometry`, :mod:`rodcad.limits` and
:mod:`rodcad.massrange`.

The format, in short (``catalogs/pla-pinned.yaml`` is a commented example, and
``catalogs/catalog.schema.json`` the generated JSON Schema)::

    catalog: 1                  # format version
    name: pla-pinned
    printer: {build_volume: [220, 220, 250], nozzle: 0.4}   # optional
    defaults: {...}             # any family key; every family inherits it
    families:
      - name: free
        length: [20, 30, 40]    # pin to pin, mm; a list makes several types
        scale: 1                # multiplies the cross-section and knuckles
        curvature: 0            # 1/mm, signed; > 0 bulges toward -y
        section: {height: 10, thickness: 8}
        joint: {pin_diameter: 1.75, pin_clearance: 0.25, knuckle_radius: 3.5,
                tongue_thickness: 2.8, layer_gap: 0.3, radial_gap: 0.4}
        ends: {setback: 0.2, top_chamfer: 50, bottom_chamfer: 50}
        material: {name: PLA, density: 1.24, min_wall: 1.2}
        balls: {diameter: 5, density: 7.85, clearance: 0.2}

Rod types are named ``<family>-<length>`` (plus ``-s<scale>`` / ``-k<curvature>``
when a family lists several scales / curvatures); they are listed family by
family, then by length, scale and curvature in the order written.

Conventions: millimetres, grams, degrees; densities in g/cm^3. Rod frame: the
first hinge axis through the origin, the second through (length, 0, 0), axes
along +z, chain plane xy. Top means +y. A chamfer angle tilts an end face away
from the partner rod (positive) or toward it (negative); see :class:`EndShape`.
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
from collections.abc import Iterator
from dataclasses import asdict, dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rodcad.cache import register_seed
from rodcad.errors import InputError, Problem
from rodcad.yamlio import (
    MISSING,
    Checked,
    Field,
    ListOf,
    Nullable,
    Num,
    Obj,
    OneOrList,
    Pos,
    Str,
    Validator,
    _suggest,
    check_document,
    child_path,
    format_number,
    load_yaml,
)

if TYPE_CHECKING:  # pragma: no cover
    from rodcad.massrange import MassInfo

__all__ = [
    "CATALOG_FORMAT",
    "GEOMETRY_VERSION",
    "Balls",
    "Catalog",
    "EndShape",
    "Family",
    "Hinge",
    "Material",
    "Printer",
    "RodGeometry",
    "RodType",
    "catalog_from_text",
    "catalog_schema",
    "default_catalog_dir",
    "load_catalog",
    "resolve_catalog",
    "shipped_catalogs",
]

#: The catalog format this code reads (the ``catalog:`` key).
CATALOG_FORMAT = 1

#: Version of how :mod:`rodcad.geometry` turns a :class:`RodGeometry` into a
#: solid. Bump it with any change there: it is part of every disk-cache key
#: (kept here so that cache hits need not import the CAD kernel).
GEOMETRY_VERSION = "1"

#: Largest half-angle of a curved rod's arc (the arc spans at most twice this).
MAX_ARC_HALF_ANGLE_DEG = 60.0

_NAME = r"[A-Za-z0-9][A-Za-z0-9_.+-]*"
_NAME_HINT = "a name of letters, digits, '.', '_', '+' or '-'"
_LAYOUTS = ("tongue-fork", "fork-tongue")


# --------------------------------------------------------------------------- data model


@dataclass(frozen=True)
class EndShape:
    """Shape of one rod end outside the hinge zone (the part that limits bending).

    The end face is two planes, one for the top (+y) half and one for the bottom
    half of the section, each parallel to the hinge axis. Each passes through
    the point ``setback`` mm back from the hinge axis along the rod's centreline
    tangent and is tilted by its chamfer angle: positive tilts the face away from
    the partner rod (cuts the corner back, more room to bend that way), negative
    tilts it toward the partner (the corner reaches past the hinge plane, so the
    joint stops before straight). Two facing square ends with setback s each and
    the pin at mid-height of a section of height h collide at
    ``2 * atan(2 s / h)``; faces with zero setback meet flush exactly at the sum
    of their chamfers.

    Attributes:
        setback: distance from the hinge axis to the face on the centreline (mm).
        top_chamfer: tilt of the top (+y) half face (deg).
        bottom_chamfer: tilt of the bottom (-y) half face (deg).
    """

    setback: float
    top_chamfer: float
    bottom_chamfer: float


@dataclass(frozen=True)
class Hinge:
    """Pinned hinge geometry shared by both ends of a rod (after scaling).

    The rod's thickness (z) is split into three layers: a middle *tongue* layer
    of ``tongue_thickness`` and two outer *fork prong* layers, separated by
    ``layer_gap``. One end of the rod carries the tongue knuckle, the other the
    fork (``layout``); a knuckle is a disc of ``knuckle_radius`` around the hinge
    axis with a pin hole of ``pin_diameter + pin_clearance``. Around each hinge
    axis, the layers the partner's knuckle occupies are cleared out to
    ``knuckle_radius + radial_gap`` (the *hinge zone*), so nothing inside the
    hinge zone ever collides; bending is limited by the end faces outside it.

    Attributes:
        layout: 'tongue-fork' (tongue at the first joint) or 'fork-tongue'.
        pin_diameter: diameter of the pin, which is not part of the rods (mm).
        pin_clearance: pin hole diameter minus pin diameter (mm).
        knuckle_radius: outer radius of the knuckles (mm).
        tongue_thickness: thickness of the middle layer (mm).
        layer_gap: axial clearance between tongue and prongs (mm).
        radial_gap: clearance around a partner's knuckle (mm).
    """

    layout: str
    pin_diameter: float
    pin_clearance: float
    knuckle_radius: float
    tongue_thickness: float
    layer_gap: float
    radial_gap: float

    @property
    def hole_diameter(self) -> float:
        """Diameter of the pin hole (mm)."""
        return self.pin_diameter + self.pin_clearance

    @property
    def zone_radius(self) -> float:
        """Radius of the hinge zone around each axis (mm)."""
        return self.knuckle_radius + self.radial_gap

    def knuckle(self, joint: int) -> str:
        """'tongue' or 'fork': the knuckle at the first (0) or second (1) joint."""
        first, second = self.layout.split("-")
        return first if joint == 0 else second


@dataclass(frozen=True)
class RodGeometry:
    """Everything that shapes a rod's solid (mm, deg), after scaling.

    Attributes:
        length: distance between the hinge axes (mm).
        height: section height in y, in the chain plane (mm).
        thickness: section thickness in z, along the hinge axes (mm).
        curvature: signed curvature of the body's centreline arc through both
            hinge axes (1/mm). Positive turns counter-clockwise going from the
            first to the second joint, so the arc bulges toward -y (like a
            sagging chain) and the centre of mass lies below the chord.
        hinge: the hinge geometry.
        first: end shape at the first joint (origin).
        second: end shape at the second joint (length, 0, 0).
    """

    length: float
    height: float
    thickness: float
    curvature: float
    hinge: Hinge
    first: EndShape
    second: EndShape

    @property
    def half_angle_deg(self) -> float:
        """Signed angle between the chord and the body's tangent at the second
        joint (deg); the tangent at the first joint is at minus this angle."""
        return math.degrees(math.asin(max(-1.0, min(1.0, self.curvature * self.length / 2))))

    def interface(self, joint: int) -> tuple[Any, ...]:
        """What must match for another rod's hinge to mate with ``joint`` (0 or 1)."""
        h = self.hinge
        return (self.thickness, h.pin_diameter, h.pin_clearance, h.knuckle_radius,
                h.tongue_thickness, h.layer_gap, h.radial_gap)

    def digest(self) -> str:
        """Stable hash of every parameter (used for disk caches)."""
        return _digest(asdict(self))


@dataclass(frozen=True)
class Material:
    """Printing material.

    Attributes:
        name: e.g. 'PLA'.
        density: g/cm^3 (PLA about 1.24).
        min_wall: thinnest wall printed reliably, also the least plastic kept
            around cavities and ball sockets (mm).
    """

    name: str
    density: float
    min_wall: float


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
class Printer:
    """The printer a catalog is sized for.

    Attributes:
        build_volume: (x, y, z) of the build volume (mm).
        nozzle: nozzle diameter (mm).
        name: free text.
    """

    build_volume: tuple[float, float, float]
    nozzle: float
    name: str = ""


@dataclass(frozen=True)
class Origin:
    """Where something was defined, for problems found after loading."""

    file: str
    key: str
    line: int
    column: int

    def problem(self, message: str, key: str | None = None) -> Problem:
        return Problem(self.file, self.line, self.column, self.key if key is None else key, message)


@dataclass(frozen=True)
class RodType:
    """One rod type of a catalog: a family with one length, scale and curvature.

    Attributes:
        name: unique within the catalog, e.g. 'free-30'.
        family: family name.
        length: pin to pin (mm).
        scale: cross-section scale factor.
        curvature: signed curvature (1/mm), positive bulges toward -y.
        geometry: everything that shapes the solid.
        material: printing material.
        balls: metal balls it may hold, or None.
        origin: where the type's family (or length) is written in the catalog.
    """

    name: str
    family: str
    length: float
    scale: float
    curvature: float
    geometry: RodGeometry
    material: Material
    balls: Balls | None
    origin: Origin = field(compare=False, repr=False)

    def solid(self) -> Any:
        """The exact B-rep solid (build123d ``Solid``) in the rod frame, labelled
        with the type's name. Built once per process.

        Raises:
            InputError: when the parameters make no valid solid (pointing at the
                family in the catalog).
        """
        from rodcad import geometry

        try:
            return geometry.rod_solid(self.geometry, self.name)
        except geometry.GeometryError as err:
            raise InputError([self.origin.problem(f"rod type {self.name!r}: {err}")]) from None

    def mass_info(self) -> MassInfo:
        """Volume, solid mass, centre of mass and mass range (disk-cached)."""
        from rodcad.massrange import mass_info

        return mass_info(self)

    @property
    def solid_mass(self) -> float:
        """Mass of the plain printed solid (g)."""
        return self.mass_info().solid_mass

    @property
    def com(self) -> tuple[float, float]:
        """Centre of mass (along, perp) in the rod frame (mm)."""
        return self.mass_info().com

    @property
    def mass_range(self) -> tuple[float, float]:
        """Achievable mass [m_min, m_max] (g): cavities to metal balls."""
        info = self.mass_info()
        return (info.m_min, info.m_max)


@dataclass(frozen=True)
class Family:
    """A family as written (after defaults): its name, types and origin."""

    name: str
    description: str
    type_names: tuple[str, ...]
    origin: Origin = field(compare=False, repr=False)


@dataclass(frozen=True)
class Catalog:
    """A validated catalog.

    Attributes:
        name: catalog name.
        description: free text.
        path: the file it was loaded from (None if built in code).
        types: rod types in catalog order.
        families: families in catalog order.
        printer: the printer it is sized for, if given.
    """

    name: str
    description: str
    path: Path | None
    types: tuple[RodType, ...]
    families: tuple[Family, ...]
    printer: Printer | None = None

    @cached_property
    def _by_name(self) -> dict[str, RodType]:
        return {t.name: t for t in self.types}

    @property
    def names(self) -> list[str]:
        """Type names in catalog order."""
        return [t.name for t in self.types]

    def __iter__(self) -> Iterator[RodType]:
        return iter(self.types)

    def __len__(self) -> int:
        return len(self.types)

    def __contains__(self, name: object) -> bool:
        return name in self._by_name

    def __getitem__(self, name: str) -> RodType:
        """The rod type called ``name``.

        Raises:
            KeyError: with a did-you-mean suggestion.
        """
        try:
            return self._by_name[name]
        except KeyError:
            raise KeyError(f"unknown rod type {name!r}{_suggest(name, self.names)}") from None

    def type(self, name_or_type: str | RodType) -> RodType:
        """Look up a type by name (a RodType is returned as is)."""
        return name_or_type if isinstance(name_or_type, RodType) else self[name_or_type]

    def can_join(self, left: str | RodType, right: str | RodType) -> bool:
        """Whether ``right`` can follow ``left`` in a chain: the knuckle at the
        left rod's second joint mates with the one at the right rod's first
        (a tongue with a fork, of identical hinge dimensions)."""
        a, b = self.type(left).geometry, self.type(right).geometry
        return (a.hinge.knuckle(1) != b.hinge.knuckle(0)) and a.interface(1) == b.interface(0)

    def pairs(self) -> list[tuple[RodType, RodType]]:
        """Every ordered pair (left, right) that can be joined, in catalog order."""
        return [(a, b) for a in self.types for b in self.types if self.can_join(a, b)]


def _digest(data: Any) -> str:
    text = json.dumps(data, sort_keys=True, separators=(",", ":"), default=repr)
    return hashlib.sha256(text.encode()).hexdigest()


# --------------------------------------------------------------------------- schema

_mm_pos = dict(exclusive_minimum=0, unit="mm")


def _end_fields(with_overrides: bool) -> dict[str, Field]:
    fields = {
        "setback": Field(
            Num(minimum=0, maximum=20, unit="mm"),
            default=0.2,
            description="Distance from the hinge axis back to the end face, along the rod's "
            "centreline (mm). Two facing ends leave the sum as a gap at straight; 0 makes "
            "faces that meet flush exactly at the sum of their chamfers.",
        ),
        "top_chamfer": Field(
            Num(minimum=-60, maximum=80, unit="deg"),
            default=0.0,
            description="Tilt of the top (+y) half of the end face (deg). Positive cuts the "
            "corner back (the joint can bend further in the sagging, positive direction); "
            "negative makes the corner reach past the hinge plane (the joint stops before "
            "straight: a concave stop).",
        ),
        "bottom_chamfer": Field(
            Num(minimum=-60, maximum=80, unit="deg"),
            default=0.0,
            description="Tilt of the bottom (-y) half of the end face (deg); positive lets the "
            "joint bend further in the negative (concave) direction.",
        ),
    }
    if with_overrides:
        sub = Obj(_end_fields(False)).replace(all_optional=True)
        for key, which in (("first", "first joint (origin)"), ("second", "second joint")):
            fields[key] = Field(
                Obj(
                    {k: Field(f.spec, description=f.description) for k, f in sub.fields.items()},
                    description=f"Overrides for the end at the {which}.",
                ),
                description=f"Overrides for the end at the {which}; unset keys come from above.",
            )
    return fields


def _family_spec() -> Obj:
    """Spec of a complete family (after defaults are applied): required flags
    and defaults here are the ones enforced after merging."""
    num_list = lambda spec, **kw: OneOrList(spec, unique=True, **kw)  # noqa: E731
    return Obj(
        {
            "name": Field(Str(pattern=_NAME, pattern_hint=_NAME_HINT), required=True,
                          description="Family name; types are named '<family>-<length>'."),
            "description": Field(Str(), description="Free text."),
            "length": Field(
                num_list(Num(exclusive_minimum=0, maximum=1000, unit="mm")),
                required=True,
                description="Distance between the two hinge axes (mm); a list makes one type per value.",
            ),
            "scale": Field(
                num_list(Num(exclusive_minimum=0, maximum=10)),
                default=[1.0],
                description="Cross-section scale factor: multiplies section height and thickness, "
                "knuckle radius and tongue thickness (not pins, gaps or setbacks); a list makes "
                "one type per value. Types of different scale do not join.",
            ),
            "curvature": Field(
                num_list(Num(minimum=-1, maximum=1, unit="1/mm")),
                default=[0.0],
                description="Signed curvature of the body's arc through both hinge axes (1/mm; "
                "1/radius). Positive bulges toward -y (below the chord, like a sagging chain), "
                "negative toward +y; 0 is straight. A list makes one type per value.",
            ),
            "section": Field(
                Obj(
                    {
                        "height": Field(Num(maximum=200, **_mm_pos), required=True,
                                        description="Section height in the chain plane, y (mm)."),
                        "thickness": Field(Num(maximum=200, **_mm_pos), required=True,
                                           description="Section thickness along the hinge axes, z (mm)."),
                    },
                    description="Rod cross-section before scaling.",
                ),
                required=True,
            ),
            "joint": Field(
                Obj(
                    {
                        "layout": Field(
                            Str(choices=_LAYOUTS), default="tongue-fork",
                            description="Which knuckle each end carries: 'tongue-fork' puts the "
                            "tongue (middle layer) at the first joint and the fork (two outer "
                            "layers) at the second. A rod's second joint mates with a rod whose "
                            "first joint has the other knuckle.",
                        ),
                        "pin_diameter": Field(Num(maximum=50, **_mm_pos), required=True,
                                              description="Pin diameter (mm); pins are separate parts, "
                                              "e.g. pieces of 1.75 mm filament."),
                        "pin_clearance": Field(Num(minimum=0, maximum=5, unit="mm"), default=0.25,
                                               description="Pin hole diameter minus pin diameter (mm)."),
                        "knuckle_radius": Field(Num(maximum=100, **_mm_pos), required=True,
                                                description="Outer radius of the knuckles around the "
                                                "hinge axis (mm, before scaling)."),
                        "tongue_thickness": Field(Num(maximum=100, **_mm_pos), required=True,
                                                  description="Thickness of the middle (tongue) layer "
                                                  "(mm, before scaling)."),
                        "layer_gap": Field(Num(maximum=5, **_mm_pos), default=0.3,
                                           description="Axial clearance between tongue and fork prongs (mm)."),
                        "radial_gap": Field(Num(maximum=5, **_mm_pos), default=0.4,
                                            description="Radial clearance around the partner's knuckle (mm)."),
                    },
                    description="Pinned hinge knuckles (see rodcad.catalog.Hinge).",
                ),
                required=True,
            ),
            "ends": Field(
                Obj(_end_fields(True), description="End faces outside the hinge zone: they set the "
                    "joint limits (see rodcad.catalog.EndShape)."),
                default={},
            ),
            "material": Field(
                Obj(
                    {
                        "name": Field(Str(), default="", description="e.g. PLA."),
                        "density": Field(Num(maximum=25, exclusive_minimum=0, unit="g/cm^3"), required=True,
                                         description="Density (g/cm^3)."),
                        "min_wall": Field(Num(maximum=50, **_mm_pos), required=True,
                                          description="Minimum wall (mm): thinnest printed wall, also kept "
                                          "around cavities, ball sockets and pin holes."),
                    },
                    description="Printing material.",
                ),
                required=True,
            ),
            "balls": Field(
                Nullable(
                    Obj(
                        {
                            "name": Field(Str(), default="", description="e.g. steel 5 mm."),
                            "diameter": Field(Num(maximum=100, **_mm_pos), required=True,
                                              description="Ball diameter (mm)."),
                            "density": Field(Num(maximum=25, exclusive_minimum=0, unit="g/cm^3"),
                                             required=True, description="Ball density (g/cm^3)."),
                            "clearance": Field(Num(minimum=0, maximum=5, unit="mm"), default=0.2,
                                               description="Socket diameter minus ball diameter (mm)."),
                        },
                    ),
                    description="Metal balls the rods may hold in closed sockets to add mass; "
                    "null for none.",
                ),
                default=None,
            ),
        },
        title="Rod family",
        description="A parameterized rod family; lists in length, scale or curvature make several types.",
    )


def _partial(spec: Any) -> Any:
    """The spec with nothing required and no defaults filled in, recursively
    (for family entries and 'defaults', which are merged before the required
    keys are enforced)."""
    if isinstance(spec, Obj):
        return Obj(
            {k: Field(_partial(f.spec), False, MISSING, f.description or "") for k, f in spec.fields.items()},
            title=spec.title,
            description=spec.description,
        )
    if isinstance(spec, Nullable):
        return Nullable(_partial(spec.inner), spec.description)
    return spec


def catalog_spec() -> Obj:
    """The spec of a whole catalog file."""
    family = _family_spec()
    entry = _partial(family)
    entry.fields["name"] = family.fields["name"]
    defaults = _partial(family)
    del defaults.fields["name"]
    defaults.title = "Defaults for every family"
    defaults.description = "Any family key except 'name'; a family's own keys win (mappings merge key by key)."
    return Obj(
        {
            "catalog": Field(Num(integer=True, minimum=1), required=True,
                             description=f"Catalog format version; this rodcad reads {CATALOG_FORMAT}."),
            "name": Field(Str(pattern=_NAME, pattern_hint=_NAME_HINT), required=True,
                          description="Catalog name."),
            "description": Field(Str(), description="Free text."),
            "printer": Field(
                Obj(
                    {
                        "name": Field(Str(), default="", description="Free text."),
                        "build_volume": Field(
                            ListOf(Num(maximum=5000, **_mm_pos), min_items=3),
                            required=True,
                            description="Build volume x, y, z (mm); every rod must fit.",
                        ),
                        "nozzle": Field(Num(maximum=5, **_mm_pos), required=True,
                                        description="Nozzle diameter (mm); the minimum wall must not be thinner."),
                    },
                    description="The printer the catalog is sized for (optional; enables size checks).",
                )
            ),
            "defaults": Field(defaults),
            "families": Field(ListOf(entry, min_items=1), required=True,
                              description="Rod families, in the order their types are listed."),
        },
        title="rodcad rod catalog",
        description="Parameterized rod families for rodcad (units: mm, g, deg; densities g/cm^3).",
    )


def catalog_schema() -> dict[str, Any]:
    """The JSON Schema of catalog files, generated from the validating specs."""
    schema = catalog_spec().json_schema()
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        **schema,
    }


# --------------------------------------------------------------------------- loading


def default_catalog_dir() -> Path:
    """The folder of shipped catalogs (``catalogs/`` next to the package)."""
    return Path(__file__).resolve().parent.parent / "catalogs"


def shipped_catalogs(base_dir: str | Path | None = None) -> list[str]:
    """Names of the catalogs in ``base_dir`` (default: the shipped folder)."""
    folder = Path(base_dir) if base_dir is not None else default_catalog_dir()
    return sorted(p.stem for p in folder.glob("*.yaml"))


def resolve_catalog(name_or_path: str | Path, base_dir: str | Path | None = None) -> Path:
    """Find a catalog file from a path or a shipped catalog's name.

    Args:
        name_or_path: a path to a YAML file, or a name such as ``pla-pinned``
            (looked up as ``<base_dir>/<name>.yaml``).
        base_dir: folder of named catalogs (default: :func:`default_catalog_dir`).

    Returns:
        The catalog file's path (as given when it exists).

    Raises:
        InputError: nothing found, with the names of the shipped catalogs.
    """
    path = Path(name_or_path)
    if path.is_file():
        return path
    folder = Path(base_dir) if base_dir is not None else default_catalog_dir()
    text = str(name_or_path)
    if "/" not in text and "\\" not in text:
        stem = text[:-5] if text.endswith(".yaml") else text[:-4] if text.endswith(".yml") else text
        for suffix in (".yaml", ".yml"):
            candidate = folder / f"{stem}{suffix}"
            if candidate.is_file():
                return candidate
    names = shipped_catalogs(folder)
    hint = _suggest(text, names).replace("expected one of", "shipped catalogs")
    if path.is_dir():
        raise InputError([Problem(text, 0, 0, "", "is a directory, expected a catalog file")])
    raise InputError([Problem(text, 0, 0, "", f"no such catalog file or shipped catalog{hint}")])


def load_catalog(name_or_path: str | Path, base_dir: str | Path | None = None) -> Catalog:
    """Load and validate a catalog.

    Everything is checked at once: unknown keys, wrong types, out-of-range
    values and parameters that make no solid (knuckle wider than the rod, wall
    thicker than half the section, ends that cut through the rod, ...).

    Args:
        name_or_path: a catalog file or a shipped catalog's name (see
            :func:`resolve_catalog`).
        base_dir: folder of named catalogs.

    Returns:
        The catalog, its families expanded into rod types.

    Raises:
        InputError: every problem as ``FILE:LINE:COL: key.path: message``.

    A ``<stem>.cache.json`` next to the file (precomputed limits and masses,
    ``rodcad catalog precompute``) is registered as a seed of the disk cache.
    """
    path = resolve_catalog(name_or_path, base_dir)
    display = str(name_or_path) if Path(name_or_path) == path else str(path)
    doc = check_document(load_yaml(path, display), catalog_spec(), filename=display, defer=True)
    catalog = _build(doc, path)
    seed = path.with_name(f"{path.stem}.cache.json")
    if seed.is_file():
        register_seed(seed)
    return catalog


def catalog_from_text(text: str, filename: str = "<catalog>") -> Catalog:
    """Validate catalog YAML given as text (for tests and tools)."""
    from rodcad.yamlio import load_yaml_text

    doc = check_document(load_yaml_text(text, filename), catalog_spec(), filename=filename, defer=True)
    return _build(doc, None)


def _merge(base: Any, over: Any, base_path: str, over_path: str, sources: dict[str, str], rel: str) -> Any:
    """Deep-merge ``over`` onto ``base`` (mappings key by key, anything else
    replaced), recording for every leaf which key path it came from."""
    if isinstance(base, dict) and isinstance(over, dict):
        out: dict[str, Any] = {}
        for key in list(base) + [k for k in over if k not in base]:
            r = child_path(rel, key)
            if key in over and key in base:
                out[key] = _merge(base[key], over[key], child_path(base_path, key),
                                  child_path(over_path, key), sources, r)
            elif key in over:
                out[key] = _record(over[key], child_path(over_path, key), sources, r)
            else:
                out[key] = _record(base[key], child_path(base_path, key), sources, r)
        sources[rel] = over_path
        return out
    return _record(over, over_path, sources, rel)


def _record(value: Any, path: str, sources: dict[str, str], rel: str) -> Any:
    sources[rel] = path
    if isinstance(value, dict):
        for key, val in value.items():
            _record(val, child_path(path, key), sources, child_path(rel, key))
    elif isinstance(value, list):
        for i, val in enumerate(value):
            _record(val, child_path(path, i), sources, child_path(rel, i))
    return copy.deepcopy(value)


def _complete(spec: Obj, value: dict[str, Any], rel: str, missing: list[str]) -> None:
    """Fill defaults into ``value`` and list required keys still missing."""
    for key, f in spec.fields.items():
        r = child_path(rel, key)
        if key not in value:
            if f.required:
                missing.append(r)
                continue
            if f.default is MISSING:
                continue
            value[key] = copy.deepcopy(f.default)
        sub = f.spec.inner if isinstance(f.spec, Nullable) else f.spec
        if isinstance(sub, Obj) and isinstance(value.get(key), dict):
            _complete(sub, value[key], r, missing)


@dataclass
class _FamilyContext:
    """Reports problems about one family at the position each value came from."""

    v: Validator
    name: str
    index: int
    sources: dict[str, str]
    seen: set[tuple[str, str]] = field(default_factory=set)

    @property
    def path(self) -> str:
        return f"families[{self.index}]"

    def source(self, rel: str) -> str:
        while rel and rel not in self.sources:
            rel = rel.rsplit(".", 1)[0] if "." in rel else ""
        return self.sources.get(rel, self.path)

    def report(self, rel: str, message: str) -> None:
        key = self.source(rel) if rel else self.path
        if not (key == self.path or key.startswith((self.path + ".", self.path + "["))):
            message = f"{message} (in family {self.name!r})"
        if (key, message) in self.seen:
            return
        self.seen.add((key, message))
        self.v.report_at(key, message, fallback=self.path)

    def origin(self, rel: str = "") -> Origin:
        key = self.source(rel) if rel else self.path
        pos = self.v.positions.get(key, self.v.positions.get(self.path, Pos()))
        return Origin(self.v.filename, key, pos.line, pos.column)


def _build(doc: Checked, path: Path | None) -> Catalog:
    """Expand a schema-checked document into a catalog, running the cross-field
    checks on every family whose own keys (and the defaults) checked cleanly."""
    v = doc.validator
    schema_failed = set(v.failed)
    data = doc.value if isinstance(doc.value, dict) else {}
    if "catalog" in data and data["catalog"] != CATALOG_FORMAT:
        v.report_at("catalog", f"unsupported catalog format {data['catalog']} "
                    f"(this rodcad reads format {CATALOG_FORMAT})")
    full = _family_spec()
    defaults = data.get("defaults", {})
    defaults_ok = v.ok("defaults", schema_failed)
    printer = None
    if "printer" in data and v.ok("printer", schema_failed):
        p = data["printer"]
        bv = p["build_volume"]
        if len(bv) != 3:
            v.report_at("printer.build_volume", f"expected 3 numbers (x, y, z), got {len(bv)}")
        else:
            printer = Printer(tuple(bv), p["nozzle"], p.get("name", ""))  # type: ignore[arg-type]

    types: list[RodType] = []
    families: list[Family] = []
    family_names: dict[str, int] = {}
    type_names: dict[str, str] = {}
    entries = data.get("families")
    for i, entry in enumerate(entries if isinstance(entries, list) else []):
        fpath = f"families[{i}]"
        if not isinstance(entry, dict) or "name" not in entry:
            continue
        sources: dict[str, str] = {}
        merged = _merge(defaults, entry, "defaults", fpath, sources, "")
        ctx = _FamilyContext(v, entry["name"], i, sources)
        if entry["name"] in family_names:
            ctx.report("name", f"duplicate family name {entry['name']!r} "
                       f"(also families[{family_names[entry['name']]}])")
            continue
        family_names[entry["name"]] = i
        if not (defaults_ok and v.ok(fpath, schema_failed)):
            continue  # its schema problems are reported; cross-checks would add noise
        missing: list[str] = []
        _complete(full, merged, "", missing)
        for key in missing:
            v.report_at(fpath, f"missing required key {key!r} (give it in the family or under 'defaults')")
        if missing:
            continue
        family_types = _expand(merged, ctx, printer)
        for t in family_types:
            if t.name in type_names:
                v.report(Pos(t.origin.line, t.origin.column), t.origin.key,
                         f"rod type name {t.name!r} is also made by {type_names[t.name]}")
                continue
            type_names[t.name] = f"family {merged['name']!r}"
            types.append(t)
        families.append(Family(merged["name"], merged.get("description", ""),
                               tuple(t.name for t in family_types), ctx.origin()))
    v.raise_if_any()
    return Catalog(data["name"], data.get("description", ""), path, tuple(types), tuple(families), printer)


def _expand(f: dict[str, Any], ctx: _FamilyContext, printer: Printer | None) -> list[RodType]:
    """The rod types of one complete family, after cross-field checks."""
    sec, jt, ends, mat = f["section"], f["joint"], f["ends"], f["material"]
    material = Material(mat.get("name", ""), mat["density"], mat["min_wall"])
    balls = None
    if f.get("balls") is not None:
        b = f["balls"]
        balls = Balls(b["diameter"], b["density"], b.get("clearance", 0.2), b.get("name", ""))

    def end(which: str) -> EndShape:
        over = ends.get(which, {})
        return EndShape(
            over.get("setback", ends["setback"]),
            over.get("top_chamfer", ends["top_chamfer"]),
            over.get("bottom_chamfer", ends["bottom_chamfer"]),
        )

    def end_key(which: str, key: str) -> str:
        return f"ends.{which}.{key}" if key in ends.get(which, {}) else f"ends.{key}"

    first, second = end("first"), end("second")
    w = material.min_wall
    if printer is not None and w < printer.nozzle:
        ctx.report("material.min_wall", f"minimum wall {format_number(w)} mm is thinner than the "
                   f"printer's nozzle ({format_number(printer.nozzle)} mm)")
    multi_scale = len(f["scale"]) > 1
    multi_curv = len(f["curvature"]) > 1
    out: list[RodType] = []
    ok = True
    per_scale: dict[int, tuple[float, float, Hinge, str]] = {}
    for si, scale in enumerate(f["scale"]):
        h, t = sec["height"] * scale, sec["thickness"] * scale
        hinge = Hinge(jt["layout"], jt["pin_diameter"], jt["pin_clearance"], jt["knuckle_radius"] * scale,
                      jt["tongue_thickness"] * scale, jt["layer_gap"], jt["radial_gap"])
        at = f" at scale {format_number(scale)}" if scale != 1 else ""
        ok &= _check_section(ctx, h, t, hinge, material, balls, first, second, end_key, at)
        per_scale[si] = (h, t, hinge, at)
    for li, length in enumerate(f["length"]):
        l_rel = f"length[{li}]" if len(f["length"]) > 1 else "length"
        for si, scale in enumerate(f["scale"]):
            h, t, hinge, at = per_scale[si]
            ok &= _check_length(ctx, l_rel, length, h, hinge, material, first, second, end_key, at)
            for ci, curv in enumerate(f["curvature"]):
                c_rel = f"curvature[{ci}]" if multi_curv else "curvature"
                ok &= _check_curvature(ctx, c_rel, curv, length, h)
                geom = RodGeometry(length, h, t, curv, hinge, first, second)
                if printer is not None:
                    ok &= _check_printer(ctx, l_rel, geom, printer)
                name = f"{f['name']}-{format_number(length)}"
                if multi_scale:
                    name += f"-s{format_number(scale)}"
                if multi_curv:
                    name += f"-k{format_number(curv)}"
                out.append(RodType(name, f["name"], length, scale, curv, geom, material, balls,
                                   ctx.origin(l_rel)))
    return out if ok else []


def _check_section(ctx: _FamilyContext, h: float, t: float, hinge: Hinge, m: Material,
                   balls: Balls | None, first: EndShape, second: EndShape, end_key: Any, at: str) -> bool:
    """Checks on the cross-section and hinge that make a rod impossible to build."""
    ok = True
    fmt = format_number
    w = m.min_wall
    if w >= min(h, t) / 2:
        ctx.report("material.min_wall", f"minimum wall {fmt(w)} mm is thicker than half the section "
                   f"({fmt(min(h, t) / 2)} mm{at}): no room inside the rod")
        return False  # every wall check below would fail for the same reason
    if hinge.zone_radius >= h / 2:
        ctx.report("joint.knuckle_radius", f"knuckle radius {fmt(hinge.knuckle_radius)} mm + radial gap "
                   f"{fmt(hinge.radial_gap)} mm is wider than the rod: it must stay below half the section "
                   f"height ({fmt(h / 2)} mm{at})")
        ok = False
    elif h / 2 - hinge.zone_radius < w:
        ctx.report("joint.knuckle_radius", f"knuckle radius {fmt(hinge.knuckle_radius)} mm + radial gap "
                   f"{fmt(hinge.radial_gap)} mm leaves {fmt(round(h / 2 - hinge.zone_radius, 6))} mm of end face "
                   f"between the hinge zone and the rod's edge ({fmt(h / 2)} mm from the axis{at}), less than "
                   f"the minimum wall {fmt(w)} mm")
        ok = False
    knuckle_wall = hinge.knuckle_radius - hinge.hole_diameter / 2
    if knuckle_wall < w:
        ctx.report("joint.knuckle_radius", f"knuckle radius {fmt(hinge.knuckle_radius)} mm leaves a wall of "
                   f"{fmt(knuckle_wall)} mm around the {fmt(hinge.hole_diameter)} mm pin hole, less than "
                   f"the minimum wall {fmt(w)} mm{at}")
        ok = False
    prong = (t - hinge.tongue_thickness - 2 * hinge.layer_gap) / 2
    if hinge.tongue_thickness < w:
        ctx.report("joint.tongue_thickness", f"tongue thickness {fmt(hinge.tongue_thickness)} mm is less than "
                   f"the minimum wall {fmt(w)} mm{at}")
        ok = False
    elif prong < w:
        ctx.report("joint.tongue_thickness", f"tongue {fmt(hinge.tongue_thickness)} mm + 2 layer gaps of "
                   f"{fmt(hinge.layer_gap)} mm leave fork prongs {fmt(prong)} mm thick in a {fmt(t)} mm "
                   f"thick rod, less than the minimum wall {fmt(w)} mm{at}")
        ok = False
    for which, e in (("first", first), ("second", second)):
        if e.setback >= hinge.knuckle_radius:
            ctx.report(end_key(which, "setback"),
                       f"setback {fmt(e.setback)} mm detaches the end face from the "
                       f"{fmt(hinge.knuckle_radius)} mm knuckle: must be less than the knuckle radius{at}")
            ok = False
    if balls is not None:
        need = balls.socket_diameter + 2 * w
        if need > min(h, t):
            ctx.report("balls.diameter", f"a {fmt(balls.diameter)} mm ball in a {fmt(balls.socket_diameter)} mm "
                       f"socket with {fmt(w)} mm walls needs a section of at least {fmt(need)} mm; the rod is "
                       f"{fmt(h)} x {fmt(t)} mm{at}")
            ok = False
    return ok


def _check_length(ctx: _FamilyContext, l_rel: str, length: float, h: float, hinge: Hinge,
                  m: Material, first: EndShape, second: EndShape, end_key: Any, at: str) -> bool:
    fmt = format_number
    need = 2 * hinge.zone_radius + m.min_wall
    if length < need:
        ctx.report(l_rel, f"length {fmt(length)} mm is too short: the two hinge zones and a minimum wall "
                   f"need {fmt(round(need, 6))} mm{at}")
        return False
    ok = True
    for half in ("top", "bottom"):
        b1 = getattr(first, f"{half}_chamfer")
        b2 = getattr(second, f"{half}_chamfer")
        cut = first.setback + second.setback + h / 2 * (math.tan(math.radians(b1)) + math.tan(math.radians(b2)))
        left = length - cut
        if left < m.min_wall:
            what = (f"the two {half} end faces would cross" if left <= 0 else
                    f"they leave {fmt(round(left, 3))} mm of {half} edge between the end faces, less than "
                    f"the minimum wall {fmt(m.min_wall)} mm")
            ctx.report(end_key("second", f"{half}_chamfer"),
                       f"{half} chamfers of {fmt(b1)} and {fmt(b2)} deg cut through a {fmt(length)} mm rod: "
                       f"{what}{at}")
            ok = False
    return ok


def _check_curvature(ctx: _FamilyContext, c_rel: str, curv: float, length: float, h: float) -> bool:
    if curv == 0:
        return True
    fmt = format_number
    limit = math.sin(math.radians(MAX_ARC_HALF_ANGLE_DEG)) * 2 / length
    if abs(curv) > limit:
        ctx.report(c_rel, f"curvature {fmt(curv)} /mm bends a {fmt(length)} mm rod past a "
                   f"{fmt(2 * MAX_ARC_HALF_ANGLE_DEG)} deg arc (at most {fmt(round(limit, 6))} /mm)")
        return False
    if abs(curv) * h > 1:
        ctx.report(c_rel, f"curvature {fmt(curv)} /mm (radius {fmt(round(1 / abs(curv), 3))} mm) is too tight "
                   f"for a {fmt(h)} mm high section: the radius must be at least the section height")
        return False
    return True


def _check_printer(ctx: _FamilyContext, l_rel: str, g: RodGeometry, printer: Printer) -> bool:
    sag = 0.0
    if g.curvature:
        sag = (1 - math.cos(math.radians(g.half_angle_deg))) / abs(g.curvature)  # arc's depth below the chord
    extent = sorted((g.length + 2 * g.hinge.knuckle_radius, g.height + sag, g.thickness))
    bed = sorted(printer.build_volume)
    if any(e > b for e, b in zip(extent, bed)):
        fmt = format_number
        ctx.report(l_rel, f"a {fmt(g.length)} mm rod ({' x '.join(fmt(round(e, 2)) for e in reversed(extent))} mm) "
                   f"does not fit the printer's build volume "
                   f"({' x '.join(fmt(b) for b in printer.build_volume)} mm)")
        return False
    return True
