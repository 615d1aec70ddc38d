"""The pipeline of a net: a design file with a ``net:`` block in, numbers, report and
pictures out. It sequences the steps and owns none of them::

    design.yaml + catalog -> load_design() (net: rodcad.design.net.target)  rodcad.design.loader
    -> hardware, lengths, mass bounds, hub masses                      rodcad.design.net.plan.plan_net
    -> masses (optimize.design_net), exact equilibrium                 rodcad.design.net.check.design_net_plan
    -> the planner's edits, the design kept, its multi-start           rodcad.design.net.choose.design_drawn_net
    -> each distinct hub and rod built once (Dask tasks), the net as built (with CAD)  rodcad.cad.net.build
    -> design.json, report.md, preview.png; rods/, hubs/, assembly.step  rodcad.outputs.net, rodcad.cad.net.build
    -> print.3mf, rods/*.3mf, hubs/*.3mf (PrusaSlicer, with pauses)    rodcad.cad.net.print_files
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rodcad.design.model import Design
from rodcad.design.net.check import NetCheck
from rodcad.design.net.choose import design_drawn_net
from rodcad.outputs.design_json import print_profile
from rodcad.outputs.net.design_json import net_json
from rodcad.outputs.net.preview import plot_net
from rodcad.outputs.net.report import net_report
from rodcad.outputs.view import write_net_view
from rodcad.pipeline.folder import staged, write_design
from rodcad.progress import Progress

__all__ = ["NetBuild", "build_net", "write_net_outputs"]


@dataclass
class NetBuild:
    """One run of a net design.

    Attributes:
        design: the validated design.
        check: the designed net, its equilibrium and fit.
        seed: the multi-start's seed.
        solids: the hubs' and rods' solids and the net as built (with CAD), or None.
    """

    design: Design
    check: NetCheck
    seed: int
    solids: Any = None  # rodcad.cad.net.solids.NetSolids when the solids were built

    @property
    def ok(self) -> bool:
        return self.check.ok and self.as_built_ok

    @property
    def as_built_ok(self) -> bool:
        """Without CAD, or the net as built within the tolerance of the design."""
        return self.solids is None or bool(self.solids.rel_size <= self.check.tolerance)  # (NaN: no equilibrium)

    @property
    def as_built_stalled(self) -> bool:
        """The as-built net's solver stopped short of round-off (see
        :data:`rodcad.cad.net.solids.AS_BUILT_KKT`): its error is read where it stopped."""
        return self.solids is not None and not self.solids.as_built.success

    def limit(self) -> str:
        """What keeps the net off its target and what would reach it; where the planner
        collapsed drawn nodes, how much larger the net drawn would keep them."""
        from rodcad.design.net.collapse import collapse_hint

        said = self.check.limit()
        hint = "" if self.check.ok else collapse_hint(self.check.plan)
        return said.rstrip(".") + hint if hint else said


def build_net(design: Design, *, seed: int | None = None, cad: bool = False, jobs: int | None = None,
              scheduler: str | None = None, progress: Progress | None = None) -> NetBuild:
    """Design a net: hardware and rods on the target, masses, the exact equilibrium; with
    ``cad``, its distinct parts built (each a task: in this process, or on Dask workers,
    :func:`rodcad.parallel.task_runner`: ``scheduler`` an existing Dask scheduler's address,
    ``jobs`` a local cluster of that many worker processes, by default one when the net has
    enough distinct parts to be worth it).

    Raises:
        DesignLimit: rods the catalog cannot print, nodes too crowded for the hubs.
    """
    progress = progress or Progress(quiet=True)
    seed = design.seed if seed is None else int(seed)
    t = design.net
    with progress.step(f"laying hubs and rods on the target ({t.n} nodes, {t.m} edges), designing the masses "
                       "and solving the net (exact equilibrium, multi-start)") as st:
        check = design_drawn_net(t, design.catalog, g=design.g, seed=seed, tolerance=design.tolerance,
                                 note=st.note)
        plan = check.plan
        st.note(f"{plan.target.m} rods, mass bounds {plan.bounds[:, 0].min():.3g}-{plan.bounds[:, 1].max():.3g} g")
    solids = None
    if cad:
        from rodcad.cad.net.build import build_net_solids, distinct_count
        from rodcad.parallel import task_runner

        prof = print_profile(design.catalog)
        parts = distinct_count(check)
        with task_runner(parts, jobs=jobs, scheduler=scheduler) as (runner, where):
            with progress.step(f"building the {parts} distinct hubs and rods (B-rep, files, checks; {where}) "
                               "and the net as built") as st:
                solids = build_net_solids(check, printer=design.catalog.printer,
                                          layer_height=float(prof["layer_height"]), runner=runner, progress=st)
    return NetBuild(design, check, seed, solids)


def write_net_outputs(b: NetBuild, outdir: str | Path, *, progress: Progress | None = None) -> dict[str, Any]:
    """Write design.json, report.md and preview.png to ``outdir`` (staged: a failed run
    leaves it as it was). Returns the data written to design.json."""
    d = b.design
    with staged(outdir, progress) as (tmp, progress):
        files = []
        if b.solids is not None:
            from rodcad.cad.net.build import write_net_files

            from rodcad.cad.net.print_files import write_net_print_files

            with progress.step("writing and checking rods/*, hubs/* (STEP, STL) and assembly.step") as st:
                files = write_net_files(b.check, b.solids, tmp, name=d.name, progress=st)
            what = "writing print.3mf (PrusaSlicer projects, one per bed) and rods/*.3mf, hubs/*.3mf"
            with progress.step(what) as st:
                files += write_net_print_files(b.check, b.solids, tmp, printer=d.catalog.printer,
                                               profile=print_profile(d.catalog), ball_name=_ball_name(d.catalog),
                                               progress=st.count)
        with progress.step("writing design.json, report.md, preview.png"):
            data = _write(b, tmp, files)
            write_net_view(b, data, tmp)  # assembly.glb, view.html
    return data


def _parts_json(s) -> list[dict[str, Any]]:
    """design.json's ``cad.parts``: each distinct printed part (a rod, a hub or a hub's half)
    once, with how many to print, for which rods or nodes, its solid's and its mesh's volume."""
    out = []
    for part in s.parts:
        for i, (solid, mesh_volume) in enumerate(zip(part.solids, part.mesh_volumes)):
            vol = float(solid.volume)
            out.append({"name": solid.label, "kind": part.kind, "count": part.prints(i),
                        "members": [int(m) for m in part.members], "volume_mm3": round(vol, 4),
                        "mesh_volume_mm3": round(float(mesh_volume), 4),
                        "mesh_volume_rel": round(float(mesh_volume) / vol - 1, 6)})
    return out


def _finite(x: float) -> float | None:
    """A float for design.json, None where it is not finite (JSON has no NaN)."""
    return float(x) if np.isfinite(x) else None


def _ball_name(catalog) -> str:
    """The name of the steel balls that weigh the net's rods down ('' without)."""
    balls = next(iter(catalog)).balls
    return str(balls.name) if balls is not None else ""


def _write(b: NetBuild, tmp: Path, files: list[str]) -> dict[str, Any]:
    """design.json (with the as-built net and the files when the solids were built), the
    preview and report.md, into ``tmp``."""
    d = b.design
    data = net_json(b.check, name=d.name, seed=b.seed, catalog=d.catalog, print_profile=print_profile(d.catalog))
    s = b.solids
    if s is not None:
        data["as_built"] = {"masses": [float(x) for x in s.rod_masses],
                            "node_masses": [float(x) for x in s.node_masses],
                            "node_com": [[float(v) for v in c] for c in s.node_com],
                            "simulated": [[float(v) for v in p] for p in s.as_built.positions],
                            "stable": bool(s.as_built.stable),
                            "converged": bool(s.as_built.success),
                            "kkt_residual": _finite(s.as_built.kkt_residual),
                            "error": {"max_mm": _finite(s.error_mm), "max_rel_size": _finite(s.rel_size)},
                            "note": "the net re-solved with the solids' masses and centres of mass, against the "
                                    "design's simulated nodes and pivots" + (
                                        "" if s.as_built.success else
                                        f"; the solver stopped short of round-off ({s.as_built.message}), the "
                                        "error read where it stopped (null: too far from an equilibrium to say)")}
        parts = s.hub_parts if s.hub_splits else [(h, None, True) for h in s.hubs]
        data["cad"] = {"hubs": sum(h is not None for h in s.hubs), "rods": len(s.rods),
                       "nodes_without_hub": [k for k, h in enumerate(s.hubs) if h is None],
                       "hub_parts": [p[0].label for p in parts],
                       "hubs_not_split": {h.parts[0].label: h.reason for h in s.hub_splits if not h.split},
                       "hubs_wider_sockets": {f"hub-{k:03d}": round(float(h.clearance), 4)
                                              for k, h in enumerate(s.hub_splits)
                                              if h.clearance is not None and h.clearance > d.catalog.node.clearance},
                       "parts": _parts_json(s),
                       "mesh": {"deflection_mm": s.deflection[0], "angle_deg": round(float(np.degrees(s.deflection[1])), 3),
                                "note": "STL and 3MF meshes (what the slicer prints) to this deflection; masses and "
                                        "checks from the exact solids"},
                       "files": files}
        rho = d.catalog.node.density / 1000.0
        data["bill_of_materials"]["parts"] = [
            {"name": p["name"], "count": p["count"], "plastic_g": round(rho * p["volume_mm3"], 4)}
            for p in data["cad"]["parts"]]
    plot_net(b.check, f"{d.name}: {b.check.error_mm:.3g} mm ({100 * b.check.rel_size:.3g} % of its size) off "
             "its target", tmp / "preview.png")
    write_design(tmp, data, net_report(b.check, data, title=d.name))
    return data
