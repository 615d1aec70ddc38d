"""The symmetric-lattice cavity fallback of every ball option of a rod laid at once
(:func:`rodcad.fabrication.cavities.lattice_layouts_many`: the lattices, the solid's
clearance and each socket's distance once, only the choice of sites per option), which both
the tables of reachable masses and :func:`place_cavities` (through :func:`lattice_layouts`)
use. Checked against :func:`sphere_layout` given each option's whole clearance written out
(the solid's, less the sockets' where the solid leaves room): the same radii, the same sites
to the bit, for options of no sockets, one orbit, several and all, of two socket radii, and
of roofs of their own; a skipped radius is not laid; a 'silo' void is refused by the batched
layout (it needs a rim check per set)."""

from __future__ import annotations

import numpy as np
import pytest

from rodcad.catalog.loader import load_catalog
from rodcad.cad.solids import mass_properties, type_solid
from rodcad.catalog.massrange import mass_info
from rodcad.fabrication.cavities import (cavity_radii, lattice_layouts, lattice_layouts_many, silo_distance,
                                         silo_distances, socket_layout, solid_clearance)
from rodcad.fabrication.layout import sphere_layout, sphere_layouts


@pytest.fixture(scope="module")
def rod_options():
    rod = load_catalog("pla-parametric").rod("rod", 48.0, 0.01, scale=1.04)
    lay = socket_layout(rod)
    assert lay.count >= 4, "the test wants a rod with several ball sockets"
    c = lay.centers
    order = np.argsort(np.abs(c[:, 0] - c[:, 0].mean()), kind="stable")
    options = [(np.zeros((0, 3)), 0.0), (c[np.sort(order[:2])], lay.radius),
               (c[np.sort(order[:4])], lay.radius), (c, lay.radius), (c[np.sort(order[-2:])], lay.radius),
               (c[np.sort(order[:2])], 0.7 * lay.radius),  # (a second ball kind: the same sites, smaller)
               (c[np.sort(order[:2])], lay.radius, (2.0 * lay.radius, 3.0 * lay.radius))]  # taller roofs
    return rod, options


def _written_out(rod, socks, rs, roofs=None):
    """The one option's layouts by :func:`sphere_layout` on its whole clearance, per radius."""
    clr = solid_clearance(rod)
    com = mass_properties(type_solid(rod)).center
    wall = rod.material.min_wall
    info = mass_info(rod)
    radii = sorted(set(cavity_radii(rod)) | {info.cavity_radius} - {0.0}, reverse=True)
    out = []
    for rd in radii:
        def clearance(p, need=rd + wall):
            c = np.array(clr(p))
            if len(socks):
                room = np.flatnonzero(c >= need)
                c[room] = np.minimum(c[room], silo_distance(p[room], socks, rs, roofs))
            return c
        out.append((rd, sphere_layout(clearance, clr.bounds, com, rd, wall, void="capped")))
    return out


def test_every_option_gets_the_layout_its_own_clearance_gives(rod_options):
    rod, options = rod_options
    many = list(lattice_layouts_many(rod, options))
    assert many, "no cavity radius tried"
    for j, option in enumerate(options):
        alone = _written_out(rod, *option)
        assert [rd for rd, _ in alone] == [rd for rd, _ in many]
        for (rd, one), (_, lays) in zip(alone, many):
            got = lays[j]
            assert got.count == one.count, (j, rd)
            assert got.symmetry == one.symmetry and got.lattice == one.lattice
            np.testing.assert_array_equal(got.centers, one.centers)
    # place_cavities' path is the same function on one option, roofs included
    socks, rs, roofs = options[-1]
    for (rd, one), (_, lays) in zip(lattice_layouts(rod, socks, rs, socket_h=roofs), many):
        np.testing.assert_array_equal(one.centers, lays[-1].centers)
    # the sockets take sites: the counts fall as options hold more of them, somewhere
    counts = np.array([[lays[j].count for j in range(len(options))] for _, lays in many])
    assert (counts[:, 0] >= counts[:, 3]).all() and (counts[:, 0] > counts[:, 3]).any()
    # taller roofs take sites too, somewhere
    assert (counts[:, 1] >= counts[:, -1]).all() and (counts[:, 1] > counts[:, -1]).any()


def test_skipped_radii_are_not_laid(rod_options):
    rod, options = rod_options
    radii = [rd for rd, _ in lattice_layouts_many(rod, options[:1])]
    skip_rd = radii[len(radii) // 2]
    for rd, lays in lattice_layouts_many(rod, options, lambda j, r: j == 2 and r == skip_rd):
        assert (lays[2] is None) == (rd == skip_rd)
        assert all(lay is not None for j, lay in enumerate(lays) if j != 2)


def test_silo_distances_columns_and_silos_refused(rod_options):
    _, options = rod_options
    socks, rs = options[3][:2]
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
