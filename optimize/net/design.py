"""Inverse design of a hanging net: masses from the statics, checked by the exact solver.

:func:`design_net` runs the whole numerical design of a net (no CAD):

1. :func:`optimize.net.statics.design_net_masses`: masses within bounds that balance the
   target exactly (LP, then the central QP), or the best fit within them and why not;
2. the exact equilibrium from the target (:func:`optimize.solve_net`): an exact design must
   come back to the target to round-off, stable;
3. when the statics are not exact and ``refine`` is set, a bounded nonlinear least squares
   on the node positions through the forward solver, with the Jacobian of the equilibrium
   with respect to the masses from implicit differentiation of its KKT system
   (:func:`shape_jacobian`), started from the best fit;
4. the multi-start for other stable shapes (``alternatives``; ``lower`` when one hangs
   lower than the design's).

Units: mm, g, forces in g x the unit of ``g``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from scipy.optimize import least_squares
from threadpoolctl import threadpool_limits

from optimize.net.solve import NetResult, solve_net
from optimize.net.deriv import evaluate, gauge_rows, hessian
from optimize.net.model import Net, NetState
from optimize.net.newton import RHO, newton_matrix, pd_factor
from optimize.net.statics import NetMassDesign, design_net_masses

__all__ = ["NetDesign", "design_net", "multistart_text", "shape_jacobian"]


def shape_jacobian(net: Net, state: NetState, tensions: np.ndarray) -> np.ndarray:
    """d(node points) / d(rod masses) at an equilibrium, shape (n, 3, m).

    Implicit differentiation of the KKT system ``grad U + J' lam = 0, c = 0``:
    ``[[H, J'], [J, 0]] [dy; dlam] = -[dG/dm; 0]``, solved in its regularised form
    ``(H + rho J'J) dy = -dG/dm`` (the symmetries held, as in the solver). Anchored nodes
    do not move. Holds while the equilibrium stays stable.

    Args:
        net, state: the validated net and its equilibrium configuration.
        tensions: (m,) the equilibrium's multipliers (``NetResult.tensions``).

    Returns:
        (n, 3, m) array of mm per g.
    """
    ev = evaluate(net, state)
    lam = np.asarray(tensions, float)
    out = np.zeros((net.n, 3, net.m))
    if net.nvar == 0:
        return out
    hess = hessian(net, state, ev, lam)
    gauge = gauge_rows(net, state, ev)
    s_h = max(net.weight, float(np.max(np.abs(lam), initial=0.0))) / net.mean_length
    lu = None
    for rho in (RHO, 1e10):
        lu = pd_factor(newton_matrix(net, hess, ev, gauge, 0.0, rho, s_h))
        if lu is not None:
            break
    if lu is None:
        raise FloatingPointError("the equilibrium is not stable: its shape has no derivative")
    # dG/dm_e: rod e's weight shares per unit mass, at its pivots
    t = net.along / net.lengths
    frac = np.column_stack([1 - t - ev.q, t + ev.q]) * net.g
    GP = np.zeros((net.m, 2, 3))
    GP[:, :, 2] = frac
    local = np.empty((net.m, net.loc.shape[1]))
    if net.per_end == 3:
        local[:] = GP.reshape(net.m, 6)
    else:
        for k in (0, 1):
            local[:, 6 * k:6 * k + 3] = GP[:, k]
            local[:, 6 * k + 3:6 * k + 6] = np.cross(ev.a[:, k], GP[:, k])
    keep = net.loc >= 0
    cols = np.broadcast_to(np.arange(net.m)[:, None], net.loc.shape)
    G = sp.csc_matrix((local[keep], (net.loc[keep], cols[keep])), shape=(net.nvar, net.m)).toarray()
    dy = -lu.solve(G)
    free = np.flatnonzero(net.pos_idx >= 0)
    out[free] = dy[net.pos_idx[free][:, None] + np.arange(3)]
    return out


@dataclass
class NetDesign:
    """The numerical design of a net and the solver's verdict on it.

    Attributes:
        masses: (m,) the designed rod masses (g).
        statics: the statics design at the target (exact or best fit, and why).
        equilibrium: the exact equilibrium of the designed net from the target, with the
            multi-start's other stable shapes in ``equilibrium.alternatives``.
        error: largest distance of a node from its target (mm); rel_error: over ``size``.
        size: the target's largest extent (mm).
        on_target: the equilibrium succeeded, is stable and within ``tol`` x size of the target.
        refined: the masses come from the nonlinear refinement (the statics were not exact).
        message: what the design reached, in words.
    """

    masses: np.ndarray
    statics: NetMassDesign
    equilibrium: NetResult
    error: float
    rel_error: float
    size: float
    on_target: bool
    refined: bool = False
    message: str = ""
    info: dict = field(default_factory=dict)

    @property
    def tensions(self) -> np.ndarray:
        """(m,) the rods' tensions in the designed equilibrium."""
        return self.equilibrium.tensions

    @property
    def unique(self) -> bool:
        """On target and no other stable shape found."""
        return self.on_target and not self.equilibrium.alternatives

    @property
    def lower(self) -> bool:
        """Another stable shape hangs lower than the design's."""
        return self.equilibrium.lower


def _error(res: NetResult, target: np.ndarray) -> float:
    if not res.success:
        return np.inf
    return float(np.max(np.linalg.norm(res.positions - target, axis=1)))


def design_net(target_positions, edges, lengths, mass_bounds, anchored, *, node_masses=None, com=None,
               allow_compression: bool = False, g: float = 9.81, node_com=None, pivots=None, rotations=None,
               n_starts: int = 8, seed: int = 0, refine: bool = True, tol: float = 1e-6,
               max_refine: int = 10, callback=None, statics: NetMassDesign | None = None,
               leave_unstable: bool = False) -> NetDesign:
    """Masses for a net to hang in its target, and the exact solver's check of them.

    Args:
        target_positions: (n, 3) target node points (mm), anchored nodes where they hang.
        edges, lengths, anchored, node_masses, com, g, node_com, pivots: as
            :func:`optimize.solve_net`; ``lengths`` are the target's pivot distances.
        mass_bounds: (m, 2) or (2,) rod mass bounds (g).
        allow_compression: let rods push (by default every rod stays in tension).
        rotations: (n, 3, 3) node bodies' orientations at the target.
        n_starts: the multi-start's starts (1: the check from the target alone).
        seed: its seed.
        refine: when the statics are not exact, refine the masses through the solver.
        tol: on target when every node lies within ``tol`` x the target's size.
        max_refine: solver evaluations the refinement may use (each also costs a shape
            Jacobian: one sparse solve per rod).
        callback: called with a line of text as the design goes (the multi-start's starts,
            the refinement's evaluations), or None.
        statics: the statics' design of these same arguments
            (:func:`optimize.net.statics.design_net_masses`) when the caller has it already
            (e.g. from a first call with ``n_starts=1``), or None: designed here.
        leave_unstable: the check's descent from the target (:func:`optimize.solve_net`'s):
            False (the design's question: is the target a stable equilibrium of these
            masses?) stops at the equilibrium near the target, stable or not; True follows an
            unstable one down to where the net would fall.

    Returns:
        NetDesign.
    """
    target = np.asarray(target_positions, float)
    if statics is None:
        statics = design_net_masses(target, edges, lengths, mass_bounds, anchored, node_masses=node_masses,
                                    com=com, allow_compression=allow_compression, g=g, node_com=node_com,
                                    pivots=pivots, rotations=rotations)
    kw = dict(node_masses=node_masses, com=com, g=g, node_com=node_com, pivots=pivots)
    size = float(np.max(np.ptp(target, axis=0)))
    masses = statics.masses
    refined = False
    info: dict = {}
    if not statics.exact and refine:
        first = solve_net(target, edges, lengths, masses, anchored, node_rotations0=rotations, **kw)
        masses, _, info = _refine(target, edges, lengths, anchored, statics, first, mass_bounds, rotations,
                                  max_refine, kw, callback)
        refined = bool(info.get("refine_improved"))
    check = solve_net(target, edges, lengths, masses, anchored, node_rotations0=rotations, n_starts=n_starts,
                      seed=seed, callback=callback, leave_unstable=leave_unstable, **kw)
    error = _error(check, target)
    on_target = bool(check.success and check.stable and error <= tol * size)
    if on_target:
        message = "On target: the designed net hangs in the target (exact equilibrium, stable)."
    elif not check.success:
        message = f"The solver found no equilibrium of the designed net: {check.message}"
    elif not check.stable:
        message = "The target is an equilibrium of the designed net, but not a stable one."
    else:
        message = (f"Off target by {error:.4g} mm ({error / size:.3g} of the size): {statics.message}")
    message += multistart_text(check)
    return NetDesign(masses=masses, statics=statics, equilibrium=check, error=error, rel_error=error / size,
                     size=size, on_target=on_target, refined=refined, message=message, info=info)


def multistart_text(check: NetResult) -> str:
    """What the multi-start of ``check`` adds to a design's message: its other stable shapes, if
    it found any (else '')."""
    if not check.alternatives:
        return ""
    return (f" The multi-start found {len(check.alternatives)} other stable shape(s)"
            + (", one lower than the design's." if check.lower else "."))


def _refine(target, edges, lengths, anchored, statics, check, mass_bounds, rotations, max_refine, kw, callback=None):
    """Bounded least squares on the node positions through the solver, from the best fit."""
    m = len(lengths)
    bounds = np.broadcast_to(np.asarray(mass_bounds, float), (m, 2))
    lo, hi = bounds[:, 0], bounds[:, 1]
    state = {"res": check, "m": statics.masses.copy()}
    net_args = dict(node_masses=kw["node_masses"], com=kw["com"], g=kw["g"], node_com=kw["node_com"],
                    pivots=kw["pivots"])

    def solve(masses):
        if np.array_equal(masses, state["m"]) and state["res"] is not None:
            return state["res"]
        state["nfev"] = state.get("nfev", 0) + 1
        if callback is not None:
            callback(f"refining the masses through the solver: evaluation {state['nfev']} of at most {max_refine}")
        start = state["res"] if state["res"] is not None and state["res"].success else None
        res = solve_net(target if start is None else start.positions, edges, lengths, masses, anchored,
                        node_rotations0=rotations if start is None else start.rotations, **kw)
        state["res"], state["m"] = res, masses.copy()
        return res

    def fun(masses):
        res = solve(masses)
        if not (res.success and res.stable):
            return np.full(target.size, 1e3 * np.max(np.ptp(target, axis=0)))
        return (res.positions - target).ravel()

    def jac(masses):
        res = solve(masses)
        net, st = Net.from_args(res.positions, edges, lengths, masses, anchored, node_rotations0=res.rotations,
                                **net_args)
        try:
            return shape_jacobian(net, st, res.tensions).reshape(-1, m)
        except FloatingPointError:
            return np.zeros((target.size, m))

    x0 = np.clip(statics.masses, lo, hi)
    # one BLAS thread: the dense trust-region steps (SVDs of hundreds of masses' columns) gain
    # little from threads, and on a busy 2-core machine OpenBLAS's spinning threads made the
    # refinement of a 200-node net ten times slower (33 s against 2.6 s, benchmarks/bench_net.py)
    with threadpool_limits(limits=1, user_api="blas"):
        ls = least_squares(fun, x0, jac=jac, bounds=(lo, hi), method="trf", x_scale=np.maximum(hi - lo, 1e-12),
                           max_nfev=max_refine, xtol=1e-14, ftol=1e-14, gtol=1e-14)
    best = solve(ls.x)
    before, after = _error(check, target), _error(best, target)
    info = {"refine_nfev": ls.nfev, "fit_error": before, "refined_error": min(before, after),
            "refine_improved": after < before}
    if after >= before:
        return statics.masses, check, info
    return ls.x, best, info
