"""Joint hardware: the pins (and the bushings or ball bearings they turn in) a chain's joints
can be assembled with, as numbers (no CAD).

A pinned hinge holds a friction moment up to ``mu F r + T`` (``F`` the force the pin carries,
``r`` the radius it turns on, ``T`` a load-independent drag: a bearing's lubricant). That
moment lets the printed chain rest anywhere in a band around its design
(:func:`optimize.friction_band`), so the hardware, not the rods, sets how close a ruler finds
the chain to its drawing. A catalog offers a menu of options (its ``pins:`` block, or
:data:`DEFAULT_OPTIONS`); the planner picks one per joint (:mod:`rodcad.design.hardware`):
the cheapest whose rated load carries the joint's force with the menu's safety factor and
whose friction keeps the chain inside its band.

Kinds:

* ``pin``: a steel pin (dowel, piano wire) turning in printed holes ``pin_diameter +
  clearance`` wide in both knuckles.
* ``bushing``: a sleeve (PTFE tube, brass tube) pressed into the tongue knuckle (a printed
  hole of the sleeve's ``outer_diameter``); the pin turns in the sleeve and passes through the
  fork's holes (``pin_diameter + clearance``).
* ``bearing``: ``count`` miniature ball bearings pressed side by side into the tongue knuckle
  (a printed hole of their ``outer_diameter``) on a pin held by the fork's holes.

What a choice changes in a rod: the knuckles' pin holes (the tongue's hole is the sleeve's
or the bearings' outer diameter), so the rod's plastic (:meth:`PinOption.plastic_delta`),
and the metal that hangs on it (:meth:`PinOption.metal`: the pin rides with the fork, a
sleeve or bearings with the tongue). The rods' tables (mass ranges, achievable masses) are
those of the family's own holes; the design adds these differences as point masses at the
joints.

Rated load (N), the least of: the printed plastic under the pin or sleeve at ``pressure``
(MPa, the menu's: long-term bearing stress on printed PLA) over its projected area, the
sleeve's own ``sleeve_pressure`` over the pin's, the bearings' static rating, and the pin in
bending as a clevis pin (tongue in the middle: ``M = F / 2 (b / 2 + gap + a / 4)``, ``a`` the
tongue, ``b`` a prong) at its ``pin_yield``. Units: mm, g, N, N mm, MPa; densities g/cm^3.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

__all__ = ["DEFAULT_OPTIONS", "DEFAULT_PRESSURE", "DEFAULT_SAFETY", "PIN_KINDS", "PinMenu", "PinOption",
           "family_pin", "menu_from_block"]

#: The kinds of joint hardware.
PIN_KINDS = ("pin", "bushing", "bearing")

#: Safety factor on every rated load.
DEFAULT_SAFETY = 3.0

#: Long-term bearing stress a printed PLA hole takes under a pin or sleeve (MPa): a sixth of
#: printed PLA's compressive strength (about 60 MPa), for creep under a load that never ends.
DEFAULT_PRESSURE = 10.0

#: Steel pins, g/cm^3.
STEEL = 7.85

#: The menu a catalog without a ``pins:`` block gets, besides the family's own pin
#: (:func:`family_pin`). Friction ranges: dry steel on PLA 0.2-0.4; steel in PTFE 0.05-0.15
#: (PTFE's static friction at low pressure); deep-groove ball bearings 0.001-0.005 referred to
#: the bore, plus the drag of their oil (open bearings, light oil: up to 0.005 N mm each).
#: Costs are per joint, in any one currency (only their order matters).
DEFAULT_OPTIONS: tuple[dict, ...] = (
    {"name": "steel-pin-1.5", "kind": "pin", "description": "1.5 mm steel dowel pin in 1.65 mm printed holes",
     "pin_diameter": 1.5, "clearance": 0.15, "friction": [0.2, 0.4], "pin_yield": 600.0, "cost": 0.05},
    {"name": "wire-1", "kind": "pin", "description": "1 mm spring-steel (piano) wire in 1.1 mm holes "
     "(drill the printed holes to 1.1 mm)", "pin_diameter": 1.0, "clearance": 0.1, "friction": [0.2, 0.4],
     "pin_yield": 1500.0, "cost": 0.05},
    {"name": "ptfe-2x4", "kind": "bushing", "description": "PTFE tube 4 mm OD x 2 mm ID (Bowden tube) pressed "
     "into the tongue, a 2 mm steel pin turning in it", "pin_diameter": 2.0, "clearance": 0.1,
     "friction": [0.05, 0.15], "outer_diameter": 4.0, "sleeve_density": 2.2, "sleeve_pressure": 3.0,
     "pin_yield": 600.0, "cost": 0.12},
    {"name": "bearing-681", "kind": "bearing", "description": "two open 681 ball bearings (1 x 3 x 1 mm, light "
     "oil) pressed into the tongue, on a 1 mm steel pin held by the fork", "pin_diameter": 1.0,
     "clearance": 0.02, "friction": [0.001, 0.005], "torque": [0.0, 0.005], "outer_diameter": 3.0, "width": 1.0,
     "count": 2, "part_mass": 0.03, "part_load": 10.0, "pin_yield": 1500.0, "cost": 0.6},
    {"name": "bearing-681x", "kind": "bearing", "description": "an open 681X ball bearing (1.5 x 4 x 2 mm, light "
     "oil) pressed into the tongue, on a 1.5 mm steel pin held by the fork", "pin_diameter": 1.5,
     "clearance": 0.02, "friction": [0.001, 0.005], "torque": [0.0, 0.005], "outer_diameter": 4.0, "width": 2.0,
     "count": 1, "part_mass": 0.12, "part_load": 25.0, "pin_yield": 600.0, "cost": 0.5},
    {"name": "bearing-682", "kind": "bearing", "description": "two open 682 ball bearings (2 x 5 x 2.3 mm, light "
     "oil) pressed into the tongue, on a 2 mm steel pin held by the fork", "pin_diameter": 2.0,
     "clearance": 0.02, "friction": [0.001, 0.005], "torque": [0.0, 0.01], "outer_diameter": 5.0, "width": 2.3,
     "count": 2, "part_mass": 0.19, "part_load": 50.0, "pin_yield": 600.0, "cost": 0.8},
)


@dataclass(frozen=True)
class PinOption:
    """One kind of joint hardware.

    Attributes:
        name: unique in the menu, e.g. 'bearing-682'.
        kind: :data:`PIN_KINDS`.
        description: what to buy and how it goes in.
        pin_diameter: the steel pin (mm).
        clearance: diametral play where the pin turns (mm): the printed holes minus the pin
            (``pin``), the sleeve's bore minus the pin (``bushing``), the bearings' radial
            play (``bearing``). The fork's holes are ``pin_diameter + clearance``.
        friction: (lo, hi) friction coefficient where the pin turns; the band is reported for
            ``hi``.
        torque: (lo, hi) friction moment that does not grow with the load (N mm, a joint's).
        outer_diameter: the sleeve's or bearings' outer diameter, the tongue's printed hole
            (mm); None for a pin.
        width: a sleeve's or bearing's length along the pin (mm); None: the tongue's
            thickness (a sleeve cut to it).
        count: bearings per joint (1 for a sleeve).
        part_mass: each sleeve or bearing (g); None: a sleeve's from ``sleeve_density``.
        part_load: each bearing's static load rating (N); None: no own rating.
        sleeve_density: a sleeve's material (g/cm^3).
        sleeve_pressure: the bearing stress a sleeve takes under the pin (MPa).
        pin_density: the pin's material (g/cm^3).
        pin_yield: the pin's yield stress (MPa).
        cost: per joint, in the menu's currency (only the order matters).
        measured: the friction range was measured (``rodcad calibrate friction``), not
            taken from tables.
    """

    name: str
    kind: str
    description: str
    pin_diameter: float
    clearance: float
    friction: tuple[float, float]
    torque: tuple[float, float] = (0.0, 0.0)
    outer_diameter: float | None = None
    width: float | None = None
    count: int = 1
    part_mass: float | None = None
    part_load: float | None = None
    sleeve_density: float = 2.2
    sleeve_pressure: float = 3.0
    pin_density: float = STEEL
    pin_yield: float = 600.0
    cost: float = 0.05
    measured: bool = False

    @property
    def sleeved(self) -> bool:
        """A bushing or bearings in the tongue (the fork holds the pin)."""
        return self.kind != "pin"

    @property
    def radius(self) -> float:
        """Where friction acts: the pin's radius (mm)."""
        return self.pin_diameter / 2

    @property
    def fork_hole(self) -> float:
        """The fork's printed pin holes (mm)."""
        return self.pin_diameter + self.clearance

    @property
    def tongue_hole(self) -> float:
        """The tongue's printed hole (mm): the sleeve's or bearings' outer diameter, else the
        pin's hole."""
        return float(self.outer_diameter) if self.sleeved else self.fork_hole

    def hole(self, knuckle: str) -> float:
        """The printed hole of a 'tongue' or 'fork' knuckle (mm)."""
        return self.tongue_hole if knuckle == "tongue" else self.fork_hole

    def sleeve_length(self, tongue: float) -> float:
        """The sleeve's or bearings' total length in a tongue ``tongue`` mm thick (mm)."""
        return self.count * (tongue if self.width is None else self.width)

    def parts_mass(self, tongue: float) -> float:
        """The sleeve or bearings of one joint (g; 0 for a pin)."""
        if not self.sleeved:
            return 0.0
        if self.part_mass is not None:
            return self.count * self.part_mass
        d, b = float(self.outer_diameter), self.pin_diameter + self.clearance
        return math.pi / 4 * (d * d - b * b) * self.sleeve_length(tongue) * self.sleeve_density / 1000.0

    def pin_mass(self, thickness: float) -> float:
        """The pin, as long as the hinge is thick (g)."""
        return math.pi / 4 * self.pin_diameter ** 2 * thickness * self.pin_density / 1000.0

    def rated_load(self, thickness: float, tongue: float, gap: float, pressure: float) -> float:
        """The largest force the joint carries (N), before the safety factor.

        Args:
            thickness: the hinge's thickness along the pin (mm). tongue: the tongue's (mm).
            gap: between the tongue and each prong (mm). pressure: the printed plastic's
                allowed bearing stress (MPa).
        """
        prong = max((thickness - tongue - 2 * gap) / 2, 1e-9)
        d = self.pin_diameter
        lever = 0.5 * (prong / 2 + gap + tongue / 4)
        bending = self.pin_yield * math.pi * d ** 3 / 32 / lever
        loads = [bending, pressure * self.fork_hole * 2 * prong]
        if self.sleeved:
            length = min(self.sleeve_length(tongue), tongue)
            loads.append(pressure * self.tongue_hole * length)
            if self.kind == "bushing":
                loads.append(self.sleeve_pressure * d * length)
            if self.part_load is not None:
                loads.append(self.count * self.part_load)
        else:
            loads.append(pressure * self.fork_hole * tongue)
        return float(min(loads))

    def capacity(self, force: float, *, upper: bool = True) -> float:
        """The friction moment the joint holds under ``force`` N (N mm), at the top of the
        friction and drag ranges (``upper``) or at their bottom."""
        k = 1 if upper else 0
        return float(self.friction[k] * abs(force) * self.radius + self.torque[k])

    def fit_problem(self, knuckle_radius: float, tongue: float, min_wall: float) -> str | None:
        """Why this hardware does not fit a knuckle of ``knuckle_radius`` with a ``tongue``
        mm thick tongue and walls of ``min_wall`` (mm), or None."""
        wall = knuckle_radius - self.tongue_hole / 2
        if wall < min_wall - 1e-9:
            return (f"its {self.tongue_hole:g} mm hole leaves a {wall:.2f} mm wall in a {2 * knuckle_radius:g} mm "
                    f"knuckle (minimum {min_wall:g} mm)")
        if self.sleeved and self.sleeve_length(tongue) > tongue + 1e-9:
            return (f"its {self.sleeve_length(tongue):g} mm of {self.kind}s are longer than the {tongue:g} mm "
                    "tongue")
        return None

    def plastic_delta(self, knuckle: str, base_hole: float, layer: float, density: float) -> float:
        """Plastic this hardware's hole adds to a knuckle against the family's ``base_hole``
        (g; negative where its hole is wider), over the knuckle's ``layer`` mm of thickness."""
        d = self.hole(knuckle)
        return math.pi / 4 * (base_hole ** 2 - d ** 2) * layer * density / 1000.0


@dataclass(frozen=True)
class PinMenu:
    """What a catalog's joints may be assembled with.

    Attributes:
        options: the hardware, cheapest first (ties: least friction first).
        safety: safety factor on every rated load.
        pressure: the printed plastic's allowed bearing stress (MPa).
        base_name: the family's own pin (:attr:`base`).
    """

    options: tuple[PinOption, ...]
    safety: float = DEFAULT_SAFETY
    pressure: float = DEFAULT_PRESSURE

    def option(self, name: str) -> PinOption:
        """The option called ``name``."""
        for o in self.options:
            if o.name == name:
                return o
        raise KeyError(f"no joint hardware {name!r} (the menu: {', '.join(o.name for o in self.options)})")

    base_name: str | None = None

    @property
    def base(self) -> PinOption:
        """The family's own pin: the holes its rods' tables were computed with."""
        return self.options[0] if self.base_name is None else self.option(self.base_name)


def _order(options: Sequence[PinOption]) -> tuple[PinOption, ...]:
    return tuple(sorted(options, key=lambda o: (o.cost, o.friction[1] * o.radius + o.torque[1] / 1e3)))


def _pair(v) -> tuple[float, float]:
    """A number or [lo, hi] (or [x]) as (lo, hi)."""
    vals = [float(x) for x in v] if isinstance(v, (list, tuple)) else [float(v)]
    return vals[0], vals[-1]


def family_pin(pin_diameter: float, clearance: float, friction) -> PinOption:
    """The family's own joint (``joint.pin_diameter``, ``pin_clearance``, ``friction``: a
    number or [lo, hi]) as a menu option: a steel dowel pin (or an M3 screw) in printed holes."""
    f = _pair(friction)
    return PinOption(name=f"steel-pin-{pin_diameter:g}", kind="pin",
                     description=f"{pin_diameter:g} mm steel dowel pin in {pin_diameter + clearance:g} mm printed holes",
                     pin_diameter=float(pin_diameter), clearance=float(clearance), friction=f, pin_yield=600.0,
                     cost=0.05)


def option_from(d: dict) -> PinOption:
    """One entry of a ``pins.options`` list (schema-checked) as a :class:`PinOption`."""
    kw = dict(d)
    for key in ("friction", "torque"):
        if key in kw:
            kw[key] = _pair(kw[key])
    kw.setdefault("description", "")
    return PinOption(**kw)


def menu_from_block(block: dict | None, base: PinOption) -> PinMenu:
    """A catalog's ``pins:`` block (schema-checked) and its families' own pin ``base``: the
    block's options (or :data:`DEFAULT_OPTIONS`) with the family's pin, which is always on
    the menu (its holes are the rods' tables'); an option of the block named like the
    family's pin replaces it (e.g. with a measured friction)."""
    block = block or {}
    listed = [option_from(o) for o in block.get("options", DEFAULT_OPTIONS)]
    own = [o for o in listed if o.name == base.name]
    if own:
        base = replace(own[0], pin_diameter=base.pin_diameter, clearance=base.clearance)
    options = _order([base] + [o for o in listed if o.name != base.name])
    return PinMenu(options, float(block.get("safety", DEFAULT_SAFETY)), float(block.get("pressure", DEFAULT_PRESSURE)),
                   base.name)
