"""A design file's net: its ``net:`` block checked and turned into target nodes and rods.

``net_target`` reads the block the schema passed (:func:`rodcad.design.net.spec.net_spec`):
explicit nodes and edges, or a net generated from a surface, an OBJ mesh or rings and spokes
(:mod:`rodcad.design.net.layouts`), and the anchored nodes. Every problem is reported at its key
(``FILE:LINE:COL: net.surface.z: ...``; a problem inside an OBJ file at its own line), all
of them at once.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from rodcad.design.net.layouts import (NetLayout, ObjError, grid_layout, mesh_layout, radial_layout, read_obj,
                                       subdivide_faces)
from rodcad.design.net.spec import ANCHOR_SETS, MAX_CELLS, MAX_NET_NODES
from rodcad.design.targets import evaluate_expression

__all__ = ["NetTarget", "net_target"]

#: Two nodes closer than this (mm) are one node given twice.
COINCIDE_MM = 1e-6

#: The ways a net is given; exactly one per design.
NET_KINDS = ("nodes", "surface", "mesh", "radial")


@dataclass(frozen=True)
class NetTarget:
    """The target of a net design: where every node should hang.

    Attributes:
        kind: 'nodes', 'surface', 'mesh' or 'radial' (how the file gave it).
        positions: (n, 3) target node points (mm, z up).
        edges: (m, 2) the two nodes each rod joins.
        anchored: (k,) anchored node indices, ascending.
        anchored_as: the keyword that chose them, or '' for a list.
        dropped: rods left out because both their nodes are anchored (a generated set).
        compression: rods may push (True), every rod in tension (False), or rods push where the
            hardware holds them (None, the default: :attr:`rodcad.design.net.check.NetCheck.unheld`).
        shape: (u, v) cells, (rings, spokes), or ().
        written: the block as written (for design.json and the report).
        rod_bends: (m,) each rod's bend (sagitta over chord of its body's arc, 0 straight;
            :mod:`rodcad.catalog.net.bend`), or None: every rod straight.
        surface: z(x, y, near) of a generated net's surface (mm; ``near`` a node whose
            angle a radial net's expression reads near), or None: the net is its edges.
        fit_nodes, fit_points: where the fit measures (:attr:`fit_pairs`), or None.
        source: (m,) the drawn edge each rod lies on (the planner's; None: rod e is edge e).
        joints: node indices of the two-rod joints the planner added, or None.
        drawn: the target as drawn, before the planner (None: this is it).
        refine_edges: every edge cut into this many rods in line by the planner (``net.refine``
            of explicit nodes and edges).
        node_of_drawn: (drawn n,) the node each drawn node became where the planner collapsed
            short edges (:mod:`rodcad.design.net.collapse`), or None.
        glued: nodes the planner has held by rods glued into their sockets toward the anchors
            (:mod:`rodcad.design.net.glued`; in ``anchored`` too: held as an anchor is), or None.
        glued_rods: the rods glued at both ends that hold them, or None.
    """

    kind: str
    positions: np.ndarray
    edges: np.ndarray
    anchored: np.ndarray
    anchored_as: str = ""
    dropped: int = 0
    compression: bool | None = None
    shape: tuple[int, ...] = ()
    written: dict[str, Any] = field(default_factory=dict)
    rod_bends: np.ndarray | None = None
    surface: Any = None
    fit_nodes: np.ndarray | None = None
    fit_points: np.ndarray | None = None
    source: np.ndarray | None = None
    joints: np.ndarray | None = None
    drawn: Any = None
    refine_edges: int = 1
    node_of_drawn: np.ndarray | None = None
    glued: np.ndarray | None = None
    glued_rods: np.ndarray | None = None

    @property
    def fit_pairs(self) -> tuple[np.ndarray, np.ndarray]:
        """(nodes (P,), points (P, 3)): where the fit measures the net, each node against
        the point drawn for it (the planner's joints against the drawn surface or edge,
        merged nodes against each node drawn); by default every node against its target."""
        if self.fit_nodes is None:
            return np.arange(self.n), self.positions
        return self.fit_nodes, self.fit_points

    def _mask(self, nodes: np.ndarray | None) -> np.ndarray:
        """(n,) True at ``nodes`` (None: none)."""
        mask = np.zeros(self.n, dtype=bool)
        if nodes is not None:
            mask[nodes] = True
        return mask

    @property
    def joint_mask(self) -> np.ndarray:
        """(n,) the two-rod joints the planner added on long edges."""
        return self._mask(self.joints)

    @property
    def bends(self) -> np.ndarray:
        """(m,) each rod's bend (0: straight)."""
        return np.zeros(self.m) if self.rod_bends is None else self.rod_bends

    @property
    def any_may_push(self) -> bool:
        """Every rod may push (``compression: true``); unset or false, the designs keep them in
        tension and the check judges what pushes (:attr:`rodcad.design.net.check.NetCheck.unheld`)."""
        return bool(self.compression)

    @property
    def edge_lengths(self) -> np.ndarray:
        """(m,) each edge's length node to node (mm)."""
        return np.linalg.norm(self.positions[self.edges[:, 1]] - self.positions[self.edges[:, 0]], axis=1)

    @property
    def n(self) -> int:
        return int(self.positions.shape[0])

    @property
    def m(self) -> int:
        return int(self.edges.shape[0])

    @property
    def size(self) -> float:
        """The net's size: the largest extent of its target along x, y or z (mm; as drawn,
        where the planner edited it)."""
        pts = self.positions if self.fit_points is None else self.fit_points
        if self.drawn is not None:  # (nodes a collapse merged away count as drawn)
            pts = np.vstack([pts, self.drawn.positions])
        return float(np.max(np.ptp(pts, axis=0)))

    def node_ends(self) -> list[list[tuple[int, int]]]:
        """Per node, the rod ends at it, (rod, end): the rods that start there, then those that
        end there, each in rod order."""
        out: list[list[tuple[int, int]]] = [[] for _ in range(self.n)]
        for c in (0, 1):
            for e, k in enumerate(self.edges[:, c].tolist()):
                out[k].append((e, c))
        return out

    @property
    def anchored_mask(self) -> np.ndarray:
        """(n,) the nodes held: the anchors and the nodes glued rods hold (:attr:`glued`)."""
        return self._mask(self.anchored)

    @property
    def glued_mask(self) -> np.ndarray:
        """(n,) the nodes held by glued rods (:attr:`glued`), not hung on the frame."""
        return self._mask(self.glued)

    @property
    def hung_from(self) -> np.ndarray:
        """The anchors the net is hung from on its frame: :attr:`anchored` less :attr:`glued`."""
        return self.anchored[~self.glued_mask[self.anchored]]


def _expr(text: str, variables: dict[str, np.ndarray], what: str, key: str, v: Any) -> np.ndarray | None:
    try:
        z = evaluate_expression(text, variables, what=what)
    except ValueError as err:
        v.report_at(key, str(err))
        return None
    if not np.all(np.isfinite(z)):
        k = int(np.flatnonzero(~np.isfinite(z.ravel()))[0])
        at = ", ".join(f"{name} = {np.broadcast_to(val, z.shape).ravel()[k]:.6g}" for name, val in variables.items())
        v.report_at(key, f"the {what} expression is not a finite number at {at}")
        return None
    return z


def _surface(s: dict[str, Any], v: Any) -> NetLayout | None:
    bad = False
    for axis in ("x", "y"):
        r = s[axis]
        if len(r) != 2 or not r[0] < r[1]:
            v.report_at(f"net.surface.{axis}", f"expected [{axis} min, {axis} max] with min < max, got {r}")
            bad = True
    u, w = int(s["u"]), int(s["v"])
    if (u + 1) * (w + 1) > MAX_NET_NODES:
        v.report_at("net.surface", f"{u} x {w} cells make {(u + 1) * (w + 1)} nodes; at most {MAX_NET_NODES}")
        return None
    xs = np.linspace(s["x"][0], s["x"][-1], u + 1)
    ys = np.linspace(s["y"][0], s["y"][-1], w + 1)
    X, Y = np.meshgrid(xs, ys)
    if _expr(s["z"], {"x": X, "y": Y}, "z(x, y)", "net.surface.z", v) is None or bad:
        return None
    layout = grid_layout(lambda x, y: evaluate_expression(s["z"], {"x": x, "y": y}, what="z(x, y)"),
                         (s["x"][0], s["x"][1]), (s["y"][0], s["y"][1]), u, w)
    layout.surface = lambda x, y, near: evaluate_expression(s["z"], {"x": x, "y": y}, what="z(x, y)")
    return layout


def _radial(r: dict[str, Any], v: Any) -> NetLayout | None:
    rad = r["radius"]
    if len(rad) > 2:
        v.report_at("net.radial.radius", f"expected the outer radius or [inner, outer], got {len(rad)} numbers")
        return None
    inner, outer = (0.0, rad[0]) if len(rad) == 1 else (min(rad), max(rad))
    if outer <= 0:
        v.report_at("net.radial.radius", "the outer radius must be greater than 0 mm")
        return None
    rings, spokes = int(r["rings"]), int(r["spokes"])
    if inner > 0 and rings < 2:
        v.report_at("net.radial.rings", "an open net (radius [inner, outer]) needs at least 2 rings")
        return None
    n = rings * spokes + (1 if inner == 0 else 0)
    if n > MAX_NET_NODES:
        v.report_at("net.radial", f"{rings} rings of {spokes} spokes make {n} nodes; at most {MAX_NET_NODES}")
        return None
    sweep, start = float(r.get("sweep_deg", 360.0)), float(r.get("start_deg", 0.0))
    if sweep < 360 - 1e-9 and spokes < 2:  # pragma: no cover - the schema asks for 3 spokes
        return None
    zf = lambda rr, a, x, y: evaluate_expression(r.get("z", "0"), {"r": rr, "a": a, "x": x, "y": y},  # noqa: E731
                                                  what="z(r, a, x, y)")
    try:
        layout = radial_layout(zf, rings, spokes, (inner, outer), sweep_deg=sweep, start_deg=start)
    except ValueError as err:
        v.report_at("net.radial.z", str(err))
        return None
    if not np.all(np.isfinite(layout.positions)):
        v.report_at("net.radial.z", "the z(r, a, x, y) expression is not a finite number at every node")
        return None
    if sweep >= 360 - 1e-9:
        ang = np.radians(start) + 2 * np.pi * np.arange(spokes) / spokes
    else:
        ang = np.radians(start + np.linspace(0.0, sweep, spokes))
    node_a = np.concatenate([[0.0] if inner == 0 else [], np.tile(ang, rings)])

    def surface(x, y, near):  # the angle read as the layout reads it near node `near`
        a0 = node_a[near]
        a = a0 + (np.arctan2(y, x) - a0 + np.pi) % (2 * np.pi) - np.pi
        return zf(np.hypot(x, y), a, x, y)

    layout.surface = surface
    return layout


def _mesh(ref: str, base: Path, v: Any, refine: int = 1) -> NetLayout | None:
    from rodcad.errors import Problem

    path = base / ref
    if not path.is_file():
        v.report_at("net.mesh", f"no such OBJ file {ref!r} (looked in {base})")
        return None
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as err:
        v.report_at("net.mesh", f"cannot read {ref!r}: {err.strerror}")
        return None
    try:
        verts, faces, _ = read_obj(text)
    except ObjError as err:
        v.problems.append(Problem(str(path), err.line, err.column, "", err.message))
        v.failed.add("net.mesh")
        return None
    if refine > 1:
        verts, faces = subdivide_faces(verts, faces, refine)
        if len(verts) > MAX_NET_NODES:
            v.report_at("net.refine", f"the mesh refined {refine} x makes {len(verts)} nodes; at most {MAX_NET_NODES}")
            return None
    return mesh_layout(verts, faces)


def _explicit(net: dict[str, Any], v: Any) -> NetLayout | None:
    nodes, edges = net["nodes"], net["edges"]
    bad = False
    for i, p in enumerate(nodes):
        if len(p) != 3:
            v.report_at(f"net.nodes[{i}]", f"expected [x, y, z] (mm), got {len(p)} numbers")
            bad = True
    n = len(nodes)
    seen: dict[tuple[int, int], int] = {}
    for k, e in enumerate(edges):
        key = f"net.edges[{k}]"
        if len(e) != 2:
            v.report_at(key, f"expected [i, j] (two node indices), got {len(e)} numbers")
            bad = True
            continue
        i, j = int(e[0]), int(e[1])
        for c, idx in enumerate((i, j)):
            if idx >= n:
                v.report_at(f"{key}[{c}]", f"node {idx} does not exist (nodes are 0 to {n - 1})", fallback=key)
                bad = True
        if i == j:
            v.report_at(key, f"joins node {i} to itself")
            bad = True
        pair = (min(i, j), max(i, j))
        if pair in seen:
            v.report_at(key, f"nodes {i} and {j} are already joined by net.edges[{seen[pair]}]")
            bad = True
        seen[pair] = k
    if n > MAX_NET_NODES:
        v.report_at("net.nodes", f"{n} nodes; at most {MAX_NET_NODES}")
        bad = True
    if isinstance(net["anchored"], list):  # checked here too, so that every problem shows at once
        for i, k in enumerate(net["anchored"]):
            if k >= n:
                v.report_at(f"net.anchored[{i}]", f"node {k} does not exist (nodes are 0 to {n - 1})",
                            fallback="net.anchored")
                bad = True
    if bad:
        return None
    return NetLayout(np.asarray(nodes, float), np.asarray(edges, int).reshape(-1, 2), {}, ())


def net_target(net: dict[str, Any], v: Any, base: Path) -> NetTarget | None:
    """The checked ``net`` block as a target, or None after reporting every problem.

    Args:
        net: the block as the schema checked it.
        v: the validator collecting problems (:class:`rodcad.yamlio.Validator`).
        base: the design file's folder (``mesh`` paths are relative to it).
    """
    given = [k for k in NET_KINDS if k in net]
    if "edges" in net and "nodes" not in net:
        v.report_at("net.edges", "edges need 'nodes' (the target positions they join)")
        return None
    if "nodes" in net and "edges" not in net:
        v.report_at("net", "explicit 'nodes' need 'edges' (the rods between them)")
        return None
    if len(given) != 1:
        if not given:
            v.report_at("net", "give the net as 'nodes' and 'edges', or generate it with 'surface', 'mesh' "
                        "or 'radial'")
        else:
            v.report_at(f"net.{given[1]}", f"give one of {', '.join(NET_KINDS)}: this net already has "
                        f"'{given[0]}'")
        return None
    kind = given[0]
    layout = {"nodes": lambda: _explicit(net, v), "surface": lambda: _surface(net["surface"], v),
              "mesh": lambda: _mesh(net["mesh"], base, v), "radial": lambda: _radial(net["radial"], v)}[kind]()
    if layout is None:
        return None
    refine = _refine_count(net, layout)
    split_edges = 1
    if refine > 1:
        layout = _refined(net, kind, refine, base, v)
        if layout is None:
            return None
        split_edges = refine if kind == "nodes" else 1
    pos, edges = layout.positions, layout.edges
    n = pos.shape[0]
    anchored_as = ""
    a = net["anchored"]
    key = "net.anchored"
    if isinstance(a, str):
        if a not in layout.sets:
            have = ", ".join(sorted(layout.sets)) or "none: list the node indices"
            v.report_at(key, f"{a!r} ({ANCHOR_SETS[a]}) does not name nodes of a {kind} net (it has: {have})")
            return None
        anchored_as = a
        anchored = np.unique(layout.sets[a]).astype(int)
    else:
        bad = [i for i, k in enumerate(a) if k >= n]
        for i in bad:
            v.report_at(f"{key}[{i}]", f"node {a[i]} does not exist (nodes are 0 to {n - 1})", fallback=key)
        if bad:
            return None
        anchored = np.unique(np.asarray(a, int))
    dropped = 0
    mask = np.zeros(n, dtype=bool)
    mask[anchored] = True
    if anchored_as:
        both = mask[edges].all(axis=1)
        dropped = int(both.sum())
        edges = edges[~both]
    # lengths: no rod of zero length, no two nodes in one place
    d = np.linalg.norm(pos[edges[:, 1]] - pos[edges[:, 0]], axis=1)
    zero = np.flatnonzero(d <= COINCIDE_MM)
    if zero.size:
        i, j = edges[zero[0]]
        where = f"net.edges[{zero[0]}]" if kind == "nodes" else f"net.{kind}"
        v.report_at(where, f"nodes {i} and {j} are in the same place: their rod would have no length")
        return None
    _topology(pos, edges, mask, kind, v)
    bends = _bends(net, edges.shape[0], v)
    if not v.ok("net"):
        return None
    return NetTarget(kind=kind, positions=pos, edges=edges, anchored=anchored, anchored_as=anchored_as,
                     dropped=dropped, compression=net.get("compression"), shape=layout.shape,
                     written=dict(net), rod_bends=bends, surface=layout.surface, refine_edges=split_edges)


def _refine_count(net: dict, layout: NetLayout) -> int:
    """``net.refine``, or the refinement whose edges come nearest ``net.edge_length`` (the larger)."""
    n = int(net.get("refine", 1))
    if "edge_length" in net and layout.edges.shape[0]:
        d = np.linalg.norm(layout.positions[layout.edges[:, 1]] - layout.positions[layout.edges[:, 0]], axis=1)
        n = max(n, int(round(float(d.mean()) / float(net["edge_length"]))))
    return max(n, 1)


def _refined(net: dict, kind: str, n: int, base: Path, v: Any) -> NetLayout | None:
    """The net generated (or subdivided) ``n`` times finer (``net.refine``)."""
    key = "net.refine" if "refine" in net else "net.edge_length"
    if kind == "surface":
        s = dict(net["surface"])
        s["u"], s["v"] = int(s["u"]) * n, int(s["v"]) * n
        if max(s["u"], s["v"]) > MAX_CELLS:
            v.report_at(key, f"refined {n} x the grid has {s['u']} x {s['v']} cells; at most {MAX_CELLS} a side")
            return None
        return _surface(s, v)
    if kind == "radial":
        r = dict(net["radial"])
        rad = r["radius"]
        inner = 0.0 if len(rad) == 1 else min(rad)
        rings, spokes = int(r["rings"]), int(r["spokes"])
        r["rings"] = rings * n if inner == 0 else (rings - 1) * n + 1
        r["spokes"] = spokes * n if r.get("sweep_deg", 360.0) >= 360 - 1e-9 else (spokes - 1) * n + 1
        if r["rings"] > MAX_CELLS or r["spokes"] > 360:
            v.report_at(key, f"refined {n} x the net has {r['rings']} rings of {r['spokes']} spokes; at most "
                        f"{MAX_CELLS} rings and 360 spokes")
            return None
        return _radial(r, v)
    if kind == "mesh":
        return _mesh(net["mesh"], base, v, n)
    return _explicit(net, v)  # (its edges are cut into rods in line by the planner: NetTarget.refine_edges)


def _bends(net: dict, m: int, v: Any) -> np.ndarray | None:
    """Each rod's bend from ``net.bend`` (every rod) and ``net.bends`` (listed rods, later
    entries over earlier ones); rods named that do not exist are reported at their key."""
    if "bend" not in net and "bends" not in net:
        return None
    out = np.full(m, float(net.get("bend", 0.0)))
    for i, entry in enumerate(net.get("bends", [])):
        for j, e in enumerate(entry["rods"]):
            if e >= m:
                v.report_at(f"net.bends[{i}].rods[{j}]", f"rod {e} does not exist (the net's rods are 0 to {m - 1}, "
                            "numbered as design.json's net.rods)", fallback="net.bends")
            else:
                out[e] = float(entry["bend"])
    return out if np.any(out > 0) else None


def _topology(pos: np.ndarray, edges: np.ndarray, mask: np.ndarray, kind: str, v: Any) -> None:
    """Report free nodes without rods and parts of the net that hang from no anchored node."""
    n = pos.shape[0]
    where = "net.nodes" if kind == "nodes" else f"net.{kind}"
    if edges.shape[0] == 0:
        v.report_at("net.anchored", "every rod joins two anchored nodes: nothing is left to hang")
        return
    if not mask.any():  # pragma: no cover - the schema asks for at least one index
        v.report_at("net.anchored", "anchor at least one node")
        return
    deg = np.bincount(edges.ravel(), minlength=n)
    lonely = np.flatnonzero((deg == 0) & ~mask)
    if lonely.size:
        v.report_at(where, f"node(s) {lonely[:8].tolist()} have no rod and are not anchored")
        return
    free_edges = ~mask[edges].all(axis=1)
    e = edges[free_edges]
    adj = sp.coo_matrix((np.ones(e.shape[0]), (e[:, 0], e[:, 1])), shape=(n, n))
    _, label = connected_components(adj, directed=False)
    held = np.zeros(label.max() + 1, dtype=bool)
    held[label[mask]] = True
    fall = np.flatnonzero(~held[label] & ~mask)
    if fall.size:
        v.report_at("net.anchored", f"node(s) {fall[:8].tolist()} hang from no anchored node: that part of the "
                    "net would fall (anchor one of its nodes or join it to the rest)")
