"""Target curve + shipped catalog -> rod types and masses (the catalog-facing inverse design)."""

from __future__ import annotations

import numpy as np
import pytest

from rodcad.catalog.loader import load_catalog
from rodcad.design.masses import design_chain
from rodcad.design.plan import catalog_arrays, plan_chain
from rodcad.design.targets import catenary, semicircle


@pytest.fixture(scope="module")
def catalog_and_arrays():
    # the session's disk cache (conftest.py): the catalog's limits are computed once per run
    cat = load_catalog("pla-pinned")
    return cat, catalog_arrays(cat, jobs=2)


def test_reachable_catenary_is_designed_exactly_and_uniquely(catalog_and_arrays):
    cat, arrays = catalog_and_arrays
    plan = plan_chain(cat, catenary((0, 0), (200, 0), length=300), arrays=arrays)
    d = design_chain(plan, "refine", n_starts=6)
    assert d.result.exact and d.unique
    assert d.result.distance.max_rel_span < 1e-6 and d.result.time_s < 0.1
    lo, hi = plan.problem.mass_bounds.T
    assert np.all((d.result.masses >= lo) & (d.result.masses <= hi))
    assert all(name.startswith("free-") for name in plan.type_names)


def test_straight_run_gets_straight_stop_types(catalog_and_arrays):
    cat, arrays = catalog_and_arrays
    # a flat-bottomed U: sloping sides, a straight 120 mm run at the bottom
    curve = np.array([[0, 0], [48, -64], [168, -64], [216, 0]], float)  # sides 80, 120, 80
    plan = plan_chain(cat, curve, arrays=arrays, lengths=[20, 40])
    bends = np.diff(plan.problem.angles)
    flat = np.flatnonzero(np.abs(bends) < 1e-6)
    # the straight joints rest on stops at straight, except next to a corner: the corner
    # rods must bend freely, and the shipped types have the same end shape at both ends
    stopped = flat[np.abs(plan.problem.limits[flat, 1]) < np.radians(0.01)]
    assert stopped.size >= 5
    assert all(plan.type_names[j].startswith("straight") for j in stopped)
    d = design_chain(plan, "refine", n_starts=4)
    assert d.result.success
    eq = d.result.equilibrium
    assert np.all(eq.active[stopped] == 1) and np.all(eq.moments[stopped] < 0)


def test_bad_constraints_explained(catalog_and_arrays):
    cat, arrays = catalog_and_arrays
    with pytest.raises(ValueError, match="no rod type of the catalog is allowed"):
        plan_chain(cat, semicircle((0, 0), (200, 0)), arrays=arrays, allowed_types=["nope"])


@pytest.mark.parametrize("seed", range(6))
def test_a_chain_of_catalog_rods_given_as_its_polyline_comes_back_exactly(catalog_and_arrays, seed):
    """Hang a random chain of free-30 and free-40 rods (masses inside their ranges), give
    its joints as a polyline target: the plan finds its own rod lengths and the design
    hangs on it to 1e-6 of the span, every mass in range."""
    from optimize import solve_equilibrium

    cat, arrays = catalog_and_arrays
    names = ["free-30", "free-40"]
    rng = np.random.default_rng(seed)
    n = int(rng.integers(5, 12))
    k = [arrays.index[names[i]] for i in rng.integers(0, 2, n)]
    lengths, com = arrays.lengths[k], arrays.com[k]
    lo, hi = arrays.mass_bounds[k].T
    span = rng.uniform(0.6, 0.9) * lengths.sum()
    b = (span * np.cos(rng.uniform(-0.3, 0.3)), span * np.sin(rng.uniform(-0.3, 0.3)))
    eq = solve_equilibrium(lengths, rng.uniform(lo, hi), (0, 0), b, com=com)
    plan = plan_chain(cat, eq.points, arrays=arrays, allowed_types=names)
    np.testing.assert_array_equal(plan.problem.lengths, lengths)
    d = design_chain(plan, "refine", n_starts=4)
    assert d.result.distance.max_rel_span < 1e-6 and d.unique
    lo, hi = plan.problem.mass_bounds.T
    assert np.all((d.result.masses >= lo) & (d.result.masses <= hi))
