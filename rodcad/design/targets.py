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

__all__ = ['polyline', 'arc', 'semicircle', 'triangle', 'polygon', 'heart', 'closed_heart', 'catenary', 'function', 'svg_path', 'TARGET_FORMS', 'make_target']


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
    """The lower outline of a heart, hung from the widest points of its lobes (A and B).

    The heart is the classic geometric one: a square standing on a corner (the tip), with a
    half circle on each of its two upper sides (the lobes). The target runs from the left
    lobe's widest point down its outside (an eighth of a circle), along the straight left
    side to the tip (a 90 degree corner), and back up the other side to the right lobe's
    widest point. A and B are 1.71 times the square's side apart; the tip hangs 1.06 sides
    below them.

    Why only the lower outline: a chain between two anchors is one open curve, and a hanging
    chain is in tension, so every rod whose joints are free points from A toward B (its
    chord has a positive x component). The rest of the outline (the lobes' tops and the dip
    between them) lies above the widest points and turns back toward the anchors: as part
    of the chain it would be in compression. The paper's Fig. 9 heart prints that "central"
    part as one rigid body; here it is the mount that holds A and B. What the chain must do
    is still more than a curve of free joints can: straight sides (stops at straight) that
    meet a freely bending tip and freely bending lobe arcs, and near-vertical ends (mass
    ratios beyond fabrication bounds), so it is a bounded best-fit target.
    """
    _, _, _, span = _frame(a, b)
    c = np.sqrt(0.5)
    s = 1.0 / (1.0 + c)  # square side in span units: span = (1 + 1/sqrt 2) s
    r = s / 2
    # frame: A at (0, 0), B at (1, 0); lobe centres at the anchors' height
    centre_l = np.array([r, 0.0])
    centre_r = np.array([1.0 - r, 0.0])
    tip = np.array([0.5, -1.5 * c * s])  # the lobe's lowest side end is c*s/2 below A
    k = max(8, samples // 6)
    t = np.linspace(np.pi, 1.25 * np.pi, k)  # widest point down to where the side leaves
    arc_l = centre_l + r * np.column_stack([np.cos(t), np.sin(t)])
    arc_r = (centre_r + r * np.column_stack([np.cos(-t + np.pi), np.sin(-t + np.pi)]))[::-1]
    m = max(2, samples // 3)
    side_l = arc_l[-1] + np.linspace(0, 1, m)[1:, None] * (tip - arc_l[-1])
    side_r = tip + np.linspace(0, 1, m)[1:, None] * (arc_r[0] - tip)
    local = np.vstack([arc_l, side_l, side_r[:-1], arc_r])
    return _place(a, b, local)


def closed_heart(a, b, width: float, bulge: float = 0.0, samples: int = 800) -> np.ndarray:
    """The whole outline of a heart hung from its cusp (the paper's Fig. 9): A and B sit on
    the two lobes' inner arcs just beside the cusp, ``width`` mm is the heart's full width.

    The classic heart: a square of side s standing on a corner (the tip), with a half circle
    on each of its upper sides (the lobes); width = s (1 + 1/sqrt 2). From A the outline
    rises over the left lobe (above the anchors), comes down its outside to the square's
    left corner, runs straight to the tip, back up to the right corner and over the right
    lobe down to B. The lobes turn back on themselves: held from the anchor fixture by
    stops (``constraints: {anchor_stops: auto}``), while the lower part can hang.
    ``bulge`` (0 to 0.25) rounds the lower sides outward: an arc whose sagitta is that
    fraction of the side (0: straight sides, which only stops can hold).
    """
    _, _, _, gap = _frame(a, b)
    w = float(width) / gap  # in units of the anchors' distance
    c = np.sqrt(0.5)
    s = w / (1.0 + c)
    r = s / 2
    if w < 3.0:
        raise ValueError(f"width {float(width):g} mm is less than 3 times the anchors' distance ({gap:g} mm): "
                         "the anchors sit beside the cusp, a short fixture apart")
    # cusp at (0.5, ycusp); left lobe centre M_l, the lobe spans the side cusp -> left corner
    ml = np.array([0.5 - s * c / 2, 0.0])
    # A lies on the left lobe's circle at x = 0 (|A - M_l| = r): its height fixes the frame
    dy = math.sqrt(max(r * r - (ml[0] - 0.0) ** 2, 0.0))
    cusp_to_centre = s * c / 2
    ml[1] = -dy  # A at (0, 0) on the circle, above the centre
    cusp = np.array([0.5, ml[1] + cusp_to_centre])
    left = cusp + s * np.array([-c, -c])
    tip = cusp + s * np.array([0.0, -2 * c])
    a0 = math.atan2(0.0 - ml[1], 0.0 - ml[0])  # A's angle on the lobe circle
    a1 = math.atan2(left[1] - ml[1], left[0] - ml[0]) + 2 * math.pi  # round over the top
    k = max(16, samples // 3)
    t = np.linspace(a0, a1, k)
    lobe = ml + r * np.column_stack([np.cos(t), np.sin(t)])
    m = max(4, samples // 6)
    if not 0.0 <= float(bulge) <= 0.25:
        raise ValueError(f"bulge {float(bulge):g} must be between 0 (straight sides) and 0.25")
    u = np.linspace(0, 1, m)[1:, None]
    side = left + u * (tip - left)
    if bulge:  # a circular arc through left and tip, bulging away from the heart's axis
        chord = tip - left
        length = float(np.hypot(*chord))
        out = np.array([chord[1], -chord[0]]) / length  # outward (left-down) normal
        h = float(bulge) * length
        radius = (length * length / 4 + h * h) / (2 * h)
        centre = left + chord / 2 - out * (radius - h)
        t0 = math.atan2(*(left - centre)[::-1])
        t1 = math.atan2(*(tip - centre)[::-1])
        dt = (t1 - t0 + math.pi) % (2 * math.pi) - math.pi
        ts = t0 + u[:, 0] * dt
        side = centre + radius * np.column_stack([np.cos(ts), np.sin(ts)])
    half = np.vstack([lobe, side])
    other = np.column_stack([1.0 - half[::-1, 0], half[::-1, 1]])  # mirror about x = 0.5
    local = np.vstack([half, other[1:]])
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


#: Longest y(x) expression (characters) and deepest nesting read.
MAX_EXPRESSION = 2000
MAX_EXPRESSION_DEPTH = 60


def _safe_eval(expr: str, x: np.ndarray) -> np.ndarray:
    """Evaluate a y(x) expression on numbers only (see :func:`evaluate_expression`)."""
    return evaluate_expression(expr, {"x": x}, what="y(x)")


def evaluate_expression(expr: str, variables: dict[str, np.ndarray], *, what: str = "y(x)") -> np.ndarray:
    """Evaluate an arithmetic expression of ``variables`` on numbers only.

    Only numbers, the variables, ``pi``, ``e``, + - * / % ** and the functions sin, cos,
    tan, exp, log, sqrt, abs, sinh, cosh, tanh, arcsin, arccos, arctan, minimum, maximum are
    read; every constant becomes a float, so powers overflow to inf instead of building
    huge integers, and strings, attributes, subscripts and keywords are refused.

    Args:
        expr: the expression, e.g. ``'0.002 * ((x - 80)**2 + (y - 80)**2) - 40'``.
        variables: name -> array (all of one shape, or broadcastable).
        what: how messages name the expression (``'z(x, y)'``).

    Returns:
        The values, broadcast to the variables' shape.

    Raises:
        ValueError: unreadable, unsupported or unknown names, in words.
    """
    if len(expr) > MAX_EXPRESSION:
        raise ValueError(f"the {what} expression is {len(expr)} characters long; keep it under {MAX_EXPRESSION}")
    try:
        tree = ast.parse(expr, mode="eval")
    except (SyntaxError, RecursionError, MemoryError) as err:
        raise ValueError(f"cannot read the {what} expression: {getattr(err, 'msg', None) or 'it nests too deep'}") \
            from None
    if _depth(tree) > MAX_EXPRESSION_DEPTH:
        raise ValueError(f"the {what} expression nests more than {MAX_EXPRESSION_DEPTH} levels deep")
    allowed = (ast.Expression, ast.BinOp, ast.UnaryOp, ast.Call, ast.Name, ast.Load,
               ast.Constant, ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow, ast.USub, ast.UAdd,
               ast.Mod)
    names = ", ".join(variables)
    for node in ast.walk(tree):
        if not isinstance(node, allowed):
            raise ValueError(f"unsupported syntax in {what} expression: {type(node).__name__}")
        if isinstance(node, ast.Name) and node.id not in {*variables, *_SAFE_FUNCS, *_SAFE_CONSTS}:
            raise ValueError(f"unknown name {node.id!r} in {what} expression (use {names}, pi, sin, ...)")
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id not in _SAFE_FUNCS:
            raise ValueError(f"unknown name {node.func.id!r} in {what} expression (use {names}, pi, sin, ...)")
        if isinstance(node, ast.Call) and (not isinstance(node.func, ast.Name) or node.keywords):
            raise ValueError(f"only plain calls of sin, cos, sqrt, ... are allowed in the {what} expression")
        if isinstance(node, ast.Constant):
            if not isinstance(node.value, (int, float)) or isinstance(node.value, bool):
                raise ValueError(f"only numbers may stand in a {what} expression, not {node.value!r}")
            node.value = float(node.value)  # no unbounded integer arithmetic (9**9**9)
    env = {**_SAFE_FUNCS, **_SAFE_CONSTS, **variables}
    shape = np.broadcast_shapes(*(np.shape(a) for a in variables.values())) if variables else ()
    with np.errstate(all="ignore"):
        try:
            y = eval(compile(tree, f"<{what}>", "eval"), {"__builtins__": {}}, env)  # noqa: S307
        except (OverflowError, ZeroDivisionError, TypeError, ValueError) as err:
            raise ValueError(f"cannot evaluate the {what} expression: {err}") from None
    return np.broadcast_to(np.asarray(y, dtype=float), shape).copy()


def _depth(node: ast.AST) -> int:
    """Nesting depth of an expression tree (iteratively: no recursion limit to hit)."""
    deepest, stack = 0, [(node, 1)]
    while stack:
        n, d = stack.pop()
        deepest = max(deepest, d)
        stack.extend((c, d + 1) for c in ast.iter_child_nodes(n))
    return deepest


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
    from rodcad.yamlspec import MAX_MAGNITUDE

    coords = [abs(c) for seg in path for c in getattr(seg, "bpoints", lambda: ())()]
    if coords and (not np.all(np.isfinite(coords)) or max(coords) > MAX_MAGNITUDE):
        raise ValueError(f"the SVG path has a coordinate beyond {MAX_MAGNITUDE:g}: no drawing is that large")
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
    "closed-heart": (closed_heart, ("width",), ("bulge", "samples")),
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
