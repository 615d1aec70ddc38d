"""The hung chain tapped until it settles: pin friction's band turned into a number.

Pin friction lets a printed chain rest anywhere in a band around its design
(:func:`optimize.friction_band`). Users are told to tap the hung chain lightly a few times;
:func:`tap_chain` simulates that advice with MuJoCo and reports where the chain comes to
rest after it is hung and after each tap.

Model (the package's own MJCF; ``tests/mujoco_chain.py`` stays an independent reference)
-----------------------------------------------------------------------------------------
* Nested hinge bodies, one per rod (hinge axis z, gravity -y), the last rod's tip held on B
  by a ``connect`` equality; bend limits as hinge ranges (a fused joint, lo == hi, a window
  of 2e-9 rad), the anchor stops as the first hinge's range and as a range on a fixed
  tendon (the last rod's absolute angle, the sum of the hinges); dry friction
  (``frictionloss``) on every hinge and, for the pin at B, on a fixed tendon over all
  hinges. ``implicitfast``, Newton solver, contacts off; every constraint at the stiffest
  MuJoCo allows (impedance 0.9999, time constant two timesteps).
* Dimensionless: lengths in units of the chain's total length L, masses of its total mass
  M, gravity 1, so time runs in units of ``T = sqrt(L / g)`` and moments in ``g M L``; every
  chain, whatever its size or mass, runs on the same numbers. Results are in the caller's.
* Rods have their thin-rod inertia about their centre of mass, ``m l^2 / 12``. Damping is
  mass proportional, ``alpha M`` (M the joint-space inertia at the design, realised as one
  damped fixed tendon per column of its Cholesky factor): every mode decays at
  ``alpha / 2``. Taps run at ``alpha =`` :data:`DECAY` ``/ T``, light: the pins' friction,
  as on a real chain, spends a tap's swing.
* :data:`TIMESTEP` = T / 400. MuJoCo's constraints are soft: a loaded stop gives by about
  ``1e-4 (2 dt)^2`` times the acceleration its moment would cause, and a pin that holds
  creeps at about ``R f dt`` (R its row's regulariser, f its moment). Both shrink with dt; at
  T / 400 the shipped heart (22 rods, 17 stops that hold) rests within 2 um of its design
  without friction, 0.2 % of its friction band, and a 25-rod chain with 10 taps takes about
  a third of a second on one core.

Hanging, taps, rest
-------------------
* Hung: the bends (and the first rod's angle) moved by a seeded uniform ``+-release`` rad,
  within the limits (fused joints untouched), closed onto B by a small SLSQP (the nearest
  closed angles), let go from rest with the slowest mode critically damped (``alpha = 2
  omega_1``, omega_1 from the linearised statics and the inertia): hung gently, the chain
  slides in and stops where friction first holds it. Rest 0.
* Tap: an impulse at a seeded random point of a seeded random rod, in a random direction in
  the plane (a finger's tap), as the joint velocities the closed chain takes: the impulse
  response of the inertia, projected onto the closure, the fused joints and the stops the
  chain rests on (a light tap does not lift a rod off a loaded stop; the motion it starts
  may). Its kinetic energy is ``strength`` times the *band energy*: the work
  the pins' friction moments do as the chain moves from the design to the edge of its band
  (:func:`band_scale`, twice the potential energy of the band's extreme shape; reaching that
  shape from the design takes 1.5 band energies, crossing the band from edge to edge about
  2). Energy goes as the square of displacement, so the band energy is the same yardstick
  for any chain's size, mass or number of rods. In one degree of freedom (stiffness k,
  friction holding the band b, band energy k b^2) a kick of s band energies from the design
  runs out to ``x = b (sqrt(1 + 2 s) - 1)`` against gravity and friction: :data:`STRENGTH`
  = 4 takes the chain one band width past the band's edge, a little beyond it, freeing its
  pins. A tap's energy spreads over the modes it excites, stiff ones too: on the shipped and
  random test chains the median tap carries the chain 1.1 to 2.3 band widths from the
  design (``TapResult.peak``).
* Rest: ``max |qvel|`` below the tolerance on :data:`REST_CHECKS` consecutive checks
  :data:`CHECK_STEPS` steps apart; the tolerance is :data:`REST_VELOCITY` / T, or
  :data:`CREEP_FACTOR` times the creep of a pin holding its full load where that is more (a
  held chain creeps, and the closure can add up its pins' creep). Each settle has
  :data:`SETTLE_TIME` T of simulated time; past it ``converged`` is False. A creep at the
  tolerance for the time it takes to see rest moves a joint by at most ``TapResult.drift``.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from scipy.optimize import minimize

from optimize.chain import Chain
from optimize.chain.endlimits import limit_turn

__all__ = ["BandScale", "STRENGTH", "TapResult", "band_scale", "slowest_mode", "tap_chain"]

#: Default tap kinetic energy, in band energies (module docstring).
STRENGTH = 4.0
#: Timestep (units of T = sqrt(L / g)).
TIMESTEP = 0.0025
#: Mass-proportional damping rate alpha during the taps (1 / T): every mode decays at alpha / 2.
DECAY = 1.0
#: Rest: max |qvel| (rad / T) below the larger of this and CREEP_FACTOR x the pins' creep.
REST_VELOCITY = 1e-6
CREEP_FACTOR = 10.0
REST_CHECKS = 3
CHECK_STEPS = 40
#: Simulated time of one settle at most (T).
SETTLE_TIME = 60.0
#: A bound within this of a joint's bend (rad) holds the joint in the linearised statics.
HELD = 1e-7

_BIG = 1e6  # stands in for an infinite side of a range (rad)


@dataclass
class TapResult:
    """Where a tapped chain comes to rest (the caller's units).

    Attributes:
        rests: (n_taps + 1, N+1, 2) joint positions at rest, after hanging and then after each
            tap (length, e.g. mm; p_N is the last rod's tip, off B by ``end_error``).
        deviation: (n_taps + 1,) the largest joint distance from the design at each rest.
        per_joint: (N+1,) each joint's distance from the design after the last tap.
        converged: every settle came to rest within its time budget.
        taps: taps simulated. seed: the random seed.
        message: what was done, and anything that went wrong.
        peak: (n_taps,) the largest joint distance from the design during each tap's motion.
        band: the largest joint displacement over the linearised band on the design's held
            stops (:func:`band_scale`, the taps' scale; :func:`optimize.friction_band` is the
            exact band). band_energy: the work to reach it (force x length, as capacity).
        energy: each tap's kinetic energy (force x length).
        end_error: (n_taps + 1,) the last rod's tip's distance from B at each rest.
        violation: (n_taps + 1,) the largest overshoot of a bend limit or anchor stop (rad).
        drift: how far a joint can move at the rest tolerance while its rest is being seen
            (length): with ``end_error`` and ``violation`` x the chain's length, MuJoCo's
            settling error.
        start: (N+1, 2) the joint positions the chain was let go from (length).
        sim_time: simulated time of all the settles (units of sqrt(L / g)).
    """

    rests: np.ndarray
    deviation: np.ndarray
    per_joint: np.ndarray
    converged: bool
    taps: int
    seed: int
    message: str
    peak: np.ndarray
    band: float
    band_energy: float
    energy: float
    end_error: np.ndarray
    violation: np.ndarray
    drift: float
    start: np.ndarray
    sim_time: float


def _f(x: float) -> str:
    return format(float(x), ".17g")


def _range(lo: float, hi: float) -> tuple[float, float] | None:
    """A MuJoCo range for [lo, hi] (infinite sides far out, lo == hi a 2e-9 rad window)."""
    if not (np.isfinite(lo) or np.isfinite(hi)):
        return None
    lo = lo if np.isfinite(lo) else -_BIG
    hi = hi if np.isfinite(hi) else _BIG
    if hi - lo < 2e-9:
        lo, hi = (lo + hi) / 2 - 1e-9, (lo + hi) / 2 + 1e-9
    return lo, hi


def _mjcf(l, m, com, b, limits, ends, tau, damping) -> str:
    """The dimensionless chain's MJCF (A at the origin, g = 1; module docstring)."""
    n = l.size
    dt = TIMESTEP
    stiff = f'solimp{{}}="0.9999 0.9999 0.001 0.5 2" solref{{}}="{_f(2 * dt)} 1"'
    out = ['<mujoco model="tapped_chain">', '  <compiler angle="radian" autolimits="false"/>',
           f'  <option gravity="0 -1 0" timestep="{_f(dt)}" integrator="implicitfast" solver="Newton"'
           ' iterations="50" tolerance="1e-12" ls_iterations="50" cone="pyramidal"'
           ' jacobian="dense">',
           '    <flag contact="disable"/>', '  </option>', '  <worldbody>',
           f'    <site name="b" pos="{_f(b[0])} {_f(b[1])} 0"/>']
    ind = "    "
    for i in range(n):
        pos = "0 0 0" if i == 0 else f"{_f(l[i - 1])} 0 0"
        out.append(f'{ind}<body name="rod{i}" pos="{pos}">')
        row = ends[0] if i == 0 else limits[i - 1]
        rng = _range(*row) if row is not None else None
        lim = 'limited="false"' if rng is None else (
            f'limited="true" range="{_f(rng[0])} {_f(rng[1])}" ' + stiff.format("limit", "limit"))
        out.append(f'{ind}  <joint name="j{i}" type="hinge" axis="0 0 1" {lim} frictionloss="{_f(tau[i])}" '
                   + stiff.format("friction", "friction") + "/>")
        inertia = m[i] * l[i] ** 2 / 12.0
        out.append(f'{ind}  <inertial pos="{_f(com[i, 0])} {_f(com[i, 1])} 0" mass="{_f(m[i])}" '
                   f'diaginertia="{_f(inertia)} {_f(inertia)} {_f(inertia)}"/>')
        out.append(f'{ind}  <geom type="capsule" fromto="0 0 0 {_f(l[i])} 0 0" size="{_f(0.01 * l[i])}" '
                   'contype="0" conaffinity="0" mass="0"/>')
        ind += "  "
    out.append(f'{ind}<site name="tip" pos="{_f(l[-1])} 0 0"/>')
    for _ in range(n):
        ind = ind[:-2]
        out.append(f"{ind}</body>")
    out += ["  </worldbody>", "  <tendon>"]
    every = "".join(f'<joint joint="j{i}" coef="1"/>' for i in range(n))
    for k, (d, coef) in enumerate(damping):
        joints = "".join(f'<joint joint="j{i}" coef="{_f(coef[i])}"/>' for i in range(n) if coef[i] != 0)
        out.append(f'    <fixed name="mode{k}" damping="{_f(d)}">{joints}</fixed>')
    rng = _range(*ends[1]) if ends[1] is not None else None
    if rng is not None:  # the anchor stop on theta_{N-1}, the sum of the hinges
        out.append(f'    <fixed name="last" limited="true" range="{_f(rng[0])} {_f(rng[1])}" '
                   + stiff.format("limit", "limit") + f">{every}</fixed>")
    if tau[n] > 0:  # the pin at B: friction on the last rod's absolute angle
        out.append(f'    <fixed name="pin_b" frictionloss="{_f(tau[n])}" '
                   + stiff.format("friction", "friction") + f">{every}</fixed>")
    out += ["  </tendon>", "  <equality>",
            f'    <connect name="close" site1="tip" site2="b" solimp="0.9999 0.9999 0.001 0.5 2" '
            f'solref="{_f(2 * dt)} 0.5"/>', "  </equality>", "</mujoco>"]
    return "\n".join(out)


def _moment_arms(n: int) -> np.ndarray:
    """(N, N+1): pin k's friction moment as a generalised force on the chord angles."""
    E = np.zeros((n, n + 1))
    E[0, 0] = 1.0
    E[n - 1, n] += 1.0
    for j in range(1, n):
        E[j, j], E[j - 1, j] = 1.0, -1.0
    return E


@dataclass
class BandScale:
    """The friction band of the statics linearised at the design, on the design's own set
    of held stops (one cell of :func:`optimize.friction_band`: exact there while the box of
    friction moments stays in it, which a stop letting go would break).

    Attributes:
        per_joint: (N+1,) each joint's largest displacement over the band (length).
        band: the largest of them.
        moments: (N+1,) the pins' friction moments at which the band is reached.
        energy: the work those moments do as the chain moves from the design to that shape
            (force x length): twice its potential energy, ``m'Rm``.
    """

    per_joint: np.ndarray
    band: float
    moments: np.ndarray
    energy: float


def _zonotope_max(gen: np.ndarray) -> tuple[float, np.ndarray]:
    """Largest norm over the zonotope ``{gen s : |s_k| <= 1}`` (gen 2 x K) and its signs s: a
    vertex, the signs of ``gen' e`` for a direction e between consecutive generator normals."""
    keep = np.hypot(gen[0], gen[1]) > 0
    if not keep.any():
        return 0.0, np.zeros(gen.shape[1])
    ang = np.arctan2(gen[1, keep], gen[0, keep])
    cuts = np.sort(np.concatenate([ang + np.pi / 2, ang - np.pi / 2]) % (2 * np.pi))
    mids = 0.5 * (cuts + np.roll(cuts, -1))
    mids[-1] += np.pi  # the arc through 2 pi
    signs = np.sign(gen.T @ np.vstack([np.cos(mids), np.sin(mids)]))
    verts = gen @ signs
    k = int(np.argmax(np.hypot(verts[0], verts[1])))
    return float(np.hypot(*verts[:, k])), signs[:, k]


def _stiffness(chain: Chain, theta: np.ndarray, ends) -> tuple[np.ndarray, np.ndarray]:
    """The statics linearised at the design: Z (N, k), the null space of the closure and of
    the stops that touch their bound (within :data:`HELD` rad), and ``K = Z'HZ``, the Hessian
    of the Lagrangian on it (the reaction and the held stops' moments balancing the design,
    least squares)."""
    n = chain.n
    l, e = chain.lengths, np.exp(1j * theta)
    phi = np.diff(theta)
    held = []
    for j, (lo, hi) in enumerate(chain.limits):
        if min(abs(phi[j] - lo), abs(phi[j] - hi)) <= HELD:
            a = np.zeros(n)
            a[j + 1], a[j] = 1.0, -1.0
            held.append(a)
    for k, idx in ((0, 0), (1, n - 1)):
        if ends is not None and np.min(np.abs(theta[idx] - ends[k])) <= HELD:
            held.append(np.eye(n)[idx])
    A = np.array(held).reshape(-1, n)
    lhs = np.column_stack([l * e.imag, -l * e.real, -A.T])
    lam = np.linalg.lstsq(lhs, l * (np.conj(chain.sigma) * e).imag, rcond=None)[0]
    z = complex(lam[0], lam[1]) - chain.sigma
    H = np.diag(l * (np.conj(z) * e).real)
    G = np.vstack([-l * e.imag, l * e.real, A])
    _, s, vt = np.linalg.svd(G)
    Z = vt[int(np.sum(s > 1e-12 * s.max())):].T
    return Z, Z.T @ H @ Z


def slowest_mode(chain: Chain, theta: np.ndarray, ends, mass_matrix: np.ndarray) -> float:
    """The slowest angular frequency of the frictionless chain about the design (1 / time
    unit of the chain's ``g``), from K (:func:`_stiffness`) and the hinges' inertia
    ``mass_matrix`` (N, N; hinge angles q_0 = theta_0, q_j = the bends); 0 without motion."""
    Z, K = _stiffness(chain, theta, ends)
    if Z.shape[1] == 0:
        return 0.0
    tri_inv = np.linalg.inv(np.tril(np.ones((chain.n, chain.n))))  # q = tri_inv theta
    Mz = Z.T @ tri_inv.T @ mass_matrix @ tri_inv @ Z
    w2 = np.linalg.eigvals(np.linalg.solve(Mz, K)).real
    return float(np.sqrt(max(np.abs(w2).min(), 0.0)))


def band_scale(chain: Chain, theta: np.ndarray, capacity: np.ndarray, ends) -> BandScale:
    """The linearised friction band at the design and the energy it takes to reach its edge.

    Args:
        chain: the chain (any consistent units). theta: (N,) the design's chord angles (rad).
        capacity: (N+1,) each pin's friction moment (force x length, 0 at fused joints).
        ends: (2, 2) anchor stops on theta_0 and theta_{N-1} on the design's turn, or None.

    Returns:
        BandScale: the stops that touch their bound (within :data:`HELD` rad) held, the
        reaction and their moments balancing the design (least squares), the Hessian of the
        Lagrangian H on the null space Z of the closure and the held stops, the pins' moments
        m acting through their arms E: rests ``q = Z (Z'HZ)^-1 Z'E m``, each joint's largest
        displacement over the box ``|m_k| <= capacity_k`` a zonotope vertex.
    """
    n = chain.n
    tau = np.asarray(capacity, dtype=float)
    zero = BandScale(np.zeros(n + 1), 0.0, np.zeros(n + 1), 0.0)
    Z, K = _stiffness(chain, theta, ends)
    if not np.any(tau > 0) or Z.shape[1] == 0:
        return zero
    l, e = chain.lengths, np.exp(1j * theta)
    w, v = np.linalg.eigh(K)
    w = np.maximum(np.abs(w), 1e-12 * np.abs(w).max())  # a stiffness scale, whatever its sign
    ZV = Z @ v
    S = ZV @ ((ZV.T @ _moment_arms(n)) / w[:, None])  # chord angles per unit pin moment
    step = np.vstack([-l * e.imag, l * e.real])  # d(rod vector) / d(theta)
    per, best = np.zeros(n + 1), (0.0, np.zeros(n + 1))
    for j in range(1, n):
        per[j], signs = _zonotope_max((step[:, :j] @ S[:j]) * tau)
        if per[j] > best[0]:
            best = (per[j], tau * signs)
    m = best[1]
    return BandScale(per, float(per.max()), m, float(m @ _moment_arms(n).T @ S @ m))


def _closed_start(chain: Chain, q0, lo, hi, last, rng, release):
    """Hinge angles ``release`` rad (seeded uniform) off ``q0`` within the bounds, the
    nearest closed onto B (SLSQP); None if no closed start is found."""
    n = chain.n
    free = hi > lo
    target = q0 + release * rng.uniform(-1.0, 1.0, n) * free
    target = np.clip(target, lo, hi)
    if release == 0.0:
        return q0.copy()
    l, d = chain.lengths, chain.anchor_b - chain.anchor_a
    tri = np.tril(np.ones((n, n)))

    def close(q):
        t = tri @ q
        return np.array([l @ np.cos(t) - d[0], l @ np.sin(t) - d[1]]) / chain.total_length

    def close_jac(q):
        t = tri @ q
        return np.vstack([-l * np.sin(t), l * np.cos(t)]) @ tri / chain.total_length

    cons = [{"type": "eq", "fun": close, "jac": close_jac}]
    for k, sign, bound in ((0, 1.0, last[0]), (1, -1.0, last[1])):
        if np.isfinite(bound):  # theta_{N-1} = sum q within its anchor stop
            cons.append({"type": "ineq", "fun": lambda q, s=sign, b=bound: s * (q.sum() - b),
                         "jac": lambda q, s=sign: s * np.ones(n)})
    bounds = [(a if np.isfinite(a) else None, b if np.isfinite(b) else None) for a, b in zip(lo, hi)]
    res = minimize(lambda q: 0.5 * np.sum((q - target) ** 2), q0, jac=lambda q: q - target,
                   bounds=bounds, constraints=cons, method="SLSQP", options={"ftol": 1e-14, "maxiter": 300})
    if not res.success or np.abs(close(res.x)).max() > 1e-10:
        return None
    return np.clip(res.x, lo, hi)


class _Sim:
    """The MuJoCo model of the dimensionless chain, its settle loop and its taps."""

    def __init__(self, xml: str, design: np.ndarray, q: np.ndarray):
        self.model = mujoco.MjModel.from_xml_string(xml)
        self.data = mujoco.MjData(self.model)
        self.n = self.model.nv
        self.bodies = np.array([self.model.body(f"rod{i}").id for i in range(self.n)])
        self.tip = self.model.site("tip").id
        self.design = design
        self.data.qpos[:] = q
        mujoco.mj_forward(self.model, self.data)

    def mass_matrix(self) -> np.ndarray:
        M = np.zeros((self.n, self.n))
        mujoco.mj_fullM(self.model, self.data, M)
        return M

    def rows(self, *types) -> np.ndarray:
        """Indices of the current constraint rows of these types."""
        return np.flatnonzero(np.isin(self.data.efc_type[: self.data.nefc], types))

    def creep(self) -> float:
        """How fast a pin at its full friction load creeps (rad / T): MuJoCo's soft dry
        friction yields ``R f / b`` (R the row's regulariser, b = 1 / timestep its reference
        damping), an upper bound for a pin that holds."""
        d = self.data
        fr = self.rows(mujoco.mjtConstraint.mjCNSTR_FRICTION_DOF, mujoco.mjtConstraint.mjCNSTR_FRICTION_TENDON)
        if not fr.size:
            return 0.0
        return float(np.max(d.efc_R[fr] * d.efc_frictionloss[fr])) * self.model.opt.timestep

    def points(self) -> np.ndarray:
        return np.vstack([self.data.xpos[self.bodies, :2], self.data.site_xpos[self.tip, :2]])

    def settle(self, vtol: float) -> tuple[bool, float]:
        """Step until at rest (max |qvel| < vtol on REST_CHECKS consecutive checks) or out of
        budget: (at rest, the largest joint distance from the design on the way)."""
        d, m = self.data, self.model
        t_end = d.time + SETTLE_TIME
        quiet, peak = 0, 0.0
        while quiet < REST_CHECKS and d.time < t_end:
            mujoco.mj_step(m, d, CHECK_STEPS)
            if d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number or not np.all(np.isfinite(d.qpos)):
                raise FloatingPointError(f"MuJoCo's simulation diverged (t = {d.time:.3f} T)")
            peak = max(peak, float(np.linalg.norm(self.points() - self.design, axis=1).max()))
            quiet = quiet + 1 if np.max(np.abs(d.qvel)) < vtol else 0
        d.qvel[:] = 0.0
        mujoco.mj_forward(m, d)
        return quiet >= REST_CHECKS, peak

    def kick(self, rng, energy: float, fixed: np.ndarray) -> None:
        """A tap: an impulse at a random point of a random rod in a random direction, as the
        velocities of the closed chain with its fused joints and the stops it rests on held
        (a light tap does not lift a rod off a loaded stop), scaled to kinetic energy
        ``energy``."""
        m, d, n = self.model, self.data, self.n
        rod = int(rng.integers(n))
        s, angle = rng.uniform(0.0, 1.0), rng.uniform(0.0, 2 * np.pi)
        p = self.points()
        at = p[rod] + s * (p[rod + 1] - p[rod])
        jac, jtip = np.zeros((3, n)), np.zeros((3, n))
        mujoco.mj_jac(m, d, jac, None, np.array([at[0], at[1], 0.0]), int(self.bodies[rod]))
        mujoco.mj_jacSite(m, d, jtip, None, self.tip)
        lim = self.rows(mujoco.mjtConstraint.mjCNSTR_LIMIT_JOINT, mujoco.mjtConstraint.mjCNSTR_LIMIT_TENDON)
        G = np.vstack([jtip[:2], np.eye(n)[fixed], d.efc_J.reshape(-1, n)[lim]])
        M = self.mass_matrix()
        Minv = np.linalg.inv(M)
        v = Minv @ (jac[:2].T @ np.array([np.cos(angle), np.sin(angle)]))
        MG = Minv @ G.T
        v -= MG @ np.linalg.lstsq(G @ MG, G @ v, rcond=None)[0]
        kin = 0.5 * v @ M @ v
        if kin > 1e-300 and energy > 0:
            d.qvel[:] = v * np.sqrt(energy / kin)


def tap_chain(lengths, masses, anchor_a, anchor_b, *, design_angles, capacity, com=None, limits=None,
              end_limits=None, g: float = 9.81, release: float = 0.01, n_taps: int = 10,
              strength: float = STRENGTH, seed: int = 0) -> TapResult:
    """Release the chain near its design, let it settle with pin friction, then tap it.

    Args:
        lengths, masses, anchor_a, anchor_b, com, limits, end_limits, g: the chain, as for
            :func:`optimize.solve_equilibrium` (lengths e.g. mm, masses g, angles rad;
            ``limits`` (N-1, 2) bend limits, lo == hi a fused joint; ``end_limits`` (2, 2)
            anchor stops on theta_0 and theta_{N-1}, or None).
        design_angles: (N,) the designed equilibrium's chord angles (rad).
        capacity: (N+1,) each pin's dry friction moment (force x length in the units of
            ``g``, masses and lengths, as :attr:`optimize.FrictionBand.capacity`; pin 0 at A,
            pin N at B). Fused joints hold without friction.
        release: how far the start is off the design (rad, each hinge uniform within
            +-release before closing onto B).
        n_taps: taps after the release. strength: each tap's kinetic energy in band energies
            (module docstring). seed: every random choice is drawn from
            ``np.random.default_rng(seed)``.

    Returns:
        TapResult (the caller's units).

    Raises:
        ValueError: bad arguments.
        FloatingPointError: MuJoCo's simulation diverged.
    """
    chain = Chain.from_args(lengths, masses, anchor_a, anchor_b, com, limits, g, end_limits)
    n = chain.n
    theta = np.asarray(design_angles, dtype=float).reshape(-1)
    tau = np.broadcast_to(np.asarray(capacity, dtype=float), (n + 1,)).copy()
    if theta.size != n or not np.all(np.isfinite(theta)):
        raise ValueError(f"design_angles must be {n} finite angles")
    if np.any(~np.isfinite(tau) | (tau < 0)) or not (release >= 0 and strength >= 0 and n_taps >= 0):
        raise ValueError("capacity, release, strength and n_taps must be finite and >= 0")
    tau[1:-1][chain.fixed] = 0.0  # a fused joint has no pin
    bends = np.angle(np.exp(1j * np.diff(theta)))
    theta = theta[0] + np.concatenate([[0.0], np.cumsum(bends)])  # the turn MuJoCo's hinges run on
    ends = None
    if np.isfinite(chain.end_limits).any():
        ends = chain.end_limits.copy()
        for k, t in ((0, theta[0]), (1, theta[-1])):
            ends[k] += limit_turn(t, ends[k])
    size, force = chain.total_length, chain.g * chain.total_mass
    rng = np.random.default_rng(seed)

    # the dimensionless chain: A at the origin, lengths / L, masses / M, g = 1
    b = (chain.anchor_b - chain.anchor_a) / size
    unit = Chain.from_args(chain.lengths / size, chain.masses / chain.total_mass, np.zeros(2), b,
                           chain.com / size, chain.limits, 1.0, ends)
    tau_ = tau / (force * size)
    scale = band_scale(unit, theta, tau_, ends)
    design = unit.points(theta)
    q_design = np.concatenate([theta[:1], bends])
    lo = np.concatenate([[ends[0, 0] if ends is not None else -np.inf], chain.limits[:, 0]])
    hi = np.concatenate([[ends[0, 1] if ends is not None else np.inf], chain.limits[:, 1]])
    last = ends[1] if ends is not None else np.array([-np.inf, np.inf])
    rows = (unit.lengths, unit.masses, unit.com, b, chain.limits, [None, None] if ends is None else list(ends), tau_)
    bare = _Sim(_mjcf(*rows, []), design, q_design)
    inertia = bare.mass_matrix()
    C = np.linalg.cholesky(inertia)  # alpha M = alpha C C': a damped tendon per column
    sim = _Sim(_mjcf(*rows, [(1.0, C[:, k]) for k in range(n)]), design, q_design)
    vtol = max(REST_VELOCITY, CREEP_FACTOR * sim.creep())

    notes = []
    q0 = _closed_start(unit, q_design, lo, hi, last, rng, float(release))
    if q0 is None:
        q0 = q_design
        notes.append("no closed start found that far off: hung from the design")
    sim.data.qpos[:] = q0
    mujoco.mj_forward(sim.model, sim.data)
    sim.model.tendon_damping[:n] = max(DECAY, 2.0 * slowest_mode(unit, theta, ends, inertia))
    converged, _ = sim.settle(vtol)
    sim.model.tendon_damping[:n] = DECAY
    qs, peaks = [sim.data.qpos.copy()], []
    rests = [sim.points()]
    fixed = np.concatenate([[False], chain.fixed])
    for _ in range(int(n_taps)):
        sim.kick(rng, strength * scale.energy, fixed)
        ok, peak = sim.settle(vtol)
        converged &= ok
        rests.append(sim.points())
        qs.append(sim.data.qpos.copy())
        peaks.append(peak)
    rests = np.array(rests)
    qs = np.array(qs)
    over = np.column_stack([lo - qs, qs - hi, last[0] - qs.sum(axis=1), qs.sum(axis=1) - last[1]])
    dist = np.linalg.norm(rests - design[None], axis=2) * size
    if not converged:
        notes.append(f"some settle did not come to rest within {SETTLE_TIME:g} sqrt(L / g)")
    msg = (f"hung {release:g} rad off the design, {int(n_taps)} taps of {strength:g} band energies: "
           f"largest joint distance {dist[0].max():.4g} at rest 0, {dist[-1].max():.4g} after the last")
    return TapResult(rests=rests * size + chain.anchor_a, deviation=dist.max(axis=1), per_joint=dist[-1],
                     converged=bool(converged), taps=int(n_taps), seed=int(seed),
                     message="; ".join([msg] + notes), peak=np.array(peaks) * size, band=scale.band * size,
                     band_energy=scale.energy * force * size, energy=strength * scale.energy * force * size,
                     end_error=np.linalg.norm(rests[:, -1] - b, axis=1) * size,
                     violation=np.maximum(over.max(axis=1), 0.0),
                     drift=vtol * REST_CHECKS * CHECK_STEPS * TIMESTEP * size,
                     start=unit.points(np.cumsum(q0)) * size + chain.anchor_a, sim_time=float(sim.data.time))
