"""A net's masses designed and checked: the mass design on the planned rods and hubs, the
exact equilibrium's verdict and the fit.

:func:`design_net_plan` turns the hubs' sockets (:mod:`rodcad.design.net.hubs`), narrows the
rods' mass bounds to what they can be built at, designs the masses with
:func:`optimize.design_net` (exact where the bounds allow, else the best fit within them,
refined through the solver, with the reason), solves the designed net from the target with a
multi-start, and measures the fit: the largest distance of a simulated node or pivot from its
target over the net's size (straight rods: their centrelines are no farther apart than their
ends).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from dataclasses import dataclass, field

import numpy as np
from threadpoolctl import threadpool_limits

from optimize import NetDesign, design_net
from rodcad.catalog.net.node import socket_centres
from rodcad.design.fit import DEFAULT_TOLERANCE
from rodcad.design.net.cones import widest_swing_limits
from rodcad.design.net.hubs import buildable_bounds, orient_sockets
from rodcad.design.net.imbalance import imbalance
from rodcad.design.net.plan import NetPlan
from rodcad.design.net.pushing import held_rods

__all__ = ["BUCKLING_SAFETY", "FULL_STARTS_NODES", "NET_STARTS", "NetCheck", "SLACK", "design_net_plan", "net_starts",
           "rank", "settle_com", "with_multistart"]


#: After the rods' bounds are narrowed to buildable masses, the sockets are turned again
#: only where the first turning brought the statics this close (over the force scale).
ORIENT_USEFUL = 1e-4

#: A rod's pivot-to-pivot length may leave the catalog's window by this much (mm): round-off
#: of the sockets' turning, far below a print's resolution.
LENGTH_TOL = 1e-6

#: The statics' masses are refined through the solver only where they hang further off
#: their target than this share of its size.
REFINE_ABOVE = 1e-6

#: Above this many nodes, a net whose statics stay far from balancing (no masses balance
#: it) keeps the statics' best fit without the refinement through the solver.
FULL_REFINE_NODES = 100

#: A rod whose force is within this share of the net's largest tension hangs slack: neither
#: pulling nor pushing to speak of (a rigid rod takes it either way).
SLACK = 1e-3

#: A rod that pushes keeps under its buckling load divided by this (a printed part's modulus
#: and straightness vary; Euler's load is an upper bound for a rod that is not quite straight).
BUCKLING_SAFETY = 5.0

#: A bent net's masses and centres of mass are consistent when the centres of mass move less
#: than this share of the net's size in a round (:func:`settle_com`); at most COM_ROUNDS rounds.
COM_TOL = 1e-12
COM_ROUNDS = 30
#: The designed masses' own centres of mass differ from those designed with by more than this
#: share of the size (the refinement moved the masses): the net is solved again with them.
COM_RECHECK = 1e-9

#: Starts of the multi-start that looks for other stable shapes of a designed net (up to
#: :data:`FULL_STARTS_NODES` nodes; fewer beyond, see :func:`net_starts`).
NET_STARTS = 8
FULL_STARTS_NODES = 50


def net_starts(n: int) -> int:
    """The multi-start's starts for a net of ``n`` nodes: 8 up to 50 nodes, then 400 / n (at
    least 2). A start from a perturbed shape costs a restoration and tens of Newton steps (about
    2 s for a 200-node net of hubs), so a 200-node design keeps within 10 s."""
    return NET_STARTS if n <= FULL_STARTS_NODES else max(2, int(NET_STARTS * FULL_STARTS_NODES / n))


@dataclass
class NetCheck:
    """A designed net, its exact equilibrium and how well it hangs on its target.

    Attributes:
        plan: the rods and hardware.
        design: optimize's design (masses, statics verdict, equilibrium with alternatives).
        masses: (m,) the designed rod masses (g).
        error_mm: largest distance of a simulated node or pivot from its target (mm).
        rel_size: that over the net's size.
        node_error: (n,) each node's distance from its target (mm).
        tolerance: the figure aimed at (design's tolerance or the default 1 %).
        sockets: (m, 2, 3) where each rod's socket is printed (hub frame, mm): its pivot
            moved ``clearance / 2`` against the rod's pull (rodcad.catalog.net.node).
        swing_deg: (m, 2) each rod's turn from its socket's axis at the equilibrium (deg).
        time_s: wall time of the design.
        notes: things the user should know.
        why: when no masses at all balance the target, where and why (else '').
        planned: the plan as it was given to :func:`design_net_plan` (before its sockets were
            turned and its bounds narrowed), or None.
        choices: the planner's choices around this design, in words (also in ``notes``).
        solved_with: the arguments the equilibrium was solved with (:func:`optimize.solve_net`'s,
            less its multi-start's), for :func:`with_multistart`.
        others_at: where in ``notes`` the multi-start's other shapes are told.
        falls_to: where the target is an unstable equilibrium of the designed net, how far off
            it (over its size) the stable shape lies that the net falls to from it, or None.
    """

    plan: NetPlan
    design: NetDesign
    masses: np.ndarray
    error_mm: float
    rel_size: float
    node_error: np.ndarray
    tolerance: float
    sockets: np.ndarray
    swing_deg: np.ndarray
    time_s: float
    notes: list[str] = field(default_factory=list)
    why: str = ""
    planned: NetPlan | None = None
    choices: list[str] = field(default_factory=list)
    solved_with: dict | None = field(default=None, repr=False)
    others_at: int | None = field(default=None, repr=False)
    falls_to: float | None = None

    def chose(self, text: str) -> None:
        """A choice the planner made around this design (its joints hung, edges made one rod,
        hubs larger, cones wider), in words: a note that a design made again from this one's
        plan keeps (:meth:`carry`)."""
        self.choices.append(text)
        self.notes.append(text)

    def carry(self, earlier: "NetCheck") -> "NetCheck":
        """This check with ``earlier``'s choices (it was designed from ``earlier``'s plan)."""
        for text in earlier.choices:
            if text not in self.choices:
                self.chose(text)
        return self

    @property
    def equilibrium(self):
        return self.design.equilibrium

    @property
    def compressed(self) -> np.ndarray:
        """Rods that push at the equilibrium by more than :data:`SLACK` of the largest tension,
        less those between two anchored nodes (their force is the anchors' business)."""
        t = self.plan.target
        T = self.equilibrium.tensions
        if not np.all(np.isfinite(T)):
            return np.zeros(0, int)
        c = np.flatnonzero(T < -SLACK * float(np.max(np.abs(T), initial=0.0)))
        return c[~t.anchored_mask[t.edges[c]].all(axis=1)] if c.size else c

    @property
    def slack(self) -> np.ndarray:
        """Rods whose force is within :data:`SLACK` of the largest tension (they hang slack: a
        rung across a strip, a designed zero)."""
        T = self.equilibrium.tensions
        if not np.all(np.isfinite(T)):
            return np.zeros(0, int)
        return np.flatnonzero(np.abs(T) <= SLACK * float(np.max(np.abs(T), initial=0.0)))

    @property
    def unheld(self) -> np.ndarray:
        """Rods that push where the hardware does not hold them (indices): with ``net.compression``
        unset, a rod may push if it is one rigid rod between two hubs (their ball sockets hold its
        balls either way; a ball joint between two pushing rods folds:
        :func:`rodcad.design.net.pushing.held_rods`) and pushes less than
        1 / :data:`BUCKLING_SAFETY` of its buckling load
        (:meth:`rodcad.catalog.net.node.NodeHardware.buckling_load`); true: every rod may push;
        false, or point nodes: none may."""
        c = self.compressed
        t, hw = self.plan.target, self.plan.hardware
        if t.compression or not c.size:
            return np.zeros(0, int)
        if t.compression is False or not hw.is_hub:
            return c
        T = self.equilibrium.tensions
        loose = ~held_rods(self.plan)[c]
        load = np.array([hw.buckling_load(float(L)) for L in self.plan.lengths[c]])
        return c[loose | (-T[c] * BUCKLING_SAFETY > load)]

    @property
    def in_tension(self) -> bool:
        """No rod pushes where the hardware does not hold it (:attr:`unheld`)."""
        return self.unheld.size == 0

    @property
    def meets_tolerance(self) -> bool:
        return bool(self.equilibrium.success and self.equilibrium.stable and self.rel_size <= self.tolerance)

    @property
    def out_of_window(self) -> np.ndarray:
        """Rods whose pivot-to-pivot length (a spliced rod's per piece), with the hubs' sockets
        turned, left the lengths the catalog prints (indices)."""
        lo, hi = self.plan.length_range
        L = self.plan.piece_lengths
        return np.flatnonzero((L < lo - LENGTH_TOL) | (L > hi + LENGTH_TOL))

    @property
    def ok(self) -> bool:
        """Hangs within the tolerance, stable, in tension (unless allowed), rods within their
        swing and within the lengths the catalog prints."""
        return (self.meets_tolerance and self.in_tension and self.out_of_window.size == 0
                and not self.over_swing.size and not self.clashes)

    @functools.cached_property
    def clashes(self) -> list[tuple[int, float, float]]:
        """Hubs whose sockets, as turned, are closer than their walls need: (node, angle, need)
        (:func:`rodcad.design.net.spacing.socket_clashes`)."""
        from rodcad.design.net.spacing import socket_clashes

        return socket_clashes(self.plan)

    @property
    def over_swing(self) -> np.ndarray:
        """(k, 2) the rod ends (rod, end) turning further than their socket lets them."""
        return np.argwhere(self.swing_deg > self.plan.end_swing_limits)

    def limit(self) -> str:
        """One line: what keeps the net off its target and what would reach it."""
        pct = (f"hangs {100 * self.rel_size:.3g} % of its size off its target (tolerance "
               f"{100 * self.tolerance:.3g} %)")
        eq, st = self.equilibrium, self.design.statics
        if not eq.success:
            if self.why:  # (why the masses could not make the target one: what the user can change, first)
                return (f"cannot rest on its target (tolerance {100 * self.tolerance:.3g} %): {self.why} With the "
                        f"best fit's masses the net moves away from the target, and the solver did not find where "
                        f"it comes to rest ({eq.message})")
            return (f"could not be solved (tolerance {100 * self.tolerance:.3g} %): the solver found no equilibrium "
                    f"of the designed net ({eq.message})")
        if not eq.stable:
            falls = ("" if self.falls_to is None else
                     f" (from it the net falls to a stable shape {100 * self.falls_to:.3g} % of its size off it)")
            return f"{pct}: the target is an equilibrium of the designed net, but not a stable one{falls}" + (
                f": {self.why}" if self.why else "")
        if not self.meets_tolerance and self.why:
            return f"{pct}: {self.why}"
        if not self.meets_tolerance:
            how = " (refined through the solver)" if self.design.refined else ""
            return f"{pct}: {st.message} The best fit within the rods' mass ranges{how} is the closest; a catalog " \
                   "with a wider mass range, more anchored nodes or a target closer to a hanging shape would reach it"
        if not self.in_tension:
            c = self.unheld
            why = ("" if self.plan.target.compression is False else
                   ": point nodes hold no push" if not self.plan.hardware.is_hub else
                   ": at two-rod joints, which fold, or beyond a fifth of their buckling load")
            return f"{pct}, but rods {c[:8].tolist()} push (compression){why}; allow it with net.compression: " \
                   "true, or anchor more nodes"
        if self.out_of_window.size:
            k = int(self.out_of_window[0])
            lo, hi = self.plan.length_range
            return (f"{pct}, but with the hubs' sockets turned {self.out_of_window.size} rod(s) leave the "
                    f"{lo:g}-{hi:g} mm the catalog prints (rod {k}: {self.plan.piece_lengths[k]:.4g} mm{' a piece' if self.plan.rod_pieces[k] > 1 else ''}); a catalog "
                    "with that length, or the net drawn with shorter edges there, would build it")
        if self.clashes:
            k, ang, need = self.clashes[0]
            return (f"{pct}, but {len(self.clashes)} hub(s)' sockets, turned to balance them, come closer than their "
                    f"walls allow (node {k}: {ang:.3g} deg apart, its {self.plan.hub(k).min_wall:g} mm wall needs "
                    f"{need:.3g}); larger hubs (node.pivot_radius) would hold them")
        over = self.over_swing
        worst = float(np.max(self.swing_deg[over[:, 0], over[:, 1]]))
        return f"{pct}, but rod {over[0][0]} turns {self.swing_deg[tuple(over[0])]:.3g} deg in its socket, more " \
               f"than the {self.plan.end_swing_limits[tuple(over[0])]:.3g} deg the hub allows ({len(over)} rod " \
               f"end(s), up to {worst:.3g} deg); {_wider_cone(self.plan.hardware, worst)}"


def _wider_cone(hw, turn: float) -> str:
    """The socket hardware that lets a rod turn ``turn`` deg, in words: the cone it needs (the
    neck's clearance added), if one still holds the ball (its opening 0.2 mm narrower than the
    ball, :meth:`rodcad.catalog.net.node.NodeHardware.problems`), else a thinner neck."""
    rs = hw.socket_radius
    neck = math.degrees(math.asin(min(1.0, (hw.neck / 2) / rs)))
    need = turn + neck
    hold = math.degrees(math.asin(min(1.0, (hw.ball / 2 - 0.1) / rs)))
    lo, hi = hw.cone_limits
    if need <= hi:  # (the catalog's range reaches it: the hubs' sockets left no room for it)
        return (f"a cone of {math.ceil(need * 10) / 10:g} deg would let this design's rods turn so far, but the hubs "
                f"where they turn so far keep less than node.min_wall between their sockets' openings with it "
                f"(the catalog's cones {lo:g}-{hi:g} deg): larger hubs (node.pivot_radius) or the net drawn with its "
                "rods meeting nearer their hubs' lines would")
    if need <= hold:
        return (f"a node.cone_deg of {math.ceil(need * 10) / 10:g} (the catalog's "
                f"{hw.cone_deg:g}" + (f"-{hi:g}" if hi > lo else "") + f"; at most {hold:.3g} "
                f"still holds the {hw.ball:g} mm ball) would let this design's rods turn so far (a wider cone lightens "
                "the hubs, and the design changes with it)")
    return (f"no cone that still holds the {hw.ball:g} mm ball lets it (at most {hold:.3g} deg): a thinner node.neck "
            f"than {hw.neck:g} mm, or the net drawn with its rods meeting nearer their hubs' lines, would")


def design_net_plan(plan: NetPlan, *, g: float = 9.81, seed: int = 0, tolerance: float | None = None,
                    n_starts: int | None = None, note=None, fall: bool = False) -> NetCheck:
    """Masses for the planned net, its exact equilibrium and its fit.

    Args:
        plan: :func:`rodcad.design.net.plan.plan_net`'s rods and hardware.
        g: gravitational acceleration (m/s^2).
        seed: the multi-start's seed.
        tolerance: largest acceptable error over the net's size (None: 1 %).
        n_starts: the multi-start's starts (None: :func:`net_starts`).
        note: called with a line of text at each stage of the design (progress), or None.
        fall: False: the check asks whether the target is a stable equilibrium of the designed
            net (an unstable one is reported as such, for the planner to mend); True: where the
            net falls to from an unstable target (:func:`optimize.solve_net`'s
            ``leave_unstable``), judged against the tolerance like any other shape.
    """
    # one BLAS thread: the design's dense steps are small and its vector operations many (an
    # iterative least squares' norms); on a busy 2-core machine OpenBLAS's spinning threads made
    # a 17,000-element dot product take 14 ms instead of 0.02 ms
    t0 = time.perf_counter()

    def stage(text: str) -> None:
        if note is not None:
            note(f"{text} ({time.perf_counter() - t0:.1f} s)")

    with threadpool_limits(limits=1, user_api="blas"):
        return _design_plan(plan, g=g, seed=seed, tolerance=tolerance, n_starts=n_starts, note=stage, fall=fall)


def rank(check: NetCheck) -> tuple:
    """Orders designs, better greater: within the tolerance, then a stable equilibrium, then the nearer fit."""
    eq = check.equilibrium
    return (check.ok, bool(eq.success and eq.stable), -check.rel_size)


def _design_plan(plan: NetPlan, *, g: float, seed: int, tolerance: float | None, n_starts: int | None,
                 note, fall: bool) -> NetCheck:
    t0 = time.perf_counter()
    planned = plan
    n_starts = net_starts(plan.target.n) if n_starts is None else int(n_starts)
    lines = plan.pivots.copy()
    hub = plan.hardware.is_hub
    note("statics at the target" + (": the hubs' sockets turned to balance" if hub else ""))
    plan, rounds, residual = orient_sockets(plan, g=g)
    note("the rods' mass bounds narrowed to masses they can be built at")
    plan, snapped = buildable_bounds(plan, g)
    if snapped and not residual > ORIENT_USEFUL:  # (where the forces themselves balance)
        note(f"{snapped} rod(s) narrowed: the sockets turned again for their bounds")
        plan, more, _ = orient_sockets(plan, g=g)
        rounds += more
    turn = 0.0
    if plan.hardware.is_hub:
        cos = np.sum(lines * plan.pivots, axis=2) / plan.end_pivot ** 2
        turn = float(np.degrees(np.arccos(np.clip(cos, -1, 1))).max())
    t = plan.target
    com_rounds = 0
    if plan.bent:
        plan, com_rounds = settle_com(plan, g=g)
    fn, fp, fit_ends = fit_of(plan)
    kw = dict(node_masses=plan.node_masses, node_com=plan.node_com, pivots=plan.pivots,
              allow_compression=plan.may_push, g=g, com=plan.statics_com, fit_nodes=fn, fit_points=fp,
              fit_ends=fit_ends)
    # a big net whose statics are far from balancing: the refinement gains about 1 % at seconds
    # a step (dense derivatives and a linear program on hundreds of masses), so the statics' best fit
    # stays; otherwise the statics' masses, solved once from the target, are refined through
    # the solver only where they hang measurably off (above REFINE_ABOVE of the size)
    refine = not (t.n > FULL_REFINE_NODES and residual > ORIENT_USEFUL)
    probe = None
    if not residual > ORIENT_USEFUL:  # (NaN for point nodes: probe)
        note("the masses designed and the net solved from the target")
        probe = design_net(t.positions, t.edges, plan.lengths, plan.bounds, t.anchored, n_starts=1, refine=False,
                           callback=note, leave_unstable=fall, **kw)
        refine = not (probe.equilibrium.success and probe.equilibrium.stable and probe.rel_error <= REFINE_ABOVE)
    note("the masses designed" + (", refined through the solver" if refine else "")
         + (f", the net solved with a multi-start of {n_starts} start(s)" if n_starts > 1 else
            ", the net solved from the target"))
    if probe is not None and not refine and n_starts <= 1:
        design = probe  # (the same solve from the target, the same statics)
    else:
        design = design_net(t.positions, t.edges, plan.lengths, plan.bounds, t.anchored, n_starts=n_starts, seed=seed,
                            refine=refine, callback=note, statics=probe.statics if probe is not None else None,
                            leave_unstable=fall, swing_limits=widest_swing_limits(plan) if hub and refine else None,
                            **kw)
    recheck = False
    if plan.bent:
        final = plan.rod_com(design.masses)
        if np.max(np.abs(final - plan.com)) > COM_RECHECK * t.size:
            # the refinement moved the masses, and with them the bent rods' centres of mass: the
            # verdict is on the rods as they will be built
            from optimize import solve_net

            eq0 = design.equilibrium
            res = solve_net(t.positions, t.edges, plan.lengths, design.masses, t.anchored, node_masses=plan.node_masses,
                            node_com=plan.node_com, pivots=plan.pivots, com=final, g=g, n_starts=n_starts, seed=seed,
                            node_rotations0=eq0.rotations if eq0.success else None, leave_unstable=fall)
            design = dataclasses.replace(design, equilibrium=res)
            plan = dataclasses.replace(plan, com=final)
            recheck = True
    solved_with = dict(node_positions0=t.positions, edges=t.edges, lengths=plan.lengths, masses=design.masses,
                       anchored=t.anchored, node_masses=plan.node_masses, node_com=plan.node_com, pivots=plan.pivots,
                       com=plan.com if recheck else plan.statics_com, g=g,
                       node_rotations0=eq0.rotations if recheck and eq0.success else None)
    eq = design.equilibrium
    size = t.size
    if eq.success:
        # against the net as drawn: a planner's joint against the drawn surface or edge, a
        # merged hub against each node drawn (rodcad.design.net.joints)
        node_err = np.zeros(t.n)
        np.maximum.at(node_err, fn, np.linalg.norm(eq.positions[fn] - fp, axis=1))
        end_err = np.linalg.norm(eq.ends - fit_ends, axis=2)
        err = float(max(node_err.max(), end_err.max()))
    else:
        node_err = np.full(t.n, np.inf)
        err = float("inf")
    # sockets: each pivot moved against the force its rod pulls with, in the hub's frame
    sockets = plan.pivots.copy()
    swing = np.zeros((t.m, 2))
    hw = plan.hardware
    if eq.success and hw.is_hub:
        for k in (0, 1):
            node = t.edges[:, k]
            R = eq.rotations[node]
            f_body = np.einsum("mba,mb->ma", R, eq.rod_forces[:, k])
            sockets[:, k] = socket_centres(plan.pivots[:, k], f_body, hw.clearance)
            axis = np.einsum("mab,mb->ma", R, plan.pivots[:, k])
            axis /= np.linalg.norm(axis, axis=1, keepdims=True)
            rod = eq.ends[:, 1 - k] - eq.ends[:, k]
            rod /= np.linalg.norm(rod, axis=1, keepdims=True)
            swing[:, k] = np.degrees(np.arccos(np.clip(np.sum(axis * rod, axis=1), -1, 1)))
    tol = DEFAULT_TOLERANCE if tolerance is None else float(tolerance)
    notes = [design.statics.message]
    why = ""
    if not design.statics.exact and np.all(~np.isfinite(design.statics.beyond)) and design.statics.residual > 1e-4:
        why = imbalance(plan, design, g, lines)
        notes.append(why)
    if plan.pushing is not None:
        notes.append(f"No masses balance this target with every rod in tension (some rods must push, as a bowl's "
                     f"hoops do below the rim it hangs from): the {int(plan.pushing.sum())} rigid rod(s) between hubs, "
                     "whose ball sockets hold them either way, may push (the check holds each to a fifth of its "
                     f"buckling load); {_pushing(eq)} of them push in the design.")
    if snapped:
        notes.append(f"{snapped} rod(s) would have weighed what neither their steel balls nor a cavity make (a short "
                     "rod has little room beside its balls): their mass bounds were narrowed to the nearest range "
                     "they can be built at and the masses designed again.")
    if turn > 0:
        notes.append(f"The hubs' sockets are turned up to {turn:.3g} deg off the lines between the node points "
                     f"(printed so; {rounds} round(s)), so that every hub balances at the target: a socket on the "
                     "line would put its rod's weight share off the hub's centre and turn it.")
    if plan.bent:
        bent = int(np.count_nonzero(t.bends > 0))
        notes.append(f"{bent} rod(s) are printed bent; each hangs with its bow below its chord, in the vertical "
                     "plane through it (a rod on ball joints turns freely about its chord, so its centre of mass "
                     "hangs as low as it can), and its centre of mass off the chord enters the design "
                     f"({com_rounds} round(s) of masses and centres of mass to a fixed point)"
                     + ("; re-solved with the centres of mass of the refined masses." if recheck else "."))
    if design.refined:
        notes.append(f"The masses were refined through the solver from the statics' best fit "
                     f"({design.info.get('fit_error', float('nan')):.4g} mm -> "
                     f"{design.info.get('refined_error', float('nan')):.4g} mm).")
    others_at = len(notes)
    if eq.alternatives:
        notes.append(_others(eq))
    if t.dropped:
        notes.append(f"{t.dropped} rod(s) between two anchored nodes were left out (the anchors hold both ends).")
    masses = np.asarray(design.masses, float)
    return NetCheck(plan, design, masses, err, err / size if size > 0 else float("inf"), node_err, tol, sockets,
                    swing, time.perf_counter() - t0, notes, why, planned, solved_with=solved_with,
                    others_at=others_at)


def _pushing(eq) -> int:
    """How many rods push in the equilibrium ``eq`` (beyond :data:`SLACK` of its largest force)."""
    T = eq.tensions
    if not eq.success or not np.all(np.isfinite(T)):
        return 0
    return int(np.count_nonzero(T < -SLACK * float(np.max(np.abs(T), initial=0.0))))


def fit_of(plan: NetPlan) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What a net's fit measures against the net as drawn: (nodes, the points they are measured
    against, (m, 2, 3) where the rods' pivots are measured against). A planner's joint against
    the drawn surface or edge, a merged hub against each node drawn
    (:attr:`rodcad.design.net.target.NetTarget.fit_pairs`); each rod's pivots where the plan puts
    them, moved with their node's point."""
    t = plan.target
    fn, fp = t.fit_pairs
    shift = np.zeros((t.n, 3))
    np.add.at(shift, fn, fp - t.positions[fn])
    shift /= np.maximum(np.bincount(fn, minlength=t.n), 1)[:, None]
    return fn, fp, plan.target_ends + shift[t.edges]


def _others(eq) -> str:
    return (f"The multi-start ({eq.n_starts} starts) found {len(eq.alternatives)} other stable shape(s)"
            + (", one hanging lower than the design's: a push may move the net there." if eq.lower else
               ", none lower than the design's."))


def with_multistart(check: NetCheck, n_starts: int | None = None, *, seed: int = 0, note=None) -> NetCheck:
    """``check`` with the multi-start that looks for other stable shapes of its designed net,
    for a check designed from its target alone (``design_net_plan(..., n_starts=1)``): the
    same as designing it with ``n_starts`` (:func:`optimize.more_starts`). The planner designs a
    drawn net several ways and keeps one; only that one's other shapes are reported, so only
    its multi-start runs. A check already made with as many starts, or with no equilibrium,
    comes back as it was.

    Args:
        check: the kept design.
        n_starts: the multi-start's starts (None: :func:`net_starts`).
        seed: its seed (the design's).
        note: progress, as for :func:`design_net_plan`.
    """
    from optimize import more_starts
    from optimize.net.design import multistart_text

    n = net_starts(check.plan.target.n) if n_starts is None else int(n_starts)
    eq = check.equilibrium
    if n <= eq.n_starts or not eq.success or check.solved_with is None:
        return check
    t0 = time.perf_counter()
    with threadpool_limits(limits=1, user_api="blas"):
        res = more_starts(eq, n_starts=n, seed=seed, callback=note, **check.solved_with)
    message = check.design.message + multistart_text(res)
    out = dataclasses.replace(check, design=dataclasses.replace(check.design, equilibrium=res, message=message),
                              notes=list(check.notes), choices=list(check.choices),
                              time_s=check.time_s + time.perf_counter() - t0)
    if res.alternatives:
        out.notes.insert(len(out.notes) if check.others_at is None else check.others_at, _others(res))
    return out


def settle_com(plan: NetPlan, *, g: float = 9.81, rounds: int = COM_ROUNDS) -> tuple[NetPlan, int]:
    """A bent net's masses and its rods' centres of mass made consistent: a bent rod's centre of
    mass moves with its fill (steel balls at mid-arc, the cavity beside them), so the statics'
    masses and the centres of mass they imply are iterated to a fixed point (the centres of
    mass move by fractions of a mm for grams: a few rounds). Returns (the plan with ``com``,
    rounds used)."""
    t = plan.target
    com = plan.statics_com
    used = 0
    for used in range(1, rounds + 1):
        st = plan.mass_design(g, com=com, explain=False)
        new = plan.rod_com(st.masses)
        change = float(np.max(np.abs(new - com)))
        com = new
        if change <= COM_TOL * t.size:
            break
    return dataclasses.replace(plan, com=com), used
