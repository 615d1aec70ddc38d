"""Target curve forms: every one runs from A to B and has the shape it names."""

from __future__ import annotations

import numpy as np
import pytest

from rodcad.design.targets import (
    arc,
    catenary,
    heart,
    make_target,
    polygon,
    semicircle,
    svg_path,
)

A, B = np.array([0.0, 0.0]), np.array([200.0, 0.0])


@pytest.mark.parametrize(
    "form, params",
    [
        ("semicircle", {}),
        ("arc", {"sag": 40}),
        ("arc", {"sag": 150}),
        ("triangle", {"depth": 120}),
        ("polygon", {"sides": 3}),
        ("heart", {}),
        ("catenary", {"length": 300}),
        ("function", {"y": "0.01*x*(x-200)"}),
        ("svg", {"d": "M 0 0 C 50 100 150 100 200 0"}),
        ("polyline", {"points": [[0, 0], [100, -50], [200, 0]]}),
    ],
)
def test_forms_run_from_a_to_b(form, params):
    c = make_target(form, A, B, **params)
    assert c.ndim == 2 and c.shape[1] == 2 and len(c) >= 3
    np.testing.assert_array_equal(c[0], A)
    np.testing.assert_array_equal(c[-1], B)
    assert c[:, 1].max() <= 1e-9  # everything hangs below the anchors


def test_semicircle_is_a_half_circle():
    c = semicircle(A, B)
    np.testing.assert_allclose(np.hypot(c[:, 0] - 100, c[:, 1]), 100, rtol=1e-12)
    assert c[:, 1].min() == pytest.approx(-100, rel=1e-4)


def test_arc_sag_and_polygon_edges():
    c = arc(A, B, sag=40)
    assert c[:, 1].min() == pytest.approx(-40, rel=1e-4)
    p = polygon(A, B, 3)
    np.testing.assert_allclose(np.hypot(*np.diff(p, axis=0).T), 100.0)  # half hexagon


def test_catenary_has_the_requested_length():
    c = catenary(A, B, length=300, samples=4000)
    assert np.hypot(*np.diff(c, axis=0).T).sum() == pytest.approx(300, rel=1e-5)


def test_svg_is_mapped_onto_the_anchors():
    c = svg_path((10, 5), (110, 5), "M 0 0 L 50 50 L 100 0")  # a V in SVG (y down)
    assert c[:, 1].min() == pytest.approx(5 - 50, rel=1e-9)


@pytest.mark.parametrize(
    "form, params, match",
    [
        ("blob", {}, "unknown target form 'blob'"),
        ("arc", {}, "needs sag"),
        ("arc", {"sag": -1}, "sag must be positive"),
        ("triangle", {"depth": 5, "size": 2}, "takes no size"),
        ("function", {"y": "x**2"}, "must pass through the anchors"),
        ("function", {"y": "__import__('os')"}, "unknown name|unsupported"),
        ("catenary", {"length": 100}, "must exceed the anchor distance"),
        ("polyline", {"points": [[1, 0], [200, 0]]}, "must start at anchor A"),
        ("svg", {"d": "M 0 0 L 10 10 Z"}, "closed"),
    ],
)
def test_bad_target_parameters(form, params, match):
    with pytest.raises(ValueError, match=match):
        make_target(form, A, B, **params)


def test_heart_is_a_hangable_lower_outline():
    c = heart(A, B)
    d = np.diff(c, axis=0)
    assert np.all(d[:, 0] > 0)  # every chord points from A toward B: a chain in tension
    turn = np.degrees(np.diff(np.unwrap(np.arctan2(d[:, 1], d[:, 0]))))
    assert turn.min() > -1e-9  # no concave bend: the lobes' tops and the dip are the mount
    assert turn.max() == pytest.approx(90.0, abs=1e-6)  # the tip of a square heart
    assert c[np.argmin(c[:, 1])] == pytest.approx([100.0, -200 * 1.5 / (np.sqrt(2) + 1)], abs=1e-9)
    assert np.degrees(np.arctan2(d[0, 1], d[0, 0])) < -85  # vertical at the widest point


@pytest.mark.parametrize("expr, words", [
    ("9**9**9", "cannot evaluate"),            # no unbounded integer arithmetic: floats overflow at once
    ("'%s' % x", "only numbers"),              # strings are refused
    ("x" + "+x" * 1000, "characters long"),
    ("sin(" * 80 + "x" + ")" * 80, "nests more than"),
])
def test_function_targets_refuse_expressions_that_run_away(expr, words):
    import time

    from rodcad.design.targets import make_target

    t0 = time.perf_counter()
    with pytest.raises(ValueError, match=words):
        make_target("function", (0, 0), (200, 0), y=expr)
    assert time.perf_counter() - t0 < 1.0
