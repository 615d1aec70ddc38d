"""Planning and physics of a net design: rods and hardware for the target, their masses,
and the exact equilibrium's verdict.

:func:`plan_net` lays the catalog's node hardware on the target (a hub at every node, each
rod's pivot ``pivot_radius`` from the hub's centre along the rod's target direction; a point
node: the node itself), gives every rod its pivot-to-pivot length and its mass bounds
(:meth:`rodcad.catalog.node.NodeHardware.rod_numbers`) and every node its hub's mass and
centre of mass, and refuses (:class:`rodcad.errors.DesignLimit`, exit 1) rods the catalog
cannot print and nodes whose rods meet closer than the hub's sockets allow.

:func:`design_net_plan` designs the masses with :func:`optimize.design_net` (exact where the
bounds allow, else the best fit within them, refined through the solver, with the reason),
solves the designed net from the target with a multi-start, and measures the fit: the
largest distance of a simulated node or pivot from its target over the net's size (straight
rods: their centrelines are no farther apart than their ends).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from optimize import NetDesign, design_net, net_statics
from rodcad.catalog.node import NetRodNumbers, NodeHardware, socket_centres
from rodcad.design.fit import DEFAULT_TOLERANCE
from rodcad.design.net import NetTarget
from rodcad.errors import DesignLimit

__all__ = ["NET_STARTS", "NetCheck", "net_starts", "NetPlan", "design_net_plan", "length_range", "orient_sockets", "plan_net"]

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
class NetPlan:
    """Rods and hardware laid on a net's target.

    Attributes:
        target: the net's target.
        hardware: the catalog's node hardware.
        pivots: (m, 2, 3) each rod's pivot at its node i and j, from the node point (mm; the
            hub's frame, which is the world frame at the target).
        lengths: (m,) pivot-to-pivot lengths (mm).
        rods: each rod's numbers (solid mass, mass range, steel balls).
        bounds: (m, 2) mass bounds (g).
        node_masses: (n,) hub (or point part) masses (g).
        node_com: (n, 3) hubs' centres of mass from the node point (mm, hub frame).
        length_range: (min, max) rod lengths the catalog prints (mm).
        degree: (n,) rods at each node.
    """

    target: NetTarget
    hardware: NodeHardware
    pivots: np.ndarray
    lengths: np.ndarray
    rods: list[NetRodNumbers]
    bounds: np.ndarray
    node_masses: np.ndarray
    node_com: np.ndarray
    length_range: tuple[float, float]
    degree: np.ndarray

    @property
    def target_ends(self) -> np.ndarray:
        """(m, 2, 3) the rods' pivots at the target (mm)."""
        return self.target.positions[self.target.edges] + self.pivots


def length_range(catalog) -> tuple[float, float]:
    """The rod lengths a catalog prints for a net (mm): its first family printed to order's
    range, else the span of its rod types' lengths."""
    fams = catalog.printed_families
    if fams:
        return tuple(float(x) for x in fams[0].ranges.length)  # type: ignore[return-value]
    lengths = [t.length for t in catalog]
    return float(min(lengths)), float(max(lengths))


def plan_net(target: NetTarget, catalog) -> NetPlan:
    """Hardware, lengths, mass bounds and hub masses for a net's target.

    Raises:
        DesignLimit: rods shorter or longer than the catalog prints, or rods meeting at a
            node closer than its hub's sockets allow (every such rod and node named).
    """
    hw: NodeHardware = catalog.node
    pos, edges = target.positions, target.edges
    n, m = target.n, target.m
    d = pos[edges[:, 1]] - pos[edges[:, 0]]
    dist = np.linalg.norm(d, axis=1)
    u = d / dist[:, None]
    r = hw.pivot
    pivots = np.stack([r * u, -r * u], axis=1)
    lengths = dist - 2 * r
    lo, hi = length_range(catalog)
    lo_hw = max(lo, hw.shortest_rod())
    problems = []
    short = np.flatnonzero(lengths < lo_hw * (1 - 1e-9))
    long = np.flatnonzero(lengths > hi * (1 + 1e-9))
    extra = f" (node to node: {2 * r:g} mm more, the hubs)" if r else ""
    if short.size:
        problems.append(f"{short.size} rod(s) would be shorter than the {lo_hw:g} mm the catalog prints: "
                        f"rods {short[:8].tolist()} need {', '.join(f'{x:.4g}' for x in lengths[short[:8]])} mm "
                        f"pivot to pivot{extra}; use fewer cells or draw the net larger")
    if long.size:
        problems.append(f"{long.size} rod(s) would be longer than the {hi:g} mm the catalog prints: rods "
                        f"{long[:8].tolist()} need {', '.join(f'{x:.4g}' for x in lengths[long[:8]])} mm; use more "
                        "cells or draw the net smaller")
    degree = np.bincount(edges.ravel(), minlength=n)
    # directions of the rods at every node (from the node toward the rod's other end)
    dirs: list[list[np.ndarray]] = [[] for _ in range(n)]
    for e, (i, j) in enumerate(edges):
        dirs[i].append(u[e])
        dirs[j].append(-u[e])
    if hw.is_hub:
        need = hw.min_angle_deg
        worst = []
        for k in range(n):
            if len(dirs[k]) < 2:
                continue
            D = np.asarray(dirs[k])
            cos = np.clip(D @ D.T, -1, 1)
            np.fill_diagonal(cos, -1)
            ang = float(np.degrees(np.arccos(cos.max())))
            if ang < need - 1e-9:
                worst.append((ang, k))
        if worst:
            worst.sort()
            problems.append(f"at {len(worst)} node(s) rods meet closer than the hub's sockets allow ({need:.3g} deg): "
                            + ", ".join(f"node {k} at {a:.3g} deg" for a, k in worst[:6])
                            + "; a larger hub (node.diameter and node.pivot_radius) or a net with wider angles")
    if problems:
        raise DesignLimit("; ".join(problems))
    rods = [hw.rod_numbers(float(L)) for L in lengths]
    bounds = np.array([rn.mass_range for rn in rods], float)
    node_masses = np.zeros(n)
    node_com = np.zeros((n, 3))
    for k in range(n):
        mass, com = hw.hub_mass(np.asarray(dirs[k]).reshape(-1, 3))
        node_masses[k] = mass
        node_com[k] = com
    return NetPlan(target, hw, pivots, lengths, rods, bounds, node_masses, node_com, (lo_hw, hi), degree)


#: Rounds of :func:`orient_sockets` at most, and the pivot change (over the pivot radius) it stops at.
ORIENT_ROUNDS = 12
ORIENT_TOL = 1e-13
#: A statics residual (over the force scale) this small ends the rounds: the design's
#: refinement through the exact solver takes it to round-off.
ORIENT_FINE = 1e-7
#: Depth of the Anderson acceleration of :func:`orient_sockets`' fixed point.
ANDERSON = 5


def _rebuild(plan: NetPlan, pivots: np.ndarray) -> NetPlan:
    """The plan with new pivots: lengths, mass bounds and hub centres of mass follow."""
    t, hw = plan.target, plan.hardware
    ends = t.positions[t.edges] + pivots
    lengths = np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)
    rods = [hw.rod_numbers(float(L)) for L in lengths]
    node_com = np.zeros((t.n, 3))
    node_masses = plan.node_masses.copy()
    dirs: list[list[np.ndarray]] = [[] for _ in range(t.n)]
    for e, (i, j) in enumerate(t.edges):
        dirs[i].append(pivots[e, 0] / np.linalg.norm(pivots[e, 0]))
        dirs[j].append(pivots[e, 1] / np.linalg.norm(pivots[e, 1]))
    for k in range(t.n):
        node_masses[k], node_com[k] = hw.hub_mass(np.asarray(dirs[k]).reshape(-1, 3))
    return NetPlan(t, hw, pivots, lengths, rods, np.array([r.mass_range for r in rods], float), node_masses,
                   node_com, plan.length_range, plan.degree)


def orient_sockets(plan: NetPlan, *, g: float = 9.81) -> tuple[NetPlan, int]:
    """Hub sockets turned so that the hubs balance at the target, as printed to order.

    A socket on the line between two node points puts its rod's weight share off the hub's
    centre: the hub would turn and the net leave its target. Each free hub's sockets are
    instead turned (on the pivot sphere) toward the force its rod pulls with, the least
    turn that makes the moments about the hub's centre, its own weight's included, vanish;
    the rods' lengths follow. The forces come from the statics at the target, so the two
    are iterated to a fixed point: the nodes' forces balanced (exactly where the mass
    bounds allow, else their best fit), the sockets turned to cancel those forces' moments,
    the rods' directions updated; a few rounds, the turns being a few degrees. A point node
    has nothing to turn.

    Returns:
        (the plan with its pivots, lengths, bounds and hub centres of mass; rounds used).
    """
    from optimize import design_net_masses

    t, hw = plan.target, plan.hardware
    if not hw.is_hub:
        return plan, 0
    r = hw.pivot_radius
    free = ~t.anchored_mask
    axis = plan.pivots.copy()  # along the rods' lines between node points
    rounds = 0
    best, best_res, stall = plan, np.inf, 0
    xs: list[np.ndarray] = []
    gs: list[np.ndarray] = []
    for rounds in range(1, ORIENT_ROUNDS + 1):
        full = design_net_masses(t.positions, t.edges, plan.lengths, plan.bounds, t.anchored,
                                 node_masses=plan.node_masses, node_com=plan.node_com, pivots=plan.pivots,
                                 allow_compression=t.compression, g=g)
        if full.exact or full.residual <= ORIENT_FINE:
            return plan, rounds  # (this close, the refinement through the solver finishes it)
        st = design_net_masses(t.positions, t.edges, plan.lengths, plan.bounds, t.anchored,
                               node_masses=plan.node_masses, node_com=plan.node_com, pivots=plan.pivots,
                               allow_compression=t.compression, g=g, forces_only=True)
        if full.residual < 0.9 * best_res:
            best, best_res, stall = plan, full.residual, 0
        else:
            if full.residual < best_res:
                best, best_res = plan, full.residual
            stall += 0 if st.exact else 1
            if stall >= 2:  # the forces themselves do not balance: turning sockets will not reach it
                break
        ends = t.positions[t.edges] + plan.pivots
        u = ends[:, 1] - ends[:, 0]
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        share = _shares(st.masses, g)
        F = np.stack([st.tensions[:, None] * u, -st.tensions[:, None] * u], axis=1)
        F[:, :, 2] -= share
        new = plan.pivots.copy()
        for k in np.flatnonzero(free):
            at = [(e, c) for c in (0, 1) for e in np.flatnonzero(t.edges[:, c] == k)]
            if len(at) < 2:
                continue
            f = np.array([F[e, c] for e, c in at])
            norm = np.linalg.norm(f, axis=1)
            a = np.array([axis[e, c] for e, c in at])
            cw = np.cross(plan.node_com[k], [0.0, 0.0, -g * plan.node_masses[k]])
            A = np.hstack([-_skew(fq) for fq in f])
            AAt = A @ A.T
            for _ in range(6):  # the least turn from the rods' lines that cancels the moments
                M = cw + np.sum(np.cross(a, f), axis=0)
                if np.max(np.abs(M)) <= 1e-15 * float(norm.max()) * r:
                    break
                a = a + (A.T @ np.linalg.lstsq(AAt, -M, rcond=None)[0]).reshape(-1, 3)
                a *= r / np.linalg.norm(a, axis=1, keepdims=True)
            for q, (e, c) in enumerate(at):
                new[e, c] = a[q]
        change = float(np.max(np.abs(new - plan.pivots))) / r
        if change <= ORIENT_TOL:
            plan = _rebuild(plan, new)
            break
        # Anderson acceleration of the fixed point (the plain iteration converges linearly)
        xs.append(plan.pivots.ravel().copy())
        gs.append(new.ravel().copy())
        del xs[:-ANDERSON], gs[:-ANDERSON]
        nxt = new
        if len(xs) >= 2:
            fs = np.array(gs) - np.array(xs)
            dF = np.diff(fs, axis=0).T
            dG = np.diff(np.array(gs), axis=0).T
            gamma = np.linalg.lstsq(dF, fs[-1], rcond=None)[0]
            nxt = (gs[-1] - dG @ gamma).reshape(new.shape)
            on = free[t.edges]
            nxt[on] *= r / np.linalg.norm(nxt[on], axis=1, keepdims=True)
            nxt[~on] = new[~on]
        plan = _rebuild(plan, nxt)
    return best, rounds


def _shares(masses: np.ndarray, g: float) -> np.ndarray:
    """(m, 2) each straight symmetric rod's weight at its two pivots (lever rule: half each)."""
    return np.column_stack([0.5 * g * masses, 0.5 * g * masses])


def _skew(a: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


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
            moved ``clearance / 2`` against the rod's pull (rodcad.catalog.node).
        swing_deg: (m, 2) each rod's turn from its socket's axis at the equilibrium (deg).
        time_s: wall time of the design.
        notes: things the user should know.
        why: when no masses at all balance the target, where and why (else '').
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

    @property
    def equilibrium(self):
        return self.design.equilibrium

    @property
    def compressed(self) -> np.ndarray:
        """Rods in compression at the equilibrium, less those between two anchored nodes
        (their tension is the anchors' business: nothing in the net sets it)."""
        t = self.plan.target
        c = self.equilibrium.compressed
        return c[~t.anchored_mask[t.edges[c]].all(axis=1)] if c.size else c

    @property
    def in_tension(self) -> bool:
        return self.plan.target.compression or self.compressed.size == 0

    @property
    def meets_tolerance(self) -> bool:
        return bool(self.equilibrium.success and self.equilibrium.stable and self.rel_size <= self.tolerance)

    @property
    def ok(self) -> bool:
        """Hangs within the tolerance, stable, in tension (unless allowed), rods within their swing."""
        return self.meets_tolerance and self.in_tension and bool(np.all(self.swing_deg <= self.plan.hardware.swing_deg))

    def limit(self) -> str:
        """One line: what keeps the net off its target and what would reach it."""
        pct = (f"hangs {100 * self.rel_size:.3g} % of its size off its target (tolerance "
               f"{100 * self.tolerance:.3g} %)")
        eq, st = self.equilibrium, self.design.statics
        if not eq.success:
            return f"{pct}: the solver found no equilibrium of the designed net ({eq.message})"
        if not eq.stable:
            return f"{pct}: the target is an equilibrium of the designed net, but not a stable one"
        if not self.meets_tolerance and self.why:
            return f"{pct}: {self.why}"
        if not self.meets_tolerance:
            return f"{pct}: {st.message} The best fit within the rods' mass ranges (refined through the solver) is " \
                   "the closest; a catalog with a wider mass range, more anchored nodes or a target closer to a " \
                   "hanging shape would reach it"
        if not self.in_tension:
            c = self.compressed
            return f"{pct}, but rods {c[:8].tolist()} push (compression): allow it with net.compression: true " \
                   "or anchor more nodes"
        over = np.argwhere(self.swing_deg > self.plan.hardware.swing_deg)
        return f"{pct}, but rod {over[0][0]} turns {self.swing_deg[tuple(over[0])]:.3g} deg in its socket, more " \
               f"than the {self.plan.hardware.swing_deg:.3g} deg the hub allows"


def design_net_plan(plan: NetPlan, *, g: float = 9.81, seed: int = 0, tolerance: float | None = None,
                    n_starts: int | None = None) -> NetCheck:
    """Masses for the planned net, its exact equilibrium and its fit.

    Args:
        plan: :func:`plan_net`'s rods and hardware.
        g: gravitational acceleration (m/s^2).
        seed: the multi-start's seed.
        tolerance: largest acceptable error over the net's size (None: 1 %).
        n_starts: the multi-start's starts (None: :func:`net_starts`).
    """
    t0 = time.perf_counter()
    n_starts = net_starts(plan.target.n) if n_starts is None else int(n_starts)
    lines = plan.pivots.copy()
    plan, rounds = orient_sockets(plan, g=g)
    turn = 0.0
    if plan.hardware.is_hub:
        cos = np.sum(lines * plan.pivots, axis=2) / plan.hardware.pivot_radius ** 2
        turn = float(np.degrees(np.arccos(np.clip(cos, -1, 1))).max())
    t = plan.target
    design = design_net(t.positions, t.edges, plan.lengths, plan.bounds, t.anchored, node_masses=plan.node_masses,
                        node_com=plan.node_com, pivots=plan.pivots, allow_compression=t.compression, g=g,
                        n_starts=n_starts, seed=seed, refine=True)
    eq = design.equilibrium
    size = t.size
    if eq.success:
        node_err = np.linalg.norm(eq.positions - t.positions, axis=1)
        end_err = np.linalg.norm(eq.ends - plan.target_ends, axis=2)
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
        why = _imbalance(plan, design, g)
        notes.append(why)
    if turn > 0:
        notes.append(f"The hubs' sockets are turned up to {turn:.3g} deg off the lines between the node points "
                     f"(printed so; {rounds} round(s)), so that every hub balances at the target: a socket on the "
                     "line would put its rod's weight share off the hub's centre and turn it.")
    if design.refined:
        notes.append(f"The masses were refined through the solver from the statics' best fit "
                     f"({design.info.get('fit_error', float('nan')):.4g} mm -> "
                     f"{design.info.get('refined_error', float('nan')):.4g} mm).")
    if eq.alternatives:
        notes.append(f"The multi-start ({n_starts} starts) found {len(eq.alternatives)} other stable shape(s)"
                     + (", one hanging lower than the design's: a push may move the net there." if eq.lower else
                        ", none lower than the design's."))
    if t.dropped:
        notes.append(f"{t.dropped} rod(s) between two anchored nodes were left out (the anchors hold both ends).")
    masses = np.asarray(design.masses, float)
    return NetCheck(plan, design, masses, err, err / size if size > 0 else float("inf"), node_err, tol, sockets,
                    swing, time.perf_counter() - t0, notes, why)


def _imbalance(plan: NetPlan, design: NetDesign, g: float) -> str:
    """Where the statics' best fit leaves the largest imbalance, when no masses at all (any
    positive mass, rods pushing or not) balance the target."""
    t = plan.target
    st = net_statics(t.positions, t.edges, plan.lengths, t.anchored, node_masses=plan.node_masses,
                     node_com=plan.node_com, pivots=plan.pivots, g=g)
    res = np.abs(st.residual(design.statics.tensions, design.statics.masses))
    force = st.rows[:, 1] < 3
    per_node = np.zeros(t.n)
    np.maximum.at(per_node, st.rows[force, 0], res[force])
    worst = np.argsort(-per_node, kind="stable")[:8]
    worst = [int(k) for k in worst if per_node[k] > 1e-6 * max(per_node.max(), 1e-300)]
    return (f"No masses at all balance this target: some nodes' rods cannot pull them in every direction the "
            f"load needs (the largest imbalance is at node(s) {worst}). A grid drawn over a rectangle and hung "
            "from its corners is one such target: its straight border has nothing to pull it outward, so a "
            "hanging net's border curves inward in plan; anchor the border, or give a target whose border does.")
