"""Anchor stops in the design (issue 15): the linear statics with the fixtures' moments, the
planner choosing which anchors the fixture must hold, and the paper's heart hung from its cusp
(examples/heart.yaml) against MuJoCo."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from optimize import solve_equilibrium
from optimize.chain.endlimits import limit_turn
from optimize.chain.inverse import InverseProblem
from optimize.chain.statics import exact_masses, statics_matrix
from optimize.chain.stops import needed_stop_sides
from rodcad import pipeline
from rodcad.cli import main
from rodcad.design.loader import load_design

ROOT = Path(__file__).resolve().parents[1]


def _random_held(seed: int):
    """A random chain whose first (and often last) rod rests on an anchor stop."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(4, 9))
    lengths, masses = rng.uniform(0.8, 1.2, n), rng.uniform(1.0, 3.0, n)
    com = np.column_stack([lengths * rng.uniform(0.4, 0.6, n), rng.uniform(-0.05, 0.05, n)])
    a = np.zeros(2)
    span = rng.uniform(0.3, 0.8) * lengths.sum()
    b = np.array([span, rng.uniform(-0.2, 0.2) * span])
    free = solve_equilibrium(lengths, masses, a, b, com=com)
    e = np.array([[free.angles[0] + rng.uniform(0.1, 0.5), np.inf],
                  [-np.inf, free.angles[-1] - rng.uniform(0.1, 0.5)]])
    if seed % 3 == 0:
        e[1] = [-np.inf, np.inf]
    return lengths, masses, com, a, b, e


@pytest.mark.parametrize("seed", range(12))
def test_statics_with_anchor_moments_give_masses_that_hang_on_the_target(seed):
    """The target is a chain held by anchor stops; the statics (the fixtures' moments as two
    more stop columns) give masses whose equilibrium, solved from scratch with the same end
    limits, is the target again."""
    lengths, masses, com, a, b, e = _random_held(seed)
    held = solve_equilibrium(lengths, masses, a, b, com=com, end_limits=e)
    if "cannot be met" in held.message:  # random bounds no configuration of the chain meets
        pytest.skip(held.message)
    assert held.success, held.message
    if not held.info["end_active"].any():
        pytest.skip("the end limits do not bind for this chain")
    prob = InverseProblem(held.points, lengths, np.tile([0.2, 20.0], (len(lengths), 1)), com=com, end_limits=e)
    _, stops, signs = statics_matrix(prob)
    n = len(lengths)
    assert {-1, n - 1} & set(stops.tolist())  # an anchor stop is a column of the statics
    m, resid, reachable, _ = exact_masses(prob)
    assert reachable and resid < 1e-9
    sim = prob.simulate(m)
    assert sim.success
    assert np.abs(sim.points - held.points).max() < 1e-8 * np.hypot(*(b - a))


def test_the_planner_asks_for_an_anchor_stop_where_the_masses_cannot_hold():
    """A chain whose first rod is held up, as a target with narrow mass bounds: no joint stop
    alone balances it, the anchor stop at A on the right side does."""
    lengths, masses, com, a, b, e = _random_held(1)
    e[1] = [-np.inf, np.inf]
    held = solve_equilibrium(lengths, masses, a, b, com=com, end_limits=e)
    assert held.success and held.info["end_active"][0]
    bounds = np.column_stack([masses * 0.98, masses * 1.02])
    bare = InverseProblem(held.points, lengths, bounds, com=com)
    assert not exact_masses(bare)[2]
    joints, sides = needed_stop_sides(bare, [], ends=(0, 1))
    assert joints.tolist() == [-1] and sides.tolist() == [1]  # A keeps theta_0 from shrinking
    fixed = InverseProblem(held.points, lengths, bounds, com=com, end_limits=[[held.angles[0], np.inf],
                                                                              [-np.inf, np.inf]])
    m, _, reachable, _ = exact_masses(fixed)
    assert reachable
    sim = fixed.simulate(m)
    assert sim.success and np.abs(sim.points - held.points).max() < 1e-8 * np.hypot(*(b - a))


@pytest.fixture(scope="module")
def heart(build_store):
    return build_store.result(ROOT / "examples" / "heart.yaml")  # the session's build (test_fixture.py's too)


def test_the_heart_hangs_from_its_cusp(heart):
    """The paper's Fig. 9, from a design file with no constraints: both lobes above the
    anchors, the tip below, within 1 % of the heart's width of its outline; the sides hang
    on free joints (as many on each side: the heart is symmetric)."""
    r = heart
    pts = r.equilibrium.points
    a, b = r.design.anchors
    assert r.equilibrium.success and r.equilibrium.stable
    from optimize.chain.curves import centerline

    arcs = centerline(pts, np.array([r.design.catalog[nm].curvature for nm in r.type_names]))
    assert arcs[:, 1].max() > a[1] + 5.0  # lobes above the anchors (the rods, arcs over their joints)
    assert pts[:, 1].min() < a[1] - 150.0  # the tip far below
    curve = r.plan.curve
    width = float(np.ptp(curve[:, 0]))
    from rodcad.outputs.design_json import curve_error, design_json
    cv = curve_error(curve, pts, np.array([r.design.catalog[nm].curvature for nm in r.type_names]), r.design.span)
    assert cv["max_mm"] <= 0.01 * width and cv["rel_size"] <= 0.01
    assert load_design(ROOT / "examples" / "heart.yaml").constraints == type(r.design.constraints)()
    bends = np.diff(r.equilibrium.angles)
    free = [j for j in range(r.n - 1) if not np.any(np.abs(r.limits[j] - bends[j]) < 1e-9)]
    assert len(free) >= 4 and sorted(r.n - 2 - j for j in free) == free, free  # mirrored
    below = pts[1:-1, 1] < a[1] - 30.0  # joints well below the anchors: the sides
    assert sum(below[j] for j in free) >= 2
    assert r.equilibrium.info["end_active"].all()  # the fixture holds both lobes
    data = design_json(r)
    lim = data["anchor_limits_deg"]
    assert lim[0] is not None and lim[1] is not None
    assert lim[0][1] == pytest.approx(math.degrees(r.equilibrium.angles[0]), abs=1e-6)


def test_the_heart_agrees_with_mujoco(heart):
    """Released a little off its shape in MuJoCo (hinge limits, the fixture as limits on the
    end rods), the heart settles where the exact solver says, within 1e-5 of the span."""
    pytest.importorskip("mujoco")
    from mujoco_chain import settle_chain

    r = heart
    p = r.plan.problem
    a, b = r.design.anchors
    # MuJoCo's angles are continuous along the chain (the last rod's is the sum of the hinge
    # angles: the heart turns more than once), so the end limits go on that branch
    theta = np.unwrap(r.equilibrium.angles)
    e = r.end_limits.copy()
    for k, t in ((0, theta[0]), (1, theta[-1])):
        e[k] += limit_turn(t, e[k])
    rng = np.random.default_rng(0)
    angles0 = theta + rng.normal(0.0, 0.01, r.n)
    mj = settle_chain(p.lengths, r.masses, a, b, com=p.com, limits=p.limits, angles0=angles0, g=r.design.g,
                      end_limits=e)
    assert mj["converged"]
    span = float(np.hypot(*(b - a)))
    assert np.max(np.hypot(*(mj["points"] - r.equilibrium.points).T)) < 1e-5 * span


def _write(tmp_path: Path, extra: str, catalog: str = "") -> Path:
    path = tmp_path / "d.yaml"
    path.write_text("design: 1\nname: d\n" + catalog + "anchors: [[0, 0], [200, 0]]\n"
                    "target: {form: semicircle}\n" + extra, encoding="utf-8")
    return path


def test_explicit_anchor_limits_reach_design_json(tmp_path, capsys):
    path = _write(tmp_path, "constraints:\n  anchor_limits_deg: [[-100, -60], null]\n")
    assert main(["build", str(path), "-o", str(tmp_path / "out"), "--no-cad"]) == 0
    data = json.loads((tmp_path / "out" / "design.json").read_text())
    lim = data["anchor_limits_deg"]
    assert lim[1] is None and lim[0] == pytest.approx([-100.0, -60.0], abs=1e-9)
    first = data["simulated"]["angles_deg"][0]
    assert -100 - 1e-9 <= first <= -60 + 1e-9


def test_bad_anchor_limits(tmp_path, capsys):
    path = _write(tmp_path, "constraints:\n  anchor_limits_deg: [[10, -10], [1, 2, 3]]\n")
    assert main(["build", str(path), "-o", str(tmp_path / "out"), "--no-cad"]) == 2
    err = capsys.readouterr().err
    assert f"{path}:6:" in err and "anchor_limits_deg[0]: lo 10 deg is above hi -10 deg" in err
    assert "anchor_limits_deg[1]: expected [lo, hi]" in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()
    path = _write(tmp_path, "constraints: {anchor_stops: auto}\n", catalog="catalog: pla-weighted\n")
    assert main(["build", str(path), "-o", str(tmp_path / "out"), "--no-cad"]) == 2
    err = capsys.readouterr().err
    assert "constraints.anchor_stops" in err and "printed to order" in err


def test_a_held_chain_is_built_with_its_fixture(tmp_path, capsys, monkeypatch):
    """With CAD: fixture.step/.stl written and checked (valid, same volume, watertight),
    in the assembly, in design.json and report.md, and no problem against the rods at rest.
    The bound given by hand (-35 deg) keeps the first rod off the arc's -50 deg: the chain
    hangs 8 % off it, so the design accepts that (else exit 1, saying which bound). Built with
    ``--jobs 1`` where the default would be two workers: no worker process is started, to the
    last file written."""
    import rodcad.parallel
    from rodcad.cad.export import assembly_leaves

    monkeypatch.setenv("RODCAD_JOBS", "2")
    monkeypatch.setattr(rodcad.parallel, "default_jobs", lambda: 2)

    class NoPool:
        def __init__(self, *args, **kwargs):
            raise AssertionError("--jobs 1 started a worker process")

    monkeypatch.setattr(rodcad.parallel, "ProcessPoolExecutor", NoPool)

    path = tmp_path / "d.yaml"
    text = ("design: 1\nname: held\nanchors: [[0, 0], [150, 0]]\ntarget: {form: arc, sag: 50}\n"
            "constraints:\n  rods: 4\n  anchor_limits_deg: [[-35, 90], null]\n")
    path.write_text(text, encoding="utf-8")
    out = tmp_path / "out"
    assert main(["build", str(path), "-o", str(out), "-q", "--no-cad"]) == 1
    assert "anchor_limits_deg holds the first rod within [-35, 90] deg" in capsys.readouterr().err
    path.write_text(text + "tolerance: 0.1\n", encoding="utf-8")
    assert main(["build", str(path), "-o", str(out), "-q", "--jobs", "1"]) == 0, capsys.readouterr().err
    data = json.loads((out / "design.json").read_text())
    assert data["simulated"]["angles_deg"][0] == pytest.approx(-35.0, abs=1e-6)  # the fixture holds rod 0
    fx = data["fixture"]
    assert fx["problems"] == [] and fx["stops"] == [0] and fx["volume_mm3"] > 0
    assert (out / "fixture.step").is_file() and (out / "fixture.stl").is_file()
    assert "fixture" in [name for name, _ in assembly_leaves(out / "assembly.step")]
    assert "anchor fixture" in (out / "report.md").read_text()
    # rodcad check re-simulates with the fixture's bound read back from design.json
    capsys.readouterr()
    assert main(["check", str(out), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    # the same chain as the build's as-built one (the solids' masses and centres of mass:
    # balls at their sockets' layers may move a rod's centre of mass off the design's)
    built = np.asarray(data["as_built"]["points"], float)
    assert np.abs(np.asarray(report["simulated"]["points"]) - built).max() < 1e-6 * 150
    assert report["error_vs_design"]["max_rel_span"] < 1e-3


def test_fused_pieces_replace_runs_of_stops(tmp_path, capsys):
    """constraints: {fuse: stops}: the heart's lobes and tip become rigid pieces (joints with
    lo == hi), solved exactly, reported as fused; the free joints stay free."""
    text = (ROOT / "examples" / "heart.yaml").read_text() + "constraints: {fuse: stops}\n"
    path = tmp_path / "heart.yaml"
    path.write_text(text, encoding="utf-8")
    r = pipeline.build(load_design(path), cad=False)
    assert r.plan.fused and all(b > a for a, b in r.plan.fused)
    fused_joints = [j for a, b in r.plan.fused for j in range(a, b)]
    assert all(r.limits[j, 0] == r.limits[j, 1] for j in fused_joints)
    bends = np.diff(r.equilibrium.angles)
    assert np.allclose(bends[fused_joints], r.limits[fused_joints, 0], atol=1e-12)
    assert r.distance.max < 1e-6 and r.equilibrium.stable
    from rodcad.outputs.report import summary_text
    assert "fused (" in summary_text(r, None)


def test_the_heart_hangs_in_one_shape(heart):
    """The example heart, as the planner designs it with no constraints, has one stable
    shape: the multi-start finds no other."""
    assert heart.unique and heart.n_stable == 1 and heart.equilibrium.stable


def test_two_sided_stops_rule_out_the_other_shapes_and_the_advice_names_them():
    """A drawn triangle hung from a vertex (benchmarks/drawn_shapes.py): with the fewest stops
    that balance it, the solver finds another stable shape, lower than the designed one;
    the planner then holds the joints where it differs both ways (two-sided stops) and the
    triangle hangs in one shape. The advice for the first design names the joints that
    differ and how to hang the chain as designed."""
    from drawn_shapes import family

    from rodcad.design.decide import Allowed, decide
    from rodcad.design.masses import ChainCheck
    from rodcad.design.plan import catalog_arrays
    from rodcad.design.printed import _laid_on  # noqa: PLC2701 - the planner's own layout

    shape = family(49, seed=0)[48]
    assert shape.kind == "polygon" and shape.params["sides"] == 3
    cat = load_design(ROOT / "examples" / "semicircle.yaml").catalog
    pf = catalog_arrays(cat).printed[0]
    disc, kappa = _laid_on(shape.points, pf.family.ranges, None)
    phi = np.diff(np.unwrap(np.arctan2(*np.diff(disc.points, axis=0).T[::-1])))
    dec = decide(cat, pf, disc.points, disc.lengths, kappa, phi, allowed=Allowed())
    assert dec.accepted and dec.verdict.unique and dec.held
    first = dec.history[0]
    assert first[0] == [] and first[1].on_target and first[1].others and first[1].lower  # a lower shape
    v = first[1]
    advice = ChainCheck(v.equilibrium, 1 + len(v.others), False, v.starts, tuple(v.others)).hang_advice()
    assert "another stable shape differs at joint(s)" in advice and "To hang it as designed" in advice
    # the joints held first are where the lowest other shape differs most
    assert dec.history[1][0][0] in v.culprits


def test_a_fixture_not_fit_to_print_is_exit_1_and_leaves_outdir(tmp_path, capsys, monkeypatch):
    """When the fixture check finds a problem (here: made to report one) the build exits 1,
    says why, and writes the design beside OUTDIR, which stays as it was."""
    import rodcad.cad.fixture as fixture

    path = tmp_path / "d.yaml"
    path.write_text("design: 1\nname: held\nanchors: [[0, 0], [150, 0]]\ntarget: {form: arc, sag: 50}\n"
                    "constraints:\n  rods: 4\n  anchor_limits_deg: [[-35, 90], null]\ntolerance: 0.1\n",
                    encoding="utf-8")
    out = tmp_path / "out"
    assert main(["build", str(path), "-o", str(out), "-q", "--no-cad"]) == 0  # an earlier run
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    monkeypatch.setattr(fixture, "check_fixture", lambda *a, **k: ["rod_02 overlaps the fixture at rest by 3 mm^3"])
    assert main(["build", str(path), "-o", str(out), "-q", "--jobs", "1"]) == 1
    err = capsys.readouterr().err
    assert "not fit to print" in err and "overlaps the fixture" in err and "Traceback" not in err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    data = json.loads((tmp_path / "out.best-fit" / "design.json").read_text())
    assert data["fixture"]["problems"] == ["rod_02 overlaps the fixture at rest by 3 mm^3"]


def test_a_chandelier_refuses_anchor_stops(tmp_path, capsys):
    """A chandelier's chains hang from the frame's bare lugs: anchor stops are refused at the key."""
    text = (ROOT / "examples" / "chandelier.yaml").read_text().replace("constraints:\n",
                                                                      "constraints:\n  anchor_stops: auto\n")
    path = tmp_path / "ch.yaml"
    path.write_text(text, encoding="utf-8")
    assert main(["build", str(path), "-o", str(tmp_path / "out"), "--no-cad"]) == 2
    err = capsys.readouterr().err
    assert "constraints.anchor_stops: a chandelier's chains hang from the frame's lugs" in err
    assert not (tmp_path / "out").exists()


def test_a_stop_at_the_end_of_the_printable_range_is_planned(tmp_path):
    """A closed heart with straight sides meets its tip at 90 deg, the family's last
    printable stop, to round-off: the planner used to bend the tip's rods less for ever."""
    path = tmp_path / "d.yaml"
    path.write_text("design: 1\nname: h\nanchors: [[0, 0], [30, 0]]\ntarget: {form: closed-heart, width: 120}\n"
                    "constraints: {anchor_stops: auto}\n", encoding="utf-8")
    r = pipeline.build(load_design(path), cad=False)
    bends = np.degrees(np.diff(r.equilibrium.angles))
    tip = int(np.argmin(r.equilibrium.points[:, 1])) - 1
    assert abs(np.angle(np.exp(1j * np.radians(bends[tip]))) - math.pi / 2) < 1e-6
    assert r.distance.max < 1e-6


def test_a_wide_heart_on_many_stops_hangs_in_its_shape(tmp_path):
    """A wide closed heart whose lower part rests on many stops: with the fewest stops that
    balance it, the chain used to settle in another stable shape, 71 % of its size off
    (reported, not avoided). The planner now checks the shape it designs and holds the
    joints where the chain would go instead: it hangs on its target, its only stable shape."""
    path = tmp_path / "d.yaml"
    path.write_text("design: 1\nname: h\nanchors: [[0, 0], [30, 0]]\n"
                    "target: {form: closed-heart, width: 300, bulge: 0.12}\n", encoding="utf-8")
    r = pipeline.build(load_design(path), cad=False)
    assert r.distance.max < 1e-6 * 300 and r.equilibrium.stable and r.unique
    assert r.fit <= 0.01 and r.meets_tolerance


@pytest.mark.parametrize("extra, key, words", [
    ("catalog: pla-weighted\nanchors: [[0, 0], [200, 0]]\ntarget: {form: semicircle}\nconstraints: {fuse: stops}\n",
     "6:21: constraints.fuse", "printed to order"),
    ("anchors: [[0, 0], [50, 0]]\ntarget: {form: closed-heart, width: 100, bulge: 0.3}\n",
     "4:49: target.bulge", "between 0 and 0.25"),
    ("anchors: [[0, 0], [50, 0]]\ntarget: {form: closed-heart, width: 100}\n",
     "4:37: target.width", "less than 3 times the anchors' distance"),
])
def test_bad_fuse_and_closed_heart_input(tmp_path, capsys, extra, key, words):
    path = tmp_path / "d.yaml"
    path.write_text("design: 1\nname: b\n" + extra, encoding="utf-8")
    assert main(["build", str(path), "-o", str(tmp_path / "out"), "--no-cad"]) == 2
    err = capsys.readouterr().err
    assert f"{path}:{key}:" in err and words in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()


def test_anchors_further_apart_than_the_printer_takes_hang_from_bare_pins(build_store):
    """One fixture holds both anchors, so anchors further apart than the printer's bed take
    none: the planner keeps the end rods free (no anchor stops) and says why (the garland's
    anchors are 240 mm apart; its fixture would be 255 mm long on a 250 mm printer)."""
    r = build_store.result(ROOT / "examples" / "garland.yaml")  # the session's build
    assert r.end_limits is None or not np.isfinite(np.asarray(r.end_limits, float)).any()
    assert any("would not fit the printer" in n and "bare pins" in n for n in r.plan.notes), r.plan.notes
