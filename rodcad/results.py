"""The result types of a build: one chain's (:class:`BuildResult`, with its as-built
re-simulation :class:`AsBuilt`) and a chandelier's (:class:`ChandelierBuild`). They carry what
every step found to the outputs; :mod:`rodcad.pipeline` fills them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from optimize import EquilibriumResult
from optimize.distance import ShapeDistance
from rodcad.design.asprinted import AsPrinted, HolePlan
from rodcad.design.chandelier import ChandelierDesign
from rodcad.design.fit import DEFAULT_TOLERANCE, curve_fit, fit_limit
from rodcad.design.frame import FramePlan
from rodcad.design.hardware import JointHardware
from rodcad.design.hung import printed_masses
from rodcad.design.masses import ChainDesign
from rodcad.design.model import Design
from rodcad.design.plan import ChainPlan

if TYPE_CHECKING:  # (the CAD kernel: imported where solids are built)
    from rodcad.cad.rods import ChainFabrication

__all__ = ["AsBuilt", "BuildResult", "ChandelierBuild"]


@dataclass
class AsBuilt:
    """The chain as it will really be printed, re-simulated.

    Attributes:
        masses: (N,) rod masses from the final B-rep plus metal (g).
        com: (N, 2) centres of mass from the final B-rep (mm, rod frame).
        equilibrium: its equilibrium.
        distance: its joints against the target joints.
    """

    masses: np.ndarray
    com: np.ndarray
    equilibrium: EquilibriumResult
    distance: ShapeDistance


@dataclass
class BuildResult:
    """Everything one run found for one chain, for the report and the output files.

    Attributes:
        design: the validated design.
        method: inverse-design method used ('' for an explicit chain).
        seed: seed used.
        type_names: rod type per position.
        lengths, masses, com: per rod (mm, g, mm in the rod frame).
        limits: (N-1, 2) joint limits (rad), (-inf, inf) where nothing collides.
        end_limits: (2, 2) the anchor fixture's bounds on the first and last rods' angles
            (rad), or None for bare pins.
        fixture: the anchor fixture's solid (with CAD, when the design stops an end rod).
        fixture_problems: what is wrong with it (it collides with a rod at rest, ...).
        target_points: (N+1, 2) target joints (None for an explicit chain).
        equilibrium: the designed chain, solved from scratch.
        distance: simulated vs target joints (None without a target).
        n_stable, unique: multi-start check (other stable equilibria?).
        plan, chain_design: the planning and inverse-design results (None for an explicit chain).
        fabrication: the fabricated rods (None without CAD).
        as_built: the as-built re-simulation (None without CAD).
        hardware: every pin's hardware (:mod:`rodcad.design.hardware`), None for an explicit chain.
        holes, as_printed: the pin holes printed; the chain as printed (rodcad.design.asprinted).
        notes: things the user should know (infeasibility, bounds, stops).
        time_s: wall time of the run.
    """

    design: Design
    method: str
    seed: int
    type_names: list[str]
    lengths: np.ndarray
    masses: np.ndarray
    com: np.ndarray
    limits: np.ndarray
    target_points: np.ndarray | None
    equilibrium: EquilibriumResult
    distance: ShapeDistance | None
    n_stable: int
    unique: bool
    plan: ChainPlan | None = None
    chain_design: ChainDesign | None = None
    fabrication: ChainFabrication | None = None
    as_built: AsBuilt | None = None
    notes: list[str] = field(default_factory=list)
    time_s: float = 0.0
    end_limits: np.ndarray | None = None
    fixture: Any = None
    fixture_problems: list[str] = field(default_factory=list)
    holes: HolePlan | None = None
    as_printed: AsPrinted | None = None
    hardware: JointHardware | None = None
    hung: Any = None  # rodcad.design.hung.HungDesign: the masses designed with the hardware on
    tapping: Any = None  # rodcad.design.tapping.TapResult: the hung chain tapped in MuJoCo

    @property
    def rods(self) -> list:
        """The chain's rod types (:class:`rodcad.catalog.model.RodType`)."""
        return [self.design.catalog[name] for name in self.type_names]

    @property
    def attached(self) -> np.ndarray:
        """(N, 2) g of joint hardware each rod carries at its hinge axes (the plastic its
        hardware's holes take or add included; 0 without hardware): what the masses were
        designed with (:attr:`rodcad.design.hung.HungDesign.attached`)."""
        if self.hung is None:
            return np.zeros((self.n, 2))
        return self.hung.attached

    @property
    def metal(self) -> np.ndarray | None:
        """(N, 2) g of the hardware's metal (pins, sleeves, bearings) on each rod's hinge axes,
        None without hardware."""
        return None if self.hardware is None else self.hardware.attached(self.rods, plastic=False)

    @property
    def printed_masses(self) -> np.ndarray:
        """(N,) each rod as its tables know it (its family's own holes, no hardware): what the
        fabrication builds for (g)."""
        return printed_masses(self.masses, self.attached)

    @property
    def hole_sizes(self) -> list[tuple[float, float]] | None:
        """Per rod, its pin holes' diameters (mm) for the chosen hardware, None without."""
        return None if self.hardware is None else self.hardware.holes(self.rods)

    @property
    def ok(self) -> bool:
        """Meets its tolerance, and its fixture (if any) is fit to print."""
        return self.meets_tolerance and not self.fixture_problems

    @property
    def n(self) -> int:
        return len(self.type_names)

    @property
    def tolerance(self) -> float:
        """The design's ``tolerance``, or :data:`rodcad.design.fit.DEFAULT_TOLERANCE`."""
        return self.design.tolerance if self.design.tolerance is not None else DEFAULT_TOLERANCE

    @property
    def fit(self) -> float | None:
        """How far the hanging rods' centrelines are from the target curve over the target's
        size (:func:`rodcad.design.fit.curve_fit`), the as-built or as-printed chain's where it
        is worse; None for an explicit chain."""
        if self.plan is None or self.design.target_curve is None:
            return None
        curvature = [self.design.catalog[n].curvature for n in self.type_names]
        fit = curve_fit(self.plan.curve, self.equilibrium.points, curvature)
        if self.as_built is not None:
            fit = max(fit, curve_fit(self.plan.curve, self.as_built.equilibrium.points, curvature))
        if self.as_printed is not None:
            fit = max(fit, curve_fit(self.plan.curve, self.as_printed.result.points, curvature))
        return fit

    @property
    def meets_tolerance(self) -> bool:
        """The rods hang within the tolerance of the target curve (always, for an explicit chain)."""
        fit = self.fit
        return fit is None or fit <= self.tolerance * (1 + 1e-9)

    def limit(self) -> str:
        """What keeps the chain off its tolerance and what would reach it, in one line."""
        fit = self.fit
        if fit is None or self.plan is None or self.chain_design is None:
            return ""
        fam = next((f for f in self.design.catalog.printed_families), None) if self.plan.rods else None
        return fit_limit(curve=self.plan.curve, target_points=self.target_points,
                         curvature=[self.design.catalog[n].curvature for n in self.type_names], plan=self.plan,
                         inverse=self.chain_design.result, check=self.chain_design.check, fit=fit,
                         tolerance=self.tolerance, family_ranges=fam.ranges if fam is not None else None,
                         constraints=self.design.constraints,
                         hardware_g=None if self.hardware is None else self.attached.sum(axis=1),
                         shot=all(r.fill is not None for r in self.rods))


@dataclass
class ChandelierBuild:
    """A designed (and optionally fabricated) chandelier.

    Attributes:
        design: the validated design.
        result: per-chain designs and the bill of materials.
        frame_plan: the frame's layout (lugs, members).
        frame: the frame solid and its check (None without CAD).
        fabrications: per chain, the fabricated rods (None without CAD).
        as_built: per chain, the as-built re-simulation (None without CAD).
        chains: per chain, the chain as a single one's result (:class:`BuildResult` in its
            plane): its joint hardware, holes, as printed bands and tapping.
        notes: things the user should know.
        time_s: wall time.
    """

    design: Design
    result: ChandelierDesign
    frame_plan: FramePlan
    frame: tuple[Any, Any] | None = None
    fabrications: list[ChainFabrication] | None = None
    as_built: list[AsBuilt] | None = None
    chains: list[BuildResult] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    time_s: float = 0.0

    @property
    def meets_tolerance(self) -> bool:
        """Every chain's rods hang within the tolerance of its target curve."""
        tol = self.design.tolerance if self.design.tolerance is not None else DEFAULT_TOLERANCE
        return all(self.fits[k] <= tol * (1 + 1e-9) for k in range(len(self.result.chains)))

    @property
    def fits(self) -> list[float]:
        """Per chain, how far its rods hang off its target curve over the target's size."""
        out = []
        for ch in self.result.chains:
            curvature = [self.design.catalog[n].curvature for n in ch.design.plan.type_names]
            out.append(curve_fit(ch.design.plan.curve, ch.points, curvature))
        return out
