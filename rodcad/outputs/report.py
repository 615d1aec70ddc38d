"""What a run reports to people: report.md and the terminal summary (design.json is
:mod:`rodcad.outputs.design_json`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from rodcad.outputs.printed import as_printed_lines, printed_summary
from rodcad import __version__
from rodcad.fabrication.layers import LayerGrid
from rodcad.outputs.hardware import hardware_lines, hardware_summary, tapping_sentence
from rodcad.outputs.design_json import ball_text, bill_of_materials, curve_error
from rodcad.outputs.view import view_line

__all__ = ['report_markdown', 'summary_text', 'chandelier_markdown', 'chandelier_summary']


def _fmt_err(e: dict[str, Any] | None) -> str:
    if not e:
        return "n/a"
    rel = e["max_rel_span"]
    return (f"max {e['max_mm']:.3g} mm ({100 * rel:.3g} % of the span), mean {e['mean_mm']:.3g} mm, "
            f"sum {e['sum_mm']:.3g} mm")


def _pauses(parts, prof: dict[str, Any]) -> str:
    """'1 pause, at z = 12.4 mm' / '3 pauses, at z = 11.4, 11.8 and 12.4 mm' / 'no pause': the
    layer tops (print_z) the print pauses at for these printed parts (rods and pieces), with the
    profile's layers (:class:`rodcad.fabrication.layers.LayerGrid`)."""
    h = float(prof.get("layer_height") or 0.2)
    layers = LayerGrid(h, float(prof.get("first_layer_height") or h))
    zs = sorted({layers.pause_z(z) for p in parts for z in p.pause_zs})
    if not zs:
        return "no pause"
    at = ", ".join(f"{z:g}" for z in zs[:-1]) + (" and " if len(zs) > 1 else "") + f"{zs[-1]:g}"
    return f"{len(zs)} pause{'s' if len(zs) > 1 else ''}, at z = {at} mm"


def report_markdown(r, data: dict[str, Any]) -> str:
    """report.md: inputs, method, error, stability, per-rod table, bill of materials, assembly."""
    d = r.design
    L: list[str] = []
    add = L.append
    add(f"# {d.name}: hanging chain report")
    add("")
    if d.description:
        add(d.description.strip())
        add("")
    add(f"Made by rodcad {__version__} from `{d.path}` in {r.time_s:.1f} s.")
    add("")
    add("## Inputs")
    add("")
    a, b = d.anchors
    add(f"- Catalog: `{d.catalog.name}` ({len(d.catalog)} rod types)")
    add(f"- Anchors: A = ({a[0]:g}, {a[1]:g}) mm, B = ({b[0]:g}, {b[1]:g}) mm, span {d.span:.4g} mm")
    if d.target_form:
        params = ", ".join(f"{k} = {v}" for k, v in d.target_params.items() if k != "points")
        add(f"- Target: {d.target_form}" + (f" ({params})" if params else ""))
    else:
        add("- Explicit chain (no target)")
    c = d.constraints
    cons = []
    if c.types:
        cons.append("types " + ", ".join(c.types))
    if c.lengths:
        cons.append("lengths " + ", ".join(f"{x:g}" for x in c.lengths) + " mm")
    if c.rods:
        cons.append(f"{c.rods} rods")
    if c.fixed:
        cons.append(f"{len(c.fixed)} fixed rod(s)")
    if cons:
        add("- Constraints: " + "; ".join(cons))
    add(f"- Method: {r.method or 'simulate (explicit chain)'}, seed {r.seed}")
    add("")
    add("## Result")
    add("")
    add(f"- Shape error (simulated vs target joints): {_fmt_err(data['error'])}")
    if "discretisation" in data:
        disc = data["discretisation"]
        add(f"- Discretisation (rods laid on the curve): curve error {disc['curve_error_mm']:.3g} mm, "
            f"stop mismatch {disc['stop_mismatch_deg']:.3g} deg (reported apart from the physics error)")
        if "curve" in data:
            cv = data["curve"]
            add(f"- The hanging rods' centrelines (curved bodies as printed) are within {cv['max_mm']:.3g} mm of "
                f"the target curve, {100 * cv['rel_span']:.3g} % of the span{_of_size(cv)} (both errors together, "
                "everywhere along the rods)")
        add(f"- Joints: {_joints_text(r)}")
    if "as_built" in data:
        add(f"- As built (masses and centres of mass of the real solids): {_fmt_err(data['as_built']['error'])}")
    if getattr(r, "as_printed", None) is not None:
        size = float(data["curve"]["size_mm"]) if "curve" in data else float(d.span)
        for line in as_printed_lines(r.as_printed, size):
            add(line)
        tapped = tapping_sentence(r, size)
        if tapped:
            add(tapped)
    if "inverse" in data:
        inv = data["inverse"]
        add(f"- Inverse design: {'exact' if inv['exact'] else 'best fit within the mass bounds'}; "
            f"{inv['nfev']} simulations in {inv['time_s']:.2f} s ({inv['message']})")
    sim = data["simulated"]
    add(f"- Equilibrium: KKT residual {sim['kkt_residual']:.1e}, "
        f"{'stable' if sim['stable'] else 'NOT stable'}; "
        f"{sim['stable_equilibria_found']} distinct stable equilibri{'um' if sim['stable_equilibria_found'] == 1 else 'a'} "
        f"found from 12 starts ({'unique' if sim['unique'] else 'not unique'})")
    add(f"- Reactions: A ({sim['reaction_a'][0]:.4g}, {sim['reaction_a'][1]:.4g}) N, "
        f"B ({sim['reaction'][0]:.4g}, {sim['reaction'][1]:.4g}) N")
    if getattr(r, "fit", None) is not None:
        given = "the design's" if d.tolerance is not None else "the default"
        add(f"- Tolerance ({given}): the rods within {100 * r.tolerance:.3g} % of the target's size of its curve: "
            + ("met" if r.meets_tolerance else f"MISSED: {r.limit()}"))
    for note in r.notes:
        add(f"- Note: {note}")
    add("")
    add("![preview](preview.png)")
    add("")
    add(view_line())
    add("")
    add("## Rods")
    add("")
    fab = r.fabrication
    head = ("| # | type | length mm | scale | curvature 1/mm | ends: first / second (chamfer deg) | mass g | range g "
            "| joint after (deg) | x, y of first pin (mm) |")
    rule = "|---|---|---|---|---|---|---|---|---|---|"
    if fab is not None:
        head += " as built g | filament g | cavities | balls | pause at Z mm | file |"
        rule += "---|---|---|---|---|---|"
    add(head)
    add(rule)
    pts = r.equilibrium.points
    for i, rod in enumerate(data["rods"]):
        lim = rod["limits_deg"]
        lim_s = "-" if lim is None else f"{_deg(lim[0])} .. {_deg(lim[1])}"
        lo, hi = rod["mass_range"]
        ends = rod["params"]["ends"]
        stops = " / ".join(_end_text(e) for e in (ends["first"], ends["second"]))
        row = (f"| {i} | {rod['type']} | {rod['length']:g} | {rod['params'].get('scale', 1.0):.3g} | "
               f"{rod['curvature']:g} | {stops} | {rod['mass']:.3f} "
               f"| {lo:.2f}-{hi:.2f} | {lim_s} | {pts[i][0]:.1f}, {pts[i][1]:.1f} |")
        if fab is not None:
            f = fab.rods[i]
            cav = f"{f.cavity_count} x r {f.cavity_radius:.2f}" if f.cavity_count else "-"
            balls = f"{f.ball_count} x {ball_text(f.ball_diameter, f.ball_name)}" if f.ball_count else "-"
            if f.fill_mass > 0:
                balls = f"pour {f.fill_mass:.2f} g of {f.fill_name} at z = {f.pause_z:.2f} mm"
            elif f.chamber_volume > 0:
                balls = "empty chamber"
            fj = rod["fabrication"]
            pause = f"{fj['pause_z_mm']:.2f}" if fj["pause_z_mm"] is not None else "-"
            where = f"`{fj['file']}`" + (" (one piece: rods {}-{})".format(*fj["piece"]) if "piece" in fj else "")
            row += f" {f.mass:.3f} | {f.filament_mass:.2f} | {cav} | {balls} | {pause} | {where} |"
        add(row)
    add("")
    for line in hardware_lines(r, data):
        add(line)
    add("## Bill of materials")
    add("")
    bom = data["bill_of_materials"]
    for name, count in bom["rods"].items():
        add(f"- {count} x rod `{name}`")
    for piece in bom.get("pieces", []):
        first, last = piece["rods"]
        add(f"- rods {first} to {last} are ONE printed piece (their joints fused at the bend, no pins between them)"
            + (f": `{piece['file']}`" if "file" in piece else ""))
    pins = bom["pins"]
    if bom.get("hardware"):
        for e in bom["hardware"]:
            add(f"- {e['joints']} joint(s) with {e['option']}: {e['description']}; "
                f"{e['pins']['count']} x {e['pins']['diameter_mm']:g} mm pin cut to {e['pins']['length_mm']:g} mm"
                + (f", {e['sleeves']['count']} x sleeve {e['sleeves']['outer_diameter_mm']:g} mm OD cut to "
                   f"the tongue" if "sleeves" in e else "")
                + (f", {e['bearings']['count']} x bearing {e['bearings']['bore_mm']:g} x "
                   f"{e['bearings']['outer_diameter_mm']:g} x {e['bearings']['width_mm']:g} mm" if "bearings" in e
                   else ""))
    else:
        add(f"- {pins['count']} pins, {pins['diameter_mm']:g} mm diameter, cut to {pins['length_mm']:g} mm "
            f"({pins['note']})")
    if "filament_g" in bom:
        add(f"- Filament: {bom['filament_g']:.1f} g in all ({d.catalog[r.type_names[0]].material.name})")
        for ball in bom["metal_balls"]:
            add(f"- {ball['count']} x {ball_text(ball['diameter_mm'], ball.get('kind') or '')}")
        for fill in bom.get("fill", []):
            add(f"- {fill['grams']:.1f} g of {fill['name']} in all (per rod in the table)")
        fx = data.get("fixture")
        if fx is not None:
            pins = fx["anchor_pins"]
            add(f"- 1 anchor fixture (`{fx['file']}`, `{fx['stl']}`): {fx['filament_g']:.1f} g of filament, "
                f"{fx['mount']}; it stops the {' and the '.join('first' if k == 0 else 'last' for k in fx['stops'])} "
                f"rod. Print it {fx['print']}. Its anchor pins: {pins['count']} x {pins['diameter_mm']:g} mm, "
                f"{pins['length_mm']:g} mm long" + (f". PROBLEMS: {'; '.join(fx['problems'])}" if fx["problems"] else ""))
    else:
        add("- Filament and metal balls: run with CAD (without --no-cad) for exact figures")
    add(f"- Total chain mass: {bom['total_mass_g']:.1f} g")
    add("")
    add("## Print settings")
    add("")
    prof = data["print"]
    add(f"Every mass above assumes solid rods: print them in {prof['material']} ({prof['density']:g} g/cm^3) "
        "with **100 % infill** (a slicer's default of 15-20 % infill prints every rod far lighter than "
        "designed, and the chain will not hang as designed). As only mass ratios shape the chain, a "
        "filament whose density is off by the same amount for every rod does no harm; an infill that differs "
        "between rods does.")
    add("")
    add("| setting | value |")
    add("|---|---|")
    add("| infill | 100 % (solid) |")
    for key, label, unit in (("layer_height", "layer height", "mm"), ("first_layer_height", "first layer height", "mm"),
                             ("perimeters", "perimeters", ""), ("filament_diameter", "filament diameter", "mm"),
                             ("temperature", "nozzle temperature", "deg C"), ("bed_temperature", "bed temperature",
                                                                              "deg C")):
        if prof.get(key) is not None:
            add(f"| {label} | {prof[key]:g}{' ' + unit if unit else ''} |")
    add(f"| material | {prof['material']}, {prof['density']:g} g/cm^3 |")
    if fab is not None:
        add("")
        add("Expected printed mass per rod (plastic at that density plus its metal balls): "
            + ", ".join(f"{f.file_stem} {f.mass:.2f} g" for f in fab.rods) + ".")
    add("")
    add("## Printing and assembly")
    add("")
    if fab is not None:
        add("1. Open `print.3mf` in PrusaSlicer (2.5 or newer): every rod is on the bed, in print orientation, "
            "with the print settings the masses assume (100 % infill) and a pause (M601) at each layer where "
            f"balls go in or shot is poured ({_pauses(fab.parts, prof)}), its message naming the rods whose "
            "inserts go in there; the other rods print on through it. Rods that do not fit one bed continue "
            "on `print-2.3mf`, .... Each `rods/NN_TYPE.3mf` is a project of that rod alone, with the same "
            "settings and its own pauses. Other slicers: print each file of `rods/` (`.stl` or `.step`) as "
            "it lies.")
        add("2. Rods with balls: at each pause drop the balls the message names into the sockets and resume "
            "(without the project: pause at the Z height in the table, e.g. PrusaSlicer's 'Add pause print'). "
            "Rods with a chamber to fill: pause at the Z height in the table (the top of the chamber), pour "
            "the grams of shot the table lists (level with the top, every cell alike), resume.")
    else:
        add("1. Build the solids first: run `rodcad build` without `--no-cad`.")
    add(f"3. Lay the rods out in order 0 to {r.n - 1} (the number leads each file name). Rod k's "
        "second joint takes rod k+1's first joint; push a pin through both.")
    add(f"4. Pin rod 0's first joint to anchor A and rod {r.n - 1}'s second joint to anchor B, "
        f"{d.span:.1f} mm apart (B at ({b[0] - a[0]:+.1f}, {b[1] - a[1]:+.1f}) mm from A).")
    add("5. Let go gently: the chain settles into the shape of preview.png" +
        ("." if r.unique else "; several stable shapes exist, so guide it into the designed one."))
    add("")
    return "\n".join(L)


def _deg(x: float | None) -> str:
    return "free" if x is None else f"{x:.1f}"


def _end_text(e: dict[str, float]) -> str:
    """One end of a rod for report.md: 'free' (setback > 0: it stops nowhere near the
    bends it is used at), or the chamfers of its flush faces ('top 12.5', 'bottom -3')."""
    if e["setback"]:
        return "free"
    return f"top {e['top_chamfer']:.4g}, bottom {e['bottom_chamfer']:.4g}"


def _of_size(cv: dict[str, Any]) -> str:
    """', 0.68 % of the target's 200 mm size' where the target is larger than its span."""
    size, rel = cv.get("size_mm"), cv.get("rel_size")
    if size is None or rel is None or cv.get("rel_span") is None or rel >= 0.67 * cv["rel_span"]:
        return ""
    return f", {100 * rel:.3g} % of the target's {size:.4g} mm size"


def _joints_text(r) -> str:
    """Which joints hang freely, which rest on stops, what the anchor fixture holds."""
    n = r.n
    on = set(int(j) for j in (r.plan.added_stops if r.plan is not None else []))
    lim = np.asarray(r.limits, float).reshape(-1, 2)
    bends = np.diff(r.equilibrium.angles)
    on |= {j for j in range(n - 1) if np.any(np.abs(lim[j] - bends[j]) < 1e-9)}
    pieces = r.plan.fused if r.plan is not None else []
    fused = {j for a, b in pieces for j in range(a, b)}
    both = {j for j in range(n - 1) if lim[j, 0] == lim[j, 1] and j not in fused}  # two-sided stops
    on -= fused | both
    free = [j for j in range(n - 1) if j not in on and j not in fused and j not in both]
    text = (f"{len(free)} of {n - 1} hang freely ({', '.join(map(str, free)) or 'none'}), "
            f"{len(on)} rest on stops ({', '.join(map(str, sorted(on))) or 'none'})")
    if both:
        text += f", {len(both)} held both ways by two-sided stops ({', '.join(map(str, sorted(both)))})"
    if fused:
        text += (f", {len(fused)} fused ({', '.join(map(str, sorted(fused)))}; one piece each: rods "
                 + ", ".join(f"{a}-{b}" for a, b in pieces) + ")")
    info = getattr(r.equilibrium, "info", {}) or {}
    held = np.asarray(info.get("end_active", np.zeros(2)), int)
    moments = np.asarray(info.get("end_moments", np.zeros(2)), float)
    ends = [f"{'A' if k == 0 else 'B'} holds the {'first' if k == 0 else 'last'} rod "
            f"({abs(moments[k]) * 1e-6:.3g} N m)" for k in range(2) if held[k]]
    if ends:
        text += "; the anchor fixture: " + ", ".join(ends)
    elif r.end_limits is not None:
        text += "; the anchor fixture's stops carry nothing"
    return text


def summary_text(r, outdir: Path | None) -> str:
    """The one-screen summary printed at the end of ``rodcad build`` (from the result itself)."""
    L = [f"rodcad: {r.design.name}: {r.n} rods from catalog {r.design.catalog.name}, "
         f"method {r.method or 'simulate'}, {r.time_s:.1f} s"]
    if r.distance is not None:
        L.append(f"  shape error   {_fmt_err(r.distance.as_dict())}")
    if r.plan is not None:
        curvature = np.array([r.design.catalog[n].curvature for n in r.type_names])
        cv = curve_error(r.plan.curve, r.equilibrium.points, curvature, r.design.span)
        L.append(f"  vs the curve  the rods' centrelines hang within {cv['max_mm']:.3g} mm of the target curve "
                 f"({100 * cv['rel_span']:.3g} % of the span{_of_size(cv)})"
                 + (f"; {len(r.plan.added_stops)} joint(s) on stops{' or fused' if r.plan.fused else ''}"
                    if r.plan.added_stops else ""))
        if r.end_limits is not None or r.plan.added_stops:
            L.append(f"  joints        {_joints_text(r)}")
    hw = hardware_summary(r)
    if hw is not None:
        L.append(f"  joint parts   {hw}")
    if r.as_built is not None:
        L.append(f"  as built      {_fmt_err(r.as_built.distance.as_dict())}")
    if getattr(r, "as_printed", None) is not None:
        size = float(cv["size_mm"]) if r.plan is not None else float(r.design.span)
        L.append(f"  as printed    {printed_summary(r.as_printed, size)}")
    eq = r.equilibrium
    L.append(f"  equilibrium   {'stable' if eq.stable else 'NOT STABLE'}, "
             f"{'unique' if r.unique else str(r.n_stable) + ' stable shapes found'}, "
             f"KKT {eq.kkt_residual:.1e}")
    bom = bill_of_materials(r)
    rods = ", ".join(f"{v} x {k}" for k, v in bom["rods"].items())
    L.append(f"  rods          {rods}")
    if "filament_g" in bom:
        balls = ", ".join(f"{b['count']} x {ball_text(b['diameter_mm'], b.get('kind') or '')}"
                          for b in bom["metal_balls"]) or "none"
        balls += "".join(f"; {b['grams']:.1f} g of {b['name']}" for b in bom.get("fill", []))
        pins = ("pins: " + ", ".join(f"{v} x {k} mm" for k, v in bom["pins"]["diameters_mm"].items())
                if "diameters_mm" in bom["pins"] else f"pins: {bom['pins']['count']} x {bom['pins']['diameter_mm']:g} mm")
        L.append(f"  filament      {bom['filament_g']:.1f} g; metal balls: {balls}; {pins}")
    for note in r.notes:
        L.append(f"  note: {note}")
    if outdir is not None:
        files = "design.json, report.md, preview.png, view.html, assembly.glb"
        if r.fabrication is not None:
            files += ", assembly.step, print.3mf, rods/*.step|stl|3mf"
        if getattr(r, "fixture", None) is not None:
            files += ", fixture.step|stl"
        L.append(f"  files         {outdir}/ ({files})")
    return "\n".join(L)


def chandelier_summary(b, outdir: Path) -> str:
    """The summary printed at the end of ``rodcad build`` for a chandelier."""
    from rodcad.design.shell import curve_size

    res = b.result
    L = [f"rodcad: {b.design.name}: chandelier of {len(res.chains)} chains, {res.bom.n_rods} rods, "
         f"method {res.method}, {b.time_s:.1f} s"]
    for k, ch in enumerate(res.chains):
        ab = (f", as built {100 * b.as_built[k].distance.max_rel_span:.3g} %"
              if b.as_built is not None else "")
        L.append(f"  {ch.name:<10} {len(ch.type_names):>3} rods  max error {ch.distance.max:.3g} mm "
                 f"({100 * ch.distance.max_rel_span:.3g} % of span{ab})")
        if b.chains:
            r = b.chains[k]
            hw, ap = hardware_summary(r), getattr(r, "as_printed", None)
            if hw:
                L.append(f"  {'':<10} joints   {hw}")
            if ap is not None:
                L.append(f"  {'':<10} printed  {printed_summary(ap, curve_size(r.plan.curve))}")
    L.append("  rods      " + ", ".join(f"{v} x {k}" for k, v in res.bom.rods_by_type.items()))
    if b.fabrications is not None:
        filament = sum(f.filament_mass for fab in b.fabrications for f in fab.rods)
        L.append(f"  filament  {filament:.1f} g for the rods; frame in frame.stl")
    for note in b.notes:
        L.append(f"  note: {note}")
    L.append(f"  files     {outdir}/")
    return "\n".join(L)


def _chandelier_hardware(b, data_chains: list[dict[str, Any]]) -> list[str]:
    """report.md's "Joint hardware" of a chandelier: per chain (chains that share a design
    once), what its joints got, its friction band and where it rests after tapping."""
    if not b.chains or all(r.hardware is None for r in b.chains):
        return []
    L = ["", "## Joint hardware", "",
         "Each joint of each chain has the cheapest hardware of the catalog that carries its load and keeps "
         "the chain's friction band within a tenth of the tolerance (0.1 % of the chain's size at most); "
         "design.json's `chains[].hardware` lists it pin by pin (pin 0 at the A lug).", ""]
    chains = b.result.chains
    for k, (ch, r) in enumerate(zip(chains, b.chains)):
        if ch.shared_with is not None:
            continue
        same = [c.name for c in chains if c.shared_with == ch.name]
        who = f"`{ch.name}`" + (f" (and {', '.join(f'`{n}`' for n in same)}: the same chain)" if same else "")
        size = float(data_chains[k]["curve"]["size_mm"])
        text = f"- {who}: {hardware_summary(r) or 'no hardware chosen'}"
        ap = r.as_printed
        if ap is not None and ap.friction is not None:
            text += f"; it rests within {ap.friction.band:.3g} mm ({100 * ap.friction.band / size:.3g} % of its size)"
        L.append(text)
        tapped = tapping_sentence(r, size)
        if tapped:
            L.append("  " + tapped[2:])
        L += [f"  - Note: {n}" for n in (r.hardware.notes if r.hardware is not None else [])]
    return L


def chandelier_markdown(b, data: dict[str, Any]) -> str:
    """report.md of a chandelier: inputs, per-chain errors, frame, bill of materials, assembly."""
    d = b.design
    L = [f"# {d.name}: chandelier report", ""]
    if d.description:
        L += [d.description.strip(), ""]
    c = d.chandelier
    L += [f"Made by rodcad {__version__} from `{d.path}` in {b.time_s:.1f} s.", "", "## Inputs", "",
          f"- Catalog: `{d.catalog.name}`",
          f"- Pattern: {c.pattern} with {len(data['chains'])} chains "
          + ", ".join(f"{k} = {v}" for k, v in c.params.items()),
          f"- Method: {data['method']}, seed {data['seed']}", "", "## Chains", "",
          "| chain | rods | mass g | max error mm | % of span | as built % | stable | unique |",
          "|---|---|---|---|---|---|---|---|"]
    for ch in data["chains"]:
        ab = f"{100 * ch['as_built']['error']['max_rel_span']:.3g}" if "as_built" in ch else "-"
        mass = sum(r["mass"] for r in ch["rods"])
        L.append(f"| {ch['name']} | {len(ch['rods'])} | {mass:.1f} | {ch['error']['max_mm']:.3g} "
                 f"| {100 * ch['error']['max_rel_span']:.3g} | {ab} | {'yes' if ch['simulated']['stable'] else 'NO'} "
                 f"| {'yes' if ch['simulated']['unique'] else 'no'} |")
    L += ["", "![preview](preview.png)", "", view_line(), ""]
    for note in b.notes:
        L.append(f"- Note: {note}")
    L += _chandelier_hardware(b, data["chains"])
    if "frame" in data:
        f = data["frame"]
        L += ["", "## Frame", "",
              f"- `frame.step` / `frame.stl`: {f['size_mm'][0]:.0f} x {f['size_mm'][1]:.0f} x "
              f"{f['size_mm'][2]:.1f} mm, valid {f['valid']}, fits the printer: {f['fits_printer']}",
              f"- Closest rod at rest: {f['closest_rod_mm']:.2f} mm from the frame"]
    bom = data["bill_of_materials"]
    L += ["", "## Bill of materials", ""]
    for name, count in bom["rods_by_type"].items():
        L.append(f"- {count} x rod `{name}`")
    if bom.get("hardware"):
        L += [f"- {e['joints']} joint(s) with {e['option']}: {e['description']}; {e['pins']['count']} x "
              f"{e['pins']['diameter_mm']:g} mm pin cut to {e['pins']['length_mm']:g} mm"
              + (f", {e['sleeves']['count']} x sleeve {e['sleeves']['outer_diameter_mm']:g} mm OD" if "sleeves" in e
                 else "")
              + (f", {e['bearings']['count']} x bearing {e['bearings']['bore_mm']:g} x "
                 f"{e['bearings']['outer_diameter_mm']:g} x {e['bearings']['width_mm']:g} mm" if "bearings" in e
                 else "") for e in bom["hardware"]]
        L.append(f"- ({bom['pins']} joints between rods and {bom['anchor_pins']} through the frame's lugs)")
    else:
        L.append(f"- {bom['pins']} pins between rods and {bom['anchor_pins']} pins through the frame's lugs")
    if "filament_g" in bom:
        L.append(f"- Filament for the rods: {bom['filament_g']:.1f} g")
        for ball in bom["metal_balls"]:
            L.append(f"- {ball['count']} x {ball_text(ball['diameter_mm'], ball.get('kind') or '')}")
    L.append(f"- Total rod mass: {bom['total_mass_g']:.1f} g")
    L += ["", "## Assembly", "",
          "1. Print the frame and every chain's rods: `<chain>/print.3mf` (PrusaSlicer) holds a chain's rods "
          "with the print settings and a pause at each layer where balls go in, naming the rods; "
          "`<chain>/rods/` has each rod in print orientation.",
          "2. Assemble each chain in index order (rod k's second joint takes rod k+1's first, one pin each).",
          "3. Pin each chain's first rod to its A lug and its last rod to its B lug, chain by chain in the "
          "order of `assembly.step`.", ""]
    return "\n".join(L)
