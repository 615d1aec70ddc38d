"""Inverse design of a hanging net: masses from the statics, checked by the exact solver.

:func:`design_net` runs the whole numerical design of a net (no CAD):

1. :func:`optimize.net.statics.design_net_masses`: masses within bounds that balance the
   target exactly (LP, then the central QP), or the best fit within them and why not;
2. the exact equilibrium from the target (:func:`optimize.solve_net`): an exact design must
   come back to the target to round-off, stable;
3. when the statics are not exact and ``refine`` is set, the masses refined through the
   forward solver toward the least *largest* distance of the fit (its nodes and its rods'
   pivots: what the verdict measures), by sequential linear programming on the equilibrium's
   derivatives with respect to the masses (implicit differentiation of its KKT system), from
   the best fit (:mod:`optimize.net.refine`);
4. the multi-start for other stable shapes (``alternatives``; ``lower`` when one hangs
   lower than the design's).

Units: mm, g, forces in g x the unit of ``g``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from threadpoolctl import threadpool_limits

from optimize.net.model import Net, NetState
from optimize.net.refine import NetFit, Swing, equilibrium_derivatives, fit_distances, net_fit, refine_masses
from optimize.net.solve import NetResult, solve_net
from optimize.net.statics import NetMassDesign, design_net_masses

__all__ = ["NetDesign", "design_net", "multistart_text", "shape_jacobian"]


def shape_jacobian(net: Net, state: NetState, tensions: np.ndarray) -> np.ndarray:
    """d(node points) / d(rod masses) at an equilibrium, shape (n, 3, m) (mm per g): the node
    points' half of :func:`optimize.net.refine.equilibrium_derivatives` (implicit
    differentiation of the KKT system ``grad U + J' lam = 0, c = 0``). Anchored nodes do not
    move. Holds while the equilibrium stays stable.

    Args:
        net, state: the validated net and its equilibrium configuration.
        tensions: (m,) the equilibrium's multipliers (``NetResult.tensions``).
    """
    return equilibrium_derivatives(net, state, tensions)[0]


@dataclass
class NetDesign:
    """The numerical design of a net and the solver's verdict on it.

    Attributes:
        masses: (m,) the designed rod masses (g).
        statics: the statics design at the target (exact or best fit, and why).
        equilibrium: the exact equilibrium of the designed net from the target, with the
            multi-start's other stable shapes in ``equilibrium.alternatives``.
        error: largest distance of what the fit measures from where it was drawn (mm: the
            nodes, and the rods' pivots of node bodies); rel_error: over ``size``.
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


def _error(res: NetResult, fit: NetFit) -> float:
    if not res.success:
        return np.inf
    return float(np.max(fit_distances(res, fit)))


def design_net(target_positions, edges, lengths, mass_bounds, anchored, *, node_masses=None, com=None,
               allow_compression: bool | np.ndarray = False, g: float = 9.81, node_com=None, pivots=None,
               rotations=None, n_starts: int = 8, seed: int = 0, refine: bool = True, tol: float = 1e-6,
               max_refine: int = 10, callback=None, statics: NetMassDesign | None = None,
               leave_unstable: bool = False, fit_nodes=None, fit_points=None, fit_ends=None,
               swing_limits=None) -> NetDesign:
    """Masses for a net to hang in its target, and the exact solver's check of them.

    Args:
        target_positions: (n, 3) target node points (mm), anchored nodes where they hang.
        edges, lengths, anchored, node_masses, com, g, node_com, pivots: as
            :func:`optimize.solve_net`; ``lengths`` are the target's pivot distances.
        mass_bounds: (m, 2) or (2,) rod mass bounds (g).
        allow_compression: let rods push: True every rod, or an (m,) mask of those that may (by
            default every rod stays in tension).
        rotations: (n, 3, 3) node bodies' orientations at the target.
        n_starts: the multi-start's starts (1: the check from the target alone).
        seed: its seed.
        refine: when the statics are not exact, refine the masses through the solver.
        tol: on target when every point the fit measures lies within ``tol`` x the target's size.
        max_refine: solver evaluations the refinement may use, each from the target (a kept
            step also costs the equilibrium's derivatives: one sparse solve per rod).
        callback: called with a line of text as the design goes (the multi-start's starts,
            the refinement's evaluations), or None.
        statics: the statics' design of these same arguments
            (:func:`optimize.net.statics.design_net_masses`) when the caller has it already
            (e.g. from a first call with ``n_starts=1``), or None: designed here.
        leave_unstable: the check's descent from the target (:func:`optimize.solve_net`'s):
            False (the design's question: is the target a stable equilibrium of these
            masses?) stops at the equilibrium near the target, stable or not; True follows an
            unstable one down to where the net would fall.
        fit_nodes, fit_points: (k,) nodes and (k, 3) the points the fit measures them against
            (None: every node against its target point).
        fit_ends: (m, 2, 3) the rods' pivots the fit measures theirs against (None: where
            ``pivots`` put them at the target; point nodes: none).
        swing_limits: (m, 2) how far each rod may turn from its socket's axis (the direction of
            its pivot, ``pivots``) at each end (deg), which the refinement keeps to (None: no
            limit).

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
    fit = net_fit(target, edges, pivots, rotations, fit_nodes, fit_points, fit_ends)
    masses = statics.masses
    refined = False
    info: dict = {}
    found = None
    if not statics.exact and refine:
        m = len(lengths)
        bounds = np.broadcast_to(np.asarray(mass_bounds, float), (m, 2))

        def solve(x):  # (from the target, as the verdict below solves)
            return solve_net(target, edges, lengths, x, anchored, node_rotations0=rotations,
                             leave_unstable=leave_unstable, **kw)

        def net_of(res, x):
            return Net.from_args(res.positions, edges, lengths, x, anchored, node_rotations0=res.rotations, **kw)

        # one BLAS thread: the derivatives' dense solves gain little from threads, and on a busy
        # 2-core machine OpenBLAS's spinning threads made a 200-node net's refinement ten times
        # slower (benchmarks/bench_net.py)
        with threadpool_limits(limits=1, user_api="blas"):
            best, found, info = refine_masses(solve, net_of, statics.masses, bounds, fit, edges, max_refine,
                                              callback, _swing(pivots, swing_limits))
        refined = bool(info.get("refine_improved"))
        if refined:
            masses = best
    if found is not None and n_starts <= 1 and np.array_equal(best, masses):
        check = found  # (the refinement's solve from the target is the verdict's)
    else:
        check = solve_net(target, edges, lengths, masses, anchored, node_rotations0=rotations, n_starts=n_starts,
                          seed=seed, callback=callback, leave_unstable=leave_unstable, **kw)
    error = _error(check, fit)
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


def _swing(pivots, swing_limits) -> Swing | None:
    if pivots is None or swing_limits is None:
        return None
    p = np.asarray(pivots, float)
    limits = np.radians(np.asarray(swing_limits, float))
    return Swing(p, np.where(np.any(p != 0, axis=2), limits, np.inf))


def multistart_text(check: NetResult) -> str:
    """What the multi-start of ``check`` adds to a design's message: its other stable shapes, if
    it found any (else '')."""
    if not check.alternatives:
        return ""
    return (f" The multi-start found {len(check.alternatives)} other stable shape(s)"
            + (", one lower than the design's." if check.lower else "."))
