"""The catalog file format as a spec tree: the validator of catalog YAML and its JSON Schema.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import yaml

from rodcad.yamlio import MISSING, Validator
from rodcad.yamlspec import Bool, Field, ListOf, Nullable, Num, Obj, OneOrList, Spec, Str

if TYPE_CHECKING:  # pragma: no cover
    pass
from rodcad.catalog.model import CATALOG_FORMAT, mm_pos

#: Longest design, catalog or family name (it names folders and files).
MAX_NAME = 100

__all__ = ["ListOrRange", "OneOrMany", "catalog_schema", "catalog_spec", "family_spec", "node_spec", "pins_spec"]


class ListOrRange(OneOrList):
    """One value, a list of values (a fixed menu: one rod type each) or a range
    ``{min, max}`` (rods printed to order: the planner picks each rod's own value).
    The Python value is a list, or a dict with 'min' and 'max' for a range."""

    def __init__(self, item: Num, *, what: str, extra: dict[str, Field] | None = None, **kw: Any) -> None:
        super().__init__(item, unique=True, **kw)
        self.range = Obj({
            "min": Field(item, required=True, description=f"Smallest {what}."),
            "max": Field(item, required=True, description=f"Largest {what}."),
            **(extra or {}),
        }, description=f"Any {what} from min to max: every rod is printed with its own value.")

    def check(self, node: yaml.Node, path: str, v: Validator) -> Any:
        if isinstance(node, yaml.MappingNode):
            return self.range.check(node, path, v)
        return super().check(node, path, v)

    def json_schema(self) -> dict[str, Any]:
        schema = super().json_schema()
        schema["anyOf"] = [*schema["anyOf"], self.range.json_schema()]
        return schema


class OneOrMany(ListOf):
    """One mapping or a list of mappings of the same spec (e.g. one ball kind or several).
    Unlike :class:`OneOrList` the Python value keeps the form written: a dict for one
    mapping (so 'defaults' and a family merge key by key), a list for several."""

    def check(self, node: yaml.Node, path: str, v: Validator) -> Any:
        if isinstance(node, yaml.SequenceNode):
            if not node.value:
                v.report(node, path, "expected a mapping or a list of at least 1 item, got an empty list")
                return MISSING
            return self._check_items(node, path, v)
        return self.item.check(node, path, v)

    def json_schema(self) -> dict[str, Any]:
        item = dict(self.item.json_schema())
        description = item.pop("description", "")
        schema: dict[str, Any] = {"anyOf": [item, {"type": "array", "items": item, "minItems": 1,
                                                   "uniqueItems": True}]}
        description = self.description or description
        return {"description": description, **schema} if description else schema


_NAME = r"[A-Za-z0-9][A-Za-z0-9_.+-]*"


_NAME_HINT = "a name of letters, digits, '.', '_', '+' or '-'"


_LAYOUTS = ("tongue-fork", "fork-tongue")


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


def family_spec() -> Obj:
    """Spec of a complete family (after defaults are applied): required flags
    and defaults here are the ones enforced after merging."""
    num_list = lambda spec, **kw: OneOrList(spec, unique=True, **kw)  # noqa: E731
    return Obj(
        {
            "name": Field(Str(pattern=_NAME, pattern_hint=_NAME_HINT, max_length=MAX_NAME), required=True,
                          description="Family name; types are named '<family>-<length>'."),
            "description": Field(Str(), description="Free text."),
            "length": Field(
                ListOrRange(Num(exclusive_minimum=0, maximum=1000, unit="mm"), what="length (mm)", extra={
                    "resolution": Field(Num(exclusive_minimum=0, maximum=10, unit="mm"),
                                        description="Print resolution (mm): every rod's length is a "
                                        "multiple of it (the joints move off the curve by up to about "
                                        "that much); default: lengths as designed, to round-off."),
                }),
                required=True,
                description="Distance between the two hinge axes (mm); a list makes one type per value, "
                "a range {min, max} makes rods printed to order, each at the length its place needs.",
            ),
            "scale": Field(
                ListOrRange(Num(exclusive_minimum=0, maximum=10), what="scale"),
                default=[1.0],
                description="Cross-section scale factor. A list makes one type per value, each "
                "scaling section height and thickness, knuckle radius and tongue thickness (not pins, "
                "gaps or setbacks); types of different scale do not join. A range {min, max} (rods "
                "printed to order) makes graduated rods: each rod's body section (height and "
                "thickness) at its own scale while its hinge ends (knuckles, pins, end faces) stay "
                "the family's, so any rod joins any other; the body keeps its bottom face, the one it "
                "is printed on (see rodcad.catalog.model.RodGeometry).",
            ),
            "curvature": Field(
                ListOrRange(Num(minimum=-1, maximum=1, unit="1/mm"), what="curvature (1/mm)"),
                default=[0.0],
                description="Signed curvature of the body's arc through both hinge axes (1/mm; "
                "1/radius). Positive bulges toward -y (below the chord, like a sagging chain), "
                "negative toward +y; 0 is straight. A list makes one type per value; a range "
                "{min, max} (with a length range) lets every rod follow its piece of the curve.",
            ),
            "stops": Field(
                Obj({
                    "min": Field(Num(minimum=-90, maximum=90, unit="deg"), required=True,
                                 description="Most concave stop angle (deg; negative: the joint stops "
                                 "before straight)."),
                    "max": Field(Num(minimum=-90, maximum=90, unit="deg"), required=True,
                                 description="Most convex (sagging) stop angle (deg)."),
                }),
                description="Stop angles printed to order (with a length range): where the masses "
                "alone cannot hold a bend, the two ends that meet there get flush faces (setback 0) "
                "whose top chamfers add up to the bend, so the joint rests on a stop exactly at it. "
                "The bend of a stop is measured between the rods' chords (deg, > 0 sagging).",
            ),
            "section": Field(
                Obj(
                    {
                        "height": Field(Num(maximum=200, **mm_pos), required=True,
                                        description="Section height in the chain plane, y (mm)."),
                        "thickness": Field(Num(maximum=200, **mm_pos), required=True,
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
                        "pin_diameter": Field(Num(maximum=50, **mm_pos), required=True,
                                              description="Pin diameter (mm); pins are separate parts, "
                                              "e.g. pieces of 1.75 mm filament."),
                        "pin_clearance": Field(Num(minimum=0, maximum=5, unit="mm"), default=0.25,
                                               description="Pin hole diameter minus pin diameter (mm). "
                                               "Under load each pin bears on the far side of its holes; "
                                               "rodcad places the holes so the loaded chain hangs on its design."),
                        "friction": Field(OneOrList(Num(minimum=0, maximum=2), min_items=1), default=[0.2, 0.4],
                                          description="Friction coefficient of the pin in its holes: a number, "
                                          "or [lo, hi] where it is known as a range (the friction band is "
                                          "reported for hi). Default [0.2, 0.4]: published for dry PLA on "
                                          "steel; measure yours with `rodcad calibrate friction`."),
                        "knuckle_radius": Field(Num(maximum=100, **mm_pos), required=True,
                                                description="Outer radius of the knuckles around the "
                                                "hinge axis (mm, before scaling)."),
                        "tongue_thickness": Field(Num(maximum=100, **mm_pos), required=True,
                                                  description="Thickness of the middle (tongue) layer "
                                                  "(mm, before scaling)."),
                        "layer_gap": Field(Num(maximum=5, **mm_pos), default=0.3,
                                           description="Axial clearance between tongue and fork prongs (mm)."),
                        "radial_gap": Field(Num(maximum=5, **mm_pos), default=0.4,
                                            description="Radial clearance around the partner's knuckle (mm)."),
                    },
                    description="Pinned hinge knuckles (see rodcad.catalog.model.Hinge).",
                ),
                required=True,
            ),
            "ends": Field(
                Obj(_end_fields(True), description="End faces outside the hinge zone: they set the "
                    "joint limits (see rodcad.catalog.model.EndShape)."),
                default={},
            ),
            "material": Field(
                Obj(
                    {
                        "name": Field(Str(), default="", description="e.g. PLA."),
                        "density": Field(Num(maximum=25, exclusive_minimum=0, unit="g/cm^3"), required=True,
                                         description="Density (g/cm^3)."),
                        "min_wall": Field(Num(maximum=50, **mm_pos), required=True,
                                          description="Minimum wall (mm): thinnest printed wall, also kept "
                                          "around cavities, ball sockets and pin holes."),
                        "modulus": Field(Num(exclusive_minimum=0, maximum=500, unit="GPa"),
                                         description="Young's modulus of a printed rod along its axis (GPa; default "
                                         "1.5, the low end of printed PLA, PETG and ABS): a net rod that pushes "
                                         "must stay under a fifth of its buckling load."),
                    },
                    description="Printing material.",
                ),
                required=True,
            ),
            "fill": Field(
                Obj(
                    {
                        "name": Field(Str(), required=True, description="e.g. tungsten shot."),
                        "density": Field(Num(maximum=25, exclusive_minimum=0, unit="g/cm^3"), required=True,
                                         description="Density of the metal (g/cm^3): tungsten 19.3, "
                                         "lead 11.35, steel 7.85."),
                        "packing": Field(Num(exclusive_minimum=0, maximum=0.75), default=0.6,
                                         description="Fraction of the chamber the loose shot fills "
                                         "(random loose packing of spheres about 0.6; at most 0.75)."),
                    },
                ),
                description="Loose dense shot (rods printed to order): every rod gets one chamber "
                "centred on its centre of mass, left empty (lighter) or filled with the shot at a "
                "print pause (heavier), sized for its mass (see rodcad.catalog.chamber).",
            ),
            "balls": Field(
                Nullable(
                    OneOrMany(
                        Obj(
                            {
                                "name": Field(Str(), default="", description="e.g. steel 5 mm."),
                                "diameter": Field(Num(maximum=100, **mm_pos), required=True,
                                                  description="Ball diameter (mm)."),
                                "density": Field(Num(maximum=25, exclusive_minimum=0, unit="g/cm^3"),
                                                 required=True, description="Ball density (g/cm^3): steel "
                                                 "7.85, tungsten carbide 15.6, tungsten alloy 17-18.5."),
                                "clearance": Field(Num(minimum=0, maximum=5, unit="mm"), default=0.2,
                                                   description="Socket diameter minus ball diameter (mm)."),
                            },
                        ),
                        unique=True,
                    ),
                    description="Metal balls the rods may hold in closed sockets to add mass: one kind, "
                    "or a list of kinds (first listed first: each further kind is used where the ones "
                    "before cannot make a rod heavy enough, one kind per rod); null for none.",
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
    if isinstance(spec, OneOrMany):  # one mapping merges with 'defaults'; list items are complete
        return OneOrMany(_partial(spec.item), unique=spec.unique, description=spec.description)
    return spec


def _size_spec(item: Num, what: str) -> Spec:
    """One size, or a family ``{min, max, nominal}`` of a node's hub."""
    return OneOrRange(item, Obj({
        "min": Field(item, required=True, description=f"Smallest {what}."),
        "max": Field(item, required=True, description=f"Largest {what}."),
        "nominal": Field(item, description=f"The {what} a node gets where its rods fit it (default min)."),
    }, description=f"Any {what} from min to max: every node gets its own hub."))


class OneOrRange(Spec):
    """A number, or a mapping (a range)."""

    def __init__(self, item: Spec, range_: Obj) -> None:
        self.item, self.range, self.description = item, range_, ""

    def check(self, node: yaml.Node, path: str, v: Validator) -> Any:
        if isinstance(node, yaml.MappingNode):
            return self.range.check(node, path, v)
        return self.item.check(node, path, v)

    def json_schema(self) -> dict[str, Any]:
        return self._describe({"anyOf": [self.item.json_schema(), self.range.json_schema()]})


def node_spec() -> Obj:
    """Spec of a catalog's ``node`` block: the hardware at a net's nodes (see
    :mod:`rodcad.catalog.net.node`; unset keys take :data:`rodcad.catalog.net.node.DEFAULT_NODE`)."""
    from rodcad.catalog.net.node import DEFAULT_NODE, NODE_KINDS

    d = DEFAULT_NODE
    mm = dict(exclusive_minimum=0, maximum=200, unit="mm")
    return Obj(
        {
            "kind": Field(Str(choices=NODE_KINDS), description="hub: a printed sphere with one ball socket per "
                          "rod, a rigid body whose pose the solver finds; point: the rods pivot about one point "
                          f"(a jump ring, a small shackle) (default {d['kind']})."),
            "name": Field(Str(), description="Free text."),
            "diameter": Field(_size_spec(Num(**mm), "diameter (mm)"),
                              description=f"hub: the sphere's diameter (default {d['diameter']:g} mm), or a "
                              "family {min, max, nominal} (see pivot_radius)."),
            "pivot_radius": Field(_size_spec(Num(**mm), "pivot radius (mm)"),
                                  description="hub: from the hub's centre to each rod's ball centre, its pivot "
                                  f"(default {d['pivot_radius']:g} mm); or a family of hubs {{min, max, nominal}}: "
                                  "every node gets the nominal hub (default min) where its rods fit it, else the "
                                  "nearest size that does (larger where rods meet at tight angles, smaller where "
                                  "a rod would be too short); the sizes keep the nominal hub's wall outside their "
                                  "pivots, so the diameter follows."),
            "ball": Field(Num(**mm), description="hub: diameter of the ball each rod ends in, printed with the rod "
                          f"(default {d['ball']:g} mm)."),
            "clearance": Field(Num(minimum=0, maximum=5, unit="mm"), description="hub: socket diameter minus ball "
                               f"diameter (default {d['clearance']:g} mm); rodcad offsets each socket so the loaded "
                               "ball sits on its pivot."),
            "cone_deg": Field(_size_spec(Num(exclusive_minimum=0, exclusive_maximum=90, unit="deg"),
                                         "socket cone (deg)"),
                              description="hub: half-angle of each socket's opening cone, apex at the ball's centre "
                              f"(default {d['cone_deg']:g} deg); or a range {{min, max, nominal}}: a hub gets the "
                              "nominal cone (default min) where its rods' turns fit it, else the narrowest wider one "
                              "that lets them, within the range and keeping the wall between its sockets."),
            "neck": Field(Num(**mm), description="hub: diameter of a rod's neck between its ball and its body "
                          f"(default {d['neck']:g} mm)."),
            "rod_diameter": Field(Num(**mm), description=f"Net rods' round body (default {d['rod_diameter']:g} mm)."),
            "gap": Field(Num(minimum=0, maximum=50, unit="mm"), description="hub: between the hub's surface and a "
                         f"rod body's end face (default {d['gap']:g} mm)."),
            "mass": Field(Num(minimum=0, maximum=1000, unit="g"), description="point: the part's mass "
                          f"(default {d['mass']:g} g)."),
            "splice": Field(_splice_spec(), description="hub: the steel dowel pins a rod longer than the catalog "
                            "prints is spliced on, where two-rod joints cannot hang (rodcad.catalog.net.splice)."),
        },
        description="The hardware at a net's nodes (every rod turns freely in every direction); printed in the "
        "families' material, rods weighed down with their steel balls.",
    )


def _splice_spec() -> Obj:
    """Spec of ``node.splice``: a rigid in-line splice's dowel pin (:mod:`rodcad.catalog.net.splice`)."""
    from rodcad.catalog.net.splice import DEFAULT_SPLICE as d

    return Obj(
        {
            "pin_diameter": Field(Num(exclusive_minimum=0, maximum=20, unit="mm"),
                                  description=f"The steel dowel pin's diameter (default {d['pin_diameter']:g} mm)."),
            "pin_length": Field(Num(exclusive_minimum=0, maximum=100, unit="mm"),
                                description=f"Its length, half in each piece (default {d['pin_length']:g} mm)."),
            "pin_density": Field(Num(exclusive_minimum=0, maximum=25, unit="g/cm^3"),
                                 description=f"Its material (default {d['pin_density']:g} g/cm^3, steel)."),
            "clearance": Field(Num(minimum=0, maximum=2, unit="mm"), description="Hole diameter minus pin "
                               f"diameter (default {d['clearance']:g} mm); the pin is glued in."),
        },
        description="Rigid in-line splice: a rod cut square into equal pieces, each cut's faces bored for a "
        "dowel pin glued into both.",
    )


def pins_spec() -> Obj:
    """Spec of a catalog's ``pins`` block: the joint hardware the planner chooses from, per
    joint (:mod:`rodcad.catalog.pins`; without the block, :data:`rodcad.catalog.pins.
    DEFAULT_OPTIONS` and the families' own pin)."""
    from rodcad.catalog.pins import DEFAULT_PRESSURE, DEFAULT_SAFETY, PIN_KINDS

    mm = dict(exclusive_minimum=0, maximum=50, unit="mm")
    pair = dict(min_items=1)
    option = Obj(
        {
            "name": Field(Str(pattern=_NAME, pattern_hint=_NAME_HINT, max_length=MAX_NAME), required=True,
                          description="Unique name, e.g. bearing-682 (the bill of materials lists it). An option "
                          "named like the families' own pin (steel-pin-<diameter>) replaces it."),
            "kind": Field(Str(choices=PIN_KINDS), required=True,
                          description="pin: a steel pin in printed holes; bushing: a sleeve pressed into the "
                          "tongue, the pin turning in it; bearing: ball bearings pressed into the tongue on a pin "
                          "the fork holds."),
            "description": Field(Str(), description="What to buy and how it goes in."),
            "pin_diameter": Field(Num(**mm), required=True, description="The steel pin (mm)."),
            "clearance": Field(Num(minimum=0, maximum=2, unit="mm"), required=True,
                               description="Diametral play where the pin turns (mm): printed holes minus the pin, "
                               "a sleeve's bore minus the pin, a bearing's radial play. The fork's holes are the "
                               "pin plus this."),
            "friction": Field(OneOrList(Num(minimum=0, maximum=2), **pair), required=True,
                              description="Friction coefficient where the pin turns: a number or [lo, hi] (the "
                              "band is reported for hi)."),
            "torque": Field(OneOrList(Num(minimum=0, maximum=100, unit="N mm"), **pair), default=[0.0, 0.0],
                            description="Friction moment that does not grow with the load (N mm per joint; a "
                            "bearing's lubricant): a number or [lo, hi]."),
            "outer_diameter": Field(Num(**mm), description="bushing, bearing: the sleeve's or bearings' outer "
                                    "diameter, the tongue's printed hole (mm)."),
            "width": Field(Num(**mm), description="bushing, bearing: each one's length along the pin (mm; a "
                           "bushing without it is cut to the tongue's thickness)."),
            "count": Field(Num(integer=True, minimum=1, maximum=10), default=1,
                           description="bearings side by side per joint."),
            "part_mass": Field(Num(minimum=0, maximum=100, unit="g"),
                               description="Each sleeve or bearing (g; a sleeve without it: from sleeve_density)."),
            "part_load": Field(Num(exclusive_minimum=0, maximum=1e5, unit="N"),
                               description="Each bearing's static load rating (N)."),
            "sleeve_density": Field(Num(exclusive_minimum=0, maximum=25, unit="g/cm^3"), default=2.2,
                                    description="A sleeve's material (PTFE 2.2, brass 8.5)."),
            "sleeve_pressure": Field(Num(exclusive_minimum=0, maximum=1000, unit="MPa"), default=3.0,
                                     description="Bearing stress a sleeve takes under its pin (MPa; PTFE about 3)."),
            "pin_density": Field(Num(exclusive_minimum=0, maximum=25, unit="g/cm^3"), default=7.85,
                                 description="The pin's material (g/cm^3)."),
            "pin_yield": Field(Num(exclusive_minimum=0, maximum=5000, unit="MPa"), default=600.0,
                               description="The pin's yield stress (MPa; spring-steel wire about 1500)."),
            "cost": Field(Num(minimum=0, maximum=1e6), default=0.05,
                          description="Per joint, in any one currency: the planner takes the cheapest option that "
                          "carries the joint's load and keeps the chain within its friction band."),
            "measured": Field(Bool(), default=False,
                              description="The friction was measured (rodcad calibrate friction); report.md says so."),
        },
        description="One kind of joint hardware.",
    )
    return Obj(
        {
            "safety": Field(Num(minimum=1, maximum=100), description="Safety factor on every rated load "
                            f"(default {DEFAULT_SAFETY:g})."),
            "pressure": Field(Num(exclusive_minimum=0, maximum=1000, unit="MPa"),
                              description="Bearing stress the printed plastic takes under a pin or sleeve, long "
                              f"term (MPa, default {DEFAULT_PRESSURE:g} for PLA)."),
            "options": Field(ListOf(option, min_items=1), description="The hardware to choose from, besides the "
                             "families' own pin (default: 1.5 mm steel pins, 1 mm spring-steel wire, a PTFE "
                             "bushing and 682 ball bearings)."),
        },
        description="Joint hardware the planner picks from, per joint: the cheapest whose rated load carries the "
        "joint's force and whose friction keeps the chain within a tenth of its tolerance.",
    )


def catalog_spec() -> Obj:
    """The spec of a whole catalog file."""
    family = family_spec()
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
            "name": Field(Str(pattern=_NAME, pattern_hint=_NAME_HINT, max_length=MAX_NAME), required=True,
                          description="Catalog name."),
            "description": Field(Str(), description="Free text."),
            "printer": Field(
                Obj(
                    {
                        "name": Field(Str(), default="", description="Free text."),
                        "build_volume": Field(
                            ListOf(Num(maximum=5000, **mm_pos), min_items=3),
                            required=True,
                            description="Build volume x, y, z (mm); every rod must fit.",
                        ),
                        "nozzle": Field(Num(maximum=5, **mm_pos), required=True,
                                        description="Nozzle diameter (mm); the minimum wall must not be thinner."),
                        "mesh_deflection": Field(
                            Num(minimum=0.001, maximum=1, unit="mm"),
                            description="How far (mm) the STL and 3MF meshes of a net's parts may lie from the "
                            "solids' surfaces (absolute linear deflection). Default: 0.15 x print.layer_height "
                            "(0.03 mm for 0.2 mm layers), well under a layer's own ridges, so that the "
                            "meshes (what the slicer prints) hold within 0.3 % of the solids' plastic; "
                            "masses and checks are taken from the exact solids, never the meshes."),
                        "mesh_angle": Field(
                            Num(minimum=1, maximum=45, unit="deg"),
                            description="The meshes' angular deflection (degrees between neighbouring "
                            "facets' normals). Default 11.5 (0.2 rad): round features as small as a net "
                            "rod's 9 mm body keep their volume (the printed plastic) within 0.3 %."),
                    },
                    description="The printer the catalog is sized for (optional; enables size checks).",
                )
            ),
            "print": Field(
                Obj(
                    {
                        "layer_height": Field(Num(exclusive_minimum=0, maximum=2, unit="mm"), default=0.2,
                                              description="Layer height (mm)."),
                        "first_layer_height": Field(Num(exclusive_minimum=0, maximum=2, unit="mm"),
                                                    description="First layer height (mm; default: the layer "
                                                    "height)."),
                        "perimeters": Field(Num(integer=True, minimum=1, maximum=20), default=2,
                                            description="Perimeter loops (the rest is 100 % infill)."),
                        "filament_diameter": Field(Num(exclusive_minimum=0, maximum=5, unit="mm"), default=1.75,
                                                   description="Filament diameter (mm)."),
                        "mass_tolerance": Field(Num(exclusive_minimum=0, maximum=0.5), default=0.03,
                                                description="Relative error of a printed rod's mass that 95 % "
                                                "of rods stay within. Default 0.03: filament sold as 1.75 +- "
                                                "0.02 to 0.05 mm is 2.3-5.7 % off in cross-section at the "
                                                "extremes of its tolerance; a rod averages metres of it."),
                        "temperature": Field(Num(minimum=100, maximum=500, unit="degC"), default=215,
                                             description="Nozzle temperature (deg C)."),
                        "bed_temperature": Field(Num(minimum=0, maximum=200, unit="degC"), default=60,
                                                 description="Bed temperature (deg C)."),
                    },
                    description="The print profile every mass assumes: solid rods (100 % infill) of the "
                    "families' material at these settings; written into print.3mf and report.md.",
                )
            ),
            "defaults": Field(defaults),
            "node": Field(node_spec()),
            "pins": Field(pins_spec()),
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
