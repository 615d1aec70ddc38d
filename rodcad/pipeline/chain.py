"""The pipeline of a chain: a design file with a ``target`` in, a designed, checked and
fabricated chain out. It sequences the steps and owns none of them::

    design.yaml + catalog -> load_design()                      rodcad.design.loader
    -> joint limits and mass ranges from the rods             rodcad.design.plan.catalog_arrays
    -> plan (every constraint), masses (buildable intervals   rodcad.design.chains.design_chains
       with CAD), one equilibrium + multi-start check
    -> joint hardware and the masses designed with it         rodcad.design.hung, rodcad.design.asprinted
    -> cavities, sockets, exact B-rep of every rod            rodcad.cad.rods.fabricate_chain
    -> fused runs of rods as one solid each                   rodcad.cad.pieces.fuse_pieces
    -> as-built re-simulation                                 as_built()
    -> the anchor fixture                                     build_fixture_for(), rodcad.cad.fixture
    -> as printed: pins in holes (compensated), bands          rodcad.design.asprinted
    -> tapped in MuJoCo                                       rodcad.design.tapping
    -> design.json, report.md, previews, STEP/STL, print.3mf  rodcad.outputs, write_outputs()

Every chain of a chandelier takes the same steps (:mod:`rodcad.pipeline.chandelier`, through
:func:`arrays_step`, :func:`intervals_step`, :func:`fabricate_step` and :func:`as_built`).
Numbers cross into :mod:`optimize` as plain arrays (mm, g, radians).
"""

from __future__ import annotations

import contextlib
import dataclasses
import pickle
import time
from collections.abc import Sequence
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from optimize import (
    shape_distance,
    solve_equilibrium,
)
from optimize.chain.discretize import MAX_RODS
from rodcad.design.asprinted import anchor_holes, chain_hardware, plan_holes, printed_chain
from rodcad.design.hung import design_hung, hung_com
from rodcad.design.chains import ChainSpec, design_chains
from rodcad.design.masses import check_equilibrium
from rodcad.catalog.model import RodType
from rodcad.design.model import Design
from rodcad.design.plan import CatalogArrays, catalog_arrays
from rodcad.design.shell import curve_size
from rodcad.errors import InputError
from rodcad.outputs.design_json import design_json, print_profile
from rodcad.outputs.preview import plot_chain
from rodcad.outputs.report import report_markdown
from rodcad.outputs.view import write_chain_view
from rodcad.parallel import default_jobs, kept_workers, worker_pool
from rodcad.pipeline.folder import staged, write_design
from rodcad.progress import Progress
from rodcad.results import AsBuilt, BuildResult

if TYPE_CHECKING:  # the CAD kernel is imported where solids are built: a run without CAD never loads it
    from rodcad.cad.rods import ChainFabrication, FabricatedRod

__all__ = [
    "N_STARTS",
    "TAPS",
    "arrays_step",
    "as_built",
    "build",
    "build_fixture_for",
    "fabricate_step",
    "hung_result",
    "intervals_step",
    "printed_step",
    "simulate",
    "write_outputs",
]

#: Multi-start count of the uniqueness check.
N_STARTS = 12


# --------------------------------------------------------------------------- steps a chandelier's chains share


def arrays_step(design: Design, jobs: int | None, progress: Progress) -> CatalogArrays:
    with progress.step("joint limits and mass ranges of the catalog's rods") as st:
        return catalog_arrays(design.catalog, jobs=jobs, progress=st.count)


def intervals_step(design: Design, jobs: int | None, progress: Progress):
    """The achievable mass intervals of the planned types (CAD on)."""
    def intervals(types: Sequence[RodType]) -> dict[str, list[tuple[float, float]]]:
        from rodcad.fabrication.intervals import chain_intervals

        with progress.step(f"masses each of {len(types)} rod types can really be built at"):
            return chain_intervals(list(types), seed=design.fabrication_seed, jobs=jobs)
    return intervals


def fabricate_step(design: Design, chains: Sequence[tuple[Sequence[str], np.ndarray]], *, jobs: int | None,
               progress: Progress, label: str, fused: Sequence[tuple[int, int]] = (), holes=None, sizes=None
               ) -> tuple[list[ChainFabrication], list[str]]:
    """Every rod of every chain built in one go (identical rods once); split per chain. The
    sockets' roofs go onto as few print layers as the rods allow (the rods of ``fused``
    runs (first, last) keep theirs: their piece lies on the bed its own way)."""
    from rodcad.cad.printfile import PrintProfile
    from rodcad.cad.rods import ChainFabrication, fabricate_chain

    types = [design.catalog[name] for names, _ in chains for name in names]
    masses = np.concatenate([np.asarray(m, float) for _, m in chains])
    layers = PrintProfile.from_mapping(print_profile(design.catalog)).layers
    keep = {i for a, b in fused for i in range(a, b + 1)}
    with progress.step(label) as st:
        fab = fabricate_chain(types, masses, seed=design.fabrication_seed, jobs=jobs, progress=st.count,
                              layers=layers, keep_roofs=keep, holes=holes, sizes=sizes)
    if len(chains) == 1:
        return [fab], list(fab.problems)
    out, k = [], 0
    for names, _ in chains:
        rods = [dataclasses.replace(r, index=i, file_stem=f"{i:02d}_{r.type_name}")
                for i, r in enumerate(fab.rods[k:k + len(names)])]
        k += len(names)
        out.append(ChainFabrication(rods, [], len({id(r.solid) for r in rods}), 0.0))
    return out, list(fab.problems)


def as_built(rods: Sequence[FabricatedRod], lengths: np.ndarray, limits: np.ndarray | None, anchors: np.ndarray,
             target: np.ndarray, g: float, end_limits: np.ndarray | None = None, metal=None) -> AsBuilt:
    """Re-simulate a chain with the masses and centres of mass of its real solids and, where
    given, the joint hardware's metal on them (``metal``, (N, 2) g at each rod's hinge axes)."""
    masses = np.array([r.mass for r in rods], float)
    com = np.array([r.com for r in rods], float)
    if metal is not None:
        masses = masses + np.asarray(metal, float).sum(axis=1)
        com = hung_com(masses, com, lengths, metal)
    a, b = anchors
    eq = solve_equilibrium(lengths, masses, a, b, com=com, limits=limits if len(lengths) > 1 else None, g=g,
                           end_limits=end_limits)
    return AsBuilt(masses, com, eq, shape_distance(target, eq.points))


# --------------------------------------------------------------------------- a chain


def build(design: Design, *, method: str | None = None, seed: int | None = None, cad: bool | None = None,
          jobs: int | None = None, progress: Progress | None = None) -> BuildResult:
    """Design the chain for the design's target, check it and (optionally) fabricate it.

    Args:
        design: a validated design with a target.
        method: inverse-design method (default: the design's).
        seed: seed (default: the design's).
        cad: build the solids (default: the design's fabrication.cad).
        jobs: worker processes for the solids and joint limits.
        progress: where to report progress (default: silent).

    Raises:
        InputError: the design has no target, or its constraints cannot be met.
    """
    progress = progress or Progress(quiet=True)
    t0 = time.perf_counter()
    if design.target_curve is None:
        raise InputError([design.problem("", "this design has no 'target' to build a chain for "
                                         "(use `rodcad simulate` for an explicit chain)")])
    method = method or design.method
    seed = design.seed if seed is None else seed
    cad = design.cad if cad is None else cad
    arrays = arrays_step(design, jobs, progress)
    spec = ChainSpec("", np.asarray(design.anchors, float), design.target_curve)
    ivfn = intervals_step(design, jobs, progress) if cad else None
    with kept_workers(jobs if cad else 1):  # a rod type's table and its rods made in one worker
        (chain,) = design_chains([spec], arrays, design.constraints, design.problem, method=method, seed=seed,
                                 n_starts=N_STARTS, g=design.g, progress=progress, intervals=ivfn)
        cd = chain.design
        if cd.plan.rods:  # rods printed to order: the catalog now knows them by name
            design = dataclasses.replace(design, catalog=design.catalog.with_types(cd.plan.rods))
        result = hung_result(design, cd, method=method, seed=seed, intervals=ivfn, progress=progress)
        p = result.plan
        if cad:
            (fab,), problems = fabricate_step(design, [(result.type_names, result.printed_masses)], jobs=jobs,
                                              progress=progress,
                                              label=f"building {result.n} rods (cavities, ball sockets, exact B-rep)",
                                              fused=p.fused, holes=result.holes.holes, sizes=result.hole_sizes)
    if cad:
        from rodcad.cad.pieces import PieceRefused, as_printed_rods, fuse_pieces

        result.fabrication = fab
        result.notes += problems
        if p.fused:
            with progress.step(f"uniting {len(p.fused)} fused piece(s) into one solid each"):
                try:
                    fuse_pieces(fab, p.fused, result.equilibrium.points,
                                [design.catalog[name] for name in result.type_names])
                except PieceRefused as err:
                    raise InputError([design.problem("constraints.fuse", str(err))]) from None
        with progress.step("as-built check (masses and centres of mass from the solids)"):
            result.as_built = as_built(as_printed_rods(fab), result.lengths, result.limits, design.anchors,
                                       result.target_points, design.g, result.end_limits, metal=result.metal)
        if result.end_limits is not None:
            with progress.step("the anchor fixture (stops for the end rods), checked against the rods at rest"):
                result.fixture, result.fixture_problems = build_fixture_for(result)
            result.notes += [f"fixture: {p}" for p in result.fixture_problems]
    printed_step(result, progress)
    result.time_s = time.perf_counter() - t0
    return result


def hung_result(design: Design, cd, *, method: str, seed: int, intervals, progress: Progress) -> BuildResult:
    """A designed chain (``cd``, :class:`rodcad.design.masses.ChainDesign`, in the plane of
    ``design.anchors``) with its joint hardware chosen per joint and its masses designed with
    that hardware hanging on the rods (:func:`rodcad.design.hung.design_hung`), as a
    :class:`BuildResult` with its pin holes planned; a chandelier's chains take it one by one.

    Args:
        intervals: the achievable mass intervals of rod types (:func:`intervals_step`), None
            without CAD.
    """
    rods = [design.catalog[name] for name in cd.plan.type_names]
    with progress.step("joint hardware (pins, bushings or bearings for each joint's load and friction) and "
                       "the masses designed with it hanging on the rods"):
        ivs = None if intervals is None else dict(intervals(list({r.name: r for r in rods}.values())))
        hung = design_hung(cd, rods, lambda c: chain_hardware(rods, design, c), method=method, seed=seed,
                           n_starts=N_STARTS, g=design.g, intervals=ivs)
    if hung is not None:
        cd = hung.design
    p, pr, chk = cd.plan, cd.plan.problem, cd.check
    result = BuildResult(
        design=design, method=method, seed=seed, type_names=list(p.type_names),
        lengths=np.asarray(pr.lengths, float), masses=np.asarray(cd.result.masses, float),
        com=np.asarray(pr.com, float), limits=_as_limits(pr.limits, len(p.type_names)),
        target_points=np.asarray(pr.target, float), equilibrium=chk.equilibrium,
        distance=shape_distance(pr.target, chk.equilibrium.points), n_stable=chk.n_stable, unique=chk.unique,
        plan=p, chain_design=cd, notes=list(p.notes), end_limits=pr.end_limits,
    )
    result.notes += _design_notes(result)
    result.hung = hung
    result.hardware = None if hung is None else hung.hardware
    result.holes = plan_holes(rods, result)
    snap = cd.buildable
    if snap is not None and snap.snapped:
        result.notes.append(
            f"{snap.snapped} rod mass(es) moved onto masses the rods can really be built at (metal balls "
            f"come in whole numbers): max error {100 * snap.error_before:.3g} % -> "
            f"{100 * snap.error_after:.3g} % of the span")
    return result


def printed_step(result: BuildResult, progress: Progress) -> None:
    """The chain as printed (every pin bearing in its holes, the friction and mass bands) and
    tapped in MuJoCo, onto ``result`` (its as-built solids' masses where built)."""
    with progress.step("as printed: every pin bearing in its holes; friction and mass tolerance bands"):
        result.as_printed = printed_chain(result.rods, result)
    result.tapping = _tapped(result, progress)


#: Light taps simulated after the chain is hung (MuJoCo with each pin's friction).
TAPS = 10


def _tapped(result: BuildResult, progress: Progress):
    """The designed chain hung 0.01 rad off its shape and tapped :data:`TAPS` times in MuJoCo
    with its joint hardware's friction (:func:`rodcad.design.tapping.tap_chain`), or None
    where there is no hardware or stable design; a MuJoCo failure becomes a note."""
    hw, eq = result.hardware, result.equilibrium
    if hw is None or not (eq.success and eq.stable) or result.n < 2:
        return None
    from rodcad.design.hardware import solver_moment
    from rodcad.design.tapping import tap_chain

    a, b = result.design.anchors
    with progress.step(f"tapping the hung chain {TAPS} times (MuJoCo, with the pins' friction)"):
        try:
            return tap_chain(result.lengths, result.masses, a, b, design_angles=eq.angles,
                             capacity=solver_moment(hw.capacity, result.design.g), com=result.com,
                             limits=result.limits, end_limits=result.end_limits, g=result.design.g,
                             n_taps=TAPS, seed=result.seed)
        except (ValueError, FloatingPointError) as err:
            result.notes.append(f"the tapping simulation did not run: {err}")
            return None


def build_fixture_for(result: BuildResult) -> tuple[Any, list[str]]:
    """The printed piece both anchor pins sit in, with a stop for each end rod the design
    holds at its bound (:mod:`rodcad.cad.fixture`), and its problems against the rods at rest."""
    from rodcad.cad.fixture import check_fixture, fixture_solid, placed_rods

    d = result.design
    rods = [d.catalog[name] for name in result.type_names]
    angles = result.equilibrium.angles
    hw = result.hardware
    solid = fixture_solid(d.anchors, rods[0], rods[-1], result.end_limits, rest_angles=(angles[0], angles[-1]),
                          pin_holes=None if result.holes is None else anchor_holes(result.holes, result.equilibrium.points),
                          hole_diameters=None if hw is None or None in (hw.options[0], hw.options[-1]) else
                          (hw.options[0].fork_hole, hw.options[-1].fork_hole))
    printer = d.catalog.printer
    problems = check_fixture(solid, placed_rods(result.equilibrium.points, rods), anchors=d.anchors,
                             end_limits=result.end_limits,
                             build_volume=printer.build_volume if printer is not None else None)
    return solid, problems


def simulate(design: Design, *, progress: Progress | None = None) -> BuildResult:
    """The equilibrium of the design's explicit chain (types and masses as given).

    Raises:
        InputError: the design has no explicit chain, or two of its rods cannot be joined.
    """
    progress = progress or Progress(quiet=True)
    t0 = time.perf_counter()
    if design.chain is None:
        raise InputError([design.problem("", "this design has no explicit 'chain' to simulate")])
    if len(design.chain) > MAX_RODS:
        raise InputError([design.problem("chain", f"{len(design.chain)} rods; rodcad simulates chains of up to "
                                         f"{MAX_RODS} rods")])
    arrays = arrays_step(design, None, progress)
    names = [r.type for r in design.chain]
    lim = arrays.limits_of(names)
    bad = [j for j in range(len(names) - 1) if not lim[j, 0] <= lim[j, 1]]
    if bad:
        raise InputError([design.problem(f"chain[{j + 1}].type", f"{names[j]!r} and {names[j + 1]!r} "
                                         "cannot be joined (the rods interfere at every angle)") for j in bad])
    k = [arrays.index[n] for n in names]
    lengths, com = arrays.lengths[k], arrays.com[k]
    masses = np.array([r.mass for r in design.chain], float)
    a, b = design.anchors
    try:
        chk = check_equilibrium(lengths, masses, a, b, com=com, limits=lim, g=design.g, seed=design.seed,
                                n_starts=N_STARTS, end_limits=design.constraints.end_limits)
    except ValueError as err:
        raise InputError([design.problem("anchors", str(err))]) from None
    target = None
    dist = None
    if design.target_curve is not None and len(design.target_curve) == len(names) + 1:
        target = design.target_curve
        dist = shape_distance(target, chk.equilibrium.points)
    res = BuildResult(design=design, method="", seed=design.seed, type_names=names, lengths=lengths,
                      masses=masses, com=com, limits=lim, target_points=target, equilibrium=chk.equilibrium,
                      distance=dist, n_stable=chk.n_stable, unique=chk.unique,
                      end_limits=design.constraints.end_limits)
    res.notes += _design_notes(res)
    res.time_s = time.perf_counter() - t0
    return res


def _as_limits(limits, n: int) -> np.ndarray:
    if limits is None or n < 2:
        return np.tile([-np.inf, np.inf], (max(n - 1, 0), 1))
    return np.asarray(limits, float).reshape(-1, 2)


def _design_notes(r: BuildResult) -> list[str]:
    notes = []
    eq = r.equilibrium
    if not eq.success:
        notes.append(f"the equilibrium solver did not converge: {eq.message}")
    if not eq.stable:
        notes.append("the designed shape is an equilibrium but NOT a stable one: the printed chain "
                     "would fall into another shape")
    if not r.unique:
        advice = r.chain_design.check.hang_advice() if r.chain_design is not None else ""
        notes.append(f"{r.n_stable} distinct stable equilibria were found from {N_STARTS} starts: the "
                     "chain may settle in another shape if hung carelessly; "
                     + (advice or "hang it from A, guide it into shape, then attach B"))
    cd = r.chain_design
    if cd is not None and cd.result.info.get("reachable") and r.distance is not None and r.plan is not None \
            and r.distance.max > 0.01 * curve_size(r.plan.curve):  # not a mass snapped onto a buildable one
        hint = ("; print the runs of stopped joints as rigid pieces (constraints: {fuse: stops}), which hold it"
                if r.plan is not None and r.plan.rods and r.design.constraints.fuse_mode == "never" else "")
        notes.append("the masses balance the target with every stop pushing the right way, but the chain does "
                     "not settle there: that shape is not a stable equilibrium with these stops (or another one "
                     f"is reached first), so it hangs {r.distance.max:.3g} mm off it{hint}")
    if cd is not None:
        res = cd.result
        lo = int(np.sum(res.at_bounds < 0))
        hi = int(np.sum(res.at_bounds > 0))
        if not res.exact and (lo or hi):
            notes.append(f"the target is not reachable with the catalog's mass ranges: {lo} rod(s) at "
                         f"their lightest and {hi} at their heaviest; this is the best fit within what can "
                         "be printed (a catalog with wider mass ranges would get closer)")
    return notes


def write_outputs(result: BuildResult, outdir: str | Path, *,
                  progress: Progress | None = None, jobs: int | None = None) -> dict[str, Any]:
    """Write design.json, report.md, preview.png/.svg and (with CAD) the STEP/STL files
    (``jobs``: worker processes for them and the preview, default the CPUs; 1: all here).

    Everything goes to a temporary folder first, renamed to ``outdir`` at the
    end: a failed or interrupted run leaves ``outdir`` as it was.

    Returns:
        The data written to design.json.
    """
    with staged(outdir, progress) as (tmp, progress), contextlib.ExitStack() as stack:
        pictures = (tmp / "preview.png", tmp / "preview.svg")
        preview = None
        if result.fabrication is not None:
            from rodcad.cad.chainfiles import start_rod_files, write_assembly

            if (default_jobs() if jobs is None else jobs) > 1:
                # the preview is drawn in a worker of its own beside the rest (matplotlib's import
                # and drawing, 1.5-2.5 s, are then off this process's path); from a copy of the
                # result without its solids, which cannot be pickled
                preview = stack.enter_context(worker_pool(1)).submit(
                    plot_chain, dataclasses.replace(result, fabrication=None, fixture=None), *pictures)
            from rodcad.cad.export import AssemblyPart
            from rodcad.cad.printfile import write_print_files

            # the rods' and the fixture's files are written in worker processes while this one
            # writes the rest
            fixture = result.fixture
            rod_files = stack.enter_context(start_rod_files(
                [(result.fabrication, tmp)], jobs=jobs, extra=[] if fixture is None else
                [(fixture, tmp / "fixture.step", tmp / "fixture.stl", "fixture", fixture.volume)]))
            extra = [] if fixture is None else [AssemblyPart("fixture", fixture, np.eye(4), (0.55, 0.55, 0.6))]
            with progress.step("writing assembly.step"):
                hw = result.hardware
                write_assembly(result.fabrication, result.equilibrium.points, tmp / "assembly.step",
                               name=result.design.name, extra=extra,
                               pin_diameters=None if hw is None else [None if o is None else o.pin_diameter
                                                                      for o in hw.options])
        with progress.step("writing design.json, report.md, preview.png/.svg"):
            data = design_json(result)
            if preview is None:
                plot_chain(result, *pictures)
            write_design(tmp, data, report_markdown(result, data))
            write_chain_view(result, data, tmp)  # assembly.glb, view.html
        if result.fabrication is not None:
            with progress.step("writing and checking rods/*.step, rods/*.stl" +
                               (", fixture.step, fixture.stl" if fixture is not None else "")):
                rod_files.finish()
            with progress.step("writing print.3mf (PrusaSlicer project with its pauses) and rods/*.3mf"):
                write_print_files(result.fabrication.parts, tmp, printer=result.design.catalog.printer,
                                  profile=print_profile(result.design.catalog))
        if preview is not None:
            try:
                preview.result()
            except (pickle.PicklingError, TypeError, BrokenProcessPool):  # a result it cannot take: here
                plot_chain(result, *pictures)
    return data
