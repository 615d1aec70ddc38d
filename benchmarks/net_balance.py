"""An independent equilibrium of a written net: design.json's rods, masses and hubs solved again
by a method of its own, from a perturbed start, with no rodcad or optimize code (numpy, scipy).

rodcad's solver minimises the potential energy under the rods' length constraints (Newton on
the KKT system with analytic second derivatives, :mod:`optimize.net.newton`). This one solves
the balance equations themselves, a square nonlinear system, by Newton's method with a
finite-difference Jacobian (columns grouped by the system's sparsity) and a backtracking line
search on the residual:

- unknowns: every free node's position, every free hub's rotation (a rotation vector composed
  onto the current rotation, reset after every step), every rod's tension;
- per free node, its force balance: each rod e at its pivot pulls with ``T_e u_e`` (``u_e``
  from that pivot toward the rod's other pivot) less its share of the rod's weight by the lever
  rule (``1 - t`` at its first end, ``t`` at its second, ``t = along / L``: straight rods,
  their centre of mass on the axis), plus the hub's own weight;
- per free hub, its moment balance about its node point (the rods' pivots and the hub's centre
  of mass turn with it: ``x + R d``);
- per rod, its length: the distance between its pivots.

Anchored nodes keep their written position and rotation. Stability is not tested here (the
system is the stationarity of the energy, not its minimum); the start is a smooth, large
perturbation of the written shape (plus noise), and the solve reports how far it started and
how far from the written equilibrium it ended.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from scipy.optimize._numdiff import approx_derivative
from scipy.sparse.linalg import lsqr, splu

__all__ = ["WrittenNet", "balance", "force_scale", "forces", "read_net", "solve_balance"]


@dataclass
class WrittenNet:
    """A net as design.json writes it (mm, g; force in g mm / s^2 / 1000 = mN with g = 9.81)."""

    edges: np.ndarray  # (m, 2)
    lengths: np.ndarray  # (m,)
    masses: np.ndarray  # (m,)
    t: np.ndarray  # (m,) centre of mass along the rod / length
    x: np.ndarray  # (n, 3) simulated node points
    rotations: np.ndarray  # (n, 3, 3) (identity for point nodes)
    pivots: np.ndarray  # (m, 2, 3) in the node body's frame
    node_masses: np.ndarray  # (n,)
    node_com: np.ndarray  # (n, 3) in the node body's frame
    anchored: np.ndarray  # (n,) bool
    body: np.ndarray  # (n,) bool: a hub (a rotation of its own)
    tensions: np.ndarray  # (m,) as written
    ends: np.ndarray  # (m, 2, 3) the rods' pivots as written
    size: float


def read_net(path: Path) -> WrittenNet:
    """The net of OUTDIR/design.json (straight rods only: their centre of mass on the axis)."""
    d = json.loads((Path(path) / "design.json").read_text())
    nodes, rods = d["net"]["nodes"], d["net"]["rods"]
    n, m = len(nodes), len(rods)
    com = np.array([r["com"] for r in rods], float)
    if np.any(np.abs(com[:, 1:]) > 0):
        raise ValueError("a rod's centre of mass is off its axis: not a straight-rod net")
    L = np.array([r["length"] for r in rods], float)
    R = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
    piv = np.zeros((m, 2, 3))
    body = np.zeros(n, bool)
    node_com = np.zeros((n, 3))
    edges = np.array([r["nodes"] for r in rods], int)
    for k, nd in enumerate(nodes):
        if nd.get("rotation") is not None:
            R[k], body[k] = np.asarray(nd["rotation"], float), True
            node_com[k] = np.asarray(nd.get("com") or (0, 0, 0), float)
        for e, dv in (nd.get("pivots") or {}).items():
            e = int(e)
            piv[e, 0 if edges[e, 0] == k else 1] = dv
    return WrittenNet(edges, L, np.array([r["mass"] for r in rods], float), com[:, 0] / L,
                      np.array([nd["simulated"] for nd in nodes], float), R, piv,
                      np.array([nd["mass"] or 0.0 for nd in nodes], float), node_com,
                      np.array([nd["anchored"] for nd in nodes], bool), body,
                      np.array([r["tension"] for r in rods], float), np.array([r["ends"] for r in rods], float),
                      float(d["net"]["size"]))


def forces(net: WrittenNet, x: np.ndarray, R: np.ndarray, T: np.ndarray, g: float = 9.81):
    """(force (n, 3), moment about the node point (n, 3), pivot distance - length (m,)) at node
    points ``x``, rotations ``R`` and tensions ``T``."""
    e0, e1 = net.edges[:, 0], net.edges[:, 1]
    P0 = x[e0] + np.einsum("mij,mj->mi", R[e0], net.pivots[:, 0])
    P1 = x[e1] + np.einsum("mij,mj->mi", R[e1], net.pivots[:, 1])
    return balance(net, x, R, P0, P1, T, g)


def balance(net: WrittenNet, x: np.ndarray, R: np.ndarray, P0: np.ndarray, P1: np.ndarray, T: np.ndarray,
            g: float = 9.81):
    """:func:`forces` with the rods' pivots given: ``P0``, ``P1`` (m, 3) (e.g. as written)."""
    e0, e1 = net.edges[:, 0], net.edges[:, 1]
    dv = P1 - P0
    dist = np.linalg.norm(dv, axis=1)
    u = dv / dist[:, None]
    n = len(x)
    f, mom = np.zeros((n, 3)), np.zeros((n, 3))
    for ends, P, sign, share in ((e0, P0, 1.0, 1 - net.t), (e1, P1, -1.0, net.t)):
        F = sign * T[:, None] * u
        F[:, 2] -= g * net.masses * share
        np.add.at(f, ends, F)
        np.add.at(mom, ends, np.cross(P - x[ends], F))
    w = np.zeros((n, 3))
    w[:, 2] = -g * net.node_masses
    f += w
    mom += np.cross(np.einsum("nij,nj->ni", R, net.node_com), w)
    return f, mom, dist - net.lengths


def force_scale(net: WrittenNet, g: float = 9.81) -> float:
    """The larger of the largest written tension and the net's weight."""
    return max(float(np.max(np.abs(net.tensions))), g * float(net.masses.sum() + net.node_masses.sum()))


def _rotation(v: np.ndarray) -> np.ndarray:
    """(k, 3) rotation vectors -> (k, 3, 3) rotations (Rodrigues)."""
    th = np.linalg.norm(v, axis=1)
    K = np.zeros((len(v), 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    K -= K.transpose(0, 2, 1)
    small = th < 1e-8
    a = np.where(small, 1 - th ** 2 / 6, np.sin(th) / np.where(small, 1, th))
    b = np.where(small, 0.5 - th ** 2 / 24, (1 - np.cos(th)) / np.where(small, 1, th) ** 2)
    return np.eye(3) + a[:, None, None] * K + b[:, None, None] * (K @ K)


class _System:
    """The square balance system around a current (x, R): z = (dx free, rotation vectors, T)."""

    def __init__(self, net: WrittenNet, g: float):
        self.net, self.g = net, g
        self.free = np.flatnonzero(~net.anchored)
        self.hubs = np.flatnonzero(~net.anchored & net.body)
        self.nf, self.nh, self.m = len(self.free), len(self.hubs), len(net.edges)
        self.size = 3 * self.nf + 3 * self.nh + self.m
        self.sparsity = self._pattern()

    def _pattern(self) -> sp.csr_matrix:
        n = len(self.net.x)
        xcol = np.full(n, -1)
        xcol[self.free] = np.arange(self.nf)
        hcol = np.full(n, -1)
        hcol[self.hubs] = np.arange(self.nh)
        rows, cols = [], []

        def node_rows(k):
            out = [3 * xcol[k] + i for i in range(3)] if xcol[k] >= 0 else []
            return out + ([3 * self.nf + 3 * hcol[k] + i for i in range(3)] if hcol[k] >= 0 else [])

        for e, (i, j) in enumerate(self.net.edges):
            r = node_rows(i) + node_rows(j) + [3 * self.nf + 3 * self.nh + e]
            c = node_rows(i) + node_rows(j) + [3 * self.nf + 3 * self.nh + e]  # rows and unknowns alike
            rows += [a for a in r for _ in c]
            cols += c * len(r)
        return sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(self.size, self.size))

    def state(self, x, R, z):
        x, R = x.copy(), R.copy()
        x[self.free] += z[:3 * self.nf].reshape(-1, 3)
        if self.nh:
            R[self.hubs] = _rotation(z[3 * self.nf:3 * self.nf + 3 * self.nh].reshape(-1, 3)) @ R[self.hubs]
        return x, R, z[3 * self.nf + 3 * self.nh:]

    def residual(self, x, R, z, scale):
        f, mom, c = forces(self.net, *self.state(x, R, z), g=self.g)
        return np.concatenate([f[self.free].ravel() / scale, mom[self.hubs].ravel() / (scale * self.lbar),
                               c / self.lbar])

    @property
    def lbar(self) -> float:
        return float(self.net.lengths.mean())


def _start(net: WrittenNet, rng, amplitude: float, noise: float, turn: float):
    """A smooth perturbation of the written shape (three long waves per axis, together up to
    ``amplitude`` x size) plus ``noise`` x the mean rod, the hubs turned by up to ``turn`` rad."""
    x, R = net.x.copy(), net.rotations.copy()
    free = ~net.anchored
    lo, span = net.x.min(axis=0), np.ptp(net.x, axis=0) + 1e-9
    s = (net.x - lo) / span
    d = np.zeros_like(x)
    for axis in range(3):
        for _ in range(3):  # waves that vanish on the bounding box's sides (a border-held net's anchors)
            k = rng.integers(1, 4, size=2)
            d[:, axis] += rng.uniform(-1, 1) * np.sin(np.pi * k[0] * s[:, 0]) * np.sin(np.pi * k[1] * s[:, 1])
    d *= amplitude * net.size / 3
    d += rng.normal(0.0, noise * float(net.lengths.mean()), x.shape)
    x[free] += d[free]
    hubs = free & net.body
    R[hubs] = _rotation(rng.uniform(-turn, turn, (int(hubs.sum()), 3))) @ R[hubs]
    return x, R


def _tensions(sysm: _System, x, R) -> np.ndarray:
    """Least-squares tensions balancing the free nodes' forces at (x, R) (the linear part)."""
    net = sysm.net
    base = forces(net, x, R, np.zeros(sysm.m), g=sysm.g)[0][sysm.free].ravel()
    e0, e1 = net.edges[:, 0], net.edges[:, 1]
    P0 = x[e0] + np.einsum("mij,mj->mi", R[e0], net.pivots[:, 0])
    P1 = x[e1] + np.einsum("mij,mj->mi", R[e1], net.pivots[:, 1])
    u = (P1 - P0) / np.linalg.norm(P1 - P0, axis=1)[:, None]
    row = np.full(len(x), -1)
    row[sysm.free] = np.arange(sysm.nf)
    rr, cc, vv = [], [], []
    for ends, sign in ((e0, 1.0), (e1, -1.0)):
        ok = row[ends] >= 0
        for i in range(3):
            rr.append(3 * row[ends[ok]] + i)
            cc.append(np.flatnonzero(ok))
            vv.append(sign * u[ok, i])
    A = sp.csr_matrix((np.concatenate(vv), (np.concatenate(rr), np.concatenate(cc))), shape=(3 * sysm.nf, sysm.m))
    return lsqr(A, -base, atol=1e-12, btol=1e-12, iter_lim=20000)[0]


def solve_balance(net: WrittenNet, *, seed: int = 0, amplitude: float = 0.003, noise: float = 0.01,
                  turn: float = 0.05, g: float = 9.81, tol: float = 1e-12, max_iter: int = 60, max_move: float = 0.1,
                  max_turn: float = 0.1,
                  verbose: bool = False) -> dict:
    """Newton on the balance system from a perturbed start (module docstring), each step cut
    so that no node moves more than ``max_move`` mean rods and no hub turns more than
    ``max_turn`` rad (a full Newton step from far off throws the net about), then halved until
    the residual falls.

    Returns:
        dict: positions (n, 3), rotations, tensions, converged, steps (Newton's), residual (the
        largest scaled residual), started (largest node distance of the start from the
        written equilibrium, mm), distance (of the result, mm), wall (s).
    """
    t0 = time.perf_counter()
    rng = np.random.default_rng(seed)
    sysm = _System(net, g)
    x, R = _start(net, rng, amplitude, noise, turn)
    started = float(np.max(np.linalg.norm(x - net.x, axis=1)))
    scale = force_scale(net, g)
    z = np.zeros(sysm.size)
    z[3 * sysm.nf + 3 * sysm.nh:] = _tensions(sysm, x, R)
    T = z[3 * sysm.nf + 3 * sysm.nh:].copy()
    it, res, converged = 0, np.inf, False
    for it in range(1, max_iter + 1):
        z = np.zeros(sysm.size)
        z[3 * sysm.nf + 3 * sysm.nh:] = T

        def fun(zz):
            return sysm.residual(x, R, zz, scale)

        r = fun(z)
        res = float(np.max(np.abs(r)))
        if res <= tol:
            converged = True
            break
        J = approx_derivative(fun, z, method="3-point", sparsity=sysm.sparsity, f0=r)
        dz = -splu(sp.csc_matrix(J)).solve(r)
        norm0 = float(r @ r)
        move = float(np.max(np.abs(dz[:3 * sysm.nf]), initial=0.0)) / (max_move * sysm.lbar)
        turn_ = float(np.max(np.abs(dz[3 * sysm.nf:3 * sysm.nf + 3 * sysm.nh]), initial=0.0)) / max_turn
        alpha = min(1.0, 1.0 / max(move, turn_, 1e-300))  # no node further than max_move rods a step
        while alpha > 1e-4:
            trial = fun(z + alpha * dz)
            if float(trial @ trial) < (1 - 1e-4 * alpha) * norm0:
                break
            alpha /= 2
        x, R, T = sysm.state(x, R, z + alpha * dz)
        if verbose:
            print(f"    newton {it}: residual {res:.3g}, step {alpha:g}", flush=True)
        T = T.copy()
    return {"positions": x, "rotations": R, "tensions": T, "converged": converged, "steps": it - 1 if converged else it,
            "residual": res, "started": started, "distance": float(np.max(np.linalg.norm(x - net.x, axis=1))),
            "tension_change": float(np.max(np.abs(T - net.tensions)) / np.max(np.abs(net.tensions))),
            "wall": time.perf_counter() - t0}
