"""The paper's shape distance D~ (Eq. 4) and deviation vector D (Eq. 5) on hand examples."""

from __future__ import annotations

import ast
import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from optimize.distance import ShapeDistance, shape_distance

TARGET = np.array([[0.0, 0.0], [1.0, -1.0], [2.0, -1.5], [3.0, -1.0], [4.0, 0.0]])


def test_identical_shapes_are_at_distance_zero():
    d = shape_distance(TARGET, TARGET.copy())
    assert d.sum == 0.0 and d.max == 0.0 and d.mean == 0.0 and d.max_rel_span == 0.0
    assert d.deviation.shape == (2,) and np.all(d.deviation == 0.0)


@pytest.mark.parametrize("shift", [(3.0, 4.0), (-0.5, 0.0), (0.0, -2.0), (1e-3, -7e-3)])
def test_shifted_polyline(shift):
    """S = T + s at every joint: D = -(N+1) s, D~ = (N+1)|s|, every joint |s| away."""
    shift = np.asarray(shift)
    d = shape_distance(TARGET, TARGET + shift)
    n1 = len(TARGET)
    norm = math.hypot(*shift)
    assert d.deviation == pytest.approx(-n1 * shift, rel=1e-12, abs=1e-12)
    assert d.sum == pytest.approx(n1 * norm, rel=1e-12)
    assert d.max == pytest.approx(norm, rel=1e-12)
    assert d.mean == pytest.approx(norm, rel=1e-12)
    assert d.max_rel_span == pytest.approx(norm / 4.0, rel=1e-12)  # |B - A| = 4


def test_one_joint_off_by_a_3_4_5_triangle():
    sim = TARGET.copy()
    sim[2] += [3.0, -4.0]  # sagging 4 too low and 3 to the right
    d = shape_distance(TARGET, sim)
    assert d.sum == pytest.approx(5.0)
    assert d.max == pytest.approx(5.0)
    assert d.mean == pytest.approx(1.0)
    assert d.max_rel_span == pytest.approx(5.0 / 4.0)
    # target minus simulated: points back up and to the left, toward the target
    assert d.deviation.tolist() == pytest.approx([-3.0, 4.0])


def test_mirror_deviations_have_the_same_sum_and_opposite_direction():
    """The paper's Fig. 3b: too deep and too shallow by the same amount."""
    bump = np.array([[0, 0], [0, -0.3], [0, -0.5], [0, -0.3], [0, 0]])
    deep = shape_distance(TARGET, TARGET + bump)
    shallow = shape_distance(TARGET, TARGET - bump)
    assert deep.sum == pytest.approx(shallow.sum)
    assert deep.deviation == pytest.approx(-shallow.deviation)
    assert deep.deviation[1] > 0  # too deep: D points up, toward the target


def test_max_rel_span_uses_the_target_anchors():
    target = np.array([[10.0, 5.0], [13.0, 1.0], [16.0, 5.0]])  # |B - A| = 6
    sim = target.copy()
    sim[1, 1] -= 1.5
    assert shape_distance(target, sim).max_rel_span == pytest.approx(0.25)


def test_as_dict_is_json_friendly():
    d = shape_distance(TARGET, TARGET + [0.0, 1.0])
    out = d.as_dict()
    assert set(out) == {"sum_mm", "max_mm", "mean_mm", "max_rel_span", "deviation"}
    assert out["deviation"] == [0.0, -5.0]
    assert all(type(v) is float for k, v in out.items() if k != "deviation")
    assert json.loads(json.dumps(out)) == out


def test_coincident_anchors():
    target = np.array([[0.0, 0.0], [0.5, -1.0], [0.0, 0.0]])
    d = shape_distance(target, target + [0.0, 0.1])
    assert d.max_rel_span == math.inf
    assert d.as_dict()["max_rel_span"] is None
    json.dumps(d.as_dict(), allow_nan=False)
    assert shape_distance(target, target).max_rel_span == 0.0


def test_accepts_lists_and_returns_plain_floats():
    d = shape_distance([[0, 0], [1, 0]], [[0, 0], [1, 1]])
    assert isinstance(d, ShapeDistance)
    assert isinstance(d.sum, float) and isinstance(d.max, float) and isinstance(d.mean, float)
    assert d.sum == 1.0 and d.deviation.tolist() == [0.0, -1.0]


@pytest.mark.parametrize(
    "target, simulated, match",
    [
        (TARGET, TARGET[:-1], r"simulated has shape \(4, 2\) but target has shape \(5, 2\)"),
        (TARGET[:, :1], TARGET, r"target must have shape \(N\+1, 2\), got \(5, 1\)"),
        (TARGET, np.zeros((5, 3)), r"simulated must have shape \(N\+1, 2\), got \(5, 3\)"),
        (TARGET.ravel(), TARGET, r"target must have shape \(N\+1, 2\)"),
        (TARGET[:1], TARGET[:1], r"target must have at least 2 joints"),
        (np.where(np.eye(5, 2) > 0, np.nan, TARGET), TARGET, r"target\[0, 0\] is not finite"),
        (TARGET, TARGET + [[0, 0], [0, 0], [0, np.inf], [0, 0], [0, 0]], r"simulated\[2, 1\]"),
        ([["a", "b"], ["c", "d"]], TARGET, r"target must be an \(N\+1, 2\) array"),
    ],
)
def test_bad_arguments_name_the_argument(target, simulated, match):
    with pytest.raises(ValueError, match=match):
        shape_distance(target, simulated)


points = st.integers(2, 12).flatmap(
    lambda k: st.tuples(
        arrays(float, (k, 2), elements=st.floats(-1e3, 1e3)),
        arrays(float, (k, 2), elements=st.floats(-1e3, 1e3)),
    )
)


@settings(max_examples=60, deadline=None)
@given(points)
def test_invariants(pair):
    t, s = pair
    d = shape_distance(t, s)
    back = shape_distance(s, t)
    k = len(t)
    assert np.hypot(*d.deviation) <= d.sum * (1 + 1e-12) + 1e-9  # triangle inequality
    assert d.max <= d.sum * (1 + 1e-12) + 1e-12 <= k * d.max * (1 + 1e-12) + 1e-9
    assert d.mean == pytest.approx(d.sum / k)
    assert back.sum == pytest.approx(d.sum) and back.max == d.max
    assert back.deviation == pytest.approx(-d.deviation)


def test_module_imports_only_numpy_stdlib_and_its_own_package():
    tree = ast.parse(Path(__file__).parents[1].joinpath("optimize", "distance.py").read_text())
    names = {a.name.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    names |= {n.module.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module}
    assert names <= {"__future__", "math", "dataclasses", "numpy", "optimize"}, names  # optimize.validate: numpy only
