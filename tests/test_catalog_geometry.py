"""Exact rod solids: validity, frame, pin holes, centre of mass, STEP round trip."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from catalog_testutil import BASE, load

from rodcad.cad.collision import Clearance
from rodcad.cad.export import export_step, import_step
from rodcad.cad.solids import (
    is_valid_solid,
    mass_properties,
    type_solid,
    with_spherical_voids,
)
from rodcad.catalog.loader import load_catalog
from rodcad.catalog.massrange import mass_info

SHIPPED = load_catalog("pla-pinned")


@pytest.fixture(autouse=True)
def _tmp_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("RODCAD_CACHE_DIR", str(tmp_path / "cache"))


def inside(solid, points) -> np.ndarray:
    return Clearance(solid)(np.asarray(points, dtype=float)) > 0


@pytest.mark.parametrize("name", SHIPPED.names)
def test_every_shipped_type_builds_a_valid_named_solid(name: str) -> None:
    rod = SHIPPED[name]
    g = rod.geometry
    solid = type_solid(rod)
    assert is_valid_solid(solid)
    assert solid.label == name
    bb = solid.bounding_box()
    r = g.hinge.knuckle_radius
    # Knuckles reach one knuckle radius past each axis along x; thickness is centred on z = 0.
    assert bb.min.X == pytest.approx(-r, abs=1e-6) and bb.max.X == pytest.approx(g.length + r, abs=1e-6)
    assert bb.min.Z == pytest.approx(-g.thickness / 2, abs=1e-6)
    assert bb.max.Z == pytest.approx(g.thickness / 2, abs=1e-6)
    # Pin holes on both hinge axes, through every layer; knuckle material around them.
    hole = g.hinge.hole_diameter / 2
    a = g.hinge.tongue_thickness / 2
    prong_z = (a + g.hinge.layer_gap + g.thickness / 2) / 2
    for x in (0.0, g.length):
        assert not inside(solid, [(x, 0, z) for z in (0.0, prong_z, -prong_z)]).any()
    ring = hole + 0.3
    assert inside(solid, [(ring, 0, 0), (-ring, 0, 0), (0, ring, 0)]).all()  # tongue at the first joint
    assert inside(solid, [(g.length + ring, 0, prong_z), (g.length, -ring, -prong_z)]).all()  # fork prongs
    # The partner's layers are cleared inside the hinge zone.
    zone = g.hinge.zone_radius - 0.05
    assert not inside(solid, [(zone, 0, prong_z), (g.length - zone, 0, 0)]).any()


def test_volume_and_com_of_a_square_ended_rod_match_a_hand_count(tmp_path: Path) -> None:
    rod = load(tmp_path, BASE)["sq-30"]
    g, hg = rod.geometry, rod.geometry.hinge
    h, t, L, s = g.height, g.thickness, g.length, g.first.setback
    r, R, Z = hg.hole_diameter / 2, hg.knuckle_radius, hg.zone_radius
    tongue, gap = hg.tongue_thickness, hg.layer_gap
    prongs = t - tongue - 2 * gap

    def bar_side(rho: float) -> float:
        """Area of a disc of radius rho about a hinge axis on the bar's side of the end face
        (the circular segment cut off by a chord at distance s)."""
        return rho**2 * math.acos(s / rho) - s * math.sqrt(rho**2 - s**2)

    bar = (L - 2 * s) * h * t  # between the two end faces
    # Each knuckle adds its disc outside the bar less the pin hole, in its own layers; the
    # partner's layers lose the hinge-zone disc inside the bar (the hole lies within it).
    knuckle = math.pi * R**2 - bar_side(R) - math.pi * r**2
    cleared = bar_side(Z)
    first = knuckle * tongue - cleared * (t - tongue)          # tongue at the first joint
    second = knuckle * prongs - cleared * (tongue + 2 * gap)   # fork at the second
    props = mass_properties(type_solid(rod))
    assert props.volume == pytest.approx(bar + first + second, rel=1e-9)
    # Mirror symmetric in y and z: the com lies on the chord.
    assert props.center[1] == pytest.approx(0, abs=1e-9) and props.center[2] == pytest.approx(0, abs=1e-9)
    assert 0 < props.center[0] < L
    assert mass_info(rod).solid_mass == pytest.approx(props.volume * 1.24e-3)


@pytest.mark.parametrize("curvature, sign", [(0.02, -1), (-0.02, 1)])
def test_curvature_sign_sets_the_side_of_the_com(tmp_path: Path, curvature: float, sign: int) -> None:
    rod = load(tmp_path, BASE.replace("length: 30", f"length: 30\n    curvature: {curvature}"))["sq-30"]
    solid = type_solid(rod)
    assert is_valid_solid(solid)
    com = mass_properties(solid).center
    assert math.copysign(1, com[1]) == sign and abs(com[1]) > 1.0
    # The body follows the arc: its middle sits one sagitta off the chord.
    rho = 1 / abs(curvature)
    sag = rho - math.sqrt(rho**2 - 15**2)
    assert inside(solid, [(15, sign * sag, 0)]).all()
    assert not inside(solid, [(15, -sign * (6 - sag + 0.2), 0)]).any()


def test_fork_tongue_layout_swaps_the_knuckles(tmp_path: Path) -> None:
    rod = load(tmp_path, BASE.replace("length: 30", "length: 30\n    joint: {layout: fork-tongue}"))["sq-30"]
    g = rod.geometry
    solid = type_solid(rod)
    assert is_valid_solid(solid)
    ring = g.hinge.hole_diameter / 2 + 0.3
    assert inside(solid, [(g.length - ring, 0, 0), (-ring, 0, 3.3)]).all()
    assert not inside(solid, [(-ring, 0, 0), (g.length + ring, 0, 3.3)]).any()


@pytest.mark.parametrize("name", SHIPPED.names)
def test_step_round_trip_keeps_validity_volume_and_name(tmp_path: Path, name: str) -> None:
    solid = type_solid(SHIPPED[name])
    path = export_step(solid, tmp_path / f"{name}.step", name)
    text = path.read_text()
    assert text.startswith("ISO-10303-21;") and f"PRODUCT('{name}'" in text
    assert text.count("MANIFOLD_SOLID_BREP") == 1
    back = import_step(path)
    assert back.is_valid and back.label == name
    assert back.volume == pytest.approx(solid.volume, rel=1e-6)
    back_bb, bb = back.bounding_box(), solid.bounding_box()
    assert (back_bb.min - bb.min).length < 1e-5 and (back_bb.max - bb.max).length < 1e-5


def test_spherical_voids_keep_the_solid_valid(tmp_path: Path) -> None:
    solid = type_solid(load(tmp_path, BASE)["sq-30"])
    centres = np.array([[11.0, 0, 0], [19.0, 0, 0]])
    holed = with_spherical_voids(solid, centres, 2.0)
    assert is_valid_solid(holed)
    assert holed.volume == pytest.approx(solid.volume - 2 * 4 / 3 * math.pi * 8, rel=1e-9)
