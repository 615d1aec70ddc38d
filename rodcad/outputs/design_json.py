"""design.json: the machine-readable result of a build (contract.md), for a chain and a chandelier.
"""

from __future__ import annotations

import json
import math
from collections import Counter
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from optimize.chain.curves import centerline, curve_distance
from rodcad import __version__
from rodcad.catalog.massrange import mass_info
from rodcad.catalog.model import Catalog, EndShape, RodType
from rodcad.design.asprinted import anchor_holes
from rodcad.outputs.hardware import hardware_bill, hardware_json, rods_hardware_json, tapping_json
from rodcad.outputs.printed import as_printed_json, printed_rod_fields

__all__ = ['ball_text', 'design_json', 'fabrication_json', 'metal_balls', 'bill_of_materials', 'write_json', 'chandelier_json']


def _socket_height(f: Any) -> float | list[float]:
    """A rod's socket roofs above the ball centres (mm): one for all, or one per ball where
    its rows were raised unequally (:mod:`rodcad.fabrication.roofs`)."""
    h = getattr(f, "socket_height", 0.0)
    return [float(v) for v in h] if isinstance(h, (tuple, list)) else float(h or f.socket_radius)


def _f(x: float) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def _pts(p: np.ndarray) -> list[list[float]]:
    return [[float(x), float(y)] for x, y in np.asarray(p, float)]


def _limits_deg(lim: np.ndarray) -> list[float | None]:
    return [_f(math.degrees(v)) for v in lim]


def anchor_limits_deg(end_limits) -> list[list[float | None] | None]:
    """design.json's ``anchor_limits_deg``: per anchor [lo, hi] in degrees (null for an open
    side), or null for a bare pin."""
    if end_limits is None:
        return [None, None]
    return [None if np.all(np.isinf(row)) else _limits_deg(row) for row in np.asarray(end_limits, float)]


def _rod_json(i: int, rod: RodType, length: float, mass: float, com, limits, n: int) -> dict[str, Any]:
    """One rod of design.json's ``rods`` (limits: the joint after it, None for the last rod)."""
    return {"index": i, "type": rod.name, "length": float(length), "mass": float(mass),
            "com": [float(v) for v in com], "limits_deg": _limits_deg(limits[i]) if i < n - 1 else None,
            "curvature": float(rod.curvature), "params": rod_params(rod)}


def rod_params(rod: RodType) -> dict[str, Any]:
    """The family parameters a rod is printed with (mm, deg, 1/mm)."""
    g = rod.geometry

    def end(e: EndShape) -> dict[str, float]:
        return {"setback": e.setback, "top_chamfer": e.top_chamfer, "bottom_chamfer": e.bottom_chamfer}

    out = {"family": rod.family, "length": rod.length, "scale": rod.scale, "curvature": rod.curvature,
           "section": {"height": g.height, "thickness": g.thickness},
           "ends": {"first": end(g.first), "second": end(g.second)},
           "pin_diameter": g.hinge.pin_diameter, "pin_clearance": g.hinge.pin_clearance,
           "material": rod.material.name}
    if g.graduated:  # the body's section at the rod's scale (the hinge ends keep 'section')
        out["body"] = {"height": g.body_h, "thickness": g.body_t}
    return out


def print_profile(catalog: Catalog) -> dict[str, Any]:
    """The print settings the masses assume (contract.md's ``print``)."""
    m = next(iter(catalog)).material
    settings = {"layer_height": 0.2, "perimeters": 2, **getattr(catalog, "print_settings", {})}
    return {"material": m.name, "density": m.density, "infill": 1.0, **settings,
            "note": "every mass assumes solid rods: print them with 100 % infill"}


def curve_error(curve: np.ndarray, points: np.ndarray, curvature: np.ndarray, span: float) -> dict[str, Any]:
    """How far the rods' centrelines (arcs for curved rods) are from the target curve
    (symmetric Hausdorff distance), in mm and as a fraction of the span and of the target's
    size (:func:`rodcad.design.shell.curve_size`: the span, or the curve's width or height
    where larger, e.g. a heart hung from its cusp)."""
    from rodcad.design.shell import curve_size

    d = curve_distance(curve, centerline(points, curvature))
    size = curve_size(curve)
    return {"max_mm": _f(d), "rel_span": _f(d / span) if span > 0 else None, "size_mm": _f(size),
            "rel_size": _f(d / size)}


def _stop_json(problem, j: int) -> dict[str, Any]:
    """A joint resting on a stop: the stop's angle (the limit the target bend sits on) and
    its side ('hi': it keeps the joint from bending further, 'lo': from straightening)."""
    bend = float(np.diff(problem.angles)[j])
    lo, hi = problem.limits[j]
    side = "lo" if abs(lo - bend) < abs(hi - bend) else "hi"
    return {"joint": int(j), "deg": _f(math.degrees(lo if side == "lo" else hi) + 0.0), "side": side}


def _simulated_json(eq, unique: bool) -> dict[str, Any]:
    """design.json's ``simulated``: points, angles, reactions (g * m/s^2 = mN -> N), KKT, stability."""
    return {"points": _pts(eq.points), "angles_deg": [float(math.degrees(v)) for v in eq.angles],
            "reaction": [_f(v * 1e-3) for v in eq.reaction],
            "reaction_a": [_f(v * 1e-3) for v in eq.reaction_a],
            "kkt_residual": _f(eq.kkt_residual), "stable": bool(eq.stable), "success": bool(eq.success),
            "unique": bool(unique)}


def _as_built_json(ab) -> dict[str, Any]:
    return {"masses": [float(v) for v in ab.masses], "com": _pts(ab.com), "points": _pts(ab.equilibrium.points),
            "error": ab.distance.as_dict(), "stable": bool(ab.equilibrium.stable)}


def _filament_and_balls(rods) -> dict[str, Any]:
    """Filament (g), metal balls by kind and diameter and shot by kind (g) over fabricated rods."""
    balls: Counter[tuple[float, str]] = Counter()
    shot: dict[str, float] = {}
    for f in rods:
        if f.ball_count:
            balls[(float(f.ball_diameter), str(getattr(f, "ball_name", "")))] += int(f.ball_count)
        if f.fill_mass > 0:
            shot[f.fill_name] = shot.get(f.fill_name, 0.0) + float(f.fill_mass)
    return {"filament_g": float(sum(f.filament_mass for f in rods)),
            "metal_balls": metal_balls(balls),
            "fill": [{"name": k, "grams": v} for k, v in sorted(shot.items())]}


def ball_text(diameter: float, name: str = "") -> str:
    """How a ball kind is named in reports and pause messages: its catalog name when it
    has one ('steel bearing ball 6 mm'), else '6 mm ball'."""
    return name or f"{diameter:g} mm ball"


def metal_balls(counts: Mapping[tuple[float, str], int]) -> list[dict[str, Any]]:
    """The bill of materials' ``metal_balls``: one entry per ball kind, ``{diameter_mm, kind,
    count}`` by diameter then kind, from counts keyed by (diameter, kind name)."""
    return [{"diameter_mm": d, "kind": name or None, "count": int(n)} for (d, name), n in sorted(counts.items())]


def _header(d, method: str | None, seed: int, time_s: float) -> dict[str, Any]:
    return {"name": d.name, "units": {"length": "mm", "mass": "g", "angle": "deg", "force": "N"},
            "rodcad": __version__, "design_file": str(d.path), "catalog": d.catalog.name,
            "method": method, "seed": int(seed), "time_s": float(time_s)}


def _piece_of(fab, i: int):
    """The fused piece rod ``i`` is part of, or None."""
    return next((p for p in getattr(fab, "pieces", ()) if p.first <= i <= p.last), None)


def fabrication_json(f, piece=None) -> dict[str, Any]:
    """design.json's ``fabrication`` of one built rod (a :class:`rodcad.cad.rods.FabricatedRod`):
    as-built mass and centre of mass, voids and inserts, pauses, its file and bed placement.
    A rod of a fused ``piece`` (:class:`rodcad.cad.pieces.FabricatedPiece`) is in the piece's
    file: ``file`` is that file, ``piece`` its [first, last] rods and ``print_matrix`` places
    the rod's frame where the rod lies in the file."""
    out = {
        "mass": float(f.mass), "com": [float(v) for v in f.com],
        "filament_g": float(f.filament_mass), "cavities": int(f.cavity_count),
        "cavity_radius_mm": float(f.cavity_radius), "balls": int(f.ball_count),
        "ball_diameter_mm": None if f.ball_diameter is None else float(f.ball_diameter),
        "pause_z_mm": None if f.pause_z is None else float(f.pause_z),
        "pause_zs_mm": [float(z) for z in f.pause_zs],
        "ball_centers": [[float(v) for v in c] for c in np.asarray(f.socket_centers).reshape(-1, 3)],
        "socket_height_mm": _socket_height(f) if f.ball_count else None,
        "ball_mass_g": float(f.mass - f.filament_mass - f.fill_mass),
        "ball_kind": (getattr(f, "ball_name", "") or None) if f.ball_count else None,
        "fill": {"name": f.fill_name, "grams": float(f.fill_mass),
                 "chamber_volume_mm3": float(f.chamber_volume),
                 "pause_z_mm": None if f.pause_z is None else float(f.pause_z)} if f.fill_name else None,
        "plastic_volume_mm3": float(f.plastic_volume),
        "file": f"rods/{f.file_stem}.step",
        "print_matrix": [[float(v) for v in row] for row in np.asarray(f.print_matrix)],
        "in_range": bool(f.in_range), "message": f.message,
    }
    if piece is not None:
        out["file"] = f"rods/{piece.file_stem}.step"
        out["piece"] = [int(piece.first), int(piece.last)]
        out["pause_z_mm"] = None if piece.pause_z is None else float(piece.pause_z)  # the piece's pauses
        out["pause_zs_mm"] = [float(z) for z in piece.pause_zs]
        pm = np.asarray(piece.print_matrix) @ piece.placements[f.index - piece.first]
        out["print_matrix"] = [[float(v) for v in row] for row in pm]
    return out


def design_json(r) -> dict[str, Any]:
    """The machine-readable result of a run (contract.md's design.json, plus extras).

    Args:
        r: a :class:`rodcad.pipeline.BuildResult`.
    """
    d = r.design
    eq = r.equilibrium
    rods = []
    per_rod = rods_hardware_json(r) if getattr(r, "hardware", None) is not None else None
    for i, name in enumerate(r.type_names):
        rod = _rod_json(i, d.catalog[name], r.lengths[i], r.masses[i], r.com[i], r.limits, r.n)
        printed = r.plan is not None and r.plan.rods  # rods printed to order: their own ranges
        # as the rods hang: with their joint hardware (the plan's bounds have it already)
        bounds = r.plan.problem.mass_bounds[i] if printed else \
            np.asarray(mass_info(d.catalog[name]).mass_range, float) + r.attached[i].sum()
        rod["mass_range"] = [float(v) for v in bounds]
        if r.fabrication is not None:
            rod["fabrication"] = fabrication_json(r.fabrication.rods[i], _piece_of(r.fabrication, i))
        if getattr(r, "as_printed", None) is not None:
            rod.update(printed_rod_fields(r.as_printed, r.lengths, r.com, i))
        if per_rod is not None:
            rod["hardware"] = per_rod[i]
        rods.append(rod)
    out: dict[str, Any] = {
        **_header(d, r.method or None, r.seed, r.time_s),
        "anchors": _pts(d.anchors),
        "target": {"form": d.target_form, "params": d.target_params,
                   "points": _pts(r.target_points) if r.target_points is not None else None},
        "rods": rods,
        "simulated": {**_simulated_json(eq, r.unique), "stable_equilibria_found": int(r.n_stable)},
        "error": r.distance.as_dict() if r.distance is not None else None,
        "anchor_limits_deg": anchor_limits_deg(r.end_limits),
        "fused": [[int(a), int(b)] for a, b in (r.plan.fused if r.plan is not None else [])],
        "tolerance": r.tolerance,
        "meets_tolerance": r.meets_tolerance,
        "notes": list(r.notes),
    }
    curvature = np.array([d.catalog[n].curvature for n in r.type_names])
    if r.plan is not None:
        out["curve"] = curve_error(r.plan.curve, eq.points, curvature, d.span)
        out["discretisation"] = {"curve_error_mm": _f(r.plan.discretization.curve_error),
                                 "hanging_curve_error_mm": _f(curve_distance(r.plan.curve, eq.points)),
                                 "joint_error_mm": _f(r.plan.discretization.joint_error),
                                 "stop_mismatch_deg": _f(math.degrees(r.plan.assign_cost)),
                                 "added_stops": [_stop_json(r.plan.problem, j) for j in r.plan.added_stops]}
    if r.chain_design is not None:
        res = r.chain_design.result
        out["inverse"] = {"exact": bool(res.exact), "statics_residual": _f(res.statics_residual),
                          "at_bounds": [int(v) for v in res.at_bounds], "nfev": int(res.nfev),
                          "time_s": float(res.time_s), "message": res.message}
    if r.as_built is not None:
        out["as_built"] = _as_built_json(r.as_built)
        if r.plan is not None:
            out["as_built"]["curve"] = curve_error(r.plan.curve, r.as_built.equilibrium.points, curvature, d.span)
    if getattr(r, "as_printed", None) is not None:
        out.update(as_printed_json(r.as_printed, r.plan.curve if r.plan is not None else None, curvature, d.span))
    if getattr(r, "hardware", None) is not None:
        out["hardware"] = hardware_json(r)
    if getattr(r, "tapping", None) is not None:
        out["tapping"] = tapping_json(r)
    out["print"] = print_profile(d.catalog)
    out["bill_of_materials"] = bill_of_materials(r)
    if getattr(r, "fixture", None) is not None:
        out["fixture"] = fixture_json(r)
    return out


def fixture_json(r) -> dict[str, Any]:
    """design.json's ``fixture``: the printed piece the anchor pins sit in (with its stops)."""
    from rodcad.cad.fixture import fixture_width

    d = r.design
    rods = [d.catalog[name] for name in r.type_names]
    volume = float(r.fixture.volume)
    mat = rods[0].material
    return {"file": "fixture.step", "stl": "fixture.stl", "volume_mm3": volume,
            "filament_g": volume * mat.density / 1000.0,
            "anchor_pins": {"count": 2, "diameter_mm": rods[0].geometry.hinge.pin_diameter,
                            "length_mm": round(fixture_width(rods[0], rods[-1]), 2),
                            "holes_mm": None if getattr(r, "holes", None) is None else  # centre minus A, B
                            [[float(v) for v in row] for row in anchor_holes(r.holes, r.equilibrium.points)]},
            "stops": [k for k in (0, 1) if np.any(np.isfinite(np.asarray(r.end_limits)[k]))],
            "mount": "a 5 mm hanging hole above the anchors' midpoint",
            "print": "lying on its back face, with supports under the front cheek's slots",
            "problems": list(r.fixture_problems)}


def bill_of_materials(r) -> dict[str, Any]:
    """Rods by type, filament, metal balls by size and pins."""
    d = r.design
    by_type = Counter(r.type_names)
    thick = max(d.catalog[n].geometry.thickness for n in r.type_names)
    pin_d = d.catalog[r.type_names[0]].geometry.hinge.pin_diameter
    bom: dict[str, Any] = {
        "rods": dict(sorted(by_type.items())),
        "pins": {"count": r.n + 1, "diameter_mm": pin_d, "length_mm": round(thick + 1.0, 2),
                 "note": "one per joint plus one at each anchor"},
    }
    hw = hardware_bill(r, round(thick + 1.0, 2)) if getattr(r, "hardware", None) is not None else []
    if hw:  # the chosen hardware's pins: by diameter (the most used first)
        by_d = Counter()
        for e in hw:
            by_d[e["pins"]["diameter_mm"]] += e["pins"]["count"]
        bom["pins"]["diameter_mm"] = by_d.most_common(1)[0][0]
        bom["pins"]["diameters_mm"] = {f"{k:g}": v for k, v in sorted(by_d.items())}
        bom["hardware"] = hw
    fused = [(a, b) for a, b in (r.plan.fused if getattr(r, "plan", None) is not None else [])]
    if fused:
        bom["pins"]["count"] -= sum(b - a for a, b in fused)
        bom["pins"]["note"] = "one per joint that is not fused plus one at each anchor"
        bom["pieces"] = [{"rods": [int(a), int(b)]} for a, b in fused]
        for entry, p in zip(bom["pieces"], getattr(r.fabrication, "pieces", None) or []):
            entry["file"] = f"rods/{p.file_stem}.step"
    if r.fabrication is not None:
        bom.update(_filament_and_balls(r.fabrication.rods))
        bom["total_mass_g"] = float(sum(f.mass for f in r.fabrication.rods))
    else:
        bom["total_mass_g"] = float(np.sum(r.masses))
    return bom


def write_json(path: Path, data: dict[str, Any]) -> None:
    path.write_text(json.dumps(data, indent=2, allow_nan=False) + "\n", encoding="utf-8")


def _pts3(p: np.ndarray) -> list[list[float]]:
    return [[float(v) for v in row] for row in np.asarray(p, float)]


def _hung_chain_json(r, rods: list[dict[str, Any]], curvature, span: float) -> dict[str, Any]:
    """A chandelier chain's joint hardware, as printed bands and tapping (as one chain's
    design.json has them); its rods get their ``hardware`` (``rods`` updated in place)."""
    out: dict[str, Any] = {}
    if r.hardware is not None:
        out["hardware"] = hardware_json(r)
        for rod, h in zip(rods, rods_hardware_json(r)):
            rod["hardware"] = h
    if r.as_printed is not None:
        out.update(as_printed_json(r.as_printed, r.plan.curve, curvature, span))
    if r.tapping is not None:
        out["tapping"] = tapping_json(r)
    return out


def merged_hardware_bill(bills: Sequence[list[dict[str, Any]]]) -> list[dict[str, Any]]:
    """Several chains' :func:`rodcad.outputs.hardware.hardware_bill` as one: each option once,
    its joints, pins, sleeves and bearings summed."""
    out: dict[str, dict[str, Any]] = {}
    for bill in bills:
        for e in bill:
            m = out.get(e["option"])
            if m is None:
                out[e["option"]] = json.loads(json.dumps(e))
                continue
            m["joints"] += e["joints"]
            for part in ("pins", "sleeves", "bearings"):
                if part in e:
                    m[part]["count"] += e[part]["count"]
    return list(out.values())


def chandelier_json(b) -> dict[str, Any]:
    """design.json of a chandelier: per chain what design.json holds for one chain, plus
    its 3D anchors and points, the frame and the bill of materials over all chains.

    Args:
        b: a :class:`rodcad.pipeline.ChandelierBuild`.
    """
    d = b.design
    res = b.result
    chains = []
    for k, ch in enumerate(res.chains):
        pr = ch.design.plan.problem
        eq = ch.equilibrium
        lim = pr.limits if pr.limits is not None else np.zeros((0, 2))
        n = len(ch.type_names)
        rods = [_rod_json(i, d.catalog[name], pr.lengths[i], ch.masses[i], pr.com[i], lim, n)
                for i, name in enumerate(ch.type_names)]
        curvature = np.array([d.catalog[name].curvature for name in ch.type_names])
        span = float(np.hypot(*np.subtract(*ch.placement.plane_anchors())))
        entry: dict[str, Any] = {
            "name": ch.name,
            "anchors_3d": _pts3([ch.placement.a3, ch.placement.b3]),
            "anchors": _pts(np.array(ch.placement.plane_anchors())),
            "target": {"points": _pts(pr.target)},
            "rods": rods,
            "simulated": {**_simulated_json(eq, ch.design.unique), "points_3d": _pts3(ch.points3d)},
            "error": ch.distance.as_dict(),
            "curve": curve_error(ch.design.plan.curve, ch.points, curvature, span),
            "anchor_limits_deg": [None, None],
            "shared_with": ch.shared_with,
        }
        if b.as_built is not None:
            entry["as_built"] = _as_built_json(b.as_built[k])
        if b.chains:
            entry.update(_hung_chain_json(b.chains[k], rods, curvature, span))
        chains.append(entry)
    bom = res.bom.as_dict()
    thick = max(d.catalog[n].geometry.thickness for ch in res.chains for n in ch.type_names)
    hw = merged_hardware_bill([hardware_bill(r, round(thick + 1.0, 2)) for r in b.chains])
    if hw:
        bom["hardware"] = hw
    if b.fabrications is not None:
        bom.update(_filament_and_balls([f for fab in b.fabrications for f in fab.rods]))
    out: dict[str, Any] = {
        **_header(d, res.method, res.seed, b.time_s),
        "chandelier": dict(d.chandelier.written),
        "chains": chains,
        "error": {"max_mm": _f(res.max_error),
                  "max_rel_span": _f(max(c.distance.max_rel_span for c in res.chains))},
        "print": print_profile(d.catalog),
        "bill_of_materials": bom,
        "notes": list(b.notes),
        "meets_tolerance": b.meets_tolerance,
    }
    if b.frame is not None:
        chk = b.frame[1]
        out["frame"] = {"kind": b.frame_plan.kind if hasattr(b.frame_plan, "kind") else None,
                        "valid": bool(chk.valid), "size_mm": [float(v) for v in chk.size],
                        "fits_printer": chk.fits_printer, "problems": list(chk.problems),
                        "closest_rod_mm": _f(min((c[-1] for c in chk.clearances), default=float("nan")))}
    return out
