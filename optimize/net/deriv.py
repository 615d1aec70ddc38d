"""The net's energy, constraints and their derivatives, on fixed sparsity patterns.

See :mod:`optimize.net.model` for the model. Every rod couples only the unknowns of its two
nodes (``Net.loc``: positions, and rotation increments at node bodies), so the constraint
Jacobian J (m x nvar), the Hessian of the Lagrangian H and the Newton matrix
``H + mu D + rho J'J`` are assembled from per-rod local blocks into patterns built once
per net (:class:`Pattern`): an iteration costs a few ``bincount`` calls, no sparse
construction. For a pivot on a node body, ``P = x + exp([w]x) a`` gives ``dP/dx = I``,
``dP/dw = -[a]x`` and, for a force ``G`` conjugate to P, the second-order term
``sym(G a') - (G.a) I`` in ``w``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from optimize.net.model import Net, NetState, cross, skew

__all__ = [
    "Hess",
    "NetEval",
    "Pattern",
    "assemble",
    "energy_change",
    "evaluate",
    "gauge_rows",
    "hessian",
    "pattern",
    "rod_frames",
]


@dataclass
class Pattern:
    """Sparsity patterns of J (CSR) and of the symmetric nvar x nvar matrices (CSC), and
    where each local entry goes in their data arrays."""

    j_indices: np.ndarray
    j_indptr: np.ndarray
    j_pos: np.ndarray        # (m, nloc) position in J's data, -1 where the unknown is fixed
    k_indices: np.ndarray
    k_indptr: np.ndarray
    k_pos: np.ndarray        # (m, nloc, nloc) position in K's data, or -1
    k_diag: np.ndarray       # (nvar,) positions of the diagonal
    k_body: np.ndarray       # (nbodies, 3, 3) positions of each free body's rotation block
    bodies: np.ndarray       # the free node bodies
    gram: object = None      # J J' on J's pattern (optimize.gram.Gram), made when first needed


def _csx(keys: np.ndarray, nrow: int, ncol: int):
    """(indices, indptr, inverse) of a compressed pattern from keys major * ncol + minor."""
    uniq, inv = np.unique(keys, return_inverse=True)
    major, minor = np.divmod(uniq, ncol)
    indptr = np.concatenate([[0], np.cumsum(np.bincount(major, minlength=nrow))])
    return minor.astype(np.int32), indptr.astype(np.int32), inv


def pattern(net: Net) -> Pattern:
    """The net's patterns (built on first use and kept on the net)."""
    if getattr(net, "pattern", None) is not None:
        return net.pattern
    m, nvar, loc = net.m, net.nvar, net.loc
    nloc = loc.shape[1]
    keep = loc >= 0
    rows = np.broadcast_to(np.arange(m)[:, None], loc.shape)
    ji, jp, inv = _csx(rows[keep] * nvar + loc[keep], m, nvar)
    j_pos = np.full(loc.shape, -1)
    j_pos[keep] = inv
    pair = keep[:, :, None] & keep[:, None, :]
    r = np.broadcast_to(loc[:, :, None], (m, nloc, nloc))
    c = np.broadcast_to(loc[:, None, :], (m, nloc, nloc))
    diag = np.arange(nvar)
    bodies = np.flatnonzero(net.rot_idx >= 0)
    bidx = net.rot_idx[bodies][:, None] + np.arange(3)
    br = np.broadcast_to(bidx[:, :, None], (bodies.size, 3, 3))
    bc = np.broadcast_to(bidx[:, None, :], (bodies.size, 3, 3))
    # column-major keys (CSC); the matrices are symmetric, so CSC of K is CSR of K
    keys = np.concatenate([c[pair] * nvar + r[pair], diag * nvar + diag, (bc * nvar + br).ravel()])
    ki, kp, inv = _csx(keys, nvar, nvar)
    npair = int(pair.sum())
    k_pos = np.full((m, nloc, nloc), -1)
    k_pos[pair] = inv[:npair]
    k_diag = inv[npair:npair + nvar]
    k_body = inv[npair + nvar:].reshape(bodies.size, 3, 3)
    net.pattern = Pattern(ji, jp, j_pos, ki, kp, k_pos, k_diag, k_body, bodies)
    return net.pattern


@dataclass
class NetEval:
    """The energy, constraints and (when ``full``) first derivatives at one state.

    Attributes:
        a: (m, 2, 3) pivot offsets from the node points (world); P: (m, 2, 3) pivots.
        dist: (m,) pivot distances; u: (m, 3) unit axes P0 -> P1; c: (m,) dist - L.
        s: (m,) (P1_z - P0_z) / L; q: (m,) the off-axis term's slope r s / (L sqrt(1 - s^2)).
        shares: (m, 2) the vertical weight share of each pivot (force).
        energy: potential energy; energy_scale: the sum of its terms' magnitudes (round-off).
        grad: (nvar,) gradient of the energy; Jloc: (m, nloc) the rods' Jacobian rows in
            their local unknowns; J: (m, nvar) constraint Jacobian (CSR, built when first
            read: most evaluations need only ``Jloc`` and :meth:`jt`). None unless full.
    """

    a: np.ndarray
    P: np.ndarray
    dist: np.ndarray
    u: np.ndarray
    c: np.ndarray
    s: np.ndarray
    q: np.ndarray
    shares: np.ndarray
    energy: float
    energy_scale: float
    grad: np.ndarray | None = None
    Jloc: np.ndarray | None = None
    #: the pattern J is assembled on and the net's local unknowns (set with Jloc)
    pattern: Pattern | None = field(default=None, repr=False)
    loc: np.ndarray | None = field(default=None, repr=False)
    _J: sp.csr_matrix | None = field(default=None, repr=False)

    @property
    def J(self) -> sp.csr_matrix | None:
        if self._J is None and self.Jloc is not None:
            pat, keep = self.pattern, self.loc >= 0
            data = np.zeros(pat.j_indices.size)
            data[pat.j_pos[keep]] = self.Jloc[keep]
            shape = (self.loc.shape[0], pat.k_indptr.size - 1)  # (m, nvar)
            self._J = sp.csr_matrix((data, pat.j_indices, pat.j_indptr), shape=shape)
        return self._J

    def jt(self, v: np.ndarray) -> np.ndarray:
        """J' v (nvar,), summed rod by rod as ``J.T @ v`` sums it (the same bits), without J."""
        keep = self.loc >= 0
        return np.bincount(self.loc[keep], weights=(self.Jloc * v[:, None])[keep],
                           minlength=self.pattern.k_indptr.size - 1).astype(float, copy=False)


def _to_local(net: Net, a: np.ndarray, GP: np.ndarray) -> np.ndarray:
    """(m, nloc): pivot forces GP (m, 2, 3) as forces on the local unknowns."""
    if net.per_end == 3:
        return GP.reshape(net.m, 6)
    out = np.empty((net.m, 12))
    for k in (0, 1):
        out[:, 6 * k:6 * k + 3] = GP[:, k]
        out[:, 6 * k + 3:6 * k + 6] = cross(a[:, k], GP[:, k])  # (-[a]x)' G = a x G
    return out


def evaluate(net: Net, state: NetState, full: bool = True) -> NetEval:
    """Energy, constraints and, when ``full``, gradient and Jacobian at ``state``."""
    g, L = net.g, net.lengths
    a = state.offsets(net) if net.has_bodies or net.body.any() else np.zeros((net.m, 2, 3))
    P = state.x[net.edges] + a
    d = P[:, 1] - P[:, 0]
    dist = np.sqrt(np.einsum("ij,ij->i", d, d))
    u = d / dist[:, None]
    c = dist - L
    s = np.clip(d[:, 2] / L, -1 + 1e-12, 1 - 1e-12)
    root = np.sqrt(1 - s * s)
    q = net.radius * s / (L * root)
    t = net.along / L
    gm = g * net.masses
    node_c = np.einsum("nab,nb->na", state.R, net.node_com)
    energy = float(np.sum(gm * ((1 - t) * P[:, 0, 2] + t * P[:, 1, 2] - net.radius * root))
                   + np.sum(g * net.node_masses * (state.x[:, 2] + node_c[:, 2])))
    scale = float(np.sum(gm * (np.abs(P[:, :, 2]).sum(axis=1) + net.radius))
                  + np.sum(g * net.node_masses * (np.abs(state.x[:, 2]) + np.abs(node_c[:, 2]))))
    shares = np.column_stack([gm * (1 - t - q), gm * (t + q)])
    ev = NetEval(a=a, P=P, dist=dist, u=u, c=c, s=s, q=q, shares=shares, energy=energy, energy_scale=scale)
    if not full:
        return ev
    pat = pattern(net)
    GP = np.zeros((net.m, 2, 3))
    GP[:, :, 2] = shares
    keep = net.loc >= 0
    grad = np.bincount(net.loc[keep], weights=_to_local(net, a, GP)[keep], minlength=net.nvar).astype(float)
    wz = g * net.node_masses
    free = net.pos_idx >= 0
    grad[net.pos_idx[free] + 2] += wz[free]
    b = pat.bodies
    if b.size:
        w = np.zeros((b.size, 3))
        w[:, 2] = wz[b]
        grad[net.rot_idx[b][:, None] + np.arange(3)] += cross(node_c[b], w)
    Gc = np.stack([-u, u], axis=1)
    ev.grad = grad
    ev.Jloc = _to_local(net, a, Gc)
    ev.pattern, ev.loc = pat, net.loc
    return ev


def energy_change(net: Net, old: NetState, old_ev: NetEval, new: NetState, new_ev: NetEval) -> float:
    """U(new) - U(old), summed term by term from coordinate differences (accurate to the
    round-off of the change, not of the energies, which carry a large constant)."""
    dP = new_ev.P - old_ev.P
    t = net.along / net.lengths
    s0, s1 = old_ev.s, new_ev.s
    droot = (s0 - s1) * (s0 + s1) / (np.sqrt(1 - s0 * s0) + np.sqrt(1 - s1 * s1))
    rods = net.g * net.masses * ((1 - t) * dP[:, 0, 2] + t * dP[:, 1, 2] - net.radius * droot)
    dz = new.x[:, 2] - old.x[:, 2] + np.einsum("nb,nb->n", new.R[:, 2] - old.R[:, 2], net.node_com)
    return float(np.sum(rods) + np.sum(net.g * net.node_masses * dz))


def _body_second_order(w: np.ndarray, a: np.ndarray) -> np.ndarray:
    """(..., 3, 3) Hessian in omega of w . exp([omega]x) a at omega = 0."""
    outer = w[..., :, None] * a[..., None, :]
    dot = np.sum(w * a, axis=-1)[..., None, None]
    return 0.5 * (outer + np.swapaxes(outer, -1, -2)) - dot * np.eye(3)


@dataclass
class Hess:
    """The Hessian of the Lagrangian as per-rod local blocks (m, nloc, nloc) and the free
    node bodies' own rotation blocks (nbodies, 3, 3)."""

    local: np.ndarray
    body: np.ndarray


def hessian(net: Net, state: NetState, ev: NetEval, lam: np.ndarray) -> Hess:
    """Hessian of the Lagrangian U + sum lam_e c_e in the unknowns (as local blocks)."""
    m, u = net.m, ev.u
    proj = (np.eye(3) - u[:, :, None] * u[:, None, :]) * (lam / ev.dist)[:, None, None]
    HP = np.empty((m, 6, 6))
    HP[:, :3, :3] = proj
    HP[:, 3:, 3:] = proj
    HP[:, :3, 3:] = -proj
    HP[:, 3:, :3] = -proj
    root = np.sqrt(1 - ev.s ** 2)
    curv = net.g * net.masses * net.radius / (net.lengths ** 2 * root ** 3)
    HP[:, 2, 2] += curv
    HP[:, 5, 5] += curv
    HP[:, 2, 5] -= curv
    HP[:, 5, 2] -= curv
    pat = pattern(net)
    if net.per_end == 3:
        return Hess(HP, np.zeros((0, 3, 3)))
    B = np.zeros((m, 6, 12))
    for k in (0, 1):
        B[:, 3 * k:3 * k + 3, 6 * k:6 * k + 3] = np.eye(3)
        B[:, 3 * k:3 * k + 3, 6 * k + 3:6 * k + 6] = -skew(ev.a[:, k])
    local = np.swapaxes(B, 1, 2) @ HP @ B
    GP = np.zeros((m, 2, 3))
    GP[:, :, 2] = ev.shares
    GP[:, 0] -= lam[:, None] * u
    GP[:, 1] += lam[:, None] * u
    for k in (0, 1):
        local[:, 6 * k + 3:6 * k + 6, 6 * k + 3:6 * k + 6] += _body_second_order(GP[:, k], ev.a[:, k])
    b = pat.bodies
    node_c = np.einsum("nab,nb->na", state.R[b], net.node_com[b])
    w = np.zeros((b.size, 3))
    w[:, 2] = net.g * net.node_masses[b]
    return Hess(local, _body_second_order(w, node_c))


def assemble(net: Net, hess: Hess, ev: NetEval | None = None, *, rho: float = 0.0, diag=None) -> sp.csc_matrix:
    """H + rho J'J + diag(diag) as a CSC matrix on the net's pattern (rho needs ``ev``)."""
    pat = pattern(net)
    local = hess.local
    if rho:
        local = local + rho * (ev.Jloc[:, :, None] * ev.Jloc[:, None, :])
    keep = pat.k_pos >= 0
    data = np.bincount(pat.k_pos[keep], weights=local[keep], minlength=pat.k_indices.size).astype(float)
    if hess.body.size:
        data += np.bincount(pat.k_body.ravel(), weights=hess.body.ravel(), minlength=data.size)
    if diag is not None:
        data[pat.k_diag] += diag
    return sp.csc_matrix((data, pat.k_indices, pat.k_indptr), shape=(net.nvar, net.nvar))


def gauge_rows(net: Net, state: NetState, ev: NetEval) -> np.ndarray:
    """Unknowns to hold still, one per exact symmetry of the net (indices into the unknowns).

    Two symmetries leave the energy and every constraint unchanged, so the Hessian of the
    Lagrangian is singular along them on the tangent space: a part of the net that hangs
    from anchor points on one vertical line turns freely about that line, and a node body
    whose pivots and centre of mass lie on one line spins freely about it. Holding the one
    unknown each moves most removes the direction without changing the equilibrium found
    (any other hyperplane across the symmetry would do).
    """
    out: list[int] = []
    size = net.mean_length
    for nodes, p0 in _turning_parts(net, ev):
        xi = np.zeros(net.nvar)
        gen = np.cross([0.0, 0.0, 1.0], state.x[nodes] - p0)
        xi[net.pos_idx[nodes][:, None] + np.arange(3)] = gen
        body_nodes = nodes[net.rot_idx[nodes] >= 0]
        xi[net.rot_idx[body_nodes] + 2] = size  # a turn about z, scaled to a length
        k = int(np.argmax(np.abs(xi)))
        if abs(xi[k]) > 1e-9 * size:
            out.append(k)
    for node, p0, axes in _spinning_bodies(net, state):  # bodies that spin about the line of their pivots
        for axis in axes:
            # the body turns by 'axis' about p0: its node point moves by axis x (-p0)
            xi = np.zeros(net.nvar)
            xi[net.rot_idx[node] + np.arange(3)] = axis * size
            if net.pos_idx[node] >= 0:
                xi[net.pos_idx[node] + np.arange(3)] = np.cross(axis, -p0)
            xi[out] = 0.0  # already held
            out.append(int(np.argmax(np.abs(xi))))
    return np.array(sorted(set(out)), dtype=int)


def _turning_parts(net: Net, ev: NetEval) -> list:
    """The parts of the net (free nodes joined by rods) that hang from anchor pivots on one
    vertical line: (their nodes, the first of those pivots). Anchors neither move nor turn, so
    the parts are found once per net (kept on it)."""
    if net.turning_parts is not None:
        return net.turning_parts
    out = []
    n, e = net.n, net.edges
    anch = net.anchored
    free_edge = ~(anch[e[:, 0]] & anch[e[:, 1]])
    inner = ~anch[e[:, 0]] & ~anch[e[:, 1]]
    adj = sp.coo_matrix((np.ones(int(inner.sum())), (e[inner, 0], e[inner, 1])), shape=(n, n))
    ncomp, label = connected_components(adj, directed=False)
    for comp in range(ncomp):
        nodes = np.flatnonzero((label == comp) & ~anch)
        if nodes.size == 0:
            continue
        pts = []  # the anchor pivots this part hangs from
        for k in (0, 1):
            hit = free_edge & anch[e[:, k]] & (label[e[:, 1 - k]] == comp) & ~anch[e[:, 1 - k]]
            pts.append(ev.P[hit, k])
        pts = np.concatenate(pts)
        if pts.size == 0 or np.max(np.abs(pts[:, :2] - pts[0, :2])) > 1e-9 * net.mean_length:
            continue
        out.append((nodes, pts[0].copy()))
    net.turning_parts = out
    return out


def _spinning_bodies(net: Net, state: NetState) -> list:
    """The free node bodies whose pivots (and centre of mass) lie on one line or at one
    point, ascending: (node, its first point, the axes it spins about (k, 3)), world frame.

    Which bodies spin, and about what axes in their own frames, does not change as they turn:
    it is found once per net (:func:`_body_spins`, kept on it) and turned by each body's
    orientation here."""
    return [(node, state.R[node] @ p0, axes @ state.R[node].T) for node, p0, axes in _body_spins(net)]


def _body_spins(net: Net) -> list:
    """:func:`_spinning_bodies` in the bodies' own frames (kept on the net).

    A body spins about the null space of the cross-product matrices of its points less its
    first; the singular value decompositions run batched, the bodies of one number of points
    at a time (a net of a thousand hubs: one call each for its 2-, 3- and 4-rod hubs)."""
    if net.body_spins is not None:
        return net.body_spins
    bodies = pattern(net).bodies
    if bodies.size == 0:
        net.body_spins = []
        return net.body_spins
    e = net.edges
    is_body = np.zeros(net.n, dtype=bool)
    is_body[bodies] = True
    # each body's points: its rods' pivots at end 0 in rod order, at end 1, then its centre of mass
    node_of = np.concatenate([e[:, 0], e[:, 1]])
    pts = np.concatenate([net.pivots[:, 0], net.pivots[:, 1]])
    keep = np.flatnonzero(is_body[node_of])
    heavy = bodies[net.node_masses[bodies] > 0]
    owner = np.concatenate([node_of[keep], heavy])
    pts = np.concatenate([pts[keep], net.node_com[heavy]])
    order = np.argsort(owner, kind="stable")
    owner, pts = owner[order], pts[order]
    count = np.bincount(owner, minlength=net.n)
    first = np.concatenate([[0], np.cumsum(count)[:-1]])
    found: dict[int, tuple] = {}
    for c in np.unique(count[bodies]):
        group = bodies[count[bodies] == c]
        P = pts[first[group][:, None] + np.arange(c)]          # (nb, c, 3)
        rel = P - P[:, :1]
        _, sv, vt = np.linalg.svd(skew(rel).reshape(group.size, 3 * c, 3))
        tol = 1e-9 * np.maximum(net.mean_length, np.max(np.abs(rel), axis=(1, 2), initial=0.0))
        rank = np.sum(sv > tol[:, None], axis=1)
        for q in np.flatnonzero(rank < 3):
            found[int(group[q])] = (P[q, 0], vt[q, rank[q]:])
    net.body_spins = [(node, *found[node]) for node in sorted(found)]
    return net.body_spins


def rod_frames(net: Net, ev: NetEval) -> np.ndarray:
    """(m, 3, 3) each rod's frame as rows (x, y, z) in world coordinates.

    x runs from pivot 0 to pivot 1; the rod has turned about x so that its centre of mass
    ``(along, perp, w)`` hangs lowest: ``perp y + w z`` points straight down across the axis.
    With no offset, y is that downward direction. A vertical rod takes y along the world's
    x (or y) projected off its axis.
    """
    x = ev.u
    down = np.array([0.0, 0.0, -1.0])
    v = down - x * (x @ down)[:, None]
    nv = np.linalg.norm(v, axis=1)
    vertical = nv < 1e-9
    if vertical.any():
        alt = np.where(np.abs(x[vertical, 0:1]) < 0.9, np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))
        alt = alt - x[vertical] * np.sum(alt * x[vertical], axis=1)[:, None]
        v[vertical] = alt
        nv[vertical] = np.linalg.norm(alt, axis=1)
    v /= nv[:, None]
    vperp = np.cross(x, v)
    r = net.radius
    safe = np.where(r > 0, r, 1.0)
    cos = np.where(r > 0, net.com[:, 1] / safe, 1.0)
    sin = np.where(r > 0, net.com[:, 2] / safe, 0.0)
    y = cos[:, None] * v - sin[:, None] * vperp
    return np.stack([x, y, np.cross(x, y)], axis=1)
