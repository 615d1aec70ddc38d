"""The planner's choice of joint hardware: for every pin of a chain, the cheapest option of
the catalog's menu (:mod:`rodcad.catalog.pins`) that carries the pin's load and keeps the
chain's friction band within its budget.

Why per joint: a pin carrying ``F`` holds a friction moment up to ``mu F r + T`` and the
chain can rest anywhere its pins hold it (:func:`optimize.friction_band`). The band is the
image of the box of those moments under the chain's linearised statics, so each pin adds to
each joint's band in proportion to its own moment: a few pins (the loaded ones where the
chain is sensitive) make most of it, and only they need the expensive hardware.

The choice (:func:`choose_hardware`):

1. every pin gets the cheapest option that fits both knuckles it joins (its hole leaves the
   minimum wall, its sleeve or bearings fit the tongue) and whose rated load carries the
   pin's force at the design times the menu's safety factor;
2. while the friction band (at the top of every option's friction range) exceeds the budget
   (:data:`FRICTION_SHARE` of the design's tolerance times the target's size), the pin that
   adds most to the widest joint's band is upgraded to the cheapest fitting option that holds
   less friction (its share of that joint's band in the equilibrium's own cell), and the exact
   band is computed again;
3. it stops when the band is within the budget or no pin can be upgraded (the report says
   so: then design option ``robust`` may hold joints both ways).

Units: mm, g, N, N mm (the catalog's), and the solver's forces (g x the design's ``g`` with
lengths in mm: :func:`newtons`). Pins are numbered 0..N (pin 0 at anchor A, pin N at B, pin j
between rods j-1 and j); a fused joint has no pin (None).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from optimize import friction_band, joint_forces
from rodcad.catalog.model import RodType
from rodcad.catalog.pins import PinMenu, PinOption

__all__ = ["FRICTION_SHARE", "JointHardware", "best_capacity", "choose_hardware", "newtons", "pin_knuckles",
           "solver_moment"]

#: The share of the design's tolerance the friction band may take (of the default 1 % where
#: the design's is looser): a band of 0.1 % of the target's size at most.
FRICTION_SHARE = 0.1

#: A pin is cut this much longer than the hinge is thick (mm; the bill of materials' length).
PIN_EXTRA = 1.0

#: The design's ``g`` is in m/s^2 with masses in g: a solver force is g m/s^2 = mN x g / 9.81.
G_STD = 9.81


def newtons(force, g: float) -> np.ndarray:
    """Solver forces (mass in g x ``g``) in newtons."""
    return np.asarray(force, float) * (G_STD / g) / 1000.0


def solver_moment(moment_nmm, g: float) -> np.ndarray:
    """Moments in N mm as the solver's (its force x mm)."""
    return np.asarray(moment_nmm, float) * 1000.0 * (g / G_STD)


def pin_knuckles(rods: Sequence[RodType], k: int) -> list[tuple[int, int, str]]:
    """The knuckles pin ``k`` passes through: (rod, end 0/1, 'tongue' or 'fork')."""
    n = len(rods)
    out = []
    if k >= 1:
        out.append((k - 1, 1, rods[k - 1].geometry.hinge.knuckle(1)))
    if k < n:
        out.append((k, 0, rods[k].geometry.hinge.knuckle(0)))
    return out


def _fits(o: PinOption, rods: Sequence[RodType], k: int) -> str | None:
    for i, _, kind in pin_knuckles(rods, k):
        h = rods[i].geometry.hinge
        why = o.fit_problem(h.knuckle_radius, h.tongue_thickness, rods[i].material.min_wall)
        if why is not None and (kind == "tongue" or not o.sleeved):
            return why
        if kind == "fork" and h.knuckle_radius - o.fork_hole / 2 < rods[i].material.min_wall - 1e-9:
            return f"its {o.fork_hole:g} mm fork hole leaves less than the minimum wall"
    return None


def _rated(o: PinOption, rods: Sequence[RodType], k: int, menu: PinMenu) -> float:
    loads = []
    for i, _, _ in pin_knuckles(rods, k):
        g = rods[i].geometry
        loads.append(o.rated_load(g.thickness, g.hinge.tongue_thickness, g.hinge.layer_gap, menu.pressure))
    return min(loads)


def _base_for(menu: PinMenu, rod: RodType) -> PinOption:
    """The menu's own-pin option with this rod's pin (a catalog of several families)."""
    from dataclasses import replace

    h = rod.geometry.hinge
    b = menu.base
    return b if (b.pin_diameter, b.clearance) == (h.pin_diameter, h.pin_clearance) else \
        replace(b, name=f"pin-{h.pin_diameter:g}", pin_diameter=h.pin_diameter, clearance=h.pin_clearance)


def _candidates(menu: PinMenu, rods: Sequence[RodType], k: int, load: float) -> list[tuple[PinOption, float]]:
    """(option, rated load N) that fit pin ``k`` and carry ``load`` N with the safety factor,
    cheapest first."""
    base = _base_for(menu, rods[min(k, len(rods) - 1)])
    opts = [base if o.name == menu.base.name else o for o in menu.options]
    out = []
    for o in opts:
        if _fits(o, rods, k) is not None:
            continue
        r = _rated(o, rods, k, menu)
        if r >= menu.safety * load:
            out.append((o, r))
    return out


def best_capacity(menu: PinMenu, rods: Sequence[RodType], forces_n) -> np.ndarray:
    """(N+1,) the least friction moment (N mm, top of the ranges) any fitting option that
    carries each pin's load holds: what no hardware of the menu can go below (inf where no
    option carries the load)."""
    f = np.asarray(forces_n, float)
    out = np.full(f.size, np.inf)
    for k in range(f.size):
        c = _candidates(menu, rods, k, f[k])
        if c:
            out[k] = min(o.capacity(f[k]) for o, _ in c)
    return out


@dataclass
class JointHardware:
    """Every pin's hardware and what it does.

    Attributes:
        options: (N+1,) the option per pin, None at a fused joint (no pin).
        loads: (N+1,) each pin's force at the design (N).
        rated: (N+1,) the chosen option's rated load (N, before the safety factor; nan: no pin).
        safety: the safety factor the loads were checked with.
        capacity: (N+1,) the friction moment each pin holds (N mm, top of its ranges).
        band: the friction band with these pins (mm), None where it was not computed.
        budget: the band the choice aimed for (mm).
        upgraded: pins moved to costlier hardware to narrow the band.
        overloaded: pins no option carries (they keep the strongest that fits).
        notes: what the choice did, in words.
    """

    options: list[PinOption | None]
    loads: np.ndarray
    rated: np.ndarray
    safety: float
    capacity: np.ndarray
    band: float | None
    budget: float
    upgraded: list[int] = field(default_factory=list)
    overloaded: list[int] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    @property
    def n(self) -> int:
        return len(self.options) - 1

    def clearance(self) -> np.ndarray:
        """(N+1,) each pin's diametral play (mm; 0 at a fused joint)."""
        return np.array([0.0 if o is None else o.clearance for o in self.options])

    def radius(self) -> np.ndarray:
        """(N+1,) where each pin's friction acts (mm)."""
        return np.array([0.0 if o is None else o.radius for o in self.options])

    def holes(self, rods: Sequence[RodType]) -> list[tuple[float, float]]:
        """Per rod, the printed hole of its first and second knuckle (mm)."""
        out = []
        for i, r in enumerate(rods):
            h = r.geometry.hinge
            pair = []
            for end, k in ((0, i), (1, i + 1)):
                o = self.options[k]
                pair.append(h.hole_diameter if o is None else o.hole(h.knuckle(end)))
            out.append((pair[0], pair[1]))
        return out

    def attached(self, rods: Sequence[RodType], *, plastic: bool = True) -> np.ndarray:
        """What each rod carries of the hardware, at its hinge axes: (N, 2) g at its first and
        second end. A pin rides with the fork it passes through, a sleeve or bearings with
        their tongue; with ``plastic``, each knuckle's plastic against the family's hole
        (negative where the hole is wider) with that knuckle (the solids built have it; the
        rods' tables do not). The anchor pins hang on the fixture."""
        n = len(rods)
        out = np.zeros((n, 2))
        for i, r in enumerate(rods):
            g = r.geometry
            h = g.hinge
            prongs = max(g.thickness - h.tongue_thickness - 2 * h.layer_gap, 0.0)
            for end, k in ((0, i), (1, i + 1)):
                o = self.options[k]
                if o is None:
                    continue
                kind = h.knuckle(end)
                layer = h.tongue_thickness if kind == "tongue" else prongs
                m = o.plastic_delta(kind, h.hole_diameter, layer, r.material.density) if plastic else 0.0
                if kind == "tongue":
                    m += o.parts_mass(h.tongue_thickness)
                if kind == "fork" and 0 < k < n:  # an interior pin: through one fork and one tongue
                    m += o.pin_mass(g.thickness + PIN_EXTRA)
                out[i, end] = m
        return out


def _mirrored(lengths, points) -> bool:
    """The chain's rods and joints read the same from B to A, mirrored about the perpendicular
    bisector of AB (to 1e-9 of its size): a symmetric design, whose masses and loads the
    hardware's own asymmetry must not tip."""
    l = np.asarray(lengths, float)
    p = np.asarray(points, float)
    a, b = p[0], p[-1]
    u = (b - a) / np.hypot(*(b - a))
    rel = p - a
    along, across = rel @ u, rel @ np.array([-u[1], u[0]])
    span = float(np.hypot(*(b - a)))
    size = max(span, float(np.ptp(across)))
    return bool(np.allclose(l, l[::-1], rtol=1e-9, atol=0)
                and np.allclose(along, span - along[::-1], atol=1e-9 * size)
                and np.allclose(across, across[::-1], atol=1e-9 * size))


def choose_hardware(rods: Sequence[RodType], menu: PinMenu, *, lengths, masses, com, anchors, limits,
                    end_limits, g: float, equilibrium, fused, budget: float, max_rounds: int | None = None
                    ) -> JointHardware:
    """Every pin's hardware (module docstring).

    Args:
        rods: the chain's rods. menu: the catalog's joint hardware.
        lengths, masses, com, anchors, limits, end_limits, g: the designed chain (mm, g, rad;
            masses as they hang).
        equilibrium: its stable equilibrium (:class:`optimize.EquilibriumResult`).
        fused: (N-1,) bool, joints printed as one piece (no pin).
        budget: the friction band to stay within (mm).
        max_rounds: upgrades at most (default: every pin through every option once).
    """
    n = len(rods)
    m = np.asarray(masses, float)
    forces = newtons(np.hypot(*joint_forces(equilibrium.reaction, m, g=g).T), g)
    none = np.zeros(n + 1, dtype=bool)
    none[1:-1] = np.asarray(fused, bool) if n > 1 else []
    cands: list[list[tuple[PinOption, float]]] = []
    overloaded = []
    for k in range(n + 1):
        if none[k]:
            cands.append([])
            continue
        c = _candidates(menu, rods, k, forces[k])
        if not c:  # nothing carries it: the strongest that fits
            fit = [(o, _rated(o, rods, k, menu)) for o in menu.options if _fits(o, rods, k) is None]
            c = [max(fit, key=lambda t: t[1])] if fit else [(_base_for(menu, rods[min(k, n - 1)]), float("nan"))]
            overloaded.append(k)
        cands.append(c)
    pick = [0] * (n + 1)

    def chosen(k):
        return None if none[k] else cands[k][pick[k]][0]

    def caps() -> np.ndarray:
        return np.array([0.0 if none[k] else chosen(k).capacity(forces[k]) for k in range(n + 1)])

    kw = dict(com=com, limits=limits if n > 1 else None, end_limits=end_limits, g=g, result=equilibrium)
    a, b = np.asarray(anchors, float)
    notes: list[str] = []
    upgraded: list[int] = []
    band = None
    rounds = 0
    limit = max_rounds if max_rounds is not None else sum(len(c) for c in cands)
    while True:
        tau = solver_moment(caps(), g)
        try:
            fb = friction_band(lengths, m, a, b, capacity=tau, **kw)
        except (ValueError, np.linalg.LinAlgError) as err:
            notes.append(f"no friction band: {err}")
            band = None
            break
        band = fb.band
        if band <= budget or rounds >= limit:
            break
        # the pin adding most to the widest joint's band, in the equilibrium's own cell
        j = int(np.argmax(fb.per_joint))
        share = tau * np.linalg.norm(fb.response[j], axis=0)
        best = None
        for k in np.argsort(-share):
            if none[k] or share[k] <= 0:
                continue
            now = chosen(k).capacity(forces[k])
            lower = [i for i, (o, _) in enumerate(cands[k]) if o.capacity(forces[k]) < now * (1 - 1e-9)]
            if lower:
                best = (int(k), lower[0])
                break
        if best is None:
            break
        k, i = best
        pick[k] = i
        upgraded.append(k)
        rounds += 1
    if _mirrored(lengths, equilibrium.points) and upgraded:
        # a mirror-symmetric chain gets mirror-symmetric hardware: each pair of mirror pins the
        # one of less friction (a smaller box of moments: the band can only narrow)
        for k in range(n + 1):
            t = n - k
            if not none[k] and cands[k][pick[k]][0].capacity(forces[k]) < cands[t][pick[t]][0].capacity(forces[t]):
                name = cands[k][pick[k]][0].name
                same = [j for j, (o, _) in enumerate(cands[t]) if o.name == name]
                if same:
                    pick[t] = same[0]
                    upgraded.append(t)
        band = None
    if band is None:
        try:
            band = friction_band(lengths, m, a, b, capacity=solver_moment(caps(), g), **kw).band
        except (ValueError, np.linalg.LinAlgError):
            band = None
    opts = [chosen(k) for k in range(n + 1)]
    rated = np.array([np.nan if none[k] else cands[k][pick[k]][1] for k in range(n + 1)])
    if band is not None and band > budget:
        notes.append(f"the friction band is {band:.3g} mm with the least-friction hardware the catalog offers "
                     f"(budget {budget:.3g} mm): measure the pins' friction (rodcad calibrate friction) or add hardware "
                     "of less friction to the catalog's pins")
    if overloaded:
        notes.append(f"pin(s) {overloaded}: no hardware in the catalog carries the load with a safety factor of "
                     f"{menu.safety:g} (largest {forces[overloaded].max():.3g} N); the strongest that fits is used")
    return JointHardware(opts, forces, rated, menu.safety, caps(), band, float(budget), sorted(set(upgraded)),
                         overloaded, notes)
