"""Solves with SuperLU's factors by compiled triangular substitution.

SuperLU (scipy.sparse.linalg.splu) factorizes Pr A Pc = L U, L unit lower and U upper
triangular (both CSC), i.e. A = Pr^T L U Pc^T with (Pr b)[perm_r[i]] = b[i] and
(Pc z)[i] = z[perm_c[i]]. Hence

    A x = b:      y[perm_r[i]] = b[i],   L U z = y,       x[i] = z[perm_c[i]],
    A^T x = b:    d[perm_c[i]] = b[i],   U^T L^T v = d,   x[i] = v[perm_r[i]].

SuperLU's own solve spends most of its time around the substitution (work arrays,
supernode bookkeeping): the substitution takes a fraction of it (benchmarks/solve_speed.py).
Copying the factors costs four to seven of SuperLU's solves, so solves.Factorization copies
them only for a factorization solved with repeatedly (ARPACK's shift-invert, the locator's
bordered matrix).
"""
from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

Array = np.ndarray


@numba.njit(cache=True)
def _strict_parts(Lp, Li, Lx, Up, Ui, Ux):
    """From CSC L (unit diagonal stored) and CSC U: the strictly lower part of L, the strictly
    upper part of U (CSC: indptr, indices, data) and 1 / diag(U)."""
    n = Lp.size - 1
    lp, up = np.zeros(n + 1, np.int64), np.zeros(n + 1, np.int64)
    li, lx = np.empty(Li.size, np.int64), np.empty(Li.size)
    ui, ux = np.empty(Ui.size, np.int64), np.empty(Ui.size)
    inv_diag = np.zeros(n)
    a = c = 0
    for j in range(n):
        for k in range(Lp[j], Lp[j + 1]):
            if Li[k] > j:
                li[a], lx[a] = Li[k], Lx[k]
                a += 1
        lp[j + 1] = a
        for k in range(Up[j], Up[j + 1]):
            if Ui[k] < j:
                ui[c], ux[c] = Ui[k], Ux[k]
                c += 1
            elif Ui[k] == j:
                inv_diag[j] = 1.0 / Ux[k]
        up[j + 1] = c
    return lp, li[:a], lx[:a], up, ui[:c], ux[:c], inv_diag


@numba.njit(cache=True)
def _solve(lp, li, lx, up, ui, ux, inv_diag, perm_r, perm_c, b):
    """x with A x = b (module docstring): column-oriented forward and back substitution."""
    n = b.size
    y = np.empty(n)
    for i in range(n):
        y[perm_r[i]] = b[i]
    for j in range(n):
        yj = y[j]
        for k in range(lp[j], lp[j + 1]):
            y[li[k]] -= lx[k] * yj
    for j in range(n - 1, -1, -1):
        yj = y[j] * inv_diag[j]
        y[j] = yj
        for k in range(up[j], up[j + 1]):
            y[ui[k]] -= ux[k] * yj
    x = np.empty(n)
    for i in range(n):
        x[i] = y[perm_c[i]]
    return x


@numba.njit(cache=True)
def _solve_transposed(lp, li, lx, up, ui, ux, inv_diag, perm_r, perm_c, b):
    """x with A^T x = b (module docstring): the columns of L and U are the rows of their
    transposes, so the substitutions take dot products."""
    n = b.size
    w = np.empty(n)
    for i in range(n):
        w[perm_c[i]] = b[i]
    for j in range(n):
        acc = w[j]
        for k in range(up[j], up[j + 1]):
            acc -= ux[k] * w[ui[k]]
        w[j] = acc * inv_diag[j]
    for j in range(n - 1, -1, -1):
        acc = w[j]
        for k in range(lp[j], lp[j + 1]):
            acc -= lx[k] * w[li[k]]
        w[j] = acc
    x = np.empty(n)
    for i in range(n):
        x[i] = w[perm_r[i]]
    return x


@dataclass(frozen=True)
class TriangularFactors:
    """SuperLU's L and U split into strictly triangular CSC parts and 1 / diag(U), with its
    row and column permutations."""

    parts: tuple

    @classmethod
    def of(cls, lu) -> "TriangularFactors":
        """From a scipy SuperLU object."""
        L, U = lu.L, lu.U
        parts = _strict_parts(L.indptr, L.indices, L.data, U.indptr, U.indices, U.data)
        return cls(parts + (lu.perm_r.astype(np.int64), lu.perm_c.astype(np.int64)))

    def solve(self, rhs: Array, transpose: bool = False) -> Array:
        """A^-1 rhs (A^-T rhs if transpose) for a vector or each column of a matrix."""
        kernel = _solve_transposed if transpose else _solve
        rhs = np.asarray(rhs, dtype=float)
        if rhs.ndim == 1:
            return kernel(*self.parts, np.ascontiguousarray(rhs))
        return np.column_stack([kernel(*self.parts, np.ascontiguousarray(col)) for col in rhs.T])
