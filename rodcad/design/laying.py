"""Rods printed to order for given joints and stops: each rod made for its place, and the
inverse problem with their numbers (:func:`lay_rods`).

A joint resting on a stop gets two flush ends whose chamfers add up to the bend it holds
(the rods' half arc angles taken off), on the side the stop works: :data:`HI` (top faces:
it cannot bend further), :data:`LO` (bottom faces: it cannot straighten) or :data:`LOCK`
(both: a two-sided stop holds it at its bend both ways; a fused joint is mitred the same
way before its rods are united). Each rod's centre of mass and mass range come from
:mod:`rodcad.catalog.printed`, its joint limits from its end geometry
(:func:`rodcad.catalog.jointlimits.joint_limits`), with no B-rep search. The planner
(:mod:`rodcad.design.decide`, :mod:`rodcad.design.printed`) decides the stops.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import lru_cache

import numpy as np

from optimize import InverseProblem
from rodcad.catalog.keptlimits import kept_joint_limits
from rodcad.catalog.model import Catalog, Family, RodGeometry, RodType
from rodcad.catalog.printed import MassTable, rod_numbers
from rodcad.catalog.scaling import mass_span, scale_for_mass

__all__ = ["HI", "LO", "LOCK", "Laid", "PrintedFamily", "SAME_ROD", "SAFE_MARGIN_DEG", "STOP_SNAP_DEG",
           "end_limits_for", "free_limits", "free_turn_range", "graduate", "lay_rods"]

#: A stop printed to order must stop, by the rods' outlines, within this of the bend it is
#: made for (deg); it is designed exactly at the bend.
STOP_SNAP_DEG = 0.05

@dataclass(frozen=True)
class PrintedFamily:
    """A family printed to order with its mass table (from the solids, cached)."""

    family: Family
    table: MassTable


def _limits(left: RodGeometry, right: RodGeometry) -> tuple[float, float]:
    """Joint limits (deg) of two rods, +-inf where nothing stops (kept in this process and
    on disk: :func:`rodcad.catalog.keptlimits.kept_joint_limits`)."""
    lo, hi = kept_joint_limits(left, right)
    return (-math.inf if lo is None else lo, math.inf if hi is None else hi)


#: Rods whose parameters (length mm, curvature 1/mm, setbacks mm, chamfers deg) agree to
#: these (and scale) are made identical (a symmetric target's mirror images differ by round-off and by
#: the curve's sampling): one solid to build, one name.
SAME_ROD = (1e-9, 1e-7, 1e-9, 1e-6, 1e-6, 1e-9, 1e-6, 1e-6, 1e-6)


def _params(t: RodType) -> tuple[float, ...]:
    g = t.geometry
    return (g.length, g.curvature, g.first.setback, g.first.top_chamfer, g.first.bottom_chamfer,
            g.second.setback, g.second.top_chamfer, g.second.bottom_chamfer, t.scale)


def _unique(rods: list[RodType], catalog: Catalog) -> list[RodType]:
    """Rods equal to round-off made one; distinct rods whose rounded names agree renamed."""
    out: list[RodType] = []
    by_name: dict[str, RodType] = {t.name: t for t in catalog.types}
    for t in rods:
        p = _params(t)
        same = next((u for u in out if all(abs(a - b) <= tol for a, b, tol in zip(p, _params(u), SAME_ROD))), None)
        if same is not None:
            out.append(same)
            continue
        name, k = t.name, 2
        while name in by_name and by_name[name] != t:
            name, k = f"{t.name}.{k}", k + 1
        if name != t.name:
            t = replace(t, name=name)
        by_name[name] = t
        out.append(t)
    return out


@dataclass
class Laid:
    """Rods made for their places and their inverse problem (:func:`lay_rods`).

    Attributes:
        rods: the rods, in chain order.
        problem: the inverse problem with these rods' numbers.
        notes: what the rods could not do, in words.
        unmet: joints whose bend these rods cannot hold.
        spans: the problem's mass bounds are each rod's span over the scales it can be
            printed at (a graduated family before its scales are chosen, :func:`graduate`).
        params: per rod (length mm, curvature 1/mm, Catalog.rod's end keywords): what the
            rod was made from, for choosing its scale.
    """

    rods: list[RodType]
    problem: InverseProblem
    notes: list[str]
    unmet: list[int]
    spans: bool = False
    params: list[tuple[float, float, dict[str, float]]] = field(default_factory=list)


#: Stop sides: a hi stop keeps the joint from bending further (top faces meet), a lo stop
#: from straightening further (bottom faces meet), a two-sided stop (lock) holds it at its
#: bend both ways (both faces flush).
HI, LO, LOCK = -1, 1, 0


def end_limits_for(points: np.ndarray, ends: dict[int, int], given: np.ndarray | None = None) -> np.ndarray | None:
    """Bounds on the end rods' angles (rad) for anchor stops at their target angles: ``ends``
    maps 0 (A) / 1 (B) to the side of :func:`optimize.chain.stops.needed_stop_sides` (HI or LO,
    in the anchor's bend, :func:`optimize.chain.statics.extended_bends`); ``given`` (2, 2): the
    design's own bounds, kept where no stop is added."""
    out = np.full((2, 2), [-np.inf, np.inf]) if given is None else np.array(given, float)
    d = np.diff(points, axis=0)
    theta = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
    for k, side in ends.items():
        t = float(theta[0] if k == 0 else theta[-1])
        t = math.atan2(math.sin(t), math.cos(t))  # the angle from +x in (-180, 180] deg
        # A: bend = theta_0 (HI keeps it from growing); B: bend = -theta_{N-1}
        upper = (side == HI) == (k == 0)  # the stop bounds the angle from above
        out[k] = (-np.inf, t) if upper else (t, np.inf)
    return None if np.all(np.isinf(out)) else out


def lay_rods(catalog: Catalog, pf: PrintedFamily, points: np.ndarray, lengths: np.ndarray, kappa: np.ndarray,
             phi: np.ndarray, stops: dict[int, tuple[float, int]], limits: bool = True, same: bool = False,
             end_limits: np.ndarray | None = None, fused: frozenset[int] | set[int] = frozenset(),
             scales: np.ndarray | None = None, spans: bool = False) -> Laid:
    """The rods for given stops and their inverse problem.

    Args:
        catalog, pf: the catalog and the family printed to order.
        points, lengths, kappa, phi: the joints on the curve (mm), the rods' lengths (mm),
            curvatures (1/mm) and the target bends (rad).
        stops: joint -> (bend deg, side): :data:`HI` (the rods' top faces meet at the bend:
            it cannot bend further), :data:`LO` (bottom faces: it cannot straighten) or
            :data:`LOCK` (a two-sided stop: both faces flush, the joint held at its bend both
            ways; a fused joint is printed the same way, as a mitre, before its rods are united).
        limits: False: only the stops are limits (enough for the statics at the target, which
            only sees joints resting on a limit); True: the rods' own limits, checked.
        same: one shell for every rod (rods bent less together where a stop needs it).
        end_limits: the anchor fixtures' bounds on the end rods' angles (rad).
        fused: joints whose rods are printed as one piece: their mitre may lie beyond the
            family's stop range (no faces meet there: the rods are united).
        scales: each rod's body scale (a graduated family, Catalog.rod's ``scale``), or None:
            the family's section for every rod.
        spans: (a graduated family, ``scales`` None) each rod's mass bounds are its span over
            the scales it can be printed at (:func:`rodcad.catalog.scaling.mass_span`), its
            centre of mass at scale 1: the statics then choose masses, and :func:`graduate`
            the scale of each rod that makes its mass.
    """
    fam = pf.family
    r = fam.ranges
    assert fam.template is not None and r is not None
    n = lengths.size
    kappa = kappa.copy()

    def tangent_bends() -> dict[int, float]:
        psi = np.degrees(np.arcsin(np.clip(kappa * lengths / 2, -1, 1)))
        return {j: s - psi[j] - psi[j + 1] for j, (s, _) in stops.items()}

    turn = tangent_bends()
    tol = 1e-9  # as the planner's test of a printable stop (a bend of 90 deg to round-off)
    while r.stops is not None and (bent := [j for j, t in turn.items()
                                            if j not in fused and not r.stops[0] - tol <= t <= r.stops[1] + tol]):
        # faces the family cannot print: the rods beside such a stop are bent less, down to
        # straight (a stop between straight rods is half the bend on each end, in the range)
        before = kappa.copy()
        for j in bent[:1] if same else bent:  # one shell: every rod bent less together
            at = slice(None) if same else [j, j + 1]
            kappa[at] = np.where(np.abs(kappa[at]) > 1e-4, kappa[at] * 0.8, 0.0)
        if np.array_equal(kappa, before):  # straight already: the bend itself is out of range
            break
        turn = tangent_bends()
    top = {j: turn[j] / 2 for j, (_, side) in stops.items() if side in (HI, LOCK)}
    under = {j: -turn[j] / 2 for j, (_, side) in stops.items() if side in (LO, LOCK)}
    params = [(float(lengths[i]), float(kappa[i]),
               {k: v for k, v in (("first_stop", top.get(i - 1)), ("second_stop", top.get(i)),
                                  ("first_under", under.get(i - 1)), ("second_under", under.get(i)))
                if v is not None})
              for i in range(n)]
    spans = spans and scales is None and r.scale is not None
    s_ref = 1.0 if r.scale is None else min(max(1.0, r.scale[0]), r.scale[1])
    rods = _unique([catalog.rod(fam.name, x, k, scale=s_ref if scales is None else float(scales[i]), **e)
                    for i, (x, k, e) in enumerate(params)], catalog)
    lengths = np.array([t.length for t in rods])  # a rod made one with its twin: the twin's length
    nums = [rod_numbers(t, pf.table, fam.template) for t in rods]
    if spans:  # each rod's mass over every scale it can be printed at
        nums = [replace(x, mass_range=mass_span(catalog, fam.name, pf.table, t.length, t.curvature, **e))
                for x, t, (_, _, e) in zip(nums, rods, params)]
    rows = np.zeros((max(n - 1, 0), 2))
    notes, unmet = [], []
    for j in range(n - 1):
        bend = math.degrees(phi[j])
        if j in stops and stops[j][1] == LOCK:  # held both ways (or fused): rigid at its bend
            rows[j] = np.radians([stops[j][0], stops[j][0]])
            if limits and j not in fused:
                lo, hi = _limits(rods[j].geometry, rods[j + 1].geometry)
                if max(abs(lo - stops[j][0]), abs(hi - stops[j][0])) > STOP_SNAP_DEG:
                    notes.append(f"joint {j}: the two-sided stop printed for {stops[j][0]:.2f} deg holds it within "
                                 f"[{lo:.2f}, {hi:.2f}] deg by the rods' outlines")
                    unmet.append(j)
            continue
        if not limits:  # only the stops: the statics at the target sees nothing else
            lo, hi = -math.inf, math.inf
            if j in stops:
                lo, hi = (lo, stops[j][0]) if stops[j][1] == HI else (stops[j][0], hi)
            rows[j] = np.radians([lo, hi])
            continue
        lo, hi = _limits(rods[j].geometry, rods[j + 1].geometry)
        if j in stops:
            s, side = stops[j]
            got = hi if side == HI else lo
            if abs(got - s) > STOP_SNAP_DEG:
                notes.append(f"joint {j}: the stop printed for {s:.2f} deg stops at {got:.2f} deg by the rods' "
                             "outlines")
                unmet.append(j)
            # designed flush: the faces meet exactly at the bend
            lo, hi = (lo, s) if side == HI else (s, hi)
        elif not lo < bend < hi:
            notes.append(f"joint {j} bends {bend:.1f} deg, beyond what the family's free ends allow "
                         f"([{lo:.1f}, {hi:.1f}] deg)")
            unmet.append(j)
        rows[j] = np.radians([lo, hi])
    problem = InverseProblem(target=points, lengths=lengths,
                             mass_bounds=np.array([x.mass_range for x in nums], float),
                             com=np.array([x.com for x in nums], float), limits=rows, end_limits=end_limits)
    return Laid(rods, problem, notes, unmet, spans, params)


def graduate(catalog: Catalog, pf: PrintedFamily, laid: Laid, masses: np.ndarray) -> np.ndarray:
    """Each rod's scale for its mass (:func:`rodcad.catalog.scaling.scale_for_mass`: the
    mass nearest the middle of the rod's range at that scale); a mass no scale reaches (the
    statics' round-off at a bound of the span) takes the nearest end of the scale range."""
    fam = pf.family
    out = np.ones(len(laid.rods))
    for i, (t, m, (_, _, e)) in enumerate(zip(laid.rods, masses, laid.params)):
        choice = scale_for_mass(catalog, fam.name, pf.table, t.length, float(m), t.curvature, **e)
        if choice is not None:
            out[i] = choice.scale
        else:
            lo, hi = catalog.scale_range(fam.name, t.length, t.curvature, **e)
            out[i] = lo if m <= laid.problem.mass_bounds[i].mean() else hi
    return out


def free_limits(catalog: Catalog, pf: PrintedFamily, lengths: np.ndarray, kappa: np.ndarray,
                bends_deg: np.ndarray | None = None) -> np.ndarray:
    """(N-1, 2) the joint limits (deg) of the rods with the family's own ends: how far each
    joint can bend either way with no stop printed (+-inf where nothing collides).

    With ``bends_deg``, a joint whose tangent turn (the bend less the rods' half arc angles:
    where their own ends meet) lies well inside the family's :func:`free_turn_range` gets
    that range shifted by the half arc angles instead of a search of its own pair (tens of
    milliseconds each), which only matters near the limits."""
    fam = pf.family
    rods = [catalog.rod(fam.name, float(length), float(k)) for length, k in zip(lengths, kappa)]
    psi = np.degrees(np.arcsin(np.clip(np.asarray(kappa, float) * np.asarray(lengths, float) / 2, -1, 1)))
    turn = free_turn_range(catalog, fam.name) if bends_deg is not None else None
    out = []
    for j in range(len(rods) - 1):
        shift = float(psi[j] + psi[j + 1])
        if turn is not None and turn[0] + SAFE_MARGIN_DEG < bends_deg[j] - shift < turn[1] - SAFE_MARGIN_DEG:
            out.append((turn[0] + shift, turn[1] + shift))
        else:
            out.append(_limits(rods[j].geometry, rods[j + 1].geometry))
    return np.array(out, float).reshape(-1, 2)


#: A tangent turn this far (deg) inside the family's free range needs no search of its own
#: pair: over the default catalog's lengths and curvatures the free range of the tangent
#: turn varies by 0.3 deg.
SAFE_MARGIN_DEG = 2.0


@lru_cache(maxsize=16)
def free_turn_range(catalog: Catalog, family: str) -> tuple[float, float]:
    """(lo, hi) deg: how far the tangents of two rods of the family meet turned at the joint,
    with their own ends (the straight shortest pair's limits). A pair's chord limits are
    this range plus the two half arc angles: the ends meet in the tangent frame."""
    r = catalog.family(family).ranges
    assert r is not None
    rod = catalog.rod(family, float(r.length[0]), 0.0)
    return _limits(rod.geometry, rod.geometry)
