"""The friction coupon's words: calibrate.md (parts, assembly, how to read, the formula with
this coupon's numbers, a table from angle to mu), the readings' summary and the YAML that
puts a measured friction into a catalog's ``pins: options:`` list.

Numbers from :mod:`rodcad.catalog.coupon`. Units: mm, g, degrees, N mm.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Sequence
from dataclasses import fields, replace

from rodcad.catalog.coupon import (
    READ_ERROR,
    TICK_STEP,
    CouponGeometry,
    FrictionFit,
    Reading,
    angle_for,
    coulomb_coefficient,
    default_rider,
    mu_from_angle,
)
from rodcad.catalog.pins import PinOption

__all__ = ["ANGLES", "calibrate_md", "measured_option", "option_yaml", "readings_text"]

#: The angle table's rows (deg).
ANGLES = (*range(2, 20, 2), *range(20, 90, 5))

_KIND_WORDS = {"pin": "a steel pin turning in printed holes", "bushing": "a sleeve pressed into the wheel",
               "bearing": "ball bearings pressed into the wheel"}


def _g(x: float, digits: int = 3) -> str:
    """A number for people: 3 significant digits, no trailing zeros."""
    if not math.isfinite(x):
        return "-"
    return f"{x:.{digits}g}" if abs(x) >= 1e-3 or x == 0 else f"{x:.2e}"


def measured_option(option: PinOption, fit: FrictionFit) -> PinOption:
    """The option with the readings' friction range (and fitted drag) and ``measured``."""
    lo, hi = (max(0.0, round(v, 4)) for v in fit.friction)
    torque = (round(fit.torque, 4),) * 2 if fit.separated else (0.0, 0.0)
    return replace(option, friction=(lo, max(lo, hi)), torque=torque, measured=True)


def _yaml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, tuple):
        return "[" + ", ".join(_yaml_value(x) for x in v) + "]"
    if isinstance(v, str):
        return v if re.fullmatch(r"[A-Za-z][A-Za-z0-9._-]*", v) else json.dumps(v)
    return f"{float(v):.6g}"


def option_yaml(options: Sequence[PinOption], indent: int = 4) -> str:
    """A ``pins.options`` list of ``options`` as YAML (each entry with its name, kind, the
    required numbers and whatever differs from the defaults)."""
    defaults = {f.name: f.default for f in fields(PinOption) if f.default is not f.default_factory}
    always = ("name", "kind", "description", "pin_diameter", "clearance", "friction")
    lines = []
    for o in options:
        first = True
        for f in fields(PinOption):
            v = getattr(o, f.name)
            if f.name not in always and (v is None or v == defaults.get(f.name)):
                continue
            lines.append(" " * indent + ("- " if first else "  ") + f"{f.name}: {_yaml_value(v)}")
            first = False
    return "\n".join(lines) + "\n"


def readings_text(geom: CouponGeometry, readings: Sequence[Reading], fit: FrictionFit,
                  menu: Sequence[PinOption], block: bool) -> str:
    """What ``rodcad calibrate friction --angle ...`` prints: mu per reading, the range, the
    fit and the YAML to paste (``block``: the catalog has a ``pins: options:`` list already,
    so the one entry replaces its namesake; else the whole menu, this option measured)."""
    o = geom.option
    out = [f"{o.name} ({o.kind}, pin radius {_g(o.radius)} mm) on the {geom.catalog} coupon:"]
    for k, (r, mu, err) in enumerate(zip(readings, fit.per_reading, fit.errors), 1):
        out.append(f"  reading {k}: {r.angle:g} deg, rider at {r.rider_radius:g} mm, load {r.load_mass:.2f} g -> "
                   f"mu = {mu:.4f} (+-{err:.4f} for +-{READ_ERROR:g} deg)")
    lo, hi = fit.friction
    out.append(f"mu over the readings: [{lo:.4f}, {hi:.4f}], fit {fit.mu:.4f}; {fit.message}")
    if fit.separated:
        out.append(f"drag T = {fit.torque:.4g} N mm (load-independent), rms moment residual {fit.rms:.2g} N mm")
    if o.kind != "bearing":
        hole = o.fork_hole / 2  # where the pin turns: printed holes, or a sleeve's bore
        out.append(f"(the Coulomb coefficient of the pin on its {2 * hole:g} mm hole: "
                   f"{_g(coulomb_coefficient(fit.mu, o.radius, hole))})")
    if not 0 <= lo <= hi <= 2:
        out.append("rodcad: mu is outside [0, 2] (the catalog's range): check the readings, --rider and --ballast; "
                   "no YAML written")
        return "\n".join(out) + "\n"
    new = measured_option(o, fit)
    if block:
        out.append(f"\nReplace the entry named {o.name!r} in the catalog's `pins: options:` list (or add it) with:\n")
        out.append(option_yaml([new]))
    else:
        out.append("\nThe catalog has no `pins:` block: add this one (the default menu, this option measured):\n")
        out.append("pins:\n  options:\n" + option_yaml([new if m.name == o.name else m for m in menu]))
    return "\n".join(out)


def _table(geom: CouponGeometry, load: float) -> list[str]:
    radii = geom.rider_radii
    lines = ["| beta (deg) | " + " | ".join(f"mu, R = {r:g} mm" for r in radii) + " |",
             "|---:|" + "---:|" * len(radii)]
    for a in ANGLES:
        mus = [mu_from_angle(a, rider_mass=geom.ball_mass, rider_radius=r, load_mass=load,
                             pin_radius=geom.option.radius) for r in radii]
        lines.append(f"| {a} | " + " | ".join(f"{m:.4f}" for m in mus) + " |")
    return lines


def _which_radius(geom: CouponGeometry, menu: Sequence[PinOption], wheel_mass: float) -> list[str]:
    lines = ["| option | kind | friction (tables) | rider at | reads about |", "|---|---|---|---:|---:|"]
    for o in menu:
        g = replace(geom, option=o)
        r, a = default_rider(g, wheel_mass - geom.hardware_mass + g.hardware_mass)
        mark = " (this coupon)" if o.name == geom.option.name else ""
        lines.append(f"| {o.name}{mark} | {o.kind} | {_g(o.friction[0])}-{_g(o.friction[1])} | {r:g} mm | "
                     f"{a:.0f} deg |")
    return lines


def calibrate_md(geom: CouponGeometry, *, wheel_volume: float, wheel_mass: float, menu: Sequence[PinOption],
                 command: str, profile: dict) -> str:
    """calibrate.md for a built coupon (its wheel's B-rep ``wheel_volume`` mm^3 and mass g)."""
    o = geom.option
    m, r = geom.ball_mass, o.radius
    rider, beta = default_rider(geom, wheel_mass)
    load = wheel_mass + m
    hw = (f" and its {o.count} {o.kind}{'s' if o.count > 1 else ''} ({_g(geom.hardware_mass)} g)"
          if o.sleeved else "")
    sleeve = None
    if o.kind == "bushing":
        sleeve = f"- the sleeve: {o.description}; cut it to the wheel's hub, {geom.hub:g} mm long"
    elif o.kind == "bearing":
        sleeve = f"- {o.count} bearing{'s' if o.count > 1 else ''}: {o.description}"
    k = m * rider / (load * r)
    lo, hi = o.friction
    lines = [
        f"# Friction coupon: {o.name} ({geom.catalog})",
        "",
        f"Measures the friction coefficient mu of `{o.name}` ({_KIND_WORDS[o.kind]}: {o.description}), the "
        "number rodcad's joint model takes (the friction moment a joint holds is mu F r + T; the catalog's "
        f"tables say {_g(lo)}-{_g(hi)}). A balanced wheel hangs on the pin; a steel ball (the rider) on it "
        "turns it until the friction no longer holds it; the largest angle that holds gives mu.",
        "",
        "## Parts",
        "",
        "- `stand.stl`: print it upright, base on the bed, as `coupon.3mf` places it (its pin holes then lie "
        "flat like the rods' hinge axes, so they print like the rods'); 25 % infill is set for it.",
        f"- `wheel.stl`: print it flat on its back, cups up, with the catalog's profile (layer "
        f"{profile.get('layer_height', 0.2)} mm, 100 % infill): its mass enters the formula.",
        f"- a {o.pin_diameter:g} mm steel pin {geom.pin_length:.1f} mm long (the rods' pins fit)",
        sleeve,
        f"- {geom.ball_diameter:g} mm steel balls ({_g(m)} g each): one rider and up to "
        f"{2 * geom.ballast_pairs} for ballast",
        "- optional: a scale reading 0.01 g (weigh the wheel: the model's mass is as good as the print's "
        "mass tolerance)",
        "",
        "## Assemble",
        "",
        "1. Clear the holes of strings; do not ream them (the rods' holes will not be reamed either"
        + ("; the option asks for the holes drilled: drill the stand's and the wheel's too" if "drill" in
           o.description else "") + ").",
    ]
    if o.sleeved:
        lines.append(f"2. Press the {o.kind}{'s' if o.count > 1 else ''} into the wheel's "
                     f"{o.tongue_hole:g} mm hole, flush with its faces.")
    else:
        lines.append("2. (Optional) A drop of glue fixing the pin in the wheel makes it turn in the stand's "
                     "holes only, printed on their side like every rod's hole; the wheel's own hole prints flat, "
                     "rounder and smoother than a rod's.")
    lines += [
        "3. Slide the wheel, cups to the front, between the dial plate and the post until its hole lines up, "
        "and push the pin through the post, the wheel and the dial plate.",
        "4. Spin it: it turns on the pin alone, its faces clear of the dial and the post "
        f"({geom.clearance:g} mm; {geom.layer_gap:g} mm at the knuckles, like a rod's hinge).",
        f"5. Put the rider in the cup at {rider:g} mm on the rider line (the cups in line with the "
        "pointers). The cups from the hub out are at " + ", ".join(f"{x:g}" for x in geom.rider_radii)
        + " mm. Ballast goes in pairs: both cups of a pair (same radius, opposite each other), never the "
        "rider's own partner.",
        "",
        "Which rider cup for which hardware (the catalog's mid-range friction, no ballast):",
        "",
        *_which_radius(geom, menu, wheel_mass),
        "",
        "A reading below 10 degrees (ball bearings, even at the innermost cup) is read to half a tick (1 "
        "degree); readings with ballast then tell the bearings' drag T from mu.",
        "",
        "## Read",
        "",
        "1. Stand the coupon on a level table, out of draughts.",
        "2. Turn the wheel by its rim so the rider rises to one side; let go gently. Turn it a little further "
        f"each time until it slips back; the largest angle that held is the reading (the top pointer on the "
        f"scale; ticks every {TICK_STEP} degrees, numbers every 10).",
        "3. The same to the other side; the reading is the mean of both (that cancels a wheel printed a little "
        "off balance across the rider line).",
        "4. Repeat 5 times. For a printed imbalance along the rider line, move the rider to its partner cup "
        "(same radius, other side) and read again: the mean of both cancels it.",
        "5. For the drag T (bearings), read again with ballast (e.g. every pair filled): the readings at two "
        "loads separate mu and T.",
        "",
        "## The formula",
        "",
        "A rider of mass m at radius R, turned beta from straight below, holds while "
        "m g R sin(beta) <= mu (M + m + B) g r + T, so (with T = 0)",
        "",
        "    mu = m R sin(beta) / ((M + m + B) r)",
        "",
        f"- m = {_g(m, 4)} g (a {geom.ball_diameter:g} mm steel ball)",
        f"- M = {_g(wheel_mass, 4)} g: the wheel, {wheel_volume:.1f} mm^3 x {geom.density:g} g/cm^3{hw} "
        "(weigh yours and give it as --wheel-mass)",
        "- B = ballast (g): the balls in pairs",
        f"- r = {_g(r, 4)} mm: the pin's radius, where it turns",
        f"- R = {rider:g} mm for this hardware (the cups: " + ", ".join(f"{x:g}" for x in geom.rider_radii) + " mm)",
        "",
        f"Here, rider at {rider:g} mm, no ballast: mu = {k:.4f} sin(beta); the tables' mid-range "
        f"{_g((lo + hi) / 2)} reads about {beta:.0f} degrees "
        f"({_g(angle_for(lo, rider_mass=m, rider_radius=rider, load_mass=load, pin_radius=r, torque=o.torque[0]), 2)}"
        f"-{_g(angle_for(hi, rider_mass=m, rider_radius=rider, load_mass=load, pin_radius=r, torque=o.torque[1]), 2)}"
        " over the tables' range).",
        "",
        "This mu is the holding moment over W r, exactly what the joint model takes; for a pin on a hole it "
        "is (hole radius / pin radius) sin(atan(mu_c)) of the Coulomb coefficient mu_c.",
        "",
        "## beta -> mu for this coupon",
        "",
        f"No ballast, M = {_g(wheel_mass, 4)} g (with ballast or a weighed wheel, use the command below):",
        "",
        *_table(geom, load),
        "",
        "## Into the catalog",
        "",
        "    " + command + " --angle A1 --angle A2 ... [--rider R] [--ballast N] [--wheel-mass G]",
        "",
        "prints mu per reading, their range and the YAML to paste into the catalog's `pins: options:` list: "
        f"the entry `{o.name}` with `friction: [lo, hi]` and `measured: true` (--ballast N and --rider R once "
        "for all readings, or once per --angle).",
        "",
    ]
    return "\n".join(x for x in lines if x is not None) + "\n"
