"""The anchor fixture: one printed part holding both anchor pins, checked against a real chain
at rest (the heart of examples/heart.yaml, both end rods held by the fixture's stops)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from rodcad.cad.collision import DistanceTo
from rodcad.cad.mesh import DEFLECTION as STL_DEFLECTION
from rodcad.cad.export import export_step, export_stl, import_step, placed, rod_matrix
from rodcad.cad.fixture import (
    check_fixture,
    fixture_solid,
    fixture_stops,
    fixture_width,
    placed_rods,
)
from rodcad.cad.frame import pin_solid
from rodcad.cad.solids import GeometryError, is_valid_solid, type_solid


@pytest.fixture(scope="module")
def heart(build_store):
    r = build_store.result(Path(__file__).resolve().parents[1] / "examples" / "heart.yaml")  # the session's build
    pts = np.asarray(r.equilibrium.points, dtype=float)
    anchors = np.array([pts[0], pts[-1]])
    rods = list(r.plan.rods)
    lim = np.asarray(r.end_limits, dtype=float)
    assert np.isfinite(lim[0, 1]) and np.isfinite(lim[1, 0])  # both end rods held
    return pts, anchors, rods, lim


@pytest.fixture(scope="module")
def fixture(heart):
    _, anchors, rods, lim = heart
    return fixture_solid(anchors, rods[0], rods[-1], lim)


@pytest.fixture(scope="module")
def at_rest(heart):
    pts, _, rods, _ = heart
    return placed_rods(pts, rods)


def _angles(pts):
    d = np.diff(pts, axis=0)
    return np.arctan2(d[:, 1], d[:, 0])


def _overlap(a, b) -> float:
    common = a.intersect(b)
    return 0.0 if common is None else sum(s.volume for s in common.solids())


def _turned(anchors, rods, k, theta):
    """The end rod at anchor k (0: first rod at A, 1: last rod at B) at chord angle theta."""
    rod = rods[0] if k == 0 else rods[-1]
    origin = anchors[0] if k == 0 else anchors[1] - rod.length * np.array([math.cos(theta), math.sin(theta)])
    return placed(type_solid(rod), rod_matrix(origin, theta))


def test_rods_are_placed_like_the_assembly(heart, at_rest):
    pts, _, rods, lim = heart
    th = _angles(pts)
    # the held rods sit exactly at their bounds, and placed_rods puts rod i at p_i along p_i -> p_i+1
    assert th[0] == pytest.approx(lim[0, 1], abs=1e-9) and th[-1] == pytest.approx(lim[1, 0], abs=1e-9)
    for i in (0, len(rods) - 1):
        ref = placed(type_solid(rods[i]), rod_matrix(pts[i], th[i]))
        assert at_rest[i][0].volume == pytest.approx(ref.volume, rel=1e-9)
        assert DistanceTo(ref)(at_rest[i][0]) == 0.0
        c, r = at_rest[i][0].center(), ref.center()
        assert np.allclose([c.X, c.Y, c.Z], [r.X, r.Y, r.Z], atol=1e-6)


def test_one_valid_solid_in_the_chain_frame(heart, fixture, tmp_path):
    import trimesh

    rods = heart[2]
    assert is_valid_solid(fixture) and fixture.label == "fixture"
    bb = fixture.bounding_box()
    half = fixture_width(rods[0], rods[-1]) / 2
    assert bb.min.Z == pytest.approx(-half) and bb.max.Z == pytest.approx(half)
    assert half > rods[0].geometry.thickness / 2
    step = export_step(fixture, tmp_path / "fixture.step")
    back = import_step(step)
    assert is_valid_solid(back)
    assert back.volume == pytest.approx(fixture.volume, rel=1e-6)
    mesh = trimesh.load(export_stl(fixture, tmp_path / "fixture.stl"))
    assert mesh.is_watertight
    assert abs(mesh.volume - fixture.volume) <= STL_DEFLECTION * fixture.area  # the mesh's accuracy


def test_pin_holes_on_the_anchors(heart, fixture):
    _, anchors, rods, _ = heart
    half = fixture_width(rods[0], rods[-1]) / 2
    near = DistanceTo(fixture)
    for k, rod in ((0, rods[0]), (1, rods[-1])):
        h = rod.geometry.hinge
        m = np.eye(4)
        m[:2, 3] = anchors[k]
        m[2, 3] = -half
        pin = placed(pin_solid(h.pin_diameter, 2 * half), m)
        assert near(pin) == pytest.approx(h.pin_clearance / 2, abs=1e-6)  # a hole of hole_diameter


def test_clear_of_every_rod_at_rest(heart, fixture, at_rest):
    _, anchors, _, lim = heart
    assert check_fixture(fixture, at_rest, anchors=anchors, end_limits=lim, build_volume=(220, 220, 250)) == []
    for solid, name in at_rest[:2] + at_rest[-2:]:
        assert _overlap(fixture, solid) < 1e-3, name


def test_stops_hold_the_end_rods_at_their_bounds(heart, fixture, at_rest):
    _, anchors, rods, lim = heart
    stops = fixture_stops(anchors, rods[0], rods[-1], lim)
    assert [(s.anchor, s.bound) for s in stops] == [(0, "hi"), (1, "lo")]
    # the heart's lobes would fall: the stops are below the end rods, under their anchors' level
    assert all(s.center[1] < 0 for s in stops)
    near = DistanceTo(fixture)
    for k, bound, past in ((0, lim[0, 1], +1), (1, lim[1, 0], -1)):
        rest = at_rest[0][0] if k == 0 else at_rest[-1][0]
        d = near(rest)
        assert 0 < d < 0.05
        assert _overlap(fixture, rest) == 0.0
        further = _turned(anchors, rods, k, bound + past * math.radians(1.0))
        assert _overlap(fixture, further) > 0.5  # mm^3: the peg is in the way
        back = _turned(anchors, rods, k, bound - past * math.radians(5.0))
        assert near(back) > 0.1


def test_check_fixture_names_the_problems(heart, at_rest):
    pts, anchors, rods, lim = heart
    th = _angles(pts)
    bare = fixture_solid(anchors, rods[0], rods[-1], None, rest_angles=(th[0], th[-1]))
    assert is_valid_solid(bare)
    assert check_fixture(bare, at_rest) == []  # a bare-pin fixture clears the rods
    problems = check_fixture(bare, at_rest, anchors=anchors, end_limits=lim, build_volume=(25, 25, 25))
    assert any("rod_00 does not rest on the fixture's stop at A" in p for p in problems)
    assert any(f"rod_{len(rods) - 1:02d} does not rest on the fixture's stop at B" in p for p in problems)
    assert any("does not stop rod_00" in p for p in problems)
    assert any("build volume" in p for p in problems)
    # a bare-pin fixture made for rods hanging straight down is in the heart's way
    hanging = fixture_solid(anchors, rods[0], rods[-1], None)
    assert is_valid_solid(hanging)
    assert any("rod_00 overlaps the fixture" in p for p in check_fixture(hanging, at_rest))


def test_screw_mount_and_a_fused_end(heart, at_rest):
    _, anchors, rods, lim = heart
    screws = fixture_solid(anchors, rods[0], rods[-1], lim, mount="screws")
    assert is_valid_solid(screws)
    assert check_fixture(screws, at_rest, anchors=anchors, end_limits=lim) == []
    # a rod fused to the fixture (lo == hi) gets a stop on either side
    fused = lim.copy()
    fused[0] = lim[0, 1]
    stops = fixture_stops(anchors, rods[0], rods[-1], fused)
    assert [(s.anchor, s.bound) for s in stops] == [(0, "lo"), (0, "hi"), (1, "lo")]
    solid = fixture_solid(anchors, rods[0], rods[-1], fused)
    assert check_fixture(solid, at_rest, anchors=anchors, end_limits=fused) == []


def test_bad_input_raises(heart):
    _, anchors, rods, lim = heart
    with pytest.raises(GeometryError, match="knuckles need at least"):
        fixture_solid(np.array([[0.0, 0.0], [9.0, 0.0]]), rods[0], rods[-1], lim)
    with pytest.raises(GeometryError, match="end_limits"):
        fixture_solid(anchors, rods[0], rods[-1], np.zeros(4))
    with pytest.raises(GeometryError, match="lo .* must be <= hi"):
        fixture_solid(anchors, rods[0], rods[-1], np.array([[1.0, 0.0], [-np.inf, np.inf]]))
    with pytest.raises(GeometryError, match="mount"):
        fixture_solid(anchors, rods[0], rods[-1], lim, mount="glue")
    # B right where the first rod lies
    with pytest.raises(GeometryError, match="sweep over anchor B"):
        b = anchors[0] + 30 * np.array([math.cos(lim[0, 1]), math.sin(lim[0, 1])])
        fixture_solid(np.array([anchors[0], b]), rods[0], rods[-1], lim)


@pytest.mark.parametrize("scale", [0.6, 1.5], ids=["lower-body", "higher-body"])
def test_stops_hold_graduated_end_rods(scale):
    """End rods of a graduated family, thinner or thicker than their hinge ends: the fixture
    clears them at rest (its rods' layer as thick as the body), its pegs touch their bodies'
    own side faces at the bounds, and a degree further the peg is in the way."""
    from rodcad.catalog.loader import load_catalog

    cat = load_catalog("pla-parametric")
    first = cat.rod("rod", 50.0, 0.004, scale=scale)
    last = cat.rod("rod", 50.0, 0.004, scale=scale)
    t0, t1 = math.radians(-50.0), math.radians(50.0)  # a U: the rods hang down from the anchors
    a = np.array([0.0, 0.0])
    b = np.array([150.0, 0.0])
    lim = np.array([[-math.inf, t0], [t1, math.inf]])  # the fixture keeps them from swinging in
    fixture = fixture_solid(np.array([a, b]), first, last, lim)
    assert is_valid_solid(fixture)
    near = DistanceTo(fixture)
    rest = [_turned(np.array([a, b]), [first, last], k, th) for k, th in ((0, t0), (1, t1))]
    assert check_fixture(fixture, [(rest[0], "rod_00"), (rest[1], "rod_01")], anchors=np.array([a, b]),
                         end_limits=lim) == []
    for k, (th, past) in enumerate(((t0, +1), (t1, -1))):
        assert 0 < near(rest[k]) < 0.05
        further = _turned(np.array([a, b]), [first, last], k, th + past * math.radians(1.0))
        assert _overlap(fixture, further) > 0.5


def test_slots_that_would_cut_the_rods_layer_through_stop_past_the_rods(heart):
    """End rods resting toward each other under a wide mount: slots cut out past the whole
    fixture would leave its top and bottom apart; each slot then goes only as far as its own
    rod reaches, and the fixture stays one valid solid that clears the rods it was made for."""
    _, _, rods, _ = heart
    anchors = np.array([[0.0, 0.0], [150.0, 0.0]])
    solid = fixture_solid(anchors, rods[0], rods[-1], None, rest_angles=(0.0, 0.0))
    assert is_valid_solid(solid) and len(solid.solids()) == 1
    for k, theta in ((0, 0.0), (1, 0.0)):
        assert _overlap(solid, _turned(anchors, rods, k, theta)) < 1e-3  # mm^3: the rod's slot is clear
