"""Several kinds of metal ball per family (issue 14): steel first, a denser kind only where
steel cannot make a rod heavy enough, one kind per rod; the catalog check names the kind
behind each heaviest mass, and the bill of materials and the print pauses count balls by kind."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from catalog_testutil import BASE, problems
from rodcad.cad.printfile import _message
from rodcad.cad.rods import MASS_TOL, fabricate_rod
from rodcad.catalog.cache import DiskCache
from rodcad.catalog.loader import catalog_from_text
from rodcad.catalog.massrange import compute_mass_info
from rodcad.commands.catalog import _balls_json
from rodcad.fabrication.intervals import compute_table
from rodcad.outputs.design_json import metal_balls

ROOT = Path(__file__).resolve().parents[1]
STEEL = "{name: steel ball 6 mm, diameter: 6.0, density: 7.85, clearance: 0.2}"
CARBIDE = "{name: tungsten carbide ball 6 mm, diameter: 6.0, density: 15.6, clearance: 0.2}"
SMALL = "{name: steel ball 4 mm, diameter: 4.0, density: 7.85}"
KINDS = (ROOT / "catalogs" / "pla-parametric.yaml").read_text().replace(
    "  balls: {name: steel bearing ball 6 mm, diameter: 6.0, density: 7.85, clearance: 0.2}",
    f"  balls:\n    - {STEEL}\n    - {CARBIDE}\n    - {SMALL}")


@pytest.fixture(scope="module")
def catalog():
    assert "tungsten carbide" in KINDS
    return catalog_from_text(KINDS, "kinds.yaml")


def test_kinds_load_in_order(catalog):
    rod = catalog.rod("rod", 40.0)
    assert [b.name for b in rod.ball_kinds] == ["steel ball 6 mm", "tungsten carbide ball 6 mm", "steel ball 4 mm"]
    assert rod.balls is rod.ball_kinds[0] and rod.heavier == rod.ball_kinds[1:]
    assert rod.ball_kinds[2].clearance == 0.2  # defaults filled in list items too
    one = rod.with_kind(1)
    assert one.ball_kinds == (rod.ball_kinds[1],) and one.geometry == rod.geometry


def test_the_heaviest_mass_is_the_best_kind_and_named(catalog):
    """mass_info over kinds is the heaviest of each kind alone; a 60 mm rod is heaviest with
    carbide balls, a 20 mm rod (no room for 6 mm sockets) with the 4 mm balls."""
    for length, best in ((60.0, 1), (20.0, 2)):
        rod = catalog.rod("rod", length)
        info = compute_mass_info(rod)
        alone = [compute_mass_info(rod.with_kind(k)) for k in range(3)]
        assert info.kind_max == tuple((a.ball_count, pytest.approx(a.m_max, rel=1e-12)) for a in alone)
        assert info.m_max == pytest.approx(max(a.m_max for a in alone), rel=1e-12)
        assert info.ball_kind == best and info.ball_count == alone[best].ball_count
        assert info.m_min == pytest.approx(alone[0].m_min, rel=1e-12)  # cavities do not depend on balls
        entry = _balls_json(rod, info)
        assert entry["kind"] == rod.ball_kinds[best].name and len(entry["kinds"]) == 3
    # a denser ball of the same size always adds mass: carbide beats steel where 6 mm fits
    rod = catalog.rod("rod", 60.0)
    steel, carbide = (compute_mass_info(rod.with_kind(k)) for k in (0, 1))
    assert steel.ball_count == carbide.ball_count > 0 and carbide.m_max > 1.5 * steel.m_max - 0.5 * steel.solid_mass


def test_a_later_kind_only_extends_the_top(catalog):
    """The table of reachable masses: every subset of steel balls, carbide (and 4 mm) subsets
    only above the heaviest steel one, so rods a steel set can make never take carbide."""
    rod = catalog.rod("rod", 40.0)
    table = compute_table(rod, 0)
    top_steel = max(o["mass"] for o in table["options"] if o["kind"] == 0)
    later = [o for o in table["options"] if o["kind"] > 0]
    assert later and all(o["mass"] > top_steel for o in later)
    assert table["intervals"][-1][1] == pytest.approx(compute_mass_info(rod).m_max, rel=1e-9)


def test_a_rod_beyond_steel_is_built_with_carbide(catalog, tmp_path):
    """Fabricated on the B-rep: the mass within MASS_TOL, the kind recorded, the centre of mass
    where the rod's own is (symmetric sockets)."""
    rod = catalog.rod("rod", 40.0)
    table = compute_table(rod, 0)
    steel_top = max(o["mass"] for o in table["options"] if o["kind"] == 0)
    lo, hi = next((a, b) for a, b in table["intervals"] if a > steel_top * (1 + 1e-6))
    target = 0.5 * (lo + hi)
    fab = fabricate_rod(rod, target, seed=0, cache=DiskCache(tmp_path))
    assert fab.ball_name == "tungsten carbide ball 6 mm" and fab.ball_count > 0
    assert fab.ball_mass_each == pytest.approx(np.pi / 6 * 6.0**3 * 15.6 / 1000, rel=1e-12)
    assert abs(fab.mass - target) <= MASS_TOL * target and fab.in_range
    info = compute_mass_info(rod)
    assert fab.com[0] == pytest.approx(info.com[0], abs=0.05) and abs(fab.com[1]) < 0.05
    light = fabricate_rod(rod, 0.5 * (steel_top + table["intervals"][0][0]), seed=0, cache=DiskCache(tmp_path))
    assert light.ball_name in ("", "steel ball 6 mm")


def test_bill_and_pauses_count_balls_by_kind():
    counts = {(6.0, "steel ball 6 mm"): 4, (6.0, "tungsten carbide ball 6 mm"): 2, (4.0, ""): 3}
    bom = metal_balls(counts)
    assert [(b["diameter_mm"], b["kind"], b["count"]) for b in bom] == [
        (4.0, None, 3), (6.0, "steel ball 6 mm", 4), (6.0, "tungsten carbide ball 6 mm", 2)]

    def placed(stem, name, n):
        rod = SimpleNamespace(file_stem=stem, ball_diameter=6.0, ball_name=name, fill_mass=0.0, fill_name="")
        return SimpleNamespace(rod=rod, pauses={5.0: n})

    msg = _message([placed("00_a", "steel ball 6 mm", 2), placed("01_b", "tungsten carbide ball 6 mm", 2),
                    placed("02_c", "steel ball 6 mm", 2)], 5.0)
    assert "insert 4 balls of 6 mm (2 in each of rods 00, 02) [steel ball 6 mm]" in msg
    assert "insert 2 balls of 6 mm (rod 01) [tungsten carbide ball 6 mm]" in msg


def test_bad_ball_kinds(tmp_path):
    """Every kind checked at its own key: a ball too big for the section, a density of zero,
    a missing diameter, the same kind twice."""
    text = BASE.replace("families:", "  balls:\n    - {diameter: 3, density: 7.85}\n"
                        "    - {diameter: 3.5, density: 15.6}\n    - {density: 0}\nfamilies:")
    found = problems(tmp_path, text)
    assert any(k == "defaults.balls[2].density" and "greater than 0" in m for _, _, k, m in found), found
    assert all(line > 0 and col > 0 for line, col, _, _ in found), found
    text = BASE.replace("families:", "  balls:\n    - {diameter: 3, density: 7.85}\n"
                        "    - {diameter: 9, density: 15.6}\n    - {diameter: 2}\nfamilies:")
    found = problems(tmp_path, text)
    assert found == [(10, 7, "defaults.balls[2]", "missing required key 'density'")], found
    text = BASE.replace("families:", "  balls:\n    - {diameter: 3, density: 7.85}\n"
                        "    - {diameter: 9, density: 15.6}\nfamilies:")
    found = problems(tmp_path, text)
    assert [(k, "section" in m) for _, _, k, m in found] == [("defaults.balls[1].diameter", True)], found
    assert found[0][0] == 9 and found[0][1] > 0
    dup = BASE.replace("families:", "  balls: [{diameter: 3, density: 7.85}, {diameter: 3, density: 7.85}]\nfamilies:")
    found = problems(tmp_path, dup)
    assert any(k == "defaults.balls[1]" and "duplicate" in m for _, _, k, m in found), found
