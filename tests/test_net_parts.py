"""A net's distinct parts (issue 33): equal rods and hubs found from what they are built from
(hubs up to a rotation, never a mirror image), confirmed on the B-rep, built and written once,
placed once per member in the assembly and on the print plates; the same build in this
process and on a 2-worker Dask cluster; the meshes' deflection from the catalog's printer."""

from __future__ import annotations

import dataclasses
import json
import os
import re
from pathlib import Path

import numpy as np
import pytest
from gcode_util import NOT_ROD, needs_slicer, read_gcode, slice_file

from rodcad.catalog.loader import catalog_from_text, load_catalog
from rodcad.cli import main
from rodcad.errors import InputError

ROOT = Path(__file__).resolve().parents[1]

#: A 3 x 3 grid on a paraboloid, its border held: symmetric under the square's 8 symmetries.
GRID = ("design: 1\nname: grid3\nnet:\n  surface: {z: \"0.002 * ((x - 60)**2 + (y - 60)**2) - 20\", "
        "x: [0, 120], y: [0, 120], u: 3, v: 3}\n  anchored: boundary\nseed: 0\n")


def _random_rotation(rng) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def test_socket_rotation_finds_the_turn_and_refuses_a_mirror_image():
    from rodcad.cad.net.parts import TOL_MM, socket_rotation

    rng = np.random.default_rng(3)
    a = rng.normal(size=(5, 3))
    a = 10 * a / np.linalg.norm(a, axis=1, keepdims=True)  # sockets on a sphere, as a hub's
    R0 = _random_rotation(rng)
    b = (a @ R0.T)[rng.permutation(5)]
    R = socket_rotation(a, b)
    assert R is not None and np.allclose(R, R0, atol=1e-9) and np.isclose(np.linalg.det(R), 1.0)
    assert socket_rotation(a, b + rng.normal(scale=1e-3, size=b.shape)) is None  # a micron off: another part
    assert socket_rotation(a, b + 1e-3 * TOL_MM) is not None  # round-off: the same
    mirror = a * np.array([1.0, 1.0, -1.0])  # a mirror image of a chiral set is no rotation of it
    assert socket_rotation(a, mirror) is None
    line = np.array([[0.0, 0.0, 9.0], [0.0, 0.0, -9.0]])  # collinear sockets: any axis turn
    R = socket_rotation(line, line @ R0.T)
    assert R is not None and np.allclose(line @ R.T, line @ R0.T, atol=1e-9)


def test_parts_are_one_only_when_every_parameter_they_are_built_from_agrees():
    from rodcad.cad.net.parts import HubSpec, RodSpec, group_parts

    hw = load_catalog("pla-parametric").node
    rng = np.random.default_rng(4)
    socks = 10.5 * np.eye(3)[[0, 1, 2]]
    R = _random_rotation(rng)
    bigger = dataclasses.replace(hw, diameter=hw.diameter + 2.0)  # a hub family's larger size
    wider = dataclasses.replace(hw, clearance=hw.clearance + 0.2)  # sockets widened to split
    hubs = [HubSpec(hw, tuple(map(tuple, socks))), HubSpec(hw, tuple(map(tuple, socks @ R.T))),
            HubSpec(bigger, tuple(map(tuple, socks))), HubSpec(wider, tuple(map(tuple, socks)))]
    groups = group_parts(hubs)
    assert [g.members for g in groups] == [[0, 1], [2], [3]]
    assert np.allclose(groups[0].rotations[1], R, atol=1e-9)
    rods = [RodSpec(hw, 40.0, 0, 100.0), RodSpec(hw, 40.0 + 1e-10, 0, 100.0 + 1e-9), RodSpec(hw, 40.0, 0, 101.0),
            RodSpec(hw, 40.001, 0, 100.0), RodSpec(hw, 40.0, 1, 100.0)]
    assert [g.members for g in group_parts(rods)] == [[0, 1], [2], [3], [4]]


def test_a_member_whose_solid_differs_is_not_shared():
    """The B-rep confirms what the parameters say: a member built from other numbers (given to
    the task as if it were equal) fails its signature and is reported unconfirmed."""
    from rodcad.cad.net.build import build_group
    from rodcad.cad.net.parts import PartTask, RodSpec

    hw = load_catalog("pla-parametric").node
    task = PartTask("rod", [RodSpec(hw, 40.0, 0, 100.0), RodSpec(hw, 40.0, 0, 100.0), RodSpec(hw, 40.0, 0, 120.0)],
                    "rod-000", (0.03, 0.2))
    res = build_group(task)
    assert res.confirmed == [True, True, False]
    assert res.volumes[0] - res.volumes[2] == pytest.approx(20.0, rel=1e-6)  # its own solid, 20 mm^3 less
    assert set(res.files[0]) == {".step", ".stl"} and len(res.solids) == 1


def test_the_mesh_deflection_is_a_printer_setting():
    from rodcad.cad.mesh import print_deflection

    base = (ROOT / "catalogs" / "pla-parametric.yaml").read_text()
    assert print_deflection(load_catalog("pla-parametric").printer, 0.2) == pytest.approx((0.03, 0.2), rel=1e-4)
    cat = catalog_from_text(base.replace("  nozzle: 0.4\n", "  nozzle: 0.4\n  mesh_deflection: 0.05\n"
                                         "  mesh_angle: 20\n"), "c.yaml")
    assert print_deflection(cat.printer, 0.2) == pytest.approx((0.05, np.radians(20)))
    with pytest.raises(InputError) as err:
        catalog_from_text(base.replace("  nozzle: 0.4\n", "  nozzle: 0.4\n  mesh_deflection: 0\n"), "c.yaml")
    line = base[:base.index("  nozzle: 0.4\n")].count("\n") + 2
    assert re.search(rf"c\.yaml:{line}:\d+: printer\.mesh_deflection: ", str(err.value)), str(err.value)


def _orbits(points: np.ndarray, centre: np.ndarray) -> list[frozenset]:
    """The classes of ``points`` (n, 3) under the square's 8 symmetries about ``centre`` in plan."""
    d = points[:, :2] - centre
    images = []
    for sx in (1, -1):
        for sy in (1, -1):
            for swap in (False, True):
                q = d[:, ::-1] if swap else d
                images.append(q * [sx, sy])
    out = {}
    for i in range(len(points)):
        key = frozenset(int(np.argmin(np.linalg.norm(d - img[i], axis=1))) for img in images)
        out[key] = key
    return list(out.values())


@pytest.fixture(scope="module")
def grid_builds(tmp_path_factory):
    """The symmetric grid built with its solids in this process (--jobs 1) and on a Dask
    LocalCluster of 2 worker processes (rodcad's, whose workers fork from a forkserver that
    imported the CAD kernel; --scheduler its address): (local, dask, what the cluster's workers
    had loaded before any task and their parents' process ids)."""
    from distributed import Client

    from rodcad.parallel import local_cluster

    tmp = tmp_path_factory.mktemp("grid3")
    design = tmp / "grid3.yaml"
    design.write_text(GRID)
    assert main(["build", str(design), "-o", str(tmp / "local"), "-q", "--jobs", "1"]) == 0
    probe = "[m in __import__('sys').modules for m in ('build123d', 'rodcad.cad.net.build')]"
    with local_cluster(2) as cluster:
        with Client(cluster) as client:
            workers = client.run(eval, probe), client.run(os.getppid)
        assert main(["build", str(design), "-o", str(tmp / "dask"), "-q", "--scheduler", cluster.scheduler_address]) == 0
    return tmp / "local", tmp / "dask", workers


def test_a_local_clusters_workers_start_with_the_cad_kernel_imported(grid_builds):
    """rodcad's local cluster (``--jobs N`` on a net) forks its workers from the forkserver that
    imported the CAD kernel once (spawned, each imported it: about 8 s of CPU a worker): before
    any task, each worker has build123d and a net's part builder loaded, and none is this
    process's own child (never forked from a process that may have used the kernel)."""
    loaded, parents = grid_builds[2]
    assert len(loaded) == 2 and all(v == [True, True] for v in loaded.values()), loaded
    assert os.getpid() not in parents.values()


def test_a_symmetric_net_writes_each_distinct_part_once(grid_builds):
    from rodcad.cad.export import import_step

    out, *_ = grid_builds
    data = json.loads((out / "design.json").read_text())
    nodes = np.array([n["target"] for n in data["net"]["nodes"]], float)
    centre = np.array([60.0, 60.0])
    hub_nodes = {k for k in range(len(nodes))} - set(data["cad"]["nodes_without_hub"])
    hub_orbits = [o for o in _orbits(nodes, centre) if o <= hub_nodes]
    edges = np.array([[r["nodes"][0], r["nodes"][1]] for r in data["net"]["rods"]])
    rod_orbits = _orbits((nodes[edges[:, 0]] + nodes[edges[:, 1]]) / 2, centre)  # a rod by its mid-point
    parts = data["cad"]["parts"]
    rods = [p for p in parts if p["kind"] == "rod"]
    hubs = [p for p in parts if p["kind"] == "hub"]
    assert {frozenset(p["members"]) for p in rods} == set(rod_orbits)  # each orbit one part
    assert {frozenset(p["members"]) for p in hubs} == set(hub_orbits)  # each orbit one part (in halves)
    assert len(hubs) == 2 * len(hub_orbits) and len(rods) == len(rod_orbits) == 2
    assert sorted(f.name for f in (out / "rods").glob("*.step")) == sorted(f"{p['name']}.step" for p in rods)
    assert sorted(f.name for f in (out / "hubs").glob("*.step")) == sorted(f"{p['name']}.step" for p in hubs)
    assert sum(p["count"] for p in rods) == len(edges)
    bom = {p["name"]: p["count"] for p in data["bill_of_materials"]["parts"]}
    assert bom == {p["name"]: p["count"] for p in parts}
    rho = load_catalog("pla-parametric").node.density / 1000
    for p in rods:  # every member's own B-rep weighs what the shared part does
        step = import_step(out / "rods" / f"{p['name']}.step").volume
        for e in p["members"]:
            assert data["as_built"]["masses"][e] == pytest.approx(rho * step, rel=1e-6)


def test_the_assembly_places_every_instance_with_its_balls_in_its_hubs_sockets(grid_builds):
    """assembly.step: one shape per part, an instance per rod and hub half named after it; each
    rod's end balls sit in the sockets of the hubs where it hangs (a hub turned wrongly would
    put its material where a ball is)."""
    from rodcad.cad.export import assembly_leaves

    out, *_ = grid_builds
    data = json.loads((out / "design.json").read_text())
    text = (out / "assembly.step").read_text()
    assert text.count("NEXT_ASSEMBLY_USAGE_OCCURRENCE") == len(data["net"]["rods"]) + len(data["cad"]["hub_parts"])
    assert text.count("MANIFOLD_SOLID_BREP") + text.count("BREP_WITH_VOIDS") == len(data["cad"]["parts"])
    leaves = dict(assembly_leaves(out / "assembly.step"))
    assert sorted(leaves) == sorted([f"rod-{r['index']:03d}" for r in data["net"]["rods"]] + data["cad"]["hub_parts"])
    hw = load_catalog("pla-parametric").node
    ball = 4 / 3 * np.pi * (hw.ball / 2) ** 3
    for r in data["net"]["rods"]:
        rod = leaves[f"rod-{r['index']:03d}"]
        for k in r["nodes"]:
            for half in "ab":
                hub = leaves.get(f"hub-{k:03d}-{half}")
                if hub is None:
                    continue
                common = rod.intersect(hub)
                vol = 0.0 if common is None else float(common.volume)
                assert vol < 1e-3 * ball, f"rod {r['index']} overlaps hub {k}{half} by {vol:.3f} mm^3"


def test_the_build_on_a_dask_cluster_equals_the_build_in_process(grid_builds):
    from rodcad.cad.export import import_step

    local, dask, _ = grid_builds
    files = sorted(str(p.relative_to(local)) for p in local.rglob("*") if p.is_file())
    assert files == sorted(str(p.relative_to(dask)) for p in dask.rglob("*") if p.is_file())
    a, b = (json.loads((d / "design.json").read_text()) for d in (local, dask))
    assert a["bill_of_materials"] == b["bill_of_materials"] and a["cad"]["parts"] == b["cad"]["parts"]
    assert a["as_built"]["masses"] == b["as_built"]["masses"]
    for name in files:
        if name.endswith(".step") and name != "assembly.step":
            assert import_step(dask / name).volume == import_step(local / name).volume
        if name.endswith(".stl"):  # the same mesh, whichever worker made it
            assert (dask / name).read_bytes() == (local / name).read_bytes()


def test_every_stl_is_watertight_within_its_deflection(grid_builds):
    import trimesh

    from rodcad.cad.export import import_step

    out, *_ = grid_builds
    data = json.loads((out / "design.json").read_text())
    defl = data["cad"]["mesh"]["deflection_mm"]
    assert defl == pytest.approx(0.03)
    for p in data["cad"]["parts"]:
        folder = out / ("rods" if p["kind"] == "rod" else "hubs")
        mesh = trimesh.load(str(folder / f"{p['name']}.stl"), force="mesh")
        solid = import_step(folder / f"{p['name']}.step")
        assert mesh.is_watertight
        assert abs(mesh.volume - solid.volume) <= defl * solid.area
        assert -0.004 < mesh.volume / solid.volume - 1 < 0  # inside the solid, within 0.4 % of its plastic
        assert p["mesh_volume_mm3"] == pytest.approx(mesh.volume, rel=1e-6)


@needs_slicer
def test_prusaslicer_prints_a_part_once_per_copy_from_one_mesh(tmp_path):
    """A part with copies is one object with several build items: PrusaSlicer prints each."""
    import zipfile

    from rodcad.cad.net.print_files import ROD_SETTINGS, NetPrintPart
    from rodcad.cad.net.solids import net_rod_solid
    from rodcad.cad.printfile import write_print_3mf

    hw = load_catalog("pla-parametric").node
    rod = net_rod_solid(hw, 40.0, 0, 150.0, name="rod-004")
    part = NetPrintPart(4, rod, float(rod.volume), np.eye(4), "rod-004", "rods", "004",
                        print_note="lies on its body", print_settings=dict(ROD_SETTINGS), copies=3,
                        copy_tags=("004", "009", "011"), mesh_deflection=(0.03, 0.2))
    (path,) = write_print_3mf([part], tmp_path / "print.3mf")
    with zipfile.ZipFile(path) as z:
        model = z.read("3D/3dmodel.model").decode()
    assert model.count("<object ") == 1 and model.count("<item ") == 3
    gcode = slice_file(path, tmp_path / "print.gcode")
    # PrusaSlicer 2.5 makes each build item an object of its own (the only object's copies
    # beyond the first named after the file): three objects printed, each the rod's plastic
    ids = set(re.findall(r"; printing object \S+ id:(\d+)", gcode))
    assert len(ids) == 3
    sliced = read_gcode(gcode)
    assert {"External perimeter", "Perimeter"} <= set(sliced.filament)
    got = sliced.grams(1.75, 1.24, skip=NOT_ROD)
    assert got == pytest.approx(3 * 1.24e-3 * rod.volume, rel=0.03)


def test_a_parts_3mf_mesh_is_the_one_its_stl_holds_and_reads_back_closed(tmp_path):
    """The print files place the mesh a part's STL holds (read back exactly, not meshed again),
    written as 3MF XML that lib3mf reads as the same closed, oriented mesh; an open mesh is refused."""
    import lib3mf

    from rodcad.cad.mesh import mesh_solid, read_stl, write_stl
    from rodcad.cad.net.print_files import NetPrintPart
    from rodcad.cad.net.solids import net_rod_solid
    from rodcad.cad.printfile import write_print_3mf
    from rodcad.cad.slicer import SlicerObject, model_xml

    hw = load_catalog("pla-parametric").node
    rod = net_rod_solid(hw, 40.0, 1, 150.0, name="rod-007")
    mesh = mesh_solid(rod, deflection=0.03, angular=0.2)
    write_stl(mesh, tmp_path / "rod.stl")
    back = read_stl((tmp_path / "rod.stl").read_bytes(), 0.03)
    assert back.vertices.shape == mesh.vertices.shape and back.triangles.shape == mesh.triangles.shape
    assert np.abs(back.vertices[back.triangles] - mesh.vertices[mesh.triangles]).max() < 1e-5  # float32
    assert back.volume == pytest.approx(mesh.volume, rel=1e-6)
    turn = np.array([[1.0, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]])
    part = NetPrintPart(7, rod, float(rod.volume), turn, "rod-007", "rods", "007", mesh=back,
                        mesh_deflection=(0.03, 0.2))
    (path,) = write_print_3mf([part], tmp_path / "print.3mf")
    model = lib3mf.get_wrapper().CreateModel()
    model.QueryReader("3mf").ReadFromFile(str(path))
    objects = model.GetMeshObjects()
    assert objects.MoveNext()
    read = objects.GetCurrentMeshObject()
    assert read.GetName() == "rod-007" and read.IsManifoldAndOriented()
    assert read.GetTriangleCount() == len(back.triangles) and read.GetVertexCount() == len(back.vertices)
    verts = read.GetVertices()
    v = np.frombuffer((type(verts[0]) * len(verts))(*verts), dtype=np.float32).reshape(-1, 3)
    placed = back.moved(turn).vertices
    assert np.abs(np.ptp(v, axis=0) - np.ptp(placed, axis=0)).max() < 1e-5 and v[:, 2].min() == pytest.approx(0.0)
    with pytest.raises(ValueError, match="not closed"):
        model_xml([SlicerObject("open", back.vertices, back.triangles[1:])])


def test_the_runners_count_each_task_as_it_finishes():
    """Long CAD work shows progress: both runners of rodcad.parallel.task_runner call
    ``progress(done, total)`` once per task (Dask's as the tasks finish, in any order) and
    return the results in item order."""
    from distributed import Client, LocalCluster

    from rodcad.parallel import _dask, in_process

    items = list(range(-5, 7))
    for make in ("here", "dask"):
        seen = []
        if make == "here":
            got = in_process(abs, items, progress=lambda d, t: seen.append((d, t)))
        else:
            with LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as c, \
                    Client(c) as client:
                got = _dask(client)(abs, items, progress=lambda d, t: seen.append((d, t)))
        assert got == [abs(x) for x in items]
        assert seen == [(k, len(items)) for k in range(1, len(items) + 1)]


def test_jobs_above_one_start_a_local_cluster_of_that_many_worker_processes(monkeypatch):
    """``--jobs N`` (N > 1) runs a net's parts on a ``distributed.LocalCluster`` of N worker
    processes that rodcad starts, each importing this rodcad (PYTHONPATH); at most one per task;
    1 runs them here. The cluster is made of threads here, the class patched to record what it
    was asked for: a build on rodcad's cluster of worker processes is :func:`grid_builds`'s
    (--scheduler its address)."""
    import distributed

    import rodcad
    from rodcad.parallel import in_process, task_runner

    asked = []
    real = distributed.LocalCluster

    def threads(**kw):
        asked.append(kw)
        threaded = {k: v for k, v in kw.items() if k != "env"}  # a nanny's, for its processes
        return real(**{**threaded, "processes": False})

    monkeypatch.setattr(distributed, "LocalCluster", threads)
    with task_runner(5, jobs=2) as (run, where):
        assert run(abs, [-3, 1, -2]) == [3, 1, 2]
    assert where == "2 Dask worker processes"
    (kw,) = asked
    assert kw["n_workers"] == 2 and kw["processes"] and kw["threads_per_worker"] == 1
    assert kw["env"]["PYTHONPATH"].split(os.pathsep)[0] == str(Path(rodcad.__file__).resolve().parents[1])
    with task_runner(1, jobs=2) as (run, where):  # one task: no cluster
        assert run is in_process and where == "in this process"
    with task_runner(5, jobs=1) as (run, where):
        assert run is in_process
    assert len(asked) == 1
    # by default a worker per CPU, up to one per PARTS_PER_WORKER tasks: none for fewer than two
    import rodcad.parallel as parallel

    monkeypatch.setattr(parallel, "default_jobs", lambda: 4)
    k = parallel.PARTS_PER_WORKER
    for tasks, workers in ((2 * k - 1, 1), (2 * k, 2), (3 * k + 1, 3), (40 * k, 4)):
        with task_runner(tasks) as (run, where):
            assert (run is in_process) == (workers == 1)
            assert where == ("in this process" if workers == 1 else f"{workers} Dask worker processes")
