"""Target curves: dense polylines from anchor A to anchor B (mm, y up).

Every form returns an (M, 2) array whose first point is A and last point is B:
``polyline``, ``arc`` (by sag), ``semicircle``, ``triangle``, ``polygon`` (lower
half of a regular polygon on AB), ``heart``, ``catenary`` (by length), ``function``
(y as an expression in x) and ``svg`` (an SVG path 'd' string, mapped so that its
ends land on the anchors).
"""

from __future__ import annotations

import ast
import math

import numpy as np

__all__ = [
    "TARGET_FORMS",
    "arc",
    "catenary",
    "function",
    "heart",
    "make_target",
    "polygon",
    "polyline",
    "semicircle",
    "svg_path",
    "triangle",
]


def _frame(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = b - a
    span = float(np.hypot(*d))
    if span <= 0:
        raise ValueError("the anchors coincide")
    u = d / span
    n = np.array([-u[1], u[0]])  # left of A->B: "up" when B is to the right of A
    return a, u, n, span


def _place(a, b, local: np.ndarray) -> np.ndarray:
    """Map points given in the frame (x along AB from 0 to 1, y up, unit = span) to the plane."""
    a0, u, n, span = _frame(a, b)
    pts = a0 + span * (local[:, :1] * u + local[:, 1:] * n)
    pts[0], pts[-1] = a, b
    return pts


def polyline(a, b, points) -> np.ndarray:
    """The given points; they must start at A and end at B."""
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 2:
        raise ValueError("a polyline needs at least two [x, y] points")
    span = np.hypot(*(np.asarray(b, float) - np.asarray(a, float)))
    if np.hypot(*(pts[0] - a)) > 1e-6 * span or np.hypot(*(pts[-1] - b)) > 1e-6 * span:
        raise ValueError(
            f"the polyline must start at anchor A {list(map(float, a))} and end at anchor B "
            f"{list(map(float, b))}; it runs from {pts[0].tolist()} to {pts[-1].tolist()}"
        )
    return pts


def arc(a, b, sag: float, samples: int = 400) -> np.ndarray:
    """Circular arc from A to B hanging `sag` mm below the chord's midpoint."""
    _, _, _, span = _frame(a, b)
    h = float(sag) / span
    if h <= 0:
        raise ValueError("sag must be positive")
    r = (0.25 + h * h) / (2 * h)  # radius in span units
    centre = np.array([0.5, r - h])
    start = math.atan2(-centre[1], -0.5)
    end = math.atan2(-centre[1], 0.5)
    if end < start:  # go round the bottom, counter-clockwise from A to B
        end += 2 * math.pi
    t = np.linspace(start, end, samples)
    local = centre + r * np.column_stack([np.cos(t), np.sin(t)])
    return _place(a, b, local)


def semicircle(a, b, samples: int = 400) -> np.ndarray:
    """Half circle on AB as diameter, hanging below."""
    _, _, _, span = _frame(a, b)
    return arc(a, b, sag=span / 2, samples=samples)


def triangle(a, b, depth: float, apex: float = 0.5) -> np.ndarray:
    """A -> apex -> B; the apex `depth` mm below AB at fraction `apex` along it."""
    _, _, _, span = _frame(a, b)
    if depth <= 0:
        raise ValueError("depth must be positive")
    local = np.array([[0.0, 0.0], [apex, -depth / span], [1.0, 0.0]])
    return _place(a, b, local)


def polygon(a, b, sides: int) -> np.ndarray:
    """`sides` equal edges: the lower half of a regular 2*sides-gon with AB as diameter."""
    if int(sides) < 2:
        raise ValueError("a polygon target needs at least 2 sides")
    k = int(sides)
    ang = np.pi + np.arange(k + 1) * np.pi / k
    local = np.column_stack([0.5 + 0.5 * np.cos(ang), 0.5 * np.sin(ang)])
    return _place(a, b, local)


def heart(a, b, samples: int = 600) -> np.ndarray:
    """The classic heart outline, hung from the tops of its two lobes (A and B).

    Uses x = 16 sin^3 t, y = 13 cos t - 5 cos 2t - 2 cos 3t - cos 4t, traversed from the
    left lobe's top round its outside, the bottom tip and the right lobe to its top; the
    cusp between the lobes is left open. The heart is about 2.3 times as tall as A and B
    are apart. Its lobes turn back over the anchors, which a hanging chain reaches only
    with stops (rigid runs), so it is a bounded best-fit target.
    """
    t0 = 0.9081  # parameter of the lobe tops (where y is largest)
    t = np.linspace(-t0, -2 * np.pi + t0, samples)  # clockwise from left of the cusp
    x = 16 * np.sin(t) ** 3
    y = 13 * np.cos(t) - 5 * np.cos(2 * t) - 2 * np.cos(3 * t) - np.cos(4 * t)
    pts = np.column_stack([x, y])
    # similarity map sending the first point to A and the last to B
    p0, p1 = pts[0], pts[-1]
    scale = 1.0 / np.hypot(*(p1 - p0))
    local = (pts - p0) * scale
    return _place(a, b, local)


def catenary(a, b, length: float, samples: int = 400) -> np.ndarray:
    """The continuous catenary of the given length hung from A and B."""
    from scipy.optimize import brentq

    a0, u, n, span = _frame(a, b)
    a_, b_ = np.asarray(a, float), np.asarray(b, float)
    dx, dy = b_[0] - a_[0], b_[1] - a_[1]
    if length <= np.hypot(dx, dy):
        raise ValueError(f"length {length} must exceed the anchor distance {np.hypot(dx, dy):.6g}")
    if abs(dx) < 1e-12:
        raise ValueError("a catenary needs anchors at different x")
    # sqrt(L^2 - dy^2) = 2 c sinh(dx / 2c)
    target = math.sqrt(length**2 - dy**2)
    f = lambda c: 2 * c * math.sinh(abs(dx) / (2 * c)) - target  # noqa: E731
    lo = abs(dx) / 1400.0
    c = brentq(f, lo, 1e9 * abs(dx))
    # vertex x0: y = c cosh((x - x0)/c) + k through both anchors
    x0 = (a_[0] + b_[0]) / 2 - c * math.asinh(dy / (2 * c * math.sinh(dx / (2 * c))))
    x = np.linspace(a_[0], b_[0], samples)
    y = c * np.cosh((x - x0) / c)
    y += a_[1] - y[0]
    pts = np.column_stack([x, y])
    pts[0], pts[-1] = a_, b_
    return pts


_SAFE_FUNCS = {
    name: getattr(np, name)
    for name in ("sin", "cos", "tan", "exp", "log", "sqrt", "abs", "sinh", "cosh", "tanh",
                 "arcsin", "arccos", "arctan", "minimum", "maximum")
}
_SAFE_CONSTS = {"pi": math.pi, "e": math.e}


def _safe_eval(expr: str, x: np.ndarray) -> np.ndarray:
    tree = ast.parse(expr, mode="eval")
    allowed = (ast.Expression, ast.BinOp, ast.UnaryOp, ast.Call, ast.Name, ast.Load,
               ast.Constant, ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow, ast.USub, ast.UAdd,
               ast.Mod)
    for node in ast.walk(tree):
        if not isinstance(node, allowed):
            raise ValueError(f"unsupported syntax in y(x) expression: {type(node).__name__}")
        if isinstance(node, ast.Name) and node.id not in {"x", *_SAFE_FUNCS, *_SAFE_CONSTS}:
            raise ValueError(f"unknown name {node.id!r} in y(x) expression (use x, pi, sin, ...)")
        if isinstance(node, ast.Call) and not isinstance(node.func, ast.Name):
            raise ValueError("only plain function calls such as cos(x) are allowed")
    env = {"x": x, **_SAFE_FUNCS, **_SAFE_CONSTS}
    with np.errstate(all="ignore"):
        y = eval(compile(tree, "<y(x)>", "eval"), {"__builtins__": {}}, env)  # noqa: S307
    return np.broadcast_to(np.asarray(y, dtype=float), x.shape).copy()


def function(a, b, y: str, samples: int = 400) -> np.ndarray:
    """y as an expression in x (mm), sampled from A.x to B.x; it must pass through both anchors."""
    a_, b_ = np.asarray(a, float), np.asarray(b, float)
    x = np.linspace(a_[0], b_[0], samples)
    yy = _safe_eval(y, x)
    if not np.all(np.isfinite(yy)):
        raise ValueError("y(x) is not finite everywhere between the anchors")
    tol = 1e-3 * max(1.0, np.hypot(*(b_ - a_)))
    if abs(yy[0] - a_[1]) > tol or abs(yy[-1] - b_[1]) > tol:
        raise ValueError(
            f"y(x) must pass through the anchors: y({a_[0]:g}) = {yy[0]:.6g} (A.y = {a_[1]:g}), "
            f"y({b_[0]:g}) = {yy[-1]:.6g} (B.y = {b_[1]:g})"
        )
    pts = np.column_stack([x, yy])
    pts[0], pts[-1] = a_, b_
    return pts


def svg_path(a, b, d: str, samples: int = 800) -> np.ndarray:
    """An SVG path ('d' attribute), y flipped to point up, moved, turned and scaled so that
    its start lands on A and its end on B."""
    from svgpathtools import parse_path

    try:
        path = parse_path(d)
    except Exception as exc:  # svgpathtools raises bare exceptions on bad syntax
        raise ValueError(f"cannot parse the SVG path: {exc}") from None
    if len(path) == 0 or path.length() == 0:
        raise ValueError("the SVG path is empty")
    # sample segment by segment so that corners between segments stay exact
    from svgpathtools import Line

    total = path.length()
    z = [path[0].start]
    for seg in path:
        if isinstance(seg, Line):
            z.append(seg.end)
            continue
        k = max(2, int(np.ceil(samples * seg.length() / total)))
        z.extend(seg.point(ti) for ti in np.linspace(0, 1, k)[1:])
    z = np.array(z)
    pts = np.column_stack([z.real, -z.imag])  # SVG y points down
    p0, p1 = pts[0], pts[-1]
    chord = p1 - p0
    if np.hypot(*chord) == 0:
        raise ValueError("the SVG path is closed: its start and end must differ (they become A and B)")
    a_, b_ = np.asarray(a, float), np.asarray(b, float)
    za, zb = complex(*a_), complex(*b_)
    w = (zb - za) / complex(*chord)  # rotation and scale as one complex factor
    zz = za + w * ((pts[:, 0] - p0[0]) + 1j * (pts[:, 1] - p0[1]))
    out = np.column_stack([zz.real, zz.imag])
    out[0], out[-1] = a_, b_
    return out


#: Target forms and their parameters (name -> (function, required, optional)).
TARGET_FORMS = {
    "polyline": (polyline, ("points",), ()),
    "arc": (arc, ("sag",), ("samples",)),
    "semicircle": (semicircle, (), ("samples",)),
    "triangle": (triangle, ("depth",), ("apex",)),
    "polygon": (polygon, ("sides",), ()),
    "heart": (heart, (), ("samples",)),
    "catenary": (catenary, ("length",), ("samples",)),
    "function": (function, ("y",), ("samples",)),
    "svg": (svg_path, ("d",), ("samples",)),
}


def make_target(form: str, a, b, **params) -> np.ndarray:
    """Build a target curve by form name (see TARGET_FORMS)."""
    if form not in TARGET_FORMS:
        raise ValueError(f"unknown target form {form!r}; one of {', '.join(TARGET_FORMS)}")
    fn, required, optional = TARGET_FORMS[form]
    missing = [k for k in required if k not in params]
    if missing:
        raise ValueError(f"target {form} needs {', '.join(missing)}")
    extra = [k for k in params if k not in required + optional]
    if extra:
        raise ValueError(f"target {form} takes no {', '.join(extra)}")
    return fn(a, b, **params)
