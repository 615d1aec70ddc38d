"""``rodcad check --rebalance``: keep the edited rods as they are, re-design the others'
masses so the chain hangs on its target again, and build them.

At the target the statics are linear in the masses (:mod:`optimize.chain.statics`), so this is
the build's inverse design again (:func:`rodcad.design.masses.design_buildable`: the
design's method, then every mass moved onto one its rod can really be built at), on the
same target joints, lengths and joint limits, with:

- an edited rod's mass pinned to its measured mass (bounds within 1e-9) and its measured
  centre of mass;
- every other rod free within the mass range design.json gives it, at the masses its
  cavities and balls can reach (:func:`rodcad.fabrication.intervals.chain_intervals`).

The rods whose mass changed are then built again (:func:`rodcad.cad.rods.fabricate_chain`,
the build's fabrication seed) and the chain re-simulated with every rod as built: the
edited ones as measured, the re-designed ones from their new solids. It is *balanced*
when that as-built chain is within :data:`REBALANCE_TOL` of the span of the target beyond
the original design's own error.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from optimize import METHODS, EquilibriumResult, InverseProblem, shape_distance
from optimize.chain.discretize import Discretization
from optimize.distance import ShapeDistance
from rodcad.cad.rods import FabricatedRod, fabricate_chain
from rodcad.check.recheck import CheckResult, simulate, with_hardware
from rodcad.design.masses import ChainDesign, design_buildable
from rodcad.design.plan import ChainPlan
from rodcad.fabrication.intervals import chain_intervals
from rodcad.progress import Progress

__all__ = ["PIN_REL", "REBALANCE_TOL", "Rebalanced", "rebalance"]

#: An edited rod's mass bounds: its measured mass to (1 + PIN_REL) times it.
PIN_REL = 1e-9

#: A re-balanced chain may hang this much (relative to the span) further from the target
#: than the original design did.
REBALANCE_TOL = 1e-3

#: A rod whose designed mass changes by no more than this (relative) keeps its files.
SAME_MASS_REL = 1e-9


@dataclass
class Rebalanced:
    """The chain re-balanced around its edited rods.

    Attributes:
        design: the inverse design (masses, the designed chain's equilibrium and its check).
        redesigned: positions whose mass changed (rebuilt, new files).
        fabricated: position -> the rebuilt rod.
        masses, com: every rod as it will be printed (g, mm): edited ones as measured,
            rebuilt ones from their solids, the rest as they were.
        as_built: the chain with those masses and centres of mass.
        vs_target: its joints against the target joints.
        vs_design: its joints against the original design's simulated joints.
        allowed: the largest acceptable ``vs_target.max_rel_span``.
        notes: what the user should know.
    """

    design: ChainDesign
    redesigned: list[int]
    fabricated: dict[int, FabricatedRod]
    masses: np.ndarray
    com: np.ndarray
    as_built: EquilibriumResult
    vs_target: ShapeDistance
    vs_design: ShapeDistance
    allowed: float
    notes: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """The edit is balanced: the as-built chain is back on its target, stably."""
        eq = self.as_built
        return bool(eq.success and eq.stable and self.vs_target.max_rel_span <= self.allowed)


def _holes(built, which: list[int]):
    """The pin holes the build printed those rods with (design.json ``holes_mm``), or None."""
    try:
        return [tuple(tuple(float(v) for v in end) for end in built.data["rods"][i]["holes_mm"]) for i in which]
    except (KeyError, TypeError, ValueError):
        return None


def _hardware(built, rods) -> tuple[np.ndarray, np.ndarray, list]:
    """Per rod: the joint hardware's metal at its hinge axes ((N, 2) g), the plastic its
    hardware's holes add against the rods' tables ((N,) g, negative where wider) and the holes'
    diameters (design.json ``rods[].hardware``; zeros and None in a build without it)."""
    from rodcad.cad.solids import hole_volume_change

    n = built.n
    metal, plastic, sizes = np.zeros((n, 2)), np.zeros(n), []
    for i, r in enumerate(built.data.get("rods") or []):
        hw = r.get("hardware") if isinstance(r, dict) else None
        if not hw or i >= n:
            sizes.append((None, None))
            continue
        metal[i] = [float(v) for v in hw["metal_g"]]
        sz = tuple(float(v) for v in hw["holes_mm"])
        sizes.append(sz)
        plastic[i] = -hole_volume_change(rods[i].geometry, sz) * rods[i].material.density / 1000.0
    return metal, plastic, sizes


def _allowed(res: CheckResult) -> float:
    data = res.built.data
    err = (data.get("error") or {}).get("max_rel_span")
    base = float(err) if isinstance(err, (int, float)) else float(shape_distance(res.built.target,
                                                                                 res.built.simulated).max_rel_span)
    # (design.json's ``tolerance`` bounds the rods' distance from the target curve over its size,
    # another figure: the re-balance brings the joints back where the design had them)
    return base + REBALANCE_TOL


def rebalance(res: CheckResult, *, jobs: int | None = None, progress: Progress | None = None) -> Rebalanced:
    """Re-design and rebuild the unedited rods of a checked chain (see the module's doc).

    Args:
        res: :func:`rodcad.check.recheck.check` of the build, with at least one edited rod
            and one that is not.
        jobs: worker processes for the solids.
        progress: where to report progress.

    Raises:
        ValueError: no rod is edited, or every rod is.
    """
    progress = progress or Progress(quiet=True)
    built, types = res.built, res.types
    edited = set(res.edited)
    if not edited:
        raise ValueError("no rod was edited: there is nothing to re-balance")
    if len(edited) == built.n:
        raise ValueError("every rod was edited: no rod is left to re-balance the chain with")
    free = [i for i in range(built.n) if i not in edited]
    seed = types.fabrication_seed
    with progress.step(f"masses the {len(free)} unedited rods can really be built at"):
        table = chain_intervals([types.rods[i] for i in free], seed=seed, jobs=jobs)
    # the joint hardware hangs on the rods: its metal at their hinge axes, its holes' plastic in
    # the solids (the tables are for the family's own holes); the masses below are as they hang
    metal, plastic, sizes = _hardware(built, types.rods)
    extra = metal.sum(axis=1) + plastic
    hung0, com0 = with_hardware(built, res.masses, res.com)
    bounds = np.array([r.mass_range for r in built.rods], float)
    intervals: list[list[tuple[float, float]]] = []
    for i, r in enumerate(res.readings):
        if i in edited:
            m = float(hung0[i])
            bounds[i] = (m, m * (1 + PIN_REL))
            intervals.append([(m, m * (1 + PIN_REL))])
        else:
            bounds[i] = bounds[i] + extra[i] if np.any(metal) else bounds[i]
            intervals.append([(lo + extra[i], hi + extra[i]) for lo, hi in table[types.rods[i].name]])
    problem = InverseProblem(built.target, built.lengths, bounds, com=com0, limits=built.limits, g=types.g,
                             end_limits=built.end_limits)
    disc = Discretization(built.target, built.lengths, 0.0, 0.0, [])
    plan = ChainPlan(built.target, disc, [r.type for r in built.rods], problem, 0.0)
    method = built.data.get("method")
    method = method if method in METHODS else "refine"
    with progress.step(f"re-designing the masses of {len(free)} rods around {len(edited)} edited one(s) ({method})"):
        cd = design_buildable(plan, method, intervals=intervals, seed=int(built.data.get("seed") or 0),
                              rescale=False, g=types.g)
    new = cd.result.masses
    redesigned = [i for i in free if abs(new[i] - built.rods[i].designed_mass) > SAME_MASS_REL * new[i]]
    fabricated: dict[int, FabricatedRod] = {}
    notes: list[str] = []
    if redesigned:
        with progress.step(f"building {len(redesigned)} re-designed rods (cavities, ball sockets, exact B-rep)") as st:
            fab = fabricate_chain([types.rods[i] for i in redesigned], [float(new[i] - extra[i]) for i in redesigned],
                                  seed=seed, jobs=jobs, progress=st.count, holes=_holes(built, redesigned),
                                  sizes=[sizes[i] for i in redesigned])
        for i, r in zip(redesigned, fab.rods):
            fabricated[i] = dataclasses.replace(r, index=i, file_stem=built.rods[i].stem)
        notes += fab.problems
    masses = res.masses.copy()
    com = res.com.copy()
    for i, r in fabricated.items():
        masses[i] = r.mass
        com[i] = r.com
    masses, com = with_hardware(built, masses, com)
    with progress.step("as-built check of the re-balanced chain"):
        eq = simulate(built, masses, com, types.g)
    out = Rebalanced(cd, redesigned, fabricated, masses, com, eq, shape_distance(built.target, eq.points),
                     shape_distance(built.simulated, eq.points), _allowed(res), notes)
    span = built.span
    if out.ok:
        out.notes.insert(0, f"re-balanced: {len(redesigned)} rod(s) re-designed around the edited rod(s) "
                         f"{', '.join(map(str, sorted(edited)))}; as built the chain hangs within "
                         f"{out.vs_target.max:.3g} mm ({100 * out.vs_target.max_rel_span:.3g} % of the span) of "
                         "the target")
    else:
        lo = [i for i in free if cd.result.at_bounds[i] < 0]
        hi = [i for i in free if cd.result.at_bounds[i] > 0]
        why = []
        if lo:
            why.append(f"rod(s) {', '.join(map(str, lo))} at their lightest")
        if hi:
            why.append(f"rod(s) {', '.join(map(str, hi))} at their heaviest")
        out.notes.insert(0, f"the edit cannot be balanced within the rods' mass ranges: the best fit hangs "
                         f"{out.vs_target.max:.3g} mm ({100 * out.vs_target.max_rel_span:.3g} % of the span) from "
                         f"the target, allowed {100 * out.allowed:.3g} % ({span:.4g} mm span)"
                         + (f", with {' and '.join(why)}" if why else "")
                         + "; make the edit lighter (or spread it over several rods) and check again")
        if not eq.stable:
            out.notes.append("the best fit is not a stable equilibrium")
    return out
