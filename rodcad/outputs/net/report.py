"""report.md and the terminal summary of a designed net."""

from __future__ import annotations

from collections import deque
from pathlib import Path
from typing import Any

import numpy as np

from rodcad.design.net.collapse import kept_larger
from rodcad.outputs.view import view_line

__all__ = ["assembly_layers", "net_report", "net_summary", "planner_summary"]


def assembly_layers(edges: np.ndarray, anchored: np.ndarray, n: int) -> list[tuple[list[int], list[int]]]:
    """The order to hang a net: (nodes, rods) per layer, breadth first from the anchored
    nodes. Layer 0 holds the anchored nodes (and the rods between them); layer k the nodes
    k rods away from an anchor and the rods that reach them from layer k - 1 or join them."""
    adj: list[list[tuple[int, int]]] = [[] for _ in range(n)]
    for e, (i, j) in enumerate(edges):
        adj[int(i)].append((int(j), e))
        adj[int(j)].append((int(i), e))
    layer = np.full(n, -1)
    q = deque()
    for a in anchored:
        layer[int(a)] = 0
        q.append(int(a))
    while q:
        i = q.popleft()
        for j, _ in adj[i]:
            if layer[j] < 0:
                layer[j] = layer[i] + 1
                q.append(j)
    out = []
    rod_layer = np.maximum(layer[edges[:, 0]], layer[edges[:, 1]])
    for k in range(int(layer.max()) + 1):
        out.append(([int(x) for x in np.flatnonzero(layer == k)], [int(x) for x in np.flatnonzero(rod_layer == k)]))
    return out


def _list(xs: list[int], most: int = 24) -> str:
    s = ", ".join(map(str, xs[:most]))
    return s + (f", ... ({len(xs)} in all)" if len(xs) > most else "")


def _planner_lines(plan, data: dict[str, Any]) -> list[str]:
    """What the planner changed in the drawn net, in words (empty when nothing)."""
    pl = data.get("planner") or {}
    out = []
    if pl.get("split_edges"):
        out.append(f"- {len(pl['split_edges'])} drawn edge(s) longer than the longest rod "
                   f"({plan.length_range[1]:g} mm) are rods in line joined by {len(pl['joints'])} two-rod ball "
                   "joints (a hub with two sockets; nodes flagged 'joint' in design.json), each placed where it "
                   "hangs and counted in the fit against the drawn surface or edge.")
    if pl.get("merged_nodes"):
        out.append(f"- {len(pl['merged_nodes'])} group(s) of drawn nodes too close for any hub were merged into one "
                   f"hub: {pl['merged_nodes'][:6]}; the fit counts each drawn node.")
    spread = pl.get("spread_nodes") or []
    if spread:
        worst = max(spread, key=lambda x: x["moved_mm"])
        out.append(f"- {len(spread)} drawn node(s) moved a little so that the family's largest hub holds rods drawn "
                   "to meet closer than its sockets allow, or so that a rod drawn too short between its hubs reaches "
                   f"the shortest printed: nodes {_list([x['node'] for x in spread], 12)}, up to "
                   f"{worst['moved_mm']:.3g} mm (node {worst['node']}); the fit measures each against where it was "
                   "drawn.")
    col = pl.get("collapsed_edges") or []
    if col:
        would, _ = kept_larger(plan)
        drawn = sum(len(c["drawn_nodes"]) for c in col)
        worst = max(col, key=lambda c: c["moved_mm"])
        out.append(f"- {drawn} drawn nodes joined by edges shorter than the shortest rod between the smallest hubs "
                   f"(or whose rods met tighter than the largest hub allows) are {len(col)} hub(s), "
                   f"{sum(c['into_anchor'] for c in col)} of them an anchor that kept its place: "
                   + "; ".join(f"nodes {c['drawn_nodes']} -> node {c['node']}" for c in col[:6])
                   + (f"; ... ({len(col)} in all)" if len(col) > 6 else "")
                   + f". Each hub is on the drawn surface or edges (at an anchor, the anchor), and the fit measures "
                   f"it against that point; a drawn node is up to {worst['moved_mm']:.3g} mm from the hub that "
                   f"replaces it (drawn nodes {worst['drawn_nodes']}). Rods that came to join the same two nodes "
                   "are one rod." + (f" The net drawn larger keeps those nodes{would}." if would else ""))
    if pl.get("added_anchors"):
        add = pl["added_anchors"]
        out.append(f"- {len(add)} anchor point(s) added, each midway between two drawn anchors (on a generated net's "
                   "surface): two rods from one hub to two anchors met tighter than the largest hub allows, and are "
                   "one rod to the point between them: "
                   + "; ".join(f"node {a['node']} between anchors {a['between_drawn_anchors']}" for a in add[:6])
                   + ". The frame holds the net there too.")
    if pl.get("spliced_rods"):
        sp = pl["spliced_rods"]
        out.append(f"- {len(sp)} drawn edge(s) whose two-rod joints could not hang on the target (the planner's "
                   "choices above say why), and longer than one rod between the family's largest hubs, are each one "
                   "rigid rod spliced from printed pieces "
                   "on steel dowel pins (rods " + ", ".join(f"{s['rod']} in {s['pieces']}" for s in sp[:8])
                   + (", ..." if len(sp) > 8 else "") + " pieces).")
    if pl.get("rods_between_anchors_left_out"):
        out.append(f"- {pl['rods_between_anchors_left_out']} rod(s) that would have joined two anchors are left out "
                   "(the anchors hold both ends).")
    sizes = pl.get("hub_pivot_radii") or []
    if len(sizes) > 1:
        out.append(f"- Hubs of {len(sizes)} sizes from the catalog's family (pivot radius "
                   f"{', '.join(f'{x:g}' for x in sizes)} mm): larger where rods meet at tight angles, smaller "
                   "where a rod would be too short and at the two-rod joints.")
    return ["The planner made the drawn net buildable:", ""] + out + [""] if out else []


def net_report(check, data: dict[str, Any], *, title: str) -> str:
    """report.md of a designed net."""
    plan, eq = check.plan, check.equilibrium
    t, hw = plan.target, plan.hardware
    net = data["net"]
    bom = data["bill_of_materials"]
    lines = [f"# {title}", ""]
    verdict = "meets" if check.ok else "misses"
    fit = (f"the simulated net hangs **{check.error_mm:.3g} mm** ({100 * check.rel_size:.3g} % of its {t.size:.4g} mm "
           f"size) from its target at worst (tolerance {100 * check.tolerance:.3g} %)." if check.ok else
           f"the simulated net {check.limit()}.")
    held = (f"{t.hung_from.size} anchored, {t.glued.size} held by glued rods" if t.glued is not None
            else f"{t.anchored.size} anchored")
    lines += [f"A net of {t.m} rods and {t.n} nodes ({held}), generated from "
              f"'{t.kind}'. It {verdict} its tolerance: {fit}", "",
              "![from above and from the side](preview.png)", "", view_line(), "", "## Fit and equilibrium", ""]
    lines += [f"- Statics at the target: {check.design.statics.message}",
              f"- Exact equilibrium of the designed net from the target: "
              f"{'stable' if eq.stable else 'NOT stable'}, KKT residual {eq.kkt_residual:.2g}; {eq.message}",
              f"- Largest distance of a node from its target {float(np.max(check.node_error)):.3g} mm, of a rod's pivot "
              f"(its centreline's end) {check.error_mm:.3g} mm; mean node {float(np.mean(check.node_error)):.3g} mm.",
              f"- Multi-start: {eq.n_starts} starts, {len(eq.alternatives)} other stable shape(s)"
              + (" (one lower than the design's)." if eq.lower else "."),
              f"- Rods slack (force within 0.1 % of the largest tension): "
              f"{_list([int(x) for x in check.slack]) if check.slack.size else 'none'}.",
              f"- Rods in compression: {check.compressed.size}"
              + ("" if not check.compressed.size else f" ({_list([int(x) for x in check.compressed])})"
                 + (" (allowed)" if t.compression else " (not allowed)" if t.compression is False or check.unheld.size
                    else " (held: rigid rods between hubs, under a fifth of their buckling load)")) + ".",
              f"- Design time {check.time_s:.2f} s."]
    for note in check.notes[1:]:
        lines.append(f"- {note}")
    lines += ["", "## Node hardware", ""]
    lines += _planner_lines(plan, data)
    if hw.is_hub:
        lines += [f"Every node is a printed hub ({hw.name}): a {hw.diameter:g} mm sphere with one ball socket per rod, "
                  f"its pivot {hw.pivot_radius:g} mm from the hub's centre along the rod's target direction. Each rod "
                  f"ends in a {hw.ball:g} mm ball on a {hw.neck:g} mm neck; the sockets are {hw.clearance:g} mm wider "
                  f"and open in a {hw.cone_deg:g} deg cone, so a rod turns {hw.swing_deg:.3g} deg from its socket's "
                  f"axis in every direction"
                  + (f" ({_wide(plan)} hub(s) open wider, up to {float(plan.node_cone.max()):.3g} deg, where their rods "
                     "turn further)" if _wide(plan) else "")
                  + f" (the designed net uses at most {float(np.max(check.swing_deg)):.3g} deg"
                  + (f"; a bent rod's tilted end face lets it turn {float(plan.swing_limits.min()):.3g} deg at least"
                     if plan.bent else "") + "). "
                  "Rods at a node must meet at "
                  f"{hw.min_angle_deg:.3g} deg or more (at the nominal hub), and a hub's sockets, turned to balance it, "
                  f"keep {hw.min_wall:g} mm of wall between every two of them. The hubs are rigid bodies whose pose the solver found; their "
                  f"masses ({float(plan.node_masses.min()):.3g}-{float(plan.node_masses.max()):.3g} g) and centres of "
                  "mass count.", "",
                  f"Free play: each socket is printed {hw.clearance / 2:g} mm back from its pivot against the "
                  "rod's pull at the design (design.json: nodes[].sockets), so the loaded balls sit on the designed "
                  f"pivots exactly; a rod without load rattles by up to {hw.clearance / 2:g} mm.", ""]
    else:
        lines += [f"Every node is one pivot point ({hw.name}, {hw.mass:g} g): the rods turn about it.", ""]
    bent = any(r.get("shape") == "bent" for r in net["rods"])
    what = ("Round rods printed to order, bent where 'bow' is not 0 (bow: the sagitta over the chord of the body's arc; each "
            "hangs below its chord in the vertical plane through it, its centre of mass 'below' mm off the chord)"
            if bent else "Straight round rods printed to order")
    spliced = [r for r in net["rods"] if r.get("splice")]
    lines += ["## Rods", "",
              f"{what} ({hw.rod_diameter:g} mm), lengths pivot to pivot, tension in mN (g x m/s^2; > 0 pulls)"
              + ("; a glued rod holds its hubs rigidly (its force is the band's, not a pull)." if t.glued is not None
                 else "."), ""]
    if spliced:
        pin = spliced[0]["splice"]["pin"]
        lines += [f"{len(spliced)} rod(s) longer than the catalog prints are spliced: each is printed in the 'pieces' "
                  "shown, cut square to its axis at equal shares of its length, and is one rigid rod once a steel "
                  f"dowel pin ({pin['diameter']:g} x {pin['length']:g} mm) is glued into the "
                  f"{pin['hole_diameter']:g} mm bores ({pin['hole_depth']:g} mm deep) of each cut's two faces; its "
                  "mass counts its pins, its pieces are filled alike so its centre of mass stays at mid-length.", ""]
    lines += ["| rod | nodes | length (mm) | mass (g) | range (g) | steel balls | tension (mN) |"
              + (" bow | below (mm) |" if bent else "") + (" pieces |" if spliced else ""),
              "|---:|---|---:|---:|---|---:|---:|" + ("---:|---:|" if bent else "") + ("---:|" if spliced else "")]
    for r in net["rods"]:
        extra = ""
        if bent:
            b = r.get("bend")
            extra = f" {b['bend']:.3g} | {r['com'][1]:.3f} |" if b else " 0 | 0 |"
        if spliced:
            extra += f" {r.get('pieces', 1)} |"
        lines.append(f"| {r['index']} | {r['nodes'][0]}-{r['nodes'][1]} | {r['length']:.2f} | {r['mass']:.3f} | "
                     f"{r['mass_range'][0]:.2f}-{r['mass_range'][1]:.2f} | {r['steel_balls']} | "
                     + ("glued |" if r.get("glued") else f"{r['tension']:.3g} |") + extra)
    lines += ["", "## Nodes", "", "| node | anchored | rods | mass (g) | error (mm) |", "|---:|---|---:|---:|---:|"]
    for nd in net["nodes"]:
        err = nd["error_mm"]
        mark = "glued" if nd.get("glued") else "yes" if nd["anchored"] else ""
        lines.append(f"| {nd['index']} | {mark} | {nd['rods']} | {nd['mass']:.3f} | "
                     f"{err:.3g} |" if err is not None else f"| {nd['index']} | | {nd['rods']} | {nd['mass']:.3f} | - |")
    lines += ["", "## Bill of materials", ""]
    lines.append(f"- {bom['rods']} rods ({bom['rod_plastic_g']:.1f} g of {bom['material']})")
    if "hubs" in bom:
        lines.append(f"- {bom['hubs']} printed hubs ({bom['hub_plastic_g']:.1f} g of {bom['material']}), each in two "
                     "halves glued together over its rods' balls (a glue for the material, e.g. cyanoacrylate)"
                     + (f", {bom['two_rod_joints']} of them two-rod ball joints on long edges"
                        if bom.get("two_rod_joints") else "") + ": "
                     + ", ".join(f"{c} x {k}" for k, c in bom.get("hub_sizes", {}).items()))
    else:
        lines.append(f"- {bom['point_parts']} x {bom['point_part']}")
    if bom.get("glued_rods"):
        lines.append(f"- glue for the {bom['glued_rods']} glued rods' {2 * bom['glued_rods']} balls in their sockets "
                     "(the hubs' glue)")
    if bom.get("dowel_pins"):
        pin = bom["dowel_pin"]
        lines.append(f"- {bom['dowel_pins']} steel dowel pins, {pin['diameter']:g} x {pin['length']:g} mm (e.g. ISO "
                     f"8734), glued into the bores of the {bom['spliced_rods']} spliced rods' pieces "
                     f"({bom['rod_pieces']} printed rod pieces in all)")
    if bom["steel_balls"]:
        lines.append(f"- {bom['steel_balls']} steel balls, {bom['steel_ball']['diameter']:g} mm (inserted at a "
                     "print pause)")
    lines.append(f"- filament: {bom['filament_g']:.1f} g in all")
    if bom.get("parts"):  # with CAD: each distinct part once, with how many to print
        lines += ["", f"{len(bom['parts'])} distinct parts to print (equal rods and hubs are one file, printed once "
                  "per rod or hub; print.3mf places every copy):", ""]
        lines += [f"- {p['count']} x {p['name']} ({p['plastic_g']:.2f} g each)" for p in bom["parts"]]
    lines += ["", "## Assembly order", ""]
    if hw.is_hub:
        lines += ["Each hub prints as two halves (hub-NNN-a and -b) cut through its sockets' centres; a socket's "
                  "mouth is narrower than a rod's ball, so the balls go in before the hub is closed. For each hub: lay "
                  "the end ball of each of its rods in its socket in either half (open at the cut, wider than the "
                  "ball), the rod's neck in the half cone; when all its rods are in, put the other half on, the "
                  "sockets aligned, and glue the flat faces (or clamp them with a band until the glue sets). Its "
                  "balls then turn freely in closed sockets.", ""]
        wider = (data.get("cad") or {}).get("hubs_wider_sockets") or {}
        if wider:
            lines.append(f"- {len(wider)} hub(s) have wider sockets ({', '.join(f'{h} {c:g} mm' for h, c in wider.items())}"
                         " socket diameter less ball diameter): their sockets lie too far off one plane for a cut "
                         "at the catalog's clearance to admit the balls. Loaded, each ball sits on its pivot (the "
                         "socket is printed back against its rod's pull); slack, it rattles more.")
        whole = (data.get("cad") or {}).get("hubs_not_split") or {}
        for hub, why in whole.items():
            lines.append(f"- {hub} is printed whole ({why}): its balls cannot be put in; move its rods or its node.")
        if whole or wider:
            lines.append("")
    lines += ["Hang the anchored hubs first, then work outward layer by layer, closing each hub on its rods "
              "(rod numbers are in design.json and on the rods' files).", ""]
    for k, (nodes, rods) in enumerate(assembly_layers(t.edges, t.anchored, t.n)):
        if k == 0 and t.glued is not None:
            glued = set(int(x) for x in t.glued)
            lines.append(f"{k + 1}. Anchored nodes {_list([x for x in nodes if x not in glued])} at their anchors, "
                         f"and the band of nodes {_list(sorted(glued))} held by glued rods "
                         f"{_list([int(x) for x in t.glued_rods])}: put a drop of glue in each of those rods' "
                         "sockets before its ball goes in, close those hubs, and let the glue set with the band "
                         "on its anchors and each of its hubs held at its target (design.json's nodes[].target; "
                         "a band of triangles holds itself there) before hanging the rest: the band is then "
                         "rigid and holds its hubs where drawn" + (f"; rods {_list(rods)} join held nodes." if rods else "."))
        elif k == 0:
            lines.append(f"{k + 1}. Anchored nodes {_list(nodes)} at their anchors"
                         + (f", with rods {_list(rods)} between them." if rods else "."))
        else:
            lines.append(f"{k + 1}. Nodes {_list(nodes)} on rods {_list(rods)}.")
    if "as_built" in data:
        ab, cad = data["as_built"], data["cad"]
        lines += ["", "## As built", "",
                  f"{cad['rods']} rods and {cad['hubs']} hubs in {len(cad['hub_parts'])} parts (each hub's two "
                  f"halves), {len(cad.get('parts', []))} of them distinct: each distinct part written once "
                  "(rods/rod-NNN.step, .stl; hubs/hub-NNN-a.step, .stl and -b; named after its first rod or hub), "
                  "each checked (the STEP re-imports as one valid solid of its volume, the STL is watertight); "
                  "assembly.step holds every part where the net hangs, an instance of its distinct part named "
                  "after its own rod or hub, rods coloured by mass. "
                  + (("With the solids' own masses and centres of mass the net hangs "
                      f"**{ab['error']['max_mm']:.3g} mm** ({100 * ab['error']['max_rel_size']:.3g} % of its size) "
                      f"from the design ({'stable' if ab['stable'] else 'NOT stable'})"
                      + ("." if ab.get("converged", True) else
                         f"; the solver stopped at KKT residual {ab['kkt_residual']:.2g}, short of round-off, and "
                         "the error is read where it stopped."))
                     if ab["error"]["max_mm"] is not None else
                     "With the solids' own masses and centres of mass rodcad's solver found no equilibrium "
                     f"(it stopped at KKT residual {ab['kkt_residual']}): rodcad's failure, not the design's."), ""]
        lines += _print_section(data)
    else:
        lines += ["", "## Not built", "",
                  "Designed without the solids (--no-cad): `rodcad build` without it writes rods/, hubs/ and "
                  "assembly.step.", ""]
    return "\n".join(lines)


def _print_section(data: dict[str, Any]) -> list[str]:
    """## Printing: the PrusaSlicer projects and how each part prints."""
    files = data["cad"]["files"]
    plates = [f for f in files if f.startswith("print") and f.endswith(".3mf")]
    pr = data.get("print", {})
    return ["## Printing", "",
            f"{', '.join(plates)}: every rod and hub part on the printer's bed ({len(plates)} plate"
            f"{'s' if len(plates) != 1 else ''}, split by the bed only; each distinct part one object placed once per copy); rods/rod-NNN.3mf "
            f"and hubs/<part>.3mf: each distinct part alone. PrusaSlicer projects with the print profile every mass assumes ({pr.get('material', '')}, "
            f"{100 * pr.get('infill', 1.0):g} % infill, {pr.get('layer_height', '')} mm layers, "
            f"{pr.get('perimeters', '')} perimeters).",
            "",
            "- Rods print lying along the bed on their round body, with support from the bed under the body and "
            "the end balls (support is not part of a rod's mass: snap it off).",
            "- Steel balls: the print pauses (M601) before the layer at the height of the rods' axes, its message "
            "naming the rods and how many balls each takes. The sockets are then open about as wide as they are "
            "round: drop each ball in (it stands about 3 mm proud of the print), check that it sits at the bottom of "
            "its socket, and resume; the top half of each socket prints around and over its ball, the nozzle "
            "passing close to it in the first layers: watch them.",
            "- Hub halves print on their flat cut faces, without support (the half sockets and cones are small "
            "domes over the bed)"
            + ("; the hubs left whole print on support." if data["cad"].get("hubs_not_split") else "."), ""]


def net_summary(check, outdir: Path) -> str:
    """The terminal summary of a net build."""
    eq = check.equilibrium
    t = check.plan.target
    st = check.design.statics
    if st.exact:
        masses = "masses exact from the statics"
    elif check.design.refined:
        masses = f"masses: the statics' best fit (residual {st.residual:.2g}), refined through the solver"
    else:
        masses = f"masses: the statics' best fit (residual {st.residual:.2g})"
    return (f"{t.n} nodes, {t.m} rods: hangs {check.error_mm:.3g} mm ({100 * check.rel_size:.3g} % of its size) "
            f"from its target, {'stable' if eq.stable else 'not stable'}, KKT residual {eq.kkt_residual:.2g}, "
            f"{len(eq.alternatives)} other stable shape(s) in {eq.n_starts} starts; {masses}\n"
            + planner_summary(check.plan)
            + f"wrote {outdir}/design.json, report.md, preview.png, view.html, assembly.glb"
            + (", rods/, hubs/, assembly.step, print.3mf" if (outdir / "assembly.step").exists() else ""))


def planner_summary(plan) -> str:
    """One line (with its newline) when the planner changed the drawn net's nodes or edges:
    drawn and built counts, and how far a collapse moved a drawn node; else empty."""
    t = plan.target
    drawn = t.drawn if t.drawn is not None else t
    collapsed, added = list(plan.collapsed), list(plan.added_anchors)
    split = len(t.joints) if t.joints is not None else 0
    k = plan.rod_pieces
    spliced = int(np.count_nonzero(k > 1))
    spread = list(plan.spread)
    if not (collapsed or added or split or plan.merged or plan.between_anchors or spliced or spread):
        return ""
    what = []
    if collapsed:
        worst = max(c.moved_mm for c in collapsed)
        would, _ = kept_larger(plan)
        what.append(f"{sum(len(c.drawn) for c in collapsed)} drawn nodes collapsed into {len(collapsed)} hub(s), a "
                    f"drawn node moved up to {worst:.3g} mm ({100 * worst / t.size:.3g} % of its size)"
                    + (f", kept if drawn larger{would}" if would else ""))
    if plan.merged:
        what.append(f"{len(plan.merged)} group(s) of nearly coincident nodes merged")
    if spread:
        worst = max(mm for _, mm in spread)
        what.append(f"{len(spread)} node(s) moved up to {worst:.3g} mm ({100 * worst / t.size:.3g} % of its size) so "
                    "that the largest hub holds rods drawn to meet too close, or a rod drawn too short reaches "
                    "the shortest printed")
    if split:
        what.append(f"{split} two-rod joint(s) on long edges")
    if spliced:
        what.append(f"{spliced} long rod(s) spliced from {int(k[k > 1].sum())} printed pieces")
    if added:
        what.append(f"{len(added)} anchor point(s) added")
    if plan.between_anchors:
        what.append(f"{plan.between_anchors} rod(s) between anchors left out")
    return f"planner: drawn {drawn.n} nodes, {drawn.m} edges; built {t.n} nodes, {t.m} rods: {'; '.join(what)} (report.md)\n"


def _wide(plan) -> int:
    """How many hubs have sockets' cones wider than the catalog's nominal."""
    if plan.node_cone is None:
        return 0
    return int(np.count_nonzero(plan.node_cone > plan.hardware.cone_deg + 1e-9))
