"""``constraints: {same_shell: true}`` (issue 14, the paper's Fig. 7): every rod of a chain
printed to order gets one outer shell (one length, one curvature, the family's own ends);
the masses differ only inside. Fast: the planner and ``pipeline.build(design, cad=False)``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rodcad import pipeline
from rodcad.catalog.loader import load_catalog
from rodcad.catalog.model import EndShape
from rodcad.design.loader import load_design
from rodcad.design.model import Constraints
from rodcad.design.plan import catalog_arrays, plan_constrained
from rodcad.design.targets import make_target
from rodcad.errors import InputError, Problem

#: a parabola between anchors 50 mm apart in height: its curvature changes along the curve
PARABOLA = dict(form="function", a=(0, 0), b=(200, 50), y="0.25*x - 0.006*x*(200 - x)")


@pytest.fixture(scope="module")
def arrays():
    return catalog_arrays(load_catalog("pla-parametric"))


def _problem(key: str, message: str) -> Problem:
    return Problem("<test>", 0, 0, key, message)


def _parabola() -> np.ndarray:
    p = dict(PARABOLA)
    return make_target(p.pop("form"), p.pop("a"), p.pop("b"), **p)


def _one_shell(rods, ends: bool = True) -> None:
    g0 = rods[0].geometry
    for t in rods:
        assert t.geometry.length == g0.length and t.geometry.curvature == g0.curvature, t.name
        if ends:
            assert t.geometry.first == t.geometry.second == g0.first, t.name


def test_every_rod_gets_one_shell(arrays):
    """On a parabola the rods laid one by one differ in length or curvature; with
    same_shell they are one rod: equal chords (every joint on the curve), the mean of the
    fitted curvatures, the family's own ends, and masses that differ."""
    curve = _parabola()
    own = plan_constrained(curve, Constraints(joints="free"), arrays, _problem)
    ks = np.array([t.geometry.curvature for t in own.rods])
    assert np.ptp(ks) > 1e-4  # the curve's curvature changes: the rods laid one by one differ
    plan = plan_constrained(curve, Constraints(joints="free", same_shell=True), arrays, _problem)
    _one_shell(plan.rods)
    assert plan.rods[0].geometry.first == EndShape(0.2, 45.0, 45.0)
    assert len(set(plan.type_names)) == 1 and plan.added_stops == []
    # equal chords between joints on the curve, landing on both anchors
    pts = plan.discretization.points
    chords = np.hypot(*np.diff(pts, axis=0).T)
    assert np.ptp(chords) < 1e-6 and np.allclose(pts[[0, -1]], curve[[0, -1]])
    # the one curvature: the mean of the fitted ones (not clipped here)
    from optimize.chain.curves import fit_curvatures
    assert plan.rods[0].geometry.curvature == pytest.approx(float(np.mean(fit_curvatures(curve, pts))), abs=1e-9)
    assert any("one shell" in n and "only inside" in n for n in plan.notes), plan.notes


def test_stops_keep_length_and_curvature_only(arrays):
    """With stops allowed (and needed: the semicircle's masses cannot hold it alone in the
    shipped catalog), the rods beside a stop get its faces; same_shell keeps one length and
    one curvature and says so."""
    curve = make_target("semicircle", (0, 0), (200, 0))
    plan = plan_constrained(curve, Constraints(same_shell=True), arrays, _problem)
    assert plan.added_stops
    _one_shell(plan.rods, ends=False)
    assert any("keeps the length and the curvature only" in n for n in plan.notes), plan.notes


def test_corners_are_joints_or_bad_input(arrays):
    """A polyline whose legs share a rod length (40 + 60 mm: 20 mm rods) keeps its corner as a
    joint; legs with no common length in the range forbid one shell: exit 2 at the key."""
    curve = np.array([[0.0, 0.0], [0.0, -40.0], [60.0, -40.0], [60.0, 0.0]])
    plan = plan_constrained(curve, Constraints(joints="free", same_shell=True), arrays, _problem)
    _one_shell(plan.rods)
    pts = plan.discretization.points
    for c in curve[1:-1]:
        assert np.hypot(*(pts - c).T).min() < 1e-9
    bad = np.array([[0.0, 0.0], [0.0, -41.0], [60.0 * math.sqrt(2), -41.0], [60.0 * math.sqrt(2), 0.0]])
    with pytest.raises(InputError) as err:
        plan_constrained(bad, Constraints(same_shell=True), arrays, _problem)
    assert [p.key for p in err.value.problems] == ["constraints.same_shell"]
    assert "corner" in err.value.problems[0].message


DESIGN = """\
design: 1
name: shell
anchors: [[0, 0], [200, 0]]
target: {form: polygon, sides: 6}
constraints: {joints: free, same_shell: true%s}
"""


def test_build_without_cad(tmp_path):
    """Through the pipeline: one rod type for the whole chain, masses that differ."""
    (tmp_path / "d.yaml").write_text(DESIGN % "")
    d = load_design(tmp_path / "d.yaml")
    assert d.constraints.same_shell and d.constraints.joints == "free"
    r = pipeline.build(d, cad=False)
    assert len(set(r.type_names)) == 1 and len(r.type_names) == 6
    assert r.masses.max() > 1.2 * r.masses.min()  # the masses differ, inside one shell
    assert r.plan is not None and any("one shell" in n for n in r.plan.notes)


def test_bad_input(tmp_path):
    """same_shell with lengths (every rod gets one length anyway), and with a catalog of
    fixed rod types: exit 2 at the key, with the file's line and column."""
    text = DESIGN % ", lengths: [40]"
    (tmp_path / "d.yaml").write_text(text)
    d = load_design(tmp_path / "d.yaml")
    with pytest.raises(InputError) as err:
        pipeline.build(d, cad=False)
    (p,) = err.value.problems
    assert p.key == "constraints.lengths" and "same_shell" in p.message and p.line == 5 and p.column > 1
    assert str(tmp_path / "d.yaml") in str(err.value) or "d.yaml" in str(err.value)
    (tmp_path / "w.yaml").write_text(DESIGN.replace("name: shell", "name: shell\ncatalog: pla-weighted") % "")
    with pytest.raises(InputError) as err:
        pipeline.build(load_design(tmp_path / "w.yaml"), cad=False)
    assert [p.key for p in err.value.problems] == ["constraints.same_shell"]
    (tmp_path / "s.yaml").write_text(DESIGN.replace("same_shell: true", "same_shell: 3") % "")
    with pytest.raises(InputError) as err:
        load_design(tmp_path / "s.yaml")
    assert any(p.key == "constraints.same_shell" for p in err.value.problems)
