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
  the equilibrium (:mod:`optimize.sensitivity`), started from ``exact``. Default.
- ``guided-pso`` and ``pso``: the paper's improved particle swarm and plain PSO
  (:mod:`optimize.pso`), on the same problem, as baselines.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares, linprog, lsq_linear

from optimize import _validate as val
from optimize.distance import ShapeDistance, shape_distance
from optimize.equilibrium import Chain, EquilibriumResult, solve_equilibrium
from optimize.sensitivity import shape_jacobian

__all__ = ["InverseProblem", "InverseResult", "METHODS", "design", "statics_matrix"]

METHODS = ("exact", "refine", "guided-pso", "pso")

#: A target bend within this many radians of a limit counts as resting on it.
LIMIT_TOL = 1e-6


@dataclass
class InverseProblem:
    """What the chain must do and what fabrication allows.

    Attributes:
        target: (N+1, 2) target joint positions; target[0] = A and target[-1] = B.
        lengths: (N,) rod lengths (pin to pin); must match the target's chords.
        mass_bounds: (N, 2) achievable [m_min, m_max] per rod.
        com: (N, 2) centres of mass (along, perp) per rod, or None for mid-chord.
        limits: (N-1, 2) bend limits in radians, or None for free joints.
        g: gravitational acceleration.
    """

    target: np.ndarray
    lengths: np.ndarray
    mass_bounds: np.ndarray
    com: np.ndarray | None = None
    limits: np.ndarray | None = None
    g: float = 9.81

    def __post_init__(self) -> None:
        self.lengths = val.as_positive_vector("lengths", self.lengths)
        n = self.lengths.size
        self.target = np.asarray(self.target, dtype=float)
        if self.target.shape != (n + 1, 2) or not np.all(np.isfinite(self.target)):
            raise ValueError(f"target must be a finite ({n + 1}, 2) array of joint positions")
        chords = np.hypot(*np.diff(self.target, axis=0).T)
        bad = np.flatnonzero(np.abs(chords - self.lengths) > 1e-7 * self.lengths)
        if bad.size:
            k = bad[0]
            raise ValueError(
                f"target joints {k} and {k + 1} are {chords[k]:.6g} apart but rod {k} is "
                f"{self.lengths[k]:.6g} long: discretise the target with the rod lengths first"
            )
        bounds = np.asarray(self.mass_bounds, dtype=float)
        if bounds.shape != (n, 2):
            raise ValueError(f"mass_bounds must have shape ({n}, 2), got {bounds.shape}")
        if np.any(~np.isfinite(bounds)) or np.any(bounds[:, 0] <= 0) or np.any(bounds[:, 0] > bounds[:, 1]):
            k = int(np.flatnonzero(~np.isfinite(bounds).all(1) | (bounds[:, 0] <= 0)
                                   | (bounds[:, 0] > bounds[:, 1]))[0])
            raise ValueError(f"mass_bounds[{k}] must satisfy 0 < m_min <= m_max, got {bounds[k].tolist()}")
        self.mass_bounds = bounds
        self.com = val.as_com(self.com, self.lengths)
        self.limits = val.as_limits(self.limits, n)
        self.g = val.as_gravity(self.g)

    @property
    def n(self) -> int:
        return self.lengths.size

    @property
    def anchors(self) -> tuple[np.ndarray, np.ndarray]:
        return self.target[0], self.target[-1]

    @property
    def span(self) -> float:
        return float(np.hypot(*(self.target[-1] - self.target[0])))

    @property
    def angles(self) -> np.ndarray:
        d = np.diff(self.target, axis=0)
        return np.unwrap(np.arctan2(d[:, 1], d[:, 0]))

    def simulate(self, masses, **kw) -> EquilibriumResult:
        a, b = self.anchors
        return solve_equilibrium(
            self.lengths, masses, a, b, com=self.com, limits=self.limits, g=self.g, **kw
        )

    def chain(self, masses) -> Chain:
        a, b = self.anchors
        return Chain.from_args(self.lengths, masses, a, b, self.com, self.limits, self.g)


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


def statics_matrix(problem: InverseProblem):
    """Linear statics at the target: rows = rods, columns = [masses, H, V, stop moments].

    Rod k balances when l_k((H - s_k) sin t_k - (V - c_k) cos t_k) = mu_{k-1} - mu_k with
    s_k = g m_k perp_k / l_k and c_k = g (sum_{i>k} m_i + m_k along_k / l_k).

    Returns:
        (A, stops, signs): A of shape (N, N + 2 + len(stops)); stops are the joints whose
        target bend rests on a limit; signs +1 (lo: moment >= 0), -1 (hi: <= 0), 0 (rigid).
    """
    n, l, g = problem.n, problem.lengths, problem.g
    theta = problem.angles
    phi = np.diff(theta)
    lo, hi = problem.limits[:, 0], problem.limits[:, 1]
    on_hi = np.abs(phi - hi) <= LIMIT_TOL
    on_lo = np.abs(phi - lo) <= LIMIT_TOL
    stops = np.flatnonzero(on_hi | on_lo)
    signs = np.where(on_hi & on_lo, 0, np.where(on_lo, 1, -1))[stops]
    s, c = np.sin(theta), np.cos(theta)
    along, perp = problem.com[:, 0], problem.com[:, 1]
    A = np.zeros((n, n + 2 + stops.size))
    # mass terms: -l_k s_k' sin + l_k c_k' cos, with s_k, c_k linear in the masses
    idx = np.arange(n)
    A[idx, idx] += -g * perp * s + g * along * c
    upper = np.triu(np.ones((n, n)), k=1)  # [i > k]
    A[:, :n] += g * (l * c)[:, None] * upper
    A[:, n] = l * s
    A[:, n + 1] = -l * c
    for col, j in enumerate(stops):
        # f_k = mu_{k-1} - mu_k: moved left, rod j gets +mu_j, rod j+1 gets -mu_j
        A[j, n + 2 + col] += 1.0
        A[j + 1, n + 2 + col] -= 1.0
    return A, stops, signs


def _moment_signs(signs: np.ndarray, lb: np.ndarray, ub: np.ndarray) -> None:
    """Sign bounds on stop moments, in place: >= 0 on a lo stop, <= 0 on a hi stop."""
    lb[signs > 0] = 0.0
    ub[signs < 0] = 0.0


def _scaled(problem: InverseProblem, A: np.ndarray):
    """Row scaling (per rod: l_k g m_ref) and column scaling for conditioning."""
    m_ref = float(np.exp(np.mean(np.log(problem.mass_bounds))))
    row = 1.0 / (problem.lengths * problem.g * m_ref * problem.n)
    col = np.ones(A.shape[1])
    col[: problem.n] = m_ref
    col[problem.n:] = problem.g * m_ref * problem.n
    col[problem.n + 2:] *= float(np.mean(problem.lengths))
    return row, col


def _exact_masses(problem: InverseProblem):
    """Masses from the linear statics: an LP when the target is reachable, else bounded LSQ.

    Returns (masses, relative statics residual, reachable, detail).
    """
    n = problem.n
    A, stops, signs = statics_matrix(problem)
    row, col = _scaled(problem, A)
    As = (A * row[:, None]) * col[None, :]
    lo_m, hi_m = problem.mass_bounds[:, 0], problem.mass_bounds[:, 1]
    nvar = A.shape[1]
    lb = np.full(nvar, -np.inf)
    ub = np.full(nvar, np.inf)
    lb[:n], ub[:n] = lo_m / col[:n], hi_m / col[:n]
    _moment_signs(signs, lb[n + 2:], ub[n + 2:])
    # LP: maximise t, the smallest relative distance of a mass from its bounds
    rng_m = (hi_m - lo_m) / col[:n]
    c = np.zeros(nvar + 1)
    c[-1] = -1.0
    A_eq = np.hstack([As, np.zeros((n, 1))])
    A_ub = np.zeros((2 * n, nvar + 1))
    A_ub[:n, :n] = -np.eye(n)
    A_ub[:n, -1] = rng_m
    A_ub[n:, :n] = np.eye(n)
    A_ub[n:, -1] = rng_m
    b_ub = np.concatenate([-lb[:n], ub[:n]])
    bounds = list(zip(np.where(np.isfinite(lb), lb, None), np.where(np.isfinite(ub), ub, None)))
    bounds.append((0.0, 0.5))
    lp = linprog(c, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=np.zeros(n), bounds=bounds,
                 method="highs")
    if lp.status == 0:
        x = lp.x[:nvar]
        resid = float(np.max(np.abs(As @ x)))
        return x[:n] * col[:n], resid, True, "linear program: target is an equilibrium within bounds"
    # bounded least squares on the statics (scale fixed by m >= m_min > 0)
    ls = lsq_linear(As, np.zeros(n), bounds=(lb, ub), method="bvls", lsmr_tol="auto")
    x = ls.x
    resid = float(np.max(np.abs(As @ x)))
    return x[:n] * col[:n], resid, False, "bounded least squares on the statics (not reachable)"


def _at_bounds(problem: InverseProblem, m: np.ndarray) -> np.ndarray:
    lo, hi = problem.mass_bounds[:, 0], problem.mass_bounds[:, 1]
    tol = 1e-9 * hi
    return np.where(m <= lo + tol, -1, np.where(m >= hi - tol, 1, 0))


def _finish(problem, method, masses, t0, nfev, history, statics, extra_msg, info=None):
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


def _statics_residual(problem: InverseProblem, masses: np.ndarray) -> float:
    """Relative statics residual of the target for these masses (best reaction and moments)."""
    n = problem.n
    A, stops, signs = statics_matrix(problem)
    row, col = _scaled(problem, A)
    As = (A * row[:, None]) * col[None, :]
    rest = As[:, n:]
    rhs = -As[:, :n] @ (masses / col[:n])
    lb = np.full(rest.shape[1], -np.inf)
    ub = np.full(rest.shape[1], np.inf)
    _moment_signs(signs, lb[2:], ub[2:])
    sol = lsq_linear(rest, rhs, bounds=(lb, ub))
    return float(np.max(np.abs(rest @ sol.x - rhs)))


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
    masses, statics, reachable, how = _exact_masses(problem)
    history: list[tuple[int, float, float]] = []
    if method == "exact":
        return _finish(problem, method, masses, t0, 0, history, statics, how,
                       {"reachable": reachable})
    if method == "refine":
        exact_eq = problem.simulate(masses)
        first = shape_distance(problem.target, exact_eq.points)
        history.append((1, time.perf_counter() - t0, first.max_rel_span))
        if exact_eq.success and first.max_rel_span < 1e-12:
            return _finish(problem, method, masses, t0, 1, history, statics,
                           how + "; no refinement needed", {"reachable": reachable})
        refined, nfev = _refine(problem, masses, t0, max_nfev, max_time, history)
        if problem.simulate(refined).success:
            masses = refined
        return _finish(problem, method, masses, t0, nfev + 1, history,
                       _statics_residual(problem, masses),
                       "bounded least squares through the simulator, started from " + how.split(":")[0],
                       {"reachable": reachable})
    # particle swarms: the paper's baseline, on masses within their bounds
    from optimize.pso import pso

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
    return _finish(problem, method, res.x, t0, res.nfev, hist,
                   _statics_residual(problem, res.x), f"{method}: {res.message}")
