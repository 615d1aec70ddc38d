"""Self-checks of the MuJoCo reference harness (tests/mujoco_chain.py).

Every case here has a closed form (or a 2-unknown root-find) and uses no
rodcad code, so a failure means the harness, not rodcad, is wrong.
"""

import numpy as np
import pytest
from mujoco_chain import settle_chain
from scipy.optimize import least_squares

INF = np.inf


def _points(theta, lengths, anchor_a):
    seg = np.column_stack([np.cos(theta), np.sin(theta)]) * np.asarray(lengths, float)[:, None]
    return np.vstack([anchor_a, np.asarray(anchor_a, float) + np.cumsum(seg, axis=0)])


def _arc_start(lengths, anchor_a, anchor_b, sag=0.8):
    """A valid (closed) start: theta linear in i (a circular-arc polygon), solved for A->B."""
    lengths = np.asarray(lengths, float)
    idx = np.arange(lengths.size)
    target = np.asarray(anchor_b, float) - np.asarray(anchor_a, float)

    def res(z):
        th = z[0] + z[1] * idx
        return np.array([lengths @ np.cos(th), lengths @ np.sin(th)]) - target

    sol = least_squares(res, [-sag, 2 * sag / max(lengths.size - 1, 1)], xtol=1e-15, ftol=1e-15, gtol=1e-15)
    assert np.max(np.abs(res(sol.x))) < 1e-12
    return sol.x[0] + sol.x[1] * idx


def _check_common(r, n, span):
    assert r["converged"]
    assert r["points"].shape == (n + 1, 2)
    assert r["angles"].shape == (n,)
    assert r["kinetic"] < 1e-15
    assert r["end_error"] < 1e-7 * span


# --------------------------------------------------------------------------- (1)
def test_two_equal_rods_symmetric_v():
    a, b = np.array([0.0, 0.0]), np.array([1.2, 0.0])
    t = np.arccos(0.6)
    r = settle_chain([1.0, 1.0], [1.0, 1.0], a, b, angles0=[-t, t])
    _check_common(r, 2, 1.2)
    expected = np.array([[0.0, 0.0], [0.6, -np.sqrt(1 - 0.36)], [1.2, 0.0]])
    assert np.max(np.abs(r["points"] - expected)) < 1e-7
    assert np.allclose(r["angles"], [-t, t], atol=1e-7)
    assert r["limit_violation"] == 0.0


# --------------------------------------------------------------------------- (2)
@pytest.mark.parametrize(
    "n, anchor_b",
    [(6, (4.0, 0.0)), (9, (6.0, 1.5)), (12, (8.0, -3.0))],
)
def test_discrete_catenary_tan_theta_linear(n, anchor_b):
    """Equal rods, equal masses, com at mid-length, free joints.

    Horizontal tension H is constant and the vertical pin force grows by m g per
    rod; a rod with its weight at mid-length points along the mean of its two
    end forces, so tan(theta_i) = (V_0 + (i + 1/2) m g) / H is linear in i.
    """
    lengths, masses = np.ones(n), np.full(n, 0.7)
    a, b = np.array([0.0, 0.0]), np.asarray(anchor_b, float)
    span = np.linalg.norm(b - a)
    r = settle_chain(lengths, masses, a, b, angles0=_arc_start(lengths, a, b))
    _check_common(r, n, span)

    tan = np.tan(r["angles"])
    assert np.max(np.abs(np.diff(tan, 2))) < 1e-6
    assert np.all(np.diff(tan) > 0)  # hanging (convex), not an arch

    # closed form: tan(theta_i) = p + q i with (p, q) fixed by the closure
    idx = np.arange(n)

    def closure(z):
        t = z[0] + z[1] * idx
        return np.array([np.sum(1 / np.hypot(1, t)), np.sum(t / np.hypot(1, t))]) - (b - a)

    sol = least_squares(closure, [-1.0, 2.0 / n], xtol=1e-15, ftol=1e-15, gtol=1e-15)
    assert np.max(np.abs(closure(sol.x))) < 1e-12
    exact = _points(np.arctan(sol.x[0] + sol.x[1] * idx), lengths, a)
    assert np.max(np.linalg.norm(r["points"] - exact, axis=1)) < 1e-6 * span


# --------------------------------------------------------------------------- (3)
def test_three_rods_pressed_into_both_limits():
    """Three equal rods, level anchors, hi = 0.1 on both interior joints.

    With 3 rods the configuration has one degree of freedom, so both bends can
    sit at 0.1 only if the span is 1 + 2 cos(0.1) (theta = -0.1, 0, 0.1); near
    that configuration one bend grows while the other shrinks, so it is the
    only feasible one.  With equal masses that shape is also the free
    equilibrium (the limits would just touch), so the last rod is made heavy:
    free, the bends would be ~(0.055, 0.139); limited, the limit presses and
    holds them at exactly (0.1, 0.1).
    """
    h = 0.1
    span = 1 + 2 * np.cos(h)
    a, b = np.array([0.0, 0.0]), np.array([span, 0.0])
    lengths, masses = [1.0, 1.0, 1.0], [1.0, 1.0, 4.0]
    theta_exact = np.array([-h, 0.0, h])

    free = settle_chain(lengths, masses, a, b, angles0=theta_exact)
    assert free["converged"]
    assert np.max(np.abs(np.diff(free["angles"]) - h)) > 0.03  # the limit really is needed

    r = settle_chain(lengths, masses, a, b, angles0=theta_exact, limits=[(-INF, h), (-INF, h)])
    _check_common(r, 3, span)
    assert np.max(np.abs(np.diff(r["angles"]) - h)) < 1e-6
    assert r["limit_violation"] < 1e-6
    assert np.max(np.linalg.norm(r["points"] - _points(theta_exact, lengths, a), axis=1)) < 1e-6 * span


@pytest.mark.parametrize("side, bend", [("hi", 0.45), ("hi", 0.2), ("lo", 1.2)])
def test_four_rods_middle_joint_limit(side, bend):
    """Four equal rods, level anchors, a limit on the middle joint only.

    The problem is mirror symmetric, so the limited equilibrium is
    theta = (-c, -bend/2, bend/2, c) with 2 cos c + 2 cos(bend/2) = span.
    The free middle bend is ~0.856 (span 3), so hi < 0.856 or lo > 0.856 press.
    The start (middle bend 0.6) violates the lo limit: exercises the harness'
    soft first phase.
    """
    span = 3.0
    a, b = np.array([0.0, 0.0]), np.array([span, 0.0])
    lengths, masses = np.ones(4), np.ones(4)
    b0 = 0.3
    c0 = np.arccos(span / 2 - np.cos(b0))
    start = np.array([-c0, -b0, b0, c0])
    lim = [(-INF, INF), (-INF, bend) if side == "hi" else (bend, INF), (-INF, INF)]

    free = settle_chain(lengths, masses, a, b, angles0=start)
    free_bend = np.diff(free["angles"])[1]
    assert (free_bend > bend + 0.1) if side == "hi" else (free_bend < bend - 0.1)

    r = settle_chain(lengths, masses, a, b, angles0=start, limits=lim)
    _check_common(r, 4, span)
    c = np.arccos(span / 2 - np.cos(bend / 2))
    theta_exact = np.array([-c, -bend / 2, bend / 2, c])
    assert abs(np.diff(r["angles"])[1] - bend) < 1e-6
    assert r["limit_violation"] < 1e-6
    assert np.max(np.abs(r["angles"] - theta_exact)) < 1e-6
    assert np.max(np.linalg.norm(r["points"] - _points(theta_exact, lengths, a), axis=1)) < 1e-6 * span
