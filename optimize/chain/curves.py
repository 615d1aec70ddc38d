"""Polylines and the rods' arcs on them: a curve resampled evenly, distances between polylines,
the rods' centrelines (straight chords or arcs) and the curvature per rod that follows a target.

Numbers only (numpy/scipy), the caller's length unit; used by the discretisation
(:mod:`optimize.chain.discretize`) and by the planner and outputs that measure how far the
hanging rods are from the target.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["centerline", "curve_distance", "fit_curvatures", "point_polyline_distance", "polyline_distance",
           "resample"]


def resample(curve: np.ndarray, count: int = 4000) -> np.ndarray:
    """The polyline resampled at `count` points evenly spaced in arc length."""
    curve = np.asarray(curve, dtype=float)
    seg = np.hypot(*np.diff(curve, axis=0).T)
    keep = np.concatenate([[True], seg > 0])
    curve = curve[keep]
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(curve, axis=0).T))])
    t = np.linspace(0, s[-1], count)
    return np.column_stack([np.interp(t, s, curve[:, 0]), np.interp(t, s, curve[:, 1])])


def point_polyline_distance(points: np.ndarray, curve: np.ndarray) -> np.ndarray:
    """Exact distance from each point to the polyline (segments, not samples)."""
    a, b = curve[:-1], curve[1:]
    ab = b - a
    denom = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    out = np.empty(len(points))
    for i, p in enumerate(points):
        t = np.clip(np.einsum("ij,ij->i", p - a, ab) / denom, 0.0, 1.0)
        out[i] = np.min(np.hypot(*(a + t[:, None] * ab - p).T))
    return out


def centerline(points, curvature=None, per_rod: int = 24) -> np.ndarray:
    """The rods' centrelines as one polyline: straight chords, or for a rod of signed
    curvature k (1/mm; > 0 bulges to the right of p_i -> p_{i+1}, the rod frame's -y) the
    arc of radius 1/|k| through both joints (a half circle where pin play puts them > 2/|k| apart).

    Args:
        points: (N+1, 2) joints.
        curvature: (N,) per rod, or None for straight rods.
        per_rod: points per curved rod.
    """
    pts = np.asarray(points, dtype=float)
    if curvature is None or not np.any(np.asarray(curvature, float)):
        return pts
    out = [pts[:1]]
    for p, q, k in zip(pts[:-1], pts[1:], np.asarray(curvature, float)):
        if k == 0:
            out.append(q[None])
            continue
        d = q - p
        c = float(np.hypot(*d))
        rho = max(1 / abs(k), c / 2)  # a chord longer than the diameter: the half circle
        x = np.linspace(0.0, c, per_rod + 1)[1:]
        t2 = (x - c / 2) ** 2
        # rho cos(psi) - sqrt(rho^2 - t^2), written without cancellation for large radii
        with np.errstate(invalid="ignore", divide="ignore"):  # a half circle's far end: 0/0, set below
            y = np.sign(k) * (t2 - (c / 2) ** 2) / (np.sqrt(max(rho**2 - (c / 2) ** 2, 0.0))
                                                   + np.sqrt(np.maximum(rho**2 - t2, 0.0)))
        u = d / c
        v = np.array([-u[1], u[0]])
        arc = p + np.outer(x, u) + np.outer(y, v)
        arc[-1] = q
        out.append(arc)
    return np.concatenate(out)


def fit_curvatures(curve, points, *, max_curvature: float = np.inf) -> np.ndarray:
    """Per rod, the signed curvature (1/mm; > 0 bulges to the right of p_i -> p_{i+1}) of
    the arc through both of its joints and through the target curve above the chord's
    middle (the curve's sagitta there): the body of a rod printed to order follows the curve
    instead of cutting across it. Clipped to +-``max_curvature``; 0 where the curve runs
    along the chord.

    Args:
        curve: (M, 2) target polyline.
        points: (N+1, 2) joints on (or near) the curve.
        max_curvature: largest |curvature| a rod can be printed with.
    """
    dense = resample(np.asarray(curve, dtype=float), max(4000, 20 * len(curve)))
    pts = np.asarray(points, dtype=float)
    # each joint's place along the curve, in order (a joint on a corner belongs to both legs)
    idx = [0]
    for p in pts[1:]:
        rest = dense[idx[-1]:]
        idx.append(idx[-1] + int(np.argmin(np.hypot(*(rest - p).T))))
    out = np.zeros(len(pts) - 1)
    for i, (p, q) in enumerate(zip(pts[:-1], pts[1:])):
        c = float(np.hypot(*(q - p)))
        u = (q - p) / c
        seg = dense[idx[i]:idx[i + 1] + 1]
        if len(seg) < 3:
            continue
        rel = seg - p
        along, off = rel @ u, rel @ np.array([-u[1], u[0]])
        order = np.argsort(along)
        if along[order[0]] > c / 2 or along[order[-1]] < c / 2:
            continue
        h = -float(np.interp(c / 2, along[order], off[order]))  # the curve's offset mid-chord; > 0: right
        if abs(h) < 1e-6 * c:  # the curve runs along the chord: a straight rod
            continue
        # the circle through (0, 0), (c, 0) and (c / 2, -h) in the rod frame
        k = 8 * h / (c * c + 4 * h * h)
        out[i] = float(np.clip(k, -max_curvature, max_curvature))
    return out


#: What :func:`_kept` keeps: (what, the array's shape and bytes' digest) -> result, the oldest
#: dropped first past :data:`KEPT_CURVES`.
_KEPT: dict[tuple[str, tuple[int, ...], bytes], Any] = {}
#: How many results :func:`_kept` keeps (a plan measures a few target curves many times).
KEPT_CURVES = 16


def _kept(what: str, points: np.ndarray, make: Callable[[np.ndarray], Any]) -> Any:
    """``make(points)``, kept by the points' values: a planner measures hundreds of chains
    against one target curve, whose dense copy and KD-tree are then made once."""
    points = np.ascontiguousarray(points, dtype=float)
    key = (what, points.shape, hashlib.blake2b(points.tobytes(), digest_size=16).digest())
    found = _KEPT.get(key)
    if found is None:
        found = _KEPT[key] = make(points)
        while len(_KEPT) > KEPT_CURVES:
            _KEPT.pop(next(iter(_KEPT)))
    return found


def curve_distance(curve, chain) -> float:
    """Hausdorff distance between a target curve (any polyline) and a chain polyline (mm):
    how far the hanging chain is from the curve, everywhere along both."""
    dense = _kept("dense", np.asarray(curve, dtype=float), lambda c: resample(c, max(4000, 20 * len(c))))
    return polyline_distance(dense, np.asarray(chain, dtype=float))


def polyline_distance(curve: np.ndarray, chain: np.ndarray) -> float:
    """Symmetric (Hausdorff) distance between the dense curve and the chain polyline."""
    dense_chain = resample(chain, max(2000, 40 * len(chain)))
    d1 = _farthest(cKDTree(dense_chain), curve)
    d2 = _farthest(_kept("tree", curve, cKDTree), dense_chain)
    return float(max(d1, d2))


#: :func:`_farthest` asks the tree for every this-many-th point first.
FARTHEST_STRIDE = 16


def _farthest(tree: cKDTree, points: np.ndarray) -> float:
    """``tree.query(points)[0].max()``, the same number, asking the tree for far fewer points.

    The distance to the nearest of the tree's points changes along the polyline ``points`` by
    at most the length travelled (it is 1-Lipschitz): a point between two asked ones (every
    :data:`FARTHEST_STRIDE`-th) lies at most its arc length beyond either one's distance. Only
    the points whose bound reaches the largest distance found are asked then; the farthest
    point is one of them, and each point's distance is the tree's answer for it alone."""
    n = len(points)
    if n <= 4 * FARTHEST_STRIDE:
        return float(tree.query(points)[0].max())
    asked = np.unique(np.r_[np.arange(0, n, FARTHEST_STRIDE), n - 1])
    d = tree.query(points[asked])[0]
    best = float(d.max())
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(points, axis=0).T))])
    k = np.searchsorted(asked, np.arange(n), side="right") - 1  # the asked point at or before each
    k1 = np.minimum(k + 1, asked.size - 1)  # and the one after
    bound = np.minimum(d[k] + (s - s[asked[k]]), d[k1] + np.abs(s[asked[k1]] - s))
    slack = 1e-9 * (s[-1] + best) + 1e-300  # (the arc lengths' round-off: a bound errs high, never low)
    ask = np.flatnonzero(bound + slack >= best)
    ask = ask[~np.isin(ask, asked)]
    if ask.size:
        best = max(best, float(tree.query(points[ask])[0].max()))
    return best
