"""The planner decides how each joint of a chain printed to order holds its bend, and checks
the result against the physics.

For rods laid on a target (:mod:`rodcad.design.printed`), every joint and anchor gets one
of:

- **free**: it hangs; the masses hold its bend (a sagging bend, within what the rods' own
  ends allow);
- **a stop** printed at its bend, on either side (:data:`HI`: it cannot bend further,
  :data:`LO`: it cannot straighten), where the masses need a moment there, or the bend is
  straight or concave;
- **a two-sided stop** (:data:`LOCK`: both faces flush, the joint held at its bend both
  ways), where a one-sided stop leaves the chain another shape to fall into;
- **fused**: the two rods printed as one piece (their ends mitred and united), where the
  bend is sharper than any stop the family prints;
- **an anchor stop**: the fixture holds the end rod at its angle (a moment at the anchor).

The loop: (1) the forced choices (straight, concave and too-sharp bends); (2) the fewest
further stops and anchor stops that let the masses balance the target within their ranges
(a linear program, :func:`optimize.chain.stops.needed_stop_sides`); (3) the masses
(:func:`optimize.chain.statics.exact_masses`); (4) the verdict of the solver
(:func:`optimize.chain.verify.verify`): the equilibrium reached from the designed state must be
the target and stable, and no other stable shape the multi-start finds may lie lower; (5)
where it fails, the joints where the chain goes instead are held both ways (two-sided
stops, or fused where no stop can be printed) and the loop starts again. Each round holds
at least one more joint, so the loop ends; a chain held at every joint is one rigid body
pinned at both anchors, the last resort. Constraints restrict the choice (``joints: free``
forbids stops, ``anchor_stops: none`` the fixture's, ``fuse: never`` fused pieces).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from optimize.chain.inverse import design
from optimize.chain.statics import exact_masses
from optimize.chain.stops import needed_stop_sides
from optimize.chain.verify import Verdict, verify
from rodcad.catalog.model import Catalog
from rodcad.design.asprinted import Robust, joint_bands, narrower, too_wide
from rodcad.design.laying import (HI, LO, LOCK, Laid, PrintedFamily, end_limits_for, free_limits, graduate,
                                  lay_rods)

__all__ = ["Allowed", "Decision", "EXTRA_ROUNDS", "HI", "LO", "LOCK", "MAX_ROUNDS", "decide"]

#: Rounds of holding more joints both ways before the planner settles for what it has.
MAX_ROUNDS = 10

#: Rods x rounds of checking with the solver the loop may spend (each round's verdict costs
#: about a multi-start of the chain): 60 rods get 6 rounds, 25 rods every round.
ROUND_WORK = 400

#: Rounds of holding one more joint once a design is accepted (on target, stable, nothing
#: lower) but the multi-start still finds other, higher shapes.
EXTRA_ROUNDS = 2

#: A bend below this (rad) is straight: only a stop holds it.
STRAIGHT_TOL = 1e-9

#: The chain must hang within this fraction of its size of the target for the planner to
#: count a design as on target (the solver's exactness, far below any printing tolerance).
ON_TARGET = 1e-6

#: An anchor stop costs this much relative to a joint's stop in the linear program: the
#: fixture is printed anyway, and a stop there keeps joints of the chain free.
END_WEIGHT = 0.5


@dataclass(frozen=True)
class Allowed:
    """What the design lets the planner use.

    Attributes:
        stops: joints may rest on stops (False: ``constraints: {joints: free}``).
        anchor_stops: the fixture may stop the end rods (False: ``anchor_stops: none``).
        fuse: 'auto' (where a bend is sharper than any stop), 'never', or 'stops' (every run
            of stopped joints is printed as one piece too).
        verify: check the result against the solver and hold more joints where it fails
            (off for one shell of rods, whose stops are fixed by the shell).
        robust: design option ``robust`` (:class:`rodcad.design.asprinted.Robust`): an accepted
            design whose band at a joint exceeds the allowance even with the least-friction
            joint hardware that carries it, or whose mass band does, gets that joint held both
            ways in one more round (:func:`rodcad.design.asprinted.loose_joints`); None: off.
    """

    stops: bool = True
    anchor_stops: bool = True
    fuse: str = "auto"
    verify: bool = True
    robust: Robust | None = None


@dataclass
class Decision:
    """How every joint holds its bend, the rods made for that, and the solver's verdict.

    Attributes:
        laid: the rods and their inverse problem (the rods' own limits).
        stops: joint -> (bend deg, side :data:`HI` / :data:`LO` / :data:`LOCK`), fused joints
            included (as :data:`LOCK`).
        ends: anchor (0: A, 1: B) -> side of its stop.
        fused: joints whose rods are printed as one piece.
        beyond: joints whose bend nothing allowed can hold.
        verdict: the solver's verdict (None when not checked).
        rounds: rounds of the loop.
        held: joints the loop held both ways to rule out other shapes.
        notes: what the planner did and why, in words.
        feasible: some choice of stops balances the target within the mass ranges.
        history: per round, the joints held both ways so far and the solver's verdict.
        masses: the masses the verdict is for (None when not checked).
    """

    laid: Laid
    stops: dict[int, tuple[float, int]]
    ends: dict[int, int]
    fused: set[int]
    beyond: list[int]
    verdict: Verdict | None = None
    rounds: int = 0
    held: list[int] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    feasible: bool = True
    history: list[tuple[list[int], Verdict | None]] = field(default_factory=list)
    masses: np.ndarray | None = None

    @property
    def accepted(self) -> bool:
        """The solver confirms it: on target, stable, nothing lower."""
        v = self.verdict
        return v is not None and v.on_target and not v.lower


def _mirror(j: int, n: int) -> int:
    return n - 2 - j


def decide(catalog: Catalog, pf: PrintedFamily, points: np.ndarray, lengths: np.ndarray, kappa: np.ndarray,
           phi: np.ndarray, *, allowed: Allowed, end_limits: np.ndarray | None = None, mirrored: bool = False,
           same: bool = False, n_starts: int = 12, seed: int = 0, work: int | None = None,
           report=None) -> Decision:
    """Decide every joint's and anchor's way of holding its bend (see the module's docstring).

    Args:
        catalog, pf: the catalog and the family printed to order.
        points, lengths, kappa, phi: joints on the curve (mm), rod lengths (mm), curvatures
            (1/mm), target bends (rad).
        allowed: what the design lets the planner use.
        end_limits: the design's own bounds on the end rods' angles (rad), kept.
        mirrored: the target is its own mirror image: every choice is mirrored.
        same: one shell for every rod.
        n_starts, seed: the multi-start of each verdict.
        work: rods x rounds the loop may check before it stops holding more joints (default
            :data:`ROUND_WORK`): counted, not timed, so a design is the same on every machine.
        report: called with a line of progress per round (or None).
    """
    n = lengths.size
    r = pf.family.ranges
    assert r is not None
    deg = np.degrees(phi)
    stop_range = r.stops if allowed.stops else None

    def printable(j: int) -> bool:
        return stop_range is not None and stop_range[0] - 1e-9 <= deg[j] <= stop_range[1] + 1e-9

    free_lim = free_limits(catalog, pf, lengths, kappa, deg) if n > 1 else np.zeros((0, 2))
    can_fuse = allowed.fuse != "never" and allowed.stops
    forced, fused, beyond = [], set(), []
    for j in range(n - 1):
        straight = phi[j] <= STRAIGHT_TOL
        free_ok = free_lim[j, 0] < deg[j] < free_lim[j, 1]
        if not straight and free_ok:
            continue
        if printable(j):
            forced.append(j)
        elif can_fuse:
            fused.add(j)
        else:
            beyond.append(j)
    if mirrored:
        fused |= {_mirror(j, n) for j in fused}
    graded = r.scale is not None and r.scale[1] > r.scale[0] and not same
    locks: set[int] = set()
    ends_allowed = (0, 1) if allowed.anchor_stops else ()
    best: Decision | None = None
    notes: list[str] = []
    history: list[tuple[list[int], Verdict | None]] = []
    settled = 0
    robust = None  # (the first accepted design, its bands) once design option robust looked at it
    budget = ROUND_WORK if work is None else work
    for rnd in range(MAX_ROUNDS + 1):
        rigid = {j: (float(deg[j]), LOCK) for j in sorted(locks | fused)}
        bare = lay_rods(catalog, pf, points, lengths, kappa, phi, rigid, limits=False, same=same,
                        end_limits=end_limits, fused=fused, spans=graded)
        optional = [j for j in range(n - 1) if printable(j) and j not in forced and j not in rigid]
        need = needed_stop_sides(bare.problem, optional, forced=[j for j in forced if j not in rigid],
                                 ends=ends_allowed, end_weight=END_WEIGHT)
        feasible = need is not None
        stops = dict(rigid)
        ends: dict[int, int] = {}
        if need is None:  # no stops balance it: the forced ones, on the sagging side
            stops.update({j: (float(deg[j]), HI) for j in forced if j not in rigid})
        else:
            for j, side in zip(*need):
                j, side = int(j), int(side)
                if j < 0 or j >= n - 1:
                    ends[0 if j < 0 else 1] = side
                elif j not in stops:
                    stops[j] = (float(deg[j]), side)
            if mirrored:
                _symmetrize(stops, ends, n, deg, printable)
        if robust is not None:  # design option robust: the accepted design's stops stay, the held joints added
            stops.update({j: v for j, v in robust[0].stops.items() if j not in stops})
            ends.update({k: v for k, v in robust[0].ends.items() if k not in ends})
        lay = dict(limits=True, same=same, end_limits=end_limits_for(points, ends, end_limits), fused=fused)
        if graded:  # each rod's scale for the mass the statics give it, then its own numbers
            laid = _graded(catalog, pf, lambda limits: lay_rods(catalog, pf, points, lengths, kappa, phi, stops,
                                                                spans=True, **{**lay, "limits": limits}),
                           lambda sc: lay_rods(catalog, pf, points, lengths, kappa, phi, stops, scales=sc, **lay),
                           mirrored)
        else:
            laid = lay_rods(catalog, pf, points, lengths, kappa, phi, stops, **lay)
        verdict = masses = None
        if allowed.verify and n > 1:
            if report is not None:
                report(f"checking the stops with the solver (round {rnd + 1}"
                       + (f", {len(locks)} joint(s) held both ways)" if locks else ")"))
            masses = exact_masses(laid.problem)[0]
            verdict = verify(laid.problem, masses, n_starts=n_starts, seed=seed, tol=ON_TARGET)
        history.append((sorted(locks), verdict))
        d = Decision(laid, stops, ends, set(fused), list(beyond), verdict, rnd, sorted(locks), notes, feasible,
                     history, masses)
        if best is None or _better(d, best):
            best = d
        if verdict is None or (d.accepted and not verdict.others and allowed.robust is None) or not feasible:
            break
        if (rnd + 2) * n > budget:  # another round would pass the work budget
            notes.append(f"the planner stopped holding joints after {rnd + 1} round(s) (its work budget: "
                         f"{budget} rod-rounds)")
            break
        new = _to_hold(verdict.culprits, n, locks | fused, printable, can_fuse)
        if d.accepted:  # other shapes exist, all higher: hold one joint more, for a few rounds
            settled += 1
            new = new[:1] if settled <= EXTRA_ROUNDS else []
        if d.accepted and not new and allowed.robust is not None:
            bands = joint_bands(laid.problem, masses, allowed.robust, seed=seed)
            if robust is None:  # the first accepted design: hold the joints whose band is too wide
                robust = (d, bands)
                new = [j for j in too_wide(bands, allowed.robust.allowance) if j not in locks | fused]
            else:  # the design that holds them, kept where its bands are narrower
                best = d if narrower(bands, robust[1]) else robust[0]
                notes.append(f"robust: joint(s) {sorted(set(best.held) - set(robust[0].held))} held both ways, "
                             "where pin friction (with the least-friction joint hardware of the catalog that "
                             "carries the load) or the print's mass tolerance moved the chain more than "
                             f"{allowed.robust.allowance:.3g} mm" if best is d else "robust: holding the joints whose "
                             "bands exceed the tolerance does not narrow them here; the design keeps them free")
                break
        if not new:
            break
        for j in new:
            (locks if printable(j) else fused).add(j)
            if mirrored:
                m = _mirror(j, n)
                (locks if printable(m) else fused).add(m)
    assert best is not None
    return best


#: Rounds of choosing scales for the masses and the masses for the scales' centres of mass.
GRADE_ROUNDS = 3

#: Simulator calls of the best fit over the scales' mass spans, where no masses balance the
#: target.
GRADE_NFEV = 100


def _graded(catalog: Catalog, pf: PrintedFamily, lay_spans, lay, mirrored: bool) -> Laid:
    """The rods at the scales their masses need: the masses from the statics over each rod's
    span of scales, each rod's scale for its mass (:func:`rodcad.design.laying.graduate`),
    then the masses again with the rods' own centres of mass and ranges, until every mass
    lies in its rod's range (at most :data:`GRADE_ROUNDS` times).

    ``lay_spans(limits)`` lays the rods over their spans: the statics at the target see only
    the stops (``limits`` False), the best fit's simulations the rods' own limits too (True,
    laid only when no masses balance the target: the joint limits of rods that are not
    printed are most of the work)."""
    spans = lay_spans(False)
    problem = spans.problem
    limited = None
    for _ in range(GRADE_ROUNDS):
        masses, _, reachable, _ = exact_masses(problem)
        if not reachable:  # the best fit over the spans (the scales then hold its masses)
            if limited is None:
                limited = lay_spans(True)
            masses = design(dataclasses.replace(limited.problem, com=problem.com), "refine",
                            max_nfev=GRADE_NFEV).masses
        if mirrored:  # a symmetric target's rods in mirror pairs, as its stops
            masses = (masses + masses[::-1]) / 2
        laid = lay(tuple(graduate(catalog, pf, spans, masses)))
        if exact_masses(laid.problem)[2]:
            break
        problem = dataclasses.replace(spans.problem, com=laid.problem.com)  # the spans, the scaled rods' coms
    return laid


def _symmetrize(stops: dict[int, tuple[float, int]], ends: dict[int, int], n: int, deg: np.ndarray,
                printable) -> None:
    """A symmetric target keeps its symmetry: every stop and anchor stop mirrored (a joint
    with stops on both sides in the two halves holds both ways)."""
    for j, (_, side) in list(stops.items()):
        m = _mirror(j, n)
        if m in stops:
            if stops[m][1] != side:
                stops[j] = stops[m] = (float(deg[j]), LOCK) if printable(j) else stops[j]
        elif printable(m):
            stops[m] = (float(deg[m]), side)
    for k, side in list(ends.items()):
        ends.setdefault(1 - k, side)


def _to_hold(culprits: list[int], n: int, held: set[int], printable, can_fuse: bool) -> list[int]:
    """The joints to hold both ways next: the culprits (an anchor's culprit moves to the joint
    next to it), those that can be held."""
    out: list[int] = []
    for j in culprits:
        j = 0 if j < 0 else (n - 2 if j >= n - 1 else j)
        if j in held or j in out or not (printable(j) or can_fuse):
            continue
        out.append(j)
    return out


def _score(d: Decision) -> tuple:
    """Accepted first, then on target, then the only stable shape found, then the error."""
    v = d.verdict
    if v is None:
        return (1, 1, 1, 0.0)
    return (0 if d.accepted else 1, 0 if v.on_target else 1, 1 if v.others else 0, v.error / max(v.size, 1e-300))


def _better(a: Decision, b: Decision) -> bool:
    return _score(a) < _score(b)
