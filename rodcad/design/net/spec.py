"""The ``net:`` block of a design file as a spec tree (validation and JSON Schema).

A net is given explicitly (``nodes`` and ``edges``) or generated (``surface``, ``mesh`` or
``radial``); ``anchored`` lists node indices or names a generated set (see
:mod:`rodcad.design.net.layouts`). The cross-checks that need the generated net (indices in
range, a part hanging from nothing, rods the catalog cannot print) are in
:mod:`rodcad.design.net.target`.
"""

from __future__ import annotations

from typing import Any

import yaml

from rodcad.catalog.net.bend import MAX_BEND
from rodcad.yamlio import MISSING, TAG_NULL, Validator
from rodcad.yamlspec import Bool, Field, ListOf, Num, Obj, OneOrList, Spec, Str

__all__ = ["ANCHOR_SETS", "AnchoredSpec", "MAX_CELLS", "MAX_NET_NODES", "MAX_REFINE", "net_spec"]

#: ``anchored`` keywords: which generated node set each names.
ANCHOR_SETS = {
    "corners": "a surface grid's four corners",
    "boundary": "the border of a grid or mesh, a radial net's outer ring (and a sector's sides)",
    "ends": "a grid's first and last columns (a strip hung from its two ends), a sector's first and last spokes",
    "outer": "a radial net's outer ring",
    "inner": "a radial net's inner ring (or its centre node)",
}

#: Most cells along one side of a generated grid, most rings or spokes of a radial net.
MAX_CELLS = 100

#: The finest refinement asked of a net (net.refine).
MAX_REFINE = 20

#: Most nodes of a net (explicit or generated).
MAX_NET_NODES = 5000


class AnchoredSpec(Spec):
    """A keyword of :data:`ANCHOR_SETS` or a list of node indices."""

    def __init__(self, description: str = "") -> None:
        self.description = description
        self.word = Str(choices=tuple(ANCHOR_SETS))
        self.indices = ListOf(Num(integer=True, minimum=0), min_items=1, unique=True)

    def check(self, node: yaml.Node, path: str, v: Validator) -> Any:
        if isinstance(node, yaml.SequenceNode):
            return self.indices.check(node, path, v)
        if isinstance(node, yaml.ScalarNode) and node.tag != TAG_NULL:
            return self.word.check(node, path, v)
        v.report(node, path, "expected a list of node indices or one of " + ", ".join(ANCHOR_SETS))
        return MISSING

    def json_schema(self) -> dict[str, Any]:
        return self._describe({"anyOf": [self.word.json_schema(), self.indices.json_schema()]})


def _range(what: str) -> ListOf:
    return ListOf(Num(unit="mm"), min_items=2, description=f"[{what} min, {what} max] (mm)")


def net_spec() -> Obj:
    """Spec of the ``net`` mapping."""
    cells = dict(integer=True, minimum=1, maximum=MAX_CELLS)
    return Obj(
        {
            "nodes": Field(ListOf(ListOf(Num(unit="mm"), min_items=3, description="[x, y, z] (mm, z up)"),
                                  min_items=2),
                           description="Target node positions [[x, y, z], ...] (mm, z up); with 'edges'."),
            "edges": Field(ListOf(ListOf(Num(integer=True, minimum=0), min_items=2, description="[i, j]"),
                                  min_items=1),
                           description="One rod between nodes i and j per entry (indices into 'nodes', from 0)."),
            "surface": Field(
                Obj({
                    "z": Field(Str(), required=True, description="z as an expression in x and y (mm), e.g. "
                               "'0.002 * ((x - 80)**2 + (y - 80)**2) - 40'; numbers, x, y, pi, e, + - * / ** "
                               "and sin, cos, sqrt, ... only."),
                    "x": Field(_range("x"), required=True, description="The grid's extent along x (mm)."),
                    "y": Field(_range("y"), required=True, description="The grid's extent along y (mm)."),
                    "u": Field(Num(**cells), required=True, description="Cells along x."),
                    "v": Field(Num(**cells), required=True, description="Cells along y."),
                }, description="A grid of u x v cells over a rectangle, its nodes on the surface z(x, y); "
                   "the rods run along the grid lines."),
            ),
            "mesh": Field(Str(), description="A Wavefront OBJ file (relative to the design file, mm, z up): "
                          "a node at every vertex of a face, a rod along every edge of a face."),
            "radial": Field(
                Obj({
                    "rings": Field(Num(**cells), required=True, description="Rings of nodes."),
                    "spokes": Field(Num(integer=True, minimum=3, maximum=360), required=True,
                                    description="Nodes per ring (spoke directions)."),
                    "radius": Field(OneOrList(Num(minimum=0, unit="mm"), unique=True), required=True,
                                    description="The outer ring's radius (a centre node joins the first "
                                    "ring), or [inner, outer] (mm): rings from inner to outer."),
                    "z": Field(Str(), default="0", description="z as an expression in r (radius, mm), a "
                               "(angle, rad), x and y (mm), e.g. '-0.6 * (120 - r)'."),
                    "sweep_deg": Field(Num(exclusive_minimum=0, maximum=360, unit="deg"), default=360.0,
                                       description="The angle the spokes span (deg); 360 closes every ring, "
                                       "less makes a sector whose rings stay open."),
                    "start_deg": Field(Num(unit="deg"), default=0.0, description="The first spoke's angle "
                                       "from +x (deg)."),
                }, description="Rings and spokes (a lampshade, a web, a collar as an open sector)."),
            ),
            "anchored": Field(AnchoredSpec(), required=True,
                              description="The nodes held where they are: a list of node indices, or for a "
                              "generated net " + "; ".join(f"'{k}': {d}" for k, d in ANCHOR_SETS.items())
                              + ". Rods between two anchored nodes of a generated set are left out."),
            "bend": Field(Num(minimum=0, maximum=round(MAX_BEND, 4)),
                          description="Every rod printed bent: its body's arc bows this share of its chord "
                          "below the chord at mid-length (sagitta over chord; 0: straight; at most "
                          f"{MAX_BEND:.4f}, an arc of 120 deg). A rod on ball joints turns freely about its "
                          "chord, so the bow hangs in the vertical plane through the chord, below it: its size "
                          "is chosen, its plane is not."),
            "bends": Field(ListOf(Obj({
                "rods": Field(ListOf(Num(integer=True, minimum=0), min_items=1, unique=True), required=True,
                              description="Rod indices (as design.json's net.rods: the order of 'edges', or of "
                              "the generated rods)."),
                "bend": Field(Num(minimum=0, maximum=round(MAX_BEND, 4)), required=True,
                              description="Their bend (sagitta over chord; 0: straight)."),
            }, description="A bend for some rods."), min_items=1),
                description="Bends per rod, over 'bend' (later entries over earlier ones)."),
            "refine": Field(Num(integer=True, minimum=1, maximum=MAX_REFINE),
                            description="A finer net of the same surface: every edge cut into N. A generated "
                            "net is generated with N times the cells (a surface grid's u and v, a radial net's "
                            "spokes and the gaps between its rings); a mesh's triangles are cut into N x N "
                            "(midpoint subdivision for 2; quads into N x N quads); explicit edges into N rods in "
                            "line (their new nodes hang as the planner's two-rod joints)."),
            "edge_length": Field(Num(exclusive_minimum=0, maximum=10000, unit="mm"),
                                 description="Refine to the finer net whose mean edge is nearest this length (mm): "
                                 "refine N = the mean edge over it, rounded (at least 1); with 'refine', the larger."),
            "compression": Field(Bool(),
                                 description="true: any rod may push; false: every rod stays in tension. Unset "
                                 "(the default): a rod may push where the hardware holds it: one rigid rod "
                                 "between two hubs (their ball sockets hold it either way), not at a two-rod "
                                 "joint, pushing less than a fifth of its buckling load (material.modulus); "
                                 "point nodes keep every rod in tension."),
        },
        description="A net of rods (three or more at a joint, 3D, z up) to hang in a target shape: nodes "
        "and edges, or generated from a surface, a mesh or rings and spokes.",
    )
