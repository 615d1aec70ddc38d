"""The refinement of a net's masses toward the least largest distance of its fit.

Truth: the equilibrium's derivatives with respect to the masses (node points, node bodies'
turns, and through them the rods' pivots) against central finite differences of the solver;
the refined design against an independent minimax (scipy's SLSQP on the epigraph form, its
gradients by finite differences of the solver), on a net of node bodies whose target no masses
within the bounds balance.
"""

from __future__ import annotations

import numpy as np
from netgen import grid_net, plan_pivots
from scipy.optimize import minimize

from optimize import design_net, solve_net
from optimize.net.model import Net
from optimize.net.newton import RHO
from optimize.net.refine import (Swing, _fit_jacobian, _swing_gradient, equilibrium_derivatives, fit_distances,
                                 net_fit, swing_angles)


def _bodies(u: int = 2, v: int = 2):
    """A bowl of node bodies (pivots 4 mm out along each rod's plan direction, centres of mass
    below the node points, rods' centres of mass off their axes), hung from its corners."""
    spec = grid_net(u, v, x=(0, 40.0 * u), y=(0, 40.0 * v),
                    z=lambda x, y: 0.004 * ((x - 20 * u) ** 2 + (y - 20 * v) ** 2) - 30)
    piv, lengths = plan_pivots(spec, 4.0)
    rng = np.random.default_rng(3)
    kw = dict(node_masses=rng.uniform(0.5, 1.5, spec.n), node_com=np.tile([0.0, 0.0, -1.0], (spec.n, 1)),
              pivots=piv, com=np.column_stack([lengths / 2, rng.uniform(-2, 2, spec.m), np.zeros(spec.m)]))
    return spec, lengths, kw


def test_derivatives_of_the_equilibrium_match_finite_differences():
    spec, lengths, kw = _bodies(3, 3)
    m = np.random.default_rng(1).uniform(1.0, 4.0, spec.m)
    res = solve_net(spec.positions, spec.edges, lengths, m, spec.anchored, **kw)
    assert res.success and res.stable
    net, st = Net.from_args(res.positions, spec.edges, lengths, m, spec.anchored, node_rotations0=res.rotations, **kw)
    derivs = equilibrium_derivatives(net, st, res.tensions)
    assert np.any(derivs[1] != 0)  # (the bodies turn with the masses)
    fit = net_fit(spec.positions, spec.edges, kw["pivots"])
    rows = np.arange(spec.n + 2 * spec.m)
    J = _fit_jacobian(res, fit, spec.edges, derivs, rows)  # node points, then pivots

    swing = Swing(kw["pivots"], np.full((spec.m, 2), np.inf))
    ends = np.argwhere(np.ones((spec.m, 2), bool))
    S = _swing_gradient(res, swing, spec.edges, derivs, ends).reshape(spec.m, 2, spec.m)

    def points(masses):
        r = solve_net(res.positions, spec.edges, lengths, masses, spec.anchored, node_rotations0=res.rotations, **kw)
        assert r.success and r.stable
        return np.vstack([r.positions, r.ends.reshape(-1, 3)]), swing_angles(r, swing, spec.edges)

    h = 1e-4
    for e in (0, spec.m // 2, spec.m - 1):
        mp, mm = m.copy(), m.copy()
        mp[e] += h
        mm[e] -= h
        (pp, sp), (pm, sm) = points(mp), points(mm)
        fd = (pp - pm) / (2 * h)
        fs = (sp - sm) / (2 * h)  # (rad per g: each rod's turn in its two sockets)
        assert np.max(np.abs(fs - S[:, :, e])) <= 100 / RHO * np.max(np.abs(S[:, :, e]))
        # central differences: truncation ~h^2 and the solves' round-off ~1e-13 mm / h, both far
        # below the derivatives' own error: their regularised KKT solve (H + RHO J'J) leaves the
        # rods' lengths to a penalty, a relative error of the order of 1 / RHO times the
        # conditioning (1e-5 here, the same for h = 1e-2 .. 1e-5)
        assert np.max(np.abs(fd - J[:, :, e])) <= 100 / RHO * np.max(np.abs(J[:, :, e]))


def _unreachable():
    """The bowl of node bodies hung from random masses, and mass bounds that exclude them: no
    masses within the bounds balance its shape. Returns (spec, lengths, kw, target, rotations,
    bounds)."""
    spec, lengths, kw = _bodies()
    truth = np.random.default_rng(0).uniform(1.0, 4.0, spec.m)
    hung = solve_net(spec.positions, spec.edges, lengths, truth, spec.anchored, **kw)
    bounds = np.column_stack([np.full(spec.m, 2.2), np.full(spec.m, 2.6)])
    return spec, lengths, kw, hung.positions, hung.rotations, bounds


def test_the_refinement_reaches_the_least_largest_distance():
    spec, lengths, kw, target, R, bounds = _unreachable()
    fit = net_fit(target, spec.edges, kw["pivots"], R)

    def largest(masses):
        r = solve_net(target, spec.edges, lengths, masses, spec.anchored, node_rotations0=R, **kw)
        return fit_distances(r, fit) if r.success and r.stable else None

    d = design_net(target, spec.edges, lengths, bounds, spec.anchored, rotations=R, n_starts=1, max_refine=60, **kw)
    assert not d.statics.exact
    assert d.refined and d.info["refined_error"] < d.info["fit_error"]
    assert np.all(d.masses >= bounds[:, 0]) and np.all(d.masses <= bounds[:, 1])
    # the verdict's equilibrium is the refinement's: solved again from the target, the same fit
    again = largest(d.masses)
    assert again is not None and abs(again.max() - d.error) <= 1e-9 * spec.size
    # what the fit measures includes the bodies' pivots, which their turns move
    assert d.error == again.max() >= np.max(np.linalg.norm(d.equilibrium.positions - target, axis=1))

    # an independent minimax: min t s.t. e_i(m) <= t, SLSQP, finite-difference gradients
    x0 = np.append(d.statics.masses, largest(d.statics.masses).max())
    cons = {"type": "ineq", "fun": lambda x: x[-1] - largest(x[:-1])}
    sq = minimize(lambda x: x[-1], x0, method="SLSQP", constraints=[cons],
                  bounds=[*map(tuple, bounds), (0, None)], options={"maxiter": 200, "ftol": 1e-10})
    independent = largest(np.clip(sq.x[:-1], bounds[:, 0], bounds[:, 1])).max()
    assert independent < d.info["fit_error"]  # (the comparison is not between two starts)
    # as low as the independent optimiser's, within the solver's and the steps' tolerance
    assert d.error <= independent * (1 + 1e-3) + 1e-9 * spec.size


def test_the_refinement_keeps_the_rods_within_their_sockets_swing():
    spec, lengths, kw, target, R, bounds = _unreachable()
    swing = Swing(kw["pivots"], np.full((spec.m, 2), np.inf))
    free = design_net(target, spec.edges, lengths, bounds, spec.anchored, rotations=R, n_starts=1, **kw)
    start = solve_net(target, spec.edges, lengths, free.statics.masses, spec.anchored, node_rotations0=R, **kw)
    before = np.degrees(swing_angles(start, swing, spec.edges))
    after = np.degrees(swing_angles(free.equilibrium, swing, spec.edges))
    # sockets that let each rod turn half as much further as the free refinement turns it
    limits = np.maximum(before, (before + after) / 2)
    assert np.any(after > limits + 1e-3)
    held = design_net(target, spec.edges, lengths, bounds, spec.anchored, rotations=R, n_starts=1,
                      swing_limits=limits, **kw)
    turned = np.degrees(swing_angles(held.equilibrium, swing, spec.edges))
    assert np.all(turned <= limits + 1e-9)
    assert held.refined and free.error * (1 - 1e-9) <= held.error < held.info["fit_error"]
