"""Chandeliers: many hanging chains in 3D, hung from one printed frame (the paper's Fig. 8).

Every chain hangs in the vertical plane through its two anchors, so a chandelier
is a set of independent 2D chains placed in 3D. The data flow, one step per function:

    pattern (ring, two_rings, polygon_frame, explicit) -> ChainPlacement per chain
    placements + targets + catalog -> design_chandelier(): each chain planned and
        designed in its own plane (in parallel), one shared rod catalog; per-chain
        errors and a bill of materials
    placements + designs -> plan_frame(): the frame members (ring, hub and ring,
        bars) and a hinge lug at every anchor (LugSpec), all numbers
    FramePlan -> build_frame(): the solid (rodcad.geometry.frame_solid) and its
        checks (valid, fits the printer, rods clear of it at rest and hanging free)
    -> preview_3d(): a 3D picture; chandelier_nodes(): the STEP assembly tree

Coordinates: world z is up, lengths in mm, masses in g. A chain's plane frame has
x horizontal from anchor A toward anchor B, y up and z = x cross y (horizontal, the
hinge axis); chain-plane 2D points are (u, y) with u measured from A horizontally,
so A = (0, z_A) and B = (horizontal distance, z_B).

This module is numpy/matplotlib only; the solids come from :mod:`rodcad.geometry`
(imported where needed).
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "MIN_HORIZONTAL_SPAN",
    "BillOfMaterials",
    "ChainPlacement",
    "ChainResult",
    "ChandelierDesign",
    "FrameCheck",
    "FramePlan",
    "LugSpec",
    "build_frame",
    "chandelier_nodes",
    "design_chandelier",
    "explicit",
    "frame_outline",
    "mass_colors",
    "plan_frame",
    "polygon_frame",
    "preview_3d",
    "ring",
    "rod_matrices",
    "two_rings",
]

#: Smallest horizontal distance between a chain's anchors (mm); below it the
#: chain's vertical plane is undefined.
MIN_HORIZONTAL_SPAN = 1e-6

_UP = np.array([0.0, 0.0, 1.0])


# --------------------------------------------------------------------------- placements


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


# --------------------------------------------------------------------------- design


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
        design: the :class:`rodcad.chain_design.ChainDesign` (plan, inverse result,
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
    def points(self) -> np.ndarray:
        """Simulated joints (N+1, 2) in the chain plane (mm)."""
        return np.asarray(self.design.result.equilibrium.points, dtype=float)

    @property
    def angles(self) -> np.ndarray:
        """Rod chord angles theta_i (N,) from the chain plane's +x (radians)."""
        return np.asarray(self.design.result.equilibrium.angles, dtype=float)

    @property
    def target(self) -> np.ndarray:
        """Target joints (N+1, 2) in the chain plane (mm)."""
        return np.asarray(self.design.plan.problem.target, dtype=float)

    @property
    def points3d(self) -> np.ndarray:
        """Simulated joints in world coordinates (N+1, 3) (mm)."""
        return self.placement.to_3d(self.points)

    @property
    def distance(self) -> Any:
        """Target vs simulated joints (:class:`optimize.distance.ShapeDistance`)."""
        return self.design.result.distance

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
            eq = c.design.result.equilibrium
            rows.append({"name": c.name, "n_rods": len(c.masses), "mass_g": float(c.masses.sum()),
                         **c.error(), "stable": bool(eq.stable), "unique": bool(c.design.unique),
                         "success": bool(c.design.result.success)})
        return rows


TargetLike = Any
"""A target: an (M, 2) chain-plane polyline, a callable ``(a2, b2) -> (M, 2)``, or a
mapping ``{"form": name, **params}`` for :func:`rodcad.targets.make_target`."""


def _target_curve(target: TargetLike, placement: ChainPlacement) -> np.ndarray:
    a2, b2 = placement.plane_anchors()
    if isinstance(target, Mapping):
        from rodcad.targets import make_target

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


def _design_one(task: tuple) -> Any:
    """Plan and design one chain (top level so worker processes can run it)."""
    from rodcad.chain_design import design_chain, plan_chain

    arrays, curve, plan_kw, method, seed, design_kw = task
    plan = plan_chain(None, curve, arrays=arrays, **plan_kw)
    return design_chain(plan, method, seed=seed, **design_kw)


def design_chandelier(catalog: Any, placements: Sequence[ChainPlacement],
                      targets: TargetLike | Sequence[TargetLike], *, method: str = "refine",
                      seed: int = 0, jobs: int = 1, arrays: Any = None,
                      plan_options: Mapping[str, Any] | Sequence[Mapping[str, Any]] | None = None,
                      design_options: Mapping[str, Any] | None = None) -> ChandelierDesign:
    """Design every chain of a chandelier independently, from one rod catalog.

    Each chain is planned on its target (in its own plane) and designed with the
    same method and seed, so the result does not depend on ``jobs``. Chains whose
    problems are identical (same plane anchors to 1e-9 mm, target and options; a
    symmetric ring) are designed once and share the result.

    Args:
        catalog: a loaded :class:`rodcad.catalog.Catalog`.
        placements: the chains.
        targets: one target for every chain, or a list with one per chain (see
            :data:`TargetLike`); a mapping or callable is evaluated in each chain's plane.
        method: inverse-design method ('refine', 'pso', ...).
        seed: random seed of every chain's design.
        jobs: worker processes (1 = in this process).
        arrays: precomputed :func:`rodcad.chain_design.catalog_arrays`.
        plan_options: keyword arguments of :func:`rodcad.chain_design.plan_chain`
            (allowed_types, lengths, preferred_length), shared or one per chain.
        design_options: keyword arguments of :func:`rodcad.chain_design.design_chain`
            (max_nfev, max_time, n_starts).

    Returns:
        The designs, per-chain errors and the bill of materials.

    Raises:
        ValueError: a target list of the wrong length, or a chain that cannot be laid.
    """
    import time

    from rodcad.chain_design import catalog_arrays

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
    if plan_options is None or isinstance(plan_options, Mapping):
        plan_kw = [dict(plan_options or {})] * n
    else:
        plan_kw = [dict(o) for o in plan_options]
        if len(plan_kw) != n:
            raise ValueError(f"{len(plan_kw)} plan options for {n} chains")
    if arrays is None:
        arrays = catalog_arrays(catalog, jobs=jobs)
    design_kw = dict(design_options or {})
    curves = [_target_curve(t, p) for t, p in zip(per_chain, placements)]
    # identical problems are designed once
    keys, first_of, tasks = [], {}, []
    for i, (p, c, kw) in enumerate(zip(placements, curves, plan_kw)):
        key = (np.round(p.plane_anchors(), 9).tobytes(), np.round(c, 9).tobytes(),
               repr(sorted(kw.items())))
        keys.append(key)
        if key not in first_of:
            first_of[key] = i
            tasks.append((arrays, c, kw, method, seed, design_kw))
    order = list(first_of.values())
    if jobs > 1 and len(tasks) > 1:
        from rodcad.parallel import worker_pool

        with worker_pool(min(jobs, len(tasks))) as pool:
            solved = list(pool.map(_design_one, tasks))
    else:
        solved = [_design_one(t) for t in tasks]
    by_first = dict(zip(order, solved))
    chains = []
    for i, p in enumerate(placements):
        j = first_of[keys[i]]
        chains.append(ChainResult(p, by_first[j], None if j == i else placements[j].name))
    bom = _bill_of_materials(chains)
    return ChandelierDesign(chains, bom, method, seed, time.perf_counter() - t0, len(tasks))


def _is_curve(obj: Any) -> bool:
    """True when a list looks like one (M, 2) curve rather than a list of targets."""
    try:
        a = np.asarray(obj, dtype=float)
    except (TypeError, ValueError):
        return False
    return a.ndim == 2 and a.shape[1] == 2


def _bill_of_materials(chains: Sequence[ChainResult]) -> BillOfMaterials:
    count: Counter[str] = Counter()
    mass: dict[str, float] = {}
    for c in chains:
        for name, m in zip(c.type_names, c.masses):
            count[name] += 1
            mass[name] = mass.get(name, 0.0) + float(m)
    n_rods = sum(count.values())
    return BillOfMaterials(dict(sorted(count.items())), dict(sorted(mass.items())), n_rods,
                           float(sum(mass.values())), n_rods - len(chains), 2 * len(chains))


# --------------------------------------------------------------------------- frame


@dataclass(frozen=True, eq=False)
class LugSpec:
    """A hinge lug of the frame, in numbers (what :func:`rodcad.geometry.frame_solid` reads).

    The lug frame has its origin on the lug's pin axis (the anchor), x horizontal
    along the chain (A toward B), y up, z along the pin axis (the chain plane's
    frame moved to the anchor). In it the lug is:

    * a knuckle around the axis: a 'fork' (two prongs in the outer layers, for a
      rod ending in a tongue) or a 'tongue' (the middle layer, for a rod ending in
      a fork), with the catalog hinge's radii, layers and pin hole;
    * an arm toward the frame member: straight from the axis along the direction
      ``tilt_deg`` off vertical (toward +x when positive) for ``elbow`` mm, then
      vertical to the member's mid-plane ``attach_dz`` above (+) or below (-) the axis.
      A fork's arm runs in two cheeks outside the rod's thickness (a clevis), so
      the rod can never touch it; a tongue's arm stays in the middle layer and
      leans away from the rod.

    Attributes:
        name: e.g. 'chain_01.A'.
        location: 4x4 matrix, lug frame -> world.
        knuckle: 'fork' or 'tongue' (the lug's own).
        thickness: the mating rod's section thickness (mm).
        hinge: the mating rod's :class:`rodcad.catalog.Hinge`.
        attach_dz: signed height of the member's mid-plane above the axis (mm).
        tilt_deg: lean of the arm's first segment from vertical (deg).
        elbow: length of the arm's first segment (mm); 0 = straight arm.
    """

    name: str
    location: np.ndarray
    knuckle: str
    thickness: float
    hinge: Any
    attach_dz: float
    tilt_deg: float = 0.0
    elbow: float = 0.0

    @property
    def anchor(self) -> np.ndarray:
        """The point on the pin axis (world, mm)."""
        return self.location[:3, 3].copy()

    @property
    def axis(self) -> np.ndarray:
        """Unit pin axis (world)."""
        return self.location[:3, 2].copy()

    @property
    def cheek(self) -> float:
        """Thickness of a fork lug's prongs and cheeks (mm): the rod's prong thickness."""
        h = self.hinge
        return (self.thickness - h.tongue_thickness) / 2 - h.layer_gap

    @property
    def width(self) -> float:
        """Extent along the pin axis (mm): the pin length through this lug."""
        if self.knuckle == "tongue":
            return self.thickness
        return self.thickness + 2 * (self.hinge.layer_gap + self.cheek)

    def arm_points(self) -> np.ndarray:
        """Arm polyline in the lug frame's xy: axis, elbow, top (3, 2) (mm)."""
        t = math.radians(self.tilt_deg)
        s = 1.0 if self.attach_dz > 0 else -1.0
        e = self.elbow * np.array([math.sin(t), s * math.cos(t)])
        return np.array([[0.0, 0.0], e, [e[0], self.attach_dz]])


@dataclass(eq=False)
class FramePlan:
    """A frame in numbers: its kind, the member parameters and the lugs.

    Attributes:
        kind: 'ring' (one flat ring), 'two_rings' (a hub disc over a ring, joined
            by struts) or 'bars' (a closed polygon of bars).
        params: member parameters (mm), see :func:`rodcad.geometry.frame_solid`.
        lugs: one per chain end, in chain order (A, B, A, B, ...).
        rest: per lug, the chord angle (rad, chain plane) of the rod at rest on it,
            i.e. theta of the first rod at A and of the last rod at B; None if unknown.
    """

    kind: str
    params: dict[str, Any]
    lugs: list[LugSpec]
    rest: list[float | None] = field(default_factory=list)


def _hinge_of(catalog: Any, type_name: str) -> tuple[Any, float, float]:
    g = catalog[type_name].geometry
    return g.hinge, g.thickness, g.height


def plan_frame(kind: str, placements: Sequence[ChainPlacement], catalog: Any,
               chains: Sequence[ChainResult] | None = None, *, width: float = 16.0,
               thickness: float = 5.0, drop: float | None = None, max_tilt_deg: float = 40.0,
               vertices: Sequence[Sequence[float]] | None = None, center: Sequence[float] | None = None,
               struts: int | None = None, strut_diameter: float | None = None,
               bottom_side: str = "auto") -> FramePlan:
    """Lay out a frame that holds every anchor, with a lug matched to each chain end.

    Members: 'ring' is a flat annulus ``width`` wide and ``thickness`` thick whose
    centre line is the anchors' circle, its bottom face ``drop`` above the anchors;
    'two_rings' is a hub disc ``drop`` above the A anchors (radius: theirs plus
    width / 2) and an annulus ``drop`` below (or above, ``bottom_side``) the B
    anchors, joined by ``struts`` round struts at the angles between the chains
    (the struts' tops on the hub, their feet on the annulus' centre line), so the
    frame is one rigid part; 'bars' is a closed polygon of
    flat bars (``width`` x ``thickness``) ``drop`` above ``vertices``.

    Lugs: a chain's rods end in the catalog's knuckles (the first rod's first
    joint, the last rod's second joint); each lug carries the other knuckle. A
    fork lug's arm is straight (a clevis clears the rod at any angle); a tongue
    lug's arm leans along the chain's end tangent continued past the anchor, at
    most ``max_tilt_deg`` off vertical, for a first segment as long as the rod's
    half height plus the hinge zone, then turns vertical.

    Args:
        kind: 'ring', 'two_rings' or 'bars'.
        placements: the chains.
        catalog: the rod catalog (hinge geometry of the end rods).
        chains: the designed chains (end rod types and rest angles); None: every
            chain ends in the catalog's first type and arms are straight.
        width, thickness: member section (mm).
        drop: vertical distance from the anchors to the member's near face (mm);
            default: the rod's section height / 2 + the hinge's zone radius + 2.
        max_tilt_deg: largest lean of a tongue lug's arm (deg).
        vertices: 'bars' only: the anchors' polygon (as given to :func:`polygon_frame`).
        center: 'ring' / 'two_rings': (x, y) of the circles; default the anchors' mean.
        struts: 'two_rings' only: number of struts (default: the number of chains, >= 3).
        strut_diameter: 'two_rings' only (default: width / 2).
        bottom_side: 'two_rings' only: the annulus 'below' or 'above' the B anchors;
            'auto' puts it above when the chains' last rods hang below their B anchor
            (the chain sags below B and rises into it), else below.

    Raises:
        ValueError: unknown kind, missing vertices, or anchors the kind cannot hold.
    """
    placements = list(placements)
    if chains is not None and len(chains) != len(placements):
        raise ValueError(f"{len(chains)} designed chains for {len(placements)} placements")
    ends: list[tuple[str, int]] = []
    for i in range(len(placements)):
        names = chains[i].type_names if chains is not None else [catalog.names[0]]
        ends.append((names[0], 0))
        ends.append((names[-1], 1))
    hinge0, t0, h0 = _hinge_of(catalog, ends[0][0])
    if drop is None:
        drop = h0 / 2 + hinge0.zone_radius + 2.0
    anchors = np.array([x for p in placements for x in (p.a3, p.b3)])
    if center is None:
        center = anchors[:, :2].mean(axis=0)
    center = np.asarray(center, dtype=float)

    # member mid-plane height above (+) / below (-) each anchor, and the member params
    attach: list[float] = []
    if kind == "ring":
        z = float(anchors[:, 2].max()) + drop
        r = np.hypot(*(anchors[:, :2] - center).T)
        params: dict[str, Any] = {"center": tuple(center), "radius": float(r.mean()),
                                  "width": width, "thickness": thickness, "z": z}
        attach = [z + thickness / 2 - a[2] for a in anchors]
    elif kind == "two_rings":
        za = max(p.a3[2] for p in placements) + drop
        if bottom_side == "auto":
            # the ring goes where the last rods are not: above B when they hang below it
            last = [float(c.angles[-1]) for c in chains] if chains is not None else [-1.0]
            bottom_side = "above" if float(np.median(last)) > 0 else "below"
        if bottom_side == "above":
            zb = max(p.b3[2] for p in placements) + drop
        elif bottom_side == "below":
            zb = min(p.b3[2] for p in placements) - drop - thickness
        else:
            raise ValueError(f"bottom_side must be 'auto', 'above' or 'below', not {bottom_side!r}")
        ra = float(np.mean([np.hypot(*(p.a3[:2] - center)) for p in placements]))
        rb = float(np.mean([np.hypot(*(p.b3[:2] - center)) for p in placements]))
        ang = [math.atan2(*(p.a3[:2] - center)[::-1]) for p in placements]
        n_st = struts if struts is not None else max(3, len(placements))
        st0 = math.degrees(ang[0]) + 180.0 / max(len(placements), 1)
        params = {"center": tuple(center), "hub_radius": ra + width / 2, "hub_z": za,
                  "ring_radius": rb, "ring_z": zb, "width": width, "thickness": thickness,
                  "struts": n_st, "strut_start_deg": st0,
                  "strut_diameter": strut_diameter if strut_diameter is not None else width / 2}
        for p in placements:
            attach.append(za + thickness / 2 - p.a3[2])
            attach.append(zb + thickness / 2 - p.b3[2])
    elif kind == "bars":
        if vertices is None:
            raise ValueError("a 'bars' frame needs the anchors' polygon vertices")
        v = np.asarray(vertices, dtype=float).copy()
        v[:, 2] += drop + thickness / 2
        params = {"vertices": v.tolist(), "width": width, "thickness": thickness}
        attach = [drop + thickness / 2] * len(anchors)
    else:
        raise ValueError(f"unknown frame kind {kind!r}; one of ring, two_rings, bars")

    lugs, rest = [], []
    for i, p in enumerate(placements):
        base = p.transform()
        a2, b2 = p.plane_anchors()
        theta = chains[i].angles if chains is not None else None
        for end, origin in ((0, a2), (1, b2)):
            type_name, joint = ends[2 * i + end]
            hinge, t, h = _hinge_of(catalog, type_name)
            rod_knuckle = hinge.knuckle(joint)
            knuckle = "fork" if rod_knuckle == "tongue" else "tongue"
            loc = base.copy()
            loc[:3, 3] = base[:3, :3] @ np.array([origin[0], origin[1], 0.0]) + base[:3, 3]
            dz = attach[2 * i + end]
            tilt, elbow = 0.0, 0.0
            th = None
            if theta is not None:
                th = float(theta[0] if end == 0 else theta[-1])
            if knuckle == "tongue":
                # continue the chain past the anchor: away from the rod
                away = th + math.pi if (end == 0 and th is not None) else th
                if away is not None:
                    s = 1.0 if dz > 0 else -1.0
                    # angle of `away` from the vertical toward the frame, positive toward +x
                    lean = math.degrees(math.atan2(math.cos(away), s * math.sin(away)))
                    tilt = float(np.clip(lean, -max_tilt_deg, max_tilt_deg))
                    elbow = h / 2 + hinge.zone_radius
            lugs.append(LugSpec(f"{p.name}.{'AB'[end]}", loc, knuckle, t, hinge, dz, tilt, elbow))
            rest.append(th)
    return FramePlan(kind, params, lugs, rest)


@dataclass(frozen=True)
class FrameCheck:
    """What :func:`build_frame` found.

    Attributes:
        valid: one valid closed solid.
        size: bounding box extents (x, y, z) of the frame (mm).
        fits_printer: the box fits the catalog printer's build volume in some
            axis-aligned orientation (None without a printer).
        build_volume: the printer's build volume (mm) or None.
        clearances: (what, pose, distance in mm): every rod near the frame at
            rest ('chain_01.rod_00', 'rest'), and the end rod on each lug hanging
            straight away from the frame ('chain_01.A', 'free'); 0 means touching
            or interfering. A rod on a lug is 'layer_gap' away at best (its knuckle
            beside the lug's).
        problems: what is wrong, in words (empty when all is well).
    """

    valid: bool
    size: tuple[float, float, float]
    fits_printer: bool | None
    build_volume: tuple[float, float, float] | None
    clearances: list[tuple[str, str, float]]
    problems: list[str]

    @property
    def ok(self) -> bool:
        return not self.problems


def _rod_matrix(origin2d: Sequence[float], theta: float) -> np.ndarray:
    c, s = math.cos(theta), math.sin(theta)
    m = np.eye(4)
    m[:2, :2] = [[c, -s], [s, c]]
    m[:2, 3] = origin2d
    return m


def rod_matrices(points2d: np.ndarray) -> list[np.ndarray]:
    """Rod frame -> chain-plane frame (4x4) per rod: rod i at p_i, x along p_i -> p_{i+1}."""
    p = np.asarray(points2d, dtype=float)
    d = np.diff(p, axis=0)
    return [_rod_matrix(p[i], math.atan2(d[i, 1], d[i, 0])) for i in range(len(d))]


def build_frame(plan: FramePlan, catalog: Any, chains: Sequence[ChainResult] | None = None, *,
                check_clearance: bool = True) -> tuple[Any, FrameCheck]:
    """Build the frame solid and check it.

    Checks: one valid solid; its bounding box against the catalog printer's
    build volume; every rod's actual solid at its rest pose (when ``chains`` are
    given; rods whose boxes are apart from the frame's are skipped) and, per lug,
    the end rod hanging straight away from the frame (down from a frame above):
    none may touch the frame.

    Returns:
        (build123d Solid, FrameCheck).

    Raises:
        rodcad.geometry.GeometryError: the parameters make no single valid solid.
    """
    from rodcad import geometry

    solid = geometry.frame_solid(plan.kind, plan.params, plan.lugs)
    problems: list[str] = []
    valid = geometry.is_valid_solid(solid)
    if not valid:  # pragma: no cover - frame_solid raises first
        problems.append("the frame is not one valid solid")
    bb = solid.bounding_box()
    size = (float(bb.size.X), float(bb.size.Y), float(bb.size.Z))
    printer = getattr(catalog, "printer", None)
    fits = None
    vol = None
    if printer is not None:
        vol = tuple(float(x) for x in printer.build_volume)
        fits = bool(np.all(np.sort(size) <= np.sort(vol) + 1e-9))
        if not fits:
            problems.append(f"the frame ({size[0]:.0f} x {size[1]:.0f} x {size[2]:.0f} mm) does not "
                            f"fit the printer's build volume {vol[0]:.0f} x {vol[1]:.0f} x "
                            f"{vol[2]:.0f} mm")
    clear: list[tuple[str, str, float]] = []
    if check_clearance:
        near = geometry.DistanceTo(solid)
        lo = np.array([bb.min.X, bb.min.Y, bb.min.Z]) - 1.0
        hi = np.array([bb.max.X, bb.max.Y, bb.max.Z]) + 1.0

        def distance(rod_solid: Any) -> float | None:
            rb = rod_solid.bounding_box()
            if np.any(np.array([rb.min.X, rb.min.Y, rb.min.Z]) > hi) or np.any(
                    np.array([rb.max.X, rb.max.Y, rb.max.Z]) < lo):
                return None  # nowhere near the frame
            return near(rod_solid)

        # every rod at rest
        for c in chains or []:
            base = c.placement.transform()
            for i, (type_name, m) in enumerate(zip(c.type_names, rod_matrices(c.points))):
                d = distance(geometry.placed(catalog[type_name].solid(), base @ m))
                if d is None:
                    continue
                clear.append((f"{c.name}.rod_{i:02d}", "rest", d))
                if d <= 1e-6:
                    problems.append(f"{c.name}: rod {i} ({type_name}) touches the frame at rest")
        # the end rods hanging straight away from the frame
        for k, lug in enumerate(plan.lugs):
            chain_i, end = divmod(k, 2)
            if chains is not None:
                type_name = chains[chain_i].type_names[-1 if end else 0]
            else:
                type_name = catalog.names[0]
            rod = catalog[type_name]
            s = 1.0 if lug.attach_dz > 0 else -1.0
            theta = -s * math.pi / 2 if end == 0 else s * math.pi / 2
            origin = (0.0, 0.0) if end == 0 else (-rod.length * math.cos(theta),
                                                   -rod.length * math.sin(theta))
            d = near(geometry.placed(rod.solid(), lug.location @ _rod_matrix(origin, theta)))
            clear.append((lug.name, "free", d))
            if d <= 1e-6:
                problems.append(f"{lug.name}: the {type_name} rod touches the frame when hanging "
                                f"straight {'down' if s > 0 else 'up'} from it")
    return solid, FrameCheck(valid, size, fits, vol, clear, problems)


def frame_outline(plan: FramePlan, samples: int = 120) -> list[np.ndarray]:
    """Polylines (M, 3) tracing the frame's members and lug arms, for previews (mm)."""
    p = plan.params
    out: list[np.ndarray] = []
    t = np.linspace(0, 2 * np.pi, samples + 1)

    def circle(c: Sequence[float], r: float, z: float) -> np.ndarray:
        return np.column_stack([c[0] + r * np.cos(t), c[1] + r * np.sin(t), np.full_like(t, z)])

    if plan.kind == "ring":
        zc = p["z"] + p["thickness"] / 2
        out += [circle(p["center"], p["radius"] - p["width"] / 2, zc),
                circle(p["center"], p["radius"] + p["width"] / 2, zc)]
    elif plan.kind == "two_rings":
        zh = p["hub_z"] + p["thickness"] / 2
        zr = p["ring_z"] + p["thickness"] / 2
        c = p["center"]
        out += [circle(c, p["hub_radius"], zh), circle(c, p["ring_radius"] - p["width"] / 2, zr),
                circle(c, p["ring_radius"] + p["width"] / 2, zr)]
        for k in range(p["struts"]):
            a = math.radians(p["strut_start_deg"]) + 2 * math.pi * k / p["struts"]
            u = np.array([math.cos(a), math.sin(a)])
            hub_r = p["hub_radius"] - p["strut_diameter"] / 2
            out.append(np.array([[*(np.asarray(c) + hub_r * u), zh],
                                 [*(np.asarray(c) + p["ring_radius"] * u), zr]]))
    elif plan.kind == "bars":
        v = np.asarray(p["vertices"], dtype=float)
        out.append(np.vstack([v, v[:1]]) if len(v) > 2 else v)
    for lug in plan.lugs:
        arm = lug.arm_points()
        out.append((lug.location @ np.column_stack([arm, np.zeros(3), np.ones(3)]).T).T[:, :3])
    return out


# --------------------------------------------------------------------------- pictures


def mass_colors(masses: np.ndarray, lo: float | None = None, hi: float | None = None,
                cmap: str = "coolwarm") -> np.ndarray:
    """RGBA (N, 4) per mass on one scale: light (blue) -> heavy (red)."""
    import matplotlib

    m = np.asarray(masses, dtype=float)
    lo = float(m.min()) if lo is None else lo
    hi = float(m.max()) if hi is None else hi
    if hi - lo <= 1e-12 * max(abs(hi), 1.0):
        lo, hi = lo * 0.95, hi * 1.05 + 1e-12
    return matplotlib.colormaps[cmap]((m - lo) / (hi - lo))


def preview_3d(path: str | Path, chains: Sequence[ChainResult],
               frame_outline: Sequence[np.ndarray] | None = None, title: str = "chandelier", *,
               svg: bool = False, elev: float = 22.0, azim: float = -60.0) -> list[Path]:
    """Draw the chandelier in 3D: rods coloured by mass, anchors, the frame's outline.

    One colour scale (coolwarm, light blue -> heavy red) spans every chain, with
    a colour bar in grams; anchors are black squares; the frame outline is grey;
    the axes have equal scale.

    Args:
        path: the PNG to write (its parent must exist).
        chains: designed chains (anything with ``placement``, ``points`` (N+1, 2)
            and ``masses`` (N,)).
        frame_outline: polylines (M, 3) of the frame (see :func:`frame_outline`).
        title: figure title.
        svg: also write the same picture as SVG next to the PNG.
        elev, azim: view angles (deg).

    Returns:
        The files written.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    all_m = np.concatenate([np.asarray(c.masses, float) for c in chains])
    lo, hi = float(all_m.min()), float(all_m.max())
    if hi - lo <= 1e-12 * max(abs(hi), 1.0):
        lo, hi = lo * 0.95, hi * 1.05 + 1e-12
    norm = Normalize(lo, hi)
    cmap = matplotlib.colormaps["coolwarm"]
    fig = plt.figure(figsize=(8, 7))
    ax = fig.add_subplot(projection="3d")
    pts_all = []
    for c in chains:
        p3 = c.placement.to_3d(c.points)
        pts_all.append(p3)
        segs = np.stack([p3[:-1], p3[1:]], axis=1)
        lc = Line3DCollection(segs, colors=cmap(norm(np.asarray(c.masses, float))), linewidths=4,
                              capstyle="round")
        ax.add_collection3d(lc)
        ax.plot(*p3[1:-1].T, "o", color="k", ms=1.5)
        ax.plot(*np.array([c.placement.a3, c.placement.b3]).T, "ks", ms=5)
    for line in frame_outline or []:
        line = np.asarray(line, float)
        ax.plot(*line.T, "-", color="0.45", lw=1.0)
        pts_all.append(line)
    allp = np.vstack(pts_all)
    mid = (allp.max(axis=0) + allp.min(axis=0)) / 2
    half = float(np.ptp(allp, axis=0).max()) / 2 * 1.05 + 1e-9
    ax.set_xlim(mid[0] - half, mid[0] + half)
    ax.set_ylim(mid[1] - half, mid[1] + half)
    ax.set_zlim(mid[2] - half, mid[2] + half)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=elev, azim=azim)
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_zlabel("z (mm)")
    ax.set_title(title)
    fig.colorbar(ScalarMappable(norm, cmap), ax=ax, label="rod mass (g)", shrink=0.6, pad=0.1)
    path = Path(path)
    fig.savefig(path, dpi=130)
    written = [path]
    if svg:
        fig.savefig(path.with_suffix(".svg"))
        written.append(path.with_suffix(".svg"))
    plt.close(fig)
    return written


# --------------------------------------------------------------------------- assembly


def chandelier_nodes(frame: Any, chains: Sequence[ChainResult], catalog: Any, *,
                     rod_solid: Callable[[int, int], Any] | None = None,
                     frame_plan: FramePlan | None = None) -> list[Any]:
    """The node tree of the whole chandelier for :func:`rodcad.geometry.export_assembly`.

    Top level: the part 'frame' (world placement) and one group per chain, named
    after it ('chain_01', ...), located by the chain's :meth:`ChainPlacement.transform`.
    A chain group holds its rods 'NN_TYPE' (as the rods/ files: rod i with its rod frame at joint p_i,
    x along p_i -> p_{i+1}, coloured by mass on one scale for all chains) and its
    pins 'pin_00'.. (one per joint; the two anchor pins are as long as their lugs).

    Args:
        frame: the frame solid (or None for no frame).
        chains: designed chains.
        catalog: the rod catalog (rod solids and pin sizes).
        rod_solid: ``(chain index, rod index) -> Solid`` for the as-built rods
            (with cavities / sockets); default: the catalog type's plain solid.
        frame_plan: the frame's plan, for the anchor pin lengths (default: the
            rod thickness plus the layer gaps and the prongs).
    """
    from rodcad import geometry

    part_cls = geometry.AssemblyPart
    group_cls = geometry.AssemblyGroup
    all_m = np.concatenate([c.masses for c in chains])
    lo, hi = float(all_m.min()), float(all_m.max())
    nodes: list[Any] = []
    if frame is not None:
        nodes.append(part_cls("frame", frame, np.eye(4), (0.6, 0.6, 0.62)))
    for ci, c in enumerate(chains):
        colors = mass_colors(c.masses, lo, hi)
        children = []
        mats = rod_matrices(c.points)
        for i, (name, m) in enumerate(zip(c.type_names, mats)):
            solid = rod_solid(ci, i) if rod_solid is not None else catalog[name].solid()
            children.append(part_cls(f"{i:02d}_{name}", solid, m, tuple(float(x) for x in colors[i][:3])))
        n = len(c.type_names)
        for j in range(n + 1):
            g = catalog[c.type_names[min(j, n - 1)]].geometry
            length = g.thickness
            if j in (0, n):  # through a lug: a fork lug's cheeks add to the rod's thickness
                if frame_plan is not None:
                    length = frame_plan.lugs[2 * ci + (1 if j == n else 0)].width
                else:
                    length = 2 * g.thickness - g.hinge.tongue_thickness
            m = np.eye(4)
            m[:2, 3] = c.points[j]
            m[2, 3] = -length / 2
            children.append(part_cls(f"pin_{j:02d}", geometry.pin_solid(g.hinge.pin_diameter, length),
                                     m, (0.75, 0.75, 0.78)))
        nodes.append(group_cls(c.name, children, c.placement.transform()))
    return nodes
