"""The fill chamber of rods printed to order: one mass range of 10:1 and more within one shell.

A family with a ``fill`` (:class:`rodcad.catalog.model.Fill`: loose dense shot, e.g. tungsten at
19.3 g/cm^3 and a packing fraction of 0.6) tunes every rod's mass with one chamber, closed by
the print, that is either EMPTY (air: the rod is lighter than its solid) or FILLED to its roof
with shot poured at a print pause (heavier). The chamber is a row of ``cells``: axis-aligned
boxes in the rod frame (x along the chord), side by side across the thickness (z) and
separated by a minimum wall, because a flat roof is printed as a bridge and a bridge is kept
no wider than a ball socket's roof (:data:`MAX_BRIDGE`, the rule the 'silo' sockets of
:mod:`rodcad.fabrication.layout` follow); their walls are vertical in print orientation (the
rod frame's +y up, :data:`rodcad.fabrication.layout.UP`), their floors lie on plastic.

Every cell is centred on the solid's centre of mass (x, y) and the cells are mirror images
across z = 0, so the plastic the chamber removes and the shot it holds both act at the centre
of mass: **the centre of mass does not move across the mass range**. The cells' height Hc
(y) and the longest length (x) that keep :attr:`Material.min_wall` from every face
(:class:`rodcad.catalog.fastgeom.RodClearance`, exact, sampled every :data:`GRID` mm; for curved
rods the boxes stay inside the arc band) are searched per rod (:func:`chamber_model`); a rod's
mass m then sets the chamber's length Lc in closed form (:func:`plan_chamber`):

    empty:  m = rho_pla (V_solid - V_c)                      for m <= rho_pla V_solid
    filled: m = rho_pla (V_solid - V_c) + rho_fill V_c       for m >= rho_pla V_solid

with V_c = cells x Hc x Tc x Lc and rho_fill = density x packing, so every mass from
rho_pla (V_solid - V_max) to rho_pla (V_solid - V_max) + rho_fill V_max is reachable
continuously. A chamber shorter than :data:`MIN_LENGTH` shrinks its section instead (same
centre): its cells get thinner (z) down to :data:`MIN_LENGTH`, keeping their roof where every
other chamber of the rod's shape has it (one pause height), and only then lower; one holding
less than :data:`MIN_VOLUME` is left out (the plain solid).

A curved rod's body is an arc band, so one straight box loses height to the band's sag. Its
cells may instead be STEPPED (:func:`_stepped`): nested boxes centred on the centre of mass
in x, sharing one roof (one pause), each shorter one deeper, their floors following the
band; the floors are raised together (or the roof lowered) until the chamber's centroid is
the centre of mass, and every length is scaled together, so the centroid stays put across
the range. A rod keeps the stepped chamber where it holds more than the straight one.

The pause height is the cells' roof (the top of the shot) in print orientation. Units: mm,
mm^3, g; densities g/cm^3.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from rodcad.catalog.fastgeom import RodClearance, rod_mass_properties
from rodcad.catalog.model import Fill, RodGeometry, RodType

__all__ = ["CHAMBER_VERSION", "Chamber", "ChamberModel", "GRID", "MAX_BRIDGE", "MIN_LENGTH", "MIN_VOLUME",
           "chamber_model", "fill_numbers", "plan_chamber"]

#: Bump when the largest chamber of a rod changes (the mass ranges and the seeds derive from
#: it; a short chamber's shape, built anew every time, does not enter them).
CHAMBER_VERSION = "2"

#: Widest flat roof bridged over a chamber cell (mm): the roof of the 6.2 mm sockets of the
#: shipped catalogs' 6 mm balls (a 'silo' socket's roof is a disc of the socket's diameter).
MAX_BRIDGE = 6.2

#: Spacing of the points at which a cell's faces are checked against the minimum wall (mm).
GRID = 0.2

#: The cells' ends are moved in by this (mm) from the longest length the samples allow: it
#: covers what lies between the samples (the section's planar walls are met exactly).
BACKOFF = GRID

#: Round-off allowed on the minimum wall where a cell face is parallel to the rod's (mm).
WALL_TOL = 1e-7

#: Shortest chamber (x, mm): below it the cells' section shrinks instead of their length.
MIN_LENGTH = 1.0

#: A chamber holding less than this (mm^3) is left out (the rod is its plain solid).
MIN_VOLUME = 1e-3

#: Section heights tried per rod: fractions of the largest the section allows.
HEIGHT_STEPS = 12


@dataclass(frozen=True)
class ChamberModel:
    """The largest chamber of one rod's solid.

    Attributes:
        solid_volume: the plain solid's volume (mm^3).
        center: the solid's centre of mass (x, y) (mm): every cell is centred on it.
        height: cell height Hc along y (mm): the print's up direction.
        thickness: each cell's thickness Tc along z (mm): the width of its bridged roof.
        cells_z: the cells' centres along z (mm), symmetric about 0.
        max_length: the longest cell length Lc along x the minimum wall allows (mm); 0 if
            no cell fits.
    """

    solid_volume: float
    center: tuple[float, float]
    height: float
    thickness: float
    cells_z: tuple[float, ...]
    max_length: float
    slabs: tuple[tuple[float, float, float], ...] | None = None

    @property
    def area(self) -> float:
        """Section of all cells together across x (mm^2), per mm of the longest length."""
        if self.slabs:
            return len(self.cells_z) * self.thickness * sum(f * (y1 - y0) for f, y0, y1 in self.slabs)
        return len(self.cells_z) * self.height * self.thickness

    @property
    def max_volume(self) -> float:
        """The largest chamber volume (mm^3)."""
        return self.area * self.max_length


@dataclass(frozen=True)
class Chamber:
    """A chamber as built for one mass.

    Attributes:
        center: (x, y) centre of every cell (mm, rod frame).
        length: Lc along x (mm).
        height: Hc along y (mm).
        thickness: Tc along z per cell (mm).
        cells_z: the cells' centres along z (mm).
        filled: True when the chamber is filled with shot, False when empty (air).
        fill_mass: grams of shot it holds (0 when empty).
        slabs: a stepped chamber (curved rods): per step (fraction of ``length``, floor y,
            top y), stacked from the roof down, each narrower than the one above (their
            centroid is ``center``); None: one box of ``height`` centred on ``center``.
    """

    center: tuple[float, float]
    length: float
    height: float
    thickness: float
    cells_z: tuple[float, ...]
    filled: bool
    fill_mass: float
    slabs: tuple[tuple[float, float, float], ...] | None = None

    @property
    def volume(self) -> float:
        if self.slabs:
            return len(self.cells_z) * self.length * self.thickness * sum(f * (y1 - y0) for f, y0, y1 in self.slabs)
        return len(self.cells_z) * self.length * self.height * self.thickness

    @property
    def roof_y(self) -> float:
        """Height of the cells' roofs in the rod frame (mm, along y = print up)."""
        if self.slabs:
            return max(y1 for _, _, y1 in self.slabs)
        return self.center[1] + self.height / 2

    def cell_boxes(self) -> list[list[tuple[tuple[float, float, float], tuple[float, float, float]]]]:
        """Per cell (along z), its boxes as ((xmin, ymin, zmin), (xmax, ymax, zmax)) in the rod
        frame (mm): one, or a stepped cell's nested boxes (each from its floor to the roof;
        their union is the cell)."""
        (cx, cy), c = self.center, self.thickness / 2
        if not self.slabs:
            a, b = self.length / 2, self.height / 2
            return [[((cx - a, cy - b, z - c), (cx + a, cy + b, z + c))] for z in self.cells_z]
        roof = self.roof_y
        return [[((cx - f * self.length / 2, y0, z - c), (cx + f * self.length / 2, roof, z + c))
                 for f, y0, _ in self.slabs] for z in self.cells_z]

    def boxes(self) -> list[tuple[tuple[float, float, float], tuple[float, float, float]]]:
        """Every box of every cell (see :meth:`cell_boxes`)."""
        return [b for cell in self.cell_boxes() for b in cell]

    def to_json(self) -> dict[str, object]:
        out: dict[str, object] = {"center": list(self.center), "length": self.length, "height": self.height,
                                  "thickness": self.thickness, "cells_z": list(self.cells_z), "filled": self.filled,
                                  "fill_mass": self.fill_mass}
        if self.slabs:
            out["slabs"] = [list(x) for x in self.slabs]
        return out


def _cells(thickness: float, wall: float, bridge: float) -> tuple[float, tuple[float, ...]]:
    """(cell thickness, cell centres along z): the fewest cells no wider than ``bridge`` that
    fill the thickness less a wall at both faces and between cells."""
    inner = thickness - 2 * wall
    if inner <= 0:
        return 0.0, ()
    n = max(1, math.ceil((inner + wall) / (bridge + wall) - 1e-9))
    tz = (inner - (n - 1) * wall) / n
    first = -inner / 2 + tz / 2
    return tz, tuple(first + k * (tz + wall) for k in range(n))


def _face_grid(lo: np.ndarray, hi: np.ndarray, skip_x: bool = False) -> np.ndarray:
    """Points every :data:`GRID` mm or closer on the faces of a box (the x faces unless
    ``skip_x``)."""
    axes = [np.linspace(lo[k], hi[k], max(2, math.ceil((hi[k] - lo[k]) / GRID) + 1)) for k in range(3)]
    pts = []
    for k in range(1 if skip_x else 0, 3):
        i, j = [m for m in range(3) if m != k]
        u, v = np.meshgrid(axes[i], axes[j], indexing="ij")
        for side in (lo[k], hi[k]):
            p = np.empty((u.size, 3))
            p[:, i], p[:, j], p[:, k] = u.ravel(), v.ravel(), side
            pts.append(p)
    return np.concatenate(pts)


def _max_half_length(clear: RodClearance, cx: float, cy: float, hc: float, tz: float, z0: float,
                     reach: float, need: float) -> float:
    """The longest half length (mm) of a cell of height ``hc`` and thickness ``tz`` centred on
    (cx, cy, z0) whose faces all keep ``need`` mm of clearance (0 if none)."""
    lo = np.array([cx - reach, cy - hc / 2, z0 - tz / 2])
    hi = np.array([cx + reach, cy + hc / 2, z0 + tz / 2])
    side = _face_grid(lo, hi, skip_x=True)  # the y and z faces over the longest reach
    ok_side = clear(side) >= need
    dx = np.abs(side[:, 0] - cx)
    bad = dx[~ok_side]
    limit = float(bad.min()) - BACKOFF if bad.size else reach
    if limit <= 0:
        return 0.0

    def fits(a: float) -> bool:
        ends = _face_grid(np.array([cx - a, lo[1], lo[2]]), np.array([cx + a, hi[1], hi[2]]))
        ends = ends[np.abs(np.abs(ends[:, 0] - cx) - a) < 1e-12]
        return bool((clear(ends) >= need).all())

    if fits(limit):
        return limit
    a0, a1 = 0.0, limit
    if not fits(min(GRID, limit)):
        return 0.0
    a0 = min(GRID, limit)
    while a1 - a0 > 0.01:
        mid = (a0 + a1) / 2
        a0, a1 = (mid, a1) if fits(mid) else (a0, mid)
    return max(a0 - BACKOFF, 0.0)


@lru_cache(maxsize=4096)
def chamber_model(g: RodGeometry, min_wall: float, bridge: float = MAX_BRIDGE) -> ChamberModel:
    """The largest chamber of the solid ``build_rod(g)`` (see the module): per section height,
    the longest cells that keep ``min_wall`` from every face (:data:`BACKOFF`); the height
    that holds the most."""
    volume, (cx, cy, _) = rod_mass_properties(g)
    tz, zs = _cells(g.thickness, min_wall, bridge)
    if not zs:
        return ChamberModel(volume, (cx, cy), 0.0, 0.0, (), 0.0)
    clear = RodClearance(g)
    (x0, y0, _), (x1, y1, _) = clear.bounds
    reach = max(0.0, min(cx - x0, x1 - cx))
    need = min_wall - WALL_TOL
    top = 2 * (min(y1 - cy, cy - y0) - min_wall)  # the section's bound (straight rods: exact)
    z0 = max(zs)  # the cells are mirror images across z = 0 (so is the solid): check one
    best = (0.0, 0.0, 0.0)
    for k in range(HEIGHT_STEPS, 0, -1):
        hc = top * k / HEIGHT_STEPS - (1e-6 if k == HEIGHT_STEPS else 0.0)
        a = _max_half_length(clear, cx, cy, hc, tz, z0, reach, need)
        if hc * a > best[0]:
            best = (hc * a, hc, a)
    _, hc, a = best
    box = ChamberModel(float(volume), (float(cx), float(cy)), float(hc), float(tz), tuple(float(z) for z in zs),
                       float(2 * a))
    if g.curvature == 0:
        return box
    stepped = _stepped(clear, box, reach, need)
    return stepped if stepped is not None and stepped.max_volume > box.max_volume else box


#: Steps of a stepped chamber (nested boxes; the shortest is 1/STEPS of the longest).
STEPS = 4

#: Sampling of the columns a stepped chamber is fitted in (mm, along y).
Y_GRID = 0.05


def _slabs_centroid(slabs) -> tuple[float, float]:
    """(area, centroid y) of slabs (fraction, y0, y1) per unit length."""
    area = sum(f * (y1 - y0) for f, y0, y1 in slabs)
    return area, (sum(f * (y1 * y1 - y0 * y0) / 2 for f, y0, y1 in slabs) / area if area > 0 else 0.0)


def _stacked(fracs, roof: float, floors) -> tuple[tuple[float, float, float], ...]:
    """Slabs from a roof and floors (deepest last, each below the one before)."""
    out, top = [], roof
    for f, y in zip(fracs, floors):
        if y < top - 1e-12:
            out.append((float(f), float(y), float(top)))
            top = y
    return tuple(out)


def _stepped(clear: RodClearance, box: ChamberModel, reach: float, need: float) -> ChamberModel | None:
    """The largest stepped chamber (see the module), or None: per column x, the y interval
    around the centre of mass that keeps ``need`` from every face (sampled every
    :data:`Y_GRID`, less one sample), then per longest length the roof (the lowest top over
    it) and each step's floor (the highest bottom over its length), the floors raised together
    (or the roof lowered) until the centroid is the centre of mass; checked on the faces of
    every box as the straight chamber is."""
    cx, cy = box.center
    tz, zs = box.thickness, box.cells_z
    z0 = max(zs)
    (_, y0, _), (_, y1, _) = clear.bounds
    xs = np.arange(0.0, reach, GRID)
    ys = np.arange(y0, y1 + Y_GRID, Y_GRID)
    zc = (z0 - tz / 2, z0, z0 + tz / 2)
    X, Y, Z = np.meshgrid(cx + xs, ys, zc, indexing="ij")
    ok = (clear(np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])) >= need).reshape(X.shape).all(axis=2)
    # the solid is symmetric about the centre of mass in x only for symmetric rods: both sides
    X2 = cx - xs[:, None, None] + 0 * Y
    ok &= (clear(np.column_stack([X2.ravel(), Y.ravel(), Z.ravel()])) >= need).reshape(X.shape).all(axis=2)
    j0 = int(np.searchsorted(ys, cy))
    top = np.full(xs.size, -np.inf)
    bot = np.full(xs.size, np.inf)
    for i in range(xs.size):
        col = ok[i]
        if not (col[j0 - 1] and col[j0]):
            break
        up = j0 + int(np.argmin(np.append(col[j0:], False)))  # first blocked above
        dn = j0 - 1 - int(np.argmin(np.append(col[j0 - 1::-1], False)))
        top[i], bot[i] = ys[up - 1] - Y_GRID, ys[dn + 1] + Y_GRID
    n_ok = int(np.argmax(~np.isfinite(top))) if not np.isfinite(top).all() else xs.size
    if n_ok < 2:
        return None
    top_env = np.minimum.accumulate(top[:n_ok])
    bot_env = np.maximum.accumulate(bot[:n_ok])
    fracs = [(STEPS - k) / STEPS for k in range(STEPS)]
    best = None
    for i in range(1, n_ok):
        a = xs[i] - BACKOFF
        if a <= 0:
            continue
        roof = float(top_env[i])
        floors = [float(bot_env[min(int(np.searchsorted(xs, a * f + BACKOFF)), n_ok - 1)]) for f in fracs]
        floors = list(np.maximum.accumulate(floors[::-1])[::-1])  # never deeper than a shorter step
        floors = [min(y, roof) for y in floors]
        slabs = _fit_centroid(fracs, roof, floors, cy)
        if slabs is None:
            continue
        vol = _slabs_centroid(slabs)[0] * 2 * a
        if best is None or vol > best[0]:
            best = (vol, a, slabs)
    if best is None:
        return None
    _, a, slabs = best
    for f, ylo, _ in slabs:  # every box, floor to roof, on the exact clearance as the straight chamber
        lo = np.array([cx - a * f, ylo, z0 - tz / 2])
        hi = np.array([cx + a * f, slabs[0][2], z0 + tz / 2])
        if not (clear(_face_grid(lo, hi)) >= need).all():
            return None
    return ChamberModel(box.solid_volume, box.center, float(slabs[0][2] - slabs[-1][1]), tz, zs, float(2 * a), slabs)


def _fit_centroid(fracs, roof: float, floors, cy: float):
    """Slabs whose centroid is ``cy``: the floors raised to a common level (a centroid below
    cy) or the roof lowered (above), by bisection to round-off; None if none."""
    def slabs_at(level: float, r: float):
        return _stacked(fracs, r, [max(y, level) for y in floors])

    s = slabs_at(-math.inf, roof)
    if not s:
        return None
    area, c = _slabs_centroid(s)
    if abs(c - cy) <= 1e-12:
        return s
    if c < cy:  # too deep: raise the floors together
        lo, hi = min(floors), roof
        f = lambda v: _slabs_centroid(slabs_at(v, roof))[1] if slabs_at(v, roof) else roof
        if f(hi - 1e-9) < cy:
            return None
        return slabs_at(_bisect(f, lo, hi, cy)[1], roof)
    lo, hi = floors[0], roof  # too high: lower the roof
    g = lambda r: _slabs_centroid(slabs_at(-math.inf, r))[1] if slabs_at(-math.inf, r) else -math.inf
    if g(lo + 1e-9) > cy:
        return None
    return slabs_at(-math.inf, _bisect(g, lo, hi, cy)[0])


def _bisect(fn, lo: float, hi: float, y: float) -> tuple[float, float]:
    """The bracket [lo, hi] of where the increasing ``fn`` crosses ``y``, bisected to 1e-13."""
    for _ in range(200):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if fn(mid) < y else (lo, mid)
        if hi - lo <= 1e-13:
            break
    return lo, hi


def _model(rod: RodType) -> ChamberModel:
    return chamber_model(rod.geometry, rod.material.min_wall)


def fill_numbers(rod: RodType) -> tuple[float, tuple[float, float], tuple[float, float]]:
    """(solid mass, centre of mass (along, perp), (m_min, m_max)) (g, mm) of a rod with a fill:
    its chamber at its largest, empty and filled."""
    if rod.fill is None:
        raise ValueError(f"rod {rod.name!r} has no fill")
    mdl = _model(rod)
    rho = rod.material.density / 1000.0
    solid = mdl.solid_volume * rho
    lightest = (mdl.solid_volume - mdl.max_volume) * rho
    return solid, mdl.center, (lightest, lightest + rod.fill.effective_density / 1000.0 * mdl.max_volume)


def plan_chamber(rod: RodType, target: float) -> tuple[Chamber | None, float, str]:
    """The chamber that makes ``rod`` weigh ``target`` g (clipped to its range).

    Returns:
        (chamber or None for the plain solid, the mass built, '' or why the target was clipped).
    """
    fill: Fill | None = rod.fill
    if fill is None:
        raise ValueError(f"rod {rod.name!r} has no fill")
    mdl = _model(rod)
    rho = rod.material.density / 1000.0
    solid, _, (lo, hi) = fill_numbers(rod)
    m = min(max(float(target), lo), hi)
    message = "" if m == target or abs(m - target) <= 1e-9 * target else (
        f"{target:.3f} g is outside its range [{lo:.3f}, {hi:.3f}] g (built at {m:.3f} g)")
    filled = m > solid
    per_mm3 = (fill.effective_density / 1000.0 - rho) if filled else rho
    volume = abs(m - solid) / per_mm3
    if volume < MIN_VOLUME or mdl.area <= 0:
        return None, solid, message
    length, scale, thin = volume / mdl.area, 1.0, 1.0
    if length < MIN_LENGTH and mdl.max_length >= MIN_LENGTH:  # a short chamber: a smaller section,
        length = MIN_LENGTH  # thinner cells first (the roof stays: one pause height for every rod),
        keep = volume / (mdl.area * MIN_LENGTH)  # then lower ones
        thin = max(keep, min(1.0, MIN_LENGTH / mdl.thickness))
        scale = keep / thin
    length = min(length, mdl.max_length)
    hc, tz = mdl.height * scale, mdl.thickness * thin
    cy = mdl.center[1]
    slabs = None if not mdl.slabs else tuple((f, cy + (y0 - cy) * scale, cy + (y1 - cy) * scale)
                                             for f, y0, y1 in mdl.slabs)
    chamber = Chamber(mdl.center, length, hc, tz, mdl.cells_z, filled, 0.0, slabs)
    grams = chamber.volume * fill.effective_density / 1000.0 if filled else 0.0
    chamber = Chamber(mdl.center, length, hc, tz, mdl.cells_z, filled, grams, slabs)
    return chamber, (mdl.solid_volume - chamber.volume) * rho + grams, message
