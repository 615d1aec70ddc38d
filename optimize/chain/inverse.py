"""Inverse design: the rod masses whose equilibrium matches a target shape.

All methods work on one :class:`InverseProblem` (target joints, rod lengths,
centres of mass, joint limits, mass bounds) and return one :class:`InverseResult`.

- ``exact``: at the target configuration the statics are linear in the masses,
  the support reaction and the moments at joints placed on a limit (per rod:
  moment balance). A linear program finds masses within their bounds that make
  the target an equilibrium, with the right sign on every stop moment; when
  none exists, bounded linear least squares gives the best statics fit.
- ``refine``: bounded nonlinear least squares on the joint positions through the
  simulator, in log-masses, with the Jacobian from implicit differentiation of
  the equilibrium (:mod:`optimize.chain.sensitivity`), started from ``exact``. Default.
- ``guided-pso`` and ``pso``: the paper's improved particle swarm and plain PSO
  (:mod:`optimize.chain.pso`), on the same problem, as baselines.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from optimize.chain.model import EquilibriumResult
from optimize.distance import ShapeDistance, shape_distance
from optimize.chain.problem import InverseProblem
from optimize.chain.sensitivity import shape_jacobian
from optimize.chain.statics import exact_masses, statics_matrix, statics_residual

__all__ = ["InverseProblem", "InverseResult", "METHODS", "design", "finish_result", "statics_matrix"]

METHODS = ("exact", "refine", "guided-pso", "pso")


@dataclass
class InverseResult:
    """Outcome of an inverse design.

    Attributes:
        method: the method used.
        masses: (N,) designed masses, within their bounds.
        equilibrium: the designed chain re-simulated from scratch.
        distance: target vs simulated joints (the paper's D~ and D, max, mean, max/span).
        exact: True when the target is an equilibrium of the masses within bounds (round-off).
        statics_residual: relative moment imbalance of the target under these masses.
        at_bounds: (N,) -1 / +1 where a mass sits on its lower / upper bound.
        nfev: simulator calls; time_s: wall time; history: (nfev, seconds, best max/span).
        success, message: outcome in words.
    """

    method: str
    masses: np.ndarray
    equilibrium: EquilibriumResult
    distance: ShapeDistance
    exact: bool
    statics_residual: float
    at_bounds: np.ndarray
    nfev: int
    time_s: float
    success: bool
    message: str
    history: list[tuple[int, float, float]] = field(default_factory=list)
    info: dict = field(default_factory=dict)


def _at_bounds(problem: InverseProblem, m: np.ndarray) -> np.ndarray:
    lo, hi = problem.mass_bounds[:, 0], problem.mass_bounds[:, 1]
    tol = 1e-9 * hi
    return np.where(m <= lo + tol, -1, np.where(m >= hi - tol, 1, 0))


def finish_result(problem, method, masses, t0, nfev, history, statics, extra_msg, info=None):
    """The :class:`InverseResult` of a design: masses clipped to their bounds, re-simulated.

    Args:
        problem: the problem designed for.
        method: the method's name, recorded in the result.
        masses: (N,) designed masses in the caller's mass unit (clipped to the bounds).
        t0: ``time.perf_counter()`` at the start of the design, in seconds.
        nfev: simulator calls so far (the re-simulation here adds one).
        history: (nfev, seconds, best max/span) entries, stored as is.
        statics: the relative statics residual of the target under the masses
            (:func:`optimize.chain.statics.statics_residual`), stored as is.
        extra_msg: how the masses were found, the message's first part.
        info: method-specific details, stored as is (None: empty).

    Returns:
        InverseResult with the re-simulated equilibrium, its distance to the target
        (in the caller's length unit and relative to the span) and the wall time.
    """
    masses = np.clip(masses, problem.mass_bounds[:, 0], problem.mass_bounds[:, 1])
    eq = problem.simulate(masses)
    dist = shape_distance(problem.target, eq.points)
    exact = bool(eq.success and dist.max_rel_span < 1e-9)
    at_b = _at_bounds(problem, masses)
    parts = [extra_msg]
    if exact:
        parts.append("target reached exactly")
    else:
        parts.append(f"best fit: max joint error {dist.max:.4g} ({dist.max_rel_span:.2e} of the span)")
        if np.any(at_b):
            parts.append(f"{int(np.count_nonzero(at_b))} rod mass(es) on a fabrication bound")
    if not eq.success:
        parts.append(f"re-simulation: {eq.message}")
    return InverseResult(
        method=method,
        masses=masses,
        equilibrium=eq,
        distance=dist,
        exact=exact,
        statics_residual=statics,
        at_bounds=at_b,
        nfev=nfev + 1,
        time_s=time.perf_counter() - t0,
        success=bool(eq.success),
        message="; ".join(parts),
        history=history,
        info=info or {},
    )


def _refine(problem: InverseProblem, m0: np.ndarray, t0: float, max_nfev: int,
            max_time: float | None, history: list):
    lo, hi = np.log(problem.mass_bounds[:, 0]), np.log(problem.mass_bounds[:, 1])
    x0 = np.clip(np.log(m0), lo, hi)
    inner = slice(1, problem.n)
    span = problem.span
    state = {"nfev": 0, "best": np.inf, "best_x": x0.copy(), "cache": None}

    class _Budget(Exception):
        pass

    def simulate(x):
        key = x.tobytes()
        if state["cache"] is not None and state["cache"][0] == key:
            return state["cache"][1]
        if max_time is not None and time.perf_counter() - t0 > max_time:
            raise _Budget
        eq = problem.simulate(np.exp(x))
        state["nfev"] += 1
        state["cache"] = (key, eq)
        err = float(np.max(np.hypot(*(eq.points - problem.target).T))) / span
        if eq.success and err < state["best"]:
            state["best"], state["best_x"] = err, x.copy()
        history.append((state["nfev"], time.perf_counter() - t0, state["best"]))
        return eq

    def fun(x):
        eq = simulate(x)
        return ((eq.points[inner] - problem.target[inner]) / span).ravel()

    def jac(x):
        eq = simulate(x)
        J = shape_jacobian(problem.chain(np.exp(x)), eq)[inner]  # (N-1, 2, N)
        return (J * np.exp(x)[None, None, :] / span).reshape(-1, problem.n)

    if lo.size and np.all(hi - lo < 1e-12):
        return np.exp(x0), state["nfev"]
    try:
        least_squares(
            fun, x0, jac=jac, bounds=(lo, np.maximum(hi, lo + 1e-12)), method="trf",
            x_scale=1.0, xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=max_nfev,
        )
    except _Budget:
        pass
    return np.exp(state["best_x"]), state["nfev"]


#: The masses of the linear program are kept as they are when the chain they hang hits its
#: target joints within this fraction of the span.
EXACT_REL = 1e-9


def design(
    problem: InverseProblem,
    method: str = "refine",
    *,
    seed: int | None = 0,
    max_nfev: int = 200,
    max_time: float | None = None,
    n_particles: int = 24,
) -> InverseResult:
    """Choose masses for the problem with the named method.

    Args:
        problem: target, rod geometry and mass bounds.
        method: one of METHODS ("exact", "refine", "guided-pso", "pso").
        seed: random seed (PSO methods); same seed, same result.
        max_nfev: simulator-call budget (refine, PSO).
        max_time: wall-time budget in seconds (refine, PSO); None = no limit.
        n_particles: swarm size (PSO).

    Returns:
        InverseResult, re-simulated from scratch.
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {', '.join(METHODS)}; got {method!r}")
    t0 = time.perf_counter()
    masses, statics, reachable, how = exact_masses(problem)
    history: list[tuple[int, float, float]] = []
    if method == "exact":
        return finish_result(problem, method, masses, t0, 0, history, statics, how,
                              {"reachable": reachable})
    if method == "refine":
        exact_eq = problem.simulate(masses)
        first = shape_distance(problem.target, exact_eq.points)
        history.append((1, time.perf_counter() - t0, first.max_rel_span))
        # a reachable target the linear program balances exactly: its masses hang on the
        # target to the solver's precision (rigid groups on stops: about 1e-12 of the span);
        # refining along the family of exact masses would only pick another member of it
        if exact_eq.success and first.max_rel_span < (EXACT_REL if reachable else 1e-12):
            return finish_result(problem, method, masses, t0, 1, history, statics,
                                  how + "; no refinement needed", {"reachable": reachable})
        refined, nfev = _refine(problem, masses, t0, max_nfev, max_time, history)
        if problem.simulate(refined).success:
            masses = refined
        return finish_result(problem, method, masses, t0, nfev + 1, history,
                              statics_residual(problem, masses),
                              "bounded least squares through the simulator, started from " + how.split(":")[0],
                              {"reachable": reachable})
    # particle swarms: the paper's baseline, on masses within their bounds
    from optimize.chain.pso import pso

    best = {"err": np.inf}

    def evaluate(m):
        eq = problem.simulate(m)
        if not eq.success:
            return 1e6 * problem.span, np.full(2, np.nan)  # never a guide
        d = shape_distance(problem.target, eq.points)
        best["err"] = min(best["err"], d.max_rel_span)
        history.append((len(history) + 1, time.perf_counter() - t0, best["err"]))
        return d.sum, d.deviation

    res = pso(
        evaluate, problem.mass_bounds[:, 0], problem.mass_bounds[:, 1],
        guided=(method == "guided-pso"), n_particles=n_particles, max_evals=max_nfev,
        max_time=max_time, seed=seed,
    )
    hist = history
    return finish_result(problem, method, res.x, t0, res.nfev, hist,
                          statics_residual(problem, res.x), f"{method}: {res.message}")
