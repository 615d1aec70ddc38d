"""The joint hardware in the outputs: design.json's ``hardware`` and ``rods[].hardware``, the
bill of materials' pins, sleeves and bearings, report.md's "Joint hardware" section and the
summary's line (from a :class:`rodcad.results.BuildResult` with its
:class:`rodcad.design.hardware.JointHardware`)."""

from __future__ import annotations

from collections import Counter
from typing import Any

import numpy as np

__all__ = ["hardware_bill", "hardware_json", "hardware_lines", "hardware_summary", "rods_hardware_json", "tapping_json",
           "tapping_sentence"]


def _f(x) -> float | None:
    x = float(x)
    return x if np.isfinite(x) else None


def rods_hardware_json(r) -> list[dict[str, Any]] | None:
    """design.json's ``rods[].hardware``, per rod: the option at each of its joints, the metal
    it carries there (g, at the hinge axes) and what it weighs printed, without that metal."""
    hw = r.hardware
    if hw is None:
        return None
    metal, holes = r.metal, hw.holes(r.rods)
    return [{"first": None if hw.options[i] is None else hw.options[i].name,
             "second": None if hw.options[i + 1] is None else hw.options[i + 1].name,
             "metal_g": [float(v) for v in metal[i]], "holes_mm": [float(v) for v in holes[i]],
             "printed_mass": float(r.masses[i] - metal[i].sum())} for i in range(r.n)]


def hardware_json(r) -> dict[str, Any] | None:
    """design.json's ``hardware``: per pin (0 at anchor A .. N at B) its option, load, rated
    load, friction and the moment it holds; the band it was chosen for."""
    hw = r.hardware
    if hw is None:
        return None
    pins = []
    for k, o in enumerate(hw.options):
        if o is None:
            pins.append({"pin": k, "option": None, "note": "fused joint: no pin"})
            continue
        pins.append({"pin": k, "option": o.name, "kind": o.kind, "pin_diameter_mm": o.pin_diameter,
                     "clearance_mm": o.clearance, "holes_mm": {"tongue": o.tongue_hole, "fork": o.fork_hole},
                     "friction": list(o.friction), "torque_nmm": list(o.torque), "measured": o.measured,
                     "load_n": _f(hw.loads[k]), "rated_n": _f(hw.rated[k]), "safety": hw.safety,
                     "capacity_nmm": _f(hw.capacity[k])})
    hung = r.hung
    return {"pins": pins, "friction_band_mm": None if hw.band is None else _f(hw.band),
            "budget_mm": _f(hw.budget), "upgraded": [int(k) for k in hw.upgraded],
            "overloaded": [int(k) for k in hw.overloaded], "notes": list(hw.notes),
            "design_rounds": None if hung is None else int(hung.rounds),
            "com_change_mm": None if hung is None else _f(hung.com_change)}


def tapping_json(r) -> dict[str, Any] | None:
    """design.json's ``tapping``: where the chain rests after it is hung 0.01 rad off its shape
    (``deviation_mm[0]``) and after each light tap (MuJoCo with the pins' friction)."""
    t = getattr(r, "tapping", None)
    if t is None:
        return None
    return {"taps": int(t.taps), "seed": int(t.seed), "deviation_mm": [_f(v) for v in t.deviation],
            "final_mm": _f(t.deviation[-1]), "largest_mm": _f(np.max(t.deviation)),
            "per_joint_mm": [_f(v) for v in t.per_joint], "final_points": [[_f(x), _f(y)] for x, y in t.rests[-1]],
            "converged": bool(t.converged), "settle_error_mm": _f(t.drift + np.max(t.end_error)),
            "message": t.message}


def tapping_sentence(r, size: float) -> str | None:
    """report.md's line on tapping: where the simulated chain came to rest."""
    t = getattr(r, "tapping", None)
    if t is None:
        return None
    dev = t.deviation
    return (f"- **Tapped** (MuJoCo, each pin's friction at the top of its range): hung 0.01 rad off its shape the "
            f"chain came to rest {dev[0]:.3g} mm from its design; after each of {t.taps} light taps it rested "
            f"within {dev[1:].min():.3g}-{dev[1:].max():.3g} mm ({100 * dev[1:].max() / size:.3g} % of its size), "
            f"{dev[-1]:.3g} mm after the last. Taps free the pins and let the chain settle anywhere in its band, "
            "not back onto the design: with these parts the band itself is small."
            + ("" if t.converged else f" (not every settle came to rest: {t.message})"))


def hardware_bill(r, length: float) -> list[dict[str, Any]]:
    """The bill of materials' ``hardware``: each option used, how many joints, what to buy
    (pins cut to ``length`` mm; bearings counted one by one)."""
    hw = r.hardware
    if hw is None:
        return []
    used = Counter(o.name for o in hw.options if o is not None)
    out = []
    for name, joints in used.items():
        o = next(x for x in hw.options if x is not None and x.name == name)
        entry = {"option": name, "description": o.description, "joints": joints,
                 "pins": {"count": joints, "diameter_mm": o.pin_diameter, "length_mm": length}}
        if o.kind == "bushing":
            entry["sleeves"] = {"count": joints, "outer_diameter_mm": o.outer_diameter, "length_mm": length}
        if o.kind == "bearing":
            entry["bearings"] = {"count": joints * o.count, "outer_diameter_mm": o.outer_diameter,
                                 "bore_mm": o.pin_diameter, "width_mm": o.width}
        out.append(entry)
    return out


def hardware_lines(r, data: dict[str, Any]) -> list[str]:
    """report.md's "Joint hardware" section."""
    hw = data.get("hardware")
    if hw is None:
        return []
    L = ["## Joint hardware", "",
         "Each joint has the cheapest hardware of the catalog that carries its load (with a safety factor of "
         f"{r.hardware.safety:g}) and keeps the chain's friction band within "
         f"{hw['budget_mm']:.3g} mm (a tenth of the tolerance, 0.1 % of the size at most): the band is reported at the top of every "
         "part's friction range. Pin 0 is at anchor A, pin k between rods k-1 and k.", "",
         "| pin | hardware | load N | rated N | friction | holds N mm | tongue / fork hole mm |",
         "|---|---|---|---|---|---|---|"]
    for p in hw["pins"]:
        if p["option"] is None:
            L.append(f"| {p['pin']} | fused: no pin | - | - | - | - | - |")
            continue
        lo, hi = p["friction"]
        fr = f"{lo:g}-{hi:g}" + (" (measured)" if p["measured"] else "")
        L.append(f"| {p['pin']} | {p['option']} | {p['load_n']:.2f} | {p['rated_n']:.0f} | {fr} | "
                 f"{p['capacity_nmm']:.3g} | {p['holes_mm']['tongue']:g} / {p['holes_mm']['fork']:g} |")
    L.append("")
    band = hw["friction_band_mm"]
    if band is not None:
        L.append(f"With these parts the chain rests within {band:.3g} mm of its design wherever friction holds it.")
    for n in hw["notes"]:
        L.append(f"- Note: {n}")
    L.append("- The rods' masses are designed with this hardware hanging on them (a pin rides with its fork, "
             "a bushing or bearing with its tongue): weigh each printed rod without it, against "
             "`rods[].hardware.printed_mass` (and the table above).")
    L.append("")
    return L


def hardware_summary(r) -> str | None:
    """The summary's line: how many joints get what."""
    hw = r.hardware
    if hw is None:
        return None
    used = Counter(o.name for o in hw.options if o is not None)
    band = "" if hw.band is None else f"; friction band {hw.band:.3g} mm (budget {hw.budget:.3g} mm)"
    return ", ".join(f"{c} x {name}" for name, c in used.items()) + band
