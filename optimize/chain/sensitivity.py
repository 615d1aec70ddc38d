"""Derivatives of the equilibrium shape with respect to the rod masses.

Implicit differentiation of the equilibrium for its active set (exact, no finite
differences). For rigid group G with load W_G = P_G lambda - Q_G(m) and angle
psi_G = arg(s_G W_G), closure F = sum_G chord_G(psi_G) - (B - A) = 0 gives

    d psi_G = a_G . d lambda - Im(dQ_G / W_G),     a_G = (Im(P_G/W_G), Re(P_G/W_G))
    sum_G i chord_G d psi_G = 0

so d lambda / dm solves a 2 x 2 system and every joint follows by a cumulative sum.
The derivative holds while the active set does not change (the shape is piecewise
smooth in the masses). A group held by an anchor stop does not rotate (d psi_G = 0); its
chord is a constant of the closure, so only the free groups enter the 2 x 2 system. With
fewer than two free groups the closure alone fixes the shape: the derivative is zero.
"""

from __future__ import annotations

import numpy as np

from optimize.chain.model import Chain, EquilibriumResult, Groups


def shape_jacobian(chain: Chain, result: EquilibriumResult) -> np.ndarray:
    """d points / d masses, shape (N+1, 2, N), for the result's active set.

    Args:
        chain: the problem the result solves (``Chain.from_args(...)``).
        result: a successful :class:`EquilibriumResult` of the exact model (the anchor
            stops it holds, ``info['end_active']``, included).

    Returns:
        J with ``J[j, :, k] = d p_j / d m_k``; rows 0 and N (the anchors) are zero.
    """
    n = chain.n
    if not np.all(np.isfinite(result.reaction)):
        return np.zeros((n + 1, 2, n))  # taut: the straight line does not move
    held_ends = np.asarray((result.info or {}).get("end_active", np.zeros(2)), dtype=int)
    groups = Groups(chain, result.active)
    free = np.ones(groups.starts.size, dtype=bool)
    free[0] &= not held_ends[0]
    free[-1] &= not held_ends[1]
    if np.count_nonzero(free) < 2:
        return np.zeros((n + 1, 2, n))
    lam = complex(*result.reaction)
    W = groups.P * lam - groups.Q
    theta = result.angles
    psi = theta[groups.starts] - groups.offsets[groups.starts]
    # dQ_G / dm_k = g ([k in G] e^{-i o_k} (perp_k + i along_k) + i sum_{j in G, j < k} w_j)
    w = chain.lengths * np.exp(-1j * groups.offsets)
    prefix = np.concatenate([[0.0], np.cumsum(w)])
    ends = np.append(groups.starts[1:], n)
    k = np.arange(n)
    clipped = np.clip(k[None, :], groups.starts[:, None], ends[:, None])
    dQ = 1j * (prefix[clipped] - prefix[groups.starts][:, None])
    own = np.exp(-1j * groups.offsets) * (chain.com[:, 1] + 1j * chain.com[:, 0])
    dQ[groups.gid, k] += own
    dQ *= chain.g
    b = (dQ / W[:, None]).imag  # (n_g, N)
    ratio = groups.P / W
    a = np.column_stack([ratio.imag, ratio.real])  # (n_g, 2)
    chords = np.conj(groups.P) * np.exp(1j * psi)
    c = np.column_stack([(1j * chords).real, (1j * chords).imag])  # (n_g, 2)
    M = c[free].T @ a[free]
    dlam = np.linalg.solve(M, c[free].T @ b[free])  # (2, N)
    dpsi = np.where(free[:, None], a @ dlam - b, 0.0)  # (n_g, N): held groups do not turn
    dtheta = dpsi[groups.gid]  # (N rods, N masses)
    steps = (1j * chain.lengths * np.exp(1j * theta))[:, None] * dtheta
    dp = np.vstack([np.zeros((1, n), complex), np.cumsum(steps, axis=0)])
    dp[-1] = 0.0  # B is fixed; the cumulative sum leaves only round-off there
    return np.stack([dp.real, dp.imag], axis=1)
