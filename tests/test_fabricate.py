"""Fabrication (issue 5): masses, centres of mass, walls, printability and the files.

Everything is measured on the solids and files written, not taken from the plan.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from OCP.BRepExtrema import BRepExtrema_DistShapeShape

from rodcad.cad.mesh import DEFLECTION as STL_DEFLECTION
from rodcad.cad.export import import_step, read_assembly
from rodcad.cad.chainfiles import write_assembly, write_rod_files
from rodcad.cad.rods import fabricate_chain, fabricate_rod
from rodcad.cad.solids import is_valid_solid, mass_properties, void_template
from rodcad.catalog.cache import DiskCache
from rodcad.catalog.loader import load_catalog
from rodcad.catalog.massrange import mass_info
from rodcad.fabrication.intervals import achievable_intervals
from rodcad.fabrication.layout import void_volume


@pytest.fixture(scope="module")
def cache_dir(tmp_path_factory: pytest.TempPathFactory):
    path = tmp_path_factory.mktemp("cache")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("RODCAD_CACHE_DIR", str(path))
        yield path


@pytest.fixture(scope="module")
def catalog(cache_dir: Path):
    return load_catalog("pla-pinned")


@pytest.fixture(scope="module")
def chain(catalog):
    """Light (catalog minimum, mid), solid, heavy (catalog maximum), a duplicate, one above range."""
    f20, s20 = catalog["free-20"], catalog["straight-20"]
    lo, hi = mass_info(f20).mass_range
    types = [f20, f20, s20, s20, f20, f20]
    masses = [lo, (lo + mass_info(f20).solid_mass) / 2, mass_info(s20).solid_mass, mass_info(s20).mass_range[1], (lo + mass_info(f20).solid_mass) / 2,
              hi * 1.05]
    return types, masses, fabricate_chain(types, masses, seed=3, jobs=2)


def _measured(rod, f) -> tuple[float, np.ndarray]:
    """Mass (g) and com (x, y) from the final B-rep plus balls."""
    props = mass_properties(f.solid)
    rho = rod.material.density / 1000
    m = props.volume * rho
    c = np.array(props.center) * m
    if f.ball_count:
        c += rod.balls.mass * f.socket_centers.sum(axis=0)
        m += f.ball_count * rod.balls.mass
    return m, (c / m)[:2]


def test_masses_and_centres_of_mass(chain) -> None:
    types, masses, fab = chain
    assert len(fab.rods) == len(types)
    kinds = set()
    for rod, m, f in zip(types, masses, fab.rods):
        lo, hi = mass_info(rod).mass_range
        goal = min(max(m, lo), hi)
        mass, com = _measured(rod, f)
        assert mass == pytest.approx(f.mass, rel=1e-9)
        assert abs(mass - goal) <= 1e-3 * goal
        assert np.allclose(com, mass_info(rod).com, atol=1e-6), (f.index, com, mass_info(rod).com)
        assert np.allclose(f.com, mass_info(rod).com, atol=1e-6)
        kinds.add("light" if f.cavity_count and not f.ball_count else "heavy" if f.ball_count else "solid")
        assert is_valid_solid(f.solid)
    assert kinds == {"light", "solid", "heavy"}
    assert fab.rods[0].cavity_count > 0 and fab.rods[3].ball_count > 0


def test_convex_stop_rod_of_pla_weighted(cache_dir: Path) -> None:
    """A curve20 rod (flush ends, +10 deg top chamfers) builds to its mass and centre of mass."""
    rod = load_catalog("pla-weighted")["curve20-30"]
    lo, hi = mass_info(rod).mass_range
    m = (lo + mass_info(rod).solid_mass) / 2
    assert lo < m < hi
    f = fabricate_rod(rod, m, seed=3)
    mass, com = _measured(rod, f)
    assert f.in_range and f.cavity_count > 0, f.message
    assert mass == pytest.approx(f.mass, rel=1e-9)
    assert abs(mass - m) <= 1e-3 * m
    assert np.allclose(com, mass_info(rod).com, atol=1e-6), (com, mass_info(rod).com)
    assert np.allclose(f.com, mass_info(rod).com, atol=1e-6)
    assert is_valid_solid(f.solid)
    assert len(f.solid.shells()) == 1 + f.cavity_count + f.ball_count
    assert f.min_wall >= rod.material.min_wall - 1e-6


def test_walls_measured_on_the_final_solid(chain) -> None:
    types, _, fab = chain
    checked = 0
    for rod, f in zip(types, fab.rods):
        shells = f.solid.shells()
        voids = f.cavity_count + f.ball_count
        assert len(shells) == 1 + voids
        if not voids:
            continue
        sizes = [s.bounding_box().diagonal for s in shells]
        outer = shells[int(np.argmax(sizes))]
        inner = [s for i, s in enumerate(shells) if i != int(np.argmax(sizes))]
        wall = rod.material.min_wall
        for s in inner:
            d = BRepExtrema_DistShapeShape(outer.wrapped, s.wrapped).Value()
            assert d >= wall - 1e-6
            checked += 1
        for i in range(len(inner)):
            for j in range(i + 1, len(inner)):
                assert BRepExtrema_DistShapeShape(inner[i].wrapped, inner[j].wrapped).Value() >= wall - 1e-6
        assert f.min_wall >= wall - 1e-6
    assert checked >= 3


def test_out_of_range_is_reported_and_clipped(chain) -> None:
    types, masses, fab = chain
    last = fab.rods[-1]
    assert not last.in_range and "above the heaviest" in last.message
    assert last.mass == pytest.approx(mass_info(types[-1]).mass_range[1], rel=1e-3)
    assert len(fab.problems) == 1 and fab.problems[0].startswith("Rod 5 (free-20)")
    assert all(r.in_range for r in fab.rods[:-1])


def test_identical_rods_are_built_once(chain) -> None:
    _, _, fab = chain
    assert fab.rods[1].solid is fab.rods[4].solid
    assert fab.distinct == 5
    assert [r.file_stem for r in fab.rods][:2] == ["00_free-20", "01_free-20"]


def test_achievable_intervals_agree_with_what_is_built(catalog) -> None:
    """Inside every interval (edges and middle) the rod builds within 0.1 % and in range;
    in every gap it is flagged and built at the nearest interval edge."""
    rod = catalog["free-20"]
    cache = DiskCache()
    ivs = achievable_intervals(rod, cache=cache)
    lo, hi = mass_info(rod).mass_range
    assert ivs[0][0] == pytest.approx(lo, rel=1e-9) and ivs[-1][1] == pytest.approx(hi, rel=1e-9)
    assert ivs[0][1] == pytest.approx(mass_info(rod).solid_mass, rel=1e-3)
    assert len(ivs) >= 2 and all(a <= b < c for (a, b), (c, _) in zip(ivs, ivs[1:]))
    assert achievable_intervals(rod, cache=cache) == ivs  # cached, same
    edges = [x for a, b in ivs for x in (a, b)]
    for a, b in ivs:
        for m in (a, (a + b) / 2, b):
            f = fabricate_rod(rod, m, cache=cache)
            assert f.in_range and abs(f.mass - m) <= 1e-3 * m, (m, f.mass, f.message)
    for (_, b), (c, _) in zip(ivs, ivs[1:]):
        m = (b + c) / 2
        f = fabricate_rod(rod, m, cache=cache)
        assert not f.in_range and "gap between the ball counts" in f.message
        assert min(abs(f.mass - e) for e in edges) <= 1e-3 * f.mass


def test_same_input_same_layout(catalog) -> None:
    rod = catalog["free-30"]
    m = (mass_info(rod).mass_range[0] + mass_info(rod).solid_mass) / 2
    a = fabricate_rod(rod, m, seed=7, cache=DiskCache(enabled=False))
    b = fabricate_rod(rod, m, seed=7, cache=DiskCache(enabled=False))
    assert a.cavity_count > 0 and np.array_equal(a.cavity_centers, b.cavity_centers)
    assert a.cavity_radius == b.cavity_radius and a.layout.startswith("poisson/")


def test_void_shapes_are_printable_and_exact() -> None:
    r = 2.0
    for kind in ("sphere", "capped", "silo"):
        assert void_template(kind, r).volume == pytest.approx(void_volume(kind, r), rel=1e-6)
    capped = void_template("capped", r)
    ys = [v.Y for v in capped.vertices()]  # flat roof and floor where the sphere reaches 45 deg
    assert max(ys) == pytest.approx(r / math.sqrt(2)) and min(ys) == pytest.approx(-r / math.sqrt(2))
    assert sorted(f.geom_type.name for f in capped.faces()) == ["PLANE", "PLANE", "SPHERE"]
    silo = void_template("silo", r)
    assert max(v.Y for v in silo.vertices()) == pytest.approx(r)  # flat roof at the sphere's top


def test_rod_files(chain, tmp_path: Path) -> None:
    import trimesh

    _, _, fab = chain
    paths = write_rod_files(fab, tmp_path)
    assert len(paths) == 2 * len(fab.rods)
    for f in fab.rods:
        step = tmp_path / "rods" / f"{f.file_stem}.step"
        back = import_step(step)
        assert is_valid_solid(back)
        assert back.volume == pytest.approx(f.plastic_volume, rel=1e-6)
        bb = back.bounding_box()
        assert bb.min.Z == pytest.approx(0, abs=1e-6)  # on the bed
        assert bb.max.Z == pytest.approx(12.0, abs=1e-6)  # on its side: the section height is up
        mesh = trimesh.load(str(tmp_path / "rods" / f"{f.file_stem}.stl"), force="mesh")
        assert mesh.is_watertight
        assert abs(mesh.volume - f.plastic_volume) <= STL_DEFLECTION * back.area  # the mesh's accuracy
        if f.ball_count:
            assert f.socket_radius < f.pause_z <= bb.max.Z - 1.2 + 1e-6  # the roof, a wall under the top
            z_centres = f.socket_centers[:, 1] + f.print_matrix[2, 3]
            assert np.allclose(f.pause_z, z_centres + f.socket_radius)


def test_assembly(chain, tmp_path: Path) -> None:
    _, _, fab = chain
    n = len(fab.rods)
    lengths = [20.0] * n
    ang = np.linspace(-0.6, 0.6, n)
    pts = np.concatenate([[[0.0, 0.0]], np.cumsum(np.c_[np.cos(ang), np.sin(ang)] * np.array(lengths)[:, None], 0)])
    path = write_assembly(fab, pts, tmp_path / "assembly.step", name="test chain")
    parts = read_assembly(path)
    names = [p[0] for p in parts]
    assert names[:n] == [f.file_stem for f in fab.rods]
    assert names[n:] == [f"pin_{j:02d}" for j in range(n + 1)]
    for (_, vol), f in zip(parts, fab.rods):
        assert vol == pytest.approx(f.plastic_volume, rel=1e-6)
    from build123d import import_step

    root = import_step(path)
    solids = root.solids()
    assert len(solids) == 2 * n + 1
    # rod i's first hinge axis sits on joint i
    rods = [c for c in root.children if c.label.endswith("free-20") or c.label.endswith("straight-20")]
    colors = [tuple(round(v, 3) for v in tuple(c.color)[:3]) for c in rods]
    masses = [f.mass for f in fab.rods]
    assert colors[int(np.argmin(masses))][2] > colors[int(np.argmin(masses))][0]  # lightest is blue
    assert colors[int(np.argmax(masses))][0] > colors[int(np.argmax(masses))][2]  # heaviest is red
    pins = [s for s in solids[n:]]
    for j, pin in enumerate(pins):
        c = pin.center()
        assert (c.X, c.Y) == pytest.approx(tuple(pts[j]), abs=1e-6)
