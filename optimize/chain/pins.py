"""Pins and what they carry: the force at every pin of a hanging chain, and the result type
of the chain whose pins sit in their holes with play (:mod:`optimize.chain.pinplay`).

Conventions (``shared/design/physics.md``): rods ``0..N-1``, pins (joints) ``0..N`` with pin 0
at anchor A and pin N at anchor B, gravity along -y, lengths in the caller's unit, forces in
mass x the unit of ``g``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["PLAY_MESSAGES", "PinPlayResult", "joint_forces"]

#: Status codes of :func:`solve_pin_play`.
PLAY_MESSAGES = {
    0: "Equilibrium with pin play found: closure exact, stops respected, KKT conditions satisfied.",
    1: "Active-set iteration limit reached before the KKT conditions held.",
    2: "The fixed point over the chain without play did not converge.",
    3: "The active-set exchange found no equilibrium (method 'dual': no fallback).",
}


@dataclass
class PinPlayResult:
    """The equilibrium of a chain whose pins sit in their holes with play.

    Lengths in the caller's unit, angles in radians, forces in mass x the unit of ``g``,
    moments in force x length.

    Attributes:
        points: (N+1, 2) the pins' centres (the loaded pivots); ``points[0] = A``,
            ``points[-1] = B``.
        holes: (N, 2, 2) each rod's hole centres, ``holes[i, 0]`` the first, ``holes[i, 1]``
            the second, ``spacing_i`` apart.
        angles: (N,) each rod body's angle (first hole -> second hole) from +x.
        com: (N, 2) each rod's centre of mass in the world.
        forces: (N+1, 2) the force at each pin that the part of the chain right of it exerts
            on the part left of it; each pin bears along it, its holes ``c_j`` apart along it.
        reaction, reaction_a: (2,) support reactions at B and at A.
        moments: (N-1,) moment carried by each stop between rod bodies (positive pushes the
            relative angle up); 0 at free joints.
        active: (N-1,) -1 where the bodies rest on lo, +1 on hi, 0 free.
        end_moments: (2,) moments of the anchor stops on the first and last bodies'
            angles (positive pushes the angle up); end_active: (2,) their sides.
        kkt_residual: relative KKT residual (closure with the links / total length, moments
            at free joints and free ends / (g x total mass x total length), stop violations in
            rad, wrong-sign stop moments).
        closure_error: distance from the last rod's second hole, plus the last gap, to B.
        energy: potential energy g sum m_i y(com_i).
        stable: second order: the Lagrangian's Hessian is positive definite on the tangent
            space of the closure and the binding stops (rod bodies and links turning).
        success, status, message: outcome (:data:`PLAY_MESSAGES`).
        nit: active-set iterations; nnewton: dual Newton iterations.
        info: ``path`` ("exchange" or "fixed-point"), ``clearance`` (N+1,) as used.
    """

    points: np.ndarray
    holes: np.ndarray
    angles: np.ndarray
    com: np.ndarray
    forces: np.ndarray
    reaction: np.ndarray
    reaction_a: np.ndarray
    moments: np.ndarray
    active: np.ndarray
    end_moments: np.ndarray
    end_active: np.ndarray
    kkt_residual: float
    closure_error: float
    energy: float
    stable: bool
    success: bool
    status: int
    message: str
    nit: int = 0
    nnewton: int = 0
    info: dict = field(default_factory=dict)

    @property
    def pivot_angles(self) -> np.ndarray:
        """(N,) chord angles of the loaded pivots p_i -> p_{i+1}, radians."""
        d = np.diff(self.points, axis=0)
        return np.unwrap(np.arctan2(d[:, 1], d[:, 0]))

    @property
    def bends(self) -> np.ndarray:
        """(N-1,) relative angles of consecutive rod bodies, radians."""
        return np.diff(self.angles)


def joint_forces(reaction, masses, *, g: float = 9.81) -> np.ndarray:
    """The force at every pin, (N+1, 2): what the part of the chain right of pin j exerts on
    the part left of it, ``F_j = (H, V - g S_j)`` with ``S_j`` the mass of rods j..N-1 and
    (H, V) the reaction at B. Pin 0 is A (``-F_0`` is A's reaction), pin N is B.

    Args:
        reaction: (2,) the support reaction (H, V) at B (force: mass x the unit of ``g``).
        masses: (N,) rod masses. g: gravitational acceleration, along -y.
    """
    m = np.asarray(masses, dtype=float).reshape(-1)
    after = np.concatenate([np.cumsum(m[::-1])[::-1], [0.0]])
    h, v = np.asarray(reaction, dtype=float).reshape(2)
    return np.column_stack([np.full(after.size, h), v - g * after])
