"""Choose a rod type for every position so the joints' limits supply what the target needs.

A free joint can only hold a convex (sagging, phi > 0) bend; a straight run or a
concave bend needs a moment that only a stop can supply, so there the pair of
adjacent types must stop exactly at the target bend. Limits belong to pairs of
types (the left rod's end meets the right rod's start), so the choice is a
shortest path over positions x types (Viterbi), O(N T^2).
"""

from __future__ import annotations

import numpy as np

__all__ = ["assign_types", "joint_mismatch"]

_BIG = 1e6


def assign_types(
    bends,
    allowed,
    pair_limits,
    *,
    stop_below: float = np.radians(0.5),
    margin: float = np.radians(3.0),
    type_cost=None,
    need_stop=None,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Rod types for a target with the given bends.

    Args:
        bends: (N-1,) target bends phi_j in radians.
        allowed: (N, T) boolean: type t may be used at position k (length, user constraints).
        pair_limits: (T, T, 2) bend limits [lo, hi] in radians for left type t, right type u
            (-inf / inf where the rods never collide).
        stop_below: a joint bending less than this needs a stop (straight or concave).
        margin: a free joint should stay this far inside its limits.
        type_cost: optional (T,) small preference cost per type (default: catalog order).
        need_stop: optional (N-1,) boolean: these joints must rest on a stop on their
            sagging side even though they bend convexly (the masses alone cannot hold the
            bend, see :func:`optimize.chain.stops.needed_stops`). Their cost is the distance
            |hi - bend| from the nearest stop; the caller then moves the joints so they
            bend exactly at the chosen stops (:func:`optimize.chain.discretize.refit`).

    Returns:
        (types (N,), limits (N-1, 2) of the chosen pairs, cost). The cost is 0 when every
        stop joint's limit equals its target bend and every free joint is clear of its
        limits; it counts radians of mismatch otherwise (>= 1e6 where impossible).

    Raises:
        ValueError: some position allows no type.
    """
    phi = np.asarray(bends, dtype=float)
    allowed = np.asarray(allowed, dtype=bool)
    lim = np.asarray(pair_limits, dtype=float)
    n, t = allowed.shape
    if phi.shape != (n - 1,):
        raise ValueError(f"bends must have shape ({n - 1},), got {phi.shape}")
    if lim.shape != (t, t, 2):
        raise ValueError(f"pair_limits must have shape ({t}, {t}, 2), got {lim.shape}")
    empty = np.flatnonzero(~allowed.any(axis=1))
    if empty.size:
        raise ValueError(f"no rod type is allowed at position {empty[0]}")
    pref = 1e-6 * np.arange(t) if type_cost is None else np.asarray(type_cost, float)
    lo, hi = lim[..., 0], lim[..., 1]
    node = np.where(allowed, pref[None, :], np.inf)
    cost = node[0].copy()
    back = np.zeros((n, t), dtype=int)
    need = np.zeros(n - 1, dtype=bool) if need_stop is None else np.asarray(need_stop, dtype=bool)
    if need.shape != (n - 1,):
        raise ValueError(f"need_stop must have shape ({n - 1},), got {need.shape}")
    for j in range(n - 1):
        if need[j]:
            edge = np.where(np.isfinite(hi) & (lo <= hi) & (phi[j] >= lo), np.abs(hi - phi[j]), _BIG)
        else:
            edge = _edge_cost(phi[j], lo, hi, stop_below, margin)
        total = cost[:, None] + edge  # (left type, right type)
        back[j + 1] = np.argmin(total, axis=0)
        cost = total[back[j + 1], np.arange(t)] + node[j + 1]
    types = np.zeros(n, dtype=int)
    types[-1] = int(np.argmin(cost))
    best = float(cost[types[-1]])
    for k in range(n - 1, 0, -1):
        types[k - 1] = back[k, types[k]]
    limits = lim[types[:-1], types[1:]] if n > 1 else np.zeros((0, 2))
    return types, limits, best - float(np.sum(pref[types]))


def _edge_cost(phi: float, lo, hi, stop_below: float, margin: float):
    """Cost of bending ``phi`` at joints with limits [lo, hi] (arrays broadcast).

    A joint bending less than ``stop_below`` needs a stop at exactly phi: a stop above the
    bend lets the joint sag past it (the masses may compensate), one below it forces a bend
    the target does not have (ten times worse); no stop at all on the sagging side, or a
    lower limit above the bend, is impossible. A free joint should stay ``margin`` inside
    its limits (ten times the intrusion) and is impossible outside them.
    """
    if phi < stop_below:
        gap = hi - phi
        edge = np.where(np.isfinite(hi), np.where(gap >= 0, gap, -10.0 * gap), _BIG)
        return edge + np.where(phi < lo, _BIG * (lo - phi + 1), 0.0)
    over = np.maximum(phi - (hi - margin), 0.0)
    under = np.maximum((lo + margin) - phi, 0.0)
    return 10.0 * (over + under) + np.where((phi > hi) | (phi < lo), _BIG, 0.0)


def joint_mismatch(
    bends,
    limits,
    *,
    stop_below: float = np.radians(0.5),
    margin: float = np.radians(3.0),
) -> np.ndarray:
    """Per joint, how far the chosen limits are from what the target needs (radians).

    Args:
        bends: (N-1,) target bends in radians.
        limits: (N-1, 2) limits [lo, hi] of the chosen pairs (radians; -inf / inf where
            nothing collides; (inf, -inf) marks a pair that cannot be joined).
        stop_below, margin: as in :func:`assign_types`.

    Returns:
        (N-1,) array: for a joint needing a stop, |hi - bend| (0 when the stop sits exactly
        at the bend); for a free joint, how far the bend intrudes into the margin at its
        limits (0 when clear). ``inf`` where the target bend is impossible with that pair:
        a stop needed and none on the sagging side, the bend outside the limits, or a pair
        that cannot be joined.
    """
    phi = np.asarray(bends, dtype=float)
    lim = np.asarray(limits, dtype=float).reshape(-1, 2)
    out = np.zeros(phi.size)
    for j, (p, (lo, hi)) in enumerate(zip(phi, lim)):
        if not lo <= hi:
            out[j] = np.inf
        elif p < stop_below:
            out[j] = abs(hi - p) if np.isfinite(hi) and p >= lo else np.inf
        elif p > hi or p < lo:
            out[j] = np.inf
        else:
            out[j] = max(p - (hi - margin), 0.0) + max((lo + margin) - p, 0.0)
    return out
