"""Sparse matrices of one committed state, assembled from the kernels' Jacobian values by a
fixed linear map (docs/packings.md, Shear: the stop-37 benchmark).

Within a committed state the contact rows, the gauge and the masses are fixed, so every matrix
the continuation asks of the network (dG/dq, A_red, A_g: packings/equilibria.py) is

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
        shape = (L.shape[0], R.shape[1])
        e = np.arange(rows.size)
        # every value e reaches A[a, b] through L[a, rows[e]] and R[cols[e], b]
        e_l, a, w_l = _expand(L.indptr, L.indices, L.data, rows, e)
        e_lr, b, w_r = _expand(R.indptr, R.indices, R.data, cols[e_l], np.arange(e_l.size))
        a, e_all, w = a[e_lr], e_l[e_lr], w_l[e_lr] * w_r
        C = sp.coo_array((0, 0) if C is None else C)
        keys = np.concatenate([a * shape[1] + b, C.row.astype(np.int64) * shape[1] + C.col])
        slots, slot_of = np.unique(keys, return_inverse=True)
        S = sp.csr_array((w, (slot_of[:a.size], e_all)), shape=(slots.size, rows.size))
        constant = np.zeros(slots.size)
        np.add.at(constant, slot_of[a.size:], C.data)
        row_of = slots // shape[1]
        indptr = np.zeros(shape[0] + 1, dtype=np.int64)
        np.cumsum(np.bincount(row_of, minlength=shape[0]), out=indptr[1:])
        return cls(shape, indptr, (slots % shape[1]).astype(np.int64), S, constant)

    def __call__(self, values: Array, constant: bool = True) -> sp.csr_array:
        """A(values) (CSR, sorted indices, the same pattern at every call); without C if not
        `constant`."""
        data = self.S @ values + self.constant if constant else self.S @ values
        A = sp.csr_array((data, self.indices, self.indptr), shape=self.shape, copy=False)
        A.has_sorted_indices = True
        return A


def _expand(indptr: Array, indices: Array, data: Array, lines: Array, owner: Array):
    """For each owner k and the compressed line lines[k] (a CSC column or CSR row): its
    entries, as (owner repeated, index, value)."""
    counts = indptr[lines + 1] - indptr[lines]
    repeated = np.repeat(owner, counts)
    starts = np.repeat(indptr[lines] - np.cumsum(counts) + counts, counts)
    at = starts + np.arange(repeated.size)
    return repeated, indices[at], data[at]
