"""Inverse statics of nets: masses recovered from shapes the nets really hang in.

Truth: a random net hung from random masses within bounds hangs in a shape; given that
shape as the target, the statics must find masses (maybe others: a net's masses for a
shape are a family) with which the exact solver reproduces it to round-off. A target the
bounds cannot reach must come back as the best fit, with the rods that would have to
leave their bounds named.
"""

from __future__ import annotations

import numpy as np
import pytest
from netgen import random_grid, random_masses
from scipy.optimize import minimize

from optimize import design_net, design_net_masses, net_statics, shape_jacobian, solve_net
from optimize.boxqp import box_qp
from optimize.net.model import Net


def _hung(seed, anchored="corners", node_mass=0.5, **kw):
    spec = random_grid(seed, anchored=anchored, **kw)
    m = random_masses(spec, seed, lo=1.0, hi=4.0)
    nm = np.random.default_rng(seed).uniform(0, node_mass, spec.n)
    res = solve_net(spec.positions, spec.edges, spec.lengths, m, spec.anchored, node_masses=nm)
    assert res.success and res.stable
    return spec, m, nm, res


@pytest.mark.parametrize("seed,anchored", [(0, "corners"), (1, "boundary"), (2, "corners"), (3, "boundary"),
                                           (4, "corners"), (6, "corners")])
def test_masses_of_a_hung_net_are_recovered_exactly(seed, anchored):
    spec, m, nm, res = _hung(seed, anchored)
    target = res.positions
    push = res.compressed.size > 0  # some random nets rest with rods that push
    d = design_net_masses(target, spec.edges, spec.lengths, (1.0, 4.0), spec.anchored, node_masses=nm,
                          allow_compression=push)
    assert d.exact and d.residual < 1e-12
    assert np.all(d.masses >= 1.0) and np.all(d.masses <= 4.0)
    if not push:
        assert np.all(d.tensions > 0)
    # the statics say the target balances: the solver, started there, stays
    chk = solve_net(target, spec.edges, spec.lengths, d.masses, spec.anchored, node_masses=nm)
    assert chk.success and chk.kkt_residual < 1e-10
    assert np.max(np.abs(chk.positions - target)) < 1e-6 * spec.size


def test_the_design_keeps_masses_central_and_rods_in_tension():
    spec, m, nm, res = _hung(2)
    d = design_net_masses(res.positions, spec.edges, spec.lengths, (1.0, 4.0), spec.anchored, node_masses=nm)
    assert d.exact and d.margin > 0
    assert np.min(np.minimum(d.masses - 1.0, 4.0 - d.masses)) >= d.margin * 3.0 * (1 - 2e-3)
    # every rod in tension: with point nodes that makes the equilibrium stable
    assert np.all(d.tensions > 0) and d.compressed.size == 0
    full = design_net(res.positions, spec.edges, spec.lengths, (1.0, 4.0), spec.anchored, node_masses=nm,
                      n_starts=4, seed=1)
    assert full.on_target and full.equilibrium.stable and full.rel_error < 1e-9


def test_statics_agree_with_the_solver_at_an_equilibrium():
    # A_T T + A_m m = b holds at every equilibrium with its own tensions and masses
    spec, m, nm, res = _hung(5)
    st = net_statics(res.positions, spec.edges, spec.lengths, spec.anchored, node_masses=nm)
    scale = max(9.81 * (m.sum() + nm.sum()), np.abs(res.tensions).max())
    assert np.max(np.abs(st.residual(res.tensions, m))) < 1e-10 * scale


def test_statics_of_node_bodies_agree_with_the_solver():
    from test_net import _ring_net

    spec, lengths, m, kw = _ring_net()
    res = solve_net(spec.positions, spec.edges, lengths, m, spec.anchored, **kw)
    st = net_statics(res.positions, spec.edges, lengths, spec.anchored, rotations=res.rotations, **kw)
    assert st.A_T.shape[0] == 6 * (spec.n - spec.anchored.size)  # force and moment rows
    scale = 9.81 * (m.sum() + kw["node_masses"].sum())
    assert np.max(np.abs(st.residual(res.tensions, m))) < 1e-10 * scale * spec.size
    d = design_net_masses(res.positions, spec.edges, lengths, (0.5, 5.0), spec.anchored, rotations=res.rotations,
                          allow_compression=True, **kw)
    assert d.exact
    chk = solve_net(res.positions, spec.edges, lengths, d.masses, spec.anchored, node_rotations0=res.rotations, **kw)
    assert chk.success and np.max(np.abs(chk.positions - res.positions)) < 1e-6 * spec.size


@pytest.mark.parametrize("seed", [0, 2])
def test_a_target_the_bounds_cannot_reach_gets_the_best_fit_and_why(seed):
    spec, m, nm, res = _hung(seed, node_mass=0.0)
    narrow = (2.4, 2.6)  # the net's masses span 1..4: no masses this narrow balance it
    d = design_net_masses(res.positions, spec.edges, spec.lengths, narrow, spec.anchored)
    assert not d.exact and d.residual > 1e-4
    assert np.all(d.masses >= narrow[0]) and np.all(d.masses <= narrow[1])
    assert d.at_lower.size + d.at_upper.size > 0
    assert np.any(d.beyond != 0) and "Not exact" in d.message
    # masses within the narrow bounds that the 'why' program would have to move beyond them
    over, under = np.flatnonzero(d.beyond > 0), np.flatnonzero(d.beyond < 0)
    assert str(int((over if over.size else under)[0])) in d.message
    # the best fit does not balance: fed to the solver the net hangs elsewhere
    full = design_net(res.positions, spec.edges, spec.lengths, narrow, spec.anchored, n_starts=1, max_refine=10)
    assert not full.on_target and full.rel_error > 1e-4
    plain = solve_net(res.positions, spec.edges, spec.lengths, d.masses, spec.anchored)
    err_plain = np.max(np.linalg.norm(plain.positions - res.positions, axis=1))
    assert full.error <= err_plain * (1 + 1e-9)  # the refinement does not make it worse


def test_shape_jacobian_matches_finite_differences():
    spec, m, nm, res = _hung(2, max_cells=4)
    net, st = Net.from_args(res.positions, spec.edges, spec.lengths, m, spec.anchored, node_masses=nm)
    J = shape_jacobian(net, st, res.tensions)
    h = 1e-5
    for e in (0, spec.m // 2, spec.m - 1):
        mp, mm = m.copy(), m.copy()
        mp[e] += h
        mm[e] -= h
        rp = solve_net(res.positions, spec.edges, spec.lengths, mp, spec.anchored, node_masses=nm)
        rm = solve_net(res.positions, spec.edges, spec.lengths, mm, spec.anchored, node_masses=nm)
        fd = (rp.positions - rm.positions) / (2 * h)
        assert np.max(np.abs(fd - J[:, :, e])) < 1e-5 * max(np.abs(J).max(), 1e-300)


@pytest.mark.parametrize("seed", range(4))
def test_box_qp_matches_slsqp(seed):
    rng = np.random.default_rng(seed)
    n, k = 30, 12
    A = rng.normal(size=(k, n))
    b = A @ rng.uniform(0.2, 0.8, n)
    q, c = rng.uniform(0.5, 2, n), rng.normal(size=n)
    lo, hi = np.zeros(n), np.ones(n)
    lo[:5] = -np.inf
    r = box_qp(q, c, A, b, lo, hi)
    ref = minimize(lambda x: 0.5 * x @ (q * x) + c @ x, np.full(n, 0.5), jac=lambda x: q * x + c, method="SLSQP",
                   constraints=[{"type": "eq", "fun": lambda x: A @ x - b, "jac": lambda x: A}],
                   bounds=list(zip(np.where(np.isfinite(lo), lo, None), hi)), options={"ftol": 1e-14, "maxiter": 500})
    assert r.success and r.residual < 1e-12
    assert np.all(r.x >= lo) and np.all(r.x <= hi)
    f = 0.5 * r.x @ (q * r.x) + c @ r.x
    assert f <= ref.fun + 1e-7 * (1 + abs(ref.fun))
