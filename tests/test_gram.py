"""optimize.gram.Gram: the interior point's and the net Newton's ``A diag(w) A' + diag(r)``
on a fixed pattern is the matrix scipy's sparse products build, to the last bit (so the
factors and every iterate computed from them are unchanged), on seeded random matrices with
exact cancellations, empty rows and columns, and other values on the same pattern."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from optimize.gram import Gram


def _same(ref: sp.spmatrix, got: sp.csc_matrix) -> None:
    ref = sp.csc_matrix(ref)
    ref.sort_indices()
    assert got.shape == ref.shape
    np.testing.assert_array_equal(got.indptr, ref.indptr)
    np.testing.assert_array_equal(got.indices, ref.indices)
    np.testing.assert_array_equal(got.data, ref.data)  # bit for bit


def _matrix(rng, t: int) -> sp.csr_matrix:
    k, n = int(rng.integers(1, 25)), int(rng.integers(1, 50))
    A = sp.random(k, n, density=rng.uniform(0.02, 0.5), random_state=rng, format="csr")
    if t % 3 == 0:  # quarters of either sign: many entries of the product cancel exactly
        A = sp.csr_matrix(np.round(A.toarray() * 4) / 4 * np.sign(rng.normal(size=(k, n))))
    return A


@pytest.mark.parametrize("seed", range(4))
def test_the_gram_matrix_is_scipys_product_bit_for_bit(seed):
    rng = np.random.default_rng(seed)
    for t in range(60):
        A = _matrix(rng, t)
        k, n = A.shape
        w = rng.uniform(0.1, 3.0, size=n)
        r = rng.uniform(0.0, 1e-3, size=k) if t % 2 else 3e-12
        if t % 7 == 0:
            r = 0.0
        # box_qp's normal matrix: (A @ diags(w) @ A.T + r I).tocsc()
        _same((A @ sp.diags(w) @ A.T.tocsr() + sp.diags(np.broadcast_to(r, (k,)))).tocsc(), Gram(A).matrix(w, r))
        # the net's multipliers: (J @ J.T).tocsc() and that plus a diagonal
        gram = Gram(A, reverse=False)
        _same((A @ A.T).tocsc(), gram.matrix())
        _same(((A @ A.T).tocsc() + sp.diags(np.broadcast_to(r, (k,)))).tocsc(), gram.matrix(None, r))
        # both from one sum of the terms (the multipliers' two matrices): the sums left as they were
        sums = gram.sums()
        _same((A @ A.T).tocsc(), gram.assemble(sums))
        _same(((A @ A.T).tocsc() + sp.diags(np.broadcast_to(r, (k,)))).tocsc(), gram.assemble(sums, r))
        # other values on the same pattern (a Jacobian at the next state)
        B = A.copy()
        B.data = rng.normal(size=B.data.size)
        _same((B @ B.T).tocsc(), gram.matrix(data=B.data))


def test_an_empty_matrix_is_its_diagonal():
    A = sp.csr_matrix((3, 4))
    np.testing.assert_array_equal(Gram(A).matrix(np.ones(4), 2.0).toarray(), 2.0 * np.eye(3))
    assert Gram(A).matrix(np.ones(4)).nnz == 0
