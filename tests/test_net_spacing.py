"""A hub's sockets, turned to balance it, keep the wall between them; hubs whose rods turn
further than their sockets let them get wider cones within the catalog's range
(rodcad.design.net.spacing, rodcad.design.net.cones)."""

from __future__ import annotations

import dataclasses
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from rodcad.catalog.loader import catalog_from_text, load_catalog
from rodcad.catalog.paths import default_catalog_dir
from rodcad.design.net.spacing import socket_clashes, spaced_turn, too_close
from rodcad.errors import InputError

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def cat():
    return load_catalog("pla-parametric")


def _unit(theta: float, phi: float) -> np.ndarray:
    return np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)])


def _least_turn(axis, f, cw, rad):
    """The hubs' least turn without the spacing (rodcad.design.net.hubs' Newton, to convergence)."""
    from rodcad.design.net.spacing import _skew

    a = axis.copy()
    A = np.hstack([-_skew(fq) for fq in f])
    for _ in range(40):
        M = cw + np.sum(np.cross(a, f), axis=0)
        a = a + (A.T @ np.linalg.lstsq(A @ A.T, -M, rcond=None)[0]).reshape(-1, 3)
        a *= rad / np.linalg.norm(a, axis=1, keepdims=True)
    return a


@pytest.mark.parametrize("seed", [0, 4, 10, 27])
def test_the_least_turn_that_would_run_two_sockets_together_is_replaced_by_one_that_keeps_them_apart(seed):
    rng = np.random.default_rng(seed)
    rad, need = 7.5, 60.0
    theta = np.radians([0.0, 64.0, 150.0]) + rng.normal(0.0, 0.05, 3)
    axis = rad * np.array([_unit(t, p) for t, p in zip(theta, rng.normal(0.0, 0.2, 3))])
    f = rng.normal(0.0, 1.0, (3, 3)) + 2 * axis / rad
    cw = rng.normal(0.0, 3.0, 3)
    scale = float(np.linalg.norm(f, axis=1).max()) * rad
    free = _least_turn(axis, f, cw, rad)
    assert np.abs(cw + np.cross(free, f).sum(axis=0)).max() < 1e-9 * scale
    assert too_close(free, need) and not too_close(axis, need)  # (the case this is about)
    a = spaced_turn(axis, f, cw, rad, need)
    assert np.allclose(np.linalg.norm(a, axis=1), rad, rtol=1e-12)
    assert not too_close(a, need)
    assert np.abs(cw + np.cross(a, f).sum(axis=0)).max() < 1e-9 * scale  # the hub balances all the same


def test_a_hub_no_spaced_turn_balances_keeps_its_planned_sockets():
    rad, need = 7.5, 60.0
    axis = rad * np.array([_unit(0.0, 0.0), _unit(math.radians(61.0), 0.0), _unit(math.radians(122.0), 0.0)])
    f = 2 * axis / rad
    cw = np.array([0.0, 50.0, 0.0])  # a moment the sockets' pulls along themselves cannot cancel
    a = spaced_turn(axis, f, cw, rad, need)
    assert not too_close(a, need)


def _family_member(name: str):
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import net_family

    return next(m for m in net_family.family(0, 120) if m.name == name)


@pytest.fixture(scope="module")
def designed(tmp_path_factory):
    """A drawn grid whose hubs' least turns ran two sockets within their wall (0.4 deg closer
    than 60 deg) before the turns kept the spacing."""
    from rodcad.design.loader import load_design
    from rodcad.pipeline.net import build_net

    folder = tmp_path_factory.mktemp("spacing")
    m = _family_member("grid-elliptic-004")
    path = folder / f"{m.name}.yaml"
    path.write_text(m.yaml)
    return build_net(load_design(path)).check


def test_a_designed_nets_hubs_keep_the_wall_between_their_turned_sockets(designed):
    check = designed
    assert check.ok, check.limit()
    assert check.clashes == [] and socket_clashes(check.plan) == []
    t = check.plan.target
    turned = np.degrees(np.arccos(np.clip(
        np.sum(check.plan.pivots * check.planned.pivots, axis=2)
        / (np.linalg.norm(check.plan.pivots, axis=2) * np.linalg.norm(check.planned.pivots, axis=2)), -1, 1)))
    assert turned[~t.anchored_mask[t.edges]].max() > 1.0  # (its sockets do turn)


def test_sockets_run_together_are_not_a_design_and_the_reason_names_larger_hubs(designed):
    check = designed
    t, plan = check.plan.target, check.plan
    k = int(np.flatnonzero((~t.anchored_mask) & (plan.degree >= 3))[0])
    (e0, c0), (e1, c1) = [(e, c) for c in (0, 1) for e in np.flatnonzero(t.edges[:, c] == k)][:2]
    pivots = plan.pivots.copy()
    mid = pivots[e0, c0] + pivots[e1, c1]
    pivots[e0, c0] = pivots[e1, c1] = mid / np.linalg.norm(mid) * plan.hub(k).pivot_radius
    bad = dataclasses.replace(check, plan=dataclasses.replace(plan, pivots=pivots))
    assert [c[0] for c in bad.clashes] == [k] and not bad.ok
    assert "larger hubs (node.pivot_radius) would hold them" in bad.limit()


# --------------------------------------------------------------------------- cones


def test_the_default_catalog_has_a_range_of_cones_that_all_hold_the_ball_and_bad_ones_are_named():
    text = (default_catalog_dir() / "pla-parametric.yaml").read_text()
    hw = catalog_from_text(text, "c.yaml").node
    assert hw.cone_deg == 55.0 and hw.cone_limits == (55.0, 65.0)
    for rp in hw.pivot_limits:
        assert hw.sized(rp).coned(65.0).problems() == []
    assert hw.coned(65.0).swing_deg == pytest.approx(hw.swing_deg + 10.0)
    line = next(i for i, s in enumerate(text.splitlines(), 1) if s.startswith("  cone_deg"))
    for wrong, says in (("{min: 55, max: 75}", "would let the 6 mm ball out"),
                        ("{min: 55, max: 65, nominal: 70}", "node.cone_deg: expected min <= nominal <= max")):
        with pytest.raises(InputError) as err:
            catalog_from_text(text.replace("{min: 55, max: 65}", wrong), "c.yaml")
        assert str(err.value.problems[0]).startswith(f"c.yaml:{line}:"), err.value.problems
        assert says in str(err.value), err.value.problems


def test_a_cone_is_as_wide_as_its_neighbours_lips_allow(cat):
    hw = cat.node
    assert hw.cone_for_turn(20.0) == 55.0  # the nominal lets it
    assert hw.cone_for_turn(30.0) == pytest.approx(30.0 + hw.neck_angle_deg)
    assert hw.cone_for_turn(60.0) == 65.0  # the widest of the range
    lip = hw.cone_lip_deg(65.0)
    assert hw.socket_angle_deg > lip  # sockets the wall keeps apart keep their lips whole
    two = lambda deg: np.array([[1.0, 0.0, 0.0], [math.cos(math.radians(deg)), math.sin(math.radians(deg)), 0.0]])
    assert hw.widest_cone(two(lip + 0.1)) == 65.0
    mid = hw.widest_cone(two(hw.cone_lip_deg(60.0)))
    assert mid == pytest.approx(60.0, abs=0.02)
    assert hw.widest_cone(two(hw.cone_lip_deg(55.0) - 0.1)) == 55.0


def test_a_hub_with_wider_cones_is_a_valid_solid_of_its_closed_form_mass(cat):
    from rodcad.cad.net.hub import precise_volume
    from rodcad.cad.net.solids import hub_solid

    hw = cat.node.coned(65.0)
    d = np.array([_unit(math.radians(a), math.radians(p)) for a, p in ((0, 0), (100, 0), (100, 120), (100, 240))])
    s = hub_solid(hw, hw.pivot_radius * d)
    assert s.is_valid
    mass = cat.node.density / 1000.0 * precise_volume(s)
    assert mass == pytest.approx(hw.hub_mass(d)[0], rel=1e-5)
    assert hw.hub_mass(d)[0] < cat.node.hub_mass(d)[0]  # lighter than the nominal hub


def _turned_too_far(check, by: float = 3.0):
    """(hub k, rod e, its end c at k, swing): a free hub of three or more rods, and the check's
    swings with that rod end turned ``by`` deg past what its socket lets it."""
    plan = check.plan
    t = plan.target
    k = int(np.flatnonzero((~t.anchored_mask) & (plan.degree >= 3))[0])
    e, c = next((int(e), c) for c in (0, 1) for e in np.flatnonzero(t.edges[:, c] == k))
    swing = check.swing_deg.copy()
    swing[e, c] = plan.end_swing_limits[e, c] + by
    return k, e, c, swing


def _recording(design):
    """(the plans designed, a design function that records them)."""
    tried = []

    def record(p):
        tried.append(p)
        return design(p)

    return tried, record


def test_a_hub_whose_rod_turns_too_far_gets_the_widest_cone_its_lips_allow_and_the_net_is_designed_again(designed):
    from rodcad.design.net.check import design_net_plan
    from rodcad.design.net.cones import widen_cones

    check = designed
    k, e, c, swing = _turned_too_far(check)
    over = dataclasses.replace(check, swing_deg=swing)
    assert not over.ok and "turns" in over.limit() and "cone" in over.limit()
    tried, design = _recording(design_net_plan)
    out = widen_cones(over, design)
    (p,) = tried
    hub = check.planned.hub(k)
    want = hub.cone_for_turn(float(swing[e, c]))
    at = check.plan.target.node_ends()[k]
    dirs = np.array([check.plan.pivots[q, r] for q, r in at], float)
    widest = hub.widest_cone(dirs / np.linalg.norm(dirs, axis=1, keepdims=True))
    # the widest the range and its neighbours' lips allow (what the design's refinement keeps
    # the rods' turns within), which lets the rod turn as far as it did
    assert want > hub.cone_deg and widest >= want and p.node_cone[k] == pytest.approx(widest)
    assert np.all(np.delete(p.node_cone, k) == hub.cone_deg)  # only that hub
    assert p.hub(k).swing_deg >= swing[e, c]
    assert p.node_masses[k] < check.planned.node_masses[k]  # the wider cone's hub is lighter, and designed with
    assert out.ok and out.plan.node_cone[k] == pytest.approx(widest)
    assert any("wider than the catalog's nominal" in n for n in out.notes)
    # a catalog of one cone and one hub size has nothing to widen or grow: the check stays as it was
    one = dataclasses.replace(check.planned, hardware=dataclasses.replace(check.planned.hardware, cone_range=None,
                                                                          pivot_range=None))
    single = dataclasses.replace(over, planned=one)
    assert widen_cones(single, design) is single and len(tried) == 1


def test_the_refinement_keeps_the_rods_within_the_widest_cone_each_hub_could_have(designed):
    # what the design's refinement keeps each rod's turn within: its hub's cone widened as far
    # as the catalog's range and the neighbours' lips allow (what widen_cones may give it)
    from rodcad.design.net.cones import widest_swing_limits

    plan = designed.plan
    own, wide = plan.end_swing_limits, widest_swing_limits(plan)
    assert np.all(wide >= own)
    t = plan.target
    for k in np.unique(t.edges):
        at = t.node_ends()[int(k)]
        hub = plan.hub(int(k))
        dirs = np.array([plan.pivots[e, c] for e, c in at], float)
        dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
        cone = max(hub.widest_cone(dirs), hub.cone_deg)
        assert hub.cone_limits[0] - 1e-9 <= cone <= hub.cone_limits[1] + 1e-9
        for e, c in at:  # (straight rods: the cone's swing itself)
            assert wide[e, c] == pytest.approx(hub.coned(cone).swing_deg, abs=1e-9)
    assert np.any(wide > own + 1.0)  # (this grid's hubs have room to open their cones)
    one = dataclasses.replace(plan, hardware=dataclasses.replace(plan.hardware, cone_range=None))
    assert np.array_equal(widest_swing_limits(one), one.end_swing_limits)


# --------------------------------------------------------------------------- lengths


def test_hubs_grown_leave_no_rod_shorter_than_the_catalog_prints(designed):
    """Grown hubs shorten their rods: where the shortest rod has almost no room, its hubs grow
    by less, and at last not at all (four halvings of the growth used to leave it short)."""
    from rodcad.design.net.spacing import GROW, grown_hubs

    planned = designed.planned
    t = planned.target
    L = (t.edge_lengths - planned.node_pivot[t.edges].sum(axis=1)) / planned.rod_pieces
    tight = dataclasses.replace(planned, length_range=(float(L.min()) - 0.01, planned.length_range[1]))
    grown = grown_hubs(tight, np.arange(t.n))
    assert grown is not None and np.any(grown > planned.node_pivot * (GROW - 1e-9) - 1e-9)  # (the others grow)
    after = (t.edge_lengths - grown[t.edges].sum(axis=1)) / planned.rod_pieces
    assert after.min() >= tight.length_range[0] - 1e-9


def test_a_rod_turned_just_out_of_the_printed_lengths_is_brought_back_by_resizing_its_hubs(designed):
    from rodcad.design.net.check import design_net_plan
    from rodcad.design.net.choose import WINDOW_REACH, in_window

    check = designed
    plan, planned = check.plan, check.planned
    t = plan.target
    free = ~t.anchored_mask
    e = int(np.flatnonzero(free[t.edges].all(axis=1))[0])
    hi = planned.length_range[1]
    lengths = plan.lengths.copy()
    lengths[e] = hi + 0.2  # as if its turned sockets had lengthened it 0.2 mm past the window
    out = dataclasses.replace(check, plan=dataclasses.replace(plan, lengths=lengths))
    assert not out.ok and "leave the" in out.limit()
    tried, design = _recording(design_net_plan)
    back = in_window(out, design)
    p = tried[0]
    i, j = t.edges[e]
    assert p.node_pivot[i] == pytest.approx(planned.node_pivot[i] + 0.2)  # each end takes the excess
    assert p.node_pivot[j] == pytest.approx(planned.node_pivot[j] + 0.2)
    assert p.lengths[e] == pytest.approx(planned.lengths[e] - 0.4, abs=1e-6)
    assert back.ok and any("resized within the family" in n for n in back.notes), back.limit()
    # farther out than the reach: the plan's to say, not resized here
    lengths[e] = hi + 2 * WINDOW_REACH
    far = dataclasses.replace(check, plan=dataclasses.replace(plan, lengths=lengths))
    assert in_window(far, design) is far and len(tried) == 1


def test_a_hub_whose_rod_turns_too_far_for_any_cone_is_made_larger(designed):
    """A catalog of one cone: the hub whose rod turns too far is made larger within the family
    (its sockets then turn less to balance it) and the net designed again."""
    from rodcad.design.net.check import design_net_plan
    from rodcad.design.net.cones import widen_cones
    from rodcad.design.net.spacing import GROW

    check = designed
    k, _, _, swing = _turned_too_far(check)
    one = dataclasses.replace(check.planned, hardware=dataclasses.replace(check.planned.hardware, cone_range=None))
    over = dataclasses.replace(check, swing_deg=swing, planned=one)
    tried, design = _recording(design_net_plan)
    out = widen_cones(over, design)
    (p,) = tried
    assert p.node_pivot[k] > one.node_pivot[k] and p.node_pivot[k] <= one.node_pivot[k] * GROW + 1e-9
    assert np.all(np.delete(p.node_pivot, k) == np.delete(one.node_pivot, k))
    # built: kept, with the reason; not built: the check as it was
    assert (out.ok and any("balances with its sockets turned less" in n for n in out.notes)) or out is over


def test_a_hub_made_larger_for_a_rod_that_still_turns_too_far_gets_wider_cones_too(designed):
    """Where no cone of the catalog holds a rod that turns too far, its hub is made larger; where
    the larger hub's rods still turn a little too far, its cones are widened too (a larger hub
    has room for wider cones between its sockets) before the try is given up."""
    from rodcad.design.net.check import design_net_plan
    from rodcad.design.net.cones import widen_cones

    check = designed
    k, e, c, swing = _turned_too_far(check)
    over = dataclasses.replace(check, swing_deg=swing)
    nominal = check.planned.hardware.cone_deg
    tried = []

    def design(p):  # (only the hub larger and its cones wider holds the rod)
        tried.append(p)
        out = design_net_plan(p)
        grown = p.node_pivot[k] > check.planned.node_pivot[k] + 1e-9
        wide = p.node_cone is not None and p.node_cone[k] > nominal + 1e-9
        if grown and wide:
            return out
        s = out.swing_deg.copy()
        s[e, c] = out.plan.end_swing_limits[e, c] + (1.0 if grown else 3.0)
        return dataclasses.replace(out, swing_deg=s)

    out = widen_cones(over, design)
    assert out.ok, out.limit()
    assert out.plan.node_pivot[k] > check.planned.node_pivot[k] and out.plan.node_cone[k] > nominal
    assert any("balances with its sockets turned less" in n for n in out.notes)
    assert len(tried) <= 2 + 2 * 3  # (the cones' rounds, the larger hub, its cones' rounds)
