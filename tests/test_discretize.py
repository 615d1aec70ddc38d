"""The chord walk keeps a polyline's vertices as joints whatever the last digits.

A polyline whose segments are whole multiples of the rod length must come back with
its vertices as joints exactly; before the walk snapped onto vertices at the rod
length up to round-off, another CPU's last digits put the joint just short of a
vertex, the walk cut the corner and the chain missed B by 10 mm.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from optimize.chain.discretize import discretize


def _polyline(legs):
    pts = [np.zeros(2)]
    for ang, length in legs:
        a = math.radians(ang)
        pts.append(pts[-1] + length * np.array([math.cos(a), math.sin(a)]))
    return np.array(pts)


LEGS = [((-40, 90), (-60, 90), (40, 120)),          # a concave bend of -20 deg, then a corner
        ((-30, 60), (-10, 30), (10, 30), (35, 90))]  # gentle bends a rod length apart


@pytest.mark.parametrize("legs", LEGS)
@pytest.mark.parametrize("seed", range(6))
def test_vertices_at_rod_multiples_are_joints_under_round_off(legs, seed):
    curve = _polyline(legs)
    if seed:  # perturb every coordinate by about 1e-12 (relative)
        rng = np.random.default_rng(seed)
        curve = curve * (1 + 1e-12 * rng.standard_normal(curve.shape))
    d = discretize(curve, [30.0])
    assert d.lengths.sum() == pytest.approx(sum(l for _, l in legs))
    for v in curve[1:-1]:  # every vertex is a joint, to round-off
        assert np.min(np.hypot(*(d.points - v).T)) < 1e-9
    assert d.joint_error < 1e-9
    theta = np.degrees(np.arctan2(*np.diff(d.points, axis=0).T[::-1]))
    wanted = np.repeat([a for a, _ in legs], [int(round(l / 30)) for _, l in legs])
    np.testing.assert_allclose(theta, wanted, atol=1e-7)


def test_centerline_of_curved_rods_is_their_arc():
    """A rod of curvature k bulges to the right of p_i -> p_{i+1} by the sagitta of its arc."""
    from optimize.chain.curves import centerline, curve_distance

    pts = np.array([[0.0, 0.0], [40.0, 0.0], [40.0, -30.0]])
    cl = centerline(pts, [0.02, -0.01])
    rho = 50.0
    assert cl[0].tolist() == [0.0, 0.0] and np.allclose(cl[-1], pts[-1])
    assert np.min(cl[:25, 1]) == pytest.approx(-(rho - math.sqrt(rho**2 - 20**2)), rel=1e-6)  # below the chord
    second = cl[25:]
    assert np.min(second[:, 0]) == pytest.approx(40.0, abs=1e-9)  # k < 0 bulges to the rod frame's +y:
    assert np.max(second[:, 0]) == pytest.approx(40.0 + (100 - math.sqrt(100**2 - 15**2)), rel=1e-3)  # +x here
    np.testing.assert_array_equal(centerline(pts, [0.0, 0.0]), pts)
    assert curve_distance(cl, pts) == pytest.approx(rho - math.sqrt(rho**2 - 20**2), rel=1e-3)


@pytest.mark.parametrize("seed", range(4))
def test_the_farthest_point_of_a_polyline_is_the_one_every_point_asked_gives(seed):
    """curves._farthest asks the tree for a sample and the points whose Lipschitz bound reaches
    the largest distance found: the same number as asking for every point, on polylines near
    the tree's points and far from them, with spikes the sample steps over."""
    from scipy.spatial import cKDTree

    from optimize.chain.curves import FARTHEST_STRIDE, _farthest, resample

    rng = np.random.default_rng(seed)
    for _ in range(150):
        walk = np.cumsum(rng.normal(size=(int(rng.integers(3, 40)), 2)) * rng.uniform(0.1, 30), axis=0)
        points = resample(walk, int(rng.integers(2, 6000)))
        near = walk + rng.normal(size=walk.shape) * rng.uniform(0, 5)
        spiky = points.copy()
        spiky[rng.integers(len(spiky), size=3)] += rng.normal(size=(3, 2)) * 40  # off between two samples
        for ref in (resample(near, int(rng.integers(2, 3000))), rng.normal(size=(int(rng.integers(1, 40)), 2)) * 50):
            tree = cKDTree(ref)
            for pts in (points, spiky):
                assert _farthest(tree, pts) == tree.query(pts)[0].max()
    assert FARTHEST_STRIDE > 1  # (else nothing is left unasked)


def test_a_taut_target_and_a_runaway_length_are_explained():
    with pytest.raises(ValueError, match="straight line between the anchors"):
        discretize(np.array([[0.0, 0.0], [100.0, 0.0], [200.0, 0.0]]), [20.0])
    with pytest.raises(ValueError, match="chains of up to 300 rods"):
        discretize(np.array([[0.0, 0.0], [5e4, -1e5], [1e5, 0.0]]), [20.0, 40.0])


@pytest.mark.parametrize("form, params", [("semicircle", {}), ("triangle", {"depth": 137.3}),
                                          ("polygon", {"sides": 6}), ("function", {"y": "-0.004*x*(200-x)"})])
def test_rods_printed_to_order_put_every_joint_on_the_curve(form, params):
    """With any length in a range (rods printed to order), each piece between corners gets
    equal chords landing exactly on its end: every joint on the curve, every corner a joint,
    every length in range."""
    from rodcad.design.targets import make_target

    curve = make_target(form, (0, 0), (200, 0), **params)
    d = discretize(curve, [30.0], length_range=(25.0, 45.0))
    assert d.joint_error < 1e-9
    assert np.all((d.lengths >= 25.0) & (d.lengths <= 45.0))
    np.testing.assert_allclose(np.hypot(*np.diff(d.points, axis=0).T), d.lengths, rtol=1e-9)
    corners = [int(i) for i in np.flatnonzero(np.abs(np.diff(np.unwrap(np.arctan2(*np.diff(curve, axis=0).T[::-1]))))
                                              > np.radians(25)) + 1]
    for c in corners:  # every corner of the target is a joint
        assert np.min(np.hypot(*(d.points - curve[c]).T)) < 1e-9
    pieces = np.split(d.lengths, d.corners)
    assert all(np.ptp(p) < 1e-9 for p in pieces)  # equal chords per piece
    with pytest.raises(ValueError, match="length_range"):
        discretize(curve, [30.0], length_range=(45.0, 25.0))


def test_a_corner_closer_than_the_shortest_rod_to_the_last_carries_no_joint_of_its_own():
    """Rods printed to order land exactly on each piece's end, so no rod fits a piece shorter than
    the shortest rod: a corner that close to an anchor (a drop drawn with a 16 mm lip under a
    catalog printing from 20 mm) was a joint of its own and the target was refused. The rods
    now cross it; the other corners stay joints."""
    lip = np.column_stack([np.zeros(9), np.linspace(0.0, -16.0, 9)])
    rest = np.array([[-16.0, -16.0 - 40.0 * t] for t in np.linspace(0, 1, 9)[1:]]
                    + [[-16.0 + 80.0 * t, -56.0] for t in np.linspace(0, 1, 9)[1:]])
    curve = np.vstack([lip, rest])  # corners at 16 mm (the lip's end) and at 56 mm (the bottom)
    d = discretize(curve, [30.0], length_range=(20.0, 60.0))
    assert np.all((d.lengths >= 20.0 - 1e-9) & (d.lengths <= 60.0 + 1e-9))
    assert np.min(np.hypot(*(d.points - [0.0, -16.0]).T)) > 1.0  # the lip's corner: crossed
    assert np.min(np.hypot(*(d.points - [-16.0, -56.0]).T)) < 1e-9  # the bottom corner: a joint
    assert d.joint_error < 1e-9 and np.allclose(d.points[[0, -1]], curve[[0, -1]])
    # with rods from 15 mm the lip's corner is a joint again
    short = discretize(curve, [30.0], length_range=(15.0, 60.0))
    assert np.min(np.hypot(*(short.points - [0.0, -16.0]).T)) < 1e-9


@pytest.mark.parametrize("form, params, before, after", [
    ("semicircle", {}, 0.5, 0.03), ("function", {"y": "-0.004*x*(200-x)"}, 0.5, 0.03),
    ("arc", {"sag": 60}, 0.5, 0.03), ("triangle", {"depth": 137.3}, 0.0, 0.1)])
def test_curved_rods_follow_the_curve(form, params, before, after):
    """Rods printed to order with the curvature of the curve between their joints: the
    centrelines follow smooth curves (the sagitta of straight chords is gone) and stay
    straight along straight sides."""
    from optimize.chain.curves import centerline, curve_distance, fit_curvatures
    from rodcad.design.targets import make_target

    curve = make_target(form, (0, 0), (200, 0), **params)
    d = discretize(curve, [30.0], length_range=(25.0, 45.0))
    k = fit_curvatures(curve, d.points, max_curvature=0.05)
    assert curve_distance(curve, d.points) >= before
    assert curve_distance(curve, centerline(d.points, k)) < after
    if form == "semicircle":
        np.testing.assert_allclose(k, 0.01, rtol=2e-3)  # the circle's own curvature, 1 / 100 mm
    if form == "triangle":
        assert not np.any(k)


def test_centerline_of_joints_further_apart_than_the_arc_allows_is_a_half_circle():
    """Pins in their holes can put a rod bent to a half circle's joints a little further apart
    than its diameter: the centreline is then the half circle on their chord, finite."""
    from optimize.chain.curves import centerline

    c = 20.0 + 0.2  # the joints 0.2 mm further apart than a rod of radius 10 mm allows
    cl = centerline(np.array([[0.0, 0.0], [c, 0.0]]), [0.1])
    assert np.all(np.isfinite(cl))
    assert np.allclose(np.hypot(cl[:, 0] - c / 2, cl[:, 1]), c / 2)  # on the circle on the chord
    assert np.min(cl[:, 1]) == pytest.approx(-c / 2, rel=1e-3)  # bulging to the right of A -> B
