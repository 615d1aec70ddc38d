"""Pins in their holes: the equilibrium of a chain with pin play, exactly.

Model
-----
Rod i is a rigid body with two pin holes whose centres are ``spacing_i`` apart (the
printed pin spacing); its centre of mass is given in the *hole frame*: origin at the first
hole's centre, x toward the second's. Pin j (j = 0..N) joins rod j-1's second hole and rod
j's first; pins 0 and N are the anchors A and B, fixed. A pin is a massless point that must
stay within ``c_j / 2`` of the centre of every hole it passes through (``c_j`` the diametral
clearance, hole minus pin diameter). Stops bound the relative angle of consecutive rod
*bodies*; anchor stops bound the first and last bodies' angles.

Exact reduction
---------------
A massless pin bears on the walls of its two holes with opposite, equal forces along the
lines through its centre, so wherever pin j carries a force its two hole centres are exactly
``c_j`` apart along that force, the pin half-way between them (at an anchor the pin's centre
is the anchor and the gap is ``c_j / 2``). The force the part of the chain right of pin j
exerts on the part left of it is ``F_j = lambda - i g S_j`` (complex numbers for planar
vectors; ``lambda = H + iV`` the reaction at B, ``S_j`` the mass of rods j..N-1): it depends on
the reaction only. So the chain with play is the chain of rod bodies with a massless link
of length ``c_j`` (``c/2`` at the anchors) at every pin, turned along ``F_j``; in the dual of
:mod:`optimize.chain.equilibrium` each link is one more Fermat-Weber term::

    Psi(lambda) = sum_G |P_G lambda - Q_G| + sum_j c_j |lambda - i g S_j| - Re(conj(B - A) lambda)

(the groups G of rod bodies as there, with the spacings for lengths). It is still convex in
(H, V) and its gradient is the closure through the rods *and* the links; damped Newton costs
O(N) per iteration. Stops join rod bodies into rigid groups (the links between them keep
turning with the force); an anchor stop holds a group at a fixed angle (a constant chord,
no term). The active set of stops and anchor stops is found by exchange as in
:mod:`optimize.chain.equilibrium`; where that fails (a rigid piece that pushes), the equilibrium is
the fixed point of solving the chain without play between anchors moved by the links
(:func:`optimize.solve_equilibrium`, which handles every case), iterated to round-off.
With ``c = 0`` everywhere this is :func:`optimize.solve_equilibrium`.

A fused joint (lo == hi) is one printed piece: it has no pin and no play there, unless the
caller says it keeps its pin (``pinned``: a two-sided stop, whose pin carries the force with its
play while the stops hold the bodies' relative angle).
"""

from __future__ import annotations

import numpy as np

from optimize import validate as val
from optimize.chain.branches import branch_newton
from optimize.chain.model import ANGLE_TOL, MOMENT_TOL, Chain, Groups, stable_on_closure
from optimize.chain.endlimits import as_end_limits, limit_turn
from optimize.chain.dual import dual_newton, initial_reaction
from optimize.chain.equilibrium import solve_equilibrium
from optimize.chain.pins import PLAY_MESSAGES, PinPlayResult, joint_forces

__all__ = ["PinPlayResult", "PLAY_MESSAGES", "joint_forces", "solve_pin_play"]


class _Play:
    """The chain of rod bodies and the links at its pins (see the module docstring)."""

    def __init__(self, chain: Chain, clearance: np.ndarray, ends: np.ndarray | None, pinned=None):
        self.chain = chain
        self.ends = ends
        c = clearance.copy()
        c[1:-1][chain.fixed & ~val.as_pinned(pinned, chain.n)] = 0.0  # a fused joint has no pin
        self.clearance = c
        self.cl = c.copy()  # link lengths: c at a pin between rods, c/2 at A and B
        self.cl[[0, -1]] *= 0.5
        m = chain.masses
        self.after = np.concatenate([np.cumsum(m[::-1])[::-1], [0.0]])  # S_j, j = 0..N
        self.has_link = self.cl > 0
        self.Pl = self.cl[self.has_link].astype(complex)
        self.Ql = self.Pl * 1j * chain.g * self.after[self.has_link]
        self.length = chain.total_length + float(self.cl.sum())
        self.scale = chain.g * chain.total_mass * self.length

    # --- the reaction's consequences -------------------------------------------------
    def forces(self, lam: complex) -> np.ndarray:
        F = joint_forces((lam.real, lam.imag), self.chain.masses, g=self.chain.g)
        return F[:, 0] + 1j * F[:, 1]

    def links(self, lam: complex) -> np.ndarray:
        """(N+1,) complex gap vectors, hole to hole (anchor to hole at A, hole to anchor at B)."""
        F = self.forces(lam)
        r = np.abs(F)
        return np.where(r > 0, self.cl * F / np.where(r > 0, r, 1.0), 0.0)

    # --- one active set ----------------------------------------------------------------
    def _bound(self, e: int, s: int) -> float:
        return float(self.ends[e, 0 if s < 0 else 1])

    def setup(self, side: np.ndarray, eside: np.ndarray):
        """Groups, the held groups' angles and the dual's terms for an active set, or None
        when the set cannot reach B."""
        chain = self.chain
        groups = Groups(chain, side)
        fixed_psi = np.full(groups.P.size, np.nan)
        if eside[0]:
            fixed_psi[0] = self._bound(0, eside[0])
        if eside[1]:
            last = groups.gid[-1]
            if eside[0] and last == 0:
                return None  # one rigid piece held at both ends: no freedom left
            fixed_psi[last] = self._bound(1, eside[1]) - groups.offsets[-1]
        held = np.isfinite(fixed_psi)
        fixed = np.conj(groups.P[held]) * np.exp(1j * fixed_psi[held])
        d_eff = chain.d - fixed.sum()
        P = np.concatenate([groups.P[~held], self.Pl])
        Q = np.concatenate([groups.Q[~held], self.Ql])
        lengths = np.abs(P)
        total = lengths.sum()
        if total <= 0 or not (2 * lengths.max() - total + 1e-12 * total < abs(d_eff) < total * (1 - 1e-12)):
            return None
        return groups, held, fixed_psi, d_eff, P, Q

    def solve_set(self, side, eside, lam, theta=None):
        """The equilibrium for one active set: (theta, lam, newton steps) or None.

        Each free group turns along its load (the convex dual) unless ``theta``, a previous
        configuration, has it pointing against the load (a piece that pushes): then the
        closure is solved on those branches (:func:`optimize.chain.branches.branch_newton`).
        """
        setup = self.setup(side, eside)
        if setup is None:
            return None
        groups, held, fixed_psi, d_eff, P, Q = setup
        nfree = int(np.count_nonzero(~held))
        signs = np.ones(P.size)
        if theta is not None:
            psi0 = (theta[groups.starts] - groups.offsets[groups.starts])[~held]
            W0 = P[:nfree] * lam - Q[:nfree]
            signs[:nfree] = np.where((np.exp(1j * psi0) * np.conj(W0)).real < 0, -1.0, 1.0)
        if np.all(signs > 0):
            lam1, W, k, converged = dual_newton(P, Q, d_eff, lam, self.length)
            if not converged and nfree:
                # the dual's minimum on a group's kink (no load on it): that group pushes
                # (e.g. a rod wedged between its pins); solve with it on the other branch
                g = int(np.argmin(np.abs(W[:nfree]) / np.maximum(np.abs(P[:nfree]), 1e-300)))
                signs[g] = -1.0
                step = abs(lam1) + self.chain.g * self.chain.total_mass
                for shift in np.array([-1, 1, -1j, 1j]) * step * 0.1:  # off the kink, each way
                    lam2, W, k2, converged = branch_newton(P, Q, d_eff, signs, lam1 + shift, self.length)
                    k += k2
                    if converged:
                        lam1 = lam2
                        break
            lam = lam1
        else:
            lam, W, k, converged = branch_newton(P, Q, d_eff, signs, lam, self.length)
        if not converged:
            return None
        psi = fixed_psi.copy()
        psi[~held] = np.angle(signs[:nfree] * W[:nfree])
        theta = np.unwrap(psi[groups.gid] + groups.offsets)
        return theta, lam, k

    # --- statics of a configuration ------------------------------------------------------
    def statics(self, theta, lam, side, eside):
        """Stop moments (N-1,), anchor-stop moments (2,) and per-rod curvatures (N,)."""
        chain = self.chain
        z = lam - chain.sigma
        e = np.exp(1j * theta)
        f = chain.lengths * (np.conj(z) * e).imag  # d(Lagrangian)/d(theta_k)
        curv = chain.lengths * (np.conj(z) * e).real
        groups = Groups(chain, side)
        e0 = float(f[groups.gid == 0].sum()) if eside[0] else 0.0
        cum = np.cumsum(f)
        moments = e0 - cum[:-1]
        return moments, np.array([e0, float(cum[-1]) - e0]), curv

    def _near(self, theta: float, e: int) -> float:
        return float(theta - limit_turn(theta, self.ends[e]))

    def violations(self, theta, lam, side, eside, moments, end_moments):
        """Primal (limits passed by free joints/ends) and dual (wrong-sign moments)
        violations over joints then ends, (N+1,) each, and the side each primal one is on."""
        chain = self.chain
        lo, hi = chain.limits[:, 0], chain.limits[:, 1]
        phi = np.diff(theta)
        free = side == 0
        over = free & (phi > hi + ANGLE_TOL)
        under = free & (phi < lo - ANGLE_TOL)
        primal = list(np.where(over, phi - hi, np.where(under, lo - phi, 0.0)))
        pside = list(np.where(over, 1, np.where(under, -1, 0)))
        for e, t in ((0, theta[0]), (1, theta[-1])):
            v, s = 0.0, 0
            if self.ends is not None and not eside[e]:
                t = self._near(t, e)
                if t > self.ends[e, 1] + ANGLE_TOL:
                    v, s = t - self.ends[e, 1], 1
                elif t < self.ends[e, 0] - ANGLE_TOL:
                    v, s = self.ends[e, 0] - t, -1
            primal.append(v)
            pside.append(s)
        tol = MOMENT_TOL * self.scale
        movable = ~chain.fixed
        wrong = np.where((side < 0) & movable & (moments < -tol), -moments, 0.0)
        wrong = np.where((side > 0) & movable & (moments > tol), moments, wrong)
        ewrong = np.where((eside < 0) & (end_moments < -tol), -end_moments, 0.0)
        ewrong = np.where((eside > 0) & (end_moments > tol), end_moments, ewrong)
        return (np.array(primal), np.array(pside, dtype=int),
                np.concatenate([wrong, ewrong]) / self.scale)

    def kkt(self, theta, lam, side, eside, moments, end_moments) -> float:
        chain = self.chain
        rods = chain.lengths * np.exp(1j * theta)
        closure = abs(rods.sum() + self.links(lam).sum() - chain.d) / self.length
        free = side == 0
        stat = max(np.max(np.abs(moments[free]), initial=0.0),
                   max((abs(end_moments[e]) for e in (0, 1) if not eside[e]), default=0.0)) / self.scale
        lo, hi = chain.limits[:, 0], chain.limits[:, 1]
        phi = np.diff(theta)
        feas = max(float(np.max(np.maximum(lo - phi, phi - hi), initial=0.0)), 0.0)
        if self.ends is not None:
            for e, t in ((0, theta[0]), (1, theta[-1])):
                t = self._near(t, e)
                feas = max(feas, self.ends[e, 0] - t, t - self.ends[e, 1])
        _, _, wrong = self.violations(theta, lam, side, eside, moments, end_moments)
        return float(max(closure, stat, feas, float(wrong.max(initial=0.0))))

    def stable(self, theta, lam, side, eside, moments, end_moments, curv) -> bool:
        """Second-order test on the bodies and links that turn (binding stops and anchor
        stops hold theirs); stops with a vanishing moment count as free (conservative)."""
        chain = self.chain
        tol = 1e3 * MOMENT_TOL * self.scale
        binding = (side != 0) & (chain.fixed | (np.abs(moments) > tol))
        ebind = (eside != 0) & (np.abs(end_moments) > tol)
        groups = Groups(chain, np.where(binding, side, 0))
        D = np.add.reduceat(curv, groups.starts)
        chords = np.add.reduceat(chain.lengths * np.exp(1j * theta), groups.starts)
        turn = np.ones(D.size, dtype=bool)
        if ebind[0]:
            turn[0] = False
        if ebind[1]:
            turn[groups.gid[-1]] = False
        F = self.forces(lam)[self.has_link]
        D = np.concatenate([D[turn], self.cl[self.has_link] * np.abs(F)])
        cols = 1j * np.concatenate([chords[turn], self.links(lam)[self.has_link]])
        return stable_on_closure(D, cols, self.length)


def _next_set(play: _Play, sides, primal, pside, dual, mode):
    """The next active set over joints then ends: every violation exchanged at once, or
    the worst primal violation alone (the worst dual one when there is none)."""
    n1 = play.chain.n - 1

    def ok(new):
        return play.setup(new[:n1], new[n1:]) is not None

    if mode == "exchange":
        new = sides.copy()
        new[dual > 0] = 0
        new[primal > 0] = pside[primal > 0]
        if ok(new):
            return new
    for j in np.argsort(-primal):
        if primal[j] <= 0:
            break
        new = sides.copy()
        new[j] = pside[j]
        if ok(new):
            return new
    if dual.any():
        new = sides.copy()
        new[int(np.argmax(dual))] = 0
        return new
    return None


def _start(play: _Play, spacings, masses, a, b, com, limits, end_limits, g, active0, theta0=None):
    """A start: the chain without play whose rods are longer by the gaps at their pins
    (its active set and reaction), or every joint free and the two-bar reaction."""
    chain = play.chain
    n = chain.n
    half = 0.5 * play.clearance
    longer = spacings + half[:-1] + half[1:]
    shifted = com + np.column_stack([half[:-1], np.zeros(n)])
    side = np.zeros(n - 1, dtype=int)
    eside = np.zeros(2, dtype=int)
    lam = theta = None
    try:
        r = solve_equilibrium(longer, masses, a, b, com=shifted, limits=limits, end_limits=end_limits, g=g,
                              theta0=theta0)
        if np.all(np.isfinite(r.reaction)):
            side = np.asarray(r.active, dtype=int)
            eside = np.asarray(r.info.get("end_active", eside), dtype=int)
            lam = complex(*r.reaction)
            theta = r.angles
    except ValueError:
        pass
    if active0 is not None:
        side = np.asarray(active0, dtype=int)
        if side.shape != (n - 1,) or not np.all(np.isin(side, (-1, 0, 1))):
            raise ValueError(f"active0 must have shape ({n - 1},) with entries -1, 0 or 1")
    lo, hi = chain.limits[:, 0], chain.limits[:, 1]
    side = np.where((side < 0) & np.isfinite(lo), -1, np.where((side > 0) & np.isfinite(hi), 1, 0))
    side = np.where(chain.fixed, -1, side)
    if play.ends is None:
        eside[:] = 0
    else:
        eside = np.array([s if s and np.isfinite(play.ends[e, 0 if s < 0 else 1]) else 0
                          for e, s in enumerate(eside)], dtype=int)
    if lam is None or play.setup(side, eside) is None:
        side, eside = np.where(chain.fixed, -1, 0), np.zeros(2, dtype=int)
        lam, theta = initial_reaction(chain), None
    return side, eside, lam, theta


def _exchange(play: _Play, side, eside, lam, theta, max_iter):
    """Active-set exchange with the play dual: (theta, lam, side, eside, it, newton) or None."""
    n1 = play.chain.n - 1
    sides = np.concatenate([side, eside])
    mode = "exchange"
    visited: set[bytes] = set()
    nnewton = 0
    for it in range(1, max_iter + 1):
        side, eside = sides[:n1], sides[n1:]
        sol = play.solve_set(side, eside, lam, theta)
        if sol is None:
            return None
        theta, lam, k = sol
        nnewton += k
        moments, end_moments, _ = play.statics(theta, lam, side, eside)
        primal, pside, dual = play.violations(theta, lam, side, eside, moments, end_moments)
        if not primal.any() and not dual.any():
            return theta, lam, side.copy(), eside.copy(), it, nnewton
        key = sides.tobytes()
        if key in visited:
            if mode == "single":
                return None
            mode, visited = "single", set()
        visited.add(key)
        new = _next_set(play, sides, primal, pside, dual, mode)
        if new is None:
            return None
        new[:n1] = np.where(play.chain.fixed, -1, new[:n1])
        sides = new
    return None


def _fixed_point(play: _Play, spacings, masses, com, limits, end_limits, lam, max_iter=200):
    """The equilibrium as the fixed point lambda -> reaction of the chain without play
    between A + gap_0 and B - (the other gaps): each rod body then hangs as in the chain
    with play, whose links are constant for a given lambda."""
    chain = play.chain
    a = chain.anchor_a
    d = chain.d
    active0 = None
    r = None
    best = np.inf
    for it in range(1, max_iter + 1):
        v = play.links(lam)
        a2 = a + np.array([v[0].real, v[0].imag])
        d2 = d - v.sum()
        b2 = a2 + np.array([d2.real, d2.imag])
        try:
            r = solve_equilibrium(spacings, masses, a2, b2, com=com, limits=limits, end_limits=end_limits,
                                  g=chain.g, active0=active0)
        except ValueError:  # the gaps leave the rods unable to reach: no fixed point here
            return None
        if not (r.success and np.all(np.isfinite(r.reaction))):
            return None
        new = complex(*r.reaction)
        active0 = r.active
        step = abs(new - lam)
        lam = new
        if step <= 1e-14 * abs(lam) or (step >= best and step <= 1e-11 * abs(lam)):
            break  # converged, or at the floor of the inner solver's round-off
        best = min(best, step)
    else:
        return None
    eside = np.asarray(r.info.get("end_active", np.zeros(2, dtype=int)), dtype=int)
    theta = r.angles[0] + np.concatenate([[0.0], np.cumsum(np.angle(np.exp(1j * np.diff(r.angles))))])
    return theta, lam, np.asarray(r.active, dtype=int), eside, it


def solve_pin_play(
    spacings,
    masses,
    anchor_a,
    anchor_b,
    *,
    clearance,
    com=None,
    limits=None,
    end_limits=None,
    g: float = 9.81,
    active0=None,
    max_iter: int | None = None,
    method: str = "auto",
    pinned=None,
    theta0=None,
) -> PinPlayResult:
    """Static equilibrium of a chain whose pins sit in their holes with play.

    Args:
        spacings: (N,) each rod's printed pin spacing (hole centre to hole centre), > 0.
        masses: (N,) rod masses, > 0 (only their ratios shape the chain).
        anchor_a, anchor_b: (2,) the anchor pins' centres A = p_0 and B = p_N.
        clearance: diametral clearance (hole diameter minus pin diameter), the caller's length
            unit, >= 0: a number for every pin or (N+1,) one per pin (pins 0 and N are the
            anchors). A fused joint (lo == hi) has no pin: its clearance is ignored.
        com: (N, 2) centres of mass in each rod's hole frame (origin at the first hole's
            centre, x toward the second's); None = (spacing/2, 0).
        limits: (N-1, 2) [lo, hi] radians on the relative angle of consecutive rod bodies,
            as for :func:`optimize.solve_equilibrium`; None = free.
        end_limits: (2, 2) [lo, hi] radians on the first and last bodies' angles; None = free.
        g: gravitational acceleration, along -y.
        active0: optional (N-1,) starting active set (-1 lo, 0 free, +1 hi).
        max_iter: cap on active-set iterations (default 10 + 4 N).
        pinned: optional (N-1,) bool: joints with lo == hi that keep their pin and its play
            (a two-sided stop: the stops hold the bodies' angle, the pin still carries the
            force); the others with lo == hi are printed as one piece (no pin). None: none.
        theta0: optional (N,) rod angles (rad) to start from (e.g. the designed chain's): the
            chain without play is solved from them (:func:`optimize.solve_equilibrium`'s
            ``theta0``), so a chain with several stable shapes stays in the one it is hung in.
        method: "auto" (the dual with the links, the fixed point where its active-set
            exchange fails), "dual" (no fallback) or "fixed-point" (only the fixed point over
            :func:`optimize.solve_equilibrium`; slower, for comparison).

    Returns:
        PinPlayResult; with ``clearance = 0`` its points are those of
        :func:`optimize.solve_equilibrium` with ``lengths = spacings``.

    Raises:
        ValueError: bad arguments, or anchors that no configuration reaches.

    Example:
        >>> r = solve_pin_play([1, 1], [1, 1], (0, 0), (1.2, 0), clearance=0.01)
        >>> bool(r.success and r.kkt_residual < 1e-12)
        True
    """
    if method not in ("auto", "dual", "fixed-point"):
        raise ValueError(f"method must be 'auto', 'dual' or 'fixed-point', got {method!r}")
    chain = Chain.from_args(spacings, masses, anchor_a, anchor_b, com, limits, g)
    clear = val.as_clearance(clearance, chain.n)
    ends = as_end_limits(end_limits)
    play = _Play(chain, clear, ends, pinned)
    reach = chain.total_length + float(play.cl.sum())
    if chain.span >= reach * (1 - 1e-12):
        raise ValueError(f"anchors are too far apart for the chain with its play (|B - A| = "
                         f"{chain.span:.6g}, rods and gaps at most {reach:.6g} long)")
    longest = float(chain.lengths.max())
    if chain.span < longest - (reach - longest) - 1e-12 * reach:
        raise ValueError(f"anchors are too close: a rod of spacing {longest:.6g} is longer than the "
                         "rest of the chain and the anchor distance together")
    if max_iter is None:
        max_iter = 10 + 4 * chain.n
    side, eside, lam, theta0 = _start(play, chain.lengths, chain.masses, chain.anchor_a, chain.anchor_b,
                              chain.com, chain.limits, ends, chain.g, active0, theta0)
    found = None if method == "fixed-point" else _exchange(play, side, eside, lam, theta0, max_iter)
    path = "exchange"
    status = 0
    nit = nnewton = 0
    if found is not None:
        theta, lam, side, eside, nit, nnewton = found
    elif method == "dual":
        status = 3
        theta = theta0 if theta0 is not None else np.full(chain.n, np.angle(chain.d))
    else:
        path = "fixed-point"
        fp = _fixed_point(play, chain.lengths, chain.masses, chain.com, chain.limits, ends, lam)
        if fp is None:
            status = 2
            theta = Groups(chain, np.where(chain.fixed, -1, 0)).angles(np.full(chain.n, 1.0 + 0j))
            side, eside = np.where(chain.fixed, -1, 0), np.zeros(2, dtype=int)
        else:
            theta, lam, side, eside, nit = fp
    return _assemble(play, theta, lam, side, eside, status, nit, nnewton, path)


def _assemble(play: _Play, theta, lam, side, eside, status, nit, nnewton, path) -> PinPlayResult:
    chain = play.chain
    n = chain.n
    moments, end_moments, curv = play.statics(theta, lam, side, eside)
    moments = np.where(side != 0, moments, 0.0)
    kkt = play.kkt(theta, lam, side, eside, moments, end_moments)
    end_moments = np.where(eside != 0, end_moments, 0.0)
    v = play.links(lam)
    rods = chain.lengths * np.exp(1j * theta)
    a = complex(*chain.anchor_a)
    first = a + np.cumsum(v[:-1]) + np.concatenate([[0.0], np.cumsum(rods[:-1])])
    second = first + rods
    pins = np.concatenate([[a], second[:-1] + 0.5 * v[1:-1], [complex(*chain.anchor_b)]])
    closure = abs(second[-1] + v[-1] - complex(*chain.anchor_b))
    com_w = first + np.exp(1j * theta) * (chain.com[:, 0] + 1j * chain.com[:, 1])
    F = play.forces(lam)
    success = status == 0 and kkt < 1e-9
    if status == 0 and not success:
        status = 1
    stable = bool(status in (0, 1) and play.stable(theta, lam, side, eside, moments, end_moments, curv))

    def xy(z):
        return np.column_stack([np.real(z), np.imag(z)])

    weight = chain.g * chain.total_mass
    return PinPlayResult(
        points=xy(pins),
        holes=np.stack([xy(first), xy(second)], axis=1),
        angles=np.asarray(theta, float),
        com=xy(com_w),
        forces=xy(F),
        reaction=np.array([lam.real, lam.imag]),
        reaction_a=np.array([-lam.real, weight - lam.imag]),
        moments=moments,
        active=np.asarray(side, dtype=int).copy(),
        end_moments=end_moments,
        end_active=np.asarray(eside, dtype=int).copy(),
        kkt_residual=kkt,
        closure_error=float(closure),
        energy=float(chain.g * np.dot(chain.masses, com_w.imag)),
        stable=stable,
        success=success,
        status=status,
        message=PLAY_MESSAGES[status],
        nit=nit,
        nnewton=nnewton,
        info={"path": path, "clearance": play.clearance.copy(), "n": n},
    )
