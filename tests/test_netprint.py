"""A net's print files (issue 27): print.3mf, rods/rod-NNN.3mf and hubs/*.3mf carry every
part a user prints with the catalog's print profile and a pause at the layer where each
rod's steel balls go in. Sliced by PrusaSlicer (when installed): the G-code pauses exactly
there, each message naming the rods, and each rod's plastic (its own extrusion by feature,
skirt and support left out) is its designed plastic (density x its solid's volume) within
2 %: the slicer's extrusion model against the B-rep (tests/test_printfile.py checks the
same for chains)."""

from __future__ import annotations

import json
import math
import re
import zipfile
from pathlib import Path

import pytest
from gcode_util import NOT_ROD, needs_slicer, read_gcode, slice_file

from rodcad.catalog.loader import load_catalog
from rodcad.cli import main

V_NET = ("design: 1\nname: v\nnet:\n  nodes: [[0, 0, 0], [45, 0, -50], [95, 0, 0]]\n"
         "  edges: [[0, 1], [1, 2]]\n  anchored: [0, 2]\n")


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """A small hub net (3 hubs, 2 rods holding steel balls) built with its solids."""
    tmp = tmp_path_factory.mktemp("netprint")
    (tmp / "v.yaml").write_text(V_NET)
    out = tmp / "v"
    assert main(["build", str(tmp / "v.yaml"), "-o", str(out), "-q"]) == 0
    return out, json.loads((out / "design.json").read_text())


def _plastic(out: Path, stem: str, folder: str = "rods") -> float:
    """Grams of PLA in a part: its STEP's volume times the catalog's density."""
    from build123d import import_step

    return float(import_step(str(out / folder / f"{stem}.step")).volume) * 1.24 / 1000


def _pause_layer(hw, layer: float) -> float:
    """The top of the first layer sliced (at mid-height) at or above a rod's axis: rods lie on
    their body, the sockets' centres ``rod_diameter / 2`` above the bed."""
    axis = hw.rod_diameter / 2
    return math.ceil((axis + layer / 2) / layer - 1e-9) * layer


def test_the_print_files_hold_every_part_and_design_json_and_the_report_name_them(built):
    out, data = built
    files = data["cad"]["files"]
    want = ["print.3mf", "rods/rod-000.3mf", "rods/rod-001.3mf"] + [f"hubs/{p}.3mf" for p in data["cad"]["hub_parts"]]
    assert set(want) <= set(files) and all((out / f).is_file() for f in want)
    with zipfile.ZipFile(out / "print.3mf") as z:
        config = z.read("Metadata/Slic3r_PE.config").decode()
        names = re.findall(r'key="name" value="([^"]+)"', z.read("Metadata/Slic3r_PE_model.config").decode())
    assert "; fill_density = 100%" in config and "; layer_height = 0.2" in config
    assert sorted(set(names)) == sorted(["rod-000", "rod-001", *data["cad"]["hub_parts"]])
    report = (out / "report.md").read_text()
    assert "print.3mf" in report and "rods/rod-NNN.3mf" in report


@needs_slicer
def test_prusaslicer_pauses_print_3mf_at_the_ball_layers_and_each_rod_weighs_its_design(built, tmp_path):
    out, data = built
    hw = load_catalog("pla-parametric").node
    layer = data["print"]["layer_height"]
    sliced = read_gcode(slice_file(out / "print.3mf", tmp_path / "print.gcode"))
    with_balls = {f"{r['index']:03d}": r["steel_balls"] for r in data["net"]["rods"] if r["steel_balls"]}
    assert with_balls  # the test net's rods are weighed down
    z = _pause_layer(hw, layer)
    assert [p for p, _ in sliced.pauses] == pytest.approx([z], abs=1e-6) and sliced.early == []
    msg = sliced.pauses[0][1]
    assert f"insert {sum(with_balls.values())} balls of 6 mm" in msg
    assert set(re.findall(r"rod (\d{3})", msg)) == set(with_balls)
    # at the pause the print stands one layer below z: each socket's opening there admits its ball
    below = hw.rod_diameter / 2 - (z - layer)
    rs = (hw.insert_diameter + hw.insert_clearance) / 2
    assert 2 * math.sqrt(rs**2 - below**2) > hw.insert_diameter
    lines = []
    for r in data["net"]["rods"]:
        stem = f"rod-{r['index']:03d}"
        got, want = sliced.object_grams(stem, 1.75, 1.24, skip=NOT_ROD), _plastic(out, stem)
        lines.append(f"print.3mf {stem}: sliced {got:.3f} g, designed {want:.3f} g ({got / want - 1:+.2%})")
        assert got == pytest.approx(want, rel=0.02), lines[-1]
    print("\n".join(lines))


@needs_slicer
def test_prusaslicer_slices_one_rod_file_alone_at_its_designed_plastic_with_its_pause(built, tmp_path):
    out, data = built
    hw = load_catalog("pla-parametric").node
    r = max(data["net"]["rods"], key=lambda r: r["steel_balls"])
    stem = f"rod-{r['index']:03d}"
    gcode = slice_file(out / "rods" / f"{stem}.3mf", tmp_path / f"{stem}.gcode")
    assert re.search(r"^; fill_density = 100%$", gcode, re.M)
    sliced = read_gcode(gcode)
    assert [p for p, _ in sliced.pauses] == pytest.approx([_pause_layer(hw, 0.2)], abs=1e-6)
    assert sliced.pauses[0][1].startswith(f"insert {r['steel_balls']} ball") and sliced.early == []
    assert "Support material" in sliced.filament  # a round rod lies on support
    got, want = sliced.object_grams(stem, 1.75, 1.24, skip=NOT_ROD), _plastic(out, stem)
    print(f"{stem} alone: sliced {got:.3f} g, designed {want:.3f} g ({got / want - 1:+.2%}); skirt and support "
          f"{sliced.grams(1.75, 1.24) - got:.3f} g")
    assert got == pytest.approx(want, rel=0.02)
