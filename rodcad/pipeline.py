"""The pipeline: a design file in, a designed, checked and fabricated chain out.

One function per step of the data flow (style.md)::

    design.yaml + catalog -> load_design()         (rodcad.design)
    -> joint limits and mass ranges from the rods  catalog_arrays()
    -> rod positions and types on the target       plan()
    -> masses by inverse design                    design_masses()
    -> equilibrium check from scratch              check_equilibrium()
    -> cavities, sockets, exact B-rep              fabricate()
    -> as-built re-simulation                      as_built()
    -> design.json, report.md, previews, STEP/STL  rodcad.outputs.report, write_outputs()

Numbers cross into :mod:`optimize` as plain arrays (mm, g, radians).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from optimize import EquilibriumResult, find_equilibria, shape_distance, solve_equilibrium
from optimize.distance import ShapeDistance
from rodcad.design.masses import ChainDesign, design_chain
from rodcad.design.plan import ChainPlan, catalog_arrays, plan_chain
from rodcad.design.model import Design
from rodcad.errors import InputError
from rodcad.progress import Progress

__all__ = ["AsBuilt", "BuildResult", "build", "simulate", "write_outputs"]

#: Multi-start count of the uniqueness check.
N_STARTS = 12


@dataclass
class AsBuilt:
    """The chain as it will really be printed, re-simulated.

    Attributes:
        masses: (N,) rod masses from the final B-rep plus metal (g).
        com: (N, 2) centres of mass from the final B-rep (mm, rod frame).
        equilibrium: its equilibrium.
        distance: its joints against the target joints.
    """

    masses: np.ndarray
    com: np.ndarray
    equilibrium: EquilibriumResult
    distance: ShapeDistance


@dataclass
class BuildResult:
    """Everything one run found, for the report and the output files.

    Attributes:
        design: the validated design.
        method: inverse-design method used ('' for an explicit chain).
        seed: seed used.
        type_names: rod type per position.
        lengths, masses, com: per rod (mm, g, mm in the rod frame).
        limits: (N-1, 2) joint limits (rad), (-inf, inf) where nothing collides.
        target_points: (N+1, 2) target joints (None for an explicit chain).
        equilibrium: the designed chain, solved from scratch.
        distance: simulated vs target joints (None without a target).
        n_stable, unique: multi-start check (other stable equilibria?).
        plan, chain_design: the planning and inverse-design results (None for an explicit chain).
        fabrication: the fabricated rods (None without CAD).
        as_built: the as-built re-simulation (None without CAD).
        notes: things the user should know (infeasibility, bounds, stops).
        time_s: wall time of the run.
    """

    design: Design
    method: str
    seed: int
    type_names: list[str]
    lengths: np.ndarray
    masses: np.ndarray
    com: np.ndarray
    limits: np.ndarray
    target_points: np.ndarray | None
    equilibrium: EquilibriumResult
    distance: ShapeDistance | None
    n_stable: int
    unique: bool
    plan: ChainPlan | None = None
    chain_design: ChainDesign | None = None
    fabrication: Any = None
    as_built: AsBuilt | None = None
    notes: list[str] = field(default_factory=list)
    time_s: float = 0.0

    @property
    def n(self) -> int:
        return len(self.type_names)

    @property
    def meets_tolerance(self) -> bool:
        """True unless the design sets a tolerance the result misses."""
        tol = self.design.tolerance
        return tol is None or self.distance is None or self.distance.max_rel_span <= tol


# --------------------------------------------------------------------------- steps


def _limits_of(names: list[str], index: dict[str, int], pair: np.ndarray) -> np.ndarray:
    """(N-1, 2) joint limits of a sequence of types; (-inf, inf) for free sides."""
    lim = np.array([pair[index[a], index[b]] for a, b in zip(names[:-1], names[1:])]).reshape(-1, 2)
    return np.where(np.isfinite(lim), lim, np.array([-np.inf, np.inf]))


def plan(design: Design, arrays: tuple, progress: Progress | None = None) -> ChainPlan:
    """Lay rods on the design's target, honouring its constraints.

    Raises:
        InputError: the constraints cannot be met (pointing at the key).
    """
    c = design.constraints
    lengths = c.lengths
    candidates: list[float | None] = [c.preferred_length]
    if c.rods is not None and c.preferred_length is None:
        types, t_len = arrays[0], arrays[1]
        allowed = {float(x) for x, t in zip(t_len, types) if c.types is None or t.name in c.types}
        if lengths is not None:
            allowed &= {float(x) for x in lengths}
        candidates = [None, *sorted(allowed)]
    counts: dict[int, ChainPlan] = {}
    for pref in candidates:
        try:
            p = plan_chain(design.catalog, design.target_curve, allowed_types=c.types, lengths=lengths,
                           preferred_length=pref, arrays=arrays)
        except ValueError as err:
            raise InputError([design.problem("target", str(err))]) from None
        counts.setdefault(len(p.type_names), p)
        if c.rods is None or len(p.type_names) == c.rods:
            break
    if c.rods is not None and c.rods not in counts:
        have = ", ".join(str(k) for k in sorted(counts))
        raise InputError([design.problem(
            "constraints.rods", f"the allowed rod lengths lay {have} rods on this target, not {c.rods}; "
            "change the rod count, the lengths allowed or preferred_length")])
    p = counts[c.rods] if c.rods is not None else next(iter(counts.values()))
    if c.fixed:
        _apply_fixed(design, p, arrays)
    return p


def _apply_fixed(design: Design, p: ChainPlan, arrays: tuple) -> None:
    """Impose the design's fixed rods on a plan (types, then masses)."""
    types, t_len, t_com, t_bounds, t_lim = arrays
    index = {t.name: i for i, t in enumerate(types)}
    n = len(p.type_names)
    problems = []
    for i, f in enumerate(design.constraints.fixed):
        key = f"constraints.fixed[{i}]"
        if f.index >= n:
            problems.append(design.problem(f"{key}.index", f"the chain has {n} rods (indices 0 to {n - 1})"))
            continue
        need = float(p.problem.lengths[f.index])
        k = index[f.type]
        if not np.isclose(t_len[k], need):
            problems.append(design.problem(f"{key}.type", f"rod {f.index} is {need:g} mm long on this target "
                                           f"but {f.type!r} is {t_len[k]:g} mm"))
            continue
        p.type_names[f.index] = f.type
        p.problem.com[f.index] = t_com[k]
        lo, hi = t_bounds[k]
        if f.mass is not None:
            lo, hi = f.mass * (1 - 1e-9), f.mass * (1 + 1e-9)
        p.problem.mass_bounds[f.index] = (lo, hi)
    if problems:
        raise InputError(problems)
    lim = _limits_of(p.type_names, index, t_lim)
    bad = [j for j in range(n - 1) if not lim[j, 0] <= lim[j, 1]]
    if bad:
        j = bad[0]
        raise InputError([design.problem("constraints.fixed", f"rods {j} ({p.type_names[j]}) and {j + 1} "
                                         f"({p.type_names[j + 1]}) cannot be joined")])
    if n > 1:
        p.problem.limits = lim
    p.notes.append(f"{len(design.constraints.fixed)} rod(s) fixed by the design")


def check_equilibrium(lengths, masses, a, b, *, com, limits, g, seed: int):
    """Solve from scratch and look for other stable equilibria (multi-start)."""
    eq = solve_equilibrium(lengths, masses, a, b, com=com, limits=limits if len(lengths) > 1 else None, g=g)
    multi = find_equilibria(lengths, masses, a, b, com=com, limits=limits if len(lengths) > 1 else None,
                            g=g, n_starts=N_STARTS, seed=seed)
    return eq, multi.n_distinct, multi.unique


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
    with progress.step("joint limits and mass ranges of the catalog's rods") as st:
        arrays = catalog_arrays(design.catalog, jobs=jobs, progress=st.count)
    with progress.step("laying rods on the target"):
        p = plan(design, arrays)
    if cad:
        # masses only where fabrication can really make them (ball counts leave gaps)
        from rodcad.design.masses import design_buildable
        from rodcad.fabrication.intervals import chain_intervals

        with progress.step("masses each rod type can really be built at"):
            intervals = chain_intervals([design.catalog[n] for n in p.type_names],
                                        seed=design.fabrication_seed, jobs=jobs)
        with progress.step(f"inverse design ({method}, {len(p.type_names)} rods, buildable masses)"):
            cd = design_buildable(p, method, intervals=intervals, seed=seed, n_starts=N_STARTS)
    else:
        with progress.step(f"inverse design ({method}, {len(p.type_names)} rods)"):
            cd = design_chain(p, method, seed=seed, n_starts=N_STARTS)
    pr = cd.plan.problem
    a, b = design.anchors
    with progress.step("equilibrium check from scratch"):
        eq, n_stable, unique = check_equilibrium(pr.lengths, cd.result.masses, a, b, com=pr.com,
                                                 limits=pr.limits, g=design.g, seed=seed)
    result = BuildResult(
        design=design, method=method, seed=seed, type_names=list(p.type_names),
        lengths=np.asarray(pr.lengths, float), masses=np.asarray(cd.result.masses, float),
        com=np.asarray(pr.com, float), limits=_as_limits(pr.limits, len(p.type_names)),
        target_points=np.asarray(pr.target, float), equilibrium=eq,
        distance=shape_distance(eq.points, pr.target), n_stable=n_stable, unique=unique,
        plan=p, chain_design=cd, notes=list(p.notes),
    )
    result.notes += _design_notes(result)
    snap = cd.result.info.get("buildable") if isinstance(cd.result.info, dict) else None
    if snap and snap.get("snapped"):
        result.notes.append(
            f"{snap['snapped']} rod mass(es) moved onto masses the rods can really be built at (metal balls "
            f"come in whole numbers): max error {100 * snap['error_before']:.3g} % -> "
            f"{100 * snap['error_after']:.3g} % of the span")
    if cad:
        fabricate(result, jobs=jobs, progress=progress)
    result.time_s = time.perf_counter() - t0
    return result


def simulate(design: Design, *, progress: Progress | None = None) -> BuildResult:
    """The equilibrium of the design's explicit chain (types and masses as given).

    Raises:
        InputError: the design has no explicit chain, or two of its rods cannot be joined.
    """
    progress = progress or Progress(quiet=True)
    t0 = time.perf_counter()
    if design.chain is None:
        raise InputError([design.problem("", "this design has no explicit 'chain' to simulate")])
    with progress.step("joint limits of the catalog's rods") as st:
        arrays = catalog_arrays(design.catalog, progress=st.count)
    types, t_len, t_com, _, t_lim = arrays
    index = {t.name: i for i, t in enumerate(types)}
    names = [r.type for r in design.chain]
    lim = _limits_of(names, index, t_lim)
    bad = [j for j in range(len(names) - 1) if not lim[j, 0] <= lim[j, 1]]
    if bad:
        raise InputError([design.problem(f"chain[{j + 1}].type", f"{names[j]!r} and {names[j + 1]!r} "
                                         "cannot be joined (the rods interfere at every angle)") for j in bad])
    lengths = t_len[[index[n] for n in names]]
    com = t_com[[index[n] for n in names]]
    masses = np.array([r.mass for r in design.chain], float)
    a, b = design.anchors
    try:
        eq, n_stable, unique = check_equilibrium(lengths, masses, a, b, com=com, limits=lim, g=design.g,
                                                 seed=design.seed)
    except ValueError as err:
        raise InputError([design.problem("anchors", str(err))]) from None
    target = None
    dist = None
    if design.target_curve is not None and len(design.target_curve) == len(names) + 1:
        target = design.target_curve
        dist = shape_distance(eq.points, target)
    res = BuildResult(design=design, method="", seed=design.seed, type_names=names, lengths=lengths,
                      masses=masses, com=com, limits=lim, target_points=target, equilibrium=eq,
                      distance=dist, n_stable=n_stable, unique=unique)
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
        notes.append(f"{r.n_stable} distinct stable equilibria were found from {N_STARTS} starts: the "
                     "chain may settle in another shape if hung carelessly (hang it from A, guide it "
                     "into shape, then attach B)")
    cd = r.chain_design
    if cd is not None:
        res = cd.result
        lo = int(np.sum(res.at_bounds < 0))
        hi = int(np.sum(res.at_bounds > 0))
        if not res.exact and (lo or hi):
            notes.append(f"the target is not reachable with the catalog's mass ranges: {lo} rod(s) at "
                         f"their lightest and {hi} at their heaviest; this is the best fit within what can "
                         "be printed (a catalog with wider mass ranges would get closer)")
    return notes


def fabricate(result: BuildResult, *, jobs: int | None = None, progress: Progress | None = None) -> None:
    """Build every rod's solid with its designed mass, then re-simulate the as-built chain."""
    from rodcad.cad.rods import fabricate_chain

    progress = progress or Progress(quiet=True)
    types = [result.design.catalog[n] for n in result.type_names]
    with progress.step(f"building {result.n} rods (cavities, ball sockets, exact B-rep)") as st:
        fab = fabricate_chain(types, result.masses, seed=result.design.fabrication_seed, jobs=jobs,
                              progress=st.count)
    result.fabrication = fab
    result.notes += list(fab.problems)
    masses = np.array([r.mass for r in fab.rods], float)
    com = np.array([r.com for r in fab.rods], float)
    a, b = result.design.anchors
    with progress.step("as-built check (masses and centres of mass from the solids)"):
        eq = solve_equilibrium(result.lengths, masses, a, b, com=com,
                               limits=result.limits if result.n > 1 else None, g=result.design.g)
    target = result.target_points if result.target_points is not None else result.equilibrium.points
    result.as_built = AsBuilt(masses, com, eq, shape_distance(eq.points, target))


def write_outputs(result: BuildResult, outdir: str | Path, *,
                  progress: Progress | None = None) -> dict[str, Any]:
    """Write design.json, report.md, preview.png/.svg and (with CAD) the STEP/STL files.

    Everything goes to a temporary folder first, renamed to ``outdir`` at the
    end: a failed or interrupted run leaves ``outdir`` as it was.

    Returns:
        The data written to design.json (for the terminal summary).
    """
    from rodcad.outputs.design_json import design_json, write_json
    from rodcad.outputs.report import report_markdown
    from rodcad.outdir import staged_output
    from rodcad.outputs.preview import plot_chain

    progress = progress or Progress(quiet=True)
    outdir = Path(outdir)
    with staged_output(outdir) as tmp:
        if result.fabrication is not None:
            from rodcad.cad.rods import write_assembly, write_rod_files

            with progress.step("writing and checking rods/*.step, rods/*.stl"):
                write_rod_files(result.fabrication, tmp)
            with progress.step("writing assembly.step"):
                write_assembly(result.fabrication, result.equilibrium.points, tmp / "assembly.step",
                               name=result.design.name)
        with progress.step("writing design.json, report.md, preview.png/.svg"):
            data = design_json(result)
            write_json(tmp / "design.json", data)
            plot_chain(result, tmp / "preview.png", tmp / "preview.svg")
            (tmp / "report.md").write_text(report_markdown(result, data), encoding="utf-8")
    return data


# --------------------------------------------------------------------------- chandeliers


@dataclass
class ChandelierBuild:
    """A designed (and optionally fabricated) chandelier.

    Attributes:
        design: the validated design.
        result: :class:`rodcad.design.chandelier.ChandelierDesign` (per-chain designs, bill of materials).
        frame_plan: the frame's layout (lugs, members).
        frame: the frame solid and its check (None without CAD).
        fabrications: per chain, the fabricated rods (None without CAD).
        as_built: per chain, the as-built re-simulation (None without CAD).
        notes: things the user should know.
        time_s: wall time.
    """

    design: Design
    result: Any
    frame_plan: Any
    frame: tuple[Any, Any] | None = None
    fabrications: list[Any] | None = None
    as_built: list[AsBuilt] | None = None
    notes: list[str] = field(default_factory=list)
    time_s: float = 0.0

    @property
    def meets_tolerance(self) -> bool:
        tol = self.design.tolerance
        return tol is None or all(c.distance.max_rel_span <= tol for c in self.result.chains)


def build_chandelier(design: Design, *, method: str | None = None, seed: int | None = None,
                     cad: bool | None = None, jobs: int | None = None,
                     progress: Progress | None = None) -> ChandelierBuild:
    """Design every chain of a chandelier, lay out its frame and (optionally) build it all."""
    from rodcad.cad.chandelier import build_frame
    from rodcad.design.chandelier import design_chandelier
    from rodcad.design.frame import plan_frame

    progress = progress or Progress(quiet=True)
    t0 = time.perf_counter()
    method = method or design.method
    seed = design.seed if seed is None else seed
    cad = design.cad if cad is None else cad
    c = design.constraints
    plan_options = {k: v for k, v in (("allowed_types", c.types), ("lengths", c.lengths),
                                      ("preferred_length", c.preferred_length)) if v is not None}
    with progress.step("joint limits and mass ranges of the catalog's rods") as st:
        arrays = catalog_arrays(design.catalog, jobs=jobs, progress=st.count)
    n = len(design.placements)
    with progress.step(f"inverse design of {n} chains ({method})"):
        try:
            res = design_chandelier(design.catalog, design.placements, design.chain_targets, method=method,
                                      seed=seed, jobs=jobs or 1, arrays=arrays, plan_options=plan_options,
                                      design_options={"n_starts": N_STARTS})
        except ValueError as err:
            raise InputError([design.problem("chandelier", str(err))]) from None
    if cad:
        _buildable_chains(design, res, method, seed, jobs, progress)
    frame_cfg = dict(design.chandelier.get("frame") or {})
    kind = frame_cfg.pop("kind", None) or _frame_kind(design)
    extra = {}
    if kind == "bars":
        # the polygon's vertices, or (explicit anchors) a closed polygon through every anchor in order
        extra["vertices"] = design.chandelier.get("vertices") or [
            list(map(float, a)) for p in design.placements for a in (p.a3, p.b3)]
    frame_plan = plan_frame(kind, design.placements, design.catalog, res.chains, **frame_cfg, **extra)
    out = ChandelierBuild(design, res, frame_plan)
    for ch in res.chains:
        eq = ch.design.result.equilibrium
        if not eq.stable:
            out.notes.append(f"{ch.name}: the designed shape is not a stable equilibrium")
        if not ch.design.unique:
            out.notes.append(f"{ch.name}: {ch.design.n_stable} stable shapes found; guide it into the designed one")
    if cad:
        from rodcad.cad.rods import fabricate_chain

        with progress.step("frame solid and clearance checks"):
            out.frame = build_frame(frame_plan, design.catalog, res.chains)
        out.notes += [f"frame: {p}" for p in out.frame[1].problems]
        types = [design.catalog[name] for ch in res.chains for name in ch.type_names]
        masses = np.concatenate([ch.masses for ch in res.chains])
        with progress.step(f"building {len(types)} rods") as st:
            fab = fabricate_chain(types, masses, seed=design.fabrication_seed, jobs=jobs, progress=st.count)
        out.notes += list(fab.problems)
        out.fabrications, out.as_built = [], []
        k = 0
        with progress.step("as-built check of every chain"):
            for ch in res.chains:
                m = len(ch.masses)
                rods = fab.rods[k:k + m]
                k += m
                out.fabrications.append(_chain_fabrication(fab, rods))
                pr = ch.design.plan.problem
                a2, b2 = ch.placement.plane_anchors()
                bm = np.array([r.mass for r in rods], float)
                bc = np.array([r.com for r in rods], float)
                eq = solve_equilibrium(pr.lengths, bm, a2, b2, com=bc, limits=pr.limits, g=design.g)
                out.as_built.append(AsBuilt(bm, bc, eq, shape_distance(eq.points, pr.target)))
    out.time_s = time.perf_counter() - t0
    return out


def _buildable_chains(design: Design, res: Any, method: str, seed: int, jobs: int | None,
                      progress: Progress) -> None:
    """Re-design every chain with masses the rods can really be built at (shared chains once)."""
    from rodcad.design.masses import design_buildable
    from rodcad.fabrication.intervals import chain_intervals

    names = sorted({n for ch in res.chains for n in ch.type_names})
    with progress.step("masses each rod type can really be built at"):
        intervals = chain_intervals([design.catalog[n] for n in names], seed=design.fabrication_seed, jobs=jobs)
    done: dict[int, Any] = {}
    with progress.step("inverse design with buildable masses"):
        for ch in res.chains:
            key = id(ch.design)
            if key not in done:
                done[key] = design_buildable(ch.design.plan, method, intervals=intervals, seed=seed,
                                             n_starts=N_STARTS)
            ch.design = done[key]


def _frame_kind(design: Design) -> str:
    from rodcad.design.spec import FRAME_OF_PATTERN

    return FRAME_OF_PATTERN[design.chandelier["pattern"]]


def _chain_fabrication(fab: Any, rods: list[Any]) -> Any:
    """The part of a fabrication that belongs to one chain, re-indexed from 0."""
    import dataclasses

    from rodcad.cad.rods import ChainFabrication

    rods = [dataclasses.replace(r, index=i, file_stem=f"{i:02d}_{r.type_name}") for i, r in enumerate(rods)]
    return ChainFabrication(rods, [], len({id(r.solid) for r in rods}), 0.0)


def write_chandelier_outputs(b: ChandelierBuild, outdir: str | Path, *,
                             progress: Progress | None = None) -> dict[str, Any]:
    """design.json, report.md, preview.png (3D) and, with CAD, assembly.step, frame.step/.stl
    and <chain>/rods/*.step|stl; staged like :func:`write_outputs`, whose return it shares."""
    from rodcad.cad.chandelier import chandelier_nodes
    from rodcad.design.frame import frame_outline
    from rodcad.outputs.preview3d import preview_3d
    from rodcad.outputs.design_json import chandelier_json, write_json
    from rodcad.outputs.report import chandelier_markdown
    from rodcad.outdir import staged_output

    progress = progress or Progress(quiet=True)
    with staged_output(outdir) as tmp:
        if b.frame is not None:
            from rodcad.cad.export import export_assembly, export_step, export_stl
            from rodcad.cad.rods import write_rod_files

            with progress.step("writing and checking the rods' STEP/STL files"):
                for ch, fab in zip(b.result.chains, b.fabrications):
                    write_rod_files(fab, tmp / ch.name)
            with progress.step("writing frame.step, frame.stl and assembly.step"):
                frame = b.frame[0]
                export_step(frame, tmp / "frame.step", name="frame")
                export_stl(frame, tmp / "frame.stl")
                nodes = chandelier_nodes(frame, b.result.chains, b.design.catalog, frame_plan=b.frame_plan,
                                           rod_solid=lambda ci, i: b.fabrications[ci].rods[i].solid)
                export_assembly(tmp / "assembly.step", nodes, b.design.name)
        with progress.step("writing design.json, report.md, preview.png"):
            data = chandelier_json(b)
            write_json(tmp / "design.json", data)
            preview_3d(tmp / "preview.png", b.result.chains, frame_outline(b.frame_plan),
                         title=f"{b.design.name}: {len(b.result.chains)} chains", svg=True)
            (tmp / "report.md").write_text(chandelier_markdown(b, data), encoding="utf-8")
    return data
