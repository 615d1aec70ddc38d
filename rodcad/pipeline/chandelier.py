"""The pipeline of a chandelier: placements of many chains on a frame, each chain through the
steps of a single one (:mod:`rodcad.pipeline.chain`), the frame laid out and built. It
sequences the steps and owns none of them::

    design.yaml (chandelier:) -> load_design()                rodcad.design.loader
    -> joint limits and mass ranges from the rods             rodcad.pipeline.chain.arrays_step
    -> placements, then per chain: plan, masses, check        rodcad.design.chandelier.design_chandelier
    -> per chain: joint hardware, masses designed with it     rodcad.pipeline.chain.hung_result
    -> the frame as numbers, its solid and clearances         rodcad.design.frame, rodcad.cad.chandelier
    -> every rod of every chain built in one go               rodcad.pipeline.chain.fabricate_step
    -> as-built re-simulation per chain                       rodcad.pipeline.chain.as_built
    -> per chain: as printed (bands), tapped in MuJoCo         rodcad.pipeline.chain.printed_step
    -> design.json, report.md, 3D preview, STEP/STL, print.3mf per chain  write_chandelier_outputs()
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import Any

import numpy as np

from rodcad.design.asprinted import anchor_holes
from rodcad.design.chandelier import bill_of_materials, design_chandelier
from rodcad.design.frame import frame_outline, plan_frame
from rodcad.design.model import Design
from rodcad.design.printed import rods_of
from rodcad.errors import InputError
from rodcad.outputs.design_json import chandelier_json, print_profile
from rodcad.outputs.preview3d import preview_3d
from rodcad.outputs.report import chandelier_markdown
from rodcad.pipeline.chain import (N_STARTS, arrays_step, as_built, fabricate_step, hung_result, intervals_step,
                                   printed_step)
from rodcad.outputs.view import write_chandelier_view
from rodcad.pipeline.folder import staged, write_design
from rodcad.progress import Progress
from rodcad.results import ChandelierBuild

__all__ = ["build_chandelier", "write_chandelier_outputs"]


def build_chandelier(design: Design, *, method: str | None = None, seed: int | None = None,
                     cad: bool | None = None, jobs: int | None = None,
                     progress: Progress | None = None) -> ChandelierBuild:
    """Design every chain of a chandelier (the path of a single chain, chain by chain), lay
    out its frame and (optionally) build it all."""
    progress = progress or Progress(quiet=True)
    t0 = time.perf_counter()
    method = method or design.method
    seed = design.seed if seed is None else seed
    cad = design.cad if cad is None else cad
    spec = design.chandelier
    c = design.constraints
    if c.anchor_stops == "auto" or c.end_limits is not None:
        key = "constraints.anchor_stops" if c.anchor_stops == "auto" else "constraints.anchor_limits_deg"
        raise InputError([design.problem(key, "a chandelier's chains hang from the frame's lugs, bare pins: anchor "
                                         "stops are for a single chain's printed fixture")])
    arrays = arrays_step(design, jobs, progress)
    ivfn = intervals_step(design, jobs, progress) if cad else None
    try:
        # the frame's lugs are bare pins, and the chains are built rod by rod: neither anchor
        # stops nor (unless asked for) fused pieces
        chains_c = dataclasses.replace(c, anchor_stops="none", fuse=c.fuse if c.fuse is not None else "never")
        res = design_chandelier(design.catalog, design.placements, design.chain_targets, method=method,
                                seed=seed, jobs=jobs or 1, arrays=arrays, constraints=chains_c,
                                problem=design.problem, n_starts=N_STARTS, g=design.g, progress=progress,
                                intervals=ivfn)
    except ValueError as err:
        raise InputError([design.problem("chandelier", str(err))]) from None
    made = rods_of([ch.design.plan for ch in res.chains])
    if made:  # rods printed to order: the catalog now knows them by name
        design = dataclasses.replace(design, catalog=design.catalog.with_types(made))
    chains = _hung_chains(design, res, method=method, seed=seed, intervals=ivfn, progress=progress)
    extra = {}
    if spec.frame_kind == "bars":
        # the polygon's vertices, or (explicit anchors) a closed polygon through every anchor in order
        extra["vertices"] = spec.vertices or [
            list(map(float, a)) for p in design.placements for a in (p.a3, p.b3)]
    frame_plan = plan_frame(spec.frame_kind, design.placements, design.catalog, res.chains, **spec.frame,
                            **extra)
    frame_plan.lugs = fitted_lugs(frame_plan.lugs, chains)
    out = ChandelierBuild(design, res, frame_plan, chains=chains)
    for ch in res.chains:
        if not ch.equilibrium.stable:
            out.notes.append(f"{ch.name}: the designed shape is not a stable equilibrium")
        if not ch.design.unique:
            out.notes.append(f"{ch.name}: {ch.design.n_stable} stable shapes found; guide it into the designed one")
    if cad and any(ch.design.plan.fused for ch in res.chains):
        raise InputError([design.problem("constraints.fuse", "a chandelier's chains are built rod by rod: fused "
                                         "pieces are built for a single chain only; use 'never'")])
    if cad:  # (the CAD kernel is imported where solids are built)
        from rodcad.cad.chandelier import build_frame

        with progress.step("frame solid and clearance checks"):
            out.frame = build_frame(frame_plan, design.catalog, res.chains)
        out.notes += [f"frame: {p}" for p in out.frame[1].problems]
        sized = all(r.hardware is not None for r in chains)
        out.fabrications, problems = fabricate_step(
            design, [(r.type_names, r.printed_masses) for r in chains], jobs=jobs, progress=progress,
            label=f"building {res.bom.n_rods} rods", holes=[h for r in chains for h in r.holes.holes],
            sizes=[s for r in chains for s in r.hole_sizes] if sized else None)
        out.notes += problems
        with progress.step("as-built check of every chain"):
            out.as_built = [as_built(fab.rods, r.lengths, r.limits, r.design.anchors, r.target_points, design.g,
                                     metal=r.metal) for r, fab in zip(chains, out.fabrications)]
        for r, ab in zip(chains, out.as_built):
            r.as_built = ab
    seen: dict[str, Any] = {}
    for ch, r in zip(res.chains, chains):
        twin = seen.get(ch.shared_with) if ch.shared_with is not None else None
        if twin is not None and (r.as_built is None or np.array_equal(r.as_built.masses, twin.as_built.masses)):
            r.as_printed, r.tapping = twin.as_printed, twin.tapping  # the same chain, the same rods
        else:
            k = len(r.notes)
            printed_step(r, progress)
            out.notes += [f"{ch.name}: {n}" for n in r.notes[k:]]
        seen[ch.name] = r
    out.time_s = time.perf_counter() - t0
    return out


def fitted_lugs(lugs: list, chains: list) -> list:
    """The frame's lugs (A, B per chain) with the pin holes of each chain's chosen anchor
    hardware, moved where the loaded anchor pins sit on the anchors (as a single chain's
    fixture: :func:`rodcad.design.asprinted.anchor_holes`)."""
    out = []
    for k, lug in enumerate(lugs):
        r = chains[k // 2]
        end = k % 2
        hw = r.hardware
        option = None if hw is None else hw.options[-1 if end else 0]
        shift = (0.0, 0.0)
        if r.holes is not None:
            shift = tuple(float(v) for v in anchor_holes(r.holes, r.equilibrium.points)[end])
        out.append(dataclasses.replace(lug, hole_offset=shift,
                                       hole_diameter=None if option is None else option.hole(lug.knuckle)))
    return out


def _hung_chains(design: Design, res, *, method: str, seed: int, intervals, progress: Progress) -> list:
    """Per chain, its joint hardware chosen joint by joint and its masses designed with it
    (:func:`rodcad.pipeline.chain.hung_result`, in the chain's plane), as a
    :class:`rodcad.results.BuildResult`; each chain's design in ``res`` becomes the hung one
    and the bill of materials follows. Chains that share a problem share its result."""
    out: list = []
    done: dict[str, Any] = {}
    for ch in res.chains:
        plane = dataclasses.replace(design, anchors=np.asarray(ch.placement.plane_anchors(), float))
        if ch.shared_with is not None and ch.shared_with in done:
            r = dataclasses.replace(done[ch.shared_with], design=plane, notes=list(done[ch.shared_with].notes))
        else:
            r = hung_result(plane, ch.design, method=method, seed=seed, intervals=intervals, progress=progress)
        ch.design = r.chain_design
        done[ch.name] = r
        out.append(r)
    res.bom = bill_of_materials(res.chains)
    return out


def write_chandelier_outputs(b: ChandelierBuild, outdir: str | Path, *,
                             progress: Progress | None = None, jobs: int | None = None) -> dict[str, Any]:
    """design.json, report.md, preview.png (3D) and, with CAD, assembly.step, frame.step/.stl
    and <chain>/rods/*.step|stl|3mf and <chain>/print.3mf; staged like a chain's
    (:func:`rodcad.pipeline.chain.write_outputs`), whose return it shares (``jobs`` as its)."""
    with staged(outdir, progress) as (tmp, progress):
        if b.frame is not None:
            from rodcad.cad.chainfiles import start_rod_files
            from rodcad.cad.chandelier import chandelier_nodes
            from rodcad.cad.export import export_assembly
            from rodcad.cad.printfile import write_print_files

            frame = b.frame[0]
            # every chain's distinct rods and the frame, written and checked in worker processes at once
            with progress.step("writing and checking the rods' STEP/STL files, frame.step and frame.stl"), \
                    start_rod_files([(fab, tmp / ch.name) for ch, fab in zip(b.result.chains, b.fabrications)],
                                    jobs=jobs, extra=[(frame, tmp / "frame.step", tmp / "frame.stl", "frame",
                                            frame.volume)]) as files:
                files.finish()
            with progress.step("writing each chain's print.3mf (PrusaSlicer project) and rods/*.3mf"):
                for ch, fab in zip(b.result.chains, b.fabrications):
                    write_print_files(fab.rods, tmp / ch.name, printer=b.design.catalog.printer,
                                      profile=print_profile(b.design.catalog))
            with progress.step("writing assembly.step"):
                nodes = chandelier_nodes(frame, b.result.chains, b.design.catalog, frame_plan=b.frame_plan,
                                         rod_solid=lambda ci, i: b.fabrications[ci].rods[i].solid,
                                         pin_diameters=[None if r.hardware is None else
                                                        [None if o is None else o.pin_diameter
                                                         for o in r.hardware.options] for r in b.chains])
                export_assembly(tmp / "assembly.step", nodes, b.design.name)
        with progress.step("writing design.json, report.md, preview.png"):
            data = chandelier_json(b)
            preview_3d(tmp / "preview.png", b.result.chains, frame_outline(b.frame_plan),
                       title=f"{b.design.name}: {len(b.result.chains)} chains", svg=True)
            write_design(tmp, data, chandelier_markdown(b, data))
            write_chandelier_view(b, data, tmp)  # assembly.glb, view.html
    return data
