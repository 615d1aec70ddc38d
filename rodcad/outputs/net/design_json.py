"""design.json of a net (contract.md, section "Nets") and its bill of materials.

The contract's fields come first and keep their names; rodcad adds more beside them (each
node's hub mass, socket centres and error, each rod's mass range and steel balls, the
hardware, the statics' verdict, the bill of materials).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from optimize import pivots_by_node
from rodcad.catalog.net.splice import piece_extents, splice_fill

__all__ = ["net_bill", "net_json", "rod_balls"]


def _f(x: float) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def _ints(a) -> list[int]:
    """A list of ints from an index array or None (empty)."""
    return [] if a is None else [int(x) for x in a]


def _v(a) -> list[float | None]:
    return [_f(x) for x in np.asarray(a, float).ravel()]


def _joint_kind(t, k: int) -> str | None:
    """'ball' for a two-rod ball joint the planner put on a long edge, else None."""
    return "ball" if t.joint_mask[k] else None


def planner_json(plan) -> dict[str, Any]:
    """What the planner did to the drawn net (rodcad.design.net.joints, rodcad.design.net.sizing)."""
    t = plan.target
    drawn = t.drawn if t.drawn is not None else t
    src = t.source if t.source is not None else np.arange(t.m)
    split = np.bincount(src, minlength=drawn.m)
    sizes = sorted({round(float(x), 4) for x in plan.node_pivot}) if plan.node_pivot is not None else []
    return {
        "drawn": {"nodes": drawn.n, "edges": drawn.m},
        "split_edges": [{"edge": int(e), "rods": int(split[e]), "joints": "ball"} for e in np.flatnonzero(split > 1)],
        "joints": [int(k) for k in (t.joints if t.joints is not None else [])],
        "merged_nodes": [[int(x) for x in g] for g in plan.merged],
        "spread_nodes": [{"node": int(k), "moved_mm": float(mm)} for k, mm in plan.spread],
        "collapsed_edges": [{"node": c.node, "drawn_nodes": list(c.drawn), "at": list(c.point),
                             "moved_mm": c.moved_mm, "into_anchor": c.anchored} for c in plan.collapsed],
        "rods_between_anchors_left_out": int(plan.between_anchors),
        "added_anchors": [{"node": k, "between_drawn_anchors": list(pair)} for k, pair in plan.added_anchors],
        "spliced_rods": [{"rod": int(e), "edge": int(src[e]), "pieces": int(plan.rod_pieces[e])}
                         for e in np.flatnonzero(plan.rod_pieces > 1)],
        "rod_edge": [int(x) for x in src],
        "hub_pivot_radii": sizes,
    }


def rod_balls(check) -> np.ndarray:
    """(m,) the steel balls each rod holds at its designed mass (the fewest whose range holds
    it: :meth:`rodcad.catalog.net.node.NodeHardware.rod_fill`)."""
    hw = check.plan.hardware
    plan = check.plan
    return np.array([hw.rod_fill(float(L), float(m), int(k))[0]
                     for L, m, k in zip(plan.fill_lengths, check.masses, plan.rod_pieces)], int)


def _splice(hw, length: float, fills: list[tuple[int, float]]) -> dict[str, Any]:
    """A spliced rod's pieces (:mod:`rodcad.catalog.net.splice`) with their ``fills``: where each
    is cut, its balls and cavity, and the dowel pins."""
    sp = hw.splice
    return {"pieces": [{"from": x0, "to": x1, "steel_balls": int(b), "cavity_mm3": c}
                       for (x0, x1, _, _), (b, c) in zip(piece_extents(hw, length, len(fills)), fills)],
            "dowel_pins": len(fills) - 1, "pin": {"diameter": sp.pin_diameter, "length": sp.pin_length,
                                                  "hole_diameter": 2 * sp.hole_radius, "hole_depth": sp.depth}}


def net_bill(check, catalog) -> dict[str, Any]:
    """What to print and buy: hubs (or point parts), rods (a spliced rod's pieces and dowel pins),
    steel balls, filament (g)."""
    plan, hw = check.plan, check.plan.hardware
    balls = rod_balls(check)
    ball_mass = hw.insert_density * math.pi / 6 * hw.insert_diameter ** 3 / 1000.0
    pins = int(np.sum(plan.rod_pieces - 1))
    rod_plastic = float(np.sum(check.masses - balls * ball_mass) - pins * hw.splice.pin_mass)
    out: dict[str, Any] = {"rods": plan.target.m, "rod_plastic_g": rod_plastic,
                           "steel_balls": int(balls.sum())}
    if balls.sum():
        out["steel_ball"] = {"diameter": hw.insert_diameter, "density": hw.insert_density}
    if pins:
        sp = hw.splice
        out["spliced_rods"] = int(np.count_nonzero(plan.rod_pieces > 1))
        out["rod_pieces"] = int(plan.rod_pieces.sum())
        out["dowel_pins"] = pins
        out["dowel_pin"] = {"diameter": sp.pin_diameter, "length": sp.pin_length, "density": sp.pin_density,
                            "note": "glued into both pieces' holes"}
    if hw.is_hub:
        held = plan.degree > 0  # a node no rod reaches (an anchor between anchors) needs no hub
        out["hubs"] = int(np.count_nonzero(held))
        out["hub_plastic_g"] = float(plan.node_masses[held].sum())
        joint = plan.target.joint_mask & held
        out["two_rod_joints"] = int(np.count_nonzero(joint))
        if plan.target.glued_rods is not None:  # (rodcad.design.net.glued: both balls glued in their sockets)
            out["glued_rods"] = int(plan.target.glued_rods.size)
        sizes: dict[str, int] = {}
        for k in np.flatnonzero(held):
            h = plan.hub(int(k))
            key = f"{h.diameter:.4g} mm (pivot radius {h.pivot_radius:.4g} mm" + (
                f", cones {h.cone_deg:.3g} deg)" if h.cone_deg != hw.cone_deg else ")")
            sizes[key] = sizes.get(key, 0) + 1
        out["hub_sizes"] = sizes
        out["filament_g"] = rod_plastic + float(plan.node_masses.sum())
    else:
        out["point_parts"] = plan.target.n
        out["point_part"] = hw.name
        out["filament_g"] = rod_plastic
    m = next(iter(catalog)).material
    out["material"] = m.name
    return out


def net_json(check, *, name: str, seed: int, catalog, print_profile: dict[str, Any]) -> dict[str, Any]:
    """design.json of a designed net (see the module docstring)."""
    plan, eq = check.plan, check.equilibrium
    t, hw = plan.target, plan.hardware
    per_node = pivots_by_node(t.edges, plan.pivots, t.n) if hw.is_hub else [None] * t.n
    sock = pivots_by_node(t.edges, check.sockets, t.n) if hw.is_hub else [None] * t.n
    mask, glued, glued_rods = t.anchored_mask, t.glued_mask, set(_ints(t.glued_rods))
    nodes = []
    for k in range(t.n):
        nodes.append({
            "index": k,
            "target": _v(t.positions[k]),
            "simulated": _v(eq.positions[k]),
            "anchored": bool(mask[k]),
            "glued": bool(glued[k]),
            "mass": _f(plan.node_masses[k]),
            "pivots": per_node[k],
            "rotation": np.asarray(eq.rotations[k]).tolist() if hw.is_hub else None,
            "sockets": sock[k],
            "com": _v(plan.node_com[k]),
            "rods": int(plan.degree[k]),
            "error_mm": _f(check.node_error[k]),
            "hub": {"diameter": plan.hub(k).diameter, "pivot_radius": plan.hub(k).pivot_radius,
                    "cone_deg": plan.hub(k).cone_deg} if hw.is_hub else None,
            "joint": _joint_kind(t, k),
        })
    rods = []
    # the plan's per-rod arrays are properties computed over every rod: read each once
    arcs = plan.arcs
    fill = plan.fill_lengths
    pieces = plan.rod_pieces
    target_ends = plan.target_ends
    swing_limits = plan.swing_limits if hw.is_hub else None
    com = plan.com if plan.com is not None else plan.rod_com(check.masses)
    for e in range(t.m):
        rn = plan.rods[e]
        L = float(plan.lengths[e])
        Lf = float(fill[e])
        arc = arcs[e]
        mass = float(check.masses[e])
        if pieces[e] > 1:  # (each piece's fill once: the rod's sums and its pieces come from it)
            fills, got = splice_fill(hw, L, mass, int(pieces[e]))
            fill_e = (sum(b for b, _ in fills), sum(c for _, c in fills), got)
        else:
            fills, fill_e = None, hw.rod_fill(Lf, mass)
        rods.append({
            "index": e,
            "nodes": [int(x) for x in t.edges[e]],
            "length": L,
            "mass": _f(check.masses[e]),
            "com": _v(com[e]),
            "tension": _f(eq.tensions[e]),
            "glued": e in glued_rods,
            "ends": [_v(eq.ends[e, 0]), _v(eq.ends[e, 1])],
            "target_ends": [_v(target_ends[e, 0]), _v(target_ends[e, 1])],
            "mass_range": [rn.mass_range[0], rn.mass_range[1]],
            "solid_mass": rn.solid_mass,
            "steel_balls": int(fill_e[0]),
            "cavity_mm3": fill_e[1],
            "buildable_mass": fill_e[2],
            "body_length": rn.body_length,
            "diameter": hw.rod_diameter,
            "shape": "straight" if arc is None else "bent",
            "pieces": int(pieces[e]),
            "splice": None if fills is None else _splice(hw, L, fills),
            "bend": None if arc is None else {"bend": arc.bend, "sagitta": arc.sagitta, "radius": arc.radius,
                                              "half_angle_deg": float(np.degrees(arc.half_angle)),
                                              "plane": "vertical through the chord, bowing down"},
            "swing_limit_deg": _f(swing_limits[e]) if hw.is_hub else None,
            "swing_deg": _v(check.swing_deg[e]),
        })
    st = check.design.statics
    alts = eq.alternatives
    return {
        "name": name,
        "kind": "net",
        "units": {"length": "mm", "mass": "g", "force": "mN", "angle": "deg"},
        "method": st.method,
        "seed": int(seed),
        "time_s": round(float(check.time_s), 3),
        "net": {
            "nodes": nodes,
            "rods": rods,
            "error": {"max_mm": _f(check.error_mm), "max_rel_size": _f(check.rel_size),
                      "mean_node_mm": _f(float(np.mean(check.node_error)))},
            "stable": bool(eq.stable),
            # (an unstable target: how far off it the stable shape lies that the net falls to)
            "falls_to_rel_size": None if check.falls_to is None else _f(check.falls_to),
            "kkt_residual": _f(eq.kkt_residual),
            "success": bool(eq.success),
            "size": t.size,
            "tolerance": check.tolerance,
            "meets_tolerance": bool(check.meets_tolerance),
            "in_tension": bool(check.in_tension),
            "compressed": [int(x) for x in check.compressed],
            "generated": t.kind,
            "anchored": [int(x) for x in t.anchored],
            # the nodes held by rods glued toward the anchors, and those rods (rodcad.design.net.glued): held,
            # and so anchored, but not hung on the frame (hung_from)
            "glued": _ints(t.glued),
            "glued_rods": sorted(glued_rods),
            "hung_from": _ints(t.hung_from),
            "anchored_as": t.anchored_as or None,
            "compression_allowed": t.any_may_push,
            "compression": ("allowed" if t.compression else "not allowed" if t.compression is False or not hw.is_hub
                            else "where the hardware holds it"),
            "pushing_unheld": [int(x) for x in check.unheld],
            # the rods the design let push where no masses balanced the net in tension (rodcad.design.net.pushing)
            "pushing_designed": ([] if check.plan.pushing is None
                                 else [int(x) for x in np.flatnonzero(check.plan.pushing)]),
            "rods_left_out": int(t.dropped),
            "statics": {"exact": bool(st.exact), "residual": _f(st.residual), "margin": _f(st.margin),
                        "message": st.message, "refined": bool(check.design.refined)},
            "alternatives": {"count": len(alts), "lower": bool(eq.lower), "starts": int(eq.n_starts),
                             "energies": [_f(a.energy) for a in alts], "energy": _f(eq.energy)},
            "reactions": [{"node": int(a), "force": _v(f), "glued": bool(glued[a])}
                          for a, f in zip(eq.anchors, eq.reactions)],
            "notes": list(check.notes),
        },
        "hardware": {
            "kind": hw.kind, "name": hw.name, "diameter": hw.diameter if hw.is_hub else None,
            "pivot_radius": hw.pivot, "ball": hw.ball if hw.is_hub else None,
            "clearance": hw.clearance if hw.is_hub else None, "cone_deg": hw.cone_deg if hw.is_hub else None,
            "neck": hw.neck if hw.is_hub else None, "rod_diameter": hw.rod_diameter,
            "swing_deg": _f(hw.swing_deg) if hw.is_hub else None,
            "min_angle_deg": _f(hw.min_angle_deg), "point_mass": None if hw.is_hub else hw.mass,
            "free_play": ("each socket printed clearance/2 back from its pivot against the rod's pull at the "
                          "design: loaded balls sit on the pivots exactly; an unloaded ball rattles by up to "
                          f"{hw.clearance / 2:g} mm") if hw.is_hub else None,
            "rod_length_range": list(plan.length_range),
            "pivot_radius_range": list(hw.pivot_limits) if hw.is_hub else None,
        },
        "planner": planner_json(plan),
        "print": print_profile,
        "bill_of_materials": net_bill(check, catalog),
        "cad": None,
    }
