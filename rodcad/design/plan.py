"""Rods laid on a target: a rod type per position whose joint limits supply what the target
needs, stops added where the masses alone cannot hold it, and every design constraint
applied (:func:`plan_constrained`).

    curve + catalog  -> catalog_arrays():   the catalog's lengths, centres of mass, mass
                                            ranges and pair limits (from the solids, cached)
                     -> plan_chain():       joints on the curve (chord walk with the
                                            catalog's lengths), a rod type per position,
                                            stops where the masses cannot hold the target
                     -> plan_constrained(): the same with the design's constraints (rod
                                            count, fixed rods), errors pointing at the key

The masses are designed next (:mod:`rodcad.design.masses`). Numbers cross into
:mod:`optimize` as plain arrays (mm, g, radians).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from optimize import InverseProblem, design
from optimize.chain.assign import assign_types, joint_mismatch
from optimize.chain.discretize import Discretization, discretize
from rodcad.catalog.limits import all_pair_limits
from rodcad.catalog.massrange import mass_info
from rodcad.catalog.model import Catalog, RodType
from rodcad.catalog.printed import mass_table
from rodcad.design.asprinted import robust_option
from rodcad.design.fit import DEFAULT_TOLERANCE
from rodcad.design.model import Constraints, FixedRod
from rodcad.design.printed import (
    PrintedFamily,
    PrintedPlan,
    ShellError,
    count_for,
    freest,
    plan_printed,
)
from rodcad.errors import DesignLimit, InputError, Problem

__all__ = ['CatalogArrays', 'ChainPlan', 'catalog_arrays', 'plan_chain', 'plan_constrained', 'STOP_REACH']


@dataclass
class ChainPlan:
    """A chain laid on a target: positions, rod types and what fabrication allows.

    Attributes:
        curve: (M, 2) target curve (mm).
        discretization: joints on the curve and the discretisation error.
        type_names: rod type per position.
        problem: the inverse problem handed to :mod:`optimize`.
        assign_cost: radians of mismatch between needed and available stops, summed over
            the joints where the target bend is possible with the chosen pair (0 = all met).
        notes: what the plan could not do, in words.
        joint_mismatch: (N-1,) per joint mismatch in radians (see
            :func:`optimize.chain.assign.joint_mismatch`); inf where the chosen pair cannot hold
            the target bend at all.
        unmet_joints: joints whose target bend no allowed pair of types can hold (a straight
            or concave bend with no stop there, or a bend beyond every limit).
        added_stops: joints put on a stop (at a sagging or straight bend) because the masses
            alone could not hold the target within their ranges; the joints were moved onto
            the stop angles (see ``plan_chain(add_stops=...)``); for rods printed to order,
            every joint resting on a stop printed at its bend.
        rods: the rods made to order (rods printed to order), in chain order; empty for a
            catalog's fixed menu.
        fused: rods printed as one rigid piece, (first, last) rod indices.
        verified: (masses, :class:`optimize.chain.verify.Verdict`) the planner checked for this
            very problem, or None.
    """

    curve: np.ndarray
    discretization: Discretization
    type_names: list[str]
    problem: InverseProblem
    assign_cost: float
    notes: list[str] = field(default_factory=list)
    joint_mismatch: np.ndarray = field(default_factory=lambda: np.zeros(0))
    unmet_joints: list[int] = field(default_factory=list)
    added_stops: list[int] = field(default_factory=list)
    rods: list[RodType] = field(default_factory=list)
    fused: list[tuple[int, int]] = field(default_factory=list)
    verified: tuple[np.ndarray, object] | None = None


@dataclass(frozen=True)
class CatalogArrays:
    """Per-type numbers of a catalog, as the numerics need them (catalog order).

    Attributes:
        types: the rod types.
        lengths: (T,) pin-to-pin lengths (mm).
        com: (T, 2) centres of mass (along, perp) in the rod frame (mm).
        mass_bounds: (T, 2) achievable mass range [m_min, m_max] (g).
        pair_limits: (T, T, 2) joint limits (rad) of type i followed by type j;
            (nan, nan) where the pair cannot be joined, +-inf on a side nothing stops.
        catalog: the catalog.
        printed: its families printed to order, with their mass tables.
    """

    types: tuple[RodType, ...]
    lengths: np.ndarray
    com: np.ndarray
    mass_bounds: np.ndarray
    pair_limits: np.ndarray
    catalog: Catalog | None = None
    printed: tuple[PrintedFamily, ...] = ()

    @property
    def names(self) -> list[str]:
        return [t.name for t in self.types]

    @cached_property
    def index(self) -> dict[str, int]:
        """Type name -> position."""
        return {t.name: i for i, t in enumerate(self.types)}

    def limits_of(self, names: Sequence[str]) -> np.ndarray:
        """(N-1, 2) joint limits (rad) of a sequence of types; (-inf, inf) for free sides and
        (nan, nan) where two neighbours cannot be joined."""
        k = [self.index[n] for n in names]
        return self.pair_limits[k[:-1], k[1:]].reshape(-1, 2)


def catalog_arrays(catalog: Catalog, *, jobs: int | None = None,
                   progress: Callable | None = None) -> CatalogArrays:
    """The catalog's per-type numbers: lengths, centres of mass, mass ranges, pair limits
    (joint limits and mass ranges from the solids, disk-cached).

    Raises:
        InputError: two types that mate interfere at every angle (pointing at the family).
    """
    types = tuple(catalog)
    t = len(types)
    index = {ty.name: i for i, ty in enumerate(types)}
    lim = np.full((t, t, 2), np.nan)
    problems = []
    for (a, b), pl in all_pair_limits(catalog, jobs=jobs, progress=progress).items():
        if pl.assemblable:
            lim[index[a], index[b]] = pl.limits_rad
        else:
            problems.append(catalog[b].origin.problem(
                f"rod types {a!r} and {b!r} interfere at every angle: they cannot be joined (their ends overlap "
                "whatever the bend; shorten the chamfers or add setback)"))
    if problems:
        raise InputError(problems)
    printed = tuple(PrintedFamily(f, mass_table(f, jobs=jobs)) for f in catalog.printed_families)
    return CatalogArrays(types, np.array([ty.length for ty in types], dtype=float),
                         np.array([mass_info(ty).com for ty in types], dtype=float).reshape(-1, 2),
                         np.array([mass_info(ty).mass_range for ty in types], dtype=float).reshape(-1, 2),
                         lim, catalog, printed)


def plan_chain(
    catalog,
    curve,
    *,
    allowed_types: Sequence[str] | None = None,
    lengths: Sequence[float] | None = None,
    preferred_length: float | None = None,
    arrays=None,
    snap_stops: float = np.radians(0.01),
    add_stops: bool = True,
) -> ChainPlan:
    """Lay a chain of the catalog's rods on the target curve.

    Args:
        catalog: a loaded :class:`rodcad.catalog.model.Catalog`.
        curve: (M, 2) target polyline from anchor A to anchor B (mm).
        allowed_types: restrict to these type names (default: every type).
        lengths: restrict rod lengths to these values (default: the allowed types' lengths).
        preferred_length: the length to use most (default: chosen by the chord walk).
        arrays: precomputed :func:`catalog_arrays` (to share between chains).
        snap_stops: a stop whose computed limit lies within this many radians of the target
            bend it must hold is taken to sit exactly at the bend (default 0.01 deg). Limits
            come from a search on the B-rep to 0.005 deg (:data:`rodcad.catalog.limits.TOLERANCE_DEG`),
            so a flush stop designed for 0 deg reads -0.0006 deg; without snapping, the
            straight run would be 0.0006 deg from its stop and the exact statics would fail.
        add_stops: when the masses cannot hold the target within the types' mass ranges
            (a semicircle's near-vertical ends need end rods many times heavier than the
            middle), let joints rest on stops where the catalog has types that stop near the
            target bend (pla-weighted's curve10 / curve20 at +5 to +20 deg, straight stops
            at 0), moving the joints onto the stop angles; kept only when the chain then
            hangs closer to the curve. ``ChainPlan.added_stops`` lists those joints.

    Raises:
        ValueError: the rods cannot be laid on the curve (explained).
    """
    arrays = arrays if arrays is not None else catalog_arrays(catalog)
    types, t_len, t_com, t_bounds, t_lim = (arrays.types, arrays.lengths, arrays.com, arrays.mass_bounds,
                                            arrays.pair_limits)
    names = [ty.name for ty in types]
    use = np.ones(len(types), dtype=bool)
    if allowed_types is not None:
        use &= np.isin(names, list(allowed_types))
    if lengths is not None:
        use &= np.isin(t_len, np.asarray(lengths, dtype=float))
    if not use.any():
        raise ValueError("no rod type of the catalog is allowed by the design's constraints")
    disc = discretize(np.asarray(curve, float), sorted(set(t_len[use].tolist())),
                      preferred=preferred_length)
    n = disc.lengths.size
    allowed = use[None, :] & np.isclose(t_len[None, :], disc.lengths[:, None])
    d = np.diff(disc.points, axis=0)
    theta = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
    joinable = np.where(np.isnan(t_lim), 0.0, t_lim)
    # unjoinable pairs: limits that exclude every bend
    joinable[np.isnan(t_lim[..., 0])] = [np.inf, -np.inf]
    bends = np.diff(theta)
    chosen, limits, _ = assign_types(bends, allowed, joinable)
    plan = _make_plan(curve, disc, chosen, limits, names, t_com, t_bounds, snap_stops)
    if add_stops and n > 1:
        plan = _with_added_stops(plan, allowed, joinable, names, t_com, t_bounds, snap_stops)
    return plan


#: A stop is tried at a joint only when some allowed pair of types stops within
#: this many radians of the target bend; the joints are then moved onto the stops.
STOP_REACH = np.radians(5.0)

#: Two sets of stops whose chains hang within this share of each other from the curve are
#: told apart by how near their joints hang to the target (:func:`_better`).
STOP_TIE = 0.01


def _make_plan(curve, disc, chosen, limits, names, t_com, t_bounds, snap_stops,
               fixed=()) -> ChainPlan:
    """The plan for chosen types: limits snapped onto the bends they hold, notes, problem."""
    n = disc.lengths.size
    d = np.diff(disc.points, axis=0)
    bends = np.diff(np.unwrap(np.arctan2(d[:, 1], d[:, 0])))
    limits = np.array(limits, dtype=float)
    if limits.size:
        stop = (bends < np.radians(0.5)) & (np.abs(limits[:, 1] - bends) <= snap_stops)
        stop[list(fixed)] = True
        limits[stop, 1] = bends[stop]
    mismatch = joint_mismatch(bends, limits)
    mismatch[list(fixed)] = 0.0
    unmet = [int(j) for j in np.flatnonzero(~np.isfinite(mismatch))]
    cost = float(np.sum(mismatch[np.isfinite(mismatch)]))
    notes = []
    for j in np.flatnonzero(mismatch > np.radians(0.5)):
        need = np.degrees(bends[j])
        lo, hi = np.degrees(limits[j])
        pair = f"{names[chosen[j]]} -> {names[chosen[j + 1]]}"
        if not lo <= hi:
            have = "no pair of allowed types joins there"
        elif bends[j] < np.radians(0.5):
            have = f"the nearest stop of the allowed types ({pair}) is at {hi:.1f} deg"
        else:
            have = f"the best pair of allowed types ({pair}) bends within [{lo:.1f}, {hi:.1f}] deg"
        kind = "a stop at" if bends[j] < np.radians(0.5) else "a free bend of"
        notes.append(f"joint {j} needs {kind} {need:.1f} deg, but {have}")
    if notes:
        notes.append(
            f"the catalog's stops and limits miss what the target needs by "
            f"{np.degrees(cost):.1f} degrees in all"
            + (f" and cannot hold joint(s) {unmet} at all" if unmet else "")
            + "; the masses will fit the target as well as they can"
        )
    problem = InverseProblem(
        target=disc.points,
        lengths=disc.lengths,
        mass_bounds=t_bounds[chosen],
        com=t_com[chosen],
        limits=limits if n > 1 else np.zeros((0, 2)),
    )
    return ChainPlan(np.asarray(curve, float), disc, [names[i] for i in chosen], problem, cost, notes,
                     mismatch, unmet, sorted(int(j) for j in fixed))


def _fit_error(plan: ChainPlan) -> tuple[float, object]:
    """Hausdorff distance (mm) between the target curve and the chain hanging with the
    masses ``refine`` chooses for the plan, and that result."""
    from optimize.chain.curves import curve_distance

    r = design(plan.problem, "refine")
    return curve_distance(plan.curve, r.equilibrium.points), r


def _better(err: float, joints: float, best_err: float, best_joints: float) -> bool:
    """Whether a plan whose chain hangs ``err`` mm from the curve with its joints at most
    ``joints`` mm from their targets beats the best so far: the nearer curve, but between two
    within :data:`STOP_TIE` of each other (which the refine's own convergence does not tell
    apart: which wins depended on the machine's last bits) the nearer joints."""
    if abs(err - best_err) <= STOP_TIE * best_err:
        return joints < best_joints * (1 - STOP_TIE)
    return err < best_err - 1e-6


def _with_added_stops(plan: ChainPlan, allowed, joinable, names, t_com, t_bounds, snap_stops,
                       rounds: int = 2) -> ChainPlan:
    """Where fabrication bounds keep the masses from holding a sagging target, rest joints
    on stops at their (positive) bends and move the joints onto the stop angles
    (:func:`optimize.chain.discretize.refit`); keep the result when the chain then hangs
    closer to the curve than the plan without them.

    A joint is a candidate when some allowed pair of types stops within
    :data:`STOP_REACH` of its bend. Each round tries three sets of stops: the
    fewest that let the masses hold the target (:func:`optimize.chain.stops.needed_stops`),
    every candidate, and the near-straight candidates (bending less than the reach) that
    a pair can hold straight, held straight; the best is scored by the Hausdorff distance
    between the curve and the chain hanging with the masses ``refine`` gives it.
    """
    from optimize.chain.discretize import refit
    from optimize.chain.statics import exact_masses
    from optimize.chain.stops import needed_stops

    if exact_masses(plan.problem)[2]:
        return plan  # the masses alone hold the target
    free_err, free_res = _fit_error(plan)
    best, best_err, best_joints = plan, free_err, float(free_res.distance.max)
    lo_all, hi_all = joinable[..., 0], joinable[..., 1]
    seen: set[tuple[int, ...]] = set()
    current = plan
    for _ in range(rounds):
        p = current.problem
        bends = np.diff(p.angles)
        on_limit = set(int(j) for j in np.flatnonzero(np.abs(p.limits[:, 1] - bends) <= 1e-6))
        near, straight = set(), set()  # joints with a stop within reach; of those, near-straight
        for j in range(bends.size):
            if j in on_limit or bends[j] <= 0:
                continue
            pair = np.ix_(np.flatnonzero(allowed[j]), np.flatnonzero(allowed[j + 1]))
            hi, lo = hi_all[pair], lo_all[pair]
            gap = np.where(np.isfinite(hi) & (lo <= hi), np.abs(hi - bends[j]), np.inf)
            if gap.min() <= STOP_REACH:
                near.add(j)
                if bends[j] <= STOP_REACH and np.any(np.abs(hi) < 1e-3):
                    straight.add(j)
        if not near:
            break
        need = needed_stops(p, sorted(near))
        options = [(near, set()), (straight, straight)]
        if need is not None and need.size:
            options.insert(0, (set(need.tolist()), set()))
        improved = False
        for opt, flat in options:
            keep = {j for j in on_limit if bends[j] > 0}  # earlier convex stops stay
            key = tuple(sorted(opt | keep))
            if not opt or (key, tuple(sorted(flat))) in seen:
                continue
            seen.add((key, tuple(sorted(flat))))
            mask = np.zeros(bends.size, dtype=bool)
            mask[list(key)] = True
            wanted = bends.copy()
            wanted[list(flat)] = 0.0  # near-straight: held straight
            chosen, limits, _ = assign_types(wanted, allowed, joinable, need_stop=mask)
            fixed = {int(j): float(limits[j, 1]) for j in key}
            for j in on_limit:  # straight runs and concave stops stay on their stops
                fixed.setdefault(j, float(limits[j, 1]))
            # a flush stop designed straight reads within the search tolerance of 0: straight
            fixed = {j: 0.0 if abs(v) <= snap_stops else v for j, v in fixed.items()}
            if any(not np.isfinite(v) for v in fixed.values()):
                continue
            disc = refit(current.curve, p.target, p.lengths, fixed)
            if disc is None:
                continue
            disc.corners = list(plan.discretization.corners)
            cand = _make_plan(current.curve, disc, chosen, limits, names, t_com, t_bounds, snap_stops,
                              fixed=[j for j in fixed if j not in on_limit])
            err, res = _fit_error(cand)
            joints = float(res.distance.max)
            if _better(err, joints, best_err, best_joints):
                best, best_err, best_joints, improved = cand, err, joints, True
        if not improved or exact_masses(best.problem)[2]:
            break
        current = best
    if best is not plan:
        stops = ", ".join(f"{j} ({round(np.degrees(best.problem.limits[j, 1]), 1) + 0.0:.1f} deg)"
                          for j in best.added_stops)
        best.notes.insert(0, (
            f"the masses alone cannot hold this shape within the rods' mass ranges, so joints {stops} "
            f"rest on stops (the adjacent rods' ends meet there) and were moved onto the stop "
            f"angles; the chain hangs within {best_err:.3g} mm of the curve (without these stops "
            f"{free_err:.3g} mm)"))
    return best


def plan_constrained(curve: np.ndarray, constraints: Constraints, arrays: CatalogArrays,
                     problem: Callable[[str, str], Problem], *, label: str = "", report=None) -> ChainPlan:
    """Lay rods on a target with every constraint of a design applied (the one place
    they are): allowed types and lengths, the preferred length, the rod count (trying
    each allowed length as the preferred one until the count is met) and fixed rods
    (their types, then their masses).

    Args:
        curve: (M, 2) target polyline from A to B (mm).
        constraints: the design's constraints.
        arrays: the catalog's numbers (:func:`catalog_arrays`).
        problem: makes a :class:`rodcad.errors.Problem` pointing at a key of the design
            file (``Design.problem``).
        label: the chain's name in messages (a chandelier's chains), or "".
        report: called with a line of progress now and then (or None).

    Raises:
        InputError: the constraints cannot be met on this target (pointing at the key).
    """
    c = constraints
    who = f"{label}: " if label else ""
    printed = _printed_family(arrays, c)
    if printed is not None:
        return _plan_printed(curve, c, arrays, printed, problem, who, report)
    if c.same_shell:
        raise InputError([problem("constraints.same_shell", f"{who}one shell for every rod needs a family printed "
                                  "to order (the default catalog pla-parametric); this catalog's rod types are a "
                                  "fixed menu")])
    if c.fuse in ("auto", "stops"):
        raise InputError([problem("constraints.fuse", f"{who}fused pieces are printed to order: they need a family "
                                  "printed to order (the default catalog pla-parametric)")])
    if c.anchor_stops == "auto":
        raise InputError([problem("constraints.anchor_stops", f"{who}anchor stops chosen by the planner need a family "
                                  "printed to order (the default catalog pla-parametric); with this catalog's fixed "
                                  "menu give the fixture's bounds as anchor_limits_deg")])
    candidates: list[float | None] = [c.preferred_length]
    if c.rods is not None and c.preferred_length is None:
        allowed = {float(x) for x, t in zip(arrays.lengths, arrays.types) if c.types is None or t.name in c.types}
        if c.lengths is not None:
            allowed &= {float(x) for x in c.lengths}
        candidates = [None, *sorted(allowed)]
    counts: dict[int, ChainPlan] = {}
    for pref in candidates:
        try:
            p = plan_chain(None, curve, allowed_types=c.types, lengths=c.lengths, preferred_length=pref,
                           arrays=arrays)
        except ValueError as err:
            raise InputError([problem("target", f"{who}{err}")]) from None
        counts.setdefault(len(p.type_names), p)
        if c.rods is None or len(p.type_names) == c.rods:
            break
    if c.rods is not None and c.rods not in counts:
        have = ", ".join(str(k) for k in sorted(counts))
        raise InputError([problem(
            "constraints.rods", f"{who}the allowed rod lengths lay {have} rods on this target, not {c.rods}; "
            "change the rod count, the lengths allowed or preferred_length")])
    p = counts[c.rods] if c.rods is not None else next(iter(counts.values()))
    if c.fixed:
        _apply_fixed(p, c.fixed, arrays, problem, who)
    if c.end_limits is not None:
        p.problem = dataclasses.replace(p.problem, end_limits=c.end_limits)
    return p


def _printed_family(arrays: CatalogArrays, c: Constraints) -> PrintedFamily | None:
    """The family printed to order the design uses: the first one the constraints allow
    (``types`` naming its reference rods), or None for the catalog's fixed menu."""
    for pf in arrays.printed:
        if c.types is None or any(n in pf.family.type_names for n in c.types):
            return pf
    return None


def _plan_printed(curve: np.ndarray, c: Constraints, arrays: CatalogArrays, pf: PrintedFamily,
                  problem: Callable[[str, str], Problem], who: str, report=None) -> ChainPlan:
    """Rods printed to order on the target, with the constraints that apply to them."""
    problems = []
    r = pf.family.ranges
    assert r is not None and arrays.catalog is not None
    span = f"{r.length[0]:g} to {r.length[1]:g} mm"
    if c.lengths is not None:
        problems.append(problem("constraints.lengths", f"{who}family {pf.family.name!r} is printed to order "
                                f"(any length from {span}): use preferred_length or rods instead"
                                + (" (same_shell gives every rod one length)" if c.same_shell else "")))
    if c.fixed:
        problems.append(problem("constraints.fixed", f"{who}family {pf.family.name!r} is printed to order: every "
                                "rod is made for its place, so there are no catalog rods to fix"))
    if c.preferred_length is not None and not r.length[0] <= c.preferred_length <= r.length[1]:
        problems.append(problem("constraints.preferred_length", f"{who}{c.preferred_length:g} mm is outside the "
                                f"lengths family {pf.family.name!r} prints ({span})"))
    if problems:
        raise InputError(problems)
    free, same = c.joints == "free", c.same_shell
    misfit = _fixture_misfit(curve, pf, arrays.catalog.printer)
    ends = {"anchor_stops": c.anchor_stops_allowed and c.end_limits is None and misfit is None,
            "end_limits": c.end_limits, "fuse": c.fuse_mode, "report": report,
            "robust": robust_option(curve, pf, arrays.catalog) if c.robust else None}
    try:
        if c.rods is not None:
            lp = count_for(curve, arrays.catalog, pf, c.rods, stops_allowed=not free, same_shell=same, **ends)
            if lp is None:
                raise InputError([problem("constraints.rods", f"{who}{c.rods} rods of {span} do not lay on this "
                                          "target with every corner a joint; change the rod count")])
        else:
            lp = plan_printed(curve, arrays.catalog, pf, preferred_length=c.preferred_length, stops_allowed=not free,
                              same_shell=same, **ends)
            if c.preferred_length is None and not same:  # longer rods where they keep more joints free
                lp = freest(curve, arrays.catalog, pf, lp, tolerance=DEFAULT_TOLERANCE, stops_allowed=not free,
                            same_shell=same, **ends)
    except ShellError as err:
        raise InputError([problem("constraints.same_shell", f"{who}{err}")]) from None
    except ValueError as err:  # the rods cannot be laid on this target: a limit, not the file's mistake
        raise DesignLimit(f"{who}cannot lay rods of {span} on this target: {err}") from None
    plan = _from_printed(curve, lp)
    if misfit is not None and c.anchor_stops_allowed and c.end_limits is None:
        plan.notes.append(misfit)
    return plan


#: How far the anchor fixture's outline reaches past each anchor pin (mm): the larger of its
#: knuckle and its stop peg (3 mm) plus its rim (2.5 mm), as rodcad.cad.fixture builds it.
FIXTURE_PEG_RADIUS, FIXTURE_RIM = 3.0, 2.5


def _fixture_misfit(curve: np.ndarray, pf: PrintedFamily, printer=None) -> str | None:
    """Why one anchor fixture cannot hold both anchors (None: it can): they must be far enough
    apart for its two knuckles (one piece, a wall between them) and near enough for it to fit
    the printer (it spans them); else the planner uses bare pins."""
    t = pf.family.template
    hg = t.geometry.hinge
    dist = float(np.hypot(*(curve[-1] - curve[0])))
    if dist < hg.zone_radius + hg.knuckle_radius + t.material.min_wall:
        return (f"the anchors are {dist:.1f} mm apart: too close for an anchor fixture's two knuckles, so the "
                "end rods hang from bare pins")
    if printer is None:
        return None
    length = dist + 2 * (max(hg.knuckle_radius, FIXTURE_PEG_RADIUS) + FIXTURE_RIM)
    if length > max(printer.build_volume):
        vol = " x ".join(f"{v:g}" for v in printer.build_volume)
        return (f"the anchors are {dist:.0f} mm apart: a fixture holding both ({length:.0f} mm long) would not fit "
                f"the printer ({vol} mm), so the end rods hang from bare pins")
    return None


def _from_printed(curve: np.ndarray, lp: PrintedPlan) -> ChainPlan:
    n = len(lp.rods)
    mismatch = np.zeros(max(n - 1, 0))
    mismatch[lp.unmet] = np.inf
    return ChainPlan(np.asarray(curve, float), lp.discretization, [t.name for t in lp.rods], lp.problem, 0.0,
                     list(lp.notes), mismatch, list(lp.unmet), list(lp.stops), list(lp.rods), list(lp.fused),
                     lp.verified)


def _apply_fixed(p: ChainPlan, fixed: Sequence[FixedRod], arrays: CatalogArrays,
                 problem: Callable[[str, str], Problem], who: str) -> None:
    """Impose fixed rods on a plan (types, then masses)."""
    n = len(p.type_names)
    problems = []
    for i, f in enumerate(fixed):
        key = f"constraints.fixed[{i}]"
        if f.index >= n:
            problems.append(problem(f"{key}.index", f"{who}the chain has {n} rods (indices 0 to {n - 1})"))
            continue
        need = float(p.problem.lengths[f.index])
        k = arrays.index[f.type]
        if not np.isclose(arrays.lengths[k], need):
            problems.append(problem(f"{key}.type", f"{who}rod {f.index} is {need:g} mm long on this target "
                                    f"but {f.type!r} is {arrays.lengths[k]:g} mm"))
            continue
        p.type_names[f.index] = f.type
        p.problem.com[f.index] = arrays.com[k]
        lo, hi = arrays.mass_bounds[k]
        if f.mass is not None:
            lo, hi = f.mass * (1 - 1e-9), f.mass * (1 + 1e-9)
        p.problem.mass_bounds[f.index] = (lo, hi)
    if problems:
        raise InputError(problems)
    lim = arrays.limits_of(p.type_names)
    bad = [j for j in range(n - 1) if not lim[j, 0] <= lim[j, 1]]
    if bad:
        j = bad[0]
        raise InputError([problem("constraints.fixed", f"{who}rods {j} ({p.type_names[j]}) and {j + 1} "
                                  f"({p.type_names[j + 1]}) cannot be joined")])
    if n > 1:
        p.problem.limits = lim
    p.notes.append(f"{len(fixed)} rod(s) fixed by the design")
