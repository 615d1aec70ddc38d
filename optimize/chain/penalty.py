"""The paper's penalty model of the hanging chain (Song, Feng, Zhou 2017, Eq. 1-3).

    E(Theta) = sum_i m_i g h_i + lambda_1 E1(Theta) + lambda_2 E2(Theta)

with the left end fixed at A, E1 the squared distance of the far end from B and
E2 the number of joints whose bend lies outside its limits (a Boolean collision
count). It is kept so the exact model can be compared with it: a finite
lambda_1 leaves the far end off its anchor by about |reaction| / (2 lambda_1), and
E2 has no gradient, so limits are only honoured where a derivative-free polish
happens to find it. Heights h_i are those of the rods' centres of mass.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize

from optimize.chain.model import (
    MESSAGES,
    Chain,
    EquilibriumResult,
    is_stable,
    kkt_residual,
    multipliers,
    sag_guess,
)


def penalty_energy(chain: Chain, theta: np.ndarray, lam1: float, lam2: float) -> float:
    """E(Theta) of the paper's Eq. 1 (in the caller's units)."""
    end = chain.anchor_a + np.array(
        [chain.lengths @ np.cos(theta), chain.lengths @ np.sin(theta)]
    )
    e1 = float(np.sum((end - chain.anchor_b) ** 2))
    phi = np.diff(theta)
    e2 = float(np.count_nonzero((phi < chain.limits[:, 0]) | (phi > chain.limits[:, 1])))
    return chain.energy(theta) + lam1 * e1 + lam2 * e2


def solve_penalty(chain: Chain, penalty_weight: float, collision_weight: float) -> EquilibriumResult:
    """Minimise the paper's penalised energy.

    Args:
        chain: the validated problem.
        penalty_weight: lambda_1 in units of total weight / total length.
        collision_weight: lambda_2 in units of total weight x total length.
    """
    if not (np.isfinite(penalty_weight) and penalty_weight > 0):
        raise ValueError(f"penalty_weight must be positive, got {penalty_weight}")
    if not (np.isfinite(collision_weight) and collision_weight >= 0):
        raise ValueError(f"collision_weight must be non-negative, got {collision_weight}")
    weight = chain.g * chain.total_mass
    lam1 = penalty_weight * weight / chain.total_length
    lam2 = collision_weight * weight * chain.total_length
    l = chain.lengths
    c_sin, c_cos = chain.c_sin, chain.c_cos

    def smooth(theta):
        c, s = np.cos(theta), np.sin(theta)
        miss = chain.anchor_a + np.array([l @ c, l @ s]) - chain.anchor_b
        value = c_sin @ s + c_cos @ c + lam1 * (miss @ miss)
        grad = c_sin * c - c_cos * s + 2 * lam1 * (miss[1] * l * c - miss[0] * l * s)
        return float(value), grad

    n = chain.n
    theta0 = sag_guess(chain)
    res = minimize(smooth, theta0, jac=True, method="BFGS", options={"gtol": 1e-12, "maxiter": 20000})
    theta = res.x
    converged = bool(res.success) or res.status == 2  # 2: precision loss at the minimum
    if np.any(np.isfinite(chain.limits)) and lam2 > 0:
        polish = minimize(
            lambda t: penalty_energy(chain, t, lam1, lam2),
            theta,
            method="Powell",
            options={"xtol": 1e-10, "ftol": 1e-14, "maxfev": 2000 * n},
        )
        theta = polish.x
    pts = chain.points(theta)
    miss = pts[-1] - chain.anchor_b
    closure = float(np.hypot(*miss))
    lam = complex(-2 * lam1 * miss[0], -2 * lam1 * miss[1])  # penalty force = reaction at B
    phi = np.diff(theta)
    lo, hi = chain.limits[:, 0], chain.limits[:, 1]
    side = np.where(phi <= lo, -1, np.where(phi >= hi, 1, 0))
    violated = int(np.count_nonzero((phi < lo - 1e-12) | (phi > hi + 1e-12)))
    status = 6 if converged else 7
    message = (
        f"{MESSAGES[status]} closure_error = {closure:.3e} "
        f"({closure / chain.total_length:.2e} of the chain length); "
        f"{violated} joint(s) outside their limits."
    )
    mult = multipliers(chain, theta, lam)
    return EquilibriumResult(
        points=pts,
        angles=theta,
        reaction=np.array([lam.real, lam.imag]),
        reaction_a=np.array([-lam.real, weight - lam.imag]),
        moments=np.where(side != 0, mult[0], 0.0),
        active=side,
        kkt_residual=kkt_residual(chain, theta, lam, side, mult),
        closure_error=closure,
        energy=chain.energy(theta),
        stable=is_stable(chain, theta, lam, side, mult),
        success=converged,
        status=status,
        message=message,
        nit=int(res.nit),
        nnewton=0,
        model="penalty",
        info={"lambda1": lam1, "lambda2": lam2, "limit_violations": violated},
    )
