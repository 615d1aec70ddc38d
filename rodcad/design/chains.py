"""One path for every chain: a single chain and each chain of a chandelier go through it.

    (label, anchors, target curve) per chain
      -> plan_constrained()   rods laid on the target, every design constraint applied
      -> buildable masses     the masses fabrication can make, when CAD is on (a callable
                              gives the achievable intervals of the planned types)
      -> design_chain() / design_buildable()
                              masses by the inverse method, then one check: the chain
                              solved from scratch and a multi-start for other stable shapes

Chains with identical problems (same plane anchors to 1e-9 mm and target: a symmetric
ring) are planned and designed once and share the result. The mass design of distinct
chains runs in worker processes when ``jobs > 1``; the result does not depend on it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from rodcad.design.masses import ChainDesign, design_buildable, design_chain
from rodcad.design.model import Constraints
from rodcad.catalog.model import RodType
from rodcad.design.plan import CatalogArrays, ChainPlan, plan_constrained
from rodcad.design.printed import rods_of
from rodcad.errors import InputError, Problem
from rodcad.parallel import worker_pool
from rodcad.progress import Progress

__all__ = ["ChainSpec", "DesignedChain", "IntervalsFn", "design_chains"]

#: Achievable mass intervals [(lo, hi), ...] (g) of the given rod types, by name.
IntervalsFn = Callable[[Sequence[RodType]], Mapping[str, Sequence[tuple[float, float]]]]


@dataclass(frozen=True)
class ChainSpec:
    """One chain to design.

    Attributes:
        label: its name in messages ('' for the one chain of a design).
        anchors: (2, 2) anchors A and B in the chain's plane (mm).
        curve: (M, 2) target polyline from A to B in that plane (mm).
    """

    label: str
    anchors: np.ndarray
    curve: np.ndarray

    def key(self) -> bytes:
        """Identical problems share this key."""
        return np.round(self.anchors, 9).tobytes() + np.round(self.curve, 9).tobytes()


@dataclass(frozen=True)
class DesignedChain:
    """A chain's design and, when it reuses another chain's, which one.

    Attributes:
        spec: the chain.
        design: plan, masses and check.
        shared_with: index of the chain whose identical problem this one reuses, or None.
    """

    spec: ChainSpec
    design: ChainDesign
    shared_with: int | None = None


@dataclass(frozen=True)
class _Task:
    plan: ChainPlan
    method: str
    seed: int
    n_starts: int
    g: float
    intervals: Mapping[str, Sequence[tuple[float, float]]] | None


def _design_masses(task: _Task) -> ChainDesign:
    """Masses for one plan (top level, so worker processes can run it)."""
    if task.intervals is None:
        return design_chain(task.plan, task.method, seed=task.seed, n_starts=task.n_starts, g=task.g)
    return design_buildable(task.plan, task.method, intervals=task.intervals, seed=task.seed,
                            n_starts=task.n_starts, g=task.g)


def design_chains(
    specs: Sequence[ChainSpec],
    arrays: CatalogArrays,
    constraints: Constraints,
    problem: Callable[[str, str], Problem],
    *,
    method: str = "refine",
    seed: int = 0,
    n_starts: int = 12,
    g: float = 9.81,
    intervals: IntervalsFn | None = None,
    jobs: int = 1,
    progress: Progress | None = None,
) -> list[DesignedChain]:
    """Plan, design and check every chain.

    Args:
        specs: the chains.
        arrays: the catalog's numbers (:func:`rodcad.design.plan.catalog_arrays`).
        constraints: the design's constraints, applied to every chain.
        problem: makes a problem pointing at a key of the design file (``Design.problem``).
        method: inverse-design method.
        seed: seed of every chain's design and multi-start.
        n_starts: multi-start count of the uniqueness check.
        g: gravitational acceleration (m/s^2; scales the reactions only).
        intervals: the achievable mass intervals of rod types (fabrication with CAD), or
            None for the continuous mass ranges.
        jobs: worker processes for the mass design of distinct chains.
        progress: where to report the steps (default: silent).

    Raises:
        InputError: a chain's constraints cannot be met (pointing at the key).
    """
    progress = progress or Progress(quiet=True)
    first: dict[bytes, int] = {}
    plans: dict[int, ChainPlan] = {}
    what = "the target" if len(specs) == 1 else f"the targets of {len(specs)} chains"
    problems: list[Problem] = []
    with progress.step(f"laying rods on {what}") as st:
        for i, s in enumerate(specs):
            k = s.key()
            if k not in first:
                first[k] = i
                try:
                    plans[i] = plan_constrained(s.curve, constraints, arrays, problem, label=s.label,
                                                report=st.note)
                except InputError as err:  # every chain's problems at once
                    problems += err.problems
    if problems:
        raise InputError(problems)
    ivs = None
    if intervals is not None:
        catalog = arrays.catalog.with_types(rods_of(plans.values())) if arrays.catalog is not None else None
        names = sorted({n for p in plans.values() for n in p.type_names})
        ivs = dict(intervals([catalog[n] if catalog is not None else arrays.types[arrays.index[n]]
                              for n in names]))
    order = sorted(plans)
    tasks = [_Task(plans[i], method, seed, n_starts, g, ivs) for i in order]
    rods = sum(len(plans[i].type_names) for i in order)
    with progress.step(f"inverse design ({method}, {rods} rods{', buildable masses' if ivs else ''}) "
                       f"and equilibrium check"):
        if jobs > 1 and len(tasks) > 1:
            with worker_pool(min(jobs, len(tasks))) as pool:
                designs = list(pool.map(_design_masses, tasks))
        else:
            designs = [_design_masses(t) for t in tasks]
    done = dict(zip(order, designs))
    out = []
    for i, s in enumerate(specs):
        j = first[s.key()]
        out.append(DesignedChain(s, done[j], None if j == i else j))
    return out
