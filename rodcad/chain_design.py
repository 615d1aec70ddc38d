"""From a target curve and a rod catalog to a designed chain (rod types and masses).

The data flow, one step per function:

    curve + catalog  -> plan_chain():   joints on the curve (chord walk with the
                                        catalog's lengths), a rod type per position
                                        (limits where the target needs moments),
                                        centres of mass, limits and mass ranges
                     -> design_chain(): masses by the chosen inverse method, the
                                        design re-simulated and checked for other
                                        stable equilibria (multi-start)

Numbers cross into :mod:`optimize` as plain arrays (mm, g, radians).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from optimize import InverseProblem, InverseResult, design, find_equilibria
from optimize.assign import assign_types, joint_mismatch
from optimize.discretize import Discretization, discretize

__all__ = ["ChainPlan", "ChainDesign", "plan_chain", "design_chain", "catalog_arrays"]


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
    """

    curve: np.ndarray
    discretization: Discretization
    type_names: list[str]
    problem: InverseProblem
    assign_cost: float
    notes: list[str] = field(default_factory=list)
    joint_mismatch: np.ndarray = field(default_factory=lambda: np.zeros(0))
    unmet_joints: list[int] = field(default_factory=list)


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
    limits = np.array(limits, dtype=float)
    if limits.size:
        stop = (bends < np.radians(0.5)) & (np.abs(limits[:, 1] - bends) <= snap_stops)
        limits[stop, 1] = bends[stop]
    mismatch = joint_mismatch(bends, limits)
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
                     mismatch, unmet)


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
