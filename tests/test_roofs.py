"""Socket roofs on shared print layers (issue 23): a chain's rods pause on as few layers as
their walls and cavities allow, with their masses and centres of mass unchanged.

Checked: the layer choice against a brute-force search for the fewest layers; the taller
socket's volume and centroid against the B-rep of the void; a fabricated pair of rods (the
test slicer chain's concave rod and one of the heart's curved rods, 0.6 mm apart in their
plain roofs, in different layers) built on one shared layer, each weighing its target, its
centre of mass where the plain rod's is, every wall measured on the B-rep.
"""

from __future__ import annotations

import itertools
import math
import re

import numpy as np
import pytest

from rodcad.cad.printfile import plan_plates
from rodcad.cad.rods import MASS_TOL, fabricate_chain
from rodcad.cad.solids import mass_properties, void_template
from rodcad.catalog.loader import load_catalog
from rodcad.catalog.massrange import mass_info
from rodcad.fabrication.layers import LayerGrid
from rodcad.fabrication.layout import UP, ball_offset, silo_volume, tall_silo
from rodcad.fabrication.roofs import RoofSpan, share_layers

LAYERS = LayerGrid(0.2, 0.2)


def fewest_layers(spans: list[RoofSpan]) -> int:
    """Brute force: the smallest set of layers that meets every span."""
    candidates = sorted({k for s in spans for k in range(s.first, s.last + 1)})
    for n in range(1, len(spans) + 1):
        for pick in itertools.combinations(candidates, n):
            if all(any(s.first <= k <= s.last for k in pick) for s in spans):
                return n
    return 0


def test_share_layers_uses_the_fewest_layers_and_raises_each_roof_least():
    rng = np.random.default_rng(23)
    for _ in range(200):
        n = int(rng.integers(1, 7))
        firsts = rng.integers(50, 62, n)
        spans = [RoofSpan(int(f), int(f + rng.choice([0, 0, 1, 3, 8])), -8.0) for f in firsts]
        got = share_layers([*spans, None])
        assert got[-1] is None
        layers = got[:-1]
        assert all(s.first <= k <= s.last for s, k in zip(spans, layers))
        assert len(set(layers)) == fewest_layers(spans)
        for s, k in zip(spans, layers):  # no lower chosen layer would have served it
            assert not any(s.first <= j < k for j in set(layers))


@pytest.mark.parametrize("extra", [0.0, 0.4, 1.3])
def test_a_taller_socket_and_its_ball_still_act_at_the_site(extra):
    r, ball, rho = 3.1, 0.8878, 1.24  # a 6.2 mm socket, a 6 mm steel ball, PLA
    site = 1.0
    plain = site + ball_offset(r, ball, rho) + r
    centre, h = tall_silo(site, r, ball, rho, plain + extra)
    assert centre + h == pytest.approx(plain + extra, abs=1e-9) and h >= r - 1e-12
    void = void_template("silo", r, h)  # the B-rep of the socket, centre at the origin
    props = mass_properties(void)
    assert props.volume == pytest.approx(silo_volume(r, h), rel=1e-6)
    removed = props.volume * rho / 1000
    acts_at = (ball * centre - removed * (centre + props.center[1])) / (ball - removed)
    assert acts_at == pytest.approx(site, abs=1e-6)


@pytest.fixture(scope="module")
def pair():
    """The slicer test's concave rod (pla-weighted, roof 12.28 mm, pausing at 12.4) and a
    heart rod printed to order (roof 11.64 mm, pausing at 11.8), built plain and on shared
    layers."""
    weighted = load_catalog("pla-weighted")["concave20-30"]
    lo, hi = mass_info(weighted).mass_range
    curved = load_catalog("pla-parametric").rod("rod", 47.604, 0.005325)
    types, masses = [weighted, curved], [lo + 0.9 * (hi - lo), 14.0]
    plain = fabricate_chain(types, masses, seed=0, jobs=1).rods
    shared = fabricate_chain(types, masses, seed=0, jobs=1, layers=LAYERS).rods
    kept = fabricate_chain(types, masses, seed=0, jobs=1, layers=LAYERS, keep_roofs={1}).rods
    return plain, shared, kept


def test_the_pair_pauses_on_one_layer_instead_of_two(pair):
    plain, shared, kept = pair
    pause = [LAYERS.pause_z(z) for r in plain for z in r.pause_zs]
    assert len(set(pause)) == 2
    assert {LAYERS.pause_z(z) for r in shared for z in r.pause_zs} == {max(pause)}
    (plate,) = plan_plates(shared)
    assert list(plate.pauses) == [max(pause)]
    assert set(re.findall(r"\b(\d{2})\b", plate.pauses[max(pause)])) == {"00", "01"}  # both rods named
    assert [r.pause_zs for r in kept] == [r.pause_zs for r in plain]  # kept as laid out


def test_raised_roofs_lie_on_a_layer_top_and_keep_mass_centre_of_mass_and_walls(pair):
    plain, shared, _ = pair
    a, b = plain[1], shared[1]
    assert a.socket_height == 0 and b.socket_height > b.socket_radius + 0.3
    (roof,) = b.pause_zs
    k = round((roof - LAYERS.first_layer) / LAYERS.layer_height)
    assert roof == pytest.approx(LAYERS.top(k), abs=1e-6)  # midway between two slicing planes
    assert abs(b.mass / b.target_mass - 1) <= MASS_TOL
    assert np.hypot(*np.subtract(b.com, a.com)) < 1e-4  # mm
    assert b.min_wall >= 1.2 - 1e-9  # measured on the B-rep
    assert b.ball_count == a.ball_count and b.cavity_count >= 1
    moved = np.asarray(b.socket_centers) - np.asarray(a.socket_centers)
    assert np.allclose(moved - np.outer(moved @ UP, UP), 0, atol=1e-9)  # straight up, the same for each
    assert np.ptp(moved @ UP) < 1e-9 and 0 < float(moved[0] @ UP) < 0.5
    # the plastic the taller sockets take is what the cavities give back
    taller = b.ball_count * math.pi * b.socket_radius**2 * (b.socket_height - b.socket_radius)
    assert a.plastic_volume - b.plastic_volume == pytest.approx(0, abs=1e-3 * a.plastic_volume)
    assert taller > 5  # mm^3
    assert shared[0].pause_zs == plain[0].pause_zs  # the highest roof stays where it is
