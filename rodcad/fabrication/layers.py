"""The print's layers as numbers: where each layer's top is, which layer bridges a socket's
roof, and so where the print pauses for it.

A slicer (PrusaSlicer) prints layer k (0 = the first) from ``top(k - 1)`` to ``top(k)``
and slices it at its mid-height. A socket whose flat roof is ``roof`` mm above the bed is
open in every layer sliced below the roof and bridged in the first layer sliced at or
above it; the print pauses before that layer, at its top (``print_z``): the smallest
layer top z with ``z - h/2 >= roof``. A roof exactly on a layer top sits midway between
two slicing planes, the position least sensitive to a mesh's or a slicer's round-off.

Units: mm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["Z_TOL", "LayerGrid"]

#: Heights closer than this (mm) are one height.
Z_TOL = 1e-6


@dataclass(frozen=True)
class LayerGrid:
    """The layer tops of a print.

    Attributes:
        layer_height: mm, every layer but the first.
        first_layer: the first layer's height (mm).
    """

    layer_height: float = 0.2
    first_layer: float = 0.2

    def __post_init__(self) -> None:
        if not (self.layer_height > 0 and self.first_layer > 0):
            raise ValueError(f"layer heights must be > 0 mm, not {self.layer_height} and {self.first_layer}")

    def top(self, k: int) -> float:
        """Top (print_z) of layer k (0 = the first layer), mm."""
        return round(self.first_layer + k * self.layer_height, 6)

    def bridging_layer(self, roof: float) -> int:
        """The index of the first layer sliced (at mid-height) at or above ``roof`` (mm): the
        layer that bridges a socket whose roof is there."""
        h1, h = self.first_layer, self.layer_height
        if h1 / 2 >= roof - Z_TOL:
            return 0
        return max(1, math.ceil((roof - Z_TOL - h1 + h / 2) / h - 1e-9))

    def pause_z(self, roof: float) -> float:
        """The print_z to pause at for a socket whose roof is ``roof`` mm above the bed: the top
        of the layer that bridges it (the pause comes before that layer is printed)."""
        return self.top(self.bridging_layer(roof))
