"""Masses for a planned chain: the inverse design, re-simulated with a multi-start
uniqueness check, and its buildable variant (every mass moved onto what fabrication can make).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from optimize import (
    EquilibriumResult,
    InverseProblem,
    InverseResult,
    design,
    find_equilibria,
    solve_equilibrium,
)
from rodcad.design.plan import ChainPlan

__all__ = ['BuildableInfo', 'ChainCheck', 'ChainDesign', 'SNAP_STRATEGIES', 'check_chain', 'check_equilibrium', 'design_buildable', 'design_chain']


@dataclass(frozen=True)
class ChainCheck:
    """The designed chain solved from scratch, and whether its shape is the only stable one.

    Attributes:
        equilibrium: the equilibrium of the designed masses, solved from a sag guess.
        n_stable: distinct stable equilibria found by the multi-start.
        unique: the multi-start found no other stable shape.
        n_starts: starts of the multi-start.
        others: the other stable shapes the multi-start found (lowest energy first).
    """

    equilibrium: EquilibriumResult
    n_stable: int
    unique: bool
    n_starts: int
    others: tuple[EquilibriumResult, ...] = ()

    def hang_advice(self) -> str:
        """How to hang the chain so that it takes the designed shape, when another stable
        shape exists ('' when none was found): which joints differ, by how much, and whether
        the other shape lies lower (then a knock can move the chain into it)."""
        if not self.others:
            return ""
        eq = self.equilibrium
        bends = np.angle(np.exp(1j * np.diff(eq.angles)))
        parts = []
        for other in self.others[:2]:
            theirs = np.angle(np.exp(1j * np.diff(other.angles)))
            moved = np.flatnonzero(np.abs(np.angle(np.exp(1j * (theirs - bends)))) > np.radians(1.0))
            if not moved.size:
                continue
            j = int(moved[np.argmax(np.abs(theirs - bends)[moved])])
            lower = other.energy < eq.energy - 1e-9 * abs(eq.energy)
            warn = "; it lies LOWER than the designed one, so a knock can move the chain into it" if lower else ""
            parts.append(f"another stable shape differs at joint(s) {', '.join(map(str, moved))} (joint {j}: "
                         f"{np.degrees(theirs[j]):.0f} deg instead of {np.degrees(bends[j]):.0f}){warn}")
        if not parts:
            return ""
        return ("; ".join(parts) + ". To hang it as designed: hang it from A, hold the rods at those joints in "
                "the designed shape (on their stops, as the preview shows) while you attach B, then let go")


@dataclass(frozen=True)
class BuildableInfo:
    """How :func:`design_buildable` moved the masses onto buildable ones.

    Attributes:
        snapped: rods fixed at an achievable mass.
        rounds: re-designs after the continuous one.
        strategy: which gap masses a round fixed (:data:`SNAP_STRATEGIES`).
        scale: the common factor applied to every continuous mass first.
        error_before, error_after: max joint error / span of the continuous design and of this one.
        max_error_before_mm, max_error_after_mm: the same in mm.
        moved: rod index -> (designed mass, built mass) (g).
        continuous_masses: the continuous design's masses (g).
    """

    snapped: int
    rounds: int
    strategy: str
    scale: float
    error_before: float
    error_after: float
    max_error_before_mm: float
    max_error_after_mm: float
    moved: dict[int, tuple[float, float]]
    continuous_masses: list[float]


@dataclass
class ChainDesign:
    """A designed chain: the plan, the inverse-design result and its check.

    Attributes:
        plan: the plan the masses were designed for.
        result: the inverse-design result (masses, best-fit distance).
        check: the chain solved from scratch and the multi-start uniqueness check.
        buildable: how the masses were moved onto buildable ones, or None.
    """

    plan: ChainPlan
    result: InverseResult
    check: ChainCheck
    buildable: BuildableInfo | None = None

    @property
    def n_stable(self) -> int:
        return self.check.n_stable

    @property
    def unique(self) -> bool:
        return self.check.unique


def check_chain(plan: ChainPlan, masses: np.ndarray, *, seed: int = 0, n_starts: int = 12,
                g: float | None = None) -> ChainCheck:
    """Solve the designed chain from its designed state (the chain assembled in its shape,
    every joint on the stop the design puts it on) and look for other stable equilibria
    (multi-start)."""
    p = plan.problem
    if plan.verified is not None and (g is None or g == p.g) and n_starts <= plan.verified[1].starts:
        m, v = plan.verified  # the planner's own check of these very masses: the same answer
        if v.equilibrium is not None and np.array_equal(np.asarray(m, float), np.asarray(masses, float)):
            return ChainCheck(v.equilibrium, 1 + len(v.others), not v.others, v.starts, tuple(v.others))
    a, b = p.anchors
    joints, ends = p.designed_active()
    return check_equilibrium(p.lengths, masses, a, b, com=p.com, limits=p.limits, g=p.g if g is None else g,
                             seed=seed, n_starts=n_starts, end_limits=p.end_limits, active0=joints,
                             end_active0=ends if p.end_limits is not None else None)


def check_equilibrium(lengths: np.ndarray, masses: np.ndarray, a: np.ndarray, b: np.ndarray, *, com: np.ndarray,
                      limits: np.ndarray | None, g: float, seed: int = 0, n_starts: int = 12,
                      end_limits: np.ndarray | None = None, active0=None, end_active0=None) -> ChainCheck:
    """A chain solved (from scratch, or from the state ``active0`` / ``end_active0``: see
    :func:`optimize.solve_equilibrium`), and a multi-start for other stable equilibria
    (``end_limits``: the anchor fixture's bounds on the end rods' angles, rad).

    Raises:
        ValueError: the anchors are out of the chain's reach.
    """
    limits = limits if len(lengths) > 1 else None
    eq = solve_equilibrium(lengths, masses, a, b, com=com, limits=limits, g=g, end_limits=end_limits,
                           active0=active0 if limits is not None else None, end_active0=end_active0)
    multi = find_equilibria(lengths, masses, a, b, com=com, limits=limits, g=g, n_starts=n_starts, seed=seed,
                            end_limits=end_limits)
    span = float(np.hypot(*(np.asarray(b, float) - np.asarray(a, float))))
    others = tuple(e for e in multi.equilibria
                   if np.max(np.hypot(*(e.points - eq.points).T)) > 1e-7 * max(span, 1e-300))
    return ChainCheck(eq, multi.n_distinct, multi.unique, n_starts, others)


def design_chain(
    plan: ChainPlan,
    method: str = "refine",
    *,
    seed: int = 0,
    max_nfev: int = 200,
    max_time: float | None = None,
    n_starts: int = 12,
    g: float | None = None,
) -> ChainDesign:
    """Masses for the plan, checked once (:func:`check_chain`; ``g`` defaults to the problem's)."""
    result = design(plan.problem, method, seed=seed, max_nfev=max_nfev, max_time=max_time)
    return ChainDesign(plan, result, check_chain(plan, result.masses, seed=seed, n_starts=n_starts, g=g))


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
    g: float | None = None,
) -> ChainDesign:
    """Masses for the plan that fabrication can really build, re-simulated and checked.

    The type's mass range [m_min, m_max] is not continuous (metal balls come in
    symmetric groups and add far more than the cavities beside them remove; see
    :func:`rodcad.fabrication.intervals.achievable_intervals`). This designs with the
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
        seed, n_starts, max_nfev, max_time, g: as for :func:`design_chain` (per round).
        max_rounds: re-designs after the first, continuous one.
        strategy: which gap masses a round fixes (:data:`SNAP_STRATEGIES`).
        rescale: first multiply every mass by the common factor that brings them
            closest to achievable masses (the shape depends only on mass ratios).

    Returns:
        A :class:`ChainDesign` whose ``result.masses`` all lie in their intervals and
        whose equilibrium and distance belong to those masses; ``buildable``
        (:class:`BuildableInfo`) records how they were moved. E.g.
        ``d.buildable.error_after >= d.buildable.error_before`` up to the optimiser's
        tolerance.
    """
    import time

    from optimize.chain.inverse import finish_result
    from optimize.chain.statics import statics_residual

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
    final = finish_result(p, method, masses, t0, nfev, history, statics_residual(p, masses),
                    f"buildable masses ({len(moved)} rod(s) fixed at an achievable mass, "
                    f"{rounds} re-design(s) after the continuous one)", dict(first.info))
    info = BuildableInfo(
        snapped=len(moved), rounds=rounds, strategy=strategy, scale=float(scale),
        error_before=float(first.distance.max_rel_span), error_after=float(final.distance.max_rel_span),
        max_error_before_mm=float(first.distance.max), max_error_after_mm=float(final.distance.max),
        moved={int(k): v for k, v in sorted(moved.items())}, continuous_masses=first.masses.tolist())
    return ChainDesign(plan, final, check_chain(plan, final.masses, seed=seed, n_starts=n_starts, g=g), info)


def _with_bounds(problem: InverseProblem, bounds: np.ndarray) -> InverseProblem:
    return InverseProblem(target=problem.target, lengths=problem.lengths, mass_bounds=bounds,
                          com=problem.com, limits=problem.limits, g=problem.g, end_limits=problem.end_limits)
