"""One outer shell for every rod of a chain printed to order (``constraints: {same_shell:
true}``, the paper's Fig. 7): equal chords along the whole curve, every corner a joint, and
one curvature, the mean of the fitted ones.

    curve -> n equal chords of one length c from A that land exactly on B (a walk along the
             whole curve, corners ignored), for the n whose c is nearest the length aimed at
          -> every corner of the curve must be one of the joints (else another n; else the
             corners forbid one length: :class:`ShellError`)
          -> one curvature: the mean of the curvatures fitted rod by rod, clipped to the
             family's range and to the arc a rod of that length can take
"""

from __future__ import annotations

import math

import numpy as np

from optimize.chain.discretize import discretize, find_corners
from optimize.chain.curves import centerline, curve_distance, fit_curvatures
from rodcad.catalog.model import max_curvature

__all__ = ["CORNER_TOL", "FOLLOW_REL", "TRIES", "ShellError", "curve_size", "most_faithful", "one_shell"]

#: A corner of the curve is a joint when one lies within this fraction of the span of it.
CORNER_TOL = 1e-6

#: A corner turns more than this (deg), as in the planner's discretisation.
CORNER_DEG = 25.0

#: Lengths aimed at when none is given, from the range's longest to its shortest
#: (geometric steps): the longest that follows the curve wins.
TRIES = 10

#: Without a preferred length, the longest rods whose centrelines follow the curve within
#: this fraction of its size (else the closest fit of the lengths tried).
FOLLOW_REL = 1e-3


def curve_size(curve: np.ndarray) -> float:
    """The size a curve's fit is measured against (mm): the anchors' distance, or the curve's
    width or height where larger (a heart hung from its cusp, its anchors a short fixture
    apart, is as large as its outline)."""
    curve = np.asarray(curve, float)
    extent = np.ptp(curve, axis=0)
    return max(float(np.hypot(*(curve[-1] - curve[0]))), float(extent.max()), 1e-9)


def most_faithful(curve: np.ndarray, layouts):
    """Of (discretisation, curvatures) layouts in the order tried (None: none at that aim),
    the first whose rods' centrelines follow the curve within :data:`FOLLOW_REL` of its
    size (:func:`curve_size`), else the closest; None when there is none."""
    span = curve_size(curve)
    best = None
    for laid in layouts:
        if laid is None:
            continue
        disc, kappa = laid
        err = curve_distance(curve, centerline(disc.points, kappa)) / span
        if err <= FOLLOW_REL:
            return disc, kappa
        if best is None or err < best[0] - 1e-12:
            best = (err, disc, kappa)
    return None if best is None else (best[1], best[2])


class ShellError(ValueError):
    """No single rod length lays on the curve with every corner a joint."""


def _equal(curve: np.ndarray, r, pref: float | None):
    """Equal chords near ``pref`` with every corner a joint, or None."""
    span = max(float(np.hypot(*(curve[-1] - curve[0]))), 1e-9)
    corners = curve[find_corners(curve, CORNER_DEG)]
    disc = discretize(curve, list(r.length), length_range=r.length, preferred=pref, corner_angle_deg=180.0)
    if r.resolution is not None:
        return None  # (rounded lengths close on B by turning, off the corners: not tried)
    ls = disc.lengths
    if float(ls.max() - ls.min()) > 1e-9 * float(ls.mean()):
        return None  # a polyline tiled segment by segment with different lengths
    for c in corners:
        if float(np.hypot(*(disc.points - c).T).min()) > CORNER_TOL * span:
            return None
    return disc


def one_shell(curve: np.ndarray, r, preferred: float | None):
    """The joints and the one curvature of a chain of one shell.

    Args:
        curve: (M, 2) target polyline from A to B (mm).
        r: the family's ranges (length, curvature, resolution).
        preferred: the length to aim at, or None (the longest rods that follow the curve
            within :data:`FOLLOW_REL` of the span).

    Returns:
        (Discretization, curvatures): every length equal, every curvature equal.

    Raises:
        ShellError: the curve's corners forbid one length (explained).
    """
    curve = np.asarray(curve, float)
    total = float(np.sum(np.hypot(*np.diff(curve, axis=0).T)))
    kmax = max(abs(r.curvature[0]), abs(r.curvature[1]))
    lo, hi = r.length
    # lengths aimed at: the given one, or the range from its longest; then every count's
    # even share of the curve (a polyline's corners land on joints for some of them only)
    aims = [preferred] if preferred is not None else [float(x) for x in np.geomspace(hi, lo, TRIES)]
    counts = range(max(1, math.floor(total / hi)), math.ceil(total / lo) + 2)
    extra = sorted((total / n for n in counts if lo <= total / n <= hi),
                   key=lambda x: abs(x - (preferred if preferred is not None else hi)))

    def lay(pref: float):
        try:
            disc = _equal(curve, r, pref)
        except ValueError:
            return None
        if disc is None:
            return None
        k = float(np.mean(fit_curvatures(curve, disc.points, max_curvature=kmax))) if kmax else 0.0
        k = float(np.clip(k, *r.curvature))
        arc = max_curvature(float(disc.lengths[0]))
        return disc, np.full(disc.lengths.size, float(np.clip(k, -arc, arc)))

    if preferred is not None:  # the first layout at or near that length, however it follows
        best = next((laid for laid in map(lay, [*aims, *extra]) if laid is not None), None)
    else:
        best = most_faithful(curve, map(lay, [*aims, *extra]))
    if best is None:
        raise ShellError(f"no single rod length from {lo:g} to {hi:g} mm lays on this target with every corner "
                         "a joint: its corners forbid one shell for every rod (drop same_shell, or change the "
                         "target)" + (f" at the preferred length {preferred:g} mm" if preferred is not None else "")
                         + (" (lengths rounded to a resolution are not laid as one shell)"
                            if r.resolution is not None else ""))
    return best
