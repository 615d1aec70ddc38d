"""Exact static equilibrium of a planar chain of rigid rods hung between two anchors.

Conventions (``shared/design/physics.md``): rods ``0..N-1`` with chord angles
``theta_i`` from +x, joint points ``p_0 = A .. p_N = B``, bends
``phi_j = theta_{j+1} - theta_j``, gravity along -y, each rod's centre of mass
``(along, perp)`` in its own frame.

Method
------
With the closure multiplier ``lambda = (H, V)`` (the support reaction at B), the
Lagrangian separates rod by rod::

    L = sum_k -l_k Re(conj(lambda - sigma_k) e^{i theta_k}) + lambda . (B - A)
    sigma_k = g (m_k perp_k / l_k  +  i (S_k + m_k along_k / l_k)),  S_k = sum_{i>k} m_i

(complex numbers stand for planar vectors). Rods joined by joints held at a
limit form rigid groups; a group with first-rod angle ``psi`` and offsets
``o_k`` contributes ``-Re(conj(P_G lambda - Q_G) e^{i psi})`` with constants
``P_G = sum l_k e^{-i o_k}``, ``Q_G = sum l_k e^{-i o_k} sigma_k``. Minimising
over every ``psi`` gives the dual function, a weighted Fermat-Weber problem::

    Psi(lambda) = sum_G |P_G lambda - Q_G| - Re(conj(B - A) lambda)

which is convex in the two unknowns (H, V); its gradient is the closure
residual. Damped Newton on ``Psi`` therefore converges from any start, each
iteration costing O(number of groups), and the minimiser is the global minimum
of the potential energy for that set of locked joints (Lagrangian sufficiency).
The set of joints held at a limit is found by an active-set iteration (primal
and dual violations exchanged all at once, then one at a time if that cycles).
When that fails (a rigid group must push: its angle on the other branch of
``|P_G lambda - Q_G|``, or the exchange cycles) the active-set descent over
(side, branch) of :mod:`optimize.branches` takes over, and SLSQP from several
starts only after that. Either way the final point satisfies the KKT conditions
exactly: closure to round-off, limits as hard inequalities, and joint moments of
the right sign. ``info['path']`` says which ("exchange", "descent", "slsqp").
"""

from __future__ import annotations

import numpy as np

from optimize.chain import (
    MESSAGES,
    Chain,
    EquilibriumResult,
    Groups,
    is_stable,
    kkt_residual,
    multipliers,
    sag_guess,
    violations,
)
from optimize.branches import descend, polish_nlp
from optimize.endlimits import as_end_limits, solve_with_end_limits
from optimize.penalty import solve_penalty

__all__ = ["Chain", "EquilibriumResult", "solve_equilibrium", "kkt_residual", "MESSAGES"]


def _initial_reaction(chain: Chain) -> complex:
    """A rough (H, V): the two-bar V with the whole weight hung at mid-span."""
    weight = chain.g * chain.total_mass
    slack = np.sqrt(max(chain.total_length**2 - chain.span**2, 1e-6 * chain.total_length**2))
    h = 0.5 * weight * chain.d.real / slack
    if abs(h) < 1e-3 * weight:
        h = 1e-3 * weight
    return complex(h, 0.5 * weight + 0.5 * weight * chain.d.imag / slack)


def _dual_newton(P, Q, d, lam, length_scale, max_iter=200):
    """Minimise Psi(lam) = sum|P lam - Q| - Re(conj(d) lam) by damped Newton.

    Returns (lam, W = P lam - Q, iterations, converged).
    """
    absP = np.abs(P)
    absP2 = absP * absP
    safeP = np.where(absP > 0, absP, 1.0)
    tol = 64 * np.finfo(float).eps * length_scale
    tiny = 1e-300

    def evaluate(lam):
        W = P * lam - Q
        r = np.abs(W)
        rs = np.maximum(r, tiny)
        u = W / rs
        grad = np.sum(np.conj(P) * u) - d
        psi = float(r.sum() - (np.conj(d) * lam).real)
        return W, rs, u, grad, psi

    W, r, u, grad, psi = evaluate(lam)
    best_gn = abs(grad)
    stall = 0
    load_scale = float(np.max(np.abs(Q) / safeP)) if Q.size else 0.0
    for it in range(1, max_iter + 1):
        gn = abs(grad)
        if gn <= tol:
            return lam, W, it - 1, True
        a = absP2 / r
        v = u * np.conj(P) / safeP
        vx, vy = v.real, v.imag
        hxx = float(np.sum(a * vy * vy))
        hyy = float(np.sum(a * vx * vx))
        hxy = -float(np.sum(a * vx * vy))
        det = hxx * hyy - hxy * hxy
        trace = hxx + hyy
        if not np.isfinite(det) or det <= 1e-14 * trace * trace:
            reg = 1e-8 * trace + tiny
            hxx += reg
            hyy += reg
            det = hxx * hyy - hxy * hxy
        gx, gy = grad.real, grad.imag
        step = complex(-(hyy * gx - hxy * gy) / det, -(hxx * gy - hxy * gx) / det)
        slope = (np.conj(grad) * step).real
        t = 1.0
        while True:
            trial = lam + t * step
            W1, r1, u1, g1, psi1 = evaluate(trial)
            if psi1 <= psi + 1e-4 * t * slope:
                break
            noise = 1e3 * np.finfo(float).eps * (abs(psi) + abs(psi1))
            if abs(psi1 - psi) <= noise and abs(g1) < gn:
                break  # the energy change is below round-off: judge by the gradient
            if t < 1e-12:
                break
            t *= 0.5
        lam, W, r, u, grad, psi = trial, W1, r1, u1, g1, psi1
        k = int(np.argmin(r / safeP))
        if r[k] <= 1e-6 * load_scale * safeP[k]:
            # near a group's kink (W_k = 0): is lam_k = Q_k / P_k the minimum? It is when
            # the rest's gradient lies within the subdifferential |P_k| of that term.
            lam_k = Q[k] / P[k]
            W_k = P * lam_k - Q
            W_k[k] = 0.0
            u_k = W_k / np.maximum(np.abs(W_k), tiny)
            if abs(np.sum(np.conj(P) * u_k) - d) <= absP[k] * (1 + 1e-12):
                return lam_k, W_k, it, False
        if abs(grad) < best_gn * 0.999:
            best_gn = abs(grad)
            stall = 0
        else:
            stall += 1
            if stall >= 3 and best_gn <= 1e-9 * length_scale:
                return lam, W, it, True  # at the floor of round-off
            if stall >= 20:
                break
            if stall >= 5 and r[k] <= 1e-10 * load_scale * safeP[k]:
                lam = Q[k] / P[k]  # no load left on group k: the minimum sits on its kink
                return lam, P * lam - Q, it, False
    return lam, W, max_iter, abs(grad) <= 1e-9 * length_scale


def _close_at_kink(chain: Chain, groups: Groups, W: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Exact closure when the dual optimum sits next to a kink.

    When one group carries almost no load (|W_G| -> 0, e.g. a bottom rod that spans a
    slack chain exactly horizontally) Newton converges slowly and stops a little short.
    That group's angle is then undetermined by statics; turn it so the chain closes.
    """
    chords = np.add.reduceat(chain.lengths * np.exp(1j * theta), groups.starts)
    miss = chords.sum() - chain.d
    if abs(miss) <= 1e-14 * chain.total_length:
        return theta
    load = np.abs(W) / np.maximum(groups.chords, 1e-300)
    g = int(np.argmin(load))
    need = chain.d - (chords.sum() - chords[g])
    if abs(abs(need) - groups.chords[g]) > 1e-6 * chain.total_length:
        return theta  # not a kink: leave it to the KKT check
    turn = np.angle(need / chords[g])
    in_g = groups.gid == g
    out = theta.copy()
    out[in_g] += turn
    return np.unwrap(out)


def _taut(chain: Chain) -> EquilibriumResult:
    angle = np.angle(chain.d)
    theta = np.full(chain.n, angle)
    lo, hi = chain.limits[:, 0], chain.limits[:, 1]
    ok = bool(np.all((lo <= 0) & (hi >= 0)))
    pts = chain.points(theta)
    pts[-1] = chain.anchor_b
    inf = np.full(2, np.inf)
    return EquilibriumResult(
        points=pts,
        angles=theta,
        reaction=inf,
        reaction_a=inf,
        moments=np.zeros(chain.n - 1),
        active=np.zeros(chain.n - 1, dtype=int),
        kkt_residual=0.0 if ok else float(np.max(np.maximum(lo, -hi))),
        closure_error=0.0,
        energy=chain.energy(theta),
        stable=ok,
        success=ok,
        status=4 if ok else 5,
        message=MESSAGES[4 if ok else 5],
    )


def _check_reach(chain: Chain) -> None:
    """Raise ValueError when no configuration of the rods can reach anchor B."""
    total = chain.total_length
    if chain.span > total * (1 + 1e-12):
        raise ValueError(
            f"anchors are {chain.span - total:.6g} farther apart than the chain is long "
            f"(|B - A| = {chain.span:.6g}, total rod length = {total:.6g})"
        )
    k = int(np.argmax(chain.lengths))
    rest = total - chain.lengths[k]
    if chain.span < chain.lengths[k] - rest - 1e-12 * total:
        raise ValueError(
            f"anchors are too close: rod {k} (length {chain.lengths[k]:.6g}) is longer than "
            f"the other rods together ({rest:.6g}) plus the anchor distance ({chain.span:.6g})"
        )


def _solve_exact(chain: Chain, active0, max_iter: int) -> EquilibriumResult:
    n = chain.n
    lo, hi = chain.limits[:, 0], chain.limits[:, 1]
    side = np.zeros(n - 1, dtype=int)
    if active0 is not None:
        a0 = np.asarray(active0, dtype=int)
        if a0.shape != (n - 1,) or not np.all(np.isin(a0, (-1, 0, 1))):
            raise ValueError(f"active0 must have shape ({n - 1},) with entries -1, 0 or 1")
        side = np.where((a0 < 0) & np.isfinite(lo), -1, np.where((a0 > 0) & np.isfinite(hi), 1, 0))
    side = np.where(chain.fixed, -1, side)
    if not Groups(chain, side).reachable(chain.span):
        side = np.where(chain.fixed, -1, 0)
        if not Groups(chain, side).reachable(chain.span):
            raise ValueError(
                "the rigid joints (lo == hi) leave no configuration that reaches anchor B"
            )

    lam = _initial_reaction(chain)
    visited: set[bytes] = set()
    mode = "exchange"
    nnewton = 0
    status = 1
    used_nlp = False
    theta = None
    last = None
    hanging = None
    it = 0
    for it in range(1, max_iter + 1):
        groups = Groups(chain, side)
        lam_try, W, k, converged = _dual_newton(
            groups.P, groups.Q, chain.d, lam, chain.total_length
        )
        nnewton += k
        if it == 1 and not np.any(side[~chain.fixed]):
            hanging = (groups, W)  # the chain hanging freely: a start for the descent
        if not converged:
            # a kink where the unloaded group just fits the gap: closure decides its angle
            theta_k = _close_at_kink(chain, groups, W, groups.angles(W))
            if kkt_residual(chain, theta_k, lam_try, side) < 1e-10:
                converged = True
        if not converged:
            # the dual optimum sits on a kink: a rigid group with no net load, whose
            # minimum lies on another branch. Step back and change one joint at a time.
            if last is None or mode == "single":
                status = 2
                break
            mode = "single"
            side, theta, lam, primal, pside, dual = last
            new = _next_active_set(chain, side, primal, pside, dual, mode)
            if new is None:
                status = 3
                break
            side = new
            continue
        lam = lam_try
        theta = _close_at_kink(chain, groups, W, groups.angles(W))
        primal, pside, dual = violations(chain, theta, lam, side)
        last = (side, theta, lam, primal, pside, dual)
        if not primal.any() and not dual.any():
            status = 0
            break
        key = side.tobytes()
        if key in visited and mode == "exchange":
            mode = "single"  # exchanging everything at once cycles: go one joint at a time
            visited = set()
        elif key in visited:
            status = 3  # cycles one joint at a time too: fall back below
            break
        visited.add(key)
        new = _next_active_set(chain, side, primal, pside, dual, mode)
        if new is None:
            status = 3  # every single change leaves anchor B out of reach: fall back below
            break
        side = new

    path = "exchange"
    if status != 0:
        # a compressed rigid group or an exchange that cycles: descend over (side, branch)
        found = _descend_from_starts(chain, hanging, theta)
        if found is not None:
            theta, lam, side, k = found
            nnewton += k
            status = 0
            path = "descent"
        else:
            if theta is None:  # not even the first dual solve converged
                theta = sag_guess(chain)
            polished = polish_nlp(chain, theta)
            used_nlp = True
            path = "slsqp"
            if polished is not None:
                theta, lam, side, k = polished
                nnewton += k
                status = 0
            else:
                status = 3
    return _assemble(chain, theta, lam, side, status, it, nnewton, used_nlp, path)


def _descend_from_starts(chain: Chain, hanging, last):
    """The first stable KKT point :func:`optimize.branches.descend` reaches, or None.

    Starts: the chain hanging freely at its joints that are not fused (``hanging``:
    its groups and loads W from the dual solve, or None), the same shape turned upside
    down (an arch: pieces that push), the exchange's last iterate; the symmetric sag
    when there are not two of those.
    """
    starts = []
    if hanging is None:
        groups = Groups(chain, np.where(chain.fixed, -1, 0))
        if groups.reachable(chain.span):
            _, W, _, _ = _dual_newton(groups.P, groups.Q, chain.d, _initial_reaction(chain),
                                      chain.total_length)
            hanging = (groups, W)
    if hanging is not None and np.all(np.isfinite(hanging[1])):
        groups, W = hanging
        psi = np.angle(W)
        load = np.abs(W) / groups.chords
        k = int(np.argmin(load))
        if load[k] <= 1e-8 * np.max(load):
            # an unloaded group (the dual's kink): point it along the gap it leaves
            chords = np.conj(groups.P) * np.exp(1j * psi)
            psi[k] += np.angle((chain.d - chords.sum() + chords[k]) / chords[k])
        theta = np.unwrap(psi[groups.gid] + groups.offsets)
        starts += [theta, theta[0] - np.concatenate([[0.0], np.cumsum(np.diff(theta))])]
    if last is not None:
        starts.append(last)
    if len(starts) < 2:
        starts.append(sag_guess(chain))
    for start in starts:
        found = descend(chain, start, max_iter=60 + 5 * chain.n)
        if found is not None and is_stable(chain, found[0], found[1], found[2]):
            return found
    return None


def _next_active_set(chain, side, primal, pside, dual, mode):
    """The next active set: all violations exchanged at once, or the worst one alone."""
    if mode == "exchange":
        new = side.copy()
        new[dual > 0] = 0
        new[primal > 0] = pside[primal > 0]
        if Groups(chain, new).reachable(chain.span):
            return new
    # one change at a time: add the worst reachable primal violator, else drop the worst dual
    for j in np.argsort(-primal):
        if primal[j] <= 0:
            break
        new = side.copy()
        new[j] = pside[j]
        if Groups(chain, new).reachable(chain.span):
            return new
    if dual.any():
        new = side.copy()
        new[int(np.argmax(dual))] = 0
        return new
    return None


def _reach_hint(chain: Chain) -> str:
    """Why the limits may keep B out of reach: the chain curled as far as its limits
    allow, either way, still spans farther than the anchors are apart."""
    chords = []
    for bound in (chain.limits[:, 1], chain.limits[:, 0]):
        if not np.all(np.isfinite(bound)) or abs(np.sum(bound)) > np.pi:
            return ""
        theta = np.concatenate([[0.0], np.cumsum(bound)])
        chords.append(abs(np.sum(chain.lengths * np.exp(1j * theta))))
    if min(chords) <= chain.span:
        return ""
    return (
        f" Bent to every upper limit the chain still spans {chords[0]:.6g}, to every lower "
        f"limit {chords[1]:.6g}, more than |B - A| = {chain.span:.6g}: move the anchors "
        "closer or allow more bending."
    )


def _assemble(chain, theta, lam, side, status, nit, nnewton, used_nlp, path="exchange") -> EquilibriumResult:
    mult = multipliers(chain, theta, lam)
    moments = np.where(side != 0, mult[0], 0.0)
    pts = chain.points(theta)
    closure = float(np.hypot(*(pts[-1] - chain.anchor_b)))
    kkt = kkt_residual(chain, theta, lam, side, mult)
    success = status == 0 and kkt < 1e-9
    if status == 0 and not success:
        status = 1
    stable = is_stable(chain, theta, lam, side, mult) if status in (0, 1) else False
    message = MESSAGES[status]
    if status == 3:
        message += _reach_hint(chain)
    if used_nlp and status == 0:
        message += " (active set found through the SLSQP fallback)"
    elif path == "descent" and status == 0:
        message += " (active set and branches found by the active-set descent)"
    reaction = np.array([lam.real, lam.imag])
    weight = chain.g * chain.total_mass
    return EquilibriumResult(
        points=pts,
        angles=theta,
        reaction=reaction,
        reaction_a=np.array([-lam.real, weight - lam.imag]),
        moments=moments,
        active=side.copy(),
        kkt_residual=kkt,
        closure_error=closure,
        energy=chain.energy(theta),
        stable=stable,
        success=success,
        status=status,
        message=message,
        nit=nit,
        nnewton=nnewton,
        model="exact",
        info={"used_nlp": used_nlp, "path": path},
    )


def solve_equilibrium(
    lengths,
    masses,
    anchor_a,
    anchor_b,
    *,
    com=None,
    limits=None,
    end_limits=None,
    g: float = 9.81,
    model: str = "exact",
    active0=None,
    max_iter: int | None = None,
    penalty_weight: float = 1e3,
    collision_weight: float = 1.0,
) -> EquilibriumResult:
    """Static equilibrium of a chain of rigid rods hung between anchors A and B.

    Args:
        lengths: (N,) pin-to-pin rod lengths, positive.
        masses: (N,) rod masses, positive (only their ratios shape the chain).
        anchor_a: (2,) the left anchor A = p_0.
        anchor_b: (2,) the right anchor B = p_N.
        com: (N, 2) centres of mass (along, perp) in each rod's frame; None = (l/2, 0).
        limits: (N-1, 2) bend limits [lo, hi] in radians for phi_j; a row of
            (-inf, inf) is a free joint, lo == hi a rigid one. None = all free.
        end_limits: (2, 2) bounds [lo, hi] in radians on the absolute angles of the first
            rod (theta_0) and of the last (theta_{N-1}), set by anchor fixtures; a row of
            (-inf, inf) is a free anchor pin. None = both free. Exact model only; the
            moment each fixture carries is in ``info['end_moments']`` (positive pushes the
            angle up) and which bound holds in ``info['end_active']``
            (:mod:`optimize.endlimits`).
        g: gravitational acceleration (> 0), along -y.
        model: "exact" (default; closure and limits as hard constraints) or
            "penalty" (the paper's Eq. 1-3, for comparison).
        active0: optional (N-1,) initial active set (-1 lo, 0 free, +1 hi).
        max_iter: cap on active-set iterations (default 10 + 4 N).
        penalty_weight: penalty model only: lambda_1 in units of total weight / total length.
        collision_weight: penalty model only: lambda_2 in units of total weight x total length.

    Returns:
        EquilibriumResult.

    Raises:
        ValueError: bad arguments (naming the argument) or anchors no configuration can reach.

    Example:
        >>> r = solve_equilibrium([1, 1], [1, 1], (0, 0), (1.2, 0))
        >>> bool(r.success and abs(r.points[1, 1] + 0.8) < 1e-12)
        True
    """
    chain = Chain.from_args(lengths, masses, anchor_a, anchor_b, com, limits, g)
    if model not in ("exact", "penalty"):
        raise ValueError(f"model must be 'exact' or 'penalty', got {model!r}")
    ends = as_end_limits(end_limits)
    if ends is not None:
        if model != "exact":
            raise ValueError("end_limits are handled by the exact model only")

        def solve(ls, ms, a, b, c, lim, first_joint=0):
            # a starting active set applies to the joints of the shorter chains too
            sub0 = None if active0 is None or len(ls) < 2 else \
                np.asarray(active0, dtype=int)[first_joint:first_joint + len(ls) - 1]
            return solve_equilibrium(ls, ms, a, b, com=c, limits=lim if len(ls) > 1 else None, g=chain.g,
                                     max_iter=max_iter, active0=sub0)

        return solve_with_end_limits(solve, chain.lengths, chain.masses, chain.anchor_a, chain.anchor_b, chain.com,
                                     chain.limits, ends, chain.g)
    _check_reach(chain)
    if chain.span >= chain.total_length * (1 - 1e-12):
        return _taut(chain)
    if model == "penalty":
        return solve_penalty(chain, penalty_weight, collision_weight)
    if max_iter is None:
        max_iter = 10 + 4 * chain.n
    return _solve_exact(chain, active0, max_iter)
