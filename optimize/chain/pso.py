"""Box-constrained particle swarm minimiser, plain and deviation-guided (paper Sec. 4.2.2).

Song, Feng and Zhou (2017) design a hanging chain by minimising the shape distance
D~ (Eq. 4) over the rod configuration with particle swarm optimisation, and speed it
up with the signed deviation vector D (Eq. 5). :func:`pso` implements both:

* ``guided=False``: standard global-best PSO (Kennedy and Eberhart; the inertia
  weight of Shi and Eberhart), the baseline.
* ``guided=True``: the paper's improved PSO, with two extra guide points per particle
  chosen from the deviation vectors (see :func:`pso` and :func:`classify_deviations`).

Only numpy; never imports rodcad or build123d. ``evaluate`` is called one particle
at a time because in rodcad it is an equilibrium solve.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

__all__ = [
    "MESSAGES",
    "PSOResult",
    "pso",
    "classify_deviations",
    "select_guides",
    "BETTER",
    "WORSE",
    "NEITHER",
]

#: Status codes and their messages (one table, as in scipy.optimize).
MESSAGES = {
    0: "Maximum number of iterations reached (max_iter).",
    1: "Evaluation budget reached (max_evals).",
    2: "Time budget reached (max_time).",
    3: "Best cost reached ftol.",
    4: "Stopped by callback.",
    5: "No evaluation returned a finite cost.",
}
_SUCCESS = {0, 1, 2, 3}

#: Labels returned by :func:`classify_deviations`.
BETTER, NEITHER, WORSE = 1, 0, -1

#: Velocities are clamped to this fraction of the box width per coordinate.
VELOCITY_FRACTION = 0.2


@dataclass
class PSOResult:
    """Outcome of :func:`pso`.

    Attributes:
        x: best position found, shape (n,).
        fun: its cost (``inf`` if no evaluation returned a finite cost).
        deviation: its deviation vector as returned by ``evaluate``, shape (2,)
            (NaN if ``evaluate`` returned a bare cost).
        nit: completed swarm iterations (the initial evaluation of the swarm is
            iteration 0 and is not counted).
        nfev: calls of ``evaluate``.
        time_s: wall time in seconds.
        success, status, message: outcome; ``message == MESSAGES[status]``. A run ended
            by max_iter, max_evals, max_time or ftol is a success; a callback stop or
            no finite cost is not.
        history: ``(nfev, elapsed seconds, best cost so far)`` after the initial swarm,
            after every iteration, and once more at the end if the run stopped part-way
            through an iteration; ``history[-1][0] == nfev``.
        guide_counts: guided mode only: how many particle moves used a "better" and a
            "worse" guide point (``{"better": int, "worse": int, "moves": int}``).
    """

    x: np.ndarray
    fun: float
    deviation: np.ndarray
    nit: int
    nfev: int
    time_s: float
    success: bool
    status: int
    message: str
    history: list[tuple[int, float, float]] = field(default_factory=list)
    guide_counts: dict = field(default_factory=dict)

    def __repr__(self) -> str:  # pragma: no cover - convenience
        return (
            f"PSOResult(fun={self.fun:.6g}, success={self.success}, nit={self.nit}, "
            f"nfev={self.nfev}, time_s={self.time_s:.3g}, message={self.message!r})"
        )


# --------------------------------------------------------------------------- guides


def classify_deviations(d0, candidates, angle_tol_deg: float = 30.0) -> np.ndarray:
    """Label candidate solutions better / worse than a particle by their deviation vectors.

    The paper's rule (Sec. 4.2.2, Fig. 5a), with ``D0 = D(T, Gamma_0)`` the particle's
    deviation and ``Dc`` a candidate's:

    * angle(Dc, D0) about 0 and ``|Dc| > |D0|``: WORSE (moving from it to the particle
      shrank D, so keep going away from it);
    * angle about 0 and ``|Dc| < |D0|``: BETTER;
    * angle about 180 degrees (opposite): BETTER ("the length of D(T, Gamma_0) would
      decrease if gamma_0 moves toward gamma_3");
    * anything else (including ``|Dc| == |D0|`` in the same direction): NEITHER.

    "About" means within ``angle_tol_deg`` (angle < tol, or angle > 180 - tol).
    A candidate with ``Dc == 0`` is BETTER (the limit of "same direction, shorter").
    A particle with ``D0 == 0`` or a non-finite ``D0`` has no direction: every
    candidate is NEITHER. Candidates with a non-finite ``Dc`` are NEITHER.

    Args:
        d0: (2,) or (m, 2) particle deviation vectors.
        candidates: (k, 2) candidate deviation vectors.
        angle_tol_deg: the tolerance in degrees, 0 <= tol <= 90.

    Returns:
        int array of shape (k,) for a single ``d0`` or (m, k), with values
        BETTER (1), NEITHER (0) or WORSE (-1).

    Example:
        >>> classify_deviations([1, 0], [[2, 0], [0.5, 0], [-1, 0.1], [0, 1]]).tolist()
        [-1, 1, 1, 0]
    """
    if not 0.0 <= angle_tol_deg <= 90.0:
        raise ValueError(f"angle_tol_deg must be in [0, 90], got {angle_tol_deg}")
    d0 = np.asarray(d0, dtype=float)
    single = d0.ndim == 1
    d0 = np.atleast_2d(d0)
    dc = np.asarray(candidates, dtype=float).reshape(-1, 2)
    n0 = np.hypot(d0[:, 0], d0[:, 1])[:, None]  # (m, 1)
    nc = np.hypot(dc[:, 0], dc[:, 1])[None, :]  # (1, k)
    with np.errstate(invalid="ignore", divide="ignore"):
        cos = (d0 @ dc.T) / (n0 * nc)
    cos_tol = math.cos(math.radians(angle_tol_deg))
    # angle < tol  <=>  cos > cos(tol); angle > 180 - tol  <=>  cos < -cos(tol)
    same = cos > cos_tol
    opposite = cos < -cos_tol
    out = np.zeros(cos.shape, dtype=int)
    out[same & (nc > n0)] = WORSE
    out[same & (nc < n0)] = BETTER
    out[opposite] = BETTER
    out[np.broadcast_to(nc == 0, out.shape)] = BETTER
    dead = ~(np.isfinite(n0) & (n0 > 0)) | ~np.isfinite(nc)
    out[np.broadcast_to(dead, out.shape)] = NEITHER
    return out[0] if single else out


def select_guides(
    d0,
    cand_dev,
    cand_cost,
    *,
    angle_tol_deg: float = 30.0,
    exclude=None,
) -> tuple[np.ndarray, np.ndarray]:
    """Pick one better and one worse guide point per particle (paper Sec. 4.2.2).

    Among the BETTER candidates (see :func:`classify_deviations`) the one with the
    smallest cost D~ is chosen (ties: the shorter deviation, then the lower index):
    the paper ranks solutions by D~ and uses D only to say which way they lie.
    Among the WORSE candidates the one with the *smallest* ``|D|`` is chosen (ties:
    the lower index), i.e. the worse solution nearest the particle's own deviation.
    Moving away from a worse point ``gamma_w`` with ``D_w = a D_0`` (a > 1) cancels D,
    in a linear model, after a step of ``|gamma_0 - gamma_w| / (a - 1)``; the PSO step
    is ``r |gamma_0 - gamma_w|`` with r in [0, 1), so a large ``a`` (the largest
    ``|D|``) overshoots by far, while ``a`` near 1 undershoots safely. On the test
    problems, picking the largest ``|D|`` stopped the swarm from converging at all.

    Args:
        d0: (m, 2) deviation vectors of the particles.
        cand_dev: (k, 2) deviation vectors of the candidates.
        cand_cost: (k,) their costs D~; a non-finite cost disqualifies a candidate.
        angle_tol_deg: see :func:`classify_deviations`.
        exclude: optional (m, k) bool mask of candidates a particle may not use
            (e.g. ones at its own position, which give no direction).

    Returns:
        (better, worse): (m,) candidate indices, -1 where no candidate qualifies.

    Example:
        >>> b, w = select_guides([[1, 0]], [[3, 0], [2, 0], [0.5, 0], [-1, 0]], [4, 3, 2, 1])
        >>> b.tolist(), w.tolist()
        ([3], [1])
    """
    d0 = np.atleast_2d(np.asarray(d0, dtype=float))
    dc = np.asarray(cand_dev, dtype=float).reshape(-1, 2)
    cost = np.asarray(cand_cost, dtype=float).reshape(-1)
    if cost.size != dc.shape[0]:
        raise ValueError(f"cand_cost has {cost.size} entries but cand_dev has {dc.shape[0]} rows")
    label = classify_deviations(d0, dc, angle_tol_deg).reshape(d0.shape[0], dc.shape[0])
    label[:, ~np.isfinite(cost)] = NEITHER
    if exclude is not None:
        label[np.asarray(exclude, dtype=bool)] = NEITHER
    norm = np.hypot(dc[:, 0], dc[:, 1])
    # lexicographic keys: better by (cost, |D|, index), worse by (|D|, index)
    order_b = np.lexsort((np.arange(cost.size), norm, cost))
    rank_b = np.empty(cost.size, dtype=int)
    rank_b[order_b] = np.arange(cost.size)
    order_w = np.lexsort((np.arange(cost.size), norm))
    rank_w = np.empty(cost.size, dtype=int)
    rank_w[order_w] = np.arange(cost.size)
    big = cost.size + 1
    kb = np.where(label == BETTER, rank_b[None, :], big)
    kw = np.where(label == WORSE, rank_w[None, :], big)
    better = np.where(kb.min(axis=1) < big, order_b[np.minimum(kb.min(axis=1), cost.size - 1)], -1)
    worse = np.where(kw.min(axis=1) < big, order_w[np.minimum(kw.min(axis=1), cost.size - 1)], -1)
    return better, worse


# --------------------------------------------------------------------------- solver


def _as_bounds(lower, upper) -> tuple[np.ndarray, np.ndarray]:
    lo = np.atleast_1d(np.asarray(lower, dtype=float))
    hi = np.atleast_1d(np.asarray(upper, dtype=float))
    if lo.ndim != 1 or hi.ndim != 1:
        raise ValueError(f"lower and upper must be 1-D, got shapes {lo.shape} and {hi.shape}")
    if lo.shape != hi.shape:
        raise ValueError(f"lower has {lo.size} entries but upper has {hi.size}")
    if lo.size == 0:
        raise ValueError("lower and upper must not be empty")
    for name, arr in (("lower", lo), ("upper", hi)):
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            raise ValueError(f"{name}[{bad[0]}] is not finite ({arr[bad[0]]})")
    bad = np.flatnonzero(lo > hi)
    if bad.size:
        j = bad[0]
        raise ValueError(f"lower[{j}] > upper[{j}] ({lo[j]} > {hi[j]})")
    return lo, hi


def _check_count(name: str, value, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be an integer, got {value!r}")
    if value < minimum:
        raise ValueError(f"{name} must be at least {minimum}, got {value}")
    return int(value)


def _check_coef(name: str, value) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not (math.isfinite(v) and v >= 0):
        raise ValueError(f"{name} must be finite and non-negative, got {value!r}")
    return v


def _split(out, guided: bool) -> tuple[float, np.ndarray]:
    """Return (cost, deviation) from what ``evaluate`` returned."""
    if not isinstance(out, (tuple, list)) and np.ndim(out) == 0:
        if guided:
            raise ValueError(
                "evaluate must return (cost, deviation) with deviation of shape (2,) "
                "when guided=True; it returned a bare cost"
            )
        cost, dev = out, np.full(2, np.nan)
    else:
        try:
            cost, dev = out
        except (TypeError, ValueError):
            raise ValueError(
                f"evaluate must return (cost, deviation), got {type(out).__name__}"
            ) from None
        dev = np.asarray(dev, dtype=float)
        if dev.shape != (2,):
            raise ValueError(f"evaluate returned a deviation of shape {dev.shape}, expected (2,)")
    cost = float(cost)
    if math.isnan(cost):
        cost = math.inf
    return cost, dev


def pso(
    evaluate: Callable,
    lower,
    upper,
    *,
    guided: bool = False,
    n_particles: int = 24,
    max_iter: int = 200,
    max_evals: int | None = None,
    max_time: float | None = None,
    x0=None,
    seed: int | np.random.Generator | None = None,
    inertia: float = 0.7,
    c_local: float = 1.5,
    c_global: float = 1.5,
    c_better: float = 1.0,
    c_worse: float = 1.0,
    angle_tol_deg: float = 30.0,
    ftol: float = 0.0,
    callback: Callable | None = None,
) -> PSOResult:
    """Minimise ``evaluate`` over the box [lower, upper] with a particle swarm.

    **Plain PSO** (``guided=False``), global-best topology, synchronous updates. Per
    particle ``i`` and coordinate, with fresh uniform ``r`` in [0, 1)::

        v <- inertia v + c_local r_l (gamma_l - x) + c_global r_g (gamma_g - x)
        v <- clip(v, -vmax, vmax),   vmax = 0.2 (upper - lower)
        x <- clip(x + v, lower, upper)   (a velocity component that hits a wall is zeroed)

    ``gamma_l`` is the particle's personal (local) best, ``gamma_g`` the swarm's best.

    **Guided PSO** (``guided=True``), the paper's improved PSO. The paper says
    (Sec. 4.2.2): "if the angle between D(T, Gamma_1) and D(T, Gamma_0) is
    approximately zero while |D(T, Gamma_1)| > |D(T, Gamma_0)|, we consider gamma_1 as
    a worse solution [...] gamma_2 is a better solution [...] for it has a smaller
    length. When the direction of D(T, Gamma_3) and D(T, Gamma_0) are opposite,
    gamma_3 is also a better solution, since the length of D(T, Gamma_0) would decrease
    if gamma_0 moves toward gamma_3. [...] Finally, one better solution gamma_b and one
    worse solution gamma_w will be selected from all the known particle positions.
    Then, the moving direction of current particle in the next iteration is the
    weighted average of four guide directions {gamma_0 gamma_g, gamma_0 gamma_l,
    gamma_0 gamma_b, gamma_w gamma_0}." Here, per particle::

        pull = c_local r_l (gamma_l - x) + c_global r_g (gamma_g - x)
               + c_better r_b (gamma_b - x) + c_worse r_w (x - gamma_w)
        v <- inertia v + pull (c_local + c_global) / (c_local + c_global + c_better + c_worse)

    followed by the same clamp and clip (a term whose guide point does not exist is
    left out of the sum and of the denominator). Choices where the paper is silent:

    * *Deviation of a particle*: ``D(T, Gamma_0)`` is the deviation ``evaluate``
      returned at the particle's current position (evaluated in the previous
      iteration).
    * *"All the known particle positions"*: the current positions of every particle
      and every personal best, each with the cost and deviation recorded when it was
      evaluated (2 m candidates, no extra evaluations). A particle never uses a
      candidate at its own current position (no direction) or one with a non-finite
      cost or deviation.
    * *"Approximately zero" / "opposite"*: within ``angle_tol_deg`` (30 degrees by
      default) of 0 or of 180 degrees. A candidate with ``D == 0`` counts as better.
      See :func:`classify_deviations`.
    * *Which better and which worse*: the better candidate with the smallest cost D~
      (the paper ranks solutions by D~; D only says which way they lie); the worse
      candidate with the smallest ``|D|`` (the mildest worse point; the largest
      ``|D|`` overshoots, see :func:`select_guides`). When no candidate qualifies,
      that term is dropped for that particle (``guide_counts`` in the result counts
      how often each term was used).
    * *"Weighted average"*: the four guide vectors are weighted by ``c * r`` (random
      per coordinate, as in PSO) and the weights are normalised, as an average
      requires, but to the plain PSO's total ``c_local + c_global`` rather than to 1,
      so that the expected total acceleration, which governs the swarm's stability,
      is the same in both modes. With ``c_better = c_worse = 0`` the update is plain
      PSO exactly (bit for bit: both modes draw the same random numbers). Without
      the normalisation (a plain sum of four terms) the swarm stopped converging on
      the test problems. If ``c_local + c_global == 0`` nothing is normalised.
    * The inertia term is kept: the paper builds on standard PSO, which has it.
    * The better/worse guide points are re-selected every iteration, for every
      particle, from the state before the swarm moves (synchronous update).

    Args:
        evaluate: ``evaluate(x) -> (cost, deviation)``; cost is D~ (Eq. 4), deviation
            the signed vector D (Eq. 5) of shape (2,). Plain PSO ignores the deviation
            and also accepts a bare float. A NaN cost is treated as +inf.
        lower, upper: (n,) finite box bounds, ``lower <= upper`` (equal pins a coordinate).
        guided: use the paper's deviation-guided update.
        n_particles: swarm size m (>= 1).
        max_iter: swarm iterations after the initial evaluation (>= 0); at most
            ``n_particles * (max_iter + 1)`` evaluations.
        max_evals: stop before an evaluation that would make nfev exceed it (>= 1).
            The run may end part-way through an iteration.
        max_time: stop before an evaluation once this many seconds have elapsed.
            The first evaluation always happens. Runs limited by time are not
            reproducible.
        x0: optional (n,) start inside the box; it becomes particle 0.
        seed: int, None or ``np.random.Generator`` (``np.random.default_rng(seed)``).
            Same seed, same result (bit-identical, apart from time_s and the times in
            history), unless max_time cut the run.
        inertia: inertia weight w.
        c_local, c_global: weights of the personal-best and global-best terms.
        c_better, c_worse: guided mode: weights of the toward-better and
            away-from-worse terms.
        angle_tol_deg: guided mode: tolerance of "same direction" / "opposite", degrees.
        ftol: stop as soon as an evaluation returns a cost <= ftol.
        callback: ``callback(iteration, best_x, best_fun)`` after the initial swarm
            (iteration 0) and after every iteration; returning True stops the run
            (status 4).

    Returns:
        PSOResult.

    Raises:
        ValueError: bad arguments (naming the argument), or ``evaluate`` returned
            something other than (cost, deviation of shape (2,)).

    Example:
        >>> r = pso(lambda x: float(np.sum((x - 0.3) ** 2)), [-1, -1], [1, 1], seed=0)
        >>> bool(r.success and np.allclose(r.x, 0.3, atol=1e-4))
        True
    """
    t0 = time.perf_counter()
    lo, hi = _as_bounds(lower, upper)
    n = lo.size
    m = _check_count("n_particles", n_particles, 1)
    max_iter = _check_count("max_iter", max_iter, 0)
    if max_evals is not None:
        max_evals = _check_count("max_evals", max_evals, 1)
    if max_time is not None:
        max_time = float(max_time)
        if not max_time >= 0:
            raise ValueError(f"max_time must be non-negative, got {max_time}")
    w = float(inertia)
    if not math.isfinite(w):
        raise ValueError(f"inertia must be finite, got {inertia!r}")
    c_l = _check_coef("c_local", c_local)
    c_g = _check_coef("c_global", c_global)
    c_b = _check_coef("c_better", c_better)
    c_w = _check_coef("c_worse", c_worse)
    if not 0.0 <= float(angle_tol_deg) <= 90.0:
        raise ValueError(f"angle_tol_deg must be in [0, 90], got {angle_tol_deg}")
    ftol = float(ftol)
    if callback is not None and not callable(callback):
        raise ValueError("callback must be callable")
    rng = np.random.default_rng(seed)

    width = hi - lo
    vmax = VELOCITY_FRACTION * width
    X = rng.uniform(lo, hi, size=(m, n))
    if x0 is not None:
        x0 = np.asarray(x0, dtype=float).reshape(-1)
        if x0.shape != (n,):
            raise ValueError(f"x0 has {x0.size} entries but the box has {n}")
        if not np.all(np.isfinite(x0)):
            raise ValueError(f"x0 must be finite, got {x0.tolist()}")
        bad = np.flatnonzero((x0 < lo) | (x0 > hi))
        if bad.size:
            j = bad[0]
            raise ValueError(f"x0[{j}] = {x0[j]} lies outside [{lo[j]}, {hi[j]}]")
        X[0] = x0
    V = rng.uniform(-1.0, 1.0, size=(m, n)) * vmax

    F = np.full(m, np.inf)  # cost at the current position
    Dv = np.full((m, 2), np.nan)  # deviation at the current position
    P = X.copy()  # personal bests
    PF = np.full(m, np.inf)
    PD = np.full((m, 2), np.nan)
    best = {"i": -1, "x": X[0].copy(), "f": math.inf, "d": np.full(2, np.nan)}
    nfev = 0
    history: list[tuple[int, float, float]] = []
    counts = {"better": 0, "worse": 0, "moves": 0}

    def budget_stop() -> int | None:
        if max_evals is not None and nfev + 1 > max_evals:
            return 1
        if max_time is not None and nfev > 0 and time.perf_counter() - t0 > max_time:
            return 2
        return None

    def evaluate_swarm() -> tuple[int | None, bool]:
        """Evaluate every particle in order.

        Returns (status code if the run must stop else None, whether all m were evaluated).
        """
        nonlocal nfev
        for i in range(m):
            stop = budget_stop()
            if stop is not None:
                return stop, False
            f, d = _split(evaluate(X[i].copy()), guided)
            nfev += 1
            F[i], Dv[i] = f, d
            if f < PF[i]:
                P[i], PF[i], PD[i] = X[i], f, d
                if f < best["f"]:
                    best.update(i=i, x=X[i].copy(), f=f, d=d.copy())
            if best["f"] <= ftol:
                return 3, i == m - 1
        return None, True

    def record() -> bool:
        """Append to history; run the callback; True if it asks to stop."""
        history.append((nfev, time.perf_counter() - t0, best["f"]))
        if callback is None:
            return False
        return bool(callback(nit, best["x"].copy(), best["f"]))

    nit = 0
    status, _ = evaluate_swarm()
    if status is None and record():
        status = 4
    while status is None:
        if nit >= max_iter:
            status = 0
            break
        g = best["x"] if best["i"] >= 0 else X[0]
        # four random arrays in both modes, so guided with c_better = c_worse = 0
        # reproduces plain PSO bit for bit
        r = rng.random((4, m, n))
        pull = c_l * r[0] * (P - X) + c_g * r[1] * (g - X)
        if guided:
            cand_x = np.vstack([X, P])
            cand_f = np.concatenate([F, PF])
            cand_d = np.vstack([Dv, PD])
            same_spot = np.all(cand_x[None, :, :] == X[:, None, :], axis=2)
            b, wst = select_guides(
                Dv, cand_d, cand_f, angle_tol_deg=angle_tol_deg, exclude=same_spot
            )
            has_b, has_w = b >= 0, wst >= 0
            counts["moves"] += m
            counts["better"] += int(has_b.sum())
            counts["worse"] += int(has_w.sum())
            toward_b = np.where(has_b[:, None], cand_x[np.maximum(b, 0)] - X, 0.0)
            away_w = np.where(has_w[:, None], X - cand_x[np.maximum(wst, 0)], 0.0)
            pull = pull + c_b * r[2] * toward_b + c_w * r[3] * away_w
            # weighted average: weights normalised to the plain PSO's total c_l + c_g
            weight = c_l + c_g + c_b * has_b + c_w * has_w
            if c_l + c_g > 0:
                pull = pull * ((c_l + c_g) / weight)[:, None]
        V = w * V + pull
        V = np.clip(V, -vmax, vmax)
        moved = X + V
        X = np.clip(moved, lo, hi)
        V[moved != X] = 0.0
        status, complete = evaluate_swarm()
        if complete:
            nit += 1
        if status is None and record():
            status = 4
    if not history or history[-1][0] != nfev:
        history.append((nfev, time.perf_counter() - t0, best["f"]))

    if best["i"] < 0 or not math.isfinite(best["f"]):
        status = 5
    return PSOResult(
        x=best["x"].copy(),
        fun=float(best["f"]),
        deviation=np.asarray(best["d"], dtype=float).copy(),
        nit=nit,
        nfev=nfev,
        time_s=time.perf_counter() - t0,
        success=status in _SUCCESS,
        status=status,
        message=MESSAGES[status],
        history=history,
        guide_counts=counts if guided else {},
    )
