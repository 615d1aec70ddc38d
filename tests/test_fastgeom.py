"""The kernel-free mass properties and clearance of rodcad.catalog.fastgeom against the
B-rep of rodcad.cad.solids.build_rod: straight and curved rods, flush, chamfered,
concave and mixed ends, both hinge layouts.
"""

from __future__ import annotations

import subprocess
import sys
import time
from dataclasses import replace

import numpy as np
import pytest

from rodcad.cad.collision import Clearance
from rodcad.cad.solids import build_rod, mass_properties
from rodcad.catalog.fastgeom import RodClearance, rod_mass_properties
from rodcad.catalog.loader import load_catalog
from rodcad.catalog.model import EndShape

WEIGHTED = load_catalog("catalogs/pla-weighted.yaml")
PINNED = load_catalog("catalogs/pla-pinned.yaml")


def _fork_tongue(g):
    return replace(g.hinge, layout="fork-tongue")


def _geometries():
    w, p = WEIGHTED, PINNED
    free40 = w["free-40"].geometry
    pfree = p["free-30"].geometry
    curve = w["curve20-40"].geometry
    return {
        "weighted-free-40": free40,
        "weighted-concave20-30": w["concave20-30"].geometry,  # concave flush stop, setback 0
        "pinned-arc-30": p["arc-30"].geometry,  # curved, k = 0.02
        "pinned-concave40-20": p["concave40-20"].geometry,  # short, concave top, free bottom
        "curved-mixed-ends": replace(free40, curvature=0.012, first=EndShape(1.0, -30.0, 60.0),
                                     second=EndShape(0.0, 60.0, -30.0)),
        "pinned-negative-curvature-fork-tongue": replace(pfree, curvature=-0.03, hinge=_fork_tongue(pfree),
                                                         first=EndShape(0.3, 20.0, 0.0)),
        # second end: a flush square face on the line where the arc meets the stub
        "weighted-curved-flush": replace(w["straight-30"].geometry, curvature=-0.02,
                                         first=EndShape(0.5, 30.0, 10.0)),
        "long-curved-fork-tongue": replace(curve, length=50.0, curvature=0.025, hinge=_fork_tongue(curve),
                                           first=EndShape(0.8, 10.0, -5.0), second=EndShape(0.3, 45.0, 25.0)),
    }


GEOMETRIES = _geometries()


@pytest.fixture(scope="module")
def kernel():
    """Per geometry: the B-rep solid, its mass properties and its clearance field."""
    out = {}
    for name, g in GEOMETRIES.items():
        solid = build_rod(g)
        out[name] = (mass_properties(solid), Clearance(solid))
    return out


@pytest.mark.parametrize("name", list(GEOMETRIES))
def test_volume_and_centre_of_mass_match_the_solid(kernel, name):
    g = GEOMETRIES[name]
    exact, _ = kernel[name]
    volume, com = rod_mass_properties(g)
    # the integration is exact: far inside the 1e-3 / 0.02 mm targets
    assert abs(volume - exact.volume) <= 1e-9 * exact.volume, (volume, exact.volume)
    assert np.abs(np.subtract(com, exact.center)).max() <= 1e-6, (com, exact.center)


def test_curvature_moves_the_centre_of_mass_off_the_chord():
    """A plain sanity check independent of the kernel: a sagging rod's (k > 0) mass
    lies below the chord, a straight symmetric rod's on it and in its middle."""
    g = WEIGHTED["free-40"].geometry
    _, (x, y, z) = rod_mass_properties(g)
    assert abs(y) < 1e-9 and z == 0.0
    assert 19.0 < x < 21.0  # tongue and fork knuckles differ a little
    _, (_, y_sag, _) = rod_mass_properties(replace(g, curvature=0.01))
    _, (_, y_hog, _) = rod_mass_properties(replace(g, curvature=-0.01))
    assert y_sag < -0.5 and y_hog > 0.5


@pytest.mark.parametrize("name", list(GEOMETRIES))
def test_clearance_is_conservative_and_exact_in_the_core(kernel, name):
    g = GEOMETRIES[name]
    _, exact = kernel[name]
    fast = RodClearance(g)
    assert np.allclose(fast.bounds, exact.bounds, atol=1e-6), (fast.bounds, exact.bounds)
    rng = np.random.default_rng(sorted(GEOMETRIES).index(name))
    lo, hi = np.array(exact.bounds)
    pts = rng.uniform(lo, hi, (300, 3))
    ours, theirs = fast(pts), exact(pts)
    assert ours.shape == (300,)
    assert (ours <= theirs + 1e-6).all(), pts[np.argmax(ours - theirs)]
    core = (theirs > 0) & (np.abs(pts[:, 0] - g.length / 2) < g.length / 6)
    assert core.sum() >= 20
    assert np.abs(ours[core] - theirs[core]).max() <= 1e-5
    # it is in fact the exact signed distance everywhere, hinge layers and all
    assert np.abs(ours - theirs).max() <= 1e-6
    assert ((ours > 0) == (theirs > 0)).all()


def test_clearance_near_the_hinge_layers(kernel):
    """Points around both joints, many right at the layer faces (tongue, gap, prongs)."""
    name = "long-curved-fork-tongue"
    g = GEOMETRIES[name]
    _, exact = kernel[name]
    rng = np.random.default_rng(7)
    pts = rng.uniform([-7, -9, -g.thickness / 2 - 1], [7, 9, g.thickness / 2 + 1], (300, 3))
    pts[::2, 0] += g.length
    a = g.hinge.tongue_thickness / 2
    faces = np.array([a, a + g.hinge.layer_gap, g.thickness / 2])
    pts[::3, 2] = rng.choice(faces, 100) * rng.choice([-1, 1], 100) + rng.normal(0, 0.02, 100)
    ours, theirs = RodClearance(g)(pts), exact(pts)
    assert (ours <= theirs + 1e-6).all()
    assert np.abs(ours - theirs).max() <= 1e-6


def test_single_point_and_speed():
    g = WEIGHTED["free-40"].geometry
    fast = RodClearance(g)
    one = fast(np.array([20.0, 0.0, 0.0]))
    assert one.shape == (1,) and one[0] == pytest.approx(8.0, abs=1e-6)  # half the 16 mm section
    pts = np.random.default_rng(0).uniform(*fast.bounds, (100_000, 3))
    t0 = time.perf_counter()
    fast(pts)
    rod_mass_properties(replace(g, length=41.0))  # not cached
    assert time.perf_counter() - t0 < 0.5  # about 30 ms on one core; generous for busy machines


def test_fastgeom_does_not_import_the_kernel():
    code = ("import sys, rodcad.catalog.fastgeom; "
            "sys.exit(any(m.split('.')[0] in ('build123d', 'OCP') for m in sys.modules))")
    assert subprocess.run([sys.executable, "-c", code], check=False).returncode == 0
