"""Graduated rods (issue 26): a body section at its own scale on the family's hinge ends.

Against truth: the closed-form volume and centre of mass against the B-rep, the joint
limits of rods of different scales against the B-rep search (stops too), the default
catalog's mass span at one length measured on the solids with their cavities and balls, a
scaled rod through fabrication and its files, and bad scale ranges.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rodcad.cad.solids import build_rod, is_valid_solid, mass_properties, void_solids
from rodcad.catalog.fastgeom import RodClearance, rod_mass_properties
from rodcad.catalog.jointlimits import joint_limits
from rodcad.catalog.limits import TOLERANCE_DEG, compute_pair_limits
from rodcad.catalog.loader import load_catalog
from rodcad.catalog.massrange import ball_layout, cavity_layout
from rodcad.catalog.printed import mass_table
from rodcad.catalog.scaling import mass_span, scale_for_mass
from tests.catalog_testutil import problems

#: The B-rep search brackets each contact to TOLERANCE_DEG and reports the middle.
BREP_SLACK = TOLERANCE_DEG / 2 + 1e-9


@pytest.fixture(scope="module")
def cat():
    return load_catalog("pla-parametric")


def test_scale_one_is_the_family_rod(cat) -> None:
    """A rod at scale 1 keeps today's name, geometry and cache keys."""
    r = cat.rod("rod", 40.0, 0.01)
    assert r.name == "rod-40-k10" and not r.geometry.graduated and r.geometry.body_height is None
    assert "body_height" not in r.geometry.key_data()
    s = cat.rod("rod", 40.0, 0.01, scale=1.25)
    assert s.name == "rod-40-s1.25-k10" and s.scale == 1.25 and s.geometry.graduated
    assert cat.can_join(r, s) and cat.can_join(s, r)  # the hinge ends are the family's
    with pytest.raises(ValueError, match="outside"):
        cat.rod("rod", 40.0, scale=2.0)


@pytest.mark.parametrize("length, k, scale, ends", [
    (40.0, 0.0, 0.55, {}), (40.0, 0.0, 1.6, {}), (30.0, 0.03, 0.7, {"first_stop": 20.0}),
    (45.0, -0.04, 1.3, {"second_under": -20.0, "first_stop": -30.0}), (34.0, 0.05, 0.8, {}),
    (60.0, 0.02, 1.4, {"second_stop": 40.0}),
])
def test_closed_form_mass_and_com_equal_the_brep(cat, length, k, scale, ends) -> None:
    g = cat.rod("rod", length, k, scale=scale, **ends).geometry
    solid = build_rod(g)
    assert is_valid_solid(solid)
    brep = mass_properties(solid)
    vol, com = rod_mass_properties(g)
    assert vol == pytest.approx(brep.volume, rel=1e-6)
    assert np.allclose(com, brep.center, rtol=0, atol=1e-6 * length)
    # the clearance is the solid's: points on a grid inside are inside the solid
    clear = RodClearance(g)
    (x0, y0, z0), (x1, y1, z1) = clear.bounds
    pts = np.stack(np.meshgrid(np.linspace(x0, x1, 9), np.linspace(y0, y1, 7), np.linspace(z0, z1, 5)),
                   -1).reshape(-1, 3)
    from OCP.BRepClass3d import BRepClass3d_SolidClassifier
    from OCP.gp import gp_Pnt
    from OCP.TopAbs import TopAbs_IN

    for p, c in zip(pts, clear(pts)):
        if abs(c) < 1e-3:
            continue
        inside = BRepClass3d_SolidClassifier(solid.wrapped, gp_Pnt(*map(float, p)), 1e-7).State() == TopAbs_IN
        assert inside == (c > 0), (p, c)


def _agrees(fast, brep, where) -> None:
    for side, (a, b) in enumerate(zip(fast, brep)):
        assert (a is None) == (b is None), (where, fast, brep)
        if a is None:
            continue
        assert abs(a - b) <= 0.05, (where, side, a, b)
        assert (b - a if side == 0 else a - b) <= BREP_SLACK, (where, side, a, b)  # never looser


@pytest.mark.parametrize("left, right", [
    ((40.0, 0.0, 0.55, {}), (40.0, 0.0, 1.6, {})),
    ((40.0, 0.0, 1.6, {}), (50.0, 0.0, 1.6, {})),
    ((40.0, 0.02, 0.7, {"second_stop": 20.0}), (30.0, -0.02, 1.5, {"first_stop": 20.0})),
    ((60.0, 0.0, 1.6, {"second_under": -30.0}), (50.0, 0.0, 0.55, {"first_under": -30.0})),
])
def test_joint_limits_of_different_scales_agree_with_the_solids(cat, left, right) -> None:
    a = cat.rod("rod", left[0], left[1], scale=left[2], **left[3]).geometry
    b = cat.rod("rod", right[0], right[1], scale=right[2], **right[3]).geometry
    r = compute_pair_limits(a, b, 1.2)
    _agrees(joint_limits(a, b), (r["lo"], r["hi"]), (left, right))


def test_a_flush_stop_between_a_thin_and_a_thick_rod_stops_at_its_bend(cat) -> None:
    """Faces through the hinge axis meet at the sum of their chamfers whatever their heights:
    on the solids, a 90 degree stop between the thinnest and the thickest rod."""
    a = cat.rod("rod", 60.0, scale=0.55, second_stop=45.0).geometry
    b = cat.rod("rod", 60.0, scale=1.6, first_stop=45.0).geometry
    r = compute_pair_limits(a, b, 1.2)
    assert r["hi"] == pytest.approx(90.0, abs=0.05)
    assert joint_limits(a, b)[1] == pytest.approx(90.0, abs=0.05)


def test_mass_span_of_one_length_on_the_solids(cat) -> None:
    """The lightest (thinnest, most cavities) and heaviest (thickest, most balls) 60 mm rods
    of the default catalog, measured on their B-reps with the balls: at least 5:1."""
    length = 60.0
    s0, s1 = cat.scale_range("rod", length)
    light, heavy = cat.rod("rod", length, scale=s0), cat.rod("rod", length, scale=s1)
    rho = light.material.density / 1000
    cav = cavity_layout(light)
    solid = build_rod(light.geometry).cut(*void_solids("capped", cav.centers, cav.radius))
    m_light = mass_properties(solid).volume * rho
    balls = ball_layout(heavy)
    socks = void_solids("silo", balls.centers, heavy.balls.socket_diameter / 2)
    solid = build_rod(heavy.geometry).cut(*socks)
    m_heavy = mass_properties(solid).volume * rho + balls.count * heavy.balls.mass
    assert balls.count > 0 and cav.count > 0
    assert m_heavy / m_light >= 5.0, (m_light, m_heavy)
    table = mass_table(cat.family("rod"))
    lo, hi = mass_span(cat, "rod", table, length)
    assert lo == pytest.approx(m_light, rel=0.02) and hi == pytest.approx(m_heavy, rel=0.02)


def test_scale_for_a_mass(cat) -> None:
    table = mass_table(cat.family("rod"))
    lo, hi = mass_span(cat, "rod", table, 45.0, 0.01)
    for mass in np.linspace(lo, hi, 5):
        choice = scale_for_mass(cat, "rod", table, 45.0, float(mass), 0.01)
        assert choice is not None
        m0, m1 = choice.numbers.mass_range
        assert m0 - 1e-9 <= mass <= m1 + 1e-9
        assert choice.scales[0] <= choice.scale <= choice.scales[1]
        assert choice.rod.scale == choice.scale
        # on the grid of a thousandth the rods' names round to, or an end of the scale range
        assert abs(choice.scale * 1000 - round(choice.scale * 1000)) < 1e-9 or choice.scale in cat.scale_range("rod", 45.0, 0.01)
    assert scale_for_mass(cat, "rod", table, 45.0, hi * 1.01, 0.01) is None
    # the chosen scale puts the mass nearest the middle: a slightly other scale is further off
    choice = scale_for_mass(cat, "rod", table, 45.0, (lo + hi) / 2, 0.01)
    assert choice is not None and choice.scales[0] < choice.scale < choice.scales[1]
    off = abs(sum(choice.numbers.mass_range) / 2 - (lo + hi) / 2)
    for ds in (-0.02, 0.02):
        other = cat.rod("rod", 45.0, 0.01, scale=choice.scale + ds)
        from rodcad.catalog.printed import rod_numbers

        nums = rod_numbers(other, table, cat.family("rod").template)
        assert abs(sum(nums.mass_range) / 2 - (lo + hi) / 2) >= off


def test_scaled_rods_fabricated_and_written(cat, tmp_path: Path) -> None:
    """A thin rod with cavities and a thick one with balls: valid solids, STL watertight, STEP
    re-imported valid with the same volume, as-built mass and com from the solids."""
    import trimesh

    from rodcad.cad.export import import_step
    from rodcad.cad.chainfiles import write_rod_files
    from rodcad.cad.rods import fabricate_chain
    from rodcad.catalog.massrange import mass_info

    thin, thick = cat.rod("rod", 40.0, 0.01, scale=0.6), cat.rod("rod", 40.0, -0.01, scale=1.5)
    masses = [mass_info(thin).m_min, mass_info(thick).m_max]
    fab = fabricate_chain([thin, thick], masses, seed=1, jobs=1)
    for rod, m, f in zip((thin, thick), masses, fab.rods):
        assert is_valid_solid(f.solid)
        props = mass_properties(f.solid)
        rho = rod.material.density / 1000
        mass = props.volume * rho + f.ball_count * rod.balls.mass
        c = np.array(props.center) * props.volume * rho
        if f.ball_count:
            c += rod.balls.mass * f.socket_centers.sum(axis=0)
        assert mass == pytest.approx(m, rel=1e-3)
        _, com = rod_mass_properties(rod.geometry)
        assert np.allclose((c / mass)[:2], com[:2], atol=1e-6)
    assert fab.rods[0].cavity_count > 0 and fab.rods[1].ball_count > 0
    write_rod_files(fab, tmp_path)
    for f in fab.rods:
        back = import_step(tmp_path / "rods" / f"{f.file_stem}.step")
        assert is_valid_solid(back)
        assert back.volume == pytest.approx(f.plastic_volume, rel=1e-6)
        assert back.bounding_box().min.Z == pytest.approx(0, abs=1e-6)  # on its flat bottom face
        mesh = trimesh.load(str(tmp_path / "rods" / f"{f.file_stem}.stl"), force="mesh")
        assert mesh.is_watertight


GRADED = """\
catalog: 1
name: test
printer: {build_volume: [220, 220, 250], nozzle: 0.4}
defaults:
  section: {height: 16, thickness: 16}
  joint: {pin_diameter: 3, knuckle_radius: 5, tongue_thickness: 5.6}
  ends: {setback: 0.2, top_chamfer: 45, bottom_chamfer: 45}
  material: {density: 1.24, min_wall: 1.2}
families:
  - name: rod
    length: {min: 20, max: 60}
    stops: {min: -90, max: 90}
    scale: SCALE
"""


@pytest.mark.parametrize("scale, key, words", [
    ("{min: 1.2, max: 0.8}", "families[0].scale.max", "inverted"),
    ("{min: 1.2, max: 1.2}", "families[0].scale.max", "empty"),
    ("{min: 0.4, max: 1.2}", "families[0].scale.min", "thinner than the hinge needs"),
    ("{min: 0.8, max: 3.0}", "families[0].scale.max", "too thick for the hinge ends"),
])
def test_bad_scale_ranges(tmp_path: Path, scale: str, key: str, words: str) -> None:
    got = problems(tmp_path, GRADED.replace("SCALE", scale))
    assert len(got) == 1, got
    line, col, k, msg = got[0]
    assert k == key and words in msg
    assert line == 13 and col > 0  # at the scale range in the file


def test_a_scale_range_that_no_longer_fits_the_printer(tmp_path: Path) -> None:
    text = GRADED.replace("SCALE", "{min: 0.8, max: 2.2}").replace("[220, 220, 250]", "[220, 220, 30]")
    got = problems(tmp_path, text)
    assert [(k, "does not fit the printer" in m) for _, _, k, m in got] == [("families[0].scale.max", True)]


def test_scale_range_cli_exit_2(tmp_path: Path, capsys) -> None:
    from rodcad.cli import main

    path = tmp_path / "bad.yaml"
    path.write_text(GRADED.replace("SCALE", "{min: 1.2, max: 0.8}"))
    assert main(["catalog", "check", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"{path}:13:" in err and "families[0].scale.max" in err


def test_outputs_show_the_scale(cat) -> None:
    """design.json params carry the scale (and the body's section); the previews draw each
    rod with a line width proportional to its body's height."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from rodcad.outputs.design_json import rod_params
    from rodcad.outputs.preview import draw_rods

    thin, thick = cat.rod("rod", 40.0, scale=0.6), cat.rod("rod", 40.0, scale=1.5)
    p = rod_params(thick)
    assert p["scale"] == 1.5 and p["body"] == {"height": 24.0, "thickness": 24.0}
    assert p["section"] == {"height": 16.0, "thickness": 16.0}  # the hinge ends
    assert "body" not in rod_params(cat.rod("rod", 40.0))
    fig, ax = plt.subplots()
    pts = np.array([[0.0, 0.0], [40.0, -10.0], [80.0, 0.0]])
    lc, _ = draw_rods(ax, pts, [0.0, 0.0], [5.0, 20.0], [g.body_h for g in (thin.geometry, thick.geometry)])
    w = lc.get_linewidths()
    assert w[1] / w[0] == pytest.approx(24.0 / 9.6)
    plt.close(fig)
