"""What the 3D view of a build shows: its parts (:class:`rodcad.outputs.viewgeom.ViewScene`) and
its side panel, for a chain, a chandelier and a net.

Every part stands where the design hangs: the simulated equilibrium, or, where CAD was built,
the as-built one (the solids' masses). With CAD the parts are the build's solids, meshed
coarsely (:mod:`rodcad.cad.viewmesh`) and placed as in assembly.step; without, simple shapes
from the numbers (:mod:`rodcad.outputs.viewgeom`). Rods are coloured by mass on the previews'
scale (:func:`rodcad.colors.mass_colors`: light blue to heavy red, one scale over the whole
build); hubs, pins and frames are grey, anchors nearly black.

The panel's numbers are design.json's (the dict :func:`rodcad.outputs.design_json.design_json`,
``chandelier_json`` or :func:`rodcad.outputs.net.design_json.net_json` returned), not recomputed.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from optimize.chain.curves import centerline
from rodcad.colors import mass_colors
from rodcad.outputs.viewgeom import (
    Y_UP,
    Mesh,
    ViewPart,
    ViewScene,
    arc_segments,
    cylinder,
    merge,
    rod_slab,
    sphere,
    tube,
    unit_cylinder,
)

__all__ = ["ANCHOR", "GREY", "PIN", "STEPS", "cad_parts", "chain_scene", "chandelier_scene", "hex_color", "legend",
           "mass_scale", "mm", "pct", "step_colors"]

#: Colours (sRGB 0..1) of the parts that are not rods.
GREY = (0.72, 0.73, 0.76)
PIN = (0.86, 0.86, 0.9)
ANCHOR = (0.1, 0.1, 0.12)
#: Colour steps of the mass scale: rods whose colours fall in one step share a mesh (and a
#: colour) in the glb; 64 steps are more than the eye tells apart.
STEPS = 64


def mass_scale(masses) -> tuple[float, float]:
    """(lo, hi) of the mass colour scale, as :func:`rodcad.colors.mass_colors` widens it when
    every rod weighs the same."""
    m = np.asarray(masses, float)
    lo, hi = float(m.min()), float(m.max())
    if hi - lo <= 1e-12 * max(abs(hi), 1.0):
        lo, hi = lo * 0.95, hi * 1.05 + 1e-12
    return lo, hi


def step_colors(masses, scale: tuple[float, float]) -> tuple[list[tuple[float, float, float]], list[int]]:
    """Each mass's colour on ``scale`` (lo, hi) and its step (0 .. STEPS - 1)."""
    lo, hi = scale
    step = np.clip(np.rint((np.asarray(masses, float) - lo) / (hi - lo) * (STEPS - 1)), 0, STEPS - 1).astype(int)
    rgba = mass_colors(lo + step / (STEPS - 1) * (hi - lo), lo, hi)
    return [tuple(float(c) for c in x[:3]) for x in rgba], [int(s) for s in step]


def hex_color(color) -> str:
    return "#" + "".join(f"{int(round(255 * float(c))):02x}" for c in color[:3])


def legend(scale: tuple[float, float], keys: list[tuple[tuple[float, float, float], str]]) -> dict[str, Any]:
    lo, hi = scale
    stops = mass_colors(np.linspace(lo, hi, 11), lo, hi)
    return {"label": "rod mass (g)", "lo": lo, "hi": hi, "stops": [hex_color(c) for c in stops],
            "keys": [{"color": hex_color(c), "label": label} for c, label in keys]}


def pct(x) -> str:
    return "-" if x is None else f"{100 * float(x):.3g} %"


def mm(x) -> str:
    return "-" if x is None else f"{float(x):.3g} mm"


def _rod_matrix(p, q) -> np.ndarray:
    """Rod frame -> chain plane: the first joint at ``p``, x toward ``q``, z the hinge axes."""
    d = np.asarray(q, float) - np.asarray(p, float)
    c, s = np.array([d[0], d[1]]) / math.hypot(d[0], d[1])
    m = np.eye(4)
    m[:2, :2] = [[c, -s], [s, c]]
    m[:2, 3] = p
    return m


def _section(rod: dict[str, Any]) -> tuple[float, float, float]:
    """(height, thickness, pin diameter) of a chain rod's body from its design.json entry."""
    params = rod.get("params") or {}
    body = params.get("body") or params.get("section") or {}
    h = float(body.get("height", 10.0))
    return h, float(body.get("thickness", 0.8 * h)), float(params.get("pin_diameter", 3.0))


def cad_parts(meshed, colors: dict[str, tuple[float, float, float]], default) -> list[ViewPart]:
    """ViewParts of meshed solids (:class:`rodcad.cad.viewmesh.SolidMesh`): a part's colour
    from ``colors`` by name, else ``default(part)``; one glb mesh per (solid, colour)."""
    out = []
    for s in meshed:
        group, color = colors.get(s.name) or default(s)
        out.append(ViewPart(s.name, group, f"{s.key}{hex_color(color)}", Mesh(s.vertices, s.faces), s.matrix, color))
    return out


# --------------------------------------------------------------------------- chains


def _chain_parts(rods: list[dict[str, Any]], points: np.ndarray, colors, steps, *, prefix: str = "",
                 group: str = "rods", base: np.ndarray | None = None, pins: list[float | None] | None = None
                 ) -> list[ViewPart]:
    """One chain's rods (its printed outline extruded, rod ``NN_TYPE``), its pins (``pin_NN``
    through every joint between rods; ``pins[j]`` its diameter, 0 for the rods' own, None for a
    fused joint: no pin) and its two anchors, from the numbers; ``base`` places the chain plane
    in the world."""
    base = np.eye(4) if base is None else base
    parts = []
    for i, (rod, color, step) in enumerate(zip(rods, colors, steps)):
        h, t, _ = _section(rod)
        t *= 1.0 if i % 2 == 0 else 0.9  # where neighbours overlap at a joint, one face in front
        k = float(rod.get("curvature") or 0.0)
        length = float(rod["length"])
        line = centerline(np.array([[0.0, 0.0], [length, 0.0]]), [k], per_rod=arc_segments(k, length))
        key = f"rod:{rod['type']}:{length:.3f}:{k:.6g}:{h:.3f}:{t:.3f}:{step}"
        parts.append(ViewPart(f"{prefix}{i:02d}_{rod['type']}", group, key, rod_slab(line, h, t), base @
                              _rod_matrix(points[i], points[i + 1]), color))
    for j, p in enumerate(points):
        rod = rods[min(j, len(rods) - 1)]
        h, t, d = _section(rod)
        if pins is not None and pins[j] is None and 0 < j < len(points) - 1:
            continue  # a fused joint: no pin
        if pins is not None and pins[j]:
            d = float(pins[j])
        m = np.eye(4)
        m[:2, 3] = p
        if j in (0, len(points) - 1):  # an anchor: a dark pin in the wall, longer and thicker
            r = max(d / 2 + 1.5, 0.22 * h)
            parts.append(ViewPart(f"{prefix}anchor_{'AB'[j > 0]}", "anchors", f"anchor:{r:.3f}:{t:.3f}",
                                  cylinder([0, 0, -0.9 * t], [0, 0, 0.9 * t], r, 16), base @ m, ANCHOR))
        else:
            parts.append(ViewPart(f"{prefix}pin_{j:02d}", "pins", f"pin:{d:.3f}:{t:.3f}",
                                  cylinder([0, 0, -t / 2 - 0.6], [0, 0, t / 2 + 0.6], d / 2, 12), base @ m, PIN))
    return parts


def _chain_panel(data: dict[str, Any], piece_of: dict[int, str]) -> list[dict[str, Any]]:
    """The rods' and joints' tables of a chain's design.json (a rod of a fused piece links to
    the piece's part, ``piece_of``)."""
    rods = data["rods"]
    rows, names = [], []
    for r in rods:
        lim = r.get("limits_deg")
        rows.append([r["index"], r["type"], r["length"], r["mass"], r.get("curvature") or 0.0,
                     "free" if not lim else f"{'-' if lim[0] is None else f'{lim[0]:.1f}'} .. "
                                            f"{'-' if lim[1] is None else f'{lim[1]:.1f}'}"])
        names.append([piece_of.get(r["index"], f"{r['index']:02d}_{r['type']}")])
    tables = [{"id": "rods", "title": "Rods", "columns": [
        {"label": "#"}, {"label": "type"}, {"label": "length mm", "digits": 2}, {"label": "mass g", "digits": 2},
        {"label": "curvature 1/mm", "digits": 4}, {"label": "joint after (deg)"}], "rows": rows, "parts": names}]
    hw = (data.get("hardware") or {}).get("pins") or []
    if hw:
        n = len(rods)
        tables.append({"id": "joints", "title": "Joints (pins)", "columns": [
            {"label": "#"}, {"label": "hardware"}, {"label": "load N", "digits": 3}, {"label": "rated N", "digits": 3},
            {"label": "friction"}],
            "rows": [[p["pin"], p["option"], p["load_n"], p["rated_n"], "{:g}-{:g}".format(*p["friction"])]
                     if p.get("option") is not None else [p["pin"], "fused (no pin)", None, None, "-"] for p in hw],
            "parts": [[f"anchor_{'AB'[p['pin'] > 0]}" if p["pin"] in (0, n) else f"pin_{p['pin']:02d}"]
                      for p in hw]})
    return tables


def chain_scene(result, data: dict[str, Any]) -> ViewScene:
    """The view of one built chain (:class:`rodcad.results.BuildResult` and its design.json):
    rods, pins, anchors and, with CAD, the solids and the anchor fixture, where the chain hangs
    (as built with CAD)."""
    rods = data["rods"]
    masses = [r["mass"] for r in rods]
    scale = mass_scale(masses)
    colors, steps = step_colors(masses, scale)
    ab = data.get("as_built")
    points = np.asarray(ab["points"] if ab and "points" in ab else data["simulated"]["points"], float)
    hw = (data.get("hardware") or {}).get("pins") or []
    pin_d = {p["pin"]: p.get("pin_diameter_mm") for p in hw}  # None: a fused joint, no pin
    pins = [pin_d.get(j, 0.0) for j in range(len(points))]
    parts = _chain_parts(rods, points, colors, steps, pins=pins)
    if result.fabrication is not None:
        parts = _chain_cad(result, data, points, parts, dict(zip([f"{r['index']:02d}_{r['type']}" for r in rods],
                                                                   colors)))
    curve, err = data.get("curve") or {}, data.get("error") or {}
    rows = [["rods", str(len(rods))], ["span", mm(math.dist(*data["anchors"]))],
            ["size", mm(curve.get("size_mm"))],
            ["rods off the target curve", f"{mm(curve.get('max_mm'))} ({pct(curve.get('rel_size'))} of its size)"],
            ["joints off the target", f"{mm(err.get('max_mm'))} ({pct(err.get('max_rel_span'))} of the span)"]]
    if ab:
        e, size = ab["error"], curve.get("size_mm")
        rel = None if e.get("max_mm") is None or not size else e["max_mm"] / size  # judged as the fit: by the size
        rows.append(["as built (the solids' masses)", f"{mm(e.get('max_mm'))} ({pct(rel)} of its size)"])
    if data.get("tolerance") is not None:
        rows.append(["tolerance", f"{pct(data['tolerance'])}: {'met' if data.get('meets_tolerance') else 'MISSED'}"])
    sim = data["simulated"]
    rows.append(["equilibrium", f"{'stable' if sim.get('stable') else 'NOT stable'}, "
                                f"{'unique' if sim.get('unique', True) else 'not unique'}"])
    bom = data.get("bill_of_materials") or {}
    rows.append(["chain mass", f"{sum(masses):.1f} g" + (f"; filament {bom['filament_g']:.1f} g"
                                                          if "filament_g" in bom else "")])
    shown = "as built (the solids)" if result.fabrication is not None else "simulated (no CAD: simple shapes)"
    panel = {"title": data["name"], "subtitle": f"chain of {len(rods)} rods, {shown}", "summary": rows,
             "legend": legend(scale, [(PIN, "pin"), (ANCHOR, "anchor")] +
                               ([(GREY, "anchor fixture")] if getattr(result, "fixture", None) is not None else [])),
             "tables": _chain_panel(data, {} if result.fabrication is None else
                                    {i: p.file_stem for p in result.fabrication.pieces
                                     for i in range(p.first, p.last + 1)})}
    return ViewScene(data["name"], parts, np.eye(4), panel, {"yaw": -22.0, "pitch": 14.0})


def _chain_cad(result, data, points, numbers: list[ViewPart], colors) -> list[ViewPart]:
    """The chain's solids (rods or fused pieces, pins) and its anchor fixture in place of the
    simple shapes (the anchors stay)."""
    from rodcad.cad.chainfiles import chain_parts
    from rodcad.cad.export import AssemblyPart
    from rodcad.cad.viewmesh import ViewMeshes

    fab = result.fabrication
    fused = {j + 1 for p in fab.pieces for j in range(p.first, p.last)}
    hw = (data.get("hardware") or {}).get("pins") or []
    pin_d = {p["pin"]: p["pin_diameter_mm"] for p in hw if p.get("pin_diameter_mm")}
    n = len(fab.rods)
    pins = [None if j in fused else (pin_d.get(j, fab.rods[min(j, n - 1)].pin_diameter), fab.rods[min(j, n - 1)].thickness)
            for j in range(len(points))]
    parts = fab.parts
    nodes = chain_parts([r.file_stem for r in parts], [r.solid for r in parts], points,
                        [r.mass for r in parts], pins, at=[r.index for r in parts])
    nodes = [nd for nd in nodes if not nd.name.startswith("pin_") or nd.name not in ("pin_00", f"pin_{n:02d}")]
    if result.fixture is not None:
        nodes.append(AssemblyPart("fixture", result.fixture, np.eye(4)))
    named = {k: ("rods", c) for k, c in colors.items()}
    scale = mass_scale([r["mass"] for r in data["rods"]])
    for p in fab.pieces:  # a fused piece: the colour of its rods' mean mass
        mean = float(np.mean([data["rods"][i]["mass"] for i in range(p.first, p.last + 1)]))
        named[p.file_stem] = ("rods", step_colors([mean], scale)[0][0])
    meshed = ViewMeshes().parts(nodes)

    def other(s):
        return ("pins", PIN) if s.name.startswith("pin_") else ("supports", GREY)

    return [p for p in numbers if p.group == "anchors"] + cad_parts(meshed, named, other)


# --------------------------------------------------------------------------- chandeliers


def chandelier_scene(b, data: dict[str, Any]) -> ViewScene:
    """The view of a chandelier (:class:`rodcad.results.ChandelierBuild` and its design.json):
    every chain in its plane, its pins and anchors, and the frame (its solid with CAD, tubes
    along its outline without)."""
    chains = b.result.chains
    masses = [r["mass"] for ch in data["chains"] for r in ch["rods"]]
    scale = mass_scale(masses)
    parts: list[ViewPart] = []
    k = 0
    rows, names = [], []
    for ci, (ch, cj) in enumerate(zip(chains, data["chains"])):
        n = len(cj["rods"])
        colors, steps = step_colors(masses[k:k + n], scale)
        k += n
        points = (b.as_built[ci].equilibrium.points if b.as_built is not None
                  else np.asarray(cj["simulated"]["points"], float))
        parts += _chain_parts(cj["rods"], np.asarray(points, float), colors, steps, prefix=f"{ch.name}.",
                              group=ch.name, base=ch.placement.transform())
        for r in cj["rods"]:
            rows.append([ch.name, r["index"], r["type"], r["length"], r["mass"], r.get("curvature") or 0.0])
            names.append([f"{ch.name}.{r['index']:02d}_{r['type']}"])
    if b.frame is not None:
        parts = _chandelier_cad(b, parts, scale)
    else:
        from rodcad.design.frame import frame_outline

        th = float(b.frame_plan.params.get("thickness", 4.0))
        frame = merge([tube(line, th / 2, 10) for line in frame_outline(b.frame_plan)])
        parts.append(ViewPart("frame", "supports", "frame", frame, np.eye(4), GREY))
    ce = data.get("error") or {}
    summary = [["chains", str(len(chains))], ["rods", str(len(masses))],
               ["frame", f"{b.frame_plan.kind}"],
               ["joints off the target (worst chain)", f"{mm(ce.get('max_mm'))} ({pct(ce.get('max_rel_span'))} "
                                                       "of its span)"],
               ["rods off the target curve (worst chain)",
                pct(max(c["curve"]["rel_size"] for c in data["chains"])) + " of its size"],
               ["total rod mass", f"{sum(masses):.1f} g"]]
    chains_table = {"id": "chains", "title": "Chains", "columns": [
        {"label": "chain"}, {"label": "rods"}, {"label": "mass g", "digits": 1}, {"label": "max error mm", "digits": 3},
        {"label": "curve % of size", "digits": 3}],
        "rows": [[c["name"], len(c["rods"]), sum(r["mass"] for r in c["rods"]), c["error"]["max_mm"],
                  100 * c["curve"]["rel_size"]] for c in data["chains"]],
        "parts": [[f"{c['name']}.{r['index']:02d}_{r['type']}" for r in c["rods"]] for c in data["chains"]]}
    rods_table = {"id": "rods", "title": "Rods", "columns": [
        {"label": "chain"}, {"label": "#"}, {"label": "type"}, {"label": "length mm", "digits": 2},
        {"label": "mass g", "digits": 2}, {"label": "curvature 1/mm", "digits": 4}], "rows": rows, "parts": names}
    shown = "as built (the solids)" if b.frame is not None else "simulated (no CAD: simple shapes)"
    panel = {"title": data["name"], "subtitle": f"chandelier of {len(chains)} chains, {shown}", "summary": summary,
             "legend": legend(scale, [(PIN, "pin"), (ANCHOR, "anchor (lug pin)"), (GREY, "frame")]),
             "tables": [chains_table, rods_table]}
    return ViewScene(data["name"], parts, Y_UP, panel, {"yaw": -30.0, "pitch": 22.0})


def _chandelier_cad(b, numbers: list[ViewPart], scale) -> list[ViewPart]:
    """The chandelier's solids (frame, rods, pins) as assembly.step places them, the anchors
    from the numbers."""
    from types import SimpleNamespace

    from rodcad.cad.chandelier import chandelier_nodes
    from rodcad.cad.viewmesh import ViewMeshes

    chains = [SimpleNamespace(name=ch.name, type_names=ch.type_names, masses=ch.masses, placement=ch.placement,
                              points=np.asarray(ab.equilibrium.points, float))  # where it hangs as built
              for ch, ab in zip(b.result.chains, b.as_built)]
    nodes = chandelier_nodes(b.frame[0], chains, b.design.catalog, frame_plan=b.frame_plan,
                             rod_solid=lambda ci, i: b.fabrications[ci].rods[i].solid)
    rod_color = {p.name: (p.group, p.color) for p in numbers if p.key.startswith("rod:")}
    meshed = ViewMeshes().parts(nodes)

    def other(s):
        return (s.group, PIN) if s.name.split(".")[-1].startswith("pin_") else ("supports", GREY)

    return [p for p in numbers if p.group == "anchors"] + cad_parts(meshed, rod_color, other)
