"""Sphere layouts inside a rod: the most equal voids on a symmetric lattice
(:mod:`rodcad.fabrication.lattice`) that keep a minimum wall (checked against a clearance
field), one set of sockets at a time or several at once, and the void shapes' volumes.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from rodcad.fabrication.lattice import (LATTICES, SYMMETRIES, BoundedMemo, lattice_image_map, lattice_sites,
                                        memo_key, symmetric_images, symmetric_subset)

__all__ = [
    "LATTICES",
    "MIN_CAVITY_RADIUS",
    "RADIUS_STEP",
    "SYMMETRIES",
    "UP",
    "VOIDS",
    "BoundedMemo",
    "ball_offset",
    "memo_key",
    "Clearance",
    "lattice_image_map",
    "lattice_sites",
    "max_ball_layout",
    "max_cavity_layout",
    "silo_rim_points",
    "silo_top_points",
    "silo_volume",
    "sphere_layout",
    "sphere_layouts",
    "SphereLayout",
    "symmetric_images",
    "symmetric_subset",
    "tall_silo",
    "void_centroid",
    "void_volume",
]


#: Smallest cavity radius considered (mm): 1 mm cavities still print as voids.
MIN_CAVITY_RADIUS = 0.5


#: Radii tried for cavities shrink by this factor from the largest that could fit.
RADIUS_STEP = 0.93


Clearance = Callable[[np.ndarray], np.ndarray]


#: Print "up" in the rod frame: every rod prints on its side, the -y face on
#: the bed, so the rod frame's +y is the printer's +Z.
UP = np.array([0.0, 1.0, 0.0])


#: Void shapes, all of "radius" r around a centre c (the print's up is :data:`UP`):
#:
#: * 'sphere': the plain sphere (layout search only; not printable without
#:   support when large).
#: * 'capped': the sphere cut flat at +-r/sqrt(2) along up. Its walls overhang
#:   at most 45 degrees and its roof is a flat disc of diameter r sqrt(2),
#:   bridged; it lies inside the sphere, so wherever a sphere fits it does.
#:   Cavities have this shape.
#: * 'silo': a ball socket: the lower half sphere plus a vertical cylinder of
#:   the same radius up to c + r, closed by a flat bridged roof. The print
#:   pauses just below the roof and the ball drops in (its top stays below the
#:   roof). Its top rim reaches past the sphere, so fits are checked there too.
#:   A taller silo (its roof higher above the ball, :func:`tall_silo`) puts the
#:   roofs of a chain's rods on a shared print layer (:mod:`rodcad.fabrication.roofs`).
VOIDS = ("sphere", "capped", "silo")


_CAPPED = 4.0 / 3.0 * math.pi - 2.0 * math.pi * (1 - 1 / math.sqrt(2)) ** 2 * (2 + 1 / math.sqrt(2)) / 3


def void_volume(kind: str, radius: float) -> float:
    """Volume (mm^3) of one void of shape ``kind`` (see :data:`VOIDS`) and radius (mm)."""
    r3 = radius**3
    if kind == "sphere":
        return 4.0 / 3.0 * math.pi * r3
    if kind == "capped":
        return _CAPPED * r3
    if kind == "silo":
        return 5.0 / 3.0 * math.pi * r3
    raise ValueError(f"unknown void shape {kind!r} (expected one of {', '.join(VOIDS)})")


def void_centroid(kind: str, radius: float) -> float:
    """Height (mm, along :data:`UP`) of a void's centroid above its centre."""
    # silo: half sphere below (-3r/8, volume 2/3 pi r^3) + cylinder above (r/2, pi r^3)
    return 0.15 * radius if kind == "silo" else 0.0


def silo_volume(radius: float, height: float | None = None) -> float:
    """Volume (mm^3) of a 'silo' socket of ``radius``: the lower half sphere plus a cylinder
    ``height`` mm tall above the centre (default: the radius, the plain silo)."""
    h = radius if height is None else height
    return 2.0 / 3.0 * math.pi * radius**3 + math.pi * radius**2 * h


def _silo_moment(radius: float, height: float) -> float:
    """First moment (mm^4) along :data:`UP` of a silo about its centre."""
    return math.pi * radius**2 * (height * height / 2 - radius * radius / 4)


def ball_offset(socket_radius: float, ball_mass: float, density: float, height: float | None = None) -> float:
    """How far (mm, along :data:`UP`) to raise a silo socket above the site it
    stands for, so that socket (plastic removed) and ball (at the socket centre)
    together act as a point mass at the site: a symmetric set of sites then
    leaves the rod's centre of mass where it was.

    Args:
        socket_radius: mm.
        ball_mass: g.
        density: plastic density (g/cm^3).
        height: the silo's roof above its centre (mm; default the radius).
    """
    h = socket_radius if height is None else height
    rho = density / 1000.0
    return rho * _silo_moment(socket_radius, h) / (ball_mass - rho * silo_volume(socket_radius, h))


def tall_silo(site: float, radius: float, ball_mass: float, density: float, roof: float, *,
              give_at: float | None = None) -> tuple[float, float]:
    """A silo socket whose flat roof is at ``roof`` (mm along :data:`UP`) and which, with its
    ball at its centre, still acts as a point mass at ``site`` (:func:`ball_offset` for a
    taller cylinder): (centre, height of the roof above the centre), both mm.

    The roof must be at least the plain silo's (site + its offset + the radius); a higher
    roof lengthens the cylinder above the ball, and the socket's centre rises a little with
    it, so the rod's centre of mass does not move.

    Args:
        give_at: where (mm along :data:`UP`) the plastic the taller socket takes is given
            back (the cavities' centroid, the rod's centre of mass), or None for the site
            itself. A socket of a row off that height (a rod with two rows) moves that
            plastic from ``give_at`` to its roof: its socket then stands for a point a
            little further from ``give_at`` than its site, so that the rod's first moment,
            and its centre of mass, stay.
    """
    rho = density / 1000.0
    plain = silo_volume(radius)

    def gap(h: float) -> float:
        moved = rho * (silo_volume(radius, h) - plain)  # g taken above the ball, given back at give_at
        acts = site if give_at is None else site + moved * (site - give_at) / (ball_mass - rho * silo_volume(radius, h))
        return acts + ball_offset(radius, ball_mass, density, h) + h - roof

    lo, hi = radius, max(roof - site, radius)
    if gap(lo) > 1e-9:
        raise ValueError(f"a roof at {roof:.4f} mm is below the plain socket's ({roof - gap(lo):.4f} mm)")
    while gap(hi) < 0:  # a row below give_at stands for a point that sinks as its roof rises
        hi *= 2
    for _ in range(80):  # gap rises with h: bisection to round-off
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if gap(mid) < 0 else (lo, mid)
    h = (lo + hi) / 2
    return roof - h, h


def silo_rim_points(centers: np.ndarray, radius: float, n: int = 16) -> np.ndarray:
    """Points on the top rims of silo sockets, where they reach past the sphere:
    (len(centers) * 2 n, 3), the rim at c + r up and the ring at c + 0.6 r up."""
    th = np.linspace(0, 2 * math.pi, n, endpoint=False)
    ring = np.stack([np.cos(th), np.zeros(n), np.sin(th)], axis=1) * radius
    rims = np.concatenate([ring + UP * radius, ring * 0.8 + UP * 0.6 * radius])
    return (np.asarray(centers, dtype=float)[:, None, :] + rims[None]).reshape(-1, 3)


def silo_top_points(centers: np.ndarray, radius: float, height: float, n: int = 24) -> np.ndarray:
    """Points on the upper part of silo sockets whose roofs are ``height`` above their
    centres: the roof's rim, a ring at half the radius and its centre, and rings on the
    cylinder every half radius below the roof ((len(centers) * m, 3))."""
    th = np.linspace(0, 2 * math.pi, n, endpoint=False)
    ring = np.stack([np.cos(th), np.zeros(n), np.sin(th)], axis=1) * radius
    levels = np.arange(height, -1e-9, -radius / 2)
    rims = [ring + UP * y for y in levels] + [ring / 2 + UP * height, UP[None] * height]
    pts = np.concatenate(rims)
    return (np.asarray(centers, dtype=float)[:, None, :] + pts[None]).reshape(-1, 3)


@dataclass(frozen=True)
class SphereLayout:
    """Equal spheres inside a rod.

    Attributes:
        radius: sphere radius (mm); 0 for an empty layout.
        centers: (n, 3) centres in the rod frame (mm).
        symmetry: the symmetry group kept (one of :data:`SYMMETRIES`) or ''.
        lattice: the lattice kind (one of :data:`LATTICES`) or ''.
        void: the shape of each void (one of :data:`VOIDS`).
    """

    radius: float
    centers: np.ndarray = field(repr=False)
    symmetry: str = ""
    lattice: str = ""
    void: str = "sphere"

    @property
    def count(self) -> int:
        return int(len(self.centers))

    @property
    def sphere_volume(self) -> float:
        """Volume of one void (mm^3), of shape :attr:`void`."""
        return void_volume(self.void, self.radius)

    @property
    def volume(self) -> float:
        """Total volume of the voids (mm^3)."""
        return self.count * self.sphere_volume

    @classmethod
    def empty(cls) -> SphereLayout:
        return cls(0.0, np.zeros((0, 3)), "")


def sphere_layout(clearance: Clearance, bounds: tuple[Sequence[float], Sequence[float]],
                  center: Sequence[float], radius: float, wall: float,
                  symmetries: Iterable[str] = SYMMETRIES, lattices: Iterable[str] = LATTICES, *,
                  void: str = "sphere", raise_by: float = 0.0, beat: int = 0) -> SphereLayout:
    """Most equal voids of ``radius`` that fit with ``wall`` everywhere, in a
    symmetric lattice layout centred on ``center``.

    Tries each lattice kind with offsets 0 and half a lattice step on each axis,
    and each symmetry group; returns the layout with the most voids (ties:
    the first found, so the result is deterministic).

    Args:
        clearance: signed distance to the solid's boundary (mm), vectorised.
        bounds: the solid's bounding box.
        center: centre of mass (mm), the centre of symmetry.
        radius: void radius (mm).
        wall: minimum wall to the boundary and between voids (mm).
        symmetries: symmetry groups to try.
        lattices: lattice kinds to try.
        void: void shape (:data:`VOIDS`). 'silo' sockets use the cubic
            lattice only (a silo's rim reaches past its sphere, so neighbours
            may only sit beside, above or diagonal to it) and their top rims
            are checked against the boundary too.
        raise_by: the voids sit this far (mm) above their symmetric sites along
            :data:`UP` (see :func:`ball_offset`); the returned centres are the
            raised ones.
        beat: only layouts of more voids than this are wanted: the empty layout when
            none has more (lattices with no more sites are not tried).
    """
    void_volume(void, radius)  # validates the kind
    need = radius + wall
    inner = (tuple(b + need for b in bounds[0]), tuple(b - need for b in bounds[1]))
    pitch = 2 * radius + wall
    lift = UP * raise_by
    best = SphereLayout.empty()
    most = int(beat)  # the count to beat
    symmetries = tuple(symmetries)
    if void == "silo":
        lattices = [k for k in lattices if k == "cubic"]
    for kind in lattices:
        for offset in ((ox, oy, oz) for ox in (0.0, 0.5) for oy in (0.0, 0.5) for oz in (0.0, 0.5)):
            pts = lattice_sites(inner, center, pitch, offset, kind)
            if len(pts) <= most:
                continue
            feasible = clearance(pts + lift) >= need
            if void == "silo" and feasible.any():
                idx = np.flatnonzero(feasible)
                rim = clearance(silo_rim_points(pts[idx] + lift, radius)).reshape(len(idx), -1)
                feasible[idx] = rim.min(axis=1) >= wall
            if feasible.sum() <= most:
                continue
            for sym in symmetries:
                near = lattice_image_map(inner, center, pitch, offset, kind, sym)
                keep = symmetric_subset(pts, feasible, center, sym, near=near)
                if keep.sum() > most:
                    best = SphereLayout(radius, pts[keep] + lift, sym, kind, void)
                    most = best.count
    return best


def sphere_layouts(clearance: Clearance, bounds: tuple[Sequence[float], Sequence[float]],
                   center: Sequence[float], radius: float, wall: float,
                   regions: Callable[[np.ndarray], np.ndarray], subsets: Sequence[np.ndarray],
                   symmetries: Iterable[str] = SYMMETRIES, lattices: Iterable[str] = LATTICES, *,
                   void: str = "sphere") -> list[SphereLayout]:
    """:func:`sphere_layout` for several sets of regions kept clear at once (the ball options
    of one rod, whose cavities must stay clear of different subsets of its sockets).

    Layout ``j`` is exactly ``sphere_layout`` with the clearance
    ``min(clearance(p), regions(p)[:, subsets[j]].min(axis=1))``: the lattices are laid
    once, the solid's clearance and each region's distance taken once per lattice, and only
    the choice of sites is made per subset.

    Args:
        clearance: signed distance to the solid's boundary (mm), vectorised.
        bounds, center, radius, wall, symmetries, lattices: as for :func:`sphere_layout`.
        regions: (n, 3) points -> (n, k) their distance (mm) from each of k regions.
        subsets: per layout wanted, the indices of the regions it keeps clear of.
        void: a void that needs no rim check ('silo' is not batched).
    """
    if void == "silo":
        raise ValueError("silo voids are laid one set at a time (sphere_layout)")
    void_volume(void, radius)  # validates the kind
    need = radius + wall
    inner = (tuple(b + need for b in bounds[0]), tuple(b - need for b in bounds[1]))
    pitch = 2 * radius + wall
    best = [SphereLayout.empty() for _ in subsets]
    most = [0] * len(subsets)
    symmetries = tuple(symmetries)
    for kind in lattices:
        for offset in ((ox, oy, oz) for ox in (0.0, 0.5) for oy in (0.0, 0.5) for oz in (0.0, 0.5)):
            pts = lattice_sites(inner, center, pitch, offset, kind)
            if len(pts) <= min(most, default=0):
                continue
            solid = clearance(pts) >= need
            room = np.flatnonzero(solid)
            clear = regions(pts[room]) >= need if len(room) else np.zeros((0, 0), dtype=bool)
            # (J, n): the sites each subset may use
            feasible = np.repeat(solid[None, :], len(subsets), axis=0)
            if len(room):
                for j, subset in enumerate(subsets):
                    if len(subset):
                        feasible[j, room] = clear[:, subset].all(axis=1)
            # only a subset with more feasible sites than its best so far can gain
            want = np.flatnonzero(feasible.sum(axis=1) > np.asarray(most))
            if not want.size:
                continue
            F = feasible[want]
            for sym in symmetries:  # (for each subset, the symmetries in the same order as sphere_layout)
                near = lattice_image_map(inner, center, pitch, offset, kind, sym)
                images = (near >= 0)[None] & F[:, np.maximum(near, 0)]
                keep = F & images.all(axis=1)
                for j, kj in zip(want, keep):
                    if kj.sum() > most[j]:
                        best[j] = SphereLayout(radius, pts[kj], sym, kind, void)
                        most[j] = best[j].count
    return best


def max_cavity_layout(clearance: Clearance, bounds: tuple[Sequence[float], Sequence[float]],
                      center: Sequence[float], wall: float, *, r_min: float = MIN_CAVITY_RADIUS,
                      r_max: float | None = None, void: str = "sphere") -> SphereLayout:
    """The symmetric lattice layout of equal cavities removing the most volume.

    Radii from ``r_max`` (default: half the smallest bounding-box side less a
    wall) down to ``r_min`` by factors of :data:`RADIUS_STEP` are tried.
    ``void`` is the cavity shape (:data:`VOIDS`).
    """
    if r_max is None:
        r_max = min(hi - lo for lo, hi in zip(*bounds)) / 2 - wall
    best = SphereLayout.empty()
    r = r_max
    while r >= r_min - 1e-12:
        # only a layout of more voids than ``beat`` removes more than the best so far
        each, bar = void_volume(void, r), best.volume + 1e-9
        beat = int(bar // each)
        while (beat + 1) * each <= bar:
            beat += 1
        while beat > 0 and beat * each > bar:
            beat -= 1
        layout = sphere_layout(clearance, bounds, center, r, wall, void=void, beat=beat)
        if layout.volume > best.volume + 1e-9:
            best = layout
        r *= RADIUS_STEP
    return best


def max_ball_layout(clearance: Clearance, bounds: tuple[Sequence[float], Sequence[float]],
                    center: Sequence[float], socket_diameter: float, wall: float, *,
                    void: str = "sphere", raise_by: float = 0.0) -> SphereLayout:
    """The symmetric lattice layout with the most ball sockets (``void``
    'silo' for the printable sockets, raised by ``raise_by``, see
    :func:`ball_offset`)."""
    return sphere_layout(clearance, bounds, center, socket_diameter / 2, wall, void=void, raise_by=raise_by)
