"""SuperLU factorizations that reuse their fill-reducing ordering for a repeated sparsity pattern.

SuperLU (scipy.sparse.linalg.splu) orders the columns of every matrix it factorizes anew
(COLAMD, or minimum degree on A + A^T for the shift-invert: nearest.SHIFT_INVERT_ORDERING),
although the ordering depends on the pattern only, and the core factorizes matrices of one
pattern hundreds of times: the corrector's and the locator's bordered matrices of a committed
contact network, A - sigma I of its spectral windows. `splu` keeps the column order q of the
last few patterns (KEPT) and factorizes a repeated one as M[:, q] (M[q][:, q] where SuperLU
permutes rows and columns alike, SymmetricMode) with the natural order. The factors are those
of the same elimination: with partial pivoting they are bit for bit the factors SuperLU's own
ordering gives; with SymmetricMode they agree to rounding (1e-13 relative in a solve, the same
nonzeros), so there a new pattern, once ordered, is factorized the same way as a repeat: the
factors never depend on what the process factorized before (a scan worker's history, a shear
resumed after its finished segments), at the cost of a second factorization per new pattern.
benchmarks/solve_speed.py --packing 256 times both.

`Reordered` shows the factors of the permuted matrix as factors of M (solve, transposed solve,
L, U, perm_r, perm_c with the permutations composed), so callers and the compiled substitution
(triangular.py) see SuperLU's interface.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

Array = np.ndarray

KEPT = 8
"""Patterns whose ordering is kept (the most recently used)."""


@dataclass(frozen=True)
class _Pattern:
    """A sparsity pattern (CSC indptr, indices; shape), the options it was ordered for, the
    column order q (rows too where symmetric), its inverse, and the permuted matrix's pattern,
    whose data is M.data[take]."""

    options: str
    shape: tuple
    indptr: Array
    indices: Array
    q: Array
    symmetric: bool
    take: Array
    q_inverse: Array
    permuted_indptr: Array
    permuted_indices: Array

    def holds(self, M: sp.csc_array, options: str) -> bool:
        return (self.options == options and self.shape == M.shape and self.indices.size == M.indices.size
                and np.array_equal(self.indptr, M.indptr) and np.array_equal(self.indices, M.indices))

    def permuted(self, M: sp.csc_array) -> sp.csc_array:
        return sp.csc_array((M.data[self.take], self.permuted_indices, self.permuted_indptr), shape=M.shape)


@dataclass(frozen=True)
class Reordered:
    """SuperLU's factors of M[rows][:, cols] seen as factors of M: perm_r, perm_c composed with
    the outer permutations, so that (triangular.py) Pr M Pc = L U still holds."""

    inner: object
    rows: Array
    cols: Array
    perm_r: Array
    perm_c: Array

    @classmethod
    def of(cls, inner, pattern: _Pattern) -> "Reordered":
        """The factors `inner` of pattern.permuted(M) as factors of M."""
        q, q_inverse = pattern.q, pattern.q_inverse
        if pattern.symmetric:
            return cls(inner, q, q, inner.perm_r[q_inverse], inner.perm_c[q_inverse])
        return cls(inner, np.arange(q.size), q, inner.perm_r, inner.perm_c[q_inverse])

    @property
    def L(self):
        return self.inner.L

    @property
    def U(self):
        return self.inner.U

    def solve(self, rhs: Array, trans: str = "N") -> Array:
        """M^-1 rhs (trans "N") or M^-T rhs ("T"): with M' = M[rows][:, cols], M x = r is
        M' y = r[rows], x[cols] = y, and M^T x = r is M'^T y = r[cols], x[rows] = y."""
        rhs = np.asarray(rhs, dtype=float)
        into, take = (self.cols, self.rows) if trans == "N" else (self.rows, self.cols)
        x = np.empty_like(rhs)
        x[into] = self.inner.solve(np.ascontiguousarray(rhs[take]), trans=trans)
        return x


_kept: list = []


def splu(M: sp.csc_array, options: Optional[dict] = None):
    """SuperLU's factorization of the CSC matrix M with `options` (splu's keywords; None: its
    defaults), reusing the column order of a pattern seen before (module docstring). Where
    SuperLU permutes rows and columns alike (SymmetricMode) a new pattern's own factors are
    replaced by those of the reordered matrix, as a repeat gets them: the two agree only to
    rounding, and the factors must not depend on what this process factorized before (a scan
    worker's history, a shear resumed after its finished segments). Raises RuntimeError as
    splu does (exactly singular)."""
    options = dict(options or {})
    key = repr(sorted(options.items()))
    for k, pattern in enumerate(_kept):
        if pattern.holds(M, key):
            _kept.insert(0, _kept.pop(k))
            return _reordered(M, pattern, options)
    lu = spla.splu(M, **options)
    symmetric = bool(options.get("options", {}).get("SymmetricMode"))
    _kept.insert(0, _order_of(M, key, np.argsort(lu.perm_c), symmetric))
    del _kept[KEPT:]
    return _reordered(M, _kept[0], options) if symmetric else lu


def _reordered(M: sp.csc_array, pattern: _Pattern, options: dict) -> Reordered:
    inner = spla.splu(pattern.permuted(M), **{**options, "permc_spec": "NATURAL"})
    return Reordered.of(inner, pattern)


def _order_of(M: sp.csc_array, key: str, q: Array, symmetric: bool) -> _Pattern:
    """The _Pattern of M ordered by q: the permuted pattern found once by permuting the entries'
    positions."""
    position = sp.csc_array((np.arange(1.0, M.nnz + 1.0), M.indices, M.indptr), shape=M.shape)
    permuted = sp.csc_array((position[q] if symmetric else position)[:, q])
    permuted.sort_indices()
    return _Pattern(key, M.shape, M.indptr.copy(), M.indices.copy(), q, symmetric,
                    permuted.data.astype(np.int64) - 1, np.argsort(q), permuted.indptr.copy(),
                    permuted.indices.copy())
