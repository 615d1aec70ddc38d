"""Numerics of hanging rod chains and nets: equilibrium, shape distance, inverse design.

numpy/scipy only; this package never imports rodcad or build123d.
"""

from optimize.compensate import PinCompensation, compensate_pin_play
from optimize.distance import ShapeDistance, shape_distance
from optimize.friction import FrictionBand, friction_band, friction_capacity
from optimize.equilibrium import MESSAGES, EquilibriumResult, solve_equilibrium
from optimize.inverse import METHODS, InverseProblem, InverseResult, design
from optimize.multistart import MultiStartResult, find_equilibria
from optimize.net import NET_MESSAGES, NetResult, pivots_by_node, pivots_from_nodes, solve_net
from optimize.netdesign import NetDesign, design_net, shape_jacobian
from optimize.netmodes import NetModes, net_modes
from optimize.netstatics import NetMassDesign, NetStatics, design_net_masses, net_statics
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
    "NET_MESSAGES",
    "NetDesign",
    "NetMassDesign",
    "NetModes",
    "NetResult",
    "NetStatics",
    "PinCompensation",
    "PinPlayResult",
    "ShapeDistance",
    "compensate_pin_play",
    "design",
    "design_net",
    "design_net_masses",
    "find_equilibria",
    "net_modes",
    "net_statics",
    "pivots_by_node",
    "pivots_from_nodes",
    "friction_band",
    "friction_capacity",
    "joint_forces",
    "mass_band",
    "shape_distance",
    "shape_jacobian",
    "solve_equilibrium",
    "solve_net",
    "solve_pin_play",
]
