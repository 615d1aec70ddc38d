"""Statics of a net at a target: linear in the rods' tensions and masses; the mass design.

At the target every pivot is known, so each free node's balance is linear in the unknown
tensions T_e and masses m_e::

    sum_e T_e u_e(node) - g sum_e m_e f_e(node) z  =  g M_node z          (3 rows)
    sum_e a_e x (T_e u_e - g m_e f_e z)            =  (R c_node) x g M_node z   (3 rows, bodies)

with ``u_e(node)`` the unit vector from the node's pivot toward the rod's other pivot,
``f_e`` the share of the rod's weight its pivot at that node carries (the lever rule of
:mod:`optimize.net.model`: ``1 - t - q'`` and ``t + q'`` with ``t = along / L`` and ``q'`` the
off-axis term), ``a_e`` the pivot's offset from a body's node point. An off-axis centre
of mass needs no equation of its own: the rod turns about its axis until its centre of
mass hangs in the vertical plane through the axis (the lever rule above already assumes
it). Anchored nodes take any reaction.

:func:`design_net_masses` finds masses within their bounds (and tensions >= 0 unless
compression is allowed: for every rod, or for a mask of them, :mod:`optimize.net.pushing`,
whose rods then push no harder than they must and whose hubs are kept from turning) that
balance the target exactly: a linear program for the
largest margin from every bound, then a quadratic program (:func:`optimize.boxqp.box_qp`)
for the masses nearest the middle of their bounds that keep most of that margin, polished
to round-off. Where no such masses exist, bounded least squares gives the best fit, and
a second linear program says why: how far beyond its bounds each rod would have to go,
or which rods would have to push, for the target to balance.

Units: lengths in mm, masses in g, forces in g x the unit of ``g``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from optimize.boxqp import box_qp
from optimize.net.deriv import evaluate
from optimize.net.model import Net, cross
from optimize.net.lp import net_linprog as _linprog
from optimize.net.pushing import hub_stiffness_rows, least_push, push_mask, stiff_enough, stiffness_ub

__all__ = ["NetStatics", "NetMassDesign", "design_net_masses", "net_statics", "node_mass_needs", "statics_of"]

#: The central masses keep this share of the linear program's margin from the bounds.
CENTRAL_SLACK = 1e-3
#: :func:`node_mass_needs`: weights balance the forces where the least absolute imbalance (over
#: the force scale) is at most this a row...
WEIGHT_EXACT = 1e-9
#: ...and where they do not, they are worth adding if they leave at most this share of it.
WEIGHT_GAIN = 0.5

#: Where the linear program fails and the balance fixes the tensions and masses, its least
#: squares solution is exact when its residual (over the force scale) is at most this.
LSQ_EXACT = 1e-11


@dataclass
class NetStatics:
    """The linear statics of a net at a target: ``A_T T + A_m m = b``.

    Attributes:
        A_T: (k, m) sparse, force (and moment) per unit tension in each row.
        A_m: (k, m) sparse, force (and moment) per unit rod mass (the weight shares).
        b: (k,) the node hardware's weights (and moments) the rods must hold.
        rows: (k, 2) (node, component): components 0-2 force x, y, z, 3-5 moment x, y, z.
        lengths: (m,) the target's pivot distances.
    """

    A_T: sp.csr_matrix
    A_m: sp.csr_matrix
    b: np.ndarray
    rows: np.ndarray
    lengths: np.ndarray

    def residual(self, tensions: np.ndarray, masses: np.ndarray) -> np.ndarray:
        """(k,) ``A_T T + A_m m - b``: the imbalance per row."""
        return self.A_T @ tensions + self.A_m @ masses - self.b


def statics_of(net: Net, state) -> NetStatics:
    """:class:`NetStatics` of a validated net in a configuration (``NetState``)."""
    ev = evaluate(net, state, full=False)
    g, m = net.g, net.m
    t = net.along / net.lengths
    frac = np.column_stack([1 - t - ev.q, t + ev.q])  # weight share per unit rod weight
    free = ~net.anchored
    body = free & net.body
    ncomp = np.where(free, np.where(body, 6, 3), 0)
    first = np.concatenate([[0], np.cumsum(ncomp)[:-1]])
    k = int(ncomp.sum())
    row_of = np.where(np.arange(6) < ncomp[:, None], first[:, None] + np.arange(6), -1)
    rT, cT, vT, rM, cM, vM = [], [], [], [], [], []
    for end in (0, 1):
        node = net.edges[:, end]
        sign = 1.0 if end == 0 else -1.0  # u points from pivot 0 to pivot 1
        pull = sign * ev.u                # the rod pulls each node toward its other end
        wz = -g * frac[:, end]
        e = np.flatnonzero(free[node])
        rows_e = row_of[node[e]]
        rT.append(rows_e[:, :3])
        cT.append(np.repeat(e[:, None], 3, axis=1))
        vT.append(pull[e])
        rM.append(rows_e[:, 2])
        cM.append(e)
        vM.append(wz[e])
        eb = e[body[node[e]]]
        if eb.size:
            arm = ev.a[eb, end]
            mT = cross(arm, pull[eb])
            wvec = np.zeros((eb.size, 3))
            wvec[:, 2] = wz[eb]
            mM = cross(arm, wvec)
            rb = row_of[node[eb], 3:]
            cb = np.repeat(eb[:, None], 3, axis=1)
            rT.append(rb)
            cT.append(cb)
            vT.append(mT)
            rM.append(rb)
            cM.append(cb)
            vM.append(mM)
    cat = (lambda xs: np.concatenate([np.ravel(x) for x in xs]))
    A_T = sp.csr_matrix((cat(vT), (cat(rT), cat(cT))), shape=(k, m))
    A_m = sp.csr_matrix((cat(vM), (cat(rM), cat(cM))), shape=(k, m))
    b = np.zeros(k)
    rows = np.zeros((k, 2), dtype=int)
    node_c = np.einsum("nab,nb->na", state.R, net.node_com)
    fn = np.flatnonzero(free)
    has = row_of[fn] >= 0
    rows[row_of[fn][has], 0] = np.broadcast_to(fn[:, None], has.shape)[has]
    rows[row_of[fn][has], 1] = np.broadcast_to(np.arange(6), has.shape)[has]
    wz_node = g * net.node_masses[fn]
    b[row_of[fn, 2]] = wz_node
    fb = np.flatnonzero(body[fn])
    if fb.size:
        w = np.zeros((fb.size, 3))
        w[:, 2] = wz_node[fb]
        b[row_of[fn[fb], 3:]] = cross(node_c[fn[fb]], w)
    return NetStatics(A_T, A_m, b, rows, ev.dist.copy())


def net_statics(target_positions, edges, lengths, anchored, *, node_masses=None, com=None, g: float = 9.81,
                node_com=None, pivots=None, rotations=None) -> NetStatics:
    """The linear statics of a net at its target (see the module docstring).

    Args:
        target_positions: (n, 3) the target node points (mm).
        edges, lengths, anchored, node_masses, com, g, node_com, pivots: as
            :func:`optimize.solve_net` (``com`` in mm; the lever rule uses ``along / L``).
        rotations: (n, 3, 3) node bodies' orientations at the target (identity if None).

    Returns:
        NetStatics.
    """
    m = np.asarray(edges).shape[0]
    net, state = Net.from_args(target_positions, edges, lengths, np.ones(m), anchored, node_masses=node_masses,
                               com=com, g=g, node_com=node_com, pivots=pivots, node_rotations0=rotations)
    return statics_of(net, state)


@dataclass
class NetMassDesign:
    """Masses (and tensions) that make a net balance at its target.

    Attributes:
        masses: (m,) rod masses (g), within their bounds.
        tensions: (m,) rod tensions (force) that balance with them.
        exact: the target balances exactly (to round-off) with these masses.
        residual: largest imbalance over the force scale (the larger of the total weight
            and the largest |tension|; moments over that times the mean rod length).
        margin: the linear program's margin: the smallest distance of a mass from its
            bounds (relative to the bounds' width), and of a tension from zero (relative
            to a mid-bound rod's weight), that an exact design can keep; < 0 when none is
            exact.
        at_lower, at_upper: rods whose mass sits at its lower / upper bound.
        slack: rods with (near) zero tension; compressed: rods in compression.
        beyond: (m,) for a target no masses within bounds balance: how far beyond its bounds
            each rod's mass would have to go for an exact balance, relative to the bounds'
            width (> 0 above the upper bound, < 0 below the lower), with every other rod as
            close to its bounds as it can be; zeros when exact.
        needs_compression: rods that would have to push for an exact balance.
        method, message: how the masses were found, and what that means.
    """

    masses: np.ndarray
    tensions: np.ndarray
    exact: bool
    residual: float
    margin: float
    at_lower: np.ndarray
    at_upper: np.ndarray
    slack: np.ndarray
    compressed: np.ndarray
    beyond: np.ndarray
    needs_compression: np.ndarray
    method: str
    message: str
    info: dict = field(default_factory=dict)


def _bounds(mass_bounds, m: int) -> np.ndarray:
    mb = np.asarray(mass_bounds, float)
    if mb.shape == (2,):
        mb = np.broadcast_to(mb, (m, 2)).copy()
    if mb.shape != (m, 2):
        raise ValueError(f"mass_bounds must have shape ({m}, 2) or (2,), got {mb.shape}")
    if not np.all(np.isfinite(mb)) or np.any(mb[:, 0] <= 0) or np.any(mb[:, 1] < mb[:, 0]):
        k = int(np.flatnonzero(~np.isfinite(mb).all(axis=1) | (mb[:, 0] <= 0) | (mb[:, 1] < mb[:, 0]))[0])
        raise ValueError(f"mass_bounds[{k}] must be finite with 0 < lo <= hi, got {mb[k].tolist()}")
    return mb


def design_net_masses(target_positions, edges, lengths, mass_bounds, anchored, *, node_masses=None, com=None,
                      allow_compression: bool | np.ndarray = False, g: float = 9.81, node_com=None, pivots=None,
                      rotations=None, forces_only: bool = False, explain: bool = True,
                      stiff_hubs: bool = True) -> NetMassDesign:
    """Rod masses within bounds that make the target an equilibrium (see the module).

    Args:
        target_positions: (n, 3) target node points (mm).
        edges, lengths, anchored, node_masses, com, g, node_com, pivots: as
            :func:`optimize.solve_net`; ``lengths`` must be the target's pivot distances.
        mass_bounds: (m, 2) [lo, hi] per rod (g), 0 < lo <= hi; or one (2,) pair for all.
        allow_compression: let rods push (T < 0): True every rod, or an (m,) mask of the rods
            that may (e.g. rigid rods whose hardware holds them either way); by default every
            rod stays in tension.
        rotations: (n, 3, 3) node bodies' orientations at the target.
        forces_only: balance the nodes' forces only, not the node bodies' moments (for a
            caller that then turns the bodies' pivots to cancel the moments of these forces).
        explain: where no masses within bounds balance, solve the second linear program
            that says why (``beyond``, ``needs_compression``); False leaves ``beyond`` NaN
            (for a caller that iterates on the best fit and explains only the last).
        stiff_hubs: with a mask of rods that may push, ask their hubs to resist turning
            (:func:`optimize.net.pushing.hub_stiffness_rows`); False leaves it aside (for a
            caller asking whether pushing alone would balance).

    Returns:
        NetMassDesign. E.g. masses of a net hung into its shape come back exactly when
        the bounds hold them.
    """
    m = np.asarray(edges).shape[0]
    net, state = Net.from_args(target_positions, edges, lengths, np.ones(m), anchored, node_masses=node_masses,
                               com=com, g=g, node_com=node_com, pivots=pivots, node_rotations0=rotations)
    if np.max(np.abs(np.linalg.norm(np.diff(state.pivots(net), axis=1)[:, 0], axis=1) - net.lengths)
              / net.lengths) > 1e-9:
        raise ValueError("lengths must be the target's pivot distances (the target is a configuration of the rods)")
    bounds = _bounds(mass_bounds, m)
    st = statics_of(net, state)
    if forces_only:
        keep = st.rows[:, 1] < 3
        st = NetStatics(st.A_T[keep], st.A_m[keep], st.b[keep], st.rows[keep], st.lengths)
    stiff = None
    if stiff_hubs and np.ndim(allow_compression) and np.any(allow_compression):
        stiff = hub_stiffness_rows(net, state, push_mask(allow_compression, m))
    return _design(net, st, bounds, allow_compression, explain, stiff)


def _fixed_solution(A: sp.csr_matrix, b: np.ndarray) -> np.ndarray | None:
    """The least squares solution of ``A x = b`` where ``A`` has full column rank (the normal
    equations, sparse LU, two rounds of iterative refinement), None where it has not."""
    from scipy.sparse.linalg import splu

    if A.shape[0] < A.shape[1]:
        return None
    N = (A.T @ A).tocsc()
    try:
        lu = splu(N)
    except RuntimeError:  # singular: the balance leaves a family of solutions
        return None
    x = lu.solve(A.T @ b)
    for _ in range(2):
        x = x + lu.solve(A.T @ (b - A @ x))
    return x if np.all(np.isfinite(x)) else None


def _scales(net: Net, st: NetStatics, bounds: np.ndarray):
    m_ref = float(np.exp(np.mean(np.log(bounds.mean(axis=1)))))
    F = net.g * m_ref                       # one mid-bound rod's weight
    row = np.where(st.rows[:, 1] < 3, 1.0 / F, 1.0 / (F * net.mean_length))
    return m_ref, F, row


def _design(net: Net, st: NetStatics, bounds: np.ndarray, allow_compression: bool | np.ndarray,
            explain: bool = True, stiff=None) -> NetMassDesign:
    m = net.m
    m_ref, F, row = _scales(net, st, bounds)
    R = sp.diags(row)
    # scaled unknowns: T / F, m / m_ref
    A = sp.hstack([R @ st.A_T * F, R @ st.A_m * m_ref]).tocsr()
    b = row * st.b
    lo_m, hi_m = bounds[:, 0] / m_ref, bounds[:, 1] / m_ref
    width = np.maximum(hi_m - lo_m, 1e-12 * hi_m)
    push = push_mask(allow_compression, m)
    lo_T = np.where(push, -np.inf, 0.0)
    # LP: maximise t with m in [lo + t w, hi - t w] and T >= t (the rods in tension), t in [0, 1/2]
    nv = 2 * m + 1
    c = np.zeros(nv)
    c[-1] = -1.0
    # (and the hubs of rods that push kept from turning: their stiffness at least `need`)
    A_ub, b_ub = stiffness_ub(*_margin_rows(m, 0, lo_m, hi_m, width, push), stiff, m)
    if np.ndim(allow_compression) and push.any():  # (a mask: the rods the hardware holds push no harder than they must)
        lo_T = np.where(push, -least_push(A, b, m, lo_m, hi_m, push, stiff), 0.0)
    lp_args = dict(A_ub=A_ub, b_ub=b_ub,
                   A_eq=sp.hstack([A, sp.csr_matrix((A.shape[0], 1))]).tocsr(), b_eq=b,
                   bounds=[(x, None) for x in np.where(push, lo_T, -np.inf)] + [(None, None)] * m + [(0.0, 0.5)])
    lp = _linprog(c, m, **lp_args)
    info = {"lp_status": int(lp.status)}
    x = _fixed_solution(A, b) if lp.status != 0 else None
    if x is not None:
        # HiGHS has called feasible balances infeasible (more rows than unknowns, which fix the
        # tensions and masses, and buildable masses a few micrograms wide): where the balance
        # fixes the unknowns, its least squares solution has the last word
        tol_m = 1e-9 * width
        if float(np.max(np.abs(A @ x - b), initial=0.0)) <= LSQ_EXACT and np.all(x[m:] >= lo_m - tol_m) \
                and np.all(x[m:] <= hi_m + tol_m) and np.all(x[:m] >= lo_T - LSQ_EXACT) and stiff_enough(stiff, x[:m]):
            info["lstsq"] = True
            x[m:] = np.clip(x[m:], lo_m, hi_m)
            x[:m] = np.where(push, x[:m], np.maximum(x[:m], 0.0))
            t = float(min(np.min((x[m:] - lo_m) / width), np.min((hi_m - x[m:]) / width),
                          np.min(x[:m][~push], initial=np.inf)))
            return _finish(net, st, bounds, x[m:] * m_ref, x[:m] * F, True, t,
                           "least squares on the balance (the linear program failed numerically)", np.zeros(m),
                           np.zeros(0, int), info)
    if lp.status == 0:
        t = float(lp.x[-1])
        s = t * (1 - CENTRAL_SLACK)
        mid = 0.5 * (lo_m + hi_m)
        q = np.concatenate([np.full(m, 1e-6), 1.0 / width ** 2])
        cq = np.concatenate([np.zeros(m), -mid / width ** 2])
        lo = np.concatenate([np.where(push, lo_T, s), lo_m + s * width])
        hi = np.concatenate([np.full(m, np.inf), hi_m - s * width])
        qp = box_qp(q, cq, A, b, lo, hi)
        x = qp.x
        info.update(qp_nit=qp.nit, qp_polished=qp.polished, qp_success=qp.success)
        resid_qp = float(np.max(np.abs(A @ x - b), initial=0.0))
        resid_lp = float(np.max(np.abs(A @ lp.x[:-1] - b), initial=0.0))
        if not qp.success or resid_qp > max(10 * resid_lp, 1e-12) or np.any(x[m:] < lo_m - 1e-12) \
                or np.any(x[m:] > hi_m + 1e-12) or not stiff_enough(stiff, x[:m]):
            x = lp.x[:-1]  # the LP's vertex: exact, less central
            method = "linear program (largest margin)"
        else:
            method = "linear program, then the masses nearest their bounds' middle (quadratic program)"
        masses, tensions = x[m:] * m_ref, x[:m] * F
        return _finish(net, st, bounds, masses, tensions, True, t, method, np.zeros(m), np.zeros(0, int), info)
    # not exact: best fit within bounds, and why
    # best fit: minimise |A x - b|^2 within the bounds, as a QP in (x, r) with A x - r = b
    k = A.shape[0]
    Afit = sp.hstack([A, -sp.identity(k)]).tocsr()
    q = np.concatenate([np.full(2 * m, 1e-9), np.ones(k)])
    lo = np.concatenate([lo_T, lo_m, np.full(k, -np.inf)])
    hi = np.concatenate([np.full(2 * m, np.inf), np.full(k, np.inf)])
    hi[m:2 * m] = hi_m
    fit = box_qp(q, np.zeros(2 * m + k), Afit, b, lo, hi)
    x = fit.x[:2 * m]
    info.update(fit_nit=fit.nit, fit_success=fit.success)
    if explain:
        beyond, needs = _why(A, b, m, lo_m, hi_m, width, push)
    else:
        beyond, needs = np.full(m, np.nan), np.zeros(0, int)
    masses, tensions = x[m:] * m_ref, x[:m] * F
    return _finish(net, st, bounds, masses, tensions, False, -1.0,
                   "bounded least squares on the statics (no masses within bounds balance the target)",
                   beyond, needs, info)


def node_mass_needs(target_positions, edges, lengths, mass_bounds, anchored, extra, *, node_masses=None,
                    com=None, allow_compression: bool | np.ndarray = False, g: float = 9.81, node_com=None,
                    pivots=None, rotations=None, sag=None) -> tuple[np.ndarray, bool] | None:
    """The least weight to add at the nodes (at each node's point, at most ``extra[k]``) for
    masses within their bounds to balance the nodes' forces at the target, keeping half the
    margin from the bounds (and from zero tension) that such weights allow at most; where no
    weights within ``extra`` balance it, the weights of the nearest balance (least absolute
    imbalance), if they leave at most :data:`WEIGHT_GAIN` of the imbalance without them.

    Node weights are the loads that shape a hanging net; a net whose node hardware weighs
    unevenly (a large hub among small ones) may balance with no rod masses, yet balance once
    the light nodes weigh more. Linear programs: the least absolute imbalance with weights within
    ``extra`` (none: they balance it; else the same without weights, to compare); where they
    balance it, the largest margin ``t`` with any such weights (as :func:`design_net_masses`),
    then the least total weight (each relative to its ``extra``) that keeps ``t / 2``. The hubs'
    moments are left aside (their sockets are turned for them afterwards, as with
    ``forces_only``).

    Args:
        extra: (n,) the most weight node ``k`` may take (g; 0: none).
        sag: (n,) bool, nodes whose height follows their load (a joint between two rods placed
            at its sag, which moves with its rods' tensions): their vertical balance is left
            free; None: none.
        the rest: as :func:`design_net_masses`.

    Returns:
        ((n,) the weights (g), whether they balance exactly), or None where none is needed or
        weights within ``extra`` do not bring the balance nearer by that much.
    """
    m = np.asarray(edges).shape[0]
    net, state = Net.from_args(target_positions, edges, lengths, np.ones(m), anchored, node_masses=node_masses,
                               com=com, g=g, node_com=node_com, pivots=pivots, node_rotations0=rotations)
    bounds = _bounds(mass_bounds, m)
    st = statics_of(net, state)
    force = st.rows[:, 1] < 3
    extra = np.asarray(extra, float)
    free = np.flatnonzero((extra > 0) & ~net.anchored)
    if not free.size:
        return None
    m_ref, F, row = _scales(net, st, bounds)
    row = row[force]
    rows = st.rows[force]
    # a node's weight w_k (scaled by its extra) pulls its z row down: A_w w = -g extra_k z
    zrow = np.flatnonzero(rows[:, 1] == 2)
    where = {int(n): int(r) for n, r in zip(rows[zrow, 0], zrow)}
    rk = np.array([where[int(k)] for k in free])
    nw = free.size
    Aw = sp.csr_matrix((-net.g * extra[free] * row[rk], (rk, np.arange(nw))), shape=(rows.shape[0], nw))
    sagging = [where[int(k)] for k in np.flatnonzero(np.zeros(net.n, bool) if sag is None else sag) if int(k) in where]
    keep = np.setdiff1d(np.arange(rows.shape[0]), sagging)  # (a sagging node's vertical row: free)
    R = sp.diags(row)
    A = sp.hstack([R @ st.A_T[force] * F, R @ st.A_m[force] * m_ref, Aw]).tocsr()[keep]
    b = (row * st.b[force])[keep]
    lo_m, hi_m = bounds[:, 0] / m_ref, bounds[:, 1] / m_ref
    push = push_mask(allow_compression, m)
    box = [(-np.inf if p else 0.0, None) for p in push] + list(zip(lo_m, hi_m)) + [(0.0, 1.0)] * nw

    def imbalance(cols: int) -> tuple[float, np.ndarray]:
        k = A.shape[0]
        Ak = sp.hstack([A[:, :cols], sp.identity(k), -sp.identity(k)]).tocsr()
        c = np.concatenate([np.zeros(cols), np.ones(2 * k)])
        lp = _linprog(c, m, A_eq=Ak, b_eq=b, bounds=box[:cols] + [(0.0, None)] * (2 * k))
        return (float(lp.fun), lp.x[:cols]) if lp.status == 0 else (np.inf, np.zeros(cols))

    out = np.zeros(net.n)
    near, x = imbalance(2 * m + nw)
    if near > WEIGHT_EXACT * A.shape[0]:  # (no weights balance it: the nearest, where they help)
        if not near <= WEIGHT_GAIN * imbalance(2 * m)[0]:
            return None
        out[free] = np.clip(x[2 * m:], 0.0, 1.0) * extra[free]
        return out, False
    width = np.maximum(hi_m - lo_m, 1e-12 * hi_m)
    A_ub, b_ub = _margin_rows(m, nw, lo_m, hi_m, width, push)
    A_eq = sp.hstack([A, sp.csr_matrix((A.shape[0], 1))]).tocsr()
    bnds = [(None, None)] * (2 * m) + [(0.0, 1.0)] * nw + [(0.0, 0.5)]
    c = np.zeros(2 * m + nw + 1)
    c[-1] = -1.0
    lp = _linprog(c, m, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=b, bounds=bnds)
    if lp.status == 0:
        bnds[-1] = (0.5 * float(lp.x[-1]), 0.5)
        c = np.zeros(2 * m + nw + 1)
        c[2 * m:2 * m + nw] = 1.0
        lp = _linprog(c, m, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=b, bounds=bnds)
    if lp.status == 0:
        x = lp.x
    out[free] = np.clip(x[2 * m:2 * m + nw], 0.0, 1.0) * extra[free]
    return (out, True) if np.any(out > 0) else None


def _margin_rows(m: int, nw: int, lo_m, hi_m, width, push: np.ndarray) -> tuple[sp.csr_matrix, np.ndarray]:
    """The margin linear program's inequalities over (T, m, ``nw`` more unknowns, t): every mass
    ``t`` widths inside its bounds, and the tension of every rod that may not push (``push``,
    (m,) bool) at least ``t``."""
    I = sp.identity(m, format="csr")
    Z = sp.csr_matrix((m, m))
    more = [sp.csr_matrix((m, nw))] if nw else []
    wcol = sp.csr_matrix(width[:, None])
    rows_ub = [sp.hstack([Z, -I, *more, wcol]), sp.hstack([Z, I, *more, wcol])]
    b_ub = [-lo_m, hi_m]
    pull = np.flatnonzero(~push)
    if pull.size:
        rows_ub.append(sp.hstack([-I[pull], Z[pull], *(x[pull] for x in more), sp.csr_matrix(np.ones((pull.size, 1)))]))
        b_ub.append(np.zeros(pull.size))
    return sp.vstack(rows_ub).tocsr(), np.concatenate(b_ub)


def _why(A, b, m, lo_m, hi_m, width, push):
    """The least total excursion beyond the mass bounds (and into compression, for the rods that
    may not push: ``push`` False) that balances the target exactly: (beyond per rod, relative to
    its width; rods that must push)."""
    # unknowns: T (m), masses (m), p >= 0 over hi, r >= 0 under lo, k >= 0 compression
    c = np.concatenate([np.zeros(2 * m), np.ones(2 * m), np.where(push, 0.0, 1.0)])
    I = sp.identity(m, format="csr")
    Z = sp.csr_matrix((m, m))
    W = sp.diags(width)
    A_ub = sp.vstack([
        sp.hstack([Z, I, -W, Z, Z]),          # m - p w <= hi
        sp.hstack([Z, -I, Z, -W, Z]),         # -m - r w <= -lo
        sp.hstack([-I, Z, Z, Z, -I]),         # -T - k <= 0
    ]).tocsr()
    b_ub = np.concatenate([hi_m, -lo_m, np.zeros(m)])
    A_eq = sp.hstack([A, sp.csr_matrix((A.shape[0], 3 * m))]).tocsr()
    bounds = [(None, None)] * m + [(0.0, None)] * m + [(0.0, None)] * (3 * m)
    lp = _linprog(c, m, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=b, bounds=bounds)
    if lp.status != 0:
        return np.full(m, np.nan), np.zeros(0, int)
    p, r, k = lp.x[2 * m:3 * m], lp.x[3 * m:4 * m], lp.x[4 * m:]
    beyond = np.where(p > 1e-9, p, np.where(r > 1e-9, -r, 0.0))
    needs = np.flatnonzero((k > 1e-9) & ~push)
    return beyond, needs


def _finish(net, st, bounds, masses, tensions, exact, margin, method, beyond, needs, info) -> NetMassDesign:
    lo, hi = bounds[:, 0], bounds[:, 1]
    width = np.maximum(hi - lo, 1e-300)
    at_lower = np.flatnonzero(masses - lo <= 1e-9 * width)
    at_upper = np.flatnonzero(hi - masses <= 1e-9 * width)
    scale = max(net.g * (float(masses.sum()) + float(net.node_masses.sum())),
                float(np.max(np.abs(tensions), initial=0.0)))
    rscale = np.where(st.rows[:, 1] < 3, scale, scale * net.mean_length)
    residual = float(np.max(np.abs(st.residual(tensions, masses)) / rscale, initial=0.0))
    slack = np.flatnonzero(np.abs(tensions) <= 1e-9 * scale)
    compressed = np.flatnonzero(tensions < -1e-9 * scale)
    if exact:
        rest = (f"{compressed.size} rod(s) pushing where they may, the others in tension" if compressed.size else
                "every rod in tension")
        message = (f"Exact: the target balances with every mass within its bounds (margin {margin:.3g} of "
                   f"the bounds' width) and {rest}." if margin > 0 else
                   "Exact, but only with masses on their bounds or rods at zero tension (no margin).")
    else:
        parts = []
        over = np.flatnonzero(beyond > 0)
        under = np.flatnonzero(beyond < 0)
        if over.size:
            parts.append(f"rods {over[:8].tolist()} would need more mass than their upper bound "
                         f"(up to {float(beyond[over].max()):.3g} of the bounds' width beyond)")
        if under.size:
            parts.append(f"rods {under[:8].tolist()} less than their lower bound "
                         f"(up to {float(-beyond[under].min()):.3g} of the width below)")
        if needs.size:
            parts.append(f"rods {needs[:8].tolist()} would have to push (compression)")
        why = "; ".join(parts) if parts else "the statics cannot balance the target"
        message = f"Not exact (best fit, residual {residual:.3g} of the force scale): {why}."
    return NetMassDesign(masses=masses, tensions=tensions, exact=exact, residual=residual, margin=margin,
                         at_lower=at_lower, at_upper=at_upper, slack=slack, compressed=compressed, beyond=beyond,
                         needs_compression=needs, method=method, message=message, info=info)
