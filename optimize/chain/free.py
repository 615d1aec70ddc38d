"""The equilibrium of a chain whose joints and anchor pins are all free: the fast path.

With no limits and no anchor stops every rod is its own group (``P_k = l_k``,
``Q_k = l_k sigma_k``, :mod:`optimize.chain.equilibrium`), so the dual function is::

    Psi(lambda) = sum_k l_k |lambda - sigma_k| - Re(conj(B - A) lambda)

and each rod turns along its load: ``e^{i theta_k} = (lambda - sigma_k) / |lambda - sigma_k|``.
Newton on the two unknowns (H, V) then needs no trigonometry (the unit loads are the rods'
cosines and sines), and it starts from the catenary of the chain's length and weight
between the anchors (a few scalar Newton steps), which a chain of many rods follows
closely: two or three steps where the two-bar guess takes five. The checks are the general
solver's, in closed form for this case: closure and every rod's moment balance (the KKT
residual), and stability, which for a chain in tension everywhere (``|lambda - sigma_k| > 0``,
the Lagrangian's Hessian diagonal and positive) holds on any tangent space.
"""

from __future__ import annotations

import math

import numpy as np

from optimize.chain.model import MESSAGES, Chain, EquilibriumResult

__all__ = ["catenary_reaction", "solve_free"]

#: Newton steps before the case is handed to the general solver (each costs O(N); from the
#: catenary a chain takes 2-5; more means the optimum sits on a kink, a rod without load).
MAX_STEPS = 12


def _sinh_ratio_root(k: float) -> float:
    """u > 0 with sinh(u) = k u (k > 1), by Newton from an asymptotic start."""
    u = math.sqrt(6.0 * (k - 1.0)) if k < 3.0 else math.log(2.0 * k * math.log(2.0 * k) + 1e-300)
    for _ in range(60):
        s, c = math.sinh(u), math.cosh(u)
        step = (s - k * u) / (c - k)
        u_new = u - step
        if u_new <= 0:
            u_new = 0.5 * u
        if abs(u_new - u) <= 1e-15 * u:
            return u_new
        u = u_new
    return u


def catenary_reaction(chain: Chain) -> complex | None:
    """The reaction at B (H + iV) of a uniform chain of the same length and weight hung
    between the anchors (a catenary), or None where it is degenerate (anchors one above the
    other, or all but taut)."""
    dx, dy = chain.d.real, chain.d.imag
    length, weight = chain.total_length, chain.g * chain.total_mass
    span_x = abs(dx)
    slack = length * length - dy * dy
    if span_x <= 1e-6 * length or slack <= 0:
        return None
    k = math.sqrt(slack) / span_x
    if not k > 1.0 + 1e-12:
        return None
    u = _sinh_ratio_root(k)
    a = span_x / (2.0 * u)
    h = weight / length * a  # horizontal tension
    slope_b = math.sinh(u + math.asinh(dy / (2.0 * a * math.sinh(u))))
    if not (math.isfinite(h) and math.isfinite(slope_b)):
        return None
    return complex(math.copysign(h, dx), h * slope_b)


def solve_free(chain: Chain) -> EquilibriumResult | None:
    """The equilibrium of a chain with every joint and anchor pin free (no limits, no anchor
    stops), or None where this path does not settle it (the general solver then does)."""
    l = chain.lengths
    sx, sy = chain.sigma.real, chain.sigma.imag
    dx, dy = chain.d.real, chain.d.imag
    tol = 64 * np.finfo(float).eps * chain.total_length
    lam = catenary_reaction(chain)
    if lam is None:
        from optimize.chain.dual import initial_reaction

        lam = initial_reaction(chain)
    hx, hy = lam.real, lam.imag

    def evaluate(hx, hy):
        zx, zy = hx - sx, hy - sy
        r = np.sqrt(zx * zx + zy * zy)
        if not r.min() > 0:
            return None
        ux, uy = zx / r, zy / r
        gx, gy = l @ ux - dx, l @ uy - dy
        psi = float(l @ r - (dx * hx + dy * hy))
        return r, ux, uy, gx, gy, psi

    ev = evaluate(hx, hy)
    if ev is None:
        return None
    steps = 0
    while True:
        r, ux, uy, gx, gy, psi = ev
        if math.hypot(gx, gy) <= tol:
            break
        if steps >= MAX_STEPS:
            return None
        a = l / r
        auy, aux = a * uy, a * ux
        hxx, hyy, hxy = float(auy @ uy), float(aux @ ux), -float(aux @ uy)
        det = hxx * hyy - hxy * hxy
        if not (math.isfinite(det) and det > 1e-14 * (hxx + hyy) ** 2):
            return None  # a chain (almost) straight along its loads: the general solver's regularised step
        px, py = -(hyy * gx - hxy * gy) / det, -(hxx * gy - hxy * gx) / det
        slope = gx * px + gy * py
        t = 1.0
        while True:
            trial = evaluate(hx + t * px, hy + t * py)
            if trial is not None:
                if trial[5] <= psi + 1e-4 * t * slope:
                    break
                if (abs(trial[5] - psi) <= 1e3 * np.finfo(float).eps * (abs(psi) + abs(trial[5]))
                        and math.hypot(trial[3], trial[4]) < math.hypot(gx, gy)):
                    break  # the change of Psi is below round-off: judged by the gradient
            if t < 1e-12:
                trial = None
                break
            t *= 0.5
        if trial is None:  # no descent left: at the floor of round-off, or not this path's case
            if math.hypot(gx, gy) <= 1e-9 * chain.total_length:
                break
            return None
        hx, hy = hx + t * px, hy + t * py
        ev = trial
        steps += 1
    r, ux, uy, gx, gy, _ = ev
    theta = np.arctan2(uy, ux)
    jumps = np.diff(theta)
    if np.abs(jumps).max(initial=0.0) > math.pi:  # unwrapped as np.unwrap: bends in (-pi, pi]
        theta[1:] -= 2 * math.pi * np.cumsum(np.round(jumps / (2 * math.pi)))
    steps_xy = np.empty((chain.n + 1, 2))
    steps_xy[0] = 0.0
    steps_xy[1:, 0] = l * ux
    steps_xy[1:, 1] = l * uy
    pts = chain.anchor_a + np.cumsum(steps_xy, axis=0)
    closure = float(math.hypot(*(pts[-1] - chain.anchor_b)))
    # KKT: closure, and each rod's moment balance (zero by construction, to round-off)
    f = l * ((hx - sx) * uy - (hy - sy) * ux)
    cum = np.cumsum(f)
    stat = float(np.abs(cum).max()) / chain.moment_scale
    kkt = max(math.hypot(gx, gy) / chain.total_length, stat)
    success = kkt < 1e-9
    stable = bool(np.all(r > 1e-12 * float(r.max())))  # tension everywhere: diagonal Hessian l r > 0
    energy = float(chain.c_sin @ uy + chain.c_cos @ ux + chain.g * chain.total_mass * chain.anchor_a[1])
    weight = chain.g * chain.total_mass
    n1 = chain.n - 1
    return EquilibriumResult(
        points=pts, angles=theta, reaction=np.array([hx, hy]), reaction_a=np.array([-hx, weight - hy]),
        moments=np.zeros(n1), active=np.zeros(n1, dtype=int), kkt_residual=kkt, closure_error=closure,
        energy=energy, stable=stable, success=success, status=0 if success else 1,
        message=MESSAGES[0 if success else 1], nit=1, nnewton=steps, model="exact",
        info={"used_nlp": False, "path": "free", "end_moments": np.zeros(2), "end_active": np.zeros(2, dtype=int),
              "fixtures_hold": True})
