"""The reachable-mass tables lay the lattice fallback of every ball option of a rod at once
(:func:`rodcad.fabrication.cavities.lattice_layouts_many`): the lattices, the solid's
clearance and each socket's distance once, only the choice of sites per option. Checked
against the one-option path :func:`place_cavities` itself falls back on
(:func:`lattice_layouts`, built on :func:`sphere_layout`): the same radii, the same sites to
the bit, for options of no sockets, one orbit, several and all, and of two socket radii; a
skipped radius is not laid; a 'silo' void is refused by the batched layout (it needs a rim
check per set)."""

from __future__ import annotations

import numpy as np
import pytest

from rodcad.catalog.loader import load_catalog
from rodcad.fabrication.cavities import lattice_layouts, lattice_layouts_many, silo_distance, silo_distances, socket_layout
from rodcad.fabrication.layout import sphere_layouts


@pytest.fixture(scope="module")
def rod_options():
    rod = load_catalog("pla-parametric").rod("rod", 48.0, 0.01, scale=1.04)
    lay = socket_layout(rod)
    assert lay.count >= 4, "the test wants a rod with several ball sockets"
    c = lay.centers
    order = np.argsort(np.abs(c[:, 0] - c[:, 0].mean()), kind="stable")
    options = [(np.zeros((0, 3)), 0.0), (c[np.sort(order[:2])], lay.radius),
               (c[np.sort(order[:4])], lay.radius), (c, lay.radius), (c[np.sort(order[-2:])], lay.radius),
               (c[np.sort(order[:2])], 0.7 * lay.radius)]  # (a second ball kind: the same sites, smaller)
    return rod, options


def test_every_option_gets_the_layout_it_gets_alone(rod_options):
    rod, options = rod_options
    many = list(lattice_layouts_many(rod, options))
    assert many, "no cavity radius tried"
    for j, (socks, rs) in enumerate(options):
        alone = list(lattice_layouts(rod, socks, rs))
        assert [rd for rd, _ in alone] == [rd for rd, _ in many]
        for (rd, one), (_, lays) in zip(alone, many):
            got = lays[j]
            assert got.count == one.count, (j, rd)
            assert got.symmetry == one.symmetry and got.lattice == one.lattice
            np.testing.assert_array_equal(got.centers, one.centers)
    # the sockets take sites: the counts fall as options hold more of them, somewhere
    counts = np.array([[lays[j].count for j in range(len(options))] for _, lays in many])
    assert (counts[:, 0] >= counts[:, 3]).all() and (counts[:, 0] > counts[:, 3]).any()


def test_skipped_radii_are_not_laid(rod_options):
    rod, options = rod_options
    radii = [rd for rd, _ in lattice_layouts_many(rod, options[:1])]
    skip_rd = radii[len(radii) // 2]
    for rd, lays in lattice_layouts_many(rod, options, lambda j, r: j == 2 and r == skip_rd):
        assert (lays[2] is None) == (rd == skip_rd)
        assert all(lay is not None for j, lay in enumerate(lays) if j != 2)


def test_silo_distances_columns_and_silos_refused(rod_options):
    _, options = rod_options
    socks, rs = options[3]
    rng = np.random.default_rng(3)
    pts = socks.mean(axis=0) + rng.normal(scale=8.0, size=(200, 3))
    cols = silo_distances(pts, socks, rs)
    assert cols.shape == (200, len(socks))
    np.testing.assert_array_equal(cols.min(axis=1), silo_distance(pts, socks, rs))
    # each column is that socket alone
    for k in range(len(socks)):
        np.testing.assert_array_equal(cols[:, k], silo_distance(pts, socks[k:k + 1], rs))
    with pytest.raises(ValueError, match="silo"):
        sphere_layouts(lambda p: np.ones(len(p)), ((0, 0, 0), (1, 1, 1)), (0.5, 0.5, 0.5), 0.1, 0.1,
                       lambda p: np.ones((len(p), 0)), [np.zeros(0, dtype=np.int64)], void="silo")
