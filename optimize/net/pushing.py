"""Rods that may push, and the hubs they push against kept from turning.

A net's mass design keeps every rod in tension unless told which may push
(:func:`push_mask`: every rod, none, or a mask, e.g. the rigid rods a net's hubs hold either
way). A rod pushing against a hub's ball socket turns the hub, as a pulling one holds it:
:func:`hub_stiffness_rows` gives the linear rows in the tensions that ask each such hub to
resist turning, which the design's linear programs keep (:mod:`optimize.net.statics`).

Units: mm, forces in g x the unit of ``g`` (the rows are over a mid-bound rod's weight).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from optimize.net.deriv import evaluate
from optimize.net.lp import net_linprog
from optimize.net.model import Net, skew

__all__ = ["AXES", "HUB_STIFFNESS", "PUSH_ROOM", "hub_stiffness_rows", "least_push", "push_mask", "stiff_enough",
           "stiffness_ub"]

#: Where only some rods may push, each pushes at most the least largest push that balances the
#: target, and this share more (:func:`least_push`): a rod pushing against a hub's ball socket
#: turns the hub, so the designs push no harder than they must.
PUSH_ROOM = 0.1
#: Directions a hub's turning stiffness is asked about (:func:`hub_stiffness_rows`): its three
#: axes, their six face diagonals and four body diagonals.
AXES = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0], [1, -1, 0], [1, 0, 1], [1, 0, -1], [0, 1, 1],
                  [0, 1, -1], [1, 1, 1], [1, 1, -1], [1, -1, 1], [-1, 1, 1]], float)
AXES /= np.linalg.norm(AXES, axis=1, keepdims=True)

#: A hub whose rods may push must resist turning about each of :data:`AXES` at least as a hub
#: held by this many mid-bound rods' weights of tension at its pivots would (times its pivot radius).
HUB_STIFFNESS = 0.25


def hub_stiffness_rows(net: Net, state, push: np.ndarray):
    """Linear rows that keep the hubs of rods that may push from turning (or None: no such hub).

    A rod pushing against a hub's ball socket turns the hub, as a pulling one holds it (a
    pendulum upright and hanging): turning a hub by ``w`` with its node point held moves each
    pivot ``q`` (its offset, world frame) by ``w x q`` and the rod's length to second order by
    ``w' G w / 2``, ``G = [q]x' (I - u u') [q]x / L + (u . q) I - (u q' + q u') / 2`` (``u`` along
    the rod, away from the hub), so the rods' forces give the hub the turning stiffness
    ``sum T G``. Each free hub with a rod that may push is asked for at least
    :data:`HUB_STIFFNESS` x a mid-bound rod's weight x its pivot radius about each of
    :data:`AXES` (a necessary condition the exact check's curvatures then judge).

    Returns:
        (G (rows, m) sparse, over the tensions in units of a mid-bound rod's weight (the design's
        scaled unknowns); need (rows,) mm), or None.
    """
    ev = evaluate(net, state, full=False)
    free = ~net.anchored & net.body
    hubs = np.unique(net.edges[push][free[net.edges[push]]]) if push.any() else np.zeros(0, int)
    if not hubs.size:
        return None
    off = state.offsets(net)
    rows, cols, vals = [], [], []
    radius = np.zeros(hubs.size)
    for h, k in enumerate(hubs):
        for end in (0, 1):
            for e in np.flatnonzero(net.edges[:, end] == k):
                q = off[e, end]
                u = ev.u[e] if end == 0 else -ev.u[e]
                Q = skew(q)
                Gk = Q.T @ (np.eye(3) - np.outer(u, u)) @ Q / net.lengths[e] + (u @ q) * np.eye(3) \
                    - 0.5 * (np.outer(u, q) + np.outer(q, u))
                rows.append(h * len(AXES) + np.arange(len(AXES)))
                cols.append(np.full(len(AXES), e))
                vals.append(np.einsum("ai,ij,aj->a", AXES, Gk, AXES))
                radius[h] = max(radius[h], float(np.linalg.norm(q)))
    G = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(hubs.size * len(AXES), net.m))
    return G, np.repeat(HUB_STIFFNESS * radius, len(AXES))


def push_mask(allow_compression, m: int) -> np.ndarray:
    """(m,) bool: the rods that may push, from ``allow_compression`` (one bool for every rod, or
    an (m,) mask)."""
    mask = np.asarray(allow_compression, dtype=bool)
    if mask.ndim == 0:
        return np.full(m, bool(mask))
    if mask.shape != (m,):
        raise ValueError(f"allow_compression must be a bool or an ({m},) mask, not of shape {mask.shape}")
    return mask


def stiffness_ub(A_ub: sp.csr_matrix, b_ub: np.ndarray, stiff, m: int) -> tuple[sp.csr_matrix, np.ndarray]:
    """A linear program's inequalities over (T (m), masses (m), one more unknown) with the rows
    of :func:`hub_stiffness_rows` (``stiff``; None: none) below them: ``G T >= need``."""
    if stiff is None:
        return A_ub, b_ub
    G, need = stiff
    return (sp.vstack([A_ub, sp.hstack([-G, sp.csr_matrix((G.shape[0], m + 1))])]).tocsr(),
            np.concatenate([b_ub, -need]))


def stiff_enough(stiff, T: np.ndarray) -> bool:
    """The scaled tensions ``T`` keep the hubs of rods that push as stiff as ``stiff`` asks
    (:func:`optimize.net.pushing.hub_stiffness_rows`; None: nothing asked)."""
    return stiff is None or bool(np.all(stiff[0] @ T >= stiff[1] * (1 - 1e-9)))


def least_push(A, b, m, lo_m, hi_m, push, stiff=None) -> float:
    """The least largest push (scaled) of the rods that may push (``push``) for masses within
    their bounds to balance ``A (T, m) = b``, the others in tension (and the hubs as stiff as
    ``stiff`` asks, :func:`hub_stiffness_rows`), with a little room above it (:data:`PUSH_ROOM`);
    inf where none balances (the design's programs say so)."""
    k = np.flatnonzero(push)
    rows = sp.csr_matrix((-np.ones(k.size), (np.arange(k.size), k)), shape=(k.size, 2 * m))
    A_ub = sp.hstack([rows, sp.csr_matrix(-np.ones((k.size, 1)))]).tocsr()  # -T_k - s <= 0
    A_ub, b_ub = stiffness_ub(A_ub, np.zeros(k.size), stiff, m)
    c = np.zeros(2 * m + 1)
    c[-1] = 1.0
    bnds = [(None, None) if q else (0.0, None) for q in push] + list(zip(lo_m, hi_m)) + [(0.0, None)]
    A_eq = sp.hstack([A, sp.csr_matrix((A.shape[0], 1))]).tocsr()
    lp = net_linprog(c, m, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=b, bounds=bnds)
    if lp.status != 0:
        return np.inf
    return float(lp.x[-1]) * (1 + PUSH_ROOM) + 1e-9
