"""Numerics of hanging rod chains: equilibrium, shape distance, inverse design.

numpy/scipy only; this package never imports rodcad or build123d.
"""

from optimize.equilibrium import MESSAGES, EquilibriumResult, solve_equilibrium
from optimize.multistart import MultiStartResult, find_equilibria

__all__ = [
    "EquilibriumResult",
    "MESSAGES",
    "MultiStartResult",
    "find_equilibria",
    "solve_equilibrium",
]
