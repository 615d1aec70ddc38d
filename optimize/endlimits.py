"""Anchor stops: bounds on the absolute angles of the first and last rods.

A fixture that stops the first rod bounds theta_0; one that stops the last rod bounds
theta_{N-1}. At a bound the fixture carries a moment, like a joint stop. The exact
equilibrium with them follows from the solver without them by clamping:

* solve without the end limits; if theta_0 and theta_{N-1} respect them, that is the
  equilibrium (the fixtures carry nothing);
* otherwise hold a violating end rod at its bound: it is then a fixed bar, so the rest
  of the chain hangs between its free joint and the other anchor, and the limit of the
  joint next to it becomes an end limit of that shorter chain (solved the same way,
  recursively);
* the clamp is right when the fixture's moment pushes back into the allowed range
  (complementarity); each choice of clamped ends is tried in a fixed order.

The rods held by fixtures, their moments and the joint stops next to them are put back
into one :class:`optimize.chain.EquilibriumResult` of the whole chain.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from optimize.chain import EquilibriumResult

__all__ = ["as_end_limits", "limit_turn", "solve_with_end_limits"]

#: A fixture moment may have the wrong sign by this fraction of the chain's weight x length
#: (round-off) and still count as holding.
SIGN_TOL = 1e-9

#: An angle this close (rad) to an end limit counts as on it.
ANGLE_TOL = 1e-10


def as_end_limits(end_limits) -> np.ndarray | None:
    """(2, 2) end limits in radians, or None when both ends are free pins.

    Raises:
        ValueError: not a (2, 2) array of [lo, hi] rows with lo <= hi.
    """
    if end_limits is None:
        return None
    try:
        e = np.asarray(end_limits, dtype=float).reshape(2, 2)
    except (TypeError, ValueError):
        raise ValueError("end_limits must be a (2, 2) array of [lo, hi] rows (radians)") from None
    if np.any(np.isnan(e)) or np.any(e[:, 0] > e[:, 1]):
        raise ValueError(f"end_limits rows must be [lo, hi] with lo <= hi, got {e.tolist()}")
    if np.all(np.isinf(e[:, 0])) and np.all(np.isinf(e[:, 1])):
        return None
    return e


def _cross(u, v) -> float:
    return float(u[0] * v[1] - u[1] * v[0])


def limit_turn(theta: float, lim: np.ndarray) -> float:
    """The whole turns (rad, a multiple of 2 pi) between ``theta`` and the turn of an end
    limit: ``theta - limit_turn`` lies within half a turn of the middle of the limit's finite
    bounds (a one-sided limit [lo, inf) allows the half turn above lo); 0 without bounds."""
    finite = lim[np.isfinite(lim)]
    if not finite.size:
        return 0.0
    return 2 * math.pi * round((float(theta) - float(finite.mean())) / (2 * math.pi))


def _near(theta: float, lim: np.ndarray) -> float:
    """``theta`` on the turn (mod 2 pi) nearest the limit's finite bounds (:func:`limit_turn`)."""
    return float(theta - limit_turn(theta, lim))


def _inside(theta: float, lim: np.ndarray) -> bool:
    t = _near(theta, lim)
    return lim[0] - ANGLE_TOL <= t <= lim[1] + ANGLE_TOL


def solve_with_end_limits(solve, lengths, masses, a, b, com, limits, end_limits, g,
                          first_joint: int = 0) -> EquilibriumResult:
    """The equilibrium with anchor stops.

    Args:
        solve: the solver without end limits, ``solve(lengths, masses, a, b, com, limits,
            first_joint)``; ``first_joint`` is the index, in the whole chain, of the first
            joint of the (shorter) chain it is given (to start from a given active set).
        lengths, masses, a, b, com, limits: as for :func:`optimize.solve_equilibrium`
            (validated arrays; ``limits`` (N-1, 2)).
        end_limits: (2, 2) bounds on theta_0 and theta_{N-1} (radians).
        g: gravitational acceleration.
        first_joint: the index of this chain's first joint in the whole chain.
    """
    free = solve(lengths, masses, a, b, com, limits, first_joint)
    ok0, ok1 = _inside(free.angles[0], end_limits[0]), _inside(free.angles[-1], end_limits[1])
    if ok0 and ok1:
        return _with_ends(free, np.zeros(2), np.zeros(2, dtype=int))
    # hold every end that passes its bound; failing that, each of two such ends alone
    violated = [end for end, ok in ((0, ok0), (1, ok1)) if not ok]
    trials = [set(violated)] + ([{end} for end in violated] if len(violated) == 2 else [])
    best = None
    for held in trials:
        r = _clamped(solve, lengths, masses, a, b, com, limits, end_limits, g, free, 0 in held, 1 in held,
                     first_joint)
        if r is None:
            continue
        if r.success and r.info.get("fixtures_hold", False):
            return r
        best = best or r
    if best is not None:
        return replace(best, success=False, message=best.message + "; no clamp of the end rods holds")
    return replace(_with_ends(free, np.zeros(2), np.zeros(2, dtype=int)), success=False,
                   message="the end limits cannot be met (the end rods cannot be held at them)")


def _bound(theta: float, lim: np.ndarray) -> tuple[float, int]:
    """The violated bound and its side (-1 lo, +1 hi)."""
    theta = _near(theta, lim)
    return (float(lim[1]), 1) if theta > lim[1] else (float(lim[0]), -1)


def _clamped(solve, lengths, masses, a, b, com, limits, end_limits, g, free, first: bool, last: bool,
             first_joint: int = 0):
    n = len(lengths)
    lo_i, hi_i = (1 if first else 0), (n - 1 if last else n)
    if hi_i - lo_i < 1:
        return None
    a2, b2 = np.array(a, float), np.array(b, float)
    th0 = th1 = None
    side = np.zeros(2, dtype=int)
    if first:
        th0, side[0] = _bound(free.angles[0], end_limits[0])
        a2 = a2 + lengths[0] * np.array([math.cos(th0), math.sin(th0)])
    if last:
        th1, side[1] = _bound(free.angles[-1], end_limits[1])
        b2 = b2 - lengths[-1] * np.array([math.cos(th1), math.sin(th1)])
    sub = slice(lo_i, hi_i)
    m = hi_i - lo_i
    sub_lengths, sub_masses, sub_com = lengths[sub], masses[sub], com[sub]
    sub_limits = limits[lo_i:hi_i - 1] if m > 1 else np.zeros((0, 2))
    e = np.array([[-np.inf, np.inf], [-np.inf, np.inf]])
    e[0] = end_limits[0] if not first else limits[0] + th0
    e[1] = end_limits[1] if not last else th1 - limits[-1][::-1]  # phi = th1 - theta_{N-2}
    if m == 1:  # one rod between two fixed points: closure decides it
        d = b2 - a2
        if abs(float(np.hypot(*d)) - sub_lengths[0]) > 1e-9 * float(lengths.sum()):
            return None
        theta = math.atan2(d[1], d[0])
        if not (_inside(theta, e[0]) and _inside(theta, e[1])):
            return None
        sub_res = _single_rod(a2, b2, sub_lengths[0], sub_masses[0], sub_com[0], g)
    else:
        sub_e = e if np.any(np.isfinite(e)) else None
        try:
            if sub_e is None:
                sub_res = _with_ends(solve(sub_lengths, sub_masses, a2, b2, sub_com, sub_limits,
                                           first_joint + lo_i), np.zeros(2),
                                     np.zeros(2, dtype=int))
            else:
                sub_res = solve_with_end_limits(solve, sub_lengths, sub_masses, a2, b2, sub_com, sub_limits,
                                                sub_e, g, first_joint + lo_i)
        except ValueError:  # the fixed rods leave anchors the rest cannot reach
            return None
    return _assemble(lengths, masses, a, b, com, g, sub_res, first, last, th0, th1, side)


def _single_rod(a, b, length, mass, com, g) -> EquilibriumResult:
    """One rod held at both ends: statically indeterminate along it; take the split of its
    weight that puts no moment at either end (pinned both ends: moments are zero)."""
    d = b - a
    theta = math.atan2(d[1], d[0])
    u = d / length
    v = np.array([-u[1], u[0]])
    c = a + com[0] * u + com[1] * v
    w = mass * g
    # moments about A: Vb * dx - Hb * dy - w * (c - a).x = 0; take the pull along the rod zero
    dx, dy = d
    t = w * (c[0] - a[0]) / (dx * dx + dy * dy) if (dx * dx + dy * dy) > 0 else 0.0
    rb = np.array([-dy * t, dx * t])  # perpendicular to the rod: carries the moment about A
    ra = np.array([0.0, w]) - rb
    return EquilibriumResult(points=np.array([a, b]), angles=np.array([theta]), reaction=rb, reaction_a=ra,
                             moments=np.zeros(0), active=np.zeros(0, dtype=int), kkt_residual=0.0, closure_error=0.0,
                             energy=g * mass * c[1], stable=True, success=True, status=0,
                             message="a single rod between two fixed points",
                             info={"end_moments": np.zeros(2), "end_active": np.zeros(2, dtype=int)})


def _assemble(lengths, masses, a, b, com, g, sub, first, last, th0, th1, side) -> EquilibriumResult:
    """The whole chain from the clamped end rods and the solved rest."""
    pts = [np.asarray(p, float) for p in sub.points]
    angles = list(sub.angles)
    moments = list(sub.moments)
    active = list(sub.active)
    sub_end = sub.info.get("end_moments", np.zeros(2))
    sub_active = sub.info.get("end_active", np.zeros(2, dtype=int))
    end_m = np.zeros(2)
    end_a = np.zeros(2, dtype=int)
    reaction_a = np.asarray(sub.reaction_a, float)
    reaction = np.asarray(sub.reaction, float)
    energy = sub.energy
    holds = True
    scale = float(np.sum(masses) * g * np.sum(lengths))
    if first:
        u = np.array([math.cos(th0), math.sin(th0)])
        c0 = a + com[0][0] * u + com[0][1] * np.array([-u[1], u[0]])
        # rod 0 in balance: the fixture's moment about A, the rest's pull at p_1, its weight
        # (a stop between rod 0 and the rest puts the rest's end moment back on rod 0, reversed)
        m_a = (_cross(pts[0] - a, reaction_a) - _cross(c0 - a, np.array([0.0, -masses[0] * g]))
               + float(sub_end[0]))
        holds &= -side[0] * m_a >= -SIGN_TOL * scale
        end_m[0], end_a[0] = m_a, side[0]
        moments.insert(0, float(sub_end[0]))
        active.insert(0, int(sub_active[0]))
        end_m[1], end_a[1] = (sub_end[1], sub_active[1]) if not last else (0.0, 0)
        reaction_a = reaction_a + np.array([0.0, masses[0] * g])
        energy += g * masses[0] * c0[1]
        pts.insert(0, np.asarray(a, float))
        angles.insert(0, th0)
    else:
        end_m[0], end_a[0] = sub_end[0], sub_active[0]
    if last:
        u = np.array([math.cos(th1), math.sin(th1)])
        p = pts[-1]
        cl = p + com[-1][0] * u + com[-1][1] * np.array([-u[1], u[0]])
        m_b = (_cross(p - b, reaction) - _cross(cl - b, np.array([0.0, -masses[-1] * g]))
               + float(sub_end[1]))
        holds &= -side[1] * m_b >= -SIGN_TOL * scale
        end_m[1], end_a[1] = m_b, side[1]
        # the rest's end limit bounds theta_{N-2}: its upper bound is the joint's lo, and a
        # moment pushing theta_{N-2} up pushes the bend phi_{N-2} down
        moments.append(-float(sub_end[1]))
        active.append(-int(sub_active[1]))
        reaction = reaction + np.array([0.0, masses[-1] * g])
        energy += g * masses[-1] * cl[1]
        pts.append(np.asarray(b, float))
        angles.append(th1)
    elif first:
        end_m[1], end_a[1] = sub_end[1], sub_active[1]
    points = np.array(pts)
    points[-1] = b
    info = dict(sub.info)
    info.update(end_moments=end_m, end_active=end_a, fixtures_hold=bool(holds and sub.info.get("fixtures_hold", True)))
    return replace(sub, points=points, angles=np.array(angles), reaction=reaction, reaction_a=reaction_a,
                   moments=np.array(moments), active=np.array(active, dtype=int), energy=float(energy), info=info)


def _with_ends(res: EquilibriumResult, moments: np.ndarray, active: np.ndarray) -> EquilibriumResult:
    info = dict(res.info)
    info.update(end_moments=moments, end_active=active, fixtures_hold=True)
    return replace(res, info=info)
