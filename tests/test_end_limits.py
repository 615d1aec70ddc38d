"""Anchor stops (``solve_equilibrium(..., end_limits=...)``): bounds on the absolute angles of
the first and last rods, checked against MuJoCo (the first hinge's range; a fixed tendon over
every hinge for the last rod's angle) and against statics."""

from __future__ import annotations

import numpy as np
import pytest

from optimize import solve_equilibrium

mujoco = pytest.importorskip("mujoco")
from mujoco_chain import settle_chain  # noqa: E402

G = 9.81


def _chain(seed: int, n: int = 6):
    rng = np.random.default_rng(seed)
    lengths = rng.uniform(0.8, 1.2, n)
    masses = rng.uniform(0.5, 2.0, n)
    com = np.column_stack([lengths * rng.uniform(0.4, 0.6, n), rng.uniform(-0.05, 0.05, n)])
    a, b = np.zeros(2), np.array([0.7 * lengths.sum(), rng.uniform(-0.3, 0.3)])
    return lengths, masses, com, a, b


def _statics(r, lengths, masses, com, a, b):
    """Every rod in force and moment balance is implied by the whole chain's: check the sum
    of forces and the moment about A, fixture moments included."""
    w = masses.sum() * G
    np.testing.assert_allclose(r.reaction + r.reaction_a, [0.0, w], atol=1e-9 * w)
    th = r.angles
    u = np.column_stack([np.cos(th), np.sin(th)])
    v = np.column_stack([-np.sin(th), np.cos(th)])
    c = r.points[:-1] + com[:, :1] * u + com[:, 1:] * v
    arm = c - a
    moment = (float(np.sum(arm[:, 0] * (-masses * G)))
              + (b - a)[0] * r.reaction[1] - (b - a)[1] * r.reaction[0] + float(np.sum(r.info["end_moments"])))
    assert abs(moment) < 1e-9 * w * lengths.sum()
    assert np.hypot(*(r.points[-1] - b)) < 1e-12 * lengths.sum()
    np.testing.assert_allclose(np.hypot(*np.diff(r.points, axis=0).T), lengths, rtol=1e-12)


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("end", ["first", "last", "both"])
def test_anchor_stops_agree_with_mujoco(seed, end):
    lengths, masses, com, a, b = _chain(seed)
    free = solve_equilibrium(lengths, masses, a, b, com=com)
    e = np.array([[-np.inf, np.inf], [-np.inf, np.inf]])
    if end in ("first", "both"):
        e[0, 0] = free.angles[0] + 0.2  # the first rod is held up, 0.2 rad above where it hangs
    if end in ("last", "both"):
        e[1, 1] = free.angles[-1] - 0.2  # the last rod is held down
    r = solve_equilibrium(lengths, masses, a, b, com=com, end_limits=e)
    assert r.success and r.stable and r.kkt_residual < 1e-9, r.message
    _statics(r, lengths, masses, com, a, b)
    held = r.info["end_active"]
    if end in ("first", "both"):
        assert held[0] == -1 and r.angles[0] == pytest.approx(e[0, 0], abs=1e-12)
        assert r.info["end_moments"][0] > 0  # the fixture pushes the rod up
    if end in ("last", "both"):
        assert held[1] == 1 and r.angles[-1] == pytest.approx(e[1, 1], abs=1e-12)
        assert r.info["end_moments"][1] < 0  # and the last one down
    mj = settle_chain(lengths, masses, a, b, com=com, angles0=free.angles, end_limits=e)
    assert mj["converged"]
    assert np.max(np.hypot(*(mj["points"] - r.points).T)) < 1e-5 * np.hypot(*(b - a))


def test_anchor_stops_with_joint_stops_next_to_the_held_rod_agree_with_mujoco():
    """The joint after the held first rod has a stop that binds too (the shorter chain's end
    limit, solved recursively)."""
    lengths, masses, com, a, b = _chain(7)
    free = solve_equilibrium(lengths, masses, a, b, com=com)
    e = np.array([[free.angles[0] + 0.3, np.inf], [-np.inf, np.inf]])
    held = solve_equilibrium(lengths, masses, a, b, com=com, end_limits=e)
    limits = np.tile([-np.inf, np.inf], (len(lengths) - 1, 1))
    limits[0, 1] = np.diff(held.angles)[0] - 0.15  # joint 0 may not bend as far as it wants
    r = solve_equilibrium(lengths, masses, a, b, com=com, limits=limits, end_limits=e)
    assert r.success and r.stable, r.message
    assert r.active[0] == 1 and r.moments[0] < 0 and r.info["end_active"][0] == -1
    _statics(r, lengths, masses, com, a, b)
    mj = settle_chain(lengths, masses, a, b, com=com, limits=limits, angles0=free.angles, end_limits=e)
    assert mj["converged"] and np.max(np.hypot(*(mj["points"] - r.points).T)) < 1e-5 * np.hypot(*(b - a))


def test_end_limits_that_do_not_bind_change_nothing():
    lengths, masses, com, a, b = _chain(3)
    free = solve_equilibrium(lengths, masses, a, b, com=com)
    e = [[free.angles[0] - 0.1, free.angles[0] + 0.1], [-np.inf, np.inf]]
    r = solve_equilibrium(lengths, masses, a, b, com=com, end_limits=e)
    # the free chain takes the fast path, the one with stops the general solver: the same
    # equilibrium to round-off
    np.testing.assert_allclose(r.points, free.points, rtol=0, atol=1e-12 * lengths.sum())
    assert list(r.info["end_active"]) == [0, 0] and not np.any(r.info["end_moments"])
    same = solve_equilibrium(lengths, masses, a, b, com=com, end_limits=[[-np.inf, np.inf]] * 2)
    np.testing.assert_array_equal(same.points, free.points)  # no bounds: the same problem, the same path


def test_bad_end_limits_are_explained():
    lengths, masses, com, a, b = _chain(0)
    with pytest.raises(ValueError, match="lo <= hi"):
        solve_equilibrium(lengths, masses, a, b, end_limits=[[1.0, 0.0], [-np.inf, np.inf]])
    with pytest.raises(ValueError, match="exact model"):
        solve_equilibrium(lengths, masses, a, b, end_limits=[[0.0, 0.1], [-np.inf, np.inf]], model="penalty")
