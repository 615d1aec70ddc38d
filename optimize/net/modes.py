"""Dense, rank-revealing analysis of a net's equilibrium: self-stresses, mechanisms, curvatures.

:func:`optimize.solve_net` decides stability without a rank decision (Debreu's lemma on
sparse factors). This module answers the questions that need one, with a singular value
decomposition of the constraint Jacobian J (dense: O(nvar^3), for nets of a few hundred
nodes): how many independent states of self-stress the net has (tensions that load no
node: ``J' s = 0``, so the statics leave those tensions open), how many mechanisms (the
dimension of the tangent space, ``null J``), and the eigenvalues of the Hessian of the
Lagrangian on that tangent space (less the exact symmetries), whose smallest decides
stability. Units: curvatures in force / length along node displacements (force x length
along body rotations, in radians).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from optimize.net.deriv import assemble, evaluate, gauge_rows, hessian
from optimize.net.model import Net, NetState
from optimize.net.newton import multipliers

__all__ = ["NetModes", "net_modes"]


@dataclass
class NetModes:
    """Rank-revealing facts about a net in a configuration.

    Attributes:
        rank: numerical rank of the constraint Jacobian (m rods x nvar unknowns).
        nvar: unknowns (3 per free node, 3 per free node body).
        self_stresses: (k, m) orthonormal basis of the tension states that load no node.
        mechanisms: dimension of the tangent space of the constraints (null J).
        symmetries: exact symmetries held out (turning about a vertical line of anchors,
            a node body spinning about its pivots' line).
        curvatures: eigenvalues of the Hessian of the Lagrangian on the tangent space less
            the symmetries, ascending (force / length for displacements).
        tensions: (m,) the multipliers used (given, or the least-squares ones).
    """

    rank: int
    nvar: int
    self_stresses: np.ndarray
    mechanisms: int
    symmetries: int
    curvatures: np.ndarray
    tensions: np.ndarray

    @property
    def stable(self) -> bool:
        """Every curvature positive (beyond 1e-9 of the largest |curvature|)."""
        if self.curvatures.size == 0:
            return True
        return bool(self.curvatures[0] > 1e-9 * max(float(np.max(np.abs(self.curvatures))), 1e-300))


def net_modes(positions, edges, lengths, masses, anchored, *, tensions=None, node_masses=None, com=None,
              g: float = 9.81, node_com=None, pivots=None, rotations=None, rcond: float = 1e-10) -> NetModes:
    """Self-stresses, mechanisms and constrained curvatures of a net in a configuration.

    Args:
        positions: (n, 3) node points, e.g. ``NetResult.positions``.
        edges, lengths, masses, anchored, node_masses, com, g, node_com, pivots: as
            :func:`optimize.solve_net`.
        tensions: (m,) the multipliers, e.g. ``NetResult.tensions``; None = least squares.
        rotations: (n, 3, 3) node bodies' orientations, e.g. ``NetResult.rotations``.
        rcond: singular values of J below ``rcond`` times the largest count as zero.

    Returns:
        NetModes.
    """
    net, state = Net.from_args(positions, edges, lengths, masses, anchored, node_masses=node_masses, com=com, g=g,
                               node_com=node_com, pivots=pivots, node_rotations0=rotations)
    return modes_at(net, state, tensions, rcond=rcond)


def modes_at(net: Net, state: NetState, tensions=None, *, rcond: float = 1e-10) -> NetModes:
    """:func:`net_modes` of a validated net in a state."""
    ev = evaluate(net, state)
    lam = multipliers(net, ev) if tensions is None else np.asarray(tensions, float)
    J = ev.J.toarray()
    if net.nvar == 0:
        return NetModes(0, 0, np.eye(net.m), 0, 0, np.zeros(0), lam)
    U, sv, Vt = np.linalg.svd(J, full_matrices=True)
    tol = rcond * (sv[0] if sv.size else 1.0)
    rank = int(np.sum(sv > tol))
    stresses = U[:, rank:].T
    gauge = gauge_rows(net, state, ev)
    Z = Vt[rank:].T  # null(J)
    if gauge.size and Z.shape[1]:
        # less the symmetries: null of the gauge rows within null(J)
        _, s2, v2 = np.linalg.svd(Z[gauge], full_matrices=True)
        r2 = int(np.sum(s2 > 1e-12))
        Z = Z @ v2[r2:].T
    H = assemble(net, hessian(net, state, ev, lam)).toarray()
    curv = np.linalg.eigvalsh(Z.T @ H @ Z) if Z.shape[1] else np.zeros(0)
    return NetModes(rank=rank, nvar=net.nvar, self_stresses=stresses, mechanisms=net.nvar - rank,
                    symmetries=int(gauge.size), curvatures=curv, tensions=lam)
