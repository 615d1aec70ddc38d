"""A hanging net of rigid rods: the validated problem, its kinematics and derivatives.

Conventions (``shared/design/contract.md``, section "Nets"): ``n`` nodes, ``m`` rods; rod ``e``
joins nodes ``edges[e] = (i, j)``; z is up and gravity acts along -z. Lengths in the
caller's unit (mm), masses in the caller's unit (g), forces in mass x the unit of ``g``
(g with g = 9.81 m/s^2: millinewtons), moments in force x length.

A node is a point (every rod at it pivots about the node point) or a rigid *node body*
(a ring, a hub): a pose (the node point ``x_i`` and a rotation ``R_i``), a mass with a
centre of mass ``node_com[i]`` in the body's frame, and per rod a pivot ``pivots[e, k]``
in the frame of the body at the rod's end ``k`` (0 at node i, 1 at node j). Rod ``e``'s
pivots are ``P_k = x + R pivots[e, k]`` and the rod is rigid: ``|P_1 - P_0| = L_e``.

Rod ``e``'s centre of mass is ``com[e] = (along, perp[, w])`` in its frame (origin ``P_0``,
x toward ``P_1``). A rod turns freely about its own axis (spherical joints at both ends),
so an off-axis centre of mass hangs as low as it can: the roll is eliminated in closed
form, and the rod's potential energy is::

    U_e = g m_e ((1 - t) P0_z + t P1_z - r sqrt(1 - s^2)),  t = along / L, r = |(perp, w)|,
    s = (P1_z - P0_z) / L

(on the constraint manifold, s is the axis's vertical direction cosine). Written this way
the rod's weight reaches its pivots as vertical forces only (the lever rule), and the
multiplier of ``|P_1 - P_0| - L = 0`` is the rod's *tension*: the axial force that joins
those vertical shares at the pivots (for a symmetric rod, the axial force at mid-length).

Unknowns: the free nodes' positions (3 each) and the free node bodies' rotation
increments ``omega`` (3 each, ``R <- exp([omega]x) R``, re-linearised at every step), in
that order. Anchored nodes (and their bodies' orientations) are fixed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, dijkstra

__all__ = ["Net", "NetState", "cross", "rotation_exp", "skew"]

#: Relative tolerance on the length of a rod whose two nodes are both anchored.
FIXED_ROD_TOL = 1e-9


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross(a, b)`` of (..., 3) float arrays, the same arithmetic in the same order (so
    the same bits) without its general axes' overhead: the derivatives take a few hundred
    thousand small ones in a design."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    np.multiply(a[..., 1], b[..., 2], out=out[..., 0])
    out[..., 0] -= a[..., 2] * b[..., 1]
    np.multiply(a[..., 2], b[..., 0], out=out[..., 1])
    out[..., 1] -= a[..., 0] * b[..., 2]
    np.multiply(a[..., 0], b[..., 1], out=out[..., 2])
    out[..., 2] -= a[..., 1] * b[..., 0]
    return out


def skew(a: np.ndarray) -> np.ndarray:
    """(..., 3, 3) cross-product matrices: ``skew(a) @ b == cross(a, b)``."""
    a = np.asarray(a, float)
    out = np.zeros(a.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -a[..., 2], a[..., 1]
    out[..., 1, 0], out[..., 1, 2] = a[..., 2], -a[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -a[..., 1], a[..., 0]
    return out


def rotation_exp(w: np.ndarray) -> np.ndarray:
    """(..., 3, 3) rotation matrices exp([w]x) (Rodrigues), w in radians."""
    w = np.asarray(w, float)
    th = np.linalg.norm(w, axis=-1)[..., None, None]
    K = skew(w)
    small = th < 1e-8
    with np.errstate(invalid="ignore", divide="ignore"):
        a = np.where(small, 1.0 - th ** 2 / 6, np.sin(th) / np.where(small, 1.0, th))
        b = np.where(small, 0.5 - th ** 2 / 24, (1 - np.cos(th)) / np.where(small, 1.0, th ** 2))
    return np.eye(3) + a * K + b * (K @ K)


def _as_array(name: str, value, shape: tuple, dtype=float) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=dtype)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be an array of numbers of shape {shape} ({exc})") from None
    if arr.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {arr.shape}")
    if dtype is float and not np.all(np.isfinite(arr)):
        k = np.argwhere(~np.isfinite(arr))[0]
        raise ValueError(f"{name}[{', '.join(map(str, k))}] is not finite")
    return arr


@dataclass
class Net:
    """A validated net problem (arrays in, arrays out; see the module docstring).

    Attributes:
        edges: (m, 2) node indices of each rod's ends 0 and 1.
        lengths: (m,) pivot-to-pivot lengths L_e.
        masses: (m,) rod masses (>= 0, their sum with the node masses > 0).
        com: (m, 3) each rod's centre of mass (along, perp, w) in its own frame.
        anchored: (n,) True where a node is held (its body's orientation too).
        node_masses: (n,) point or body masses at the nodes (>= 0).
        node_com: (n, 3) each node body's centre of mass from the node point, body frame.
        pivots: (m, 2, 3) each rod end's pivot from its node point, that node's body frame.
        g: gravitational acceleration, along -z.
    """

    edges: np.ndarray
    lengths: np.ndarray
    masses: np.ndarray
    com: np.ndarray
    anchored: np.ndarray
    node_masses: np.ndarray
    node_com: np.ndarray
    pivots: np.ndarray
    g: float

    def __post_init__(self) -> None:
        n, m = self.anchored.size, self.lengths.size
        self.n, self.m = n, m
        e = self.edges
        # a node is a body when its orientation matters: a pivot off the node point, or
        # an off-centre mass
        offset = np.zeros(n, dtype=bool)
        np.logical_or.at(offset, e[:, 0], np.any(self.pivots[:, 0] != 0, axis=1))
        np.logical_or.at(offset, e[:, 1], np.any(self.pivots[:, 1] != 0, axis=1))
        offset |= np.any(self.node_com != 0, axis=1) & (self.node_masses > 0)
        self.body = offset
        free = ~self.anchored
        self.pos_idx = np.full(n, -1)
        nf = int(free.sum())
        self.pos_idx[free] = 3 * np.arange(nf)
        fb = free & self.body
        self.rot_idx = np.full(n, -1)
        self.rot_idx[fb] = 3 * nf + 3 * np.arange(int(fb.sum()))
        self.nvar = 3 * nf + 3 * int(fb.sum())
        # per rod, the global index of each of its local unknowns, or -1 (fixed): (x0, x1)
        # for a net of point nodes, (x0, w0, x1, w1) when it has node bodies
        self.has_bodies = bool(fb.any())
        per_end = 6 if self.has_bodies else 3
        loc = np.full((m, 2 * per_end), -1)
        for k in (0, 1):
            node = e[:, k]
            p, r = self.pos_idx[node], self.rot_idx[node]
            for c in range(3):
                loc[:, per_end * k + c] = np.where(p >= 0, p + c, -1)
                if self.has_bodies:
                    loc[:, per_end * k + 3 + c] = np.where(r >= 0, r + c, -1)
        self.loc = loc
        self.per_end = per_end
        self.along = self.com[:, 0]
        self.radius = np.hypot(self.com[:, 1], self.com[:, 2])
        self.total_mass = float(self.masses.sum() + self.node_masses.sum())
        self.weight = self.g * self.total_mass
        self.mean_length = float(np.mean(self.lengths))
        # unknowns' scale: 1 for positions, a length^2 for rotations (proximal terms)
        self.var_scale = np.ones(self.nvar)
        self.var_scale[3 * nf:] = self.mean_length ** 2
        self.pattern = None  # the sparsity patterns, built by optimize.net.deriv on first use
        self.turning_parts = None  # parts hung from one vertical line of anchors (optimize.net.deriv)
        self.body_spins = None  # node bodies that spin about the line of their pivots, own frames (same)

    @classmethod
    def from_args(cls, node_positions0, edges, lengths, masses, anchored, *, node_masses=None, com=None,
                  g=9.81, node_com=None, pivots=None, node_rotations0=None) -> tuple["Net", "NetState"]:
        """Validate the arguments of :func:`optimize.solve_net`; the problem and its start."""
        try:
            pos = np.asarray(node_positions0, dtype=float)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"node_positions0 must be an (n, 3) array of numbers ({exc})") from None
        if pos.ndim != 2 or pos.shape[1] != 3 or pos.shape[0] < 2:
            raise ValueError(f"node_positions0 must have shape (n, 3) with n >= 2, got {pos.shape}")
        n = pos.shape[0]
        pos = _as_array("node_positions0", pos, (n, 3))
        try:
            edges = np.asarray(edges)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"edges must be an (m, 2) array of node indices ({exc})") from None
        if edges.ndim != 2 or edges.shape[1] != 2 or edges.shape[0] < 1:
            raise ValueError(f"edges must have shape (m, 2) with m >= 1, got {edges.shape}")
        if not np.issubdtype(edges.dtype, np.integer):
            if not np.all(np.isfinite(edges.astype(float))) or np.any(edges != np.round(edges)):
                raise ValueError("edges must hold integer node indices")
        edges = edges.astype(int)
        m = edges.shape[0]
        bad = np.flatnonzero((edges < 0).any(axis=1) | (edges >= n).any(axis=1))
        if bad.size:
            raise ValueError(f"edges[{bad[0]}] = {edges[bad[0]].tolist()} names a node outside 0..{n - 1}")
        bad = np.flatnonzero(edges[:, 0] == edges[:, 1])
        if bad.size:
            raise ValueError(f"edges[{bad[0]}] joins node {edges[bad[0], 0]} to itself")
        lengths = _as_array("lengths", lengths, (m,))
        if np.any(lengths <= 0):
            k = int(np.flatnonzero(lengths <= 0)[0])
            raise ValueError(f"lengths[{k}] must be positive, got {lengths[k]}")
        masses = _as_array("masses", masses, (m,))
        if np.any(masses < 0):
            k = int(np.flatnonzero(masses < 0)[0])
            raise ValueError(f"masses[{k}] must not be negative, got {masses[k]}")
        anchored = np.asarray(anchored)
        if anchored.dtype == bool:
            if anchored.shape != (n,):
                raise ValueError(f"anchored as a mask must have shape ({n},), got {anchored.shape}")
            mask = anchored.copy()
        else:
            idx = anchored.reshape(-1)
            if idx.size and (not np.issubdtype(idx.dtype, np.integer) and np.any(idx != np.round(idx))):
                raise ValueError("anchored must list node indices (or be a boolean mask)")
            idx = idx.astype(int)
            if np.any((idx < 0) | (idx >= n)):
                raise ValueError(f"anchored names a node outside 0..{n - 1}: {idx[(idx < 0) | (idx >= n)][0]}")
            mask = np.zeros(n, dtype=bool)
            mask[idx] = True
        if not mask.any():
            raise ValueError("anchored is empty: a net needs at least one anchored node to hang from")
        node_masses = np.zeros(n) if node_masses is None else _as_array("node_masses", node_masses, (n,))
        if np.any(node_masses < 0):
            k = int(np.flatnonzero(node_masses < 0)[0])
            raise ValueError(f"node_masses[{k}] must not be negative, got {node_masses[k]}")
        if com is None:
            com3 = np.column_stack([lengths / 2, np.zeros(m), np.zeros(m)])
        else:
            c = np.asarray(com, dtype=float)
            if c.ndim == 2 and c.shape == (m, 2):
                c = np.column_stack([c, np.zeros(m)])
            com3 = _as_array("com", c, (m, 3))
        node_com = np.zeros((n, 3)) if node_com is None else _as_array("node_com", node_com, (n, 3))
        pivots = np.zeros((m, 2, 3)) if pivots is None else _as_array("pivots", pivots, (m, 2, 3))
        if node_rotations0 is None:
            rot = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
        else:
            rot = _as_array("node_rotations0", node_rotations0, (n, 3, 3))
            err = np.abs(rot @ np.swapaxes(rot, 1, 2) - np.eye(3)).max(axis=(1, 2))
            if np.any(err > 1e-6) or np.any(np.linalg.det(rot) <= 0):
                k = int(np.flatnonzero((err > 1e-6) | (np.linalg.det(rot) <= 0))[0])
                raise ValueError(f"node_rotations0[{k}] is not a rotation matrix")
            u, _, vt = np.linalg.svd(rot)  # re-orthonormalise to round-off
            rot = u @ vt
        g = float(g)
        if not np.isfinite(g) or g <= 0:
            raise ValueError(f"g must be positive and finite, got {g}")
        if masses.sum() + node_masses.sum() <= 0:
            raise ValueError("the net has no mass: masses and node_masses are all zero")
        net = cls(edges=edges, lengths=lengths, masses=masses, com=com3, anchored=mask,
                  node_masses=node_masses, node_com=node_com, pivots=pivots, g=g)
        state = NetState(pos.copy(), rot)
        net.check_topology(state)
        return net, state

    def check_topology(self, state: "NetState") -> None:
        """ValueError when a free node has no rod, a part of the net hangs from no anchor,
        a rod between two anchored nodes does not fit between them, or two anchors are
        farther apart than any path of rods between them can reach."""
        n, e = self.n, self.edges
        deg = np.bincount(e.ravel(), minlength=n)
        lonely = np.flatnonzero((deg == 0) & ~self.anchored)
        if lonely.size:
            raise ValueError(f"node {lonely[0]} is not anchored and no rod reaches it")
        free_edges = ~(self.anchored[e[:, 0]] & self.anchored[e[:, 1]])
        # components of the graph where anchored nodes are split per rod: a free part must
        # touch an anchor
        adj = sp.coo_matrix((np.ones(int(free_edges.sum())), (e[free_edges, 0], e[free_edges, 1])), shape=(n, n))
        ncomp, label = connected_components(adj, directed=False)
        has_anchor = np.zeros(ncomp, dtype=bool)
        has_anchor[label[self.anchored]] = True
        bad = np.flatnonzero(~has_anchor[label] & ~self.anchored)
        if bad.size:
            raise ValueError(f"node {bad[0]} hangs from no anchored node (its part of the net would fall)")
        P = state.pivots(self)
        both = np.flatnonzero(~free_edges)
        for k in both:
            dist = float(np.linalg.norm(P[k, 1] - P[k, 0]))
            if abs(dist - self.lengths[k]) > FIXED_ROD_TOL * self.lengths[k]:
                i, j = e[k]
                raise ValueError(f"rod {k} joins anchored nodes {i} and {j} whose pivots are {dist:.6g} apart, "
                                 f"not its length {self.lengths[k]:.6g}")
        reach = self.lengths + np.linalg.norm(self.pivots[:, 0], axis=1) + np.linalg.norm(self.pivots[:, 1], axis=1)
        w = sp.coo_matrix((reach, (e[:, 0], e[:, 1])), shape=(n, n)).tocsr()
        anchors = np.flatnonzero(self.anchored)
        if anchors.size > 1 and anchors.size <= 400:
            dist = dijkstra(w, directed=False, indices=anchors)[:, anchors]
            gap = np.linalg.norm(state.x[anchors][:, None] - state.x[anchors][None], axis=2)
            over = np.isfinite(dist) & (gap > dist * (1 + 1e-12))
            if over.any():
                a, b = np.argwhere(over)[0]
                raise ValueError(f"anchored nodes {anchors[a]} and {anchors[b]} are {gap[a, b]:.6g} apart, farther "
                                 f"than the shortest path of rods between them ({dist[a, b]:.6g}) can reach")


@dataclass
class NetState:
    """A configuration: node points x (n, 3) and node body orientations R (n, 3, 3)."""

    x: np.ndarray
    R: np.ndarray

    def copy(self) -> "NetState":
        return NetState(self.x.copy(), self.R.copy())

    def offsets(self, net: Net) -> np.ndarray:
        """(m, 2, 3) each pivot's offset from its node point, world frame."""
        return np.einsum("mkab,mkb->mka", self.R[net.edges], net.pivots)

    def pivots(self, net: Net) -> np.ndarray:
        """(m, 2, 3) the rods' pivot points, world frame."""
        return self.x[net.edges] + self.offsets(net)

    def moved(self, net: Net, dy: np.ndarray) -> "NetState":
        """The state moved by the step ``dy`` (positions added, rotations composed)."""
        out = self.copy()
        free = net.pos_idx >= 0
        out.x[free] += dy[net.pos_idx[free][:, None] + np.arange(3)]
        bodies = net.rot_idx >= 0
        if bodies.any():
            w = dy[net.rot_idx[bodies][:, None] + np.arange(3)]
            out.R[bodies] = rotation_exp(w) @ out.R[bodies]
        return out


