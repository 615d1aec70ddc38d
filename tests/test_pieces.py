"""Fused pieces printed as one solid (issue 15): ``constraints: {fuse: stops}`` turns runs of
joints on stops into rigid pieces; each piece is ONE part in every output (rods/, assembly,
print.3mf, design.json, report.md) and ``rodcad check`` measures it as a whole."""

from __future__ import annotations

import dataclasses
import json
import zipfile

import numpy as np
import pytest

from rodcad.cli import main

DESIGN = """design: 1
name: fused-triangle
anchors: [[0, 0], [150, 0]]
target: {form: triangle, depth: 60}
constraints: {fuse: stops}
"""


@pytest.fixture(scope="module")
def built(build_design):
    return build_design(DESIGN, "fused", "--jobs", "1")


def test_the_plan_fuses_and_each_piece_is_one_file(built):
    out, data = built
    assert data["fused"] == [[0, 1], [2, 3]]
    stems = {p.stem for p in (out / "rods").glob("*.step")}
    assert stems == {"00-01_piece", "02-03_piece"}  # no per-rod files of rods inside a piece
    assert {p.stem for p in (out / "rods").glob("*.stl")} == stems
    assert {p.stem for p in (out / "rods").glob("*.3mf")} == stems
    for rod in data["rods"]:
        a, b = rod["fabrication"]["piece"]
        assert a <= rod["index"] <= b and rod["fabrication"]["file"] == f"rods/{a:02d}-{b:02d}_piece.step"
    bom = data["bill_of_materials"]
    assert bom["pins"]["count"] == 1 + 2  # the one free joint plus the anchors
    assert [p["rods"] for p in bom["pieces"]] == [[0, 1], [2, 3]]
    report = (out / "report.md").read_text()
    assert "(one piece: rods 0-1)" in report and "rods 2 to 3 are ONE printed piece" in report


def test_a_piece_is_one_valid_solid_with_its_rods_mass_and_centre_of_mass(built):
    from rodcad.cad.export import import_step, placed
    from rodcad.cad.solids import is_valid_solid, mass_properties

    out, data = built
    rho = data["print"]["density"] / 1000.0
    for a, b in data["fused"]:
        rods = data["rods"][a:b + 1]
        fabs = [r["fabrication"] for r in rods]
        solid = import_step(out / fabs[0]["file"])
        assert is_valid_solid(solid)
        # the bridges add as much as they take (the widened hole): the rods' plastic exactly
        assert solid.volume == pytest.approx(sum(f["plastic_volume_mm3"] for f in fabs), rel=1e-7)
        first = placed(solid, np.linalg.inv(fabs[0]["print_matrix"]))  # the first rod's frame
        props = mass_properties(first)
        mass = props.volume * rho + sum(f["ball_mass_g"] for f in fabs)
        moment = props.volume * rho * np.array(props.center[:2])
        want = np.zeros(2)
        for f in fabs:
            m = np.linalg.inv(fabs[0]["print_matrix"]) @ np.array(f["print_matrix"])  # rod -> first rod frame
            balls = np.array(f["ball_centers"]).reshape(-1, 3)
            if len(balls):
                moment += f["ball_mass_g"] / len(balls) * (balls @ m[:2, :3].T + m[:2, 3]).sum(axis=0)
            want += f["mass"] * (m[:2, :2] @ f["com"] + m[:2, 3])
        assert mass == pytest.approx(sum(f["mass"] for f in fabs), rel=1e-7)
        np.testing.assert_allclose(moment / mass, want / mass, atol=1e-5)
        # the fused joint is bridged: its layer gaps are filled out at the knuckle's rim
        hinge = rods[0]["params"]
        assert hinge["pin_diameter"] > 0
        knuckle = 5.0 - 0.4  # just inside the default family's 5 mm knuckle
        x = rods[0]["length"]
        gap_z = 2.8 + 0.15  # in the layer gap between tongue (5.6 mm) and fork (0.3 mm gap)
        assert first.is_inside((x + knuckle * np.cos(2.0), knuckle * np.sin(2.0), gap_z))


def test_the_assembly_and_print_file_hold_the_pieces(built):
    from rodcad.cad.export import assembly_leaves
    from rodcad.cad.printfile import MODEL_CONFIG_FILE, PAUSES_FILE

    out, data = built
    labels = [label for label, _ in assembly_leaves(out / "assembly.step")]
    assert sum("00-01_piece" in s for s in labels) == 1 and sum("02-03_piece" in s for s in labels) == 1
    pins = sorted(s for s in labels if s.startswith("pin_"))
    assert pins == ["pin_00", "pin_02", "pin_04"]  # none at the fused joints 1 and 3
    assert not any("_rod-" in s for s in labels)
    z = zipfile.ZipFile(out / "print.3mf")
    config = z.read(MODEL_CONFIG_FILE).decode()
    assert "00-01_piece" in config and "02-03_piece" in config and "_rod-" not in config
    balls = sum(r["fabrication"]["balls"] for r in data["rods"])
    if balls:
        pauses = z.read(PAUSES_FILE).decode()
        assert "piece 00-01" in pauses or "rods 00-01" in pauses


def test_check_reads_each_piece_once_and_reproduces_the_design(built, capsys):
    out, data = built
    capsys.readouterr()
    assert main(["check", str(out), "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["edited"] == [] and res["ok"]
    assert res["error_vs_design"]["max_rel_span"] < 1e-6
    for got, rod in zip(res["rods"], data["rods"]):
        assert got["file"].endswith(rod["fabrication"]["file"])
        assert got["mass"] == pytest.approx(rod["fabrication"]["mass"], rel=1e-7)


def test_an_edited_piece_is_edited_as_a_whole(built, tmp_path, capsys):
    import shutil

    from rodcad.cad.export import export_step, import_step
    from rodcad.cad.solids import one_solid
    from build123d import Box, Location

    out, data = built
    copy = tmp_path / "edited"
    shutil.copytree(out, copy)
    step = copy / "rods" / "02-03_piece.step"
    solid = import_step(step)
    bb = solid.bounding_box()
    cx = (bb.min.X + bb.max.X) / 2  # a notch in the top face, in the middle of the piece
    notch = Box(4, 4, 2).moved(Location((cx + 20, (bb.min.Y + bb.max.Y) / 2, bb.max.Z)))
    export_step(one_solid(solid.cut(notch), "a notch"), step, "02-03_piece")
    capsys.readouterr()
    main(["check", str(copy), "--json"])
    res = json.loads(capsys.readouterr().out)
    assert res["edited"] == [2, 3]
    before = sum(r["fabrication"]["mass"] for r in data["rods"][2:4])
    after = sum(r["mass"] for r in res["rods"][2:4])
    assert after < before
    # the rods keep their mass proportions
    assert res["rods"][2]["mass"] / res["rods"][3]["mass"] == pytest.approx(
        data["rods"][2]["fabrication"]["mass"] / data["rods"][3]["fabrication"]["mass"], rel=1e-9)
    capsys.readouterr()
    assert main(["check", str(copy), "--rebalance", "--json"]) == 1
    assert "fused pieces" in json.loads(capsys.readouterr().out)["notes"][-1]


def test_mixed_ball_kinds_or_fill_chambers_are_refused():
    from rodcad.cad.pieces import fuse_piece
    from rodcad.cad.rods import FabricatedRod
    from rodcad.fabrication.cavities import FabricationError

    base = FabricatedRod(index=0, type_name="t", target_mass=1.0, mass=1.0, com=(1.0, 0.0), plastic_volume=1.0,
                         filament_mass=1.0, cavity_count=0, cavity_radius=0.0, ball_count=2, ball_diameter=6.0,
                         pause_z=1.0, mass_error=0.0, in_range=True, message="", solid=None,
                         cavity_centers=np.zeros((0, 3)), socket_centers=np.zeros((2, 3)), ball_name="steel 6 mm",
                         ball_mass_each=0.89)
    other = dataclasses.replace(base, index=1, ball_diameter=8.0, ball_name="steel 8 mm", ball_mass_each=2.11)
    pts = np.array([[0.0, 0.0], [10.0, 0.0], [20.0, 0.0]])
    with pytest.raises(FabricationError, match="2 kinds"):
        fuse_piece([base, other], pts, [])
    filled = dataclasses.replace(base, index=1, fill_mass=3.0, fill_name="shot", ball_count=0)
    with pytest.raises(FabricationError, match="fill chamber"):
        fuse_piece([base, filled], pts, [])
