"""Mass properties and mass ranges: lattice helpers, layouts checked on the B-rep."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from catalog_testutil import BASE, load
from scipy.spatial.distance import pdist

from rodcad.cad.collision import Clearance
from rodcad.cad.solids import is_valid_solid, mass_properties, type_solid, with_voids
from rodcad.catalog.massrange import compute_mass_info, layouts, mass_info, mass_infos
from rodcad.fabrication.layout import (
    LATTICES,
    SYMMETRIES,
    lattice_image_map,
    lattice_sites,
    sphere_layout,
    symmetric_subset,
)

BALLS = BASE + "    balls: {diameter: 5, density: 7.85, clearance: 0.2}\n"


@pytest.fixture(autouse=True)
def _tmp_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    cache = tmp_path / "cache"
    monkeypatch.setenv("RODCAD_CACHE_DIR", str(cache))
    return cache


def box_clearance(half: tuple[float, float, float]):
    """Signed clearance of the box |x_i| <= half_i."""
    h = np.asarray(half)

    def clearance(points: np.ndarray) -> np.ndarray:
        return np.min(h - np.abs(np.atleast_2d(points)), axis=1)

    bounds = (tuple(-h), tuple(h))
    return clearance, bounds


@pytest.mark.parametrize("kind", LATTICES)
@pytest.mark.parametrize("offset", [(0, 0, 0), (0.5, 0, 0.5), (0.5, 0.5, 0.5)])
def test_lattices_are_symmetric_with_the_given_pitch(kind: str, offset) -> None:
    center = np.array([1.0, -0.5, 0.0])
    pts = lattice_sites(((-9, -6, -4), (11, 5, 4)), center, 2.5, offset, kind)
    assert len(pts) > 10
    assert pdist(pts).min() == pytest.approx(2.5)
    keep = symmetric_subset(pts, np.ones(len(pts), bool), center, "point-xy")
    assert np.allclose(pts[keep].mean(axis=0)[:2], center[:2])


@pytest.mark.parametrize("kind", LATTICES)
@pytest.mark.parametrize("symmetry", SYMMETRIES)
def test_lattice_image_maps_match_the_search(kind: str, symmetry: str) -> None:
    # the image map from lattice indices keeps what the nearest-point search keeps, every offset
    rng = np.random.default_rng(7)
    for _ in range(6):
        center = rng.normal(size=3) * 3
        pitch = float(rng.uniform(0.8, 4.0))
        lo = center - rng.uniform(2, 12, size=3)
        hi = center + rng.uniform(2, 12, size=3)
        for offset in ((ox, oy, oz) for ox in (0.0, 0.5) for oy in (0.0, 0.5) for oz in (0.0, 0.5)):
            pts = lattice_sites((tuple(lo), tuple(hi)), center, pitch, offset, kind)
            if not len(pts):
                continue
            near = lattice_image_map((tuple(lo), tuple(hi)), center, pitch, offset, kind, symmetry)
            for feasible in (np.ones(len(pts), bool), rng.random(len(pts)) < 0.9):
                assert np.array_equal(symmetric_subset(pts, feasible, center, symmetry, near=near),
                                      symmetric_subset(pts, feasible, center, symmetry))


@pytest.mark.parametrize("symmetry", SYMMETRIES)
def test_symmetric_subsets_are_centred(symmetry: str) -> None:
    rng = np.random.default_rng(1)
    center = (3.0, 0.4, 0.0)
    pts = lattice_sites(((-10, -5, -4), (16, 6, 4)), center, 1.7, (0.5, 0, 0))
    feasible = rng.random(len(pts)) < 0.8
    keep = symmetric_subset(pts, feasible, center, symmetry)
    assert keep.sum() > 0 and not (keep & ~feasible).any()
    assert np.allclose(pts[keep].mean(axis=0), center)


def test_sphere_layout_in_a_box_matches_a_hand_count() -> None:
    # 40 x 12 x 8 mm box, r = 2.8, wall 1.2: centres within |x| <= 16, |y| <= 2, z = 0,
    # pitch 6.8 -> x in {0, +-6.8, +-13.6}: five spheres in a row.
    clearance, bounds = box_clearance((20, 6, 4))
    layout = sphere_layout(clearance, bounds, (0, 0, 0), 2.8, 1.2)
    assert layout.count == 5
    assert sorted(layout.centers[:, 0]) == pytest.approx([-13.6, -6.8, 0, 6.8, 13.6])
    # r = 2.2 (pitch 5.6): a hexagonal double row fits (rows 4.85 apart in |y| <= 2.6).
    layout = sphere_layout(clearance, bounds, (0, 0, 0), 2.2, 1.2)
    assert layout.lattice == "hex" and layout.count > 6
    assert pdist(layout.centers).min() >= 2 * 2.2 + 1.2 - 1e-9
    assert (clearance(layout.centers) >= 2.2 + 1.2 - 1e-9).all()


def test_cavities_and_sockets_fit_the_real_solid_and_keep_the_com(tmp_path: Path) -> None:
    rod = load(tmp_path, BALLS.replace("length: 30", "length: 40"))["sq-40"]
    solid = type_solid(rod)
    props = mass_properties(solid)
    cavities, balls = layouts(rod)
    wall = rod.material.min_wall
    clearance = Clearance(solid)
    for layout in (cavities, balls):
        assert layout.count > 0
        assert (clearance(layout.centers) >= layout.radius + wall - 1e-9).all()
        if layout.count > 1:
            assert pdist(layout.centers).min() >= 2 * layout.radius + wall - 1e-9
        # Cut the printable voids from the B-rep: still one valid solid, exact volume, same com
        # (sockets with their balls in).
        holed = with_voids(solid, [(layout.void, layout.centers, layout.radius)])
        assert is_valid_solid(holed)
        assert holed.volume == pytest.approx(props.volume - layout.volume, rel=1e-6)
        hp = mass_properties(holed)
        rho = rod.material.density / 1000
        m = hp.volume * rho
        c = np.array(hp.center) * m
        if layout.void == "silo":
            c += rod.balls.mass * layout.centers.sum(axis=0)
            m += layout.count * rod.balls.mass
        assert np.allclose(c / m, props.center, atol=1e-6)
    assert balls.radius == pytest.approx(2.6)


def test_mass_range_numbers(tmp_path: Path) -> None:
    rod = load(tmp_path, BALLS)["sq-30"]
    info = compute_mass_info(rod)
    cavities, balls = layouts(rod)
    rho = 1.24e-3
    assert info.solid_mass == pytest.approx(info.volume * rho)
    assert info.m_min == pytest.approx((info.volume - cavities.volume) * rho)
    ball_mass = math.pi / 6 * 5**3 * 7.85e-3
    assert info.m_max == pytest.approx((info.volume - balls.volume) * rho + balls.count * ball_mass)
    assert info.m_min < info.solid_mass < info.m_max
    assert info.ball_count == balls.count and info.cavity_count == cavities.count
    assert info.com == pytest.approx(mass_properties(type_solid(rod)).center[:2])
    assert mass_info(rod).mass_range == (info.m_min, info.m_max)


def test_without_balls_the_top_of_the_range_is_the_solid(tmp_path: Path) -> None:
    rod = load(tmp_path, BASE)["sq-30"]
    info = mass_info(rod)
    assert info.m_max == info.solid_mass and info.ball_count == 0


def test_mass_info_is_cached(tmp_path: Path, _tmp_cache: Path) -> None:
    cat = load(tmp_path, BASE.replace("length: 30", "length: [20, 30]"))
    infos = mass_infos(list(cat), jobs=2)
    assert list(infos) == ["sq-20", "sq-30"] and len(list(_tmp_cache.glob("mass/*/*.json"))) == 2
    assert mass_info(cat["sq-30"]) == infos["sq-30"]
    assert infos["sq-20"].solid_mass < infos["sq-30"].solid_mass
