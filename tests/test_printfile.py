"""The slicer project (issue 16): print.3mf with every rod placed on the bed, the print
settings and a pause at every ball-insert layer; one 3MF per rod.

The files are read back with lib3mf and zipfile; when PrusaSlicer's command line is
installed (Debian: ``apt-get install prusa-slicer``) every plate is sliced and its
G-code checked (M601 at each insert layer and nowhere else), and every distinct rod is
sliced alone with the project's settings: its filament times the density must be its
designed plastic mass within 2 %.
"""

from __future__ import annotations

import dataclasses
import math
import re
import shutil
import subprocess
import zipfile
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from rodcad.cad.printfile import (
    CONFIG_FILE,
    MODEL_CONFIG_FILE,
    PAUSES_FILE,
    PrintProfile,
    plan_plates,
    write_print_3mf,
    write_print_files,
)
from rodcad.cad.rods import fabricate_chain
from rodcad.catalog.loader import load_catalog
from rodcad.catalog.massrange import mass_info
from rodcad.catalog.model import Printer

PRUSA = shutil.which("prusa-slicer")
needs_slicer = pytest.mark.skipif(PRUSA is None, reason="prusa-slicer is not on PATH (Debian: apt-get install "
                                                          "prusa-slicer): the G-code checks need the slicer")
#: (type, where in its mass range) per chain position: heavy rods with balls whose socket
#: roofs fall in different layers (two identical ones sharing theirs) and a light one with
#: cavities only: three plates.
CHAIN = [("free-30", 0.95), ("free-30", 0.95), ("concave20-30", 0.9), ("straight-40", 0.05)]
LAYER = 0.2
PROFILE = {"material": "PLA", "density": 1.24, "infill": 1.0, "note": "ignored"}


@pytest.fixture(scope="module")
def catalog():
    return load_catalog("pla-weighted")


@pytest.fixture(scope="module")
def rods(catalog):
    types = [catalog[name] for name, _ in CHAIN]
    masses = []
    for rod, f in zip(types, (f for _, f in CHAIN)):
        lo, hi = mass_info(rod).mass_range
        masses.append(lo + f * (hi - lo))
    return fabricate_chain(types, masses, seed=0, jobs=2).rods


@pytest.fixture(scope="module")
def project(rods, catalog, tmp_path_factory):
    out = tmp_path_factory.mktemp("print")
    paths = write_print_files(rods, out, printer=catalog.printer, profile=PROFILE)
    plates = [p for p in paths if p.parent == out]
    return out, plates


def covering_layer(roof: float) -> float:
    """The top of the first 0.2 mm layer sliced (at mid-height) at or above ``roof``."""
    k = 1
    while k * LAYER - LAYER / 2 < roof - 1e-6:
        k += 1
    return round(k * LAYER, 6)


def needed_pauses(rod) -> dict[float, int]:
    """{layer top: balls} from the rod's sockets, computed here from its print matrix."""
    m = np.asarray(rod.print_matrix)
    out: dict[float, int] = {}
    for c in np.asarray(rod.socket_centers).reshape(-1, 3):
        z = covering_layer(float(m[2, :3] @ c + m[2, 3]) + rod.socket_radius)
        out[z] = out.get(z, 0) + 1
    return out


def read_objects(path: Path) -> dict[str, np.ndarray]:
    """{object name: (n, 3) vertices in bed coordinates} of every build item (lib3mf)."""
    import lib3mf

    wrapper = lib3mf.get_wrapper()
    model = wrapper.CreateModel()
    model.QueryReader("3mf").ReadFromFile(str(path))
    out = {}
    items = model.GetBuildItems()
    while items.MoveNext():
        item = items.GetCurrent()
        obj = item.GetObjectResource()
        mesh = model.GetMeshObjectByID(obj.GetResourceID())
        t = np.array([list(row) for row in item.GetObjectTransform().Fields])  # 4 rows x 3, row vectors
        verts = mesh.GetVertices()
        v = np.frombuffer((type(verts[0]) * len(verts))(*verts), dtype=np.float32).reshape(-1, 3).astype(float)
        assert mesh.IsManifoldAndOriented(), f"{path.name}: {mesh.GetName()} is not a closed mesh"
        out[mesh.GetName()] = v @ t[:3] + t[3]
    return out


def config(path: Path) -> dict[str, str]:
    text = zipfile.ZipFile(path).read(CONFIG_FILE).decode()
    return dict(line[2:].split(" = ", 1) for line in text.splitlines()[1:])


def pauses_in(path: Path) -> dict[float, str]:
    import xml.etree.ElementTree as ET

    z = zipfile.ZipFile(path)
    if PAUSES_FILE not in z.namelist():
        return {}
    root = ET.fromstring(z.read(PAUSES_FILE))
    assert root.tag == "custom_gcodes_per_print_z"
    assert root.find("mode").get("value") == "SingleExtruder"
    out = {}
    for code in root.findall("code"):
        assert (code.get("type"), code.get("extruder"), code.get("gcode")) == ("1", "1", "M601")
        out[float(code.get("print_z"))] = code.get("extra")
    return out


def test_the_chain_exercises_grouping(rods):
    sets = [tuple(sorted(needed_pauses(r))) for r in rods]
    assert len({s for s in sets if s}) >= 2, sets  # rods pausing at different layers
    assert sets[0] == sets[1] != () and () in sets


def test_every_rod_is_one_object_named_by_its_file_with_the_print_settings(project, rods, catalog):
    out, plates = project
    assert plates[0].name == "print.3mf" and [p.name for p in plates[1:]] == [
        f"print-{k}.3mf" for k in range(2, len(plates) + 1)]
    names = [n for p in plates for n in read_objects(p)]
    assert sorted(names) == sorted(r.file_stem for r in rods)
    bx, by, bz = catalog.printer.build_volume
    for p in plates:
        cfg = config(p)
        assert cfg["fill_density"] == "100%" and cfg["layer_height"] == "0.2" and cfg["perimeters"] == "2"
        assert cfg["filament_density"] == "1.24" and cfg["pause_print_gcode"] == "M601"
        assert cfg["bed_shape"] == f"0x0,{bx:g}x0,{bx:g}x{by:g},0x{by:g}" and cfg["max_print_height"] == f"{bz:g}"
        model_config = zipfile.ZipFile(p).read(MODEL_CONFIG_FILE).decode()
        assert all(f'value="{n}"' in model_config for n in read_objects(p))
    for r in rods:  # one plain 3MF per rod, the same geometry on the bed
        (name, v), = read_objects(out / "rods" / f"{r.file_stem}.3mf").items()
        assert name == r.file_stem and v.min(axis=0) == pytest.approx([0, 0, 0], abs=1e-4)


def test_rods_lie_on_the_bed_apart_and_whole(project, rods, catalog):
    _, plates = project
    by_name = {r.file_stem: r for r in rods}
    bx, by, bz = catalog.printer.build_volume
    for p in plates:
        objs = read_objects(p)
        boxes = []
        for name, v in objs.items():
            lo, hi = v.min(axis=0), v.max(axis=0)
            assert lo[2] == pytest.approx(0, abs=1e-4)
            assert lo[0] >= 0 and lo[1] >= 0 and hi[0] <= bx and hi[1] <= by and hi[2] <= bz
            solid = by_name[name].solid.bounding_box()
            assert sorted(hi - lo) == pytest.approx(sorted([solid.size.X, solid.size.Y, solid.size.Z]), abs=0.02)
            boxes.append((lo, hi))
        for i in range(len(boxes)):
            for j in range(i):
                (a0, a1), (b0, b1) = boxes[i], boxes[j]
                apart = max(b0[0] - a1[0], a0[0] - b1[0], b0[1] - a1[1], a0[1] - b1[1])
                assert apart >= 5 - 1e-3, f"{p.name}: objects {i} and {j} are {apart:.2f} mm apart"


def test_each_plate_pauses_exactly_where_its_rods_need(project, rods):
    _, plates = project
    by_name = {r.file_stem: r for r in rods}
    for p in plates:
        on = [by_name[n] for n in read_objects(p)]
        needs = [needed_pauses(r) for r in on]
        assert all(set(n) == set(needs[0]) for n in needs), f"{p.name} mixes rods that pause differently"
        got = pauses_in(p)
        assert sorted(got) == pytest.approx(sorted(needs[0]), abs=1e-9)
        for z, msg in got.items():
            total = sum(n.get(round(z, 6), 0) for n in needs)
            assert msg.startswith(f"insert {total} ball") and "of 6 mm" in msg, msg
        for r in on:  # design.json's pause heights are the socket roofs these layers cover
            assert {covering_layer(z) for z in r.pause_zs} == set(needed_pauses(r))


def test_profile_and_pause_layers():
    with pytest.raises(ValueError, match="layer_height"):
        PrintProfile(layer_height=0)
    with pytest.raises(ValueError, match="infill"):
        PrintProfile.from_mapping({"infill": 0})
    p = PrintProfile()
    assert p.pause_z(11.2295) == 11.4 and p.pause_z(12.357) == 12.6 and p.pause_z(11.3) == 11.4
    assert p.pause_z(11.3001) == 11.6 and p.pause_z(0.05) == 0.2
    thick = PrintProfile(first_layer_height=0.3)  # layer tops 0.3, 0.5, ..., 11.3 (sliced at 11.2), 11.5
    assert thick.pause_z(11.15) == 11.3 and thick.pause_z(11.2295) == 11.5
    assert PrintProfile.from_mapping(PROFILE).density == 1.24


def test_a_small_bed_takes_several_plates_and_a_rod_that_fits_none_is_refused(rods, tmp_path):
    light = rods[3]  # 50 x 16 mm on the bed, no balls; a twin and a third one pause alike
    twins = [light] + [dataclasses.replace(light, index=k, file_stem=f"{k:02d}_{light.type_name}") for k in (4, 5)]
    plates = plan_plates(twins, printer=Printer((120.0, 45.0, 30.0), 0.4))
    assert [[q.rod.index for q in p.placements] for p in plates] == [[3, 4], [5]]  # 2 per row, 1 row per bed
    for plate in plates:
        for q in plate.placements:
            x0, y0, x1, y1 = q.box
            assert x0 >= 5 - 1e-6 and y0 >= 5 - 1e-6 and x1 <= 115 + 1e-6 and y1 <= 40 + 1e-6
        assert plate.pauses == {}
    narrow = Printer((40.0, 80.0, 30.0), 0.4)
    assert plan_plates([light], printer=narrow)[0].placements[0].rotated  # fits only along y
    (tmp_path / "print-2.3mf").write_bytes(b"a plate of an earlier run")
    paths = write_print_3mf([light], tmp_path / "print.3mf", printer=narrow)
    assert paths == [tmp_path / "print.3mf"] and not (tmp_path / "print-2.3mf").exists()
    (name, v), = read_objects(paths[0]).items()
    assert name == light.file_stem and np.ptp(v, axis=0) == pytest.approx([16, 50, 16], abs=0.02)
    with pytest.raises(ValueError, match="does not fit"):
        plan_plates([light], printer=Printer((30.0, 30.0, 30.0), 0.4))
    with pytest.raises(ValueError, match="tall"):
        plan_plates([light], printer=Printer((200.0, 200.0, 10.0), 0.4))


def test_a_rod_whose_chamber_is_filled_pauses_alone_to_pour_its_shot(rods):
    light = rods[3]
    filled = SimpleNamespace(**{**light.__dict__, "index": 6, "file_stem": f"06_{light.type_name}", "ball_count": 0,
                                "socket_centers": np.zeros((0, 3)), "pause_zs": (8.05,), "fill_mass": 12.5,
                                "fill_name": "tungsten shot"})
    plates = plan_plates([light, filled])
    assert [(len(p.placements), p.pauses) for p in plates] == [
        (1, {}), (1, {8.2: "pour 12.50 g of tungsten shot into rod 06"})]


# --------------------------------------------------------------------------- PrusaSlicer


def slice_file(src: Path, gcode: Path, *extra: str) -> str:
    run = subprocess.run([PRUSA, "--dont-arrange", *extra, "--export-gcode", str(src), "--output", str(gcode)],
                         capture_output=True, text=True, timeout=300)
    said = [line for line in (run.stdout + run.stderr).splitlines() if "[trace]" not in line]
    assert run.returncode == 0 and gcode.exists(), f"{src.name}: " + "\n".join(said[-20:])
    errors = [line for line in said if re.search(r"error|warning", line, re.I)]
    assert errors == [], f"{src.name}: {errors}"
    return gcode.read_text()


def layers(gcode: str) -> tuple[list[float], dict[float, set[str]]]:
    """(print_z of every M601, {print_z: extrusion types}) from PrusaSlicer's comments."""
    z, pauses, types = 0.0, [], {}
    for line in gcode.splitlines():
        if line.startswith(";Z:"):
            z = float(line[3:])
        elif line.startswith(";TYPE:"):
            types.setdefault(z, set()).add(line[6:])
        elif line.split(";")[0].strip() == "M601":
            pauses.append(z)
    return pauses, types


@needs_slicer
def test_prusaslicer_pauses_each_plate_at_its_insert_layers_only(project, rods, tmp_path):
    _, plates = project
    for p in plates:
        gcode = slice_file(p, tmp_path / f"{p.stem}.gcode")
        names = set(re.findall(r"^; printing object (\S+)", gcode, re.M))
        assert names == set(read_objects(p))
        rod = next(r for r in rods if r.file_stem in names)
        want = sorted(needed_pauses(rod))
        got, types = layers(gcode)
        assert got == pytest.approx(want, abs=1e-6), p.name
        for z in got:  # the layer after the pause closes the sockets
            assert "Bridge infill" in types[z], (p.name, z, types[z])


@needs_slicer
def test_prusaslicer_filament_of_each_rod_alone_is_its_designed_mass(project, rods, tmp_path):
    out, plates = project
    ini = tmp_path / "project.ini"  # the project's settings, as a PrusaSlicer config file
    ini.write_text("\n".join(f"{k} = {v}" for k, v in config(plates[0]).items()) + "\n")
    density, diameter = 1.24, float(config(plates[0])["filament_diameter"])
    seen, lines = set(), []
    for r in rods:
        if id(r.solid) in seen:
            continue
        seen.add(id(r.solid))
        gcode = slice_file(out / "rods" / f"{r.file_stem}.3mf", tmp_path / f"{r.file_stem}.gcode",
                           "--load", str(ini), "--skirts", "0")
        used_mm = float(re.search(r"^; filament used \[mm\] = ([\d.]+)", gcode, re.M)[1])
        mass = used_mm * math.pi * diameter**2 / 4 * density / 1000
        dev = mass / r.filament_mass - 1
        lines.append(f"{r.file_stem}: sliced {mass:.3f} g, designed {r.filament_mass:.3f} g ({dev:+.2%})")
        assert abs(dev) <= 0.02, lines[-1]
    print("\n".join(lines))
