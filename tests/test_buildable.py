"""Inverse design onto the masses fabrication can really build (gaps between ball counts)."""

from __future__ import annotations

import numpy as np
import pytest

from rodcad.catalog.loader import load_catalog
from rodcad.design.masses import design_buildable, design_chain
from rodcad.design.plan import catalog_arrays, plan_chain
from rodcad.design.targets import catenary, semicircle


@pytest.fixture(scope="module")
def catalog_and_arrays():
    # the session's disk cache (conftest.py): the catalog's limits are computed once per run
    cat = load_catalog("pla-pinned")
    return cat, catalog_arrays(cat, jobs=2)


def _inside(masses, intervals) -> bool:
    return all(any(lo <= m <= hi for lo, hi in iv) for m, iv in zip(masses, intervals))


def _gappy(plan, width: float = 0.25):
    """Hand-made intervals: each rod's bounds with a gap of ``width`` x the range in the middle
    of the upper half (like the ball-count gaps above the solid mass)."""
    out = []
    for lo, hi in plan.problem.mass_bounds:
        mid = lo + 0.6 * (hi - lo)
        out.append([(lo, mid - width / 2 * (hi - lo)), (mid + width / 2 * (hi - lo), hi)])
    return out


def test_snapped_masses_are_buildable_and_reported(catalog_and_arrays):
    cat, arrays = catalog_and_arrays
    # the exact design of a catenary keeps its masses well inside their bounds
    plan = plan_chain(cat, catenary((0, 0), (240, 30), length=330), arrays=arrays, allowed_types=["free-30"])
    ivs = _gappy(plan, 0.6)
    free = design_chain(plan, "refine", n_starts=4)
    d = design_buildable(plan, "refine", intervals=ivs, n_starts=4, rescale=False)
    info = d.buildable
    assert _inside(d.result.masses, ivs)
    assert not _inside(free.result.masses, ivs) and info.snapped >= 1
    # re-simulated for the buildable masses, and no better than the continuous design
    eq = plan.problem.simulate(d.result.masses)
    assert np.allclose(eq.points, d.result.equilibrium.points, atol=1e-9)
    assert info.error_after == pytest.approx(d.result.distance.max_rel_span)
    assert info.error_before == pytest.approx(free.result.distance.max_rel_span, rel=1e-6)
    assert info.error_after >= info.error_before * (1 - 1e-6) - 1e-12
    assert info.error_after < 0.01
    assert isinstance(d.unique, bool) and d.n_stable >= 1
    for k, (designed, built) in info.moved.items():
        assert not _inside([designed], [ivs[k]]) and _inside([built], [ivs[k]])
    # same input, same output
    again = design_buildable(plan, "refine", intervals=ivs, n_starts=4, rescale=False)
    assert np.array_equal(again.result.masses, d.result.masses)


def test_common_scale_keeps_an_exact_shape(catalog_and_arrays):
    """A catenary is reachable for a whole family of mass scales: one of them fits the gaps."""
    cat, arrays = catalog_and_arrays
    plan = plan_chain(cat, catenary((0, 0), (240, 30), length=330), arrays=arrays, allowed_types=["free-30"])
    ivs = _gappy(plan, 0.5)
    d = design_buildable(plan, "refine", intervals=ivs, n_starts=4)
    assert _inside(d.result.masses, ivs)
    assert d.result.exact and d.buildable.snapped == 0
    assert d.buildable.scale != 1.0


def test_max_rounds_zero_snaps_without_redesign(catalog_and_arrays):
    cat, arrays = catalog_and_arrays
    plan = plan_chain(cat, semicircle((0, 0), (200, 0)), arrays=arrays, lengths=[30])
    ivs = _gappy(plan, 0.6)
    d = design_buildable(plan, "exact", intervals=ivs, n_starts=2, max_rounds=0, rescale=False)
    assert _inside(d.result.masses, ivs) and d.buildable.rounds == 0


def test_real_intervals_of_the_catalog(catalog_and_arrays):
    """With the intervals fabrication reports (pla-pinned: gaps between the ball counts)."""
    from rodcad.fabrication.intervals import chain_intervals

    cat, arrays = catalog_and_arrays
    plan = plan_chain(cat, catenary((0, 0), (240, 30), length=330), arrays=arrays, allowed_types=["free-30"])
    by_type = chain_intervals([cat[n] for n in set(plan.type_names)], jobs=1)
    ivs = [by_type[n] for n in plan.type_names]
    assert len(ivs[0]) >= 2  # not one continuous range
    d = design_buildable(plan, "refine", intervals=by_type, n_starts=4)
    assert _inside(d.result.masses, ivs)
    assert d.result.distance.max_rel_span < 1e-3
