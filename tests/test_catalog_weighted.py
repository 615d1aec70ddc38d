"""The pla-weighted catalog (asymmetric ends, wider mass ranges) and what the chain
planner makes of it on the paper's shapes.

Computing every limit and mass range of this catalog from the B-rep takes minutes
cold, so most tests read the catalog's check table from ``data/pla-weighted.check.json``
(the output of ``rodcad catalog check pla-weighted --json``) and one test recomputes a
sample of it from the solids to show that the table is current. Regenerate the table
after changing the catalog, the rod geometry or the limit or mass code.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from rodcad.catalog.limits import all_pair_limits
from rodcad.catalog.loader import load_catalog
from rodcad.design.masses import design_chain
from rodcad.design.plan import CatalogArrays, plan_chain
from rodcad.design.targets import heart, make_target

CHECK = Path(__file__).with_name("data") / "pla-weighted.check.json"
A, B = (0.0, 0.0), (200.0, 0.0)

#: End shape at (first, second) joint per family: F free, S straight stop, C concave stop,
#: V5 / V10 / V12.5 convex stop (flush, top chamfer +5 / +10 / +12.5 deg).
ENDS = {
    "free": ("F", "F"),
    "straight": ("S", "S"),
    "straight-free": ("S", "F"),
    "free-straight": ("F", "S"),
    "concave20": ("C", "S"),
    "curve10": ("V5", "V5"),
    "curve20": ("V10", "V10"),
    "curve25": ("V12.5", "V12.5"),
}


@pytest.fixture(scope="module")
def cat():
    return load_catalog("pla-weighted")


@pytest.fixture(scope="module")
def check():
    return json.loads(CHECK.read_text())


@pytest.fixture(scope="module")
def arrays(cat, check):
    """What :func:`rodcad.design.plan.catalog_arrays` returns, from the check table."""
    types = list(cat)
    by_name = {t["name"]: t for t in check["types"]}
    assert [t.name for t in types] == [t["name"] for t in check["types"]]
    lengths = np.array([by_name[t.name]["length"] for t in types])
    com = np.array([by_name[t.name]["com"] for t in types])
    bounds = np.array([by_name[t.name]["mass_range"] for t in types])
    index = {t.name: i for i, t in enumerate(types)}
    lim = np.full((len(types), len(types), 2), np.nan)
    for p in check["pairs"]:
        lo, hi = p["limits_deg"]
        lim[index[p["left"]], index[p["right"]]] = [
            -math.inf if lo is None else math.radians(lo), math.inf if hi is None else math.radians(hi)]
    return CatalogArrays(tuple(types), lengths, com, bounds, lim)


def _family(check, name):
    return next(t["family"] for t in check["types"] if t["name"] == name)


def test_catalog_loads_with_mixed_end_families(cat, check):
    assert cat.name == "pla-weighted"
    assert {f.name for f in cat.families} == set(ENDS)
    assert cat.names == [t["name"] for t in check["types"]]
    for ty in cat:
        g = ty.geometry
        first, second = ENDS[ty.family]
        for end, kind in ((g.first, first), (g.second, second)):
            assert (end.setback == 0) == (kind != "F")
    assert len(check["pairs"]) == len(cat) ** 2  # every rod can follow every other


def test_limits_follow_the_end_shapes(check):
    """Per (left rod's second end, right rod's first end): S-S stops at exactly 0, S-C at
    -20, F-F bends past 100 degrees both ways; convex stops add their chamfers (V5-V10 stops
    at +15, V10-C at -10, F-V10 at about 65.8); everything bends past -100 the other way."""
    expected_hi = {("S", "S"): 0.0, ("S", "C"): -20.0, ("F", "F"): 110.9, ("F", "S"): 55.8,
                   ("S", "F"): 55.8, ("F", "C"): 35.8,
                   ("S", "V5"): 5.0, ("S", "V10"): 10.0, ("V5", "S"): 5.0, ("V10", "S"): 10.0,
                   ("V5", "V5"): 10.0, ("V5", "V10"): 15.0, ("V10", "V5"): 15.0, ("V10", "V10"): 20.0,
                   ("V5", "C"): -15.0, ("V10", "C"): -10.0,
                   ("F", "V5"): 60.8, ("F", "V10"): 65.8, ("V5", "F"): 60.8, ("V10", "F"): 65.8,
                   ("S", "V12.5"): 12.5, ("V12.5", "S"): 12.5, ("V5", "V12.5"): 17.5,
                   ("V12.5", "V5"): 17.5, ("V10", "V12.5"): 22.5, ("V12.5", "V10"): 22.5,
                   ("V12.5", "V12.5"): 25.0, ("V12.5", "C"): -7.5, ("F", "V12.5"): 68.3,
                   ("V12.5", "F"): 68.3}
    for p in check["pairs"]:
        key = (ENDS[_family(check, p["left"])][1], ENDS[_family(check, p["right"])][0])
        lo, hi = p["limits_deg"]
        assert hi == pytest.approx(expected_hi[key], abs=0.1), (p, key)
        assert lo < -100
        if "F" not in key:  # flush faces: exact to the search tolerance
            assert hi == pytest.approx(expected_hi[key], abs=0.005)


def test_mass_ranges_are_wider_than_pla_pinned(check):
    ratios = {t["name"]: t["mass_range"][1] / t["mass_range"][0] for t in check["types"]}
    assert min(ratios.values()) > 1.2
    assert max(ratios.values()) > 1.4
    lo = min(t["mass_range"][0] for t in check["types"])
    hi = max(t["mass_range"][1] for t in check["types"])
    assert hi / lo > 2.4  # across types (30 and 40 mm)
    for t in check["types"]:
        assert t["balls"]["diameter"] == 6.0 and t["balls"]["count"] >= 1


def test_check_table_matches_the_solids(cat, check, tmp_path, monkeypatch):
    """A sample of the stored limits, recomputed from the B-rep (no cache, no seeds)."""
    monkeypatch.setenv("RODCAD_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("RODCAD_SEED_CACHE", "0")
    sample = [("straight-30", "straight-free-30"), ("straight-free-30", "free-straight-30"),
              ("free-straight-30", "concave20-30"), ("curve10-30", "curve20-30")]
    fresh = all_pair_limits(cat, pairs=[(cat[a], cat[b]) for a, b in sample], jobs=2)
    assert all(not r.cached for r in fresh.values())
    stored = {(p["left"], p["right"]): p["limits_deg"] for p in check["pairs"]}
    for key, r in fresh.items():
        assert r.limits_deg == pytest.approx(tuple(stored[key]), abs=1e-3), key


def _stops_and_free(plan):
    bends = np.diff(plan.problem.angles)
    lim = plan.problem.limits
    stops = np.flatnonzero(np.abs(bends) < 1e-9)
    corners = np.flatnonzero(bends > np.radians(30))
    return bends, lim, stops, corners


@pytest.mark.parametrize("form, params", [
    ("triangle", {"depth": math.sqrt(150**2 - 100**2)}),  # sides of 5 x 30 mm
    ("polygon", {"sides": 3}),
])
def test_corners_bend_freely_and_straight_sides_rest_on_stops(cat, arrays, form, params):
    plan = plan_chain(cat, make_target(form, A, B, **params), arrays=arrays)
    bends, lim, stops, corners = _stops_and_free(plan)
    assert plan.assign_cost == 0 and not plan.unmet_joints and not plan.notes
    assert corners.size == (1 if form == "triangle" else 2)
    assert stops.size == bends.size - corners.size
    np.testing.assert_array_equal(lim[stops, 1], bends[stops])  # stops exactly at straight
    assert np.all(lim[corners, 1] > bends[corners] + np.radians(3))
    for j in corners:  # the rods meeting at a corner have free ends there
        assert plan.type_names[j].endswith("free-30") or plan.type_names[j].startswith("straight-free")
        assert plan.type_names[j + 1].startswith(("free-straight", "free-"))
    for j in stops:
        assert plan.type_names[j].startswith(("straight", "free-straight"))
    d = design_chain(plan, "refine", n_starts=4)
    assert d.result.exact and d.result.distance.max_rel_span < 1e-9
    eq = d.result.equilibrium
    assert np.all(eq.active[stops] == 1) and np.all(eq.moments[stops] <= 0)


def _concave_polyline():
    # down at -40 deg for 90 mm, a -20 deg (concave) bend, down at -60 deg for 90 mm,
    # a 100 deg corner, up at +40 deg for 120 mm
    pts = [np.zeros(2)]
    for ang, length in ((-40, 90), (-60, 90), (40, 120)):
        a = math.radians(ang)
        pts.append(pts[-1] + length * np.array([math.cos(a), math.sin(a)]))
    return np.array(pts)


def test_straight_run_leads_into_a_concave_stop(cat, arrays):
    plan = plan_chain(cat, _concave_polyline(), arrays=arrays, lengths=[30])
    bends = np.diff(plan.problem.angles)
    j = int(np.argmin(bends))
    assert np.degrees(bends[j]) == pytest.approx(-20.0, abs=1e-6)
    assert plan.type_names[j + 1] == "concave20-30"
    assert plan.type_names[j].startswith(("straight", "free-straight"))
    assert plan.problem.limits[j, 1] == bends[j] and not plan.unmet_joints
    d = design_chain(plan, "exact", n_starts=4)
    assert d.result.exact, d.result.message
    assert d.result.equilibrium.active[j] == 1 and d.result.equilibrium.moments[j] < 0


def test_concave_bend_without_a_stop_type_is_explained_and_best_fit(cat, arrays):
    allowed = [t.name for t in cat if t.family in ("free", "straight")]
    plan = plan_chain(cat, _concave_polyline(), arrays=arrays, lengths=[30], allowed_types=allowed)
    j = int(np.argmin(np.diff(plan.problem.angles)))
    assert any(f"joint {j} needs a stop at -20.0 deg, but the nearest stop" in note for note in plan.notes)
    assert np.degrees(plan.joint_mismatch[j]) == pytest.approx(20.0, abs=0.01)  # straight: 0 deg
    assert "as well as they can" in plan.notes[-1]
    d = design_chain(plan, "refine", n_starts=4)
    assert d.result.success and not d.result.exact
    assert 1e-4 < d.result.distance.max_rel_span < 0.2
    lo, hi = plan.problem.mass_bounds.T
    assert np.all((d.result.masses >= lo) & (d.result.masses <= hi))


def test_heart_tip_bends_freely_and_is_a_bounded_best_fit(cat, arrays):
    plan = plan_chain(cat, heart(A, B), arrays=arrays)
    bends = np.diff(plan.problem.angles)
    tip = int(np.argmax(bends))
    assert np.degrees(bends[tip]) > 60
    assert plan.problem.limits[tip, 1] > bends[tip] + np.radians(3)
    assert not plan.unmet_joints and np.degrees(plan.assign_cost) < 2.0
    assert any(name.startswith("straight") for name in plan.type_names)  # the straight sides
    d = design_chain(plan, "refine", n_starts=4)
    assert d.result.success and d.result.distance.max_rel_span < 0.1


def _hang_error(plan, result) -> float:
    """Hausdorff distance (mm) between the target curve and the hanging chain."""
    from optimize.chain.curves import curve_distance

    return curve_distance(plan.curve, result.equilibrium.points)


def test_semicircle_rests_on_curve_stops_where_the_masses_cannot_hold_it(cat, arrays):
    """The semicircle's near-vertical ends need end rods many times heavier than the
    middle ones; no type's mass range allows that, so the planner rests the middle joints
    on curve stops (20 to 25 degrees) and the design becomes exact, and hangs closer to
    the curve than the masses-only best fit."""
    target = make_target("semicircle", A, B)
    free = plan_chain(cat, target, arrays=arrays, add_stops=False)
    plan = plan_chain(cat, target, arrays=arrays)
    assert not free.added_stops and plan.added_stops
    bends = np.diff(plan.problem.angles)
    for j in plan.added_stops:
        assert plan.problem.limits[j, 1] == bends[j]  # the joint sits exactly on its stop
        assert round(np.degrees(bends[j]), 2) in (15.0, 17.5, 20.0, 22.5, 25.0)
        assert plan.type_names[j].startswith("curve") and plan.type_names[j + 1].startswith("curve")
    assert "rest on stops" in plan.notes[0]
    d_free = design_chain(free, "refine", n_starts=4)
    d = design_chain(plan, "refine", n_starts=4)
    assert not d_free.result.exact and d_free.result.distance.max_rel_span > 0.02
    assert d.result.exact and d.result.distance.max_rel_span < 1e-9, d.result.message
    eq = d.result.equilibrium
    assert np.all(eq.active[plan.added_stops] == 1) and np.all(eq.moments[plan.added_stops] <= 0)
    assert _hang_error(plan, d.result) < 0.8 * _hang_error(free, d_free.result)


def test_heart_sides_are_held_straight_by_added_stops(cat, arrays):
    target = heart(A, B)
    free = plan_chain(cat, target, arrays=arrays, add_stops=False)
    plan = plan_chain(cat, target, arrays=arrays)
    bends = np.diff(plan.problem.angles)
    assert plan.added_stops and np.all(np.abs(bends[plan.added_stops]) < 1e-9)  # straight
    d_free = design_chain(free, "refine", n_starts=4)
    d = design_chain(plan, "refine", n_starts=4)
    assert d.result.distance.max_rel_span < 0.2 * d_free.result.distance.max_rel_span
    assert _hang_error(plan, d.result) < 0.5 * _hang_error(free, d_free.result)
