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
(side, branch) of :mod:`optimize.chain.branches` takes over, and SLSQP from several
starts only after that. Either way the final point satisfies the KKT conditions
exactly: closure to round-off, limits as hard inequalities, and joint moments of
the right sign. ``info['path']`` says which ("exchange", "descent", "slsqp").

Anchor stops (``end_limits``: bounds on theta_0 and theta_{N-1}) take part in the same
active set as two more stops, between a fixed ground and an end rod: a held one fixes the
angle of its group, whose chord then moves the anchor in the dual (:mod:`optimize.chain.dual`),
and the fixture's moment follows from that group's balance. Each active-set iteration
costs O(N); there is no search over combinations of held ends.
"""

from __future__ import annotations

import numpy as np

from optimize.chain.branches import descend, polish_nlp, reach_start
from optimize.chain.model import (
    MESSAGES,
    ActiveSet,
    Chain,
    EquilibriumResult,
    fixture_moments,
    is_stable,
    kkt_residual,
    multipliers,
    sag_guess,
    violations,
)
from optimize.chain.dual import dual_newton, initial_reaction, solve_set
from optimize.chain.endlimits import limit_turn, near
from optimize.chain.free import solve_free
from optimize.chain.penalty import solve_penalty

__all__ = ["Chain", "EquilibriumResult", "solve_equilibrium", "kkt_residual", "MESSAGES"]


def _taut(chain: Chain) -> EquilibriumResult:
    angle = np.angle(chain.d)
    theta = np.full(chain.n, angle)
    lo, hi = chain.limits[:, 0], chain.limits[:, 1]
    t = np.array([near(angle, chain.end_limits[k]) for k in (0, 1)])
    elo, ehi = chain.end_limits[:, 0], chain.end_limits[:, 1]
    miss = max(float(np.max(np.maximum(lo, -hi), initial=0.0)), float(np.max(np.maximum(elo - t, t - ehi))), 0.0)
    ok = miss == 0.0
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
        kkt_residual=miss,
        closure_error=0.0,
        energy=chain.energy(theta),
        stable=ok,
        success=ok,
        status=4 if ok else 5,
        message=MESSAGES[4 if ok else 5],
        info={"used_nlp": False, "path": "exchange", "end_moments": np.zeros(2),
              "end_active": np.zeros(2, dtype=int), "fixtures_hold": True},
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


def _held_always(chain: Chain) -> np.ndarray:
    """(N+1,) True where a stop is fused (lo == hi): a joint or an anchor stop always held."""
    return np.concatenate([[chain.end_fixed[0]], chain.fixed, [chain.end_fixed[1]]])


def _start_set(chain: Chain, active0, end_active0) -> np.ndarray:
    """The first active set (N+1,): the given joints and anchor stops where their bounds are
    finite, fused stops held; the fused stops alone when that cannot close the chain."""
    n = chain.n
    act = np.zeros(n + 1, dtype=int)
    for given, sl, size, name in ((active0, slice(1, n), n - 1, "active0"), (end_active0, [0, n], 2, "end_active0")):
        if given is None:
            continue
        a0 = np.asarray(given, dtype=int)
        if a0.shape != (size,) or not np.all(np.isin(a0, (-1, 0, 1))):
            raise ValueError(f"{name} must have shape ({size},) with entries -1, 0 or 1")
        act[sl] = a0
    lo = np.concatenate([[chain.end_limits[0, 0]], chain.limits[:, 0], [chain.end_limits[1, 0]]])
    hi = np.concatenate([[chain.end_limits[0, 1]], chain.limits[:, 1], [chain.end_limits[1, 1]]])
    act = np.where((act < 0) & np.isfinite(lo), -1, np.where((act > 0) & np.isfinite(hi), 1, 0))
    fused = _held_always(chain)
    act = np.where(fused, -1, act)
    if not ActiveSet(chain, act).feasible(chain):
        act = np.where(fused, -1, 0)
        if not ActiveSet(chain, act).feasible(chain):
            raise ValueError(
                "the rigid joints (lo == hi) leave no configuration that reaches anchor B"
                if not chain.end_fixed.any() else
                "the rigid joints (lo == hi) and the fixed end rods leave no configuration that reaches anchor B"
            )
    return act


def _exchange(chain: Chain, act: np.ndarray, max_iter: int):
    """The active-set iteration of the dual solves, from the active set act.

    Returns (status, act, theta, lam, iterations, newton iterations, hanging): status 0
    when a KKT point was found; hanging is (ActiveSet, W) of the chain hanging freely at
    its stops that are not fused, when it was solved on the way (else None).
    """
    fused = _held_always(chain)
    lam = initial_reaction(chain)
    visited: set[bytes] = set()
    kinked: set[bytes] = set()
    cycling = False
    nnewton = 0
    status = 1
    theta = None
    last = None
    hanging = None
    it = 0
    for it in range(1, max_iter + 1):
        aset = ActiveSet(chain, act)
        sol = solve_set(chain, aset, lam)
        if sol is not None:
            nnewton += sol.newton
        if sol is not None and hanging is None and not np.any(act[~fused]) and sol.W is not None:
            hanging = (aset, sol.W)  # the chain hanging freely: a start for the descent
        if sol is None or not sol.converged:
            # the dual optimum sits on a kink: a rigid group with no net load, whose
            # minimum lies on another branch. Step back and change one stop at a time.
            kinked.add(act.tobytes())
            if last is None:
                status = 2
                break
            act, theta, lam, primal, pside, dual = last
            new = _next_active_set(chain, act, primal, pside, dual, "single", kinked, (theta, lam))
            if new is None:
                status = 3
                break
            act = new
            continue
        lam, theta = sol.lam, sol.theta
        primal, pside, dual = violations(chain, theta, lam, act)
        last = (act, theta, lam, primal, pside, dual)
        if not primal.any() and not dual.any():
            status = 0
            break
        key = act.tobytes()
        if key in visited and cycling:
            status = 3  # cycles one stop at a time too: fall back below
            break
        if key in visited:
            cycling = True  # exchanging everything at once cycles: go one stop at a time
            visited = set()
        visited.add(key)
        new = _next_active_set(chain, act, primal, pside, dual, "single" if cycling else "exchange", kinked,
                               (theta, lam))
        if new is None:
            status = 3  # every single change leaves anchor B out of reach: fall back below
            break
        act = new
    return status, act, theta, lam, it, nnewton, hanging


def _solve_exact(chain: Chain, active0, end_active0, max_iter: int, nlp_fallback: bool = True,
                 theta0=None) -> EquilibriumResult:
    if theta0 is not None:
        # a configuration the caller knows (the designed shape, on the branches its rigid
        # pieces take there): where it is a stable equilibrium the descent stays on it
        found = _first_stable(chain, [np.asarray(theta0, float)])
        if found is not None:
            theta, lam, act, k = found
            return _assemble(chain, theta, lam, act, 0, 0, k, False, "start")
    act0 = _start_set(chain, active0, end_active0)
    status, act, theta, lam, it, nnewton, hanging = _exchange(chain, act0, max_iter)
    hanging_set = np.where(_held_always(chain), -1, 0)
    lasts = [theta] if theta is not None else []
    path = "exchange"
    used_nlp = False
    if status != 0 and not np.array_equal(act0, hanging_set):
        # a start that ends on kinks or cycles: the equilibrium near where it got to (a rigid
        # piece that pushes, say), else start again from the chain hanging freely
        found = _descend_from_starts(chain, None, lasts, alone=True) if lasts else None
        if found is not None:
            theta, lam, act, k = found
            nnewton += k
            status, path = 0, "descent"
        else:
            status, act, theta, lam, it2, k, hanging = _exchange(chain, hanging_set, max_iter)
            it, nnewton = it + it2, nnewton + k
            if theta is not None:
                lasts.append(theta)
    if status != 0:
        # a compressed rigid group or an exchange that cycles: descend over (side, branch)
        found = _descend_from_starts(chain, hanging, lasts)
        if found is not None:
            theta, lam, act, k = found
            nnewton += k
            status = 0
            path = "descent"
        elif not nlp_fallback:  # the caller would rather know it failed than wait for SLSQP
            theta = lasts[0] if lasts else sag_guess(chain)
            status = 3
        else:
            # from where the exchange from the given start got to (a start of the multi-start's
            # reaches its own equilibrium), or the symmetric sag when no dual solve converged
            theta = lasts[0] if lasts else sag_guess(chain)
            polished = polish_nlp(chain, theta)
            used_nlp = True
            path = "slsqp"
            if polished is not None:
                theta, lam, act, k = polished
                nnewton += k
                status = 0
            else:
                status = 3
    return _assemble(chain, theta, lam, act, status, it, nnewton, used_nlp, path)


def _descend_from_starts(chain: Chain, hanging, lasts, alone: bool = False):
    """The first stable KKT point :func:`optimize.chain.branches.descend` reaches, or None.

    Starts: the chain hanging freely at its joints that are not fused (``hanging``:
    its active set and loads W from the dual solve, or None), the same shape turned upside
    down (an arch: pieces that push), the exchanges' last iterates; the symmetric sag
    when there are not two of those; only ``lasts`` when ``alone``.
    """
    if alone:
        return _first_stable(chain, lasts)
    starts = []
    if hanging is None:
        aset = ActiveSet(chain, np.where(_held_always(chain), -1, 0))
        if aset.reachable():
            free = aset.free
            _, W, _, _ = dual_newton(aset.groups.P[free], aset.groups.Q[free], aset.d, initial_reaction(chain),
                                     chain.total_length)
            hanging = (aset, W)
    if hanging is not None and np.all(np.isfinite(hanging[1])):
        aset, W = hanging
        groups, free = aset.groups, aset.free
        psi = aset.psi_held.copy()
        psi[free] = np.angle(W)
        load = np.abs(W) / groups.chords[free]
        k = int(np.flatnonzero(free)[np.argmin(load)])
        if load.min() <= 1e-8 * np.max(load):
            # an unloaded group (the dual's kink): point it along the gap it leaves
            chords = np.conj(groups.P) * np.exp(1j * psi)
            psi[k] += np.angle((chain.d - chords.sum() + chords[k]) / chords[k])
        theta = np.unwrap(psi[groups.gid] + groups.offsets)
        starts += [theta, theta[0] - np.concatenate([[0.0], np.cumsum(np.diff(theta))])]
    starts += lasts
    if len(starts) < 2:
        starts.append(sag_guess(chain))
    found = _first_stable(chain, starts)
    if found is None:  # the same starts moved, within the limits, to the nearest shapes that reach B
        moved = (reach_start(chain, s) for s in starts)
        found = _first_stable(chain, (t for t in moved if t is not None))
    return found


def _first_stable(chain: Chain, starts):
    for start in starts:
        found = descend(chain, start, max_iter=60 + 5 * chain.n)
        if found is not None and is_stable(chain, found[0], found[1], found[2]):
            return found
    return None


def _held_moments(chain: Chain, theta: np.ndarray, lam: complex, act: np.ndarray) -> np.ndarray:
    """(N+1,) how firmly each held stop holds: its moment times the side it pushes to (> 0
    the right way), +inf where a stop is free or fused."""
    mu0, mu_end, _ = multipliers(chain, theta, lam)
    mu, fixtures, _ = fixture_moments(chain, mu0, mu_end, act)
    m = np.concatenate([[fixtures[0]], mu, [fixtures[1]]])
    return np.where((act != 0) & ~_held_always(chain), -act * m, np.inf)


#: How many held stops, the least firm first, one change may let go of to make room for
#: a stop it must hold (each try costs one O(N) check).
RELEASE_TRIES = 8


def _next_active_set(chain, act, primal, pside, dual, mode, kinked, point):
    """The next active set: all violations exchanged at once, or one change: the anchor
    stops' violations first (the fixture holds the chain's ends before its joints), then
    the worst joint's, letting go of one of the least firm held stops (at ``point``, the
    set's (theta, lam): :func:`_held_moments`) when the rods could not close the chain
    otherwise; else the worst wrong-sign moment let go. Sets that can not close the chain,
    or whose dual solve ended on a kink (``kinked``), are passed over."""

    def usable(new):
        return new.tobytes() not in kinked and ActiveSet(chain, new).feasible(chain)

    if mode == "exchange":
        new = act.copy()
        new[dual > 0] = 0
        new[primal > 0] = pside[primal > 0]
        if usable(new):
            return new
    ends_first = np.lexsort((-primal, ~np.isin(np.arange(act.size), (0, act.size - 1))))
    adds = [j for j in ends_first if primal[j] > 0]
    for j in adds:
        new = act.copy()
        new[j] = pside[j]
        if usable(new):
            return new
    firm = _held_moments(chain, point[0], point[1], act) if adds else np.zeros(0)
    releases = [k for k in np.argsort(firm)[:RELEASE_TRIES] if np.isfinite(firm[k])]
    for j in adds:
        for k in releases:
            new = act.copy()
            new[j], new[k] = pside[j], 0
            if usable(new):
                return new
    for j in np.argsort(-dual):
        if dual[j] <= 0:
            break
        new = act.copy()
        new[j] = 0
        if new.tobytes() not in kinked:
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


def _assemble(chain, theta, lam, act, status, nit, nnewton, used_nlp, path="exchange") -> EquilibriumResult:
    side, ends = act[1:-1], act[[0, -1]]
    if chain.end_limited[0]:
        theta = theta - limit_turn(theta[0], chain.end_limits[0])  # theta_0 on its limit's turn
    mult = multipliers(chain, theta, lam)
    mu, fixtures, _ = fixture_moments(chain, mult[0], mult[1], act)
    moments = np.where(side != 0, mu, 0.0)
    pts = chain.points(theta)
    closure = float(np.hypot(*(pts[-1] - chain.anchor_b)))
    kkt = kkt_residual(chain, theta, lam, act, mult)
    success = status == 0 and kkt < 1e-9
    if status == 0 and not success:
        status = 1
    stable = is_stable(chain, theta, lam, act, mult) if status in (0, 1) else False
    message = MESSAGES[status]
    if status == 3:
        message += _reach_hint(chain)
        if chain.end_limited.any():
            message += " The anchor stops bound the end rods' angles too."
    if used_nlp and status == 0:
        message += " (active set found through the SLSQP fallback)"
    elif path == "descent" and status == 0:
        message += " (active set and branches found by the active-set descent)"
    reaction = np.array([lam.real, lam.imag])
    weight = chain.g * chain.total_mass
    holds = bool(np.all((ends * fixtures <= 1e-9 * chain.moment_scale) | chain.end_fixed))
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
        info={"used_nlp": used_nlp, "path": path, "end_moments": np.where(ends != 0, fixtures, 0.0),
              "end_active": ends.copy(), "fixtures_hold": holds},
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
    end_active0=None,
    max_iter: int | None = None,
    penalty_weight: float = 1e3,
    collision_weight: float = 1.0,
    nlp_fallback: bool = True,
    theta0=None,
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
            (:mod:`optimize.chain.endlimits`).
        g: gravitational acceleration (> 0), along -y.
        model: "exact" (default; closure and limits as hard constraints) or
            "penalty" (the paper's Eq. 1-3, for comparison).
        active0: optional (N-1,) initial active set (-1 lo, 0 free, +1 hi).
        end_active0: optional (2,) initial state of the two anchor stops (same codes).
        max_iter: cap on active-set iterations (default 10 + 4 N).
        penalty_weight: penalty model only: lambda_1 in units of total weight / total length.
        collision_weight: penalty model only: lambda_2 in units of total weight x total length.
        nlp_fallback: when the exchange and the descent both fail, polish with SLSQP (slow:
            up to a second on a long chain of stops); False reports the failure instead (a
            multi-start's random starts: a start that fails is just a failed start).
        theta0: optional (N,) chord angles (rad) to start from: where the chain is in a
            stable equilibrium there (a design checked in its designed shape, rigid pieces
            that push included), it is returned as found (``info['path']`` "start").

    Returns:
        EquilibriumResult.

    Raises:
        ValueError: bad arguments (naming the argument) or anchors no configuration can reach.

    Example:
        >>> r = solve_equilibrium([1, 1], [1, 1], (0, 0), (1.2, 0))
        >>> bool(r.success and abs(r.points[1, 1] + 0.8) < 1e-12)
        True
    """
    chain = Chain.from_args(lengths, masses, anchor_a, anchor_b, com, limits, g, end_limits)
    if model not in ("exact", "penalty"):
        raise ValueError(f"model must be 'exact' or 'penalty', got {model!r}")
    if chain.end_limited.any() and model != "exact":
        raise ValueError("end_limits are handled by the exact model only")
    _check_reach(chain)
    if chain.span >= chain.total_length * (1 - 1e-12):
        return _taut(chain)
    if model == "penalty":
        return solve_penalty(chain, penalty_weight, collision_weight)
    if (active0 is None and end_active0 is None and theta0 is None and not chain.end_limited.any()
            and not np.isfinite(chain.limits).any()):
        res = solve_free(chain)  # every joint and anchor free: the closed-form fast path
        if res is not None and res.success:
            return res
    if max_iter is None:
        max_iter = 10 + 4 * chain.n
    return _solve_exact(chain, active0, end_active0, max_iter, nlp_fallback, theta0)
