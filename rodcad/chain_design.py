"""From a target curve and a rod catalog to a designed chain (rod types and masses).

The data flow, one step per function:

    curve + catalog  -> plan_chain():   joints on the curve (chord walk with the
                                        catalog's lengths), a rod type per position
                                        (limits where the target needs moments),
                                        centres of mass, limits and mass ranges
                     -> design_chain(): masses by the chosen inverse method, the
                                        design re-simulated and checked for other
                                        stable equilibria (multi-start)
                     -> design_buildable(): the same, with every mass moved into
                                        the type's achievable intervals (gaps
                                        between ball counts) and the rest re-designed

Numbers cross into :mod:`optimize` as plain arrays (mm, g, radians).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from optimize import InverseProblem, InverseResult, design, find_equilibria
from optimize.assign import assign_types, joint_mismatch
from optimize.discretize import Discretization, discretize

__all__ = ["ChainPlan", "ChainDesign", "plan_chain", "design_chain", "design_buildable", "catalog_arrays"]


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
            :func:`optimize.assign.joint_mismatch`); inf where the chosen pair cannot hold
            the target bend at all.
        unmet_joints: joints whose target bend no allowed pair of types can hold (a straight
            or concave bend with no stop there, or a bend beyond every limit).
        added_stops: joints put on a stop (at a sagging or straight bend) because the masses
            alone could not hold the target within their ranges; the joints were moved onto
            the stop angles (see ``plan_chain(add_stops=...)``).
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


@dataclass
class ChainDesign:
    """A designed chain: the plan, the inverse-design result and its uniqueness check."""

    plan: ChainPlan
    result: InverseResult
    n_stable: int
    unique: bool


def catalog_arrays(catalog, *, jobs: int | None = None, progress: Callable | None = None):
    """Per-type arrays the numerics need.

    Returns:
        (types, lengths (T,), com (T, 2), mass_bounds (T, 2), pair_limits (T, T, 2) rad).
        Pairs that cannot be joined get limits (nan, nan).
    """
    from rodcad.limits import all_pair_limits

    types = list(catalog)
    t = len(types)
    lengths = np.array([ty.length for ty in types], dtype=float)
    com = np.array([ty.com for ty in types], dtype=float)
    bounds = np.array([ty.mass_range for ty in types], dtype=float)
    index = {ty.name: i for i, ty in enumerate(types)}
    lim = np.full((t, t, 2), np.nan)
    for (a, b), pl in all_pair_limits(catalog, jobs=jobs, progress=progress).items():
        if pl.assemblable:
            lim[index[a], index[b]] = pl.limits_rad
    return types, lengths, com, bounds, lim


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
        catalog: a loaded :class:`rodcad.catalog.Catalog`.
        curve: (M, 2) target polyline from anchor A to anchor B (mm).
        allowed_types: restrict to these type names (default: every type).
        lengths: restrict rod lengths to these values (default: the allowed types' lengths).
        preferred_length: the length to use most (default: chosen by the chord walk).
        arrays: precomputed :func:`catalog_arrays` (to share between chains).
        snap_stops: a stop whose computed limit lies within this many radians of the target
            bend it must hold is taken to sit exactly at the bend (default 0.01 deg). Limits
            come from a search on the B-rep to 0.005 deg (:data:`rodcad.limits.TOLERANCE_DEG`),
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
    types, t_len, t_com, t_bounds, t_lim = arrays if arrays is not None else catalog_arrays(catalog)
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
    from optimize.discretize import curve_distance

    r = design(plan.problem, "refine")
    return curve_distance(plan.curve, r.equilibrium.points), r


def _with_added_stops(plan: ChainPlan, allowed, joinable, names, t_com, t_bounds, snap_stops,
                       rounds: int = 2) -> ChainPlan:
    """Where fabrication bounds keep the masses from holding a sagging target, rest joints
    on stops at their (positive) bends and move the joints onto the stop angles
    (:func:`optimize.discretize.refit`); keep the result when the chain then hangs
    closer to the curve than the plan without them.

    A joint is a candidate when some allowed pair of types stops within
    :data:`STOP_REACH` of its bend. Each round tries three sets of stops: the
    fewest that let the masses hold the target (:func:`optimize.stops.needed_stops`),
    every candidate, and the near-straight candidates (bending less than the reach) that
    a pair can hold straight, held straight; the best is scored by the Hausdorff distance
    between the curve and the chain hanging with the masses ``refine`` gives it.
    """
    from optimize.discretize import refit
    from optimize.statics import exact_masses
    from optimize.stops import needed_stops

    if exact_masses(plan.problem)[2]:
        return plan  # the masses alone hold the target
    free_err, _ = _fit_error(plan)
    best, best_err = plan, free_err
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
            err, _ = _fit_error(cand)
            if err < best_err - 1e-6:
                best, best_err, improved = cand, err, True
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


def design_chain(
    plan: ChainPlan,
    method: str = "refine",
    *,
    seed: int = 0,
    max_nfev: int = 200,
    max_time: float | None = None,
    n_starts: int = 12,
) -> ChainDesign:
    """Masses for the plan, re-simulated, with a multi-start uniqueness check."""
    result = design(plan.problem, method, seed=seed, max_nfev=max_nfev, max_time=max_time)
    p = plan.problem
    a, b = p.anchors
    multi = find_equilibria(p.lengths, result.masses, a, b, com=p.com, limits=p.limits,
                            g=p.g, n_starts=n_starts, seed=seed)
    return ChainDesign(plan, result, multi.n_distinct, multi.unique)


# --------------------------------------------------------------------------- buildable masses

#: How :func:`design_buildable` picks the rods to fix in a round: 'all' fixes every mass
#: in a gap at once; 'worst' only those at least half as far into a gap (relative to
#: their mass) as the furthest one, so the rest can still adapt.
SNAP_STRATEGIES = ("all", "worst")


def _as_intervals(plan: ChainPlan, intervals) -> list[np.ndarray]:
    """Per position: the (k, 2) achievable intervals within the plan's mass bounds."""
    if isinstance(intervals, Mapping):
        intervals = [intervals[name] for name in plan.type_names]
    if len(intervals) != plan.problem.n:
        raise ValueError(f"intervals: need one list per rod ({plan.problem.n}), got {len(intervals)}")
    out = []
    for k, (iv, (lo, hi)) in enumerate(zip(intervals, plan.problem.mass_bounds)):
        a = np.asarray(sorted((float(x), float(y)) for x, y in iv), dtype=float).reshape(-1, 2)
        a = np.column_stack([np.maximum(a[:, 0], lo), np.minimum(a[:, 1], hi)]) if a.size else a
        a = a[a[:, 0] <= a[:, 1]]
        if not a.size:
            raise ValueError(f"rod {k} ({plan.type_names[k]}): no achievable mass interval within its "
                             f"bounds [{lo:.4g}, {hi:.4g}] g")
        out.append(a)
    return out


def _nearest(iv: np.ndarray, m: float) -> tuple[float, float, int]:
    """(nearest achievable mass, distance, interval index) for mass ``m``."""
    near = np.clip(m, iv[:, 0], iv[:, 1])
    i = int(np.argmin(np.abs(near - m)))
    return float(near[i]), float(abs(near[i] - m)), i


def _gap_cost(ivs: list[np.ndarray], masses: np.ndarray, scale: float) -> float:
    """Sum over rods of the relative distance from scale x mass to its nearest achievable mass."""
    return float(sum(_nearest(iv, scale * m)[1] / m for iv, m in zip(ivs, masses)))


def _best_scale(ivs: list[np.ndarray], masses: np.ndarray) -> float:
    """The common factor on every mass (the shape only depends on mass ratios) that
    puts the masses closest to achievable ones (summed relative distance; the cost is
    piecewise linear in the factor, so its minimum is at an interval edge / mass);
    ties go to the factor nearest 1."""
    cands = {1.0} | {float(e / m) for iv, m in zip(ivs, masses) for e in iv.ravel()}
    return min(cands, key=lambda f: (round(_gap_cost(ivs, masses, f), 12), abs(np.log(f))))


def _pin(iv: np.ndarray, m: float, i: int, rel: float = 1e-9) -> tuple[float, float]:
    """Nearly equal bounds around ``m`` inside interval ``i`` (the inverse design needs lo < hi)."""
    a, b = iv[i]
    w = rel * m
    lo, hi = max(a, m - w), min(b, m + w)
    if hi <= lo:  # a single-point interval
        lo, hi = m, m * (1 + rel)
    return lo, hi


def design_buildable(
    plan: ChainPlan,
    method: str = "refine",
    *,
    intervals,
    seed: int = 0,
    n_starts: int = 12,
    max_rounds: int = 4,
    max_nfev: int = 200,
    max_time: float | None = None,
    strategy: str = "all",
    rescale: bool = True,
) -> ChainDesign:
    """Masses for the plan that fabrication can really build, re-simulated and checked.

    The type's mass range [m_min, m_max] is not continuous (metal balls come in
    symmetric groups and add far more than the cavities beside them remove; see
    :func:`rodcad.fabricate.achievable_intervals`). This designs with the
    continuous bounds first, multiplies every mass by the common factor that
    brings them closest to achievable masses (the shape only depends on mass
    ratios), then repeatedly fixes the masses that fall in a gap
    at the nearest achievable mass (bounds pinned to within 1e-9) and re-runs the
    inverse design for the others, until every mass is achievable; after
    ``max_rounds`` re-designs the remaining ones are snapped without re-design.

    Args:
        plan: from :func:`plan_chain`.
        method: inverse method (:data:`optimize.METHODS`).
        intervals: per chain position, the achievable [(lo, hi), ...] in g (e.g.
            ``[achievable_intervals(catalog[name]) for name in plan.type_names]``), or
            a mapping type name -> intervals.
        seed, n_starts, max_nfev, max_time: as for :func:`design_chain` (per round).
        max_rounds: re-designs after the first, continuous one.
        strategy: which gap masses a round fixes (:data:`SNAP_STRATEGIES`).
        rescale: first multiply every mass by the common factor that brings them
            closest to achievable masses (the shape depends only on mass ratios).

    Returns:
        A :class:`ChainDesign` whose ``result.masses`` all lie in their intervals and
        whose equilibrium and distance belong to those masses; ``result.info['buildable']``
        records: ``snapped`` (rods fixed at an interval edge), ``rounds``, ``error_before`` /
        ``error_after`` (max joint error / span of the continuous design and of this one),
        ``max_error_before_mm`` / ``max_error_after_mm``, ``moved`` (index -> (designed g,
        built g)) and ``continuous_masses``. E.g.
        ``d.result.info['buildable']['error_after'] >= d.result.info['buildable']['error_before']``
        up to the optimiser's tolerance.
    """
    import time

    from optimize.inverse import finish_result
    from optimize.statics import statics_residual

    if strategy not in SNAP_STRATEGIES:
        raise ValueError(f"strategy must be one of {', '.join(SNAP_STRATEGIES)}; got {strategy!r}")
    t0 = time.perf_counter()
    p = plan.problem
    ivs = _as_intervals(plan, intervals)
    hull = np.array([[iv[0, 0], iv[-1, 1]] for iv in ivs])
    first = design(_with_bounds(p, hull), method, seed=seed, max_nfev=max_nfev, max_time=max_time)
    result = first
    # every mass times one factor gives the same shape: take the factor that puts the
    # most mass into the achievable intervals before fixing any
    scale = _best_scale(ivs, first.masses) if rescale else 1.0
    if scale != 1.0:
        from dataclasses import replace

        result = replace(first, masses=first.masses * scale)
    fixed: dict[int, tuple[float, float]] = {}
    moved: dict[int, tuple[float, float]] = {}
    nfev = first.nfev
    rounds = 0
    rel_gap = np.zeros(p.n)
    while True:
        m = result.masses
        snaps = {}
        for k in range(p.n):
            if k in fixed:
                continue
            near, dist, i = _nearest(ivs[k], float(m[k]))
            if dist > 1e-9 * m[k]:
                snaps[k] = (near, i)
                rel_gap[k] = dist / m[k]
        if not snaps:
            break
        if strategy == "worst":
            worst = max(rel_gap[k] for k in snaps)
            snaps = {k: v for k, v in snaps.items() if rel_gap[k] >= 0.5 * worst}
        for k, (near, i) in snaps.items():
            fixed[k] = _pin(ivs[k], near, i)
            moved[k] = (float(m[k]), near)
        if rounds >= max_rounds:  # snap whatever is left, no re-design
            masses = m.copy()
            for k in range(p.n):
                near, dist, i = _nearest(ivs[k], float(m[k]))
                if dist > 0:
                    moved.setdefault(k, (float(m[k]), near))
                masses[k] = near
            result = None
            break
        rounds += 1
        bounds = hull.copy()
        for k, b in fixed.items():
            bounds[k] = b
        result = design(_with_bounds(p, bounds), method, seed=seed, max_nfev=max_nfev, max_time=max_time)
        nfev += result.nfev
    if result is not None:
        masses = result.masses.copy()
        for k in range(p.n):  # within 1e-9 already: put it exactly inside
            masses[k] = _nearest(ivs[k], float(masses[k]))[0]
    history = list(first.history)
    info = dict(first.info)
    final = finish_result(p, method, masses, t0, nfev, history, statics_residual(p, masses),
                    f"buildable masses ({len(moved)} rod(s) fixed at an achievable mass, "
                    f"{rounds} re-design(s) after the continuous one)", info)
    final.info["buildable"] = {
        "snapped": len(moved),
        "rounds": rounds,
        "strategy": strategy,
        "scale": float(scale),
        "error_before": float(first.distance.max_rel_span),
        "error_after": float(final.distance.max_rel_span),
        "max_error_before_mm": float(first.distance.max),
        "max_error_after_mm": float(final.distance.max),
        "moved": {int(k): v for k, v in sorted(moved.items())},
        "continuous_masses": first.masses.tolist(),
    }
    a, b = p.anchors
    multi = find_equilibria(p.lengths, final.masses, a, b, com=p.com, limits=p.limits,
                            g=p.g, n_starts=n_starts, seed=seed)
    return ChainDesign(plan, final, multi.n_distinct, multi.unique)


def _with_bounds(problem: InverseProblem, bounds: np.ndarray) -> InverseProblem:
    return InverseProblem(target=problem.target, lengths=problem.lengths, mass_bounds=bounds,
                          com=problem.com, limits=problem.limits, g=problem.g)
