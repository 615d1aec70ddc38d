"""How many stable equilibria does a chain have? Multi-start over initial active sets.

With free joints the equilibrium is unique (the dual problem is strictly convex);
joint limits can create several stable equilibria (a locked run resting on one
side or the other, an arch held up by its stops). A design should know whether
its target is the only one.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from optimize.chain.equilibrium import EquilibriumResult, solve_equilibrium


#: Random starts of chains up to this many rods that the exchange and the descent cannot
#: finish are polished by SLSQP (milliseconds at this size: an arch leaning the other way is
#: found that way); longer chains' such starts count as failed (SLSQP there takes seconds
#: a start, and the descent already covers what it would find).
NLP_RODS = 16


@dataclass
class MultiStartResult:
    """Distinct stable equilibria found from several starts.

    Attributes:
        equilibria: the distinct stable equilibria, lowest potential energy first.
        counts: how many starts ended at each of them.
        n_starts: starts tried; n_failed: starts that found no stable equilibrium.
    """

    equilibria: list[EquilibriumResult] = field(default_factory=list)
    counts: list[int] = field(default_factory=list)
    n_starts: int = 0
    n_failed: int = 0

    @property
    def n_distinct(self) -> int:
        return len(self.equilibria)

    @property
    def unique(self) -> bool:
        return self.n_distinct == 1


def find_equilibria(
    lengths,
    masses,
    anchor_a,
    anchor_b,
    *,
    com=None,
    limits=None,
    g: float = 9.81,
    n_starts: int = 16,
    end_limits=None,
    seed: int | np.random.Generator | None = 0,
    tol: float = 1e-7,
) -> MultiStartResult:
    """Solve from the default start and from random initial active sets.

    Args:
        lengths, masses, anchor_a, anchor_b, com, limits, g, end_limits: as
            :func:`solve_equilibrium` (with end limits each start also holds the end rods
            at random: free, or at a finite bound of their anchor stop).
        n_starts: number of starts (the first is the default start).
        seed: seed or generator for the random active sets (same seed, same result).
        tol: two equilibria are the same when no joint differs by more than
            ``tol`` times the span |B - A|.

    Returns:
        MultiStartResult.
    """
    rng = np.random.default_rng(seed)
    n_rods = np.asarray(lengths).size
    first = solve_equilibrium(lengths, masses, anchor_a, anchor_b, com=com, limits=limits, g=g, end_limits=end_limits,
                              nlp_fallback=n_rods <= NLP_RODS)
    n = first.angles.size
    lim = np.asarray(limits, dtype=float) if limits is not None else None
    span = max(float(np.hypot(*(np.asarray(anchor_b, float) - np.asarray(anchor_a, float)))), 1e-300)
    out = MultiStartResult(n_starts=n_starts)

    def record(res: EquilibriumResult) -> None:
        if not (res.success and res.stable):
            out.n_failed += 1
            return
        for k, known in enumerate(out.equilibria):
            if np.max(np.abs(known.points - res.points)) <= tol * span:
                out.counts[k] += 1
                return
        out.equilibria.append(res)
        out.counts.append(1)

    record(first)
    limited = np.zeros(max(n - 1, 0), dtype=bool) if lim is None else np.isfinite(lim).any(axis=1)
    ends = np.array([[-np.inf, np.inf]] * 2) if end_limits is None else np.asarray(end_limits, float).reshape(2, 2)
    for _ in range(n_starts - 1):
        if not limited.any() and not np.isfinite(ends).any():
            record(first)  # free joints: the equilibrium is unique, every start ends there
            continue
        p = rng.uniform(0.1, 0.9)
        active0 = np.where(rng.random(n - 1) < p, rng.choice([-1, 1], size=n - 1), 0)
        active0 = np.where(limited, active0, 0)
        # each anchor stop free or held at one of its finite bounds, at random (no draw for
        # a bare pin: the starts of a chain without anchor stops stay as they were)
        end0 = [0, 0]
        for k, e in enumerate(ends):
            options = [0] + [s for s, bound in ((-1, e[0]), (1, e[1])) if np.isfinite(bound)]
            if len(options) > 1:
                end0[k] = int(rng.choice(options))
        try:
            res = solve_equilibrium(
                lengths, masses, anchor_a, anchor_b, com=com, limits=limits, g=g, active0=active0,
                end_limits=end_limits, end_active0=end0, nlp_fallback=n <= NLP_RODS,
            )
        except ValueError:
            out.n_failed += 1
            continue
        record(res)
    order = np.argsort([e.energy for e in out.equilibria])
    out.equilibria = [out.equilibria[i] for i in order]
    out.counts = [out.counts[i] for i in order]
    return out
