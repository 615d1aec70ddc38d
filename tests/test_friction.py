"""The friction band (optimize.chain.friction) against MuJoCo with dry friction at the pins, and
against the linearised model it computes exactly."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize

from mujoco_chain import settle_chain
from optimize import friction_band, friction_capacity, joint_forces, solve_equilibrium
from optimize.chain.endlimits import limit_turn
from test_pinplay import load_example, random_chain


def closed_angles(l, a, b, target):
    """The chord angles nearest ``target`` that close the chain on B (SLSQP)."""
    d = b - a
    cons = [{"type": "eq", "fun": lambda t: np.array([l @ np.cos(t) - d[0], l @ np.sin(t) - d[1]]),
             "jac": lambda t: np.vstack([-l * np.sin(t), l * np.cos(t)])}]
    res = minimize(lambda t: 0.5 * np.sum((t - target) ** 2), target, jac=lambda t: t - target,
                   constraints=cons, method="SLSQP", options={"ftol": 1e-15, "maxiter": 500})
    return res.x


def chord_angles(points):
    d = np.diff(points, axis=0)
    return np.unwrap(np.arctan2(d[:, 1], d[:, 0]))


def starts_beyond_band(fb, base, rng, count):
    """Shapes twice as far out as the band's extreme shapes (each joint's, both signs), then
    random vertices of the friction moments' box pushed out the same way."""
    shapes = []
    for j in np.flatnonzero(fb.per_joint > 0):
        for sign in (1.0, -1.0):
            shapes.append(base + 2.0 * sign * (fb.extreme_shapes[j] - base))
    while len(shapes) < count:
        m = fb.capacity * rng.choice([-1.0, 1.0], size=fb.capacity.size)
        shapes.append(base + 2.0 * np.einsum("jdk,k->jd", fb.response, m))
    return shapes


CHAINS = [("random", ("stops", 1)), ("random", ("ends", 2)), ("random", ("free", 3)),
          ("example", "garland-rise"), pytest.param(("example", "heart"), marks=pytest.mark.slow)]


@pytest.mark.parametrize("case", CHAINS, ids=lambda c: str(c[1]))
def test_mujoco_rests_inside_the_band_and_reaches_its_edge(case):
    """MuJoCo with each pin's dry friction loss equal to mu |F| r of the design (mu 0.3, 1.5 mm
    pins), released from 20+ seeded starts beyond the band, settles (damped, until the
    velocities vanish) inside the band: every joint within its band plus MuJoCo's settling
    tolerance and the linearisation's second-order error; and the furthest rest reaches at
    least 60 % of the band's edge."""
    kind, what = case
    ch = load_example(what) if kind == "example" else random_chain(what[1], what[0])
    kw = dict(com=ch["com"], limits=ch["lim"], end_limits=ch["ends"])
    st = solve_equilibrium(ch["l"], ch["m"], ch["a"], ch["b"], **kw)
    fb = friction_band(ch["l"], ch["m"], ch["a"], ch["b"], mu=0.3, pin_radius=1.5, result=st, **kw)
    size = max(np.ptp(st.points[:, 0]), np.ptp(st.points[:, 1]))
    settle = 1e-6 * size  # MuJoCo's soft closure and limits, friction creep before rest
    second_order = fb.band * fb.band / size  # the linearisation's error, ~ band x (band / size)
    if ch["ends"] is not None:
        # MuJoCo's angles run on along the chain (the last rod's is the sum of the hinge
        # angles): the anchor stops go on the turn the chain is on
        theta = np.unwrap(st.angles)
        ends = ch["ends"].copy()
        for k, t in ((0, theta[0]), (1, theta[-1])):
            ends[k] += limit_turn(t, ends[k])
        kw["end_limits"] = ends
    rng = np.random.default_rng(11)
    reach = np.zeros_like(fb.per_joint)
    rests = 0
    for shape in starts_beyond_band(fb, st.points, rng, 24):
        theta0 = closed_angles(ch["l"], ch["a"], ch["b"], chord_angles(shape))
        out = settle_chain(ch["l"], ch["m"], ch["a"], ch["b"], angles0=theta0, frictionloss=fb.capacity,
                           soft_timeconst=0, max_time=60.0, tol=1e-7, **kw)
        assert out["converged"] and out["end_error"] < settle
        disp = np.linalg.norm(out["points"] - st.points, axis=1)
        assert np.all(disp <= fb.per_joint + second_order + settle), (disp - fb.per_joint).max()
        reach = np.maximum(reach, disp)
        rests += 1
    print(f"{what}: band {fb.band:.3f} mm ({fb.cells} cell(s)), furthest rest {reach.max():.3f} mm "
          f"({100 * reach.max() / fb.band:.0f} %), per joint {np.round(reach[1:-1] / np.maximum(fb.per_joint[1:-1], 1e-300), 2)}")
    assert rests >= 20
    assert reach.max() >= 0.6 * fb.band


def linear_rest(fb_lin, m):
    """Rest shape of the linearised model under friction moments m, by SLSQP on its quadratic
    energy (independent of the band's cells): min f.q + q'Hq/2 - (E m).q over the linearised
    closure and stops. Scaled (angles x 100, energy / max|H|, closure / mean rod length,
    stop rows x 100): unscaled, SLSQP stops 1e-6 rad outside a stop."""
    H, f, C, E, A, b, Aeq, Jp = fb_lin
    w = E @ m
    k, sc, cl = 100.0, float(np.abs(H).max()), float(np.abs(C).max())
    cons = [{"type": "eq", "fun": lambda x: C @ x / (k * cl), "jac": lambda x: C / (k * cl)}]
    if Aeq.shape[0]:
        cons.append({"type": "eq", "fun": lambda x: Aeq @ x, "jac": lambda x: Aeq})
    if A.shape[0]:
        cons.append({"type": "ineq", "fun": lambda x: A @ x - k * b, "jac": lambda x: A})
    res = minimize(lambda x: (f @ x / k + 0.5 * x @ H @ x / k**2 - w @ x / k) / sc, np.zeros(H.shape[0]),
                   jac=lambda x: (f / k + H @ x / k**2 - w / k) / sc, constraints=cons, method="SLSQP",
                   options={"ftol": 1e-16, "maxiter": 1000})
    return np.einsum("jdk,k->jd", Jp, res.x / k)


def linearised(ch, st):
    """The linearised statics written out independently of optimize.chain.friction."""
    l, m, g = ch["l"], ch["m"], 9.81
    theta, n = st.angles, l.size
    after = np.cumsum(m[::-1])[::-1] - m
    sigma = g * (m * ch["com"][:, 1] / l + 1j * (after + m * ch["com"][:, 0] / l))
    z = complex(*st.reaction) - sigma
    e = np.exp(1j * theta)
    f = l * (np.conj(z) * e).imag
    H = np.diag(l * (np.conj(z) * e).real)
    step = 1j * l * e
    C = np.vstack([step.real, step.imag])
    E = np.zeros((n, n + 1))
    E[0, 0], E[n - 1, n] = 1.0, 1.0
    for j in range(1, n):
        E[j, j], E[j - 1, j] = 1.0, -1.0
    rows, rhs = [], []
    phi = np.angle(np.exp(1j * np.diff(theta)))
    for j, (lo, hi) in enumerate(ch["lim"]):
        a = np.zeros(n)
        a[j + 1], a[j] = 1.0, -1.0
        if np.isfinite(lo):
            rows.append(a), rhs.append(min(lo - phi[j], 0.0))
        if np.isfinite(hi):
            rows.append(-a), rhs.append(min(phi[j] - hi, 0.0))
    tri = np.tril(np.ones((n + 1, n)), -1)
    Jp = np.stack([tri * step.real, tri * step.imag], axis=1)
    return H, f, C, E, np.array(rows).reshape(-1, n), np.array(rhs), np.zeros((0, n)), Jp


@pytest.mark.parametrize("case", [("random", ("stops", 1)), ("example", "garland")], ids=str)
def test_band_is_the_linearised_models_extreme(case):
    """Rest shapes of the linearised model at random vertices of the friction moments' box
    (by SLSQP, not by the band's cells) all lie in the band; at the band's own extreme moments
    they reach it."""
    kind, what = case
    ch = load_example(what) if kind == "example" else random_chain(what[1], what[0])
    st = solve_equilibrium(ch["l"], ch["m"], ch["a"], ch["b"], com=ch["com"], limits=ch["lim"])
    fb = friction_band(ch["l"], ch["m"], ch["a"], ch["b"], mu=0.3, pin_radius=1.5, com=ch["com"],
                       limits=ch["lim"], result=st)
    model = linearised(ch, st)
    rng = np.random.default_rng(3)
    tol = 1e-6 * fb.band
    for _ in range(30):
        m = fb.capacity * rng.choice([-1.0, 1.0], size=fb.capacity.size) * rng.uniform(0.5, 1.0)
        disp = np.linalg.norm(linear_rest(model, m), axis=1)
        assert np.all(disp <= fb.per_joint + tol)
    j = int(np.argmax(fb.per_joint))
    at = np.linalg.norm(linear_rest(model, fb.extreme_moments[j]), axis=1)[j]
    assert at == pytest.approx(fb.per_joint[j], rel=1e-5)
    np.testing.assert_allclose(fb.extreme_shapes[j], st.points + linear_rest(model, fb.extreme_moments[j]),
                               atol=1e-5 * fb.band)


def test_zonotope_band_against_every_vertex():
    """One cell: the band of each joint is its largest displacement over all 2^(N+1) vertices
    of the box of friction moments (the image is a zonotope)."""
    ch = random_chain(0, "free")
    fb = friction_band(ch["l"], ch["m"], ch["a"], ch["b"], mu=0.3, pin_radius=1.5, com=ch["com"])
    assert fb.cells == 1
    n1 = fb.capacity.size
    signs = np.array(np.meshgrid(*[[-1.0, 1.0]] * n1)).reshape(n1, -1)
    disp = np.einsum("jdk,kv->jdv", fb.response, fb.capacity[:, None] * signs)
    np.testing.assert_allclose(np.linalg.norm(disp, axis=1).max(axis=1), fb.per_joint, rtol=1e-12,
                               atol=1e-12 * fb.band)
    # linear in the capacities while the box stays in one cell
    fb2 = friction_band(ch["l"], ch["m"], ch["a"], ch["b"], capacity=0.5 * fb.capacity, com=ch["com"])
    np.testing.assert_allclose(fb2.per_joint, 0.5 * fb.per_joint, rtol=1e-12)
    fb0 = friction_band(ch["l"], ch["m"], ch["a"], ch["b"], capacity=0.0, com=ch["com"])
    assert fb0.band == 0.0


def test_capacity_is_mu_force_radius():
    ch = random_chain(2, "stops")
    st = solve_equilibrium(ch["l"], ch["m"], ch["a"], ch["b"], com=ch["com"], limits=ch["lim"])
    tau = friction_capacity(st.reaction, ch["m"], mu=0.25, pin_radius=1.5)
    F = joint_forces(st.reaction, ch["m"])
    np.testing.assert_allclose(tau, 0.25 * 1.5 * np.linalg.norm(F, axis=1), rtol=1e-14)
    # the forces balance each rod's weight: F_{j+1} - F_j = (0, g m_j)
    np.testing.assert_allclose(np.diff(F, axis=0), np.column_stack([0 * ch["m"], 9.81 * ch["m"]]),
                               atol=1e-12 * np.abs(F).max())
    np.testing.assert_allclose(-F[0], st.reaction_a, rtol=1e-12)


@pytest.mark.parametrize("case", CHAINS[:2] + CHAINS[3:4], ids=lambda c: str(c[1]))
def test_band_past_its_work_budget_is_an_upper_bound(case, monkeypatch):
    """With no polygon searches allowed, every cell's joints take the bound of the cell's map
    over the whole box: never below the exact band, and flagged as not tight."""
    import optimize.chain.friction as F

    kind, what = case
    ch = load_example(what) if kind == "example" else random_chain(what[1], what[0])
    st = solve_equilibrium(ch["l"], ch["m"], ch["a"], ch["b"], com=ch["com"], limits=ch["lim"])
    args = dict(mu=0.3, pin_radius=1.5, com=ch["com"], limits=ch["lim"], result=st)
    exact = friction_band(ch["l"], ch["m"], ch["a"], ch["b"], **args)
    monkeypatch.setattr(F, "MAX_POLYGONS", 0)
    bound = friction_band(ch["l"], ch["m"], ch["a"], ch["b"], **args)
    assert np.all(bound.per_joint >= exact.per_joint * (1 - 1e-9))
    assert exact.tight and (bound.tight or exact.cells > 1)  # a zonotope needs no search
    if bound.tight:
        np.testing.assert_allclose(bound.per_joint, exact.per_joint, rtol=1e-9, atol=1e-12)
