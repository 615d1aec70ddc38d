"""Print tolerance: how far the chain moves when every rod's mass is a little off.

A rod's plastic mass is off by a few per cent, independently per rod (filament diameter,
extrusion), so the shape moves. This module gives the exact first-order map from relative
mass errors to joint displacements and the band it implies.

Method
------
The equilibrium is differentiated implicitly for its active set of stops and anchor stops
(:func:`optimize.chain.sensitivity.shape_jacobian`: exact, from the KKT conditions; a rod an anchor
stop holds, and the rods stops lock to it, stay put). With relative errors ``e_k`` drawn
independently from N(0, sigma^2), ``sigma = tol / 1.96`` (``tol`` the relative error that 95 %
of the rods stay within), joint j moves by ``dp_j = sum_k (d p_j / d m_k) m_k e_k``. The band
is the 95th percentile (``quantile``) of ``max_j |dp_j|``, estimated by sampling this linear
map (seeded; ``n_samples`` draws, about 1 % sampling error at 20 000). It holds while the
active set does not change: a stop whose moment is near zero may let go under a few per cent
of mass error, which the linear map does not see (a Monte Carlo of the solver does).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from optimize.chain import Chain
from optimize.chain.equilibrium import EquilibriumResult, solve_equilibrium
from optimize.chain.sensitivity import shape_jacobian

__all__ = ["MassBand", "mass_band"]


@dataclass
class MassBand:
    """Joint displacements from independent relative mass errors (lengths in the caller's unit).

    Attributes:
        band: the ``quantile`` of the largest joint displacement over the draws (length).
        per_joint: (N+1,) the ``quantile`` of each joint's displacement (0 at the anchors).
        response: (N+1, 2, N) ``d p_j / d ln m_k``: joint j's displacement per unit relative
            error of rod k's mass (length).
        sigma: the relative standard deviation used, ``tol / 1.96``.
        quantile, n_samples, seed: the sampling.
        method: how the band was computed.
        errors: (n_samples, N) the relative mass errors drawn, when asked for
            (``keep_draws``), else None.
    """

    band: float
    per_joint: np.ndarray
    response: np.ndarray
    sigma: float
    quantile: float
    n_samples: int
    seed: int | None
    method: str = "linear map of the KKT system (exact derivative), sampled"
    errors: np.ndarray | None = field(default=None, repr=False)

    def displacements(self, errors: np.ndarray) -> np.ndarray:
        """Joint displacements (..., N+1, 2) for relative mass errors (..., N), to first order."""
        return np.einsum("jdk,...k->...jd", self.response, np.asarray(errors, dtype=float))


def mass_band(
    lengths,
    masses,
    anchor_a,
    anchor_b,
    *,
    com=None,
    limits=None,
    end_limits=None,
    g: float = 9.81,
    tol: float = 0.03,
    quantile: float = 0.95,
    n_samples: int = 20000,
    seed: int | None = 0,
    result: EquilibriumResult | None = None,
    keep_draws: bool = False,
) -> MassBand:
    """The band of joint displacements that rods' mass errors of relative size ``tol`` cause.

    Args:
        lengths, masses, anchor_a, anchor_b, com, limits, end_limits, g: the chain, as for
            :func:`optimize.solve_equilibrium`.
        tol: relative mass error that 95 % of rods stay within (``sigma = tol / 1.96``),
            e.g. 0.03 for +-3 %.
        quantile: the quantile of the largest joint displacement to report (0.95).
        n_samples: draws of the linear map.
        seed: seed of the draws (same seed, same band).
        result: the chain's equilibrium if already solved (must be of these arguments).
        keep_draws: keep the drawn relative errors in ``MassBand.errors`` (e.g. to run the
            same draws through the nonlinear solver).

    Returns:
        MassBand.

    Raises:
        ValueError: bad arguments, or an equilibrium that was not found.
    """
    if not (0 < tol < 1):
        raise ValueError(f"tol must be a relative error in (0, 1), got {tol}")
    if not (0 < quantile < 1):
        raise ValueError(f"quantile must be in (0, 1), got {quantile}")
    if n_samples < 1:
        raise ValueError(f"n_samples must be positive, got {n_samples}")
    chain = Chain.from_args(lengths, masses, anchor_a, anchor_b, com, limits, g)
    if result is None:
        result = solve_equilibrium(chain.lengths, chain.masses, chain.anchor_a, chain.anchor_b,
                                   com=chain.com, limits=chain.limits, end_limits=end_limits, g=chain.g)
    if not result.success:
        raise ValueError(f"the chain's equilibrium was not found: {result.message}")
    response = shape_jacobian(chain, result) * chain.masses  # d p / d ln m
    sigma = tol / 1.96
    rng = np.random.default_rng(seed)
    n = chain.n
    kept = np.empty((n_samples, n)) if keep_draws else None
    largest = np.empty(n_samples)
    joint = np.empty((n_samples, n + 1))
    chunk = max(1, 2_000_000 // (2 * (n + 1) * max(n, 1)))
    for start in range(0, n_samples, chunk):
        stop = min(n_samples, start + chunk)
        e = sigma * rng.standard_normal((stop - start, n))
        if kept is not None:
            kept[start:stop] = e
        dp = np.einsum("jdk,sk->sjd", response, e)
        dist = np.hypot(dp[..., 0], dp[..., 1])
        joint[start:stop] = dist
        largest[start:stop] = dist.max(axis=1)
    return MassBand(
        band=float(np.quantile(largest, quantile)),
        per_joint=np.quantile(joint, quantile, axis=0),
        response=response,
        sigma=sigma,
        quantile=quantile,
        n_samples=n_samples,
        seed=seed if not isinstance(seed, np.random.Generator) else None,
        errors=kept,
    )
