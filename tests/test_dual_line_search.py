"""optimize.chain.dual's line search: Psi at several halved step lengths in one array
operation takes the same step as halving one length at a time."""

from __future__ import annotations

import numpy as np
import pytest

from optimize.chain.dual import HALVINGS, _accepted, _first_accepted


def _psi(P, Q, d, lam):
    return float(np.abs(P * lam - Q).sum() - (np.conj(d) * lam).real)


@pytest.mark.parametrize("seed", range(20))
def test_the_batched_halving_takes_the_first_step_one_at_a_time_would(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 60))
    P = rng.normal(size=n) + 1j * rng.normal(size=n)
    Q = rng.normal(size=n) + 1j * rng.normal(size=n)
    d = complex(*rng.normal(size=2))
    lam = complex(*rng.normal(size=2))
    psi = _psi(P, Q, d, lam)
    step = complex(*rng.normal(size=2)) * 10.0 ** rng.uniform(0, 6)  # often far too long
    slope = -abs(step) * rng.uniform(0.1, 10.0)
    k = _first_accepted(P, Q, d, lam, step, psi, slope, lambda x: False)
    sequential = next((j for j in range(HALVINGS)
                       if _accepted(psi, _psi(P, Q, d, lam + 0.5 ** (j + 1) * step), 0.5 ** (j + 1), slope,
                                    lambda: False)), HALVINGS - 1)
    assert k == sequential
