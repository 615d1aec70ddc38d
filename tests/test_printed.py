"""Rods printed to order (a catalog family with ``length: {min, max}``, ``curvature`` and
``stops`` ranges, catalogs/pla-parametric.yaml): the catalog model and its validation,
stops printed at the bend they hold, the planner laying such rods on targets (exactness on
reachable chains, shapes, ``joints: free``, mirror symmetry) and design.json from
``rodcad build`` on a design that names no catalog.

Tolerances are physical (fractions of the span, hundredths of a degree, grams), not
last digits. CAD appears once (one curved rod with stop ends against the fast integration).
"""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest

from optimize import solve_equilibrium
from rodcad.catalog.jointlimits import joint_limits
from rodcad.catalog.loader import catalog_from_text, load_catalog
from rodcad.catalog.model import EndShape, max_curvature
from rodcad.catalog.printed import rod_numbers, stop_chamfer
from rodcad.cli import main
from rodcad.design.masses import design_chain
from rodcad.design.model import DEFAULT_CATALOG, Constraints
from rodcad.design.plan import catalog_arrays, plan_constrained
from rodcad.design.targets import make_target
from rodcad.errors import InputError, Problem
from rodcad.outputs.design_json import curve_error

#: The shipped pla-parametric catalog, written compactly so that lines and columns are known
#: (test_the_compact_text_is_the_shipped_catalog keeps it in step with the shipped file).
PARAM = """\
catalog: 1
name: param-test
printer: {build_volume: [220, 220, 250], nozzle: 0.4}
defaults:
  section: {height: 16, thickness: 16}
  joint: {layout: tongue-fork, pin_diameter: 3.0, pin_clearance: 0.2, knuckle_radius: 5.0, tongue_thickness: 5.6, layer_gap: 0.3, radial_gap: 0.4}
  ends: {setback: 0.2, top_chamfer: 45, bottom_chamfer: 45}
  material: {name: PLA, density: 1.24, min_wall: 1.2}
  balls: {name: steel bearing ball 6 mm, diameter: 6.0, density: 7.85, clearance: 0.2}
families:
  - name: rod
    length: {min: 20, max: 60}
    curvature: {min: -0.05, max: 0.05}
    stops: {min: -90, max: 90}
"""
LENGTH_LINE, CURV_LINE, STOPS_LINE = 12, 13, 14

#: Design file text for the default catalog (rods printed to order); {constraints} filled in.
DESIGN = """\
design: 1
name: printed
anchors: [[0, 0], [200, 0]]
target: {form: semicircle}
"""

#: The rods' centrelines must follow the target within this fraction of the span.
SHAPE_REL = 0.005

#: A stop printed to order stops within this of the bend it is made for (deg).
STOP_DEG = 0.05


@pytest.fixture(scope="module")
def cat():
    return load_catalog("pla-parametric")


@pytest.fixture(scope="module")
def arrays(cat):
    return catalog_arrays(cat)


def _problem(key: str, message: str) -> Problem:
    return Problem("<test>", 0, 0, key, message)


def _bad(text: str) -> list[tuple[int, int, str, str]]:
    with pytest.raises(InputError) as info:
        catalog_from_text(text, "p.yaml")
    assert all(p.file == "p.yaml" for p in info.value.problems)
    return [(p.line, p.column, p.key, p.message) for p in info.value.problems]


def _col(text: str, line: int, needle: str) -> int:
    """1-based column of ``needle`` on a 1-based line of text."""
    return text.splitlines()[line - 1].index(needle) + 1


# --------------------------------------------------------------------------- catalog


def test_the_compact_text_is_the_shipped_catalog(cat):
    mine = catalog_from_text(PARAM + "    scale: {min: 0.55, max: 1.6}\n")  # the shipped rods are graduated
    assert mine.family("rod").ranges == cat.family("rod").ranges
    assert mine.family("rod").template.geometry == cat.family("rod").template.geometry
    assert (mine.printer.build_volume, mine.printer.nozzle) == (cat.printer.build_volume, cat.printer.nozzle)


def test_pla_parametric_is_a_family_printed_to_order(cat):
    assert cat.name == "pla-parametric" and DEFAULT_CATALOG == "pla-parametric"
    (fam,) = cat.printed_families
    assert fam.name == "rod" and fam.printed_to_order
    r = fam.ranges
    assert r.length == (20.0, 60.0) and r.curvature == (-0.05, 0.05) and r.stops == (-90.0, 90.0)
    # two reference types: the shortest and the longest straight rod with the family's ends
    assert fam.type_names == ("rod-20", "rod-60") and cat.names == ["rod-20", "rod-60"]
    for name, length in (("rod-20", 20.0), ("rod-60", 60.0)):
        t = cat[name]
        assert t.length == length and t.curvature == 0 and t.family == "rod"
        assert t.geometry.first == t.geometry.second == EndShape(0.2, 45.0, 45.0)
        assert t.geometry.height == 16 and t.geometry.thickness == 16
        assert t.material.name == "PLA" and t.material.density == pytest.approx(1.24)
    assert fam.template.geometry == cat["rod-20"].geometry
    # the largest curvature is a 120 deg arc through both pins: sqrt(3) / L
    assert max_curvature(20.0) == pytest.approx(math.sqrt(3) / 20, rel=1e-12)
    # the shipped curvature range fits the shortest rod and a 16 mm section
    assert 0.05 < max_curvature(20.0) and 0.05 * 16 < 1
    with pytest.raises(ValueError, match="not printed to order"):
        load_catalog("pla-pinned").rod("free", 30.0)


def test_catalog_rod_geometry_and_names(cat):
    own = EndShape(0.2, 45.0, 45.0)
    r = cat.rod("rod", 37.5, 0.004, second_stop=12.5)
    assert r.name == "rod-37.5-k4-b12.5"
    g = r.geometry
    assert (r.length, r.curvature, g.length, g.curvature) == (37.5, 0.004, 37.5, 0.004)
    assert g.first == own and g.second == EndShape(0.0, 12.5, 45.0)  # flush stop end: setback 0
    assert g.hinge == cat["rod-20"].geometry.hinge and g.height == 16 and g.thickness == 16
    # a bottom chamfer alone (kept from straightening) and both on one end
    u = cat.rod("rod", 41.0, -0.01, first_under=-7.25, second_stop=3.0, second_under=-4.0)
    assert u.geometry.first == EndShape(0.0, 45.0, -7.25)
    assert u.geometry.second == EndShape(0.0, 3.0, -4.0)
    assert u.curvature == -0.01 and u.geometry.half_angle_deg == pytest.approx(
        -math.degrees(math.asin(0.01 * 41 / 2)), abs=1e-12)
    # no parameters: the family's own rod (the reference type itself at its length)
    assert cat.rod("rod", 20.0) == cat["rod-20"]
    # the exact values are kept whatever the rounding of the name
    odd = cat.rod("rod", 33.33333333, 0.0123456789, first_stop=-1.23456789)
    assert odd.length == 33.33333333 and odd.geometry.first.top_chamfer == -1.23456789

    variants = [
        cat.rod("rod", 30.0), cat.rod("rod", 30.5), cat.rod("rod", 30.0, 0.01), cat.rod("rod", 30.0, -0.01),
        cat.rod("rod", 30.0, first_stop=10.0), cat.rod("rod", 30.0, second_stop=10.0),
        cat.rod("rod", 30.0, first_under=10.0), cat.rod("rod", 30.0, second_under=10.0),
        cat.rod("rod", 30.0, first_stop=0.0), cat.rod("rod", 30.0, first_stop=-10.0),
        cat.rod("rod", 30.0, first_stop=10.0, second_stop=10.0),
        cat.rod("rod", 30.0, 0.01, first_stop=10.0, first_under=-5.0),
        cat.rod("rod", 30.0, 0.01, second_stop=10.0, second_under=-5.0),
        cat.rod("rod", 59.999, 0.0289, first_stop=-29.5, second_under=12.125),
        odd,
    ]
    names = [t.name for t in variants]
    assert len(set(names)) == len(names), names  # distinct parameters, distinct names
    assert len({t.geometry for t in variants}) == len(variants)
    for n in names:  # names are file names (STEP/STL per rod type)
        assert re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9._+-]*", n), n
        assert n.startswith("rod-") and "/" not in n and " " not in n


def test_with_types_adds_rods_and_refuses_a_name_clash(cat):
    a = cat.rod("rod", 37.5, 0.004, second_stop=12.5)
    b = cat.rod("rod", 44.0, first_under=-3.0)
    more = cat.with_types([a, b, a])
    assert more.names == ["rod-20", "rod-60", a.name, b.name]
    assert more[a.name] is a and cat.names == ["rod-20", "rod-60"]  # the catalog itself is unchanged
    assert more.can_join(a, b) and more.can_join(b, a) and more.can_join("rod-20", a)
    assert more.with_types([a]) is more and cat.with_types([cat.rod("rod", 60.0)]) is cat
    # the same name for another rod (parameters equal to the name's 0.001 rounding only)
    twin = cat.rod("rod", 37.5, 0.0040001, second_stop=12.5)
    assert twin.name == a.name and twin != a
    with pytest.raises(ValueError, match="two different rods are both named 'rod-37.5-k4-b12.5'"):
        more.with_types([twin])
    with pytest.raises(ValueError, match="both named 'rod-20'"):
        cat.with_types([replace(cat.rod("rod", 20.0, 0.01), name="rod-20")])


# --------------------------------------------------------------------------- bad catalogs


def test_inverted_and_empty_ranges_point_at_max():
    text = PARAM.replace("length: {min: 20, max: 60}", "length: {min: 60, max: 25}")
    assert _bad(text) == [(LENGTH_LINE, _col(text, LENGTH_LINE, "25}"), "families[0].length.max",
                           "inverted range: max 25 must be above min 60")]
    text = PARAM.replace("curvature: {min: -0.05, max: 0.05}", "curvature: {min: 0.01, max: 0.01}")
    got = _bad(text)
    assert len(got) == 1 and got[0][:3] == (CURV_LINE, _col(text, CURV_LINE, "0.01}"), "families[0].curvature.max")
    assert got[0][3].startswith("empty range: max 0.01 must be above min 0.01")


def test_every_range_problem_is_reported_at_once():
    text = (PARAM.replace("length: {min: 20, max: 60}", "length: {min: 40, max: 40}")
            .replace("stops: {min: -90, max: 90}", "stops: {min: 10, max: -10}")
            + "  - name: tight\n    length: {min: 25, max: 50}\n    curvature: {min: -0.065, max: 0.01}\n")
    got = _bad(text)
    assert [(line, key) for line, _, key, _ in got] == [
        (LENGTH_LINE, "families[0].length.max"), (STOPS_LINE, "families[0].stops.max"),
        (17, "families[1].curvature.min")], got
    assert got[0][3].startswith("empty range") and got[1][3].startswith("inverted range")
    assert "too tight for a 16 mm high section" in got[2][3]
    assert got[2][1] == _col(text, 17, "-0.065")


def test_curvature_range_too_tight_for_the_section():
    # 0.065 /mm is under the 120 deg arc limit of a 25 mm rod (0.0693) but its radius
    # (15.4 mm) is under the 16 mm section height
    text = PARAM.replace("curvature: {min: -0.05, max: 0.05}", "curvature: {min: -0.04, max: 0.065}")
    assert _bad(text) == [(CURV_LINE, _col(text, CURV_LINE, "0.065"), "families[0].curvature.max",
                           ("curvature 0.065 /mm (radius 15.385 mm) is too tight for a 16 mm high section: the "
                            "radius must be at least the section height"))]


def test_curvature_range_checked_at_the_shortest_length():
    # 0.05 /mm is a 120 deg arc at 34.6 mm: fine for 30 mm rods, too much for 35 mm ones,
    # so only the range's shortest rod decides (longer rods are bent less by the planner)
    ok = PARAM.replace("length: {min: 20, max: 60}", "length: {min: 30, max: 60}").replace(
        "curvature: {min: -0.05, max: 0.05}", "curvature: {min: -0.05, max: 0.05}")
    assert catalog_from_text(ok).family("rod").ranges.curvature == (-0.05, 0.05)
    bad = ok.replace("length: {min: 30, max: 60}", "length: {min: 35, max: 60}")
    assert _bad(bad) == [(CURV_LINE, _col(bad, CURV_LINE, "0.05}"), "families[0].curvature.max",
                          "curvature 0.05 /mm bends a 35 mm rod past a 120 deg arc (at most 0.049487 /mm)")]


def test_stop_range_limits():
    # -59 .. 60 (and up to 90) is printable on this section: flush ends meet at the stop
    for stops in ("{min: -59, max: 60}", "{min: -60, max: 90}"):
        c = catalog_from_text(PARAM.replace("{min: -90, max: 90}", stops))
        assert c.family("rod").ranges.stops[0] in (-59.0, -60.0)
    text = PARAM.replace("stops: {min: -90, max: 90}", "stops: {min: -95, max: 60}")
    assert _bad(text) == [(STOPS_LINE, _col(text, STOPS_LINE, "-95"), "families[0].stops.min",
                           "must be between -90 deg and 90 deg (got -95)")]


def test_stop_range_whose_chamfers_cut_through_the_shortest_rod():
    """A stop of 80 deg needs top chamfers of 40 deg on both ends of a rod: on a 13 mm rod
    16 mm high the two top faces cross."""
    short = (PARAM.replace("length: {min: 20, max: 60}", "length: {min: 13, max: 60}")
             .replace("top_chamfer: 45, bottom_chamfer: 45", "top_chamfer: 30, bottom_chamfer: 30")
             .replace("balls: {name: steel bearing ball 6 mm, diameter: 6.0, density: 7.85, clearance: 0.2}",
                      "balls: {diameter: 6.0, density: 7.85}")
             .replace("stops: {min: -90, max: 90}", "stops: {min: -60, max: 60}"))
    assert catalog_from_text(short).family("rod").ranges.length == (13.0, 60.0)
    text = short.replace("stops: {min: -60, max: 60}", "stops: {min: -60, max: 80}")
    assert _bad(text) == [(STOPS_LINE, _col(text, STOPS_LINE, "80}"), "families[0].stops.max",
                           ("top chamfers of 40 and 40 deg cut through a 13 mm rod: the two top end faces would "
                            "cross"))]


def test_rod_longer_than_the_printer_is_reported_at_the_length():
    text = PARAM.replace("curvature: {min: -0.05, max: 0.05}", "curvature: 0").replace(
        "length: {min: 20, max: 60}", "length: {min: 25, max: 245}")
    assert _bad(text) == [(LENGTH_LINE, _col(text, LENGTH_LINE, "245"), "families[0].length.max",
                           ("a 245 mm rod (255 x 16 x 16 mm) does not fit the printer's build volume "
                            "(220 x 220 x 250 mm)"))]
    # with a curvature range the longest rod is too long even straight: still the length's fault
    text = PARAM.replace("length: {min: 20, max: 60}", "length: {min: 25, max: 300}")
    got = _bad(text)
    assert len(got) == 1 and "does not fit the printer's build volume" in got[0][3], got
    assert got[0][:3] == (LENGTH_LINE, _col(text, LENGTH_LINE, "300"), "families[0].length.max"), got


def test_curved_rod_taller_than_the_printer_is_reported_at_the_curvature():
    # straight, a 60 mm rod (70 x 16 x 16) fits a 100 x 30 x 30 bed; bent into a 120 deg arc
    # it sags 17.3 mm: 33.3 mm high
    text = PARAM.replace("build_volume: [220, 220, 250]", "build_volume: [100, 30, 30]")
    got = _bad(text)
    assert len(got) == 1 and got[0][:3] == (CURV_LINE, _col(text, CURV_LINE, "0.05}"), "families[0].curvature.max")
    assert got[0][3] == ("a 60 mm rod (70 x 33.32 x 16 mm) does not fit the printer's build volume "
                         "(100 x 30 x 30 mm)")


def test_a_list_of_curvatures_or_scales_is_refused_for_rods_printed_to_order():
    text = PARAM.replace("curvature: {min: -0.05, max: 0.05}", "curvature: [0, 0.01]")
    assert _bad(text) == [(CURV_LINE, _col(text, CURV_LINE, "["), "families[0].curvature",
                           "a family printed to order takes one curvature or a range {min, max}, not a list")]
    # ranges with a list of lengths
    text = PARAM.replace("length: {min: 20, max: 60}", "length: [25, 30]")
    assert _bad(text) == [
        (CURV_LINE, _col(text, CURV_LINE, "{"), "families[0].curvature",
         "a curvature range is for rods printed to order: give the length as a range {min, max} too"),
        (STOPS_LINE, _col(text, STOPS_LINE, "{"), "families[0].stops",
         "a stops range is for rods printed to order: give the length as a range {min, max} too")]
    # one curvature (not a range) is fine: every rod has it
    one = catalog_from_text(PARAM.replace("curvature: {min: -0.05, max: 0.05}", "curvature: 0.01"))
    assert one.family("rod").ranges.curvature == (0.01, 0.01) and one["rod-20"].curvature == 0.01


# --------------------------------------------------------------------------- bad designs


def test_design_with_catalog_lengths_on_rods_printed_to_order(tmp_path, capsys):
    """constraints.lengths makes no sense for a family that prints any length of its range:
    refused at the key, with what to use instead."""
    path = tmp_path / "d.yaml"
    path.write_text(DESIGN + "constraints: {lengths: [30]}\n")
    assert main(["build", str(path), "--no-cad", "-q", "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert f"{path}:5:" in err and "constraints.lengths" in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()
    # 30 mm is a length the family prints: the problem is the key, not a missing 30 mm rod
    assert "printed to order" in err, err


def test_design_preferred_length_outside_the_range_and_lengths_reported_together(tmp_path, capsys):
    path = tmp_path / "d.yaml"
    path.write_text(DESIGN + "constraints: {preferred_length: 70}\n")
    assert main(["build", str(path), "--no-cad", "-q", "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert f"{path}:5:33: constraints.preferred_length: 70 mm is outside the lengths family 'rod' prints " \
           "(20 to 60 mm)" in err, err
    line = "constraints: {lengths: [25], preferred_length: 19.5}"
    path.write_text(DESIGN + line + "\n")
    assert main(["build", str(path), "--no-cad", "-q", "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert f"{path}:5:{line.index('[25]') + 1}: constraints.lengths: family 'rod' is printed to order" in err, err
    assert f"{path}:5:{line.index('19.5') + 1}: constraints.preferred_length: 19.5 mm is outside" in err, err


# --------------------------------------------------------------------------- stops


def test_stops_printed_to_order_stop_at_their_bend(cat):
    """Two flush ends with the chamfers of stop_chamfer stop the joint within 0.05 deg of
    the bend: top faces (a stop against more bend: hi) and bottom faces (against
    straightening: lo), between straight and curved rods of any length in the range."""
    rng = np.random.default_rng(7)
    stops = cat.family("rod").ranges.stops
    done = 0
    while done < 10:
        length = rng.uniform(25, 60, 2)
        k = [float(rng.uniform(-1, 1) * min(0.04, max_curvature(x))) for x in length]
        if done < 2:
            k = [0.0, 0.0] if done == 0 else [k[0], 0.0]
        s = float(rng.uniform(-60, 60))
        a, b = cat.rod("rod", length[0], k[0]).geometry, cat.rod("rod", length[1], k[1]).geometry
        c = stop_chamfer(s, a, b)
        if not stops[0] <= 2 * c <= stops[1]:  # the planner keeps the faces' turn in the family's range
            continue
        assert c == pytest.approx((s - a.half_angle_deg - b.half_angle_deg) / 2, abs=1e-12)
        left = cat.rod("rod", length[0], k[0], second_stop=c)
        right = cat.rod("rod", length[1], k[1], first_stop=c)
        lo, hi = joint_limits(left.geometry, right.geometry)
        assert hi is not None and abs(hi - s) <= STOP_DEG, (length, k, s, hi)
        assert lo is None or lo < s - 1.0
        left = cat.rod("rod", length[0], k[0], second_under=-c)
        right = cat.rod("rod", length[1], k[1], first_under=-c)
        lo, hi = joint_limits(left.geometry, right.geometry)
        assert lo is not None and abs(lo - s) <= STOP_DEG, (length, k, s, lo)
        assert hi is None or hi > s + 1.0
        done += 1


# --------------------------------------------------------------------------- planner


def test_reachable_chains_come_back_exactly(cat, arrays):
    """Chains of pla-parametric rods with masses inside their ranges, hung by the solver,
    given back as polyline targets: the planner finds rods and masses that hang there."""
    (pf,) = arrays.printed
    rng = np.random.default_rng(1)
    for trial in range(5):
        n = int(rng.integers(5, 12))
        lengths = (rng.choice([25.0, 30.0, 35.5, 40.0, 47.25, 60.0], n) if trial % 2 == 0
                   else rng.uniform(25, 60, n))
        nums = [rod_numbers(cat.rod("rod", float(x)), pf.table, pf.family.template) for x in lengths]
        lo = np.array([x.mass_range[0] for x in nums])
        hi = np.array([x.mass_range[1] for x in nums])
        assert np.all(hi > lo * 1.05)  # a real range to pick from
        masses = lo + rng.random(n) * (hi - lo)
        com = np.array([x.com for x in nums])
        span = lengths.sum() * rng.uniform(0.6, 0.85)
        a, b = np.zeros(2), np.array([span, rng.uniform(-0.2, 0.2) * span])
        eq = solve_equilibrium(lengths, masses, a, b, com=com)
        assert eq.success and eq.stable

        plan = plan_constrained(eq.points, Constraints(), arrays, _problem)
        assert len(plan.rods) == n, trial
        np.testing.assert_allclose(plan.problem.lengths, lengths, rtol=1e-9)
        np.testing.assert_allclose(plan.discretization.points, eq.points, atol=1e-9 * span)
        assert all(abs(t.curvature) < 1e-9 for t in plan.rods)  # straight segments, straight rods
        d = design_chain(plan, "refine")
        err = np.abs(d.check.equilibrium.points - eq.points).max() / math.dist(a, b)
        assert err < 1e-6, (trial, err)
        mb, m = plan.problem.mass_bounds, d.result.masses
        assert np.all(m >= mb[:, 0] * (1 - 1e-9)) and np.all(m <= mb[:, 1] * (1 + 1e-9)), trial
        assert d.check.equilibrium.stable


def _design(curve, arrays, **constraints):
    plan = plan_constrained(curve, Constraints(**constraints), arrays, _problem)
    return plan, design_chain(plan, "refine")


def _centreline_rel(plan, d) -> float:
    curve = plan.curve
    span = math.dist(curve[0], curve[-1])
    k = np.array([t.curvature for t in plan.rods])
    return curve_error(curve, d.check.equilibrium.points, k, span)["rel_span"]


SHAPES = {
    "semicircle": lambda: make_target("semicircle", (0, 0), (200, 0)),
    "triangle": lambda: make_target("triangle", (0, 0), (200, 0), depth=100, apex=0.5),
    # a parabola between anchors 50 mm apart in height (its lowest point 41 mm below A)
    "parabola": lambda: make_target("function", (0, 0), (200, 50), y="0.25*x - 0.006*x*(200 - x)"),
}


@pytest.mark.parametrize("shape", SHAPES)
def test_shapes_hang_along_the_target(shape, arrays):
    curve = SHAPES[shape]()
    span = math.dist(curve[0], curve[-1])
    plan, d = _design(curve, arrays)
    assert plan.unmet_joints == []
    eq = d.check.equilibrium
    assert eq.stable
    # the chain hangs at the planned joints (stops where the masses alone cannot)
    assert np.abs(eq.points - plan.problem.target).max() < 1e-6 * span
    assert _centreline_rel(plan, d) < SHAPE_REL
    mb, m = plan.problem.mass_bounds, d.result.masses
    assert np.all(m >= mb[:, 0] * (1 - 1e-9)) and np.all(m <= mb[:, 1] * (1 + 1e-9))
    r = plan.rods[0]
    assert all(t.family == "rod" and 25 - 1e-9 <= t.length <= 60 + 1e-9 for t in plan.rods)
    assert all(abs(t.curvature) <= min(0.04, max_curvature(t.length)) + 1e-12 for t in plan.rods), r
    if shape == "semicircle":  # the circle's own curvature, 1 / 100 mm
        np.testing.assert_allclose([t.curvature for t in plan.rods], 0.01, rtol=2e-3)
    if shape == "triangle":  # straight sides, straight rods; the apex a joint
        assert all(t.curvature == 0 for t in plan.rods)
        assert np.min(np.hypot(*(plan.discretization.points - [100, -100]).T)) < 1e-9
    # every stop is where the chain rests: the target bend is the limit on its side
    phi = np.degrees(np.diff(plan.problem.angles))
    lim = np.degrees(plan.problem.limits)
    for j in plan.added_stops:
        assert min(abs(lim[j, 0] - phi[j]), abs(lim[j, 1] - phi[j])) < 1e-6, (j, phi[j], lim[j])


@pytest.mark.parametrize("shape", ["semicircle", "parabola"])
def test_free_joints_get_no_stops(shape, arrays):
    curve = SHAPES[shape]()
    plan, d = _design(curve, arrays, joints="free")
    assert plan.added_stops == [] and plan.unmet_joints == []
    own = plan.rods[0].geometry.first
    for t in plan.rods:  # every end the family's own (no flush stop faces)
        assert t.geometry.first == t.geometry.second == own == EndShape(0.2, 45.0, 45.0), t.name
        assert not re.search(r"-[abcd]-?\d", t.name), t.name
    phi = np.degrees(np.diff(plan.problem.angles))
    lim = np.degrees(plan.problem.limits)
    assert np.all(lim[:, 1] > phi + 1.0) and np.all(lim[:, 0] < phi - 1.0), (phi, lim)
    assert d.check.equilibrium.stable
    if shape == "parabola":  # the masses alone hold it
        assert _centreline_rel(plan, d) < SHAPE_REL


def test_concave_polyline_with_free_joints_is_reported(arrays):
    """A concave bend can only rest on a stop; with joints: free the plan says so."""
    curve = np.array([[0.0, 0.0], [60.0, -80.0], [100.0, -60.0], [140.0, -80.0], [200.0, 0.0]])
    plan = plan_constrained(curve, Constraints(joints="free"), arrays, _problem)
    phi = np.degrees(np.diff(plan.problem.angles))
    concave = [j for j in range(phi.size) if phi[j] < -1.0]
    assert concave, phi
    assert plan.added_stops == []
    assert set(concave) <= set(plan.unmet_joints)
    notes = " ".join(plan.notes)
    assert "stop" in notes and "joints: free" in notes and f"{phi[concave[0]]:.1f}" in notes, plan.notes
    # with stops allowed, the same target rests on a stop printed at that bend
    held = plan_constrained(curve, Constraints(), arrays, _problem)
    assert set(concave) <= set(held.added_stops) and held.unmet_joints == []
    for j in concave:
        assert math.degrees(held.problem.limits[j, 1]) == pytest.approx(phi[j], abs=STOP_DEG)


MIRRORED = {
    "semicircle": ("semicircle", {}, None),
    "triangle": ("triangle", {"depth": 100, "apex": 0.5}, None),
    "triangle-30": ("triangle", {"depth": 100, "apex": 0.5}, 30.0),
    "catenary": ("catenary", {"length": 300}, None),
    "concave": ("polyline", {"points": [[0, 0], [60, -80], [100, -60], [140, -80], [200, 0]]}, None),
    "parabola-45": ("function", {"y": "-0.006*x*(200 - x)"}, 45.0),
    "arc-30": ("arc", {"sag": 60}, 30.0),
    "hexagon-30": ("polygon", {"sides": 6}, 30.0),
}


@pytest.mark.parametrize("case", MIRRORED)
def test_symmetric_targets_give_mirrored_rods(case, arrays):
    form, params, pref = MIRRORED[case]
    curve = make_target(form, (0, 0), (200, 0), **params)
    plan = plan_constrained(curve, Constraints(preferred_length=pref), arrays, _problem)
    rods = plan.rods
    n = len(rods)
    assert {n - 2 - j for j in plan.added_stops} == set(plan.added_stops), plan.added_stops
    for i in range(n):
        a, b = rods[i].geometry, rods[n - 1 - i].geometry
        assert a.length == pytest.approx(b.length, abs=1e-6) and a.curvature == pytest.approx(b.curvature, abs=1e-7)
        # the first end of one is the second end of its mirror image (stop chamfers swap)
        for e, f in ((a.first, b.second), (a.second, b.first)):
            assert (e.setback, e.top_chamfer, e.bottom_chamfer) == pytest.approx(
                (f.setback, f.top_chamfer, f.bottom_chamfer), abs=1e-6), (i, rods[i].name, rods[n - 1 - i].name)


# --------------------------------------------------------------------------- rodcad build


def test_build_without_a_catalog_uses_rods_printed_to_order(tmp_path):
    path = tmp_path / "semicircle.yaml"
    path.write_text(DESIGN)
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-m", "rodcad.cli", "build", str(path), "--no-cad", "-q", "-o", str(out)],
                          capture_output=True, text=True, timeout=300, check=False)
    assert proc.returncode == 0, proc.stderr
    data = json.loads((out / "design.json").read_text())
    assert data["catalog"] == "pla-parametric"
    rods = data["rods"]
    assert 4 <= len(rods) <= 12
    for r in rods:
        p = r["params"]
        assert p["family"] == "rod" and 25 - 1e-9 <= r["length"] <= 60 + 1e-9
        assert r["curvature"] == p["curvature"] == pytest.approx(0.01, rel=2e-3)
        assert set(p["ends"]) == {"first", "second"}
        lo, hi = r["mass_range"]
        assert 0 < lo < hi and lo * (1 - 1e-9) <= r["mass"] <= hi * (1 + 1e-9), r
    assert data["curve"]["rel_span"] < SHAPE_REL
    assert data["curve"]["max_mm"] == pytest.approx(data["curve"]["rel_span"] * 200, rel=1e-9)
    sim = data["simulated"]
    assert sim["stable"] and data["error"]["max_rel_span"] < 1e-6
    # a joint on a stop rests on it: the stop listed is the bend the chain hangs at
    bends = np.diff(sim["angles_deg"])
    stops = data["discretisation"]["added_stops"]
    for s in stops:
        j = s["joint"]
        assert s["deg"] == pytest.approx(bends[j], abs=STOP_DEG), (s, bends[j], rods[j]["limits_deg"])
    # every other joint hangs freely, inside what its rods' ends allow (graduated rods' masses
    # may hold every bend: then no joint needs a stop)
    on_stop = {s["joint"] for s in stops}
    for j, bend in enumerate(bends):
        if j not in on_stop:
            lo, hi = (v if v is not None else (-1e9 if k == 0 else 1e9) for k, v in enumerate(rods[j]["limits_deg"]))
            assert lo < bend < hi, (j, bend, rods[j]["limits_deg"])


# --------------------------------------------------------------------------- CAD (one check)


def test_curved_rod_with_stop_ends_builds_a_valid_solid(cat):
    from rodcad.cad.solids import is_valid_solid, mass_properties, type_solid
    from rodcad.catalog.fastgeom import rod_mass_properties

    rod = cat.rod("rod", 42.5, 0.021, first_stop=-7.5, second_stop=6.0, second_under=-12.0)
    solid = type_solid(rod)
    assert is_valid_solid(solid)
    exact = mass_properties(solid)
    volume, com = rod_mass_properties(rod.geometry)
    assert volume == pytest.approx(exact.volume, rel=1e-6)
    assert np.abs(np.subtract(com, exact.center)).max() < 1e-6
    assert com[1] < -1.0  # k > 0 bulges toward -y: the mass below the chord


def test_fast_limits_of_rods_printed_to_order_against_the_brep(cat):
    """The collision-angle lookup at rods sampled over the family's ranges (free ends, top and
    bottom stops at the ends of the stop range, curved and straight, shortest and longest)
    against the B-rep interference search: never more bend than the solids, within 0.05 deg.
    (The B-rep limits of these samples ship in the catalog's seed.)"""
    from rodcad.catalog.limits import TOLERANCE_DEG, all_pair_limits
    from rodcad.catalog.printed import sample_pairs

    pairs = sample_pairs(cat, cat.family("rod"))
    assert len(pairs) >= 7
    ext = cat.with_types([t for p in pairs for t in p])
    brep = all_pair_limits(ext, pairs=pairs, jobs=1)
    for (a, b), r in brep.items():
        fast = joint_limits(ext[a].geometry, ext[b].geometry)
        for side, (f, s) in enumerate(zip(fast, r.limits_deg)):
            if s is not None and abs(s) >= 180 - 10 * TOLERANCE_DEG:
                s = None  # the search's bound: nothing stops before it
            assert (f is None) == (s is None), (a, b, fast, r.limits_deg)
            if f is None:
                continue
            assert abs(f - s) <= 0.05, (a, b, fast, r.limits_deg)
            looser = (s - f) if side == 0 else (f - s)
            assert looser <= TOLERANCE_DEG, (a, b, fast, r.limits_deg)


def test_rods_printed_to_order_are_built_and_checked(tmp_path):
    """Curved rods with stop ends printed to order, through the whole build: every solid valid,
    STEP re-imported with its volume and STL watertight (checked by the build, exit 0 or 1),
    each rod built at its designed mass, and the chain as built hangs as designed."""
    path = tmp_path / "d.yaml"
    path.write_text("design: 1\nname: small-arc\nanchors: [[0, 0], [120, 0]]\ntarget: {form: semicircle}\n"
                    "constraints: {rods: 4}\n")
    out = tmp_path / "out"
    assert main(["build", str(path), "-o", str(out), "--jobs", "1", "-q"]) == 0
    data = json.loads((out / "design.json").read_text())
    rods = data["rods"]
    assert len(rods) == 4 and all(r["params"]["family"] == "rod" for r in rods)
    assert all(abs(r["curvature"]) > 0.01 for r in rods)  # a 60 mm radius: curved bodies
    assert any(r["params"]["ends"]["second"]["setback"] == 0 for r in rods[:-1])  # a stop printed to order
    for r in rods:
        assert r["fabrication"]["in_range"]
        # the rod as built weighs what it hangs less its joint hardware's metal
        assert r["fabrication"]["mass"] == pytest.approx(r["hardware"]["printed_mass"], rel=2e-3)
    assert data["as_built"]["error"]["max_rel_span"] < 1e-3
    assert data["curve"]["rel_span"] < SHAPE_REL
    assert len(list((out / "rods").glob("*.step"))) == 4 and len(list((out / "rods").glob("*.stl"))) == 4


def test_print_resolution_rounds_every_length():
    """``length: {min, max, resolution}``: every rod's length a multiple of the resolution, the
    chain closed on its anchors again, still on the curve; a range holding no multiple is
    bad input at the key."""
    text = PARAM.replace("length: {min: 20, max: 60}", "length: {min: 20, max: 60, resolution: 0.5}")
    cat = catalog_from_text(text)
    assert cat.family("rod").ranges.resolution == 0.5
    arrays = catalog_arrays(cat)
    a, b = np.array([0.0, 0.0]), np.array([200.0, 0.0])
    curve = make_target("semicircle", a, b)
    plan = plan_constrained(curve, Constraints(), arrays, _problem)
    lengths = plan.problem.lengths
    np.testing.assert_allclose(lengths / 0.5, np.round(lengths / 0.5), atol=1e-9)
    np.testing.assert_allclose(plan.problem.target[[0, -1]], [a, b], atol=1e-9)
    d = design_chain(plan, "refine")
    k = np.array([t.curvature for t in plan.rods])
    assert curve_error(curve, d.check.equilibrium.points, k, 200.0)["rel_span"] < SHAPE_REL
    bad = PARAM.replace("length: {min: 20, max: 60}", "length: {min: 20.1, max: 20.4, resolution: 0.5}")
    got = _bad(bad)
    assert [g[2] for g in got] == ["families[0].length.resolution"], got
