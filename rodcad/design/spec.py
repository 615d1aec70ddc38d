"""The design file format as a spec tree: the validator of design YAML and its JSON Schema.
"""

from __future__ import annotations

from typing import Any

from rodcad.design.model import ANCHOR_STOP_MODES, DEFAULT_CATALOG, FUSE_MODES, DESIGN_FORMAT, JOINT_MODES, METHOD_NAMES
from rodcad.design.net.spec import net_spec
from rodcad.yamlspec import Bool, Field, ListOf, Nullable, Num, Obj, Str

#: Longest design, catalog or family name (it names folders and files).
MAX_NAME = 100

__all__ = ['target_spec', 'PATTERNS', 'FRAME_OF_PATTERN', 'chandelier_spec', 'design_spec', 'design_schema']


_NAME = r"[A-Za-z0-9][A-Za-z0-9_.+-]*"


_NAME_HINT = "a name of letters, digits, '.', '_', '+' or '-'"


def _point() -> ListOf:
    return ListOf(Num(unit="mm"), min_items=2, description="[x, y] in mm (y up)")


def target_spec() -> Obj:
    """Spec of the ``target`` mapping (one ``form`` plus that form's parameters)."""
    from rodcad.design.targets import TARGET_FORMS

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
            "width": Field(Num(exclusive_minimum=0, unit="mm"),
                           description="closed-heart: the heart's full width (mm); the anchors sit beside "
                           "its cusp."),
            "bulge": Field(Num(minimum=0, maximum=0.25),
                           description="closed-heart: how far the lower sides bulge outward (sagitta over "
                           "side length, 0 to 0.25; default 0, straight)."),
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
            "name": Field(Str(pattern=_NAME, pattern_hint=_NAME_HINT, max_length=MAX_NAME), required=True,
                          description="Design name; the default output folder is outputs/<name>."),
            "description": Field(Str(), description="Free text."),
            "catalog": Field(Str(), default=DEFAULT_CATALOG,
                             description="Rod catalog: a shipped catalog's name (e.g. pla-pinned) or a "
                             f"path relative to this file (default: {DEFAULT_CATALOG}, rods printed to order)."),
            "anchors": Field(ListOf(_point(), min_items=2),
                             description="Anchor A and anchor B: [[x, y], [x, y]] in mm, y up "
                             "(required unless the design is a chandelier)."),
            "target": Field(target_spec()),
            "chain": Field(ListOf(rod, min_items=1),
                           description="An explicit chain (for `rodcad simulate`): rod types and masses "
                           "from anchor A to anchor B."),
            "chandelier": Field(chandelier_spec()),
            "net": Field(net_spec()),
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
                        "joints": Field(Str(choices=JOINT_MODES), default="any",
                                        description="'free' forbids every stop: the masses alone hold "
                                        "the shape (the best fit where they cannot); 'any' (default) "
                                        "lets joints rest on stops where the masses cannot hold a bend."),
                        "same_shell": Field(Bool(), default=False,
                                            description="Rods printed to order: every rod of the chain gets "
                                            "one outer shell (one length, one curvature, the family's own "
                                            "ends); the masses differ only inside (the paper's Fig. 7)."),
                        "anchor_stops": Field(Str(choices=ANCHOR_STOP_MODES),
                                              description="'auto' (what the planner does unless told): the "
                                              "piece the chain hangs from (a printed fixture) may stop the "
                                              "first and last rods at their target angles where the shape needs "
                                              "it (a shape that rises above its anchors); 'none': bare pins."),
                        "fuse": Field(Str(choices=FUSE_MODES),
                                      description="'auto' (what the planner does unless told): rods are "
                                      "printed as one piece where a bend is sharper than any stop the "
                                      "family prints; 'never' (or 'none'): no fused pieces; 'stops': also "
                                      "every run of joints resting on stops is printed as one rigid piece "
                                      "(where it fits the printer)."),
                        "anchor_limits_deg": Field(ListOf(Nullable(ListOf(Num(unit="deg"), min_items=2)),
                                                          min_items=2),
                                                   description="Bounds [lo, hi] on the angle (deg from +x) of "
                                                   "the first and of the last rod that the anchor fixture "
                                                   "imposes: [[lo, hi] | null, [lo, hi] | null]."),
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
            "robust": Field(Bool(), default=True,
                            description="Prefer, among designs that hang on the curve, those whose pin "
                            "friction and print tolerance bands stay within the tolerance: where a free "
                            "joint's band is larger, the planner holds it with a two-sided stop (rods "
                            "printed to order). false: the first design that hangs on the curve."),
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
        description="A hanging chain to design (target) or simulate (chain), or a net of rods (net); "
        "units mm, g, deg.",
    )


def design_schema() -> dict[str, Any]:
    """The JSON Schema of design files, generated from the validating specs."""
    return {"$schema": "https://json-schema.org/draft/2020-12/schema", **design_spec().json_schema()}
