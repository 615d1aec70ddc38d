"""Particle swarm minimiser: plain (Kennedy) and the paper's deviation-guided variant."""

from __future__ import annotations

import ast
import time
from pathlib import Path

import numpy as np
import pytest

from optimize.chain.pso import (
    BETTER,
    MESSAGES,
    NEITHER,
    WORSE,
    PSOResult,
    classify_deviations,
    pso,
    select_guides,
)

# ----------------------------------------------------------------------------- helpers


def sphere(center):
    center = np.asarray(center, dtype=float)

    def f(x):
        d = x - center
        return float(d @ d), d[:2].copy() if d.size >= 2 else np.array([d[0], 0.0])

    return f


def rosenbrock(x):
    return float(np.sum(100.0 * (x[1:] - x[:-1] ** 2) ** 2 + (1.0 - x[:-1]) ** 2))


class Recorder:
    """Wrap evaluate() and keep every point it was called with."""

    def __init__(self, f):
        self.f = f
        self.xs: list[np.ndarray] = []

    def __call__(self, x):
        self.xs.append(np.array(x, copy=True))
        return self.f(x)


def linear_chain_toy(n: int, seed: int, n_joints: int = 11):
    """A deviation-aware toy: joints = target + A (x - x*), anchors fixed.

    cost = sum_i |p_T,i - p_S,i| (paper Eq. 4), deviation = sum_i (p_T,i - p_S,i) (Eq. 5);
    the minimum, cost 0, is at x* inside the unit box.
    """
    rng = np.random.default_rng(seed)
    A = 10.0 * rng.normal(size=(2 * n_joints, n))
    A[:2] = 0.0
    A[-2:] = 0.0
    x_star = rng.uniform(0.2, 0.8, n)

    def evaluate(x):
        diff = -(A @ (x - x_star)).reshape(n_joints, 2)  # target - simulated
        return float(np.hypot(diff[:, 0], diff[:, 1]).sum()), diff.sum(axis=0)

    return evaluate, np.zeros(n), np.ones(n), x_star


def evals_to_reach(res: PSOResult, level: float) -> float:
    for nfev, _, best in res.history:
        if best <= level:
            return nfev
    return np.inf


# ----------------------------------------------------------------------------- plain PSO


@pytest.mark.parametrize("n", [2, 4, 6])
def test_finds_shifted_sphere_minimum(n):
    center = np.linspace(-0.6, 0.7, n)
    res = pso(sphere(center), -np.ones(n), np.ones(n), seed=1, max_iter=150)
    assert isinstance(res, PSOResult)
    assert res.success and res.status == 0 and res.message == MESSAGES[0]
    assert res.nit == 150 and res.nfev == 24 * 151
    assert np.max(np.abs(res.x - center)) < 1e-4
    assert res.fun < 1e-8
    assert res.deviation == pytest.approx((res.x - center)[:2])


def test_finds_rosenbrock_minimum_2d():
    res = pso(rosenbrock, [-2.0, -2.0], [2.0, 2.0], seed=0, n_particles=30, max_iter=300)
    assert np.max(np.abs(res.x - 1.0)) < 1e-4 and res.fun < 1e-8


def test_rosenbrock_3d_gets_close():
    res = pso(rosenbrock, -2 * np.ones(3), 2 * np.ones(3), seed=2, n_particles=30, max_iter=400)
    assert res.fun < 1e-2 and np.max(np.abs(res.x - 1.0)) < 0.25


def test_accepts_a_bare_float_cost_in_plain_mode():
    res = pso(lambda x: float(np.sum((x - 0.25) ** 2)), [0, 0], [1, 1], seed=0, max_iter=60)
    assert np.allclose(res.x, 0.25, atol=1e-4)
    assert res.deviation.shape == (2,) and np.all(np.isnan(res.deviation))


@pytest.mark.parametrize("guided", [False, True])
def test_every_evaluated_point_respects_the_bounds(guided):
    lo, hi = np.array([0.0, -1.0, 2.0]), np.array([1.0, 0.5, 2.0])  # last coordinate pinned
    rec = Recorder(sphere([3.0, -5.0, 0.0]))  # minimum outside the box
    res = pso(rec, lo, hi, guided=guided, seed=4, max_iter=80)
    xs = np.array(rec.xs)
    assert len(xs) == res.nfev
    assert np.all(xs >= lo) and np.all(xs <= hi)
    assert np.all(xs[:, 2] == 2.0)
    # the constrained minimum is the nearest box point
    assert res.x == pytest.approx([1.0, -1.0, 2.0], abs=1e-9)


def test_x0_is_the_first_evaluated_point():
    rec = Recorder(sphere([0.1, 0.2]))
    pso(rec, [-1, -1], [1, 1], x0=[0.5, -0.5], seed=0, max_iter=0)
    assert rec.xs[0].tolist() == [0.5, -0.5]


def test_same_seed_is_bit_identical_and_different_seeds_differ():
    ev, lo, hi, _ = linear_chain_toy(4, seed=0)
    for guided in (False, True):
        runs = []
        for seed in (7, 7, np.random.default_rng(7), 8):
            rec = Recorder(ev)
            res = pso(rec, lo, hi, guided=guided, seed=seed, max_iter=30)
            runs.append((res, np.array(rec.xs)))
        (a, xa), (b, xb), (c, xc), (d, xd) = runs
        for other, xo in ((b, xb), (c, xc)):
            assert np.array_equal(xa, xo)
            assert np.array_equal(a.x, other.x) and a.fun == other.fun
            assert np.array_equal(a.deviation, other.deviation)
            assert (a.nit, a.nfev) == (other.nit, other.nfev)
            assert [h[::2] for h in a.history] == [h[::2] for h in other.history]
            assert a.guide_counts == other.guide_counts
        assert xd.shape == xa.shape and not np.array_equal(xa, xd)


def test_history_is_monotone_and_ends_at_nfev():
    ev, lo, hi, _ = linear_chain_toy(3, seed=1)
    res = pso(ev, lo, hi, seed=0, max_iter=25, n_particles=10)
    nf, ts, best = (np.array(c) for c in zip(*res.history))
    assert len(res.history) == res.nit + 1  # initial swarm + every iteration
    assert nf.tolist() == [10 * (k + 1) for k in range(26)]
    assert np.all(np.diff(ts) >= 0) and np.all(np.diff(best) <= 0)
    assert best[-1] == res.fun and nf[-1] == res.nfev
    assert res.time_s >= ts[-1]


# ----------------------------------------------------------------------------- budgets


@pytest.mark.parametrize("guided", [False, True])
@pytest.mark.parametrize("max_evals", [1, 23, 24, 25, 100])
def test_max_evals_is_never_exceeded(guided, max_evals):
    ev, lo, hi, _ = linear_chain_toy(3, seed=2)
    rec = Recorder(ev)
    res = pso(rec, lo, hi, guided=guided, seed=0, max_evals=max_evals, max_iter=1000)
    assert res.nfev == len(rec.xs) == max_evals
    assert res.status == 1 and res.success and res.message == MESSAGES[1]
    assert res.nit == max_evals // 24 - 1 if max_evals >= 24 else res.nit == 0
    assert res.history[-1][0] == max_evals
    assert res.fun == min(ev(x)[0] for x in rec.xs)


def test_max_iter_zero_evaluates_the_initial_swarm_only():
    res = pso(sphere([0, 0]), [-1, -1], [1, 1], n_particles=5, max_iter=0, seed=0)
    assert (res.nit, res.nfev, res.status, res.success) == (0, 5, 0, True)


def test_max_time():
    def slow(x):
        time.sleep(0.002)
        return float(x @ x), x.copy()

    res = pso(slow, [-1, -1], [1, 1], seed=0, max_time=0.05, max_iter=10_000)
    assert res.status == 2 and res.success and res.message == MESSAGES[2]
    assert 1 <= res.nfev < 200
    assert res.time_s < 0.5
    # the first evaluation always happens
    assert pso(slow, [-1, -1], [1, 1], seed=0, max_time=0.0).nfev == 1


def test_ftol_stops_as_soon_as_reached():
    rec = Recorder(lambda x: float(np.sum(x**2)))
    res = pso(rec, [-1, -1], [1, 1], seed=0, ftol=1e-3, max_iter=1000)
    assert res.status == 3 and res.success and res.fun <= 1e-3
    costs = [float(np.sum(x**2)) for x in rec.xs]
    assert costs[-1] <= 1e-3 and min(costs[:-1]) > 1e-3  # it stopped at the first hit


def test_callback_sees_every_iteration_and_can_stop():
    seen = []

    def cb(it, x, f):
        seen.append((it, x.copy(), f))
        return it == 3

    res = pso(sphere([0.2, 0.3]), [-1, -1], [1, 1], seed=0, callback=cb, n_particles=8)
    assert [s[0] for s in seen] == [0, 1, 2, 3]
    assert res.status == 4 and not res.success and res.message == MESSAGES[4]
    assert res.nit == 3 and res.nfev == 8 * 4
    assert seen[-1][2] == res.fun and np.array_equal(seen[-1][1], res.x)


def test_non_finite_costs():
    res = pso(lambda x: (float("nan"), np.zeros(2)), [0, 0], [1, 1], seed=0, max_iter=2)
    assert res.status == 5 and not res.success and res.fun == np.inf
    # NaN in part of the box is avoided, not fatal
    res = pso(lambda x: np.nan if x[0] < 0 else float(np.sum((x - 0.5) ** 2)),
              [-1, -1], [1, 1], seed=0, max_iter=80)
    assert res.success and np.allclose(res.x, 0.5, atol=1e-4)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(lower=[0, 1], upper=[1, 0]), r"lower\[1\] > upper\[1\]"),
        (dict(lower=[0, 0], upper=[1, 1, 1]), "lower has 2 entries but upper has 3"),
        (dict(lower=[0, -np.inf], upper=[1, 1]), r"lower\[1\] is not finite"),
        (dict(x0=[2.0, 0.0]), r"x0\[0\] = 2.0 lies outside \[0.0, 1.0\]"),
        (dict(x0=[0.5]), "x0 has 1 entries but the box has 2"),
        (dict(n_particles=0), "n_particles must be at least 1"),
        (dict(max_iter=-1), "max_iter must be at least 0"),
        (dict(max_evals=0), "max_evals must be at least 1"),
        (dict(max_evals=2.5), "max_evals must be an integer"),
        (dict(max_time=-1.0), "max_time must be non-negative"),
        (dict(c_worse=-1.0), "c_worse must be finite and non-negative"),
        (dict(angle_tol_deg=120.0), r"angle_tol_deg must be in \[0, 90\]"),
    ],
)
def test_bad_arguments(kwargs, match):
    args = dict(lower=[0, 0], upper=[1, 1])
    args.update(kwargs)
    lo, hi = args.pop("lower"), args.pop("upper")
    with pytest.raises(ValueError, match=match):
        pso(sphere([0.5, 0.5]), lo, hi, **args)


def test_guided_needs_a_deviation():
    with pytest.raises(ValueError, match="bare cost"):
        pso(lambda x: float(x @ x), [0, 0], [1, 1], guided=True, max_iter=1)
    with pytest.raises(ValueError, match=r"deviation of shape \(3,\)"):
        pso(lambda x: (float(x @ x), np.zeros(3)), [0, 0], [1, 1], max_iter=1)


# ----------------------------------------------------------------------------- guided PSO


def test_classify_paper_rule():
    d0 = np.array([2.0, 1.0])
    u = d0 / np.linalg.norm(d0)
    rot = lambda deg: np.array(  # noqa: E731
        [[np.cos(np.radians(deg)), -np.sin(np.radians(deg))],
         [np.sin(np.radians(deg)), np.cos(np.radians(deg))]]
    )
    cands = np.array([
        3.0 * d0,             # same direction, longer      -> worse
        0.5 * d0,             # same direction, shorter     -> better
        -0.2 * d0,            # opposite, shorter           -> better
        -5.0 * d0,            # opposite, longer            -> better (the paper's gamma_3)
        rot(90) @ d0,         # perpendicular               -> neither
        rot(20) @ (2 * d0),   # 20 deg off, longer          -> worse (within 30 deg)
        rot(-25) @ (0.3 * d0),  # 25 deg off, shorter       -> better
        rot(40) @ (2 * d0),   # 40 deg off                  -> neither
        rot(165) @ (3 * d0),  # 15 deg from opposite        -> better
        d0.copy(),            # same vector                 -> neither
        [0.0, 0.0],           # zero deviation              -> better
        [np.nan, 1.0],        # unknown                     -> neither
    ])
    expect = [WORSE, BETTER, BETTER, BETTER, NEITHER, WORSE, BETTER, NEITHER, BETTER,
              NEITHER, BETTER, NEITHER]
    assert classify_deviations(d0, cands).tolist() == expect
    # the tolerance is honoured: at 45 degrees the 40-degree candidate counts
    assert classify_deviations(d0, cands[7:8], angle_tol_deg=45.0).tolist() == [WORSE]
    assert classify_deviations(d0, cands[5:6], angle_tol_deg=10.0).tolist() == [NEITHER]
    assert np.allclose(np.linalg.norm(u), 1.0)


def test_classify_without_a_particle_direction_and_vectorised():
    cands = np.array([[1.0, 0.0], [2.0, 0.0], [-1.0, 0.0], [0.0, 0.0]])
    assert classify_deviations([0.0, 0.0], cands).tolist() == [NEITHER] * 4
    assert classify_deviations([np.nan, 0.0], cands).tolist() == [NEITHER] * 4
    table = classify_deviations([[1.5, 0.0], [-1.5, 0.0], [0.0, 0.0]], cands)
    assert table.shape == (3, 4)
    assert table.tolist() == [
        [BETTER, WORSE, BETTER, BETTER],
        [BETTER, BETTER, BETTER, BETTER],
        [NEITHER] * 4,
    ]


def test_select_guides():
    d0 = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 0.0]])
    cand_dev = np.array([
        [3.0, 0.0],   # 0: worse for particle 0 (|D| 3)
        [2.0, 0.1],   # 1: worse for particle 0 (|D| ~2): the mildest worse
        [0.5, 0.0],   # 2: better for particle 0, cost 2
        [-1.0, 0.0],  # 3: better for particle 0 (opposite), cost 1: the cheapest better
        [0.0, 4.0],   # 4: worse for particle 1
        [0.0, 0.2],   # 5: better for particle 1, cost 5
    ])
    cost = np.array([4.0, 3.0, 2.0, 1.0, 6.0, 5.0])
    b, w = select_guides(d0, cand_dev, cost)
    assert b.tolist() == [3, 5, 3] and w.tolist() == [1, 4, 1]
    # exclusion and non-finite costs remove candidates; none left -> -1
    exclude = np.zeros((3, 6), dtype=bool)
    exclude[2, [1, 3]] = True
    cost2 = cost.copy()
    cost2[5] = np.inf
    b, w = select_guides(d0, cand_dev, cost2, exclude=exclude)
    assert b.tolist() == [3, -1, 2] and w.tolist() == [1, 4, 0]
    b, w = select_guides([[0.0, 0.0]], cand_dev, cost)
    assert b.tolist() == [-1] and w.tolist() == [-1]


def test_guided_without_new_terms_is_plain_pso():
    ev, lo, hi, _ = linear_chain_toy(4, seed=3)
    plain = pso(ev, lo, hi, seed=5, max_iter=40)
    same = pso(ev, lo, hi, guided=True, c_better=0.0, c_worse=0.0, seed=5, max_iter=40)
    assert np.array_equal(plain.x, same.x) and plain.fun == same.fun
    assert [h[2] for h in plain.history] == [h[2] for h in same.history]


def test_guided_uses_its_better_and_worse_terms():
    ev, lo, hi, _ = linear_chain_toy(4, seed=3)
    plain = pso(ev, lo, hi, seed=5, max_iter=40)
    guided = pso(ev, lo, hi, guided=True, seed=5, max_iter=40)
    counts = guided.guide_counts
    assert counts["moves"] == 24 * 40
    assert 0 < counts["better"] <= counts["moves"] and 0 < counts["worse"] <= counts["moves"]
    assert plain.guide_counts == {}
    assert [h[2] for h in plain.history][1:] != [h[2] for h in guided.history][1:]
    # only the better term, or only the worse term, gives yet other trajectories
    only_b = pso(ev, lo, hi, guided=True, c_worse=0.0, seed=5, max_iter=40)
    only_w = pso(ev, lo, hi, guided=True, c_better=0.0, seed=5, max_iter=40)
    finals = {plain.fun, guided.fun, only_b.fun, only_w.fun}
    assert len(finals) == 4


@pytest.mark.parametrize("n", [2, 4])
def test_both_modes_converge_on_the_deviation_aware_toy(n):
    """Both modes reach the zero-cost design; the speeds are printed, not asserted."""
    level = 1e-2
    reached = {"plain": [], "guided": [], "guided, no worse term": []}
    for seed in range(6):
        ev, lo, hi, x_star = linear_chain_toy(n, seed=seed)
        for name, kw in (
            ("plain", {}),
            ("guided", dict(guided=True)),
            ("guided, no worse term", dict(guided=True, c_worse=0.0)),
        ):
            res = pso(ev, lo, hi, seed=100 + seed, max_iter=150, **kw)
            assert res.success
            assert res.fun < 0.1, (name, seed, res.fun)
            assert np.max(np.abs(res.x - x_star)) < 1e-2
            reached[name].append(evals_to_reach(res, level))
    summary = {k: float(np.median(v)) for k, v in reached.items()}
    print(f"\nn={n}: median evaluations to cost <= {level}: {summary}")


def test_modules_import_only_numpy_and_stdlib():
    tree = ast.parse(Path(__file__).parents[1].joinpath("optimize", "chain", "pso.py").read_text())
    names = {a.name.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    names |= {n.module.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module}
    assert names <= {"__future__", "math", "time", "dataclasses", "typing", "numpy"}, names
