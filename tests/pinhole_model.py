"""Independent model of a chain whose pins sit in their holes with play.

Uses *no* rodcad / optimize code. Every pin is a free point, every hole a disc of radius
c/2 (diametral clearance c) that the pin's centre must stay inside, every rod a rigid body
(first hole's centre and body angle); anchors A and B are pins fixed in the first and last
rods' holes. The potential energy g sum m_i y(com_i) is minimised by SLSQP over all of them
(5N - 2 unknowns) from a given start, with the stops between rod bodies and the anchor stops
as linear inequalities. Centres of mass are given in the hole frame (origin at the first
hole's centre, x toward the second's).

For a built chain: :func:`step_holes` measures a rod's pin holes on its STEP file (build123d
reads it; the cylinders' axes) and :func:`hang_built` hangs the rods of a design.json with them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.optimize import minimize

__all__ = ["hang_built", "hang_pins_in_holes", "step_holes"]


def hang_pins_in_holes(spacings, masses, a, b, clearance, com, start_holes, start_angles, *,
                       limits=None, end_limits=None, g=9.81, ftol=1e-16, maxiter=3000) -> dict:
    """Minimise the potential energy of rods on pins in holes.

    Args:
        spacings, masses: (N,) hole spacings and masses; a, b: (2,) anchor pins.
        clearance: (N+1,) diametral clearance at each pin (anchors included), > 0.
        com: (N, 2) centres of mass in the hole frame.
        start_holes: (N, 2) the first holes' centres to start from; start_angles: (N,).
        limits: (N-1, 2) bounds on the relative body angles (radians, +-inf free).
        end_limits: (2, 2) bounds on the first and last body angles.

    Returns:
        dict: points (N+1, 2) pins (the anchors at the ends), holes (N, 2, 2), angles (N,),
        energy, success, message, nit, max_violation (largest disc violation, length).
    """
    s = np.asarray(spacings, float)
    m = np.asarray(masses, float)
    c = np.asarray(clearance, float)
    com = np.asarray(com, float)
    n = s.size
    a, b = np.asarray(a, float), np.asarray(b, float)
    r = 0.5 * c
    scale = float(s.sum())

    def unpack(x):
        h0 = x[: 2 * n].reshape(n, 2) * scale
        ang = x[2 * n: 3 * n]
        pins = x[3 * n:].reshape(n - 1, 2) * scale
        u = np.column_stack([np.cos(ang), np.sin(ang)])
        h1 = h0 + s[:, None] * u
        return h0, ang, pins, u, h1

    def energy(x):
        h0, ang, _, _, _ = unpack(x)
        y = h0[:, 1] + com[:, 0] * np.sin(ang) + com[:, 1] * np.cos(ang)
        return g * float(m @ y) / (g * m.sum() * scale)

    def energy_grad(x):
        _, ang, _, _, _ = unpack(x)
        gr = np.zeros_like(x)
        gr[1: 2 * n: 2] = m * scale
        gr[2 * n: 3 * n] = m * (com[:, 0] * np.cos(ang) - com[:, 1] * np.sin(ang))
        return g * gr / (g * m.sum() * scale)

    # disc constraints: 1 - |pin - hole|^2 / r^2 >= 0, one per (pin, hole): rows in the order
    # (A, rod 0 first), then per inner pin j (rod j-1 second, rod j first), then (B, rod N-1 second)
    k = np.arange(1, n)
    rod = np.concatenate([[0], np.column_stack([k - 1, k]).ravel(), [n - 1]])
    second = np.concatenate([[False], np.tile([True, False], n - 1), [True]])
    pin = np.concatenate([[-1], np.repeat(k - 1, 2), [-2]])  # -1 = A, -2 = B
    radius = np.concatenate([[r[0]], np.repeat(r[1:n], 2), [r[n]]])
    rows_n = rod.size

    def geometry(x):
        h0, ang, pins, u, h1 = unpack(x)
        pts = np.vstack([pins, b, a])  # index -1 -> a, -2 -> b
        gap = pts[pin] - np.where(second[:, None], h1[rod], h0[rod])
        return gap, ang

    def discs(x):
        gap, _ = geometry(x)
        return 1.0 - np.sum(gap ** 2, axis=1) / radius ** 2

    def discs_jac(x):
        gap, ang = geometry(x)
        dv = -2.0 * gap / radius[:, None] ** 2  # d/d(pin)
        J = np.zeros((rows_n, x.size))
        idx = np.arange(rows_n)
        J[idx, 2 * rod] = -dv[:, 0] * scale
        J[idx, 2 * rod + 1] = -dv[:, 1] * scale
        dh = s[rod, None] * np.column_stack([-np.sin(ang[rod]), np.cos(ang[rod])])
        J[idx, 2 * n + rod] = np.where(second, -np.sum(dv * dh, axis=1), 0.0)
        inner = pin >= 0
        J[idx[inner], 3 * n + 2 * pin[inner]] = dv[inner, 0] * scale
        J[idx[inner], 3 * n + 2 * pin[inner] + 1] = dv[inner, 1] * scale
        return J

    rows, rhs = [], []
    if limits is not None:
        for j, (lo, hi) in enumerate(np.asarray(limits, float)):
            e = np.zeros(5 * n - 2)
            e[2 * n + j + 1], e[2 * n + j] = 1.0, -1.0
            if np.isfinite(lo):
                rows.append(e), rhs.append(lo)
            if np.isfinite(hi):
                rows.append(-e), rhs.append(-hi)
    if end_limits is not None:
        for k, (lo, hi) in zip((0, n - 1), np.asarray(end_limits, float)):
            e = np.zeros(5 * n - 2)
            e[2 * n + k] = 1.0
            if np.isfinite(lo):
                rows.append(e), rhs.append(lo)
            if np.isfinite(hi):
                rows.append(-e), rhs.append(-hi)
    cons = [{"type": "ineq", "fun": discs, "jac": discs_jac}]
    if rows:
        A, lb = np.array(rows), np.array(rhs)
        cons.append({"type": "ineq", "fun": lambda x: A @ x - lb, "jac": lambda x: A})

    h0s = np.asarray(start_holes, float)
    ang0 = np.asarray(start_angles, float)
    u0 = np.column_stack([np.cos(ang0), np.sin(ang0)])
    h1s = h0s + s[:, None] * u0
    pins0 = 0.5 * (h1s[:-1] + h0s[1:])
    x0 = np.concatenate([h0s.ravel() / scale, ang0, pins0.ravel() / scale])
    res = minimize(energy, x0, jac=energy_grad, constraints=cons, method="SLSQP",
                   options={"ftol": ftol, "maxiter": maxiter})
    h0, ang, pins, _, h1 = unpack(res.x)
    return {
        "points": np.vstack([a, pins, b]),
        "holes": np.stack([h0, h1], axis=1),
        "angles": ang,
        "energy": res.fun,
        "success": bool(res.success),
        "message": res.message,
        "nit": res.nit,
        "max_violation": float(max(0.0, -np.min(discs(res.x) * radius ** 2) / (2 * radius.min()))),
    }


def _rad(pair):
    if pair is None:
        return [-np.inf, np.inf]
    return [-np.inf if pair[0] is None else np.radians(pair[0]), np.inf if pair[1] is None else np.radians(pair[1])]


def step_holes(path: Path, print_matrix, hole_radius, length: float) -> np.ndarray:
    """(2, 2) the pin holes' centres (rod frame) measured on a rod's STEP file: the axes of its
    cylindrical faces of the hole's radius (one, or one per end: (first, second)), the one near
    x = 0 first."""
    from build123d import GeomType, import_step
    from OCP.BRepAdaptor import BRepAdaptor_Surface

    inv = np.linalg.inv(np.asarray(print_matrix, float))
    found = []
    for face in import_step(str(path)).faces():
        if face.geom_type != GeomType.CYLINDER:
            continue
        cyl = BRepAdaptor_Surface(face.wrapped).Cylinder()
        if min(abs(cyl.Radius() - r) for r in np.atleast_1d(hole_radius)) > 1e-6:
            continue
        loc = cyl.Location()
        found.append((inv @ np.array([loc.X(), loc.Y(), loc.Z(), 1.0]))[:2])
    found = np.array(found)
    first = found[found[:, 0] < length / 2]
    second = found[found[:, 0] >= length / 2]
    if not (len(first) and len(second)) or max(np.ptp(g, axis=0).max() for g in (first, second)) > 1e-6:
        raise ValueError(f"{path}: not two pin holes, each on one axis")
    return np.array([first[0], second[0]])


def hang_built(d: dict, holes: np.ndarray) -> np.ndarray:
    """A built chain (``d``: its design.json) hung by the independent model: holes (N, 2, 2) in
    the rod frames (e.g. measured by :func:`step_holes`), the B-rep's masses and centres of
    mass (design.json ``fabrication``), the design's stops on the rod bodies. Returns the pins."""
    rods = d["rods"]
    n = len(rods)
    mass = np.array([r["fabrication"]["mass"] for r in rods])
    com = np.array([r["fabrication"]["com"] for r in rods])  # rod frame, from the B-rep
    # the joint hardware's metal (pins, sleeves, bearings) at the rods' hinge axes, where the
    # loaded pins sit (design.json rods[].hardware.metal_g)
    metal = np.array([(r.get("hardware") or {}).get("metal_g", [0.0, 0.0]) for r in rods], float)
    lengths = np.array([r["length"] for r in rods], float)
    hung = mass + metal.sum(axis=1)
    com = (mass[:, None] * com + np.column_stack([metal[:, 1] * lengths, np.zeros(n)])) / hung[:, None]
    mass = hung
    axis = holes[:, 1] - holes[:, 0]
    spacing = np.hypot(axis[:, 0], axis[:, 1])
    turn = np.arctan2(axis[:, 1], axis[:, 0])
    rel = com - holes[:, 0]
    com_h = np.column_stack([np.cos(turn) * rel[:, 0] + np.sin(turn) * rel[:, 1],
                             -np.sin(turn) * rel[:, 0] + np.cos(turn) * rel[:, 1]])
    lim = np.array([_rad(r["limits_deg"]) for r in rods[:-1]]) + np.diff(turn)[:, None]
    ends = np.array([_rad(p) for p in d["anchor_limits_deg"]]) + np.array([[turn[0]], [turn[-1]]])
    clearance = np.array([r["params"]["pin_clearance"] for r in rods] + [rods[-1]["params"]["pin_clearance"]])
    if d.get("hardware"):  # each pin's own play
        clearance = np.array([p.get("clearance_mm", 0.0) if p.get("option") else 0.0 for p in d["hardware"]["pins"]])
    pts = np.array(d["simulated"]["points"])
    theta = np.arctan2(*np.diff(pts, axis=0).T[::-1])
    start = pts[:-1] + np.column_stack([np.cos(theta) * holes[:, 0, 0] - np.sin(theta) * holes[:, 0, 1],
                                        np.sin(theta) * holes[:, 0, 0] + np.cos(theta) * holes[:, 0, 1]])
    windows = ends.copy()  # anchor stops on the turn of the start (one bound: its half turn)
    for e, t in ((0, theta[0] + turn[0]), (1, theta[-1] + turn[-1])):
        lo, hi = windows[e]
        if np.isinf(lo) and np.isinf(hi):
            continue
        windows[e] = [hi - np.pi if np.isinf(lo) else lo, lo + np.pi if np.isinf(hi) else hi]
        windows[e] += 2 * np.pi * np.round((t - windows[e].mean()) / (2 * np.pi))
    a, b = np.array(d["anchors"], float)
    ref = hang_pins_in_holes(spacing, mass, a, b, clearance, com_h, start, theta + turn,
                             limits=lim if n > 1 else None, end_limits=windows, ftol=1e-14)
    if ref["max_violation"] > 1e-9:
        raise RuntimeError(f"the independent model left a pin {ref['max_violation']:.2e} outside its hole")
    return ref["points"]
