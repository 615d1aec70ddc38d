"""Chandeliers: many hanging chains in 3D, hung from one printed frame (the paper's Fig. 8).

Every chain hangs in the vertical plane through its two anchors, so a chandelier
is a set of independent 2D chains placed in 3D. The data flow, one step per function:

    pattern (ring, two_rings, polygon_frame, explicit) -> ChainPlacement per chain
    placements + targets + catalog -> design_chandelier(): each chain planned and
        designed in its own plane (in parallel), one shared rod catalog; per-chain
        errors and a bill of materials
    placements + designs -> plan_frame(): the frame members (ring, hub and ring,
        bars) and a hinge lug at every anchor (LugSpec), all numbers
    FramePlan -> build_frame(): the solid (rodcad.cad.frame.frame_solid) and its
        checks (valid, fits the printer, rods clear of it at rest and hanging free)
    -> preview_3d(): a 3D picture; chandelier_nodes(): the STEP assembly tree

Coordinates: world z is up, lengths in mm, masses in g. A chain's plane frame has
x horizontal from anchor A toward anchor B, y up and z = x cross y (horizontal, the
hinge axis); chain-plane 2D points are (u, y) with u measured from A horizontally,
so A = (0, z_A) and B = (horizontal distance, z_B).

This module is numpy/matplotlib only; the solids come from :mod:`rodcad.cad`
(imported where needed).
"""

from __future__ import annotations

import math
import time
from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from optimize import EquilibriumResult, ShapeDistance, shape_distance
from rodcad.catalog.model import Catalog
from rodcad.design.chains import ChainSpec, IntervalsFn, design_chains
from rodcad.design.model import Constraints
from rodcad.design.plan import CatalogArrays, catalog_arrays
from rodcad.errors import Problem
from rodcad.progress import Progress

__all__ = ['MIN_HORIZONTAL_SPAN', 'ChainPlacement', 'ring', 'two_rings', 'polygon_frame', 'explicit', 'BillOfMaterials', 'bill_of_materials', 'ChainResult', 'ChandelierDesign', 'TargetLike', 'design_chandelier']


#: Smallest horizontal distance between a chain's anchors (mm); below it the
#: chain's vertical plane is undefined.
MIN_HORIZONTAL_SPAN = 1e-6


_UP = np.array([0.0, 0.0, 1.0])


@dataclass(eq=False)
class ChainPlacement:
    """Where one chain hangs: its name and its two anchors (pin axes) in 3D.

    Attributes:
        name: e.g. 'chain_01' (names the chain's sub-assembly).
        a3: anchor A (x, y, z) in mm, the chain's first joint.
        b3: anchor B (x, y, z) in mm, the chain's last joint.

    Raises:
        ValueError: anchors not 3D points, or vertically above each other.
    """

    name: str
    a3: np.ndarray
    b3: np.ndarray

    def __post_init__(self) -> None:
        self.a3 = np.asarray(self.a3, dtype=float).reshape(-1)
        self.b3 = np.asarray(self.b3, dtype=float).reshape(-1)
        if self.a3.shape != (3,) or self.b3.shape != (3,) or not (
                np.all(np.isfinite(self.a3)) and np.all(np.isfinite(self.b3))):
            raise ValueError(f"{self.name}: anchors must be finite [x, y, z] points (mm)")
        if self.horizontal_distance < MIN_HORIZONTAL_SPAN:
            raise ValueError(
                f"{self.name}: anchors {self.a3.tolist()} and {self.b3.tolist()} are vertically "
                f"above each other (horizontal distance {self.horizontal_distance:.3g} mm): a "
                f"chain between them has no vertical plane to hang in")

    @property
    def horizontal_distance(self) -> float:
        """Horizontal distance between the anchors (mm)."""
        return float(np.hypot(*(self.b3[:2] - self.a3[:2])))

    @property
    def direction(self) -> np.ndarray:
        """Unit horizontal vector from A toward B: the chain plane's x axis (3,)."""
        d = np.zeros(3)
        d[:2] = (self.b3[:2] - self.a3[:2]) / self.horizontal_distance
        return d

    @property
    def axis(self) -> np.ndarray:
        """Unit hinge axis, horizontal and normal to the chain plane: x cross up (3,)."""
        return np.cross(self.direction, _UP)

    def plane_anchors(self) -> np.ndarray:
        """The anchors in the chain plane: [[0, z_A], [horizontal distance, z_B]] (mm)."""
        return np.array([[0.0, self.a3[2]], [self.horizontal_distance, self.b3[2]]])

    def transform(self) -> np.ndarray:
        """4x4 matrix from the chain-plane frame (x toward B, y up, z hinge axis) to world.

        Its origin is A's foot on z = 0, so a chain-plane point (u, y, 0) lands at
        ``A_xy + u * direction`` at height y (the same map as :meth:`to_3d`).
        """
        m = np.eye(4)
        m[:3, 0] = self.direction
        m[:3, 1] = _UP
        m[:3, 2] = self.axis
        m[:2, 3] = self.a3[:2]
        return m

    def to_3d(self, points2d: np.ndarray) -> np.ndarray:
        """Chain-plane points (M, 2) as (u, y) -> world points (M, 3) (mm)."""
        p = np.atleast_2d(np.asarray(points2d, dtype=float))
        out = np.empty((len(p), 3))
        out[:, :2] = self.a3[:2] + p[:, :1] * self.direction[:2]
        out[:, 2] = p[:, 1]
        return out

    def to_plane(self, points3d: np.ndarray) -> np.ndarray:
        """World points (M, 3) -> chain-plane (u, y) (M, 2); the offset from the plane is dropped."""
        p = np.atleast_2d(np.asarray(points3d, dtype=float))
        return np.column_stack([(p[:, :2] - self.a3[:2]) @ self.direction[:2], p[:, 2]])


def _names(n: int, prefix: str = "chain") -> list[str]:
    width = max(2, len(str(n)))
    return [f"{prefix}_{i + 1:0{width}d}" for i in range(n)]


def _check_distinct_anchors(placements: list[ChainPlacement], min_distance: float = 1e-6) -> None:
    pts = [(p.name, end, x) for p in placements for end, x in (("A", p.a3), ("B", p.b3))]
    for i in range(len(pts)):
        for j in range(i + 1, len(pts)):
            if np.linalg.norm(pts[i][2] - pts[j][2]) < min_distance:
                raise ValueError(
                    f"{pts[i][0]} {pts[i][1]} and {pts[j][0]} {pts[j][1]} share the anchor "
                    f"{pts[i][2].tolist()}: two hinge lugs cannot sit on one point; separate them "
                    f"(e.g. a gap > 0)")


def _circle_point(center: Sequence[float], radius: float, angle_rad: float, z: float) -> np.ndarray:
    return np.array([center[0] + radius * math.cos(angle_rad), center[1] + radius * math.sin(angle_rad), z])


def ring(n: int, radius: float, height: float = 0.0, *, start_deg: float = 0.0, gap: float = 20.0,
         center: Sequence[float] = (0.0, 0.0)) -> list[ChainPlacement]:
    """Festoons around one horizontal ring: chain k hangs below the k-th side of a regular n-gon.

    The n polygon vertices sit on the circle at ``start_deg + 360 k / n``. Two
    chains cannot share a vertex (their lugs would occupy one point), so each chain
    stops ``gap / 2`` short of each vertex, measured along the circle: chain k
    runs from the circle point at ``theta_k + gap / (2 radius)`` to the one at
    ``theta_{k+1} - gap / (2 radius)`` (radians), i.e. along a chord of the circle.
    Every anchor lies on the circle, at one height, so one flat ring carries them.

    Args:
        n: number of chains (>= 2).
        radius: circle radius through the anchors (pin axes) (mm).
        height: z of every anchor (mm).
        start_deg: angle of the first polygon vertex from +x (deg).
        gap: arc length between neighbouring chains' anchors at a vertex (mm, > 0).
        center: (x, y) of the circle (mm).

    Returns:
        n placements 'chain_01'.. in counter-clockwise order, A before B.

    Raises:
        ValueError: n < 2, radius <= 0, or a gap that leaves no chord.
    """
    if n < 2:
        raise ValueError(f"a ring needs at least 2 chains, got {n}")
    if radius <= 0:
        raise ValueError(f"ring radius must be > 0 mm, got {radius}")
    if gap <= 0:
        raise ValueError(f"gap must be > 0 mm (two lugs cannot share an anchor), got {gap}")
    step = 2 * math.pi / n
    half = gap / (2 * radius)
    if 2 * half >= step:
        raise ValueError(f"gap {gap} mm is at least the ring's side arc {step * radius:.3g} mm")
    start = math.radians(start_deg)
    out = []
    for k, name in enumerate(_names(n)):
        t0 = start + k * step
        out.append(ChainPlacement(name, _circle_point(center, radius, t0 + half, height),
                                  _circle_point(center, radius, t0 + step - half, height)))
    return out


def two_rings(n: int, r_top: float, z_top: float, r_bottom: float, z_bottom: float, *,
              twist_deg: float = 0.0, start_deg: float = 0.0,
              center: Sequence[float] = (0.0, 0.0)) -> list[ChainPlacement]:
    """Chains from a top hub down to a lower ring, both parts of one rigid frame.

    Anchor A of chain k is on the top circle at ``start_deg + 360 k / n``, anchor B
    on the bottom circle at that angle plus ``twist_deg``. With no twist every
    chain hangs in a radial plane (a crown, or a lampshade when the bottom ring is
    the wider). Both circles are fixed: :func:`plan_frame` joins the hub and the
    ring with struts between the chains, so the frame is one rigid printed part.

    Args:
        n: number of chains (>= 1).
        r_top, z_top: radius and height of the top anchors (mm); r_top > 0.
        r_bottom, z_bottom: radius and height of the bottom anchors (mm); z_bottom < z_top.
        twist_deg: angular offset of each bottom anchor from its top anchor (deg).
        start_deg: angle of the first top anchor from +x (deg).
        center: (x, y) of both circles (mm).

    Raises:
        ValueError: bad radii or heights, or a chain whose anchors are vertically
            above each other (r_top == r_bottom and no twist).
    """
    if n < 1:
        raise ValueError(f"two_rings needs at least 1 chain, got {n}")
    if r_top <= 0 or r_bottom <= 0:
        raise ValueError("two_rings radii must be > 0 mm (chains on the axis would share an anchor)")
    if not z_bottom < z_top:
        raise ValueError(f"the bottom ring (z = {z_bottom}) must be below the top one (z = {z_top})")
    start, twist = math.radians(start_deg), math.radians(twist_deg)
    out = []
    for k, name in enumerate(_names(n)):
        t = start + 2 * math.pi * k / n
        out.append(ChainPlacement(name, _circle_point(center, r_top, t, z_top),
                                  _circle_point(center, r_bottom, t + twist, z_bottom)))
    _check_distinct_anchors(out)
    return out


def polygon_frame(vertices: Sequence[Sequence[float]], *, gap: float = 20.0) -> list[ChainPlacement]:
    """A chain below every edge of a closed polygon of frame bars.

    Chain k hangs below the edge from vertex k to vertex k+1 (the last edge closes
    the polygon), stopping ``gap / 2`` short of each vertex along the edge so that
    neighbouring chains' lugs do not meet. The vertices are points on the anchors'
    (pin axes') polygon; the bars sit above it (:func:`plan_frame`).

    Args:
        vertices: (K, 3) polygon vertices (mm), K >= 2 (K = 2: one edge each way
            would overlap, so two vertices give a single chain).
        gap: distance along an edge between neighbouring chains' anchors (mm, > 0).

    Raises:
        ValueError: fewer than 2 vertices, an edge not longer than the gap, or a
            vertical edge.
    """
    v = np.asarray(vertices, dtype=float)
    if v.ndim != 2 or v.shape[1] != 3 or len(v) < 2:
        raise ValueError("polygon_frame needs at least 2 [x, y, z] vertices")
    if gap <= 0:
        raise ValueError(f"gap must be > 0 mm (two lugs cannot share an anchor), got {gap}")
    edges = [(0, 1)] if len(v) == 2 else [(i, (i + 1) % len(v)) for i in range(len(v))]
    out = []
    for (i, j), name in zip(edges, _names(len(edges))):
        e = v[j] - v[i]
        length = float(np.linalg.norm(e))
        if length <= gap:
            raise ValueError(f"edge {i}-{j} is {length:.3g} mm long, not longer than the gap {gap} mm")
        u = e / length
        out.append(ChainPlacement(name, v[i] + u * gap / 2, v[j] - u * gap / 2))
    return out


def explicit(pairs: Sequence[tuple[Sequence[float], Sequence[float]]],
             names: Sequence[str] | None = None) -> list[ChainPlacement]:
    """Placements from given (A, B) anchor pairs (mm).

    Raises:
        ValueError: a bad pair, names of the wrong count, or two chains sharing an anchor.
    """
    if names is not None and len(names) != len(pairs):
        raise ValueError(f"{len(names)} names for {len(pairs)} chains")
    names = list(names) if names is not None else _names(len(pairs))
    out = [ChainPlacement(nm, a, b) for nm, (a, b) in zip(names, pairs)]
    _check_distinct_anchors(out)
    return out


@dataclass(frozen=True)
class BillOfMaterials:
    """What to print and cut for a chandelier (the frame excluded).

    Attributes:
        rods_by_type: rod type name -> count.
        mass_by_type: rod type name -> total designed mass (g).
        n_rods: number of rods.
        total_mass: designed mass of all rods (g).
        pins: pins between rods (one per interior joint).
        anchor_pins: pins through the frame's lugs (two per chain).
    """

    rods_by_type: dict[str, int]
    mass_by_type: dict[str, float]
    n_rods: int
    total_mass: float
    pins: int
    anchor_pins: int

    def as_dict(self) -> dict[str, Any]:
        return {"rods_by_type": dict(self.rods_by_type),
                "mass_by_type_g": {k: round(v, 4) for k, v in self.mass_by_type.items()},
                "n_rods": self.n_rods, "total_mass_g": round(self.total_mass, 4),
                "pins": self.pins, "anchor_pins": self.anchor_pins}


@dataclass(eq=False)
class ChainResult:
    """One designed chain of a chandelier.

    Attributes:
        placement: where it hangs.
        design: the :class:`rodcad.design.masses.ChainDesign` (plan, inverse result,
            uniqueness check), in the chain's plane coordinates.
        shared_with: name of the chain whose design this one reuses (an identical
            problem: same plane anchors, target and options), or None.
    """

    placement: ChainPlacement
    design: Any
    shared_with: str | None = None

    @property
    def name(self) -> str:
        return self.placement.name

    @property
    def type_names(self) -> list[str]:
        return list(self.design.plan.type_names)

    @property
    def masses(self) -> np.ndarray:
        """Designed masses (N,) (g)."""
        return np.asarray(self.design.result.masses, dtype=float)

    @property
    def equilibrium(self) -> EquilibriumResult:
        """The designed chain solved from scratch (in the chain plane)."""
        return self.design.check.equilibrium

    @property
    def points(self) -> np.ndarray:
        """Simulated joints (N+1, 2) in the chain plane (mm)."""
        return np.asarray(self.equilibrium.points, dtype=float)

    @property
    def angles(self) -> np.ndarray:
        """Rod chord angles theta_i (N,) from the chain plane's +x (radians)."""
        return np.asarray(self.equilibrium.angles, dtype=float)

    @property
    def target(self) -> np.ndarray:
        """Target joints (N+1, 2) in the chain plane (mm)."""
        return np.asarray(self.design.plan.problem.target, dtype=float)

    @property
    def points3d(self) -> np.ndarray:
        """Simulated joints in world coordinates (N+1, 3) (mm)."""
        return self.placement.to_3d(self.points)

    @property
    def distance(self) -> ShapeDistance:
        """Target vs simulated joints (:class:`optimize.distance.ShapeDistance`)."""
        return shape_distance(self.target, self.points)

    def error(self) -> dict[str, float]:
        """Shape error {max_mm, mean_mm, sum_mm, max_rel_span} as in design.json."""
        d = self.distance
        return {"max_mm": float(d.max), "mean_mm": float(d.mean), "sum_mm": float(d.sum),
                "max_rel_span": float(d.max_rel_span)}


@dataclass(eq=False)
class ChandelierDesign:
    """Every chain designed, with the totals.

    Attributes:
        chains: one result per placement, in order.
        bom: bill of materials over all chains.
        method, seed: how the chains were designed.
        time_s: wall time of the design (s).
        n_distinct: number of distinct chain problems actually solved.
    """

    chains: list[ChainResult]
    bom: BillOfMaterials
    method: str
    seed: int
    time_s: float
    n_distinct: int

    @property
    def max_error(self) -> float:
        """Largest joint error over all chains (mm)."""
        return max(float(c.distance.max) for c in self.chains)

    @property
    def success(self) -> bool:
        return all(bool(c.design.result.success) for c in self.chains)

    def errors(self) -> list[dict[str, Any]]:
        """Per-chain summary rows: name, rods, mass (g), error, stable, unique."""
        rows = []
        for c in self.chains:
            eq = c.equilibrium
            rows.append({"name": c.name, "n_rods": len(c.masses), "mass_g": float(c.masses.sum()),
                         **c.error(), "stable": bool(eq.stable), "unique": bool(c.design.unique),
                         "success": bool(c.design.result.success)})
        return rows


TargetLike = Any


"""A target: an (M, 2) chain-plane polyline, a callable ``(a2, b2) -> (M, 2)``, or a
mapping ``{"form": name, **params}`` for :func:`rodcad.design.targets.make_target`."""


def _target_curve(target: TargetLike, placement: ChainPlacement) -> np.ndarray:
    a2, b2 = placement.plane_anchors()
    if isinstance(target, Mapping):
        from rodcad.design.targets import make_target

        params = dict(target)
        form = params.pop("form", None)
        if form is None:
            raise ValueError(f"{placement.name}: a target mapping needs a 'form'")
        return np.asarray(make_target(str(form), a2, b2, **params), dtype=float)
    if callable(target):
        return np.asarray(target(a2, b2), dtype=float)
    curve = np.asarray(target, dtype=float)
    if curve.ndim != 2 or curve.shape[1] != 2 or len(curve) < 2:
        raise ValueError(f"{placement.name}: a target curve must be an (M, 2) array of (u, y) points")
    span = float(np.hypot(*(b2 - a2)))
    if np.hypot(*(curve[0] - a2)) > 1e-6 * span or np.hypot(*(curve[-1] - b2)) > 1e-6 * span:
        raise ValueError(f"{placement.name}: the target curve must run from A {a2.tolist()} to "
                         f"B {b2.tolist()} in the chain plane; it runs from {curve[0].tolist()} "
                         f"to {curve[-1].tolist()}")
    return curve


def design_chandelier(catalog: Catalog, placements: Sequence[ChainPlacement],
                      targets: TargetLike | Sequence[TargetLike], *, method: str = "refine",
                      seed: int = 0, jobs: int = 1, arrays: CatalogArrays | None = None,
                      constraints: Constraints | None = None,
                      problem: Callable[[str, str], Problem] | None = None,
                      intervals: IntervalsFn | None = None, n_starts: int = 12,
                      g: float = 9.81, progress: Progress | None = None) -> ChandelierDesign:
    """Design every chain of a chandelier, from one rod catalog, through the per-chain path
    a single chain takes (:func:`rodcad.design.chains.design_chains`).

    Each chain is planned on its target (in its own plane) with the design's constraints
    and designed with the same method and seed, so the result does not depend on
    ``jobs``. Chains whose problems are identical (same plane anchors to 1e-9 mm and
    target; a symmetric ring) are designed once and share the result.

    Args:
        catalog: a loaded :class:`rodcad.catalog.model.Catalog`.
        placements: the chains.
        targets: one target for every chain, or a list with one per chain (see
            :data:`TargetLike`); a mapping or callable is evaluated in each chain's plane.
        method: inverse-design method ('refine', 'pso', ...).
        seed: random seed of every chain's design.
        jobs: worker processes (1 = in this process).
        arrays: precomputed :func:`rodcad.design.plan.catalog_arrays`.
        constraints: the design's constraints (types, lengths, preferred length, rod
            count, fixed rods), applied to every chain (default: none).
        problem: makes a problem pointing at a key of the design file (default: problems
            name the chandelier, without a file position).
        intervals: achievable mass intervals of rod types (fabrication with CAD), or None.
        n_starts: multi-start count of each chain's uniqueness check.
        g: gravitational acceleration (m/s^2).
        progress: where to report the steps (default: silent).

    Returns:
        The designs, per-chain errors and the bill of materials.

    Raises:
        ValueError: a target list of the wrong length or a bad target.
        InputError: a chain whose constraints cannot be met.
    """
    t0 = time.perf_counter()
    placements = list(placements)
    if not placements:
        raise ValueError("a chandelier needs at least one chain")
    n = len(placements)
    if isinstance(targets, (list, tuple)) and len(targets) == n and not _is_curve(targets):
        per_chain = list(targets)
    elif isinstance(targets, (list, tuple)) and not _is_curve(targets):
        raise ValueError(f"{len(targets)} targets for {n} chains (give one, or one per chain)")
    else:
        per_chain = [targets] * n
    if arrays is None:
        arrays = catalog_arrays(catalog, jobs=jobs)
    specs = [ChainSpec(p.name, np.array(p.plane_anchors(), dtype=float), _target_curve(t, p))
             for t, p in zip(per_chain, placements)]
    designed = design_chains(specs, arrays, constraints or Constraints(), problem or _problem,
                             method=method, seed=seed, n_starts=n_starts, g=g, intervals=intervals, jobs=jobs,
                             progress=progress)
    chains = [ChainResult(p, d.design, None if d.shared_with is None else placements[d.shared_with].name)
              for p, d in zip(placements, designed)]
    n_distinct = sum(1 for d in designed if d.shared_with is None)
    return ChandelierDesign(chains, bill_of_materials(chains), method, seed, time.perf_counter() - t0, n_distinct)


def _problem(key: str, message: str) -> Problem:
    return Problem("<chandelier>", 0, 0, key, message)


def _is_curve(obj: Any) -> bool:
    """True when a list looks like one (M, 2) curve rather than a list of targets."""
    try:
        a = np.asarray(obj, dtype=float)
    except (TypeError, ValueError):
        return False
    return a.ndim == 2 and a.shape[1] == 2


def bill_of_materials(chains: Sequence[ChainResult]) -> BillOfMaterials:
    """Rods by type and their masses (as they hang), pins between rods and at the lugs."""
    count: Counter[str] = Counter()
    mass: dict[str, float] = {}
    for c in chains:
        for name, m in zip(c.type_names, c.masses):
            count[name] += 1
            mass[name] = mass.get(name, 0.0) + float(m)
    n_rods = sum(count.values())
    return BillOfMaterials(dict(sorted(count.items())), dict(sorted(mass.items())), n_rods,
                           float(sum(mass.values())), n_rods - len(chains), 2 * len(chains))
