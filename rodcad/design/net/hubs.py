"""The hubs' sockets turned so that every hub balances at the target, and rods' mass bounds
narrowed to masses they can be built at (see :func:`orient_sockets`, :func:`buildable_bounds`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from rodcad.design.net.plan import NetPlan, mass_segments, replan, rod_bounds
from rodcad.design.net.spacing import socket_clashes, spaced_turn, too_close

__all__ = ["ANDERSON", "ORIENT_FINE", "ORIENT_ROUNDS", "ORIENT_STALL", "JOINT_NFEV", "JOINT_PROGRESS", "JOINT_ROUNDS", "ORIENT_TOL", "balance_jointly", "buildable_bounds", "orient_sockets"]


#: Rounds of :func:`orient_sockets` at most, and the pivot change (over the pivot radius) it stops at.
ORIENT_ROUNDS = 12
ORIENT_TOL = 1e-13
#: A statics residual (over the force scale) this small ends the rounds: the design's
#: refinement through the exact solver takes it to round-off.
ORIENT_FINE = 1e-7
#: Rounds in a row that cut the statics' residual by less than a tenth end the rounds where the
#: nodes' forces alone balance (where they do not, two): a 2,200-rod net's turns settled in 2
#: rounds at 1.5e-7 and the other 10 gained 0.3 % (5 s each).
ORIENT_STALL = 3
#: Depth of the Anderson acceleration of :func:`orient_sockets`' fixed point.
ANDERSON = 5
#: Rounds of :func:`balance_jointly` at most (the rods' lengths and bounds follow each).
JOINT_ROUNDS = 3
#: Evaluations of one joint solve at most: JOINT_NFEV / rods, within 20-200 (a reachable balance
#: takes 5-20 a round; a big net no turns within the cap balance would spend tens of seconds on
#: hundreds).
JOINT_NFEV = 12000
#: Nets above JOINT_NODES nodes whose least turns leave a residual above JOINT_FAR (over the
#: force scale; hung hub grids start at 3e-3 to 1.2e-2) get no joint solve.
JOINT_NODES = 100
JOINT_FAR = 0.05
#: A joint solve goes on to another round only where the last one cut the residual at least
#: this many times (one that no turns balance stops after its first round).
JOINT_PROGRESS = 10.0


def orient_sockets(plan: NetPlan, *, g: float = 9.81) -> tuple[NetPlan, int, float]:
    """Hub sockets turned so that the hubs balance at the target, as printed to order.

    A socket on the line between two node points puts its rod's weight share off the hub's
    centre: the hub would turn and the net leave its target. Each free hub's sockets are
    instead turned (on the pivot sphere) toward the force its rod pulls with, the least
    turn that makes the moments about the hub's centre, its own weight's included, vanish;
    the rods' lengths follow. The forces come from the statics at the target, so the two
    are iterated to a fixed point: the nodes' forces balanced (exactly where the mass
    bounds allow, else their best fit), the sockets turned to cancel those forces' moments,
    the rods' directions updated; a few rounds, the turns being a few degrees. A point node
    has nothing to turn. The balancing turns are not unique, and the least turns may need
    masses the rods cannot be built at: where the rounds end short of an exact balance (and
    the nodes' forces alone do balance), the turns and the masses are solved together
    (:func:`balance_jointly`) from where they ended, and kept where that balances better.

    Returns:
        (the plan with its pivots, lengths, bounds and hub centres of mass; rounds used; the
        statics' residual there, over the force scale; NaN for point nodes).
    """
    t, hw = plan.target, plan.hardware
    if not hw.is_hub:
        return plan, 0, float("nan")
    r = float(plan.end_pivot.max())  # (the scale of the pivot changes; each hub keeps its own radius)
    rk = plan.end_pivot
    free = ~t.anchored_mask
    at_node = t.node_ends()
    axis = plan.pivots.copy()  # along the rods' lines between node points
    rounds = 0
    best, best_res, stall = plan, np.inf, 0
    xs: list[np.ndarray] = []
    gs: list[np.ndarray] = []
    for rounds in range(1, ORIENT_ROUNDS + 1):
        full = plan.mass_design(g, explain=False)
        if full.exact:
            return plan, rounds, full.residual
        if full.residual <= ORIENT_FINE:  # (this close, the joint solve below or the refinement finishes it)
            best, best_res = plan, full.residual
            break
        st = plan.mass_design(g, forces_only=True, explain=False)
        if full.residual < 0.9 * best_res:
            best, best_res, stall = plan, full.residual, 0
        else:
            if full.residual < best_res:
                best, best_res = plan, full.residual
            stall += 1
            # the forces themselves do not balance: the least turns will not reach it; they do, but
            # the rounds have stopped gaining: the turns have settled where they leave a residual
            # that more rounds do not take off (the joint solve and the refinement may)
            if stall >= (ORIENT_STALL if st.exact else 2):
                break
        ends = t.positions[t.edges] + plan.pivots
        u = ends[:, 1] - ends[:, 0]
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        share = _shares(st.masses, g, u, plan.statics_com, plan.lengths)
        F = np.stack([st.tensions[:, None] * u, -st.tensions[:, None] * u], axis=1)
        F[:, :, 2] -= share
        new = plan.pivots.copy()
        for k in np.flatnonzero(free):
            at = at_node[k]
            if len(at) < 2:
                continue
            f = np.array([F[e, c] for e, c in at])
            norm = np.linalg.norm(f, axis=1)
            a = np.array([axis[e, c] for e, c in at])
            cw = np.cross(plan.node_com[k], [0.0, 0.0, -g * plan.node_masses[k]])
            A = np.hstack([-_skew(fq) for fq in f])
            AAt = A @ A.T
            rad = plan.hub(int(k)).pivot_radius
            for _ in range(6):  # the least turn from the rods' lines that cancels the moments
                M = cw + np.sum(np.cross(a, f), axis=0)
                if np.max(np.abs(M)) <= 1e-15 * float(norm.max()) * r:
                    break
                a = a + (A.T @ np.linalg.lstsq(AAt, -M, rcond=None)[0]).reshape(-1, 3)
                a *= rad / np.linalg.norm(a, axis=1, keepdims=True)
            need = plan.hub(int(k)).socket_angle_deg
            if too_close(a, need):  # (the least turn runs two sockets into each other's wall)
                a = spaced_turn(np.array([axis[e, c] for e, c in at]), f, cw, rad, need)
            for q, (e, c) in enumerate(at):
                new[e, c] = a[q]
        change = float(np.max(np.abs(new - plan.pivots))) / r
        if change <= ORIENT_TOL:
            plan = replan(plan, new)
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
            nxt[on] *= rk[on][:, None] / np.linalg.norm(nxt[on], axis=1, keepdims=True)
            nxt[~on] = new[~on]
            if socket_clashes(dataclasses.replace(plan, pivots=nxt)):  # (the extrapolation ran two sockets together)
                nxt = new
        plan = replan(plan, nxt)
    if t.n > JOINT_NODES and best_res > JOINT_FAR:
        return best, rounds, best_res  # (a big net this far from balancing: seconds for nothing)
    joint, joint_res = balance_jointly(best, g=g)
    if joint_res < best_res:
        return joint, rounds + 1, joint_res
    return best, rounds, best_res


def balance_jointly(plan: NetPlan, *, g: float = 9.81) -> tuple[NetPlan, float]:
    """The plan with its free hubs' sockets turned and its rods' masses found together
    (:func:`optimize.net.sockets.balance_sockets`), from its sockets and the statics' best fit
    there: where turning each hub by its least turn needs masses the rods cannot be built at,
    other turns may balance within them. Returns (the plan, the statics' residual there over
    the force scale); the plan as it was when the joint solve does not improve it."""
    from optimize.net.sockets import FIXED_TURN, balance_sockets

    t = plan.target

    def statics(p):
        return p.mass_design(g, allow_compression=plan.may_push, explain=False)

    st = statics(plan)
    if st.exact:
        return plan, st.residual
    socket_com = np.zeros(t.n)
    for k in np.flatnonzero(plan.degree > 0):
        deg = int(plan.degree[k])
        socket_com[k] = plan.hub(int(k)).hub_mass(np.tile([1.0, 0.0, 0.0], (deg, 1)))[1][0] / deg
    # the turns are measured from the lines between the node points, and kept within half the
    # swing the sockets allow (the net still swings its rods as it hangs)
    x = t.positions
    line = x[t.edges[:, 1]] - x[t.edges[:, 0]]
    nrm = np.linalg.norm(line, axis=1, keepdims=True)
    ep = plan.end_pivot
    lines = np.stack([line * (ep[:, :1] / nrm), -(line * (ep[:, 1:] / nrm))], axis=1)
    cap = 0.5 * float(plan.swing_limits.min())
    best, best_res = plan, st.residual
    cur = plan
    for _ in range(JOINT_ROUNDS):  # the rods' lengths, and with them their mass bounds, follow the sockets
        h = 1e-4 * float(cur.lengths.mean())
        slopes = (rod_bounds(cur, cur.lengths + h) - rod_bounds(cur, cur.lengths - h)) / (2 * h)
        for turns in (cap, np.minimum(cap, _room(plan, lines))):  # (the second keeps every two sockets apart)
            # (a socket with no room stays on its line; the others start within their box)
            start = np.where((np.asarray(turns) <= FIXED_TURN)[..., None], lines, cur.pivots)
            sb = balance_sockets(t.positions, t.edges, lines, cur.bounds, t.anchored, node_masses=cur.node_masses,
                                 start=start, max_turn_deg=turns, bound_slopes=slopes,
                                 socket_com=socket_com, masses0=st.masses, tensions0=st.tensions, com=cur.statics_com,
                                 allow_compression=plan.may_push, g=g,
                                 max_nfev=int(np.clip(JOINT_NFEV / t.m, 20, 200)))
            if not socket_clashes(dataclasses.replace(cur, pivots=sb.pivots)):
                break
        else:
            break
        cur = replan(cur, sb.pivots)
        st = statics(cur)
        before = best_res
        if st.residual < best_res:
            best, best_res = cur, st.residual
        if st.exact or best_res * JOINT_PROGRESS > before:
            break
    return best, best_res


def _room(plan: NetPlan, lines: np.ndarray) -> np.ndarray:
    """(m, 2) how far each socket may turn from its line, about each of two axes across it (deg),
    for every two sockets of a hub to stay :attr:`~rodcad.catalog.net.node.NodeHardware.
    socket_angle_deg` apart whichever way they turn: half its least slack to a neighbour, the
    box's corner (``sqrt(2)`` times its side) within it."""
    t = plan.target
    out = np.full((t.m, 2), 90.0)
    for k, at in enumerate(t.node_ends()):
        if len(at) < 2:
            continue
        d = np.array([lines[e, c] for e, c in at], float)
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        ang = np.degrees(np.arccos(np.clip(d @ d.T, -1.0, 1.0)))
        np.fill_diagonal(ang, 360.0)
        slack = np.maximum(ang.min(axis=1) - plan.hub(k).socket_angle_deg, 0.0) / 2
        side = np.degrees(np.arctan(np.tan(np.radians(np.minimum(slack, 89.0))) / np.sqrt(2)))
        for q, (e, c) in enumerate(at):
            out[e, c] = side[q]
    return out


def buildable_bounds(plan: NetPlan, g: float) -> tuple[NetPlan, int]:
    """The plan with its rods' mass bounds narrowed to masses they can be built at.

    A rod's buildable masses are segments with gaps between them (a steel ball adds more than
    the room beside it lets a cavity take away). Where the statics' design puts a rod in a
    gap, every rod's bounds become the segment nearest its design, and the masses are designed
    again; a rod that then rests on a bound facing a gap moves to the segment across it (a
    few rounds, keeping the best). Returns (the plan, rods whose design fell in a gap: 0 leaves
    the bounds as they were)."""
    hw = plan.hardware

    def statics(bounds):
        return plan.mass_design(g, bounds=bounds, explain=False)

    st = statics(plan.bounds)
    segs = [mass_segments(hw, float(L), int(k)) for L, k in zip(plan.fill_lengths, plan.rod_pieces)]
    choice = []
    snapped = 0
    for e, m in enumerate(st.masses):
        gaps = [max(lo - m, m - hi, 0.0) for lo, hi in segs[e]]
        choice.append(int(np.argmin(gaps)))
        snapped += min(gaps) > 1e-9 * m
    if not snapped:
        return plan, 0
    best, best_res = None, np.inf
    for _ in range(4):
        bounds = np.array([segs[e][c] for e, c in enumerate(choice)], float)
        st = statics(bounds)
        if st.residual < best_res:
            best, best_res = (bounds, list(choice)), st.residual
        if st.exact:
            break
        width = bounds[:, 1] - bounds[:, 0]
        moved = 0
        for e, m in enumerate(st.masses):
            if m - bounds[e, 0] <= 1e-9 * width[e] and choice[e] > 0:
                choice[e] -= 1
                moved += 1
            elif bounds[e, 1] - m <= 1e-9 * width[e] and choice[e] < len(segs[e]) - 1:
                choice[e] += 1
                moved += 1
        if not moved:
            break
    return dataclasses.replace(plan, bounds=best[0], segment=np.array(best[1], int)), snapped


def _shares(masses: np.ndarray, g: float, u: np.ndarray, com, lengths: np.ndarray) -> np.ndarray:
    """(m, 2) each rod's weight at its two pivots: half each for a rod with its centre of mass
    on its axis at mid-length; a bent rod's off-axis centre of mass moves ``q = r s / (L
    sqrt(1 - s^2))`` of it to the upper pivot (:mod:`optimize.net.model`; ``s`` the chord's
    vertical direction cosine, ``r`` the centre of mass's distance from the chord)."""
    if com is None:
        return np.column_stack([0.5 * g * masses, 0.5 * g * masses])
    com = np.asarray(com, float)
    t = com[:, 0] / lengths
    r = np.linalg.norm(com[:, 1:], axis=1)
    s = u[:, 2]
    q = r * s / (lengths * np.sqrt(np.maximum(1 - s * s, 1e-300)))
    return np.column_stack([g * masses * (1 - t - q), g * masses * (t + q)])


def _skew(a: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
