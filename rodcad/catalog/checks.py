"""Cross-field checks of a catalog family (called by :mod:`rodcad.catalog.loader`): what makes
a rod impossible to build, a range that cannot be printed, a stop that would not hold.

Each check reports every problem it finds through the family's context (``ctx.report(key,
message)``, pointing at the key in the file) and returns whether the family is sound.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from rodcad.catalog.model import (
    MAX_ARC_HALF_ANGLE_DEG,
    Balls,
    EndShape,
    Hinge,
    Material,
    Printer,
    RodGeometry,
    graduated,
    max_body_scale,
)
from rodcad.yamlio import format_number

__all__ = ["STOP_CHECK_DEG", "check_curvature", "check_length", "check_printer", "check_scales",
           "check_section", "check_stop", "check_stops"]


def check_section(ctx: Any, h: float, t: float, hinge: Hinge, m: Material,
                   kinds: tuple[Balls, ...], first: EndShape, second: EndShape, end_key: Any, at: str) -> bool:
    """Checks on the cross-section and hinge that make a rod impossible to build."""
    ok = True
    fmt = format_number
    w = m.min_wall
    if w >= min(h, t) / 2:
        ctx.report("material.min_wall", f"minimum wall {fmt(w)} mm is thicker than half the section "
                   f"({fmt(min(h, t) / 2)} mm{at}): no room inside the rod")
        return False  # every wall check below would fail for the same reason
    if hinge.zone_radius >= h / 2:
        ctx.report("joint.knuckle_radius", f"knuckle radius {fmt(hinge.knuckle_radius)} mm + radial gap "
                   f"{fmt(hinge.radial_gap)} mm is wider than the rod: it must stay below half the section "
                   f"height ({fmt(h / 2)} mm{at})")
        ok = False
    elif h / 2 - hinge.zone_radius < w:
        ctx.report("joint.knuckle_radius", f"knuckle radius {fmt(hinge.knuckle_radius)} mm + radial gap "
                   f"{fmt(hinge.radial_gap)} mm leaves {fmt(round(h / 2 - hinge.zone_radius, 6))} mm of end face "
                   f"between the hinge zone and the rod's edge ({fmt(h / 2)} mm from the axis{at}), less than "
                   f"the minimum wall {fmt(w)} mm")
        ok = False
    knuckle_wall = hinge.knuckle_radius - hinge.hole_diameter / 2
    if knuckle_wall < w:
        ctx.report("joint.knuckle_radius", f"knuckle radius {fmt(hinge.knuckle_radius)} mm leaves a wall of "
                   f"{fmt(knuckle_wall)} mm around the {fmt(hinge.hole_diameter)} mm pin hole, less than "
                   f"the minimum wall {fmt(w)} mm{at}")
        ok = False
    prong = (t - hinge.tongue_thickness - 2 * hinge.layer_gap) / 2
    if hinge.tongue_thickness < w:
        ctx.report("joint.tongue_thickness", f"tongue thickness {fmt(hinge.tongue_thickness)} mm is less than "
                   f"the minimum wall {fmt(w)} mm{at}")
        ok = False
    elif prong < w:
        ctx.report("joint.tongue_thickness", f"tongue {fmt(hinge.tongue_thickness)} mm + 2 layer gaps of "
                   f"{fmt(hinge.layer_gap)} mm leave fork prongs {fmt(prong)} mm thick in a {fmt(t)} mm "
                   f"thick rod, less than the minimum wall {fmt(w)} mm{at}")
        ok = False
    for which, e in (("first", first), ("second", second)):
        if e.setback >= hinge.knuckle_radius:
            ctx.report(end_key(which, "setback"),
                       f"setback {fmt(e.setback)} mm detaches the end face from the "
                       f"{fmt(hinge.knuckle_radius)} mm knuckle: must be less than the knuckle radius{at}")
            ok = False
    for key, kind in zip(ctx.ball_keys, kinds):
        need = kind.socket_diameter + 2 * w
        if need > min(h, t):
            ctx.report(f"{key}.diameter", f"a {fmt(kind.diameter)} mm ball in a {fmt(kind.socket_diameter)} mm "
                       f"socket with {fmt(w)} mm walls needs a section of at least {fmt(need)} mm; the rod is "
                       f"{fmt(h)} x {fmt(t)} mm{at}")
            ok = False
    return ok


def check_length(ctx: Any, l_rel: str, length: float, h: float, hinge: Hinge,
                  m: Material, first: EndShape, second: EndShape, end_key: Any, at: str) -> bool:
    fmt = format_number
    need = 2 * hinge.zone_radius + m.min_wall
    if length < need:
        ctx.report(l_rel, f"length {fmt(length)} mm is too short: the two hinge zones and a minimum wall "
                   f"need {fmt(round(need, 6))} mm{at}")
        return False
    ok = True
    for half in ("top", "bottom"):
        b1 = getattr(first, f"{half}_chamfer")
        b2 = getattr(second, f"{half}_chamfer")
        cut = first.setback + second.setback + h / 2 * (math.tan(math.radians(b1)) + math.tan(math.radians(b2)))
        left = length - cut
        if left < m.min_wall:
            what = (f"the two {half} end faces would cross" if left <= 0 else
                    f"they leave {fmt(round(left, 3))} mm of {half} edge between the end faces, less than "
                    f"the minimum wall {fmt(m.min_wall)} mm")
            ctx.report(end_key("second", f"{half}_chamfer"),
                       f"{half} chamfers of {fmt(b1)} and {fmt(b2)} deg cut through a {fmt(length)} mm rod: "
                       f"{what}{at}")
            ok = False
    return ok


def check_curvature(ctx: Any, c_rel: str, curv: float, length: float, h: float) -> bool:
    if curv == 0:
        return True
    fmt = format_number
    limit = math.sin(math.radians(MAX_ARC_HALF_ANGLE_DEG)) * 2 / length
    if abs(curv) > limit:
        ctx.report(c_rel, f"curvature {fmt(curv)} /mm bends a {fmt(length)} mm rod past a "
                   f"{fmt(2 * MAX_ARC_HALF_ANGLE_DEG)} deg arc (at most {fmt(round(limit, 6))} /mm)")
        return False
    if abs(curv) * h > 1:
        ctx.report(c_rel, f"curvature {fmt(curv)} /mm (radius {fmt(round(1 / abs(curv), 3))} mm) is too tight "
                   f"for a {fmt(h)} mm high section: the radius must be at least the section height")
        return False
    return True


def check_printer(ctx: Any, l_rel: str, g: RodGeometry, printer: Printer) -> bool:
    sag = 0.0
    if g.curvature:
        sag = (1 - math.cos(math.radians(g.half_angle_deg))) / abs(g.curvature)  # arc's depth below the chord
    extent = sorted((g.length + 2 * g.hinge.knuckle_radius, g.max_height + sag, g.max_thickness))
    bed = sorted(printer.build_volume)
    if any(e > b for e, b in zip(extent, bed)):
        fmt = format_number
        ctx.report(l_rel, f"a {fmt(g.length)} mm rod ({' x '.join(fmt(round(e, 2)) for e in reversed(extent))} mm) "
                   f"does not fit the printer's build volume "
                   f"({' x '.join(fmt(b) for b in printer.build_volume)} mm)")
        return False
    return True


#: A stop printed to order must stop within this of the bend it is made for (deg), checked
#: at the ends of the family's ranges with the end geometry (rodcad.catalog.jointlimits).
STOP_CHECK_DEG = 0.05


def check_scales(ctx: Any, scales: tuple[float, float], length: tuple[float, float],
                  stops: tuple[float, float] | None, base: RodGeometry, material: Material,
                  printer: Printer | None) -> bool:
    """A scale range (graduated rods): the thinnest body still holds the hinge layers with
    a minimum wall, the longest straight rod takes the thickest body, it fits the printer,
    and stops at the ends of the stop range still stop at their bend between the thinnest
    and the thickest rods (end geometry, rodcad.catalog.jointlimits)."""
    from rodcad.catalog.keptlimits import kept_joint_limits as joint_limits

    fmt = format_number
    w, hg = material.min_wall, base.hinge
    need = hg.tongue_thickness + 2 * hg.layer_gap + 2 * w
    thin = min(base.height, base.thickness) * scales[0]
    if thin < need:
        ctx.report("scale.min", f"scale {fmt(scales[0])} makes a {fmt(round(base.height * scales[0], 3))} x "
                   f"{fmt(round(base.thickness * scales[0], 3))} mm body, thinner than the hinge needs: the tongue "
                   f"({fmt(hg.tongue_thickness)} mm), two layer gaps and two minimum walls make "
                   f"{fmt(round(need, 3))} mm (at least scale {fmt(round(need / min(base.height, base.thickness), 4))})")
        return False
    longest = graduated(base, scales[1], w)
    top = max_body_scale(base, w)
    if scales[1] > top + 1e-9:
        ctx.report("scale.max", f"scale {fmt(scales[1])} is too thick for the hinge ends of a {fmt(base.length)} mm "
                   f"rod: its top end faces reach so high that they leave less than the minimum wall "
                   f"({fmt(w)} mm) of top edge between them (at most scale {fmt(round(top, 4))})")
        return False
    if printer is not None and not check_printer(ctx, "scale.max", longest, printer):
        return False
    if stops is None:
        return True
    ok = True
    for s in stops:
        c = s / 2
        for a, b in ((scales[0], scales[1]), (scales[1], scales[0]), (scales[1], scales[1])):
            left = graduated(dataclasses.replace(base, second=EndShape(0.0, c, base.second.bottom_chamfer)), a, w)
            right = graduated(dataclasses.replace(base, first=EndShape(0.0, c, base.first.bottom_chamfer)), b, w)
            try:
                got = joint_limits(left, right)[1 if s > 0 else 0] if s != 0 else joint_limits(left, right)[1]
            except ValueError:
                got = None
            if got is None or abs(got - s) > STOP_CHECK_DEG:
                where = "no stop at all" if got is None else f"a stop at {fmt(round(got, 3))} deg"
                ctx.report("scale.max", f"a stop at {fmt(s)} deg between rods of scale {fmt(a)} and {fmt(b)} gives "
                           f"{where}: the thicker body meets its partner before the end faces do "
                           "(narrow the scale range)")
                ok = False
                break
        if not ok:
            break
    return ok


def check_stops(ctx: Any, stops: tuple[float, float], length: tuple[float, float],
                 curv: tuple[float, float], h: float, t: float, hinge: Hinge, material: Material,
                 first: EndShape, second: EndShape) -> bool:
    """Every stop of the range, between straight rods at the ends of the length range, is
    made by flush ends that leave the rod whole and meet exactly at the stop angle (each end's
    top chamfer half the stop; between curved rods the planner keeps the chamfers within
    these)."""
    return all([check_stop(ctx, rel, s, length, curv, h, t, hinge, material, first, second)
                for rel, s in (("stops.min", stops[0]), ("stops.max", stops[1]))])


def check_stop(ctx: Any, rel: str, s: float, length: tuple[float, float], curv: tuple[float, float],
                h: float, t: float, hinge: Hinge, material: Material, first: EndShape, second: EndShape) -> bool:
    from rodcad.catalog.keptlimits import kept_joint_limits as joint_limits

    fmt = format_number
    for lv in length:
        for k in (0.0,):
            c = s / 2  # each end's top chamfer where two straight rods meet at s
            a, b = EndShape(0.0, c, first.bottom_chamfer), EndShape(0.0, c, second.bottom_chamfer)
            if not check_length(ctx, rel, lv, h, hinge, material, a, b, lambda w, key: rel, ""):
                return False
            geo = RodGeometry(lv, h, t, k, hinge, a, b)
            try:
                hi = joint_limits(geo, geo)[1]
            except ValueError:
                hi = None
            if hi is None or abs(hi - s) > STOP_CHECK_DEG:
                got = "no stop at all" if hi is None else f"a stop at {fmt(round(hi, 3))} deg"
                ctx.report(rel, f"a stop at {fmt(s)} deg between two {fmt(lv)} mm rods of curvature {fmt(k)} "
                           f"needs top chamfers of {fmt(round(c, 3))} deg, which cut into the hinge zone or "
                           f"knuckle: their outlines give {got} (narrow the stop range)")
                return False
    return True
