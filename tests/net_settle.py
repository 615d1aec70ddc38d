"""MuJoCo's rest of a designed net against rodcad's equilibrium (tests/mujoco_net.py is the
independent engine; this helper starts it from another shape of the same rods, which rodcad's
solver gives)."""

from __future__ import annotations

import mujoco_net
import numpy as np

from optimize import solve_net

__all__ = ["settle_from_other_masses"]


def settle_from_other_masses(check, seed: int, *, turn_rods: bool = False) -> tuple[float, float]:
    """The designed net hung with its masses changed by up to 30 % (rodcad's solver), then
    released in MuJoCo with the designed masses (``turn_rods``: each rod rolled about its axis
    at random, which a rod on ball joints may): (how far MuJoCo rests from rodcad's
    equilibrium, how far the start was from it), both in mm (max over nodes). Asserts that
    MuJoCo converged with its closures held to 1e-6 of the size."""
    plan, t, eq = check.plan, check.plan.target, check.equilibrium
    kw = dict(node_masses=plan.node_masses, node_com=plan.node_com, pivots=plan.pivots)
    rng = np.random.default_rng(seed)
    start = solve_net(eq.positions, t.edges, plan.lengths, check.masses * rng.uniform(0.7, 1.3, t.m), t.anchored,
                      node_rotations0=eq.rotations, **kw)
    assert start.success
    if turn_rods:
        kw["rod_y"] = rng.normal(size=(t.m, 3))
    sim = mujoco_net.settle_net(start.positions, t.edges, plan.lengths, check.masses, t.anchored,
                                rotations0=start.rotations, **kw)
    assert sim["converged"] and sim["closure_error"] < 1e-6 * t.size
    err = float(np.max(np.linalg.norm(sim["positions"] - eq.positions, axis=1)))
    return err, float(np.max(np.linalg.norm(start.positions - eq.positions, axis=1)))
