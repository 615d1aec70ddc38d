"""How well a designed chain hangs on its target, the tolerance it is held to, and, when it
misses, what limits it and what would reach it.

The figure a user checks with a ruler: the largest distance between the hanging rods'
centrelines (arcs for curved rods) and the target curve, over the target's size (the
larger of the anchors' distance, its width and its height: :func:`rodcad.design.shell.
curve_size`). A design file's ``tolerance`` sets the largest acceptable figure; without one
it is :data:`DEFAULT_TOLERANCE`. ``rodcad build`` exits 1 above it, with
:func:`fit_limit`'s one line.
"""

from __future__ import annotations

import numpy as np

from optimize.chain.curves import centerline, curve_distance
from optimize.chain.endlimits import limit_turn
from rodcad.design.shell import curve_size

__all__ = ["DEFAULT_TOLERANCE", "curve_fit", "fit_limit"]

#: Without a ``tolerance`` in the design file: rods hanging more than this fraction of the
#: target's size off its curve are a failed design (exit 1, the best fit beside OUTDIR).
DEFAULT_TOLERANCE = 0.01


def curve_fit(curve: np.ndarray, points: np.ndarray, curvature) -> float:
    """The rods' centrelines (joints ``points``, per-rod ``curvature`` 1/mm) against the
    target curve: symmetric Hausdorff distance over the target's size."""
    return float(curve_distance(curve, centerline(points, curvature)) / curve_size(curve))


def fit_limit(*, curve: np.ndarray, target_points: np.ndarray, curvature, plan, inverse, check,
              fit: float, tolerance: float, family_ranges=None, constraints=None, hardware_g=None,
              shot: bool = False) -> str:
    """One line: what keeps the chain from hanging within ``tolerance`` and what would reach it.

    Args:
        curve: the target curve (mm).
        target_points: the joints the rods were laid on (mm).
        curvature: per-rod curvature (1/mm).
        plan: the :class:`rodcad.design.plan.ChainPlan`.
        inverse: the inverse design's result (:class:`optimize.InverseResult`).
        check: the :class:`rodcad.design.masses.ChainCheck` of the designed masses.
        fit: the achieved figure (:func:`curve_fit`).
        tolerance: the figure aimed at.
        family_ranges: the family's ranges, for rods printed to order (or None).
        constraints: the design's :class:`rodcad.design.model.Constraints` (or None).
        hardware_g: (N,) g of joint hardware hanging on each rod (or None): said where the
            rods at their lightest carry some.
        shot: the rods already have the widest mass range rodcad prints (a shot chamber).
    """
    laid = curve_fit(curve, target_points, curvature)
    pct = f"{100 * fit:.3g} % of its size off the curve (tolerance {100 * tolerance:.3g} %)"
    if laid > tolerance:
        what = "rods"
        if family_ranges is not None:
            lo = family_ranges.length[0]
            kmax = max(abs(k) for k in family_ranges.curvature)
            what = (f"rods of {lo:g} mm and longer, bent to a radius of {1 / kmax:.3g} mm at most" if kmax else
                    f"rods of {lo:g} mm and longer")
        return (f"hangs {pct}: even laid exactly on its joints the {what} miss the curve by "
                f"{100 * laid:.3g} % of its size (its features are smaller than the rods can follow); "
                "a family with shorter rods or tighter curvature would reach it, or draw it larger")
    unmet = list(getattr(plan, "unmet_joints", []) or [])
    c = constraints
    if unmet:
        why = []
        if c is not None and c.joints == "free":
            why.append("allow stops (remove constraints.joints: free)")
        if c is not None and c.fuse_mode == "never":
            why.append("allow fused pieces (remove constraints.fuse: never)")
        hint = "; ".join(why) or "a family printing stops over a wider range of angles would hold them"
        return (f"hangs {pct}: joint(s) {', '.join(map(str, unmet))} bend more than anything allowed can hold; "
                f"{hint}")
    eq = check.equilibrium
    given = c.end_limits if c is not None else None
    if given is not None:
        d = np.diff(np.asarray(target_points, float), axis=0)
        theta = np.arctan2(d[:, 1], d[:, 0])[[0, -1]]
        for k, (t, lim) in enumerate(zip(theta, np.asarray(given, float))):
            t = float(t - limit_turn(t, lim))  # on the limit's turn
            if not lim[0] - 1e-9 <= t <= lim[1] + 1e-9:
                return (f"hangs {pct}: constraints.anchor_limits_deg holds the {'first' if k == 0 else 'last'} rod "
                        f"within [{np.degrees(lim[0]):.4g}, {np.degrees(lim[1]):.4g}] deg, where the target needs "
                        f"{np.degrees(t):.4g} deg; widen or remove that bound (the planner chooses the fixture's "
                        "stops itself)")
    if inverse is not None and not inverse.exact and np.any(inverse.at_bounds != 0):
        lo = int(np.sum(inverse.at_bounds < 0))
        hi = int(np.sum(inverse.at_bounds > 0))
        light = ""
        if hardware_g is not None and np.any(inverse.at_bounds < 0):
            g = np.asarray(hardware_g, float)[inverse.at_bounds < 0]
            light = (f"; the joint hardware (pins, bushings, bearings) adds {g.min():.2g}-{g.max():.2g} g to the "
                     "rods at their lightest")
        if c is not None and c.joints == "free":
            wider = "" if shot else " or use a catalog with a wider mass range (pla-shot)"
            return (f"hangs {pct}: weights alone cannot hold it ({lo} rod(s) at their lightest, {hi} at their "
                    f"heaviest{light}); allow stops (remove constraints.joints: free){wider}")
        extra = "" if c is None or c.anchor_stops_allowed else " or let the fixture stop the end rods " \
            "(remove constraints.anchor_stops: none)"
        return (f"hangs {pct}: the rods' mass ranges cannot balance it ({lo} rod(s) at their lightest, {hi} at "
                f"their heaviest{light}); a catalog with a wider mass range (heavier inserts, or pla-shot){extra} "
                "would reach it")
    if not eq.stable or not check.unique:
        return (f"hangs {pct}: the masses balance the target, but the chain settles in another shape there; "
                "holding more joints both ways (two-sided stops) or fused pieces would keep it (the planner "
                "ran out of rounds)")
    return (f"hangs {pct}: the masses the rods can really be built at (balls come in whole numbers) move it; "
            "a catalog with finer insert steps would reach it")
