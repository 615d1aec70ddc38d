"""Independent MuJoCo reference for the static equilibrium of a hanging net.

Uses *no* rodcad / optimize code. Every rod is a rigid body; every free node body (ring,
hub) is one too. A spanning tree over them (breadth first from the anchored nodes) nests
the bodies, each hanging from its parent by a ball joint at the pivot they share; every
rod end the tree does not reach that way is closed onto its node by a ``connect``
equality constraint (site on site). Point masses at point nodes are merged into the
body that carries the node in the tree (statically the same). MuJoCo then simulates the
net with damping until it rests, and the rest state is read from the bodies.

Conventions as in ``optimize.net.model``: z up, gravity along -z; rod e joins nodes
edges[e] = (i, j); its centre of mass (along, perp, w) is in a frame with origin at the
pivot at node i and x toward node j; pivots[e, k] are the rod's pivots in the frame of
the node body at its end k (zero for point nodes).

Choices (see ``mujoco_chain`` for the reasoning they share):

* Length and mass are scaled to O(1) (lengths by the net's size, masses by their mean),
  gravity 9.81; the rest shape depends only on the geometry and mass ratios.
* Equality constraints at MuJoCo's stiffest: solimp 0.9999, time constant 2 dt, damping
  ratio 0.5 (dead-beat), so the static violation is ~1e-9 of the size.
* Every body's rotational inertia is the heaviest rod's thin-rod value (statics-neutral;
  light rods otherwise make the constraints mobile and soft), except a rod's about its own
  axis, a thousandth of that (its pivots lie on the axis, so its roll, which hangs an
  off-axis centre of mass lowest, settles fast without softening any constraint).
* Damping is mass proportional, D = alpha M, applied exactly: ``qvel *= exp(-alpha dt)``
  after every step (every mode decays at alpha / 2 or faster; the rest state is not
  affected), alpha = 4 sqrt(g / size).
"""

from __future__ import annotations

import time as _time
from collections import deque

import mujoco
import numpy as np

__all__ = ["build_net_mjcf", "settle_net", "NET_DEFAULTS"]

NET_DEFAULTS = dict(
    timestep=1e-3,
    integrator="implicitfast",
    iterations=100,
    solver_tolerance=1e-13,
    impedance=0.9999,
    dampratio=0.5,
    alpha_factor=4.0,
    check_every=100,
)


def _f(x: float) -> str:
    return format(float(x), ".17g")


def _v(a) -> str:
    return " ".join(_f(t) for t in a)


def _quat(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a rotation matrix."""
    q = np.empty(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, dtype=float).ravel())
    return q


def _frame_of_rod(p0, p1, roll_y=None):
    x = (p1 - p0) / np.linalg.norm(p1 - p0)
    y = np.array([0.0, 0.0, -1.0]) if roll_y is None else np.asarray(roll_y, float)
    y = y - x * (x @ y)
    if np.linalg.norm(y) < 1e-9:
        y = np.array([1.0, 0.0, 0.0]) - x * x[0]
    y /= np.linalg.norm(y)
    return np.column_stack([x, y, np.cross(x, y)])  # columns: rod axes in world


class _Tree:
    """The spanning tree of bodies and the loop closures (world frame poses)."""

    def __init__(self, x, R, edges, anchored, pivots, body_nodes, rod_y=None, welded=()):
        n, m = x.shape[0], edges.shape[0]
        welded = set((int(e), int(k)) for e, k in welded)
        self.fixed = set()      # bodies welded to their parent (no joint)
        self.welds = []         # (rod body, the body its end is welded to) by an equality
        self.x, self.R, self.edges = x, R, edges
        self.P = np.stack([x[edges[:, k]] + np.einsum("mab,mb->ma", R[edges[:, k]], pivots[:, k]) for k in (0, 1)], 1)
        self.rod_R = [_frame_of_rod(self.P[e, 0], self.P[e, 1], None if rod_y is None else rod_y[e]) for e in range(m)]
        self.parent = {}        # body name -> (parent name, joint point world)
        self.children = {"world": []}
        self.owner = {}         # point node -> (body name, site name at the node point)
        self.closures = []      # (site on the rod end, site it must meet)
        self.sites = {"world": []}  # body -> [(site name, world point)]
        anchored = set(int(a) for a in anchored)
        body_nodes = set(int(b) for b in body_nodes) - anchored
        at = [[] for _ in range(n)]
        for e, (i, j) in enumerate(edges):
            at[i].append((e, 0))
            at[j].append((e, 1))
        placed = set()
        located = set(anchored)
        queue = deque(sorted(anchored))
        for a in anchored:
            self.owner[a] = ("world", None)

        def carrier(node):
            if node in body_nodes:
                return f"node{node}"
            return self.owner[node][0]

        def pivot_site(node, e, k):
            """A site where rod e's end k meets node: on the carrying body, at P[e, k]."""
            body = carrier(node)
            name = f"s_{body}_e{e}_{k}"
            self.sites.setdefault(body, []).append((name, self.P[e, k]))
            return name

        while queue:
            node = queue.popleft()
            for e, k in at[node]:
                if e in placed:
                    continue
                placed.add(e)
                par = carrier(node)
                name = f"rod{e}"
                self._add(name, par, self.P[e, k])
                if (e, k) in welded:
                    self.fixed.add(name)
                other = int(edges[e, 1 - k])
                end_site = f"s_{name}_{1 - k}"
                self.sites.setdefault(name, []).extend([(f"s_{name}_0", self.P[e, 0]), (f"s_{name}_1", self.P[e, 1])])
                if other in located:
                    self.closures.append((end_site, pivot_site(other, e, 1 - k)))
                    if (e, 1 - k) in welded:
                        self.welds.append((name, carrier(other)))
                elif other in body_nodes:
                    self._add(f"node{other}", name, self.P[e, 1 - k])
                    if (e, 1 - k) in welded:
                        self.fixed.add(f"node{other}")
                    located.add(other)
                    queue.append(other)
                else:
                    self.owner[other] = (name, end_site)
                    located.add(other)
                    queue.append(other)
        self.body_nodes = body_nodes

    def _add(self, name, parent, point):
        self.parent[name] = (parent, point)
        self.children.setdefault(parent, []).append(name)
        self.children.setdefault(name, [])


def build_net_mjcf(tree: _Tree, masses, com, node_masses, node_com, g, inertia, *, timestep, integrator,
                   iterations, solver_tolerance, impedance, dampratio) -> str:
    """The MJCF text of the net in the tree's configuration (every joint at identity)."""
    sref = f"{_f(2 * timestep)} {_f(dampratio)}"
    simp = f"{_f(impedance)} {_f(impedance)} 0.001 0.5 2"
    out = ['<mujoco model="rod_net">', '  <compiler angle="radian" autolimits="false"/>',
           f'  <option gravity="0 0 {_f(-g)}" timestep="{_f(timestep)}" integrator="{integrator}" '
           f'solver="Newton" iterations="{int(iterations)}" tolerance="{_f(solver_tolerance)}" ls_iterations="50" '
           'cone="pyramidal">', '    <flag contact="disable"/>', '  </option>', '  <worldbody>']
    # extra point masses carried by rods (point nodes' hardware)
    extra = {}
    for node, (body, site) in tree.owner.items():
        if body != "world" and node_masses[node] > 0:
            extra.setdefault(body, []).append((node_masses[node], tree.x[node]))

    def pose(name):
        if name.startswith("rod"):
            e = int(name[3:])
            return tree.P[e, 0], tree.rod_R[e]
        if name.startswith("node"):
            k = int(name[4:])
            return tree.x[k], tree.R[k]
        return np.zeros(3), np.eye(3)

    def emit(name, indent):
        p, Rw = pose(name)
        if name != "world":
            par, point = tree.parent[name]
            pp, Rp = pose(par)
            rel = Rp.T @ (p - pp)
            Rrel = Rp.T @ Rw
            out.append(f'{indent}<body name="{name}" pos="{_v(rel)}" quat="{_v(_quat(Rrel))}">')
            if name not in tree.fixed:  # (a rod end glued in its socket: welded to its parent)
                out.append(f'{indent}  <joint name="j_{name}" type="ball" pos="{_v(Rw.T @ (point - p))}"/>')
            if name.startswith("rod"):
                e = int(name[3:])
                mass, c = masses[e], np.asarray(com[e], float)
            else:
                k = int(name[4:])
                mass, c = node_masses[k], np.asarray(node_com[k], float)
            for mx, xw in extra.get(name, []):
                cl = Rw.T @ (xw - p)
                c = (mass * c + mx * cl) / (mass + mx)
                mass = mass + mx
            # a rod turns about its own axis (x) with a thousandth of that: the pivots lie on
            # the axis, so this does not soften the constraints, and the roll settles fast
            ixx = inertia * (1e-3 if name.startswith("rod") else 1.0)
            out.append(f'{indent}  <inertial pos="{_v(c)}" mass="{_f(mass)}" '
                       f'diaginertia="{_f(ixx)} {_f(inertia)} {_f(inertia)}"/>')
        for sname, sw in tree.sites.get(name, []):
            out.append(f'{indent}  <site name="{sname}" pos="{_v(Rw.T @ (sw - p))}"/>')
        if name.startswith("node"):
            out.append(f'{indent}  <site name="s_{name}_origin" pos="0 0 0"/>')
        for child in tree.children.get(name, []):
            emit(child, indent + "  ")
        if name != "world":
            out.append(f"{indent}</body>")

    emit("world", "  ")
    out.append("  </worldbody>")
    if tree.closures:
        out.append("  <equality>")
        for a, b in tree.closures:
            out.append(f'    <connect site1="{a}" site2="{b}" solref="{sref}" solimp="{simp}"/>')
        for a, b in tree.welds:  # (relpose all zeros: as the bodies are in the model's configuration)
            other = "" if b == "world" else f' body2="{b}"'
            out.append(f'    <weld body1="{a}"{other} relpose="0 0 0 0 0 0 0" solref="{sref}" solimp="{simp}"/>')
        out.append("  </equality>")
    out.append("</mujoco>")
    return "\n".join(out)


def settle_net(positions0, edges, lengths, masses, anchored, *, node_masses=None, com=None, node_com=None,
               pivots=None, rotations0=None, body_nodes=None, rod_y=None, welded=(), g=9.81, tol=1e-8,
               max_time=200.0, **options) -> dict:
    """Simulate the net in MuJoCo from ``positions0`` until it rests; return the rest state.

    Args:
        positions0: (n, 3) a configuration of the rods (every rod at its length; the
            model is built in it, so its constraints hold there).
        edges, lengths, masses, anchored: the net (lengths only checked against positions0).
        node_masses, com, node_com, pivots: as ``optimize.solve_net``.
        rotations0: (n, 3, 3) node bodies' start orientations (identity by default).
        body_nodes: nodes simulated as rigid bodies (default: those with a pivot off the
            node point or an off-centre mass).
        rod_y: (m, 3) each rod's start y axis (its roll), default straight down.
        welded: (rod, end) pairs glued in their sockets: the rod end is welded to its node's
            body (to the world at an anchored node) instead of turning on its ball joint.
        tol: rest when max |qvel| (scaled units) stays below tol for three checks.
        max_time: simulated seconds (scaled) at most.

    Returns:
        dict: positions (n, 3), rotations (n, 3, 3), ends (m, 2, 3), rod_axes (m, 3, 3)
        (columns: each rod's frame in world), converged, time, wall, qvel_max,
        closure_error (largest distance between sites a connect joins, in the caller's unit).
    """
    opts = dict(NET_DEFAULTS)
    unknown = set(options) - set(opts)
    if unknown:
        raise TypeError(f"unknown options: {sorted(unknown)}")
    opts.update(options)
    x0 = np.asarray(positions0, float)
    edges = np.asarray(edges, int)
    n, m = x0.shape[0], edges.shape[0]
    masses = np.asarray(masses, float)
    node_masses = np.zeros(n) if node_masses is None else np.asarray(node_masses, float)
    com = np.column_stack([np.asarray(lengths) / 2, np.zeros(m), np.zeros(m)]) if com is None else np.asarray(com, float)
    if com.shape[1] == 2:
        com = np.column_stack([com, np.zeros(m)])
    node_com = np.zeros((n, 3)) if node_com is None else np.asarray(node_com, float)
    pivots = np.zeros((m, 2, 3)) if pivots is None else np.asarray(pivots, float)
    R0 = np.broadcast_to(np.eye(3), (n, 3, 3)).copy() if rotations0 is None else np.asarray(rotations0, float)
    if body_nodes is None:
        off = np.zeros(n, dtype=bool)
        for k in (0, 1):
            np.logical_or.at(off, edges[:, k], np.any(pivots[:, k] != 0, axis=1))
        off |= np.any(node_com != 0, axis=1) & (node_masses > 0)
        body_nodes = np.flatnonzero(off)
    anchored = np.flatnonzero(np.isin(np.arange(n), anchored)) if np.asarray(anchored).dtype != bool \
        else np.flatnonzero(anchored)
    # scale to O(1)
    size = float(np.max(np.ptp(x0, axis=0)))
    mref = float(np.mean(masses))
    origin = x0[anchored[0]].copy()
    xs = (x0 - origin) / size
    tree = _Tree(xs, R0, edges, anchored, pivots / size, body_nodes, rod_y, welded)
    dist = np.linalg.norm(tree.P[:, 1] - tree.P[:, 0], axis=1) * size
    if np.max(np.abs(dist - lengths) / lengths) > 1e-6:
        raise ValueError("positions0 is not a configuration of the rods (lengths differ)")
    inertia = float(np.max(masses / mref) * np.max(lengths / size) ** 2 / 12)
    kw = {k: opts[k] for k in ("timestep", "integrator", "iterations", "solver_tolerance", "impedance", "dampratio")}
    xml = build_net_mjcf(tree, masses / mref, com / size, node_masses / mref, node_com / size, g, inertia, **kw)
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    dt = float(opts["timestep"])
    alpha = opts["alpha_factor"] * np.sqrt(g / 1.0)
    decay = np.exp(-alpha * dt)
    chunk = int(opts["check_every"])
    t_wall = _time.perf_counter()
    quiet = 0
    converged = False
    while data.time < max_time:
        for _ in range(chunk):
            mujoco.mj_step(model, data)
            data.qvel[:] *= decay
        if data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number or not np.all(np.isfinite(data.qpos)):
            raise FloatingPointError(f"MuJoCo simulation diverged (t = {data.time:.3f} s)")
        if np.max(np.abs(data.qvel)) < tol:
            quiet += 1
            if quiet >= 3:
                converged = True
                break
        else:
            quiet = 0
    wall = _time.perf_counter() - t_wall
    mujoco.mj_forward(model, data)

    def site(name):
        return data.site(name).xpos.copy()

    pos = np.zeros((n, 3))
    rot = R0.copy()
    for k in range(n):
        if k in set(anchored.tolist()):
            pos[k] = xs[k]
        elif k in tree.body_nodes:
            pos[k] = data.body(f"node{k}").xpos
            rot[k] = data.body(f"node{k}").xmat.reshape(3, 3)
        else:
            pos[k] = site(tree.owner[k][1])
    ends = np.zeros((m, 2, 3))
    axes = np.zeros((m, 3, 3))
    for e in range(m):
        b = data.body(f"rod{e}")
        axes[e] = b.xmat.reshape(3, 3)
        ends[e, 0] = b.xpos
        ends[e, 1] = b.xpos + axes[e][:, 0] * lengths[e] / size
    closure = max((np.linalg.norm(site(a) - site(b)) for a, b in tree.closures), default=0.0)
    return {
        "positions": pos * size + origin,
        "rotations": rot,
        "ends": ends * size + origin,
        "rod_axes": axes,
        "converged": converged,
        "time": float(data.time),
        "wall": wall,
        "qvel_max": float(np.max(np.abs(data.qvel))),
        "closure_error": float(closure * size),
        "size": size,
    }
