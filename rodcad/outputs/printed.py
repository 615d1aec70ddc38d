"""The chain as printed in design.json and report.md (contract.md "As printed").

Reads a :class:`rodcad.design.asprinted.AsPrinted` (pins in their holes, the friction and
mass bands) and writes the numbers and the sentences that say what they mean.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from optimize.chain.curves import centerline, curve_distance
from rodcad.design.asprinted import AsPrinted, hole_frame
from rodcad.design.shell import curve_size

__all__ = ["as_printed_json", "as_printed_lines", "draw_bands", "printed_rod_fields", "printed_summary"]


def _f(x: float) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def printed_rod_fields(ap: AsPrinted, lengths, com, i: int) -> dict[str, Any]:
    """design.json's per-rod fields: ``printed_pin_spacing`` (mm), ``holes_mm`` (each hole's
    centre minus its hinge axis, rod frame), and where the holes moved ``com`` in the hole
    frame with ``com_rod_frame`` beside it."""
    out: dict[str, Any] = {"printed_pin_spacing": float(ap.spacings[i]),
                           "holes_mm": [[float(v) for v in row] for row in ap.plan.offsets[i]]}
    if np.any(ap.plan.offsets[i] != 0):
        _, com_h, _, _, _ = hole_frame(lengths, com, ap.plan.offsets)
        out["com"] = [float(v) for v in com_h[i]]
        out["com_rod_frame"] = [float(v) for v in np.asarray(com, float)[i]]
    return out


def as_printed_json(ap: AsPrinted, curve: np.ndarray | None, curvature, span: float) -> dict[str, Any]:
    """design.json's ``as_printed``, ``friction_band_mm`` and ``mass_band_mm`` (contract.md)."""
    r = ap.result
    err = ap.distance.as_dict()
    out: dict[str, Any] = {
        "points": [[float(x), float(y)] for x, y in r.points],
        "error": err, "stable": bool(r.stable), "success": bool(r.success), "kkt_residual": _f(r.kkt_residual),
        "clearance_mm": [float(c) for c in ap.plan.clearance], "compensated": bool(ap.plan.compensated),
        "uncompensated_error": None if ap.uncompensated is None else ap.uncompensated.as_dict(),
        "notes": list(ap.notes),
    }
    if curve is not None:
        d = float(curve_distance(curve, centerline(r.points, curvature)))
        size = curve_size(curve)
        out["curve"] = {"max_mm": _f(d), "rel_span": _f(d / span) if span > 0 else None, "size_mm": _f(size),
                        "rel_size": _f(d / size)}
    fb, mb = ap.friction, ap.mass_band
    bands = {
        "friction_band_mm": None if fb is None else float(fb.band),
        "mass_band_mm": None if mb is None else float(mb.band),
        "bands": {
            "friction": None if fb is None else {
                "mu": ap.mu, "per_joint_mm": [float(v) for v in fb.per_joint], "cells": int(fb.cells),
                "exhaustive": bool(fb.exhaustive), "tight": bool(fb.tight), "method": fb.method},
            "mass": None if mb is None else {
                "mass_tolerance": ap.mass_tolerance, "quantile": mb.quantile, "samples": int(mb.n_samples),
                "per_joint_mm": [float(v) for v in mb.per_joint], "method": mb.method},
        },
    }
    return {"as_printed": out, **bands}


def printed_summary(ap: AsPrinted, size: float) -> str:
    """One line for the terminal: pins in holes, and the two bands (mm, % of the target's size)."""
    def mm(v: float) -> str:
        return f"{v:.3g} mm ({100 * v / size:.3g} %)"

    out = f"pins in their holes {mm(ap.distance.max)}"
    if ap.uncompensated is not None:
        out += f" (holes on the axes: {mm(ap.uncompensated.max)})"
    if ap.friction is not None:
        out += f"; friction band {mm(ap.friction.band)}"
    if ap.mass_band is not None:
        out += f"; mass band (95 %) {mm(ap.mass_band.band)}"
    return out


def _worst(per_joint) -> int:
    """The joint (numbered as the report's joints: 0 between rods 0 and 1) whose band is widest,
    from per-joint bands over p_0..p_N."""
    return int(np.argmax(per_joint)) - 1


def _friction_label(ap: AsPrinted) -> str:
    """The friction the band is for: one coefficient, or the joint hardware's ranges."""
    return "each joint's hardware, at the top of its friction range" if ap.hardware else f"coefficient {ap.mu:g}"


def as_printed_lines(ap: AsPrinted, size: float) -> list[str]:
    """report.md's sentences on the chain as printed: pins in their holes, friction, mass."""
    pct = 100.0 / size
    d = ap.distance.max
    clear = max(ap.plan.clearance) if len(ap.plan.clearance) else 0.0
    lines = []
    if ap.plan.compensated and ap.uncompensated is not None:
        u = ap.uncompensated.max
        lines.append(
            f"- **Pins in their holes**: every pin bears on the far side of its {clear:g} mm of clearance. The "
            f"holes are printed where the loaded pins put the rods on the design (the pin spacing "
            f"{float(np.min(ap.spacings)):.3f}-{float(np.max(ap.spacings)):.3f} mm, about the length minus the "
            f"clearance), so the chain as printed hangs {d:.3g} mm ({d * pct:.3g} % of its size) from the target; "
            f"with the holes on the hinge axes it would hang {u:.3g} mm ({u * pct:.3g} %) off.")
    else:
        lines.append(f"- **Pins in their holes** ({clear:g} mm clearance): the chain as printed hangs {d:.3g} mm "
                     f"({d * pct:.3g} % of its size) from the target.")
    fb = ap.friction
    if fb is not None:
        j = _worst(fb.per_joint)
        lines.append(
            f"- **Pin friction** ({_friction_label(ap)}): the chain can come to rest anywhere within "
            f"{fb.band:.3g} mm ({fb.band * pct:.3g} % of its size) of its design"
            + ("" if fb.tight else " (an upper bound: its many stops make the exact band costly)")
            + f", most at joint {j}. Hang it gently: a chain let go far off its shape rests near the band's "
            "edge, and light taps free the pins and bring it back inside the band (not onto the design).")
    mb = ap.mass_band
    if mb is not None:
        j = _worst(mb.per_joint)
        lines.append(
            f"- **Print tolerance**: with every rod's mass within +-{100 * ap.mass_tolerance:g} % (95 %; the "
            f"catalog's print.mass_tolerance), 95 % of printed chains hang within {mb.band:.3g} mm "
            f"({mb.band * pct:.3g} % of its size) of the design, most at joint {j}. Weigh the printed rods "
            "against the masses below: one further off than that is worth printing again.")
    lines += [f"- note: {n}" for n in ap.notes]
    return lines


def draw_bands(ax, ap: AsPrinted, points: np.ndarray, size: float, rest: np.ndarray | None = None) -> None:
    """On a preview: a circle around every joint of the friction band's radius (orange) and
    of the mass band's (purple), magnified by a stated power of ten where the largest would be
    under 2 % of the chain's size (drawn over the rods); with ``rest`` ((N+1, 2), the chain
    after its simulated taps), a green cross where each joint came to rest, its distance from
    the design magnified alike."""
    from matplotlib.patches import Circle

    basis = "top of each pin's friction range" if ap.hardware else f"coefficient {ap.mu:g}"
    bands = [(ap.friction, "C1", f"pin friction band ({basis})"),
             (ap.mass_band, "C4", f"mass band (+-{100 * ap.mass_tolerance:g} %, 95 %)")]
    largest = max([float(np.max(b.per_joint)) for b, _, _ in bands if b is not None], default=0.0)
    scale = 1.0
    if 0 < largest < 0.02 * size:
        scale = float(10 ** math.floor(math.log10(0.05 * size / largest)))
    times = f", radius x{scale:g}" if scale > 1 else ""
    for band, color, label in bands:
        if band is None:
            continue
        for j, (p, rad) in enumerate(zip(points, band.per_joint)):
            if rad > 0:
                ax.add_patch(Circle(p, rad * scale, fc=color, ec=color, alpha=0.35, lw=0.8, zorder=4.5,
                                    label=f"{label}{times}" if j == int(np.argmax(band.per_joint)) else None))
    if rest is not None:
        shown = points + scale * (np.asarray(rest, float) - points)
        ax.plot(*shown.T, "x", color="C2", ms=6, mew=1.5, zorder=6,
                label=f"rest after the simulated taps{', offset x' + format(scale, 'g') if scale > 1 else ''}")
