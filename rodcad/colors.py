"""Colours by mass, one scale for previews and the STEP assembly: light (blue) to heavy (red)."""

from __future__ import annotations

import numpy as np

__all__ = ["mass_colors"]


def mass_colors(masses: np.ndarray, lo: float | None = None, hi: float | None = None,
                cmap: str = "coolwarm") -> np.ndarray:
    """RGBA (N, 4) per mass on one scale: light (blue) -> heavy (red)."""
    import matplotlib

    m = np.asarray(masses, dtype=float)
    lo = float(m.min()) if lo is None else lo
    hi = float(m.max()) if hi is None else hi
    if hi - lo <= 1e-12 * max(abs(hi), 1.0):
        lo, hi = lo * 0.95, hi * 1.05 + 1e-12
    return matplotlib.colormaps[cmap]((m - lo) / (hi - lo))
