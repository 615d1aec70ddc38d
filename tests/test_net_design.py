"""Net design files (``net:``), their generated nets and the catalog's node hardware."""

from __future__ import annotations

import json
import math
from pathlib import Path

import jsonschema
import numpy as np
import pytest
import yaml

from rodcad.catalog.loader import catalog_from_text
from rodcad.catalog.net.node import DEFAULT_NODE, NodeHardware, socket_centres
from rodcad.design.loader import load_design
from rodcad.design.net.layouts import read_obj
from rodcad.design.spec import design_schema
from rodcad.errors import InputError

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
CATALOGS = Path(__file__).resolve().parents[1] / "catalogs"


def _problems(text: str, tmp_path: Path, name: str = "net.yaml") -> list[str]:
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(InputError) as err:
        load_design(path)
    return [str(p).replace(str(tmp_path) + "/", "") for p in err.value.problems]


def _design(text: str, tmp_path: Path):
    path = tmp_path / "net.yaml"
    path.write_text(text)
    return load_design(path)


HEAD = "design: 1\nname: n\n"


# --------------------------------------------------------------------------- generated nets


@pytest.mark.parametrize("u,v", [(1, 2), (3, 2), (8, 8)])
def test_a_surface_grid_has_its_nodes_rods_corners_and_border(tmp_path, u, v):
    d = _design(HEAD + f"net:\n  surface: {{z: '0.001 * x * y', x: [0, {40 * u}], y: [0, {40 * v}], "
                f"u: {u}, v: {v}}}\n  anchored: corners\n", tmp_path)
    t = d.net
    assert t.n == (u + 1) * (v + 1)
    assert t.m == u * (v + 1) + v * (u + 1) - 2 * (u == 1) - 2 * (v == 1)  # rods between two corners go
    assert t.anchored.tolist() == sorted({0, u, v * (u + 1), (u + 1) * (v + 1) - 1})
    np.testing.assert_allclose(t.positions[:, 2], 0.001 * t.positions[:, 0] * t.positions[:, 1], rtol=1e-12)
    if min(u, v) < 2:
        return  # no interior: every node on the border
    b = _design(HEAD + f"net:\n  surface: {{z: '0', x: [0, 100], y: [0, 100], u: {u}, v: {v}}}\n"
                "  anchored: boundary\n", tmp_path).net
    assert b.anchored.size == 2 * (u + v)
    assert b.dropped == 2 * (u + v)  # the border's rods join two anchors: left out
    assert b.m == u * (v + 1) + v * (u + 1) - 2 * (u + v)


def test_a_radial_net_has_its_rings_spokes_and_centre(tmp_path):
    d = _design(HEAD + "net:\n  radial: {rings: 3, spokes: 8, radius: 120, z: '0.5 * r - 60'}\n"
                "  anchored: outer\n", tmp_path).net
    assert d.n == 1 + 3 * 8
    assert d.m == 3 * 8 + 2 * 8 + 8 - 8  # rings, spokes between rings, from the centre; outer ring left out
    np.testing.assert_allclose(np.hypot(*d.positions[d.anchored, :2].T), 120)
    assert d.positions[0].tolist() == [0.0, 0.0, -60.0]
    sector = _design(HEAD + "net:\n  radial: {rings: 2, spokes: 7, radius: [50, 90], sweep_deg: 180}\n"
                     "  anchored: ends\n", tmp_path).net
    assert sector.n == 14 and sector.anchored.size == 4
    assert sector.m == 2 * 6 + 7 - 2  # open rings, spokes, less the two end spokes between anchors
    ang = np.degrees(np.arctan2(sector.positions[:, 1], sector.positions[:, 0]))
    assert ang.min() == pytest.approx(0.0, abs=1e-9) and ang.max() == pytest.approx(180.0)


def test_an_obj_mesh_gives_a_rod_per_face_edge(tmp_path):
    (tmp_path / "m.obj").write_text("# a square of four triangles around its centre\n"
                                    "v 0 0 0\nv 40 0 0\nv 40 40 0\nv 0 40 0\nv 20 20 -10\nv 9 9 9\n"
                                    "f 1 2 5\nf 2/1 3/2 5/3\nf 3//1 4//1 5//1\nf -3 -6 -2\n")
    t = _design(HEAD + "net:\n  mesh: m.obj\n  anchored: boundary\n", tmp_path).net
    assert t.n == 5  # the unused vertex is no node
    assert t.anchored.tolist() == [0, 1, 2, 3]
    assert t.m == 4 and t.dropped == 4  # 8 edges, the border's 4 between anchors left out
    t = _design(HEAD + "net:\n  mesh: m.obj\n  anchored: [0, 2]\n", tmp_path).net
    assert (t.n, t.m) == (5, 8)
    np.testing.assert_allclose(t.positions[4], [20, 20, -10])


def test_explicit_nodes_and_edges_are_kept_as_written(tmp_path):
    t = _design(HEAD + "net:\n  nodes: [[0, 0, 0], [30, 0, -30], [60, 0, 0], [30, 20, -40]]\n"
                "  edges: [[0, 1], [1, 2], [1, 3], [0, 2]]\n  anchored: [0, 2]\n", tmp_path).net
    assert t.edges.tolist() == [[0, 1], [1, 2], [1, 3], [0, 2]]
    assert t.kind == "nodes" and t.anchored_as == "" and t.dropped == 0
    assert t.size == pytest.approx(60.0)


# --------------------------------------------------------------------------- bad input


def test_every_problem_of_a_net_block_at_its_line_and_column(tmp_path):
    got = _problems(HEAD + "net:\n"
                    "  nodes: [[0, 0, 0], [10, 0, 0], [20, 0, 0]]\n"
                    "  edges: [[0, 1], [1, 5], [2, 2], [1, 0]]\n"
                    "  anchored: [0, 9]\n", tmp_path)
    assert got == [
        "net.yaml:5:23: net.edges[1][1]: node 5 does not exist (nodes are 0 to 2)",
        "net.yaml:5:27: net.edges[2]: joins node 2 to itself",
        "net.yaml:5:35: net.edges[3]: nodes 1 and 0 are already joined by net.edges[0]",
        "net.yaml:6:17: net.anchored[1]: node 9 does not exist (nodes are 0 to 2)",
    ]


@pytest.mark.parametrize("block,where,match", [
    ("surface: {z: 'x + w', x: [0, 100], y: [0, 100], u: 2, v: 2}\n  anchored: corners",
     "4:16: net.surface.z", "unknown name 'w'"),
    ("surface: {z: \"__import__('os').system('ls')\", x: [0, 100], y: [0, 100], u: 2, v: 2}\n  anchored: corners",
     "4:16: net.surface.z", "only plain calls"),
    ("surface: {z: '1 / (x - 50)', x: [0, 100], y: [0, 100], u: 2, v: 2}\n  anchored: corners",
     "4:16: net.surface.z", "not a finite number at x = 50"),
    ("surface: {z: '0', x: [0, 100], y: [0, 100], u: 2, v: 2}\n  anchored: outer",
     "5:13: net.anchored", "does not name nodes of a surface net"),
    ("radial: {rings: 2, spokes: 6, radius: 100}\n  anchored: corners",
     "5:13: net.anchored", "'corners'"),
    ("radial: {rings: 1, spokes: 6, radius: [40, 100]}\n  anchored: outer",
     "4:19: net.radial.rings", "at least 2 rings"),
    ("nodes: [[0, 0, 0], [10, 0, 0], [20, 0, 0], [30, 0, 0]]\n  edges: [[0, 1], [2, 3]]\n  anchored: [0]",
     "6:13: net.anchored", "node(s) [2, 3] hang from no anchored node"),
    ("nodes: [[0, 0, 0], [0, 0, 0]]\n  edges: [[0, 1]]\n  anchored: [0]",
     "5:11: net.edges[0]", "in the same place"),
    ("surface: {z: '0', x: [0, 100], y: [0, 100], u: 2, v: 2}\n  mesh: m.obj\n  anchored: corners",
     "5:9: net.mesh", "this net already has 'surface'"),
    ("edges: [[0, 1]]\n  anchored: [0]", "4:10: net.edges", "need 'nodes'"),
    ("mesh: nothere.obj\n  anchored: boundary", "4:9: net.mesh", "no such OBJ file"),
])
def test_bad_net_blocks_are_reported_at_their_key(tmp_path, block, where, match):
    got = _problems(HEAD + "net:\n  " + block + "\n", tmp_path)
    assert len(got) == 1, got
    assert got[0].startswith(f"net.yaml:{where}"), got
    assert match in got[0]


def test_a_net_takes_no_chain_keys_and_the_schema_checks_its_block(tmp_path):
    got = _problems(HEAD + "anchors: [[0, 0], [1, 0]]\nnet:\n  surface: {z: '0', x: [0, 1], y: [0, 1], u: 0, "
                    "v: 1}\n  anchored: side\n", tmp_path)
    assert any(p.startswith("net.yaml:3:10: anchors: a net design takes no 'anchors'") for p in got)
    assert any("net.yaml:5:46: net.surface.u: must be between 1 and 100 (got 0)" == p for p in got)
    assert any(p.startswith("net.yaml:6:13: net.anchored: unknown value 'side'") for p in got)


def test_an_obj_file_is_blamed_at_its_own_line(tmp_path):
    (tmp_path / "bad.obj").write_text("v 0 0 0\nv 1 0 0\nv 1 1\nf 1 2 7\n")
    got = _problems(HEAD + "net:\n  mesh: bad.obj\n  anchored: boundary\n", tmp_path)
    assert got[0].startswith("bad.obj:3:1: a vertex needs three")
    assert "line 4: vertex 7 is not defined" in got[0]
    with pytest.raises(ValueError, match="no faces"):
        read_obj("v 0 0 0\n")


def test_the_example_nets_follow_the_published_schema():
    schema = json.loads((EXAMPLES / "design.schema.json").read_text())
    assert schema == design_schema()
    for name in ("dome", "lampshade", "collar"):
        jsonschema.validate(yaml.safe_load((EXAMPLES / f"{name}.yaml").read_text()), schema)
        assert load_design(EXAMPLES / f"{name}.yaml").net is not None


# --------------------------------------------------------------------------- node hardware


def _hub(**kw) -> NodeHardware:
    d = {**DEFAULT_NODE, **kw}
    d.pop("name")
    return NodeHardware(name="hub", density=1.24, min_wall=1.2, insert_diameter=6.0, insert_density=7.85,
                        insert_clearance=0.2, **d)


def test_the_hub_mass_and_centre_of_mass_agree_with_monte_carlo():
    hw = _hub()
    dirs = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, -0.6, -0.8]])
    mass, com = hw.hub_mass(dirs)
    rng = np.random.default_rng(0)
    R, rp, rs = hw.radius, hw.pivot_radius, hw.socket_radius
    p = rng.uniform(-R, R, (1_000_000, 3))
    inside = np.linalg.norm(p, axis=1) <= R
    for d in dirs:  # carve the socket sphere and its opening cone (apex at the ball's centre)
        q = p - rp * d
        dist = np.linalg.norm(q, axis=1)
        cone = (q @ d) >= dist * math.cos(math.radians(hw.cone_deg))
        inside &= ~((dist <= rs) | cone)
    vol = inside.mean() * (2 * R) ** 3
    sd = math.sqrt(inside.mean() * (1 - inside.mean()) / p.shape[0]) * (2 * R) ** 3
    assert mass == pytest.approx(1.24e-3 * vol, abs=4 * 1.24e-3 * sd)
    np.testing.assert_allclose(com, p[inside].mean(axis=0), atol=0.03)
    sym = hw.hub_mass(np.vstack([np.eye(3), -np.eye(3)]))[1]
    np.testing.assert_allclose(sym, 0.0, atol=1e-12)


def test_net_rod_masses_span_a_cavity_to_steel_balls():
    hw = _hub()
    rn = hw.rod_numbers(40.0)
    body = 40 - 2 * hw.end_offset
    cyl = math.pi * 4.5 ** 2 * body * 1.24e-3
    assert rn.body_length == pytest.approx(body)
    assert cyl < rn.solid_mass < cyl + 2 * (4 / 3 * math.pi * 3 ** 3 + math.pi * 1.5 ** 2 * hw.end_offset) * 1.24e-3
    assert rn.mass_range[0] == pytest.approx(rn.solid_mass - math.pi * 3.3 ** 2 * (body - 2.4) * 1.24e-3)
    ball = 7.85e-3 * math.pi / 6 * 216 - 1.24e-3 * math.pi / 6 * 6.2 ** 3
    assert rn.balls == int((body - 1.2) // 7.4)
    assert rn.mass_range[1] == pytest.approx(rn.solid_mass + rn.balls * ball)
    lo, hi = zip(*(hw.rod_numbers(L).mass_range for L in (20, 30, 45, 60)))
    assert all(np.diff(lo) > 0) and all(np.diff(hi) >= 0)


def test_sockets_sit_back_so_the_loaded_balls_rest_on_their_pivots():
    pivots = np.array([[7.5, 0, 0], [0, 7.5, 0]])
    forces = np.array([[3.0, 0.0, -1.0], [0.0, 0.0, 0.0]])
    s = socket_centres(pivots, forces, 0.3)
    loaded = s + 0.15 * forces / np.maximum(np.linalg.norm(forces, axis=1, keepdims=True), 1e-300)
    np.testing.assert_allclose(loaded, pivots, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(s - pivots, axis=1), [0.15, 0.0])


def test_the_default_catalog_has_hub_hardware_and_bad_hardware_is_refused(tmp_path):
    text = (CATALOGS / "pla-parametric.yaml").read_text()
    cat = catalog_from_text(text, "c.yaml")
    assert cat.node.kind == "hub" and cat.node.swing_deg > 20 and cat.node.min_angle_deg <= 60 + 1e-9
    assert "  pivot_radius: {min: 4, max: 16, nominal: 7.5}" in text
    bad = text.replace("  pivot_radius: {min: 4, max: 16, nominal: 7.5}", "  pivot_radius: 10").replace(
        "  cone_deg: {min: 55, max: 65}", "  cone_deg: 80")
    with pytest.raises(InputError) as err:
        catalog_from_text(bad, "c.yaml")
    got = [str(p) for p in err.value.problems]
    line = next(i for i, s in enumerate(bad.splitlines(), 1) if s.startswith("  pivot_radius"))
    assert got[0].startswith(f"c.yaml:{line}:17: node.pivot_radius: a socket")
    cone = next(i for i, s in enumerate(bad.splitlines(), 1) if s.startswith("  cone_deg"))
    assert got[1].startswith(f"c.yaml:{cone}:13: node.cone_deg: the opening")
    point = catalog_from_text(text.replace("  kind: hub", "  kind: point\n  mass: 0.8"), "c.yaml").node
    assert point.pivot == 0.0 and point.hub_mass(np.eye(3))[0] == 0.8 and point.min_angle_deg == 0.0
