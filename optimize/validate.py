"""Argument checking shared by the solvers: clear ValueErrors naming the argument."""

from __future__ import annotations

import numpy as np


def as_positive_vector(name: str, value, n: int | None = None) -> np.ndarray:
    """Return ``value`` as a 1-D float array of finite, positive entries."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be an array of numbers ({exc})") from None
    if arr.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional, got shape {arr.shape}")
    if arr.size == 0:
        raise ValueError(f"{name} must not be empty")
    if n is not None and arr.size != n:
        raise ValueError(f"{name} has {arr.size} entries but the chain has {n} rods")
    if arr.min() > 0 and arr.max() < np.inf:  # the common case, in two passes (NaN fails both)
        return arr
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        raise ValueError(f"{name}[{bad[0]}] is not finite ({arr[bad[0]]})")
    bad = np.flatnonzero(arr <= 0)
    raise ValueError(f"{name}[{bad[0]}] must be positive, got {arr[bad[0]]}")


def as_point(name: str, value) -> np.ndarray:
    """Return ``value`` as a finite point of shape (2,)."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a point (x, y) ({exc})") from None
    if arr.shape != (2,):
        raise ValueError(f"{name} must have shape (2,), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got {arr.tolist()}")
    return arr


def as_com(com, lengths: np.ndarray) -> np.ndarray:
    """Centres of mass (along, perp) per rod; None means the chord midpoint."""
    n = lengths.size
    if com is None:
        return np.column_stack([lengths / 2.0, np.zeros(n)])
    try:
        arr = np.asarray(com, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"com must be an (N, 2) array of numbers ({exc})") from None
    if arr.shape != (n, 2):
        raise ValueError(f"com must have shape ({n}, 2), got {arr.shape}")
    return all_finite("com", arr)


def as_joints(name: str, value) -> np.ndarray:
    """An (N+1, 2) array of joint positions, anchors first and last, every one finite."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be an (N+1, 2) array of joint positions ({exc})") from None
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise ValueError(f"{name} must have shape (N+1, 2), got {arr.shape}")
    if arr.shape[0] < 2:
        raise ValueError(f"{name} must have at least 2 joints (the two anchors), got {arr.shape[0]}")
    return all_finite(name, arr)


def all_finite(name: str, arr: np.ndarray) -> np.ndarray:
    """``arr`` if every entry is finite; else a ValueError naming the first that is not."""
    if np.isfinite(arr).all():
        return arr
    bad = np.argwhere(~np.isfinite(arr))
    if bad.size:
        i, j = bad[0]
        raise ValueError(f"{name}[{i}, {j}] is not finite ({arr[i, j]})")
    return arr


def as_limits(limits, n: int) -> np.ndarray:
    """Joint limits of shape (N-1, 2) in radians; None means free joints."""
    if limits is None:
        out = np.empty((max(n - 1, 0), 2))
        out[:, 0], out[:, 1] = -np.inf, np.inf
        return out
    try:
        arr = np.asarray(limits, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"limits must be an (N-1, 2) array of numbers ({exc})") from None
    if arr.shape != (n - 1, 2):
        raise ValueError(f"limits must have shape ({n - 1}, 2) for {n} rods, got {arr.shape}")
    bad = np.argwhere(np.isnan(arr))
    if bad.size:
        i, j = bad[0]
        raise ValueError(f"limits[{i}, {j}] is NaN")
    bad = np.flatnonzero(arr[:, 0] > arr[:, 1])
    if bad.size:
        j = bad[0]
        raise ValueError(
            f"limits[{j}] has lo > hi ({arr[j, 0]} > {arr[j, 1]}); give [lo, hi] in radians"
        )
    if np.any(arr[:, 0] == np.inf) or np.any(arr[:, 1] == -np.inf):
        j = np.flatnonzero((arr[:, 0] == np.inf) | (arr[:, 1] == -np.inf))[0]
        raise ValueError(f"limits[{j}] excludes every angle ({arr[j].tolist()})")
    return arr


def as_gravity(g) -> float:
    try:
        g = float(g)
    except (TypeError, ValueError):
        raise ValueError(f"g must be a number, got {g!r}") from None
    if not np.isfinite(g) or g <= 0:
        raise ValueError(f"g must be positive and finite, got {g}")
    return g


def as_clearance(value, n: int) -> np.ndarray:
    """Diametral pin clearances per pin (N+1,): a scalar for every pin, or one per pin.

    Raises:
        ValueError: not a scalar or an (N+1,) array of finite numbers >= 0.
    """
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"clearance must be a number or an array of N+1 numbers ({exc})") from None
    if arr.ndim == 0:
        arr = np.full(n + 1, float(arr))
    if arr.shape != (n + 1,):
        raise ValueError(f"clearance must be a number or have shape ({n + 1},) (one per pin, "
                         f"anchors included), got {arr.shape}")
    bad = np.flatnonzero(~np.isfinite(arr) | (arr < 0))
    if bad.size:
        raise ValueError(f"clearance[{bad[0]}] must be finite and >= 0, got {arr[bad[0]]}")
    return arr


def as_pinned(value, n: int) -> np.ndarray:
    """(N-1,) bool: joints with lo == hi that keep their pin (a two-sided stop); None: none.

    Raises:
        ValueError: not N-1 booleans.
    """
    if value is None:
        return np.zeros(max(n - 1, 0), dtype=bool)
    arr = np.asarray(value)
    if arr.shape != (max(n - 1, 0),) or arr.dtype.kind not in "bi":
        raise ValueError(f"pinned must be {max(n - 1, 0)} booleans (one per joint), got shape {arr.shape}")
    return arr.astype(bool)
