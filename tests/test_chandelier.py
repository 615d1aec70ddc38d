"""Chandeliers: chain placements in 3D, the frame with its lugs, previews, STEP, design."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rodcad.cad.chandelier import build_frame, chandelier_nodes
from rodcad.cad.export import rod_matrix
from rodcad.cad.solids import type_solid
from rodcad.catalog.loader import load_catalog
from rodcad.design.chandelier import (
    ChainPlacement,
    design_chandelier,
    explicit,
    polygon_frame,
    ring,
    two_rings,
)
from rodcad.design.frame import FramePlan, frame_outline, plan_frame
from rodcad.outputs.preview3d import preview_3d


@pytest.fixture(scope="module")
def catalog():
    return load_catalog("pla-pinned")


@pytest.fixture(scope="module")
def arrays(catalog):
    from rodcad.design.plan import catalog_arrays

    return catalog_arrays(catalog, jobs=2)


@pytest.fixture(scope="module")
def small(catalog, arrays):
    """Three 7-rod chains around a ring, designed, with their ring frame built."""
    pl = ring(3, 60, 0)
    design = design_chandelier(catalog, pl, {"form": "catenary", "length": 140}, arrays=arrays)
    plan = plan_frame("ring", pl, catalog, design.chains)
    frame, check = build_frame(plan, catalog, design.chains)
    return pl, design, plan, frame, check


# --------------------------------------------------------------------------- placements


def _assert_frame_maps(p: ChainPlacement) -> None:
    m = p.transform()
    r = m[:3, :3]
    assert np.allclose(r.T @ r, np.eye(3), atol=1e-12) and np.isclose(np.linalg.det(r), 1.0)
    assert np.allclose(m[3], [0, 0, 0, 1])
    assert np.allclose(r[:, 1], [0, 0, 1])  # y up
    assert abs(r[2, 2]) < 1e-12 and abs(r[2, 0]) < 1e-12  # x and the hinge axis horizontal
    a2, b2 = p.plane_anchors()
    assert a2[0] == 0 and np.isclose(b2[0], p.horizontal_distance)
    ends = p.to_3d(np.array([a2, b2]))
    assert np.allclose(ends, [p.a3, p.b3], atol=1e-9)
    # any chain-plane point lands on the vertical plane through both anchors, as transform() puts it
    rng = np.random.default_rng(1)
    q = rng.normal(size=(20, 2)) * 50
    w = p.to_3d(q)
    assert np.allclose((w - p.a3) @ p.axis, 0, atol=1e-9)
    hom = (m @ np.column_stack([q, np.zeros(20), np.ones(20)]).T).T[:, :3]
    assert np.allclose(hom, w, atol=1e-9)
    assert np.allclose(p.to_plane(w), q, atol=1e-9)


def test_ring_places_chords_with_gaps():
    pl = ring(6, 100, 5.0, start_deg=15, gap=20)
    assert [p.name for p in pl] == [f"chain_0{i}" for i in range(1, 7)]
    for k, p in enumerate(pl):
        _assert_frame_maps(p)
        for x in (p.a3, p.b3):
            assert np.isclose(np.hypot(x[0], x[1]), 100) and x[2] == 5.0
        # chain k ends gap / 2 (along the circle) before vertex k+1, where chain k+1 starts gap / 2 after
        nxt = pl[(k + 1) % 6].a3
        ang = math.atan2(nxt[1], nxt[0]) - math.atan2(p.b3[1], p.b3[0])
        assert np.isclose((ang + math.pi) % (2 * math.pi) - math.pi, 20 / 100)
        assert np.isclose(p.horizontal_distance, 2 * 100 * math.sin((math.pi / 3 - 0.2) / 2))
    with pytest.raises(ValueError, match="gap must be > 0"):
        ring(6, 100, gap=0)
    with pytest.raises(ValueError, match="at least the ring's side arc"):
        ring(6, 10, gap=20)


def test_two_rings_polygon_and_explicit():
    pl = two_rings(5, 20, 0, 90, -150, twist_deg=30)
    assert len(pl) == 5
    for k, p in enumerate(pl):
        _assert_frame_maps(p)
        assert np.isclose(np.hypot(*p.a3[:2]), 20) and p.a3[2] == 0
        assert np.isclose(np.hypot(*p.b3[:2]), 90) and p.b3[2] == -150
        turn = math.atan2(p.b3[1], p.b3[0]) - math.atan2(p.a3[1], p.a3[0])
        assert np.isclose((turn + math.pi) % (2 * math.pi) - math.pi, math.radians(30))
    with pytest.raises(ValueError, match="vertically above each other"):
        two_rings(4, 50, 0, 50, -100)
    sq = np.array([[0, 0, 0], [100, 0, 0], [100, 100, 20], [0, 100, 20]], float)
    pl = polygon_frame(sq, gap=10)
    assert len(pl) == 4
    for k, p in enumerate(pl):
        _assert_frame_maps(p)
        e = sq[(k + 1) % 4] - sq[k]
        assert np.allclose(p.a3, sq[k] + e / np.linalg.norm(e) * 5)
        assert np.isclose(np.linalg.norm(p.b3 - p.a3), np.linalg.norm(e) - 10)
    with pytest.raises(ValueError, match="vertically above each other"):
        polygon_frame([[0, 0, 0], [0, 0, 100]], gap=10)
    pl = explicit([((0, 0, 0), (50, 0, -10)), ((0, 10, 0), (0, 60, 0))], names=["a", "b"])
    assert [p.name for p in pl] == ["a", "b"] and pl[1].plane_anchors().tolist() == [[0, 0], [50, 0]]
    with pytest.raises(ValueError, match="share the anchor"):
        explicit([((0, 0, 0), (50, 0, 0)), ((50, 0, 0), (90, 0, 0))])
    with pytest.raises(ValueError, match="vertically above each other"):
        ChainPlacement("v", (1, 2, 3), (1, 2, -40))


# --------------------------------------------------------------------------- frame


def _hole_axes(frame, radius: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """(point, direction) of every cylindrical face of the given radius."""
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.GeomAbs import GeomAbs_Cylinder

    out = []
    for f in frame.faces():
        s = BRepAdaptor_Surface(f.wrapped)
        if s.GetType() == GeomAbs_Cylinder and abs(s.Cylinder().Radius() - radius) < 1e-9:
            ax = s.Cylinder().Axis()
            p, d = ax.Location(), ax.Direction()
            out.append((np.array([p.X(), p.Y(), p.Z()]), np.array([d.X(), d.Y(), d.Z()])))
    return out


def test_ring_frame_is_valid_and_its_pin_axes_pass_through_the_anchors(catalog, small):
    from rodcad.cad.solids import is_valid_solid

    pl, design, plan, frame, check = small
    assert is_valid_solid(frame) and check.valid
    hinge = catalog[design.chains[0].type_names[0]].geometry.hinge
    axes = _hole_axes(frame, hinge.hole_diameter / 2)
    assert plan.lugs and len(plan.lugs) == 2 * len(pl)
    for lug, x in zip(plan.lugs, [x for p in pl for x in (p.a3, p.b3)]):
        assert np.allclose(lug.anchor, x)
        hits = [(q, d) for q, d in axes
                if abs(abs(d @ lug.axis) - 1) < 1e-9 and np.linalg.norm(np.cross(x - q, d)) < 1e-6]
        assert hits, f"no pin hole on the axis through {lug.name}"
        assert all(abs(d @ np.array([0, 0, 1.0])) < 1e-9 for _, d in hits)  # horizontal
    # first rods start in tongues: their lugs are forks (clevis); last rods end in forks
    assert [lug.knuckle for lug in plan.lugs[:2]] == ["fork", "tongue"]
    # the frame hangs above the anchors (only the knuckles reach below) and fits the printer
    assert frame.bounding_box().min.Z == pytest.approx(pl[0].a3[2] - hinge.knuckle_radius)
    assert frame.bounding_box().max.Z == pytest.approx(plan.params["z"] + plan.params["thickness"])
    assert check.fits_printer
    assert check.size[0] <= 2 * (60 + plan.params["width"] / 2) + 1e-6


def test_rods_clear_the_frame_at_rest_and_hanging_free(catalog, small):
    pl, design, plan, frame, check = small
    assert check.ok, check.problems
    poses = {(n, pose) for n, pose, _ in check.clearances}
    for lug in plan.lugs:
        assert (lug.name, "free") in poses
    for c in design.chains:
        assert (f"{c.name}.rod_00", "rest") in poses and (f"{c.name}.rod_{len(c.masses) - 1:02d}", "rest") in poses
    gap = catalog[design.chains[0].type_names[0]].geometry.hinge.layer_gap
    # a rod on a lug comes no closer than the hinge's layer gap
    assert min(d for *_, d in check.clearances) == pytest.approx(gap, abs=1e-6)


def test_frame_problems_are_reported(catalog, small):
    from rodcad.cad.collision import DistanceTo
    from rodcad.cad.export import placed
    from rodcad.cad.frame import frame_solid
    from rodcad.cad.solids import GeometryError

    pl, design, plan, frame, check = small
    # a rod turned up into the ring touches it
    bad = FramePlan(plan.kind, plan.params, plan.lugs, [math.pi / 2 if r is not None else None
                                                          for r in plan.rest])
    lug = bad.lugs[0]
    rod = catalog[design.chains[0].type_names[0]]
    d = DistanceTo(frame)(placed(type_solid(rod), lug.location @ rod_matrix((0, 0), math.pi / 2)))
    assert d == 0.0
    # a ring too far out for the lugs to reach
    far = dict(plan.params, radius=plan.params["radius"] + 40)
    with pytest.raises(GeometryError, match="lug chain_01.A"):
        frame_solid("ring", far, plan.lugs)
    # a frame larger than the printer is reported, not refused
    big = ring(6, 130, 0)
    bplan = plan_frame("ring", big, catalog)
    _, bcheck = build_frame(bplan, catalog, check_clearance=False)
    assert bcheck.fits_printer is False and "does not fit the printer" in bcheck.problems[0]


def test_two_rings_and_bars_frames_are_single_valid_solids(catalog):
    from rodcad.cad.solids import is_valid_solid

    pl = two_rings(4, 25, 0, 80, -120)
    plan = plan_frame("two_rings", pl, catalog, bottom_side="below")
    frame, check = build_frame(plan, catalog, check_clearance=False)
    assert check.valid and check.fits_printer
    bb = frame.bounding_box()
    assert bb.max.Z > 0 and bb.min.Z < -120  # hub above the top anchors, ring below the bottom ones
    assert len(_hole_axes(frame, plan.lugs[0].hinge.hole_diameter / 2)) >= len(plan.lugs)
    sq = np.array([[0, 0, 0], [120, 0, 0], [120, 120, 0], [0, 120, 0]], float)
    pl = polygon_frame(sq)
    plan = plan_frame("bars", pl, catalog, vertices=sq)
    frame, check = build_frame(plan, catalog)
    assert is_valid_solid(frame) and check.ok, check.problems
    with pytest.raises(ValueError, match="needs the anchors' polygon"):
        plan_frame("bars", pl, catalog)


# --------------------------------------------------------------------------- preview, assembly


def test_preview_writes_png_and_svg(small, tmp_path):
    pl, design, plan, frame, check = small
    files = preview_3d(tmp_path / "preview.png", design.chains, frame_outline(plan), title="t", svg=True)
    assert [f.name for f in files] == ["preview.png", "preview.svg"]
    assert (tmp_path / "preview.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (tmp_path / "preview.png").stat().st_size > 20_000


def test_assembly_holds_the_frame_and_every_chain_in_place(catalog, small, tmp_path):
    from build123d import import_step

    from rodcad.cad.export import export_assembly, read_assembly

    pl, design, plan, frame, check = small
    nodes = chandelier_nodes(frame, design.chains, catalog, frame_plan=plan)
    assert [n.name for n in nodes] == ["frame"] + [p.name for p in pl]
    for g, c in zip(nodes[1:], design.chains):
        assert np.allclose(g.location, c.placement.transform())
        n = len(c.masses)
        assert [k.name for k in g.children[:n]] == [f"{i:02d}_{t}" for i, t in enumerate(c.type_names)]
        assert len(g.children) == 2 * n + 1
    path = export_assembly(tmp_path / "assembly.step", nodes, "chandelier")
    leaves = read_assembly(path)
    n_rods = sum(len(c.masses) for c in design.chains)
    assert len(leaves) == 1 + n_rods + (n_rods + len(pl))
    root = import_step(path)
    assert [c.label for c in root.children] == ["frame"] + [p.name for p in pl]
    # the pins sit on the world joints: the anchors among them
    pin_vol = math.pi * (0.875**2)
    centers = np.array([[*s.center()] for s in root.solids() if s.volume < 200 * pin_vol])
    for p in pl:
        for x in (p.a3, p.b3):
            assert np.min(np.linalg.norm(centers - x, axis=1)) < 1e-6


# --------------------------------------------------------------------------- design


def test_design_chandelier_end_to_end(catalog, arrays):
    pl = ring(6, 100, 0)
    targets = [{"form": "catenary", "length": 260}, {"form": "catenary", "length": 280}] * 3
    d1 = design_chandelier(catalog, pl, targets, method="refine", seed=3, jobs=1,
                                arrays=arrays)
    assert d1.n_distinct == 2 and len(d1.chains) == 6
    rows = d1.errors()
    assert [r["name"] for r in rows] == [p.name for p in pl]
    for r, c in zip(rows, d1.chains):
        assert r["n_rods"] >= 12 and r["stable"] and r["success"]
        assert r["max_mm"] == c.distance.max and r["max_rel_span"] < 0.01
        assert np.allclose(c.points[[0, -1]], c.placement.plane_anchors(), atol=1e-9)
        assert np.allclose(c.points3d[[0, -1]], [c.placement.a3, c.placement.b3], atol=1e-9)
    assert d1.chains[2].shared_with == "chain_01" and d1.chains[1].shared_with is None
    bom = d1.bom
    assert bom.n_rods == sum(bom.rods_by_type.values()) == sum(r["n_rods"] for r in rows)
    assert bom.total_mass == pytest.approx(sum(r["mass_g"] for r in rows))
    assert bom.pins == bom.n_rods - 6 and bom.anchor_pins == 12
    # parallel workers give the same design
    d2 = design_chandelier(catalog, pl, targets, method="refine", seed=3, jobs=2,
                                arrays=arrays)
    for a, b in zip(d1.chains, d2.chains):
        assert a.type_names == b.type_names and np.array_equal(a.masses, b.masses)
    with pytest.raises(ValueError, match="4 targets for 6 chains"):
        design_chandelier(catalog, pl, targets[:4])


def test_lug_holes_take_each_chain_s_anchor_hardware_and_its_compensation(tmp_path):
    """With joint hardware chosen per joint, each lug's pin hole is the anchor option's hole
    for the lug's knuckle, moved to where the loaded anchor pin bears on the anchor (as a
    single chain's fixture), and the frame solid has it there: the hole's centre and a point
    just inside its rim are empty, a point just outside the rim is frame."""
    from build123d import Vector

    from rodcad import pipeline
    from rodcad.design.asprinted import anchor_holes
    from rodcad.design.loader import load_design

    text = ("design: 1\nname: two\ncatalog: pla-pinned\nchandelier: {pattern: explicit, chains: [\n"
            "  {anchors: [[0, 0, 0], [150, 0, 0]], target: {form: arc, sag: 50}},\n"
            "  {anchors: [[0, 60, 0], [0, 200, 20]], target: {form: catenary, length: 220}}]}\n")
    b = pipeline.build_chandelier(load_design(tmp_path / "two.yaml", text=text), cad=False)
    frame, check = build_frame(b.frame_plan, b.design.catalog, check_clearance=False)
    assert check.valid
    for k, lug in enumerate(b.frame_plan.lugs):
        r = b.chains[k // 2]
        option = r.hardware.options[-1 if k % 2 else 0]
        assert lug.pin_hole == pytest.approx(option.hole(lug.knuckle))
        shift = anchor_holes(r.holes, r.equilibrium.points)[k % 2]
        assert np.allclose(lug.hole_offset, shift) and 0 < np.hypot(*shift) <= option.clearance / 2 + 1e-9
        m = lug.location
        rim = lug.pin_hole / 2
        knuckle = lug.hinge.knuckle_radius
        for radius, inside in ((0.0, False), (rim - 0.05, False), (min(rim + 0.2, knuckle - 0.2), True)):
            for ang in np.linspace(0, 2 * np.pi, 6, endpoint=False):
                q = np.array([shift[0] + radius * np.cos(ang), shift[1] + radius * np.sin(ang), 0.0, 1.0])
                if lug.knuckle == "fork":  # a fork's material is in its prongs, off the mid-plane
                    q[2] = lug.width / 2 - lug.cheek / 2
                w = m @ q
                assert frame.is_inside(Vector(*w[:3])) == inside, (lug.name, radius, ang)


def test_a_chandelier_built_with_cad_writes_its_frame_and_rods_checked(build_design):
    """`rodcad build` of a small chandelier with CAD: the frame's STEP re-imports as one valid
    solid and its STL is watertight with the solid's volume (written and checked beside every
    chain's rods, :func:`rodcad.cad.chainfiles.start_rod_files`), and every chain has its rods'
    files and print.3mf."""
    import trimesh

    from rodcad.cad.export import import_step
    from rodcad.cad.mesh import DEFLECTION
    from rodcad.cad.solids import is_valid_solid

    text = ("design: 1\nname: small-chandelier\ncatalog: pla-pinned\nchandelier:\n  pattern: ring\n  count: 3\n"
            "  radius: 60\n  height: 0\n  gap: 20\n  target:\n    form: catenary\n    length: 100\n"
            "  frame: {width: 16, thickness: 5}\nconstraints:\n  lengths: [20]\nmethod: refine\nseed: 0\n"
            "tolerance: 0.02\n")
    out, data = build_design(text, "small-chandelier")
    frame = import_step(out / "frame.step")
    assert is_valid_solid(frame)
    mesh = trimesh.load(str(out / "frame.stl"), force="mesh")
    assert mesh.is_watertight
    assert abs(mesh.volume - frame.volume) <= DEFLECTION * frame.area  # the STL's deflection x the area
    chains = sorted(p for p in out.iterdir() if p.is_dir())
    assert len(chains) == 3
    for chain in chains:
        assert (chain / "print.3mf").is_file()
        rods = chain / "rods"
        assert sorted(p.stem for p in rods.glob("*.step")) == sorted(p.stem for p in rods.glob("*.stl"))
        assert list(rods.glob("*.step"))
