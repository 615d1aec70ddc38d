"""Rods printed to order laid on a target: every rod gets its own length, curvature, stop
ends and (next, :mod:`rodcad.design.masses`) mass.

    curve + a family printed to order
      -> joints on the curve     equal chords per piece between corners, every corner a
                                 joint; a polyline whose segments split into rods of the
                                 family's lengths comes back exactly (its vertices are joints)
      -> curvatures              each rod's body follows the curve between its joints
                                 (the arc through both pins and the curve mid-chord)
      -> stops                   concave and straight bends need a stop; where the masses
                                 cannot hold a sagging bend within their ranges, the fewest
                                 stops that let them (a linear program,
                                 :func:`optimize.chain.stops.needed_stops`), each printed at the
                                 bend it holds: two flush ends whose chamfers add up to it
      -> the inverse problem     centres of mass, mass ranges and joint limits of these
                                 very rods (:mod:`rodcad.catalog.printed`, no B-rep search)

``constraints: {joints: free}`` forbids stops: the masses alone, the best fit where they
cannot hold the shape. ``constraints: {same_shell: true}`` lays one outer shell for every
rod (:mod:`rodcad.design.shell`: one length, one curvature, the family's own ends).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from optimize import InverseProblem
from optimize.chain.discretize import discretize
from optimize.chain.curves import fit_curvatures
from rodcad.catalog.model import Catalog, RodType, max_curvature
from rodcad.design.decide import Allowed, decide
from rodcad.design.laying import HI, LO, LOCK, PrintedFamily, STOP_SNAP_DEG
from rodcad.design.shell import TRIES, ShellError, most_faithful, one_shell

__all__ = ["FREE_SHARE", "FREER_FIT", "LONGER", "PrintedFamily", "PrintedPlan", "STOP_SNAP_DEG", "ShellError", "count_for",
           "free_share", "freest", "fused_pieces", "plan_printed", "returns", "rods_of"]

@dataclass
class PrintedPlan:
    """Rods printed to order laid on a target.

    Attributes:
        discretization: joints on the curve.
        rods: the rods made to order, in chain order (a rod repeated where identical).
        problem: the inverse problem with these rods' numbers.
        notes: what the plan could not do, in words.
        unmet: joints whose bend these rods cannot hold.
        stops: joints resting on stops printed at their bends.
        anchor_stops: anchors whose fixture stops the end rod at its target angle: 0 (A,
            the first rod), 1 (B, the last rod); the bounds are ``problem.end_limits``.
        fused: rods printed as one rigid piece, as (first, last) rod indices: the joints
            between them are fused (a limits row with lo == hi at the bend).
        verified: (masses, verdict) the planner checked with the solver
            (:func:`optimize.chain.verify.verify`), or None: the mass design reuses the verdict
            when it chooses the same masses for the same problem.
    """

    discretization: object
    rods: list[RodType]
    problem: InverseProblem
    notes: list[str]
    unmet: list[int]
    stops: list[int]
    anchor_stops: list[int] = field(default_factory=list)
    fused: list[tuple[int, int]] = field(default_factory=list)
    verified: tuple[np.ndarray, object] | None = None


#: A bend below this (rad) is straight: only a stop holds it.
STRAIGHT_TOL = 1e-9

#: Joints mirror each other to this fraction of the span on a symmetric target.
MIRROR_TOL = 1e-7


def _is_mirror_symmetric(points: np.ndarray) -> bool:
    """Whether the joints are their own mirror image about the vertical through the middle
    of the anchors (anchors at one height): the chain, its rods and stops then mirror too."""
    a, b = points[0], points[-1]
    span = float(np.hypot(*(b - a)))
    if span <= 0 or abs(b[1] - a[1]) > MIRROR_TOL * span:
        return False
    mirror = np.column_stack([a[0] + b[0] - points[::-1, 0], points[::-1, 1]])
    return bool(np.abs(mirror - points).max() <= MIRROR_TOL * span)


def _at_resolution(disc, res: float, bounds: tuple[float, float]):
    """The discretisation with every length a multiple of ``res`` (within the range), the
    chain closed again on B by the smallest turn of its rods (Gauss-Newton on the closure):
    the joints move off the curve by about ``res`` at most."""
    from dataclasses import replace as _replace

    lengths = np.round(disc.lengths / res) * res
    lo, hi = math.ceil(bounds[0] / res - 1e-9) * res, math.floor(bounds[1] / res + 1e-9) * res
    lengths = np.clip(lengths, lo, hi)
    if np.array_equal(lengths, disc.lengths):
        return disc
    pts = disc.points
    d = np.diff(pts, axis=0)
    theta = np.arctan2(d[:, 1], d[:, 0])
    goal = pts[-1] - pts[0]
    span = max(float(np.hypot(*goal)), 1e-9)
    for _ in range(50):
        r = np.array([lengths @ np.cos(theta), lengths @ np.sin(theta)]) - goal
        if np.hypot(*r) <= 1e-13 * span:
            break
        J = np.vstack([-lengths * np.sin(theta), lengths * np.cos(theta)])
        theta = theta - J.T @ np.linalg.solve(J @ J.T, r)
    else:
        raise ValueError(f"rods of lengths rounded to {res:g} mm do not close on the anchors")
    points = np.vstack([pts[:1], pts[0] + np.cumsum(lengths[:, None] * np.column_stack([np.cos(theta),
                                                                                          np.sin(theta)]), axis=0)])
    points[-1] = pts[-1]
    moved = float(np.hypot(*(points - pts).T).max())
    return _replace(disc, points=points, lengths=lengths, joint_error=max(disc.joint_error, moved))


def _layout(curve: np.ndarray, r, preferred: float | None, same_shell: bool):
    """(discretization, curvatures) of the rods :func:`plan_printed` lays on ``curve``."""
    return one_shell(curve, r, preferred) if same_shell else _laid_on(curve, r, preferred)


def _laid_on(curve: np.ndarray, r, preferred: float | None):
    """Joints and curvatures: at the preferred length, or the longest rods that follow the
    curve within :data:`rodcad.design.shell.FOLLOW_REL` of the span (the rods' arcs against
    the curve)."""
    kmax = max(abs(r.curvature[0]), abs(r.curvature[1]))

    def lay(pref: float | None):
        disc = discretize(curve, list(r.length), length_range=r.length, preferred=pref)
        if r.resolution is not None:
            disc = _at_resolution(disc, r.resolution, r.length)
        n = disc.lengths.size
        kappa = np.clip(fit_curvatures(curve, disc.points, max_curvature=kmax) if kmax else np.zeros(n),
                        *r.curvature)
        arc = np.array([max_curvature(x) for x in disc.lengths])  # at most a 120 deg arc per rod
        return disc, np.clip(kappa, -arc, arc)

    if preferred is not None:
        return lay(preferred)

    def tried(pref: float):
        try:
            return lay(pref)
        except ValueError:
            return None

    best = most_faithful(curve, (tried(float(x)) for x in np.geomspace(r.length[1], r.length[0], TRIES)))
    return best if best is not None else lay(None)  # lay(None) raises the discretisation's explanation


def plan_printed(curve: np.ndarray, catalog: Catalog, pf: PrintedFamily, *, preferred_length: float | None = None,
                 stops_allowed: bool = True, same_shell: bool = False, anchor_stops: bool = True,
                 end_limits: np.ndarray | None = None, fuse: str = "auto", n_starts: int = 12, seed: int = 0,
                 report=None, robust: tuple[float, float, float, float] | None = None, layout=None):
    """Lay rods printed to order on a target (see the module's docstring); how each joint
    holds its bend is decided, and checked, by :func:`rodcad.design.decide.decide`.

    Args:
        curve: (M, 2) target polyline from A to B (mm).
        catalog: the catalog (rods are made with :meth:`Catalog.rod`).
        pf: the family and its mass table.
        preferred_length: the rod length to aim at (default: the longest rods that follow
            the curve).
        stops_allowed: False forbids stops (``constraints: {joints: free}``).
        same_shell: one outer shell for every rod (``constraints: {same_shell: true}``).
        anchor_stops: the anchor fixtures may stop the first and last rods at their target
            angles where the shape needs it (False: ``constraints: {anchor_stops: none}``).
        end_limits: (2, 2) bounds on the end rods' angles the design gives (rad), or None.
        fuse: 'auto' (rods printed as one piece where a bend is sharper than any stop),
            'never', or 'stops' (also every run of joints resting on stops, where the piece
            fits the catalog's printer).
        n_starts, seed: the multi-start of the planner's checks.
        report: called with a line of progress now and then (or None).
        robust: design option ``robust`` (:attr:`rodcad.design.decide.Allowed.robust`), or None.
        layout: the rods' (discretization, curvatures) for these arguments when the caller has
            them already (:func:`_layout`), or None.

    Returns:
        The :class:`PrintedPlan`.

    Raises:
        ShellError: same_shell, and the curve's corners forbid one length (explained).
        ValueError: the rods cannot be laid on the curve (explained).
    """
    fam = pf.family
    r = fam.ranges
    assert r is not None
    curve = np.asarray(curve, float)
    disc, kappa = _layout(curve, r, preferred_length, same_shell) if layout is None else layout
    points, lengths = disc.points, disc.lengths
    d = np.diff(points, axis=0)
    phi = np.diff(np.unwrap(np.arctan2(d[:, 1], d[:, 0])))
    deg = np.degrees(phi)
    allowed = Allowed(stops=stops_allowed and r.stops is not None, anchor_stops=anchor_stops,
                      fuse=fuse, verify=not same_shell, robust=robust)
    dec = decide(catalog, pf, points, lengths, kappa, phi, allowed=allowed, end_limits=end_limits,
                 mirrored=_is_mirror_symmetric(points), same=same_shell, n_starts=n_starts, seed=seed,
                 report=report)
    laid, stops, ends = dec.laid, dec.stops, dec.ends
    notes: list[str] = list(dec.notes)
    beyond = dec.beyond
    if beyond:
        why = ("stops are forbidden (constraints.joints: free)" if not stops_allowed else
               "the family prints no stops" if r.stops is None else
               f"the family prints stops from {r.stops[0]:g} to {r.stops[1]:g} deg and fused pieces are not allowed")
        notes.append(f"joint(s) {beyond} bend {', '.join(f'{deg[j]:.1f}' for j in beyond)} deg, which only a stop "
                     f"or a fused piece can hold, but {why}; the masses fit the target as well as they can")
    if ends:
        d = np.degrees(np.arctan2(*np.diff(points, axis=0)[[0, -1]].T[::-1]))
        notes.append("the anchor fixture stops " + " and ".join(
            f"the {'first' if k == 0 else 'last'} rod at {d[k]:.2f} deg" for k in sorted(ends))
            + " (its angle from +x): the fixture carries a moment there")
    problem = laid.problem
    fuse_joints = sorted(dec.fused | (set(stops) if fuse == "stops" else set()))
    fused: list[tuple[int, int]] = []
    if fuse_joints:
        fused, too_big = fused_pieces(fuse_joints, points, np.array([t.curvature for t in laid.rods]),
                                      fam.template.geometry.height, catalog.printer)
        lim = problem.limits.copy()
        for first, last in fused:
            lim[first:last] = phi[first:last, None]  # lo == hi: the rods are one rigid body
        problem = replace(problem, limits=lim)
        if fused:
            notes.append("printed as one rigid piece each (their joints fused at the bend): rods "
                         + ", ".join(f"{a} to {b}" for a, b in fused))
        for a, b in too_big:
            if any(j in dec.fused for j in range(a, b)):
                notes.append(f"rods {a} to {b} should be one piece (a bend sharper than any stop) but do not fit the "
                             "printer's build volume as one")
            else:
                notes.append(f"rods {a} to {b} rest on stops instead of being fused: as one piece they do not fit "
                             "the printer's build volume")
    in_piece = {j for a, b in fused for j in range(a, b)}
    held = [j for j in sorted(stops) if j not in in_piece]
    locked = [j for j in held if stops[j][1] == LOCK]
    if held:
        notes.append(f"{len(held)} joint(s) rest on stops printed at the bend they hold: "
                     + ", ".join(f"{j} ({stops[j][0]:.2f} deg"
                                 + {HI: "", LO: ", kept from straightening", LOCK: ", held both ways"}[stops[j][1]] + ")"
                                 for j in held))
    if locked and dec.held:
        notes.append(f"joint(s) {', '.join(map(str, sorted(set(locked) & set(dec.held))))} are held both ways "
                     "(two-sided stops) so that the chain has no other shape to settle in")
    if not dec.feasible and stops_allowed:
        notes.append("even with stops at every joint the family can print, the masses cannot hold this shape "
                     "within their ranges; the masses fit it as well as they can")
    if same_shell:
        k = laid.problem.lengths[0], laid.rods[0].geometry.curvature
        notes.append(f"one shell: every rod {k[0]:.4g} mm long with curvature {k[1]:.5g}/mm" + (
            "; the stops make the ends of the rods beside them differ, so same_shell keeps the length and the "
            "curvature only" if stops else ", the family's own ends; the masses differ only inside"))
    notes += laid.notes
    e0, e1 = problem.end_limits, laid.problem.end_limits
    same = problem is laid.problem or (np.array_equal(problem.limits, laid.problem.limits)
                                       and (e0 is e1 or (e0 is not None and e1 is not None and np.array_equal(e0, e1))))
    verified = (dec.masses, dec.verdict) if dec.verdict is not None and same else None
    return PrintedPlan(disc, laid.rods, problem, notes, sorted(set(beyond) | set(laid.unmet)), sorted(stops),
                       sorted(ends), fused, verified)


def fused_pieces(joints: Sequence[int], points: np.ndarray, curvature: np.ndarray, height: float,
                 printer) -> tuple[list[tuple[int, int]], list[tuple[int, int]]]:
    """Runs of consecutive joints as rigid pieces (first rod, last rod), split where a piece
    would not fit the printer lying on its side (the chain plane on the bed's x and the
    build height, turned in that plane as it fits best; ``printer`` None: any size).

    Returns:
        (pieces, too_big): the pieces that fit, and the runs left on stops because even two
        rods of them do not fit.
    """
    from optimize.chain.curves import centerline

    runs: list[list[int]] = []
    for j in joints:
        if runs and j == runs[-1][-1] + 1:
            runs[-1].append(j)
        else:
            runs.append([j])
    pieces, too_big = [], []

    def fits(first: int, last: int) -> bool:
        if printer is None:
            return True
        c = centerline(points[first:last + 2], curvature[first:last + 1])
        room = sorted(printer.build_volume)[-2:]  # the two largest sides of the build volume
        for a in np.radians(np.arange(0.0, 180.0, 2.0)):
            u = c @ np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
            w, h = np.ptp(u, axis=0) + height
            if (w <= room[0] and h <= room[1]) or (w <= room[1] and h <= room[0]):
                return True
        return False

    for run in runs:
        first = run[0]
        while first <= run[-1]:
            last = first  # joints first..last fuse rods first..last + 1
            while last + 1 <= run[-1] and fits(first, last + 2):
                last += 1
            if fits(first, last + 1):
                pieces.append((first, last + 1))
            else:
                too_big.append((first, last + 1))
            first = last + 1
    return pieces, too_big


def count_for(curve: np.ndarray, catalog: Catalog, pf: PrintedFamily, rods: int, *, stops_allowed: bool = True,
              same_shell: bool = False, **kw):
    """A plan with exactly ``rods`` rods, or None: the preferred length is set so that the
    curve takes that many (then nudged); ``kw`` as :func:`plan_printed`'s."""
    from optimize.chain.curves import resample

    c = resample(np.asarray(curve, float), 2000)
    total = float(np.sum(np.hypot(*np.diff(c, axis=0).T)))
    r = pf.family.ranges
    assert r is not None
    shell_error = None
    for k in (0.0, 0.25, -0.25, 0.5, -0.5, 0.75, -0.75):
        pref = float(np.clip(total / (rods + k), *r.length))
        try:
            p = plan_printed(curve, catalog, pf, preferred_length=pref, stops_allowed=stops_allowed,
                             same_shell=same_shell, **kw)
        except ShellError as err:
            shell_error = err
            continue
        except ValueError:
            continue
        if len(p.rods) == rods:
            return p
    if shell_error is not None:
        raise ShellError(f"{rods} rods of one length do not lay on this target with every corner a joint; change "
                         "the rod count, or drop same_shell")
    return None


#: A plan whose stops and fused pieces leave fewer than this share of its joints free is laid
#: again on longer rods (:func:`freest`).
FREE_SHARE = 0.5

#: ... and a plan on longer rods is kept only where its rods follow the curve within this share
#: of the tolerance (the rest left for the chain as built and as printed).
FREER_FIT = 0.75

#: The longer rods :func:`freest` tries, as multiples of the first plan's mean length.
LONGER = (1.25, 1.5, 1.75, 2.0, 2.5)

#: A longer plan's chain, released this far off its shape (rad, every hinge, closed onto B)
#: from :data:`RELEASES` seeded starts without friction, must come back within
#: :data:`RETURN_TOL` of the target's size (:func:`returns`).
RELEASE = 0.05
RELEASES = 2
RETURN_TOL = 1e-3


def free_share(p: PrintedPlan) -> float:
    """The share of a plan's joints that hang freely (no stop, not fused)."""
    n = len(p.rods) - 1
    if n < 1:
        return 1.0
    held = set(p.stops) | {j for a, b in p.fused for j in range(a, b)}
    return 1.0 - len(held) / n


def returns(p: PrintedPlan, size: float) -> bool:
    """Whether the plan's checked chain, released :data:`RELEASE` rad off its shape without
    friction and let settle in MuJoCo (:func:`rodcad.design.tapping.tap_chain`, no taps), comes
    back to its shape from every one of :data:`RELEASES` seeded starts: the static check
    (solver, multi-start) finds the design stable and alone; this asks the dynamics the same
    question from nearby, as a chain let go by a hand."""
    from rodcad.design.tapping import tap_chain

    if p.verified is None or p.verified[1].equilibrium is None:
        return False
    masses, v = p.verified
    pr = p.problem
    for seed in range(RELEASES):
        try:
            t = tap_chain(pr.lengths, masses, pr.target[0], pr.target[-1], design_angles=v.equilibrium.angles,
                          capacity=np.zeros(len(pr.lengths) + 1), com=pr.com, limits=pr.limits,
                          end_limits=pr.end_limits, g=pr.g, release=RELEASE, n_taps=0, seed=seed)
        except (ValueError, FloatingPointError):
            return False
        if not t.converged or float(t.deviation[0]) > RETURN_TOL * size:
            return False
    return True


def freest(curve: np.ndarray, catalog: Catalog, pf: PrintedFamily, plan: PrintedPlan, *, tolerance: float,
           **kw) -> PrintedPlan:
    """The plan on the longest rods that follow the curve (``plan``) or, where it leaves fewer
    than :data:`FREE_SHARE` of its joints free, one on longer rods that keeps more free (the
    physics' advice: keep as many joints free as the shape allows; a hanging chain, not a
    sculpture).

    Longer rods: :data:`LONGER` times the plan's mean length (within the family's range), tried
    from the longest (the quickest to plan, and the freest): going shorter while a plan keeps at
    least as many free (at :data:`FREE_SHARE` or more, while it keeps that share), it stops at
    the first that keeps fewer; so the plan taken is the most faithful of the freest. A longer
    plan counts only where the solver accepted it (on target, stable, nothing lower), its rods'
    centrelines follow the curve within :data:`FREER_FIT` x ``tolerance`` of the target's size,
    and its chain comes back to its shape when released near it (:func:`returns`). ``kw`` as
    :func:`plan_printed`'s."""
    from rodcad.design.fit import curve_fit
    from rodcad.design.shell import curve_size

    share = free_share(plan)
    if share >= FREE_SHARE or len(plan.rods) < 3:
        return plan
    mean = float(np.mean(plan.problem.lengths))
    top = float(pf.family.ranges.length[1])
    size = curve_size(curve)
    best, best_share = None, share
    seen = {len(plan.rods)}
    for length in sorted({min(top, f * mean) for f in LONGER}, reverse=True):
        if length <= 1.05 * mean:
            continue
        try:
            layout = _layout(curve, pf.family.ranges, length, bool(kw.get("same_shell")))
            if layout[0].lengths.size in seen:
                continue  # the same rods as a length already tried
            p = plan_printed(curve, catalog, pf, preferred_length=length, layout=layout, **kw)
        except ValueError:
            continue
        seen.add(len(p.rods))
        v = p.verified[1] if p.verified is not None else None
        if v is None or not v.on_target or v.lower or p.unmet:
            continue
        if curve_fit(curve, p.discretization.points, [r.curvature for r in p.rods]) > FREER_FIT * tolerance:
            continue
        s = free_share(p)
        if best is not None and s < min(best_share, FREE_SHARE) - 1e-9:
            break  # shorter rods keep fewer free (or fall below half) from here on
        if s <= share + 1e-9 or not returns(p, size):
            continue
        best, best_share = p, s  # as free as the best so far, on shorter rods: more faithful
    if best is None:
        return plan
    best.notes.append(f"rods of about {np.mean(best.problem.lengths):.0f} mm keep {100 * best_share:.0f} % of "
                      f"the joints free (the longest rods that follow the curve, {mean:.0f} mm, {100 * share:.0f} "
                      "%): a hanging chain, not a rigid one")
    return best


def rods_of(plans: Sequence) -> list[RodType]:
    """The rods made to order of some chain plans (in order, each name once)."""
    out: dict[str, RodType] = {}
    for p in plans:
        for t in p.rods:
            out.setdefault(t.name, t)
    return list(out.values())
