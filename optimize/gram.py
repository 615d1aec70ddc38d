"""``A diag(w) A' + diag(r)`` for many ``w`` and data on one sparsity pattern of A.

The interior point of :func:`optimize.boxqp.box_qp` factors ``A D A'`` at every iteration
and the net's Newton method ``J J'`` at every step; scipy's sparse product builds four
matrices each time (the product, a diagonal, their sum, its CSC), checking each, which cost
more than the factorization on the nets of a few hundred rods. :class:`Gram` finds the
product's pattern and where each of its terms ``A_ik w_k A_jk`` goes once, and then sums
the terms with one ``bincount``.

The terms of an entry are summed in the order scipy's product sums them, and entries that
sum to exactly zero are left out as scipy leaves them out: the matrix is the same to the
last bit as ``(A @ sp.diags(w) @ A.T.tocsr() + sp.diags(r)).tocsc()`` (``reverse=True``:
the product lists a row of ``A @ diags(w)`` last entry first) or ``((A @ A.T).tocsc() +
sp.diags(r)).tocsc()`` (``reverse=False``), so the factors, and whatever is computed from
them, are the same.

    gram = Gram(A)                       # A: CSR, its pattern fixed
    N = gram.matrix(w, r)                # CSC, (k, k)
    N = gram.matrix(w, r, data=A2.data)  # the same pattern with other values
    s = gram.sums(w); N0, N1 = gram.assemble(s), gram.assemble(s, r)  # one product, two diagonals
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["Gram"]


class Gram:
    """``A diag(w) A' + diag(r)`` on the pattern of the CSR matrix ``A`` (see the module)."""

    def __init__(self, A: sp.csr_matrix, *, reverse: bool = True) -> None:
        A = sp.csr_matrix(A)
        k, nnz = A.shape[0], A.indptr[-1]
        # At's entries as indices into A.data
        index = sp.csr_matrix((np.arange(1, nnz + 1, dtype=float), A.indices, A.indptr), shape=A.shape)
        At = index.T.tocsr()
        at_entry = At.data.astype(np.int64) - 1
        rows = np.repeat(np.arange(k), np.diff(A.indptr))
        offset = np.arange(rows.size) - A.indptr[rows]
        # A's entries row by row, in the order the product takes them
        entry = A.indptr[rows + 1] - 1 - offset if reverse else A.indptr[rows] + offset
        cols = A.indices[entry]
        reach = np.diff(At.indptr)[cols]                      # the entries of A's column
        term = np.repeat(np.arange(entry.size), reach)        # the A_ik of each term
        first = np.cumsum(reach) - reach
        term_t = At.indptr[cols][term] + np.arange(term.size) - first[term]  # its A_jk
        i, j = rows[term], At.indices[term_t]
        keys = np.concatenate([j * k + i, np.arange(k) * (k + 1)])  # column-major: CSC
        uniq, inv = np.unique(keys, return_inverse=True)
        self.k = k
        self.cols = cols[term]
        self.ia = entry[term]
        self.ib = at_entry[term_t]
        self.data = A.data
        self.pos = inv[:term.size]
        self.diag = inv[term.size:]
        self.size = uniq.size
        self.col, self.indices = np.divmod(uniq, k)
        self.indptr = np.concatenate([[0], np.cumsum(np.bincount(self.col, minlength=k))])

    def matrix(self, w: np.ndarray | None = None, r: np.ndarray | float = 0.0, *,
               data: np.ndarray | None = None) -> sp.csc_matrix:
        """The matrix (CSC) for column weights ``w`` (None: ones) and diagonal ``r``; ``data``:
        A's values on its pattern (default: those it was made with)."""
        return self.assemble(self.sums(w, data=data), r)

    def sums(self, w: np.ndarray | None = None, *, data: np.ndarray | None = None) -> np.ndarray:
        """The product's entries on its pattern, before a diagonal is added and exact zeros are
        left out: several matrices of one product (:meth:`assemble`) sum its terms once."""
        a = self.data if data is None else data
        if w is None:
            terms = a[self.ia] * a[self.ib]
        else:
            terms = (a[self.ia] * w[self.cols]) * a[self.ib]
        return np.bincount(self.pos, weights=terms, minlength=self.size).astype(float, copy=False)

    def assemble(self, sums: np.ndarray, r: np.ndarray | float = 0.0) -> sp.csc_matrix:
        """The matrix (CSC) of the product's entries ``sums`` (:meth:`sums`, left as they are)
        plus the diagonal ``r``."""
        out = sums.copy()
        out[self.diag] += r  # a zero sum the product left out is 0 + r there too
        keep = out != 0
        if keep.all():
            return sp.csc_matrix((out, self.indices, self.indptr), shape=(self.k, self.k))
        indptr = np.concatenate([[0], np.cumsum(np.bincount(self.col[keep], minlength=self.k))])
        return sp.csc_matrix((out[keep], self.indices[keep], indptr), shape=(self.k, self.k))
