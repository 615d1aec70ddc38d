"""``rodcad catalog check|export|schema`` through the CLI entry point."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from catalog_testutil import BASE, write

from rodcad.cad.export import import_step
from rodcad.catalog.paths import default_catalog_dir
from rodcad.cli import main

TWO = BASE.replace("length: 30", "length: [20, 30]") + \
    "    balls: {diameter: 5, density: 7.85}\n"


@pytest.fixture(autouse=True)
def _tmp_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    cache = tmp_path / "cache"
    monkeypatch.setenv("RODCAD_CACHE_DIR", str(cache))
    return cache


@pytest.fixture(scope="module")
def checked(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict]:
    """`catalog check --json` of a two-type catalog (computed once)."""
    folder = tmp_path_factory.mktemp("check")
    path = write(folder, TWO)
    mp = pytest.MonkeyPatch()
    mp.setenv("RODCAD_CACHE_DIR", str(folder / "cache"))
    try:
        import contextlib
        import io

        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            code = main(["catalog", "check", str(path), "--json", "--jobs", "1"])
    finally:
        mp.undo()
    assert code == 0
    return path, json.loads(out.getvalue())


def test_check_json_follows_the_contract(checked: tuple[Path, dict]) -> None:
    path, report = checked
    assert {"types", "pairs"} <= set(report)
    assert [t["name"] for t in report["types"]] == ["sq-20", "sq-30"]
    for t in report["types"]:
        assert {"name", "length", "solid_mass", "mass_range", "com"} <= set(t)
        lo, hi = t["mass_range"]
        assert lo < t["solid_mass"] < hi
        assert len(t["com"]) == 2 and t["com"][1] == pytest.approx(0, abs=1e-9)
    assert [t["length"] for t in report["types"]] == [20, 30]
    assert [(p["left"], p["right"]) for p in report["pairs"]] == [
        ("sq-20", "sq-20"), ("sq-20", "sq-30"), ("sq-30", "sq-20"), ("sq-30", "sq-30")]
    corner = math.degrees(2 * math.atan(2 * 0.2 / 12))  # square ends, default setback 0.2
    for p in report["pairs"]:
        assert p["limits_deg"] == pytest.approx([-corner, corner], abs=0.02)
    assert report["problems"] == []


def test_check_text_and_the_cache(checked: tuple[Path, dict], capsys: pytest.CaptureFixture[str],
                                  monkeypatch: pytest.MonkeyPatch) -> None:
    path, _ = checked
    monkeypatch.setenv("RODCAD_CACHE_DIR", str(path.parent / "cache"))  # warm from the fixture
    assert main(["catalog", "check", str(path)]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"catalog test ({path}): 2 rod types, 4 joinable ordered pairs\n")
    rows = [line.split() for line in out.splitlines()[3:5]]
    assert [r[:3] for r in rows] == [["sq-20", "20", "mm"], ["sq-30", "30", "mm"]]
    assert all("[-3.82, 3.82] deg" in line for line in out.splitlines()[3:5])
    assert "  sq-20 -> [-3.82, 3.82]: sq-20 sq-30\n" in out
    assert "(0 pairs computed, 4 from cache" in out


def test_bad_catalog_exits_2_with_every_problem(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write(tmp_path, BASE.replace("length: 30", "length: thirty") + "    colour: red\n")
    assert main(["catalog", "check", str(path)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.splitlines() == [
        f"{path}:9:13: families[0].length: expected a number, got a string ('thirty')",
        f"{path}:10:5: families[0].colour: unknown key 'colour' (expected one of: name, description, length, "
        "scale, curvature, stops, section, joint, ends, material, fill, balls)",
    ]
    assert "Traceback" not in captured.err


def test_precompute_of_a_bad_catalog_exits_2_and_writes_nothing(tmp_path: Path,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    path = write(tmp_path, BASE.replace("length: 30", "length: thirty"))
    assert main(["catalog", "precompute", str(path)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.splitlines() == [
        f"{path}:9:13: families[0].length: expected a number, got a string ('thirty')"]
    assert "Traceback" not in captured.err
    assert sorted(p.name for p in tmp_path.iterdir()) == [path.name]  # no seed file, no temporary


def test_unknown_catalog_name(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["catalog", "check", "pla-pinne"]) == 2
    assert capsys.readouterr().err == (
        "pla-pinne:0:0: no such catalog file or shipped catalog (did you mean 'pla-pinned'?)\n")


def test_export_writes_one_step_per_type(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write(tmp_path, TWO)
    out = tmp_path / "out"
    assert main(["catalog", "export", str(path), "-o", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["sq-20.step", "sq-30.step"]
    for name in ("sq-20", "sq-30"):
        solid = import_step(out / f"{name}.step")
        assert solid.is_valid and solid.label == name
        bb = solid.bounding_box()  # rod frame: axes at x = 0 and x = length, along z
        assert bb.min.X == pytest.approx(-3.2, abs=1e-5)
        assert bb.max.X == pytest.approx(float(name[3:]) + 3.2, abs=1e-5)
    assert capsys.readouterr().out.count(".step: sq-") == 2


def test_failed_export_leaves_the_folder_as_it_was(tmp_path: Path) -> None:
    path = write(tmp_path, BASE.replace("length: 30", "length: 3"))
    out = tmp_path / "out"
    assert main(["catalog", "export", str(path), "-o", str(out)]) == 2
    assert not out.exists()
    out.mkdir()
    (out / "keep.txt").write_text("x")
    assert main(["catalog", "export", str(path), "-o", str(out)]) == 2
    assert [p.name for p in out.iterdir()] == ["keep.txt"]


def test_schema_command(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    shipped = (default_catalog_dir() / "catalog.schema.json").read_text()
    assert main(["catalog", "schema"]) == 0
    assert capsys.readouterr().out == shipped
    assert main(["catalog", "schema", "-o", str(tmp_path / "s.json")]) == 0
    assert (tmp_path / "s.json").read_text() == shipped


def test_catalog_without_subcommand_prints_usage(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["catalog"]) == 2
    assert "SUBCOMMAND" in capsys.readouterr().err


JAMMED = """\
catalog: 1
name: jammed
defaults:
  length: [30]
  section: {height: 10, thickness: 8}
  joint: {layout: tongue-fork, pin_diameter: 1.75, pin_clearance: 0.25, knuckle_radius: 3.0,
          tongue_thickness: 2.8, layer_gap: 0.3, radial_gap: 0.4}
  material: {name: PLA, density: 1.24, min_wall: 1.2}
families:
  - name: jam
    ends: {setback: 0, top_chamfer: -30, bottom_chamfer: -30}
"""


def test_rods_that_interfere_at_every_angle_are_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Both faces of each end reach past the hinge plane: the rods jam whatever the bend.
    catalog check and build say so at the catalog's line instead of dropping the family."""
    cat = tmp_path / "jammed.yaml"
    cat.write_text(JAMMED)
    assert main(["catalog", "check", str(cat)]) == 2
    err = capsys.readouterr().err
    assert f"{cat}:4:11: defaults.length: rod types 'jam-30' and 'jam-30' interfere at every angle" in err
    design = tmp_path / "d.yaml"
    design.write_text("design: 1\nname: j\ncatalog: jammed.yaml\nanchors: [[0, 0], [100, 0]]\n"
                      "target: {form: catenary, length: 150}\n")
    assert main(["build", str(design), "-o", str(tmp_path / "out"), "--no-cad", "-q"]) == 2
    err = capsys.readouterr().err
    assert "interfere at every angle" in err and "Traceback" not in err and not (tmp_path / "out").exists()
