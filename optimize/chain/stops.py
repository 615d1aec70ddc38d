"""Where the masses cannot hold a sagging target, stops can.

At the target, statics is linear in the masses, the reaction at B and the moments at
joints resting on stops (:func:`optimize.chain.statics.statics_matrix`). A sagging (convex)
joint needs no moment when the masses are free, but fabrication bounds the masses: a
semicircle's near-vertical ends need end rods many times heavier than any rod type can
be. A stop on the joint's sagging side, placed exactly at the target bend, supplies a
moment of one sign (it only pushes back against more sag). :func:`needed_stops` finds
the fewest such stops, as the L1-smallest moments that balance the target with every
mass inside its bounds (a linear program; L1 favours few non-zero moments).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.optimize import linprog

from optimize.chain.problem import InverseProblem
from optimize.chain.statics import moment_signs, scaled_statics, statics_matrix

__all__ = ["needed_stop_sides", "needed_stops"]


def needed_stops(problem: InverseProblem, candidates=None, *, rel_tol: float = 1e-7) -> np.ndarray | None:
    """Joints that must rest on a stop at their target bend for the target to be an
    equilibrium with every mass inside its bounds.

    Args:
        problem: the target, rods and mass bounds; joints already resting on a limit keep
            their stops (their moments are free and cost nothing).
        candidates: joints that may get a stop on their sagging side (default: every
            interior joint not already on a limit whose target bend is convex, phi > 0).
        rel_tol: a candidate's moment counts as needed above this fraction of the largest.

    Returns:
        Sorted joint indices (empty when the masses alone can hold the target), or None
        when even stops at every candidate cannot balance it (a moment of the wrong sign
        would be needed: the target bends less than the chain wants to somewhere a stop
        on the sagging side cannot help).
    """
    phi = np.diff(problem.angles)
    lim = problem.limits.copy()
    on_limit = set(statics_matrix(problem)[1].tolist())
    if candidates is None:
        candidates = [j for j in range(phi.size) if phi[j] > 0]
    cand = np.array(sorted(set(int(j) for j in candidates) - on_limit), dtype=int)
    if cand.size:
        lim[cand, 1] = phi[cand]
        lim[cand, 0] = np.minimum(lim[cand, 0], phi[cand])
    trial = replace(problem, limits=lim)
    A, stops, signs = statics_matrix(trial)
    n = problem.n
    row, col = scaled_statics(trial, A)
    As = (A * row[:, None]) * col[None, :]
    nvar = A.shape[1]
    lb = np.full(nvar, -np.inf)
    ub = np.full(nvar, np.inf)
    lb[:n], ub[:n] = problem.mass_bounds[:, 0] / col[:n], problem.mass_bounds[:, 1] / col[:n]
    new = np.isin(stops, cand)
    # a new stop sits on the sagging side (hi): its moment is <= 0; existing stops keep their signs
    moment_signs(signs, lb[n + 2:], ub[n + 2:])
    c = np.zeros(nvar)
    c[n + 2:][new] = -1.0  # minimise sum |mu| over the new stops (all <= 0)
    bounds = list(zip(np.where(np.isfinite(lb), lb, None), np.where(np.isfinite(ub), ub, None)))
    lp = linprog(c, A_eq=As, b_eq=np.zeros(n), bounds=bounds, method="highs")
    if lp.status != 0:
        return None
    mu = np.abs(lp.x[n + 2:][new])
    if mu.size == 0 or mu.max() <= 0:
        return np.zeros(0, dtype=int)
    return np.sort(stops[new][mu > rel_tol * max(mu.max(), 1e-300)]).astype(int)


#: Reweighted L1 rounds of :func:`needed_stop_sides` (the fewest stops found is kept).
REWEIGHT_ROUNDS = 4


def needed_stop_sides(problem: InverseProblem, candidates, *, rel_tol: float = 1e-7, ends=(), forced=(),
                      end_weight: float = 1.0):
    """Like :func:`needed_stops`, for stops printed to order on either side: a candidate
    joint may rest on a stop that keeps it from bending further (hi, moment <= 0) or from
    straightening (lo, moment >= 0), each placed exactly at its target bend.

    Args:
        problem: the target, rods and mass bounds; joints already on a limit keep it (a
            rigid joint, lo == hi, takes a moment of either sign at no cost).
        candidates: joints that may get a stop (either side); the fewest are chosen
            (reweighted L1 of their moments).
        rel_tol: a moment counts as needed above this fraction of the largest.
        ends: anchors whose fixture may stop the end rod at its target angle: 0 (A, the
            first rod) and/or 1 (B, the last rod).
        forced: joints that rest on a stop whatever the masses (a straight or concave
            bend): their side is chosen here at (almost) no cost, and they are always in
            the result (on the hi side where they carry no moment).
        end_weight: the cost of an anchor stop relative to a joint's.

    Returns:
        (joints, sides): sorted joint indices and, per joint, -1 for a stop on the sagging
        side (hi) or +1 on the other side (lo); empty arrays when the masses alone can hold
        the target; None when no set of stops can. An anchor stop is joint -1 (A) or N-1
        (B), its side that of the anchor's bend (:func:`optimize.chain.statics.extended_bends`):
        at A, -1 keeps theta_0 from growing and +1 from shrinking; at B, -1 keeps
        theta_{N-1} from shrinking and +1 from growing.
    """
    n = problem.n
    phi = np.diff(problem.angles)
    on_limit = set(statics_matrix(problem)[1].tolist())
    forced_set = set(int(j) for j in forced) - on_limit
    cand = np.array(sorted((set(int(j) for j in candidates) | forced_set) - on_limit), dtype=int)
    lim = problem.limits.copy()
    lim[cand] = phi[cand, None]  # held both ways: the moment may take either sign
    end_lim = (np.full((2, 2), [-np.inf, np.inf]) if problem.end_limits is None
               else problem.end_limits.copy())
    theta = problem.angles
    end_cand = [k for k in sorted(set(int(k) for k in ends)) if (-1 if k == 0 else n - 1) not in on_limit]
    for k in end_cand:
        end_lim[k] = theta[0 if k == 0 else -1]
    cand = np.concatenate([cand, [-1 if k == 0 else n - 1 for k in end_cand]]).astype(int)
    trial = replace(problem, limits=lim, end_limits=end_lim if end_cand or problem.end_limits is not None else None)
    A, stops, signs = statics_matrix(trial)
    n = problem.n
    row, col = scaled_statics(trial, A)
    As = (A * row[:, None]) * col[None, :]
    new = np.isin(stops, cand)
    # the new stops' moments split into a positive and a negative part, each >= 0
    As = np.hstack([As, -As[:, n + 2:][:, new]])
    k = int(new.sum())
    lb = np.full(As.shape[1], -np.inf)
    ub = np.full(As.shape[1], np.inf)
    lb[:n], ub[:n] = problem.mass_bounds[:, 0] / col[:n], problem.mass_bounds[:, 1] / col[:n]
    old_lb, old_ub = lb[n + 2:n + 2 + stops.size], ub[n + 2:n + 2 + stops.size]
    moment_signs(signs, old_lb, old_ub)
    old_lb[new], old_ub[new] = 0.0, np.inf
    lb[n + 2:n + 2 + stops.size], ub[n + 2:n + 2 + stops.size] = old_lb, old_ub
    if k:
        lb[-k:] = 0.0
    bounds = list(zip(np.where(np.isfinite(lb), lb, None), np.where(np.isfinite(ub), ub, None)))
    which = stops[new]
    base = np.where(np.isin(which, list(forced_set)), FORCED_WEIGHT,
                    np.where((which < 0) | (which >= n - 1), end_weight, 1.0))
    weights = base.copy()
    best = None
    for _ in range(REWEIGHT_ROUNDS):
        # L1 of the moments, reweighted by their last size: favours few stops (reweighted L1)
        c = np.zeros(As.shape[1])
        c[n + 2:n + 2 + stops.size][new] = weights
        if k:
            c[-k:] = weights
        lp = linprog(c, A_eq=As, b_eq=np.zeros(n), bounds=bounds, method="highs")
        if lp.status != 0:
            break
        mu = lp.x[n + 2:n + 2 + stops.size][new] - (lp.x[-k:] if k else 0.0)
        if mu.size == 0 or np.abs(mu).max() <= 0:
            best = (0, mu)
            break
        optional = ~np.isin(which, list(forced_set))
        count = int(np.sum(np.abs(mu[optional]) > rel_tol * np.abs(mu).max()))
        if best is None or count < best[0]:
            best = (count, mu)
        weights = base / (np.abs(mu) + 1e-3 * np.abs(mu).max())
    if best is None:
        return None
    mu = best[1]
    big = np.abs(mu).max() if mu.size else 0.0
    keep = (np.abs(mu) > rel_tol * big) if big > 0 else np.zeros(mu.size, dtype=bool)
    keep |= np.isin(which, list(forced_set))
    joints = which[keep].astype(int)
    sides = np.where(mu[keep] > rel_tol * big, 1, -1).astype(int)
    order = np.argsort(joints)
    return joints[order], sides[order]


#: The cost of a forced stop's moment in :func:`needed_stop_sides` (a joint's is 1): small,
#: so its side follows the statics rather than the count.
FORCED_WEIGHT = 1e-3
