"""The chain as printed: pins in their holes, pin friction and the rods' mass tolerance.

A printed chain is not the model: every pin sits in holes ``pin_clearance`` wider than itself,
every pin has friction, and every rod's plastic is a few per cent off. This module turns a
designed chain (numbers in mm, g, radians) into what a ruler will measure:

* :func:`hole_plan`: where to put each rod's pin holes so that, loaded, every pin bears on
  the far side of its holes exactly at the designed joint (:func:`optimize.compensate_pin_play`).
  Each rod's body, stops and centre of mass stay where the design has them in its rod frame
  (origin on the first hinge axis, x toward the second): only the holes move, each by at
  most half the clearance, along the force its pin carries. The printed pin spacing is the
  distance between the two holes (about the design length minus the clearance).
* :func:`as_printed`: the chain with every pin bearing in its holes
  (:func:`optimize.solve_pin_play`) for given holes, masses and centres of mass (the as-built
  solids', or the design's), its error against the target, and the same chain with its holes
  on the axes (what the compensation buys). The bands are computed on the designed
  equilibrium (linearised; the play moves it by a fraction of a per cent):
  :func:`optimize.friction_band` with the catalog's ``joint.friction`` and the pins' radii,
  :func:`optimize.mass_band` with ``print.mass_tolerance``.
* :func:`sensitive_joints`, :func:`loose_joints`: the joints whose band exceeds what the
  tolerance allows: where a robust design (design option ``robust``) holds the bend both ways.

Frames: a rod's *rod frame* is its solid's (hinge axes at (0, 0) and (length, 0)); its *hole
frame* has its origin at the first hole's centre and x toward the second's (design.json's
``rods[].com`` where the holes moved, contract.md "As printed").
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from optimize import (
    FrictionBand,
    MassBand,
    PinPlayResult,
    compensate_pin_play,
    friction_band,
    joint_forces,
    mass_band,
    shape_distance,
    solve_pin_play,
)
from optimize.distance import ShapeDistance
from rodcad.catalog.model import RodType
from rodcad.design.fit import DEFAULT_TOLERANCE
from rodcad.design.hardware import (FRICTION_SHARE, JointHardware, best_capacity, choose_hardware, newtons,
                                    solver_moment)
from rodcad.design.shell import curve_size

__all__ = ["anchor_holes", "as_printed", "AsPrinted", "chain_hardware", "DesignedChain", "fused_joints",
           "hole_frame", "hole_plan", "HolePlan", "joint_bands", "loose_joints", "narrower",
           "pins_of", "plan_holes", "plan_of", "printed_chain", "Robust", "robust_option",
           "sensitive_joints", "too_wide"]

#: Draws of the mass band (about 1 % sampling error on its 95th percentile).
MASS_SAMPLES = 20000


@dataclass
class HolePlan:
    """Where every rod's pin holes go (mm, rod frame).

    Attributes:
        clearance: (N+1,) diametral clearance of each pin (0 at fused joints: no pin).
        offsets: (N, 2, 2) each hole's centre minus its hinge axis, [rod, end, (x, y)].
        compensated: whether the holes were moved (False: on the axes).
    """

    clearance: np.ndarray
    offsets: np.ndarray
    compensated: bool

    @property
    def holes(self) -> list[tuple[tuple[float, float], tuple[float, float]]]:
        """Per rod, the offsets as nested tuples (:func:`rodcad.cad.solids.build_rod`)."""
        return [((float(o[0, 0]), float(o[0, 1])), (float(o[1, 0]), float(o[1, 1]))) for o in self.offsets]


@dataclass
class AsPrinted:
    """The chain as printed (mm, g, radians; forces in g mm / s^2 as the solver's).

    Attributes:
        plan: the holes printed.
        spacings: (N,) printed pin spacing, hole centre to hole centre.
        masses: (N,) the masses hung (as built, or as designed).
        com: (N, 2) centres of mass in the hole frame.
        result: the chain with every pin bearing in its holes.
        distance: its pins against the target joints.
        uncompensated: the same chain with its holes on the hinge axes, against the target
            (None when the plan is not compensated, or that chain has no equilibrium).
        friction: the friction band (None where it could not be computed: say why in
            ``notes``). mu: the friction coefficient used.
        mass_band: the 95 % mass band; mass_tolerance: the relative tolerance used.
        notes: what could not be computed.
        hardware: the friction band is the joint hardware's (per pin), not ``mu``'s.
    """

    plan: HolePlan
    spacings: np.ndarray
    masses: np.ndarray
    com: np.ndarray
    result: PinPlayResult
    distance: ShapeDistance
    uncompensated: ShapeDistance | None
    friction: FrictionBand | None
    mu: float
    mass_band: MassBand | None
    mass_tolerance: float
    notes: list[str]
    hardware: bool = False


def pins_of(rods: Sequence[RodType]) -> tuple[np.ndarray, np.ndarray, float]:
    """Per pin (N+1, the anchors' included; pin j is rod j's first, pin N the last rod's
    second): the diametral clearance and the pin radius (mm) of the catalog's joint, and the
    friction coefficient (the largest of the rods')."""
    hinges = [r.geometry.hinge for r in rods] + [rods[-1].geometry.hinge]
    return (np.array([h.pin_clearance for h in hinges], float), np.array([h.pin_diameter / 2 for h in hinges], float),
            float(max(r.friction for r in rods)))


def anchor_holes(plan: HolePlan, points) -> np.ndarray:
    """(2, 2) where the anchor fixture's pin holes go, minus A and B (mm): opposite the end
    rods' holes, so the loaded anchor pins sit on A and B as the chain with play assumes."""
    p = np.asarray(points, float)
    out = np.zeros((2, 2))
    for k, (rod, end, a, b) in enumerate(((0, 0, p[0], p[1]), (-1, 1, p[-2], p[-1]))):
        t = np.arctan2(b[1] - a[1], b[0] - a[0])
        dx, dy = plan.offsets[rod, end]
        out[k] = -np.array([dx * np.cos(t) - dy * np.sin(t), dx * np.sin(t) + dy * np.cos(t)])
    return out


def _limits(limits, n: int) -> np.ndarray:
    return np.tile([-np.inf, np.inf], (max(n - 1, 0), 1)) if limits is None else np.asarray(limits, float)


def fused_joints(runs: Sequence[Sequence[int]], n: int) -> np.ndarray:
    """(N-1,) bool: the joints inside fused runs of rods (first, last), printed as one piece."""
    out = np.zeros(max(n - 1, 0), dtype=bool)
    for a, b in runs:
        out[int(a):int(b)] = True
    return out


def _pins(clearance, fused, limits: np.ndarray, n: int) -> np.ndarray:
    """(N+1,) clearance per pin, 0 at fused joints (one printed piece: no pin); ``fused`` None:
    every joint whose limits are lo == hi."""
    c = np.broadcast_to(np.asarray(clearance, float), (n + 1,)).copy()
    if n > 1:
        c[1:-1][limits[:, 0] == limits[:, 1] if fused is None else np.asarray(fused, bool)] = 0.0
    return c


def _pinned(plan: HolePlan, limits: np.ndarray | None) -> np.ndarray | None:
    """Joints held both ways (lo == hi) that keep a pin: two-sided stops, not fused pieces."""
    if limits is None or len(limits) == 0:
        return None
    return (limits[:, 0] == limits[:, 1]) & (plan.clearance[1:-1] > 0)


def plan_of(offsets, clearance, limits=None, fused=None) -> HolePlan:
    """The holes a build printed (design.json ``rods[].holes_mm``, (N, 2, 2) mm) with each pin's
    clearance ((N+1,) or a number; 0 at the ``fused`` joints, (N-1,) bool, default those whose
    limits are lo == hi)."""
    off = np.asarray(offsets, float).reshape(-1, 2, 2)
    n = off.shape[0]
    return HolePlan(_pins(clearance, fused, _limits(limits, n), n), off, bool(np.any(off != 0)))


def hole_plan(points, masses, reaction, *, clearance, com, limits=None, end_limits=None, g: float = 9.81,
              compensate: bool = True, fused=None) -> HolePlan:
    """The pin holes that put the loaded pins on the designed joints.

    Args:
        points: (N+1, 2) the designed equilibrium's joints (mm).
        masses: (N,) the design's masses (g).
        reaction: (2,) that equilibrium's reaction at B (the solver's units, with ``g``).
        clearance: diametral pin clearance (mm), a number or (N+1,) per pin.
        com: (N, 2) centres of mass in the rod frame (mm).
        limits, end_limits: the design's stops (radians), as for :func:`optimize.solve_equilibrium`.
        g: the gravity the reaction was solved with.
        compensate: False: every hole on its hinge axis.
        fused: (N-1,) bool, the joints printed as one piece (no pin; :func:`fused_joints`);
            None: every joint with lo == hi. A joint with lo == hi that is not fused is a
            two-sided stop: it keeps its pin and its play.
    """
    p = np.asarray(points, float)
    n = p.shape[0] - 1
    lim = _limits(limits, n)
    c = _pins(clearance, fused, lim, n)
    if not compensate or not np.any(c > 0) or not np.all(np.isfinite(reaction)):
        return HolePlan(c, np.zeros((n, 2, 2)), False)
    comp = compensate_pin_play(p, masses, reaction, clearance=c, com=com, limits=lim if n > 1 else None,
                               end_limits=end_limits, g=g, pinned=(lim[:, 0] == lim[:, 1]) & (c[1:-1] > 0))
    chord = np.diff(p, axis=0)
    theta = np.arctan2(chord[:, 1], chord[:, 0])
    rot = np.stack([np.stack([np.cos(theta), np.sin(theta)], -1), np.stack([-np.sin(theta), np.cos(theta)], -1)], 1)
    ends = np.stack([p[:-1], p[1:]], axis=1)  # (N, 2, 2): the hinge axes in the world
    offsets = np.einsum("nij,nkj->nki", rot, comp.holes - ends)
    return HolePlan(c, offsets, True)


def hole_frame(lengths, com, offsets, limits=None, end_limits=None):
    """Spacings, centres of mass, stops and anchor stops in the rods' hole frames.

    Args:
        lengths: (N,) hinge axis to hinge axis (mm). com: (N, 2) rod frame (mm).
        offsets: (N, 2, 2) :attr:`HolePlan.offsets`.
        limits, end_limits: stops between the rod bodies (radians), rod frames.

    Returns:
        (spacings (N,), com (N, 2), limits (N-1, 2) or None, end_limits (2, 2) or None,
        turn (N,)): ``turn`` is each hole axis's angle from the rod frame's x axis.
    """
    l = np.asarray(lengths, float)
    h0 = np.asarray(offsets, float)[:, 0]
    h1 = np.asarray(offsets, float)[:, 1] + np.column_stack([l, np.zeros_like(l)])
    axis = h1 - h0
    spacings = np.hypot(axis[:, 0], axis[:, 1])
    turn = np.arctan2(axis[:, 1], axis[:, 0])
    rel = np.asarray(com, float) - h0
    c, s = np.cos(turn), np.sin(turn)
    com_h = np.column_stack([c * rel[:, 0] + s * rel[:, 1], -s * rel[:, 0] + c * rel[:, 1]])
    lim = None if limits is None else np.asarray(limits, float) + np.diff(turn)[:, None]
    ends = None if end_limits is None else np.asarray(end_limits, float) + np.array([[turn[0]], [turn[-1]]])
    return spacings, com_h, lim, ends, turn


def _solve(lengths, masses, com, offsets, clearance, anchors, limits, end_limits, g, pinned=None, theta0=None):
    spacings, com_h, lim, ends, _ = hole_frame(lengths, com, offsets, limits, end_limits)
    a, b = np.asarray(anchors, float)
    res = solve_pin_play(spacings, masses, a, b, clearance=clearance, com=com_h,
                         limits=lim if len(spacings) > 1 else None, end_limits=ends, g=g,
                         pinned=pinned if len(spacings) > 1 else None, theta0=theta0)
    return spacings, com_h, res


def as_printed(*, lengths, masses, com, plan: HolePlan, anchors, target, limits=None, end_limits=None,
               design_equilibrium=None, design_masses=None, design_com=None, pin_radius=None,
               mu: float = 0.3, mass_tolerance: float = 0.03, g: float = 9.81, seed: int = 0,
               capacity=None) -> AsPrinted:
    """The chain as printed, and its friction and mass bands.

    Args:
        lengths: (N,) hinge axis to hinge axis (mm).
        masses, com: (N,) g and (N, 2) mm rod frame: what hangs (the as-built solids', or the
            design's).
        plan: the holes (:func:`hole_plan`).
        anchors: (2, 2) A and B (mm). target: (N+1, 2) the target joints (mm).
        limits, end_limits: the design's stops (radians, rod frames).
        design_equilibrium: the designed chain's :class:`optimize.EquilibriumResult` (for
            the bands), with ``design_masses`` and ``design_com`` (default: masses, com).
        pin_radius: (N+1,) or a number, mm: where friction acts (the pins' radii).
        mu: friction coefficient; mass_tolerance: relative, 95 %.
        capacity: (N+1,) the friction moment each pin holds (the solver's force x mm: the
            chosen hardware's), instead of ``mu`` and ``pin_radius``.
        g: gravity in the solver's units; seed: the mass band's draws.

    Raises:
        ValueError: the chain with its play has no configuration (anchors out of reach).
    """
    n = len(lengths)
    lim = None if limits is None or n < 2 else np.asarray(limits, float)
    pinned = _pinned(plan, lim)
    eq = design_equilibrium
    theta0 = eq.angles if eq is not None and eq.success else None  # hung in the designed shape
    spacings, com_h, res = _solve(lengths, masses, com, plan.offsets, plan.clearance, anchors, lim, end_limits, g,
                                  pinned, theta0)
    tgt = np.asarray(target, float)
    unc = None
    if plan.compensated:
        try:
            unc = shape_distance(tgt, _solve(lengths, masses, com, np.zeros_like(plan.offsets), plan.clearance,
                                             anchors, lim, end_limits, g, pinned, theta0)[2].points)
        except ValueError:
            unc = None
    notes: list[str] = []
    fb = mb = None
    if eq is not None and eq.success:
        dm = np.asarray(masses if design_masses is None else design_masses, float)
        dc = np.asarray(com if design_com is None else design_com, float)
        a, b = np.asarray(anchors, float)
        args = dict(com=dc, limits=lim, end_limits=end_limits, g=g, result=eq)
        try:
            fb = (friction_band(lengths, dm, a, b, mu=mu, pin_radius=pin_radius, **args) if capacity is None
                  else friction_band(lengths, dm, a, b, capacity=capacity, **args))
        except (ValueError, np.linalg.LinAlgError) as err:
            notes.append(f"no friction band: {err}")
        try:
            mb = mass_band(lengths, dm, a, b, tol=mass_tolerance, n_samples=MASS_SAMPLES, seed=seed, **args)
        except (ValueError, np.linalg.LinAlgError) as err:
            notes.append(f"no mass band: {err}")
    return AsPrinted(plan, spacings, np.asarray(masses, float), com_h, res, shape_distance(tgt, res.points), unc,
                     fb, mu, mb, mass_tolerance, notes, capacity is not None)


def sensitive_joints(band: Sequence[float], allowance: float) -> list[int]:
    """Interior joints (1..N-1, chain order: joint j between rods j-1 and j) whose band
    (per joint, mm, e.g. :attr:`optimize.FrictionBand.per_joint` or the mass band's) exceeds
    ``allowance`` (mm): where a robust design would hold the bend with a stop."""
    b = np.asarray(band, float)
    return [int(j) for j in range(1, b.size - 1) if b[j] > allowance]



class DesignedChain(Protocol):
    """What :func:`plan_holes` and :func:`printed_chain` read of a designed chain
    (:class:`rodcad.pipeline.BuildResult`): mm, g, radians, the solver's gravity."""

    design: Any  # .catalog.print_settings, .anchors, .g
    seed: int
    lengths: np.ndarray
    masses: np.ndarray
    com: np.ndarray
    limits: np.ndarray
    end_limits: np.ndarray | None
    target_points: np.ndarray | None
    equilibrium: Any  # optimize.EquilibriumResult
    as_built: Any  # .masses, .com of the solids, or None
    holes: HolePlan | None
    plan: Any  # .fused: runs (first, last) printed as one piece; None for an explicit chain
    notes: list[str]


def chain_hardware(rods: Sequence[RodType], design: Any, cd: Any) -> JointHardware | None:
    """Every pin's hardware for a designed chain (``cd``, a :class:`rodcad.design.masses.
    ChainDesign` of ``design``'s, :class:`rodcad.design.model.Design`), by :func:`rodcad.design.
    hardware.choose_hardware`: its friction band within :data:`rodcad.design.hardware.
    FRICTION_SHARE` of the design's tolerance (or of the default one, where the design's is
    looser: a fixed menu's straight chords are no reason to let the chain rattle) times the
    target's size. None where the catalog
    has no menu or the equilibrium is not a stable one (the bands need it)."""
    menu = design.catalog.pins
    eq = cd.check.equilibrium
    if menu is None or not (eq.success and eq.stable):
        return None
    p = cd.plan.problem
    tol = design.tolerance if design.tolerance is not None else DEFAULT_TOLERANCE
    n = p.n
    return choose_hardware(rods, menu, lengths=p.lengths, masses=cd.result.masses, com=p.com,
                           anchors=design.anchors, limits=p.limits if n > 1 else None, end_limits=p.end_limits,
                           g=design.g, equilibrium=eq, fused=fused_joints(cd.plan.fused, n),
                           budget=FRICTION_SHARE * min(tol, DEFAULT_TOLERANCE) * curve_size(cd.plan.curve))


def plan_holes(rods: Sequence[RodType], chain: DesignedChain) -> HolePlan:
    """:func:`hole_plan` for a designed chain of catalog rods (their joints' clearances: the
    chosen hardware's, else the catalog's), compensated where its equilibrium was found."""
    clearance, _, _ = pins_of(rods)
    if getattr(chain, "hardware", None) is not None:
        clearance = chain.hardware.clearance()
    eq = chain.equilibrium
    runs = chain.plan.fused if chain.plan is not None else []
    return hole_plan(eq.points, chain.masses, eq.reaction, clearance=clearance, com=chain.com, limits=chain.limits,
                     end_limits=chain.end_limits, g=chain.design.g, compensate=bool(eq.success),
                     fused=fused_joints(runs, len(chain.masses)) if chain.plan is not None else None)


def printed_chain(rods: Sequence[RodType], chain: DesignedChain) -> AsPrinted | None:
    """:func:`as_printed` for a designed chain of catalog rods with its :attr:`holes`: the
    as-built solids' masses and centres of mass where built, else the design's; the catalog's
    friction, pin radii and ``print.mass_tolerance``. None (and a note in ``chain.notes``)
    where the chain with its play reaches no configuration (a taut chain) or its solve does
    not converge."""
    _, radius, mu = pins_of(rods)
    hw = getattr(chain, "hardware", None)
    capacity = None if hw is None else solver_moment(hw.capacity, chain.design.g)
    b = chain.as_built
    hung_m, hung_c = (chain.masses, chain.com) if b is None else (b.masses, b.com)
    tol = float(chain.design.catalog.print_settings.get("mass_tolerance", 0.03))
    try:
        ap = as_printed(lengths=chain.lengths, masses=hung_m, com=hung_c, plan=chain.holes,
                        anchors=chain.design.anchors, target=chain.target_points, limits=chain.limits,
                        end_limits=chain.end_limits, design_equilibrium=chain.equilibrium, design_masses=chain.masses,
                        design_com=chain.com, pin_radius=radius, mu=mu, mass_tolerance=tol, g=chain.design.g,
                        seed=chain.seed, capacity=capacity)
    except ValueError as err:
        chain.notes.append(f"the chain as printed (every pin bearing in its holes) was not solved: {err}")
        return None
    if not ap.result.success:  # no equilibrium found: its figures would be the solver's, not the chain's
        chain.notes.append("the chain as printed (every pin bearing in its holes) was not solved: "
                           f"{ap.result.message} Its figures are left out of the report.")
        return None
    return ap


@dataclass(frozen=True)
class Robust:
    """Design option ``robust`` as the planner reads it (:attr:`rodcad.design.decide.Allowed.robust`).

    Attributes:
        allowance: the band a joint may have before it is held both ways (mm: the default
            tolerance x the target's size).
        menu: the catalog's joint hardware (:class:`rodcad.catalog.pins.PinMenu`): a joint's
            friction band is that of the least-friction hardware that carries its load.
        rod: a rod of the family (its knuckles decide what hardware fits).
        mass_tolerance: the catalog's ``print.mass_tolerance``.
    """

    allowance: float
    menu: Any
    rod: RodType
    mass_tolerance: float


def joint_bands(problem, masses, robust: Robust, *, seed: int = 0) -> np.ndarray | None:
    """Per chain joint (N+1,), the larger of its friction band (with the least-friction joint
    hardware of the catalog that carries each pin's load: :func:`rodcad.design.hardware.
    best_capacity`) and its 95 % mass band (mm), for design option ``robust``.

    Args:
        problem: the design's :class:`optimize.InverseProblem` (mm, radians).
        masses: (N,) its masses (g).
        robust: :class:`Robust`.
        seed: the mass band's draws (4000 of them: a few per cent of sampling error).

    Returns:
        The bands, or None where the equilibrium is not found, not stable, or a band cannot be
        computed.
    """
    eq = problem.simulate(masses)
    if not (eq.success and eq.stable) or problem.n < 2:
        return None
    a, b = problem.anchors
    kw = dict(com=problem.com, limits=problem.limits, end_limits=problem.end_limits, g=problem.g, result=eq)
    forces = newtons(np.hypot(*joint_forces(eq.reaction, masses, g=problem.g).T), problem.g)
    least = best_capacity(robust.menu, [robust.rod] * problem.n, forces)
    tau = solver_moment(np.where(np.isfinite(least), least, 0.0), problem.g)
    try:
        fb = friction_band(problem.lengths, masses, a, b, capacity=tau, **kw).per_joint
        mb = mass_band(problem.lengths, masses, a, b, tol=robust.mass_tolerance, n_samples=4000, seed=seed,
                       **kw).per_joint
    except (ValueError, np.linalg.LinAlgError):
        return None
    return np.maximum(fb, mb)


def too_wide(bands: np.ndarray | None, allowance: float) -> list[int]:
    """The bends (j = 0..N-2, between rods j and j+1) whose joint's band exceeds ``allowance`` (mm)."""
    return [] if bands is None else [j - 1 for j in sensitive_joints(bands, allowance)]


def narrower(bands: np.ndarray | None, than: np.ndarray | None) -> bool:
    """Is the largest of ``bands`` below the largest of ``than`` (None: not computed)?"""
    return bands is not None and (than is None or float(bands.max()) < float(than.max()))


def loose_joints(problem, masses, *, allowance: float, mass_tolerance: float, menu, rod: RodType,
                 seed: int = 0) -> list[int]:
    """The bends (j = 0..N-2) of a verified design whose friction band (with the least-friction
    hardware of ``menu`` for ``rod``'s knuckles) or mass band exceeds ``allowance`` (mm):
    :func:`joint_bands` and :func:`too_wide`."""
    return too_wide(joint_bands(problem, masses, Robust(allowance, menu, rod, mass_tolerance), seed=seed), allowance)


def robust_option(curve, pf, catalog) -> Robust:
    """The planner's ``robust`` setting (:attr:`rodcad.design.decide.Allowed.robust`) for a
    family printed to order: the default tolerance x the target's size, the catalog's joint
    hardware for the family's knuckles, its mass tolerance."""
    return Robust(DEFAULT_TOLERANCE * curve_size(np.asarray(curve, float)), catalog.pins, pf.family.template,
                  float(catalog.print_settings.get("mass_tolerance", 0.03)))
