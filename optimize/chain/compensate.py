"""Compensation for pin play: the rods to print so the loaded chain hangs on its design.

Under load every pin bears on the far side of both holes it passes through
(:mod:`optimize.chain.pinplay`): pin j sits ``c_j / 2`` from each of its hole centres, along the
force ``F_j`` it carries (:func:`optimize.chain.pins.joint_forces`). So for the pins to sit on the
designed joints ``p_j``, with the design's forces (the same masses and centres of mass in the
world, hence the same reaction and joint forces, every rod loaded along the same lines of
action through the pins), rod i's holes go at::

    first  = p_i     + (c_i / 2)     u_i          u_j = F_j / |F_j|
    second = p_{i+1} - (c_{i+1} / 2) u_{i+1}

and the printed pin spacing is the distance between them, exactly::

    s_i = | l_i e^{i theta_i} - (c_i / 2) u_i - (c_{i+1} / 2) u_{i+1} |
        ~= l_i - (c_i / 2) cos a_i - (c_{i+1} / 2) cos b_i

(a_i, b_i the angles between the chord p_i -> p_{i+1} and the forces at its ends): the
"spacing = l - c" of the rule of thumb where the forces run along the chords, less where they
do not. The rod's body axis (first hole -> second) turns from the chord by
``delta_i = beta_i - theta_i``; its centre of mass, the same point of the world as designed, is
given in the hole frame; every stop, which acts between rod bodies, moves by the difference of
the two bodies' turns, and an anchor stop by its rod's turn. Then every rod carries the
design's forces along the design's lines of action and the stops the design's moments: the
chain with play hangs exactly on the design (and :func:`optimize.chain.pinplay.solve_pin_play`
finds it, to round-off). A fused joint has no pin and no play.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from optimize import validate as val
from optimize.chain.endlimits import as_end_limits
from optimize.chain.pins import joint_forces

__all__ = ["PinCompensation", "compensate_pin_play"]


@dataclass
class PinCompensation:
    """What to print so the chain with pin play hangs on its design.

    Lengths in the caller's unit (mm in rodcad), angles in radians.

    Attributes:
        spacings: (N,) each rod's printed pin spacing, hole centre to hole centre.
        com: (N, 2) each rod's centre of mass in its hole frame (origin at the first hole's
            centre, x toward the second's), as printed.
        limits: (N-1, 2) the stops as printed: bounds on the relative angle of consecutive
            rod bodies (the design's bend limits plus ``delta_{j+1} - delta_j``).
        end_limits: (2, 2) the anchor stops on the first and last bodies' angles, or None.
        holes: (N, 2, 2) the hole centres in the world when the chain hangs on its design.
        body_turn: (N,) ``delta_i``: the angle of rod i's body axis minus its chord's.
        shortening: (N,) design length minus printed spacing (``~ c`` along the forces).
        forces: (N+1, 2) the joint forces the holes are placed along.
        clearance: (N+1,) the clearances used (0 at fused joints).
    """

    spacings: np.ndarray
    com: np.ndarray
    limits: np.ndarray
    end_limits: np.ndarray | None
    holes: np.ndarray
    body_turn: np.ndarray
    shortening: np.ndarray
    forces: np.ndarray
    clearance: np.ndarray


def compensate_pin_play(points, masses, reaction, *, clearance, com=None, limits=None,
                        end_limits=None, g: float = 9.81, pinned=None) -> PinCompensation:
    """The printed pin spacings, centres of mass and stops that put the loaded pins on the design.

    Args:
        points: (N+1, 2) the designed equilibrium's joints (p_0 = A, p_N = B).
        masses: (N,) rod masses.
        reaction: (2,) the designed equilibrium's reaction (H, V) at B (it fixes every joint's
            force, :func:`optimize.chain.pins.joint_forces`).
        clearance: diametral pin clearance, a number or (N+1,) per pin (anchors included).
        com: (N, 2) the design's centres of mass (along, perp) in the pivot frame (origin
            p_i, x along p_i -> p_{i+1}); None = the chord midpoints.
        limits: (N-1, 2) the design's bend limits [lo, hi] (radians) on phi_j, or None.
        end_limits: (2, 2) the design's anchor stops on theta_0 and theta_{N-1}, or None.
        g: gravitational acceleration (the unit of the reaction).
        pinned: optional (N-1,) bool: joints with lo == hi that keep their pin (a two-sided
            stop), as for :func:`optimize.chain.pinplay.solve_pin_play`; the others are one piece.

    Returns:
        PinCompensation. Feeding its spacings, com, limits and end_limits to
        :func:`optimize.chain.pinplay.solve_pin_play` with the same clearance puts the pins on
        ``points``.

    Raises:
        ValueError: bad arguments, or a joint that carries no force (its pin's place in the
        holes is then undetermined).
    """
    p = val.as_joints("points", points)
    n = p.shape[0] - 1
    m = val.as_positive_vector("masses", masses, n)
    chord = np.diff(p, axis=0)
    lengths = np.hypot(chord[:, 0], chord[:, 1])
    if np.any(lengths <= 0):
        raise ValueError("points: two consecutive joints coincide")
    com = val.as_com(com, lengths)
    lim = val.as_limits(limits, n)
    ends = as_end_limits(end_limits)
    c = val.as_clearance(clearance, n)
    c[1:-1][(lim[:, 0] == lim[:, 1]) & ~val.as_pinned(pinned, n)] = 0.0  # a fused joint has no pin
    F = joint_forces(reaction, m, g=val.as_gravity(g))
    Fz = F[:, 0] + 1j * F[:, 1]
    size = np.abs(Fz)
    if np.any((size <= 1e-12 * np.max(size)) & (c > 0)):
        raise ValueError("a pin with play carries no force: its place in the holes is undetermined")
    u = np.where(size > 0, Fz / np.where(size > 0, size, 1.0), 0.0)
    pz = p[:, 0] + 1j * p[:, 1]
    first = pz[:-1] + 0.5 * c[:-1] * u[:-1]
    second = pz[1:] - 0.5 * c[1:] * u[1:]
    axis = second - first
    spacings = np.abs(axis)
    if np.any(spacings <= 0):
        raise ValueError("the clearance is as large as a rod: no spacing is left")
    theta = np.angle(pz[1:] - pz[:-1])
    beta = np.angle(axis)
    turn = np.angle(np.exp(1j * (beta - theta)))
    com_world = pz[:-1] + np.exp(1j * theta) * (com[:, 0] + 1j * com[:, 1])
    com_hole = (com_world - first) * np.exp(-1j * (theta + turn))
    new_lim = lim + np.diff(turn)[:, None]
    new_ends = None
    if ends is not None:
        new_ends = ends + np.array([[turn[0]], [turn[-1]]])

    def xy(z):
        return np.stack([np.real(z), np.imag(z)], axis=-1)

    return PinCompensation(
        spacings=spacings,
        com=xy(com_hole),
        limits=new_lim,
        end_limits=new_ends,
        holes=np.stack([xy(first), xy(second)], axis=1),
        body_turn=turn,
        shortening=lengths - spacings,
        forces=F,
        clearance=c,
    )
