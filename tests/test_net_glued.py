"""A band of hubs held by rods glued toward the anchors (issue 33, rodcad.design.net.glued): a bowl
hung from its widest ring cannot hang there on ball sockets (its rim band's hoops push as hard as
its meridians pull, and those hubs turn freely), so the planner glues the rods from the anchors to
the first ring of hubs at both ends and the rest hangs.

Truth: MuJoCo (tests/mujoco_net.py, no rodcad code) with those rod ends welded in their sockets
and only the drawn anchors held rests where rodcad's equilibrium is; with the same rods free on
their ball joints the net rests elsewhere.
"""

from __future__ import annotations

import dataclasses

import mujoco_net
import numpy as np
import pytest
from test_net_push import _bowl

from optimize import solve_net
from rodcad.design.loader import load_design
from rodcad.design.net.choose import design_drawn_net
from rodcad.design.net.glued import GLUE_SHARE, glued_plan, rings_from_anchors


@pytest.fixture(scope="module")
def glued(tmp_path_factory):
    folder = tmp_path_factory.mktemp("equator")
    (folder / "bowl.obj").write_text(_bowl(170.0, 0.0))  # (an icosphere's lower half, hung from its equator)
    (folder / "bowl.yaml").write_text("design: 1\nname: bowl\nnet:\n  mesh: bowl.obj\n  anchored: boundary\n")
    d = load_design(folder / "bowl.yaml")
    return d, design_drawn_net(d.net, d.catalog, seed=0)


def test_a_bowl_hung_from_its_equator_is_held_by_a_glued_band_next_to_its_anchors(glued):
    d, check = glued
    t, drawn = check.plan.target, d.net
    assert check.ok and check.rel_size <= check.tolerance
    assert t.glued is not None and t.glued_rods is not None
    # the drawn anchors are still what it hangs from; the glued hubs are the first ring below them
    assert np.array_equal(t.hung_from, drawn.anchored)
    ring = rings_from_anchors(dataclasses.replace(t, anchored=drawn.anchored))
    free = ~drawn.anchored_mask
    assert np.array_equal(t.glued, np.flatnonzero(free & (ring <= 1 + 1e-9)))
    assert t.glued.size <= GLUE_SHARE * free.sum()
    assert np.array_equal(t.anchored, np.union1d(drawn.anchored, t.glued))
    # every glued rod joins a glued hub to an anchor (one ring: nothing between), and every glued hub has one
    ends = t.edges[t.glued_rods]
    assert np.all(t.glued_mask[ends].sum(axis=1) == 1) and np.all(drawn.anchored_mask[ends].sum(axis=1) == 1)
    assert set(np.unique(ends[t.glued_mask[ends]])) == set(t.glued.tolist())
    assert any("Hung from its anchors alone" in note for note in check.notes)


def test_the_glued_band_is_in_design_json_the_report_and_the_preview(glued, tmp_path):
    from rodcad.outputs.design_json import print_profile
    from rodcad.outputs.net.design_json import net_json
    from rodcad.outputs.net.report import net_report

    d, check = glued
    t = check.plan.target
    data = net_json(check, name="bowl", seed=0, catalog=d.catalog, print_profile=print_profile(d.catalog))
    net = data["net"]
    assert net["glued"] == t.glued.tolist() and net["glued_rods"] == t.glued_rods.tolist()
    assert net["hung_from"] == d.net.anchored.tolist()
    assert [nd["index"] for nd in net["nodes"] if nd["glued"]] == t.glued.tolist()
    assert all(nd["anchored"] for nd in net["nodes"] if nd["glued"])  # (held: a re-solve holds them)
    assert [r["index"] for r in net["rods"] if r["glued"]] == t.glued_rods.tolist()
    assert data["bill_of_materials"]["glued_rods"] == t.glued_rods.size
    text = net_report(check, data, title="bowl")
    assert f"{t.glued.size} held by glued rods" in text and "drop of glue" in text


def _settle(check, welded):
    """MuJoCo's rest from the net hung with other masses, only the drawn anchors held."""
    plan, t, eq = check.plan, check.plan.target, check.equilibrium
    kw = dict(node_masses=plan.node_masses, node_com=plan.node_com, pivots=plan.pivots)
    rng = np.random.default_rng(3)
    start = solve_net(eq.positions, t.edges, plan.lengths, check.masses * rng.uniform(0.7, 1.3, t.m), t.anchored,
                      node_rotations0=eq.rotations, **kw)
    assert start.success
    return start, mujoco_net.settle_net(start.positions, t.edges, plan.lengths, check.masses, t.hung_from,
                                        rotations0=start.rotations, welded=welded, max_time=60.0, **kw)


def test_mujoco_with_the_glued_rods_welded_rests_on_the_design_and_on_ball_joints_the_net_leaves_it(glued):
    _, check = glued
    t, eq = check.plan.target, check.equilibrium
    welded = [(int(e), k) for e in t.glued_rods for k in (0, 1)]
    start, sim = _settle(check, welded)
    assert sim["converged"] and sim["closure_error"] < 1e-6 * t.size
    err = float(np.max(np.linalg.norm(sim["positions"] - eq.positions, axis=1)))
    moved = float(np.max(np.linalg.norm(start.positions - eq.positions, axis=1)))
    assert err < 1e-5 * t.size and moved > 20 * err
    # the same rods on ball joints (rodcad's solver, only the drawn anchors held): the band's hubs turn and the
    # net rests off its design, a thousand times as far as MuJoCo rests from it glued
    plan = check.plan
    loose = solve_net(eq.positions, t.edges, plan.lengths, check.masses, t.hung_from, node_masses=plan.node_masses,
                      node_com=plan.node_com, pivots=plan.pivots, node_rotations0=eq.rotations)
    off = float(np.max(np.linalg.norm(loose.positions - eq.positions, axis=1)))
    assert loose.success and off > 1e3 * err and off > 0.1 * check.tolerance * t.size


def test_a_band_is_not_glued_where_it_would_hold_most_of_the_net(glued):
    _, check = glued
    planned = check.planned
    drawn = planned.target
    base = dataclasses.replace(planned, target=dataclasses.replace(drawn, glued=None, glued_rods=None))
    assert glued_plan(base, 3) is None  # (three rings: more than half the free hubs)


def test_rings_are_counted_in_drawn_edges_so_a_planners_joint_is_half_an_edge_away():
    from types import SimpleNamespace

    # drawn edges 0-1, 1-2 (cut in two rods by a joint, node 4), 2-3; anchored at node 0
    t = SimpleNamespace(n=5, m=4, edges=np.array([[0, 1], [1, 4], [4, 2], [2, 3]]), source=np.array([0, 1, 1, 2]),
                        anchored=np.array([0]))
    assert rings_from_anchors(t).tolist() == [0.0, 1.0, 2.0, 3.0, 1.5]
    assert rings_from_anchors(SimpleNamespace(**{**t.__dict__, "source": None})).tolist() == [0, 1, 3, 4, 2]
    # a second rod between nodes 0 and 1 is another way there, not a longer one
    twice = SimpleNamespace(n=5, m=5, edges=np.vstack([t.edges, [[1, 0]]]), source=np.append(t.source, 3),
                            anchored=t.anchored)
    assert rings_from_anchors(twice).tolist() == [0.0, 1.0, 2.0, 3.0, 1.5]


def test_glue_holds_hubs_that_turn_not_a_shape_that_cannot_hang(glued):
    """The bowl's nodes balance with its held rods pushing (what fails is its rim band's hubs
    turning): glued. A grid drawn over a square and hung from its corners (examples/dome.yaml)
    has nothing to pull its straight border outward: no glue, the honest exit stays."""
    from pathlib import Path

    from rodcad.design.net.imbalance import hubs_fail
    from rodcad.design.net.plan import plan_net

    d, _ = glued
    assert hubs_fail(plan_net(d.net, d.catalog), 9.81)
    dome = load_design(Path(__file__).parent.parent / "examples" / "dome.yaml")
    assert not hubs_fail(plan_net(dome.net, dome.catalog), 9.81)
