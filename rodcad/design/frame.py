"""A chandelier's frame as numbers: the lugs at every anchor, the members between them,
and its check against the rods at rest.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rodcad.design.chandelier import ChainPlacement, ChainResult

__all__ = ['LugSpec', 'FramePlan', 'plan_frame', 'FrameCheck', 'frame_outline']


@dataclass(frozen=True, eq=False)
class LugSpec:
    """A hinge lug of the frame, in numbers (what :func:`rodcad.cad.frame.frame_solid` reads).

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
        hinge: the mating rod's :class:`rodcad.catalog.model.Hinge`.
        attach_dz: signed height of the member's mid-plane above the axis (mm).
        tilt_deg: lean of the arm's first segment from vertical (deg).
        elbow: length of the arm's first segment (mm); 0 = straight arm.
        hole_diameter: the pin hole (mm): the joint hardware's for this lug's knuckle, or
            None: the hinge's own.
        hole_offset: the pin hole's centre from the anchor in the lug frame's xy (mm): where
            the loaded pin bears on its far side at the anchor (the pins-in-holes
            compensation, :func:`rodcad.design.asprinted.anchor_holes`).
    """

    name: str
    location: np.ndarray
    knuckle: str
    thickness: float
    hinge: Any
    attach_dz: float
    tilt_deg: float = 0.0
    elbow: float = 0.0
    hole_diameter: float | None = None
    hole_offset: tuple[float, float] = (0.0, 0.0)

    @property
    def pin_hole(self) -> float:
        """The pin hole's diameter (mm)."""
        return float(self.hinge.hole_diameter if self.hole_diameter is None else self.hole_diameter)

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
        params: member parameters (mm), see :func:`rodcad.cad.frame.frame_solid`.
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
