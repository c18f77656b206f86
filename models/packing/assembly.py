"""Sparse matrices of one committed state of a sheared packing, assembled from the kernels'
Jacobian values by fixed linear maps (models/packing/equilibria.py).

Within a committed state the contact rows, the gauge and the masses are fixed, so every matrix
the continuation asks of the network (dG/dq, A_red, A_g and the deflation's A: StateMaps) is

    A(v) = L J(v) R + C,   J(v) = sum_e v_e e_(r_e) e_(c_e)^T,

linear in the values v of J's pattern (r, c) (duplicates summed), with constant sparse L, R
and C (GaugeMaps: those fixed by the gauge alone). Assembly precomputes A's pattern (CSR,
sorted indices) and the sparse map S with A.data = S v + C.data, so each call costs one sparse
product of length nnz(S) instead of a chain of general sparse products and their index
bookkeeping. The pattern keeps the entries that happen to be zero at some v (an open
contact's), so it is the same at every point of the state. NetworkMatrix is A_g at a trial
point with the structure the eigensolvers read.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property

import numba
import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from diskfriction.continuation.linalg.solves import book
from diskfriction.continuation.spectra.nearest import Deflated
from diskfriction.continuation.spectra.structure import StructuredMatrix
from diskfriction.continuation.spectra.tracking import Eigensystem
from diskfriction.matrices import Matrix

Array = np.ndarray

PARKED = 2.0
"""The gauge rows' diagonal in the tracked matrix A_g is -PARKED times A_red's largest absolute
row sum at the committed state: below every eigenvalue of A_red (Gershgorin), so that a
shift-invert near the tracked spectrum (a partial sample near a fold's zero eigenvalue) never
meets the gauge rows, and constant along a step, so that dA/dgamma is zero there."""


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


@dataclass(frozen=True)
class StateMaps:
    """A committed state's matrices as fixed linear maps of J's values: J's pattern (rows,
    cols), dG/dq, A_red, A_g and the deflation's parts (the assembly of its matrix, and a
    nearest.Deflated without its matrix) (models/packing/equilibria.py)."""

    pattern: tuple
    dG_dq: Assembly
    reduced: Assembly
    stability: Assembly
    deflation: tuple


@dataclass(frozen=True)
class GaugeMaps:
    """The constant sparse factors of a state's maps that depend on its gauge alone (n = 3N
    dofs, kept: A_red's): -1 on the non-gauge diagonal and the gauge rows' pattern (dG/dq),
    the identity, M^-1 (or I for J), P M^-1 and the kept columns E (A_red = P A E), the map
    to A_g's coordinates (relative = embed P) times M^-1 and E embed^T (A_g), T and U (the
    translations and total forces of the network) and the map of left vectors to A_g's."""

    minus_kept: sp.dia_array
    gauge_diagonal: sp.dia_array
    identity: sp.dia_array
    inverse_mass: sp.dia_array
    reduce: sp.csr_array
    E: sp.csr_array
    relative: sp.csr_array
    relative_reduce: sp.csr_array
    E_embed: sp.csr_array
    T: np.ndarray
    U: np.ndarray
    left_map: sp.csr_array

    @classmethod
    def of(cls, g, N: int, mass: np.ndarray, matrix: Matrix) -> "GaugeMaps":
        """The factors of gauge g (equilibria.Gauge) of N disks with masses diag(M) = mass."""
        n = mass.size
        keep, gauge = np.ones(n), np.zeros(n)
        keep[g.rows], gauge[g.rows] = 0.0, 1.0
        inverse_mass = sp.diags_array(np.ones(n) if matrix is Matrix.J else 1.0 / mass)
        E = sp.eye_array(n, format="csr")[:, g.kept]
        embed = sp.csr_array((np.ones(g.kept.size), (g.kept, np.arange(g.kept.size))),
                             shape=(n, g.kept.size))
        relative = sp.csr_array(embed @ g.P)  # q -> A_g's coordinates
        T = np.zeros((n, 2))
        T[:N, 0], T[N:2 * N, 1] = ~g.loose, ~g.loose
        U = T if matrix is Matrix.J else T * mass[:, None]
        return cls(sp.diags_array(-keep), sp.diags_array(gauge), sp.eye_array(n), inverse_mass,
                   g.P @ inverse_mass, E, relative, relative @ inverse_mass, E @ embed.T, T, U,
                   sp.csr_array(embed @ E.T))


def state_maps(pattern: tuple, fixed: GaugeMaps, g, N: int, kappa: float, values) -> StateMaps:
    """The maps of a committed state whose J has the pattern (rows, cols), gauge g
    (equilibria.Gauge) of N disks with the factors `fixed` and gauge rows kappa (q - q_c) = 0
    (kappa [force / length]); values(): J's values at the committed point, which fix the gauge
    rows' PARKED diagonal of A_g. The deflation's matrix is A (J or M^-1 J) with the loose
    disks' dofs (and without tangential forces every rotation) parked on its diagonal, its null
    spaces without them the x and y translations T and the total x and y forces U = M T (U = T
    for J)."""
    rows, cols = pattern
    n = fixed.T.shape[0]
    dG_dq = Assembly.of(rows, cols, fixed.minus_kept, fixed.identity, fixed.gauge_diagonal * kappa)
    reduced = Assembly.of(rows, cols, fixed.reduce, fixed.E)
    A = reduced(values())
    parked = np.zeros(n)
    parked[g.rows] = -PARKED * max(float(np.abs(A).sum(axis=1).max(initial=0.0)), 1.0)
    stability = Assembly.of(rows, cols, fixed.relative_reduce, fixed.E_embed, sp.diags_array(parked))
    gauged = np.zeros(n, bool)
    gauged[g.rows] = True
    gauged[[g.ref, N + g.ref]] = False  # the reference disk is in the network
    full = Assembly.of(rows, cols, fixed.inverse_mass, fixed.identity,
                       sp.diags_array(np.where(gauged, parked[g.rows[0]], 0.0)))
    return StateMaps(pattern, dG_dq, reduced, stability,
                     (full, Deflated(None, fixed.T, fixed.U, fixed.relative, fixed.left_map)))


class NetworkMatrix(StructuredMatrix):
    """The tracked matrix A_g of a packing's committed state (problem: its PackingEquilibria) at a
    trial (q, gamma) with its structure (equilibria.py's module docstring;
    continuation/spectra/structure.py), each part computed at its
    first use: A_g (matrix); A_red on the kept dofs (coupled; the gauge rows' modes are zeros
    and excluded); the deflation (deflated: A, J or M^-1 J, with the loose disks parked, to
    shift-invert in place of A_g: the same spectrum but for its two translation zeros, which
    the shift-invert projects out, and a sparser LU than A_g's, whose rows each carry the
    reference disk's); A_g without its PARKED diagonal (spectrum_matrix: a constant of the
    committed state, which changes no eigenvalue); without tangential forces, the symmetric
    form of A_red (symmetric: SymmetricNetwork)."""

    def __init__(self, problem, q: np.ndarray, gamma: float):
        self.maps = problem.maps
        self.values = problem._evaluate(q, gamma)[1]
        self.problem, self.q, self.gamma = problem, q, gamma
        self.kept = problem.gauge.kept

    @cached_property
    def matrix(self) -> sp.csr_array:
        return self.maps.stability(self.values)

    @cached_property
    def coupled(self) -> sp.csr_array:
        return self.maps.reduced(self.values)

    @cached_property
    def deflated(self):
        full, deflation = self.maps.deflation
        return replace(deflation, matrix=full(self.values))

    @cached_property
    def spectrum_matrix(self) -> sp.csr_array:
        return self.maps.stability(self.values, constant=False)

    @cached_property
    def symmetric(self):
        return None if self.problem.network.frictional else SymmetricNetwork(self)


class SymmetricNetwork:
    """A_red without tangential forces as a symmetric eigenproblem (structure.SymmetricForm):
    on the network's positions V (the kept dofs and the reference disk's x, y) J_V is the
    Hessian of the Hertz energy, symmetric, and A = W^-1 J_V with W = diag(M) on V (W = I for
    J); with Q an orthonormal basis of the complement of W^1/2 T (T: the x and y translations,
    J_V T = 0), S = Q^T W^-1/2 J_V W^-1/2 Q is symmetric with A_red's spectrum, and S's
    eigenvectors (columns of Y) give A's right vectors r = W^-1/2 Q Y and left ones l = W^1/2
    Q Y, l^T r = 1, l^T T = 0; A_red's are then P r and l at the kept dofs (l^T = l_kept^T P
    since l^T T = 0). A real spectrum: no complex pair arises from rounding."""

    def __init__(self, network_matrix: NetworkMatrix):
        self.of = network_matrix

    def eigensystem(self, vectors: bool) -> Eigensystem:
        """A_red's eigensystem from S (one dense spectrum, booked as such)."""
        book("spectra")
        problem, values = self.of.problem, self.of.values
        g, N, n = problem.gauge, problem.network.N, self.of.q.size
        V = np.union1d(g.kept, [g.ref, N + g.ref])
        J = sp.csr_array((values, self.of.maps.pattern), shape=(n, n))
        w = np.ones(V.size) if problem.matrix is Matrix.J else problem.mass[V]
        T = np.stack([V < N, V >= N], axis=1).astype(float)
        Q = np.linalg.qr(np.sqrt(w)[:, None] * T, mode="complete")[0][:, 2:]
        WQ = Q / np.sqrt(w)[:, None]  # W^-1/2 Q
        S = WQ.T @ (J[V][:, V] @ WQ)
        if not vectors:
            return Eigensystem(sla.eigh(S, eigvals_only=True, check_finite=False).astype(complex))
        eigenvalues, Y = sla.eigh(S, check_finite=False)
        right, left = np.zeros((n, Y.shape[1])), np.zeros((n, Y.shape[1]))
        right[V], left[V] = WQ @ Y, (Q * np.sqrt(w)[:, None]) @ Y
        return Eigensystem(eigenvalues.astype(complex), g.P @ right, left[g.kept].T.copy())
