"""Joint limits from the end geometry, without the CAD kernel: a fast function of the
rods' parameters (length, section, curvature, setback, chamfers, hinge zone).

Outside the hinge zone a rod's collision proxy (:func:`rodcad.cad.solids.collision_proxy`)
is a full-thickness prism, so two rods meet where their outlines in the chain plane meet.
Near a joint the outline of a rod, in the joint's frame (origin on the hinge axis, x along
the body's outward tangent, y the rod's +y side), is

* the body: the straight stub ahead of the axis (``0 <= x``, ``|y| <= h/2``) and behind
  it the straight bar or, for a curved rod, the band of half-width h/2 around the
  centreline arc (centre at ``(0, rho)`` for a positive curvature);
* cut by the end faces: ``x <= -s - y tan(c_top)`` above the centreline and
  ``x <= -s + y tan(c_bottom)`` below it (:class:`rodcad.catalog.model.EndShape`);
* less the hinge zone, the disc of the zone radius around the axis.

Turning the right rod about the axis, the outlines overlap as soon as a point of one's
boundary lies inside the other. Each outline's boundary is sampled every 0.05 mm (faces,
sides, the zone circle) with its corners exactly (the faces' ends on the zone circle and on
the sides), and the membership test is exact. :func:`joint_limits` marches the bend from
the free middle in 1-degree steps until the outlines overlap and bisects the contact to
1e-6 degrees. Most of the march is far from contact: there it strides over up to :data:`LONGEST_STRIDE`
steps at once where a quick test (every :data:`COARSE_STRIDE`-th boundary sample, against
the other outline grown by what the samples left out and the stride's motion could cover:
:meth:`_Pair.clear_over`) proves that none of them overlaps, and every single step is first
tried that way (the same test over no turn); only where a quick test cannot rule out an
overlap does the full test run. The march stops at the same step, and the limits are the
same, as with the full test at every step.
It agrees with the B-rep search of :mod:`rodcad.catalog.limits` within 0.002 degrees on
every pair of the shipped catalogs (tests/test_jointlimits.py), moved 0.005 degrees
toward the free middle so that it never allows more bend than the solids, and takes
about 20 ms a pair instead of about a second.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rodcad.catalog.model import RodGeometry

__all__ = ["EndOutline", "joint_limits"]

#: Points closer than this to the other outline's boundary do not count as inside (mm).
INSIDE_TOL = 1e-9

#: Spacing of the sample points along a curved rod's arcs (mm).
ARC_STEP = 0.05

#: Bend step of the march toward contact (deg); bodies are far thicker than a step moves
#: any point within their reach.
MARCH_DEG = 1.0

#: Width of the final bracket on the contact angle (deg).
BISECT_DEG = 1e-6

#: Each limit is moved this far toward the free middle, so that it never allows more bend
#: than the solids (the outline's samples can only miss a contact, never invent one).
SAFETY_DEG = 0.005

#: The march's quick tests take every this many boundary samples.
COARSE_STRIDE = 8

#: The longest stride of the march (in steps) a quick test may clear at once.
LONGEST_STRIDE = 16


@dataclass(frozen=True)
class EndOutline:
    """A rod's outline near one of its joints, in that joint's frame (mm, rad).

    Attributes:
        height: section height h.
        curvature: signed curvature as seen from this joint's frame (1/mm).
        setback, tan_top, tan_bottom: the end face.
        zone: hinge-zone radius.
        stub: how far the straight stub reaches ahead of the axis.
        depth: how far behind the axis the outline matters (the partner's reach).
        top_end: the top side's offset from the centreline near the axis (default h/2).
        top_body: the top side's offset more than ``reach`` behind the axis (a graduated
            rod's body: :class:`rodcad.catalog.model.RodGeometry`; default ``top_end``).
        reach: how far behind the axis (along the centreline) ``top_end`` holds.
        cut_top, cut_bottom: how far above / below the end's tangent the end faces cut (the
            solid's end-cut prisms, :meth:`rodcad.catalog.model.RodGeometry.cut_reach`): a
            strongly curved rod's far part lies beyond the face's plane but above its cut.
        far: the centreline's length from this axis to the rod's other axis, where its body
            ends (with its own end faces, ``far_end``).
        far_knuckle: the knuckle radius around the other axis.
        far_end: the other end's faces (setback, tan top, tan bottom, cut top, cut bottom),
            or None.
        far_reach: how far from the other axis its end keeps ``top_end`` (a graduated rod).
    """

    height: float
    curvature: float
    setback: float
    tan_top: float
    tan_bottom: float
    zone: float
    stub: float
    depth: float
    top_end: float | None = None
    top_body: float | None = None
    reach: float = math.inf
    cut_top: float = math.inf
    cut_bottom: float = math.inf
    far: float = math.inf
    far_knuckle: float = 0.0
    far_end: tuple[float, float, float, float, float] | None = None
    far_reach: float = math.inf

    @classmethod
    def of(cls, g: RodGeometry, joint: int, depth: float) -> EndOutline:
        end = g.first if joint == 0 else g.second
        top_end = top_body = g.height / 2
        reach = far_reach = math.inf
        if g.graduated:
            top_body = g.body_top
            top_end = max(g.height / 2, top_body)
            assert g.end_reach is not None
            reach, far_reach = g.end_reach[joint], g.end_reach[1 - joint]
        tan_top, tan_bottom = math.tan(math.radians(end.top_chamfer)), math.tan(math.radians(end.bottom_chamfer))
        return cls(g.height, g.curvature, end.setback, tan_top, tan_bottom, g.hinge.zone_radius, g.stub, depth,
                   top_end, top_body, reach, g.cut_reach(1, tan_top), g.cut_reach(-1, tan_bottom),
                   _arc_length(g), g.hinge.knuckle_radius, _far_end(g, 1 - joint), far_reach)

    @property
    def growth(self) -> float:
        """How much :meth:`contains`' margin must exceed a distance to grow the outline by at
        least that distance along every edge's normal: it shifts the end faces (slope t to
        the y axis) along x, 1 / sqrt(1 + t^2) of the shift along their normals; the sides,
        circles and the far end's sides exactly."""
        tans = [self.tan_top, self.tan_bottom] + ([] if self.far_end is None else list(self.far_end[1:3]))
        return max(1.0, max(math.hypot(1.0, t) for t in tans)) * (1 + 1e-9)

    def far_frame(self) -> tuple[np.ndarray, np.ndarray]:
        """The other end's outward tangent and the rod's +y normal there, in this frame."""
        k = self.curvature
        th = 0.0 if k == 0 else self.far * abs(k)
        sk = math.copysign(1.0, k) if k else 1.0
        return np.array([-math.cos(th), sk * math.sin(th)]), np.array([sk * math.sin(th), math.cos(th)])

    def _far_cut(self, x: np.ndarray, y: np.ndarray, e: float) -> np.ndarray:
        """Points the other end's face cuts remove (within ``e`` of them count as removed)."""
        out = np.zeros(x.shape, dtype=bool)
        if self.far_end is None:
            return out
        setback, t_top, t_bottom, c_top, c_bottom = self.far_end
        q = self.far_axis()
        u, v = self.far_frame()
        a = q - setback * u
        dx, dy = x - a[0], y - a[1]
        xp = dx * u[0] + dy * u[1]
        for side, t, c in ((1.0, t_top, c_top), (-1.0, t_bottom, c_bottom)):
            yp = side * (dx * v[0] + dy * v[1])
            out |= (yp >= -e) & (yp <= c + e) & (xp >= -yp * t - e)
        return out

    def far_axis(self) -> np.ndarray:
        """The rod's other hinge axis in this frame."""
        k = self.curvature
        if k == 0:
            return np.array([-self.far, 0.0])
        rho = 1 / abs(k)
        ang = self.far / rho
        return np.array([-rho * math.sin(ang), math.copysign(rho, k) * (1 - math.cos(ang))])

    @property
    def top(self) -> float:
        """The top side's offset near the axis (mm)."""
        return self.height / 2 if self.top_end is None else self.top_end

    @property
    def body(self) -> float:
        """The top side's offset behind ``reach`` (mm)."""
        return self.top if self.top_body is None else self.top_body

    def contains(self, p: np.ndarray, e: float = INSIDE_TOL) -> np.ndarray:
        """Whether points (M, 2) lie inside the outline, more than ``e`` from its edge
        (a negative ``e``: inside or within ``-e`` of the edge)."""
        x, y = p[:, 0], p[:, 1]
        body = self._body(x, y, e) & ~self._far_cut(x, y, e)
        return self._clear_of_ends(x, y, e) & (body | self._knuckle(x, y, e))

    def meets(self, p: np.ndarray, e: float | np.ndarray = INSIDE_TOL) -> bool:
        """``contains(p, e).any()``, each of its tests made only on the points the ones
        before left (``e``: a number, or one per point)."""
        x, y = p[:, 0], p[:, 1]
        per_point = np.ndim(e) > 0

        def keep(mask: np.ndarray) -> bool:
            nonlocal x, y, e
            x, y = x[mask], y[mask]
            if per_point:
                e = e[mask]
            return x.size > 0

        if not keep(self._clear_of_ends(x, y, e)):
            return False
        if self._knuckle(x, y, e).any():
            return True
        return keep(self._body(x, y, e)) and bool((~self._far_cut(x, y, e)).any())

    def _clear_of_ends(self, x: np.ndarray, y: np.ndarray, e) -> np.ndarray:
        """Points on the body's side of this end's faces, outside its hinge zone."""
        face = np.where(y >= 0, (x < -self.setback - y * self.tan_top - e) | (y > self.cut_top + e),
                        (x < -self.setback + y * self.tan_bottom - e) | (y < -self.cut_bottom - e))
        return face & (x * x + y * y > (self.zone + e) * abs(self.zone + e))

    def _knuckle(self, x: np.ndarray, y: np.ndarray, e) -> np.ndarray:
        """Points in the knuckle around the other axis."""
        q = self.far_axis()
        return (x - q[0]) ** 2 + (y - q[1]) ** 2 < (self.far_knuckle - e) * abs(self.far_knuckle - e)

    def _body(self, x: np.ndarray, y: np.ndarray, e) -> np.ndarray:
        """Points in the body (the stub, the bar or band behind the axis, the far stub),
        before the far end's faces cut it."""
        lo = -self.height / 2 + e
        stub = (x >= 0) & (x < self.stub - e) & (y > lo) & (y < self.top - e)
        k = self.curvature
        if k == 0:
            top = np.where((x >= -self.reach) | (x <= self.far_reach - self.far), self.top, self.body)
            behind = (x < 0) & (x > -self.far) & (y > lo) & (y < top - e)
        else:
            rho = 1 / abs(k)
            cy = math.copysign(rho, k)  # the arc's centre, on the +y side for k > 0
            r = np.hypot(x, y - cy)
            w = math.copysign(1.0, k) * (rho - r)  # offset from the centreline toward +y
            # angle travelled back along the arc from the axis, seen from the centre
            back = np.arctan2(-x, np.sign(k) * (cy - y))
            top = np.where((back <= self.reach / rho) | (back >= (self.far - self.far_reach) / rho), self.top, self.body)
            behind = (x < 0) & (w > lo) & (w < top - e) & (back > 0) & (back < min(self.depth, self.far) / rho)
        # the body past the far axis is cut by the far end's faces (:meth:`_far_cut`); its knuckle is not
        return stub | behind | self._far_stub(x, y, e)

    def _far_stub(self, x: np.ndarray, y: np.ndarray, e: float) -> np.ndarray:
        """The straight stub past the other axis (what its faces leave of it)."""
        if not math.isfinite(self.far) or self.far_end is None:
            return np.zeros(x.shape, dtype=bool)
        q = self.far_axis()
        u, v = self.far_frame()
        dx, dy = x - q[0], y - q[1]
        along = dx * u[0] + dy * u[1]
        off = dx * v[0] + dy * v[1]
        return (along >= 0) & (along < self.stub - e) & (off > -self.height / 2 + e) & (off < self.top - e)

    def corners(self) -> np.ndarray:
        """Points along the outline's boundary, :data:`ARC_STEP` apart, with its corners
        exactly (where the faces meet the zone circle and the sides)."""
        pts: list[np.ndarray] = []  # blocks of rows
        r = self.zone
        for sign in (1.0, -1.0):
            # the face, x = -s - |y| t on this side, from the zone circle to the side
            p0, d = self._face(sign)
            roots = _line_meets_circle(p0, d, np.zeros(2), r)
            u0 = max(0.0, roots[0]) if roots else 0.0
            end = self._face_meets_side(sign)
            u1 = float((end - p0) @ d)
            if u1 > u0:
                pts.append(p0 + np.outer(_steps(u0, u1), d))
            pts.append(end[None])
        pts += self._side_samples()
        if math.isfinite(self.far):  # the body's far end (across the band) and the far knuckle
            end = min(self.depth, self.far)
            w = _steps(-self.height / 2, max(self.top, self.body))
            k = self.curvature
            if k == 0:
                pts.append(np.column_stack([np.full(w.size, -end), w]))
            else:
                rho, sk = 1 / abs(k), math.copysign(1.0, k)
                radius, ang = rho - sk * w, end / rho
                pts.append(np.column_stack([-radius * math.sin(ang), sk * rho - sk * radius * math.cos(ang)]))
            q, r = self.far_axis(), self.far_knuckle
            ang = np.linspace(0.0, 2 * math.pi, int(2 * math.pi * r / ARC_STEP) + 2)
            pts.append(q + r * np.column_stack([np.cos(ang), np.sin(ang)]))
            if self.far_end is not None:  # the far faces and the far stub's sides
                setback, t_top, t_bottom, _, _ = self.far_end
                u, v = self.far_frame()
                a = q - setback * u
                hmax = max(self.top, self.height / 2) + 1.0
                for side, t in ((1.0, t_top), (-1.0, t_bottom)):
                    ys = _steps(0.0, hmax)
                    pts.append(a + np.outer(-ys * t, u) + np.outer(side * ys, v))
                    xs = _steps(0.0, self.stub)
                    w = self.top if side > 0 else -self.height / 2
                    pts.append(q + np.outer(xs, u) + w * v)
        for sign, cut, t in ((1.0, self.cut_top, self.tan_top), (-1.0, self.cut_bottom, self.tan_bottom)):
            if math.isfinite(cut):  # the end cut's far edge, where the body reaches past it
                x0 = -self.setback - cut * t
                xs = -_steps(-x0, self.depth) if x0 < 0 else -_steps(0.0, self.depth)
                pts.append(np.column_stack([xs, np.full(xs.size, sign * cut)]))
        ang = np.linspace(0.0, 2 * math.pi, int(2 * math.pi * r / ARC_STEP) + 1)
        pts.append(r * np.column_stack([np.cos(ang), np.sin(ang)]))
        pts = np.concatenate(pts, dtype=float)
        return pts[self.contains(pts, -1e-7)]  # only points of this outline (its boundary)

    def _face(self, sign: float) -> tuple[np.ndarray, np.ndarray]:
        """The end face's line on the top (sign +1) or bottom (-1) half: its point on the
        centreline and its unit direction away from it."""
        t = self.tan_top if sign > 0 else self.tan_bottom
        return np.array([-self.setback, 0.0]), np.array([-t, sign]) / math.hypot(1.0, t)

    def _face_meets_side(self, sign: float) -> np.ndarray:
        """The face's end on the top (sign +1) or bottom (-1) surface."""
        t = self.tan_top if sign > 0 else self.tan_bottom
        s, k = self.setback, self.curvature
        h2 = self.top if sign > 0 else self.height / 2
        if k == 0:
            return np.array([-s - h2 * t, sign * h2])
        # intersect the face line with the side arc |p - c| = rho - sign * sign(k) * h2
        rho = 1 / abs(k)
        c = np.array([0.0, math.copysign(rho, k)])
        radius = rho - sign * math.copysign(1.0, k) * h2
        p0, d = self._face(sign)
        roots = _line_meets_circle(p0, d, c, radius)
        if not roots:  # the face misses the side arc: its end is where the stub's side is
            return np.array([-s - h2 * t, sign * h2])
        u = min((x for x in roots if x >= 0), default=max(roots))
        q = p0 + u * d
        if q[0] >= 0:  # on the stub (ahead of the axis), where the side is straight
            return np.array([-s - h2 * t, sign * h2])
        return q

    def _side_samples(self) -> list[np.ndarray]:
        """Points (blocks of rows) along the top and bottom sides: the stub's straight sides ahead of the
        axis, then the bar's straight sides or a curved rod's arcs behind it (a graduated
        rod's top steps to its body's ``reach`` behind the axis)."""
        k = self.curvature
        out = []
        for sign in (1.0, -1.0):
            near = self.top if sign > 0 else -self.height / 2
            far = self.body if sign > 0 else near
            ahead = _steps(0.0, self.stub)
            out.append(np.column_stack([ahead, np.full(ahead.size, near)]))
            end = min(self.depth, self.far)
            cut = min(self.reach, end)
            spans = [(0.0, cut, near)] + ([(cut, end, far)] if cut < end else [])
            back_cut = self.far - self.far_reach  # the far end's block (a lower body steps up to it)
            if far != near and cut < back_cut < end:
                spans = [(0.0, cut, near), (cut, back_cut, far), (back_cut, end, near)]
            step = _steps(min(near, far), max(near, far)) if far != near and cut < end else np.zeros(0)
            steps_at = [cut] + ([back_cut] if len(spans) == 3 else [])
            if k == 0:
                for a, b, w in spans:
                    back = -_steps(a, b)
                    out.append(np.column_stack([back, np.full(back.size, w)]))
                for at in steps_at:
                    out.append(np.column_stack([np.full(step.size, -at), step]))
                continue
            rho = 1 / abs(k)
            cy = math.copysign(rho, k)
            sk = math.copysign(1.0, k)
            for a, b, w in spans:
                radius = rho - sk * w
                ang = _steps(a, b) / rho  # back along the arc from the axis's radial line
                out.append(np.column_stack([-radius * np.sin(ang), cy - sk * radius * np.cos(ang)]))
            radius = rho - sk * step
            for at in steps_at:
                ang = at / rho
                out.append(np.column_stack([-radius * math.sin(ang), cy - sk * radius * math.cos(ang)]))
        return out


def _far_end(g: RodGeometry, joint: int) -> tuple[float, float, float, float, float]:
    """The end faces at ``joint`` as EndOutline.far_end."""
    end = g.first if joint == 0 else g.second
    t_top, t_bottom = math.tan(math.radians(end.top_chamfer)), math.tan(math.radians(end.bottom_chamfer))
    return (end.setback, t_top, t_bottom, g.cut_reach(1, t_top), g.cut_reach(-1, t_bottom))


def _arc_length(g: RodGeometry) -> float:
    """The centreline's length between the two hinge axes (mm)."""
    if g.curvature == 0:
        return g.length
    return 2 * abs(math.radians(g.half_angle_deg)) / abs(g.curvature)


def _line_meets_circle(p0: np.ndarray, d: np.ndarray, centre: np.ndarray, radius: float) -> list[float]:
    """Parameters u (larger first) where p0 + u d (d a unit vector) meets the circle; [] if it misses."""
    w = p0 - centre
    b = float(w @ d)
    disc = b * b - (float(w @ w) - radius * radius)
    if disc < 0:
        return []
    return [-b + math.sqrt(disc), -b - math.sqrt(disc)]


def _steps(a: float, b: float) -> np.ndarray:
    """a to b (a <= b) in steps of at most :data:`ARC_STEP`, both ends included."""
    return np.linspace(a, b, max(2, int(math.ceil((b - a) / ARC_STEP)) + 1))


def _frame(angle: float) -> np.ndarray:
    """Rows: the x and y axes of a frame turned by ``angle`` (rad)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, s], [-s, c]])


class _Pair:
    """Two rods at their shared joint, the right one turned by the bend phi (rad)."""

    def __init__(self, left: RodGeometry, right: RodGeometry) -> None:
        reach = max(left.length, right.length) + 1.2 * max(left.max_height, right.max_height) + 2.0
        self.left = EndOutline.of(left, 1, reach)
        self.right = EndOutline.of(right, 0, reach)
        self.psi_l = math.radians(left.half_angle_deg)
        self.psi_r = math.radians(right.half_angle_deg)
        self.left_pts = self.left.corners()
        self.right_pts = self.right.corners()
        # each outline's bounding box (its boundary samples, 1 mm wider): a point outside it
        # is outside the outline, without the full test
        self.left_box = (self.left_pts.min(axis=0) - 1.0, self.left_pts.max(axis=0) + 1.0)
        self.right_box = (self.right_pts.min(axis=0) - 1.0, self.right_pts.max(axis=0) + 1.0)
        self.left_coarse, self.left_gap = _thinned(self.left_pts)
        self.right_coarse, self.right_gap = _thinned(self.right_pts)
        self.left_radius = np.hypot(*self.left_coarse.T)
        self.right_radius = np.hypot(*self.right_coarse.T)

    def _axes(self, phi: float) -> tuple[np.ndarray, np.ndarray]:
        """(left frame, right frame) as 2x2 matrices whose rows are the local x and y axes
        in the left rod's chord frame (the right frame is mirrored: its x points back)."""
        left = _frame(self.psi_l)
        fwd = phi - self.psi_r
        c, s = math.cos(fwd), math.sin(fwd)
        right = np.array([[-c, -s], [-s, c]])  # x = -forward, y = forward turned +90 deg
        return left, right

    def overlaps(self, phi_deg: float, near: tuple[np.ndarray, np.ndarray] | None = None) -> bool:
        """Whether the outlines overlap at the bend ``phi_deg``: a boundary sample of one lies
        inside the other (with ``near``, :meth:`near`'s samples only)."""
        left, right = self._axes(math.radians(phi_deg))
        right_pts, left_pts = (self.right_pts, self.left_pts) if near is None else near
        # right corners into the left frame, and left corners into the right frame
        r_in_l = (right_pts @ right) @ left.T
        if _inside(self.left, self.left_box, r_in_l):
            return True
        l_in_r = (left_pts @ left) @ right.T
        return _inside(self.right, self.right_box, l_in_r)

    def near(self, phi_deg: float, sweep_deg: float) -> tuple[np.ndarray, np.ndarray]:
        """The boundary samples (right's, left's) that can lie inside the other outline at a
        bend between ``phi_deg`` and ``phi_deg + sweep_deg``: those within the arc the turn moves
        them about the axis (radius x turn) of the other outline at ``phi_deg``. A sample left
        out lies inside at no such bend, so :meth:`overlaps` on these decides as on all."""
        left, right = self._axes(math.radians(phi_deg))
        turn = math.radians(abs(sweep_deg))
        kept = []
        for pts, outline, box, to_other in ((self.right_pts, self.left, self.left_box, lambda q: (q @ right) @ left.T),
                                            (self.left_pts, self.right, self.right_box, lambda q: (q @ left) @ right.T)):
            grow = outline.growth * (np.hypot(pts[:, 0], pts[:, 1]) * turn + 1e-9)
            q = to_other(pts)
            keep = np.flatnonzero(_in_box(q, box, grow))
            if keep.size:
                keep = keep[outline.contains(q[keep], -grow[keep])]
            kept.append(pts[keep])
        return kept[0], kept[1]


    def clear_over(self, phi_deg: float, sweep_deg: float = 0.0) -> bool:
        """True where the outlines certainly do not overlap at any bend from ``phi_deg`` to
        ``phi_deg + sweep_deg``: no kept sample of either lies within the distance a left-out
        sample or the sweep could cover (the gap to the farthest left-out sample, plus the
        arc the sample travels about the axis) of the other outline at ``phi_deg``. False says
        nothing: :meth:`overlaps` decides."""
        left, right = self._axes(math.radians(phi_deg))
        turn = math.radians(abs(sweep_deg))
        r_in_l = (self.right_coarse @ right) @ left.T
        reach = self.right_gap + (self.right_radius + self.right_gap) * turn
        if _inside(self.left, self.left_box, r_in_l, self.left.growth * reach):
            return False
        l_in_r = (self.left_coarse @ left) @ right.T
        reach = self.left_gap + (self.left_radius + self.left_gap) * turn
        return not _inside(self.right, self.right_box, l_in_r, self.right.growth * reach)



def _thinned(pts: np.ndarray) -> tuple[np.ndarray, float]:
    """Every :data:`COARSE_STRIDE`-th sample, and the farthest any sample lies from those (mm)."""
    from scipy.spatial import cKDTree

    kept = pts[::COARSE_STRIDE]
    gap = float(cKDTree(kept).query(pts)[0].max()) if len(pts) else 0.0
    return kept, gap + 1e-9


def _inside(outline: EndOutline, box: tuple[np.ndarray, np.ndarray], pts: np.ndarray, grow=None) -> bool:
    """Whether any of the points lies inside the outline (only those in its box are tested);
    with ``grow`` (per point, mm), inside it or within ``grow`` of its edges along x or y
    (:attr:`EndOutline.growth` turns a distance into that)."""
    x, y = pts[:, 0], pts[:, 1]
    (x0, y0), (x1, y1) = box
    if grow is None:
        near = pts[(x >= x0) & (x <= x1) & (y >= y0) & (y <= y1)]
        return bool(near.size and outline.meets(near))
    g = np.broadcast_to(np.asarray(grow, float), pts.shape[:1])
    keep = _in_box(pts, box, g)
    return bool(keep.any() and outline.meets(pts[keep], -g[keep]))


def _in_box(pts: np.ndarray, box: tuple[np.ndarray, np.ndarray], grow: np.ndarray) -> np.ndarray:
    """Which points lie in the box grown by ``grow`` (per point, mm) on every side."""
    (x0, y0), (x1, y1) = box
    x, y = pts[:, 0], pts[:, 1]
    return (x >= x0 - grow) & (x <= x1 + grow) & (y >= y0 - grow) & (y <= y1 + grow)


def _contact(pair: _Pair, start: float, direction: float, bound: float) -> float | None:
    a = start
    stride = LONGEST_STRIDE
    while True:
        if stride > 1 and abs(a + direction * stride * MARCH_DEG) < bound:
            if pair.clear_over(a, stride * MARCH_DEG):  # none of the next steps overlaps
                a += direction * stride * MARCH_DEG
            else:
                stride //= 2
            continue
        b = a + direction * MARCH_DEG
        if abs(b) >= bound:
            b = direction * bound
            if not pair.overlaps(b):
                return None
        if not pair.clear_over(b) and pair.overlaps(b):
            break
        a = b
    near = pair.near(a, b - a)  # the samples that can meet within the bracket
    while abs(b - a) > BISECT_DEG:
        m = (a + b) / 2
        if pair.overlaps(m, near):
            b = m
        else:
            a = m
    return a


def joint_limits(left: RodGeometry, right: RodGeometry, *, bound: float = 180.0) -> tuple[float | None, float | None]:
    """The bend range (deg) of two rods joined at ``left``'s second joint and ``right``'s
    first: the last angles on either side of the free middle at which their outlines do
    not overlap, less :data:`SAFETY_DEG`, each None when nothing meets before +-``bound``.

    Example: two flush stop ends with top chamfers of 10 degrees stop at 20 degrees,
    ``joint_limits(a, b)[1] == pytest.approx(20.0, abs=0.01)``.

    Raises:
        ValueError: the rods overlap at every angle tried as a start.
    """
    pair = _Pair(left, right)
    mid = (left.half_angle_deg + right.half_angle_deg
           + (left.second.top_chamfer + right.first.top_chamfer
              - left.second.bottom_chamfer - right.first.bottom_chamfer) / 2)
    for start in [mid, 0.0] + [s * k * 5.0 for k in range(1, 36) for s in (1, -1)]:
        if not pair.overlaps(start):
            break
    else:
        raise ValueError("the two rods overlap at every bend angle")
    lo, hi = _contact(pair, start, -1.0, bound), _contact(pair, start, 1.0, bound)
    return (None if lo is None else lo + SAFETY_DEG, None if hi is None else hi - SAFETY_DEG)
