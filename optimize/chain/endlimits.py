"""Anchor stops: bounds on the absolute angles of the first and last rods.

A fixture that stops the first rod bounds theta_0; one that stops the last rod bounds
theta_{N-1}. Each is a stop between a fixed "ground" and an end rod, and the solver treats
it like a joint stop (:mod:`optimize.chain.model`, :mod:`optimize.chain.dual`): in the active set an
anchor stop is held at its lower bound (-1), its upper bound (+1) or free (0), alongside
the joints. When it is held, the rigid group containing the end rod has a fixed angle; its
chord is then a constant that moves the anchor in the dual problem, and the fixture's
moment follows from that group's moment balance. Primal violation: a free end rod's angle
outside its bound; dual violation: a fixture moment that pulls the rod off its bound.

An end limit bounds an angle, which is only defined up to whole turns: the angle is
compared with the bound on the turn nearest it (:func:`limit_turn`; a closed heart's last
rod is one turn round from its first). This module holds those conventions (numpy only).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "ANGLE_TOL",
    "SIGN_TOL",
    "as_active",
    "as_end_limits",
    "end_bound",
    "limit_turn",
    "reach",
    "near",
    "no_end_limits",
]

#: A fixture moment may have the wrong sign by this fraction of the chain's weight x length
#: (round-off) and still count as holding.
SIGN_TOL = 1e-9

#: An angle this close (rad) to an end limit counts as on it.
ANGLE_TOL = 1e-10


def as_end_limits(end_limits) -> np.ndarray | None:
    """(2, 2) end limits in radians, or None when both ends are free pins.

    Raises:
        ValueError: not a (2, 2) array of [lo, hi] rows with lo <= hi.
    """
    if end_limits is None:
        return None
    try:
        e = np.asarray(end_limits, dtype=float).reshape(2, 2)
    except (TypeError, ValueError):
        raise ValueError("end_limits must be a (2, 2) array of [lo, hi] rows (radians)") from None
    if np.any(np.isnan(e)) or np.any(e[:, 0] > e[:, 1]):
        raise ValueError(f"end_limits rows must be [lo, hi] with lo <= hi, got {e.tolist()}")
    if np.all(np.isinf(e[:, 0])) and np.all(np.isinf(e[:, 1])):
        return None
    return e


def no_end_limits() -> np.ndarray:
    """(2, 2) end limits of two bare pins: every row (-inf, inf)."""
    return np.array([[-np.inf, np.inf], [-np.inf, np.inf]])


def limit_turn(theta: float, lim: np.ndarray) -> float:
    """The whole turns (rad, a multiple of 2 pi) between ``theta`` and the turn of an end
    limit: ``theta - limit_turn`` lies within half a turn of the middle of the limit's finite
    bounds (a one-sided limit [lo, inf) allows the half turn above lo); 0 without bounds."""
    finite = lim[np.isfinite(lim)]
    if not finite.size:
        return 0.0
    return 2 * math.pi * round((float(theta) - float(finite.mean())) / (2 * math.pi))


def near(theta: float, lim: np.ndarray) -> float:
    """``theta`` on the turn (mod 2 pi) nearest the limit's finite bounds (:func:`limit_turn`)."""
    return float(theta - limit_turn(theta, lim))


def reach(lim: np.ndarray, margin: float = 0.0) -> np.ndarray:
    """(2,) the interval an end angle may take on the limit's turn: [lo, hi] within half a
    turn of the middle of the finite bounds (:func:`near`; ``margin`` rad inside that half
    turn, where near() wraps round); (-inf, inf) without bounds."""
    finite = lim[np.isfinite(lim)]
    if not finite.size:
        return np.array([-np.inf, np.inf])
    mid = float(finite.mean())
    half = math.pi - margin
    return np.array([max(float(lim[0]), mid - half), min(float(lim[1]), mid + half)])


def end_bound(lim: np.ndarray, side: int) -> float:
    """The bound an end rod is held at: lo for side -1, hi for +1 (radians, the limit's turn)."""
    return float(lim[0] if side < 0 else lim[1])


def as_active(side: np.ndarray, n: int) -> np.ndarray:
    """The active set in chain order, anchor stops included: (N+1,) integers, entry 0 the
    anchor stop of the first rod, entries 1..N-1 the joints, entry N the last rod's.

    Args:
        side: (N-1,) joints only (both anchor stops free), or already (N+1,).
        n: the number of rods N.

    Raises:
        ValueError: another shape.
    """
    side = np.asarray(side, dtype=int)
    if side.shape == (n + 1,):
        return side
    if side.shape == (n - 1,):
        return np.concatenate([[0], side, [0]])
    raise ValueError(f"an active set has shape ({n - 1},) or ({n + 1},), got {side.shape}")
