"""Rods that push where the hardware holds them (issue 33): with ``net.compression`` unset, a
rigid rod between two hubs may push (the ball sockets hold its balls either way) while it stays
under a fifth of its Euler buckling load; a rod at a two-rod joint, or at point nodes, may not.

Truth: MuJoCo (tests/mujoco_net.py, no rodcad code) for the equilibrium with pushing diagonals,
and the buckling criterion flipped by the material's modulus.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from net_settle import settle_from_other_masses
from test_net_collapse import _strip

from rodcad.design.loader import load_design
from rodcad.design.net.check import BUCKLING_SAFETY
from rodcad.design.net.choose import design_drawn_net

#: A strip 55 mm wide and 300 mm long in 6 bays with diagonals, sagging 30 mm: hung from its
#: ends, its diagonals push (5-6 % of the largest tension).
STRIP = _strip(55.0, 300.0, 6, 30.0)


@pytest.fixture(scope="module")
def pushed():
    d = load_design("strip.yaml", text=STRIP)
    return d, design_drawn_net(d.net, d.catalog, seed=0)


def test_diagonals_that_push_are_held_by_default_and_mujoco_agrees(pushed):
    d, check = pushed
    plan, t = check.plan, check.plan.target
    T = check.equilibrium.tensions
    assert d.net.compression is None  # (unset: the default)
    assert check.ok and check.rel_size <= check.tolerance and check.compressed.size >= 3
    assert check.unheld.size == 0
    hw = plan.hardware
    for e in check.compressed:
        assert not t.joint_mask[t.edges[e]].any()  # one rigid rod between two hubs
        assert -T[e] * BUCKLING_SAFETY <= hw.buckling_load(float(plan.lengths[e]))
    # MuJoCo, released from another shape of the same rods, rests where rodcad's equilibrium is
    err, moved = settle_from_other_masses(check, 7)
    assert err < 1e-5 * t.size and moved > 20 * err  # (a braced strip is stiff: 30 % other masses move it 0.1 mm)


def test_pushing_is_refused_when_asked_or_beyond_a_fifth_of_the_buckling_load(pushed):
    d, check = pushed
    no = dataclasses.replace(check.plan.target, compression=False)
    refused = dataclasses.replace(check, plan=dataclasses.replace(check.plan, target=no))
    assert not refused.ok and np.array_equal(refused.unheld, check.compressed)
    assert "push (compression)" in refused.limit() and "net.compression: true" in refused.limit()
    # the same rods of a material a million times softer buckle under their push
    hw = check.plan.hardware
    soft = dataclasses.replace(hw, modulus=hw.modulus * 1e-6)
    assert soft.buckling_load(100.0) == pytest.approx(hw.buckling_load(100.0) * 1e-6)
    assert hw.buckling_load(50.0) == pytest.approx(4 * hw.buckling_load(100.0))  # Euler: 1 / L^2
    weak = dataclasses.replace(check, plan=dataclasses.replace(check.plan, hardware=soft))
    assert not weak.ok and np.array_equal(weak.unheld, check.compressed)
    assert "buckling" in weak.limit()


def test_a_catalogs_modulus_is_read_and_a_bad_one_is_refused_at_its_key():
    from rodcad.catalog.loader import catalog_from_text
    from rodcad.catalog.paths import default_catalog_dir
    from rodcad.errors import InputError

    text = (default_catalog_dir() / "pla-parametric.yaml").read_text()
    shipped = "  material: {name: PLA, density: 1.24, min_wall: 1.2}"
    assert shipped in text
    stiff = catalog_from_text(text.replace(shipped, shipped[:-1] + ", modulus: 3.5}"), "c.yaml")
    assert stiff.node.modulus == 3.5 and next(iter(stiff)).material.modulus == 3.5
    assert catalog_from_text(text, "c.yaml").node.modulus == 1.5  # (the default)
    bad = text.replace(shipped, shipped[:-1] + ", modulus: -2}")
    with pytest.raises(InputError) as err:
        catalog_from_text(bad, "c.yaml")
    line = next(i for i, s in enumerate(bad.splitlines(), 1) if "modulus: -2" in s)
    col = bad.splitlines()[line - 1].index("-2") + 1
    got = [str(p) for p in err.value.problems]
    assert got == [f"c.yaml:{line}:{col}: defaults.material.modulus: must be greater than 0 GPa and at most 500 GPa "
                   "(got -2)"], got
