"""A chain designed with its joint hardware hanging on it.

The pins, sleeves and bearings a joint is assembled with (:mod:`rodcad.design.hardware`)
hang on the rods: a pin rides with the fork it passes through, a sleeve or bearings with
their tongue, and a hole wider or narrower than the family's changes the knuckle's plastic
(:meth:`rodcad.design.hardware.JointHardware.attached`). All of it sits on the rods' hinge
axes, so a rod of body mass ``b`` and centre of mass ``c`` (its rod frame) with ``a0`` at its
first axis and ``a1`` at its second hangs as a rod of mass ``M = b + a0 + a1`` and centre of
mass ``(b c + a1 (l, 0)) / M``.

The mass design's unknown is ``M`` (what hangs) with that centre of mass, which depends on
``M``: :func:`design_hung` solves the fixed point. Each round re-designs the masses with the
centres of mass of the last round's masses and the bounds (and achievable intervals) moved by
each rod's hardware; the hardware is chosen again for the new forces. A rod's share of the
hardware is a few per cent of its mass, so each round shrinks the centre-of-mass mismatch by
about that factor: the loop stops when no centre of mass moves by more than
:data:`COM_TOL` mm, or after :data:`ROUNDS`.

The chain's masses and centres of mass everywhere after this step (the equilibrium, the
bands, design.json's ``rods[].mass`` and ``com``) are the hung ones; fabrication builds each
rod for ``M`` less its hardware (:func:`printed_masses`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from optimize import InverseProblem
from rodcad.catalog.model import RodType
from rodcad.design.hardware import JointHardware
from rodcad.design.masses import ChainDesign, design_buildable, design_chain

__all__ = ["COM_TOL", "ROUNDS", "HungDesign", "design_hung", "hung_com", "printed_masses"]

#: Rounds of the fixed point at most.
ROUNDS = 5

#: The fixed point is reached when no rod's centre of mass moves by more than this (mm).
COM_TOL = 1e-7


def hung_com(hung, body_com, lengths, attached) -> np.ndarray:
    """(N, 2) centres of mass (rod frame, mm) of rods hanging ``hung`` g with ``attached`` (N, 2)
    g of hardware at their first and second hinge axes and the rest at ``body_com``."""
    M = np.asarray(hung, float)
    a = np.asarray(attached, float)
    c = np.asarray(body_com, float)
    body = M - a.sum(axis=1)
    out = body[:, None] * c
    out[:, 0] += a[:, 1] * np.asarray(lengths, float)
    return out / M[:, None]


def printed_masses(hung, attached) -> np.ndarray:
    """(N,) what each rod is printed for (g): the hung mass less its hardware."""
    return np.asarray(hung, float) - np.asarray(attached, float).sum(axis=1)


@dataclass
class HungDesign:
    """The design with its hardware.

    Attributes:
        design: the mass design for the hung rods (its plan's problem has the hung centres
            of mass and bounds).
        hardware: every pin's hardware.
        attached: (N, 2) g of hardware at each rod's hinge axes.
        body_com: (N, 2) the rods' own centres of mass (rod frame, mm).
        rounds: rounds of the fixed point.
        com_change: the largest centre-of-mass change of the last round (mm).
    """

    design: ChainDesign
    hardware: JointHardware
    attached: np.ndarray
    body_com: np.ndarray
    rounds: int
    com_change: float


def design_hung(cd: ChainDesign, rods: Sequence[RodType], choose: Callable[[ChainDesign], JointHardware | None], *,
                method: str, seed: int, n_starts: int, g: float,
                intervals: Mapping[str, Sequence[tuple[float, float]]] | None = None) -> HungDesign | None:
    """The fixed point of masses, centres of mass and hardware (module docstring).

    Args:
        cd: the design of the rods alone.
        rods: its rods.
        choose: the hardware for a design (:func:`rodcad.design.asprinted.chain_hardware`),
            None where there is none to choose.
        method, seed, n_starts, g: the mass design's (:func:`rodcad.design.masses.design_chain`).
        intervals: achievable masses of the rods alone by type name (with CAD), or None.

    Returns:
        None where ``choose`` gives no hardware for ``cd``.
    """
    hw = choose(cd)
    if hw is None:
        return None
    p0 = cd.plan.problem
    body_com = np.asarray(p0.com, float)
    lengths = np.asarray(p0.lengths, float)
    base_bounds = np.asarray(p0.mass_bounds, float)
    hung = np.asarray(cd.result.masses, float)
    change = np.inf
    rounds = 0
    while rounds < ROUNDS:
        used = hw
        att = hw.attached(rods)
        a = att.sum(axis=1)
        com = hung_com(hung, body_com, lengths, att)
        problem = InverseProblem(target=p0.target, lengths=lengths, mass_bounds=base_bounds + a[:, None], com=com,
                                 limits=p0.limits, g=p0.g, end_limits=p0.end_limits)
        plan = dataclasses.replace(cd.plan, problem=problem, verified=None)
        if intervals is None:
            new = design_chain(plan, method, seed=seed, n_starts=n_starts, g=g)
        else:
            ivs = [[(lo + a[i], hi + a[i]) for lo, hi in intervals[name]] for i, name in enumerate(plan.type_names)]
            new = design_buildable(plan, method, intervals=ivs, seed=seed, n_starts=n_starts, g=g)
        rounds += 1
        hung_new = np.asarray(new.result.masses, float)
        change = float(np.abs(hung_com(hung_new, body_com, lengths, att) - com).max())
        hung, cd_new = hung_new, new
        nxt = choose(cd_new)
        same = nxt is not None and [o.name if o else None for o in nxt.options] == \
            [o.name if o else None for o in hw.options]
        hw = used if nxt is None else nxt
        if same and change <= COM_TOL:
            break
    # the hardware the last round's masses were designed with (its loads for those masses
    # where the choice came back the same)
    return HungDesign(cd_new, hw if same else used, att, body_com, rounds, change)
