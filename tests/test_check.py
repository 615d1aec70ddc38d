"""`rodcad check OUTDIR [--rebalance]`: the round trip after editing rods by hand.

A small chain (a catenary of 5 rods printed to order) is built with CAD once; rods are then
edited the way a person does in a CAD program (build123d here): a bead fused onto one
rod's side face, a groove cut across another's top, saved back as STEP in the same
placement on the bed. `check` must report the shape a forward simulation gives with the
edited rods' masses and centres of mass measured independently (trimesh on an STL of the
solids), and `--rebalance` must bring the chain back onto its design.
"""

from __future__ import annotations

import hashlib
import json
import math
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from mesh_accuracy import measure
from optimize import solve_equilibrium
from rodcad.cli import main

ROOT = Path(__file__).resolve().parents[1]

DESIGN = """\
design: 1
name: roundtrip
anchors: [[0, 0], [160, 0]]
target: {form: catenary, length: 220}
constraints: {rods: 5}
"""

#: The bead's radius (mm) and the groove's length (mm): heavy enough to move the chain
#: by more than 0.2 % of its span, light enough to be balanced.
BEAD_R = 7.0
GROOVE_L = 12.0

#: Edited rods: rods next to each other, so the other three can balance them.
BEAD_ROD, GROOVE_ROD = 1, 2


def _b3d():
    import build123d

    return build123d


def _step(folder: Path, data: dict, i: int) -> Path:
    return folder / data["rods"][i]["fabrication"]["file"]


def _read(path: Path):
    (solid,) = _b3d().import_step(path).solids()
    return solid


def _write(solid, path: Path) -> None:
    assert _b3d().export_step(solid, path)


def _bead(solid, r: float = BEAD_R):
    """A sphere fused onto the rod's side face (the rod frame's +z face, the bed's -Y), off
    the middle towards the second joint."""
    b = _b3d()
    bb = solid.bounding_box()
    at = ((bb.min.X + bb.max.X) / 2 + 8, bb.min.Y, (bb.min.Z + bb.max.Z) / 2)
    (out,) = solid.fuse(b.Solid.make_sphere(r).moved(b.Location(at))).solids()
    return out


def _groove(solid, length: float = GROOVE_L):
    """A groove engraved into the rod's other side face (the rod frame's -z face, the bed's
    +Y), 3 mm wide and 1.5 mm deep, along the rod."""
    b = _b3d()
    bb = solid.bounding_box()
    at = ((bb.min.X + bb.max.X - length) / 2, bb.max.Y - 1.5, (bb.min.Z + bb.max.Z) / 2 - 1.5)
    (out,) = solid.cut(b.Solid.make_box(length, 3.0, 3.0).moved(b.Location(at))).solids()
    return out


def _copy(src: Path, dst: Path) -> Path:
    shutil.copytree(src, dst)
    return dst


def _snapshot(folder: Path) -> dict[str, str]:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def _limits(data: dict) -> np.ndarray:
    lim = [r["limits_deg"] for r in data["rods"][:-1]]
    return np.array([[-np.inf if lo is None else math.radians(lo), np.inf if hi is None else math.radians(hi)]
                     for lo, hi in lim])


def _check(args: list[str], capsys) -> tuple[int, dict | None, str]:
    code = main(["check", *args])
    out, err = capsys.readouterr()
    return code, (json.loads(out) if "--json" in args and out.strip() else None), err


@pytest.fixture(scope="module")
def built(build_design, tmp_path_factory):
    # the default catalog's family at one section: a re-balance keeps each rod's scale, and
    # at a graduated rod's scale the next ball count may lie beyond the mass an edit needs
    root = tmp_path_factory.mktemp("one-scale")
    text = (ROOT / "catalogs" / "pla-parametric.yaml").read_text(encoding="utf-8")
    text = text.replace("name: pla-parametric\n", "name: pla-parametric-one-scale\n", 1).replace(
        "    scale: {min: 0.55, max: 1.6}\n", "")
    (root / "one-scale.yaml").write_text(text, encoding="utf-8")
    return build_design(DESIGN + f"catalog: {root / 'one-scale.yaml'}\n", "roundtrip", "--jobs", "1")


@pytest.fixture(scope="module")
def edited(built, tmp_path_factory):
    """The build with a bead on rod 1 and a groove in rod 2, saved back in place."""
    src, data = built
    out = _copy(src, tmp_path_factory.mktemp("edited") / "chain")
    for i, edit in ((BEAD_ROD, _bead), (GROOVE_ROD, _groove)):
        path = _step(out, data, i)
        _write(edit(_read(path)), path)
    return out, data


#: Linear deflection (mm) asked of the independent meshes. BRepMesh keeps the angular
#: deflection (0.05 rad) rather than this on the rods' large-radius curved faces, so their
#: accuracy is measured on the meshes themselves (tests/mesh_accuracy.py): about 6e-4 of a
#: rod's volume here.
MESH_TOL = 1e-4


@dataclass
class _Measured:
    """Edited rod i measured independently: mass (g) and (along, perp) com (mm), with the
    bounds that follow from the meshes' accuracy."""

    mass: float
    com: np.ndarray
    mass_bound: float
    com_bound: float


def _independent(built_dir: Path, edited_dir: Path, data: dict, i: int, tmp: Path) -> _Measured:
    """Mass (g) and (along, perp) centre of mass of edited rod i: design.json's as-built rod
    plus what the edit added (or minus what it cut), both measured by trimesh on STLs of the
    original and the edited solid, each mesh's error bounded from its own triangles
    (tests/mesh_accuracy.py). The two meshes need not be drawn alike: nothing is assumed
    to cancel."""
    fab = data["rods"][i]["fabrication"]
    rho = data["print"]["density"] / 1000.0
    m = np.array(fab["print_matrix"], float)
    com_bed = m[:3, :3] @ np.array([*fab["com"], 0.0]) + m[:3, 3]
    orig = measure(_read(_step(built_dir, data, i)), tmp / f"orig{i}.stl", tolerance=MESH_TOL, about=com_bed)
    edit = measure(_read(_step(edited_dir, data, i)), tmp / f"edit{i}.stl", tolerance=MESH_TOL, about=com_bed)
    mass = fab["mass"] + rho * (edit.volume - orig.volume)
    # first moments about the design's centre of mass, on the bed
    first = rho * (edit.volume * (edit.center - com_bed) - orig.volume * (orig.center - com_bed))
    com = m[:3, :3].T @ (com_bed + first / mass - m[:3, 3])
    mass_bound = rho * (orig.volume_bound + edit.volume_bound)
    moment_bound = rho * (orig.moment_bound + edit.moment_bound)
    com_bound = (moment_bound + mass_bound * float(np.linalg.norm(first / mass))) / (mass - mass_bound)
    # and absolutely: the original's mesh alone, plus its balls, is design.json's mass
    # within that mesh's accuracy
    assert abs(rho * orig.volume + fab["ball_mass_g"] - fab["mass"]) <= rho * orig.volume_bound
    return _Measured(mass, com[:2], mass_bound, com_bound)


def test_check_reports_the_shape_of_the_edited_rods(built, edited, tmp_path, capsys):
    src, data = built
    out, _ = edited
    code, res, err = _check([str(out), "--json", "--preview", str(tmp_path / "check.png")], capsys)
    assert code == 0, err
    n = len(data["rods"])
    assert [r["edited"] for r in res["rods"]] == [i in (BEAD_ROD, GROOVE_ROD) for i in range(n)]
    assert res["edited"] == [BEAD_ROD, GROOVE_ROD]
    assert res["joints"] == []  # the bead and the groove keep clear of the neighbours
    assert (tmp_path / "check.png").stat().st_size > 10_000
    span = math.dist(*data["anchors"])
    # unedited rods: design.json's as-built numbers
    for r, d in zip(res["rods"], data["rods"]):
        if not r["edited"]:
            assert r["mass"] == pytest.approx(d["fabrication"]["mass"], rel=1e-9)
            assert np.allclose(r["com"], d["fabrication"]["com"], atol=1e-6)
    # edited rods: as measured independently, within the meshes' accuracy
    masses = np.array([r["mass"] for r in res["rods"]])
    com = np.array([r["com"] for r in res["rods"]])
    for i in (BEAD_ROD, GROOVE_ROD):
        ind = _independent(src, out, data, i, tmp_path)
        with capsys.disabled():
            print(f"\nrod {i}: check {masses[i]:.6f} g, meshes {ind.mass:.6f} +- {ind.mass_bound:.2g} g; "
                  f"com off by {np.linalg.norm(com[i] - ind.com):.2g} mm (bound {ind.com_bound:.2g} mm)")
        assert abs(masses[i] - ind.mass) <= ind.mass_bound
        assert np.linalg.norm(com[i] - ind.com) <= ind.com_bound
        # the edit is several times larger than what the meshes leave uncertain (the groove,
        # 54 mm^3, about 9 times), so the comparison tells an edit from none
        assert abs(ind.mass - data["rods"][i]["fabrication"]["mass"]) > 5 * ind.mass_bound
    assert masses[BEAD_ROD] > data["rods"][BEAD_ROD]["fabrication"]["mass"] * 1.05  # the bead adds > 5 %
    assert masses[GROOVE_ROD] < data["rods"][GROOVE_ROD]["fabrication"]["mass"]
    # and check's chain is the forward simulation with those masses and centres of mass
    lengths = np.array([d["length"] for d in data["rods"]])
    a, b = np.array(data["anchors"], float)
    # with the joint hardware's metal on the rods' hinge axes (design.json rods[].hardware)
    metal = np.array([d["hardware"]["metal_g"] for d in data["rods"]], float)
    hung = masses + metal.sum(axis=1)
    com = (masses[:, None] * com + np.column_stack([metal[:, 1] * lengths, np.zeros(len(lengths))])) / hung[:, None]
    eq = solve_equilibrium(lengths, hung, a, b, com=com, limits=_limits(data))
    pts = np.array(res["simulated"]["points"])
    gap = np.max(np.hypot(*(pts - eq.points).T)) / span
    with capsys.disabled():
        print(f"check vs forward simulation with its masses: {gap:.3g} of the span; the edits move the chain "
              f"{res['error_vs_design']['max_rel_span']:.3g} of the span; masses "
              f"{[round(r['mass_change_rel'], 5) for r in res['rods']]} relative")
    assert gap <= 1e-9  # the solver's KKT tolerance
    # the edit moved the chain measurably, and the report says how far
    moved = np.max(np.hypot(*(pts - np.array(data["simulated"]["points"])).T))
    assert res["error_vs_design"]["max_mm"] == pytest.approx(moved, rel=1e-9)
    assert res["error_vs_design"]["max_rel_span"] > 2e-3
    assert set(res["error"]) >= {"max_mm", "max_rel_span"}


def test_rebalance_brings_the_chain_back(built, edited, tmp_path, capsys):
    src, data = built
    out = _copy(edited[0], tmp_path / "chain")
    before = _snapshot(out)
    code, res, err = _check([str(out), "--rebalance", "--json", "--jobs", "2"], capsys)
    assert code == 0, err
    rb = res["rebalance"]
    span = math.dist(*data["anchors"])
    design_pts = np.array(data["simulated"]["points"])
    after = np.max(np.hypot(*(np.array(rb["as_built"]["points"]) - design_pts).T)) / span
    with capsys.disabled():
        print(f"\nre-balanced: as built {after:.3g} of the span from the original design "
              f"(edited, not re-balanced: {res['error_vs_design']['max_rel_span']:.3g}); re-designed "
              f"{rb['redesigned']}, masses {[round(m, 4) for m in rb['masses']]} g")
    assert rb["balanced"] and rb["written"] == str(out)
    assert after <= 2e-3 and after < res["error_vs_design"]["max_rel_span"] / 10
    assert sorted(rb["redesigned"] + [BEAD_ROD, GROOVE_ROD]) == list(range(len(data["rods"])))
    now = _snapshot(out)
    for i, d in enumerate(data["rods"]):
        step = d["fabrication"]["file"]
        if i in (BEAD_ROD, GROOVE_ROD):  # kept as saved; its STL made to match
            assert now[step] == before[step]
        else:
            assert now[step] != before[step]
    assert (out / ".rodcad-output").is_file() and not (tmp_path / "chain.best-fit").exists()
    new = json.loads((out / "design.json").read_text())
    assert new["round_trip"][-1]["edited"] == [BEAD_ROD, GROOVE_ROD]
    # no 3D view of the chain before the re-balance is left beside the new design.json
    assert not (out / "view.html").exists() and not (out / "assembly.glb").exists()
    assert any("view.html" in n for n in new["notes"])
    assert new["rods"][BEAD_ROD]["fabrication"]["edited"] is True
    assert "Round trip" in (out / "report.md").read_text()
    # checked again, nothing is edited any more and the chain hangs as the new design.json says
    code, again, err = _check([str(out), "--json"], capsys)
    assert code == 0, err
    assert again["edited"] == []
    gap = np.max(np.hypot(*(np.array(again["simulated"]["points"]) - np.array(new["as_built"]["points"])).T))
    assert gap / span <= 1e-9


def test_an_edit_that_cannot_be_balanced_exits_1_with_the_best_fit(built, tmp_path, capsys):
    """Rods 1 and 3 pulled apart (heavier and lighter) leave the other rods no masses in
    their ranges that hang the target: exit 1, OUTDIR as it was, the best fit beside it."""
    src, data = built
    out = _copy(src, tmp_path / "chain")
    for i, edit in ((1, _bead), (3, _groove)):
        _write(edit(_read(_step(out, data, i))), _step(out, data, i))
    before = _snapshot(out)
    code, res, err = _check([str(out), "--rebalance", "--json", "--jobs", "1"], capsys)
    assert code == 1
    assert not res["rebalance"]["balanced"]
    assert "cannot be balanced" in res["rebalance"]["notes"][0]
    assert "best fit" in err
    assert _snapshot(out) == before
    best = json.loads((tmp_path / "chain.best-fit" / "design.json").read_text())
    assert best["round_trip"][-1]["balanced"] is False


def test_assembly_step_round_trip(built, capsys):
    out, data = built
    code, res, err = _check([str(out), "--json", "--assembly", str(out / "assembly.step")], capsys)
    assert code == 0, err
    assert res["edited"] == []
    # the rods as built, re-read from the assembly, hang where the build's own as-built check
    # put them (not exactly on the design: moving the pin holes by the play's compensation moves
    # each rod's centre of mass by ~1e-3 mm, 1e-7 of the span)
    built_off = np.hypot(*(np.array(data["as_built"]["points"]) - np.array(data["simulated"]["points"])).T).max()
    span = float(np.hypot(*np.subtract(*data["anchors"])))
    assert abs(res["error_vs_design"]["max_rel_span"] - built_off / span) < 1e-9


def test_overlap_at_a_joint_is_reported(built, tmp_path, capsys):
    """A bead on top near the second joint: the neighbour can no longer bend as far."""
    src, data = built
    out = _copy(src, tmp_path / "chain")
    b = _b3d()
    path = _step(out, data, 1)
    solid = _read(path)
    bb = solid.bounding_box()
    (bump,) = solid.fuse(b.Solid.make_sphere(6.0).moved(
        b.Location(((bb.min.X + bb.max.X) / 2 + 10, (bb.min.Y + bb.max.Y) / 2, bb.max.Z)))).solids()
    _write(bump, path)
    code, res, err = _check([str(out), "--json"], capsys)
    assert code == 0, err  # the chain still hangs: only the joint's range shrank
    assert res["joints"] and {j["joint"] for j in res["joints"]} <= {0, 1}
    assert all(j["where"] in ("lo", "hi") and j["overlap_mm3"] > 0 for j in res["joints"])
    assert any("overlap" in n for n in res["notes"])


# --------------------------------------------------------------------------- bad input


def test_not_an_output_folder(tmp_path, capsys):
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "notes.txt").write_text("mine")
    code, _, err = _check([str(tmp_path / "a")], capsys)
    assert code == 2 and "design.json" in err and "Traceback" not in err
    (tmp_path / "a" / "design.json").write_text('{"rodcad": "0.1.0"}')
    code, _, err = _check([str(tmp_path / "a"), "--rebalance"], capsys)
    assert code == 2 and ".rodcad-output" in err
    code, _, err = _check([str(tmp_path / "missing")], capsys)
    assert code == 2 and "no such folder" in err


def _faces_only(solid):
    return _b3d().Compound(solid.faces()[:5])


def _two_solids(solid):
    b = _b3d()
    bb = solid.bounding_box()
    return b.Compound([solid, b.Solid.make_sphere(2.0).moved(b.Location((bb.max.X + 10, 0, 0)))])


def _moved_up(solid):
    return solid.moved(_b3d().Location((0, 0, 2.0)))  # the rod frame's +y: the holes move 2 mm


def _knuckle_cut(solid, matrix):
    """The material around the first pin hole cut away (a 4 mm cylinder about its axis)."""
    b = _b3d()
    x, z = matrix[0][3], matrix[2][3]  # the first pin axis on the bed: along Y through (x, z)
    cyl = b.Solid.make_cylinder(4.0, 60.0, b.Plane((x, -30.0, z), z_dir=(0, 1, 0)))
    (out,) = solid.cut(cyl).solids()
    return out


@pytest.mark.parametrize("edit, says", [
    (_faces_only, "no closed solid"),
    (_two_solids, "2 solids"),
    (_moved_up, "pin hole is blocked"),
    (_knuckle_cut, "lost the material around it"),
])
def test_bad_rod_files_are_bad_input_and_nothing_is_written(built, tmp_path, capsys, edit, says):
    src, data = built
    out = _copy(src, tmp_path / "chain")
    i = 3
    path = _step(out, data, i)
    solid = _read(path)
    shape = edit(solid, data["rods"][i]["fabrication"]["print_matrix"]) if edit is _knuckle_cut else edit(solid)
    _write(shape, path)
    before = _snapshot(out)
    code, _, err = _check([str(out), "--rebalance"], capsys)
    assert code == 2, err
    assert str(path) in err and says in err and "Traceback" not in err
    assert _snapshot(out) == before and not (tmp_path / "chain.best-fit").exists()
