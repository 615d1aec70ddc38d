"""Numerics of hanging rod chains: equilibrium, shape distance, inverse design.

numpy/scipy only; this package never imports rodcad or build123d.
"""

from optimize.distance import ShapeDistance, shape_distance
from optimize.equilibrium import MESSAGES, EquilibriumResult, solve_equilibrium
from optimize.inverse import METHODS, InverseProblem, InverseResult, design
from optimize.multistart import MultiStartResult, find_equilibria

__all__ = [
    "EquilibriumResult",
    "InverseProblem",
    "InverseResult",
    "MESSAGES",
    "METHODS",
    "MultiStartResult",
    "ShapeDistance",
    "design",
    "find_equilibria",
    "shape_distance",
    "solve_equilibrium",
]
