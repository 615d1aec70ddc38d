"""Reference for anchor stops: every set of held end rods tried, by brute force.

The method the solver used before anchor stops joined its active set: an end rod held at a
bound of its anchor stop is a fixed bar, so the rest of the chain hangs between that bar's
free pin and the other anchor, and the stop of the joint next to the bar becomes an anchor
stop of that shorter chain. Here every choice (free, held at lo, held at hi) at each end, at
every level, is tried; each leaf is solved by ``solve_equilibrium`` *without* end limits. A
candidate counts when its free end rods lie within their bounds, each fixture's moment
(from the held rod's own balance, computed here) pushes the right way, and the shorter
chain's solution is a stable KKT point. Exponential in the chain's length: small chains only.

Conventions as ``shared/design/physics.md``; an end angle is compared with its bound on the
turn nearest the bound's middle, within half a turn (``optimize.chain.endlimits.limit_turn``).
"""

from __future__ import annotations

import math

import numpy as np

from optimize import solve_equilibrium

__all__ = ["Candidate", "held_end_candidates"]


def _near(theta: float, lim) -> float:
    finite = [x for x in lim if np.isfinite(x)]
    if not finite:
        return theta
    mid = sum(finite) / len(finite)
    return theta - 2 * math.pi * round((theta - mid) / (2 * math.pi))


def _inside(theta: float, lim, tol: float = 1e-10) -> bool:
    t = _near(theta, lim)
    return lim[0] - tol <= t <= lim[1] + tol


def _cross(u, v) -> float:
    return float(u[0] * v[1] - u[1] * v[0])


class Candidate:
    """One equilibrium of a choice of held ends: angles (N,), reaction at B (2,), fixture
    moments (2,) (positive pushes the angle up), which ends are held (-1 lo, +1 hi, 0), energy."""

    def __init__(self, angles, reaction, moments, held, energy):
        self.angles, self.reaction, self.moments, self.held, self.energy = angles, reaction, moments, held, energy


def _energy(lengths, masses, com, a, angles, g) -> float:
    pts = a + np.vstack([np.zeros(2), np.cumsum(lengths[:, None] * np.column_stack([np.cos(angles), np.sin(angles)]),
                                                 axis=0)])
    u = np.column_stack([np.cos(angles), np.sin(angles)])
    v = np.column_stack([-np.sin(angles), np.cos(angles)])
    c = pts[:-1] + com[:, :1] * u + com[:, 1:] * v
    return float(g * masses @ c[:, 1])


def held_end_candidates(lengths, masses, a, b, com, limits, end_limits, g=9.81, depth=0):
    """Every stable equilibrium the choices of held ends give (list of :class:`Candidate`).

    Args:
        lengths, masses: (N,); a, b: (2,) anchors; com: (N, 2); limits: (N-1, 2) radians;
        end_limits: (2, 2) radians (rows of +-inf: free); g: gravity.
    """
    lengths, masses = np.asarray(lengths, float), np.asarray(masses, float)
    a, b, com = np.asarray(a, float), np.asarray(b, float), np.asarray(com, float)
    limits = np.asarray(limits, float).reshape(-1, 2)
    e = np.asarray(end_limits, float).reshape(2, 2)
    n = lengths.size
    out = []
    choices = [[0] + [s for s, x in ((-1, e[k, 0]), (1, e[k, 1])) if np.isfinite(x)] for k in (0, 1)]
    for s0 in choices[0]:
        for s1 in choices[1]:
            if n == 1 and (s0 or s1):
                continue
            out += _clamped(lengths, masses, a, b, com, limits, e, g, s0, s1, depth)
    return out


def _clamped(lengths, masses, a, b, com, limits, e, g, s0, s1, depth):
    n = lengths.size
    lo_i, hi_i = (1 if s0 else 0), (n - 1 if s1 else n)
    m = hi_i - lo_i
    if m < 1:
        return []
    a2, b2 = a.copy(), b.copy()
    th0 = th1 = None
    if s0:
        th0 = e[0, 0] if s0 < 0 else e[0, 1]
        a2 = a + lengths[0] * np.array([math.cos(th0), math.sin(th0)])
    if s1:
        th1 = e[1, 0] if s1 < 0 else e[1, 1]
        b2 = b - lengths[-1] * np.array([math.cos(th1), math.sin(th1)])
    sub = slice(lo_i, hi_i)
    sub_e = np.array([[-np.inf, np.inf], [-np.inf, np.inf]])
    sub_e[0] = e[0] if not s0 else limits[0] + th0
    sub_e[1] = e[1] if not s1 else th1 - limits[-1][::-1]
    sub_lim = limits[lo_i:hi_i - 1]
    subs = []
    if m == 1:
        d = b2 - a2
        if abs(float(np.hypot(*d)) - lengths[lo_i]) > 1e-9 * lengths.sum():
            return []
        theta = math.atan2(d[1], d[0])
        if not (_inside(theta, sub_e[0]) and _inside(theta, sub_e[1])):
            return []
        return []  # a lone rod between two fixed pins: indeterminate, left out of the reference
    if np.any(np.isfinite(sub_e)) and (s0 or s1):
        try:
            subs = held_end_candidates(lengths[sub], masses[sub], a2, b2, com[sub], sub_lim, sub_e, g, depth + 1)
        except ValueError:
            return []
    else:
        try:
            r = solve_equilibrium(lengths[sub], masses[sub], a2, b2, com=com[sub], limits=sub_lim, g=g)
        except ValueError:
            return []
        if not (r.success and r.stable):
            return []
        if not (_inside(r.angles[0], sub_e[0]) and _inside(r.angles[-1], sub_e[1])):
            return []
        subs = [Candidate(r.angles, r.reaction, np.zeros(2), np.zeros(2, int), 0.0)]
    out = []
    scale = float(np.sum(masses) * g * np.sum(lengths))
    for s in subs:
        angles = list(s.angles)
        r_b2 = np.asarray(s.reaction, float)  # the force the rest takes at its far pin b2
        r_a2 = np.array([0.0, g * float(np.sum(masses[sub]))]) - r_b2  # and at its near pin a2
        sub_m = np.asarray(s.moments, float)  # the rest's own fixture (here: joint stop) moments
        moments = sub_m.copy()
        reaction = r_b2.copy()
        ok = True
        # a held bar in balance about its anchor: the rest's pull on its free pin, its weight,
        # the fixture, and the rest's stop moment at that pin taken back reversed
        if s1:
            u = np.array([math.cos(th1), math.sin(th1)])
            c = b2 + com[-1, 0] * u + com[-1, 1] * np.array([-u[1], u[0]])
            m_b = _cross(b2 - b, r_b2) - _cross(c - b, np.array([0.0, -masses[-1] * g])) + float(sub_m[1])
            ok &= -s1 * m_b >= -1e-9 * scale
            moments[1] = m_b
            reaction = r_b2 + np.array([0.0, masses[-1] * g])
            angles.append(th1)
        if s0:
            u = np.array([math.cos(th0), math.sin(th0)])
            c = a + com[0, 0] * u + com[0, 1] * np.array([-u[1], u[0]])
            m_a = _cross(a2 - a, r_a2) - _cross(c - a, np.array([0.0, -masses[0] * g])) + float(sub_m[0])
            ok &= -s0 * m_a >= -1e-9 * scale
            moments[0] = m_a
            angles.insert(0, th0)
        if not ok:
            continue
        angles = np.array(angles)
        held = np.array([s0 if s0 else s.held[0], s1 if s1 else s.held[1]])
        out.append(Candidate(angles, reaction, moments, held, _energy(lengths, masses, com, a, angles, g)))
    return out
