"""Sparse matrices of one committed state, assembled from the kernels' Jacobian values by a
fixed linear map (docs/packings.md, Shear: the stop-37 benchmark).

Within a committed state the contact rows, the gauge and the masses are fixed, so every matrix
the continuation asks of the network (dG/dq, A_red, A_g: models/packing/equilibria.py) is

    A(v) = L J(v) R + C,   J(v) = sum_e v_e e_(r_e) e_(c_e)^T,

linear in the values v of J's pattern (r, c) (duplicates summed), with constant sparse L, R
and C. Assembly precomputes A's pattern (CSR, sorted indices) and the sparse map S with
A.data = S v + C.data, so each call costs one sparse product of length nnz(S) instead of a
chain of general sparse products and their index bookkeeping (each of which re-sorts and
re-checks its indices). The pattern keeps the entries that happen to be zero at some v (an
open contact's), so it is the same at every point of the state.
"""
from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
import scipy.sparse as sp

Array = np.ndarray


@dataclass(frozen=True)
class Assembly:
    """The fixed linear map v -> A(v) = L J(v) R + C of one committed state (module
    docstring)."""

    shape: tuple[int, int]
    indptr: Array
    indices: Array
    S: sp.csr_array  # (nnz(A), len(v))
    constant: Array  # C on A's pattern

    @classmethod
    def of(cls, rows: Array, cols: Array, L, R, C=None) -> "Assembly":
        """The map for J's pattern (rows, cols) (one entry per value, duplicates allowed), L
        (m x n), R (n x k) and C (m x k, or None: zero)."""
        L, R = sp.csc_array(L), sp.csr_array(R)
        C = sp.coo_array((L.shape[0], R.shape[1]) if C is None else C)
        shape = (L.shape[0], R.shape[1])
        indptr, indices, s_indptr, s_indices, s_data, constant = _linear_map(
            np.asarray(rows, np.int64), np.asarray(cols, np.int64),
            L.indptr.astype(np.int64), L.indices.astype(np.int64), L.data.astype(float),
            R.indptr.astype(np.int64), R.indices.astype(np.int64), R.data.astype(float),
            C.row.astype(np.int64), C.col.astype(np.int64), C.data.astype(float), shape[0], shape[1])
        S = sp.csr_array((s_data, s_indices, s_indptr), shape=(indices.size, len(rows)))
        return cls(shape, indptr, indices, S, constant)

    def __call__(self, values: Array, constant: bool = True) -> sp.csr_array:
        """A(values) (CSR, sorted indices, the same pattern at every call); without C if not
        `constant`."""
        data = self.S @ values + self.constant if constant else self.S @ values
        A = sp.csr_array((data, self.indices, self.indptr), shape=self.shape, copy=False)
        A.has_sorted_indices = True
        return A


@numba.njit(cache=True)
def _linear_map(rows, cols, Lp, Li, Lx, Rp, Ri, Rx, Crow, Ccol, Cdata, m, k):
    """A's pattern and the map S of Assembly.of, in O(contributions): value e reaches A[a, b]
    with weight L[a, rows[e]] R[cols[e], b]; A's columns sorted within each row (Gustavson's
    symbolic product, a marker per column), S's rows (A's entries) holding their values e in
    increasing order. Returns (indptr, indices) of A and (indptr, indices, data) of S (int32
    indices: scipy keeps them without a check or a copy) and C on A's pattern."""
    nv = rows.size
    count = 0
    for e in range(nv):
        count += (Lp[rows[e] + 1] - Lp[rows[e]]) * (Rp[cols[e] + 1] - Rp[cols[e]])
    a_of, b_of = np.empty(count, np.int64), np.empty(count, np.int64)
    e_of, w_of = np.empty(count, np.int64), np.empty(count)
    c = 0
    for e in range(nv):
        for p in range(Lp[rows[e]], Lp[rows[e] + 1]):
            for q in range(Rp[cols[e]], Rp[cols[e] + 1]):
                a_of[c], b_of[c], e_of[c], w_of[c] = Li[p], Ri[q], e, Lx[p] * Rx[q]
                c += 1
    # the contributions and C's entries grouped by row of A (counting sort)
    total = count + Crow.size
    per_row = np.zeros(m + 1, np.int64)
    for c in range(count):
        per_row[a_of[c] + 1] += 1
    for c in range(Crow.size):
        per_row[Crow[c] + 1] += 1
    for a in range(m):
        per_row[a + 1] += per_row[a]
    fill = per_row[:-1].copy()
    by_row = np.empty(total, np.int64)  # c < count: a contribution; else C's entry c - count
    for c in range(count):
        by_row[fill[a_of[c]]] = c
        fill[a_of[c]] += 1
    for c in range(Crow.size):
        by_row[fill[Crow[c]]] = count + c
        fill[Crow[c]] += 1
    # A's pattern row by row, and the slot of every contribution and C entry
    indptr = np.zeros(m + 1, np.int32)
    indices = np.empty(total, np.int32)
    slot_of = np.empty(total, np.int64)
    position = np.full(k, -1, np.int64)
    nnz = 0
    for a in range(m):
        start = nnz
        for r in range(per_row[a], per_row[a + 1]):
            c = by_row[r]
            b = b_of[c] if c < count else Ccol[c - count]
            if position[b] < 0:
                position[b] = 0
                indices[nnz] = b
                nnz += 1
        for t in range(start + 1, nnz):  # insertion sort: a row holds a few tens of columns
            b, u = indices[t], t
            while u > start and indices[u - 1] > b:
                indices[u] = indices[u - 1]
                u -= 1
            indices[u] = b
        for t in range(start, nnz):
            position[indices[t]] = t
        for r in range(per_row[a], per_row[a + 1]):
            c = by_row[r]
            slot_of[c] = position[b_of[c] if c < count else Ccol[c - count]]
        for t in range(start, nnz):
            position[indices[t]] = -1
        indptr[a + 1] = nnz
    # S: one row per slot, its values in increasing e (the contributions are generated so)
    s_indptr = np.zeros(nnz + 1, np.int32)
    for c in range(count):
        s_indptr[slot_of[c] + 1] += 1
    for t in range(nnz):
        s_indptr[t + 1] += s_indptr[t]
    at = s_indptr[:-1].astype(np.int64)
    s_indices, s_data = np.empty(count, np.int32), np.empty(count)
    for c in range(count):
        s_indices[at[slot_of[c]]], s_data[at[slot_of[c]]] = e_of[c], w_of[c]
        at[slot_of[c]] += 1
    constant = np.zeros(nnz)
    for c in range(Crow.size):
        constant[slot_of[count + c]] += Cdata[c]
    return indptr, indices[:nnz].copy(), s_indptr, s_indices, s_data, constant
