"""Mass properties and clearance of a rod's solid without the CAD kernel: fast, exact
functions of its parameters (:class:`rodcad.catalog.model.RodGeometry`).

The solid :func:`rodcad.cad.solids.build_rod` makes is, in each of three z-bands, the
extrusion of a plane region bounded by line segments and circular arcs:

* the outline: the body (the straight bar, or the band of half-width h/2 around the
  centreline arc with straight stubs past the axes) less the four end-cut prisms;
* ``mid`` (``|z| <= a``, a = tongue_thickness / 2): the outline plus the tongue knuckle
  disc, less the hinge zone at the fork joint;
* ``gap`` (``a < |z| < a + layer_gap``): the outline less both hinge zones;
* ``out`` (``a + layer_gap <= |z| <= t/2``): the outline plus the fork knuckle discs,
  less the hinge zone at the tongue joint;
* in every band less the pin holes.

Each band's boundary is found exactly: every primitive curve (body edges and arcs, the
cut prisms' edges, the six circles) is split where it meets any other, and a piece
bounds a band's region where the region's membership differs on its two sides (tested
:data:`SIDE` mm off its midpoint). Area and first moments follow from Green's theorem
in closed form (:func:`rod_mass_properties`, agreeing with the B-rep to about 1e-12),
and the clearance (:class:`RodClearance`) is the exact distance to the layered solid:
the nearest point of each band's boundary, combined with the band's z-distance.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from rodcad.catalog.model import RodGeometry

__all__ = ["RodClearance", "rod_mass_properties"]

#: Offset of the side points that decide whether a boundary piece bounds a region (mm).
SIDE = 1e-6

#: Curve parameters (segment fraction, arc angle in rad) closer than this to a curve's
#: end do not split it.
TOL = 1e-9

#: RodClearance subtracts this (mm), so that rounding never makes it exceed the solid's.
SAFETY = 1e-9

TAU = 2 * math.pi


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _first_rows(a: np.ndarray) -> np.ndarray:
    """Indices, in order, of the rows of ``a`` that equal no earlier row (NumPy's
    ``np.unique(a, axis=0, return_index=True)`` sorted, without its structured-dtype sort)."""
    order = np.lexsort(a.T[::-1])  # stable: equal rows keep their order
    rows = a[order]
    first = np.ones(len(a), dtype=bool)
    first[1:] = (rows[1:] != rows[:-1]).any(axis=1)
    return np.sort(order[first])


class _Outline:
    """The rod's plane primitives, their membership tests and the bands' boundaries."""

    def __init__(self, g: RodGeometry) -> None:
        h, L, hg = g.height, g.length, g.hinge
        self.g = g
        self.h2 = h / 2
        self.stub = g.stub  # rodcad.cad.solids._stub_length
        self.straight = g.curvature == 0
        grad = g.graduated
        lo = -h / 2
        #: the body's band (lo, hi) and, for a lower body, the family's band kept in the end blocks
        self.body = (lo, g.body_top if grad else h / 2)
        self.thin = grad and g.body_h < h
        self.fam = (lo, h / 2)
        offsets = sorted({lo, self.body[1], *((h / 2,) if self.thin else ())})
        psi_s = math.radians(g.half_angle_deg)
        self.frames = []  # (pin P, outward tangent u, +y normal v), as rodcad.cad.solids._frame
        for p, fwd, sgn in (((0.0, 0.0), -psi_s, -1.0), ((L, 0.0), psi_s, 1.0)):
            f = np.array([math.cos(fwd), math.sin(fwd)])
            self.frames.append((np.array(p), sgn * f, np.array([-f[1], f[0]])))
        segs: list[tuple[np.ndarray, np.ndarray]] = []
        arcs: list[tuple[float, float, float, float, float]] = []  # cx, cy, r, start, sweep
        if self.straight:
            x0, x1 = -self.stub, L + self.stub
            segs += [(np.array((x0, w)), np.array((x1, w))) for w in offsets]
            for w0, w1 in zip(offsets[:-1], offsets[1:]):
                segs += [(np.array((x0, w0)), np.array((x0, w1))), (np.array((x1, w0)), np.array((x1, w1)))]
        else:
            self.rho = 1 / abs(g.curvature)
            self.sigma = sigma = 1 if g.curvature > 0 else -1
            psi = abs(psi_s)
            self.centre = np.array([L / 2, sigma * self.rho * math.cos(psi)])
            start = math.radians(-90.0 if sigma > 0 else 90.0) - psi
            for w in offsets:
                arcs.append((*self.centre, self.rho - sigma * w, start, 2 * psi))
            for p, u, v in self.frames:  # the stubs' sides and far ends (not the edge the band continues)
                segs += [(p + v * w, p + v * w + u * self.stub) for w in offsets]
                segs += [(p + v * w0 + u * self.stub, p + v * w1 + u * self.stub)
                         for w0, w1 in zip(offsets[:-1], offsets[1:])]
        #: the end blocks (rectangles: corner, unit edge directions, lengths) of a graduated rod
        self.blocks = []
        for rect in g.end_blocks():
            c = [np.array(q) for q in rect]
            segs += [(c[i], c[(i + 1) % 4]) for i in range(4)]
            e1, e2 = c[1] - c[0], c[3] - c[0]
            self.blocks.append((c[0], e1 / np.hypot(*e1), float(np.hypot(*e1)), e2 / np.hypot(*e2),
                                float(np.hypot(*e2))))
        self.wedges = []  # (corner A, u, n, tan, reach, far): as rodcad.cad.solids._end_cuts
        for (p, u, v), end in zip(self.frames, (g.first, g.second)):
            a = p - end.setback * u
            far = self.stub + 1.0 + end.setback
            for side, chamfer in ((1, end.top_chamfer), (-1, end.bottom_chamfer)):
                n = side * v
                tan_b = math.tan(math.radians(chamfer))
                reach = g.cut_reach(side, tan_b)
                top = a + n * reach - u * reach * tan_b
                c = [a, a + u * far, a + u * far + n * reach, top]
                segs += [(c[i], c[(i + 1) % 4]) for i in range(4)]
                self.wedges.append((a, u, n, tan_b, reach, far))
        self.radii = (hg.knuckle_radius, hg.zone_radius, hg.hole_diameter / 2)
        for r in self.radii:
            for p, _, _ in self.frames:
                arcs.append((p[0], p[1], r, 0.0, TAU))
        # coincident curves would count twice: keep one of each (its ends in either order)
        P, Q = np.array([s[0] for s in segs]), np.array([s[1] for s in segs])
        swap = ((Q[:, 0] < P[:, 0]) | ((Q[:, 0] == P[:, 0]) & (Q[:, 1] < P[:, 1])))[:, None]
        keep = _first_rows(np.hstack([np.where(swap, Q, P), np.where(swap, P, Q)]).round(12))
        self.A, self.B = P[keep], Q[keep]
        arcs_a = np.array(arcs)
        self.arcs = arcs_a[_first_rows(arcs_a.round(12))]
        a_half, gap, t = hg.tongue_thickness / 2, hg.layer_gap, g.thickness
        self.a, self.gap = a_half, gap
        m = min(t, g.body_t) / 2 if grad else t / 2
        self.t2 = max(t, g.body_t) / 2 if grad else t / 2
        forks = tuple(j for j in (0, 1) if hg.knuckle(j) == "fork")
        tongues = tuple(j for j in (0, 1) if hg.knuckle(j) == "tongue")
        #: per z-layer: (z from, z to, knuckle discs it adds, joints whose zone it clears,
        #: 'all' / 'in' (only within the fork ends' blocks) / 'out' (clear of every block))
        self.layers = [(0.0, a_half, tongues, forks, "all"), (a_half, a_half + gap, (), (0, 1), "all"),
                       (a_half + gap, m, forks, tongues, "all")]
        if grad and g.body_t != t:
            self.layers.append((m, self.t2, forks, tongues, "in") if g.body_t < t else
                               (m, self.t2, (), tongues, "out"))
        self.fork_blocks = forks
        #: total thickness of each layer (both signs of z)
        self.thick = np.array([2 * (z1 - z0) for z0, z1, *_ in self.layers])
        self._pieces()

    # -- membership ------------------------------------------------------------------

    def _band(self, x: np.ndarray, y: np.ndarray, lo: float, hi: float) -> np.ndarray:
        """Points in the raw bar between offsets lo and hi (stubs included)."""
        if self.straight:
            return (y >= lo) & (y <= hi) & (x >= -self.stub) & (x <= self.g.length + self.stub)
        (p0, u0, _), (p1, u1, _) = self.frames
        cx, cy = self.centre
        w = self.sigma * (self.rho - np.sqrt((x - cx) ** 2 + (y - cy) ** 2))
        band = ((w >= lo) & (w <= hi) & ((x - p0[0]) * u0[0] + (y - p0[1]) * u0[1] <= 0)
                & ((x - p1[0]) * u1[0] + (y - p1[1]) * u1[1] <= 0))
        for p, u, v in self.frames:
            dx, dy = x - p[0], y - p[1]
            along = dx * u[0] + dy * u[1]
            off = dx * v[0] + dy * v[1]
            band |= (along >= 0) & (along <= self.stub) & (off >= lo) & (off <= hi)
        return band

    def _block(self, j: int, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        c, d1, n1, d2, n2 = self.blocks[j]
        s1 = (x - c[0]) * d1[0] + (y - c[1]) * d1[1]
        s2 = (x - c[0]) * d2[0] + (y - c[1]) * d2[1]
        return (s1 >= 0) & (s1 <= n1) & (s2 >= 0) & (s2 <= n2)

    def inside(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """(layers, n) bool: whether plane points lie in each z-layer's region (mid, gap,
        out and, on a graduated rod of another thickness, its outer layer)."""
        body = self._band(x, y, *self.body)
        blocks = [self._block(j, x, y) for j in range(len(self.blocks))]
        if self.thin:
            body |= self._band(x, y, *self.fam) & (blocks[0] | blocks[1])
        for a, u, n, tan_b, reach, far in self.wedges:
            dx, dy = x - a[0], y - a[1]
            xp = dx * u[0] + dy * u[1]
            yp = dx * n[0] + dy * n[1]
            body &= ~((yp >= 0) & (yp <= reach) & (xp <= far) & (xp >= -yp * tan_b))
        kr2, zr2, hr2 = (r * r for r in self.radii)
        d2 = [(x - p[0]) ** 2 + (y - p[1]) ** 2 for p, _, _ in self.frames]
        holes = (d2[0] <= hr2) | (d2[1] <= hr2)
        out = np.empty((len(self.layers), len(x)), dtype=bool)
        for i, (_, _, knuckles, zones, where) in enumerate(self.layers):
            region = body.copy()
            if where == "in":
                region &= np.logical_or.reduce([blocks[j] for j in self.fork_blocks])
            elif where == "out":
                region &= ~(blocks[0] | blocks[1])
            for j in knuckles:
                region |= d2[j] <= kr2
            for j in zones:
                region &= d2[j] > zr2
            out[i] = region & ~holes
        return out

    # -- boundary pieces -------------------------------------------------------------

    def _pieces(self) -> None:
        """Split every curve where it meets another and classify the pieces per band."""
        A, B, arcs = self.A, self.B, self.arcs
        D = B - A
        m = len(A)
        C, R, T0, SW = arcs[:, :2], arcs[:, 2], arcs[:, 3], arcs[:, 4]
        seg_i, seg_t, arc_i, arc_t = [np.arange(m)] * 2, [np.zeros(m), np.ones(m)], [], []
        k = len(C)
        arc_i += [np.arange(k)] * 2
        arc_t += [np.zeros(k), SW.copy()]
        seglen = np.hypot(D[:, 0], D[:, 1])
        with np.errstate(divide="ignore", invalid="ignore"):
            # segment with segment
            den = _cross(D[:, None, :], D[None, :, :])
            w = A[None, :, :] - A[:, None, :]
            t = _cross(w, D[None, :, :]) / den
            s = _cross(w, D[:, None, :]) / den
            ok = ((np.abs(den) > 1e-12 * np.outer(seglen, seglen)) & (t > TOL) & (t < 1 - TOL)
                  & (s >= -TOL) & (s <= 1 + TOL))
            i, _ = np.nonzero(ok)
            seg_i.append(i)
            seg_t.append(t[ok])
            # segment with arc
            f = A[:, None, :] - C[None, :, :]
            qa = (D * D).sum(-1)[:, None]
            qb = 2 * (f * D[:, None, :]).sum(-1)
            qc = (f * f).sum(-1) - R[None, :] ** 2
            disc = qb * qb - 4 * qa * qc
            sq = np.sqrt(np.maximum(disc, 0.0))
            for sign in (-1.0, 1.0):
                t = (-qb + sign * sq) / (2 * qa)
                P = A[:, None, :] + t[..., None] * D[:, None, :]
                rel = (np.arctan2(P[..., 1] - C[:, 1], P[..., 0] - C[:, 0]) - T0) % TAU
                on_arc = (rel <= SW + TOL) | (rel >= TAU - TOL)
                ok = (disc >= 0) & on_arc & (t > TOL) & (t < 1 - TOL)
                seg_i.append(np.nonzero(ok)[0])
                seg_t.append(t[ok])
                ok = (disc >= 0) & (t >= -TOL) & (t <= 1 + TOL) & (rel > TOL) & (rel < SW - TOL)
                arc_i.append(np.nonzero(ok)[1])
                arc_t.append(rel[ok])
            # arc with arc
            dC = C[None, :, :] - C[:, None, :]
            dd = np.hypot(dC[..., 0], dC[..., 1])
            Rc, Rd = R[:, None], R[None, :]
            ok0 = (dd > 1e-12) & (dd <= Rc + Rd) & (dd >= np.abs(Rc - Rd))
            alpha = np.arccos(np.clip((Rc**2 + dd**2 - Rd**2) / (2 * Rc * dd), -1, 1))
            base = np.arctan2(dC[..., 1], dC[..., 0])
            for sign in (-1.0, 1.0):
                ang = base + sign * alpha
                px, py = C[:, None, 0] + Rc * np.cos(ang), C[:, None, 1] + Rc * np.sin(ang)
                rel_c = (ang - T0[:, None]) % TAU
                rel_d = (np.arctan2(py - C[None, :, 1], px - C[None, :, 0]) - T0[None, :]) % TAU
                ok = (ok0 & (rel_c > TOL) & (rel_c < SW[:, None] - TOL)
                      & ((rel_d <= SW[None, :] + TOL) | (rel_d >= TAU - TOL)))
                arc_i.append(np.nonzero(ok)[0])
                arc_t.append(rel_c[ok])

        def split(idx: list[np.ndarray], par: list[np.ndarray]) -> tuple[np.ndarray, ...]:
            idx_a, par_a = np.concatenate(idx), np.concatenate(par)
            order = np.lexsort((par_a, idx_a))
            idx_a, par_a = idx_a[order], par_a[order]
            keep = (idx_a[1:] == idx_a[:-1]) & (par_a[1:] - par_a[:-1] > 1e-12)
            return idx_a[:-1][keep], par_a[:-1][keep], par_a[1:][keep]

        si, sa, sb = split(seg_i, seg_t)
        ai, aa, ab = split(arc_i, arc_t)
        # midpoints and left normals (arcs run counter-clockwise)
        d = D[si]
        mid_s = A[si] + 0.5 * (sa + sb)[:, None] * d
        nrm_s = np.stack([-d[:, 1], d[:, 0]], 1) / seglen[si][:, None]
        th = T0[ai] + 0.5 * (aa + ab)
        cs = np.stack([np.cos(th), np.sin(th)], 1)
        mid_a = C[ai] + R[ai][:, None] * cs
        mid = np.concatenate([mid_s, mid_a])
        nrm = np.concatenate([nrm_s, -cs])
        both = self.inside(*np.concatenate([mid + SIDE * nrm, mid - SIDE * nrm]).T)
        left, right = both[:, :len(mid)], both[:, len(mid):]
        orient = left.astype(np.int8) - right.astype(np.int8)  # (3, pieces)
        ns = len(si)
        self.seg_pieces = (si, sa, sb, orient[:, :ns])
        self.arc_pieces = (ai, aa, ab, orient[:, ns:])

    def moments(self) -> tuple[float, float, float]:
        """Volume (mm^3) and first moments about x and y (mm^4) of the solid."""
        ox = self.g.length / 2  # integrate about the rod's middle, for rounding
        si, sa, sb, os_ = self.seg_pieces
        D = self.B - self.A
        x0 = self.A[si, 0] - ox + sa * D[si, 0]
        y0 = self.A[si, 1] + sa * D[si, 1]
        dx, dy = (sb - sa) * D[si, 0], (sb - sa) * D[si, 1]
        area = x0 * dy - y0 * dx  # integral of x dy - y dx
        mx = dy * (x0 * x0 + x0 * dx + dx * dx / 3)  # integral of x^2 dy
        my = dx * (y0 * y0 + y0 * dy + dy * dy / 3)  # integral of y^2 dx
        ai, aa, ab, oa = self.arc_pieces
        cx, cy, r, t0 = self.arcs[ai, 0] - ox, self.arcs[ai, 1], self.arcs[ai, 2], self.arcs[ai, 3]
        ta, tb = t0 + aa, t0 + ab
        sa_, sb_, ca, cb = np.sin(ta), np.sin(tb), np.cos(ta), np.cos(tb)
        dth, ds2 = tb - ta, np.sin(2 * tb) - np.sin(2 * ta)
        area_a = r * cx * (sb_ - sa_) - r * cy * (cb - ca) + r * r * dth
        mx_a = r * (cx * cx * (sb_ - sa_) + 2 * cx * r * (dth / 2 + ds2 / 4)
                    + r * r * ((sb_ - sb_**3 / 3) - (sa_ - sa_**3 / 3)))
        my_a = -r * (cy * cy * (ca - cb) + 2 * cy * r * (dth / 2 - ds2 / 4)
                     + r * r * ((cb**3 / 3 - cb) - (ca**3 / 3 - ca)))
        A = 0.5 * (os_ @ area + oa @ area_a)
        Mx = 0.5 * (os_ @ mx + oa @ mx_a) + ox * A
        My = -0.5 * (os_ @ my + oa @ my_a)
        return float(self.thick @ A), float(self.thick @ Mx), float(self.thick @ My)

    def boundary(self) -> tuple[list[tuple], np.ndarray]:
        """The bands' boundary pieces, consecutive pieces of one curve merged where they
        bound the same bands: ([('s', x0, y0, ux, uy, length) or ('a', cx, cy, r,
        start, sweep)], (3, pieces) bool: which bands each bounds)."""
        pieces, masks = [], []
        for kind, (ci, pa, pb, orient) in (("s", self.seg_pieces), ("a", self.arc_pieces)):
            key = np.vstack([ci, orient])
            new = np.ones(len(ci), dtype=bool)
            new[1:] = (key[:, 1:] != key[:, :-1]).any(0) | (pa[1:] - pb[:-1] > 1e-12)
            starts = np.flatnonzero(new)
            groups = [[ci[s0], pa[s0], pb[s1], orient[:, s0]]
                      for s0, s1 in zip(starts, np.append(starts[1:], len(ci)) - 1)]
            if kind == "a":  # a full circle's pieces on both sides of its angle 0 are one
                for c in np.unique(ci[self.arcs[ci, 4] >= TAU]):
                    mine = [g_ for g_ in groups if g_[0] == c]
                    first, last = mine[0], mine[-1]
                    if len(mine) > 1 and first[1] == 0 and last[2] == TAU and (first[3] == last[3]).all():
                        last[2] += first[2]
                        first[3] = 0 * first[3]
            for c, lo, hi, o in groups:
                if not o.any():
                    continue
                if kind == "s":
                    a, d = self.A[c], self.B[c] - self.A[c]
                    n = float(np.hypot(*d))
                    p = a + lo * d
                    pieces.append(("s", p[0], p[1], d[0] / n, d[1] / n, (hi - lo) * n))
                else:
                    cx, cy, r, t0, _ = self.arcs[c]
                    pieces.append(("a", cx, cy, r, t0 + lo, hi - lo))
                masks.append(o != 0)
        return pieces, np.array(masks).T


@lru_cache(maxsize=256)
def _outline(g: RodGeometry) -> _Outline:
    return _Outline(g)


#: How many rods' moments :func:`rod_mass_properties` keeps: the planner asks again for the
#: same rods (a graduated rod's scale is bisected for each mass it is designed at).
MOMENTS_CACHE = 8192


@lru_cache(maxsize=MOMENTS_CACHE)
def _moments(key: str, g: RodGeometry) -> tuple[float, float, float]:
    """The solid's moments (:meth:`_Outline.moments`), kept by ``key``, the geometry's repr:
    every field to the last digit, the sign of a zero too (equal geometries can differ there)."""
    del key
    return _outline(g).moments()


def rod_mass_properties(g: RodGeometry, *, cell: float = 0.05) -> tuple[float, tuple[float, float, float]]:
    """Volume (mm^3) and centre of mass (x, y, z) (mm) of the solid
    :func:`rodcad.cad.solids.build_rod` builds for ``g``, without the CAD kernel.

    Exact (Green's theorem on each z-band's boundary): agrees with the B-rep's
    :func:`rodcad.cad.solids.mass_properties` to about 1e-12 relative. ``cell`` is
    accepted for callers written for a grid integration and not used.
    """
    del cell
    vol, mx, my = _moments(repr(g), g)
    return vol, (mx / vol, my / vol, 0.0)


class RodClearance:
    """Signed clearance of points from the solid ``build_rod(g)``'s boundary (mm,
    negative outside): a vectorised, kernel-free :class:`rodcad.cad.collision.Clearance`.

    Exact (the distance to each z-band's plane boundary combined with the band's
    z-distance), less :data:`SAFETY`, so it never exceeds the solid's clearance.

    Attributes:
        bounds: ((xmin, ymin, zmin), (xmax, ymax, zmax)) of the solid (mm).
    """

    def __init__(self, g: RodGeometry) -> None:
        self._outline = out = _outline(g)
        self._pieces, self._masks = out.boundary()
        xs, ys = [], []
        for kind, *p in self._pieces:
            if kind == "s":
                x0, y0, ux, uy, n = p
                xs += [x0, x0 + n * ux]
                ys += [y0, y0 + n * uy]
            else:
                cx, cy, r, t0, sw = p
                ang = [t0, t0 + sw] + [t0 + ((q * math.pi / 2 - t0) % TAU) for q in range(4)]
                ang = [a for a in ang if a <= t0 + sw]
                xs += [cx + r * math.cos(a) for a in ang]
                ys += [cy + r * math.sin(a) for a in ang]
        self.bounds = ((min(xs), min(ys), -out.t2), (max(xs), max(ys), out.t2))

    def _plane_distance2(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """(3, n): squared distance of plane points to each band region's boundary."""
        best = np.full((len(self._outline.layers), len(x)), np.inf)
        for (kind, *p), mask in zip(self._pieces, self._masks.T):
            if kind == "s":
                x0, y0, ux, uy, n = p
                along = x * ux + y * uy - (x0 * ux + y0 * uy)
                d2 = x * uy - y * ux - (x0 * uy - y0 * ux)
                d2 *= d2
                along -= np.clip(along, 0.0, n)
                along *= along
                d2 += along
            else:  # to the circle where w points into the arc, else to its nearer end
                cx, cy, r, t0, sw = p
                wx, wy = x - cx, y - cy
                reach = np.sqrt(wx * wx + wy * wy)
                d2 = reach - r
                d2 *= d2
                if sw < TAU - TOL:
                    mid = t0 + sw / 2
                    within = wx * math.cos(mid) + wy * math.sin(mid) >= reach * math.cos(sw / 2)
                    ax, ay = r * math.cos(t0), r * math.sin(t0)
                    bx, by = r * math.cos(t0 + sw), r * math.sin(t0 + sw)
                    ends = np.minimum((wx - ax) ** 2 + (wy - ay) ** 2, (wx - bx) ** 2 + (wy - by) ** 2)
                    d2 = np.where(within, d2, ends)
            for b in np.flatnonzero(mask):
                np.minimum(best[b], d2, out=best[b])
        return best

    def __call__(self, points: np.ndarray) -> np.ndarray:
        """Signed clearance of each point (array of shape (n, 3)) in mm."""
        x, y, z = np.array(np.atleast_2d(np.asarray(points, dtype=float)).T)
        o = self._outline
        t2 = o.t2
        az = np.abs(z)
        inside = o.inside(x, y)
        rho2 = self._plane_distance2(x, y)
        # z-distance to each layer's z-range (mid |z| <= a, gap a..a+gap, out a+gap..t/2, ...)
        dz = [np.maximum(np.maximum(z0 - az, az - z1), 0.0) for z0, z1, *_ in o.layers]
        solid = np.zeros(len(x), dtype=bool)
        near_in = np.full(len(x), np.inf)  # squared distance to the complement
        near_out = np.full(len(x), np.inf)  # squared distance to the solid
        for b in range(len(o.layers)):
            ins, sq = inside[b], dz[b] * dz[b]
            np.minimum(near_in, sq + np.where(ins, rho2[b], 0.0), out=near_in)
            np.minimum(near_out, sq + np.where(ins, 0.0, rho2[b]), out=near_out)
            solid |= ins & (dz[b] == 0)
        clear = np.minimum(t2 - az, np.sqrt(near_in))
        return np.where(solid, clear, -np.sqrt(near_out)) - SAFETY
