"""A net of a few hundred rods designed on the paths the big nets take, checked independently.

A 13 x 13 grid (312 rods: past :data:`optimize.net.lp.LP_SIMPLEX_RODS`, so its linear
programs run HiGHS's interior point) hung from its border into a paraboloid is designed
(:func:`optimize.design_net`), and the design is checked without the project's statics or
solver: every free node's force balance at the target recomputed in plain numpy from the
designed masses and tensions, and MuJoCo (``mujoco_net``, no project code) released from
another shape of the same rods, resting where the solver says the designed net hangs.
"""

from __future__ import annotations

import mujoco_net
import numpy as np
from netgen import grid_net

import optimize.net.solve as solve_mod
from optimize import design_net, solve_net
from optimize.net.lp import LP_SIMPLEX_RODS

G = 9.81


def _dome(u: int = 13, cell: float = 40.0):
    w = u * cell
    return grid_net(u, u, x=(0, w), y=(0, w), z=lambda x, y: 0.0015 * ((x - w / 2) ** 2 + (y - w / 2) ** 2) - 0.25 * w,
                    anchored="boundary", boundary_rods=False)


def _imbalance(x, edges, masses, tensions, node_masses, anchored) -> float:
    """Largest free node's force imbalance over the force scale, in plain numpy: rod e pulls
    node i toward node j with T_e and hangs half its weight on each end."""
    u = x[edges[:, 1]] - x[edges[:, 0]]
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    f = np.zeros_like(x)
    np.add.at(f, edges[:, 0], tensions[:, None] * u)
    np.add.at(f, edges[:, 1], -tensions[:, None] * u)
    np.add.at(f[:, 2], edges[:, 0], -0.5 * G * masses)
    np.add.at(f[:, 2], edges[:, 1], -0.5 * G * masses)
    f[:, 2] -= G * node_masses
    free = np.ones(len(x), bool)
    free[anchored] = False
    scale = max(float(np.abs(tensions).max()), G * float(masses.sum() + node_masses.sum()))
    return float(np.max(np.linalg.norm(f[free], axis=1)) / scale)


def test_a_312_rod_design_balances_and_hangs_where_mujoco_rests():
    spec = _dome()
    assert spec.edges.shape[0] > LP_SIMPLEX_RODS
    nm = np.full(spec.n, 0.5)
    d = design_net(spec.positions, spec.edges, spec.lengths, (0.8, 4.5), spec.anchored, node_masses=nm, n_starts=2)
    st = d.statics
    assert st.exact and d.on_target, d.message
    assert np.all(d.masses >= 0.8 - 1e-12) and np.all(d.masses <= 4.5 + 1e-12)
    assert np.all(st.tensions >= -1e-9 * np.abs(st.tensions).max())
    # the statics' balance at the target, recomputed independently: exact to round-off
    assert _imbalance(spec.positions, spec.edges, d.masses, st.tensions, nm, spec.anchored) < 1e-12
    # ... and the solver's equilibrium with its own tensions
    eq = d.equilibrium
    assert eq.success and eq.stable and eq.kkt_residual < 1e-10
    assert _imbalance(eq.positions, spec.edges, d.masses, eq.tensions, nm, spec.anchored) < 1e-10
    # MuJoCo from the equilibrium of the same rods with masses changed by up to 30 %
    rng = np.random.default_rng(13)
    start = solve_net(spec.positions, spec.edges, spec.lengths, d.masses * rng.uniform(0.7, 1.3, d.masses.size),
                      spec.anchored, node_masses=nm)
    assert start.success
    # a step of 2 ms: MuJoCo's soft constraints (time constant two steps) then rest about 4e-7 of
    # the size off the rigid net's rest (it goes as the step squared: 1e-7 at 1 ms, measured), well
    # inside what is asserted, in half the steps (each a factorization of the 312 rods' loops)
    sim = mujoco_net.settle_net(start.positions, spec.edges, spec.lengths, d.masses, spec.anchored, node_masses=nm,
                                timestep=2e-3)
    assert sim["converged"] and sim["closure_error"] < 1e-6 * spec.size
    err = float(np.max(np.linalg.norm(sim["positions"] - eq.positions, axis=1)))
    moved = float(np.max(np.linalg.norm(start.positions - eq.positions, axis=1)))
    assert err < 1e-5 * spec.size, f"MuJoCo rests {err / spec.size:.2e} of the size from the solver"
    assert moved > 100 * err  # it really travelled


def test_a_big_nets_linear_programs_without_presolve_where_the_presolved_ones_stop(monkeypatch):
    """Past LP_SIMPLEX_RODS the statics' linear programs run HiGHS's interior point presolved
    and, where that has not ended optimal or infeasible within LP_PRESOLVED_ITERATIONS, again
    without presolve: forced to fall back at once (a limit of one iteration), the 312-rod
    dome's masses are the same as presolved (the margin program's optimum is unique, the
    central masses the strictly convex program's), and an infeasible one says so either way."""
    import optimize.net.lp as lp_mod
    import optimize.net.statics as statics

    spec = _dome()
    nm = np.full(spec.n, 0.5)
    asked = []
    real = lp_mod.linprog

    def recorded(c, **kw):
        lp = real(c, **kw)
        asked.append((kw.get("options", {}).get("presolve", True), lp.status))
        return lp

    monkeypatch.setattr(lp_mod, "linprog", recorded)

    def design(positions):
        return statics.design_net_masses(positions, spec.edges, spec.lengths, (0.8, 4.5), spec.anchored,
                                         node_masses=nm)

    presolved = design(spec.positions)
    assert presolved.exact and asked and all(p and s == 0 for p, s in asked)
    monkeypatch.setattr(lp_mod, "LP_PRESOLVED_ITERATIONS", 1)
    asked.clear()
    fallen = design(spec.positions)
    assert fallen.exact and [p for p, _ in asked] == [True, False] and asked[0][1] == 1
    np.testing.assert_allclose(fallen.masses, presolved.masses, rtol=0, atol=1e-6 * 4.5)
    np.testing.assert_allclose(fallen.tensions, presolved.tensions, rtol=0, atol=1e-6 * np.abs(presolved.tensions).max())
    # the same rods standing as a dome would push: no masses hang it, presolved or not
    for limit in (100, 1):
        monkeypatch.setattr(lp_mod, "LP_PRESOLVED_ITERATIONS", limit)
        asked.clear()
        assert not design(spec.positions * [1.0, 1.0, -1.0]).exact
        assert asked[0] == (True, 2) or (limit == 1 and asked[:2] == [(True, 1), (False, 2)]), asked


def test_big_nets_limited_perturbed_starts_find_the_same_shape(monkeypatch):
    """The iteration limits a big net's perturbed starts get (here forced on a small net) still
    bring a start back to the designed shape, and a start they stop is reported, not hidden."""
    spec = _dome(6)
    nm = np.full(spec.n, 0.5)
    d = design_net(spec.positions, spec.edges, spec.lengths, (0.8, 4.5), spec.anchored, node_masses=nm, n_starts=1)
    full = solve_net(spec.positions, spec.edges, spec.lengths, d.masses, spec.anchored, node_masses=nm, n_starts=4)
    monkeypatch.setattr(solve_mod, "PERTURBED_NVAR", 0)
    limited = solve_net(spec.positions, spec.edges, spec.lengths, d.masses, spec.anchored, node_masses=nm, n_starts=4)
    assert limited.success and limited.stable
    assert np.max(np.abs(limited.positions - full.positions)) < 1e-9 * spec.size
    assert sum(limited.counts) <= 4
    monkeypatch.setattr(solve_mod, "PERTURBED_ITER", 0)  # no Newton step at all: every perturbed start is lost
    stopped = solve_net(spec.positions, spec.edges, spec.lengths, d.masses, spec.anchored, node_masses=nm, n_starts=3)
    assert stopped.counts == [1] and "2 of the multi-start's 2 perturbed start(s) found no equilibrium" in stopped.message


def test_a_big_nets_tensile_tensions_come_from_the_sparse_program(monkeypatch):
    """The sector whose least-squares tensions push (test_net_mujoco): its tensions that pull in
    every rod found by the sparse linear program a big net gets (forced here) hold the same
    equilibrium, are stable there, and match the dense search's verdict."""
    from test_net_mujoco import SECTOR

    from optimize.net.deriv import evaluate
    from optimize.net.model import Net
    from optimize.net.newton import is_stable, kkt_residual, multipliers
    from rodcad.design.loader import load_design
    from rodcad.design.net.check import design_net_plan
    from rodcad.design.net.plan import plan_net

    d = load_design("sector.yaml", text=SECTOR)
    c = design_net_plan(plan_net(d.net, d.catalog), seed=0)
    p, t, eq = c.plan, c.plan.target, c.equilibrium
    net, st = Net.from_args(eq.positions, t.edges, p.lengths, c.masses, t.anchored, node_rotations0=eq.rotations,
                            node_masses=p.node_masses, node_com=p.node_com, pivots=p.pivots)
    ev = evaluate(net, st)
    least = multipliers(net, ev)
    assert least.min() < -1e-3 * least.max() and not is_stable(net, st, ev, least)
    dense = solve_mod.tensile_multipliers(net, ev, least)
    monkeypatch.setattr(solve_mod, "SELF_STRESS_NVAR", 0)
    sparse = solve_mod.tensile_multipliers(net, ev, least)
    assert dense is not None and sparse is not None
    assert np.all(sparse >= 0) and kkt_residual(net, ev, sparse)[0] < 1e-10
    assert is_stable(net, st, ev, sparse)
