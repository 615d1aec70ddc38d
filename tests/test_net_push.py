"""Rods that push where the hardware holds them (issue 33): with ``net.compression`` unset, a
rigid rod between two hubs may push (the ball sockets hold its balls either way) while it stays
under a fifth of its Euler buckling load; a rod at a two-rod joint, or at point nodes, may not.

Truth: MuJoCo (tests/mujoco_net.py, no rodcad code) for the equilibrium with pushing diagonals,
and the buckling criterion flipped by the material's modulus.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from net_settle import settle_from_other_masses
from test_net_collapse import _strip

from rodcad.design.loader import load_design
from rodcad.design.net.check import BUCKLING_SAFETY
from rodcad.design.net.choose import design_drawn_net

#: A strip 55 mm wide and 300 mm long in 6 bays with diagonals, sagging 30 mm: hung from its
#: ends, its diagonals push (5-6 % of the largest tension).
STRIP = _strip(55.0, 300.0, 6, 30.0)


@pytest.fixture(scope="module")
def pushed():
    d = load_design("strip.yaml", text=STRIP)
    return d, design_drawn_net(d.net, d.catalog, seed=0)


def test_diagonals_that_push_are_held_by_default_and_mujoco_agrees(pushed):
    d, check = pushed
    plan, t = check.plan, check.plan.target
    T = check.equilibrium.tensions
    assert d.net.compression is None  # (unset: the default)
    assert check.ok and check.rel_size <= check.tolerance and check.compressed.size >= 3
    assert check.unheld.size == 0
    hw = plan.hardware
    for e in check.compressed:
        assert not t.joint_mask[t.edges[e]].any()  # one rigid rod between two hubs
        assert -T[e] * BUCKLING_SAFETY <= hw.buckling_load(float(plan.lengths[e]))
    # MuJoCo, released from another shape of the same rods, rests where rodcad's equilibrium is
    err, moved = settle_from_other_masses(check, 7)
    assert err < 1e-5 * t.size and moved > 20 * err  # (a braced strip is stiff: 30 % other masses move it 0.1 mm)


def test_pushing_is_refused_when_asked_or_beyond_a_fifth_of_the_buckling_load(pushed):
    d, check = pushed
    no = dataclasses.replace(check.plan.target, compression=False)
    refused = dataclasses.replace(check, plan=dataclasses.replace(check.plan, target=no))
    assert not refused.ok and np.array_equal(refused.unheld, check.compressed)
    assert "push (compression)" in refused.limit() and "net.compression: true" in refused.limit()
    # the same rods of a material a million times softer buckle under their push
    hw = check.plan.hardware
    soft = dataclasses.replace(hw, modulus=hw.modulus * 1e-6)
    assert soft.buckling_load(100.0) == pytest.approx(hw.buckling_load(100.0) * 1e-6)
    assert hw.buckling_load(50.0) == pytest.approx(4 * hw.buckling_load(100.0))  # Euler: 1 / L^2
    weak = dataclasses.replace(check, plan=dataclasses.replace(check.plan, hardware=soft))
    assert not weak.ok and np.array_equal(weak.unheld, check.compressed)
    assert "buckling" in weak.limit()


def test_a_catalogs_modulus_is_read_and_a_bad_one_is_refused_at_its_key():
    from rodcad.catalog.loader import catalog_from_text
    from rodcad.catalog.paths import default_catalog_dir
    from rodcad.errors import InputError

    text = (default_catalog_dir() / "pla-parametric.yaml").read_text()
    shipped = "  material: {name: PLA, density: 1.24, min_wall: 1.2}"
    assert shipped in text
    stiff = catalog_from_text(text.replace(shipped, shipped[:-1] + ", modulus: 3.5}"), "c.yaml")
    assert stiff.node.modulus == 3.5 and next(iter(stiff)).material.modulus == 3.5
    assert catalog_from_text(text, "c.yaml").node.modulus == 1.5  # (the default)
    bad = text.replace(shipped, shipped[:-1] + ", modulus: -2}")
    with pytest.raises(InputError) as err:
        catalog_from_text(bad, "c.yaml")
    line = next(i for i, s in enumerate(bad.splitlines(), 1) if "modulus: -2" in s)
    col = bad.splitlines()[line - 1].index("-2") + 1
    got = [str(p) for p in err.value.problems]
    assert got == [f"c.yaml:{line}:{col}: defaults.material.modulus: must be greater than 0 GPa and at most 500 GPa "
                   "(got -2)"], got


# -- where no masses balance the target in tension, the rods the hubs hold push (the design's choice)


def _bowl(radius: float, cut: float) -> str:
    """A bowl hung from its rim: an icosphere's (2 subdivisions) cap below ``cut`` x its radius,
    as an OBJ mesh (anchored at its boundary)."""
    import trimesh

    ico = trimesh.creation.icosphere(subdivisions=2, radius=radius)
    v, f = ico.vertices, ico.faces
    faces = f[np.all(v[f][:, :, 2] <= cut * radius + 1e-6 * radius, axis=1)]
    used = np.unique(faces)
    idx = np.full(len(v), -1)
    idx[used] = np.arange(used.size)
    return "".join(f"v {x:.5f} {y:.5f} {z:.5f}\n" for x, y, z in v[used]) + \
        "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in idx[faces])


@pytest.fixture(scope="module")
def bowl(tmp_path_factory):
    folder = tmp_path_factory.mktemp("bowl")
    (folder / "bowl.obj").write_text(_bowl(150.0, -0.2))
    (folder / "bowl.yaml").write_text("design: 1\nname: bowl\nnet:\n  mesh: bowl.obj\n  anchored: boundary\n")
    d = load_design(folder / "bowl.yaml")
    return d, design_drawn_net(d.net, d.catalog, seed=0)


def test_a_bowl_hung_from_its_rim_pushes_along_its_hoops_where_its_hubs_hold_them_and_mujoco_agrees(bowl):
    from optimize import design_net_masses
    from rodcad.design.net.pushing import held_rods

    d, check = bowl
    plan, t = check.plan, check.plan.target
    assert d.net.compression is None  # (unset: the default)
    # the physics: below the rim a bowl's hoops push, so no masses balance its nodes in tension
    tense = design_net_masses(t.positions, t.edges, plan.lengths, plan.bounds, t.anchored,
                              node_masses=plan.node_masses, node_com=plan.node_com, pivots=plan.pivots,
                              com=plan.statics_com, forces_only=True)
    assert not tense.exact and tense.needs_compression.size > 0  # (balanced only with some rods pushing)
    assert np.array_equal(plan.pushing, held_rods(plan)) and plan.pushing.all()  # (no two-rod joint in this net)
    assert check.ok and check.equilibrium.stable and check.rel_size < 1e-5
    T = check.equilibrium.tensions
    assert check.compressed.size >= 10 and check.unheld.size == 0
    hw = plan.hardware
    for e in check.compressed:
        assert -T[e] * BUCKLING_SAFETY <= hw.buckling_load(float(plan.lengths[e]))
    assert any("may push" in n for n in check.notes)
    from rodcad.outputs.design_json import print_profile
    from rodcad.outputs.net.design_json import net_json

    block = net_json(check, name="bowl", seed=0, catalog=d.catalog, print_profile=print_profile(d.catalog))["net"]
    assert block["pushing_designed"] == list(range(t.m)) and set(block["compressed"]) == set(check.compressed.tolist())
    # MuJoCo, released from another shape of the same rods, rests where rodcad's equilibrium is
    err, moved = settle_from_other_masses(check, 7)
    assert err < 1e-5 * t.size and moved > 20 * err


def test_a_hubs_turning_stiffness_is_the_second_derivative_of_its_rods_lengths():
    """:func:`optimize.net.pushing.hub_stiffness_rows` against finite differences: a hub turned by
    ``s`` about each axis, its node point held, lengthens each rod by ``s^2 a' G a / 2``."""
    from scipy.spatial.transform import Rotation

    from optimize.net.model import Net
    from optimize.net.pushing import AXES, hub_stiffness_rows

    rng = np.random.default_rng(3)
    far = np.array([[60.0, 5.0, 20.0], [-40.0, 45.0, 25.0], [-20.0, -55.0, 30.0], [10.0, 5.0, -50.0]])
    x = np.vstack([np.zeros(3), far])
    edges = np.array([[0, 1], [2, 0], [0, 3], [4, 0]])
    pivots = np.zeros((4, 2, 3))
    for e, (i, j) in enumerate(edges):  # (each socket a little off its line, as the design turns them)
        k = 0 if i == 0 else 1
        u = x[j if k == 0 else i] / np.linalg.norm(x[j if k == 0 else i])
        pivots[e, k] = 8.0 * (u + 0.2 * rng.normal(size=3))
    ends = x[edges] + pivots
    lengths = np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)
    net, state = Net.from_args(x, edges, lengths, np.ones(4), [1, 2, 3, 4], pivots=pivots)
    G, need = hub_stiffness_rows(net, state, np.ones(4, bool))
    G = G.toarray()
    assert G.shape == (len(AXES), 4) and np.all(need > 0)

    def length(e: int, w: np.ndarray) -> float:
        q = Rotation.from_rotvec(w).apply(pivots[e, 0 if edges[e, 0] == 0 else 1])
        other = x[edges[e, 1] if edges[e, 0] == 0 else edges[e, 0]]
        return float(np.linalg.norm(other - q))

    h = 1e-3
    for a, axis in enumerate(AXES):
        for e in range(4):
            fd = (length(e, h * axis) - 2 * length(e, 0 * axis) + length(e, -h * axis)) / h ** 2
            assert fd == pytest.approx(G[a, e], abs=1e-5 * np.abs(G).max())  # (O(h^2) of the fourth derivative)


def test_rods_that_may_push_are_a_mask_the_others_stay_in_tension():
    from optimize.net.pushing import push_mask

    assert push_mask(True, 3).tolist() == [True] * 3 and push_mask(False, 2).tolist() == [False] * 2
    assert push_mask(np.array([1, 0, 1]), 3).tolist() == [True, False, True]
    with pytest.raises(ValueError, match="mask"):
        push_mask(np.ones(4, bool), 3)


def test_the_rods_a_hub_holds_are_not_at_a_ball_joint_between_two_rods_nor_on_point_nodes():
    from types import SimpleNamespace

    from rodcad.design.net.pushing import held_rods

    # a triangle 0-1-2 of free hubs, hub 3 anchored; node 4 free with two rods (a ball joint
    # between two rods: they fold if both push); node 5 a planner's two-rod joint
    edges = np.array([[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 4], [4, 3], [2, 5], [5, 3]])
    joint = np.zeros(6, bool)
    joint[5] = True
    anchored = np.zeros(6, bool)
    anchored[3] = True
    t = SimpleNamespace(edges=edges, n=6, m=len(edges), joint_mask=joint, anchored_mask=anchored)
    hubs = SimpleNamespace(target=t, hardware=SimpleNamespace(is_hub=True))
    assert held_rods(hubs).tolist() == [True] * 5 + [False] * 4
    points = SimpleNamespace(target=t, hardware=SimpleNamespace(is_hub=False))
    assert not held_rods(points).any()
