"""Place rod joints on a target curve: chord walk with the catalog's rod lengths.

The target is a dense polyline from anchor A to anchor B. Rods are rigid, so the
joints can lie on the curve only where the lengths allow; corners of the target
(a triangle's apex) become joints when the lengths between them can be mixed to
fit, and a final least-squares step moves the joints as little as possible off
the curve so that the chain closes exactly on B. The discretisation error (how
far the chain polyline is from the curve) is reported apart from the physics error. The
curves themselves (resampling, distances, the rods' centrelines and curvatures) are
:mod:`optimize.chain.curves`.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq, least_squares
from scipy.spatial import cKDTree

from optimize.chain.curves import point_polyline_distance, polyline_distance, resample

__all__ = ["Discretization", "discretize", "find_corners", "refit"]


@dataclass
class Discretization:
    """Joints placed on a target curve.

    Attributes:
        points: (N+1, 2) joint positions, points[0] = A, points[-1] = B exactly.
        lengths: (N,) rod lengths used (from the allowed set).
        joint_error: max distance of a joint from the curve.
        curve_error: max distance between the curve and the chain polyline (both ways).
        corners: indices of joints placed on detected corners of the target.
    """

    points: np.ndarray
    lengths: np.ndarray
    joint_error: float
    curve_error: float
    corners: list[int]


def find_corners(curve: np.ndarray, angle_deg: float = 25.0) -> list[int]:
    """Vertices of a polyline where it turns by more than `angle_deg` at one vertex."""
    d = np.diff(curve, axis=0)
    a = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
    turn = np.abs(np.diff(a))
    return [int(i) + 1 for i in np.flatnonzero(turn > np.radians(angle_deg))]


#: Relative tolerance (of the rod length) within which a chord of the walk ends on a
#: polyline vertex: the joint is put on the vertex exactly.
VERTEX_TOL = 1e-9


#: Points of the polyline the chord walk looks at first for a joint (:func:`_walk`): a joint
#: is usually found within them, and the next windows are searched only where it is not.
WALK_WINDOW = 64


def _walk(curve: np.ndarray, s: np.ndarray, start_s: float, lengths) -> tuple[np.ndarray, float]:
    """Chord walk along the polyline from arc length start_s; returns joints and end arc length."""
    cx, cy = curve[:, 0], curve[:, 1]
    px, py = float(np.interp(start_s, s, cx)), float(np.interp(start_s, s, cy))
    i = int(np.searchsorted(s, start_s, side="right")) - 1
    out = [(px, py)]
    cur_s = start_s
    n = len(curve)
    on_curve = True  # (px, py) lies on the polyline at arc length cur_s
    for l in lengths:
        # first polyline point beyond cur_s at distance >= l from p; a vertex at distance l
        # up to round-off is the joint itself (a polyline whose segments are multiples of the
        # rod length keeps its vertices as joints on every CPU, whatever the last digits)
        tol = VERTEX_TOL * l
        # while p is on the curve, no point less than l - tol further along it is that far
        # from p (a chord is no longer than its arc): the search starts there, in windows
        # that grow (the first point found is the first one, as in one search of them all)
        lo = i + 1
        if on_curve:
            lo = max(lo, int(np.searchsorted(s, cur_s + l - 2 * tol, side="left")))
        j = -1
        for k in range(3):
            hi = (lo + WALK_WINDOW if k == 0 else
                  int(np.searchsorted(s, cur_s + 4 * l + tol, side="right")) + 1 if k == 1 else n)
            if hi <= lo:
                continue
            dist = np.hypot(cx[lo:hi] - px, cy[lo:hi] - py)
            far = np.flatnonzero(dist >= l - tol)
            if far.size:
                j = int(far[0]) + lo
                d = float(dist[far[0]])
                break
            lo = max(lo, hi)
        if j >= 0 and abs(d - l) <= tol:
            px, py = float(cx[j]), float(cy[j])
            cur_s = s[j]
            i = min(j, n - 2)
            out.append((px, py))
            continue
        if j < 0:  # past the end of the curve: carry on straight toward its end
            dx, dy = float(cx[-1]) - px, float(cy[-1]) - py
            norm = math.hypot(dx, dy)
            dx, dy = (dx / norm, dy / norm) if norm > 0 else (1.0, 0.0)
            px, py = px + l * dx, py + l * dy
            out.append((px, py))
            cur_s = s[-1] + 1.0
            i = n - 2
            on_curve = False
            continue
        ax, ay, bx, by = float(cx[j - 1]), float(cy[j - 1]), float(cx[j]), float(cy[j])
        # solve |a + t (b - a) - p| = l on the segment
        ux, uy = bx - ax, by - ay
        wx, wy = ax - px, ay - py
        qa, qb, qc = ux * ux + uy * uy, 2 * (ux * wx + uy * wy), wx * wx + wy * wy - l * l
        disc = max(qb * qb - 4 * qa * qc, 0.0)
        t = (-qb + math.sqrt(disc)) / (2 * qa)
        t = min(max(t, 0.0), 1.0)
        px, py = ax + t * ux, ay + t * uy
        cur_s = s[j - 1] + t * (s[j] - s[j - 1])
        i = j - 1
        out.append((px, py))
    return np.array(out), cur_s


def _piece_sequence(curve, s, s0, s1, allowed, preferred, max_candidates=400):
    """Rod lengths whose chord walk from arc length s0 ends closest to arc length s1."""
    arc = s1 - s0
    end = np.array([np.interp(s1, s, curve[:, 0]), np.interp(s1, s, curve[:, 1])])
    start = np.array([np.interp(s0, s, curve[:, 0]), np.interp(s0, s, curve[:, 1])])
    chord = float(np.hypot(*(end - start)))
    allowed = sorted(set(float(x) for x in allowed))
    lmin = min(allowed)
    nmax = int(np.ceil(arc / lmin)) + 1
    cands = []
    for counts in itertools.product(range(nmax + 1), repeat=len(allowed)):
        total = sum(c * l for c, l in zip(counts, allowed))
        if total <= 0 or total < chord - 0.5 * lmin or total > arc + 0.5 * lmin:
            continue
        cands.append((arc - total, counts))
        if len(cands) > 20000:
            break
    if not cands:
        return None
    cands.sort(key=lambda c: (abs(c[0]), -c[1][allowed.index(preferred)] if preferred in allowed else 0))
    best = None
    for _, counts in cands[:max_candidates]:
        seq = _spread(counts, allowed, preferred)
        joints, _ = _walk(curve, s, s0, seq)
        gap = float(np.hypot(*(joints[-1] - end)))
        n_kinds = sum(1 for c in counts if c)
        key = (round(gap, 9), n_kinds, -counts[allowed.index(preferred)] if preferred in allowed else 0)
        if best is None or key < best[0]:
            best = (key, seq)
    return None if best is None else best[1]


def _equal_chords(curve, s, s0, s1, lo, hi, preferred) -> list[float] | None:
    """n equal chords of one length c in [lo, hi] whose walk from arc length s0 lands exactly
    on arc length s1 (the next corner or B): every joint on the curve; the n whose c is
    nearest the preferred length (ties to fewer rods)."""
    def landing(c: float, n: int) -> float:
        return _walk(curve, s, s0, [c] * n)[1] - s1

    arc = s1 - s0
    best = None
    counts = range(max(1, math.floor(arc / hi)), min(math.ceil(arc / lo) + 2, MAX_RODS + 1))
    # n chords of length c span a little less than n c of arc: try the counts whose arc / n is
    # nearest the preferred length first, and stop once a few have landed
    landed = 0
    for n in sorted(counts, key=lambda n: (abs(arc / n - preferred), n)):
        a, b = landing(lo, n), landing(hi, n)
        if a > 0 or b < 0:
            continue
        c = lo if a == 0 else hi if b == 0 else brentq(lambda x: landing(x, n), lo, hi, xtol=1e-13, rtol=1e-15)
        key = (abs(c - preferred), n)
        if best is None or key < best[0]:
            best = (key, [c] * n)
        landed += 1
        if landed >= EQUAL_CHORD_TRIES:
            break
    return None if best is None else best[1]


#: Rod counts of one piece whose equal chords are solved for (nearest the preferred length).
EQUAL_CHORD_TRIES = 3


def _spread(counts, allowed, preferred) -> list[float]:
    """A sequence with the given counts, each length spread evenly along the piece."""
    items = []
    for c, l in zip(counts, allowed):
        for k in range(c):
            items.append(((k + 0.5) / c, 0 if l == preferred else 1, l))
    items.sort()
    return [l for _, _, l in items]


#: Longest chain laid on a target (rods): planning, the inverse design and the multi-start
#: grow with the rod count, and no printed chain gets near this.
MAX_RODS = 300

#: A segment of a given polyline is tiled by rods when their lengths add up to its length
#: within this relative tolerance.
TILE_TOL = 1e-9

#: Largest number of length combinations tried per segment when tiling a polyline.
MAX_TILINGS = 200_000


def _tile_counts(length: float, allowed: list[float], preferred: float) -> tuple[int, ...] | None:
    """How many rods of each allowed length add up to ``length`` (fewest kinds, then the
    most of the preferred length, then the fewest rods), or None."""
    nmax = int(length / min(allowed) + 1)
    if (nmax + 1) ** len(allowed) > MAX_TILINGS:
        return None
    best, best_key = None, None
    for counts in itertools.product(range(nmax + 1), repeat=len(allowed)):
        total = sum(c * l for c, l in zip(counts, allowed))
        if total == 0 or abs(total - length) > TILE_TOL * length:
            continue
        pref = counts[allowed.index(preferred)] if preferred in allowed else 0
        key = (sum(1 for c in counts if c), -pref, sum(counts), counts)
        if best_key is None or key < best_key:
            best, best_key = counts, key
    return best


def _tile_polyline(curve: np.ndarray, allowed: list[float], preferred: float | None) -> Discretization | None:
    """The exact discretisation of a polyline whose every segment is a sum of allowed
    lengths: vertices become joints, segments are split into rods along their line."""
    seg = np.hypot(*np.diff(curve, axis=0).T)
    keep = np.concatenate([[True], seg > 0])
    pts = curve[keep]
    seg = seg[seg > 0]
    if seg.size == 0 or seg.min() < min(allowed) * (1 - TILE_TOL):
        return None
    if preferred is None:
        fits = [l for l in allowed if seg.sum() / l >= 8]
        preferred = max(fits) if fits else min(allowed)
    points, lengths, corners = [pts[0]], [], []
    for a, b, length in zip(pts[:-1], pts[1:], seg):
        counts = _tile_counts(float(length), allowed, preferred)
        if counts is None:
            return None
        run = _spread(counts, allowed, preferred)
        scale = length / sum(run)  # exact to TILE_TOL: put the last joint on the vertex
        at = np.cumsum(run) * scale
        points += [a + (b - a) * (t / length) for t in at[:-1]] + [b]
        lengths += run
        corners.append(len(lengths))
    return Discretization(np.array(points), np.array(lengths, dtype=float), 0.0, 0.0, corners[:-1])


def _tile_range(curve: np.ndarray, lo: float, hi: float, preferred: float | None) -> Discretization | None:
    """Rods printed to order on a polyline whose every segment splits into equal rods of a
    length in [lo, hi]: vertices become joints (the polyline comes back exactly), each
    segment split into the count of rods whose length is nearest the preferred one."""
    seg = np.hypot(*np.diff(curve, axis=0).T)
    keep = np.concatenate([[True], seg > 0])
    pts = curve[keep]
    seg = seg[seg > 0]
    if seg.size == 0 or seg.size > MAX_RODS or seg.min() < lo * (1 - TILE_TOL):
        return None
    if preferred is None:
        preferred = float(np.clip(seg.sum() / 8, lo, hi))
    points, lengths, corners = [pts[0]], [], []
    for a, b, length in zip(pts[:-1], pts[1:], seg):
        counts = [k for k in range(max(1, math.ceil(length / hi * (1 - TILE_TOL))),
                                   math.floor(length / lo * (1 + TILE_TOL)) + 1)]
        if not counts:
            return None
        k = min(counts, key=lambda k: (abs(length / k - preferred), k))
        points += [a + (b - a) * (i / k) for i in range(1, k)] + [b]
        lengths += [float(length) / k] * k
        corners.append(len(lengths))
    if len(lengths) > MAX_RODS:
        return None
    return Discretization(np.array(points), np.array(lengths, dtype=float), 0.0, 0.0, corners[:-1])


def discretize(
    curve,
    allowed_lengths,
    *,
    preferred: float | None = None,
    corner_angle_deg: float = 25.0,
    length_range: tuple[float, float] | None = None,
) -> Discretization:
    """Joints on the curve for a chain of rods with lengths from `allowed_lengths`.

    Args:
        curve: (M, 2) polyline from A (first point) to B (last point), dense or not.
        allowed_lengths: rod lengths that may be used (e.g. the catalog's 20, 30, 40 mm).
        preferred: the length to use most (default: the longest that gives at least
            eight rods, else the shortest; for a length range, the length that makes eight
            rods of the curve's length, clipped to the range).
        corner_angle_deg: a vertex of the given polyline turning more than this is a corner
            that should carry a joint.
        length_range: rods printed to order: any length in (lo, hi) instead of the allowed
            list; each piece between corners gets equal chords that land exactly on its end,
            so every joint lies on the curve and every corner is a joint.

    Returns:
        Discretization with points[0] = A and points[-1] = B exactly. A polyline whose
        every segment is a sum of allowed lengths (to :data:`TILE_TOL`) is tiled exactly:
        its vertices are joints and its segments are rods (a chain of the catalog's rods
        given as its own polyline comes back exactly).

    Raises:
        ValueError: the curve is degenerate or the anchors are farther apart than
            any chain of these rods along the curve.
    """
    curve = np.asarray(curve, dtype=float)
    if curve.ndim != 2 or curve.shape[1] != 2 or curve.shape[0] < 2 or not np.all(np.isfinite(curve)):
        raise ValueError("curve must be a finite (M, 2) polyline with at least two points")
    allowed = sorted(set(float(x) for x in np.atleast_1d(allowed_lengths)))
    if length_range is not None:
        lo, hi = (float(x) for x in length_range)
        if not 0 < lo < hi:
            raise ValueError(f"length_range must be 0 < lo < hi, got {length_range}")
        allowed = [lo, hi]
    if not allowed or min(allowed) <= 0:
        raise ValueError("allowed_lengths must be positive")
    total_length = float(np.sum(np.hypot(*np.diff(curve, axis=0).T)))
    if total_length / max(allowed) > MAX_RODS:
        raise ValueError(
            f"the target is {total_length:.4g} long: it takes at least {math.ceil(total_length / max(allowed))} "
            f"rods of the allowed lengths (up to {max(allowed):g}); rodcad lays chains of up to {MAX_RODS} rods "
            "(allow longer rods, or make the target smaller)")
    if length_range is None:
        exact = _tile_polyline(curve, allowed, preferred)
    else:
        exact = _tile_range(curve, allowed[0], allowed[1], preferred)
    if exact is not None:
        return _slack(exact)
    corners_in = find_corners(curve, corner_angle_deg)
    # a corner too close to the ends or to the previous corner cannot carry a joint of its own:
    # keep the first of such a cluster, the rods cross the others. Too close: nearer than half
    # the shortest rod (a piece's rods end within half a rod of its end), or for rods printed to
    # order, whose equal chords land on the piece's end exactly, nearer than the shortest rod
    # (no rod fits the piece between)
    s_vert = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(curve, axis=0).T))])
    near = min(allowed) if length_range is not None else 0.5 * min(allowed)
    kept, last = [], 0.0
    for c in corners_in:
        if s_vert[c] - last >= near and s_vert[-1] - s_vert[c] >= near:
            kept.append(c)
            last = s_vert[c]
    corners_in = kept
    # arc length of the given vertices, then a dense copy for walking
    s_given = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(curve, axis=0).T))])
    total = s_given[-1]
    if total <= 0:
        raise ValueError("the target curve has zero length")
    # a dense copy for walking that keeps every given vertex exactly (corners, and the
    # gentler bends of a sparse polyline, such as a concave stop's vertex)
    keep = np.concatenate([[True], np.diff(s_given) > 0])
    s = np.union1d(np.linspace(0, total, max(4000, 20 * len(curve))), s_given[keep])
    dense = np.column_stack([np.interp(s, s_given[keep], curve[keep, 0]),
                             np.interp(s, s_given[keep], curve[keep, 1])])
    dense[np.searchsorted(s, s_given[keep])] = curve[keep]
    if preferred is None and length_range is not None:
        preferred = float(np.clip(total / 8, allowed[0], allowed[1]))
    elif preferred is None:
        fits = [l for l in allowed if total / l >= 8]
        preferred = max(fits) if fits else min(allowed)
    breaks = [0.0] + [s_given[c] for c in corners_in] + [total]
    seq: list[float] = []
    corner_joints: list[int] = []
    for s0, s1 in zip(breaks, breaks[1:]):
        if length_range is not None:
            piece = _equal_chords(dense, s, s0, s1, float(length_range[0]), float(length_range[1]), preferred)
        else:
            piece = _piece_sequence(dense, s, s0, s1, allowed, preferred)
        if piece is None:
            raise ValueError(
                f"no combination of rod lengths {allowed} fits the piece of the target between "
                f"arc lengths {s0:.4g} and {s1:.4g} (length {s1 - s0:.4g}); allow shorter rods"
            )
        seq.extend(piece)
        corner_joints.append(len(seq))
    corner_joints = corner_joints[:-1]
    lengths = np.array(seq)
    joints, _ = _walk(dense, s, 0.0, lengths)
    a, b = curve[0], curve[-1]
    if lengths.sum() < np.hypot(*(b - a)):
        raise ValueError(
            f"anchors are {np.hypot(*(b - a)) - lengths.sum():.4g} farther apart than the chain is long"
        )
    if np.hypot(*(joints[-1] - b)) <= 1e-9 * lengths.sum():
        points = joints.copy()  # the walk already lands on B: keep the joints on the curve
        points[-1] = b
    else:
        points = _close(joints, lengths, a, b, dense)
    joint_err = float(point_polyline_distance(points, curve).max())
    curve_err = polyline_distance(dense, points)
    return _slack(Discretization(points, lengths, joint_err, curve_err, corner_joints))


#: A chain at most this much (relative) longer than the span between its anchors hangs
#: (nearly) straight: it would pull (nearly) infinitely hard on them.
TAUT_SLACK = 1e-6


def _slack(disc: Discretization) -> Discretization:
    span = float(np.hypot(*(disc.points[-1] - disc.points[0])))
    if disc.lengths.sum() <= span * (1 + TAUT_SLACK):
        raise ValueError(
            f"the target is (nearly) the straight line between the anchors: a chain of {disc.lengths.sum():.6g} "
            f"over a span of {span:.6g} would hang taut and pull infinitely hard on its anchors; give it some "
            "sag (a longer target)")
    return disc


def _close(joints, lengths, a, b, dense) -> np.ndarray:
    """Least-squares move of the joints toward the curve with exact closure on B."""
    d = np.diff(joints, axis=0)
    theta0 = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
    n = len(lengths)
    out = _fit_groups(a, b, lengths, np.arange(n), np.zeros(n), theta0, cKDTree(dense))
    miss = float(np.hypot(*(out[-1] - b)))
    if miss > 1e-9 * float(lengths.sum()):
        raise ValueError(
            f"the rods ({len(lengths)} of lengths {sorted(set(lengths.tolist()))}) cannot close "
            f"on anchor B along this curve (they miss it by {miss:.4g}); allow other lengths"
        )
    out[-1] = b
    return out


def _fit_groups(a, b, lengths, group, offset, psi0, tree) -> np.ndarray:
    """Joints of a chain from A whose rods turn in rigid groups, moved toward the curve.

    Rod k points at angle ``psi[group[k]] + offset[k]``: least squares on the joints'
    distances to the curve (``tree``, a KD-tree of its dense points) with a heavy
    closure term, then minimum-norm Newton steps on the two closure equations. Returns
    the (N+1, 2) joints; the caller checks how far the last one is from B.
    """
    n_groups = int(group.max()) + 1
    scale = float(lengths.sum())

    def pts(psi):
        th = psi[group] + offset
        steps = lengths[:, None] * np.column_stack([np.cos(th), np.sin(th)])
        return a + np.vstack([np.zeros(2), np.cumsum(steps, axis=0)])

    def resid(psi):
        p = pts(psi)
        return np.concatenate([tree.query(p[1:-1])[0], 1e3 * (p[-1] - b)]) / scale

    psi = least_squares(resid, psi0, method="trf", xtol=1e-14, ftol=1e-14, gtol=1e-14,
                        max_nfev=200 * n_groups).x
    G = np.zeros((len(lengths), n_groups))
    G[np.arange(len(lengths)), group] = 1.0
    for _ in range(50):
        th = psi[group] + offset
        r = a + np.array([lengths @ np.cos(th), lengths @ np.sin(th)]) - b
        if np.hypot(*r) <= 1e-13 * scale:
            break
        J = np.vstack([-lengths * np.sin(th), lengths * np.cos(th)]) @ G
        psi = psi - np.linalg.lstsq(J, r, rcond=None)[0]
    return pts(psi)


def refit(curve, points, lengths, fixed_bends) -> Discretization | None:
    """Move the joints so that some joints bend by given angles exactly, staying close to the curve.

    Rods joined at a fixed bend move as one rigid group (a run resting on stops), so the
    unknowns are one angle per group: least squares on the joints' distances to the
    curve, then exact closure on B by minimum-norm Newton steps.

    Args:
        curve: (M, 2) target polyline from A to B.
        points: (N+1, 2) current joints (the start), points[0] = A, points[-1] = B.
        lengths: (N,) rod lengths.
        fixed_bends: {joint j: bend phi_j in radians} for interior joints j = 0..N-2.

    Returns:
        The new Discretization (corners: none recorded), or None when the groups cannot
        close on B (fewer than two groups, or Newton fails).
    """
    curve = np.asarray(curve, dtype=float)
    points = np.asarray(points, dtype=float)
    lengths = np.asarray(lengths, dtype=float)
    n = lengths.size
    d = np.diff(points, axis=0)
    theta = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
    group = np.zeros(n, dtype=int)
    offset = np.zeros(n)
    for k in range(1, n):
        j = k - 1
        if j in fixed_bends:
            group[k], offset[k] = group[k - 1], offset[k - 1] + float(fixed_bends[j])
        else:
            group[k], offset[k] = group[k - 1] + 1, 0.0
    n_groups = int(group[-1]) + 1
    if n_groups < 2:
        return None
    psi0 = np.array([np.mean(theta[group == g] - offset[group == g]) for g in range(n_groups)])
    a, b = points[0], points[-1]
    dense = resample(curve, max(4000, 20 * len(curve)))
    out = _fit_groups(a, b, lengths, group, offset, psi0, cKDTree(dense))
    if float(np.hypot(*(out[-1] - b))) > 1e-9 * float(lengths.sum()):
        return None
    out[-1] = b
    return Discretization(out, lengths.copy(), float(point_polyline_distance(out, curve).max()),
                          polyline_distance(dense, out), [])
