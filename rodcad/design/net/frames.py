"""Where a net's rods and hubs sit in the world: 4 x 4 placements from a rotation and an origin,
and a rod's frame from its two pivots (x along the chord, y horizontal, z the chord's upward
side: a bent rod, bowing toward -z, hangs so). assembly.step, the 3D view and the as-built
check place the solids by them; no CAD kernel is needed to compute them.
"""

from __future__ import annotations

import numpy as np

__all__ = ["place", "rod_frame", "rod_matrix"]


def place(R: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """4 x 4 of a rotation R (3 x 3) and a translation (mm)."""
    m = np.eye(4)
    m[:3, :3] = R
    m[:3, 3] = origin
    return m


def rod_matrix(p0: np.ndarray, p1: np.ndarray) -> np.ndarray:
    """4 x 4: the rod frame (:func:`rod_frame`) placed at its first pivot ``p0``, as
    assembly.step and the 3D view place a net's rods."""
    return place(rod_frame(p0, p1), p0)


def rod_frame(p0: np.ndarray, p1: np.ndarray) -> np.ndarray:
    """The rod frame in the world: x along the chord, y horizontal, z = x cross y the upward
    side of the chord (a bent rod, bowing toward -z, hangs so)."""
    x = (p1 - p0) / np.linalg.norm(p1 - p0)
    y = np.cross([0.0, 0.0, 1.0], x)
    if np.linalg.norm(y) < 1e-9:
        y = np.cross([0.0, 1.0, 0.0], x)
    y /= np.linalg.norm(y)
    return np.column_stack([x, y, np.cross(x, y)])
