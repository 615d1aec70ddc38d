"""Joint hardware: the catalog's menu (rodcad.catalog.pins), the planner's choice per joint
(rodcad.design.hardware) and the masses designed with the hardware hanging on the rods
(rodcad.design.hung), against independent statics and textbook formulas."""

from __future__ import annotations

import math
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from optimize import friction_band, solve_equilibrium
from rodcad.catalog.loader import load_catalog
from rodcad.catalog.pins import DEFAULT_OPTIONS, PinOption
from rodcad.design.hardware import choose_hardware, newtons, solver_moment
from rodcad.design.loader import load_design
from rodcad import pipeline

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def semicircle():
    return pipeline.build(load_design("examples/semicircle.yaml"), cad=False)


def independent_pin_forces(points, masses, com, g, attached=None):
    """Every pin's force (N+1, 2) from each rod's free-body statics alone (force and moment
    balance of every rod, least squares over the unknown pin forces; free joints: no
    moments), with ``attached`` (N, 2) g of point masses at each rod's two hinge axes.
    The anchor fixture may hold a moment on each end rod. No rodcad or optimize code. Returns
    the forces and the equations' residual (relative to the weight)."""
    p = np.asarray(points, float)
    n = len(masses)
    att = np.zeros((n, 2)) if attached is None else np.asarray(attached, float)
    # unknowns: F_k (force of the part right of pin k on the part left of it), k = 0..N
    A = np.zeros((3 * n, 2 * (n + 1) + 2))  # and the anchor fixture's moments on the end rods
    A[2, -2] = A[3 * (n - 1) + 2, -1] = 1.0
    b = np.zeros(3 * n)
    for i in range(n):
        a, e = p[i], p[i + 1]
        u = (e - a) / np.hypot(*(e - a))
        v = np.array([-u[1], u[0]])
        c = a + com[i][0] * u + com[i][1] * v
        # rod i: pin i pulls it with -F_i (at a), pin i+1 with +F_{i+1} (at e), gravity
        A[3 * i:3 * i + 2, 2 * i:2 * i + 2] = -np.eye(2)
        A[3 * i:3 * i + 2, 2 * i + 2:2 * i + 4] = np.eye(2)
        w = [(masses[i], c), (att[i, 0], a), (att[i, 1], e)]
        b[3 * i + 1] = g * sum(m for m, _ in w)
        # moments about a: (e - a) x F_{i+1} + sum (x - a) x (0, -m g) = 0
        r = e - a
        A[3 * i + 2, 2 * i + 2:2 * i + 4] = [-r[1], r[0]]
        b[3 * i + 2] = g * sum(m * (x - a)[0] for m, x in w)
    sol, *_ = np.linalg.lstsq(A, b, rcond=None)
    return sol[:-2].reshape(n + 1, 2), float(np.abs(A @ sol - b).max() / (g * np.sum(masses)))


def clevis_rating(d, tongue, prong, gap, yield_mpa):
    """Textbook clevis pin: two reactions F/2 at the prongs' mid-planes, F spread over the
    tongue; the largest moment at the middle, sigma = M c / I."""
    a, b = tongue, prong
    moment_per_force = 0.5 * (b / 2 + gap + a / 2) - 0.5 * (a / 4)  # reactions' arm less the load's own
    stress_per_moment = (d / 2) / (math.pi * d ** 4 / 64)
    return yield_mpa / (stress_per_moment * moment_per_force)


def test_default_menu_has_the_families_pin_and_the_default_options():
    menu = load_catalog("pla-parametric").pins
    names = [o.name for o in menu.options]
    assert menu.base.name == "steel-pin-3" and menu.base.pin_diameter == 3.0 and menu.base.clearance == 0.2
    assert set(names) >= {o["name"] for o in DEFAULT_OPTIONS}
    costs = [o.cost for o in menu.options]
    assert costs == sorted(costs)


def test_pin_option_numbers_against_textbook():
    o = PinOption("p", "pin", "", pin_diameter=1.5, clearance=0.15, friction=(0.2, 0.4), pin_yield=600.0)
    t, tongue, gap = 16.0, 5.6, 0.3
    prong = (t - tongue - 2 * gap) / 2
    bend = clevis_rating(1.5, tongue, prong, gap, 600.0)
    bearing = 10.0 * 1.65 * min(tongue, 2 * prong)
    assert o.rated_load(t, tongue, gap, 10.0) == pytest.approx(min(bend, bearing), rel=1e-12)
    assert o.capacity(2.0) == pytest.approx(0.4 * 2.0 * 0.75)
    assert o.capacity(2.0, upper=False) == pytest.approx(0.2 * 2.0 * 0.75)
    b = PinOption("b", "bearing", "", pin_diameter=2.0, clearance=0.02, friction=(0.001, 0.005),
                  torque=(0.0, 0.01), outer_diameter=5.0, width=2.3, count=2, part_mass=0.19, part_load=50.0)
    assert b.capacity(1.0) == pytest.approx(0.005 * 1.0 * 1.0 + 0.01)
    assert b.tongue_hole == 5.0 and b.fork_hole == pytest.approx(2.02)
    assert b.rated_load(t, tongue, gap, 10.0) <= 100.0
    assert b.fit_problem(5.0, 5.6, 1.2) is None
    assert "wall" in b.fit_problem(3.5, 5.6, 1.2)  # a 5 mm hole in a 7 mm knuckle
    assert "longer" in b.fit_problem(5.0, 2.8, 1.2)  # two 2.3 mm bearings in a 2.8 mm tongue
    # the pin's mass: a steel cylinder
    assert o.pin_mass(17.0) == pytest.approx(math.pi / 4 * 1.5 ** 2 * 17.0 * 7.85e-3)


def test_chosen_pins_carry_their_loads_by_independent_statics(semicircle):
    """Every joint's force from each rod's free-body statics at the design (with the hardware
    hanging on the rods) is within its hardware's rated load divided by the safety factor."""
    r = semicircle
    hw = r.hardware
    body = r.masses - r.attached.sum(axis=1)
    from rodcad.design.hung import hung_com

    # the rods' own centres of mass: undo the hung ones with the attached masses
    own = (r.com * r.masses[:, None] - np.column_stack([r.attached[:, 1] * r.lengths, np.zeros(r.n)])) / body[:, None]
    assert np.allclose(hung_com(r.masses, own, r.lengths, r.attached), r.com, atol=1e-12)
    F, res = independent_pin_forces(r.equilibrium.points, body, own, r.design.g, r.attached)
    assert res < 1e-9  # the free-body equations hold: the design hangs in equilibrium with its hardware
    load = newtons(np.hypot(*F.T), r.design.g)
    assert np.allclose(load, hw.loads, rtol=1e-6)
    for k, o in enumerate(hw.options):
        assert o is not None
        assert load[k] * hw.safety <= hw.rated[k]


def test_semicircle_friction_band_within_a_tenth_of_the_tolerance(semicircle):
    r = semicircle
    hw = r.hardware
    size = 200.0
    assert hw.budget == pytest.approx(0.1 * 0.01 * size)
    assert r.as_printed.friction.band <= hw.budget * (1 + 1e-9)
    # every joint free: nothing was held both ways to narrow it
    assert not np.any(r.equilibrium.active)
    # the band at the top of the chosen parts' ranges: recomputed independently of the choice
    tau = solver_moment([o.friction[1] * newtons_f * o.radius + o.torque[1]
                         for o, newtons_f in zip(hw.options, hw.loads)], r.design.g)
    fb = friction_band(r.lengths, r.masses, *r.design.anchors, capacity=tau, com=r.com, end_limits=r.end_limits,
                       g=r.design.g)
    assert fb.band == pytest.approx(r.as_printed.friction.band, rel=1e-6)
    # a mirror-symmetric chain gets mirror-symmetric hardware
    names = [o.name for o in hw.options]
    assert names == names[::-1]


def random_chain(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(4, 12))
    l = rng.uniform(25, 55, n)
    m = rng.uniform(5, 25, n)
    a, b = np.zeros(2), np.array([0.7 * l.sum(), rng.uniform(-20, 20)])
    return l, m, a, b


@pytest.mark.parametrize("seed", range(6))
def test_choice_on_random_chains(seed):
    """On random chains of the default catalog's rods: with no budget to meet every pin gets
    the cheapest hardware that carries it; with a budget, the band is within it or no pin
    can go lower; the band never widens past the all-cheapest one."""
    cat = load_catalog("pla-parametric")
    l, m, a, b = random_chain(seed)
    rods = [cat.types[0]] * len(l)
    eq = solve_equilibrium(l, m, a, b)
    kw = dict(lengths=l, masses=m, com=None, anchors=(a, b), limits=None, end_limits=None, g=9.81,
              equilibrium=eq, fused=np.zeros(len(l) - 1, bool))
    loose = choose_hardware(rods, cat.pins, budget=np.inf, **kw)
    cheapest = min(o.cost for o in cat.pins.options)
    assert all(o.cost == cheapest for o in loose.options) and not loose.upgraded
    budget = 0.5 * loose.band
    tight = choose_hardware(rods, cat.pins, budget=budget, **kw)
    assert tight.band <= loose.band * (1 + 1e-9)
    if tight.band > budget:  # then no pin can go lower than it has
        best = min(o.capacity(1.0) for o in cat.pins.options)
        assert any("least-friction" in n for n in tight.notes)
        assert all(o.capacity(1.0) == pytest.approx(best) for o in tight.options) or tight.upgraded
    for k, o in enumerate(tight.options):
        assert tight.loads[k] * tight.safety <= tight.rated[k]


def test_masses_are_designed_with_the_hardware_hanging_on(semicircle):
    """The rods' own masses (less the hardware) with the hardware's point masses at their hinge
    axes hang on the target: solved as a chain of rods plus point masses by the free-body
    statics above, and by the solver with the hung numbers."""
    r = semicircle
    att = r.attached
    assert np.all(att.sum(axis=1) != 0)  # every rod carries some hardware
    eq = solve_equilibrium(r.lengths, r.masses, *r.design.anchors, com=r.com, end_limits=r.end_limits, g=r.design.g)
    assert np.abs(eq.points - r.target_points).max() < 1e-6 * 200
    assert r.hung.com_change < 1e-6


def test_report_and_design_json_list_the_hardware(semicircle, tmp_path):
    from rodcad.outputs.design_json import design_json
    from rodcad.outputs.report import report_markdown

    data = design_json(semicircle)
    hw = data["hardware"]
    assert len(hw["pins"]) == semicircle.n + 1
    assert all(p["load_n"] * p["safety"] <= p["rated_n"] for p in hw["pins"])
    bom = data["bill_of_materials"]
    assert sum(e["joints"] for e in bom["hardware"]) == semicircle.n + 1
    assert sum(bom["pins"]["diameters_mm"].values()) == semicircle.n + 1
    for rod, r in zip(data["rods"], semicircle.masses):
        assert rod["hardware"]["printed_mass"] == pytest.approx(r - sum(rod["hardware"]["metal_g"]))
    md = report_markdown(semicircle, data)
    assert "## Joint hardware" in md
    for e in bom["hardware"]:
        assert e["option"] in md


BAD_PINS = """\
catalog: 1
name: bad-pins
defaults:
  section: {height: 16, thickness: 16}
  joint: {pin_diameter: 3, knuckle_radius: 5, tongue_thickness: 5.6, friction: [0.4, 0.2]}
  material: {density: 1.24, min_wall: 1.2}
families:
  - name: r
    length: [40]
pins:
  options:
    - {name: b1, kind: bearing, pin_diameter: 2, clearance: 0.02, friction: 0.003}
    - {name: b2, kind: bushing, pin_diameter: 2, clearance: 0.1, friction: 0.1, outer_diameter: 1.5}
    - {name: b3, kind: washer, pin_diameter: 2, clearance: 0.1, friction: 0.1}
"""


def test_bad_pins_block_names_file_line_column_and_key(tmp_path):
    f = tmp_path / "bad-pins.yaml"
    f.write_text(BAD_PINS)
    out = subprocess.run([sys.executable, "-m", "rodcad.cli", "catalog", "check", str(f)], capture_output=True, text=True)
    assert out.returncode == 2, out.stderr
    err = out.stderr
    assert "Traceback" not in err
    assert f"{f}:5:" in err and "joint.friction" in err
    assert f"{f}:14:" in err and "pins.options[2].kind" in err
    # the schema's problem stops the cross-field checks of the options: fix it and see them
    f.write_text(BAD_PINS.replace("kind: washer", "kind: pin").replace("friction: [0.4, 0.2]", "friction: 0.3"))
    out = subprocess.run([sys.executable, "-m", "rodcad.cli", "catalog", "check", str(f)], capture_output=True, text=True)
    assert out.returncode == 2
    assert f"{f}:12:" in out.stderr and "pins.options[0]" in out.stderr and "outer_diameter" in out.stderr
    assert f"{f}:13:" in out.stderr and "pins.options[1].outer_diameter" in out.stderr


def _rested_inside(r, label):
    """The designed chain with its chosen hardware's friction (top of each range), hung 0.01 rad
    off its shape in MuJoCo and then tapped (the build's own simulation, rodcad.design.tapping),
    and released by the independent MuJoCo reference (tests/mujoco_chain.py, no rodcad code)
    from the same start: every rest within the band rodcad reports, per joint, plus MuJoCo's
    settling error and the band's second-order term."""
    from mujoco_chain import settle_chain
    from optimize.chain.endlimits import limit_turn

    t = r.tapping
    fb = r.as_printed.friction
    assert t is not None and t.converged, t.message
    second = fb.band ** 2 / float(np.min(r.lengths))  # a rod turned by band / l leaves its tangent by ~band^2 / 2l
    for k, rest in enumerate(t.rests):
        settle = t.drift + t.end_error[k] + float(np.sum(r.lengths)) * t.violation[k]
        disp = np.hypot(*(rest - r.equilibrium.points).T)
        assert np.all(disp <= fb.per_joint + second + settle), (label, k, (disp - fb.per_joint).max())
    # the independent engine, from the start the build let go of
    theta0 = np.unwrap(np.arctan2(*np.diff(t.start, axis=0).T[::-1]))
    ends = None
    if r.end_limits is not None:
        ends = np.asarray(r.end_limits, float).copy()
        th = np.unwrap(r.equilibrium.angles)
        for e, a in ((0, th[0]), (1, th[-1])):
            ends[e] += limit_turn(a, ends[e])
    out = settle_chain(r.lengths, r.masses, *r.design.anchors, com=r.com, limits=r.limits, angles0=theta0,
                       end_limits=ends, frictionloss=solver_moment(r.hardware.capacity, r.design.g),
                       soft_timeconst=0, max_time=240.0, tol=1e-7, g=r.design.g)  # low friction: slow to stop
    size = max(float(np.ptp(r.equilibrium.points[:, 0])), float(np.ptp(r.equilibrium.points[:, 1])))
    assert out["converged"] and out["end_error"] < 1e-6 * size
    disp = np.hypot(*(out["points"] - r.equilibrium.points).T)
    assert np.all(disp <= fb.per_joint + second + 1e-6 * size), (label, (disp - fb.per_joint).max())
    return float(t.deviation.max()), fb.band


def test_mujoco_with_the_chosen_pins_rests_inside_the_reported_band(semicircle):
    dev, band = _rested_inside(semicircle, "semicircle")
    assert band <= semicircle.hardware.budget * (1 + 1e-9) and dev <= band * 1.05


@pytest.mark.parametrize("what", ["necklace", "drawn"])
def test_mujoco_with_the_chosen_pins_rests_inside_the_band_necklace_and_a_drawn_shape(what, build_store):
    pytest.importorskip("mujoco")
    if what == "necklace":
        r = build_store.result(ROOT / "examples" / "necklace.yaml")
    else:
        from drawn_shapes import design_text, family

        shape = family(10, seed=7)[1]  # a drop: stops both sides, free joints, anchor stops
        r = build_store.result(f"{shape.name}.yaml", text=design_text(shape))
        if not r.meets_tolerance:
            pytest.skip(f"{shape.name} exits 1: no design to hang")
    _rested_inside(r, what)


def test_chandelier_chains_get_hardware_per_joint_that_carries_their_loads():
    """A chandelier's chains take a single chain's hardware step: every joint its own pin
    option (by the chain's loads, in its plane), the masses designed with it on, the pins'
    loads within their ratings by independent statics, the friction band recomputed from the
    chosen parts, and the hardware in design.json's bill of materials."""
    from rodcad.outputs.design_json import chandelier_json

    b = pipeline.build_chandelier(load_design("examples/chandelier.yaml"), cad=False)
    assert len(b.chains) == len(b.result.chains)
    for ch, r in zip(b.result.chains, b.chains):
        hw = r.hardware
        assert hw is not None and all(o is not None for o in hw.options)
        assert np.allclose(r.masses, ch.masses) and r.chain_design is ch.design
        body = r.masses - r.attached.sum(axis=1)
        own = (r.com * r.masses[:, None] - np.column_stack([r.attached[:, 1] * r.lengths, np.zeros(r.n)])) \
            / body[:, None]
        F, res = independent_pin_forces(r.equilibrium.points, body, own, r.design.g, r.attached)
        assert res < 1e-9
        load = newtons(np.hypot(*F.T), r.design.g)
        assert np.allclose(load, hw.loads, rtol=1e-6)
        assert np.all(load * hw.safety <= hw.rated)
        tau = solver_moment([o.friction[1] * f * o.radius + o.torque[1] for o, f in zip(hw.options, hw.loads)],
                            r.design.g)
        fb = friction_band(r.lengths, r.masses, *r.design.anchors, capacity=tau, com=r.com, g=r.design.g)
        assert fb.band == pytest.approx(r.as_printed.friction.band, rel=1e-6)
        assert r.tapping is not None and r.tapping.converged
    data = chandelier_json(b)
    used = {o.name for r in b.chains for o in r.hardware.options}
    bill = {e["option"]: e["joints"] for e in data["bill_of_materials"]["hardware"]}
    assert set(bill) == used
    assert sum(bill.values()) == sum(r.n + 1 for r in b.chains)
    assert data["chains"][0]["hardware"]["pins"][0]["load_n"] > 0
