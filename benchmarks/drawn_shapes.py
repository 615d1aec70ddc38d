"""Shapes people draw, as plain polylines: a seeded family for the planner (issue 24).

Closed outlines hung from two points near their top (hearts with varied lobes, aspect,
asymmetry and tilt; drops; rings; polygons hung from a vertex; leaves; spades) and open
curves with concave bends (waves, M shapes, steps). Each shape is a polyline from anchor
A to anchor B (mm, y up), the way a user writes it in a design file with no catalog and
no constraints:

    design: 1
    name: <name>
    anchors: [A, B]
    target: {form: polyline, points: [...]}

A closed outline is cut open at its hanging point: the two anchors sit a fixture apart
(8-30 mm) astride it, and the outline runs from A round the shape to B. Sizes are
80-300 mm. ``family(n, seed)`` gives n shapes cycling through the kinds; the same seed
gives the same shapes.

    python benchmarks/drawn_shapes.py --n 24 --out /tmp/shapes    # writes the design files
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["KINDS", "Shape", "design_text", "diamond", "family", "heart_outline", "shape"]

KINDS = ("heart", "drop", "ring", "polygon", "leaf", "spade", "wave", "m-shape", "steps")


@dataclass(frozen=True)
class Shape:
    """A drawn target: its kind, a name, the anchors and the polyline from A to B (mm).

    Attributes:
        kind: one of :data:`KINDS`.
        name: unique in a family (kind and index).
        anchors: (2, 2) A and B.
        points: (M, 2) the polyline, points[0] = A, points[-1] = B.
        params: what was drawn (for the tables).
    """

    kind: str
    name: str
    anchors: np.ndarray
    points: np.ndarray
    params: dict

    @property
    def size(self) -> float:
        """The target's size: the larger of its span, width and height (mm)."""
        span = float(np.hypot(*(self.anchors[1] - self.anchors[0])))
        return max(span, *np.ptp(self.points, axis=0))


def _arclength_resample(pts: np.ndarray, n: int) -> np.ndarray:
    d = np.hypot(*np.diff(pts, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(d)])
    t = np.linspace(0.0, s[-1], n)
    return np.column_stack([np.interp(t, s, pts[:, 0]), np.interp(t, s, pts[:, 1])])


def _open_at_top(closed: np.ndarray, gap: float, top: np.ndarray) -> np.ndarray:
    """A closed outline (counter-clockwise or not, first point anywhere) cut open at the
    point nearest ``top``: the two ends go as far from it along the outline, either way, as
    puts them ``gap`` mm apart (the anchors, a fixture apart), the rest a polyline from the
    left end (A) to the right end (B)."""
    pts = np.asarray(closed, float)
    if np.allclose(pts[0], pts[-1]):
        pts = pts[:-1]
    k = int(np.argmin(np.hypot(*(pts - top).T)))
    ring = np.vstack([pts[k:], pts[:k], pts[k:k + 1]])  # from the top round back to it
    d = np.hypot(*np.diff(ring, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(d)])

    def at(t: float) -> np.ndarray:
        return np.array([np.interp(t, s, ring[:, 0]), np.interp(t, s, ring[:, 1])])

    lo, hi = 0.0, s[-1] / 4  # half the cut, along the outline: the ends' distance grows with it
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if np.hypot(*(at(mid) - at(s[-1] - mid))) < gap else (lo, mid)
    cut = hi
    keep = (s > cut) & (s < s[-1] - cut)
    out = np.vstack([at(cut), ring[keep], at(s[-1] - cut)])
    if out[0, 0] > out[-1, 0]:  # A on the left
        out = out[::-1]
    return out


def _rotate(pts: np.ndarray, deg: float, about: np.ndarray) -> np.ndarray:
    a = math.radians(deg)
    r = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    return (pts - about) @ r.T + about


def _heart(rng) -> tuple[np.ndarray, dict]:
    """A heart outline, cusp at the top: the classic parametric heart
    (x = 16 sin^3 t, y = 13 cos t - 5 cos 2t - 2 cos 3t - cos 4t), varied: width, aspect,
    lobe shape (the power of the sine), one lobe wider than the other, tilt."""
    width = rng.uniform(100, 260)
    aspect = rng.uniform(0.75, 1.2)  # height / width
    power = rng.uniform(2.3, 3.4)  # lobe roundness
    lopsided = float(rng.choice([1.0, rng.uniform(1.05, 1.3)]))  # right half's width / left's
    tilt = float(rng.choice([0.0, rng.uniform(-15, 15)]))
    t = np.linspace(0, 2 * math.pi, 721)[:-1]
    sn = np.sin(t)
    x = 16 * np.sign(sn) * np.abs(sn) ** power
    y = 13 * np.cos(t) - 5 * np.cos(2 * t) - 2 * np.cos(3 * t) - np.cos(4 * t)
    cusp_y = 13 - 5 - 2 - 1  # y at t = 0 (the cusp)
    x = np.where(x > 0, x * lopsided, x)
    x = x / np.ptp(x) * width
    y = (y - cusp_y) / np.ptp(y) * width * aspect
    closed = np.column_stack([x, y])
    closed = _rotate(closed, tilt, np.zeros(2))
    return closed, dict(width=round(width, 1), aspect=round(aspect, 2), power=round(power, 2),
                        lobes=round(lopsided, 2), tilt=round(tilt, 1))


def _drop(rng) -> tuple[np.ndarray, dict]:
    """A teardrop hung from its point: a circle below, tangent lines up to the point."""
    r = rng.uniform(35, 110)
    length = r * rng.uniform(1.6, 3.0)  # point to the circle's centre
    c = np.array([0.0, -length])
    half = math.asin(r / length)  # the tangents' half angle at the point
    t = np.linspace(math.pi / 2 + half, 2 * math.pi + math.pi / 2 - half, 200)  # round the bottom
    circ = c + r * np.column_stack([np.cos(t), np.sin(t)])
    closed = np.vstack([[0.0, 0.0], circ, [0.0, 0.0]])
    tilt = rng.choice([0.0, rng.uniform(-10, 10)])
    return _rotate(closed, tilt, np.zeros(2)), dict(r=round(r, 1), length=round(length, 1),
                                                    tilt=round(float(tilt), 1))


def _ring(rng) -> tuple[np.ndarray, dict]:
    r = rng.uniform(40, 140)
    t = np.linspace(math.pi / 2, math.pi / 2 + 2 * math.pi, 400)
    closed = r * np.column_stack([np.cos(t), np.sin(t)])
    squash = rng.uniform(0.7, 1.3)
    closed[:, 1] *= squash
    return closed, dict(r=round(r, 1), squash=round(squash, 2))


def _polygon(rng) -> tuple[np.ndarray, dict]:
    """A regular polygon hung from a vertex (the vertex at the top)."""
    k = int(rng.integers(3, 9))
    r = rng.uniform(50, 140)
    t = math.pi / 2 + 2 * math.pi * np.arange(k + 1) / k
    closed = r * np.column_stack([np.cos(t), np.sin(t)])
    return closed, dict(sides=k, r=round(r, 1))


def _leaf(rng) -> tuple[np.ndarray, dict]:
    """A pointed ellipse (two circular arcs meeting at two points), hung from one point."""
    length = rng.uniform(90, 280)
    width = length * rng.uniform(0.3, 0.7)
    # two arcs through (0, 0) and (0, -length) bulging by width / 2
    h = width / 2
    rr = (length * length / 4 + h * h) / (2 * h)
    cx = rr - h
    ang = math.asin(length / 2 / rr)
    t = np.linspace(math.pi - ang, math.pi + ang, 120)
    left = np.array([cx, -length / 2]) + rr * np.column_stack([np.cos(t), np.sin(t)])
    right = np.column_stack([-left[::-1, 0], left[::-1, 1]])
    closed = np.vstack([left, right[1:]])
    tilt = rng.choice([0.0, rng.uniform(-12, 12)])
    return _rotate(closed, tilt, np.zeros(2)), dict(length=round(length, 1), width=round(width, 1),
                                                    tilt=round(float(tilt), 1))


def _spade(rng) -> tuple[np.ndarray, dict]:
    """A spade: a heart upside down (its tip at the top, where it hangs), a short stem
    below its cusp."""
    closed, p = _heart(rng)
    closed = np.column_stack([closed[:, 0], -closed[:, 1]])
    tip_y = closed[:, 1].max()
    closed[:, 1] -= tip_y
    # a stem: a small triangle below the cusp (the cusp is now at the bottom, at x ~ 0)
    k = int(np.argmin(np.abs(closed[:, 0]) + 10 * (closed[:, 1] > closed[:, 1].min() + 0.5 * np.ptp(closed[:, 1]))))
    cusp = closed[k]
    stem = np.array([[cusp[0] - 6, cusp[1] - 0.5], [cusp[0], cusp[1] - 25], [cusp[0] + 6, cusp[1] - 0.5]])
    closed = np.vstack([closed[:k], stem, closed[k + 1:]])
    p["stem"] = 25
    return closed, p


def _wave(rng) -> tuple[np.ndarray, np.ndarray, dict]:
    span = rng.uniform(150, 320)
    amp = span * rng.uniform(0.05, 0.15)
    waves = rng.uniform(1.0, 2.5)
    sag = span * rng.uniform(0.2, 0.45)
    dh = span * rng.uniform(-0.3, 0.3)
    x = np.linspace(0, span, 300)
    u = x / span
    y = dh * u - sag * 4 * u * (1 - u) + amp * np.sin(2 * math.pi * waves * u) * np.sin(math.pi * u)
    return np.column_stack([x, y]), dict(span=round(span, 1), amp=round(amp, 1), waves=round(waves, 2),
                                         sag=round(sag, 1), dh=round(dh, 1))


def _m_shape(rng) -> tuple[np.ndarray, np.ndarray, dict]:
    """Two dips with a rise between them (the middle above the dips' bottoms)."""
    span = rng.uniform(160, 320)
    depth = span * rng.uniform(0.25, 0.5)
    rise = depth * rng.uniform(0.3, 0.8)
    x = np.linspace(0, span, 300)
    u = x / span
    y = -depth * np.sin(math.pi * u) ** 0.8 + (rise + depth * 0.2) * np.exp(-((u - 0.5) / 0.12) ** 2)
    return np.column_stack([x, y]), dict(span=round(span, 1), depth=round(depth, 1), rise=round(rise, 1))


def _steps(rng) -> tuple[np.ndarray, np.ndarray, dict]:
    """A staircase between anchors at different heights: flat treads, vertical-ish risers,
    sagging overall."""
    k = int(rng.integers(2, 5))
    tread = rng.uniform(35, 70)
    riser = rng.uniform(20, 50)
    pts = [[0.0, 0.0]]
    for i in range(k):
        x, y = pts[-1]
        pts.append([x + 0.15 * tread, y - riser])
        pts.append([x + tread, y - riser])
    x, y = pts[-1]
    pts.append([x + 0.5 * tread, y + riser * k * rng.uniform(0.3, 1.0)])
    return np.array(pts), dict(steps=k, tread=round(tread, 1), riser=round(riser, 1))


_CLOSED = {"heart": _heart, "drop": _drop, "ring": _ring, "polygon": _polygon, "leaf": _leaf, "spade": _spade}
_OPEN = {"wave": _wave, "m-shape": _m_shape, "steps": _steps}


def shape(kind: str, rng: np.random.Generator, index: int = 0) -> Shape:
    """One drawn shape of ``kind``."""
    if kind in _CLOSED:
        closed, params = _CLOSED[kind](rng)
        # hung from the top point; a heart from its cusp (the origin, between the lobes)
        top = np.zeros(2) if kind == "heart" else closed[int(np.argmax(closed[:, 1]))]
        gap = float(rng.uniform(8, 30))
        pts = _open_at_top(_arclength_resample(closed, 600), gap, top)
        params["gap"] = round(gap, 1)
    else:
        pts, params = _OPEN[kind](rng)
        pts = _arclength_resample(pts, 300) if kind != "steps" else pts
    pts = pts - pts[0]
    pts = np.round(pts, 3)
    return Shape(kind, f"{kind}-{index:03d}", np.array([pts[0], pts[-1]]), pts, params)


def diamond(side: float = 100.0, gap: float = 10.0) -> Shape:
    """A square standing on a corner, hung from its top corner: anchors ``gap`` mm apart on
    the two sides at the top (issue 24's square hung from one corner)."""
    h = side / math.sqrt(2)
    top, left, bottom, right = np.array([0.0, 0.0]), np.array([-h, -h]), np.array([0.0, -2 * h]), np.array([h, -h])
    d = gap / 2 / math.cos(math.radians(45))
    a = top + (left - top) / side * d
    b = top + (right - top) / side * d
    pts = np.round(np.array([a, left, bottom, right, b]) - a, 6)
    return Shape("polygon", "diamond", pts[[0, -1]], pts, dict(side=side, gap=gap))


def heart_outline(width: float = 160.0, gap: float = 12.0, lobes: float = 1.0) -> Shape:
    """The classic parametric heart ``width`` mm wide (the right lobe ``lobes`` times as wide
    as the left one), hung from its cusp, anchors ``gap`` mm apart (issue 24's hearts)."""
    t = np.linspace(0, 2 * math.pi, 721)[:-1]
    x = 16 * np.sin(t) ** 3
    y = 13 * np.cos(t) - 5 * np.cos(2 * t) - 2 * np.cos(3 * t) - np.cos(4 * t)
    x = x / np.ptp(x) * width
    y = (y - 5) / np.ptp(y) * width * 0.95
    x = np.where(x > 0, x * lobes, x)
    pts = _open_at_top(_arclength_resample(np.column_stack([x, y]), 600), gap, np.zeros(2))
    pts = np.round(pts - pts[0], 3)
    return Shape("heart", f"heart-{width:g}-{lobes:g}", pts[[0, -1]], pts, dict(width=width, gap=gap, lobes=lobes))


def family(n: int, seed: int = 0) -> list[Shape]:
    """``n`` shapes cycling through :data:`KINDS`, each drawn from its own seeded generator."""
    out = []
    for i in range(n):
        rng = np.random.default_rng([seed, i])
        out.append(shape(KINDS[i % len(KINDS)], rng, i))
    return out


def design_text(s: Shape) -> str:
    """The design file a user writes for the shape: anchors and polyline, nothing else."""
    pts = ", ".join(f"[{x:g}, {y:g}]" for x, y in s.points)
    a, b = s.anchors
    return (f"design: 1\nname: {s.name}\nanchors: [[{a[0]:g}, {a[1]:g}], [{b[0]:g}, {b[1]:g}]]\n"
            f"target: {{form: polyline, points: [{pts}]}}\n")


def _main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=24)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--plot", action="store_true", help="also draw every shape into OUT/shapes.png")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    shapes = family(args.n, args.seed)
    for s in shapes:
        (args.out / f"{s.name}.yaml").write_text(design_text(s), encoding="utf-8")
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        cols = 6
        rows = math.ceil(len(shapes) / cols)
        fig, axes = plt.subplots(rows, cols, figsize=(3 * cols, 3 * rows))
        for ax, s in zip(np.ravel(axes), shapes):
            ax.plot(*s.points.T, "-", lw=1)
            ax.plot(*s.anchors.T, "ks", ms=4)
            ax.set_aspect("equal")
            ax.set_title(s.name, fontsize=8)
            ax.axis("off")
        for ax in np.ravel(axes)[len(shapes):]:
            ax.axis("off")
        fig.tight_layout()
        fig.savefig(args.out / "shapes.png", dpi=80)
    print(f"{len(shapes)} design files in {args.out}")


if __name__ == "__main__":
    _main()
