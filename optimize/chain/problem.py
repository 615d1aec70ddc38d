"""The inverse-design problem: a target shape, the rods that must hang in it, and
what fabrication allows (:class:`InverseProblem`).

Shared by :mod:`optimize.chain.statics` (the linear statics at the target) and
:mod:`optimize.chain.inverse` (the design methods). Lengths in the caller's length unit,
masses in its mass unit, angles in radians, ``g`` in length / time^2.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from optimize import validate as val
from optimize.chain.model import Chain, EquilibriumResult
from optimize.chain.endlimits import as_end_limits, limit_turn
from optimize.chain.equilibrium import solve_equilibrium

__all__ = ["DESIGNED_TOL", "InverseProblem"]

#: A target bend (or end angle) within this many radians of a limit rests on it (as
#: :data:`optimize.chain.statics.LIMIT_TOL`).
DESIGNED_TOL = 1e-6


@dataclass
class InverseProblem:
    """What the chain must do and what fabrication allows.

    Attributes:
        target: (N+1, 2) target joint positions; target[0] = A and target[-1] = B.
        lengths: (N,) rod lengths (pin to pin); must match the target's chords.
        mass_bounds: (N, 2) achievable [m_min, m_max] per rod.
        com: (N, 2) centres of mass (along, perp) per rod, or None for mid-chord.
        limits: (N-1, 2) bend limits in radians, or None for free joints.
        g: gravitational acceleration.
        end_limits: (2, 2) bounds on the absolute angles of the first and last rods (the
            anchor fixtures' stops), radians, or None for bare pins (see
            :func:`optimize.solve_equilibrium`).
    """

    target: np.ndarray
    lengths: np.ndarray
    mass_bounds: np.ndarray
    com: np.ndarray | None = None
    limits: np.ndarray | None = None
    g: float = 9.81
    end_limits: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.lengths = val.as_positive_vector("lengths", self.lengths)
        n = self.lengths.size
        self.target = np.asarray(self.target, dtype=float)
        if self.target.shape != (n + 1, 2) or not np.all(np.isfinite(self.target)):
            raise ValueError(f"target must be a finite ({n + 1}, 2) array of joint positions")
        chords = np.hypot(*np.diff(self.target, axis=0).T)
        bad = np.flatnonzero(np.abs(chords - self.lengths) > 1e-7 * self.lengths)
        if bad.size:
            k = bad[0]
            raise ValueError(
                f"target joints {k} and {k + 1} are {chords[k]:.6g} apart but rod {k} is "
                f"{self.lengths[k]:.6g} long: discretise the target with the rod lengths first"
            )
        bounds = np.asarray(self.mass_bounds, dtype=float)
        if bounds.shape != (n, 2):
            raise ValueError(f"mass_bounds must have shape ({n}, 2), got {bounds.shape}")
        if np.any(~np.isfinite(bounds)) or np.any(bounds[:, 0] <= 0) or np.any(bounds[:, 0] > bounds[:, 1]):
            k = int(np.flatnonzero(~np.isfinite(bounds).all(1) | (bounds[:, 0] <= 0)
                                   | (bounds[:, 0] > bounds[:, 1]))[0])
            raise ValueError(f"mass_bounds[{k}] must satisfy 0 < m_min <= m_max, got {bounds[k].tolist()}")
        self.mass_bounds = bounds
        self.com = val.as_com(self.com, self.lengths)
        self.limits = val.as_limits(self.limits, n)
        self.g = val.as_gravity(self.g)
        self.end_limits = as_end_limits(self.end_limits)

    @property
    def n(self) -> int:
        return self.lengths.size

    @property
    def anchors(self) -> tuple[np.ndarray, np.ndarray]:
        return self.target[0], self.target[-1]

    @property
    def span(self) -> float:
        return float(np.hypot(*(self.target[-1] - self.target[0])))

    @property
    def angles(self) -> np.ndarray:
        d = np.diff(self.target, axis=0)
        return np.unwrap(np.arctan2(d[:, 1], d[:, 0]))

    def designed_active(self) -> tuple[np.ndarray, np.ndarray]:
        """The active set of the designed state: (N-1,) per joint -1 where the target bend
        rests on the joint's lower limit, +1 on its upper limit, 0 free (a rigid joint: -1);
        (2,) per end rod the same for the anchor fixture's bounds on its angle."""
        phi = np.diff(self.angles)
        lo, hi = self.limits[:, 0], self.limits[:, 1]
        on_hi = np.abs(phi - hi) <= DESIGNED_TOL
        on_lo = np.abs(phi - lo) <= DESIGNED_TOL
        joints = np.where(on_lo, -1, np.where(on_hi, 1, 0)).astype(int)
        ends = np.zeros(2, dtype=int)
        if self.end_limits is not None:
            theta = self.angles
            for k, t in enumerate((theta[0], theta[-1])):
                lim = self.end_limits[k]
                t = t - limit_turn(t, lim)
                ends[k] = -1 if abs(t - lim[0]) <= DESIGNED_TOL else (1 if abs(t - lim[1]) <= DESIGNED_TOL else 0)
        return joints, ends

    def simulate(self, masses, **kw) -> EquilibriumResult:
        """The equilibrium of these masses, reached from the designed state (every joint and
        end rod on the stop the target rests on: the chain assembled in its designed shape);
        ``kw`` as :func:`optimize.solve_equilibrium` (``active0``/``end_active0`` override)."""
        a, b = self.anchors
        joints, ends = self.designed_active()
        kw.setdefault("active0", joints if self.n > 1 else None)
        kw.setdefault("end_active0", ends if self.end_limits is not None else None)
        kw.setdefault("theta0", self.angles)
        return solve_equilibrium(
            self.lengths, masses, a, b, com=self.com, limits=self.limits, g=self.g,
            end_limits=self.end_limits, **kw
        )

    def chain(self, masses) -> Chain:
        a, b = self.anchors
        return Chain.from_args(self.lengths, masses, a, b, self.com, self.limits, self.g, self.end_limits)
