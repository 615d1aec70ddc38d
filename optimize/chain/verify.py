"""Is a design's target the shape the chain really hangs in?

Statics at the target (:mod:`optimize.chain.statics`) say the target *balances*: with these
masses and stops every rod is in equilibrium there. That is not enough: the balance can
be unstable (a stop that only pushes one way under a load that can roll off it, a
compressed run), and a stable one can have neighbours the chain may settle in instead
(a lobe that folds the other way, a run that swings onto other stops). :func:`verify`
asks the solver:

1. the equilibrium reached from the designed state (every joint resting on the stop the
   design puts it on): it must be the target (to ``tol`` of the chain's size), found to
   round-off (KKT) and stable (second order on the binding constraints);
2. a multi-start (:func:`optimize.find_equilibria`) for other stable shapes: how many,
   and whether one lies lower than the design (a knock can move the chain into a lower
   one);
3. where the other shapes differ from the design: the joints (and anchors) whose bends
   differ most, the first ones to hold rigid (a two-sided stop) to rule them out.

Angles in radians, lengths in the caller's unit. numpy/scipy only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from optimize.chain.model import EquilibriumResult
from optimize.chain.multistart import find_equilibria
from optimize.chain.problem import InverseProblem
from optimize.chain.statics import extended_bends

__all__ = ["Verdict", "extended_differences", "verify"]


@dataclass
class Verdict:
    """What the solver says of a design.

    Attributes:
        equilibrium: the equilibrium reached from the designed state (None: the solver
            found none, e.g. the rigid joints leave no way to reach anchor B).
        error: its largest joint distance from the target (length unit).
        size: the chain's size the tolerance is relative to (the larger of the anchors'
            distance and the target's width and height).
        on_target: ``equilibrium`` succeeded, is stable and lies within the tolerance of the
            target.
        others: the other stable equilibria the multi-start found, lowest energy first.
        lower: one of ``others`` lies lower than ``equilibrium`` (by more than round-off).
        culprits: extended joints (-1: anchor A, 0..N-2: joints, N-1: anchor B) where the
            other shapes (or, off target, the shape reached) differ most from the design,
            the largest difference first.
        starts: how many starts the multi-start made.
    """

    equilibrium: EquilibriumResult | None
    error: float
    size: float
    on_target: bool
    others: list[EquilibriumResult] = field(default_factory=list)
    lower: bool = False
    culprits: list[int] = field(default_factory=list)
    starts: int = 0

    @property
    def unique(self) -> bool:
        """On target and no other stable shape found."""
        return self.on_target and not self.others


def extended_differences(problem: InverseProblem, eq: EquilibriumResult) -> np.ndarray:
    """(N+1,) |bend difference| (rad, wrapped to +-pi) between an equilibrium and the target
    at every extended joint: anchor A (theta_0), the joints, anchor B (-theta_{N-1})."""
    target, _ = extended_bends(problem)
    theta = np.asarray(eq.angles, float)
    theirs = np.concatenate([[theta[0]], np.diff(theta), [-theta[-1]]])
    return np.abs(np.angle(np.exp(1j * (theirs - target))))


def _size(problem: InverseProblem) -> float:
    t = problem.target
    return float(max(problem.span, *np.ptp(t, axis=0)))


def verify(problem: InverseProblem, masses, *, n_starts: int = 12, seed: int = 0, tol: float = 1e-6,
           max_culprits: int = 4) -> Verdict:
    """The solver's verdict on a design (see the module's docstring).

    Args:
        problem: the target, rods, limits (the stops at their designed bends, rigid joints
            with lo == hi) and end limits.
        masses: (N,) the designed masses.
        n_starts: starts of the multi-start (0: none).
        seed: its seed.
        tol: the reached equilibrium must lie within ``tol`` times the chain's size of the
            target.
        max_culprits: how many joints to name in ``culprits``.

    Returns:
        The :class:`Verdict`. E.g. a free chain whose masses come from
        :func:`optimize.chain.statics.exact_masses` is on target and unique.
    """
    masses = np.asarray(masses, float)
    a, b = problem.anchors
    size = _size(problem)
    limits = problem.limits if problem.n > 1 else None
    try:
        eq = problem.simulate(masses)  # from the designed state
    except ValueError:  # no configuration reaches B from there: not this design's shape
        return Verdict(None, math.inf, size, False)
    error = float(np.max(np.hypot(*(eq.points - problem.target).T))) if eq.success else math.inf
    on_target = bool(eq.success and eq.stable and error <= tol * size)
    others: list[EquilibriumResult] = []
    starts = 0
    if n_starts > 0:
        try:
            multi = find_equilibria(problem.lengths, masses, a, b, com=problem.com, limits=limits, g=problem.g,
                                    n_starts=n_starts, seed=seed, end_limits=problem.end_limits)
        except ValueError:
            multi = None
        starts = multi.n_starts if multi is not None else 0
        for e in multi.equilibria if multi is not None else ():
            if np.max(np.hypot(*(e.points - eq.points).T)) > max(tol, 1e-7) * size:
                others.append(e)
    scale = abs(eq.energy) + 1e-300
    lower = any(e.energy < eq.energy - 1e-9 * scale for e in others)
    diffs = [extended_differences(problem, e) for e in others]
    if not on_target:
        diffs.insert(0, extended_differences(problem, eq))
    culprits: list[int] = []
    for d in diffs:  # the largest difference of each shape first, then the next ones
        for k in np.argsort(-d, kind="stable"):
            if d[k] <= 1e-3:
                break
            j = int(k) - 1
            if j not in culprits:
                culprits.append(j)
                break
    for d in diffs:
        for k in np.argsort(-d, kind="stable")[:max_culprits]:
            j = int(k) - 1
            if d[k] > 1e-3 and j not in culprits:
                culprits.append(j)
    return Verdict(eq, error, size, on_target, others, lower, culprits[:max_culprits], starts)
