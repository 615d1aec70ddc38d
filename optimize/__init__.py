"""Numerics of hanging rod chains: equilibrium, shape distance, inverse design.

numpy/scipy only; this package never imports rodcad or build123d.
"""

from optimize.compensate import PinCompensation, compensate_pin_play
from optimize.distance import ShapeDistance, shape_distance
from optimize.friction import FrictionBand, friction_band, friction_capacity
from optimize.equilibrium import MESSAGES, EquilibriumResult, solve_equilibrium
from optimize.inverse import METHODS, InverseProblem, InverseResult, design
from optimize.multistart import MultiStartResult, find_equilibria
from optimize.pinplay import solve_pin_play
from optimize.pins import PinPlayResult, joint_forces
from optimize.tolerance import MassBand, mass_band

__all__ = [
    "EquilibriumResult",
    "FrictionBand",
    "InverseProblem",
    "InverseResult",
    "MESSAGES",
    "METHODS",
    "MassBand",
    "MultiStartResult",
    "PinCompensation",
    "PinPlayResult",
    "ShapeDistance",
    "compensate_pin_play",
    "design",
    "find_equilibria",
    "friction_band",
    "friction_capacity",
    "joint_forces",
    "mass_band",
    "shape_distance",
    "solve_equilibrium",
    "solve_pin_play",
]
