"""Unstable equilibria: reported as such from a design's target, left for a stable one otherwise.

Truth: closed forms. A chain of rods standing straight up from its anchor is an equilibrium (every
rod's weight along its neighbours) and an unstable one, with two equal negative curvatures (it
may tip toward x or y): the case ARPACK's shift-invert could not separate. Hanging straight down
is its only stable equilibrium, node k at -k L below the anchor.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import optimize.net.newton as newton
from optimize import solve_net

L = 30.0


def _upright(n: int):
    pts = np.array([[0.0, 0.0, k * L] for k in range(n + 1)])
    edges = np.column_stack([np.arange(n), np.arange(1, n + 1)])
    return pts, edges, np.full(n, L), np.linspace(1.0, 2.0, n)


def _hangs_down(res, n: int) -> None:
    want = np.array([[0.0, 0.0, -k * L] for k in range(n + 1)])
    assert res.success and res.stable and res.escapes >= 1
    # (converged: KKT residual below 1e-10 of the weight, so the nodes sit within far less than a
    # millionth of a rod's length of the closed form; a tipped chain would be off by tens of mm)
    np.testing.assert_allclose(res.positions, want, atol=1e-6 * L)


@pytest.mark.parametrize("n", [1, 3])
def test_an_upright_chain_is_an_unstable_equilibrium_the_check_reports_and_the_solver_leaves(n):
    pts, edges, lengths, masses = _upright(n)
    kept = solve_net(pts, edges, lengths, masses, [0], leave_unstable=False)
    assert kept.success and not kept.stable and kept.escapes == 0
    np.testing.assert_allclose(kept.positions, pts, atol=1e-9 * L)
    assert "not stable" in kept.message
    fallen = solve_net(pts, edges, lengths, masses, [0])  # (the default: where the net falls to)
    _hangs_down(fallen, n)
    assert fallen.energy < kept.energy


def test_the_sparse_eigensolver_and_its_fallback_leave_the_saddle_the_same_way(monkeypatch):
    """Nets above DENSE_EIG_NVAR unknowns take ARPACK's direction, or where ARPACK fails, one read
    from the factorization's most negative pivot: each leaves the saddle for the hanging chain."""
    n = 4
    pts, edges, lengths, masses = _upright(n)
    monkeypatch.setattr(newton, "DENSE_EIG_NVAR", 0)
    _hangs_down(solve_net(pts, edges, lengths, masses, [0]), n)

    def failing(*args, **kwargs):
        raise RuntimeError("ARPACK did not converge")

    monkeypatch.setattr("scipy.sparse.linalg.eigsh", failing)
    _hangs_down(solve_net(pts, edges, lengths, masses, [0]), n)


def test_the_pivot_direction_has_negative_curvature():
    """v'Kv = d_k < 0 for the LDL^T's most negative pivot d_k; None for a definite K."""
    rng = np.random.default_rng(3)
    indefinite = 0
    for seed in range(6):
        A = sp.random(80, 80, density=0.05, random_state=seed)
        K = (A + A.T + sp.diags(rng.uniform(0.5, 2.0, 80))).tocsc()
        K = K - sp.diags(np.where(np.arange(80) == seed * 7, 4.0, 0.0))
        lowest = np.linalg.eigvalsh(K.toarray())[0]
        v = newton._pivot_direction(K)
        if lowest < 0:
            indefinite += 1
            assert v is not None and np.isclose(np.linalg.norm(v), 1.0) and v @ (K @ v) < 0
    assert indefinite >= 3
    definite = (sp.diags(rng.uniform(1.0, 2.0, 30)) + 0.1 * sp.eye(30, k=1) + 0.1 * sp.eye(30, k=-1)).tocsc()
    assert newton._pivot_direction(definite) is None


@pytest.fixture(scope="module")
def arch():
    """An arch of four rods drawn to push (``compression: true``) between two anchors: its
    target is an equilibrium of the designed net, but a ball-jointed arch is a mechanism that
    folds down. No hardware mends that, so the check reports it and where the net falls."""
    from rodcad.catalog.loader import load_catalog
    from rodcad.design.net.choose import design_drawn_net
    from rodcad.design.net.target import NetTarget

    pts = np.array([[0.0, 0, 0], [40, 0, 35], [90, 0, 50], [140, 0, 35], [180, 0, 0]])
    t = NetTarget("nodes", pts, np.column_stack([np.arange(4), np.arange(1, 5)]), np.array([0, 4]),
                  compression=True)
    return design_drawn_net(t, load_catalog("pla-parametric"), seed=0)


def test_an_arch_that_can_only_fall_is_reported_with_where_it_falls(arch):
    eq = arch.equilibrium
    assert eq.success and not eq.stable and not arch.ok and arch.rel_size < 1e-9  # (on the target, unstable)
    assert arch.falls_to is not None and arch.falls_to > 0.2  # (folded below its anchors)
    said = arch.limit()
    assert "not a stable one" in said and "falls to a stable shape" in said


def test_the_fall_from_a_flat_saddle_is_followed_to_a_rest_mujoco_keeps(arch):
    """The arch's hubs of two rods, balanced for the push, hang upside down once it has folded:
    a curvature so flat (their centres of mass a hair off their spin axes) that the proximal
    steps crept (KKT residual 6e-8 after 600 iterations). The descent leaves such a creep along
    the negative curvature and comes to rest; MuJoCo, started there, stays."""
    import mujoco_net

    res = solve_net(**arch.solved_with)
    assert res.success and res.stable and res.escapes >= 1 and res.nit < 200
    plan = arch.plan
    sim = mujoco_net.settle_net(res.positions, plan.target.edges, plan.lengths, arch.masses, plan.target.anchored,
                                node_masses=plan.node_masses, node_com=plan.node_com, pivots=plan.pivots,
                                rotations0=res.rotations, com=arch.solved_with["com"])
    assert sim["converged"]
    # (MuJoCo's soft constraints rest ~1e-8 of the size off; a thousandth of the size is far tighter than
    # the fold it would show if the rest were not stable)
    assert np.max(np.linalg.norm(sim["positions"] - res.positions, axis=1)) < 1e-3 * plan.target.size



def test_the_arch_build_says_where_it_falls_in_its_line_design_json_and_report(tmp_path, capsys):
    import json

    from rodcad.cli import main

    path = tmp_path / "arch.yaml"
    path.write_text("design: 1\nname: arch\nnet:\n  nodes: [[0, 0, 0], [40, 0, 35], [90, 0, 50], [140, 0, 35], "
                    "[180, 0, 0]]\n  edges: [[0, 1], [1, 2], [2, 3], [3, 4]]\n  anchored: [0, 4]\n"
                    "  compression: true\n")
    assert main(["build", str(path), "--no-cad", "-q", "-o", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err
    assert "but not a stable one (from it the net falls to a stable shape" in err
    best = tmp_path / "out.best-fit"
    net = json.loads((best / "design.json").read_text())["net"]
    assert not net["stable"] and net["falls_to_rel_size"] > 0.2
    assert "falls to a stable shape" in (best / "report.md").read_text().splitlines()[2]
