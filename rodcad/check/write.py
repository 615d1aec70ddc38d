"""What ``rodcad check`` writes: the preview, and for ``--rebalance`` the output folder
again, with the re-designed rods, a new design.json, report.md and assembly.

The folder is written like every rodcad output (:func:`rodcad.outdir.staged_output`): a
copy of OUTDIR with the changed files replaced, renamed into place only when everything
is written, so a failed run leaves OUTDIR as it was. Only the rods whose mass changed get
new STEP/STL files; an edited rod keeps its STEP as saved (or gets one, when it was read
from an assembly) and gets an STL that matches it; the other files are copied as they are.
"""

from __future__ import annotations

import copy
import math
import shutil
import time
from pathlib import Path
from typing import Any

import numpy as np

from optimize import shape_distance
from optimize.chain.curves import centerline
from rodcad.design.asprinted import hole_frame
from rodcad.cad.export import export_assembly
from rodcad.cad.printfile import write_print_files
from rodcad.cad.reread import write_rod_step, write_rod_stl
from rodcad.cad.chainfiles import chain_parts, write_rod_files
from rodcad.cad.rods import ChainFabrication
from rodcad.check.rebalance import Rebalanced
from rodcad.check.recheck import CheckResult, equilibrium_json, with_hardware
from rodcad.outdir import MARKER, staged_output
from rodcad.outputs.design_json import (
    ball_text,
    curve_error,
    fabrication_json,
    metal_balls,
    print_profile,
    write_json,
)
from rodcad.outputs.preview import draw_rods, finish_figure

__all__ = ["plot_check", "rebalanced_json", "report_section", "write_rebalanced"]

#: Files of OUTDIR a re-balance writes again (the rods it changes come on top).
REWRITTEN = ("design.json", "report.md", "preview.png", "preview.svg", "assembly.step", MARKER)

#: Slicer files of OUTDIR a re-balance writes again from the rods as they are now
#: (their meshes and pauses would print the old chain).
STALE = ("*.3mf",)


def _curvatures(res: CheckResult) -> list[float]:
    return [float(r.params.get("curvature") or 0.0) for r in res.built.rods]


def plot_check(res: CheckResult, *paths: Path, rb: Rebalanced | None = None) -> None:
    """Draw the check: the target (dashed, its joints open circles), the designed chain
    (thin grey), the chain as it is now with its rods coloured by mass (edited rods
    outlined in black) and, after a re-balance, the re-balanced chain as built (dotted).
    Saved to every path (PNG, SVG, ...)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    b = res.built
    curv = _curvatures(res)
    fig, ax = plt.subplots(figsize=(8, 6))
    curve = res.types.target_curve
    if curve is not None:
        ax.plot(*np.asarray(curve).T, "--", color="0.45", lw=1.2, label="target")
    ax.plot(*b.target.T, "o", mfc="none", mec="0.35", ms=6, label="target joints")
    ax.plot(*centerline(b.simulated, curv).T, "-", color="0.6", lw=1.0, label="as designed")
    final = rb.as_built.points if rb is not None else res.equilibrium.points
    masses = rb.masses if rb is not None else res.masses
    lc, segs = draw_rods(ax, final, curv, masses)
    edited = res.edited
    if edited:  # outlined in black, under the rods
        ax.add_collection(LineCollection([segs[i] for i in edited], colors="k", linewidths=9, capstyle="round",
                                         zorder=2))
    if rb is not None:
        ax.plot(*centerline(res.equilibrium.points, curv).T, ":", color="k", lw=1, zorder=5,
                label="with the edits, before re-balancing")
    shift = final - b.simulated
    biggest = float(np.max(np.hypot(*shift.T)))
    if biggest > 1e-9 * b.span:  # joint shifts are far below the line width: draw them magnified
        k = 0.08 * b.span / biggest
        ax.quiver(*b.simulated.T, *(k * shift).T, angles="xy", scale_units="xy", scale=1, color="tab:green",
                  width=0.004, zorder=7, label=f"joint shift from the design x {k:.3g}")
    name = b.data.get("name") or b.outdir.name
    title = f"{name}: {b.n} rods, {len(edited)} edited (outlined)"
    if rb is None:
        d = res.vs_design
        title += (f"\nnow {100 * d.max_rel_span:.3g} % of the span from the design, "
                  f"{100 * res.vs_target.max_rel_span:.3g} % from the target")
    else:
        title += (f"; re-balanced {len(rb.redesigned)}\nas built {100 * rb.vs_target.max_rel_span:.3g} % of the "
                  f"span from the target (edits alone: {100 * res.vs_target.max_rel_span:.3g} %)")
    finish_figure(fig, ax, lc, b.anchors, title, paths)


def _bill(data: dict[str, Any]) -> None:
    """Filament, balls and total mass of the bill of materials from the rods' fabrication."""
    bom = data.setdefault("bill_of_materials", {})
    fabs = [r["fabrication"] for r in data["rods"]]
    bom["filament_g"] = float(sum(f["filament_g"] for f in fabs))
    balls: dict[tuple[float, str], int] = {}
    for f in fabs:
        if f.get("balls") and f.get("ball_diameter_mm") is not None:
            key = (float(f["ball_diameter_mm"]), str(f.get("ball_kind") or ""))
            balls[key] = balls.get(key, 0) + int(f["balls"])
    bom["metal_balls"] = metal_balls(balls)
    shot: dict[str, float] = {}
    for f in fabs:
        fill = f.get("fill")
        if isinstance(fill, dict) and fill.get("grams"):
            shot[str(fill.get("name"))] = shot.get(str(fill.get("name")), 0.0) + float(fill["grams"])
    if shot or "fill" in bom:
        bom["fill"] = [{"name": k, "grams": v} for k, v in sorted(shot.items())]
    bom["total_mass_g"] = float(sum(f["mass"] for f in fabs))


def rebalanced_json(res: CheckResult, rb: Rebalanced) -> dict[str, Any]:
    """design.json after a re-balance: the edited rods with their measured numbers, the
    re-designed ones with their new masses and fabrication, the new designed and as-built
    chain, and a ``round_trip`` record of what changed."""
    data = copy.deepcopy(res.built.data)
    b = res.built
    cd = rb.design
    span = b.span
    hung_m, hung_c = with_hardware(b, res.masses, res.com)  # with the joint hardware's metal, as they hang
    for i, rod in enumerate(data["rods"]):
        r = res.readings[i]
        fab = rod["fabrication"]
        if rod.get("hardware") and (r.edited or i in rb.fabricated):
            rod["hardware"]["printed_mass"] = float(r.mass if r.edited else rb.fabricated[i].mass)
        if r.edited:
            rod["mass"] = float(hung_m[i])
            rod["com"] = [float(v) for v in hung_c[i]]
            if "holes_mm" in rod:  # design.json's com is in the hole frame (contract.md "As printed")
                rod["com_rod_frame"] = rod["com"]
                rod["com"] = [float(v) for v in hole_frame([b.lengths[i]], [hung_c[i]], [rod["holes_mm"]])[1][0]]
            fab.update({"mass": float(r.mass), "com": [float(v) for v in r.com],
                        "filament_g": float(r.mass - b.rods[i].ball_mass - b.rods[i].fill_mass),
                        "plastic_volume_mm3": float(r.volume), "edited": True,
                        "message": "edited by hand; kept as it is by `rodcad check --rebalance`"})
        elif i in rb.fabricated:
            rod["mass"] = float(cd.result.masses[i])
            rod["fabrication"] = fabrication_json(rb.fabricated[i])
    eq = cd.check.equilibrium
    data["simulated"] = {**equilibrium_json(eq), "unique": bool(cd.check.unique),
                         "stable_equilibria_found": int(cd.check.n_stable)}
    data["error"] = shape_distance(b.target, eq.points).as_dict()
    data["as_built"] = {"masses": [float(v) for v in rb.masses], "com": [[float(x), float(y)] for x, y in rb.com],
                        "points": [[float(x), float(y)] for x, y in rb.as_built.points],
                        "error": rb.vs_target.as_dict(), "stable": bool(rb.as_built.stable)}
    curve = res.types.target_curve
    curv = np.array(_curvatures(res))
    if curve is not None:
        data["curve"] = curve_error(curve, eq.points, curv, span)
        data["as_built"]["curve"] = curve_error(curve, rb.as_built.points, curv, span)
    else:
        data.pop("curve", None)
    res_inv = cd.result
    data["inverse"] = {"exact": bool(res_inv.exact), "statics_residual": _num(res_inv.statics_residual),
                       "at_bounds": [int(v) for v in res_inv.at_bounds], "nfev": int(res_inv.nfev),
                       "time_s": float(res_inv.time_s), "message": res_inv.message}
    tol = data.get("tolerance")
    data["meets_tolerance"] = bool(tol is None or data["error"]["max_rel_span"] <= tol)
    _bill(data)
    data["notes"] = list(data.get("notes") or []) + list(rb.notes)
    data.setdefault("round_trip", [])
    if not isinstance(data["round_trip"], list):
        data["round_trip"] = []
    data["round_trip"].append({
        "date": time.strftime("%Y-%m-%dT%H:%M:%S"), "edited": res.edited, "redesigned": list(rb.redesigned),
        "before": {"masses": [float(r.mass) for r in b.rods], "points": [[float(x), float(y)] for x, y in b.simulated]},
        "with_edits": {"points": [[float(x), float(y)] for x, y in res.equilibrium.points],
                       "error": res.vs_target.as_dict(), "error_vs_design": res.vs_design.as_dict()},
        "error_vs_original_design": rb.vs_design.as_dict(), "balanced": bool(rb.ok)})
    return data


def _num(x: float) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def report_section(res: CheckResult, rb: Rebalanced | None) -> str:
    """Markdown: the rods as re-read, what was re-designed and how the chain hangs now."""
    b = res.built
    L = ["## Round trip: re-checked after manual edits (`rodcad check" + (" --rebalance" if rb else "") + "`)", ""]
    L.append(f"{time.strftime('%Y-%m-%d %H:%M')}: {len(res.edited)} edited rod(s); "
             + ("the tables further down are those of the original build." if rb else ""))
    L.append("")
    L.append("| # | type | built g | now g | change | com shift mm | edited | re-designed g |")
    L.append("|---:|---|---:|---:|---:|---:|:---:|---:|")
    for r, rod in zip(res.readings, b.rods):
        new = ""
        if rb is not None and r.index in rb.fabricated:
            new = f"{rb.fabricated[r.index].mass:.4f}"
        L.append(f"| {r.index} | {rod.type} | {rod.mass:.4f} | {r.mass:.4f} | {100 * r.mass_change:+.3f} % | "
                 f"{r.com_shift:.4f} | {'yes' if r.edited else ''} | {new} |")
    L.append("")
    d, t = res.vs_design, res.vs_target
    L.append(f"- With the edits the chain hangs up to {d.max:.3g} mm ({100 * d.max_rel_span:.3g} % of the span) from "
             f"the designed shape and {t.max:.3g} mm ({100 * t.max_rel_span:.3g} %) from the target.")
    if rb is not None:
        L.append(f"- Re-balanced ({'balanced' if rb.ok else 'NOT balanced: best fit'}): {len(rb.redesigned)} rod(s) "
                 f"re-designed and rebuilt ({', '.join(map(str, rb.redesigned)) or 'none'}); as built the chain "
                 f"hangs {rb.vs_target.max:.3g} mm ({100 * rb.vs_target.max_rel_span:.3g} % of the span) from the "
                 f"target and {rb.vs_design.max:.3g} mm from the original design.")
        for i, f in sorted(rb.fabricated.items()):
            balls = f", {f.ball_count} x {ball_text(f.ball_diameter, f.ball_name)} (pause at {f.pause_z:.2f} mm)" if f.ball_count \
                else ""
            L.append(f"  - rod {i} ({f.type_name}): {f.mass:.4f} g, {f.cavity_count} cavities{balls}; print "
                     f"`rods/{f.file_stem}.step` again")
    notes = [n for n in res.notes if rb is None or "--rebalance`" not in n]
    for n in notes + (rb.notes if rb is not None else []):
        L.append(f"- {n}")
    L.append("")
    return "\n".join(L)


def _copy_tree(src: Path, dst: Path, skip: set[Path]) -> None:
    for p in sorted(src.iterdir()):
        rel = p.relative_to(src)
        if p in skip:
            continue
        if p.is_dir() and not p.is_symlink():
            (dst / rel).mkdir(parents=True, exist_ok=True)
            _copy_tree(p, dst / rel, skip)
        elif p.is_file():
            shutil.copy2(p, dst / rel)


def _print_rods(res: CheckResult, rb: Rebalanced, stems: list[str]) -> list[Any]:
    """Every rod as the slicer project needs it: the rebuilt ones as fabricated, the others
    (edited or untouched) as read now, with their recorded balls and shot."""
    from types import SimpleNamespace

    out: list[Any] = []
    for i, r in enumerate(res.readings):
        if i in rb.fabricated:
            out.append(rb.fabricated[i])
            continue
        b = res.built.rods[i]
        kinds = res.types.rods[i].ball_kinds
        count = int(np.asarray(b.ball_centers).reshape(-1, 3).shape[0])
        # the kind recorded in design.json (by diameter and name), else the catalog's first
        balls = next((k for k in kinds if b.ball_diameter is not None and abs(k.diameter - b.ball_diameter) < 1e-9
                      and (not b.ball_kind or k.name == b.ball_kind)), kinds[0] if kinds else None)
        out.append(SimpleNamespace(
            index=i, file_stem=stems[i], solid=r.solid, print_matrix=np.asarray(b.print_matrix, float),
            plastic_volume=float(r.volume), ball_count=count,
            ball_diameter=None if balls is None or not count else balls.diameter,
            ball_name="" if balls is None or not count else balls.name,
            socket_centers=np.asarray(b.ball_centers, float).reshape(-1, 3),
            socket_radius=0.0 if balls is None else balls.socket_diameter / 2, socket_height=b.socket_height, pause_zs=(),
            print_note="", fill_mass=float(b.fill_mass), fill_name=""))
    return out


def write_rebalanced(res: CheckResult, rb: Rebalanced, outdir: Path, *, from_assembly: bool = False) -> dict[str, Any]:
    """Write the re-balanced chain to ``outdir`` (OUTDIR itself, or OUTDIR.best-fit):
    OUTDIR's files, with the re-designed rods' STEP/STL (and the edited rods', when they
    were read from an assembly), design.json, report.md, previews and assembly.step
    written again. Staged: all or nothing.

    Returns:
        The new design.json.
    """
    b = res.built
    src = b.outdir
    stems = [r.stem for r in b.rods]
    rewrite = {src / n for n in REWRITTEN}
    for i in rb.fabricated:
        rewrite |= {src / "rods" / f"{stems[i]}.step", src / "rods" / f"{stems[i]}.stl"}
    for i in res.edited:
        rewrite.add(src / "rods" / f"{stems[i]}.stl")
        if from_assembly:
            rewrite.add(src / "rods" / f"{stems[i]}.step")
    stale = sorted({p for pattern in STALE for p in src.rglob(pattern) if p.is_file()})
    if stale:  # written again below, from the rods as they are now
        rb.notes.append("print.3mf and rods/*.3mf written again from the rods as they are now (the edited "
                        "rods as saved, the re-designed ones rebuilt)")
    rewrite |= set(stale)
    views = {src / "view.html", src / "assembly.glb"}
    if any(p.is_file() for p in views):  # the build's 3D view shows the chain before the re-balance
        rewrite |= views
        rb.notes.append("view.html and assembly.glb (the 3D view) are left out: they showed the chain before the "
                        "re-balance; `rodcad build` writes them for a design")
    data = rebalanced_json(res, rb)
    old_report = (src / "report.md").read_text(encoding="utf-8") if (src / "report.md").is_file() else ""
    with staged_output(outdir) as tmp:
        _copy_tree(src, tmp, rewrite)
        (tmp / "rods").mkdir(exist_ok=True)
        if rb.fabricated:
            write_rod_files(ChainFabrication([rb.fabricated[i] for i in sorted(rb.fabricated)], []), tmp)
        for i in res.edited:  # the STEP as saved (or from the assembly), its STL to match
            if from_assembly:
                write_rod_step(res.readings[i].solid, b.rods[i].print_matrix, tmp / "rods" / f"{stems[i]}.step",
                               stems[i])
            else:
                write_rod_stl(res.readings[i].solid, b.rods[i].print_matrix, tmp / "rods" / f"{stems[i]}.stl")
        solids = [rb.fabricated[i].solid if i in rb.fabricated else r.solid for i, r in enumerate(res.readings)]
        pins = [(b.rods[min(j, b.n - 1)].pin_diameter, b.rods[min(j, b.n - 1)].thickness) for j in range(b.n + 1)]
        points = np.array(data["simulated"]["points"], float)
        export_assembly(tmp / "assembly.step", chain_parts(stems, solids, points, list(rb.masses), pins),
                        str(data.get("name") or "chain"))
        write_json(tmp / "design.json", data)
        write_print_files(_print_rods(res, rb, stems), tmp, printer=res.types.catalog.printer,
                          profile=data.get("print") or print_profile(res.types.catalog))
        plot_check(res, tmp / "preview.png", tmp / "preview.svg", rb=rb)
        head, sep, rest = old_report.partition("\n")
        text = (head + sep + "\n" + report_section(res, rb) + "\n" + rest) if old_report else report_section(res, rb)
        (tmp / "report.md").write_text(text, encoding="utf-8")
    return data
