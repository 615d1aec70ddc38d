"""Node weights that make a net balance (:func:`optimize.node_mass_needs`), and the planner's hubs
made heavier with them (:mod:`rodcad.design.net.weights`).

Truth: a random net hung from known rod and node masses hangs in a shape. Given that shape with
some nodes lighter than they were and the rods' masses held to a hair around the ones it hung
from, the weights asked for balance it again; for a chain, whose shape fixes its loads up to
its tension, they are exactly what the nodes lost. Weights only pull down, so
they cannot balance a node pushed above where its rods can hold it.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from netgen import random_grid, random_masses

from optimize import design_net_masses, node_mass_needs, solve_net

ROOT = Path(__file__).resolve().parents[1]


def _hung(seed):
    spec = random_grid(seed, anchored="boundary")
    m = random_masses(spec, seed, lo=1.0, hi=4.0)
    nm = np.random.default_rng(seed).uniform(0.2, 0.5, spec.n)
    res = solve_net(spec.positions, spec.edges, spec.lengths, m, spec.anchored, node_masses=nm)
    assert res.success and res.stable
    return spec, m, nm, res


#: The rods' masses are held within this share of the masses the net hung from.
HAIR = 1e-4


def _chain(n_rods: int = 9, seed: int = 0):
    """A chain of point nodes hung between two anchors (a net whose free nodes hold two rods each)."""
    rng = np.random.default_rng(seed)
    x = np.linspace(0.0, 300.0, n_rods + 1)
    pos = np.column_stack([x, np.zeros_like(x), -0.4 * x * (300.0 - x) / 300.0])
    edges = np.column_stack([np.arange(n_rods), np.arange(1, n_rods + 1)])
    lengths = np.linalg.norm(pos[edges[:, 1]] - pos[edges[:, 0]], axis=1)
    anchored = np.array([0, n_rods])
    m = rng.uniform(1.0, 4.0, n_rods)
    nm = rng.uniform(2.0, 5.0, n_rods + 1)
    res = solve_net(pos, edges, lengths, m, anchored, node_masses=nm)
    assert res.success and res.stable and res.compressed.size == 0
    return res.positions, edges, lengths, anchored, m, nm


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_chain_needs_exactly_what_its_nodes_lost(seed):
    # a chain's shape fixes its loads up to its tension: the least weights that balance it are
    # what the light nodes lost (any less tension leaves another node needing negative weight)
    pos, edges, lengths, anchored, m, nm = _chain(seed=seed)
    rng = np.random.default_rng(10 + seed)
    light = rng.choice(np.arange(1, len(nm) - 1), size=3, replace=False)
    lost = np.zeros(len(nm))
    lost[light] = rng.uniform(0.3, 0.9, 3) * nm[light]
    bounds = np.column_stack([m * (1 - HAIR), m * (1 + HAIR)])
    args = (pos, edges, lengths, bounds, anchored)
    assert not design_net_masses(*args, node_masses=nm - lost).exact
    extra = np.full(len(nm), 10.0)
    w, exact = node_mass_needs(*args, extra, node_masses=nm - lost)
    assert exact
    # the rods' hair of freedom moves a node's load by half its rods' widths, and the tension
    # with it (every load scales with the tension): by that times the loads' ratio at most
    slack = np.zeros(len(nm))
    np.add.at(slack, edges.ravel(), np.repeat(m * HAIR, 2))
    load = nm.copy()
    np.add.at(load, edges.ravel(), np.repeat(m / 2, 2))
    free = slice(1, -1)
    bound = slack[free].max() * load[free].max() / load[free].min()
    assert np.max(np.abs(w - lost)[free]) <= bound, (w, lost)
    assert design_net_masses(*args, node_masses=nm - lost + w).exact


@pytest.mark.parametrize("seed", [1, 3, 5])
def test_weights_the_statics_ask_for_balance_a_net(seed):
    spec, m, nm, res = _hung(seed)
    rng = np.random.default_rng(100 + seed)
    free = np.flatnonzero(~np.isin(np.arange(spec.n), spec.anchored))
    light = rng.choice(free, size=3, replace=False)
    lost = np.zeros(spec.n)
    lost[light] = rng.uniform(0.5, 0.9, 3) * nm[light]
    bounds = np.column_stack([m * (1 - HAIR), m * (1 + HAIR)])
    args = (res.positions, spec.edges, spec.lengths, bounds, spec.anchored)
    push = res.compressed.size > 0  # some random nets rest with rods that push
    extra = np.where(np.isin(np.arange(spec.n), free), 2.0, 0.0)
    # (the weights it lost balance it: the least that do, asked for, balance it too)
    got = node_mass_needs(*args, extra, node_masses=nm - lost, allow_compression=push)
    if design_net_masses(*args, node_masses=nm - lost, allow_compression=push).exact and got is None:
        return  # (a grid's balance need not fix its loads: this one balances lighter)
    w, exact = got
    assert exact and np.all(w >= 0) and np.all(w <= extra)
    after = design_net_masses(*args, node_masses=nm - lost + w, allow_compression=push)
    assert after.exact and after.residual < 1e-9


def test_weights_within_reach_that_do_not_balance_come_back_as_the_nearest():
    pos, edges, lengths, anchored, m, nm = _chain(seed=4)
    k = len(nm) // 2
    lost = np.zeros(len(nm))
    lost[k] = 0.8 * nm[k]
    bounds = np.column_stack([m * (1 - HAIR), m * (1 + HAIR)])
    extra = np.zeros(len(nm))
    extra[k] = 0.7 * lost[k]  # less than it lost
    w, exact = node_mass_needs(pos, edges, lengths, bounds, anchored, extra, node_masses=nm - lost)
    assert not exact
    assert w[k] == pytest.approx(extra[k], rel=1e-6) and np.count_nonzero(w) == 1


def test_no_weights_hold_a_node_pushed_up_or_where_none_may_be_added():
    spec, m, nm, res = _hung(2)  # (every rod in tension)
    free = np.flatnonzero(~np.isin(np.arange(spec.n), spec.anchored))
    k = int(free[len(free) // 2])
    target = res.positions.copy()
    target[k, 2] += 0.3 * spec.size  # above its neighbours: its rods would have to push
    lengths = np.linalg.norm(target[spec.edges[:, 1]] - target[spec.edges[:, 0]], axis=1)
    args = (target, spec.edges, lengths, (1.0, 4.0), spec.anchored)
    assert node_mass_needs(*args, np.where(np.isin(np.arange(spec.n), free), 5.0, 0.0), node_masses=nm) is None
    assert node_mass_needs(*args, np.zeros(spec.n), node_masses=nm) is None


#: MuJoCo's rest against rodcad's equilibrium, over the net's size (its soft closures at the
#: default step: tests/mujoco_net.py).
TOL = 1e-5


@pytest.fixture(scope="module")
def zigzag(tmp_path_factory):
    """A drawn strip with zig-zag diagonals (4 bays, 246 x 60 mm, 72 mm sag), hung from its ends:
    the nodes where the diagonals meet the rails take hubs large enough for their tight angles,
    four times the weight of the others, which the rods' masses cannot make up."""
    from rodcad.design.loader import load_design
    from rodcad.pipeline.net import build_net

    sys.path.insert(0, str(ROOT / "benchmarks"))
    import net_family

    m = net_family._strip(None, 0, (245.6, 60.4, 4, 71.65, True))
    path = tmp_path_factory.mktemp("weights") / "zigzag.yaml"
    path.write_text(m.yaml)
    return build_net(load_design(path)).check


def test_light_hubs_are_made_heavier_and_the_strip_hangs_where_mujoco_rests(zigzag):
    from net_settle import settle_from_other_masses

    check = zigzag
    assert check.ok, check.limit()
    note = next(n for n in check.notes if "to weigh more" in n)
    before = float(note.split("it hung ")[1].split(" %")[0])
    assert before > 100 * check.tolerance  # (off its tolerance with the hubs its rods need)
    planned = check.planned
    t = planned.target
    free = ~t.anchored_mask & ~t.joint_mask
    masses = planned.node_masses[free]
    assert masses.max() / masses.min() < 1.5  # (the rails' hubs weigh alike once weighed)
    err, moved = settle_from_other_masses(check, seed=0, turn_rods=True)
    assert moved > 10 * TOL * t.size  # (a start away from the equilibrium)
    assert err / t.size < TOL
