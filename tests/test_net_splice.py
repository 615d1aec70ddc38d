"""Rigid in-line splices (issue 33): a drawn edge whose two-rod joints cannot hang, longer than
one rod between the family's largest hubs, is one rigid rod printed in pieces glued on steel
dowel pins (rodcad.catalog.net.splice, rodcad.cad.net.splice), the planner's default.

Truth: the pieces' own B-rep (OCC's volumes and centre of mass against the closed form), the
drawn ladder's rungs (straight, where drawn), and MuJoCo (tests/mujoco_net.py, no rodcad code)
for the spliced net's equilibrium.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from build123d import Axis, CenterOf
from net_settle import settle_from_other_masses

from rodcad.cad.net.build import build_group
from rodcad.cad.net.parts import PartTask, RodSpec
from rodcad.cad.net.splice import spliced_rod_solids
from rodcad.catalog.loader import catalog_from_text, load_catalog
from rodcad.catalog.net.splice import Splice, piece_extents, splice_fill
from rodcad.cli import main
from rodcad.design.loader import load_design
from rodcad.pipeline.net import build_net, write_net_outputs
from rodcad.errors import InputError
from rodcad.catalog.paths import default_catalog_dir

#: OCC integrates a solid's volume of cylinders and spheres to about 1e-9 of it; its boolean
#: faces to about 1e-7 mm: the closed form and the B-rep agree within this share.
VOLUME_REL = 1e-6


@pytest.fixture(scope="module")
def hw():
    return load_catalog("pla-parametric").node


@pytest.mark.parametrize("length, pieces", [(100.0, 2), (150.0, 3)])
def test_a_spliced_rods_masses_are_its_solids_and_its_centre_of_mass_stays_at_mid_length(hw, length, pieces):
    rn = hw.rod_numbers(length, pieces)
    rho = hw.density / 1000.0
    ball = hw.insert_density * math.pi / 6 * hw.insert_diameter ** 3 / 1000.0
    pins = (pieces - 1) * hw.splice.pin_mass
    ivs = hw.rod_intervals(length, pieces)
    assert min(lo for _, lo, _ in ivs) == pytest.approx(rn.mass_range[0])
    assert max(hi for _, _, hi in ivs) == pytest.approx(rn.mass_range[1])
    for mass in (rn.mass_range[0], float(np.mean(rn.mass_range)), rn.mass_range[1]):
        fills, got = splice_fill(hw, length, mass, pieces)
        assert len(fills) == pieces and fills[0] == fills[-1]  # the two ends alike
        whole, parts = spliced_rod_solids(hw, length, fills)
        assert whole.is_valid and all(p.is_valid for p in parts) and len(parts) == pieces
        built = rho * whole.volume + sum(b for b, _ in fills) * ball + pins
        assert built == pytest.approx(got, rel=VOLUME_REL)
        assert sum(p.volume for p in parts) == pytest.approx(whole.volume, rel=VOLUME_REL)
        # the plastic is symmetric about mid-length (and so are the balls, alike pieces filled alike)
        com = whole.center(CenterOf.MASS)
        assert abs(com.X - length / 2) < 1e-6 * length and abs(com.Y) < 1e-9 and abs(com.Z) < 1e-9
        for (x0, x1, _, _), p in zip(piece_extents(hw, length, pieces), parts):
            box = p.bounding_box()
            assert x1 - x0 == pytest.approx(length / pieces)  # equal shares, each within the catalog's lengths
            assert box.min.X >= x0 - hw.ball / 2 - 1e-6 and box.max.X <= x1 + hw.ball / 2 + 1e-6
    # the lightest holds no balls and the heaviest the most; a choice in between lies in a segment
    assert splice_fill(hw, length, rn.mass_range[0], pieces)[0][0][0] == 0
    assert sum(b for b, _ in splice_fill(hw, length, rn.mass_range[1], pieces)[0]) == rn.balls


@pytest.mark.parametrize("length, pieces", [(110.0, 2), (160.0, 3)])
def test_a_spliced_rods_part_is_built_written_and_checked_its_equal_pieces_once(hw, length, pieces):
    """Its pieces are the printed solids (STEP re-imported at the same volume, STL watertight:
    rodcad.cad.export.check_files inside the task), the two end pieces one solid printed twice
    (the same turned end for end), the whole rod is what hangs."""
    fills, _ = splice_fill(hw, length, 0.5 * sum(hw.rod_numbers(length, pieces).mass_range), pieces)
    spec = RodSpec(hw, length, sum(b for b, _ in fills), sum(c for _, c in fills), None, tuple(fills))
    res = build_group(PartTask("rod", [spec, spec], "rod-007", (0.03, 0.2)))
    labels = [label for label, _ in res.solids]
    assert labels == ["rod-007-a", "rod-007-b"][: min(pieces, 3) - 1] and res.copies == [2, pieces - 2][: len(labels)]
    assert res.whole and all(res.confirmed) and all(set(f) == {".step", ".stl"} for f in res.files)
    whole, parts = spliced_rod_solids(hw, length, fills)
    assert res.volumes[0] == pytest.approx(whole.volume, rel=VOLUME_REL)
    # the end piece turned end for end is the last piece: the same volume and moments
    flipped = parts[-1].rotate(Axis.Y, 180)
    assert flipped.volume == pytest.approx(parts[0].volume, rel=VOLUME_REL)
    assert np.allclose(_moments(flipped), _moments(parts[0]), rtol=VOLUME_REL)
    printed = sum(c * v for c, v in zip(res.copies, res.mesh_volumes))
    assert printed == pytest.approx(whole.volume, rel=0.01)  # (meshed at 0.03 mm)


def _moments(solid) -> np.ndarray:
    """The solid's principal moments of inertia about its centre of mass (sorted)."""
    from OCP.GProp import GProp_GProps
    from OCP.BRepGProp import BRepGProp

    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(solid.wrapped, props)
    p = props.PrincipalProperties()
    return np.sort(np.array(p.Moments()))


def _ladder(width: float = 130.0, n: int = 5, step: float = 48.0) -> str:
    """Two rails hung from their ends (catenaries), joined by rungs ``width`` apart: a rung
    between two rails pulls nothing, so joints on it cannot hang."""
    xs = np.arange(n) * step
    z = 200.0 * np.cosh((xs - xs.mean()) / 200.0)
    z = z - z[0]
    nodes = [[float(x), 0.0, round(float(h), 4)] for x, h in zip(xs, z)]
    nodes += [[float(x), width, round(float(h), 4)] for x, h in zip(xs, z)]
    edges = [[i, i + 1] for i in range(n - 1)] + [[n + i, n + i + 1] for i in range(n - 1)]
    edges += [[i, n + i] for i in range(1, n - 1)]
    return (f"design: 1\nname: ladder\nnet:\n  nodes: {nodes}\n  edges: {edges}\n"
            f"  anchored: [0, {n - 1}, {n}, {2 * n - 1}]\n")


def test_slack_rungs_are_spliced_rods_and_the_ladder_hangs_where_drawn_as_mujoco_agrees(tmp_path):
    d = load_design("ladder.yaml", text=_ladder())
    b = build_net(d)  # (the pipeline's design: the planner's choice, no switches)
    check = b.check
    plan, t = check.plan, check.plan.target
    rungs = [e for e, (i, j) in enumerate(t.edges) if abs(j - i) == 5]
    assert len(rungs) == 3 and t.m == 11 and (t.joints is None or not len(t.joints))  # no joint left
    assert np.all(plan.rod_pieces[rungs] == 2) and np.all(np.delete(plan.rod_pieces, rungs) == 1)
    lo, hi = plan.length_range
    assert np.all(plan.lengths[rungs] > hi + 2 * plan.hardware.pivot_limits[1] - 2 * plan.hardware.pivot)
    assert np.all(plan.piece_lengths <= hi) and np.all(plan.piece_lengths >= lo)
    assert check.ok and check.rel_size <= 1e-6  # (the rails' masses balance the rungs' weight exactly)
    # MuJoCo, each spliced rod one rigid body of its pieces' and pins' mass, released from another
    # shape of the same rods, rests where rodcad's equilibrium is
    err, moved = settle_from_other_masses(check, 5)
    assert moved > 1e-3 * t.size and err < 1e-5 * t.size  # (it travelled, and came back)
    # design.json, the bill and the report say which rods are spliced and what to buy
    write_net_outputs(b, tmp_path / "out")
    data = json.loads((tmp_path / "out" / "design.json").read_text())
    assert [s["rod"] for s in data["planner"]["spliced_rods"]] == rungs
    rod = data["net"]["rods"][rungs[0]]
    assert rod["pieces"] == 2 and rod["splice"]["dowel_pins"] == 1
    assert [p["to"] - p["from"] for p in rod["splice"]["pieces"]] == pytest.approx([rod["length"] / 2] * 2)
    bom = data["bill_of_materials"]
    assert bom["dowel_pins"] == 3 and bom["rod_pieces"] == t.m + 3
    pins = 3 * plan.hardware.splice.pin_mass
    balls = sum(r["steel_balls"] for r in data["net"]["rods"]) * plan.hardware.insert_density * math.pi / 6 * \
        plan.hardware.insert_diameter ** 3 / 1000.0
    assert bom["rod_plastic_g"] == pytest.approx(sum(r["mass"] for r in data["net"]["rods"]) - pins - balls)
    report = (tmp_path / "out" / "report.md").read_text()
    assert "3 steel dowel pins" in report and "spliced from printed pieces" in report


def test_a_catalogs_splice_is_read_and_a_pin_too_thick_is_refused_at_its_key():
    text = (default_catalog_dir() / "pla-parametric.yaml").read_text()
    shipped = "  splice: {pin_diameter: 3, pin_length: 16, pin_density: 7.85, clearance: 0.1}\n"
    assert shipped in text and catalog_from_text(text, "c.yaml").node.splice == Splice()  # (the defaults)
    ok = catalog_from_text(text.replace(shipped, "  splice: {pin_diameter: 4, pin_length: 20}\n"), "c.yaml").node
    assert ok.splice.pin_diameter == 4 and ok.splice.pin_length == 20 and ok.splice.depth == 10.5
    assert ok.splice.pin_density == Splice().pin_density  # (unset keys: the defaults)
    bad = text.replace(shipped, "  splice:\n    pin_diameter: 8\n")
    with pytest.raises(InputError) as err:
        catalog_from_text(bad, "c.yaml")
    line = next(i for i, s in enumerate(bad.splitlines(), 1) if s == "  splice:") + 1
    got = [str(p) for p in err.value.problems]
    assert any(g.startswith(f"c.yaml:{line}:") and "node.splice.pin_diameter" in g and "wall" in g for g in got), got


#: A hub hung from three anchors by straight edges of 108-110 mm (tests/test_net_planner.py's
#: TRIPOD): its joints cannot hang, each edge is a rod spliced from two pieces.
TRIPOD = ("design: 1\nname: tripod\nnet:\n  nodes: [[0, 0, 0], [160, 0, 0], [80, 140, 0], [80, 46, -60]]\n"
          "  edges: [[0, 3], [1, 3], [2, 3]]\n  anchored: [0, 1, 2]\n")


def test_a_spliced_nets_files_print_each_piece_and_assemble_each_rod_whole(tmp_path):
    from build123d import import_step

    (tmp_path / "tripod.yaml").write_text(TRIPOD)
    out = tmp_path / "out"
    assert main(["build", str(tmp_path / "tripod.yaml"), "-o", str(out), "--quiet"]) == 0
    data = json.loads((out / "design.json").read_text())
    rods = data["net"]["rods"]
    assert [r["pieces"] for r in rods] == [2, 2, 2]
    parts = {p["name"]: p for p in data["cad"]["parts"] if p["kind"] == "rod"}
    # one end piece per distinct rod, printed twice a rod: rods 0 and 1 mirror each other (x = 80)
    assert sorted(parts) == ["rod-000-a", "rod-002-a"]
    assert parts["rod-000-a"]["members"] == [0, 1] and parts["rod-000-a"]["count"] == 4
    assert parts["rod-002-a"]["count"] == 2
    assert sorted(f.name for f in (out / "rods").glob("*.step")) == ["rod-000-a.step", "rod-002-a.step"]
    vol = {0: parts["rod-000-a"]["volume_mm3"], 1: parts["rod-000-a"]["volume_mm3"], 2: parts["rod-002-a"]["volume_mm3"]}
    # assembly.step: each rod whole where it hangs (its two pieces' plastic), rods first in order
    # (build123d names an instance after its shared shape: rod 1 reads as rod-000)
    asm = list(import_step(out / "assembly.step").children)
    for e in range(3):
        assert asm[e].label.startswith("rod-")
        whole = asm[e].solids()
        assert len(whole) == 1 and whole[0].is_valid
        assert whole[0].volume == pytest.approx(2 * vol[e], rel=VOLUME_REL)
    # the as-built net (every solid's own volume, the pins' steel) hangs where it was designed
    assert data["as_built"]["error"]["max_rel_size"] < 1e-3
    assert "straight, 2 pieces" in (out / "view.html").read_text()  # (the 3D view's rod table says so)
