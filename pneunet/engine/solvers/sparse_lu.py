"""Direct solves with the Newton matrix of large circuits (fixed sparsity pattern).

Two factorisations, chosen once per pattern by :func:`sparse_lu`:

* *Bordered band* (LAPACK).  The few unknowns coupled to very many others (a
  control line that drives 64 valves) form a border S; the others, I, ordered
  by reverse Cuthill–McKee, make a narrow band.  With B = P_II (band LU with
  partial pivoting, dgbtrf), X = B⁻¹·P_IS and the Schur complement
  T = P_SS − P_SI·X (dense LU):

      x_S = T⁻¹·(b_S − P_SI·B⁻¹·b_I),   x_I = B⁻¹·b_I − X·x_S.

  A demultiplexer's cells are independent chains once its control lines are
  the border (bandwidth 1): ~0.09 ms per factorisation at 390 unknowns, where
  SuperLU needs ~0.3–0.4 ms (mostly its per-call set-up).
* *SuperLU* otherwise, in a fill-reducing order computed once (minimum degree on
  PᵀP + P, applied to rows and columns alike so that the diagonal stays the
  preferred pivot): SuperLU's COLAMD on every call cost 2–4× the factorisation.

Both take the matrix's CSC data (its pattern fixed at construction) and return
an object whose ``solve(b)`` gives x with P·x = b.
"""
from __future__ import annotations

import numpy as np

PIVOT_THRESHOLD = 0.1  # SuperLU keeps a diagonal pivot ≥ 0.1 × the column's largest entry
BAND_WORK_LIMIT = 4e5  # largest estimated flop count of a bordered-band factorisation
BORDER_LIMIT = 32  # most border unknowns tried


def sparse_lu(pattern):
    """The cheaper factorisation for this CSC ``pattern`` (values ignored)."""
    band = BorderedBand.plan(pattern)
    return band if band is not None else SuperLU(pattern)


class SuperLU:
    """SuperLU in a fill-reducing symmetric order computed at the first factorisation."""

    name = "SuperLU"

    def __init__(self, pattern):
        self._pattern = pattern.copy()
        self._perm = None

    def factor(self, data):
        from scipy.sparse.linalg import splu

        if self._perm is None:
            self._pattern.data[:] = data
            lu = splu(self._pattern, permc_spec="MMD_AT_PLUS_A",
                      diag_pivot_thresh=PIVOT_THRESHOLD, options=dict(SymmetricMode=True))
            self._perm = lu.perm_c
            index = self._pattern.copy()
            index.data = np.arange(1, index.nnz + 1, dtype=float)  # no zero entry
            self._permuted = index[self._perm][:, self._perm].tocsc()
            self._permuted.sort_indices()
            self._permuted_from = self._permuted.data.astype(int) - 1
        self._permuted.data[:] = data[self._permuted_from]
        self._lu = splu(self._permuted, permc_spec="NATURAL", diag_pivot_thresh=PIVOT_THRESHOLD,
                        panel_size=1, options=dict(SymmetricMode=True))
        return self

    def solve(self, b):
        x = np.empty_like(b)
        x[self._perm] = self._lu.solve(np.asarray(b)[self._perm])
        return x


class BorderedBand:
    """Band LU of the interior and a dense Schur complement on the border (see module)."""

    name = "bordered band"

    @classmethod
    def plan(cls, pattern):
        """A bordered-band solver for ``pattern``, or None if its band is too wide.

        Border candidates are the unknowns of highest degree (ties taken together);
        the one whose estimated factorisation work is least is kept."""
        from scipy.sparse.csgraph import reverse_cuthill_mckee

        n = pattern.shape[0]
        ones = pattern.copy()
        ones.data = np.ones(ones.nnz)
        graph = (ones + ones.T).tocsr()
        degree = np.diff(graph.indptr)
        by_degree = np.argsort(-degree, kind="stable")
        sizes = [0] + [k for k in range(1, min(BORDER_LIMIT, n - 1) + 1)
                       if degree[by_degree[k - 1]] > degree[by_degree[k]]]
        best = None
        for k in sizes:
            border = np.sort(by_degree[:k])
            inner = np.setdiff1d(np.arange(n), border)
            inner = inner[reverse_cuthill_mckee(graph[inner][:, inner], symmetric_mode=True)]
            order = np.concatenate([inner, border])
            sub = ones[order][:, order].tocoo()
            in_band = (sub.row < inner.size) & (sub.col < inner.size)
            offset = sub.row[in_band] - sub.col[in_band]
            kl, ku = max(int(offset.max(initial=0)), 0), max(int(-offset.min(initial=0)), 0)
            m = inner.size
            work = m * (kl + 1) * (kl + ku + 1) + k * m * (2 * kl + ku + 1 + k) + k ** 3
            if best is None or work < best[0]:
                best = (work, order, m, kl, ku)
        work, order, m, kl, ku = best
        return cls(pattern, order, m, kl, ku) if work <= BAND_WORK_LIMIT else None

    def __init__(self, pattern, order, m, kl, ku):
        self._pattern = pattern
        coo = pattern.tocoo()  # entries in CSC data order
        position = np.empty_like(order)
        position[order] = np.arange(order.size)
        r, c = position[coo.row], position[coo.col]
        self.order, self.m, self.kl, self.ku = order, m, kl, ku
        self.k = order.size - m

        def part(mask, row_shift, col_shift):
            return np.flatnonzero(mask), r[mask] - row_shift, c[mask] - col_shift
        band = (r < m) & (c < m)
        self._band = (np.flatnonzero(band), kl + ku + r[band] - c[band], c[band])
        self._right = part((r < m) & (c >= m), 0, m)   # P_IS
        self._below = part((r >= m) & (c < m), m, 0)   # P_SI
        self._corner = part((r >= m) & (c >= m), m, m)  # P_SS
        self._fallback = None

    def factor(self, data):
        """Factorise; an exactly singular band or Schur block goes to SuperLU instead."""
        from scipy.linalg import lapack

        m, k, kl, ku = self.m, self.k, self.kl, self.ku
        at, rows, cols = self._band
        ab = np.zeros((2 * kl + ku + 1, m))
        ab[rows, cols] = data[at]
        self._lu, self._piv, info = lapack.dgbtrf(ab, kl, ku, overwrite_ab=1)
        if info == 0 and k:
            right, below, corner = (self._dense(data, part, shape) for part, shape in
                                    ((self._right, (m, k)), (self._below, (k, m)),
                                     (self._corner, (k, k))))
            self._x, _ = lapack.dgbtrs(self._lu, kl, ku, right, self._piv, overwrite_b=1)
            self._below_dense = below
            self._schur, self._schur_piv, info = lapack.dgetrf(corner - below @ self._x,
                                                               overwrite_a=1)
        if info != 0:
            if self._fallback is None:
                self._fallback = SuperLU(self._pattern)
            return self._fallback.factor(data)
        return self

    def solve(self, b):
        from scipy.linalg import lapack

        m = self.m
        b = np.asarray(b)[self.order]
        z, _ = lapack.dgbtrs(self._lu, self.kl, self.ku, b[:m], self._piv)
        x = np.empty(b.size)
        if self.k:
            xs, _ = lapack.dgetrs(self._schur, self._schur_piv, b[m:] - self._below_dense @ z)
            z = z - self._x @ xs
            x[self.order[m:]] = xs
        x[self.order[:m]] = z
        return x

    @staticmethod
    def _dense(data, part, shape):
        at, rows, cols = part
        out = np.zeros(shape)
        out[rows, cols] = data[at]
        return out
