"""Exact static equilibrium of a hanging net of rigid rods in 3D (:func:`solve_net`).

Rigid rods joined at nodes by spherical joints, gravity along -z (z up), some nodes
anchored. Nodes are points or rigid node bodies (rings, hubs) whose pose the solver finds;
rods may carry their centre of mass off their axis (they turn about it to hang it lowest).
The model and its conventions are in :mod:`optimize.net.model`, the method in
:mod:`optimize.net.newton`. Units are the caller's (mm, g); forces are mass x the unit of
``g`` (g and m/s^2: millinewtons), moments force x length.

Example:
    >>> import numpy as np
    >>> x = np.array([[0.0, 0, 0], [30, 0, -40], [60, 0, 0]])
    >>> res = solve_net(x, [[0, 1], [1, 2]], [50, 50], [1, 1], [0, 2], node_masses=[0, 2, 0])
    >>> bool(res.success and res.stable and res.kkt_residual < 1e-12)
    True
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from optimize.net.deriv import evaluate, rod_frames
from optimize.net.model import Net, NetState, cross
from optimize.net.newton import CONVERGED, descend, is_stable, kkt_residual, restore

__all__ = ["NET_MESSAGES", "NetResult", "more_starts", "net_sag_guess", "pivots_by_node", "pivots_from_nodes",
           "solve_net"]

#: Status codes and their messages (one table, as in scipy.optimize).
NET_MESSAGES = {
    0: "Equilibrium found: every rod at its length, KKT conditions satisfied to round-off.",
    1: "Iteration limit reached before the KKT conditions held.",
    2: "No configuration keeps every rod at its length (restoration failed from every start): "
       "the anchors may be out of the rods' reach.",
    3: "No step lowers the energy any more, but the KKT residual is above the tolerance.",
}


@dataclass
class NetResult:
    """The equilibrium of a hanging net.

    Attributes:
        positions: (n, 3) node points (the anchored ones where they were given).
        rotations: (n, 3, 3) node bodies' orientations (body frame -> world; identity at
            point nodes and where a body's orientation does not matter).
        ends: (m, 2, 3) each rod's pivots (at node i, at node j), ``L_e`` apart.
        rod_frames: (m, 3, 3) each rod's frame, rows x (pivot 0 -> 1), y, z in world
            coordinates, turned so that its centre of mass (along, perp, w) hangs lowest.
        tensions: (m,) the multiplier of each rod's length constraint: the axial force
            that, with the rod's weight shared vertically between its pivots (lever rule),
            makes up the pivot forces; > 0 in tension. For a symmetric rod, the axial force
            at mid-length. Statically indeterminate nets: the tensions of equally stiff
            rods (minimum sum L_e T_e^2 among those that balance).
        rod_forces: (m, 2, 3) the force each rod exerts on its node at pivot 0 and 1.
        anchors: (k,) the anchored nodes, ascending.
        reactions: (k, 3) the force each anchor exerts on its node (its weight included).
        reaction_moments: (k, 3) the moment each anchor exerts on its node body about the
            node point (zero for point nodes).
        compressed: indices of rods in compression (tension below -1e-9 x the force scale).
        energy: potential energy (force x length), zero at z = 0.
        kkt_residual: relative KKT residual (:func:`optimize.net.newton.kkt_residual`).
        stable: the Hessian of the Lagrangian is positive definite on the tangent space of
            the constraints, modulo exact symmetries (a net on one vertical line of anchors
            turning about it, a node body spinning about the line of its pivots).
        success, status, message: outcome, ``message = NET_MESSAGES[status]`` plus detail.
        nit: Newton iterations; nrestore: restoration iterations; nfactor: factorizations
            of the Newton matrix; escapes: times a KKT point that was not stable was left.
        alternatives: other distinct stable equilibria the multi-start found (lowest
            energy first), each a NetResult with no alternatives of its own.
        counts: how many starts ended at this equilibrium, then at each alternative.
        n_starts: starts made.
    """

    positions: np.ndarray
    rotations: np.ndarray
    ends: np.ndarray
    rod_frames: np.ndarray
    tensions: np.ndarray
    rod_forces: np.ndarray
    anchors: np.ndarray
    reactions: np.ndarray
    reaction_moments: np.ndarray
    compressed: np.ndarray
    energy: float
    kkt_residual: float
    stable: bool
    success: bool
    status: int
    message: str
    nit: int = 0
    nrestore: int = 0
    nfactor: int = 0
    escapes: int = 0
    alternatives: list = field(default_factory=list)
    counts: list = field(default_factory=list)
    n_starts: int = 1

    @property
    def lower(self) -> bool:
        """An alternative lies lower than this equilibrium (beyond round-off)."""
        tol = 1e-9 * (abs(self.energy) + 1e-300)
        return any(a.energy < self.energy - tol for a in self.alternatives)

    def __repr__(self) -> str:  # pragma: no cover - convenience
        return (f"NetResult(success={self.success}, stable={self.stable}, kkt_residual={self.kkt_residual:.2e}, "
                f"nit={self.nit}, compressed={self.compressed.size}, alternatives={len(self.alternatives)}, "
                f"message={self.message!r})")


def pivots_from_nodes(edges, node_pivots) -> np.ndarray:
    """The (m, 2, 3) ``pivots`` array from design.json's per-node form.

    Args:
        edges: (m, 2) the rods' nodes.
        node_pivots: one entry per node: None (a point node) or a mapping {rod index:
            [dx, dy, dz]}, each rod's pivot from the node point in the node body's frame
            (mm); a rod the mapping leaves out pivots about the node point.

    Returns:
        (m, 2, 3) array: rod e's pivot at its node i (column 0) and at its node j (1).
    """
    edges = np.asarray(edges, int)
    out = np.zeros((edges.shape[0], 2, 3))
    for node, entry in enumerate(node_pivots):
        if not entry:
            continue
        for rod, offset in entry.items():
            rod = int(rod)
            ends = np.flatnonzero(edges[rod] == node)
            if ends.size == 0:
                raise ValueError(f"node {node} gives a pivot for rod {rod}, which does not end at it")
            out[rod, ends[0]] = np.asarray(offset, float)
    return out


def pivots_by_node(edges, pivots, n: int | None = None) -> list:
    """design.json's per-node form of a (m, 2, 3) ``pivots`` array: for each of the ``n``
    nodes (default: up to the largest in ``edges``) None (all its rods pivot about the node
    point) or {rod index: [dx, dy, dz]}."""
    edges = np.asarray(edges, int)
    pivots = np.asarray(pivots, float)
    n = (int(edges.max()) + 1 if edges.size else 0) if n is None else int(n)
    out: list = [None] * n
    for rod, (i, j) in enumerate(edges):
        for end, node in enumerate((i, j)):
            if np.any(pivots[rod, end] != 0) or out[node] is not None:
                out[node] = out[node] or {}
    for rod, (i, j) in enumerate(edges):
        for end, node in enumerate((i, j)):
            if out[node] is not None:
                out[node][rod] = pivots[rod, end].tolist()
    return out


def net_sag_guess(net: Net, state: NetState, *, iterations: int = 30) -> NetState:
    """A hanging start: the force-density shape of the net as a cable net under its weights.

    Each free node balances ``sum_e q_e (x_j - x_i)`` against its share of the weights, a
    linear system; the force densities ``q_e`` are then scaled by each rod's length ratio
    until the lengths roughly match. Pivot offsets are ignored (node bodies keep their
    orientation); the restoration makes the guess exact.
    """
    n, e = net.n, net.edges
    free = ~net.anchored
    load = np.zeros(n)
    np.add.at(load, e[:, 0], 0.5 * net.masses)
    np.add.at(load, e[:, 1], 0.5 * net.masses)
    load = -net.g * (load + net.node_masses)
    q = net.weight / (net.m * net.lengths)
    x = state.x.copy()
    idx = np.full(n, -1)
    idx[free] = np.arange(int(free.sum()))
    for _ in range(iterations):
        A = sp.coo_matrix((np.concatenate([q, q, -q, -q]),
                           (np.concatenate([e[:, 0], e[:, 1], e[:, 0], e[:, 1]]),
                            np.concatenate([e[:, 0], e[:, 1], e[:, 1], e[:, 0]]))), shape=(n, n)).tocsr()
        Aff = A[free][:, free].tocsc()
        rhs = -(A[free][:, ~free] @ x[~free])
        rhs[:, 2] += load[free]
        lu = splu(Aff, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
        x[free] = lu.solve(rhs)
        dist = np.linalg.norm(x[e[:, 1]] - x[e[:, 0]], axis=1)
        q = q * np.clip(dist / net.lengths, 0.5, 2.0)
    return NetState(x, state.R.copy())


def _perturbed(net: Net, state: NetState, rng: np.random.Generator, scale: float) -> NetState:
    out = state.copy()
    free = ~net.anchored
    out.x[free] += scale * net.mean_length * rng.standard_normal((int(free.sum()), 3))
    bodies = net.rot_idx >= 0
    if bodies.any():
        from optimize.net.model import rotation_exp

        out.R[bodies] = rotation_exp(scale * rng.standard_normal((int(bodies.sum()), 3))) @ out.R[bodies]
    return out


#: Above this many unknowns a perturbed start of the multi-start gets at most
#: PERTURBED_RESTORE restoration iterations and PERTURBED_ITER Newton iterations (the start
#: from the target keeps the full limits): on a 2,000-rod hub grid one random start took
#: minutes of factorizations to come back to its rods' lengths. A start that stops there
#: counts as one that found no equilibrium, and the result says how many did.
PERTURBED_NVAR = 3000
PERTURBED_RESTORE = 60
PERTURBED_ITER = 100


#: A perturbed start of the multi-start whose KKT residual has not halved in this many Newton
#: iterations stops there (it counts as a start that found no equilibrium): such a descent
#: creeps (a step a hundred-thousandth of Newton's, a degenerate point it cannot leave) and
#: would run to the iteration limit.
PERTURBED_PATIENCE = 40


#: Unstable equilibria a descent leaves along negative curvature before it reports one as it is.
MAX_ESCAPES = 3


def _solve_from(net: Net, start: NetState, max_iter: int, max_restore: int = 200, perturbed: bool = False,
                leave_unstable: bool = True):
    """(Outcome or None, restoration iterations) from one start; a perturbed start of the
    multi-start stops where it stops making progress (:data:`PERTURBED_PATIENCE`);
    ``leave_unstable`` (:func:`solve_net`)."""
    state, ev, ok, nres = restore(net, start, max_iter=max_restore)
    if not ok:
        return None, nres
    out = descend(net, state, max_iter=max_iter, patience=PERTURBED_PATIENCE if perturbed else None,
                  max_escapes=MAX_ESCAPES if leave_unstable else 0)
    out.nrestore = nres
    return out, nres


def _result(net: Net, out) -> NetResult:
    ev, lam, state = out.ev, out.lam, out.state
    success = out.status == 0 and out.kkt <= CONVERGED
    stable = bool(success and is_stable(net, state, ev, lam))
    scale = max(net.weight, float(np.max(np.abs(lam), initial=0.0)))
    if success and (not stable or np.any(lam < -1e-9 * scale)):
        # a net with self-stresses (J' s = 0) leaves its tensions open: the least-squares ones
        # may push where tensions that also hold it pull, and the stability test reads the
        # Hessian of the Lagrangian at the tensions it is given
        alt = tensile_multipliers(net, ev, lam)
        if alt is not None and is_stable(net, state, ev, alt):
            lam, stable = alt, True
    u = ev.u
    F = np.zeros((net.m, 2, 3))
    F[:, :, 2] = -ev.shares
    F[:, 0] += lam[:, None] * u
    F[:, 1] -= lam[:, None] * u
    anchors = np.flatnonzero(net.anchored)
    pos_in = {int(a): k for k, a in enumerate(anchors)}
    reactions = np.zeros((anchors.size, 3))
    moments = np.zeros((anchors.size, 3))
    reactions[:, 2] = net.g * net.node_masses[anchors]
    node_c = np.einsum("nab,nb->na", state.R, net.node_com)
    for k, a in enumerate(anchors):
        w = np.array([0.0, 0.0, net.g * net.node_masses[a]])
        moments[k] = cross(node_c[a], w)
    for end in (0, 1):
        nodes = net.edges[:, end]
        for e in np.flatnonzero(net.anchored[nodes]):
            k = pos_in[int(nodes[e])]
            reactions[k] -= F[e, end]
            moments[k] -= cross(ev.a[e, end], F[e, end])
    force_scale = max(net.weight, float(np.max(np.abs(lam), initial=0.0)))
    compressed = np.flatnonzero(lam < -1e-9 * force_scale)
    status = out.status if not (out.status == 0 and not success) else 1
    message = NET_MESSAGES[status]
    if success and not stable:
        message += " The equilibrium is not stable (or only marginally)."
    if compressed.size:
        message += f" {compressed.size} rod(s) in compression: {compressed[:8].tolist()}."
    if out.escapes:
        message += f" (left {out.escapes} unstable equilibrium(s) along negative curvature)"
    return NetResult(positions=state.x.copy(), rotations=state.R.copy(), ends=ev.P.copy(),
                     rod_frames=rod_frames(net, ev), tensions=lam.copy(), rod_forces=F, anchors=anchors,
                     reactions=reactions, reaction_moments=moments, compressed=compressed, energy=ev.energy,
                     kkt_residual=out.kkt, stable=stable, success=success, status=status, message=message,
                     nit=out.nit, nrestore=out.nrestore, nfactor=out.nfactor, escapes=out.escapes)


#: Nets up to this many unknowns get the dense search of their self-stresses
#: (:func:`tensile_multipliers`) where the least-squares tensions push or do not hold them;
#: larger ones a sparse linear program in the tensions themselves.
SELF_STRESS_NVAR = 600


def tensile_multipliers(net: Net, ev, lam: np.ndarray) -> np.ndarray | None:
    """Tensions of the same equilibrium that pull in every rod, nearest ``lam``, or None.

    At an equilibrium ``grad U + J' lam = 0``; where J lacks full row rank (states of
    self-stress ``s``, ``J' s = 0``: rods whose tensions load no node) every ``lam + S a``
    holds the net as well, and rigid rods do not say which. The least-squares ``lam`` (the
    limit of equally stiff rods) may push in some rods where others of the set pull in all:
    those are found by a linear program, least ``sum |a|`` subject to ``lam + S a >= 0`` (S the
    self-stresses from a dense SVD of J; nets up to :data:`SELF_STRESS_NVAR` unknowns). A
    larger net's program is sparse, in the change of tensions ``d`` itself: least ``sum |d|``
    subject to ``J' d = 0`` and ``lam + d >= 0`` (HiGHS's interior point), its ``J' d = 0`` then
    made exact by the least change (LSMR) and the tensions kept only where they hold the
    equilibrium to the solver's tolerance.

    Returns:
        (m,) the tensions, or None: no self-stress, or none that pull in every rod.
    """
    from scipy.optimize import linprog

    if net.nvar == 0:
        return None
    if net.nvar > SELF_STRESS_NVAR:
        return _tensile_sparse(net, ev, lam)
    J = ev.J.toarray()
    U, sv, _ = np.linalg.svd(J, full_matrices=True)
    rank = int(np.sum(sv > 1e-9 * (sv[0] if sv.size else 0.0)))
    S = U[:, rank:]
    k = S.shape[1]
    if k == 0:
        return None
    # a = p - q, p, q >= 0: min sum(p + q) s.t. -S (p - q) <= lam
    res = linprog(np.ones(2 * k), A_ub=np.hstack([-S, S]), b_ub=lam, bounds=(0, None), method="highs")
    if res.status != 0:
        return None
    alt = lam + S @ (res.x[:k] - res.x[k:])
    return np.maximum(alt, 0.0)  # (round-off below zero)


def _tensile_sparse(net: Net, ev, lam: np.ndarray) -> np.ndarray | None:
    """:func:`tensile_multipliers` for a large net: sparse throughout (see there)."""
    from scipy.optimize import linprog
    from scipy.sparse.linalg import lsmr

    m = net.m
    F = max(net.weight, float(np.max(np.abs(lam), initial=0.0)))
    Jt = ev.J.T.tocsr()
    eye = sp.identity(m, format="csr")
    # d = p - q, p, q >= 0: min sum(p + q) s.t. J' (p - q) = 0, -(p - q) <= lam (over F)
    res = linprog(np.ones(2 * m), A_ub=sp.hstack([-eye, eye]).tocsr(), b_ub=lam / F,
                  A_eq=sp.hstack([Jt, -Jt]).tocsr(), b_eq=np.zeros(net.nvar), bounds=(0, None), method="highs-ipm",
                  options={"presolve": False})
    if res.status != 0:
        return None
    d = (res.x[:m] - res.x[m:]) * F
    d -= lsmr(Jt, Jt @ d, atol=1e-15, btol=1e-15, maxiter=20 * m)[0]  # (J' d = 0 to round-off)
    alt = lam + d
    if np.any(alt < -1e-9 * F) or kkt_residual(net, ev, alt)[0] > CONVERGED:
        return None
    return np.maximum(alt, 0.0)


def _failed(net: Net, start: NetState, nres: int) -> NetResult:
    ev = evaluate(net, start)
    anchors = np.flatnonzero(net.anchored)
    nan3 = np.full((anchors.size, 3), np.nan)
    return NetResult(positions=start.x.copy(), rotations=start.R.copy(), ends=ev.P.copy(),
                     rod_frames=rod_frames(net, ev), tensions=np.full(net.m, np.nan),
                     rod_forces=np.full((net.m, 2, 3), np.nan), anchors=anchors, reactions=nan3,
                     reaction_moments=nan3.copy(), compressed=np.zeros(0, dtype=int), energy=ev.energy,
                     kkt_residual=float(np.max(np.abs(ev.c) / net.lengths)), stable=False, success=False, status=2,
                     message=NET_MESSAGES[2], nrestore=nres)


def _invariants(net: Net, res: NetResult) -> np.ndarray:
    """Node coordinates to compare equilibria by (turned into a fixed azimuth when the
    net hangs from one vertical line of anchors, whose turning is a symmetry)."""
    x = res.positions
    anchors = x[net.anchored]
    if np.max(np.abs(anchors[:, :2] - anchors[0, :2]), initial=0.0) <= 1e-9 * net.mean_length:
        rel = x[:, :2] - anchors[0, :2]
        return np.column_stack([np.hypot(rel[:, 0], rel[:, 1]), x[:, 2]])
    return x


def solve_net(node_positions0, edges, lengths, masses, anchored, *, node_masses=None, com=None, g: float = 9.81,
              n_starts: int = 1, seed: int | None = 0, node_com=None, pivots=None, node_rotations0=None,
              start_scale: float = 0.5, max_iter: int = 200, tol: float = 1e-7, callback=None,
              leave_unstable: bool = True) -> NetResult:
    """Stable static equilibrium of a net of rigid rods hung from anchored nodes.

    Args:
        node_positions0: (n, 3) start positions of the nodes (mm; e.g. the target); the
            anchored ones are where the anchors hold them.
        edges: (m, 2) the two nodes (i, j) each rod joins.
        lengths: (m,) pivot-to-pivot rod lengths, positive.
        masses: (m,) rod masses (>= 0; only mass ratios shape the net).
        anchored: indices of the anchored nodes, or an (n,) boolean mask.
        node_masses: (n,) masses at the nodes (hardware), >= 0; None = none.
        com: (m, 2) or (m, 3) each rod's centre of mass (along, perp[, w]) in its frame
            (origin at the pivot at node i, x toward node j); None = (L/2, 0, 0).
        g: gravitational acceleration, along -z.
        n_starts: starts in all: the given one, then seeded perturbations of it (free nodes
            moved by ``start_scale`` x the mean rod length, bodies turned by that many
            radians, at random); the distinct stable equilibria go to ``alternatives``. Where
            the given start (and the sag) reach no equilibrium, the perturbed ones are not tried.
            A perturbed start stops where its KKT residual stops halving
            (:data:`PERTURBED_PATIENCE`); the message says how many found no equilibrium.
        seed: seed of the perturbations (same seed, same result).
        node_com: (n, 3) node bodies' centres of mass from the node point, body frame.
        pivots: (m, 2, 3) each rod's pivot at node i and at node j, from the node point in
            that node's body frame (a ring of radius r: points on the ring). A node with a
            pivot off its point (or an off-centre mass) is a rigid body whose orientation
            the solver finds; anchored ones keep the given orientation.
        node_rotations0: (n, 3, 3) start orientations of the node bodies (body -> world);
            None = identity.
        start_scale: the multi-start's perturbation size (see ``n_starts``).
        max_iter: Newton iterations per start.
        tol: two equilibria are the same when no node differs by more than ``tol`` times
            the net's size (the largest extent of its start).
        callback: called with a line of text before each start of the multi-start, or None.
        leave_unstable: True: an unstable equilibrium the descent reaches is left along the
            most negative curvature for a stable one (where the net falls to), up to
            :data:`MAX_ESCAPES` times. False: the descent from the given start stops at the
            first equilibrium it reaches, stable or not (``stable`` says): a design check asks
            whether its target is a stable equilibrium, not where the net would fall from it.
            The multi-start's perturbed starts always leave unstable equilibria.

    Returns:
        NetResult: the equilibrium reached from the given start (the designed state, when
        it is the target), other stable equilibria in ``alternatives``. If the given start
        cannot be made feasible, the force-density sag (:func:`net_sag_guess`) is tried.

    Raises:
        ValueError: bad arguments (naming the argument), a node no anchor holds up, a rod
            between two anchors that does not fit, or anchors farther apart than the rods
            between them reach.
    """
    net, start = Net.from_args(node_positions0, edges, lengths, masses, anchored, node_masses=node_masses, com=com,
                               g=g, node_com=node_com, pivots=pivots, node_rotations0=node_rotations0)
    out, nres = _solve_from(net, start, max_iter, leave_unstable=leave_unstable)
    if out is None or out.status != 0:
        # the given start could not be made feasible, or the descent from it stalled (a
        # flat start with rods longer than its spacing): from the hanging cable-net shape
        sag, nres2 = _solve_from(net, net_sag_guess(net, start), max_iter, leave_unstable=leave_unstable)
        nres += nres2
        if sag is not None and (out is None or sag.status == 0):
            out = sag
    first = _result(net, out) if out is not None else _failed(net, start, nres)
    return _multistart(net, start, first, n_starts, seed, start_scale, max_iter, tol, callback)


def more_starts(first: NetResult, node_positions0, edges, lengths, masses, anchored, *, n_starts: int,
                seed: int | None = 0, node_masses=None, com=None, g: float = 9.81, node_com=None, pivots=None,
                node_rotations0=None, start_scale: float = 0.5, max_iter: int = 200, tol: float = 1e-7,
                callback=None) -> NetResult:
    """The multi-start of :func:`solve_net` run after a one-start solve: ``first`` is
    ``solve_net(...)``'s result with these same arguments and ``n_starts=1``, and the result is
    what ``solve_net(..., n_starts=n_starts, seed=seed)`` returns (the same perturbed starts),
    without descending from the given start again. A planner that designs a net several ways
    solves each from its target alone, then asks this of the design it keeps. ``first`` itself
    is left as it was."""
    net, start = Net.from_args(node_positions0, edges, lengths, masses, anchored, node_masses=node_masses, com=com,
                               g=g, node_com=node_com, pivots=pivots, node_rotations0=node_rotations0)
    first = dataclasses.replace(first, alternatives=[], counts=[])
    return _multistart(net, start, first, n_starts, seed, start_scale, max_iter, tol, callback)


def _multistart(net: Net, start: NetState, first: NetResult, n_starts: int, seed, start_scale: float,
                max_iter: int, tol: float, callback) -> NetResult:
    """``first`` (the equilibrium from ``start``) with the other stable equilibria that
    ``n_starts - 1`` seeded perturbations of ``start`` reach (:func:`solve_net`)."""
    first.n_starts = max(int(n_starts), 1)
    first.counts = [1]
    if n_starts <= 1 or not first.success:  # (no equilibrium from the start given: the verdict, whatever else is found)
        return first
    rng = np.random.default_rng(seed)
    size = max(float(np.max(np.ptp(start.x, axis=0))), net.mean_length)
    found: list[NetResult] = []
    counts: list[int] = []
    ref = _invariants(net, first) if first.success and first.stable else None
    big = net.nvar > PERTURBED_NVAR
    lost = 0
    for k in range(n_starts - 1):
        if callback is not None:
            callback(f"multi-start: start {k + 2} of {n_starts} (a perturbed shape)")
        o, _ = _solve_from(net, _perturbed(net, start, rng, start_scale),
                           min(max_iter, PERTURBED_ITER) if big else max_iter,
                           PERTURBED_RESTORE if big else 200, perturbed=True)
        if o is None or o.status != 0:
            lost += 1
        if o is None:
            continue
        r = _result(net, o)
        if not (r.success and r.stable):
            continue
        inv = _invariants(net, r)
        if ref is not None and np.max(np.abs(inv - ref)) <= tol * size:
            first.counts[0] += 1
            continue
        for k, known in enumerate(found):
            if np.max(np.abs(inv - _invariants(net, known))) <= tol * size:
                counts[k] += 1
                break
        else:
            found.append(r)
            counts.append(1)
    if lost:
        first.message += (f" {lost} of the multi-start's {n_starts - 1} perturbed start(s) found no equilibrium within "
                          "the iteration limits.")
    order = np.argsort([f.energy for f in found], kind="stable")
    first.alternatives = [found[k] for k in order]
    first.counts += [counts[k] for k in order]
    return first
