"""Socket rows of graduated rods on shared print layers (issue 23, graduated rods).

A thick graduated rod can hold its balls in two rows, one above the other about its centre
of mass: two pauses, and the lower row cannot rise (the row above is one minimum wall over
its roof). The semicircle's rod 0 (scale 1.271, 51.76 mm, 6 mm steel balls) is taken with
its 4- and 8-ball options only (their reachable masses computed for real, as in the full
table, but two options instead of sixteen keep the test short). Checked, on the fabrication
plans alone (no B-rep): a chain of two such rods pauses on one layer, each rod's balls in one
row, against two layers (at least) with the designed rows; every plan's mass and centre of
mass, summed in closed form from the voids and the balls, are the designed ones; a raised
upper row keeps the centre of mass too (the plastic its taller sockets take is given back by
the cavities at the centre of mass, off the row's height); and the lower row's bound is the
wall to the row above.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rodcad.catalog.loader import load_catalog
from rodcad.catalog.massrange import mass_info
from rodcad.fabrication.cavities import CAPPED_K, socket_layout, socket_rows
from rodcad.fabrication.intervals import removable_volumes, row_alternates
from rodcad.fabrication.layers import LayerGrid
from rodcad.fabrication.layout import UP, void_volume
from rodcad.fabrication.plan import RoofPlan, plan_rod
from rodcad.fabrication.roofs import roof_options, share_layers

LAYERS = LayerGrid(0.2, 0.2)
MASSES = (21.627, 25.2)  # 4 and 8 balls, each in two rows as designed


@pytest.fixture(scope="module")
def rod_table():
    rod = load_catalog("pla-parametric").rod("rod", 51.763608458837815, 0.009999489832780796,
                                             scale=1.270783016132191)
    info = mass_info(rod)
    rho = rod.material.density / 1000
    lay = socket_layout(rod)
    rs = lay.radius
    net = rod.balls.mass - void_volume("silo", rs) * rho
    rel = lay.centers - np.array([info.com[0], 0.0, 0.0])
    options = [{"mass": info.volume * rho, "sockets": [], "socket_radius": 0.0, "kind": 0, "pieces": []}]
    for n in (4, 8):  # the sockets nearest the centre of mass along the rod, in both rows
        near = np.argsort(np.abs(rel[:, 0]) + 1e-3 * np.abs(rel[:, 2]), kind="stable")[:n]
        socks = lay.centers[np.sort(near)]
        mass_k = info.volume * rho + n * net
        pieces = [[mass_k - b * rho, mass_k - a * rho] for a, b in removable_volumes(rod, socks, rs, 0)]
        options.append({"mass": mass_k, "sockets": socks.tolist(), "socket_radius": rs, "kind": 0,
                        "pieces": sorted(pieces)})
    table = {"options": options, "intervals": [p for o in options for p in o["pieces"]],
             "m_min": info.m_min, "m_max": info.m_max}
    return rod, table, row_alternates(rod, 0, table=table)


def closed_form(rod, plan) -> tuple[float, np.ndarray]:
    """Mass (g) and centre of mass (mm, rod frame) of a plan: the plain solid less its silos
    (half sphere, centroid 3r/8 below the centre, and a cylinder to the roof) and its capped
    cavities, plus the balls at the socket centres."""
    info = mass_info(rod)
    rho = rod.material.density / 1000
    vol = info.volume
    moment = np.array([info.com[0], info.com[1], 0.0]) * vol
    r = plan.socket_radius
    for c, h in zip(plan.sockets, plan.socket_tops):
        half, cyl = 2 / 3 * math.pi * r**3, math.pi * r * r * h
        vol -= half + cyl
        moment -= half * (c - UP * 3 * r / 8) + cyl * (c + UP * h / 2)
    cav = CAPPED_K * plan.cavity_radius**3
    vol -= cav * len(plan.cavities)
    moment -= cav * plan.cavities.sum(axis=0)
    ball = rod.ball_kinds[plan.ball_kind].mass
    mass = vol * rho + ball * len(plan.sockets)
    return mass, (moment * rho + ball * plan.sockets.sum(axis=0)) / mass


def bed_layer(plan, floor: float) -> set[float]:
    return {LAYERS.pause_z(float(y) + float(h) - floor) for y, h in zip(plan.sockets @ UP, plan.socket_tops)}


def test_two_graduated_rods_pause_on_one_layer_with_their_balls_in_one_row(rod_table):
    rod, table, alts = rod_table
    options = [roof_options(rod, m, LAYERS, table, alts) for m in MASSES]
    designed = [s for opts in options for s in opts[0][1]]
    assert all(len(opts[0][1]) == 2 for opts in options)  # two rows each, as designed
    assert len(set(share_layers(designed))) >= 2  # the lower rows cannot rise: two layers at least
    row = [opts[1][1] for opts in options]  # the same balls in one row: one span each
    assert all(len(spans) == 1 for spans in row)
    layers = share_layers([s for spans in row for s in spans])
    assert len(set(layers)) == 1
    info = mass_info(rod)
    for m, opts, k in zip(MASSES, options, layers):
        sockets, (span,) = opts[1]
        roof = LAYERS.top(k - 1) + span.floor if k != span.first else -math.inf
        plan = plan_rod(rod, m, 0, table, roof=RoofPlan((roof,), tuple(map(tuple, sockets))))
        assert len(socket_rows(plan.sockets)) == 1 and len(plan.sockets) == len(opts[0][0] if opts[0][0] is not None
                                                                                else sockets)
        assert bed_layer(plan, span.floor) == {LAYERS.top(k)}
        mass, com = closed_form(rod, plan)
        assert mass == pytest.approx(plan.build_mass, rel=1e-9)  # the cavities remove what is left
        assert np.allclose(com[:2], info.com, atol=1e-6)  # mm: balls and voids about the com
        assert abs(com[2]) < 1e-9


def test_a_raised_upper_row_keeps_the_centre_of_mass_and_the_lower_row_is_walled_in(rod_table):
    rod, table, alts = rod_table
    (plain_socks, spans), _ = roof_options(rod, MASSES[0], LAYERS, table, alts)
    lower, upper = spans
    assert plain_socks is None and lower.first == lower.last and upper.last > upper.first
    plain = plan_rod(rod, MASSES[0], 0, table)
    rows = socket_rows(plain.sockets)
    r, wall = plain.socket_radius, rod.material.min_wall
    gap = float(plain.sockets[rows[1][0]] @ UP) - r - (float(plain.sockets[rows[0][0]] @ UP) + r)
    assert gap == pytest.approx(wall, abs=1e-6)  # the lower roof is one wall under the upper socket
    roof = LAYERS.top(upper.last - 1) + upper.floor
    raised = plan_rod(rod, MASSES[0], 0, table, roof=RoofPlan((-math.inf, roof)))
    tops = raised.socket_tops
    assert np.allclose(tops[rows[0]], r) and np.all(tops[rows[1]] > r + 0.5)
    assert bed_layer(raised, upper.floor) == {LAYERS.top(lower.first), LAYERS.top(upper.last)}
    m0, c0 = closed_form(rod, plain)
    m1, c1 = closed_form(rod, raised)
    assert m1 == pytest.approx(m0, rel=1e-9)
    assert np.allclose(c1, c0, atol=1e-6)  # mm
