"""The slicer projects (issues 16, 23): print.3mf with every rod placed on the bed, the
print settings and a pause at every insert layer, each message naming the rods whose
inserts go in there; one project per rod that slices alone the same way.

The files are read back with lib3mf and zipfile; when PrusaSlicer's command line is
installed (Debian: ``apt-get install prusa-slicer``) the plate is sliced and its G-code
checked (an M601 at each insert layer and nowhere else, just before the layer that
bridges the sockets of the rods its message names), and every distinct rod's own 3MF is
sliced alone, as a user opening it would: its plastic (the G-code's extrusion by feature,
skirt and support left out) times the density must be its designed plastic mass within
2 %, and it pauses at its own insert layers.
"""

from __future__ import annotations

import dataclasses
import re
import zipfile
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from gcode_util import NOT_ROD, needs_slicer, read_gcode, slice_file

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

#: (type, where in its mass range) per chain position: heavy rods with balls whose socket
#: roofs fall in different layers (two identical ones sharing theirs) and a light one with
#: cavities only; then a rod printed to order (catalog pla-parametric), curved (it rests on
#: its arc, with support) and weighted with two balls whose roofs fall in a third layer.
CHAIN = [("free-30", 0.95), ("free-30", 0.95), ("concave20-30", 0.9), ("straight-40", 0.05)]
#: (length, curvature, mass) of the curved rod printed to order: one of the heart's.
CURVED = (47.604, 0.005325, 14.0)
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
    length, curvature, mass = CURVED
    types.append(load_catalog("pla-parametric").rod("rod", length, curvature))
    masses.append(mass)
    return fabricate_chain(types, masses, seed=0, jobs=1).rods


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


def tag(rod) -> str:
    return rod.file_stem.split("_")[0]


def named(msg: str) -> set[str]:
    """The rod tags a pause message names ('rod 03', 'rods 00, 03', '2 in rod 05', ...)."""
    return set(re.findall(r"\b(\d{2})\b", msg))


def test_the_chain_pauses_at_several_heights(rods):
    sets = [tuple(sorted(needed_pauses(r))) for r in rods]
    assert len({s for s in sets if s}) >= 3, sets  # rods pausing at different layers
    assert sets[0] == sets[1] != () and () in sets
    assert rods[-1].print_note and not any(r.print_note for r in rods[:-1])  # the curved one rests on its arc


def test_every_rod_is_one_object_named_by_its_file_with_the_print_settings(project, rods, catalog):
    out, plates = project
    assert [p.name for p in plates] == ["print.3mf"]  # every rod fits one bed, whatever its pauses
    names = [n for p in plates for n in read_objects(p)]
    assert sorted(names) == sorted(r.file_stem for r in rods)
    bx, by, bz = catalog.printer.build_volume
    for p in [*plates, *(out / "rods" / f"{r.file_stem}.3mf" for r in rods)]:  # the rods' own files too
        cfg = config(p)
        assert cfg["fill_density"] == "100%" and cfg["layer_height"] == "0.2" and cfg["perimeters"] == "2"
        assert cfg["filament_density"] == "1.24" and cfg["pause_print_gcode"] == "M601"
        assert cfg["bed_shape"] == f"0x0,{bx:g}x0,{bx:g}x{by:g},0x{by:g}" and cfg["max_print_height"] == f"{bz:g}"
        model_config = zipfile.ZipFile(p).read(MODEL_CONFIG_FILE).decode()
        assert all(f'value="{n}"' in model_config for n in read_objects(p))
        assert model_config.count('key="support_material" value="1"') == sum(
            1 for n in read_objects(p) if n == rods[-1].file_stem)
    for r in rods:  # one project per rod: the same geometry, on the bed, its own pauses
        (name, v), = read_objects(out / "rods" / f"{r.file_stem}.3mf").items()
        lo, hi = v.min(axis=0), v.max(axis=0)
        assert name == r.file_stem and lo[2] == pytest.approx(0, abs=1e-4)
        assert lo[0] >= 5 - 1e-4 and lo[1] >= 5 - 1e-4 and hi[0] <= bx - 5 + 1e-4 and hi[1] <= by - 5 + 1e-4
        solid = r.solid.bounding_box()
        assert sorted(hi - lo) == pytest.approx(sorted([solid.size.X, solid.size.Y, solid.size.Z]), abs=0.02)
        got = pauses_in(out / "rods" / f"{r.file_stem}.3mf")
        assert sorted(got) == pytest.approx(sorted(needed_pauses(r)), abs=1e-9)
        for z, msg in got.items():
            n = needed_pauses(r)[round(z, 6)]
            assert msg == f"insert {n} ball{'s' if n > 1 else ''} of 6 mm (rod {tag(r)}) [{r.ball_name}]"


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


def test_the_plate_pauses_at_every_height_its_rods_need_naming_them(project, rods):
    _, plates = project
    by_name = {r.file_stem: r for r in rods}
    for p in plates:
        on = [by_name[n] for n in read_objects(p)]
        needs = {tag(r): needed_pauses(r) for r in on}
        got = pauses_in(p)
        assert sorted(got) == pytest.approx(sorted({z for n in needs.values() for z in n}), abs=1e-9)
        assert len(got) >= 3
        for z, msg in got.items():
            who = {t for t, n in needs.items() if round(z, 6) in n}
            assert named(msg) == who, (z, msg)  # exactly the rods whose balls go in here
            total = sum(n.get(round(z, 6), 0) for n in needs.values())
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
    light = rods[3]  # 50 x 16 mm on the bed, no balls; a twin and a third one alike
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


def test_only_the_bed_splits_rods_into_plates(rods):
    """On a bed too small for them (one 16 mm row of 115 mm a plate) the rods fill the plates
    in packing order, whatever their pauses; each plate pauses where its own rods need it."""
    plates = plan_plates([rods[0], rods[2], rods[3], rods[4]], printer=Printer((125.0, 40.0, 30.0), 0.4))
    assert [[q.rod.index for q in p.placements] for p in plates] == [[0, 2], [3, 4]]
    assert len({tuple(needed_pauses(q.rod)) for q in plates[0].placements}) == 2  # two pause heights, one plate
    for p in plates:
        assert sorted(p.pauses) == pytest.approx(sorted({z for q in p.placements for z in needed_pauses(q.rod)}))


def test_a_rod_whose_chamber_is_filled_pauses_to_pour_its_shot_beside_the_others(rods):
    light = rods[3]
    filled = SimpleNamespace(**{**light.__dict__, "index": 6, "file_stem": f"06_{light.type_name}", "ball_count": 0,
                                "socket_centers": np.zeros((0, 3)), "pause_zs": (8.05,), "fill_mass": 12.5,
                                "fill_name": "tungsten shot"})
    (plate,) = plan_plates([light, rods[0], filled])
    z0 = max(needed_pauses(rods[0]))
    assert len(plate.placements) == 3 and plate.pauses == {
        8.2: "pour 12.50 g of tungsten shot into rod 06", z0: f"insert 2 balls of 6 mm (rod 00) [{rods[0].ball_name}]"}


# --------------------------------------------------------------------------- PrusaSlicer

@needs_slicer
def test_prusaslicer_pauses_the_plate_just_before_the_layer_that_closes_each_named_rods_sockets(project, rods,
                                                                                              tmp_path):
    _, plates = project
    by_name = {r.file_stem: r for r in rods}
    for p in plates:
        sliced = read_gcode(slice_file(p, tmp_path / f"{p.stem}.gcode"))
        names = {obj for _, obj in sliced.types if obj}
        assert names == set(read_objects(p))
        needs = {tag(by_name[n]): (by_name[n], needed_pauses(by_name[n])) for n in names}
        want = sorted({z for _, n in needs.values() for z in n})
        assert [z for z, _ in sliced.pauses] == pytest.approx(want, abs=1e-6), p.name  # once each, in order
        assert len(want) >= 3 and sliced.early == []  # each pause before its layer prints anything
        project_msgs = pauses_in(p)
        for z, msg in sliced.pauses:
            assert msg == project_msgs[round(z, 6)]
            who = {t for t, (_, n) in needs.items() if round(z, 6) in n}
            assert named(msg) == who, (z, msg)
            for t in who:  # the layer after the pause bridges that rod's sockets
                rod = needs[t][0]
                assert "Bridge infill" in sliced.types.get((z, rod.file_stem), set()), (p.name, z, rod.file_stem)


@needs_slicer
def test_prusaslicer_slices_each_rod_file_alone_at_its_designed_mass_with_its_pauses(project, rods, tmp_path):
    """What a user opening rods/NN_TYPE.3mf alone gets: 100 % infill, the rod's pauses, and
    the rod's plastic (skirt and support left out) its designed mass within 2 %."""
    out, plates = project
    density, diameter = 1.24, float(config(plates[0])["filament_diameter"])
    seen, lines = set(), []
    for r in rods:
        if id(r.solid) in seen:
            continue
        seen.add(id(r.solid))
        gcode = slice_file(out / "rods" / f"{r.file_stem}.3mf", tmp_path / f"{r.file_stem}.gcode")
        assert re.search(r"^; fill_density = 100%$", gcode, re.M)
        sliced = read_gcode(gcode)
        used = float(re.search(r"^; filament used \[mm\] = ([\d.]+)", gcode, re.M)[1])
        assert sum(sliced.filament.values()) == pytest.approx(used, rel=2e-3)  # the reader misses nothing
        assert ("Support material" in sliced.filament) == bool(r.print_note)  # the curved rod gets support
        mass = sliced.grams(diameter, density, skip=NOT_ROD)
        dev = mass / r.filament_mass - 1
        lines.append(f"{r.file_stem}: sliced {mass:.3f} g, designed {r.filament_mass:.3f} g ({dev:+.2%}); "
                     f"skirt and support {sliced.grams(diameter, density) - mass:.3f} g")
        assert abs(dev) <= 0.02, lines[-1]
        assert [z for z, _ in sliced.pauses] == pytest.approx(sorted(needed_pauses(r)), abs=1e-6)
        assert all(named(msg) == {tag(r)} for _, msg in sliced.pauses) and sliced.early == []
    print("\n".join(lines))


def test_a_face_narrower_than_the_tessellation_leaves_a_closed_mesh(tmp_path):
    """A flush stop end whose bottom chamfer is 1.4e-5 deg (the semicircle of the default
    catalog has four) has a face 2e-6 mm wide across the rod: its vertices are welded onto
    its edges, so the mesh stays closed (build123d's Mesher rounds them apart and lib3mf
    rejects the mesh)."""
    from rodcad.cad.export import print_matrix
    from rodcad.cad.solids import mass_properties, type_solid

    rod = load_catalog("pla-parametric").rod("rod", 51.764, 0.0099995, second_under=-1.418147038556583e-05)
    solid = type_solid(rod)
    assert min(f.area for f in solid.faces()) < 1e-4  # mm^2: the sliver is there
    plain = SimpleNamespace(index=0, file_stem=f"00_{rod.name}", solid=solid, print_matrix=print_matrix(solid),
                            plastic_volume=mass_properties(solid).volume, socket_centers=np.zeros((0, 3)),
                            socket_radius=0.0, ball_count=0, ball_diameter=None, pause_zs=(), fill_mass=0.0,
                            print_note="curved")
    (path,) = write_print_3mf([plain], tmp_path / "print.3mf")
    (name, v), = read_objects(path).items()  # closed and oriented, as lib3mf reads it
    bb = solid.bounding_box()
    assert name == plain.file_stem and sorted(np.ptp(v, axis=0)) == pytest.approx(
        sorted([bb.size.X, bb.size.Y, bb.size.Z]), abs=0.02)
