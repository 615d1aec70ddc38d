"""Numerics of hanging rod chains and nets: equilibrium, shape distance, inverse design.

One package per kind of structure: :mod:`optimize.chain` (a chain of rods in a plane) and
:mod:`optimize.net` (a net of rods in 3D), which never import each other; what both use sits
here at the top: the box-constrained QP (:mod:`optimize.boxqp`), the shape distance
(:mod:`optimize.distance`) and the input checks (:mod:`optimize.validate`). This module
exports the public entry points of both.

numpy/scipy only; this package never imports rodcad or build123d.
"""

from optimize.chain.compensate import PinCompensation, compensate_pin_play
from optimize.chain.equilibrium import MESSAGES, EquilibriumResult, solve_equilibrium
from optimize.chain.friction import FrictionBand, friction_band, friction_capacity
from optimize.chain.inverse import METHODS, InverseProblem, InverseResult, design
from optimize.chain.multistart import MultiStartResult, find_equilibria
from optimize.chain.pinplay import solve_pin_play
from optimize.chain.pins import PinPlayResult, joint_forces
from optimize.chain.tolerance import MassBand, mass_band
from optimize.distance import ShapeDistance, shape_distance
from optimize.net.design import NetDesign, design_net, shape_jacobian
from optimize.net.modes import NetModes, net_modes
from optimize.net.solve import NET_MESSAGES, NetResult, more_starts, pivots_by_node, pivots_from_nodes, solve_net
from optimize.net.statics import NetMassDesign, NetStatics, design_net_masses, net_statics, node_mass_needs

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
    "node_mass_needs",
    "pivots_by_node",
    "pivots_from_nodes",
    "friction_band",
    "friction_capacity",
    "joint_forces",
    "mass_band",
    "more_starts",
    "shape_distance",
    "shape_jacobian",
    "solve_equilibrium",
    "solve_net",
    "solve_pin_play",
]
