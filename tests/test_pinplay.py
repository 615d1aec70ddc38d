"""Pins in their holes (optimize.chain.pinplay) and the compensation for their play
(optimize.chain.compensate), against an independent model and against invariants.

The independent model (tests/pinhole_model.py) shares no code with optimize: every pin a
free point, every hole a disc of radius c/2 its centre must stay inside, rods rigid, the
potential energy minimised by SLSQP. SLSQP stops where the energy is flat to about 1e-16 of
its scale; positions are then determined to about 1e-8 of the chain's size, so the two models
must agree to 1e-6 of the size (the play itself moves the chain by about 1e-2 of its size).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from optimize import compensate_pin_play, solve_equilibrium, solve_pin_play
from pinhole_model import hang_pins_in_holes

DATA = Path(__file__).parent / "data" / "example_chains.json"


def random_chain(seed: int, kind: str):
    """A random chain: kind "free", "stops" (a third of the joints held by stops on the hi
    side at 0.7 of their free bend) or "ends" (an anchor stop that lifts the first rod, and
    one that holds the last rod down)."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 10))
    l = rng.uniform(20, 40, n)
    m = rng.uniform(0.5, 2.0, n)
    com = np.column_stack([l * rng.uniform(0.4, 0.6, n), l * rng.uniform(-0.1, 0.1, n)])
    a, b = np.zeros(2), np.array([0.7 * l.sum(), rng.uniform(-10, 10)])
    free = solve_equilibrium(l, m, a, b, com=com)
    lim = np.tile([-np.inf, np.inf], (n - 1, 1))
    ends = None
    if kind == "stops":
        j = rng.choice(n - 1, size=max(1, n // 3), replace=False)
        lim[j, 1] = 0.7 * free.bends[j]
    elif kind == "ends":
        t0, t1 = free.angles[0], free.angles[-1]
        ends = np.array([[t0 + 0.15, t0 + 0.15 + np.pi], [t1 - 0.1 - np.pi, t1 - 0.1]])
    c = rng.uniform(0.2, 1.0, n + 1)
    return dict(l=l, m=m, com=com, a=a, b=b, lim=lim, ends=ends, c=c)


def reference(ch, spacings, com, lim, ends, c):
    """The independent model, started from the chain without play whose rods are longer by
    half the clearance at each end (the holes placed along its chords)."""
    half = 0.5 * c
    st = solve_equilibrium(spacings + half[:-1] + half[1:], ch["m"], ch["a"], ch["b"],
                           com=com + np.column_stack([half[:-1], 0 * half[:-1]]), limits=lim, end_limits=ends)
    theta = st.angles[0] + np.concatenate([[0.0], np.cumsum(np.angle(np.exp(1j * st.bends)))])
    start = st.points[:-1] + half[:-1, None] * np.column_stack([np.cos(theta), np.sin(theta)])
    windows = None
    if ends is not None:  # the anchor stops on the turn the start is on; one bound allows
        windows = ends.copy()  # the half turn on its side (optimize.chain.endlimits.limit_turn)
        for e, t in ((0, theta[0]), (1, theta[-1])):
            lo, hi = windows[e]
            if np.isinf(lo) and np.isinf(hi):
                continue
            windows[e] = [hi - np.pi if np.isinf(lo) else lo, lo + np.pi if np.isinf(hi) else hi]
            windows[e] += 2 * np.pi * np.round((t - windows[e].mean()) / (2 * np.pi))
    return hang_pins_in_holes(spacings, ch["m"], ch["a"], ch["b"], c, com, start, theta,
                              limits=lim, end_limits=windows, ftol=1e-13)


def size_of(points, a, b):
    return max(np.ptp(points[:, 0]), np.ptp(points[:, 1]), float(np.hypot(*(b - a))))


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("kind", ["free", "stops", "ends"])
def test_agrees_with_independent_model(seed, kind):
    ch = random_chain(seed, kind)
    r = solve_pin_play(ch["l"], ch["m"], ch["a"], ch["b"], clearance=ch["c"], com=ch["com"],
                       limits=ch["lim"], end_limits=ch["ends"])
    assert r.success and r.stable and r.kkt_residual < 1e-12
    if kind != "free":
        assert np.any(r.active) or np.any(r.end_active)  # the stops are what is tested
    ref = reference(ch, ch["l"], ch["com"], ch["lim"], ch["ends"], ch["c"])
    size = size_of(r.points, ch["a"], ch["b"])
    assert ref["max_violation"] < 1e-9 * size
    np.testing.assert_allclose(ref["points"], r.points, atol=1e-6 * size)
    np.testing.assert_allclose(ref["holes"], r.holes, atol=1e-6 * size)
    # the play moves the chain by far more than that
    plain = solve_equilibrium(ch["l"], ch["m"], ch["a"], ch["b"], com=ch["com"], limits=ch["lim"],
                              end_limits=ch["ends"])
    assert np.abs(plain.points - r.points).max() > 1e-3 * size


@pytest.mark.parametrize("seed", range(4))
def test_pins_bear_along_their_forces(seed):
    """Each pin sits c/2 from both its hole centres, on the line of the force it carries."""
    ch = random_chain(seed, "stops")
    r = solve_pin_play(ch["l"], ch["m"], ch["a"], ch["b"], clearance=ch["c"], com=ch["com"],
                       limits=ch["lim"])
    u = r.forces / np.linalg.norm(r.forces, axis=1)[:, None]
    tol = 1e-12 * ch["l"].sum()
    np.testing.assert_allclose(r.holes[:, 0] - r.points[:-1], 0.5 * ch["c"][:-1, None] * u[:-1], atol=tol)
    np.testing.assert_allclose(r.points[1:] - r.holes[:, 1], 0.5 * ch["c"][1:, None] * u[1:], atol=tol)
    np.testing.assert_allclose(np.linalg.norm(np.diff(r.holes, axis=1)[:, 0], axis=1), ch["l"], rtol=1e-13)
    # every rod in balance: its weight and the forces at its pins (moments about its first pin)
    g = 9.81
    for i in range(ch["l"].size):
        f_first, f_second = -r.forces[i], r.forces[i + 1]
        force = f_first + f_second + np.array([0.0, -g * ch["m"][i]])
        arm = r.points[i + 1] - r.points[i]
        carm = r.com[i] - r.points[i]
        moment = arm[0] * f_second[1] - arm[1] * f_second[0] - carm[0] * g * ch["m"][i]
        stop = (r.moments[i] if i < ch["l"].size - 1 else 0.0) - (r.moments[i - 1] if i > 0 else 0.0)
        scale = g * ch["m"].sum() * ch["l"].sum()
        assert np.abs(force).max() < 1e-12 * g * ch["m"].sum()
        assert abs(moment - stop) < 1e-11 * scale


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("kind", ["free", "stops", "ends"])
def test_zero_clearance_is_the_chain_without_play(seed, kind):
    ch = random_chain(seed, kind)
    r = solve_pin_play(ch["l"], ch["m"], ch["a"], ch["b"], clearance=0.0, com=ch["com"],
                       limits=ch["lim"], end_limits=ch["ends"])
    st = solve_equilibrium(ch["l"], ch["m"], ch["a"], ch["b"], com=ch["com"], limits=ch["lim"],
                           end_limits=ch["ends"])
    assert r.success
    np.testing.assert_allclose(r.points, st.points, atol=1e-12 * ch["l"].sum())
    np.testing.assert_allclose(r.reaction, st.reaction, rtol=1e-10)
    np.testing.assert_array_equal(r.active, st.active)


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("kind", ["stops", "ends"])
def test_mirror_symmetry(seed, kind):
    """Mirrored in x (rods reversed): the mirrored equilibrium. A rod's hole-frame centre of
    mass (along, perp) becomes (spacing - along, perp); bend limits reverse their order; an
    anchor stop [lo, hi] on one end becomes [-hi, -lo] on the other."""
    ch = random_chain(seed, kind)
    r = solve_pin_play(ch["l"], ch["m"], ch["a"], ch["b"], clearance=ch["c"], com=ch["com"],
                       limits=ch["lim"], end_limits=ch["ends"])
    M = np.array([-1.0, 1.0])
    com = np.column_stack([ch["l"] - ch["com"][:, 0], ch["com"][:, 1]])[::-1]
    ends = None if ch["ends"] is None else -ch["ends"][::-1, ::-1]
    rm = solve_pin_play(ch["l"][::-1], ch["m"][::-1], M * ch["b"], M * ch["a"], clearance=ch["c"][::-1],
                        com=com, limits=ch["lim"][::-1], end_limits=ends)
    assert r.success and rm.success
    np.testing.assert_allclose(rm.points, (M * r.points)[::-1], atol=1e-11 * ch["l"].sum())


@pytest.mark.parametrize("seed", range(3))
def test_mass_scaling_leaves_the_shape(seed):
    ch = random_chain(seed, "stops")
    kw = dict(clearance=ch["c"], com=ch["com"], limits=ch["lim"])
    r1 = solve_pin_play(ch["l"], ch["m"], ch["a"], ch["b"], **kw)
    r2 = solve_pin_play(ch["l"], 37.5 * ch["m"], ch["a"], ch["b"], **kw)
    np.testing.assert_allclose(r2.points, r1.points, atol=1e-12 * ch["l"].sum())
    np.testing.assert_allclose(r2.reaction, 37.5 * r1.reaction, rtol=1e-10)


@pytest.mark.parametrize("seed", range(3))
def test_fixed_point_path_agrees(seed):
    """The fallback (a fixed point over the chain without play) finds the same equilibrium."""
    for kind in ("stops", "ends"):
        ch = random_chain(seed, kind)
        kw = dict(clearance=ch["c"], com=ch["com"], limits=ch["lim"], end_limits=ch["ends"])
        r1 = solve_pin_play(ch["l"], ch["m"], ch["a"], ch["b"], method="dual", **kw)
        r2 = solve_pin_play(ch["l"], ch["m"], ch["a"], ch["b"], method="fixed-point", **kw)
        assert r1.success and r2.success and r2.info["path"] == "fixed-point"
        np.testing.assert_allclose(r2.points, r1.points, atol=1e-11 * ch["l"].sum())


def test_fused_joint_has_no_play():
    """A fused joint (lo == hi) is one printed piece: no pin, no play there."""
    ch = random_chain(5, "free")
    n = ch["l"].size
    lim = ch["lim"].copy()
    st = solve_equilibrium(ch["l"], ch["m"], ch["a"], ch["b"], com=ch["com"])
    lim[1] = st.bends[1]
    c0 = ch["c"].copy()
    c0[2] = 0.0
    r1 = solve_pin_play(ch["l"], ch["m"], ch["a"], ch["b"], clearance=ch["c"], com=ch["com"], limits=lim)
    r2 = solve_pin_play(ch["l"], ch["m"], ch["a"], ch["b"], clearance=c0, com=ch["com"], limits=lim)
    np.testing.assert_allclose(r1.points, r2.points, atol=1e-12 * ch["l"].sum())
    assert r1.info["clearance"][2] == 0.0 and n > 2


def test_unreachable_anchors_raise():
    with pytest.raises(ValueError, match="too far apart"):
        solve_pin_play([1.0, 1.0], [1.0, 1.0], (0, 0), (2.1, 0), clearance=0.01)
    with pytest.raises(ValueError, match="clearance"):
        solve_pin_play([1.0, 1.0], [1.0, 1.0], (0, 0), (1.5, 0), clearance=[0.1, 0.1])


# --- compensation -------------------------------------------------------------------------

def compensated(ch, c, st):
    return compensate_pin_play(st.points, ch["m"], st.reaction, clearance=c, com=ch["com"],
                               limits=ch["lim"], end_limits=ch["ends"], g=9.81)


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("kind", ["free", "stops", "ends"])
def test_compensated_chain_hangs_on_its_design(seed, kind):
    ch = random_chain(seed, kind)
    st = solve_equilibrium(ch["l"], ch["m"], ch["a"], ch["b"], com=ch["com"], limits=ch["lim"],
                           end_limits=ch["ends"])
    comp = compensated(ch, ch["c"], st)
    size = size_of(st.points, ch["a"], ch["b"])
    r = solve_pin_play(comp.spacings, ch["m"], ch["a"], ch["b"], clearance=ch["c"], com=comp.com,
                       limits=comp.limits, end_limits=comp.end_limits)
    assert r.success and r.stable
    np.testing.assert_allclose(r.points, st.points, atol=1e-10 * size)
    ref = reference(ch, comp.spacings, comp.com, comp.limits, comp.end_limits, ch["c"])
    np.testing.assert_allclose(ref["points"], st.points, atol=1e-6 * size)
    # where the forces run near the chords, the spacing is about l - c (half c at each end)
    expect = 0.5 * (ch["c"][:-1] + ch["c"][1:])
    assert np.all(comp.shortening <= expect + 1e-12)
    assert np.all(comp.shortening > 0.5 * expect)


def load_example(name):
    ex = json.loads(DATA.read_text())["chains"][name]
    n = len(ex["lengths"])

    def rad(pair, default):
        return [default[k] if pair is None or pair[k] is None else np.radians(pair[k]) for k in (0, 1)]

    free = (-np.inf, np.inf)
    lim = np.array([rad(p, free) for p in ex["limits_deg"]])
    ends = np.array([rad(p, free) for p in ex["anchor_limits_deg"]])
    return dict(l=np.array(ex["lengths"]), m=np.array(ex["masses"]), com=np.array(ex["com"]),
                a=np.array(ex["anchors"][0], float), b=np.array(ex["anchors"][1], float), lim=lim,
                ends=None if np.all(np.isinf(ends)) else ends, n=n)


@pytest.mark.parametrize("name", ["semicircle", "necklace", "heart"])
def test_examples_compensated_against_independent_model(name):
    """The shipped semicircle, necklace and heart with 3.0 mm pins in 3.2 mm holes: the
    independent model hangs the compensated rods on the design (within 0.05 % of the size;
    in fact to its own tolerance) and the uncompensated ones well off: every pin's play adds
    about its clearance (0.2 mm, 0.1 % of a 200 mm chain) to a rod; today's designs measure
    0.39 % (semicircle), 0.77 % (necklace) and 1.07 % (heart)."""
    ch = load_example(name)
    c = np.full(ch["n"] + 1, 0.2)
    st = solve_equilibrium(ch["l"], ch["m"], ch["a"], ch["b"], com=ch["com"], limits=ch["lim"],
                           end_limits=ch["ends"])
    size = size_of(st.points, ch["a"], ch["b"])
    comp = compensated(ch, c, st)
    ref_c = reference(ch, comp.spacings, comp.com, comp.limits, comp.end_limits, c)
    ref_u = reference(ch, ch["l"], ch["com"], ch["lim"], ch["ends"], c)
    err_c = np.linalg.norm(ref_c["points"] - st.points, axis=1).max()
    err_u = np.linalg.norm(ref_u["points"] - st.points, axis=1).max()
    print(f"{name}: size {size:.1f} mm, uncompensated {err_u:.3f} mm ({100 * err_u / size:.3f} %), "
          f"compensated {err_c:.2e} mm ({100 * err_c / size:.2e} %)")
    assert err_c < 5e-4 * size
    assert err_c < 1e-6 * size  # the compensation is exact: only the reference's tolerance is left
    assert 2e-3 * size < err_u < 1.5e-2 * size
    r = solve_pin_play(ch["l"], ch["m"], ch["a"], ch["b"], clearance=c, com=ch["com"],
                       limits=ch["lim"], end_limits=ch["ends"])
    np.testing.assert_allclose(ref_u["points"], r.points, atol=1e-6 * size)


def test_a_rod_wedged_between_its_pins():
    """One rod longer than the anchors are apart, held only because its holes let the pins
    in: it pushes (the pins bear on the inner sides of its holes). The dual's minimum sits on
    the rod's kink; the solver takes the rod on the other branch and agrees with the
    independent model."""
    r = solve_pin_play([1.0], [1.0], (0, 0), (0.95, 0.1), clearance=0.2)
    assert r.success and r.stable
    ref = hang_pins_in_holes([1.0], [1.0], np.zeros(2), np.array([0.95, 0.1]), np.full(2, 0.2), [[0.5, 0.0]],
                             [[0.0, -0.05]], [0.0], ftol=1e-14)
    np.testing.assert_allclose(ref["holes"], r.holes, atol=1e-6)
    axis = r.holes[0, 1] - r.holes[0, 0]
    assert axis @ r.forces[1] < 0  # the force at B pushes back along the rod: compression


@pytest.mark.parametrize("seed", range(3))
def test_two_sided_stop_keeps_its_pin(seed):
    """A joint held both ways by stops (lo == hi) but still pinned (``pinned``): the stops fix
    the bodies' relative angle, the pin still bears in its holes with its play. Against the
    independent model with that joint's stops as two inequalities; it differs from the same
    joint fused (no pin there) by about the clearance; the compensation with ``pinned`` puts
    the loaded pins on the design."""
    ch = random_chain(seed, "free")
    n = ch["l"].size
    free = solve_equilibrium(ch["l"], ch["m"], ch["a"], ch["b"], com=ch["com"])
    j = n // 2 - 1
    lim = np.tile([-np.inf, np.inf], (n - 1, 1))
    lim[j] = free.bends[j] * 0.8
    pinned = np.zeros(n - 1, dtype=bool)
    pinned[j] = True
    size = size_of(free.points, ch["a"], ch["b"])
    r = solve_pin_play(ch["l"], ch["m"], ch["a"], ch["b"], clearance=ch["c"], com=ch["com"], limits=lim,
                       pinned=pinned)
    assert r.success and r.stable and r.kkt_residual < 1e-10
    assert abs(r.bends[j] - lim[j, 0]) < 1e-9  # the bodies held at the stop
    ref = reference(ch, ch["l"], ch["com"], lim, None, ch["c"])
    np.testing.assert_allclose(ref["points"], r.points, atol=1e-6 * size)
    fused = solve_pin_play(ch["l"], ch["m"], ch["a"], ch["b"], clearance=ch["c"], com=ch["com"], limits=lim)
    assert np.abs(fused.points - r.points).max() > 0.05 * ch["c"][j + 1]
    st = solve_equilibrium(ch["l"], ch["m"], ch["a"], ch["b"], com=ch["com"], limits=lim)
    comp = compensate_pin_play(st.points, ch["m"], st.reaction, clearance=ch["c"], com=ch["com"], limits=lim,
                               pinned=pinned)
    assert comp.clearance[j + 1] == ch["c"][j + 1]
    back = solve_pin_play(comp.spacings, ch["m"], ch["a"], ch["b"], clearance=ch["c"], com=comp.com,
                          limits=comp.limits, pinned=pinned)
    np.testing.assert_allclose(back.points, st.points, atol=1e-10 * size)
