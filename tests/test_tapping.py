"""The chain tapped until it settles (rodcad.design.tapping), against the exact statics.

The truth here is not the simulation's: the designed equilibrium is
:func:`optimize.solve_equilibrium`'s, and the band of shapes pin friction lets the chain rest in
is :func:`optimize.friction_band`'s (mu 0.3, 1.5 mm pins, its capacities fed to MuJoCo).
Tolerances come from what is measured, per rest: MuJoCo's own settling residuals as the result
reports them (the tip's distance from B, the largest stop overshoot times the chain's length,
and the drift a joint can make at the rest tolerance while rest is being seen), and the band's
linearisation error. tests/test_friction.py takes that as band^2 / size; a chain hung from far
off comes to rest at the nonlinear band's edge, which lies off the linear one by about
band^2 / l for a rod of length l turned by band / l (the necklace rests 0.0065 mm, 1 % of its
band, past the linear band, more than band^2 / size = 0.0018 mm allows), so band^2 / l_min.

Tapping randomises the chain within its band: hung close to the design (within its band) a
chain ends further out after taps than it was hung; hung from well beyond the band it slides
in, stops out towards the band's edge, and taps bring it closer (measured and asserted below).
"""

from __future__ import annotations

import functools
import time

import numpy as np
import pytest

from optimize import friction_band, friction_capacity, solve_equilibrium
from optimize.chain import Chain
from optimize.chain.endlimits import limit_turn
from rodcad.design.tapping import band_scale, tap_chain
from test_pinplay import load_example, random_chain

CASES = [("random", "free", 0), ("random", "stops", 1), ("random", "ends", 2), ("random", "free", 3),
         ("random", "fused", 4), ("example", "semicircle", 0), ("example", "necklace", 0),
         ("example", "heart", 0)]


def case_id(case):
    return case[1] if case[0] == "example" else f"{case[1]}{case[2]}"


@functools.lru_cache(maxsize=None)
def setup(case):
    """(chain, equilibrium, band, size) of a case; "fused": a random free chain with two joints
    fused at their equilibrium bends (the equilibrium unchanged, those pins gone)."""
    kind, what, seed = case
    if kind == "example":
        ch = load_example(what)
    elif what == "fused":
        ch = random_chain(seed, "free")
        free = solve_equilibrium(ch["l"], ch["m"], ch["a"], ch["b"], com=ch["com"])
        for j in (0, ch["l"].size - 3):
            ch["lim"][j] = free.bends[j]
    else:
        ch = random_chain(seed, what)
    kw = dict(com=ch["com"], limits=ch["lim"], end_limits=ch["ends"])
    st = solve_equilibrium(ch["l"], ch["m"], ch["a"], ch["b"], **kw)
    assert st.success and st.stable
    fb = friction_band(ch["l"], ch["m"], ch["a"], ch["b"], mu=0.3, pin_radius=1.5, result=st, **kw)
    size = max(np.ptp(st.points[:, 0]), np.ptp(st.points[:, 1]))
    return ch, st, fb, size


def tap(case, **kw):
    ch, st, fb, _ = setup(case)
    kw.setdefault("capacity", fb.capacity)
    return tap_chain(ch["l"], ch["m"], ch["a"], ch["b"], design_angles=st.angles, com=ch["com"],
                     limits=ch["lim"], end_limits=ch["ends"], **kw)


def settling(r, ch) -> np.ndarray:
    """(n_taps + 1,) MuJoCo's settling error at each rest, from its own residuals: the closure
    (the tip off B), the stops' overshoot (rad) over at most the chain's length, the drift at
    the rest tolerance."""
    return r.end_error + ch["l"].sum() * r.violation + r.drift


@pytest.mark.parametrize("case", CASES, ids=case_id)
def test_every_rest_lies_in_the_friction_band(case):
    """Hung near the design (0.01 rad) and far off it (0.1 rad), then tapped 10 times: every
    rest has every joint within its band, plus MuJoCo's settling error and the band's
    linearisation error; that settling error is under a tenth of the band (what is measured
    is friction, not MuJoCo); and friction does hold the chain off its design, at least half
    the band out at the furthest rest."""
    ch, st, fb, size = setup(case)
    second_order = fb.band ** 2 / ch["l"].min()
    reach, excess = 0.0, 0.0
    for release, seed in ((0.01, 0), (0.1, 1)):
        r = tap(case, release=release, seed=seed)
        assert r.converged, r.message
        assert r.rests.shape == (11, ch["l"].size + 1, 2)
        settle = settling(r, ch)
        assert settle.max() < 0.1 * fb.band
        disp = np.linalg.norm(r.rests - st.points[None], axis=2)
        over = disp - (fb.per_joint[None] + second_order + settle[:, None])
        assert np.all(over <= 0), over.max()
        excess = max(excess, float((disp - fb.per_joint[None] - settle[:, None]).max()))
        np.testing.assert_allclose(r.deviation, disp.max(axis=1), rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(r.per_joint, disp[-1], rtol=1e-9, atol=1e-12)
        reach = max(reach, float(disp.max()))
    print(f"{case_id(case)}: band {fb.band:.3f} mm, furthest rest {reach:.3f} mm ({reach / fb.band:.0%}), "
          f"settling {settle.max():.1e} mm, beyond band + settling {excess:.1e} mm "
          f"(second order {second_order:.1e} mm)")
    assert reach >= 0.5 * fb.band


@pytest.mark.parametrize("case", CASES, ids=case_id)
def test_without_friction_the_chain_returns_to_its_design(case):
    """With no friction the chain hung 0.2 rad off returns to the design within MuJoCo's
    settling error (its frames, units and constraints are the design's), from a start far
    beyond that."""
    ch, st, fb, size = setup(case)
    r = tap(case, capacity=np.zeros(ch["l"].size + 1), release=0.2, n_taps=2, seed=2)
    assert r.converged, r.message
    assert r.band == 0.0 and r.energy == 0.0
    start = np.linalg.norm(r.start - st.points, axis=1).max()
    disp = np.linalg.norm(r.rests - st.points[None], axis=2)
    settle = settling(r, ch)
    print(f"{case_id(case)}: started {start:.2f} mm off, rests within {disp.max():.1e} mm "
          f"(settling {settle.max():.1e} mm)")
    assert start > fb.band
    assert np.all(disp <= settle[:, None] + 1e-12 * size)


@pytest.mark.parametrize("case", CASES, ids=case_id)
def test_tapping_brings_a_roughly_hung_chain_closer(case):
    """Hung 0.3 rad off (twice the band away on average) and let slide in gently, the chain stops
    where friction first holds it, out towards the band's edge; ten taps later it rests, on
    average over 8 seeds, no further from the design than that."""
    ch, st, fb, _ = setup(case)
    first, last, start = [], [], []
    for seed in range(8):
        r = tap(case, release=0.3, seed=seed)
        assert r.converged, r.message
        start.append(np.linalg.norm(r.start - st.points, axis=1).max())
        first.append(r.deviation[0])
        last.append(r.deviation[-1])
    first, last, start = np.array(first) / fb.band, np.array(last) / fb.band, np.array(start) / fb.band
    print(f"{case_id(case)}: let go {start.mean():.1f} bands off, hung {first.mean():.2f} band, "
          f"tapped {last.mean():.2f} band (closer in {np.sum(last < first)} of 8)")
    assert start.min() >= 1.0 and start.mean() >= 2.0
    assert last.mean() <= first.mean()


@pytest.mark.parametrize("case", [CASES[0], CASES[1], CASES[5], CASES[6]], ids=case_id)
def test_taps_carry_the_chain_beyond_its_band(case):
    """The default tap frees the pins: the median tap carries the chain past the exact band."""
    _, _, fb, _ = setup(case)
    peaks = np.concatenate([tap(case, seed=seed).peak for seed in (0, 1)])
    print(f"{case_id(case)}: peaks / band {np.round(np.quantile(peaks / fb.band, [0.1, 0.5, 0.9]), 2)}")
    assert np.median(peaks) >= fb.band


@pytest.mark.parametrize("case", [CASES[1], CASES[2], CASES[5], CASES[6]], ids=case_id)
def test_band_scale_is_the_friction_bands_own_cell(case):
    """The taps' yardstick: the band linearised on the design's held stops is the exact
    band's, where that band lies in one cell."""
    ch, st, fb, _ = setup(case)
    assert fb.cells == 1
    chain = Chain.from_args(ch["l"], ch["m"], ch["a"], ch["b"], ch["com"], ch["lim"], 9.81, ch["ends"])
    theta = np.unwrap(st.angles)
    ends = None
    if ch["ends"] is not None:  # the anchor stops on the turn the chain is on
        ends = ch["ends"].copy()
        for k, t in ((0, theta[0]), (1, theta[-1])):
            ends[k] += limit_turn(t, ends[k])
    scale = band_scale(chain, theta, fb.capacity, ends)
    np.testing.assert_allclose(scale.per_joint, fb.per_joint, rtol=1e-9, atol=1e-12 * fb.band)
    assert scale.energy > 0


def test_any_size_and_mass_taps_alike():
    """Lengths x10, masses x3 (capacities x30), or g x1000: the same rests, to scale."""
    case = CASES[1]
    ch, st, fb, size = setup(case)
    kw = dict(design_angles=st.angles, limits=ch["lim"], end_limits=ch["ends"], release=0.05, seed=3)
    base = tap(case, release=0.05, seed=3)
    big = tap_chain(10 * ch["l"], 3 * ch["m"], 10 * ch["a"], 10 * ch["b"], capacity=30 * fb.capacity,
                    com=10 * ch["com"], **kw)
    fast = tap_chain(ch["l"], ch["m"], ch["a"], ch["b"], capacity=1e3 * fb.capacity, com=ch["com"], g=9.81e3, **kw)
    np.testing.assert_allclose(big.rests, 10 * base.rests, rtol=0, atol=1e-9 * 10 * size)
    np.testing.assert_allclose(fast.rests, base.rests, rtol=0, atol=1e-9 * size)
    assert big.energy == pytest.approx(30 * base.energy, rel=1e-9)  # force x length


def test_same_seed_same_result():
    case = CASES[1]
    a, b, c = tap(case, release=0.05, seed=7), tap(case, release=0.05, seed=7), tap(case, release=0.05, seed=8)
    np.testing.assert_allclose(a.rests, b.rests, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(a.peak, b.peak)
    assert np.abs(a.rests - c.rests).max() > 1e-3 * setup(case)[2].band


def test_a_25_rod_chain_with_10_taps_takes_seconds():
    """A build runs this once per chain: 25 rods, a third of the joints on stops, 10 taps,
    in well under ten seconds on one core (the capacities straight from the joint forces: the
    exact band of this chain spans many cells and takes longer than the taps)."""
    rng = np.random.default_rng(5)
    n = 25
    l, m = rng.uniform(10, 20, n), rng.uniform(0.5, 2.0, n)
    a, b = np.zeros(2), np.array([0.7 * l.sum(), 5.0])
    free = solve_equilibrium(l, m, a, b)
    lim = np.tile([-np.inf, np.inf], (n - 1, 1))
    j = rng.choice(n - 1, size=n // 3, replace=False)
    lim[j, 1] = 0.7 * free.bends[j]
    st = solve_equilibrium(l, m, a, b, limits=lim)
    capacity = friction_capacity(st.reaction, m, mu=0.3, pin_radius=1.5)
    t0 = time.perf_counter()
    r = tap_chain(l, m, a, b, design_angles=st.angles, capacity=capacity, limits=lim)
    wall = time.perf_counter() - t0
    print(f"25 rods, 10 taps: {wall:.2f} s wall, {r.sim_time:.0f} sqrt(L/g) simulated; {r.message}")
    assert r.converged and np.any(st.active != 0)
    assert wall < 10.0


def test_bad_arguments():
    ch, st, fb, _ = setup(CASES[0])
    args = (ch["l"], ch["m"], ch["a"], ch["b"])
    with pytest.raises(ValueError):
        tap_chain(*args, design_angles=st.angles[:-1], capacity=fb.capacity)
    with pytest.raises(ValueError):
        tap_chain(*args, design_angles=st.angles, capacity=-fb.capacity)
    with pytest.raises(ValueError):
        tap_chain(*args, design_angles=st.angles, capacity=fb.capacity, release=-0.1)
