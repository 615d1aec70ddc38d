"""What the 3D view of a net shows (:mod:`rodcad.outputs.viewscene` for chains and chandeliers):
every rod (``rod-NNN``), every hub (``hub-NNN``; a built hub's halves ``hub-NNN-a`` / ``-b``) or
point node (``node-NNN``), and a dark hanger above each anchored node (``anchor-NNN``), where the
net hangs: simulated, or as built from the solids' masses when CAD was built.

Without CAD a straight rod is one cylinder of the rod's diameter from pivot to pivot (a unit
cylinder scaled by its node, so rods of one colour share one mesh however many there are), a
bent rod a tube along its arc (:mod:`rodcad.catalog.netbend`) and a hub a sphere of the hub's
diameter. The net's frame is z up; the glb turns it to glTF's y up.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rodcad.design.net.frames import rod_matrix
from rodcad.outputs.viewgeom import Y_UP, ViewPart, ViewScene, cylinder, sphere, tube, unit_cylinder
from rodcad.outputs.viewscene import ANCHOR, GREY, cad_parts, legend, mass_scale, mm, pct, step_colors

__all__ = ["VIEW_TRIANGLES", "net_scene"]


def _bent_line(arc, segments: int = 10) -> np.ndarray:
    """A bent rod's centreline in its frame: the necks along the chord, the body on its arc."""
    x = np.linspace(arc.offset, arc.length - arc.offset, segments + 1)
    return np.vstack([[0.0, 0.0, 0.0], arc.point(x), [arc.length, 0.0, 0.0]])


def _pose(b, data: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, bool]:
    """(node positions (n, 3), rod pivots (m, 2, 3), node rotations or None, as built?)."""
    s = b.solids
    if s is not None and s.as_built is not None:
        ab = s.as_built
        pos, ends = np.asarray(ab.positions, float), np.asarray(ab.ends, float)
        if np.all(np.isfinite(pos)) and np.all(np.isfinite(ends)):
            rot = getattr(ab, "rotations", None)
            return pos, ends, None if rot is None else np.asarray(rot, float), True
    net = data["net"]
    pos = np.array([nd["simulated"] for nd in net["nodes"]], float)
    ends = np.array([r["ends"] for r in net["rods"]], float)
    rot = [nd.get("rotation") for nd in net["nodes"]]
    return pos, ends, None if any(r is None for r in rot) else np.array(rot, float), False


def net_scene(b, data: dict[str, Any]) -> ViewScene:
    """The view of a net (:class:`rodcad.pipeline.net.NetBuild` and its design.json)."""
    net = data["net"]
    hw = data.get("hardware") or {}
    rods, nodes = net["rods"], net["nodes"]
    masses = [r["mass"] for r in rods]
    scale = mass_scale(masses)
    colors, steps = step_colors(masses, scale)
    pos, ends, rot, built = _pose(b, data)
    hub = hw.get("kind") == "hub"
    rod_d = float(hw.get("rod_diameter") or rods[0].get("diameter") or 6.0)
    node_d = float(hw.get("diameter") or 0.0) if hub else 1.4 * rod_d
    parts: list[ViewPart] = []
    simple_hubs = b.solids is None
    if b.solids is not None:
        cad, simple_hubs = _net_cad(b, pos, ends, rot, colors)
        parts += cad
    else:
        arcs = b.check.plan.arcs
        unit = unit_cylinder(rod_d / 2, 12)
        for e, (r, color, step) in enumerate(zip(rods, colors, steps)):
            p0, p1 = ends[e]
            m = rod_matrix(p0, p1)  # (as assembly.step places the rod)
            if arcs[e] is None:
                m = m @ np.diag([float(np.linalg.norm(p1 - p0)), 1.0, 1.0, 1.0])
                parts.append(ViewPart(f"rod-{e:03d}", "rods", f"rod:{step}", unit, m, color))
            else:
                a = arcs[e]
                parts.append(ViewPart(f"rod-{e:03d}", "rods", f"bent:{a.length:.3f}:{a.bend:.5f}:{step}",
                                      tube(_bent_line(a), rod_d / 2, 12), m, color))
    if simple_hubs:
        balls: dict[float, Any] = {}
        for k, nd in enumerate(nodes):
            if hub and not nd.get("rods", 1):
                continue  # an anchor no rod reaches: no hub is printed
            d = float((nd.get("hub") or {}).get("diameter") or node_d)  # (its own size of the hub family)
            if d not in balls:
                balls[d] = sphere(d / 2, 8, 14)
            m = np.eye(4)
            m[:3, 3] = pos[k]
            parts.append(ViewPart(f"hub-{k:03d}" if hub else f"node-{k:03d}", "hubs", f"hub:{d:g}" if d != node_d
                                  else "hub", balls[d], m, GREY))
    hanger = cylinder([0, 0, 0.4 * node_d], [0, 0, 0.4 * node_d + 1.2 * max(node_d, 10.0)], max(0.1 * node_d, 1.2), 10)
    for k, nd in enumerate(nodes):
        # (an anchor no rod reaches holds nothing; a node glued rods hold hangs on no frame)
        if nd.get("anchored") and nd.get("rods", 1) and not nd.get("glued"):
            m = np.eye(4)
            m[:3, 3] = pos[k]
            parts.append(ViewPart(f"anchor-{k:03d}", "anchors", "anchor", hanger, m, ANCHOR))
    err = net.get("error") or {}
    glued = sum(bool(nd.get("glued")) for nd in nodes)
    held = sum(bool(nd.get("anchored")) for nd in nodes) - glued
    summary = [["nodes", f"{len(nodes)} ({held} anchored" + (f", {glued} held by glued rods)" if glued else ")")],
               ["rods", str(len(rods))], ["size", mm(net.get("size"))],
               ["off its target", f"{mm(err.get('max_mm'))} ({pct(err.get('max_rel_size'))} of its size)"],
               ["tolerance", f"{pct(net.get('tolerance'))}: {'met' if net.get('meets_tolerance') else 'MISSED'}"],
               ["equilibrium", f"{'stable' if net.get('stable') else 'NOT stable'}, KKT residual "
                               f"{float(net.get('kkt_residual') or 0):.2g}"
                               + ("" if net.get("falls_to_rel_size") is None else
                                  f"; it falls to a stable shape {pct(net['falls_to_rel_size'])} of its size off")]]
    ab = data.get("as_built")
    if ab:
        summary.append(["as built (the solids' masses)", f"{mm(ab['error'].get('max_mm'))} "
                                                         f"({pct(ab['error'].get('max_rel_size'))})"])
    if hub:  # (each node's own size of the hub family)
        sizes = sorted({round(float((nd.get("hub") or {}).get("diameter") or node_d), 2) for nd in nodes
                        if nd.get("rods", 1)})
        span = (f"{sizes[0]:g} mm" if len(sizes) == 1 else
                f"{sizes[0]:g}-{sizes[-1]:g} mm ({len(sizes)} sizes)")
        summary.append(["hubs", f"{span} printed spheres with ball sockets"])
    bom = data.get("bill_of_materials") or {}
    total = sum(masses) + sum(float(nd.get("mass") or 0.0) for nd in nodes)
    summary.append(["net mass", f"{total:.1f} g" + (f"; filament {bom['filament_g']:.1f} g" if "filament_g" in bom
                                                     else "")])
    force = (data.get("units") or {}).get("force", "mN")
    half: dict[int, list[str]] = {k: [] for k in range(len(nodes))}  # a node's hub (or its halves)
    for p in parts:
        if p.group == "hubs":
            half[int(p.name.split("-")[1])].append(p.name)
    tables = [{"id": "rods", "title": "Rods", "columns": [
        {"label": "#"}, {"label": "nodes"}, {"label": "length mm", "digits": 2}, {"label": "mass g", "digits": 3},
        {"label": f"tension {force}", "digits": 1}, {"label": "shape"}],
        # (a glued rod holds its hubs rigidly: it carries more than a pull, none of it computed)
        "rows": [[r["index"], "{}-{}".format(*r["nodes"]), r["length"], r["mass"],
                  None if r.get("glued") else r.get("tension"),
                  (r.get("shape") or "straight") + (f", {r['pieces']} pieces" if (r.get("pieces") or 1) > 1
                                                    else "") + (", glued" if r.get("glued") else "")]
                 for r in rods],
        "parts": [[f"rod-{r['index']:03d}"] for r in rods]},
        {"id": "nodes", "title": "Nodes (hubs)" if hub else "Nodes", "columns": [
            {"label": "#"}, {"label": "anchored"}, {"label": "rods"}, {"label": "mass g", "digits": 3},
            {"label": "off target mm", "digits": 3}],
         "rows": [[nd["index"], "glued" if nd.get("glued") else "yes" if nd.get("anchored") else "", nd.get("rods"),
                   nd.get("mass"),
                   nd.get("error_mm")] for nd in nodes],
         "parts": [half[nd["index"]] + ([f"anchor-{nd['index']:03d}"] if nd.get("anchored") and not nd.get("glued")
                                         else [])
                   for nd in nodes]}]
    shown = "as built (the solids)" if built else ("the solids, where the design hangs" if b.solids is not None
                                                   else "simulated (no CAD: simple shapes)")
    if b.solids is not None and simple_hubs:
        shown += f"; the hubs drawn as spheres (their solids' meshes would pass {VIEW_TRIANGLES:,} triangles)"
    panel = {"title": data["name"], "subtitle": f"net of {len(rods)} rods and {len(nodes)} nodes, {shown}",
             "summary": summary,
             "legend": legend(scale, [(GREY, "hub" if hub else "node"), (ANCHOR, "anchored node")]),
             "tables": tables}
    return ViewScene(data["name"], parts, Y_UP, panel, {"yaw": -35.0, "pitch": 28.0})


#: The most triangles a net's view meshes from its solids (about 10 MB of glb): beyond, its hubs
#: (each one its own solid, where the rods of one length share a mesh) are drawn as spheres.
VIEW_TRIANGLES = 400_000


def _net_cad(b, pos, ends, rot, colors) -> tuple[list[ViewPart], bool]:
    """The net's solids (rods, hub halves) where it hangs, and whether its hubs are left to
    the simple shapes: when meshing them all would pass :data:`VIEW_TRIANGLES` (estimated
    from the first hub's mesh)."""
    from rodcad.cad.viewmesh import ViewMeshes, net_view_nodes

    rods, hubs = net_view_nodes(b.solids, pos, ends, rot)
    named = {p.name: ("rods", c) for p, c in zip(rods, colors)}
    for p in hubs:
        shade = 0.66 if p.name.endswith("-b") else 0.78  # a hub's halves in two greys
        named[p.name] = ("hubs", (shade, shade, shade + 0.03))
    meshes = ViewMeshes()
    parts = meshes.parts(rods)
    rod_tris = sum(len(f) for f in (m[1] for m in meshes.meshes.values()))
    if hubs:
        first = meshes.parts(hubs[:1])
        if rod_tris + len(first[0].faces) * len(hubs) > VIEW_TRIANGLES:
            return cad_parts(parts, named, lambda s: ("hubs", GREY)), True
        parts += first + meshes.parts(hubs[1:])
    return cad_parts(parts, named, lambda s: ("hubs", GREY)), False
