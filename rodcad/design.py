"""Design files: what a user asks ``rodcad build`` / ``rodcad simulate`` for.

A design file is YAML (units: mm, g, degrees)::

    design: 1                     # format version
    name: semicircle              # default output folder outputs/<name>
    catalog: pla-pinned           # shipped catalog name, or a path relative to this file
    anchors: [[0, 0], [200, 0]]   # anchor A and anchor B (mm, y up)
    target:                       # the shape to hang in (for `build`)
      form: semicircle            # polyline, arc, semicircle, triangle, polygon, heart,
                                  # catenary, function, svg (see rodcad.targets)
    constraints:                  # optional
      types: [free-20, free-30]   # rod types allowed (default: all)
      lengths: [30]               # rod lengths allowed (default: all)
      rods: 8                     # number of rods (default: what the chord walk gives)
      fixed:                      # rods whose type (and mass) is imposed
        - {index: 0, type: free-30, mass: 6.5}
    method: refine                # exact, refine (default), guided-pso, pso
    seed: 0
    tolerance: 0.01               # optional: largest acceptable error / span
    fabrication: {cad: true, seed: 0}

or, for ``rodcad simulate``, an explicit chain instead of (or besides) a target::

    chain:
      - {type: free-30, mass: 6.5}
      - {type: straight-30}       # mass defaults to the type's solid mass

Loading checks everything at once (:func:`load_design`): schema problems, then
names against the catalog (did-you-mean), the target's parameters and the
anchors against the chain's reach, each reported as ``FILE:LINE:COL: key.path:
message``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rodcad.catalog import Catalog, load_catalog
from rodcad.errors import InputError, Problem
from rodcad.yamlio import (
    Bool,
    Checked,
    Field,
    ListOf,
    Num,
    Obj,
    Str,
    _suggest,
    check_document,
    load_yaml,
    load_yaml_text,
)

__all__ = [
    "DESIGN_FORMAT",
    "ChainRod",
    "Constraints",
    "Design",
    "FixedRod",
    "design_schema",
    "design_spec",
    "load_design",
]

#: Design file format this rodcad reads.
DESIGN_FORMAT = 1

#: Inverse-design methods (mirrors optimize.inverse.METHODS).
METHOD_NAMES = ("exact", "refine", "guided-pso", "pso")

_NAME = r"[A-Za-z0-9][A-Za-z0-9_.+-]*"
_NAME_HINT = "a name of letters, digits, '.', '_', '+' or '-'"


# --------------------------------------------------------------------------- data model


@dataclass(frozen=True)
class FixedRod:
    """A rod whose type (and optionally mass) the user imposes.

    Attributes:
        index: position in the chain (0 = the rod at anchor A).
        type: rod type name.
        mass: imposed mass (g), or None to let the design choose it.
    """

    index: int
    type: str
    mass: float | None = None


@dataclass(frozen=True)
class Constraints:
    """Optional restrictions on the designed chain.

    Attributes:
        types: rod type names allowed (None: all).
        lengths: rod lengths allowed (mm; None: all).
        rods: number of rods (None: what the chord walk gives).
        preferred_length: the length to use most (mm; None: chosen by the walk).
        fixed: imposed rods.
    """

    types: tuple[str, ...] | None = None
    lengths: tuple[float, ...] | None = None
    rods: int | None = None
    preferred_length: float | None = None
    fixed: tuple[FixedRod, ...] = ()


@dataclass(frozen=True)
class ChainRod:
    """One rod of an explicit chain: its type and mass (g)."""

    type: str
    mass: float


@dataclass
class Design:
    """A validated design file.

    Attributes:
        path: the design file.
        name: design name (default output folder ``outputs/<name>``).
        description: free text.
        catalog: the loaded rod catalog.
        catalog_ref: the catalog as written in the file.
        anchors: (2, 2) anchors A and B (mm).
        target_form: target form name, or None (explicit chain only).
        target_params: the form's parameters.
        target_curve: (M, 2) dense target polyline from A to B, or None.
        chain: explicit chain, or None.
        constraints: restrictions on the designed chain.
        method: inverse-design method.
        seed: random seed of the design (PSO, multi-start).
        tolerance: largest acceptable max error / span, or None.
        g: gravitational acceleration (m/s^2; only scales moments and reactions).
        cad: build the solids (False: design and check only).
        fabrication_seed: seed of the cavity layouts.
        source: the checked document (positions of every key, for later problems).
    """

    path: Path
    name: str
    description: str
    catalog: Catalog
    catalog_ref: str
    anchors: np.ndarray
    target_form: str | None
    target_params: dict[str, Any]
    target_curve: np.ndarray | None
    chain: list[ChainRod] | None
    constraints: Constraints
    method: str
    seed: int
    tolerance: float | None
    g: float
    cad: bool
    fabrication_seed: int
    source: Checked | None = field(default=None, repr=False)
    chandelier: dict[str, Any] | None = None
    placements: list[Any] | None = None
    chain_targets: list[dict[str, Any]] | None = None

    @property
    def span(self) -> float:
        """Distance between the anchors (mm)."""
        return float(np.hypot(*(self.anchors[1] - self.anchors[0])))

    def problem(self, key: str, message: str) -> Problem:
        """A problem pointing at ``key`` in the design file (for later stages)."""
        pos = self.source.pos(key) if self.source is not None else None
        return Problem(str(self.path), pos.line if pos else 0, pos.column if pos else 0, key, message)


# --------------------------------------------------------------------------- schema


def _point() -> ListOf:
    return ListOf(Num(unit="mm"), min_items=2, description="[x, y] in mm (y up)")


def target_spec() -> Obj:
    """Spec of the ``target`` mapping (one ``form`` plus that form's parameters)."""
    from rodcad.targets import TARGET_FORMS

    return Obj(
        {
            "form": Field(Str(choices=tuple(TARGET_FORMS)), required=True,
                          description="Target form: " + ", ".join(TARGET_FORMS) + "."),
            "points": Field(ListOf(_point(), min_items=2),
                            description="polyline: [x, y] points from anchor A to anchor B (mm)."),
            "sag": Field(Num(unit="mm"), description="arc: depth of the arc below the chord (mm)."),
            "depth": Field(Num(unit="mm"), description="triangle: depth of the apex below the chord (mm)."),
            "apex": Field(Num(minimum=0, maximum=1),
                          description="triangle: where the apex is along the chord (0..1, default 0.5)."),
            "sides": Field(Num(integer=True, minimum=3, maximum=64),
                           description="polygon: number of sides of the regular polygon whose lower part "
                           "hangs from the anchors."),
            "length": Field(Num(exclusive_minimum=0, unit="mm"),
                            description="catenary: length of the hanging curve (mm)."),
            "y": Field(Str(), description="function: y as an expression in x (mm), e.g. "
                       "'-0.004 * x * (200 - x)'."),
            "d": Field(Str(), description="svg: an SVG path 'd' string; it is scaled and rotated so "
                       "that its ends land on the anchors."),
            "samples": Field(Num(integer=True, minimum=8, maximum=100000),
                             description="Points sampled on the curve (default depends on the form)."),
        },
        description="The shape the chain should hang in (mm).",
    )


def _point3() -> ListOf:
    return ListOf(Num(unit="mm"), min_items=3, description="[x, y, z] in mm (z up)")


#: Chandelier patterns and the parameters each needs (required, optional).
PATTERNS = {
    "ring": (("count", "radius"), ("height", "start_deg", "gap")),
    "two-rings": (("count", "r_top", "z_top", "r_bottom", "z_bottom"), ("twist_deg", "start_deg")),
    "polygon": (("vertices",), ("gap",)),
    "explicit": (("chains",), ()),
}

#: Frame kind used by default for each pattern.
FRAME_OF_PATTERN = {"ring": "ring", "two-rings": "two_rings", "polygon": "bars", "explicit": "bars"}


def chandelier_spec() -> Obj:
    """Spec of the ``chandelier`` mapping: several chains in 3D and their frame."""
    mm = {"unit": "mm"}
    return Obj(
        {
            "pattern": Field(Str(choices=tuple(PATTERNS)), required=True,
                             description="ring: a chain below each side of a regular polygon on a "
                             "horizontal ring; two-rings: chains from a top hub down to a lower ring; "
                             "polygon: a chain below each edge of a polygon frame; explicit: anchors "
                             "given per chain."),
            "count": Field(Num(integer=True, minimum=1, maximum=64), description="Number of chains."),
            "radius": Field(Num(exclusive_minimum=0, **mm), description="ring: radius through the anchors."),
            "height": Field(Num(**mm), description="ring: z of the anchors (default 0)."),
            "start_deg": Field(Num(unit="deg"), description="Angle of the first anchor from +x."),
            "gap": Field(Num(exclusive_minimum=0, **mm),
                         description="ring/polygon: distance between neighbouring chains' anchors at a "
                         "vertex (default 20 mm)."),
            "r_top": Field(Num(exclusive_minimum=0, **mm), description="two-rings: radius of the top anchors."),
            "z_top": Field(Num(**mm), description="two-rings: height of the top anchors."),
            "r_bottom": Field(Num(exclusive_minimum=0, **mm),
                              description="two-rings: radius of the bottom anchors."),
            "z_bottom": Field(Num(**mm), description="two-rings: height of the bottom anchors."),
            "twist_deg": Field(Num(unit="deg"), description="two-rings: angle from each top anchor to its "
                               "bottom anchor."),
            "vertices": Field(ListOf(_point3(), min_items=2), description="polygon: the frame's vertices."),
            "chains": Field(
                ListOf(Obj({
                    "anchors": Field(ListOf(_point3(), min_items=2),
                                     description="explicit: anchor A and B [[x, y, z], [x, y, z]] (mm)."),
                    "target": Field(target_spec(), description="This chain's target (in its own "
                                    "vertical plane: x from A toward B, y up)."),
                }), min_items=1),
                description="Per chain: anchors (explicit pattern) and/or its own target; one entry per chain.",
            ),
            "target": Field(target_spec(), description="The target shared by every chain without its own."),
            "frame": Field(
                Obj({
                    "kind": Field(Str(choices=("ring", "two_rings", "bars")),
                                  description="Frame members (default: ring for ring, two_rings for "
                                  "two-rings, bars otherwise)."),
                    "width": Field(Num(exclusive_minimum=0, **mm), default=16.0, description="Member width."),
                    "thickness": Field(Num(exclusive_minimum=0, **mm), default=5.0,
                                       description="Member thickness."),
                }),
                default={"width": 16.0, "thickness": 5.0},
                description="The printed frame the chains hang from (hinge lugs match the catalog).",
            ),
        },
        description="Several chains in 3D (z up) hanging from one frame; each chain hangs in the vertical "
        "plane through its anchors.",
    )


def design_spec() -> Obj:
    """The spec of a whole design file."""
    fixed = Obj(
        {
            "index": Field(Num(integer=True, minimum=0), required=True,
                           description="Position in the chain (0 = the rod at anchor A)."),
            "type": Field(Str(), required=True, description="Rod type name from the catalog."),
            "mass": Field(Num(exclusive_minimum=0, unit="g"), description="Imposed mass (g)."),
        },
        description="A rod whose type (and mass) is imposed.",
    )
    rod = Obj(
        {
            "type": Field(Str(), required=True, description="Rod type name from the catalog."),
            "mass": Field(Num(exclusive_minimum=0, unit="g"),
                          description="Mass (g); default: the type's solid mass."),
        },
        description="One rod of an explicit chain, from anchor A to anchor B.",
    )
    return Obj(
        {
            "design": Field(Num(integer=True, minimum=1), required=True,
                            description=f"Design format version; this rodcad reads {DESIGN_FORMAT}."),
            "name": Field(Str(pattern=_NAME, pattern_hint=_NAME_HINT), required=True,
                          description="Design name; the default output folder is outputs/<name>."),
            "description": Field(Str(), description="Free text."),
            "catalog": Field(Str(), required=True,
                             description="Rod catalog: a shipped catalog's name (e.g. pla-pinned) or a "
                             "path relative to this file."),
            "anchors": Field(ListOf(_point(), min_items=2),
                             description="Anchor A and anchor B: [[x, y], [x, y]] in mm, y up "
                             "(required unless the design is a chandelier)."),
            "target": Field(target_spec()),
            "chain": Field(ListOf(rod, min_items=1),
                           description="An explicit chain (for `rodcad simulate`): rod types and masses "
                           "from anchor A to anchor B."),
            "chandelier": Field(chandelier_spec()),
            "constraints": Field(
                Obj(
                    {
                        "types": Field(ListOf(Str(), min_items=1, unique=True),
                                       description="Rod types allowed (default: all)."),
                        "lengths": Field(ListOf(Num(exclusive_minimum=0, unit="mm"), min_items=1,
                                                unique=True),
                                         description="Rod lengths allowed (mm; default: all)."),
                        "rods": Field(Num(integer=True, minimum=1, maximum=10000),
                                      description="Number of rods (default: what the chord walk gives)."),
                        "preferred_length": Field(Num(exclusive_minimum=0, unit="mm"),
                                                  description="The rod length to use most (mm)."),
                        "fixed": Field(ListOf(fixed), description="Rods whose type (and mass) is imposed."),
                    },
                    description="Optional restrictions on the designed chain.",
                )
            ),
            "method": Field(Str(choices=METHOD_NAMES), default="refine",
                            description="Inverse-design method: " + ", ".join(METHOD_NAMES) + "."),
            "seed": Field(Num(integer=True, minimum=0), default=0,
                          description="Random seed (PSO, multi-start checks)."),
            "tolerance": Field(Num(exclusive_minimum=0),
                               description="Largest acceptable max joint error relative to the anchor "
                               "span; `build` exits with code 1 when the design misses it."),
            "g": Field(Num(exclusive_minimum=0, unit="m/s^2"), default=9.81,
                       description="Gravitational acceleration (scales only forces and moments)."),
            "fabrication": Field(
                Obj(
                    {
                        "cad": Field(Bool(), default=True,
                                     description="Build the solids (STEP/STL); false = design only."),
                        "seed": Field(Num(integer=True, minimum=0), default=0,
                                      description="Seed of the cavity layouts."),
                    },
                    description="Fabrication options.",
                ),
                default={"cad": True, "seed": 0},
            ),
        },
        title="rodcad design",
        description="A hanging chain to design (target) or simulate (chain); units mm, g, deg.",
    )


def design_schema() -> dict[str, Any]:
    """The JSON Schema of design files, generated from the validating specs."""
    return {"$schema": "https://json-schema.org/draft/2020-12/schema", **design_spec().json_schema()}


# --------------------------------------------------------------------------- loading


def load_design(path: str | Path, *, text: str | None = None) -> Design:
    """Load and validate a design file, reporting every problem at once.

    Args:
        path: the design file (also the name used in problems when ``text`` is given).
        text: the file's content (for tests); read from ``path`` when None.

    Returns:
        The validated design with its catalog loaded and the target curve built.

    Raises:
        InputError: every problem as ``FILE:LINE:COL: key.path: message``.
    """
    path = Path(path)
    display = str(path)
    if text is None:
        if not path.is_file():
            raise InputError([Problem(display, 0, 0, "", "no such design file"
                                      if not path.is_dir() else "is a directory, expected a design file")])
        root = load_yaml(path, display)
    else:
        root = load_yaml_text(text, display)
    doc = check_document(root, design_spec(), filename=display, defer=True)
    v = doc.validator
    data: dict[str, Any] = doc.value if isinstance(doc.value, dict) else {}
    schema_ok = set(v.failed)

    def ok(key: str) -> bool:
        return v.ok(key, schema_ok) and key in data

    if "design" in data and data["design"] != DESIGN_FORMAT:
        v.report_at("design", f"unsupported design format {data['design']} (this rodcad reads format "
                    f"{DESIGN_FORMAT})")

    catalog = None
    if ok("catalog"):
        ref = data["catalog"]
        beside = path.parent / ref
        try:
            catalog = load_catalog(beside if beside.is_file() else ref)
        except InputError as err:
            for p in err.problems:
                if p.line == 0:  # the reference itself: point at the design's key
                    v.report_at("catalog", f"{ref!r}: {p.message} (looked next to the design file "
                                "and among the shipped catalogs)")
                else:  # problems inside the catalog file itself
                    v.problems.append(p)
                    v.failed.add("catalog")

    anchors = None
    if ok("anchors"):
        pts = data["anchors"]
        if len(pts) != 2 or any(len(p) != 2 for p in pts):
            v.report_at("anchors", "expected two anchors [[x, y], [x, y]]")
        else:
            anchors = np.asarray(pts, dtype=float)
            if np.hypot(*(anchors[1] - anchors[0])) <= 0:
                v.report_at("anchors", "the two anchors coincide")
                anchors = None

    if "anchors" not in data and "chandelier" not in data and v.ok("", schema_ok):
        v.report_at("", "missing required key 'anchors' (or describe a 'chandelier')")
    placements = chain_targets = None
    if "chandelier" in data and v.ok("chandelier", schema_ok):
        placements, chain_targets = _chandelier(data["chandelier"], v)
        if placements is not None:
            anchors = np.array([[0.0, 0.0], [1.0, 0.0]])  # unused for a chandelier
    if "target" not in data and "chain" not in data and "chandelier" not in data and v.ok("", schema_ok):
        v.report_at("", "give a 'target' to design a chain for, or an explicit 'chain' to simulate")

    names = catalog.names if catalog is not None else None
    by_name = {t.name: t for t in catalog} if catalog is not None else {}

    def check_type(key: str, name: str) -> bool:
        if names is None:
            return False
        if name not in by_name:
            v.report_at(key, f"unknown rod type {name!r} in catalog {catalog.name!r}{_suggest(name, names)}")
            return False
        return True

    # explicit chain: every item's type is checked, even when another item failed
    chain = None
    items = data.get("chain") if isinstance(data.get("chain"), list) else []
    rods: list[ChainRod] = []
    for i, rod in enumerate(items):
        key = f"chain[{i}]"
        if not isinstance(rod, dict) or "type" not in rod or not check_type(f"{key}.type", rod["type"]):
            continue
        if v.ok(key, schema_ok):
            t = by_name[rod["type"]]
            rods.append(ChainRod(t.name, float(rod.get("mass", t.mass_info().solid_mass))))
    if items and len(rods) == len(items) and v.ok("chain", schema_ok):
        chain = rods
        if anchors is not None:
            reach = sum(by_name[r.type].length for r in chain)
            span = float(np.hypot(*(anchors[1] - anchors[0])))
            if span > reach * (1 + 1e-12):
                v.report_at("anchors", f"the anchors are {span:.6g} mm apart but the chain is only "
                            f"{reach:.6g} mm long (pin to pin): move them closer or add rods")

    # constraints
    c = data.get("constraints", {}) if isinstance(data.get("constraints"), dict) else {}
    types = None
    if isinstance(c.get("types"), list):
        good = [isinstance(n, str) and check_type(f"constraints.types[{i}]", n) for i, n in enumerate(c["types"])]
        types = tuple(c["types"]) if all(good) else None
    lengths = (tuple(float(x) for x in c["lengths"]) if v.ok("constraints.lengths", schema_ok)
               and isinstance(c.get("lengths"), list) else None)
    if lengths is not None and catalog is not None:
        have = sorted({t.length for t in catalog})
        for i, x in enumerate(lengths):
            if not any(math.isclose(x, h, rel_tol=1e-9) for h in have):
                v.report_at(f"constraints.lengths[{i}]", f"no rod type of catalog {catalog.name!r} is "
                            f"{x:g} mm long (lengths: {', '.join(f'{h:g}' for h in have)})")
    fixed = []
    for i, f in enumerate(c.get("fixed", []) if isinstance(c.get("fixed"), list) else []):
        key = f"constraints.fixed[{i}]"
        if not (isinstance(f, dict) and "index" in f and "type" in f):
            continue
        if check_type(f"{key}.type", f["type"]):
            t = by_name[f["type"]]
            m = f.get("mass")
            if m is not None:
                lo, hi = t.mass_range
                if not lo * (1 - 1e-9) <= m <= hi * (1 + 1e-9):
                    v.report_at(f"{key}.mass", f"{m:g} g is outside what type {t.name!r} can be made to "
                                f"weigh ({lo:.4g} to {hi:.4g} g)")
            fixed.append(FixedRod(int(f["index"]), t.name, None if m is None else float(m)))
    seen: dict[int, int] = {}
    for i, f in enumerate(fixed):
        if f.index in seen:
            v.report_at(f"constraints.fixed[{i}].index", f"rod {f.index} is already fixed by "
                        f"constraints.fixed[{seen[f.index]}]")
        seen[f.index] = i
    constraints = Constraints(types, lengths, int(c["rods"]) if "rods" in c else None,
                              c.get("preferred_length"), tuple(fixed))

    # target
    form, params, curve = None, {}, None
    if ok("target") and anchors is not None:
        form, params, curve = _target(data["target"], anchors, v)

    v.problems.sort(key=lambda p: (p.file != display, p.line, p.column))
    v.raise_if_any()
    assert catalog is not None and anchors is not None
    name = data["name"]
    fab = data.get("fabrication", {})
    return Design(
        path=path,
        name=name,
        description=data.get("description", ""),
        catalog=catalog,
        catalog_ref=data["catalog"],
        anchors=anchors,
        target_form=form,
        target_params=params,
        target_curve=curve,
        chain=chain,
        constraints=constraints,
        method=data.get("method", "refine"),
        seed=int(data.get("seed", 0)),
        tolerance=data.get("tolerance"),
        g=float(data.get("g", 9.81)),
        cad=bool(fab.get("cad", True)),
        fabrication_seed=int(fab.get("seed", 0)),
        source=doc,
        chandelier=data.get("chandelier"),
        placements=placements,
        chain_targets=chain_targets,
    )


def _chandelier(c: dict[str, Any], v: Any) -> tuple[list[Any] | None, list[dict[str, Any]] | None]:
    """Chain placements and per-chain targets of a chandelier, every problem reported."""
    from rodcad import chandelier as C

    pattern = c["pattern"]
    required, optional = PATTERNS[pattern]
    bad = False
    for k in required:
        if k not in c:
            v.report_at("chandelier", f"a {pattern} chandelier needs {k!r}")
            bad = True
    known = set(required) | set(optional) | {"pattern", "target", "frame", "chains"}
    for k in c:
        if k not in known:
            v.report_at(f"chandelier.{k}", f"a {pattern} chandelier takes no {k!r} "
                        f"(it takes: {', '.join(required + optional)})")
            bad = True
    if bad:
        return None, None
    try:
        if pattern == "ring":
            placements = C.ring(int(c["count"]), c["radius"], c.get("height", 0.0),
                                start_deg=c.get("start_deg", 0.0), gap=c.get("gap", 20.0))
        elif pattern == "two-rings":
            placements = C.two_rings(int(c["count"]), c["r_top"], c["z_top"], c["r_bottom"], c["z_bottom"],
                                     twist_deg=c.get("twist_deg", 0.0), start_deg=c.get("start_deg", 0.0))
        elif pattern == "polygon":
            placements = C.polygon_frame(c["vertices"], gap=c.get("gap", 20.0))
        else:
            pairs = []
            for i, ch in enumerate(c["chains"]):
                if "anchors" not in ch or len(ch["anchors"]) != 2:
                    v.report_at(f"chandelier.chains[{i}]", "an explicit chain needs 'anchors': "
                                "[[x, y, z], [x, y, z]]", fallback="chandelier.chains")
                    bad = True
                else:
                    pairs.append(ch["anchors"])
            if bad:
                return None, None
            placements = C.explicit(pairs)
    except ValueError as err:
        v.report_at("chandelier", str(err))
        return None, None
    n = len(placements)
    per = c.get("chains")
    if per is not None and len(per) != n:
        v.report_at("chandelier.chains", f"{len(per)} entries for {n} chains (give one per chain)")
        return None, None
    targets = []
    for i, p in enumerate(placements):
        own = per[i].get("target") if per is not None else None
        t = own if own is not None else c.get("target")
        key = f"chandelier.chains[{i}].target" if own is not None else "chandelier.target"
        if t is None:
            v.report_at("chandelier", f"chain {p.name} has no target (give 'target' for every chain, or one "
                        "per chain under 'chains')")
            return None, None
        a2, b2 = p.plane_anchors()
        form, params, curve = _target(t, np.array([a2, b2]), v, key=key)
        if curve is None:
            return None, None
        targets.append({"form": form, **params})
    return placements, targets


def _target(t: dict[str, Any], anchors: np.ndarray, v: Any, *,
            key: str = "target") -> tuple[str | None, dict[str, Any], np.ndarray | None]:
    """Check the target's parameters against its form and build the curve.

    Args:
        t: the checked target mapping.
        anchors: (2, 2) anchors A and B in the target's plane.
        v: the validator collecting problems.
        key: key path of the target mapping (e.g. ``chandelier.chains[2].target``).
    """
    from rodcad.targets import TARGET_FORMS, make_target

    form = t["form"]
    _, required, optional = TARGET_FORMS[form]
    params = {k: val for k, val in t.items() if k != "form"}
    bad = False
    for k in params:
        if k not in required + optional:
            takes = ", ".join(required + optional) or "no parameters"
            v.report_at(f"{key}.{k}", f"a {form} target takes no {k!r} (it takes: {takes})")
            bad = True
    for k in required:
        if k not in params:
            v.report_at(key, f"a {form} target needs {k!r}", fallback=key)
            bad = True
    if bad:
        return None, {}, None
    if "sides" in params:
        params["sides"] = int(params["sides"])
    if "samples" in params:
        params["samples"] = int(params["samples"])
    try:
        curve = make_target(form, anchors[0], anchors[1], **params)
    except (ValueError, ArithmeticError, SyntaxError, TypeError) as err:
        at = f"{key}.{required[0]}" if required else key
        v.report_at(at, f"cannot make the {form} target: {err}", fallback=key)
        return None, {}, None
    if not np.all(np.isfinite(curve)):
        v.report_at(key, f"the {form} target has points that are not finite numbers")
        return None, {}, None
    return form, params, curve


__all__ += ["METHOD_NAMES", "target_spec"]
